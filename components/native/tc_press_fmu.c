/* Glue of the Press FMU: the generic FMI wrapper's component functions (tc_fmu.h) on the native press model. */
#include <stdlib.h>

#include "tc_fmu.h"
#include "tc_fmu_model.h"
#include "tc_press.h"

struct tc_component {
    tc_press *model;
};

int tc_component_create(const tc_param_value *values, const char *resources, tc_component **out, tc_msg msg) {
    tc_press_params p;
    (void)resources;
    *out = NULL;
    tc_component *c = calloc(1, sizeof *c);
    if (c == NULL) return tc_fail(msg, TC_NOMEM, "out of memory for the press");
    tc_press_fill_params(values, &p);
    int rc = tc_press_create(&p, &c->model, msg);
    if (rc != TC_OK) {
        free(c);
        return rc;
    }
    *out = c;
    return TC_OK;
}

void tc_component_free(tc_component *c) {
    if (c == NULL) return;
    tc_press_free(c->model);
    free(c);
}

int tc_component_step(tc_component *c, double dt, const double *inputs, const double *derivatives, tc_msg msg) {
    (void)derivatives;
    (void)inputs;
    return tc_press_step(c->model, dt, msg);
}

void tc_component_outputs(const tc_component *c, double *outputs) { tc_press_outputs(c->model, outputs); }

int tc_component_after_step(tc_component *c, tc_msg msg) {
    (void)c;
    (void)msg;
    return TC_OK;
}

int tc_component_terminate(tc_component *c, char *log_line, size_t size, tc_msg msg) {
    (void)c;
    (void)msg;
    if (size > 0) log_line[0] = '\0';
    return TC_OK;
}

size_t tc_component_state_size(const tc_component *c) { return tc_press_state_size(c->model); }

void tc_component_get_state(const tc_component *c, void *buf) { tc_press_get_state(c->model, buf); }

int tc_component_set_state(tc_component *c, const void *buf, size_t size, tc_msg msg) {
    return tc_press_set_state(c->model, buf, size, msg);
}

const char *tc_component_note(const tc_component *c) {
    (void)c;
    return "";
}
