/* Monotone cubic Hermite interpolation along one line of a grid (Fritsch and Butland's PCHIP, as
 * scipy.interpolate.PchipInterpolator, with the nodes in two kinds): the slopes at the nodes, the slopes of a piece
 * and the Hermite piece. The friction table's version 4 form and its lookups are built on it (tc_table.c,
 * tc_table_lookup.c); the equations are in tc_pchip.c. */
#ifndef TC_PCHIP_H
#define TC_PCHIP_H

#include <math.h>
#include <stddef.h>

/* One line: node positions x[k], values y[k * ys], kinds u[k * us] (nonzero: a node the campaign did not simulate;
 * u NULL: all of one kind), n nodes, x strictly increasing. */
typedef struct {
    const double *x, *y, *u;
    size_t ys, us, n;
} tc_pchip_line;

/* The slope at node k from its neighbours of its kind (every neighbour for a node alone of its kind); 0 for n < 2. */
double tc_pchip_slope(const tc_pchip_line *line, size_t k);

/* The slopes of the piece from node k to k + 1 from its nodes' slopes *d0, *d1 (in place): limited to the square
 * 0 <= d / m <= 3 of the piece's secant m where the two nodes differ in kind, else as they are. */
void tc_pchip_piece_slopes(const tc_pchip_line *line, size_t k, double *d0, double *d1);

/* A slope d limited to the square 0 <= d / m <= 3 of a piece's secant m, where a cubic Hermite piece is monotone
 * (Fritsch and Carlson). */
static inline double tc_pchip_limited(double d, double m) {
    if (m == 0.0 || (d > 0) - (d < 0) != (m > 0) - (m < 0)) return 0.0;
    return fabs(d) > 3.0 * fabs(m) ? 3.0 * m : d;
}

/* The cubic Hermite piece from (0, y0) with slope d0 to (h, y1) with slope d1 at t = x / h. */
static inline double tc_pchip_hermite(double y0, double y1, double d0, double d1, double h, double t) {
    const double s = 1.0 - t;
    return (1.0 + 2.0 * t) * s * s * y0 + t * t * (3.0 - 2.0 * t) * y1 + h * t * s * (s * d0 - t * d1);
}

#endif
