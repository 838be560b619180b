/* The explicit (central-difference) integrator of the strip's bar (the equations are in tc_explicit.c). n = number
 * of nodes, node n - 1 is the grip. */
#ifndef TC_EXPLICIT_H
#define TC_EXPLICIT_H

#include <stddef.h>

/* n_sub central-difference steps of dt of the bar (U, V, A, the plastic slip Up and the contact flags updated in
 * place) with the nodes' friction limits tmax and the grip velocity vg; the friction force of the last into *fric,
 * the axial force at the grip into *reaction; f_work holds n doubles. */
void tc_sd_explicit(size_t n, long long n_sub, double dt, double *U, double *V, double *A, double *Up,
                    signed char *contact, const double *X, const double *minv, double ke, double ks, double wT,
                    double half_le, double a_lo, double a_hi, const double *tmax, double vg, double *fric,
                    double *reaction, double *f_work);

#endif
