"""Numba kernels of the Fourier-BEM contact solve (private; use :mod:`tribocosim.surrogate.bem`).

The loops of the constrained conjugate gradient over the grid or over the free set F, the saturated set S and the
violators: the active sets and the residual (:func:`_classify`, :func:`_violations`), the search direction, the
kernel product in Fourier space, the steps, the mean-pressure map of an active-set change and its projection, and the
direct-summation correction of a few changed points. The equations are in :mod:`tribocosim.surrogate.bem`'s
docstring. The point states are ``_ZERO`` (t = 0), ``_FREE`` (0 < t < p_crit) and ``_SAT`` (t = p_crit).
"""

from __future__ import annotations

import numba as nb
import numpy as np

_FM = {"reassoc", "contract", "nsz", "arcp"}
_jit = nb.njit(cache=True, nogil=True, fastmath=_FM)  # reductions may be reassociated
_jit_exact = nb.njit(cache=True, nogil=True)  # no FMA contraction: exact zero differences

_ZERO, _FREE, _SAT = 0, 1, 2


@_jit
def _classify(t, g, state, pc, dguess):
    """Set state (0 zero, 1 free, 2 saturated); sums over F of (g - dguess) and its square."""
    cf = 0
    s1 = 0.0
    s2 = 0.0
    gmax_s = -np.inf
    gmin_z = np.inf
    for i in range(t.size):
        ti = t[i]
        if ti <= 0.0:
            state[i] = 0
            gmin_z = min(gmin_z, g[i])
        elif ti >= pc:
            state[i] = 2
            gmax_s = max(gmax_s, g[i])
        else:
            state[i] = 1
            x = g[i] - dguess
            cf += 1
            s1 += x
            s2 += x * x
    return cf, s1, s2, gmax_s, gmin_z


@_jit
def _violations(g, state, delta, vbuf):
    """Sum of squared bound violations at the approach delta; their indices go to vbuf."""
    v = 0.0
    nv = 0
    for i in range(g.size):
        s = state[i]
        x = g[i] - delta
        if (s == 0 and x < 0.0) or (s == 2 and x > 0.0):
            v += x * x
            vbuf[nv] = i
            nv += 1
    return v, nv


@_jit
def _direction(fidx, g, d, delta, beta):
    """d = r + beta (d - mean_F d) on F (r = g - delta); returns sum(r d)."""
    m = fidx.size
    dm = 0.0
    if beta != 0.0:
        for k in range(m):
            dm += d[fidx[k]]
        dm /= max(m, 1)
    rd = 0.0
    for k in range(m):
        i = fidx[k]
        r = g[i] - delta
        di = r + beta * (d[i] - dm)
        d[i] = di
        rd += r * di
    return rd


@_jit
def _apply_kernel(spec, kern, even):
    """spec *= kern in place; returns sum over the full spectrum of kern |spec|^2 (Parseval)."""
    n0, n1 = spec.shape
    acc = 0.0
    for a in range(n0):
        for b in range(n1):
            z = spec[a, b]
            k = kern[a, b]
            w = 1.0 if (b == 0 or (even and b == n1 - 1)) else 2.0
            acc += w * k * (z.real * z.real + z.imag * z.imag)
            spec[a, b] = z * k
    return acc


@_jit
def _step_free(fidx, t, d, w, tau, pc):
    """t -= tau d on F; returns (sum_F w, number of F points that left [0, pc])."""
    sw = 0.0
    nc = 0
    for k in range(fidx.size):
        i = fidx[k]
        sw += w[i]
        x = t[i] - tau * d[i]
        t[i] = x
        if x <= 0.0 or x >= pc:
            nc += 1
    return sw, nc


@_jit
def _step_gap(g, w, state, tau, delta, vbuf):
    """g -= tau w; sums over F of (g - delta) and its square; squared violations (indices to
    vbuf) and their count."""
    s1 = 0.0
    s2 = 0.0
    v = 0.0
    nv = 0
    for i in range(g.size):
        x = g[i] - tau * w[i]
        g[i] = x
        x -= delta
        s = state[i]
        if s == 1:
            s1 += x
            s2 += x * x
        elif (s == 0 and x < 0.0) or (s == 2 and x > 0.0):
            v += x * x
            vbuf[nv] = i
            nv += 1
    return s1, s2, v, nv


@_jit
def _capped_sum(y, c, pc):
    """f(c) = sum min(c y, pc) over y > 0 and df/dc."""
    f = 0.0
    df = 0.0
    for i in range(y.size):
        yi = y[i]
        if yi > 0.0:
            x = c * yi
            if x < pc:
                f += x
                df += yi
            else:
                f += pc
    return f, df


@_jit
def _shift_sum(y, lam, pc):
    f = 0.0
    for i in range(y.size):
        f += min(max(y[i] - lam, 0.0), pc)
    return f


@_jit_exact
def _project(y, c, lam, pc, every, t, idx_c, val_c, idx_1, val_1):
    """t <- clip(c y - lam, 0, pc) where y > 0 (everywhere if ``every``), else 0; collect
    t_new - c t_old and t_new - t_old (up to the buffer size) and count them."""
    mc = 0
    m1 = 0
    cap = idx_c.size
    for i in range(y.size):
        yi = y[i]
        tn = min(max(c * yi - lam, 0.0), pc) if (every or yi > 0.0) else 0.0
        to = t[i]
        dc = tn - c * to
        d1 = tn - to
        if dc != 0.0:
            if mc < cap:
                idx_c[mc] = i
                val_c[mc] = dc
            mc += 1
        if d1 != 0.0:
            if m1 < cap:
                idx_1[m1] = i
                val_1[m1] = d1
            m1 += 1
        t[i] = tn
    return mc, m1


@_jit
def _sparse_correct(g, h, kr, idx, val, m, c):
    """g <- c (g - h) + h + sum_k val_k Kr(x - x_k) (periodic direct sum, 2D arrays)."""
    n = g.shape[0]
    for a in range(n):
        if c != 1.0:
            for b in range(n):
                g[a, b] = c * (g[a, b] - h[a, b]) + h[a, b]
        for k in range(m):
            ia = idx[k] // n
            jb = idx[k] - ia * n
            ra = a - ia
            if ra < 0:
                ra += n
            v = val[k]
            for b in range(jb):
                g[a, b] += v * kr[ra, b - jb + n]
            for b in range(jb, n):
                g[a, b] += v * kr[ra, b - jb]


@_jit_exact
def _candidates(t, g, state, fidx, viol_idx, sidx, delta, tau_v, pc):
    """The points an active-set change considers (free, violating zero and saturated), their tractions and
    their trial values y: t on F, -tau_v (G - delta) at a zero point, pc - tau_v (G - delta) at a saturated one
    (module docstring, step 2)."""
    nz = 0
    for i in viol_idx:
        if state[i] == _ZERO:
            nz += 1
    nf, ns = fidx.size, sidx.size
    m = nf + nz + ns
    idx = np.empty(m, dtype=np.int64)
    t_old = np.empty(m)
    y = np.empty(m)
    for k in range(nf):
        i = fidx[k]
        idx[k] = i
        t_old[k] = t[i]
        y[k] = t[i]
    k = nf
    for i in viol_idx:
        if state[i] == _ZERO:
            idx[k] = i
            t_old[k] = 0.0
            y[k] = -tau_v * (g[i] - delta)
            k += 1
    for q in range(ns):
        i = sidx[q]
        idx[k] = i
        t_old[k] = pc
        y[k] = pc - tau_v * (g[i] - delta)
        k += 1
    return idx, t_old, y


@_jit_exact
def _new_sets(idx, t_new, pc, state, old_free, keep, d):
    """The points' new states from their tractions t_new (zero, free or saturated); the search direction d
    cleared where it loses its meaning: on the points that left F (``keep``), else on all of old F. Returns the
    new free and saturated indices, in the order of ``idx``."""
    nf = 0
    ns = 0
    for k in range(idx.size):
        x = t_new[k]
        s = _ZERO if x <= 0.0 else (_SAT if x >= pc else _FREE)
        state[idx[k]] = s
        if s == _FREE:
            nf += 1
        elif s == _SAT:
            ns += 1
    fidx = np.empty(nf, dtype=np.int64)
    sidx = np.empty(ns, dtype=np.int64)
    nf = 0
    ns = 0
    for k in range(idx.size):
        s = state[idx[k]]
        if s == _FREE:
            fidx[nf] = idx[k]
            nf += 1
        elif s == _SAT:
            sidx[ns] = idx[k]
            ns += 1
    for i in old_free:
        if not keep or state[i] != _FREE:
            d[i] = 0.0
    return fidx, sidx
