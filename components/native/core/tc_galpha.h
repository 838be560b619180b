/* One generalized-alpha step of the strip's bar, the free parts of the bar condensed onto the pad (the equations
 * are in tc_galpha.c). n = number of nodes, node n - 1 is the grip. */
#ifndef TC_GALPHA_H
#define TC_GALPHA_H

#include <stddef.h>

/* the elimination factors of the free bar for one step (cm = (1 - am) / (beta dt^2), c = (1 - af) k_e) into chain
 * (TC_SD_CHAIN(n) doubles: rows et, qt, it, eg, qg, ig, then cm m and am m, of n values each). */
#define TC_SD_CHAIN(n) (8 * (n))
void tc_sd_chain_factors(size_t n, double cm, double am, const double *m, double c, double *chain);

/* the bar's state a step starts from: displacements, velocities, accelerations and the nodal forces (n values each) */
typedef struct {
    const double *U, *V, *A, *fprev;
} tc_sd_bar;

/* one generalized-alpha step (tc_galpha.c) from the state *from into U, V, A and fprev (the same arrays as from's, or
 * others): returns the Newton iterations, -1 without convergence, or -2 when beta dt^2 is 0; nothing is changed when
 * it returns < 0. Up and contact are read and updated in place. chain holds tc_sd_chain_factors of dt; the nodes
 * with ov > 0 lie in [first, last] (first > last: not known). */
#define TC_SD_GALPHA_WORK(n) (14 * (n))
#define TC_SD_GALPHA_IWORK(n) (2 * (n))
typedef int tc_sd_galpha_fn(size_t n, double dt, const tc_sd_bar *from, double *U, double *V, double *A, double *Up,
                            signed char *contact, double *fprev, const double *ov, size_t first, size_t last,
                            const double *m, double ke, double ks, double wT, const double *tmax, double vg, double am,
                            double af, double beta, double gamma, int max_iter, double rtol, const double *chain,
                            double *fric, double *reaction, double *work, signed char *iwork);
tc_sd_galpha_fn tc_sd_galpha;

#endif
