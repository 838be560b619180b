"""One generalized-alpha step of the bar, with the free parts of the bar condensed onto the pad.

The step (Chung & Hulbert 1993, doi:10.1115/1.2900803; force-averaged form, docs/model.md section 2)
minimises the convex incremental potential of the free nodes 0..N-1 (node N is the grip, moved with the
grip velocity):

    Pi(u) = sum_i [ cm m_i / 2 (u_i - u~_i)^2 + lin_i (u_i - u0_i) ]
          + (1 - af) [ 1/2 u^T K u + sum_i w_T ov_i phi_i(u_i - Up_i) ],

with cm = (1 - am) / (b dt^2), the Newmark predictor u~ = u_n + dt v_n + dt^2 (1/2 - b) a_n,
lin_i = am m_i a_n,i + af f_n,i, u0 = u_n + dt V0 (the strip following the grip rigidly: the initial
guess) and phi the potential of the return-mapped interface spring (kernels.interface_law; Eq. 4-5).

Only the nodes under the pad (ov_i > 0) make Pi non-quadratic. The bar outside the pad, the *tail*
(nodes 0..lo-1, not yet drawn in) and the *grip side* (hi+1..N-1), is a linear chain, so it is solved
exactly for any position of the pad's end nodes (static condensation, a Schur complement): Gaussian
elimination of the tail from node 0 towards lo and of the grip side from N-1 towards hi. What the
elimination leaves on an end node is a spring of stiffness K_t (K_g) and a force s_t (s_g), so that
the potential of the window [lo, hi],

    Pi_W(d) = sum_{i in W} [ cm m_i / 2 (x_i + d_i)^2 + lin_i d_i + (1 - af) w_T ov_i phi_i(z_i + d_i) ]
            + (1 - af) k_e / 2 sum_{e = lo}^{hi-1} (dU_e + d_{e+1} - d_e)^2
            + s_t d_lo + K_t d_lo^2 / 2 + s_g d_hi + K_g d_hi^2 / 2,

is Pi minimised over the free chains (up to a constant). The unknowns are the increments d = u - u0,
with x_i = u0_i - u~_i = dt V0 - dt v_i - dt^2 (1/2 - b) a_i, z_i = u0_i - Up_i and dU_e = U_e+1 - U_e:
no difference of two displacements of the size of the draw is ever taken. The window is solved by
Newton's method on the stick/slip set (tangent k_s w_T ov_i on sticking nodes), globalised by a
backtracking (Armijo) line search on Pi_W; it is converged when a full Newton step lands on the set it
was built from (the problem is linear on that set, so that step was exact), or when the window's
residual is below ``rtol`` times the force scale (friction capacity + grip pull). The chains are then
back-substituted and every free node gets its Newmark update.

The elimination factors depend on the step length only (:func:`chain_factors`; the model keeps them per
step length). Written with c = (1 - af) k_e and the excess e_i = d'_i - c of the eliminated diagonal d'_i
over c, the recurrences have no cancellation:

    tail:       e_0 = cm m_0,              e_i = cm m_i + q_{i-1} e_{i-1},   q_i = c / (c + e_i),
    grip side:  g_{N-1} = cm m_{N-1} + c,  g_j = cm m_j + q'_{j+1} g_{j+1}, q'_j = c / (c + g_j),

and the end springs are K_t = q_{lo-1} e_{lo-1}, K_g = q'_{hi+1} g_{hi+1} (c with no grip side: the
element to the grip node itself). With rho the eliminated right-hand sides (the negative residuals at
d = 0, rho_i += q_{i-1} rho_{i-1} along the tail), the back-substitution is d_i = rho_i / d'_i + q_i d_{i+1}.
Both chains are swept side by side (they are independent), with each node's residual and Newmark update
computed on the way: the sweeps are recurrences whose latency, not their arithmetic, sets their cost.

The cost of a step is one pass over the free nodes plus Newton on the window (~24 of the default 151
nodes), where the monolithic solve (the whole bar in every Newton iteration) cost a pass over all nodes per
iteration and line-search trial. ``tests/components/test_stripdraw_galpha.py`` holds this step against a
monolithic Newton solve of the same Pi (the same minimiser) and the loop form against the NumPy form; the
native model (tc_galpha.c) follows the loop form operation by operation.
"""

from __future__ import annotations

import numpy as np

from tribocosim.components.stripdraw.kernels import (
    USE_NUMBA,
    _interface_law_k,
    _positive_range_k,
    _thomas_k,
    interface_law,
    jit,
    thomas_numpy,
)


def _chain_factors(cm, m, c):
    """Elimination factors of the free chains for one step (module docstring): rows et, qt, it (tail:
    excess, c / d', 1 / d' of node i), eg, qg, ig (grip side). Entries a chain never uses stay 0."""
    n = m.size
    N = n - 1
    out = np.zeros((6, n))
    et, qt, it, eg, qg, ig = out[0], out[1], out[2], out[3], out[4], out[5]
    for i in range(N - 1):  # the tail never reaches node N-1 (the window holds at least one node)
        e = cm * m[i] if i == 0 else cm * m[i] + qt[i - 1] * et[i - 1]
        et[i] = e
        it[i] = 1.0 / (c + e)
        qt[i] = c * it[i]
    for j in range(N - 1, 0, -1):  # the grip side never reaches node 0
        g = cm * m[j] + c if j == N - 1 else cm * m[j] + qg[j + 1] * eg[j + 1]
        eg[j] = g
        ig[j] = 1.0 / (c + g)
        qg[j] = c * ig[j]
    return out


def _window(ov):
    """First and last node of the window: the nodes with ov > 0 and the free nodes between them, free
    nodes only (<= N-1); node N-1 alone when no free node touches the pad."""
    N = ov.size - 1
    lo, hi = _positive_range_k(ov)
    if lo < 0 or lo > N - 1:
        return N - 1, N - 1
    return lo, min(hi, N - 1)


def _window_eval(lo, hi, d, x, z, dU, lin, ov, m, ke, ks, wT, tmax, af, cm, st, kt, sg, kg, T, state, f, r):
    """Pi_W(d), the window residual r = dPi_W/dd and max |r|; tractions T and stick/slip states (0 off the
    pad, 1 stick, 2/3 slip +/-) and the nodal forces f (contact + elements inside the window)."""
    pot = 0.0
    for i in range(lo, hi + 1):
        T[i] = 0.0
        state[i] = 0
        if ov[i] > 0.0:
            xs = z[i] + d[i]
            t, slipping, phi = _interface_law_k(xs, ks, tmax[i])
            T[i] = t
            state[i] = 1 if not slipping else (2 if xs > 0 else 3)
            pot += (1.0 - af) * wT * ov[i] * phi
        f[i] = T[i] * wT * ov[i]
    for e in range(lo, hi):
        s = dU[e] + (d[e + 1] - d[e])
        f[e] -= ke * s
        f[e + 1] += ke * s
        pot += (1.0 - af) * 0.5 * ke * s * s
    rmax = 0.0
    for i in range(lo, hi + 1):
        y = x[i] + d[i]
        r[i] = cm * m[i] * y + lin[i] + (1.0 - af) * f[i]
        pot += 0.5 * cm * m[i] * y * y + lin[i] * d[i]
    r[lo] += st + kt * d[lo]
    pot += (st + 0.5 * kt * d[lo]) * d[lo]
    r[hi] += sg + kg * d[hi]
    pot += (sg + 0.5 * kg * d[hi]) * d[hi]
    for i in range(lo, hi + 1):
        rmax = max(rmax, abs(r[i]))
    return pot, rmax


def _galpha_loop(dt, U, V, A, Up, contact, fprev, ov, m, ke, ks, wT, tmax, vg, am, af, beta, gamma, max_iter,
                 rtol, chain):
    """One generalized-alpha step (module docstring); ``ov`` are the contact weights of the step, ``chain``
    the :func:`chain_factors` of ``dt``. Returns (iterations, friction force, grip reaction), or
    iterations = -1 when ``max_iter`` Newton iterations did not converge; then nothing has been changed."""
    n = U.size
    N = n - 1
    c = (1.0 - af) * ke
    et, qt, it_, eg, qg, ig = chain[0], chain[1], chain[2], chain[3], chain[4], chain[5]
    lo, hi = _window_k(ov)
    cm = (1.0 - am) / (beta * dt * dt)
    cA = dt * dt * (0.5 - beta)
    shift = dt * vg
    x = np.empty(n)
    lin = np.empty(n)
    dU = np.empty(n)
    z = np.zeros(n)
    d = np.zeros(n)
    rho = np.zeros(n)
    for i in range(N):
        dU[i] = U[i + 1] - U[i]
    Upn = Up.copy()
    for i in range(lo, hi + 1):
        x[i] = shift - dt * V[i] - cA * A[i]
        lin[i] = am * m[i] * A[i] + af * fprev[i]
        if ov[i] > 0.0:
            if contact[i] == 0:
                Upn[i] = U[i]  # nodes entering the pad start stress-free
            z[i] = (U[i] - Upn[i]) + shift
    if ov[N] > 0.0 and contact[N] == 0:
        Upn[N] = U[N]
    # eliminate the tail forwards (i = k) and the grip side backwards (j = N-1-k), side by side: the two
    # recurrences are independent, and each node's residual at d = 0 is computed on the way
    nt = lo
    ng = N - 1 - hi
    for k in range(max(nt, ng)):
        if k < nt:
            i = k
            x[i] = shift - dt * V[i] - cA * A[i]
            fel = (ke * dU[i - 1] if i > 0 else 0.0) - ke * dU[i]
            rho[i] = -(cm * m[i] * x[i] + (am * m[i] * A[i] + af * fprev[i]) + (1.0 - af) * fel)
            if i > 0:
                rho[i] += qt[i - 1] * rho[i - 1]
        if k < ng:
            j = N - 1 - k
            x[j] = shift - dt * V[j] - cA * A[j]
            fel = ke * dU[j - 1] - ke * dU[j]
            rho[j] = -(cm * m[j] * x[j] + (am * m[j] * A[j] + af * fprev[j]) + (1.0 - af) * fel)
            if j < N - 1:
                rho[j] += qg[j + 1] * rho[j + 1]
    st = 0.0
    kt = 0.0
    if lo > 0:
        st = c * dU[lo - 1] - qt[lo - 1] * rho[lo - 1]
        kt = qt[lo - 1] * et[lo - 1]
    if hi < N - 1:
        sg = -c * dU[hi] - qg[hi + 1] * rho[hi + 1]
        kg = qg[hi + 1] * eg[hi + 1]
    else:  # the element to the grip node, which does not move within the step
        sg = -c * dU[hi]
        kg = c
    fscale = ke * abs(dt * vg) + 1e-300
    for i in range(lo, hi + 1):  # ov = 0 outside the window and the grip node: those terms are +0.0
        fscale += tmax[i] * wT * ov[i]
    fscale += tmax[N] * wT * ov[N]
    T = np.zeros(n)
    state = np.zeros(n, np.int8)
    used = np.zeros(n, np.int8)
    f = np.zeros(n)
    r = np.zeros(n)
    dt_ = np.zeros(n)
    w = hi - lo + 1
    sub = np.zeros(w)
    dia = np.zeros(w)
    sup = np.zeros(w)
    rhs = np.zeros(w)
    pot, rmax = _window_eval_k(lo, hi, d, x, z, dU, lin, ov, m, ke, ks, wT, tmax, af, cm, st, kt, sg, kg, T,
                               state, f, r)
    iters = 0
    while rmax > rtol * fscale:
        if iters >= max_iter:
            return -1, 0.0, 0.0
        for i in range(lo, hi + 1):
            kt_i = ks * wT * ov[i] if state[i] == 1 else 0.0
            springs = (1.0 if i > lo else 0.0) + (1.0 if i < hi else 0.0)
            dia[i - lo] = cm * m[i] + (1.0 - af) * (springs * ke + kt_i)
            sub[i - lo] = -(1.0 - af) * ke
            sup[i - lo] = -(1.0 - af) * ke
            rhs[i - lo] = -r[i]
            used[i] = state[i]
        dia[0] += kt
        dia[w - 1] += kg
        step = _thomas_k(sub, dia, sup, rhs)
        slope = 0.0
        for i in range(w):
            slope += r[lo + i] * step[i]
        alpha = 1.0
        while True:
            for i in range(w):
                dt_[lo + i] = d[lo + i] + alpha * step[i]
            pot_t, rmax_t = _window_eval_k(lo, hi, dt_, x, z, dU, lin, ov, m, ke, ks, wT, tmax, af, cm, st, kt,
                                           sg, kg, T, state, f, r)
            if pot_t <= pot + 1e-4 * alpha * slope or alpha < 1e-12:
                break
            alpha *= 0.5
        for i in range(lo, hi + 1):
            d[i] = dt_[i]
        pot, rmax = pot_t, rmax_t
        iters += 1
        if alpha == 1.0:
            same = True
            for i in range(lo, hi + 1):
                if state[i] != used[i]:
                    same = False
                    break
            if same:
                break
    # back-substitute the chains (side by side, as above), each node's Newmark update on the way
    bdt2 = beta * dt * dt
    for k in range(max(nt, ng)):
        if k < nt:
            i = lo - 1 - k
            d[i] = rho[i] * it_[i] + qt[i] * d[i + 1]
            anew = (x[i] + d[i]) / bdt2
            V[i] = V[i] + dt * ((1.0 - gamma) * A[i] + gamma * anew)
            A[i] = anew
            U[i] = U[i] + (shift + d[i])
        if k < ng:
            j = hi + 1 + k
            d[j] = rho[j] * ig[j] + qg[j] * d[j - 1]
            anew = (x[j] + d[j]) / bdt2
            V[j] = V[j] + dt * ((1.0 - gamma) * A[j] + gamma * anew)
            A[j] = anew
            U[j] = U[j] + (shift + d[j])
    for i in range(lo, hi + 1):
        anew = (x[i] + d[i]) / bdt2
        V[i] = V[i] + dt * ((1.0 - gamma) * A[i] + gamma * anew)
        A[i] = anew
        U[i] = U[i] + (shift + d[i])
    U[N] = U[N] + shift
    V[N] = vg
    A[N] = 0.0
    # forces at the new state: friction (the window's tractions, and the grip node's if it is under the pad)
    if ov[N] > 0.0:
        t, slipping, _ = _interface_law_k(U[N] - Upn[N], ks, tmax[N])
        T[N] = t
        state[N] = 1 if not slipping else 2
    # the elements' extensions at the new state from the increments (not from the updated U, whose rounding
    # to draw-sized values would make the forces jump by ~k_e ulp(U) between nearby inputs), their forces at
    # every node, then the friction of the nodes under the pad (window and grip node)
    d[N] = 0.0
    for e in range(N):
        dU[e] = dU[e] + (d[e + 1] - d[e])
    fprev[0] = 0.0 - ke * dU[0]
    for i in range(1, N):
        fprev[i] = (0.0 + ke * dU[i - 1]) - ke * dU[i]
    fprev[N] = 0.0 + ke * dU[N - 1]
    contact[:] = 0
    fric = 0.0
    for k in range(lo, hi + 2):
        i = k if k <= hi else N  # the window, then the grip node (hi < N always)
        if not ov[i] > 0.0:
            continue
        contact[i] = 1
        Up[i] = Upn[i]
        if state[i] != 1:
            Up[i] = U[i] - T[i] / ks
        fc = T[i] * wT * ov[i]
        fric += fc
        f_i = fc
        if i > 0:
            f_i += ke * dU[i - 1]
        if i < N:
            f_i -= ke * dU[i]
        fprev[i] = f_i
    return iters, fric, fprev[N]


def galpha_numpy(dt, U, V, A, Up, contact, fprev, ov, m, ke, ks, wT, tmax, vg, am, af, beta, gamma, max_iter,
                 rtol, chain):
    """NumPy form of :func:`galpha_loop` (the reference it is tested against, and the kernel without numba):
    the same elimination, window Newton and convergence test, with the window's potential, residual and
    tangent as array expressions (the chain recurrences stay loops)."""
    n = U.size
    N = n - 1
    c = (1.0 - af) * ke
    et, qt, it_, eg, qg, ig = chain
    lo, hi = _window(ov)
    cm = (1.0 - am) / (beta * dt * dt)
    cA = dt * dt * (0.5 - beta)
    shift = dt * vg
    x = shift - dt * V[:N] - cA * A[:N]
    lin = am * m[:N] * A[:N] + af * fprev[:N]
    dU = np.diff(U)
    inside = ov > 0
    Upn = Up.copy()
    entering = inside & (contact == 0)
    Upn[entering] = U[entering]
    z = np.where(inside, (U - Upn) + shift, 0.0)
    fel = np.zeros(N)
    fel[1:] += ke * dU[:-1]
    fel -= ke * dU
    res0 = -(cm * m[:N] * x + lin + (1.0 - af) * fel)
    rho = np.zeros(n)
    for i in range(lo):
        rho[i] = res0[i] + (qt[i - 1] * rho[i - 1] if i > 0 else 0.0)
    for j in range(N - 1, hi, -1):
        rho[j] = res0[j] + (qg[j + 1] * rho[j + 1] if j < N - 1 else 0.0)
    st, kt = (c * dU[lo - 1] - qt[lo - 1] * rho[lo - 1], qt[lo - 1] * et[lo - 1]) if lo > 0 else (0.0, 0.0)
    if hi < N - 1:
        sg, kg = -c * dU[hi] - qg[hi + 1] * rho[hi + 1], qg[hi + 1] * eg[hi + 1]
    else:
        sg, kg = -c * dU[hi], c
    fscale = ke * abs(dt * vg) + 1e-300 + np.sum(tmax * wT * ov)
    W = slice(lo, hi + 1)
    xw, zw, lw, mw, ovw, tw, dUw = x[W], z[W], lin[W], m[W], ov[W], tmax[W], dU[lo:hi]
    inw = ovw > 0

    def evaluate(dw):
        xs = zw + dw
        T, slipping, phi = interface_law(xs, ks, tw)
        T, phi = T * inw, phi * inw
        state = np.where(inw, np.where(slipping, np.where(xs > 0, 2, 3), 1), 0).astype(np.int8)
        s = dUw + np.diff(dw)
        f = T * wT * ovw
        f[:-1] -= ke * s
        f[1:] += ke * s
        y = xw + dw
        r = cm * mw * y + lw + (1.0 - af) * f
        r[0] += st + kt * dw[0]
        r[-1] += sg + kg * dw[-1]
        pot = (np.sum(0.5 * cm * mw * y * y + lw * dw) + (1.0 - af) * (np.sum(wT * ovw * phi) + 0.5 * ke * np.sum(s * s))
               + (st + 0.5 * kt * dw[0]) * dw[0] + (sg + 0.5 * kg * dw[-1]) * dw[-1])
        return pot, r, T, state

    dw = np.zeros(hi - lo + 1)
    pot, r, T, state = evaluate(dw)
    iters = 0
    springs = np.full(dw.size, 2.0)
    springs[0] -= 1.0
    springs[-1] -= 1.0
    while np.abs(r).max() > rtol * fscale:
        if iters >= max_iter:
            return -1, 0.0, 0.0
        used = state
        diag = cm * mw + (1.0 - af) * (springs * ke + ks * wT * ovw * (state == 1))
        diag[0] += kt
        diag[-1] += kg
        off = np.full(dw.size, -(1.0 - af) * ke)
        step = thomas_numpy(off, diag, off, -r)
        slope = float(r @ step)
        alpha = 1.0
        while True:
            trial = dw + alpha * step
            pot_t, r, T, state = evaluate(trial)
            if pot_t <= pot + 1e-4 * alpha * slope or alpha < 1e-12:
                break
            alpha *= 0.5
        dw, pot = trial, pot_t
        iters += 1
        if alpha == 1.0 and np.array_equal(state, used):
            break
    d = np.zeros(n)
    d[W] = dw
    for i in range(lo - 1, -1, -1):
        d[i] = rho[i] * it_[i] + qt[i] * d[i + 1]
    for j in range(hi + 1, N):
        d[j] = rho[j] * ig[j] + qg[j] * d[j - 1]
    anew = (x + d[:N]) / (beta * dt * dt)
    V[:N] = V[:N] + dt * ((1.0 - gamma) * A[:N] + gamma * anew)
    A[:N] = anew
    U[:N] = U[:N] + (shift + d[:N])
    U[N] = U[N] + shift
    V[N] = vg
    A[N] = 0.0
    Tall = np.zeros(n)
    stick = np.zeros(n, bool)
    Tall[W] = T
    stick[W] = state == 1
    if inside[N]:
        t, slipping, _ = interface_law(U[N] - Upn[N], ks, tmax[N])
        Tall[N], stick[N] = t, not slipping
    F = Tall * wT * ov * inside
    Up[inside] = Upn[inside]
    slip_in = inside & ~stick
    Up[slip_in] = U[slip_in] - Tall[slip_in] / ks
    contact[:] = inside
    s = dU + np.diff(d)  # the extensions from the increments (d_N = 0), as the loop form
    fprev[:] = F
    fprev[:-1] -= ke * s
    fprev[1:] += ke * s
    return iters, float(np.sum(F)), float(fprev[N])


_window_k = jit(_window)
_window_eval_k = jit(_window_eval)
chain_factors = jit(_chain_factors)
galpha_loop = jit(_galpha_loop)
#: the kernel the model runs: the loop form when numba is importable, else the NumPy form
galpha_kernel = galpha_loop if USE_NUMBA else galpha_numpy
