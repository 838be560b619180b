/* The user friction routines' arrays over one contact point's friction (tc_fe_friction.h states them). */
#include "tc_fe_friction.h"

#include <math.h>

/* the magnitude of a slip vector of n components */
static double magnitude(const double *v, int n) {
    double s = 0.0;
    for (int i = 0; i < n; ++i) s += v[i] * v[i];
    return sqrt(s);
}

static int checked(const tc_fe_law *fe, const double *props, int n_props, int n_states) {
    if (n_states < TC_FE_MIN_STATES) return TC_FE_TOO_FEW_STATES;
    if (n_props < 1 || props[0] != fe->check) return TC_FE_WRONG_CHECK;
    return TC_FE_OK;
}

/* one point in deck units: the pressure (deck unit), the slip magnitude (deck length), dt; its states st[n_states]
 * updated; returns mu */
static double point(const tc_fe_law *fe, double pressure, double slip, double dt, double *st, int n_states,
                    tc_table_rows *rows) {
    int flagged;
    const double mu = tc_node_friction(&fe->law, pressure * fe->pressure_scale, slip * fe->length_scale, dt, &st[0],
                                       &flagged, rows);
    if (pressure > 0) st[1] += slip;
    if (n_states > 2 && flagged) st[2] += 1.0;
    return mu;
}

/* the points of a VFRICTION block looked up together: runs of one pressure, at most this many at once */
#define RUN 64

int tc_fe_vfriction(const tc_fe_law *fe, int n_block, int n_dir, int n_fric_dir, int n_states, int n_nod_state,
                    const double *props, int n_props, double dt, const double *dslip, const double *fstick,
                    const double *fnormal, const double *area, double *state, double *ftang) {
    const int rc = checked(fe, props, n_props, n_states);
    if (rc != TC_FE_OK) return rc;
    if (n_block < 0 || n_dir < 1 || n_fric_dir < 1 || n_nod_state < 1) return TC_FE_BAD_SIZES;
    const size_t stride = (size_t)n_nod_state * (size_t)n_states;
    tc_table_rows rows = {0};
    double pressure[RUN], slide[RUN], slip[RUN], rate[RUN], beta[RUN], mu[RUN], work[RUN];
    unsigned char flagged[RUN];
    for (int k0 = 0; k0 < n_block;) {
        /* a run of points in contact at one pressure (F_N / A: the deck's unit), a point out of contact or with an
         * input that is not finite alone */
        int n = 0;
        for (int k = k0; k < n_block && n < RUN; ++k) {
            const double fn = fnormal[k], a = area[k];
            const double p = (fn > 0 && a > 0 ? fn / a : 0.0) * fe->pressure_scale;
            const double d = magnitude(dslip + (size_t)k * (size_t)n_dir, n_dir), b = state[(size_t)k * stride];
            const int valid = p > 0 && isfinite(p) && isfinite(d) && isfinite(dt) && isfinite(b);
            if (n > 0 && !(valid && p == pressure[0])) break;
            pressure[n] = p;
            slide[n] = d;
            slip[n] = d * fe->length_scale;
            beta[n] = b;
            rate[n] = dt > 0 ? slip[n] / dt : 0.0;
            ++n;
            if (!valid) break;
        }
        const double p = pressure[0];
        const int looked_up = p > 0 && isfinite(p) && isfinite(slide[0]) && isfinite(dt) && isfinite(beta[0]);
        if (looked_up) tc_node_mu(&fe->law, p, (size_t)n, rate, beta, mu, flagged, work, &rows);
        for (int j = 0; j < n; ++j) {
            const int k = k0 + j;
            double *st = state + (size_t)k * stride, *ft = ftang + (size_t)k * (size_t)n_fric_dir;
            for (int i = 0; i < n_fric_dir; ++i) ft[i] = 0.0;
            if (!looked_up) { /* out of contact (no friction, the state kept) or an input not finite (counted) */
                if (p > 0 && n_states > 2) st[2] += 1.0;
                continue;
            }
            st[0] = tc_node_debris(&fe->law, p, slip[j], rate[j], beta[j], &rows);
            st[1] += slide[j];
            if (n_states > 2 && flagged[j]) st[2] += 1.0;
            const double force = mu[j] * fnormal[k], stick = fstick[k];
            ft[0] = -(force < stick ? force : stick); /* opposite to the slip, no more than what sticks the point */
        }
        k0 += n;
    }
    return TC_FE_OK;
}

int tc_fe_fric(const tc_fe_law *fe, int *lm, double *tau, double *ddtddg, double *ddtddp, const double *dgam,
               double press, double dtime, double chrlngth, int nfdir, double *statev, int nstatv, const double *props,
               int nprops) {
    const int rc = checked(fe, props, nprops, nstatv);
    if (rc != TC_FE_OK) return rc;
    if (nfdir < 1 || nfdir > 2) return TC_FE_BAD_SIZES;
    if (*lm == 2) return TC_FE_OK; /* open at the last iteration or increment: it stays open */
    tc_table_rows rows = {0};
    const double mu = point(fe, press, magnitude(dgam, nfdir), dtime, statev, nstatv, &rows);
    const double crit = mu * press;
    for (int i = 0; i < nfdir * nfdir; ++i) ddtddg[i] = 0.0;
    for (int i = 0; i < nfdir; ++i) ddtddp[i] = 0.0;
    if (!(crit > 0) || !(chrlngth > 0)) { /* no pressure (or no length to stick over): frictionless */
        for (int i = 0; i < nfdir; ++i) tau[i] = 0.0;
        *lm = 2;
        return TC_FE_OK;
    }
    *lm = 0;
    const double k = crit / (TC_FE_SLIP_TOLERANCE * chrlngth); /* elastic stick: tau_crit at the slip tolerance */
    double trial[2] = {0.0, 0.0};
    for (int i = 0; i < nfdir; ++i) trial[i] = tau[i] + k * dgam[i];
    const double t = magnitude(trial, nfdir);
    if (t <= crit) { /* stick: the elastic trial stress */
        for (int i = 0; i < nfdir; ++i) {
            tau[i] = trial[i];
            ddtddg[i * nfdir + i] = k;
        }
        return TC_FE_OK;
    }
    /* slip: the trial stress returned to the limit mu p along it */
    const double ratio = crit / t;
    for (int i = 0; i < nfdir; ++i) {
        const double n_i = trial[i] / t;
        tau[i] = crit * n_i;
        ddtddp[i] = mu * n_i;
        for (int j = 0; j < nfdir; ++j)
            ddtddg[j * nfdir + i] = ratio * k * ((i == j ? 1.0 : 0.0) - n_i * trial[j] / t);
    }
    return TC_FE_OK;
}

int tc_fe_node(const tc_fe_law *fe, double fnormal, double area, const double *dslip, int n_dir, double dt,
               double *hsv, int n_hsv, const double *uc, int n_uc, double *fric) {
    const int rc = checked(fe, uc, n_uc, n_hsv);
    if (rc != TC_FE_OK) return rc;
    if (n_dir < 1) return TC_FE_BAD_SIZES;
    tc_table_rows rows = {0};
    const double pressure = fnormal > 0 && area > 0 ? fnormal / area : 0.0;
    const double mu = point(fe, pressure, magnitude(dslip, n_dir), dt, hsv, n_hsv, &rows);
    fric[0] = mu;
    fric[1] = mu;
    fric[2] = 0.0;
    fric[3] = 0.0;
    return TC_FE_OK;
}
