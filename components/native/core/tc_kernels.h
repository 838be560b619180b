/* Array kernels shared by the strip's integrators (tc_explicit.c, tc_galpha.c), its debris transport (tc_debris.c)
 * and its outputs (tc_stripdraw.c), and the interface law they evaluate. */
#ifndef TC_KERNELS_H
#define TC_KERNELS_H

#include <math.h>
#include <stddef.h>

#include "tc_common.h"

/* the first and last index k < n with a[k] > 0 (the pad's nodes); returns 0 when there is none. */
TC_API int tc_sd_positive_range(size_t n, const double *a, size_t *first, size_t *last);

/* tridiagonal solve (Thomas algorithm); sub NULL: no subdiagonal (an upper bidiagonal system); work holds 2 n doubles;
 * x must not alias the inputs. */
TC_API void tc_thomas(size_t n, const double *sub, const double *diag, const double *sup, const double *rhs,
                      double *x, double *work);

/* The interface law (Eq. 4-5) on one node of elastic slip x: the traction k_s x limited to +-tmax; *slipping when the
 * trial traction exceeds the limit. The limits are selects, not branches: a node sliding at its limit has a trial
 * traction within round-off of it on either side, which no branch predictor foresees. */
static inline double tc_sd_traction(double x, double ks, double tmax, int *slipping) {
    const double trial = ks * x;
    *slipping = fabs(trial) > tmax;
    const double below = tmax < trial ? tmax : trial; /* min(trial, tmax); a NaN trial stays */
    return -tmax > below ? -tmax : below;
}

#endif
