"""Tests of cosim.engine.results_csv: the C master's text of a double is Python's repr, byte for byte."""

from __future__ import annotations

import ctypes
import random
import struct
import sys

import numpy as np

from tribocosim.cosim.engine.native_lib import library
from tribocosim.cosim.engine.results_csv import format_rows


def _c_repr(lib, x: float) -> str:
    out = ctypes.create_string_buffer(32)
    n = lib.tcm_repr(x, out)
    return out.raw[:n].decode()


def test_the_text_of_a_double_is_pythons_repr():
    """Random bit patterns (every exponent, subnormals), random decimals of few digits, powers of two (whose rounding
    interval is narrower below than above), the boundaries of fixed and exponent notation, and the specials."""
    lib = library()
    rng = random.Random(20261128)
    values = [struct.unpack("<d", struct.pack("<Q", rng.getrandbits(64)))[0] for _ in range(100_000)]
    values += [rng.uniform(-1e4, 1e4) for _ in range(20_000)]
    values += [round(rng.uniform(-1e3, 1e3), rng.randint(0, 6)) * 10.0 ** rng.randint(-30, 30) for _ in range(20_000)]
    values += [s * 2.0 ** e for e in range(-1074, 1024) for s in (1.0, -1.0)]
    values += [s * 10.0 ** e for e in range(-320, 309) for s in (1.0, -1.0)]
    values += [0.0, -0.0, float("inf"), float("-inf"), float("nan"), sys.float_info.max, sys.float_info.min,
               5e-324, 1e16, 1e16 - 2, 9999999999999998.0, 1e-4, 1e-5, 0.1, 12250.0, 3027.348479]
    bad = [(repr(x), _c_repr(lib, x)) for x in values if _c_repr(lib, x) != repr(x)]
    assert not bad, f"{len(bad)} of {len(values)} differ, e.g. {bad[:5]}"


def test_the_rows_are_the_python_writers_rows():
    rng = np.random.default_rng(3)
    times = np.arange(50) * 5e-4
    rows = rng.normal(size=(50, 4)) * 10.0 ** rng.integers(-8, 8, size=(50, 4))
    expected = "".join(",".join(map(repr, [t, *r])) + "\n" for t, r in zip(times.tolist(), rows.tolist()))
    assert format_rows(times.tolist(), rows.ravel().tolist(), 4) == expected
