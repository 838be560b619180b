"""Tests of scene validation (cosim.scene.schema + cosim.scene.validate): every problem, one message, file and key."""

from pathlib import Path

import numpy as np
import pytest

from tribocosim.errors import SceneError
from tribocosim.cosim import load_scene, run


def _problems(path):
    with pytest.raises(SceneError) as info:
        load_scene(path)
    return str(info.value)


def test_typo_in_a_variable_name_names_file_key_and_known_names(tmp_path, osc_scene):
    path = osc_scene(tmp_path)
    path.write_text(path.read_text().replace('to = "a.force"', 'to = "a.forse"'))
    msg = _problems(path)
    assert msg.startswith(f"1 problem in scene {path}"), msg
    line = msg.splitlines()[1].strip()
    assert line.startswith(f"{path}: connections[0].to: unknown variable 'forse' in instance 'a'"), line
    assert "did you mean 'force'?" in line and "known: der(force), der(force,2), force" in line, line


def test_all_problems_are_reported_at_once(tmp_path, make_scene, fmu_dir):
    path = make_scene(tmp_path, "bad.toml", f"""
        [experiment]
        stop = 1.0
        step = 0.1
        stpo = 2.0

        [master]
        algoritm = "jacobi"
        extrapolation = 3

        [fmus.a]
        path = "{fmu_dir / 'OscMassA.fmu'}"
        parameters = {{ k = "stiff", q = 1.0 }}

        [fmus.b]
        path = "missing.fmu"

        [fmus.c]
        path = "{fmu_dir / 'OscMassB.fmu'}"

        [[connections]]
        from = "a.force"
        to = "c.x1"

        [[connections]]
        from = "c.x2"
        to = "a.force"

        [[connections]]
        from = "c.force"
        to = "zz.u"

        [output]
        variables = ["a.x1", "c.nope", "a"]
        """)
    msg = _problems(path)
    expected = [
        "experiment.stpo: unknown key",
        "master.algoritm: unknown key; did you mean 'algorithm'?",
        "master.extrapolation: 3 is not allowed; allowed: 0, 1, 2",
        "fmus.a.parameters.k: 'k' is a Real; got 'stiff'",
        "fmus.a.parameters.q: unknown parameter of OscMassA.fmu",
        "fmus.b.path: FMU file not found",
        "connections[0].from: a.force has causality 'input'; outputs need causality output",
        "connections[1]: unit mismatch: c.x2 is in 'm', a.force in 'N'",
        "connections[2].to: unknown instance 'zz'; known: a, b, c",
        "output.variables[1]: unknown variable 'nope' in instance 'c'",
        "output.variables[2]: must be 'instance.variable', got 'a'",
    ]
    for e in expected:
        assert f"{path}: {e}" in msg, f"missing {e!r} in:\n{msg}"
    assert msg.startswith(f"{len(expected)} problems in scene"), msg


def test_unconnected_inputs_are_warnings_with_the_value_used(tmp_path, make_scene, fmu_dir):
    path = make_scene(tmp_path, "one.toml", f"""
        [experiment]
        stop = 1.0
        step = 0.1

        [fmus.b]
        path = "{fmu_dir / 'OscMassB.fmu'}"
        parameters = {{ x1 = 0.25 }}
        """)
    plan = load_scene(path)
    assert "input b.x1 is not connected; its scene value 0.25 is used" in plan.warnings
    assert "input b.v1 is not connected; its start value 0.0 is used" in plan.warnings
    assert not any("der(" in w for w in plan.warnings), "derivative companions are not reported"


@pytest.mark.parametrize("master, key", [
    ('algorithm = "iterative"', "master.algorithm"),
    ('[master.adaptive]\nestimator = "step-doubling"', "master.adaptive.estimator"),
])
def test_schemes_that_roll_back_are_refused_for_fmus_that_cannot(tmp_path, osc_scene, fmu_dir, master, key):
    path = osc_scene(tmp_path, fmus=fmu_dir / "nostate", extra_master=master)
    path.write_text(path.read_text().replace('algorithm = "jacobi"\n', "") if "iterative" in master else path.read_text())
    msg = _problems(path)
    assert f"{key}: " in msg and "a, b cannot roll back (canGetAndSetFMUstate = false)" in msg, msg


def test_fmus_that_cannot_roll_back_run_with_jacobi_and_the_scene_is_told(tmp_path, osc_scene, fmu_dir):
    plan = load_scene(osc_scene(tmp_path, fmus=fmu_dir / "nostate"))
    assert any("a, b cannot roll back" in n and "stops the run" in n for n in plan.notes), plan.notes


def test_power_bonds_must_pair_declared_connections(tmp_path, osc_scene):
    bad = '[[power_bonds]]\neffort = ["b.force", "a.force"]\nflow = ["b.x2", "a.force"]'
    msg = _problems(osc_scene(tmp_path, extra=bad))
    assert "power_bonds[0].flow: b.x2 -> a.force is not one of the [[connections]]" in msg, msg
    assert "must join the same two instances in opposite directions" in msg, msg


def test_only_the_named_variables_are_recorded(tmp_path, osc_scene):
    plan = load_scene(osc_scene(tmp_path))
    assert [str(r) for r, _, _ in plan.recorded] == ["a.x1", "b.x2", "b.force"]
    assert [f"{l.source} -> {l.target}" for l in plan.links] == ["b.force -> a.force", "a.x1 -> b.x1", "a.v1 -> b.v1"]
    vr = {v.name: v.valueReference for v in plan.fmus["b"].md.modelVariables}
    assert plan.fmus["b"].derivative_inputs == {"x1": {1: vr["der(x1)"], 2: vr["der(x1,2)"]},
                                                "v1": {1: vr["der(v1)"], 2: vr["der(v1,2)"]}}


def test_toml_syntax_error_names_the_file(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text("[experiment\nstop = 1\n")
    msg = _problems(path)
    assert f"{path}: (syntax): not valid TOML" in msg, msg


def test_a_parameter_on_a_declared_bound_to_round_off_is_on_it_for_the_projects_fmu(tmp_path):
    """The StripDraw FMU given by path: density is declared in [1, 1e5] kg/m3. A value within 1e-9 of the bound
    (relative) is on it, as the FMU's own check compares (tc_below): the scene takes it and the FMU runs with it;
    1e-6 below is refused, the value printed with all its digits."""
    from tribocosim.cosim.scene.fmucache import component_fmu

    fmu = component_fmu("stripdraw")

    def scene(density: float) -> Path:
        path = tmp_path / f"d{density!r}.toml"
        path.write_text(f'[experiment]\nstop = 0.002\nstep = 1e-3\n[fmus.strip]\npath = "{fmu}"\n'
                        f'parameters = {{ density = {density!r}, normal_force = 12250.0, grip_velocity = 0.08 }}\n'
                        '[output]\nvariables = ["strip.pull_force"]\n')
        return path

    on_bound = 1.0 * (1 - 1e-12)
    res = run(scene(on_bound), write=False)
    assert len(res.time) == 3 and np.all(np.isfinite(res["strip.pull_force"]))
    below = 1.0 - 1e-6
    assert f"density = {below!r} is outside the declared range [1.0, 100000.0]" in _problems(scene(below))
