/* The strip-draw model (native twin of components/stripdraw/model.py; the equations are in tc_stripdraw.c).
 *
 * One instance = one strip under one pad: a 1D bar with lumped masses, an elastic-perfectly-plastic
 * Coulomb interface, debris transport and a friction law (constant, closed form or a friction table).
 * All memory is allocated at creation; there is no global state, so instances are independent.
 *
 * Errors: every function that can fail returns a tc_status and writes a message into msg. A step that
 * returns TC_DISCARD has left the state bit-identical to what it was before the call.
 */
#ifndef TC_STRIPDRAW_H
#define TC_STRIPDRAW_H

#include <stddef.h>

#include "tc_common.h"
#include "tc_stripdraw_params.h"
#include "tc_table.h"

/* outputs, in the order of model.OUTPUT_NAMES */
enum tc_stripdraw_output {
    TC_STRIPDRAW_PULL_FORCE = 0,   /* 2 x axial force at the grip [N] */
    TC_STRIPDRAW_FRICTION_FORCE,   /* F_S on the modelled face [N] */
    TC_STRIPDRAW_MU_MEAN,          /* F_S / F_N (Eq. 28), 0 when F_N = 0 */
    TC_STRIPDRAW_SLIDING_DISTANCE, /* contact-weighted mean displacement under the pad [m] */
    TC_STRIPDRAW_BETA_MEAN,        /* contact-weighted mean beta under the pad */
    TC_STRIPDRAW_BETA_MAX,         /* largest beta on the strip */
    TC_STRIPDRAW_CONTACT_PRESSURE, /* P = F_N / (L_T w_T) [Pa] */
    TC_STRIPDRAW_GRIP_POSITION,    /* grip displacement [m] */
    TC_STRIPDRAW_TABLE_CLAMP_COUNT, /* cumulative count of clamped nodal table lookups (an integer) */
    TC_STRIPDRAW_N_OUTPUTS
};

typedef struct tc_stripdraw tc_stripdraw;

/* Create a model (StripDrawModel.__init__). table is borrowed (it must outlive the model) and required
 * when p->friction_model is TC_STRIPDRAW_FRICTION_MODEL_TABLE; beta_field (n_beta values, copied) is the
 * initial debris field, NULL for p->beta_initial everywhere. Checks what __init__ checks (beta_field length,
 * finite, >= 0; initial beta not above the cap) with its messages, and refuses parameters that cannot
 * be computed with (bad choice indices, n_elements < 1); the ranges of the other parameters are the
 * caller's to check (the field metadata of StripDrawParameters). */
TC_API int tc_stripdraw_create(const tc_stripdraw_params *p, const tc_table *table, const double *beta_field,
                               size_t n_beta, tc_stripdraw **out, tc_msg msg);

TC_API void tc_stripdraw_free(tc_stripdraw *m);

/* Advance by dt [s] with normal_force [N] (one pad, >= 0) and grip_velocity [m/s] held (StripDrawModel.step).
 * TC_DISCARD, state unchanged: non-finite or negative input, dt <= 0, a table lookup outside the table under
 * the error policy, an implicit solve that fails after all step halvings, a non-finite bar state, or a
 * step so long that it would need more than TC_STRIPDRAW_MAX_INTERVALS coupling intervals (or, explicit,
 * TC_STRIPDRAW_MAX_SUBSTEPS central-difference steps), where the Python model would run for days. */
TC_API int tc_stripdraw_step(tc_stripdraw *m, double dt, double normal_force, double grip_velocity, tc_msg msg);
/* The same with the inputs' first and second time derivatives at the step's start (d[0], d[1]): each input is
 * u + d[0] s + d[1] s^2 / 2 over the step, each coupling interval takes its mean (model.StripDrawModel.step). */
TC_API int tc_stripdraw_step_poly(tc_stripdraw *m, double dt, double normal_force, const double d_normal_force[2],
                                  double grip_velocity, const double d_grip_velocity[2], tc_msg msg);
#define TC_STRIPDRAW_MAX_INTERVALS 1e8
#define TC_STRIPDRAW_MAX_SUBSTEPS 1e10

/* The current outputs (StripDrawModel.outputs), indexed by enum tc_stripdraw_output. */
TC_API void tc_stripdraw_outputs(const tc_stripdraw *m, double out[TC_STRIPDRAW_N_OUTPUTS]);

/* The state as a flat byte image (native byte order): a header (magic, version, node count), the arrays
 * U, V, A, Up, beta, slip_rate, fprev and the scalars time, friction_force, reaction, normal_force,
 * beta_removed, n_steps, clamp_count, then the contact flags. Everything else is fixed by the parameters or
 * derived from the state (the contact weights from U). Setting a state and stepping replays bit-identically. */
TC_API size_t tc_stripdraw_state_size(const tc_stripdraw *m);
TC_API void tc_stripdraw_get_state(const tc_stripdraw *m, void *buf);
/* TC_ERROR (state unchanged) when the image is not one of this model: size, magic, version, node count. */
TC_API int tc_stripdraw_set_state(tc_stripdraw *m, const void *buf, size_t size, tc_msg msg);

/* Nodal fields (StripDrawModel.fields): node count, then X (material coordinates), U, beta, slip (plastic
 * slip U_p) and contact (contact weight in [0, 1]) into arrays of tc_stripdraw_n_nodes values; any
 * pointer may be NULL. The pad covers [window[0], window[1]] in space: node i is under it when
 * window[0] <= X_i + U_i <= window[1]. */
TC_API size_t tc_stripdraw_n_nodes(const tc_stripdraw *m);
TC_API void tc_stripdraw_fields(const tc_stripdraw *m, double *X, double *U, double *beta, double *slip,
                                double *contact);
TC_API void tc_stripdraw_window(const tc_stripdraw *m, double window[2]);
TC_API double tc_stripdraw_time(const tc_stripdraw *m);
/* cap of beta in use (Eq. 24) and the explicit scheme's step (cfl_safety x the stability limit) [s] */
TC_API double tc_stripdraw_beta_cap(const tc_stripdraw *m);
TC_API double tc_stripdraw_explicit_time_step(const tc_stripdraw *m);

/* ---------------------------------------------------------------------------------------------------
 * Kernels, exported for the tests (same arguments and effects as the loop forms of kernels.py and
 * transport.py; n = number of nodes, node n - 1 is the grip).
 * ------------------------------------------------------------------------------------------------- */

/* kernels.overlap_numpy: overlap of each node's tributary segment at X + U with [a_lo, a_hi]. */
TC_API void tc_sd_overlap(size_t n, const double *X, const double *U, double half_le, double a_lo, double a_hi,
                          double *ov);

/* kernels.positive_range: the first and last index k < n with a[k] > 0 (the pad's nodes); returns 0 when there is
 * none (then *first and *last are not written). */
TC_API int tc_sd_positive_range(size_t n, const double *a, size_t *first, size_t *last);

/* kernels._thomas_loop: tridiagonal solve; work holds 2 n doubles; x must not alias the inputs. */
TC_API void tc_thomas(size_t n, const double *sub, const double *diag, const double *sup, const double *rhs,
                      double *x, double *work);

/* kernels._explicit_loop; f_work holds n doubles. */
TC_API void tc_sd_explicit(size_t n, long long n_sub, double dt, double *U, double *V, double *A, double *Up,
                           signed char *contact, const double *X, const double *minv, double ke, double ks,
                           double wT, double half_le, double a_lo, double a_hi, const double *tmax, double vg,
                           double *fric, double *reaction, double *f_work);

/* galpha.chain_factors: the elimination factors of the free bar for one step (cm = (1 - am) / (beta dt^2),
 * c = (1 - af) k_e) into chain (TC_SD_CHAIN(n) doubles: rows et, qt, it, eg, qg, ig of n values each). */
#define TC_SD_CHAIN(n) (6 * (n))
TC_API void tc_sd_chain_factors(size_t n, double cm, const double *m, double c, double *chain);

/* galpha._galpha_loop (tc_galpha.c): returns the Newton iterations, -1 without convergence, or -2 when beta dt^2 is 0
 * (where the numba-compiled loop form raises ZeroDivisionError); nothing is changed when it returns < 0. chain holds
 * tc_sd_chain_factors of dt. */
#define TC_SD_GALPHA_WORK(n) (18 * (n))
#define TC_SD_GALPHA_IWORK(n) (2 * (n))
TC_API int tc_sd_galpha(size_t n, double dt, double *U, double *V, double *A, double *Up, signed char *contact,
                        double *fprev, const double *ov, const double *m, double ke, double ks, double wT,
                        const double *tmax, double vg, double am, double af, double beta, double gamma,
                        int max_iter, double rtol, const double *chain, double *fric, double *reaction, double *work,
                        signed char *iwork);

/* transport._advect_loop: out = beta advected implicitly (upwind) under the pad; work holds 5 n doubles. */
TC_API void tc_sd_advect(size_t n, const double *beta, const double *dU, const double *weight, double zeta,
                         double element_length, double *out, double *work);

#endif
