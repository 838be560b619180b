/* Debris on the strip under the pad (paper Sec. 3, Eq. 12-14, 24, 37; docs/model.md section 3): production, transport
 * and cap of the debris area fraction beta over one coupling interval of the strip-draw model (tc_stripdraw.c).
 *
 * - source (Eq. 37): the Archard wear of the interval's slide, K P |dU_i| w_i / (H h_p), with w_i the contact weight
 *   averaged over the interval;
 * - sink (debris_sink_length lambda > 0: lateral ejection or compaction into a transfer layer): source and sink are one
 *   local equation per unit slide s under the pad, d beta / ds = q - beta / lambda (q = K P / (H h_p)), integrated
 *   exactly over the interval's slide s_i = w_i |dU_i|: beta_i e^(-s_i/lambda) + q lambda (1 - e^(-s_i/lambda));
 *   source and sink of a node are tc_debris_source and tc_debris_sunk (tc_debris_node.h), the formula a forming code's contact point
 *   evaluates too (tc_node_friction.c);
 * - transport (Eq. 13-14): implicit upwind advection with the tool-carried flux -zeta u beta (u = face velocity)
 *   between nodes that are both under the pad: a tridiagonal M-matrix with unit column sums, so beta >= 0 and
 *   sum(beta) is conserved for any step;
 * - cap (Eq. 24): beta <= beta_thres, the law's cap at the interval's pressure and grip speed unless beta_threshold
 *   is set (tc_friction.h).
 * What the sink and the cap take is summed (beta_removed), what the source makes too (beta_produced).
 */
#include "tc_debris.h"

#include <math.h>
#include <string.h>

#include "tc_debris_node.h"
#include "tc_friction.h"
#include "tc_kernels.h"
#include "tc_stripdraw_model.h"

/* implicit upwind advection of beta under the pad (Eq. 13-14); work holds 5 n doubles */
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
    int lower = 0; /* whether a subdiagonal entry is nonzero */
    for (size_t k = 0; k + 1 < n; ++k) {
        const size_t a = lo + k, b = a + 1;
        if (weight[a] > 0.0 && weight[b] > 0.0) {
            /* face Courant number; upwind: from node k+1 into k when c > 0, from k into k+1 otherwise */
            const double c = zeta * 0.5 * (dU[a] + dU[b]) / element_length;
            if (c > 0.0) {
                diag[k + 1] += c;
                sup[k] -= c;
            } else {
                diag[k] -= c;
                sub[k + 1] += c;
                lower |= c != 0.0;
            }
        }
    }
    /* rhs is only read before x is written */
    tc_thomas(n, lower ? sub : NULL, diag, sup, beta + lo, out + lo, tw);
}

/* the cap of beta of an interval at pressure P and grip speed (Eq. 24), kept for the last (P, speed) */
static double interval_cap(struct tc_stripdraw *m, double pressure, double speed) {
    if (m->p.beta_threshold > 0) return m->beta_cap;
    if (!(m->cap_known && pressure == m->cap_pressure && speed == m->cap_speed)) {
        m->cap_value = tc_law_beta_cap(&m->p, m->table, pressure, speed, &m->rows);
        m->cap_pressure = pressure;
        m->cap_speed = speed;
        m->cap_known = 1;
    }
    return fmin(m->beta_cap, m->cap_value);
}

/* beta_i = min(b_i, cap) for i in [a, e), what the cap takes added to *removed (in the order of i), *finite cleared
 * when a b_i is not finite */
static void cap_range(const double *b, double *beta, size_t a, size_t e, double cap, double *removed, int *finite) {
    double r = *removed;
    int ok = *finite;
    for (size_t i = a; i < e; ++i) {
        const double bi = b[i];
        if (bi > cap) r += bi - cap;
        beta[i] = bi > cap ? cap : bi;
        ok &= isfinite(bi);
    }
    *removed = r;
    *finite = ok;
}

void tc_sd_debris_interval(struct tc_stripdraw *m, double pressure, double speed, const double *w0, size_t f0,
                           size_t l0, int du_finite) {
    const tc_stripdraw_params *p = &m->p;
    const size_t n = m->n;
    const double kp = p->archard_k * pressure, hh = p->hardness * p->particle_thickness;
    size_t t0 = f0 < m->w_first ? f0 : m->w_first, t1 = l0 > m->w_last ? l0 : m->w_last;
    if (f0 > l0) t0 = m->w_first, t1 = m->w_last;
    if (m->w_first > m->w_last) t0 = f0, t1 = l0;
    const int windowed = isfinite(kp) && du_finite && m->beta_hi == m->beta_hi;
    if (!windowed) t0 = 0, t1 = n - 1;
    const double cap = interval_cap(m, pressure, speed);
    if (t0 <= t1) {
        double produced = 0.0, sunk = 0.0;
        const double lambda = p->debris_sink_length;
        for (size_t i = t0; i <= t1; ++i) {
            m->weight[i] = 0.5 * (w0[i] + m->w[i]);
            const double slide = m->weight[i] * fabs(m->dU[i]); /* s of the interval under the pad */
            const double src = tc_debris_source(fabs(m->dU[i]), m->weight[i], kp, hh);
            m->bsrc[i] = m->beta[i] + src;
            if (lambda > 0 && slide > 0) {
                const double b = tc_debris_sunk(m->beta + i, src, slide, lambda);
                sunk += m->bsrc[i] - b;
                m->bsrc[i] = b;
            }
            produced += src;
        }
        m->beta_produced += produced;
        m->beta_removed += sunk;
        tc_sd_advect(t1 + 1 - t0, m->bsrc + t0, m->dU + t0, m->weight + t0, p->zeta, m->le, m->bnew + t0, m->awork);
    }
    /* the cap: over every node unless it is >= every beta away from [t0, t1]; the new beta of [t0, t1] is bnew */
    double removed = 0.0;
    int finite = 1;
    if (t0 > t1) {
        if (!(windowed && cap >= m->beta_hi)) cap_range(m->beta, m->beta, 0, n, cap, &removed, &finite);
    } else {
        const int all = !(windowed && cap >= m->beta_hi);
        if (all) cap_range(m->beta, m->beta, 0, t0, cap, &removed, &finite);
        cap_range(m->bnew, m->beta, t0, t1 + 1, cap, &removed, &finite);
        if (all) cap_range(m->beta, m->beta, t1 + 1, n, cap, &removed, &finite);
    }
    m->beta_hi = finite ? cap : NAN;
    m->beta_removed += removed;
}

