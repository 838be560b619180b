"""Benchmarks of the BEM-DEM sliding loop.

``perf``: one full 2L slide for each grid size (default 256 and 512) with 20 flakes of 12 um at
v0 = 50 m/s and p = 10 MPa, split into DEM, BEM, classification and the rest (set-up: surfaces, first
solve, placement), with the DEM's cost per pixel and per substep and the load average before and
after. It only reads ``SlideResult.timings`` and ``info``, so the same script times an older checkout:
``PYTHONPATH=<a package tree of that checkout> python benchmarks/bench_slide.py perf`` (set
``TRIBOCOSIM_FFTW_WISDOM`` to one file for both runs so that they use the same FFT plans, and so the same
numbers).

``deposit``: the shipped table's slides (surrogate/presets/quick.toml: 256^2 pixels of 1 um, roll-off
surfaces, flakes deposited in the 1 MPa gap, the DEM at 10 m/s for the test's 0.08 m/s) at 30 MPa for the
debris levels ``--betas`` (default 0.3, 0.5 and 1.0), each with the preset's numerics (``dt_safety`` 0.5,
flake-flake points 2 px apart) and with the finer ones they replace (``dt_safety`` 0.25, 1 px), over
``--steps`` pixels (default 30): the DEM and BEM cost per pixel of each, before and after.

``physics``: reduced-size checks of Sec. 6 on a 256^2 grid with 20 flakes:
<A_p>/A0 vs flake diameter (6, 12, 24 um at 10 MPa) and vs pressure (2..30 MPa at 12 um); the
pressure series is fitted with <A_p>/A0 = alpha beta p / E* (Eq. 23, a line through the origin)
and R^2 is reported. Several placements (``--seeds``) are averaged as in the paper.

Usage::

    python benchmarks/bench_slide.py perf [--sizes 256 512] [--steps K]
    python benchmarks/bench_slide.py deposit [--betas 0.3 0.5 1.0] [--steps 30]
    python benchmarks/bench_slide.py physics [--seeds 3] [--jobs 2] [--steps K]

``--steps K`` slides K pixels instead of 2n (a quicker, partial run). Results are printed and
written as JSON next to ``--out`` (default ``bench_slide_<mode>.json``).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np


def run_case(kw: dict) -> dict:
    """One slide for the SlideConfig keywords ``kw``; returns its summary plus the keywords."""
    from tribocosim.surrogate.coupling import run_slide
    from tribocosim.surrogate.slide_config import SlideConfig

    cfg = SlideConfig(**kw)
    t0 = time.perf_counter()
    try:
        res = run_slide(cfg)
    except Exception as exc:  # report the failure of one case, keep the others
        return {**kw, "error": f"{type(exc).__name__}: {exc}"}
    out = {**kw, **res.summary(), "wall_s": time.perf_counter() - t0,
           "bem_iterations_mean": float(np.mean(res.bem_iterations))}
    return out


def _load_note() -> str:
    try:
        return "loadavg(1,5,15 min) = " + " ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:  # pragma: no cover
        return "loadavg unavailable"


def time_split(r: dict) -> dict:
    """DEM / BEM / classification / rest of one ``run_case`` row [s], and the DEM's cost per pixel and
    per substep."""
    wall = r["wall_s"]  # set-up included
    dem, bem, cls = r["time_dem_s"], r["time_bem_s"], r["time_classify_s"]
    sub = r.get("dem_steps_per_pixel", 0)
    return {"wall_s": wall, "dem_s": dem, "bem_s": bem, "classify_s": cls,
            "other_s": wall - dem - bem - cls, "dem_ms_per_pixel": 1e3 * dem / r["steps"],
            "dem_us_per_substep": 1e6 * dem / (r["steps"] * sub) if sub else float("nan")}


def split_line(n: int, t: dict) -> str:
    parts = " + ".join(f"{name} {t[key]:.1f} s ({t[key] / t['wall_s']:.0%})" for name, key in (
        ("DEM", "dem_s"), ("BEM", "bem_s"), ("classify", "classify_s"), ("other", "other_s")))
    return (f"split n={n}: wall {t['wall_s']:.1f} s = {parts}; DEM {t['dem_ms_per_pixel']:.1f} ms "
            f"per pixel, {t['dem_us_per_substep']:.2f} us per substep")


def perf(args) -> dict:
    from tribocosim.surrogate import coupling

    print(f"code under test: {os.path.dirname(coupling.__file__)}", flush=True)
    rows = []
    for n in args.sizes:
        kw = dict(n=n, n_flakes=20, flake_diameter=12e-6, v0=50.0, pressure=10e6)
        if args.steps:
            kw["n_slide_steps"] = args.steps
        load0 = _load_note()
        print(f"perf n={n} ... ({load0})", flush=True)
        r = run_case(kw)
        r["load_before"], r["load_after"] = load0, _load_note()
        print(json.dumps(r, indent=1), flush=True)
        if "error" not in r:
            r["split"] = time_split(r)
            print(split_line(n, r["split"]), f"(before: {load0}; after: {r['load_after']})",
                  flush=True)
        rows.append(r)
    return {"mode": "perf", "code": os.path.dirname(coupling.__file__), "rows": rows,
            "load": _load_note()}


def deposit(args) -> dict:
    import math

    from tribocosim.surrogate.sweep import load_preset

    sweep = load_preset("quick")
    size = sweep.base_config().size
    numerics = {"preset (dt_safety 0.5, pairs 2 px)": {},
                "finer (dt_safety 0.25, pairs 1 px)": {"dt_safety": 0.25, "pair_spacing_px": None}}
    rows = []
    for beta in args.betas:
        count = round(beta * size**2 / (math.pi * 36e-12))
        for label, over in numerics.items():
            kw = {**sweep.slide, **sweep.surfaces[0], "pressure": 30e6, "v0": 0.08, "n_flakes": count,
                  "flake_seed": 11, "n_slide_steps": args.steps or 30, **over}
            load0 = _load_note()
            r = run_case(kw)
            r.update(load_before=load0, load_after=_load_note(), numerics=label)
            if "error" not in r:
                r["split"] = time_split(r)
                t = r["split"]
                print(f"beta {beta:g} ({count} flakes), {label}: DEM {t['dem_ms_per_pixel'] / 1e3:.3f} s/pixel, "
                      f"BEM {t['bem_s'] / r['steps']:.3f} s/pixel, <A_p>/A0 {r['mean_particle_fraction']:.4g} "
                      f"over {r['steps']} pixels ({load0}; after: {r['load_after']})", flush=True)
            else:
                print(f"beta {beta:g}, {label}: {r['error']}", flush=True)
            rows.append(r)
    return {"mode": "deposit", "rows": rows, "load": _load_note()}


def fit_alpha(rows, e_star: float) -> dict:
    """Least-squares alpha of <A_p>/A0 = alpha beta p/E* (through the origin) and its R^2."""
    x = np.array([r["beta"] * r["pressure"] / e_star for r in rows])
    y = np.array([r["mean_particle_fraction"] for r in rows])
    alpha = float(x @ y / (x @ x))
    ss_res = float(np.sum((y - alpha * x) ** 2))
    ss_tot = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - ss_res / ss_tot if ss_tot > 0 else float("nan")
    return {"alpha": alpha, "r2": r2, "x": x.tolist(), "y": y.tolist()}


def physics(args) -> dict:
    base = dict(n=256, n_flakes=20, v0=50.0)
    if args.steps:
        base["n_slide_steps"] = args.steps
    cases = []
    for seed in range(1, args.seeds + 1):
        for d in (6e-6, 12e-6, 24e-6):
            cases.append({**base, "flake_diameter": d, "pressure": 10e6, "flake_seed": seed})
        for p in (2e6, 5e6, 20e6, 30e6):
            cases.append({**base, "flake_diameter": 12e-6, "pressure": p, "flake_seed": seed})
    print(f"physics: {len(cases)} slides, {args.jobs} job(s) ({_load_note()})", flush=True)
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        rows = []
        for r in pool.map(run_case, cases):
            rows.append(r)
            print(json.dumps({k: r.get(k) for k in ("flake_diameter", "pressure", "flake_seed",
                                                      "mean_particle_fraction",
                                                      "mean_contact_fraction",
                                                      "fraction_steps_blocked", "wall_s",
                                                      "error")}), flush=True)
    ok = [r for r in rows if "error" not in r]

    def mean_over_seeds(sel):
        group = {}
        for r in sel:
            group.setdefault((r["flake_diameter"], r["pressure"]), []).append(r)
        return [{**g[0], "mean_particle_fraction": float(np.mean(
            [x["mean_particle_fraction"] for x in g])), "n_seeds": len(g)}
            for g in group.values()]

    by_d = sorted(mean_over_seeds([r for r in ok if r["pressure"] == 10e6]),
                  key=lambda r: r["flake_diameter"])
    by_p = sorted(mean_over_seeds([r for r in ok if r["flake_diameter"] == 12e-6]),
                  key=lambda r: r["pressure"])
    fit = fit_alpha(by_p, 55e9) if len(by_p) >= 2 else {}
    report = {
        "mode": "physics", "load": _load_note(), "rows": rows,
        "diameter_series": [(r["flake_diameter"], r["mean_particle_fraction"]) for r in by_d],
        "pressure_series": [(r["pressure"], r["mean_particle_fraction"]) for r in by_p],
        "fit_eq23": fit,
    }
    print("<A_p>/A0 vs d_p (10 MPa):", report["diameter_series"])
    print("<A_p>/A0 vs p (12 um):", report["pressure_series"])
    print("fit <A_p>/A0 = alpha beta p/E*:", {k: fit.get(k) for k in ("alpha", "r2")})
    return report


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mode", choices=("perf", "physics", "deposit"))
    ap.add_argument("--betas", type=float, nargs="+", default=[0.3, 0.5, 1.0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[256, 512])
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--steps", type=int, default=0, help="pixels to slide (0: the full 2n)")
    ap.add_argument("--out", default=None)
    args = ap.parse_args(argv)
    report = {"perf": perf, "physics": physics, "deposit": deposit}[args.mode](args)
    out = args.out or f"bench_slide_{args.mode}.json"
    with open(out, "w") as fh:
        json.dump(report, fh, indent=1)
    print(f"written {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
