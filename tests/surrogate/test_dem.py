"""Tests of surrogate.dem: conservation laws, settling, exact free motion, kernels vs NumPy."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tribocosim.components.errors import ParameterError
from tribocosim.surrogate import dem
from tribocosim.surrogate.dem import DemBlowUpError, DemParams, DemState, FlakeShape
from tribocosim.surrogate.flakes import axis_angle_quaternion, rotation_matrices

L = 100e-6
N = 32
DX = L / N
SHAPE = FlakeShape(12e-6, 0.5e-6, 2700.0)


def make_params(damping=0.0, v_ref=50.0, shape=SHAPE, spacing=DX / 2):
    return DemParams.build(shape, L, DX, 55e9, v_ref, damping, spacing=spacing)


def flat(z):
    return np.full((N, N), float(z))


# ------------------------------------------------------------------------------------------
# NumPy oracles (slow, straightforward): the numba kernels are tested against these
# ------------------------------------------------------------------------------------------
def bilinear_ref(h, x, y, dx):
    n = h.shape[0]
    u, v = x / dx, y / dx
    i0, j0 = int(np.floor(u)), int(np.floor(v))
    tx, ty = u - i0, v - j0
    i0, j0 = i0 % n, j0 % n
    i1, j1 = (i0 + 1) % n, (j0 + 1) % n
    val = ((1 - tx) * (1 - ty) * h[i0, j0] + tx * (1 - ty) * h[i1, j0]
           + (1 - tx) * ty * h[i0, j1] + tx * ty * h[i1, j1])
    gx = ((1 - ty) * (h[i1, j0] - h[i0, j0]) + ty * (h[i1, j1] - h[i0, j1])) / dx
    gy = ((1 - tx) * (h[i0, j1] - h[i0, j0]) + tx * (h[i1, j1] - h[i1, j0])) / dx
    return val, np.array([gx, gy])


def forces_ref(pos, quat, p: DemParams, h_low, h_top, shift, offset, dh_low=None, lam=0.0):
    a, c = p.shape.a, p.shape.c
    nf = len(pos)
    F, T, ov, E = np.zeros((nf, 3)), np.zeros((nf, 3)), np.zeros(nf), 0.0
    rot = rotation_matrices(quat)
    zb = c * np.sqrt(np.maximum(0, 1 - np.sum(p.samples**2, 1) / a**2))
    for i in range(nf):
        down = -1.0 if rot[i][2, 2] >= 0 else 1.0
        for k, ((xb, yb), w) in enumerate(zip(p.samples, p.weights)):
            kw = p.k_area * w
            for sgn, top in ((down, False), (-down, True)):
                r = rot[i] @ np.array([xb, yb, sgn * zb[k]])
                x = pos[i] + r
                if top:
                    h, g = bilinear_ref(h_top, x[0] - shift, x[1], p.dx)
                    d = x[2] - (h + offset)
                    f = kw * d * np.array([g[0], g[1], -1.0])
                else:
                    h, g = bilinear_ref(h_low, x[0], x[1], p.dx)
                    if dh_low is not None:
                        h2, g2 = bilinear_ref(dh_low, x[0], x[1], p.dx)
                        h, g = h + lam * h2, g + lam * g2
                    d = h - x[2]
                    f = kw * d * np.array([-g[0], -g[1], 1.0])
                if d > 0:
                    F[i] += f
                    T[i] += np.cross(r, f)
                    E += 0.5 * kw * d * d
                    ov[i] = max(ov[i], d)
    ac = a - c
    for i in range(nf):
        for j in range(i + 1, nf):
            o = pos[j] - pos[i]
            o[:2] -= L * np.floor(o[:2] / L + 0.5)
            if np.linalg.norm(o) >= 2 * a:
                continue
            for P, Q, off in ((i, j, o), (j, i, -o)):
                nq = rot[Q][:, 2]
                for (xb, yb), w in zip(p.samples * (ac / a), p.weights):
                    kw = 0.5 * p.k_area * w * (ac / a) ** 2
                    r = rot[P] @ np.array([xb, yb, 0.0])
                    v = r - off
                    t = v - (v @ nq) * nq
                    if np.linalg.norm(t) > ac:
                        t *= ac / np.linalg.norm(t)
                    e = v - t
                    d = 2 * c - np.linalg.norm(e)
                    if d > 0:
                        f = kw * d * e / np.linalg.norm(e)
                        F[P] += f
                        T[P] += np.cross(r, f)
                        F[Q] -= f
                        T[Q] -= np.cross(t, f)
                        E += 0.5 * kw * d * d
                        ov[P] = max(ov[P], d)
                        ov[Q] = max(ov[Q], d)
    return F, T, ov, E


def qmul(p, q):
    w1, v1, w2, v2 = p[0], p[1:], q[0], q[1:]
    return np.concatenate([[w1 * w2 - v1 @ v2], w1 * v2 + w2 * v1 + np.cross(v1, v2)])


def step_ref(s: DemState, p: DemParams, h_low, h_top, shift0, dshift, offset, dtop=0.0,
             dh_low=None):
    """One step of the documented splitting, written with NumPy."""
    s = s.copy()
    m = p.shape.mass
    i1, i3 = p.shape.inertia
    dec = math.exp(-0.5 * p.damping * p.dt)
    F, T, _, _ = forces_ref(s.pos, s.quat, p, h_low, h_top, shift0, offset)
    s.vel = s.vel * dec + 0.5 * p.dt * F / m
    s.angmom = s.angmom * dec + 0.5 * p.dt * T
    s.pos = s.pos + p.dt * s.vel
    s.pos[:, :2] %= L
    for i in range(len(s.pos)):
        Lv = s.angmom[i]
        n = rotation_matrices(s.quat[i])[0][:, 2]
        q = qmul(axis_angle_quaternion(Lv, np.linalg.norm(Lv) * p.dt / i1), s.quat[i])
        q = qmul(q, axis_angle_quaternion([0, 0, 1], (Lv @ n) * (1 / i3 - 1 / i1) * p.dt))
        s.quat[i] = q / np.linalg.norm(q)
    F, T, _, _ = forces_ref(s.pos, s.quat, p, h_low, h_top, shift0 + dshift, offset + dtop,
                            dh_low, 1.0)
    s.vel = (s.vel + 0.5 * p.dt * F / m) * dec
    s.angmom = (s.angmom + 0.5 * p.dt * T) * dec
    return s


def rough(seed, amp=0.05e-6):
    """Pixel noise; the gap opens by 2 um on both sides for x >= 62.5 um (pixels 20-31)."""
    rng = np.random.default_rng(seed)
    h = amp * rng.standard_normal((N, N))
    h[20:, :] += 2e-6 if seed % 2 == 0 else -2e-6
    return h


def tangled_state():
    """Four tilted, moving flakes, two touching across the periodic boundary, one floating."""
    rng = np.random.default_rng(3)
    pos = np.array([[2e-6, 50e-6, 0.02e-6], [L - 9.8e-6, 51e-6, 0.05e-6], [60e-6, 20e-6, 0.0],
                    [80e-6, 40e-6, 0.0]])  # the last one floats in the wide gap at x > 62 um
    quat = np.array([axis_angle_quaternion(rng.standard_normal(3), 0.03) for _ in range(4)])
    return DemState(pos, quat, rng.standard_normal((4, 3)), 1e-16 * rng.standard_normal((4, 3)))


# ------------------------------------------------------------------------------------------
def test_forces_kernel_matches_numpy_reference():
    p = make_params(spacing=DX)
    s = tangled_state()
    h_low, h_top = rough(1) - 0.25e-6, rough(2) + 0.25e-6
    got = dem.compute_forces(s, p, h_low, h_top, top_shift=0.37 * DX, top_offset=0.02e-6)
    ref = forces_ref(s.pos, s.quat, p, h_low, h_top, 0.37 * DX, 0.02e-6)
    assert np.all(got[2][:3] > 0) and got[2][3] == 0, "contacts on flakes 0-2, none on 3"
    far = dem.compute_forces(s, p, flat(-1e-3), flat(1e-3))
    assert far[2][0] > 0 and far[2][1] > 0, "flakes 0 and 1 must touch across the boundary"
    for g, r, name in zip(got, ref, ("force", "torque", "overlap", "energy")):
        assert_allclose(g, r, rtol=1e-10, atol=1e-12 * np.max(np.abs(r)), err_msg=name)


def test_advance_one_step_matches_numpy_reference():
    p = make_params(damping=3e7, spacing=DX)
    s = tangled_state()
    s.pos[3, 2] = 1.6e-6  # moving up towards the tool's broad-phase bound during the step
    s.vel[3, 2] = 2e4
    h_low, h_top = rough(1) - 0.25e-6, rough(2) + 0.25e-6
    dh = 0.3 * rough(5)  # the sheet moves during the step (ramped over the call)
    ref = step_ref(s, p, h_low, h_top, 0.1 * DX, 0.01 * DX, 0.02e-6, dtop=-3e-9, dh_low=dh)
    dem.advance(s, p, h_low, h_top, 1, shift0=0.1 * DX, dshift=0.01 * DX, top_offset=0.02e-6,
                dtop=-3e-9, dh_low=dh)
    for name in ("pos", "quat", "vel", "angmom"):
        assert_allclose(getattr(s, name), getattr(ref, name), rtol=1e-10,
                        atol=1e-13 * np.max(np.abs(getattr(ref, name))), err_msg=name)


def test_free_flake_moves_ballistically_and_exactly():
    p = make_params()
    v = np.array([[30.0, -20.0, 0.5]])
    s = DemState(np.array([[50e-6, 50e-6, 0.0]]), np.array([[1.0, 0, 0, 0]]), v, np.zeros((1, 3)))
    x0 = s.pos.copy()
    nsteps = 4000
    dem.advance(s, p, flat(-1e-3), flat(1e-3), nsteps)
    expect = x0 + v * nsteps * p.dt
    expect[:, :2] %= L
    assert_allclose(s.pos, expect, rtol=1e-12, atol=1e-18, err_msg="ballistic position")
    assert_allclose(s.vel, v, rtol=0, atol=0, err_msg="velocity must not change")


def test_spinning_flake_conserves_angular_momentum_and_precesses_exactly():
    p = make_params()
    i1, i3 = SHAPE.inertia
    q0 = axis_angle_quaternion([1.0, 0.3, 0.0], 0.7)
    Lv = np.array([2e-17, -1e-17, 4e-17])  # not along the symmetry axis: the top precesses
    s = DemState(np.array([[50e-6, 50e-6, 0.0]]), q0[None], np.zeros((1, 3)), Lv[None])
    e0 = dem.kinetic_energy(s, SHAPE)
    n0 = rotation_matrices(q0)[0][:, 2]
    nsteps = 5000
    dem.advance(s, p, flat(-1e-3), flat(1e-3), nsteps)
    t = nsteps * p.dt
    assert_allclose(s.angmom[0], Lv, rtol=1e-14, err_msg="angular momentum")
    assert_allclose(dem.kinetic_energy(s, SHAPE), e0, rtol=1e-10, err_msg="rotational energy")
    # torque-free symmetric top: the symmetry axis precesses about L at |L|/I1
    phi = np.linalg.norm(Lv) * t / i1
    assert phi > 2.0, "the test must cover a substantial precession angle"
    n_exact = rotation_matrices(axis_angle_quaternion(Lv, phi))[0] @ n0
    assert_allclose(rotation_matrices(s.quat)[0][:, 2], n_exact, atol=1e-9,
                    err_msg="symmetry axis vs analytic precession")


def bounce_run(damping, nsteps, tilt=0.15, spin=1e-19):
    """A tilted, spinning flake bouncing between two flat surfaces."""
    p = make_params(damping=damping)
    gap = 3.0 * SHAPE.thickness
    q0 = axis_angle_quaternion([0.0, 1.0, 0.0], tilt)
    s = DemState(np.array([[50e-6, 50e-6, 0.0]]), q0[None], np.array([[3.0, 1.0, 20.0]]),
                 np.array([[spin, 0.5 * spin, 0.2 * spin]]))
    h_low, h_top = flat(-0.5 * gap), flat(0.5 * gap)
    energies, overlaps = [], []
    for _ in range(nsteps // 50):
        dem.advance(s, p, h_low, h_top, 50)
        _, _, ov, epot = dem.compute_forces(s, p, h_low, h_top)
        energies.append(dem.kinetic_energy(s, SHAPE) + epot)
        overlaps.append(ov[0])
    return p, s, np.array(energies), np.array(overlaps)


def test_bouncing_flake_conserves_energy_without_damping():
    p, s, e, ov = bounce_run(0.0, 60000)
    n_contacts = np.count_nonzero(np.diff((ov > 0).astype(int)) == 1)
    assert n_contacts >= 4, f"expected several impacts, got {n_contacts}"
    assert_allclose(e, e[0], rtol=0.01, err_msg="total energy drifts by more than 1 %")


def test_bouncing_flake_settles_with_damping():
    p, s, e, ov = bounce_run(5e7, 60000)
    assert e[-1] < 1e-6 * e[0], f"energy did not decay: {e[0]:.3e} -> {e[-1]:.3e}"
    # settled flat between the two surfaces: no overlap, symmetry axis vertical
    n = rotation_matrices(s.quat)[0][:, 2]
    assert abs(abs(n[2]) - 1.0) < 1e-6 or ov[-1] == 0.0


def test_pinched_flake_settles_to_symmetric_equilibrium():
    """gap = h_p - 2 d0: with damping the flake ends flat, centred, overlap d0 on both faces."""
    p = make_params(damping=5e7)
    d0 = 0.02 * SHAPE.thickness
    half = 0.5 * SHAPE.thickness - d0
    s = DemState(np.array([[50e-6, 50e-6, 0.03e-6]]),
                 axis_angle_quaternion([1.0, 0.0, 0.0], 0.02)[None],
                 np.array([[0.0, 0.0, 2.0]]), np.zeros((1, 3)))
    h_low, h_top = flat(-half), flat(half)
    dem.advance(s, p, h_low, h_top, 40000)
    F, T, ov, _ = dem.compute_forces(s, p, h_low, h_top)
    assert_allclose(s.pos[0, 2], 0.0, atol=1e-4 * d0, err_msg="centred")
    assert_allclose(ov[0], d0, rtol=1e-3, err_msg="overlap d0 at equilibrium")
    assert_allclose(abs(rotation_matrices(s.quat)[0][2, 2]), 1.0, atol=1e-9, err_msg="flat")
    assert dem.kinetic_energy(s, SHAPE) < 1e-6 * 0.5 * SHAPE.mass * 2.0**2, "not at rest"


@pytest.mark.parametrize("diameter", [6e-6, 12e-6, 24e-6])
def test_pole_impact_at_v0_keeps_overlap_below_five_percent(diameter):
    """A flat flake (curved face, pole first) hitting a flat surface normally at v0."""
    v0 = 50.0
    shape = FlakeShape(diameter, 0.5e-6)
    p = make_params(v_ref=v0, shape=shape, spacing=0.2e-6)
    s = DemState(np.array([[50e-6, 50e-6, 0.3e-6]]), np.array([[1.0, 0, 0, 0]]),
                 np.array([[0.0, 0.0, -v0]]), np.zeros((1, 3)))
    worst = 0.0
    for _ in range(200):
        dem.advance(s, p, flat(0.0), flat(1e-3), 5)
        worst = max(worst, dem.compute_forces(s, p, flat(0.0), flat(1e-3))[2][0])
    assert s.vel[0, 2] > 0, "flake must have rebounded"
    # the rule is exact for the continuous face; the sampled face adds < 2 %
    assert 0 < worst <= 1.02 * 0.05 * shape.thickness, f"overlap {worst / shape.thickness:.2%}"
    assert_allclose(s.vel[0, 2], v0, rtol=1e-3, err_msg="elastic rebound speed")


@pytest.mark.parametrize("v_ref", [5.0, 50.0, 500.0])
def test_hertz_rule_overlap_at_peak_force_and_impact_energy(v_ref):
    k = dem.penalty_stiffness(SHAPE, 55e9, v_ref)
    m, R, d_a = SHAPE.mass, SHAPE.a**2 / SHAPE.c, 0.05 * SHAPE.thickness
    d_h = (15 * m * v_ref**2 / (16 * 55e9 * math.sqrt(R))) ** 0.4
    f_h = 4 / 3 * 55e9 * math.sqrt(R) * d_h**1.5
    # Hertz energy balance: work of the Hertz force up to d_h equals the kinetic energy
    assert_allclose(0.4 * f_h * d_h, 0.5 * m * v_ref**2, rtol=1e-12, err_msg="Hertz impact")
    # penalty paraboloid (pole): F(d) = k pi R d^2, U(d) = k pi R d^3 / 3
    d_static = math.sqrt(f_h / (k * math.pi * R))
    d_dynamic = (1.5 * m * v_ref**2 / (k * math.pi * R)) ** (1 / 3)
    assert d_static <= d_a * (1 + 1e-12), "overlap at the Hertz peak force exceeds 5 % h_p"
    assert d_dynamic <= d_a * (1 + 1e-12), "impact overlap exceeds 5 % h_p"
    assert_allclose(max(d_static, d_dynamic), d_a, rtol=1e-12, err_msg="rule is not tight")


def test_flake_collision_conserves_momentum_angular_momentum_and_energy():
    p = make_params()
    pos = np.array([[20e-6, 50e-6, 0.0], [33e-6, 52e-6, 0.1e-6]])
    quat = np.array([axis_angle_quaternion([0, 1, 0], 0.05), axis_angle_quaternion([1, 0, 0], -0.04)])
    s = DemState(pos, quat, np.array([[20.0, 0.0, 0.0], [-10.0, 0.0, 0.0]]), np.zeros((2, 3)))
    m = SHAPE.mass
    far = (flat(-1e-3), flat(1e-3))

    def totals(st):
        lin = m * st.vel.sum(0)
        ang = (m * np.cross(st.pos, st.vel)).sum(0) + st.angmom.sum(0)
        return lin, ang, dem.kinetic_energy(st, SHAPE) + dem.compute_forces(st, p, *far)[3]

    p0, l0, e0 = totals(s)
    touched = False
    for _ in range(400):  # no periodic wrap in this window of time: positions stay inside
        dem.advance(s, p, *far, 25)
        touched |= dem.compute_forces(s, p, *far)[2][0] > 0
    p1, l1, e1 = totals(s)
    assert touched and dem.compute_forces(s, p, *far)[2][0] == 0, "must collide and separate"
    assert_allclose(p1, p0, atol=1e-12 * m * 20, err_msg="linear momentum")
    assert_allclose(l1, l0, atol=1e-9 * m * 20 * 50e-6, err_msg="angular momentum")
    assert_allclose(e1, e0, rtol=0.01, err_msg="energy")


def test_head_on_collision_of_equal_flat_flakes_exchanges_velocities():
    p = make_params()
    s = DemState.at_rest([[20e-6, 50e-6, 0.0], [33e-6, 50e-6, 0.0]])
    s.vel[:, 0] = [20.0, -10.0]
    far = (flat(-1e-3), flat(1e-3))
    dem.advance(s, p, *far, 12000)
    assert dem.compute_forces(s, p, *far)[2].max() == 0, "flakes still in contact"
    assert_allclose(s.vel[:, 0], [-10.0, 20.0], rtol=1e-6, err_msg="1D elastic collision")
    assert_allclose(s.angmom, 0.0, atol=1e-30, err_msg="a central collision makes no spin")


def test_overlap_blow_up_names_step_and_flake():
    p = make_params()
    s = DemState.at_rest([[50e-6, 50e-6, 0.0], [10e-6, 10e-6, 0.0]])
    h_top = flat(0.5e-6)
    # the tool comes down on the second flake only: a ridge at x ~ 10 um
    h_top[3:7, :] = -0.05e-6
    with pytest.raises(DemBlowUpError, match=r"step \d+.*flake 1"):
        dem.advance(s, p, flat(-0.25e-6), h_top, 10, step_offset=100)
    s = DemState.at_rest([[50e-6, 50e-6, np.nan]])
    with pytest.raises(DemBlowUpError, match="flake 0"):
        dem.advance(s, p, flat(-1e-3), flat(1e-3), 3)


def test_bad_parameters_are_rejected():
    with pytest.raises(ParameterError, match="thickness"):
        FlakeShape(1e-6, 2e-6)
    with pytest.raises(ParameterError, match="diameter"):
        FlakeShape(-1e-6)
    with pytest.raises(ParameterError, match="does not fit"):
        make_params(shape=FlakeShape(60e-6, 0.5e-6))
    with pytest.raises(ParameterError, match="v_ref"):
        dem.penalty_stiffness(SHAPE, 55e9, 0.0)
