/* Matrix exponential and the affine-input propagator (see tc_linear.h). */
#include "tc_linear.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAXD TC_LINEAR_MAX_DIM


void tc_balance(size_t n, const double *M, double *d) {
    double A[MAXD * MAXD];
    memcpy(A, M, n * n * sizeof *A);
    for (size_t i = 0; i < n; ++i) d[i] = 1.0;
    for (int sweep = 0; sweep < 100; ++sweep) {
        int converged = 1;
        for (size_t i = 0; i < n; ++i) {
            double c = 0.0, r = 0.0; /* 1-norms of column and row i without the diagonal */
            for (size_t j = 0; j < n; ++j)
                if (j != i) {
                    c += fabs(A[j * n + i]);
                    r += fabs(A[i * n + j]);
                }
            if (c == 0.0 || r == 0.0) continue;
            /* an infinite norm cannot be balanced; such a matrix fails in tc_expm */
            if (!isfinite(c) || !isfinite(r)) continue;
            double f = 1.0;
            while (c < r / 2.0) {
                c = c * 2.0;
                r = r / 2.0;
                f = f * 2.0;
            }
            while (c >= r * 2.0) {
                c = c / 2.0;
                r = r * 2.0;
                f = f / 2.0;
            }
            if (f != 1.0) {
                converged = 0;
                d[i] *= f;
                for (size_t j = 0; j < n; ++j) A[j * n + i] *= f;
                for (size_t j = 0; j < n; ++j) A[i * n + j] /= f;
            }
        }
        if (converged) break;
    }
}

/* C = A B for n x n matrices (C must not alias A or B). */
static void matmul(size_t n, const double *A, const double *B, double *C) {
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j) {
            double s = 0.0;
            for (size_t k = 0; k < n; ++k) s += A[i * n + k] * B[k * n + j];
            C[i * n + j] = s;
        }
}

/* scaling by 2^-s with ||M/2^s||_1 <= 1/4, 18 Taylor terms, s squarings. */
static int expm_taylor(size_t n, const double *M, double *E, tc_msg msg) {
    double X[MAXD * MAXD], term[MAXD * MAXD], tmp[MAXD * MAXD];
    double norm = 0.0; /* the 1-norm: the largest column sum of |M_ij| */
    for (size_t j = 0; j < n; ++j) {
        double col = 0.0;
        for (size_t i = 0; i < n; ++i) col += fabs(M[i * n + j]);
        if (col > norm || isnan(col)) norm = col;
    }
    int s = 0;
    if (norm > 0) {
        double e = ceil(log2(norm / 0.25));
        /* too large to scale (or not finite) */
        if (!(e < 1024.0))
            return tc_fail(msg, TC_DISCARD, "matrix exponential: the matrix norm %.17g is too large to scale", norm);
        s = e > 0.0 ? (int)e : 0;
    }
    double scale = ldexp(1.0, s); /* 2.0**s, exact */
    for (size_t i = 0; i < n * n; ++i) X[i] = M[i] / scale;
    for (size_t i = 0; i < n * n; ++i) term[i] = 0.0;
    for (size_t i = 0; i < n; ++i) term[i * n + i] = 1.0;
    memcpy(E, term, n * n * sizeof *E);
    for (int k = 1; k < 19; ++k) {
        matmul(n, term, X, tmp);
        for (size_t i = 0; i < n * n; ++i) term[i] = tmp[i] / (double)k;
        for (size_t i = 0; i < n * n; ++i) E[i] = E[i] + term[i];
    }
    for (int k = 0; k < s; ++k) {
        matmul(n, E, E, tmp);
        memcpy(E, tmp, n * n * sizeof *E);
    }
    return TC_OK;
}

int tc_expm(size_t n, const double *M, double *E, tc_msg msg) {
    double d[MAXD], Mb[MAXD * MAXD], Eb[MAXD * MAXD];
    if (n < 1 || n > MAXD)
        return tc_fail(msg, TC_ERROR, "matrix exponential: size %zu is outside [1, %d]", n, MAXD);
    for (size_t i = 0; i < n * n; ++i)
        if (!isfinite(M[i]))
            return tc_fail(msg, TC_DISCARD, "matrix exponential: entry (%zu, %zu) = %.17g is not finite", i / n, i % n,
                           M[i]);
    tc_balance(n, M, d);
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j) Mb[i * n + j] = M[i * n + j] * d[j] / d[i];
    int rc = expm_taylor(n, Mb, Eb, msg);
    if (rc != TC_OK) return rc;
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j) E[i * n + j] = Eb[i * n + j] * d[i] / d[j];
    return TC_OK;
}

int tc_propagator_init(tc_propagator *prop, size_t n, size_t m, const double *A, const double *B, tc_msg msg) {
    if (n < 1 || n > TC_LINEAR_MAX_STATES || m < 1 || m > TC_LINEAR_MAX_INPUTS)
        return tc_fail(msg, TC_ERROR, "linear system with %zu states and %zu inputs exceeds the limits %d, %d", n, m,
                       TC_LINEAR_MAX_STATES, TC_LINEAR_MAX_INPUTS);
    memset(prop, 0, sizeof *prop);
    prop->n = n;
    prop->m = m;
    memcpy(prop->A, A, n * n * sizeof *A);
    memcpy(prop->B, B, n * m * sizeof *B);
    return TC_OK;
}

/* AffineInputPropagator._matrices: Phi, G0, G1 for dt, from the cache or by tc_expm. */
static const tc_propagator_entry *matrices(tc_propagator *prop, double dt, tc_msg msg, int *rc) {
    for (size_t k = 0; k < TC_LINEAR_CACHE; ++k)
        if (prop->cache[k].used && prop->cache[k].dt == dt) return &prop->cache[k];
    size_t n = prop->n, m = prop->m, nb = n + 2 * m;
    double big[MAXD * MAXD], E[MAXD * MAXD];
    for (size_t i = 0; i < nb * nb; ++i) big[i] = 0.0;
    for (size_t i = 0; i < n; ++i) {
        for (size_t j = 0; j < n; ++j) big[i * nb + j] = prop->A[i * n + j];
        for (size_t j = 0; j < m; ++j) big[i * nb + n + j] = prop->B[i * m + j];
    }
    for (size_t j = 0; j < m; ++j) big[(n + j) * nb + n + m + j] = 1.0;
    for (size_t i = 0; i < nb * nb; ++i) big[i] = big[i] * dt;
    *rc = tc_expm(nb, big, E, msg);
    if (*rc != TC_OK) return NULL;
    tc_propagator_entry *e = &prop->cache[prop->next];
    prop->next = (prop->next + 1) % TC_LINEAR_CACHE;
    e->used = 1;
    e->dt = dt;
    for (size_t i = 0; i < n; ++i) {
        for (size_t j = 0; j < n; ++j) e->Phi[i * n + j] = E[i * nb + j];
        for (size_t j = 0; j < m; ++j) {
            e->G0[i * m + j] = E[i * nb + n + j];
            e->G1[i * m + j] = E[i * nb + n + m + j];
        }
    }
    return e;
}

int tc_propagator_step(tc_propagator *prop, const double *x, double dt, const double *u0, const double *u1,
                       double *out, tc_msg msg) {
    int rc = TC_OK;
    const tc_propagator_entry *e = matrices(prop, dt, msg, &rc);
    if (e == NULL) return rc;
    size_t n = prop->n, m = prop->m;
    double y[TC_LINEAR_MAX_STATES];
    for (size_t i = 0; i < n; ++i) {
        double a = 0.0, b = 0.0;
        for (size_t j = 0; j < n; ++j) a += e->Phi[i * n + j] * x[j];
        for (size_t j = 0; j < m; ++j) b += e->G0[i * m + j] * u0[j];
        y[i] = a + b; /* Phi @ x + G0 @ u0 */
        if (u1 != NULL) {
            double c = 0.0;
            for (size_t j = 0; j < m; ++j) c += e->G1[i * m + j] * u1[j];
            y[i] = y[i] + c; /* + G1 @ u1 */
        }
    }
    memcpy(out, y, n * sizeof *out);
    return TC_OK;
}
