/* A minimal FMI 2.0 co-simulation host for Windows (tests only; run under wine on Linux): loads an FMU's win64 DLL with
 * LoadLibrary and drives it through the fmi2 functions of the standard's headers, as a Windows importer does.
 *
 *   fmi2_host_windows DLL GUID RESOURCE_URI STEPS DT VR_IN1=VALUE VR_IN2=VALUE VR_OUT [VR_OUT ...]
 *
 * Instantiates a co-simulation slave, initializes it at t = 0, then STEPS steps of DT with the inputs set before each,
 * and prints the real outputs after each step, "%.17g" comma-separated, one line per step. Exit 0 on success.
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <windows.h>

#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env;
    (void)category;
    va_list ap;
    va_start(ap, message);
    fprintf(stderr, "%s [%d]: ", name, (int)status);
    vfprintf(stderr, message, ap);
    fprintf(stderr, "\n");
    va_end(ap);
}

static FARPROC need(HMODULE lib, const char *name) {
    FARPROC f = GetProcAddress(lib, name);
    if (f == NULL) {
        fprintf(stderr, "fmi2_host_windows: %s is not exported\n", name);
        exit(1);
    }
    return f;
}

#define FUNCTION(type, name) type *name = (type *)(void *)need(lib, #name)

int main(int argc, char **argv) {
    if (argc < 9) {
        fprintf(stderr, "usage: fmi2_host_windows DLL GUID RESOURCE_URI STEPS DT VR=IN1 VR=IN2 VR_OUT...\n");
        return 2;
    }
    HMODULE lib = LoadLibraryA(argv[1]);
    if (lib == NULL) {
        fprintf(stderr, "fmi2_host_windows: LoadLibrary %s failed (%lu)\n", argv[1], (unsigned long)GetLastError());
        return 1;
    }
    FUNCTION(fmi2InstantiateTYPE, fmi2Instantiate);
    FUNCTION(fmi2SetupExperimentTYPE, fmi2SetupExperiment);
    FUNCTION(fmi2EnterInitializationModeTYPE, fmi2EnterInitializationMode);
    FUNCTION(fmi2ExitInitializationModeTYPE, fmi2ExitInitializationMode);
    FUNCTION(fmi2SetRealTYPE, fmi2SetReal);
    FUNCTION(fmi2GetRealTYPE, fmi2GetReal);
    FUNCTION(fmi2DoStepTYPE, fmi2DoStep);
    FUNCTION(fmi2TerminateTYPE, fmi2Terminate);
    FUNCTION(fmi2FreeInstanceTYPE, fmi2FreeInstance);
    const long steps = strtol(argv[4], NULL, 10);
    const double dt = strtod(argv[5], NULL);
    fmi2ValueReference in[2], out[16];
    double u[2], y[16];
    for (int k = 0; k < 2; ++k) {
        char *end;
        in[k] = (fmi2ValueReference)strtoul(argv[6 + k], &end, 10);
        u[k] = strtod(end + 1, NULL);
    }
    const size_t n_out = (size_t)(argc - 8) < 16 ? (size_t)(argc - 8) : 16;
    for (size_t k = 0; k < n_out; ++k) out[k] = (fmi2ValueReference)strtoul(argv[8 + k], NULL, 10);
    const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("windows", fmi2CoSimulation, argv[2], argv[3], &callbacks, fmi2False, fmi2False);
    if (c == NULL || fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK ||
        fmi2EnterInitializationMode(c) != fmi2OK || fmi2ExitInitializationMode(c) != fmi2OK) {
        fprintf(stderr, "fmi2_host_windows: instantiation or initialization failed\n");
        return 1;
    }
    for (long s = 0; s < steps; ++s) {
        if (fmi2SetReal(c, in, 2, u) != fmi2OK || fmi2DoStep(c, (double)s * dt, dt, fmi2True) != fmi2OK ||
            fmi2GetReal(c, out, n_out, y) != fmi2OK) {
            fprintf(stderr, "fmi2_host_windows: step %ld failed\n", s);
            return 1;
        }
        for (size_t k = 0; k < n_out; ++k) printf(k ? ",%.17g" : "%.17g", y[k]);
        printf("\n");
    }
    fmi2Terminate(c);
    fmi2FreeInstance(c);
    return 0;
}
