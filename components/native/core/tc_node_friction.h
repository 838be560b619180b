/* The friction of one contact point of a forming simulation with its own debris state: the strip-draw model's law and
 * debris production at a point of a sheet sliding under a tool (paper Sec. 3-4, Eq. 6-9, 23-24, 37; docs/model.md
 * sections 3-4), what the user friction routines of Abaqus and LS-DYNA evaluate (components/native/fe/tc_fe_friction.c,
 * written out by components/friction_export/user_routines.py).
 *
 * One increment of the FE code at a point in contact, pressure P (normal force over contact area), slip increment ds
 * (its magnitude |ds|) over the increment's time dt, debris area fraction beta at the increment's start:
 *   - slip rate v = |ds| / dt (0 when dt = 0);
 *   - mu = mu(P, v, beta) of the strip's law (tc_law_mu of tc_friction.c, the same parameters and table lookup), from
 *     the state at the increment's start, as the strip holds mu over a coupling interval at its start's debris;
 *   - then beta from the increment's slide: the Archard production q |ds| with q = K P / (H h_p) (Eq. 37) and the sink
 *     lambda integrated exactly (tc_debris_source and tc_debris_sunk of tc_debris_node.h, the strip's own formulas, at
 *     contact weight 1),
 *     capped at the law's cap at (P, v) (Eq. 24: tc_law_beta_cap, never above the law's largest cap beta_cap), as the
 *     strip caps its nodes at the interval's pressure and speed.
 * A point whose pressure is not > 0 (open, or no normal force) bears no friction and keeps its state.
 *
 * What one point's state cannot hold: in the strip model the tool carries the share zeta of the debris with it
 * (Eq. 13-14), from node to node under the pad; a point here keeps the debris it makes (zeta = 0). Lookups are made
 * under the clamp policy: outside the table's axes the law holds its edge values, and the lookup is flagged.
 */
#ifndef TC_NODE_FRICTION_H
#define TC_NODE_FRICTION_H

#include "tc_common.h"
#include "tc_friction.h"
#include "tc_stripdraw_params.h"
#include "tc_table.h"
#include "tc_table_lookup.h"

/* The law of the points: the strip-draw parameters (friction model, mu0, r, s, K, H, h_p, lambda, beta_threshold; the
 * table policy is clamp whatever p says), the table (friction_model = table) and the cap that holds everywhere
 * (p.beta_threshold when > 0, else tc_law_beta_threshold of the law: a constant of the law, made once). */
typedef struct tc_node_law {
    tc_stripdraw_params p;
    const tc_table *table;
    double beta_cap;
} tc_node_law;

/* The cap of beta that holds everywhere for the parameters and the table: p->beta_threshold when > 0, else the law's
 * largest cap (tc_law_beta_threshold). */
TC_API double tc_node_law_cap(const tc_stripdraw_params *p, const tc_table *table);

/* Make a law from parameters and a table (copied; the table borrowed): TC_ERROR naming what is not allowed (a parameter
 * outside its range, a law the table cannot give). */
TC_API int tc_node_law_make(const tc_stripdraw_params *p, const tc_table *table, tc_node_law *out, tc_msg msg);

/* One increment of one point (the equations above): pressure [Pa], slip = |ds| [m], dt [s]; *beta is the point's
 * debris at the increment's start and is updated to its end. Returns mu (0 and *beta unchanged when pressure is not
 * > 0 or an input is not finite). *flagged (may be NULL) is set to 1 when the lookup was outside the table or read a
 * node the campaign did not simulate (or an input was refused), else 0. rows: the table rows of the last lookup,
 * zeroed before its first use (tc_table_rows; points at one pressure share them). */
TC_API double tc_node_friction(const tc_node_law *law, double pressure, double slip, double dt, double *beta,
                               int *flagged, tc_table_rows *rows);

/* The two halves of tc_node_friction for n points at one pressure > 0 (finite inputs): mu from their slip rates
 * (|ds| / dt) and their beta at the increment's start, flagged[k] as tc_node_friction's (one lookup for the n points,
 * as the strip looks up its nodes); work holds n doubles. */
TC_API void tc_node_mu(const tc_node_law *law, double pressure, size_t n, const double *rate, const double *beta,
                       double *mu, unsigned char *flagged, double *work, tc_table_rows *rows);
/* and one point's beta at the increment's end from its slip |ds|, its slip rate and its beta at the start. */
TC_API double tc_node_debris(const tc_node_law *law, double pressure, double slip, double rate, double beta,
                             tc_table_rows *rows);

/* The debris of a point that slides `slide` [m] at a constant pressure and slip rate from beta0 (a sheet point under a
 * die radius or a blankholder; the table the exports write for codes without user routines, --slide): for each of the
 * n points (pressure[k] > 0, rate[k] >= 0) beta[k] is tc_node_debris of one increment of the whole slide, with the law
 * made from p and table by tc_node_law_make. One increment is the slide's many: the production is linear in the slide
 * and the sink's exact integral composes (e^-a e^-b = e^-(a+b)), so a point that slides S in any increments at
 * constant (P, v) reaches the same beta to rounding; the cap at (P, v) is a constant of the point and the update is
 * monotone in beta, so capping after each increment or at the end gives the same. Without the sink and below the cap
 * beta = beta0 + K P S / (H h_p); with it, beta0 e^(-S/lambda) + q lambda (1 - e^(-S/lambda)). TC_ERROR naming the
 * value for a law tc_node_law_make refuses, a pressure not > 0, a rate < 0, a slide < 0, a beta0 outside [0, 1], or
 * one of them not finite. */
TC_API int tc_node_slide(const tc_stripdraw_params *p, const tc_table *table, size_t n, const double *pressure,
                         const double *rate, double slide, double beta0, double *beta, tc_msg msg);

#endif
