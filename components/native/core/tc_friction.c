/* The local friction law (the equations are in tc_friction.h). */
#include "tc_friction.h"

#include <math.h>
#include <stdio.h>

static const tc_msg NO_MSG = {NULL, 0}; /* lookups under the clamp policy cannot fail */

static int with_areas(const tc_stripdraw_params *p, const tc_table *table) {
    return p->friction_model == TC_STRIPDRAW_FRICTION_MODEL_TABLE && table != NULL && table->format_version >= 2;
}

int tc_law_check(const tc_stripdraw_params *p, const tc_table *table, tc_msg msg) {
    if (p->friction_model != TC_STRIPDRAW_FRICTION_MODEL_TABLE) return TC_OK;
    if (table == NULL) return tc_fail(msg, TC_ERROR, "friction_model = 'table' needs a friction table; none was given");
    if (p->particle_area_rule == TC_STRIPDRAW_PARTICLE_AREA_RULE_CLUSTERS && table->format_version < 3)
        return tc_fail(msg, TC_ERROR,
                       "particle_area_rule = 'clusters' needs a friction table of format version 3 (with the flake-borne "
                       "area of the paper's cluster rule); this table is version %d: rebuild it with tribocosim "
                       "surrogate table", table->format_version);
    if (table->format_version < 2 &&
        (p->contact_area != TC_STRIPDRAW_CONTACT_AREA_MESOSCALE || p->particle_area_scale != 1.0 ||
         p->flake_shear_ratio != 0.0)) {
        char s[TC_REPR_SIZE], r[TC_REPR_SIZE];
        return tc_fail(msg, TC_ERROR,
                       "contact_area = '%s' with particle_area_scale = %s and flake_shear_ratio = %s needs a friction "
                       "table of format version 2 (with the contact areas); this table is version 1 (the mu of "
                       "frictionless flakes only), which serves the paper's model alone (contact_area = 'mesoscale', "
                       "particle_area_scale = 1, flake_shear_ratio = 0): rebuild it with tribocosim surrogate table",
                       p->contact_area == TC_STRIPDRAW_CONTACT_AREA_EQ8 ? "eq8" : "mesoscale",
                       tc_repr_double(p->particle_area_scale, s), tc_repr_double(p->flake_shear_ratio, r));
    }
    return TC_OK;
}

double tc_law_alpha(const tc_stripdraw_params *p, double velocity) {
    if (p->alpha_v_ref == 0) return p->alpha_b;
    return p->alpha_b * -expm1(-fabs(velocity) / p->alpha_v_ref);
}

/* the table's A_p/A0 of the rule the parameters name: every load-bearing flake, or the paper's cluster rule alone
 * (version 3 tables; a table without it has only the first) */
static const double *particle_area(const tc_stripdraw_params *p, const tc_table *table) {
    if (p->particle_area_rule == TC_STRIPDRAW_PARTICLE_AREA_RULE_CLUSTERS) return table->particle_area_clusters;
    return table->particle_area;
}

/* the share A_p / A_c of the rule the parameters name (version 4 tables) */
static const double *particle_share(const tc_stripdraw_params *p, const tc_table *table) {
    if (p->particle_area_rule == TC_STRIPDRAW_PARTICLE_AREA_RULE_CLUSTERS) return table->share_clusters;
    return table->share;
}

static double eq8_area(const tc_stripdraw_params *p, double pressure) {
    return p->kappa * pressure / (p->rms_slope * p->e_star);
}

/* the share of the particle-free shear that the flake-borne contact lacks: (1 - r) s, so that
 * mu = mu0 [(1 - s A_p / A_c) + r s A_p / A_c] = mu0 (1 - (1 - r) s A_p / A_c) */
static double shear_loss(const tc_stripdraw_params *p) {
    return (1.0 - p->flake_shear_ratio) * p->particle_area_scale;
}

/* A_c/A0 at one pressure for n queries: Eq. 8, or the table's (clamped). */
static void contact_area(const tc_stripdraw_params *p, const tc_table *table, double pressure, size_t n,
                         const double *velocity, const double *beta, double *ac) {
    if (p->contact_area == TC_STRIPDRAW_CONTACT_AREA_EQ8) {
        const double eq8 = eq8_area(p, pressure);
        for (size_t k = 0; k < n; ++k) ac[k] = eq8;
        return;
    }
    (void)tc_table_lookup(table, table->contact_area, pressure, n, velocity, beta, TC_TABLE_CLAMP, ac, NULL, NO_MSG);
}

/* The cap of a version 4 table at (P, v): the first beta where s times the interpolated share reaches 1 (mesoscale)
 * or s times the interpolated A_p reaches A_c of Eq. 8, limited to 1; 1 when it never does. */
static double crossing_cubic(const tc_stripdraw_params *p, const tc_table *table, double pressure, double velocity,
                             double limit, tc_table_rows *rows) {
    const int eq8 = p->contact_area == TC_STRIPDRAW_CONTACT_AREA_EQ8;
    const double level = eq8 ? eq8_area(p, pressure) : 1.0, s = p->particle_area_scale;
    if (!(s > 0)) return 1.0;
    double y[TC_TABLE_BETA_MAX], dl[TC_TABLE_BETA_MAX], dr[TC_TABLE_BETA_MAX], at;
    (void)tc_table_beta_line(table, eq8 ? particle_area(p, table) : particle_share(p, table), pressure, velocity, y,
                             dl, dr, rows, NO_MSG);
    if (!tc_table_first_crossing_below(table->n_beta, table->beta, y, dl, dr, level / s * (1.0 - TC_REACH_RTOL), limit,
                                       &at))
        return 1.0;
    return fmin(1.0, at);
}

/* where s A_p reaches A_c along the table's beta axis at (P, v), limited to 1; 1 when it never does */
static double crossing(const tc_stripdraw_params *p, const tc_table *table, double pressure, double velocity,
                       tc_table_rows *rows) {
    if (table->interpolation == TC_TABLE_MONOTONE_CUBIC)
        return crossing_cubic(p, table, pressure, velocity, HUGE_VAL, rows);
    const double *b = table->beta;
    double d_prev = 0.0;
    for (size_t k = 0; k < table->n_beta; ++k) {
        double ap, ac;
        (void)tc_table_lookup(table, particle_area(p, table), pressure, 1, &velocity, b + k, TC_TABLE_CLAMP, &ap, NULL,
                              NO_MSG);
        contact_area(p, table, pressure, 1, &velocity, b + k, &ac);
        const double d = p->particle_area_scale * ap - ac;
        if (d >= -TC_REACH_RTOL * ac) {
            if (k == 0) return 0.0;
            return fmin(1.0, b[k - 1] + (b[k] - b[k - 1]) * (-d_prev) / (d - d_prev));
        }
        d_prev = d;
    }
    return 1.0;
}

double tc_law_beta_threshold(const tc_stripdraw_params *p, const tc_table *table) {
    switch (p->friction_model) {
    case TC_STRIPDRAW_FRICTION_MODEL_TABLE: {
        if (!with_areas(p, table)) return table != NULL ? table->beta_threshold : 1.0;
        double top = 1.0;
        int first = 1;
        for (size_t i = 0; i < table->n_pressure; ++i) {
            if (!(table->pressure[i] > 0)) continue;
            for (size_t j = 0; j < table->n_velocity; ++j) {
                const double c = crossing(p, table, table->pressure[i], table->velocity[j], NULL);
                top = first || c > top ? c : top;
                first = 0;
            }
        }
        return top;
    }
    case TC_STRIPDRAW_FRICTION_MODEL_CLOSED_FORM: {
        const double top = p->particle_area_scale * p->alpha_b * p->rms_slope;
        return top <= 0 ? 1.0 : fmin(1.0, p->kappa / top);
    }
    default:
        return 1.0;
    }
}

double tc_law_beta_cap(const tc_stripdraw_params *p, const tc_table *table, double pressure, double speed,
                       tc_table_rows *rows) {
    if (with_areas(p, table) && pressure > 0) return crossing(p, table, pressure, fabs(speed), rows);
    return tc_law_beta_threshold(p, table);
}

double tc_law_beta_capped(const tc_stripdraw_params *p, const tc_table *table, double pressure, double speed,
                          double beta, tc_table_rows *rows) {
    /* the cap's search stops at beta: a crossing above it does not cap (first_crossing in tc_table_lookup.c) */
    const double cap = with_areas(p, table) && pressure > 0 && table->interpolation == TC_TABLE_MONOTONE_CUBIC
                           ? crossing_cubic(p, table, pressure, fabs(speed), beta, rows)
                           : tc_law_beta_cap(p, table, pressure, speed, rows);
    return beta > cap ? cap : beta;
}

/* max(0, x), and 0 for a NaN x (as fmax(0, x)), in a compare the loops vectorise */
static inline double at_least_0(double x) { return x > 0.0 ? x : 0.0; }

int tc_law_mu(const tc_stripdraw_params *p, const tc_table *table, double pressure, size_t n, const double *velocity,
              const double *beta, double *mu, unsigned char *clamped, double *ac_work, tc_table_rows *rows,
              tc_msg msg) {
    switch (p->friction_model) {
    case TC_STRIPDRAW_FRICTION_MODEL_CONSTANT:
        for (size_t k = 0; k < n; ++k) mu[k] = p->mu_const;
        break;
    case TC_STRIPDRAW_FRICTION_MODEL_CLOSED_FORM:
        for (size_t k = 0; k < n; ++k) /* Eq. 9 with Eq. 23 */
            mu[k] = p->mu0 * (1.0 - shear_loss(p) * tc_law_alpha(p, velocity[k]) * beta[k] * p->rms_slope / p->kappa);
        break;
    default: {
        if (!with_areas(p, table))
            return tc_table_lookup(table, table->mu, pressure, n, velocity, beta, p->table_policy, mu, clamped, msg);
        /* mu = mu0 (1 - (1 - r) s A_p / A_c) */
        const int eq8 = p->contact_area == TC_STRIPDRAW_CONTACT_AREA_EQ8;
        const double loss = shear_loss(p);
        if (table->interpolation == TC_TABLE_MONOTONE_CUBIC) { /* the share (or A_p over Eq. 8's A_c) interpolated */
            int rc = tc_table_lookup2(table, eq8 ? particle_area(p, table) : particle_share(p, table), NULL, pressure,
                                      n, velocity, beta, p->table_policy, mu, NULL, clamped, rows, msg);
            if (rc != TC_OK) return rc;
            if (!eq8) { /* the share itself (A_c = 1: dividing by it is exact) */
                for (size_t k = 0; k < n; ++k) mu[k] = p->mu0 * at_least_0(1.0 - loss * mu[k]);
                return TC_OK;
            }
            const double ac = eq8_area(p, pressure);
            for (size_t k = 0; k < n; ++k) mu[k] = p->mu0 * at_least_0(1.0 - loss * (ac > 0 ? mu[k] / ac : 0.0));
            return TC_OK;
        }
        /* A_p (and the table's A_c) located once per query */
        int rc = tc_table_lookup2(table, particle_area(p, table), eq8 ? NULL : table->contact_area, pressure, n,
                                  velocity, beta, p->table_policy, mu, ac_work, clamped, NULL, msg);
        if (rc != TC_OK) return rc;
        if (eq8) contact_area(p, table, pressure, n, velocity, beta, ac_work);
        for (size_t k = 0; k < n; ++k) {
            const double share = ac_work[k] > 0 ? mu[k] / ac_work[k] : 0.0;
            mu[k] = p->mu0 * at_least_0(1.0 - loss * share);
        }
        return TC_OK;
    }
    }
    if (clamped != NULL)
        for (size_t k = 0; k < n; ++k) clamped[k] = 0;
    return TC_OK;
}

int tc_law_floor_note(const tc_stripdraw_params *p, double mu, tc_msg msg) {
    const double least_allowed = TC_STRIPDRAW_MU_FLOOR, lowest = p->flake_shear_ratio * p->mu0;
    if (!tc_below(mu, least_allowed)) return 0;
    char why[512];
    if (p->friction_model == TC_STRIPDRAW_FRICTION_MODEL_CONSTANT)
        snprintf(why, sizeof why, "friction_model = constant with mu_const = %g; mu_const >= %g keeps mu at or above "
                 "it", p->mu_const, least_allowed);
    else if (tc_below(p->mu0, least_allowed))
        snprintf(why, sizeof why, "mu0 = %g is below it, and the law gives at most mu0 (no debris)", p->mu0);
    else if (tc_below(lowest, least_allowed))
        snprintf(why, sizeof why, "flake_shear_ratio = %g with mu0 = %g lets mu fall to %.4g where flakes carry the "
                 "whole contact; flake_shear_ratio >= %.4g keeps mu at or above it", p->flake_shear_ratio, p->mu0,
                 lowest, least_allowed / p->mu0);
    else
        snprintf(why, sizeof why, "the settings give at least %.4g where flakes carry the whole contact (r mu0); a "
                 "lower value comes from debris beyond the law's cap (beta_threshold above it, or debris made at "
                 "another pressure or velocity)", lowest);
    if (msg.text != NULL && msg.size > 0)
        snprintf(msg.text, msg.size, "mu = %.4g is below the documented floor %g of the strip-draw contact "
                 "(docs/model.md, the floor under debris): %s", mu, least_allowed, why);
    return 1;
}
