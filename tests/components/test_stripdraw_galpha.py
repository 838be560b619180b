"""The generalized-alpha step with the free bar condensed onto the pad (components/stripdraw/galpha.py).

Oracles: the Schur complement of the free chains by a dense solve (the condensation factors), and a
monolithic Newton solve of the same incremental potential over every free node with dense linear algebra
(the step's answer: the potential is strictly convex, so both must reach the same minimiser, whatever path
their Newton iterations take). The loop form (numba) is also held against the NumPy form, which must take
the same iterations.
"""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tribocosim.components.stripdraw import StripDrawModel, StripDrawParameters, galpha, kernels, make_friction_law

pytest.importorskip("numba")


def monolithic_step(dt, U, V, A, Up, contact, fprev, ov, m, ke, ks, wT, tmax, vg, am, af, beta, gamma, rtol):
    """Newton on Pi over all free nodes 0..N-1 (dense solves, Armijo line search), from u = U + dt vg."""
    n = U.size
    N = n - 1
    inside = ov > 0
    Upn = np.where(inside & (contact == 0), U, Up)
    cm = (1.0 - am) / (beta * dt * dt)
    upred = U + dt * V + dt * dt * (0.5 - beta) * A
    u = U + dt * vg
    u0 = u.copy()
    lin = am * m[:N] * A[:N] + af * fprev[:N]
    K = np.zeros((n, n))
    for e in range(N):
        K[e:e + 2, e:e + 2] += ke * np.array([[1.0, -1.0], [-1.0, 1.0]])

    def evaluate(u):
        T, slipping, phi = kernels.interface_law(u - Upn, ks, tmax)
        T, phi = T * inside, phi * inside
        f = K @ u + T * wT * ov
        r = cm * m[:N] * (u[:N] - upred[:N]) + lin + (1 - af) * f[:N]
        pot = (np.sum(0.5 * cm * m[:N] * (u[:N] - upred[:N]) ** 2 + lin * (u[:N] - u0[:N]))
               + (1 - af) * (0.5 * u @ K @ u + np.sum((wT * ov * phi)[:N])))
        return pot, r, T, slipping, f

    pot, r, T, slipping, f = evaluate(u)
    fscale = ke * abs(dt * vg) + np.sum(tmax * wT * ov)
    for _ in range(200):
        if np.abs(r).max() <= 1e-3 * rtol * fscale:  # tighter than the kernel's test: the reference answer
            break
        H = cm * np.diag(m[:N]) + (1 - af) * (K[:N, :N] + np.diag(ks * wT * ov[:N] * (inside[:N] & ~slipping[:N])))
        du = np.linalg.solve(H, -r)
        alpha = 1.0
        while True:
            ut = u.copy()
            ut[:N] += alpha * du
            pot_t, r_t, T_t, s_t, f_t = evaluate(ut)
            if pot_t <= pot + 1e-4 * alpha * (r @ du) or alpha < 1e-12:
                break
            alpha *= 0.5
        u, pot, r, T, slipping, f = ut, pot_t, r_t, T_t, s_t, f_t
    anew = (u[:N] - upred[:N]) / (beta * dt * dt)
    V[:N] = V[:N] + dt * ((1 - gamma) * A[:N] + gamma * anew)
    A[:N] = anew
    V[N], A[N] = vg, 0.0
    U[:] = u
    fprev[:] = f
    Up[inside] = Upn[inside]
    Up[inside & slipping] = u[inside & slipping] - T[inside & slipping] / ks
    contact[:] = inside
    return float(np.sum(T * wT * ov)), float(f[N])


def _sliding_state(n_elements=90, steps=6):
    """A model mid-draw, with sticking and slipping nodes and nodes about to enter the pad."""
    p = StripDrawParameters(friction_model="closed_form", draw_length=0.01, n_elements=n_elements)
    model = StripDrawModel(p, make_friction_law(p))
    fn = 1e7 * 0.035**2
    for k in range(steps):
        model.step(1e-3, {"normal_force": fn, "grip_velocity": 0.08 * (k + 0.5) / 6})
    mu, _ = model.law.mu(1e7, model.slip_rate, model.beta)
    return model, mu * 1e7


def _args(model, st, ov, tmax, vg, dt):
    m, p = model.mesh, model.params
    return (dt, st["U"], st["V"], st["A"], st["Up"], st["contact"], st["fprev"], ov, m.mass, m.element_stiffness,
            p.shear_stiffness, p.tool_width, tmax, vg, model._am, model._af, model._beta_nm, model._gamma)


def _chain(model, dt):
    cm = (1.0 - model._am) / (model._beta_nm * dt * dt)
    return galpha.chain_factors(cm, model.mesh.mass, (1.0 - model._af) * model.mesh.element_stiffness)


def _assert_same_state(s1, s2, res1, res2, model, rtol, fscale=0.0):
    """Friction force, reaction and the state arrays agree to rtol; forces also within rtol of the largest
    nodal force and within 1e-10 of ``fscale``, the kernels' force scale: both solvers stop at a residual of
    1e-10 fscale (a reaction near 0 is a small difference of element forces)."""
    m = model.mesh
    force_scale = np.abs(s2["fprev"]).max()
    atol = max(rtol * force_scale, 1e-10 * fscale)
    assert_allclose(res1, res2, rtol=rtol, atol=atol)
    for k, tol in (("U", 1e-15), ("V", 1e-12), ("Up", 1e-15), ("fprev", atol), ("A", atol / m.mass.min())):
        assert_allclose(s1[k], s2[k], rtol=rtol, atol=tol, err_msg=k)
    assert np.array_equal(s1["contact"], s2["contact"])


def _exact_end_response(cm, m, c, first_single):
    """[H^-1]_{k,k} at the chain's end node k attached to the window, in exact rational arithmetic (no
    rounding, no cancellation: the diagonal cm m_i + 2c holds the small mass term exactly). H is the chain's
    tridiagonal (1 - af) K + cm M; ``first_single``: the chain's far end is free (a tail starting at node 0,
    one element there), else it is fixed (the grip side ends at the grip node). The chain is ordered from its
    far end to the node next to the window. Forward elimination gives the last pivot p; [H^-1]_{k,k} = 1 / p."""
    from fractions import Fraction

    C = Fraction(float(c))
    pivot = None
    for j, mass in enumerate(m):
        diag = Fraction(float(cm)) * Fraction(float(mass)) + (C if (j == 0 and first_single) else 2 * C)
        pivot = diag if pivot is None else diag - C * C / pivot
    return 1 / pivot, C


def test_chain_factors_are_the_schur_complements_of_the_free_chains():
    """K_t = q e of the last tail node is the stiffness a tail 0..lo-1 in equilibrium puts on node lo,
    c - c^2 [H_tail^-1]_{lo-1, lo-1}, computed exactly; likewise K_g for the grip side (node N fixed)."""
    rng = np.random.default_rng(3)
    n, ke, af = 23, 3.0e9, 1 / 3
    m = np.full(n, 2e-4) * rng.uniform(0.5, 1.5, n)
    cm, c = 2.7e6, (1 - af) * ke
    ch = galpha.chain_factors(cm, m, c)
    N = n - 1
    for lo in (1, 5, 17):  # tail 0..lo-1
        inv, C = _exact_end_response(cm, m[:lo], c, first_single=True)
        assert ch[1, lo - 1] * ch[0, lo - 1] == pytest.approx(float(C - C * C * inv), rel=1e-13)
    for hi in (2, 9, N - 2):  # grip side hi+1..N-1, eliminated from N-1 towards hi
        inv, C = _exact_end_response(cm, m[hi + 1:N][::-1], c, first_single=False)
        assert ch[4, hi + 1] * ch[3, hi + 1] == pytest.approx(float(C - C * C * inv), rel=1e-13)


@pytest.mark.parametrize("case", ["sliding", "entering", "pad_at_grip", "no_contact", "long_step"])
def test_condensed_step_reaches_the_monolithic_minimiser(case):
    model, tmax = _sliding_state()
    m = model.mesh
    ov = kernels.overlap_numpy(m.X, model.U, 0.5 * m.element_length, m.window_lo, m.window_hi)
    dt, vg = 2e-3, 0.085
    if case == "entering":
        ov[np.flatnonzero(ov > 0)[0] - 1] = 0.3 * m.element_length
    elif case == "pad_at_grip":  # the pad over the last nodes, the grip node included
        ov = np.zeros_like(ov)
        ov[-12:] = m.element_length
        tmax = np.full_like(ov, 1e7 * 0.12)
    elif case == "no_contact":
        ov = np.zeros_like(ov)
    elif case == "long_step":
        dt, vg = 0.05, -0.3
    runs = []
    for kernel in ("condensed", "monolithic"):
        st = model.get_state()
        if kernel == "condensed":
            res = galpha.galpha_loop(*_args(model, st, ov, tmax, vg, dt), 60, 1e-10, _chain(model, dt))
            assert res[0] >= (0 if case == "no_contact" else 1)
            res = res[1:]
        else:
            res = monolithic_step(*_args(model, st, ov, tmax, vg, dt), 1e-10)
        runs.append((res, st))
    (res1, s1), (res2, s2) = runs
    fscale = m.element_stiffness * abs(dt * vg) + np.sum(tmax * model.params.tool_width * ov)
    _assert_same_state(s1, s2, res1, res2, model, 1e-9, fscale)


def test_loop_form_and_numpy_form_take_the_same_iterations():
    model, tmax = _sliding_state()
    m = model.mesh
    ov = kernels.overlap_numpy(m.X, model.U, 0.5 * m.element_length, m.window_lo, m.window_hi)
    ov[np.flatnonzero(ov > 0)[0] - 1] = 0.3 * m.element_length
    runs = []
    for kernel in (galpha.galpha_loop, galpha.galpha_numpy):
        st = model.get_state()
        runs.append((kernel(*_args(model, st, ov, tmax, 0.085, 2e-3), 60, 1e-10, _chain(model, 2e-3)), st))
    (res1, s1), (res2, s2) = runs
    assert res1[0] > 0 and res1[0] == res2[0], "same number of Newton iterations"
    _assert_same_state(s1, s2, res1[1:], res2[1:], model, 1e-12)


def test_a_step_that_does_not_converge_changes_nothing():
    model, tmax = _sliding_state()
    m = model.mesh
    ov = kernels.overlap_numpy(m.X, model.U, 0.5 * m.element_length, m.window_lo, m.window_hi)
    for kernel in (galpha.galpha_loop, galpha.galpha_numpy):
        st = model.get_state()
        before = {k: v.copy() for k, v in st.items() if isinstance(v, np.ndarray)}
        assert kernel(*_args(model, st, ov, tmax, 0.085, 2e-3), 0, 1e-10, _chain(model, 2e-3))[0] == -1
        for k, v in before.items():
            assert np.array_equal(st[k], v), k


def test_a_whole_draw_matches_the_monolithic_solver():
    """The model's outputs over a short draw (ramps, steady sliding) with the condensed kernel against the
    same model stepped with the monolithic solve: the same answers to 1e-9."""
    from tribocosim.components.stripdraw import model as sdmodel

    p = StripDrawParameters(friction_model="closed_form", alpha_b=63.64, draw_length=0.01, n_elements=80)
    fn = 1e7 * 0.035**2
    a, b = StripDrawModel(p, make_friction_law(p)), StripDrawModel(p, make_friction_law(p))

    def mono(dt, U, V, A, Up, contact, fprev, ov, m, ke, ks, wT, tmax, vg, am, af, beta, gamma, max_iter, rtol, chain):
        return (1,) + monolithic_step(dt, U, V, A, Up, contact, fprev, ov, m, ke, ks, wT, tmax, vg, am, af, beta,
                                      gamma, rtol)

    out_a, out_b = [], []
    for k in range(60):
        inputs = {"normal_force": fn * min(1.0, (k + 1) / 20), "grip_velocity": 0.08 * min(1.0, (k + 0.5) / 10)}
        out_a.append(a.step(1e-3, inputs)["pull_force"])
        kernel = sdmodel.galpha.galpha_kernel
        try:
            sdmodel.galpha.galpha_kernel = mono
            out_b.append(b.step(1e-3, inputs)["pull_force"])
        finally:
            sdmodel.galpha.galpha_kernel = kernel
    assert_allclose(out_a, out_b, rtol=1e-9)
    assert_allclose(a.U, b.U, rtol=0, atol=1e-15)


def test_pull_force_is_smooth_in_the_inputs_at_the_rounding_level():
    """Late in a draw (U ~ 0.1 m) and without friction, the pull force is a small difference of element
    forces; computed from the updated displacements it would jump by ~k_e ulp(U) ~ 1e-7 N between inputs one
    ulp apart, which stalls a co-simulation master's fixed point at 1e-8 relative tolerance (measured on the
    stability report's 0.99 p_crit row before the extensions were taken from the increments). Stepping the same
    state with grip velocities whose grip displacements are a few ulps of U apart, the pull force must follow a straight line to 1e-11 N."""
    p = StripDrawParameters(friction_model="constant", mu_const=0.0, draw_length=0.12, n_elements=120)
    model = StripDrawModel(p, make_friction_law(p))
    fn = 1e7 * 0.035**2
    for k in range(13):
        model.step(0.1, {"normal_force": fn, "grip_velocity": 0.08 * min(1.0, (k + 1) / 3)})
    assert model.U[-1] > 0.09
    saved = model.get_state()
    dv = np.arange(-8, 9) * 1e-14  # the grip moves by dt dv: up to ~6 ulps of U
    pulls = []
    for d in dv:
        model.set_state(saved)
        pulls.append(model.step(1e-3, {"normal_force": fn, "grip_velocity": 0.08 + d})["pull_force"])
    pulls = np.array(pulls)
    line = np.polyval(np.polyfit(dv, pulls, 1), dv)
    assert np.abs(pulls - line).max() < 1e-10, np.abs(pulls - line).max()
