/* Lookups in the friction table (tc_table_lookup.h).
 *
 * Each axis is located so: the query is clamped to [axis_0, axis_last], the cell index is
 * i = min(searchsorted(axis, q, "right") - 1, n - 2) and the local coordinate t = (q - axis_i) / (axis_{i+1} - axis_i)
 * (i = 0, t = 0 on a one-point axis); a version 4 table locates the pressure in ln P. A query within
 * AXIS_END_TOLERANCE of an axis end (relative to the end) is on the end, not outside: that is the round-off of the
 * inputs (a press holding a set-point equal to the last pressure delivers it to within 1e-15, on either side).
 *
 * Multilinear (format versions 1-3). The table is interpolated linearly in P to a (v, beta) plane,
 *
 *     plane(iv, ib) = (1 - tp) m[ip, iv, ib] + tp m[ip + 1, iv, ib]      (m[0, iv, ib] if nP = 1),
 *
 * then bilinearly in (|v|, beta):
 *
 *     m = (1 - tv) ((1 - tb) plane(iv, ib) + tb plane(iv, ib + sb)) + tv ((1 - tb) plane(iv + sv, ib) + tb plane(...)),
 *
 * with sv, sb = 1 (0 on a one-point axis).
 *
 * Monotone cubic (format version 4). Along one axis the values y_k at the nodes x_k are joined by the cubic Hermite
 * pieces of Fritsch and Butland's monotone interpolation (PCHIP, as scipy.interpolate.PchipInterpolator): with
 * h_k = x_{k+1} - x_k and the secants m_k = (y_{k+1} - y_k) / h_k, the slope at an interior node is 0 where m_{k-1}
 * and m_k differ in sign or one is 0, else the weighted harmonic mean
 *
 *     d_k = (w1 + w2) / (w1 / m_{k-1} + w2 / m_k),   w1 = 2 h_k + h_{k-1},  w2 = h_k + 2 h_{k-1},
 *
 * and at an end the one-sided three-point value d_0 = ((2 h_0 + h_1) m_0 - h_0 m_1) / (h_0 + h_1), set to 0 when its
 * sign differs from m_0's and to 3 m_0 when m_0 and m_1 differ in sign and |d_0| > 3 |m_0| (two nodes: the secant).
 * On [x_k, x_{k+1}], t = (x - x_k) / h_k, s = 1 - t:
 *
 *     y(x) = (1 + 2 t) s^2 y_k + t^2 (3 - 2 t) y_{k+1} + h_k t s (s d_k - t d_{k+1}).
 *
 * Each piece is monotone between its end values (no overshoot), a piece between equal values is flat, y is C1, and
 * the nodes are reproduced exactly. The slopes of a node are taken from its neighbours of the same kind (simulated
 * or not; a node alone of its kind takes every neighbour): the value in a cell whose nodes were all simulated depends
 * on simulated nodes only. On a piece between nodes of different kinds (whose lookups read an unsimulated node and
 * are counted) the two slopes are limited to the square 0 <= d / m <= 3 of the piece's secant m, where a cubic
 * Hermite piece is monotone (Fritsch and Carlson), so that it too stays between its end values.
 *
 * The table is interpolated so in x = ln P, node by node, to the two (v, beta) rows of the query's velocity cell: their
 * values at the beta nodes, and their slopes along beta (each table row's slopes, taken along it, interpolated in ln P
 * the same way). Each row is then the cubic Hermite pieces in beta through those values with those slopes, limited to
 * the square of each piece's secant (at a node pressure they are in it already: the row's own PCHIP), and the two rows
 * are blended linearly in |v|:
 *
 *     m = (1 - tv) row_iv(beta) + tv row_{iv + sv}(beta).
 *
 * The result is continuous in (P, v, beta), C1 in ln P and in beta where no limit acts, exact at the nodes, and no
 * piece leaves the values at its ends: monotone in beta wherever the rows' values at the beta nodes are (at every
 * node pressure where the data are; between pressure nodes where the columns keep the order of the rows).
 */
#include "tc_table_lookup.h"

#include <math.h>
#include <stdint.h>
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

/* the pressure's cell: in P (multilinear) or in ln P (monotone cubic) */
static void locate_pressure(const tc_table *t, double q, size_t *i, double *tp) {
    const size_t n = t->n_pressure;
    if (t->interpolation != TC_TABLE_MONOTONE_CUBIC || n == 1) {
        locate(t->pressure, n, q, i, tp);
        return;
    }
    double qc = q < t->pressure[0] ? t->pressure[0] : q;
    qc = qc > t->pressure[n - 1] ? t->pressure[n - 1] : qc;
    locate(t->log_pressure, n, log(qc), i, tp);
}

static int domain_error(const char *name, const char *unit, double bad, const double *axis, size_t n, tc_msg msg) {
    char r[TC_REPR_SIZE];
    return tc_fail(msg, TC_DISCARD, "friction table lookup %s = %s %s is outside the table's range [%g, %g] %s", name,
                   tc_repr_double(bad, r), unit, axis[0], axis[n - 1], unit);
}

/* whether a lookup in the cell (ip, iv, ib) at the local coordinates (tp, tv, tb) reads an unsimulated node */
static int reads_unsimulated(const tc_table *t, size_t ip, double tp, size_t iv, double tv, size_t ib, double tb) {
    if (t->unsimulated == NULL) return 0;
    const double wp[2] = {1.0 - tp, tp}, wv[2] = {1.0 - tv, tv}, wb[2] = {1.0 - tb, tb};
    for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b)
            for (int c = 0; c < 2; ++c)
                if (wp[a] * wv[b] * wb[c] > TC_TABLE_READ_WEIGHT &&
                    t->unsimulated[((ip + (size_t)a) * t->n_velocity + iv + (size_t)b) * t->n_beta + ib + (size_t)c] !=
                        0)
                    return 1;
    return 0;
}

/* ---- monotone cubic Hermite (PCHIP) along one line of the table --------------------------------------------- */

/* one line: node positions x[k], values y[k * ys], kinds u[k * us] (1: unsimulated; u NULL: all of one kind) */
typedef struct {
    const double *x, *y, *u;
    size_t ys, us, n;
} line;

static double sgn(double v) { return (double)((v > 0) - (v < 0)); }

static double secant(const line *L, size_t k) {
    return (L->y[(k + 1) * L->ys] - L->y[k * L->ys]) / (L->x[k + 1] - L->x[k]);
}

static int same_kind(const line *L, size_t a, size_t b) { return L->u == NULL || L->u[a * L->us] == L->u[b * L->us]; }

/* the one-sided three-point slope at an end (h0, m0: the end's piece; h1, m1: the next), shape-preserving */
static double end_slope(double h0, double h1, double m0, double m1) {
    const double d = ((2.0 * h0 + h1) * m0 - h0 * m1) / (h0 + h1);
    if (sgn(d) != sgn(m0)) return 0.0;
    if (sgn(m0) != sgn(m1) && fabs(d) > 3.0 * fabs(m0)) return 3.0 * m0;
    return d;
}

/* the slope at node k from its neighbours of its kind (every neighbour for a node alone of its kind) */
static double slope_at(const line *L, size_t k) {
    const size_t n = L->n;
    if (n < 2) return 0.0;
    const int left = k > 0 && same_kind(L, k - 1, k), right = k + 1 < n && same_kind(L, k + 1, k);
    if (!left && !right) {
        const line all = {L->x, L->y, NULL, L->ys, 0, L->n};
        return slope_at(&all, k);
    }
    const double *x = L->x;
    if (left && right) {
        const double m0 = secant(L, k - 1), m1 = secant(L, k);
        if (sgn(m0) != sgn(m1) || m0 == 0.0 || m1 == 0.0) return 0.0;
        const double h0 = x[k] - x[k - 1], h1 = x[k + 1] - x[k];
        const double w1 = 2.0 * h1 + h0, w2 = h1 + 2.0 * h0;
        return (w1 + w2) / (w1 / m0 + w2 / m1);
    }
    if (right) {
        if (k + 2 < n && same_kind(L, k + 2, k))
            return end_slope(x[k + 1] - x[k], x[k + 2] - x[k + 1], secant(L, k), secant(L, k + 1));
        return secant(L, k);
    }
    if (k >= 2 && same_kind(L, k - 2, k))
        return end_slope(x[k] - x[k - 1], x[k - 1] - x[k - 2], secant(L, k - 1), secant(L, k - 2));
    return secant(L, k - 1);
}

/* the cubic Hermite piece from (0, y0) with slope d0 to (h, y1) with slope d1 at t = x / h */
static double hermite(double y0, double y1, double d0, double d1, double h, double t) {
    const double s = 1.0 - t;
    return (1.0 + 2.0 * t) * s * s * y0 + t * t * (3.0 - 2.0 * t) * y1 + h * t * s * (s * d0 - t * d1);
}

/* A node slope on a piece whose end nodes are of different kinds (each slope taken on its own side), limited to the
 * square 0 <= d / m <= 3 of the piece's secant m, where a cubic Hermite piece is monotone (Fritsch and Carlson). */
static double limited(double d, double m) {
    if (m == 0.0 || sgn(d) != sgn(m)) return 0.0;
    return fabs(d) > 3.0 * fabs(m) ? 3.0 * m : d;
}

/* the slopes of the piece from node k to k + 1 of a line from its nodes' slopes d0, d1: limited where the nodes are of
 * different kinds */
static void piece_slopes(const line *L, size_t k, double *d0, double *d1) {
    if (same_kind(L, k, k + 1)) return;
    const double m = secant(L, k);
    *d0 = limited(*d0, m);
    *d1 = limited(*d1, m);
}

/* the piece from node k to k + 1 of a line with the node slopes d0, d1 at t */
static double piece(const line *L, size_t k, double d0, double d1, double t) {
    piece_slopes(L, k, &d0, &d1);
    return hermite(L->y[k * L->ys], L->y[(k + 1) * L->ys], d0, d1, L->x[k + 1] - L->x[k], t);
}


/* The two (v, beta) rows of the velocity cell (iv, iv + sv) of one array at the pressure (ip, tp): their values at the
 * beta nodes and their slopes along beta, both interpolated monotone cubic in ln P from the table's rows (the slopes
 * of a table row taken along it, from each node's neighbours of its kind). */
typedef struct {
    double y[2][TC_TABLE_BETA_MAX], d[2][TC_TABLE_BETA_MAX];
} cubic_rows;

#define P_WINDOW 6 /* the pressure rows the slopes at ip and ip + 1 of a column read: ip - 2 to ip + 3 */

static void cubic_rows_at(const tc_table *t, const double *values, size_t ip, double tp, size_t iv, size_t sv,
                          cubic_rows *r) {
    const size_t nP = t->n_pressure, nv = t->n_velocity, nb = t->n_beta, plane = nv * nb;
    const double *u = t->unsimulated;
    const size_t lo = ip >= 2 ? ip - 2 : 0, hi = ip + 3 < nP ? ip + 3 : nP - 1;
    double rs[P_WINDOW][TC_TABLE_BETA_MAX]; /* the slopes along beta of the table rows lo..hi */
    for (size_t row = 0; row < 2; ++row) {
        const size_t j = iv + row * sv;
        for (size_t i = lo; i <= hi; ++i) {
            const size_t at = i * plane + j * nb;
            const line b = {t->beta, values + at, u != NULL ? u + at : NULL, 1, 1, nb};
            for (size_t k = 0; k < nb; ++k) rs[i - lo][k] = slope_at(&b, k);
        }
        for (size_t k = 0; k < nb; ++k) {
            const size_t at = j * nb + k;
            if (nP == 1) {
                r->y[row][k] = values[at];
                r->d[row][k] = rs[0][k];
                continue;
            }
            const line col = {t->log_pressure, values + at, u != NULL ? u + at : NULL, plane, plane, nP};
            r->y[row][k] = piece(&col, ip, slope_at(&col, ip), slope_at(&col, ip + 1), tp);
            const line dcol = {t->log_pressure + lo, &rs[0][k], u != NULL ? u + lo * plane + at : NULL,
                               TC_TABLE_BETA_MAX, plane, hi - lo + 1};
            r->d[row][k] = piece(&dcol, ip - lo, slope_at(&dcol, ip - lo), slope_at(&dcol, ip - lo + 1), tp);
        }
    }
}

/* the slopes of the piece from beta node k to k + 1 of a row, limited to the square 0 <= d / m <= 3 of its secant m
 * (where a cubic Hermite piece is monotone: at a table row the slopes are in it already) */
static void row_piece_slopes(const tc_table *t, const cubic_rows *r, int row, size_t k, double *d0, double *d1) {
    const double m = (r->y[row][k + 1] - r->y[row][k]) / (t->beta[k + 1] - t->beta[k]);
    *d0 = limited(r->d[row][k], m);
    *d1 = limited(r->d[row][k + 1], m);
}

/* the rows' value at the beta cell (ib, tb), linear in v between them */
static double cubic_value(const tc_table *t, const cubic_rows *r, double tv, size_t ib, double tb) {
    double at[2];
    for (int row = 0; row < 2; ++row) {
        if (t->n_beta == 1) {
            at[row] = r->y[row][0];
            continue;
        }
        double d0, d1;
        row_piece_slopes(t, r, row, ib, &d0, &d1);
        at[row] = hermite(r->y[row][ib], r->y[row][ib + 1], d0, d1, t->beta[ib + 1] - t->beta[ib], tb);
    }
    return tv == 0.0 ? at[0] : (1.0 - tv) * at[0] + tv * at[1];
}

static void cubic_lookup(const tc_table *t, const double *values, const double *values_b, size_t ip, double tp,
                         int outp, size_t n, const double *velocity, const double *beta, double *out, double *out_b,
                         unsigned char *clamped) {
    const size_t nv = t->n_velocity, nb = t->n_beta, sv = nv > 1 ? 1 : 0;
    cubic_rows ra, rb;
    size_t iv = 0, ib = 0, cell = SIZE_MAX;
    double tv = 0.0, tb;
    int outv = 0;
    for (size_t k = 0; k < n; ++k) {
        const double v = fabs(velocity[k]);
        if (k == 0 || !(v == fabs(velocity[k - 1]))) {
            locate(t->velocity, nv, v, &iv, &tv);
            outv = outside(t->velocity, nv, v);
            if (iv != cell) {
                cubic_rows_at(t, values, ip, tp, iv, sv, &ra);
                if (values_b != NULL) cubic_rows_at(t, values_b, ip, tp, iv, sv, &rb);
                cell = iv;
            }
        }
        const int outb = locate_near(t->beta, nb, beta[k], ib, &ib, &tb);
        out[k] = cubic_value(t, &ra, tv, ib, tb);
        if (values_b != NULL) out_b[k] = cubic_value(t, &rb, tv, ib, tb);
        if (clamped != NULL)
            clamped[k] = (unsigned char)(outp || outv || outb || reads_unsimulated(t, ip, tp, iv, tv, ib, tb));
    }
}

/* ---- multilinear --------------------------------------------------------------------------------------------- */

#define ROWS_MAX 64 /* beta axes up to this length get the rows of one velocity cell interpolated in P once */

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

/* Every query at one velocity v (the grip's, for every node): the two velocity rows of its cell interpolated in P
 * once (values m, and b when not NULL), then each query bilinear in (|v|, beta): the numbers interpolate() gives,
 * with fewer operations. */
static void lookup_rows(const tc_table *table, const double *m0, const double *m1, const double *b0, const double *b1,
                        size_t ip, double tp, double v, size_t n, const double *beta, int outpv, double *out,
                        double *out_b, unsigned char *clamped) {
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
        if (clamped != NULL)
            clamped[k] = (unsigned char)(outpv || outb || reads_unsimulated(table, ip, tp, iv, tv, ib, tb));
    }
}

static void multilinear_lookup(const tc_table *table, const double *values, const double *values_b, size_t ip,
                               double tp, int outp, size_t n, const double *velocity, const double *beta, double *out,
                               double *out_b, unsigned char *clamped) {
    const size_t nP = table->n_pressure, nv = table->n_velocity, nb = table->n_beta;
    const size_t sv = nv > 1 ? 1 : 0, sb = nb > 1 ? 1 : 0, plane = nv * nb;
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
        lookup_rows(table, m0, m1, b0, b1, ip, tp, v, n, beta, outp || outside(table->velocity, nv, v), out, out_b,
                    clamped);
        return;
    }
    size_t iv = 0, ib = 0;
    double tv = 0.0, tb;
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
        if (clamped != NULL)
            clamped[k] = (unsigned char)(outp || outv || outb || reads_unsimulated(table, ip, tp, iv, tv, ib, tb));
    }
}

/* ---- the lookups --------------------------------------------------------------------------------------------- */

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
    size_t ip;
    double tp;
    locate_pressure(table, pressure, &ip, &tp);
    if (table->interpolation == TC_TABLE_MONOTONE_CUBIC)
        cubic_lookup(table, values, values_b, ip, tp, outp, n, velocity, beta, out, out_b, clamped);
    else
        multilinear_lookup(table, values, values_b, ip, tp, outp, n, velocity, beta, out, out_b, clamped);
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

size_t tc_table_read_nodes(const tc_table *table, double pressure, double velocity, double beta, size_t nodes[8],
                           double weights[8], int *out) {
    const size_t nv = table->n_velocity, nb = table->n_beta;
    size_t ip, iv, ib, count = 0;
    double tp, tv, tb;
    const double v = fabs(velocity);
    locate_pressure(table, pressure, &ip, &tp);
    locate(table->velocity, nv, v, &iv, &tv);
    locate(table->beta, nb, beta, &ib, &tb);
    if (out != NULL)
        *out = outside(table->pressure, table->n_pressure, pressure) || outside(table->velocity, nv, v) ||
               outside(table->beta, nb, beta);
    const double wp[2] = {1.0 - tp, tp}, wv[2] = {1.0 - tv, tv}, wb[2] = {1.0 - tb, tb};
    for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b)
            for (int c = 0; c < 2; ++c) {
                const double w = wp[a] * wv[b] * wb[c];
                if (!(w > TC_TABLE_READ_WEIGHT)) continue;
                nodes[count] = ((ip + (size_t)a) * nv + iv + (size_t)b) * nb + ib + (size_t)c;
                weights[count++] = w;
            }
    return count;
}

int tc_table_beta_line(const tc_table *table, const double *values, double pressure, double velocity, double *y,
                       double *dl, double *dr, tc_msg msg) {
    if (table->interpolation != TC_TABLE_MONOTONE_CUBIC)
        return tc_fail(msg, TC_ERROR, "the beta line is that of a version 4 table; this table is version %d",
                       table->format_version);
    const size_t nv = table->n_velocity, nb = table->n_beta, sv = nv > 1 ? 1 : 0;
    size_t ip, iv;
    double tp, tv;
    cubic_rows r;
    locate_pressure(table, pressure, &ip, &tp);
    locate(table->velocity, nv, fabs(velocity), &iv, &tv);
    cubic_rows_at(table, values, ip, tp, iv, sv, &r);
    /* a Hermite piece is linear in its data: the blend of the rows' pieces is the piece of the blended data */
    const double wa = tv == 0.0 ? 1.0 : 1.0 - tv, wb = tv;
    for (size_t k = 0; k < nb; ++k) y[k] = wa * r.y[0][k] + wb * r.y[1][k];
    for (size_t k = 0; k + 1 < nb; ++k) {
        double ends[2][2];
        for (int row = 0; row < 2; ++row) row_piece_slopes(table, &r, row, k, &ends[row][0], &ends[row][1]);
        dl[k] = wa * ends[0][0] + wb * ends[1][0];
        dr[k] = wa * ends[0][1] + wb * ends[1][1];
    }
    return TC_OK;
}

/* the cubic c0 + c1 t + c2 t^2 + c3 t^3 */
static double cubic(const double c[4], double t) { return ((c[3] * t + c[2]) * t + c[1]) * t + c[0]; }

int tc_table_first_crossing(size_t n, const double *x, const double *y, const double *dl, const double *dr,
                            double level, double *at) {
    if (n == 0) return 0;
    if (y[0] >= level) {
        *at = x[0];
        return 1;
    }
    for (size_t k = 0; k + 1 < n; ++k) {
        const double h = x[k + 1] - x[k], dy = y[k + 1] - y[k];
        /* the piece in t = (x - x_k) / h: p(0) = y_k, p(1) = y_k+1, p'(0) = h dl, p'(1) = h dr */
        const double c[4] = {y[k], h * dl[k], 3.0 * dy - h * (2.0 * dl[k] + dr[k]), -2.0 * dy + h * (dl[k] + dr[k])};
        /* the zeros of p'(t) = c1 + 2 c2 t + 3 c3 t^2 in (0, 1) split the piece into monotone parts */
        double ends[4] = {0.0, 1.0, 1.0, 1.0};
        size_t m = 1;
        const double qa = 3.0 * c[3], qb = 2.0 * c[2], qc = c[1];
        double roots[2];
        size_t nr = 0;
        if (qa == 0.0) {
            if (qb != 0.0) roots[nr++] = -qc / qb;
        } else {
            const double disc = qb * qb - 4.0 * qa * qc;
            if (disc >= 0.0) {
                const double q = -0.5 * (qb + (qb >= 0 ? sqrt(disc) : -sqrt(disc)));
                if (q != 0.0) {
                    roots[nr++] = q / qa;
                    roots[nr++] = qc / q;
                } else {
                    roots[nr++] = 0.0;
                }
            }
        }
        if (nr == 2 && roots[1] < roots[0]) {
            const double s = roots[0];
            roots[0] = roots[1];
            roots[1] = s;
        }
        for (size_t r = 0; r < nr; ++r)
            if (roots[r] > ends[m - 1] && roots[r] < 1.0) ends[m++] = roots[r];
        ends[m] = 1.0;
        for (size_t part = 0; part < m; ++part) {
            double a = ends[part], b = ends[part + 1];
            if (!(part + 1 == m ? y[k + 1] >= level : cubic(c, b) >= level)) continue;
            /* p(a) < level <= p(b), p monotone on [a, b]: bisect */
            for (int it = 0; it < 200 && (b - a) * h > TC_TABLE_CROSSING_TOL; ++it) {
                const double mid = 0.5 * (a + b);
                if (cubic(c, mid) >= level)
                    b = mid;
                else
                    a = mid;
            }
            *at = x[k] + a * h;
            return 1;
        }
    }
    return 0;
}
