/* The strip-draw model: 1D bar under a pad + interface law + debris transport + friction law.
 *
 * Native twin of components/stripdraw/{model,kernels,transport,friction,mesh}.py; the Python modules are the
 * readable reference and their docstrings give the reasoning. The arithmetic here is written in the order of
 * the Python loop forms (the ones numba compiles) and of NumPy's element-wise expressions, and the sources are
 * compiled without fused multiply-add, so both implementations round alike (see tests/native).
 *
 * Physics (paper Sec. 3-4, App. B-C):
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
 * - implicit integrator: generalized-alpha (Chung & Hulbert 1993) in force-averaged form,
 *   M [(1-am) a_{n+1} + am a_n] + (1-af) f(u_{n+1}) + af f(u_n) = 0, Newmark updates, am = (2r-1)/(r+1),
 *   af = r/(r+1), gamma = 1/2 - am + af, beta = (1 - am + af)^2 / 4 (r = rho_inf); each step is solved by
 *   Newton's method on the stick/slip set (tangent k_s w_T ov_i on sticking nodes), globalised by an Armijo
 *   line search on the step's convex incremental potential Pi (kernels.py states Pi); a step that does not
 *   converge in 60 iterations is halved, up to 12 times;
 * - friction (Eq. 6-9, 23): constant mu_const; closed form mu = mu0 (1 - s alpha(v) beta h'_rms / kappa) with
 *   alpha(v) = b (1 - exp(-|v|/v_ref)) (evaluated with expm1, as NumPy does) or b when v_ref = 0; or the table:
 *   version 2, mu = mu0 (1 - s A_p / A_c) with A_p from the table and A_c from it (mesoscale) or Eq. 8,
 *   version 1, its mu (tc_table_lookup); v is the grip speed |V0| or each node's slip rate of the last
 *   interval (friction_velocity);
 * - debris (Eq. 12-14, 24, 37): Archard source K P |dU_i| w_i / (H h_p), then implicit upwind advection with
 *   the tool-carried flux -zeta u beta (u = face velocity) between nodes that are both under the pad (a
 *   tridiagonal M-matrix, Thomas algorithm), then the cap beta <= beta_thres (Eq. 24) whose removal is summed;
 *   unless beta_threshold is set, the cap of a version 2 table is where s A_p reaches A_c at the interval's
 *   pressure and grip speed (friction.TableFriction.beta_cap).
 *
 * Coupling (model.py): a step is cut into pieces on the internal grid k * internal_step (grid_pieces; one
 * piece, the step, when internal_step = 0), and each piece of length d into n_int = max(1, ceil(d / h_max -
 * 1e-9)) intervals with h_max = window_courant l_e / |V0| (the largest |V0| of the piece's ends and middle);
 * the inputs are polynomials of the time into the step (held, or from their derivatives: tc_stripdraw_step_poly)
 * and each interval takes their means (input_mean); per interval mu is evaluated on the nodes that can
 * reach the pad (contact nodes +- ceil(window_courant) + 1) and held, the bar advanced, then beta updated from
 * the nodal slip increments with the contact weights averaged over the interval.
 *
 * Outputs: pull_force = 2 x the axial force at the grip (Eq. 1: mu = pull_force / (2 F_N)), friction_force
 * F_S = sum of nodal friction forces, mu_mean = F_S / F_N (Eq. 28), contact-weighted means under the pad.
 *
 * Where the Python model fails from deep inside a step (numba's ZeroDivisionError when dt^2 underflows, an
 * OverflowError for infinitely many intervals) the native step is refused the same way (TC_DISCARD, state
 * unchanged); a step that would need more than TC_STRIPDRAW_MAX_INTERVALS intervals or
 * TC_STRIPDRAW_MAX_SUBSTEPS explicit steps (where Python would run for days) is refused as well.
 */
#include "tc_stripdraw.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define LEAD_LENGTH 0.005 /* mesh.LEAD_LENGTH [m] */
#define MAX_HALVINGS 12   /* model._MAX_HALVINGS */
#define CHAIN_CACHE 4     /* model._CHAIN_CACHE */
#ifndef TC_STRIPDRAW_NEWTON_MAX_ITER
#define TC_STRIPDRAW_NEWTON_MAX_ITER 60 /* model._NEWTON_MAX_ITER; the tests build with fewer to exercise the halving */
#endif
#define NEWTON_RTOL 1e-10 /* model._NEWTON_RTOL: residual relative to the friction capacity + grip pull */
#define GRID_TOLERANCE 1e-6 /* model.GRID_TOLERANCE: a step's end this close to a grid point (in internal_step) is on it */
#define STATE_MAGIC 0x44534354u /* "TCSD" in little-endian bytes */
#define STATE_VERSION 1u
#define STATE_HEADER 16
#define N_STATE_ARRAYS 7
#define N_STATE_DOUBLES 5
#define N_STATE_INTS 2

struct tc_stripdraw {
    tc_stripdraw_params p;
    const tc_table *table; /* borrowed; NULL unless the table law is used */
    size_t n;              /* nodes; node n - 1 is the grip */
    /* mesh (mesh.BarMesh) and constants */
    double le, half_le, a_lo, a_hi, ke, ks, wT, dt_explicit, pad_area;
    double am, af, gamma, beta_nm; /* generalized-alpha */
    double beta_cap;      /* params.beta_threshold if > 0, else the law's threshold */
    double law_threshold; /* law_beta_threshold */
    long long reach; /* ceil(window_courant) + 1 */
    double *X, *mass, *minv;
    /* state (model._ARRAYS, model._SCALARS) */
    double *U, *V, *A, *Up, *beta, *slip_rate, *fprev;
    signed char *contact;
    double time, friction_force, reaction, normal_force, beta_removed;
    long long n_steps, clamp_count;
    /* derived from U: contact weights (model._w), and the first and last node where they are not 0 (w_first >
     * w_last: none) */
    double *w;
    size_t w_first, w_last;
    /* slip_h > 0: slip_rate[i] is |dU[i]| / slip_h, formed when read (form_slip_rates; model._interval divides
     * at every interval, and the rates are read only by the slip-rate friction law and the state image) */
    double slip_h, backup_slip_h;
    /* every beta <= beta_hi and none is -0 (NaN: not known), so a cap >= beta_hi changes no node away from the
     * pad (interval); over may be nonzero only in [over_lo, over_hi] */
    double beta_hi;
    size_t over_lo, over_hi;
    /* work arrays */
    double *tmax, *U0, *w0, *dU, *weight, *vel, *mu, *ac, *bsrc, *bnew, *over, *awork;
    double *fwork;          /* explicit: nodal forces */
    double *gwork, *ov;     /* implicit: tc_sd_galpha work, and the overlaps of each halving level */
    double *chain;          /* implicit: tc_sd_chain_factors of the last CHAIN_CACHE step lengths */
    double chain_h[CHAIN_CACHE];
    int chain_used, chain_next;
    double cap_pressure, cap_speed, cap_value; /* law_beta_cap of the last (P, |V0|), when cap_known */
    int cap_known;
    unsigned char *clamped; /* table lookups flagged as clamped */
    signed char *giwork;
    unsigned char *backup; /* the state before the current step */
    size_t state_size;
    double *pool;          /* every double array above, in one allocation */
    unsigned char *bytes;  /* contact, clamped, giwork and backup, in one allocation */
};

/* ---------------------------------------------------------------------------------------------------
 * helpers
 * ------------------------------------------------------------------------------------------------- */



/* Python's max(a, b) / min(a, b) for floats (numba compiles them the same way): b replaces a only if
 * strictly larger / smaller. */
static double py_max(double a, double b) { return b > a ? b : a; }
static double py_min(double a, double b) { return b < a ? b : a; }

/* np.max of a[0..n-1] (n >= 1), or of |a| when magnitude is set: the largest value, NaN if there is one (four
 * running maxima, so that the compares overlap) */
static double largest(const double *a, size_t n, int magnitude) {
    const double a0 = magnitude ? fabs(a[0]) : a[0];
    double mx[4] = {a0, a0, a0, a0};
    int nan = 0;
    for (size_t i = 0; i < n; i += 4)
        for (size_t k = 0; k < 4 && i + k < n; ++k) {
            const double v = magnitude ? fabs(a[i + k]) : a[i + k];
            mx[k] = v > mx[k] ? v : mx[k];
            nan |= v != v;
        }
    return nan ? NAN : py_max(py_max(mx[0], mx[1]), py_max(mx[2], mx[3]));
}

/* ---------------------------------------------------------------------------------------------------
 * kernels (kernels.py, transport.py)
 * ------------------------------------------------------------------------------------------------- */

void tc_sd_overlap(size_t n, const double *X, const double *U, double half_le, double a_lo, double a_hi,
                   double *ov) {
    /* np.maximum(0.0, np.minimum(hi, a_hi) - np.maximum(lo, a_lo)) of the segment [lo, hi]; NaN propagates as
     * in NumPy */
#define TC_SD_OVERLAP(lo, hi) (((hi) > a_hi ? a_hi : (hi)) - ((lo) < a_lo ? a_lo : (lo)))
    if (n == 0) return;
    for (size_t i = 1; i + 1 < n; ++i) { /* the interior: the end nodes' segments are one-sided */
        const double x = X[i] + U[i];
        const double d = TC_SD_OVERLAP(x - half_le, x + half_le);
        ov[i] = d < 0.0 ? 0.0 : d;
    }
    const double x0 = X[0] + U[0], xn = X[n - 1] + U[n - 1];
    const double d0 = TC_SD_OVERLAP(x0, n == 1 ? x0 : x0 + half_le), dn = TC_SD_OVERLAP(xn - half_le, xn);
    ov[0] = d0 < 0.0 ? 0.0 : d0;
    if (n > 1) ov[n - 1] = dn < 0.0 ? 0.0 : dn;
#undef TC_SD_OVERLAP
}

int tc_sd_positive_range(size_t n, const double *a, size_t *first, size_t *last) {
    size_t i = 0;
    while (i < n && !(a[i] > 0.0)) ++i;
    if (i == n) return 0;
    size_t j = n - 1;
    while (!(a[j] > 0.0)) --j;
    *first = i;
    *last = j;
    return 1;
}

void tc_thomas(size_t n, const double *sub, const double *diag, const double *sup, const double *rhs, double *x,
               double *work) {
    double *c = work, *d = work + n;
    /* with no subdiagonal (the advection of debris on a strip drawn forwards) m = diag - 0 c = diag, the same
     * numbers: the forward sweep reduces to divisions that need not wait for each other */
    int lower = 0;
    for (size_t i = 1; i < n && !lower; ++i) lower = sub[i] != 0.0;
    if (!lower) {
        for (size_t i = 0; i < n; ++i) {
            c[i] = sup[i] / diag[i];
            d[i] = rhs[i] / diag[i];
        }
    } else {
        double cp = sup[0] / diag[0], dp = rhs[0] / diag[0]; /* the recurrences' carries, kept in registers */
        c[0] = cp;
        d[0] = dp;
        for (size_t i = 1; i < n; ++i) {
            const double m = diag[i] - sub[i] * cp;
            c[i] = cp = sup[i] / m;
            d[i] = dp = (rhs[i] - sub[i] * dp) / m;
        }
    }
    double xp = d[n - 1];
    x[n - 1] = xp;
    for (size_t i = n - 1; i-- > 0;) x[i] = xp = d[i] - c[i] * xp;
}

void tc_sd_explicit(size_t n, long long n_sub, double dt, double *U, double *V, double *A, double *Up,
                    signed char *contact, const double *X, const double *minv, double ke, double ks, double wT,
                    double half_le, double a_lo, double a_hi, const double *tmax, double vg, double *fric,
                    double *reaction, double *f) {
    const size_t N = n - 1;
    double fr = 0.0;
    for (size_t i = 0; i < n; ++i) f[i] = 0.0; /* reaction = -f[N] is defined even for n_sub = 0 */
    for (long long s = 0; s < n_sub; ++s) {
        /* predictor: U += dt V + dt^2/2 A, V += dt/2 A; the grip follows V0 */
        for (size_t i = 0; i < N; ++i) {
            U[i] += dt * V[i] + 0.5 * dt * dt * A[i];
            V[i] += 0.5 * dt * A[i];
        }
        U[N] += dt * vg;
        V[N] = vg;
        A[N] = 0.0;
        for (size_t i = 0; i < n; ++i) f[i] = 0.0;
        for (size_t e = 0; e < N; ++e) {
            const double s_e = ke * (U[e + 1] - U[e]);
            f[e] += s_e;
            f[e + 1] -= s_e;
        }
        /* interface law with return mapping on the nodes under the pad */
        fr = 0.0;
        for (size_t i = 0; i < n; ++i) {
            const double x = X[i] + U[i];
            const double lo = i == 0 ? x : x - half_le;
            const double hi = i == N ? x : x + half_le;
            const double ov = py_min(hi, a_hi) - py_max(lo, a_lo);
            if (ov > 0.0) {
                if (contact[i] == 0) {
                    Up[i] = U[i];
                    contact[i] = 1;
                }
                double T = ks * (U[i] - Up[i]);
                if (T > tmax[i]) {
                    T = tmax[i];
                    Up[i] = U[i] - T / ks;
                } else if (T < -tmax[i]) {
                    T = -tmax[i];
                    Up[i] = U[i] - T / ks;
                }
                const double F = T * wT * ov;
                f[i] -= F;
                fr += F;
            } else {
                contact[i] = 0;
            }
        }
        /* corrector: A = f / m, V += dt/2 A */
        for (size_t i = 0; i < N; ++i) {
            A[i] = f[i] * minv[i];
            V[i] += 0.5 * dt * A[i];
        }
    }
    *fric = fr;
    *reaction = -f[N];
}

/* transport._advect_loop */
void tc_sd_advect(size_t n_all, const double *beta, const double *dU, const double *weight, double zeta,
                  double element_length, double *out, double *work) {
    memcpy(out, beta, n_all * sizeof *out);
    size_t lo, last; /* the pad covers one contiguous run of nodes */
    if (zeta == 0.0 || !tc_sd_positive_range(n_all, weight, &lo, &last) || last - lo < 1) return;
    const size_t n = last + 1 - lo;
    double *diag = work, *sub = work + n, *sup = work + 2 * n, *tw = work + 3 * n;
    for (size_t k = 0; k < n; ++k) {
        diag[k] = 1.0;
        sub[k] = 0.0;
        sup[k] = 0.0;
    }
    for (size_t k = 0; k + 1 < n; ++k) {
        const size_t a = (size_t)lo + k, b = a + 1;
        if (weight[a] > 0.0 && weight[b] > 0.0) {
            /* face Courant number; upwind: from node k+1 into k when c > 0, from k into k+1 otherwise */
            const double c = zeta * 0.5 * (dU[a] + dU[b]) / element_length;
            if (c > 0.0) {
                diag[k + 1] += c;
                sup[k] -= c;
            } else {
                diag[k] -= c;
                sub[k + 1] += c;
            }
        }
    }
    tc_thomas(n, sub, diag, sup, beta + lo, out + lo, tw); /* rhs is only read before x is written */
}

/* ---------------------------------------------------------------------------------------------------
 * friction laws (friction.py)
 * ------------------------------------------------------------------------------------------------- */

#define REACH_RTOL 1e-12 /* friction.REACH_RTOL: s A_p "reaches" A_c within this relative tolerance */

static const tc_msg NO_MSG = {NULL, 0}; /* for lookups under the clamp policy, which cannot fail */

static int table_v2(const tc_stripdraw_params *p, const tc_table *table) {
    return p->friction_model == TC_STRIPDRAW_FRICTION_MODEL_TABLE && table->format_version >= 2;
}

/* A_c/A0 by the contact_area convention (TableFriction.contact) at one pressure for n (velocity, beta):
 * Eq. 8, kappa P / (h'_rms E*), or the table's (clamped). */
static void contact_area(const tc_stripdraw_params *p, const tc_table *table, double pressure, size_t n,
                         const double *velocity, const double *beta, double *ac) {
    if (p->contact_area == TC_STRIPDRAW_CONTACT_AREA_EQ8) {
        const double eq8 = p->kappa * pressure / (p->rms_slope * p->e_star);
        for (size_t k = 0; k < n; ++k) ac[k] = eq8;
        return;
    }
    /* the clamp policy never fails */
    (void)tc_table_lookup(table, table->contact_area, pressure, n, velocity, beta, TC_TABLE_CLAMP, ac, NULL, NO_MSG);
}

/* TableFriction._crossing: where s A_p reaches A_c along the table's beta axis at (P, v) (both are piecewise
 * linear in beta there, so the crossing is exact), limited to 1; 1 when A_p stays below A_c. */
static double crossing(const tc_stripdraw_params *p, const tc_table *table, double pressure, double velocity) {
    const double *b = table->beta;
    double d_prev = 0.0;
    for (size_t k = 0; k < table->n_beta; ++k) {
        double ap, ac;
        (void)tc_table_lookup(table, table->particle_area, pressure, 1, &velocity, b + k, TC_TABLE_CLAMP, &ap, NULL,
                              NO_MSG);
        contact_area(p, table, pressure, 1, &velocity, b + k, &ac);
        const double d = p->particle_area_scale * ap - ac;
        if (d >= -REACH_RTOL * ac) {
            if (k == 0) return 0.0;
            return py_min(1.0, b[k - 1] + (b[k] - b[k - 1]) * (-d_prev) / (d - d_prev));
        }
        d_prev = d;
    }
    return 1.0;
}

/* beta_threshold of the law (Eq. 24): constant 1; closed form kappa / (s b h'_rms) limited to 1; a version 1
 * table's metadata; a version 2 table's largest crossing over its (P > 0, v) nodes. */
static double law_beta_threshold(const tc_stripdraw_params *p, const tc_table *table) {
    if (p->friction_model == TC_STRIPDRAW_FRICTION_MODEL_TABLE) {
        if (!table_v2(p, table)) return table->beta_threshold;
        double top = 1.0;
        int first = 1;
        for (size_t i = 0; i < table->n_pressure; ++i) {
            if (!(table->pressure[i] > 0)) continue;
            for (size_t j = 0; j < table->n_velocity; ++j) {
                const double c = crossing(p, table, table->pressure[i], table->velocity[j]);
                top = first ? c : py_max(top, c);
                first = 0;
            }
        }
        return top;
    }
    if (p->friction_model == TC_STRIPDRAW_FRICTION_MODEL_CLOSED_FORM) {
        const double top = p->particle_area_scale * p->alpha_b * p->rms_slope;
        if (top <= 0) return 1.0;
        return py_min(1.0, p->kappa / top);
    }
    return 1.0;
}

/* law.beta_cap(P, |V0|): a version 2 table's crossing at the interval's pressure and speed (the threshold
 * without pressure); every other law's threshold. */
static double law_beta_cap(tc_stripdraw *m, double pressure, double speed) {
    if (m->table != NULL && table_v2(&m->p, m->table) && pressure > 0) {
        /* a function of (P, |V0|) alone: kept for the last pair (a draw repeats it interval after interval) */
        if (!(m->cap_known && pressure == m->cap_pressure && speed == m->cap_speed)) {
            m->cap_value = crossing(&m->p, m->table, pressure, speed);
            m->cap_pressure = pressure;
            m->cap_speed = speed;
            m->cap_known = 1;
        }
        return m->cap_value;
    }
    return m->law_threshold;
}

/* the slip rates of the last interval, |dU| / h (model._interval), into slip_rate if they are not there */
static void form_slip_rates(tc_stripdraw *m) {
    if (!(m->slip_h > 0)) return;
    for (size_t i = 0; i < m->n; ++i) m->slip_rate[i] = fabs(m->dU[i]) / m->slip_h;
    m->slip_h = 0.0;
}

/* mu of the nodes lo..lo+cnt-1 at pressure P (law.mu with the velocity model.py passes), flags of clamped
 * table lookups into m->clamped. */
static int law_mu(tc_stripdraw *m, double pressure, double vg, size_t lo, size_t cnt, tc_msg msg) {
    const tc_stripdraw_params *p = &m->p;
    const int grip = p->friction_velocity == TC_STRIPDRAW_FRICTION_VELOCITY_GRIP;
    const double *b = m->beta + lo;
    if (!grip) form_slip_rates(m);
    switch (p->friction_model) {
    case TC_STRIPDRAW_FRICTION_MODEL_CONSTANT:
        for (size_t k = 0; k < cnt; ++k) {
            m->mu[k] = p->mu_const;
            m->clamped[k] = 0;
        }
        return TC_OK;
    case TC_STRIPDRAW_FRICTION_MODEL_CLOSED_FORM:
        for (size_t k = 0; k < cnt; ++k) {
            const double v = grip ? fabs(vg) : m->slip_rate[lo + k];
            const double alpha = p->alpha_v_ref == 0 ? p->alpha_b
                                                     : p->alpha_b * -expm1(-fabs(v) / p->alpha_v_ref); /* Eq. 23 */
            m->mu[k] = p->mu0 * (1.0 - p->particle_area_scale * alpha * b[k] * p->rms_slope / p->kappa); /* Eq. 9 */
            m->clamped[k] = 0;
        }
        return TC_OK;
    default: {
        const double *v = m->slip_rate + lo;
        if (grip) {
            for (size_t k = 0; k < cnt; ++k) m->vel[k] = fabs(vg);
            v = m->vel;
        }
        if (!table_v2(p, m->table))
            return tc_table_mu(m->table, pressure, cnt, v, b, p->table_policy, m->mu, m->clamped, msg);
        /* mu = mu0 (1 - s A_p / A_c), Eq. 7 with Eq. 6; A_c from the table (one lookup of both) or Eq. 8 */
        const int eq8 = p->contact_area == TC_STRIPDRAW_CONTACT_AREA_EQ8;
        int rc = tc_table_lookup2(m->table, m->table->particle_area, eq8 ? NULL : m->table->contact_area, pressure,
                                  cnt, v, b, p->table_policy, m->mu, m->ac, m->clamped, msg);
        if (rc != TC_OK) return rc;
        if (eq8) contact_area(p, m->table, pressure, cnt, v, b, m->ac);
        for (size_t k = 0; k < cnt; ++k) {
            const double share = m->ac[k] > 0 ? p->particle_area_scale * m->mu[k] / m->ac[k] : 0.0;
            const double rest = 1.0 - share;
            m->mu[k] = p->mu0 * (rest < 0.0 ? 0.0 : rest); /* np.maximum(0.0, rest) */
        }
        return TC_OK;
    }
    }
}

/* ---------------------------------------------------------------------------------------------------
 * the model (model.py)
 * ------------------------------------------------------------------------------------------------- */

/* model._weights into m->w (the overlap of each node's segment with the pad over l_e), and its nonzero range.
 * An overlap of 0 gives a weight of +0 without the division (bit for bit what 0 / l_e gives). */
static void update_weights(tc_stripdraw *m) {
    double *w = m->w;
    const size_t n = m->n;
    tc_sd_overlap(n, m->X, m->U, m->half_le, m->a_lo, m->a_hi, w);
    size_t first = 0, last = n;
    while (first < n && w[first] == 0.0) ++first;
    while (last > first && w[last - 1] == 0.0) --last;
    m->w_first = first < n ? first : 1;
    m->w_last = first < n ? last - 1 : 0;
    for (size_t i = first; i < last; ++i)
        if (w[i] != 0.0) w[i] = w[i] / m->le;
}

/* StripDrawModel._chain: the elimination factors of the free bar for the step length h, kept for the last
 * CHAIN_CACHE step lengths (first in, first out). */
static const double *chain_for(tc_stripdraw *m, double h) {
    const size_t size = TC_SD_CHAIN(m->n);
    for (int k = 0; k < m->chain_used; ++k)
        if (m->chain_h[k] == h) return m->chain + (size_t)k * size;
    int k;
    if (m->chain_used < CHAIN_CACHE) {
        k = m->chain_used++;
    } else {
        k = m->chain_next;
        m->chain_next = (k + 1) % CHAIN_CACHE;
    }
    m->chain_h[k] = h;
    const double cm = (1.0 - m->am) / (m->beta_nm * h * h);
    tc_sd_chain_factors(m->n, cm, m->mass, (1.0 - m->af) * m->ke, m->chain + (size_t)k * size);
    return m->chain + (size_t)k * size;
}

static int implicit_step(tc_stripdraw *m, double h, const double *ov, double vg, int depth, double *fric,
                         double *reaction, tc_msg msg) {
    const size_t n = m->n;
    int it = tc_sd_galpha(n, h, m->U, m->V, m->A, m->Up, m->contact, m->fprev, ov, m->mass, m->ke, m->ks, m->wT,
                          m->tmax, vg, m->am, m->af, m->beta_nm, m->gamma, TC_STRIPDRAW_NEWTON_MAX_ITER,
                          NEWTON_RTOL, chain_for(m, h), fric, reaction, m->gwork, m->giwork);
    if (it >= 0) return TC_OK;
    if (it == -2) { /* Python: ZeroDivisionError */
        char r[TC_REPR_SIZE];
        return tc_fail(msg, TC_DISCARD,
                       "division by zero: the implicit bar step of %s s is too short (its square underflows) at "
                       "t = %.9g s", tc_repr_double(h, r), m->time);
    }
    if (depth >= MAX_HALVINGS)
        return tc_fail(msg, TC_DISCARD,
                       "implicit bar step did not converge (stick/slip set kept changing) at t = %.9g s even with "
                       "the step halved %d times to %.3g s",
                       m->time, depth, h);
    int rc = implicit_step(m, 0.5 * h, ov, vg, depth + 1, fric, reaction, msg);
    if (rc != TC_OK) return rc;
    double *ov_mid = m->ov + (size_t)(depth + 1) * n; /* level depth+1: in use only below this call */
    tc_sd_overlap(n, m->X, m->U, m->half_le, m->a_lo, m->a_hi, ov_mid);
    return implicit_step(m, 0.5 * h, ov_mid, vg, depth + 1, fric, reaction, msg);
}

/* StripDrawModel._interval: one coupling interval of length h. */
static int interval(tc_stripdraw *m, double h, double pressure, double vg, tc_msg msg) {
    const tc_stripdraw_params *p = &m->p;
    const size_t n = m->n;
    for (size_t i = 0; i < n; ++i) m->tmax[i] = 0.0;
    if (pressure > 0) {
        /* only nodes that can be under the pad during this interval need mu: the pad slides at most
         * window_courant elements per interval */
        size_t f, l; /* the nodes with w > 0, which lie in [w_first, w_last] */
        long long lo = 0, hi = (long long)n;
        if (m->w_first <= m->w_last &&
            tc_sd_positive_range(m->w_last + 1 - m->w_first, m->w + m->w_first, &f, &l)) {
            const long long first = (long long)(m->w_first + f), last = (long long)(m->w_first + l);
            lo = first - m->reach > 0 ? first - m->reach : 0;
            hi = last + 1 + m->reach < (long long)n ? last + 1 + m->reach : (long long)n;
        }
        if (hi > lo) {
            const size_t cnt = (size_t)(hi - lo);
            int rc = law_mu(m, pressure, vg, (size_t)lo, cnt, msg);
            if (rc != TC_OK) return rc;
            for (size_t k = 0; k < cnt; ++k) {
                if (m->clamped[k] && m->w[(size_t)lo + k] > 0) m->clamp_count += 1;
                m->tmax[(size_t)lo + k] = m->mu[k] * pressure;
            }
        }
    }
    memcpy(m->U0, m->U, n * sizeof *m->U);
    double fric, reaction;
    if (p->integrator == TC_STRIPDRAW_INTEGRATOR_EXPLICIT) {
        double q = ceil(h / m->dt_explicit - 1e-9);
        long long n_sub = q > 1.0 ? (long long)q : 1; /* bounded in advance() */
        tc_sd_explicit(n, n_sub, h / (double)n_sub, m->U, m->V, m->A, m->Up, m->contact, m->X, m->minv, m->ke, m->ks,
                       m->wT, m->half_le, m->a_lo, m->a_hi, m->tmax, vg, &fric, &reaction, m->fwork);
    } else {
        for (size_t i = 0; i < n; ++i) m->ov[i] = m->w[i] * m->le; /* w0 * element_length */
        int rc = implicit_step(m, h, m->ov, vg, 0, &fric, &reaction, msg);
        if (rc != TC_OK) return rc;
    }
    m->friction_force = fric;
    m->reaction = reaction;
    /* the interval's increments; their slip rates |dU| / h are formed when read (form_slip_rates) */
    for (size_t i = 0; i < n; ++i) m->dU[i] = m->U[i] - m->U0[i];
    const double du_max = largest(m->dU, n, 1);
    m->slip_h = h;
    double *w0 = m->w; /* the weights at the start of the interval */
    const size_t w0_first = m->w_first, w0_last = m->w_last;
    m->w = m->w0;
    m->w0 = w0;
    update_weights(m);
    /* transport.transport_step: Archard source (Eq. 37), advection (Eq. 13-14), cap (Eq. 24). The weight
     * 0.5 (w0 + w) is 0 outside the nodes where w0 or w is not, and there the source adds +0 (a finite) and the
     * advection leaves the node alone: new = beta + 0, which is beta (no beta is -0 while beta_hi is known).
     * So the source and the advection run over [t0, t1] only, unless a source term could be inf (0 x inf). */
    const double kp = p->archard_k * pressure, hh = p->hardness * p->particle_thickness;
    size_t t0 = w0_first < m->w_first ? w0_first : m->w_first, t1 = w0_last > m->w_last ? w0_last : m->w_last;
    if (w0_first > w0_last) t0 = m->w_first, t1 = m->w_last;
    if (m->w_first > m->w_last) t0 = w0_first, t1 = w0_last;
    const int windowed = isfinite(kp * du_max) && m->beta_hi == m->beta_hi;
    if (!windowed) t0 = 0, t1 = n - 1;
    const double cap = p->beta_threshold > 0 ? m->beta_cap : py_min(m->beta_cap, law_beta_cap(m, pressure, fabs(vg)));
    if (t0 <= t1) {
        for (size_t i = t0; i <= t1; ++i) {
            m->weight[i] = 0.5 * (w0[i] + m->w[i]);
            const double a = kp * fabs(m->dU[i]);
            /* off the pad (weight 0, a finite) the source is 0 / hh = +0: the same sum without the division */
            m->bsrc[i] = m->weight[i] == 0.0 && isfinite(a) ? m->beta[i] + 0.0 : m->beta[i] + a * m->weight[i] / hh;
        }
        tc_sd_advect(t1 + 1 - t0, m->bsrc + t0, m->dU + t0, m->weight + t0, p->zeta, m->le, m->bnew + t0, m->awork);
    }
    /* the cap: over every node unless it is >= every beta away from [t0, t1] */
    size_t c0 = t0, c1 = t1;
    if (!(windowed && cap >= m->beta_hi)) c0 = 0, c1 = n - 1;
    for (size_t i = m->over_lo; i <= m->over_hi && i < n; ++i) m->over[i] = 0.0; /* the last interval's */
    int removed = 0, unknown = 0;
    for (size_t i = c0; i <= c1 && i < n; ++i) {
        const double b = i >= t0 && i <= t1 ? m->bnew[i] : m->beta[i] + 0.0; /* beta + 0: see above */
        const double d = b - cap;
        m->over[i] = d < 0.0 ? 0.0 : d; /* np.maximum(new - cap, 0.0) */
        const double r = b > cap ? cap : b; /* np.minimum(new, cap) */
        m->beta[i] = r;
        removed |= !(m->over[i] == 0.0);
        unknown |= r != r || (r == 0.0 && signbit(r)); /* NaN, or a -0 that Python's next + 0 would make +0 */
    }
    m->over_lo = c0;
    m->over_hi = c1;
    m->beta_hi = unknown ? NAN : cap;
    /* the sum of over; the nodes outside [c0, c1] add +0 (the sum of zeros when nothing was removed) */
    if (removed) m->beta_removed += tc_pairwise_sum_range(m->over, n, c0, c1);
    return TC_OK;
}

/* model.grid_pieces: the pieces of the step [t, t + dt] cut at the grid points k tau strictly inside it, as at
 * most three runs of len[j] x count[j] (counts as doubles: they are integers, and a step with more pieces than
 * TC_STRIPDRAW_MAX_INTERVALS is refused by the caller before any is taken). Returns the number of runs. Where
 * Python's math.floor/ceil of an infinite t / tau raises OverflowError, the counts come out infinite. */
static int grid_pieces(double t, double dt, double tau, double len[3], double count[3]) {
    if (!(tau > 0)) {
        len[0] = dt;
        count[0] = 1.0;
        return 1;
    }
    const double end = t + dt;
    const double a = t / tau;
    const double b = end / tau;
    const double ka = nearbyint(a); /* round(); ties (never within the tolerance) may go either way */
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

/* model.input_mean: the mean over [a, b] of the input polynomial c[0] + c[1] s + c[2] s^2 (its value at a when
 * a == b); the same operations in the same order as Python. */
static double input_mean(const double c[3], double a, double b) {
    return c[0] + c[1] * 0.5 * (a + b) + c[2] * (a * a + a * b + b * b) / 3.0;
}

/* StripDrawModel._piece: the number of coupling intervals of the piece [s, s + len] (at the largest grip speed
 * of its ends and middle, as Python's max of the three). */
static double piece_intervals(const tc_stripdraw *m, const double vg[3], double s, double len) {
    double speed = fabs(input_mean(vg, s, s));
    speed = py_max(speed, fabs(input_mean(vg, s + 0.5 * len, s + 0.5 * len)));
    speed = py_max(speed, fabs(input_mean(vg, s + len, s + len)));
    const double h_max = speed != 0 ? m->p.window_courant * m->le / speed : INFINITY;
    const double q = ceil(len / h_max - 1e-9);
    return q > 1.0 ? q : 1.0;
}

/* StripDrawModel._advance: cut the step on the internal grid, each piece into coupling intervals; the inputs
 * are the polynomials fn, vg (Taylor coefficients at the step's start), each interval takes their mean. */
static int advance(tc_stripdraw *m, double dt, const double fn[3], const double vg[3], tc_msg msg) {
    const tc_stripdraw_params *p = &m->p;
    char r1[TC_REPR_SIZE], r2[TC_REPR_SIZE];
    const int held = fn[1] == 0.0 && fn[2] == 0.0 && vg[1] == 0.0 && vg[2] == 0.0;
    double len[3], count[3];
    const int runs = grid_pieces(m->time, dt, p->internal_step, len, count);
    /* the refusals before any interval is taken: the intervals (and explicit steps) of the whole step */
    double total = 0.0, total_sub = 0.0, pieces = 0.0;
    for (int j = 0; j < runs; ++j) pieces += count[j];
    if (!(pieces <= TC_STRIPDRAW_MAX_INTERVALS))
        return tc_fail(msg, TC_DISCARD, "dt = %s s cuts into %.3g pieces of internal_step, so as many coupling "
                       "intervals at least; at most %.0e are allowed", tc_repr_double(dt, r1), pieces, TC_STRIPDRAW_MAX_INTERVALS);
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
        return tc_fail(msg, TC_DISCARD,
                       "dt = %s s at grip_velocity = %s m/s needs %.3g coupling intervals; at most %.0e are allowed",
                       tc_repr_double(dt, r1), tc_repr_double(vg[0], r2), total, TC_STRIPDRAW_MAX_INTERVALS);
    if (!(total_sub <= TC_STRIPDRAW_MAX_SUBSTEPS))
        return tc_fail(msg, TC_DISCARD, "dt = %s s needs %.3g explicit steps of %.3g s; at most %.0e are allowed per step",
                       tc_repr_double(dt, r1), total_sub, m->dt_explicit, TC_STRIPDRAW_MAX_SUBSTEPS);
    s = 0.0;
    for (int j = 0; j < runs; ++j) {
        for (long long k = 0; k < (long long)count[j]; ++k) {
            const double n_int = piece_intervals(m, vg, s, len[j]);
            const double h = len[j] / n_int;
            for (long long i = 0; i < (long long)n_int; ++i) {
                const double a = s + (double)i * h, b = s + (double)(i + 1) * h;
                /* a normal force interpolated below zero is a pad that lifts off: no pressure (no adhesion) */
                m->normal_force = py_max(0.0, input_mean(fn, a, b));
                const double pressure = m->normal_force / (p->tool_length * p->tool_width);
                int rc = interval(m, h, pressure, input_mean(vg, a, b), msg);
                if (rc != TC_OK) return rc;
            }
            s += len[j];
        }
    }
    return TC_OK;
}

/* ---------------------------------------------------------------------------------------------------
 * state image
 * ------------------------------------------------------------------------------------------------- */

static size_t state_size(size_t n) {
    return STATE_HEADER + sizeof(double) * (N_STATE_ARRAYS * n + N_STATE_DOUBLES) + sizeof(int64_t) * N_STATE_INTS +
           n;
}

/* the state image; its slip rates from slip, as they stand (h = 0) or as |slip[i]| / h */
static void write_image(const tc_stripdraw *m, unsigned char *b, const double *slip, double h) {
    const size_t n = m->n, nb = n * sizeof(double);
    const uint32_t head[2] = {STATE_MAGIC, STATE_VERSION};
    const uint64_t nn = (uint64_t)n;
    memcpy(b, head, sizeof head);
    memcpy(b + 8, &nn, sizeof nn);
    b += STATE_HEADER;
    const double *arrays[N_STATE_ARRAYS] = {m->U, m->V, m->A, m->Up, m->beta, slip, m->fprev};
    for (int k = 0; k < N_STATE_ARRAYS; ++k, b += nb) {
        if (arrays[k] != slip || !(h > 0)) {
            memcpy(b, arrays[k], nb);
            continue;
        }
        for (size_t i = 0; i < n; ++i) {
            const double rate = fabs(slip[i]) / h;
            memcpy(b + i * sizeof rate, &rate, sizeof rate);
        }
    }
    const double scalars[N_STATE_DOUBLES] = {m->time, m->friction_force, m->reaction, m->normal_force,
                                             m->beta_removed};
    memcpy(b, scalars, sizeof scalars);
    b += sizeof scalars;
    const int64_t counts[N_STATE_INTS] = {(int64_t)m->n_steps, (int64_t)m->clamp_count};
    memcpy(b, counts, sizeof counts);
    b += sizeof counts;
    memcpy(b, m->contact, n);
}

static void write_state(const tc_stripdraw *m, unsigned char *b) {
    write_image(m, b, m->slip_h > 0 ? m->dU : m->slip_rate, m->slip_h);
}

/* the state image of a user's set_state, or of the backup (the slip rates as the backup held them) */
static void read_state(tc_stripdraw *m, const unsigned char *b) {
    const size_t n = m->n, nb = n * sizeof(double);
    b += STATE_HEADER;
    double *arrays[N_STATE_ARRAYS] = {m->U, m->V, m->A, m->Up, m->beta, m->slip_rate, m->fprev};
    for (int k = 0; k < N_STATE_ARRAYS; ++k, b += nb) memcpy(arrays[k], b, nb);
    double scalars[N_STATE_DOUBLES];
    memcpy(scalars, b, sizeof scalars);
    b += sizeof scalars;
    m->time = scalars[0];
    m->friction_force = scalars[1];
    m->reaction = scalars[2];
    m->normal_force = scalars[3];
    m->beta_removed = scalars[4];
    int64_t counts[N_STATE_INTS];
    memcpy(counts, b, sizeof counts);
    b += sizeof counts;
    m->n_steps = (long long)counts[0];
    m->clamp_count = (long long)counts[1];
    memcpy(m->contact, b, n);
    m->slip_h = 0.0;
    m->beta_hi = NAN;
    update_weights(m); /* derived, as set_state recomputes _w */
}

/* The state before a step (restore_state brings it back if the step is refused): the state image with the
 * slip rates as they are held (unformed: dU, and slip_h). */
static void backup_state(tc_stripdraw *m) {
    write_image(m, m->backup, m->slip_h > 0 ? m->dU : m->slip_rate, 0.0);
    m->backup_slip_h = m->slip_h;
}

static void restore_state(tc_stripdraw *m) {
    read_state(m, m->backup); /* bit-identical: arrays, scalars, and the weights recomputed from U */
    if (m->backup_slip_h > 0) { /* the image holds dU */
        memcpy(m->dU, m->slip_rate, m->n * sizeof *m->dU);
        m->slip_h = m->backup_slip_h;
    }
}

size_t tc_stripdraw_state_size(const tc_stripdraw *m) { return m->state_size; }

void tc_stripdraw_get_state(const tc_stripdraw *m, void *buf) { write_state(m, buf); }

int tc_stripdraw_set_state(tc_stripdraw *m, const void *buf, size_t size, tc_msg msg) {
    const unsigned char *b = buf;
    if (b == NULL || size != m->state_size)
        return tc_fail(msg, TC_ERROR, "strip-draw state image has %zu bytes; this model's has %zu",
                       b == NULL ? (size_t)0 : size, m->state_size);
    uint32_t head[2];
    uint64_t nn;
    memcpy(head, b, sizeof head);
    memcpy(&nn, b + 8, sizeof nn);
    if (head[0] != STATE_MAGIC || head[1] != STATE_VERSION)
        return tc_fail(msg, TC_ERROR, "not a strip-draw state image (version %u of this format is read)",
                       (unsigned)STATE_VERSION);
    if (nn != (uint64_t)m->n)
        return tc_fail(msg, TC_ERROR, "strip-draw state image has %llu nodes; this model has %zu",
                       (unsigned long long)nn, m->n);
    const unsigned char *contact = b + size - m->n;
    for (size_t i = 0; i < m->n; ++i)
        if (contact[i] > 1) return tc_fail(msg, TC_ERROR, "strip-draw state image has a contact flag that is not 0/1");
    read_state(m, b);
    return TC_OK;
}

/* ---------------------------------------------------------------------------------------------------
 * public API
 * ------------------------------------------------------------------------------------------------- */

void tc_stripdraw_free(tc_stripdraw *m) {
    if (m == NULL) return;
    free(m->pool);
    free(m->bytes);
    free(m);
}

int tc_stripdraw_create(const tc_stripdraw_params *p, const tc_table *table, const double *beta_field,
                        size_t n_beta, tc_stripdraw **out, tc_msg msg) {
    char r1[TC_REPR_SIZE];
    if (out == NULL) return tc_fail(msg, TC_ERROR, "tc_stripdraw_create: no place for the model (out is NULL)");
    *out = NULL;
    if (p == NULL) return tc_fail(msg, TC_ERROR, "tc_stripdraw_create: no parameters (p is NULL)");
    if (p->friction_model < 0 || p->friction_model > 2)
        return tc_fail(msg, TC_ERROR, "friction_model = %d is not allowed; choose 0 (table), 1 (closed_form) or 2 "
                       "(constant)", p->friction_model);
    if (p->friction_velocity < 0 || p->friction_velocity > 1)
        return tc_fail(msg, TC_ERROR, "friction_velocity = %d is not allowed; choose 0 (grip) or 1 (slip_rate)",
                       p->friction_velocity);
    if (p->table_policy < 0 || p->table_policy > 1)
        return tc_fail(msg, TC_ERROR, "table_policy = %d is not allowed; choose 0 (clamp) or 1 (error)",
                       p->table_policy);
    if (p->contact_area < 0 || p->contact_area > 1)
        return tc_fail(msg, TC_ERROR, "contact_area = %d is not allowed; choose 0 (mesoscale) or 1 (eq8)",
                       p->contact_area);
    if (p->integrator < 0 || p->integrator > 1)
        return tc_fail(msg, TC_ERROR, "integrator = %d is not allowed; choose 0 (explicit) or 1 (implicit)",
                       p->integrator);
    if (p->n_elements < 1 || p->n_elements > 100000000)
        return tc_fail(msg, TC_ERROR, "n_elements = %d is out of range; allowed: [1, 100000000]", p->n_elements);
    if (p->friction_model == TC_STRIPDRAW_FRICTION_MODEL_TABLE && table == NULL)
        return tc_fail(msg, TC_ERROR, "friction_model = 'table' needs a friction table; none was given");
    const size_t n = (size_t)p->n_elements + 1;
    if (p->friction_model == TC_STRIPDRAW_FRICTION_MODEL_TABLE && table->format_version < 2 &&
        (p->contact_area != TC_STRIPDRAW_CONTACT_AREA_MESOSCALE || p->particle_area_scale != 1.0))
        return tc_fail(msg, TC_ERROR,
                       "contact_area = '%s' with particle_area_scale = %s needs a friction table of format version 2 "
                       "(with the contact areas); this table is version 1 (mu only): rebuild it with tribocosim "
                       "surrogate table",
                       p->contact_area == TC_STRIPDRAW_CONTACT_AREA_EQ8 ? "eq8" : "mesoscale",
                       tc_repr_double(p->particle_area_scale, r1));
    const double law_threshold = law_beta_threshold(p, table);
    const double cap = p->beta_threshold > 0 ? p->beta_threshold : law_threshold;
    if (beta_field != NULL) {
        int ok = n_beta == n;
        for (size_t i = 0; ok && i < n; ++i) ok = isfinite(beta_field[i]) && !(beta_field[i] < 0);
        if (!ok)
            return tc_fail(msg, TC_ERROR,
                           "beta_field must hold %zu finite values >= 0 (one per node); got shape (%zu,)", n, n_beta);
    }
    double bmax = 0.0;
    int over = 0;
    for (size_t i = 0; i < n; ++i) {
        const double b = beta_field != NULL ? beta_field[i] : p->beta_initial;
        if (i == 0 || b > bmax) bmax = b;
        if (b > cap) over = 1;
    }
    if (over)
        return tc_fail(msg, TC_ERROR, "initial beta = %s exceeds the cap beta_threshold = %g", tc_repr_double(bmax, r1),
                       cap);

    tc_stripdraw *m = calloc(1, sizeof *m);
    if (m == NULL) return tc_fail(msg, TC_NOMEM, "out of memory for the strip-draw model");
    const int implicit = p->integrator == TC_STRIPDRAW_INTEGRATOR_IMPLICIT;
    /* one pool of doubles, in arrays of n: mesh 3, state 7, weights 1, work 11, advection 5, then the
     * explicit forces (1) or the generalized-alpha work, the overlaps of each halving level (13) and the
     * cached elimination factors */
    const size_t n_arrays = 3 + 7 + 1 + 11 + 5 +
                            (implicit ? (size_t)TC_SD_GALPHA_WORK(1) + MAX_HALVINGS + 1 + CHAIN_CACHE * TC_SD_CHAIN(1)
                                      : 1);
    m->state_size = state_size(n);
    m->pool = calloc(n_arrays * n, sizeof *m->pool);
    m->bytes = calloc(4 * n + m->state_size, 1); /* contact, clamped, generalized-alpha flags (2), backup */
    if (m->pool == NULL || m->bytes == NULL) {
        tc_stripdraw_free(m);
        return tc_fail(msg, TC_NOMEM, "out of memory for the strip-draw model (%zu nodes)", n);
    }
    double *q = m->pool;
    double **arrays[] = {&m->X,    &m->mass, &m->minv,      &m->U,  &m->V,      &m->A,      &m->Up,
                         &m->beta, &m->slip_rate, &m->fprev, &m->w,  &m->tmax,   &m->U0,     &m->w0,
                         &m->dU,   &m->weight,    &m->vel,   &m->mu, &m->ac,     &m->bsrc,   &m->bnew,
                         &m->over};
    for (size_t k = 0; k < sizeof arrays / sizeof arrays[0]; ++k, q += n) *arrays[k] = q;
    m->awork = q;
    q += 5 * n;
    if (implicit) {
        m->gwork = q;
        m->ov = q + TC_SD_GALPHA_WORK(n);
        m->chain = m->ov + (MAX_HALVINGS + 1) * n;
    } else {
        m->fwork = q;
    }
    m->contact = (signed char *)m->bytes;
    m->clamped = m->bytes + n;
    m->giwork = (signed char *)(m->bytes + 2 * n);
    m->backup = m->bytes + 4 * n;

    m->p = *p;
    m->table = p->friction_model == TC_STRIPDRAW_FRICTION_MODEL_TABLE ? table : NULL;
    m->n = n;
    m->beta_cap = cap;
    m->law_threshold = law_threshold;
    /* mesh.BarMesh.build */
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
    m->dt_explicit = p->cfl_safety * (2.0 / sqrt((4.0 * m->ke + node_ks) / m->mass[1])); /* critical_time_step */
    for (size_t i = 0; i < n; ++i) m->minv[i] = 1.0 / m->mass[i];
    const double r = p->rho_inf;
    m->am = (2.0 * r - 1.0) / (r + 1.0);
    m->af = r / (r + 1.0);
    m->gamma = 0.5 - m->am + m->af;
    m->beta_nm = 0.25 * pow(1.0 - m->am + m->af, 2.0); /* Python's float ** 2 is pow() */
    /* math.ceil(window_courant) + 1, kept within [-n, n] (where it acts as +-infinity) */
    const double reach = ceil(p->window_courant) + 1.0;
    if (reach >= -(double)n && reach <= (double)n)
        m->reach = (long long)reach;
    else
        m->reach = reach < 0 ? -(long long)n : (long long)n;
    /* state */
    for (size_t i = 0; i < n; ++i) m->beta[i] = beta_field != NULL ? beta_field[i] : p->beta_initial;
    m->beta_hi = NAN; /* the first interval caps every node */
    m->over_lo = 0;
    m->over_hi = n - 1;
    update_weights(m);
    *out = m;
    return TC_OK;
}

int tc_stripdraw_step(tc_stripdraw *m, double dt, double normal_force, double grip_velocity, tc_msg msg) {
    const double none[2] = {0.0, 0.0};
    return tc_stripdraw_step_poly(m, dt, normal_force, none, grip_velocity, none, msg);
}

int tc_stripdraw_step_poly(tc_stripdraw *m, double dt, double normal_force, const double d_normal_force[2],
                           double grip_velocity, const double d_grip_velocity[2], tc_msg msg) {
    static const char *const names[4] = {"d(normal_force)/dt", "d2(normal_force)/dt2", "d(grip_velocity)/dt",
                                         "d2(grip_velocity)/dt2"};
    const double d[4] = {d_normal_force[0], d_normal_force[1], d_grip_velocity[0], d_grip_velocity[1]};
    char r1[TC_REPR_SIZE];
    if (!isfinite(dt))
        return tc_fail(msg, TC_DISCARD, "dt = %s is not finite; a finite number is required", tc_repr_double(dt, r1));
    if (dt <= 0) return tc_fail(msg, TC_DISCARD, "dt = %s s must be > 0", tc_repr_double(dt, r1));
    if (!isfinite(normal_force))
        return tc_fail(msg, TC_DISCARD, "normal_force = %s is not finite; a finite number is required",
                       tc_repr_double(normal_force, r1));
    if (normal_force < 0)
        return tc_fail(msg, TC_DISCARD, "normal_force = %s N must be >= 0", tc_repr_double(normal_force, r1));
    if (!isfinite(grip_velocity))
        return tc_fail(msg, TC_DISCARD, "grip_velocity = %s is not finite; a finite number is required",
                       tc_repr_double(grip_velocity, r1));
    for (int k = 0; k < 4; ++k)
        if (!isfinite(d[k]))
            return tc_fail(msg, TC_DISCARD, "%s = %s is not finite; a finite number is required", names[k],
                           tc_repr_double(d[k], r1));
    const double fn[3] = {normal_force, d[0], 0.5 * d[1]}, vg[3] = {grip_velocity, d[2], 0.5 * d[3]};
    backup_state(m);
    int rc = advance(m, dt, fn, vg, msg);
    if (rc == TC_OK) {
        double probe[4] = {0.0, 0.0, 0.0, 0.0}; /* 0 x U is NaN for an infinite or NaN U, else 0 */
        for (size_t i = 0; i < m->n; i += 4)
            for (size_t k = 0; k < 4 && i + k < m->n; ++k) probe[k] += 0.0 * m->U[i + k];
        const int finite = isfinite(m->reaction) && isfinite(probe[0] + probe[1] + probe[2] + probe[3]);
        if (!finite) rc = tc_fail(msg, TC_DISCARD, "non-finite bar state at t = %.9g s", m->time + dt);
    }
    if (rc != TC_OK) {
        restore_state(m);
        return rc;
    }
    m->time = m->time + dt;
    m->n_steps += 1;
    return TC_OK;
}

void tc_stripdraw_outputs(const tc_stripdraw *m, double out[TC_STRIPDRAW_N_OUTPUTS]) {
    const size_t n = m->n;
    const double fn = m->normal_force;
    /* the contact-weighted means over the nodes with a weight (the others add 0; NumPy's w @ U rounds in its own
     * order anyway: the module docstring of tests/native/test_native_stripdraw.py) */
    double wsum = 0.0, wu = 0.0, wb = 0.0;
    for (size_t i = m->w_first; i <= m->w_last && i < n; ++i) {
        wsum += m->w[i];
        wu += m->w[i] * m->U[i];
        wb += m->w[i] * m->beta[i];
    }
    const double bmax = largest(m->beta, n, 0);
    out[TC_STRIPDRAW_PULL_FORCE] = 2.0 * m->reaction;
    out[TC_STRIPDRAW_FRICTION_FORCE] = m->friction_force;
    out[TC_STRIPDRAW_MU_MEAN] = fn > 0 ? m->friction_force / fn : 0.0;
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

void tc_stripdraw_window(const tc_stripdraw *m, double window[2]) {
    window[0] = m->a_lo;
    window[1] = m->a_hi;
}

double tc_stripdraw_time(const tc_stripdraw *m) { return m->time; }

double tc_stripdraw_beta_cap(const tc_stripdraw *m) { return m->beta_cap; }

double tc_stripdraw_explicit_time_step(const tc_stripdraw *m) { return m->dt_explicit; }
