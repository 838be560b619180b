/* The debris one point of the strip makes over one slide (paper Sec. 3, Eq. 37; docs/model.md section 3): the Archard
 * production and the sink, the one formula of the strip-draw model's nodes (tc_debris.c) and of a forming code's
 * contact points (tc_node_friction.c).
 *
 * Over a slide of |du| with contact weight w (the share of the point's segment under the tool; 1 for a point in full
 * contact) at pressure P, the slide under the tool is s = w |du| and the source (Eq. 37) q s with q = K P / (H h_p),
 * formed as (K P) |du| w / (H h_p): beta + q s without a sink. With the sink (lambda > 0: lateral ejection or
 * compaction into a transfer layer) source and sink are one local equation d beta / ds = q - beta / lambda, integrated
 * exactly over s: beta e^(-s / lambda) + q lambda (1 - e^(-s / lambda)). The cap (Eq. 24) is the caller's.
 */
#ifndef TC_DEBRIS_NODE_H
#define TC_DEBRIS_NODE_H

#include <math.h>

/* The Archard source q s of a slide: kp = K P, hh = H h_p, du_abs = |du|, weight = w (0: no source). */
static inline double tc_debris_source(double du_abs, double weight, double kp, double hh) {
    return weight == 0.0 ? 0.0 : kp * du_abs * weight / hh;
}

/* beta after a slide s = w |du| > 0 with the sink of length lambda > 0 and the source src = tc_debris_source(...), from
 * *beta at the slide's start: d beta / ds = q - beta / lambda (q = src / s) integrated exactly over the slide (*beta is
 * read after the exponential, so that the strip's loop keeps its operations in the order it has always had them). */
static inline double tc_debris_sunk(const double *beta, double src, double slide, double lambda) {
    const double decay = exp(-slide / lambda);
    return *beta * decay + (src == 0.0 ? 0.0 : src / slide * lambda * -expm1(-slide / lambda));
}

#endif
