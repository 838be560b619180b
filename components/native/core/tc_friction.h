/* The local friction law mu(P, v, beta) of the strip draw (paper Sec. 4, Eq. 6-9, 23-24; docs/model.md section 4).
 *
 * Bowden-Tabor with debris (Eq. 7 with Eq. 6) and a flake-borne contact of shear strength r tau0
 * (r = flake_shear_ratio; the paper's frictionless flakes: r = 0): mu = mu0 [(1 - s A_p / A_c) + r s A_p / A_c]
 * = mu0 (1 - (1 - r) s A_p / A_c), s = particle_area_scale. A_p is that of every load-bearing flake, or of the
 * paper's cluster rule alone (particle_area_rule = clusters; version 3 tables).
 *   - constant:     mu = mu_const; beta capped at 1;
 *   - closed_form:  A_p/A0 = alpha(v) beta P / E* (Eq. 23), A_c/A0 = kappa P / (h'_rms E*) (Eq. 8), so
 *                   mu = mu0 (1 - s alpha(v) beta h'_rms / kappa) (Eq. 9), alpha(v) = b (1 - exp(-|v| / v_ref))
 *                   when v_ref > 0, else b; cap kappa / (s b h'_rms), limited to 1;
 *   - table:        A_p (and A_c under contact_area = mesoscale) interpolated in a friction table (tc_table.h);
 *                   A_c = kappa P / (h'_rms E*) under contact_area = eq8; mu >= 0. A lookup that reads a node the
 *                   campaign did not simulate (simulated = 0, with a weight above TC_TABLE_READ_WEIGHT) is flagged
 *                   like one outside the axes. A table without the areas (format version 1) gives its mu as it is.
 *                   Versions 2 and 3 interpolate A_p and A_c multilinearly and divide; version 4 interpolates (monotone
 *                   cubic, tc_table_lookup.h) what mu is linear in: the share A_p / A_c (mesoscale) or A_p (eq8).
 *                   The cap of beta at (P, v) is where s A_p reaches A_c along the table's beta axis, limited to 1:
 *                   versions 2-3 solve the linear pieces exactly; version 4 finds the first crossing of s times the
 *                   interpolated share (or A_p) with 1 (or A_c of Eq. 8) on its cubic pieces by bisection of their
 *                   monotone parts, to within TC_TABLE_CROSSING_TOL in beta and from below. The law's threshold is
 *                   the largest such cap over the table's (P > 0, v) nodes.
 * The velocity v is the grip speed or each node's slip rate (the caller chooses, friction_velocity).
 */
#ifndef TC_FRICTION_H
#define TC_FRICTION_H

#include <stddef.h>

#include "tc_common.h"
#include "tc_stripdraw_params.h"
#include "tc_table.h"
#include "tc_table_lookup.h"

/* s A_p "reaches" A_c within this relative tolerance (a table tabulated to its cap) */
#define TC_REACH_RTOL 1e-12

/* TC_ERROR when the parameters ask for what the table cannot give (contact_area = eq8 or s != 1 with a table
 * without the areas), or for the table law without a table. */
TC_API int tc_law_check(const tc_stripdraw_params *p, const tc_table *table, tc_msg msg);

/* mu at one pressure for n (velocity, beta) queries; clamped[k] (may be NULL) is 1 when query k was outside the
 * table (clamp policy); ac_work holds n doubles. Under table_policy = error an outside query is TC_DISCARD, with
 * nothing written. rows (may be NULL): the interpolated table rows a caller keeps (tc_table_rows), shared with
 * tc_law_beta_cap at the same pressure and speed. */
TC_API int tc_law_mu(const tc_stripdraw_params *p, const tc_table *table, double pressure, size_t n,
                     const double *velocity, const double *beta, double *mu, unsigned char *clamped,
                     double *ac_work, tc_table_rows *rows, tc_msg msg);

/* The largest cap of beta (Eq. 24) of the law, and its cap at (P, |v|) (the threshold when P = 0 or the law does
 * not depend on P and v; rows as tc_law_mu's). */
TC_API double tc_law_beta_threshold(const tc_stripdraw_params *p, const tc_table *table);
TC_API double tc_law_beta_cap(const tc_stripdraw_params *p, const tc_table *table, double pressure, double speed,
                              tc_table_rows *rows);
/* min(beta, tc_law_beta_cap(p, table, pressure, speed, rows)) for a beta <= 1, the same number, without the search
 * for a cap above beta (a point's debris update: tc_node_friction.c). */
TC_API double tc_law_beta_capped(const tc_stripdraw_params *p, const tc_table *table, double pressure, double speed,
                                 double beta, tc_table_rows *rows);

/* alpha(v) of Eq. 23 (closed form). */
TC_API double tc_law_alpha(const tc_stripdraw_params *p, double velocity);

/* Whether mu lies below the documented floor TC_STRIPDRAW_MU_FLOOR (components/stripdraw/friction_floor.py, generated
 * from its MU_FLOOR) by more than TC_BOUND_RTOL of it: 1, with a one-line note into msg naming the setting of p that
 * lets mu fall there (mu_const of the constant law, mu0, flake_shear_ratio with mu0: the law's least value r mu0 where
 * flakes carry the whole contact, or else debris beyond the law's cap), the text friction_floor.floor_note gives;
 * else 0, msg untouched. The default r = 0.2 with mu0 = 0.15 gives the floor itself at the cap: not below. */
TC_API int tc_law_floor_note(const tc_stripdraw_params *p, double mu, tc_msg msg);

#endif
