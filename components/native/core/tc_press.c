/* The servo-hydraulic press, advanced exactly between set-point breakpoints.
 *
 *     m_p v' = F_a - k_f x - c_f v                          (piston on the frame stiffness)
 *     F_N    = k_f x + c_f v                                (force on the pad: the output)
 *     tau_a F_a' = u - F_a                                  (first-order actuator lag)
 *     u      = F_set(t) + K_p (F_set - F_N) + K_i I,  I' = F_set - F_N   (PI with feed-forward)
 *
 * so with z = [x, v, F_a, I] and the input w = F_set:
 *
 *     A = [[0, 1, 0, 0], [-k/m, -c/m, 1/m, 0], [-K_p k/tau, -K_p c/tau, -1/tau, K_i/tau], [-k, -c, 0, 0]],
 *     B = [0, 0, (1 + K_p)/tau, 1].
 *
 * F_set is piecewise linear (held before the first and after the last breakpoint), so each step is split at
 * the breakpoints inside it and every piece advanced with the input affine in time (tc_propagator_step).
 */
#include "tc_press.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tc_linear.h"

#define STATE_MAGIC 0x50534354u /* "TCSP" */
#define STATE_VERSION 1u

struct tc_press {
    tc_press_params p; /* setpoint_table is not kept (NULL): the breakpoints below are */
    size_t n_set;
    double *t_set, *f_set; /* breakpoints of F_set: times [s] (increasing), forces [N] */
    tc_propagator prop;
    double z[4];
    double time;
};

/* ---------------------------------------------------------------------------------------------------
 * the set-point table "t0 F0; t1 F1; ...": entries separated by ';' (blank ones skipped), each a time [s] and a
 * force [N] separated by spaces or tabs, each a decimal number [+-](digits[.digits] | .digits)[(e|E)[+-]digits]
 * (components/press/parameters.py checks the same grammar)
 * ------------------------------------------------------------------------------------------------- */

static int is_blank(char c) { return c == ' ' || c == '\t'; }
static int is_digit(char c) { return c >= '0' && c <= '9'; }

/* One number of the grammar at s[0..len) into *value; 0 if the token is not one. The digits are converted as
 * "<digits>e<exponent>" (no decimal point, so the C locale does not matter); work holds len + 32 chars. */
static int parse_number(const char *s, size_t len, double *value, char *work) {
    size_t i = 0, nd = 0, n_int = 0, n_frac = 0;
    const int neg = len > 0 && s[0] == '-';
    if (len > 0 && (s[0] == '+' || s[0] == '-')) ++i;
    for (; i < len && is_digit(s[i]); ++i, ++n_int) work[nd++] = s[i];
    if (i < len && s[i] == '.')
        for (++i; i < len && is_digit(s[i]); ++i, ++n_frac) work[nd++] = s[i];
    if (n_int + n_frac == 0) return 0;
    long long exponent = 0;
    if (i < len && (s[i] == 'e' || s[i] == 'E')) {
        ++i;
        const int eneg = i < len && s[i] == '-';
        if (i < len && (s[i] == '+' || s[i] == '-')) ++i;
        size_t n_exp = 0;
        for (; i < len && is_digit(s[i]); ++i, ++n_exp)
            if (exponent < 100000000) exponent = exponent * 10 + (s[i] - '0'); /* saturated far beyond a double's */
        if (n_exp == 0) return 0;
        if (eneg) exponent = -exponent;
    }
    if (i != len) return 0;
    snprintf(work + nd, 32, "e%lld", exponent - (long long)n_frac);
    const double v = strtod(work, NULL);
    *value = neg ? -v : v;
    return 1;
}

/* PressParameters.setpoints(): breakpoints from the ramp, or parsed from the table. */
static int setpoints(const tc_press_params *p, tc_press *m, tc_msg msg) {
    const char *table = p->setpoint_table;
    if (table == NULL || table[0] == '\0') {
        m->t_set = malloc(2 * sizeof(double));
        m->f_set = malloc(2 * sizeof(double));
        if (m->t_set == NULL || m->f_set == NULL) return tc_fail(msg, TC_NOMEM, "out of memory for the press");
        if (p->ramp_time == 0) {
            m->n_set = 1;
            m->t_set[0] = 0.0;
            m->f_set[0] = p->force_setpoint;
        } else {
            m->n_set = 2;
            m->t_set[0] = 0.0;
            m->t_set[1] = p->ramp_time;
            m->f_set[0] = 0.0;
            m->f_set[1] = p->force_setpoint;
        }
        return TC_OK;
    }
    const size_t len = strlen(table);
    size_t n_items = 1;
    for (size_t k = 0; k < len; ++k) n_items += table[k] == ';';
    char *work = malloc(len + 64);
    m->t_set = malloc(n_items * sizeof(double));
    m->f_set = malloc(n_items * sizeof(double));
    if (work == NULL || m->t_set == NULL || m->f_set == NULL) {
        free(work);
        return tc_fail(msg, TC_NOMEM, "out of memory for the press set-point table");
    }
    int rc = TC_OK;
    size_t n_pairs = 0;
    const char *item = table;
    for (;;) {
        const char *end = strchr(item, ';');
        if (end == NULL) end = table + len;
        size_t n_tok = 0;
        double vals[2] = {0.0, 0.0};
        for (const char *c = item; c < end;) {
            if (is_blank(*c)) {
                ++c;
                continue;
            }
            const char *tok = c;
            while (c < end && !is_blank(*c)) ++c;
            double v;
            if (n_tok >= 2 || !parse_number(tok, (size_t)(c - tok), &v, work)) {
                rc = tc_fail(msg, TC_ERROR, "setpoint_table = '%s' is malformed: each entry is a time and a force, "
                             "two decimal numbers separated by spaces (entries separated by ';')", table);
                goto done;
            }
            vals[n_tok++] = v;
        }
        if (n_tok == 1) {
            rc = tc_fail(msg, TC_ERROR, "setpoint_table = '%s' is malformed: each entry is a time and a force, two "
                         "decimal numbers separated by spaces (entries separated by ';')", table);
            goto done;
        }
        if (n_tok == 2) {
            m->t_set[n_pairs] = vals[0];
            m->f_set[n_pairs] = vals[1];
            ++n_pairs;
        }
        if (*end == '\0') break;
        item = end + 1;
    }
    if (n_pairs == 0) {
        rc = tc_fail(msg, TC_ERROR, "setpoint_table = '%s' is malformed: it has no entry", table);
        goto done;
    }
    for (size_t k = 0; k < n_pairs; ++k) {
        const double t = m->t_set[k], f = m->f_set[k];
        if (!isfinite(t) || !isfinite(f) || f < 0 || (k > 0 && !(t - m->t_set[k - 1] > 0))) {
            rc = tc_fail(msg, TC_ERROR,
                         "setpoint_table = '%s': times must increase and forces be finite and >= 0", table);
            goto done;
        }
    }
    m->n_set = n_pairs;
done:
    free(work);
    return rc;
}

/* F_set(x): linear between the breakpoints, held before the first and after the last. */
static double setpoint(const tc_press *m, double x) {
    const double *xp = m->t_set, *fp = m->f_set;
    const size_t n = m->n_set;
    if (n == 1) return fp[0]; /* left = right = fp[0] */
    if (isnan(x)) return x;
    if (x < xp[0]) return fp[0];
    if (x > xp[n - 1]) return fp[n - 1];
    size_t lo = 0, hi = n; /* j: the last breakpoint with xp[j] <= x */
    while (hi - lo > 1) {
        size_t mid = lo + (hi - lo) / 2;
        if (xp[mid] <= x)
            lo = mid;
        else
            hi = mid;
    }
    const size_t j = lo;
    if (j == n - 1 || xp[j] == x) return fp[j];
    const double slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j]);
    double r = slope * (x - xp[j]) + fp[j];
    if (isnan(r)) { /* if we get nan in one direction, try the other */
        r = slope * (x - xp[j + 1]) + fp[j + 1];
        if (isnan(r) && fp[j] == fp[j + 1]) r = fp[j];
    }
    return r;
}

void tc_press_free(tc_press *m) {
    if (m == NULL) return;
    free(m->t_set);
    free(m->f_set);
    free(m);
}

int tc_press_check_params(const tc_press_params *p, tc_msg msg) { return tc_press_params_check(p, msg); }

int tc_press_create(const tc_press_params *p, tc_press **out, tc_msg msg) {
    if (out == NULL || p == NULL) return tc_fail(msg, TC_ERROR, "tc_press_create: parameters or out is NULL");
    *out = NULL;
    const int checked = tc_press_params_check(p, msg);
    if (checked != TC_OK) return checked;
    tc_press *m = calloc(1, sizeof *m);
    if (m == NULL) return tc_fail(msg, TC_NOMEM, "out of memory for the press");
    int rc = setpoints(p, m, msg);
    if (rc != TC_OK) {
        tc_press_free(m);
        return rc;
    }
    m->p = *p;
    m->p.setpoint_table = NULL;
    const double mp = p->piston_mass, k = p->frame_stiffness, c = p->frame_damping, tau = p->actuator_time_constant;
    const double A[16] = {
        0.0,              1.0,              0.0,         0.0,
        -k / mp,          -c / mp,          1.0 / mp,    0.0,
        -(p->kp * k) / tau, -(p->kp * c) / tau, -1.0 / tau, p->ki / tau,
        -k,               -c,               0.0,         0.0,
    };
    const double B[4] = {0.0, 0.0, (1.0 + p->kp) / tau, 1.0};
    rc = tc_propagator_init(&m->prop, 4, 1, A, B, msg);
    if (rc != TC_OK) {
        tc_press_free(m);
        return rc;
    }
    *out = m;
    return TC_OK;
}

/* advance z over [a, b] with F_set affine between its values at a and b */
static int piece(tc_press *m, double *z, double a, double b, tc_msg msg) {
    const double fa = setpoint(m, a), fb = setpoint(m, b), h = b - a;
    if (!(h > 0)) { /* a step lost in rounding against the time */
        char r[TC_REPR_SIZE];
        return tc_fail(msg, TC_DISCARD, "step of %s s is lost in rounding at t = %.17g s", tc_repr_double(h, r), a);
    }
    const double slope = (fb - fa) / h;
    return tc_propagator_step(&m->prop, z, h, &fa, &slope, z, msg);
}

int tc_press_step(tc_press *m, double dt, tc_msg msg) {
    char r[TC_REPR_SIZE];
    if (!isfinite(dt))
        return tc_fail(msg, TC_DISCARD, "dt = %s is not finite; a finite number is required", tc_repr_double(dt, r));
    if (dt <= 0) return tc_fail(msg, TC_DISCARD, "dt = %s s must be > 0", tc_repr_double(dt, r));
    const double t0 = m->time, t1 = m->time + dt;
    double z[4], a = t0;
    memcpy(z, m->z, sizeof z);
    for (size_t k = 0; k < m->n_set; ++k) { /* split at the breakpoints inside (t0, t1) */
        const double t = m->t_set[k];
        if (t0 < t && t < t1) {
            int rc = piece(m, z, a, t, msg);
            if (rc != TC_OK) return rc;
            a = t;
        }
    }
    int rc = piece(m, z, a, t1, msg);
    if (rc != TC_OK) return rc;
    for (int i = 0; i < 4; ++i)
        if (!isfinite(z[i])) return tc_fail(msg, TC_DISCARD, "press state became non-finite");
    memcpy(m->z, z, sizeof z);
    m->time = t1;
    return TC_OK;
}

void tc_press_outputs(const tc_press *m, double out[TC_PRESS_N_OUTPUTS]) {
    out[TC_PRESS_NORMAL_FORCE] = m->p.frame_stiffness * m->z[0] + m->p.frame_damping * m->z[1];
    out[TC_PRESS_FORCE_SETPOINT] = setpoint(m, m->time);
}

double tc_press_time(const tc_press *m) { return m->time; }

size_t tc_press_state_size(const tc_press *m) {
    (void)m;
    return 8 + 5 * sizeof(double);
}

void tc_press_get_state(const tc_press *m, void *buf) {
    unsigned char *b = buf;
    const uint32_t head[2] = {STATE_MAGIC, STATE_VERSION};
    memcpy(b, head, sizeof head);
    memcpy(b + 8, m->z, sizeof m->z);
    memcpy(b + 8 + sizeof m->z, &m->time, sizeof m->time);
}

int tc_press_set_state(tc_press *m, const void *buf, size_t size, tc_msg msg) {
    const unsigned char *b = buf;
    uint32_t head[2];
    if (b == NULL || size != tc_press_state_size(m))
        return tc_fail(msg, TC_ERROR, "press state image has %zu bytes; %zu expected", b == NULL ? (size_t)0 : size,
                       tc_press_state_size(m));
    memcpy(head, b, sizeof head);
    if (head[0] != STATE_MAGIC || head[1] != STATE_VERSION)
        return tc_fail(msg, TC_ERROR, "not a press state image (version %u of this format is read)",
                       (unsigned)STATE_VERSION);
    memcpy(m->z, b + 8, sizeof m->z);
    memcpy(&m->time, b + 8 + sizeof m->z, sizeof m->time);
    return TC_OK;
}
