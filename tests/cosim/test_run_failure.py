"""A run that meets a step it cannot recover stops: ``tribocosim run`` exits 1 with a
message naming the FMU, the variable, the time and the step, and writes what was accepted up to then (CSV
without a NaN, JSON with a ``failure`` entry and the rejected attempts). Real FMUs: the test FMU
``Lag`` (pythonfmu, tests/cosim/fmus) whose output turns NaN at a set time, and the native strip-draw FMU refusing a
negative normal force."""

from __future__ import annotations

import json
import textwrap

import numpy as np
import pytest

from tribocosim.cosim.apps.run_cli import main as run_main


def _scene(folder, body: str, variables: list[str]):
    path = folder / "failing.toml"
    path.write_text(textwrap.dedent("""
        [experiment]
        stop = 0.1
        step = 1e-3
        [fmus.press]
        component = "press"
        parameters = { force_setpoint = 1000.0, ramp_time = 0.02 }
        """) + textwrap.dedent(body) + textwrap.dedent(f"""
        [output]
        file = "failing.csv"
        variables = {json.dumps(variables)}
        """))
    return path


def test_a_non_finite_output_that_smaller_steps_do_not_cure_stops_the_run(tmp_path, fmu_dir, capsys):
    scene = _scene(tmp_path, f"""
        [fmus.lag]
        path = "{fmu_dir / 'Lag.fmu'}"
        parameters = {{ gain = 2.0, time_constant = 0.01, nan_from = 0.05 }}
        [[connections]]
        from = "press.normal_force"
        to = "lag.u"
        """, ["lag.y", "press.normal_force"])
    assert run_main([str(scene), "--out", str(tmp_path / "out"), "--quiet"]) == 1
    err = capsys.readouterr().err
    # the master halves the step down to one tick of the time grid and gets as close to 0.05 s as that allows
    assert "FMU instance 'lag': non-finite output lag.y at t = 0.05 s (step from t = 0.04999" in err, err
    assert "still failing at the smallest allowed step" in err and "the run stopped at t = 0.04999" in err, err

    csv = np.genfromtxt(tmp_path / "out" / "failing.csv", delimiter=",", names=True)
    assert 0.0499 < csv["time"][-1] < 0.05 and np.all(np.isfinite(csv["lagy"]))
    assert csv["lagy"][-1] > 0  # the lag had been rising toward 2 x the press force
    meta = json.loads((tmp_path / "out" / "failing.json").read_text())
    assert meta["failure"]["last_accepted_time"] == csv["time"][-1]
    assert meta["failure"]["recorded_rows"] == csv.size
    assert "non-finite output lag.y" in meta["failure"]["message"]
    assert meta["steps"]["rejected_failure"] >= 10  # every halving from 1 ms to the tick was tried


def test_a_step_the_fmu_discards_at_every_size_stops_the_run(tmp_path, fmu_dir, capsys):
    scene = _scene(tmp_path, f"""
        [fmus.lag]
        path = "{fmu_dir / 'Lag.fmu'}"
        parameters = {{ gain = -1.0, time_constant = 0.01 }}
        [fmus.strip]
        component = "stripdraw"
        parameters = {{ friction_model = "constant" }}
        [[connections]]
        from = "press.normal_force"
        to = "lag.u"
        [[connections]]
        from = "lag.y"
        to = "strip.normal_force"
        """, ["strip.pull_force", "lag.y"])
    assert run_main([str(scene), "--out", str(tmp_path / "out"), "--quiet"]) == 1
    err = capsys.readouterr().err
    # the strip refuses a negative normal force at any step size: an FMI error, so the master does not halve it
    assert "FMU instance 'strip': fmi2DoStep failed (status 3, error)" in err and "normal_force" in err, err
    assert err.count("no step size can complete it") == 1, err
    meta = json.loads((tmp_path / "out" / "failing.json").read_text())
    assert "no step size can complete it" in meta["failure"]["message"]
    assert (tmp_path / "out" / "failing.csv").is_file()


def test_a_coupling_iteration_that_does_not_converge_stops_the_run_and_keeps_its_work(tmp_path, monkeypatch, capsys):
    """The strip-draw rig (native FMUs) under iterative coupling limited to 2 fixed-point iterations: the loop
    strip.pull_force <-> drive.grip_velocity cannot converge to 1e-8 in 2 iterations once the drive pulls."""
    monkeypatch.setenv("TRIBOCOSIM_CACHE", str(tmp_path / "cache"))
    scene = _scene(tmp_path, """
        [master]
        algorithm = "iterative"
        [master.iterative]
        method = "fixed-point"
        max_iterations = 2
        [fmus.strip]
        component = "stripdraw"
        parameters = { friction_model = "constant", n_elements = 60 }
        [fmus.drive]
        component = "drawingmachine"
        [[connections]]
        from = "press.normal_force"
        to = "strip.normal_force"
        [[connections]]
        from = "drive.grip_velocity"
        to = "strip.grip_velocity"
        [[connections]]
        from = "strip.pull_force"
        to = "drive.pull_force"
        """, ["strip.pull_force", "drive.grip_velocity"])
    assert run_main([str(scene), "--out", str(tmp_path / "out"), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "iterative coupling did not converge in 2 iterations at t = " in err and "the run stopped at t = " in err, err
    meta = json.loads((tmp_path / "out" / "failing.json").read_text())
    assert "did not converge" in meta["failure"]["message"]
    csv = np.atleast_1d(np.genfromtxt(tmp_path / "out" / "failing.csv", delimiter=",", names=True))
    assert meta["failure"]["recorded_rows"] == csv.size
    assert meta["failure"]["last_accepted_time"] == csv["time"][-1]
    assert np.all(np.isfinite(csv["strippull_force"]))
