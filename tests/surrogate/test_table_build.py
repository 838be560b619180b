"""Tests of surrogate.table_build on synthetic campaign records whose A_p(beta) and A_c are known: the ensemble means
and standard errors at the simulated nodes, the goodness-of-fit test that decides what fills the others (a passing
fit, or the nearest simulated level held), where the table marks nodes as simulated (levels restricted by pressure
and velocity), the quasi-static row, the caps, mu and its standard error, the metadata, the file round trip and
compare_tables."""

from __future__ import annotations

import json

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tribocosim.errors import TableError
from tribocosim.components.stripdraw.table import FrictionTable, read_table, write_table
from tribocosim.surrogate.campaign import expand_cases
from tribocosim.surrogate.sweep import parse_sweep
from tribocosim.surrogate.table_build import build_table, compare_tables, describe, plot_table

E_STAR, P_CRIT = 55e9, 340e6
STATS = {"gap_rms_slope_mean": 0.3, "pairs": []}

SWEEP = """
name = "synthetic"
[grid]
pressure = [5e6, 10e6, 30e6]
velocity = [0.08, 2.0]
seeds = [1, 2, 3, 4, 5]
[[flakes]]
count = 1
diameter = 12e-6
[[flakes]]
count = 3
diameter = 12e-6
[[flakes]]
count = 6
diameter = 12e-6
[[flakes]]
count = 9
diameter = 12e-6
min_pressure = 10e6
velocities = [0.08]
[slide]
n = 256
size = 64e-6
wavelength_ratio = 0.25
[table]
mu0 = 0.15
quasi_static_row = true
"""


def langmuir(p, v, beta, c=4.0):
    """A_p/A0 saturating in beta (alpha 400 at small beta, half the line at beta = 1/c)."""
    return 400.0 * beta * p / E_STAR / (1.0 + c * beta)


def campaign(ap_of=langmuir, noise=0.02, seed=0, sweep_text=SWEEP):
    """Manifest and finished records of the sweep with A_p = ap_of(P, v, beta), A_c = P/p_crit (+ noise)."""
    sweep = parse_sweep(sweep_text)
    cases = expand_cases(sweep)
    rng = np.random.default_rng(seed)
    records = []
    for c in cases:
        lab = c.labels
        ap = float(ap_of(lab["pressure"], lab["velocity"], lab["beta"]))
        ac = lab["pressure"] / P_CRIT
        records.append({"case_id": c.case_id, "labels": lab, "wall_s": 1.0 + lab["n_flakes"], "code_version": "test",
                        "summary": {"mean_particle_fraction": ap * (1 + noise * rng.standard_normal()),
                                    "mean_particle_fraction_clusters": 0.01 * ap,
                                    "mean_contact_fraction": ac * (1 + noise * rng.standard_normal())}})
    manifest = {"sweep": sweep.to_dict(), "cases": [{"case_id": c.case_id, "labels": c.labels} for c in cases]}
    return manifest, records


@pytest.fixture(scope="module")
def built():
    manifest, records = campaign()
    table, fits = build_table(records, manifest, surface_stats=STATS)
    return manifest, records, table, fits


def test_axes_are_the_grid_with_the_quasi_static_row_and_every_level(built):
    manifest, _, t, _ = built
    assert_allclose(t.pressure, [5e6, 10e6, 30e6])
    assert_allclose(t.velocity, [0.0, 0.08, 2.0])
    assert_allclose(t.beta, [0.0] + [f["beta"] for f in manifest["sweep"]["flakes"]])
    assert t.version == 4


def _members(records, p, v, b, key):
    return np.array([r["summary"][key] for r in records if r["labels"]["pressure"] == p
                     and r["labels"]["velocity"] == v and abs(r["labels"]["beta"] - b) <= 1e-9 * max(b, 1e-30)])


def test_simulated_nodes_hold_the_ensemble_means_and_their_standard_errors(built):
    """At every simulated node: the members' mean of A_p, A_c and A_p of the cluster rule, their standard errors
    (std / sqrt(n); one contact pixel for a node of one member), mu = mu0 (1 - A_p / A_c) of the means with a standard error that agrees with the spread of the
    members' own mu (first order in the noise); mu0 and no flake-borne area at beta = 0."""
    _, records, t, _ = built
    sim = t.array("simulated")
    for i, p in enumerate(t.pressure):
        for j, v in enumerate(t.velocity[1:], start=1):
            for k, b in enumerate(t.beta):
                if not sim[i, j, k]:
                    continue
                ap, ac = (_members(records, p, v, b, key) for key in ("mean_particle_fraction",
                                                                      "mean_contact_fraction"))
                apc = _members(records, p, v, b, "mean_particle_fraction_clusters")
                n = ap.size
                assert t.contact_area[i, j, k] == pytest.approx(ac.mean(), rel=1e-12)
                se = ac.std(ddof=1) / np.sqrt(n) if n > 1 else 1.0 / 256**2  # one member: one contact pixel
                assert t.array("contact_area_se")[i, j, k] == pytest.approx(se, rel=1e-9)
                if b > 0:
                    assert t.particle_area[i, j, k] == pytest.approx(ap.mean(), rel=1e-12)
                    assert t.array("particle_area_se")[i, j, k] == pytest.approx(ap.std(ddof=1) / np.sqrt(n),
                                                                                rel=1e-9)
                    assert t.array("particle_area_clusters")[i, j, k] == pytest.approx(apc.mean(), rel=1e-12)
                    mus = 0.15 * (1 - ap / ac)
                    assert t.array("mu_se")[i, j, k] == pytest.approx(mus.std(ddof=1) / np.sqrt(n), rel=0.1)
    assert_allclose(t.mu, 0.15 * np.maximum(0.0, 1.0 - t.particle_area / t.contact_area), rtol=1e-12)
    assert_allclose(t.mu[:, :, 0], 0.15, rtol=0, atol=0)
    assert np.all(t.particle_area[:, :, 0] == 0) and np.all(t.array("mu_se")[:, :, 0] == 0)


def test_a_passing_fit_fills_the_unsimulated_nodes_and_a_failing_one_holds_the_last_level():
    """Saturating data with noise as the standard errors say: the saturating form passes the chi^2 test, the line
    fails, and the saturating fit fills the nodes a row did not simulate. Data the saturating form cannot follow
    (a kink, noise-free): every fit fails and those nodes hold the row's last simulated level."""
    manifest, records = campaign(noise=0.01)
    t, fits = build_table(records, manifest, surface_stats=STATS)
    row = next(r for r in fits["rows"] if r["pressure"] == 5e6 and r["velocity"] == 0.08)
    assert row["particle_area"]["langmuir"]["p_value"] >= 0.05 > row["particle_area"]["linear"]["p_value"]
    assert row["fills"]["particle_area"] == "langmuir"
    a, c = row["particle_area"]["langmuir"]["params"]
    k = t.beta.size - 1
    assert t.array("simulated")[0, 1, k] == 0
    assert t.particle_area[0, 1, k] == pytest.approx(a * t.beta[k] / (1 + c * t.beta[k]), rel=1e-12)
    assert t.particle_area[0, 1, k] == pytest.approx(langmuir(5e6, 0.08, t.beta[k]), rel=0.1)
    assert {u["particle_area"] for u in fits["unsimulated"] if u["pressure"] == 5e6} == {"langmuir"}

    kinked = (lambda p, v, b: 300.0 * min(b, 0.04) * p / E_STAR)
    manifest, records = campaign(ap_of=kinked, noise=0.0)
    t, fits = build_table(records, manifest, surface_stats=STATS)
    row = next(r for r in fits["rows"] if r["pressure"] == 5e6 and r["velocity"] == 0.08)
    assert row["fills"]["particle_area"] == "held"
    for name in ("particle_area", "contact_area", "particle_area_se", "mu"):
        assert t.array(name)[0, 1, k] == t.array(name)[0, 1, k - 1], name


def test_the_goodness_of_fit_is_recorded_per_row_and_in_total(built):
    _, _, _, fits = built
    row = fits["rows"][0]
    for name in ("particle_area", "particle_area_clusters"):
        for form in ("linear", "langmuir"):
            f = row[name][form]
            assert f["dof"] == len(row["levels"]) - len(f["params"]) and len(f["residuals"]) == len(row["levels"])
            assert f["chi2"] == pytest.approx(sum(r * r for r in f["residuals"]), rel=1e-9)
            assert f["chi2_per_dof"] == pytest.approx(f["chi2"] / f["dof"], rel=1e-12)
    total = fits["summary"]["particle_area"]["langmuir"]
    rows = [r["particle_area"]["langmuir"] for r in fits["rows"]]
    assert total["chi2"] == pytest.approx(sum(r["chi2"] for r in rows)) and total["dof"] == sum(r["dof"] for r in rows)


def test_levels_restricted_by_pressure_and_velocity_are_simulated_only_there(built):
    """The fourth level (min_pressure 10 MPa, 0.08 m/s only): simulated at (10, 0.08) and (30, 0.08) and on the
    quasi-static row above them, unsimulated (filled or held) at 5 MPa and at 2 m/s."""
    _, _, t, _ = built
    sim = t.array("simulated")
    assert_allclose(sim[:, :, :4], 1.0)
    assert_allclose(sim[:, :, 4], [[0, 0, 0], [1, 1, 0], [1, 1, 0]])
    assert np.array(t.metadata["ensemble"]["n_members"])[1, 1, 4] == 5
    assert np.array(t.metadata["ensemble"]["n_members"])[0, 1, 4] == 0


def test_the_quasi_static_row_is_the_slowest_row(built):
    _, _, t, _ = built
    for name in t.arrays():
        assert_allclose(t.array(name)[:, 0, :], t.array(name)[:, 1, :], rtol=0, atol=0, err_msg=name)
    assert "quasi-static" in t.metadata["axes"]["velocity"]["note"]


def test_caps_are_where_the_interpolated_share_reaches_one():
    """A_p = 0.8 A_c at beta = 0.2 growing linearly: the cap (A_p = A_c) at beta = 0.25 inside the axis; a row
    whose A_p stays below A_c has none."""
    text = SWEEP.replace("count = 9", "count = 40")
    def ap(p, v, b):
        return (p / P_CRIT) * 4.0 * b if v == 0.08 else 0.5 * (p / P_CRIT) * b
    manifest, records = campaign(ap_of=ap, noise=0.0, sweep_text=text)
    t, fits = build_table(records, manifest, surface_stats=STATS)
    caps = {(c["pressure"], c["velocity"]): c["beta_cap_s1"] for c in fits["caps"]}
    assert caps[(30e6, 0.08)] == pytest.approx(0.25, abs=1e-9)
    assert caps[(30e6, 2.0)] is None and t.beta_threshold == 1.0


def test_metadata_records_fits_nodes_cases_and_is_strict_json(built):
    _, records, t, _ = built
    m = t.metadata
    assert m["provenance"] == "mesoscale" and m["campaign"]["sweep"]["name"] == "synthetic"
    assert {"rows", "summary", "unsimulated", "contact_area", "caps", "alpha_eq23_per_velocity"} <= set(m["fits"])
    assert len(m["cases"]) == len(records) and {"a_p", "a_c", "a_p_clusters", "wall_s"} <= set(m["cases"][0])
    node = m["ensemble"]["nodes"][0]
    assert {"a_p", "a_p_se", "mu_se", "alpha", "relative_se", "members"} <= set(node)
    json.dumps(m, allow_nan=False)


def test_round_trip_through_the_file_format_with_hash(built, tmp_path):
    _, _, t, _ = built
    path = tmp_path / "t.npz"
    digest = write_table(path, t)
    back = read_table(path)
    assert back.metadata["content_hash"] == digest == back.content_hash() and back.version == 4
    for name in back.arrays():
        assert np.array_equal(back.array(name), t.array(name)), name
    assert compare_tables(back, t)["within_uncertainty"]
    text = describe(back)
    assert "goodness of fit" in text and digest in text and "simulated nodes" in text
    plot_table(back, tmp_path / "mu.png")
    assert (tmp_path / "mu.png").stat().st_size > 1000


def test_tampered_or_wrong_version_table_is_refused(built, tmp_path):
    _, _, t, _ = built
    path = tmp_path / "t.npz"
    write_table(path, t)
    with np.load(path) as d:
        arrays = {k: d[k] for k in d.files}
    sim = arrays["simulated"].copy()
    sim[0, 0, 4] = 1.0
    np.savez(tmp_path / "bad.npz", **{**arrays, "simulated": sim})
    with pytest.raises(TableError, match="hash"):
        read_table(tmp_path / "bad.npz")
    meta = json.loads(str(arrays["metadata"]))
    meta["format_version"] = 99
    np.savez(tmp_path / "v99.npz", **{**arrays, "metadata": np.array(json.dumps(meta))})
    with pytest.raises(TableError, match="version 99"):
        read_table(tmp_path / "v99.npz")


def test_missing_rows_are_errors_naming_them():
    manifest, records = campaign()
    drop = [r for r in records if not (r["labels"]["pressure"] == 10e6 and r["labels"]["velocity"] == 2.0
                                       and r["labels"]["n_flakes"] > 0)]
    with pytest.raises(TableError, match=r"P = 1e\+07 Pa, v = 2 m/s"):
        build_table(drop, manifest, surface_stats=STATS)
    free = [r for r in records if not (r["labels"]["pressure"] == 5e6 and r["labels"]["n_flakes"] == 0)]
    with pytest.raises(TableError, match=r"particle-free case at P = 5e\+06 Pa"):
        build_table(free, manifest, surface_stats=STATS)


def test_compare_tables_within_two_standard_errors(built):
    _, _, t, _ = built
    ap = t.particle_area.copy()
    se = t.array("particle_area_se")
    ap[2, 1, 3] += 5 * se[2, 1, 3]  # beyond 2 combined standard errors (sqrt 2 x se)
    ap[1, 1, 2] += 1.0 * se[1, 1, 2]  # within
    other = FrictionTable(t.pressure, t.velocity, t.beta, t.mu, t.metadata, contact_area=t.contact_area,
                          particle_area=ap, contact_area_std=t.contact_area_std, particle_area_std=t.particle_area_std,
                          extras=t.extras)
    res = compare_tables(t, other)
    assert not res["within_uncertainty"] and res["particle_area_nodes_beyond_tolerance"] == 1
    assert compare_tables(t, t)["within_uncertainty"]
    shorter = FrictionTable(t.pressure, t.velocity[1:], t.beta, t.mu[:, 1:], t.metadata)
    with pytest.raises(TableError, match="different velocity axes"):
        compare_tables(t, shorter)


def test_a_sweep_whose_pairs_set_the_surface_keys_builds_its_table():
    """[slide] is taken with a surface pair, as the sweep checks it: here n = 64 with the wavelength_ratio only in the
    [[surfaces]] entry (the default 0.02 alone is below 2/n)."""
    text = SWEEP.replace("n = 256\n", "n = 64\n").replace("wavelength_ratio = 0.25\n", "").replace(
        "[slide]", "[[surfaces]]\nsheet_seed = 1\ntool_seed = 2\nwavelength_ratio = 0.25\n[slide]")
    manifest, records = campaign(sweep_text=text)
    table, _ = build_table(records, manifest, surface_stats=STATS)
    assert table.mu.shape == (3, 3, 5)
