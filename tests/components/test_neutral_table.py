"""The neutral JSON table: self-describing axes and units, mu and its standard error at every node, which nodes rest
on simulated table nodes, the interpolation rule and the accuracy it reaches."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tribocosim.components.friction_export.export_run import AXIS_STATE, DebrisState, ExportRequest, run_export
from tribocosim.components.friction_export.export_units import UNIT_SYSTEMS
from tribocosim.components.friction_export.grid_refinement import multilinear
from tribocosim.components.friction_export.exported_law import load_law


@pytest.fixture(scope="module")
def law():
    return load_law()


def _export(law, folder, beta, units="mm-t-s", **options):
    state = AXIS_STATE if beta is None else DebrisState(beta, "", f"beta = {beta}", {"beta": beta, "how": "given"})
    result = run_export(law, ExportRequest("table", folder / "friction.json", (state,), UNIT_SYSTEMS[units],
                                           **options))
    return result, [json.loads(f.path.read_text()) for f in result.files]


def test_the_file_describes_itself_and_holds_mu_and_its_standard_error_at_every_node(law, tmp_path):
    beta = float(law.table.beta[4])  # a node of the beta axis where the linear reading needs a pressure between nodes
    _, (doc,) = _export(law, tmp_path, beta)
    assert doc["format"] == "tribocosim-friction-export" and doc["role"] == "nominal"
    assert [(a["name"], a["unit"]) for a in doc["axes"]] == [("pressure", "MPa"), ("velocity", "mm/s")]
    p, v = (np.array(a["values"]) for a in doc["axes"])
    mu, se = np.array(doc["mu"]), np.array(doc["mu_se"])
    assert mu.shape == se.shape == (p.size, v.size)
    P, V = np.meshgrid(p * 1e6, v * 1e-3, indexing="ij")
    np.testing.assert_allclose(mu, law.mu(P, V, beta)[0], rtol=1e-15)
    np.testing.assert_allclose(se, law.standard_error(P, V, beta), rtol=1e-15)
    assert np.array(doc["simulated"]).all()
    on_table = np.isin(p * 1e6, law.table.pressure)[:, None] & np.isin(v * 1e-3, law.table.velocity)[None, :]
    assert on_table.any() and not on_table.all()
    np.testing.assert_array_equal(np.array(doc["table_node"]), on_table)
    assert doc["debris_state"]["beta"] == beta and doc["units"]["system"] == "mm-t-s"
    assert doc["provenance"]["table"]["content_hash"] == law.table.metadata["content_hash"]
    assert doc["provenance"]["parameters"]["mu0"] == 0.15
    assert "native core libtc_core-" in doc["provenance"]["code_version"]
    assert doc["interpolation"]["accuracy"] <= doc["interpolation"]["tolerance"] == 0.005
    assert doc["band"] is None and doc["warnings"] == []


def test_its_stated_rule_reproduces_tribocosims_mu_within_its_stated_accuracy(law, tmp_path):
    _, (doc,) = _export(law, tmp_path, None, units="SI")
    axes = [np.array(a["values"]) for a in doc["axes"]]
    assert [a["name"] for a in doc["axes"]] == ["pressure", "velocity", "beta"]
    mu = np.array(doc["mu"])
    rng = np.random.default_rng(12)
    p, v, b = rng.uniform(1e6, 3e7, 1000), rng.uniform(0, 0.5, 1000), rng.uniform(0, axes[2][-1], 1000)
    fe = multilinear(axes, mu[..., None], (p, v, b))[:, 0]
    exact, _ = law.mu(p, v, b)
    assert (np.abs(fe - exact) / exact).max() <= doc["interpolation"]["accuracy"]


def test_unsimulated_nodes_are_refused_or_written_marked(law, tmp_path):
    from tribocosim.errors import ParameterError

    with pytest.raises(ParameterError, match=r"--beta 0.5: .* did not simulate .*--pressure-range 5 30"):
        _export(law, tmp_path, 0.5)
    assert not list(tmp_path.iterdir()), "nothing written"
    result, (doc,) = _export(law, tmp_path, 0.5, allow_unsimulated=True)
    p = np.array(doc["axes"][0]["values"])
    simulated = np.array(doc["simulated"])
    assert not simulated[p < 5].any() and simulated[p >= 5].all()  # the table simulated beta 0.5 from 5 MPa
    assert "written as asked (--allow-unsimulated)" in result.files[0].unsimulated
    assert any(line.startswith("unsimulated:") for line in doc["header"])


def test_the_band_files_hold_the_band_at_the_same_nodes(law, tmp_path):
    result, (nominal, upper, lower) = _export(law, tmp_path, 0.2, band=1.5)
    assert [f.path.name for f in result.files] == ["friction.json", "friction.upper.json", "friction.lower.json"]
    assert upper["role"] == "upper" and lower["band"]["k"] == 1.5
    assert nominal["axes"] == upper["axes"] == lower["axes"]
    mu, up, lo, se = (np.array(d) for d in (nominal["mu"], upper["mu"], lower["mu"], nominal["mu_se"]))
    np.testing.assert_allclose(up, np.minimum(0.15, mu + 1.5 * se), rtol=1e-12)
    np.testing.assert_allclose(lo, np.maximum(0.0, mu - 1.5 * se), rtol=1e-12)


def test_a_slide_state_holds_the_debris_at_every_node(law, tmp_path):
    """--slide 20 (mm): the file's debris state holds beta at every node, K P S / (H h_p) (below the cap at s = 1),
    and mu there is the law's at that beta; the velocity axis is one value with its range (the law does not depend
    on it)."""
    from tribocosim.cosim.apps.debris_state import DebrisChoice, debris_states

    (state,) = debris_states(DebrisChoice(slide=20), law, UNIT_SYSTEMS["mm-t-s"])
    result = run_export(law, ExportRequest("table", tmp_path / "friction.json", (state,), UNIT_SYSTEMS["mm-t-s"]))
    doc = json.loads(result.files[0].path.read_text())
    p = np.array(doc["axes"][0]["values"]) * 1e6
    assert doc["axes"][1] == {"name": "velocity", "unit": "mm/s", "values": [0.0], "independent": True,
                              "range": [0.0, 500.0]}
    prm = law.params
    beta = np.array(doc["debris_state"]["beta_at_nodes"])
    assert beta.shape == (p.size, 1)
    np.testing.assert_allclose(beta[:, 0], prm.archard_k * p * 0.02 / (prm.hardness * prm.particle_thickness),
                               rtol=8 * 2.0**-53)
    np.testing.assert_allclose(np.array(doc["mu"])[:, 0], law.mu(p, 0.0, beta[:, 0])[0], rtol=1e-15)
    assert doc["debris_state"]["how"] == "slide" and doc["debris_state"]["slide"] == 0.02
    assert np.all(np.diff(np.array(doc["mu"])[:, 0]) < 0), "mu falls with pressure"
