/* The fixed-step loop of the co-simulation master (see tc_master.h for the data and the contract).
 *
 * One macro step from t = start + n tick over h = k tick, k = min(macro_ticks, ticks to the next macro step, ticks
 * to the end), with the coupling values y held over the step (extrapolation order 0: every input u_k = y_k of the
 * last communication point):
 *
 *   Jacobi        every slave gets its inputs, then every slave steps, then the outputs are refreshed;
 *   Gauss-Seidel  in the sequence, each slave gets its inputs (the new outputs of the slaves already stepped, the
 *                 held ones of the others), steps, gets them again (propagate) and its outputs are read; then the
 *                 outputs are refreshed.
 *
 * The refresh visits the slaves in the evaluation order; one that may feed through gets its inputs set to the
 * current y first (propagate), then its outputs are read into y. Inputs are not set again when they already hold
 * the values (as tribocosim.cosim.engine.system does), so the FMUs see the same calls as under the Python loop. The
 * values the Python loop computes as c0 + h (c1 + h c2) with c1 = c2 = 0 are c0 + 0.0 here (the same bits: the sum
 * turns -0.0 into +0.0). After the step the recorded variables are read; a non-finite one, or a non-finite linked
 * output, stops the loop as a discarded step does (TCM_STOPPED).
 */
#include "tc_master.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double wall_clock(void) {
    struct timespec ts;
    if (timespec_get(&ts, TIME_UTC) != TIME_UTC) return 0.0;
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Note what failed; returns `outcome` (TCM_STOPPED or TCM_FMI_ERROR). */
static int failed(tcm_state *s, int outcome, int slave, int status, const char *function, double t) {
    s->failed_slave = slave;
    s->failed_status = status;
    s->failed_function = function;
    s->failed_time = t;
    return outcome;
}

/* A discarded step stops the loop; any other status above warning is an error. */
static int fmi_failed(tcm_state *s, int slave, fmi2Status status, const char *function, double t) {
    int stop = status == fmi2Discard && strcmp(function, "fmi2DoStep") == 0;
    return failed(s, stop ? TCM_STOPPED : TCM_FMI_ERROR, slave, (int)status, function, t);
}

/* One batched get: the values go to out[dst[j]]. */
static int get_values(const tcm_rig *r, tcm_state *s, const tcm_get *g, double *out) {
    tcm_slave *sl = &r->slaves[g->slave];
    const char *function = "fmi2GetReal";
    double t0 = wall_clock();
    fmi2Status st;
    if (g->kind == TCM_REAL) {
        st = sl->get_real(sl->component, g->vrs, g->n_vrs, s->values);
    } else if (g->kind == TCM_INTEGER) {
        function = "fmi2GetInteger";
        st = sl->get_integer(sl->component, g->vrs, g->n_vrs, s->ints);
    } else {
        function = "fmi2GetBoolean";
        st = sl->get_boolean(sl->component, g->vrs, g->n_vrs, s->ints);
    }
    sl->wall_time += wall_clock() - t0;
    if (st > fmi2Warning) return fmi_failed(s, g->slave, st, function, sl->current_time);
    if (g->kind == TCM_INTEGER) {
        for (size_t j = 0; j < g->n_vrs; j++) s->values[j] = (double)s->ints[j];
    } else if (g->kind == TCM_BOOLEAN) {
        for (size_t j = 0; j < g->n_vrs; j++) s->values[j] = s->ints[j] ? 1.0 : 0.0;
    }
    for (size_t j = 0; j < g->n_dst; j++) out[g->dst[j]] = s->values[g->pos[j]];
    return TCM_DONE;
}

/* Set slave i's linked inputs to values[link] and remember them. */
static int set_inputs(const tcm_rig *r, tcm_state *s, int i, const double *values) {
    tcm_slave *sl = &r->slaves[i];
    s->written_ok[i] = 0;
    for (size_t g = r->set_first[i]; g < r->set_first[i + 1]; g++) {
        const tcm_set *set = &r->sets[g];
        for (size_t j = 0; j < set->n; j++) s->values[j] = values[set->link[j]];
        double t0 = wall_clock();
        fmi2Status st = sl->set_real(sl->component, set->vrs, set->n, s->values);
        sl->wall_time += wall_clock() - t0;
        if (st > fmi2Warning) return fmi_failed(s, i, st, "fmi2SetReal", sl->current_time);
    }
    for (size_t g = r->set_first[i]; g < r->set_first[i + 1]; g++) {
        const tcm_set *set = &r->sets[g];
        for (size_t j = 0; j < set->n; j++) s->written[set->link[j]] = values[set->link[j]];
    }
    s->written_ok[i] = 1;
    return TCM_DONE;
}

/* The inputs of a step: set unless they already hold the values (==, so that NaN is always set again). */
static int apply_inputs(const tcm_rig *r, tcm_state *s, int i, const double *values) {
    if (r->set_first[i] == r->set_first[i + 1]) return TCM_DONE;
    if (s->written_ok[i]) {
        int same = 1;
        for (size_t g = r->set_first[i]; g < r->set_first[i + 1] && same; g++) {
            const tcm_set *set = &r->sets[g];
            for (size_t j = 0; j < set->n; j++) {
                if (!(s->written[set->link[j]] == values[set->link[j]])) {
                    same = 0;
                    break;
                }
            }
        }
        if (same) return TCM_DONE;
    }
    return set_inputs(r, s, i, values);
}

/* Read slave i's linked outputs into y; a non-finite one stops the loop. */
static int read_outputs(const tcm_rig *r, tcm_state *s, int i) {
    for (size_t g = r->get_first[i]; g < r->get_first[i + 1]; g++) {
        int rc = get_values(r, s, &r->gets[g], s->y);
        if (rc != TCM_DONE) return rc;
    }
    for (size_t g = r->get_first[i]; g < r->get_first[i + 1]; g++) {
        const tcm_get *get = &r->gets[g];
        for (size_t j = 0; j < get->n_dst; j++) {
            if (!isfinite(s->y[get->dst[j]])) {
                return failed(s, TCM_STOPPED, i, fmi2OK, "non-finite output", r->slaves[i].current_time);
            }
        }
    }
    return TCM_DONE;
}

static int do_step(const tcm_rig *r, tcm_state *s, int i, double t, double h) {
    tcm_slave *sl = &r->slaves[i];
    sl->current_time = t;
    sl->do_steps++;
    double t0 = wall_clock();
    fmi2Status st = sl->do_step(sl->component, t, h, fmi2True);
    sl->wall_time += wall_clock() - t0;
    return st > fmi2Warning ? fmi_failed(s, i, st, "fmi2DoStep", t) : TCM_DONE;
}

static int refresh(const tcm_rig *r, tcm_state *s) {
    for (size_t idx = 0; idx < r->n_slaves; idx++) {
        int i = r->eval_order[idx];
        int rc = TCM_DONE;
        if (r->propagate && r->feeds[i]) rc = set_inputs(r, s, i, s->y);
        if (rc == TCM_DONE) rc = read_outputs(r, s, i);
        if (rc != TCM_DONE) return rc;
    }
    return TCM_DONE;
}

static int jacobi(const tcm_rig *r, tcm_state *s, double t, double h) {
    int rc = TCM_DONE;
    for (size_t i = 0; i < r->n_slaves && rc == TCM_DONE; i++) rc = apply_inputs(r, s, (int)i, s->y);
    for (size_t i = 0; i < r->n_slaves && rc == TCM_DONE; i++) rc = do_step(r, s, (int)i, t, h);
    return rc == TCM_DONE ? refresh(r, s) : rc;
}

static int gauss_seidel(const tcm_rig *r, tcm_state *s, double t, double h) {
    memset(s->stepped, 0, r->n_slaves);
    for (size_t idx = 0; idx < r->n_slaves; idx++) {
        int i = r->sequence[idx];
        int rc = apply_inputs(r, s, i, s->y);
        if (rc == TCM_DONE) rc = do_step(r, s, i, t, h);
        if (rc == TCM_DONE && r->propagate && r->set_first[i] != r->set_first[i + 1]) {
            for (size_t k = 0; k < r->n_links; k++) {
                s->held[k] = s->stepped[r->link_source[k]] ? s->y[k] : s->y[k] + 0.0;
            }
            rc = set_inputs(r, s, i, s->held);
        }
        if (rc == TCM_DONE) rc = read_outputs(r, s, i);
        if (rc != TCM_DONE) return rc;
        s->stepped[i] = 1;
    }
    return refresh(r, s);
}

/* Read the recorded variables into s->row; a non-finite one stops the loop. */
static int record(const tcm_rig *r, tcm_state *s, double t) {
    for (size_t g = 0; g < r->n_record_gets; g++) {
        int rc = get_values(r, s, &r->record_gets[g], s->row);
        if (rc != TCM_DONE) return rc;
    }
    for (size_t j = 0; j < r->n_from_links; j++) s->row[r->from_link_column[j]] = s->y[r->from_link[j]];
    for (size_t j = 0; j < r->n_columns; j++) {
        if (!isfinite(s->row[j])) return failed(s, TCM_STOPPED, -1, fmi2OK, "non-finite output", t);
    }
    return TCM_DONE;
}

TCM_API int tcm_run(const tcm_rig *r, tcm_state *s, int64_t max_steps) {
    for (int64_t taken = 0; taken < max_steps && s->n < r->end_ticks && s->n_rows < s->capacity; taken++) {
        int64_t n = s->n;
        int64_t k = (n / r->macro_ticks + 1) * r->macro_ticks - n;
        if (r->end_ticks - n < k) k = r->end_ticks - n;
        double t = r->start + (double)n * r->tick;
        double h = (double)k * r->tick;
        int rc = r->gauss_seidel ? gauss_seidel(r, s, t, h) : jacobi(r, s, t, h);
        if (rc == TCM_DONE) rc = record(r, s, t);
        if (rc != TCM_DONE) return rc;
        s->n = n + k;
        s->min_step = h < s->min_step ? h : s->min_step;
        s->max_step = h > s->max_step ? h : s->max_step;
        s->times[s->n_rows] = r->start + (double)s->n * r->tick;
        memcpy(s->rows + s->n_rows * r->n_columns, s->row, r->n_columns * sizeof(double));
        s->n_rows++;
        s->steps++;
    }
    return TCM_DONE;
}

TCM_API int tcm_refresh(const tcm_rig *r, tcm_state *s) { return refresh(r, s); }

TCM_API int tcm_probe(const tcm_rig *r, tcm_state *s, const int *targets, const fmi2ValueReference *target_vrs,
                      const unsigned char *probe, double *jac, unsigned char *dep, double *scratch) {
    size_t m = r->n_links;
    double *base = scratch, *pert = scratch + m;
    memcpy(base, s->y, m * sizeof(double));
    for (size_t j = 0; j < m; j++) {
        if (!probe[j]) continue;
        int i = targets[j];
        tcm_slave *sl = &r->slaves[i];
        double u = base[j];
        double delta = 1e-6 * fmax(1.0, fabs(u));
        double values[2] = {u + delta, u};
        for (int pass = 0; pass < 2; pass++) {
            double t0 = wall_clock();
            fmi2Status st = sl->set_real(sl->component, &target_vrs[j], 1, &values[pass]);
            sl->wall_time += wall_clock() - t0;
            if (st > fmi2Warning) return fmi_failed(s, i, st, "fmi2SetReal", sl->current_time);
            int rc = read_outputs(r, s, i);
            if (rc != TCM_DONE) return rc;
            if (pass == 0) memcpy(pert, s->y, m * sizeof(double));
        }
        for (size_t g = r->get_first[i]; g < r->get_first[i + 1]; g++) {
            const tcm_get *get = &r->gets[g];
            for (size_t q = 0; q < get->n_dst; q++) {
                size_t k = (size_t)get->dst[q];
                double d = (pert[k] - s->y[k]) / delta;
                double tol = 1e-8 * fmax(1.0, fabs(s->y[k])) / fmax(1.0, fabs(u));
                jac[k * m + j] = d;
                dep[k * m + j] = fabs(d) > tol;
            }
        }
    }
    memcpy(s->y, base, m * sizeof(double));
    memset(s->written_ok, 0, r->n_slaves);
    return TCM_DONE;
}

TCM_API int tcm_record_row(const tcm_rig *r, tcm_state *s) {
    if (s->n_rows >= s->capacity) return failed(s, TCM_STOPPED, -1, fmi2OK, "no room for a row", 0.0);
    double t = r->start + (double)s->n * r->tick;
    int rc = record(r, s, t);
    if (rc != TCM_DONE) return rc;
    s->times[s->n_rows] = t;
    memcpy(s->rows + s->n_rows * r->n_columns, s->row, r->n_columns * sizeof(double));
    s->n_rows++;
    return TCM_DONE;
}

TCM_API void tcm_logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status, fmi2String category,
                        fmi2String message, ...) {
    (void)instance;
    (void)category;
    const tcm_log_env *e = (const tcm_log_env *)env;
    if (e == NULL || e->sink == NULL) return;
    char text[4096];
    va_list args;
    va_start(args, message);
    vsnprintf(text, sizeof text, message != NULL ? message : "", args);
    va_end(args);
    e->sink(e->key, (int)status, text);
}

TCM_API void *tcm_allocate_memory(size_t n, size_t size) { return calloc(n, size); }

TCM_API void tcm_free_memory(void *block) { free(block); }
