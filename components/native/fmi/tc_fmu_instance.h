/* The part of a native FMU instance that does not depend on the FMI version: shared by the FMI 2.0 wrapper
 * (tc_fmi2.c) and the FMI 3.0 wrapper (tc_fmi3.c), which add only the standard's function signatures, its
 * state machine and its logger.
 *
 * An instance holds the parameter values, the inputs and outputs, the time and the component (tc_fmu.h); the
 * functions below carry the status contract both wrappers promise:
 *
 *   - tc_inst_make_component checks every parameter against its declared range or choices and makes the
 *     component; a bad parameter or file fails the instance (TC_LOG_ERROR, a message naming the parameter, its
 *     value and what is allowed), after which every call that needs the model is an error;
 *   - tc_inst_do_step with a bad input or a step the model cannot take is TC_LOG_DISCARD with the state
 *     unchanged and a message naming the cause, the inputs and the time: a shorter step may be taken. When a step
 *     2^-20 as long is discarded too (tried, then the state restored), no step size can complete it (the inputs
 *     are invalid): TC_LOG_ERROR, the instance failed (FMI: "the simulation cannot be continued with this FMU
 *     instance", unless a host restores an FMU state taken before), so that every host stops;
 *   - a doStep that repeats a discarded one unchanged (the same state, time, step size, inputs and input
 *     derivatives) is TC_LOG_DISCARD at once, with terminate_requested: the model is deterministic, so it would be
 *     discarded again, and a host that repeats it would repeat it forever (the standard's redo is a restored state
 *     and a shorter step, FMI 2.0.4 section 4.2.3); the message says what was refused and why;
 *   - an accepted step after which an output has left a range it is built for (TC_BOUNDS: the strip drawn past
 *     draw_length, a nominal pressure above the hardness), or whose inputs are outside the range they are built
 *     for (a grip moving backwards), is TC_LOG_WARNING with a message naming the variable, its value, the bound
 *     and the time, once each time the variable leaves the range; a value within 1e-9 (relative) of its bound is
 *     on it (the round-off of a displacement summed over many steps); so is one after which the component reports
 *     a result it does not support (tc_component_warning: the strip's mu below the documented floor, once);
 *   - in initialization mode, the outputs read (fmi2GetReal...) are computed from the parameters and the inputs
 *     set so far (the model description's InitialUnknowns and their dependencies);
 *   - an FMU state (tc_inst_get_state...) holds the parameters, inputs, outputs, time and the component's
 *     state image, so that a restored state replays bit-identically, also in another instance; deserializing
 *     bytes that are not such a state is an error, never a crash;
 *   - no global mutable state; memory is the C library's, all of it freed by tc_inst_release.
 *
 * Statuses are the TC_LOG_* numbers, which are those of fmi2Status and fmi3Status alike.
 */
#ifndef TC_FMU_INSTANCE_H
#define TC_FMU_INSTANCE_H

#include <stddef.h>

#include "tc_fmu.h"
#include "tc_fmu_model.h"

enum tc_log_status { TC_LOG_OK = 0, TC_LOG_WARNING = 1, TC_LOG_DISCARD = 2, TC_LOG_ERROR = 3, TC_LOG_FATAL = 4 };

enum tc_phase { TC_PHASE_INSTANTIATED, TC_PHASE_INITIALIZATION, TC_PHASE_STEPPING, TC_PHASE_TERMINATED,
                TC_PHASE_FAILED };

typedef struct tc_instance tc_instance;

/* The wrapper's logger: one finished message with its status and category ("logStatusError"...). */
typedef void tc_emit_fn(const tc_instance *c, int status, const char *category, const char *text);

struct tc_instance {
    tc_emit_fn *emit; /* NULL: nothing is logged */
    char *name;
    char *resources; /* the FMU's resources folder, no trailing separator */
    int logging_on;
    int phase; /* enum tc_phase */
    double time;
    tc_param_value values[TC_N_PARAMETERS];
    double inputs[TC_N_INPUTS > 0 ? TC_N_INPUTS : 1];
    double input_derivatives[2 * (TC_N_INPUTS > 0 ? TC_N_INPUTS : 1)]; /* per input: 1st, 2nd; for the next step */
    double outputs[TC_N_OUTPUTS];
    tc_component *component;
    int terminate_requested; /* the FMU asks to end the simulation (after the last doStep) */
    const char *terminate_name; /* how the wrapper's standard names the request ("fmi2Terminated"...) */
    unsigned long generation;   /* counts the changes of the model's state: accepted steps, restored states */
    int refused;                /* the last doStep was discarded; its call: */
    unsigned long refused_generation;
    double refused_t, refused_dt;
    double refused_inputs[TC_N_INPUTS > 0 ? TC_N_INPUTS : 1];
    double refused_derivatives[2 * (TC_N_INPUTS > 0 ? TC_N_INPUTS : 1)];
    char refusal[1024]; /* why it was discarded */
    unsigned char outside[TC_N_BOUNDS > 0 ? TC_N_BOUNDS : 1]; /* the output is outside bound k (TC_BOUNDS) */
    char message[2048];
    char failure[2048]; /* why the instance is unusable */
};

/* Log a message (an OK one only when logging is on). */
void tc_inst_logf(const tc_instance *c, int status, const char *fmt, ...)
#if defined(__GNUC__) || defined(__clang__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* A copy of s ("" for NULL) from malloc; NULL when out of memory. */
char *tc_inst_copy_text(const char *s);

/* Set up c (zeroed by the caller, emit set) with its name, resources folder (owned by c from now on, even on
 * failure) and the start values; 0 when out of memory (c released). */
int tc_inst_init(tc_instance *c, const char *name, char *resources, int logging_on);
/* Free what c owns (the component, texts); c itself is the caller's. */
void tc_inst_release(tc_instance *c);
/* Back to the start values and the instantiated phase, the component freed; 0 when out of memory. */
int tc_inst_reset(tc_instance *c);

/* Fail the instance with a message (logged as an error); returns TC_LOG_ERROR. */
int tc_inst_fail(tc_instance *c, const char *what);
/* Check the parameters and make the component, outputs from it (TC_LOG_OK), or fail (TC_LOG_ERROR). */
int tc_inst_make_component(tc_instance *c);
/* In initialization mode: the outputs from the parameters and the inputs set so far (the component made for them,
 * then made again when initialization ends); TC_LOG_ERROR, logged naming `function` and the bad parameter, when it
 * cannot be made (the instance stays in initialization mode, where the parameter can still be set). Other phases:
 * TC_LOG_OK, nothing done. */
int tc_inst_initial_outputs(tc_instance *c, const char *function);
/* Leave initialization: make the component, keep the start time, step from here on. */
int tc_inst_exit_initialization(tc_instance *c);
/* Write the side outputs (TC_LOG_ERROR if that fails); the instance is terminated. */
int tc_inst_terminate(tc_instance *c);
/* Advance by dt from t (the contract above); the input derivatives apply to this step only (zero after it).
 * TC_LOG_OK, TC_LOG_WARNING (accepted; an output left a range it is built for, or the component warned),
 * TC_LOG_DISCARD or TC_LOG_ERROR. */
int tc_inst_do_step(tc_instance *c, double t, double dt);
/* Set input variable v (causality input) to value; its derivatives (if any were set) are zero again. */
void tc_inst_set_input(tc_instance *c, const tc_variable *v, double value);
/* The order-th time derivative (1 or 2) of input variable v at the start of the next step; TC_LOG_ERROR,
 * logged naming `function`, if the FMU cannot interpolate inputs, v is not an input, the order is not 1 or 2
 * or the value is not finite. */
int tc_inst_set_input_derivative(tc_instance *c, const tc_variable *v, int order, double value, const char *function);

/* The variable behind FMI 2.0 value reference vr, of kind `kind` (enum tc_kind); NULL, logged as an error
 * naming `function`, if there is none or it is another kind (kind_names: how the standard calls the kinds). */
const tc_variable *tc_inst_variable(const tc_instance *c, unsigned vr, int kind, const char *function,
                                    const char *const kind_names[3], unsigned last_vr);
/* The current value of a Real or Integer variable. */
double tc_inst_number(const tc_instance *c, const tc_variable *v);

/* FMU states (opaque): get into *state (reused when not NULL), set, free. */
int tc_inst_get_state(tc_instance *c, void **state, const char *function);
int tc_inst_set_state(tc_instance *c, const void *state);
void tc_inst_free_state(void *state);
/* The serialized state into buf (when size suffices; NULL to measure); returns the bytes it needs. */
size_t tc_inst_serialize(const void *state, unsigned char *buf, size_t size);
/* A state from serialized bytes into *state (an old one there is freed); TC_LOG_ERROR naming `function` for
 * bytes that are not a state of this FMU (token_label: what the standard calls TC_GUID). */
int tc_inst_deserialize(tc_instance *c, const unsigned char *bytes, size_t size, void **state,
                        const char *function, const char *token_label);

#endif
