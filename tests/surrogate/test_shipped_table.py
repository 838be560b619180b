"""The friction table shipped in models/ is the quick preset's mesoscale table (format version 4), and it is
reproducible: its recorded sweep is the current preset, the table build makes its arrays from its recorded cases
(within what another processor or library build may move them: surrogate.table_rebuild), and a recorded case rerun
from the preset gives its recorded result.

The shipped domain: pressures 1-30 MPa, the test's 0.08 m/s among the simulated velocities with the quasi-static
v = 0 row below it, debris simulated up to beta ~ 1 at 20-30 MPa, every simulated node's ensemble standard error
of <A_p> at most 10 % of its mean (the preset's target), and no node above the largest simulated level.
``tribocosim surrogate verify`` (run by .ci/run) reruns a larger sample of its cases.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tribocosim.paths import DEFAULT_TABLE
from tribocosim.components.stripdraw.table import read_table
from tribocosim.surrogate.campaign import make_case, run_case
from tribocosim.surrogate.sweep import load_preset, parse_sweep_dict
from tribocosim.surrogate.table_rebuild import rebuild_differences, rebuild_from_metadata, rebuild_tolerance


@pytest.fixture(scope="module")
def shipped():
    return read_table(DEFAULT_TABLE)


def test_shipped_table_is_the_quick_presets_table(shipped):
    meta = shipped.metadata
    assert shipped.provenance == "mesoscale" and shipped.version == 4
    recorded = {k: v for k, v in meta["campaign"]["sweep"].items() if k != "source"}  # a path
    current = json.loads(json.dumps(load_preset("quick").to_dict()))
    current.pop("source", None)
    assert recorded == current, "the quick preset changed since the table was built: rebuild and ship it (README)"
    assert meta["campaign"]["cases_finished"] == len(meta["cases"]) and not meta["campaign"]["cases_failed"]
    assert len(meta["case_source_digests"]) == 1, "every case computed by one version of the mesoscale code"


def test_the_domain_covers_the_strip_draw(shipped):
    assert (shipped.pressure[0], shipped.pressure[-1]) == (1e6, 30e6)
    assert shipped.velocity[0] == 0.0 and 0.08 in shipped.velocity
    sim = shipped.array("simulated")
    j = int(np.flatnonzero(shipped.velocity == 0.08)[0])
    for p in (20e6, 30e6):
        i = int(np.flatnonzero(shipped.pressure == p)[0])
        assert shipped.beta[sim[i, j] == 1].max() >= 0.99, "simulated up to beta ~ 1 where the long pad reaches it"
    assert shipped.beta[-1] == pytest.approx(max(f["beta"] for f in shipped.metadata["campaign"]["sweep"]["flakes"]))
    for node in shipped.metadata["ensemble"]["nodes"]:
        assert node["relative_se"] is not None and node["relative_se"] <= 0.1, node


def test_the_build_makes_the_shipped_arrays_from_the_recorded_cases(shipped):
    """Every array rebuilt from the recorded cases within what a rebuild on another processor or library build may move
    (surrogate.table_rebuild: the round-off of the ensemble arithmetic; a fitted node by what the fit's computation
    may leave its parameters from the optimum); the axes exactly."""
    rebuilt = rebuild_from_metadata(shipped.metadata)
    assert set(rebuilt.arrays()) == set(shipped.arrays())
    assert rebuild_differences(rebuilt, shipped, rebuild_tolerance(shipped.metadata)) == []


def _domain(variant):
    from tribocosim.cosim.reports.paper_physics import DOMAIN_TABLES
    from tribocosim.paths import MODELS_DIR

    return read_table(MODELS_DIR / DOMAIN_TABLES[variant])


def test_the_rebuild_tolerance_holds_a_refit_from_perturbed_data_and_stays_below_the_nodes_uncertainty():
    """The tolerance of a rebuild is what moves a fitted node when its fit runs another path to the same optimum: the
    recorded results moved by 4 units in the last place (a rounding of other hardware, four times over) rebuild within
    it, at every fitted node (the 128 um table's rows are filled by langmuir and affine fits: 10 such nodes). The
    tolerance is below each fitted node's own standard error, so a rebuild that moves a node by as much as its
    ensemble could resolve fails."""
    domain = _domain("domain_128")
    meta = domain.metadata
    fitted = domain.array("simulated") == 0
    assert fitted.sum() == len(meta["fits"]["unsimulated"]) > 0
    assert {u["particle_area"] for u in meta["fits"]["unsimulated"]} == {"langmuir"}
    tol = rebuild_tolerance(meta)
    for name in ("particle_area", "contact_area", "particle_area_clusters"):
        assert np.all(tol[name][fitted] < domain.array(name + "_se")[fitted]), name
    for name in ("particle_area", "contact_area"):  # the cluster rule's area is 0 on this table's rows
        assert np.all(tol[name][fitted] > 0), name
    perturbed = json.loads(json.dumps(meta))
    for c in perturbed["cases"]:
        for key in ("a_p", "a_c", "a_p_clusters"):
            if c.get(key):
                c[key] = float(np.nextafter(np.nextafter(np.nextafter(np.nextafter(c[key], 1), 1), 1), 1))
    rebuilt = rebuild_from_metadata(perturbed)
    assert not np.array_equal(rebuilt.particle_area[fitted], domain.particle_area[fitted])
    assert rebuild_differences(rebuilt, domain, tol) == []


def test_a_rebuild_that_moves_a_fitted_node_by_its_standard_error_is_refused():
    domain = _domain("domain_512")
    tol = rebuild_tolerance(domain.metadata)
    rebuilt = rebuild_from_metadata(domain.metadata)
    i, j, k = (int(x[0]) for x in np.nonzero(domain.array("simulated") == 0))
    moved = rebuilt.particle_area.copy()
    moved[i, j, k] += domain.array("particle_area_se")[i, j, k]
    import dataclasses

    lines = rebuild_differences(dataclasses.replace(rebuilt, particle_area=moved), domain, tol)
    assert len(lines) == 1 and lines[0].startswith("particle_area at P = "), lines


def test_a_rebuild_keeps_the_code_version_that_computed_the_cases(shipped):
    """The shipped table's cases come from one version of the mesoscale code, which ``surrogate verify`` compares a
    rerun's with (bit for bit when it is the same); a table rebuilt from them records that version, not 'unknown'."""
    digests = shipped.metadata["case_source_digests"]
    assert len(digests) == 1 and digests != ["unknown"]
    assert rebuild_from_metadata(shipped.metadata).metadata["case_source_digests"] == digests


def test_a_recorded_case_reruns_to_its_recorded_result(shipped):
    """The cheapest recorded case (particle-free: the contact alone) rebuilt from the preset and rerun."""
    sweep = parse_sweep_dict(shipped.metadata["campaign"]["sweep"])
    rec = min((c for c in shipped.metadata["cases"] if c["labels"]["n_flakes"] == 0), key=lambda c: c["wall_s"])
    lab = rec["labels"]
    case = make_case(sweep, lab["surface"], lab["pressure"], lab["velocity"])
    assert case.case_id == rec["case_id"]
    out = run_case(case.payload())
    assert out["status"] == "done", out
    n = case.config.n
    assert abs(out["summary"]["mean_contact_fraction"] - rec["a_c"]) <= 1.0 / (n * n)
    assert out["summary"]["mean_particle_fraction"] == rec["a_p"] == 0.0


@pytest.mark.parametrize("variant, preset, size", [("domain_128", "domain_128um", 128e-6),
                                                   ("domain_512", "domain_512um", 512e-6)])
def test_the_domain_size_variations_tables_are_their_presets_and_fit_the_shipped_rows(shipped, variant, preset, size):
    """models/friction_table_128um.npz and _512um.npz (the budget's domain-size variation, both sides of the shipped
    256 um): each its preset's table, rebuilt from its recorded cases, computed by one version of the mesoscale code,
    on rows the shipped table has and a beta axis that spans the shipped one's (what paper_physics.with_rows_of
    needs). Their fitted nodes come from langmuir fits, an iterative solver whose last iterate depends on the
    processor and the libraries' builds: the rebuild is compared within surrogate.table_rebuild's tolerance."""
    domain = _domain(variant)
    meta = domain.metadata
    recorded = {k: v for k, v in meta["campaign"]["sweep"].items() if k != "source"}
    current = json.loads(json.dumps(load_preset(preset).to_dict()))
    current.pop("source", None)
    assert recorded == current, f"the {preset} preset changed since its table was built: rebuild and ship it"
    assert len(meta["case_source_digests"]) == 1
    assert rebuild_differences(rebuild_from_metadata(meta), domain, rebuild_tolerance(meta)) == []
    assert meta["campaign"]["sweep"]["slide"]["size"] == size
    assert set(domain.pressure) <= set(shipped.pressure) and set(domain.velocity) <= set(shipped.velocity)
    assert domain.beta[0] == shipped.beta[0] and domain.beta[-1] >= shipped.beta[-1]


def test_the_quick_presets_stated_cost_is_the_shipped_tables_recorded_one(shipped, capsys):
    """One statement of the quick build's cost, from the shipped table's recorded cases: their number and the sum of
    their wall times, in the preset's comment, the table's physics page and ``tribocosim surrogate presets``."""
    from tribocosim.surrogate import surrogate_cli
    from tribocosim.surrogate.campaign import expand_cases
    from tribocosim.surrogate.sweep import PRESET_DIR

    cases = shipped.metadata["cases"]
    slides, hours = len(cases), sum(c["wall_s"] for c in cases) / 3600
    base = len(expand_cases(load_preset("quick")))
    preset = " ".join((PRESET_DIR / "quick.toml").read_text().replace("#", " ").split())
    assert f"{slides} slides ({base} base cases, {slides - base} adaptive placements), {hours:.3g} core-hours" in preset
    page = " ".join((Path(__file__).parents[2] / "docs" / "physics" / "table_domain.md").read_text().split())
    assert f"{slides} slides ({base} base, {slides - base} adaptive)" in page and f"{hours:.3g} core-hours" in page
    assert surrogate_cli.main(["presets"]) == 0
    assert f"models/friction_table.npz: {slides} slides, {hours:.3g} core-hours (recorded)" in capsys.readouterr().out
