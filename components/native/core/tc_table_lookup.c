/* Lookups in the friction table (tc_table_lookup.h).
 *
 * Each axis is located so: the query is clamped to [axis_0, axis_last], the cell index is
 * i = min(searchsorted(axis, q, "right") - 1, n - 2) and the local coordinate t = (q - axis_i) / (axis_{i+1} - axis_i)
 * (i = 0, t = 0 on a one-point axis); a version 4 table locates the pressure in ln P. A query within
 * TC_TABLE_AXIS_END_TOLERANCE of an axis end (relative to the end) is on the end, not outside (tc_table.h).
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
 * Monotone cubic (format version 4). Along one axis the values are joined by the cubic Hermite pieces of Fritsch and
 * Butland's monotone interpolation (PCHIP, tc_pchip.c states it), the slopes of a node taken from its neighbours of
 * the same kind (simulated or not; a node alone of its kind takes every neighbour): the value in a cell whose nodes
 * were all simulated depends on simulated nodes only. On a piece between nodes of different kinds (whose lookups read
 * an unsimulated node and are counted) the two slopes are limited to the square 0 <= d / m <= 3 of the piece's secant
 * m, so that it too stays between its end values.
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
 *
 * What a lookup computes in stages, each reused by the next: the slopes of the table's rows along beta and of each
 * piece of its columns along ln P are the table's (tc_table_cubic, made with the table); the two rows of a velocity cell
 * at a pressure, with the limited end slopes of their pieces, are made once for every query in that cell
 * (tc_table_rows, which a caller may keep); the line along beta of a query's velocity, the rows blended, once for
 * every query at that velocity (rows_line); a query evaluates one Hermite piece of the line.
 */
#include "tc_table_lookup.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "tc_pchip.h"

/* whether q is outside the axis whose ends, widened by the tolerance, are lo and hi (tc_table.h) */
static int outside(double lo, double hi, double q) { return q < lo || q > hi; }

static int outside_pressure(const tc_table *t, double q) { return outside(t->pressure_lo, t->pressure_hi, q); }
static int outside_velocity(const tc_table *t, double q) { return outside(t->velocity_lo, t->velocity_hi, q); }
static int outside_beta(const tc_table *t, double q) { return outside(t->beta_lo, t->beta_hi, q); }

/* the first k < n with q < axis[k] (n when there is none), by bisection of the increasing axis */
static size_t first_above(const double *axis, size_t n, double q) {
    size_t lo = 0, hi = n;
    while (lo < hi) {
        const size_t mid = lo + (hi - lo) / 2;
        if (q < axis[mid])
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
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
    const size_t lo = first_above(axis, n, qc);
    size_t k = lo > 0 ? lo - 1 : 0;
    if (k > n - 2) k = n - 2;
    *i = k;
    *t = (qc - axis[k]) / (axis[k + 1] - axis[k]);
}

/* locate() of a query that is likely in cell h (the cell of the query before): on an increasing axis of n >= 2 points
 * the cell of the clamped query qc is the one k <= n - 2 with axis_k <= qc < axis_k+1 (or k = n - 2), which the
 * bisection finds; a query in cell h is given that cell without it. The same cell and coordinate as locate(). */
static void locate_near(const double *axis, size_t n, double q, size_t h, size_t *i, double *t) {
    double qc = q < axis[0] ? axis[0] : q;
    qc = qc > axis[n - 1] ? axis[n - 1] : qc;
    if (n > 1 && h <= n - 2 && axis[h] <= qc && (h == n - 2 || qc < axis[h + 1])) {
        *i = h;
        *t = (qc - axis[h]) / (axis[h + 1] - axis[h]);
    } else {
        locate(axis, n, q, i, t);
    }
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

/* the pressure's cell, from rows made at this pressure when they are (locate_pressure's cell for it: the rows keep the
 * cell they were made at) */
static void pressure_cell(const tc_table *t, double q, const tc_table_rows *rows, size_t *i, double *tp) {
    if (rows != NULL && rows->filled > 0 && rows->table == t && rows->pressure == q) {
        *i = rows->ip;
        *tp = rows->tp;
        return;
    }
    locate_pressure(t, q, i, tp);
}

static int domain_error(const char *name, const char *unit, double bad, const double *axis, size_t n, tc_msg msg) {
    char r[TC_REPR_SIZE], a[TC_REPR_SIZE], b[TC_REPR_SIZE];
    return tc_fail(msg, TC_DISCARD, "friction table lookup %s = %s %s is outside the table's range [%s, %s] %s (by "
                   "more than %g of the end)", name, tc_repr_double(bad, r), unit, tc_repr_double(axis[0], a),
                   tc_repr_double(axis[n - 1], b), unit, TC_TABLE_AXIS_END_TOLERANCE);
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

/* ---- monotone cubic: the rows of a velocity cell at a pressure ------------------------------------------------ */

/* Row `row` (table velocity iv + row) of rows r at the pressure cell (ip, tp) from the monotone cubic form c: its
 * values and slopes along beta, each the Hermite piece along ln P of its column between the pressure nodes ip and
 * ip + 1 (with the piece's slopes of the form), then the limited end slopes of each piece along beta; and at each beta
 * node the largest weight in P, 1 - tp or tp, of an unsimulated node of the row's two pressure nodes (0: none). */
static void fill_row(const tc_table *t, const tc_table_cubic *c, int row, tc_table_rows *r) {
    const size_t nP = t->n_pressure, nb = t->n_beta, plane = t->n_velocity * nb, ip = r->ip;
    const size_t j = r->iv + (t->n_velocity > 1 ? (size_t)row : 0);
    const double tp = r->tp, *values = c->values, *u = t->unsimulated;
    double d[TC_TABLE_BETA_MAX], *y = r->y[row];
    const size_t at = ip * plane + j * nb;
    if (nP == 1) {
        for (size_t k = 0; k < nb; ++k) {
            y[k] = values[at + k];
            d[k] = c->beta_slope[at + k];
        }
    } else {
        const double h = t->log_pressure[ip + 1] - t->log_pressure[ip];
        const double *y0 = values + at, *y1 = values + at + plane, *s0 = c->beta_slope + at,
                     *s1 = c->beta_slope + at + plane;
        const double *vl = c->value_piece[0] + at, *vr = c->value_piece[1] + at, *sl = c->slope_piece[0] + at,
                     *sr = c->slope_piece[1] + at;
        for (size_t k = 0; k < nb; ++k) {
            y[k] = tc_pchip_hermite(y0[k], y1[k], vl[k], vr[k], h, tp);
            d[k] = tc_pchip_hermite(s0[k], s1[k], sl[k], sr[k], h, tp);
        }
    }
    for (size_t k = 0; k + 1 < nb; ++k) {
        const double m = (y[k + 1] - y[k]) / (t->beta[k + 1] - t->beta[k]);
        r->dl[row][k] = tc_pchip_limited(d[k], m);
        r->dr[row][k] = tc_pchip_limited(d[k + 1], m);
    }
    double *w = r->unsimulated[row];
    const double wp[2] = {1.0 - tp, tp};
    int reads = 0;
    for (size_t k = 0; k < nb; ++k) {
        double top = 0.0;
        for (size_t a = 0; a < 2; ++a)
            if (wp[a] > 0.0 && u != NULL && u[at + a * plane + k] != 0) top = wp[a] > top ? wp[a] : top;
        w[k] = top;
        reads |= top > TC_TABLE_READ_WEIGHT;
    }
    if (nb < TC_TABLE_BETA_MAX) w[nb] = 0.0; /* the second node of a one-point axis's cell (weight tb = 0) */
    for (size_t k = 0; k + 1 < nb || k == 0; ++k) r->unsimulated_cell[row][k] = w[k] != 0.0 || w[k + 1] != 0.0;
    r->reads_unsimulated |= reads;
}

/* The rows of the velocity cell iv at the pressure (ip, tp) (pressure: their key), the first `need` of them (1, or 2
 * when a query lies inside the cell): kept as they are when r holds them already. */
static void rows_at(const tc_table *t, const tc_table_cubic *c, double pressure, size_t ip, double tp, size_t iv,
                    int need, tc_table_rows *r) {
    if (!(r->filled > 0 && r->table == t && r->values == c->values && r->pressure == pressure && r->iv == iv)) {
        r->table = t;
        r->values = c->values;
        r->pressure = pressure;
        r->iv = iv;
        r->ip = ip;
        r->tp = tp;
        r->filled = 0;
        r->reads_unsimulated = 0;
        r->line_made = 0;
    }
    for (int row = r->filled; row < need; ++row) fill_row(t, c, row, r);
    if (need > r->filled) r->filled = need;
}

/* The line along beta at the local velocity coordinate tv of the rows' cell, made into r when it does not hold the line
 * of tv: row 0 at tv = 0, else the rows blended (both rows are made then), and whether the cell of each of its pieces
 * has a node of unsimulated weight (the last node's piece: the last cell's). */
static void rows_line(const tc_table *t, tc_table_rows *r, double tv) {
    if (r->line_made && r->line_tv == tv) return;
    const size_t nb = t->n_beta;
    if (tv == 0.0) {
        memcpy(r->line_y, r->y[0], nb * sizeof *r->line_y);
        memcpy(r->line_dl, r->dl[0], (nb - 1) * sizeof *r->line_dl);
        memcpy(r->line_dr, r->dr[0], (nb - 1) * sizeof *r->line_dr);
    } else {
        const double wa = 1.0 - tv, wb = tv;
        for (size_t k = 0; k < nb; ++k) r->line_y[k] = wa * r->y[0][k] + wb * r->y[1][k];
        for (size_t k = 0; k + 1 < nb; ++k) {
            r->line_dl[k] = wa * r->dl[0][k] + wb * r->dl[1][k];
            r->line_dr[k] = wa * r->dr[0][k] + wb * r->dr[1][k];
        }
    }
    for (size_t k = 0; k < nb; ++k) {
        const size_t ib = k + 1 == nb && nb > 1 ? k - 1 : k;
        r->line_unsimulated[k] = r->reads_unsimulated &&
                                 (r->unsimulated_cell[0][ib] || (tv != 0.0 && r->unsimulated_cell[1][ib]));
    }
    r->line_tv = tv;
    r->line_made = 1;
}

/* The piece of the line (rows_line) of a beta query clamped to the axis, qc: the k with beta_k <= qc < beta_k+1, or
 * nb - 1 at the axis's last node (where the line is its value); the piece h (of the query before) is tried first */
static size_t beta_piece(const double *axis, size_t n, double qc, size_t h) {
    if (h + 1 < n && axis[h] <= qc && qc < axis[h + 1]) return h;
    if (!(qc < axis[n - 1])) return n - 1;
    const size_t lo = first_above(axis, n, qc); /* <= n - 1 here */
    return lo > 0 ? lo - 1 : 0;
}

/* Whether the query of the clamped beta qc in piece k (beta_piece) of the line at tv, a piece whose cell has an
 * unsimulated node (line_unsimulated), reads one, as reads_unsimulated() decides it at the cell (ib, tb) locate() gives
 * (the last node: ib = nb - 2, tb = 1): a corner's weight is wp wv wb, and the largest wp of an unsimulated node at a
 * beta node times wv wb exceeds the read weight exactly when one of them does (rounding keeps the order of
 * products). */
static int rows_read_unsimulated(const tc_table *t, const tc_table_rows *r, double tv, size_t k, double qc) {
    const size_t nb = t->n_beta, ib = k + 1 == nb && nb > 1 ? k - 1 : k;
    const double tb = nb == 1 ? 0.0 : (k == ib ? (qc - t->beta[ib]) / (t->beta[ib + 1] - t->beta[ib]) : 1.0);
    const double wv[2] = {1.0 - tv, tv}, wb[2] = {1.0 - tb, tb};
    for (int b = 0; b < 2; ++b) {
        if (!(wv[b] > 0.0)) continue;
        for (size_t c = 0; c < 2; ++c)
            if (wb[c] > 0.0 && ib + c < nb && r->unsimulated[b][ib + c] * wv[b] * wb[c] > TC_TABLE_READ_WEIGHT)
                return 1;
    }
    return 0;
}

/* Every query in the monotone cubic form c at the pressure (ip, tp): the rows of a velocity cell made (or found in
 * r) when the cell changes, then each query evaluated on them. */
static void cubic_lookup(const tc_table *t, const tc_table_cubic *c, double pressure, size_t ip, double tp, int outp,
                         size_t n, const double *velocity, const double *beta, double *out, unsigned char *clamped,
                         tc_table_rows *r) {
    const size_t nv = t->n_velocity, nb = t->n_beta;
    const double *axis = t->beta, lo = axis[0], hi = axis[nb - 1];
    const double *y = r->line_y, *dl = r->line_dl, *dr = r->line_dr;
    const unsigned char *unsimulated = r->line_unsimulated;
    size_t iv = 0, k = 0;
    double tv = 0.0, vprev = 0.0;
    int outpv = 0;
    for (size_t q = 0; q < n; ++q) {
        const double v = fabs(velocity[q]);
        if (q == 0 || !(v == vprev)) {
            locate(t->velocity, nv, v, &iv, &tv);
            outpv = outp || outside_velocity(t, v);
            rows_at(t, c, pressure, ip, tp, iv, tv != 0.0 ? 2 : 1, r);
            rows_line(t, r, tv);
            vprev = v;
        }
        const double b = beta[q];
        double qc = b < lo ? lo : b;
        qc = qc > hi ? hi : qc;
        k = beta_piece(axis, nb, qc, k);
        if (k + 1 < nb) {
            const double h = axis[k + 1] - axis[k];
            out[q] = tc_pchip_hermite(y[k], y[k + 1], dl[k], dr[k], h, (qc - axis[k]) / h);
        } else {
            out[q] = y[k];
        }
        if (clamped != NULL)
            clamped[q] = (unsigned char)((outpv | outside_beta(t, b)) ||
                                         (unsimulated[k] && rows_read_unsimulated(t, r, tv, k, qc)));
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
        locate_near(table->beta, nb, beta[k], ib, &ib, &tb); /* neighbours: mostly the same cell */
        const int outb = outside_beta(table, beta[k]);
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
        lookup_rows(table, m0, m1, b0, b1, ip, tp, v, n, beta, outp || outside_velocity(table, v), out, out_b, clamped);
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
            outv = outside_velocity(table, v);
        }
        locate_near(table->beta, nb, b, ib, &ib, &tb);
        const int outb = outside_beta(table, b);
        const size_t c00 = iv * nb + ib, c01 = iv * nb + ib + sb, c10 = (iv + sv) * nb + ib,
                     c11 = (iv + sv) * nb + ib + sb;
        out[k] = interpolate(m0, m1, tp, c00, c01, c10, c11, tv, tb);
        if (b0 != NULL) out_b[k] = interpolate(b0, b1, tp, c00, c01, c10, c11, tv, tb);
        if (clamped != NULL)
            clamped[k] = (unsigned char)(outp || outv || outb || reads_unsimulated(table, ip, tp, iv, tv, ib, tb));
    }
}

/* ---- the lookups --------------------------------------------------------------------------------------------- */

/* The monotone cubic form of values: the table's (*temp untouched) or one made into *temp (free it with
 * tc_table_cubic_free); NULL when it cannot be made (msg says why). */
static const tc_table_cubic *cubic_form(const tc_table *table, const double *values, tc_table_cubic *temp, int *rc,
                                        tc_msg msg) {
    const tc_table_cubic *c = tc_table_cubic_of(table, values);
    if (c != NULL) return c;
    *rc = tc_table_cubic_make(table, values, temp, msg);
    return *rc == TC_OK ? temp : NULL;
}

int tc_table_lookup2(const tc_table *table, const double *values, const double *values_b, double pressure, size_t n,
                     const double *velocity, const double *beta, int policy, double *out, double *out_b,
                     unsigned char *clamped, tc_table_rows *rows, tc_msg msg) {
    if (policy != TC_TABLE_CLAMP && policy != TC_TABLE_ERROR)
        return tc_fail(msg, TC_ERROR, "table policy = %d is not allowed; choose clamp (%d) or error (%d)", policy,
                       TC_TABLE_CLAMP, TC_TABLE_ERROR);
    const size_t nP = table->n_pressure, nv = table->n_velocity, nb = table->n_beta;
    const int outp = outside_pressure(table, pressure);
    if (policy == TC_TABLE_ERROR) {
        if (outp) return domain_error("pressure", "Pa", pressure, table->pressure, nP, msg);
        for (size_t k = 0; k < n; ++k)
            if (outside_velocity(table, fabs(velocity[k])))
                return domain_error("velocity", "m/s", fabs(velocity[k]), table->velocity, nv, msg);
        for (size_t k = 0; k < n; ++k)
            if (outside_beta(table, beta[k])) return domain_error("beta", "1", beta[k], table->beta, nb, msg);
    }
    size_t ip;
    double tp;
    pressure_cell(table, pressure, rows, &ip, &tp);
    if (table->interpolation != TC_TABLE_MONOTONE_CUBIC) {
        multilinear_lookup(table, values, values_b, ip, tp, outp, n, velocity, beta, out, out_b, clamped);
        return TC_OK;
    }
    const double *arrays[2] = {values, values_b};
    double *outs[2] = {out, out_b};
    for (int a = 0; a < 2 && arrays[a] != NULL; ++a) {
        tc_table_cubic temp = {0};
        tc_table_rows local;
        int rc = TC_OK;
        const tc_table_cubic *c = cubic_form(table, arrays[a], &temp, &rc, msg);
        if (c == NULL) return rc;
        tc_table_rows *r = a == 0 && rows != NULL && c != &temp ? rows : &local; /* a made form's rows are not kept */
        if (r == &local) local.filled = 0;
        cubic_lookup(table, c, pressure, ip, tp, outp, n, velocity, beta, outs[a], a == 0 ? clamped : NULL, r);
        tc_table_cubic_free(&temp);
    }
    return TC_OK;
}

int tc_table_lookup(const tc_table *table, const double *values, double pressure, size_t n, const double *velocity,
                    const double *beta, int policy, double *out, unsigned char *clamped, tc_msg msg) {
    return tc_table_lookup2(table, values, NULL, pressure, n, velocity, beta, policy, out, NULL, clamped, NULL, msg);
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
        *out = outside_pressure(table, pressure) || outside_velocity(table, v) || outside_beta(table, beta);
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
                       double *dl, double *dr, tc_table_rows *rows, tc_msg msg) {
    if (table->interpolation != TC_TABLE_MONOTONE_CUBIC)
        return tc_fail(msg, TC_ERROR, "the beta line is that of a version 4 table; this table is version %d",
                       table->format_version);
    const size_t nv = table->n_velocity, nb = table->n_beta;
    size_t ip, iv;
    double tp, tv;
    tc_table_cubic temp = {0};
    int rc = TC_OK;
    const tc_table_cubic *c = cubic_form(table, values, &temp, &rc, msg);
    if (c == NULL) return rc;
    tc_table_rows local;
    tc_table_rows *r = rows != NULL && c != &temp ? rows : &local;
    if (r == &local) local.filled = 0;
    pressure_cell(table, pressure, r, &ip, &tp);
    locate(table->velocity, nv, fabs(velocity), &iv, &tv);
    rows_at(table, c, pressure, ip, tp, iv, tv != 0.0 ? 2 : 1, r);
    rows_line(table, r, tv); /* the line the lookups at this velocity evaluate */
    memcpy(y, r->line_y, nb * sizeof *y);
    if (nb > 1) {
        memcpy(dl, r->line_dl, (nb - 1) * sizeof *dl);
        memcpy(dr, r->line_dr, (nb - 1) * sizeof *dr);
    }
    tc_table_cubic_free(&temp);
    return TC_OK;
}


/* the cubic c0 + c1 t + c2 t^2 + c3 t^3 */
static double cubic(const double c[4], double t) { return ((c[3] * t + c[2]) * t + c[1]) * t + c[0]; }

/* tc_table_first_crossing over the pieces that start at or below limit: a crossing in a later piece lies above limit
 * (the bisection stays in its part), so min(limit, the first crossing) is the same with or without the pieces left */
static int first_crossing(size_t n, const double *x, const double *y, const double *dl, const double *dr, double level,
                          double limit, double *at) {
    if (n == 0) return 0;
    if (y[0] >= level) {
        *at = x[0];
        return 1;
    }
    for (size_t k = 0; k + 1 < n && !(x[k] > limit); ++k) {
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

int tc_table_first_crossing(size_t n, const double *x, const double *y, const double *dl, const double *dr,
                            double level, double *at) {
    return first_crossing(n, x, y, dl, dr, level, HUGE_VAL, at);
}

int tc_table_first_crossing_below(size_t n, const double *x, const double *y, const double *dl, const double *dr,
                                  double level, double limit, double *at) {
    return first_crossing(n, x, y, dl, dr, level, limit, at);
}
