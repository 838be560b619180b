"""Tests of ``tribocosim run`` (cosim.apps.run_cli) and of the result files (cosim.api, cosim.engine.recorder)."""

import io
import json

import numpy as np
from fmpy.util import read_csv

from tribocosim.cosim import run
from tribocosim.cli import main as tribocosim
from tribocosim.cosim.engine.observers import Progress


def test_run_writes_csv_readable_by_fmpy_and_metadata(tmp_path, osc_scene, capsys):
    scene = osc_scene(tmp_path, stop=1.0, step=0.01, extrapolation=1)
    out = tmp_path / "out"
    assert tribocosim(["run", str(scene), "--out", str(out), "--plot"]) == 0
    printed = capsys.readouterr().out
    assert "steps:    100 accepted" in printed and "results:" in printed, printed
    traj = read_csv(out / "results.csv")
    assert traj.dtype.names == ("time", "a.x1", "b.x2", "b.force"), "time, then the scene's order"
    assert len(traj) == 101 and traj["time"][-1] == 1.0
    meta = json.loads((out / "results.json").read_text())
    assert meta["scene"] == str(scene) and meta["master"]["algorithm"] == "jacobi"
    assert meta["master"]["extrapolation"] == 1 and meta["steps"]["accepted"] == 100
    assert meta["steps"]["rejected_error"] == 0 and meta["fmi_calls"]["a"]["doStep"] == 100
    assert set(meta["wall_time"]["fmus"]) == {"a", "b"} and meta["wall_time"]["master"] > 0
    assert meta["outputs"]["columns"] == ["time", "a.x1", "b.x2", "b.force"]
    assert (out / "results.png").stat().st_size > 1000
    api = run(scene, write=False)
    for name in ("a.x1", "b.x2", "b.force"):
        np.testing.assert_array_equal(traj[name], api[name], err_msg=f"CSV round trip of {name}")


def test_set_overrides_a_scene_key(tmp_path, osc_scene):
    scene = osc_scene(tmp_path, stop=0.5, step=0.01)
    assert tribocosim(["run", str(scene), "--quiet", "--set", "experiment.step=0.05", "--set", 'master.algorithm="gauss-seidel"']) == 0
    meta = json.loads((tmp_path / "results.json").read_text())
    assert meta["experiment"]["step"] == 0.05 and meta["master"]["algorithm"] == "gauss-seidel"
    assert meta["steps"]["accepted"] == 10


def test_scene_problems_exit_with_2_and_one_message(tmp_path, osc_scene, capsys):
    scene = osc_scene(tmp_path)
    scene.write_text(scene.read_text().replace('"b.x2"', '"b.xx2"'))
    assert tribocosim(["run", str(scene), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "1 problem in scene" in err and "output.variables[1]: unknown variable 'xx2'" in err, err


def test_progress_bar_appears_only_after_the_delay():
    stream = io.StringIO()
    bar = Progress(0.0, 10.0, delay=0.0, stream=stream)
    bar(5.0)
    bar.close()
    assert "50.0%" in stream.getvalue() and stream.getvalue().endswith("\n")
    quiet = io.StringIO()
    bar = Progress(0.0, 10.0, delay=60.0, stream=quiet)
    bar(5.0)
    bar.close()
    assert quiet.getvalue() == ""


def test_gauss_seidel_reports_the_cycle_it_breaks(tmp_path, osc_scene):
    res = run(osc_scene(tmp_path, stop=0.1, algorithm="gauss-seidel"), write=False)
    gs = res.metadata["gauss_seidel"]
    assert gs["order"] == ["a", "b"] and gs["cycles"] == [["a", "b"]]
    assert gs["extrapolated_links"] == ["b.force -> a.force"]
    assert any("a -> b form a cycle" in n and "b.force -> a.force is extrapolated" in n for n in res.metadata["notes"])


def test_run_of_fmu_files_imports_neither_numba_nor_the_mesoscale_code(tmp_path, osc_scene):
    """``tribocosim run`` on a scene of FMU files, in a fresh interpreter: nothing heavy is imported."""
    import subprocess
    import sys

    scene = osc_scene(tmp_path, stop=0.01, step=0.01)
    script = (
        "import sys\n"
        "from tribocosim.cli import main\n"
        f"assert main(['run', {str(scene)!r}, '--quiet']) == 0\n"
        "heavy = ('numba', 'pyfftw', 'scipy', 'matplotlib', 'tribocosim.surrogate', 'tribocosim.components.stripdraw')\n"
        "print(sorted(m for m in sys.modules if m.startswith(heavy)))\n"
    )
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip().splitlines()[-1] == "[]", proc.stdout


def test_packaged_scenes_resolve_by_name_and_write_to_the_working_directory(tmp_path, monkeypatch):
    from tribocosim.errors import SceneError
    from tribocosim.paths import SCENES_DIR, packaged_scenes, scene_file
    from tribocosim.cosim.api import default_out_dir

    assert {"demo", "pressure_sweep", "multipass"} <= set(packaged_scenes())
    assert scene_file("demo") == SCENES_DIR / "demo.toml" == scene_file("demo.toml")
    monkeypatch.chdir(tmp_path)
    assert default_out_dir(scene_file("demo")) == tmp_path / "demo", "never into the installed package"
    mine = tmp_path / "demo.toml"
    mine.write_text("")
    assert scene_file("demo.toml").resolve() == mine, "a file in the working directory wins"
    assert default_out_dir(mine) == tmp_path
    try:
        scene_file("nope")
    except SceneError as exc:
        assert "scene file not found: nope" in str(exc) and "demo" in str(exc)
    else:
        raise AssertionError("an unknown scene name must be refused")


def test_run_says_when_the_friction_table_was_read_outside_its_simulated_range(tmp_path, capsys):
    """The strip at 60 MPa (above the shipped table's 30 MPa) for 0.05 s: every nodal lookup is clamped, the
    FMU counts them in table_clamp_count and tribocosim run warns, naming the instance and the count; the
    default test (10 MPa) draws without a warning."""
    scene = tmp_path / "hot.toml"
    scene.write_text('[experiment]\nstart = 0.0\nstop = 0.05\nstep = 1e-3\n[fmus.strip]\ncomponent = "stripdraw"\n'
                     'parameters = { normal_force = 73500.0, grip_velocity = 0.08 }\n'
                     '[output]\nfile = "hot.csv"\nvariables = ["strip.table_clamp_count"]\n')
    assert tribocosim(["run", str(scene), "--out", str(tmp_path)]) == 0
    err = capsys.readouterr().err
    counted = read_csv(tmp_path / "hot.csv")["strip.table_clamp_count"][-1]
    assert counted > 0 and f"FMU instance 'strip': {counted:.0f} friction-table lookups" in err, err
    meta = json.loads((tmp_path / "hot.json").read_text())
    assert any("table_clamp_count" in w for w in meta["warnings"])
    cold = tmp_path / "cold.toml"
    cold.write_text(scene.read_text().replace("73500.0", "12250.0").replace("hot.csv", "cold.csv"))
    assert tribocosim(["run", str(cold), "--out", str(tmp_path)]) == 0
    assert "friction-table lookups" not in capsys.readouterr().err


def test_an_fmu_or_a_folder_given_as_the_scene_is_named_as_such(tmp_path, fmu_dir, capsys):
    """``tribocosim run X.fmu`` says that an FMU is not a scene and how to run one; a folder is named a folder (with
    the scenes in it), not "not found": one line each, exit 2, nothing written."""
    import shutil

    fmu = shutil.copy(fmu_dir / "OscMassA.fmu", tmp_path / "OscMassA.fmu")
    assert tribocosim(["run", str(fmu), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"tribocosim run: {fmu} is an FMU, not a scene: write a scene file (TOML) that names it, e.g. "
                   '[experiment] stop = 1.0, step = 1e-3 and [fmus.oscmassa] path = "OscMassA.fmu", and run that '
                   "(docs/scene-format.md)"]
    folder = tmp_path / "scenes"
    folder.mkdir()
    (folder / "b.toml").write_text("", encoding="utf-8")
    (folder / "a.ssp").write_bytes(b"")
    for given, holds in ((folder, "; it holds a.ssp, b.toml"), (tmp_path / "empty.toml", "")):
        given.mkdir(exist_ok=True)
        assert tribocosim(["run", str(given), "--out", str(tmp_path / "out")]) == 2
        assert capsys.readouterr().err.strip().splitlines() == [
            f"tribocosim run: {given} is a folder, not a scene file: give a scene (TOML) or an SSP package (.ssp)"
            + holds]
    assert not (tmp_path / "out").exists()


def test_a_packaged_scene_runs_by_its_name_beside_the_folder_of_its_last_results(tmp_path, monkeypatch):
    """``tribocosim run demo`` writes into ./demo; run again from there it is still the packaged scene."""
    monkeypatch.chdir(tmp_path)
    for _ in range(2):
        assert tribocosim(["run", "demo", "--quiet", "--set", "experiment.stop=0.01"]) == 0
    assert (tmp_path / "demo" / "demo.csv").is_file()


def test_an_fmu_path_that_is_a_folder_is_named_as_such(tmp_path, osc_scene, fmu_dir, capsys):
    scene = osc_scene(tmp_path)
    (tmp_path / "extracted.fmu").mkdir()
    scene.write_text(scene.read_text().replace(str(fmu_dir / "OscMassA.fmu"), str(tmp_path / "extracted.fmu")))
    assert str(tmp_path / "extracted.fmu") in scene.read_text()
    assert tribocosim(["run", str(scene), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert (f"fmus.a.path: {tmp_path / 'extracted.fmu'} is a folder, not an FMU file: give the .fmu file (the zip "
            "archive of an FMU's folder)") in err, err


def test_run_says_the_strips_mu_bar_as_the_demo_does(tmp_path, capsys):
    """``tribocosim run demo --set ...`` prints mu_bar, the mean of pull_force / (2 normal_force) (Eq. 1) over the last
    20 % of the run, of the results it wrote (the press's normal force, which the strip's input reads)."""
    import numpy as np

    from tribocosim.cosim.apps.run_cli import main as run_main

    assert run_main(["demo", "--out", str(tmp_path), "--quiet"]) == 0
    assert "mu_bar" not in capsys.readouterr().out  # --quiet says nothing
    assert run_main(["demo", "--out", str(tmp_path), "--set", "fmus.strip.parameters.flake_shear_ratio=0"]) == 0
    line = [x for x in capsys.readouterr().out.splitlines() if x.startswith("mu_bar:")]
    data = np.genfromtxt(tmp_path / "demo.csv", delimiter=",", names=True)
    t = data["time"]
    sel = (t >= t[-1] - 0.2 * (t[-1] - t[0]) - 1e-12) & (data["pressnormal_force"] > 0)
    want = np.mean(data["strippull_force"][sel] / (2 * data["pressnormal_force"][sel]))
    assert len(line) == 1 and line[0].split()[1] == f"{want:.4f}", line
