/* What the generic FMI wrappers (tc_fmi2.c, tc_fmi3.c, on the core tc_fmu_instance.c) know of an FMU: its
 * variables, and its component's glue.
 *
 * The variable table (TC_VARIABLES), the value references and the function that fills a model's parameter
 * struct are GENERATED from the component's description (tribocosim/components/<name>/component.py) by
 * tribocosim/components/native/toolchain/declarations.py into "tc_fmu_model.h" when an FMU is built; the same
 * description generates the modelDescription.xml, so the two cannot drift. A component's glue file
 * (tc_<name>_fmu.c) implements the tc_component functions below on top of its native model.
 *
 * Variables are numbered as in the model description: the parameters (the model's fields, then the FMU's
 * files), the inputs, then the outputs; the value reference of variable k is k. The FMI 3.0 FMU adds, after
 * them, the independent variable time and, for a component with array outputs (TC_N_ARRAYS > 0), the UInt64
 * structural parameter of their length and the arrays themselves (TC_VR_* in "tc_fmu_model.h").
 */
#ifndef TC_FMU_H
#define TC_FMU_H

#include <stddef.h>

#include "tc_common.h"

enum tc_kind { TC_KIND_REAL = 0, TC_KIND_INTEGER = 1, TC_KIND_STRING = 2 };
enum tc_causality { TC_CAUSALITY_PARAMETER = 0, TC_CAUSALITY_INPUT = 1, TC_CAUSALITY_OUTPUT = 2 };

typedef struct tc_variable {
    const char *name;
    int kind;                    /* enum tc_kind */
    int causality;               /* enum tc_causality */
    int index;                   /* position among the parameters, inputs or outputs */
    const char *unit;            /* "" for dimensionless and text */
    double start;                /* Real and Integer start value */
    const char *start_text;      /* String start value */
    int has_low, has_high;
    double low, high;            /* allowed range of a Real or Integer parameter: low <= value <= high (FMI's
                                  * min and max are inclusive: FMI 2.0 section 2.2.7, FMI 3.0 section 2.4.7) */
    const char *const *choices;  /* String parameters with a fixed set of values, else NULL */
    int n_choices;
} tc_variable;

/* A range an output or an input is built for (the component's Port low/high): an output outside it after a step,
 * or an input outside it in a step, is warned by the FMU. */
typedef struct tc_bound {
    int output;          /* index among the outputs, or among the inputs when input is 1 */
    int side;            /* -1: the output must be >= the bound, +1: <= */
    double value;        /* the bound, when parameter < 0 */
    int parameter;       /* index of the parameter whose value is the bound, or -1 */
    const char *bound;   /* the bound as declared: the parameter's name or the number */
    const char *why;     /* what lies outside */
    int input;           /* 1: the bound of an input (checked on the inputs of an accepted step) */
} tc_bound;

/* The value of one parameter: Real and Integer in `number`, String in `text` (owned by the instance) and,
 * for a parameter with choices, the index of its value in `choice`. */
typedef struct tc_param_value {
    double number;
    char *text;
    int choice;
} tc_param_value;

/* ----------------------------------------------------------------------------------------------------
 * A component's glue (one per FMU, linked with the wrapper). Every function that can fail returns a
 * tc_status with a message; TC_DISCARD from a step leaves the component's state unchanged.
 * -------------------------------------------------------------------------------------------------- */
typedef struct tc_component tc_component;

/* The component for checked parameter values (ranges and choices are checked by the wrapper); resources
 * is the FMU's resources folder (no trailing separator). TC_ERROR names the parameter or file at fault. */
int tc_component_create(const tc_param_value *values, const char *resources, tc_component **out, tc_msg msg);
void tc_component_free(tc_component *c);
/* Advance by dt [s] from the inputs (in their order) at the step's start; derivatives holds, per input k, its
 * first and second time derivative there (derivatives[2k], [2k + 1]): all zero (inputs held over the step)
 * unless the component interpolates inputs (TC_CAN_INTERPOLATE_INPUTS; FMI 2.0 canInterpolateInputs) and
 * the importer set them (fmi2SetRealInputDerivatives). */
int tc_component_step(tc_component *c, double dt, const double *inputs, const double *derivatives, tc_msg msg);
/* At the end of initialization: make the inputs (in their order) current without advancing time, so that the
 * outputs report what depends on them (the Port's initial_inputs); TC_DISCARD naming an input a step would refuse. */
int tc_component_start(tc_component *c, const double *inputs, tc_msg msg);
/* The outputs, in their order (Integer outputs as doubles). */
void tc_component_outputs(const tc_component *c, double *outputs);
/* After every accepted step (side outputs: the strip's field file); a failure makes the instance unusable. */
int tc_component_after_step(tc_component *c, tc_msg msg);
/* After every accepted step, once tc_component_after_step has run: 1 with a message the wrapper logs as a warning
 * (the step's status is then a warning), for results the model gives but does not support (the strip: mu below the
 * documented floor, once per instance); else 0. */
int tc_component_warning(tc_component *c, tc_msg msg);
/* At fmi2Terminate (write the side outputs); log_line receives what to log on success ("" for nothing). */
int tc_component_terminate(tc_component *c, char *log_line, size_t size, tc_msg msg);
/* The component's state as bytes (the model's state, and facts a restored state must match, e.g. the
 * friction table's hash). set returns TC_ERROR, state unchanged, for an image of another configuration. */
size_t tc_component_state_size(const tc_component *c);
void tc_component_get_state(const tc_component *c, void *buf);
int tc_component_set_state(tc_component *c, const void *buf, size_t size, tc_msg msg);
/* A line to log after creation ("" for none), e.g. which friction table is used. */
const char *tc_component_note(const tc_component *c);
/* FMI 3.0, components with array outputs only (TC_N_ARRAYS > 0): array output k (in the order of TC_ARRAYS)
 * into out, when out is not NULL; returns its length (the node count). */
size_t tc_component_array(const tc_component *c, int k, double *out);

#endif
