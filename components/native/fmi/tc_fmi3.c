/* The FMI 3.0 co-simulation interface of a native FMU, written in this project against the standard's headers.
 *
 * Generic, as the FMI 2.0 wrapper (tc_fmi2.c): the variables come from the generated "tc_fmu_model.h", the
 * component from its glue (tc_fmu.h), and the instance, parameter checks, step and FMU states from the shared
 * core (tc_fmu_instance.h), so both versions compute the same outputs to the last bit and keep the same status
 * contract:
 *
 *   - parameters are set in the instantiated and initialization states; fmi3ExitInitializationMode checks
 *     every parameter against its declared range or choices and makes the component. A bad parameter or file
 *     is fmi3Error with a message naming the parameter, its value and what is allowed; the instance is then
 *     unusable. Setting a parameter after initialization is fmi3Error (they are fixed), the value unchanged;
 *   - fmi3DoStep with a bad input or a step the model cannot take returns fmi3Discard with the state unchanged
 *     (lastSuccessfulTime = the current time) and a message naming the cause, the inputs and the time; when a step
 *     2^-20 as long is discarded too, no step size can complete it (the inputs are at fault): fmi3Error with
 *     terminateSimulation = fmi3True, "the FMU requests to stop the simulation" (FMI 3.0 section 4.2.1), as it
 *     sets whenever the instance failed.
 *     It returns fmi3Warning, with a message, when an output has just left a range the model is built for or the
 *     step's inputs are outside theirs. A doStep that repeats a discarded one unchanged (same state, step size and
 *     inputs) is discarded at once with terminateSimulation: it would be discarded again, forever. It never asks for event handling and never
 *     returns early;
 *   - in initialization mode, getting a scalar output computes it from the parameters and the inputs set so far
 *     (its InitialUnknown dependencies);
 *   - FMU states (get/set, serialize/deserialize) replay bit-identically, also in another instance;
 *   - messages go to the importer's logMessage (errors and discards always, the rest when logging is on);
 *   - no global mutable state; the C library's memory, all of it freed by fmi3FreeInstance.
 *
 * What FMI 3.0 adds: the independent variable `time`; for a component with array outputs (the strip's nodal
 * fields beta, U and contact), Float64 arrays whose length is the UInt64 structural parameter TC_ARRAY_SIZE_NAME
 * (n_nodes), which equals the Integer parameter it derives from plus TC_ARRAY_SIZE_OFFSET (n_elements + 1).
 * Both are structural parameters, set in Configuration Mode or, as importers that set every start value
 * before initialization do, in the instantiated state; setting either sets both (n_nodes is stored as
 * n_elements). fmi3ExitInitializationMode checks a set n_nodes against its own range and, when both were set,
 * that they agree (n_nodes = n_elements + 1): either is fmi3Error naming the values. The arrays are computed
 * from fmi3ExitInitializationMode on; before, getting them is fmi3Error.
 *
 * Not provided, each fmi3Error with a message naming the function: model exchange and scheduled execution,
 * event mode, clocks, intermediate update, Reconfiguration Mode, directional and adjoint derivatives, output
 * derivatives, variable dependencies; getters and setters of types the FMU has no variable of.
 *
 * The standard's headers (fmpy's copies) are compiled as system headers: fmi3FunctionTypes.h declares two
 * callbacks without prototypes, which this project's warning flags would refuse.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "tc_fmu.h"
#include "tc_fmu_instance.h"
#include "tc_fmu_model.h"

/* the FMI 3.0 instance: the core first (the logger below casts back), then the importer's logger */
typedef struct instance {
    tc_instance core;
    fmi3LogMessageCallback logger;
    fmi3InstanceEnvironment environment;
    int configuring; /* in Configuration Mode (entered from, and left back to, the instantiated state) */
    int nodes_set, elements_set; /* the array length (n_nodes) and its parameter (n_elements) set by the importer */
    double nodes, elements;      /* their last values set */
} instance;

static const char *const KIND_NAMES[3] = {"Float64", "Int32", "String"};

#if TC_N_ARRAYS > 0
#define VR_LAST (TC_VR_ARRAYS + TC_N_ARRAYS - 1)
#else
#define VR_LAST TC_VR_TIME
#endif

static void emit(const tc_instance *core, int status, const char *category, const char *text) {
    const instance *c = (const instance *)core;
    if (c->logger != NULL) c->logger(c->environment, (fmi3Status)status, category, text);
}

/* the instance behind an fmi3Instance (NULL stays NULL: every function then returns fmi3Error) */
static instance *checked(fmi3Instance inst) { return (instance *)inst; }

static fmi3Status not_provided(fmi3Instance inst, const char *function, const char *why) {
    instance *c = checked(inst);
    if (c != NULL) tc_inst_logf(&c->core, TC_LOG_ERROR, "%s: not provided by %s (%s)", function, TC_MODEL_IDENTIFIER,
                                why);
    return fmi3Error;
}

/* ================================================================================= common functions */
const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance inst, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    instance *c = checked(inst);
    (void)nCategories;
    (void)categories;
    if (c == NULL) return fmi3Error;
    c->core.logging_on = loggingOn ? 1 : 0;
    return fmi3OK;
}

/* a logger-only instance, for the messages of a refused instantiation */
static void refuse(fmi3String name, fmi3InstanceEnvironment env, fmi3LogMessageCallback logMessage,
                   const char *text) {
    instance tmp;
    memset(&tmp, 0, sizeof tmp);
    tmp.core.emit = emit;
    tmp.core.name = (char *)(name ? name : "?");
    tmp.logger = logMessage;
    tmp.environment = env;
    tc_inst_logf(&tmp.core, TC_LOG_ERROR, "%s", text);
}

/* the resources folder from resourcePath (a path with a trailing separator; NULL: the working directory) */
static char *resources_folder(fmi3String path) {
    char *out = tc_inst_copy_text(path ? path : ".");
    if (out == NULL) return NULL;
    size_t n = strlen(out);
    while (n > 1 && (out[n - 1] == '/' || out[n - 1] == '\\')) out[--n] = '\0';
    return out;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                         fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate) {
    char text[512];
    (void)visible;
    (void)earlyReturnAllowed; /* allowed, never done */
    (void)requiredIntermediateVariables;
    (void)intermediateUpdate;
    if (instantiationToken == NULL || strcmp(instantiationToken, TC_GUID) != 0) {
        snprintf(text, sizeof text, "instantiation token %s does not match this FMU's %s (a model description of "
                 "another build?)", instantiationToken ? instantiationToken : "(null)", TC_GUID);
        refuse(instanceName, instanceEnvironment, logMessage, text);
        return NULL;
    }
    if (eventModeUsed) {
        snprintf(text, sizeof text, "fmi3InstantiateCoSimulation: eventModeUsed = true, but %s has no event mode "
                 "(hasEventMode = false)", TC_MODEL_IDENTIFIER);
        refuse(instanceName, instanceEnvironment, logMessage, text);
        return NULL;
    }
    if (nRequiredIntermediateVariables > 0) {
        snprintf(text, sizeof text, "fmi3InstantiateCoSimulation: %zu intermediate variables required, but %s "
                 "provides no intermediate update (providesIntermediateUpdate = false)",
                 nRequiredIntermediateVariables, TC_MODEL_IDENTIFIER);
        refuse(instanceName, instanceEnvironment, logMessage, text);
        return NULL;
    }
    instance *c = calloc(1, sizeof *c);
    if (c == NULL) return NULL;
    c->core.emit = emit;
    c->logger = logMessage;
    c->environment = instanceEnvironment;
    c->core.terminate_name = "terminateSimulation";
    if (!tc_inst_init(&c->core, instanceName, resources_folder(resourcePath), loggingOn)) {
        free(c);
        return NULL;
    }
    return c;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    char text[256];
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    snprintf(text, sizeof text, "fmi3InstantiateModelExchange: %s is a co-simulation FMU; model exchange is not "
             "provided", TC_MODEL_IDENTIFIER);
    refuse(instanceName, instanceEnvironment, logMessage, text);
    return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    char text[256];
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    (void)clockUpdate;
    (void)lockPreemption;
    (void)unlockPreemption;
    snprintf(text, sizeof text, "fmi3InstantiateScheduledExecution: %s is a co-simulation FMU; scheduled execution "
             "is not provided", TC_MODEL_IDENTIFIER);
    refuse(instanceName, instanceEnvironment, logMessage, text);
    return NULL;
}

void fmi3FreeInstance(fmi3Instance inst) {
    instance *c = checked(inst);
    if (c == NULL) return;
    tc_inst_release(&c->core);
    free(c);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance inst, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    instance *c = checked(inst);
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (c == NULL) return fmi3Error;
    if (c->core.phase != TC_PHASE_INSTANTIATED || c->configuring) {
        tc_inst_logf(&c->core, TC_LOG_ERROR, "fmi3EnterInitializationMode is allowed only after "
                     "fmi3InstantiateCoSimulation%s", c->configuring ? " (leave Configuration Mode first)" : "");
        return fmi3Error;
    }
    if (!isfinite(startTime)) {
        tc_inst_logf(&c->core, TC_LOG_ERROR, "fmi3EnterInitializationMode: startTime = %g s is not finite", startTime);
        return fmi3Error;
    }
    c->core.time = startTime;
    c->core.phase = TC_PHASE_INITIALIZATION;
    return fmi3OK;
}

/* n_nodes in its own range, and n_nodes = n_elements + offset when the importer set both; 0 with the instance
 * failed (a message naming both) if not */
static int array_size_agrees(instance *c) {
#if TC_N_ARRAYS > 0
    char text[512];
    const tc_variable *p = &TC_VARIABLES[TC_ARRAY_SIZE_PARAMETER];
    double lo = p->low + TC_ARRAY_SIZE_OFFSET, hi = p->high + TC_ARRAY_SIZE_OFFSET;
    if (c->nodes_set && (c->nodes < lo || c->nodes > hi)) {
        snprintf(text, sizeof text, "initialization failed: %s = %.0f is out of range; allowed: [%.0f, %.0f] (%s + %d)",
                 TC_ARRAY_SIZE_NAME, c->nodes, lo, hi, p->name, TC_ARRAY_SIZE_OFFSET);
        tc_inst_fail(&c->core, text);
        return 0;
    }
    if (c->nodes_set && c->elements_set && c->nodes != c->elements + TC_ARRAY_SIZE_OFFSET) {
        snprintf(text, sizeof text, "initialization failed: %s = %.0f and %s = %.0f were both set and disagree; %s must "
                 "be %s + %d: set one of them", TC_ARRAY_SIZE_NAME, c->nodes, p->name, c->elements,
                 TC_ARRAY_SIZE_NAME, p->name, TC_ARRAY_SIZE_OFFSET);
        tc_inst_fail(&c->core, text);
        return 0;
    }
#else
    (void)c;
#endif
    return 1;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance inst) {
    instance *c = checked(inst);
    if (c == NULL) return fmi3Error;
    if (c->core.phase != TC_PHASE_INITIALIZATION) {
        tc_inst_logf(&c->core, TC_LOG_ERROR, "fmi3ExitInitializationMode is allowed only in initialization mode");
        return fmi3Error;
    }
    if (!array_size_agrees(c)) return fmi3Error;
    c->nodes_set = c->elements_set = 0; /* from here on one value, n_elements, holds both */
    return (fmi3Status)tc_inst_exit_initialization(&c->core);
}

fmi3Status fmi3EnterEventMode(fmi3Instance inst) {
    return not_provided(inst, "fmi3EnterEventMode", "hasEventMode = false");
}

fmi3Status fmi3Terminate(fmi3Instance inst) {
    instance *c = checked(inst);
    if (c == NULL) return fmi3Error;
    c->configuring = 0;
    return (fmi3Status)tc_inst_terminate(&c->core);
}

fmi3Status fmi3Reset(fmi3Instance inst) {
    instance *c = checked(inst);
    if (c == NULL) return fmi3Error;
    c->configuring = 0;
    c->nodes_set = c->elements_set = 0;
    return tc_inst_reset(&c->core) ? fmi3OK : fmi3Fatal;
}

/* ================================================================================= get and set */
/* array output k of value reference vr, or -1 */
static int array_of(fmi3ValueReference vr) {
#if TC_N_ARRAYS > 0
    if (vr >= TC_VR_ARRAYS && vr < TC_VR_ARRAYS + TC_N_ARRAYS) return (int)(vr - TC_VR_ARRAYS);
#endif
    (void)vr;
    return -1;
}

/* array output k: its name, and its values into out (when not NULL); returns its length */
static const char *array_name(int k) {
#if TC_N_ARRAYS > 0
    return TC_ARRAYS[k];
#else
    (void)k;
    return "";
#endif
}

static size_t array_values(const tc_component *component, int k, double *out) {
#if TC_N_ARRAYS > 0
    return tc_component_array(component, k, out);
#else
    (void)component;
    (void)k;
    (void)out;
    return 0;
#endif
}

static int is_structural(const tc_variable *v) {
#if TC_N_ARRAYS > 0
    return v->causality == TC_CAUSALITY_PARAMETER && v->index == TC_ARRAY_SIZE_PARAMETER;
#else
    (void)v;
    return 0;
#endif
}

static const tc_variable *variable(instance *c, fmi3ValueReference vr, int kind, const char *function) {
    return tc_inst_variable(&c->core, (unsigned)vr, kind, function, KIND_NAMES, VR_LAST);
}

/* Whether parameter `name` may be set now (an error naming `function` is logged if not). */
static int settable(instance *c, const char *name, int structural, const char *function) {
    int phase = c->core.phase;
    if (structural) {
        if (phase == TC_PHASE_INSTANTIATED) return 1;
        tc_inst_logf(&c->core, TC_LOG_ERROR, "%s: %s is a structural parameter; set it in Configuration Mode or "
                     "before fmi3EnterInitializationMode", function, name);
        return 0;
    }
    if (c->configuring) {
        tc_inst_logf(&c->core, TC_LOG_ERROR, "%s: only structural parameters can be set in Configuration Mode, not %s",
                     function, name);
        return 0;
    }
    if (phase == TC_PHASE_INSTANTIATED || phase == TC_PHASE_INITIALIZATION) return 1;
    tc_inst_logf(&c->core, TC_LOG_ERROR, "%s: parameter %s is fixed after initialization; it cannot be set",
                 function, name);
    return 0;
}

/* nValues must be the number of values the value references hold */
static int counted(instance *c, const char *function, size_t nvr, size_t need, size_t nValues) {
    if (need == nValues) return 1;
    tc_inst_logf(&c->core, TC_LOG_ERROR, "%s: nValues = %zu, but the %zu value references hold %zu values", function,
                 nValues, nvr, need);
    return 0;
}

/* an Integer value as fmi3Int32 (values come from fmi3SetInt32 or a checked n_nodes, but a restored state may
 * hold anything: no undefined conversion) */
static fmi3Int32 to_int32(double x) {
    if (!(x >= (double)INT32_MIN)) return INT32_MIN; /* and NaN */
    if (x > (double)INT32_MAX) return INT32_MAX;
    return (fmi3Int32)x;
}

/* whether the value references name a scalar output (computed in initialization mode when read) */
static int reads_output(const fmi3ValueReference vr[], size_t nvr) {
    for (size_t k = 0; k < nvr; ++k)
        if (vr[k] < (fmi3ValueReference)TC_N_VARIABLES && TC_VARIABLES[vr[k]].causality == TC_CAUSALITY_OUTPUT)
            return 1;
    return 0;
}

fmi3Status fmi3GetFloat64(fmi3Instance inst, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          fmi3Float64 values[], size_t nValues) {
    static const char *const function = "fmi3GetFloat64";
    instance *c = checked(inst);
    size_t need = 0, at = 0;
    if (c == NULL || (nValueReferences > 0 && (valueReferences == NULL || values == NULL))) return fmi3Error;
    for (size_t k = 0; k < nValueReferences; ++k) { /* check everything, and count, before writing */
        fmi3ValueReference vr = valueReferences[k];
        int a = array_of(vr);
        if (a >= 0) {
            if (c->core.component == NULL || c->core.phase == TC_PHASE_INITIALIZATION) {
                tc_inst_logf(&c->core, TC_LOG_ERROR, "%s: %s is computed from fmi3ExitInitializationMode on%s",
                             function, array_name(a),
                             c->core.phase == TC_PHASE_FAILED ? " (the FMU is not usable)" : "");
                return fmi3Error;
            }
            need += array_values(c->core.component, a, NULL);
        } else if (vr == TC_VR_TIME || variable(c, vr, TC_KIND_REAL, function) != NULL) {
            need += 1;
        } else {
            return fmi3Error;
        }
    }
    if (!counted(c, function, nValueReferences, need, nValues)) return fmi3Error;
    if (reads_output(valueReferences, nValueReferences) && tc_inst_initial_outputs(&c->core, function) != TC_LOG_OK)
        return fmi3Error;
    for (size_t k = 0; k < nValueReferences; ++k) {
        fmi3ValueReference vr = valueReferences[k];
        int a = array_of(vr);
        if (a >= 0) at += array_values(c->core.component, a, values + at);
        else values[at++] = vr == TC_VR_TIME ? c->core.time : tc_inst_number(&c->core, &TC_VARIABLES[vr]);
    }
    return fmi3OK;
}

fmi3Status fmi3GetInt32(fmi3Instance inst, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        fmi3Int32 values[], size_t nValues) {
    instance *c = checked(inst);
    if (c == NULL || (nValueReferences > 0 && (valueReferences == NULL || values == NULL))) return fmi3Error;
    for (size_t k = 0; k < nValueReferences; ++k)
        if (variable(c, valueReferences[k], TC_KIND_INTEGER, "fmi3GetInt32") == NULL) return fmi3Error;
    if (!counted(c, "fmi3GetInt32", nValueReferences, nValueReferences, nValues)) return fmi3Error;
    if (reads_output(valueReferences, nValueReferences) &&
        tc_inst_initial_outputs(&c->core, "fmi3GetInt32") != TC_LOG_OK)
        return fmi3Error;
    for (size_t k = 0; k < nValueReferences; ++k)
        values[k] = to_int32(tc_inst_number(&c->core, &TC_VARIABLES[valueReferences[k]]));
    return fmi3OK;
}

fmi3Status fmi3GetString(fmi3Instance inst, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         fmi3String values[], size_t nValues) {
    instance *c = checked(inst);
    if (c == NULL || (nValueReferences > 0 && (valueReferences == NULL || values == NULL))) return fmi3Error;
    for (size_t k = 0; k < nValueReferences; ++k)
        if (variable(c, valueReferences[k], TC_KIND_STRING, "fmi3GetString") == NULL) return fmi3Error;
    if (!counted(c, "fmi3GetString", nValueReferences, nValueReferences, nValues)) return fmi3Error;
    for (size_t k = 0; k < nValueReferences; ++k)
        values[k] = c->core.values[TC_VARIABLES[valueReferences[k]].index].text;
    return fmi3OK;
}

/* the UInt64 structural parameter of the arrays' length, if the value reference is it */
static int is_array_size(fmi3ValueReference vr) {
#if TC_N_ARRAYS > 0
    return vr == TC_VR_ARRAY_SIZE;
#else
    (void)vr;
    return 0;
#endif
}

/* a getter or setter of a type the FMU has no variable of: fine for no value references */
static fmi3Status no_variables(fmi3Instance inst, const char *function, const char *type,
                               const fmi3ValueReference valueReferences[], size_t nValueReferences) {
    instance *c = checked(inst);
    if (c == NULL) return fmi3Error;
    if (nValueReferences == 0) return fmi3OK;
    tc_inst_logf(&c->core, TC_LOG_ERROR, "%s: %s has no %s variables (value reference %u)", function,
                 TC_MODEL_IDENTIFIER, type, valueReferences ? (unsigned)valueReferences[0] : 0u);
    return fmi3Error;
}

fmi3Status fmi3GetUInt64(fmi3Instance inst, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         fmi3UInt64 values[], size_t nValues) {
    instance *c = checked(inst);
    if (c == NULL || (nValueReferences > 0 && (valueReferences == NULL || values == NULL))) return fmi3Error;
    for (size_t k = 0; k < nValueReferences; ++k)
        if (!is_array_size(valueReferences[k])) return no_variables(inst, "fmi3GetUInt64", "other UInt64",
                                                                    valueReferences + k, 1);
    if (!counted(c, "fmi3GetUInt64", nValueReferences, nValueReferences, nValues)) return fmi3Error;
#if TC_N_ARRAYS > 0
    for (size_t k = 0; k < nValueReferences; ++k) {
        double n = c->core.values[TC_ARRAY_SIZE_PARAMETER].number + TC_ARRAY_SIZE_OFFSET;
        values[k] = n >= 0.0 && n < 1.8e19 ? (fmi3UInt64)n : 0u; /* n_elements may be negative until checked */
    }
#endif
    return fmi3OK;
}

/* The scalar types this project's FMUs have no variables of: getting or setting any returns fmi3Error
 * naming the function and the type (nothing to get or set is fmi3OK). */
#define TC_NO_VARIABLES_OF(T)                                                                                    \
    fmi3Status fmi3Get##T(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr, fmi3##T values[],      \
                          size_t nValues) {                                                                    \
        (void)values;                                                                                          \
        (void)nValues;                                                                                         \
        return no_variables(inst, "fmi3Get" #T, #T, vr, nvr);                                                 \
    }                                                                                                          \
    fmi3Status fmi3Set##T(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr, const fmi3##T values[], \
                          size_t nValues) {                                                                    \
        (void)values;                                                                                          \
        (void)nValues;                                                                                         \
        return no_variables(inst, "fmi3Set" #T, #T, vr, nvr);                                                 \
    }
TC_NO_VARIABLES_OF(Float32)
TC_NO_VARIABLES_OF(Int8)
TC_NO_VARIABLES_OF(UInt8)
TC_NO_VARIABLES_OF(Int16)
TC_NO_VARIABLES_OF(UInt16)
TC_NO_VARIABLES_OF(UInt32)
TC_NO_VARIABLES_OF(Int64)
TC_NO_VARIABLES_OF(Boolean)
#undef TC_NO_VARIABLES_OF
fmi3Status fmi3GetBinary(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr, size_t valueSizes[],
                         fmi3Binary values[], size_t nValues) {
    (void)valueSizes;
    (void)values;
    (void)nValues;
    return no_variables(inst, "fmi3GetBinary", "Binary", vr, nvr);
}
fmi3Status fmi3GetClock(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr, fmi3Clock values[]) {
    (void)values;
    return no_variables(inst, "fmi3GetClock", "Clock", vr, nvr);
}

fmi3Status fmi3SetFloat64(fmi3Instance inst, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          const fmi3Float64 values[], size_t nValues) {
    static const char *const function = "fmi3SetFloat64";
    instance *c = checked(inst);
    if (c == NULL || (nValueReferences > 0 && (valueReferences == NULL || values == NULL))) return fmi3Error;
    if (!counted(c, function, nValueReferences, nValueReferences, nValues)) return fmi3Error;
    for (size_t k = 0; k < nValueReferences; ++k) {
        fmi3ValueReference vr = valueReferences[k];
        int a = array_of(vr);
        if (vr == TC_VR_TIME || a >= 0) {
            tc_inst_logf(&c->core, TC_LOG_ERROR, "%s: %s is %s; it cannot be set", function,
                         a >= 0 ? array_name(a) : "time", a >= 0 ? "an output" : "the independent variable");
            return fmi3Error;
        }
        const tc_variable *v = variable(c, vr, TC_KIND_REAL, function);
        if (v == NULL) return fmi3Error;
        if (v->causality == TC_CAUSALITY_OUTPUT) {
            tc_inst_logf(&c->core, TC_LOG_ERROR, "%s: %s is an output; it cannot be set", function, v->name);
            return fmi3Error;
        }
        if (v->causality == TC_CAUSALITY_INPUT) {
            if (c->configuring) {
                tc_inst_logf(&c->core, TC_LOG_ERROR, "%s: only structural parameters can be set in Configuration "
                             "Mode, not %s", function, v->name);
                return fmi3Error;
            }
            tc_inst_set_input(&c->core, v, values[k]);
        } else if (settable(c, v->name, is_structural(v), function)) {
            c->core.values[v->index].number = values[k];
        } else {
            return fmi3Error;
        }
    }
    return fmi3OK;
}

fmi3Status fmi3SetInt32(fmi3Instance inst, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        const fmi3Int32 values[], size_t nValues) {
    instance *c = checked(inst);
    if (c == NULL || (nValueReferences > 0 && (valueReferences == NULL || values == NULL))) return fmi3Error;
    if (!counted(c, "fmi3SetInt32", nValueReferences, nValueReferences, nValues)) return fmi3Error;
    for (size_t k = 0; k < nValueReferences; ++k) {
        const tc_variable *v = variable(c, valueReferences[k], TC_KIND_INTEGER, "fmi3SetInt32");
        if (v == NULL) return fmi3Error;
        if (v->causality != TC_CAUSALITY_PARAMETER) {
            tc_inst_logf(&c->core, TC_LOG_ERROR, "fmi3SetInt32: %s is an output; it cannot be set", v->name);
            return fmi3Error;
        }
        if (!settable(c, v->name, is_structural(v), "fmi3SetInt32")) return fmi3Error;
        c->core.values[v->index].number = (double)values[k];
        if (is_structural(v)) {
            c->elements_set = 1;
            c->elements = (double)values[k];
        }
    }
    return fmi3OK;
}

fmi3Status fmi3SetUInt64(fmi3Instance inst, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         const fmi3UInt64 values[], size_t nValues) {
    instance *c = checked(inst);
    if (c == NULL || (nValueReferences > 0 && (valueReferences == NULL || values == NULL))) return fmi3Error;
    for (size_t k = 0; k < nValueReferences; ++k)
        if (!is_array_size(valueReferences[k])) return no_variables(inst, "fmi3SetUInt64", "other UInt64",
                                                                    valueReferences + k, 1);
    if (!counted(c, "fmi3SetUInt64", nValueReferences, nValueReferences, nValues)) return fmi3Error;
#if TC_N_ARRAYS > 0
    const tc_variable *p = &TC_VARIABLES[TC_ARRAY_SIZE_PARAMETER];
    for (size_t k = 0; k < nValueReferences; ++k) {
        if (!settable(c, TC_ARRAY_SIZE_NAME, 1, "fmi3SetUInt64")) return fmi3Error;
        if (values[k] > (fmi3UInt64)INT32_MAX + TC_ARRAY_SIZE_OFFSET) { /* its parameter is an Int32 */
            tc_inst_logf(&c->core, TC_LOG_ERROR, "fmi3SetUInt64: %s = %llu is out of range; allowed: [%.0f, %.0f] "
                         "(%s + %d)", TC_ARRAY_SIZE_NAME, (unsigned long long)values[k], p->low + TC_ARRAY_SIZE_OFFSET,
                         p->high + TC_ARRAY_SIZE_OFFSET, p->name, TC_ARRAY_SIZE_OFFSET);
            return fmi3Error;
        }
        c->core.values[TC_ARRAY_SIZE_PARAMETER].number = (double)values[k] - TC_ARRAY_SIZE_OFFSET;
        c->nodes_set = 1;
        c->nodes = (double)values[k];
    }
#endif
    return fmi3OK;
}

fmi3Status fmi3SetString(fmi3Instance inst, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         const fmi3String values[], size_t nValues) {
    instance *c = checked(inst);
    if (c == NULL || (nValueReferences > 0 && (valueReferences == NULL || values == NULL))) return fmi3Error;
    if (!counted(c, "fmi3SetString", nValueReferences, nValueReferences, nValues)) return fmi3Error;
    for (size_t k = 0; k < nValueReferences; ++k) {
        const tc_variable *v = variable(c, valueReferences[k], TC_KIND_STRING, "fmi3SetString");
        if (v == NULL || !settable(c, v->name, 0, "fmi3SetString")) return fmi3Error;
        char *text = tc_inst_copy_text(values[k]);
        if (text == NULL) return fmi3Error;
        free(c->core.values[v->index].text);
        c->core.values[v->index].text = text;
    }
    return fmi3OK;
}

fmi3Status fmi3SetBinary(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr, const size_t valueSizes[],
                         const fmi3Binary values[], size_t nValues) {
    (void)valueSizes;
    (void)values;
    (void)nValues;
    return no_variables(inst, "fmi3SetBinary", "Binary", vr, nvr);
}
fmi3Status fmi3SetClock(fmi3Instance inst, const fmi3ValueReference vr[], size_t nvr, const fmi3Clock values[]) {
    (void)values;
    return no_variables(inst, "fmi3SetClock", "Clock", vr, nvr);
}

/* ================================================================================= dependencies, derivatives */
fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance inst, fmi3ValueReference valueReference,
                                               size_t *nDependencies) {
    (void)valueReference;
    (void)nDependencies;
    return not_provided(inst, "fmi3GetNumberOfVariableDependencies", "the model description's ModelStructure gives "
                        "every output's dependencies: none");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance inst, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[], fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[], fmi3DependencyKind dependencyKinds[],
                                       size_t nDependencies) {
    (void)dependent;
    (void)elementIndicesOfDependent;
    (void)independents;
    (void)elementIndicesOfIndependents;
    (void)dependencyKinds;
    (void)nDependencies;
    return not_provided(inst, "fmi3GetVariableDependencies", "the model description's ModelStructure gives every "
                        "output's dependencies: none");
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance inst, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                        size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns;
    (void)nUnknowns;
    (void)knowns;
    (void)nKnowns;
    (void)seed;
    (void)nSeed;
    (void)sensitivity;
    (void)nSensitivity;
    return not_provided(inst, "fmi3GetDirectionalDerivative", "providesDirectionalDerivatives = false");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance inst, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                    const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                    size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns;
    (void)nUnknowns;
    (void)knowns;
    (void)nKnowns;
    (void)seed;
    (void)nSeed;
    (void)sensitivity;
    (void)nSensitivity;
    return not_provided(inst, "fmi3GetAdjointDerivative", "providesAdjointDerivatives = false");
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance inst, const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues) {
    instance *c = checked(inst);
    (void)valueReferences;
    (void)orders;
    (void)values;
    (void)nValues;
    if (c == NULL) return fmi3Error;
    if (nValueReferences == 0) return fmi3OK;
    return not_provided(inst, "fmi3GetOutputDerivatives", "maxOutputDerivativeOrder = 0");
}

/* ================================================================================= FMU state */
fmi3Status fmi3GetFMUState(fmi3Instance inst, fmi3FMUState *FMUState) {
    instance *c = checked(inst);
    if (c == NULL || FMUState == NULL) return fmi3Error;
    return (fmi3Status)tc_inst_get_state(&c->core, FMUState, "fmi3GetFMUState");
}

fmi3Status fmi3SetFMUState(fmi3Instance inst, fmi3FMUState FMUState) {
    instance *c = checked(inst);
    if (c == NULL || FMUState == NULL) return fmi3Error;
    c->configuring = 0;
    c->nodes_set = c->elements_set = 0; /* the state's parameters hold the array length */
    return (fmi3Status)tc_inst_set_state(&c->core, FMUState);
}

fmi3Status fmi3FreeFMUState(fmi3Instance inst, fmi3FMUState *FMUState) {
    (void)inst;
    if (FMUState == NULL) return fmi3OK;
    tc_inst_free_state(*FMUState);
    *FMUState = NULL;
    return fmi3OK;
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance inst, fmi3FMUState FMUState, size_t *size) {
    if (inst == NULL || FMUState == NULL || size == NULL) return fmi3Error;
    *size = tc_inst_serialize(FMUState, NULL, 0);
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance inst, fmi3FMUState FMUState, fmi3Byte serializedState[], size_t size) {
    instance *c = checked(inst);
    if (c == NULL || FMUState == NULL || serializedState == NULL) return fmi3Error;
    size_t need = tc_inst_serialize(FMUState, NULL, 0);
    if (size < need) {
        tc_inst_logf(&c->core, TC_LOG_ERROR, "fmi3SerializeFMUState: the buffer holds %zu bytes; the state needs %zu",
                     size, need);
        return fmi3Error;
    }
    tc_inst_serialize(FMUState, serializedState, size);
    return fmi3OK;
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance inst, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState) {
    instance *c = checked(inst);
    if (c == NULL || FMUState == NULL || (size > 0 && serializedState == NULL)) return fmi3Error;
    return (fmi3Status)tc_inst_deserialize(&c->core, serializedState, size, FMUState, "fmi3DeserializeFMUState",
                                           "instantiation token");
}

/* ================================================================================= configuration */
fmi3Status fmi3EnterConfigurationMode(fmi3Instance inst) {
    instance *c = checked(inst);
    if (c == NULL) return fmi3Error;
    if (c->core.phase == TC_PHASE_INSTANTIATED && !c->configuring) {
        c->configuring = 1;
        return fmi3OK;
    }
    if (c->core.phase == TC_PHASE_STEPPING)
        return not_provided(inst, "fmi3EnterConfigurationMode", "Reconfiguration Mode: the structural parameters are "
                            "fixed after initialization");
    tc_inst_logf(&c->core, TC_LOG_ERROR, "fmi3EnterConfigurationMode is allowed only after "
                 "fmi3InstantiateCoSimulation%s", c->configuring ? " (already in Configuration Mode)" : "");
    return fmi3Error;
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance inst) {
    instance *c = checked(inst);
    if (c == NULL) return fmi3Error;
    if (!c->configuring) {
        tc_inst_logf(&c->core, TC_LOG_ERROR, "fmi3ExitConfigurationMode is allowed only in Configuration Mode");
        return fmi3Error;
    }
    c->configuring = 0;
    return fmi3OK;
}

/* ================================================================================= clocks (absent) */
fmi3Status fmi3GetIntervalDecimal(fmi3Instance inst, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[]) {
    (void)valueReferences;
    (void)nValueReferences;
    (void)intervals;
    (void)qualifiers;
    return not_provided(inst, "fmi3GetIntervalDecimal", "no clocks");
}
fmi3Status fmi3GetIntervalFraction(fmi3Instance inst, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[]) {
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    (void)qualifiers;
    return not_provided(inst, "fmi3GetIntervalFraction", "no clocks");
}
fmi3Status fmi3GetShiftDecimal(fmi3Instance inst, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, fmi3Float64 shifts[]) {
    (void)valueReferences;
    (void)nValueReferences;
    (void)shifts;
    return not_provided(inst, "fmi3GetShiftDecimal", "no clocks");
}
fmi3Status fmi3GetShiftFraction(fmi3Instance inst, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    return not_provided(inst, "fmi3GetShiftFraction", "no clocks");
}
fmi3Status fmi3SetIntervalDecimal(fmi3Instance inst, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, const fmi3Float64 intervals[]) {
    (void)valueReferences;
    (void)nValueReferences;
    (void)intervals;
    return not_provided(inst, "fmi3SetIntervalDecimal", "no clocks");
}
fmi3Status fmi3SetIntervalFraction(fmi3Instance inst, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[]) {
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    return not_provided(inst, "fmi3SetIntervalFraction", "no clocks");
}
fmi3Status fmi3SetShiftDecimal(fmi3Instance inst, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, const fmi3Float64 shifts[]) {
    (void)valueReferences;
    (void)nValueReferences;
    (void)shifts;
    return not_provided(inst, "fmi3SetShiftDecimal", "no clocks");
}
fmi3Status fmi3SetShiftFraction(fmi3Instance inst, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, const fmi3UInt64 counters[],
                                const fmi3UInt64 resolutions[]) {
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    return not_provided(inst, "fmi3SetShiftFraction", "no clocks");
}

/* ================================================================================= event mode (absent) */
fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance inst) {
    return not_provided(inst, "fmi3EvaluateDiscreteStates", "hasEventMode = false");
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance inst, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation, fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged, fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime) {
    (void)discreteStatesNeedUpdate;
    (void)terminateSimulation;
    (void)nominalsOfContinuousStatesChanged;
    (void)valuesOfContinuousStatesChanged;
    (void)nextEventTimeDefined;
    (void)nextEventTime;
    return not_provided(inst, "fmi3UpdateDiscreteStates", "hasEventMode = false");
}

/* ================================================================================= model exchange (absent) */
static fmi3Status no_model_exchange(fmi3Instance inst, const char *function) {
    return not_provided(inst, function, "a co-simulation FMU; model exchange is not provided");
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance inst) {
    return no_model_exchange(inst, "fmi3EnterContinuousTimeMode");
}
fmi3Status fmi3CompletedIntegratorStep(fmi3Instance inst, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    (void)enterEventMode;
    (void)terminateSimulation;
    return no_model_exchange(inst, "fmi3CompletedIntegratorStep");
}
fmi3Status fmi3SetTime(fmi3Instance inst, fmi3Float64 time) {
    (void)time;
    return no_model_exchange(inst, "fmi3SetTime");
}
fmi3Status fmi3SetContinuousStates(fmi3Instance inst, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    (void)continuousStates;
    (void)nContinuousStates;
    return no_model_exchange(inst, "fmi3SetContinuousStates");
}
fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance inst, fmi3Float64 derivatives[],
                                             size_t nContinuousStates) {
    (void)derivatives;
    (void)nContinuousStates;
    return no_model_exchange(inst, "fmi3GetContinuousStateDerivatives");
}
fmi3Status fmi3GetEventIndicators(fmi3Instance inst, fmi3Float64 eventIndicators[], size_t nEventIndicators) {
    (void)eventIndicators;
    (void)nEventIndicators;
    return no_model_exchange(inst, "fmi3GetEventIndicators");
}
fmi3Status fmi3GetContinuousStates(fmi3Instance inst, fmi3Float64 continuousStates[], size_t nContinuousStates) {
    (void)continuousStates;
    (void)nContinuousStates;
    return no_model_exchange(inst, "fmi3GetContinuousStates");
}
fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance inst, fmi3Float64 nominals[], size_t nContinuousStates) {
    (void)nominals;
    (void)nContinuousStates;
    return no_model_exchange(inst, "fmi3GetNominalsOfContinuousStates");
}
fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance inst, size_t *nEventIndicators) {
    (void)nEventIndicators;
    return no_model_exchange(inst, "fmi3GetNumberOfEventIndicators");
}
fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance inst, size_t *nContinuousStates) {
    (void)nContinuousStates;
    return no_model_exchange(inst, "fmi3GetNumberOfContinuousStates");
}

/* ================================================================================= co-simulation */
fmi3Status fmi3EnterStepMode(fmi3Instance inst) {
    return not_provided(inst, "fmi3EnterStepMode", "hasEventMode = false: the FMU is in Step Mode from "
                        "fmi3ExitInitializationMode on");
}

fmi3Status fmi3DoStep(fmi3Instance inst, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean *eventHandlingNeeded,
                      fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    instance *c = checked(inst);
    (void)noSetFMUStatePriorToCurrentPoint;
    if (c == NULL) return fmi3Error;
    if (eventHandlingNeeded == NULL || terminateSimulation == NULL || earlyReturn == NULL ||
        lastSuccessfulTime == NULL) {
        tc_inst_logf(&c->core, TC_LOG_ERROR, "fmi3DoStep: eventHandlingNeeded, terminateSimulation, earlyReturn and "
                     "lastSuccessfulTime must point to variables; one of them is NULL");
        return fmi3Error;
    }
    int status = tc_inst_do_step(&c->core, currentCommunicationPoint, communicationStepSize);
    *eventHandlingNeeded = fmi3False;
    *earlyReturn = fmi3False;
    *terminateSimulation = c->core.phase == TC_PHASE_FAILED || c->core.terminate_requested ? fmi3True : fmi3False;
    *lastSuccessfulTime = c->core.time; /* the end of the step, or the unchanged time of a discarded one */
    return (fmi3Status)status;
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance inst, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    (void)clockReference;
    (void)activationTime;
    return not_provided(inst, "fmi3ActivateModelPartition", "scheduled execution");
}
