"""Friction laws: calibration, the cap of Eq. 24, and the table built from the closed form."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tribocosim.errors import ParameterError
from tribocosim.components.stripdraw.friction import closed_form_law, closed_form_table, make_friction_law
from tribocosim.components.stripdraw.parameters import StripDrawParameters


def test_closed_form_limits():
    p = StripDrawParameters(friction_model="closed_form", mu0=0.15, kappa=2.0, rms_slope=0.34, alpha_b=20, alpha_v_ref=0.05)
    law = make_friction_law(p)
    # no debris: the particle-free coefficient mu0 (Eq. 6); no sliding: alpha = 0 -> mu0
    assert_allclose(law.mu(1e7, 0.08, 0.0)[0], 0.15)
    assert_allclose(law.mu(1e7, 0.0, 0.2)[0], 0.15)
    # Eq. 24 with the saturated alpha = b: beta_thres = kappa / (b h'); there flakes carry the whole contact at
    # v >> v_ref and mu -> r mu0 (0 with the paper's frictionless flakes)
    assert_allclose(law.beta_threshold, 2.0 / (20 * 0.34))
    assert_allclose(law.mu(1e7, 1e3, law.beta_threshold)[0], p.flake_shear_ratio * 0.15, atol=1e-15)
    paper = make_friction_law(p.replace(flake_shear_ratio=0.0))
    assert_allclose(paper.mu(1e7, 1e3, law.beta_threshold)[0], 0.0, atol=1e-15)
    # Eq. 9 with flake-borne shear: linear in beta with slope -(1 - r) mu0 alpha(v) h'/kappa
    v = 0.08
    alpha = 20 * (1 - np.exp(-v / 0.05))
    mu = law.mu(1e7, v, np.array([0.0, 0.1]))[0]
    assert_allclose(mu[1] - mu[0], -(1 - p.flake_shear_ratio) * 0.15 * alpha * 0.34 / 2.0 * 0.1, rtol=1e-12)


def test_table_law_matches_closed_form_on_its_nodes():
    p = StripDrawParameters(friction_model="table")
    table = closed_form_table(p)
    law = make_friction_law(p, table)
    ref = closed_form_law(p)
    PP, VV, BB = np.meshgrid(table.pressure, table.velocity, table.beta, indexing="ij")
    assert_allclose(law.mu(PP, VV, BB)[0], ref.mu(PP, VV, BB)[0], atol=1e-15)


def test_table_law_needs_a_table_and_says_where_the_shipped_one_is():
    with pytest.raises(ParameterError, match=r"needs a friction table.*read_table\(tribocosim.DEFAULT_TABLE\)"):
        make_friction_law(StripDrawParameters(friction_model="table"))


def _eq23_table(**changes):
    """The closed form tabulated (A_c from Eq. 8, A_p from Eq. 23), alpha rising with v (Fig. 15)."""
    p = StripDrawParameters(friction_model="table", alpha_b=40.0, alpha_v_ref=0.05, **changes)
    return p, closed_form_table(p)


@pytest.mark.parametrize("scale", [1.0, 0.37])
def test_eq8_with_an_eq23_table_reproduces_the_closed_form_eq9_exactly(scale):
    """mu = mu0 (1 - s A_p / A_c) with A_c of Eq. 8 and A_p of Eq. 23 is Eq. 9; A_p is multilinear in
    (P, beta), which the trilinear interpolation reproduces between the nodes (at velocity nodes)."""
    p, table = _eq23_table(contact_area="eq8", particle_area_scale=scale)
    law, ref = make_friction_law(p, table), closed_form_law(p)
    rng = np.random.default_rng(1)
    P = rng.uniform(table.pressure[0], table.pressure[-1], 300)
    V = rng.choice(table.velocity, 300)
    B = rng.uniform(0, table.beta[-1] * 0.9, 300)
    assert_allclose(law.mu(P, V, B)[0], ref.mu(P, V, B)[0], rtol=1e-12, atol=1e-15)
    # the cap (Eq. 24): where s A_p reaches A_c, kappa / (s alpha(v) h'), here at the velocity node v
    for v in table.velocity[table.velocity > 0.2]:
        want = min(1.0, 2.0 / (scale * float(ref.alpha(v)) * 0.34))
        if want < table.beta[-1]:
            assert law.beta_cap(1e7, v) == pytest.approx(want, rel=1e-12)


def test_the_two_conventions_share_mu0_and_differ_by_the_contact_area():
    p, table = _eq23_table()
    meso = make_friction_law(p, table)
    eq8 = make_friction_law(p.replace(contact_area="eq8", e_star=5.5e9), table)  # a 10x larger Eq. 8 area
    assert_allclose(meso.mu(1e7, 1.0, 0.0)[0], 0.15)
    assert_allclose(eq8.mu(1e7, 1.0, 0.0)[0], 0.15)
    # A_p / A_c is 10x smaller with the 10x larger contact area: the debris effect shrinks 10x
    d_meso = 0.15 - meso.mu(1e7, 1.0, 0.05)[0]
    d_eq8 = 0.15 - eq8.mu(1e7, 1.0, 0.05)[0]
    assert d_eq8 == pytest.approx(d_meso / 10, rel=1e-12)


def test_a_version_1_table_gives_its_mu_and_refuses_what_needs_the_areas():
    from tribocosim.components.stripdraw.table import FrictionTable

    _, t2 = _eq23_table()
    t1 = FrictionTable(t2.pressure, t2.velocity, t2.beta, 0.5 * t2.mu, t2.metadata)  # mu only
    assert t1.version == 1 and t2.version == 2
    # a version 1 table holds mu of the paper's frictionless flakes: it serves flake_shear_ratio = 0 ...
    law = make_friction_law(StripDrawParameters(friction_model="table", flake_shear_ratio=0.0), t1)
    assert_allclose(law.mu(1e7, 1.0, 0.01)[0], t1.interpolate(1e7, 1.0, 0.01)[0])
    assert law.beta_cap(1e7, 1.0) == t1.beta_threshold
    # ... and refuses what needs the areas: another A_c, a scale of A_p, flake-borne shear (the default r)
    for bad in ({"contact_area": "eq8", "flake_shear_ratio": 0.0},
                {"particle_area_scale": 2.0, "flake_shear_ratio": 0.0}, {}):
        with pytest.raises(ParameterError, match="needs a friction table of format version 2"):
            make_friction_law(StripDrawParameters(friction_model="table", **bad), t1)
    with pytest.raises(ParameterError, match=r"particle_area_scale = 1 and flake_shear_ratio = 0.2 needs a friction "
                                             r"table of format version 2 .* serves the paper's model alone"):
        make_friction_law(StripDrawParameters(friction_model="table"), t1)  # the values as given, not to 17 digits


def test_closed_form_without_a_velocity_law_uses_alpha_b_and_its_cap():
    p = StripDrawParameters(friction_model="closed_form")  # defaults: alpha = alpha_b at every velocity
    law = make_friction_law(p)
    a = p.alpha_b
    assert p.alpha_v_ref == 0 and law.alpha(0.08) == law.alpha(50.0) == a
    assert law.beta_threshold == pytest.approx(2.0 / (a * 0.34))
    beta = 0.5 * law.beta_threshold  # below the cap: Eq. 9 itself, the debris effect times 1 - r
    assert_allclose(law.mu(1e7, 0.08, beta)[0], 0.15 * (1 - (1 - p.flake_shear_ratio) * a * beta * 0.34 / 2.0))


def test_closed_form_default_alpha_is_the_shipped_campaigns_at_its_slowest_velocity():
    from tribocosim.paths import DEFAULT_TABLE
    from tribocosim.components.stripdraw.table import read_table

    fits = read_table(DEFAULT_TABLE).metadata["fits"]
    per_velocity = fits.get("alpha_eq23_per_velocity") or fits["alpha_per_velocity"]  # format 3 / format 2
    fit = per_velocity[0]
    assert fit["velocity"] == min(a["velocity"] for a in per_velocity)
    assert StripDrawParameters().alpha_b == pytest.approx(fit["alpha"], abs=0.005)


def test_the_strip_caps_beta_where_the_particle_area_reaches_the_contact_area():
    """With Eq. 8's area and Eq. 23's A_p, debris piles up to kappa / (s alpha h') and no further."""
    from tribocosim.components.stripdraw.model import StripDrawModel

    p = StripDrawParameters(friction_model="table", contact_area="eq8", alpha_b=40.0, alpha_v_ref=0.0,
                            archard_k=5e-3, draw_length=0.01, n_elements=60, particle_area_scale=2.0)
    table = closed_form_table(p)
    model = StripDrawModel(p, make_friction_law(p, table))
    cap = 2.0 / (2.0 * 40.0 * 0.34)
    for k in range(120):
        out = model.step(1e-3, {"normal_force": 12250.0, "grip_velocity": 0.08 * min(1.0, (k + 0.5) / 10)})
    assert out["beta_max"] == pytest.approx(cap, rel=1e-12), "saturated at the cap"
    assert model.beta_removed > 0
    floor = p.flake_shear_ratio * p.mu0  # where A_p = A_c the flakes carry the whole contact: mu = r mu0
    assert floor <= out["mu_mean"] < floor + 0.01, (out["mu_mean"], floor)


# ------------------------------------------------------------------------------------------------ a point's slide
U = 2.0**-53


@pytest.fixture(scope="module")
def shipped_law():
    from tribocosim.components.stripdraw.table import read_table
    from tribocosim.paths import DEFAULT_TABLE

    return make_friction_law(StripDrawParameters(), read_table(DEFAULT_TABLE))


def test_a_points_slide_makes_the_archard_production_below_the_cap(shipped_law):
    """beta = beta0 + K P S / (H h_p) (Eq. 37 at contact weight 1), formed as fl(fl(K P) S / (H h_p)): within 4 u."""
    p = StripDrawParameters()
    pressure = np.array([1e6, 2e6, 5e6, 10e6, 20e6, 30e6])
    for slide, beta0 in ((0.02, 0.0), (0.01, 0.03), (0.0, 0.02)):
        beta = shipped_law.beta_after_slide(pressure, 0.08, slide, beta0)
        expected = beta0 + p.archard_k * pressure * slide / (p.hardness * p.particle_thickness)
        assert np.all(beta < [shipped_law.beta_cap(x, 0.08) for x in pressure]), "below the cap"
        assert_allclose(beta, expected, rtol=8 * U, atol=0)
    assert shipped_law.beta_after_slide(20e6, 0.08, 0.02) == pytest.approx(0.1, rel=4 * U)  # 1e-4 20e6 0.02 / 400


def test_with_the_sink_a_points_slide_approaches_q_lambda(shipped_law):
    """d beta / ds = q - beta / lambda: beta = beta0 exp(-S / lambda) + q lambda (1 - exp(-S / lambda))."""
    from tribocosim.components.stripdraw.table import read_table
    from tribocosim.paths import DEFAULT_TABLE

    p = StripDrawParameters(debris_sink_length=0.035)
    law = make_friction_law(p, read_table(DEFAULT_TABLE))
    pressure = np.array([1e6, 5e6, 10e6, 20e6])
    q = p.archard_k * pressure / (p.hardness * p.particle_thickness)
    lam = p.debris_sink_length
    for slide, beta0 in ((0.02, 0.0), (0.1, 0.0), (0.05, 0.04)):
        decay = np.exp(-slide / lam)
        expected = beta0 * decay + q * lam * (1.0 - decay)
        assert_allclose(law.beta_after_slide(pressure, 0.08, slide, beta0), expected, rtol=1e-14, atol=0)
    # a long slide: the balance q lambda, below the cap for these pressures
    assert_allclose(law.beta_after_slide(pressure, 0.08, 50 * lam), q * lam, rtol=1e-14)


def test_a_long_slide_holds_the_laws_cap_and_slides_compose(shipped_law):
    """Beyond the cap (Eq. 24, at (P, v)) beta is the cap itself; and a slide in n increments from each one's end
    reaches the one slide's beta within (2 n + 8) u (each increment's source within 4 u and one rounding of its sum; the
    production is linear in the slide, the cap a constant of the point): what the user routines make of a point that
    slides S in increments. With s = 1.6 (about the paper calibration's) blocked flakes reach the contact inside the
    table's beta axis."""
    from tribocosim.components.stripdraw.table import read_table
    from tribocosim.paths import DEFAULT_TABLE

    law = make_friction_law(StripDrawParameters(particle_area_scale=1.6), read_table(DEFAULT_TABLE))
    pressure = np.array([5e6, 10e6, 30e6])
    caps = np.array([law.beta_cap(x, 0.08) for x in pressure])
    assert np.all(caps < 0.5)
    beta = law.beta_after_slide(pressure, 0.08, 1.0)  # 1 m: far beyond the cap at these pressures
    assert np.array_equal(beta, caps)
    for slide in (0.02, 0.2):  # below the cap, and through it at 10 and 30 MPa
        one = law.beta_after_slide(pressure, 0.08, slide)
        steps, n = np.zeros(pressure.size), 100
        for _ in range(n):
            steps = np.array([law.beta_after_slide(x, 0.08, slide / n, b) for x, b in zip(pressure, steps)])
        assert_allclose(steps, one, rtol=(2 * n + 8) * U, atol=0)
    assert np.array_equal(law.beta_after_slide(pressure[1:], 0.08, 0.2), caps[1:])


@pytest.mark.parametrize("args, message", [
    ((1e6, 0.08, -0.01), "slide = -0.01 m: a finite slide >= 0"),
    ((1e6, 0.08, np.inf), "slide = inf m"),
    ((1e6, 0.08, 0.02, 1.5), "beta_initial = 1.5: a debris area fraction in"),
    ((0.0, 0.08, 0.02), "pressure = 0 Pa, slip rate = 0.08 m/s: a pressure > 0"),
    ((1e6, np.nan, 0.02), "slip rate = nan m/s"),
])
def test_a_bad_slide_is_refused_naming_the_value(shipped_law, args, message):
    with pytest.raises(ParameterError, match=message.replace("(", r"\(")):
        shipped_law.beta_after_slide(*args)
