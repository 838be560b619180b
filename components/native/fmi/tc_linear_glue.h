/* The glue of an FMU whose model is one of the linear models (press, drawing machine; tc_linear.c): the
 * generic FMI wrapper's component functions (tc_fmu.h) on a model with the functions
 * <TC_GLUE>_create(params, &model, msg), _free, _outputs, _state_size, _get_state, _set_state and the
 * parameter filler <TC_GLUE>_fill_params (generated). Included once by the FMU's glue file, which defines
 *   TC_GLUE          the model's prefix (tc_press, tc_machine),
 *   TC_GLUE_WHAT     what it is, for messages ("the press"),
 *   TC_GLUE_STEP(model, dt, inputs, msg)   its step from the FMU's inputs (held: canInterpolateInputs = false).
 * The models have no side outputs, no files and nothing to say after creation. */
#include <stdlib.h>

#include "tc_fmu.h"
#include "tc_fmu_model.h"

#define TC_GLUE_CAT2(a, b) a##b
#define TC_GLUE_CAT(a, b) TC_GLUE_CAT2(a, b)
#define TC_GLUE_FN(suffix) TC_GLUE_CAT(TC_GLUE, suffix)

struct tc_component {
    TC_GLUE *model;
};

int tc_component_create(const tc_param_value *values, const char *resources, tc_component **out, tc_msg msg) {
    TC_GLUE_CAT(TC_GLUE, _params) p;
    (void)resources;
    *out = NULL;
    tc_component *c = calloc(1, sizeof *c);
    if (c == NULL) return tc_fail(msg, TC_NOMEM, "out of memory for %s", TC_GLUE_WHAT);
    TC_GLUE_FN(_fill_params)(values, &p);
    int rc = TC_GLUE_FN(_create)(&p, &c->model, msg);
    if (rc != TC_OK) {
        free(c);
        return rc;
    }
    *out = c;
    return TC_OK;
}

void tc_component_free(tc_component *c) {
    if (c == NULL) return;
    TC_GLUE_FN(_free)(c->model);
    free(c);
}

int tc_component_step(tc_component *c, double dt, const double *inputs, const double *derivatives, tc_msg msg) {
    (void)derivatives; /* canInterpolateInputs = false: always zero */
    return TC_GLUE_STEP(c->model, dt, inputs, msg);
}

int tc_component_start(tc_component *c, const double *inputs, tc_msg msg) {
    (void)c; /* the outputs at the start come from the state alone */
    (void)inputs;
    (void)msg;
    return TC_OK;
}

void tc_component_outputs(const tc_component *c, double *outputs) { TC_GLUE_FN(_outputs)(c->model, outputs); }

int tc_component_after_step(tc_component *c, tc_msg msg) {
    (void)c;
    (void)msg;
    return TC_OK;
}

int tc_component_warning(tc_component *c, tc_msg msg) {
    (void)c;
    (void)msg;
    return 0;
}

int tc_component_terminate(tc_component *c, char *log_line, size_t size, tc_msg msg) {
    (void)c;
    (void)msg;
    if (size > 0) log_line[0] = '\0';
    return TC_OK;
}

size_t tc_component_state_size(const tc_component *c) { return TC_GLUE_FN(_state_size)(c->model); }

void tc_component_get_state(const tc_component *c, void *buf) { TC_GLUE_FN(_get_state)(c->model, buf); }

int tc_component_set_state(tc_component *c, const void *buf, size_t size, tc_msg msg) {
    return TC_GLUE_FN(_set_state)(c->model, buf, size, msg);
}

const char *tc_component_note(const tc_component *c) {
    (void)c;
    return "";
}
