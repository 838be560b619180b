"""Local friction laws mu(P, v, beta) behind one interface (paper Sec. 4, Eq. 6-9, 23-24; docs/model.md section 4).

Bowden-Tabor with debris (Eq. 7): mu = tau0 (A_c - A_p) / (P A0), A_c the real contact area and A_p
the part of it carried by blocked flakes. tau0 is set by the particle-free coefficient
mu0 = tau0 A_c / (P A0) (Eq. 6 at beta = 0), so that

    mu = mu0 (1 - A_p / A_c)                                                   (Eq. 7 with Eq. 6)

and ``mu0`` means the same whatever A_c is; A_p is scaled by ``particle_area_scale`` (1: as the
mesoscale campaign measured it; the one scalar a strip-draw calibration fits). Two conventions for
A_c (``contact_area``):

``mesoscale`` (default)
    A_c from the friction table (version 2: the ensemble mean of the BEM-DEM runs), physically
    consistent with the mesoscale contact, which saturates at p_crit: A_c/A0 ~ P / p_crit.
``eq8``
    the paper's Eq. 8 (Bush-Gibson-Thomas), A_c/A0 = kappa P / (h'_rms E*), about 29 times smaller
    than any contact capped at p_crit (docs/model.md section 4): blocked flakes take a larger share,
    which is the regime of the paper's macro figures (Eq. 9).

The cap of beta (Eq. 24) is where s A_p reaches A_c: :meth:`TableFriction.beta_cap` finds it on the
table's beta axis at the interval's pressure and sliding velocity (A_p and A_c are piecewise linear
in beta there, so the crossing is exact), limited to 1; the largest of these caps at the table's
(P, v) nodes bounds beta everywhere (``beta_threshold``: the initial debris is checked against it).

Laws, sharing ``mu(pressure, velocity, beta) -> (mu, clamped)`` and ``beta_cap(pressure, velocity)``:

- ``table``: the above with a friction table; a version 1 table (mu only) gives its mu as it is
  (``mesoscale``, scale 1 only);
- ``closed_form``: Eq. 8 and Eq. 23 (A_p/A0 = alpha beta P / E*) in closed form (Eq. 9):
  mu = mu0 (1 - s alpha(v) beta h'_rms / kappa), cap kappa / (s alpha h'_rms). alpha(v) =
  b (1 - exp(-|v| / v_ref)) (Fig. 15) when ``alpha_v_ref`` > 0, else alpha = b at every velocity
  (the default: the shipped campaign's alpha falls with v, so no saturation law is fitted; b is its
  alpha at the slowest velocity, whose row the table holds down to the test's 0.08 m/s);
- ``constant``: mu_const, no debris effect (beta capped at 1).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from tribocosim.components.errors import ParameterError
from tribocosim.components.stripdraw.parameters import StripDrawParameters
from tribocosim.components.stripdraw.table import FrictionTable


REACH_RTOL = 1e-12  # s A_p "reaches" A_c within this relative tolerance


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

    def beta_cap(self, pressure: float, velocity: float) -> float:
        """The cap of beta at this pressure and velocity: 1."""
        return self.beta_threshold


@dataclass(frozen=True)
class ClosedFormFriction:
    """mu = mu0 (1 - s alpha(v) beta h'_rms / kappa) (Eq. 9 with Eq. 23)."""

    mu0: float
    kappa: float
    rms_slope: float
    alpha_b: float
    alpha_v_ref: float
    particle_area_scale: float = 1.0
    name: str = "closed_form"

    def alpha(self, velocity):
        """alpha(v) of Eq. 23: b (1 - exp(-|v| / v_ref)) (Fig. 15), or b when v_ref is 0."""
        v = np.abs(np.asarray(velocity, float))
        if self.alpha_v_ref == 0:
            return np.full(v.shape, self.alpha_b) if v.ndim else self.alpha_b
        return self.alpha_b * -np.expm1(-v / self.alpha_v_ref)

    @property
    def beta_threshold(self) -> float:
        """Eq. 24 with the largest alpha (b), limited to 1."""
        top = self.particle_area_scale * self.alpha_b * self.rms_slope
        return 1.0 if top <= 0 else min(1.0, self.kappa / top)

    def beta_cap(self, pressure: float, velocity: float) -> float:
        """The cap of beta (Eq. 24) with the saturated alpha: A_p <= A_c at every velocity."""
        return self.beta_threshold

    def mu(self, pressure, velocity, beta):
        """Return ``(mu, clamped)`` broadcast over the inputs (nothing is ever clamped)."""
        p, v, b = np.broadcast_arrays(np.asarray(pressure, float), np.asarray(velocity, float), np.asarray(beta, float))
        mu = self.mu0 * (1.0 - self.particle_area_scale * self.alpha(v) * b * self.rms_slope / self.kappa)
        return mu, np.zeros(p.shape, dtype=bool)


@dataclass(frozen=True)
class TableFriction:
    """mu = mu0 (1 - s A_p / A_c) from a friction table, A_c by the ``contact_area`` convention."""

    table: FrictionTable
    policy: str = "clamp"
    mu0: float = 0.15
    contact_area: str = "mesoscale"
    kappa: float = 2.0
    rms_slope: float = 0.34
    e_star: float = 55e9
    particle_area_scale: float = 1.0
    name: str = "table"

    def __post_init__(self) -> None:
        if self.table.version == 1 and (self.contact_area != "mesoscale" or self.particle_area_scale != 1.0):
            raise ParameterError(
                f"contact_area = {self.contact_area!r} with particle_area_scale = {self.particle_area_scale!r} needs a "
                "friction table of format version 2 (with the contact areas); this table is version 1 (mu only): "
                "rebuild it with tribocosim surrogate table")

    @functools.cached_property
    def beta_threshold(self) -> float:
        """The largest cap of beta: the table's (version 1), else the largest of the caps at the table's
        (P, v) nodes (:meth:`beta_cap`): above it, s A_p exceeds A_c at every node."""
        t = self.table
        if t.version == 1:
            return t.beta_threshold
        return max((self._crossing(float(p), float(v)) for p in t.pressure if p > 0 for v in t.velocity),
                   default=1.0)

    def contact(self, pressure, velocity, beta):
        """A_c/A0 at the query points: the table's (``mesoscale``) or Eq. 8 (``eq8``)."""
        if self.contact_area == "eq8":
            p = np.asarray(pressure, float)
            return self.kappa * p / (self.rms_slope * self.e_star) + 0.0 * np.asarray(beta, float)
        ac, _ = self.table.interpolate_array(self.table.contact_area, pressure, velocity, beta, "clamp")
        return ac

    def mu(self, pressure, velocity, beta):
        """Return ``(mu, clamped)``; raises TableDomainError under the ``error`` policy."""
        t = self.table
        if t.version == 1:
            return t.interpolate(pressure, velocity, beta, self.policy)
        ap, clamped = t.interpolate_array(t.particle_area, pressure, velocity, beta, self.policy)
        ac = self.contact(pressure, velocity, beta)
        share = np.where(ac > 0, self.particle_area_scale * ap / np.where(ac > 0, ac, 1.0), 0.0)
        return self.mu0 * np.maximum(0.0, 1.0 - share), clamped

    def beta_cap(self, pressure: float, velocity: float) -> float:
        """Where s A_p reaches A_c along the beta axis at (P, |v|) (Eq. 24; exact: both are piecewise linear
        in beta), limited to 1; 1 when A_p stays below A_c on the whole axis; without pressure (or with a
        version 1 table) :attr:`beta_threshold`."""
        if self.table.version == 1 or not pressure > 0:
            return self.beta_threshold
        return self._crossing(pressure, abs(velocity))

    def _crossing(self, pressure: float, velocity: float) -> float:
        t = self.table
        b = t.beta
        ap, _ = t.interpolate_array(t.particle_area, pressure, velocity, b, "clamp")
        ac = self.contact(pressure, velocity, b)
        d = self.particle_area_scale * ap - ac
        for k in range(b.size):
            if d[k] >= -REACH_RTOL * ac[k]:  # reached, up to rounding (a table tabulated to its cap)
                if k == 0:
                    return 0.0
                return min(1.0, float(b[k - 1] + (b[k] - b[k - 1]) * (-d[k - 1]) / (d[k] - d[k - 1])))
        return 1.0


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
    return TableFriction(table, params.table_policy, params.mu0, params.contact_area, params.kappa,
                         params.rms_slope, params.e_star, params.particle_area_scale)


def closed_form_law(params: StripDrawParameters) -> ClosedFormFriction:
    """The closed-form law with the parameters' mu0, kappa, h'_rms, b, v_ref and A_p scale."""
    return ClosedFormFriction(params.mu0, params.kappa, params.rms_slope, params.alpha_b, params.alpha_v_ref,
                              params.particle_area_scale)


def closed_form_table(
    params: StripDrawParameters | None = None,
    pressure=None,
    velocity=None,
    beta=None,
) -> FrictionTable:
    """Tabulate the closed form as a version 2 table (A_c from Eq. 8, A_p from Eq. 23; no member spread).

    With ``contact_area = "eq8"`` such a table reproduces the closed form exactly on its velocity
    nodes (A_p is multilinear in (P, beta), which trilinear interpolation reproduces). The metadata
    says ``"provenance": "closed_form"`` so that nobody mistakes it for mesoscale results. Default
    axes: P 0.1-100 MPa, v 0-50 m/s (log-spaced above 1 mm/s), beta 0 to the cap.
    """
    params = (params or StripDrawParameters()).replace(particle_area_scale=1.0)  # a table holds the measured A_p
    law = closed_form_law(params)
    pressure = np.geomspace(1e5, 1e8, 13) if pressure is None else pressure
    velocity = np.concatenate(([0.0], np.geomspace(1e-3, 50.0, 40))) if velocity is None else velocity
    beta = np.linspace(0.0, law.beta_threshold, 21) if beta is None else beta
    P, V, B = np.meshgrid(pressure, velocity, beta, indexing="ij")
    mu, _ = law.mu(P, V, B)
    ac = params.kappa * P / (params.rms_slope * params.e_star)
    ap = law.alpha(V) * B * P / params.e_star
    meta = {
        "provenance": "closed_form",
        "note": "Generated from the closed form (Eq. 8, Eq. 23, Eq. 9), NOT from mesoscale BEM-DEM runs.",
        "beta_threshold": law.beta_threshold,
        "parameters": {
            "mu0": params.mu0,
            "kappa": params.kappa,
            "rms_slope": params.rms_slope,
            "e_star": params.e_star,
            "alpha_b": params.alpha_b,
            "alpha_v_ref": params.alpha_v_ref,
        },
    }
    if not math.isfinite(float(np.max(mu))):  # pragma: no cover - guarded by parameter ranges
        raise ParameterError("closed-form table has non-finite values")
    zeros = np.zeros(P.shape)
    return FrictionTable(pressure, velocity, beta, np.clip(mu, 0.0, None), meta, contact_area=ac,
                         particle_area=ap, contact_area_std=zeros, particle_area_std=zeros)
