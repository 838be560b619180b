/* The passes over the bar's nodes of a step and its implicit step compiled for x86-64 processors with AVX
 * (tc_step_kernels_avx.c), where clang compiles for x86-64 (its target attribute and pragma); elsewhere only the
 * baseline is built. */
#ifndef TC_STEP_KERNELS_AVX_H
#define TC_STEP_KERNELS_AVX_H

#include "tc_step_kernels.h"

#if defined(__x86_64__) && defined(__clang__)
#define TC_STEP_KERNELS_AVX 1
extern const tc_step_kernels tc_step_kernels_avx;
#else
#define TC_STEP_KERNELS_AVX 0
#endif

#endif
