"""``tribocosim calibrate`` refuses what it cannot fit honestly before it spends the fit, in one line with exit code
2 and nothing written: data outside the friction table (with the likely unit slip), an output it cannot write, a bad
``--set``; after the fit, rows whose draws at the fitted values read the table clamped, unless ``--allow-clamped``
keeps them and the record counts them; ``--units mm-t-s`` reads the data in MPa and mm; Ctrl-C ends it in one line
with nothing left."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from tribocosim.components.stripdraw.friction import closed_form_table
from tribocosim.components.stripdraw.parameters import StripDrawParameters
from tribocosim.components.stripdraw.table import read_table, write_table
from tribocosim.cosim.apps.calibrate import main
from tribocosim.cosim.studies.stripdraw_experiment import Point, run_points

#: the fast strip of tests/cosim/test_calibrate.py
FAST = {"n_elements": 60, "draw_length": 0.02, "archard_k": 5e-4}


def _write(path, rows, header="pressure,tool_length,passes,mu_bar,mu_bar_std"):
    path.write_text(header + "\n" + "\n".join(",".join(str(x) for x in r) for r in rows) + "\n")
    return path


def _args(data, out, table, *extra):
    return ["--measured", str(data), "--out", str(out), "--table", str(table), "--contact-area", "eq8",
            "--workers", "1", *(x for k, v in FAST.items() for x in ("--set", f"{k}={v}")), *extra]


@pytest.fixture(scope="module")
def tables(tmp_path_factory):
    """Eq. 23 (alpha = 40) tabulated to beta = 1 (no draw of these tests leaves it) and to the cap at s = 1 only
    (a draw at s < 1 makes debris beyond it)."""
    folder = tmp_path_factory.mktemp("tables")
    wide, short = folder / "wide.npz", folder / "short.npz"
    write_table(wide, closed_form_table(StripDrawParameters(alpha_b=40.0), beta=np.linspace(0.0, 1.0, 41)))
    write_table(short, closed_form_table(StripDrawParameters(alpha_b=40.0)))
    return wide, short


def _model_rows(table, scale, points):
    params = {**FAST, "contact_area": "eq8", "table_file": str(table), "particle_area_scale": scale}
    clean = [m[-1] for m in run_points([Point(p, L, n, params) for p, L, n in points], workers=1)]
    return [(p, L, n, m, 2e-4) for (p, L, n), m in zip(points, clean)]


def test_pressures_written_in_mpa_are_refused_with_the_unit_slip_named_and_read_with_units_mm_t_s(tmp_path, tables,
                                                                                                  capsys):
    wide, _ = tables
    rows = _model_rows(wide, 0.6, [(5e6, 0.035, 1), (20e6, 0.035, 1)])
    out = tmp_path / "cal.npz"
    in_mpa = _write(tmp_path / "mpa.csv", [(p / 1e6, L, n, m, s) for p, L, n, m, s in rows])
    assert main(_args(in_mpa, out, wide)) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and not out.exists(), err
    assert "column pressure holds 5, 20 Pa (rows 2, 3), outside the friction table's 100000-1e+08 Pa" in err, err
    assert "they look like MPa: give --units mm-t-s" in err
    both = _write(tmp_path / "mm.csv", [(p / 1e6, L * 1e3, n, m, s) for p, L, n, m, s in rows])
    assert main(_args(both, out, wide, "--units", "mm-t-s")) == 0
    cal = read_table(out).metadata["strip_draw_calibration"]
    assert cal["data"]["units"] == "mm-t-s" and cal["clamped_rows"] == []
    assert [(p["pressure"], p["tool_length"]) for p in cal["points"]] == [(5e6, 0.035), (20e6, 0.035)]
    assert abs(cal["fitted"]["particle_area_scale"]["value"] - 0.6) < 1e-3
    pad_in_mm = _write(tmp_path / "pad.csv", [(p, L * 1e3, n, m, s) for p, L, n, m, s in rows])
    assert main(_args(pad_in_mm, out, wide)) == 2
    assert "row 2, column tool_length: 35 m (in mm? give --units mm-t-s)" in capsys.readouterr().err


def test_a_pressure_above_the_table_is_refused_before_the_fit(tmp_path, capsys):
    """The shipped table ends at 30 MPa: a 40 MPa row would be fitted on lookups clamped at 30 MPa."""
    data = _write(tmp_path / "d.csv", [(10e6, 0.035, 1, 0.12, 0.01), (40e6, 0.035, 1, 0.08, 0.01)])
    out = tmp_path / "cal.npz"
    assert main(["--measured", str(data), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "column pressure holds 4e+07 Pa (rows 3), outside the friction table's 1e+06-3e+07 Pa" in err, err
    assert "calibrating" not in err and not out.exists()


@pytest.mark.parametrize("target, message", [
    ("folder", "--out {out} is a folder; give the file to write"),
    ("missing/cal.npz", "its folder {parent} does not exist or is not a folder"),
    ("readonly/cal.npz", "the folder {parent} is not writable"),
])
def test_an_output_that_cannot_be_written_is_refused_before_the_fit(tmp_path, tables, capsys, target, message):
    wide, _ = tables
    (tmp_path / "folder").mkdir()
    (tmp_path / "readonly").mkdir(mode=0o555)
    if os.geteuid() == 0 and target.startswith("readonly"):
        pytest.skip("root writes into a read-only folder")
    data = _write(tmp_path / "d.csv", [(5e6, 0.035, 1, 0.12, 0.01)])
    out = tmp_path / target
    assert main(_args(data, out, wide)) == 2
    err = capsys.readouterr().err
    assert message.format(out=out, parent=out.parent) in err and "calibrating" not in err, err
    assert not list(tmp_path.rglob("*.partial*")) and not (tmp_path / "folder" / "cal.npz").exists()


@pytest.mark.parametrize("item, message", [("mu0=abc", "--set mu0=abc: 'abc' is not a number"),
                                           ("mu0", "--set 'mu0': expected NAME=VALUE"),
                                           ("n_elements=1.5", "--set n_elements=1.5: '1.5' is not an integer"),
                                           ("no_such=1", "'no_such' is not a strip-draw parameter")])
def test_a_bad_set_is_one_line_and_exit_2(tmp_path, item, message, capsys):
    data = _write(tmp_path / "d.csv", [(5e6, 0.035, 1, 0.12, 0.01)])
    assert main(["--measured", str(data), "--out", str(tmp_path / "c.npz"), "--set", item]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err, err


def test_rows_read_clamped_at_the_fitted_values_are_refused_unless_kept_and_then_counted(tmp_path, tables, capsys):
    """On the table that ends at the cap of s = 1, a fitted s = 0.6 makes debris beyond its beta axis at 20 MPa: the
    row is refused after the fit (the fit rests on clamped lookups), and --allow-clamped writes the table with the
    count of the row's clamped lookups in its record."""
    wide, short = tables
    rows = _model_rows(short, 0.6, [(5e6, 0.035, 1), (20e6, 0.035, 1)])
    data = _write(tmp_path / "d.csv", rows)
    out = tmp_path / "cal.npz"
    assert main(_args(data, out, short)) == 2
    err = capsys.readouterr().err
    assert "read the friction table outside its axes or its simulated range" in err and not out.exists(), err
    assert "row 3 (P = 20 MPa, L_T = 35 mm, pass 1): " in err and "--allow-clamped" in err
    assert main(_args(data, out, short, "--allow-clamped")) == 0
    assert "warning:" in capsys.readouterr().err
    clamped = read_table(out).metadata["strip_draw_calibration"]["clamped_rows"]
    assert [r["row"] for r in clamped] == [3] and clamped[0]["clamped_lookups"] > 0


def test_ctrl_c_ends_the_fit_in_one_line_with_exit_130_and_nothing_left(tmp_path):
    """SIGINT to the command's process group (a terminal's Ctrl-C reaches its worker processes too) while the fit's
    draws run: one line on stderr, no traceback, exit code 130, no file in the output folder."""
    data = _write(tmp_path / "d.csv", [(p, 0.035, n, 0.1, 0.01) for p in (5e6, 10e6, 20e6, 25e6) for n in (1, 5)])
    out = tmp_path / "out" / "cal.npz"
    out.parent.mkdir()
    proc = subprocess.Popen([sys.executable, "-m", "tribocosim.cli", "calibrate", "--measured", str(data), "--out",
                             str(out), "--workers", "2", "--set", "n_elements=900"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    deadline = time.monotonic() + 120
    line = ""
    while "calibrating" not in line and time.monotonic() < deadline:
        line = proc.stderr.readline()
    time.sleep(1.0)  # within the first evaluation's draws (five passes of a 900-element strip at four pressures)
    assert proc.poll() is None
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    lines = [x for x in err.splitlines() if x.strip()]
    assert "Traceback" not in err and lines[-1].startswith("tribocosim calibrate: stopped by SIGINT"), err
    assert "nothing is written" in lines[-1] and list(out.parent.iterdir()) == []


def test_the_command_says_whether_its_standard_errors_are_scaled_by_the_reduced_chi2(tmp_path, tables, capsys):
    wide, _ = tables
    rows = _model_rows(wide, 0.6, [(5e6, 0.035, 1), (20e6, 0.035, 1), (10e6, 0.035, 1)])
    out = tmp_path / "cal.npz"
    assert main(_args(_write(tmp_path / "with.csv", rows), out, wide)) == 0
    assert "standard errors from the data's standard deviations, not scaled" in capsys.readouterr().out
    assert read_table(out).metadata["strip_draw_calibration"]["stderr_scaled_by_reduced_chi2"] is False
    without = _write(tmp_path / "without.csv", [r[:4] for r in rows], "pressure,tool_length,passes,mu_bar")
    assert main(_args(without, out, wide)) == 0
    assert "standard errors scaled by the reduced chi^2 = " in capsys.readouterr().out
    assert read_table(out).metadata["strip_draw_calibration"]["stderr_scaled_by_reduced_chi2"] is True
