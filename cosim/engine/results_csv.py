"""The results CSV of a run: the FMI cross-check format that ``fmpy.util.read_csv`` reads.

A header ``"time","a.x",...`` and one row per recorded communication point, each value as Python's ``repr`` of the
double (the shortest text that reads back as the same double: an exact round trip).
"""

from __future__ import annotations

from pathlib import Path


def write_csv(path: Path, names: list[str], times, rows) -> Path:
    """Write ``times`` and ``rows`` (``len(times) x len(names)`` values, row after row: any sequence of floats) to
    ``path`` atomically (a ``.part`` file renamed into place); returns ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".part")
    times = list(times)
    values = list(rows)
    c = len(names)
    row = ",".join(["%r"] * (c + 1)) + "\n"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(",".join(f'"{n}"' for n in ["time", *names]) + "\n")
        f.write("".join(row % (t, *values[r * c:(r + 1) * c]) for r, t in enumerate(times)))
    tmp.replace(path)
    return path
