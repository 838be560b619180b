"""The files one export writes, all of them or none: their names, and writing them through temporary files.

Names: a file ``FILE`` (``friction.k``) of several debris states becomes ``friction.<state>.k`` (``friction.pass2.k``,
``friction.beta0.1.k``); a band adds ``.upper`` and ``.lower`` before the suffix (``friction.upper.k``,
``friction.pass2.lower.k``). Writing: every file is first written in full to a temporary name in its target folder,
then each is renamed onto its name (an atomic replace on one file system); when any write fails, the temporary
files are removed and nothing is left behind.
"""

from __future__ import annotations

from pathlib import Path

from tribocosim.errors import ParameterError


def tagged(path: Path, *tags: str) -> Path:
    """``path`` with ``.tag`` inserted before its suffix for each non-empty tag (``friction.k`` ->
    ``friction.pass2.upper.k``)."""
    path = Path(path)
    middle = "".join(f".{t}" for t in tags if t)
    return path.with_name(f"{path.stem}{middle}{path.suffix}")


def check_target(path: Path) -> None:
    """ParameterError naming ``-o`` when ``path`` cannot be written (:func:`tribocosim.atomic.check_writable`)."""
    from tribocosim.atomic import check_writable

    check_writable(path, "-o")


def write_all(contents: dict) -> list[Path]:
    """Write ``{path: text}``: all files or none (module docstring, :func:`tribocosim.atomic.write_all`);
    ParameterError naming the file that failed."""
    from tribocosim import atomic

    for path in contents:
        check_target(path)
    try:
        return atomic.write_all(contents)
    except OSError as exc:
        raise ParameterError(f"-o: {exc.filename or ''} cannot be written: {exc.strerror or exc}") from None
