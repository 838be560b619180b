"""Cost of the paper-scale campaign (the ``paper`` preset: 512^2 pixels on 512 um, 0.08-50 m/s), before and after
the overdamped flake solver.

A case slides 2L = 1024 pixels; each pixel is one contact solve (BEM), one classification and one flake phase.
The inertial DEM's flake phase takes n_sub = ceil(dx / (v_run dt)) substeps (v_run = v0, or ``dem_velocity`` when
v0 is below it), so its cost grows with 1/v_run and with the flakes; the overdamped solver's does not depend on v0,
and a preset may use it where the damping per pixel allows (``flake_solver = "auto"``: Lambda >= LAMBDA_MIN, here
0.08 and 0.5 m/s). This script times, on the preset's first surface pair at 10 MPa after the set-up (timed apart),
partial slides of ``--pixels`` pixels at the preset's debris levels ``--levels`` (flake counts; default its
lightest, a middle and its heaviest level run at 0.08 m/s with both solvers, and the lightest at 50 m/s with the
DEM) and predicts every case of the preset from them:

    t(case) = set-up + pixels x (t_bem + t_flakes(solver, flakes, v0)),

t_bem the mean contact-solve time per pixel over the runs; t_flakes (flake phase plus classification) interpolated
linearly in the number of flakes between the timed levels, and for the DEM scaled by n_sub(v0) / n_sub(0.08 m/s).
It prints the campaign's core-hours with the inertial DEM everywhere ("before") and with the overdamped solver where
the preset's velocities allow it ("after"), and the wall time on a Dask cluster of N single-threaded workers (the
cases are independent; the wall time is bounded below by the longest case). Every figure is a measurement or this
interpolation of measurements, printed with the load average.

    python benchmarks/paper_scale_cost.py [--pixels 4] [--levels 46 1159 2318] [--workers 8 32 128]
"""

from __future__ import annotations

import argparse
import math
import os
import time
from dataclasses import replace

import numpy as np


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def timed(sweep, v0: float, flakes: int, pixels: int, solver: str) -> dict:
    """A partial slide of the preset's first surface pair at 10 MPa; set-up and per-pixel seconds."""
    from tribocosim.surrogate.coupling import SlideSimulation
    from tribocosim.surrogate.slide_config import SlideConfig

    cfg = SlideConfig(**{**sweep.slide, **sweep.surfaces[0], "pressure": 10e6, "v0": v0, "n_flakes": flakes,
                         "flake_seed": sweep.seeds[0], "n_slide_steps": pixels, "flake_solver": solver})
    t0 = time.perf_counter()
    sim = SlideSimulation(cfg)
    setup = time.perf_counter() - t0
    base = dict(sim.timings)
    for _ in range(pixels):
        sim.step()
    per = {k: (sim.timings[k] - base[k]) / pixels for k in ("bem", "dem", "classify")}
    return {"v0": v0, "flakes": flakes, "solver": solver, "n_sub": sim.n_sub, "setup_s": setup,
            "bem_px": per["bem"], "flakes_px": per["dem"] + per["classify"]}


def n_sub(config) -> int:
    """DEM substeps per pixel of an inertial case (as SlideSimulation computes them)."""
    from tribocosim.surrogate import dem

    shape = dem.FlakeShape(config.flake_diameter, config.flake_thickness, config.flake_density)
    p = dem.DemParams.build(shape, config.size, config.dx, config.e_star, config.penalty_velocity,
                            config.run_damping(shape), spacing=config.sample_spacing_px * config.dx,
                            dt_safety=config.dt_safety)
    return max(1, math.ceil(config.dx / (config.run_velocity * p.dt)))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--preset", default="paper")
    ap.add_argument("--pixels", type=int, default=4)
    ap.add_argument("--levels", type=int, nargs="+", default=None, help="flake counts timed at 0.08 m/s")
    ap.add_argument("--workers", type=int, nargs="+", default=[8, 32, 128])
    args = ap.parse_args(argv)
    from tribocosim.surrogate.campaign import expand_cases
    from tribocosim.surrogate.sweep import load_preset

    sweep = load_preset(args.preset)
    cases = expand_cases(sweep)
    counts = sorted({c.config.n_flakes for c in cases if c.config.n_flakes})
    levels = args.levels or [counts[0], counts[len(counts) // 2], counts[-1]]
    slow = min(sweep.velocities)
    print(f"load average before: {_load()}", flush=True)
    runs = [timed(sweep, slow, f, args.pixels, s) for s in ("inertial", "overdamped") for f in levels]
    runs.append(timed(sweep, max(sweep.velocities), levels[0], args.pixels, "inertial"))
    print("| solver | v0 [m/s] | flakes | substeps/pixel | set-up [s] | BEM [s/pixel] | flakes + classify [s/pixel] |")
    print("|---|---|---|---|---|---|---|")
    for r in runs:
        print(f"| {r['solver']} | {r['v0']:g} | {r['flakes']} | {r['n_sub']} | {r['setup_s']:.1f} | "
              f"{r['bem_px']:.3f} | {r['flakes_px']:.3f} |", flush=True)
    print(f"load average after: {_load()}")
    bem = float(np.mean([r["bem_px"] for r in runs]))
    setup = float(np.mean([r["setup_s"] for r in runs]))
    curve = {s: ([r["flakes"] for r in runs if r["solver"] == s and r["v0"] == slow],
                 [r["flakes_px"] for r in runs if r["solver"] == s and r["v0"] == slow])
             for s in ("inertial", "overdamped")}
    slow_sub = next(r["n_sub"] for r in runs if r["solver"] == "inertial" and r["v0"] == slow)

    def per_pixel(config, solver):
        if not config.n_flakes:
            return bem
        f = float(np.interp(config.n_flakes, *curve[solver]))
        return bem + (f * n_sub(config) / slow_sub if solver == "inertial" else f)

    out = {}
    for label in ("before", "after"):
        costs = []
        for case in cases:
            c = case.config
            solver = "overdamped" if label == "after" and replace(c, flake_solver="auto").overdamped else "inertial"
            costs.append(setup + c.steps * per_pixel(c, solver))
        out[label] = np.array(costs)
    vel = np.array([case.config.v0 for case in cases])
    print(f"\n{args.preset}: {len(cases)} cases of {cases[0].config.steps} pixels; BEM {bem:.3f} s a pixel, "
          f"set-up {setup:.1f} s")
    for label, costs in out.items():
        total = costs.sum()
        print(f"{label} ({'inertial DEM everywhere' if label == 'before' else 'overdamped where Lambda allows'}): "
              f"{total / 3600:.0f} core-hours; longest case {costs.max() / 3600:.2f} h")
        for v in sorted(set(vel)):
            sel = vel == v
            print(f"  v0 = {v:g} m/s: {sel.sum()} cases, {costs[sel].sum() / 3600:.1f} core-hours")
        for n in args.workers:
            wall = max(total / n, costs.max())
            print(f"  Dask, {n} single-threaded workers: >= {wall / 3600:.1f} h wall "
                  f"({'bounded by the longest case' if wall == costs.max() else 'total / N'})")


if __name__ == "__main__":
    main()
