/* Lookups in the friction table mu(P, v, beta) (tc_table.h): trilinear, at one pressure for many (velocity, beta)
 * queries, in mu or in any array of the table with its layout. Outside the axes they follow the table policy:
 * TC_TABLE_CLAMP evaluates at the nearest edge and flags the query, TC_TABLE_ERROR refuses, naming the quantity, its
 * value and the table's range. */
#ifndef TC_TABLE_LOOKUP_H
#define TC_TABLE_LOOKUP_H

#include <stddef.h>

#include "tc_common.h"
#include "tc_table.h"

/* mu at one pressure for n (velocity, beta) queries (interpolate in P once, then bilinearly in (|v|, beta)).
 * clamped[k] (may be NULL) is set to 1 when query k (or the pressure) was outside the axes. Under TC_TABLE_ERROR
 * an outside query returns TC_DISCARD, naming the quantity, its value and the table's range, and writes
 * nothing. */
TC_API int tc_table_mu(const tc_table *table, double pressure, size_t n, const double *velocity,
                       const double *beta, int policy, double *mu, unsigned char *clamped, tc_msg msg);

/* The same lookup in any array of the table with its layout (mu, or an area array of a version 2 table). */
TC_API int tc_table_lookup(const tc_table *table, const double *values, double pressure, size_t n,
                           const double *velocity, const double *beta, int policy, double *out,
                           unsigned char *clamped, tc_msg msg);

/* Two arrays of the table at the same queries (A_p and A_c of the strip-draw law): the axes are located once
 * per query for both (and the velocity only when it differs from the query before). values_b and out_b may be
 * NULL (one array). */
TC_API int tc_table_lookup2(const tc_table *table, const double *values, const double *values_b, double pressure,
                            size_t n, const double *velocity, const double *beta, int policy, double *out,
                            double *out_b, unsigned char *clamped, tc_msg msg);

#endif
