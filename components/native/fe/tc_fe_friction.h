/* The user friction routines of forming FE codes over the friction of a contact point with its own debris state
 * (tc_node_friction.h): the arrays of Abaqus/Explicit VFRICTION, of Abaqus/Standard FRIC and of one LS-DYNA contact
 * node, in the deck's units, each point through tc_node_friction. The Fortran routines that the FE codes call
 * (components/friction_export/user_routines.py writes them) pass their arguments here through bind(C) interfaces; the
 * argument lists are those of the Abaqus User Subroutines Reference (VFRICTION, FRIC), cited in the routines' headers.
 *
 * The state of a point, in the FE code's state array: 1 beta (the debris area fraction; the FE code's initial state,
 * zero or the deck's initial conditions, is the debris the blank arrives with), 2 the accumulated slip (deck length),
 * 3 (when the deck gives a third) the number of increments whose lookup was outside the friction table's axes or read
 * a node the mesoscale campaign did not simulate. Every routine returns a status: TC_FE_OK, or why it cannot run
 * (the Fortran routine names it and stops the analysis). No global mutable state: everything a call needs is in its
 * arguments and in the law, which is constant data.
 */
#ifndef TC_FE_FRICTION_H
#define TC_FE_FRICTION_H

#include "tc_node_friction.h"

/* The law of the routines: the points' law, the deck's units (a length in the deck is length_scale m, a pressure
 * pressure_scale Pa; forces are N in both systems of components/friction_export/export_units.py) and the number the
 * deck's first property must hold (the export's check number: the deck and the routine belong to one export). */
typedef struct tc_fe_law {
    tc_node_law law;
    double length_scale, pressure_scale;
    double check;
} tc_fe_law;

#define TC_FE_MIN_STATES 2 /* beta and the accumulated slip */

enum tc_fe_status {
    TC_FE_OK = 0,
    TC_FE_TOO_FEW_STATES = 1, /* fewer than TC_FE_MIN_STATES state variables per point */
    TC_FE_WRONG_CHECK = 2,    /* no property, or the first is not the export's check number */
    TC_FE_BAD_SIZES = 3       /* an array size of the call that the routine cannot take */
};

/* Abaqus/Explicit VFRICTION, a block of n_block contact points (column-major arrays as Abaqus passes them):
 * dslip(n_dir, n_block) incremental slip, fstick(n_block) the force that sticks the point, fnormal(n_block) the normal
 * force, area(n_block) the contact area, state(n_states, n_nod_state, n_block) (the point's first node's states are
 * kept), ftang(n_fric_dir, n_block) the friction force written: component 1 (along the slip increment)
 * -min(mu F_N, fstick), the others 0. dt: the time increment. */
int tc_fe_vfriction(const tc_fe_law *fe, int n_block, int n_dir, int n_fric_dir, int n_states, int n_nod_state,
                    const double *props, int n_props, double dt, const double *dslip, const double *fstick,
                    const double *fnormal, const double *area, double *state, double *ftang);

/* Abaqus/Standard FRIC at one contact point: lm (in: 0 slipping, 1 sticking, 2 open at the last iteration or
 * increment; out: 0, relative motion allowed, or 2, open/frictionless), tau(nfdir) the friction stress (in: the
 * increment's start; out: its end), ddtddg(nfdir, nfdir), ddtddp(nfdir), dgam(nfdir) the increment's slip, press the
 * contact pressure, dtime, chrlngth the characteristic contact length, statev(nstatv) (at the increment's start on
 * every iteration). Elastic stick with the stiffness tau_crit / (TC_FE_SLIP_TOLERANCE chrlngth), tau_crit = mu p. */
#define TC_FE_SLIP_TOLERANCE 0.005
int tc_fe_fric(const tc_fe_law *fe, int *lm, double *tau, double *ddtddg, double *ddtddp, const double *dgam,
               double press, double dtime, double chrlngth, int nfdir, double *statev, int nstatv, const double *props,
               int nprops);

/* One LS-DYNA contact node: fnormal the normal force, area its contact area, dslip(n_dir) the slip increment, dt, hsv
 * (n_hsv) its history variables (the states above), uc(n_uc) the interface's user constants (the first: the check
 * number); fric(4) written as LS-DYNA's friction coefficients (static, dynamic, decay, viscous) = (mu, mu, 0, 0). */
int tc_fe_node(const tc_fe_law *fe, double fnormal, double area, const double *dslip, int n_dir, double dt,
               double *hsv, int n_hsv, const double *uc, int n_uc, double *fric);

#endif
