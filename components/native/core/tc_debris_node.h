/* The debris of one point of the strip over one slide (paper Sec. 3, Eq. 24, 37; docs/model.md section 3): the Archard
 * production and the sink, the one formula of the strip-draw model's nodes (tc_debris.c) and of a forming code's
 * contact points (tc_node_friction.c).
 *
 * Over a slide of |du| with contact weight w (the share of the point's segment under the tool; 1 for a point in full
 * contact) at pressure P, the interval's slide is s = w |du| and the source (Eq. 37) q s with q = K P / (H h_p),
 * formed as (K P) |du| w / (H h_p). With the sink (lambda > 0: lateral ejection or compaction into a transfer layer)
 * source and sink are one local equation d beta / ds = q - beta / lambda, integrated exactly over s:
 * beta e^(-s / lambda) + q lambda (1 - e^(-s / lambda)). The cap (Eq. 24) is the caller's.
 */
#ifndef TC_DEBRIS_NODE_H
#define TC_DEBRIS_NODE_H

#include <math.h>

/* beta after the slide (before the cap): kp = K P, hh = H h_p, du_abs = |du|, weight = w, lambda the sink length (0:
 * none); *source is set to the Archard source, and what the sink took is added to *sunk. */
static inline double tc_debris_slide(double beta, double du_abs, double weight, double kp, double hh, double lambda,
                                     double *source, double *sunk) {
    const double slide = weight * du_abs; /* s of the slide under the tool */
    const double src = weight == 0.0 ? 0.0 : kp * du_abs * weight / hh;
    double out = beta + src;
    if (lambda > 0 && slide > 0) {
        /* d beta / ds = q - beta / lambda (q = src / slide) integrated exactly over the slide */
        const double decay = exp(-slide / lambda);
        const double b = beta * decay + (src == 0.0 ? 0.0 : src / slide * lambda * -expm1(-slide / lambda));
        *sunk += out - b;
        out = b;
    }
    *source = src;
    return out;
}

#endif
