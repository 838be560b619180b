"""Numba kernels of the flake DEM (private; use :mod:`tribocosim.surrogate.dem`).

Two kernels (and their helpers), all ``njit(cache=True)`` with float64 arrays:

- ``_forces``: surface + flake-flake penalty forces, torques, potential energy and the largest
  overlap of each flake, for one configuration (tested against a NumPy oracle);
- ``_advance``: ``n_steps`` steps of the splitting integrator described in :mod:`tribocosim.surrogate.dem`
  (tested against a NumPy oracle for one step and by conservation laws).

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


@_jit
def _rotmat(q, out):
    w, x, y, z = q[0], q[1], q[2], q[3]
    out[0, 0] = 1.0 - 2.0 * (y * y + z * z)
    out[0, 1] = 2.0 * (x * y - w * z)
    out[0, 2] = 2.0 * (x * z + w * y)
    out[1, 0] = 2.0 * (x * y + w * z)
    out[1, 1] = 1.0 - 2.0 * (x * x + z * z)
    out[1, 2] = 2.0 * (y * z - w * x)
    out[2, 0] = 2.0 * (x * z - w * y)
    out[2, 1] = 2.0 * (y * z + w * x)
    out[2, 2] = 1.0 - 2.0 * (x * x + y * y)


@_jit
def _bilinear(h, x, y, inv_dx):
    """Periodic bilinear value and exact gradient of the interpolant at (x, y)."""
    n0, n1 = h.shape
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
    h00 = h[i0, j0]
    ca = h[i1, j0] - h00
    cb = h[i0, j1] - h00
    cc = h[i1, j1] - h[i1, j0] - h[i0, j1] + h00
    val = h00 + tx * ca + ty * cb + tx * ty * cc
    return val, (ca + ty * cc) * inv_dx, (cb + tx * cc) * inv_dx


@_jit
def _forces(pos, quat, h_low, dh_low, low_w, h_top, hmax_low, hmin_top, top_shift, top_offset,
            dx, size, a, c, samples, weights, k_area, force, torque, overlap):
    """Penalty forces/torques (space frame) on every flake; returns the penalty energy.

    ``samples`` (ns, 2) are body-frame in-plane points of the face, ``weights`` (ns,) their
    areas (summing to pi a^2); face heights are +/- c sqrt(1 - r^2/a^2). A face point has the
    stiffness k_A w, a flake-flake point k_A w ((a-c)/a)^2 / 2 (half: both flakes of a pair are
    sampled). ``overlap`` receives the largest overlap of each flake (vertical for surfaces,
    normal for flake-flake).

    The lower surface is ``h_low + low_w * dh_low`` (the second read is skipped when low_w = 0).

    Broad phase: ``hmax_low`` / ``hmin_top`` are the max / min of ``h_low`` / ``h_top`` over the
    (2 r + 1)^2 pixels around each pixel, r = ceil(a/dx) + 1 (every pixel a bilinear read of
    the flake can touch); a face is skipped when the flake's vertical extent
    z +/- sqrt(a^2 (1 - n_z^2) + c^2 n_z^2) clears that bound (its forces would be zero).
    """
    nf = pos.shape[0]
    ns = samples.shape[0]
    rot = np.empty((nf, 3, 3))
    for i in range(nf):
        _rotmat(quat[i], rot[i])
        for d in range(3):
            force[i, d] = 0.0
            torque[i, d] = 0.0
        overlap[i] = 0.0
    energy = 0.0
    n0, n1 = h_low.shape
    inv_dx = 1.0 / dx
    for i in range(nf):
        R = rot[i]
        s_low = -1.0 if R[2, 2] >= 0.0 else 1.0  # sign of the body face that looks down
        nz2 = R[2, 2] * R[2, 2]
        half_z = math.sqrt(a * a * max(0.0, 1.0 - nz2) + c * c * nz2)
        ix = int(math.floor(pos[i, 0] / dx)) % n0
        iy = int(math.floor(pos[i, 1] / dx)) % n1
        it = int(math.floor((pos[i, 0] - top_shift) / dx)) % n0
        test_low = pos[i, 2] - half_z <= hmax_low[ix, iy]
        test_top = pos[i, 2] + half_z >= hmin_top[it, iy] + top_offset
        if not (test_low or test_top):
            continue
        for k in range(ns):
            xb = samples[k, 0]
            yb = samples[k, 1]
            zb = c * math.sqrt(max(0.0, 1.0 - (xb * xb + yb * yb) / (a * a)))
            for face in range(2):
                if (face == 0 and not test_low) or (face == 1 and not test_top):
                    continue
                sz = s_low * zb if face == 0 else -s_low * zb
                rx = R[0, 0] * xb + R[0, 1] * yb + R[0, 2] * sz
                ry = R[1, 0] * xb + R[1, 1] * yb + R[1, 2] * sz
                rz = R[2, 0] * xb + R[2, 1] * yb + R[2, 2] * sz
                px = pos[i, 0] + rx
                py = pos[i, 1] + ry
                pz = pos[i, 2] + rz
                if face == 0:
                    hv, gx, gy = _bilinear(h_low, px, py, inv_dx)
                    if low_w != 0.0:
                        hv2, gx2, gy2 = _bilinear(dh_low, px, py, inv_dx)
                        hv += low_w * hv2
                        gx += low_w * gx2
                        gy += low_w * gy2
                    d = hv - pz
                    fx, fy, fz = -gx, -gy, 1.0
                else:
                    hv, gx, gy = _bilinear(h_top, px - top_shift, py, inv_dx)
                    d = pz - (hv + top_offset)
                    fx, fy, fz = gx, gy, -1.0
                if d > 0.0:
                    kw = k_area * weights[k]
                    f = kw * d
                    fx *= f
                    fy *= f
                    fz *= f
                    force[i, 0] += fx
                    force[i, 1] += fy
                    force[i, 2] += fz
                    torque[i, 0] += ry * fz - rz * fy
                    torque[i, 1] += rz * fx - rx * fz
                    torque[i, 2] += rx * fy - ry * fx
                    energy += 0.5 * kw * d * d
                    if d > overlap[i]:
                        overlap[i] = d
    # flake-flake: sphere-swept mid-plane discs (core radius a - c, sweep radius c)
    ac = a - c
    scale = ac / a
    k_pair = 0.5 * k_area * scale * scale
    reach = 2.0 * a
    for i in range(nf):
        for j in range(i + 1, nf):
            dxij = pos[j, 0] - pos[i, 0]
            dyij = pos[j, 1] - pos[i, 1]
            dxij -= size * math.floor(dxij / size + 0.5)
            dyij -= size * math.floor(dyij / size + 0.5)
            dzij = pos[j, 2] - pos[i, 2]
            if not (dxij * dxij + dyij * dyij + dzij * dzij < reach * reach):
                continue  # (also skips a pair with a non-finite position)
            for side in range(2):  # side 0: points of i against disc j; side 1: the reverse
                if side == 0:
                    P, Q = i, j
                    ox, oy, oz = dxij, dyij, dzij  # centre of Q relative to centre of P
                else:
                    P, Q = j, i
                    ox, oy, oz = -dxij, -dyij, -dzij
                RP = rot[P]
                RQ = rot[Q]
                nx, ny, nz = RQ[0, 2], RQ[1, 2], RQ[2, 2]
                for k in range(ns):
                    xb = samples[k, 0] * scale
                    yb = samples[k, 1] * scale
                    rx = RP[0, 0] * xb + RP[0, 1] * yb  # point relative to centre of P
                    ry = RP[1, 0] * xb + RP[1, 1] * yb
                    rz = RP[2, 0] * xb + RP[2, 1] * yb
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
                        continue
                    if dist > 1e-12 * c:
                        ux, uy, uz = ex / dist, ey / dist, ez / dist
                    else:
                        sgn = 1.0 if vn >= 0.0 else -1.0
                        ux, uy, uz = sgn * nx, sgn * ny, sgn * nz
                    kw = k_pair * weights[k]
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


@_jit
def _qmul(p, q, out):
    out[0] = p[0] * q[0] - p[1] * q[1] - p[2] * q[2] - p[3] * q[3]
    out[1] = p[0] * q[1] + p[1] * q[0] + p[2] * q[3] - p[3] * q[2]
    out[2] = p[0] * q[2] - p[1] * q[3] + p[2] * q[0] + p[3] * q[1]
    out[3] = p[0] * q[3] + p[1] * q[2] - p[2] * q[1] + p[3] * q[0]


@_jit
def _free_rotation(q, L, i1, i3, dt, tmp_r, tmp_a, tmp_b):
    """Exact torque-free rotation of an axisymmetric body over dt (in place on q)."""
    _rotmat(q, tmp_r)
    lmag = math.sqrt(L[0] * L[0] + L[1] * L[1] + L[2] * L[2])
    if lmag == 0.0:
        return
    l3 = L[0] * tmp_r[0, 2] + L[1] * tmp_r[1, 2] + L[2] * tmp_r[2, 2]
    half = 0.5 * lmag * dt / i1  # rotation about the space-fixed L
    s = math.sin(half) / lmag
    tmp_a[0] = math.cos(half)
    tmp_a[1] = L[0] * s
    tmp_a[2] = L[1] * s
    tmp_a[3] = L[2] * s
    _qmul(tmp_a, q, tmp_b)
    half3 = 0.5 * l3 * (1.0 / i3 - 1.0 / i1) * dt  # rotation about the body symmetry axis
    tmp_a[0] = math.cos(half3)
    tmp_a[1] = 0.0
    tmp_a[2] = 0.0
    tmp_a[3] = math.sin(half3)
    _qmul(tmp_b, tmp_a, q)
    nrm = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    for d in range(4):
        q[d] /= nrm


@_jit
def _damp_axes(q, v, L, dec_vp, dec_va, dec_lp, dec_la):
    """Damping half-flow in the principal axes of a flake (in place on v and L).

    The components along the symmetry axis n = R(q) e_z are multiplied by ``dec_va`` / ``dec_la``,
    the rest by ``dec_vp`` / ``dec_lp`` (exact: the orientation does not change in this sub-flow).
    """
    w, x, y, z = q[0], q[1], q[2], q[3]
    nx = 2.0 * (x * z + w * y)
    ny = 2.0 * (y * z - w * x)
    nz = 1.0 - 2.0 * (x * x + y * y)
    vn = (dec_va - dec_vp) * (v[0] * nx + v[1] * ny + v[2] * nz)
    ln = (dec_la - dec_lp) * (L[0] * nx + L[1] * ny + L[2] * nz)
    v[0] = dec_vp * v[0] + vn * nx
    v[1] = dec_vp * v[1] + vn * ny
    v[2] = dec_vp * v[2] + vn * nz
    L[0] = dec_lp * L[0] + ln * nx
    L[1] = dec_lp * L[1] + ln * ny
    L[2] = dec_lp * L[2] + ln * nz


@_jit
def _advance(pos, quat, vel, angmom, h_low, dh_low, ramp, h_top, hmax_low, hmin_top, shift0, dshift,
             top_offset, dtop, dx, size, a, c,
             samples, weights, k_area, mass, i1, i3, gamma_vp, gamma_va, gamma_lp, gamma_la, dt,
             n_steps, max_overlap, force, torque, overlap):
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
    """
    nf = pos.shape[0]
    tmp_r = np.empty((3, 3))
    tmp_a = np.empty(4)
    tmp_b = np.empty(4)
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
    _forces(pos, quat, h_low, dh_low, 0.0, h_top, hmax_low, hmin_top, shift0, top_offset, dx, size,
            a, c, samples, weights, k_area, force, torque, overlap)
    for i in range(nf):
        if overlap[i] > max_overlap:
            return 2, 0, i
    for s in range(1, n_steps + 1):
        for i in range(nf):
            if not uniform:
                _damp_axes(quat[i], vel[i], angmom[i], decay, dec_va, dec_lp, dec_la)
            for d in range(3):
                vel[i, d] = vel[i, d] * decay_d + 0.5 * dt * force[i, d] / mass
                angmom[i, d] = angmom[i, d] * decay_d + 0.5 * dt * torque[i, d]
                pos[i, d] += dt * vel[i, d]
            pos[i, 0] -= size * math.floor(pos[i, 0] / size)
            pos[i, 1] -= size * math.floor(pos[i, 1] / size)
            _free_rotation(quat[i], angmom[i], i1, i3, dt, tmp_r, tmp_a, tmp_b)
        _forces(pos, quat, h_low, dh_low, ramp * s / n_steps, h_top, hmax_low, hmin_top,
                shift0 + s * dshift, top_offset + s * dtop, dx, size, a, c, samples, weights,
                k_area, force, torque, overlap)
        for i in range(nf):
            for d in range(3):
                vel[i, d] = (vel[i, d] + 0.5 * dt * force[i, d] / mass) * decay_d
                angmom[i, d] = (angmom[i, d] + 0.5 * dt * torque[i, d]) * decay_d
            if not uniform:
                _damp_axes(quat[i], vel[i], angmom[i], decay, dec_va, dec_lp, dec_la)
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
