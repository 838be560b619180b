"""The multi-pass options: named sets of strip-draw parameters for how debris lives from one pass to the next.

docs/model.md sections 3-4 and "The floor under debris". The default model has flake-borne shear at the floor the
project sets (r = 0.2), no sink, and every flake carried into the next pass; the paper's model has frictionless flakes
(r = 0); the others change one of r (the upper end of its sourced range), the debris sink length lambda, or the share
of debris carried into the next pass. None of r, lambda or the carried share is measured: each is shown at values
that bracket what the literature and the mesoscale model allow (each option's ``why``). The paper report calibrates
every option on the paper's one-pass 35 % and predicts the rest (:mod:`tribocosim.cosim.reports.paper_physics`);
``tribocosim export --option NAME`` exports the law and passes of one of them.
"""

from __future__ import annotations

import dataclasses

from tribocosim.components.stripdraw.friction_floor import FLAKE_SHEAR_RATIO_RANGE, PAPER_MODEL

__all__ = ["OPTIONS", "Option", "option_names"]


@dataclasses.dataclass(frozen=True)
class Option:
    """A multi-pass option: the strip-draw parameters it changes, and why those values."""

    name: str
    label: str
    parameters: dict
    why: str


R_LOW, R_HIGH = FLAKE_SHEAR_RATIO_RANGE
OPTIONS = (
    Option("default", f"the default model (r = {R_LOW:g})", {},
           "flake-borne shear at the floor the project sets (r mu0 = 0.03 at full coverage: a bound chosen, not "
           "measured), no sink, every flake carried into the next pass (docs/model.md, the floor under debris)"),
    Option("paper", "the paper's model (r = 0)", dict(PAPER_MODEL),
           "frictionless flakes (r = 0), no sink, every flake carried into the next pass"),
    Option(f"shear_{R_HIGH:g}", f"flake-borne shear r = {R_HIGH:g}", {"flake_shear_ratio": R_HIGH},
           "the upper end of r's sourced range: a flake junction that shears like boundary-lubricated aluminium with "
           "an additive (mu 0.09, Tabary et al. 1996); r = 1 would remove the debris effect"),
    Option("sink_140", "the paper's model, debris sink lambda = 140 mm", {**PAPER_MODEL, "debris_sink_length": 0.14},
           "r = 0; lambda = one draw length: a flake leaves the interface after ~140 mm of sliding under the pad"),
    Option("sink_35", "the paper's model, debris sink lambda = 35 mm", {**PAPER_MODEL, "debris_sink_length": 0.035},
           "r = 0; lambda = the pad's width: ejected sideways after sliding about one pad width"),
    Option("carry_0.5", "the paper's model, half the debris carried over", {**PAPER_MODEL, "debris_carry_over": 0.5},
           "r = 0; half the debris falls off or is wiped from the strip between passes"),
)


def option_names() -> tuple[str, ...]:
    """The options' names, in :data:`OPTIONS`' order."""
    return tuple(o.name for o in OPTIONS)
