/* Trilinear lookup of mu(P, v, beta), or of an area array of a version 2 table, in a friction table.
 *
 * Each axis is located so: the query is clamped to [axis_0, axis_last], the
 * cell index is i = min(searchsorted(axis, q, "right") - 1, n - 2) and the local coordinate
 * t = (q - axis_i) / (axis_{i+1} - axis_i) (i = 0, t = 0 on a one-point axis). The pressure is located
 * once and the table interpolated linearly in P to a (v, beta) plane,
 *
 *     plane(iv, ib) = (1 - tp) mu[ip, iv, ib] + tp mu[ip + 1, iv, ib]      (mu[0, iv, ib] if nP = 1),
 *
 * then bilinearly in (|v|, beta):
 *
 *     mu = (1 - tv) ((1 - tb) plane(iv, ib) + tb plane(iv, ib + sb))
 *          + tv ((1 - tb) plane(iv + sv, ib) + tb plane(iv + sv, ib + sb)),
 *
 * with sv, sb = 1 (0 on a one-point axis). A query outside an axis is flagged (clamp policy) or refused
 * (error policy: pressure first, then the first velocity, then the first beta outside the table). A query within
 * AXIS_END_TOLERANCE of an axis end (relative to the end) is on the end, not outside: that is the round-off of the
 * inputs (a press holding a set-point equal to the last pressure delivers it to within 1e-15, on either side), and
 * it moves a value by far less than the table's standard errors (10 % of A_p at most).
 */
#include "tc_table_lookup.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>


#define AXIS_END_TOLERANCE 1e-9 /* relative; components/stripdraw/table.py reads the same */

static int outside(const double *axis, size_t n, double q) {
    return q < axis[0] - AXIS_END_TOLERANCE * fabs(axis[0]) || q > axis[n - 1] + AXIS_END_TOLERANCE * fabs(axis[n - 1]);
}

/* the cell and the local coordinate of one query */
static void locate(const double *axis, size_t n, double q, size_t *i, double *t) {
    double qc = q < axis[0] ? axis[0] : q;
    qc = qc > axis[n - 1] ? axis[n - 1] : qc;
    if (n == 1) {
        *i = 0;
        *t = 0.0;
        return;
    }
    size_t lo = 0, hi = n; /* the first k with qc < axis[k] */
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (qc < axis[mid])
            hi = mid;
        else
            lo = mid + 1;
    }
    size_t k = lo > 0 ? lo - 1 : 0;
    if (k > n - 2) k = n - 2;
    *i = k;
    *t = (qc - axis[k]) / (axis[k + 1] - axis[k]);
}

/* locate() of a query that is likely in cell h (the cell of the query before): on an increasing axis of n >= 2 points
 * the cell of the clamped query qc is the one k <= n - 2 with axis_k <= qc < axis_k+1 (or k = n - 2), which the
 * bisection finds; a query in cell h is given that cell without it. The same cell and coordinate as locate();
 * returns whether q is outside the axis (as outside()). */
static int locate_near(const double *axis, size_t n, double q, size_t h, size_t *i, double *t) {
    double qc = q < axis[0] ? axis[0] : q;
    qc = qc > axis[n - 1] ? axis[n - 1] : qc;
    if (n > 1 && h <= n - 2 && axis[h] <= qc && (h == n - 2 || qc < axis[h + 1])) {
        *i = h;
        *t = (qc - axis[h]) / (axis[h + 1] - axis[h]);
    } else {
        locate(axis, n, q, i, t);
    }
    return outside(axis, n, q);
}

static int domain_error(const char *name, const char *unit, double bad, const double *axis, size_t n, tc_msg msg) {
    char r[TC_REPR_SIZE];
    return tc_fail(msg, TC_DISCARD, "friction table lookup %s = %s %s is outside the table's range [%g, %g] %s", name,
                   tc_repr_double(bad, r), unit, axis[0], axis[n - 1], unit);
}

/* bilinear in (|v|, beta) between the P-interpolated values at a cell's four corners */
static double bilinear(double p00, double p01, double p10, double p11, double tv, double tb) {
    return (1.0 - tv) * ((1.0 - tb) * p00 + tb * p01) + tv * ((1.0 - tb) * p10 + tb * p11);
}

/* The P-interpolated (v, beta) plane of one array at the four corners of a cell, then bilinear in (|v|, beta). */
static double interpolate(const double *m0, const double *m1, double tp, size_t c00, size_t c01, size_t c10,
                          size_t c11, double tv, double tb) {
    double p00, p01, p10, p11;
    if (m1 == NULL) {
        p00 = m0[c00];
        p01 = m0[c01];
        p10 = m0[c10];
        p11 = m0[c11];
    } else {
        p00 = (1.0 - tp) * m0[c00] + tp * m1[c00];
        p01 = (1.0 - tp) * m0[c01] + tp * m1[c01];
        p10 = (1.0 - tp) * m0[c10] + tp * m1[c10];
        p11 = (1.0 - tp) * m0[c11] + tp * m1[c11];
    }
    return bilinear(p00, p01, p10, p11, tv, tb);
}

#define ROWS_MAX 64 /* beta axes up to this length get the rows of one velocity cell interpolated in P once */

/* Every query at one velocity v (the grip's, for every node): the two velocity rows of its cell interpolated in P
 * once (values m, and b when not NULL), then each query bilinear in (|v|, beta): the numbers interpolate() gives,
 * with fewer operations. */
static void lookup_rows(const tc_table *table, const double *m0, const double *m1, const double *b0, const double *b1,
                        double tp, double v, size_t n, const double *beta, int outpv, double *out, double *out_b,
                        unsigned char *clamped) {
    const size_t nv = table->n_velocity, nb = table->n_beta, sv = nv > 1 ? 1 : 0, sb = nb > 1 ? 1 : 0;
    double rows[4][ROWS_MAX]; /* m at the cell's two velocities, then b */
    size_t iv, ib = 0;
    double tv, tb;
    locate(table->velocity, nv, v, &iv, &tv);
    for (size_t j = 0; j < nb; ++j) {
        const size_t c0 = iv * nb + j, c1 = (iv + sv) * nb + j;
        rows[0][j] = (1.0 - tp) * m0[c0] + tp * m1[c0];
        rows[1][j] = (1.0 - tp) * m0[c1] + tp * m1[c1];
        if (b0 != NULL) {
            rows[2][j] = (1.0 - tp) * b0[c0] + tp * b1[c0];
            rows[3][j] = (1.0 - tp) * b0[c1] + tp * b1[c1];
        }
    }
    for (size_t k = 0; k < n; ++k) {
        const int outb = locate_near(table->beta, nb, beta[k], ib, &ib, &tb); /* neighbours: mostly the same cell */
        out[k] = bilinear(rows[0][ib], rows[0][ib + sb], rows[1][ib], rows[1][ib + sb], tv, tb);
        if (b0 != NULL) out_b[k] = bilinear(rows[2][ib], rows[2][ib + sb], rows[3][ib], rows[3][ib + sb], tv, tb);
        if (clamped != NULL) clamped[k] = (unsigned char)(outpv || outb);
    }
}

int tc_table_lookup2(const tc_table *table, const double *values, const double *values_b, double pressure, size_t n,
                     const double *velocity, const double *beta, int policy, double *out, double *out_b,
                     unsigned char *clamped, tc_msg msg) {
    if (policy != TC_TABLE_CLAMP && policy != TC_TABLE_ERROR)
        return tc_fail(msg, TC_ERROR, "table policy = %d is not allowed; choose clamp (%d) or error (%d)", policy,
                       TC_TABLE_CLAMP, TC_TABLE_ERROR);
    const size_t nP = table->n_pressure, nv = table->n_velocity, nb = table->n_beta;
    const int outp = outside(table->pressure, nP, pressure);
    if (policy == TC_TABLE_ERROR) {
        if (outp) return domain_error("pressure", "Pa", pressure, table->pressure, nP, msg);
        for (size_t k = 0; k < n; ++k)
            if (outside(table->velocity, nv, fabs(velocity[k])))
                return domain_error("velocity", "m/s", fabs(velocity[k]), table->velocity, nv, msg);
        for (size_t k = 0; k < n; ++k)
            if (outside(table->beta, nb, beta[k]))
                return domain_error("beta", "1", beta[k], table->beta, nb, msg);
    }
    size_t ip, iv = 0, ib = 0;
    double tp, tv = 0.0, tb;
    locate(table->pressure, nP, pressure, &ip, &tp);
    const size_t sv = nv > 1 ? 1 : 0, sb = nb > 1 ? 1 : 0;
    const size_t plane = nv * nb;
    const double *m0 = values + ip * plane, *m1 = nP > 1 ? values + (ip + 1) * plane : NULL;
    const double *b0 = values_b != NULL ? values_b + ip * plane : NULL;
    const double *b1 = values_b != NULL && nP > 1 ? values_b + (ip + 1) * plane : NULL;
    int one_velocity = n > 1 && nP > 1 && nb <= ROWS_MAX;
    if (one_velocity) { /* every |v| the first's (compared without an exit test per query) */
        const double v0 = fabs(velocity[0]);
        for (size_t k = 1; k < n; ++k) one_velocity &= fabs(velocity[k]) == v0;
    }
    if (one_velocity) {
        const double v = fabs(velocity[0]);
        lookup_rows(table, m0, m1, b0, b1, tp, v, n, beta, outp || outside(table->velocity, nv, v), out, out_b,
                    clamped);
        return TC_OK;
    }
    int outv = 0;
    for (size_t k = 0; k < n; ++k) {
        const double v = fabs(velocity[k]), b = beta[k];
        /* the same velocity as the query before (every node's, under friction_velocity = grip): same cell */
        if (k == 0 || !(v == fabs(velocity[k - 1]))) {
            locate(table->velocity, nv, v, &iv, &tv);
            outv = outside(table->velocity, nv, v);
        }
        const int outb = locate_near(table->beta, nb, b, ib, &ib, &tb);
        const size_t c00 = iv * nb + ib, c01 = iv * nb + ib + sb, c10 = (iv + sv) * nb + ib,
                     c11 = (iv + sv) * nb + ib + sb;
        out[k] = interpolate(m0, m1, tp, c00, c01, c10, c11, tv, tb);
        if (b0 != NULL) out_b[k] = interpolate(b0, b1, tp, c00, c01, c10, c11, tv, tb);
        if (clamped != NULL) clamped[k] = (unsigned char)(outp || outv || outb);
    }
    return TC_OK;
}

int tc_table_lookup(const tc_table *table, const double *values, double pressure, size_t n, const double *velocity,
                    const double *beta, int policy, double *out, unsigned char *clamped, tc_msg msg) {
    return tc_table_lookup2(table, values, NULL, pressure, n, velocity, beta, policy, out, NULL, clamped, msg);
}

int tc_table_mu(const tc_table *table, double pressure, size_t n, const double *velocity, const double *beta,
                int policy, double *mu, unsigned char *clamped, tc_msg msg) {
    return tc_table_lookup(table, table->mu, pressure, n, velocity, beta, policy, mu, clamped, msg);
}
