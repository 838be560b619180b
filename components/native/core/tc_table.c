/* The friction table in memory: construction from arrays (checked: increasing finite axes, finite values >= 0), the
 * version 4 form (ln P, the shares A_p / A_c, the monotone cubic forms of the arrays the law reads) and release. */
#include "tc_table.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "tc_pchip.h"

static int check_axis(const char *name, const double *a, size_t n, int nonnegative, tc_msg msg) {
    if (n < 1) return tc_fail(msg, TC_ERROR, "table axis %s must be a non-empty 1-D array", name);
    for (size_t i = 0; i < n; ++i) {
        if (!isfinite(a[i])) return tc_fail(msg, TC_ERROR, "table axis %s has non-finite values", name);
        if (i > 0 && !(a[i] > a[i - 1]))
            return tc_fail(msg, TC_ERROR, "table axis %s must be strictly increasing", name);
    }
    if (nonnegative && a[0] < 0)
        return tc_fail(msg, TC_ERROR, "table axis %s starts at %.17g; it must be >= 0", name, a[0]);
    return TC_OK;
}

static double *copy_array(const double *src, size_t n) {
    double *dst = malloc(n * sizeof *dst);
    if (dst != NULL) memcpy(dst, src, n * sizeof *dst);
    return dst;
}

void tc_table_cubic_free(tc_table_cubic *cubic) {
    free(cubic->beta_slope); /* the block of every array of the form */
    memset(cubic, 0, sizeof *cubic);
}

/* The monotone cubic form of values on a table's axes with ln P = logp and the kinds of the table's nodes (a
 * node is unsimulated where table->unsimulated is not 0; every node one kind without it): tc_table_cubic. */
static int build_cubic_form(const tc_table *t, const double *logp, const double *values, tc_table_cubic *c, tc_msg msg) {
    const size_t nP = t->n_pressure, nv = t->n_velocity, nb = t->n_beta, plane = nv * nb, n = nP * plane;
    const size_t pieces = (nP - 1) * plane;
    const double *u = t->unsimulated;
    double *block = malloc((n + 4 * pieces) * sizeof *block);
    if (block == NULL) return tc_fail(msg, TC_NOMEM, "out of memory for the friction table's monotone cubic form");
    memset(c, 0, sizeof *c);
    c->values = values;
    c->beta_slope = block;
    if (pieces > 0) {
        c->value_piece[0] = block + n;
        c->value_piece[1] = block + n + pieces;
        c->slope_piece[0] = block + n + 2 * pieces;
        c->slope_piece[1] = block + n + 3 * pieces;
    }
    for (size_t at = 0; at < n; at += nb) { /* each table row along beta */
        const tc_pchip_line row = {t->beta, values + at, u != NULL ? u + at : NULL, 1, 1, nb};
        for (size_t k = 0; k < nb; ++k) c->beta_slope[at + k] = tc_pchip_slope(&row, k);
    }
    for (size_t at = 0; at < plane && pieces > 0; ++at) { /* each column along ln P, of values and of row slopes */
        const tc_pchip_line cols[2] = {{logp, values + at, u != NULL ? u + at : NULL, plane, plane, nP},
                                       {logp, c->beta_slope + at, u != NULL ? u + at : NULL, plane, plane, nP}};
        double *const left[2] = {c->value_piece[0], c->slope_piece[0]}, *const right[2] = {c->value_piece[1],
                                                                                            c->slope_piece[1]};
        for (int which = 0; which < 2; ++which)
            for (size_t ip = 0; ip + 1 < nP; ++ip) {
                double d0 = tc_pchip_slope(&cols[which], ip), d1 = tc_pchip_slope(&cols[which], ip + 1);
                tc_pchip_piece_slopes(&cols[which], ip, &d0, &d1);
                left[which][ip * plane + at] = d0;
                right[which][ip * plane + at] = d1;
            }
    }
    return TC_OK;
}

int tc_table_cubic_make(const tc_table *table, const double *values, tc_table_cubic *cubic, tc_msg msg) {
    if (table->log_pressure == NULL)
        return tc_fail(msg, TC_ERROR, "the monotone cubic form is that of a version 4 table; this table is version %d",
                       table->format_version);
    return build_cubic_form(table, table->log_pressure, values, cubic, msg);
}

const tc_table_cubic *tc_table_cubic_of(const tc_table *table, const double *values) {
    for (int k = 0; k < TC_TABLE_N_CUBIC; ++k)
        if (table->cubic[k].values == values && values != NULL) return &table->cubic[k];
    return NULL;
}

void tc_table_free(tc_table *table) {
    if (table == NULL) return;
    for (int k = 0; k < TC_TABLE_N_CUBIC; ++k) tc_table_cubic_free(&table->cubic[k]);
    free(table->pressure);
    free(table->velocity);
    free(table->beta);
    free(table->mu);
    free(table->contact_area);
    free(table->particle_area);
    free(table->contact_area_std);
    free(table->particle_area_std);
    free(table->unsimulated);
    free(table->particle_area_clusters);
    free(table->log_pressure);
    free(table->share);
    free(table->share_clusters);
    free(table);
}

int tc_table_from_arrays(size_t n_pressure, size_t n_velocity, size_t n_beta, const double *pressure,
                         const double *velocity, const double *beta, const double *mu, double beta_threshold,
                         tc_table **out, tc_msg msg) {
    int rc;
    *out = NULL;
    if ((rc = check_axis("pressure", pressure, n_pressure, 0, msg)) != TC_OK) return rc;
    if ((rc = check_axis("velocity", velocity, n_velocity, 1, msg)) != TC_OK) return rc;
    if ((rc = check_axis("beta", beta, n_beta, 1, msg)) != TC_OK) return rc;
    size_t n = n_pressure * n_velocity * n_beta;
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(mu[i]) || mu[i] < 0) return tc_fail(msg, TC_ERROR, "table mu must be finite and >= 0 everywhere");
    if (!(beta_threshold > 0 && beta_threshold <= 1))
        return tc_fail(msg, TC_ERROR, "table metadata beta_threshold = %.17g; a value in (0, 1] is required",
                       beta_threshold);
    tc_table *t = calloc(1, sizeof *t);
    if (t == NULL) return tc_fail(msg, TC_NOMEM, "out of memory for the friction table");
    t->n_pressure = n_pressure;
    t->n_velocity = n_velocity;
    t->n_beta = n_beta;
    t->pressure = copy_array(pressure, n_pressure);
    t->velocity = copy_array(velocity, n_velocity);
    t->beta = copy_array(beta, n_beta);
    t->mu = copy_array(mu, n);
    t->beta_threshold = beta_threshold;
    t->format_version = 1;
    t->pressure_lo = pressure[0] - TC_TABLE_AXIS_END_TOLERANCE * fabs(pressure[0]);
    t->pressure_hi = pressure[n_pressure - 1] + TC_TABLE_AXIS_END_TOLERANCE * fabs(pressure[n_pressure - 1]);
    t->velocity_lo = velocity[0] - TC_TABLE_AXIS_END_TOLERANCE * fabs(velocity[0]);
    t->velocity_hi = velocity[n_velocity - 1] + TC_TABLE_AXIS_END_TOLERANCE * fabs(velocity[n_velocity - 1]);
    t->beta_lo = beta[0] - TC_TABLE_AXIS_END_TOLERANCE * fabs(beta[0]);
    t->beta_hi = beta[n_beta - 1] + TC_TABLE_AXIS_END_TOLERANCE * fabs(beta[n_beta - 1]);
    if (!t->pressure || !t->velocity || !t->beta || !t->mu) {
        tc_table_free(t);
        return tc_fail(msg, TC_NOMEM, "out of memory for the friction table");
    }
    *out = t;
    return TC_OK;
}

int tc_table_set_areas(tc_table *table, const double *contact_area, const double *particle_area,
                       const double *contact_area_std, const double *particle_area_std, tc_msg msg) {
    static const char *const names[4] = {"contact_area", "particle_area", "contact_area_std", "particle_area_std"};
    const double *src[4] = {contact_area, particle_area, contact_area_std, particle_area_std};
    double **dst[4] = {&table->contact_area, &table->particle_area, &table->contact_area_std, &table->particle_area_std};
    const size_t n = table->n_pressure * table->n_velocity * table->n_beta;
    for (int a = 0; a < 4; ++a)
        for (size_t i = 0; i < n; ++i)
            if (!isfinite(src[a][i]) || src[a][i] < 0)
                return tc_fail(msg, TC_ERROR, "table %s must be finite and >= 0 everywhere", names[a]);
    for (int k = 0; k < TC_TABLE_N_CUBIC; ++k) tc_table_cubic_free(&table->cubic[k]); /* of the arrays replaced */
    for (int a = 0; a < 4; ++a) {
        double *copy = copy_array(src[a], n);
        if (copy == NULL) return tc_fail(msg, TC_NOMEM, "out of memory for the friction table");
        free(*dst[a]);
        *dst[a] = copy;
    }
    table->format_version = 2;
    table->interpolation = TC_TABLE_MULTILINEAR;
    return TC_OK;
}

int tc_table_set_extras(tc_table *table, const double *simulated, const double *particle_area_clusters, tc_msg msg) {
    if (table->format_version < 2)
        return tc_fail(msg, TC_ERROR, "table version 3 arrays need the version 2 areas; this table has none");
    const size_t n = table->n_pressure * table->n_velocity * table->n_beta;
    for (size_t i = 0; i < n; ++i) {
        if (!(simulated[i] == 0.0 || simulated[i] == 1.0))
            return tc_fail(msg, TC_ERROR, "table simulated must be 0 or 1 at every node");
        if (!isfinite(particle_area_clusters[i]) || particle_area_clusters[i] < 0)
            return tc_fail(msg, TC_ERROR, "table particle_area_clusters must be finite and >= 0 everywhere");
    }
    double *unsim = malloc(n * sizeof *unsim), *clusters = copy_array(particle_area_clusters, n);
    if (unsim == NULL || clusters == NULL) {
        free(unsim);
        free(clusters);
        return tc_fail(msg, TC_NOMEM, "out of memory for the friction table");
    }
    for (size_t i = 0; i < n; ++i) unsim[i] = 1.0 - simulated[i];
    for (int k = 0; k < TC_TABLE_N_CUBIC; ++k) tc_table_cubic_free(&table->cubic[k]); /* of the kinds replaced */
    free(table->unsimulated);
    free(table->particle_area_clusters);
    table->unsimulated = unsim;
    table->particle_area_clusters = clusters;
    table->format_version = 3;
    table->interpolation = TC_TABLE_MULTILINEAR;
    return TC_OK;
}

int tc_table_set_cubic(tc_table *table, tc_msg msg) {
    if (table->format_version < 3)
        return tc_fail(msg, TC_ERROR, "table version 4 needs the version 3 arrays; this table is version %d",
                       table->format_version);
    if (!(table->pressure[0] > 0))
        return tc_fail(msg, TC_ERROR, "table version 4 interpolates in log P: its pressure axis must be > 0, it starts "
                       "at %.17g Pa", table->pressure[0]);
    if (table->n_beta > TC_TABLE_BETA_MAX)
        return tc_fail(msg, TC_ERROR, "table version 4 takes at most %d beta nodes; this table has %zu",
                       TC_TABLE_BETA_MAX, table->n_beta);
    const size_t n = table->n_pressure * table->n_velocity * table->n_beta;
    double *logp = malloc(table->n_pressure * sizeof *logp), *share = malloc(n * sizeof *share),
           *clusters = malloc(n * sizeof *clusters);
    if (logp == NULL || share == NULL || clusters == NULL) {
        free(logp);
        free(share);
        free(clusters);
        return tc_fail(msg, TC_NOMEM, "out of memory for the friction table");
    }
    for (size_t i = 0; i < table->n_pressure; ++i) logp[i] = log(table->pressure[i]);
    for (size_t i = 0; i < n; ++i) {
        const double ac = table->contact_area[i];
        share[i] = ac > 0 ? table->particle_area[i] / ac : 0.0;
        clusters[i] = ac > 0 ? table->particle_area_clusters[i] / ac : 0.0;
    }
    const double *arrays[TC_TABLE_N_CUBIC] = {share, clusters, table->particle_area, table->particle_area_clusters};
    tc_table_cubic forms[TC_TABLE_N_CUBIC] = {{0}};
    for (int k = 0; k < TC_TABLE_N_CUBIC; ++k) {
        const int rc = build_cubic_form(table, logp, arrays[k], &forms[k], msg);
        if (rc != TC_OK) {
            for (int j = 0; j < k; ++j) tc_table_cubic_free(&forms[j]);
            free(logp);
            free(share);
            free(clusters);
            return rc;
        }
    }
    for (int k = 0; k < TC_TABLE_N_CUBIC; ++k) {
        tc_table_cubic_free(&table->cubic[k]);
        table->cubic[k] = forms[k];
    }
    free(table->log_pressure);
    free(table->share);
    free(table->share_clusters);
    table->log_pressure = logp;
    table->share = share;
    table->share_clusters = clusters;
    table->interpolation = TC_TABLE_MONOTONE_CUBIC;
    table->format_version = 4;
    return TC_OK;
}

const double *tc_table_part(const tc_table *table, int which, size_t *n) {
    const size_t nP = table->n_pressure, plane = table->n_velocity * table->n_beta, all = nP * plane;
    const size_t pieces = (nP - 1) * plane;
    if (which >= TC_TABLE_PART_CUBIC && which < TC_TABLE_PART_CUBIC + 6 * TC_TABLE_N_CUBIC) {
        const tc_table_cubic *c = &table->cubic[(which - TC_TABLE_PART_CUBIC) / 6];
        const int k = (which - TC_TABLE_PART_CUBIC) % 6;
        const double *parts[6] = {c->values, c->beta_slope, c->value_piece[0], c->value_piece[1], c->slope_piece[0],
                                  c->slope_piece[1]};
        *n = k < 2 ? all : pieces;
        return parts[k];
    }
    const double *arrays[TC_TABLE_PART_CUBIC] = {
        table->pressure, table->velocity, table->beta, table->mu, table->contact_area, table->particle_area,
        table->contact_area_std, table->particle_area_std, table->unsimulated, table->particle_area_clusters,
        table->log_pressure, table->share, table->share_clusters};
    if (which < 0 || which >= TC_TABLE_PART_CUBIC) {
        *n = 0;
        return NULL;
    }
    *n = which == TC_TABLE_PART_PRESSURE || which == TC_TABLE_PART_LOG_PRESSURE ? nP
         : which == TC_TABLE_PART_VELOCITY                                     ? table->n_velocity
         : which == TC_TABLE_PART_BETA                                         ? table->n_beta
                                                                               : all;
    return arrays[which];
}

void tc_table_scalars(const tc_table *table, double out[TC_TABLE_N_SCALARS]) {
    const double values[TC_TABLE_N_SCALARS] = {
        table->pressure_lo, table->pressure_hi, table->velocity_lo, table->velocity_hi, table->beta_lo,
        table->beta_hi, table->beta_threshold, (double)table->format_version, (double)table->interpolation};
    for (int k = 0; k < TC_TABLE_N_SCALARS; ++k) out[k] = values[k];
}
