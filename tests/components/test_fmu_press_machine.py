"""The Press and DrawingMachine FMUs driven through fmpy: declarations, equality with the pure
models, closed-form steady states, FMU state, errors, and all three FMUs in one clean process.

The FMUs are built once per session by ``tribocosim fmu build`` in a subprocess (conftest.py).
References are the pure models run in this process (no FMI, no adapter) and closed forms:
with integral action the press holds F_N = F_set exactly; the drive holds v_g = v_set, the motor
force carries the load (F_m = F_p) and the grip lags the integrated set-point by the PI
controller's and the drivetrain's deflections, x_g = v_set (t - T_r/2) - F_p/K_i - F_p/k_d.
"""

from __future__ import annotations

import dataclasses
import json
import math
import re
import shutil
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from tribocosim.components.machine import MachineModel, MachineParameters
from tribocosim.components.press import PressModel, PressParameters

PROJECT_ROOT = Path(__file__).resolve().parents[2]
FMI_DISCARD, FMI_ERROR = 2, 3
F10 = 10e6 * 0.035 * 0.035  # N: 10 MPa on the default 35 x 35 mm pad
V0 = 0.08  # m/s

#: the public contract: FMU variable -> unit
PRESS_OUTPUTS = {"normal_force": "N", "force_reference": "N"}
MACHINE_INPUTS = {"pull_force": "N"}
MACHINE_OUTPUTS = {"grip_velocity": "m/s", "grip_position": "m", "velocity_reference": "m/s", "motor_force": "N"}
#: FMU output -> the model's output key, where they differ (the parameter has the model's name)
MODEL_KEY = {"force_reference": "force_setpoint", "velocity_reference": "velocity_setpoint"}


@dataclasses.dataclass(frozen=True)
class Spec:
    parameters: type
    model: type
    inputs: dict
    outputs: dict


SPECS = {
    "Press": Spec(PressParameters, PressModel, {}, PRESS_OUTPUTS),
    "DrawingMachine": Spec(MachineParameters, MachineModel, MACHINE_INPUTS, MACHINE_OUTPUTS),
}
TABLE = "0 0; 0.05 5000; 0.3 5000; 0.35 9000"  # set-point table [s N]


def fmpy_grid(n: int, h: float) -> tuple[np.ndarray, list[float]]:
    """fmpy's communication points t_k = k h and step sizes t_(k+1) - t_k (not always exactly h)."""
    t = np.array([k * h for k in range(n + 1)])
    return t, [float(t[k + 1] - t[k]) for k in range(n)]


def model_run(fmu: str, parameters: dict, dts, inputs=None) -> np.ndarray:
    """The pure model over steps ``dts`` with ``inputs[k]`` held over step k; one row per step,
    the FMU's output columns."""
    spec = SPECS[fmu]
    model = spec.model(spec.parameters(**parameters))
    rows = []
    for k, dt in enumerate(dts):
        out = model.step(dt, {} if inputs is None else dict(zip(spec.inputs, inputs[k])))
        rows.append([out[MODEL_KEY.get(n, n)] for n in spec.outputs])
    return np.array(rows)


def fmu_run(inst, dts, inputs=None) -> np.ndarray:
    return np.array([inst.step(dt, *(() if inputs is None else inputs[k])) for k, dt in enumerate(dts)])


def pull_schedule(n: int) -> list[tuple[float]]:
    """A strip-like load: ramp to 3.7 kN over 50 steps with a 10 % wobble (every value changes)."""
    return [(3700.0 * min(1.0, k / 50) * (1 + 0.1 * math.sin(k / 7)),) for k in range(n)]


def irregular_steps(n: int) -> list[float]:
    """Step sizes that put the set-point breakpoints inside steps."""
    return [(0.7e-3, 1.3e-3, 2.9e-3, 0.41e-3)[k % 4] for k in range(n)]


@pytest.fixture
def make(fmu_instance):
    """``make(fmu, instance_name, parameters=None)``: an FMU instance with the contract's inputs/outputs."""

    def _make(fmu: str, name: str, parameters: dict | None = None):
        spec = SPECS[fmu]
        return fmu_instance(fmu, name, parameters, tuple(spec.inputs), tuple(spec.outputs))

    return _make


def _fmpy_exe() -> str:
    exe = Path(sys.executable).with_name("fmpy")
    return str(exe) if exe.exists() else shutil.which("fmpy")


# ----------------------------------------------------------------------------------- declaration
@pytest.mark.parametrize("fmu", SPECS)
def test_fmpy_validate_finds_no_problem(built_fmus, fmu):
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(built_fmus[fmu])) == []
    proc = subprocess.run([_fmpy_exe(), "validate", str(built_fmus[fmu])], capture_output=True, text=True)
    assert proc.returncode == 0 and "No problems found" in proc.stdout, proc.stdout + proc.stderr



@pytest.mark.parametrize("fmu", SPECS)
def test_variables_follow_the_parameter_dataclass(fmu_description, fmu):
    spec = SPECS[fmu]
    md = fmu_description(fmu)
    variables = {v.name: v for v in md.modelVariables}
    fields = dataclasses.fields(spec.parameters)
    assert set(variables) == {f.name for f in fields} | set(spec.inputs) | set(spec.outputs)
    for field in fields:
        var, meta = variables[field.name], field.metadata
        assert var.causality == "parameter" and var.variability == "fixed", field.name
        assert meta["description"] in var.description, field.name
        if meta.get("text"):
            assert (var.type, var.start, field.default) == ("String", "", ""), field.name
            assert var.description.endswith("[text]"), field.name
        else:
            assert var.type == "Real" and float(var.start) == field.default, field.name
            assert var.unit == (meta["unit"] or "1"), field.name
            assert var.description.endswith(f"[{var.unit}]"), field.name
            assert (float(var.min), float(var.max)) == (meta["low"], meta["high"]), field.name
    # outputs are the model's values after initialization (initial = calculated, no start value)
    for names, causality in ((spec.inputs, "input"), (spec.outputs, "output")):
        for name, unit in names.items():
            var = variables[name]
            assert (var.causality, var.type, var.unit) == (causality, "Real", unit), name
            assert var.description.endswith(f"[{unit}]"), name
            if causality == "output":
                assert var.initial == "calculated" and var.start is None, name
    assert [u.variable.name for u in md.outputs] == list(spec.outputs), "ModelStructure/Outputs"
    assert md.coSimulation.modelIdentifier == fmu
    assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate


def _si_exponents(unit: str) -> dict:
    """Independent oracle: SI base exponents of a unit string like ``"N s/m"`` or ``"kg m2"``."""
    derived = {"N": {"kg": 1, "m": 1, "s": -2}, "Pa": {"kg": 1, "m": -1, "s": -2}}
    out: dict[str, int] = {}
    num, _, den = unit.partition("/")
    for sign, part in ((1, num), (-1, den)):
        for token in part.split():
            if token == "1":
                continue
            symbol, power = re.fullmatch(r"([a-zA-Z]+)(\d*)", token).groups()
            for base, e in derived.get(symbol, {symbol: 1}).items():
                out[base] = out.get(base, 0) + sign * int(power or 1) * e
    return {k: v for k, v in out.items() if v}


@pytest.mark.parametrize("fmu", ["StripDraw", *SPECS])
def test_every_unit_is_defined_with_its_si_base_units(fmu_description, fmu):
    md = fmu_description(fmu)
    defined = {u.name: u.baseUnit for u in md.unitDefinitions}
    used = {v.unit for v in md.modelVariables if v.type == "Real"}
    assert used == set(defined), "every Real has a unit and every defined unit is used"
    for name, base in defined.items():
        got = {k: getattr(base, k) for k in ("kg", "m", "s", "A", "K", "mol", "cd", "rad")} if base else {}
        assert {k: v for k, v in got.items() if v} == _si_exponents(name), name



# ----------------------------------------------------------------------------------- FMU == model
@pytest.mark.parametrize(
    "parameters",
    [{}, {"setpoint_table": TABLE}, {"force_setpoint": 5000.0, "ramp_time": 0.0, "kp": 2.0, "ki": 50.0}],
    ids=["ramp", "table", "step-setpoint"],
)
def test_press_outputs_identical_to_pure_model(make, parameters):
    dts = irregular_steps(300)  # 0.4 s: ramp and table breakpoints fall inside steps
    got = fmu_run(make("Press", "same", parameters).initialize(), dts)
    want = model_run("Press", parameters, dts)
    assert np.ptp(want[:, 0]) > 1000.0, "the press must move"
    for j, name in enumerate(PRESS_OUTPUTS):
        assert_array_equal(got[:, j], want[:, j], err_msg=f"{name}: FMU differs from the model")


def test_machine_outputs_identical_to_pure_model_with_an_input_array(fmu_unzipped):
    """fmpy.simulate_fmu with ``pull_force`` sampled on the communication grid: fmpy applies the
    sample at each step's start, which the model holds over the step."""
    from fmpy import simulate_fmu

    n, h = 400, 1e-3
    t, dts = fmpy_grid(n, h)
    load = pull_schedule(n + 1)
    signals = np.array([(ti, f) for ti, (f,) in zip(t, load)], dtype=[("time", float), ("pull_force", float)])
    parameters = {"velocity_setpoint": 0.1, "drive_damping": 5e3, "ramp_time": 0.0137}
    res = simulate_fmu(
        str(fmu_unzipped("DrawingMachine")), stop_time=t[-1], output_interval=h, input=signals,
        start_values=parameters, output=list(MACHINE_OUTPUTS),
    )  # fmt: skip
    assert_array_equal(res["time"], t, err_msg="fmpy's communication points")
    want = model_run("DrawingMachine", parameters, dts, load)
    for j, name in enumerate(MACHINE_OUTPUTS):
        assert res[name][0] == 0.0, f"{name}: start value"
        assert_array_equal(res[name][1:], want[:, j], err_msg=f"{name}: FMU differs from the model")


def test_machine_command_line_with_an_input_csv(built_fmus, tmp_path):
    """``fmpy simulate`` in a fresh process (the FMU's bundled modules), CSV in and out."""
    from fmpy.util import read_csv

    n, h = 200, 1e-3
    t, dts = fmpy_grid(n, h)
    load = pull_schedule(n + 1)
    inputs = tmp_path / "pull_force.csv"
    inputs.write_text('"time","pull_force"\n' + "".join(f"{float(ti)!r},{f!r}\n" for ti, (f,) in zip(t, load)))
    result = tmp_path / "result.csv"
    cmd = [
        _fmpy_exe(), "simulate", str(built_fmus["DrawingMachine"]),
        "--start-values", "drive_stiffness", "2e7", "velocity_setpoint", "0.05",
        "--input-file", str(inputs), "--output-file", str(result),
        "--stop-time", repr(float(t[-1])), "--output-interval", repr(h),
    ]  # fmt: skip
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    got = read_csv(str(result))
    want = model_run("DrawingMachine", {"drive_stiffness": 2e7, "velocity_setpoint": 0.05}, dts, load)
    assert_array_equal(got["time"], t)
    for j, name in enumerate(MACHINE_OUTPUTS):
        assert_array_equal(got[name][1:], want[:, j], err_msg=f"{name}: FMU (CSV) differs from the model")


# ----------------------------------------------------------------------------------- closed forms
def test_press_holds_its_setpoint_within_one_percent_through_fmpy(fmu_unzipped):
    from fmpy import simulate_fmu

    force, ramp = 8000.0, 0.05
    res = simulate_fmu(
        str(fmu_unzipped("Press")), stop_time=0.4, output_interval=1e-3,
        start_values={"force_setpoint": force, "ramp_time": ramp}, output=list(PRESS_OUTPUTS),
    )  # fmt: skip
    t = res["time"]
    assert_allclose(res["force_reference"], force * np.minimum(t / ramp, 1.0), rtol=1e-12, atol=1e-9,
                    err_msg="set-point: linear ramp, then hold")  # fmt: skip
    steady = t >= 0.2
    assert steady.sum() == 201
    assert np.all(np.abs(res["normal_force"][steady] - force) <= 0.01 * force), "within 1 % after 0.2 s"
    assert_allclose(res["normal_force"][-1], force, rtol=1e-6, err_msg="integral action: no steady-state error")
    # the set-point table: holds each level
    res = simulate_fmu(
        str(fmu_unzipped("Press")), stop_time=0.6, output_interval=1e-3,
        start_values={"setpoint_table": TABLE}, output=["normal_force"],
    )  # fmt: skip
    at = {round(ti, 6): f for ti, f in zip(res["time"], res["normal_force"])}
    assert abs(at[0.3] - 5000.0) <= 0.01 * 5000.0 and abs(at[0.6] - 9000.0) <= 0.01 * 9000.0, (at[0.3], at[0.6])


def test_drive_reaches_its_velocity_setpoint_through_fmpy(fmu_unzipped):
    from fmpy import simulate_fmu

    load = 3700.0
    p = MachineParameters()
    signals = np.array([(0.0, load), (1.0, load)], dtype=[("time", float), ("pull_force", float)])
    res = simulate_fmu(
        str(fmu_unzipped("DrawingMachine")), stop_time=1.0, output_interval=1e-3, input=signals,
        output=list(MACHINE_OUTPUTS),
    )  # fmt: skip
    t, end = res["time"], res[-1]
    assert_allclose(res["velocity_reference"], V0 * np.minimum(t / p.ramp_time, 1.0), rtol=1e-12, atol=1e-15,
                    err_msg="set-point: linear ramp, then hold")  # fmt: skip
    assert_allclose(end["grip_velocity"], p.velocity_setpoint, rtol=1e-4, err_msg="v_g = v_set")
    assert_allclose(end["motor_force"], load, rtol=1e-4, err_msg="F_m = F_p")
    lag = load / p.speed_ki + load / p.drive_stiffness
    x_closed = p.velocity_setpoint * (end["time"] - p.ramp_time / 2) - lag
    assert_allclose(end["grip_position"], x_closed, rtol=0, atol=1e-9, err_msg="x_g = v (t - T_r/2) - F/K_i - F/k_d")
    assert lag > 200 * 1e-9, "the closed form must resolve the lag"


def test_drive_holds_its_setpoint_without_drift(fmu_unzipped):
    from fmpy import simulate_fmu

    load = 3700.0
    signals = np.array([(0.0, load), (2.0, load)], dtype=[("time", float), ("pull_force", float)])
    res = simulate_fmu(
        str(fmu_unzipped("DrawingMachine")), stop_time=2.0, output_interval=1e-3, input=signals,
        output=["grip_velocity", "motor_force"],
    )  # fmt: skip
    assert abs(res["grip_velocity"][-1] - V0) <= 1e-10 * V0, "integral action: no velocity error"
    assert abs(res["motor_force"][-1] - load) <= 1e-6 * load, "integral action: F_m = F_p"


# ----------------------------------------------------------------------------------- FMU state
@pytest.mark.parametrize("fmu", SPECS)
def test_get_set_and_serialized_state_replay_bit_identical(make, fmu):
    parameters = {"setpoint_table": TABLE} if fmu == "Press" else {"drive_damping": 1e4}
    other = {"force_setpoint": 1.0} if fmu == "Press" else {"velocity_setpoint": -0.02}
    n = 120
    dts = irregular_steps(n)
    inputs = pull_schedule(n) if SPECS[fmu].inputs else None
    first, rest = slice(0, n // 2), slice(n // 2, n)
    sub = (lambda s: None) if inputs is None else (lambda s: inputs[s])
    a = make(fmu, "a", parameters).initialize()
    fmu_run(a, dts[first], sub(first))
    state, t_state = a.slave.getFMUstate(), a.time
    reference = fmu_run(a, dts[rest], sub(rest))
    for replay in ("after setFMUstate", "second replay of the same state"):
        a.time = t_state
        a.slave.setFMUstate(state)
        assert_array_equal(fmu_run(a, dts[rest], sub(rest)), reference, err_msg=replay)
    blob = bytes(a.slave.serializeFMUstate(state))
    a.slave.freeFMUstate(state)
    # deserialize into another instance, made with other parameters: the state carries its own
    b = make(fmu, "b", other).initialize()
    fmu_run(b, dts[:3], sub(slice(0, 3)))
    b.slave.setFMUstate(b.slave.deSerializeFMUstate(blob))
    b.time = t_state
    assert_array_equal(fmu_run(b, dts[rest], sub(rest)), reference, err_msg="replay after serialize/deserialize")
    assert_array_equal(reference, model_run(fmu, parameters, dts, inputs)[rest], err_msg="state replay vs model")


# ----------------------------------------------------------------------------------- errors



# ----------------------------------------------------------------------------------- one clean process
_TOGETHER_SCRIPT = textwrap.dedent(
    """
    import json, sys
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    fmus, order, n, h = json.loads(sys.argv[1]), json.loads(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4])
    s, vr, unzipped = {}, {}, {}
    for name in order:  # the first one instantiated provides the `tribocosim` package
        md = read_model_description(fmus[name])
        unzipped[name] = str(extract(fmus[name]))
        s[name] = FMU2Slave(guid=md.guid, unzipDirectory=unzipped[name], modelIdentifier=name, instanceName=name)
        s[name].instantiate()
        s[name].setupExperiment(startTime=0.0)
        s[name].enterInitializationMode()
        s[name].exitInitializationMode()
        vr[name] = {v.name: v.valueReference for v in md.modelVariables}
    get = lambda f, n: s[f].getReal([vr[f][n]])[0]
    rows = []
    for k in range(n):  # Jacobi coupling: every FMU gets the others' outputs of the previous step
        fn, vg = get("Press", "normal_force"), get("DrawingMachine", "grip_velocity")
        fp = get("StripDraw", "pull_force")
        s["StripDraw"].setReal([vr["StripDraw"]["normal_force"], vr["StripDraw"]["grip_velocity"]], [fn, vg])
        s["DrawingMachine"].setReal([vr["DrawingMachine"]["pull_force"]], [fp])
        for name in order:
            s[name].doStep(k * h, (k + 1) * h - k * h)
        rows.append([get("Press", "normal_force"), get("DrawingMachine", "grip_velocity"),
                     get("DrawingMachine", "grip_position"), get("StripDraw", "pull_force")])
    for name in order:
        s[name].terminate()
        s[name].freeInstance()
    print(json.dumps({
        "rows": rows,
        "unzipped": unzipped,
        "files": {m: getattr(sys.modules[m], "__file__", None) for m in sys.modules if m.startswith("tribocosim")},
        "modules": sorted(sys.modules),
    }))
    """
)


def _coupled_models(n: int, h: float) -> np.ndarray:
    from tribocosim.components.stripdraw import StripDrawModel, StripDrawParameters, make_friction_law, read_table

    strip_p = StripDrawParameters()
    table = read_table(PROJECT_ROOT / "models" / "friction_table.npz")
    strip = StripDrawModel(strip_p, make_friction_law(strip_p, table))
    press, machine = PressModel(PressParameters()), MachineModel(MachineParameters())
    fn, vg, fp = 0.0, 0.0, 0.0  # the FMUs' start values
    rows = []
    for k in range(n):
        dt = (k + 1) * h - k * h
        fp_next = strip.step(dt, {"normal_force": fn, "grip_velocity": vg})["pull_force"]
        m = machine.step(dt, {"pull_force": fp})
        fn = press.step(dt)["normal_force"]
        vg, fp = m["grip_velocity"], fp_next
        rows.append([fn, vg, m["grip_position"], fp])
    return np.array(rows)


