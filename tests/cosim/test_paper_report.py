"""The paper report's pieces (tribocosim.cosim.reports.paper): the root finder of the one-number calibration
against closed-form functions, the ensemble standard error against its formula on a table of constant
values, the figures' numbers from known curves, the run cache on the real model, and the refusal of a
version 1 table. The whole report runs in .ci/run (``tribocosim report paper --quick``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tribocosim.errors import TribocosimError
from tribocosim.components.stripdraw.friction import closed_form_table
from tribocosim.components.stripdraw.table import FrictionTable, write_table
from tribocosim.cosim.apps.report_cli import main as report_main
from tribocosim.cosim.reports import paper
from tribocosim.cosim.studies.stripdraw_experiment import Point, mu_bar


@pytest.mark.parametrize("rate, start", [(1.0, 1.0), (100.0, 1.0), (0.01, 1.0), (3.0, 1e-3)])
def test_solve_increasing_finds_the_root_of_a_saturating_curve(rate, start):
    calls = []

    def f(x):
        calls.append(x)
        return 1.0 - math.exp(-rate * x)

    x, reached = paper.solve_increasing(f, 0.35, 1e-6, start)
    exact = -math.log(0.65) / rate
    assert abs(reached - 0.35) < 1e-6
    assert abs(x - exact) <= 1e-6 / (rate * 0.65) * 1.01  # |f(x) - 0.35| < tol: |x - exact| < tol / f'(x)
    assert len(calls) < 40


def test_solve_increasing_names_an_unreachable_target():
    with pytest.raises(TribocosimError, match="stays below the target 0.35"):
        paper.solve_increasing(lambda x: 0.2 * (1.0 - math.exp(-x)), 0.35, 1e-6)


def _constant_table(ap, ap_std, ac, ac_std, members, measured_max=0.1):
    p, v, b = np.array([1e6, 30e6]), np.array([0.0, 2.0]), np.array([0.0, 0.05, 0.1, 0.2])
    shape = (2, 2, 4)
    full = lambda x: np.full(shape, float(x))  # noqa: E731
    meta = {"beta_threshold": 1.0, "ensemble": {"n_members": full(members).tolist()},
            "axes": {"beta": {"measured_max": measured_max}}}
    return FrictionTable(p, v, b, full(0.1), meta, contact_area=full(ac), particle_area=full(ap),
                         contact_area_std=full(ac_std), particle_area_std=full(ap_std))


def test_ensemble_standard_error_is_std_over_root_members_relative_to_the_mean():
    table = _constant_table(ap=0.02, ap_std=0.004, ac=0.1, ac_std=0.01, members=3)
    rel_ap, rel_ac = 0.004 / (math.sqrt(3) * 0.02), 0.01 / (math.sqrt(3) * 0.1)
    assert paper.ensemble_rel_stderr(table, "eq8") == pytest.approx(rel_ap, rel=1e-12)
    assert paper.ensemble_rel_stderr(table, "mesoscale") == pytest.approx(math.hypot(rel_ap, rel_ac), rel=1e-12)
    single = _constant_table(ap=0.02, ap_std=0.004, ac=0.1, ac_std=0.01, members=1)
    assert paper.ensemble_rel_stderr(single, "eq8") == 0.0  # one member: no spread to speak of


def test_ensemble_standard_error_of_a_version_4_table_is_its_tabulated_standard_errors():
    """The relative standard errors the table holds (A_p 5 %, A_c 2 %) at the levels whose lookups at 25 MPa read
    simulated nodes only (the top level is not simulated at 30 MPa and is left out)."""
    p, v, b = np.array([1e6, 20e6, 30e6]), np.array([0.0, 0.08]), np.array([0.0, 0.05, 0.1, 0.2])
    full = np.ones((3, 2, 4))
    ap, ac = 0.02 * full * b, 0.1 * full
    sim = full.copy()
    sim[2, :, 3] = 0.0
    extras = {"simulated": sim, "contact_area_se": 0.02 * ac, "particle_area_se": 0.05 * ap,
              "particle_area_clusters": 0 * ap, "particle_area_clusters_se": 0 * ap, "mu_se": 0 * ap}
    table = FrictionTable(p, v, b, 0.15 * (1 - ap / ac), {"beta_threshold": 1.0}, contact_area=ac, particle_area=ap,
                          contact_area_std=0 * ac, particle_area_std=0 * ap, extras=extras)
    assert table.version == 4
    assert paper.ensemble_rel_stderr(table, "eq8") == pytest.approx(0.05, rel=1e-9)
    assert paper.ensemble_rel_stderr(table, "mesoscale") == pytest.approx(math.hypot(0.05, 0.02), rel=1e-9)


def _figures(grid, mu):
    """Rows of every figure from ``mu(figure, series value, pass, pressure_mpa)``."""
    extra = {"beta_max": 0.1, "table_clamps": 0}
    return {
        "fig19b": [{"tool_length": L, "pressure_mpa": P, "mu_bar": mu("pad", L, 1, P), **extra}
                   for L in grid.pads for P in grid.pressures],
        "fig2b": [{"pass": k, "pressure_mpa": P, "mu_bar": mu("pass", k, k, P), **extra}
                  for k in range(1, grid.passes + 1) for P in grid.pressures],
        "fig17b": [{"zeta": z, "pressure_mpa": P, "mu_bar": mu("zeta", z, 1, P), **extra}
                   for z in grid.zetas for P in grid.trend_pressures],
        "fig18b": [{"archard_k": K, "pressure_mpa": P, "mu_bar": mu("k", K, 1, P), **extra}
                   for K in grid.ks for P in grid.trend_pressures],
    }


def test_metrics_of_known_curves():
    grid = paper.FULL

    def mu(kind, value, k, P):
        if kind == "pad":  # drop grows with the pad: 0.15 (1 - c L P / 25)
            return 0.15 * (1.0 - 4.0 * value * (P - 1) / 24)
        if kind == "pass":
            return 0.15 * (1.0 - 0.2 * k * (P - 1) / 24)
        if kind == "zeta":
            return 0.15 - 0.01 * value * P / 30
        return 0.15 - 0.05 * (1 - math.exp(-value / 1e-4)) * P / 30  # K: saturates above 1e-4

    m = paper.metrics(_figures(grid, mu), grid)
    assert m["drop_at_mpa"] == 25
    assert m["drop_by_pad"][0.035] == pytest.approx(4 * 0.035)
    assert m["drop_by_pad"][0.14] == pytest.approx(4 * 0.14)
    assert m["drop_1pass"] == pytest.approx(0.2) and m["drop_by_pass"][3] == pytest.approx(0.6)
    assert m["pad_order_holds"] == [7, 7]
    assert m["zeta_falls"] and m["k_falls"] and m["k_saturates"]

    flat = paper.metrics(_figures(grid, lambda kind, value, k, P: 0.15), grid)
    assert flat["drop_1pass"] == 0 and flat["pad_order_holds"] == [0, 7]
    assert not flat["zeta_falls"] and not flat["k_falls"]


def test_runs_share_one_test_between_figures_and_passes():
    """Points that differ only in the passes asked for run once, with the most passes; pass 1 of that run is
    the one-pass test."""
    runs = paper.Runs(workers=1)
    params = paper._params({}, paper.Config("mesoscale", False), 1.0)
    one, three = Point(10e6, 0.035, 1, params), Point(10e6, 0.035, 2, dict(params))
    runs.run([one, three])
    assert runs.evaluations == 2
    runs.run([one])
    assert runs.evaluations == 2
    first, second = runs.mu(one), runs.mu(three, 2)
    assert first == mu_bar(Point(10e6, 0.035, 1, params))[0]
    assert second < first  # the second pass starts from the first's debris
    assert runs.result(three, 2)["beta_max"] > runs.result(one)["beta_max"] > 0


def test_report_refuses_a_version_1_table(tmp_path, capsys):
    base = closed_form_table()
    v1 = tmp_path / "v1.npz"
    write_table(v1, FrictionTable(base.pressure, base.velocity, base.beta, base.mu, dict(base.metadata)))
    assert report_main(["paper", "--quick", "--out", str(tmp_path / "out"), "--table", str(v1)]) == 2
    err = capsys.readouterr().err
    assert f"friction table {v1} is format version 1" in err and "need version 2 or 3" in err
