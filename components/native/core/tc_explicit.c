/* The explicit integrator of the strip's bar: central difference (paper App. B, Eq. 31-32), sub-cycled inside a
 * coupling interval at the step the model chooses (cfl_safety x 2 / omega_max, tc_stripdraw.c).
 *
 * Per sub-step: predictor U += dt V + dt^2/2 A, V += dt/2 A (the grip node follows the grip velocity V0); the
 * element forces k_e (U_e+1 - U_e); the interface law with return mapping (Eq. 4-5, tc_sd_traction) on the nodes whose
 * tributary segment overlaps the pad (a node that enters it starts stress-free, Up := U), nodal force -T w_T ov;
 * corrector A = f / m, V += dt/2 A. The friction force is that of the last sub-step, the reaction the grip node's
 * force.
 */
#include "tc_explicit.h"

#include <math.h>

#include "tc_kernels.h"

void tc_sd_explicit(size_t n, long long n_sub, double dt, double *U, double *V, double *A, double *Up,
                    signed char *contact, const double *X, const double *minv, double ke, double ks, double wT,
                    double half_le, double a_lo, double a_hi, const double *tmax, double vg, double *fric,
                    double *reaction, double *f) {
    const size_t N = n - 1;
    double fr = 0.0;
    for (size_t i = 0; i < n; ++i) f[i] = 0.0;
    for (long long s = 0; s < n_sub; ++s) {
        /* predictor: U += dt V + dt^2/2 A, V += dt/2 A; the grip follows V0 */
        for (size_t i = 0; i < N; ++i) {
            U[i] += dt * V[i] + 0.5 * dt * dt * A[i];
            V[i] += 0.5 * dt * A[i];
        }
        U[N] += dt * vg;
        V[N] = vg;
        A[N] = 0.0;
        for (size_t i = 0; i < n; ++i) f[i] = 0.0;
        for (size_t e = 0; e < N; ++e) {
            const double s_e = ke * (U[e + 1] - U[e]);
            f[e] += s_e;
            f[e + 1] -= s_e;
        }
        /* interface law with return mapping on the nodes under the pad */
        fr = 0.0;
        for (size_t i = 0; i < n; ++i) {
            const double x = X[i] + U[i];
            const double lo = i == 0 ? x : x - half_le;
            const double hi = i == N ? x : x + half_le;
            const double ov = fmin(hi, a_hi) - fmax(lo, a_lo);
            if (ov > 0.0) {
                if (contact[i] == 0) {
                    Up[i] = U[i];
                    contact[i] = 1;
                }
                int slipping;
                const double T = tc_sd_traction(U[i] - Up[i], ks, tmax[i], &slipping);
                if (slipping) Up[i] = U[i] - T / ks;
                const double F = T * wT * ov;
                f[i] -= F;
                fr += F;
            } else {
                contact[i] = 0;
            }
        }
        /* corrector: A = f / m, V += dt/2 A */
        for (size_t i = 0; i < N; ++i) {
            A[i] = f[i] * minv[i];
            V[i] += 0.5 * dt * A[i];
        }
    }
    *fric = fr;
    *reaction = -f[N];
}

