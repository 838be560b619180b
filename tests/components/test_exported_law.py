"""The law an export writes: the strip-draw model's table law through the same native core, its standard error from
the table's ensemble standard errors, the band, and the parameters of a calibration file."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from tribocosim.errors import ParameterError
from tribocosim.paths import DEFAULT_TABLE
from tribocosim.components.friction_export.exported_law import load_law, table_mu0
from tribocosim.components.stripdraw.friction import FrictionLaw, closed_form_table
from tribocosim.components.stripdraw.parameters import StripDrawParameters
from tribocosim.components.stripdraw.table import read_table, write_table


@pytest.fixture(scope="module")
def law():
    return load_law()


def _below_cap(law, mu):
    """Where the law is below its cap (mu > r mu0, the value where flakes carry the whole real contact)."""
    return mu > law.params.flake_shear_ratio * law.params.mu0 * (1 + 1e-12)


def _simulated_nodes(table):
    i, j, k = np.nonzero(table.array("simulated") == 1.0)
    return table.pressure[i], table.velocity[j], table.beta[k], (i, j, k)


def test_the_law_is_the_strip_draw_models(law):
    """The same parameters and table through FrictionLaw (the model's and the FMU's core): equal to the last bit."""
    rng = np.random.default_rng(3)
    p, v, b = rng.uniform(1e6, 3e7, 300), rng.uniform(0, 0.5, 300), rng.uniform(0, 0.3, 300)
    reference = FrictionLaw(StripDrawParameters(), read_table(DEFAULT_TABLE))
    assert np.array_equal(law.mu(p, v, b)[0], reference.mu(p, v, b)[0])


def test_the_table_mu0_is_the_one_its_mu_column_was_made_with(law):
    assert table_mu0(law.table) == pytest.approx(law.table.metadata["calibration"]["mu0"], rel=1e-12)


@pytest.mark.parametrize("changes", [{}, {"mu0": 0.3}, {"flake_shear_ratio": 0.5}, {"flake_shear_ratio": 0.0},
                                     {"particle_area_scale": 1.5}])
def test_at_a_simulated_node_the_standard_error_is_the_tables_propagated_to_the_parameters(changes):
    """se(mu) = mu0 (1 - r) s se(A_p / A_c), and the table's mu_se is 0.15 se(A_p / A_c) (its mu column: mu0 = 0.15,
    r = 0, s = 1): at a node below the cap, the table's mu_se times mu0 (1 - r) s / 0.15."""
    law = load_law(settings=changes)
    prm = law.params
    factor = prm.mu0 * (1.0 - prm.flake_shear_ratio) * prm.particle_area_scale / 0.15
    p, v, b, at = _simulated_nodes(law.table)
    mu, _ = law.mu(p, v, b)
    live = _below_cap(law, mu)
    assert live.sum() > 10
    se = law.standard_error(p, v, b)
    np.testing.assert_allclose(se[live], factor * law.table.array("mu_se")[at][live], rtol=1e-9, atol=1e-15)


def test_the_band_is_mu_plus_minus_k_standard_errors_clipped_to_the_laws_least_value_and_mu0(law):
    """The band never leaves the values the law can give: r mu0 (flakes carry the whole contact) to mu0."""
    rng = np.random.default_rng(4)
    p, v, b = rng.uniform(1e6, 3e7, 400), rng.uniform(0, 0.5, 400), rng.uniform(0, 0.3, 400)
    mu, _ = law.mu(p, v, b)
    se = law.standard_error(p, v, b)
    assert np.all(se >= 0) and np.all(se[b > 0.03] > 0)
    upper, lower = law.band(p, v, b, 2.0)
    np.testing.assert_allclose(upper, np.minimum(0.15, mu + 2 * se), rtol=1e-14)
    least = law.params.flake_shear_ratio * 0.15
    np.testing.assert_allclose(lower, np.maximum(least, mu - 2 * se), rtol=1e-14)
    big_upper, big_lower = law.band(p, v, b, 1e4)
    assert big_upper.max() == 0.15 and big_lower.min() == least


def test_a_table_without_standard_errors_has_no_band(tmp_path):
    path = tmp_path / "closed.npz"
    write_table(path, closed_form_table(pressure=np.array([1e6, 3e7]), velocity=np.array([0.0, 0.5]),
                                        beta=np.array([0.0, 0.2])))
    law = load_law(table_path=path)
    assert law.table.version == 2
    with pytest.raises(ParameterError, match="--band needs a table with the ensemble standard errors"):
        law.check_band()


def test_the_highest_level_simulated_everywhere_in_a_range(law):
    """The table's own simulated flags decide (docs/physics/table_domain.md): lookups up to that level read
    simulated nodes only, and a lookup above it at the range's lowest pressure reads an unsimulated one."""
    t = law.table
    for lo_mpa, expected in ((1, 0.3), (5, 0.5), (10, 0.75), (20, 1.0)):
        prange = (lo_mpa * 1e6, 3e7)
        top = law.simulated_beta_top(prange, law.velocity_axis)
        assert top == pytest.approx(expected, abs=0.002)
        rng = np.random.default_rng(lo_mpa)
        p = np.exp(rng.uniform(math.log(prange[0]), math.log(prange[1]), 2000))
        _, flagged = law.mu(p, rng.uniform(0, 0.5, 2000), rng.uniform(0, top, 2000))
        assert not flagged.any()
        if top < t.beta[-1]:
            _, above = law.mu(prange[0], 0.08, top + 0.01)
            assert above.all()


def _calibration_file(tmp_path, scale=2.0, stderr=0.1, contact_area="mesoscale"):
    """A calibration file as tribocosim calibrate writes it: the table with A_p times the scale, and its record."""
    from tribocosim.cosim.apps.calibrate import scaled_table

    table = read_table(DEFAULT_TABLE)
    record = {"fitted": {"particle_area_scale": {"value": scale, "stderr": stderr}, "zeta": {"value": 0.3,
                                                                                              "stderr": 0.05}},
              "status": "converged", "contact_area": contact_area, "particle_area_rule": "load_bearing",
              "parameters": {"contact_area": contact_area, "archard_k": 2e-4}, "note": "test"}
    path = tmp_path / "calibrated.npz"
    write_table(path, scaled_table(table, scale, 0.15, "load_bearing", record))
    return path


def test_a_calibration_file_is_its_table_with_the_parameters_its_record_names(tmp_path):
    path = _calibration_file(tmp_path)
    law = load_law(calibration_path=path)
    assert law.params.particle_area_scale == 1.0 and law.params.zeta == 0.3 and law.params.archard_k == 2e-4
    # the calibrated law is the uncalibrated table's law at s = 2
    plain = load_law(settings={"particle_area_scale": 2.0})
    rng = np.random.default_rng(5)
    p, v, b = rng.uniform(1e6, 3e7, 200), rng.uniform(0, 0.5, 200), rng.uniform(0, 0.3, 200)
    np.testing.assert_allclose(law.mu(p, v, b)[0], plain.mu(p, v, b)[0], rtol=1e-12)
    with pytest.raises(ParameterError, match="--set particle_area_scale"):
        load_law(calibration_path=path, settings={"particle_area_scale": "2"})
    with pytest.raises(ParameterError, match="--table and --calibration"):
        load_law(table_path=DEFAULT_TABLE, calibration_path=path)
    with pytest.raises(ParameterError, match="no calibration record"):
        load_law(calibration_path=DEFAULT_TABLE)


def test_the_calibrations_scale_interval_widens_the_band_in_quadrature(tmp_path):
    """se_total(q)^2 = se(q)^2 + (q se(s) / s)^2 at a node, q the calibrated share A_p / A_c (its A_p times s, so the
    law has s = 1); se(mu) = mu0 (1 - r) se_total(q)."""
    law = load_law(calibration_path=_calibration_file(tmp_path, 2.0, 0.1))
    assert law.scale_interval == (2.0, 0.1)
    p, v, b, at = _simulated_nodes(law.table)
    mu, _ = law.mu(p, v, b)
    live = _below_cap(law, mu)
    q = law.table.particle_area[at] / law.table.contact_area[at]
    se_q = law.table.array("mu_se")[at] / 0.15
    expected = 0.15 * (1 - law.params.flake_shear_ratio) * np.hypot(se_q, q * 0.05)  # s = 1: q holds the scale
    np.testing.assert_allclose(law.standard_error(p, v, b)[live], expected[live], rtol=1e-9, atol=1e-15)


def test_only_the_table_law_is_exported_and_settings_are_checked():
    with pytest.raises(ParameterError, match="friction_model = 'closed_form'"):
        load_law(settings={"friction_model": "closed_form"})
    with pytest.raises(ParameterError, match="'table_file' is not a strip-draw parameter.*--table"):
        load_law(settings={"table_file": "x.npz"})
    with pytest.raises(ParameterError, match="is not a number"):
        load_law(settings={"mu0": "abc"})
    with pytest.raises(ParameterError, match="mu0"):
        load_law(settings={"mu0": "nan"})
    law = load_law(settings={"mu0": "0.12", "n_elements": "200"})
    assert law.params.mu0 == 0.12 and law.params.n_elements == 200
    assert dataclasses.asdict(law.params) == law.provenance()["parameters"]
    assert law.params.table_policy == "clamp"  # lookups flagged, never refused



def test_the_standard_error_under_eq8_and_the_cluster_rule():
    """eq8: se(mu) = mu0 (1 - r) s se(A_p) / A_c(Eq. 8); the cluster rule: se(A_p/A_c) from the standard errors of
    its A_p and of A_c, their covariance left out. At nodes, where the interpolation reproduces the node values."""
    t = read_table(DEFAULT_TABLE)
    p, v, b, at = _simulated_nodes(t)
    eq8 = load_law(settings={"contact_area": "eq8", "particle_area_scale": 0.05})
    mu, _ = eq8.mu(p, v, b)
    live = _below_cap(eq8, mu)
    ac8 = 2.0 * p / (0.34 * 55e9)
    expected = 0.15 * (1 - eq8.params.flake_shear_ratio) * 0.05 * t.array("particle_area_se")[at] / ac8
    np.testing.assert_allclose(eq8.standard_error(p, v, b)[live], expected[live], rtol=1e-9)
    clusters = load_law(settings={"particle_area_rule": "clusters"})
    mu, _ = clusters.mu(p, v, b)
    ap, ap_se = t.array("particle_area_clusters")[at], t.array("particle_area_clusters_se")[at]
    ac, ac_se = t.contact_area[at], t.array("contact_area_se")[at]
    expected = 0.15 * (1 - clusters.params.flake_shear_ratio) * np.hypot(ap_se / ac, ap * ac_se / ac**2)
    live = _below_cap(clusters, mu)
    np.testing.assert_allclose(clusters.standard_error(p, v, b)[live], expected[live], rtol=1e-9)
