"""Tests of cosim.reports.metrics: the error metric and the cheapest-setting selection (known answers)."""

import math

import numpy as np
import pytest

from tribocosim.cosim.reports.metrics import cheapest_reaching, max_relative_error, relative_difference


def test_max_relative_error_is_the_largest_deviation_over_the_reference_range():
    t = np.linspace(0.0, 1.0, 101)
    ref = np.sin(2 * np.pi * t) * 4.0  # max |ref| = 4
    y = ref.copy()
    y[37] += 0.02  # deviation 0.02 -> 0.005 of the range
    y[80] -= 0.01
    assert max_relative_error(t, y, t, ref) == pytest.approx(0.005, rel=1e-12)
    assert max_relative_error(t, y, t, ref, scale=2.0) == pytest.approx(0.01, rel=1e-12)


def test_reference_on_another_grid_is_interpolated_linearly():
    """A linear reference sampled coarsely is interpolated exactly; the run sees only its own points."""
    t_ref = np.linspace(0.0, 2.0, 5)
    ref = 3.0 * t_ref + 1.0  # max |ref| = 7
    t = np.linspace(0.0, 2.0, 41)
    y = 3.0 * t + 1.0 + 0.07 * (t == t[13])
    assert max_relative_error(t, y, t_ref, ref) == pytest.approx(0.01, rel=1e-9)


def test_non_finite_run_has_infinite_error_and_a_short_reference_is_refused():
    t = np.linspace(0.0, 1.0, 11)
    y = np.ones(11)
    y[4] = np.nan
    assert math.isinf(max_relative_error(t, y, t, np.ones(11)))
    with pytest.raises(ValueError, match="covers"):
        max_relative_error(t, np.ones(11), t[:5], np.ones(5))
    with pytest.raises(ValueError, match="zero"):
        max_relative_error(t, np.ones(11), t, np.zeros(11))


def test_relative_difference():
    assert relative_difference(0.1414, 0.1400) == pytest.approx(0.01, rel=1e-9)
    assert math.isinf(relative_difference(float("nan"), 1.0))


def test_cheapest_setting_per_target():
    rows = [{"setting": "a", "error": 2e-2, "wall_time": 0.1},
            {"setting": "b", "error": 5e-3, "wall_time": 0.5},
            {"setting": "c", "error": 4e-3, "wall_time": 0.3},  # cheaper than b and better
            {"setting": "d", "error": 5e-5, "wall_time": 9.0},
            {"setting": "e", "error": float("inf"), "wall_time": 0.01}]  # a failed run never wins
    best = cheapest_reaching(rows, (1e-2, 1e-3, 1e-4, 1e-6))
    assert best[1e-2]["setting"] == "c"
    assert best[1e-3]["setting"] == "d"
    assert best[1e-4]["setting"] == "d"
    assert best[1e-6] is None


def test_summary_curves_get_their_own_cheapest_rows():
    """A family's summary_curves are summarised alone too: the adaptive rows of the demo show even when a fixed
    step is the family's cheapest."""
    from tribocosim.cosim.reports.common import Family
    from tribocosim.cosim.reports.markdown import accuracy_markdown

    rows = [{"curve": "fixed", "setting": "h=1", "error": 1e-3, "wall_time": 1.0, "do_steps": 10},
            {"curve": "adaptive", "setting": "tol=1", "error": 5e-4, "wall_time": 3.0, "do_steps": 30},
            {"curve": "adaptive", "setting": "tol=2", "error": 5e-2, "wall_time": 2.0, "do_steps": 20}]
    fam = Family("f", "F", rows=rows, curve="curve", summary_curves=("adaptive",))
    text = accuracy_markdown([fam], {}, "# r")
    summary = text.split("## Summary")[1].split("\n\n")[1]
    assert "| f | error | h=1 (1 s, 10 doSteps) | h=1 (1 s, 10 doSteps) | not reached |" in summary
    assert "| f: adaptive | error | tol=1 (3 s, 30 doSteps) | tol=1 (3 s, 30 doSteps) | not reached |" in summary
