/* The passes over every node of the bar that a step of the strip-draw model makes, and its implicit step (tc_galpha.c),
 * for the processor running the library: compiled for the x86-64 baseline, SSE2 (two doubles per register), and
 * again for processors with AVX (four: tc_step_kernels_avx.c, the same C and the same numbers bit for bit). */
#ifndef TC_STEP_KERNELS_H
#define TC_STEP_KERNELS_H

#include <stddef.h>

#include "tc_common.h"
#include "tc_galpha.h"

/* One variant of the kernels; a model keeps a pointer to the one tc_step_kernels_for_cpu gives. */
typedef struct tc_step_kernels {
    int avx; /* 1: the AVX variant */
    tc_sd_galpha_fn *galpha;
    /* d = a - b over n values: whether every d is finite (returned), and whether every a is (*a_finite) */
    int (*difference_finite)(size_t n, const double *restrict a, const double *restrict b, double *restrict d,
                             int *a_finite);
    /* the largest of a[0..n-1], n >= 1 */
    double (*largest)(const double *a, size_t n);
    /* whether the node positions X + U are in order (none below the one before it; not with a NaN) */
    int (*positions_in_order)(size_t n, const double *X, const double *U);
} tc_step_kernels;

/* the baseline variant (the AVX one: tc_step_kernels_avx.h; the one for the processor: tc_cpu.h) */
extern const tc_step_kernels tc_step_kernels_baseline;

#endif
