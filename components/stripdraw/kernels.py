"""Hot loops of the strip-draw bar: explicit sub-cycling, generalized-alpha step, tridiagonal solve.

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
convex incremental potential (see the generalized-alpha section below).
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


# --------------------------------------------------------------------------------------------
# generalized-alpha step: Newton on the stick/slip set, globalised by a line search
# --------------------------------------------------------------------------------------------
# The step's equations are the gradient of a convex incremental potential (C1, piecewise quadratic):
#   Pi(u) = sum_i [ cm m_i / 2 (u_i - u~_i)^2 + (am m_i a_n,i + af f_n,i)(u_i - u0_i) ]
#         + (1 - af) [ 1/2 u^T K u + sum_i w_T ov_i phi_i(u_i - Up_i) ],
# with cm = (1 - am) / (b dt^2), the Newmark predictor u~ = u_n + dt v_n + dt^2 (1/2 - b) a_n,
# u0 the initial guess (a constant shift that keeps Pi small and well rounded), and phi the
# potential of the return-mapped interface spring: k_s x^2 / 2 while |k_s x| <= T_max, else
# T_max |x| - T_max^2 / (2 k_s). Newton directions are descent directions (the tangent is
# positive definite), and a backtracking (Armijo) line search on Pi makes the iteration converge
# from any start: without it, a pad whose nodes all slip has no interface stiffness in the
# tangent, and the iteration can flip the whole pad between slipping forwards and backwards.


def _galpha_eval(u, u0, upred, A, Upn, fprev, ov, m, ke, ks, wT, tmax, am, af, cm, T, state, f, r):
    """Tractions, stick/slip state, nodal forces f = K u + F, residual r = dPi/du, and Pi."""
    n = u.size
    N = n - 1
    pot = 0.0
    for i in range(n):
        T[i] = 0.0
        state[i] = 0
        if ov[i] > 0.0:
            x = u[i] - Upn[i]
            t, slipping, phi = _interface_law_k(x, ks, tmax[i])
            T[i] = t
            state[i] = 1 if not slipping else (2 if x > 0 else 3)
            if i < N:
                pot += (1.0 - af) * wT * ov[i] * phi
        f[i] = T[i] * wT * ov[i]
    for e in range(N):
        d = u[e + 1] - u[e]
        f[e] -= ke * d
        f[e + 1] += ke * d
        pot += (1.0 - af) * 0.5 * ke * d * d
    rmax = 0.0
    for i in range(N):
        lin = am * m[i] * A[i] + af * fprev[i]
        r[i] = cm * m[i] * (u[i] - upred[i]) + lin + (1.0 - af) * f[i]
        pot += 0.5 * cm * m[i] * (u[i] - upred[i]) ** 2 + lin * (u[i] - u0[i])
        rmax = max(rmax, abs(r[i]))
    return pot, rmax


def _galpha_loop(dt, U, V, A, Up, contact, fprev, ov, m, ke, ks, wT, tmax, vg, am, af, beta, gamma, max_iter, rtol):
    """One generalized-alpha step; ``ov`` are the contact weights of the step.

    Converged when a full Newton step lands on the stick/slip set (with slip directions) it was
    built from (the problem is linear on that set, so the step was exact), or when the residual
    is below ``rtol`` times the force scale (friction capacity + grip pull). Returns
    (iterations, friction force, grip reaction), or iterations = -1 when ``max_iter`` Newton
    iterations did not converge; then nothing has been changed.
    """
    n = U.size
    N = n - 1
    Upn = Up.copy()
    for i in range(n):
        if ov[i] > 0.0 and contact[i] == 0:
            Upn[i] = U[i]  # nodes entering the pad start stress-free
    cm = (1.0 - am) / (beta * dt * dt)
    upred = U + dt * V + dt * dt * (0.5 - beta) * A
    u = U + dt * vg  # initial guess: the strip follows the grip rigidly
    u0 = u.copy()
    fscale = ke * abs(dt * vg) + 1e-300
    for i in range(n):
        fscale += tmax[i] * wT * ov[i]
    T = np.zeros(n)
    state = np.zeros(n, np.int8)
    used = np.zeros(n, np.int8)
    f = np.zeros(n)
    r = np.zeros(N)
    ut = np.zeros(n)
    sub = np.zeros(N)
    dia = np.zeros(N)
    sup = np.zeros(N)
    rhs = np.zeros(N)
    pot, rmax = _galpha_eval_k(u, u0, upred, A, Upn, fprev, ov, m, ke, ks, wT, tmax, am, af, cm, T, state, f, r)
    it = 0
    while rmax > rtol * fscale:
        if it >= max_iter:
            return -1, 0.0, 0.0
        slope = 0.0
        for i in range(N):
            kt = ks * wT * ov[i] if state[i] == 1 else 0.0
            dia[i] = cm * m[i] + (1.0 - af) * ((2.0 * ke if i > 0 else ke) + kt)
            sub[i] = -(1.0 - af) * ke
            sup[i] = -(1.0 - af) * ke
            rhs[i] = -r[i]
        for i in range(n):
            used[i] = state[i]
        du = _thomas_k(sub, dia, sup, rhs)
        for i in range(N):
            slope += r[i] * du[i]
        alpha = 1.0
        while True:
            for i in range(N):
                ut[i] = u[i] + alpha * du[i]
            ut[N] = u[N]
            pot_t, rmax_t = _galpha_eval_k(ut, u0, upred, A, Upn, fprev, ov, m, ke, ks, wT, tmax, am, af, cm, T, state, f, r)
            if pot_t <= pot + 1e-4 * alpha * slope or alpha < 1e-12:
                break
            alpha *= 0.5
        for i in range(n):
            u[i] = ut[i]
        pot, rmax = pot_t, rmax_t
        it += 1
        if alpha == 1.0:
            same = True
            for i in range(n):
                if state[i] != used[i]:
                    same = False
                    break
            if same:
                break
    # accept: Newmark updates, plastic slip, contact flags
    for i in range(N):
        anew = (u[i] - upred[i]) / (beta * dt * dt)
        V[i] = V[i] + dt * ((1.0 - gamma) * A[i] + gamma * anew)
        A[i] = anew
    V[N] = vg
    A[N] = 0.0
    fric = 0.0
    for i in range(n):
        U[i] = u[i]
        fprev[i] = f[i]
        if ov[i] > 0.0:
            contact[i] = 1
            Up[i] = Upn[i]
            if state[i] != 1:
                Up[i] = u[i] - T[i] / ks
            fric += T[i] * wT * ov[i]
        else:
            contact[i] = 0
    return it, fric, f[N]


def thomas_numpy(sub, diag, sup, rhs):
    """Reference/fallback tridiagonal solve (plain Python loop over NumPy arrays)."""
    return _thomas_loop(np.asarray(sub, float), np.asarray(diag, float), np.asarray(sup, float), np.asarray(rhs, float))


def galpha_numpy(dt, U, V, A, Up, contact, fprev, ov, m, ke, ks, wT, tmax, vg, am, af, beta, gamma, max_iter, rtol):
    """Reference of the generalized-alpha kernel (and its fallback without numba): vectorised Pi,
    residual and tangent, Thomas solve; the same Newton/line-search logic and convergence test."""
    n = U.size
    N = n - 1
    Upn = Up.copy()
    entering = (ov > 0) & (contact == 0)
    Upn[entering] = U[entering]
    cm = (1.0 - am) / (beta * dt * dt)
    upred = U + dt * V + dt * dt * (0.5 - beta) * A
    u = U + dt * vg
    u0 = u.copy()
    fscale = ke * abs(dt * vg) + 1e-300 + np.sum(tmax * wT * ov)
    lin = am * m[:N] * A[:N] + af * fprev[:N]
    inside = ov > 0

    def evaluate(u):
        x = u - Upn
        T, slipping, phi = interface_law(x, ks, tmax)
        T = T * inside
        phi = phi * inside
        state = np.where(inside, np.where(slipping, np.where(x > 0, 2, 3), 1), 0).astype(np.int8)
        d = np.diff(u)
        f = T * wT * ov
        f[:-1] -= ke * d
        f[1:] += ke * d
        r = cm * m[:N] * (u[:N] - upred[:N]) + lin + (1 - af) * f[:N]
        pot = (np.sum(0.5 * cm * m[:N] * (u[:N] - upred[:N]) ** 2 + lin * (u[:N] - u0[:N]))
               + (1 - af) * (0.5 * ke * np.sum(d * d) + np.sum((wT * ov * phi)[:N])))
        return pot, r, T, state, f

    pot, r, T, state, f = evaluate(u)
    it = 0
    while np.abs(r).max() > rtol * fscale:
        if it >= max_iter:
            return -1, 0.0, 0.0
        used = state
        diag = cm * m[:N] + (1 - af) * (ke * np.where(np.arange(N) > 0, 2.0, 1.0) + ks * wT * ov[:N] * (state[:N] == 1))
        off = np.full(N, -(1 - af) * ke)
        du = thomas_numpy(off, diag, off, -r)
        slope = float(r @ du)
        alpha = 1.0
        while True:
            ut = u.copy()
            ut[:N] += alpha * du
            pot_t, r, T, state, f = evaluate(ut)
            if pot_t <= pot + 1e-4 * alpha * slope or alpha < 1e-12:
                break
            alpha *= 0.5
        u, pot = ut, pot_t
        it += 1
        if alpha == 1.0 and np.array_equal(state, used):
            break
    anew = (u[:N] - upred[:N]) / (beta * dt * dt)
    V[:N] = V[:N] + dt * ((1 - gamma) * A[:N] + gamma * anew)
    A[:N] = anew
    V[N] = vg
    A[N] = 0.0
    U[:] = u
    fprev[:] = f
    Up[inside] = Upn[inside]
    slip_in = inside & (state != 1)
    Up[slip_in] = u[slip_in] - T[slip_in] / ks
    contact[:] = inside
    return it, float(np.sum(T * wT * ov)), float(f[N])


_thomas_k = jit(_thomas_loop)
_interface_law_k = jit(interface_law)
_galpha_eval_k = jit(_galpha_eval)
if USE_NUMBA:
    explicit_kernel = jit(_explicit_loop)
    galpha_kernel = jit(_galpha_loop)
    thomas = _thomas_k
else:  # pragma: no cover - numpy-only environment
    explicit_kernel = explicit_numpy
    galpha_kernel = galpha_numpy
    thomas = thomas_numpy

#: the loop forms, compiled or not, for tests that compare them with the NumPy references
explicit_loop = jit(_explicit_loop)
galpha_loop = jit(_galpha_loop)
