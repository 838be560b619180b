"""The strip held while the press closes (docs/model.md section 1): with the grip still and the bar at rest as made,
nothing can move whatever the friction limits, so none is looked up or counted and no debris is made, carried or
capped. The press's ramp from 0 passes below the table's first pressure; a strip held through it reads no value
there, and then draws exactly as a strip whose press was closed from the start.
"""

from __future__ import annotations

import numpy as np
import pytest

from tribocosim.components.stripdraw import StripDrawModel, StripDrawParameters, make_friction_law, read_table
from tribocosim.paths import DEFAULT_TABLE

P = 1e7
F_N = P * 0.035 * 0.035
V0 = 0.08
DT = 1e-3


def _model(**changes) -> StripDrawModel:
    p = StripDrawParameters(**changes)
    return StripDrawModel(p, make_friction_law(p, read_table(DEFAULT_TABLE)))


def _close(m: StripDrawModel, grip_velocity: float = 0.0) -> list[dict]:
    """The press's ramp from 0 to F_N over 50 steps, then 10 steps at F_N (the first pressure 0.2 MPa)."""
    return [m.step(DT, {"normal_force": F_N * min(1.0, (k + 1) / 50), "grip_velocity": grip_velocity})
            for k in range(60)]


def _draw(m: StripDrawModel, n: int = 150) -> list[dict]:
    return [m.step(DT, {"normal_force": F_N, "grip_velocity": V0 * min(1.0, (k + 0.5) / 20)}) for k in range(n)]


@pytest.mark.parametrize("beta_initial", [0.0, 0.3])
def test_a_strip_held_while_the_press_closes_draws_as_one_closed_from_the_start(beta_initial):
    held, closed = _model(beta_initial=beta_initial), _model(beta_initial=beta_initial)
    field = held.fields()["beta"].copy()
    during = _close(held)
    assert min(out["contact_pressure"] for out in during) < 1e6, "the ramp passes below the table's first pressure"
    for out in during:
        assert out["table_clamp_count"] == 0 and out["pull_force"] == 0.0 and out["friction_force"] == 0.0
    assert np.array_equal(held.fields()["beta"], field), "no debris is made, carried or capped while nothing moves"
    a, b = _draw(held), _draw(closed)
    assert a[-1]["sliding_distance"] > 0.005
    for k, (x, y) in enumerate(zip(a, b)):
        assert x == y, f"step {k} of the draw: a held start changes the result"


def test_a_strip_that_creeps_while_the_press_closes_counts_the_lookups_below_the_table():
    """The rule is the rest, not the pressure: a grip creeping at 1 um/s through the same ramp reads the friction
    below the table's first pressure, and the count says so."""
    during = _close(_model(), grip_velocity=1e-6)
    assert during[-1]["table_clamp_count"] > 0
