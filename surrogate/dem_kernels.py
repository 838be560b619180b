"""Numba kernels of the flake DEM (private; use :mod:`tribocosim.surrogate.dem`).

Two kernels (and their helpers), all ``njit(cache=True)`` with float64 arrays:

- ``_forces``: surface + flake-flake penalty forces, torques, potential energy and the largest
  overlap of each flake, for one configuration (tested against a NumPy oracle);
- ``_advance``: ``n_steps`` steps of the splitting integrator described in :mod:`tribocosim.surrogate.dem`
  (tested against a NumPy oracle for one step and by conservation laws).

Helpers with their own NumPy oracles: ``_slope_bound`` (the largest pixel difference of a field around
a pixel), ``_face_modes`` (the clearance test below) and ``_pair_candidates``.

What is not computed (the results are bit for bit those of computing it: every
skipped term is provably zero and the others are summed in the same order):

- Clearance records. Reading a face at every sample point and every step would be ~95 % of a slide's DEM
  time, and most faces touch nothing. When a face is read whole, the vertical gap g_k of each of its
  points to the surface is kept (for the sheet, to the highest the sheet gets there during the call:
  its weight only grows, from ``low_w`` to ``low_end``), with the flake's pose, the tool's shift and
  height, and a bound G [m/m] on the slope of the surface's bilinear interpolant around the flake
  (the largest pixel difference / dx, ``_slope_bound``). Once the flake has moved by at most
  D = |x - x_ref| + 2 a |vec(q q_ref*)| (a point of the face moves by |dx_c| + ||R - R_ref|| |b| <= D,
  as |b| <= a and ||R - R_ref|| = 2 sin(theta/2)), and the tool has shifted by ds and moved vertically
  by dz, a point can have approached the surface by at most

      A = D (vertically) + G (2 D + ds) (the surface under it: |dx|, |dy| <= D + ds) + dz,

  so a point with g_k - A > tol has no overlap. A face whose min_k g_k - A > tol is skipped; otherwise
  only its points with g_k - A <= tol are read, for at most RENEW_STEPS steps, then the face is read
  whole again and its record renewed. A record lapses when D + ds exceeds REACH_PX pixels (the window
  of G) or the other face turns down; tol = 1e-9 c is far above the round-off of a bilinear read
  (~1e-16 of the heights).
- Pair candidates: flake pairs are tested only if their centres were closer than (2 + PAIR_SKIN) a
  when the list was made; it is made again once a flake may have travelled PAIR_SKIN a / 2 (the L1
  length of its steps).
- A flake at rest (zero velocity, angular momentum, force and torque) is not stepped: the step would
  leave it as it is.

Conventions: arrays of heights are indexed ``h[ix, iy]`` (axis 0 = x = sliding direction), the
value of pixel (ix, iy) sits at (ix*dx, iy*dx) and the field is periodic with period n*dx; a
height is read by bilinear interpolation, and its gradient is the exact gradient of that
bilinear interpolant (so the penalty force is the exact gradient of the penalty energy).
Quaternions are (w, x, y, z) and map body to space: v_space = R(q) v_body.
"""

from __future__ import annotations

import math

import numba
import numpy as np

_jit = numba.njit(cache=True)  # the one jit policy of this module
#: the same for the small helpers called per point or per flake, inlined into their callers (the
#: call would cost more than their work)
_inline = numba.njit(cache=True, inline="always")


@_inline
def _rotmat(quat, i, out):
    """out[i] = R(quat[i]). (Helpers take an array and an index, not a row view: in a loop a view
    costs two atomic reference counts, more than the work here.)"""
    w, x, y, z = quat[i, 0], quat[i, 1], quat[i, 2], quat[i, 3]
    out[i, 0, 0] = 1.0 - 2.0 * (y * y + z * z)
    out[i, 0, 1] = 2.0 * (x * y - w * z)
    out[i, 0, 2] = 2.0 * (x * z + w * y)
    out[i, 1, 0] = 2.0 * (x * y + w * z)
    out[i, 1, 1] = 1.0 - 2.0 * (x * x + z * z)
    out[i, 1, 2] = 2.0 * (y * z - w * x)
    out[i, 2, 0] = 2.0 * (x * z - w * y)
    out[i, 2, 1] = 2.0 * (y * z + w * x)
    out[i, 2, 2] = 1.0 - 2.0 * (x * x + y * y)


@_inline
def _cell(n0, n1, x, y, inv_dx):
    """The periodic grid cell (i0, j0)-(i1, j1) of (x, y) and the fractions (tx, ty) inside it."""
    u = x * inv_dx
    v = y * inv_dx
    fu = math.floor(u)
    fv = math.floor(v)
    tx = u - fu
    ty = v - fv
    i0 = int(fu)
    j0 = int(fv)
    if i0 < 0 or i0 >= n0:
        i0 -= n0 * (i0 // n0)
    if j0 < 0 or j0 >= n1:
        j0 -= n1 * (j0 // n1)
    i1 = i0 + 1 if i0 + 1 < n0 else 0
    j1 = j0 + 1 if j0 + 1 < n1 else 0
    return i0, j0, i1, j1, tx, ty


@_inline
def _bilinear(h, x, y, inv_dx):
    """Periodic bilinear value and exact gradient of the interpolant at (x, y)."""
    i0, j0, i1, j1, tx, ty = _cell(h.shape[0], h.shape[1], x, y, inv_dx)
    h00 = h[i0, j0]
    ca = h[i1, j0] - h00
    cb = h[i0, j1] - h00
    cc = h[i1, j1] - h[i1, j0] - h[i0, j1] + h00
    val = h00 + tx * ca + ty * cb + tx * ty * cc
    return val, (ca + ty * cc) * inv_dx, (cb + tx * cc) * inv_dx


@_inline
def _bilinear_pair(h, g, x, y, inv_dx):
    """:func:`_bilinear` of two fields at one point (the cell is found once)."""
    i0, j0, i1, j1, tx, ty = _cell(h.shape[0], h.shape[1], x, y, inv_dx)
    h00 = h[i0, j0]
    ca = h[i1, j0] - h00
    cb = h[i0, j1] - h00
    cc = h[i1, j1] - h[i1, j0] - h[i0, j1] + h00
    g00 = g[i0, j0]
    da = g[i1, j0] - g00
    db = g[i0, j1] - g00
    dc = g[i1, j1] - g[i1, j0] - g[i0, j1] + g00
    return (h00 + tx * ca + ty * cb + tx * ty * cc, (ca + ty * cc) * inv_dx,
            (cb + tx * cc) * inv_dx, g00 + tx * da + ty * db + tx * ty * dc,
            (da + ty * dc) * inv_dx, (db + tx * dc) * inv_dx)


#: tolerance of the clearance test, relative to the half-thickness c
CLEARANCE_TOL = 1e-9
#: displacement (pixels) of a flake plus the tool's shift that a clearance record allows
REACH_PX = 1
#: flake pairs closer than 2a + PAIR_SKIN a are tested for contact until one may have moved that far
PAIR_SKIN = 1.0
#: a face whose record cannot prove it clear reads only the points it cannot prove clear, for at most
#: this many steps before it is read whole again (and its record renewed)
RENEW_STEPS = 32
#: columns of a clearance record (``clear[i, face]``, face 0 = against the sheet, 1 = the tool); no
#: record while _SIDE is 0
_GAP, _SLOPE, _POS, _QUAT, _SHIFT, _OFFSET, _SIDE, _AGE, _CAP, _RECORD = (
    0, 1, 2, 5, 9, 10, 11, 12, 13, 14)
#: how a face is treated in one step (``mode[i, face]``)
_SKIP, _PARTIAL, _WHOLE = 0, 1, 2


@_inline
def _face_lever(rot, i, xb, yb, zb, s_low, face):
    """The face point over the body point (xb, yb) relative to the centre of flake i, space frame: on the face
    looking down (face 0, the sheet's; body height s_low zb) or up (face 1, the tool's)."""
    sz = s_low * zb if face == 0 else -s_low * zb
    rx = rot[i, 0, 0] * xb + rot[i, 0, 1] * yb + rot[i, 0, 2] * sz
    ry = rot[i, 1, 0] * xb + rot[i, 1, 1] * yb + rot[i, 1, 2] * sz
    rz = rot[i, 2, 0] * xb + rot[i, 2, 1] * yb + rot[i, 2, 2] * sz
    return rx, ry, rz


@_inline
def _face_contact(face, hv, gx, gy, pz):
    """Overlap d of a face point at height pz with the surface of height hv and slope (gx, gy) there (the sheet
    below, face 0; the tool above, face 1) and the direction of its penalty force k w d (f_x, f_y, f_z), the
    gradient of the surface's half-space (module docstring of :mod:`tribocosim.surrogate.dem`)."""
    if face == 0:
        return hv - pz, -gx, -gy, 1.0
    return pz - hv, gx, gy, -1.0


@_inline
def _add_point_force(force, torque, i, cf, ct, f, fx, fy, fz, rx, ry, rz):
    """A face point's penalty force f (fx, fy, fz) at the lever (rx, ry, rz) added to force[i, cf:cf+3] and its
    moment to torque[i, ct:ct+3] (the columns, so that one array may hold both)."""
    fx *= f
    fy *= f
    fz *= f
    force[i, cf] += fx
    force[i, cf + 1] += fy
    force[i, cf + 2] += fz
    torque[i, ct] += ry * fz - rz * fy
    torque[i, ct + 1] += rz * fx - rx * fz
    torque[i, ct + 2] += rx * fy - ry * fx


@_inline
def _disc_point(rot, P, xb, yb, ox, oy, oz, nx, ny, nz, ac, c):
    """A point of the mid-plane disc of flake P (body (xb, yb), on the core disc of radius ac) against the
    sphere-swept disc of flake Q (centre at (ox, oy, oz) from P's, axis (nx, ny, nz), core radius ac, sweep
    radius c): the overlap d = 2c - distance, the unit separation u (from Q's closest point to P's point),
    the point relative to P's centre r and Q's closest point relative to Q's centre t."""
    rx = rot[P, 0, 0] * xb + rot[P, 0, 1] * yb  # point relative to centre of P
    ry = rot[P, 1, 0] * xb + rot[P, 1, 1] * yb
    rz = rot[P, 2, 0] * xb + rot[P, 2, 1] * yb
    vx, vy, vz = rx - ox, ry - oy, rz - oz  # relative to centre of Q
    vn = vx * nx + vy * ny + vz * nz
    tx, ty, tz = vx - vn * nx, vy - vn * ny, vz - vn * nz
    tl = math.sqrt(tx * tx + ty * ty + tz * tz)
    if tl > ac:
        tx *= ac / tl
        ty *= ac / tl
        tz *= ac / tl
    ex, ey, ez = vx - tx, vy - ty, vz - tz  # closest point of Q -> point of P
    dist = math.sqrt(ex * ex + ey * ey + ez * ez)
    d = 2.0 * c - dist
    if d <= 0.0:
        return d, 0.0, 0.0, 0.0, rx, ry, rz, tx, ty, tz
    if dist > 1e-12 * c:
        ux, uy, uz = ex / dist, ey / dist, ez / dist
    else:
        sgn = 1.0 if vn >= 0.0 else -1.0
        ux, uy, uz = sgn * nx, sgn * ny, sgn * nz
    return d, ux, uy, uz, rx, ry, rz, tx, ty, tz


@_jit
def _slope_bound(h, dh, w_dh, ic, jc, half, inv_dx):
    """Largest |h[i+1, j] - h[i, j]|, |h[i, j+1] - h[i, j]| over the pixels i = ic-half..ic+half,
    j = jc-half..jc+half (periodic), of both h and h + w_dh dh (w_dh = 0: h only), times inv_dx.

    It bounds |dh/dx| and |dh/dy| of the bilinear interpolant of h + lam dh, lam in [0, w_dh], over
    the cells with a corner in the window but the last row and column.
    """
    n0, n1 = h.shape
    best = 0.0
    for di in range(-half, half + 1):
        i = (ic + di) % n0
        ip = i + 1 if i + 1 < n0 else 0
        for dj in range(-half, half + 1):
            j = (jc + dj) % n1
            jp = j + 1 if j + 1 < n1 else 0
            ex = h[ip, j] - h[i, j]
            ey = h[i, jp] - h[i, j]
            best = max(best, abs(ex), abs(ey))
            if w_dh != 0.0:
                best = max(best, abs(ex + w_dh * (dh[ip, j] - dh[i, j])),
                           abs(ey + w_dh * (dh[i, jp] - dh[i, j])))
    return best * inv_dx


@_jit
def _face_modes(clear, gaps, pos, quat, shift, offset, a, reach, tol, mode, approach, near):
    """How each face is read in this step (module docstring): ``mode[i, face]`` = _SKIP where the
    record ``clear[i, face]`` still proves the whole face out of contact; _PARTIAL where it is valid
    but cannot (then only the points whose own gap does not exceed ``approach[i, face]`` + tol are
    read), for at most RENEW_STEPS steps; _WHOLE where there is no valid record.

    ``near[i, face]`` lists, in increasing order, the points of a _PARTIAL face whose gap in
    ``gaps[i, face]`` does not exceed a cap >= approach + tol (the first entry holds their number, -1
    when there is no list; the cap is in ``clear[i, face, _CAP]``): the points that may have to be
    read. It is made at the first _PARTIAL step after a record, with room for the approach to grow
    linearly over RENEW_STEPS steps, and made again if the approach outgrows it.

    (One call for all flakes: a helper called per flake with array arguments costs two atomic
    reference counts per array and call, more than the test itself.)
    """
    for i in range(pos.shape[0]):
        qx, qy = quat[i, 1], quat[i, 2]
        side = -1.0 if 1.0 - 2.0 * (qx * qx + qy * qy) >= 0.0 else 1.0  # as in _forces
        for face in range(2):
            mode[i, face] = _WHOLE
            if clear[i, face, _SIDE] != side:  # (also when there is no record)
                continue
            ex = pos[i, 0] - clear[i, face, _POS]
            ey = pos[i, 1] - clear[i, face, _POS + 1]
            ez = pos[i, 2] - clear[i, face, _POS + 2]
            w, x, y, z = (clear[i, face, _QUAT], clear[i, face, _QUAT + 1],
                          clear[i, face, _QUAT + 2], clear[i, face, _QUAT + 3])
            q0, q1, q2, q3 = quat[i, 0], quat[i, 1], quat[i, 2], quat[i, 3]
            move = 0.0
            if ex != 0.0 or ey != 0.0 or ez != 0.0 or q0 != w or q1 != x or q2 != y or q3 != z:
                # vector part of q conj(q_ref): w_ref v - w v_ref - v x v_ref
                vx = w * q1 - q0 * x - (q2 * z - q3 * y)
                vy = w * q2 - q0 * y - (q3 * x - q1 * z)
                vz = w * q3 - q0 * z - (q1 * y - q2 * x)
                move = (math.sqrt(ex * ex + ey * ey + ez * ez)
                        + 2.0 * a * math.sqrt(vx * vx + vy * vy + vz * vz))
            ds = 0.0
            dz = 0.0
            if face == 1:  # the tool moves; the sheet's motion is in the record's gaps
                ds = abs(shift - clear[i, face, _SHIFT])
                dz = abs(offset - clear[i, face, _OFFSET])
            if not (move + ds <= reach):
                continue
            app = move + clear[i, face, _SLOPE] * (2.0 * move + ds) + dz
            if clear[i, face, _GAP] - app > tol:
                mode[i, face] = _SKIP
            elif clear[i, face, _AGE] < RENEW_STEPS:
                mode[i, face] = _PARTIAL
                approach[i, face] = app
                clear[i, face, _AGE] += 1.0
                if near[i, face, 0] < 0 or app + tol > clear[i, face, _CAP]:
                    cap = (RENEW_STEPS + 1.0) * (app + tol)
                    m = 0
                    for k in range(gaps.shape[2]):
                        if gaps[i, face, k] <= cap:
                            m += 1
                            near[i, face, m] = k
                    near[i, face, 0] = m
                    clear[i, face, _CAP] = cap


@_inline
def _keep_record(clear, near, i, face, gap, slope, pos, quat, side, shift, offset):
    near[i, face, 0] = -1
    clear[i, face, _AGE] = 0.0
    clear[i, face, _GAP] = gap
    clear[i, face, _SLOPE] = slope
    for d in range(3):
        clear[i, face, _POS + d] = pos[i, d]
    for d in range(4):
        clear[i, face, _QUAT + d] = quat[i, d]
    clear[i, face, _SHIFT] = shift
    clear[i, face, _OFFSET] = offset
    clear[i, face, _SIDE] = side


@_jit
def _pair_candidates(pos, size, cutoff, pairs):
    """The pairs i < j (in the order of i then j) whose centres are closer than ``cutoff``
    (periodic in x and y), written to ``pairs``; returns their number."""
    nf = pos.shape[0]
    m = 0
    for i in range(nf):
        for j in range(i + 1, nf):
            dxij = pos[j, 0] - pos[i, 0]
            dyij = pos[j, 1] - pos[i, 1]
            dxij -= size * math.floor(dxij / size + 0.5)
            dyij -= size * math.floor(dyij / size + 0.5)
            dzij = pos[j, 2] - pos[i, 2]
            if dxij * dxij + dyij * dyij + dzij * dzij < cutoff * cutoff:
                pairs[m, 0] = i
                pairs[m, 1] = j
                m += 1
    return m


@_jit
def _face_heights(samples, a, c):
    """Height c sqrt(1 - r^2/a^2) of the upper face over each sample point."""
    ns = samples.shape[0]
    out = np.empty(ns)
    for k in range(ns):
        xb = samples[k, 0]
        yb = samples[k, 1]
        out[k] = c * math.sqrt(max(0.0, 1.0 - (xb * xb + yb * yb) / (a * a)))
    return out


@_jit
def _forces(pos, quat, h_low, dh_low, low_w, low_end, h_top, top_shift, top_offset, dx, size, a, c,
            samples, zface, weights, k_area, force, torque, overlap, rot, clear, gaps, slopes, near,
            mode, approach, reach_px, pairs, n_pairs, pair_samples, pair_weights):
    """Penalty forces/torques (space frame) on every flake; returns the penalty energy.

    ``samples`` (ns, 2) are body-frame in-plane points of the face, ``weights`` (ns,) their
    areas (summing to pi a^2); face heights are +/- ``zface`` = c sqrt(1 - r^2/a^2). A face point has
    the stiffness k_A w, a flake-flake point k_A w ((a-c)/a)^2 / 2 (half: both flakes of a pair are
    sampled). ``overlap`` receives the largest overlap of each flake (vertical for surfaces,
    normal for flake-flake). ``rot`` (nf, 3, 3) is a work array.

    The lower surface is ``h_low + low_w * dh_low`` (the second read is skipped when low_w = 0);
    within one call of ``_advance`` its weight grows up to ``low_end``.

    ``clear`` (nf, 2, _RECORD) and ``gaps`` (nf, 2, ns): the clearance records of the module
    docstring and the gap of every point when they were made, used and renewed (what they prove clear
    is not read); with zero rows every face is read and nothing is kept. ``slopes`` (nf, 2, 3): the
    last slope bound of each face and the pixel it was taken around ([ic, jc, G], ic = -1: none).
    ``near`` (nf, 2, ns + 1), ``mode`` (nf, 2) and ``approach`` (nf, 2) are work arrays
    (:func:`_face_modes`). The points are visited in the order k = 0..ns-1, the sheet's face before
    the tool's, whichever are skipped, so that the sums are those of reading every point.
    ``reach_px``: the displacement (in pixels) a record allows.

    ``pairs[:n_pairs]`` (i < j, in the order of i then j): the flake pairs tested for contact; every
    pair closer than 2a must be among them (:func:`_pair_candidates`). ``pair_samples`` (np, 2) and
    ``pair_weights`` (np,) are the points and areas of a flake's mid-plane disc in flake-flake contact
    (the face's own, or a coarser set: flakes pressed on one another are in contact over most of their
    area at every step, and their points dominate the cost of a dense deposit).
    """
    nf = pos.shape[0]
    ns = samples.shape[0]
    for i in range(nf):
        for d in range(3):
            force[i, d] = 0.0
            torque[i, d] = 0.0
        overlap[i] = 0.0
    energy = 0.0
    n0, n1 = h_low.shape
    inv_dx = 1.0 / dx
    track = clear.shape[0] == nf and nf > 0
    tol = CLEARANCE_TOL * c
    allowed = reach_px * dx
    half = int(math.ceil(a * inv_dx)) + 2 + reach_px  # window of the slope bound (pixels)
    if track:
        _face_modes(clear, gaps, pos, quat, top_shift, top_offset, a, allowed, tol, mode, approach,
                    near)
    else:
        mode[:, :] = _WHOLE
    for i in range(nf):
        mode_low = mode[i, 0]
        mode_top = mode[i, 1]
        if mode_low == _SKIP and mode_top == _SKIP:
            continue
        app_low = approach[i, 0] + tol
        app_top = approach[i, 1] + tol
        qx, qy = quat[i, 1], quat[i, 2]
        r22 = 1.0 - 2.0 * (qx * qx + qy * qy)  # rot[i, 2, 2], as _rotmat computes it
        s_low = -1.0 if r22 >= 0.0 else 1.0  # sign of the body face that looks down
        _rotmat(quat, i, rot)
        gap_low = np.inf
        gap_top = np.inf
        # the points to visit: all (_WHOLE), the near list (_PARTIAL) or none (_SKIP), merged in
        # the order (k, face)
        n_low = ns if mode_low == _WHOLE else (near[i, 0, 0] if mode_low == _PARTIAL else 0)
        n_top = ns if mode_top == _WHOLE else (near[i, 1, 0] if mode_top == _PARTIAL else 0)
        p_low = 0
        p_top = 0
        while p_low < n_low or p_top < n_top:
            k_low = ns
            if p_low < n_low:
                k_low = p_low if mode_low == _WHOLE else near[i, 0, p_low + 1]
            k_top = ns
            if p_top < n_top:
                k_top = p_top if mode_top == _WHOLE else near[i, 1, p_top + 1]
            if k_low <= k_top:
                face = 0
                k = k_low
                p_low += 1
                m = mode_low
                if m == _PARTIAL and gaps[i, 0, k] > app_low:
                    continue  # proven clear
            else:
                face = 1
                k = k_top
                p_top += 1
                m = mode_top
                if m == _PARTIAL and gaps[i, 1, k] > app_top:
                    continue  # proven clear
            rx, ry, rz = _face_lever(rot, i, samples[k, 0], samples[k, 1], zface[k], s_low, face)
            px = pos[i, 0] + rx
            py = pos[i, 1] + ry
            pz = pos[i, 2] + rz
            if face == 0:
                hv2 = 0.0
                if low_w != 0.0 or (track and low_end != 0.0):
                    hv, gx, gy, hv2, gx2, gy2 = _bilinear_pair(h_low, dh_low, px, py, inv_dx)
                    if low_w != 0.0:
                        hv += low_w * hv2
                        gx += low_w * gx2
                        gy += low_w * gy2
                else:
                    hv, gx, gy = _bilinear(h_low, px, py, inv_dx)
                if track and m == _WHOLE:  # the highest the sheet gets here in the call
                    rise = (low_end - low_w) * hv2
                    g = pz - (hv + max(rise, 0.0))
                    gaps[i, 0, k] = g
                    gap_low = min(gap_low, g)
                d, fx, fy, fz = _face_contact(0, hv, gx, gy, pz)
            else:
                hv, gx, gy = _bilinear(h_top, px - top_shift, py, inv_dx)
                if track and m == _WHOLE:
                    g = hv + top_offset - pz
                    gaps[i, 1, k] = g
                    gap_top = min(gap_top, g)
                d, fx, fy, fz = _face_contact(1, hv + top_offset, gx, gy, pz)
            if d > 0.0:
                kw = k_area * weights[k]
                _add_point_force(force, torque, i, 0, 0, kw * d, fx, fy, fz, rx, ry, rz)
                energy += 0.5 * kw * d * d
                if d > overlap[i]:
                    overlap[i] = d
        if track:
            jc = int(math.floor(pos[i, 1] * inv_dx)) % n1
            for face in range(2):
                if (mode_low if face == 0 else mode_top) != _WHOLE:
                    continue
                if face == 0:
                    ic = int(math.floor(pos[i, 0] * inv_dx)) % n0
                else:
                    ic = int(math.floor((pos[i, 0] - top_shift) * inv_dx)) % n0
                if slopes[i, face, 0] != ic or slopes[i, face, 1] != jc:  # a new window
                    slopes[i, face, 0] = ic
                    slopes[i, face, 1] = jc
                    if face == 0:
                        slopes[i, face, 2] = _slope_bound(h_low, dh_low, low_end, ic, jc, half,
                                                          inv_dx)
                    else:
                        slopes[i, face, 2] = _slope_bound(h_top, h_top, 0.0, ic, jc, half, inv_dx)
                if face == 0:
                    _keep_record(clear, near, i, 0, gap_low, slopes[i, 0, 2], pos, quat, s_low, 0.0, 0.0)
                else:
                    _keep_record(clear, near, i, 1, gap_top, slopes[i, 1, 2], pos, quat, s_low,
                                 top_shift, top_offset)
    # flake-flake: sphere-swept mid-plane discs (core radius a - c, sweep radius c)
    ac = a - c
    scale = ac / a
    k_pair = 0.5 * k_area * scale * scale
    reach = 2.0 * a
    nps = pair_samples.shape[0]
    for m in range(n_pairs):
        i = pairs[m, 0]
        j = pairs[m, 1]
        dxij = pos[j, 0] - pos[i, 0]
        dyij = pos[j, 1] - pos[i, 1]
        dxij -= size * math.floor(dxij / size + 0.5)
        dyij -= size * math.floor(dyij / size + 0.5)
        dzij = pos[j, 2] - pos[i, 2]
        if not (dxij * dxij + dyij * dyij + dzij * dzij < reach * reach):
            continue  # (also skips a pair with a non-finite position)
        _rotmat(quat, i, rot)
        _rotmat(quat, j, rot)
        for side in range(2):  # side 0: points of i against disc j; side 1: the reverse
            if side == 0:
                P, Q = i, j
                ox, oy, oz = dxij, dyij, dzij  # centre of Q relative to centre of P
            else:
                P, Q = j, i
                ox, oy, oz = -dxij, -dyij, -dzij
            nx, ny, nz = rot[Q, 0, 2], rot[Q, 1, 2], rot[Q, 2, 2]
            for k in range(nps):
                d, ux, uy, uz, rx, ry, rz, tx, ty, tz = _disc_point(
                    rot, P, pair_samples[k, 0] * scale, pair_samples[k, 1] * scale, ox, oy, oz, nx, ny,
                    nz, ac, c)
                if d <= 0.0:
                    continue
                kw = k_pair * pair_weights[k]
                f = kw * d
                fx, fy, fz = f * ux, f * uy, f * uz
                force[P, 0] += fx
                force[P, 1] += fy
                force[P, 2] += fz
                torque[P, 0] += ry * fz - rz * fy
                torque[P, 1] += rz * fx - rx * fz
                torque[P, 2] += rx * fy - ry * fx
                force[Q, 0] -= fx
                force[Q, 1] -= fy
                force[Q, 2] -= fz
                torque[Q, 0] -= ty * fz - tz * fy
                torque[Q, 1] -= tz * fx - tx * fz
                torque[Q, 2] -= tx * fy - ty * fx
                energy += 0.5 * kw * d * d
                if d > overlap[P]:
                    overlap[P] = d
                if d > overlap[Q]:
                    overlap[Q] = d
    return energy


@_inline
def _qmul(p0, p1, p2, p3, q0, q1, q2, q3):
    """Quaternion product p q."""
    return (p0 * q0 - p1 * q1 - p2 * q2 - p3 * q3,
            p0 * q1 + p1 * q0 + p2 * q3 - p3 * q2,
            p0 * q2 - p1 * q3 + p2 * q0 + p3 * q1,
            p0 * q3 + p1 * q2 - p2 * q1 + p3 * q0)


@_inline
def _free_rotation(quat, angmom, i, i1, i3, dt):
    """Exact torque-free rotation of an axisymmetric body over dt (in place on quat[i])."""
    l0, l1, l2 = angmom[i, 0], angmom[i, 1], angmom[i, 2]
    lmag = math.sqrt(l0 * l0 + l1 * l1 + l2 * l2)
    if lmag == 0.0:
        return
    w, x, y, z = quat[i, 0], quat[i, 1], quat[i, 2], quat[i, 3]
    # the symmetry axis n = R(q) e_z, as _rotmat computes it
    l3 = (l0 * (2.0 * (x * z + w * y)) + l1 * (2.0 * (y * z - w * x))
          + l2 * (1.0 - 2.0 * (x * x + y * y)))
    half = 0.5 * lmag * dt / i1  # rotation about the space-fixed L
    s = math.sin(half) / lmag
    b0, b1, b2, b3 = _qmul(math.cos(half), l0 * s, l1 * s, l2 * s, w, x, y, z)
    half3 = 0.5 * l3 * (1.0 / i3 - 1.0 / i1) * dt  # rotation about the body symmetry axis
    q0, q1, q2, q3 = _qmul(b0, b1, b2, b3, math.cos(half3), 0.0, 0.0, math.sin(half3))
    nrm = math.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    quat[i, 0] = q0 / nrm
    quat[i, 1] = q1 / nrm
    quat[i, 2] = q2 / nrm
    quat[i, 3] = q3 / nrm


@_inline
def _damp_axes(quat, vel, angmom, i, dec_vp, dec_va, dec_lp, dec_la):
    """Damping half-flow in the principal axes of flake i (in place on vel[i] and angmom[i]).

    The components along the symmetry axis n = R(q) e_z are multiplied by ``dec_va`` / ``dec_la``,
    the rest by ``dec_vp`` / ``dec_lp`` (exact: the orientation does not change in this sub-flow).
    """
    w, x, y, z = quat[i, 0], quat[i, 1], quat[i, 2], quat[i, 3]
    nx = 2.0 * (x * z + w * y)
    ny = 2.0 * (y * z - w * x)
    nz = 1.0 - 2.0 * (x * x + y * y)
    vn = (dec_va - dec_vp) * (vel[i, 0] * nx + vel[i, 1] * ny + vel[i, 2] * nz)
    ln = (dec_la - dec_lp) * (angmom[i, 0] * nx + angmom[i, 1] * ny + angmom[i, 2] * nz)
    for d, n_d in ((0, nx), (1, ny), (2, nz)):
        vel[i, d] = dec_vp * vel[i, d] + vn * n_d
        angmom[i, d] = dec_lp * angmom[i, d] + ln * n_d


@_jit
def _advance(pos, quat, vel, angmom, h_low, dh_low, ramp, h_top, shift0, dshift,
             top_offset, dtop, dx, size, a, c,
             samples, weights, k_area, mass, i1, i3, gamma_vp, gamma_va, gamma_lp, gamma_la, dt,
             n_steps, max_overlap, force, torque, overlap, use_clearance, pair_samples, pair_weights):
    """``n_steps`` integrator steps; at step s the tool is shifted by ``shift0 + s*dshift`` and
    sits at the height ``top_offset + s*dtop``, and the lower surface is
    ``h_low + ramp (s/n_steps) dh_low`` (ramp = 0 or 1).

    Damping rates [1/s] in the flake's principal axes: ``gamma_vp`` / ``gamma_va`` for the velocity
    in the flake's plane / along its axis, ``gamma_lp`` / ``gamma_la`` for the angular momentum
    about a diameter / about the axis. When all four are equal the half-flow is the scalar decay
    v, L *= exp(-gamma dt/2) (bit for bit the one-rate integrator).

    Returns (status, step, flake): status 0 = fine, 1 = non-finite state, 2 = overlap above
    ``max_overlap``; ``step`` is the 1-based step within this call (0 = initial state).
    On return ``force``/``torque`` hold the forces of the final configuration.

    ``use_clearance``: skip the faces a clearance record proves out of contact (module docstring;
    the same numbers, bit for bit); False reads every face at every step.
    """
    nf = pos.shape[0]
    rot = np.empty((nf, 3, 3))
    zface = _face_heights(samples, a, c)
    nt = nf if use_clearance else 0
    clear = np.zeros((nt, 2, _RECORD))  # _SIDE = 0: no record yet
    gaps = np.empty((nt, 2, samples.shape[0]))
    slopes = np.full((nt, 2, 3), -1.0)
    near = np.full((nt, 2, samples.shape[0] + 1), -1, dtype=np.int64)
    mode = np.empty((nf, 2), dtype=np.int64)
    approach = np.zeros((nf, 2))
    # flake pairs within 2a + skin; rebuilt once a flake may have travelled skin/2 (L1 path length)
    skin = PAIR_SKIN * a
    pairs = np.empty((nf * (nf - 1) // 2, 2), dtype=np.int64)
    n_pairs = _pair_candidates(pos, size, 2.0 * a + skin, pairs)
    travel = np.zeros(nf)
    far_travel = 0.0
    uniform = gamma_vp == gamma_va and gamma_vp == gamma_lp and gamma_vp == gamma_la
    decay = math.exp(-0.5 * gamma_vp * dt)
    dec_va = math.exp(-0.5 * gamma_va * dt)
    dec_lp = math.exp(-0.5 * gamma_lp * dt)
    dec_la = math.exp(-0.5 * gamma_la * dt)
    decay_d = decay if uniform else 1.0  # 1: the damping is left to _damp_axes
    for i in range(nf):
        for d in range(3):
            if not (math.isfinite(pos[i, d]) and math.isfinite(vel[i, d])
                    and math.isfinite(angmom[i, d])):
                return 1, 0, i
    _forces(pos, quat, h_low, dh_low, 0.0, ramp, h_top, shift0, top_offset, dx, size, a, c,
            samples, zface, weights, k_area, force, torque, overlap, rot, clear, gaps, slopes, near,
            mode, approach, REACH_PX, pairs, n_pairs, pair_samples, pair_weights)
    for i in range(nf):
        if overlap[i] > max_overlap:
            return 2, 0, i
    rest = np.zeros(nf, dtype=np.bool_)
    for s in range(1, n_steps + 1):
        for i in range(nf):
            # at rest with no force and inside the domain: the step leaves the flake as it is
            rest[i] = (vel[i, 0] == 0.0 and vel[i, 1] == 0.0 and vel[i, 2] == 0.0
                       and angmom[i, 0] == 0.0 and angmom[i, 1] == 0.0 and angmom[i, 2] == 0.0
                       and force[i, 0] == 0.0 and force[i, 1] == 0.0 and force[i, 2] == 0.0
                       and torque[i, 0] == 0.0 and torque[i, 1] == 0.0 and torque[i, 2] == 0.0
                       and math.floor(pos[i, 0] / size) == 0.0
                       and math.floor(pos[i, 1] / size) == 0.0)
            if rest[i]:
                continue
            if not uniform:
                _damp_axes(quat, vel, angmom, i, decay, dec_va, dec_lp, dec_la)
            for d in range(3):
                vel[i, d] = vel[i, d] * decay_d + 0.5 * dt * force[i, d] / mass
                angmom[i, d] = angmom[i, d] * decay_d + 0.5 * dt * torque[i, d]
                pos[i, d] += dt * vel[i, d]
            pos[i, 0] -= size * math.floor(pos[i, 0] / size)
            pos[i, 1] -= size * math.floor(pos[i, 1] / size)
            _free_rotation(quat, angmom, i, i1, i3, dt)
            travel[i] += dt * (abs(vel[i, 0]) + abs(vel[i, 1]) + abs(vel[i, 2]))
            far_travel = max(far_travel, travel[i])
        if 2.0 * far_travel >= skin:
            n_pairs = _pair_candidates(pos, size, 2.0 * a + skin, pairs)
            travel[:] = 0.0
            far_travel = 0.0
        _forces(pos, quat, h_low, dh_low, ramp * s / n_steps, ramp, h_top, shift0 + s * dshift,
                top_offset + s * dtop, dx, size, a, c, samples, zface, weights, k_area, force,
                torque, overlap, rot, clear, gaps, slopes, near, mode, approach, REACH_PX,
                pairs, n_pairs, pair_samples, pair_weights)
        for i in range(nf):
            if rest[i] and (force[i, 0] == 0.0 and force[i, 1] == 0.0 and force[i, 2] == 0.0
                            and torque[i, 0] == 0.0 and torque[i, 1] == 0.0
                            and torque[i, 2] == 0.0):
                continue
            for d in range(3):
                vel[i, d] = (vel[i, d] + 0.5 * dt * force[i, d] / mass) * decay_d
                angmom[i, d] = (angmom[i, d] + 0.5 * dt * torque[i, d]) * decay_d
            if not uniform:
                _damp_axes(quat, vel, angmom, i, decay, dec_va, dec_lp, dec_la)
        for i in range(nf):
            ok = True
            for d in range(3):
                if not (math.isfinite(pos[i, d]) and math.isfinite(vel[i, d])
                        and math.isfinite(angmom[i, d])):
                    ok = False
            if not ok:
                return 1, s, i
            if overlap[i] > max_overlap:
                return 2, s, i
    return 0, n_steps, -1
