"""Hot loops of the strip-draw bar: contact weights, the interface law, explicit sub-cycling, tridiagonal solve.

Each kernel is written twice: a loop form (compiled by numba when it is importable) and a
vectorised NumPy form that is the reference the loop form is tested against, and the fallback
when numba is absent (the FMU runs with numpy only). ``USE_NUMBA`` says which one the model uses.

Notation (one pad, one face; node N is the grip, nodes 0..N-1 are free):

- lumped mass m_i = rho A l_e (half at both ends), element stiffness k_e = E A / l_e;
- contact weight: the overlap ``ov_i`` of node i's tributary segment, placed at its current
  position x_i = X_i + U_i, with the tool window [a_lo, a_hi] (length l_e inside, l_e/2 at the ends);
- interface law (Eq. 4-5), :func:`interface_law`, the one function every kernel calls: trial
  T = k_s (U_i - Up_i); if |T| > mu_i P then T = sign(T) mu_i P and Up_i = U_i - T / k_s (return
  mapping); nodal force on the bar -T w_T ov_i. A node that enters the window starts stress-free
  (Up_i := U_i).

Explicit central difference (App. B, Eq. 31-32, Newmark beta=0, gamma=1/2), lumped mass:
predictor U += dt V + dt^2/2 A, V += dt/2 A; forces at the predicted U; A = f/m; V += dt/2 A.

Generalized-alpha (Chung & Hulbert 1993, doi:10.1115/1.2900803), force-averaged form:
M [(1-am) a_{n+1} + am a_n] + (1-af) f(u_{n+1}) + af f(u_n) = 0, with the Newmark updates
u_{n+1} = u_n + dt v_n + dt^2 [(1/2 - b) a_n + b a_{n+1}], v_{n+1} = v_n + dt [(1-g) a_n + g a_{n+1}],
am = (2 r - 1)/(r + 1), af = r/(r + 1), g = 1/2 - am + af, b = (1 - am + af)^2 / 4 for the spectral
radius r = rho_inf. Second order, unconditionally stable for the linear part. The friction law is
piecewise linear, so each step is solved by Newton's method on the stick/slip set (tangent
k_s w_T ov_i on sticking nodes, 0 on slipping ones), globalised by a line search on the step's
convex incremental potential; the step, with the bar outside the pad condensed onto it, is
:mod:`tribocosim.components.stripdraw.galpha`.
"""

from __future__ import annotations

import numpy as np

try:  # numba is optional at run time (the FMU needs only numpy)
    import numba

    USE_NUMBA = True
except ImportError:  # pragma: no cover - exercised in the numpy-only FMU environment
    numba = None
    USE_NUMBA = False


def jit(func):
    """The one jit policy: nopython, cached; identity without numba."""
    if numba is None:
        return func
    return numba.njit(cache=True, nogil=True)(func)


# --------------------------------------------------------------------------------------------
# contact weights and the return mapping (shared by both integrators)
# --------------------------------------------------------------------------------------------
def overlap_numpy(X, U, half_le, a_lo, a_hi):
    """Overlap of each node's tributary segment with the tool window [a_lo, a_hi] (NumPy)."""
    x = X + U
    lo = x - half_le
    hi = x + half_le
    lo[0] = x[0]
    hi[-1] = x[-1]
    return np.maximum(0.0, np.minimum(hi, a_hi) - np.maximum(lo, a_lo))


def positive_range(a):
    """First and last index i with a[i] > 0 (loop form; (-1, -1) when there is none): the pad's nodes."""
    first = -1
    last = -1
    for i in range(a.size):
        if a[i] > 0.0:
            if first < 0:
                first = i
            last = i
    return first, last


def interface_law(x, ks, tmax):
    """The interface law (Eq. 4-5), the one place it is written: elastic-perfectly-plastic Coulomb.

    For the elastic slip ``x = U - U_p`` of a node (scalars, or arrays element-wise): trial traction
    k_s x; if |k_s x| > T_max = mu P the node slips and T = sign(k_s x) T_max (the return mapping then
    sets U_p = U - T / k_s). Returns ``(T, slipping, phi)`` with ``phi`` the potential of the
    return-mapped spring: k_s x^2 / 2 while sticking, T_max |x| - T_max^2 / (2 k_s) while slipping
    (its derivative is T; the generalized-alpha step minimises it). Called by every integrator kernel
    (compiled inside the numba loops, vectorised in the NumPy references).
    """
    trial = ks * x
    T = np.minimum(np.maximum(trial, -tmax), tmax)
    slipping = np.abs(trial) > tmax
    phi = slipping * (tmax * np.abs(x) - 0.5 * tmax * tmax / ks) + (1 - slipping) * (0.5 * ks * x * x)
    return T, slipping, phi


def return_mapping_numpy(U, Up, contact, ov, ks, tmax):
    """Eq. 4-5 on every node (NumPy). Updates ``Up`` and ``contact`` in place; returns T, stick."""
    entering = (ov > 0) & (contact == 0)
    Up[entering] = U[entering]
    contact[:] = ov > 0
    T, slip, _ = interface_law(U - Up, ks, tmax)
    T[contact == 0] = 0.0
    Up[slip & (contact == 1)] = U[slip & (contact == 1)] - T[slip & (contact == 1)] / ks
    return T, (~slip) & (contact == 1)


# --------------------------------------------------------------------------------------------
# explicit central difference, sub-cycled
# --------------------------------------------------------------------------------------------
def _explicit_loop(n_sub, dt, U, V, A, Up, contact, X, minv, ke, ks, wT, half_le, a_lo, a_hi, tmax, vg):
    n = U.size
    N = n - 1
    f = np.empty(n)
    fric = 0.0
    for _ in range(n_sub):
        for i in range(N):
            U[i] += dt * V[i] + 0.5 * dt * dt * A[i]
            V[i] += 0.5 * dt * A[i]
        U[N] += dt * vg
        V[N] = vg
        A[N] = 0.0
        for i in range(n):
            f[i] = 0.0
        for e in range(N):
            s = ke * (U[e + 1] - U[e])
            f[e] += s
            f[e + 1] -= s
        fric = 0.0
        for i in range(n):
            x = X[i] + U[i]
            lo = x if i == 0 else x - half_le
            hi = x if i == N else x + half_le
            ov = min(hi, a_hi) - max(lo, a_lo)
            if ov > 0.0:
                if contact[i] == 0:
                    Up[i] = U[i]
                    contact[i] = 1
                T, slipping, _ = _interface_law_k(U[i] - Up[i], ks, tmax[i])
                if slipping:
                    Up[i] = U[i] - T / ks
                F = T * wT * ov
                f[i] -= F
                fric += F
            else:
                contact[i] = 0
        for i in range(N):
            A[i] = f[i] * minv[i]
            V[i] += 0.5 * dt * A[i]
    reaction = -f[N]
    return fric, reaction


def explicit_numpy(n_sub, dt, U, V, A, Up, contact, X, minv, ke, ks, wT, half_le, a_lo, a_hi, tmax, vg):
    """Vectorised reference of the explicit sub-cycling kernel (same arguments and effects)."""
    N = U.size - 1
    fric = 0.0
    f = np.zeros(U.size)
    for _ in range(n_sub):
        U[:N] += dt * V[:N] + 0.5 * dt * dt * A[:N]
        V[:N] += 0.5 * dt * A[:N]
        U[N] += dt * vg
        V[N] = vg
        A[N] = 0.0
        s = ke * np.diff(U)
        f = np.zeros(U.size)
        f[:-1] += s
        f[1:] -= s
        ov = overlap_numpy(X, U, half_le, a_lo, a_hi)
        T, _ = return_mapping_numpy(U, Up, contact, ov, ks, tmax)
        F = T * wT * ov
        f -= F
        fric = float(F.sum())
        A[:N] = f[:N] * minv[:N]
        V[:N] += 0.5 * dt * A[:N]
    return fric, -f[N]


# --------------------------------------------------------------------------------------------
# tridiagonal solve (Thomas algorithm); the reference is a dense solve in the tests
# --------------------------------------------------------------------------------------------
def _thomas_loop(sub, diag, sup, rhs):
    n = diag.size
    c = np.empty(n)
    d = np.empty(n)
    c[0] = sup[0] / diag[0]
    d[0] = rhs[0] / diag[0]
    for i in range(1, n):
        m = diag[i] - sub[i] * c[i - 1]
        c[i] = sup[i] / m
        d[i] = (rhs[i] - sub[i] * d[i - 1]) / m
    x = np.empty(n)
    x[n - 1] = d[n - 1]
    for i in range(n - 2, -1, -1):
        x[i] = d[i] - c[i] * x[i + 1]
    return x


def thomas_numpy(sub, diag, sup, rhs):
    """Reference/fallback tridiagonal solve (plain Python loop over NumPy arrays)."""
    return _thomas_loop(np.asarray(sub, float), np.asarray(diag, float), np.asarray(sup, float), np.asarray(rhs, float))


_thomas_k = jit(_thomas_loop)
_positive_range_k = jit(positive_range)
_interface_law_k = jit(interface_law)
if USE_NUMBA:
    explicit_kernel = jit(_explicit_loop)
    thomas = _thomas_k
else:  # pragma: no cover - numpy-only environment
    explicit_kernel = explicit_numpy
    thomas = thomas_numpy

#: the loop forms, compiled or not, for tests that compare them with the NumPy references
explicit_loop = jit(_explicit_loop)
