/* The friction table mu(P, v, beta) in memory, its trilinear lookup, and the reader of the table file.
 *
 * The table's format is owned by components/stripdraw/table.py (its docstring); the native code reads the
 * resource form the Python side converts it to (tc_table_file.c). Axes
 * pressure [Pa], velocity [m/s], beta [-], strictly increasing; mu[(ip * n_velocity + iv) * n_beta + ib]
 * (C order of the (nP, nv, nb) array). Lookups outside the axes follow a policy: TC_TABLE_CLAMP
 * (evaluate at the nearest edge and flag the lookup) or TC_TABLE_ERROR (refuse, naming the quantity,
 * its value and the table's range).
 */
#ifndef TC_TABLE_H
#define TC_TABLE_H

#include <stddef.h>

#include "tc_common.h"

enum tc_table_policy { TC_TABLE_CLAMP = 0, TC_TABLE_ERROR = 1 };

typedef struct tc_table {
    size_t n_pressure, n_velocity, n_beta;
    double *pressure; /* [n_pressure] */
    double *velocity; /* [n_velocity] */
    double *beta;     /* [n_beta] */
    double *mu;       /* [n_pressure * n_velocity * n_beta] */
    /* format version 2 (NULL in version 1): ensemble means of A_c/A0 and A_p/A0 and their member spreads,
     * same layout as mu */
    double *contact_area, *particle_area, *contact_area_std, *particle_area_std;
    /* format version 3 (NULL before): 1 - simulated (1 where the node holds its row's fit, not slides), and A_p/A0
     * of the paper's cluster rule alone, same layout as mu */
    double *unsimulated, *particle_area_clusters;
    double beta_threshold;  /* metadata "beta_threshold": the cap of beta (Eq. 24), in (0, 1] */
    int format_version;     /* 3 with the version 3 arrays, 2 with the areas, else 1 */
    char content_hash[65];  /* the table's content hash (SHA-256, lowercase hex), "" when not known */
    char provenance[32];    /* where the values come from ("mesoscale", "closed_form", ...) */
} tc_table;

/* A table from arrays (copied), checked: non-empty strictly increasing finite axes (velocity and beta >= 0),
 * finite mu >= 0, beta_threshold in (0, 1]; content_hash and provenance are left empty. */
TC_API int tc_table_from_arrays(size_t n_pressure, size_t n_velocity, size_t n_beta, const double *pressure,
                                const double *velocity, const double *beta, const double *mu,
                                double beta_threshold, tc_table **out, tc_msg msg);

/* Attach the version 2 arrays (copied; checked finite and >= 0) and make the table version 2. */
TC_API int tc_table_set_areas(tc_table *table, const double *contact_area, const double *particle_area,
                              const double *contact_area_std, const double *particle_area_std, tc_msg msg);

/* Attach the version 3 arrays of a version 2 table (copied; simulated 0 or 1, the areas finite and >= 0) and make
 * the table version 3. */
TC_API int tc_table_set_extras(tc_table *table, const double *simulated, const double *particle_area_clusters,
                               tc_msg msg);

/* Read the friction table resource (an array file, tc_table_file.c) at path; a path ending in .npz names the
 * resource beside it ending in .tca. TC_ERROR naming the path when it is missing or malformed. */
TC_API int tc_table_read(const char *path, tc_table **out, tc_msg msg);

TC_API void tc_table_free(tc_table *table);

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
