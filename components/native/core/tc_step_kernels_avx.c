/* The passes over the bar's nodes of a step and its implicit step (tc_step_kernels.c, tc_galpha.c) compiled a second
 * time, for x86-64 processors with AVX: the same C, whose loops over the nodes the compiler then runs in four-double
 * registers instead of the two-double ones of SSE2 (what every x86-64 processor has, and so the library's baseline).
 * tc_step_kernels_for_cpu chooses them where the processor and the operating system run AVX (tc_cpu.h).
 *
 * The numbers are the baseline's bit for bit: AVX widens the registers, not the arithmetic (each operation is the same
 * IEEE double operation, rounded alike); fused multiply-add is another extension and is not enabled, and the compiler
 * does not reorder floating-point operations (no -ffast-math). tests/components/test_native_library.py holds the two
 * variants to the same outputs and states. Built by clang for x86-64 only (TC_STEP_KERNELS_AVX); elsewhere this file
 * declares nothing of use. */
#include "tc_step_kernels_avx.h"

#if TC_STEP_KERNELS_AVX
#pragma clang attribute push(__attribute__((target("avx"))), apply_to = function)
#define TC_VARIANT(name) name##_avx
#define TC_VARIANT_AVX 1
#define TC_STEP_KERNELS_TABLE tc_step_kernels_avx
#include "tc_galpha.c"
#include "tc_step_kernels.c"
#pragma clang attribute pop
#else
typedef int tc_step_kernels_avx_not_built; /* ISO C: a translation unit declares something */
#endif
