"""The paper report's physics pieces (tribocosim.cosim.reports.paper_physics): alpha at small beta on a table of
known areas, the table variants of the budget, and the options' tests on the real model (the whole report runs in
.ci/run: tribocosim report paper --quick)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from tribocosim.components.stripdraw.table import FrictionTable
from tribocosim.errors import RangeWarning, TableError
from tribocosim.cosim.reports import paper, paper_physics as pp
from tribocosim.cosim.reports.paper_discriminators import coverage_without_sink


def _v3_table(alpha=400.0, clusters=0.01):
    p, v, b = np.array([1e6, 10e6, 30e6]), np.array([0.0, 0.08, 0.5]), np.array([0.0, 0.02, 0.1])
    ap = alpha * b[None, None, :] * p[:, None, None] / 55e9 * np.ones((3, 3, 3))
    ac = np.broadcast_to((p / 3e8)[:, None, None], (3, 3, 3)).copy()
    se = 0.1 * ap
    zeros = np.zeros((3, 3, 3))
    return FrictionTable(p, v, b, 0.15 * np.maximum(0.0, 1 - ap / ac), {"beta_threshold": 1.0, "calibration": {"mu0": 0.15}},
                         contact_area=ac, particle_area=ap, contact_area_std=zeros, particle_area_std=se,
                         extras={"simulated": np.ones((3, 3, 3)), "contact_area_se": zeros, "particle_area_se": se,
                                 "particle_area_clusters": clusters * ap, "particle_area_clusters_se": zeros})


def test_table_alpha_is_eq23_at_the_first_level_for_both_observables():
    t = _v3_table()
    a = pp.table_alpha(t, "particle_area")
    c = pp.table_alpha(t, "particle_area_clusters")
    assert [r["velocity"] for r in a] == [0.08, 0.5]
    assert all(r["alpha"] == pytest.approx(400.0) and r["stderr"] == pytest.approx(0.0, abs=1e-9) for r in a)
    assert all(r["alpha"] == pytest.approx(4.0) for r in c)


def test_simulated_velocities_leave_out_the_copied_v0_row_and_unsimulated_columns():
    from tribocosim.components.stripdraw.table import read_table
    from tribocosim.paths import DEFAULT_TABLE

    t = _v3_table()
    assert pp.simulated_velocities(t) == [0.08, 0.5]
    t.extras["simulated"][:, 2, :] = 0.0
    assert pp.simulated_velocities(t) == [0.08]
    shipped = read_table(DEFAULT_TABLE)
    if shipped.version == 2:  # the campaign velocities recorded in its metadata
        assert pp.simulated_velocities(shipped) == shipped.metadata["axes"]["velocity"]["campaign"]


def test_with_rows_of_takes_the_other_tables_shared_rows_interpolated_in_beta(tmp_path):
    """The other table's A_p is linear in beta, so its values on this table's beta axis are exact; rows the other
    table lacks (10 MPa, 0.5 m/s) keep their values, and mu follows the new areas."""
    from tribocosim.components.stripdraw.table import read_table

    t = _v3_table()
    p, v, b = np.array([1e6, 30e6]), np.array([0.0, 0.08]), np.array([0.0, 0.05, 0.12])
    ap = 300.0 * b[None, None, :] * p[:, None, None] / 55e9 * np.ones((2, 2, 3))
    ac = np.broadcast_to((p / 2e8)[:, None, None], (2, 2, 3)).copy()
    zeros = np.zeros((2, 2, 3))
    other = FrictionTable(p, v, b, 0.15 * (1 - ap / ac), {"beta_threshold": 1.0, "calibration": {"mu0": 0.15}},
                          contact_area=ac, particle_area=ap, contact_area_std=zeros, particle_area_std=zeros,
                          extras={"simulated": np.ones((2, 2, 3)), "contact_area_se": zeros, "particle_area_se": zeros,
                                  "particle_area_clusters": zeros, "particle_area_clusters_se": zeros})
    paths = pp.table_variants(t, tmp_path, {"domain_128": _write(tmp_path / "other.npz", other)})
    got = read_table(paths["domain_128"])
    for i, j in ((0, 0), (0, 1), (2, 0), (2, 1)):  # 1 and 30 MPa at v = 0 and 0.08 m/s
        pressure = t.pressure[i]
        np.testing.assert_allclose(got.particle_area[i, j], 300.0 * t.beta * pressure / 55e9, rtol=1e-12)
        np.testing.assert_allclose(got.contact_area[i, j], pressure / 2e8, rtol=1e-12)
    np.testing.assert_array_equal(got.particle_area[1], t.particle_area[1])
    np.testing.assert_array_equal(got.particle_area[:, 2], t.particle_area[:, 2])
    np.testing.assert_allclose(got.mu, 0.15 * np.maximum(0.0, 1 - got.particle_area / got.contact_area), rtol=1e-12)
    short = dataclasses.replace(other, beta=np.array([0.0, 0.05, 0.09]))
    with pytest.raises(TableError, match="does not span"):
        pp.with_rows_of(t, short)


def _write(path, table):
    from tribocosim.components.stripdraw.table import write_table

    write_table(path, table)
    return path


def test_ensemble_variants_move_a_p_by_one_standard_error(tmp_path):
    from tribocosim.components.stripdraw.table import read_table

    t = _v3_table()
    paths = pp.table_variants(t, tmp_path)
    low, high = read_table(paths["ensemble_low"]), read_table(paths["ensemble_high"])
    np.testing.assert_allclose(low.particle_area, 0.9 * t.particle_area, rtol=1e-12)
    np.testing.assert_allclose(high.particle_area, 1.1 * t.particle_area, rtol=1e-12)
    np.testing.assert_allclose(high.mu, 0.15 * (1 - high.particle_area / high.contact_area), rtol=1e-12)
    assert "pair_0" not in paths  # no campaign recorded


def test_options_calibrate_on_the_one_pass_drop_and_a_sink_leaves_less_debris(tmp_path):
    """On the real model with a table of known areas: each option reaches the 35 % one-pass drop with its own s;
    in the paper's model the debris on the strip grows pass by pass, and a debris sink leaves less after every
    pass."""
    from tribocosim.components.stripdraw.table import write_table

    path = tmp_path / "t.npz"
    write_table(path, _v3_table(alpha=3000.0))
    table = _v3_table(alpha=3000.0)
    runs = paper.Runs(workers=1)
    params = paper.config_params({"table_file": str(path)}, paper.Config("mesoscale", True))
    base = pp.calibrated_predictions(runs, params, table, paper.calibrate)
    sink = pp.calibrated_predictions(runs, {**params, "debris_sink_length": 0.035}, table, paper.calibrate)
    assert base["drops"][0] == pytest.approx(0.35, abs=2e-4) and sink["drops"][0] == pytest.approx(0.35, abs=2e-4)
    d = base["debris_g_m2"]
    assert d[2] > d[1] > d[0] > 0
    assert all(s < b for s, b in zip(sink["debris_g_m2"], base["debris_g_m2"]))
    assert sink["scale"] > base["scale"]  # less debris under the pad needs a larger A_p scale for the same 35 %
    # the debris is conserved without a sink: its mean over the strip that passed is K P D L_T / (H h_p (D + L_T))
    want = coverage_without_sink(25e6, 0.035, 1e-4, 0.8e9, 0.5e-6, 0.14)
    assert base["coverage"][0] == pytest.approx(want, rel=3e-3) and sink["coverage"][0] < 0.9 * want
    # mu >= r mu0 where flakes carry the contact: no drop beyond 1 - r mu0 / mu_bar(1 MPa), nor beyond 1 - r
    assert base["floor"] == pytest.approx(0.2 * 0.15)
    assert base["drops"][2] <= base["bound_3"] <= 1.0 - 0.2 and base["drop_140"] <= base["bound_140"] <= 0.8


def _v4_table(alpha=400.0):
    """_v3_table with a bent A_p (not the fit's form) and the fits a version 4 build records per row."""
    from tribocosim.surrogate.fit import fit_beta_forms

    t = _v3_table(alpha)
    ap = t.particle_area * (1.0 + 3.0 * t.beta)[None, None, :]
    meta = dict(t.metadata)
    rows = []
    for i, p in enumerate(t.pressure):
        for v in (0.08, 0.5):
            j = int(np.flatnonzero(t.velocity == v)[0])
            forms = fit_beta_forms(t.beta[1:], ap[i, j, 1:], 0.05 * ap[i, j, 1:])
            rows.append({"pressure": float(p), "velocity": v,
                         "particle_area": {f: fit.to_dict() for f, fit in forms.items()}})
    meta["fits"] = {"rows": rows}
    return dataclasses.replace(t, particle_area=ap, metadata=meta,
                               extras={**t.extras, "mu_se": np.zeros_like(ap)}), rows


def test_the_table_form_variant_holds_each_rows_fit_at_its_simulated_nodes():
    """A_p at every simulated node with flakes is its row's fit of smaller AIC (the v = 0 row the slowest row's);
    the particle-free nodes and A_c are as they were, mu follows."""
    from tribocosim.surrogate.fit import beta_form

    t, rows = _v4_table()
    f = pp.with_fitted_rows(t)
    for row in rows:
        i = int(np.flatnonzero(t.pressure == row["pressure"])[0])
        best = min(row["particle_area"].values(), key=lambda x: x["aic"])
        want = beta_form(best["form"], t.beta[1:], best["params"])
        for v in ((0.0, 0.08) if row["velocity"] == 0.08 else (0.5,)):
            j = int(np.flatnonzero(t.velocity == v)[0])
            np.testing.assert_allclose(f.particle_area[i, j, 1:], want, rtol=1e-12)
    assert not np.allclose(f.particle_area, t.particle_area)
    assert np.array_equal(f.particle_area[:, :, 0], t.particle_area[:, :, 0])
    assert np.array_equal(f.contact_area, t.contact_area)
    np.testing.assert_allclose(f.mu, 0.15 * (1 - f.particle_area / f.contact_area), rtol=1e-12)


def test_observable_evidence_gives_the_alpha_the_macro_model_needs_and_each_shares_alpha_eff(tmp_path):
    """alpha_needed: the closed-form law with alpha_b = alpha_needed and s = 1 gives the 35 % drop again (only s alpha
    enters); alpha_eff = (A_p / A_c) kappa / (h'_rms beta) at the first level, from the table's values."""
    from tribocosim.components.stripdraw.table import write_table

    t = _v3_table(alpha=3000.0, clusters=0.001)
    write_table(tmp_path / "t.npz", t)
    runs = paper.Runs(workers=1)
    params = paper.config_params({"table_file": str(tmp_path / "t.npz")}, paper.Config("mesoscale", True))
    with pytest.warns(RangeWarning, match="flake_shear_ratio = 0 with mu0"):  # the paper's model falls below the floor
        ev = pp.observable_evidence(runs, params, t, paper.calibrate)
        closed = {**params, "friction_model": "closed_form", "alpha_b": ev["alpha_needed"], "particle_area_scale": 1.0,
                  "flake_shear_ratio": 0.0}  # the paper's own macro model: frictionless flakes
        drop = paper._drops(runs, closed, [1.0])[0]
    assert drop == pytest.approx(0.35, abs=2e-4)
    i = int(np.flatnonzero(t.pressure == 30e6)[0])
    share = t.particle_area[i, 1, 1] / t.contact_area[i, 1, 1]
    assert ev["load_bearing"]["alpha_eff_max"] == pytest.approx(share * 2.0 / (0.34 * t.beta[1]), rel=1e-12)
    assert ev["clusters"]["alpha_eff_25mpa"] == pytest.approx(0.001 * ev["load_bearing"]["alpha_eff_25mpa"], rel=1e-9)
