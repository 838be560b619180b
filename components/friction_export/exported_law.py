"""The friction law an export writes: the StripDraw FMU's table law, evaluated by the same native core, with the
band of its ensemble standard error.

The law (docs/model.md section 4; :class:`~tribocosim.components.stripdraw.friction.FrictionLaw` over
``tc_friction.c``) is mu = mu0 (1 - (1 - r) s q), q the interpolated share A_p / A_c of the table (``contact_area
= mesoscale``) or A_p over Eq. 8's A_c (``eq8``), r = ``flake_shear_ratio``, s = ``particle_area_scale``; every value
an export writes comes from it, with the parameters the export was given (the table's calibration, then ``--set``).

The band (``--band K``): mu_upper = min(mu0, mu + K se(mu)) and mu_lower = max(r mu0, mu - K se(mu)), with the standard
error propagated to first order, se(mu) = mu0 (1 - r) s se(q) below the cap (0 where flakes carry the whole real
contact, s q >= 1, and the law gives its least value r mu0, which also bounds mu_lower), and
se(q) the table's ensemble standard error of q interpolated as the table interpolates (the same native lookup):

- ``mesoscale`` with every load-bearing flake (format version 4): se(A_p / A_c) = se(mu_table) / mu0_table, the
  table's ``mu_se`` (from the members' A_p and A_c, their covariance included) over the mu0 its mu column was made
  with (recovered from the table: mu / (1 - A_p / A_c) at its nodes);
- ``mesoscale`` otherwise (version 3, or the cluster rule): se(A_p / A_c)^2 = (se A_p / A_c)^2 + (A_p se A_c /
  A_c^2)^2, the covariance of A_p and A_c left out;
- ``eq8``: se(A_p) / A_c(Eq. 8).

A calibration (a table of ``tribocosim calibrate``, or a calibration file such as the shipped ``paper``,
:mod:`.named_calibration`) adds the interval of its scale s: se(q) and q se(s) / s are combined in quadrature (the
table's ensemble noise and the data's scatter are independent sources), so that the calibrated law's band holds both.
With a calibration file the table's q is unscaled and s is the law's particle_area_scale: se(mu) = mu0 (1 - r)
hypot(s se(q), q se(s)), the same as a calibrated table's.

:meth:`ExportedLaw.beta_after_slide` is the debris one sheet point makes sliding at constant (P, v), the per-point
update the strip's nodes and the user friction routines share (``tc_node_slide`` of tc_node_friction.c).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from tribocosim.components.stripdraw.settings import typed_setting
from tribocosim.errors import ParameterError
from tribocosim.components.stripdraw.friction_floor import below_floor, floor_note, mu_at_full_coverage
from tribocosim.components.stripdraw.parameters import StripDrawParameters
from tribocosim.components.stripdraw.table import FrictionTable, read_table

#: the metadata key of a calibration file's record (cosim/apps/calibrate.py)
CALIBRATION_KEY = "strip_draw_calibration"
#: mu within this relative distance of the law's least value r mu0 is at the cap (round-off of the lookup's sums)
CAP_RTOL = 1e-12
#: mu0 of a table's mu column is recovered where the share A_p / A_c is below this (far from the cap)
MU0_SHARE_MAX = 0.5


def table_mu0(table: FrictionTable) -> float:
    """The mu0 the table's mu column was made with: the median of mu / (1 - A_p / A_c) over its nodes with a share
    below :data:`MU0_SHARE_MAX` (mu = mu0 (1 - A_p / A_c), Eq. 7 with Eq. 6)."""
    ac, ap = table.contact_area, table.particle_area
    share = np.divide(ap, ac, out=np.full(ac.shape, np.inf), where=ac > 0)
    at = share < MU0_SHARE_MAX
    if not np.any(at):
        raise ParameterError("the table has no node with A_p / A_c below 0.5: the mu0 of its mu column (needed for "
                             "the standard error of the share) cannot be recovered")
    return float(np.median(table.mu[at] / (1.0 - share[at])))


class ExportedLaw:
    """The table law of the strip-draw model with the parameters an export is given (module docstring).

    Parameters
    ----------
    params : StripDrawParameters
        The model's parameters; ``friction_model`` must be ``table``. Lookups are made under the clamp policy, so
        that a lookup outside the table or reading an unsimulated node is flagged, never refused.
    table : FrictionTable
        The friction table (a calibration file is one).
    table_path : Path
        Where the table was read from (for the provenance).
    calibration : dict, optional
        The calibration's record: a calibrated table's (its metadata's ``strip_draw_calibration``) or a calibration
        file's (:mod:`.named_calibration`).
    fitted_with : StripDrawParameters, optional
        The parameters the calibration was fitted with (before ``--set``).
    """

    def __init__(self, params: StripDrawParameters, table: FrictionTable, table_path: Path,
                 calibration: dict | None = None, fitted_with: StripDrawParameters | None = None):
        from tribocosim.components.stripdraw.friction import FrictionLaw

        if params.friction_model != "table":
            raise ParameterError(f"friction_model = {params.friction_model!r}: the export writes the table law "
                                 "(friction_model = table), the friction the StripDraw FMU reads from its table")
        self.params = params.replace(table_policy="clamp")
        self.table, self.table_path, self.calibration = table, Path(table_path), calibration
        self.fitted_with = fitted_with
        self.law = FrictionLaw(self.params, table)

    def departures(self) -> dict:
        """The parameters that differ from those the calibration was fitted with: name -> (the fit's value, the
        law's); empty without a calibration (the table policy aside: a law is looked up under clamp)."""
        if self.fitted_with is None:
            return {}
        fit, own = dataclasses.asdict(self.fitted_with), dataclasses.asdict(self.params)
        return {k: (fit[k], own[k]) for k in fit if k != "table_policy" and fit[k] != own[k]}

    # ---------------------------------------------------------------------------------------------- the law
    def mu(self, pressure, velocity, beta) -> tuple[np.ndarray, np.ndarray]:
        """``(mu, flagged)`` at the points (SI; broadcast together): flagged where the lookup left the table's axes
        or read a node the campaign did not simulate (the FMU's ``table_clamp_count``)."""
        mu, flagged = self.law.mu(pressure, velocity, beta)
        return np.asarray(mu, dtype=float), np.asarray(flagged, dtype=bool)

    def beta_after_slide(self, pressure, velocity, slide: float, beta_initial: float = 0.0) -> np.ndarray:
        """beta of a sheet point that slides ``slide`` at each (P, v) from ``beta_initial``: the per-point debris
        update of the strip's nodes and the user routines (:meth:`FrictionLaw.beta_after_slide`, with the cap)."""
        return np.asarray(self.law.beta_after_slide(pressure, velocity, slide, beta_initial), dtype=float)

    def cap(self, pressure: float, velocity: float) -> float:
        """The cap of beta (Eq. 24) at (P, v): the strip-draw model never holds more debris there."""
        return self.law.beta_cap(pressure, velocity)

    @property
    def pressure_axis(self) -> tuple[float, float]:
        return float(self.table.pressure[0]), float(self.table.pressure[-1])

    @property
    def velocity_axis(self) -> tuple[float, float]:
        return float(self.table.velocity[0]), float(self.table.velocity[-1])

    @property
    def beta_axis(self) -> tuple[float, float]:
        return float(self.table.beta[0]), float(self.table.beta[-1])

    def simulated_beta_top(self, pressure_range, velocity_range) -> float:
        """The largest beta node up to which every lookup in the pressure and velocity ranges reads simulated nodes
        only (the table's first beta node when none; its last for a table that records no simulated flags)."""
        t = self.table
        if t.version < 3:
            return float(t.beta[-1])
        sim = t.array("simulated")
        rows = _cell_span(t.pressure, *pressure_range)
        cols = _cell_span(t.velocity, *velocity_range)
        block = sim[rows[0]:rows[1] + 1, cols[0]:cols[1] + 1, :]
        top = 0
        for k in range(t.beta.size):
            if not np.all(block[:, :, :k + 1] == 1.0):
                break
            top = k
        return float(t.beta[top])

    # ---------------------------------------------------------------------------------------------- the band
    @property
    def scale_interval(self) -> tuple[float, float] | None:
        """``(s, se(s))`` of the calibration file's fitted scale, or None (no calibration, or s not fitted)."""
        fitted = (self.calibration or {}).get("fitted", {}).get("particle_area_scale")
        if not fitted or fitted.get("stderr") is None:
            return None
        return float(fitted["value"]), float(fitted["stderr"])

    def standard_error(self, pressure, velocity, beta) -> np.ndarray:
        """se(mu) at the points (module docstring); ParameterError when the table holds no standard errors."""
        p, v, b = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (pressure, velocity, beta)))
        q_nodes, se_nodes = self._share_nodes()
        se_q = np.maximum(np.asarray(self.table.interpolate_array(se_nodes, p, v, b)[0], dtype=float), 0.0)
        prm = self.params
        interval = self.scale_interval
        if interval is not None and interval[0] > 0:
            q = np.asarray(self.table.interpolate_array(q_nodes, p, v, b)[0], dtype=float)
            se_q = np.hypot(se_q, q * interval[1] / interval[0])
        if prm.contact_area == "eq8":
            se_q = se_q / (prm.kappa * p / (prm.rms_slope * prm.e_star))
        mu, _ = self.mu(p, v, b)
        loss = (1.0 - prm.flake_shear_ratio) * prm.particle_area_scale
        below_cap = mu > self.least_mu * (1.0 + CAP_RTOL)
        return np.where(below_cap, prm.mu0 * loss * se_q, 0.0)

    @property
    def least_mu(self) -> float:
        """r mu0: mu where flakes carry the whole real contact (the cap, Eq. 24), the least value the law gives."""
        return mu_at_full_coverage(self.params.mu0, self.params.flake_shear_ratio)

    def band(self, pressure, velocity, beta, k: float) -> tuple[np.ndarray, np.ndarray]:
        """``(mu_upper, mu_lower)`` at K standard errors, clipped to [r mu0, mu0] (module docstring)."""
        mu, _ = self.mu(pressure, velocity, beta)
        se = self.standard_error(pressure, velocity, beta)
        return np.minimum(self.params.mu0, mu + k * se), np.maximum(self.least_mu, mu - k * se)

    def check_band(self) -> None:
        """ParameterError naming ``--band`` when the table holds no standard errors."""
        self._share_nodes()

    def _share_nodes(self) -> tuple[np.ndarray, np.ndarray]:
        """The node arrays of q (A_p / A_c, or A_p under eq8) and of se(q) (module docstring)."""
        t, prm = self.table, self.params
        if t.version < 3:
            raise ParameterError(f"--band needs a table with the ensemble standard errors of its areas (format "
                                 f"version 3 or later); {self.table_path} is format version {t.version}")
        clusters = prm.particle_area_rule == "clusters"
        ap = t.array("particle_area_clusters" if clusters else "particle_area")
        ap_se = t.array("particle_area_clusters_se" if clusters else "particle_area_se")
        if prm.contact_area == "eq8":
            return ap, ap_se
        ac, ac_se = t.contact_area, t.array("contact_area_se")
        safe = np.where(ac > 0, ac, 1.0)
        q = np.where(ac > 0, ap / safe, 0.0)
        if t.version >= 4 and not clusters:
            return q, t.array("mu_se") / table_mu0(t)
        return q, np.where(ac > 0, np.hypot(ap_se / safe, ap * ac_se / safe**2), 0.0)

    # ---------------------------------------------------------------------------------------------- provenance
    def provenance(self) -> dict:
        """What the law is: the table (file name, content hash, provenance, format version: the hash, not the
        writer's folders, names it), the calibration (status, scale, note, its data by file name and SHA-256), every
        parameter of the model."""
        meta = self.table.metadata
        out = {"table": {"file": self.table_path.name, "content_hash": meta.get("content_hash"),
                         "provenance": self.table.provenance, "format_version": self.table.version},
               "parameters": dataclasses.asdict(self.params)}
        if self.calibration is not None:
            cal = self.calibration
            out["calibration"] = {"status": cal.get("status"), "fitted": cal.get("fitted"), "note": cal.get("note"),
                                  "source_table": cal.get("source_table"), "data": cal.get("data")}
            out["calibration"].update({k: cal[k] for k in ("name", "title", "file", "sha256", "fit", "made_by")
                                       if k in cal})
            if self.departures():
                out["calibration"]["departures"] = {k: {"fitted_with": a, "law": b}
                                                    for k, (a, b) in self.departures().items()}
        return out


def value_warnings(law: ExportedLaw, mu: np.ndarray) -> list[str]:
    """Warnings about the mu values one exported file holds (``mu``: every value it writes), each one line: written
    into that file's header and printed by the command. The least value below the documented floor of the strip-draw
    contact (:func:`~tribocosim.components.stripdraw.friction_floor.floor_note`: it names the setting that lets mu
    fall there, e.g. ``flake_shear_ratio = 0``, the paper's model); an empty list when nothing is to be said."""
    values = np.asarray(mu, dtype=float)
    if values.size == 0:
        return []
    note = floor_note(float(np.min(values)), law.params.mu0, law.params.flake_shear_ratio)
    if note is None:
        return []
    share = int(np.count_nonzero(below_floor(values)))
    return [f"the least value: {note} ({share} of the file's {values.size} values are below the floor)"]


def _cell_span(axis: np.ndarray, low: float, high: float) -> tuple[int, int]:
    """The first and last node of ``axis`` whose cells a lookup in [low, high] reads."""
    lo = int(np.clip(np.searchsorted(axis, low, side="right") - 1, 0, axis.size - 1))
    hi = int(np.clip(np.searchsorted(axis, high, side="left"), 0, axis.size - 1))
    return lo, hi


def load_law(table_path=None, calibration_path=None, settings: dict | None = None) -> ExportedLaw:
    """The law an export writes: the table (``table_path``, default the shipped one) or the calibration
    (``calibration_path``), then ``settings`` (strip-draw parameter -> value, ``--set``).

    A calibration is a shipped one's name (``paper``; ``none``: the shipped table uncalibrated,
    :mod:`.named_calibration`), a calibration file of that form (JSON: its table with the parameters it was fitted
    with, particle_area_scale = the fitted s), or a table written by ``tribocosim calibrate`` (an .npz with the
    parameters its record says to run with: its contact area, rule, the other fitted parameters, and
    particle_area_scale = 1, the scale being in its A_p). The parameters before ``settings`` are the calibration's
    (:meth:`ExportedLaw.departures` names those ``settings`` change)."""
    from tribocosim.components.friction_export import named_calibration as named
    from tribocosim.paths import DEFAULT_TABLE

    if table_path is not None and calibration_path is not None:
        raise ParameterError("--table and --calibration both given: a calibration file is the table it was "
                             "calibrated on with A_p scaled; give one of them")
    given = calibration_path
    if calibration_path is not None and str(calibration_path) == named.NONE:
        calibration_path = None
    calibration_path = named.named_path(calibration_path) or calibration_path
    if calibration_path is not None and not Path(calibration_path).is_file():
        raise ParameterError(f"--calibration {given}: no such file, and not a calibration's name "
                             f"({', '.join(sorted((*named.NAMED, named.NONE)))})")
    names = {f.name for f in dataclasses.fields(StripDrawParameters)}
    values: dict = {}
    if calibration_path is not None and named.is_calibration_json(Path(calibration_path)):
        cal = named.read_calibration(calibration_path)
        path, table, calibration = cal.table_path, read_table(cal.table_path), cal.law_record()
        values.update({k: v for k, v in cal.record["parameters"].items() if k in names})
    else:
        path = Path(calibration_path or table_path or DEFAULT_TABLE)
        table = read_table(path)
        calibration = table.metadata.get(CALIBRATION_KEY)
        if calibration_path is not None and calibration is None:
            raise ParameterError(f"--calibration {path}: the file holds no calibration record ({CALIBRATION_KEY} in "
                                 "its metadata); a friction table is given with --table")
        if calibration is not None:
            values.update({k: v for k, v in (calibration.get("parameters") or {}).items() if k in names})
            values.update({k: d["value"] for k, d in (calibration.get("fitted") or {}).items() if k in names})
            values.update(particle_area_scale=1.0, contact_area=calibration.get("contact_area", "mesoscale"),
                          particle_area_rule=calibration.get("particle_area_rule", "load_bearing"))
    fitted_with = StripDrawParameters(**values) if calibration is not None else None
    for name, value in (settings or {}).items():
        if calibration is not None and name == "particle_area_scale":
            raise ParameterError(f"--set particle_area_scale={value} with the calibration {given}: it sets the "
                                 "fitted scale itself")
        values[name] = typed_setting(name, value)
    params = StripDrawParameters(**values)
    return ExportedLaw(params, table, path.resolve(), calibration, fitted_with)
