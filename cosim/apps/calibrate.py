"""``tribocosim calibrate``: fit the particle-borne area (and zeta) to measured strip-draw friction.

    tribocosim calibrate --measured DATA.csv --out TABLE.npz [--table T] [--contact-area mesoscale|eq8]
                         [--fit particle_area_scale [zeta]] [--set NAME=VALUE ...] [--workers N]
                         [--max-iterations N] [--keep-unconverged]

DATA.csv: a header, then one row per measurement; columns ``pressure`` [Pa], ``tool_length`` [m],
``passes`` (1, 2, 3...: a later pass starts from the debris the previous one left), ``mu_bar`` (the
steady-state friction coefficient) and optionally ``mu_bar_std`` (its standard deviation; the
residuals are weighted by 1 / mu_bar_std, and the standard errors then use it as it is).

What the mesoscale campaign does not pin down is one scalar: the load share of blocked flakes at the
test's 0.08 m/s, far below the campaign's velocities (docs/model.md section 4). The fit scales the
table's A_p by ``particle_area_scale`` s (mu = mu0 (1 - s A_p / A_c)); with ``--fit ... zeta`` also
the fraction of debris carried by the tool. Every point is simulated with the pure strip-draw model
(:mod:`tribocosim.cosim.apps.stripdraw_experiment`, in parallel processes) and the parameters are fitted by
Gauss-Newton least squares with a finite-difference Jacobian, within their ranges (s >= 0,
0 <= zeta <= 1). Standard errors: sqrt(diag((J^T J)^-1)), scaled by the residual variance
chi^2 / (N - n) when the data give no mu_bar_std.

Convergence: an iteration that changes every fitted parameter by at most 1e-6 of its value (of 1e-3 for
values below 1e-3), or by at most 1 % of its standard error (changes that small are far inside what the
data determine), ends the fit. A fit that reaches ``--max-iterations`` (20) without it is not converged:
the command then says so, with the last changes, writes nothing and exits with 1, unless
``--keep-unconverged`` asks for the last iterate; that table's metadata then say ``"converged": false``.

The output is the input table with A_p (and its member spread) times s, and mu recomputed, so that
the model with ``particle_area_scale = 1`` and the same ``contact_area`` is the calibrated one; its
metadata (``strip_draw_calibration``) record the factor and its standard error, zeta when fitted,
the convention, every point's measured and model mu_bar and residual, and the data file's SHA-256.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import hashlib
import sys
import time
from pathlib import Path

import numpy as np

from tribocosim.errors import ParameterError, TribocosimError

COLUMNS = ("pressure", "tool_length", "passes", "mu_bar")
FITTABLE = ("particle_area_scale", "zeta")
BOUNDS = {"particle_area_scale": (0.0, np.inf), "zeta": (0.0, 1.0)}
#: convergence: every parameter's change in an iteration within RTOL of its value (of ATOL_SCALE below it) ...
RTOL, ATOL_SCALE = 1e-6, 1e-3
#: ... or within this fraction of its standard error
STDERR_FRACTION = 0.01
MAX_ITERATIONS = 20


@dataclasses.dataclass(frozen=True)
class Measurement:
    """One row of the data file."""

    pressure: float
    tool_length: float
    passes: int
    mu_bar: float
    mu_bar_std: float | None
    row: int


def read_measurements(path: str | Path) -> list[Measurement]:
    """The rows of a measurement file; ParameterError naming the file, row and column of a bad value."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise ParameterError(f"measurement file {path} cannot be read: {exc}") from exc
    reader = csv.DictReader(text.splitlines())
    header = [h.strip() for h in (reader.fieldnames or [])]
    missing = [c for c in COLUMNS if c not in header]
    if missing:
        raise ParameterError(f"{path}: missing column(s) {', '.join(missing)}; the header needs "
                             f"{', '.join(COLUMNS)} (and optionally mu_bar_std); it has {', '.join(header) or 'nothing'}")
    rows = []
    for k, raw in enumerate(reader, start=2):  # line 1 is the header
        rec = {key.strip(): (value or "").strip() for key, value in raw.items() if key is not None}
        if not any(rec.values()):
            continue

        def number(name: str, check, allowed: str, cast=float):
            text = rec.get(name, "")
            try:
                x = cast(float(text)) if cast is int else float(text)
                if cast is int and float(text) != x:
                    raise ValueError
            except ValueError:
                raise ParameterError(f"{path}, row {k}, column {name}: {text!r} is not {'an integer' if cast is int else 'a number'}") from None
            if not (np.isfinite(x) and check(x)):
                raise ParameterError(f"{path}, row {k}, column {name}: {text} is not allowed; {allowed}")
            return x

        std = rec.get("mu_bar_std", "")
        rows.append(Measurement(
            number("pressure", lambda x: x > 0, "it must be > 0 [Pa]"),
            number("tool_length", lambda x: x > 0, "it must be > 0 [m]"),
            int(number("passes", lambda x: x >= 1, "it must be an integer >= 1", int)),
            number("mu_bar", lambda x: 0 < x < 1, "it must lie in (0, 1)"),
            number("mu_bar_std", lambda x: x > 0, "it must be > 0") if std else None,
            k,
        ))
    if not rows:
        raise ParameterError(f"{path}: no data rows")
    return rows


@dataclasses.dataclass
class Fit:
    """The outcome of :func:`calibrate`."""

    names: tuple[str, ...]
    values: np.ndarray
    stderr: np.ndarray
    model: np.ndarray  # mu_bar of every point at the fit
    residuals: np.ndarray  # model - measured
    iterations: int
    evaluations: int
    converged: bool = True
    last_change: np.ndarray | None = None  # the last iteration's change of every parameter

    def as_dict(self) -> dict:
        return {n: {"value": float(v), "stderr": float(e)} for n, v, e in zip(self.names, self.values, self.stderr)}


def calibrate(data: list[Measurement], parameters: dict, fit: tuple[str, ...] = ("particle_area_scale",),
              workers: int | None = None, log=None, max_iterations: int = MAX_ITERATIONS) -> Fit:
    """Least-squares fit of the ``fit`` parameters of the strip-draw model to ``data``.

    Parameters
    ----------
    data : list of Measurement
    parameters : dict
        The strip-draw component's parameters (``table_file``, ``contact_area``...), fixed.
    fit : tuple of str
        Names among :data:`FITTABLE`; their start values are those of ``parameters`` (or the defaults).
    max_iterations : int
        Gauss-Newton iterations at most; ``Fit.converged`` says whether the convergence test (module
        docstring) passed before.
    """
    from tribocosim.components.stripdraw.component import COMPONENT
    from tribocosim.cosim.apps.stripdraw_experiment import Point, run_points

    unknown = [f for f in fit if f not in FITTABLE]
    if unknown or not fit:
        raise ParameterError(f"--fit {' '.join(fit)}: fit one or both of {', '.join(FITTABLE)}")
    if isinstance(max_iterations, bool) or not isinstance(max_iterations, int) or max_iterations < 1:
        raise ParameterError(f"max_iterations = {max_iterations!r} is not allowed; an integer >= 1 is required")
    theta = np.array([float(parameters.get(n, COMPONENT.defaults[n])) for n in fit])
    if "particle_area_scale" in fit and theta[0] == 0:
        theta[0] = 1.0
    measured = np.array([d.mu_bar for d in data])
    sigma = np.array([d.mu_bar_std or 1.0 for d in data])
    weighted = all(d.mu_bar_std for d in data)
    evaluations = 0

    def model(thetas: list[np.ndarray]) -> list[np.ndarray]:
        nonlocal evaluations
        points = [Point(d.pressure, d.tool_length, d.passes, {**parameters, **dict(zip(fit, th))})
                  for th in thetas for d in data]
        evaluations += len(points)
        mus = np.array([m[-1] for m in run_points(points, workers)])
        return list(mus.reshape(len(thetas), len(data)))

    lo = np.array([BOUNDS[n][0] for n in fit])
    hi = np.array([BOUNDS[n][1] for n in fit])
    current = model([theta])[0]
    it, converged, change = 0, False, np.zeros_like(theta)
    for it in range(1, max_iterations + 1):
        steps = np.maximum(1e-3 * np.abs(theta), 1e-4)
        probes = []
        for j in range(len(fit)):
            t = theta.copy()
            t[j] = t[j] + steps[j] if t[j] + steps[j] <= hi[j] else t[j] - steps[j]
            probes.append(t)
        cols = model(probes)
        J = np.column_stack([(c - current) / (p[j] - theta[j]) for j, (c, p) in enumerate(zip(cols, probes))])
        r = (current - measured) / sigma
        Jw = J / sigma[:, None]
        delta, *_ = np.linalg.lstsq(Jw, -r, rcond=None)
        new = np.clip(theta + delta, lo, hi)
        trial = model([new])[0]
        if np.sum(((trial - measured) / sigma) ** 2) > np.sum(r ** 2) * (1 + 1e-12):  # no progress: half steps
            for _ in range(6):
                new = 0.5 * (theta + new)
                trial = model([new])[0]
                if np.sum(((trial - measured) / sigma) ** 2) <= np.sum(r ** 2):
                    break
        change = new - theta
        stderr = _stderr(J, sigma, (trial - measured) / sigma, weighted, len(data))
        converged = bool(np.all((np.abs(change) <= RTOL * np.maximum(np.abs(theta), ATOL_SCALE))
                                | (np.abs(change) <= STDERR_FRACTION * stderr)))
        theta, current = new, trial
        if log:
            log(f"  iteration {it}: " + ", ".join(f"{n} = {v:.6g}" for n, v in zip(fit, theta))
                + f", RMS residual {np.sqrt(np.mean((current - measured) ** 2)):.3g}")
        if converged:
            break
    r = (current - measured) / sigma
    return Fit(tuple(fit), theta, _stderr(J, sigma, r, weighted, len(data)), current, current - measured, it,
               evaluations, converged, change)


def _stderr(J: np.ndarray, sigma: np.ndarray, r: np.ndarray, weighted: bool, n: int) -> np.ndarray:
    """Standard errors sqrt(diag((J^T J)^-1)) of the weighted problem, scaled by chi^2 / (N - n) unless the data
    give their standard deviations."""
    Jw = J / sigma[:, None]
    cov = np.linalg.pinv(Jw.T @ Jw)
    if not weighted:
        cov = cov * float(np.sum(r ** 2)) / max(1, n - J.shape[1])
    return np.sqrt(np.maximum(np.diag(cov), 0.0))


def scaled_table(table, scale: float, contact_area: str, mu0: float, metadata: dict):
    """The table with A_p and its spread times ``scale`` and mu recomputed (mu0 (1 - A_p / A_c) with the
    table's A_c; the model recomputes mu with the chosen convention anyway), metadata added."""
    from tribocosim.components.stripdraw.table import FrictionTable

    ap = table.particle_area * scale
    mu = mu0 * np.maximum(0.0, 1.0 - np.where(table.contact_area > 0, ap / np.where(table.contact_area > 0,
                                                                                       table.contact_area, 1.0), 0.0))
    meta = {**table.metadata, "strip_draw_calibration": metadata}
    meta.pop("content_hash", None)
    return FrictionTable(table.pressure, table.velocity, table.beta, mu, meta, contact_area=table.contact_area,
                         particle_area=ap, contact_area_std=table.contact_area_std,
                         particle_area_std=table.particle_area_std * scale)


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="tribocosim calibrate", description=__doc__.split("\n\n")[2].strip())
    p.add_argument("--measured", required=True, type=Path, help="CSV: pressure [Pa], tool_length [m], passes, mu_bar "
                   "[, mu_bar_std]")
    p.add_argument("--out", required=True, type=Path, help="the calibrated table to write (.npz)")
    p.add_argument("--table", type=Path, default=None, help="the friction table to calibrate (format version 2; "
                   "default: the shipped one)")
    p.add_argument("--contact-area", choices=("mesoscale", "eq8"), default="mesoscale",
                   help="A_c in mu = mu0 (1 - A_p / A_c): from the table, or the paper's Eq. 8")
    p.add_argument("--fit", nargs="+", default=["particle_area_scale"], metavar="NAME",
                   help=f"what to fit: {' and/or '.join(FITTABLE)} (default: particle_area_scale)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="a strip-draw parameter for every simulation (e.g. zeta=0.2, n_elements=200)")
    p.add_argument("--workers", type=int, default=None, help="processes (default: one per CPU)")
    p.add_argument("--max-iterations", type=int, default=MAX_ITERATIONS, metavar="N",
                   help=f"Gauss-Newton iterations at most (default: {MAX_ITERATIONS})")
    p.add_argument("--keep-unconverged", action="store_true",
                   help="write the table from the last iterate (metadata: converged = false) and exit 0 when the fit "
                        "has not converged within --max-iterations; without it, that is exit code 1 and no table")
    return p


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
                                 "area: rebuild the table with tribocosim surrogate table (version 2)")
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
        print(f"calibrating {', '.join(args.fit)} on {len(data)} point(s) of {args.measured} "
              f"(contact_area = {args.contact_area}, table {table_path.name})", file=sys.stderr)
        fit = calibrate(data, parameters, tuple(args.fit), args.workers, log=lambda s: print(s, file=sys.stderr),
                        max_iterations=args.max_iterations)
    except TribocosimError as exc:
        print(f"tribocosim calibrate: {exc}", file=sys.stderr)
        return 2
    if not fit.converged:
        moved = ", ".join(f"{n} = {v:.6g} changed by {d:+.3g} (standard error {e:.2g})"
                          for n, v, d, e in zip(fit.names, fit.values, fit.last_change, fit.stderr))
        print(f"tribocosim calibrate: the fit has not converged in {fit.iterations} iterations ({fit.evaluations} "
              f"simulations): in the last one {moved}; converged means every change within {RTOL:g} of the value "
              f"or {STDERR_FRACTION:.0%} of the standard error. "
              + (f"Writing the last iterate to {args.out} as asked (--keep-unconverged)." if args.keep_unconverged
                 else f"Nothing written; allow more iterations (--max-iterations) or write the last iterate with "
                      f"--keep-unconverged."), file=sys.stderr)
        if not args.keep_unconverged:
            return 1
    values = dict(zip(fit.names, fit.values))
    scale = float(values.get("particle_area_scale", parameters.get("particle_area_scale", 1.0)))
    mu0 = float(parameters.get("mu0", COMPONENT.defaults["mu0"]))
    meta = {
        "fitted": fit.as_dict(),
        "contact_area": args.contact_area,
        "parameters": {k: v for k, v in parameters.items() if k != "table_file"},
        "source_table": {"path": str(table_path), "content_hash": table.metadata.get("content_hash")},
        "data": {"path": str(args.measured.resolve()),
                 "sha256": hashlib.sha256(args.measured.read_bytes()).hexdigest()},
        "points": [{"row": d.row, "pressure": d.pressure, "tool_length": d.tool_length, "passes": d.passes,
                    "measured": d.mu_bar, "measured_std": d.mu_bar_std, "model": float(m), "residual": float(r)}
                   for d, m, r in zip(data, fit.model, fit.residuals)],
        "note": "particle_area holds the table's A_p times the fitted particle_area_scale: use this table with "
                f"particle_area_scale = 1 and contact_area = {args.contact_area}"
                + (f" and zeta = {values['zeta']:.6g}" if "zeta" in values else ""),
        "iterations": fit.iterations, "simulations": fit.evaluations, "converged": fit.converged,
        "last_change": {n: float(d) for n, d in zip(fit.names, fit.last_change)},
    }
    digest = write_table(args.out, scaled_table(table, scale, args.contact_area, mu0, meta))
    print(f"{'row':>4} {'P [MPa]':>8} {'L_T [mm]':>8} {'passes':>6} {'measured':>9} {'model':>9} {'residual':>9}")
    for p in meta["points"]:
        print(f"{p['row']:>4} {p['pressure'] / 1e6:8.3g} {p['tool_length'] * 1e3:8.3g} {p['passes']:>6} "
              f"{p['measured']:9.4f} {p['model']:9.4f} {p['residual']:+9.4f}")
    for name, v, e in zip(fit.names, fit.values, fit.stderr):
        print(f"{name} = {v:.6g} +- {e:.2g} (standard error){'' if fit.converged else ', NOT CONVERGED'}")
    print(f"wrote {args.out} (sha256 {digest[:16]}...; contact_area = {args.contact_area}; "
          f"{fit.evaluations} simulations in {time.perf_counter() - t0:.1f} s)")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
