"""Tests of surrogate.flakes: spheroid footprints on the grid and the random placement."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tribocosim.errors import ParameterError
from tribocosim.surrogate.dem import FlakeShape
from tribocosim.surrogate.flake_body import axis_angle_quaternion, rotation_matrices
from tribocosim.surrogate.flakes import footprints, random_placement

SHAPE = FlakeShape(12e-6, 0.5e-6)
N, L = 64, 64e-6  # dx = 1 um


def test_rotation_matrix_is_orthonormal_and_rotates_about_axis():
    q = axis_angle_quaternion([0.0, 0.0, 1.0], 0.5 * math.pi)
    R = rotation_matrices(q)[0]
    assert_allclose(R @ [1.0, 0, 0], [0, 1.0, 0], atol=1e-15, err_msg="x -> y about z")
    q = axis_angle_quaternion([1.0, 2.0, -0.5], 1.1)
    R = rotation_matrices(q)[0]
    assert_allclose(R @ R.T, np.eye(3), atol=1e-14, err_msg="orthonormal")


def test_flat_flake_footprint_matches_spheroid_faces():
    centre = np.array([[20.3e-6, 40.7e-6, 1e-6]])
    fp = footprints(centre, [[1.0, 0, 0, 0]], SHAPE, N, L)[0]
    X, Y = np.meshgrid(fp.ix * 1e-6, fp.iy * 1e-6, indexing="ij")
    r2 = (X - centre[0, 0]) ** 2 + (Y - centre[0, 1]) ** 2
    inside = r2 <= SHAPE.a**2
    assert np.array_equal(fp.inside, inside), "footprint = grid points within the disc"
    face = SHAPE.c * np.sqrt(1 - r2[inside] / SHAPE.a**2)
    assert_allclose(fp.z_hi[inside], 1e-6 + face, rtol=0, atol=1e-18, err_msg="upper face")
    assert_allclose(fp.z_lo[inside], 1e-6 - face, rtol=0, atol=1e-18, err_msg="lower face")


def test_tilted_flake_footprint_area_and_vertical_chord():
    theta = 0.6
    q = axis_angle_quaternion([0.0, 1.0, 0.0], theta)
    fine_n = 256  # dx = 0.25 um for an accurate pixel count
    fp = footprints([[30e-6, 30e-6, 0.0]], [q], SHAPE, fine_n, L)[0]
    # projected ellipse: semi-axes a and sqrt(a^2 cos^2 + c^2 sin^2)
    b = math.sqrt(SHAPE.a**2 * math.cos(theta) ** 2 + SHAPE.c**2 * math.sin(theta) ** 2)
    area = fp.inside.sum() * (L / fine_n) ** 2
    assert_allclose(area, math.pi * SHAPE.a * b, rtol=0.02, err_msg="projected area")
    # vertical chord through the centre: 2 / sqrt(M33), M33 = sin^2/a^2 + cos^2/c^2
    i = np.flatnonzero(fp.ix == 120)[0]
    j = np.flatnonzero(fp.iy == 120)[0]
    chord = 2.0 / math.sqrt(math.sin(theta) ** 2 / SHAPE.a**2 + math.cos(theta) ** 2 / SHAPE.c**2)
    assert_allclose(fp.z_hi[i, j] - fp.z_lo[i, j], chord, rtol=1e-12, err_msg="chord")


def test_footprint_wraps_periodically():
    fp = footprints([[0.2e-6, 63.9e-6, 0.0]], [[1.0, 0, 0, 0]], SHAPE, N, L)[0]
    assert fp.ix.min() == 0 and fp.ix.max() == N - 1, "window wraps in x"
    assert fp.inside.sum() == footprints([[32.2e-6, 31.9e-6, 0.0]], [[1.0, 0, 0, 0]],
                                         SHAPE, N, L)[0].inside.sum()


def test_random_placement_is_seeded_non_overlapping_and_in_the_gap():
    # smooth wavy surfaces (the placement checks the sheet at the face sample points)
    x = np.arange(4 * N) / N * 2 * np.pi
    big = 4 * L
    h_low4 = 0.5e-6 * np.sin(x)[:, None] * np.cos(x)[None, :]
    h_top4 = 1.2e-6 + 0.4e-6 * np.cos(2 * x)[:, None] + 0 * h_low4
    a = random_placement(8, SHAPE, big, h_low4, h_top4, seed=5)
    b = random_placement(8, SHAPE, big, h_low4, h_top4, seed=5)
    assert np.array_equal(a, b), "same seed, same placement"
    d = a[:, None, :2] - a[None, :, :2]
    d -= big * np.round(d / big)
    dist = np.hypot(d[..., 0], d[..., 1]) + np.eye(8) * big
    assert dist.min() >= SHAPE.diameter, "no in-plane overlap"
    fps = footprints(a, np.tile([1.0, 0, 0, 0], (8, 1)), SHAPE, 4 * N, big)
    for fp in fps:
        lo, hi = h_low4[np.ix_(fp.ix, fp.iy)], h_top4[np.ix_(fp.ix, fp.iy)]
        assert np.all(fp.z_lo[fp.inside] >= lo[fp.inside]), "above the sheet"
        assert np.all(fp.z_hi[fp.inside] <= hi[fp.inside]), "below the tool"


def test_placement_errors_are_clear():
    flat = np.zeros((N, N))
    with pytest.raises(ParameterError, match="does not fit"):
        random_placement(1, FlakeShape(40e-6, 0.5e-6), L, flat, flat + 1e-6, seed=0)
    with pytest.raises(ParameterError, match="beta"):
        random_placement(40, SHAPE, L, flat, flat + 1e-6, seed=0)
    with pytest.raises(ParameterError, match="could not place flake 0"):
        random_placement(1, SHAPE, L, flat, flat + 0.3e-6, seed=0)  # gap thinner than h_p


def footprint_ref(r, R, shape, n, size):
    """One flake's footprint, NumPy, one flake at a time (module docstring of flakes)."""
    dx, a, c = size / n, shape.a, shape.c
    half = int(math.ceil(a / dx)) + 1
    offs = np.arange(-half, half + 1)
    m = R @ np.diag([a**-2, a**-2, c**-2]) @ R.T
    i0, j0 = int(math.floor(r[0] / dx)), int(math.floor(r[1] / dx))
    dX, dY = np.meshgrid((i0 + offs) * dx - r[0], (j0 + offs) * dx - r[1], indexing="ij")
    qa = m[2, 2]
    qb = 2.0 * (m[0, 2] * dX + m[1, 2] * dY)
    qc = m[0, 0] * dX**2 + 2.0 * m[0, 1] * dX * dY + m[1, 1] * dY**2 - 1.0
    disc = qb * qb - 4.0 * qa * qc
    root = np.sqrt(np.where(disc >= 0.0, disc, np.nan))
    return ((i0 + offs) % n, (j0 + offs) % n, r[2] + (-qb - root) / (2.0 * qa),
            r[2] + (-qb + root) / (2.0 * qa))


def test_footprints_of_all_flakes_at_once_equal_one_at_a_time_bit_for_bit():
    """footprints() rasterises every flake in one set of array operations."""
    rng = np.random.default_rng(4)
    pos = np.column_stack([rng.uniform(-2e-6, L, 30), rng.uniform(0, L, 30),
                           rng.uniform(-1e-6, 1e-6, 30)])
    quat = np.array([axis_angle_quaternion(rng.standard_normal(3), rng.uniform(0, 3.1))
                     for _ in range(30)])
    fps = footprints(pos, quat, SHAPE, N, L)
    for r, R, fp in zip(pos, rotation_matrices(quat), fps):
        ix, iy, z_lo, z_hi = footprint_ref(r, R, SHAPE, N, L)
        assert np.array_equal(fp.ix, ix) and np.array_equal(fp.iy, iy)
        assert np.array_equal(fp.z_lo, z_lo, equal_nan=True)
        assert np.array_equal(fp.z_hi, z_hi, equal_nan=True)
    assert len(footprints(np.zeros((0, 3)), np.zeros((0, 4)), SHAPE, N, L)) == 0
