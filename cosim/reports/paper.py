"""The paper's macro results (Sec. 2.1 and 7; Figs. 2b, 17b, 18b, 19b), the multi-pass options, the uncertainty
budget, the drawing-speed prediction and the friction table's checks.

``tribocosim report paper --out DIR [--quick] [--table T] [--workers N]``

Every figure is a set of strip-draw tests (:mod:`tribocosim.cosim.studies.stripdraw_experiment`: V0 = 0.08 m/s,
140 mm draw, mu_bar the mean of mu = pull_force / (2 F_N) (Eq. 1) over the last 20 %) with the pure
model and the friction law mu = mu0 (1 - (1 - r) s A_p / A_c) (Eq. 7 with Eq. 6 and flake-borne shear r;
docs/model.md section 4 and "The floor under debris"):

- Fig. 19b: mu_bar against P_N for the 35, 70 and 140 mm pads (zeta 0.2, K 1e-4);
- Fig. 2b: 1, 2 and 3 passes over the same strip on the 35 mm pad;
- Fig. 17b: zeta 0, 0.2, 0.5, 1 on the 35 mm pad (K 1e-4);
- Fig. 18b: K 1e-5 ... 1e-2 on the 70 mm pad (zeta 0).

The drop at a pressure is 1 - mu_bar(P) / mu_bar(1 MPa) on the same curve (same pad, same pass).

Calibration on one number of the paper's text (Sec. 2.1): after one pass on the 35 mm pad, mu_bar at
25 MPa is 35 % below its 1 MPa value. The scale s of A_p (``particle_area_scale``) solves
drop(s) = 0.35 (drop rises with s: blocked flakes carry more of the contact), by bracketing and false
position (Illinois) to |drop - 0.35| < 1e-4. The columns:

- A_c from the table (``mesoscale``, the default), s fitted: the default model (r at the floor the project sets);
- the paper's model (frictionless flakes, r = 0), A_c from the table, s fitted;
- A_c from Eq. 8 (``eq8``), s fitted: the same model up to a constant factor on A_p / A_c (Eq. 8's area over the
  table's), so its s is the other's times that factor and its predictions nearly the same: it confirms nothing
  the first column does not;
- A_c from the table with s = 1: A_p as the mesoscale campaign simulated it, with K, H and zeta as chosen (the
  drop it gives rests on those choices: the uncertainty budget says how much).

The standard error of s reported beside it combines the quote ("35 %" rounded to a whole percent: a uniform error
of +-0.5 points, carried to s by d drop / d s) and the table's ensemble noise; the uncertainty budget
(:mod:`tribocosim.cosim.reports.paper_budget`) adds every other chosen input, r among them, with the floor scan.
Nothing else is fitted; an entry whose mu_bar the floor r mu0 holds (within 10 %) is marked as set by that choice,
the others are predictions. The floor's prediction at 25 MPa (five passes, a seeded strip:
:mod:`tribocosim.cosim.reports.paper_floor`) and the discriminating predictions (the drops against pressure, five
passes at 10 MPa, the coverage after one pass, the start of mu(t): :mod:`tribocosim.cosim.reports.paper_discriminators`)
close the report.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import time
from pathlib import Path

import numpy as np

from tribocosim.errors import TribocosimError
from tribocosim.components.stripdraw.friction_floor import (FLAKE_SHEAR_RATIO_DEFAULT, FLAKE_SHEAR_RATIO_RANGE,
                                                           MU_FLOOR, PAPER_MODEL)
from tribocosim.cosim.studies.stripdraw_experiment import V0, Point, draw, point_pool, run_points
from tribocosim.cosim.reports import paper_budget, paper_discriminators, paper_floor
from tribocosim.cosim.reports import paper_physics as pp
from tribocosim.cosim.reports import paper_text
from tribocosim.cosim.reports.paper_physics import CAL_PAD, CAL_PRESSURE, LOW_PRESSURE

PAPER_DROP_1PASS = 0.35  # Sec. 2.1: 35 % at 25 MPa after one pass, 35 x 35 mm pad
PAPER_DROP_3PASS = 0.72  # Sec. 2.1: "up to 72 % at 25 MPa" after three passes
QUOTE_STD = 0.005 / math.sqrt(3.0)  # "35 %" rounded to a whole percent
PAPER_ZETA, PAPER_K = 0.2, 1e-4  # Fig. 19: the only fitted parameter zeta = 0.2; K = 1e-4
DROP_TOL = 1e-4


@dataclasses.dataclass(frozen=True)
class Grid:
    """The sweeps' values (pressures in MPa)."""

    pressures: tuple = (1, 2, 5, 10, 15, 20, 25, 30)
    pads: tuple = (0.035, 0.07, 0.14)
    passes: int = 3
    zetas: tuple = (0.0, 0.2, 0.5, 1.0)
    ks: tuple = (1e-5, 1e-4, 1e-3, 1e-2)
    trend_pressures: tuple = (1, 5, 10, 20, 30)  # Figs. 17b and 18b
    trend_at: float = 30  # MPa: where the zeta and K trends are read (Figs. 17a and 18a are at 30 MPa)


FULL = Grid()
QUICK = Grid(pressures=(1, 10, 25), zetas=(0.0, 1.0), ks=(1e-5, 1e-3, 1e-2), trend_pressures=(1, 30))


@dataclasses.dataclass(frozen=True)
class Config:
    """One column of the report: a contact-area convention, calibrated or with s = 1, the default model or the
    paper's (frictionless flakes)."""

    contact_area: str
    calibrated: bool
    paper_model: bool = False

    @property
    def label(self) -> str:
        model = "paper's model (r = 0), " if self.paper_model else ""
        return f"{model}A_c {self.contact_area}, {'s fitted' if self.calibrated else 's = 1'}"

    @property
    def key(self) -> str:
        """The name of its calibration: the convention, and the paper's model apart."""
        return f"{self.contact_area}, r = 0" if self.paper_model else self.contact_area


CONFIGS = (Config("mesoscale", True), Config("mesoscale", True, paper_model=True), Config("eq8", True),
           Config("mesoscale", False))


@dataclasses.dataclass
class Calibration:
    """The scale s of A_p that gives the paper's 35 % one-pass drop, with its standard error."""

    scale: float
    drop: float
    slope: float  # d drop / d s at the solution
    stderr_quote: float
    stderr_ensemble: float
    evaluations: int
    history: list

    @property
    def stderr(self) -> float:
        return math.hypot(self.stderr_quote, self.stderr_ensemble)


class Runs:
    """mu_bar of strip-draw tests, each run once (a test with n passes also gives passes 1..n-1), in one pool of
    worker processes kept until :meth:`close` (a calibration's steps are batches of two tests)."""

    def __init__(self, workers: int | None, log=None):
        self.workers, self.log, self._done = workers, log, {}
        self.evaluations = 0
        self._pool = None

    def close(self) -> None:
        """End the worker processes (the results stay)."""
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None

    @staticmethod
    def _key(p: Point) -> tuple:
        return (p.pressure, p.tool_length, p.velocity, tuple(sorted(p.parameters.items())))

    def run(self, points: list[Point]) -> None:
        need: dict[tuple, Point] = {}  # per test, the point with the most passes
        for p in points:
            k = self._key(p)
            if len(self._done.get(k, ())) < p.passes and (k not in need or need[k].passes < p.passes):
                need[k] = p
        todo = list(need.values())
        if todo:
            t0 = time.perf_counter()
            if self._pool is None and len(todo) > 1 and (self.workers or os.cpu_count() or 1) > 1:
                self._pool = point_pool(self.workers)
            for p, passes in zip(todo, run_points(todo, self.workers, draw, self._pool)):
                self._done[self._key(p)] = passes
            self.evaluations += sum(p.passes for p in todo)
            if self.log:
                self.log(f"  {len(todo)} strip-draw tests in {time.perf_counter() - t0:.1f} s")

    def mu(self, point: Point, passes: int = 1) -> float:
        """mu_bar of pass ``passes`` of ``point`` (run by :meth:`run` before)."""
        return self._done[self._key(point)][passes - 1]["mu_bar"]

    def result(self, point: Point, passes: int = 1) -> dict:
        """mu_bar, beta_max and table_clamps of pass ``passes`` of ``point``."""
        return self._done[self._key(point)][passes - 1]


def _params(base: dict, config: Config, scale: float, **extra) -> dict:
    """The strip-draw parameters of a test: the paper's zeta and K (Fig. 19) unless ``extra`` changes them."""
    return {**config_params(base, config), "particle_area_scale": float(scale), **extra}


def config_params(base: dict, config: Config) -> dict:
    """The parameters of a configuration but its scale: the paper's zeta and K (Fig. 19), the table law, and
    frictionless flakes for the paper's model."""
    return {"zeta": PAPER_ZETA, "archard_k": PAPER_K, **base, "friction_model": "table",
            "contact_area": config.contact_area, **(PAPER_MODEL if config.paper_model else {})}


def shear_ratio(base: dict, config: Config) -> float:
    """The flake-borne shear ratio r of a configuration (the default's unless set)."""
    return float(config_params(base, config).get("flake_shear_ratio", FLAKE_SHEAR_RATIO_DEFAULT))


def _drop_points(params: dict, scale: float) -> tuple[Point, Point]:
    p = {**params, "particle_area_scale": float(scale)}
    return Point(LOW_PRESSURE, CAL_PAD, 1, p), Point(CAL_PRESSURE, CAL_PAD, 1, p)


def _drops(runs: Runs, params: dict, scales: list[float]) -> list[float]:
    pairs = [_drop_points(params, s) for s in scales]
    runs.run([p for pair in pairs for p in pair])
    return [1.0 - runs.mu(hi) / runs.mu(lo) for lo, hi in pairs]


def ensemble_rel_stderr(table, contact_area: str) -> float:
    """Relative standard error of the table's A_p (and A_c with ``mesoscale``) at 25 MPa and the test's velocity,
    averaged over the debris levels whose lookups there read simulated nodes only: the tabulated values' standard
    errors (versions 3 and 4), else the member spread over the square root of the members (version 2); 0 without
    either."""
    if table.version < 2:
        return 0.0
    names = ("particle_area", "contact_area") if contact_area == "mesoscale" else ("particle_area",)
    if table.version >= 3:
        betas = np.array([b for b in table.beta if b > 0 and not table.reads_unsimulated(CAL_PRESSURE, V0, b)])
        errors = {name: table.array(name + "_se") for name in names}
        members = None
    else:
        members = np.asarray(table.metadata.get("ensemble", {}).get("n_members", np.zeros(table.mu.shape)), float)
        if not np.any(members > 1):
            return 0.0
        top = table.metadata.get("axes", {}).get("beta", {}).get("measured_max", float(table.beta[-1]))
        betas = table.beta[(table.beta > 0) & (table.beta <= top + 1e-12)]
        errors = {name: getattr(table, name + "_std") for name in names}
    if betas.size == 0:
        return 0.0
    total = 0.0
    for name in names:
        mean, _ = table.interpolate_array(getattr(table, name), CAL_PRESSURE, V0, betas)
        err, _ = table.interpolate_array(errors[name], CAL_PRESSURE, V0, betas)
        if members is not None:
            n, _ = table.interpolate_array(members, CAL_PRESSURE, V0, betas)
            ok = (mean > 0) & (n > 1)
            err = err / np.sqrt(np.where(ok, n, 1.0))
        else:
            ok = mean > 0
        total += float(np.mean((err[ok] / mean[ok]) ** 2)) if np.any(ok) else 0.0
    return math.sqrt(total)


def solve_increasing(f, target: float, tol: float, start: float = 1.0, limit: float = 1e4):
    """``x >= 0`` with ``|f(x) - target| < tol`` for ``f`` increasing from ``f(0) = 0 < target``: a
    bracket grown or shrunk by factors of 4 from ``start``, then false position (Illinois).

    Returns ``(x, f(x))``; raises TribocosimError when ``f`` stays below ``target`` up to ``limit``.
    """
    lo, f_lo = 0.0, -target
    hi = start
    f_hi = f(hi) - target
    while f_hi < 0:
        if hi >= limit:
            raise TribocosimError(f"the value stays below the target {target:g} up to {hi:g}")
        lo, f_lo, hi = hi, f_hi, 4.0 * hi
        f_hi = f(hi) - target
    while lo == 0.0 and hi > 1e-6 * start:  # shrink the upper end while f(hi / 4) is still above the target
        f_q = f(hi / 4.0) - target
        if f_q < 0:
            lo, f_lo = hi / 4.0, f_q
            break
        hi, f_hi = hi / 4.0, f_q
    x, fx, side = hi, f_hi, 0
    for _ in range(100):
        if abs(fx) < tol:
            break
        x = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        fx = f(x) - target
        if fx < 0:
            lo, f_lo = x, fx
            if side == -1:
                f_hi *= 0.5
            side = -1
        else:
            hi, f_hi = x, fx
            if side == 1:
                f_lo *= 0.5
            side = 1
    return x, fx + target


def calibrate(runs: Runs, params: dict, table, target: float = PAPER_DROP_1PASS, log=None) -> Calibration:
    """Solve drop(s) = ``target`` for the scale s of A_p with the strip-draw parameters ``params`` (module
    docstring)."""
    start = runs.evaluations
    history = []
    label = params.get("contact_area", "mesoscale")

    def drop(s: float) -> float:
        d = _drops(runs, params, [s])[0]
        history.append((s, d))
        if log:
            log(f"  {label}: s = {s:.6g}: drop {100 * d:.3f} %")
        return d

    try:
        s, reached = solve_increasing(drop, target, DROP_TOL)
    except TribocosimError as exc:
        raise TribocosimError(f"{label}: the one-pass drop at 25 MPa cannot reach {target:.0%}: {exc}") from None
    h = 0.02 * s
    d_minus, d_plus = _drops(runs, params, [s - h, s + h])
    slope = (d_plus - d_minus) / (2 * h)
    return Calibration(s, reached, slope, QUOTE_STD / abs(slope) if slope else math.inf,
                       s * ensemble_rel_stderr(table, label), runs.evaluations - start, history)


def calibrate_drop(runs: Runs, base: dict, config: Config, table, target: float = PAPER_DROP_1PASS,
                   log=None) -> Calibration:
    """:func:`calibrate` for a configuration's parameters."""
    return calibrate(runs, config_params(base, config), table, target, log)


def figure_points(base: dict, config: Config, scale: float, grid: Grid) -> dict[str, list[tuple[dict, Point]]]:
    """The tests of each figure: (labels, point) pairs."""
    mpa = 1e6
    figs = {"fig19b": [], "fig2b": [], "fig17b": [], "fig18b": []}
    for pad in grid.pads:
        for P in grid.pressures:
            figs["fig19b"].append(({"tool_length": pad, "pressure_mpa": P},
                                   Point(P * mpa, pad, grid.passes if pad == CAL_PAD else 1,
                                         _params(base, config, scale))))
    for k in range(1, grid.passes + 1):
        for P in grid.pressures:
            figs["fig2b"].append(({"pass": k, "pressure_mpa": P},
                                  Point(P * mpa, CAL_PAD, grid.passes, _params(base, config, scale))))
    for z in grid.zetas:
        for P in grid.trend_pressures:
            figs["fig17b"].append(({"zeta": z, "pressure_mpa": P},
                                   Point(P * mpa, CAL_PAD, grid.passes if z == PAPER_ZETA else 1,
                                         _params(base, config, scale, zeta=z))))
    for K in grid.ks:
        for P in grid.trend_pressures:
            figs["fig18b"].append(({"archard_k": K, "pressure_mpa": P},
                                   Point(P * mpa, 0.07, 1, _params(base, config, scale, zeta=0.0, archard_k=K))))
    return figs


def collect(runs: Runs, figs: dict) -> dict[str, list[dict]]:
    """mu_bar of every figure point, as rows."""
    out = {}
    for name, pairs in figs.items():
        rows = []
        for labels, p in pairs:
            rows.append({**labels, **runs.result(p, labels.get("pass", 1))})
        out[name] = rows
    return out


def _curve(rows, key, value, x="pressure_mpa") -> dict[float, float]:
    return {r[x]: r["mu_bar"] for r in rows if r[key] == value}


def _drop(curve: dict, at: float) -> float:
    return 1.0 - curve[at] / curve[min(curve)]


def metrics(figures: dict, grid: Grid) -> dict:
    """The report's numbers from one configuration's figures (module docstring)."""
    at = 25 if 25 in grid.pressures else max(grid.pressures)
    pads = {pad: _curve(figures["fig19b"], "tool_length", pad) for pad in grid.pads}
    passes = {k: _curve(figures["fig2b"], "pass", k) for k in range(1, grid.passes + 1)}
    ordered = [P for P in grid.pressures if P > min(grid.pressures)
               and all(pads[a][P] > pads[b][P] for a, b in zip(grid.pads, grid.pads[1:]))]
    zeta = {z: _curve(figures["fig17b"], "zeta", z)[grid.trend_at] for z in grid.zetas}
    ks = {K: _curve(figures["fig18b"], "archard_k", K)[grid.trend_at] for K in grid.ks}
    k_steps = [ks[b] - ks[a] for a, b in zip(grid.ks, grid.ks[1:])]
    return {
        "drop_at_mpa": at,
        "drop_1pass": _drop(passes[1], at),
        "drop_by_pass": {k: _drop(c, at) for k, c in passes.items()},
        "drop_by_pad": {pad: _drop(c, at) for pad, c in pads.items()},
        "pad_order_holds": [len(ordered), len(grid.pressures) - 1],
        "mu_by_zeta": zeta,
        "zeta_falls": all(zeta[b] < zeta[a] for a, b in zip(grid.zetas, grid.zetas[1:])),
        "mu_by_k": ks,
        "k_falls": all(s < 0 for s in k_steps),
        "k_steps": k_steps,
        "k_saturates": len(k_steps) >= 2 and abs(k_steps[-1]) < abs(k_steps[-2]),
        "mu_low": passes[1][min(grid.pressures)],
        "mu_at_drop": {k: c[at] for k, c in passes.items()},
        "beta_max": max(r["beta_max"] for rows in figures.values() for r in rows),
        "beta_max_3pass": next(r["beta_max"] for r in figures["fig2b"]
                               if r["pass"] == grid.passes and r["pressure_mpa"] == at),
        "table_clamps": sum(r["table_clamps"] for rows in figures.values() for r in rows),
        "table_clamps_by_scene": _clamps_by_scene(figures),
        "mu_by_pad": pads,
    }


def _clamps_by_scene(figures: dict) -> dict[str, int]:
    """Clamped lookups (outside the table's axes or its simulated range) per figure and series."""
    out = {}
    for name, (_, key, label) in FIGURES.items():
        for r in figures[name]:
            scene = f"{name}: {label(r[key])}, {r['pressure_mpa']:g} MPa"
            out[scene] = out.get(scene, 0) + int(r["table_clamps"])
    return out


# ---- the report ------------------------------------------------------------------------------------------


FIGURES = {  # name: (title, series key, legend label)
    "fig19b": ("Fig. 19b: pad length", "tool_length", lambda v: f"{1000 * v:g} mm pad"),
    "fig2b": ("Fig. 2b: passes (35 mm pad)", "pass", lambda v: f"pass {v}"),
    "fig17b": ("Fig. 17b: zeta (35 mm pad, K 1e-4)", "zeta", lambda v: f"zeta {v:g}"),
    "fig18b": ("Fig. 18b: Archard K (70 mm pad, zeta 0)", "archard_k", lambda v: f"K {v:g}"),
}


def clamps_per_figure(m: dict) -> dict[str, int]:
    """Clamped lookups per figure of one configuration's metrics."""
    out = {name: 0 for name in FIGURES}
    for scene, count in m["table_clamps_by_scene"].items():
        out[scene.split(":")[0]] += count
    return out


def plot(results: dict, out: Path) -> list[str]:
    """One PNG per figure, one panel per configuration."""
    from tribocosim.cosim.studies.plotting import _pyplot

    plt = _pyplot()
    names = []
    for fig_name, (title, key, label) in FIGURES.items():
        fig, axes = plt.subplots(1, len(results), figsize=(3.4 * len(results), 3.2), sharey=True, squeeze=False)
        for ax, (config, res) in zip(axes[0], results.items()):
            rows = res["figures"][fig_name]
            for value in dict.fromkeys(r[key] for r in rows):
                curve = sorted((r["pressure_mpa"], r["mu_bar"]) for r in rows if r[key] == value)
                ax.plot(*zip(*curve), "o-", ms=3, lw=1.2, label=label(value))
            ax.set_title(config.label, fontsize=8)
            ax.set_xlabel("P_N [MPa]")
            ax.grid(True, alpha=0.3)
        axes[0, 0].set_ylabel("mu_bar")
        axes[0, 0].legend(fontsize=7)
        fig.suptitle(title, fontsize=9)
        fig.tight_layout()
        fig.savefig(out / f"{fig_name}.png", dpi=110)
        plt.close(fig)
        names.append(f"{fig_name}.png")
    return names


def run_report(out: Path, table_file: str | None = None, quick: bool = False, workers: int | None = None,
               log=None) -> dict:
    """Run the report (module docstring) into ``out``: paper.md, paper.json, paper.csv, the figures and
    readme_results.md (the README's block of the results)."""
    import csv

    from tribocosim.errors import ParameterError
    from tribocosim.paths import DEFAULT_TABLE
    from tribocosim.components.stripdraw.table import read_table

    grid = QUICK if quick else FULL
    table_path = Path(table_file) if table_file else DEFAULT_TABLE
    table = read_table(table_path)
    if table.version < 2:
        raise ParameterError(f"report paper: friction table {table_path} is format version {table.version}; the "
                             "eq8 and scaled conventions need version 2 or 3 (with the contact areas)")
    base = {"table_file": str(table_path.resolve())}
    out.mkdir(parents=True, exist_ok=True)
    runs = Runs(workers, log)
    t0 = time.perf_counter()
    try:
        cals, results, extra = _compute(runs, base, table, grid, quick, workers, log)
    finally:
        runs.close()
    wall = time.perf_counter() - t0
    with open(out / "paper.csv", "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(["configuration", "figure", "tool_length", "pass", "zeta", "archard_k", "pressure_mpa", "mu_bar"])
        for c, res in results.items():
            for name, rows in res["figures"].items():
                for r in rows:
                    tool = r.get("tool_length", 0.07 if name == "fig18b" else CAL_PAD)
                    w.writerow([c.label, name, tool, r.get("pass", 1), r.get("zeta", 0.0 if name == "fig18b" else
                                PAPER_ZETA), r.get("archard_k", PAPER_K), r["pressure_mpa"], repr(r["mu_bar"])])
    files = plot(results, out) + [paper_floor.plot(extra["prediction"], MU_FLOOR, out),
                                  paper_discriminators.plot(extra["discriminators"], out, floor=MU_FLOOR)]
    header = (f"# The paper's macro results ({'quick' if quick else 'full'} report)\n\nGenerated by `tribocosim report "
              f"paper{' --quick' if quick else ''}` in {wall:.0f} s ({runs.evaluations} strip-draw passes).")
    text = paper_text.markdown(results, cals, grid, table, table_path, header, files)
    calibrated = results[Config("mesoscale", True)]["metrics"]
    text += "\n".join(paper_text.physics_markdown(extra, cals, grid, calibrated, clamps_per_figure(calibrated))) + "\n"
    (out / "paper.md").write_text(text, encoding="utf-8")
    (out / "readme_results.md").write_text(readme_results(results, cals, grid, extra), encoding="utf-8")
    summary = {
        "mode": "quick" if quick else "full", "wall_time": wall, "table": str(table_path),
        "table_hash": table.metadata.get("content_hash"), "grid": dataclasses.asdict(grid),
        "paper": {"drop_1pass_25mpa": PAPER_DROP_1PASS, "drop_3pass_25mpa": PAPER_DROP_3PASS},
        "calibrations": {k: {**dataclasses.asdict(v), "stderr": v.stderr} for k, v in cals.items()},
        "configurations": {c.label: {"contact_area": c.contact_area, "calibrated": c.calibrated,
                                     "flake_shear_ratio": shear_ratio(base, c),
                                     "metrics": _jsonable(r["metrics"])} for c, r in results.items()},
        "floor": {"mu_floor": MU_FLOOR, "flake_shear_ratio_range": list(FLAKE_SHEAR_RATIO_RANGE)},
        "prediction": _jsonable(extra["prediction"]),
        "options": _jsonable({k: {kk: vv for kk, vv in v.items() if kk != "calibration"}
                              for k, v in extra["options"].items()}),
        "budget": _jsonable(extra["budget"]), "discriminators": _jsonable(extra["discriminators"]),
        "observable": _jsonable({"choice": {k: v for k, v in extra["observable"]["choice"].items()
                                            if k != "calibration"},
                                 "evidence": extra["observable"]["evidence"]}),
        "speed": _jsonable(extra["speed"]), "alpha": _jsonable(extra["alpha"]),
        "direct_slides": _jsonable(extra["direct_slides"]),
    }
    (out / "paper.json").write_text(json.dumps(summary, indent=2), encoding="utf-8")
    return summary


def readme_results(results: dict, cals: dict, grid: Grid, extra: dict) -> str:
    """The README's block of the results: the paper-vs-model table, what its entries are, the budget in a paragraph."""
    from tribocosim.cosim.reports.paper_text_predictions import budget_summary

    lines = paper_text.results_table(results, cals, grid)
    lines += ["", paper_text.table_note(), "",
              "Uncertainty budget of the default model (each chosen input over the range its evidence gives, s recalibrated "
              "at every end, each side summed apart; docs/model.md section 8): " + budget_summary(extra["budget"], extra["options"]["default"],
                                                                          cals["mesoscale"])]
    return "\n".join(lines) + "\n"


def _compute(runs: Runs, base: dict, table, grid: Grid, quick: bool, workers: int | None, log=None) -> tuple:
    """The calibrations, every configuration's figures with their metrics, and :func:`physics`."""
    cals = {}
    for config in CONFIGS:
        if config.calibrated and config.key not in cals:
            if log:
                log(f"calibrating s for {config.key} on the 35 % one-pass drop at 25 MPa ...")
            cals[config.key] = calibrate_drop(runs, base, config, table, log=log)
    figs = {c: figure_points(base, c, cals[c.key].scale if c.calibrated else 1.0, grid) for c in CONFIGS}
    if log:
        log("figures ...")
    runs.run([p for f in figs.values() for pairs in f.values() for _, p in pairs])
    results = {}
    for c in CONFIGS:
        figures = collect(runs, figs[c])
        results[c] = {"figures": figures, "metrics": metrics(figures, grid)}
    return cals, results, physics(runs, base, table, cals["mesoscale"], quick, workers, log)


def physics(runs: Runs, base: dict, table, cal: Calibration, quick: bool, workers: int | None, log=None) -> dict:
    """The multi-pass options, the uncertainty budget with its intervals (:mod:`tribocosim.cosim.reports.paper_budget`),
    the observable chosen (the other choice's predictions and the evidence), the drawing-speed prediction, alpha of
    both observables, the floor's prediction (:mod:`tribocosim.cosim.reports.paper_floor`), the discriminating
    predictions (:mod:`tribocosim.cosim.reports.paper_discriminators`) and the direct-slide check
    (:mod:`tribocosim.cosim.reports.paper_physics`), for A_c from the table."""
    params = config_params(base, Config("mesoscale", True))
    if log:
        log("multi-pass options ...")
    options = {o.name: pp.calibrated_predictions(runs, {**params, **o.parameters}, table, calibrate) for o in pp.OPTIONS}
    if log:
        log("uncertainty budget ...")
    nominal = options["default"]
    budget = paper_budget.run_budget(runs, params, base["table_file"], table, calibrate, nominal, cal.stderr_quote,
                                     log)
    if log:
        log("the observable: the other choice and the evidence ...")
    observable = {"choice": pp.calibrated_predictions(runs, {**params, **pp.OBSERVABLE_CHOICE}, table, calibrate),
                  "evidence": pp.observable_evidence(runs, params, table, calibrate)}
    if log:
        log("drawing speed ...")
    speed = pp.speed_prediction(runs, params, cal.scale, budget["intervals"]["scale"])
    alpha = {"load_bearing": pp.table_alpha(table, "particle_area"),
             "clusters": pp.table_alpha(table, "particle_area_clusters"), "study": pp.alpha_study(),
             "sizes": pp.cluster_rule_sizes()}
    if log:
        log("the floor's prediction: five passes and a seeded strip ...")
    prediction = {"five_passes": paper_floor.five_passes(runs, options, params),
                  "seeded": paper_floor.seeded_strip(runs, options, params)}
    if log:
        log("the discriminating predictions: drops against pressure, five passes at 10 MPa, coverage, mu(t) ...")
    discriminators = paper_discriminators.predict(runs, options, params)
    discriminators["separations"] = paper_discriminators.separations(discriminators, prediction["five_passes"],
                                                                     prediction["seeded"])
    checks = pp.direct_slide_check(table, workers, quick, log)
    return {"options": options, "budget": budget, "prediction": prediction, "discriminators": discriminators,
            "observable": observable, "speed": speed, "alpha": alpha, "direct_slides": checks,
            "simulated_velocities": pp.simulated_velocities(table)}


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.floating, np.integer, np.bool_)):
        return x.item()
    return x
