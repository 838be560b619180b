"""The multi-pass options of the strip-draw core against closed forms (docs/model.md sections 3-4):

- flake-borne shear (flake_shear_ratio r): mu = mu0 (1 - (1 - r) s A_p / A_c), so the debris effect scales by 1 - r;
- the debris sink (debris_sink_length lambda): d beta / ds = q - beta / lambda per unit slide s under the pad,
  q = K P / (H h_p): beta(s) = beta0 e^(-s/lambda) + q lambda (1 - e^(-s/lambda)) without transport, exact;
  the debris balance produced = on the strip + removed holds with the sink;
- the carry-over into a later pass (debris_carry_over c): the pass starts from c times the field it is given;
- the observable (particle_area_rule): the cluster rule's A_p of a version 3 table, refused with an older one;
- lookups of a version 3 table that read a node the campaign did not simulate are counted (table_clamp_count).
"""

from __future__ import annotations

import numpy as np
import pytest

from tribocosim.errors import ParameterError
from tribocosim.paths import DEFAULT_TABLE
from tribocosim.components.stripdraw import StripDrawModel, StripDrawParameters, make_friction_law, read_table
from tribocosim.components.stripdraw.table import FrictionTable

P = 1e7
F_N = P * 0.035 * 0.035
V0 = 0.08


def _draw(m: StripDrawModel, n: int, dt: float = 1e-3) -> list[dict]:
    return [m.step(dt, {"normal_force": F_N, "grip_velocity": V0 * min(1.0, (k + 0.5) / 10)}) for k in range(n)]


def _version3(simulated_top: float = 1.0) -> FrictionTable:
    """A small version 3 table: A_c = P / 300 MPa, A_p = 0.8 A_c beta / 0.5 (every load-bearing flake), the cluster
    rule's a quarter of it; the top beta node simulated or not."""
    p, v, b = np.array([1e6, 3e7]), np.array([0.0, 1.0]), np.array([0.0, 0.25, 0.5])
    ac = np.broadcast_to((p / 3e8)[:, None, None], (2, 2, 3)).copy()
    ap = 0.8 * ac * b[None, None, :] / 0.5
    sim = np.ones((2, 2, 3))
    sim[:, :, 2] = simulated_top
    zeros = np.zeros((2, 2, 3))
    return FrictionTable(p, v, b, 0.15 * (1 - ap / ac), {"beta_threshold": 1.0, "provenance": "test"},
                         contact_area=ac, particle_area=ap, contact_area_std=zeros, particle_area_std=zeros,
                         extras={"simulated": sim, "contact_area_se": zeros, "particle_area_se": zeros,
                                 "particle_area_clusters": 0.25 * ap, "particle_area_clusters_se": zeros})


@pytest.mark.parametrize("r", [0.25, 0.6, 1.0])
def test_flake_borne_shear_scales_the_debris_effect_by_one_minus_r(r):
    table = read_table(DEFAULT_TABLE)
    pressure, v, beta = 2e7, 0.08, np.array([0.0, 0.05, 0.1, 0.2])
    base = make_friction_law(StripDrawParameters(flake_shear_ratio=0.0), table).mu(pressure, v, beta)[0]
    with_r = make_friction_law(StripDrawParameters(flake_shear_ratio=r), table).mu(pressure, v, beta)[0]
    assert base[0] == with_r[0] == 0.15
    np.testing.assert_allclose(0.15 - with_r, (1 - r) * (0.15 - base), rtol=1e-12, atol=1e-17)
    law = make_friction_law(StripDrawParameters(friction_model="closed_form", flake_shear_ratio=r))
    closed = make_friction_law(StripDrawParameters(friction_model="closed_form", flake_shear_ratio=0.0))
    np.testing.assert_allclose(0.15 - law.mu(pressure, v, beta)[0], (1 - r) * (0.15 - closed.mu(pressure, v, beta)[0]),
                               rtol=1e-12, atol=1e-17)


@pytest.mark.parametrize("archard_k, beta0", [(0.0, 0.1), (1e-4, 0.0), (1e-4, 0.03)])
def test_the_sink_integrates_source_and_decay_exactly(archard_k, beta0):
    """No transport (zeta 0), constant mu (no cap below 1): a node under the pad for the whole slide s (its
    displacement) holds beta0 e^(-s/lambda) + q lambda (1 - e^(-s/lambda)), q = K P / (H h_p), to rounding."""
    lam = 0.01
    p = StripDrawParameters(friction_model="constant", zeta=0.0, draw_length=0.01, archard_k=archard_k,
                            beta_initial=beta0, debris_sink_length=lam)
    m = StripDrawModel(p, make_friction_law(p))
    X0 = m.mesh.X.copy()
    _draw(m, 100)
    inside = (X0 - 0.5 * m.mesh.element_length > m.mesh.window_lo) & (
        X0 + m.U + 0.5 * m.mesh.element_length < m.mesh.window_hi)
    assert inside.sum() >= 10
    s = m.U[inside]
    q = archard_k * P / (p.hardness * p.particle_thickness)
    np.testing.assert_allclose(m.beta[inside], beta0 * np.exp(-s / lam) + q * lam * -np.expm1(-s / lam),
                               rtol=1e-12, atol=1e-15)


def test_debris_balance_with_the_sink():
    p = StripDrawParameters(draw_length=0.06, beta_initial=0.001, debris_sink_length=0.02)
    m = StripDrawModel(p, make_friction_law(p, read_table(DEFAULT_TABLE)))
    start = float(m.beta.sum())
    _draw(m, 700)
    assert m.beta_removed > 0.1 * m.beta_produced
    assert float(m.beta.sum()) - start == pytest.approx(m.beta_produced - m.beta_removed, rel=1e-12)


@pytest.mark.parametrize("carry", [1.0, 0.4, 0.0])
def test_a_later_pass_keeps_the_carried_share_of_the_field(carry):
    p = StripDrawParameters(friction_model="constant", debris_carry_over=carry)
    n = p.n_elements + 1
    field = np.linspace(0.0, 0.3, n)
    m = StripDrawModel(p, make_friction_law(p), beta_field=field)
    np.testing.assert_array_equal(m.beta, carry * field)


def test_the_cluster_rule_reads_its_own_area_and_needs_a_version_3_table():
    t = _version3()
    beta = np.array([0.0, 0.25, 0.5])
    every = make_friction_law(StripDrawParameters(), t).mu(2e7, 0.5, beta)[0]
    rule = make_friction_law(StripDrawParameters(particle_area_rule="clusters"), t).mu(2e7, 0.5, beta)[0]
    lost = 1 - StripDrawParameters().flake_shear_ratio  # the debris effect times 1 - r
    np.testing.assert_allclose(every, 0.15 * (1 - lost * 0.8 * beta / 0.5), rtol=1e-12)
    np.testing.assert_allclose(rule, 0.15 * (1 - lost * 0.25 * 0.8 * beta / 0.5), rtol=1e-12)
    v2 = FrictionTable(t.pressure, t.velocity, t.beta, t.mu, t.metadata, contact_area=t.contact_area,
                       particle_area=t.particle_area, contact_area_std=t.contact_area_std,
                       particle_area_std=t.particle_area_std)
    with pytest.raises(ParameterError, match="particle_area_rule = 'clusters' needs a friction table of format version 3"):
        make_friction_law(StripDrawParameters(particle_area_rule="clusters"), v2)


def test_lookups_that_read_an_unsimulated_node_are_counted():
    """The top beta node not simulated: a query in the last cell (weight on it > 0) is flagged, one on the node
    below or in the first cell is not; with every node simulated nothing is; a strip drawn with such a table counts
    its lookups only once beta passes the last simulated level."""
    beta = np.array([0.1, 0.25, 0.3, 0.49])
    flagged = make_friction_law(StripDrawParameters(), _version3(0.0)).mu(2e7, 0.5, beta)[1]
    assert flagged.tolist() == [False, False, True, True]
    assert not make_friction_law(StripDrawParameters(), _version3(1.0)).mu(2e7, 0.5, beta)[1].any()
    counts = []
    for start in (0.2, 0.3):
        p = StripDrawParameters(beta_initial=start, archard_k=0.0)
        m = StripDrawModel(p, make_friction_law(p, _version3(0.0)))
        counts.append(_draw(m, 20)[-1]["table_clamp_count"])
    assert counts[0] == 0 and counts[1] > 0
