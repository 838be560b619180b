"""The native FMUs: built by ``tribocosim fmu build``, run in a C host with no Python, through fmpy
and libcosimpy, and held against the Python models.

- the model descriptions declare the components' variables (names, causality, units, ranges, start values);
  ``fmpy validate`` is clean;
- the linux64 binary exports every fmi2 function and no internal one; the FMU holds no ``.py`` file (the binaries
  of the other platforms: tests/native/test_native_platforms.py, slow);
- a C host (tests/native/host/fmi2_host.c, compiled here) loads each FMU with dlopen in a process without
  Python and runs it; its outputs agree with the Python models (StripDraw: the demo draw and a pressure ramp
  with a reversing grip, both integrators, all three friction laws; also the beta field of field_output);
- FMU states (get/set, serialize/deserialize) replay bit-identically; bad inputs are fmi2Discard with the
  outputs unchanged (thousands of random calls in the C host, no crash); bad parameters and tables are
  fmi2Error at initialization with a message naming them; nothing leaks (valgrind, when installed).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from tribocosim.errors import RangeWarning

HERE = Path(__file__).resolve().parent


def exported_functions(path):
    """tests/native/exports.py (a sibling module: loaded by path under pytest's importlib mode)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("native_exports", HERE / "exports.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.exported_functions(path)
NAMES = ("DrawingMachine", "Press", "StripDraw")
def _fmi2_functions() -> set[str]:
    """Every function of the FMI 2.0 standard, from its header (the names fmi2Functions.h maps through
    fmi2FullName)."""
    import re

    from tribocosim.components.fmus.native_build import fmi2_headers

    text = (fmi2_headers() / "fmi2Functions.h").read_text()
    return set(re.findall(r"#define (fmi2\w+)\s+fmi2FullName\(", text))


FMI2_FUNCTIONS = _fmi2_functions()
STRIP_OUTPUTS = ("pull_force", "mu_mean", "beta_max", "friction_force", "beta_mean", "sliding_distance",
                 "contact_pressure", "grip_position", "table_clamp_count")


@pytest.fixture(scope="session")
def native_fmus(tmp_path_factory) -> dict[str, Path]:
    """``tribocosim fmu build --platform linux64 --out TMP`` (the command line: native, this machine's binary)."""
    out = tmp_path_factory.mktemp("native_fmus")
    proc = subprocess.run([sys.executable, "-m", "tribocosim.cli", "fmu", "build", "--platform", "linux64", "--out",
                           str(out)],
                          capture_output=True, text=True, timeout=1800)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert [Path(p) for p in proc.stdout.split()] == [out.resolve() / f"{n}.fmu" for n in NAMES]
    return {n: out / f"{n}.fmu" for n in NAMES}


@pytest.fixture(scope="session")
def unzipped(native_fmus, tmp_path_factory):
    from fmpy import extract

    return {n: Path(extract(str(p), str(tmp_path_factory.mktemp(f"u_{n}")))) for n, p in native_fmus.items()}


@pytest.fixture(scope="session")
def descriptions(native_fmus):
    from fmpy import read_model_description

    return {n: read_model_description(str(p)) for n, p in native_fmus.items()}


@pytest.fixture(scope="session")
def fmi2_host(tmp_path_factory) -> Path:
    """The C host, compiled with the project's toolchain (a linux64 executable, no Python)."""
    from tribocosim.components.fmus.native_build import fmi2_headers
    from tribocosim.components.native.toolchain.compiler import compile_executable

    out = tmp_path_factory.mktemp("host") / "fmi2_host"
    return compile_executable([HERE / "host" / "fmi2_host.c"], out, include_dirs=[fmi2_headers()], libs=["-ldl"])


def _vr(description, name: str) -> int:
    return next(v.valueReference for v in description.modelVariables if v.name == name)


def run_host(host, unzipped, description, tmp_path, steps, *, inputs=(), outputs=(), parameters=None, extra=(),
             check=True):
    """Run the C host on a schedule ``steps`` (rows: dt, inputs...); return (outputs per step, process)."""
    md = description
    kinds = {v.name: v for v in md.modelVariables}
    sets = []
    for name, value in (parameters or {}).items():
        v = kinds[name]
        kind = {"Real": "r", "Integer": "i", "String": "s"}[v.type]
        sets += ["--set", f"{kind}:{v.valueReference}={value}"]
    spec = ",".join(f"{'i' if kinds[n].type == 'Integer' else 'r'}:{kinds[n].valueReference}" for n in outputs)
    steps_file = tmp_path / "steps.txt"
    steps_file.write_text("\n".join(",".join(repr(float(x)) for x in row) for row in steps) + "\n")
    given = ["--inputs", ",".join(str(kinds[n].valueReference) for n in inputs)] if inputs else []
    cmd = [str(host), str(unzipped), md.coSimulation.modelIdentifier, md.guid, *sets, *given,  # inputs before steps
           "--outputs", spec or "r:0", "--steps", str(steps_file), *extra]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600, env={"PATH": "/usr/bin:/bin"},
                          cwd=tmp_path)
    if check:
        assert proc.returncode == 0, f"exit {proc.returncode}\n{proc.stderr[-3000:]}"
    rows = np.array([[float(x) for x in line.split(",")] for line in proc.stdout.split()]) if proc.stdout.strip() else None
    return rows, proc


# ----------------------------------------------------------------------------------- the FMUs as files
def test_model_descriptions_declare_the_components_variables(descriptions):
    """Every parameter field, input and output of the component's declaration, with its unit and range; the outputs
    are the model's values after initialization (initial = calculated, no start value)."""
    import dataclasses

    from tribocosim.components import registry

    for name in NAMES:
        md = descriptions[name]
        comp = registry.find(name)
        variables = {v.name: v for v in md.modelVariables}
        fields = [f for cls in (comp.parameters, comp.files) if cls is not None for f in dataclasses.fields(cls)]
        assert set(variables) == {f.name for f in fields} | {p.name for p in (*comp.inputs, *comp.outputs)}, name
        for f in fields:
            var, meta = variables[f.name], f.metadata
            assert var.causality == "parameter" and meta["description"] in var.description, (name, f.name)
            if var.type == "Real":
                assert float(var.start) == f.default and var.unit == (meta["unit"] or "1"), (name, f.name)
                num = lambda x: None if x is None else float(x)  # noqa: E731
                assert (num(var.min), num(var.max)) == (num(meta.get("low")), num(meta.get("high"))), (name, f.name)
        for port in comp.outputs:
            var = variables[port.name]
            assert var.causality == "output" and var.initial == "calculated" and var.start is None, (name, port.name)
        assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate
        assert md.coSimulation.canHandleVariableCommunicationStepSize and not md.coSimulation.needsExecutionTool


def test_fmpy_validate_is_clean_and_no_python_file_is_inside(native_fmus):
    from fmpy.validation import validate_fmu

    for name, path in native_fmus.items():
        assert validate_fmu(str(path)) == [], name
        with zipfile.ZipFile(path) as z:
            files = z.namelist()
        assert not [f for f in files if f.endswith((".py", ".pyc"))], files
        assert ("resources/friction_table.tca" in files) == (name == "StripDraw"), "the table in its resource form"


def test_the_binary_exports_every_fmi2_function_and_no_internal_one(unzipped, fmi2_host, descriptions):
    for name, folder in unzipped.items():
        assert sorted(p.name for p in (folder / "binaries").iterdir()) == ["linux64"]
        exported = exported_functions(folder / "binaries" / "linux64" / f"{name}.so")
        assert FMI2_FUNCTIONS <= exported, (name, sorted(FMI2_FUNCTIONS - exported))
        assert not [f for f in exported if f.startswith("tc_")], "internal functions stay hidden"
        md = descriptions[name]
        proc = subprocess.run([str(fmi2_host), str(folder), name, md.guid, "--symbols"], capture_output=True, text=True)
        assert proc.stdout.strip() == f"{len(FMI2_FUNCTIONS)} functions exported", proc.stderr


# ----------------------------------------------------------------------------------- native == Python
def _strip_schedule(kind: str, n: int, dt: float = 1e-3):
    """(dt, normal_force, grip_velocity) rows: the demo draw (10 MPa, velocity ramp over 10 ms), or a pressure
    ramp 1 -> 20 MPa with the grip reversing half-way."""
    rows = []
    for k in range(n):
        t = (k + 0.5) * dt
        if kind == "demo":
            rows.append((dt, 12250.0, 0.08 * min(1.0, t / 0.01)))
        else:
            frac = k / max(1, n - 1)
            v = 0.08 * min(1.0, t / 0.01) if frac < 0.5 else -0.08 * min(1.0, (frac - 0.5) * n * dt / 0.01)
            rows.append((dt, (1e6 + 19e6 * frac) * 0.035 * 0.035, v))
    return rows


def _python_strip(parameters: dict, schedule):
    from tribocosim.components.stripdraw.component import COMPONENT

    model = COMPONENT.make(parameters).model
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RangeWarning)
        outs = [model.step(dt, {"normal_force": f, "grip_velocity": v}) for dt, f, v in schedule]
    backwards = [w for w in caught if issubclass(w.category, RangeWarning) and "grip_velocity = -" in str(w.message)]
    reverses = any(v < 0 for _, _, v in schedule)
    assert len(backwards) == int(reverses), "a grip that moves back is warned once, when it starts (as the FMU does)"
    return np.array([[o[k] for k in STRIP_OUTPUTS] for o in outs]), model


CASES = [("implicit", "table", "demo"), ("implicit", "closed_form", "ramp"), ("implicit", "constant", "demo"),
         ("explicit", "table", "ramp"), ("explicit", "closed_form", "demo"), ("explicit", "constant", "ramp")]


@pytest.mark.parametrize("integrator, law, kind", CASES)
def test_c_host_without_python_equals_the_binding_bit_for_bit(fmi2_host, unzipped, descriptions, tmp_path,
                                                             integrator, law, kind):
    """One core: the FMU in a C host and StripDrawModel in Python give the same numbers, to the last bit (the
    host prints 17 significant digits). The explicit integrator resolves the waves (~1e4 substeps per ms): its
    cases run 25 ms."""
    n = 1750 if integrator == "implicit" else 25
    schedule = _strip_schedule(kind, n)
    field = tmp_path / "field.csv"
    params = {"integrator": integrator, "friction_model": law, "field_output": str(field),
              "field_output_interval": 0.0 if n < 100 else 0.05}
    got, _ = run_host(fmi2_host, unzipped["StripDraw"], descriptions["StripDraw"], tmp_path, schedule,
                      inputs=("normal_force", "grip_velocity"), outputs=STRIP_OUTPUTS, parameters=params)
    want, model = _python_strip({k: v for k, v in params.items() if not k.startswith("field")}, schedule)
    worst = {}
    for j, name in enumerate(STRIP_OUTPUTS):
        scale = max(np.abs(want[:, j]).max(), 1e-300)
        worst[name] = float(np.abs(got[:, j + 1] - want[:, j]).max() / scale)
    from tribocosim.components.native.resource_io.field_file import read_fields

    beta = read_fields(field)["beta"][-1]
    worst["beta field"] = float(np.abs(beta - model.beta).max() / max(model.beta.max(), 1e-300))
    print(f"\n{integrator} {law} {kind}: largest relative difference " + ", ".join(f"{k} {v:.2g}" for k, v in worst.items()))
    assert max(worst.values()) == 0.0, worst
    assert want[:, 0].max() > 0, "the strip must be pulled"


def _initialized_strip(unzipped, md, name: str):
    """A StripDraw FMU2Slave with its default parameters, out of initialization mode."""
    from fmpy.fmi2 import FMU2Slave

    s = FMU2Slave(guid=md.guid, unzipDirectory=str(unzipped["StripDraw"]), modelIdentifier="StripDraw",
                  instanceName=name)
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    return s


def test_a_vanishing_step_changes_the_fmus_outputs_by_a_vanishing_amount(unzipped, descriptions):
    """After 500 steps of the default draw, doStep(1e-15 s) in fmpy changes no output by more than 1e-9 relative
    (the rates of the state: tests/components/test_stripdraw_verification.py), and gives the binding's numbers
    bit for bit."""
    from tribocosim.components.stripdraw.component import COMPONENT

    md = descriptions["StripDraw"]
    vr = {v.name: v.valueReference for v in md.modelVariables}
    names = [n for n in STRIP_OUTPUTS if n != "table_clamp_count"]
    s = _initialized_strip(unzipped, md, "tiny")
    model = COMPONENT.make({}).model
    t = 0.0
    steps = [(dt, f, v) for dt, f, v in _strip_schedule("demo", 500)] + [(1e-15, 12250.0, 0.08)]
    rows = []
    for dt, f, v in steps:
        s.setReal([vr["normal_force"], vr["grip_velocity"]], [f, v])
        s.doStep(t, dt)
        t += dt
        rows.append(s.getReal([vr[n] for n in names]))
        out = model.step(dt, {"normal_force": f, "grip_velocity": v})
        assert rows[-1] == [out[n] for n in names]
    s.terminate()
    s.freeInstance()
    before, after = np.array(rows[-2]), np.array(rows[-1])
    change = np.abs(after - before) / np.abs(before)
    assert change.max() <= 1e-9, dict(zip(names, change))


def test_press_and_machine_in_the_c_host_agree_with_the_python_models(fmi2_host, unzipped, descriptions, tmp_path):
    from tribocosim.components.machine import MachineModel, MachineParameters
    from tribocosim.components.press import PressModel, PressParameters

    rng = np.random.default_rng(3)
    dts = rng.uniform(2e-4, 3e-3, 200)
    table = "0 0; 0.05 12250; 0.2 20000"
    got, _ = run_host(fmi2_host, unzipped["Press"], descriptions["Press"], tmp_path, [(dt,) for dt in dts],
                      outputs=("normal_force", "force_reference"), parameters={"setpoint_table": table})
    press = PressModel(PressParameters(setpoint_table=table))
    want = np.array([list(press.step(dt).values()) for dt in dts])
    np.testing.assert_allclose(got[:, 1:], want, rtol=1e-9, atol=1e-9 * np.abs(want).max())
    pulls = rng.uniform(0, 4000, dts.size)
    got, _ = run_host(fmi2_host, unzipped["DrawingMachine"], descriptions["DrawingMachine"], tmp_path,
                      list(zip(dts, pulls)), inputs=("pull_force",),
                      outputs=("grip_velocity", "grip_position", "velocity_reference", "motor_force"))
    machine = MachineModel(MachineParameters())
    want = np.array([list(machine.step(dt, {"pull_force": f}).values()) for dt, f in zip(dts, pulls)])
    for j in range(want.shape[1]):
        np.testing.assert_allclose(got[:, 1 + j], want[:, j], rtol=0, atol=1e-9 * np.abs(want[:, j]).max())


# ----------------------------------------------------------------------------------- state, errors, leaks
def test_serialized_state_replays_bit_identically_in_the_c_host(fmi2_host, unzipped, descriptions, tmp_path):
    schedule = _strip_schedule("ramp", 400)
    _, proc = run_host(fmi2_host, unzipped["StripDraw"], descriptions["StripDraw"], tmp_path, schedule,
                       inputs=("normal_force", "grip_velocity"), outputs=STRIP_OUTPUTS, extra=["--replay", "150"])
    assert "replay from step 150 bit-identical" in proc.stderr


def test_fmpy_state_round_trips_across_instances(unzipped, descriptions):
    from fmpy.fmi2 import FMU2Slave

    md = descriptions["StripDraw"]
    vr = {v.name: v.valueReference for v in md.modelVariables}
    outs = [vr[n] for n in STRIP_OUTPUTS if n != "table_clamp_count"]

    def make(name):
        s = FMU2Slave(guid=md.guid, unzipDirectory=str(unzipped["StripDraw"]), modelIdentifier="StripDraw",
                      instanceName=name)
        s.instantiate()
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        s.setString([vr["friction_model"]], ["closed_form"])
        s.exitInitializationMode()
        return s

    a, b = make("a"), make("b")
    schedule = _strip_schedule("ramp", 300)
    t = 0.0
    for dt, f, v in schedule[:120]:
        a.setReal([vr["normal_force"], vr["grip_velocity"]], [f, v])
        a.doStep(t, dt)
        t += dt
    blob = a.serializeFMUstate(a.getFMUstate())
    rows_a, rows_b = [], []
    state = b.deSerializeFMUstate(blob)
    b.setFMUstate(state)
    for dt, f, v in schedule[120:]:
        for s, rows in ((a, rows_a), (b, rows_b)):
            s.setReal([vr["normal_force"], vr["grip_velocity"]], [f, v])
            s.doStep(t, dt)
            rows.append(s.getReal(outs))
        t += dt
    assert_array_equal(np.array(rows_a), np.array(rows_b))
    for s in (a, b):
        s.terminate()
        s.freeInstance()


def _fmpy_instance(unzipped, md, parameters: dict, messages: list):
    from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

    def log(env, name, status, category, message):
        messages.append((int(status), message.decode()))

    cb = fmi2CallbackFunctions()
    cb.logger = fmi2CallbackLoggerTYPE(log)
    s = FMU2Slave(guid=md.guid, unzipDirectory=str(unzipped), modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName="x")
    s.instantiate(callbacks=cb)
    s._keep = cb
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    vr = {v.name: v for v in md.modelVariables}
    for k, value in parameters.items():
        v = vr[k]
        {"Real": s.setReal, "Integer": s.setInteger, "String": s.setString}[v.type]([v.valueReference], [value])
    return s


BAD_PARAMETERS = [
    ("StripDraw", {"tool_length": -1.0}, "tool_length = -1 m is out of range; allowed: [0.0001, 1] m"),
    ("StripDraw", {"friction_model": "tabel"}, "friction_model = 'tabel' is not allowed; choose one of table, "
                                               "closed_form, constant"),
    ("StripDraw", {"table_file": "/nowhere/t.npz"}, "friction table /nowhere/t.npz: the native model reads its resource form /nowhere/t.tca"),
    ("StripDraw", {"n_elements": 2}, "n_elements = 2 is out of range; allowed: [4, 200000]"),
    ("StripDraw", {"field_input": "/nowhere/f.npz"}, "field_input = '/nowhere/f.npz' cannot be read"),
    ("Press", {"setpoint_table": "0 0; 0.1"}, "setpoint_table = '0 0; 0.1' is malformed"),
    ("DrawingMachine", {"screw_lead": 0.0}, "screw_lead = 0 m is out of range"),
]


@pytest.mark.parametrize("name, parameters, message", BAD_PARAMETERS)
def test_a_bad_parameter_is_an_error_at_initialization_naming_it(unzipped, descriptions, name, parameters, message):
    from fmpy.fmi1 import FMICallException

    msgs = []
    s = _fmpy_instance(unzipped[name], descriptions[name], parameters, msgs)
    with pytest.raises(FMICallException) as exc:
        s.exitInitializationMode()
    assert exc.value.status == 3, "fmi2Error"
    assert any(status == 3 and message in text for status, text in msgs), msgs
    with pytest.raises(FMICallException):
        s.doStep(0.0, 1e-3)
    s.freeInstance()


def _bounds(md):
    """(name, value) of every Real and Integer parameter at its declared min and at its declared max."""
    for v in md.modelVariables:
        if v.causality == "parameter" and v.type in ("Real", "Integer"):
            for bound in (v.min, v.max):
                if bound is not None:
                    yield v.name, (int(bound) if v.type == "Integer" else float(bound))


@pytest.mark.parametrize("name", NAMES)
def test_every_parameter_is_accepted_at_its_declared_min_and_at_its_max(unzipped, descriptions, name):
    """FMI 2.0 (section 2.2.7, Real and Integer attributes): min and max bound the value inclusively
    (min <= value <= max); a host's parameter dialog offers them as valid. Each parameter alone at each bound
    (the others at their start values) initializes without a message above OK."""
    from fmpy.fmi1 import FMICallException

    checked = []
    for pname, value in _bounds(descriptions[name]):
        msgs = []
        s = _fmpy_instance(unzipped[name], descriptions[name], {pname: value}, msgs)
        try:
            s.exitInitializationMode()
        except FMICallException:
            pytest.fail(f"{name}.{pname} = {value!r} (a declared bound) refused: {msgs}")
        finally:
            s.freeInstance()
        assert not [m for m in msgs if m[0] >= 2], (pname, value, msgs)
        checked.append(pname)
    assert len(checked) >= 10, checked


def _raw(unzipped, md, function: str, restype, argtypes):
    """An FMI function of an FMU's linux64 library without fmpy's status check (its status is the result)."""
    import ctypes

    lib = ctypes.CDLL(str(Path(unzipped) / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"))
    f = getattr(lib, function)
    f.restype, f.argtypes = restype, argtypes
    return f


def _strip_stepped(unzipped, md, parameters: dict, steps: int, messages: list, normal_force=12250.0,
                   grip_velocity=0.08):
    """A StripDraw instance (fmpy) after ``steps`` steps of 1 ms with the given inputs; (slave, time, vr)."""
    s = _fmpy_instance(unzipped, md, parameters, messages)
    s.exitInitializationMode()
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s.setReal([vr["normal_force"], vr["grip_velocity"]], [normal_force, grip_velocity])
    t = 0.0
    for _ in range(steps):
        s.doStep(t, 1e-3)
        t += 1e-3
    return s, t, vr


@pytest.mark.parametrize("name", NAMES)
def test_no_output_has_direct_feedthrough_and_the_model_description_says_so(unzipped, descriptions, name):
    """FMI 2.0 section 2.2.8: an output listed without dependencies depends on every input; dependencies=""
    says it depends on none. Measured: after steps, setting every input to another value changes no output until
    the next doStep (bit for bit). An importer that reads the ModelStructure (our validation) then sees no
    dependency and so no algebraic loop (OMSimulator reported 'Alg. loop (size 2/4) strip, drive' without it)."""

    md = descriptions[name]
    outputs = [v for v in md.modelVariables if v.causality == "output"]
    inputs = [v for v in md.modelVariables if v.causality == "input"]
    assert [(u.variable.name, u.dependencies) for u in md.outputs] == [(v.name, []) for v in outputs]
    initial = {"contact_pressure": ["normal_force"]} if name == "StripDraw" else {}  # at initialization only
    assert [(u.variable.name, [d.name for d in u.dependencies]) for u in md.initialUnknowns] == \
        [(v.name, initial.get(v.name, [])) for v in outputs]
    msgs = []
    s = _fmpy_instance(unzipped[name], md, {}, msgs)
    s.exitInitializationMode()
    reals = [v.valueReference for v in outputs if v.type == "Real"]
    ints = [v.valueReference for v in outputs if v.type == "Integer"]
    t = 0.0
    for _ in range(20):
        s.doStep(t, 1e-3)
        t += 1e-3
    before = (s.getReal(reals), s.getInteger(ints))
    for v in inputs:
        s.setReal([v.valueReference], [0.5 * float(v.start or 1.0) + 1000.0])
        assert (s.getReal(reals), s.getInteger(ints)) == before, f"{name}.{v.name} feeds an output through"
    s.doStep(t, 1e-3)
    if inputs:
        assert (s.getReal(reals), s.getInteger(ints)) != before, "the inputs reach the outputs in the next step"
    s.terminate()
    s.freeInstance()


def test_outputs_after_initialization_are_the_model_s_values(unzipped, descriptions):
    """Outputs are initial="calculated" (FMI 2.0 section 2.2.7): what a host reads at t = 0, after
    fmi2ExitInitializationMode, is the model's value there, not a declared start. A later pass that starts from
    a debris field (beta_initial = 0.01) has beta_mean = beta_max = 0.01 at t = 0 (a declared start of 0, as
    initial="exact" had it, would be stale)."""
    md = descriptions["StripDraw"]
    vr = {v.name: v for v in md.modelVariables}
    assert vr["beta_max"].initial == "calculated" and vr["beta_max"].start is None
    msgs = []
    s = _fmpy_instance(unzipped["StripDraw"], md, {"n_elements": 40, "beta_initial": 0.01}, msgs)
    s.exitInitializationMode()
    assert s.getReal([vr["beta_max"].valueReference, vr["beta_mean"].valueReference]) == [0.01, 0.01]
    s.terminate()
    s.freeInstance()


def test_outputs_at_the_start_report_the_inputs_set_during_initialization(unzipped, descriptions):
    """contact_pressure at t = 0 is F_N / (L_T w_T) of the normal force set during initialization (the model's
    value after initialization, not the 0 of no input), and the model description says it depends on that input
    at initialization (InitialUnknown dependencies) and on none in a step (Outputs dependencies=""); a normal force
    a step would refuse is logged as a warning and the first doStep discards it."""
    md = descriptions["StripDraw"]
    vr = {v.name: v for v in md.modelVariables}
    index = {v.name: k + 1 for k, v in enumerate(md.modelVariables)}
    initial = {u.variable.name: [d.name for d in u.dependencies] for u in md.initialUnknowns}
    assert initial["contact_pressure"] == ["normal_force"] and initial["pull_force"] == []
    assert all(not u.dependencies for u in md.outputs)
    assert index["normal_force"] == next(k + 1 for k, v in enumerate(md.modelVariables) if v.name == "normal_force")
    msgs = []
    s = _fmpy_instance(unzipped["StripDraw"], md, {"n_elements": 40}, msgs)
    s.setReal([vr["normal_force"].valueReference], [12250.0])
    s.exitInitializationMode()
    assert s.getReal([vr["contact_pressure"].valueReference]) == [12250.0 / (0.035 * 0.035)]
    s.terminate()
    s.freeInstance()
    msgs = []
    s = _fmpy_instance(unzipped["StripDraw"], md, {"n_elements": 40}, msgs)
    s.setReal([vr["normal_force"].valueReference], [-5.0])
    assert s.exitInitializationMode() == 1  # fmi2Warning
    assert any(st == 1 and "at the end of initialization: normal_force = -5 N must be >= 0" in m for st, m in msgs), msgs
    s.terminate()
    s.freeInstance()


def test_the_demo_scene_has_no_algebraic_loop_for_an_importer_that_reads_the_dependencies():
    from tribocosim.cosim.scene.validate import load_scene

    plan = load_scene(Path(__file__).resolve().parents[2] / "models" / "scenes" / "demo.toml")
    for name, model in plan.fmus.items():
        assert all(d == set() for d in model.dependencies.values()), (name, model.dependencies)


def test_a_step_no_step_size_can_complete_is_an_error_and_a_restored_state_goes_on(unzipped, descriptions):
    """A negative normal force is refused at any step size (a step 2^-20 as long is refused too): fmi2Error, "the
    simulation cannot be continued with this FMU instance" (FMI 2.0.4 section 2.1.3), so that every host stops
    instead of retrying (fmpy's simulate_fmu retried a discard forever; our master halved it ten times); the
    message says why; fmi2Terminated is true. A zero step, which a host can fix, is a discard. An FMU state taken
    before restores the instance (the standard's way back), and it steps on."""
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import fmi2Terminated

    md = descriptions["StripDraw"]
    msgs = []
    s, t, vr = _strip_stepped(unzipped["StripDraw"], md, {"n_elements": 40}, 5, msgs)
    assert s.getBooleanStatus(fmi2Terminated) is False
    with pytest.raises(FMICallException) as exc:
        s.doStep(t, 0.0)
    assert exc.value.status == 2 and s.getBooleanStatus(fmi2Terminated) is False, "a zero step: fix the step"
    state = s.getFMUstate()
    s.setReal([vr["normal_force"]], [-5.0])
    with pytest.raises(FMICallException) as exc:
        s.doStep(t, 1e-3)
    assert exc.value.status == 3 and s.getBooleanStatus(fmi2Terminated) is True
    assert any(st == 3 and "normal_force = -5 N" in m and "no step size can complete it" in m for st, m in msgs), msgs
    with pytest.raises(FMICallException):
        s.doStep(t, 1e-4)
    s.setFMUstate(state)
    s.doStep(t, 1e-3)
    assert s.getBooleanStatus(fmi2Terminated) is False
    s.freeFMUstate(state)
    s.terminate()
    s.freeInstance()


def test_a_step_repeated_unchanged_after_a_discard_asks_the_host_to_stop(unzipped, descriptions):
    """A step too long for the model (more coupling intervals than it takes) is discarded and a shorter one would
    do: Terminated stays false. The same doStep again, unchanged (same state, step size and inputs), would be
    discarded forever (fmpy's simulate_fmu repeats it): it is discarded at once and Terminated is true; a shorter
    step from the same state is taken."""
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import fmi2Terminated

    md = descriptions["StripDraw"]
    msgs = []
    s, t, vr = _strip_stepped(unzipped["StripDraw"], md, {"n_elements": 40}, 2, msgs)
    with pytest.raises(FMICallException) as exc:
        s.doStep(t, 1e8)  # 8e6 m of draw: more than 1e8 coupling intervals
    assert exc.value.status == 2 and s.getBooleanStatus(fmi2Terminated) is False
    with pytest.raises(FMICallException):
        s.doStep(t, 1e8)
    assert s.getBooleanStatus(fmi2Terminated) is True
    assert any(st == 2 and "repeats a step this FMU discarded, unchanged" in m and "fmi2Terminated" in m
               for st, m in msgs), msgs
    s.doStep(t, 1e-5)
    assert s.getBooleanStatus(fmi2Terminated) is False
    s.terminate()
    s.freeInstance()


def test_a_grip_faster_than_the_strips_waves_is_refused_at_once(unzipped, descriptions):
    """A grip velocity of 1e6 m/s made one 1 ms step cut into 3e5 coupling intervals. A grip speed at or above the
    bar's wave speed sqrt(E / rho) (5130 m/s) is an input the model refuses at any step size: an error at once (the
    input check, which runs before any coupling interval, says so), naming the speed and the limit; the same core in
    the Python binding refuses it as an input, its state unchanged."""
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import fmi2Terminated

    from tribocosim.components.stripdraw import StripDrawModel, StripDrawParameters, make_friction_law, read_table
    from tribocosim.errors import ParameterError
    from tribocosim.paths import DEFAULT_TABLE

    md = descriptions["StripDraw"]
    msgs = []
    s, t, vr = _strip_stepped(unzipped["StripDraw"], md, {}, 2, msgs)
    s.setReal([vr["grip_velocity"]], [1e6])
    with pytest.raises(FMICallException) as exc:
        s.doStep(t, 1e-3)
    params = StripDrawParameters()
    model = StripDrawModel(params, make_friction_law(params, read_table(DEFAULT_TABLE)))
    model.step(1e-3, {"normal_force": 12250.0, "grip_velocity": 0.08})
    before = model.get_state()
    with pytest.raises(ParameterError, match="is not below the strip's wave speed"):
        model.step(1e-3, {"normal_force": 12250.0, "grip_velocity": 1e6})
    assert np.array_equal(model.get_state(), before) and model.n_steps == 1
    assert exc.value.status == 3 and s.getBooleanStatus(fmi2Terminated) is True
    assert any("grip_velocity = 1e+06 m/s is not below the strip's wave speed sqrt(E / rho) = 5129.8917" in m
               for _, m in msgs), msgs
    s.terminate()
    s.freeInstance()


def test_outputs_read_in_initialization_mode_follow_the_inputs_set_there(unzipped, descriptions):
    """contact_pressure is an InitialUnknown that depends on normal_force: read in initialization mode after
    normal_force is set, it is F_N / (L_T w_T) (it read 0); a parameter set after it counts too."""
    md = descriptions["StripDraw"]
    msgs = []
    s = _fmpy_instance(unzipped["StripDraw"], md, {}, msgs)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s.setReal([vr["normal_force"]], [24500.0])
    assert s.getReal([vr["contact_pressure"]]) == [24500.0 / 0.035**2]
    s.setReal([vr["tool_length"]], [0.07])
    assert s.getReal([vr["contact_pressure"], vr["grip_position"]]) == [24500.0 / (0.07 * 0.035), 0.0]
    s.exitInitializationMode()
    assert s.getReal([vr["contact_pressure"]]) == [24500.0 / (0.07 * 0.035)]
    s.terminate()
    s.freeInstance()


@pytest.mark.parametrize("extra, warned", [(6e-14, False), (1e-8, True)])
def test_a_draw_of_draw_length_ends_without_a_warning_whatever_its_round_off(unzipped, descriptions, extra, warned):
    """StripDraw's default experiment draws exactly draw_length (1.75 s at 0.08 m/s), and the grip position, a sum
    over 1750 steps, ends a few 1e-16 m on either side of it depending on the host's step sizes: a last step 6e-14 s
    long (a host's time grid) ended 4.4e-16 m beyond it with a warning. A value within 1e-9 (relative) of its bound
    is on it; a draw 8e-10 m longer (1e-8 s more) still warns."""
    import ctypes

    md = descriptions["StripDraw"]
    msgs = []
    s = _fmpy_instance(unzipped["StripDraw"], md, {}, msgs)
    s.exitInitializationMode()
    do_step = _raw(unzipped["StripDraw"], md, "fmi2DoStep", ctypes.c_int,
                   [ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_int])
    statuses = [do_step(s.component, k * 1e-3, 1e-3 + (extra if k == 1749 else 0.0), 1) for k in range(1750)]
    assert statuses.count(1) == (1 if warned else 0) and set(statuses) <= {0, 1}, msgs
    assert s.getReal([_vr(md, "grip_position")])[0] > 0.14
    s.terminate()
    s.freeInstance()


def _closed_form_first_below_floor(parameters: dict, steps: int) -> int | None:
    """The first step (index) of a draw of 1 ms steps at the default inputs after which a node under the pad holds mu
    of the closed-form law below the floor: mu = mu0 (1 - (1 - r) s b beta h'_rms / kappa) (Eq. 9, alpha = b) from the
    Python model's nodal beta and contact weights; None when none does."""
    from tribocosim.components.stripdraw import StripDrawParameters, make_friction_law
    from tribocosim.components.stripdraw.friction_floor import MU_FLOOR
    from tribocosim.components.stripdraw.model import StripDrawModel

    import warnings

    from tribocosim.errors import RangeWarning

    p = StripDrawParameters(friction_model="closed_form", **parameters)
    model = StripDrawModel(p, make_friction_law(p, None))
    for k in range(steps):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RangeWarning)  # its own floor warning (tests/components)
            model.step(1e-3, {"normal_force": 12250.0, "grip_velocity": 0.08})
        beta = model.beta[model.fields()["contact"] > 0]
        mu = p.mu0 * (1 - (1 - p.flake_shear_ratio) * p.particle_area_scale * p.alpha_b * beta * p.rms_slope / p.kappa)
        if beta.size and mu.min() < MU_FLOOR * (1 - 1e-9):
            return k
    return None


def test_mu_below_the_documented_floor_is_one_warning_naming_the_setting(unzipped, descriptions):
    """The paper's model (flake_shear_ratio = 0) with the closed-form law, whose cap of beta the first pass reaches:
    the doStep after which mu under the pad first falls below the floor 0.03 returns fmi2Warning, once, with a
    message naming flake_shear_ratio = 0 with mu0 and the time; the steps after it return fmi2OK. A state restored
    from before it and stepped past it again warns no more (once per instance). The default r = 0.2 gives the floor
    itself at the cap (r mu0 = 0.03) and no warning over as many steps."""
    import ctypes

    md = descriptions["StripDraw"]
    do_step = _raw(unzipped["StripDraw"], md, "fmi2DoStep", ctypes.c_int,
                   [ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_int])
    for r in (0.0, 0.2):
        msgs = []
        s = _fmpy_instance(unzipped["StripDraw"], md, {"friction_model": "closed_form", "flake_shear_ratio": r}, msgs)
        s.exitInitializationMode()
        statuses, times, t = [], [], 0.0
        for k in range(300):
            if k == 50:
                before = s.getFMUstate()
            statuses.append(do_step(s.component, t, 1e-3, 1))
            t += 1e-3
            times.append(t)
        cap = s.getReal([_vr(md, "beta_max")])[0]
        assert cap == pytest.approx(2.0 / (207.91 * 0.34), rel=1e-12), "the cap kappa / (s b h'_rms) is reached"
        warned = [m for st, m in msgs if st == 1]
        first = _closed_form_first_below_floor({"flake_shear_ratio": r}, 300)
        if r == 0.2:
            assert first is None and statuses == [0] * 300 and not warned, msgs
            s.freeInstance()
            continue
        assert first is not None and 50 < first < 250, first
        assert [k for k, st in enumerate(statuses) if st != 0] == [first], statuses
        assert len(warned) == 1 and warned[0].startswith(f"at t = {times[first]!r} s mu = "), (first, warned)
        assert "below the documented floor 0.03" in warned[0]
        assert "flake_shear_ratio = 0 with mu0 = 0.15 lets mu fall to 0 where flakes carry the whole contact" in warned[0]
        s.setFMUstate(before)
        t = 51e-3 - 1e-3
        again = []
        for _ in range(250):
            again.append(do_step(s.component, t, 1e-3, 1))
            t += 1e-3
        assert again == [0] * 250 and len([m for st, m in msgs if st == 1]) == 1, msgs
        s.freeInstance()


_SIMULATE_NEGATIVE = """
import sys
from fmpy import simulate_fmu
result = simulate_fmu(sys.argv[1], stop_time=0.01, step_size=1e-3, start_values={"normal_force": -5.0})
print("rows", len(result), "last time", result["time"][-1])
"""


def test_fmpy_simulate_fmu_with_a_negative_normal_force_ends_and_says_why(native_fmus, tmp_path):
    """fmpy's simulate_fmu retries a discarded step until the slave says it is terminated: it ran forever (killed
    after 120 s, hundreds of MB of log). It ends at once with fmpy's error for fmi2DoStep and the reason in the
    log."""
    script = tmp_path / "negative.py"
    script.write_text(_SIMULATE_NEGATIVE)
    proc = subprocess.run([sys.executable, str(script), str(native_fmus["StripDraw"])], capture_output=True,
                          text=True, timeout=120, cwd=tmp_path)
    assert proc.returncode != 0 and "fmi2DoStep failed with status 3 (error)" in proc.stderr, proc.stderr[-2000:]
    out = proc.stdout + proc.stderr
    assert out.count("the inputs are at fault") == 1 and "normal_force = -5 N must be >= 0" in out, out[-2000:]
    assert "at the end of initialization: normal_force = -5 N must be >= 0" in out, out[-2000:]


@pytest.mark.parametrize("inputs, parameters, message", [
    ({"grip_velocity": 4.0}, {}, "m is above draw_length = 0.14 m, the largest grip_position"),
    ({"normal_force": 1e30}, {}, "contact_pressure = 8.163265306122448e+32 Pa is above hardness = 8e+08 Pa"),
    ({"grip_velocity": 0.08}, {"draw_length": 0.002}, "m is above draw_length = 0.002 m, the largest grip_position"),
    ({"grip_velocity": -0.08}, {}, "grip_velocity = -0.08 m/s is below 0 m/s, the least grip_velocity"),
    ({"grip_velocity": -1e3}, {}, "grip_velocity = -1e+03 m/s is below 0 m/s, the least grip_velocity"),
])
def test_absurd_but_finite_inputs_give_a_warning_status_and_message(unzipped, descriptions, inputs, parameters,
                                                                   message):
    """The strip's ports declare the ranges its outputs and inputs are built for (grip_position <= draw_length: the
    bar's length; contact_pressure <= hardness; grip_velocity >= 0: the grip pulls). The step after which an output
    leaves one, or that takes an input outside one, returns fmi2Warning (the status a host can test) with a message
    naming the variable, its value, the bound and the time; the steps after it, while the variable stays outside,
    return fmi2OK; the results are still computed."""
    import ctypes

    md = descriptions["StripDraw"]
    msgs = []
    s = _fmpy_instance(unzipped["StripDraw"], md, {"n_elements": 40, **parameters}, msgs)
    s.exitInitializationMode()
    vr = {v.name: v.valueReference for v in md.modelVariables}
    for k, x in inputs.items():
        s.setReal([vr[k]], [x])
    do_step = _raw(unzipped["StripDraw"], md, "fmi2DoStep", ctypes.c_int,
                   [ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_int])
    statuses, ends = [], []
    for k in range(60):
        statuses.append(do_step(s.component, k * 1e-3, 1e-3, 1))
        ends.append(k * 1e-3 + 1e-3)
    warned = [i for i, st in enumerate(statuses) if st == 1]
    assert len(warned) == 1 and set(statuses) <= {0, 1}, statuses
    text = [m for st, m in msgs if st == 1]
    assert len(text) == 1 and message in text[0] and "the model is built for" in text[0], msgs
    when = "in the step to" if "grip_velocity =" in message else "at"
    assert text[0].startswith(f"{when} t = {ends[warned[0]]!r} s"), (warned, text)
    s.terminate()
    s.freeInstance()


def test_bad_inputs_are_discarded_with_the_state_unchanged_and_a_message(unzipped, descriptions):
    from fmpy.fmi1 import FMICallException

    md = descriptions["StripDraw"]
    vr = {v.name: v.valueReference for v in md.modelVariables}
    msgs = []
    s = _fmpy_instance(unzipped["StripDraw"], md, {}, msgs)
    s.exitInitializationMode()
    s.setReal([vr["normal_force"], vr["grip_velocity"]], [12250.0, 0.01])
    s.doStep(0.0, 1e-3)
    before = s.getReal([vr["pull_force"], vr["beta_max"]])
    state = s.getFMUstate()
    for f, v, dt, status in ((float("nan"), 0.01, 1e-3, 3), (-5.0, 0.01, 1e-3, 3), (12250.0, float("inf"), 1e-3, 3),
                             (12250.0, 0.01, 0.0, 2), (12250.0, 0.01, -1e-3, 2)):
        s.setReal([vr["normal_force"], vr["grip_velocity"]], [f, v])
        with pytest.raises(FMICallException) as exc:
            s.doStep(1e-3, dt)
        assert exc.value.status == status, "fmi2Error for bad inputs (no step size helps), fmi2Discard for a bad step"
        assert s.getReal([vr["pull_force"], vr["beta_max"]]) == before
        s.setFMUstate(state)  # the way back from fmi2Error
    s.freeFMUstate(state)
    assert any(st == 3 and "normal_force = nan" in m and "the FMU state is unchanged" in m for st, m in msgs), msgs
    s.setReal([vr["normal_force"], vr["grip_velocity"]], [12250.0, 0.01])
    s.doStep(1e-3, 1e-3)  # usable again
    s.terminate()
    s.freeInstance()


def test_input_derivatives_reach_the_strip_for_one_step_and_only_it_takes_them(unzipped, descriptions):
    """The StripDraw FMU declares canInterpolateInputs and follows fmi2SetRealInputDerivatives as the Python
    model follows step(..., derivatives) (bit for bit); the derivatives apply to the next doStep only (a step
    after it without new ones equals a held step), fmi2SetReal of the input clears them, a state round trip
    carries them, and the Press and DrawingMachine (canInterpolateInputs = false) refuse them."""
    from fmpy.fmi1 import FMICallException

    from tribocosim.components.stripdraw.friction import make_friction_law
    from tribocosim.components.stripdraw.model import StripDrawModel
    from tribocosim.components.stripdraw.parameters import StripDrawParameters

    assert descriptions["StripDraw"].coSimulation.canInterpolateInputs
    assert not descriptions["Press"].coSimulation.canInterpolateInputs
    assert not descriptions["DrawingMachine"].coSimulation.canInterpolateInputs
    md = descriptions["StripDraw"]
    vr = {v.name: v.valueReference for v in md.modelVariables}
    outs = [vr[n] for n in STRIP_OUTPUTS if n != "table_clamp_count"]
    msgs = []
    s = _fmpy_instance(unzipped["StripDraw"], md, {"friction_model": "closed_form", "internal_step": 2e-4}, msgs)
    s.exitInitializationMode()
    p = StripDrawParameters(friction_model="closed_form", internal_step=2e-4)
    py = StripDrawModel(p, make_friction_law(p, None))
    u, d = {"normal_force": 12250.0, "grip_velocity": 0.02}, {"normal_force": (4e5, -1e6), "grip_velocity": (3.0, 0.0)}
    t = 0.0
    for k in range(6):
        s.setReal([vr["normal_force"], vr["grip_velocity"]], [u["normal_force"], u["grip_velocity"]])
        if k % 2 == 0:  # even steps interpolate, odd ones must be held again
            s.setRealInputDerivatives([vr["normal_force"], vr["normal_force"], vr["grip_velocity"]], [1, 2, 1],
                                      [d["normal_force"][0], d["normal_force"][1], d["grip_velocity"][0]])
        s.doStep(t, 1e-3)
        ref = py.step(1e-3, u, d if k % 2 == 0 else None)
        assert_allclose(s.getReal(outs), [ref[n] for n in STRIP_OUTPUTS if n != "table_clamp_count"], rtol=1e-12,
                        atol=0, err_msg=str(k))  # rounding of the contact-weighted means (NumPy's dot product)
        t += 1e-3
    # fmi2SetReal after the derivatives clears them: the step is a held one
    s.setRealInputDerivatives([vr["normal_force"]], [1], [4e5])
    s.setReal([vr["normal_force"]], [u["normal_force"]])
    s.doStep(t, 1e-3)
    ref = py.step(1e-3, u)
    assert_allclose(s.getReal(outs), [ref[n] for n in STRIP_OUTPUTS if n != "table_clamp_count"], rtol=1e-12, atol=0)
    # a state taken with derivatives set replays them
    s.setRealInputDerivatives([vr["grip_velocity"]], [1], [3.0])
    state = s.getFMUstate()
    s.doStep(t + 1e-3, 1e-3)
    first = s.getReal(outs)
    s.setFMUstate(state)
    s.doStep(t + 1e-3, 1e-3)
    assert s.getReal(outs) == first
    for order, value, text in ((3, 1.0, "derivative order 3 of normal_force; this FMU takes orders 1 and 2"),
                               (1, float("nan"), "derivative 1 of normal_force = nan is not finite")):
        with pytest.raises(FMICallException):
            s.setRealInputDerivatives([vr["normal_force"]], [order], [value])
        assert any(st == 3 and text in m for st, m in msgs), msgs
    with pytest.raises(FMICallException):
        s.setRealInputDerivatives([vr["pull_force"]], [1], [1.0])
    s.terminate()
    s.freeInstance()
    mm = descriptions["DrawingMachine"]
    msgs = []
    m = _fmpy_instance(unzipped["DrawingMachine"], mm, {}, msgs)
    m.exitInitializationMode()
    with pytest.raises(FMICallException):
        m.setRealInputDerivatives([{v.name: v.valueReference for v in mm.modelVariables}["pull_force"]], [1], [1.0])
    assert any("canInterpolateInputs = false" in text for _, text in msgs), msgs
    m.freeInstance()


@pytest.mark.parametrize("name, inputs", [("StripDraw", ("normal_force", "grip_velocity")), ("Press", ()),
                                          ("DrawingMachine", ("pull_force",))])
def test_thousands_of_random_calls_never_crash_the_c_host(fmi2_host, unzipped, descriptions, tmp_path, name, inputs):
    md = descriptions[name]
    outs = [v.name for v in md.modelVariables if v.causality == "output"]
    steps = [(1e-3, *([12250.0, 0.01][:len(inputs)] if name == "StripDraw" else [100.0] * len(inputs)))] * 5
    _, proc = run_host(fmi2_host, unzipped[name], md, tmp_path, steps, inputs=inputs, outputs=outs,
                       extra=["--fuzz", "3000", "11"])
    summary = [line for line in proc.stderr.splitlines() if "fuzz:" in line][-1]
    import re

    taken, discarded = map(int, re.search(r"(\d+) steps taken, (\d+) discarded", summary).groups())
    assert taken > 0 and discarded > 0, summary


def test_nothing_leaks_valgrind(fmi2_host, unzipped, descriptions, tmp_path):
    if shutil.which("valgrind") is None:
        pytest.skip("valgrind is not installed")
    schedule = _strip_schedule("demo", 30)
    _, proc = run_host(fmi2_host, unzipped["StripDraw"], descriptions["StripDraw"], tmp_path, schedule,
                       inputs=("normal_force", "grip_velocity"), outputs=STRIP_OUTPUTS,
                       parameters={"n_elements": 60, "field_output": str(tmp_path / "f.npz")},
                       extra=["--replay", "10", "--fuzz", "200", "5"], check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]
    cmd = ["valgrind", "--leak-check=full", "--errors-for-leak-kinds=definite,indirect", "--error-exitcode=9",
           "--quiet"]
    host_cmd = proc.args
    full = subprocess.run(cmd + host_cmd, capture_output=True, text=True, timeout=900, cwd=tmp_path)
    assert full.returncode == 0, full.stderr[-4000:]


def test_libcosimpy_gives_the_same_outputs_as_fmpy(native_fmus, unzipped, descriptions, libcosim_run):
    from fmpy.fmi2 import FMU2Slave

    schedule = _strip_schedule("demo", 200)
    outs = [n for n in STRIP_OUTPUTS if n != "table_clamp_count"]
    got = np.array(libcosim_run(native_fmus["StripDraw"], 1_000_000, ("normal_force", "grip_velocity"),
                                [(f, v) for _, f, v in schedule], outs))
    md = descriptions["StripDraw"]
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s = _initialized_strip(unzipped, md, "f")
    rows = []
    for k, (_, f, v) in enumerate(schedule):  # libcosim passes doStep the difference of integer-ns times
        dt = ((k + 1) * 1_000_000) / 1e9 - (k * 1_000_000) / 1e9
        s.setReal([vr["normal_force"], vr["grip_velocity"]], [f, v])
        s.doStep(k * 1_000_000 / 1e9, dt)
        rows.append(s.getReal([vr[n] for n in outs]))
    s.terminate()
    s.freeInstance()
    assert_array_equal(got, np.array(rows))
