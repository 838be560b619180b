"""Numba kernels of the overdamped flake solver (private; use :mod:`tribocosim.surrogate.flake_relax`).

``_relax`` moves the tool and the sheet through one pixel in ``n_sub`` substeps and, at each, brings the
flakes to force and torque balance by Levenberg-Marquardt iterations in the metric of the drag (the
equations and the tolerances are in :mod:`tribocosim.surrogate.flake_relax`). The contact law is the
inertial DEM's (:mod:`tribocosim.surrogate.dem_kernels`: the face points' overlap and force direction, the
flake-flake point geometry, the bilinear surfaces), evaluated here with its Gauss-Newton Hessian.

Incremental evaluation. A flake that does not move keeps what it had: the forces, torques, Hessian blocks,
energy and largest overlap of its faces against the surfaces (its *face part*) and of each flake pair (its
*pair part*) are kept separately and recomputed only when they can have changed: a face part when its flake
moved, or when the surfaces moved and its record cannot prove the faces still clear (the smallest gap of
each face at its last reading, less the most the surfaces can have approached since: the tool's shift times
a bound on its slope around the flake plus its vertical move; the sheet's change times the largest pixel
change of the sheet around the flake); a pair part when either flake moved. A flake's totals are its face
part plus the parts of the pairs it is in, summed in the pairs' order. A component of flakes whose data did
not change since its last solve, and whose step was then below the tolerance, is not solved again.

Components. The system couples two flakes only through a flake-flake contact; the flakes are grouped into
the connected components of the contact graph (union-find), and each component's system (6 unknowns per
flake) is solved on its own, dense (a Cholesky factorisation, :func:`_cholesky_solve`): a flake alone is a
6 x 6 system, a stack of m flakes a 6m x 6m one. Each component has its own damping and accepts or rejects its step on its
own energy, so that a flake whose linearised contacts mislead it (the bilinear surfaces are smooth only
within a pixel) does not hold back the others.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .dem_kernels import (CLEARANCE_TOL, PAIR_SKIN, REACH_PX, _add_point_force, _bilinear, _bilinear_pair,
                          _disc_point, _face_contact, _face_heights, _face_lever, _pair_candidates, _qmul, _rotmat,
                          _slope_bound)

_jit = numba.njit(cache=True)
_inline = numba.njit(cache=True, inline="always")

#: statistics the kernel accumulates in ``stats`` (see :class:`tribocosim.surrogate.flake_relax.RelaxStats`)
(_EVALS, _ITERS, _REJECTED, _LARGEST, _SOLVED, _SUBSTEPS, _FACE_READS, _PAIR_READS, _FACE_PARTIAL,
 _PAIR_SKIPS) = range(10)
N_STATS = 10


@_jit
def _drag(quat, i, t_plane, t_axial, r_diam, r_axis, out):
    """out[i] = the drag matrix of flake i in (translation, rotation) coordinates: t_plane (I - n n^T) +
    t_axial n n^T for the translation, r_diam (I - n n^T) + r_axis n n^T for the rotation, n its symmetry
    axis."""
    w, x, y, z = quat[i, 0], quat[i, 1], quat[i, 2], quat[i, 3]
    n = (2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y))
    for r in range(3):
        for s in range(3):
            nn = n[r] * n[s]
            out[i, r, s] = (t_axial - t_plane) * nn
            out[i, 3 + r, 3 + s] = (r_axis - r_diam) * nn
            out[i, r, 3 + s] = 0.0
            out[i, 3 + r, s] = 0.0
        out[i, r, r] += t_plane
        out[i, 3 + r, 3 + r] += r_diam


@_inline
def _add_outer(h, i, b, kw, a0, a1, a2, a3, a4, a5):
    """h[i, b] += kw a a^T."""
    a = (a0, a1, a2, a3, a4, a5)
    for r in range(6):
        for q in range(6):
            h[i, b, r, q] += kw * a[r] * a[q]


def new_bounds(shape) -> np.ndarray:
    """The cache of the face records' surface bounds by pixel (:func:`_read_faces`), empty (-1)."""
    return np.full((3,) + tuple(shape), -1.0)


@_jit
def _window_max(dh, ic, jc, half):
    """Largest |dh| over the pixels ic-half..ic+half, jc-half..jc+half (periodic)."""
    n0, n1 = dh.shape
    best = 0.0
    for di in range(-half, half + 1):
        i = (ic + di) % n0
        for dj in range(-half, half + 1):
            best = max(best, abs(dh[i, (jc + dj) % n1]))
    return best


#: columns of a face record (``rec[i]``): the smallest gap of each face at the last full reading, the sheet
#: weight, tool shift and tool height then, the bounds on the tool's and the sheet's slopes and on the sheet's
#: change around the flake, the flake's pose then, and whether there is a record
(_GLOW, _GTOP, _LAM, _SHIFT, _OFF, _SLOPE_TOP, _DH, _SLOPE_LOW, _POS, _QUAT, _VALID, _REC) = (
    0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 15, 16)


@_jit
def _approach(i, pos, quat, rec, lam, shift, offset, a):
    """(reach, app_low, app_top): how far flake i and the surfaces can have moved since its face record
    (dem_kernels' clearance records: a point of the flake moves by at most D = |dx_c| + 2 a |vec(q q_ref*)|,
    the surface under it by at most the slope bound times its displacement plus the tool's shift), and the
    most each face can have approached its surface [m]."""
    ex = pos[i, 0] - rec[i, _POS]
    ey = pos[i, 1] - rec[i, _POS + 1]
    ez = pos[i, 2] - rec[i, _POS + 2]
    w, x, y, z = rec[i, _QUAT], rec[i, _QUAT + 1], rec[i, _QUAT + 2], rec[i, _QUAT + 3]
    q0, q1, q2, q3 = quat[i, 0], quat[i, 1], quat[i, 2], quat[i, 3]
    vx = w * q1 - q0 * x - (q2 * z - q3 * y)
    vy = w * q2 - q0 * y - (q3 * x - q1 * z)
    vz = w * q3 - q0 * z - (q1 * y - q2 * x)
    move = math.sqrt(ex * ex + ey * ey + ez * ez) + 2.0 * a * math.sqrt(vx * vx + vy * vy + vz * vz)
    ds = abs(shift - rec[i, _SHIFT])
    low = move + rec[i, _SLOPE_LOW] * 2.0 * move + abs(lam - rec[i, _LAM]) * rec[i, _DH]
    top = move + rec[i, _SLOPE_TOP] * (2.0 * move + ds) + abs(offset - rec[i, _OFF])
    return move + ds, low, top


@_jit
def _read_faces(i, pos, quat, rot, h_low, dh_low, lam, h_top, shift, offset, dx, a, samples, zface, weights,
                k_area, half, cap, tol, face_part, face_h, rec, gaps, near, bounds):
    """Face part of flake i: forces (0:3), torques (3:6), energy (6) and largest overlap (7) in face_part[i],
    the Gauss-Newton Hessian in face_h[i, 0]. A full reading keeps the gap of every point (``gaps[i]``), the
    points within ``cap`` of contact (``near[i, face]``: their number, then their indices) and the record
    ``rec[i]``; while the flake and the surfaces have moved less than a pixel and less than ``cap`` towards
    each other since, only the near points that can be within ``tol`` of contact are read (the others have
    no overlap). ``bounds`` (3, n, n), -1 where not yet computed: the surfaces' bounds of the record by pixel (the
    sheet's slope, its largest change, the tool's slope at its pixel in the tool's frame), each computed once per
    pixel for the surfaces of one call of :func:`_relax` (:func:`new_bounds`). Returns True for a full reading."""
    inv_dx = 1.0 / dx
    reach, app_low, app_top = _approach(i, pos, quat, rec, lam, shift, offset, a)
    full = (rec[i, _VALID] == 0.0 or reach > dx or app_low + tol > cap or app_top + tol > cap)
    _rotmat(quat, i, rot)
    qx, qy = quat[i, 1], quat[i, 2]
    s_low = -1.0 if 1.0 - 2.0 * (qx * qx + qy * qy) >= 0.0 else 1.0  # as in dem_kernels._forces
    for r in range(8):
        face_part[i, r] = 0.0
    for r in range(6):
        for q in range(6):
            face_h[i, 0, r, q] = 0.0
    ns = samples.shape[0]
    for face in range(2):
        app = app_low if face == 0 else app_top
        count = ns if full else near[i, face, 0]
        gmin = np.inf
        if full:
            near[i, face, 0] = 0
        for p in range(count):
            k = p if full else near[i, face, p + 1]
            if not full and gaps[i, face, k] - app > tol:
                continue  # proven clear
            rx, ry, rz = _face_lever(rot, i, samples[k, 0], samples[k, 1], zface[k], s_low, face)
            px = pos[i, 0] + rx
            py = pos[i, 1] + ry
            pz = pos[i, 2] + rz
            if face == 0:
                if lam != 0.0:
                    hv, gx, gy, hv2, gx2, gy2 = _bilinear_pair(h_low, dh_low, px, py, inv_dx)
                    hv += lam * hv2
                    gx += lam * gx2
                    gy += lam * gy2
                else:
                    hv, gx, gy = _bilinear(h_low, px, py, inv_dx)
                d, fx, fy, fz = _face_contact(0, hv, gx, gy, pz)
            else:
                hv, gx, gy = _bilinear(h_top, px - shift, py, inv_dx)
                d, fx, fy, fz = _face_contact(1, hv + offset, gx, gy, pz)
            if full:
                gaps[i, face, k] = -d
                gmin = min(gmin, -d)
                if -d <= cap:
                    near[i, face, 0] += 1
                    near[i, face, near[i, face, 0]] = k
            if d > 0.0:
                kw = k_area * weights[k]
                _add_outer(face_h, i, 0, kw, fx, fy, fz, ry * fz - rz * fy, rz * fx - rx * fz,
                           rx * fy - ry * fx)
                _add_point_force(face_part, face_part, i, 0, 3, kw * d, fx, fy, fz, rx, ry, rz)
                face_part[i, 6] += 0.5 * kw * d * d
                face_part[i, 7] = max(face_part[i, 7], d)
        if full:
            rec[i, _GLOW + face] = gmin
    if full:
        n0, n1 = h_low.shape
        ic = int(math.floor(pos[i, 0] * inv_dx)) % n0
        jc = int(math.floor(pos[i, 1] * inv_dx)) % n1
        it = int(math.floor((pos[i, 0] - shift) * inv_dx)) % n0
        rec[i, _LAM] = lam
        rec[i, _SHIFT] = shift
        rec[i, _OFF] = offset
        if bounds[0, ic, jc] < 0.0:
            bounds[0, ic, jc] = _slope_bound(h_low, dh_low, 1.0, ic, jc, half, inv_dx)
            bounds[1, ic, jc] = _window_max(dh_low, ic, jc, half)
        if bounds[2, it, jc] < 0.0:
            bounds[2, it, jc] = _slope_bound(h_top, h_top, 0.0, it, jc, half, inv_dx)
        rec[i, _SLOPE_TOP] = bounds[2, it, jc]
        rec[i, _SLOPE_LOW] = bounds[0, ic, jc]
        rec[i, _DH] = bounds[1, ic, jc]
        for d in range(3):
            rec[i, _POS + d] = pos[i, d]
        for d in range(4):
            rec[i, _QUAT + d] = quat[i, d]
        rec[i, _VALID] = 1.0
    return full


@_jit
def _read_pair(m, pairs, pos, quat, rot, size, a, c, pair_samples, pair_weights, k_area, pair_part, pair_h,
               moved, point_gaps, point_ref, cap, tol):
    """Pair part of pair m = (i, j): forces and torques on i (0:6) and on j (6:12), energy (12) and largest
    overlap (13, 0 without contact) in pair_part[m]; the Hessian blocks (i, i), (j, j) and the coupling
    (i, j) in pair_h[m] (dem_kernels._forces' flake-flake contact: a point of P's disc against Q's,
    J_P = -(u, r x u), J_Q = (u, t x u)). Returns an upper bound on the largest overlap of a point (negative:
    a lower bound on the smallest separation).

    A full reading keeps the separation -d of every point (``point_gaps[m]``) and the distances the two flakes
    had moved then (``point_ref[m]``, of ``moved``; -1: no reading to refer to). A point's separation falls by
    at most the distance both flakes have moved since (the distance from a point to a disc changes by at most
    the point's and the disc's displacements), so while that is at most ``cap`` a reading evaluates only the
    points that can be within ``tol`` of contact: the others have no overlap and add nothing."""
    i = pairs[m, 0]
    j = pairs[m, 1]
    app = math.inf
    if point_ref[m, 0] >= 0.0:
        app = (moved[i] - point_ref[m, 0]) + (moved[j] - point_ref[m, 1])
    full = not (app <= cap)
    for r in range(14):
        pair_part[m, r] = 0.0
    for b in range(3):
        for r in range(6):
            for q in range(6):
                pair_h[m, b, r, q] = 0.0
    dxij = pos[j, 0] - pos[i, 0]
    dyij = pos[j, 1] - pos[i, 1]
    dxij -= size * math.floor(dxij / size + 0.5)
    dyij -= size * math.floor(dyij / size + 0.5)
    dzij = pos[j, 2] - pos[i, 2]
    dist = math.sqrt(dxij * dxij + dyij * dyij + dzij * dzij)
    if not (dist < 2.0 * a):
        point_ref[m, 0] = -1.0
        return 2.0 * a - dist  # the discs are at least dist - 2a apart
    _rotmat(quat, i, rot)
    _rotmat(quat, j, rot)
    ac = a - c
    scale = ac / a
    k_pair = 0.5 * k_area * scale * scale
    dmax = -np.inf
    for side in range(2):  # side 0: points of i against disc j; side 1: the reverse
        if side == 0:
            P, Q = i, j
            ox, oy, oz = dxij, dyij, dzij
            bp, bq = 0, 6
        else:
            P, Q = j, i
            ox, oy, oz = -dxij, -dyij, -dzij
            bp, bq = 6, 0
        nx, ny, nz = rot[Q, 0, 2], rot[Q, 1, 2], rot[Q, 2, 2]
        for k in range(pair_samples.shape[0]):
            if not full and point_gaps[m, side, k] - app > tol:
                dmax = max(dmax, app - point_gaps[m, side, k])  # proven clear: no overlap
                continue
            d, ux, uy, uz, rx, ry, rz, tx, ty, tz = _disc_point(
                rot, P, pair_samples[k, 0] * scale, pair_samples[k, 1] * scale, ox, oy, oz, nx, ny, nz, ac, c)
            if full:
                point_gaps[m, side, k] = -d
            dmax = max(dmax, d)
            if d <= 0.0:
                continue
            kw = k_pair * pair_weights[k]
            f = kw * d
            fx, fy, fz = f * ux, f * uy, f * uz
            pair_part[m, bp + 0] += fx
            pair_part[m, bp + 1] += fy
            pair_part[m, bp + 2] += fz
            pair_part[m, bp + 3] += ry * fz - rz * fy
            pair_part[m, bp + 4] += rz * fx - rx * fz
            pair_part[m, bp + 5] += rx * fy - ry * fx
            pair_part[m, bq + 0] -= fx
            pair_part[m, bq + 1] -= fy
            pair_part[m, bq + 2] -= fz
            pair_part[m, bq + 3] -= ty * fz - tz * fy
            pair_part[m, bq + 4] -= tz * fx - tx * fz
            pair_part[m, bq + 5] -= tx * fy - ty * fx
            pair_part[m, 12] += 0.5 * kw * d * d
            pair_part[m, 13] = max(pair_part[m, 13], d)
            # a = (u, r x u) for P, b = (u, t x u) for Q: H_PP += kw a a^T, H_QQ += kw b b^T, H_PQ -= kw a b^T
            av = (ux, uy, uz, ry * uz - rz * uy, rz * ux - rx * uz, rx * uy - ry * ux)
            bv = (ux, uy, uz, ty * uz - tz * uy, tz * ux - tx * uz, tx * uy - ty * ux)
            hp, hq = (0, 1) if side == 0 else (1, 0)
            for r in range(6):
                for q in range(6):
                    pair_h[m, hp, r, q] += kw * av[r] * av[q]
                    pair_h[m, hq, r, q] += kw * bv[r] * bv[q]
                    if side == 0:
                        pair_h[m, 2, r, q] -= kw * av[r] * bv[q]
                    else:
                        pair_h[m, 2, r, q] -= kw * bv[r] * av[q]
    if full:
        point_ref[m, 0] = moved[i]
        point_ref[m, 1] = moved[j]
    return dmax


@_jit
def _total(i, face_part, face_h, adj_start, adj, pairs, pair_part, pair_h, force, torque, hess, energy,
           overlap):
    """Totals of flake i: its face part plus the parts of the pairs it is in, in the pairs' order."""
    for r in range(3):
        force[i, r] = face_part[i, r]
        torque[i, r] = face_part[i, 3 + r]
    energy[i] = face_part[i, 6]
    overlap[i] = face_part[i, 7]
    for r in range(6):
        for q in range(6):
            hess[i, r, q] = face_h[i, 0, r, q]
    for p in range(adj_start[i], adj_start[i + 1]):
        m = adj[p]
        if pair_part[m, 13] <= 0.0:
            continue
        first = pairs[m, 0] == i
        b = 0 if first else 6
        for r in range(3):
            force[i, r] += pair_part[m, b + r]
            torque[i, r] += pair_part[m, b + 3 + r]
        energy[i] += 0.5 * pair_part[m, 12]
        overlap[i] = max(overlap[i], pair_part[m, 13])
        hb = 0 if first else 1
        for r in range(6):
            for q in range(6):
                hess[i, r, q] += pair_h[m, hb, r, q]


@_jit
def _adjacency(nf, pairs, n_pairs, adj_start, adj):
    """adj[adj_start[i]:adj_start[i + 1]]: the pairs flake i is in, in increasing order."""
    adj_start[:] = 0
    for m in range(n_pairs):
        adj_start[pairs[m, 0] + 1] += 1
        adj_start[pairs[m, 1] + 1] += 1
    for i in range(nf):
        adj_start[i + 1] += adj_start[i]
    fill = adj_start[:nf].copy()
    for m in range(n_pairs):
        for e in range(2):
            i = pairs[m, e]
            adj[fill[i]] = m
            fill[i] += 1


@_jit
def _root(parent, i):
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@_jit
def _rotate(quat, i, src, t0, t1, t2):
    """quat[i] = exp(theta) src[i], theta = (t0, t1, t2) a space-frame rotation vector."""
    th = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
    w, x, y, z = src[i, 0], src[i, 1], src[i, 2], src[i, 3]
    if th == 0.0:
        quat[i, 0], quat[i, 1], quat[i, 2], quat[i, 3] = w, x, y, z
        return
    s = math.sin(0.5 * th) / th
    q0, q1, q2, q3 = _qmul(math.cos(0.5 * th), t0 * s, t1 * s, t2 * s, w, x, y, z)
    nrm = math.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    quat[i, 0] = q0 / nrm
    quat[i, 1] = q1 / nrm
    quat[i, 2] = q2 / nrm
    quat[i, 3] = q3 / nrm


@_jit
def _components(nf, pairs, n_pairs, pair_part, active, parent, order, start):
    """Connected components of the active flakes over the pairs in contact: ``order[start[c]:start[c+1]]``
    are the members of component c in increasing index order; returns their number."""
    for i in range(nf):
        parent[i] = i
    for m in range(n_pairs):
        if pair_part[m, 13] > 0.0 and active[pairs[m, 0]] and active[pairs[m, 1]]:
            ri = _root(parent, pairs[m, 0])
            rj = _root(parent, pairs[m, 1])
            if ri != rj:
                parent[max(ri, rj)] = min(ri, rj)
    count = np.zeros(nf + 1, dtype=np.int64)
    label = np.full(nf, -1, dtype=np.int64)
    nc = 0
    for i in range(nf):  # a root is the smallest index of its component, so it comes first
        if active[i] and _root(parent, i) == i:
            label[i] = nc
            nc += 1
    for i in range(nf):
        if active[i]:
            count[label[_root(parent, i)] + 1] += 1
    for c in range(nc):
        count[c + 1] += count[c]
    start[:nc + 1] = count[:nc + 1]
    fill = count[:nc].copy()
    for i in range(nf):
        if active[i]:
            c = label[_root(parent, i)]
            order[fill[c]] = i
            fill[c] += 1
    return nc


@_jit
def _move(delta, i, a):
    """Largest displacement of a point of flake i under delta[i]: |dx_c| + a |dtheta|."""
    return (math.sqrt(delta[i, 0] ** 2 + delta[i, 1] ** 2 + delta[i, 2] ** 2)
            + a * math.sqrt(delta[i, 3] ** 2 + delta[i, 4] ** 2 + delta[i, 5] ** 2))


@_jit
def _assemble(members, hess, force, torque, adj_start, adj, pairs, pair_part, pair_h, local):
    """The Gauss-Newton Hessian H and the forces F (right-hand side) of one component."""
    k = members.shape[0]
    m6 = 6 * k
    big = np.zeros((m6, m6))
    rhs = np.empty(m6)
    for l in range(k):
        local[members[l]] = l
    for l in range(k):
        j = members[l]
        for r in range(3):
            rhs[6 * l + r] = force[j, r]
            rhs[6 * l + 3 + r] = torque[j, r]
        for r in range(6):
            for q in range(6):
                big[6 * l + r, 6 * l + q] = hess[j, r, q]
        if k == 1:
            continue
        for p in range(adj_start[j], adj_start[j + 1]):
            m = adj[p]
            if pairs[m, 0] != j or pair_part[m, 13] <= 0.0 or local[pairs[m, 1]] < 0:
                continue
            lj = local[pairs[m, 1]]
            for r in range(6):
                for q in range(6):
                    big[6 * l + r, 6 * lj + q] += pair_h[m, 2, r, q]
                    big[6 * lj + q, 6 * l + r] += pair_h[m, 2, r, q]
    for l in range(k):
        local[members[l]] = -1
    return big, rhs


@_jit
def _cholesky_solve(m, x):
    """Solve m y = x in place for a symmetric positive definite ``m`` (overwritten: its lower triangle by the
    Cholesky factor L, m = L L^T; ``x`` by y). Returns False, with ``m`` and ``x`` spoilt, when a pivot is not
    positive (``m`` not positive definite in floating point).

    H + nu D is positive definite (H a Gauss-Newton sum of k w a a^T, D the drag, nu > 0), and the factor needs no
    pivoting; it is unchanged by a diagonal scaling of the unknowns (translations and rotations), so that the
    condition that matters is the scaled matrix's (Higham, Accuracy and Stability of Numerical Algorithms, 2nd ed.,
    SIAM 2002, ch. 10). The systems are 6k x 6k for a component of k flakes (k = 1 mostly), where a library call
    costs more than the n^3/3 operations."""
    n = m.shape[0]
    for j in range(n):
        s = m[j, j]
        for q in range(j):
            s -= m[j, q] * m[j, q]
        if not s > 0.0:
            return False
        d = math.sqrt(s)
        m[j, j] = d
        for i in range(j + 1, n):
            s = m[i, j]
            for q in range(j):
                s -= m[i, q] * m[j, q]
            m[i, j] = s / d
    for i in range(n):
        s = x[i]
        for q in range(i):
            s -= m[i, q] * x[q]
        x[i] = s / m[i, i]
    for i in range(n - 1, -1, -1):
        s = x[i]
        for q in range(i + 1, n):
            s -= m[q, i] * x[q]
        x[i] = s / m[i, i]
    return True


@_jit
def _lm_step(members, big, rhs, drag, nu, a, delta):
    """delta = (H + nu D)^-1 F for the members; returns the largest move of a point (infinite when H + nu D is
    not positive definite in floating point: the caller then raises nu)."""
    k = members.shape[0]
    shifted = big.copy()
    sol = rhs.copy()
    for l in range(k):
        j = members[l]
        for r in range(6):
            for q in range(6):
                shifted[6 * l + r, 6 * l + q] += nu * drag[j, r, q]
    if not _cholesky_solve(shifted, sol):
        return math.inf
    move = 0.0
    for l in range(k):
        j = members[l]
        for r in range(6):
            delta[j, r] = sol[6 * l + r]
        move = max(move, _move(delta, j, a))
    return move


@_jit
def _predicted(members, big, rhs, delta):
    """Change of the energy the quadratic model predicts for delta: -F.delta + delta.H.delta / 2."""
    m6 = 6 * members.shape[0]
    out = 0.0
    for q in range(m6):
        dq = delta[members[q // 6], q % 6]
        hs = 0.0
        for r in range(m6):
            hs += big[q, r] * delta[members[r // 6], r % 6]
        out += -rhs[q] * dq + 0.5 * dq * hs
    return out


@_jit
def _refresh(nf, pos, quat, rot, h_low, dh_low, lam, h_top, shift, offset, dx, size, a, c, samples, zface,
             weights, k_area, half, cap, tol, pair_samples, pair_weights, pairs, n_pairs, adj_start, adj,
             face_stale, pair_stale, face_part, face_h, rec, gaps, near, pair_part, pair_h, pair_gap, pair_ref,
             point_gaps, point_ref, moved, force, torque, hess, energy, overlap, dirty, bounds, stats):
    """Recompute the stale face parts and the stale pair parts that can have changed, and the totals of every
    flake they touch (marked dirty). A pair out of contact at its last reading whose separation then exceeds
    the distance both flakes can have moved since (``moved``, each flake's accumulated |dx_c| + a |dtheta|)
    by ``tol`` is still out of contact and is not read."""
    for i in range(nf):
        if face_stale[i]:
            if _read_faces(i, pos, quat, rot, h_low, dh_low, lam, h_top, shift, offset, dx, a, samples, zface,
                           weights, k_area, half, cap, tol, face_part, face_h, rec, gaps, near, bounds):
                stats[_FACE_READS] += 1
            else:
                stats[_FACE_PARTIAL] += 1
            face_stale[i] = False
            dirty[i] = True
    for m in range(n_pairs):
        if not pair_stale[m]:
            continue
        pair_stale[m] = False
        i = pairs[m, 0]
        j = pairs[m, 1]
        if (pair_part[m, 13] <= 0.0
                and -pair_gap[m] - (moved[i] - pair_ref[m, 0]) - (moved[j] - pair_ref[m, 1]) > tol):
            stats[_PAIR_SKIPS] += 1
            continue
        pair_gap[m] = _read_pair(m, pairs, pos, quat, rot, size, a, c, pair_samples, pair_weights, k_area,
                                 pair_part, pair_h, moved, point_gaps, point_ref, cap, tol)
        pair_ref[m, 0] = moved[i]
        pair_ref[m, 1] = moved[j]
        dirty[i] = True
        dirty[j] = True
        stats[_PAIR_READS] += 1
    for i in range(nf):
        if dirty[i]:
            _total(i, face_part, face_h, adj_start, adj, pairs, pair_part, pair_h, force, torque, hess, energy,
                   overlap)
    stats[_EVALS] += 1


@_jit
def _relax(pos, quat, h_low, dh_low, ramp, h_top, shift0, dshift, top_offset, dtop, dx, size, a, c,
           samples, weights, k_area, t_plane, t_axial, r_diam, r_axis, n_sub, max_overlap, tol_move,
           nu_floor, radius, radius_max, cap, max_iter, force, torque, overlap, pair_samples, pair_weights,
           stats):
    """``n_sub`` substeps; at substep s the tool is shifted by ``shift0 + s*dshift`` and sits at
    ``top_offset + s*dtop``, and the sheet is ``h_low + ramp (s/n_sub) dh_low`` (ramp = 0 or 1). At each
    substep the flakes move from where they are to force and torque balance by Levenberg-Marquardt
    iterations per component of flakes in contact, delta = (H + nu D)^-1 F with D the drag matrix of
    :func:`_drag` (coefficients t_plane, t_axial, r_diam, r_axis [kg/s, kg m^2/s]) and nu [1/s] at least
    ``nu_floor``, adapted to the ratio of the actual to the predicted decrease of the component's energy and
    raised until the step moves no point by more than the component's radius: ``radius`` [m], doubled (up to
    ``radius_max``) after each step that it shortened, that the model predicted well and that went on in the
    direction of the one before (a straight stretch of the descent), back to ``radius`` where the path turns.
    A substep is done when the step at
    ``nu_floor`` moves no point of any flake by more than ``tol_move`` [m]. ``cap`` [m]: the points a partial
    reading of a face considers (:func:`_read_faces`).

    Returns (status, substep, flake): status 0 = fine, 1 = non-finite state, 2 = overlap above
    ``max_overlap``, 3 = no balance within ``max_iter`` iterations. ``force``/``torque``/``overlap`` hold
    those of the final configuration; ``stats`` accumulates the counts of the module's _EVALS.. columns.
    """
    nf = pos.shape[0]
    for i in range(nf):
        for d in range(3):
            if not math.isfinite(pos[i, d]):
                return 1, 0, i
    rot = np.empty((nf, 3, 3))
    zface = _face_heights(samples, a, c)
    half = int(math.ceil(a / dx)) + 2 + REACH_PX  # window of the slope bounds (pixels)
    tol_clear = CLEARANCE_TOL * c
    skin = PAIR_SKIN * a
    pairs = np.empty((max(1, nf * (nf - 1) // 2), 2), dtype=np.int64)
    n_pairs = _pair_candidates(pos, size, 2.0 * a + skin, pairs)
    cap_pairs = max(1, n_pairs)
    pair_part = np.zeros((cap_pairs, 14))
    pair_h = np.zeros((cap_pairs, 3, 6, 6))
    pair_stale = np.ones(cap_pairs, dtype=np.bool_)
    adj_start = np.zeros(nf + 1, dtype=np.int64)
    adj = np.empty(2 * cap_pairs, dtype=np.int64)
    _adjacency(nf, pairs, n_pairs, adj_start, adj)
    face_part = np.zeros((nf, 8))
    face_h = np.zeros((nf, 1, 6, 6))
    rec = np.zeros((nf, _REC))
    gaps = np.zeros((nf, 2, samples.shape[0]))
    near = np.zeros((nf, 2, samples.shape[0] + 1), dtype=np.int64)
    face_stale = np.ones(nf, dtype=np.bool_)
    old_face_part = np.zeros((nf, 8))
    old_face_h = np.zeros((nf, 1, 6, 6))
    pair_gap = np.zeros(cap_pairs)
    pair_ref = np.zeros((cap_pairs, 2))
    point_gaps = np.zeros((cap_pairs, 2, pair_samples.shape[0]))
    point_ref = np.full((cap_pairs, 2), -1.0)
    moved = np.zeros(nf)
    bounds = np.full((3, h_low.shape[0], h_low.shape[1]), -1.0)  # new_bounds
    hess = np.zeros((nf, 6, 6))
    energy = np.zeros(nf)
    dirty = np.zeros(nf, dtype=np.bool_)
    travel = np.zeros(nf)
    drag = np.zeros((nf, 6, 6))
    delta = np.zeros((nf, 6))
    parent = np.empty(nf, dtype=np.int64)
    active = np.zeros(nf, dtype=np.bool_)
    order = np.empty(nf, dtype=np.int64)
    start = np.empty(nf + 1, dtype=np.int64)
    local = np.full(nf, -1, dtype=np.int64)
    nu = np.full(nf, nu_floor)
    rad = np.full(nf, radius)
    last = np.zeros((nf, 6))
    limited = np.zeros(nf, dtype=np.bool_)
    moving = np.zeros(nf, dtype=np.bool_)
    settled = np.zeros(nf, dtype=np.bool_)
    comp_pred = np.zeros(nf)
    old_pos = pos.copy()
    old_quat = quat.copy()
    old_energy = np.zeros(nf)
    for i in range(nf):
        _drag(quat, i, t_plane, t_axial, r_diam, r_axis, drag)
    for s in range(1, n_sub + 1):
        lam = ramp * s / n_sub
        shift = shift0 + s * dshift
        offset = top_offset + s * dtop
        stats[_SUBSTEPS] += 1
        rad[:] = radius
        last[:, :] = 0.0
        # the surfaces moved: read again the faces their records cannot prove still clear
        for i in range(nf):
            if face_stale[i]:
                continue
            if rec[i, _VALID] != 0.0 and face_part[i, 7] <= 0.0:
                reach, app_low, app_top = _approach(i, pos, quat, rec, lam, shift, offset, a)
                if reach <= dx and rec[i, _GLOW] - app_low > tol_clear and rec[i, _GTOP] - app_top > tol_clear:
                    continue
            face_stale[i] = True
        done = False
        for it in range(max_iter + 1):
            far = 0.0
            for i in range(nf):
                far = max(far, travel[i])
            if 2.0 * far >= skin:  # a flake may have come within reach of one not on the list
                n_pairs = _pair_candidates(pos, size, 2.0 * a + skin, pairs)
                if n_pairs > cap_pairs:
                    cap_pairs = n_pairs
                    pair_part = np.zeros((cap_pairs, 14))
                    pair_h = np.zeros((cap_pairs, 3, 6, 6))
                    pair_stale = np.ones(cap_pairs, dtype=np.bool_)
                    pair_gap = np.zeros(cap_pairs)
                    pair_ref = np.zeros((cap_pairs, 2))
                    point_gaps = np.zeros((cap_pairs, 2, pair_samples.shape[0]))
                    point_ref = np.full((cap_pairs, 2), -1.0)
                    adj = np.empty(2 * cap_pairs, dtype=np.int64)
                point_ref[:, 0] = -1.0  # the list's indices changed: full readings
                pair_stale[:] = True
                pair_part[:n_pairs, 13] = 1.0  # read every pair of the new list
                _adjacency(nf, pairs, n_pairs, adj_start, adj)
                dirty[:] = True
                travel[:] = 0.0
            _refresh(nf, pos, quat, rot, h_low, dh_low, lam, h_top, shift, offset, dx, size, a, c, samples,
                     zface, weights, k_area, half, cap, tol_clear, pair_samples, pair_weights, pairs, n_pairs,
                     adj_start, adj, face_stale, pair_stale, face_part, face_h, rec, gaps, near, pair_part,
                     pair_h, pair_gap, pair_ref, point_gaps, point_ref, moved, force, torque, hess, energy, overlap,
                     dirty, bounds, stats)
            if it == max_iter:
                break
            stats[_ITERS] += 1
            for i in range(nf):
                active[i] = (force[i, 0] != 0.0 or force[i, 1] != 0.0 or force[i, 2] != 0.0
                             or torque[i, 0] != 0.0 or torque[i, 1] != 0.0 or torque[i, 2] != 0.0)
                moving[i] = False
            nc = _components(nf, pairs, n_pairs, pair_part, active, parent, order, start)
            worst = 0.0
            for cc in range(nc):
                members = order[start[cc]:start[cc + 1]]
                changed = False
                for j in members:
                    changed = changed or dirty[j] or not settled[j]
                if not changed:
                    continue  # balanced at its last solve, and nothing it reads has changed since
                for j in members:
                    dirty[j] = False
                big, rhs = _assemble(members, hess, force, torque, adj_start, adj, pairs, pair_part, pair_h,
                                     local)
                stats[_SOLVED] += 1
                stats[_LARGEST] = max(stats[_LARGEST], members.shape[0])
                move = _lm_step(members, big, rhs, drag, nu_floor, a, delta)
                worst = max(worst, move)
                if move <= tol_move:  # balanced: this component stays
                    for j in members:
                        settled[j] = True
                    continue
                damp = nu_floor
                reach = radius_max
                for j in members:
                    damp = max(damp, nu[j])
                    reach = min(reach, rad[j])
                short = move > reach
                if damp > nu_floor or short:
                    move = _lm_step(members, big, rhs, drag, damp, a, delta)
                    short = move > reach
                    while move > reach:
                        damp *= 4.0
                        move = _lm_step(members, big, rhs, drag, damp, a, delta)
                pred = _predicted(members, big, rhs, delta)
                for j in members:
                    limited[j] = short
                    moving[j] = True
                    settled[j] = False
                    nu[j] = damp
                    comp_pred[j] = pred
            if worst <= tol_move:
                done = True
                break
            # trial: every moving flake takes its step
            for i in range(nf):
                old_energy[i] = energy[i]
                if moving[i]:
                    old_face_part[i] = face_part[i]
                    old_face_h[i] = face_h[i]
                    moved[i] += _move(delta, i, a)
                    for d in range(3):
                        old_pos[i, d] = pos[i, d]
                        pos[i, d] += delta[i, d]
                    pos[i, 0] -= size * math.floor(pos[i, 0] / size)
                    pos[i, 1] -= size * math.floor(pos[i, 1] / size)
                    for d in range(4):
                        old_quat[i, d] = quat[i, d]
                    _rotate(quat, i, old_quat, delta[i, 3], delta[i, 4], delta[i, 5])
                    face_stale[i] = True
                    for p in range(adj_start[i], adj_start[i + 1]):
                        pair_stale[adj[p]] = True
            _refresh(nf, pos, quat, rot, h_low, dh_low, lam, h_top, shift, offset, dx, size, a, c, samples,
                     zface, weights, k_area, half, cap, tol_clear, pair_samples, pair_weights, pairs, n_pairs,
                     adj_start, adj, face_stale, pair_stale, face_part, face_h, rec, gaps, near, pair_part,
                     pair_h, pair_gap, pair_ref, point_gaps, point_ref, moved, force, torque, hess, energy, overlap,
                     dirty, bounds, stats)
            # accept or reject each component's step on its own energy (its flakes' shares)
            for cc in range(nc):
                members = order[start[cc]:start[cc + 1]]
                if not moving[members[0]]:
                    continue
                before = 0.0
                after = 0.0
                for j in members:
                    before += old_energy[j]
                    after += energy[j]
                pred = comp_pred[members[0]]
                rho = (before - after) / (-pred) if pred < 0.0 else (1.0 if after < before else 0.0)
                if rho > 1e-4:
                    dot = 0.0
                    n1 = 0.0
                    n2 = 0.0
                    for j in members:
                        for r in range(6):
                            w = 1.0 if r < 3 else a * a
                            dot += w * delta[j, r] * last[j, r]
                            n1 += w * delta[j, r] * delta[j, r]
                            n2 += w * last[j, r] * last[j, r]
                    cos = dot / math.sqrt(n1 * n2) if n1 > 0.0 and n2 > 0.0 else 0.0
                    for j in members:
                        travel[j] += _move(delta, j, a)
                        if rho > 0.75:
                            nu[j] = max(nu_floor, 0.25 * nu[j])
                        elif rho < 0.25:
                            nu[j] *= 4.0
                        if limited[j] and rho > 0.75 and cos > 0.9:
                            rad[j] = min(radius_max, 2.0 * rad[j])
                        elif rho < 0.25 or cos < 0.5:
                            rad[j] = radius
                        for r in range(6):
                            last[j, r] = delta[j, r]
                        _drag(quat, j, t_plane, t_axial, r_diam, r_axis, drag)
                else:  # back to where it was; its pairs are read again at the next refresh
                    stats[_REJECTED] += 1
                    for j in members:
                        nu[j] *= 16.0
                        rad[j] = radius
                        last[j, :] = 0.0
                        for d in range(3):
                            pos[j, d] = old_pos[j, d]
                        for d in range(4):
                            quat[j, d] = old_quat[j, d]
                        face_part[j] = old_face_part[j]
                        face_h[j] = old_face_h[j]
                        rec[j, _VALID] = 0.0  # its next reading is a full one
                        moved[j] += _move(delta, j, a)  # back: as far again
                        dirty[j] = True
                        for p in range(adj_start[j], adj_start[j + 1]):
                            pair_stale[adj[p]] = True
        if not done:
            return 3, s, -1
        for i in range(nf):
            for d in range(3):
                if not math.isfinite(pos[i, d]):
                    return 1, s, i
            if overlap[i] > max_overlap:
                return 2, s, i
    return 0, n_sub, -1
