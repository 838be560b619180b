/* Glue of the StripDraw FMU: the generic FMI wrapper's component functions (tc_fmu.h) on the native
 * strip-draw model, with what the component (tribocosim/components/stripdraw/component.py) declares:
 *
 *   - table_file: the friction table used when friction_model = table, relative to the FMU's resources
 *     folder or absolute, read in its resource form by tc_table_read (the build converts the shipped table
 *     into resources/); its content hash is part of the state image, so a state is restored only into an
 *     instance using the same table;
 *   - field_input: the strip starts from the last beta row of a field file written for this mesh;
 *   - field_output / field_output_interval: the nodal fields recorded at the start, after every step at
 *     least the interval after the last row, and written at terminate with the final state (tc_fields);
 *     a restored state drops the rows recorded after its time;
 *   - FMI 3.0: the nodal fields beta, U and contact of the current state as array outputs;
 *   - the first accepted step after which the least mu under the pad lies below the documented floor
 *     (tc_stripdraw_floor_note) is a warning naming the setting that lets it, once per instance: a restored state
 *     keeps whether it was given (a host that retries a step from a state taken before is not told again).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tc_fields.h"
#include "tc_fmu.h"
#include "tc_fmu_model.h"
#include "tc_stripdraw.h"
#include "tc_table_file.h"

#define HASH_SIZE 64

struct tc_component {
    tc_stripdraw *model;
    tc_table *table;
    tc_field_recorder *recorder;
    size_t n;
    double *X, *U, *beta, *contact; /* work rows for the recorder */
    char table_hash[HASH_SIZE + 1];  /* "" without a table */
    int floor_warned;                /* the floor warning was given */
    char note[1024];
};

static int is_absolute(const char *path) {
    return path[0] == '/' || path[0] == '\\' || (path[0] && path[1] == ':');
}

/* the FMU's parameters as "name: value" lines (the field file's parameter lines) */
static char *parameters_text(const tc_param_value *values) {
    size_t size = 16, used = 0;
    char number[TC_REPR_SIZE];
    for (int k = 0; k < TC_N_PARAMETERS; ++k)
        size += strlen(TC_VARIABLES[k].name) + 8 + TC_REPR_SIZE + (values[k].text ? strlen(values[k].text) : 0);
    char *out = malloc(size);
    if (out == NULL) return NULL;
    out[0] = '\0';
    for (int k = 0; k < TC_N_PARAMETERS; ++k) {
        const tc_variable *v = &TC_VARIABLES[k];
        const char *value = v->kind == TC_KIND_STRING ? values[k].text : tc_repr_double(values[k].number, number);
        used += (size_t)snprintf(out + used, size - used, "%s: %s\n", v->name, value);
    }
    return out;
}

static int record(tc_component *c, int force, tc_msg msg) {
    tc_stripdraw_fields(c->model, NULL, c->U, c->beta, NULL, c->contact);
    return tc_field_recorder_record(c->recorder, tc_stripdraw_time(c->model), c->beta, c->U, c->contact, force, msg);
}

void tc_component_free(tc_component *c) {
    if (c == NULL) return;
    tc_stripdraw_free(c->model);
    tc_table_free(c->table);
    tc_field_recorder_free(c->recorder);
    free(c->X);
    free(c->U);
    free(c->beta);
    free(c->contact);
    free(c);
}

int tc_component_create(const tc_param_value *values, const char *resources, tc_component **out, tc_msg msg) {
    tc_stripdraw_params p;
    int rc = TC_OK;
    *out = NULL;
    tc_component *c = calloc(1, sizeof *c);
    if (c == NULL) return tc_fail(msg, TC_NOMEM, "out of memory for the strip-draw FMU");
    tc_stripdraw_fill_params(values, &p);
    if (p.friction_model == TC_STRIPDRAW_FRICTION_MODEL_TABLE) {
        const char *file = values[TC_P_table_file].text;
        size_t n = strlen(resources) + strlen(file) + 2;
        char *path = malloc(n);
        if (path == NULL) {
            tc_component_free(c);
            return tc_fail(msg, TC_NOMEM, "out of memory for the table path");
        }
        if (is_absolute(file)) snprintf(path, n, "%s", file);
        else snprintf(path, n, "%s/%s", resources, file);
        rc = tc_table_read(path, &c->table, msg);
        char *read = rc == TC_OK ? malloc(n) : NULL; /* the file read: the resource form of a .npz */
        if (rc == TC_OK && read == NULL) rc = tc_fail(msg, TC_NOMEM, "out of memory for the table path");
        if (rc == TC_OK) {
            tc_table_resource_path(path, read, n);
            snprintf(c->table_hash, sizeof c->table_hash, "%s", c->table->content_hash);
            snprintf(c->note, sizeof c->note, "friction table %s: provenance %s, content hash %s", read,
                     c->table->provenance, c->table->content_hash);
        }
        free(read);
        free(path);
        if (rc != TC_OK) {
            tc_component_free(c);
            return rc == TC_NOMEM ? TC_NOMEM : TC_ERROR;
        }
    }
    rc = tc_stripdraw_create(&p, c->table, NULL, 0, &c->model, msg);
    if (rc == TC_OK) {
        c->n = tc_stripdraw_n_nodes(c->model);
        c->X = malloc(c->n * sizeof(double));
        c->U = malloc(c->n * sizeof(double));
        c->beta = malloc(c->n * sizeof(double));
        c->contact = malloc(c->n * sizeof(double));
        if (!c->X || !c->U || !c->beta || !c->contact) rc = tc_fail(msg, TC_NOMEM, "out of memory for the fields");
        else tc_stripdraw_fields(c->model, c->X, NULL, NULL, NULL, NULL);
    }
    if (rc == TC_OK && values[TC_P_field_input].text[0]) { /* a later pass: start from the last beta row */
        rc = tc_field_read_initial_beta(values[TC_P_field_input].text, c->n, c->X, c->beta, msg);
        if (rc == TC_OK) {
            tc_stripdraw_free(c->model);
            c->model = NULL;
            rc = tc_stripdraw_create(&p, c->table, c->beta, c->n, &c->model, msg);
        }
    }
    if (rc == TC_OK && values[TC_P_field_output].text[0]) {
        double window[2];
        char *text = parameters_text(values);
        tc_stripdraw_window(c->model, window);
        rc = text == NULL ? tc_fail(msg, TC_NOMEM, "out of memory for the field metadata")
                          : tc_field_recorder_create(values[TC_P_field_output].text,
                                                     values[TC_P_field_output_interval].number, c->n, c->X, window,
                                                     text, &c->recorder, msg);
        free(text);
        if (rc == TC_OK) rc = record(c, 1, msg);
    }
    if (rc != TC_OK) {
        tc_component_free(c);
        return rc == TC_NOMEM ? TC_NOMEM : TC_ERROR;
    }
    *out = c;
    return TC_OK;
}

int tc_component_step(tc_component *c, double dt, const double *inputs, const double *derivatives, tc_msg msg) {
    /* normal_force, grip_velocity with their derivatives (canInterpolateInputs = true) */
    return tc_stripdraw_step_poly(c->model, dt, inputs[0], derivatives, inputs[1], derivatives + 2, msg);
}

int tc_component_start(tc_component *c, const double *inputs, tc_msg msg) {
    return tc_stripdraw_set_inputs(c->model, inputs[0], inputs[1], msg);
}

void tc_component_outputs(const tc_component *c, double *outputs) { tc_stripdraw_outputs(c->model, outputs); }

int tc_component_after_step(tc_component *c, tc_msg msg) {
    return c->recorder == NULL ? TC_OK : record(c, 0, msg);
}

int tc_component_warning(tc_component *c, tc_msg msg) {
    if (c->floor_warned || !tc_stripdraw_floor_note(c->model, msg)) return 0;
    c->floor_warned = 1;
    return 1;
}

int tc_component_terminate(tc_component *c, char *log_line, size_t size, tc_msg msg) {
    if (size > 0) log_line[0] = '\0';
    if (c->recorder == NULL) return TC_OK;
    tc_stripdraw_fields(c->model, NULL, c->U, c->beta, NULL, c->contact); /* the final state is always in the file */
    int rc = tc_field_recorder_finish(c->recorder, tc_stripdraw_time(c->model), c->beta, c->U, c->contact, msg);
    if (rc == TC_OK && size > 0)
        snprintf(log_line, size, "field_output: %zu rows written", tc_field_recorder_rows(c->recorder));
    return rc;
}

/* state image: the table hash (64 characters, blank without a table), then the model's image */
size_t tc_component_state_size(const tc_component *c) { return HASH_SIZE + tc_stripdraw_state_size(c->model); }

void tc_component_get_state(const tc_component *c, void *buf) {
    memset(buf, ' ', HASH_SIZE);
    memcpy(buf, c->table_hash, strlen(c->table_hash));
    tc_stripdraw_get_state(c->model, (unsigned char *)buf + HASH_SIZE);
}

int tc_component_set_state(tc_component *c, const void *buf, size_t size, tc_msg msg) {
    char mine[HASH_SIZE], theirs[HASH_SIZE + 1];
    if (size < HASH_SIZE) return tc_fail(msg, TC_ERROR, "the state image is too short (%zu bytes)", size);
    memset(mine, ' ', HASH_SIZE);
    memcpy(mine, c->table_hash, strlen(c->table_hash));
    if (memcmp(mine, buf, HASH_SIZE) != 0) {
        memcpy(theirs, buf, HASH_SIZE);
        theirs[HASH_SIZE] = '\0';
        return tc_fail(msg, TC_ERROR, "the FMU state was taken with friction table hash %s; this instance uses %s",
                       theirs, c->table_hash[0] ? c->table_hash : "none");
    }
    int rc = tc_stripdraw_set_state(c->model, (const unsigned char *)buf + HASH_SIZE, size - HASH_SIZE, msg);
    if (rc == TC_OK && c->recorder != NULL) tc_field_recorder_truncate(c->recorder, tc_stripdraw_time(c->model));
    return rc;
}

const char *tc_component_note(const tc_component *c) { return c->note; }

size_t tc_component_array(const tc_component *c, int k, double *out) {
    if (out != NULL)
        tc_stripdraw_fields(c->model, NULL, k == TC_A_U ? out : NULL, k == TC_A_beta ? out : NULL, NULL,
                            k == TC_A_contact ? out : NULL);
    return c->n;
}
