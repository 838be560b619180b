/* The friction table mu(P, v, beta) in memory: its axes, value arrays and checks.
 *
 * The table's format is owned by components/stripdraw/table.py (its docstring); the native code reads the
 * resource form the Python side converts it to (resource_io/tc_table_file.h). Lookups: tc_table_lookup.h. Axes
 * pressure [Pa], velocity [m/s], beta [-], strictly increasing; mu[(ip * n_velocity + iv) * n_beta + ib]
 * (C order of the (nP, nv, nb) array). Lookups outside the axes follow a policy: TC_TABLE_CLAMP
 * (evaluate at the nearest edge and flag the lookup) or TC_TABLE_ERROR (refuse, naming the quantity,
 * its value and the table's range).
 *
 * Interpolation: multilinear in (P, v, beta) for format versions 1-3; format version 4 interpolates monotone
 * cubic (Fritsch-Butland PCHIP, tc_pchip.h) in log P and in beta and linearly in v (tc_table_lookup.c), and the
 * strip-draw law reads the share A_p / A_c of each observable, which the table computes from its areas
 * (tc_table_set_cubic). Making a table version 4 also computes what the lookups of the arrays the law reads reuse
 * (tc_table_cubic): the slopes of every table row along beta, and the slopes of each piece along ln P of every column
 * of values and of row slopes; a lookup then evaluates Hermite pieces only.
 */
#ifndef TC_TABLE_H
#define TC_TABLE_H

#include <stddef.h>

#include "tc_common.h"

enum tc_table_policy { TC_TABLE_CLAMP = 0, TC_TABLE_ERROR = 1 };
enum tc_table_interpolation { TC_TABLE_MULTILINEAR = 0, TC_TABLE_MONOTONE_CUBIC = 1 };

/* the longest beta axis the monotone cubic interpolation takes (its lines are kept on the stack) */
#define TC_TABLE_BETA_MAX 64
/* a query within this of an axis end (relative to the end) is on the end, not outside: the round-off of the inputs
 * (12250 N on the 35 x 35 mm pad is 9999999.999999998 Pa; a press holding a set-point equal to the last pressure
 * delivers it to within 1e-15, on either side); components/stripdraw/table.py reads the same */
#define TC_TABLE_AXIS_END_TOLERANCE TC_BOUND_RTOL
/* the arrays of a version 4 table whose monotone cubic form is kept (tc_table_cubic): the shares A_p / A_c of every
 * load-bearing flake and of the cluster rule alone, and A_p / A0 of both (contact_area = eq8) */
#define TC_TABLE_N_CUBIC 4

/* The monotone cubic form of one array of a version 4 table (tc_table_lookup.c states the equations): with
 * plane = n_velocity * n_beta and the layout of mu,
 *   beta_slope[ip * plane + iv * n_beta + ib]   the PCHIP slope along beta of table row (ip, iv) at node ib;
 *   value_piece[0][...], value_piece[1][...]    the slopes along ln P at the left and right end of the piece from
 *                                               pressure node ip to ip + 1 of column (iv, ib) of values (limited
 *                                               where the two nodes differ in kind), for ip < n_pressure - 1;
 *   slope_piece[0][...], slope_piece[1][...]    the same for the columns of beta_slope.
 * The piece arrays are NULL on a one-point pressure axis. */
typedef struct tc_table_cubic {
    const double *values; /* the array (one of the table's) */
    double *beta_slope;
    double *value_piece[2], *slope_piece[2];
} tc_table_cubic;

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
    /* format version 4 (NULL before): ln P of the pressure axis, and the shares A_p / A_c of every load-bearing
     * flake and of the cluster rule alone (0 where A_c = 0), same layout as mu */
    double *log_pressure, *share, *share_clusters;
    /* version 4: the monotone cubic forms of share, share_clusters, particle_area and particle_area_clusters */
    tc_table_cubic cubic[TC_TABLE_N_CUBIC];
    /* each axis's ends widened by TC_TABLE_AXIS_END_TOLERANCE: a query below lo or above hi is outside it */
    double pressure_lo, pressure_hi, velocity_lo, velocity_hi, beta_lo, beta_hi;
    int interpolation;      /* TC_TABLE_MONOTONE_CUBIC in version 4, else TC_TABLE_MULTILINEAR */
    double beta_threshold;  /* metadata "beta_threshold": the cap of beta (Eq. 24), in (0, 1] */
    int format_version;     /* 4 with the monotone cubic interpolation, 3 with the version 3 arrays, 2 with the
                               areas, else 1 */
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

/* Make a version 3 table version 4: interpolated monotone cubic in log P and beta (tc_table_lookup.h), its shares
 * A_p / A_c and the monotone cubic forms (tc_table_cubic) computed. TC_ERROR (the table unchanged) unless the
 * pressure axis is > 0 and the beta axis has at most TC_TABLE_BETA_MAX nodes. */
TC_API int tc_table_set_cubic(tc_table *table, tc_msg msg);

/* The monotone cubic form of values (computed by tc_table_set_cubic) when it is one of the arrays whose form the
 * table keeps, else NULL. */
const tc_table_cubic *tc_table_cubic_of(const tc_table *table, const double *values);

/* The monotone cubic form of any array with the table's layout into *cubic (allocated: free it with
 * tc_table_cubic_free), for a table with a positive pressure axis. TC_NOMEM when an allocation fails. */
int tc_table_cubic_make(const tc_table *table, const double *values, tc_table_cubic *cubic, tc_msg msg);
void tc_table_cubic_free(tc_table_cubic *cubic);

TC_API void tc_table_free(tc_table *table);

/* The arrays of a table, for a writer that embeds it as constant data (the user friction routines:
 * components/friction_export/table_source.py): the members named in enum tc_table_part, and of form k of tc_table_cubic
 * (k < TC_TABLE_N_CUBIC, in the order of cubic[]) TC_TABLE_PART_CUBIC + 6 k + (0 values, 1 beta_slope,
 * 2 value_piece[0], 3 value_piece[1], 4 slope_piece[0], 5 slope_piece[1]). Returns the array (NULL where the table has
 * none) and its length in *n. */
enum tc_table_part {
    TC_TABLE_PART_PRESSURE = 0, TC_TABLE_PART_VELOCITY, TC_TABLE_PART_BETA, TC_TABLE_PART_MU,
    TC_TABLE_PART_CONTACT_AREA, TC_TABLE_PART_PARTICLE_AREA, TC_TABLE_PART_CONTACT_AREA_STD,
    TC_TABLE_PART_PARTICLE_AREA_STD, TC_TABLE_PART_UNSIMULATED, TC_TABLE_PART_PARTICLE_AREA_CLUSTERS,
    TC_TABLE_PART_LOG_PRESSURE, TC_TABLE_PART_SHARE, TC_TABLE_PART_SHARE_CLUSTERS, TC_TABLE_PART_CUBIC
};
TC_API const double *tc_table_part(const tc_table *table, int which, size_t *n);
/* The scalars of a table beside its sizes, in this order: pressure_lo, pressure_hi, velocity_lo, velocity_hi, beta_lo,
 * beta_hi, beta_threshold, format_version, interpolation. */
#define TC_TABLE_N_SCALARS 9
TC_API void tc_table_scalars(const tc_table *table, double out[TC_TABLE_N_SCALARS]);

#endif
