"""Tests of ``tribocosim report``: the files each report writes, and the "not available yet" lines."""

import csv
import json

import pytest

from tribocosim.cosim.apps import report_cli
from tribocosim.cosim.reports import accuracy, stability_report
from tribocosim.cosim.reports.common import Family, timed


def test_accuracy_report_writes_markdown_csv_png_and_names_missing_pieces(tmp_path):
    out = tmp_path / "acc"
    rc = report_cli.main(["accuracy", "--quick", "--quiet", "--out", str(out), "--only", "bem", "surrogate",
                          "--surrogate-results", str(tmp_path / "absent.json")])
    assert rc == 0
    md = (out / "accuracy.md").read_text()
    assert "## Summary: the cheapest setting reaching each error" in md
    assert "not available yet: no result of the hold-out measurement" in md
    rows = list(csv.DictReader(open(out / "bem.csv")))
    assert [int(r["n"]) for r in rows] == [64, 128, 256, 512]
    errors = [float(r["error"]) for r in rows[:-1]]
    assert errors == sorted(errors, reverse=True) and errors[-1] < 0.01  # converges towards the finest grid
    assert (out / "bem.png").stat().st_size > 1000
    meta = json.loads((out / "accuracy.json").read_text())
    assert meta["families"]["surrogate"]["available"] is False and meta["mode"] == "quick"


def test_stability_report_matrix_with_reasons(tmp_path, monkeypatch):
    """The matrix, the verdict notes and the bisection lines, on a family with known content."""
    from tribocosim.cosim.reports.stability_criterion import StepLimit, Verdict

    @timed
    def fake(settings):
        fam = Family("fake", "Fake cases")
        fam.note = "two cases"
        lim = StepLimit(1e-3, 1.1e-3, "growing oscillation in x: peak ratio 1.01 per period", 5)
        for case in ("soft", "stiff"):
            v = Verdict("stable") if case == "soft" else Verdict("unstable", "non-finite x (nan) at t = 0.5 s")
            fam.rows.append(stability_report._cell_row(case, "jacobi/0", v, lim))
            fam.rows.append(stability_report._cell_row(case, "iterative/1", Verdict("error", "CosimStepError: boom"),
                                                       StepLimit(0.0, 1e-6, "boom", 1)))
        return fam

    monkeypatch.setattr(stability_report, "FAMILIES", {"fake": fake})
    assert report_cli.main(["stability", "--quick", "--quiet", "--out", str(tmp_path), "--only", "fake"]) == 0
    md = (tmp_path / "stability.md").read_text()
    assert "| case | jacobi/0 | iterative/1 |" in md
    assert "| soft | stable<br>h_max = 0.001 s | **error** [1]<br>h_max < 1e-06 s |" in md
    assert "non-finite x (nan) at t = 0.5 s" in md and "CosimStepError: boom" in md
    assert "ratio of successive peak amplitudes" in md  # the definition is stated
    assert (tmp_path / "fake.csv").exists() and (tmp_path / "fake.png").exists()


def test_stability_cells_of_iterative_coupling_show_the_observed_contraction(tmp_path, monkeypatch):
    from tribocosim.cosim.reports.stability_criterion import Verdict

    @timed
    def fake(settings):
        fam = Family("fake", "Fake cases")
        fam.rows.append(stability_report._cell_row("near p_crit", "jacobi/0", Verdict("stable"), None))
        fam.rows.append(stability_report._cell_row("near p_crit", "iterative/0", Verdict(
            "stable", extra={"observed_contraction": 0.04621785}), None))
        fam.rows.append(stability_report._cell_row("near p_crit", "iterative/1", Verdict(
            "error", "ConvergenceError: did not converge", extra={"observed_contraction": 0.873}), None))
        return fam

    monkeypatch.setattr(stability_report, "FAMILIES", {"fake": fake})
    assert report_cli.main(["stability", "--quick", "--quiet", "--out", str(tmp_path), "--only", "fake"]) == 0
    md = (tmp_path / "stability.md").read_text()
    assert "| near p_crit | stable | stable, rho_obs = 0.046 | **error** [1], rho_obs = 0.87 |" in md, md
    assert "`rho_obs`, the largest contraction factor observed" in md


def test_unknown_family_is_refused(capsys):
    assert report_cli.main(["accuracy", "--out", "x", "--only", "nope"]) == 2
    assert "unknown family nope" in capsys.readouterr().err


def test_every_family_is_a_function_of_the_settings_alone():
    for fams in (accuracy.FAMILIES, stability_report.FAMILIES):
        for fn in fams.values():
            assert callable(fn)
    with pytest.raises(SystemExit):
        report_cli.main(["--help"])


def test_surrogate_family_reads_the_hold_out_result_of_bench_table(tmp_path):
    """The JSON format written by benchmarks/bench_table.py: one row per grid."""
    from pathlib import Path

    from tribocosim.cosim.reports.common import Settings

    data = {"holdout_points": 18, "load_before": "loadavg 1.0",
            "grids": [{"grid": g, "pressures_mpa": list(range(n_p)), "velocities": list(range(n_v)), "cases": c,
                       "case_core_seconds": cost, "fit_and_table_s": 0.5, "rms_error": err / 2, "max_abs_error": err,
                       "holdout_mean_std_error_of_mean": 1e-4, "mu_at_10mpa_0p08": [0.15, 0.14]}
                      for g, n_p, n_v, c, cost, err in (("coarse", 2, 2, 12, 100.0, 0.015), ("fine", 5, 5, 75, 900.0, 1.2e-4))]}
    path = tmp_path / "bench_table.json"
    path.write_text(json.dumps(data))
    fam = accuracy.surrogate(Settings(True, Path(tmp_path)), path)
    assert fam.available and [r["setting"] for r in fam.rows] == ["coarse (2 P x 2 v)", "fine (5 P x 5 v)"]
    assert fam.rows[0]["error"] == pytest.approx(0.1) and fam.rows[1]["error"] == pytest.approx(8e-4)
    assert fam.rows[1]["build_core_seconds"] == pytest.approx(900.5)
