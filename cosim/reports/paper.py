"""The paper's macro results (Sec. 2.1 and 7; Figs. 2b, 17b, 18b, 19b), the multi-pass options, the uncertainty
budget, the drawing-speed prediction and the friction table's checks.

``tribocosim report paper --out DIR [--quick] [--table T] [--workers N]``

Every figure is a set of strip-draw tests (:mod:`tribocosim.cosim.apps.stripdraw_experiment`: V0 = 0.08 m/s,
140 mm draw, mu_bar the mean of mu = pull_force / (2 F_N) (Eq. 1) over the last 20 %) with the pure
model and the friction law mu = mu0 (1 - s A_p / A_c) (Eq. 7 with Eq. 6; docs/model.md section 4):

- Fig. 19b: mu_bar against P_N for the 35, 70 and 140 mm pads (zeta 0.2, K 1e-4);
- Fig. 2b: 1, 2 and 3 passes over the same strip on the 35 mm pad;
- Fig. 17b: zeta 0, 0.2, 0.5, 1 on the 35 mm pad (K 1e-4);
- Fig. 18b: K 1e-5 ... 1e-2 on the 70 mm pad (zeta 0).

The drop at a pressure is 1 - mu_bar(P) / mu_bar(1 MPa) on the same curve (same pad, same pass).

Calibration on one number of the paper's text (Sec. 2.1): after one pass on the 35 mm pad, mu_bar at
25 MPa is 35 % below its 1 MPa value. The scale s of A_p (``particle_area_scale``) solves
drop(s) = 0.35 (drop rises with s: blocked flakes carry more of the contact), by bracketing and false
position (Illinois) to |drop - 0.35| < 1e-4. The columns:

- A_c from the table (``mesoscale``, the default), s fitted;
- A_c from Eq. 8 (``eq8``), s fitted: the same model up to a constant factor on A_p / A_c (Eq. 8's area over the
  table's), so its s is the other's times that factor and its predictions nearly the same: it confirms nothing
  the first column does not;
- A_c from the table with s = 1: A_p as the mesoscale campaign simulated it, with K, H and zeta as chosen (the
  drop it gives rests on those choices: the uncertainty budget says how much).

The standard error of s reported beside it combines the quote ("35 %" rounded to a whole percent: a uniform error
of +-0.5 points, carried to s by d drop / d s) and the table's ensemble noise; the uncertainty budget
(:mod:`tribocosim.cosim.reports.paper_physics`) adds every other chosen input. Nothing else is fitted: the
3-pass drop, the pad ordering and the zeta and K trends are predictions.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from pathlib import Path

import numpy as np

from tribocosim.errors import TribocosimError
from tribocosim.cosim.apps.stripdraw_experiment import V0, Point, draw, run_points
from tribocosim.cosim.reports import paper_physics as pp
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
    """One column of the report: a contact-area convention, calibrated or with s = 1."""

    contact_area: str
    calibrated: bool

    @property
    def label(self) -> str:
        return f"A_c {self.contact_area}, {'s fitted' if self.calibrated else 's = 1'}"


CONFIGS = (Config("mesoscale", True), Config("eq8", True), Config("mesoscale", False))


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
    """mu_bar of strip-draw tests, each run once (a test with n passes also gives passes 1..n-1)."""

    def __init__(self, workers: int | None, log=None):
        self.workers, self.log, self._done = workers, log, {}
        self.evaluations = 0

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
            for p, passes in zip(todo, run_points(todo, self.workers, draw)):
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
    """The parameters of a configuration but its scale: the paper's zeta and K (Fig. 19) and the table law."""
    return {"zeta": PAPER_ZETA, "archard_k": PAPER_K, **base, "friction_model": "table",
            "contact_area": config.contact_area}


def _drop_points(params: dict, scale: float) -> tuple[Point, Point]:
    p = {**params, "particle_area_scale": float(scale)}
    return Point(LOW_PRESSURE, CAL_PAD, 1, p), Point(CAL_PRESSURE, CAL_PAD, 1, p)


def _drops(runs: Runs, params: dict, scales: list[float]) -> list[float]:
    pairs = [_drop_points(params, s) for s in scales]
    runs.run([p for pair in pairs for p in pair])
    return [1.0 - runs.mu(hi) / runs.mu(lo) for lo, hi in pairs]


def ensemble_rel_stderr(table, contact_area: str) -> float:
    """Relative standard error of the table's A_p (and A_c with ``mesoscale``) at 25 MPa and the test's velocity,
    averaged over the debris levels simulated there: the tabulated values' standard errors (version 3), else the
    member spread over the square root of the members (version 2); 0 without either."""
    if table.version < 2:
        return 0.0
    names = ("particle_area", "contact_area") if contact_area == "mesoscale" else ("particle_area",)
    if table.version >= 3:
        sim, _ = table.interpolate_array(table.array("simulated"), CAL_PRESSURE, V0, table.beta)
        betas = table.beta[(table.beta > 0) & (sim == 1.0)]
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


def _pct(x: float) -> str:
    return f"{100 * x:.1f} %"


def _row_values(m: dict, cal: Calibration | None, grid: Grid) -> dict[str, str]:
    at = m["drop_at_mpa"]
    return {
        "scale": (f"{cal.scale:.4g} +- {cal.stderr:.2g}" if cal else "1"),
        "drop1": _pct(m["drop_1pass"]) + (" (calibrated)" if cal else ""),
        "drop3": _pct(m["drop_by_pass"][grid.passes]),
        "pads": " / ".join(_pct(m["drop_by_pad"][p]) for p in grid.pads),
        "order": f"{'yes' if m['pad_order_holds'][0] == m['pad_order_holds'][1] else 'no'} "
                 f"({m['pad_order_holds'][0]} of {m['pad_order_holds'][1]} pressures)",
        "zeta": ("falls: " if m["zeta_falls"] else "does not fall: ")
                + " / ".join(f"{m['mu_by_zeta'][z]:.4f}" for z in grid.zetas),
        "k": ("falls" if m["k_falls"] else "does not fall") + ", "
             + ("saturates" if m["k_saturates"] else "does not saturate") + ": "
             + " / ".join(f"{m['mu_by_k'][K]:.4f}" for K in grid.ks),
        "mu_low": f"{m['mu_low']:.4f}",
        "beta": f"{m['beta_max_3pass']:.3g} ({m['beta_max']:.3g})",
        "clamps": str(m["table_clamps"]),
        "_at": at,
    }


def table_contact_ratio(table, kappa: float = 2.0, rms_slope: float = 0.34, e_star: float = 55e9) -> float | None:
    """A_c of Eq. 8 (kappa P / (h'_rms E*), the strip model's defaults) over the table's particle-free A_c at 25 MPa
    and the test's velocity."""
    if table.version < 2:
        return None
    ac, _ = table.interpolate_array(table.contact_area, CAL_PRESSURE, V0, 0.0)
    return float(kappa * CAL_PRESSURE / (rms_slope * e_star) / ac) if ac > 0 else None


def markdown(results: dict, cals: dict, grid: Grid, table, table_path: Path, header: str, files: list[str]) -> str:
    """The report text: the paper-vs-model table, the calibrations, links to the figures and data."""
    configs = list(results)
    values = {c: _row_values(results[c]["metrics"], cals.get(c.contact_area) if c.calibrated else None, grid)
              for c in configs}
    at = grid.pressures[-2] if 25 not in grid.pressures else 25
    pads = " / ".join(f"{1000 * p:g}" for p in grid.pads)
    rows = [
        ("A_p scale s (+- standard error)", "-", "scale"),
        (f"mu_bar drop at {at} MPa, 1 pass, 35 mm pad", "35 %", "drop1"),
        (f"mu_bar drop at {at} MPa after {grid.passes} passes, 35 mm pad", "up to 72 %", "drop3"),
        (f"mu_bar drop at {at} MPa, 1 pass, {pads} mm pads", "grows with pad length (Fig. 19b)", "pads"),
        ("pad ordering mu(35) > mu(70) > mu(140) above 1 MPa", "yes (Figs. 2a, 19b)", "order"),
        (f"mu_bar at {grid.trend_at:g} MPa for zeta = " + " / ".join(f"{z:g}" for z in grid.zetas),
         "falls with zeta (Fig. 17b)", "zeta"),
        (f"mu_bar at {grid.trend_at:g} MPa for K = " + " / ".join(f"{K:g}" for K in grid.ks),
         "falls with K and saturates (Fig. 18b)", "k"),
        (f"mu_bar at {min(grid.pressures)} MPa, 35 mm pad", "-", "mu_low"),
        (f"largest beta after {grid.passes} passes at {at} MPa (in any test)", "-", "beta"),
        ("table lookups outside the table's axes or simulated range (clamped)", "-", "clamps"),
    ]
    lines = [header, "", "| quantity | paper | " + " | ".join(c.label for c in configs) + " |",
             "|---|---|" + "---|" * len(configs)]
    for title, paper, key in rows:
        lines.append(f"| {title} | {paper} | " + " | ".join(values[c][key] for c in configs) + " |")
    ratio = table_contact_ratio(table)
    lines += ["", "Drops are 1 - mu_bar(P) / mu_bar(1 MPa) on the same curve (same pad, same pass). Only the "
              "one-pass drop at 25 MPa is fitted (by s, per convention); every other entry is a prediction. "
              f"The table's beta axis ends at {table.beta[-1]:.4g}."
              + (f" The eq8 column is the first up to the factor A_c(Eq. 8) / A_c(table) = {ratio:.3g} at 25 MPa "
                 f"on A_p / A_c: its s is {cals['eq8'].scale / cals['mesoscale'].scale:.3g} times the first's."
                 if ratio and "eq8" in cals and "mesoscale" in cals else ""), ""]
    for conv, cal in cals.items():
        lines.append(f"- `{conv}`: s = {cal.scale:.6g}, standard error {cal.stderr:.3g} (quote of the 35 %: "
                     f"{cal.stderr_quote:.3g}, through d drop/ds = {cal.slope:.4g}; ensemble means of the table: "
                     f"{cal.stderr_ensemble:.3g}); drop reached {_pct(cal.drop)} in {cal.evaluations} strip-draw "
                     "tests.")
    from tribocosim.paths import DEFAULT_TABLE

    shipped = Path(table_path).resolve() == Path(DEFAULT_TABLE).resolve()
    table_text = "`models/friction_table.npz` (the shipped one)" if shipped else f"`{table_path}`"
    lines += ["", f"Friction table: {table_text}. Figures: " + ", ".join(f"[{f}]({f})" for f in files)
              + "; every test's mu_bar: [paper.csv](paper.csv), the numbers: [paper.json](paper.json).", ""]
    return "\n".join(lines)


def physics_markdown(extra: dict, cals: dict, grid: Grid, results: dict) -> list[str]:
    """The sections after the paper-vs-model table (paper_physics): options, budget, speed, alpha, checks."""

    lines = ["", "## Multi-pass options", "",
             "Each option calibrated on the one-pass 35 % alone (A_c from the table); the paper: 35 % after one pass, up "
             "to 72 % after three. What would tell them apart: the spacing of the 2- and 3-pass drops, the 140 mm pad's "
             "drop, and the debris weighed on the strip after each pass (beta h_p rho over the strip that was under the "
             "pad).", "",
             "| option | why these values | s | drop 1 / 2 / 3 passes at 25 MPa | 3-pass minus 2-pass | 140 mm pad, 1 pass "
             "| debris after pass 1 / 2 / 3 [g/m^2] | clamped lookups |", "|---|---|---|---|---|---|---|---|"]
    for opt in pp.OPTIONS:
        r = extra["options"].get(opt.name, {})
        if "error" in r:
            lines.append(f"| {opt.label} | {opt.why} | cannot be calibrated: {r['error']} | | | | | |")
            continue
        lines.append(f"| {opt.label} | {opt.why} | {r['scale']:.4g} | " + " / ".join(_pct(d) for d in r["drops"])
                     + f" | {100 * r['spacing_3_2']:.1f} points | {_pct(r['drop_140'])} | "
                     + " / ".join(f"{g:.3g}" for g in r["debris_g_m2"]) + f" | {r['clamps']} |")
    rows = extra["budget"]
    nominal = extra["options"]["paper"]
    cal = cals["mesoscale"]
    lines += ["", "## Uncertainty budget (the paper's model, A_c from the table)", "",
              "Each chosen input varied over the range shown (an input not varied is named in the table, and the "
              "total leaves it out), s recalibrated on the 35 %, and the change of s and of the predictions recorded "
              "(a two-sided range: half the difference of its ends). The quote of the 35 % "
              f"alone gives s a standard error of {cal.stderr_quote:.2g}.", "",
              "| input | range | s | 3-pass drop [points] | 140 mm drop [points] |", "|---|---|---|---|---|"]
    for r in rows:
        if "error" in r:
            lines.append(f"| {r['quantity']} | {r['range']} | {r['error']} | | |")
        else:
            s_cell = (f"{r['scale']:.3g}" if "scale" in r
                      else f"s = {r['scale_value']:.3g} scales another A_p: not in the total")
            lines.append(f"| {r['quantity']} | {r['range']} | {s_cell} | {100 * r['drop3']:.1f} | "
                         f"{100 * r['drop140']:.1f} |")
    tot = extra["budget_total"]
    missing = extra["budget_not_varied"]
    for m in missing:
        lines.append(f"| {m['quantity']} | {m['range']} | not varied: {m['why']} | - | - |")
    not_in = f", without the {', '.join(m['quantity'] for m in missing)}" if missing else ""
    lines += [f"| **total** (quadrature, with the quote{not_in}) | | **{tot['scale']:.3g}** | "
              f"**{100 * tot['drop3']:.1f}** | **{100 * tot['drop140']:.1f}** |", "",
              f"So s = {cal.scale:.3g} +- {tot['scale']:.2g}, the 3-pass drop {_pct(nominal['drops'][2])} +- "
              f"{100 * tot['drop3']:.1f} points (the paper: up to 72 %), the 140 mm pad's one-pass drop "
              f"{_pct(nominal['drop_140'])} +- {100 * tot['drop140']:.1f} points"
              + (f"; the {', '.join(m['quantity'] for m in missing)} is not varied, so these ranges leave "
                 f"{'it' if len(missing) == 1 else 'them'} out." if missing else ".")]
    lines.append("")
    lines += ["## Drawing speed", "",
              f"mu_bar at 25 MPa on the 35 mm pad (s = {cal.scale:.3g} +- {tot['scale']:.2g}: the range in brackets), "
              "and the drop against 1 MPa at the same speed. The paper's alpha(v) (Fig. 15) rises with the sliding "
              "speed, which would make the debris effect grow from 0.08 to 0.5 m/s; here A_p is simulated at "
              f"{' / '.join(f'{v:g}' for v in extra['simulated_velocities']) or 'no recorded'} m/s "
              "(docs/physics/table_domain.md).", "",
              "| V0 [m/s] | mu_bar, 1 pass | drop, 1 pass | mu_bar, 3 passes | drop, 3 passes |", "|---|---|---|---|---|"]
    for r in extra["speed"]:
        lines.append(f"| {r['velocity']:g} | {r['mu_1']:.4f} [{r['mu_1_band'][0]:.4f}, {r['mu_1_band'][1]:.4f}] | "
                     f"{_pct(r['drop_1'])} | {r['mu_3']:.4f} [{r['mu_3_band'][0]:.4f}, {r['mu_3_band'][1]:.4f}] | "
                     f"{_pct(r['drop_3'])} |")
    by_v = {r["velocity"]: r for r in extra["speed"]}
    if 0.08 in by_v and 0.5 in by_v and by_v[0.08]["drop_1"] > 0:
        lines += ["", f"The one-pass drop at 0.5 m/s is {by_v[0.5]['drop_1'] / by_v[0.08]['drop_1']:.3f} times that at "
                      f"0.08 m/s, the three-pass drop {by_v[0.5]['drop_3'] / by_v[0.08]['drop_3']:.3f} times."]
    lines += ["", "## alpha of both observables", ""]
    if not extra["alpha"]["load_bearing"]:
        lines.append("The friction table is format version 2: it holds A_p of every load-bearing flake only, not that "
                     "of the paper's cluster rule; a version 3 table gives alpha of both here.")
    else:
        lines += ["Eq. 23's alpha = A_p / A0 / (beta P / E*) at the table's first debris level, mean over the pressures "
                  "(+- standard error), for every load-bearing flake and for the paper's cluster rule alone:", "",
                  "| v [m/s] | every load-bearing flake | cluster rule alone |", "|---|---|---|"]
    for a, c in zip(extra["alpha"]["load_bearing"], extra["alpha"]["clusters"]):
        lines.append(f"| {a['velocity']:g} | {a['alpha']:.4g} +- {a['stderr']:.2g} | {c['alpha']:.3g} +- "
                     f"{c['stderr']:.2g} |")
    study = extra["alpha"].get("study")
    if study:
        lines += ["", f"The alpha(v) study ({study.get('source', 'docs/physics/alpha_velocity.md')}), 1-50 m/s, "
                      "mean +- standard error:", "", "| setting | observable | " + " | ".join(
                          f"{float(v):g} m/s" for v in study["velocities"]) + " | alpha(50)/alpha(1) |",
                  "|---|---|" + "---|" * (len(study["velocities"]) + 1)]
        for name, entry in study["settings"].items():
            for key, label in (("all", "every load-bearing flake"), ("clusters", "cluster rule alone")):
                cells = [f"{entry[key][str(v)][0]:.3g} +- {entry[key][str(v)][1]:.2g}" if str(v) in entry[key] else "-"
                         for v in study["velocities"]]
                ratio = entry["ratio_50_1"][key]
                lines.append(f"| {entry['label']} | {label} | " + " | ".join(cells)
                             + f" | {ratio[0]:.3g} +- {ratio[1]:.2g} |")
    lines += ["", "## The friction table's checks", ""]
    checks = extra.get("direct_slides", [])
    if checks:
        lines += ["Direct slides at points between the table's nodes (the table's own sweep settings) against the "
                  "table's interpolation: within two combined standard errors?", "",
                  "| P [MPa] | v [m/s] | beta | members | A_p/A0 direct | A_p/A0 table | difference / combined SE | "
                  "nodes read all simulated | passes |", "|---|---|---|---|---|---|---|---|---|"]
        for c in checks:
            lines.append(f"| {c['pressure'] / 1e6:g} | {c['velocity']:g} | {c['beta']:.3g} | {c['members']} | "
                         f"{c['a_p_direct']:.4g} +- {c['a_p_direct_se']:.2g} | {c['a_p_table']:.4g} +- "
                         f"{c['a_p_table_se']:.2g} | {c['difference_over_combined_se']:+.2f} | "
                         f"{'yes' if c['all_nodes_simulated'] else 'no'} | {'yes' if c['passed'] else 'NO'} |")
    else:
        lines.append("The table is not version 3 with its campaign recorded: no direct-slide check.")
    m = results[Config("mesoscale", True)]["metrics"]
    lines += ["", "Clamped lookups (outside the table's axes or its simulated range) in every test of the calibrated "
                  "column, by figure: " + ", ".join(f"{k}: {v}" for k, v in _clamps_per_figure(m).items()) + ".", "",
              "mu_bar(P) on the three pads (calibrated column):", "",
              "| P [MPa] | " + " | ".join(f"{1000 * pad:g} mm" for pad in grid.pads) + " |",
              "|---|" + "---|" * len(grid.pads)]
    for P in grid.pressures:
        lines.append(f"| {P:g} | " + " | ".join(f"{m['mu_by_pad'][pad][P]:.4f}" for pad in grid.pads) + " |")
    return lines


def _clamps_per_figure(m: dict) -> dict[str, int]:
    out = {name: 0 for name in FIGURES}
    for scene, count in m["table_clamps_by_scene"].items():
        out[scene.split(":")[0]] += count
    return out


FIGURES = {  # name: (title, series key, legend label)
    "fig19b": ("Fig. 19b: pad length", "tool_length", lambda v: f"{1000 * v:g} mm pad"),
    "fig2b": ("Fig. 2b: passes (35 mm pad)", "pass", lambda v: f"pass {v}"),
    "fig17b": ("Fig. 17b: zeta (35 mm pad, K 1e-4)", "zeta", lambda v: f"zeta {v:g}"),
    "fig18b": ("Fig. 18b: Archard K (70 mm pad, zeta 0)", "archard_k", lambda v: f"K {v:g}"),
}


def plot(results: dict, out: Path) -> list[str]:
    """One PNG per figure, one panel per configuration."""
    from tribocosim.cosim.apps.plotting import _pyplot

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
    """Run the report (module docstring) into ``out``: paper.md, paper.json, paper.csv and the figures."""
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
    cals = {}
    for config in CONFIGS:
        if config.calibrated and config.contact_area not in cals:
            if log:
                log(f"calibrating s for {config.contact_area} on the 35 % one-pass drop at 25 MPa ...")
            cals[config.contact_area] = calibrate_drop(runs, base, config, table, log=log)
    figs = {c: figure_points(base, c, cals[c.contact_area].scale if c.calibrated else 1.0, grid) for c in CONFIGS}
    if log:
        log("figures ...")
    runs.run([p for f in figs.values() for pairs in f.values() for _, p in pairs])
    results = {}
    for c in CONFIGS:
        figures = collect(runs, figs[c])
        results[c] = {"figures": figures, "metrics": metrics(figures, grid)}
    extra = physics(runs, base, table, cals["mesoscale"], quick, workers, log)
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
    files = plot(results, out)
    header = (f"# The paper's macro results ({'quick' if quick else 'full'} report)\n\nGenerated by `tribocosim report "
              f"paper{' --quick' if quick else ''}` in {wall:.0f} s ({runs.evaluations} strip-draw passes).")
    text = markdown(results, cals, grid, table, table_path, header, files)
    text += "\n".join(physics_markdown(extra, cals, grid, results)) + "\n"
    (out / "paper.md").write_text(text, encoding="utf-8")
    summary = {
        "mode": "quick" if quick else "full", "wall_time": wall, "table": str(table_path),
        "table_hash": table.metadata.get("content_hash"), "grid": dataclasses.asdict(grid),
        "paper": {"drop_1pass_25mpa": PAPER_DROP_1PASS, "drop_3pass_25mpa": PAPER_DROP_3PASS},
        "calibrations": {k: {**dataclasses.asdict(v), "stderr": v.stderr} for k, v in cals.items()},
        "configurations": {c.label: {"contact_area": c.contact_area, "calibrated": c.calibrated,
                                     "metrics": _jsonable(r["metrics"])} for c, r in results.items()},
        "options": _jsonable({k: {kk: vv for kk, vv in v.items() if kk != "calibration"}
                              for k, v in extra["options"].items()}),
        "budget": _jsonable(extra["budget"]), "budget_total": _jsonable(extra["budget_total"]),
        "budget_not_varied": _jsonable(extra["budget_not_varied"]),
        "speed": _jsonable(extra["speed"]), "alpha": _jsonable(extra["alpha"]),
        "direct_slides": _jsonable(extra["direct_slides"]),
    }
    (out / "paper.json").write_text(json.dumps(summary, indent=2), encoding="utf-8")
    return summary


def physics(runs: Runs, base: dict, table, cal: Calibration, quick: bool, workers: int | None, log=None) -> dict:
    """The multi-pass options, the uncertainty budget, the drawing-speed prediction, alpha of both observables and
    the direct-slide check (:mod:`tribocosim.cosim.reports.paper_physics`), for A_c from the table."""
    from tribocosim.paths import DEFAULT_TABLE

    params = config_params(base, Config("mesoscale", True))
    if log:
        log("multi-pass options ...")
    options = {o.name: pp.calibrated_predictions(runs, {**params, **o.parameters}, table, calibrate) for o in pp.OPTIONS}
    if log:
        log("uncertainty budget ...")
    varied = {}
    with pp.scratch_folder() as folder:
        # the domain-size variation's table is the shipped table's (the same slides on a 128 um domain)
        shipped = Path(base["table_file"]).resolve() == Path(DEFAULT_TABLE).resolve()
        domain = Path(DEFAULT_TABLE).with_name(pp.DOMAIN_TABLE)
        tables = pp.table_variants(table, Path(folder), domain if shipped and domain.is_file() else None)
        for v in pp.VARIATIONS:
            if v.table == pp.DOMAIN_VARIANT and v.table not in tables:
                continue  # no table on another domain size: named as not varied (pp.inputs_not_varied)
            if v.table is not None and v.table not in tables:
                varied[v.name] = {"error": "needs a version 3 table that records its campaign"}
                continue
            p = {**params, **({"table_file": tables[v.table]} if v.table else {}), **v.parameters}
            varied[v.name] = pp.calibrated_predictions(runs, p, table, calibrate)
    rows = pp.budget(options["paper"], varied)
    total = {key: pp.budget_total(rows, key, cal.stderr_quote if key == "scale" else 0.0)
             for key in ("scale", "drop3", "drop140")}
    if log:
        log("drawing speed ...")
    speed = pp.speed_prediction(runs, params, cal.scale, total["scale"])
    alpha = {"load_bearing": pp.table_alpha(table, "particle_area"),
             "clusters": pp.table_alpha(table, "particle_area_clusters"), "study": pp.alpha_study()}
    checks = pp.direct_slide_check(table, workers, quick, log)
    return {"options": options, "budget": rows, "budget_total": total, "budget_not_varied": pp.inputs_not_varied(table, tables),
            "speed": speed, "alpha": alpha, "direct_slides": checks,
            "simulated_velocities": pp.simulated_velocities(table)}


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.floating, np.integer, np.bool_)):
        return x.item()
    return x
