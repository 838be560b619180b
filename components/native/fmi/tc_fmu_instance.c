/* The FMI-version-independent part of a native FMU instance (see tc_fmu_instance.h). */
#include "tc_fmu_instance.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* an FMU state: a copy of everything that determines the future */
typedef struct saved_state {
    int phase;
    double time;
    tc_param_value values[TC_N_PARAMETERS];
    double inputs[TC_N_INPUTS > 0 ? TC_N_INPUTS : 1];
    double input_derivatives[2 * (TC_N_INPUTS > 0 ? TC_N_INPUTS : 1)];
    double outputs[TC_N_OUTPUTS];
    int has_component;
    size_t size;
    unsigned char *bytes;
    char failure[2048];
} saved_state;

static tc_msg msg_of(tc_instance *c) {
    tc_msg m = {c->message, sizeof c->message};
    c->message[0] = '\0';
    return m;
}

void tc_inst_logf(const tc_instance *c, int status, const char *fmt, ...) {
    static const char *const categories[] = {"logStatusOK", "logStatusWarning", "logStatusDiscard",
                                             "logStatusError", "logStatusFatal"};
    char text[4096];
    va_list ap;
    if (c == NULL || c->emit == NULL || status < TC_LOG_OK || status > TC_LOG_FATAL) return;
    if (status == TC_LOG_OK && !c->logging_on) return;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    c->emit(c, status, categories[status], text);
}

char *tc_inst_copy_text(const char *s) {
    size_t n = strlen(s ? s : "");
    char *out = malloc(n + 1);
    if (out != NULL) memcpy(out, s ? s : "", n + 1);
    return out;
}

static void free_values(tc_param_value *v) {
    for (int k = 0; k < TC_N_PARAMETERS; ++k) {
        free(v[k].text);
        v[k].text = NULL;
    }
}

/* copy parameter values (strings duplicated); 0 when out of memory */
static int copy_values(tc_param_value *dst, const tc_param_value *src) {
    for (int k = 0; k < TC_N_PARAMETERS; ++k) {
        dst[k] = src[k];
        dst[k].text = NULL;
        if (src[k].text != NULL && (dst[k].text = tc_inst_copy_text(src[k].text)) == NULL) return 0;
    }
    return 1;
}

static int same_values(const tc_param_value *a, const tc_param_value *b) {
    for (int k = 0; k < TC_N_PARAMETERS; ++k) {
        if (memcmp(&a[k].number, &b[k].number, sizeof(double)) != 0) return 0;
        if ((a[k].text == NULL) != (b[k].text == NULL)) return 0;
        if (a[k].text != NULL && strcmp(a[k].text, b[k].text) != 0) return 0;
    }
    return 1;
}

static int set_defaults(tc_instance *c) {
    for (int k = 0; k < TC_N_VARIABLES; ++k) {
        const tc_variable *v = &TC_VARIABLES[k];
        if (v->causality == TC_CAUSALITY_PARAMETER) {
            tc_param_value *p = &c->values[v->index];
            free(p->text);
            p->text = NULL;
            p->number = v->start;
            p->choice = 0;
            if (v->kind == TC_KIND_STRING && (p->text = tc_inst_copy_text(v->start_text)) == NULL) return 0;
        } else if (v->causality == TC_CAUSALITY_INPUT) {
            c->inputs[v->index] = v->start;
        } else {
            c->outputs[v->index] = v->start;
        }
    }
    memset(c->input_derivatives, 0, sizeof c->input_derivatives);
    c->time = 0.0;
    return 1;
}

static void free_component(tc_instance *c) {
    tc_component_free(c->component);
    c->component = NULL;
}

int tc_inst_init(tc_instance *c, const char *name, char *resources, int logging_on) {
    c->logging_on = logging_on ? 1 : 0;
    c->name = tc_inst_copy_text(name ? name : "");
    c->resources = resources;
    if (c->name == NULL || c->resources == NULL || !set_defaults(c)) {
        tc_inst_release(c);
        return 0;
    }
    c->phase = TC_PHASE_INSTANTIATED;
    return 1;
}

void tc_inst_release(tc_instance *c) {
    free_component(c);
    free_values(c->values);
    free(c->name);
    free(c->resources);
    c->name = c->resources = NULL;
}

int tc_inst_reset(tc_instance *c) {
    free_component(c);
    c->failure[0] = '\0';
    c->terminate_requested = 0;
    c->refused = 0;
    c->generation += 1;
    memset(c->outside, 0, sizeof c->outside);
    if (!set_defaults(c)) return 0;
    c->phase = TC_PHASE_INSTANTIATED;
    return 1;
}

int tc_inst_fail(tc_instance *c, const char *what) {
    snprintf(c->failure, sizeof c->failure, "%s", what);
    c->phase = TC_PHASE_FAILED;
    tc_inst_logf(c, TC_LOG_ERROR, "%s", what);
    return TC_LOG_ERROR;
}

/* A bound for a message: "%g", with more digits when that does not read back as the bound (components/params.py's
 * bound_text prints the same). */
static void bound_text(double x, char *buf, size_t size) {
    for (int digits = 6; digits <= 17; ++digits) {
        snprintf(buf, size, "%.*g", digits, x);
        if (strtod(buf, NULL) == x) return;
    }
}

/* The check of one parameter (ranges as components/params.py's validate_fields); 0 if it is bad. */
static int check_parameter(tc_instance *c, const tc_variable *v, tc_param_value *p) {
    char a[TC_REPR_SIZE], lo[40], hi[40];
    const char *unit = v->unit && v->unit[0] && strcmp(v->unit, "1") != 0 ? v->unit : "";
    const char *sp = unit[0] ? " " : "";
    if (v->kind == TC_KIND_STRING) {
        if (v->choices == NULL) return 1;
        for (int k = 0; k < v->n_choices; ++k) {
            if (strcmp(p->text, v->choices[k]) == 0) {
                p->choice = k;
                return 1;
            }
        }
        char allowed[512] = "";
        for (int k = 0; k < v->n_choices; ++k) {
            if (k) strncat(allowed, ", ", sizeof allowed - strlen(allowed) - 1);
            strncat(allowed, v->choices[k], sizeof allowed - strlen(allowed) - 1);
        }
        snprintf(c->message, sizeof c->message, "%s = '%s' is not allowed; choose one of %s", v->name, p->text,
                 allowed);
        return 0;
    }
    if (!isfinite(p->number)) {
        snprintf(c->message, sizeof c->message, "%s = %s is not finite; a finite number is required", v->name,
                 tc_repr_double(p->number, a));
        return 0;
    }
    /* min and max inclusive, as the model description says, a value within TC_BOUND_RTOL of one on it (as the
     * declaration's checks, components/params.py); an integer's bounds are exact */
    const int integer = v->kind == TC_KIND_INTEGER;
    int ok_lo = !v->has_low || (integer ? p->number >= v->low : !tc_below(p->number, v->low));
    int ok_hi = !v->has_high || (integer ? p->number <= v->high : !tc_above(p->number, v->high));
    if (ok_lo && ok_hi) return 1;
    bound_text(v->low, lo, sizeof lo);
    bound_text(v->high, hi, sizeof hi);
    if (v->kind == TC_KIND_INTEGER) snprintf(a, sizeof a, "%.0f", p->number);
    else tc_repr_double(p->number, a);
    snprintf(c->message, sizeof c->message, "%s = %s%s%s is out of range; allowed: %s%s, %s%s%s%s", v->name, a, sp,
             unit, v->has_low ? "[" : "(", v->has_low ? lo : "-inf", v->has_high ? hi : "inf",
             v->has_high ? "]" : ")", sp, unit);
    return 0;
}

int tc_inst_make_component(tc_instance *c) {
    char text[2300];
    for (int k = 0; k < TC_N_PARAMETERS; ++k) {
        if (!check_parameter(c, &TC_VARIABLES[k], &c->values[k])) {
            snprintf(text, sizeof text, "initialization failed: %s", c->message);
            return tc_inst_fail(c, text);
        }
    }
    free_component(c);
    int rc = tc_component_create(c->values, c->resources, &c->component, msg_of(c));
    if (rc != TC_OK) {
        snprintf(text, sizeof text, "initialization failed: %s", c->message);
        return tc_inst_fail(c, text);
    }
    tc_component_outputs(c->component, c->outputs);
    if (tc_component_note(c->component)[0]) tc_inst_logf(c, TC_LOG_OK, "%s", tc_component_note(c->component));
    memset(c->outside, 0, sizeof c->outside); /* outputs outside a range from the start are warned at the first step */
    c->terminate_requested = 0;
    c->refused = 0;
    c->generation += 1;
    return TC_LOG_OK;
}

int tc_inst_initial_outputs(tc_instance *c, const char *function) {
    if (c->phase != TC_PHASE_INITIALIZATION) return TC_LOG_OK;
    const int logging = c->logging_on;
    c->logging_on = 0; /* the component's note is logged when initialization ends */
    const int made = tc_inst_make_component(c);
    c->logging_on = logging;
    if (made != TC_LOG_OK) { /* the parameters can still be changed: not a failed instance yet */
        c->phase = TC_PHASE_INITIALIZATION;
        c->failure[0] = '\0';
        tc_inst_logf(c, TC_LOG_ERROR, "%s: the outputs cannot be computed in initialization mode (%s)", function,
                     c->message);
        return TC_LOG_ERROR;
    }
    if (tc_component_start(c->component, c->inputs, msg_of(c)) == TC_OK) tc_component_outputs(c->component, c->outputs);
    return TC_LOG_OK;
}

int tc_inst_exit_initialization(tc_instance *c) {
    double start = c->time;
    if (tc_inst_make_component(c) != TC_LOG_OK) return TC_LOG_ERROR;
    /* the outputs at the communication point t = start are the model's for the inputs set during initialization
     * (initial="calculated"); inputs a step would refuse are logged, and the first doStep discards them */
    int status = TC_LOG_OK;
    if (tc_component_start(c->component, c->inputs, msg_of(c)) == TC_OK) {
        tc_component_outputs(c->component, c->outputs);
    } else {
        tc_inst_logf(c, TC_LOG_WARNING, "at the end of initialization: %s; the outputs keep the values without the "
                     "inputs", c->message);
        status = TC_LOG_WARNING;
    }
    c->time = start;
    c->phase = TC_PHASE_STEPPING;
    return status;
}

int tc_inst_terminate(tc_instance *c) {
    char line[1024] = "";
    if (c->phase == TC_PHASE_FAILED || c->component == NULL) {
        c->phase = c->phase == TC_PHASE_FAILED ? TC_PHASE_FAILED : TC_PHASE_TERMINATED;
        return TC_LOG_OK;
    }
    c->phase = TC_PHASE_TERMINATED;
    if (tc_component_terminate(c->component, line, sizeof line, msg_of(c)) != TC_OK) {
        tc_inst_logf(c, TC_LOG_ERROR, "terminate: %s", c->message);
        return TC_LOG_ERROR;
    }
    if (line[0]) tc_inst_logf(c, TC_LOG_OK, "%s", line);
    return TC_LOG_OK;
}

/* The value of bound b for the instance's parameters. */
static double bound_value(const tc_instance *c, const tc_bound *b) {
    return b->parameter >= 0 ? c->values[b->parameter].number : b->value;
}

/* Whether output or input k of TC_BOUNDS is outside its bound by more than TC_BOUND_RTOL of the bound (a draw of
 * exactly draw_length ends 2.2e-15 m beyond it after 1750 steps: round-off, not a longer draw). */
static int is_outside(const tc_instance *c, int k) {
    const tc_bound *b = &TC_BOUNDS[k];
    const double y = b->input ? c->inputs[b->output] : c->outputs[b->output], limit = bound_value(c, b);
    return b->side < 0 ? tc_below(y, limit) : tc_above(y, limit);
}

/* Which outputs are outside their bounds now (after a restored state: no warning for what it already held). */
static void note_outside(tc_instance *c) {
    for (int k = 0; k < TC_N_BOUNDS; ++k) c->outside[k] = (unsigned char)is_outside(c, k);
}

/* After an accepted step that ends at c->time: TC_LOG_WARNING, logged, for each output that has just left a range
 * it is built for and each input of the step that has; TC_LOG_OK otherwise. */
static int check_bounds(tc_instance *c) {
    char a[TC_REPR_SIZE], b[TC_REPR_SIZE], t[TC_REPR_SIZE];
    int status = TC_LOG_OK;
    for (int k = 0; k < TC_N_BOUNDS; ++k) {
        int out = is_outside(c, k);
        if (out && !c->outside[k]) {
            const tc_bound *bd = &TC_BOUNDS[k];
            const tc_variable *v = &TC_VARIABLES[TC_N_PARAMETERS + (bd->input ? 0 : TC_N_INPUTS) + bd->output];
            const char *unit = strcmp(v->unit, "1") != 0 ? v->unit : "";
            const double y = bd->input ? c->inputs[bd->output] : c->outputs[bd->output];
            tc_inst_logf(c, TC_LOG_WARNING, "%s t = %s s %s = %s%s%s is %s %s%s%s%s%s, the %s %s the model is built "
                         "for (%s); the results from here on are outside what it describes",
                         bd->input ? "in the step to" : "at", tc_repr_double(c->time, t), v->name,
                         tc_repr_double(y, a),
                         unit[0] ? " " : "", unit, bd->side < 0 ? "below" : "above",
                         bd->parameter >= 0 ? bd->bound : "", bd->parameter >= 0 ? " = " : "",
                         tc_repr_double(bound_value(c, bd), b), unit[0] ? " " : "", unit,
                         bd->side < 0 ? "least" : "largest", v->name, bd->why);
            status = TC_LOG_WARNING;
        }
        c->outside[k] = (unsigned char)out;
    }
    return status;
}

/* Whether a step 2^-20 as long as dt from the same state and inputs is discarded too (then the inputs, not the
 * step size, are at fault). The probe's state is undone; 0 if it cannot be tried (no memory). */
static int discarded_at_any_step(tc_instance *c, double dt) {
    static const double PROBE = 0x1p-20;
    char text[1024];
    tc_msg m = {text, sizeof text};
    double zero[2 * (TC_N_INPUTS > 0 ? TC_N_INPUTS : 1)] = {0};
    size_t size = tc_component_state_size(c->component);
    unsigned char *saved = malloc(size ? size : 1);
    if (saved == NULL) return 0;
    tc_component_get_state(c->component, saved);
    int rc = tc_component_step(c->component, dt * PROBE, c->inputs, zero, m);
    if (rc != TC_DISCARD && tc_component_set_state(c->component, saved, size, m) != TC_OK) rc = TC_ERROR;
    free(saved);
    return rc == TC_DISCARD;
}

/* whether doStep(t, dt) repeats the last discarded call unchanged: the same state, time, step and inputs */
static int repeats_refusal(const tc_instance *c, double t, double dt) {
    return c->refused && c->refused_generation == c->generation && memcmp(&c->refused_t, &t, sizeof t) == 0 &&
           memcmp(&c->refused_dt, &dt, sizeof dt) == 0 &&
           memcmp(c->refused_inputs, c->inputs, sizeof c->inputs) == 0 &&
           memcmp(c->refused_derivatives, c->input_derivatives, sizeof c->input_derivatives) == 0;
}

int tc_inst_do_step(tc_instance *c, double t, double dt) {
    char a[TC_REPR_SIZE], b[TC_REPR_SIZE], text[4096];
    if (c->phase == TC_PHASE_FAILED) {
        tc_inst_logf(c, TC_LOG_ERROR, "doStep refused: the FMU is not usable (%s)", c->failure);
        return TC_LOG_ERROR;
    }
    if (c->phase != TC_PHASE_STEPPING || c->component == NULL) {
        tc_inst_logf(c, TC_LOG_ERROR, "doStep refused: the FMU has not left initialization mode");
        return TC_LOG_ERROR;
    }
    if (repeats_refusal(c, t, dt)) {
        c->terminate_requested = 1;
        tc_inst_logf(c, TC_LOG_DISCARD, "doStep from t = %s s by %s s repeats a step this FMU discarded, unchanged (the "
                     "same state, step size and inputs), so it is discarded again (%s); the FMU asks to end the "
                     "simulation (%s): retry from a restored state with a shorter step or other inputs instead",
                     tc_repr_double(t, a), tc_repr_double(dt, b), c->refusal,
                     c->terminate_name ? c->terminate_name : "terminate");
        return TC_LOG_DISCARD;
    }
    c->refused = 0;
    c->refused_t = t;
    c->refused_dt = dt;
    memcpy(c->refused_inputs, c->inputs, sizeof c->inputs);
    memcpy(c->refused_derivatives, c->input_derivatives, sizeof c->input_derivatives);
    int rc = tc_component_step(c->component, dt, c->inputs, c->input_derivatives, msg_of(c));
    memset(c->input_derivatives, 0, sizeof c->input_derivatives); /* they were for this step */
    c->terminate_requested = 0;
    if (rc != TC_OK) {
        char shown[1024] = ""; /* the inputs, for the message (made only for a refused step) */
        for (int k = 0; k < TC_N_VARIABLES; ++k) {
            const tc_variable *v = &TC_VARIABLES[k];
            if (v->causality != TC_CAUSALITY_INPUT) continue;
            char one[160];
            snprintf(one, sizeof one, "%s%s = %s %s", shown[0] ? ", " : "", v->name,
                     tc_repr_double(c->inputs[v->index], a), v->unit[0] ? v->unit : "1");
            strncat(shown, one, sizeof shown - strlen(shown) - 1);
        }
        if (rc == TC_DISCARD && dt > 0.0 && discarded_at_any_step(c, dt)) c->terminate_requested = 1;
        snprintf(text, sizeof text, "doStep from t = %s s by %s s rejected: %s %s%s%sthe FMU state is unchanged%s",
                 tc_repr_double(t, a), tc_repr_double(dt, b), c->message, shown[0] ? "(inputs " : "", shown,
                 shown[0] ? "); " : "; ",
                 c->terminate_requested ? "; a step 2^-20 as long is rejected too, so no step size can complete it "
                                          "(the inputs are at fault): the simulation cannot go on (an error; a host "
                                          "may restore an FMU state taken before)" : "");
        if (rc != TC_DISCARD || c->terminate_requested) return tc_inst_fail(c, text);
        tc_inst_logf(c, TC_LOG_DISCARD, "%s", text);
        c->refused = 1;
        c->refused_generation = c->generation;
        snprintf(c->refusal, sizeof c->refusal, "%s", c->message);
        return TC_LOG_DISCARD;
    }
    c->generation += 1;
    tc_component_outputs(c->component, c->outputs);
    c->time = t + dt;
    if (tc_component_after_step(c->component, msg_of(c)) != TC_OK) {
        snprintf(text, sizeof text, "after the step to t = %s s: %s", tc_repr_double(c->time, a), c->message);
        return tc_inst_fail(c, text);
    }
    int status = check_bounds(c);
    if (tc_component_warning(c->component, msg_of(c))) {
        tc_inst_logf(c, TC_LOG_WARNING, "at t = %s s %s", tc_repr_double(c->time, a), c->message);
        status = TC_LOG_WARNING;
    }
    return status;
}

void tc_inst_set_input(tc_instance *c, const tc_variable *v, double value) {
    c->inputs[v->index] = value; /* checked by the model at the next step */
    c->input_derivatives[2 * v->index] = 0.0;
    c->input_derivatives[2 * v->index + 1] = 0.0;
}

int tc_inst_set_input_derivative(tc_instance *c, const tc_variable *v, int order, double value, const char *function) {
    char a[TC_REPR_SIZE];
    if (!TC_CAN_INTERPOLATE_INPUTS) {
        tc_inst_logf(c, TC_LOG_ERROR, "%s: %s holds its inputs over a step (canInterpolateInputs = false)", function,
                     TC_MODEL_IDENTIFIER);
        return TC_LOG_ERROR;
    }
    if (v->causality != TC_CAUSALITY_INPUT || v->kind != TC_KIND_REAL) {
        tc_inst_logf(c, TC_LOG_ERROR, "%s: %s is not a Real input; only inputs have derivatives", function, v->name);
        return TC_LOG_ERROR;
    }
    if (order != 1 && order != 2) {
        tc_inst_logf(c, TC_LOG_ERROR, "%s: derivative order %d of %s; this FMU takes orders 1 and 2", function, order,
                     v->name);
        return TC_LOG_ERROR;
    }
    if (!isfinite(value)) {
        tc_inst_logf(c, TC_LOG_ERROR, "%s: derivative %d of %s = %s is not finite; a finite number is required",
                     function, order, v->name, tc_repr_double(value, a));
        return TC_LOG_ERROR;
    }
    c->input_derivatives[2 * v->index + (order - 1)] = value;
    return TC_LOG_OK;
}

/* ================================================================================= variables */
const tc_variable *tc_inst_variable(const tc_instance *c, unsigned vr, int kind, const char *function,
                                    const char *const kind_names[3], unsigned last_vr) {
    if (vr >= (unsigned)TC_N_VARIABLES) {
        tc_inst_logf(c, TC_LOG_ERROR, "%s: value reference %u is not a variable of %s (0 to %u)", function, vr,
                     TC_MODEL_IDENTIFIER, last_vr);
        return NULL;
    }
    const tc_variable *v = &TC_VARIABLES[vr];
    if (v->kind != kind) {
        tc_inst_logf(c, TC_LOG_ERROR, "%s: %s (value reference %u) is a %s", function, v->name, vr,
                     kind_names[v->kind]);
        return NULL;
    }
    return v;
}

double tc_inst_number(const tc_instance *c, const tc_variable *v) {
    return v->causality == TC_CAUSALITY_PARAMETER ? c->values[v->index].number
           : v->causality == TC_CAUSALITY_INPUT   ? c->inputs[v->index]
                                                  : c->outputs[v->index];
}

/* ================================================================================= FMU state */
void tc_inst_free_state(void *state) {
    saved_state *s = state;
    if (s == NULL) return;
    free_values(s->values);
    free(s->bytes);
    free(s);
}

int tc_inst_get_state(tc_instance *c, void **state, const char *function) {
    saved_state *s = *state ? (saved_state *)*state : calloc(1, sizeof *s);
    if (s == NULL) return TC_LOG_ERROR;
    free_values(s->values);
    free(s->bytes);
    s->bytes = NULL;
    s->size = 0;
    s->phase = c->phase;
    s->time = c->time;
    memcpy(s->inputs, c->inputs, sizeof s->inputs);
    memcpy(s->input_derivatives, c->input_derivatives, sizeof s->input_derivatives);
    memcpy(s->outputs, c->outputs, sizeof s->outputs);
    memcpy(s->failure, c->failure, sizeof s->failure);
    s->has_component = c->component != NULL;
    int ok = copy_values(s->values, c->values);
    if (ok && c->component != NULL) {
        s->size = tc_component_state_size(c->component);
        s->bytes = malloc(s->size ? s->size : 1);
        if (s->bytes == NULL) ok = 0;
        else tc_component_get_state(c->component, s->bytes);
    }
    if (!ok) {
        if (*state == NULL) tc_inst_free_state(s);
        tc_inst_logf(c, TC_LOG_ERROR, "%s: out of memory", function);
        return TC_LOG_ERROR;
    }
    *state = s;
    return TC_LOG_OK;
}

int tc_inst_set_state(tc_instance *c, const void *state) {
    const saved_state *s = state;
    char text[2300];
    if (!same_values(s->values, c->values) || (c->component != NULL) != s->has_component) {
        /* a state of another configuration: remake the component for the state's parameters */
        free_component(c);
        free_values(c->values);
        if (!copy_values(c->values, s->values)) return tc_inst_fail(c, "setFMUstate failed: out of memory");
        if (s->has_component) {
            double t = c->time;
            if (tc_inst_make_component(c) != TC_LOG_OK) return TC_LOG_ERROR;
            c->time = t;
        }
    }
    if (s->has_component && c->component != NULL &&
        tc_component_set_state(c->component, s->bytes, s->size, msg_of(c)) != TC_OK) {
        snprintf(text, sizeof text, "setFMUstate failed: %s", c->message);
        return tc_inst_fail(c, text);
    }
    c->phase = s->phase;
    c->time = s->time;
    memcpy(c->inputs, s->inputs, sizeof c->inputs);
    memcpy(c->input_derivatives, s->input_derivatives, sizeof c->input_derivatives);
    memcpy(c->outputs, s->outputs, sizeof c->outputs);
    memcpy(c->failure, s->failure, sizeof c->failure);
    c->terminate_requested = 0;
    c->refused = 0;
    c->generation += 1;
    if (s->has_component) note_outside(c);
    return TC_LOG_OK;
}

/* Serialized layout (little-endian fixed-size fields written byte by byte):
 *   magic "TCFMUST2", GUID (length-prefixed), phase, time, inputs, input derivatives, outputs, failure text,
 *   per parameter: number (8 bytes), choice, text (length-prefixed, or length ~0 for none), has_component,
 *   component bytes (length-prefixed). */
typedef struct writer {
    unsigned char *buf;
    size_t size, pos;
} writer;

static void put(writer *w, const void *src, size_t n) {
    if (w->buf != NULL && w->pos + n <= w->size) memcpy(w->buf + w->pos, src, n);
    w->pos += n;
}

static void put_u64(writer *w, unsigned long long x) {
    unsigned char b[8];
    for (int k = 0; k < 8; ++k) b[k] = (unsigned char)(x >> (8 * k));
    put(w, b, 8);
}

static void put_double(writer *w, double x) {
    unsigned long long u;
    memcpy(&u, &x, 8);
    put_u64(w, u);
}

static void put_text(writer *w, const char *s) {
    if (s == NULL) {
        put_u64(w, ~0ULL);
        return;
    }
    size_t n = strlen(s);
    put_u64(w, n);
    put(w, s, n);
}

size_t tc_inst_serialize(const void *state, unsigned char *buf, size_t size) {
    const saved_state *s = state;
    writer w = {buf, size, 0};
    put(&w, "TCFMUST2", 8);
    put_text(&w, TC_GUID);
    put_u64(&w, (unsigned long long)s->phase);
    put_double(&w, s->time);
    for (int k = 0; k < (TC_N_INPUTS > 0 ? TC_N_INPUTS : 1); ++k) put_double(&w, s->inputs[k]);
    for (int k = 0; k < 2 * (TC_N_INPUTS > 0 ? TC_N_INPUTS : 1); ++k) put_double(&w, s->input_derivatives[k]);
    for (int k = 0; k < TC_N_OUTPUTS; ++k) put_double(&w, s->outputs[k]);
    put_text(&w, s->failure);
    for (int k = 0; k < TC_N_PARAMETERS; ++k) {
        put_double(&w, s->values[k].number);
        put_u64(&w, (unsigned long long)s->values[k].choice);
        put_text(&w, s->values[k].text);
    }
    put_u64(&w, (unsigned long long)s->has_component);
    put_u64(&w, s->size);
    put(&w, s->bytes, s->bytes ? s->size : 0);
    return w.pos;
}

typedef struct reader {
    const unsigned char *buf;
    size_t size, pos;
    int ok;
} reader;

static const unsigned char *take(reader *r, size_t n) {
    if (!r->ok || n > r->size - r->pos) {
        r->ok = 0;
        return NULL;
    }
    const unsigned char *p = r->buf + r->pos;
    r->pos += n;
    return p;
}

static unsigned long long get_u64(reader *r) {
    const unsigned char *b = take(r, 8);
    unsigned long long x = 0;
    if (b == NULL) return 0;
    for (int k = 7; k >= 0; --k) x = (x << 8) | b[k];
    return x;
}

static double get_double(reader *r) {
    unsigned long long u = get_u64(r);
    double x;
    memcpy(&x, &u, 8);
    return x;
}

/* a length-prefixed text (NULL for the "none" marker); r->ok cleared on malformed input */
static char *get_text(reader *r, int *none) {
    unsigned long long n = get_u64(r);
    *none = 0;
    if (!r->ok) return NULL;
    if (n == ~0ULL) {
        *none = 1;
        return NULL;
    }
    const unsigned char *p = take(r, (size_t)n);
    if (p == NULL || n != (size_t)n) {
        r->ok = 0;
        return NULL;
    }
    char *s = malloc((size_t)n + 1);
    if (s == NULL) {
        r->ok = 0;
        return NULL;
    }
    memcpy(s, p, (size_t)n);
    s[n] = '\0';
    if (strlen(s) != (size_t)n) { /* an embedded NUL: not ours */
        free(s);
        r->ok = 0;
        return NULL;
    }
    return s;
}

int tc_inst_deserialize(tc_instance *c, const unsigned char *bytes, size_t size, void **state,
                        const char *function, const char *token_label) {
    reader r = {bytes, size, 0, 1};
    int none;
    saved_state *s = calloc(1, sizeof *s);
    if (s == NULL) return TC_LOG_ERROR;
    const unsigned char *magic = take(&r, 8);
    char *guid = NULL;
    if (magic == NULL || memcmp(magic, "TCFMUST2", 8) != 0) r.ok = 0;
    if (r.ok) guid = get_text(&r, &none);
    if (r.ok && (guid == NULL || strcmp(guid, TC_GUID) != 0)) {
        tc_inst_logf(c, TC_LOG_ERROR, "%s: the state was serialized by another FMU (%s %s; this FMU is %s)", function,
                     token_label, guid ? guid : "none", TC_GUID);
        free(guid);
        tc_inst_free_state(s);
        return TC_LOG_ERROR;
    }
    free(guid);
    unsigned long long phase = get_u64(&r);
    s->phase = (int)phase;
    if (phase > TC_PHASE_FAILED) r.ok = 0;
    s->time = get_double(&r);
    for (int k = 0; k < (TC_N_INPUTS > 0 ? TC_N_INPUTS : 1); ++k) s->inputs[k] = get_double(&r);
    for (int k = 0; k < 2 * (TC_N_INPUTS > 0 ? TC_N_INPUTS : 1); ++k) s->input_derivatives[k] = get_double(&r);
    for (int k = 0; k < TC_N_OUTPUTS; ++k) s->outputs[k] = get_double(&r);
    char *failure = get_text(&r, &none);
    if (failure != NULL) {
        snprintf(s->failure, sizeof s->failure, "%s", failure);
        free(failure);
    }
    for (int k = 0; k < TC_N_PARAMETERS && r.ok; ++k) {
        s->values[k].number = get_double(&r);
        unsigned long long choice = get_u64(&r);
        s->values[k].choice = (int)choice;
        if (choice > 1000000ULL) r.ok = 0;
        s->values[k].text = get_text(&r, &none);
        if (r.ok && (TC_VARIABLES[k].kind == TC_KIND_STRING) == (s->values[k].text == NULL)) r.ok = 0;
    }
    unsigned long long has = get_u64(&r);
    s->has_component = (int)has;
    if (has > 1) r.ok = 0;
    unsigned long long n = get_u64(&r);
    const unsigned char *component = r.ok ? take(&r, (size_t)n) : NULL;
    if (r.ok && n == (size_t)n && (s->bytes = malloc(n ? (size_t)n : 1)) != NULL) {
        memcpy(s->bytes, component, (size_t)n);
        s->size = (size_t)n;
    } else {
        r.ok = 0;
    }
    if (!r.ok || r.pos != size) {
        tc_inst_logf(c, TC_LOG_ERROR, "%s: %zu bytes that are not a serialized state of %s", function, size,
                     TC_MODEL_IDENTIFIER);
        tc_inst_free_state(s);
        return TC_LOG_ERROR;
    }
    tc_inst_free_state(*state);
    *state = s;
    return TC_LOG_OK;
}
