"""Tests of the stability report's building blocks on cases with known answers.

- bisection: a judge with a known threshold;
- growth detection: synthetic growing, decaying and neutral oscillations (exact per-period ratios),
  a growing oscillation on a ramp plus a slow second mode, an insignificant ripple, noise;
- the criterion: a NaN, a bound, a growth, each named;
- Jacobi (extrapolation 0) on the stiff two-mass oscillator (k2 = 1e4): the stability limit from
  the spectral radius of the exact one-step map (derived here with numpy alone, independently of
  cosim.reports.monodromy) against the bisection through the real master and FMUs with the
  report's run-based criterion (within 5 %).
"""

import math

import numpy as np
import pytest

from tribocosim.cosim.reports.stability_criterion import (ERROR, STABLE, UNSTABLE, Criterion, Verdict, classify, growth_bounds,
                                     growth_factor, largest_stable_step, swings)


# ----------------------------------------------------------------------------- bisection
@pytest.mark.parametrize("lazy", [False, True])
def test_bisection_finds_a_known_threshold(lazy):
    limit = 0.0123
    calls = []

    def judge(h):
        calls.append(h)
        return Verdict(STABLE) if h <= limit else Verdict(UNSTABLE, f"h = {h:g} above the limit")

    res = largest_stable_step(judge, 1e-6, 1.0, rel=0.01, lazy_lo=lazy)
    assert res.stable_step <= limit < res.unstable_step
    assert res.unstable_step / res.stable_step <= 1.01 + 1e-12
    assert "above the limit" in res.reason
    assert res.evaluations == len(calls) <= 16
    assert (1e-6 in calls) != lazy  # lazy: the presumed-stable lower end is never run


def test_bisection_edges_and_scan_for_a_stability_window():
    always = largest_stable_step(lambda h: Verdict(STABLE), 1e-3, 1.0)
    assert always.stable_step == 1.0 and math.isinf(always.unstable_step)
    never = largest_stable_step(lambda h: Verdict(UNSTABLE, "no"), 1e-3, 1.0, lazy_lo=True)
    assert never.stable_step == 0.0 and never.reason == "no"
    # stable on [lo, 0.01] and again on [0.1, 1]: plain bisection may land in the upper window,
    # the scan finds the first instability
    window = lambda h: Verdict(STABLE if h <= 0.01 or h >= 0.1 else UNSTABLE, "window")  # noqa: E731
    scanned = largest_stable_step(window, 1e-4, 1.0, scan_per_decade=4, rel=0.01)
    assert scanned.stable_step <= 0.01 < scanned.unstable_step <= 0.0102


# ----------------------------------------------------------------------------- growth detection
T = np.arange(0.0, 20.0, 0.005)


@pytest.mark.parametrize("rate", [0.05, 0.002, -0.05, 0.0])
def test_growth_factor_of_exponential_oscillations_is_exact(rate):
    y = np.exp(rate * T) * np.sin(2 * np.pi * T)  # period 1 s: ratio exp(rate) per period
    assert growth_factor(y) == pytest.approx(math.exp(rate), rel=1e-6)
    v = classify(T, {"y": y}, {})
    assert v.status == (UNSTABLE if rate > 0 else STABLE), v.reason
    if rate > 0:
        assert "growing oscillation in y" in v.reason


def test_growth_on_a_ramp_with_a_slow_second_mode():
    y = 5 * T + 3 * np.sin(0.3 * T) + np.exp(0.01 * T) * np.sin(2 * np.pi * 7 * T)
    assert growth_factor(y) == pytest.approx(math.exp(0.01 / 7), rel=5e-4)
    assert classify(T, {"y": y}, {}).status == UNSTABLE
    decaying = 5 * T + 3 * np.sin(0.3 * T) + np.exp(-0.01 * T) * np.sin(2 * np.pi * 7 * T)
    assert growth_factor(decaying) == pytest.approx(math.exp(-0.01 / 7), rel=5e-4)
    assert classify(T, {"y": decaying}, {}).stable


def test_insignificant_ripple_and_noise_are_not_growth():
    ripple = 1000 + 0.2 * (1 + 0.001 * T) * np.sin(2 * np.pi * 3 * T)  # 0.02 % ripple, slowly growing
    assert math.isnan(growth_factor(ripple))
    rng = np.random.default_rng(3)
    noisy = 100 + 20 * (1 + 0.3 * rng.standard_normal(T.size // 50)).repeat(50) * np.sin(2 * np.pi * T)
    ratio, lower = growth_bounds(noisy)
    assert lower < 1.0, "a scatter without trend must not count as growth"
    assert classify(T, {"y": noisy}, {}).stable
    assert swings(np.array([0.0, 1.0, -1.0, 2.0, 0.5])).tolist() == [2.0, 3.0]  # interior extrema only


def test_a_kick_that_rings_down_after_decayed_noise_is_not_growth():
    """Ringing decays into round-off, then an event kicks a new, decaying ringing: the swings jump up
    once but the oscillation does not grow."""
    kick = (T > 14.0) * np.exp(-0.5 * np.clip(T - 14.0, 0, None)) * 1e-3
    y = 8.0 + 1e-3 * np.exp(-3 * T) * np.sin(2 * np.pi * 5 * T) + kick * np.sin(2 * np.pi * 5 * T)
    assert classify(T, {"v": y}, {}).stable
    # the same jump followed by growth is growth
    grow = (T > 14.0) * np.exp(0.5 * np.clip(T - 14.0, 0, None)) * 1e-3
    y = 8.0 + 1e-3 * np.exp(-3 * T) * np.sin(2 * np.pi * 5 * T) + grow * np.sin(2 * np.pi * 5 * T)
    assert classify(T, {"v": y}, {}).status == UNSTABLE


def test_classify_names_the_failed_test():
    t = np.linspace(0.0, 1.0, 11)
    y = np.zeros(11)
    y[6] = np.nan
    v = classify(t, {"a.x": np.zeros(11), "b.f": y}, {})
    assert v.status == UNSTABLE and "non-finite b.f" in v.reason and "t = 0.6" in v.reason
    v = classify(t, {"b.f": np.linspace(0, 30, 11)}, {"b.f": 2.0})
    assert v.status == UNSTABLE and "|b.f| reached 15 x" in v.reason
    assert classify(t, {"b.f": np.linspace(0, 19, 11)}, {"b.f": 2.0}).stable
    assert Criterion().bound_factor == 10.0 and "10 x" in Criterion().describe()
    assert Verdict(ERROR, "boom").short() == "error: boom"


# ----------------------------------------------------------------------------- Jacobi on the stiff oscillator
K1, K2, K3, C1, C2, C3, M1, M2 = 10.0, 1e4, 20.0, 0.2, 0.5, 0.3, 1.0, 1.0


def _expm_eig(a):
    lam, v = np.linalg.eig(a)
    return (v @ np.diag(np.exp(lam)) @ np.linalg.inv(v)).real


def jacobi0_monodromy(h):
    """Exact one-step map of Jacobi/0 on z = (x1, v1, x2, v2): one 7-state system in which the held
    coupling values (F, x1, v1 at t_n) are constant states, started from z_n, exponentiated by
    eigen-decomposition (numpy only)."""
    a = np.zeros((7, 7))
    a[0, 1] = 1.0
    a[1, 0], a[1, 1], a[1, 4] = -K1 / M1, -C1 / M1, 1.0 / M1
    a[2, 3] = 1.0
    a[3, 2], a[3, 3], a[3, 5], a[3, 6] = -(K2 + K3) / M2, -(C2 + C3) / M2, K2 / M2, C2 / M2
    s = np.zeros((7, 4))
    s[:4, :4] = np.eye(4)
    s[4] = [-K2, -C2, K2, C2]  # F_n
    s[5, 0] = s[6, 1] = 1.0  # x1_n, v1_n held
    return (_expm_eig(a * h) @ s)[:4]


def exact_limit():
    rho = lambda h: max(abs(np.linalg.eigvals(jacobi0_monodromy(h))))  # noqa: E731
    lo, hi = 1e-5, 1e-3
    assert rho(lo) < 1.0 < rho(hi)
    while hi / lo > 1.0 + 1e-6:
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if rho(mid) <= 1.0 else (lo, mid)
    return lo


def test_monodromy_of_the_report_agrees_with_this_derivation():
    from tribocosim.cosim.reports.monodromy import jacobi0_map

    for h in (1e-5, 1.6e-4, 1e-3):
        np.testing.assert_allclose(jacobi0_map(h, K2), jacobi0_monodromy(h), rtol=1e-9, atol=1e-9)


def test_jacobi_stability_limit_through_the_master_matches_the_exact_one_step_map(tmp_path, fmu_dir):
    from tribocosim.cosim.studies.monolithic import TwoMassOscillator
    from tribocosim.cosim.reports.oscfmus import oscillator_scene
    from tribocosim.cosim.reports.runner import judged_run
    from tribocosim.cosim.scene.validate import load_scene

    h_exact = exact_limit()
    assert 1.5e-4 < h_exact < 1.8e-4, h_exact  # ~1.667 / k2
    omega = max(abs(np.linalg.eigvals(TwoMassOscillator(k2=K2).matrix()).imag))
    t_end = 8 * 2 * math.pi / omega  # 8 periods of the stiff mode
    ref = TwoMassOscillator(k2=K2).solve(np.linspace(0.0, t_end, 2001))
    scales = {n: float(np.max(np.abs(ref[n]))) for n in ("a.x1", "b.x2", "b.force")}
    verdicts = {}

    def judge(h):
        n = int(round(t_end / h))
        scene = oscillator_scene(tmp_path, fmu_dir, step=h, stop=n * h, k2=K2)
        verdicts[h] = judged_run(load_scene(scene), scales)[0]
        return verdicts[h]

    lim = largest_stable_step(judge, 2e-5, 1e-3, rel=0.01, lazy_lo=True)
    print(f"\nJacobi/0, k2 = {K2:g}: exact limit {h_exact:.5g} s, bisection through the master {lim.stable_step:.5g} s "
          f"(unstable at {lim.unstable_step:.5g} s: {lim.reason}; {lim.evaluations} runs)")
    assert lim.stable_step == pytest.approx(h_exact, rel=0.05)
    assert "growing oscillation" in lim.reason or "reached" in lim.reason
