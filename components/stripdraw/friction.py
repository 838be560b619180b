"""Local friction laws mu(P, v, beta) (paper Sec. 4, Eq. 6-9, 23-24; docs/model.md section 4): a binding over the
native law (``components/native/core/tc_friction.c``, the same code the strip-draw model and its FMU run).

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

The cap of beta (Eq. 24) is where s A_p reaches A_c: :meth:`FrictionLaw.beta_cap` finds it on the
table's beta axis at the interval's pressure and sliding velocity (format versions 2-3: A_p and A_c are
piecewise linear in beta there, and the crossing is solved exactly; version 4: the first crossing of the
interpolated share's monotone cubic pieces, bisected to 1e-12 in beta), limited to 1; the largest of these caps
at the table's (P, v) nodes bounds beta everywhere (``beta_threshold``: the initial debris is checked against it).

Laws (``friction_model``), each a :class:`FrictionLaw` with ``mu(pressure, velocity, beta) -> (mu, clamped)``,
``beta_cap(pressure, velocity)`` and ``beta_threshold``:

- ``table``: the above with a friction table; a version 1 table (mu only) gives its mu as it is
  (``mesoscale``, scale 1 only);
- ``closed_form``: Eq. 8 and Eq. 23 (A_p/A0 = alpha beta P / E*) in closed form (Eq. 9):
  mu = mu0 (1 - s alpha(v) beta h'_rms / kappa), cap kappa / (s alpha h'_rms). alpha(v) =
  b (1 - exp(-|v| / v_ref)) (Fig. 15) when ``alpha_v_ref`` > 0, else alpha = b at every velocity
  (the default: the shipped campaign's alpha falls with v, so no saturation law is fitted; b is its
  alpha at the slowest velocity, whose row the table holds down to the test's 0.08 m/s);
- ``constant``: mu_const, no debris effect (beta capped at 1).

:meth:`FrictionLaw.beta_after_slide` gives the debris one point makes sliding at constant (P, v) by the per-point
update the strip's nodes and the user friction routines share (``tc_node_slide`` of tc_node_friction.c).
"""

from __future__ import annotations

import ctypes
import functools
import math

import numpy as np

from tribocosim.errors import ParameterError, TableDomainError
from tribocosim.components.native.toolchain.library import UBYTE_P, core, ptr
from tribocosim.components.stripdraw.parameters import StripDrawParameters
from tribocosim.components.stripdraw.table import FrictionTable


class FrictionLaw:
    """The friction law that ``params.friction_model`` names (the module docstring), evaluated by the native core.

    ``table`` is required for ``friction_model = "table"`` and ignored otherwise.
    """

    def __init__(self, params: StripDrawParameters, table: FrictionTable | None = None):
        if params.friction_model == "table" and table is None:
            raise ParameterError("friction_model = 'table' needs a friction table; none was given (the shipped one: "
                                 "make_friction_law(p, read_table(tribocosim.DEFAULT_TABLE)), or friction_model = "
                                 "'closed_form' or 'constant')")
        self.params = params
        self.name = params.friction_model
        self.table = table if params.friction_model == "table" else None
        c = self._core = core()
        self._struct = c.struct(params)
        self._native = self.table.native if self.table is not None else None
        c.call(c.lib.tc_law_check, ctypes.byref(self._struct), self.native_table)

    @property
    def native_table(self):
        """The native table handle (None without a table)."""
        return self._native.handle if self._native is not None else None

    def mu(self, pressure, velocity, beta):
        """``(mu, clamped)`` at the query points (broadcast together); TableDomainError outside the table under
        ``table_policy = "error"``."""
        p, v, b = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (pressure, velocity, beta)))
        mu = np.empty(p.shape)
        clamped = np.zeros(p.shape, dtype=np.uint8)
        c = self._core
        for value in np.unique(p):  # one native call per pressure
            at = p == value
            vq, bq = np.ascontiguousarray(v[at]), np.ascontiguousarray(b[at])
            out, flags, work = np.empty(vq.size), np.zeros(vq.size, dtype=np.uint8), np.empty(vq.size)
            c.call(c.lib.tc_law_mu, ctypes.byref(self._struct), self.native_table, float(value), vq.size, ptr(vq),
                   ptr(bq), ptr(out), ptr(flags, UBYTE_P), ptr(work), None, discard=TableDomainError)
            mu[at], clamped[at] = out, flags
        return (mu if mu.ndim else float(mu)), clamped.astype(bool)

    @functools.cached_property
    def beta_threshold(self) -> float:
        """The largest cap of beta (Eq. 24) of the law."""
        return float(self._core.lib.tc_law_beta_threshold(ctypes.byref(self._struct), self.native_table))

    def beta_cap(self, pressure: float, velocity: float) -> float:
        """The cap of beta (Eq. 24) at (P, |v|)."""
        return float(self._core.lib.tc_law_beta_cap(ctypes.byref(self._struct), self.native_table, float(pressure),
                                                     float(velocity), None))

    def beta_after_slide(self, pressure, velocity, slide: float, beta_initial: float = 0.0) -> np.ndarray:
        """beta of a point that slides ``slide`` [m] at constant pressure and slip rate, at each (P, |v|) (broadcast
        together), from ``beta_initial``: the per-point debris update of the strip's nodes and the user friction
        routines (``tc_node_slide`` of tc_node_friction.c: the Archard production K P S / (H h_p) of Eq. 37, the sink
        ``debris_sink_length`` integrated exactly, the cap of Eq. 24 at (P, v); no transport, zeta = 0);
        ParameterError for a pressure not > 0, a slide < 0 or a beta outside [0, 1]."""
        p, v = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (pressure, velocity)))
        pq, vq = np.ascontiguousarray(p.ravel()), np.ascontiguousarray(np.abs(v).ravel())
        out = np.empty(pq.size)
        c = self._core
        c.call(c.lib.tc_node_slide, ctypes.byref(self._struct), self.native_table, pq.size, ptr(pq), ptr(vq),
               float(slide), float(beta_initial), ptr(out))
        out = out.reshape(p.shape)
        return out if out.ndim else float(out)

    def alpha(self, velocity):
        """alpha(v) of Eq. 23 (the closed form): b (1 - exp(-|v| / v_ref)), or b when v_ref is 0."""
        f = np.vectorize(lambda x: self._core.lib.tc_law_alpha(ctypes.byref(self._struct), float(x)), otypes=[float])
        out = f(np.asarray(velocity, dtype=float))
        return out if out.ndim else float(out)


def make_friction_law(params: StripDrawParameters, table: FrictionTable | None = None) -> FrictionLaw:
    """The friction law that ``params.friction_model`` names (``table`` required for the table law, the default one:
    the shipped table is ``read_table(tribocosim.DEFAULT_TABLE)``)."""
    return FrictionLaw(params, table)


def closed_form_law(params: StripDrawParameters) -> FrictionLaw:
    """The closed-form law with the parameters' mu0, kappa, h'_rms, b, v_ref and A_p scale."""
    return FrictionLaw(params.replace(friction_model="closed_form"))


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
    # a table holds the measured A_p and the mu of frictionless flakes, mu0 (1 - A_p / A_c); the law applies s and r
    params = (params or StripDrawParameters()).replace(particle_area_scale=1.0, flake_shear_ratio=0.0)
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
