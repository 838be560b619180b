"""Tests of SSP 1.0 packages: export (cosim.ssp.export), import (cosim.ssp.reader), the TOML writer (cosim.ssp.names).

The rig is the demo scene (press + strip draw + drawing machine, component FMUs from the cache) cut to
400 steps of 1 ms, with a press force (9800 N), a pad width (30 mm) and a drive ramp (30 ms) that are
not the FMUs' defaults, so that a tool that dropped a parameter set would be seen. fmpy's
``simulate_ssp``, libcosim and ecos all step all FMUs from the outputs read right after the last doStep:
that is our Jacobi (no FMU of the rig has direct feedthrough, so ``output_update`` does not matter).
OMSimulator runs the package in tests/native/test_third_party_tools.py where an OMSimulator built from source is
named (its pip package downloads a binary when it is installed); here the package is checked against what its SSP
reader requires, from its source.
"""

import json
import math
import os
import subprocess
import sys
import textwrap
import tomllib
import zipfile
from pathlib import Path

import numpy as np
import pytest

from tribocosim.cli import main as tribocosim
from tribocosim.errors import SceneError
from tribocosim.cosim import run
from tribocosim.cosim.ssp.names import toml_text
from tribocosim.cosim.api import run_ssp
from tribocosim.cosim.ssp.reader import load_ssp

#: the short demo rig: scene keys set on models/scenes/demo.toml (the strip held for 0.1 s while the press closes, so
#: every host also runs the drive's start_time; a 1 ms step, stable at this load)
RIG = {"experiment.stop": 0.4, "experiment.step": 1e-3, "fmus.press.parameters.force_setpoint": 9800.0,
       "fmus.strip.parameters.tool_width": 0.03, "fmus.drive.parameters.ramp_time": 0.03,
       "fmus.drive.parameters.start_time": 0.1}
STEPS = 400


@pytest.fixture(scope="module")
def rig(tmp_path_factory) -> Path:
    """The rig exported by ``tribocosim ssp export``."""
    ssp = tmp_path_factory.mktemp("ssp") / "rig.ssp"
    assert tribocosim(["ssp", "export", "demo", "-o", str(ssp), *_sets(RIG)]) == 0
    return ssp


@pytest.fixture(scope="module")
def scene_run():
    """The rig run from its scene by our master (Jacobi, 1 ms)."""
    result = run("demo", overrides=RIG, write=False)
    assert len(result.time) == STEPS + 1 and result.metadata["master"]["algorithm"] == "jacobi"
    return result


def _sets(keys: dict) -> list[str]:
    return [x for k, v in keys.items() for x in ("--set", f"{k}={v!r}")]


def _schema(name: str):
    from lxml import etree
    import fmpy.ssp.ssd

    return etree.XMLSchema(file=str(Path(fmpy.ssp.ssd.__file__).parent / "schema" / name))


def _package(path: Path, ssd: str, files: dict[str, Path]) -> Path:
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("SystemStructure.ssd", ssd)
        for member, source in files.items():
            zf.write(source, member)
    return path


# ------------------------------------------------------------------ TOML writer
def test_toml_text_reads_back_as_the_same_document():
    doc = {
        "experiment": {"start": 0.0, "stop": 0.1 + 0.2, "step": 1e-300},
        "master": {"algorithm": "iterative", "iterative": {"relaxation": "aitken", "tolerance": 1e-8},
                   "adaptive": {"max_step": float("inf"), "min_step": -0.0}},
        "fmus": {"a b": {"path": 'C:\\dir\\"q".fmu', "parameters": {"x.y": 3, "flag": True, "s": "é\n\t\x7f\x01"}}},
        "connections": [{"from": "a.x", "to": "b.u"}, {"from": "b.y", "to": "a.u"}],
        "output": {"variables": ["a.x", "b.y"], "empty": [], "nested": [[1, 2], [3.5]]},
    }
    text = toml_text(doc)
    assert tomllib.loads(text) == doc, text
    assert math.copysign(1.0, tomllib.loads(text)["master"]["adaptive"]["min_step"]) == -1.0
    assert math.isnan(tomllib.loads(toml_text({"t": {"v": float("nan")}}))["t"]["v"])


# ------------------------------------------------------------------ export
def test_package_holds_the_rig_and_validates_against_the_ssp_schema(rig, tmp_path):
    import xml.etree.ElementTree as ET
    from lxml import etree

    with zipfile.ZipFile(rig) as zf:
        names = zf.namelist()
        assert names[0] == "SystemStructure.ssd"
        assert set(names[1:]) == {"resources/Press.fmu", "resources/StripDraw.fmu", "resources/DrawingMachine.fmu",
                                  "resources/press.ssv", "resources/strip.ssv", "resources/drive.ssv"}
        ssd_schema = _schema("SystemStructureDescription.xsd")
        ssv_schema = _schema("SystemStructureParameterValues.xsd")
        ssd_bytes = zf.read("SystemStructure.ssd")
        assert ssd_schema.validate(etree.fromstring(ssd_bytes)), ssd_schema.error_log
        for m in names:
            if m.endswith(".ssv"):
                assert ssv_schema.validate(etree.fromstring(zf.read(m))), (m, ssv_schema.error_log)
        press_ssv = zf.read("resources/press.ssv").decode()
    ns = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
          "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
          "osp": "http://opensimulationplatform.com/SSP/OSPAnnotations"}
    root = ET.fromstring(ssd_bytes)
    comps = root.findall("ssd:System/ssd:Elements/ssd:Component", ns)
    assert [(c.get("name"), c.get("source")) for c in comps] == [
        ("press", "resources/Press.fmu"), ("strip", "resources/StripDraw.fmu"), ("drive", "resources/DrawingMachine.fmu")]
    strip = comps[1]
    assert strip.find("ssd:Connectors/ssd:Connector[@name='pull_force']/ssc:Real", ns).get("unit") == "N"
    assert strip.find("ssd:Connectors/ssd:Connector[@name='grip_velocity']", ns).get("kind") == "input"
    assert strip.find("ssd:Connectors/ssd:Connector[@name='table_clamp_count']/ssc:Integer", ns) is not None
    newton = root.find("ssd:Units/ssc:Unit[@name='N']/ssc:BaseUnit", ns)
    assert (newton.get("kg"), newton.get("m"), newton.get("s")) == ("1", "1", "-2")
    conns = [(c.get("startElement"), c.get("startConnector"), c.get("endElement"), c.get("endConnector"))
             for c in root.findall("ssd:System/ssd:Connections/ssd:Connection", ns)]
    assert conns == [("press", "normal_force", "strip", "normal_force"),
                     ("drive", "grip_velocity", "strip", "grip_velocity"),
                     ("strip", "pull_force", "drive", "pull_force")]
    default = root.find("ssd:DefaultExperiment", ns)
    assert (default.get("startTime"), default.get("stopTime")) == ("0.0", "0.4")
    assert default.find(".//osp:FixedStepAlgorithm", ns).get("baseStepSize") == "0.001"
    assert 'name="force_setpoint"' in press_ssv and '<ssv:Real value="9800.0" unit="N" />' in press_ssv
    assert root.find("ssd:Annotations", ns) is None, "nothing but System, Units, Enumerations, DefaultExperiment on top"
    # the same scene gives the same bytes
    again = tmp_path / "again.ssp"
    assert tribocosim(["ssp", "export", "demo", "-o", str(again), *_sets(RIG)]) == 0
    assert again.read_bytes() == rig.read_bytes()


def test_export_of_a_scene_with_problems_exits_2(tmp_path, capsys):
    bad = tmp_path / "x.ssp"
    assert tribocosim(["ssp", "export", "demo", "-o", str(bad), "--set", "fmus.strip.parameters.nope=1.0"]) == 2
    assert "fmus.strip.parameters.nope" in capsys.readouterr().err
    assert not bad.exists()


def test_export_os_errors_name_the_path_given(tmp_path, capsys):
    """A folder in place of the package, a file in place of its folder, a folder that cannot hold files: one line
    naming the path given, not a temporary name; nothing left behind."""
    folder = tmp_path / "rigs"
    folder.mkdir()
    (tmp_path / "file").write_text("")
    cases = [(folder, f"cannot write the SSP package {folder}: it is a folder"),
             (tmp_path / "file" / "rig.ssp", f"cannot write the SSP package {tmp_path / 'file' / 'rig.ssp'}: "
                                            f"{tmp_path / 'file'} is a file")]
    if Path("/proc").is_dir():
        cases.append((Path("/proc/rig.ssp"), "cannot write the SSP package /proc/rig.ssp: "))
    for out, words in cases:
        assert tribocosim(["ssp", "export", "demo", "-o", str(out)]) == 1
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and words in err and ".rig-" not in err, err
    assert list(folder.iterdir()) == []


# ------------------------------------------------------------------ other tools
def test_fmpy_simulate_ssp_gives_our_jacobi_pull_force(rig, scene_run):
    from fmpy.ssp.simulation import simulate_ssp

    from tribocosim.cosim.ssp.names import fmpy_parameter_set

    # fmpy 0.3's simulate_ssp applies one parameter set of "component.variable" names, not the SSD's
    # bindings: fmpy_parameter_set gathers the components' bindings into one
    merged = fmpy_parameter_set(rig)
    assert len(merged.parameters) == 8 and "strip.tool_width" in {p.name for p in merged.parameters}
    res = simulate_ssp(str(rig), stop_time=0.4, step_size=1e-3, parameter_set=merged)
    ours = scene_run["strip.pull_force"][1:]  # fmpy's row k holds the outputs after the step from t_k
    got = res["strip.pull_force"][:STEPS]
    assert len(got) == STEPS
    diff = np.max(np.abs(got - ours))
    print(f"fmpy simulate_ssp vs tribocosim run (Jacobi, 1 ms, {STEPS} steps): max |d pull_force| = {diff!r} N "
          f"of max {np.max(np.abs(ours)):.6g} N")
    assert diff <= 1e-9 * np.max(np.abs(ours)), diff
    np.testing.assert_array_equal(res["press.force_reference"][-1], 9800.0, err_msg="the press's parameter set")


def test_libcosim_runs_the_package_with_its_step_and_parameters(rig, scene_run):
    pytest.importorskip("libcosimpy")
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.WARNING)
    ex = CosimExecution.from_ssp_file(str(rig))  # the step from the osp:FixedStepAlgorithm annotation
    strip, press = ex.slave_index_from_instance_name("strip"), ex.slave_index_from_instance_name("press")
    vr = {i: {v.name.decode(): v.reference for v in ex.slave_variables(i)} for i in (strip, press)}
    observer = CosimObserver.create_last_value()
    ex.add_observer(observer)
    rows = []
    for _ in range(STEPS):
        assert ex.step(1), f"libcosim step failed: {ex.status()}"
        rows.append([observer.last_real_values(strip, [vr[strip]["pull_force"]])[0],
                     observer.last_real_values(press, [vr[press]["force_reference"]])[0]])
    assert ex.status().current_time == 400_000_000, "400 steps of 1 ms (integer nanoseconds)"
    rows = np.array(rows)
    ours = scene_run["strip.pull_force"][1:]
    diff = np.max(np.abs(rows[:, 0] - ours))
    print(f"libcosim vs tribocosim run (Jacobi, 1 ms, {STEPS} steps): max |d pull_force| = {diff!r} N")
    assert diff <= 1e-9 * np.max(np.abs(ours)), diff
    assert rows[-1, 1] == 9800.0, "the press's parameter set"


_ECOS = textwrap.dedent("""
    import json, sys
    from ecospy import EcosLib, EcosSimulation

    EcosLib().set_log_level("warn")
    rig, name, steps = sys.argv[1], sys.argv[2], int(sys.argv[3])
    rows = []
    with EcosSimulation(ssp_path=rig, step_size=1e-3) as sim:
        sim.init(parameter_set=name)  # ecos applies the parameter sets of this one name, nothing else
        for _ in range(steps):
            sim.step(1)
            rows.append([sim.get_real("strip::pull_force"), sim.get_real("press::force_reference"),
                         sim.get_real("strip::tool_width")])
        sim.terminate()
    print(json.dumps(rows))
""")


def _tbb_library_dirs() -> list[str]:
    """The folders of the tbb package's libtbb.so.* (ecospy's library needs them on LD_LIBRARY_PATH)."""
    from importlib.metadata import files

    return sorted({str(Path(f.locate()).resolve().parent) for f in files("tbb") or () if f.name.startswith("libtbb.so")})


def test_ecos_runs_the_package_with_one_named_parameter_set(rig, scene_run, tmp_path):
    """ecos (ecospy) applies the parameter sets of the one name given to init; every .ssv of the package is
    called after the system, so that one name sets all of them (a rig run on FMU defaults would differ:
    12250 N press force, 35 mm pad)."""
    libs = _tbb_library_dirs()
    assert libs, "the tbb package (ecospy's libtbb.so.12) is part of the test extra"
    script = tmp_path / "run_ecos.py"
    script.write_text(_ECOS)
    env = {**os.environ, "LD_LIBRARY_PATH": os.pathsep.join([*libs, os.environ.get("LD_LIBRARY_PATH", "")])}
    proc = subprocess.run([sys.executable, str(script), str(rig), "demo", str(STEPS)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, f"ecos failed (exit {proc.returncode}):\n{proc.stdout}\n{proc.stderr}"
    rows = np.array(json.loads(proc.stdout.strip().splitlines()[-1]))
    ours = scene_run["strip.pull_force"][1:]
    diff = np.max(np.abs(rows[:, 0] - ours))
    print(f"ecos vs tribocosim run (Jacobi, 1 ms, {STEPS} steps): max |d pull_force| = {diff!r} N "
          f"of max {np.max(np.abs(ours)):.6g} N")
    assert rows[-1, 1] == 9800.0 and rows[-1, 2] == 0.03, "the press's and the strip's parameter sets"
    assert diff <= 1e-9 * np.max(np.abs(ours)), diff


def test_the_package_is_what_omsimulator_s_ssp_reader_requires(rig):
    """OMSimulator (OpenModelica/OMSimulator, src/OMSimulatorLib) reads the SSD with pugixml, by prefixed names:

    - Model::importFromSnapshot takes only ssd:System, ssd:Units, ssd:Enumerations and ssd:DefaultExperiment at
      the top ("wrong xml schema detected" for anything else, e.g. an ssd:Annotations);
    - Model::getSystemType makes the system from the first ssc:Annotation of the system's ssd:Annotations, of
      type org.openmodelica, holding oms:Annotations/oms:SimulationInformation with an oms:FixedStepMaster (or
      oms:VariableStepMaster) that has a description: without it the type is oms_system_none and
      System::NewSystem fails ("[NewSystem] internal error");
    - SystemWC::setSolverMethod accepts the descriptions oms-ma, oms-mav and oms-mav2; importFromSSD_
      SimulationInformation reads the fixed step from stepSize;
    - System::importFromSnapshot takes ssd:ElementGeometry, ssd:ParameterBindings, ssd:Connections,
      ssd:Connectors, ssd:Elements (ssd:Component, ssd:System) and ssd:Annotations, nothing else."""
    import xml.etree.ElementTree as ET

    from tribocosim.cosim.ssp.names import NS, prefixed

    with zipfile.ZipFile(rig) as zf:
        root = ET.fromstring(zf.read("SystemStructure.ssd"))
    assert {prefixed(c.tag) for c in root} <= {"ssd:System", "ssd:Units", "ssd:Enumerations", "ssd:DefaultExperiment"}
    assert root.get("version") == "1.0"
    system = root.find("ssd:System", NS)
    assert {prefixed(c.tag) for c in system} <= {"ssd:ElementGeometry", "ssd:ParameterBindings", "ssd:Connections",
                                                 "ssd:Connectors", "ssd:Elements", "ssd:Annotations"}
    first = system.find("ssd:Annotations/ssc:Annotation", NS)
    assert first is not None and first.get("type") == "org.openmodelica", "OMSimulator reads the first one only"
    master = first.find("oms:Annotations/oms:SimulationInformation/oms:FixedStepMaster", NS)
    assert master is not None and master.get("description") == "oms-ma"
    assert float(master.get("stepSize")) == 1e-3
    assert all(prefixed(e.tag) == "ssd:Component" and e.get("type") == "application/x-fmu-sharedlibrary"
               for e in system.find("ssd:Elements", NS))
    # the prefixes are the ones OMSimulator compares literally
    text = zipfile.ZipFile(rig).read("SystemStructure.ssd").decode()
    assert "<oms:FixedStepMaster " in text and "<ssd:System " in text and "<ssc:Annotation " in text


# ------------------------------------------------------------------ import
def test_tribocosim_run_of_the_package_is_bit_identical_to_the_scene_run(rig, tmp_path, capsys):
    scene = run("demo", tmp_path / "scene", overrides=RIG)
    assert tribocosim(["run", str(rig), "--out", str(tmp_path / "ssp")]) == 0
    assert f"scene:    {rig}" in capsys.readouterr().out
    csv = tmp_path / "ssp" / "demo.csv"
    assert csv.read_bytes() == scene.csv_path.read_bytes(), "every recorded column, to the last bit"
    meta = json.loads(csv.with_suffix(".json").read_text())
    assert meta["scene"] == str(rig) and meta["steps"]["accepted"] == STEPS
    assert meta["master"] == scene.metadata["master"]
    assert "[fmus.strip]" in meta["ssp"]["scene_toml"] and "force_setpoint = 9800.0" in meta["ssp"]["scene_toml"]


def test_set_overrides_the_master_and_experiment_of_a_package(rig, tmp_path):
    assert tribocosim(["run", str(rig), "--out", str(tmp_path), "--quiet", "--set", 'master.algorithm="gauss-seidel"',
                       "--set", "experiment.stop=0.1"]) == 0
    meta = json.loads((tmp_path / "demo.json").read_text())
    assert meta["master"]["algorithm"] == "gauss-seidel" and meta["steps"]["accepted"] == 100


FOREIGN = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription version="1.0" name="foreign"
    xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
    xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues">
  <ssd:System name="top">
    <ssd:ParameterBindings>
      <ssd:ParameterBinding prefix="press.">
        <ssd:ParameterValues>
          <ssv:ParameterSet version="1.0" name="system">
            <ssv:Parameters>
              <ssv:Parameter name="force_setpoint"><ssv:Real value="5000" unit="N"/></ssv:Parameter>
              <ssv:Parameter name="no_such"><ssv:Real value="1"/></ssv:Parameter>
            </ssv:Parameters>
          </ssv:ParameterSet>
        </ssd:ParameterValues>
      </ssd:ParameterBinding>
    </ssd:ParameterBindings>
    <ssd:Elements>
      <ssd:Component name="press" source="resources/P%20ress.fmu">
        <ssd:Connectors>
          <ssd:Connector name="force_reference" kind="output"><ssc:Real unit="N"/></ssd:Connector>
          <ssd:Connector name="normal_force" kind="output"/>
        </ssd:Connectors>
        <ssd:ParameterBindings>
          <ssd:ParameterBinding>
            <ssd:ParameterValues>
              <ssv:ParameterSet version="1.0" name="component">
                <ssv:Parameters>
                  <ssv:Parameter name="force_setpoint"><ssv:Real value="7000"/></ssv:Parameter>
                  <ssv:Parameter name="ramp_time"><ssv:Real value="0.01"/></ssv:Parameter>
                </ssv:Parameters>
              </ssv:ParameterSet>
            </ssd:ParameterValues>
          </ssd:ParameterBinding>
        </ssd:ParameterBindings>
        <ssd:ElementGeometry x1="0" y1="0" x2="1" y2="1"/>
      </ssd:Component>
      <ssd:Component name="strip" source="./resources/StripDraw.fmu">
        <ssd:Connectors>
          <ssd:Connector name="normal_force" kind="input"><ssc:Real unit="N"/></ssd:Connector>
          <ssd:Connector name="pull_force" kind="output"><ssc:Real/></ssd:Connector>
        </ssd:Connectors>
      </ssd:Component>
    </ssd:Elements>
    <ssd:Connections>
      <ssd:Connection startElement="strip" startConnector="normal_force" endElement="press" endConnector="normal_force"/>
    </ssd:Connections>
  </ssd:System>
  <ssd:DefaultExperiment startTime="0" stopTime="0.05"/>
</ssd:SystemStructureDescription>
"""


def test_a_foreign_package_runs_with_bindings_and_default_outputs(tmp_path):
    from tribocosim.cosim.scene.fmucache import component_fmu

    ssp = _package(tmp_path / "foreign.ssp", FOREIGN, {"resources/P ress.fmu": component_fmu("press"),
                                                       "resources/StripDraw.fmu": component_fmu("stripdraw")})
    with pytest.raises(SceneError, match=r"ssd:DefaultExperiment: no step size .*--set experiment\.step"):
        load_ssp(ssp)
    plan = load_ssp(ssp, {"experiment.step": 0.01})
    (link,) = plan.links  # start/end given against the data flow
    assert (str(link.source), str(link.target)) == ("press.normal_force", "strip.normal_force")
    assert plan.scene.fmus["press"].parameters == {"force_setpoint": 5000.0, "ramp_time": 0.01}, \
        "the system's binding wins over the component's"
    result = run_ssp(ssp, overrides={"experiment.step": 0.01}, write=False)
    assert list(result.columns) == ["press.force_reference", "press.normal_force", "strip.pull_force"], \
        "without our annotation every output connector is recorded"
    assert len(result.time) == 6 and result["press.force_reference"][-1] == 5000.0
    assert "# ignored (no such variable): press.no_such" in result.metadata["ssp"]["scene_toml"]


UNSUPPORTED = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription version="1.0" name="unsupported"
    xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
    xmlns:ssb="http://ssp-standard.org/SSP1/SystemStructureSignalDictionary"
    xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues">
  <ssd:System name="top">
    <ssd:Connectors>
      <ssd:Connector name="F" kind="output"><ssc:Real unit="N"/></ssd:Connector>
    </ssd:Connectors>
    <ssd:Elements>
      <ssd:Component name="press" source="resources/Press.fmu">
        <ssd:Connectors>
          <ssd:Connector name="normal_force" kind="output"><ssc:Real unit="kN"/></ssd:Connector>
        </ssd:Connectors>
        <ssd:ParameterBindings>
          <ssd:ParameterBinding source="resources/press.ssv">
            <ssd:ParameterMapping source="resources/press.ssm"/>
          </ssd:ParameterBinding>
        </ssd:ParameterBindings>
      </ssd:Component>
      <ssd:Component name="strip" source="resources/StripDraw.fmu">
        <ssd:Connectors>
          <ssd:Connector name="normal_force" kind="input"><ssc:Real unit="N"/></ssd:Connector>
        </ssd:Connectors>
      </ssd:Component>
      <ssd:SignalDictionaryReference name="bus" dictionary="signals"/>
      <ssd:System name="inner"/>
    </ssd:Elements>
    <ssd:Connections>
      <ssd:Connection startElement="press" startConnector="normal_force" endElement="strip" endConnector="normal_force">
        <ssc:LinearTransformation factor="1000"/>
      </ssd:Connection>
      <ssd:Connection startElement="press" startConnector="normal_force" endConnector="F"/>
    </ssd:Connections>
    <ssd:SignalDictionaries>
      <ssd:SignalDictionary name="signals" source="resources/signals.ssb"/>
    </ssd:SignalDictionaries>
  </ssd:System>
  <ssd:DefaultExperiment stopTime="0.05"/>
</ssd:SystemStructureDescription>
"""


def test_unsupported_elements_are_refused_each_by_name(tmp_path, capsys):
    from tribocosim.cosim.scene.fmucache import component_fmu

    ssp = _package(tmp_path / "unsupported.ssp", UNSUPPORTED, {"resources/Press.fmu": component_fmu("press"),
                                                               "resources/StripDraw.fmu": component_fmu("stripdraw")})
    assert tribocosim(["run", str(ssp), "--quiet", "--set", "experiment.step=0.01"]) == 2
    err = capsys.readouterr().err
    sys_ = "ssd:System[@name='top']"
    expected = [
        f"{sys_}/ssd:Connectors: system connectors",
        f"{sys_}/ssd:Elements/ssd:Component[@name='press']/ssd:Connectors/ssd:Connector[@name='normal_force']: "
        "unit 'kN' differs from the FMU variable's 'N'",
        f"{sys_}/ssd:Elements/ssd:Component[@name='press']/ssd:ParameterBindings/ssd:ParameterBinding[1]/"
        "ssd:ParameterMapping: parameter mappings are not supported",
        f"{sys_}/ssd:Elements/ssd:SignalDictionaryReference[@name='bus']: signal dictionaries are not supported",
        f"{sys_}/ssd:Elements/ssd:System[@name='inner']: nested systems are not supported",
        f"{sys_}/ssd:Connections/ssd:Connection[1]/ssc:LinearTransformation: transformations on connections",
        f"{sys_}/ssd:Connections/ssd:Connection[1]: press.normal_force is in 'kN' and strip.normal_force in 'N': "
        "unit conversions are not supported",
        f"{sys_}/ssd:Connections/ssd:Connection[2]: connections to the system's own connectors",
        f"{sys_}/ssd:SignalDictionaries: signal dictionaries are not supported",
    ]
    assert f"{len(expected)} problems in SSP {ssp}" in err, err
    for line in expected:
        assert line in err, f"{line}\nnot in:\n{err}"


def test_not_a_package_is_refused(tmp_path):
    bad = tmp_path / "bad.ssp"
    bad.write_text("not a zip")
    with pytest.raises(SceneError, match="not an SSP package"):
        load_ssp(bad)
    _package(bad, "<x/>", {})
    with pytest.raises(SceneError, match="root element is x, not ssd:SystemStructureDescription"):
        load_ssp(bad)
