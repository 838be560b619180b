"""Local friction laws mu(P, v, beta) behind one interface (paper Sec. 4, Eq. 6-9, 23-24).

Bowden-Tabor with debris (Eq. 7): mu = tau0 (A_c - A_p) / (P A0), with
A_c / A0 = kappa P / (h'_rms E*) (Eq. 8) and A_p / A0 = alpha(v) beta P / E* (Eq. 23), so

    mu = (tau0 / E*) (kappa / h'_rms - alpha(v) beta)                       (Eq. 9 with Eq. 23)

Calibrating with the particle-free coefficient mu0 = tau0 kappa / (E* h'_rms) (Eq. 6 at beta = 0)
removes tau0 and E*:

    mu = mu0 (1 - alpha(v) beta h'_rms / kappa),   alpha(v) = b (1 - exp(-|v| / v_ref)).

b and v_ref are PROVISIONAL defaults (the paper does not print them; Fig. 15): the surrogate
issue fits them to mesoscale runs. Which velocity v is (the pulling speed or each node's slip
rate) is the model's ``friction_velocity`` parameter (see :mod:`tribocosim.components.stripdraw.model`).

The cap of beta (Eq. 24, A_p <= A_c) is beta_thres = kappa / (alpha h'_rms). We evaluate it with
the largest alpha, its saturation value b, so that A_p <= A_c holds at every velocity and mu never
turns negative; it is further limited to 1 (beta is an area fraction).

Three laws share the interface ``mu(pressure, velocity, beta) -> (mu, clamped)``:
``constant`` (mu_const), ``closed_form`` (above) and ``table`` (a :class:`FrictionTable` built
from mesoscale runs, the design's default).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tribocosim.components.errors import ParameterError
from tribocosim.components.stripdraw.parameters import StripDrawParameters
from tribocosim.components.stripdraw.table import FrictionTable


@dataclass(frozen=True)
class ConstantFriction:
    """mu = mu_const everywhere; debris does not change friction (beta is capped at 1)."""

    mu_const: float
    beta_threshold: float = 1.0
    name: str = "constant"

    def mu(self, pressure, velocity, beta):
        """Return ``(mu, clamped)`` broadcast over the inputs."""
        shape = np.broadcast(np.asarray(pressure), np.asarray(velocity), np.asarray(beta)).shape
        return np.full(shape, self.mu_const), np.zeros(shape, dtype=bool)


@dataclass(frozen=True)
class ClosedFormFriction:
    """mu = mu0 (1 - alpha(v) beta h'_rms / kappa) with alpha(v) = b (1 - exp(-|v|/v_ref))."""

    mu0: float
    kappa: float
    rms_slope: float
    alpha_b: float
    alpha_v_ref: float
    name: str = "closed_form"

    def alpha(self, velocity):
        """alpha(v) of Eq. 23 (exponential saturation, Fig. 15)."""
        return self.alpha_b * -np.expm1(-np.abs(np.asarray(velocity, float)) / self.alpha_v_ref)

    @property
    def beta_threshold(self) -> float:
        """Eq. 24 with the saturated alpha = b, limited to 1."""
        if self.alpha_b <= 0:
            return 1.0
        return min(1.0, self.kappa / (self.alpha_b * self.rms_slope))

    def mu(self, pressure, velocity, beta):
        """Return ``(mu, clamped)`` broadcast over the inputs (nothing is ever clamped)."""
        p, v, b = np.broadcast_arrays(np.asarray(pressure, float), np.asarray(velocity, float), np.asarray(beta, float))
        mu = self.mu0 * (1.0 - self.alpha(v) * b * self.rms_slope / self.kappa)
        return mu, np.zeros(p.shape, dtype=bool)


@dataclass(frozen=True)
class TableFriction:
    """mu interpolated in a :class:`FrictionTable`; out-of-range lookups follow ``policy``."""

    table: FrictionTable
    policy: str = "clamp"
    name: str = "table"

    @property
    def beta_threshold(self) -> float:
        """The cap recorded with the table."""
        return self.table.beta_threshold

    def mu(self, pressure, velocity, beta):
        """Return ``(mu, clamped)``; raises TableDomainError under the ``error`` policy."""
        return self.table.interpolate(pressure, velocity, beta, self.policy)


def make_friction_law(params: StripDrawParameters, table: FrictionTable | None = None):
    """The friction law that ``params.friction_model`` names.

    Parameters
    ----------
    params : StripDrawParameters
        Model parameters.
    table : FrictionTable, optional
        Required when ``params.friction_model == "table"``.
    """
    if params.friction_model == "constant":
        return ConstantFriction(params.mu_const)
    if params.friction_model == "closed_form":
        return closed_form_law(params)
    if table is None:
        raise ParameterError("friction_model = 'table' needs a friction table; none was given")
    return TableFriction(table, params.table_policy)


def closed_form_law(params: StripDrawParameters) -> ClosedFormFriction:
    """The closed-form law with the parameters' mu0, kappa, h'_rms, b, v_ref."""
    return ClosedFormFriction(params.mu0, params.kappa, params.rms_slope, params.alpha_b, params.alpha_v_ref)


def closed_form_table(
    params: StripDrawParameters | None = None,
    pressure=None,
    velocity=None,
    beta=None,
) -> FrictionTable:
    """Tabulate the closed-form law (the stand-in table until mesoscale results exist).

    The metadata says ``"provenance": "closed_form"`` so that nobody mistakes it for mesoscale
    results. Default axes: P 0.1-100 MPa, v 0-50 m/s (log-spaced above 1 mm/s), beta 0 to the cap.
    """
    params = params or StripDrawParameters()
    law = closed_form_law(params)
    pressure = np.geomspace(1e5, 1e8, 13) if pressure is None else pressure
    velocity = np.concatenate(([0.0], np.geomspace(1e-3, 50.0, 40))) if velocity is None else velocity
    beta = np.linspace(0.0, law.beta_threshold, 21) if beta is None else beta
    P, V, B = np.meshgrid(pressure, velocity, beta, indexing="ij")
    mu, _ = law.mu(P, V, B)
    meta = {
        "provenance": "closed_form",
        "note": "Generated from the closed form (Eq. 9 with Eq. 23), NOT from mesoscale BEM-DEM runs; "
        "alpha(v) parameters are provisional.",
        "beta_threshold": law.beta_threshold,
        "parameters": {
            "mu0": params.mu0,
            "kappa": params.kappa,
            "rms_slope": params.rms_slope,
            "alpha_b": params.alpha_b,
            "alpha_v_ref": params.alpha_v_ref,
        },
    }
    if not math.isfinite(float(np.max(mu))):  # pragma: no cover - guarded by parameter ranges
        raise ParameterError("closed-form table has non-finite values")
    return FrictionTable(pressure, velocity, beta, np.clip(mu, 0.0, None), meta)
