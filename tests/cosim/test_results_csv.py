"""The results CSV: every value is Python's repr of the double, formatted in C (native/tc_csv.c), and reads back
as the same double.

The C formatter is held to Python's own ``repr`` (David Gay's shortest round trip) on doubles of every kind: random
bit patterns (every exponent, subnormals included), the magnitudes of physical results, the time grid, short
decimals, the ends of every binade (where the rounding interval is lopsided), powers of two and ten, large integers
and the special values.
"""

from __future__ import annotations

import array
import math
import random
import struct

import numpy as np
import pytest

from tribocosim.cosim.engine.results_csv import write_csv

N = 40_000


def _samples() -> dict[str, list[float]]:
    rnd = random.Random(20240509)
    bits = [struct.unpack("<d", struct.pack("<Q", rnd.getrandbits(64)))[0] for _ in range(N)]
    return {
        "random bit patterns": [x for x in bits if math.isfinite(x)],
        "physical magnitudes": [rnd.choice((1, -1)) * rnd.lognormvariate(0.0, 15.0) for _ in range(N)],
        "time grid": [k * 5e-4 for k in range(N)],
        "short decimals": [round(rnd.uniform(0.0, 1e3), rnd.randint(0, 12)) for _ in range(N)],
        "binade ends": [y for k in range(-1073, 1024)
                        for y in (math.nextafter(2.0 ** k, 0.0), 2.0 ** k, math.nextafter(2.0 ** k, math.inf))],
        "powers of ten": [10.0 ** k for k in range(-323, 309)],
        "large integers": [float(rnd.getrandbits(rnd.randint(54, 70))) for _ in range(N // 4)],
        "special": [0.0, -0.0, math.inf, -math.inf, 5e-324, -5e-324, 2.2250738585072014e-308, 1.7976931348623157e308,
                    0.1, 0.2, 0.3, 1 / 3, 2.0 ** 53, 2.0 ** 53 + 2, 2.0 ** 61, 1e16, 1e15, 1e-4, 1e-5, 123.0],
    }


@pytest.mark.parametrize("kind", list(_samples()))
def test_each_value_is_pythons_repr(tmp_path, kind):
    values = _samples()[kind]
    path = write_csv(tmp_path / "r.csv", ["x"], array.array("d", values), array.array("d", values))
    lines = path.read_text(encoding="utf-8").splitlines()
    assert lines[0] == '"time","x"'
    got = [line.split(",") for line in lines[1:]]
    assert len(got) == len(values)
    wrong = [(v, g[0]) for v, g in zip(values, got) if g[0] != repr(v) or g[1] != repr(v)]
    assert not wrong, f"{len(wrong)} of {len(values)} {kind} differ from repr, e.g. {wrong[:3]}"


def test_rows_read_back_bit_for_bit_in_blocks(tmp_path, monkeypatch):
    """Rows written over several blocks, from a numpy array and from plain lists, read back as the same doubles
    (NaN is written as Python writes it)."""
    from tribocosim.cosim.engine import results_csv

    monkeypatch.setattr(results_csv, "BLOCK", 4096)  # many blocks of a few dozen rows
    rnd = np.random.default_rng(7)
    data = rnd.standard_normal((3001, 5)) * 10.0 ** rnd.integers(-30, 30, (3001, 5))
    data[17, 2] = math.nan
    times = [k * 1e-3 for k in range(3001)]
    for rows in (data.ravel(), data.ravel().tolist(), np.asfortranarray(data).ravel(order="C")):
        path = write_csv(tmp_path / "r.csv", [f"c{j}" for j in range(5)], times, rows)
        lines = path.read_text(encoding="utf-8").splitlines()
        back = np.array([[float(x) for x in line.split(",")] for line in lines[1:]])
        assert back.shape == (3001, 6)
        assert back[:, 0].tolist() == times
        np.testing.assert_array_equal(back[:, 1:], data)
        assert lines[18].split(",")[3] == "nan"
    assert not list(tmp_path.glob("*.part"))


def test_a_count_that_does_not_match_the_columns_is_refused(tmp_path):
    with pytest.raises(ValueError, match="5 values for 2 rows of 3 columns"):
        write_csv(tmp_path / "r.csv", ["a", "b", "c"], [0.0, 1.0], [1.0] * 5)
    assert not (tmp_path / "r.csv").exists() and not list(tmp_path.iterdir())
