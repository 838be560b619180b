/* The FMI 2.0 co-simulation interface of a native FMU, written in this project against the standard's headers.
 *
 * Generic: the FMU's variables and its component come from the generated "tc_fmu_model.h" and the
 * component's glue (tc_fmu.h); the instance, the parameter checks, the step and the FMU states are the
 * version-independent core's (tc_fmu_instance.h), which the FMI 3.0 wrapper (tc_fmi3.c) shares. This file
 * holds the FMI 2.0 function signatures, life cycle and logger:
 *
 *   - parameters are set in the instantiated and initialization modes (they are "fixed": a later set is
 *     ignored with a warning); fmi2ExitInitializationMode checks every parameter against its declared range
 *     or choices and makes the component (reads the friction table, the field file...). A bad parameter or
 *     file is fmi2Error with a message naming the parameter, its value and what is allowed; the instance is
 *     then unusable (every later call that needs the model returns fmi2Error);
 *   - fmi2DoStep with a bad input or a step the model cannot take returns fmi2Discard with the state
 *     unchanged and a message naming the cause, the inputs and the time: the importer may shorten the step,
 *     change the input or restore a state, and retry. When a step 2^-20 as long is discarded too, no step size
 *     can complete it (the inputs are at fault): fmi2Error, "the simulation cannot be continued with this FMU
 *     instance" (FMI 2.0.4 section 2.1.3) unless the importer restores an FMU state taken before, so that every
 *     importer stops instead of retrying;
 *   - a doStep that repeats a discarded one unchanged (same state, step size and inputs) is discarded at once, and
 *     fmi2GetBooleanStatus(fmi2Terminated) is fmi2True: it would be discarded again, forever, so the FMU asks the
 *     importer to stop, as FMI 2.0.4 section 4.2.3 lets a slave do after fmi2Discard (fmpy's simulate_fmu repeats
 *     a discarded step unless the slave asks to end);
 *   - fmi2DoStep returns fmi2Warning, with a message, when an output has just left a range the model is built
 *     for (the strip drawn past draw_length, a nominal pressure above the hardness) or the step's inputs are
 *     outside theirs (a grip moving backwards);
 *   - in initialization mode, fmi2GetReal/fmi2GetInteger of an output computes it from the parameters and the
 *     inputs set so far (its InitialUnknown dependencies);
 *   - the FMU state (get/set, serialize/deserialize) holds the parameters, inputs, outputs, time and the
 *     component's state image, so that a restored state replays bit-identically, also in another instance;
 *     deserializing bytes that are not such a state is fmi2Error, never a crash;
 *   - messages go to the importer's logger (errors and discards always, the rest when logging is on);
 *   - no global mutable state: everything lives in the instance; memory is the C library's (the model
 *     description says canNotUseMemoryManagementFunctions), all of it freed by fmi2FreeInstance.
 * Model exchange is not provided: its functions exist and return fmi2Error.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "tc_fmu.h"
#include "tc_fmu_instance.h"
#include "tc_fmu_model.h"

/* the FMI 2.0 instance: the core first (the logger below casts back), then the importer's logger */
typedef struct instance {
    tc_instance core;
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment environment;
} instance;

static const char *const KIND_NAMES[3] = {"Real", "Integer", "String"};

/* The message goes as the format string ('%' doubled): hosts that do not format the variadic arguments (a
 * plain ctypes callback) still see the text. */
static void emit(const tc_instance *core, int status, const char *category, const char *text) {
    const instance *c = (const instance *)core;
    char escaped[8192];
    size_t n = 0;
    if (c->logger == NULL) return;
    for (const char *p = text; *p && n + 2 < sizeof escaped; ++p) {
        if (*p == '%') escaped[n++] = '%';
        escaped[n++] = *p;
    }
    escaped[n] = '\0';
    c->logger(c->environment, core->name, (fmi2Status)status, category, escaped);
}

/* Resources folder from a file URI: file:///path, file:/path, file://host/path; %xx decoded. */
static char *path_from_uri(const char *uri) {
    const char *p = uri;
    char *out, *q;
    if (uri == NULL) return tc_inst_copy_text(".");
    if (strncmp(p, "file://", 7) == 0) {
        p += 7;
        if (*p != '/') { /* file://host/path: drop the host */
            const char *slash = strchr(p, '/');
            p = slash ? slash : p + strlen(p);
        }
    } else if (strncmp(p, "file:", 5) == 0) {
        p += 5;
    }
#ifdef _WIN32
    if (p[0] == '/' && p[1] != '\0' && p[2] == ':') ++p; /* /C:/... */
#endif
    out = malloc(strlen(p) + 1);
    if (out == NULL) return NULL;
    for (q = out; *p; ++p) {
        if (p[0] == '%' && p[1] && p[2]) {
            char hex[3] = {p[1], p[2], 0};
            char *end;
            long ch = strtol(hex, &end, 16);
            if (*end == '\0') {
                *q++ = (char)ch;
                p += 2;
                continue;
            }
        }
        *q++ = *p;
    }
    while (q > out + 1 && (q[-1] == '/' || q[-1] == '\\')) --q;
    *q = '\0';
    return out;
}

/* the instance behind an fmi2Component (NULL stays NULL: every function then returns fmi2Error) */
static tc_instance *checked(fmi2Component comp, const char *function) {
    (void)function;
    return comp == NULL ? NULL : &((instance *)comp)->core;
}

/* ================================================================================= common functions */
const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    tc_instance *c = checked(comp, "fmi2SetDebugLogging");
    (void)nCategories;
    (void)categories;
    if (c == NULL) return fmi2Error;
    c->logging_on = loggingOn ? 1 : 0;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    instance tmp;
    (void)visible;
    memset(&tmp, 0, sizeof tmp);
    tmp.core.emit = emit;
    tmp.logger = functions ? functions->logger : NULL;
    tmp.environment = functions ? functions->componentEnvironment : NULL;
    tmp.core.name = (char *)(instanceName ? instanceName : "?");
    if (fmuType != fmi2CoSimulation) {
        tc_inst_logf(&tmp.core, TC_LOG_ERROR, "%s supports co-simulation only, not model exchange",
                     TC_MODEL_IDENTIFIER);
        return NULL;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, TC_GUID) != 0) {
        tc_inst_logf(&tmp.core, TC_LOG_ERROR, "GUID %s does not match this FMU's %s (a model description of another "
                     "build?)", fmuGUID ? fmuGUID : "(null)", TC_GUID);
        return NULL;
    }
    instance *c = calloc(1, sizeof *c);
    if (c == NULL) return NULL;
    c->core.emit = emit;
    c->logger = tmp.logger;
    c->environment = tmp.environment;
    c->core.terminate_name = "fmi2Terminated";
    if (!tc_inst_init(&c->core, instanceName, path_from_uri(fmuResourceLocation), loggingOn)) {
        free(c);
        return NULL;
    }
    return c;
}

void fmi2FreeInstance(fmi2Component comp) {
    tc_instance *c = checked(comp, "fmi2FreeInstance");
    if (c == NULL) return;
    tc_inst_release(c);
    free(comp);
}

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    tc_instance *c = checked(comp, "fmi2SetupExperiment");
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (c == NULL) return fmi2Error;
    if (c->phase != TC_PHASE_INSTANTIATED) {
        tc_inst_logf(c, TC_LOG_ERROR, "fmi2SetupExperiment is allowed only after fmi2Instantiate");
        return fmi2Error;
    }
    if (!isfinite(startTime)) {
        tc_inst_logf(c, TC_LOG_ERROR, "startTime = %g s is not finite", startTime);
        return fmi2Error;
    }
    c->time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp) {
    tc_instance *c = checked(comp, "fmi2EnterInitializationMode");
    if (c == NULL) return fmi2Error;
    if (c->phase != TC_PHASE_INSTANTIATED) {
        tc_inst_logf(c, TC_LOG_ERROR, "fmi2EnterInitializationMode is allowed only after fmi2Instantiate");
        return fmi2Error;
    }
    c->phase = TC_PHASE_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp) {
    tc_instance *c = checked(comp, "fmi2ExitInitializationMode");
    if (c == NULL) return fmi2Error;
    if (c->phase != TC_PHASE_INITIALIZATION) {
        tc_inst_logf(c, TC_LOG_ERROR, "fmi2ExitInitializationMode is allowed only in initialization mode");
        return fmi2Error;
    }
    return (fmi2Status)tc_inst_exit_initialization(c);
}

fmi2Status fmi2Terminate(fmi2Component comp) {
    tc_instance *c = checked(comp, "fmi2Terminate");
    if (c == NULL) return fmi2Error;
    return (fmi2Status)tc_inst_terminate(c);
}

fmi2Status fmi2Reset(fmi2Component comp) {
    tc_instance *c = checked(comp, "fmi2Reset");
    if (c == NULL) return fmi2Error;
    return tc_inst_reset(c) ? fmi2OK : fmi2Fatal;
}

/* ================================================================================= get and set */
static const tc_variable *variable(tc_instance *c, fmi2ValueReference vr, int kind, const char *function) {
    return tc_inst_variable(c, (unsigned)vr, kind, function, KIND_NAMES, TC_N_VARIABLES - 1);
}

static int parameter_settable(tc_instance *c, const tc_variable *v) {
    if (c->phase == TC_PHASE_INSTANTIATED || c->phase == TC_PHASE_INITIALIZATION) return 1;
    tc_inst_logf(c, TC_LOG_WARNING, "parameter %s is fixed after initialization; the new value is ignored", v->name);
    return 0;
}

/* the position of the first output among the value references (nvr when there is none) */
static size_t first_output(const tc_instance *c, const fmi2ValueReference vr[], size_t nvr) {
    (void)c;
    for (size_t k = 0; k < nvr; ++k)
        if (vr[k] < (fmi2ValueReference)TC_N_VARIABLES && TC_VARIABLES[vr[k]].causality == TC_CAUSALITY_OUTPUT)
            return k;
    return nvr;
}

static fmi2Status get_numbers(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, int kind,
                              double *dst_real, fmi2Integer *dst_int, const char *function) {
    tc_instance *c = checked(comp, function);
    if (c == NULL || (nvr > 0 && vr == NULL)) return fmi2Error;
    for (size_t k = 0; k < nvr; ++k) {
        const tc_variable *v = variable(c, vr[k], kind, function);
        if (v == NULL) return fmi2Error;
        if (v->causality == TC_CAUSALITY_OUTPUT && c->phase == TC_PHASE_INITIALIZATION && k == first_output(c, vr, nvr)
            && tc_inst_initial_outputs(c, function) != TC_LOG_OK)
            return fmi2Error;
        double x = tc_inst_number(c, v);
        if (dst_real) dst_real[k] = x;
        if (dst_int) dst_int[k] = (fmi2Integer)x;
    }
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    if (nvr > 0 && value == NULL) return fmi2Error;
    return get_numbers(c, vr, nvr, TC_KIND_REAL, value, NULL, "fmi2GetReal");
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    if (nvr > 0 && value == NULL) return fmi2Error;
    return get_numbers(c, vr, nvr, TC_KIND_INTEGER, NULL, value, "fmi2GetInteger");
}

fmi2Status fmi2GetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    tc_instance *c = checked(comp, "fmi2GetBoolean");
    (void)value;
    if (c == NULL) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    tc_inst_logf(c, TC_LOG_ERROR, "fmi2GetBoolean: %s has no Boolean variables (value reference %u)",
                 TC_MODEL_IDENTIFIER, vr ? (unsigned)vr[0] : 0u);
    return fmi2Error;
}

fmi2Status fmi2GetString(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    tc_instance *c = checked(comp, "fmi2GetString");
    if (c == NULL || (nvr > 0 && (vr == NULL || value == NULL))) return fmi2Error;
    for (size_t k = 0; k < nvr; ++k) {
        const tc_variable *v = variable(c, vr[k], TC_KIND_STRING, "fmi2GetString");
        if (v == NULL) return fmi2Error;
        value[k] = c->values[v->index].text;
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    tc_instance *c = checked(comp, "fmi2SetReal");
    if (c == NULL || (nvr > 0 && (vr == NULL || value == NULL))) return fmi2Error;
    fmi2Status status = fmi2OK;
    for (size_t k = 0; k < nvr; ++k) {
        const tc_variable *v = variable(c, vr[k], TC_KIND_REAL, "fmi2SetReal");
        if (v == NULL) return fmi2Error;
        if (v->causality == TC_CAUSALITY_OUTPUT) {
            tc_inst_logf(c, TC_LOG_ERROR, "fmi2SetReal: %s is an output; it cannot be set", v->name);
            return fmi2Error;
        }
        if (v->causality == TC_CAUSALITY_INPUT) {
            tc_inst_set_input(c, v, value[k]);
        } else if (parameter_settable(c, v)) {
            c->values[v->index].number = value[k];
        } else {
            status = fmi2Warning;
        }
    }
    return status;
}

fmi2Status fmi2SetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    tc_instance *c = checked(comp, "fmi2SetInteger");
    if (c == NULL || (nvr > 0 && (vr == NULL || value == NULL))) return fmi2Error;
    fmi2Status status = fmi2OK;
    for (size_t k = 0; k < nvr; ++k) {
        const tc_variable *v = variable(c, vr[k], TC_KIND_INTEGER, "fmi2SetInteger");
        if (v == NULL) return fmi2Error;
        if (v->causality != TC_CAUSALITY_PARAMETER) {
            tc_inst_logf(c, TC_LOG_ERROR, "fmi2SetInteger: %s is an output; it cannot be set", v->name);
            return fmi2Error;
        }
        if (parameter_settable(c, v)) c->values[v->index].number = (double)value[k];
        else status = fmi2Warning;
    }
    return status;
}

fmi2Status fmi2SetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    tc_instance *c = checked(comp, "fmi2SetBoolean");
    (void)value;
    if (c == NULL) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    tc_inst_logf(c, TC_LOG_ERROR, "fmi2SetBoolean: %s has no Boolean variables (value reference %u)",
                 TC_MODEL_IDENTIFIER, vr ? (unsigned)vr[0] : 0u);
    return fmi2Error;
}

fmi2Status fmi2SetString(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    tc_instance *c = checked(comp, "fmi2SetString");
    if (c == NULL || (nvr > 0 && (vr == NULL || value == NULL))) return fmi2Error;
    fmi2Status status = fmi2OK;
    for (size_t k = 0; k < nvr; ++k) {
        const tc_variable *v = variable(c, vr[k], TC_KIND_STRING, "fmi2SetString");
        if (v == NULL) return fmi2Error;
        if (!parameter_settable(c, v)) {
            status = fmi2Warning;
            continue;
        }
        char *text = tc_inst_copy_text(value[k]);
        if (text == NULL) return fmi2Error;
        free(c->values[v->index].text);
        c->values[v->index].text = text;
    }
    return status;
}

/* ================================================================================= stepping */
fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    tc_instance *c = checked(comp, "fmi2DoStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    if (c == NULL) return fmi2Error;
    return (fmi2Status)tc_inst_do_step(c, currentCommunicationPoint, communicationStepSize);
}

fmi2Status fmi2CancelStep(fmi2Component comp) {
    tc_instance *c = checked(comp, "fmi2CancelStep");
    if (c == NULL) return fmi2Error;
    tc_inst_logf(c, TC_LOG_ERROR, "fmi2CancelStep: doStep always completes synchronously; there is nothing to cancel");
    return fmi2Error;
}

fmi2Status fmi2GetStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Status *value) {
    tc_instance *c = checked(comp, "fmi2GetStatus");
    if (c == NULL || value == NULL) return fmi2Error;
    if (s == fmi2DoStepStatus) {
        *value = c->phase == TC_PHASE_FAILED ? fmi2Error : fmi2OK;
        return fmi2OK;
    }
    tc_inst_logf(c, TC_LOG_DISCARD, "fmi2GetStatus: status kind %d is not provided", (int)s);
    return fmi2Discard;
}

fmi2Status fmi2GetRealStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Real *value) {
    tc_instance *c = checked(comp, "fmi2GetRealStatus");
    if (c == NULL || value == NULL) return fmi2Error;
    if (s == fmi2LastSuccessfulTime) {
        *value = c->time;
        return fmi2OK;
    }
    tc_inst_logf(c, TC_LOG_DISCARD, "fmi2GetRealStatus: status kind %d is not provided", (int)s);
    return fmi2Discard;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Integer *value) {
    tc_instance *c = checked(comp, "fmi2GetIntegerStatus");
    (void)value;
    if (c == NULL) return fmi2Error;
    tc_inst_logf(c, TC_LOG_DISCARD, "fmi2GetIntegerStatus: status kind %d is not provided", (int)s);
    return fmi2Discard;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Boolean *value) {
    tc_instance *c = checked(comp, "fmi2GetBooleanStatus");
    if (c == NULL || value == NULL) return fmi2Error;
    if (s == fmi2Terminated) { /* FMI 2.0.4 section 4.2.3: after fmi2Discard, whether the slave wants to stop */
        *value = c->terminate_requested || c->phase == TC_PHASE_FAILED ? fmi2True : fmi2False;
        return fmi2OK;
    }
    tc_inst_logf(c, TC_LOG_DISCARD, "fmi2GetBooleanStatus: status kind %d is not provided", (int)s);
    return fmi2Discard;
}

fmi2Status fmi2GetStringStatus(fmi2Component comp, const fmi2StatusKind s, fmi2String *value) {
    tc_instance *c = checked(comp, "fmi2GetStringStatus");
    (void)value;
    if (c == NULL) return fmi2Error;
    tc_inst_logf(c, TC_LOG_DISCARD, "fmi2GetStringStatus: status kind %d is not provided", (int)s);
    return fmi2Discard;
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    /* The derivatives at the current communication point, for the next fmi2DoStep only; setting the input's
     * value (fmi2SetReal) makes them zero again (tc_fmu_instance.h). */
    tc_instance *c = checked(comp, "fmi2SetRealInputDerivatives");
    if (c == NULL || (nvr > 0 && (vr == NULL || order == NULL || value == NULL))) return fmi2Error;
    for (size_t k = 0; k < nvr; ++k) {
        const tc_variable *v = variable(c, vr[k], TC_KIND_REAL, "fmi2SetRealInputDerivatives");
        if (v == NULL) return fmi2Error;
        if (tc_inst_set_input_derivative(c, v, (int)order[k], value[k], "fmi2SetRealInputDerivatives") != TC_LOG_OK)
            return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    tc_instance *c = checked(comp, "fmi2GetRealOutputDerivatives");
    (void)vr;
    (void)order;
    (void)value;
    if (c == NULL) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    tc_inst_logf(c, TC_LOG_ERROR, "fmi2GetRealOutputDerivatives: %s provides no output derivatives "
                 "(maxOutputDerivativeOrder = 0)", TC_MODEL_IDENTIFIER);
    return fmi2Error;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component comp, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    tc_instance *c = checked(comp, "fmi2GetDirectionalDerivative");
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    if (c == NULL) return fmi2Error;
    tc_inst_logf(c, TC_LOG_ERROR, "fmi2GetDirectionalDerivative: not provided (providesDirectionalDerivative = false)");
    return fmi2Error;
}

/* ================================================================================= FMU state */
fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate *FMUstate) {
    tc_instance *c = checked(comp, "fmi2GetFMUstate");
    if (c == NULL || FMUstate == NULL) return fmi2Error;
    return (fmi2Status)tc_inst_get_state(c, FMUstate, "fmi2GetFMUstate");
}

fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate FMUstate) {
    tc_instance *c = checked(comp, "fmi2SetFMUstate");
    if (c == NULL || FMUstate == NULL) return fmi2Error;
    return (fmi2Status)tc_inst_set_state(c, FMUstate);
}

fmi2Status fmi2FreeFMUstate(fmi2Component comp, fmi2FMUstate *FMUstate) {
    (void)comp;
    if (FMUstate == NULL) return fmi2OK;
    tc_inst_free_state(*FMUstate);
    *FMUstate = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component comp, fmi2FMUstate FMUstate, size_t *size) {
    if (comp == NULL || FMUstate == NULL || size == NULL) return fmi2Error;
    *size = tc_inst_serialize(FMUstate, NULL, 0);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component comp, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                 size_t size) {
    tc_instance *c = checked(comp, "fmi2SerializeFMUstate");
    if (c == NULL || FMUstate == NULL || serializedState == NULL) return fmi2Error;
    size_t need = tc_inst_serialize(FMUstate, NULL, 0);
    if (size < need) {
        tc_inst_logf(c, TC_LOG_ERROR, "fmi2SerializeFMUstate: the buffer holds %zu bytes; the state needs %zu", size,
                     need);
        return fmi2Error;
    }
    tc_inst_serialize(FMUstate, (unsigned char *)serializedState, size);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate) {
    tc_instance *c = checked(comp, "fmi2DeSerializeFMUstate");
    if (c == NULL || FMUstate == NULL || (size > 0 && serializedState == NULL)) return fmi2Error;
    return (fmi2Status)tc_inst_deserialize(c, (const unsigned char *)serializedState, size, FMUstate,
                                           "fmi2DeSerializeFMUstate", "GUID");
}

/* ================================================================================= model exchange (absent) */
static fmi2Status no_model_exchange(fmi2Component comp, const char *function) {
    tc_instance *c = checked(comp, function);
    if (c != NULL)
        tc_inst_logf(c, TC_LOG_ERROR, "%s: %s is a co-simulation FMU; model exchange is not provided", function,
                     TC_MODEL_IDENTIFIER);
    return fmi2Error;
}

fmi2Status fmi2EnterEventMode(fmi2Component c) { return no_model_exchange(c, "fmi2EnterEventMode"); }
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info) {
    (void)info;
    return no_model_exchange(c, "fmi2NewDiscreteStates");
}
fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { return no_model_exchange(c, "fmi2EnterContinuousTimeMode"); }
fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    (void)enterEventMode;
    (void)terminateSimulation;
    return no_model_exchange(c, "fmi2CompletedIntegratorStep");
}
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    (void)time;
    return no_model_exchange(c, "fmi2SetTime");
}
fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    (void)x;
    (void)nx;
    return no_model_exchange(c, "fmi2SetContinuousStates");
}
fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    (void)derivatives;
    (void)nx;
    return no_model_exchange(c, "fmi2GetDerivatives");
}
fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    (void)eventIndicators;
    (void)ni;
    return no_model_exchange(c, "fmi2GetEventIndicators");
}
fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    (void)x;
    (void)nx;
    return no_model_exchange(c, "fmi2GetContinuousStates");
}
fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    (void)x_nominal;
    (void)nx;
    return no_model_exchange(c, "fmi2GetNominalsOfContinuousStates");
}
