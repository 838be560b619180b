"""Geometry of oblate-spheroid flakes on a pixel grid, and their random initial placement.

A flake with centre r, rotation R (body -> space) and semi-axes (a, a, c) is the set
(p - r)^T M (p - r) <= 1, M = R diag(a^-2, a^-2, c^-2) R^T. The vertical line through a grid
point (X, Y) meets it where M33 t^2 + 2 t (M13 dX + M23 dY) + (M11 dX^2 + 2 M12 dX dY + M22 dY^2 - 1)
= 0 with t = z - r_z, (dX, dY) the periodic (minimum-image) offset of the grid point from the
centre. Grid points with a real root are the flake's footprint; the smaller root gives the
flake's lower surface z_lo(X, Y) (used in Eq. 18) and the larger its upper surface
z_hi(X, Y) (z_p of Fig. 8, compared with the tool to classify the flake).

Grid convention: arrays are indexed [ix, iy], the value of pixel (ix, iy) sits at (ix dx, iy dx).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tribocosim.errors import ParameterError

from .dem import face_samples
from .footprint_kernels import _rasterise
from .flake_body import FlakeShape, rotation_matrices


@dataclass(frozen=True)
class Footprint:
    """The part of the grid under one flake.

    Attributes
    ----------
    ix, iy : ndarray (wx,), (wy,)
        Global pixel indices of the window's rows/columns (already wrapped mod n).
    z_lo, z_hi : ndarray (wx, wy)
        Lower and upper surface heights over each window pixel [m]; NaN outside the footprint.
    """

    ix: np.ndarray
    iy: np.ndarray
    z_lo: np.ndarray
    z_hi: np.ndarray

    @property
    def inside(self) -> np.ndarray:
        """Boolean (wx, wy) mask of the footprint."""
        return np.isfinite(self.z_lo)


class Footprints:
    """The footprints of a set of flakes, all windows of one size, as stacked arrays: a sequence of
    :class:`Footprint` (made when one is asked for) whose arrays the classification of a slide reads at once.

    Attributes
    ----------
    ix, iy : ndarray (k, w)
        Global pixel indices of each window's rows/columns (wrapped mod n).
    z_lo, z_hi : ndarray (k, w, w)
        Lower and upper surface heights [m]; NaN outside the footprint.
    inside : ndarray (k, w, w) of bool
        The footprints' masks.
    """

    __slots__ = ("ix", "iy", "z_lo", "z_hi", "inside", "_flat")

    def __init__(self, ix, iy, z_lo, z_hi, flat=None):
        self.ix, self.iy, self.z_lo, self.z_hi = ix, iy, z_lo, z_hi
        self.inside = np.isfinite(z_lo)
        self._flat = flat  # (n, flat indices) of the last flat_indices(n), shared by footprints on the same windows

    @classmethod
    def of(cls, fps) -> Footprints:
        """``fps`` itself if it is a Footprints, else the list of :class:`Footprint` stacked (one window size)."""
        if isinstance(fps, Footprints):
            return fps
        fps = list(fps)
        if not fps:
            return cls(np.zeros((0, 0), np.int64), np.zeros((0, 0), np.int64), np.zeros((0, 0, 0)),
                       np.zeros((0, 0, 0)))
        if len({fp.z_lo.shape for fp in fps}) != 1:
            raise ParameterError(f"footprint windows of sizes {sorted({fp.z_lo.shape for fp in fps})}; allowed: "
                                 f"one size (the windows of one footprints() call)")
        return cls(np.stack([fp.ix for fp in fps]), np.stack([fp.iy for fp in fps]),
                   np.stack([fp.z_lo for fp in fps]), np.stack([fp.z_hi for fp in fps]))

    def __len__(self) -> int:
        return len(self.z_lo)

    def __getitem__(self, k: int) -> Footprint:
        return Footprint(self.ix[k], self.iy[k], self.z_lo[k], self.z_hi[k])

    def __iter__(self):
        return (self[k] for k in range(len(self)))

    def take(self, idx) -> Footprints:
        """The footprints of the flakes ``idx`` (integer indices)."""
        flat = None if self._flat is None else (self._flat[0], self._flat[1][idx])
        return Footprints(self.ix[idx], self.iy[idx], self.z_lo[idx], self.z_hi[idx], flat)

    def with_faces(self, z_lo, z_hi) -> Footprints:
        """The same windows with other lower and upper surfaces."""
        return Footprints(self.ix, self.iy, z_lo, z_hi, self._flat)

    def windows(self, field) -> np.ndarray:
        """(k, w, w): ``field`` (n, n) read over every window."""
        field = np.asarray(field)
        return np.take(field.reshape(-1), self.flat_indices(field.shape[0]))

    def flat_indices(self, n: int) -> np.ndarray:
        """(k, w, w): the flat indices of the windows' pixels in an (n, n) grid (computed once per n)."""
        if self._flat is None or self._flat[0] != n:
            self._flat = (n, self.ix[:, :, None] * n + self.iy[:, None, :])
        return self._flat[1]


def footprints(pos, quat, shape: FlakeShape, n: int, size: float) -> Footprints:
    """Rasterise every flake on the n x n grid of a periodic domain of side ``size``.

    Returns
    -------
    Footprints
        One footprint per flake, windows of (2 ceil(a/dx) + 3)^2 pixels around the pixel of each centre.
    """
    dx = size / n
    a, c = shape.a, shape.c
    pos = np.asarray(pos, dtype=np.float64).reshape(-1, 3)
    rot = rotation_matrices(quat)
    half = int(math.ceil(a / dx)) + 1
    if len(pos) == 0:
        return Footprints.of([])
    m = (rot @ np.diag([a**-2, a**-2, c**-2])) @ rot.transpose(0, 2, 1)  # R diag(a^-2, a^-2, c^-2) R^T
    return Footprints(*_rasterise(np.ascontiguousarray(m), np.ascontiguousarray(pos), dx, half, n))


def _bilinear_np(h, x, y, dx):
    n0, n1 = h.shape
    u, v = x / dx, y / dx
    fu, fv = np.floor(u), np.floor(v)
    tx, ty = u - fu, v - fv
    i0, j0 = fu.astype(np.int64) % n0, fv.astype(np.int64) % n1
    i1, j1 = (i0 + 1) % n0, (j0 + 1) % n1
    return ((1 - tx) * (1 - ty) * h[i0, j0] + tx * (1 - ty) * h[i1, j0]
            + (1 - tx) * ty * h[i0, j1] + tx * ty * h[i1, j1])


def random_placement(n_flakes: int, shape: FlakeShape, size: float, h_low, h_top,
                     seed: int, clearance: float | None = None,
                     max_attempts: int = 200, stacked: bool = False) -> np.ndarray:
    """Seeded random flat placement of flakes resting on the lower surface, inside the gap.

    Each flake is laid flat (symmetry axis along z) at a uniformly random (x, y); its centre
    height is the lowest at which no face point is below ``h_low`` plus ``clearance``. A
    candidate is rejected if its upper face comes within ``clearance`` of the tool ``h_top``
    (the gap is too thin there). Monolayer (``stacked`` False): a candidate whose centre is
    closer than d_p (in plane, periodic) to an already placed flake is rejected too, which bounds
    beta by the jamming of random sequential adsorption (0.547; in practice ~0.45 with the
    attempts given). Deposition (``stacked`` True): a candidate overlapping placed flakes in plane
    rests on the highest of them, its mid-plane at least h_p + ``clearance`` above theirs (flat discs:
    the DEM's flake-flake contact, a disc swept by a sphere of radius h_p/2, then starts without
    overlap).

    Parameters
    ----------
    n_flakes : int
    shape : FlakeShape
    size : float
        Domain side L [m].
    h_low, h_top : ndarray (n, n)
        Lower surface and tool (in its current vertical position) [m].
    seed : int
    clearance : float, optional
        Gap left to both surfaces [m]; default 2 % of h_p.
    max_attempts : int
        Candidates tried per flake before giving up.

    Returns
    -------
    ndarray (n_flakes, 3)
        Centre positions [m].

    Raises
    ------
    ParameterError
        If the flakes cannot cover the domain without overlap, or if no admissible place is
        found within the attempts.
    """
    if n_flakes < 0:
        raise ParameterError(f"number of flakes = {n_flakes} is negative; allowed: >= 0")
    if shape.diameter >= 0.5 * size:
        raise ParameterError(f"flake diameter d_p = {shape.diameter:g} m does not fit the domain "
                             f"L = {size:g} m; allowed: d_p < L/2")
    beta = n_flakes * shape.area / size**2
    if beta > 0.5 and not stacked:
        raise ParameterError(f"flake area fraction beta = n_flakes pi a^2 / L^2 = {beta:.3g} "
                             f"is too large for a non-overlapping placement; allowed: <= 0.5")
    h_low = np.asarray(h_low, dtype=np.float64)
    h_top = np.asarray(h_top, dtype=np.float64)
    n = h_low.shape[0]
    dx = size / n
    clearance = 0.02 * shape.thickness if clearance is None else float(clearance)
    pts, _ = face_samples(shape, 0.5 * dx)
    zb = shape.c * np.sqrt(np.maximum(0.0, 1.0 - np.sum(pts**2, axis=1) / shape.a**2))
    rng = np.random.default_rng(seed)
    placed: list[np.ndarray] = []
    for k in range(n_flakes):
        for _ in range(max_attempts):
            x, y = rng.uniform(0.0, size, 2)
            below = -np.inf
            if placed:
                d = np.asarray(placed)[:, :2] - (x, y)
                d -= size * np.round(d / size)
                near = np.hypot(d[:, 0], d[:, 1]) < shape.diameter
                if near.any():
                    if not stacked:
                        continue
                    below = np.max(np.asarray(placed)[near, 2]) + shape.thickness + clearance
            px, py = x + pts[:, 0], y + pts[:, 1]
            z = max(np.max(_bilinear_np(h_low, px, py, dx) + zb) + clearance, below)
            if np.all(_bilinear_np(h_top, px, py, dx) - (z + zb) >= clearance):
                placed.append(np.array([x, y, z]))
                break
        else:
            raise ParameterError(
                f"could not place flake {k} of {n_flakes} (d_p = {shape.diameter:g} m, "
                f"h_p = {shape.thickness:g} m) in the gap without overlap after {max_attempts} "
                f"attempts; use fewer/smaller flakes or a lower pressure")
    return np.asarray(placed, dtype=np.float64).reshape(-1, 3)
