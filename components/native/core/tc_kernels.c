/* Array kernels shared by the strip's integrators and its debris transport (tc_kernels.h). */
#include "tc_kernels.h"

int tc_sd_positive_range(size_t n, const double *a, size_t *first, size_t *last) {
    size_t i = 0;
    while (i < n && !(a[i] > 0.0)) ++i;
    if (i == n) return 0;
    size_t j = n - 1;
    while (!(a[j] > 0.0)) --j;
    *first = i;
    *last = j;
    return 1;
}

void tc_thomas(size_t n, const double *sub, const double *diag, const double *sup, const double *rhs, double *x,
               double *work) {
    double *c = work, *d = work + n;
    /* with no subdiagonal (the advection of debris on a strip drawn forwards) the forward sweep is divisions that
     * need not wait for each other */
    if (sub == NULL) {
        for (size_t i = 0; i < n; ++i) {
            c[i] = sup[i] / diag[i];
            d[i] = rhs[i] / diag[i];
        }
    } else {
        double cp = sup[0] / diag[0], dp = rhs[0] / diag[0]; /* the recurrences' carries, kept in registers */
        c[0] = cp;
        d[0] = dp;
        for (size_t i = 1; i < n; ++i) {
            const double m = diag[i] - sub[i] * cp;
            c[i] = cp = sup[i] / m;
            d[i] = dp = (rhs[i] - sub[i] * dp) / m;
        }
    }
    double xp = d[n - 1];
    x[n - 1] = xp;
    for (size_t i = n - 1; i-- > 0;) x[i] = xp = d[i] - c[i] * xp;
}
