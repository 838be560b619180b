"""Tests of surrogate.table_build: the areas and mu = mu0 (1 - A_p / A_c) on the grid from synthetic
campaign records, the rows below the campaign's velocities, the beta extension and threshold, the
metadata, and the round trip through the table format (hash and version checks)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tribocosim.components.errors import TableError
from tribocosim.components.stripdraw.table import FrictionTable, read_table, write_table
from tribocosim.surrogate.campaign import expand_cases
from tribocosim.surrogate.fit import alpha_law
from tribocosim.surrogate.sweep import parse_sweep
from tribocosim.surrogate.table_build import build_table, compare_tables, describe, plot_table, surface_statistics

E_STAR, P_CRIT = 55e9, 340e6
B, VREF = 300.0, 4.0  # beta_thres = E*/(p_crit b) = 0.54 < 1

SWEEP = """
name = "synthetic"
[grid]
pressure = [5e6, 10e6, 30e6]
velocity = [1.0, 5.0, 50.0]
seeds = [1, 2, 3]
[[flakes]]
count = 2
diameter = 12e-6
[[flakes]]
count = 4
diameter = 12e-6
[slide]
n = 16
size = 64e-6
wavelength_ratio = 0.25
[table]
mu0 = 0.15
low_velocities = [0.0, 0.08]
beta_extension = 3
"""


def campaign(noise=0.03, seed=0, alpha=lambda v: alpha_law(v, B, VREF)):
    """Manifest and finished records of SWEEP with A_p = alpha(v) beta P/E*, A_c = P/p_crit (+ noise)."""
    sweep = parse_sweep(SWEEP)
    cases = expand_cases(sweep)
    rng = np.random.default_rng(seed)
    records = []
    for c in cases:
        lab = c.labels
        ap = float(alpha(lab["velocity"])) * lab["beta"] * lab["pressure"] / E_STAR
        ac = lab["pressure"] / P_CRIT
        records.append({"case_id": c.case_id, "labels": lab, "wall_s": 1.0, "code_version": "test",
                        "summary": {"mean_particle_fraction": ap * (1 + noise * rng.standard_normal()),
                                    "mean_contact_fraction": ac * (1 + noise * rng.standard_normal())}})
    manifest = {"sweep": sweep.to_dict(), "cases": [{"case_id": c.case_id, "labels": c.labels} for c in cases]}
    return manifest, records


@pytest.fixture(scope="module")
def built():
    manifest, records = campaign()
    stats = surface_statistics(manifest["sweep"]["slide"], manifest["sweep"]["surfaces"])
    table, fits = build_table(records, manifest, surface_stats=stats)
    return manifest, records, table, fits


def test_axes_are_campaign_grid_plus_low_velocities_and_beta_nodes(built):
    manifest, _, t, _ = built
    assert_allclose(t.pressure, [5e6, 10e6, 30e6])
    assert_allclose(t.velocity, [0.0, 0.08, 1.0, 5.0, 50.0])
    levels = [f["beta"] for f in manifest["sweep"]["flakes"]]
    assert_allclose(t.beta[:3], [0.0] + levels)
    assert len(t.beta) == 3 + 3 and t.beta[-1] == pytest.approx(t.beta_threshold)
    assert t.metadata["axes"]["beta"]["extrapolated"] == pytest.approx(list(t.beta[3:]))


def test_campaign_nodes_hold_the_member_areas_and_mu_from_them(built):
    """Version 2: the ensemble means and member stds of A_c/A0 and A_p/A0 of every campaign node, and
    mu = mu0 (1 - <A_p> / <A_c>) (Eq. 7 with tau0 set by mu0): mu0 exactly where there is no debris."""
    _, records, t, fits = built
    std = lambda x: float(np.std(x, ddof=1)) if len(x) > 1 else 0.0  # noqa: E731 - the members' spread
    assert t.version == 2
    assert t.metadata["calibration"]["tau0"] == pytest.approx(0.15 / fits.contact.slope)
    for i, p in enumerate(t.pressure):
        for j, v in enumerate(t.velocity):
            if v < 1.0:
                continue
            for k, b in enumerate(t.beta[:3]):
                mem = [r["summary"] for r in records if r["labels"]["pressure"] == p
                       and r["labels"]["velocity"] == v and abs(r["labels"]["beta"] - b) <= 1e-9 * b]
                ap = np.array([m["mean_particle_fraction"] for m in mem])
                ac = np.array([m["mean_contact_fraction"] for m in mem])
                assert t.particle_area[i, j, k] == pytest.approx(ap.mean(), rel=1e-12)
                assert t.contact_area[i, j, k] == pytest.approx(ac.mean(), rel=1e-12)
                assert t.contact_area_std[i, j, k] == pytest.approx(std(ac), rel=1e-9, abs=1e-18)
                assert t.mu[i, j, k] == pytest.approx(0.15 * (1 - ap.mean() / ac.mean()), rel=1e-12)
                assert t.metadata["ensemble"]["mu_std"][i][j][k] == pytest.approx(std(0.15 * (1 - ap / ac)), rel=1e-9,
                                                                                abs=1e-15)
    assert_allclose(t.mu[:, :, 0], 0.15, rtol=0, atol=0)


def test_low_velocity_rows_follow_the_fitted_alpha_law(built):
    _, records, t, fits = built
    law = fits.law
    j_min = list(t.velocity).index(1.0)
    assert list(t.velocity[:j_min]) == [0.0, 0.08]
    # v = 0: alpha(0) = 0, no debris effect: A_p = 0, A_c the members' at v_min, mu = mu0
    for i, p in enumerate(t.pressure):
        for k in (1, 2):
            ac = [r["summary"]["mean_contact_fraction"] for r in records if r["labels"]["pressure"] == p
                  and r["labels"]["velocity"] == 1.0 and abs(r["labels"]["beta"] - t.beta[k]) <= 1e-9 * t.beta[k]]
            assert t.contact_area[i, 0, k] == pytest.approx(np.mean(ac), rel=1e-12)
            assert t.particle_area[i, 0, k] == 0.0 and t.mu[i, 0, k] == 0.15
    # v = 0.08: A_p = A_p(v_min) alpha(v)/alpha(v_min), A_c = A_c(v_min)
    r = float(law(0.08)) / float(law(1.0))
    assert_allclose(t.particle_area[:, 1, :], r * t.particle_area[:, j_min, :], rtol=1e-12, atol=0)
    assert_allclose(t.contact_area[:, 1, :], t.contact_area[:, j_min, :], rtol=0, atol=0)
    assert 0 < r < 1
    assert t.metadata["axes"]["velocity"]["below_campaign_policy"] == "alpha_law"


def test_low_velocity_rows_hold_the_slowest_row_when_alpha_falls_with_v():
    """A campaign whose alpha falls with v (as our meso model's does) cannot be extrapolated with
    the saturating law: the rows below the campaign repeat the v_min row exactly, and say why."""
    manifest, records = campaign(alpha=lambda v: 200.0 - 2.0 * v)  # 198, 190, 100
    stats = surface_statistics(manifest["sweep"]["slide"], manifest["sweep"]["surfaces"])
    t, fits = build_table(records, manifest, surface_stats=stats)
    assert fits.alpha[0].alpha > fits.alpha[-1].alpha
    j_min = list(t.velocity).index(1.0)
    for j in range(j_min):
        assert_allclose(t.mu[:, j, :], t.mu[:, j_min, :], rtol=0, atol=0)
    vel = t.metadata["axes"]["velocity"]
    assert vel["below_campaign_policy"] == "hold"
    assert "does not rise" in vel["below_campaign_policy_reason"]
    assert "held" in vel["note"]


def test_beta_extension_is_linear_and_threshold_is_eq24(built):
    _, _, t, fits = built
    alpha_max = max([fits.law.b] + [a.alpha for a in fits.alpha])
    assert t.beta_threshold == pytest.approx(min(1.0, fits.contact.slope * E_STAR / alpha_max), rel=1e-12)
    assert fits.law.b == pytest.approx(B, rel=0.1) and fits.law.v_ref == pytest.approx(VREF, rel=0.3)
    # on the extension mu is linear in beta (A_p linear, A_c constant) and reaches ~0 at beta_thres
    assert t.beta_threshold < 1
    ext = t.beta[3:]
    for i in range(len(t.pressure)):
        for j in range(len(t.velocity)):
            y = t.mu[i, j, 3:]
            coef = np.polyfit(ext, y, 1)
            assert_allclose(np.polyval(coef, ext), y, atol=1e-12)
    # at 50 m/s alpha ~ b, so A_p ~ A_c at beta_thres: mu ~ 0 (up to the noise)
    assert np.all(t.mu[:, -1, -1] < 0.1 * t.mu[:, -1, 0])
    assert np.all(t.mu >= 0)


def test_metadata_has_provenance_fits_units_seeds_and_surfaces(built):
    _, _, t, _ = built
    m = t.metadata
    assert m["provenance"] == "mesoscale"
    assert m["axes"]["pressure"]["unit"] == "Pa" and m["axes"]["velocity"]["unit"] == "m/s"
    assert "0.08 m/s" in m["axes"]["velocity"]["note"] and "NOT simulated" in m["axes"]["velocity"]["note"]
    assert m["campaign"]["seeds"] == [1, 2, 3] and m["campaign"]["sweep"]["name"] == "synthetic"
    fits = m["fits"]
    assert len(fits["alpha_per_velocity"]) == 3 and {"b", "b_err", "v_ref", "v_ref_err", "r2"} <= set(fits["alpha_law"])
    assert {"slope", "kappa", "r2"} <= set(fits["contact_area"])
    pair = m["surfaces"]["pairs"][0]
    assert pair["sheet"]["rms_height"] == pytest.approx(1.4e-6, rel=1e-9)
    assert pair["tool"]["rms_height"] == pytest.approx(0.6e-6, rel=1e-9)
    assert m["code_version"] and m["created"].endswith("Z")
    json.dumps(m, allow_nan=False)  # strict JSON


def test_round_trip_through_the_file_format_with_hash(built, tmp_path):
    _, _, t, _ = built
    path = tmp_path / "t.npz"
    digest = write_table(path, t)
    back = read_table(path)
    assert back.metadata["content_hash"] == digest == back.content_hash()
    for name in ("pressure", "velocity", "beta", "mu"):
        assert np.array_equal(getattr(back, name), getattr(t, name))
    assert compare_tables(back, t)["max_abs_diff"] == 0.0
    # interpolation on the grid nodes is exact
    P, V, Bt = np.meshgrid(back.pressure, back.velocity, back.beta, indexing="ij")
    mu, clamped = back.interpolate(P, V, Bt, "error")
    assert np.array_equal(mu, back.mu) and not clamped.any()
    for i, p in enumerate(back.pressure):  # the single-pressure path of the strip-draw model
        mu_p, _ = back.interpolate(p, V[0], Bt[0], "error")
        assert np.array_equal(mu_p, back.mu[i])
    text = describe(back)
    assert "alpha(v)" in text and "v = 0.08 m/s" in text and digest in text
    plot_table(back, tmp_path / "mu.png")
    assert (tmp_path / "mu.png").stat().st_size > 1000


def test_tampered_or_wrong_version_table_is_refused(built, tmp_path):
    _, _, t, _ = built
    path = tmp_path / "t.npz"
    write_table(path, t)
    with np.load(path) as d:
        arrays = {k: d[k] for k in d.files}
    mu = arrays["mu"].copy()
    mu[0, 0, 0] += 1e-9
    np.savez(tmp_path / "bad.npz", **{**arrays, "mu": mu})
    with pytest.raises(TableError, match="hash"):
        read_table(tmp_path / "bad.npz")
    meta = json.loads(str(arrays["metadata"]))
    meta["format_version"] = 99
    np.savez(tmp_path / "v99.npz", **{**arrays, "metadata": np.array(json.dumps(meta))})
    with pytest.raises(TableError, match="version 99"):
        read_table(tmp_path / "v99.npz")


def test_missing_grid_point_is_an_error_naming_it():
    manifest, records = campaign()
    drop = [r for r in records if not (r["labels"]["pressure"] == 10e6 and r["labels"]["velocity"] == 5.0
                                       and r["labels"]["n_flakes"] == 2)]
    with pytest.raises(TableError, match=r"P = 1e\+07 Pa, v = 5 m/s"):
        build_table(drop, manifest, surface_stats={"gap_rms_slope_mean": 0.3, "pairs": []})
    # one member missing is fine: the point keeps the others, and the metadata count them
    one_less = records[:]
    idx = next(i for i, r in enumerate(records) if r["labels"]["seed"] == 2)
    del one_less[idx]
    t, _ = build_table(one_less, manifest, surface_stats={"gap_rms_slope_mean": 0.3, "pairs": []},
                       failed=[{"case_id": records[idx]["case_id"], "labels": records[idx]["labels"],
                                "error": {"message": "boom"}}])
    n_mem = np.array(t.metadata["ensemble"]["n_members"])
    lab = records[idx]["labels"]
    i, j = list(t.pressure).index(lab["pressure"]), list(t.velocity).index(lab["velocity"])
    k = int(np.argmin(np.abs(t.beta - lab["beta"])))
    assert n_mem[i, j, k] == 2 and n_mem[i, j, 1:3].sum() == 5
    assert t.metadata["campaign"]["cases_failed"][0]["error"] == "boom"


def test_compare_tables_against_recorded_std(built):
    _, _, t, _ = built
    m2 = t.mu.copy()
    pixel = t.metadata["calibration"]["tau0"] / (t.pressure[1] * 16**2)
    m2[1, -1, 1] += 10 * max(t.metadata["ensemble"]["mu_std"][1][-1][1], pixel)
    m2[0, 0, 0] += 0.5 * t.metadata["calibration"]["tau0"] / (t.pressure[0] * 16**2)  # half a pixel
    other = FrictionTable(t.pressure, t.velocity, t.beta, m2, t.metadata)
    res = compare_tables(t, other)
    assert not res["within_uncertainty"] and res["nodes_beyond_tolerance"] == 1
    assert compare_tables(t, t)["within_uncertainty"]


def test_compare_reads_a_rebuilds_extension_on_the_first_tables_nodes(built):
    """The extrapolated beta nodes end at the fitted beta_thres, so a rebuild places them elsewhere:
    a table with 5 extension nodes instead of 3, from the same (noise-free) campaign, lies on the same
    lines A_p ~ beta, A_c constant, so compare finds no difference at the first table's nodes."""
    import copy

    manifest, records = campaign(noise=0.0)
    stats = surface_statistics(manifest["sweep"]["slide"], manifest["sweep"]["surfaces"])
    a, _ = build_table(records, manifest, surface_stats=stats)
    m5 = copy.deepcopy(manifest)
    m5["sweep"]["table"]["beta_extension"] = 5
    b, _ = build_table(records, m5, surface_stats=stats)
    assert b.beta.size == a.beta.size + 2
    res = compare_tables(a, b)
    assert res["within_uncertainty"] and res["max_abs_diff"] < 1e-15
    assert res["particle_area_max_abs_diff"] < 1e-15 and res["beta_threshold"]["abs_diff"] == 0.0


def test_compare_flags_a_threshold_outside_its_standard_error(built):
    """alpha 1.5 x larger moves beta_thres = s_c E*/alpha to 2/3 of its value, far beyond the standard
    error of a 3 % noise campaign: compare says so; different debris levels cannot be compared."""
    manifest, records, a, _ = built
    stats = surface_statistics(manifest["sweep"]["slide"], manifest["sweep"]["surfaces"])
    m2, r2 = campaign(alpha=lambda v: 1.5 * alpha_law(v, B, VREF))
    b, _ = build_table(r2, m2, surface_stats=stats)
    assert b.beta_threshold == pytest.approx(a.beta_threshold / 1.5, rel=0.05)
    res = compare_tables(a, b)
    thr = res["beta_threshold"]
    assert 0.0 < thr["tolerance"] < thr["abs_diff"] and not res["within_uncertainty"]
    other = FrictionTable(a.pressure, a.velocity, np.r_[a.beta[0], 0.5 * a.beta[1:]], a.mu, a.metadata)
    with pytest.raises(TableError, match="different beta axes"):
        compare_tables(a, other)


def test_out_of_range_queries_follow_the_recorded_policy(built):
    from tribocosim.components.errors import TableDomainError

    _, _, t, _ = built
    assert t.metadata["out_of_range_policy"].startswith("clamp")
    mu, clamped = t.interpolate(40e6, 0.08, 0.0, "clamp")
    assert clamped.all() and mu == pytest.approx(t.interpolate(30e6, 0.08, 0.0, "clamp")[0])
    with pytest.raises(TableDomainError, match=r"pressure = 4000000.0 Pa is outside the table.s range \[5e\+06, 3e\+07\]"):
        t.interpolate(4e6, 0.08, 0.0, "error")
