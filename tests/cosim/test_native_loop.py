"""Tests of the C master (cosim.engine.native_session: a whole run; cosim.engine.native_loop: the loop of the Python
master): the fixed-step loop in C gives the Python loop's results to the last bit, saves no FMU state, and leaves to
the Python loop the steps it does not take."""

from __future__ import annotations

import ctypes
import re

import numpy as np
import pytest

from tribocosim.components.native.toolchain.prototypes import code
from tribocosim.cosim.engine import native_lib

from tribocosim.errors import RunFailed
from tribocosim.cosim import run
from tribocosim.cosim.api import build
from tribocosim.cosim.scene.validate import load_scene
from tribocosim.paths import scene_file

#: the demo rig cut to 0.4 s at 1 ms, the strip pulled from 0.1 s (every FMU's behaviour in a short run)
SHORT = {"experiment.stop": 0.4, "experiment.step": 1e-3, "fmus.drive.parameters.start_time": 0.1}


def _same(a, b) -> None:
    assert np.array_equal(a.time, b.time), "the same communication points"
    assert list(a.columns) == list(b.columns)
    for name in a.columns:
        np.testing.assert_array_equal(a.columns[name], b.columns[name], err_msg=name)


@pytest.mark.parametrize("algorithm", ["jacobi", "gauss-seidel"])
@pytest.mark.parametrize("update", ["propagate", "none"])
def test_the_demo_rig_gives_the_python_loops_values_to_the_last_bit(algorithm, update):
    keys = {**SHORT, "master.algorithm": algorithm, "master.output_update": update}
    native = run("demo", overrides=keys, write=False)
    python = run("demo", overrides=keys, write=False, loop="python")
    assert native.metadata["master"]["loop"] == "native"
    assert python.metadata["master"]["loop"] == "python"
    _same(native, python)
    assert native.metadata["steps"] == python.metadata["steps"]
    for name, calls in native.metadata["fmi_calls"].items():
        assert calls == {"doStep": 400, "getFMUstate": 0, "setFMUstate": 0}, (name, "no state saved by the C loop")


@pytest.mark.parametrize("algorithm", ["jacobi", "gauss-seidel"])
def test_the_python_masters_c_loop_gives_the_whole_c_runs_values(algorithm):
    """The loop of the Python master in C (after the Python initialization: build, initialize, run) and the whole
    run in C (native_session) make the same FMI calls: the same recorded values, bit for bit."""
    keys = {**SHORT, "master.algorithm": algorithm}
    session = run("demo", overrides=keys, write=False)
    b = build(load_scene(scene_file("demo"), keys))
    m = b.master
    try:
        m.initialize(m.grid.start, b.plan.scene.experiment.stop, b.parameters)
        m.run()
    finally:
        b.close()
    assert m.loop_used == "native" and session.metadata["master"]["loop"] == "native"
    np.testing.assert_array_equal(m.recorder.time, session.time)
    for name, column in m.recorder.columns().items():
        np.testing.assert_array_equal(column, session.columns[name], err_msg=name)


#: what ``tribocosim run demo`` does not read: the numerical and FMI stacks, the mesoscale code, and the modules a
#: fixed-step run of a scene whose summaries and checks are cached has no use for (the TOML parser: the document is
#: cached; logging: nothing to say; the module finders, archive, diff, date and temporary-file machinery)
NOT_ON_THE_RUN_PATH = ("numpy", "fmpy", "scipy", "matplotlib", "numba", "tribocosim.surrogate", "tomllib", "logging",
                       "typing", "importlib.resources", "pkgutil", "zipfile", "tempfile", "difflib", "datetime",
                       "subprocess", "concurrent", "multiprocessing", "xml")


def test_the_whole_c_run_imports_only_what_it_reads(tmp_path):
    """``tribocosim run demo`` with the FMUs built: the run path of the C master (its summaries and checks cached)
    imports none of :data:`NOT_ON_THE_RUN_PATH`, and no class of a ``tribocosim.cosim`` module it imports is made by
    ``dataclasses`` (whose generated methods are compiled at import: 3 to 4 million instructions a class)."""
    import json
    import subprocess
    import sys

    code = ("import dataclasses, json, sys; from tribocosim.cli import main; "
            "main(['run', 'demo', '--quiet', '--out', sys.argv[1]]); "
            "mods = sorted(sys.modules); "
            "print(json.dumps({'modules': mods, 'records': sorted(f'{m}.{k}' for m in mods "
            "if m.startswith('tribocosim.cosim') for k, v in vars(sys.modules[m]).items() "
            "if isinstance(v, type) and v.__module__ == m and dataclasses.is_dataclass(v))}))")
    for _ in range(2):  # the first run may fill the caches
        out = subprocess.run([sys.executable, "-c", code, str(tmp_path)], capture_output=True, text=True, timeout=300)
        assert out.returncode == 0, out.stderr
    found = json.loads(out.stdout.strip().splitlines()[-1])
    assert (tmp_path / "demo.csv").is_file()
    assert [m for m in found["modules"] if m.split(".")[0] in NOT_ON_THE_RUN_PATH or m in NOT_ON_THE_RUN_PATH
            or any(m.startswith(f"{n}.") for n in NOT_ON_THE_RUN_PATH)] == []
    assert found["records"] == []


@pytest.mark.parametrize("algorithm", ["jacobi", "gauss-seidel"])
def test_fmus_with_direct_feedthrough_refresh_in_the_same_order(tmp_path, osc_scene, algorithm):
    """The oscillator's mass B feeds its input through to its force output: the refresh sets its inputs first."""
    scene = osc_scene(tmp_path, stop=2.0, algorithm=algorithm)
    native = run(scene, write=False)
    python = run(scene, write=False, loop="python")
    assert native.metadata["master"]["loop"] == "native" and native.metadata["fmus"]["b"]["feedthrough"] is True
    _same(native, python)


def test_a_run_the_c_loop_does_not_take_says_why(tmp_path, osc_scene):
    res = run(osc_scene(tmp_path, stop=0.5, extrapolation=1), write=False)
    assert res.metadata["master"]["loop"] == "python"
    assert res.metadata["master"]["python_loop_because"] == "extrapolation order 1"


@pytest.mark.parametrize("mode", [0, 1], ids=["discard", "non-finite"])
def test_a_step_the_c_loop_does_not_take_is_repeated_by_the_python_loop(tmp_path, make_scene, fmu_dir, mode):
    """The C loop stops where the FMU refuses a step; the run is repeated in Python, which halves the step."""
    scene = make_scene(tmp_path, "fragile.toml", f"""
        [experiment]
        stop = 1.0
        step = 0.05
        [fmus.f]
        path = "{fmu_dir / 'Fragile.fmu'}"
        parameters = {{ mode = {mode} }}
        [output]
        variables = ["f.y", "f.refusals"]
        """)
    auto = run(scene, write=False)
    python = run(scene, write=False, loop="python")
    _same(auto, python)
    assert auto.metadata["steps"]["rejected_failure"] == python.metadata["steps"]["rejected_failure"] > 0
    assert any("the native loop stopped" in n for n in auto.metadata["notes"]), auto.metadata["notes"]


def test_without_rollback_the_repeated_run_stops_with_the_python_loops_message(tmp_path, make_scene, fmu_dir):
    scene = make_scene(tmp_path, "fragile.toml", f"""
        [experiment]
        stop = 1.0
        step = 0.05
        [fmus.f]
        path = "{fmu_dir / 'nostate' / 'Fragile.fmu'}"
        [output]
        variables = ["f.y"]
        """)
    with pytest.raises(RunFailed) as auto:
        run(scene, write=False)
    with pytest.raises(RunFailed) as python:
        run(scene, write=False, loop="python")
    assert str(auto.value) == str(python.value) and "cannot roll back" in str(auto.value)
    _same(auto.value.result, python.value.result)


#: the C types of tc_master.h's struct members and the ctypes type each is passed as
_C_TYPES = {"fmi2Component": ctypes.c_void_p, "tcm_sink *": ctypes.c_void_p, "void *": ctypes.c_void_p, "double": ctypes.c_double, "int64_t": ctypes.c_int64,
            "int": ctypes.c_int, "size_t": ctypes.c_size_t, "double *": ctypes.POINTER(ctypes.c_double),
            "fmi2Integer *": ctypes.POINTER(ctypes.c_int), "unsigned char *": ctypes.POINTER(ctypes.c_ubyte),
            "const int *": ctypes.POINTER(ctypes.c_int), "const size_t *": ctypes.POINTER(ctypes.c_size_t),
            "const fmi2ValueReference *": ctypes.POINTER(ctypes.c_uint), "const char *": ctypes.c_char_p}


def test_the_ctypes_structs_are_the_headers():
    """Every struct of tc_master.h, member by member (name and type), is the ctypes structure native_lib passes."""
    text = code((native_lib.NATIVE_DIR / "tc_master.h").read_text())
    structs = dict(re.findall(r"typedef struct (\w+) \{(.*?)\} \1;", text, flags=re.S))
    assert set(structs) == set(native_lib.STRUCTS)
    for name, body in structs.items():
        members = []
        for decl in filter(None, (d.strip() for d in body.split(";"))):
            ctype, member = re.fullmatch(r"(.*?)\s*\b(\w+)", " ".join(decl.split())).groups()
            if ctype in _C_TYPES:
                expected = _C_TYPES[ctype]
            elif ctype.endswith("TYPE *"):  # a pointer to an FMI function
                expected = ctypes.c_void_p
            elif ctype.startswith(("tcm_", "const tcm_")):  # a pointer to an array of the loop's structs
                expected = ctypes.POINTER(native_lib.STRUCTS[ctype.replace("const ", "").rstrip(" *")])
            else:
                expected = _C_TYPES[ctype]
            members.append((member, expected))
        assert native_lib.STRUCTS[name]._fields_ == members, name
