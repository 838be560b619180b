"""Tests of cosim.engine.extrapolation against numpy.polyfit (oracle) and exact integrals."""

import numpy as np
import pytest

from tribocosim.cosim.engine.extrapolation import History, StepPolynomial, taylor_coefficients


@pytest.mark.parametrize("taus", [[0.0], [0.0, -0.1], [0.0, -0.1, -0.25], [0.3, 0.0, -0.05]])
def test_taylor_coefficients_match_polyfit(taus):
    rng = np.random.default_rng(1)
    vals = [rng.normal(size=3) for _ in taus]
    c0, c1, c2 = taylor_coefficients(taus, vals)
    deg = len(taus) - 1
    for j in range(3):
        ref = np.polyfit(taus, [v[j] for v in vals], deg)[::-1]
        ref = np.concatenate([ref, np.zeros(3 - len(ref))])
        np.testing.assert_allclose([c0[j], c1[j], c2[j]], ref, rtol=1e-9, atol=1e-9,
                                   err_msg=f"coefficients of signal {j} through {taus}")


def test_polynomials_of_the_degree_are_reproduced_exactly():
    p = lambda t: 1.5 - 2.0 * t + 0.75 * t * t
    taus = [0.0, -0.01, -0.03]
    c0, c1, c2 = taylor_coefficients(taus, [np.array([p(t)]) for t in taus])
    poly = StepPolynomial(0.02, c0, c1, c2)
    np.testing.assert_allclose(poly.value(0.02), p(0.02), rtol=1e-12, err_msg="extrapolated value")
    np.testing.assert_allclose(poly.derivative(1), -2.0, rtol=1e-9, err_msg="first derivative at tau=0")
    np.testing.assert_allclose(poly.derivative(2), 1.5, rtol=1e-7, err_msg="second derivative")
    # the step mean is the exact integral mean of p over [0, h]
    h = 0.02
    exact = (1.5 * h - h * h + 0.25 * h**3) / h
    np.testing.assert_allclose(poly.mean(), exact, rtol=1e-12, err_msg="mean over the step")


def test_history_extrapolation_order_grows_with_points_and_interpolation_hits_end():
    hist = History(depth=3)
    f = lambda t: np.array([np.cos(t), t**2])
    hist.push(0, f(0.0))
    poly = hist.extrapolate(2, 0.1, 0.1)
    np.testing.assert_allclose(poly.c1, 0.0, err_msg="one point: constant extrapolation")
    for n in (1, 2, 3):
        hist.push(n, f(0.1 * n))
    assert hist.ticks == [1, 2, 3], "depth 3 keeps the newest three points"
    poly = hist.extrapolate(2, 0.1, 0.1)
    np.testing.assert_allclose(poly.value(0.1)[1], 0.4**2, rtol=1e-12, err_msg="t^2 extrapolated exactly")
    end = f(0.4)
    ip = hist.interpolate(1, 0.1, 0.1, end)
    np.testing.assert_allclose(ip.value(0.1), end, rtol=1e-14, err_msg="interpolation passes through the end value")
    np.testing.assert_allclose(ip.value(0.0), f(0.3), rtol=1e-14, err_msg="... and through the newest point")
    snap = hist.copy()
    hist.push(4, f(0.5))
    assert snap.ticks == [1, 2, 3], "a copy is not changed by later pushes"
