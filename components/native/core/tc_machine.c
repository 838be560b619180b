/* The drawing machine, advanced exactly over each step (Python binding: components/machine/model.py).
 *
 * The motor's rotor inertia J_m appears at the screw nut as m_m = J_m (2 pi / lead)^2:
 *
 *     m_m x_m'' = F_m - k_d (x_m - x_g) - c_d (v_m - v_g)
 *     m_g x_g'' = k_d (x_m - x_g) + c_d (v_m - v_g) - F_p
 *     tau_i F_m' = F_c - F_m                                  (current loop: first-order lag)
 *     F_c = K_p (v_set - v_m) + K_i I,   I' = v_set - v_m     (PI speed control on the motor encoder)
 *
 * With z = [x_m, v_m, x_g, v_g, F_m, I] and w = [v_set, F_p] this is z' = A z + B w (matrices below). v_set is 0
 * until start_time, then ramps linearly to velocity_setpoint over ramp_time (a step at start_time when ramp_time =
 * 0), so a step is split at the ramp's start and end and each piece advanced with v_set affine and F_p held
 * (tc_propagator_step).
 */
#include "tc_machine.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "tc_linear.h"

#define STATE_MAGIC 0x4d534354u /* "TCSM" */
#define STATE_VERSION 1u
#define PI 3.141592653589793 /* math.pi */

struct tc_machine {
    tc_machine_params p;
    tc_propagator prop;
    double z[6];
    double time, pull_force;
};

/* v_set(t) = velocity_setpoint min(1, max(0, (t - start_time) / ramp_time)); with ramp_time = 0 a step at
 * start_time, whose value there is 0 from the left (left != 0) and velocity_setpoint from the right */
static double setpoint(const tc_machine *m, double t, int left) {
    const double s = t - m->p.start_time;
    if (m->p.ramp_time == 0) return s > 0 || (s == 0 && !left) ? m->p.velocity_setpoint : 0.0;
    const double r = s / m->p.ramp_time;
    return m->p.velocity_setpoint * (r < 0.0 ? 0.0 : r < 1.0 ? r : 1.0);
}

void tc_machine_free(tc_machine *m) { free(m); }

int tc_machine_check_params(const tc_machine_params *p, tc_msg msg) { return tc_machine_params_check(p, msg); }

int tc_machine_create(const tc_machine_params *p, tc_machine **out, tc_msg msg) {
    if (out == NULL || p == NULL) return tc_fail(msg, TC_ERROR, "tc_machine_create: parameters or out is NULL");
    *out = NULL;
    const int checked = tc_machine_params_check(p, msg);
    if (checked != TC_OK) return checked;
    tc_machine *m = calloc(1, sizeof *m);
    if (m == NULL) return tc_fail(msg, TC_NOMEM, "out of memory for the drawing machine");
    m->p = *p;
    const double mm = p->motor_inertia * pow(2.0 * PI / p->screw_lead, 2.0); /* motor_side_mass; ** 2 is pow() */
    const double mg = p->carriage_mass, k = p->drive_stiffness, c = p->drive_damping;
    const double tau = p->current_time_constant, kp = p->speed_kp, ki = p->speed_ki;
    const double A[36] = {
        0.0,      1.0,       0.0,     0.0,     0.0,        0.0,
        -k / mm,  -c / mm,   k / mm,  c / mm,  1.0 / mm,   0.0,
        0.0,      0.0,       0.0,     1.0,     0.0,        0.0,
        k / mg,   c / mg,    -k / mg, -c / mg, 0.0,        0.0,
        0.0,      -kp / tau, 0.0,     0.0,     -1.0 / tau, ki / tau,
        0.0,      -1.0,      0.0,     0.0,     0.0,        0.0,
    };
    const double B[12] = {
        0.0,      0.0,
        0.0,      0.0,
        0.0,      0.0,
        0.0,      -1.0 / mg,
        kp / tau, 0.0,
        1.0,      0.0,
    };
    int rc = tc_propagator_init(&m->prop, 6, 2, A, B, msg);
    if (rc != TC_OK) {
        free(m);
        return rc;
    }
    *out = m;
    return TC_OK;
}

int tc_machine_step(tc_machine *m, double dt, double pull_force, tc_msg msg) {
    char r[TC_REPR_SIZE];
    if (!isfinite(dt))
        return tc_fail(msg, TC_DISCARD, "dt = %s is not finite; a finite number is required", tc_repr_double(dt, r));
    if (dt <= 0) return tc_fail(msg, TC_DISCARD, "dt = %s s must be > 0", tc_repr_double(dt, r));
    if (!isfinite(pull_force))
        return tc_fail(msg, TC_DISCARD, "pull_force = %s is not finite; a finite number is required",
                       tc_repr_double(pull_force, r));
    const double t0 = m->time, t1 = m->time + dt;
    const double start = m->p.start_time, end = m->p.start_time + m->p.ramp_time; /* the set-point's breakpoints */
    double cuts[4];
    int n_cuts = 0;
    cuts[n_cuts++] = t0;
    if (t0 < start && start < t1) cuts[n_cuts++] = start;
    if (t0 < end && end < t1 && end > start) cuts[n_cuts++] = end;
    cuts[n_cuts++] = t1;
    double z[6];
    memcpy(z, m->z, sizeof z);
    for (int k = 0; k + 1 < n_cuts; ++k) {
        const double a = cuts[k], b = cuts[k + 1], h = b - a;
        if (!(h > 0)) /* a step lost in rounding against the time */
            return tc_fail(msg, TC_DISCARD, "step of %s s is lost in rounding at t = %.17g s", tc_repr_double(h, r), a);
        const double va = setpoint(m, a, 0), vb = setpoint(m, b, 1); /* the piece's ends, from inside it */
        const double u0[2] = {va, pull_force}, u1[2] = {(vb - va) / h, 0.0};
        int rc = tc_propagator_step(&m->prop, z, h, u0, u1, z, msg);
        if (rc != TC_OK) return rc;
    }
    for (int i = 0; i < 6; ++i)
        if (!isfinite(z[i]))
            return tc_fail(msg, TC_DISCARD,
                           "pull_force = %s N drove the drive state to non-finite values at t = %.9g s",
                           tc_repr_double(pull_force, r), t1);
    memcpy(m->z, z, sizeof z);
    m->time = t1;
    m->pull_force = pull_force;
    return TC_OK;
}

void tc_machine_outputs(const tc_machine *m, double out[TC_MACHINE_N_OUTPUTS]) {
    out[TC_MACHINE_GRIP_VELOCITY] = m->z[3];
    out[TC_MACHINE_GRIP_POSITION] = m->z[2];
    out[TC_MACHINE_VELOCITY_SETPOINT] = setpoint(m, m->time, 0);
    out[TC_MACHINE_MOTOR_FORCE] = m->z[4];
}

double tc_machine_time(const tc_machine *m) { return m->time; }

size_t tc_machine_state_size(const tc_machine *m) {
    (void)m;
    return 8 + 8 * sizeof(double);
}

void tc_machine_get_state(const tc_machine *m, void *buf) {
    unsigned char *b = buf;
    const uint32_t head[2] = {STATE_MAGIC, STATE_VERSION};
    const double scalars[2] = {m->time, m->pull_force};
    memcpy(b, head, sizeof head);
    memcpy(b + 8, m->z, sizeof m->z);
    memcpy(b + 8 + sizeof m->z, scalars, sizeof scalars);
}

int tc_machine_set_state(tc_machine *m, const void *buf, size_t size, tc_msg msg) {
    const unsigned char *b = buf;
    uint32_t head[2];
    double scalars[2];
    if (b == NULL || size != tc_machine_state_size(m))
        return tc_fail(msg, TC_ERROR, "drawing-machine state image has %zu bytes; %zu expected",
                       b == NULL ? (size_t)0 : size, tc_machine_state_size(m));
    memcpy(head, b, sizeof head);
    if (head[0] != STATE_MAGIC || head[1] != STATE_VERSION)
        return tc_fail(msg, TC_ERROR, "not a drawing-machine state image (version %u of this format is read)",
                       (unsigned)STATE_VERSION);
    memcpy(m->z, b + 8, sizeof m->z);
    memcpy(scalars, b + 8 + sizeof m->z, sizeof scalars);
    m->time = scalars[0];
    m->pull_force = scalars[1];
    return TC_OK;
}
