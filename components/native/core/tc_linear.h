/* Exact time stepping of small linear ODE systems x' = A x + B u(t)
 *
 * Over a step in which the input is affine in time, u(t0 + s) = u0 + s u1, the state is advanced exactly
 * (to rounding) with the exponential of the augmented matrix (Van Loan 1978, doi:10.1109/TAC.1978.1101743)
 *
 *     d/dt [x, u, u1] = [[A, B, 0], [0, 0, I], [0, 0, 0]] [x, u, u1],
 *     exp(dt [[A, B, 0], [0, 0, I], [0, 0, 0]]) = [[Phi, G0, G1], [0, I, dt I], [0, 0, I]],
 *     x(t0 + dt) = Phi x + G0 u0 + G1 u1.
 *
 * tc_expm balances the matrix (diagonal similarity by powers of 2, Parlett & Reinsch 1969, as LAPACK's
 * gebal without permutations), then uses scaling and squaring of an 18-term Taylor polynomial (Moler &
 * Van Loan 2003, doi:10.1137/S00361445024180). Products are plain loops.
 *
 * Everything is sized at compile time (at most TC_LINEAR_MAX_DIM rows of the augmented matrix): no
 * allocation, no global state. Matrices are row-major.
 */
#ifndef TC_LINEAR_H
#define TC_LINEAR_H

#include <stddef.h>

#include "tc_common.h"

#define TC_LINEAR_MAX_STATES 8                                           /* n: states */
#define TC_LINEAR_MAX_INPUTS 4                                           /* m: inputs */
#define TC_LINEAR_MAX_DIM (TC_LINEAR_MAX_STATES + 2 * TC_LINEAR_MAX_INPUTS) /* n + 2 m */
#define TC_LINEAR_CACHE 8 /* propagators kept per instance, one per step length */

/* Balancing scales d (powers of 2) of the n x n matrix M: diag(1/d) M diag(d) has rows
 * and columns of comparable norm. n <= TC_LINEAR_MAX_DIM. */
TC_API void tc_balance(size_t n, const double *M, double *d);

/* E = exp(M) for the n x n matrix M. TC_DISCARD when M is not finite or too large to scale; E is then
 * untouched. */
TC_API int tc_expm(size_t n, const double *M, double *E, tc_msg msg);

/* One cached propagator (Phi, G0, G1) for a step length dt. */
typedef struct tc_propagator_entry {
    int used;  /* 0: empty slot */
    double dt;
    double Phi[TC_LINEAR_MAX_STATES * TC_LINEAR_MAX_STATES];
    double G0[TC_LINEAR_MAX_STATES * TC_LINEAR_MAX_INPUTS];
    double G1[TC_LINEAR_MAX_STATES * TC_LINEAR_MAX_INPUTS];
} tc_propagator_entry;

/* The propagator of x' = A x + B u: A (n x n), B (n x m), and a small cache of step lengths. The cache
 * changes nothing but the cost: a propagator is a function of dt alone. */
typedef struct tc_propagator {
    size_t n, m;
    double A[TC_LINEAR_MAX_STATES * TC_LINEAR_MAX_STATES];
    double B[TC_LINEAR_MAX_STATES * TC_LINEAR_MAX_INPUTS];
    size_t next; /* round-robin replacement */
    tc_propagator_entry cache[TC_LINEAR_CACHE];
} tc_propagator;

/* Set up a propagator (no allocation); TC_ERROR when n or m exceed the compiled limits. */
int tc_propagator_init(tc_propagator *prop, size_t n, size_t m, const double *A, const double *B, tc_msg msg);

/* out = Phi(dt) x + G0(dt) u0 + G1(dt) u1 (u1 may be NULL: zero), as AffineInputPropagator.step.
 * out may alias x. TC_DISCARD (out untouched) when the exponential cannot be formed. */
int tc_propagator_step(tc_propagator *prop, const double *x, double dt, const double *u0, const double *u1,
                       double *out, tc_msg msg);

#endif
