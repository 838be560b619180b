"""The strip-draw model's inputs as polynomials over a step (``step(..., derivatives=...)``).

Each coupling interval [a, b] takes the mean of u(s) = u + u' s + u'' s^2 / 2 over [a, b]:
so one interpolated step is, bit for bit, the sequence of held steps that take those means over the same
intervals; zero derivatives are a held step; a normal force that the polynomial takes below zero is a pad
that lifts off (no pressure, no friction) on those intervals.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tribocosim.errors import ParameterError
from tribocosim.components.stripdraw.friction import make_friction_law
from tribocosim.components.stripdraw.model import StripDrawModel
from tribocosim.components.stripdraw.parameters import StripDrawParameters

TAU = 1e-4
F_N = 12250.0


def _model(**kw):
    p = StripDrawParameters(friction_model="closed_form", draw_length=0.01, n_elements=40, internal_step=TAU, **kw)
    return StripDrawModel(p, make_friction_law(p, None))


def _same_state(a: StripDrawModel, b: StripDrawModel) -> bool:
    """Same physical state (the step count and the float sum of the steps may differ)."""
    return all(np.array_equal(getattr(a, k), getattr(b, k)) for k in ("U", "V", "A", "Up", "beta", "slip_rate"))


def input_mean(poly, a, b):
    """The mean over [a, b] of c0 + c1 s + c2 s^2, in the native model's operation order (tc_stripdraw.c)."""
    c0, c1, c2 = poly
    return c0 + c1 * 0.5 * (a + b) + c2 * (a * a + a * b + b * b) / 3.0


def test_the_interval_mean_is_the_polynomials_mean():
    poly = (2.0, -3.0, 5.0)
    a, b = 0.3, 0.7
    exact = (poly[0] * (b - a) + poly[1] * (b * b - a * a) / 2 + poly[2] * (b ** 3 - a ** 3) / 3) / (b - a)
    assert input_mean(poly, a, b) == pytest.approx(exact, rel=1e-15)


def test_one_interpolated_step_is_the_held_steps_at_the_interval_means():
    """At 2 mm/s the pad slides less than window_courant elements per internal step, so each grid piece is one
    coupling interval; 10 held steps of tau at the means are the interpolated step of 10 tau, bit for bit."""
    warm = {"normal_force": F_N, "grip_velocity": 0.002}
    a, b = _model(), _model()
    for m in (a, b):
        for _ in range(20):
            m.step(TAU, warm)
    d = {"normal_force": (3e6, -4e8), "grip_velocity": (5.0, 100.0)}
    out_a = a.step(10 * TAU, warm, d)
    fn = (F_N, d["normal_force"][0], 0.5 * d["normal_force"][1])
    vg = (0.002, d["grip_velocity"][0], 0.5 * d["grip_velocity"][1])
    s0 = 0.0  # the model's time into the step: the running sum of the pieces
    for _ in range(10):
        out_b = b.step(TAU, {"normal_force": input_mean(fn, s0, s0 + TAU), "grip_velocity": input_mean(vg, s0, s0 + TAU)})
        s0 += TAU
    assert out_a == out_b
    assert _same_state(a, b)


def test_zero_derivatives_are_a_held_step():
    a, b = _model(), _model()
    u = {"normal_force": F_N, "grip_velocity": 0.08}
    for _ in range(5):
        assert a.step(7e-4, u, {"normal_force": (0.0, 0.0), "grip_velocity": (0.0, 0.0)}) == b.step(7e-4, u)
    assert _same_state(a, b)


def test_a_normal_force_interpolated_below_zero_lifts_the_pad():
    """F_N falling from 1000 N at 2e6 N/s reaches 0 at 0.5 ms: in a 1 ms step the last intervals carry no
    pressure, so the step ends with no friction, whatever the history; the input itself must stay >= 0."""
    m = _model()
    for _ in range(10):
        m.step(TAU, {"normal_force": F_N, "grip_velocity": 0.08})
    out = m.step(1e-3, {"normal_force": 1000.0, "grip_velocity": 0.08}, {"normal_force": (-2e6, 0.0)})
    assert out["contact_pressure"] == 0.0
    assert out["friction_force"] == 0.0 and out["mu_mean"] == 0.0
    with pytest.raises(ParameterError, match="normal_force = -1 N must be >= 0"):
        m.step(1e-3, {"normal_force": -1.0, "grip_velocity": 0.08}, {"normal_force": (5e6, 0.0)})


@pytest.mark.parametrize("name", ["normal_force", "grip_velocity"])
def test_non_finite_derivatives_are_refused_with_the_state_unchanged(name):
    m = _model()
    m.step(TAU, {"normal_force": F_N, "grip_velocity": 0.08})
    before = m.get_state()
    with pytest.raises(ParameterError, match=rf"d2\({name}\)/dt2 = inf"):
        m.step(1e-3, {"normal_force": F_N, "grip_velocity": 0.08}, {name: (0.0, math.inf)})
    assert np.array_equal(before, m.get_state())
