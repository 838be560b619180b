"""The results CSV of a run: the FMI cross-check format that ``fmpy.util.read_csv`` reads.

A header ``"time","a.x",...`` and one row per recorded communication point, each value as Python's ``repr`` of the
double (the shortest text that reads back as the same double: an exact round trip). The rows are formatted in C
(``native/tc_csv.c`` in the C master's library, :mod:`.native_lib`), a block of rows at a time, so that writing a
run's results costs no Python work per value.
"""

from __future__ import annotations

import array
import ctypes
from pathlib import Path

#: characters of formatted rows per block written (a bound on the memory the text takes)
BLOCK = 1 << 20


def _doubles(values) -> array.array:
    """``values`` as an ``array('d')``: as it is, or copied (a float64 buffer such as a numpy array byte for byte)."""
    if isinstance(values, array.array) and values.typecode == "d":
        return values
    try:
        view = memoryview(values)
    except TypeError:
        return array.array("d", values)
    if view.format == "d" and view.c_contiguous:
        out = array.array("d")
        out.frombytes(view.cast("B"))
        return out
    return array.array("d", values)


def write_csv(path: Path, names: list[str], times, rows) -> Path:
    """Write ``times`` and ``rows`` (``len(times) x len(names)`` values, row after row: an ``array('d')``, a numpy
    array or any sequence of floats) to ``path`` atomically (a ``.part`` file renamed into place); returns ``path``."""
    from tribocosim.cosim.engine.native_lib import library

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".part")
    times, values = _doubles(times), _doubles(rows)
    n_rows, c = len(times), len(names)
    if len(values) != n_rows * c:
        raise ValueError(f"{len(values)} values for {n_rows} rows of {c} columns")
    lib = library()
    double_p = ctypes.POINTER(ctypes.c_double)
    t_address, v_address = times.buffer_info()[0], values.buffer_info()[0]
    row_max = (c + 1) * 25  # TCM_CSV_CELL_MAX per cell
    buffer = ctypes.create_string_buffer(max(BLOCK, row_max))
    length = ctypes.c_size_t()
    try:
        with open(tmp, "wb") as f:
            f.write((",".join(f'"{n}"' for n in ["time", *names]) + "\n").encode("utf-8"))
            done = 0
            while done < n_rows:
                count = lib.tcm_csv_rows(ctypes.cast(t_address + 8 * done, double_p),
                                         ctypes.cast(v_address + 8 * done * c, double_p), c, n_rows - done, buffer,
                                         len(buffer), ctypes.byref(length))
                f.write(memoryview(buffer)[:length.value])
                done += count
        tmp.replace(path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path
