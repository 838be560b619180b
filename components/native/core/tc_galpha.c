/* One generalized-alpha step of the bar, with the free parts of the bar condensed onto the pad.
 *
 * The step (Chung & Hulbert 1993, doi:10.1115/1.2900803; force-averaged form, docs/model.md section 2)
 * minimises the convex incremental potential of the free nodes 0..N-1 (node N is the grip, moved with the
 * grip velocity):
 *
 *     Pi(u) = sum_i [ cm m_i / 2 (u_i - u~_i)^2 + lin_i (u_i - u0_i) ]
 *           + (1 - af) [ 1/2 u^T K u + sum_i w_T ov_i phi_i(u_i - Up_i) ],
 *
 * with cm = (1 - am) / (b dt^2), the Newmark predictor u~ = u_n + dt v_n + dt^2 (1/2 - b) a_n,
 * lin_i = am m_i a_n,i + af f_n,i, u0 = u_n + dt V0 (the strip following the grip rigidly: the initial
 * guess) and phi the potential of the return-mapped interface spring (interface_law below; Eq. 4-5).
 *
 * Only the nodes under the pad (ov_i > 0) make Pi non-quadratic. The bar outside the pad, the *tail*
 * (nodes 0..lo-1, not yet drawn in) and the *grip side* (hi+1..N-1), is a linear chain, so it is solved
 * exactly for any position of the pad's end nodes (static condensation, a Schur complement): Gaussian
 * elimination of the tail from node 0 towards lo and of the grip side from N-1 towards hi. What the
 * elimination leaves on an end node is a spring of stiffness K_t (K_g) and a force s_t (s_g), so that
 * the potential of the window [lo, hi],
 *
 *     Pi_W(d) = sum_{i in W} [ cm m_i / 2 (x_i + d_i)^2 + lin_i d_i + (1 - af) w_T ov_i phi_i(z_i + d_i) ]
 *             + (1 - af) k_e / 2 sum_{e = lo}^{hi-1} (dU_e + d_{e+1} - d_e)^2
 *             + s_t d_lo + K_t d_lo^2 / 2 + s_g d_hi + K_g d_hi^2 / 2,
 *
 * is Pi minimised over the free chains (up to a constant). The unknowns are the increments d = u - u0,
 * with x_i = u0_i - u~_i = dt V0 - dt v_i - dt^2 (1/2 - b) a_i, z_i = u0_i - Up_i and dU_e = U_e+1 - U_e:
 * no difference of two displacements of the size of the draw is ever taken. The window is solved by
 * Newton's method on the stick/slip set (tangent k_s w_T ov_i on sticking nodes), globalised by a
 * line search on Pi_W; it is converged when a full Newton step lands on the set it was built from (the problem is
 * linear on that set, so that step was exact: it is taken without evaluating Pi_W), or when the window's residual is
 * below ``rtol`` times the force scale (friction capacity + grip pull). A step that lands on another set crosses a
 * kink of the interface law: it is taken when it descends by the Armijo condition, else the exact minimiser along
 * it (Pi_W is piecewise quadratic along the step, exact_step). The chains are then
 * back-substituted and every free node gets its Newmark update.
 *
 * The elimination factors depend on the step length only (tc_sd_chain_factors; the model keeps them per
 * step length). Written with c = (1 - af) k_e and the excess e_i = d'_i - c of the eliminated diagonal d'_i
 * over c, the recurrences have no cancellation:
 *
 *     tail:       e_0 = cm m_0,              e_i = cm m_i + q_{i-1} e_{i-1},   q_i = c / (c + e_i),
 *     grip side:  g_{N-1} = cm m_{N-1} + c,  g_j = cm m_j + q'_{j+1} g_{j+1}, q'_j = c / (c + g_j),
 *
 * and the end springs are K_t = q_{lo-1} e_{lo-1}, K_g = q'_{hi+1} g_{hi+1} (c with no grip side: the
 * element to the grip node itself). With rho the eliminated right-hand sides (the negative residuals at
 * d = 0, rho_i += q_{i-1} rho_{i-1} along the tail), the back-substitution is d_i = rho_i / d'_i + q_i d_{i+1}.
 * The nodes' residuals at d = 0, the terms rho_i / d'_i, their Newmark updates and the elements' forces have no
 * recurrence and are formed in passes of their own (in vector lanes: two doubles, or four where the processor runs
 * AVX, tc_step_kernels_avx.c). Each recurrence is a chain of dependent operations, so a long one is swept as two
 * halves side by side whose latencies overlap (the second half from zero, then corrected by the products of its q
 * times the first half's last value; the results differ from one sweep by round-off only), and the tail's and the grip
 * side's side by side too (recurrences()).
 *
 * The cost of a step is one pass over the free nodes plus Newton on the window (~24 of the default 151
 * nodes). tests/components/test_stripdraw_verification.py holds the step to its convergence order on the linear
 * bar and to the explicit scheme.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "tc_galpha.h"
#include "tc_kernels.h"

#ifndef TC_VARIANT /* the baseline; tc_step_kernels_avx.c compiles this file again, naming its step tc_sd_galpha_avx */
#define TC_VARIANT(name) name
#define TC_GALPHA_BASELINE
#endif

/* the interface law (Eq. 4-5) for one node: traction, slipping flag, and the potential phi of the return-mapped
 * spring (k_s x^2 / 2 sticking, T_max |x| - T_max^2 / (2 k_s) slipping; its derivative is T) */
static double interface_law(double x, double ks, double tmax, int *slipping, double *phi) {
    const double trial = ks * x;
    if (trial > tmax) {
        *slipping = 1;
        *phi = tmax * fabs(x) - 0.5 * tmax * tmax / ks;
        return tmax;
    }
    if (trial < -tmax) {
        *slipping = 1;
        *phi = tmax * fabs(x) - 0.5 * tmax * tmax / ks;
        return -tmax;
    }
    *slipping = 0;
    *phi = 0.5 * ks * x * x;
    return trial;
}

#ifdef TC_GALPHA_BASELINE /* defined once, in the baseline's translation unit */
void tc_sd_chain_factors(size_t n, double cm, double am, const double *m, double c, double *chain) {
    const size_t N = n - 1;
    double *et = chain, *qt = chain + n, *it = chain + 2 * n, *eg = chain + 3 * n, *qg = chain + 4 * n,
           *ig = chain + 5 * n, *cmm = chain + 6 * n, *amm = chain + 7 * n;
    memset(chain, 0, TC_SD_CHAIN(n) * sizeof *chain);
    for (size_t i = 0; i < n; ++i) {
        cmm[i] = cm * m[i];
        amm[i] = am * m[i];
    }
    for (size_t i = 0; i + 1 < N; ++i) { /* the tail never reaches node N-1 */
        const double e = i == 0 ? cm * m[i] : cm * m[i] + qt[i - 1] * et[i - 1];
        et[i] = e;
        it[i] = 1.0 / (c + e);
        qt[i] = c * it[i];
    }
    for (size_t j = N - 1; j >= 1 && j < N; --j) { /* the grip side never reaches node 0 */
        const double g = j == N - 1 ? cm * m[j] + c : cm * m[j] + qg[j + 1] * eg[j + 1];
        eg[j] = g;
        ig[j] = 1.0 / (c + g);
        qg[j] = c * ig[j];
    }
}
#endif

/* the window: the nodes with ov > 0 and the free nodes between them, free nodes only (<= N-1); node N-1 alone
 * when no free node touches the pad. The nodes with ov > 0 lie in [first, last] (first > last: anywhere). */
static void window(size_t n, const double *ov, size_t first, size_t last, size_t *lo_out, size_t *hi_out) {
    const size_t N = n - 1;
    size_t lo, hi;
    int found;
    if (first <= last && last < n) {
        found = tc_sd_positive_range(last + 1 - first, ov + first, &lo, &hi);
        lo += first;
        hi += first;
    } else {
        found = tc_sd_positive_range(n, ov, &lo, &hi);
    }
    if (!found || lo > N - 1) {
        *lo_out = *hi_out = N - 1;
        return;
    }
    *lo_out = lo;
    *hi_out = hi < N - 1 ? hi : N - 1;
}

/* the window's inputs and its boundary springs */
typedef struct {
    size_t lo, hi;
    const double *x, *z, *dU, *lin, *ov, *m, *tmax;
    double ke, ks, wT, af, cm, st, kt, sg, kg;
} window_problem;

/* Pi_W(d), the tractions T and stick/slip states (0 off the pad, 1 stick, 2/3 slip +/-) of the window */
static double window_potential(const window_problem *w, const double *d, double *T, signed char *state) {
    const size_t lo = w->lo, hi = w->hi;
    const double *x = w->x, *z = w->z, *dU = w->dU, *lin = w->lin, *ov = w->ov, *m = w->m, *tmax = w->tmax;
    const double ks = w->ks, cw = (1.0 - w->af) * w->wT, ce = (1.0 - w->af) * 0.5 * w->ke, hcm = 0.5 * w->cm;
    double pot = 0.0;
    for (size_t i = lo; i <= hi; ++i) {
        T[i] = 0.0;
        state[i] = 0;
        if (ov[i] > 0.0) {
            const double xs = z[i] + d[i];
            int slipping;
            double phi;
            T[i] = interface_law(xs, ks, tmax[i], &slipping, &phi);
            state[i] = (signed char)(!slipping ? 1 : (xs > 0 ? 2 : 3));
            pot += cw * ov[i] * phi;
        }
    }
    for (size_t e = lo; e < hi; ++e) {
        const double s = dU[e] + (d[e + 1] - d[e]);
        pot += ce * s * s;
    }
    for (size_t i = lo; i <= hi; ++i) {
        const double y = x[i] + d[i];
        pot += hcm * m[i] * y * y + lin[i] * d[i];
    }
    pot += (w->st + 0.5 * w->kt * d[lo]) * d[lo];
    pot += (w->sg + 0.5 * w->kg * d[hi]) * d[hi];
    return pot;
}

/* the tractions T (tc_sd_traction) and stick/slip states of the window at d, as window_potential sets them (without
 * the potential) */
static void window_tractions(const window_problem *w, const double *d, double *T, signed char *state) {
    const double *z = w->z, *ov = w->ov, *tmax = w->tmax, ks = w->ks;
    for (size_t i = w->lo; i <= w->hi; ++i) {
        const double xs = z[i] + d[i];
        int slipping;
        const double t = tc_sd_traction(xs, ks, tmax[i], &slipping);
        const int on = ov[i] > 0.0;
        T[i] = on ? t : 0.0;
        state[i] = (signed char)(!on ? 0 : (!slipping ? 1 : (xs > 0 ? 2 : 3)));
    }
}

/* the window residual r = dPi_W/dd at d with the tractions T of window_potential, and max |r|; f: work (the elements'
 * forces k_e s_e, s_e = dU_e + d_e+1 - d_e the extensions of the window's elements [lo, hi)) */
static double window_residual(const window_problem *w, const double *d, const double *T, double *f, double *r) {
    const size_t lo = w->lo, hi = w->hi;
    const double *x = w->x, *dU = w->dU, *lin = w->lin, *ov = w->ov, *m = w->m;
    const double wT = w->wT, ke = w->ke, cm = w->cm, caf = 1.0 - w->af;
    for (size_t e = lo; e < hi; ++e) f[e] = ke * (dU[e] + (d[e + 1] - d[e]));
    /* the nodal force (T_i w_T ov_i + k_e s_i-1) - k_e s_i, without the terms of elements outside the window */
#define RESIDUAL(i, fi) (cm * m[i] * (x[i] + d[i]) + lin[i] + caf * (fi))
    if (lo == hi) {
        r[lo] = RESIDUAL(lo, T[lo] * wT * ov[lo]);
    } else {
        r[lo] = RESIDUAL(lo, T[lo] * wT * ov[lo] - f[lo]);
        for (size_t i = lo + 1; i < hi; ++i) r[i] = RESIDUAL(i, (T[i] * wT * ov[i] + f[i - 1]) - f[i]);
        r[hi] = RESIDUAL(hi, T[hi] * wT * ov[hi] + f[hi - 1]);
    }
#undef RESIDUAL
    r[lo] += w->st + w->kt * d[lo];
    r[hi] += w->sg + w->kg * d[hi];
    double rm = 0.0;
    for (size_t i = lo; i <= hi; ++i) rm = fabs(r[i]) > rm ? fabs(r[i]) : rm;
    return rm;
}

/* A window of this many nodes or more is eliminated from both ends at once (newton_step) */
#define TWIST_NODES 8

/* The Newton step s of the window on its stick/slip set (state), H s = -r: H is tridiagonal with
 *
 *     H_ii = cm m_i + (1 - af) (k_e e_i + k_s w_T ov_i [i sticks])  (+ K_t at lo, + K_g at hi),
 *     H_i,i+1 = H_i+1,i = o = -(1 - af) k_e,
 *
 * e_i the number of window elements at node i. Gaussian elimination without pivoting (H is symmetric positive definite
 * and diagonally dominant) from the top row down (the Thomas algorithm, as tc_thomas does it): c_0 = o / H_00,
 * g_0 = -r_0 / H_00, then m_i = H_ii - o c_i-1, c_i = o / m_i, g_i = (-r_i - o g_i-1) / m_i, and s_i = g_i - c_i s_i+1
 * backwards. Each row's elimination waits for the one before (a division among them), so a window of TWIST_NODES or
 * more is eliminated from both ends at once (a twisted factorization): the rows above the middle row p from the top
 * down as above, the rows below it from the bottom up (the same recurrences mirrored, into c_i and g_i of those rows),
 * the middle row solved from both, (H_pp - o c_p-1 - o c_p+1) s_p = -r_p - o g_p-1 - o g_p+1, then s substituted
 * outwards: s_i = g_i - c_i s_i+1 above p, s_i = g_i - c_i s_i-1 below. c and g: work of nw values each. */
static void newton_step(const window_problem *w, const signed char *state, const double *r, double *step, double *c,
                        double *g) {
    const size_t lo = w->lo, hi = w->hi, nw = hi - lo + 1;
    const double *ov = w->ov, *m = w->m;
    const double ks = w->ks, wT = w->wT, ke = w->ke, cm = w->cm, af = w->af, off = -(1.0 - af) * ke;
    /* H_ii without K_t and K_g, with ek = k_e e_i: k_e at an end of a window of two nodes or more, 2 k_e inside */
#define DIAGONAL(i, ek) (cm * m[i] + (1.0 - af) * ((ek) + (state[i] == 1 ? ks * wT * ov[i] : 0.0)))
    const double ke_end = (nw > 1 ? 1.0 : 0.0) * ke, ke_mid = 2.0 * ke;
    double h0 = DIAGONAL(lo, ke_end) + w->kt;
    if (nw == 1) h0 += w->kg;
    double cp = off / h0, gp = -r[lo] / h0; /* the recurrences' carries */
    c[0] = cp;
    g[0] = gp;
    if (nw < TWIST_NODES) {
        for (size_t k = 1; k < nw; ++k) {
            const size_t i = lo + k;
            const double h = k < nw - 1 ? DIAGONAL(i, ke_mid) : DIAGONAL(i, ke_end) + w->kg;
            const double mk = h - off * cp;
            c[k] = cp = off / mk;
            g[k] = gp = (-r[i] - off * gp) / mk;
        }
        double sp = g[nw - 1];
        step[nw - 1] = sp;
        for (size_t k = nw - 1; k-- > 0;) step[k] = sp = g[k] - c[k] * sp;
        return;
    }
    const size_t p = nw / 2, below = nw - 1 - p; /* the middle row; the rows below it (p or p - 1 of them) */
    const double hb = DIAGONAL(hi, ke_end) + w->kg;
    double cb = off / hb, gb = -r[hi] / hb; /* the bottom-up carries */
    c[nw - 1] = cb;
    g[nw - 1] = gb;
    for (size_t t = 1; t < p; ++t) { /* row t from the top and row nw - 1 - t from the bottom, side by side */
        const size_t k = t, i = lo + k, kb = nw - 1 - t, ib = lo + kb;
        const double mk = DIAGONAL(i, ke_mid) - off * cp;
        c[k] = cp = off / mk;
        g[k] = gp = (-r[i] - off * gp) / mk;
        if (t < below) {
            const double mb = DIAGONAL(ib, ke_mid) - off * cb;
            c[kb] = cb = off / mb;
            g[kb] = gb = (-r[ib] - off * gb) / mb;
        }
    }
    const size_t ip = lo + p;
    double su = (-r[ip] - off * gp - off * gb) / (DIAGONAL(ip, ke_mid) - off * cp - off * cb), sd = su;
#undef DIAGONAL
    step[p] = su;
    for (size_t t = 1; t <= p; ++t) { /* row p - t upwards and row p + t downwards, side by side */
        step[p - t] = su = g[p - t] - c[p - t] * su;
        if (t <= below) step[p + t] = sd = g[p + t] - c[p + t] * sd;
    }
}

/* the derivative of Pi_W along the step s at d + alpha s: sum_i s_i r_i(d + alpha s) (dtr, T, state, f, r: work) */
static double slope_at(const window_problem *w, const double *d, const double *s, double alpha, double *dtr, double *T,
                       signed char *state, double *f, double *r) {
    const size_t lo = w->lo, hi = w->hi;
    for (size_t i = lo; i <= hi; ++i) dtr[i] = d[i] + alpha * s[i - lo];
    (void)window_potential(w, dtr, T, state);
    (void)window_residual(w, dtr, T, f, r);
    double g = 0.0;
    for (size_t i = lo; i <= hi; ++i) g += s[i - lo] * r[i];
    return g;
}

static int compare_doubles(const void *a, const void *b) {
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The exact line search: the alpha in (0, 1] that minimises Pi_W(d + alpha s) for a descent direction s (slope0 =
 * its derivative at alpha = 0, < 0). Along s, Pi_W is convex and piecewise quadratic: its derivative is piecewise
 * linear and non-decreasing in alpha, with kinks where a node under the pad changes between stick and slip
 * (x_i = z_i + d_i + alpha s_i = +-T_max,i / k_s). alpha = 1 when the derivative is still <= 0 there; else the kinks
 * in (0, 1) are sorted (into kinks: 2 nw doubles), the two neighbours between which the derivative turns positive
 * are found by bisection, and the derivative, linear between them, is set to zero. With a stiff interface (k_s w_T
 * l_e many times k_e) a backtracking search stalls at the first node that changes state; this one steps across
 * every change the direction implies. */
static double exact_step(const window_problem *w, const double *d, const double *s, double slope0, double *kinks,
                         double *dtr, double *T, signed char *state, double *f, double *r) {
    const double g1 = slope_at(w, d, s, 1.0, dtr, T, state, f, r);
    if (!(g1 > 0.0)) return 1.0;
    size_t m = 0;
    for (size_t i = w->lo; i <= w->hi; ++i) {
        const double si = s[i - w->lo];
        if (!(w->ov[i] > 0.0) || si == 0.0) continue;
        const double x0 = w->z[i] + d[i], bound = w->tmax[i] / w->ks;
        const double a[2] = {(bound - x0) / si, (-bound - x0) / si};
        for (int k = 0; k < 2; ++k)
            if (a[k] > 0.0 && a[k] < 1.0) kinks[m++] = a[k];
    }
    qsort(kinks, m, sizeof *kinks, compare_doubles);
    /* points p_0 = 0, p_1..p_m = the kinks, p_m+1 = 1; the derivative is <= 0 at p_lo and > 0 at p_hi */
    size_t plo = 0, phi = m + 1;
    double glo = slope0, ghi = g1;
    while (phi - plo > 1) {
        const size_t mid = plo + (phi - plo) / 2;
        const double g = slope_at(w, d, s, kinks[mid - 1], dtr, T, state, f, r);
        if (g > 0.0) {
            phi = mid;
            ghi = g;
        } else {
            plo = mid;
            glo = g;
        }
    }
    const double alo = plo == 0 ? 0.0 : kinks[plo - 1], ahi = phi == m + 1 ? 1.0 : kinks[phi - 1];
    const double alpha = alo + (ahi - alo) * (-glo / (ghi - glo));
    return alpha > alo ? (alpha < ahi ? alpha : ahi) : alo;
}

/* x_i = u0_i - u~_i = dt V0 - dt v_i - dt^2 (1/2 - b) a_i of a node (shift = dt V0, cA = dt^2 (1/2 - b)) */
static inline double predictor_gap(double shift, double dt, double cA, double v, double a) {
    return shift - dt * v - cA * a;
}

/* the residual at d = 0 of a free node outside the window, -(cm m_i x_i + am m_i a_i + af f_i + (1 - af)(kl - kr)),
 * with kl = k_e dU_i-1 (0 at node 0) and kr = k_e dU_i its elements' forces */
static inline double chain_residual(double cmm, double x, double amm, double a, double af, double f, double caf,
                                    double kl, double kr) {
    return -(cmm * x + (amm * a + af * f) + caf * (kl - kr));
}

/* x_i (predictor_gap) and the residual at d = 0 (into r0) of the free nodes [b, e), b >= 1:
 * no recurrence, so the loop runs in vector lanes */
static void chain_residuals(size_t b, size_t e, double shift, double dt, double cA, double ke, double af,
                            const double *restrict V, const double *restrict A, const double *restrict fprev,
                            const double *restrict dU, const double *restrict cmm, const double *restrict amm,
                            double *restrict x, double *restrict r0) {
    const double caf = 1.0 - af;
    for (size_t i = b; i < e; ++i) {
        const double xi = predictor_gap(shift, dt, cA, V[i], A[i]);
        r0[i] = chain_residual(cmm[i], xi, amm[i], A[i], af, fprev[i], caf, ke * dU[i - 1], ke * dU[i]);
        x[i] = xi;
    }
}

/* the window's x_i (predictor_gap), lin_i = am m_i a_i + af f_i, Up_i and d_i = 0 for the nodes [b, e) (in vector
 * lanes) */
static void window_inputs(size_t b, size_t e, double shift, double dt, double cA, double af, const double *restrict V,
                          const double *restrict A, const double *restrict fprev, const double *restrict amm,
                          const double *restrict Up, double *restrict x, double *restrict lin, double *restrict Upn,
                          double *restrict d) {
    for (size_t i = b; i < e; ++i) {
        x[i] = predictor_gap(shift, dt, cA, V[i], A[i]);
        lin[i] = amm[i] * A[i] + af * fprev[i];
        Upn[i] = Up[i];
        d[i] = 0.0;
    }
}

/* the Newmark update of the free nodes [0, N) from their increments d: a = (x + d) / (b dt^2),
 * v = v_n + dt ((1 - gamma) a_n + gamma a), u = u_n + dt V0 + d, from (U0, V0, A0) into (U, V, A), which may be the
 * same arrays (each node is read before it is written) */
static void newmark_update(size_t N, double dt, double bdt2, double gamma, double shift, const double *restrict x,
                           const double *restrict d, const double *U0, const double *V0, const double *A0, double *U,
                           double *V, double *A) {
    for (size_t i = 0; i < N; ++i) {
        const double anew = (x[i] + d[i]) / bdt2;
        const double vnew = V0[i] + dt * ((1.0 - gamma) * A0[i] + gamma * anew);
        const double unew = U0[i] + (shift + d[i]);
        V[i] = vnew;
        A[i] = anew;
        U[i] = unew;
    }
}

/* the elements' extensions at the new state, e_k = dU_k + (d_k+1 - d_k) (d_N = 0: the grip node's increment), into
 * dU, and their forces on the nodes, f_i = k_e e_i-1 - k_e e_i (-k_e e_0 at node 0, k_e e_N-1 at the grip node N) */
static void element_forces(size_t N, double ke, const double *restrict d, double *restrict dU,
                           double *restrict fprev) {
    for (size_t i = 0; i < N; ++i) dU[i] = dU[i] + (d[i + 1] - d[i]);
    fprev[0] = -ke * dU[0];
    for (size_t i = 1; i < N; ++i) fprev[i] = ke * dU[i - 1] - ke * dU[i];
    fprev[N] = ke * dU[N - 1];
}

/* Node i under the pad at the step's end: in contact, its plastic slip (Up = U - T / k_s where it slides, else as it
 * was), its nodal force the elements' and the contact force T w_T ov; returns the contact force */
static inline double in_contact(size_t i, size_t N, const signed char *state, const double *T, const double *U,
                                const double *Upn, const double *ov, double ks, double wT, double ke, const double *dU,
                                signed char *contact, double *Up, double *fprev) {
    contact[i] = 1;
    Up[i] = state[i] != 1 ? U[i] - T[i] / ks : Upn[i];
    const double fc = T[i] * wT * ov[i];
    double f_i = fc;
    if (i > 0) f_i += ke * dU[i - 1];
    if (i < N) f_i -= ke * dU[i];
    fprev[i] = f_i;
    return fc;
}

/* y += c p over n values (in vector lanes) */
static void add_scaled(size_t n, double *restrict y, const double *restrict p, double c) {
    for (size_t j = 0; j < n; ++j) y[j] += p[j] * c;
}

/* A run shorter than this is swept as one recurrence (splitting it would save less latency than it costs) */
#define SPLIT_RUN 24

/* The linear recurrence y_k = a_k + q_k y_prev over the L nodes k = at, at + s, ... (s = +1 or -1), with
 * q_k = q[k + qoff] and y_prev = carry before the first, into y (which may be a): a run.
 * A run of SPLIT_RUN nodes or more is swept as two halves side by side, so that their latencies overlap: the first
 * from the carry, the second from y_prev = 0 with the running products P of its q (into work, L / 2 + 1 doubles), then
 * corrected by P times the first half's last value (the recurrence is linear: its solution from a start value is the
 * solution from 0 plus the start value carried by the products of q). */
typedef struct {
    size_t L, h;                     /* its nodes; the first half's (a split run) */
    const double *a1, *q1, *a2, *q2; /* a and q at each half's first node */
    double *y1, *y2, *P;             /* y at each half's first node; P at the second half's first node */
    double *work;                    /* P's first value in memory */
    ptrdiff_t s;
    double carry;
} run;

/* a run of L nodes set up for its sweep */
static run make_run(size_t L, ptrdiff_t at, ptrdiff_t s, ptrdiff_t qoff, const double *a, const double *q, double carry,
                    double *y, double *work) {
    if (L == 0) return (run){0, 0, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL, s, carry}; /* no pointer into y */
    const size_t h = L / 2, L2 = L - h;
    const ptrdiff_t at2 = at + (ptrdiff_t)h * s;
    /* P in the order of the second half's nodes in memory (backwards when s = -1), so that the correction is one
     * contiguous pass in vector lanes */
    return (run){L, h, a + at, q + at + qoff, a + at2, q + at2 + qoff, y + at, y + at2, work + (s > 0 ? 0 : L2 - 1),
                 work, s, carry};
}

/* a run shorter than SPLIT_RUN, swept as one recurrence */
static void whole_run(const run *r) {
    double carry = r->carry;
    for (size_t t = 0; t < r->L; ++t) {
        const ptrdiff_t k = (ptrdiff_t)t * r->s;
        r->y1[k] = carry = r->a1[k] + r->q1[k] * carry;
    }
}

/* node t of each half of a split run, from and into the carries c[0] (first half), c[1] (second), c[2] (P) */
static inline void split_node(const run *r, size_t t, double c[3]) {
    const ptrdiff_t k = (ptrdiff_t)t * r->s;
    r->y1[k] = c[0] = r->a1[k] + r->q1[k] * c[0];
    r->y2[k] = c[1] = r->a2[k] + r->q2[k] * c[1];
    r->P[k] = c[2] = c[2] * r->q2[k];
}

/* a split run's last node of an odd second half, then the second half corrected */
static void split_finish(const run *r, const double c[3]) {
    const size_t L2 = r->L - r->h;
    if (L2 > r->h) {
        const ptrdiff_t k = (ptrdiff_t)r->h * r->s;
        r->y2[k] = r->a2[k] + r->q2[k] * c[1];
        r->P[k] = c[2] * r->q2[k];
    }
    add_scaled(L2, r->s > 0 ? r->y2 : r->y2 - (L2 - 1), r->work, c[0]); /* from its first node in memory */
}

/* Two independent runs (the tail's and the grip side's; L = 0: none, their work apart) swept side by side while both
 * are split, so that the latencies of all four halves overlap; each run's operations are those it has alone, in its
 * order (the same numbers as one run after the other). */
static void recurrences(const run *u, const run *v) {
    const int su = u->L >= SPLIT_RUN, sv = v->L >= SPLIT_RUN;
    if (!su) whole_run(u);
    if (!sv) whole_run(v);
    const size_t hu = su ? u->h : 0, hv = sv ? v->h : 0, both = hu < hv ? hu : hv;
    double cu[3] = {u->carry, 0.0, 1.0}, cv[3] = {v->carry, 0.0, 1.0};
    size_t t = 0;
    for (; t < both; ++t) {
        split_node(u, t, cu);
        split_node(v, t, cv);
    }
    for (size_t tu = t; tu < hu; ++tu) split_node(u, tu, cu);
    for (size_t tv = t; tv < hv; ++tv) split_node(v, tv, cv);
    if (su) split_finish(u, cu);
    if (sv) split_finish(v, cv);
}

int TC_VARIANT(tc_sd_galpha)(size_t n, double dt, const tc_sd_bar *from, double *U, double *V, double *A, double *Up,
                             signed char *contact, double *fprev, const double *ov, size_t first, size_t last,
                             const double *m, double ke, double ks, double wT, const double *tmax, double vg, double am,
                             double af, double beta, double gamma, int max_iter, double rtol, const double *chain,
                             double *fric, double *reaction, double *work, signed char *iwork) {
    const size_t N = n - 1;
    const double c = (1.0 - af) * ke;
    const double *et = chain, *qt = chain + n, *it = chain + 2 * n, *eg = chain + 3 * n, *qg = chain + 4 * n,
                 *ig = chain + 5 * n, *cmm = chain + 6 * n, *amm = chain + 7 * n;
    double *x = work, *lin = work + n, *dU = work + 2 * n, *z = work + 3 * n, *d = work + 4 * n;
    double *rho = work + 5 * n, *Upn = work + 6 * n, *T = work + 7 * n, *f = work + 8 * n, *r = work + 9 * n;
    double *dtr = work + 10 * n, *step = work + 11 * n, *tw = work + 12 * n; /* tw: 2 n for the Newton step */
    signed char *state = iwork, *used = iwork + n;
    const double *U0 = from->U, *V0 = from->V, *A0 = from->A, *f0 = from->fprev;

    /* a step whose square underflows cannot be taken */
    if (beta * dt * dt == 0.0) return -2;
    size_t lo, hi;
    window(n, ov, first, last, &lo, &hi);
    const double cm = (1.0 - am) / (beta * dt * dt);
    const double cA = dt * dt * (0.5 - beta);
    const double shift = dt * vg;
    for (size_t i = 0; i < N; ++i) dU[i] = U0[i + 1] - U0[i];
    window_inputs(lo, hi + 1, shift, dt, cA, af, V0, A0, f0, amm, Up, x, lin, Upn, d);
    for (size_t i = lo; i <= hi; ++i) {
        if (ov[i] > 0.0) {
            if (contact[i] == 0) Upn[i] = U0[i]; /* nodes entering the pad start stress-free */
            z[i] = (U0[i] - Upn[i]) + shift;
        }
    }
    Upn[N] = Up[N];
    if (ov[N] > 0.0 && contact[N] == 0) Upn[N] = U0[N];
    /* eliminate the tail forwards and the grip side backwards: first every node's x and residual at d = 0 (into rho),
     * then the two recurrences */
    const size_t nt = lo, ng = N - 1 - hi;
    if (nt > 0) {
        x[0] = predictor_gap(shift, dt, cA, V0[0], A0[0]);
        rho[0] = chain_residual(cmm[0], x[0], amm[0], A0[0], af, f0[0], 1.0 - af, 0.0, ke * dU[0]);
        chain_residuals(1, nt, shift, dt, cA, ke, af, V0, A0, f0, dU, cmm, amm, x, rho);
    }
    chain_residuals(hi + 1, N, shift, dt, cA, ke, af, V0, A0, f0, dU, cmm, amm, x, rho);
    /* each chain's recurrence from its free end (rho_0 = r_0, rho_N-1 = r_N-1), as two halves side by side, the two
     * chains side by side too (step and tw: work until the Newton steps) */
    run tail = make_run(nt > 1 ? nt - 1 : 0, 1, 1, -1, rho, qt, rho[0], rho, step);
    run grip = make_run(ng > 1 ? ng - 1 : 0, (ptrdiff_t)(N - 2), -1, 1, rho, qg, rho[N - 1], rho, tw);
    recurrences(&tail, &grip);
    window_problem w = {lo, hi, x, z, dU, lin, ov, m, tmax, ke, ks, wT, af, cm, 0.0, 0.0, 0.0, 0.0};
    if (lo > 0) {
        w.st = c * dU[lo - 1] - qt[lo - 1] * rho[lo - 1];
        w.kt = qt[lo - 1] * et[lo - 1];
    }
    if (hi < N - 1) {
        w.sg = -c * dU[hi] - qg[hi + 1] * rho[hi + 1];
        w.kg = qg[hi + 1] * eg[hi + 1];
    } else { /* the element to the grip node, which does not move within the step */
        w.sg = -c * dU[hi];
        w.kg = c;
    }
    /* the back-substitution's own terms rho_i / d'_i (rho_i times the inverse diagonal), in vector lanes */
    for (size_t i = 0; i < nt; ++i) rho[i] *= it[i];
    for (size_t i = hi + 1; i < N; ++i) rho[i] *= ig[i];
    double fscale = ke * fabs(dt * vg) + 1e-300;
    for (size_t i = lo; i <= hi; ++i) fscale += tmax[i] * wT * ov[i]; /* ov = 0 outside: those terms are +0 */
    fscale += tmax[N] * wT * ov[N];

    const size_t nw = hi - lo + 1;
    window_tractions(&w, d, T, state);
    double rmax = window_residual(&w, d, T, f, r);
    int iters = 0;
    while (rmax > rtol * fscale) {
        if (iters >= max_iter) return -1;
        memcpy(used + lo, state + lo, nw);
        newton_step(&w, state, r, step, tw, tw + nw);
        double slope = 0.0;
        for (size_t i = 0; i < nw; ++i) slope += r[lo + i] * step[i];
        double alpha = 1.0;
        for (size_t i = 0; i < nw; ++i) dtr[lo + i] = d[lo + i] + step[i];
        window_tractions(&w, dtr, T, state);
        /* a full step that ends on the stick/slip set it was built from stays on it (each node's slip is linear along
         * the step, and each state is an interval of it), where Pi_W is the quadratic the step minimises: it is
         * exact, and it descends by half its slope. Else it crosses a kink of the interface law: taken when it
         * descends by the Armijo condition, else the minimiser along it. */
        const int same = memcmp(state + lo, used + lo, nw) == 0;
        if (!same) {
            const double pot = window_potential(&w, d, T, state);
            if (!(window_potential(&w, dtr, T, state) <= pot + 1e-4 * slope)) {
                alpha = exact_step(&w, d, step, slope, tw, dtr, T, state, f, r);
                for (size_t i = 0; i < nw; ++i) dtr[lo + i] = d[lo + i] + alpha * step[i];
                window_tractions(&w, dtr, T, state); /* at the point taken */
            }
        }
        for (size_t i = lo; i <= hi; ++i) d[i] = dtr[i];
        iters += 1;
        if (same) break; /* exact: the problem is linear on that set (its residual is not needed) */
        rmax = window_residual(&w, d, T, f, r);
    }
    /* back-substitute the chains (side by side, each as two halves, as above), then every free node's Newmark update */
    tail = make_run(nt, (ptrdiff_t)lo - 1, -1, 0, rho, qt, d[lo], d, step);
    grip = make_run(ng, (ptrdiff_t)hi + 1, 1, 0, rho, qg, d[hi], d, tw);
    recurrences(&tail, &grip);
    newmark_update(N, dt, beta * dt * dt, gamma, shift, x, d, U0, V0, A0, U, V, A);
    U[N] = U0[N] + shift;
    V[N] = vg;
    A[N] = 0.0;
    /* forces at the new state: friction (the window's tractions, and the grip node's if it is under the pad) */
    if (ov[N] > 0.0) {
        int slipping;
        double phi;
        T[N] = interface_law(U[N] - Upn[N], ks, tmax[N], &slipping, &phi);
        state[N] = (signed char)(!slipping ? 1 : 2);
    }
    /* the elements' extensions from the increments (not from the updated U, whose rounding to draw-sized values would
     * make the forces jump by ~k_e ulp(U) between nearby inputs), their forces at every node, then the friction of the
     * nodes under the pad (window and grip node) */
    d[N] = 0.0;
    element_forces(N, ke, d, dU, fprev);
    memset(contact, 0, n);
    double fr = 0.0;
    for (size_t i = lo; i <= hi; ++i) /* the window (hi < N always), then the grip node */
        if (ov[i] > 0.0) fr += in_contact(i, N, state, T, U, Upn, ov, ks, wT, ke, dU, contact, Up, fprev);
    if (ov[N] > 0.0) fr += in_contact(N, N, state, T, U, Upn, ov, ks, wT, ke, dU, contact, Up, fprev);
    *fric = fr;
    *reaction = fprev[N];
    return iters;
}
