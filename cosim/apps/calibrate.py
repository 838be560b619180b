"""``tribocosim calibrate``: fit the particle-borne area and the debris balance to measured friction and debris.

    tribocosim calibrate --measured DATA.csv --out TABLE.npz [--table T] [--contact-area mesoscale|eq8]
                         [--fit NAME ...] [--set NAME=VALUE ...] [--units SI|mm-t-s] [--workers N]
                         [--max-iterations N] [--allow-clamped] [--keep-unconverged]

DATA.csv: a header, then one row per measurement; columns ``pressure`` [Pa], ``tool_length`` [m] (``--units
mm-t-s``: MPa and mm, as ``tribocosim export`` writes them), ``passes`` (1, 2, 3...: a later pass starts from the
debris the previous one left) and at least one of ``mu_bar`` (the steady-state friction coefficient),
``debris_g_m2`` (the debris left on the strip after that pass, weighed per unit area [g/m^2]) and ``beta`` (its
coverage), each with an optional standard deviation ``<name>_std`` (the residuals are weighted by 1 / std; data that
mix observables need every std).

Refused before anything runs (exit code 2, one line, nothing written): an ``--out`` that cannot be written (a folder,
a missing or read-only folder), a bad ``--set``, a row the model cannot draw (a pad length out of its range), and a
pressure outside the friction table's pressure axis (the line names the column, its values, the table's range and a
likely unit slip, e.g. pressures in MPa read as Pa). Refused after the fit (exit code 2, nothing written): rows whose
draws at the fitted values read the table outside its axes or its simulated range (clamped lookups, e.g. debris beyond
the levels simulated at that pressure), unless ``--allow-clamped`` keeps them; the table's metadata then counts them
per row. SIGINT (Ctrl-C) or SIGTERM stops the fit between draws: one line, nothing written, exit code 128 + the
signal's number.

What the mesoscale campaign does not pin down is the load share of blocked flakes at the test's 0.08 m/s (the scale
s of the table's A_p, ``particle_area_scale``: mu = mu0 (1 - (1 - r) s A_p / A_c)), the flake-borne shear ratio r
(``flake_shear_ratio``, the floor mu = r mu0 where flakes carry the whole contact), and the debris balance that sets
how much debris there is: the production K / H (``archard_k``, H fixed), the share of debris the tool carries
(``zeta``), the share kept between passes (``debris_carry_over``) or a sink (``debris_sink_length``). ``--fit`` names
the parameters to fit (default: particle_area_scale); the fit (:mod:`tribocosim.cosim.apps.calibrate_fit`) is
Gauss-Newton least squares within the parameters' bounds on the pure strip-draw model, with standard errors from the
Jacobian. Below the cap mu depends on s and r only through (1 - r) s: fitted together, they are separated only by
tests whose debris reaches the cap (several passes, high pressure, long pads). When the fit from the start does not
succeed, the fit searches the valley (1 - r) s = const for where the model's debris reaches the cap and fits from
there (the cap search); when no start there fits better, the command says in one line that the data determine only
(1 - r) s, with its value and standard error.

It succeeds when it has converged (every change within 1e-6 of its value, or the change within 1 % of a standard
error), no parameter is held at a bound the data push it against, the residual is not larger than the data's noise
(chi^2 against the stated standard deviations, or the lack of fit against the spread of replicated tests; not judged,
and said so, when the data carry neither) and the data separate the parameters (the Jacobian's singular values, the
parameters' correlations), each judged at the best fit. Otherwise the command says which of these failed (a residual
beyond the noise: the model does not describe the data, with the residual), writes nothing and exits with 1, unless
``--keep-unconverged`` asks for the last iterate; that table's metadata then give the status.

The output is the input table (format version 2 or later) with the A_p of the chosen rule (and its spread and
standard error) times s and mu recomputed, so that the model with ``particle_area_scale = 1`` and the same
``contact_area`` is the calibrated one; its metadata (``strip_draw_calibration``) record every fitted parameter with
its standard error, their correlations, the status, the convention, every point's measured and model values and
residuals, the residual's judgement, the cap search's starts, and the data file's SHA-256. The fitted debris-balance
parameters are strip-draw parameters: the note says which values to run with.
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import sys
import time
from pathlib import Path

import numpy as np

from tribocosim.errors import ParameterError, TribocosimError
from tribocosim.cosim.apps.calibrate_fit import (FITTABLE, MAX_ITERATIONS, RTOL, STDERR_FRACTION, Fit, fit,
                                                 read_measurements, strip_draw_model)

__all__ = ["calibrate", "main", "read_measurements", "scaled_table"]


def calibrate(data, parameters: dict, names: tuple[str, ...] = ("particle_area_scale",), workers: int | None = None,
              log=None, max_iterations: int = MAX_ITERATIONS) -> Fit:
    """:func:`tribocosim.cosim.apps.calibrate_fit.fit` of ``names`` on the strip-draw model (``parameters``: the
    strip-draw component's, ``table_file`` included)."""
    return fit(data, parameters, tuple(names), strip_draw_model(data, workers), log, max_iterations)


def scaled_table(table, scale: float, mu0: float, rule: str, metadata: dict):
    """The table with the A_p of ``rule`` (``load_bearing``: every load-bearing flake; ``clusters``: the cluster rule)
    and its spread and standard error times ``scale``, mu recomputed from the areas (mu0 (1 - A_p / A_c), and its
    standard error times ``scale``), metadata added; every other array as it was."""
    from tribocosim.components.stripdraw.table import mu_of_areas

    meta = {**table.metadata, "strip_draw_calibration": metadata}
    meta.pop("content_hash", None)
    if rule == "clusters":
        extras = dict(table.extras)
        for name in ("particle_area_clusters", "particle_area_clusters_se"):
            extras[name] = table.array(name) * scale
        return dataclasses.replace(table, extras=extras, metadata=meta)
    ap = table.particle_area * scale
    extras = dict(table.extras)
    for name in ("particle_area_se", "mu_se"):
        if name in extras:
            extras[name] = extras[name] * scale
    return dataclasses.replace(table, particle_area=ap, particle_area_std=table.particle_area_std * scale,
                               mu=mu_of_areas(mu0, ap, table.contact_area), extras=extras, metadata=meta)


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="tribocosim calibrate", description=__doc__.split("\n\n")[2].strip())
    p.add_argument("--measured", required=True, type=Path,
                   help="CSV: pressure [Pa], tool_length [m], passes, and mu_bar, debris_g_m2 and/or beta (each with an "
                        "optional <name>_std)")
    p.add_argument("--out", required=True, type=Path, help="the calibrated table to write (.npz)")
    p.add_argument("--table", type=Path, default=None, help="the friction table to calibrate (format version 2 or "
                   "later: with the contact areas; default: the shipped one)")
    p.add_argument("--contact-area", choices=("mesoscale", "eq8"), default="mesoscale",
                   help="A_c in mu = mu0 (1 - A_p / A_c): from the table, or the paper's Eq. 8")
    p.add_argument("--fit", nargs="+", default=["particle_area_scale"], metavar="NAME",
                   help=f"what to fit, any of {', '.join(FITTABLE)} (default: particle_area_scale)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="a strip-draw parameter for every simulation (e.g. zeta=0.2, n_elements=200); a fitted "
                        "parameter's value is its start")
    p.add_argument("--workers", type=int, default=None, help="processes (default: one per CPU)")
    p.add_argument("--max-iterations", type=int, default=MAX_ITERATIONS, metavar="N",
                   help=f"Gauss-Newton iterations at most (default: {MAX_ITERATIONS})")
    p.add_argument("--units", default="SI", help="the unit system of the data's pressure and tool_length columns: SI "
                   "(Pa, m; the default) or mm-t-s (MPa, mm), as tribocosim export's --units")
    p.add_argument("--allow-clamped", action="store_true",
                   help="keep rows whose draws at the fitted values read the friction table outside its axes or its "
                        "simulated range (clamped lookups; the table's metadata counts them per row); without it, "
                        "such rows are refused (exit code 2, nothing written)")
    p.add_argument("--keep-unconverged", action="store_true",
                   help="write the table from the last iterate (metadata: its status) and exit 0 when the fit has not "
                        "converged, is held at a bound, does not describe the data or cannot separate its parameters; "
                        "without it, that is exit code 1 and no table")
    return p


def _failure(f: Fit) -> str:
    """What went wrong with a fit that did not succeed, in words."""
    parts = []
    for n, side in f.at_bound.items():
        lo, hi, _ = FITTABLE[n]
        parts.append(f"{n} = {f.values[f.names.index(n)]:.6g} is held at its {side} bound "
                     f"({lo if side == 'lower' else hi:g}): the data ask for a value beyond it, which the model does "
                     "not allow (e.g. a measured mu_bar above mu0 needs particle_area_scale < 0)")
    if not f.converged:
        moved = ", ".join(f"{n} = {v:.6g} changed by {d:+.3g} (standard error {e:.2g})"
                          for n, v, d, e in zip(f.names, f.values, f.last_change, f.stderr))
        parts.append(f"the fit has not converged in {f.iterations} iterations ({f.evaluations} model evaluations): in "
                     f"the last one {moved}; converged means every change within {RTOL:g} of its value, or the "
                     f"change within {STDERR_FRACTION:.0%} of a standard error")
    parts += f.problems
    rms = np.sqrt(np.mean([(r["residual"] / r["measured"]) ** 2 for r in f.residuals if r["measured"]] or [0.0]))
    return "; ".join(parts) + f" (RMS residual {100 * rms:.3g} % of the data)"


def in_si(data, units) -> list:
    """The measurements with their pressure and tool_length columns converted from ``units`` to SI."""
    return [dataclasses.replace(d, pressure=float(units.pressure_from_file(d.pressure)),
                                tool_length=float(units.length_from_file(d.tool_length))) for d in data]


def _values(xs) -> str:
    return ", ".join(f"{x:g}" for x in dict.fromkeys(xs))


def check_rows(data, parameters: dict, table, source, units) -> None:
    """ParameterError, before anything runs, for a row the model cannot draw or whose lookups would leave the table's
    pressure axis: one line naming the column, its values (in the data's units), what is allowed and the likely unit
    slip."""
    from tribocosim.components.stripdraw.component import COMPONENT

    scale, name = units.pressure_scale, units.pressure
    if parameters.get("friction_model", COMPONENT.defaults["friction_model"]) == "table":
        lo, hi = float(table.pressure[0]), float(table.pressure[-1])
        tol = 1e-9  # an axis end within this (relative) is on it, as the table's lookups take it
        outside = [d for d in data if d.pressure < lo * (1 - tol) or d.pressure > hi * (1 + tol)]
        if outside:
            pressures = [d.pressure for d in outside]
            hint = ""
            if units.name == "SI" and all(lo <= 1e6 * x <= hi for x in pressures):
                hint = "; they look like MPa: give --units mm-t-s (pressure in MPa, tool_length in mm)"
            elif units.name != "SI" and all(lo <= x <= hi for x in pressures):
                hint = "; they look like Pa: give --units SI (pressure in Pa, tool_length in m)"
            raise ParameterError(
                f"--measured {source}: column pressure holds {_values(x / scale for x in pressures)} {name} (rows "
                f"{', '.join(str(d.row) for d in outside)}), outside the friction table's {lo / scale:g}-{hi / scale:g} "
                f"{name}: the model would read the table clamped at its edge{hint}")
    for d in data:
        try:
            COMPONENT.split({**parameters, "tool_length": d.tool_length})
        except ParameterError as exc:
            hint = (" (in mm? give --units mm-t-s)" if units.name == "SI" and d.tool_length >= 1.0 else "")
            raise ParameterError(f"--measured {source}, row {d.row}, column tool_length: "
                                 f"{d.tool_length / units.length_scale:g} {units.length}{hint}: {exc}") from None


def clamped_lookups(data, parameters: dict, workers: int | None = None) -> list[dict]:
    """The rows whose draws with ``parameters`` read the friction table outside its axes or its simulated range: per
    row its test and the number of clamped nodal lookups in its pass (the strip-draw model's ``table_clamp_count``)."""
    from tribocosim.cosim.studies.stripdraw_experiment import Point, draw, run_points

    tests: dict = {}
    for d in data:
        tests[(d.pressure, d.tool_length)] = max(tests.get((d.pressure, d.tool_length), 0), d.passes)
    done = dict(zip(tests, run_points([Point(p, pad, n, parameters) for (p, pad), n in tests.items()], workers,
                                      draw)))
    out = []
    for d in data:
        count = done[(d.pressure, d.tool_length)][d.passes - 1]["table_clamps"]
        if count:
            out.append({"row": d.row, "pressure": d.pressure, "tool_length": d.tool_length, "passes": d.passes,
                        "clamped_lookups": int(count)})
    return out


def _clamped_line(rows: list[dict]) -> str:
    tests = "; ".join(f"row {r['row']} (P = {r['pressure'] / 1e6:g} MPa, L_T = {r['tool_length'] * 1e3:g} mm, pass "
                      f"{r['passes']}): {r['clamped_lookups']}" for r in rows)
    return (f"at the fitted values the draws of {len(rows)} row(s) read the friction table outside its axes or its "
            f"simulated range (clamped lookups: {tests}): the fit rests on values the mesoscale campaign did not "
            "simulate (debris beyond its levels at that pressure)")


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``tribocosim calibrate``."""
    args = _parser().parse_args(argv)
    from tribocosim import interrupt
    from tribocosim.atomic import check_writable
    from tribocosim.components.friction_export.export_units import unit_system
    from tribocosim.components.stripdraw.component import COMPONENT
    from tribocosim.components.stripdraw.table import read_table, write_table
    from tribocosim.components.stripdraw.settings import parse_settings
    from tribocosim.errors import Interrupted
    from tribocosim.paths import DEFAULT_TABLE

    try:
        check_writable(args.out, "--out")
        units = unit_system(args.units)
        data = in_si(read_measurements(args.measured), units)
        table_path = (args.table or DEFAULT_TABLE).resolve()
        table = read_table(table_path)
        if table.version < 2:
            raise ParameterError(f"--table {table_path} is format version 1 (mu only); calibration scales the particle "
                                 "area: rebuild the table with tribocosim surrogate table (version 2 or later)")
        parameters = {"table_file": str(table_path), "contact_area": args.contact_area,
                      **parse_settings(args.set, "--set")}
        COMPONENT.split(parameters)  # every value checked before anything runs
        check_rows(data, parameters, table, args.measured, units)
        t0 = time.perf_counter()
        print(f"calibrating {', '.join(args.fit)} on {len(data)} row(s) of {args.measured} "
              f"(contact_area = {args.contact_area}, table {table_path.name})", file=sys.stderr)
        with interrupt.stop_on_signals("nothing is written"):
            f = calibrate(data, parameters, tuple(args.fit), args.workers, log=lambda s: print(s, file=sys.stderr),
                          max_iterations=args.max_iterations)
            clamped = clamped_lookups(data, {**parameters, **dict(zip(f.names, map(float, f.values)))},
                                      args.workers)
    except Interrupted as exc:
        print(f"tribocosim calibrate: {exc}: the fit is discarded and nothing is written", file=sys.stderr)
        return 128 + exc.signum
    except TribocosimError as exc:
        print(f"tribocosim calibrate: {exc}", file=sys.stderr)
        return 2
    if not f.succeeded and not args.keep_unconverged:
        print(f"tribocosim calibrate: the fit failed ({f.status()}): {_failure(f)}. Nothing written; fix the data or "
              "the parameters fitted (--fit), allow more iterations (--max-iterations), or write the last iterate "
              "with --keep-unconverged.", file=sys.stderr)
        if clamped:
            print(f"tribocosim calibrate: note: {_clamped_line(clamped)}", file=sys.stderr)
        return 1
    if clamped and not args.allow_clamped:
        print(f"tribocosim calibrate: {_clamped_line(clamped)}. Nothing written; leave these rows out, or keep them "
              "with --allow-clamped (the table's metadata then counts their clamped lookups).", file=sys.stderr)
        return 2
    if clamped:
        print(f"tribocosim calibrate: warning: {_clamped_line(clamped)}; kept as asked (--allow-clamped), the table's "
              "metadata counts them (strip_draw_calibration.clamped_rows)", file=sys.stderr)
    if not f.succeeded:
        print(f"tribocosim calibrate: the fit failed ({f.status()}): {_failure(f)}. Writing the last iterate to "
              f"{args.out} as asked (--keep-unconverged).", file=sys.stderr)
    values = dict(zip(f.names, f.values))
    scaled = not all(n in d.stds for d in data for n in d.values)  # calibrate_fit's covariance rule
    scale = float(values.get("particle_area_scale", parameters.get("particle_area_scale", 1.0)))
    mu0 = float(parameters.get("mu0", COMPONENT.defaults["mu0"]))
    rule = str(parameters.get("particle_area_rule", COMPONENT.defaults["particle_area_rule"]))
    others = {n: v for n, v in values.items() if n != "particle_area_scale"}
    meta = {
        "fitted": f.as_dict(),
        "status": f.status(), "converged": f.converged, "at_bound": f.at_bound, "separable": f.separable,
        "inseparable": f.inseparable, "correlation": f.correlation.tolist(),
        "singular_values_in_scale_units": f.singular_values.tolist(),
        "chi2": f.chi2, "dof": f.dof, "shear_scale_product": f.shear_scale,
        "residual_test": f.residual_test.as_dict(), "cap_search": f.search,
        "stderr_scaled_by_reduced_chi2": scaled,
        "contact_area": args.contact_area, "particle_area_rule": rule,
        "parameters": {k: v for k, v in parameters.items() if k != "table_file"},
        "source_table": {"file": table_path.name, "content_hash": table.metadata.get("content_hash")},
        "data": {"file": args.measured.name, "units": units.name,
                 "sha256": hashlib.sha256(args.measured.read_bytes()).hexdigest()},
        "clamped_rows": clamped,
        "points": [{**r, **next({"pressure": d.pressure, "tool_length": d.tool_length, "passes": d.passes}
                                for d in data if d.row == r["row"])} for r in f.residuals],
        "note": f"the {'cluster-rule ' if rule == 'clusters' else ''}particle area holds the table's times the fitted "
                f"particle_area_scale: use this table with particle_area_scale = 1, contact_area = {args.contact_area}"
                + "".join(f", {n} = {v:.6g}" for n, v in others.items()),
        "iterations": f.iterations, "model_evaluations": f.evaluations,
        "last_change": {n: float(d) for n, d in zip(f.names, f.last_change)},
    }
    digest = write_table(args.out, scaled_table(table, scale, mu0, rule, meta))
    print(f"{'row':>4} {'P [MPa]':>8} {'L_T [mm]':>8} {'passes':>6} {'observable':>12} {'measured':>10} {'model':>10} "
          f"{'residual':>10}")
    for p in meta["points"]:
        print(f"{p['row']:>4} {p['pressure'] / 1e6:8.3g} {p['tool_length'] * 1e3:8.3g} {p['passes']:>6} "
              f"{p['observable']:>12} {p['measured']:10.4g} {p['model']:10.4g} {p['residual']:+10.3g}")
    for name, v, e in zip(f.names, f.values, f.stderr):
        error = f"+- {e:.2g} (standard error)" if np.isfinite(e) else f"(at its {f.at_bound.get(name)} bound)"
        print(f"{name} = {v:.6g} {error}{'' if f.succeeded else ', ' + f.status().upper()}")
    reduced = f.chi2 / f.dof if f.dof > 0 else float("nan")
    if scaled:
        print(f"standard errors scaled by the reduced chi^2 = {reduced:.3g} (chi^2 {f.chi2:.4g} over {f.dof} degrees "
              "of freedom): the data give no standard deviations, so their scatter about the fit stands for them")
    else:
        print(f"standard errors from the data's standard deviations, not scaled by the reduced chi^2 = {reduced:.3g} "
              f"(chi^2 {f.chi2:.4g} over {f.dof} degrees of freedom; near 1 when the model describes the data within "
              "them)")
    if f.shear_scale is not None:
        print(f"(1 - flake_shear_ratio) particle_area_scale = {f.shear_scale['value']:.6g} +- "
              f"{f.shear_scale['stderr']:.2g} (the combination mu depends on below the cap)")
    print(f"residual: {f.residual_test.line()}")
    if len(f.names) > 1:
        print("correlations: " + ", ".join(f"{a}/{b} {f.correlation[i, j]:+.3f}" for i, a in enumerate(f.names)
                                           for j, b in enumerate(f.names) if j > i))
    print(f"wrote {args.out} (sha256 {digest[:16]}...; contact_area = {args.contact_area}; "
          f"{f.evaluations} model evaluations in {time.perf_counter() - t0:.1f} s)")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
