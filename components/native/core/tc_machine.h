/* The drawing machine: servo drive that pulls the strip (Python binding: components/machine/model.py).
 *
 * States z = [x_m, v_m, x_g, v_g, F_m, I] (motor side and grip positions [m] and velocities [m/s], motor force
 * [N], integral of the speed error [m]); inputs w = [v_set, F_p], the velocity set-point (0 until start_time, then a
 * ramp to velocity_setpoint over ramp_time) and the strip's pull force (held over a step). Each step is advanced
 * exactly with the affine-input propagator (tc_linear.h), split at the ramp's start and end. No global state; a step that
 * returns TC_DISCARD leaves the state unchanged.
 */
#ifndef TC_MACHINE_H
#define TC_MACHINE_H

#include <stddef.h>

#include "tc_common.h"
#include "tc_machine_params.h"

/* outputs, in the order of the component's outputs (components/machine/model.py) */
enum tc_machine_output {
    TC_MACHINE_GRIP_VELOCITY = 0, /* v_g [m/s] */
    TC_MACHINE_GRIP_POSITION,     /* x_g [m] */
    TC_MACHINE_VELOCITY_SETPOINT, /* v_set at the current time [m/s] */
    TC_MACHINE_MOTOR_FORCE,       /* F_m [N] */
    TC_MACHINE_N_OUTPUTS
};

typedef struct tc_machine tc_machine;

/* Create a drawing machine; TC_ERROR for a parameter outside its declared range (tc_machine_check_params). */
TC_API int tc_machine_create(const tc_machine_params *p, tc_machine **out, tc_msg msg);
/* Every parameter against the range MachineParameters declares (tc_machine_params_check, generated from it). */
TC_API int tc_machine_check_params(const tc_machine_params *p, tc_msg msg);
TC_API void tc_machine_free(tc_machine *m);

/* Advance by dt [s] with pull_force [N] held; TC_DISCARD with the state unchanged for a
 * non-finite input, dt <= 0, a step lost in rounding against the time, or a non-finite state. */
TC_API int tc_machine_step(tc_machine *m, double dt, double pull_force, tc_msg msg);
TC_API void tc_machine_outputs(const tc_machine *m, double out[TC_MACHINE_N_OUTPUTS]);
TC_API double tc_machine_time(const tc_machine *m);

/* State image (native byte order): header (magic, version), z[6], time, pull_force. */
TC_API size_t tc_machine_state_size(const tc_machine *m);
TC_API void tc_machine_get_state(const tc_machine *m, void *buf);
TC_API int tc_machine_set_state(tc_machine *m, const void *buf, size_t size, tc_msg msg);

#endif
