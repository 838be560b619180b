/* A small FMI 3.0 co-simulation host in C (tests only): loads an FMU's shared library with dlopen, in a process
 * with no Python, and drives it through the fmi3 functions, as a C/C++ importer does.
 *
 *   fmi3_host UNZIPPED_DIR MODEL_IDENTIFIER INSTANTIATION_TOKEN [options]
 *     --set KIND:VR=VALUE      set a variable before initialization (KIND r Float64, i Int32, s String, or u UInt64:
 *                              set in Configuration Mode), repeatable
 *     --inputs VR,VR,...       value references of the Float64 inputs given in the steps file
 *     --outputs KIND:VR,...    the scalar outputs to print after every step (r Float64 or i Int32: r:35,i:43)
 *     --arrays SIZE_VR:VR,...  Float64 array outputs to print after the scalars, their length the UInt64 SIZE_VR
 *     --steps FILE             one step per line: dt,input1,input2,...
 *     --replay K               after step K: get and serialize the state, finish the run, deserialize and set it
 *                              in a second instance, run the rest again and require bit-identical outputs
 *     --fuzz N SEED            N random calls with NaN, inf, negative and huge values (after the steps): no crash,
 *                              only allowed statuses, a discarded step leaves the outputs unchanged
 *     --symbols                check that every fmi3 function of the standard is exported, and stop
 * Prints "t,outputs...,arrays..." per step (%.17g) to stdout, FMU log messages to stderr. Exit 0 on success.
 */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"

/* the FMI 3.0 platform tuple of the binary this host loads: its own architecture's */
#if defined(__aarch64__)
#define PLATFORM_TUPLE "aarch64-linux"
#else
#define PLATFORM_TUPLE "x86_64-linux"
#endif

static const char *const ALL_FUNCTIONS[] = {
    "fmi3GetVersion", "fmi3SetDebugLogging", "fmi3InstantiateModelExchange", "fmi3InstantiateCoSimulation",
    "fmi3InstantiateScheduledExecution", "fmi3FreeInstance", "fmi3EnterInitializationMode",
    "fmi3ExitInitializationMode", "fmi3EnterEventMode", "fmi3Terminate", "fmi3Reset", "fmi3GetFloat32",
    "fmi3GetFloat64", "fmi3GetInt8", "fmi3GetUInt8", "fmi3GetInt16", "fmi3GetUInt16", "fmi3GetInt32",
    "fmi3GetUInt32", "fmi3GetInt64", "fmi3GetUInt64", "fmi3GetBoolean", "fmi3GetString", "fmi3GetBinary",
    "fmi3GetClock", "fmi3SetFloat32", "fmi3SetFloat64", "fmi3SetInt8", "fmi3SetUInt8", "fmi3SetInt16",
    "fmi3SetUInt16", "fmi3SetInt32", "fmi3SetUInt32", "fmi3SetInt64", "fmi3SetUInt64", "fmi3SetBoolean",
    "fmi3SetString", "fmi3SetBinary", "fmi3SetClock", "fmi3GetNumberOfVariableDependencies",
    "fmi3GetVariableDependencies", "fmi3GetFMUState", "fmi3SetFMUState", "fmi3FreeFMUState",
    "fmi3SerializedFMUStateSize", "fmi3SerializeFMUState", "fmi3DeserializeFMUState",
    "fmi3GetDirectionalDerivative", "fmi3GetAdjointDerivative", "fmi3EnterConfigurationMode",
    "fmi3ExitConfigurationMode", "fmi3GetIntervalDecimal", "fmi3GetIntervalFraction", "fmi3GetShiftDecimal",
    "fmi3GetShiftFraction", "fmi3SetIntervalDecimal", "fmi3SetIntervalFraction", "fmi3SetShiftDecimal",
    "fmi3SetShiftFraction", "fmi3EvaluateDiscreteStates", "fmi3UpdateDiscreteStates",
    "fmi3EnterContinuousTimeMode", "fmi3CompletedIntegratorStep", "fmi3SetTime", "fmi3SetContinuousStates",
    "fmi3GetContinuousStateDerivatives", "fmi3GetEventIndicators", "fmi3GetContinuousStates",
    "fmi3GetNominalsOfContinuousStates", "fmi3GetNumberOfEventIndicators", "fmi3GetNumberOfContinuousStates",
    "fmi3EnterStepMode", "fmi3GetOutputDerivatives", "fmi3DoStep", "fmi3ActivateModelPartition",
};

typedef struct api {
    fmi3InstantiateCoSimulationTYPE *instantiate;
    fmi3FreeInstanceTYPE *free_instance;
    fmi3EnterConfigurationModeTYPE *enter_config;
    fmi3ExitConfigurationModeTYPE *exit_config;
    fmi3EnterInitializationModeTYPE *enter_init;
    fmi3ExitInitializationModeTYPE *exit_init;
    fmi3TerminateTYPE *terminate;
    fmi3SetFloat64TYPE *set_float64;
    fmi3SetInt32TYPE *set_int32;
    fmi3SetUInt64TYPE *set_uint64;
    fmi3SetStringTYPE *set_string;
    fmi3GetFloat64TYPE *get_float64;
    fmi3GetInt32TYPE *get_int32;
    fmi3GetUInt64TYPE *get_uint64;
    fmi3DoStepTYPE *do_step;
    fmi3GetFMUStateTYPE *get_state;
    fmi3SetFMUStateTYPE *set_state;
    fmi3FreeFMUStateTYPE *free_state;
    fmi3SerializedFMUStateSizeTYPE *state_size;
    fmi3SerializeFMUStateTYPE *serialize;
    fmi3DeserializeFMUStateTYPE *deserialize;
} api;

typedef struct host {
    int quiet; /* the fuzz silences the log */
} host;

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    const host *h = env;
    if (h != NULL && h->quiet) return;
    fprintf(stderr, "[%d %s] %s\n", (int)status, category, message);
}

static void die(const char *what) {
    fprintf(stderr, "fmi3_host: %s\n", what);
    exit(2);
}

static void *symbol(void *lib, const char *name) {
    void *f = dlsym(lib, name);
    if (f == NULL) {
        fprintf(stderr, "fmi3_host: %s is not exported\n", name);
        exit(3);
    }
    return f;
}

typedef struct output_ref {
    char kind;
    fmi3ValueReference vr;
} output_ref;

typedef struct run {
    const api *f;
    fmi3Instance c;
    output_ref outs[64];
    size_t n_outs;
    fmi3ValueReference arrays[16], size_vr;
    size_t n_arrays, n_nodes; /* row: n_outs scalars, then n_arrays x n_nodes values */
} run;

static size_t row_size(const run *r) { return r->n_outs + r->n_arrays * r->n_nodes; }

static void read_row(const run *r, double *values) {
    for (size_t k = 0; k < r->n_outs; ++k) {
        if (r->outs[k].kind == 'i') {
            fmi3Int32 x = 0;
            if (r->f->get_int32(r->c, &r->outs[k].vr, 1, &x, 1) != fmi3OK) die("fmi3GetInt32 failed");
            values[k] = (double)x;
        } else if (r->f->get_float64(r->c, &r->outs[k].vr, 1, &values[k], 1) != fmi3OK) {
            die("fmi3GetFloat64 failed");
        }
    }
    if (r->n_arrays > 0 &&
        r->f->get_float64(r->c, r->arrays, r->n_arrays, values + r->n_outs, r->n_arrays * r->n_nodes) != fmi3OK)
        die("fmi3GetFloat64 of the arrays failed");
}

/* one step: inputs, doStep, its output arguments; returns the status */
static fmi3Status step(const run *r, const fmi3ValueReference *inputs, size_t n_inputs, const double *row, double t) {
    fmi3Boolean event = fmi3True, terminate = fmi3True, early = fmi3True;
    fmi3Float64 last = -1.0;
    if (n_inputs && r->f->set_float64(r->c, inputs, n_inputs, row + 1, n_inputs) != fmi3OK)
        die("fmi3SetFloat64 failed");
    fmi3Status st = r->f->do_step(r->c, t, row[0], fmi3True, &event, &terminate, &early, &last);
    if ((st == fmi3OK || st == fmi3Warning) && (event || terminate || early || last != t + row[0]))
        die("fmi3DoStep: odd output arguments");
    /* a discard may ask to terminate (terminateSimulation: the inputs are at fault) */
    if (st == fmi3Discard && (event || early || last != t)) die("fmi3DoStep: odd outputs of a discard");
    return st;
}

/* xorshift random numbers for the fuzz (no global state: the generator is passed around) */
static unsigned long long next_random(unsigned long long *s) {
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return *s;
}

/* NaN, infinities, signed zeros, denormals, and numbers either small (<= 10) or huge (>= 1e20) */
static double odd_value(unsigned long long *s) {
    static const double specials[] = {0.0, -0.0, 1.0, -1.0, 1e300, -1e300, 1e-300, 5e-324, 1e-9, 12250.0, 0.08};
    unsigned long long r = next_random(s);
    double mantissa = (double)(r >> 11) / 9007199254740992.0;
    double small = pow(10.0, -(double)((r >> 3) % 12)), huge = pow(10.0, 20.0 + (double)((r >> 3) % 280));
    switch (r % 6) {
    case 0: return NAN;
    case 1: return (r & 64) ? INFINITY : -INFINITY;
    case 2: return specials[(r >> 8) % (sizeof specials / sizeof specials[0])];
    case 3: return -mantissa * ((r & 128) ? huge : 10.0 * small);
    default: return mantissa * ((r & 128) ? huge : 10.0 * small);
    }
}

static fmi3Instance instantiate(const api *f, const char *guid, const char *resources, host *h, const char *name) {
    fmi3Instance c = f->instantiate(name, guid, resources, fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0, h,
                                    logger, NULL);
    if (c == NULL) die("fmi3InstantiateCoSimulation returned NULL");
    return c;
}

/* the --set options, in Configuration Mode for UInt64 (structural parameters) */
static void apply_sets(const api *f, fmi3Instance c, int argc, char **argv) {
    int configured = 0;
    for (int pass = 0; pass < 2; ++pass) {
        for (int a = 4; a < argc; ++a) {
            if (strcmp(argv[a], "--set") != 0 || a + 1 >= argc) continue;
            const char *spec = argv[++a], *value = strchr(spec, '=');
            char kind = spec[0];
            fmi3ValueReference vr = (fmi3ValueReference)strtoul(spec + 2, NULL, 10);
            if (value == NULL) die("--set KIND:VR=VALUE");
            ++value;
            if ((kind == 'u') != (pass == 0)) continue;
            fmi3Status st;
            if (kind == 'u') {
                if (!configured && f->enter_config(c) != fmi3OK) die("fmi3EnterConfigurationMode failed");
                configured = 1;
                fmi3UInt64 x = strtoull(value, NULL, 10);
                st = f->set_uint64(c, &vr, 1, &x, 1);
            } else if (kind == 'r') {
                fmi3Float64 x = strtod(value, NULL);
                st = f->set_float64(c, &vr, 1, &x, 1);
            } else if (kind == 'i') {
                fmi3Int32 x = (fmi3Int32)atoi(value);
                st = f->set_int32(c, &vr, 1, &x, 1);
            } else {
                st = f->set_string(c, &vr, 1, &value, 1);
            }
            if (st != fmi3OK) die("setting a variable failed");
        }
        if (pass == 0 && configured && f->exit_config(c) != fmi3OK) die("fmi3ExitConfigurationMode failed");
    }
}

int main(int argc, char **argv) {
    if (argc < 4) die("usage: fmi3_host UNZIPPED_DIR MODEL_IDENTIFIER INSTANTIATION_TOKEN [options]");
    const char *dir = argv[1], *id = argv[2], *guid = argv[3];
    char path[4096], resources[4200];
    snprintf(path, sizeof path, "%s/binaries/%s/%s.so", dir, PLATFORM_TUPLE, id);
    void *lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (lib == NULL) {
        fprintf(stderr, "fmi3_host: dlopen %s: %s\n", path, dlerror());
        return 4;
    }
    for (int a = 4; a < argc; ++a) {
        if (strcmp(argv[a], "--symbols") == 0) {
            for (size_t k = 0; k < sizeof ALL_FUNCTIONS / sizeof ALL_FUNCTIONS[0]; ++k) symbol(lib, ALL_FUNCTIONS[k]);
            printf("%zu functions exported\n", sizeof ALL_FUNCTIONS / sizeof ALL_FUNCTIONS[0]);
            dlclose(lib);
            return 0;
        }
    }
    api f;
    *(void **)&f.instantiate = symbol(lib, "fmi3InstantiateCoSimulation");
    *(void **)&f.free_instance = symbol(lib, "fmi3FreeInstance");
    *(void **)&f.enter_config = symbol(lib, "fmi3EnterConfigurationMode");
    *(void **)&f.exit_config = symbol(lib, "fmi3ExitConfigurationMode");
    *(void **)&f.enter_init = symbol(lib, "fmi3EnterInitializationMode");
    *(void **)&f.exit_init = symbol(lib, "fmi3ExitInitializationMode");
    *(void **)&f.terminate = symbol(lib, "fmi3Terminate");
    *(void **)&f.set_float64 = symbol(lib, "fmi3SetFloat64");
    *(void **)&f.set_int32 = symbol(lib, "fmi3SetInt32");
    *(void **)&f.set_uint64 = symbol(lib, "fmi3SetUInt64");
    *(void **)&f.set_string = symbol(lib, "fmi3SetString");
    *(void **)&f.get_float64 = symbol(lib, "fmi3GetFloat64");
    *(void **)&f.get_int32 = symbol(lib, "fmi3GetInt32");
    *(void **)&f.get_uint64 = symbol(lib, "fmi3GetUInt64");
    *(void **)&f.do_step = symbol(lib, "fmi3DoStep");
    *(void **)&f.get_state = symbol(lib, "fmi3GetFMUState");
    *(void **)&f.set_state = symbol(lib, "fmi3SetFMUState");
    *(void **)&f.free_state = symbol(lib, "fmi3FreeFMUState");
    *(void **)&f.state_size = symbol(lib, "fmi3SerializedFMUStateSize");
    *(void **)&f.serialize = symbol(lib, "fmi3SerializeFMUState");
    *(void **)&f.deserialize = symbol(lib, "fmi3DeserializeFMUState");

    host h = {0};
    snprintf(resources, sizeof resources, "%s/resources/", dir);
    run r;
    memset(&r, 0, sizeof r);
    r.f = &f;
    r.c = instantiate(&f, guid, resources, &h, "host");
    apply_sets(&f, r.c, argc, argv);
    if (f.enter_init(r.c, fmi3False, 0.0, 0.0, fmi3False, 0.0) != fmi3OK) die("fmi3EnterInitializationMode failed");

    fmi3ValueReference inputs[16];
    size_t n_inputs = 0, n_steps = 0, cap = 0;
    double *steps = NULL; /* n_steps rows of 17 values: dt, inputs */
    long replay = -1, fuzz = 0;
    unsigned long long seed = 1;
    for (int a = 4; a < argc; ++a) {
        if (strcmp(argv[a], "--set") == 0) {
            ++a;
        } else if (strcmp(argv[a], "--inputs") == 0 && a + 1 < argc) {
            for (char *tok = strtok(argv[++a], ","); tok && n_inputs < 16; tok = strtok(NULL, ","))
                inputs[n_inputs++] = (fmi3ValueReference)strtoul(tok, NULL, 10);
        } else if (strcmp(argv[a], "--outputs") == 0 && a + 1 < argc) {
            for (char *tok = strtok(argv[++a], ","); tok && r.n_outs < 64; tok = strtok(NULL, ",")) {
                r.outs[r.n_outs].kind = tok[0];
                r.outs[r.n_outs++].vr = (fmi3ValueReference)strtoul(tok + 2, NULL, 10);
            }
        } else if (strcmp(argv[a], "--arrays") == 0 && a + 1 < argc) {
            char *spec = argv[++a], *colon = strchr(spec, ':');
            if (colon == NULL) die("--arrays SIZE_VR:VR,...");
            r.size_vr = (fmi3ValueReference)strtoul(spec, NULL, 10);
            for (char *tok = strtok(colon + 1, ","); tok && r.n_arrays < 16; tok = strtok(NULL, ","))
                r.arrays[r.n_arrays++] = (fmi3ValueReference)strtoul(tok, NULL, 10);
        } else if (strcmp(argv[a], "--steps") == 0 && a + 1 < argc) {
            FILE *in = fopen(argv[++a], "r");
            char line[4096];
            if (in == NULL) die("cannot open the steps file");
            while (fgets(line, sizeof line, in)) {
                if (strspn(line, " \t\r\n") == strlen(line)) continue;
                if (n_steps + 1 > cap) {
                    cap = cap ? 2 * cap : 1024;
                    steps = realloc(steps, cap * 17 * sizeof(double));
                    if (steps == NULL) die("out of memory");
                }
                char *p = line;
                for (size_t k = 0; k < 1 + n_inputs; ++k) {
                    steps[n_steps * 17 + k] = strtod(p, &p);
                    if (*p == ',') ++p;
                }
                ++n_steps;
            }
            fclose(in);
        } else if (strcmp(argv[a], "--replay") == 0 && a + 1 < argc) {
            replay = atol(argv[++a]);
        } else if (strcmp(argv[a], "--fuzz") == 0 && a + 2 < argc) {
            fuzz = atol(argv[++a]);
            seed = strtoull(argv[++a], NULL, 10) | 1ULL;
        }
    }
    if (f.exit_init(r.c) != fmi3OK) die("fmi3ExitInitializationMode failed");
    if (r.n_arrays > 0) {
        fmi3UInt64 n = 0;
        if (f.get_uint64(r.c, &r.size_vr, 1, &n, 1) != fmi3OK || n == 0 || n > 10000000) die("fmi3GetUInt64 failed");
        r.n_nodes = (size_t)n;
    }

    size_t width = row_size(&r);
    double t = 0.0, *first = calloc((n_steps + 1) * (width + 1), sizeof(double));
    fmi3Byte *saved = NULL;
    size_t saved_size = 0;
    double saved_time = 0.0;
    if (first == NULL) die("out of memory");
    for (size_t s = 0; s < n_steps; ++s) {
        const double *row = &steps[s * 17];
        fmi3Status st = step(&r, inputs, n_inputs, row, t);
        if (st != fmi3OK && st != fmi3Warning) { /* a warning: accepted (an output left the range it is built for) */
            fprintf(stderr, "fmi3_host: fmi3DoStep at t = %.17g returned %d\n", t, (int)st);
            return 5;
        }
        t += row[0];
        double *out = &first[s * (width + 1)];
        out[0] = t;
        read_row(&r, out + 1);
        printf("%.17g", t);
        for (size_t k = 0; k < width; ++k) printf(",%.17g", out[1 + k]);
        printf("\n");
        if ((long)s + 1 == replay) { /* the state after this step, serialized */
            fmi3FMUState state = NULL;
            if (f.get_state(r.c, &state) != fmi3OK || f.state_size(r.c, state, &saved_size) != fmi3OK)
                die("fmi3GetFMUState failed");
            saved = malloc(saved_size);
            if (saved == NULL || f.serialize(r.c, state, saved, saved_size) != fmi3OK)
                die("fmi3SerializeFMUState failed");
            f.free_state(r.c, &state);
            saved_time = t;
        }
    }
    if (saved != NULL) { /* a second instance from the serialized state replays the rest bit-identically */
        run second = r;
        fmi3FMUState state = NULL;
        second.c = instantiate(&f, guid, resources, &h, "replay");
        apply_sets(&f, second.c, argc, argv);
        if (f.enter_init(second.c, fmi3False, 0.0, 0.0, fmi3False, 0.0) != fmi3OK ||
            f.exit_init(second.c) != fmi3OK)
            die("initializing the replay instance failed");
        if (f.deserialize(second.c, saved, saved_size, &state) != fmi3OK || f.set_state(second.c, state) != fmi3OK)
            die("restoring the serialized state failed");
        f.free_state(second.c, &state);
        double t2 = saved_time, *again = malloc((width + 1) * sizeof(double));
        if (again == NULL) die("out of memory");
        for (size_t s = (size_t)replay; s < n_steps; ++s) {
            const double *row = &steps[s * 17];
            fmi3Status st2 = step(&second, inputs, n_inputs, row, t2);
            if (st2 != fmi3OK && st2 != fmi3Warning) die("fmi3DoStep failed in the replay");
            t2 += row[0];
            read_row(&second, again);
            if (memcmp(again, &first[s * (width + 1) + 1], width * sizeof(double)) != 0) {
                fprintf(stderr, "fmi3_host: the replay differs at step %zu\n", s);
                return 6;
            }
        }
        free(again);
        free(saved);
        if (f.terminate(second.c) != fmi3OK) die("fmi3Terminate failed (replay)");
        f.free_instance(second.c);
        fprintf(stderr, "fmi3_host: replay from step %ld bit-identical\n", replay);
    }
    if (fuzz > 0) { /* random abuse: no crash, allowed statuses, a discarded step changes nothing, and an instance
                     * failed by a step no size can complete is usable again from a state taken before */
        long discards = 0, oks = 0, errors = 0;
        double fuzz_t0 = t;
        fmi3FMUState fuzz_start = NULL;
        if (f.get_state(r.c, &fuzz_start) != fmi3OK) die("fuzz: fmi3GetFMUState failed");
        double *before = malloc((width + 1) * sizeof(double)), *after = malloc((width + 1) * sizeof(double));
        if (before == NULL || after == NULL) die("out of memory");
        h.quiet = 1;
        for (long k = 0; k < fuzz; ++k) {
            unsigned long long x = next_random(&seed);
            fmi3ValueReference vr = (fmi3ValueReference)(next_random(&seed) % 64);
            fmi3Status st = fmi3OK;
            if (x % 5 == 0 && n_inputs) {
                double values[16];
                for (size_t j = 0; j < n_inputs; ++j) values[j] = odd_value(&seed);
                if (f.set_float64(r.c, inputs, n_inputs, values, n_inputs) != fmi3OK)
                    die("fuzz: fmi3SetFloat64 of an input failed");
            } else if (x % 5 == 1) {
                double value = odd_value(&seed);
                st = f.set_float64(r.c, &vr, 1, &value, 1);
            } else if (x % 5 == 2) {
                fmi3UInt64 n = next_random(&seed);
                fmi3Int32 i = (fmi3Int32)(next_random(&seed) & 0x7fffffff);
                double sink[4];
                st = (x & 8) ? f.set_uint64(r.c, &vr, 1, &n, 1) : f.set_int32(r.c, &vr, 1, &i, 1);
                if (st == fmi3OK) die("fuzz: a variable was set after initialization");
                st = f.get_float64(r.c, &vr, 1, sink, (size_t)(x >> 5) % 4); /* often the wrong nValues */
            } else {
                fmi3Boolean event, terminate, early;
                fmi3Float64 last;
                double dt = (x & 8) ? odd_value(&seed) : 1e-3 * (double)(x % 7);
                if (dt > 1e-2 && dt < 1e20) dt = 1e-2; /* a legal but long step: minutes of computation */
                read_row(&r, before);
                st = f.do_step(r.c, t, dt, fmi3True, &event, &terminate, &early, &last);
                read_row(&r, after);
                if (st == fmi3OK || st == fmi3Warning) {
                    ++oks;
                    t += dt;
                } else if (st == fmi3Discard) {
                    ++discards;
                    if (memcmp(before, after, width * sizeof(double)) != 0)
                        die("fuzz: a discarded step changed the outputs");
                    if (last != t) die("fuzz: lastSuccessfulTime of a discarded step is not the current time");
                } else if (st == fmi3Error) {
                    ++errors;
                    if (memcmp(before, after, width * sizeof(double)) != 0)
                        die("fuzz: a failed step changed the outputs");
                    if (!terminate) die("fuzz: a failed step does not ask to end the simulation");
                    if (f.set_state(r.c, fuzz_start) != fmi3OK) die("fuzz: fmi3SetFMUState after fmi3Error failed");
                    t = fuzz_t0;
                } else {
                    fprintf(stderr, "fmi3_host: fuzz: fmi3DoStep returned %d\n", (int)st);
                    return 7;
                }
                continue;
            }
            if (st != fmi3OK && st != fmi3Error) die("fuzz: odd status of a get or set");
        }
        f.free_state(r.c, &fuzz_start);
        free(before);
        free(after);
        fprintf(stderr, "fmi3_host: fuzz: %ld calls, %ld steps taken, %ld discarded, %ld failed and restored\n", fuzz,
                oks, discards, errors);
    }
    if (f.terminate(r.c) != fmi3OK) die("fmi3Terminate failed");
    f.free_instance(r.c);
    free(first);
    free(steps);
    /* no Python anywhere in this process */
    FILE *maps = fopen("/proc/self/maps", "r");
    char line[4096];
    while (maps && fgets(line, sizeof line, maps)) {
        if (strstr(line, "libpython") != NULL) {
            fprintf(stderr, "fmi3_host: a Python library is loaded: %s", line);
            return 8;
        }
    }
    if (maps) fclose(maps);
    dlclose(lib);
    return 0;
}
