/* The FMI 2.0 co-simulation interface of a native FMU, written in this project against the standard's headers.
 *
 * Generic: the FMU's variables and its component come from the generated "tc_fmu_model.h" and the
 * component's glue (tc_fmu.h). This file holds the FMI life cycle and its status contract:
 *
 *   - parameters are set in the instantiated and initialization modes (they are "fixed": a later set is
 *     ignored with a warning); fmi2ExitInitializationMode checks every parameter against its declared range
 *     or choices and makes the component (reads the friction table, the field file...). A bad parameter or
 *     file is fmi2Error with a message naming the parameter, its value and what is allowed; the instance is
 *     then unusable (every later call that needs the model returns fmi2Error);
 *   - fmi2DoStep with a bad input or a step the model cannot take returns fmi2Discard with the state
 *     unchanged and a message naming the cause, the inputs and the time: the importer may shorten the step,
 *     change the input or restore a state, and retry;
 *   - the FMU state (get/set, serialize/deserialize) holds the parameters, inputs, outputs, time and the
 *     component's state image, so that a restored state replays bit-identically, also in another instance;
 *     deserializing bytes that are not such a state is fmi2Error, never a crash;
 *   - messages go to the importer's logger (errors and discards always, the rest when logging is on);
 *   - no global mutable state: everything lives in the instance; memory is the C library's (the model
 *     description says canNotUseMemoryManagementFunctions), all of it freed by fmi2FreeInstance.
 * Model exchange is not provided: its functions exist and return fmi2Error.
 */
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "tc_fmu.h"
#include "tc_fmu_model.h"

enum phase { PHASE_INSTANTIATED, PHASE_INITIALIZATION, PHASE_STEPPING, PHASE_TERMINATED, PHASE_FAILED };

typedef struct instance {
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment environment;
    char *name;
    char *resources;
    int logging_on;
    int phase;
    double time;
    tc_param_value values[TC_N_PARAMETERS];
    double inputs[TC_N_INPUTS > 0 ? TC_N_INPUTS : 1];
    double outputs[TC_N_OUTPUTS];
    tc_component *component;
    char message[2048];
    char failure[2048]; /* why the instance is unusable */
} instance;

/* an FMU state: a copy of everything that determines the future */
typedef struct saved_state {
    int phase;
    double time;
    tc_param_value values[TC_N_PARAMETERS];
    double inputs[TC_N_INPUTS > 0 ? TC_N_INPUTS : 1];
    double outputs[TC_N_OUTPUTS];
    int has_component;
    size_t size;
    unsigned char *bytes;
    char failure[2048];
} saved_state;

static tc_msg msg_of(instance *c) {
    tc_msg m = {c->message, sizeof c->message};
    c->message[0] = '\0';
    return m;
}

static void logf_(instance *c, fmi2Status status, const char *fmt, ...)
#if defined(__GNUC__) || defined(__clang__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static void logf_(instance *c, fmi2Status status, const char *fmt, ...) {
    static const char *const categories[] = {"logStatusOK", "logStatusWarning", "logStatusDiscard",
                                             "logStatusError", "logStatusFatal", "logStatusPending"};
    char text[4096], escaped[8192];
    size_t n = 0;
    va_list ap;
    if (c == NULL || c->logger == NULL) return;
    if (status == fmi2OK && !c->logging_on) return;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    /* the message is the format string ('%' doubled): hosts that do not format the variadic arguments
     * (a plain ctypes callback) still see the text */
    for (const char *p = text; *p && n + 2 < sizeof escaped; ++p) {
        if (*p == '%') escaped[n++] = '%';
        escaped[n++] = *p;
    }
    escaped[n] = '\0';
    c->logger(c->environment, c->name, status, categories[status], escaped);
}

static char *copy_text(const char *s) {
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
        if (src[k].text != NULL && (dst[k].text = copy_text(src[k].text)) == NULL) return 0;
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

static const tc_variable *parameter(int index) {
    return &TC_VARIABLES[index];
}

static int set_defaults(instance *c) {
    for (int k = 0; k < TC_N_VARIABLES; ++k) {
        const tc_variable *v = &TC_VARIABLES[k];
        if (v->causality == TC_CAUSALITY_PARAMETER) {
            tc_param_value *p = &c->values[v->index];
            free(p->text);
            p->text = NULL;
            p->number = v->start;
            p->choice = 0;
            if (v->kind == TC_KIND_STRING && (p->text = copy_text(v->start_text)) == NULL) return 0;
        } else if (v->causality == TC_CAUSALITY_INPUT) {
            c->inputs[v->index] = v->start;
        } else {
            c->outputs[v->index] = v->start;
        }
    }
    c->time = 0.0;
    return 1;
}

/* Resources folder from a file URI: file:///path, file:/path, file://host/path; %xx decoded. */
static char *path_from_uri(const char *uri) {
    const char *p = uri;
    char *out, *q;
    if (uri == NULL) return copy_text(".");
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

static fmi2Status fail(instance *c, const char *what) {
    snprintf(c->failure, sizeof c->failure, "%s", what);
    c->phase = PHASE_FAILED;
    logf_(c, fmi2Error, "%s", what);
    return fmi2Error;
}


/* The check of one parameter (ranges as components/params.py's validate_fields); 0 if it is bad. */
static int check_parameter(instance *c, const tc_variable *v, tc_param_value *p) {
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
    int ok_lo = !v->has_low || (v->low_inclusive ? p->number >= v->low : p->number > v->low);
    int ok_hi = !v->has_high || p->number <= v->high;
    if (ok_lo && ok_hi) return 1;
    snprintf(lo, sizeof lo, "%g", v->low);
    snprintf(hi, sizeof hi, "%g", v->high);
    if (v->kind == TC_KIND_INTEGER) snprintf(a, sizeof a, "%.0f", p->number);
    else tc_repr_double(p->number, a);
    snprintf(c->message, sizeof c->message, "%s = %s%s%s is out of range; allowed: %s%s, %s%s%s%s", v->name, a, sp,
             unit, (v->has_low && v->low_inclusive) ? "[" : "(", v->has_low ? lo : "-inf", v->has_high ? hi : "inf",
             v->has_high ? "]" : ")", sp, unit);
    return 0;
}

static void free_component(instance *c) {
    tc_component_free(c->component);
    c->component = NULL;
}

/* Make the component for the current parameters; on failure the instance is failed. */
static fmi2Status make_component(instance *c) {
    char text[2300];
    for (int k = 0; k < TC_N_PARAMETERS; ++k) {
        if (!check_parameter(c, parameter(k), &c->values[k])) {
            snprintf(text, sizeof text, "initialization failed: %s", c->message);
            return fail(c, text);
        }
    }
    free_component(c);
    int rc = tc_component_create(c->values, c->resources, &c->component, msg_of(c));
    if (rc != TC_OK) {
        snprintf(text, sizeof text, "initialization failed: %s", c->message);
        return fail(c, text);
    }
    tc_component_outputs(c->component, c->outputs);
    if (tc_component_note(c->component)[0]) logf_(c, fmi2OK, "%s", tc_component_note(c->component));
    return fmi2OK;
}

/* the instance behind an fmi2Component (NULL stays NULL: every function then returns fmi2Error) */
static instance *checked(fmi2Component comp, const char *function) {
    (void)function;
    return (instance *)comp;
}

/* ================================================================================= common functions */
const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    instance *c = checked(comp, "fmi2SetDebugLogging");
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
    tmp.logger = functions ? functions->logger : NULL;
    tmp.environment = functions ? functions->componentEnvironment : NULL;
    tmp.name = (char *)(instanceName ? instanceName : "?");
    if (fmuType != fmi2CoSimulation) {
        logf_(&tmp, fmi2Error, "%s supports co-simulation only, not model exchange", TC_MODEL_IDENTIFIER);
        return NULL;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, TC_GUID) != 0) {
        logf_(&tmp, fmi2Error, "GUID %s does not match this FMU's %s (a model description of another build?)",
              fmuGUID ? fmuGUID : "(null)", TC_GUID);
        return NULL;
    }
    instance *c = calloc(1, sizeof *c);
    if (c == NULL) return NULL;
    c->logger = tmp.logger;
    c->environment = tmp.environment;
    c->logging_on = loggingOn ? 1 : 0;
    c->name = copy_text(instanceName ? instanceName : "");
    c->resources = path_from_uri(fmuResourceLocation);
    if (c->name == NULL || c->resources == NULL || !set_defaults(c)) {
        free_values(c->values);
        free(c->name);
        free(c->resources);
        free(c);
        return NULL;
    }
    c->phase = PHASE_INSTANTIATED;
    return c;
}

void fmi2FreeInstance(fmi2Component comp) {
    instance *c = checked(comp, "fmi2FreeInstance");
    if (c == NULL) return;
    free_component(c);
    free_values(c->values);
    free(c->name);
    free(c->resources);
    free(c);
}

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    instance *c = checked(comp, "fmi2SetupExperiment");
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (c == NULL) return fmi2Error;
    if (c->phase != PHASE_INSTANTIATED) {
        logf_(c, fmi2Error, "fmi2SetupExperiment is allowed only after fmi2Instantiate");
        return fmi2Error;
    }
    if (!isfinite(startTime)) {
        logf_(c, fmi2Error, "startTime = %g s is not finite", startTime);
        return fmi2Error;
    }
    c->time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp) {
    instance *c = checked(comp, "fmi2EnterInitializationMode");
    if (c == NULL) return fmi2Error;
    if (c->phase != PHASE_INSTANTIATED) {
        logf_(c, fmi2Error, "fmi2EnterInitializationMode is allowed only after fmi2Instantiate");
        return fmi2Error;
    }
    c->phase = PHASE_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp) {
    instance *c = checked(comp, "fmi2ExitInitializationMode");
    if (c == NULL) return fmi2Error;
    if (c->phase != PHASE_INITIALIZATION) {
        logf_(c, fmi2Error, "fmi2ExitInitializationMode is allowed only in initialization mode");
        return fmi2Error;
    }
    double start = c->time;
    if (make_component(c) != fmi2OK) return fmi2Error;
    c->time = start;
    c->phase = PHASE_STEPPING;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component comp) {
    instance *c = checked(comp, "fmi2Terminate");
    char line[1024] = "";
    if (c == NULL) return fmi2Error;
    if (c->phase == PHASE_FAILED || c->component == NULL) {
        c->phase = c->phase == PHASE_FAILED ? PHASE_FAILED : PHASE_TERMINATED;
        return fmi2OK;
    }
    c->phase = PHASE_TERMINATED;
    if (tc_component_terminate(c->component, line, sizeof line, msg_of(c)) != TC_OK) {
        logf_(c, fmi2Error, "terminate: %s", c->message);
        return fmi2Error;
    }
    if (line[0]) logf_(c, fmi2OK, "%s", line);
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component comp) {
    instance *c = checked(comp, "fmi2Reset");
    if (c == NULL) return fmi2Error;
    free_component(c);
    c->failure[0] = '\0';
    if (!set_defaults(c)) return fmi2Fatal;
    c->phase = PHASE_INSTANTIATED;
    return fmi2OK;
}

/* ================================================================================= get and set */
static const tc_variable *variable(instance *c, fmi2ValueReference vr, int kind, const char *function) {
    if (vr >= (fmi2ValueReference)TC_N_VARIABLES) {
        logf_(c, fmi2Error, "%s: value reference %u is not a variable of %s (0 to %d)", function, (unsigned)vr,
              TC_MODEL_IDENTIFIER, TC_N_VARIABLES - 1);
        return NULL;
    }
    const tc_variable *v = &TC_VARIABLES[vr];
    if (v->kind != kind) {
        static const char *const kinds[] = {"Real", "Integer", "String"};
        logf_(c, fmi2Error, "%s: %s (value reference %u) is a %s", function, v->name, (unsigned)vr, kinds[v->kind]);
        return NULL;
    }
    return v;
}

static int parameter_settable(instance *c, const tc_variable *v) {
    if (c->phase == PHASE_INSTANTIATED || c->phase == PHASE_INITIALIZATION) return 1;
    logf_(c, fmi2Warning, "parameter %s is fixed after initialization; the new value is ignored", v->name);
    return 0;
}

static fmi2Status get_numbers(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, int kind,
                              double *dst_real, fmi2Integer *dst_int, const char *function) {
    instance *c = checked(comp, function);
    if (c == NULL || (nvr > 0 && vr == NULL)) return fmi2Error;
    for (size_t k = 0; k < nvr; ++k) {
        const tc_variable *v = variable(c, vr[k], kind, function);
        if (v == NULL) return fmi2Error;
        double x = v->causality == TC_CAUSALITY_PARAMETER ? c->values[v->index].number
                   : v->causality == TC_CAUSALITY_INPUT   ? c->inputs[v->index]
                                                          : c->outputs[v->index];
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
    instance *c = checked(comp, "fmi2GetBoolean");
    (void)value;
    if (c == NULL) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    logf_(c, fmi2Error, "fmi2GetBoolean: %s has no Boolean variables (value reference %u)", TC_MODEL_IDENTIFIER,
          vr ? (unsigned)vr[0] : 0u);
    return fmi2Error;
}

fmi2Status fmi2GetString(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    instance *c = checked(comp, "fmi2GetString");
    if (c == NULL || (nvr > 0 && (vr == NULL || value == NULL))) return fmi2Error;
    for (size_t k = 0; k < nvr; ++k) {
        const tc_variable *v = variable(c, vr[k], TC_KIND_STRING, "fmi2GetString");
        if (v == NULL) return fmi2Error;
        value[k] = c->values[v->index].text;
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    instance *c = checked(comp, "fmi2SetReal");
    if (c == NULL || (nvr > 0 && (vr == NULL || value == NULL))) return fmi2Error;
    fmi2Status status = fmi2OK;
    for (size_t k = 0; k < nvr; ++k) {
        const tc_variable *v = variable(c, vr[k], TC_KIND_REAL, "fmi2SetReal");
        if (v == NULL) return fmi2Error;
        if (v->causality == TC_CAUSALITY_OUTPUT) {
            logf_(c, fmi2Error, "fmi2SetReal: %s is an output; it cannot be set", v->name);
            return fmi2Error;
        }
        if (v->causality == TC_CAUSALITY_INPUT) {
            c->inputs[v->index] = value[k]; /* checked by the model at the next step */
        } else if (parameter_settable(c, v)) {
            c->values[v->index].number = value[k];
        } else {
            status = fmi2Warning;
        }
    }
    return status;
}

fmi2Status fmi2SetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    instance *c = checked(comp, "fmi2SetInteger");
    if (c == NULL || (nvr > 0 && (vr == NULL || value == NULL))) return fmi2Error;
    fmi2Status status = fmi2OK;
    for (size_t k = 0; k < nvr; ++k) {
        const tc_variable *v = variable(c, vr[k], TC_KIND_INTEGER, "fmi2SetInteger");
        if (v == NULL) return fmi2Error;
        if (v->causality != TC_CAUSALITY_PARAMETER) {
            logf_(c, fmi2Error, "fmi2SetInteger: %s is an output; it cannot be set", v->name);
            return fmi2Error;
        }
        if (parameter_settable(c, v)) c->values[v->index].number = (double)value[k];
        else status = fmi2Warning;
    }
    return status;
}

fmi2Status fmi2SetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    instance *c = checked(comp, "fmi2SetBoolean");
    (void)value;
    if (c == NULL) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    logf_(c, fmi2Error, "fmi2SetBoolean: %s has no Boolean variables (value reference %u)", TC_MODEL_IDENTIFIER,
          vr ? (unsigned)vr[0] : 0u);
    return fmi2Error;
}

fmi2Status fmi2SetString(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    instance *c = checked(comp, "fmi2SetString");
    if (c == NULL || (nvr > 0 && (vr == NULL || value == NULL))) return fmi2Error;
    fmi2Status status = fmi2OK;
    for (size_t k = 0; k < nvr; ++k) {
        const tc_variable *v = variable(c, vr[k], TC_KIND_STRING, "fmi2SetString");
        if (v == NULL) return fmi2Error;
        if (!parameter_settable(c, v)) {
            status = fmi2Warning;
            continue;
        }
        char *text = copy_text(value[k]);
        if (text == NULL) return fmi2Error;
        free(c->values[v->index].text);
        c->values[v->index].text = text;
    }
    return status;
}

/* ================================================================================= stepping */
fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    instance *c = checked(comp, "fmi2DoStep");
    char a[TC_REPR_SIZE], b[TC_REPR_SIZE], shown[1024] = "", text[4096];
    (void)noSetFMUStatePriorToCurrentPoint;
    if (c == NULL) return fmi2Error;
    if (c->phase == PHASE_FAILED) {
        logf_(c, fmi2Error, "doStep refused: the FMU is not usable (%s)", c->failure);
        return fmi2Error;
    }
    if (c->phase != PHASE_STEPPING || c->component == NULL) {
        logf_(c, fmi2Error, "doStep refused: the FMU has not left initialization mode");
        return fmi2Error;
    }
    int rc = tc_component_step(c->component, communicationStepSize, c->inputs, msg_of(c));
    if (rc != TC_OK) {
        for (int k = 0; k < TC_N_VARIABLES; ++k) {
            const tc_variable *v = &TC_VARIABLES[k];
            if (v->causality != TC_CAUSALITY_INPUT) continue;
            char one[160];
            snprintf(one, sizeof one, "%s%s = %s %s", shown[0] ? ", " : "", v->name,
                     tc_repr_double(c->inputs[v->index], a), v->unit[0] ? v->unit : "1");
            strncat(shown, one, sizeof shown - strlen(shown) - 1);
        }
        snprintf(text, sizeof text, "doStep from t = %s s by %s s rejected: %s %s%s%sthe FMU state is unchanged",
                 tc_repr_double(currentCommunicationPoint, a), tc_repr_double(communicationStepSize, b), c->message,
                 shown[0] ? "(inputs " : "", shown, shown[0] ? "); " : "; ");
        logf_(c, rc == TC_DISCARD ? fmi2Discard : fmi2Error, "%s", text);
        if (rc == TC_DISCARD) return fmi2Discard;
        return fail(c, text);
    }
    tc_component_outputs(c->component, c->outputs);
    c->time = currentCommunicationPoint + communicationStepSize;
    if (tc_component_after_step(c->component, msg_of(c)) != TC_OK) {
        snprintf(text, sizeof text, "after the step to t = %s s: %s", tc_repr_double(c->time, a), c->message);
        return fail(c, text);
    }
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component comp) {
    instance *c = checked(comp, "fmi2CancelStep");
    if (c == NULL) return fmi2Error;
    logf_(c, fmi2Error, "fmi2CancelStep: doStep always completes synchronously; there is nothing to cancel");
    return fmi2Error;
}

fmi2Status fmi2GetStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Status *value) {
    instance *c = checked(comp, "fmi2GetStatus");
    if (c == NULL || value == NULL) return fmi2Error;
    if (s == fmi2DoStepStatus) {
        *value = c->phase == PHASE_FAILED ? fmi2Error : fmi2OK;
        return fmi2OK;
    }
    logf_(c, fmi2Discard, "fmi2GetStatus: status kind %d is not provided", (int)s);
    return fmi2Discard;
}

fmi2Status fmi2GetRealStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Real *value) {
    instance *c = checked(comp, "fmi2GetRealStatus");
    if (c == NULL || value == NULL) return fmi2Error;
    if (s == fmi2LastSuccessfulTime) {
        *value = c->time;
        return fmi2OK;
    }
    logf_(c, fmi2Discard, "fmi2GetRealStatus: status kind %d is not provided", (int)s);
    return fmi2Discard;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Integer *value) {
    instance *c = checked(comp, "fmi2GetIntegerStatus");
    (void)value;
    if (c == NULL) return fmi2Error;
    logf_(c, fmi2Discard, "fmi2GetIntegerStatus: status kind %d is not provided", (int)s);
    return fmi2Discard;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Boolean *value) {
    instance *c = checked(comp, "fmi2GetBooleanStatus");
    if (c == NULL || value == NULL) return fmi2Error;
    if (s == fmi2Terminated) {
        *value = fmi2False; /* the FMU never asks to end the simulation */
        return fmi2OK;
    }
    logf_(c, fmi2Discard, "fmi2GetBooleanStatus: status kind %d is not provided", (int)s);
    return fmi2Discard;
}

fmi2Status fmi2GetStringStatus(fmi2Component comp, const fmi2StatusKind s, fmi2String *value) {
    instance *c = checked(comp, "fmi2GetStringStatus");
    (void)value;
    if (c == NULL) return fmi2Error;
    logf_(c, fmi2Discard, "fmi2GetStringStatus: status kind %d is not provided", (int)s);
    return fmi2Discard;
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    instance *c = checked(comp, "fmi2SetRealInputDerivatives");
    (void)vr;
    (void)order;
    (void)value;
    if (c == NULL) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    logf_(c, fmi2Error, "fmi2SetRealInputDerivatives: %s holds its inputs over a step (canInterpolateInputs = false)",
          TC_MODEL_IDENTIFIER);
    return fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    instance *c = checked(comp, "fmi2GetRealOutputDerivatives");
    (void)vr;
    (void)order;
    (void)value;
    if (c == NULL) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    logf_(c, fmi2Error, "fmi2GetRealOutputDerivatives: %s provides no output derivatives "
                        "(maxOutputDerivativeOrder = 0)", TC_MODEL_IDENTIFIER);
    return fmi2Error;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component comp, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    instance *c = checked(comp, "fmi2GetDirectionalDerivative");
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    if (c == NULL) return fmi2Error;
    logf_(c, fmi2Error, "fmi2GetDirectionalDerivative: not provided (providesDirectionalDerivative = false)");
    return fmi2Error;
}

/* ================================================================================= FMU state */
static void free_saved(saved_state *s) {
    if (s == NULL) return;
    free_values(s->values);
    free(s->bytes);
    free(s);
}

fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate *FMUstate) {
    instance *c = checked(comp, "fmi2GetFMUstate");
    if (c == NULL || FMUstate == NULL) return fmi2Error;
    saved_state *s = *FMUstate ? (saved_state *)*FMUstate : calloc(1, sizeof *s);
    if (s == NULL) return fmi2Error;
    free_values(s->values);
    free(s->bytes);
    s->bytes = NULL;
    s->size = 0;
    s->phase = c->phase;
    s->time = c->time;
    memcpy(s->inputs, c->inputs, sizeof s->inputs);
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
        if (*FMUstate == NULL) free_saved(s);
        logf_(c, fmi2Error, "fmi2GetFMUstate: out of memory");
        return fmi2Error;
    }
    *FMUstate = s;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate FMUstate) {
    instance *c = checked(comp, "fmi2SetFMUstate");
    const saved_state *s = (const saved_state *)FMUstate;
    char text[2300];
    if (c == NULL || s == NULL) return fmi2Error;
    if (!same_values(s->values, c->values) || (c->component != NULL) != s->has_component) {
        /* a state of another configuration: remake the component for the state's parameters */
        free_component(c);
        free_values(c->values);
        if (!copy_values(c->values, s->values)) return fail(c, "setFMUstate failed: out of memory");
        if (s->has_component) {
            double t = c->time;
            if (make_component(c) != fmi2OK) return fmi2Error;
            c->time = t;
        }
    }
    if (s->has_component && c->component != NULL &&
        tc_component_set_state(c->component, s->bytes, s->size, msg_of(c)) != TC_OK) {
        snprintf(text, sizeof text, "setFMUstate failed: %s", c->message);
        return fail(c, text);
    }
    c->phase = s->phase;
    c->time = s->time;
    memcpy(c->inputs, s->inputs, sizeof c->inputs);
    memcpy(c->outputs, s->outputs, sizeof c->outputs);
    memcpy(c->failure, s->failure, sizeof c->failure);
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component comp, fmi2FMUstate *FMUstate) {
    (void)comp;
    if (FMUstate == NULL) return fmi2OK;
    free_saved((saved_state *)*FMUstate);
    *FMUstate = NULL;
    return fmi2OK;
}

/* Serialized layout (little-endian fixed-size fields written byte by byte):
 *   magic "TCFMUST1", GUID (length-prefixed), phase, time, inputs, outputs, failure text,
 *   per parameter: number (8 bytes), text (length-prefixed, or length ~0 for none), has_component,
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

static size_t serialize(const saved_state *s, unsigned char *buf, size_t size) {
    writer w = {buf, size, 0};
    put(&w, "TCFMUST1", 8);
    put_text(&w, TC_GUID);
    put_u64(&w, (unsigned long long)s->phase);
    put_double(&w, s->time);
    for (int k = 0; k < (TC_N_INPUTS > 0 ? TC_N_INPUTS : 1); ++k) put_double(&w, s->inputs[k]);
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

fmi2Status fmi2SerializedFMUstateSize(fmi2Component comp, fmi2FMUstate FMUstate, size_t *size) {
    if (comp == NULL || FMUstate == NULL || size == NULL) return fmi2Error;
    *size = serialize((const saved_state *)FMUstate, NULL, 0);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component comp, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                 size_t size) {
    instance *c = checked(comp, "fmi2SerializeFMUstate");
    if (c == NULL || FMUstate == NULL || serializedState == NULL) return fmi2Error;
    size_t need = serialize((const saved_state *)FMUstate, NULL, 0);
    if (size < need) {
        logf_(c, fmi2Error, "fmi2SerializeFMUstate: the buffer holds %zu bytes; the state needs %zu", size, need);
        return fmi2Error;
    }
    serialize((const saved_state *)FMUstate, (unsigned char *)serializedState, size);
    return fmi2OK;
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

/* a length-prefixed text (NULL for the "none" marker); *ok cleared on malformed input */
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

fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate) {
    instance *c = checked(comp, "fmi2DeSerializeFMUstate");
    reader r = {(const unsigned char *)serializedState, size, 0, 1};
    int none;
    if (c == NULL || FMUstate == NULL || (size > 0 && serializedState == NULL)) return fmi2Error;
    saved_state *s = calloc(1, sizeof *s);
    if (s == NULL) return fmi2Error;
    const unsigned char *magic = take(&r, 8);
    char *guid = NULL;
    if (magic == NULL || memcmp(magic, "TCFMUST1", 8) != 0) r.ok = 0;
    if (r.ok) guid = get_text(&r, &none);
    if (r.ok && (guid == NULL || strcmp(guid, TC_GUID) != 0)) {
        logf_(c, fmi2Error, "fmi2DeSerializeFMUstate: the state was serialized by another FMU (GUID %s; this FMU is "
                            "%s)", guid ? guid : "none", TC_GUID);
        free(guid);
        free_saved(s);
        return fmi2Error;
    }
    free(guid);
    unsigned long long phase = get_u64(&r);
    s->phase = (int)phase;
    if (phase > PHASE_FAILED) r.ok = 0;
    s->time = get_double(&r);
    for (int k = 0; k < (TC_N_INPUTS > 0 ? TC_N_INPUTS : 1); ++k) s->inputs[k] = get_double(&r);
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
    const unsigned char *bytes = r.ok ? take(&r, (size_t)n) : NULL;
    if (r.ok && n == (size_t)n && (s->bytes = malloc(n ? (size_t)n : 1)) != NULL) {
        memcpy(s->bytes, bytes, (size_t)n);
        s->size = (size_t)n;
    } else {
        r.ok = 0;
    }
    if (!r.ok || r.pos != size) {
        logf_(c, fmi2Error, "fmi2DeSerializeFMUstate: %zu bytes that are not a serialized state of %s",
              size, TC_MODEL_IDENTIFIER);
        free_saved(s);
        return fmi2Error;
    }
    if (*FMUstate != NULL) free_saved((saved_state *)*FMUstate);
    *FMUstate = s;
    return fmi2OK;
}

/* ================================================================================= model exchange (absent) */
static fmi2Status no_model_exchange(fmi2Component comp, const char *function) {
    instance *c = checked(comp, function);
    if (c != NULL) logf_(c, fmi2Error, "%s: %s is a co-simulation FMU; model exchange is not provided", function,
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
