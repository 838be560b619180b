"""Figures in the documentation that a command prints, written by that command: ``--update`` rewrites them, ``--check``
fails when one differs from what the command prints now on the shipped data (``.ci/run`` runs it).

    python -m tribocosim.cosim.apps.doc_outputs --check [FILE ...]    # default: README.md and docs/**/*.md
    python -m tribocosim.cosim.apps.doc_outputs --update [FILE ...]

Three markers, HTML comments a Markdown reader does not show:

- a file of the repository shown as it is (an example a block then runs), fenced in its language::

      <!-- include: docs/examples/strip_draw_model.py -->
      ```python
      the file
      ```
      <!-- include: end -->

- a block, the output of a command between a marker line and an end line::

      <!-- output: COMMAND [| FILTER ...] -->
      ```text
      what COMMAND prints
      ```
      <!-- output: end -->

- an inline figure, the first group of a regular expression matched in what a command prints (stdout, then stderr)::

      mu_bar <!-- value: COMMAND | REGEX -->0.1286<!-- /value -->

COMMAND is split as a shell would split it (no shell runs it); a leading ``tribocosim`` is the console script of this
interpreter (``python -m tribocosim.cli``), a leading ``python`` this interpreter. It runs in a fresh temporary folder
(its relative paths land there), with ``{root}`` the repository's folder; the folder's path is written as ``.`` in
what it prints. A command that ends with a status other than 0 is an error. FILTERs of a block, in order: ``stdout``
(the default), ``stderr`` or ``both`` (stdout, then stderr), ``grep REGEX`` (the lines that match), ``drop REGEX`` (what matches, removed from each line:
a column of wall times), ``file PATH`` (the
content of a file the command wrote, relative to its folder, as it is: Markdown, not fenced). Each command runs once
per check, however many markers name it.

Only what a command prints on the shipped data belongs here: figures of a measurement on a machine (timings, the
load) are stated with their date and machine instead.
"""

from __future__ import annotations

import argparse
import re
import shlex
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BLOCK = re.compile(r"^<!-- output: (?P<spec>.+?) -->\n(?P<body>.*?)^<!-- output: end -->$", re.M | re.S)
INCLUDE = re.compile(r"^<!-- include: (?P<path>\S+) -->\n(?P<body>.*?)^<!-- include: end -->$", re.M | re.S)
LANGUAGES = {".py": "python", ".toml": "toml", ".csv": "text", ".k": "text", ".inp": "text"}
VALUE = re.compile(r"<!-- value: (?P<command>.+?) \| (?P<regex>.+?) -->(?P<text>.*?)<!-- /value -->", re.S)
#: every command a check runs is refused after this long [s]
TIMEOUT_S = 1800


class DocOutputError(Exception):
    """A marker that cannot be evaluated: its command failed, or its expression matched nothing."""


@dataclass(frozen=True)
class Printed:
    """What a command printed, and the folder it ran in (its files)."""

    stdout: str
    stderr: str
    folder: Path


def _argv(command: str) -> list[str]:
    words = shlex.split(command.replace("{root}", str(ROOT)))
    if words and words[0] == "tribocosim":
        return [sys.executable, "-m", "tribocosim.cli", *words[1:]]
    if words and words[0] == "python":
        return [sys.executable, *words[1:]]
    return words


class Runner:
    """Runs each command once, in a folder of its own under one temporary folder."""

    def __init__(self, base: Path):
        self.base, self.done = base, {}

    def __call__(self, command: str) -> Printed:
        if command not in self.done:
            folder = Path(tempfile.mkdtemp(dir=self.base))
            proc = subprocess.run(_argv(command), cwd=folder, capture_output=True, text=True, timeout=TIMEOUT_S)
            if proc.returncode != 0:
                raise DocOutputError(f"{command!r} ended with status {proc.returncode}:\n{proc.stderr[-2000:]}")

            def clean(text):
                return text.replace(str(folder) + "/", "").replace(str(folder), ".")

            self.done[command] = Printed(clean(proc.stdout), clean(proc.stderr), folder)
        return self.done[command]


def _block(spec: str, run: Runner) -> str:
    command, *filters = (part.strip() for part in spec.split(" | "))
    printed = run(command)
    text, fenced = printed.stdout, True
    for f in filters:
        word, _, arg = f.partition(" ")
        if word in ("stdout", "stderr", "both"):
            text = {"stdout": printed.stdout, "stderr": printed.stderr, "both": printed.stdout + printed.stderr}[word]
        elif word == "grep":
            text = "".join(line for line in text.splitlines(keepends=True) if re.search(arg, line))
        elif word == "drop":
            text = "".join(re.sub(arg, "", line) + "\n" for line in text.splitlines())
        elif word == "file":
            text, fenced = (printed.folder / arg).read_text(encoding="utf-8"), False
        else:
            raise DocOutputError(f"{spec!r}: {word!r} is not a filter (stdout, stderr, both, grep REGEX, drop REGEX, "
                                 "file PATH)")
    if not text.strip():
        raise DocOutputError(f"{spec!r} gives no text")
    text = text if text.endswith("\n") else text + "\n"
    return f"```text\n{text}```\n" if fenced else text


def render(text: str, run: Runner) -> str:
    """``text`` with every marker's content as its command gives it now."""
    def block(m):
        return f"<!-- output: {m['spec']} -->\n{_block(m['spec'], run)}<!-- output: end -->"

    def value(m):
        printed = run(m["command"])
        found = re.search(m["regex"], printed.stdout + printed.stderr, re.M)
        if found is None:
            raise DocOutputError(f"{m['regex']!r} matches nothing {m['command']!r} prints")
        return f"<!-- value: {m['command']} | {m['regex']} -->{found.group(1)}<!-- /value -->"

    def include(m):
        path = ROOT / m["path"]
        body = path.read_text(encoding="utf-8")
        body = body if body.endswith("\n") else body + "\n"
        return (f"<!-- include: {m['path']} -->\n```{LANGUAGES.get(path.suffix, 'text')}\n{body}```\n"
                "<!-- include: end -->")

    return VALUE.sub(value, BLOCK.sub(block, INCLUDE.sub(include, text)))


def documents(paths) -> list[Path]:
    """The files given, or README.md and every Markdown file under docs/ but the reports the report commands write."""
    if paths:
        return [Path(p) for p in paths]
    return [ROOT / "README.md", *sorted(p for p in (ROOT / "docs").rglob("*.md") if "reports" not in p.parts[-3:-1])]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m tribocosim.cosim.apps.doc_outputs", description=__doc__.split("\n\n")[0])
    mode = ap.add_mutually_exclusive_group(required=True)
    mode.add_argument("--check", action="store_true", help="exit 1 when a figure differs from its command's output")
    mode.add_argument("--update", action="store_true", help="rewrite the figures from their commands")
    ap.add_argument("files", nargs="*", help="Markdown files (default: README.md and docs/)")
    args = ap.parse_args(argv)
    stale = []
    with tempfile.TemporaryDirectory(prefix="tribocosim-docs-") as base:
        run = Runner(Path(base))
        for path in documents(args.files):
            text = path.read_text(encoding="utf-8")
            if not any(f"<!-- {kind}: " in text for kind in ("output", "value", "include")):
                continue
            try:
                new = render(text, run)
            except DocOutputError as exc:
                print(f"{path}: {exc}", file=sys.stderr)
                return 2
            if new != text:
                stale.append(path)
                if args.check:
                    import difflib

                    diff = difflib.unified_diff(text.splitlines(), new.splitlines(), str(path), "what the commands "
                                                "print now", lineterm="", n=1)
                    print("\n".join(list(diff)[:60]), file=sys.stderr)
                if args.update:
                    from tribocosim.atomic import write_text

                    write_text(path, new)
    for path in stale:
        print(f"{path}: {'rewritten' if args.update else 'a figure differs from what its command prints now'}")
    return 1 if stale and args.check else 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
