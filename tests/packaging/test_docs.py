"""The documentation against the code: the FMU variable tables of docs/fmu-reference.md are the variables the FMUs
declare, and the README's quick start is the three commands CI runs."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BEGIN = "<!-- variables: generated from the component descriptions -->"
END = "<!-- variables: end -->"


def _number(x) -> str:
    return "" if x is None else (f"{x:g}" if isinstance(x, float) else str(x))


def variable_tables() -> str:
    """One Markdown table per native FMU: value reference, name, causality, type, unit, start, range, description."""
    from tribocosim.components.fmus.native_build import fmus
    from tribocosim.components.native.toolchain import declarations

    out = []
    for name, comp in sorted(fmus().items()):
        out += [f"### {name}", "", "| vr | name | causality | type | unit | start | range | description |",
                "|---|---|---|---|---|---|---|---|"]
        for vr, v in enumerate(declarations.variables(comp)):
            if v["choices"]:
                allowed = " / ".join(v["choices"])
            elif v["low"] is not None or v["high"] is not None:
                allowed = f"[{_number(v['low'])}, {_number(v['high'])}]"
            else:
                allowed = ""
            start = "" if v["causality"] == "output" else (
                repr(v["start"]) if v["kind"] == "string" else _number(v["start"]))
            text = v["description"].replace("|", "\\|")
            out.append(f"| {vr} | `{v['name']}` | {v['causality']} | {v['kind']} | {v['unit']} | {start} | {allowed} "
                       f"| {text} |")
        out.append("")
    return "\n".join(out)


def test_the_fmu_reference_lists_the_variables_the_fmus_declare():
    text = (ROOT / "docs" / "fmu-reference.md").read_text()
    written = text.split(BEGIN, 1)[1].split(END, 1)[0].strip("\n")
    expected = variable_tables().strip("\n")
    assert written == expected, f"docs/fmu-reference.md, between the variables markers, should read:\n\n{expected}"


def test_the_readme_quick_start_is_what_ci_runs():
    """A virtual environment made and activated first (CI makes its own, .ci-venv), then the three commands."""
    readme = (ROOT / "README.md").read_text()
    block = re.search(r"```bash\n(.*?)```", readme, re.S).group(1).split("\n")
    commands = [line.split("#")[0].strip() for line in block if line.strip()]
    assert commands == ["python3 -m venv .venv && source .venv/bin/activate", 'pip install -e ".[test]"',
                        "tribocosim demo", "pytest"]
    ci = (ROOT / ".ci" / "run").read_text()
    assert re.search(r"^python3 -m venv (\S+)\n(?:#.*\n)*source \1/bin/activate$", ci, re.M), \
        ".ci/run does not make and activate a virtual environment first"
    for command in commands[1:]:
        assert re.search(rf"^{re.escape(command)}\s", ci, re.M), f".ci/run does not run {command!r}"


def test_what_the_demo_the_docs_and_ci_write_in_the_checkout_is_ignored_by_git():
    """The demo's folder, the user guide's campaigns and the example's results, CI's virtual environment and build
    folder, the README's virtual environment: untracked output never shows up in ``git status``."""
    import shutil
    import subprocess

    import pytest

    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    written = ["tribocosim-demo/mu.png", "runs/first/friction_table.npz", "reports/paper/paper.md",
               "docs/examples/measured_drive/results/results.csv", "docs/examples/measured_drive/MeasuredDrive.fmu",
               "build/fmus/StripDraw.fmu", ".ci-venv/bin/python", ".venv/bin/python"]
    proc = subprocess.run(["git", "check-ignore", "--no-index", *written], cwd=ROOT, capture_output=True, text=True)
    ignored = set(proc.stdout.split())
    assert ignored == set(written), f"not ignored by .gitignore: {sorted(set(written) - ignored)}"
