"""The floor under debris: the lowest friction coefficient the evidence supports in the strip-draw contact, and the
flake-borne shear ratio r it sets (docs/model.md, "The floor under debris").

The friction law with flake-borne shear (docs/model.md section 4):

    mu = mu0 [(1 - s A_p / A_c) + r s A_p / A_c] = mu0 (1 - (1 - r) s A_p / A_c)

r = tau_flake / tau0 is the shear strength of a junction carried by a flake over that of the lubricated metal
junction (tau0, fixed by mu0 = tau0 A_c / (P A0), Eq. 6). Debris is capped where flakes carry the whole real contact
(s A_p = A_c, Eq. 24): there mu = r mu0, the lowest value the law gives.

:data:`MU_FLOOR` is the documented floor, a bound the project sets for this oil-starved contact (1.12 g/m^2 of
mineral oil, at most a 1.30 um film against 1.52 um of combined RMS roughness: lambda <= 0.86, no full film) with
debris of aluminium and its oxide (the paper's EDS, Table 2); no source gives its value. The sources put a hydrodynamic
film at mu < 0.01 and boundary lubrication of aluminium with a boundary additive at 0.09 (Tabary et al., J. Tribol. 118
(1996) 629, doi:10.1115/1.2831584); a purpose-made lamellar solid lubricant (PVD MoS2) keeps 0.06 in long runs and
reaches 0.02 only at 77 K in high vacuum (Coatings 15 (2025) 500, introduction, citing Gradt et al.). The floor is half
the solid lubricant's long-run value, a factor of the project's choosing. Where flakes carry the whole contact it fixes
mu_bar, so a drop 1 - mu_bar(P) / mu_bar(1 MPa) is at most 1 - r mu0 / mu_bar(1 MPa): the paper report's floor scan
gives the 3-pass drop at each r.

:data:`FLAKE_SHEAR_RATIO_RANGE` is the range of r with mu0 = 0.15: from the floor the project sets (0.03 / 0.15) to a
flake junction that shears like boundary-lubricated aluminium with an additive (0.09 / 0.15, sourced). The default r is
its lower end: the paper's premise (flakes shear more easily than metal) kept down to the floor and no further.
:data:`PAPER_MODEL` is the paper's model, frictionless flakes.

A friction coefficient below the floor is reported, naming the setting that lets it (:func:`floor_note`): the
native FMU logs a warning once per instance, the Python model warns once (RangeWarning), the friction export warns
and writes the note into the file's header. The floor reaches the C code as ``TC_STRIPDRAW_MU_FLOOR``, generated from
:data:`MU_FLOOR` (the component's ``Native.constants``).

This module does no I/O and imports nothing of the model, so that the FMU glue and the friction exports can read it.
"""

from __future__ import annotations

from tribocosim.components.params import BOUND_RTOL

#: the documented floor of the friction coefficient in the strip-draw contact (module docstring)
MU_FLOOR = 0.03
#: the range of the flake-borne shear ratio r = tau_flake / tau0 at mu0 = 0.15, from the floor up (module docstring)
FLAKE_SHEAR_RATIO_RANGE = (0.2, 0.6)
#: the default r: the lower end of the range, MU_FLOOR / mu0 at the default mu0 = 0.15
FLAKE_SHEAR_RATIO_DEFAULT = 0.2
#: the parameters that make the paper's model of the default one: frictionless flakes (r = 0)
PAPER_MODEL = {"flake_shear_ratio": 0.0}


def mu_at_full_coverage(mu0: float, flake_shear_ratio: float) -> float:
    """mu = r mu0 where flakes carry the whole real contact (the cap, Eq. 24): the lowest mu of the table and
    closed-form laws."""
    return flake_shear_ratio * mu0


def below_floor(mu):
    """Whether a friction coefficient (or each of an array's) lies below :data:`MU_FLOOR` by more than the project's
    relative tolerance (:data:`tribocosim.components.params.BOUND_RTOL`, 1e-9 of the floor; ``tc_below`` of
    tc_common.h): the default
    r = 0.2 with mu0 = 0.15 gives the floor itself at the cap, up to the round-off of the law's sums, and is not
    below it."""
    return mu < MU_FLOOR - BOUND_RTOL * MU_FLOOR


def floor_note(mu: float, mu0: float, flake_shear_ratio: float, mu_const: float | None = None) -> str | None:
    """A one-line note when ``mu`` lies below :data:`MU_FLOOR` (:func:`below_floor`), naming the setting that lets it
    fall there (None otherwise): ``mu_const`` (given for the constant law), ``mu0`` (the most the law gives), the
    flake-borne shear ratio r with mu0 (r mu0, the least value of the table and closed-form laws), or else debris
    beyond the law's cap. The native model's note (``tc_law_floor_note`` of tc_friction.c) is the same text."""
    if not below_floor(mu):
        return None
    lowest = mu_at_full_coverage(mu0, flake_shear_ratio)
    if mu_const is not None:
        why = f"friction_model = constant with mu_const = {mu_const:g}; mu_const >= {MU_FLOOR:g} keeps mu at or above it"
    elif below_floor(mu0):
        why = f"mu0 = {mu0:g} is below it, and the law gives at most mu0 (no debris)"
    elif below_floor(lowest):
        why = (f"flake_shear_ratio = {flake_shear_ratio:g} with mu0 = {mu0:g} lets mu fall to {lowest:.4g} where flakes "
               f"carry the whole contact; flake_shear_ratio >= {MU_FLOOR / mu0:.4g} keeps mu at or above it")
    else:
        why = (f"the settings give at least {lowest:.4g} where flakes carry the whole contact (r mu0); a lower value "
               "comes from debris beyond the law's cap (beta_threshold above it, or debris made at another pressure "
               "or velocity)")
    return (f"mu = {mu:.4g} is below the documented floor {MU_FLOOR:g} of the strip-draw contact (docs/model.md, "
            f"the floor under debris): {why}")
