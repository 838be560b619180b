"""Tests of cosim.engine.stepcontrol: step doubling, the energy (ECCO) estimator, rejection and rollback."""

import numpy as np
import pytest

from tribocosim.errors import CosimStepError
from tribocosim.cosim import run
from tribocosim.cosim.studies.monolithic import TwoMassOscillator, coupling_error

BOND = """
[[power_bonds]]
effort = ["b.force", "a.force"]
flow = ["a.v1", "b.v1"]
"""


def _sup_error(res):
    return max(coupling_error(res, TwoMassOscillator(), ["a.x1", "b.x2"]).values())


def test_step_doubling_reaches_the_tolerance_with_fewer_do_steps_than_a_fixed_step(tmp_path, osc_scene):
    """Over 30 s the oscillator decays; the controller lengthens the step, a fixed step cannot."""
    tol = 1e-3
    ada = run(osc_scene(tmp_path, name="ada.toml", stop=30.0, step=0.01, extrapolation=1,
                        extra_master=f'[master.adaptive]\ntolerance = {tol}\nmin_step = 1e-6\nmax_step = 1.0\n'
                                     'estimator = "step-doubling"'), write=False)
    err_ada = _sup_error(ada)
    calls = ada.metadata["fmi_calls"]["a"]["doStep"]  # every attempt, rejected ones and the step-H probes included
    assert err_ada <= tol, f"largest error {err_ada:.3g} over the run exceeds the requested tolerance {tol}"
    assert ada.metadata["steps"]["rejected_error"] > 0 and ada.metadata["fmi_calls"]["a"]["setFMUstate"] > 0
    # a fixed step with the same number of doStep calls is clearly less accurate
    h_same = 30.0 / calls
    fixed = run(osc_scene(tmp_path, name="fix.toml", stop=30.0, step=float(h_same), extrapolation=1), write=False)
    err_fixed = _sup_error(fixed)
    print(f"\nstep doubling: {calls} doStep calls per FMU, error {err_ada:.3g}; "
          f"fixed h = {h_same:.4g}: {fixed.metadata['fmi_calls']['a']['doStep']} calls, error {err_fixed:.3g}")
    assert fixed.metadata["fmi_calls"]["a"]["doStep"] <= calls + 1
    assert err_fixed > 2.0 * err_ada, "a fixed step needs more doStep calls than step doubling for the same error"
    steps = np.diff(ada.time)
    assert steps.max() > 4 * steps[len(steps) // 10], "the step grows as the motion decays"


def test_energy_estimator_is_rollback_free_and_tolerance_driven(tmp_path, osc_scene, fmu_dir):
    errors, calls = [], []
    for tol in (1e-2, 1e-3, 1e-4):
        res = run(osc_scene(tmp_path, fmus=fmu_dir / "nostate", name=f"e{tol}.toml", step=0.01, extra=BOND,
                            extra_master=f'[master.adaptive]\ntolerance = {tol}\nmin_step = 1e-5\nmax_step = 0.5\n'
                                         'estimator = "energy"'), write=False)
        assert res.metadata["fmi_calls"]["a"]["getFMUstate"] == 0 and res.metadata["steps"]["rejected_error"] == 0
        assert not res.metadata["fmus"]["a"]["can_roll_back"]
        errors.append(_sup_error(res))
        calls.append(res.metadata["fmi_calls"]["a"]["doStep"])
        steps = np.diff(res.time)
        assert steps.max() > 3 * steps.min(), "the step adapts"
    assert errors[0] > errors[1] > errors[2], f"error must fall with the tolerance: {errors}"
    assert calls[0] < calls[1] < calls[2], f"and cost more steps: {calls}"


def fragile_scene(make_scene, folder, fmus, mode, extra_master="", step=0.05):
    return make_scene(folder, f"fragile{mode}.toml", f"""
        [experiment]
        stop = 1.0
        step = {step!r}

        [master]
        algorithm = "jacobi"
        {extra_master}

        [fmus.f]
        path = "{fmus / 'Fragile.fmu'}"
        parameters = {{ tau = 0.5, max_step = 0.01, t_on = 0.3, t_off = 0.6, mode = {mode} }}

        [output]
        variables = ["f.y"]
        """)


@pytest.mark.parametrize("mode", [0, 1], ids=["discard", "non-finite"])
def test_refused_steps_are_rolled_back_and_halved(tmp_path, make_scene, fmu_dir, mode):
    res = run(fragile_scene(make_scene, tmp_path, fmu_dir, mode), write=False)
    np.testing.assert_allclose(res["f.y"], 1.0 - np.exp(-res.time / 0.5), rtol=1e-12, atol=1e-15,
                               err_msg="exact lag response through the retried steps")
    steps = np.round(np.diff(res.time), 12)
    mid = res.time[:-1] + steps / 2
    inside = (mid >= 0.3) & (mid < 0.6)
    assert set(steps[inside]) == {0.00625}, "0.05 halved three times inside the window"
    assert set(steps[~inside]) == {0.05}, "full macro steps outside the window"
    assert res.metadata["steps"]["rejected_failure"] == 6 * 3


@pytest.mark.parametrize("mode, what", [(0, "discarded the step"), (1, "non-finite output f.y")])
def test_refused_step_without_rollback_stops_with_a_clear_error(tmp_path, make_scene, fmu_dir, mode, what):
    with pytest.raises(CosimStepError) as info:
        run(fragile_scene(make_scene, tmp_path, fmu_dir / "nostate", mode), write=False)
    msg = str(info.value)
    assert "'f'" in msg and what in msg and "t = 0.3" in msg and "cannot roll back" in msg, msg


def test_step_doubling_shrinks_on_discard(tmp_path, make_scene, fmu_dir):
    res = run(fragile_scene(make_scene, tmp_path, fmu_dir, 0, step=0.02, extra_master=(
        '[master.adaptive]\ntolerance = 1e-3\nmin_step = 1e-4\nmax_step = 0.1\nestimator = "step-doubling"')),
        write=False)
    np.testing.assert_allclose(res["f.y"], 1.0 - np.exp(-res.time / 0.5), rtol=1e-12, atol=1e-15,
                               err_msg="exact response with adaptive steps")
    steps = np.diff(res.time)
    mid = res.time[:-1] + steps / 2
    inside = (mid >= 0.3) & (mid < 0.6)  # where Fragile refuses steps longer than 0.01
    assert steps[inside].max() <= 0.01 + 1e-12 and steps[~inside].max() > 0.02
    assert res.metadata["steps"]["rejected_failure"] > 0


# ------------------------------------------------------------------ step_quantum
def test_step_quantum_puts_every_step_and_half_step_on_its_grid(tmp_path, osc_scene):
    """step_quantum q: every step is a multiple of 2 q (and at least 2 q), so every communication point, the
    half steps included, lies on the grid k q; the tolerance is still met."""
    tol, q = 1e-3, 2.5e-3
    res = run(osc_scene(tmp_path, name="quantum.toml", stop=30.0, step=0.01, extrapolation=1,
                        extra_master=f'[master.adaptive]\ntolerance = {tol}\nmin_step = {2 * q}\nmax_step = 1.0\n'
                                     f'estimator = "step-doubling"\nstep_quantum = {q}'), write=False)
    k = res.time[:-1] / q
    np.testing.assert_allclose(k, np.round(k), rtol=0, atol=1e-6, err_msg="communication points off the grid k q")
    pairs = np.diff(res.time)[::2]  # step doubling records both halves of each accepted step
    assert pairs.min() >= q * (1 - 1e-9)
    assert res.metadata["steps"]["rejected_error"] > 0
    assert _sup_error(res) <= tol


class _FakeMaster:
    """The primitives StepDoubling uses, for one signal that a step of k ticks leaves at 1 + c k**3: the one-step
    and two-half-step values differ by 7/8 c k**3, so the error per unit step grows as k**2 (order 2)."""

    def __init__(self, grid, c):
        from types import SimpleNamespace

        self.grid, self.c, self.n = grid, c, 0
        self.system = SimpleNamespace(y=np.zeros(1))
        self.continuous = np.array([True])
        self.stats = SimpleNamespace(rejected_failures=0, rejected_error=0, error_estimates=[])
        self.attempts = []

    def snapshot(self):
        return self.n

    def restore(self, snap):
        self.n = snap

    def release(self, snap):
        pass

    def attempt(self, n, k):
        self.attempts.append(k)
        if len(self.attempts) > 100:
            raise RuntimeError(f"the controller loops: attempts {sorted(set(self.attempts))}")
        self.system.y = np.array([1.0 + self.c * k**3])
        return True

    def accept(self, n):
        self.n = n

    def fail_at_minimum(self, n, k):
        raise CosimStepError(f"minimum at {n}")


def test_a_rejected_step_shrinks_by_a_quantum_at_least():
    """A rejection whose smaller step rounds back to the same whole number of double quanta (err = 1.05 at four:
    0.9 x 4 / sqrt(1.05) = 3.5 rounds to 4) must still shrink the step, not retry it for ever."""
    from tribocosim.cosim.engine.schemes import Adaptive
    from tribocosim.cosim.engine.stepcontrol import StepDoubling
    from tribocosim.cosim.engine.timegrid import TimeGrid

    q, tol = 1e-3, 1e-3
    grid = TimeGrid.variable(0.0, 1.0, 2 * q)  # 32 ticks per quantum
    q2 = 2 * grid.ticks(q)
    k_bad = 4 * q2
    # err = |y2 - y1| / 3 / (h (atol + tol |y2|)) with |y2 - y1| = 7/8 c k^3 and y2 ~ 1
    c = 1.05 * 3 * (k_bad * grid.tick) * (tol + tol) / (7 / 8 * k_bad**3)
    ctrl = StepDoubling(Adaptive(tolerance=tol, min_step=2 * q, max_step=1.0, step_quantum=q), k_bad, order=2)
    master = _FakeMaster(grid, c)
    taken = ctrl.advance(master, 0)
    assert master.stats.rejected_error == 1 and taken == 3 * q2
    assert master.stats.error_estimates[0] < 1.0


def test_step_quantum_is_checked_against_the_grid(tmp_path, osc_scene):
    from tribocosim.errors import SceneError

    bad = {"1.5e-7": "whole number of grid ticks", "0.6": "exceed max_step"}
    for quantum, words in bad.items():
        scene = osc_scene(tmp_path, name=f"bad{quantum}.toml", stop=1.0, step=0.01, extrapolation=1,
                          extra_master=f'[master.adaptive]\ntolerance = 1e-3\nmin_step = 1e-5\nmax_step = 1.0\n'
                                       f'estimator = "step-doubling"\nstep_quantum = {quantum}')
        with pytest.raises(SceneError, match=words):
            run(scene, write=False)
    scene = osc_scene(tmp_path, name="badest.toml", stop=1.0, step=0.01, extrapolation=1, extra=BOND,
                      extra_master='[master.adaptive]\ntolerance = 1e-3\nmin_step = 1e-5\nmax_step = 1.0\n'
                                   'estimator = "energy"\nstep_quantum = 1e-4')
    with pytest.raises(SceneError, match="step-doubling estimator only"):
        run(scene, write=False)


def test_step_doubling_on_the_strips_internal_grid_does_not_collapse():
    """Step doubling on the demo (press + strip + drive, first 0.2 s): without the strip's internal grid its own
    first-order lag keeps the error per unit step above the tolerance and every step is the smallest allowed;
    with internal_step = step_quantum the estimate sees the coupling alone and the step grows after the ramps."""
    ad = {"tolerance": 1e-2, "min_step": 1e-4, "max_step": 0.05, "estimator": "step-doubling"}
    base = {"experiment.stop": 0.2, "experiment.step": 1e-3, "fmus.drive.parameters.start_time": 0.0,
            "master.extrapolation": 1, "master.adaptive": ad}
    plain = run("demo", overrides=base, write=False)
    grid = run("demo", overrides={**base, "fmus.strip.parameters.internal_step": 5e-5,
                                  "master.adaptive": {**ad, "step_quantum": 5e-5}}, write=False)
    late = {}
    for name, res in (("plain", plain), ("grid", grid)):
        steps = np.diff(res.time)[::2] * 2  # the step H of each accepted pair of half steps
        late[name] = steps[res.time[1::2][: len(steps)] > 0.1]
    assert late["plain"].max() <= 2e-4 * (1 + 1e-9), "without the grid the step stays at min_step"
    assert late["grid"].min() >= 20 * late["plain"].max()
    assert grid.metadata["fmi_calls"]["strip"]["doStep"] < 0.5 * plain.metadata["fmi_calls"]["strip"]["doStep"]
