"""``tribocosim calibrate``: fit the particle-borne area and the debris balance to measured friction and debris.

    tribocosim calibrate --measured DATA.csv --out TABLE.npz [--table T] [--contact-area mesoscale|eq8]
                         [--fit NAME ...] [--set NAME=VALUE ...] [--workers N] [--max-iterations N]
                         [--keep-unconverged]

DATA.csv: a header, then one row per measurement; columns ``pressure`` [Pa], ``tool_length`` [m], ``passes`` (1, 2,
3...: a later pass starts from the debris the previous one left) and at least one of ``mu_bar`` (the steady-state
friction coefficient), ``debris_g_m2`` (the debris left on the strip after that pass, weighed per unit area
[g/m^2]) and ``beta`` (its coverage), each with an optional standard deviation ``<name>_std`` (the residuals are
weighted by 1 / std; data that mix observables need every std).

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


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``tribocosim calibrate``."""
    args = _parser().parse_args(argv)
    from tribocosim.paths import DEFAULT_TABLE
    from tribocosim.components.stripdraw.component import COMPONENT
    from tribocosim.components.stripdraw.table import read_table, write_table

    try:
        data = read_measurements(args.measured)
        table_path = (args.table or DEFAULT_TABLE).resolve()
        table = read_table(table_path)
        if table.version < 2:
            raise ParameterError(f"--table {table_path} is format version 1 (mu only); calibration scales the particle "
                                 "area: rebuild the table with tribocosim surrogate table (version 2 or later)")
        parameters = {"table_file": str(table_path), "contact_area": args.contact_area}
        for item in args.set:
            name, sep, value = item.partition("=")
            field = next((f for f in COMPONENT.parameter_fields if f.name == name.strip()), None)
            if not sep or field is None:
                raise ParameterError(f"--set {item!r}: expected NAME=VALUE with a strip-draw parameter name")
            kind = field.metadata
            parameters[name.strip()] = (value if kind.get("text") or "choices" in kind
                                        else int(value) if kind.get("integer") else float(value))
        COMPONENT.split(parameters)  # every value checked before anything runs
        t0 = time.perf_counter()
        print(f"calibrating {', '.join(args.fit)} on {len(data)} row(s) of {args.measured} "
              f"(contact_area = {args.contact_area}, table {table_path.name})", file=sys.stderr)
        f = calibrate(data, parameters, tuple(args.fit), args.workers, log=lambda s: print(s, file=sys.stderr),
                      max_iterations=args.max_iterations)
    except TribocosimError as exc:
        print(f"tribocosim calibrate: {exc}", file=sys.stderr)
        return 2
    if not f.succeeded:
        print(f"tribocosim calibrate: the fit failed ({f.status()}): {_failure(f)}. "
              + (f"Writing the last iterate to {args.out} as asked (--keep-unconverged)." if args.keep_unconverged
                 else "Nothing written; fix the data or the parameters fitted (--fit), allow more iterations "
                      "(--max-iterations), or write the last iterate with --keep-unconverged."), file=sys.stderr)
        if not args.keep_unconverged:
            return 1
    values = dict(zip(f.names, f.values))
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
        "contact_area": args.contact_area, "particle_area_rule": rule,
        "parameters": {k: v for k, v in parameters.items() if k != "table_file"},
        "source_table": {"path": str(table_path), "content_hash": table.metadata.get("content_hash")},
        "data": {"path": str(args.measured.resolve()),
                 "sha256": hashlib.sha256(args.measured.read_bytes()).hexdigest()},
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
