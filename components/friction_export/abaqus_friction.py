"""The Abaqus form of the friction law: a *SURFACE INTERACTION with its tabulated *FRICTION.

What Abaqus reads: *FRICTION introduces friction into the mechanical surface interaction that *SURFACE INTERACTION
opens (Abaqus Keywords Reference, *FRICTION); isotropic friction data give per line the friction coefficient, then
the slip rate, the contact pressure, the average temperature at the contact point and the field variables, as many
as DEPENDENCIES says (the order of the Abaqus Scripting Reference's ContactTangentialBehavior table: mu, slip rate,
contact pressure, temperature, first field variable, ...). The lines are given with the first independent variable
varying fastest; Abaqus interpolates linearly in each of them between the values given and holds the end values
beyond them (Abaqus Analysis User's Guide, "Material data definition"; the reading of abq2ccx 1.6.0, an Abaqus deck
reader on PyPI, is the same).

Written here:

- with a debris state (``--beta``, ``--passes`` or ``--slide``): *FRICTION without DEPENDENCIES, lines ``mu, slip
  rate, contact pressure``, slip rate fastest;
- without one: *FRICTION, DEPENDENCIES=1 with beta as field variable 1, lines ``mu, slip rate, contact pressure,
  (temperature left blank: no temperature dependence), beta``, slip rate fastest, then pressure, then beta. The
  deck gives the nodes beta as field variable 1 (*INITIAL CONDITIONS, TYPE=FIELD, VARIABLE=1, or *FIELD,
  VARIABLE=1 in a step); user subroutines FRIC_COEF / VFRIC_COEF, which receive the accumulated slip, could evolve
  it within the analysis, which nothing here can run.

A law that does not depend on the slip rate (the shipped table's) is written without it: one line per pressure (and
beta) with the slip-rate field blank, which Abaqus reads as no slip-rate dependence (one value of an independent
variable: the property is constant in it, the end values held).
"""

from __future__ import annotations

import numpy as np

DEFAULT_NAME = "TRIBOCOSIM_FRICTION"
SUFFIX = ".inp"


def number(x: float) -> str:
    """A real for a data line: 13 significant digits."""
    return f"{x:.12E}"


def render(header: list[str], slip_rates: np.ndarray | None, pressures: np.ndarray, mu: np.ndarray, units,
           betas: np.ndarray | None = None, name: str = DEFAULT_NAME) -> str:
    """The *SURFACE INTERACTION and *FRICTION lines: ``mu[i, j]`` at pressure i and slip rate j, or ``mu[i, j, k]``
    at beta k too (``betas`` given), in file units. ``slip_rates`` None: mu does not depend on the slip rate
    (``mu[i, 0]``, ``mu[i, 0, k]``), one line per pressure (and beta) with the slip rate left blank."""
    lines = [*(f"** {h}" for h in header), "**", f"*SURFACE INTERACTION, NAME={name}"]
    rate = f"slip rate [{units.velocity}]" if slip_rates is not None else "slip rate (blank: no slip-rate dependence)"
    rates = [""] if slip_rates is None else [number(v) for v in slip_rates]
    if betas is None:
        lines += ["*FRICTION",
                  f"** mu, {rate}, contact pressure [{units.pressure}]"]
        lines += [f"{number(mu[i, j])}, {v}, {number(p)}"
                  for i, p in enumerate(pressures) for j, v in enumerate(rates)]
    else:
        lines += ["*FRICTION, DEPENDENCIES=1",
                  f"** mu, {rate}, contact pressure [{units.pressure}], temperature (none), beta (field variable 1)"]
        lines += [f"{number(mu[i, j, k])}, {v}, {number(p)}, , {number(b)}"
                  for k, b in enumerate(betas) for i, p in enumerate(pressures) for j, v in enumerate(rates)]
    return "\n".join(lines) + "\n"
