"""Tests of surrogate.fit: ensemble statistics and the fits of Eq. 23, Fig. 15 and Eq. 8 recover
known parameters from synthetic campaign records with noise."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tribocosim.errors import ParameterError
from tribocosim.surrogate.fit import (alpha_law, ensemble, fit_all, fit_alpha, fit_alpha_law, fit_contact,
                           fit_through_origin)

E_STAR, P_CRIT = 55e9, 340e6
B_TRUE, VREF_TRUE = 60.0, 8.0
P = [2e6, 5e6, 10e6, 20e6, 30e6]
V = [1.0, 2.0, 5.0, 10.0, 20.0, 50.0]
BETAS = [0.01, 0.02, 0.04]
SEEDS = [1, 2, 3]


def synthetic_records(noise=0.05, seed=0, b=B_TRUE, v_ref=VREF_TRUE, pressures=P, velocities=V,
                      betas=BETAS, seeds=SEEDS, ac_slope=1 / P_CRIT):
    """Case records whose <A_p>/A0 = alpha(v) beta P / E* and <A_c>/A0 = s_c P, times (1 + noise)."""
    rng = np.random.default_rng(seed)

    def noisy(x):
        return float(x * (1 + noise * rng.standard_normal()))

    recs = []
    for p in pressures:
        for v in velocities:
            recs.append({"labels": {"pressure": p, "velocity": v, "beta": 0.0, "seed": None, "surface": 0},
                         "summary": {"mean_particle_fraction": 0.0,
                                     "mean_contact_fraction": noisy(ac_slope * p)}})
            for beta in betas:
                for s in seeds:
                    ap = float(alpha_law(v, b, v_ref)) * beta * p / E_STAR
                    recs.append({"labels": {"pressure": p, "velocity": v, "beta": beta, "seed": s, "surface": 0},
                                 "summary": {"mean_particle_fraction": noisy(ap),
                                             "mean_contact_fraction": noisy(ac_slope * p)}})
    return recs


def test_ensemble_mean_and_std_per_point():
    recs = [{"labels": {"pressure": 1e7, "velocity": 5.0, "beta": 0.02, "seed": s, "surface": 0},
             "summary": {"mean_particle_fraction": ap, "mean_contact_fraction": ac}}
            for s, ap, ac in ((1, 1e-4, 0.03), (2, 2e-4, 0.031), (3, 3e-4, 0.032))]
    ens = ensemble(recs)
    (pt,) = ens.values()
    assert pt.n == 3
    assert_allclose([pt.ap_mean, pt.ap_std], [2e-4, 1e-4], rtol=1e-12)
    assert_allclose([pt.ac_mean, pt.ac_std], [0.031, 0.001], rtol=1e-12)


def test_fit_through_origin_exact_line_and_r2():
    x = np.array([1.0, 2.0, 3.0])
    a, se, r2 = fit_through_origin(x, 2.5 * x)
    assert_allclose(a, 2.5, rtol=1e-14)
    assert se == pytest.approx(0.0, abs=1e-14) and r2 == pytest.approx(1.0)
    with pytest.raises(ParameterError):
        fit_through_origin([0.0], [1.0])


def test_alpha_per_velocity_recovers_eq23_with_noise():
    ens = ensemble(synthetic_records(noise=0.05))
    fits = fit_alpha(ens, E_STAR)
    assert [f.velocity for f in fits] == V
    for f in fits:
        truth = float(alpha_law(f.velocity, B_TRUE, VREF_TRUE))
        # the spread of the per-placement alphas is the uncertainty of Fig. 15
        assert abs(f.alpha - truth) < 3 * f.alpha_member_std, (f.velocity, f.alpha, truth)
        assert abs(f.alpha - truth) / truth < 0.05
        assert f.r2 > 0.95, "A_p proportional to beta P: R^2 close to 1"
        assert len(f.member_alphas) == 3 and f.alpha_member_std > 0


def test_alpha_law_recovers_b_and_vref_with_uncertainties():
    fits = fit_all(ensemble(synthetic_records(noise=0.05, seed=3)), E_STAR, 0.34)
    law = fits.law
    assert abs(law.b - B_TRUE) < 4 * law.b_err and abs(law.b - B_TRUE) / B_TRUE < 0.05
    assert abs(law.v_ref - VREF_TRUE) < 4 * law.v_ref_err and abs(law.v_ref - VREF_TRUE) / VREF_TRUE < 0.1
    assert 0 < law.b_err < 0.1 * B_TRUE and 0 < law.v_ref_err < 0.3 * VREF_TRUE
    assert law.r2 > 0.98 and law.note == ""


def test_alpha_law_noise_free_is_exact_and_undefined_errors_with_two_points():
    v = np.array([1.0, 3.0, 10.0, 30.0])
    law = fit_alpha_law(v, alpha_law(v, 40.0, 5.0))
    assert_allclose([law.b, law.v_ref], [40.0, 5.0], rtol=1e-6)
    two = fit_alpha_law(v[:2], alpha_law(v[:2], 40.0, 5.0))
    assert math.isnan(two.b_err) and math.isnan(two.v_ref_err)


def test_saturated_alpha_gives_small_vref_with_a_note_and_zero_alpha_gives_b_zero():
    v = np.array([1.0, 10.0, 50.0])
    law = fit_alpha_law(v, [30.0, 30.5, 29.8], [1.0, 1.0, 1.0])
    assert law.b == pytest.approx(30.1, abs=0.5)
    assert law.v_ref < 0.5 and "below the smallest campaign velocity" in law.note
    assert math.isnan(law.v_ref_err), "an unconstrained v_ref has no uncertainty, not zero"
    zero = fit_alpha_law(v, [0.0, 0.0, 0.0])
    assert zero.b == 0.0 and math.isnan(zero.v_ref) and np.all(zero(v) == 0.0)


def test_contact_slope_uses_particle_free_cases_and_gives_kappa():
    ens = ensemble(synthetic_records(noise=0.02, seed=5))
    c = fit_contact(ens, E_STAR, 0.3)
    assert c.source.startswith("particle-free") and c.n_points == len(P) * len(V)
    assert abs(c.slope * P_CRIT - 1) < 0.02 and c.r2 > 0.99
    assert_allclose(c.kappa, c.slope * E_STAR * 0.3, rtol=1e-14,
                    err_msg="kappa = s_c E* h'_rms (Eq. 8 read backwards)")
