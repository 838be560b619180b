"""Debris transport: exact conservation, positivity, advection speed zeta*U_dot, Archard source."""

import numpy as np
from numpy.testing import assert_allclose

from tribocosim.components.stripdraw.transport import advect_implicit, advect_implicit_numpy, advect_loop, archard_source


def test_advection_moves_debris_backwards_at_zeta_times_slip_and_conserves_it():
    n, le = 400, 1e-3
    x = np.arange(n) * le
    beta = np.exp(-(((x - 0.3) / 0.01) ** 2))
    weight = np.ones(n)
    zeta, du = 0.5, 1e-5  # Courant number zeta du / le = 5e-3 per step
    total, centroid = beta.sum(), (x * beta).sum() / beta.sum()
    steps = 2000
    for _ in range(steps):
        beta = advect_implicit(beta, np.full(n, du), weight, zeta, le)
    assert_allclose(beta.sum(), total, rtol=1e-12, err_msg="conservation")
    assert beta.min() >= 0
    moved = (x * beta).sum() / beta.sum() - centroid
    assert_allclose(moved, -zeta * du * steps, rtol=1e-6, err_msg="centroid moves at -zeta U_dot")


def test_no_flux_across_the_pad_edges_and_large_steps_stay_bounded():
    n, le = 50, 1e-3
    weight = np.zeros(n)
    weight[10:30] = 1.0
    beta = np.linspace(0.1, 0.2, n)
    out = advect_implicit(beta, np.full(n, 0.5), weight, 1.0, le)  # Courant number 500
    assert_allclose(out[:10], beta[:10], rtol=0, atol=0)
    assert_allclose(out[30:], beta[30:], rtol=0, atol=0)
    assert_allclose(out[10:30].sum(), beta[10:30].sum(), rtol=1e-13)
    assert out.min() >= 0 and out[10] > beta[10], "tool-carried debris piles up at the entry edge"


def test_archard_source_is_eq_37():
    src = archard_source(np.array([2e-3, -2e-3, 1e-3]), np.array([1.0, 1.0, 0.5]), 1e7, 1e-4, 0.8e9, 0.5e-6)
    assert_allclose(src, 1e-4 * 1e7 / (0.8e9 * 0.5e-6) * np.array([2e-3, 2e-3, 0.5e-3]))


def test_compiled_advection_matches_numpy_reference():
    rng = np.random.default_rng(5)
    n = 80
    weight = np.zeros(n)
    weight[20:60] = rng.uniform(0.2, 1.0, 40)
    beta = rng.uniform(0, 0.3, n)
    dU = rng.normal(0.0, 1e-3, n)  # slip in both directions: both upwind branches
    assert_allclose(advect_loop(beta, dU, weight, 0.4, 1e-3), advect_implicit_numpy(beta, dU, weight, 0.4, 1e-3),
                    rtol=1e-13, atol=1e-16)
