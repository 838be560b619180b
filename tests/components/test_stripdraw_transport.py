"""Debris transport (the native implicit upwind advection, tc_sd_advect): exact conservation, positivity,
advection speed zeta U_dot, no flux across the pad's edges."""

import numpy as np
from numpy.testing import assert_allclose

from tribocosim.components.native.toolchain.library import core, ptr


def advect_implicit(beta, dU, weight, zeta, element_length):
    """One implicit upwind advection step of the native core."""
    beta, dU, weight = (np.ascontiguousarray(a, dtype=float) for a in (beta, dU, weight))
    out, work = np.empty(beta.size), np.empty(5 * beta.size)
    core().lib.tc_sd_advect(beta.size, ptr(beta), ptr(dU), ptr(weight), zeta, element_length, ptr(out), ptr(work))
    return out


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
