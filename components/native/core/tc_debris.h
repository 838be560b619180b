/* Debris production, transport and cap of the strip-draw model over one coupling interval (the equations are in
 * tc_debris.c). */
#ifndef TC_DEBRIS_H
#define TC_DEBRIS_H

#include <stddef.h>

#include "tc_common.h"

struct tc_stripdraw;

/* implicit upwind advection of beta under the pad (Eq. 13-14) of n_all nodes with the slip increments dU and the
 * contact weights weight: out = the new beta; work holds 5 n_all doubles. */
TC_API void tc_sd_advect(size_t n_all, const double *beta, const double *dU, const double *weight, double zeta,
                         double element_length, double *out, double *work);

/* Debris production (Eq. 37), transport (Eq. 13-14) and cap (Eq. 24) of the model's interval at pressure P and grip
 * speed from its increments m->dU (du_finite: every one finite), with the contact weights averaged over the interval
 * (m->w at its end, w0 at its start, nonzero within [f0, l0]): m->beta updated, what was made and removed added to
 * m->beta_produced and m->beta_removed. Only nodes where a weight is not 0 change (the source and the flux are 0
 * elsewhere), unless the cap falls below beta elsewhere. */
void tc_sd_debris_interval(struct tc_stripdraw *m, double pressure, double speed, const double *w0, size_t f0,
                           size_t l0, int du_finite);

#endif
