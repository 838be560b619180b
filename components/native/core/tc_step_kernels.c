/* The passes over every node of the bar that a step makes (tc_step_kernels.h). This file is compiled for the baseline
 * and again in tc_step_kernels_avx.c, which includes it with TC_VARIANT naming the step it includes (tc_galpha.c) and
 * TC_STEP_KERNELS_TABLE its table. */
#include "tc_step_kernels.h"

#include <math.h>

#ifndef TC_VARIANT /* the baseline */
#define TC_VARIANT(name) name
#define TC_VARIANT_AVX 0
#define TC_STEP_KERNELS_TABLE tc_step_kernels_baseline
#endif

/* d = a - b over n values, whether every d is finite (returned) and whether every a is (*a_finite): sums of 0 d in
 * four lanes (inf or NaN anywhere makes a sum NaN; the lanes let the loop run in vector registers). A finite
 * difference has finite operands, so a is scanned only when a d is not finite. */
static int difference_finite(size_t n, const double *restrict a, const double *restrict b, double *restrict d,
                             int *a_finite) {
    double s[4] = {0.0, 0.0, 0.0, 0.0};
    size_t i = 0;
    for (; i + 4 <= n; i += 4)
        for (int k = 0; k < 4; ++k) {
            d[i + (size_t)k] = a[i + (size_t)k] - b[i + (size_t)k];
            s[k] += 0.0 * d[i + (size_t)k];
        }
    for (; i < n; ++i) {
        d[i] = a[i] - b[i];
        s[0] += 0.0 * d[i];
    }
    if (isfinite(s[0] + s[1] + s[2] + s[3])) {
        *a_finite = 1;
        return 1;
    }
    double sa = 0.0;
    for (i = 0; i < n; ++i) sa += 0.0 * a[i];
    *a_finite = isfinite(sa);
    return 0;
}

/* the largest of a[0..n-1], n >= 1, in four lanes (the compares overlap) */
static double largest(const double *a, size_t n) {
    double mx[4] = {a[0], a[0], a[0], a[0]};
    size_t i = 0;
    for (; i + 4 <= n; i += 4)
        for (int k = 0; k < 4; ++k) mx[k] = a[i + (size_t)k] > mx[k] ? a[i + (size_t)k] : mx[k];
    for (; i < n; ++i) mx[0] = a[i] > mx[0] ? a[i] : mx[0];
    const double m01 = mx[1] > mx[0] ? mx[1] : mx[0], m23 = mx[3] > mx[2] ? mx[3] : mx[2];
    return m23 > m01 ? m23 : m01;
}

/* whether the node positions X + U are in order (none below the one before it; not with a NaN) */
static int positions_in_order(size_t n, const double *X, const double *U) {
    int sorted = 1;
    double before = X[0] + U[0];
    for (size_t i = 1; i < n; ++i) {
        const double x = X[i] + U[i];
        sorted &= before <= x;
        before = x;
    }
    return sorted;
}

const tc_step_kernels TC_STEP_KERNELS_TABLE = {TC_VARIANT_AVX, TC_VARIANT(tc_sd_galpha), difference_finite, largest,
                                               positions_in_order};
