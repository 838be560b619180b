/* The servo-hydraulic press that closes the strip-draw pads (Python binding: components/press/model.py).
 *
 * States z = [x, v, F_a, I] (pad displacement [m], velocity [m/s], actuator force [N], integral of the force
 * error [N s]); the force set-point F_set(t) is piecewise linear (a ramp, or setpoint_table "t0 F0; t1 F1; ...").
 * Each step is advanced exactly with the affine-input propagator (tc_linear.h), split at the set-point's
 * breakpoints. No global state; a step that returns TC_DISCARD leaves the state unchanged.
 */
#ifndef TC_PRESS_H
#define TC_PRESS_H

#include <stddef.h>

#include "tc_common.h"
#include "tc_press_params.h"

/* outputs, in the order of the component's outputs (components/press/model.py) */
enum tc_press_output {
    TC_PRESS_NORMAL_FORCE = 0, /* force on the pad k_f x + c_f v [N] */
    TC_PRESS_FORCE_SETPOINT,   /* F_set at the current time [N] */
    TC_PRESS_N_OUTPUTS
};

typedef struct tc_press tc_press;

/* Create a press. TC_ERROR for a parameter outside its declared range (tc_press_check_params) and for a malformed
 * set-point table, read with the grammar of tc_press.c (PressParameters checks the same); the table is copied, and
 * p->setpoint_table may be NULL (empty). */
TC_API int tc_press_create(const tc_press_params *p, tc_press **out, tc_msg msg);
/* Every parameter against the range PressParameters declares (tc_press_params_check, generated from it). */
TC_API int tc_press_check_params(const tc_press_params *p, tc_msg msg);
TC_API void tc_press_free(tc_press *m);

/* Advance by dt [s]; TC_DISCARD with the state unchanged for a non-finite dt, dt <= 0,
 * a step lost in rounding against the time, or a non-finite state. */
TC_API int tc_press_step(tc_press *m, double dt, tc_msg msg);
TC_API void tc_press_outputs(const tc_press *m, double out[TC_PRESS_N_OUTPUTS]);
TC_API double tc_press_time(const tc_press *m);

/* State image (native byte order): header (magic, version), z[4], time. The propagator cache is not state. */
TC_API size_t tc_press_state_size(const tc_press *m);
TC_API void tc_press_get_state(const tc_press *m, void *buf);
TC_API int tc_press_set_state(tc_press *m, const void *buf, size_t size, tc_msg msg);

#endif
