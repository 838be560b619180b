"""Cost of the paper-scale campaign: the ``rolloff`` preset, 512^2 on 500 um.

A case slides 2L = 1024 pixels; each pixel is one contact solve (BEM) and one DEM phase of
n_sub = ceil(dx / (v0 dt)) substeps, so the DEM's cost per pixel grows with 1/v0 and with the
number of flakes, and the BEM's does not depend on v0. This script measures, on the preset's
first surface pair at 10 MPa, partial slides of ``--pixels`` pixels (after the set-up, whose time is
reported apart) for a few (v0, flakes) and fits per pixel

    t_bem = b (mean over the runs),   t_dem = d0 + d1 x flakes x n_sub(v0)

(least squares), then predicts every case of the preset (grid x flake levels x seeds x surfaces,
plus the particle-free ones) and the campaign: core-hours, and the wall time on a Dask cluster of N
single-threaded workers (the cases are independent; the wall time is bounded below by the longest
case). Every figure printed is a measurement or this fit of measurements; the load average is printed
with them (the machine may be shared).

    python benchmarks/paper_scale_cost.py [--pixels 12] [--workers 8 32 128]
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np

#: (v0 [m/s], flakes) of the timed partial slides
RUNS = ((50.0, 20), (50.0, 60), (10.0, 20), (10.0, 60))


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def timed(sweep, v0: float, flakes: int, pixels: int) -> dict:
    """A partial slide of the preset's first surface pair; per-pixel BEM and DEM seconds."""
    from tribocosim.surrogate.coupling import SlideSimulation
    from tribocosim.surrogate.slide_config import SlideConfig

    cfg = SlideConfig(**{**sweep.slide, **sweep.surfaces[0], "pressure": 10e6, "v0": v0,
                         "n_flakes": flakes, "flake_seed": sweep.seeds[0], "n_slide_steps": pixels})
    t0 = time.perf_counter()
    sim = SlideSimulation(cfg)
    setup = time.perf_counter() - t0
    bem0, dem0 = sim.timings["bem"], sim.timings["dem"]
    for _ in range(pixels):
        sim.step()
    return {"v0": v0, "flakes": flakes, "n_sub": sim.n_sub, "setup_s": setup,
            "bem_px": (sim.timings["bem"] - bem0) / pixels, "dem_px": (sim.timings["dem"] - dem0) / pixels,
            "other_px": sim.timings["classify"] / pixels}


def n_sub(sweep, v0: float) -> int:
    """DEM substeps per pixel at v0 (as SlideSimulation computes them)."""
    from tribocosim.surrogate import dem
    from tribocosim.surrogate.slide_config import SlideConfig

    cfg = SlideConfig(**{**sweep.slide, **sweep.surfaces[0], "v0": v0})
    shape = dem.FlakeShape(cfg.flake_diameter, cfg.flake_thickness, cfg.flake_density)
    p = dem.DemParams.build(shape, cfg.size, cfg.dx, cfg.e_star, cfg.penalty_velocity,
                            cfg.damping(shape), spacing=cfg.sample_spacing_px * cfg.dx,
                            dt_safety=cfg.dt_safety)
    return max(1, math.ceil(cfg.dx / (v0 * p.dt)))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--preset", default="rolloff")
    ap.add_argument("--pixels", type=int, default=12)
    ap.add_argument("--workers", type=int, nargs="+", default=[8, 32, 128])
    args = ap.parse_args(argv)
    from tribocosim.surrogate.campaign import expand_cases
    from tribocosim.surrogate.sweep import load_preset

    sweep = load_preset(args.preset)
    print(f"load average before: {_load()}")
    rows = [timed(sweep, v, f, args.pixels) for v, f in RUNS]
    print("| v0 [m/s] | flakes | DEM substeps/pixel | set-up [s] | BEM [s/pixel] | DEM [s/pixel] | classify [s/pixel] |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['v0']:g} | {r['flakes']} | {r['n_sub']} | {r['setup_s']:.1f} | {r['bem_px']:.3f} | "
              f"{r['dem_px']:.3f} | {r['other_px']:.3f} |")
    print(f"load average after: {_load()}")
    bem = float(np.mean([r["bem_px"] + r["other_px"] for r in rows]))
    setup = float(np.mean([r["setup_s"] for r in rows]))
    a = np.array([[1.0, r["flakes"] * r["n_sub"]] for r in rows])
    d0, d1 = np.linalg.lstsq(a, np.array([r["dem_px"] for r in rows]), rcond=None)[0]
    print(f"fit per pixel: BEM + classify {bem:.3f} s; DEM {d0:.3g} + {d1:.3g} x flakes x n_sub s")
    cases = expand_cases(sweep)
    costs = []
    for case in cases:
        c = case.config
        dem_px = d0 + d1 * c.n_flakes * n_sub(sweep, c.v0) if c.n_flakes else 0.0
        costs.append(setup + c.steps * (bem + dem_px))
    costs = np.array(costs)
    vel = np.array([case.config.v0 for case in cases])
    print(f"\n{args.preset}: {len(cases)} cases of {cases[0].config.steps} pixels")
    for v in sorted(set(vel)):
        sel = vel == v
        print(f"  v0 = {v:g} m/s: {sel.sum()} cases, {costs[sel].mean() / 3600:.2f} h per case on average, "
              f"longest {costs[sel].max() / 3600:.2f} h")
    total = costs.sum()
    print(f"campaign: {total / 3600:.0f} core-hours; longest case {costs.max() / 3600:.2f} h")
    for n in args.workers:
        wall = max(total / n, costs.max())
        print(f"  Dask, {n} single-threaded workers: >= {wall / 3600:.1f} h wall "
              f"({'bounded by the longest case' if wall == costs.max() else 'total / N'})")


if __name__ == "__main__":
    main()
