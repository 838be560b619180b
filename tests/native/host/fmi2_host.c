/* A small FMI 2.0 co-simulation host in C (tests only): loads an FMU's shared library with dlopen, in a process
 * with no Python, and drives it through the fmi2 functions, as a C/C++ importer (Simulink, OMSimulator,
 * libcosim...) does.
 *
 *   fmi2_host UNZIPPED_DIR MODEL_IDENTIFIER GUID [options]
 *     --set KIND:VR=VALUE      set a parameter before initialization (KIND r, i or s), repeatable
 *     --inputs VR,VR,...       value references of the inputs given in the steps file
 *     --outputs KIND:VR,...    the outputs to print after every step (r or i per entry: r:35,i:43)
 *     --steps FILE             one step per line: dt,input1,input2,...
 *     --replay K               after step K: get and serialize the state, finish the run, deserialize and set
 *                              it, run the rest again and require bit-identical outputs
 *     --fuzz N SEED            N random calls with NaN, inf, negative and huge values (after the steps): no
 *                              crash, only allowed statuses, a discarded step leaves the outputs unchanged
 *     --symbols                check that every fmi2 function of the standard is exported, and stop
 *     --no-print               do not print the outputs (benchmarks: the stepping loop's time alone)
 * Prints "t,outputs..." per step (%.17g) to stdout, FMU log messages and "N steps in S s" (the wall time of
 * the stepping loop, set + doStep + get per step) to stderr. Exit 0 on success.
 */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"

static const char *const ALL_FUNCTIONS[] = {
    "fmi2GetTypesPlatform", "fmi2GetVersion", "fmi2SetDebugLogging", "fmi2Instantiate", "fmi2FreeInstance",
    "fmi2SetupExperiment", "fmi2EnterInitializationMode", "fmi2ExitInitializationMode", "fmi2Terminate",
    "fmi2Reset", "fmi2GetReal", "fmi2GetInteger", "fmi2GetBoolean", "fmi2GetString", "fmi2SetReal",
    "fmi2SetInteger", "fmi2SetBoolean", "fmi2SetString", "fmi2GetFMUstate", "fmi2SetFMUstate",
    "fmi2FreeFMUstate", "fmi2SerializedFMUstateSize", "fmi2SerializeFMUstate", "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative", "fmi2EnterEventMode", "fmi2NewDiscreteStates", "fmi2EnterContinuousTimeMode",
    "fmi2CompletedIntegratorStep", "fmi2SetTime", "fmi2SetContinuousStates", "fmi2GetDerivatives",
    "fmi2GetEventIndicators", "fmi2GetContinuousStates", "fmi2GetNominalsOfContinuousStates",
    "fmi2SetRealInputDerivatives", "fmi2GetRealOutputDerivatives", "fmi2DoStep", "fmi2CancelStep",
    "fmi2GetStatus", "fmi2GetRealStatus", "fmi2GetIntegerStatus", "fmi2GetBooleanStatus", "fmi2GetStringStatus",
};

typedef struct api {
    fmi2InstantiateTYPE *instantiate;
    fmi2FreeInstanceTYPE *free_instance;
    fmi2SetupExperimentTYPE *setup;
    fmi2EnterInitializationModeTYPE *enter_init;
    fmi2ExitInitializationModeTYPE *exit_init;
    fmi2TerminateTYPE *terminate;
    fmi2SetRealTYPE *set_real;
    fmi2SetIntegerTYPE *set_integer;
    fmi2SetStringTYPE *set_string;
    fmi2GetRealTYPE *get_real;
    fmi2GetIntegerTYPE *get_integer;
    fmi2DoStepTYPE *do_step;
    fmi2GetFMUstateTYPE *get_state;
    fmi2SetFMUstateTYPE *set_state;
    fmi2FreeFMUstateTYPE *free_state;
    fmi2SerializedFMUstateSizeTYPE *state_size;
    fmi2SerializeFMUstateTYPE *serialize;
    fmi2DeSerializeFMUstateTYPE *deserialize;
} api;

static int quiet_logs = 0;

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    va_list ap;
    (void)env;
    if (quiet_logs) return;
    fprintf(stderr, "[%s %d %s] ", name, (int)status, category);
    va_start(ap, message);
    vfprintf(stderr, message, ap);
    va_end(ap);
    fputc('\n', stderr);
}

static void die(const char *what) {
    fprintf(stderr, "fmi2_host: %s\n", what);
    exit(2);
}

static void *symbol(void *lib, const char *name) {
    void *f = dlsym(lib, name);
    if (f == NULL) {
        fprintf(stderr, "fmi2_host: %s is not exported\n", name);
        exit(3);
    }
    return f;
}

typedef struct output_ref {
    char kind;
    fmi2ValueReference vr;
} output_ref;

static size_t read_outputs(const api *f, fmi2Component c, const output_ref *outs, size_t n, double *values) {
    for (size_t k = 0; k < n; ++k) {
        if (outs[k].kind == 'i') {
            fmi2Integer x = 0;
            if (f->get_integer(c, &outs[k].vr, 1, &x) != fmi2OK) die("fmi2GetInteger failed");
            values[k] = (double)x;
        } else {
            if (f->get_real(c, &outs[k].vr, 1, &values[k]) != fmi2OK) die("fmi2GetReal failed");
        }
    }
    return n;
}

/* xorshift random numbers for the fuzz (no global state: the generator is passed around) */
static unsigned long long next_random(unsigned long long *s) {
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return *s;
}

/* NaN, infinities, signed zeros, denormals, and numbers either small (<= 10) or huge (>= 1e20): a huge input is
 * refused at once, while a velocity of 1e5 m/s would be a legal step of hours of computation */
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

int main(int argc, char **argv) {
    if (argc < 4) die("usage: fmi2_host UNZIPPED_DIR MODEL_IDENTIFIER GUID [options]");
    const char *dir = argv[1], *id = argv[2], *guid = argv[3];
    char path[4096], uri[4200];
    snprintf(path, sizeof path, "%s/binaries/linux64/%s.so", dir, id);
    void *lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (lib == NULL) {
        fprintf(stderr, "fmi2_host: dlopen %s: %s\n", path, dlerror());
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
    *(void **)&f.instantiate = symbol(lib, "fmi2Instantiate");
    *(void **)&f.free_instance = symbol(lib, "fmi2FreeInstance");
    *(void **)&f.setup = symbol(lib, "fmi2SetupExperiment");
    *(void **)&f.enter_init = symbol(lib, "fmi2EnterInitializationMode");
    *(void **)&f.exit_init = symbol(lib, "fmi2ExitInitializationMode");
    *(void **)&f.terminate = symbol(lib, "fmi2Terminate");
    *(void **)&f.set_real = symbol(lib, "fmi2SetReal");
    *(void **)&f.set_integer = symbol(lib, "fmi2SetInteger");
    *(void **)&f.set_string = symbol(lib, "fmi2SetString");
    *(void **)&f.get_real = symbol(lib, "fmi2GetReal");
    *(void **)&f.get_integer = symbol(lib, "fmi2GetInteger");
    *(void **)&f.do_step = symbol(lib, "fmi2DoStep");
    *(void **)&f.get_state = symbol(lib, "fmi2GetFMUstate");
    *(void **)&f.set_state = symbol(lib, "fmi2SetFMUstate");
    *(void **)&f.free_state = symbol(lib, "fmi2FreeFMUstate");
    *(void **)&f.state_size = symbol(lib, "fmi2SerializedFMUstateSize");
    *(void **)&f.serialize = symbol(lib, "fmi2SerializeFMUstate");
    *(void **)&f.deserialize = symbol(lib, "fmi2DeSerializeFMUstate");

    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    snprintf(uri, sizeof uri, "file://%s/resources", dir);
    fmi2Component c = f.instantiate("host", fmi2CoSimulation, guid, uri, &cb, fmi2False, fmi2False);
    if (c == NULL) die("fmi2Instantiate returned NULL");
    if (f.setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK) die("fmi2SetupExperiment failed");
    if (f.enter_init(c) != fmi2OK) die("fmi2EnterInitializationMode failed");

    fmi2ValueReference inputs[16];
    size_t n_inputs = 0, n_outputs = 0, n_steps = 0, cap = 0;
    output_ref outputs[64];
    double *steps = NULL; /* n_steps rows of 1 + n_inputs values */
    long replay = -1, fuzz = 0;
    int print_outputs = 1;
    unsigned long long seed = 1;
    for (int a = 4; a < argc; ++a) {
        if (strcmp(argv[a], "--set") == 0 && a + 1 < argc) {
            char kind = argv[++a][0];
            fmi2ValueReference vr = (fmi2ValueReference)strtoul(argv[a] + 2, NULL, 10);
            const char *value = strchr(argv[a], '=');
            if (value == NULL) die("--set KIND:VR=VALUE");
            ++value;
            fmi2Status st = kind == 'r'   ? f.set_real(c, &vr, 1, (double[]){strtod(value, NULL)})
                            : kind == 'i' ? f.set_integer(c, &vr, 1, (int[]){atoi(value)})
                                          : f.set_string(c, &vr, 1, &value);
            if (st != fmi2OK) die("setting a parameter failed");
        } else if (strcmp(argv[a], "--inputs") == 0 && a + 1 < argc) {
            for (char *tok = strtok(argv[++a], ","); tok && n_inputs < 16; tok = strtok(NULL, ","))
                inputs[n_inputs++] = (fmi2ValueReference)strtoul(tok, NULL, 10);
        } else if (strcmp(argv[a], "--outputs") == 0 && a + 1 < argc) {
            for (char *tok = strtok(argv[++a], ","); tok && n_outputs < 64; tok = strtok(NULL, ",")) {
                outputs[n_outputs].kind = tok[0];
                outputs[n_outputs++].vr = (fmi2ValueReference)strtoul(tok + 2, NULL, 10);
            }
        } else if (strcmp(argv[a], "--steps") == 0 && a + 1 < argc) {
            FILE *in = fopen(argv[++a], "r");
            char line[4096];
            if (in == NULL) die("cannot open the steps file");
            while (fgets(line, sizeof line, in)) {
                if (strspn(line, " \t\r\n") == strlen(line)) continue; /* blank line */
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
        } else if (strcmp(argv[a], "--no-print") == 0) {
            print_outputs = 0;
        } else if (strcmp(argv[a], "--replay") == 0 && a + 1 < argc) {
            replay = atol(argv[++a]);
        } else if (strcmp(argv[a], "--fuzz") == 0 && a + 2 < argc) {
            fuzz = atol(argv[++a]);
            seed = strtoull(argv[++a], NULL, 10) | 1ULL;
        }
    }
    if (f.exit_init(c) != fmi2OK) die("fmi2ExitInitializationMode failed");

    double t = 0.0, *first = calloc((n_steps + 1) * (n_outputs + 1), sizeof(double));
    fmi2Byte *saved = NULL;
    size_t saved_size = 0;
    double saved_time = 0.0;
    if (first == NULL) die("out of memory");
    struct timespec t_start, t_end;
    clock_gettime(CLOCK_MONOTONIC, &t_start);
    for (size_t s = 0; s < n_steps; ++s) {
        const double *row = &steps[s * 17];
        if (n_inputs && f.set_real(c, inputs, n_inputs, row + 1) != fmi2OK) die("fmi2SetReal failed");
        fmi2Status st = f.do_step(c, t, row[0], fmi2True);
        if (st != fmi2OK && st != fmi2Warning) { /* a warning: accepted (an output left the range it is built for) */
            fprintf(stderr, "fmi2_host: fmi2DoStep at t = %.17g returned %d\n", t, (int)st);
            return 5;
        }
        t += row[0];
        read_outputs(&f, c, outputs, n_outputs, &first[s * (n_outputs + 1) + 1]);
        first[s * (n_outputs + 1)] = t;
        if (print_outputs) {
            printf("%.17g", t);
            for (size_t k = 0; k < n_outputs; ++k) printf(",%.17g", first[s * (n_outputs + 1) + 1 + k]);
            printf("\n");
        }
        if ((long)s + 1 == replay) { /* the state after this step, serialized */
            fmi2FMUstate state = NULL;
            if (f.get_state(c, &state) != fmi2OK || f.state_size(c, state, &saved_size) != fmi2OK)
                die("fmi2GetFMUstate failed");
            saved = malloc(saved_size);
            if (saved == NULL || f.serialize(c, state, saved, saved_size) != fmi2OK) die("fmi2SerializeFMUstate failed");
            f.free_state(c, &state);
            saved_time = t;
        }
    }
    clock_gettime(CLOCK_MONOTONIC, &t_end);
    fprintf(stderr, "fmi2_host: %zu steps in %.9f s\n", n_steps,
            (double)(t_end.tv_sec - t_start.tv_sec) + 1e-9 * (double)(t_end.tv_nsec - t_start.tv_nsec));
    if (saved != NULL) { /* restore the serialized state and replay the rest: bit-identical */
        fmi2FMUstate state = NULL;
        if (f.deserialize(c, saved, saved_size, &state) != fmi2OK || f.set_state(c, state) != fmi2OK)
            die("restoring the serialized state failed");
        f.free_state(c, &state);
        t = saved_time;
        double *again = malloc((n_outputs + 1) * sizeof(double));
        for (size_t s = (size_t)replay; s < n_steps; ++s) {
            const double *row = &steps[s * 17];
            if (n_inputs) f.set_real(c, inputs, n_inputs, row + 1);
            fmi2Status st = f.do_step(c, t, row[0], fmi2True);
            if (st != fmi2OK && st != fmi2Warning) die("fmi2DoStep failed in the replay");
            t += row[0];
            read_outputs(&f, c, outputs, n_outputs, again);
            if (memcmp(again, &first[s * (n_outputs + 1) + 1], n_outputs * sizeof(double)) != 0) {
                fprintf(stderr, "fmi2_host: the replay differs at step %zu\n", s);
                return 6;
            }
        }
        free(again);
        free(saved);
        fprintf(stderr, "fmi2_host: replay from step %ld bit-identical\n", replay);
    }
    if (fuzz > 0) { /* random abuse: no crash, allowed statuses, a discarded step changes nothing, and an instance
                     * failed by a step no size can complete is usable again from a state taken before */
        long discards = 0, oks = 0, errors = 0;
        double before[64], after[64], fuzz_t0 = t;
        fmi2FMUstate fuzz_start = NULL;
        if (f.get_state(c, &fuzz_start) != fmi2OK) die("fuzz: fmi2GetFMUstate failed");
        quiet_logs = 1;
        for (long k = 0; k < fuzz; ++k) {
            unsigned long long r = next_random(&seed);
            if (r % 3 == 0 && n_inputs) {
                double values[16];
                for (size_t j = 0; j < n_inputs; ++j) values[j] = odd_value(&seed);
                if (f.set_real(c, inputs, n_inputs, values) != fmi2OK) die("fuzz: fmi2SetReal of an input failed");
            } else if (r % 3 == 1) {
                fmi2ValueReference vr = (fmi2ValueReference)(next_random(&seed) % 64);
                double x = odd_value(&seed);
                fmi2Status st = f.set_real(c, &vr, 1, &x);
                if (st != fmi2OK && st != fmi2Warning && st != fmi2Error) die("fuzz: odd status of fmi2SetReal");
            } else {
                double dt = (r & 8) ? odd_value(&seed) : 1e-3 * (double)(r % 7);
                if (dt > 1e-2 && dt < 1e20) dt = 1e-2; /* a legal but long step: minutes of computation */
                read_outputs(&f, c, outputs, n_outputs, before);
                fmi2Status st = f.do_step(c, t, dt, fmi2True);
                read_outputs(&f, c, outputs, n_outputs, after);
                if (st == fmi2OK || st == fmi2Warning) {
                    ++oks;
                    t += dt;
                } else if (st == fmi2Discard) {
                    ++discards;
                    if (memcmp(before, after, n_outputs * sizeof(double)) != 0) die("fuzz: a discarded step changed the outputs");
                } else if (st == fmi2Error) {
                    ++errors;
                    if (memcmp(before, after, n_outputs * sizeof(double)) != 0) die("fuzz: a failed step changed the outputs");
                    if (f.set_state(c, fuzz_start) != fmi2OK) die("fuzz: fmi2SetFMUstate after fmi2Error failed");
                    t = fuzz_t0;
                } else {
                    fprintf(stderr, "fmi2_host: fuzz: fmi2DoStep returned %d\n", (int)st);
                    return 7;
                }
            }
        }
        f.free_state(c, &fuzz_start);
        fprintf(stderr, "fmi2_host: fuzz: %ld calls, %ld steps taken, %ld discarded, %ld failed and restored\n", fuzz,
                oks, discards, errors);
    }
    if (f.terminate(c) != fmi2OK) die("fmi2Terminate failed");
    f.free_instance(c);
    free(first);
    free(steps);
    /* no Python anywhere in this process */
    FILE *maps = fopen("/proc/self/maps", "r");
    char line[4096];
    while (maps && fgets(line, sizeof line, maps)) {
        if (strstr(line, "libpython") != NULL) {
            fprintf(stderr, "fmi2_host: a Python library is loaded: %s", line);
            return 8;
        }
    }
    if (maps) fclose(maps);
    dlclose(lib);
    return 0;
}
