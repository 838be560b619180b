"""Exact linear stepping: expm against closed forms, affine inputs against the analytic solution."""

import math

import numpy as np
from numpy.testing import assert_allclose

from tribocosim.components.linear import AffineInputPropagator, expm


def test_expm_closed_forms():
    w, t = 3.0, 0.7
    rot = expm(np.array([[0.0, w], [-w, 0.0]]) * t)
    assert_allclose(rot, [[math.cos(w * t), math.sin(w * t)], [-math.sin(w * t), math.cos(w * t)]], rtol=1e-13)
    # a defective (Jordan) block: exp([[a, 1], [0, a]] t) = e^{at} [[1, t], [0, 1]]
    a = -250.0
    assert_allclose(expm(np.array([[a, 1.0], [0.0, a]]) * t), math.exp(a * t) * np.array([[1, t], [0, 1]]), rtol=1e-12, atol=1e-300)
    big = expm(np.diag([-1e4, 2.0]) * 1e-2)
    assert_allclose(np.diag(big), [math.exp(-100.0), math.exp(0.02)], rtol=1e-12)


def test_affine_input_step_is_exact():
    """x' = -a x + u0 + u1 t has x(t) = (x0 - c0) e^{-a t} + c0 + (u1/a) t with c0 = (u0 - u1/a)/a."""
    a, u0, u1, x0, dt = 40.0, 3.0, -7.0, 0.2, 0.013
    prop = AffineInputPropagator(np.array([[-a]]), np.array([[1.0]]))
    c0 = (u0 - u1 / a) / a
    exact = (x0 - c0) * math.exp(-a * dt) + c0 + u1 / a * dt
    assert_allclose(prop.step(np.array([x0]), dt, u0, u1), [exact], rtol=1e-13)
    # two half steps equal one step (no discretisation error)
    half = prop.step(prop.step(np.array([x0]), dt / 2, u0, u1), dt / 2, u0 + u1 * dt / 2, u1)
    assert_allclose(half, [exact], rtol=1e-13)


def test_expm_is_accurate_entry_by_entry_on_a_badly_scaled_controller_matrix():
    """The drive's matrix mixes entries of 1e-3 and 4e13 (PI integral state in physical units);
    balancing keeps every entry of exp(A h) accurate (scipy's expm as the independent oracle)."""
    scipy_linalg = __import__("pytest").importorskip("scipy.linalg")
    from tribocosim.components.machine import MachineModel, MachineParameters

    prop = MachineModel(MachineParameters())._prop
    n = prop.A.shape[0]
    for dt in (1e-3, 1e-2):
        E = expm(prop.A * dt)
        R = scipy_linalg.expm(prop.A * dt)
        big = np.abs(R) > 1e-300
        assert_allclose(E[big], R[big], rtol=1e-9, err_msg=f"dt = {dt}")
        assert n == 6
