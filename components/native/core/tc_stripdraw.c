/* The strip-draw model: 1D bar under a pad + interface law + debris transport + friction law.
 *
 * Physics (paper Sec. 3-4, App. B-C; docs/model.md sections 1-4):
 *
 * - bar, half model (one pad, one face): rho U_tt = E U_XX (Eq. 2), linear elements of length l_e, lumped
 *   masses m_i = rho A l_e (half at both ends), element stiffness k_e = E A / l_e (Eq. 29-30); the grip node
 *   N moves with the grip velocity V0. L_B = lead + draw_length + L_T + free_length, pad over
 *   [a, a + L_T] with a = lead + draw_length (lead = 5 mm);
 * - contact weight of node i: overlap ov_i of its tributary segment [x_i - l_e/2, x_i + l_e/2] (one-sided at the
 *   ends) at x_i = X_i + U_i with the pad, divided by l_e;
 * - interface (Eq. 4-5), elastic-perfectly-plastic Coulomb with return mapping: trial T = k_s (U_i - Up_i),
 *   |T| <= T_max,i = mu_i P with P = F_N / (L_T w_T); nodal force -T w_T ov_i; a node that enters the pad starts
 *   stress-free (Up_i := U_i); k_s = shear_stiffness_factor E / h_B;
 * - explicit integrator: central difference (App. B, Eq. 31-32) at cfl_safety x 2 / omega_max, with
 *   omega_max^2 <= (4 k_e + k_s w_T l_e) / m_1 (Gershgorin), sub-cycled inside each coupling interval;
 * - implicit integrator: generalized-alpha (Chung & Hulbert 1993), the bar outside the pad condensed onto it
 *   (tc_galpha.c states the equations); a step that does not converge in 60 Newton iterations is halved, up
 *   to 12 times;
 * - friction mu(P, v, beta) (Eq. 6-9, 23): tc_friction.h; v is the grip speed |V0| or each node's slip rate of
 *   the last interval (friction_velocity);
 * - debris (Eq. 12-14, 24, 37): Archard source, sink, upwind transport under the pad and the cap of beta, per
 *   coupling interval (tc_debris.c states them). A later pass starts from debris_carry_over times the beta field the
 *   earlier one left (beta_field).
 *
 * The model's members are in tc_stripdraw_model.h; its state image and the backup that makes a refused step leave it
 * unchanged are in tc_stripdraw_state.c.
 *
 * Coupling: a step is cut into pieces on the internal grid k * internal_step (grid_pieces; one piece, the step,
 * when internal_step = 0), and each piece of length d into n_int = max(1, ceil(d / h_max - 1e-9)) intervals with
 * h_max = window_courant l_e / |V0| (the largest |V0| of the piece's ends and middle); the inputs are
 * polynomials of the time into the step (held, or from their derivatives: tc_stripdraw_step_poly) and each
 * interval takes their means (input_mean); per interval mu is held on the nodes that can reach the pad (contact
 * nodes +- ceil(window_courant) + 1), the bar advanced, then beta updated from the nodal slip increments with
 * the contact weights averaged over the interval, and the interface made consistent with the state's weights and
 * limits (settle_interface: a node that entered the pad during the interval in contact, a node that slid at the
 * interval's limit at the state's).
 *
 * Outputs are functions of the state at the communication point (a vanishing step changes them by a vanishing
 * amount, down to the bar solve's tolerance: pull_force moves by ~2e-11 of itself on a step of any length, below
 * NEWTON_RTOL times the capacity it is relative to): pull_force = 2 x the axial force of the last element at the grip (Eq. 1: mu = pull_force / (2 F_N)),
 * friction_force F_S = sum over the nodes under the pad of T_i w_T ov_i with T_i = k_s (U_i - Up_i) limited to
 * mu(P, v, beta_i) P of the current debris (what the return mapping of a vanishing step gives), mu_mean =
 * F_S / F_N (Eq. 28), contact-weighted means under the pad at the current displacements.
 *
 * A step that would need more than TC_STRIPDRAW_MAX_INTERVALS intervals or TC_STRIPDRAW_MAX_SUBSTEPS explicit
 * steps is refused (TC_DISCARD, state unchanged) before any is taken.
 */
#include "tc_stripdraw.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "tc_cpu.h"
#include "tc_debris.h"
#include "tc_explicit.h"
#include "tc_friction.h"
#include "tc_galpha.h"
#include "tc_kernels.h"
#include "tc_stripdraw_model.h"
#include "tc_stripdraw_state.h"

#define LEAD_LENGTH 0.005 /* m of strip behind the material under the pad at the end of the draw */
#define MAX_HALVINGS 12
#ifndef TC_STRIPDRAW_NEWTON_MAX_ITER
#define TC_STRIPDRAW_NEWTON_MAX_ITER 60 /* the tests build with fewer to exercise the halving */
#endif
#define NEWTON_RTOL 1e-10 /* residual relative to the friction capacity + grip pull */
#define GRID_TOLERANCE 1e-6 /* a step's end this close to a grid point (in internal_step) is on it */

/* ---------------------------------------------------------------------------------------------------
 * kernels
 * ------------------------------------------------------------------------------------------------- */

/* the overlap of the segment [lo, hi] with the pad, 0 when they do not meet (compares, not fmin/fmax: the
 * positions are finite, and the compares vectorise) */
#define TC_SD_OVERLAP(lo, hi) (((hi) > a_hi ? a_hi : (hi)) - ((lo) < a_lo ? a_lo : (lo)))

/* tc_sd_overlap of the interior nodes [b, e) (their segments are two-sided) */
static void overlap_interior(size_t b, size_t e, const double *X, const double *U, double half_le, double a_lo,
                             double a_hi, double *ov) {
    for (size_t i = b; i < e; ++i) {
        const double x = X[i] + U[i];
        const double d = TC_SD_OVERLAP(x - half_le, x + half_le);
        ov[i] = d > 0.0 ? d : 0.0;
    }
}

/* tc_sd_overlap of the end nodes (n >= 1; their segments are one-sided) */
static void overlap_ends(size_t n, const double *X, const double *U, double half_le, double a_lo, double a_hi,
                         double *ov) {
    const double x0 = X[0] + U[0], xn = X[n - 1] + U[n - 1];
    const double d0 = TC_SD_OVERLAP(x0, n == 1 ? x0 : x0 + half_le), dn = TC_SD_OVERLAP(xn - half_le, xn);
    ov[0] = d0 > 0.0 ? d0 : 0.0;
    if (n > 1) ov[n - 1] = dn > 0.0 ? dn : 0.0;
}
#undef TC_SD_OVERLAP

void tc_sd_overlap(size_t n, const double *X, const double *U, double half_le, double a_lo, double a_hi,
                   double *ov) {
    if (n == 0) return;
    overlap_interior(1, n - 1, X, U, half_le, a_lo, a_hi, ov);
    overlap_ends(n, X, U, half_le, a_lo, a_hi, ov);
}

/* ---------------------------------------------------------------------------------------------------
 * the model
 * ------------------------------------------------------------------------------------------------- */

/* The contact weights of U (the overlap with the pad over l_e) and their nonzero range. With the positions in order,
 * the interior nodes whose segment reaches past a_lo (x + l_e/2 > a_lo) are those from some node on, those whose
 * segment starts before a_hi (x - l_e/2 < a_hi) those up to some node: only the nodes of both sets can meet the pad,
 * and bisection finds them; the others' overlaps are 0 (as tc_sd_overlap computes them: the same expressions). On entry
 * w is 0 outside [w_first, w_last]. */
static void update_weights(tc_stripdraw *m) {
    double *w = m->w;
    const size_t n = m->n;
    const double *X = m->X, *U = m->U, h = m->half_le;
    size_t b = 1, e = n > 1 ? n - 1 : 1; /* the interior nodes that may meet the pad: [b, e) */
    if (n > 2 && m->kernels->positions_in_order(n, X, U)) {
        size_t lo = 1, hi = n - 1;
        while (lo < hi) { /* the first interior node with x + l_e/2 > a_lo */
            const size_t mid = lo + (hi - lo) / 2;
            if (X[mid] + U[mid] + h > m->a_lo)
                hi = mid;
            else
                lo = mid + 1;
        }
        b = lo;
        hi = n - 1;
        while (lo < hi) { /* the first one on with x - l_e/2 >= a_hi */
            const size_t mid = lo + (hi - lo) / 2;
            if (!(X[mid] + U[mid] - h < m->a_hi))
                hi = mid;
            else
                lo = mid + 1;
        }
        e = lo;
        for (size_t i = m->w_first; i <= m->w_last; ++i) w[i] = 0.0; /* 0 elsewhere already */
        overlap_interior(b, e, X, U, h, m->a_lo, m->a_hi, w);
        overlap_ends(n, X, U, h, m->a_lo, m->a_hi, w);
    } else {
        tc_sd_overlap(n, X, U, h, m->a_lo, m->a_hi, w);
    }
    /* the first and last node with w != 0, in the order 0, [b, e), n - 1 (the other nodes' w are 0) */
    size_t first = n, last = 0; /* last: one past it */
    if (w[0] != 0.0) {
        first = 0;
    } else {
        for (size_t i = b; i < e && first == n; ++i)
            if (w[i] != 0.0) first = i;
        if (first == n && n > 1 && w[n - 1] != 0.0) first = n - 1;
    }
    if (n > 1 && w[n - 1] != 0.0) {
        last = n;
    } else {
        for (size_t i = e; i > b && last == 0; --i)
            if (w[i - 1] != 0.0) last = i;
        if (last == 0 && w[0] != 0.0) last = 1;
    }
    m->w_first = first < n ? first : 1;
    m->w_last = first < n ? last - 1 : 0;
    for (size_t i = first; i < last; ++i) w[i] = w[i] / m->le;
}

/* the slip rates of the last interval, |dU| / h, into slip_rate if they are not there */
static void form_slip_rates(tc_stripdraw *m) {
    if (!(m->slip_h > 0)) return;
    for (size_t i = 0; i < m->n; ++i) m->slip_rate[i] = fabs(m->dU[i]) / m->slip_h;
    m->slip_h = 0.0;
}

/* The friction limits mu P of the nodes that can reach the pad within an interval (contact nodes +- reach) at
 * pressure P and grip speed (or the slip rates), into tmax (0 elsewhere), the clamped lookups flagged; the range
 * and the key kept for reuse, and the least mu over the nodes under the pad (what the floor is checked on). */
static int friction_limits(tc_stripdraw *m, double pressure, double speed, int policy, tc_msg msg) {
    const size_t n = m->n;
    for (size_t i = m->limit_lo; i < m->limit_hi; ++i) m->tmax[i] = 0.0; /* 0 elsewhere already */
    m->limit_pressure = pressure;
    m->limit_speed = speed;
    m->limit_lo = m->limit_hi = 0;
    m->limit_clamped = 0;
    m->mu_least = NAN;
    if (!(pressure > 0)) return TC_OK;
    long long lo = 0, hi = (long long)n;
    if (m->w_first <= m->w_last) {
        const long long first = (long long)m->w_first, last = (long long)m->w_last;
        lo = first - m->reach > 0 ? first - m->reach : 0;
        hi = last + 1 + m->reach < (long long)n ? last + 1 + m->reach : (long long)n;
    }
    if (hi <= lo) return TC_OK;
    const size_t l = (size_t)lo, cnt = (size_t)(hi - lo);
    const double *v = m->vel;
    if (m->p.friction_velocity == TC_STRIPDRAW_FRICTION_VELOCITY_GRIP) {
        for (size_t k = 0; k < cnt; ++k) m->vel[k] = speed;
    } else {
        form_slip_rates(m);
        v = m->slip_rate + l;
    }
    tc_stripdraw_params p = m->p;
    p.table_policy = policy;
    int rc = tc_law_mu(&p, m->table, pressure, cnt, v, m->beta + l, m->mu, m->clamped, m->ac, &m->rows, msg);
    if (rc != TC_OK) return rc;
    const double *mu = m->mu, *w = m->w + l;
    const unsigned char *clamped = m->clamped;
    double *tmax = m->tmax + l, least = HUGE_VAL;
    int any = 0, under = 0;
    for (size_t k = 0; k < cnt; ++k) { /* in selects: the least is a chain from node to node */
        tmax[k] = mu[k] * pressure;
        any |= clamped[k];
        under |= w[k] > 0;
        const double candidate = w[k] > 0 ? mu[k] : HUGE_VAL;
        least = candidate < least ? candidate : least; /* fmin(least, candidate): a NaN mu is passed over */
    }
    m->limit_clamped = any;
    m->mu_least = under ? least : NAN;
    m->limit_lo = l;
    m->limit_hi = l + cnt;
    return TC_OK;
}

/* the limits of the state (its pressure and velocity), for the outputs and the next interval; they cannot fail */
static void state_limits(tc_stripdraw *m) {
    const tc_msg none = {NULL, 0};
    (void)friction_limits(m, m->normal_force / m->pad_area, fabs(m->grip_velocity), TC_TABLE_CLAMP, none);
}

/* the elimination factors of the free bar for the step length h, kept for the last TC_SD_CHAIN_CACHE step lengths */
static const double *chain_for(tc_stripdraw *m, double h) {
    const size_t size = TC_SD_CHAIN(m->n);
    for (int k = 0; k < m->chain_used; ++k)
        if (m->chain_h[k] == h) return m->chain + (size_t)k * size;
    int k;
    if (m->chain_used < TC_SD_CHAIN_CACHE) {
        k = m->chain_used++;
    } else {
        k = m->chain_next;
        m->chain_next = (k + 1) % TC_SD_CHAIN_CACHE;
    }
    m->chain_h[k] = h;
    const double cm = (1.0 - m->am) / (m->beta_nm * h * h);
    tc_sd_chain_factors(m->n, cm, m->am, m->mass, (1.0 - m->af) * m->ke, m->chain + (size_t)k * size);
    return m->chain + (size_t)k * size;
}

static int refuse(tc_stripdraw *m, int kind) {
    m->refusal = kind;
    return TC_DISCARD;
}

/* one implicit step of h from the bar's state *from (into U, V, A, fprev) and the overlaps ov (nonzero within
 * [first, last]; first > last: not known), halved when its Newton iteration does not converge */
static int implicit_step(tc_stripdraw *m, double h, const tc_sd_bar *from, const double *ov, size_t first, size_t last,
                         double vg, int depth, tc_msg msg) {
    const size_t n = m->n;
    double fric, reaction;
    int it = m->kernels->galpha(n, h, from, m->U, m->V, m->A, m->Up, m->contact, m->fprev, ov, first, last, m->mass,
                                m->ke, m->ks, m->wT, m->tmax, vg, m->am, m->af, m->beta_nm, m->gamma,
                                TC_STRIPDRAW_NEWTON_MAX_ITER, NEWTON_RTOL, chain_for(m, h), &fric, &reaction, m->gwork,
                                m->giwork);
    if (it >= 0) {
        m->reaction = reaction;
        return TC_OK;
    }
    if (it == -2)
        return tc_fail(msg, refuse(m, TC_REFUSED_SOLVER),
                       "the implicit bar step of %.3g s is too short (its square underflows) at t = %.9g s", h,
                       m->time);
    if (depth >= MAX_HALVINGS)
        return tc_fail(msg, refuse(m, TC_REFUSED_SOLVER),
                       "implicit bar step did not converge (stick/slip set kept changing) at t = %.9g s even with "
                       "the step halved %d times to %.3g s",
                       m->time, depth, h);
    int rc = implicit_step(m, 0.5 * h, from, ov, first, last, vg, depth + 1, msg);
    if (rc != TC_OK) return rc;
    double *ov_mid = m->ov + (size_t)(depth + 1) * n; /* level depth+1: in use only below this call */
    tc_sd_overlap(n, m->X, m->U, m->half_le, m->a_lo, m->a_hi, ov_mid);
    const tc_sd_bar mid = {m->U, m->V, m->A, m->fprev};
    return implicit_step(m, 0.5 * h, &mid, ov_mid, 1, 0, vg, depth + 1, msg);
}

/* whether the bar is at rest as made: every U, V, A, fprev and Up 0 (scanned from the grip, whose node moves first,
 * so a bar that has moved is found at once) */
static int bar_at_rest(const tc_stripdraw *m) {
    const tc_sd_bar bar = m->bar_in_backup ? (tc_sd_bar){m->bU, m->bV, m->bA, m->bfprev}
                                           : (tc_sd_bar){m->U, m->V, m->A, m->fprev};
    const double *arrays[5] = {bar.U, bar.V, bar.A, bar.fprev, m->Up};
    for (int k = 0; k < 5; ++k)
        for (size_t i = m->n; i-- > 0;)
            if (arrays[k][i] != 0.0) return 0;
    return 1;
}

/* The interface at the end of an interval made consistent with the state's contact weights and friction limits, so
 * that the outputs are those a vanishing next step gives (docs/model.md section 2): the interval decides contact
 * and holds the limits from its start, so without this a node that entered the pad during it is not in contact at
 * its end (its friction uncounted until the next step's first ~0.2 us load it to the limit: a jump of ~1e-3 of F_S
 * at the start of every step, whatever its length), and a node that slid at the interval's limit sits below the
 * state's limit (which the debris the interval made has moved) until the next step's first nanoseconds. So
 *   - a node under the pad (w > 0) not in contact entered during the interval and slid in by its overlap w l_e:
 *     in contact with the traction sign(dU) min(T_max, k_s w l_e) (at the limit unless it entered less than
 *     T_max / k_s, 16 nm by default, ago);
 *   - a node that slid at the interval's limit (slipped, over [lo, hi)) is at the state's limit, with its sign.
 * The plastic slip Up = U - T / k_s carries the traction. */
static void settle_interface(tc_stripdraw *m, const unsigned char *slipped, size_t lo, size_t hi) {
    const double ks = m->ks, le = m->le;
    const double *w = m->w, *dU = m->dU, *tmax = m->tmax, *U = m->U;
    double *Up = m->Up;
    signed char *contact = m->contact;
    for (size_t i = m->w_first; i <= m->w_last && i < m->n; ++i) {
        if (!(w[i] > 0.0)) continue;
        if (!contact[i]) {
            if (dU[i] == 0.0) continue;
            const double t = fmin(tmax[i], ks * w[i] * le);
            contact[i] = 1;
            Up[i] = U[i] - copysign(t, dU[i]) / ks;
        } else if (i >= lo && i < hi && slipped[i]) {
            Up[i] = U[i] - copysign(tmax[i], U[i] - Up[i]) / ks;
        }
    }
}

/* one coupling interval of length h at normal force fn (>= 0) and grip velocity vg */
static int interval(tc_stripdraw *m, double h, double fn, double vg, tc_msg msg) {
    const tc_stripdraw_params *p = &m->p;
    const size_t n = m->n;
    const double speed = fabs(vg), pressure = fn / m->pad_area; /* as state_limits computes it */
    /* The strip held at rest while the press closes (the grip still, the bar at rest as made): it stays at rest
     * whatever the friction limits, nothing slides, so no debris is made, carried or capped and no limit enters the
     * result; none is looked up for the interval (nor counted in clamp_count), and the state takes the inputs. */
    if (vg == 0.0 && bar_at_rest(m)) {
        m->normal_force = fn;
        m->grip_velocity = vg;
        m->u_finite = 1;
        state_limits(m);
        return TC_OK;
    }
    /* the limits of the state serve when the pressure and the speed are the same (and under the error policy
     * when none was clamped); else they are looked up under the model's policy */
    const int same = pressure == m->limit_pressure &&
                     (p->friction_velocity != TC_STRIPDRAW_FRICTION_VELOCITY_GRIP || speed == m->limit_speed) &&
                     (p->table_policy == TC_TABLE_CLAMP || !m->limit_clamped);
    if (!same) {
        int rc = friction_limits(m, pressure, speed, p->table_policy, msg);
        if (rc != TC_OK) return rc == TC_DISCARD ? refuse(m, TC_REFUSED_TABLE) : rc;
    }
    for (size_t i = m->limit_lo; i < m->limit_hi; ++i)
        if (m->clamped[i - m->limit_lo] && m->w[i] > 0) m->clamp_count += 1;
    /* the bar's state at the interval's start: in the backup's arrays for a step's first interval, else in U, V, A,
     * fprev (U copied to U0 for the increments) */
    const tc_sd_bar from = m->bar_in_backup ? (tc_sd_bar){m->bU, m->bV, m->bA, m->bfprev}
                                            : (tc_sd_bar){m->U, m->V, m->A, m->fprev};
    const double *U0 = m->bar_in_backup ? m->bU : m->U0;
    if (!m->bar_in_backup) memcpy(m->U0, m->U, n * sizeof *m->U);
    if (p->integrator == TC_STRIPDRAW_INTEGRATOR_EXPLICIT) {
        if (m->bar_in_backup) { /* the central difference works in place */
            memcpy(m->U, m->bU, n * sizeof *m->U);
            memcpy(m->V, m->bV, n * sizeof *m->V);
            memcpy(m->A, m->bA, n * sizeof *m->A);
            memcpy(m->fprev, m->bfprev, n * sizeof *m->fprev);
        }
        double q = ceil(h / m->dt_explicit - 1e-9), fric;
        long long n_sub = q > 1.0 ? (long long)q : 1; /* bounded in advance() */
        tc_sd_explicit(n, n_sub, h / (double)n_sub, m->U, m->V, m->A, m->Up, m->contact, m->X, m->minv, m->ke, m->ks,
                       m->wT, m->half_le, m->a_lo, m->a_hi, m->tmax, vg, &fric, &m->reaction, m->fwork);
    } else {
        for (size_t i = m->ov_first; i <= m->ov_last; ++i) m->ov[i] = 0.0;
        for (size_t i = m->w_first; i <= m->w_last; ++i) m->ov[i] = m->w[i] * m->le; /* the weights are 0 elsewhere */
        m->ov_first = m->w_first;
        m->ov_last = m->w_last;
        int rc = implicit_step(m, h, &from, m->ov, m->w_first, m->w_last, vg, 0, msg);
        if (rc != TC_OK) return rc;
    }
    m->bar_in_backup = 0;
    /* the interval's increments; their slip rates |dU| / h are formed when read (form_slip_rates) */
    const int du_finite = m->kernels->difference_finite(n, m->U, U0, m->dU, &m->u_finite);
    m->slip_h = h;
    m->normal_force = fn;
    m->grip_velocity = vg;
    double *w0 = m->w; /* the weights at the start of the interval */
    const size_t f0 = m->w_first, l0 = m->w_last;
    m->w = m->w0;
    m->w0 = w0;
    m->w_first = m->w0_first; /* the range of w's nonzero values, which update_weights clears */
    m->w_last = m->w0_last;
    m->w0_first = f0;
    m->w0_last = l0;
    update_weights(m);
    tc_sd_debris_interval(m, pressure, speed, w0, f0, l0, du_finite);
    /* the nodes that slid at the interval's limits, over [lo, hi): those of the limits' range that settle_interface
     * reads (under the pad now) */
    unsigned char *slipped = (unsigned char *)m->giwork + m->n;
    const size_t lo = m->limit_lo > m->w_first ? m->limit_lo : m->w_first;
    const size_t hi = m->limit_hi < m->w_last + 1 ? m->limit_hi : m->w_last + 1;
    const double ks = m->ks, *U = m->U, *Up = m->Up, *tmax = m->tmax;
    const signed char *contact = m->contact;
    for (size_t i = lo; i < hi; ++i) { /* at the limit to its rounding: k_s times that of U (Up = U - T / k_s) */
        const int at_limit = fabs(ks * (U[i] - Up[i])) >= tmax[i] * (1.0 - 1e-9) - 8.0 * DBL_EPSILON * ks * fabs(U[i]);
        slipped[i] = (unsigned char)((contact[i] != 0) & at_limit);
    }
    state_limits(m);
    settle_interface(m, slipped, lo, hi);
    return TC_OK;
}

/* The pieces of the step [t, t + dt] cut at the grid points k tau strictly inside it, as at most three runs of
 * len[j] x count[j] (counts as doubles: a step with more pieces than TC_STRIPDRAW_MAX_INTERVALS is refused
 * before any is taken). An end within GRID_TOLERANCE tau of a grid point is on it; a piece between two grid
 * points is tau exactly. Returns the number of runs; an infinite t / tau gives an infinite count. */
static int grid_pieces(double t, double dt, double tau, double len[3], double count[3]) {
    if (!(tau > 0)) {
        len[0] = dt;
        count[0] = 1.0;
        return 1;
    }
    const double end = t + dt;
    const double a = t / tau;
    const double b = end / tau;
    const double ka = nearbyint(a);
    const double kb = nearbyint(b);
    const int start_on = fabs(a - ka) <= GRID_TOLERANCE;
    const int end_on = fabs(b - kb) <= GRID_TOLERANCE;
    const double first = start_on ? ka + 1.0 : floor(a) + 1.0; /* first grid point inside */
    const double last = end_on ? kb - 1.0 : ceil(b) - 1.0;     /* last grid point inside */
    if (!isfinite(first) || !isfinite(last)) {
        len[0] = dt;
        count[0] = INFINITY;
        return 1;
    }
    if (first > last) {
        len[0] = start_on && end_on && kb == ka + 1.0 ? tau : dt;
        count[0] = 1.0;
        return 1;
    }
    int k = 0;
    len[k] = start_on ? tau : first * tau - t;
    count[k++] = 1.0;
    if (last > first) {
        len[k] = tau;
        count[k++] = last - first;
    }
    len[k] = end_on ? tau : end - last * tau;
    count[k++] = 1.0;
    return k;
}

/* the mean over [a, b] of the input polynomial c[0] + c[1] s + c[2] s^2 (its value at a when a == b): the exact
 * impulse of a force and the exact displacement of a velocity that vary so */
static double input_mean(const double c[3], double a, double b) {
    return c[0] + c[1] * 0.5 * (a + b) + c[2] * (a * a + a * b + b * b) / 3.0;
}

/* the number of coupling intervals of the piece [s, s + len] (at the largest grip speed of its ends and middle) */
static double piece_intervals(const tc_stripdraw *m, const double vg[3], double s, double len) {
    const double speed = fmax(fabs(input_mean(vg, s, s)),
                              fmax(fabs(input_mean(vg, s + 0.5 * len, s + 0.5 * len)), fabs(input_mean(vg, s + len, s + len))));
    const double h_max = speed != 0 ? m->p.window_courant * m->le / speed : INFINITY;
    const double q = ceil(len / h_max - 1e-9);
    return q > 1.0 ? q : 1.0;
}

/* cut the step on the internal grid, each piece into coupling intervals; the inputs are the polynomials fn, vg
 * (Taylor coefficients at the step's start), each interval takes their means */
static int advance(tc_stripdraw *m, double dt, const double fn[3], const double vg[3], tc_msg msg) {
    const tc_stripdraw_params *p = &m->p;
    const int held = fn[1] == 0.0 && fn[2] == 0.0 && vg[1] == 0.0 && vg[2] == 0.0;
    double len[3], count[3];
    const int runs = grid_pieces(m->time, dt, p->internal_step, len, count);
    /* the refusals before any interval is taken: the intervals (and explicit steps) of the whole step */
    double total = 0.0, total_sub = 0.0, pieces = 0.0;
    for (int j = 0; j < runs; ++j) pieces += count[j];
    if (!(pieces <= TC_STRIPDRAW_MAX_INTERVALS))
        return tc_fail(msg, refuse(m, TC_REFUSED_INPUT), "dt = %.17g s cuts into %.3g pieces of internal_step, so as "
                       "many coupling intervals at least; at most %.0e are allowed", dt, pieces,
                       TC_STRIPDRAW_MAX_INTERVALS);
    double s = 0.0;
    for (int j = 0; j < runs; ++j) {
        const long long reps = held ? 1 : (long long)count[j];
        for (long long k = 0; k < reps; ++k) {
            const double n_int = piece_intervals(m, vg, s, len[j]);
            const double times = held ? count[j] : 1.0;
            total += times * n_int;
            if (p->integrator == TC_STRIPDRAW_INTEGRATOR_EXPLICIT) {
                const double qs = ceil(len[j] / n_int / m->dt_explicit - 1e-9);
                total_sub += times * n_int * (qs > 1.0 ? qs : 1.0);
            }
            s += len[j];
        }
    }
    if (!(total <= TC_STRIPDRAW_MAX_INTERVALS))
        return tc_fail(msg, refuse(m, TC_REFUSED_INPUT),
                       "dt = %.17g s at grip_velocity = %.17g m/s needs %.3g coupling intervals; at most %.0e are "
                       "allowed", dt, vg[0], total, TC_STRIPDRAW_MAX_INTERVALS);
    if (!(total_sub <= TC_STRIPDRAW_MAX_SUBSTEPS))
        return tc_fail(msg, refuse(m, TC_REFUSED_INPUT),
                       "dt = %.17g s needs %.3g explicit steps of %.3g s; at most %.0e are allowed per step", dt,
                       total_sub, m->dt_explicit, TC_STRIPDRAW_MAX_SUBSTEPS);
    s = 0.0;
    for (int j = 0; j < runs; ++j) {
        for (long long k = 0; k < (long long)count[j]; ++k) {
            const double n_int = piece_intervals(m, vg, s, len[j]);
            const double h = len[j] / n_int;
            for (long long i = 0; i < (long long)n_int; ++i) {
                const double a = s + (double)i * h, b = s + (double)(i + 1) * h;
                /* a normal force interpolated below zero is a pad that lifts off: no pressure (no adhesion) */
                int rc = interval(m, h, fmax(0.0, input_mean(fn, a, b)), input_mean(vg, a, b), msg);
                if (rc != TC_OK) return rc;
            }
            s += len[j];
        }
    }
    return TC_OK;
}

/* ---------------------------------------------------------------------------------------------------
 * public API
 * ------------------------------------------------------------------------------------------------- */

size_t tc_stripdraw_state_size(const tc_stripdraw *m) { return m->state_size; }

void tc_stripdraw_get_state(const tc_stripdraw *m, void *buf) { tc_sd_state_write(m, buf); }

int tc_stripdraw_set_state(tc_stripdraw *m, const void *buf, size_t size, tc_msg msg) {
    const int rc = tc_sd_state_read(m, buf, size, msg);
    if (rc != TC_OK) return rc;
    update_weights(m); /* what the state image leaves out: the contact weights and friction limits it implies */
    state_limits(m);
    return TC_OK;
}

void tc_stripdraw_free(tc_stripdraw *m) {
    if (m == NULL) return;
    free(m->pool);
    free(m->bytes);
    free(m);
}

int tc_stripdraw_check_params(const tc_stripdraw_params *p, tc_msg msg) { return tc_stripdraw_params_check(p, msg); }

int tc_stripdraw_create(const tc_stripdraw_params *p, const tc_table *table, const double *beta_field,
                        size_t n_beta, tc_stripdraw **out, tc_msg msg) {
    if (out == NULL) return tc_fail(msg, TC_ERROR, "tc_stripdraw_create: no place for the model (out is NULL)");
    *out = NULL;
    if (p == NULL) return tc_fail(msg, TC_ERROR, "tc_stripdraw_create: no parameters (p is NULL)");
    int rc = tc_stripdraw_params_check(p, msg);
    if (rc != TC_OK) return rc;
    rc = tc_law_check(p, table, msg);
    if (rc != TC_OK) return rc;
    const size_t n = (size_t)p->n_elements + 1;
    const double cap = p->beta_threshold > 0 ? p->beta_threshold : tc_law_beta_threshold(p, table);
    if (beta_field != NULL) {
        int ok = n_beta == n;
        for (size_t i = 0; ok && i < n; ++i) ok = isfinite(beta_field[i]) && !(beta_field[i] < 0);
        if (!ok)
            return tc_fail(msg, TC_ERROR,
                           "beta_field must hold %zu finite values >= 0 (one per node); got shape (%zu,)", n, n_beta);
    }
    double bmax = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const double b = beta_field != NULL ? p->debris_carry_over * beta_field[i] : p->beta_initial;
        bmax = i == 0 || b > bmax ? b : bmax;
    }
    if (bmax > cap)
        return tc_fail(msg, TC_ERROR, "initial beta = %.17g exceeds the cap beta_threshold = %g", bmax, cap);

    tc_stripdraw *m = calloc(1, sizeof *m);
    if (m == NULL) return tc_fail(msg, TC_NOMEM, "out of memory for the strip-draw model");
    const int implicit = p->integrator == TC_STRIPDRAW_INTEGRATOR_IMPLICIT;
    /* one pool of doubles, in arrays of n: mesh 3, state 7, weights 1, limits 1, work 10, backup 7, advection 5, then the
     * explicit forces (1) or the generalized-alpha work, the overlaps of each halving level and the cached
     * elimination factors */
    const size_t n_arrays = 3 + 7 + 1 + 1 + 10 + 7 + 5 +
                            (implicit ? (size_t)TC_SD_GALPHA_WORK(1) + MAX_HALVINGS + 1 + TC_SD_CHAIN_CACHE * TC_SD_CHAIN(1)
                                      : 1);
    m->state_size = tc_sd_state_size(n);
    m->kernels = tc_step_kernels_for_cpu();
    m->pool = calloc(n_arrays * n, sizeof *m->pool);
    m->bytes = calloc(5 * n, 1); /* contact, clamped, generalized-alpha flags (2), bcontact */
    if (m->pool == NULL || m->bytes == NULL) {
        tc_stripdraw_free(m);
        return tc_fail(msg, TC_NOMEM, "out of memory for the strip-draw model (%zu nodes)", n);
    }
    double *q = m->pool;
    double **arrays[] = {&m->X,     &m->mass, &m->minv,   &m->U,   &m->V,     &m->A,   &m->Up,
                         &m->beta,  &m->slip_rate, &m->fprev, &m->w, &m->tmax,  &m->U0,  &m->w0,
                         &m->dU,    &m->weight,    &m->vel,   &m->mu,  &m->ac,  &m->bsrc, &m->bnew,
                         &m->bU,    &m->bV,        &m->bA,    &m->bfprev, &m->bUp, &m->bbeta, &m->bslip};
    for (size_t k = 0; k < sizeof arrays / sizeof arrays[0]; ++k, q += n) *arrays[k] = q;
    q += n; /* spare */
    m->awork = q;
    q += 5 * n;
    if (implicit) {
        m->gwork = q;
        m->ov = q + TC_SD_GALPHA_WORK(n);
        m->chain = m->ov + (MAX_HALVINGS + 1) * n;
        m->ov_first = 1; /* none (the pool is zeroed) */
        m->ov_last = 0;
    } else {
        m->fwork = q;
    }
    m->contact = (signed char *)m->bytes;
    m->clamped = m->bytes + n;
    m->giwork = (signed char *)(m->bytes + 2 * n);
    m->bcontact = (signed char *)(m->bytes + 4 * n);

    m->p = *p;
    m->table = p->friction_model == TC_STRIPDRAW_FRICTION_MODEL_TABLE ? table : NULL;
    m->n = n;
    m->beta_cap = cap;
    /* the mesh */
    const double length = LEAD_LENGTH + p->draw_length + p->tool_length + p->free_length;
    const double le = length / (double)p->n_elements;
    const double bar_area = p->sheet_width * (0.5 * p->sheet_thickness);
    m->le = le;
    m->half_le = 0.5 * le;
    for (size_t i = 0; i < n; ++i) m->X[i] = (double)i * le;
    m->X[n - 1] = length;
    for (size_t i = 0; i < n; ++i) m->mass[i] = p->density * bar_area * le;
    m->mass[0] *= 0.5;
    m->mass[n - 1] *= 0.5;
    m->a_lo = LEAD_LENGTH + p->draw_length;
    m->a_hi = m->a_lo + p->tool_length;
    m->ke = p->youngs_modulus * bar_area / le;
    m->ks = p->shear_stiffness_factor * p->youngs_modulus / (0.5 * p->sheet_thickness);
    m->wT = p->tool_width;
    m->pad_area = p->tool_length * p->tool_width;
    const double node_ks = m->ks * p->tool_width * le;
    m->dt_explicit = p->cfl_safety * (2.0 / sqrt((4.0 * m->ke + node_ks) / m->mass[n > 2 ? 1 : 0]));
    for (size_t i = 0; i < n; ++i) m->minv[i] = 1.0 / m->mass[i];
    const double r = p->rho_inf;
    m->am = (2.0 * r - 1.0) / (r + 1.0);
    m->af = r / (r + 1.0);
    m->gamma = 0.5 - m->am + m->af;
    m->beta_nm = 0.25 * (1.0 - m->am + m->af) * (1.0 - m->am + m->af);
    const double reach = ceil(p->window_courant) + 1.0; /* kept within [-n, n], where it acts as +-infinity */
    m->reach = reach >= -(double)n && reach <= (double)n ? (long long)reach : (reach < 0 ? -(long long)n : (long long)n);
    /* the state */
    /* a later pass starts from the debris the earlier one left, the share debris_carry_over of it */
    for (size_t i = 0; i < n; ++i) m->beta[i] = beta_field != NULL ? p->debris_carry_over * beta_field[i] : p->beta_initial;
    m->beta_hi = NAN; /* the first interval caps every node */
    update_weights(m);
    state_limits(m);
    *out = m;
    return TC_OK;
}

int tc_stripdraw_step(tc_stripdraw *m, double dt, double normal_force, double grip_velocity, tc_msg msg) {
    const double none[2] = {0.0, 0.0};
    return tc_stripdraw_step_poly(m, dt, normal_force, none, grip_velocity, none, msg);
}

/* TC_DISCARD naming the input when the inputs cannot be used: non-finite, a negative normal force, or a grip speed
 * not below the bar's wave speed c = sqrt(E / rho) (the bar's elastic waves carry the pull to the pad; a grip that
 * outruns them tears the strip, which the model does not describe; and since a coupling interval slides at most
 * window_courant elements, the intervals of a step grow with |V0| dt: at 1e6 m/s a 1 ms step would need 3e5) */
static int check_inputs(const tc_stripdraw *m, double normal_force, double grip_velocity, tc_msg msg) {
    char r[TC_REPR_SIZE], w[TC_REPR_SIZE];
    const double wave_speed = sqrt(m->p.youngs_modulus / m->p.density);
    if (!isfinite(normal_force))
        return tc_fail(msg, TC_DISCARD, "normal_force = %s is not finite; a finite number is required",
                       tc_repr_double(normal_force, r));
    if (normal_force < 0)
        return tc_fail(msg, TC_DISCARD, "normal_force = %s N must be >= 0", tc_repr_double(normal_force, r));
    if (!isfinite(grip_velocity))
        return tc_fail(msg, TC_DISCARD, "grip_velocity = %s is not finite; a finite number is required",
                       tc_repr_double(grip_velocity, r));
    if (!(fabs(grip_velocity) < wave_speed))
        return tc_fail(msg, TC_DISCARD, "grip_velocity = %s m/s is not below the strip's wave speed sqrt(E / rho) = "
                       "%s m/s: the bar's elastic waves cannot carry a faster pull to the pad",
                       tc_repr_double(grip_velocity, r), tc_repr_double(wave_speed, w));
    return TC_OK;
}

int tc_stripdraw_set_inputs(tc_stripdraw *m, double normal_force, double grip_velocity, tc_msg msg) {
    int rc = check_inputs(m, normal_force, grip_velocity, msg);
    if (rc != TC_OK) return rc;
    m->normal_force = normal_force;
    m->grip_velocity = grip_velocity;
    state_limits(m);
    return TC_OK;
}

int tc_stripdraw_step_poly(tc_stripdraw *m, double dt, double normal_force, const double d_normal_force[2],
                           double grip_velocity, const double d_grip_velocity[2], tc_msg msg) {
    static const char *const names[4] = {"d(normal_force)/dt", "d2(normal_force)/dt2", "d(grip_velocity)/dt",
                                         "d2(grip_velocity)/dt2"};
    const double d[4] = {d_normal_force[0], d_normal_force[1], d_grip_velocity[0], d_grip_velocity[1]};
    char r[TC_REPR_SIZE];
    m->refusal = TC_REFUSED_INPUT;
    if (!isfinite(dt))
        return tc_fail(msg, TC_DISCARD, "dt = %s is not finite; a finite number is required", tc_repr_double(dt, r));
    if (dt <= 0) return tc_fail(msg, TC_DISCARD, "dt = %s s must be > 0", tc_repr_double(dt, r));
    int checked = check_inputs(m, normal_force, grip_velocity, msg);
    if (checked != TC_OK) return checked;
    for (int k = 0; k < 4; ++k)
        if (!isfinite(d[k]))
            return tc_fail(msg, TC_DISCARD, "%s = %s is not finite; a finite number is required", names[k],
                           tc_repr_double(d[k], r));
    const double fn[3] = {normal_force, d[0], 0.5 * d[1]}, vg[3] = {grip_velocity, d[2], 0.5 * d[3]};
    /* the largest grip speed of the step's polynomial: at its end or at its vertex inside the step */
    const double vertex = vg[2] != 0.0 ? -vg[1] / (2.0 * vg[2]) : -1.0;
    double vmax = fabs(input_mean(vg, dt, dt));
    if (vertex > 0.0 && vertex < dt) vmax = fmax(vmax, fabs(input_mean(vg, vertex, vertex)));
    const double wave_speed = sqrt(m->p.youngs_modulus / m->p.density);
    if (!(vmax < wave_speed)) {
        char r2[TC_REPR_SIZE];
        return tc_fail(msg, TC_DISCARD, "grip_velocity with its derivatives reaches %s m/s within the step of dt = %s "
                       "s, not below the strip's wave speed sqrt(E / rho) = %.6g m/s", tc_repr_double(vmax, r),
                       tc_repr_double(dt, r2), wave_speed);
    }
    tc_sd_backup(m);
    int rc = advance(m, dt, fn, vg, msg);
    if (rc == TC_OK && m->bar_in_backup) tc_sd_swap_bar(m); /* no interval was taken: the bar is as it was */
    if (rc == TC_OK) {
        if (!(isfinite(m->reaction) && m->u_finite)) /* u_finite: of the last interval (a step has at least one) */
            rc = tc_fail(msg, refuse(m, TC_REFUSED_SOLVER), "non-finite bar state at t = %.9g s", m->time + dt);
    }
    if (rc != TC_OK) {
        tc_sd_restore(m); /* with the weights and limits derived from the state restored */
        update_weights(m);
        state_limits(m);
        return rc;
    }
    m->time = m->time + dt;
    m->n_steps += 1;
    return TC_OK;
}

int tc_stripdraw_refusal(const tc_stripdraw *m) { return m->refusal; }

/* The outputs of the state. Over the nodes under the pad (weights w_i = ov_i / l_e > 0): the sums of w_i, w_i U_i and
 * w_i beta_i, and the friction force, the return-mapped tractions T_i w_T ov_i at the state's limits (of the nodes in
 * contact: a node entering the pad starts stress-free). */
void tc_stripdraw_outputs(const tc_stripdraw *m, double out[TC_STRIPDRAW_N_OUTPUTS]) {
    const size_t n = m->n;
    const double fn = m->normal_force;
    double wsum = 0.0, wu = 0.0, wb = 0.0, fs = 0.0;
    for (size_t i = m->w_first; i <= m->w_last && i < n; ++i) {
        const double w = m->w[i];
        wsum += w;
        wu += w * m->U[i];
        wb += w * m->beta[i];
        if (!(w > 0.0) || !m->contact[i]) continue;
        int slipping;
        fs += tc_sd_traction(m->U[i] - m->Up[i], m->ks, m->tmax[i], &slipping) * m->wT * (w * m->le);
    }
    const double bmax = m->kernels->largest(m->beta, n);
    out[TC_STRIPDRAW_PULL_FORCE] = 2.0 * m->reaction;
    out[TC_STRIPDRAW_FRICTION_FORCE] = fs;
    out[TC_STRIPDRAW_MU_MEAN] = fn > 0 ? fs / fn : 0.0;
    out[TC_STRIPDRAW_SLIDING_DISTANCE] = wsum > 0 ? wu / wsum : 0.0;
    out[TC_STRIPDRAW_BETA_MEAN] = wsum > 0 ? wb / wsum : 0.0;
    out[TC_STRIPDRAW_BETA_MAX] = bmax;
    out[TC_STRIPDRAW_CONTACT_PRESSURE] = fn / m->pad_area;
    out[TC_STRIPDRAW_GRIP_POSITION] = m->U[n - 1];
    out[TC_STRIPDRAW_TABLE_CLAMP_COUNT] = (double)m->clamp_count;
}

size_t tc_stripdraw_n_nodes(const tc_stripdraw *m) { return m->n; }

void tc_stripdraw_fields(const tc_stripdraw *m, double *X, double *U, double *beta, double *slip, double *contact) {
    const size_t nb = m->n * sizeof(double);
    if (X != NULL) memcpy(X, m->X, nb);
    if (U != NULL) memcpy(U, m->U, nb);
    if (beta != NULL) memcpy(beta, m->beta, nb);
    if (slip != NULL) memcpy(slip, m->Up, nb);
    if (contact != NULL) memcpy(contact, m->w, nb);
}

void tc_stripdraw_nodal(const tc_stripdraw *m, int which, double *out) {
    const size_t n = m->n, nb = n * sizeof(double);
    switch (which) {
    case TC_SD_NODAL_X: memcpy(out, m->X, nb); break;
    case TC_SD_NODAL_U: memcpy(out, m->U, nb); break;
    case TC_SD_NODAL_V: memcpy(out, m->V, nb); break;
    case TC_SD_NODAL_A: memcpy(out, m->A, nb); break;
    case TC_SD_NODAL_UP: memcpy(out, m->Up, nb); break;
    case TC_SD_NODAL_BETA: memcpy(out, m->beta, nb); break;
    case TC_SD_NODAL_CONTACT_WEIGHT: memcpy(out, m->w, nb); break;
    case TC_SD_NODAL_MASS: memcpy(out, m->mass, nb); break;
    case TC_SD_NODAL_FRICTION_LIMIT: memcpy(out, m->tmax, nb); break;
    case TC_SD_NODAL_SLIP_RATE:
        if (m->slip_h > 0)
            for (size_t i = 0; i < n; ++i) out[i] = fabs(m->dU[i]) / m->slip_h;
        else
            memcpy(out, m->slip_rate, nb);
        break;
    case TC_SD_NODAL_CONTACT:
        for (size_t i = 0; i < n; ++i) out[i] = m->contact[i];
        break;
    default:
        for (size_t i = 0; i < n; ++i) out[i] = NAN;
    }
}

double tc_stripdraw_info(const tc_stripdraw *m, int which) {
    switch (which) {
    case TC_SD_INFO_TIME: return m->time;
    case TC_SD_INFO_N_STEPS: return (double)m->n_steps;
    case TC_SD_INFO_CLAMP_COUNT: return (double)m->clamp_count;
    case TC_SD_INFO_BETA_REMOVED: return m->beta_removed;
    case TC_SD_INFO_BETA_PRODUCED: return m->beta_produced;
    case TC_SD_INFO_BETA_CAP: return m->beta_cap;
    case TC_SD_INFO_EXPLICIT_TIME_STEP: return m->dt_explicit;
    case TC_SD_INFO_ELEMENT_LENGTH: return m->le;
    case TC_SD_INFO_WINDOW_LO: return m->a_lo;
    case TC_SD_INFO_WINDOW_HI: return m->a_hi;
    case TC_SD_INFO_ELEMENT_STIFFNESS: return m->ke;
    case TC_SD_INFO_SHEAR_STIFFNESS: return m->ks;
    case TC_SD_INFO_NORMAL_FORCE: return m->normal_force;
    case TC_SD_INFO_GRIP_VELOCITY: return m->grip_velocity;
    case TC_SD_INFO_REACTION: return m->reaction;
    case TC_SD_INFO_MU_LEAST: return m->mu_least;
    default: return NAN;
    }
}

void tc_stripdraw_window(const tc_stripdraw *m, double window[2]) {
    window[0] = m->a_lo;
    window[1] = m->a_hi;
}

double tc_stripdraw_time(const tc_stripdraw *m) { return m->time; }

int tc_stripdraw_floor_note(const tc_stripdraw *m, tc_msg msg) { return tc_law_floor_note(&m->p, m->mu_least, msg); }
