/* What the processor running the library can execute, and the variant of the code that has one for it (the passes
 * over the strip's bar a step makes, tc_step_kernels.h) chosen for it. The native code's only departures from ISO C11
 * are here and in tc_step_kernels_avx.c: GNU inline assembly (CPUID, XGETBV) and clang's target attribute, each behind
 * a check of the compiler and the processor, so that any other C11 compiler builds the portable baseline alone. */
#ifndef TC_CPU_H
#define TC_CPU_H

#include "tc_common.h"
#include "tc_step_kernels.h"

/* Whether the processor executes AVX instructions and the operating system keeps their registers (CPUID leaf 1: AVX
 * and OSXSAVE; XGETBV: the XMM and YMM state enabled): 1 or 0, and 0 wherever this library is not compiled by clang
 * or GCC for x86-64. The answer is read from the processor at each call, into no global. */
int tc_cpu_runs_avx(void);

/* The step kernels for the processor running the library: the AVX variant where it is built (tc_step_kernels_avx.h) and
 * tc_cpu_runs_avx, else the baseline; always the baseline in a build with -DTC_NO_AVX (what the tests compare with). */
const tc_step_kernels *tc_step_kernels_for_cpu(void);

/* whether tc_step_kernels_for_cpu chooses the AVX variant here (1) or the baseline (0) */
TC_API int tc_step_kernels_avx_chosen(void);

#endif
