"""Files written whole or not at all: every file the project writes goes through here.

A file is first written in full to a temporary name in its target folder (hidden, named after the file, this process
and this thread, so that concurrent writers never share one), then renamed onto its name: ``os.replace``, atomic on
one file system, so a reader sees the old file or the new one, never a part. When writing fails or is interrupted
(an exception, Ctrl-C's KeyboardInterrupt, a SIGTERM raised as SystemExit), the temporary file is removed and the
old file, if any, is left as it was.

- :func:`replaced`: a context manager for a writer that needs a path (``numpy.savez``, a zip file, a compiler);
- :func:`write_text`, :func:`write_bytes`: one file from its content;
- :func:`write_all`: several files, all of them or none (an export's file set);
- :func:`check_writable`: whether a file can be written there, asked before the work that makes it.
"""

from __future__ import annotations

import os
import threading
from contextlib import ExitStack, contextmanager
from pathlib import Path
from collections.abc import Iterator


def check_writable(path: str | os.PathLike, option: str) -> None:
    """ParameterError naming ``option`` when ``path`` cannot be written: its folder is missing or is not a folder, the
    path is a folder, or the folder is not writable."""
    from tribocosim.errors import ParameterError

    path = Path(path)
    folder = path.parent
    if not folder.is_dir():
        raise ParameterError(f"{option} {path}: its folder {folder} does not exist or is not a folder")
    if path.is_dir():
        raise ParameterError(f"{option} {path} is a folder; give the file to write")
    if not os.access(folder, os.W_OK):
        raise ParameterError(f"{option} {path}: the folder {folder} is not writable")


def _temporary(path: Path, suffix: str) -> Path:
    return path.with_name(f".{path.name}.{os.getpid()}.{threading.get_ident()}.partial{suffix}")


@contextmanager
def replaced(path: str | os.PathLike, suffix: str = "") -> Iterator[Path]:
    """Yield a temporary path beside ``path`` (ending in ``suffix``, for writers that add or need one, e.g. ``.npz``)
    and rename it onto ``path`` when the block ends without an exception; remove it otherwise (module docstring).
    The folder must exist."""
    path = Path(path)
    tmp = _temporary(path, suffix)
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        if os.path.lexists(tmp):
            os.unlink(tmp)


def write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` whole or not at all."""
    with replaced(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_text(path: str | os.PathLike, text: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` whole or not at all (newlines as given)."""
    with replaced(path) as tmp:
        with open(tmp, "w", encoding=encoding, newline="") as f:
            f.write(text)
    return Path(path)


def write_all(contents: dict) -> list[Path]:
    """Write ``{path: text or bytes}``: every file in full to its temporary name first, then each renamed onto its
    name; when any write fails, every temporary file is removed and no file is changed."""
    with ExitStack() as stack:
        temporary = []
        for path, data in contents.items():
            tmp = stack.enter_context(replaced(path))
            if isinstance(data, bytes):
                tmp.write_bytes(data)
            else:
                with open(tmp, "w", encoding="utf-8", newline="\n") as f:
                    f.write(data)
            temporary.append(Path(path))
    return temporary
