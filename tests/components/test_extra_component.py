"""A component from outside the package, added by its folder alone (tests/components/extra/lagcomponent).

Its model and its description are all there is: registering the description makes it an FMU the
build builds, a ``component = "lag"`` the scene checks know, and a model the monolithic reference
runs. Physics: y' = (k u - y) / tau driven by the press, whose force is exact; the co-simulation
with a held input converges to the monolithic reference as the step shrinks.
"""

from __future__ import annotations

import textwrap

import numpy as np
import pytest

from tribocosim.errors import SceneError


def _scene(folder, tau=0.01, gain=2.0, step=1e-3):
    path = folder / "lag.toml"
    path.write_text(textwrap.dedent(f"""
        [experiment]
        stop = 0.1
        step = {step}
        [fmus.press]
        component = "press"
        parameters = {{ force_setpoint = 1000.0, ramp_time = 0.02 }}
        [fmus.lag]
        component = "lag"
        parameters = {{ gain = {gain}, time_constant = {tau} }}
        [[connections]]
        from = "press.normal_force"
        to = "lag.u"
        [output]
        file = "lag.csv"
        variables = ["lag.y", "press.normal_force"]
        """))
    return path


def test_a_registered_component_builds_checks_runs_and_has_a_reference(tmp_path, lag_component, monkeypatch):
    from tribocosim.cosim.api import run
    from tribocosim.cosim.apps.monolithic import reference_for_scene
    from tribocosim.cosim.scene.component_checks import load_component_scene

    monkeypatch.setenv("TRIBOCOSIM_CACHE", str(tmp_path / "cache"))
    # the scene checks know its parameters: a bad one is reported by name before anything runs
    with pytest.raises(SceneError) as exc:
        load_component_scene(_scene(tmp_path, tau=-1.0))
    assert [p.key for p in exc.value.problems] == ["fmus.lag.parameters.time_constant"], exc.value.problems
    assert "time_constant = -1.0 is outside the declared range" in str(exc.value)
    # the build made its FMU (from the test folder's modules) and the master runs it
    errors = []
    for step in (2e-3, 1e-3, 5e-4):
        plan = load_component_scene(_scene(tmp_path, step=step))
        res = run(plan, tmp_path / "out", write=False)
        ref = reference_for_scene(plan, 1e-5).solve(res.time)
        np.testing.assert_allclose(res["press.normal_force"], ref["press.normal_force"], rtol=1e-9, atol=1e-6)
        errors.append(np.max(np.abs(res["lag.y"] - ref["lag.y"])))
    assert res["lag.y"][-1] == pytest.approx(2.0 * 1000.0, rel=1e-3), "y -> k F_set after the ramp"
    rates = np.diff(np.log(errors)) / np.diff(np.log([2e-3, 1e-3, 5e-4]))
    assert np.all(rates > 0.8), f"the coupling error falls with the step (first order, held input): {errors}"
