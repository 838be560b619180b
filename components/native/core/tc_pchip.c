/* Monotone cubic Hermite interpolation along one line (tc_pchip.h).
 *
 * The values y_k at the nodes x_k are joined by the cubic Hermite pieces of Fritsch and Butland's monotone
 * interpolation (PCHIP, as scipy.interpolate.PchipInterpolator): with h_k = x_{k+1} - x_k and the secants
 * m_k = (y_{k+1} - y_k) / h_k, the slope at an interior node is 0 where m_{k-1} and m_k differ in sign or one is 0,
 * else the weighted harmonic mean
 *
 *     d_k = (w1 + w2) / (w1 / m_{k-1} + w2 / m_k),   w1 = 2 h_k + h_{k-1},  w2 = h_k + 2 h_{k-1},
 *
 * and at an end the one-sided three-point value d_0 = ((2 h_0 + h_1) m_0 - h_0 m_1) / (h_0 + h_1), set to 0 when its
 * sign differs from m_0's and to 3 m_0 when m_0 and m_1 differ in sign and |d_0| > 3 |m_0| (two nodes: the secant).
 * On [x_k, x_{k+1}], t = (x - x_k) / h_k, s = 1 - t:
 *
 *     y(x) = (1 + 2 t) s^2 y_k + t^2 (3 - 2 t) y_{k+1} + h_k t s (s d_k - t d_{k+1}).
 *
 * Each piece is monotone between its end values (no overshoot), a piece between equal values is flat, y is C1, and
 * the nodes are reproduced exactly. The slopes of a node are taken from its neighbours of the same kind (simulated
 * or not; a node alone of its kind takes every neighbour). On a piece between nodes of different kinds the two slopes
 * are limited to the square 0 <= d / m <= 3 of the piece's secant m, where a cubic Hermite piece is monotone
 * (Fritsch and Carlson), so that it too stays between its end values.
 */
#include "tc_pchip.h"

static double sgn(double v) { return (double)((v > 0) - (v < 0)); }

static double secant(const tc_pchip_line *L, size_t k) {
    return (L->y[(k + 1) * L->ys] - L->y[k * L->ys]) / (L->x[k + 1] - L->x[k]);
}

static int same_kind(const tc_pchip_line *L, size_t a, size_t b) {
    return L->u == NULL || L->u[a * L->us] == L->u[b * L->us];
}

/* the one-sided three-point slope at an end (h0, m0: the end's piece; h1, m1: the next), shape-preserving */
static double end_slope(double h0, double h1, double m0, double m1) {
    const double d = ((2.0 * h0 + h1) * m0 - h0 * m1) / (h0 + h1);
    if (sgn(d) != sgn(m0)) return 0.0;
    if (sgn(m0) != sgn(m1) && fabs(d) > 3.0 * fabs(m0)) return 3.0 * m0;
    return d;
}

double tc_pchip_slope(const tc_pchip_line *L, size_t k) {
    const size_t n = L->n;
    if (n < 2) return 0.0;
    const int left = k > 0 && same_kind(L, k - 1, k), right = k + 1 < n && same_kind(L, k + 1, k);
    if (!left && !right) {
        const tc_pchip_line all = {L->x, L->y, NULL, L->ys, 0, L->n};
        return tc_pchip_slope(&all, k);
    }
    const double *x = L->x;
    if (left && right) {
        const double m0 = secant(L, k - 1), m1 = secant(L, k);
        if (sgn(m0) != sgn(m1) || m0 == 0.0 || m1 == 0.0) return 0.0;
        const double h0 = x[k] - x[k - 1], h1 = x[k + 1] - x[k];
        const double w1 = 2.0 * h1 + h0, w2 = h1 + 2.0 * h0;
        return (w1 + w2) / (w1 / m0 + w2 / m1);
    }
    if (right) {
        if (k + 2 < n && same_kind(L, k + 2, k))
            return end_slope(x[k + 1] - x[k], x[k + 2] - x[k + 1], secant(L, k), secant(L, k + 1));
        return secant(L, k);
    }
    if (k >= 2 && same_kind(L, k - 2, k))
        return end_slope(x[k] - x[k - 1], x[k - 1] - x[k - 2], secant(L, k - 1), secant(L, k - 2));
    return secant(L, k - 1);
}

void tc_pchip_piece_slopes(const tc_pchip_line *L, size_t k, double *d0, double *d1) {
    if (same_kind(L, k, k + 1)) return;
    const double m = secant(L, k);
    *d0 = tc_pchip_limited(*d0, m);
    *d1 = tc_pchip_limited(*d1, m);
}
