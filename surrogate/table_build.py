"""The friction table mu(P, v, beta) from a finished campaign (Sec. 4, 6; docs/model.md section 4).

The table (format version 4, :mod:`tribocosim.components.stripdraw.table`) serves what the slides measured. At
every simulated node (P, v, beta) it holds the ensemble means of <A_c>/A0, <A_p>/A0 of every load-bearing flake and
of the paper's cluster rule alone (Eq. 22) with their ensemble standard errors (member std / sqrt(members); one
contact pixel, 1/n^2 of A0, for a node of one member), mu = mu0 (1 - A_p / A_c) of the means (Eq. 7 with tau0 set
by the particle-free mu0, Eq. 6; mu0 at beta = 0 at every pressure) and its standard error (the members' A_p and
A_c, their variances and covariance, propagated to first order through the ratio of the means).

Axes: the campaign's pressures; its velocities, below them a v = 0 row when the sweep asks for the quasi-static
row (``[table] quasi_static_row``: the values of the slowest velocity, the plateau where the damping per pixel
of sliding is large; docs/physics/table_domain.md measures it); beta = 0 and every debris level of the sweep.
No node lies above the largest simulated level.

Nodes a (P, v) row did not simulate (``simulated`` = 0; a lookup that reads one is counted, docs/model.md section 4)
are filled from the row's simulated levels when a fit of every area passes the goodness-of-fit test against the
ensemble standard errors at :data:`FIT_SIGNIFICANCE`: A_p and A_p of the cluster rule by a form of
:data:`tribocosim.surrogate.fit.BETA_FORMS` (Eq. 23's line through the origin, the saturating a beta / (1 + c beta);
the smaller AIC when both pass), A_c by a line in beta through the particle-free node and the levels. Otherwise
the row's unsimulated nodes hold the values and standard errors of its nearest simulated level below (a clamp to the
simulated range: the areas fill together or not at all, since a share A_p / A_c of a fit over a held value would be
neither). Every fit of every row, with chi^2, its degrees of freedom, chi^2 / dof, the
probability and the normalised residuals, and what filled each unsimulated node are in the metadata (``fits.rows``,
``fits.unsimulated``).

For reference the metadata also give tau0 = mu0 / s_c, with s_c the through-origin slope of <A_c>/A0 against
P of the particle-free cases (:func:`tribocosim.surrogate.fit.fit_contact`), the cap of beta at s = 1 at every
(P, v) (Eq. 24: where the interpolated share A_p / A_c reaches 1, or none inside the axis), and alpha =
<A_p>/A0 / (beta P / E*) per node.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import asdict

import numpy as np

from tribocosim.errors import TableError
from tribocosim.components.stripdraw.table import UNITS, FrictionTable, mu_of_areas

from .fit import BETA_FORMS, EnsemblePoint, _key, ensemble, fit_affine, fit_alpha, fit_beta_forms, fit_contact
from .slide_config import SlideConfig

#: a fit fills the unsimulated nodes of its row only when the probability of a chi^2 at least as large as its own
#: (against the ensemble standard errors, with its degrees of freedom) is at least this
FIT_SIGNIFICANCE = 0.05
#: the quantities a row's fits may fill, with the forms tried
FILLED = {"particle_area": BETA_FORMS, "particle_area_clusters": BETA_FORMS, "contact_area": ("affine",)}


def surface_statistics(slide: dict, surfaces: list[dict]) -> dict:
    """RMS heights and slopes of the sheet, the tool and the gap (tool - sheet) per surface pair."""
    from . import coupling
    from .surfaces import rms_height, rms_slope

    gen = getattr(coupling, "generate_surfaces", None) or coupling._generate_surfaces
    pairs = []
    for surf in surfaces:
        cfg = SlideConfig(**{**slide, **surf})
        sheet, tool = gen(cfg)
        entry = {**surf}
        for name, h in (("sheet", sheet), ("tool", tool), ("gap", tool - sheet)):
            entry[name] = {"rms_height": rms_height(h),
                           "rms_slope": rms_slope(h, cfg.size, "spectral"),
                           "rms_slope_finite_difference": rms_slope(h, cfg.size, "finite_difference")}
        pairs.append(entry)
    mean_gap_slope = float(np.mean([p["gap"]["rms_slope"] for p in pairs]))
    return {"pairs": pairs, "gap_rms_slope_mean": mean_gap_slope,
            "rms_slope_definition": "spectral (gradient of the trigonometric interpolant); "
                                    "kappa uses the gap's"}


def _sigma(point, n_pixels: int) -> float:
    """Standard error of a node's <A_p>/A0 for the fit: member std / sqrt(n), at least one contact pixel
    per member (1 / (n_pixels sqrt(n))), so that a node whose members agree exactly (or are all 0) does not
    get an infinite weight."""
    floor = 1.0 / (n_pixels * math.sqrt(point.n))
    return max(point.ap_std / math.sqrt(point.n) if point.n > 1 else 0.0, floor)


def _se(std: float, n: int, n_pixels: int) -> float:
    """The ensemble standard error of a node's mean: std / sqrt(n), one contact pixel for one member."""
    return std / math.sqrt(n) if n > 1 else 1.0 / n_pixels


def _mu_se(q: EnsemblePoint, mu0: float, n_pixels: int) -> float:
    """Standard error of mu = mu0 (1 - <A_p> / <A_c>) at a simulated node: the members' variances and covariance of
    A_p and A_c propagated to first order through the ratio (one contact pixel of A_c for one member)."""
    if q.ac_mean <= 0:
        return 0.0
    share = q.ap_mean / q.ac_mean
    if q.n < 2:
        return mu0 * share / (n_pixels * q.ac_mean)
    ap = np.array([m[1] for m in q.members])
    ac = np.array([m[2] for m in q.members])
    cov = np.cov(ap, ac, ddof=1)
    var = (cov[0, 0] - 2.0 * share * cov[0, 1] + share**2 * cov[1, 1]) / (q.ac_mean**2 * q.n)
    return mu0 * math.sqrt(max(var, 0.0))


class _Row:
    """One (P, v) row: its simulated levels' ensemble statistics, and the fits that may fill the levels it did not
    simulate (module docstring)."""

    def __init__(self, ens: dict, p: float, v: float, levels: list, n_pixels: int):
        self.p, self.v, self.n_pixels = p, v, n_pixels
        self.points = {b: ens.get((_key(p), _key(v), _key(b))) for b in [0.0, *levels]}
        self.simulated = [b for b in levels if self.points[b] is not None]
        if not self.simulated:
            raise TableError(f"no finished case with flakes at P = {p:g} Pa, v = {v:g} m/s: rerun the campaign "
                             "(failed cases are retried) before building the table")
        if self.points[0.0] is None:
            raise TableError(f"no finished particle-free case at P = {p:g} Pa, v = {v:g} m/s")
        pts = [self.points[b] for b in self.simulated]
        floor = [1.0 / (n_pixels * math.sqrt(q.n)) for q in pts]
        sig_c = [max(q.apc_std / math.sqrt(q.n) if q.n > 1 else 0.0, f) for q, f in zip(pts, floor)]
        free = [self.points[0.0], *pts]
        sig_ac = [max(q.ac_std / math.sqrt(q.n) if q.n > 1 else 0.0, 1.0 / n_pixels) for q in free]
        #: per filled quantity, the levels and standard errors its fits weigh
        self.fit_data = {"particle_area": (self.simulated, [_sigma(q, n_pixels) for q in pts]),
                         "particle_area_clusters": (self.simulated, sig_c),
                         "contact_area": ([0.0, *self.simulated], sig_ac)}
        self.fits = {
            "particle_area": fit_beta_forms(self.simulated, [q.ap_mean for q in pts],
                                            self.fit_data["particle_area"][1]),
            "particle_area_clusters": fit_beta_forms(self.simulated, [q.apc_mean for q in pts], sig_c),
            "contact_area": {"affine": fit_affine([0.0, *self.simulated], [q.ac_mean for q in free], sig_ac)},
        }
        best = {}
        for name, forms in FILLED.items():
            passing = [self.fits[name][f] for f in forms if f in self.fits[name]
                       and self.fits[name][f].passes(FIT_SIGNIFICANCE)]
            best[name] = min(passing, key=lambda f: f.aic) if passing else None
        # the areas fill together or not at all: a share A_p / A_c of a fit over a held value would be neither
        self.fill = best if all(f is not None for f in best.values()) else {name: None for name in FILLED}

    def node(self, beta: float, mu0: float, fill: dict | None = None) -> dict:
        """The values of the node at ``beta``: the ensemble's where simulated, else per quantity the passing fit or
        the nearest simulated level below (``sources``); ``fill`` replaces the row's fits (``self.fill``)."""
        if beta == 0.0 or beta in self.simulated:
            q = self.points[beta]
            return {"contact_area": q.ac_mean, "contact_area_se": _se(q.ac_std, q.n, self.n_pixels),
                    "contact_area_std": q.ac_std, "particle_area": q.ap_mean,
                    "particle_area_se": _se(q.ap_std, q.n, self.n_pixels) if beta > 0 else 0.0,
                    "particle_area_std": q.ap_std, "particle_area_clusters": q.apc_mean,
                    "particle_area_clusters_se": _se(q.apc_std, q.n, self.n_pixels) if beta > 0 else 0.0,
                    "mu_se": _mu_se(q, mu0, self.n_pixels), "simulated": 1.0, "members": q.n}
        held = self.node(max(b for b in [0.0, *self.simulated] if b < beta), mu0)
        out = {"simulated": 0.0, "members": 0, "sources": {}}
        for name in FILLED:
            fit = (self.fill if fill is None else fill)[name]
            if fit is None:
                out[name], out[name + "_se"] = held[name], held[name + "_se"]
                out["sources"][name] = "held"
            else:
                out[name], out[name + "_se"] = max(float(fit(beta)), 0.0), float(fit.stderr(beta)[0])
                out["sources"][name] = fit.form
        out["contact_area_std"], out["particle_area_std"] = out["contact_area_se"], out["particle_area_se"]
        ap, ac = out["particle_area"], out["contact_area"]
        out["mu_se"] = (mu0 * ap / ac * math.hypot(out["particle_area_se"] / ap, out["contact_area_se"] / ac)
                        if ap > 0 and ac > 0 else 0.0)
        return out

    def fits_record(self) -> dict:
        """Every fit of the row with its goodness of fit, and what fills the row's unsimulated nodes."""
        return {"pressure": self.p, "velocity": self.v, "levels": self.simulated,
                **{name: {f: fit.to_dict() for f, fit in forms.items()} for name, forms in self.fits.items()},
                "fills": {name: (f.form if f is not None else "held") for name, f in self.fill.items()}}


@dataclasses.dataclass(frozen=True)
class Grid:
    """The table's axes and settings from a campaign's sweep, and the (P, v) rows of an ensemble on them."""

    sweep: dict
    pressures: list
    v_grid: list
    qs_row: bool
    levels: list
    mu0: float
    e_star: float
    p_crit: float
    n_pixels: int

    @classmethod
    def of(cls, sweep: dict) -> "Grid":
        if not sweep.get("particle_free", True):
            raise TableError("the sweep has no particle-free cases (particle_free = false); A_c at beta = 0 and tau0 "
                             "need them")
        base = SlideConfig(**{**sweep["slide"], **sweep["surfaces"][0]})  # [slide] checked with a pair (sweep.py)
        return cls(sweep, sorted(float(p) for p in sweep["pressures"]), sorted(float(v) for v in sweep["velocities"]),
                   bool(sweep["table"].get("quasi_static_row", False)),
                   sorted({_key(f["beta"]) for f in sweep["flakes"]}), float(sweep["table"]["mu0"]), base.e_star,
                   base.p_crit, base.n * base.n)

    @property
    def vel_axis(self) -> list:
        return ([0.0] if self.qs_row else []) + self.v_grid

    @property
    def beta_axis(self) -> list:
        return [0.0] + self.levels

    def row_key(self, p: float, v: float) -> tuple:
        """The (P, v) row that the table's node velocity v reads (v = 0: the slowest velocity's, the quasi-static
        row)."""
        return p, (v if v > 0 or not self.qs_row else self.v_grid[0])

    def rows(self, ens: dict) -> dict:
        def level_at(f, p, v):
            return p >= f.get("min_pressure", 0.0) and (f.get("velocities") is None or v in f["velocities"])

        flakes = self.sweep["flakes"]
        return {(p, v): _Row(ens, p, v, sorted({_key(f["beta"]) for f in flakes if level_at(f, p, v)}),
                             self.n_pixels) for p in self.pressures for v in self.v_grid}


def _fit_summary(rows: list[_Row]) -> dict:
    """Per quantity and form: chi^2 and degrees of freedom summed over the rows, chi^2 / dof, and the rows that pass."""
    out = {}
    for name, forms in FILLED.items():
        out[name] = {}
        for form in forms:
            fits = [r.fits[name][form] for r in rows if form in r.fits[name] and r.fits[name][form].dof > 0]
            chi2, dof = sum(f.chi2 for f in fits), sum(f.dof for f in fits)
            out[name][form] = {"chi2": chi2, "dof": dof, "chi2_per_dof": chi2 / dof if dof else None,
                               "rows_tested": len(fits),
                               "rows_passing": sum(f.passes(FIT_SIGNIFICANCE) for f in fits)}
    return out


def _caps(table: FrictionTable, mu0: float, pressures, velocities) -> list[float | None]:
    """The cap of beta at s = 1 (Eq. 24) at every (P, v): where the table's interpolated share reaches 1
    (tc_law_beta_cap), None when it does not below 1."""
    from tribocosim.components.stripdraw.friction import make_friction_law
    from tribocosim.components.stripdraw.parameters import StripDrawParameters

    law = make_friction_law(StripDrawParameters(mu0=mu0), table)
    caps = []
    for p in pressures:
        for v in velocities:
            c = law.beta_cap(p, v)
            caps.append(c if c < 1.0 else None)
    return caps


def build_table(records: list[dict], manifest: dict, *, failed: list | None = None,
                campaign_info: dict | None = None, surface_stats: dict | None = None) -> tuple[FrictionTable, dict]:
    """The friction table and its fits from the finished case ``records`` of a campaign.

    Parameters
    ----------
    records : list of dict
        Finished case records (:func:`tribocosim.surrogate.campaign.load_records`).
    manifest : dict
        ``OUT/campaign.json``: the sweep (``manifest["sweep"]``) and its cases.
    failed : list of dict, optional
        Failed/missing case records (listed in the metadata).
    campaign_info : dict, optional
        Executor, wall time, ... (recorded as is).
    surface_stats : dict, optional
        :func:`surface_statistics` (computed if not given).

    Returns
    -------
    (FrictionTable, dict)
        The table and its fits (as in the metadata's ``fits``).

    Raises
    ------
    TableError
        If a (P, v) row has no finished case with flakes or no particle-free case.
    """
    from .campaign import case_cpu_seconds, code_version, source_digest

    if not records:
        raise TableError("the campaign has no finished case; nothing to build a table from")
    grid = Grid.of(manifest["sweep"])
    sweep, mu0, e_star = grid.sweep, grid.mu0, grid.e_star
    pressures, v_grid, vel_axis, levels, beta_axis = (grid.pressures, grid.v_grid, grid.vel_axis, grid.levels,
                                                      grid.beta_axis)
    if surface_stats is None:
        surface_stats = surface_statistics(sweep["slide"], sweep["surfaces"])
    h_rms_slope = surface_stats["gap_rms_slope_mean"]

    ens = ensemble(records)
    contact = fit_contact(ens, e_star, h_rms_slope)
    if not contact.slope > 0:
        raise TableError(f"the A_c/A0-vs-P slope is {contact.slope!r}; a positive slope is needed for tau0")
    tau0 = mu0 / contact.slope
    rows = grid.rows(ens)

    shape = (len(pressures), len(vel_axis), len(beta_axis))
    names = ("contact_area", "contact_area_se", "contact_area_std", "particle_area", "particle_area_se",
             "particle_area_std", "particle_area_clusters", "particle_area_clusters_se", "mu_se", "simulated",
             "members")
    arr = {name: np.zeros(shape) for name in names}
    nodes, unsimulated = [], []
    for i, p in enumerate(pressures):
        for j, v in enumerate(vel_axis):
            row = rows[grid.row_key(p, v)]
            for k, b in enumerate(beta_axis):
                node = row.node(b, mu0)
                for name in names:
                    arr[name][i, j, k] = node[name]
                if node["simulated"] == 0.0:
                    unsimulated.append({"pressure": p, "velocity": v, "beta": b, **node["sources"]})
                elif b > 0:
                    q = row.points[b]
                    nodes.append({"pressure": p, "velocity": v, "beta": b, "members": q.n,
                                  "a_p": q.ap_mean, "a_p_se": q.ap_se if q.n > 1 else None, "a_c": q.ac_mean,
                                  "a_p_clusters": q.apc_mean, "mu_se": node["mu_se"],
                                  "alpha": q.ap_mean / (b * p / e_star),
                                  "relative_se": (q.ap_se / q.ap_mean) if q.n > 1 and q.ap_mean > 0 else None})
    mu = mu_of_areas(mu0, arr["particle_area"], arr["contact_area"])
    table = FrictionTable(np.array(pressures), np.array(vel_axis), np.array(beta_axis), mu, {"beta_threshold": 1.0},
                          contact_area=arr["contact_area"], particle_area=arr["particle_area"],
                          contact_area_std=arr["contact_area_std"], particle_area_std=arr["particle_area_std"],
                          extras={name: arr[name] for name in ("simulated", "contact_area_se", "particle_area_se",
                                                               "particle_area_clusters", "particle_area_clusters_se",
                                                               "mu_se")})
    cap_values = _caps(table, mu0, pressures, v_grid)
    caps = [{"pressure": p, "velocity": v, "beta_cap_s1": c, "simulated_max_beta": max(rows[(p, v)].simulated)}
            for (p, v), c in zip([(p, v) for p in pressures for v in v_grid], cap_values)]
    beta_thres = min(1.0, max(cap_values)) if all(c is not None for c in cap_values) else 1.0

    alpha_diag = [{"velocity": a.velocity, "alpha": a.alpha, "alpha_stderr": a.alpha_stderr,
                   "alpha_member_std": a.alpha_member_std, "r2": a.r2, "n_points": a.n_points}
                  for a in fit_alpha(ens, e_star)]
    fits = {"significance": FIT_SIGNIFICANCE,
            "test": "a fit passes when P(chi^2_dof >= its chi^2) >= significance, chi^2 against the ensemble standard "
                    "errors (A_p: at least one contact pixel per member), dof = levels - parameters >= 1",
            "summary": _fit_summary(list(rows.values())),
            "rows": [r.fits_record() for r in rows.values()],
            "unsimulated": unsimulated,
            "contact_area": asdict(contact), "alpha_eq23_per_velocity": alpha_diag, "caps": caps}
    meta = {
        "provenance": "mesoscale",
        "title": f"friction table from the mesoscale campaign '{sweep['name']}'",
        "law": "mu = mu0 (1 - A_p / A_c) (Eq. 7 with tau0 set by mu0, Eq. 6); at every simulated node the ensemble "
               "means of <A_p>/A0 and <A_c>/A0 (Eq. 22) with their ensemble standard errors; unsimulated nodes "
               "filled by their row's fit where it passes its goodness-of-fit test, else held at the row's nearest "
               "simulated level below (fits.unsimulated); interpolated monotone cubic in ln P and beta, linearly "
               "in v; see surrogate.table_build",
        "a_p_definition": "<A_p>/A0 = SlideResult.summary()['mean_particle_fraction']: traction > 0 under every "
                          "load-bearing flake (the cluster rule of Fig. 8, the pinch and hold rules of "
                          "tribocosim.surrogate.coupling); particle_area_clusters: the cluster rule alone "
                          "('mean_particle_fraction_clusters'); A_c from 'mean_contact_fraction'",
        "interpolation": "monotone cubic (Fritsch-Butland PCHIP; the slopes of a node from its neighbours of the same "
                         "kind, simulated or not) in ln P, then in beta, linear in v; the strip-draw law interpolates "
                         "the share A_p / A_c (A_p under contact_area = eq8): components/native/core/tc_table_lookup.c",
        "beta_threshold": beta_thres,
        "beta_threshold_note": "the largest cap of beta at s = 1 over the (P, v) nodes (Eq. 24: where the "
                               "interpolated share A_p / A_c reaches 1), 1 when some (P, v) has none below 1; the "
                               "strip-draw model finds the cap at each (P, v) from the table",
        "calibration": {"mu0": mu0, "tau0": tau0, "tau0_unit": "Pa",
                        "tau0_source": "for reference: tau0 = mu0 / s_c, s_c the through-origin slope of "
                                       f"<A_c>/A0 vs P of the {contact.source}; mu uses mu0 and the areas"},
        "e_star": e_star, "p_crit": grid.p_crit,
        "axes": {
            "pressure": {"unit": UNITS["pressure"], "values": pressures, "source": "campaign grid"},
            "velocity": {"unit": UNITS["velocity"], "campaign": v_grid, "quasi_static_row": grid.qs_row,
                         "note": (f"v = 0: the quasi-static limit, the values of the {v_grid[0]:g} m/s row (the "
                                  "plateau of A_p where the damping per pixel of sliding is large; "
                                  "docs/physics/table_domain.md). " if grid.qs_row else "")
                                 + "Slides slower than the sweep's dem_velocity run the DEM at that speed with the "
                                   "damping per pixel of the physical one (surrogate.slide_config)."},
            "beta": {"unit": UNITS["beta"], "levels": levels, "simulated_max": levels[-1],
                     "note": "beta = N pi (d/2)^2 / L^2 (Eq. 10); 0: particle-free cases. Nodes a (P, v) row did "
                             "not simulate (simulated = 0) are filled as fits.unsimulated says."},
            "order": ["pressure", "velocity", "beta"],
        },
        "fits": fits,
        "campaign": {
            "sweep": sweep,
            "cases_total": len(manifest["cases"]),
            "cases_finished": len(records),
            "cases_failed": [{"case_id": f.get("case_id"), "labels": f.get("labels"),
                              "error": f.get("error", {}).get("message", f.get("status"))}
                             for f in (failed or [])],
            "case_cpu_seconds": case_cpu_seconds(records),
            **(campaign_info or {}),
        },
        "surfaces": surface_stats,
        "ensemble": {"n_members": arr["members"].astype(int).tolist(), "nodes": nodes,
                     "note": "members per node (0: not simulated) and, per simulated node with flakes, the "
                             "ensemble mean of <A_p>/A0 and its standard error (the tabulated values)"},
        "cases": [{"case_id": r["case_id"], "labels": r["labels"],
                   "a_p": r["summary"]["mean_particle_fraction"],
                   "a_p_clusters": r["summary"].get("mean_particle_fraction_clusters"),
                   "a_c": r["summary"]["mean_contact_fraction"], "wall_s": r.get("wall_s")}
                  for r in sorted(records, key=lambda r: r["case_id"])],
        "cases_note": "every finished case behind the table: its labels and results, so that any case can be "
                      "rebuilt from the sweep (surrogate.campaign.make_case), rerun and checked "
                      "(tribocosim surrogate verify)",
        "out_of_range_policy": "clamp (default: nearest edge, counted) or error (components.stripdraw.table); "
                               "lookups that read a node with simulated = 0 are counted too",
        "code_version": code_version(),
        "source_digest": source_digest(),
        "case_code_versions": sorted({r.get("code_version", "unknown") for r in records}),
        "case_source_digests": sorted({r.get("source_digest", "unknown") for r in records}),
        "case_numerics": sorted({r.get("numerics", "unknown") for r in records}),
        "created": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    }
    return dataclasses.replace(table, metadata=json_clean(meta)), json_clean(fits)


def compare_tables(a: FrictionTable, b: FrictionTable) -> dict:
    """Differences of two tables with the same axes, against the uncertainty recorded with both.

    The tolerance per node is two combined standard errors of the tabulated A_p (sqrt(se_a^2 + se_b^2),
    version 3) or the recorded member spread (versions 1 and 2), and at least one contact pixel
    (1/n^2 of A0; tau0 / (P n^2) for mu). Returns the largest difference of mu and the areas, the largest
    ratio to the tolerance, the nodes beyond it and ``within_uncertainty``.
    """
    for name in ("pressure", "velocity", "beta"):
        x, y = getattr(a, name), getattr(b, name)
        if x.shape != y.shape or not np.allclose(x, y, rtol=1e-9, atol=0.0):
            raise TableError(f"the tables have different {name} axes; they cannot be compared node by node")
    n = a.metadata.get("campaign", {}).get("sweep", {}).get("slide", {}).get("n", 256)
    pixel = 1.0 / (n * n)
    out: dict = {"nodes": int(a.mu.size)}
    ok = True
    names = [x for x in ("particle_area", "contact_area") if x in a.arrays() and x in b.arrays()]
    for name in names:
        se = (np.hypot(a.array(name + "_se"), b.array(name + "_se")) if a.version == 3 and b.version == 3
              else np.asarray(a.array(name + "_std")))
        tol = np.maximum(2.0 * se, pixel)
        d = np.abs(a.array(name) - b.array(name))
        out[f"{name}_max_abs_diff"] = float(d.max())
        out[f"{name}_max_diff_over_tolerance"] = float(np.max(d / tol))
        out[f"{name}_nodes_beyond_tolerance"] = int(np.count_nonzero(d > tol))
        ok = ok and bool(np.all(d <= tol))
    tau0 = a.metadata.get("calibration", {}).get("tau0")
    d = np.abs(a.mu - b.mu)
    out["max_abs_diff"] = float(d.max())
    if not names:
        std = np.asarray(a.metadata.get("ensemble", {}).get("mu_std", np.zeros_like(a.mu)), float)
        tol = np.maximum(np.maximum(std, tau0 / (a.pressure[:, None, None] * n * n) if tau0 else 0.0), 1e-12)
        out["max_diff_over_tolerance"] = float(np.max(d / tol))
        out["nodes_beyond_tolerance"] = int(np.count_nonzero(d > tol))
        ok = ok and bool(np.all(d <= tol))
    out["tolerance"] = ("2 combined standard errors of the tabulated areas (member spread for versions 1-2), at "
                        "least one contact pixel")
    out["within_uncertainty"] = ok
    return out


def table_at(table: FrictionTable, pressure: float, velocity: float, betas) -> np.ndarray:
    """mu at one (P, v) for several beta (clamped lookups)."""
    return table.interpolate(pressure, velocity, np.asarray(betas, float), "clamp")[0]


def _f(x, spec: str) -> str:
    """Format a number that may be None (a NaN in the JSON metadata)."""
    return "n/a" if x is None else format(x, spec)


def describe(table: FrictionTable) -> str:
    """A human-readable summary of a table (used by ``tribocosim surrogate show``)."""
    m = table.metadata
    lines = [f"friction table  provenance={table.provenance}  format_version={m.get('format_version')}",
             f"  content hash   {m.get('content_hash', '')}",
             f"  created        {m.get('created', '?')}  code {m.get('code_version', '?')}",
             f"  pressure [Pa]  {len(table.pressure)} nodes {table.pressure[0]:.4g} .. {table.pressure[-1]:.4g}",
             f"  velocity [m/s] {len(table.velocity)} nodes " + " ".join(f"{v:g}" for v in table.velocity),
             f"  beta [-]       {len(table.beta)} nodes " + " ".join(f"{b:.4g}" for b in table.beta),
             f"  beta_threshold {table.beta_threshold:.6g}",
             f"  mu range       {table.mu.min():.4f} .. {table.mu.max():.4f}"]
    cal = m.get("calibration")
    if cal:
        lines.append(f"  mu0 = {cal['mu0']:g}, tau0 = {cal['tau0'] / 1e6:.4g} MPa ({cal['tau0_source']})")
    fits = m.get("fits")
    if fits and "rows" in fits:
        for name, forms in fits.get("summary", {}).items():
            lines.append(f"  {name}(beta) per (P, v), goodness of fit at significance {fits['significance']:g}: "
                         + "; ".join(f"{f} chi^2/dof {_f(g['chi2_per_dof'], '.3g')} ({g['rows_passing']} of "
                                     f"{g['rows_tested']} rows pass)" for f, g in forms.items()))
        for a in fits.get("alpha_eq23_per_velocity", []):
            lines.append(f"    Eq. 23 at v = {_f(a['velocity'], 'g')} m/s: alpha = {_f(a['alpha'], '.4g')} +- "
                         f"{_f(a['alpha_stderr'], '.2g')}, R^2 = {_f(a['r2'], '.3f')} ({a['n_points']} points)")
        c = fits["contact_area"]
        lines.append(f"  A_c/A0 = s_c P: s_c = {_f(c['slope'], '.4g')} +- {_f(c['slope_err'], '.2g')} 1/Pa "
                     f"(1/s_c = {1 / c['slope'] / 1e6:.4g} MPa), R^2 = {_f(c['r2'], '.4f')} ({c['source']})")
        for cap in fits.get("caps", []):
            if cap["velocity"] == table.velocity[-1] or cap["velocity"] == 0.08:
                lines.append(f"    cap at s = 1, P = {cap['pressure'] / 1e6:g} MPa, v = {cap['velocity']:g} m/s: "
                             f"{_f(cap['beta_cap_s1'], '.3g')} (simulated up to {cap['simulated_max_beta']:.3g})")
    if table.version >= 3:
        sim = table.array("simulated")
        lines.append(f"  simulated nodes {int(sim.sum())} of {sim.size} (the others: fits.unsimulated)")
    ax = m.get("axes", {}).get("velocity", {})
    if ax.get("note"):
        lines.append(f"  velocity note: {ax['note']}")
    digests = m.get("case_source_digests") or []
    if len(digests) > 1:
        lines.append(f"  WARNING: the cases were computed with {len(digests)} different source versions "
                     f"({', '.join(digests)}): rerun the campaign in a fresh folder for a consistent table")
    camp = m.get("campaign")
    if camp:
        lines.append(f"  campaign '{camp['sweep']['name']}': {camp['cases_finished']}/{camp['cases_total']} "
                     f"cases, {len(camp['cases_failed'])} failed, {camp['case_cpu_seconds']:.0f} core-s")
    if m.get("note"):
        lines.append(f"  note: {m['note']}")
    v08 = 0.08
    if table.velocity[0] <= v08 <= table.velocity[-1]:
        lines.append(f"  mu at v = {v08} m/s:")
        for p in table.pressure:
            mus = table_at(table, p, v08, table.beta)
            lines.append(f"    P = {p / 1e6:6.3g} MPa: " + " ".join(f"{x:.4f}" for x in mus))
    return "\n".join(lines)


def plot_table(table: FrictionTable, path, velocities=None) -> None:
    """mu vs P per beta, one panel per velocity (default: 0.08 m/s if in range and the grid's)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if velocities is None:
        camp = table.metadata.get("axes", {}).get("velocity", {}).get("campaign")
        velocities = list(camp) if camp else list(table.velocity)
        if table.velocity[0] <= 0.08 <= table.velocity[-1] and 0.08 not in velocities:
            velocities = [0.08] + velocities
        velocities = velocities[:4]
    fig, axes = plt.subplots(1, len(velocities), figsize=(4.2 * len(velocities), 3.6),
                             sharey=True, constrained_layout=True, squeeze=False)
    p = np.linspace(table.pressure[0], table.pressure[-1], 60)
    cmap = plt.get_cmap("viridis")
    for ax, v in zip(axes[0], velocities):
        for k, b in enumerate(table.beta):
            mu = table.interpolate(p, v, b, "clamp")[0]
            ax.plot(p / 1e6, mu, color=cmap(k / max(1, len(table.beta) - 1)), label=f"beta = {b:.3g}")
            if v in table.velocity:
                j = int(np.searchsorted(table.velocity, v))
                ax.plot(table.pressure / 1e6, table.mu[:, j, k], "o", ms=3,
                        color=cmap(k / max(1, len(table.beta) - 1)))
        ax.set(xlabel="P [MPa]", title=f"v = {v:g} m/s")
    axes[0][0].set_ylabel("mu")
    axes[0][-1].legend(fontsize=7)
    fig.suptitle(f"friction table ({table.provenance})")
    fig.savefig(path, dpi=110)
    plt.close(fig)


def json_clean(obj):
    """``obj`` with NaN/inf floats replaced by None (strict JSON) and tuples as lists."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {str(k): json_clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_clean(v) for v in obj]
    if isinstance(obj, np.generic):
        return json_clean(obj.item())
    return obj
