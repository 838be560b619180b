"""The StripDraw FMU outside this project's environment and through a second FMI importer.

- a throwaway virtual environment with only numpy and fmpy (pip, from the package registry):
  the FMU must run on what it bundles, without numba, scipy, pyfftw, matplotlib or this project;
- libcosimpy (OSP's libcosim, a C++ co-simulation master) as an importer independent of fmpy.

Both run in subprocesses: a separate interpreter is the point of the first, and a crash of a
native importer must not take the test session down.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from tribocosim.components.stripdraw.friction import make_friction_law
from tribocosim.components.stripdraw.model import OUTPUT_NAMES, StripDrawModel
from tribocosim.components.stripdraw.parameters import StripDrawParameters
from tribocosim.components.stripdraw.table import read_table

PROJECT_ROOT = Path(__file__).resolve().parents[2]
TABLE = PROJECT_ROOT / "models" / "friction_table.npz"
REAL_OUTPUTS = OUTPUT_NAMES[:-1]  # table_clamp_count is an Integer output
FORBIDDEN = ("numba", "scipy", "pyfftw", "matplotlib", "tribocosim.surrogate", "tribocosim.cosim")
F10 = 10e6 * 0.035 * 0.035

CASES = [
    # (parameters, [(dt, normal_force, grip_velocity), ...])
    ({}, [(1e-3, F10 * (1 + 0.1 * (k % 3)), 0.08 * min(1.0, (k + 1) / 10)) for k in range(40)]),
    ({"integrator": "explicit", "n_elements": 60}, [(2e-4, F10, 0.08 * min(1.0, (k + 1) / 5)) for k in range(10)]),
]

_VENV_SCRIPT = textwrap.dedent(
    """
    import json, sys
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    fmu, cases, real_outputs = sys.argv[1], json.loads(sys.argv[2]), json.loads(sys.argv[3])
    md = read_model_description(fmu)
    unzipped = extract(fmu)
    var = {v.name: v for v in md.modelVariables}
    results = []
    for i, (params, schedule) in enumerate(cases):
        s = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier="StripDraw", instanceName=f"i{i}")
        s.instantiate(loggingOn=True)
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        for name, value in params.items():
            vr = [var[name].valueReference]
            {"Real": s.setReal, "Integer": s.setInteger, "String": s.setString}[var[name].type](vr, [value])
        s.exitInitializationMode()
        rows, t = [], 0.0
        for dt, f, v in schedule:
            s.setReal([var["normal_force"].valueReference, var["grip_velocity"].valueReference], [f, v])
            s.doStep(t, dt)
            t += dt
            reals = s.getReal([var[n].valueReference for n in real_outputs])
            rows.append(list(reals) + [float(s.getInteger([var["table_clamp_count"].valueReference])[0])])
        results.append(rows)
        s.terminate()
        s.freeInstance()
    import tribocosim.components.native.toolchain.library as library
    print(json.dumps({
        "results": results,
        "unzipped": str(unzipped),
        "components": sys.modules["tribocosim.components"].__file__,
        "library": str(library.core().path),
        "modules": sorted(sys.modules),
    }))
    """
)


def _model_rows(parameters, schedule) -> np.ndarray:
    params = StripDrawParameters(**parameters)
    table = read_table(TABLE) if params.friction_model == "table" else None
    model = StripDrawModel(params, make_friction_law(params, table))
    rows = []
    for dt, f, v in schedule:
        out = model.step(dt, {"normal_force": f, "grip_velocity": v})
        rows.append([out[n] for n in OUTPUT_NAMES])
    return np.array(rows)


def test_fmu_runs_in_a_venv_with_only_numpy_and_fmpy(stripdraw_fmu_file, numpy_fmpy_venv, tmp_path):
    python, env = numpy_fmpy_venv
    script = tmp_path / "run_fmu.py"
    script.write_text(_VENV_SCRIPT)
    proc = subprocess.run(
        [str(python), str(script), str(stripdraw_fmu_file), json.dumps(CASES), json.dumps(list(REAL_OUTPUTS))],
        cwd=tmp_path, env=env, capture_output=True, text=True, timeout=900,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stdout + proc.stderr
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    # the model code came from the FMU's resources, and nothing heavy was imported
    assert report["components"].startswith(report["unzipped"]), report["components"]
    assert report["library"].startswith(report["unzipped"]), "the core library the FMU carries"
    heavy = [m for m in report["modules"] if m.split(".")[0] in FORBIDDEN or m.startswith(FORBIDDEN[-2:])]
    assert heavy == [], heavy
    for (params, schedule), rows in zip(CASES, report["results"]):
        got, want = np.array(rows), _model_rows(params, schedule)
        for j, name in enumerate(OUTPUT_NAMES):
            # the same native core
            assert np.array_equal(got[:, j], want[:, j]), f"{name} {params}"


def test_libcosimpy_gives_the_same_outputs_as_fmpy(stripdraw_fmu_file, stripdraw_fmu_instance, libcosim_run):
    params, schedule = CASES[0]
    step_ns = 1_000_000
    inputs = [(f, v) for _, f, v in schedule]
    got = np.array(libcosim_run(stripdraw_fmu_file, step_ns, ("normal_force", "grip_velocity"), inputs,
                                REAL_OUTPUTS, ("table_clamp_count",)))
    # libcosim keeps time in integer nanoseconds and passes doStep the difference of the two
    # time points in seconds, t_(k+1)/1e9 - t_k/1e9, which is not always exactly 1e-3
    steps = [((k + 1) * step_ns) / 1e9 - (k * step_ns) / 1e9 for k in range(len(inputs))]
    assert any(dt != 1e-3 for dt in steps), "the replay below would not test the step sizes"
    inst = stripdraw_fmu_instance("fmpy", params).initialize()
    want = np.array([inst.step(dt, f, v) for dt, (f, v) in zip(steps, inputs)])
    assert got.shape == want.shape
    for j, name in enumerate(OUTPUT_NAMES):
        assert_array_equal(got[:, j], want[:, j], err_msg=f"{name}: libcosim differs from fmpy")


_EXIT_SCRIPT = textwrap.dedent(
    """
    import sys
    from fmpy import read_model_description
    from fmpy.fmi2 import FMU2Slave

    unzipped = sys.argv[1]
    md = read_model_description(unzipped + "/modelDescription.xml")
    s = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier="StripDraw", instanceName="x")
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    s.doStep(0.0, 1e-3)
    s.terminate()
    s.freeInstance()
    """
)


def test_python_host_exits_cleanly_after_freeing_the_fmu(stripdraw_fmu_unzipped, tmp_path):
    """Regression test of components/fmus/exitguard.py: without the guard, a fresh Python
    process that ran the FMU (bundled model, numba and scipy loaded) and freed it aborted at
    exit in about one run of three ("corrupted double-linked list")."""
    script = tmp_path / "run_and_exit.py"
    script.write_text(_EXIT_SCRIPT)
    codes = []
    for _ in range(8):
        proc = subprocess.run(
            [sys.executable, str(script), str(stripdraw_fmu_unzipped)],
            cwd=tmp_path, capture_output=True, text=True, timeout=300,
        )  # fmt: skip
        codes.append((proc.returncode, proc.stderr[-300:]))
    assert all(code == 0 for code, _ in codes), codes


def test_exit_guard_registers_only_for_a_real_fmu_binary(tmp_path, stripdraw_fmu_unzipped):
    from tribocosim.components.fmus import exitguard

    assert not exitguard.guard_pythonfmu_exit(None, "StripDraw")
    assert not exitguard.guard_pythonfmu_exit(str(tmp_path), "StripDraw"), "no binary at build time"
    resources = str(Path(stripdraw_fmu_unzipped) / "resources")
    if sys.platform.startswith("linux"):
        assert exitguard.guard_pythonfmu_exit(resources, "StripDraw")
        n = len(exitguard._guarded)
        assert exitguard.guard_pythonfmu_exit(resources, "StripDraw") and len(exitguard._guarded) == n


_MANY_INSTANCES = textwrap.dedent(
    """
    import gc, sys
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    fmu, n = sys.argv[1], int(sys.argv[2])
    md = read_model_description(fmu)
    unzipped = extract(fmu)
    for k in range(n):
        s = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName=f"i{k}")
        s.instantiate()
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        s.exitInitializationMode()
        s.doStep(0.0, 1e-3)
        s.terminate()
        s.freeInstance()
        gc.collect()
    print("done", n)
    """
)


@pytest.mark.parametrize("name", ["Press", "StripDraw"])
def test_many_instances_in_one_process_and_a_clean_exit(built_fmus, tmp_path, name):
    """Regression: pythonfmu 0.7.0 releases a reference to the script's globals at every
    instantiation (adapter.hold_script_globals); a generated script without it crashed the host."""
    script = tmp_path / "many.py"
    script.write_text(_MANY_INSTANCES)
    proc = subprocess.run([sys.executable, str(script), str(built_fmus[name]), "40"], capture_output=True, text=True,
                          timeout=600, cwd=tmp_path)
    assert proc.returncode == 0, f"exit {proc.returncode}\n{proc.stderr[-2000:]}"
    assert proc.stdout.split()[-2:] == ["done", "40"]
