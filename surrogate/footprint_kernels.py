"""Numba kernels of the flake classification (private; use :mod:`tribocosim.surrogate.coupling`).

Each reads the stacked footprints of :class:`tribocosim.surrogate.flakes.Footprints` (``flat``: the flat
indices of the windows' pixels in the (n, n) grid, ``inside``: the footprint masks, ``z_lo``/``z_hi``: the
flake's lower and upper surface, NaN outside) against a field on the grid, one flake at a time, and computes
what :mod:`tribocosim.surrogate.coupling` defines in array form, with the same floating-point operations (a
difference, a comparison, a minimum or a maximum), so that the numbers are those of the array form bit for bit.
"""

from __future__ import annotations

import numba
import numpy as np

_jit = numba.njit(cache=True)


@_jit
def _largest_cut(flat, inside, z, field, sign):
    """Per flake, the largest of sign (z - field) over its footprint (-inf for an empty footprint): with sign
    1 the depth by which the flake's surface z rises above the field (the tool cutting into its upper face),
    with sign -1 the depth by which the field rises above z (the sheet cutting into its lower face)."""
    k, w0, w1 = inside.shape
    out = np.full(k, -np.inf)
    for f in range(k):
        best = -np.inf
        for a in range(w0):
            for b in range(w1):
                if inside[f, a, b]:
                    h = field[flat[f, a, b]]
                    d = z[f, a, b] - h if sign > 0 else h - z[f, a, b]
                    if d > best:
                        best = d
        out[f] = best
    return out


@_jit
def _overlap_clusters(flat, inside, z_hi, field, threshold):
    """Per flake, the number of 8-connected clusters of its footprint pixels where z_hi > field + threshold
    (within its window: a flake is smaller than the domain, so no cluster wraps around it)."""
    k, w0, w1 = inside.shape
    counts = np.zeros(k, dtype=np.int64)
    mask = np.zeros((w0, w1), dtype=np.bool_)
    stack = np.empty(w0 * w1, dtype=np.int64)
    for f in range(k):
        for a in range(w0):
            for b in range(w1):
                mask[a, b] = inside[f, a, b] and z_hi[f, a, b] > field[flat[f, a, b]] + threshold
        for a in range(w0):
            for b in range(w1):
                if not mask[a, b]:
                    continue
                counts[f] += 1  # a new cluster: clear it by a flood fill
                mask[a, b] = False
                top = 0
                stack[top] = a * w1 + b
                top += 1
                while top > 0:
                    top -= 1
                    p = stack[top]
                    pa, pb = p // w1, p % w1
                    for da in range(-1, 2):
                        for db in range(-1, 2):
                            qa, qb = pa + da, pb + db
                            if 0 <= qa < w0 and 0 <= qb < w1 and mask[qa, qb]:
                                mask[qa, qb] = False
                                stack[top] = qa * w1 + qb
                                top += 1
    return counts


@_jit
def _grown_faces(z_lo, z_hi, idx):
    """For the flakes ``idx``: the lower face replaced by its 3 x 3 pixel minimum and the upper face by its
    3 x 3 maximum within the window (NaN, outside the footprint, read as +inf and -inf; a pixel no footprint
    pixel neighbours stays +inf and -inf). Separable: the minimum over three rows of the minima over three
    columns (exact: a minimum does not round)."""
    _, w0, w1 = z_lo.shape
    lo = np.empty((idx.size, w0, w1))
    hi = np.empty((idx.size, w0, w1))
    row_lo = np.empty((w0, w1))
    row_hi = np.empty((w0, w1))
    for s in range(idx.size):
        f = idx[s]
        for a in range(w0):
            for b in range(w1):
                mn = np.inf
                mx = -np.inf
                for qb in range(max(0, b - 1), min(w1, b + 2)):
                    zl = z_lo[f, a, qb]
                    if zl == zl:  # not NaN: inside the footprint
                        mn = min(mn, zl)
                        mx = max(mx, z_hi[f, a, qb])
                row_lo[a, b] = mn
                row_hi[a, b] = mx
        for a in range(w0):
            for b in range(w1):
                mn = np.inf
                mx = -np.inf
                for qa in range(max(0, a - 1), min(w0, a + 2)):
                    mn = min(mn, row_lo[qa, b])
                    mx = max(mx, row_hi[qa, b])
                lo[s, a, b] = mn
                hi[s, a, b] = mx
    return lo, hi


@_jit
def _dropped(lo, hi, drop, idx, out_lo, out_hi):
    """out_lo[idx], out_hi[idx] = the grown faces moved down by their flake's ``drop`` (NaN where not finite)."""
    _, w0, w1 = lo.shape
    for s in range(idx.size):
        f = idx[s]
        for a in range(w0):
            for b in range(w1):
                x = lo[s, a, b]
                out_lo[f, a, b] = x - drop[s] if np.isfinite(x) else np.nan
                y = hi[s, a, b]
                out_hi[f, a, b] = y - drop[s] if np.isfinite(y) else np.nan


@_jit
def _stack_labels(flat, inside, n_pixels):
    """Connected components of the flakes that share a pixel (union-find over the first flake seen on each
    pixel), labelled 0, 1, ... in the order of their first flake."""
    k = flat.shape[0]
    parent = np.arange(k)
    owner = np.full(n_pixels, -1, dtype=np.int64)
    for f in range(k):
        for a in range(flat.shape[1]):
            for b in range(flat.shape[2]):
                if not inside[f, a, b]:
                    continue
                p = flat[f, a, b]
                if owner[p] < 0:
                    owner[p] = f
                    continue
                r, q = f, owner[p]
                while parent[r] != r:
                    r = parent[r]
                while parent[q] != q:
                    q = parent[q]
                if r != q:
                    parent[max(r, q)] = min(r, q)
    labels = np.empty(k, dtype=np.int64)
    count = 0
    for f in range(k):
        r = f
        while parent[r] != r:
            r = parent[r]
        if r == f:
            labels[f] = count
            count += 1
        else:
            labels[f] = labels[r]
    return labels


@_jit
def _rasterise(m, pos, dx, half, n):
    """The footprints of :func:`tribocosim.surrogate.flakes.footprints`: for each flake (matrix m = R diag(a^-2,
    a^-2, c^-2) R^T, centre pos) the window of 2 half + 1 pixels around its centre's pixel and the two roots of
    the vertical line through each pixel, z = z0 + (-qb -+ sqrt(qb^2 - 4 qa qc)) / (2 qa) (NaN where the line
    misses the flake), in the arithmetic order of the array form."""
    k = pos.shape[0]
    w = 2 * half + 1
    ix = np.empty((k, w), dtype=np.int64)
    iy = np.empty((k, w), dtype=np.int64)
    z_lo = np.empty((k, w, w))
    z_hi = np.empty((k, w, w))
    for f in range(k):
        i0 = int(np.floor(pos[f, 0] / dx))
        j0 = int(np.floor(pos[f, 1] / dx))
        qa = m[f, 2, 2]
        two_qa = 2.0 * qa
        four_qa = 4.0 * qa
        two_m01 = 2.0 * m[f, 0, 1]
        z0 = pos[f, 2]
        for a in range(w):
            ix[f, a] = (i0 + a - half) % n
            iy[f, a] = (j0 + a - half) % n
        for a in range(w):
            dX = float(i0 + a - half) * dx - pos[f, 0]
            for b in range(w):
                dY = float(j0 + b - half) * dx - pos[f, 1]
                qb = 2.0 * (m[f, 0, 2] * dX + m[f, 1, 2] * dY)
                qc = m[f, 0, 0] * (dX * dX) + two_m01 * dX * dY + m[f, 1, 1] * (dY * dY) - 1.0
                disc = qb * qb - four_qa * qc
                if disc >= 0.0:
                    root = np.sqrt(disc)
                    z_lo[f, a, b] = z0 + (-qb - root) / two_qa
                    z_hi[f, a, b] = z0 + (-qb + root) / two_qa
                else:
                    z_lo[f, a, b] = np.nan
                    z_hi[f, a, b] = np.nan
    return ix, iy, z_lo, z_hi

