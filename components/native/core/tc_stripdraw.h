/* The strip-draw model (the equations are in tc_stripdraw.c and the files it names; Python binding:
 * components/stripdraw/model.py).
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

/* outputs, in the order of the component's outputs (components/stripdraw/component.py) */
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

/* Create a model. table is borrowed (it must outlive the model) and required when p->friction_model is
 * TC_STRIPDRAW_FRICTION_MODEL_TABLE; beta_field (n_beta values, copied) is the initial debris field, NULL for
 * p->beta_initial everywhere. TC_ERROR for a parameter outside its declared range or choices
 * (tc_stripdraw_check_params), a beta_field of the wrong length, not finite or < 0, an initial beta above the cap and
 * a law the table cannot give (tc_law_check). */
TC_API int tc_stripdraw_create(const tc_stripdraw_params *p, const tc_table *table, const double *beta_field,
                               size_t n_beta, tc_stripdraw **out, tc_msg msg);
/* Every parameter against the range and choices StripDrawParameters declares (tc_stripdraw_params_check, generated
 * from it by components/native/toolchain/declarations.py): TC_ERROR naming the first that is not allowed. */
TC_API int tc_stripdraw_check_params(const tc_stripdraw_params *p, tc_msg msg);

TC_API void tc_stripdraw_free(tc_stripdraw *m);

/* Advance by dt [s] with normal_force [N] (one pad, >= 0) and grip_velocity [m/s] held.
 * TC_DISCARD, state unchanged: non-finite or negative input, a grip speed not below the wave speed sqrt(E / rho),
 * dt <= 0, a table lookup outside the table under
 * the error policy, an implicit solve that fails after all step halvings, a non-finite bar state, or a
 * step so long that it would need more than TC_STRIPDRAW_MAX_INTERVALS coupling intervals (or, explicit,
 * TC_STRIPDRAW_MAX_SUBSTEPS central-difference steps). tc_stripdraw_refusal says which kind. */
TC_API int tc_stripdraw_step(tc_stripdraw *m, double dt, double normal_force, double grip_velocity, tc_msg msg);
/* The same with the inputs' first and second time derivatives at the step's start (d[0], d[1]): each input is
 * u + d[0] s + d[1] s^2 / 2 over the step, each coupling interval takes its mean. */
TC_API int tc_stripdraw_step_poly(tc_stripdraw *m, double dt, double normal_force, const double d_normal_force[2],
                                  double grip_velocity, const double d_grip_velocity[2], tc_msg msg);
#define TC_STRIPDRAW_MAX_INTERVALS 1e8
#define TC_STRIPDRAW_MAX_SUBSTEPS 1e10

/* what the last refused step was refused for */
enum tc_stripdraw_refusal {
    TC_REFUSED_INPUT = 0, /* an input or the step length */
    TC_REFUSED_TABLE = 1, /* a friction-table lookup outside the table under table_policy = error */
    TC_REFUSED_SOLVER = 2 /* the implicit solve did not converge, or the bar state became non-finite */
};
TC_API int tc_stripdraw_refusal(const tc_stripdraw *m);

/* The outputs of the current state, indexed by enum tc_stripdraw_output. */
TC_API void tc_stripdraw_outputs(const tc_stripdraw *m, double out[TC_STRIPDRAW_N_OUTPUTS]);

/* Make the inputs current without advancing time (the end of initialization: the outputs then report them, e.g.
 * contact_pressure = F_N / (L_T w_T)). TC_DISCARD naming the input, state unchanged, for inputs a step would refuse
 * (non-finite, a negative normal force). */
TC_API int tc_stripdraw_set_inputs(tc_stripdraw *m, double normal_force, double grip_velocity, tc_msg msg);

/* The state as a flat byte image (native byte order; tc_stripdraw_state.c states the format): a header (magic,
 * version, node count), the arrays U, V, A, Up, beta, slip_rate, fprev, the scalars time, reaction, normal_force,
 * grip_velocity, beta_removed, beta_produced, beta_hi, the counts n_steps, clamp_count, then the contact flags.
 * Everything else is fixed by the parameters or derived from the state (the contact weights from U, the friction
 * limits from beta, the normal force and the velocity). Setting a state and stepping replays bit-identically. */
TC_API size_t tc_stripdraw_state_size(const tc_stripdraw *m);
TC_API void tc_stripdraw_get_state(const tc_stripdraw *m, void *buf);
/* TC_ERROR (state unchanged) when the image is not one of this model: size, magic, version, node count. */
TC_API int tc_stripdraw_set_state(tc_stripdraw *m, const void *buf, size_t size, tc_msg msg);

/* Nodal fields: node count, then X (material coordinates), U, beta, slip (plastic
 * slip U_p) and contact (contact weight in [0, 1]) into arrays of tc_stripdraw_n_nodes values; any
 * pointer may be NULL. The pad covers [window[0], window[1]] in space: node i is under it when
 * window[0] <= X_i + U_i <= window[1]. */
TC_API size_t tc_stripdraw_n_nodes(const tc_stripdraw *m);
TC_API void tc_stripdraw_fields(const tc_stripdraw *m, double *X, double *U, double *beta, double *slip,
                                double *contact);
TC_API void tc_stripdraw_window(const tc_stripdraw *m, double window[2]);
TC_API double tc_stripdraw_time(const tc_stripdraw *m);
/* one nodal array (n_nodes values) into out */
enum tc_stripdraw_nodal {
    TC_SD_NODAL_X = 0, TC_SD_NODAL_U, TC_SD_NODAL_V, TC_SD_NODAL_A, TC_SD_NODAL_UP, TC_SD_NODAL_BETA,
    TC_SD_NODAL_SLIP_RATE,      /* |dU| / h of the last coupling interval [m/s] */
    TC_SD_NODAL_CONTACT_WEIGHT, /* overlap of the node's segment with the pad / l_e */
    TC_SD_NODAL_MASS,           /* lumped mass [kg] */
    TC_SD_NODAL_FRICTION_LIMIT, /* mu P of the state [Pa] (0 on nodes that cannot reach the pad) */
    TC_SD_NODAL_CONTACT         /* 1 for a node in contact (its plastic slip is set), else 0 */
};
TC_API void tc_stripdraw_nodal(const tc_stripdraw *m, int which, double *out);

/* one scalar of the model (counts as doubles) */
enum tc_stripdraw_info {
    TC_SD_INFO_TIME = 0, TC_SD_INFO_N_STEPS, TC_SD_INFO_CLAMP_COUNT,
    TC_SD_INFO_BETA_REMOVED,  /* sum over nodes of what the cap removed */
    TC_SD_INFO_BETA_PRODUCED, /* sum over nodes of the Archard source */
    TC_SD_INFO_BETA_CAP,      /* the cap of beta in use (Eq. 24) */
    TC_SD_INFO_EXPLICIT_TIME_STEP, /* cfl_safety x the stability limit [s] */
    TC_SD_INFO_ELEMENT_LENGTH, TC_SD_INFO_WINDOW_LO, TC_SD_INFO_WINDOW_HI,
    TC_SD_INFO_ELEMENT_STIFFNESS, /* k_e = E A / l_e [N/m] */
    TC_SD_INFO_SHEAR_STIFFNESS,   /* k_s [Pa/m] */
    TC_SD_INFO_NORMAL_FORCE,      /* of the last coupling interval [N] */
    TC_SD_INFO_GRIP_VELOCITY,     /* of the last coupling interval [m/s] */
    TC_SD_INFO_REACTION,          /* axial force at the grip of the half bar [N] */
    TC_SD_INFO_MU_LEAST           /* the least mu of the state's friction limits over the nodes under the pad (contact
                                   * weight > 0); NaN when there is none or no pressure */
};
TC_API double tc_stripdraw_info(const tc_stripdraw *m, int which);

/* Whether the least mu of the state (TC_SD_INFO_MU_LEAST) lies below the documented floor: 1 with a note naming the
 * setting that lets it (tc_law_floor_note of tc_friction.h), else 0. The FMU logs it once per instance, the Python
 * binding warns once per model (RangeWarning). */
TC_API int tc_stripdraw_floor_note(const tc_stripdraw *m, tc_msg msg);

/* ---------------------------------------------------------------------------------------------------
 * Kernels (n = number of nodes, node n - 1 is the grip), exported for the tests.
 * ------------------------------------------------------------------------------------------------- */

/* overlap of each node's tributary segment at X + U with [a_lo, a_hi]. */
TC_API void tc_sd_overlap(size_t n, const double *X, const double *U, double half_le, double a_lo, double a_hi,
                          double *ov);

#endif
