/* The friction table mu(P, v, beta) in memory, its trilinear lookup, and the reader of the table file.
 *
 * Mirrors tribocosim/components/stripdraw/table.py (the format's owner; read its docstring): axes
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
    double beta_threshold;  /* metadata "beta_threshold": the cap of beta (Eq. 24), in (0, 1] */
    int format_version;     /* metadata "format_version" */
    char content_hash[65];  /* metadata "content_hash": SHA-256, lowercase hex */
    char provenance[32];    /* metadata "provenance" ("mesoscale", "closed_form", ...) */
} tc_table;

/* A table from arrays (copied), checked as FrictionTable.__post_init__ checks them; content_hash and
 * provenance are left empty. */
TC_API int tc_table_from_arrays(size_t n_pressure, size_t n_velocity, size_t n_beta, const double *pressure,
                                const double *velocity, const double *beta, const double *mu,
                                double beta_threshold, tc_table **out, tc_msg msg);

/* Attach the version 2 arrays (copied; checked finite and >= 0 as FrictionTable.__post_init__ does) and make
 * the table version 2. */
TC_API int tc_table_set_areas(tc_table *table, const double *contact_area, const double *particle_area,
                              const double *contact_area_std, const double *particle_area_std, tc_msg msg);

/* Read and verify a table file written by table.write_table (the .npz): format name and version (1 or 2),
 * array shapes and values (version 2: the areas too), and the content hash recomputed exactly as table.py
 * computes it. */
TC_API int tc_table_read(const char *path, tc_table **out, tc_msg msg);

TC_API void tc_table_free(tc_table *table);

/* mu at one pressure for n (velocity, beta) queries, as FrictionTable.interpolate with a scalar
 * pressure (interpolate in P once, then bilinearly in (|v|, beta)). clamped[k] (may be NULL) is set to 1
 * when query k (or the pressure) was outside the axes. Under TC_TABLE_ERROR an outside query returns
 * TC_DISCARD with the message of table.py's TableDomainError and writes nothing. */
TC_API int tc_table_mu(const tc_table *table, double pressure, size_t n, const double *velocity,
                       const double *beta, int policy, double *mu, unsigned char *clamped, tc_msg msg);

/* The same lookup in any array of the table with its layout (mu, or an area array of a version 2 table):
 * FrictionTable.interpolate_array with a scalar pressure, bit for bit. */
TC_API int tc_table_lookup(const tc_table *table, const double *values, double pressure, size_t n,
                           const double *velocity, const double *beta, int policy, double *out,
                           unsigned char *clamped, tc_msg msg);

/* Two arrays of the table at the same queries (A_p and A_c of the strip-draw law), each bit for bit as
 * tc_table_lookup gives it: the axes are located once per query for both (and the velocity only when it
 * differs from the query before). values_b and out_b may be NULL (one array). */
TC_API int tc_table_lookup2(const tc_table *table, const double *values, const double *values_b, double pressure,
                            size_t n, const double *velocity, const double *beta, int policy, double *out,
                            double *out_b, unsigned char *clamped, tc_msg msg);

#endif
