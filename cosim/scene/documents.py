"""The TOML documents of scene and sweep files, parsed once per file content.

A document depends on nothing but the bytes of its file, and Python's TOML parser costs a run more than reading the
scene does: importing it compiles its regular expressions (with ``typing`` and ``datetime``), some 40 million
instructions (callgrind), a tenth of the C loop of the demo. So :func:`read_toml` parses a file's text the first time
its content is seen and keeps the document as JSON in ``$TRIBOCOSIM_CACHE/documents/``, under the SHA-256 of the
bytes; every later read of that content loads the JSON (C code). A document holds the same values after the round
trip: JSON keeps strings, booleans, integers and floats (``repr``, infinities and NaN included) and the order of the
keys; a document with a date or a time, which JSON cannot hold, is not kept. Nothing that cannot be parsed is kept:
its error is raised again, the parser's.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path


class TomlError(ValueError):
    """A file is not valid TOML (the message is the parser's: what, line, column)."""


def parse_toml(text: str) -> dict:
    """The TOML document of ``text``; TomlError if it is not TOML."""
    import tomllib

    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise TomlError(str(exc)) from None


def read_toml(path: str | Path) -> dict:
    """The TOML document of the file ``path`` (see the module docstring). Raises OSError and UnicodeDecodeError when
    the file cannot be read as UTF-8 text, TomlError when it is not TOML."""
    data = Path(path).read_bytes()
    text = data.decode("utf-8")
    stored = _store(hashlib.sha256(data).hexdigest())
    try:
        return json.loads(stored.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        pass
    doc = parse_toml(text)
    if _json_exact(doc):
        _write_atomically(stored, json.dumps(doc))
    return doc


def _store(digest: str) -> Path:
    from tribocosim.components.native.toolchain.library import cache_dir

    return cache_dir() / "documents" / f"{digest[:32]}.json"


def _json_exact(value) -> bool:
    """Whether JSON gives ``value`` back as it is: dicts with string keys, lists, strings, booleans, integers and
    floats (TOML's arrays of tables and inline tables are dicts and lists too)."""
    if isinstance(value, dict):
        return all(isinstance(k, str) and _json_exact(v) for k, v in value.items())
    if isinstance(value, list):
        return all(_json_exact(v) for v in value)
    return isinstance(value, (str, bool, int, float))  # json writes a float's repr, Infinity and NaN, and reads them


def _write_atomically(path: Path, text: str) -> None:
    from tribocosim.atomic import write_text

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_text(path, text)
    except OSError:  # a cache that cannot be written costs time, not results
        pass
