"""The friction table mu(P, v, beta) from a finished campaign (Sec. 4, 6; docs/model.md section 4).

The table (format version 3, :mod:`tribocosim.components.stripdraw.table`) holds, at every node (P, v, beta),
A_c/A0 and A_p/A0 with their standard errors, where the node was simulated, A_p of the paper's cluster rule
alone, and mu = mu0 (1 - A_p / A_c) (Eq. 7 with tau0 set by the particle-free mu0, Eq. 6), so that mu at
beta = 0 is mu0 at every pressure. The strip-draw model computes mu from the areas, with A_c from the table
(``contact_area = "mesoscale"``) or from Eq. 8 (``"eq8"``).

Axes: the campaign's pressures; its velocities, below them a v = 0 row when the sweep asks for the quasi-static
row (``[table] quasi_static_row``: the values of the slowest velocity, the plateau where the damping per pixel
of sliding is large; docs/physics/table_domain.md measures it); beta = 0 and every debris level of the sweep.
No node lies above the largest simulated level.

Values. At each (P, v) the simulated levels' ensemble means of <A_p>/A0 (Eq. 22), with their standard errors
(member std / sqrt(members)), are fitted with each form of :data:`tribocosim.surrogate.fit.BETA_FORMS`
(Eq. 23's line through the origin and the saturating a beta / (1 + c beta)); the form with the smaller total
Akaike criterion over every (P, v) is the table's (both forms' chi^2 and AIC per (P, v) and in total are in the
metadata, ``fits.beta_forms``). The tabulated A_p is that fit at every beta node, its standard error the
fit's; A_p of the cluster rule alone is fitted with the same form. A_c is the ensemble mean where the node
was simulated (particle-free cases at beta = 0) and a weighted line in beta through the row's simulated nodes
elsewhere. ``simulated`` marks the nodes with slides; the others come from the fit of their (P, v) row and a
strip draw that reads them counts the lookup (docs/model.md section 4).

For reference the metadata also give tau0 = mu0 / s_c, with s_c the through-origin slope of <A_c>/A0 against
P of the particle-free cases (:func:`tribocosim.surrogate.fit.fit_contact`), the cap of beta at s = 1 at every
(P, v) (Eq. 24: where the fitted A_p reaches A_c, or none inside the axis), and alpha = <A_p>/A0 / (beta P / E*)
per node.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict

import numpy as np

from tribocosim.errors import TableError
from tribocosim.components.stripdraw.table import UNITS, FrictionTable, mu_of_areas

from .fit import BETA_FORMS, BetaFit, _key, ensemble, fit_alpha, fit_beta_forms, fit_contact
from .slide_config import SlideConfig


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


class _RowFit:
    """The fits of one (P, v) row: A_p and A_p by the cluster rule in beta, A_c linear in beta."""

    def __init__(self, ens: dict, p: float, v: float, levels: list, n_pixels: int):
        self.p, self.v = p, v
        self.points = {b: ens.get((_key(p), _key(v), _key(b))) for b in [0.0, *levels]}
        self.simulated = [b for b in levels if self.points[b] is not None]
        if not self.simulated:
            raise TableError(f"no finished case with flakes at P = {p:g} Pa, v = {v:g} m/s: rerun the campaign "
                             "(failed cases are retried) before building the table")
        if self.points[0.0] is None:
            raise TableError(f"no finished particle-free case at P = {p:g} Pa, v = {v:g} m/s")
        pts = [self.points[b] for b in self.simulated]
        sig = [_sigma(q, n_pixels) for q in pts]
        self.forms = fit_beta_forms(self.simulated, [q.ap_mean for q in pts], sig)
        sig_c = [max(q.apc_std / math.sqrt(q.n) if q.n > 1 else 0.0, 1.0 / (n_pixels * math.sqrt(q.n))) for q in pts]
        self.forms_clusters = fit_beta_forms(self.simulated, [q.apc_mean for q in pts], sig_c)
        # A_c: a weighted line in beta through the particle-free node and the simulated levels
        bs = np.array([0.0, *self.simulated])
        acs = np.array([self.points[b].ac_mean for b in bs])
        w = np.array([1.0 / max(self.points[b].ac_std / math.sqrt(self.points[b].n) if self.points[b].n > 1
                                else 0.0, 1.0 / n_pixels) ** 2 for b in bs])
        design = np.stack([np.ones_like(bs), bs], axis=1)
        cov = np.linalg.pinv(design.T @ (w[:, None] * design))
        self.ac_line = cov @ (design.T @ (w * acs))
        self.ac_cov = cov

    def contact(self, beta: float) -> tuple[float, float]:
        """A_c/A0 and its standard error at ``beta``: the node's mean where simulated, else the line."""
        q = self.points.get(beta)
        if q is not None and (beta == 0.0 or beta in self.simulated):
            return q.ac_mean, (q.ac_std / math.sqrt(q.n) if q.n > 1 else 0.0)
        g = np.array([1.0, beta])
        return float(g @ self.ac_line), float(math.sqrt(max(g @ self.ac_cov @ g, 0.0)))


def _choose_form(rows: list[_RowFit]) -> tuple[str, dict]:
    """The form of A_p(beta) with the smaller total AIC over the rows where every form was fitted, and the
    evidence (per-row and total chi^2 and AIC of every form)."""
    both = [r for r in rows if all(f in r.forms for f in BETA_FORMS)]
    total = {f: float(sum(r.forms[f].aic for r in both)) for f in BETA_FORMS}
    chi2 = {f: float(sum(r.forms[f].chi2 for r in both)) for f in BETA_FORMS}
    points = int(sum(r.forms["linear"].n_points for r in both))
    form = min(BETA_FORMS, key=lambda f: total[f]) if both else "linear"
    evidence = {
        "chosen": form,
        "criterion": "Akaike AIC = chi^2 + 2 k summed over the (P, v) rows with at least two simulated levels "
                     "(k parameters per row, chi^2 with the ensemble standard errors)",
        "total_aic": total, "total_chi2": chi2, "rows_compared": len(both), "points": points,
        "parameters_per_row": {"linear": 1, "langmuir": 2},
        "rows": [{"pressure": r.p, "velocity": r.v, "levels": r.simulated,
                  **{f: r.forms[f].to_dict() for f in BETA_FORMS if f in r.forms}} for r in rows],
    }
    return form, evidence


def _fit_of(forms: dict, form: str) -> BetaFit:
    return forms.get(form) or forms["linear"]


def _cap(row: _RowFit, fit: BetaFit, top: float) -> float | None:
    """The smallest beta in (0, top] where the fitted A_p reaches A_c (s = 1), or None."""
    grid = np.linspace(0.0, top, 2001)[1:]
    d = fit(grid) - np.array([row.contact(float(b))[0] if b in row.points else float(np.array([1.0, b]) @ row.ac_line)
                              for b in grid])
    hit = np.flatnonzero(d >= 0.0)
    return float(grid[hit[0]]) if hit.size else None


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

    sweep = manifest["sweep"]
    if not records:
        raise TableError("the campaign has no finished case; nothing to build a table from")
    if not sweep.get("particle_free", True):
        raise TableError("the sweep has no particle-free cases (particle_free = false); A_c at beta = 0 and tau0 "
                         "need them")
    base = SlideConfig(**sweep["slide"])
    e_star, p_crit, n_pixels = base.e_star, base.p_crit, base.n * base.n
    tset = sweep["table"]
    mu0 = float(tset["mu0"])
    if surface_stats is None:
        surface_stats = surface_statistics(sweep["slide"], sweep["surfaces"])
    h_rms_slope = surface_stats["gap_rms_slope_mean"]

    ens = ensemble(records)
    contact = fit_contact(ens, e_star, h_rms_slope)
    if not contact.slope > 0:
        raise TableError(f"the A_c/A0-vs-P slope is {contact.slope!r}; a positive slope is needed for tau0")
    tau0 = mu0 / contact.slope

    pressures = sorted(float(p) for p in sweep["pressures"])
    v_grid = sorted(float(v) for v in sweep["velocities"])
    qs_row = bool(tset.get("quasi_static_row", False))
    vel_axis = ([0.0] if qs_row else []) + v_grid
    flakes = sweep["flakes"]
    levels = sorted({_key(f["beta"]) for f in flakes})
    beta_axis = [0.0] + levels

    def level_at(f, p, v):
        return p >= f.get("min_pressure", 0.0) and (f.get("velocities") is None or v in f["velocities"])

    rows = {(p, v): _RowFit(ens, p, v, sorted({_key(f["beta"]) for f in flakes if level_at(f, p, v)}), n_pixels)
            for p in pressures for v in v_grid}
    form, evidence = _choose_form(list(rows.values()))

    shape = (len(pressures), len(vel_axis), len(beta_axis))
    arr = {name: np.zeros(shape) for name in ("mu", "ap", "ap_se", "ap_std", "ac", "ac_se", "ac_std", "apc",
                                              "apc_se", "simulated", "n")}
    caps, nodes = [], []
    for i, p in enumerate(pressures):
        for j, v in enumerate(vel_axis):
            v_row = v if v > 0 or not qs_row else v_grid[0]
            row = rows[(p, v_row)]
            fit = _fit_of(row.forms, form)
            fit_c = _fit_of(row.forms_clusters, form)
            for k, b in enumerate(beta_axis):
                simulated = b == 0.0 or b in row.simulated
                q = row.points.get(b) if simulated else None
                ac, ac_se = row.contact(b)
                if b == 0.0:
                    ap = ap_se = apc = apc_se = 0.0
                else:
                    ap, ap_se = float(fit(b)), float(fit.stderr(b)[0])
                    apc, apc_se = max(0.0, float(fit_c(b))), float(fit_c.stderr(b)[0])
                arr["ap"][i, j, k], arr["ap_se"][i, j, k] = max(ap, 0.0), ap_se
                arr["apc"][i, j, k], arr["apc_se"][i, j, k] = apc, apc_se
                arr["ac"][i, j, k], arr["ac_se"][i, j, k] = max(ac, 0.0), ac_se
                arr["ap_std"][i, j, k] = q.ap_std if q is not None else ap_se
                arr["ac_std"][i, j, k] = q.ac_std if q is not None else ac_se
                arr["simulated"][i, j, k] = 1.0 if simulated else 0.0
                arr["n"][i, j, k] = q.n if q is not None else 0
                if q is not None and b > 0:
                    x = b * p / e_star
                    nodes.append({"pressure": p, "velocity": v, "beta": b, "members": q.n,
                                  "a_p": q.ap_mean, "a_p_se": q.ap_se if q.n > 1 else None,
                                  "a_p_fit": ap, "a_p_fit_se": ap_se, "a_c": q.ac_mean,
                                  "a_p_clusters": q.apc_mean, "alpha": q.ap_mean / x,
                                  "relative_se": (q.ap_se / q.ap_mean) if q.n > 1 and q.ap_mean > 0 else None})
            caps.append({"pressure": p, "velocity": v, "beta_cap_s1": _cap(row, fit, beta_axis[-1]),
                         "simulated_max_beta": max(row.simulated)})
    arr["mu"] = mu_of_areas(mu0, arr["ap"], arr["ac"])
    cap_values = [c["beta_cap_s1"] for c in caps if c["beta_cap_s1"] is not None]
    beta_thres = min(1.0, max(cap_values)) if cap_values and len(cap_values) == len(caps) else 1.0

    alpha_diag = [{"velocity": a.velocity, "alpha": a.alpha, "alpha_stderr": a.alpha_stderr,
                   "alpha_member_std": a.alpha_member_std, "r2": a.r2, "n_points": a.n_points}
                  for a in fit_alpha(ens, e_star)]
    fits = {"beta_forms": evidence, "contact_area": asdict(contact),
            "alpha_eq23_per_velocity": alpha_diag,
            "caps": caps}
    meta = {
        "provenance": "mesoscale",
        "title": f"friction table from the mesoscale campaign '{sweep['name']}'",
        "law": "mu = mu0 (1 - A_p / A_c) (Eq. 7 with tau0 set by mu0, Eq. 6); A_p(beta) at every (P, v) the fitted "
               f"form '{form}' of the simulated levels' ensemble means of <A_p>/A0 (Eq. 22), A_c the ensemble "
               "mean where simulated; see surrogate.table_build",
        "a_p_definition": "<A_p>/A0 = SlideResult.summary()['mean_particle_fraction']: traction > 0 under every "
                          "load-bearing flake (the cluster rule of Fig. 8, the pinch and hold rules of "
                          "tribocosim.surrogate.coupling); particle_area_clusters: the cluster rule alone "
                          "('mean_particle_fraction_clusters'); A_c from 'mean_contact_fraction'",
        "a_p_form": form,
        "beta_threshold": beta_thres,
        "beta_threshold_note": "the largest cap of beta at s = 1 over the (P, v) nodes (Eq. 24: where the fitted "
                               "A_p reaches A_c), 1 when some (P, v) has none inside the axis; the strip-draw "
                               "model finds the cap at each (P, v) from the tabulated areas",
        "calibration": {"mu0": mu0, "tau0": tau0, "tau0_unit": "Pa",
                        "tau0_source": "for reference: tau0 = mu0 / s_c, s_c the through-origin slope of "
                                       f"<A_c>/A0 vs P of the {contact.source}; mu uses mu0 and the areas"},
        "e_star": e_star, "p_crit": p_crit,
        "axes": {
            "pressure": {"unit": UNITS["pressure"], "values": pressures, "source": "campaign grid"},
            "velocity": {"unit": UNITS["velocity"], "campaign": v_grid, "quasi_static_row": qs_row,
                         "note": (f"v = 0: the quasi-static limit, the values of the {v_grid[0]:g} m/s row (the "
                                  "plateau of A_p where the damping per pixel of sliding is large; "
                                  "docs/physics/table_domain.md). " if qs_row else "")
                                 + "Slides slower than the sweep's dem_velocity run the DEM at that speed with the "
                                   "damping per pixel of the physical one (surrogate.slide_config)."},
            "beta": {"unit": UNITS["beta"], "levels": levels, "simulated_max": levels[-1],
                     "note": "beta = N pi (d/2)^2 / L^2 (Eq. 10); 0: particle-free cases. Nodes a (P, v) row did "
                             "not simulate hold its fit (simulated = 0)."},
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
        "ensemble": {"n_members": arr["n"].astype(int).tolist(), "nodes": nodes,
                     "note": "members per node (0: not simulated) and, per simulated node with flakes, the "
                             "ensemble mean of <A_p>/A0, its standard error and the fitted value"},
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
        "created": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    }
    table = FrictionTable(np.array(pressures), np.array(vel_axis), np.array(beta_axis), arr["mu"], json_clean(meta),
                          contact_area=arr["ac"], particle_area=arr["ap"], contact_area_std=arr["ac_std"],
                          particle_area_std=arr["ap_std"],
                          extras={"simulated": arr["simulated"], "contact_area_se": arr["ac_se"],
                                  "particle_area_se": arr["ap_se"], "particle_area_clusters": arr["apc"],
                                  "particle_area_clusters_se": arr["apc_se"]})
    return table, json_clean(fits)


def rebuild_from_metadata(metadata: dict, cases: list[dict] | None = None) -> FrictionTable:
    """The table :func:`build_table` makes from the cases a version 3 table records (``metadata["cases"]``, or the
    subset ``cases`` of them) with its recorded sweep and surface statistics: what the table was built from, without
    the campaign folder."""
    cases = metadata["cases"] if cases is None else cases
    records = [{"case_id": c["case_id"], "labels": c["labels"], "wall_s": c.get("wall_s", 0.0),
                "summary": {"mean_particle_fraction": c["a_p"], "mean_contact_fraction": c["a_c"],
                            "mean_particle_fraction_clusters": c.get("a_p_clusters") or 0.0}} for c in cases]
    manifest = {"sweep": metadata["campaign"]["sweep"],
                "cases": [{"case_id": c["case_id"], "labels": c["labels"]} for c in cases]}
    table, _ = build_table(records, manifest, surface_stats=metadata["surfaces"])
    return table


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
    if fits and "beta_forms" in fits:
        bf = fits["beta_forms"]
        lines.append(f"  A_p(beta) per (P, v): form '{bf['chosen']}' (total AIC "
                     + ", ".join(f"{f} {_f(a, '.1f')}" for f, a in bf["total_aic"].items())
                     + f" over {bf['rows_compared']} rows, {bf['points']} points)")
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
    if table.version == 3:
        sim = table.array("simulated")
        lines.append(f"  simulated nodes {int(sim.sum())} of {sim.size} (the others hold their row's fit)")
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
