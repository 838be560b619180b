"""The FMI 3.0 variants of the native FMUs: ``tribocosim fmu build --fmi 3``.

- the model descriptions have the FMI 2.0 variables (names, value references, units, descriptions, starts,
  ranges), plus ``time``, and for StripDraw the structural parameter ``n_nodes = n_elements + 1`` and the
  nodal fields ``beta``, ``U``, ``contact`` as arrays of that length; ``fmpy validate`` is clean; the CLI
  writes the same file names, the binary exporting every fmi3 function (every platform's binaries:
  tests/native/test_native_platforms.py, slow);
- run through fmpy's FMI 3 API and through a C host with no Python (tests/native/host/fmi3_host.c), the
  outputs are those of the FMI 2.0 FMUs to the last bit (StripDraw on a short draw, Press, DrawingMachine),
  and the arrays are the FMI 2.0 FMU's field_output rows to the last bit (and the Python model's fields);
- FMU states (get/set, serialize into another instance) replay bit-identically; a bad parameter is fmi3Error
  at initialization naming it; a negative normal force is fmi3Discard with the state unchanged (its
  serialized image byte for byte); what does not apply is fmi3Error naming the function; nothing leaks.

The FMUs are built for linux64 only.
"""

from __future__ import annotations

import importlib.util
import json
import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from tribocosim.errors import RangeWarning

HERE = Path(__file__).resolve().parent
NAMES = ("DrawingMachine", "Press", "StripDraw")
STRIP_OUTPUTS = ("pull_force", "mu_mean", "beta_max", "friction_force", "beta_mean", "sliding_distance",
                 "contact_pressure", "grip_position")
FIELDS = ("beta", "U", "contact")


def _default_nodes() -> int:
    """Nodes of the default bar (n_elements + 1), the length of every field array."""
    from tribocosim.components.stripdraw.parameters import StripDrawParameters

    return StripDrawParameters().n_elements + 1


def _fmi3_functions() -> set[str]:
    """Every function of the FMI 3.0 standard, from its header (the names fmi3Functions.h maps through
    fmi3FullName)."""
    import re

    from tribocosim.components.fmus.native_build import fmi3_headers

    text = (fmi3_headers() / "fmi3Functions.h").read_text()
    return set(re.findall(r"#define (fmi3\w+)\s+fmi3FullName\(", text))


def exported_functions(path):
    """tests/native/exports.py (a sibling module: loaded by path under pytest's importlib mode)."""
    spec = importlib.util.spec_from_file_location("native_exports", HERE / "exports.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.exported_functions(path)


# ----------------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def built(tmp_path_factory) -> dict[int, dict[str, Path]]:
    """``{2: FMI 2.0 FMUs, 3: FMI 3.0 FMUs}`` of the three components, linux64, from the same tree."""
    from tribocosim.components.fmus.native_build import build_native_fmus

    return {v: build_native_fmus(tmp_path_factory.mktemp(f"fmi{v}"), platforms=["linux64"], fmi_version=v)
            for v in (2, 3)}


@pytest.fixture(scope="module")
def unzipped(built, tmp_path_factory):
    from fmpy import extract

    return {(v, n): Path(extract(str(p), str(tmp_path_factory.mktemp(f"u{v}_{n}"))))
            for v, fmus in built.items() for n, p in fmus.items()}


@pytest.fixture(scope="module")
def md(built):
    from fmpy import read_model_description

    return {(v, n): read_model_description(str(p)) for v, fmus in built.items() for n, p in fmus.items()}


@pytest.fixture(scope="module")
def hosts(tmp_path_factory) -> dict[int, Path]:
    """The C hosts of both versions (linux64 executables, no Python)."""
    from tribocosim.components.fmus.native_build import fmi3_headers
    from tribocosim.components.native.toolchain.compiler import compile_executable

    folder = tmp_path_factory.mktemp("hosts")
    flags = ["-isystem", str(fmi3_headers())]  # fmi3FunctionTypes.h has prototype-less callbacks
    return {v: compile_executable([HERE / "host" / f"fmi{v}_host.c"], folder / f"fmi{v}_host", extra_flags=flags,
                                  libs=["-ldl"]) for v in (2, 3)}


def _vr(description, name: str) -> int:
    return next(v.valueReference for v in description.modelVariables if v.name == name)


def _schedule(n: int, dt: float = 1e-3):
    """(dt, normal_force, grip_velocity): a pressure ramp 5 -> 15 MPa on the 35 mm pad, the grip speeding up
    over 10 ms and reversing for the last quarter."""
    rows = []
    for k in range(n):
        t, frac = (k + 0.5) * dt, k / max(1, n - 1)
        v = 0.08 * min(1.0, t / 0.01) * (1.0 if frac < 0.75 else -1.0)
        rows.append((dt, (5e6 + 10e6 * frac) * 0.035 * 0.035, v))
    return rows


def _slave(unzipped, md, name: str, messages: list, instance: str = "x"):
    """An instantiated FMU3Slave whose log goes to ``messages`` as (status, text)."""
    from fmpy.fmi3 import FMU3Slave

    def log(env, status, category, message):
        messages.append((int(status), message.decode()))

    s = FMU3Slave(guid=md.guid, unzipDirectory=str(unzipped), modelIdentifier=name, instanceName=instance)
    s.instantiate(logMessage=log)
    return s


def _run_host(host, folder, description, tmp_path, steps, *, inputs=(), outputs=(), sets=(), extra=()):
    """Run a C host; returns its stdout rows (t, outputs..., arrays...) as an array of floats, and the process."""
    vr = {v.name: v for v in description.modelVariables}
    kind = {"Real": "r", "Float64": "r", "Integer": "i", "Int32": "i", "String": "s", "UInt64": "u"}
    args = []
    for name, value in sets:
        args += ["--set", f"{kind[vr[name].type]}:{vr[name].valueReference}={value}"]
    if inputs:
        args += ["--inputs", ",".join(str(vr[n].valueReference) for n in inputs)]
    args += ["--outputs", ",".join(f"{kind[vr[n].type]}:{vr[n].valueReference}" for n in outputs)]
    steps_file = tmp_path / "steps.txt"
    steps_file.write_text("\n".join(",".join(repr(float(x)) for x in row) for row in steps) + "\n")
    cmd = [str(host), str(folder), description.coSimulation.modelIdentifier, description.guid, *args,
           "--steps", str(steps_file), *extra]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env={"PATH": "/usr/bin:/bin"},
                          cwd=tmp_path)
    assert proc.returncode == 0, f"exit {proc.returncode}\n{proc.stderr[-3000:]}"
    return np.array([[float(x) for x in line.split(",")] for line in proc.stdout.split()]), proc


# ----------------------------------------------------------------------------------- the FMUs as files
def test_cli_builds_fmi3_fmus_exporting_every_function(tmp_path, hosts):
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    proc = subprocess.run([sys.executable, "-m", "tribocosim.cli", "fmu", "build", "--fmi", "3", "--only", "Press",
                           "--platform", "linux64", "--out", str(tmp_path)], capture_output=True, text=True,
                          timeout=900)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    fmu = tmp_path.resolve() / "Press.fmu"
    assert [Path(p) for p in proc.stdout.split()] == [fmu]
    assert validate_fmu(str(fmu)) == []
    assert read_model_description(str(fmu)).fmiVersion == "3.0"
    assert json.loads((tmp_path / "Press.fmu.json").read_text())["fmi_version"] == 3
    folder = tmp_path / "unzipped"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
        assert not [f for f in z.namelist() if f.endswith((".py", ".pyc"))]
    functions = _fmi3_functions()
    assert len(functions) == 75
    assert sorted(p.name for p in (folder / "binaries").iterdir()) == ["x86_64-linux"]
    exported = exported_functions(folder / "binaries" / "x86_64-linux" / "Press.so")
    assert functions <= exported, sorted(functions - exported)
    assert not [f for f in exported if f.startswith(("tc_", "fmi2"))], "internal and FMI 2.0 functions stay out"
    symbols = subprocess.run([str(hosts[3]), str(folder), "Press", "x", "--symbols"], capture_output=True, text=True)
    assert symbols.stdout.strip() == "75 functions exported", symbols.stderr


def test_model_descriptions_have_the_fmi2_variables_plus_time_and_the_nodal_arrays(built, md):
    from fmpy.validation import validate_fmu

    types = {"Real": "Float64", "Integer": "Int32", "String": "String"}
    num = lambda x: None if x is None else float(x)  # noqa: E731
    for name in NAMES:
        assert validate_fmu(str(built[3][name])) == [], name
        two, three = md[2, name], md[3, name]
        by_vr = {v.valueReference: v for v in three.modelVariables}
        assert three.fmiVersion == "3.0" and three.guid != two.guid
        assert three.coSimulation.canGetAndSetFMUstate and three.coSimulation.canSerializeFMUstate
        for a in two.modelVariables:
            b = by_vr[a.valueReference]
            assert (b.name, b.type, b.unit, b.description, b.variability) == \
                   (a.name, types[a.type], a.unit, a.description, a.variability), a.name
            assert b.causality == ("structuralParameter" if a.name == "n_elements" else a.causality), a.name
            assert (num(b.min), num(b.max)) == (num(a.min), num(a.max)), a.name
            start = (lambda x: x) if a.type == "String" else float
            assert (a.start is None) == (b.start is None) and (a.start is None or start(a.start) == start(b.start))
        extra = [v for v in three.modelVariables if v.valueReference >= len(two.modelVariables)]
        assert extra[0].name == "time" and extra[0].causality == "independent" and extra[0].unit == "s"
        if name != "StripDraw":
            assert len(extra) == 1
            continue
        size, *arrays = extra[1:]
        assert (size.name, size.type, size.causality, int(size.start)) == ("n_nodes", "UInt64", "structuralParameter",
                                                                          _default_nodes())
        assert [(v.name, v.unit, v.shape, v.dimensions[0].valueReference) for v in arrays] == \
               [(f, u, (_default_nodes(),), size.valueReference) for f, u in zip(FIELDS, ("1", "m", "1"))]
        assert {u.variable.name for u in three.outputs} >= set(FIELDS)


# ----------------------------------------------------------------------------------- FMI 3 == FMI 2
def test_stripdraw_through_fmpy_equals_the_fmi2_fmu_and_its_field_output_to_the_bit(unzipped, md, tmp_path):
    """n_nodes = 101 set in Configuration Mode (FMI 3) against n_elements = 100 (FMI 2, with field_output every
    step); the arrays are the field file's rows, and close to the Python model's fields."""
    from fmpy.fmi2 import FMU2Slave

    from tribocosim.components.stripdraw.component import COMPONENT
    from tribocosim.components.native.resource_io.field_file import read_fields

    schedule = _schedule(60)
    m2, m3 = md[2, "StripDraw"], md[3, "StripDraw"]
    v2 = {v.name: v.valueReference for v in m2.modelVariables}
    v3 = {v.name: v.valueReference for v in m3.modelVariables}
    field = tmp_path / "fields.npz"
    two = FMU2Slave(guid=m2.guid, unzipDirectory=str(unzipped[2, "StripDraw"]), modelIdentifier="StripDraw",
                    instanceName="two")
    two.instantiate()
    two.setupExperiment(startTime=0.0)
    two.enterInitializationMode()
    two.setInteger([v2["n_elements"]], [100])
    two.setString([v2["field_output"]], [str(field)])
    two.exitInitializationMode()
    messages = []
    three = _slave(unzipped[3, "StripDraw"], m3, "StripDraw", messages)
    three.enterConfigurationMode()
    three.setUInt64([v3["n_nodes"]], [101])
    three.exitConfigurationMode()
    three.enterInitializationMode(startTime=0.0)
    three.exitInitializationMode()
    assert three.getInt32([v3["n_elements"]]) == [100] and three.getUInt64([v3["n_nodes"]]) == [101]
    rows2, rows3, arrays, t = [], [], [], 0.0
    for dt, f, v in schedule:
        two.setReal([v2["normal_force"], v2["grip_velocity"]], [f, v])
        two.doStep(t, dt)
        three.setFloat64([v3["normal_force"], v3["grip_velocity"]], [f, v])
        event, terminate, early, last = three.doStep(t, dt)
        t += dt
        assert (event, terminate, early, last) == (False, False, False, t)
        rows2.append(two.getReal([v2[n] for n in STRIP_OUTPUTS]) + two.getInteger([v2["table_clamp_count"]]))
        rows3.append(three.getFloat64([v3[n] for n in STRIP_OUTPUTS]) + three.getInt32([v3["table_clamp_count"]]))
        arrays.append(three.getFloat64([v3[n] for n in FIELDS], nValues=3 * 101))
    assert three.getFloat64([v3["time"]]) == [t]
    two.terminate()
    two.freeInstance()
    three.terminate()
    three.freeInstance()
    assert_array_equal(np.array(rows3), np.array(rows2))
    assert np.array(rows3)[:, 0].max() > 0, "the strip must be pulled"
    recorded = read_fields(field)
    arrays = np.array(arrays).reshape(len(schedule), 3, 101)
    for k, name in enumerate(FIELDS):
        assert_array_equal(arrays[:, k], recorded[name][1:], err_msg=name)  # row 0: the initial state
    model = COMPONENT.make({"n_elements": 100}).model
    with pytest.warns(RangeWarning, match=r"grip_velocity = -\S+ m/s is below 0 m/s"):  # the schedule reverses
        for dt, f, v in schedule:
            model.step(dt, {"normal_force": f, "grip_velocity": v})
    python = model.fields()
    for k, name in enumerate(FIELDS):
        scale = max(np.abs(python[name]).max(), 1e-300)
        assert_allclose(arrays[-1, k], python[name], rtol=0, atol=1e-9 * scale, err_msg=name)


def test_c_hosts_give_the_same_outputs_to_the_bit_and_replay_a_serialized_state(hosts, unzipped, md, tmp_path):
    """Both hosts on StripDraw (default mesh), Press and DrawingMachine; the FMI 3 host also prints the arrays,
    replays from a state serialized after step 40 in a second instance, and fuzzes the FMU."""
    rng = np.random.default_rng(5)
    dts = rng.uniform(2e-4, 3e-3, 150)
    cases = [("StripDraw", _schedule(80), ("normal_force", "grip_velocity"), (*STRIP_OUTPUTS, "table_clamp_count")),
             ("Press", [(dt,) for dt in dts], (), ("normal_force", "force_reference")),
             ("DrawingMachine", list(zip(dts, rng.uniform(0, 4000, dts.size))), ("pull_force",),
              ("grip_velocity", "grip_position", "velocity_reference", "motor_force"))]
    for name, steps, inputs, outputs in cases:
        sets = [("setpoint_table", "0 0; 0.05 12250; 0.2 20000")] if name == "Press" else []
        field = tmp_path / f"{name}.npz"
        got2, _ = _run_host(hosts[2], unzipped[2, name], md[2, name], tmp_path, steps, inputs=inputs, outputs=outputs,
                            sets=sets + ([("field_output", str(field))] if name == "StripDraw" else []))
        extra = ["--replay", "40", "--fuzz", "1500", "3"]
        if name == "StripDraw":
            v3 = {v.name: v.valueReference for v in md[3, name].modelVariables}
            extra += ["--arrays", f"{v3['n_nodes']}:" + ",".join(str(v3[f]) for f in FIELDS)]
        got3, proc = _run_host(hosts[3], unzipped[3, name], md[3, name], tmp_path, steps, inputs=inputs,
                               outputs=outputs, sets=sets, extra=extra)
        assert_array_equal(got3[:, :1 + len(outputs)], got2, err_msg=name)
        assert "replay from step 40 bit-identical" in proc.stderr, proc.stderr[-2000:]
        fuzz = [line for line in proc.stderr.splitlines() if "fuzz:" in line][-1]
        taken, discarded = map(int, re.search(r"(\d+) steps taken, (\d+) discarded", fuzz).groups())
        assert taken > 0 and discarded > 0, fuzz
        if name == "StripDraw":
            from tribocosim.components.native.resource_io.field_file import read_fields

            recorded = read_fields(field)
            arrays = got3[:, 1 + len(outputs):].reshape(len(steps), 3, _default_nodes())
            for k, f in enumerate(FIELDS):
                assert_array_equal(arrays[:, k], recorded[f][1:], err_msg=f)


def test_simulate_fmu_runs_the_fmi3_fmu_as_the_fmi2_one(built):
    """fmpy's high-level driver: start values in the instantiated state (n_nodes there too), arrays recorded (fmpy
    sizes them from the model description's start of n_nodes: the default mesh)."""
    from fmpy import simulate_fmu

    def run(version, **kwargs):
        return simulate_fmu(str(built[version]["StripDraw"]), stop_time=0.02, output_interval=1e-3, **kwargs)

    two = run(2, start_values={"n_elements": 40}, output=["pull_force", "beta_max"])
    three = run(3, start_values={"n_nodes": 41}, output=["pull_force", "beta_max"])
    for name in ("pull_force", "beta_max"):
        assert_array_equal(three[name], two[name], err_msg=name)
    two, three = run(2, output=["pull_force", "beta_max"]), run(3, output=["pull_force", "beta"])
    assert_array_equal(three["pull_force"], two["pull_force"])
    assert three["beta"].shape == (len(two), _default_nodes())
    assert_array_equal(three["beta"].max(axis=1)[1:], two["beta_max"][1:])
    press = [simulate_fmu(str(built[v]["Press"]), stop_time=0.3, output_interval=2e-3, output=["normal_force"])
             for v in (2, 3)]
    assert_array_equal(press[1]["normal_force"], press[0]["normal_force"])


# ----------------------------------------------------------------------------------- state, errors
def test_fmu_state_get_set_and_serialize_replay_bit_identically(unzipped, md):
    from fmpy.fmi1 import FMICallException

    m3 = md[3, "StripDraw"]
    vr = {v.name: v.valueReference for v in m3.modelVariables}
    schedule = _schedule(50)

    def make(instance):
        s = _slave(unzipped[3, "StripDraw"], m3, "StripDraw", [], instance)
        s.setInt32([vr["n_elements"]], [80])
        s.setString([vr["friction_model"]], ["closed_form"])
        s.enterInitializationMode(startTime=0.0)
        s.exitInitializationMode()
        return s

    def run(s, rows, t):
        out = []
        for dt, f, v in rows:
            s.setFloat64([vr["normal_force"], vr["grip_velocity"]], [f, v])
            s.doStep(t, dt)
            t += dt
            out.append(s.getFloat64([vr[n] for n in (*STRIP_OUTPUTS, *FIELDS)], nValues=len(STRIP_OUTPUTS) + 3 * 81))
        return np.array(out)

    a, b = make("a"), make("b")
    run(a, schedule[:20], 0.0)
    t = sum(dt for dt, _, _ in schedule[:20])
    state = a.getFMUState()
    blob = a.serializeFMUState(state)
    first = run(a, schedule[20:], t)
    a.setFMUState(state)  # back in the same instance
    again = run(a, schedule[20:], t)
    b.setFMUState(b.deserializeFMUState(blob))  # into another instance
    other = run(b, schedule[20:], t)
    assert_array_equal(again, first)
    assert_array_equal(other, first)
    a.freeFMUState(state)
    for bad in (blob[:-1], blob + b"\0", b"garbage", b""):  # never a crash
        with pytest.raises(FMICallException) as exc:
            b.deserializeFMUState(bad)
        assert exc.value.status == 3
    for s in (a, b):
        s.terminate()
        s.freeInstance()


BAD_PARAMETERS = [
    ("StripDraw", {"tool_length": -1.0}, "tool_length = -1 m is out of range; allowed: [0.0001, 1] m"),
    ("StripDraw", {"friction_model": "tabel"}, "friction_model = 'tabel' is not allowed; choose one of table, "
                                               "closed_form, constant"),
    ("StripDraw", {"n_nodes": 3}, "n_nodes = 3 is out of range; allowed: [5, 200001] (n_elements + 1)"),
    ("StripDraw", {"n_nodes": 0}, "n_nodes = 0 is out of range; allowed: [5, 200001] (n_elements + 1)"),
    ("StripDraw", {"n_elements": 60, "n_nodes": 100}, "n_nodes = 100 and n_elements = 60 were both set and "
                                                      "disagree; n_nodes must be n_elements + 1"),
    ("StripDraw", {"n_nodes": 100, "n_elements": 60}, "n_nodes = 100 and n_elements = 60 were both set and disagree"),
    ("Press", {"setpoint_table": "0 0; 0.1"}, "setpoint_table = '0 0; 0.1' is malformed"),
    ("DrawingMachine", {"screw_lead": 0.0}, "screw_lead = 0 m is out of range"),
]


@pytest.mark.parametrize("name, parameters, message", BAD_PARAMETERS)
def test_a_bad_parameter_is_fmi3_error_at_initialization_naming_it(unzipped, md, name, parameters, message):
    from fmpy.fmi1 import FMICallException

    messages = []
    description = md[3, name]
    s = _slave(unzipped[3, name], description, name, messages)
    variables = {v.name: v for v in description.modelVariables}
    for key, value in parameters.items():
        v = variables[key]
        getattr(s, f"set{v.type}")([v.valueReference], [value])
    s.enterInitializationMode(startTime=0.0)
    with pytest.raises(FMICallException) as exc:
        s.exitInitializationMode()
    assert exc.value.status == 3, "fmi3Error"
    assert any(status == 3 and message in text for status, text in messages), messages
    with pytest.raises(FMICallException):
        s.doStep(0.0, 1e-3)
    s.freeInstance()


def _initialized(unzipped, md, name: str, parameters: dict, messages: list):
    """An FMU3Slave with ``parameters`` set (in their order) and initialization left: the slave, or the
    FMICallException of fmi3ExitInitializationMode."""
    from fmpy.fmi1 import FMICallException

    s = _slave(unzipped[3, name], md[3, name], name, messages)
    variables = {v.name: v for v in md[3, name].modelVariables}
    for key, value in parameters.items():
        v = variables[key]
        getattr(s, f"set{v.type}")([v.valueReference], [value])
    s.enterInitializationMode(startTime=0.0)
    try:
        s.exitInitializationMode()
    except FMICallException as exc:
        s.freeInstance()
        return exc
    return s


@pytest.mark.parametrize("name", NAMES)
def test_every_parameter_is_accepted_at_its_declared_min_and_at_its_max(unzipped, md, name):
    """FMI 3.0 section 2.4.7 (Float64, Int32, UInt64 attributes): min <= value <= max. Each parameter alone at
    each declared bound, n_nodes too, initializes without a message above OK. (The bounds are read from the XML:
    fmpy 0.3 does not read them for UInt64.)"""
    import xml.etree.ElementTree as ET

    root = ET.parse(unzipped[3, name] / "modelDescription.xml").getroot()
    checked = []
    for v in root.find("ModelVariables"):
        if v.get("causality") not in ("parameter", "structuralParameter") or v.tag == "String":
            continue
        for bound in (v.get("min"), v.get("max")):
            if bound is None:
                continue
            value = float(bound) if v.tag == "Float64" else int(bound)
            messages = []
            s = _initialized(unzipped, md, name, {v.get("name"): value}, messages)
            assert not isinstance(s, Exception), (v.get("name"), value, messages)
            assert not [m for m in messages if m[0] >= 2], (v.get("name"), value, messages)
            s.freeInstance()
            checked.append(v.get("name"))
    assert len(checked) >= 10 and (name != "StripDraw" or {"n_nodes", "n_elements"} <= set(checked)), checked


def test_n_nodes_and_n_elements_set_together_must_agree(unzipped, md):
    """Setting either structural parameter sets both; set both, they must agree (or initialization is fmi3Error
    naming both, see BAD_PARAMETERS); n_nodes is checked against its own range [5, 200001]."""
    vr = {v.name: v.valueReference for v in md[3, "StripDraw"].modelVariables}
    for parameters in ({"n_elements": 60, "n_nodes": 61}, {"n_nodes": 61, "n_elements": 60}, {"n_nodes": 61},
                       {"n_elements": 60}):
        messages = []
        s = _initialized(unzipped, md, "StripDraw", parameters, messages)
        assert not isinstance(s, Exception), (parameters, messages)
        assert s.getUInt64([vr["n_nodes"]]) == [61] and s.getInt32([vr["n_elements"]]) == [60]
        assert len(s.getFloat64([vr["beta"]], nValues=61)) == 61
        s.freeInstance()


def test_model_structure_declares_no_output_dependencies_and_every_output_calculated(md):
    """FMI 3.0 section 2.4.8: an Output without dependencies depends on every input; dependencies="" on none.
    No output has direct feedthrough (tests/native/test_native_fmus.py measures it on the same core); outputs
    are the model's values after initialization (initial = calculated, InitialUnknown); the strip's
    contact_pressure there depends on the normal force set during initialization."""
    for name in NAMES:
        m = md[3, name]
        outputs = [v for v in m.modelVariables if v.causality == "output"]
        assert [(u.variable.name, u.dependencies) for u in m.outputs] == [(v.name, []) for v in outputs]
        initial = {"contact_pressure": ["normal_force"]} if name == "StripDraw" else {}  # at initialization only
        assert [(u.variable.name, [d.name for d in u.dependencies]) for u in m.initialUnknowns] == \
            [(v.name, initial.get(v.name, [])) for v in outputs]
        assert all(v.initial == "calculated" and v.start is None for v in outputs), name


def test_a_step_no_step_size_can_complete_sets_terminate_simulation(unzipped, md):
    """FMI 3.0 section 4.2.1 (fmi3DoStep): terminateSimulation = fmi3True, "the FMU requests to stop the
    simulation". A negative normal force is refused at any step size: fmi3Error with terminateSimulation true and
    lastSuccessfulTime the step's start, and the messages name FMI 3.0's flag; a zero step (the host's to fix) is
    fmi3Discard with it false, and the same zero step again asks to end. A state taken before restores the
    instance."""
    import ctypes

    m3 = md[3, "StripDraw"]
    vr = {v.name: v.valueReference for v in m3.modelVariables}
    messages = []
    s = _initialized(unzipped, md, "StripDraw", {"n_elements": 40}, messages)
    lib = ctypes.CDLL(str(unzipped[3, "StripDraw"] / "binaries" / "x86_64-linux" / "StripDraw.so"))
    do_step = lib.fmi3DoStep
    do_step.restype = ctypes.c_int
    flags = [ctypes.c_bool(), ctypes.c_bool(), ctypes.c_bool()]
    last = ctypes.c_double()

    def step(t, dt):
        status = do_step(ctypes.c_void_p(s.component), ctypes.c_double(t), ctypes.c_double(dt), ctypes.c_bool(True),
                         *(ctypes.byref(f) for f in flags), ctypes.byref(last))
        return status, [f.value for f in flags], last.value

    assert step(0.0, 1e-3) == (0, [False, False, False], 1e-3)
    assert step(1e-3, 0.0) == (2, [False, False, False], 1e-3), "a zero step: not the inputs' fault"
    assert step(1e-3, 0.0) == (2, [False, True, False], 1e-3), "the same discarded step again: it asks to end"
    assert any("repeats a step this FMU discarded, unchanged" in m and "(terminateSimulation)" in m
               for _, m in messages), messages
    state = s.getFMUState()
    s.setFloat64([vr["normal_force"]], [-5.0])
    assert step(1e-3, 1e-3) == (3, [False, True, False], 1e-3), "no step size helps: fmi3Error"
    assert any(st == 3 and "normal_force = -5 N" in m and "the inputs are at fault" in m for st, m in messages)
    assert all("fmi2" not in m for _, m in messages), "an FMI 3.0 FMU names FMI 3.0's flags"
    s.setFMUState(state)
    s.setFloat64([vr["normal_force"]], [12250.0])
    assert step(1e-3, 1e-3) == (0, [False, False, False], 2e-3)
    s.freeFMUState(state)
    s.terminate()
    s.freeInstance()


def test_mu_below_the_documented_floor_is_one_fmi3_warning_at_the_step_its_arrays_show_it(unzipped, md):
    """The paper's model (flake_shear_ratio = 0) with the closed-form law: mu = mu0 (1 - s b beta h'_rms / kappa)
    (Eq. 9, alpha = b) falls below the floor 0.03 where beta > 0.8 kappa / (s b h'_rms) = 0.0226. The step after
    which the arrays beta and contact first hold a node under the pad (contact > 0) with that much debris returns
    fmi3Warning with a message naming flake_shear_ratio = 0 and the time; every other step fmi3OK."""
    import ctypes

    from tribocosim.components.stripdraw.friction_floor import MU_FLOOR
    from tribocosim.components.stripdraw.parameters import StripDrawParameters

    m3 = md[3, "StripDraw"]
    vr = {v.name: v.valueReference for v in m3.modelVariables}
    messages = []
    s = _initialized(unzipped, md, "StripDraw", {"friction_model": "closed_form", "flake_shear_ratio": 0.0}, messages)
    lib = ctypes.CDLL(str(unzipped[3, "StripDraw"] / "binaries" / "x86_64-linux" / "StripDraw.so"))
    do_step = lib.fmi3DoStep
    do_step.restype = ctypes.c_int
    flags = [ctypes.c_bool(), ctypes.c_bool(), ctypes.c_bool()]
    last = ctypes.c_double()
    p = StripDrawParameters(flake_shear_ratio=0.0)
    n = _default_nodes()
    statuses, below, times, t = [], [], [], 0.0
    for _ in range(300):
        statuses.append(do_step(ctypes.c_void_p(s.component), ctypes.c_double(t), ctypes.c_double(1e-3),
                                ctypes.c_bool(True), *(ctypes.byref(f) for f in flags), ctypes.byref(last)))
        t += 1e-3
        times.append(t)
        beta, contact = np.array(s.getFloat64([vr["beta"], vr["contact"]], nValues=2 * n)).reshape(2, n)
        mu = p.mu0 * (1 - p.particle_area_scale * p.alpha_b * beta[contact > 0] * p.rms_slope / p.kappa)
        below.append(bool(mu.size) and mu.min() < MU_FLOOR * (1 - 1e-9))
    first = below.index(True)
    assert 50 < first < 250 and all(below[first:]), first
    assert [k for k, st in enumerate(statuses) if st != 0] == [first] and statuses[first] == 1, statuses
    warned = [m for st, m in messages if st == 1]
    assert len(warned) == 1 and warned[0].startswith(f"at t = {times[first]!r} s mu = "), warned
    assert "flake_shear_ratio = 0 with mu0 = 0.15 lets mu fall to 0" in warned[0]
    s.terminate()
    s.freeInstance()


def test_outputs_read_in_initialization_mode_follow_the_inputs_set_there(unzipped, md):
    """contact_pressure is an InitialUnknown that depends on normal_force: read in Initialization Mode after
    normal_force is set, it is F_N / (L_T w_T) (it read 0); the nodal arrays are still computed from
    fmi3ExitInitializationMode on."""
    from fmpy.fmi1 import FMICallException

    m3 = md[3, "StripDraw"]
    vr = {v.name: v.valueReference for v in m3.modelVariables}
    messages = []
    s = _slave(unzipped[3, "StripDraw"], m3, "StripDraw", messages)
    s.enterInitializationMode(startTime=0.0)
    s.setFloat64([vr["normal_force"]], [24500.0])
    assert s.getFloat64([vr["contact_pressure"]]) == [24500.0 / 0.035**2]
    with pytest.raises(FMICallException):
        s.getFloat64([vr["beta"]], nValues=_default_nodes())
    s.exitInitializationMode()
    assert s.getFloat64([vr["contact_pressure"]]) == [24500.0 / 0.035**2]
    s.terminate()
    s.freeInstance()


def test_fmpy_simulate_fmu_of_the_fmi3_fmu_with_a_negative_normal_force_ends_with_an_error(built):
    from fmpy import simulate_fmu
    from fmpy.fmi1 import FMICallException

    with pytest.raises(FMICallException) as exc:
        simulate_fmu(str(built[3]["StripDraw"]), stop_time=0.01, step_size=1e-3, start_values={"normal_force": -5.0})
    assert exc.value.status == 3


def test_a_negative_normal_force_is_an_error_with_the_state_unchanged(unzipped, md):
    from fmpy.fmi1 import FMICallException

    m3 = md[3, "StripDraw"]
    vr = {v.name: v.valueReference for v in m3.modelVariables}
    watched = [vr[n] for n in (*STRIP_OUTPUTS, *FIELDS)]
    messages = []
    s = _slave(unzipped[3, "StripDraw"], m3, "StripDraw", messages)
    s.setInt32([vr["n_elements"]], [60])
    s.enterInitializationMode(startTime=0.0)
    s.exitInitializationMode()
    t = 0.0
    for dt, f, v in _schedule(15):
        s.setFloat64([vr["normal_force"], vr["grip_velocity"]], [f, v])
        s.doStep(t, dt)
        t += dt
    saved = s.getFMUState()
    image = s.serializeFMUState(saved)
    before = s.getFloat64(watched, nValues=len(watched) + 3 * 60)
    s.setFloat64([vr["normal_force"]], [-5.0])
    with pytest.raises(FMICallException) as exc:
        s.doStep(t, 1e-3)
    assert exc.value.status == 3, "fmi3Error: no step size can complete it"
    assert any(status == 3 and "normal_force = -5 N" in text and "the FMU state is unchanged" in text
               for status, text in messages), messages
    assert s.getFloat64(watched, nValues=len(watched) + 3 * 60) == before
    s.setFMUState(saved)  # the way back from fmi3Error
    assert s.serializeFMUState(s.getFMUState()) == image
    assert s.doStep(t, 1e-3)[3] == t + 1e-3, "usable again"
    s.terminate()
    s.freeInstance()


def test_what_does_not_apply_is_fmi3_error_naming_the_function(unzipped, md):
    from ctypes import byref, c_size_t

    from fmpy.fmi1 import FMICallException

    m3 = md[3, "StripDraw"]
    vr = {v.name: v.valueReference for v in m3.modelVariables}
    messages = []
    s = _slave(unzipped[3, "StripDraw"], m3, "StripDraw", messages)

    def refused(call, *words):
        messages.clear()
        with pytest.raises(FMICallException) as exc:
            call()
        assert exc.value.status == 3, exc.value
        assert any(all(w in text for w in words) for status, text in messages if status == 3), (words, messages)

    refused(lambda: s.getFloat64([vr["beta"]], nValues=_default_nodes()), "fmi3GetFloat64", "beta", "fmi3ExitInitializationMode")
    s.enterInitializationMode(startTime=0.0)
    refused(lambda: s.setUInt64([vr["n_nodes"]], [41]), "fmi3SetUInt64", "n_nodes", "structural parameter")
    refused(lambda: s.setInt32([vr["n_elements"]], [40]), "fmi3SetInt32", "n_elements", "structural parameter")
    s.exitInitializationMode()
    refused(lambda: s.fmi3EnterEventMode(s.component), "fmi3EnterEventMode", "hasEventMode")
    refused(lambda: s.fmi3EnterConfigurationMode(s.component), "fmi3EnterConfigurationMode", "Reconfiguration")
    refused(lambda: s.fmi3GetNumberOfContinuousStates(s.component, byref(c_size_t())),
            "fmi3GetNumberOfContinuousStates", "model exchange")
    refused(lambda: s.getDirectionalDerivative([vr["pull_force"]], [vr["normal_force"]], [1.0]),
            "fmi3GetDirectionalDerivative")
    refused(lambda: s.getBoolean([vr["pull_force"]]), "fmi3GetBoolean", "no Boolean variables")
    refused(lambda: s.getFloat64([vr["beta"]], nValues=3), "fmi3GetFloat64", "nValues = 3", f"{_default_nodes()} values")
    refused(lambda: s.setFloat64([vr["tool_length"]], [0.02]), "fmi3SetFloat64", "tool_length", "fixed")
    refused(lambda: s.setFloat64([vr["time"]], [1.0]), "fmi3SetFloat64", "time", "independent")
    refused(lambda: s.getFloat64([10_000]), "fmi3GetFloat64", "value reference 10000")
    assert s.getFloat64([vr["pull_force"]]) == [0.0], "still usable"
    s.terminate()
    s.freeInstance()


def test_nothing_leaks_valgrind(hosts, unzipped, md, tmp_path):
    if shutil.which("valgrind") is None:
        pytest.skip("valgrind is not installed")
    m3 = md[3, "StripDraw"]
    v3 = {v.name: v.valueReference for v in m3.modelVariables}
    _, proc = _run_host(hosts[3], unzipped[3, "StripDraw"], m3, tmp_path, _schedule(30),
                        inputs=("normal_force", "grip_velocity"), outputs=("pull_force", "table_clamp_count"),
                        sets=[("n_nodes", 61), ("field_output", str(tmp_path / "f.npz"))],
                        extra=["--arrays", f"{v3['n_nodes']}:{v3['beta']},{v3['U']}", "--replay", "10",
                               "--fuzz", "200", "5"])
    cmd = ["valgrind", "--leak-check=full", "--errors-for-leak-kinds=definite,indirect", "--error-exitcode=9",
           "--quiet", *proc.args]
    full = subprocess.run(cmd, capture_output=True, text=True, timeout=600, cwd=tmp_path)
    assert full.returncode == 0, full.stderr[-4000:]
