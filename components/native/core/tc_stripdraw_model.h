/* The members of a strip-draw model (struct tc_stripdraw, opaque in tc_stripdraw.h): its parameters, mesh, state,
 * derived quantities and work arrays. Shared by the files of the model: the bar and its coupling (tc_stripdraw.c), the
 * debris transport and cap (tc_debris.c) and the state image and the step's backup (tc_stripdraw_state.c). */
#ifndef TC_STRIPDRAW_MODEL_H
#define TC_STRIPDRAW_MODEL_H

#include <stddef.h>

#include "tc_common.h"
#include "tc_stripdraw_params.h"
#include "tc_table.h"
#include "tc_step_kernels.h"
#include "tc_table_lookup.h"

#define TC_SD_CHAIN_CACHE 4   /* step lengths whose elimination factors are kept */
#define TC_SD_STEP_SCALARS 7  /* the doubles of the model a step changes besides its arrays */

struct tc_stripdraw {
    tc_stripdraw_params p;
    const tc_table *table; /* borrowed; NULL unless the table law is used */
    size_t n;              /* nodes; node n - 1 is the grip */
    /* mesh and constants */
    double le, half_le, a_lo, a_hi, ke, ks, wT, dt_explicit, pad_area;
    double am, af, gamma, beta_nm; /* generalized-alpha */
    double beta_cap;      /* params.beta_threshold if > 0, else the law's threshold */
    long long reach;      /* ceil(window_courant) + 1 */
    double *X, *mass, *minv;
    /* state */
    double *U, *V, *A, *Up, *beta, *slip_rate, *fprev;
    signed char *contact;
    double time, reaction, normal_force, grip_velocity, beta_removed, beta_produced;
    long long n_steps, clamp_count;
    /* derived from U: contact weights, and the first and last node where they are not 0 (w_first > w_last: none) */
    double *w;
    size_t w_first, w_last;
    size_t w0_first, w0_last; /* the work array w0 is 0 outside [w0_first, w0_last] */
    /* derived from the state: the friction limits mu P of the nodes that can reach the pad (tmax), at the
     * state's pressure and velocity; the next interval reuses them when its pressure and speed are the same */
    double *tmax;
    double limit_pressure, limit_speed;
    size_t limit_lo, limit_hi; /* the nodes [lo, hi) looked up, flagged in clamped */
    int limit_clamped;         /* a lookup was outside the table */
    double mu_least;           /* the least mu of these limits over the nodes under the pad (w > 0); NaN: none */
    /* slip_h > 0: slip_rate[i] is |dU[i]| / slip_h, formed when read (form_slip_rates) */
    double slip_h;
    /* every beta <= beta_hi, so a cap >= beta_hi changes no node away from the pad (NaN: not known) */
    double beta_hi;
    int refusal; /* enum tc_stripdraw_refusal of the last refused step */
    int u_finite; /* every U is finite after the last interval */
    const tc_step_kernels *kernels; /* the passes over the bar and the implicit step for this processor */
    /* work arrays */
    double *U0, *w0, *dU, *weight, *vel, *mu, *ac, *bsrc, *bnew, *awork;
    double *fwork;          /* explicit: nodal forces */
    double *gwork, *ov;     /* implicit: tc_sd_galpha work, and the overlaps of each halving level */
    size_t ov_first, ov_last; /* the first level's overlaps are 0 outside [ov_first, ov_last] */
    double *chain;          /* implicit: tc_sd_chain_factors of the last TC_SD_CHAIN_CACHE step lengths */
    double chain_h[TC_SD_CHAIN_CACHE];
    int chain_used, chain_next;
    double cap_pressure, cap_speed, cap_value; /* tc_law_beta_cap of the last (P, |V0|), when cap_known */
    int cap_known;
    /* the table rows the last lookup of the law made (a function of its pressure and velocity cell): the limits and
     * the cap of an interval, and the state's limits after it, at one pressure and grip speed, share them */
    tc_table_rows rows;
    unsigned char *clamped; /* table lookups flagged as clamped */
    signed char *giwork;
    /* the state before the current step: U, V, A, fprev by exchanging the arrays (bar_in_backup: from the step's
     * start to its first interval the bar's state is in bU, bV, bA, bfprev only, and U, V, A, fprev are free), the
     * rest copied */
    double *bU, *bV, *bA, *bfprev, *bUp, *bbeta, *bslip;
    signed char *bcontact;
    int bar_in_backup;
    double b_scalars[TC_SD_STEP_SCALARS]; /* the doubles a step changes (tc_stripdraw_state.c) */
    long long b_clamp_count;
    size_t state_size;
    double *pool;          /* every double array above, in one allocation */
    unsigned char *bytes;  /* contact, clamped, giwork and bcontact, in one allocation */
};

#endif
