"""Fourier-BEM contact: Westergaard, Hertz, rigid-plastic limit, a brute-force reference,
plastic accumulation, BGT linearity, warm starts and bad input."""

import math
import warnings
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tribocosim.errors import ConvergenceError, ParameterError
from tribocosim.surrogate.bem import ContactResult, ContactSolver, gap_against_flat
from tribocosim.surrogate.fft import RFFT2Pair, export_wisdom, import_wisdom
from tribocosim.surrogate.contact_solutions import (hertz_contact_radius, hertz_peak_pressure,
                                           projected_gradient_contact, rigid_plastic_paraboloid,
                                           westergaard_full_contact_pressure,
                                           westergaard_half_width, westergaard_traction)
from tribocosim.surrogate.surfaces import rms_slope, self_affine_surface

# --------------------------------------------------------------------------- fixtures
WL, WE, WG0, WN = 1e-3, 1e9, 1e-6, 256  # Westergaard: period, E*, amplitude, grid


@pytest.fixture(scope="module")
def westergaard():
    x = np.arange(WN) * WL / WN
    gap = np.tile((WG0 * (1 - np.cos(2 * np.pi * x / WL)))[:, None], (1, WN))
    return x, gap, ContactSolver(WN, WL, WE), westergaard_full_contact_pressure(WE, WG0, WL)


HL, HE, HN = 500e-6, 55e9, 256  # Hertz: period, E*, grid
HR = 10 * HL  # radius of the paraboloid


@pytest.fixture(scope="module")
def bump():
    c = (np.arange(HN) - HN // 2) * HL / HN
    x, y = np.meshgrid(c, c, indexing="ij")
    r2 = x**2 + y**2
    return r2, r2 / (2 * HR)


def _hertz_load(a_over_l):
    a = a_over_l * HL
    force = 4 * HE * a**3 / (3 * HR)
    return force, force / HL**2


# --------------------------------------------------------------------------- Westergaard
def _edge_half_width(row, dx):
    """Half-width from the last two contact points: t^2 is linear near the edge (t ~ sqrt)."""
    k = 0
    while row[k + 1] > 0:
        k += 1
    p1, p2 = row[k - 1] ** 2, row[k] ** 2
    return (k + p2 / (p1 - p2)) * dx


@pytest.mark.parametrize("ratio", [0.1, 0.25, 0.5, 0.75, 0.95])
def test_westergaard_half_width_and_peak(westergaard, ratio):
    x, gap, solver, p_star = westergaard
    p = ratio * p_star
    res = solver.solve(gap, p)
    row = res.traction[:, 0]
    a = westergaard_half_width(p, p_star, WL)
    assert_allclose(_edge_half_width(row, WL / WN), a, rtol=0.01,
                    err_msg=f"contact half-width at p/p* = {ratio}")
    assert_allclose(row.max(), westergaard_traction(0.0, p, p_star, WL), rtol=0.01,
                    err_msg=f"peak traction at p/p* = {ratio}")
    assert_allclose(res.traction.mean(), p, rtol=1e-12, err_msg="mean pressure not imposed")
    assert_allclose(res.contact_area_fraction, 2 * a / WL, atol=2.5 / WN,
                    err_msg="contact fraction 2a/lambda beyond one pixel per edge")


def test_westergaard_full_contact(westergaard):
    x, gap, solver, p_star = westergaard
    full = solver.solve(gap, 1.2 * p_star)
    assert full.contact_area_fraction == 1.0
    assert_allclose(full.traction[:, 3], westergaard_traction(x, 1.2 * p_star, p_star, WL),
                    atol=1e-5 * p_star, err_msg="full-contact traction p + p* cos(2 pi x / lambda)")
    assert solver.solve(gap, 0.97 * p_star).contact_area_fraction < 1.0


# --------------------------------------------------------------------------- Hertz
def test_hertz_single_bump(bump):
    r2, gap = bump
    force, p = _hertz_load(0.1)  # a = L / 10: ~26 pixels, periodic images negligible
    res = ContactSolver(HN, HL, HE).solve(gap, p)
    a_num = math.sqrt(res.contact_area_fraction * HL**2 / math.pi)
    assert_allclose(a_num, hertz_contact_radius(force, HR, HE), rtol=0.03,
                    err_msg="Hertz contact radius")
    assert_allclose(res.traction.max(), hertz_peak_pressure(force, HR, HE), rtol=0.03,
                    err_msg="Hertz peak pressure")


# --------------------------------------------------------------------------- plasticity
def test_saturated_bump_is_capped_and_bearing_area(bump):
    r2, gap = bump
    force, p = _hertz_load(0.1)
    pc = 0.2 * hertz_peak_pressure(force, HR, HE)  # pressed well beyond yield
    res = ContactSolver(HN, HL, HE, p_crit=pc).solve(gap, p)
    assert res.traction.max() <= pc, "traction above p_crit"
    assert res.saturated_area_fraction > 0.95 * res.contact_area_fraction
    assert_allclose(res.contact_area_fraction, p / pc, rtol=0.01,
                    err_msg="contact area of a saturated contact is P A0 / p_crit")
    # rigid-plastic limit (E* -> infinity): bearing-area contact, u_p fills the bump to a level
    stiff = ContactSolver(HN, HL, 1000 * HE, p_crit=pc).solve(gap, p)
    a, depth = rigid_plastic_paraboloid(force, HR, pc)
    assert_allclose(stiff.contact_area_fraction, p / pc, rtol=0.005,
                    err_msg="rigid-plastic contact area")
    assert_allclose(stiff.u_plastic, np.maximum(a * a - r2, 0) / (2 * HR), rtol=0,
                    atol=0.02 * depth, err_msg="rigid-plastic u_p = (a^2 - r^2) / 2R")


def test_plastic_displacement_accumulates(bump):
    r2, gap = bump
    force, p2 = _hertz_load(0.1)
    pc = 0.3 * hertz_peak_pressure(force, HR, HE)
    solver = ContactSolver(HN, HL, HE, p_crit=pc, tol=1e-10)
    first = solver.solve(gap, 0.5 * p2)
    second = solver.solve(gap, p2, u_plastic=first.u_plastic, warm_start=first)
    once = solver.solve(gap, p2)
    depth = once.u_plastic.max()
    assert np.all(second.u_plastic >= first.u_plastic), "u_p decreased on reloading"
    assert second.u_plastic.max() > 1.2 * first.u_plastic.max()
    # monotonic loading of one bump: the two-step u_p equals the one-step u_p
    assert_allclose(second.u_plastic, once.u_plastic, rtol=0, atol=1e-6 * depth,
                    err_msg="u_p after p/2 then p differs from u_p after p")
    again = solver.solve(gap, p2, u_plastic=second.u_plastic)
    assert_allclose(again.u_plastic, second.u_plastic, rtol=0, atol=1e-8 * depth,
                    err_msg="re-solving a conforming state must not add plastic flow")
    slid = solver.solve(np.roll(gap, 3, axis=0), p2, u_plastic=second.u_plastic)
    assert np.all(slid.u_plastic >= second.u_plastic) and slid.u_plastic.max() > depth


def test_fully_saturated_when_pressure_equals_p_crit():
    gap = np.add.outer(np.linspace(0, 1e-6, 16), np.zeros(16))
    res = ContactSolver(16, 1e-4, 1e9, p_crit=1e6).solve(gap, 1e6)
    assert_allclose(res.traction, 1e6, rtol=0, err_msg="every point at p_crit")
    assert_allclose(res.u_plastic, gap.max() - gap, rtol=1e-14, atol=0,
                    err_msg="profile flattened to its top")


# --------------------------------------------------------------------------- reference solver
@pytest.fixture(scope="module")
def small_rough():
    n, size = 32, 100e-6
    h = self_affine_surface(n, size, 0.8, 2 * math.pi / size, 8 * 2 * math.pi / size,
                            rms_slope=0.005, seed=3)
    return n, size, gap_against_flat(h)


@pytest.mark.parametrize("p_crit, p", [(None, 20e6), (200e6, 20e6), (100e6, 30e6)])
def test_matches_projected_gradient_reference(small_rough, p_crit, p):
    n, size, gap = small_rough
    res = ContactSolver(n, size, 55e9, p_crit=p_crit, tol=1e-12).solve(gap, p)
    ref = projected_gradient_contact(gap, size, 55e9, p, p_crit=p_crit)
    assert 0.05 < res.contact_area_fraction < 0.9
    if p_crit is not None:
        assert res.saturated_area_fraction > 0.02
    assert_allclose(res.traction, ref["traction"], rtol=0, atol=1e-7 * ref["traction"].max(),
                    err_msg="traction differs from the projected-gradient reference")
    assert_allclose(res.u_elastic, ref["u_elastic"], rtol=0,
                    atol=1e-7 * np.ptp(ref["u_elastic"]), err_msg="u_e differs")
    assert_allclose(res.u_plastic, ref["u_plastic"], rtol=0,
                    atol=1e-7 * max(ref["u_plastic"].max(), 1e-300), err_msg="u_p differs")
    assert_allclose(res.approach, ref["approach"], rtol=1e-9, err_msg="approach differs")


def test_result_satisfies_eq21(small_rough):
    n, size, gap = small_rough
    solver = ContactSolver(n, size, 55e9, p_crit=100e6, tol=1e-10)
    res = solver.solve(gap, 30e6)
    assert isinstance(res, ContactResult) and res.converged and res.iterations > 0
    k = 2 * np.pi * np.fft.fftfreq(n, d=size / n)
    q = np.hypot(k[:, None], k[None, :])
    kern = np.divide(2.0, 55e9 * q, out=np.zeros_like(q), where=q > 0)
    u = np.real(np.fft.ifft2(np.fft.fft2(res.traction) * kern))
    assert_allclose(res.u_elastic, u, rtol=0, atol=1e-12 * np.ptp(u), err_msg="u_e != K t")
    final = gap + res.u_plastic + res.u_elastic - res.approach  # deformed gap after plastic flow
    scale = gap.std()
    assert final.min() > -1e-8 * scale, "interpenetration left after the solve"
    assert np.abs(final[res.traction > 0]).max() < 1e-8 * scale, "open gap under traction"
    assert_allclose(res.mean_gap, np.maximum(final, 0).mean(), rtol=1e-12, err_msg="mean_gap")


# --------------------------------------------------------------------------- rough, BGT
def test_contact_area_is_linear_in_pressure_on_a_self_affine_surface():
    n, size, estar = 256, 1.0, 1.0
    kappas = []
    for seed in (1, 2, 3):
        h = self_affine_surface(n, size, 0.8, 4 * 2 * math.pi, 64 * 2 * math.pi, rms_slope=1.0,
                                seed=seed)
        gap = gap_against_flat(h)
        slope = rms_slope(gap, size)
        solver = ContactSolver(n, size, estar)
        reduced = np.array([0.005, 0.01, 0.02])  # p / (E* h'_rms)
        area = [solver.solve(gap, r * estar * slope).contact_area_fraction for r in reduced]
        kappas.append(np.array(area) / reduced)
    kappa = np.mean(kappas, axis=0)  # A_c/A0 = kappa p / (E* h'_rms), Eq. 8
    print(f"kappa (256^2, H=0.8, lambda_s = 4 px, 3 seeds) at p/(E* h') = 0.005, 0.01, 0.02: "
          f"{np.round(kappa, 3)}")
    assert_allclose(kappa, kappa.mean(), rtol=0.1, err_msg="A_c/A0 not proportional to p")
    assert 1.6 < kappa.mean() < 2.8, f"kappa = {kappa.mean():.3f} outside the BGT/Hyun range"


def test_warm_start_reaches_the_cold_solution():
    n, size = 128, 500e-6
    h = self_affine_surface(n, size, 0.8, 2 * 2 * math.pi / size, 32 * 2 * math.pi / size,
                            rms_slope=0.34, seed=4)
    gap = gap_against_flat(h)
    for pc in (None, 340e6):
        solver = ContactSolver(n, size, 55e9, p_crit=pc)
        first = solver.solve(gap, 10e6)
        moved = np.roll(gap, 1, axis=0)
        cold = solver.solve(moved, 10e6)
        warm = solver.solve(moved, 10e6, warm_start=first)
        assert_allclose(warm.traction, cold.traction, rtol=0,
                        atol=1e-4 * cold.traction.max(), err_msg="warm start changed the answer")
        exact = solver.solve(moved, 10e6, warm_start=first, warm_shift=(1, 0))
        assert exact.iterations <= 1, "a rigidly shifted problem is solved by the shifted guess"


# --------------------------------------------------------------------------- failure modes
def test_non_convergence_raises_or_is_flagged(small_rough):
    n, size, gap = small_rough
    with pytest.raises(ConvergenceError, match="did not converge"):
        ContactSolver(n, size, 55e9, max_iter=2).solve(gap, 20e6)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = ContactSolver(n, size, 55e9, max_iter=2, on_failure="flag").solve(gap, 20e6)
    assert not res.converged and res.residual > 1e-8
    assert any("did not converge" in str(w.message) for w in caught)


@pytest.mark.parametrize("make, name", [
    (lambda s, g: s.solve(g[:, :-1], 1e6), "gap"),
    (lambda s, g: s.solve(np.where(g > g.mean(), np.nan, g), 1e6), "gap"),
    (lambda s, g: s.solve(g[:16, :16], 1e6), "gap"),
    (lambda s, g: s.solve(g, 0.0), "pressure"),
    (lambda s, g: s.solve(g, 400e6), "p_crit"),
    (lambda s, g: s.solve(g, 1e6, u_plastic=np.zeros((32, 31))), "u_plastic"),
    (lambda s, g: ContactSolver(32, -1.0, 1e9), "size"),
    (lambda s, g: ContactSolver(32, 1e-4, 0.0), "e_star"),
    (lambda s, g: ContactSolver(32, 1e-4, 1e9, p_crit=-5.0), "p_crit"),
    (lambda s, g: ContactSolver(32, 1e-4, 1e9, on_failure="ignore"), "on_failure"),
])
def test_bad_input_names_the_argument(small_rough, make, name):
    n, size, gap = small_rough
    solver = ContactSolver(n, size, 55e9, p_crit=340e6)
    with pytest.raises(ParameterError, match=name):
        make(solver, gap)


# --------------------------------------------------------------------------- FFT plans
def test_fft_pair_matches_numpy_and_wisdom_round_trips(tmp_path):
    pair = RFFT2Pair(24)
    x = np.random.default_rng(0).standard_normal((24, 24))
    pair.real_in[...] = x
    assert_allclose(pair.forward(), np.fft.rfft2(x), rtol=0, atol=1e-12, err_msg="rfft2")
    assert_allclose(pair.backward(), 24 * 24 * x, rtol=0, atol=1e-9, err_msg="unnormalised irfft2")
    export_wisdom(tmp_path / "w.json")
    assert import_wisdom(tmp_path / "w.json") and not import_wisdom(tmp_path / "none.json")


def test_plans_are_estimated_unless_a_wisdom_file_is_shared(monkeypatch, tmp_path):
    """Measured plans are chosen by timing and differ between processes under load (and so do the bits of a
    slide); without a shared wisdom file the plans are FFTW's estimate, the same in every process."""
    monkeypatch.delenv("TRIBOCOSIM_FFTW_WISDOM", raising=False)
    assert "FFTW_ESTIMATE" in RFFT2Pair(20)._fwd.flags
    monkeypatch.setenv("TRIBOCOSIM_FFTW_WISDOM", str(tmp_path / "w.json"))
    pair = RFFT2Pair(20)
    assert "FFTW_MEASURE" in pair._fwd.flags and "FFTW_MEASURE" in pair._bwd.flags
    assert (tmp_path / "w.json").exists()


# --------------------------------------------------------------------------- sliding regression
def _flake_slide_case(seed=3, steps=8, n=32, size=64e-6):
    """A tiny sliding loop like surrogate/coupling.py's: a rough tool with a flake plateau (a disc
    lowered by 0.8 um) rolled by one pixel a step, u_plastic accumulating and warm starts; at this
    seed nearly every contact point saturates and the last solve is left with a free set of a
    few points.  Returns the solver, the last solve's inputs and the previous result."""
    rng = np.random.default_rng(seed)
    h = rng.standard_normal((n, n))
    k = np.fft.fftfreq(n)
    q = np.hypot(k[:, None], k[None, :])
    q[0, 0] = 1.0
    h = np.real(np.fft.ifft2(np.fft.fft2(h) * q**-1.8))
    h *= 0.5e-6 / h.std()
    a, b = rng.integers(0, n, 2)
    r = rng.integers(2, 4)
    x, y = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    flake = ((x - a) % n) ** 2 + ((y - b) % n) ** 2 <= r * r
    p = 340e6 * rng.uniform(0.005, 0.05)
    solver = ContactSolver(n, size, 55e9, p_crit=340e6)
    up, last = np.zeros((n, n)), None
    for step in range(steps):
        gap = np.roll(h, step, 0) - np.where(np.roll(flake, step, 0), 0.8e-6, 0.0)
        if step == steps - 1:
            return solver, gap, p, up, last
        last = solver.solve(gap, p, u_plastic=up, warm_start=last)
        up = last.u_plastic


def test_warm_started_slide_with_flake_plateau_converges_and_satisfies_eq21():
    """Regression: after an active-set change that keeps the CG direction, the new direction
    r + beta d_old need not be a descent direction (r.d <= 0).  The solver took that for "no
    free residual" and stopped with ConvergenceError after 5 iterations (campaign cases with
    flakes: "did not converge ... after 4-17 iterations"); it must restart CG instead."""
    solver, gap, p, up, last = _flake_slide_case()
    n, pc = solver.n, solver.p_crit
    res = solver.solve(gap, p, u_plastic=up, warm_start=last)  # raised before the fix
    assert res.converged and res.residual <= solver.tol
    assert res.iterations < 50, "CG should restart, not need the cold-start fallback"
    t = res.traction
    assert res.saturated_area_fraction > 0.5 * res.contact_area_fraction > 0
    # Eq. 21 / KKT on the returned state
    assert t.min() >= 0.0 and t.max() <= pc
    assert_allclose(t.mean(), p, rtol=1e-12, err_msg="mean traction != p")
    k = 2 * np.pi * np.fft.fftfreq(n, d=solver.size / n)
    q = np.hypot(k[:, None], k[None, :])
    kern = np.divide(2.0, 55e9 * q, out=np.zeros_like(q), where=q > 0)
    assert_allclose(res.u_elastic, np.real(np.fft.ifft2(np.fft.fft2(t) * kern)), rtol=0,
                    atol=1e-12 * np.ptp(res.u_elastic), err_msg="u_e != K t")
    before = gap + up + res.u_elastic - res.approach  # G, before the plastic increment
    after = gap + res.u_plastic + res.u_elastic - res.approach
    scale = (gap + up).std()
    free, sat = (t > 0) & (t < pc), t >= pc
    assert after.min() > -1e-7 * scale, "interpenetration left after the solve"
    assert before[t <= 0].min() > -1e-7 * scale, "penetration at zero traction"
    assert np.abs(before[free]).max() < 1e-7 * scale, "free points off contact (complementarity)"
    assert before[sat].max() < 1e-7 * scale, "saturated points with an open gap"
    assert np.all(res.u_plastic >= up) and np.all(res.u_plastic[~sat] == up[~sat])
    cold = solver.solve(gap, p, u_plastic=up)
    assert_allclose(t, cold.traction, rtol=0, atol=1e-6 * pc, err_msg="warm != cold answer")


def test_stalled_cg_hands_over_to_the_projected_gradient_and_matches_the_reference():
    """Regression (accuracy-vs-cost campaign, P 5 MPa, v 25 m/s, 7 flakes, sliding step 32): on
    this flake-modified gap the contact is nearly fully plastic (2 free points, 60 saturated) and
    the CG's active-set changes cycle with the residual stuck at 4.3e-5 for 10,000 iterations.
    The solver must notice the stall and finish with the accelerated projected gradient; the
    answer is checked against the independent brute-force projected gradient."""
    data = np.load(Path(__file__).parent / "data" / "bem_stall_64.npz")
    gap, up, p = data["gap"], data["u_plastic"], float(data["pressure"])
    solver = ContactSolver(64, 128e-6, 55e9, p_crit=340e6, tol=1e-11)
    res = solver.solve(gap, p, u_plastic=up)
    assert res.converged and res.residual <= 1e-11
    assert res.fallback, "the CG does not stall here: keep the test, drop this line"
    assert res.iterations < 1000
    ref = projected_gradient_contact(gap, 128e-6, 55e9, p, p_crit=340e6, u_plastic=up, tol=1e-12)
    assert_allclose(res.traction, ref["traction"], rtol=0, atol=1e-5 * p)
    assert_allclose(res.u_plastic, ref["u_plastic"], rtol=0, atol=1e-6 * np.ptp(gap + up))
    assert res.traction.mean() == pytest.approx(p, rel=1e-12)
