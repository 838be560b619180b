"""Damping of the flakes by the lubricant: the thin-disc Stokes resistances against the
ellipsoid integrals, exact exponential decay of a free flake at the four principal rates, the kernel's
principal-axis damping against NumPy, bad input, and the default (one rate gamma = 5e7 1/s) unchanged."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.integrate import quad

from tribocosim.errors import ParameterError
from tribocosim.surrogate import dem, flake_body
from tribocosim.surrogate.campaign import case_id
from tribocosim.surrogate.coupling import SlideSimulation, run_slide
from tribocosim.surrogate.dem import DampingRates, DemParams, DemState, FlakeShape
from tribocosim.surrogate.flake_body import axis_angle_quaternion, rotation_matrices
from tribocosim.surrogate.slide_config import SlideConfig

L = 100e-6
N = 32
DX = L / N
SHAPE = FlakeShape(12e-6, 0.5e-6, 2700.0)
ETA = 32e-6 * 870.0  # ISO VG 32 at 40 C: 32 mm^2/s x 870 kg/m^3 [Pa s]


def flat(z):
    return np.full((N, N), float(z))


def params(damping, spacing=DX):
    return DemParams.build(SHAPE, L, DX, 55e9, 50.0, damping, spacing=spacing)


def disc_rates(shape: FlakeShape, eta: float) -> dict:
    """The rates derived here from the disc's resistances (force 16 eta a v broadside, 32/3 eta a v
    edgewise; torque 32/3 eta a^3 omega about a diameter and about the axis) and the spheroid's mass and
    principal moments."""
    a, c = 0.5 * shape.diameter, 0.5 * shape.thickness
    m = shape.density * 4.0 / 3.0 * math.pi * a * a * c
    i_diameter, i_axis = m * (a * a + c * c) / 5.0, 2.0 * m * a * a / 5.0
    return {"velocity_plane": 32.0 / 3.0 * eta * a / m, "velocity_axial": 16.0 * eta * a / m,
            "angmom_diameter": 32.0 / 3.0 * eta * a**3 / i_diameter,
            "angmom_axis": 32.0 / 3.0 * eta * a**3 / i_axis}


# ------------------------------------------------------------------------------------------
# the resistances: thin-disc limit of the ellipsoid (Oberbeck 1876; Jeffery 1922)
# ------------------------------------------------------------------------------------------
def ellipsoid_resistances(a1, a2, a3):
    """Stokes resistances of an ellipsoid with semi-axes a1, a2, a3 per unit viscosity:
    force / U along each axis, 16 pi / (chi + a_i^2 alpha_i), and torque / Omega about each axis,
    16 pi (a_j^2 + a_k^2) / (3 (a_j^2 alpha_j + a_k^2 alpha_k)), with
    chi = int_0^inf dl / D, alpha_i = int_0^inf dl / ((a_i^2 + l) D), D = sqrt(prod (a_i^2 + l))
    (Kim & Karrila, Microhydrodynamics, 1991, Ch. 3). Quadrature in u = ln l."""
    ax = np.array([a1, a2, a3], dtype=float)
    brk = sorted({2.0 * math.log(x) for x in ax})

    def integral(f):
        lo, hi = brk[0] - 40.0, brk[-1] + 70.0  # tails: e^-20 of the first, e^-35 of the last
        g = lambda u: math.exp(u) * f(math.exp(u))  # noqa: E731
        return quad(g, lo, hi, points=brk, limit=400, epsabs=0.0, epsrel=1e-11)[0]

    delta = lambda lam: math.sqrt(np.prod(ax**2 + lam))  # noqa: E731
    chi = integral(lambda lam: 1.0 / delta(lam))
    alpha = [integral(lambda lam, i=i: 1.0 / ((ax[i] ** 2 + lam) * delta(lam))) for i in range(3)]
    force = [16.0 * math.pi / (chi + ax[i] ** 2 * alpha[i]) for i in range(3)]
    torque = [16.0 * math.pi * (ax[j] ** 2 + ax[k] ** 2)
              / (3.0 * (ax[j] ** 2 * alpha[j] + ax[k] ** 2 * alpha[k]))
              for j, k in ((1, 2), (0, 2), (0, 1))]
    return np.array(force), np.array(torque)


def test_ellipsoid_integrals_give_stokes_law_for_a_sphere():
    force, torque = ellipsoid_resistances(1.0, 1.0, 1.0)
    assert_allclose(force, 6.0 * math.pi, rtol=1e-9, err_msg="6 pi eta a")
    assert_allclose(torque, 8.0 * math.pi, rtol=1e-9, err_msg="8 pi eta a^3")


def test_disc_coefficients_are_the_thin_limit_of_the_oblate_spheroid():
    """F = 16 eta a v broadside, 32/3 eta a v edgewise, T = 32/3 eta a^3 omega about both axes: the
    spheroid's resistances converge to them linearly in c/a and, as the thicker body, exceed them (so
    the disc values are a lower bound for the flake)."""
    expect_f = np.array([flake_body.DISC_EDGEWISE, flake_body.DISC_EDGEWISE, flake_body.DISC_BROADSIDE])
    expect_t = np.full(3, flake_body.DISC_ROTATION)
    errors = []
    for ratio in (1e-2, 1e-3, 1e-4):
        force, torque = ellipsoid_resistances(1.0, 1.0, ratio)
        rel = np.concatenate([force / expect_f, torque / expect_t]) - 1.0
        assert np.all(rel > 0.0), (ratio, rel)
        errors.append(np.max(rel))
    order = np.polyfit(np.log([1e-2, 1e-3, 1e-4]), np.log(errors), 1)[0]
    assert_allclose(order, 1.0, atol=0.1, err_msg="convergence order in c/a")
    assert errors[-1] < 1e-3
    # at the flake's own aspect ratio (c/a = 0.042) the disc formulas are a few per cent low
    force, torque = ellipsoid_resistances(SHAPE.a, SHAPE.a, SHAPE.c)
    rel = np.concatenate([force / (expect_f * SHAPE.a), torque / (expect_t * SHAPE.a**3)]) - 1.0
    assert np.all((rel > 0.0) & (rel < 0.1)), rel


def test_rates_from_viscosity_follow_the_disc_formulas():
    got = DampingRates.from_viscosity(SHAPE, ETA)
    for name, value in disc_rates(SHAPE, ETA).items():
        assert_allclose(getattr(got, name), value, rtol=1e-14, err_msg=name)
    assert_allclose(flake_body.VG32_VISCOSITY_40C, ETA, rtol=1e-15)
    assert not got.is_uniform and DampingRates.uniform(3.0).is_uniform


# ------------------------------------------------------------------------------------------
# closed-form decay of a free flake
# ------------------------------------------------------------------------------------------
def test_free_flake_velocity_decays_at_the_axial_and_in_plane_rates():
    """No contacts, no rotation: v_n(t) = v_n(0) exp(-gamma_axial t), v_p(t) = v_p(0) exp(-gamma_plane t)
    exactly (the damping sub-flows are exact), and the centre moves by the midpoint sum of that decay,
    v0 (1 - exp(-gamma t)) dt / (2 sinh(gamma dt / 2)) per component."""
    rates = disc_rates(SHAPE, ETA)
    p = params(DampingRates(**rates))
    q0 = axis_angle_quaternion([0.3, -1.0, 0.2], 0.8)
    n = rotation_matrices(q0)[0][:, 2]
    v_axial = 3.0 * n
    v_plane = np.cross(n, [1.0, 0.0, 0.0])
    v_plane *= 5.0 / np.linalg.norm(v_plane)
    s = DemState(np.array([[50e-6, 50e-6, 0.0]]), q0[None], (v_axial + v_plane)[None], np.zeros((1, 3)))
    x0 = s.pos[0].copy()
    nsteps = 8000
    dem.advance(s, p, flat(-1e-3), flat(1e-3), nsteps)
    t = nsteps * p.dt
    g_a, g_p = rates["velocity_axial"], rates["velocity_plane"]
    assert g_p * t > 1.0 and g_a * t > 1.0, "the run must cover more than one decay time"
    vn = s.vel[0] @ n
    assert_allclose(vn, 3.0 * math.exp(-g_a * t), rtol=1e-11, err_msg="axial velocity")
    assert_allclose(s.vel[0] - vn * n, v_plane * math.exp(-g_p * t), rtol=1e-11,
                    atol=1e-14, err_msg="in-plane velocity")
    assert_allclose(s.quat[0], q0, rtol=0, atol=1e-15, err_msg="no rotation")

    def travel(v0, g):
        return v0 * (1.0 - math.exp(-g * t)) * p.dt / (2.0 * math.sinh(0.5 * g * p.dt))

    expect = x0 + travel(v_axial, g_a) + travel(v_plane, g_p)
    d = s.pos[0] - expect
    d[:2] -= L * np.round(d[:2] / L)
    assert_allclose(d, 0.0, atol=1e-12 * np.linalg.norm(travel(v_plane, g_p)), err_msg="position")


def test_free_flake_angular_velocity_decays_at_the_diameter_and_axis_rates():
    """No contacts, no translation: free rotation keeps L.n and |L - (L.n) n| (the top precesses) and the
    damping scales them, so omega_axis = L.n / I3 decays at (32/3) eta a^3 / I3 and
    |omega_perp| = |L_perp| / I1 at (32/3) eta a^3 / I1, exactly."""
    rates = disc_rates(SHAPE, ETA)
    p = params(DampingRates(**rates))
    i1, i3 = SHAPE.inertia
    q0 = axis_angle_quaternion([1.0, 0.3, 0.0], 0.7)
    Lv = np.array([2e-17, -1e-17, 4e-17])
    s = DemState(np.array([[50e-6, 50e-6, 0.0]]), q0[None], np.zeros((1, 3)), Lv[None])

    def split(state):
        n = rotation_matrices(state.quat)[0][:, 2]
        omega = dem.angular_velocity(state, SHAPE)[0]
        w_axis = omega @ n
        return w_axis, np.linalg.norm(omega - w_axis * n)

    w_axis0, w_perp0 = split(s)
    nsteps = 8000
    dem.advance(s, p, flat(-1e-3), flat(1e-3), nsteps)
    t = nsteps * p.dt
    assert rates["angmom_axis"] * t > 1.0, "the run must cover more than one decay time"
    w_axis, w_perp = split(s)
    assert_allclose(w_axis, w_axis0 * math.exp(-rates["angmom_axis"] * t), rtol=1e-10,
                    err_msg="spin about the symmetry axis")
    assert_allclose(w_perp, w_perp0 * math.exp(-rates["angmom_diameter"] * t), rtol=1e-10,
                    err_msg="rotation about a diameter")
    assert_allclose(s.vel, 0.0, atol=0.0, err_msg="no translation")
    assert_allclose(s.pos[0], [50e-6, 50e-6, 0.0], rtol=0, atol=0.0)


def qmul(p, q):
    w1, v1, w2, v2 = p[0], p[1:], q[0], q[1:]
    return np.concatenate([[w1 * w2 - v1 @ v2], w1 * v2 + w2 * v1 + np.cross(v1, v2)])


def damp_ref(s: DemState, r: DampingRates, dt: float):
    """Half-flow of the principal-axis damping, NumPy."""
    for i in range(len(s.pos)):
        n = rotation_matrices(s.quat[i])[0][:, 2]
        for arr, g_perp, g_axis in ((s.vel, r.velocity_plane, r.velocity_axial),
                                    (s.angmom, r.angmom_diameter, r.angmom_axis)):
            along = (arr[i] @ n) * n
            arr[i] = math.exp(-0.5 * g_perp * dt) * (arr[i] - along) + math.exp(-0.5 * g_axis * dt) * along


def test_one_step_with_contacts_matches_numpy_splitting():
    """The kernel's damping half-flows against NumPy around the (separately tested) forces."""
    r = DampingRates.from_viscosity(SHAPE, 0.3)  # a viscous oil: damping visible in one step
    p = params(r)
    rng = np.random.default_rng(7)
    pos = np.array([[20e-6, 50e-6, 0.0], [70e-6, 40e-6, 0.01e-6]])
    quat = np.array([axis_angle_quaternion(rng.standard_normal(3), 0.05) for _ in range(2)])
    s = DemState(pos, quat, rng.standard_normal((2, 3)), 1e-16 * rng.standard_normal((2, 3)))
    h_low, h_top = flat(-0.24e-6) + 0.02e-6 * rng.standard_normal((N, N)), flat(0.24e-6)
    ref = s.copy()
    m, (i1, i3) = SHAPE.mass, SHAPE.inertia
    damp_ref(ref, r, p.dt)
    F, T, _, _ = dem.compute_forces(ref, p, h_low, h_top)
    assert np.all(np.abs(F[:, 2]) > 0), "both flakes must touch"
    ref.vel += 0.5 * p.dt * F / m
    ref.angmom += 0.5 * p.dt * T
    ref.pos += p.dt * ref.vel
    for i in range(2):
        Lv = ref.angmom[i]
        n = rotation_matrices(ref.quat[i])[0][:, 2]
        q = qmul(axis_angle_quaternion(Lv, np.linalg.norm(Lv) * p.dt / i1), ref.quat[i])
        q = qmul(q, axis_angle_quaternion([0, 0, 1], (Lv @ n) * (1 / i3 - 1 / i1) * p.dt))
        ref.quat[i] = q / np.linalg.norm(q)
    F, T, _, _ = dem.compute_forces(ref, p, h_low, h_top)
    ref.vel += 0.5 * p.dt * F / m
    ref.angmom += 0.5 * p.dt * T
    damp_ref(ref, r, p.dt)
    dem.advance(s, p, h_low, h_top, 1)
    for name in ("pos", "quat", "vel", "angmom"):
        assert_allclose(getattr(s, name), getattr(ref, name), rtol=1e-10,
                        atol=1e-13 * np.max(np.abs(getattr(ref, name))), err_msg=name)


# ------------------------------------------------------------------------------------------
# bad input
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("value, message", [
    (-0.1, r"oil viscosity eta = -0\.1 Pa s is out of range; allowed: \[0, inf\) Pa s"),
    (float("nan"), r"oil viscosity eta = nan is not finite"),
    ("0.03", r"oil viscosity eta = '0\.03' is not a number; allowed: a finite number in \[0, inf\) Pa s"),
])
def test_bad_viscosity_is_refused_with_name_value_and_range(value, message):
    with pytest.raises(ParameterError, match=message):
        DampingRates.from_viscosity(SHAPE, value)


@pytest.mark.parametrize("kw, message", [
    (dict(oil_viscosity=-0.1), r"oil_viscosity = -0\.1 Pa s is out of range; allowed: \[0, inf\) Pa s"),
    (dict(oil_viscosity=float("inf")), r"oil_viscosity = inf is not finite"),
    (dict(damping_rate=float("nan")), r"damping_rate = nan is not finite"),
    (dict(damping_rate=-1.0), r"damping_rate = -1\.0 1/s is out of range; allowed: \[0, inf\) 1/s"),
    (dict(oil_viscosity=0.03, damping_rate=5e7),
     r"damping_rate = 50000000\.0 1/s and oil_viscosity = 0\.03 Pa s are both given; allowed: one"),
])
def test_bad_damping_configuration_is_refused(kw, message):
    with pytest.raises(ParameterError, match=message):
        SlideConfig(**kw)


def test_bad_rates_are_refused():
    with pytest.raises(ParameterError, match=r"damping rate angmom_axis = -1\.0 1/s is out of range"):
        DampingRates(1.0, 1.0, 1.0, -1.0)
    with pytest.raises(ParameterError, match=r"damping rate = -2\.0 1/s is out of range"):
        params(-2.0)


# ------------------------------------------------------------------------------------------
# the default: the oil's viscosity; gamma an expert override
# ------------------------------------------------------------------------------------------
def test_default_configuration_is_vg32_oil_and_gamma_an_override_with_its_own_case_id():
    default, explicit = SlideConfig(), SlideConfig(oil_viscosity=ETA)
    assert default == explicit and default.oil_viscosity == ETA and default.damping_rate is None
    assert default.to_dict() == explicit.to_dict() and case_id(default) == case_id(explicit)
    assert not {"damping_rate", "sheet_rolloff_wavelength", "tool_rolloff_wavelength"} & {
        k for k, v in default.to_dict().items() if v is not None}
    assert SlideConfig.from_dict(default.to_dict()) == default
    gamma = dataclasses.replace(default, oil_viscosity=None, damping_rate=5e7)
    assert "oil_viscosity" not in gamma.to_dict()
    assert SlideConfig.from_dict(gamma.to_dict()) == gamma and case_id(gamma) != case_id(default)
    assert default.damping(SHAPE) == DampingRates.from_viscosity(SHAPE, ETA)
    assert gamma.damping(SHAPE) == 5e7


def test_one_rate_as_float_and_as_uniform_rates_are_bit_identical():
    """The scalar path of the kernel (v, L *= exp(-gamma dt/2)) is the one the existing DEM tests pin;
    four equal rates take it too."""
    rng = np.random.default_rng(3)
    pos = np.array([[2e-6, 50e-6, 0.02e-6], [L - 9.8e-6, 51e-6, 0.05e-6], [60e-6, 20e-6, 0.0]])
    quat = np.array([axis_angle_quaternion(rng.standard_normal(3), 0.03) for _ in range(3)])
    state = DemState(pos, quat, rng.standard_normal((3, 3)), 1e-16 * rng.standard_normal((3, 3)))
    h_low = flat(-0.25e-6) + 0.05e-6 * rng.standard_normal((N, N))
    h_top = flat(0.25e-6) + 0.05e-6 * rng.standard_normal((N, N))
    out = []
    for damping in (5e7, DampingRates.uniform(5e7)):
        s = state.copy()
        dem.advance(s, params(damping), h_low, h_top, 500, shift0=0.1 * DX, dshift=0.001 * DX)
        out.append(np.concatenate([s.pos.ravel(), s.quat.ravel(), s.vel.ravel(), s.angmom.ravel()]))
    assert np.array_equal(out[0], out[1])


def test_slide_default_equals_explicit_viscosity_and_gamma_changes_it():
    base = dict(n=64, size=125e-6, wavelength_ratio=0.1, n_flakes=5, n_slide_steps=3, pressure=20e6,
                v0=10.0)
    runs = {name: run_slide(SlideConfig(**base, **kw)) for name, kw in
            (("default", {}), ("oil", {"oil_viscosity": ETA}), ("gamma", {"damping_rate": 5e7}))}
    a, b, c = runs["default"], runs["oil"], runs["gamma"]
    for name in ("contact_fraction", "particle_fraction", "tool_height"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert np.array_equal(a.snapshots[3]["pos"], b.snapshots[3]["pos"])
    assert not np.array_equal(a.snapshots[3]["pos"], c.snapshots[3]["pos"]), "gamma must change the DEM"
    sim = SlideSimulation(SlideConfig(**base, oil_viscosity=ETA))
    assert sim.params.damping == DampingRates.from_viscosity(sim.shape, ETA)
