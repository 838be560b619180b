"""Parameters of the strip-draw model (one frozen dataclass, SI units, validated on creation).

Defaults are the paper's strip-draw test (AA5182-O, 1.5 mm sheet, 35 x 35 mm pad, 140 mm draw at
0.08 m/s; docs/model.md section 6); the flake-borne shear ratio is the documented floor's
(:mod:`tribocosim.components.stripdraw.friction_floor`), the paper's model one setting away
(flake_shear_ratio = 0). The field metadata (unit, description, allowed range) is the single source
for validation messages and for the FMU's variable declarations, so the two cannot drift.

Half model: one pad and one face are modelled (paper Fig. 1b). The bar carries half the sheet:
thickness h_B = sheet_thickness / 2 and width sheet_width; the pull force reported for the whole
strip is twice the axial force of the half model, so that mu = pull_force / (2 normal_force)
reads like Eq. 1.
"""

from __future__ import annotations

import dataclasses
import math

from tribocosim.components.params import param, parameters, validate_fields
from tribocosim.components.stripdraw.friction_floor import FLAKE_SHEAR_RATIO_DEFAULT

FRICTION_MODELS = ("table", "closed_form", "constant")
INTEGRATORS = ("explicit", "implicit")
TABLE_POLICIES = ("clamp", "error")
FRICTION_VELOCITIES = ("grip", "slip_rate")
CONTACT_AREAS = ("mesoscale", "eq8")
PARTICLE_AREA_RULES = ("load_bearing", "clusters")


_p = param


@parameters
class StripDrawParameters:
    """All parameters of the strip-draw model, SI units.

    Each field's metadata holds ``unit``, ``description`` and the allowed range (``low``,
    ``high``); ``__post_init__`` checks every field against it and raises
    :class:`~tribocosim.errors.ParameterError` naming the field, its value and the range.
    """

    # --- geometry -------------------------------------------------------------------------
    tool_length: float = _p(0.035, "m", "pad length L_T in the draw direction", 1e-4, 1.0)
    tool_width: float = _p(0.035, "m", "pad width w_T", 1e-4, 1.0)
    sheet_thickness: float = _p(1.5e-3, "m", "sheet thickness (the half model carries half of it)", 1e-5, 0.05)
    sheet_width: float = _p(0.1, "m", "sheet width", 1e-4, 2.0)
    draw_length: float = _p(0.14, "m", "longest draw the bar is built for", 0.0, 5.0)
    free_length: float = _p(0.05, "m", "free strip length between the pad's exit edge and the grip", 1e-4, 5.0)
    n_elements: int = _p(150, "1", "number of linear bar elements", 4, 200000, integer=True)
    # --- strip material -------------------------------------------------------------------
    youngs_modulus: float = _p(70e9, "Pa", "Young's modulus of the strip", 1e6, 1e13)
    density: float = _p(2660.0, "kg/m3", "density of the strip", 1.0, 1e5)
    # --- interface ------------------------------------------------------------------------
    # up to 1e4: the range the implicit solve converges on at a cost within ~10x of the default's
    # (tests/components/test_stripdraw_model.py); on the 140 mm pad at 30 MPa 1e5 costs 30x more than 1e4 and from
    # ~3e5 a step at the start of the draw is refused
    shear_stiffness_factor: float = _p(
        1.0, "1", "interface penalty k_s in units of E/h_B (Eq. 4: k_s ~ E/h_B)", 1e-6, 1e4
    )
    # --- debris (Eq. 12-14, 37) -----------------------------------------------------------
    archard_k: float = _p(1e-4, "1", "Archard wear coefficient K", 0.0, 1.0)
    hardness: float = _p(0.8e9, "Pa", "hardness H of the strip (HV 84 of AA5182-O)", 1e6, 1e12)
    zeta: float = _p(0.2, "1", "fraction of debris that sticks to the tool", 0.0, 1.0)
    particle_thickness: float = _p(0.5e-6, "m", "debris flake thickness h_p", 1e-9, 1e-3)
    beta_initial: float = _p(0.0, "1", "initial debris area fraction on the strip (multi-pass runs)", 0.0, 1.0)
    beta_threshold: float = _p(
        0.0, "1", "cap of beta (Eq. 24); 0 takes it from the friction law", 0.0, 1.0
    )
    debris_sink_length: float = _p(
        0.0, "m", "debris sink: slide lambda over which debris under the pad leaves the interface (lateral ejection "
        "or compaction into a transfer layer), d beta/ds = source - beta/lambda; 0: no sink (the paper's model)",
        0.0, 1e3
    )
    debris_carry_over: float = _p(
        1.0, "1", "share of the debris of the previous pass that a pass started from its field (field_input) keeps "
        "(1: all of it, the paper's repeated passes without cleaning)", 0.0, 1.0
    )
    # --- friction law (Eq. 6-9, 23) -------------------------------------------------------
    friction_model: str = _p("table", "", "friction law: table | closed_form | constant", choices=FRICTION_MODELS)
    mu0: float = _p(0.15, "1", "particle-free friction coefficient (calibration)", 0.0, 5.0)
    mu_const: float = _p(0.15, "1", "friction coefficient of the constant law", 0.0, 5.0)
    kappa: float = _p(2.0, "1", "contact-area constant kappa of Eq. 8", 1e-6, 100.0)
    rms_slope: float = _p(0.34, "1", "RMS slope h'_rms of the strip surface", 1e-6, 100.0)
    alpha_b: float = _p(
        207.91, "1", "alpha of Eq. 23 in the closed_form law, the amplitude b of alpha(v) = b (1 - exp(-v/v_ref)) "
        "(Fig. 15): the shipped campaign's straight-line fit of Eq. 23 at its slowest velocity, 0.08 m/s, over "
        "beta 0.02-1 at 1-30 MPa (standard error 6.6)", 0.0, 1e6
    )
    alpha_v_ref: float = _p(
        0.0, "m/s", "velocity scale v_ref of alpha(v) in the closed_form law; 0: alpha = alpha_b at every velocity "
        "(A_p of the shipped campaign does not depend on v at 0.08-0.5 m/s, and alpha falls with v at 1-50 m/s "
        "with the oil: no saturation law is fitted)", 0.0, 1e6
    )
    contact_area: str = _p(
        "mesoscale", "", "real contact area A_c in mu = mu0 (1 - A_p / A_c): mesoscale (from the friction table) | "
        "eq8 (the paper's Eq. 8, kappa P / (rms_slope e_star))", choices=CONTACT_AREAS
    )
    e_star: float = _p(55e9, "Pa", "effective modulus E* of Eq. 8 (eq8 contact area)", 1e6, 1e13)
    particle_area_scale: float = _p(
        1.0, "1", "factor on the particle-borne area A_p (1: as the mesoscale campaign measured it; "
        "fitted by tribocosim calibrate)", 0.0, 1e6
    )
    particle_area_rule: str = _p(
        "load_bearing", "", "which flakes carry A_p in the table law: load_bearing (every flake that bears load in the "
        "mesoscale contact: the paper's cluster rule, pinched and held flakes) | clusters (the paper's cluster rule "
        "alone, Fig. 8)", choices=PARTICLE_AREA_RULES
    )
    flake_shear_ratio: float = _p(
        FLAKE_SHEAR_RATIO_DEFAULT, "1", "shear strength of a flake-borne junction over the metal junction's tau0, r in "
        "mu = mu0 (1 - (1 - r) s A_p/A_c), so that mu = r mu0 where flakes carry the whole contact; default: the "
        "documented friction floor 0.03 over mu0 0.15 (sourced range 0.2-0.6, docs/model.md); 0: frictionless flakes, "
        "the paper's model", 0.0, 1.0
    )
    friction_velocity: str = _p(
        "grip", "", "velocity in mu(P, v, beta): grip (the pulling speed, as the paper) | slip_rate (each node's)",
        choices=FRICTION_VELOCITIES,
    )
    table_policy: str = _p(
        "clamp", "", "lookups outside the table: clamp (counted) | error", choices=TABLE_POLICIES
    )
    # --- numerics -------------------------------------------------------------------------
    integrator: str = _p("implicit", "", "bar integrator: explicit | implicit", choices=INTEGRATORS)
    cfl_safety: float = _p(0.9, "1", "explicit step as a fraction of the CFL limit", 1e-3, 1.0)
    rho_inf: float = _p(0.5, "1", "spectral radius at infinity of the generalized-alpha scheme", 0.0, 1.0)
    window_courant: float = _p(
        2.0, "1", "largest slide per coupling step, in elements (sets the debris/friction update step)", 1e-3, 100.0
    )
    internal_step: float = _p(
        0.0, "s", "fixed internal time grid k * internal_step: every requested step is cut at the grid points "
        "inside it, so that one step H and two steps H/2 take the same internal intervals when H/2 is a multiple "
        "of it (step-doubling error control); 0: the coupling intervals follow the requested step", 0.0, 1.0
    )

    def __post_init__(self) -> None:
        validate_fields(self)

    # --- derived quantities ---------------------------------------------------------------
    @property
    def bar_thickness(self) -> float:
        """h_B: thickness of the half-model bar [m]."""
        return 0.5 * self.sheet_thickness

    @property
    def bar_area(self) -> float:
        """Cross-section of the half-model bar [m^2]."""
        return self.sheet_width * self.bar_thickness

    @property
    def shear_stiffness(self) -> float:
        """Interface penalty k_s per unit area [Pa/m] (Eq. 4)."""
        return self.shear_stiffness_factor * self.youngs_modulus / self.bar_thickness

    @property
    def pad_area(self) -> float:
        """Nominal contact area of one pad, L_T w_T [m^2]."""
        return self.tool_length * self.tool_width

    def pressure(self, normal_force: float) -> float:
        """Nominal contact pressure P = F_N / (L_T w_T) [Pa] of a normal force [N] on one pad (uniform
        over the pad: the paper's choice)."""
        return normal_force / self.pad_area

    def normal_force(self, pressure: float) -> float:
        """The normal force [N] on one pad that gives the nominal pressure ``pressure`` [Pa]."""
        return pressure * self.tool_length * self.tool_width

    @property
    def wave_speed(self) -> float:
        """Bar wave speed sqrt(E/rho) [m/s]."""
        return math.sqrt(self.youngs_modulus / self.density)

    def replace(self, **changes) -> "StripDrawParameters":
        """A copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)


def parameter_fields() -> tuple[dataclasses.Field, ...]:
    """The dataclass fields of :class:`StripDrawParameters` (for adapters that declare variables)."""
    return dataclasses.fields(StripDrawParameters)
