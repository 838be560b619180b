"""Tests of cosim.engine.timegrid: communication points are t0 + n*h exactly, never accumulated."""

import numpy as np
import pytest

from tribocosim.errors import ParameterError
from tribocosim.cosim.engine.timegrid import FIXED_SUBDIVISION, TimeGrid


def test_fixed_grid_hits_multiples_of_the_step_exactly():
    grid = TimeGrid.fixed(0.0, 1.75, 1e-3)
    assert grid.end_ticks == 1750 * 2**FIXED_SUBDIVISION
    for k in (1, 7, 999, 1750):
        assert grid.time(k * grid.macro_ticks) == k * 1e-3, f"t({k} steps) must equal {k}*h bit for bit"
    # accumulating h would drift; the grid does not
    acc = 0.0
    for _ in range(1750):
        acc += 1e-3
    assert acc != 1.75 and grid.time(grid.end_ticks) == 1750 * 1e-3


def test_fixed_grid_with_start_offset_and_halvable_steps():
    grid = TimeGrid.fixed(2.5, 3.0, 0.1)
    assert grid.time(3 * grid.macro_ticks) == 2.5 + 3 * 0.1
    half = grid.macro_ticks // 2
    np.testing.assert_allclose(grid.time(half), 2.55, rtol=0, atol=1e-15, err_msg="half step on the grid")


def test_fixed_grid_shortens_the_last_step():
    grid = TimeGrid.fixed(0.0, 1.05, 0.1)
    np.testing.assert_allclose(grid.time(grid.end_ticks), 1.05, rtol=1e-12, err_msg="run must end at stop")
    assert 10 * grid.macro_ticks < grid.end_ticks < 11 * grid.macro_ticks


def test_variable_grid_even_ticks():
    grid = TimeGrid.variable(0.0, 1.0, 1e-6)
    assert grid.even_ticks(1e-3) % 2 == 0
    assert grid.even_ticks(1e-12) == 2
    np.testing.assert_allclose(grid.even_ticks(1e-3) * grid.tick, 1e-3, rtol=1e-3, err_msg="quantized step")


@pytest.mark.parametrize("start, stop, step", [(0.0, 0.0, 1e-3), (1.0, 0.5, 1e-3), (0.0, 1.0, 0.0), (0.0, 1.0, float("nan"))])
def test_bad_spans_raise(start, stop, step):
    with pytest.raises(ParameterError):
        TimeGrid.fixed(start, stop, step)
