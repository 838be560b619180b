/* Array kernels shared by the strip's integrators (tc_stripdraw.c, tc_galpha.c) and its debris transport. */
#ifndef TC_KERNELS_H
#define TC_KERNELS_H

#include <stddef.h>

#include "tc_common.h"

/* the first and last index k < n with a[k] > 0 (the pad's nodes); returns 0 when there is none. */
TC_API int tc_sd_positive_range(size_t n, const double *a, size_t *first, size_t *last);

/* tridiagonal solve (Thomas algorithm); work holds 2 n doubles; x must not alias the inputs. */
TC_API void tc_thomas(size_t n, const double *sub, const double *diag, const double *sup, const double *rhs,
                      double *x, double *work);

#endif
