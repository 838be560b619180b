"""Iterative coupling of the demo rig at 0.99 p_crit, through the native FMUs.

The press closes the pads with 0.99 x 340 MPa x 35 mm x 35 mm = 412335 N; the strip takes the closed-form
friction law (Eq. 9), because the shipped friction table's pressure axis does not reach 337 MPa (the scene
check refuses the set-point). Iterative coupling, extrapolation 0, h = 1 ms, the first 20 ms (the drive's
velocity ramp, where the coupling is hardest: later the fixed-point iteration of the monolithic reference needs
fewer and fewer passes).

What the physics gives, measured (whole draw to 0.3 s in the accuracy report's ``near_pcrit`` family):

- The coupling map of a step is a contraction, but a slow one with a turn in it. The residual of plain
  fixed-point iteration (relaxation 1) repeats its sign pattern every four iterations (pull force +, +, -, -
  with alternating magnitudes), so the map's derivative on the loop strip.pull_force -> drive.pull_force ->
  drive.grip_velocity -> strip.grip_velocity has eigenvalues +-i rho: a faster grip pulls harder, a harder
  pull slows the drive, a negative loop gain -rho^2 per round. rho = 0.87 at t = 0 and 0.96 at t = 1 ms, so
  fixed point needs some 130 and 400+ iterations to reach the master's 1e-8 from a scaled residual of 1e7,
  and with the default 50 it stops at t = 0 with ``ConvergenceError`` (``RunFailed`` from the API) that
  reports the contraction. Aitken's relaxation does not help (0.88 at t = 0, the same failure).
- Quasi-Newton (IQN-ILS, the default) learns the loop from the secants and converges in 2-5 iterations per
  step (largest observed contraction 0.006 over these 20 steps, 0.05 over 300).
- A constant relaxation chosen from the measured contraction also converges: with eigenvalues +-i rho the
  relaxed map has |1 - w + i w rho|, smallest at w = 1 / (1 + rho^2) (0.57 from rho = 0.87), where the rate is
  rho / sqrt(1 + rho^2) ~ 0.66-0.70 (observed 0.63); at that rate a step needs up to 53 iterations, so the
  test allows 200. It costs about ten times the iterations of quasi-Newton.
"""

from __future__ import annotations

import numpy as np
import pytest

from tribocosim.errors import ConvergenceError, RunFailed
from tribocosim.paths import scene_file
from tribocosim.cosim.api import run
from tribocosim.cosim.studies.monolithic import reference_for_scene
from tribocosim.cosim.scene.validate import load_scene

P_CRIT = 340e6
STOP = 0.02
STEP = 1e-3
NEAR = {"experiment.stop": STOP, "experiment.step": STEP, "fmus.drive.parameters.start_time": 0.0,  # drive at once
        "fmus.press.parameters.force_setpoint": 0.99 * P_CRIT * 0.035 * 0.035,
        "fmus.strip.parameters.friction_model": "closed_form"}
#: the master's convergence test per coupling value, |G(x) - x| <= TOL (1 + |x|) (the default of [master.iterative])
TOL = 1e-8
#: the reference's, and the contraction of its plain fixed-point iteration (largest measured, t = 1 ms)
REF_TOL, REF_RHO = 1e-10, 0.965
#: Agreement of pull_force with the monolithic reference at the same step (the same implicit coupling, inputs held
#: at their end values, solved by the reference's own fixed point), relative to max |F_ref|. Per step, the master's
#: accepted outputs are within about TOL of the exact fixed point (|(I - G')^-1| <= 1 for eigenvalues +-i rho) and
#: the reference's within REF_TOL rho / (1 - rho) = 2.8e-9; if every step's error added up with one sign, 20 steps
#: make 20 x 1.3e-8 = 2.6e-7. Measured: 1.8e-9 (quasi-Newton). An iteration stopped early is off by the residual it
#: stopped at (2 fixed-point iterations: ~1e-4) and the fine reference (dt = 5e-5 s) differs by 2e-2 (the time
#: discretization at 1 ms), so the bound tells a converged coupling from both.
RTOL = STOP / STEP * (TOL + REF_TOL * REF_RHO / (1 - REF_RHO)) * 1.1


def _iterative(method: str, relaxation: float | str = 1.0, max_iterations: int = 50) -> dict:
    return {**NEAR, "master.algorithm": "iterative", "master.extrapolation": 0,
            "master.iterative": {"method": method, "relaxation": relaxation, "max_iterations": max_iterations}}


@pytest.fixture(scope="module")
def f_ref() -> np.ndarray:
    """strip.pull_force of the monolithic reference (pure models) at the communication points."""
    ref = reference_for_scene(load_scene(scene_file("demo"), NEAR), STEP, tol=REF_TOL, max_iterations=2000)
    return ref.solve(STEP * np.arange(round(STOP / STEP) + 1))["strip.pull_force"]


@pytest.fixture(scope="module")
def fixed_point_failure() -> RunFailed:
    with pytest.raises(RunFailed) as info:
        run("demo", overrides=_iterative("fixed-point"), write=False)
    return info.value


def _error(res, f_ref) -> float:
    assert np.allclose(res.time, STEP * np.arange(f_ref.size), rtol=0, atol=1e-12)
    return float(np.max(np.abs(res["strip.pull_force"] - f_ref)) / np.max(np.abs(f_ref)))


def test_quasi_newton_converges_and_agrees_with_the_monolithic_reference(f_ref):
    res = run("demo", overrides=_iterative("quasi-newton"), write=False)
    steps = res.metadata["steps"]
    assert steps["accepted"] == 20 and "failure" not in res.metadata
    assert 0 < steps["observed_contraction"] < 0.1, steps  # measured 0.0058
    assert steps["iterations"] <= 6 * 20, steps  # measured 88: 2-5 per step
    err = _error(res, f_ref)
    print(f"\nquasi-Newton: {steps['iterations']} iterations, contraction {steps['observed_contraction']:.3g}, "
          f"pull_force error {err:.2g} (bound {RTOL:.2g})")
    assert err < RTOL, f"pull_force vs the monolithic reference: {err:.3g} >= {RTOL:.3g}"


def test_plain_fixed_point_stops_at_the_first_step_and_reports_the_contraction(fixed_point_failure):
    exc = fixed_point_failure
    cause = exc.__cause__
    assert isinstance(cause, ConvergenceError)
    assert 0.8 < cause.contraction < 1.0, cause.contraction  # measured 0.873: a contraction, but a slow one
    msg = str(exc)
    assert "iterative coupling did not converge in 50 iterations at t = 0 s" in msg, msg
    assert f"estimated contraction factor {cause.contraction:.3g}" in msg, msg
    meta = exc.result.metadata
    assert meta["failure"]["last_accepted_time"] == 0.0 and meta["failure"]["recorded_rows"] == 1
    assert meta["steps"]["observed_contraction"] == cause.contraction  # the stats include the failed step
    assert meta["steps"]["iterations"] == 50 and meta["steps"]["accepted"] == 0


def test_relaxation_chosen_from_the_measured_contraction_converges(fixed_point_failure, f_ref):
    rho = fixed_point_failure.__cause__.contraction
    w = 1.0 / (1.0 + rho * rho)  # eigenvalues +-i rho: |1 - w + i w rho| is smallest here
    res = run("demo", overrides=_iterative("fixed-point", w, max_iterations=200), write=False)
    steps = res.metadata["steps"]
    assert steps["accepted"] == 20 and "failure" not in res.metadata
    predicted = rho / np.sqrt(1.0 + rho * rho)
    assert steps["observed_contraction"] < min(rho, predicted + 0.1), (steps, predicted)  # measured 0.626 (0.66)
    qn = run("demo", overrides=_iterative("quasi-newton"), write=False).metadata["steps"]["iterations"]
    assert steps["iterations"] > 3 * qn, (steps, qn)  # measured 836 against 88
    err = _error(res, f_ref)
    print(f"\nfixed point, w = {w:.3f}: {steps['iterations']} iterations, contraction "
          f"{steps['observed_contraction']:.3g} (predicted {predicted:.3g}), pull_force error {err:.2g}")
    assert err < RTOL, f"pull_force vs the monolithic reference: {err:.3g} >= {RTOL:.3g}"


def test_the_stability_report_cells_carry_the_observed_contraction():
    """judged_run (the stability report's runs) puts the master's contraction on the verdict, also when the
    iteration stopped the run."""
    from tribocosim.cosim.reports.runner import judged_run
    from tribocosim.cosim.reports.stability_criterion import ERROR
    from tribocosim.cosim.reports.stability_report import _cell_row, _component_scales

    plan = load_scene(scene_file("demo"), _iterative("quasi-newton"))
    verdict, info = judged_run(plan, _component_scales(plan))
    assert verdict.extra["observed_contraction"] == info["observed_contraction"] < 0.1, (verdict, info)
    assert _cell_row("near p_crit", "iterative/0", verdict, None)["observed_contraction"] < 0.1
    plan = load_scene(scene_file("demo"), _iterative("fixed-point"))
    verdict, _ = judged_run(plan, _component_scales(plan))
    assert verdict.status == ERROR and "ConvergenceError" in verdict.reason, verdict
    assert 0.8 < verdict.extra["observed_contraction"] < 1.0, verdict
