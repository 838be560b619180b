"""``tribocosim export`` as a user runs it: its output, its exit codes, one line naming the option for bad input and
no file written, and what it imports."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tribocosim.components.stripdraw.friction import closed_form_table
from tribocosim.components.stripdraw.table import write_table
from tribocosim.cosim.apps.export_cli import main


def _cli(args, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "tribocosim.cli", "export", *args], cwd=cwd, capture_output=True,
                          text=True, timeout=300)


def test_an_export_prints_the_files_their_accuracy_and_the_range(tmp_path, capsys):
    assert main(["lsdyna", "-o", str(tmp_path / "friction.k"), "--beta", "0.1", "--band", "2"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert [line.split(" (")[0] for line in out if line.startswith("wrote")] == [
        f"wrote {tmp_path / name}" for name in ("friction.k", "friction.upper.k", "friction.lower.k")]
    assert all("reproduces tribocosim's mu within" in line for line in out if line.startswith("wrote"))
    assert out[-2] == "range: contact pressure 1-30 MPa, relative sliding velocity 0-500 mm/s"
    assert out[-1].startswith("beyond it: LS-DYNA holds the end values (clamps)")
    header = (tmp_path / "friction.k").read_text()
    assert "$   with: tribocosim export lsdyna -o" in header


@pytest.fixture(scope="module")
def table_without_standard_errors(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("table") / "closed_form.npz"
    write_table(path, closed_form_table(pressure=np.array([1e6, 3e7]), velocity=np.array([0.0, 0.5]),
                                        beta=np.array([0.0, 0.2])))
    return path


BAD = [
    (["nastran", "-o", "f.k", "--beta", "0.1"], "FORMAT 'nastran' is not an export format"),
    (["lsdyna", "-o", "f.k", "--beta", "1.5"], "--beta: beta = 1.5 is outside the table's beta axis"),
    (["lsdyna", "-o", "f.k", "--beta", "-0.1"], "--beta -0.1 is negative"),
    (["lsdyna", "-o", "f.k", "--beta", "nan"], "--beta nan is not finite"),
    (["lsdyna", "-o", "f.k", "--beta", "0.1", "--band", "nan"], "--band nan"),
    (["lsdyna", "-o", "f.k", "--beta", "0.1", "--band", "-2"], "--band -2.0"),
    (["lsdyna", "-o", "f.k", "--beta", "0.1", "--set", "mu0=-0.1"], "mu0 = -0.1 is out of range"),
    (["lsdyna", "-o", "f.k", "--beta", "0.1", "--pressure-range", "2", "nan"], "--pressure-range 2 nan MPa"),
    (["lsdyna", "-o", "missing/f.k", "--beta", "0.1"], "-o missing/f.k: its folder missing does not exist"),
    (["lsdyna", "-o", "f.k", "--passes", "3"], "--passes needs --pressure"),
    (["lsdyna", "-o", "f.k"], "FORMAT lsdyna needs a debris state"),
    (["lsdyna", "-o", "f.k", "--beta", "0.1", "--units", "inch"], "--units 'inch' is not a unit system"),
    (["lsdyna", "-o", "f.k", "--beta", "0.1", "--option", "nope"], "--option 'nope' is not a multi-pass option"),
    (["lsdyna", "--beta", "0.1"], "the following arguments are required: -o/--out"),
    (["lsdyna", "-o", "f.k", "--beta", "0.1", "--table", "nowhere.npz"], "friction table file not found"),
    (["abaqus", "-o", "f.inp", "--beta-levels", "0", "0.5", "0.1", "--calibration", "none"],
     "lookups in the exported range read friction-table nodes the mesoscale campaign did not simulate"),
    (["table", "-o", "f.json", "--beta-levels", "0", "0.5", "0.1", "--calibration", "none"],
     "the beta axis (--beta-levels 0 0.5 0.1): "),
    (["abaqus", "-o", "f.inp", "--beta-levels", "0", "0.5", "0.1"], "--beta-levels: 0.5 is outside the table's beta "
     "axis [0, 1.00092] or above the cap of beta in the range"),
    (["lsdyna", "-o", "f.k", "--slide", "20", "--beta", "0.1"], "--beta and --slide both given"),
    (["lsdyna", "-o", "f.k", "--slide", "20", "--passes", "2", "--pressure", "25"], "--passes and --slide both given"),
    (["lsdyna", "-o", "f.k", "--slide", "-1"], "--slide -1 mm is negative"),
    (["lsdyna", "-o", "f.k", "--slide", "abc"], "--slide 'abc' is not a number"),
    (["lsdyna", "-o", "f.k", "--slide", "inf"], "--slide inf is not finite"),
    (["lsdyna", "-o", "f.k", "--slide", "20", "--pressure", "25"], "--pressure describes the strip-draw test of "
     "--passes"),
    (["lsdyna", "-o", "f.k", "--slide", "20", "--set", "beta_initial=2"], "beta_initial = 2"),
    (["lsdyna", "-o", "f.k", "--beta", "0.1", "--calibration", "nowhere"], "--calibration nowhere: no such file, and "
     "not a calibration's name (none, paper)"),
    (["lsdyna", "-o", "f.k", "--beta", "0.1", "--calibration", "paper", "--set", "particle_area_scale=2"],
     "particle_area_scale=2.0 with the calibration paper: it sets the fitted scale itself"),
    (["vfriction", "-o", "f.f", "--slide", "20"], "--slide does not apply to FORMAT vfriction"),
    (["lsdyna", "-o", "f.k", "--beta", "0.1", "--set", "mu0=abc"], "--set mu0=abc: 'abc' is not a number"),
    (["lsdyna", "-o", "f.k", "--beta", "0.1", "--set", "mu0"], "--set 'mu0': expected NAME=VALUE"),
]


@pytest.mark.parametrize("args, message", BAD, ids=[m.split(":")[0][:30] for _, m in BAD])
def test_bad_input_is_one_line_naming_the_option_exit_2_and_no_file(tmp_path, monkeypatch, capsys, args, message):
    monkeypatch.chdir(tmp_path)
    assert main(args) == 2
    out, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("tribocosim export: "), err
    assert message in lines[0]
    assert out == "" and list(tmp_path.iterdir()) == []


def test_the_console_script_reports_bad_input_without_a_traceback(tmp_path):
    proc = _cli(["lsdyna", "-o", "f.k", "--beta", "0.5", "--calibration", "none"], tmp_path)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.startswith("tribocosim export: --beta 0.5: ") and len(proc.stderr.strip().splitlines()) == 1
    assert "--allow-unsimulated writes them marked" in proc.stderr and "Traceback" not in proc.stderr
    assert list(tmp_path.iterdir()) == []


def test_a_band_from_a_table_without_standard_errors_and_an_unwritable_output_write_nothing(
        tmp_path, table_without_standard_errors):
    proc = _cli(["lsdyna", "-o", "f.k", "--beta", "0.01", "--band", "2", "--table",
                 str(table_without_standard_errors)], tmp_path)
    assert proc.returncode == 2 and "--band needs a table with the ensemble standard errors" in proc.stderr
    (tmp_path / "blocker").write_text("a file where a folder is expected")
    proc = _cli(["table", "-o", "blocker/f.json", "--beta", "0.1"], tmp_path)
    assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1
    (tmp_path / "f.upper.k").mkdir()  # the band's second file cannot be written: none of the three is
    proc = _cli(["lsdyna", "-o", "f.k", "--beta", "0.1", "--band", "2"], tmp_path)
    assert proc.returncode == 2 and "-o" in proc.stderr and "is a folder" in proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["blocker", "f.upper.k"]


def test_the_command_imports_neither_numba_nor_the_mesoscale_code(tmp_path):
    script = ("import sys\n"
              "from tribocosim.cli import main\n"
              f"rc = main(['export', 'abaqus', '-o', {str(tmp_path / 'f.inp')!r}, '--passes', '1', '--pressure', "
              "'20', '--set', 'draw_length=0.035'])\n"
              "heavy = ('numba', 'pyfftw', 'tribocosim.surrogate')\n"
              "print(rc, [m for m in sys.modules if m.split('.')[0] in heavy or m.startswith(heavy)])\n")
    proc = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip().splitlines()[-1] == "0 []"
    assert (tmp_path / "f.inp").is_file()


def test_the_console_lists_the_command():
    proc = subprocess.run([sys.executable, "-m", "tribocosim.cli", "--help"], capture_output=True, text=True,
                          timeout=60)
    assert any(line.split()[:1] == ["export"] for line in proc.stdout.splitlines())


def test_mu_below_the_documented_floor_is_a_warning_naming_the_setting_and_the_file_is_written(tmp_path):
    """particle_area_scale = 2 makes the shipped table's flakes carry the whole contact inside its beta axis (the cap,
    where mu = r mu0). The default r = 0.2 gives the floor there, 0.2 x 0.15 = 0.03, and its band's lower file is
    clipped to it: no warning. The paper's model (--set flake_shear_ratio=0) goes to 0 there: one line on stderr
    per file naming flake_shear_ratio = 0, the exit code 0, the files written with the warning in their header."""
    import json

    from tribocosim.components.stripdraw.friction_floor import MU_FLOOR

    common = ["--set", "particle_area_scale=2", "--pressure-range", "5", "30"]
    proc = _cli(["table", "-o", "default.json", *common, "--band", "2"], tmp_path)
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    for name in ("default.json", "default.lower.json"):
        doc = json.loads((tmp_path / name).read_text())
        assert min(np.ravel(doc["mu"])) == pytest.approx(MU_FLOOR, rel=1e-9), name  # the cap is in the file
        assert doc["warnings"] == [], name
    proc = _cli(["table", "-o", "paper.json", *common, "--beta", "0.2", "--band", "2", "--set",
                 "flake_shear_ratio=0"], tmp_path)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert [line.split(": ")[2] for line in lines] == ["paper.json", "paper.upper.json", "paper.lower.json"], lines
    for line, name in zip(lines, ("paper.json", "paper.upper.json", "paper.lower.json")):
        assert line.startswith(f"tribocosim export: warning: {name}: the least value: mu = ")
        assert "is below the documented floor 0.03" in line
        assert "flake_shear_ratio = 0 with mu0 = 0.15 lets mu fall to 0 where flakes carry the whole contact" in line
        doc = json.loads((tmp_path / name).read_text())
        least = min(np.ravel(doc["mu"]))
        assert least < MU_FLOOR and f"mu = {least:.4g} is below" in line, (least, line)
        assert doc["warnings"] == [line.split(f"{name}: ", 1)[1]]
        assert any("WARNING: the least value: mu =" in h for h in doc["header"]), doc["header"]


def test_a_slide_at_one_velocity_and_the_note_on_an_uncalibrated_law(tmp_path, capsys):
    """--slide 20 with the default (calibrated) law: the output says the file holds one velocity and why, nothing on
    stderr; the campaign's law (--calibration none) adds one note line with its one-pass drop, computed."""
    from tribocosim.components.friction_export.exported_law import load_law
    from tribocosim.cosim.apps.paper_calibration import one_pass_drop

    assert main(["lsdyna", "-o", str(tmp_path / "f.k"), "--slide", "20"]) == 0
    out, err = capsys.readouterr()
    lines = out.splitlines()
    assert err == "" and "(nominal; " in lines[0] and "x 1 velocity (mu does not depend on it))" in lines[0]
    assert lines[1].startswith("velocity: mu does not depend on the relative sliding velocity over 0-500 mm/s")
    assert "LS-DYNA curve has two points or more" in lines[1]
    assert lines[-2] == "range: contact pressure 1-30 MPa, relative sliding velocity 0-500 mm/s"
    for fmt, name in (("table", "g.json"), ("vfriction", "r.f")):
        assert main([fmt, "-o", str(tmp_path / name), "--calibration", "none"]) == 0
        out, err = capsys.readouterr()
        (line,) = err.strip().splitlines()
        assert line.startswith("tribocosim export: note: the law is the mesoscale campaign's (friction_table.npz), "
                               "uncalibrated")
        assert f"is {100 * one_pass_drop(load_law()):.1f} %, where the paper measures 35 %" in line
    assert main(["usrfrc", "-o", str(tmp_path / "u.f")]) == 0
    assert capsys.readouterr().err == ""
    assert "calibration paper (calibration_paper.json" in (tmp_path / "u.f").read_text().replace("\nC     ", " ")


def test_the_help_says_the_law_is_calibrated_by_default(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "The law is calibrated by default" in text and "--slide S [S ...]" in text
    assert "paper (the default, without --table and --set particle_area_scale" in text


def test_the_option_help_names_every_multi_pass_option_and_each_is_accepted(tmp_path, capsys):
    """The --option help lists the options the code defines (one list: multipass_options.OPTIONS), and each name
    it lists exports."""
    from tribocosim.components.stripdraw.multipass_options import option_names

    with pytest.raises(SystemExit):
        main(["table", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    listed = help_text.split("a multi-pass option of the paper report (", 1)[1].split(")", 1)[0]
    assert [name.strip() for name in listed.split(",")] == list(option_names())
    for name in option_names():
        assert main(["table", "-o", str(tmp_path / f"{name}.json"), "--beta", "0.1", "--option", name]) == 0, name
