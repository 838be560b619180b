/* Lookups in the friction table mu(P, v, beta) (tc_table.h), at one pressure for many (velocity, beta) queries, in
 * mu or in any array of the table with its layout: multilinear (format versions 1-3) or monotone cubic in log P and
 * beta and linear in v (version 4; tc_table_lookup.c states the equations). Outside the axes they follow the table
 * policy: TC_TABLE_CLAMP evaluates at the nearest edge and flags the query, TC_TABLE_ERROR refuses, naming the
 * quantity, its value and the table's range.
 *
 * A lookup reads the corners of its cell whose weight, the product of the local coordinates (1 - t or t per axis, t in
 * log P on a version 4 table's pressure axis), exceeds TC_TABLE_READ_WEIGHT; the weights of a lookup sum to 1. A
 * lookup is flagged (clamped) when it is outside an axis or reads a node the campaign did not simulate. */
#ifndef TC_TABLE_LOOKUP_H
#define TC_TABLE_LOOKUP_H

#include <stddef.h>

#include "tc_common.h"
#include "tc_table.h"

/* a node is read by a lookup when its weight exceeds this (relative: the weights of a lookup sum to 1) */
#define TC_TABLE_READ_WEIGHT 1e-9
/* the crossing of a line with a level (tc_table_first_crossing) is found to within this in the line's x, from below */
#define TC_TABLE_CROSSING_TOL 1e-12

/* The two (v, beta) rows of one array of a version 4 table at one pressure and one velocity cell (table velocities iv
 * and iv + 1): their values at the beta nodes and the end slopes of each of their pieces along beta (limited), made from
 * the table's monotone cubic form (tc_table_cubic); what every query at that pressure and in that cell evaluates, and
 * at each beta node the largest weight in P of an unsimulated node the row reads (0: none). A caller that keeps one
 * (zeroed before its first use) lets the lookups of an array of the table at the same pressure and velocity cell
 * share it (the friction law and the cap of beta of one interval): its content is a function of its key (table,
 * array, pressure, cell), so a lookup gives the same numbers with or without it. */
typedef struct tc_table_rows {
    const tc_table *table;
    const double *values;
    double pressure;
    size_t iv;
    int filled; /* how many of the two rows are made (the second one only when a query lies inside the cell) */
    size_t ip;
    double tp;
    double y[2][TC_TABLE_BETA_MAX], dl[2][TC_TABLE_BETA_MAX], dr[2][TC_TABLE_BETA_MAX];
    double unsimulated[2][TC_TABLE_BETA_MAX];
    unsigned char unsimulated_cell[2][TC_TABLE_BETA_MAX]; /* whether either node of beta cell ib has such a weight */
    int reads_unsimulated; /* whether an unsimulated weight above TC_TABLE_READ_WEIGHT is among them */
    /* the line along beta at the local velocity coordinate line_tv of the cell (when line_made): the rows blended,
     * (1 - tv) row 0 + tv row 1, in values and piece slopes (a Hermite piece is linear in its data, so the line's
     * piece is the blend of the rows' pieces); what every query at that velocity evaluates */
    int line_made;
    double line_tv;
    double line_y[TC_TABLE_BETA_MAX], line_dl[TC_TABLE_BETA_MAX], line_dr[TC_TABLE_BETA_MAX];
    unsigned char line_unsimulated[TC_TABLE_BETA_MAX]; /* whether piece k's cell has a node of unsimulated weight */
} tc_table_rows;

/* mu at one pressure for n (velocity, beta) queries (interpolate in P once, then in (|v|, beta)).
 * clamped[k] (may be NULL) is set to 1 when query k (or the pressure) was outside the axes or read a node the
 * campaign did not simulate. Under TC_TABLE_ERROR a query outside the axes returns TC_DISCARD, naming the quantity,
 * its value and the table's range, and writes nothing. */
TC_API int tc_table_mu(const tc_table *table, double pressure, size_t n, const double *velocity,
                       const double *beta, int policy, double *mu, unsigned char *clamped, tc_msg msg);

/* The same lookup in any array of the table with its layout (mu, an area array, a share). */
TC_API int tc_table_lookup(const tc_table *table, const double *values, double pressure, size_t n,
                           const double *velocity, const double *beta, int policy, double *out,
                           unsigned char *clamped, tc_msg msg);

/* Two arrays of the table at the same queries (A_p and A_c of the strip-draw law): the axes are located once
 * per query for both (and the velocity only when it differs from the query before). values_b and out_b may be
 * NULL (one array). rows (may be NULL) holds the rows of values a version 4 table's lookup made last (tc_table_rows).
 * TC_NOMEM when the monotone cubic form of an array that is not one the table keeps cannot be made. */
TC_API int tc_table_lookup2(const tc_table *table, const double *values, const double *values_b, double pressure,
                            size_t n, const double *velocity, const double *beta, int policy, double *out,
                            double *out_b, unsigned char *clamped, tc_table_rows *rows, tc_msg msg);

/* The nodes a lookup at (P, |v|, beta) reads (the corners of its cell with a weight above TC_TABLE_READ_WEIGHT):
 * their flat indices into the (nP, nv, nb) arrays and their weights, at most 8; returns their count. *outside (may be
 * NULL) is set to whether the query is outside an axis (it is then located at the nearest edge). */
TC_API size_t tc_table_read_nodes(const tc_table *table, double pressure, double velocity, double beta,
                                  size_t nodes[8], double weights[8], int *outside);

/* The line of one array of a version 4 table along beta at (P, |v|), clamped to the axes: its values at the beta
 * nodes, y[n_beta], and the slopes of each piece at its left and right end, dl[n_beta - 1] and dr[n_beta - 1]: the
 * piecewise cubic Hermite a lookup evaluates in beta. rows (may be NULL): as tc_table_lookup2's. TC_ERROR for a table
 * of another version. */
TC_API int tc_table_beta_line(const tc_table *table, const double *values, double pressure, double velocity,
                              double *y, double *dl, double *dr, tc_table_rows *rows, tc_msg msg);

/* The first x at which the piecewise cubic Hermite line through (x[k], y[k]) with the piece end slopes dl[k], dr[k]
 * (k < n - 1) reaches level: returns 1 and sets *at (x[0] when y[0] >= level; else within TC_TABLE_CROSSING_TOL below
 * the crossing, where the line is still below level), or 0 when the line stays below level. Each piece is split at
 * the zeros of its derivative into monotone parts, and the first part that reaches level is bisected: the first
 * crossing is found even where the line is not monotone. */
TC_API int tc_table_first_crossing(size_t n, const double *x, const double *y, const double *dl, const double *dr,
                                   double level, double *at);
/* The same search over the pieces that start at or below limit only: where the first crossing is at or below limit it
 * is found as tc_table_first_crossing finds it; otherwise 0, or a crossing above limit (so that min(limit, *at) is
 * min(limit, the first crossing) either way). */
TC_API int tc_table_first_crossing_below(size_t n, const double *x, const double *y, const double *dl, const double *dr,
                                         double level, double limit, double *at);

#endif
