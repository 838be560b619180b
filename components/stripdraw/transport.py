"""Debris transport on the strip: Archard source, advection with the tool, cap (Eq. 12-14, 24, 37).

beta(X, t) is the area fraction of the strip face covered by flakes, a nodal field in material
coordinates X. Over a coupling interval of length dt in which node i slid by dU_i:

    d(beta)/dt + d(j)/dX = K P |dU/dt| / (H h_p)   (Eq. 12 with the source of Eq. 37)
    j = -zeta (dU/dt) beta                           (Eq. 13)

The source acts on contact nodes in proportion to their contact weight (tributary overlap with
the pad, averaged over the interval), so that a node integrates K P s_under_pad / (H h_p).

Upwind discretisation (Eq. 14) of the flux on the face between nodes i and i+1, with the face
velocity u = (dU_i + dU_{i+1}) / (2 dt): F = -zeta u beta_{i+1} if u > 0 (debris carried by the
tool moves towards -X relative to the strip), F = -zeta u beta_i if u < 0. We take the upwind
difference IMPLICITLY in time (backward Euler): the matrix is an M-matrix whose columns sum to 1,
so the update is unconditionally stable, keeps beta >= 0, and conserves sum(beta) exactly for any
coupling step, also the very large steps that the stability report tries. At small steps it agrees
with the paper's explicit Eq. 14 to first order.

Boundary rule (docs/model.md section 3): transport acts only between nodes that are both under the pad;
the faces at the pad's edges carry no flux. Debris riding on the tool therefore stays under the
pad (it piles up at the entry edge, the "accumulation zone" of Sec. 7) and is never lost; debris
on the strip leaves the pad with the strip. Mass is conserved exactly.

Cap (Eq. 24): after the update beta = min(beta, beta_thres); what the cap removes is returned so
the caller can account for it (only the cap removes debris).
"""

from __future__ import annotations

import numpy as np

from tribocosim.components.stripdraw.kernels import USE_NUMBA, _positive_range_k, jit, thomas


def archard_source(dU, weight, pressure, archard_k, hardness, particle_thickness):
    """Debris produced per node over an interval: K P |dU| w / (H h_p) (Eq. 37 integrated)."""
    return archard_k * pressure * np.abs(dU) * weight / (hardness * particle_thickness)


def advect_implicit_numpy(beta, dU, weight, zeta, element_length):
    """Implicit upwind advection of ``beta`` with the tool-carried flux (Eq. 13-14).

    Parameters
    ----------
    beta : ndarray
        Nodal debris fraction before the interval (not modified).
    dU : ndarray
        Nodal displacement increments over the interval [m].
    weight : ndarray
        Contact weights in [0, 1]; faces between two nodes with positive weight carry flux.
    zeta : float
        Fraction of debris that sticks to the tool.
    element_length : float
        Element length l_e [m].

    Returns
    -------
    ndarray
        beta after advection; ``sum`` is conserved to rounding.
    """
    out = beta.copy()
    if zeta == 0.0:
        return out
    inside = np.flatnonzero(weight > 0)
    if inside.size < 2:
        return out
    lo, hi = inside[0], inside[-1] + 1  # the pad covers one contiguous run of nodes
    b = beta[lo:hi]
    n = b.size
    # face Courant numbers c_f = zeta * u_face * dt / l_e, both end nodes under the pad
    face_ok = (weight[lo:hi - 1] > 0) & (weight[lo + 1:hi] > 0)
    c = zeta * 0.5 * (dU[lo:hi - 1] + dU[lo + 1:hi]) / element_length * face_ok
    pos = np.maximum(c, 0.0)  # flux from node k+1 into node k
    neg = np.maximum(-c, 0.0)  # flux from node k into node k+1
    diag = np.ones(n)
    sub = np.zeros(n)
    sup = np.zeros(n)
    diag[1:] += pos
    sup[:-1] -= pos
    diag[:-1] += neg
    sub[1:] -= neg
    out[lo:hi] = thomas(sub, diag, sup, b.copy())
    return out


def _advect_loop(beta, dU, weight, zeta, element_length):
    """Loop form of :func:`advect_implicit_numpy` (compiled with numba; same result)."""
    out = beta.copy()
    lo, last = _positive_range_k(weight)  # the pad covers one contiguous run of nodes
    hi = last + 1
    if zeta == 0.0 or lo < 0 or hi - lo < 2:
        return out
    n = hi - lo
    diag = np.ones(n)
    sub = np.zeros(n)
    sup = np.zeros(n)
    for k in range(n - 1):
        a, b = lo + k, lo + k + 1
        if weight[a] > 0.0 and weight[b] > 0.0:
            c = zeta * 0.5 * (dU[a] + dU[b]) / element_length
            if c > 0.0:
                diag[k + 1] += c
                sup[k] -= c
            else:
                diag[k] -= c
                sub[k + 1] += c
    x = _thomas_for_advect(sub, diag, sup, beta[lo:hi].copy())
    for k in range(n):
        out[lo + k] = x[k]
    return out


_thomas_for_advect = thomas
advect_loop = jit(_advect_loop)
advect_implicit = advect_loop if USE_NUMBA else advect_implicit_numpy


def transport_step(beta, dU, weight, pressure, params, element_length, beta_cap):
    """One coupling interval of debris production (Eq. 37), transport (Eq. 13-14) and cap (Eq. 24).

    Parameters
    ----------
    beta, dU, weight : ndarray
        Nodal debris fraction, displacement increments [m] and contact weights in [0, 1].
    pressure : float
        Contact pressure P [Pa].
    params : StripDrawParameters
        Supplies archard_k, hardness, particle_thickness and zeta.
    element_length : float
        l_e [m].
    beta_cap : float
        beta_thres.

    Returns
    -------
    beta_new : ndarray
    removed : float
        Sum over nodes of what the cap removed.
    """
    src = archard_source(dU, weight, pressure, params.archard_k, params.hardness, params.particle_thickness)
    new = advect_implicit(beta + src, dU, weight, params.zeta, element_length)
    over = np.maximum(new - beta_cap, 0.0)
    return np.minimum(new, beta_cap), float(over.sum())
