"""tribocosim.cosim.scene.component_checks: the monolithic reference of component scenes, and the parameter checks.

The reference couples the pure models (StripDrawModel with the shipped table, PressModel,
MachineModel) with a tiny step and the coupling solved every step; the co-simulation of the same
scene through the FMUs must converge to it as the communication step shrinks (Jacobi, zero-order
hold: first order), and in quasi-steady sliding pull_force / (2 normal_force) (Eq. 1) must equal
the strip's mu_mean (Eq. 28) in both.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tribocosim.errors import SceneError
from tribocosim.paths import DEFAULT_TABLE
from tribocosim.components.stripdraw.table import read_table
from tribocosim.cosim.api import run
from tribocosim.cosim.studies.monolithic import ComponentModel, make_model, reference_for_scene
from tribocosim.cosim.scene.component_checks import component_problems
from tribocosim.cosim.scene.validate import load_scene
from tribocosim.cosim.scene.schema import parse_scene

DEMO = Path(__file__).resolve().parents[2] / "models" / "scenes" / "demo.toml"

STOP = 0.2  # s: the velocity and force ramps, break-away and 14 mm of sliding
CHEAP = {"fmus.strip.parameters.n_elements": 100, "fmus.strip.parameters.draw_length": 0.05, "experiment.stop": STOP,
         "experiment.step": 1e-3, "fmus.drive.parameters.start_time": 0.0}  # the drive at once: ramps and break-away
VARIABLES = ("strip.pull_force", "drive.grip_velocity", "press.normal_force")


@pytest.fixture(scope="module")
def reference():
    plan = load_scene(DEMO, CHEAP)
    ref = reference_for_scene(plan, 1e-4)
    times = np.arange(0, 51) * (STOP / 50)  # every 4 ms: on the grid of every step below
    return times, ref.solve(times), ref


def test_reference_has_every_fmu_output_under_the_fmu_name(reference):
    _, sol, ref = reference
    assert {"strip.pull_force", "strip.mu_mean", "press.normal_force", "press.force_reference",
            "drive.grip_velocity", "drive.velocity_reference", "drive.motor_force"} <= set(ref.variables)
    assert sol["press.force_reference"][-1] == 12250.0 and sol["drive.velocity_reference"][-1] == 0.08


def test_cosimulation_converges_to_the_monolithic_reference(reference):
    times, sol, _ = reference
    errors = []
    for h in (4e-3, 2e-3, 1e-3, 5e-4):
        r = run(load_scene(DEMO, {**CHEAP, "experiment.step": h}), write=False)
        k = np.round(times / h).astype(int)
        assert np.allclose(r.time[k], times, rtol=0, atol=1e-12)
        errors.append(max(np.max(np.abs(r[n][k] - sol[n])) / np.max(np.abs(sol[n])) for n in VARIABLES))
    print("\nrelative error vs the monolithic reference, h = 4, 2, 1, 0.5 ms:", ", ".join(f"{e:.3g}" for e in errors))
    assert all(a > b for a, b in zip(errors, errors[1:])), f"error must fall as the step shrinks: {errors}"
    order = np.polyfit(np.log([4e-3, 2e-3, 1e-3, 5e-4]), np.log(errors), 1)[0]
    assert 0.8 < order < 1.3, f"Jacobi with zero-order hold is first order; fitted {order:.2f}"
    assert errors[-1] < 0.02


def test_pull_force_over_twice_the_normal_force_is_mu_mean_in_the_reference(reference):
    times, sol, _ = reference
    late = times >= 0.16
    ratio = sol["strip.pull_force"][late] / (2 * sol["press.normal_force"][late])
    np.testing.assert_allclose(ratio, sol["strip.mu_mean"][late], rtol=5e-3,
                               err_msg="Eq. 1 vs Eq. 28 in quasi-steady sliding (monolithic)")


def test_unconnected_inputs_are_held_at_the_scene_value(tmp_path):
    scene = tmp_path / "alone.toml"
    scene.write_text(f"""
[experiment]
stop = 0.05
step = 1e-3
[fmus.strip]
component = "stripdraw"
parameters = {{ n_elements = 60, draw_length = 0.02, normal_force = 8000.0, grip_velocity = 0.05 }}
[output]
variables = ["strip.pull_force", "strip.contact_pressure"]
""")
    ref = reference_for_scene(scene, 1e-3)
    sol = ref.solve([0.0, 0.05])  # times from the start
    assert sol["strip.contact_pressure"][-1] == pytest.approx(8000.0 / 0.035**2)
    co = run(scene, write=False)
    assert co["strip.pull_force"][-1] > 0
    np.testing.assert_allclose(sol["strip.pull_force"][-1], co["strip.pull_force"][-1], rtol=1e-12,
                               err_msg="one FMU with held inputs: the reference is the FMU's run")


def test_component_model_renames_the_outputs_like_the_fmu():
    m = ComponentModel(make_model("press", {"force_setpoint": 5000.0, "ramp_time": 0.0}), {}, {
        "normal_force": "normal_force", "force_reference": "force_setpoint"})
    out = m.step(1e-3, {})
    assert set(out) == {"normal_force", "force_reference"} and out["force_reference"] == 5000.0


def test_a_scene_with_a_foreign_fmu_has_no_reference(tmp_path):
    path = tmp_path / "foreign.toml"
    path.write_text(DEMO.read_text().replace('component = "press"', 'path = "ThirdParty.fmu"'))
    scene, _ = parse_scene(path)
    with pytest.raises(SceneError, match="no monolithic reference for press: only component"):
        reference_for_scene(scene, 1e-3)


def test_component_problems_name_instance_and_parameter(tmp_path):
    scene, _ = parse_scene(DEMO, {
        "fmus.strip.parameters.friction_model": "tabel",
        "fmus.strip.parameters.field_input": str(tmp_path / "missing.npz"),
        "fmus.press.parameters.force_setpoint": 50.0,  # 0.04 MPa: below the shipped table's axis
        "fmus.drive.parameters.screw_lead": 0.0,
    })
    lines = [str(p) for p in component_problems(scene)]
    text = "\n".join(lines)
    assert len(lines) == 4, text
    assert f"{DEMO}: fmus.strip.parameters.friction_model: friction_model = 'tabel' is not allowed" in text
    assert f"{DEMO}: fmus.strip.parameters.field_input: field file {tmp_path / 'missing.npz'} does not exist" in text
    assert f"{DEMO}: fmus.drive.parameters.screw_lead: screw_lead = 0.0 m is out of range" in text
    # the set-point is checked against the table of the strip's valid parameters (default law: table)
    assert f"{DEMO}: fmus.press.parameters.force_setpoint: the set-point, 50 N on the 35 x 35 mm pad" in text
    ok, _ = parse_scene(DEMO, {"fmus.press.parameters.force_setpoint": 50.0})
    low = [str(p) for p in component_problems(ok)]
    assert len(low) == 1 and "fmus.press.parameters.force_setpoint: the set-point, 50 N" in low[0]
    axis = read_table(DEFAULT_TABLE).pressure / 1e6
    assert f"0.04082 MPa, outside the friction table's pressure axis [{axis[0]:g}, {axis[-1]:g}] MPa" in low[0]
    assert component_problems(parse_scene(DEMO)[0]) == []
