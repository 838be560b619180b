"""The results CSV of a run: the FMI cross-check format that ``fmpy.util.read_csv`` reads.

A header ``"time","a.x",...`` and one row per recorded communication point, each value as Python's ``repr`` of the
double (the shortest text that reads back as the same double: an exact round trip). The rows are formatted by the C
master's library (``tcm_format_rows``, :mod:`tribocosim.cosim.engine.native_lib`: the same text,
``tests/cosim/test_results_csv.py``, an order of magnitude faster), or in Python where the library is not available.
"""

from __future__ import annotations

import array
import ctypes
from pathlib import Path

from tribocosim.errors import TribocosimError

#: the longest text of a double (``-2.2250738585072014e-308``) and its separator
_WIDEST = 25


def format_rows(times, rows, n_cols: int) -> str:
    """The CSV lines of ``times`` and ``rows`` (``len(times) x n_cols`` values, row after row)."""
    t, v = array.array("d", times), array.array("d", rows)
    try:
        from tribocosim.cosim.engine.native_lib import library

        lib = library()
    except (TribocosimError, OSError):
        lib = None
    if lib is not None and len(t):
        capacity = len(t) * (n_cols + 1) * _WIDEST + 1
        out = ctypes.create_string_buffer(capacity)
        pd = ctypes.POINTER(ctypes.c_double)
        used = lib.tcm_format_rows(ctypes.cast(t.buffer_info()[0], pd), ctypes.cast(v.buffer_info()[0], pd),
                                   len(t), n_cols, out, capacity)
        if used:
            return out.raw[:used].decode("ascii")
    values = v.tolist()
    line = ",".join(["%r"] * (n_cols + 1)) + "\n"
    return "".join(line % (tt, *values[r * n_cols:(r + 1) * n_cols]) for r, tt in enumerate(t.tolist()))


def write_csv(path: Path, names: list[str], times, rows) -> Path:
    """Write ``times`` and ``rows`` (``len(times) x len(names)`` values, row after row: any sequence of floats) to
    ``path`` atomically (a ``.part`` file renamed into place); returns ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".part")
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(",".join(f'"{n}"' for n in ["time", *names]) + "\n")
        f.write(format_rows(times, rows, len(names)))
    tmp.replace(path)
    return path
