"""What the paper report adds to the paper's figures: the multi-pass options, the uncertainty budget, the
drawing-speed prediction, alpha of both observables, and the friction table's checks.

Every strip-draw test is the pure model of :mod:`tribocosim.cosim.studies.stripdraw_experiment` (140 mm draw,
mu_bar over the last 20 %); a drop is 1 - mu_bar(25 MPa) / mu_bar(1 MPa) on the same pad and pass. Each setting is
calibrated the same way as the report's main columns: the scale s of A_p solves the paper's one number, the 35 %
one-pass drop at 25 MPa on the 35 mm pad (:func:`tribocosim.cosim.reports.paper.calibrate`); everything else is
predicted.

- Multi-pass options (:data:`tribocosim.components.stripdraw.multipass_options.OPTIONS`; docs/model.md sections 3-4 and "The floor under debris"): the default model
  (flake-borne shear at the floor the project sets, r = 0.2, no sink, every flake carried into the next pass), the paper's
  model (frictionless flakes, r = 0), the upper end of r's sourced range, and the paper's model with a debris sink
  of length lambda or with half the debris carried into the next pass. None of r, lambda or the carried share is
  measured here: each is shown at values that bracket what the literature and the mesoscale model allow (the
  module constants say why), calibrated on the one-pass 35 % alone, so that the 2- and 3-pass drops, their
  spacing, the 140 mm pad's drop and the debris weighed after each pass are what would tell them apart
  (:mod:`tribocosim.cosim.reports.paper_floor`: five passes at 25 MPa and a seeded strip;
  :mod:`tribocosim.cosim.reports.paper_discriminators`: the drops against pressure, five passes at 10 MPa, the
  coverage after one pass and the start of mu(t)).
- Uncertainty budget: :mod:`tribocosim.cosim.reports.paper_budget` varies every chosen input over the range its
  evidence gives, each setting calibrated and predicted here (:func:`calibrated_predictions`, on the table variants of
  :func:`table_variants`: the ensemble noise, each surface pair alone, the slides on another domain size
  (:data:`DOMAIN_TABLES`), the rows' fits at the simulated nodes (:func:`with_fitted_rows`)).
- The observable (:func:`observable_evidence`): A_p of every load-bearing flake or of the paper's cluster rule alone
  is a model choice, not an input with a range: it is reported beside the budget with its evidence (the alpha of
  Eq. 23 the paper's own macro model needs for the 35 % drop, against the alpha_eff each observable's share gives at
  that model's contact area) and with the predictions of the other choice, and is not summed into the total.
- Drawing speed (:data:`SPEEDS`): mu_bar at 0.02-0.5 m/s after 1 and 3 passes at 25 MPa, with the band of s's
  interval in the budget. The paper's alpha(v) (Fig. 15, rising with v0 by an exponential saturation) would make
  the debris effect grow with the drawing speed; the report names the velocities the table simulated.
- alpha of both observables (every load-bearing flake, the paper's cluster rule alone): the table's Eq. 23 slope
  at its first debris level per velocity row (alpha = A_p / A0 / (beta P / E*), mean over the pressures with its
  standard error), and the alpha(v) study of docs/physics/alpha_velocity.md when its results are shipped
  (``models/alpha_velocity.json``), and the cluster rule at the paper's flake sizes, 25-100 um on a 512 um domain
  (``models/cluster_rule_sizes.json``, benchmarks/cluster_sizes.py).
"""

from __future__ import annotations

import dataclasses
import math
import tempfile
from pathlib import Path

import numpy as np

from tribocosim.errors import TribocosimError
from tribocosim.components.stripdraw.friction_floor import PAPER_MODEL
from tribocosim.components.stripdraw.multipass_options import OPTIONS  # noqa: F401 - the report's options
from tribocosim.components.stripdraw.table import mu_of_areas
from tribocosim.cosim.studies.stripdraw_experiment import Point

#: drawing speeds of the speed prediction [m/s]
SPEEDS = (0.02, 0.05, 0.08, 0.2, 0.5)
#: the long pad of the prediction that tells the options apart
LONG_PAD = 0.14
CAL_PRESSURE, LOW_PRESSURE, CAL_PAD = 25e6, 1e6, 0.035  # the calibration test and its 1 MPa reference
#: the domain-size variation's tables beside the shipped table (256 um), by their variants' names in
#: table_variants: the quick preset's slides on a 128 um and on a 512 um domain (pixels of 1 um) at 1, 20 and
#: 30 MPa, 0.08 m/s (``tribocosim surrogate build --preset domain_128um`` / ``domain_512um``)
DOMAIN_TABLES = {"domain_128": "friction_table_128um.npz", "domain_512": "friction_table_512um.npz"}
FORM_VARIANT = "fitted_rows"  # the table with its rows' fits at the simulated nodes (with_fitted_rows)


#: the model choice reported beside the budget: the observable, as the parameters that choose the other one
OBSERVABLE_CHOICE = {"particle_area_rule": "clusters"}


def with_rows_of(table, other):
    """``table`` with the areas of ``other`` on the (pressure, velocity) rows both tables have: A_p, A_c, their
    standard errors (and mu's, version 4) interpolated in beta onto ``table``'s beta axis (which ``other``'s must
    span) by ``other``'s own interpolation, a node simulated where that lookup reads no unsimulated node of
    ``other``, mu = mu0 (1 - A_p / A_c) there. Version 3 or 4 tables."""
    from tribocosim.errors import TableError

    if other.beta[0] > table.beta[0] or other.beta[-1] < table.beta[-1]:
        raise TableError(f"the beta axis [{other.beta[0]:g}, {other.beta[-1]:g}] does not span the table's "
                         f"[{table.beta[0]:g}, {table.beta[-1]:g}]")
    names = ("particle_area", "contact_area", "particle_area_se", "contact_area_se",
             *(("mu_se",) if table.version >= 4 and other.version >= 4 else ()))
    arrays = {name: table.array(name).copy() for name in (*names, "simulated")}
    for i, p in enumerate(table.pressure):
        for j, v in enumerate(table.velocity):
            if p not in other.pressure or v not in other.velocity:
                continue
            for name in names:
                arrays[name][i, j] = other.interpolate_array(other.array(name), p, v, table.beta, "error")[0]
            arrays["simulated"][i, j] = [0.0 if other.reads_unsimulated(p, v, b) else 1.0 for b in table.beta]
    names = (*names, "simulated")
    ap, ac = arrays["particle_area"], arrays["contact_area"]
    mu = mu_of_areas(table.metadata["calibration"]["mu0"], ap, ac)
    extras = {**table.extras, **{k: arrays[k] for k in names if k in table.extras}}
    return dataclasses.replace(table, particle_area=ap, contact_area=ac, mu=mu, extras=extras)


def with_fitted_rows(table):
    """``table`` (version 4, with its fits recorded) with A_p at every simulated node with flakes replaced by its
    (P, v) row's fit of A_p(beta) of the smaller AIC (the quasi-static row: the slowest row's), mu recomputed: the
    form the table would have if it held a fit where the slides were run. The unsimulated nodes are as they were."""
    from tribocosim.surrogate.fit import beta_form

    rows = {(r["pressure"], r["velocity"]): r for r in table.metadata["fits"]["rows"]}
    slowest = min(v for _, v in rows)
    ap = table.particle_area.copy()
    sim = table.array("simulated") == 1.0
    for i, p in enumerate(table.pressure):
        for j, v in enumerate(table.velocity):
            row = rows.get((float(p), float(v) if v > 0 else slowest))
            if row is None:
                continue
            best = min(row["particle_area"].values(), key=lambda f: f["aic"])
            at = sim[i, j] & (table.beta > 0)
            ap[i, j, at] = np.maximum(beta_form(best["form"], table.beta[at], best["params"]), 0.0)
    return dataclasses.replace(table, particle_area=ap,
                               mu=mu_of_areas(table.metadata["calibration"]["mu0"], ap, table.contact_area))


def table_variants(table, folder: Path, domain_tables: dict[str, Path] | None = None) -> dict[str, str]:
    """The tables the budget varies, written into ``folder``: A_p -/+ one standard error at every node
    (``ensemble_low``/``ensemble_high``), the table rebuilt from the recorded cases of each surface pair alone
    (``pair_0``, ``pair_1``; a version 3 or 4 table that records its campaign), the table with the rows of the
    slides on another domain size (for each variant name -> table file of ``domain_tables``, the names of
    :data:`DOMAIN_TABLES`: :func:`with_rows_of` that table), and the table with its rows' fits at the simulated
    nodes (:data:`FORM_VARIANT`, a version 4 table). Returns name -> path."""
    from tribocosim.components.stripdraw.table import read_table, write_table

    out = {}
    if table.version >= 3:
        se = table.array("particle_area_se")
        for name, sign in (("ensemble_low", -1.0), ("ensemble_high", 1.0)):
            ap = np.maximum(table.particle_area + sign * se, 0.0)
            mu = mu_of_areas(table.metadata["calibration"]["mu0"], ap, table.contact_area)
            variant = dataclasses.replace(table, particle_area=ap, mu=mu)
            out[name] = str(folder / f"{name}.npz")
            write_table(out[name], variant)
        meta = table.metadata
        surfaces = {c["labels"]["surface"] for c in meta.get("cases", [])}
        if "sweep" in meta.get("campaign", {}) and len(surfaces) > 1:
            from tribocosim.surrogate.table_rebuild import rebuild_from_metadata

            for s in sorted(surfaces):
                rebuilt = rebuild_from_metadata(meta, [c for c in meta["cases"] if c["labels"]["surface"] == s])
                out[f"pair_{s}"] = str(folder / f"pair_{s}.npz")
                write_table(out[f"pair_{s}"], rebuilt)
        for name, path in (domain_tables or {}).items():
            out[name] = str(folder / f"{name}.npz")
            write_table(out[name], with_rows_of(table, read_table(path)))
        if table.version >= 4 and "rows" in meta.get("fits", {}):
            out[FORM_VARIANT] = str(folder / f"{FORM_VARIANT}.npz")
            write_table(out[FORM_VARIANT], with_fitted_rows(table))
    return out


def three_pass_points(params: dict, velocity: float = 0.08) -> dict[str, Point]:
    """The tests the options and the budget read: 3 passes on the 35 mm pad at 1 and 25 MPa, one pass on the
    140 mm pad at 1 and 25 MPa."""
    return {"low": Point(LOW_PRESSURE, CAL_PAD, 3, params, velocity),
            "high": Point(CAL_PRESSURE, CAL_PAD, 3, params, velocity),
            "long_low": Point(LOW_PRESSURE, LONG_PAD, 1, params, velocity),
            "long_high": Point(CAL_PRESSURE, LONG_PAD, 1, params, velocity)}


def floor_of(params: dict) -> float:
    """r mu0 of strip-draw parameters (the component's defaults where unset): the least mu of the law, where flakes
    carry the whole contact."""
    from tribocosim.components.stripdraw.component import COMPONENT

    return float(params.get("flake_shear_ratio", COMPONENT.defaults["flake_shear_ratio"])) * float(
        params.get("mu0", COMPONENT.defaults["mu0"]))


def predictions(runs, params: dict, velocity: float = 0.08) -> dict:
    """The drops after 1, 2, 3 passes at 25 MPa (35 mm pad), the 140 mm pad's one-pass drop, the debris weighed and
    the coverage beta (the mean over the strip that passed under the pad) after each pass at 25 MPa, the floor
    r mu0, the largest drops it allows (``bound_3``, ``bound_140``: 1 - r mu0 / mu_bar(1 MPa) of the same test) and
    the clamped lookups of these tests."""
    pts = three_pass_points(params, velocity)
    runs.run(list(pts.values()))
    drops = [1.0 - runs.mu(pts["high"], k) / runs.mu(pts["low"], k) for k in (1, 2, 3)]
    floor = floor_of(params)
    return {"drops": drops, "spacing_3_2": drops[2] - drops[1],
            "drop_140": 1.0 - runs.mu(pts["long_high"]) / runs.mu(pts["long_low"]),
            "debris_g_m2": [runs.result(pts["high"], k)["debris_g_m2"] for k in (1, 2, 3)],
            "coverage": [runs.result(pts["high"], k)["beta_left"] for k in (1, 2, 3)],
            "floor": floor, "bound_3": 1.0 - floor / runs.mu(pts["low"], 3),
            "bound_140": 1.0 - floor / runs.mu(pts["long_low"]),
            "mu_bar_1mpa": runs.mu(pts["low"]),
            "clamps": sum(runs.result(p, k)["table_clamps"] for p in pts.values() for k in range(1, p.passes + 1))}


def calibrated_predictions(runs, params: dict, table, calibrate, log=None) -> dict:
    """s calibrated on the 35 % one-pass drop with ``params`` by ``calibrate`` (the paper report's), then
    :func:`predictions` at that s (or the reason the 35 % cannot be reached)."""
    try:
        cal = calibrate(runs, params, table, log=log)
    except TribocosimError as exc:
        return {"error": str(exc)}
    return {"scale": cal.scale, "calibration": cal, **predictions(runs, {**params, "particle_area_scale": cal.scale})}


def observable_evidence(runs, params: dict, table, calibrate) -> dict:
    """What speaks for each observable at the level the macro model reads (the choice of :data:`OBSERVABLE_CHOICE`).

    - ``alpha_needed``: the alpha of Eq. 23 the paper's own macro model needs for the 35 % one-pass drop: the
      closed-form law (A_c of Eq. 8 with kappa, A_p / A0 = alpha beta P / E* linear in beta, Eq. 9, frictionless
      flakes) with its alpha times the scale ``calibrate`` fits (mu = mu0 (1 - s alpha beta h'_rms / kappa): only
      s alpha enters).
    - per observable, ``alpha_eff``: the table's share A_p / A_c at its first debris level at the test's 0.08 m/s
      times Eq. 8's A_c, as an alpha of Eq. 23: alpha_eff = (A_p / A_c) kappa / (h'_rms beta); at 25 MPa (the
      calibration) and its range over the table's pressures.
    """
    from tribocosim.components.stripdraw.component import COMPONENT

    cal = calibrate(runs, {**params, "friction_model": "closed_form", "particle_area_scale": 1.0, **PAPER_MODEL}, table)
    kappa, slope = (float(params.get(n, COMPONENT.defaults[n])) for n in ("kappa", "rms_slope"))
    alpha_b = float(params.get("alpha_b", COMPONENT.defaults["alpha_b"]))
    out = {"alpha_needed": cal.scale * alpha_b, "alpha_b": alpha_b, "scale": cal.scale, "kappa": kappa,
           "rms_slope": slope, "beta": float(table.beta[1]), "velocity": 0.08}
    for rule, name in (("load_bearing", "particle_area"), ("clusters", "particle_area_clusters")):
        if name not in table.arrays():
            continue
        share = np.where(table.contact_area > 0, table.array(name) / np.where(table.contact_area > 0,
                                                                               table.contact_area, 1.0), 0.0)
        at_nodes = table.interpolate_array(share, table.pressure, 0.08, table.beta[1])[0]
        at_cal = float(table.interpolate_array(share, CAL_PRESSURE, 0.08, table.beta[1])[0])
        factor = kappa / (slope * table.beta[1])
        out[rule] = {"alpha_eff_25mpa": at_cal * factor, "alpha_eff_min": float(at_nodes.min() * factor),
                     "alpha_eff_max": float(at_nodes.max() * factor)}
    return out


def table_alpha(table, rule: str = "particle_area") -> list[dict]:
    """Eq. 23's alpha at small beta per velocity row of a version 3 or 4 table: alpha = A_p / A0 / (beta P / E*)
    at the table's first debris level, mean over the pressures with its standard error; the cluster rule's the same
    way."""
    if table.version < 3:
        return []
    e_star = table.metadata.get("e_star", 55e9)
    values = table.array(rule)
    k = 1  # the first debris level
    out = []
    for j, v in enumerate(table.velocity):
        if v == 0.0:
            continue
        a = values[:, j, k] / table.beta[k] * e_star / table.pressure
        out.append({"velocity": float(v), "alpha": float(a.mean()),
                    "stderr": float(a.std(ddof=1) / math.sqrt(a.size)) if a.size > 1 else math.nan,
                    "beta": float(table.beta[k])})
    return out


def _shipped_json(name: str) -> dict | None:
    """A study's results shipped with the models (``models/NAME``), or None."""
    import json

    from tribocosim.paths import MODELS_DIR

    path = Path(MODELS_DIR) / name
    if not path.is_file():
        return None
    return json.loads(path.read_text())


def alpha_study() -> dict | None:
    """The alpha(v) study's results shipped with the models (docs/physics/alpha_velocity.md), or None."""
    return _shipped_json("alpha_velocity.json")


def cluster_rule_sizes() -> dict | None:
    """The cluster rule at the paper's flake sizes (benchmarks/cluster_sizes.py on a ``cluster_sizes`` campaign:
    25-100 um flakes on a 512 um domain), shipped with the models, or None."""
    return _shipped_json("cluster_rule_sizes.json")


def simulated_velocities(table) -> list[float]:
    """The velocities at which the table's A_p was simulated: a version 3 table's velocities with a simulated node
    (not the v = 0 row copied from the slowest one), a version 2 table's campaign velocities."""
    if table.version >= 3:
        sim = table.array("simulated")
        return [float(v) for j, v in enumerate(table.velocity) if v > 0.0 and sim[:, j, :].any()]
    return [float(v) for v in table.metadata.get("axes", {}).get("velocity", {}).get("campaign", [])]


def speed_points(params: dict, scale: float) -> list[tuple[float, dict[str, Point]]]:
    """The speed prediction's tests: per drawing speed, 3 passes at 1 and 25 MPa on the 35 mm pad."""
    return [(v, {k: p for k, p in three_pass_points({**params, "particle_area_scale": scale}, v).items()
                 if k in ("low", "high")}) for v in SPEEDS]


def speed_prediction(runs, params: dict, scale: float, scales: tuple[float, float]) -> list[dict]:
    """mu_bar after 1 and 3 passes at 25 MPa per drawing speed, and its band over the interval ``scales`` of s."""
    rows = []
    for s in (scale, *scales):
        pts = speed_points(params, s)
        runs.run([p for _, d in pts for p in d.values()])
        for v, d in pts:
            rows.append({"velocity": v, "scale": s, **{f"mu_{k}": runs.mu(d["high"], k) for k in (1, 3)},
                         **{f"drop_{k}": 1.0 - runs.mu(d["high"], k) / runs.mu(d["low"], k) for k in (1, 3)}})
    out = []
    for v in SPEEDS:
        at = [r for r in rows if r["velocity"] == v]
        nominal = at[0]
        entry = {"velocity": v}
        for key in ("mu_1", "mu_3", "drop_1", "drop_3"):
            vals = [r[key] for r in at]
            entry[key] = nominal[key]
            entry[key + "_band"] = (min(vals), max(vals))
        out.append(entry)
    return out


def direct_slide_check(table, workers: int | None, quick: bool, log=None) -> list[dict]:
    """The table against direct slides between its nodes (surrogate.table_check), three placements per surface pair,
    on A_p and on mu: every point in the full report (6 slides a point), the moderate-debris point alone in the quick
    one (CI: a slide at beta = 0.4 or above carries three or more times the flakes and costs several times more). The
    quick check is the full one's first point, slide for slide (seeded), so the two cannot disagree on it."""
    from tribocosim.surrogate.executors import make_executor
    from tribocosim.surrogate.table_check import POINTS, SEEDS, run_check

    if table.version < 3 or "sweep" not in table.metadata.get("campaign", {}):
        return []
    points = POINTS[:1] if quick else POINTS
    if log:
        log(f"direct slides at {len(points)} point(s), {len(SEEDS)} placements per surface pair ...")
    ex = make_executor(workers)
    try:
        return [r.to_dict() for r in run_check(table, ex, points=points)]
    finally:
        ex.close()


def scratch_folder():
    """A temporary folder for the table variants (removed when the report ends)."""
    return tempfile.TemporaryDirectory(prefix="tribocosim-paper-")
