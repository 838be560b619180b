"""Tests of the overdamped flake solver (surrogate.flake_relax, surrogate.relax_kernels): the DEM's contact law,
its Gauss-Newton Hessian, force balance against closed forms, partial readings, determinism, its regime."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tribocosim.errors import ParameterError
from tribocosim.surrogate import dem
from tribocosim.surrogate import dem_kernels as dk
from tribocosim.surrogate import relax_kernels as rk
from tribocosim.surrogate.coupling import run_slide
from tribocosim.surrogate.dem import DemParams, DemState, FlakeShape
from tribocosim.surrogate.flake_body import DampingRates, axis_angle_quaternion
from tribocosim.surrogate.flake_relax import TOL_MOVE_FRACTION, Drag, RelaxStats, relax
from tribocosim.surrogate.slide_config import SlideConfig

L = 64e-6
N = 64
DX = L / N
SHAPE = FlakeShape(12e-6, 0.5e-6, 2700.0)
H_P = SHAPE.thickness


def params():
    return DemParams.build(SHAPE, L, DX, 55e9, 50.0, 1e7, spacing=DX, pair_spacing=2 * DX)


def drag(scale=1.0):
    rates = DampingRates.from_viscosity(SHAPE, 0.0278 * scale)
    return Drag(rates, SHAPE.mass, SHAPE.inertia)


def rough(seed, amplitude):
    x = np.arange(N) * DX
    rng = np.random.default_rng(seed)
    h = np.zeros((N, N))
    for _ in range(6):
        kx, ky = rng.integers(1, 6, 2)
        ph = rng.uniform(0, 2 * np.pi, 2)
        h += np.cos(2 * np.pi * kx * x / L + ph[0])[:, None] * np.cos(2 * np.pi * ky * x / L + ph[1])[None, :]
    return amplitude * h / np.abs(h).max()


def kernel_totals(state, p, h_low, h_top, shift=0.0, offset=0.0):
    """Forces, torques, Hessian and energy of every flake from the solver's face and pair parts."""
    nf, ns = len(state.pos), len(p.samples)
    zf = dk._face_heights(p.samples, SHAPE.a, SHAPE.c)
    rot = np.empty((nf, 3, 3))
    fp, fh = np.zeros((nf, 8)), np.zeros((nf, 1, 6, 6))
    rec, gaps, near = np.zeros((nf, rk._REC)), np.zeros((nf, 2, ns)), np.zeros((nf, 2, ns + 1), dtype=np.int64)
    half = int(math.ceil(SHAPE.a / DX)) + 3
    dh = np.zeros_like(h_low)
    for i in range(nf):
        rk._read_faces(i, state.pos, state.quat, rot, h_low, dh, 0.0, h_top, shift, offset, DX, SHAPE.a,
                       p.samples, zf, p.weights, p.k_area, half, 0.5 * H_P, 1e-9 * SHAPE.c, fp, fh, rec, gaps,
                       near, rk.new_bounds(h_low.shape))
    pairs = np.ascontiguousarray(np.stack(np.triu_indices(nf, 1), axis=1), dtype=np.int64)
    npairs = len(pairs)
    pp, ph = np.zeros((max(npairs, 1), 14)), np.zeros((max(npairs, 1), 3, 6, 6))
    point_gaps, point_ref = np.zeros((max(npairs, 1), 2, len(p.pair_points[0]))), np.full((max(npairs, 1), 2), -1.0)
    for m in range(npairs):  # full readings
        rk._read_pair(m, pairs, state.pos, state.quat, rot, L, SHAPE.a, SHAPE.c, *p.pair_points, p.k_area, pp, ph,
                      np.zeros(nf), point_gaps, point_ref, 0.5 * H_P, 1e-9 * SHAPE.c)
    adj_start, adj = np.zeros(nf + 1, dtype=np.int64), np.empty(max(2 * npairs, 1), dtype=np.int64)
    rk._adjacency(nf, pairs, npairs, adj_start, adj)
    F, T, H, E, ov = np.zeros((nf, 3)), np.zeros((nf, 3)), np.zeros((nf, 6, 6)), np.zeros(nf), np.zeros(nf)
    for i in range(nf):
        rk._total(i, fp, fh, adj_start, adj, pairs, pp, ph, F, T, H, E, ov)
    return F, T, H, E, ov, (fp, fh, rec, gaps, near)


def deposit(seed=3, nf=6):
    """Flakes near a rough sheet, a rough tool 0.9 h_p above it and on one another (overlapping both)."""
    rng = np.random.default_rng(seed)
    pos = np.column_stack([rng.uniform(0, L, nf), rng.uniform(0, L, nf), rng.uniform(-0.1, 0.4, nf) * H_P])
    pos[1, :2] = pos[0, :2] + (3e-6, 1e-6)
    pos[1, 2] = pos[0, 2] + 0.8 * H_P
    quat = np.array([axis_angle_quaternion(rng.normal(size=3), rng.uniform(0, 0.08)) for _ in range(nf)])
    return DemState.at_rest(pos, quat), rough(seed, 0.2e-6), rough(seed + 1, 0.2e-6) + 0.9 * H_P


def test_forces_are_the_dem_contact_law():
    state, h_low, h_top = deposit()
    p = params()
    F, T, _, E, ov, _ = kernel_totals(state, p, h_low, h_top, shift=0.3 * DX, offset=0.01e-6)
    Fd, Td, ovd, Ed = dem.compute_forces(state, p, h_low, h_top, top_shift=0.3 * DX, top_offset=0.01e-6)
    assert np.abs(Fd).max() > 0 and ovd.max() > 0 and np.count_nonzero(ovd) >= 3, "the deposit must touch"
    scale = np.abs(Fd).max()
    assert_allclose(F, Fd, atol=1e-12 * scale, err_msg="forces differ from dem.compute_forces")
    assert_allclose(T, Td, atol=1e-12 * scale * SHAPE.a, err_msg="torques differ from dem.compute_forces")
    assert_allclose(E.sum(), Ed, rtol=1e-12)
    assert_allclose(ov, ovd, rtol=1e-12)


def test_hessian_is_the_derivative_of_the_forces_on_flat_surfaces():
    """On flat surfaces a face point's overlap is linear in the translation, so the Gauss-Newton Hessian is
    the exact derivative of the forces in the translations."""
    p = params()
    q = axis_angle_quaternion([1.0, 0.4, 0.0], 0.03)[None, :]
    state = DemState.at_rest([[30e-6, 31e-6, 0.2 * H_P]], q)
    h_low, h_top = np.zeros((N, N)), np.full((N, N), 0.95 * H_P)
    F0, T0, H, *_ = kernel_totals(state, p, h_low, h_top)
    for r in range(3):
        step = np.zeros(3)
        step[r] = 1e-11
        moved = DemState.at_rest(state.pos + step, q)
        F1, T1, *_ = kernel_totals(moved, p, h_low, h_top)
        assert_allclose(-(np.concatenate([F1[0], T1[0]]) - np.concatenate([F0[0], T0[0]])) / 1e-11, H[0][:, r],
                        rtol=1e-5, atol=1e-9 * np.abs(H[0]).max())


def test_pinched_flake_balances_halfway_between_flat_surfaces():
    """A flat flake between flat surfaces a gap g < h_p apart: each face overlaps by (h_p - g)/2, no net force."""
    p = params()
    gap = 0.8 * H_P
    state = DemState.at_rest([[31e-6, 30e-6, 0.53 * H_P]])
    stats = RelaxStats()
    relax(state, p, drag(), np.zeros((N, N)), np.full((N, N), gap), 4, stats=stats)
    assert_allclose(state.pos[0, 2], 0.5 * gap, atol=1e-3 * H_P)
    _, _, _, _, ov, _ = kernel_totals(state, p, np.zeros((N, N)), np.full((N, N), gap))
    assert_allclose(ov[0], 0.5 * (H_P - gap), atol=1e-3 * H_P)
    F, T, *_ = kernel_totals(state, p, np.zeros((N, N)), np.full((N, N), gap))
    # balanced to the solver's tolerance: a last step of at most TOL_MOVE_FRACTION h_p against two faces
    residual = 2.0 * p.k_area * SHAPE.area * TOL_MOVE_FRACTION * H_P
    assert np.abs(F).max() < residual and np.abs(T).max() < residual * SHAPE.a
    assert stats.substeps == 4 and stats.iterations >= 4


def test_flake_without_contact_stays_where_it_is():
    p = params()
    state = DemState.at_rest([[20e-6, 40e-6, 0.6e-6]], axis_angle_quaternion([0, 1, 0], 0.02)[None, :])
    before = state.copy()
    relax(state, p, drag(), np.zeros((N, N)), np.full((N, N), 2e-6), 8, dshift=0.1 * DX)
    assert np.array_equal(state.pos, before.pos) and np.array_equal(state.quat, before.quat)


def test_wedge_squeezes_a_frictionless_flake_towards_its_opening():
    """A tool inclined in x over a flat sheet: the gap opens towards +x; a flake pinched in the wedge slides
    there until it fits (frictionless: nothing holds it), and ends free of load."""
    p = params()
    x = np.arange(N) * DX
    slope = 0.02
    h_top = np.broadcast_to((0.6 * H_P + slope * (x - 20e-6))[:, None], (N, N)).copy()
    state = DemState.at_rest([[20e-6, 30e-6, 0.5 * H_P]])
    x0 = state.pos[0, 0]
    relax(state, p, drag(), np.zeros((N, N)), h_top, 8)
    assert state.pos[0, 0] > x0 + 1e-6, "the flake must move towards the opening of the wedge"
    F, T, *_ = kernel_totals(state, p, np.zeros((N, N)), h_top)
    assert np.abs(F).max() < 1e-6 * p.k_area * SHAPE.area * H_P


def test_equilibrium_does_not_depend_on_the_drag():
    """The drag only sets the path between equilibria: a unique one (a pinched flake) is the same for a 100
    times more viscous oil."""
    p = params()
    out = []
    for scale in (1.0, 100.0):
        state = DemState.at_rest([[31e-6, 30e-6, 0.45 * H_P]], axis_angle_quaternion([1, 0, 0], 0.01)[None, :])
        relax(state, p, drag(scale), np.zeros((N, N)), np.full((N, N), 0.8 * H_P), 4)
        out.append(state.pos[0, 2])
    assert_allclose(out[0], out[1], atol=1e-3 * H_P)


def test_a_partial_reading_equals_a_full_one():
    """After a small move, a face read from the points near contact gives the full reading's sums exactly."""
    state, h_low, h_top = deposit(seed=5)
    p = params()
    _, _, _, _, _, (fp, fh, rec, gaps, near) = kernel_totals(state, p, h_low, h_top)
    moved = DemState.at_rest(state.pos + [2e-9, -1e-9, 3e-9], state.quat)
    nf, ns = len(state.pos), len(p.samples)
    zf = dk._face_heights(p.samples, SHAPE.a, SHAPE.c)
    half = int(math.ceil(SHAPE.a / DX)) + 3
    rot, dh = np.empty((nf, 3, 3)), np.zeros_like(h_low)
    full_fp, full_fh = np.zeros_like(fp), np.zeros_like(fh)
    partial = 0
    for i in range(nf):
        was_full = rk._read_faces(i, moved.pos, moved.quat, rot, h_low, dh, 0.0, h_top, 0.0, 0.0, DX, SHAPE.a,
                                  p.samples, zf, p.weights, p.k_area, half, 0.5 * H_P, 1e-9 * SHAPE.c, fp, fh, rec,
                                  gaps, near, rk.new_bounds(h_low.shape))
        partial += not was_full
        rk._read_faces(i, moved.pos, moved.quat, rot, h_low, dh, 0.0, h_top, 0.0, 0.0, DX, SHAPE.a, p.samples,
                       zf, p.weights, p.k_area, half, 0.5 * H_P, 1e-9 * SHAPE.c, full_fp, full_fh,
                       np.zeros((nf, rk._REC)), np.zeros((nf, 2, ns)), np.zeros((nf, 2, ns + 1), dtype=np.int64),
                       rk.new_bounds(h_low.shape))
    assert partial == nf, "every face must have been read in part"
    assert np.array_equal(fp, full_fp) and np.array_equal(fh, full_fh)


def small_slide(**over):
    cfg = SlideConfig(n=32, size=64e-6, pressure=20e6, v0=0.08, n_flakes=8, flake_seed=4,
                      wavelength_ratio=0.125, sheet_rolloff_wavelength=32e-6, tool_rolloff_wavelength=16e-6,
                      n_slide_steps=6, placement="deposition", placement_pressure=1e6, flake_solver="overdamped",
                      **over)
    return run_slide(cfg)


@pytest.mark.parametrize("flakes", [1, 3, 20])
def test_the_step_solve_is_the_solution_of_the_damped_system(flakes):
    """delta = (H + nu D)^-1 F: the residual of the solve is round-off of the system's scale, on a Gauss-Newton sum
    of rank-one terms with translations and rotations of different units (as H + nu D is), and an indefinite
    matrix is reported, not solved."""
    rng = np.random.default_rng(flakes)
    n = 6 * flakes
    scale = np.repeat([[1.0, 1.0, 1.0, 1e-5, 1e-5, 1e-5]], flakes, axis=0).ravel()  # m against rad (a ~ 6 um)
    rows = rng.normal(size=(2 * n, n)) * scale
    m = 1e7 * rows.T @ rows + 1e-3 * np.diag(scale**2)
    x = rng.normal(size=n)
    factor, y = m.copy(), x.copy()
    assert rk._cholesky_solve(factor, y)
    assert_allclose(m @ y, x, rtol=0, atol=1e-12 * np.abs(m).max() * np.abs(y).max() * n)
    assert_allclose(np.tril(factor) @ np.tril(factor).T, m, rtol=0, atol=1e-13 * np.abs(m).max())
    indefinite = m - 2.0 * np.abs(m).max() * np.eye(n)
    assert not rk._cholesky_solve(indefinite, x.copy())


def test_overdamped_slide_is_deterministic_and_counts_its_work():
    a, b = small_slide(), small_slide()
    assert np.array_equal(a.particle_fraction, b.particle_fraction)
    assert np.array_equal(a.contact_fraction, b.contact_fraction)
    assert a.info["relax_substeps"] == 6 * 8 and a.info["dem_steps_per_pixel"] == 8
    assert small_slide(relax_substeps=2).info["relax_substeps"] == 6 * 2


def test_overdamped_solver_is_refused_where_the_flakes_are_not_overdamped():
    base = dict(n=32, size=64e-6, wavelength_ratio=0.125, flake_solver="overdamped")
    SlideConfig(v0=0.08, **base)
    with pytest.raises(ParameterError, match=r"Lambda = gamma dx / v0 = .*allowed: Lambda >= "):
        SlideConfig(v0=50.0, **base)
    with pytest.raises(ParameterError, match="flake_solver = 'implicit' is not known"):
        SlideConfig(v0=0.08, **{**base, "flake_solver": "implicit"})
    with pytest.raises(ParameterError, match="every rate > 0"):
        Drag(DampingRates.uniform(0.0), SHAPE.mass, SHAPE.inertia)


def test_auto_takes_the_overdamped_solver_where_lambda_allows_it():
    """``auto`` is resolved when the configuration is made: the case's dict (and id) names the solver that runs."""
    base = dict(n=32, size=64e-6, wavelength_ratio=0.125, flake_solver="auto")
    slow, fast = SlideConfig(v0=0.08, **base), SlideConfig(v0=50.0, **base)
    assert slow.overdamped and not fast.overdamped
    assert slow.to_dict()["flake_solver"] == "overdamped" and fast.to_dict()["flake_solver"] == "inertial"
    assert slow._damping_per_pixel() > 20.0 > fast._damping_per_pixel()


def test_inertial_case_ids_do_not_see_the_new_keys():
    """The solver keys are left out of a configuration's dict while unset, so the recorded inertial cases keep
    their ids."""
    cfg = SlideConfig()
    assert "flake_solver" not in cfg.to_dict() and "relax_substeps" not in cfg.to_dict()
    assert replace(cfg, flake_solver="overdamped", v0=0.08).to_dict()["flake_solver"] == "overdamped"
