"""The StripDraw FMU driven through fmpy: declarations, closed forms, equality with the model,
FMU state, independence of instances, and errors.

The FMU is built once per session by ``tribocosim fmu build`` in a subprocess (conftest.py).
References are closed forms (steady state under constant mu) and the pure model run in this
process (an independent path: no FMI, no adapter).
"""

from __future__ import annotations

import csv
import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from tribocosim.components.stripdraw.friction import make_friction_law
from tribocosim.components.stripdraw.model import OUTPUT_NAMES, StripDrawModel
from tribocosim.components.stripdraw.parameters import StripDrawParameters, parameter_fields
from tribocosim.components.stripdraw.table import read_table

PROJECT_ROOT = Path(__file__).resolve().parents[2]
TABLE = PROJECT_ROOT / "models" / "friction_table.npz"
FMI_DISCARD, FMI_ERROR, FMI_FATAL = 2, 3, 4

#: the public contract of the issue
CONTRACT_PARAMETERS = (
    "tool_length", "tool_width", "sheet_thickness", "sheet_width", "draw_length", "n_elements",
    "youngs_modulus", "density", "archard_k", "hardness", "zeta", "particle_thickness", "mu0",
    "friction_model", "mu_const", "beta_initial", "integrator", "table_file", "table_policy",
)  # fmt: skip
CONTRACT_INPUTS = {"normal_force": "N", "grip_velocity": "m/s"}
CONTRACT_OUTPUTS = {
    "pull_force": "N", "friction_force": "N", "mu_mean": "1", "sliding_distance": "m",
    "beta_mean": "1", "beta_max": "1", "contact_pressure": "Pa", "grip_position": "m",
}  # fmt: skip

V0 = 0.08  # m/s, the paper's draw speed
F10 = 10e6 * 0.035 * 0.035  # N: 10 MPa on the default pad


def ramp_schedule(n_steps, dt=1e-3, force=F10, v0=V0, t_ramp=0.01, force_wobble=0.0):
    """[(dt, normal_force, grip_velocity)]: velocity ramped linearly over t_ramp (no elastic
    shock), force optionally modulated so that every input changes."""
    rows = []
    for k in range(n_steps):
        t_end = (k + 1) * dt
        v = v0 * min(1.0, t_end / t_ramp)
        f = force * (1.0 + force_wobble * math.sin(2 * math.pi * t_end / 0.05))
        rows.append((dt, f, v))
    return rows


def model_run(parameters: dict, schedule) -> np.ndarray:
    """The pure model over ``schedule``; one row of outputs per step (FMU column order)."""
    params = StripDrawParameters(**parameters)
    table = read_table(TABLE) if params.friction_model == "table" else None
    model = StripDrawModel(params, make_friction_law(params, table))
    rows = []
    for dt, f, v in schedule:
        out = model.step(dt, {"normal_force": f, "grip_velocity": v})
        rows.append([out[name] for name in _COLUMNS])
    return np.array(rows)


def fmu_run(instance, schedule) -> np.ndarray:
    return np.array([instance.step(dt, f, v) for dt, f, v in schedule])


_COLUMNS = (
    "pull_force", "friction_force", "mu_mean", "sliding_distance", "beta_mean", "beta_max",
    "contact_pressure", "grip_position", "table_clamp_count",
)  # fmt: skip


def _fmpy_exe() -> str:
    exe = Path(sys.executable).with_name("fmpy")
    return str(exe) if exe.exists() else shutil.which("fmpy")


# ----------------------------------------------------------------------------------- declaration
def test_fmpy_validate_finds_no_problem(stripdraw_fmu_file):
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(stripdraw_fmu_file)) == []
    proc = subprocess.run([_fmpy_exe(), "validate", str(stripdraw_fmu_file)], capture_output=True, text=True)
    assert proc.returncode == 0 and "No problems found" in proc.stdout, proc.stdout + proc.stderr


def test_variables_follow_the_parameter_dataclass(stripdraw_fmu_description):
    md = stripdraw_fmu_description
    variables = {v.name: v for v in md.modelVariables}
    assert _COLUMNS == OUTPUT_NAMES, "the tests' column order must be the model's"
    for name in CONTRACT_PARAMETERS:
        assert variables[name].causality == "parameter", name
    for field in parameter_fields():
        var = variables[field.name]
        meta = field.metadata
        assert var.causality == "parameter" and var.variability == "fixed", field.name
        assert meta["description"] in var.description, field.name
        if "choices" in meta:
            assert (var.type, var.start) == ("String", field.default), field.name
        elif meta.get("integer"):
            assert (var.type, int(var.start)) == ("Integer", field.default), field.name
            assert var.description.endswith(f"[{meta['unit']}]"), field.name
        else:
            assert var.type == "Real" and float(var.start) == field.default, field.name
            assert var.unit == (meta["unit"] or "1"), field.name
            assert var.description.endswith(f"[{var.unit}]"), field.name
    assert (variables["table_file"].type, variables["table_file"].start) == ("String", "friction_table.npz")
    for names, causality in ((CONTRACT_INPUTS, "input"), (CONTRACT_OUTPUTS, "output")):
        for name, unit in names.items():
            var = variables[name]
            assert (var.causality, var.type, var.unit) == (causality, "Real", unit), name
            assert var.description.endswith(f"[{unit}]"), name
    clamp = variables["table_clamp_count"]
    assert (clamp.causality, clamp.type) == ("output", "Integer")
    for var in md.modelVariables:
        assert var.description and var.description.rstrip().endswith("]"), f"{var.name}: no unit in description"
    assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate



# ----------------------------------------------------------------------------------- command line
def test_fmpy_command_line_simulate_with_start_values_and_input_csv(stripdraw_fmu_file, tmp_path):
    mu, force, tool_length = 0.12, 8000.0, 0.07
    inputs = tmp_path / "inputs.csv"
    inputs.write_text(
        '"time","normal_force","grip_velocity"\n'
        f"0.0,{force},0.0\n0.01,{force},{V0}\n0.06,{force},{V0}\n"
    )
    result = tmp_path / "result.csv"
    cmd = [
        _fmpy_exe(), "simulate", str(stripdraw_fmu_file),
        "--start-values", "tool_length", str(tool_length), "friction_model", "constant",
        "mu_const", str(mu), "integrator", "implicit",
        "--input-file", str(inputs), "--output-file", str(result),
        "--stop-time", "0.06", "--output-interval", "0.001",
    ]  # fmt: skip
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    with result.open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 61, f"{len(rows)} rows"
    last = rows[-1]
    assert_allclose(float(last["time"]), 0.06, err_msg="stop time")
    # tool_length = 0.07 from the command line reached the model: P = F / (L_T w_T)
    assert_allclose(float(last["contact_pressure"]), force / (tool_length * 0.035), rtol=1e-12, err_msg="pressure")
    assert_allclose(float(last["pull_force"]), 2 * mu * force, rtol=5e-3, err_msg="Eq. 1 steady state")
    # fmpy holds each input over a step at its value at the step's start (left Riemann sum)
    grip = sum(V0 * min(1.0, k * 1e-3 / 0.01) * 1e-3 for k in range(60))
    assert_allclose(float(last["grip_position"]), grip, rtol=1e-9, err_msg="grip = sum of v dt")


# ----------------------------------------------------------------------------------- closed forms
@pytest.mark.parametrize("mu, force", [(0.15, F10), (0.08, 3e6 * 0.035 * 0.035)])
def test_constant_mu_steady_state_pull_force(stripdraw_fmu_file, mu, force):
    from fmpy import simulate_fmu

    t = np.array([0.0, 0.01, 0.05])
    signals = np.array(
        [(ti, force, V0 * min(1.0, ti / 0.01)) for ti in t],
        dtype=[("time", float), ("normal_force", float), ("grip_velocity", float)],
    )
    res = simulate_fmu(
        str(stripdraw_fmu_file),
        stop_time=0.05,
        output_interval=1e-3,
        input=signals,
        start_values={"friction_model": "constant", "mu_const": mu, "integrator": "implicit"},
        output=list(CONTRACT_OUTPUTS),
    )
    late = res[res["time"] >= 0.03]
    assert late.size == 21
    assert_allclose(late["pull_force"], 2 * mu * force, rtol=5e-3, err_msg="pull_force = 2 mu F_N")
    assert_allclose(late["friction_force"], mu * force, rtol=5e-3, err_msg="F_S = mu F_N on one face")
    assert_allclose(late["mu_mean"], mu, rtol=5e-3, err_msg="mu_mean = mu_const")
    assert_allclose(late["contact_pressure"], force / 0.035**2, rtol=1e-12, err_msg="P = F/(L_T w_T)")


# ----------------------------------------------------------------------------------- FMU == model
@pytest.mark.parametrize(
    "parameters, schedule",
    [
        ({}, ramp_schedule(120, force_wobble=0.3)),  # default: table friction, implicit
        ({"friction_model": "closed_form", "n_elements": 200}, ramp_schedule(60, dt=2e-3, force_wobble=0.3)),
        ({"integrator": "explicit", "n_elements": 100}, ramp_schedule(15, dt=2e-4, t_ramp=1e-3)),
    ],
    ids=["table-implicit", "closed_form", "explicit"],
)
def test_fmu_outputs_identical_to_pure_model(stripdraw_fmu_instance, parameters, schedule):
    inst = stripdraw_fmu_instance("same", parameters).initialize()
    got = fmu_run(inst, schedule)
    want = model_run(parameters, schedule)
    assert np.all(want[:, 0] > 0), "the run must pull"
    for j, name in enumerate(_COLUMNS):
        assert_array_equal(got[:, j], want[:, j], err_msg=f"{name}: FMU differs from the model")


# ----------------------------------------------------------------------------------- FMU state
def test_get_set_and_serialized_state_replay_bit_identical(stripdraw_fmu_instance):
    schedule = ramp_schedule(60, force_wobble=0.3)
    first, rest = schedule[:30], schedule[30:]
    a = stripdraw_fmu_instance("a").initialize()
    fmu_run(a, first)
    state = a.slave.getFMUstate()
    t_state = a.time
    reference = fmu_run(a, rest)
    a.time = t_state
    a.slave.setFMUstate(state)
    assert_array_equal(fmu_run(a, rest), reference, err_msg="replay after setFMUstate")
    a.time = t_state
    a.slave.setFMUstate(state)  # a state can be restored more than once
    assert_array_equal(fmu_run(a, rest), reference, err_msg="second replay of the same state")
    blob = bytes(a.slave.serializeFMUstate(state))
    a.slave.freeFMUstate(state)
    # deserialize in another instance, created with other parameters: the state carries its own
    b = stripdraw_fmu_instance("b", {"mu_const": 0.3, "friction_model": "constant"}).initialize()
    fmu_run(b, ramp_schedule(3))
    b.slave.setFMUstate(b.slave.deSerializeFMUstate(blob))
    b.time = t_state
    assert_array_equal(fmu_run(b, rest), reference, err_msg="replay after serialize/deserialize")
    assert_array_equal(reference, model_run({}, schedule)[30:], err_msg="state replay vs model")



def test_parameters_are_fixed_after_initialization(stripdraw_fmu_instance):
    inst = stripdraw_fmu_instance("fixed").initialize()
    inst.set("tool_length", 0.07)
    assert any("tool_length is fixed" in m for s, m in inst.messages if s == 1), inst.messages
    out = inst.step(1e-3, F10, 0.008)
    assert_allclose(out[_COLUMNS.index("contact_pressure")], F10 / 0.035**2, rtol=1e-12, err_msg="L_T changed")


def test_two_instances_in_one_process_are_independent(stripdraw_fmu_instance):
    pa = {"friction_model": "constant", "mu_const": 0.1}
    pb = {"friction_model": "constant", "mu_const": 0.2, "tool_length": 0.07}
    sa, sb = ramp_schedule(40), ramp_schedule(40, force=2 * F10)
    a = stripdraw_fmu_instance("A", pa).initialize()
    b = stripdraw_fmu_instance("B", pb).initialize()
    got_a, got_b = [], []
    for (dt, fa, va), (_, fb, vb) in zip(sa, sb):  # interleaved
        got_a.append(a.step(dt, fa, va))
        got_b.append(b.step(dt, fb, vb))
    assert_array_equal(np.array(got_a), model_run(pa, sa), err_msg="instance A")
    assert_array_equal(np.array(got_b), model_run(pb, sb), err_msg="instance B")
    before = b.outputs()
    fmu_run(a, ramp_schedule(10))
    assert_array_equal(b.outputs(), before, err_msg="stepping A changed B")


# ----------------------------------------------------------------------------------- errors



def _assert_refuses_steps(inst, text: str) -> None:
    from fmpy.fmi1 import FMICallException

    at_init = [m for s, m in inst.messages if s == FMI_ERROR]
    assert any("initialization failed" in m and text in m for m in at_init), inst.messages
    for _ in range(2):
        inst.messages.clear()
        with pytest.raises(FMICallException) as exc:
            inst.step(1e-3, F10, 0.008)
        assert exc.value.status == FMI_DISCARD
        assert any(text in m for s, m in inst.messages if s == FMI_ERROR), inst.messages



