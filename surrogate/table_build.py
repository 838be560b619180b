"""The friction table mu(P, v, beta) from a finished campaign (Sec. 4, 6; docs/model.md section 4).

The table (format version 2) holds, at every node (P, v, beta), the ensemble means of <A_c>/A0 and
<A_p>/A0 over the members (placement seeds x surfaces) of the grid point and their member standard
deviations, and mu = mu0 (1 - <A_p> / <A_c>) (Eq. 7 with tau0 set by the particle-free mu0, Eq. 6),
so that mu at beta = 0 is mu0 at every pressure whatever the grid resolves of A_c; the metadata
hold the members' spread of mu (``ensemble.mu_std``) and their count. The strip-draw model computes
mu from the areas, with A_c from the table (``contact_area = "mesoscale"``) or from Eq. 8
(``"eq8"``); the table does not fix that choice.

For reference the metadata also give tau0 = mu0 / s_c, with s_c the through-origin slope of
<A_c>/A0 against P (:func:`tribocosim.surrogate.fit.fit_contact`; particle-free cases when the
sweep has them): the shear strength a single-tau0 law would need.

Axes.

- P: the campaign pressures.
- v: the campaign velocities, and below them ``table.low_velocities`` (e.g. the macro test's
  0.08 m/s, far below the meso runs at m/s to tens of m/s): there A_c = A_c(v_min) (the contact
  is quasi-static) and A_p(v) = A_p(v_min) alpha(v) / alpha(v_min) with the fitted
  alpha(v) = b (1 - exp(-v/v_ref)) (Fig. 15) when that law describes the campaign, else
  A_p(v_min) (held; :func:`low_velocity_policy` says when and the metadata say which), so the
  rows meet the measured row at v_min continuously.
- beta: 0 (particle-free cases, or A_p = 0 with the members' A_c when the sweep has none), the
  campaign's debris levels, and ``table.beta_extension`` nodes above the largest level up to
  beta_thres, with A_p linear in beta (Eq. 23; per member the through-origin slope over the
  levels) and A_c the members' mean over the levels. Such nodes are extrapolated, and the
  metadata say where measurement stops (``axes.beta.measured_max``).

beta_thres (Eq. 24) = kappa / (alpha h'_rms) = s_c E* / alpha with the largest alpha (b, or the
largest per-velocity alpha if that is larger), so that A_p <= A_c at every velocity; limited to 1.
It does not depend on which h'_rms is used, as long as kappa is measured with the same one.

Out-of-range lookups follow the table module's policy (``clamp`` by default, or ``error``).
"""

from __future__ import annotations

import math
import time

import numpy as np

from tribocosim.components.errors import TableError
from tribocosim.components.stripdraw.table import UNITS, FrictionTable

from .fit import FitReport, _key, ensemble, fit_all
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


def _members(ens: dict, p: float, v: float, beta: float) -> dict:
    pt = ens.get((_key(p), _key(v), _key(beta)))
    if pt is None:
        return {}
    return {mk: (ap, ac) for mk, ap, ac in pt.members}


class _Row:
    """Member values (A_p/A0, A_c/A0) of every beta node at one (P, campaign v)."""

    def __init__(self, ens: dict, p: float, v: float, levels: list, particle_free: bool):
        self.levels = {b: _members(ens, p, v, b) for b in levels}
        for b, m in self.levels.items():
            if not m:
                raise TableError(f"no finished case at P = {p:g} Pa, v = {v:g} m/s, beta = {b:.6g}: "
                                 "rerun the campaign (failed cases are retried) before building the table")
        keys = sorted(set().union(*[set(m) for m in self.levels.values()]))
        self.keys = keys
        self.slope, self.ac = {}, {}
        for mk in keys:
            bs = [b for b in levels if mk in self.levels[b]]
            aps = [self.levels[b][mk][0] for b in bs]
            self.slope[mk] = float(np.dot(bs, aps) / np.dot(bs, bs))
            self.ac[mk] = float(np.mean([self.levels[b][mk][1] for b in bs]))
        self.free = _members(ens, p, v, 0.0) if particle_free else {}
        if particle_free and not self.free:
            raise TableError(f"no finished particle-free case at P = {p:g} Pa, v = {v:g} m/s")

    def at(self, beta: float) -> dict:
        if beta == 0.0:
            return self.free or {mk: (0.0, ac) for mk, ac in self.ac.items()}
        if beta in self.levels:
            return self.levels[beta]
        return {mk: (beta * self.slope[mk], self.ac[mk]) for mk in self.keys}


def build_table(records: list[dict], manifest: dict, *, failed: list | None = None,
                campaign_info: dict | None = None, surface_stats: dict | None = None) -> tuple[FrictionTable, FitReport]:
    """The friction table and the fits from the finished case ``records`` of a campaign.

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

    Raises
    ------
    TableError
        If a grid point has no finished case.
    """
    from .campaign import case_cpu_seconds, code_version, source_digest

    sweep = manifest["sweep"]
    if not records:
        raise TableError("the campaign has no finished case; nothing to build a table from")
    base = SlideConfig(**sweep["slide"])
    e_star, p_crit = base.e_star, base.p_crit
    tset = sweep["table"]
    mu0 = float(tset["mu0"])
    if surface_stats is None:
        surface_stats = surface_statistics(sweep["slide"], sweep["surfaces"])
    h_rms_slope = surface_stats["gap_rms_slope_mean"]

    ens = ensemble(records)
    fits = fit_all(ens, e_star, h_rms_slope)
    s_c = fits.contact.slope
    if not s_c > 0:
        raise TableError(f"the A_c/A0-vs-P slope is {s_c!r}; a positive slope is needed for tau0")
    tau0 = mu0 / s_c

    pressures = sorted(float(p) for p in sweep["pressures"])
    v_camp = sorted(float(v) for v in sweep["velocities"])
    v_low = sorted(float(v) for v in tset["low_velocities"])
    levels = sorted({_key(f["beta"]) for f in sweep["flakes"]})
    alpha_max = max([fits.law.b] + [a.alpha for a in fits.alpha])
    beta_thres = 1.0 if alpha_max <= 0 else min(1.0, s_c * e_star / alpha_max)
    ext = []
    if tset["beta_extension"] > 0 and beta_thres > levels[-1] * (1 + 1e-9):
        ext = list(np.linspace(levels[-1], beta_thres, tset["beta_extension"] + 1)[1:])
    beta_axis = [0.0] + levels + ext
    vel_axis = v_low + v_camp

    law = fits.law
    policy, policy_reason = low_velocity_policy(fits)
    if policy == "alpha_law":
        a_min = float(law(v_camp[0]))
        ratio = {v: float(law(v)) / a_min for v in v_low}
    else:
        ratio = {v: 1.0 for v in v_low}

    shape = (len(pressures), len(vel_axis), len(beta_axis))
    mu, mu_std = np.zeros(shape), np.zeros(shape)
    ac_mean, ap_mean, ac_std, ap_std = (np.zeros(shape) for _ in range(4))
    n_mem = np.zeros(shape, dtype=int)

    def std(x):
        return float(np.std(x, ddof=1)) if x.size > 1 else 0.0

    for i, p in enumerate(pressures):
        rows = {v: _Row(ens, p, v, levels, sweep["particle_free"]) for v in v_camp}
        for j, v in enumerate(vel_axis):
            row, scale = (rows[v], 1.0) if v in rows else (rows[v_camp[0]], ratio[v])
            for k, b in enumerate(beta_axis):
                mem = row.at(b)
                ap = np.array([scale * a for a, _ in mem.values()])
                ac = np.array([c for _, c in mem.values()])
                ap_mean[i, j, k], ac_mean[i, j, k] = float(ap.mean()), float(ac.mean())
                ap_std[i, j, k], ac_std[i, j, k] = std(ap), std(ac)
                mu[i, j, k] = mu0 * max(0.0, 1.0 - ap_mean[i, j, k] / ac_mean[i, j, k])
                mu_std[i, j, k] = std(mu0 * (1.0 - ap / ac))
                n_mem[i, j, k] = ap.size

    flakes = sweep["flakes"]
    seeds = sweep["seeds"]
    meta = {
        "provenance": "mesoscale",
        "title": f"friction table from the mesoscale campaign '{sweep['name']}'",
        "law": "mu = mu0 (1 - <A_p> / <A_c>) (Eq. 7 with tau0 set by mu0, Eq. 6) with ensemble-averaged "
               "<A_c>/A0 and <A_p>/A0 (Eq. 22) of BEM-DEM slides (Sec. 5-6), both tabulated (format version 2) "
               "so that the model can take A_c from Eq. 8 instead; see surrogate.table_build",
        "a_p_definition": "<A_p>/A0 = SlideResult.summary()['mean_particle_fraction']: traction > 0 under "
                          "every blocked flake (the cluster rule of Fig. 8 and the pinch rule of "
                          "tribocosim.surrogate.coupling); A_c from 'mean_contact_fraction'",
        "beta_threshold": beta_thres,
        "beta_threshold_note": "Eq. 24: beta_thres = kappa / (alpha h'_rms) = s_c E* / alpha with the "
                               f"largest alpha ({alpha_max:.6g}), limited to 1",
        "calibration": {"mu0": mu0, "tau0": tau0, "tau0_unit": "Pa",
                        "tau0_source": "for reference: tau0 = mu0 / s_c, s_c the through-origin slope of "
                                       f"<A_c>/A0 vs P of the {fits.contact.source}; mu uses mu0 and the areas"},
        "e_star": e_star, "p_crit": p_crit,
        "axes": {
            "pressure": {"unit": UNITS["pressure"], "values": pressures, "source": "campaign grid"},
            "velocity": {"unit": UNITS["velocity"], "campaign": v_camp, "below_campaign": v_low,
                         "below_campaign_policy": policy, "below_campaign_policy_reason": policy_reason,
                         "note": f"The mesoscale runs slide at {v_camp[0]:g} to {v_camp[-1]:g} m/s; the "
                                 "macro strip-draw test runs at 0.08 m/s. Rows below "
                                 f"{v_camp[0]:g} m/s are NOT simulated: A_c there is the measured "
                                 f"A_c at {v_camp[0]:g} m/s and A_p "
                                 + (f"the measured A_p at {v_camp[0]:g} m/s times alpha(v)/alpha("
                                    f"{v_camp[0]:g}) of the fitted alpha(v) = b (1 - exp(-v/v_ref)) "
                                    "(Fig. 15)." if policy == "alpha_law" else
                                    f"the measured A_p at {v_camp[0]:g} m/s (held: {policy_reason}).")},
            "beta": {"unit": UNITS["beta"], "measured": levels, "measured_max": levels[-1],
                     "extrapolated": ext,
                     "note": "beta = N pi (d/2)^2 / L^2 (Eq. 10). beta = 0: "
                             + ("particle-free cases" if sweep["particle_free"] else
                                "A_p = 0 with the members' A_c (no particle-free cases)")
                             + "; nodes above measured_max are extrapolated with A_p linear in "
                               "beta (Eq. 23) up to beta_threshold"},
            "order": ["pressure", "velocity", "beta"],
        },
        "fits": fits.to_dict(),
        "campaign": {
            "sweep": sweep,
            "seeds": seeds,
            "flake_levels": flakes,
            "cases_total": len(manifest["cases"]),
            "cases_finished": len(records),
            "cases_failed": [{"case_id": f.get("case_id"), "labels": f.get("labels"),
                              "error": f.get("error", {}).get("message", f.get("status"))}
                             for f in (failed or [])],
            "case_cpu_seconds": case_cpu_seconds(records),
            **(campaign_info or {}),
        },
        "surfaces": surface_stats,
        "ensemble": {"mu_std": mu_std.tolist(), "n_members": n_mem.tolist(),
                     "note": "standard deviation (ddof 1) of the member values of mu at each node, "
                             "same (pressure, velocity, beta) order as mu"},
        "cases": [{"case_id": r["case_id"], "labels": r["labels"],
                   "a_p": r["summary"]["mean_particle_fraction"],
                   "a_c": r["summary"]["mean_contact_fraction"]}
                  for r in sorted(records, key=lambda r: r["case_id"])],
        "cases_note": "every finished case behind the table: its labels and <A_p>/A0, <A_c>/A0, so "
                      "that any case can be rerun (surrogate.campaign.expand_cases) and checked",
        "out_of_range_policy": "clamp (default: nearest edge, counted) or error "
                               "(components.stripdraw.table)",
        "code_version": code_version(),
        "source_digest": source_digest(),
        "case_code_versions": sorted({r.get("code_version", "unknown") for r in records}),
        "case_source_digests": sorted({r.get("source_digest", "unknown") for r in records}),
        "created": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    }
    table = FrictionTable(np.array(pressures), np.array(vel_axis), np.array(beta_axis), mu, json_clean(meta),
                          contact_area=ac_mean, particle_area=ap_mean, contact_area_std=ac_std,
                          particle_area_std=ap_std)
    return table, fits


def low_velocity_policy(fits: FitReport) -> tuple[str, str]:
    """How the rows below the campaign's velocities get A_p, and why.

    ``"alpha_law"``: scaled by alpha(v)/alpha(v_min) of the fitted law b (1 - exp(-v/v_ref)),
    used only when the law describes the campaign: alpha rises from the smallest to the largest
    campaign velocity, R^2 of the law >= 0.5, and v_ref is resolved (not below v_min/2, where the
    law is flat over the campaign and says nothing about slower sliding). Otherwise ``"hold"``:
    A_p as measured at the smallest campaign velocity (the nearest data; no trend is invented).
    """
    law, per_v = fits.law, sorted(fits.alpha, key=lambda a: a.velocity)
    if not law.b > 0:
        return "hold", "no blocked flake in the campaign (alpha = 0)"
    if not per_v[-1].alpha > per_v[0].alpha:
        return "hold", (f"alpha does not rise with v over the campaign (alpha = {per_v[0].alpha:.4g} at "
                        f"{per_v[0].velocity:g} m/s, {per_v[-1].alpha:.4g} at {per_v[-1].velocity:g} m/s), "
                        "unlike the paper's Fig. 15, so the saturating law cannot be extrapolated")
    if not (math.isfinite(law.r2) and law.r2 >= 0.5):
        return "hold", f"the alpha(v) law fits the campaign poorly (R^2 = {law.r2:.3g} < 0.5)"
    if law.note:
        return "hold", law.note
    return "alpha_law", (f"alpha(v) = b (1 - exp(-v/v_ref)), b = {law.b:.4g}, v_ref = {law.v_ref:.4g} m/s, "
                         f"R^2 = {law.r2:.3f}")


def _threshold_uncertainty(table: FrictionTable) -> float:
    """Standard error of beta_thres = s_c E* / alpha_max (Eq. 24) from the recorded fit errors.

    First-order propagation of the standard errors of s_c and of the alpha that set the threshold
    (the largest per-velocity alpha, or the law's b when that is larger); 0 when the metadata hold no
    fits or the threshold is the cap 1.
    """
    fits = table.metadata.get("fits")
    thr = table.beta_threshold
    if not fits or thr >= 1.0:
        return 0.0
    law = fits["alpha_law"]
    cands = [(a["alpha"], a["alpha_stderr"]) for a in fits["alpha_per_velocity"] if a["alpha"] is not None]
    if law.get("b") is not None:
        cands.append((law["b"], law.get("b_err")))
    alpha, alpha_err = max(cands, key=lambda c: c[0])
    c = fits["contact_area"]
    rel2 = (alpha_err / alpha) ** 2 if alpha_err else 0.0
    rel2 += (c["slope_err"] / c["slope"]) ** 2 if c.get("slope_err") else 0.0
    return thr * math.sqrt(rel2)


def _measured_beta(table: FrictionTable) -> np.ndarray:
    """The beta nodes of a table that are not extrapolated (0 and the campaign's debris levels)."""
    top = table.metadata.get("axes", {}).get("beta", {}).get("measured_max")
    if top is None:
        return table.beta
    return table.beta[table.beta <= top * (1.0 + 1e-9)]


def _along_beta(table: FrictionTable, values: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """``values`` (nP, nv, nb) of ``table`` at other beta nodes, linear along beta in each cell.

    The last cell's line continues past the axis' end: above the measured levels A_p is linear in beta
    and A_c constant (module docstring), so nodes of a slightly larger threshold lie on that line.
    """
    k = np.clip(np.searchsorted(table.beta, beta, side="right") - 1, 0, table.beta.size - 2)
    t = (beta - table.beta[k]) / (table.beta[k + 1] - table.beta[k])
    return (1.0 - t) * values[..., k] + t * values[..., k + 1]


def compare_tables(a: FrictionTable, b: FrictionTable) -> dict:
    """Differences of two tables on ``a``'s nodes, against the uncertainty recorded with ``a``.

    The tolerance per node is the larger of the recorded ensemble std of mu and one contact
    pixel, tau0 / (P n^2) (a rebuild with the same seeds may differ in the last bits of the FFT
    plans, which can flip one pixel and move a flake's path). Returns max |mu_a - mu_b|, the largest
    ratio to the tolerance, the number of nodes beyond it and ``within_uncertainty``.

    The pressure, velocity and measured beta nodes (0 and the debris levels) must be the same. The
    extrapolated beta nodes end at beta_thres (Eq. 24), which the fitted alpha sets, so a rebuild
    puts them elsewhere by a fraction of its standard error: then the thresholds must agree within
    the standard error recorded with ``a`` (:func:`_threshold_uncertainty`), and ``b`` is read at
    ``a``'s extrapolated nodes along its own (linear) extension.
    """
    for name in ("pressure", "velocity"):
        x, y = getattr(a, name), getattr(b, name)
        if x.shape != y.shape or not np.allclose(x, y, rtol=1e-9, atol=0.0):
            raise TableError(f"the tables have different {name} axes; they cannot be compared node by node")
    arrays = ("mu",) + ((("contact_area", "particle_area")) if a.version == 2 and b.version == 2 else ())
    out: dict = {}
    if a.beta.shape == b.beta.shape and np.allclose(a.beta, b.beta, rtol=1e-9, atol=0.0):
        on_a = {name: getattr(b, name) for name in arrays}
        thr_ok = True
    else:
        ma, mb = _measured_beta(a), _measured_beta(b)
        if ma.size == a.beta.size or mb.size == b.beta.size or ma.shape != mb.shape \
                or not np.allclose(ma, mb, rtol=1e-9, atol=0.0):
            raise TableError("the tables have different beta axes (measured debris levels "
                             f"{list(ma)} and {list(mb)}); they cannot be compared node by node")
        thr_tol = _threshold_uncertainty(a)
        thr_diff = abs(a.beta_threshold - b.beta_threshold)
        thr_ok = thr_diff <= thr_tol
        out["beta_threshold"] = {"a": a.beta_threshold, "b": b.beta_threshold, "abs_diff": thr_diff,
                                 "tolerance": thr_tol, "note": "extrapolated beta nodes differ: b is read at "
                                 "a's nodes along its linear extension; tolerance = standard error of "
                                 "beta_thres = s_c E*/alpha_max recorded with a"}
        on_a = {name: _along_beta(b, getattr(b, name), a.beta) for name in arrays}
    d = np.abs(a.mu - on_a["mu"])
    std = np.asarray(a.metadata.get("ensemble", {}).get("mu_std", np.zeros_like(a.mu)), float)
    # one contact pixel more or less (last-bit differences of FFT plans can flip one): tau0/(P n^2)
    tau0 = a.metadata.get("calibration", {}).get("tau0")
    n = a.metadata.get("campaign", {}).get("sweep", {}).get("slide", {}).get("n", 256)
    pixel = tau0 / (a.pressure[:, None, None] * n * n) if tau0 else np.zeros_like(a.mu)
    tol = np.maximum(np.maximum(std, pixel), 1e-12)
    out.update({"max_abs_diff": float(d.max()), "max_diff_over_tolerance": float(np.max(d / tol)),
                "nodes_beyond_tolerance": int(np.count_nonzero(d > tol)), "nodes": int(d.size),
                "tolerance": "max(recorded ensemble std, one contact pixel: tau0/(P n^2) for mu, 1/n^2 for the areas)"})
    ok = bool(np.all(d <= tol)) and thr_ok
    for name in arrays[1:]:
        da = np.abs(getattr(a, name) - on_a[name])
        tol_a = np.maximum(np.maximum(getattr(a, name + "_std"), 1.0 / (n * n)), 1e-15)
        out[f"{name}_max_abs_diff"] = float(da.max())
        out[f"{name}_nodes_beyond_tolerance"] = int(np.count_nonzero(da > tol_a))
        ok = ok and bool(np.all(da <= tol_a))
    if a.version != b.version:
        out["note"] = f"format versions {a.version} and {b.version}: only mu is compared"
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
    if fits:
        lines.append("  Eq. 23 per velocity: A_p/A0 = alpha beta P / E*")
        for a in fits["alpha_per_velocity"]:
            lines.append(f"    v = {_f(a['velocity'], '>6g')} m/s  alpha = {_f(a['alpha'], '.4g')} +- {_f(a['alpha_stderr'], '.2g')} "
                         f"(member std {_f(a['alpha_member_std'], '.2g')})  R^2 = {_f(a['r2'], '.3f')}  ({a['n_points']} points)")
        law = fits["alpha_law"]
        lines.append(f"  alpha(v) = b (1 - exp(-v/v_ref)): b = {_f(law['b'], '.4g')} +- {_f(law['b_err'], '.2g')}, "
                     f"v_ref = {_f(law['v_ref'], '.4g')} +- {_f(law['v_ref_err'], '.2g')} m/s, R^2 = {_f(law['r2'], '.3f')}")
        if law.get("note"):
            lines.append(f"    note: {law['note']}")
        c = fits["contact_area"]
        lines.append(f"  A_c/A0 = s_c P: s_c = {_f(c['slope'], '.4g')} +- {_f(c['slope_err'], '.2g')} 1/Pa "
                     f"(1/s_c = {1 / c['slope'] / 1e6:.4g} MPa), R^2 = {_f(c['r2'], '.4f')}; kappa = "
                     f"{_f(c['kappa'], '.4g')} with h'_rms = {_f(c['rms_slope'], '.4g')} ({c['source']})")
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
