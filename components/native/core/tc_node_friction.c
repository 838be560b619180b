/* The friction of one contact point with its own debris state (the equations are in tc_node_friction.h). */
#include "tc_node_friction.h"

#include <math.h>

#include "tc_debris_node.h"

double tc_node_law_cap(const tc_stripdraw_params *p, const tc_table *table) {
    if (p->beta_threshold > 0) return p->beta_threshold;
    return tc_law_beta_threshold(p, p->friction_model == TC_STRIPDRAW_FRICTION_MODEL_TABLE ? table : NULL);
}

int tc_node_law_make(const tc_stripdraw_params *p, const tc_table *table, tc_node_law *out, tc_msg msg) {
    int rc = tc_stripdraw_params_check(p, msg);
    if (rc != TC_OK) return rc;
    rc = tc_law_check(p, table, msg);
    if (rc != TC_OK) return rc;
    out->p = *p;
    out->p.table_policy = TC_TABLE_CLAMP;
    out->table = p->friction_model == TC_STRIPDRAW_FRICTION_MODEL_TABLE ? table : NULL;
    out->beta_cap = tc_node_law_cap(&out->p, out->table);
    return TC_OK;
}

void tc_node_mu(const tc_node_law *law, double pressure, size_t n, const double *rate, const double *beta,
                double *mu, unsigned char *flagged, double *work, tc_table_rows *rows) {
    const tc_msg none = {NULL, 0};
    (void)tc_law_mu(&law->p, law->table, pressure, n, rate, beta, mu, flagged, work, rows, none); /* clamp: no fail */
}

double tc_node_debris(const tc_node_law *law, double pressure, double slip, double rate, double beta,
                      tc_table_rows *rows) {
    const tc_stripdraw_params *p = &law->p;
    const double lambda = p->debris_sink_length;
    /* the debris the increment's slide makes (the strip's formulas at contact weight 1), then the cap at (P, v) */
    const double src = tc_debris_source(slip, 1.0, p->archard_k * pressure, p->hardness * p->particle_thickness);
    const double b = lambda > 0 && slip > 0 ? tc_debris_sunk(&beta, src, slip, lambda) : beta + src;
    const double held = b > law->beta_cap ? law->beta_cap : b; /* beta_cap <= 1 */
    return p->beta_threshold > 0 ? held : tc_law_beta_capped(p, law->table, pressure, rate, held, rows);
}

int tc_node_slide(const tc_stripdraw_params *p, const tc_table *table, size_t n, const double *pressure,
                  const double *rate, double slide, double beta0, double *beta, tc_msg msg) {
    char a[TC_REPR_SIZE], b[TC_REPR_SIZE];
    if (!(isfinite(slide) && slide >= 0))
        return tc_fail(msg, TC_ERROR, "slide = %s m: a finite slide >= 0 is required", tc_repr_double(slide, a));
    if (!(isfinite(beta0) && beta0 >= 0 && beta0 <= 1))
        return tc_fail(msg, TC_ERROR, "beta_initial = %s: a debris area fraction in [0, 1] is required",
                       tc_repr_double(beta0, a));
    tc_node_law law;
    const int rc = tc_node_law_make(p, table, &law, msg);
    if (rc != TC_OK) return rc;
    tc_table_rows rows = {0};
    for (size_t k = 0; k < n; ++k) {
        if (!(isfinite(pressure[k]) && pressure[k] > 0 && isfinite(rate[k]) && rate[k] >= 0))
            return tc_fail(msg, TC_ERROR, "pressure = %s Pa, slip rate = %s m/s: a pressure > 0 and a slip rate >= 0, "
                           "both finite, are required", tc_repr_double(pressure[k], a), tc_repr_double(rate[k], b));
        beta[k] = tc_node_debris(&law, pressure[k], slide, rate[k], beta0, &rows);
    }
    return TC_OK;
}

double tc_node_friction(const tc_node_law *law, double pressure, double slip, double dt, double *beta, int *flagged,
                        tc_table_rows *rows) {
    const double b0 = *beta, ds = fabs(slip);
    if (flagged != NULL) *flagged = 0;
    if (!(isfinite(pressure) && isfinite(ds) && isfinite(dt) && isfinite(b0))) {
        if (flagged != NULL) *flagged = 1;
        return 0.0;
    }
    if (!(pressure > 0)) return 0.0;
    const double v = dt > 0 ? ds / dt : 0.0;
    double mu, work;
    unsigned char clamped = 0;
    tc_node_mu(law, pressure, 1, &v, &b0, &mu, &clamped, &work, rows);
    *beta = tc_node_debris(law, pressure, ds, v, b0, rows);
    if (flagged != NULL) *flagged = clamped != 0;
    return mu;
}
