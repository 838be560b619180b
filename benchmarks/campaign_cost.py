"""Predicted cost of a full campaign of a preset (default ``quick``, the shipped table's) from timed cases of every
debris level.

For each debris level of the preset (and the particle-free cases) one whole case is timed at the lowest and one at
the highest pressure the level runs at (the preset's first surface pair and placement, its slowest velocity), with
the flake solver ``--solver`` (default ``auto``: the overdamped solver where the damping per pixel allows it).
Every case of the preset is then predicted by interpolating the level's two timings linearly in the pressure (a
case's cost does not depend on the placement seed or the surface pair beyond their scatter, nor, with the
overdamped solver or the DEM's ``dem_velocity``, on 0.08 or 0.5 m/s), and the sum is printed in core-hours per
level and in all, beside the recorded cost of the shipped table's cases (the wall time of each, in the table's
metadata) when the preset is ``quick``. Every figure is a measurement or this interpolation of measurements, with the
load average.

    python benchmarks/campaign_cost.py [--preset quick] [--solver auto] [--workers 2]
"""

from __future__ import annotations

import argparse
import json
import os
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace

import numpy as np


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def timed(job: dict) -> dict:
    """One whole case, set-up included; wall and CPU seconds."""
    from tribocosim.surrogate.campaign import make_case
    from tribocosim.surrogate.coupling import run_slide
    from tribocosim.surrogate.sweep import load_preset

    sweep = load_preset(job["preset"])
    cfg = make_case(sweep, 0, job["pressure"], job["velocity"], job["count"], job["diameter"],
                    job["seed"]).config
    if job["solver"]:
        cfg = replace(cfg, flake_solver=job["solver"])
    load0, t0, c0 = _load(), time.perf_counter(), time.process_time()
    run_slide(cfg)
    return {**job, "wall_s": time.perf_counter() - t0, "cpu_s": time.process_time() - c0,
            "overdamped": bool(cfg.overdamped), "load_before": load0, "load_after": _load()}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--preset", default="quick")
    ap.add_argument("--solver", default="auto", help="inertial, overdamped or auto")
    ap.add_argument("--workers", type=int, default=1, help="timed cases run side by side (the load is printed)")
    ap.add_argument("--out", default="campaign_cost.json")
    args = ap.parse_args(argv)
    from tribocosim.surrogate.campaign import expand_cases
    from tribocosim.surrogate.sweep import load_preset

    sweep = load_preset(args.preset)
    cases = expand_cases(sweep)
    slow = min(sweep.velocities)
    levels = sorted({(c.config.n_flakes, c.config.flake_diameter if c.config.n_flakes else None) for c in cases})
    jobs = []
    for count, diameter in levels:
        ps = sorted({c.labels["pressure"] for c in cases if c.config.n_flakes == count})
        for p in sorted({ps[0], ps[-1]}):
            jobs.append({"preset": args.preset, "pressure": p, "velocity": slow, "count": count,
                         "diameter": diameter if count else None, "seed": sweep.seeds[0] if count else None,
                         "solver": args.solver})
    print(f"{len(jobs)} timed cases, {args.workers} at a time (load before: {_load()})", flush=True)
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        rows = []
        for r in pool.map(timed, jobs):
            rows.append(r)
            print(f"  {r['count']} flakes at {r['pressure'] / 1e6:g} MPa ({'overdamped' if r['overdamped'] else 'inertial'}): "
                  f"{r['wall_s']:.1f} s wall, {r['cpu_s']:.1f} s CPU (load {r['load_before']} -> {r['load_after']})",
                  flush=True)
    per_level = {}
    for case in cases:
        c = case.config
        mine = sorted((r["pressure"], r["cpu_s"]) for r in rows if r["count"] == c.n_flakes)
        cost = float(np.interp(case.labels["pressure"], [p for p, _ in mine], [t for _, t in mine]))
        key = round(case.labels["beta"], 4)
        n, s = per_level.get(key, (0, 0.0))
        per_level[key] = (n + 1, s + cost)
    total = sum(s for _, s in per_level.values())
    print(f"\n{args.preset} ({args.solver}): {len(cases)} cases, predicted from CPU seconds")
    print("| beta | cases | predicted core-hours |")
    print("|---|---|---|")
    for b, (n, s) in sorted(per_level.items()):
        print(f"| {b:g} | {n} | {s / 3600:.2f} |")
    print(f"| all | {len(cases)} | {total / 3600:.2f} |")
    recorded = None
    if args.preset == "quick":
        from tribocosim.paths import DEFAULT_TABLE

        meta = json.loads(str(np.load(DEFAULT_TABLE)["metadata"]))
        recorded = sum(c["wall_s"] for c in meta.get("cases", []))
        print(f"the shipped table's recorded cases: {len(meta.get('cases', []))} slides, {recorded / 3600:.1f} "
              f"core-hours (their wall times on the campaign's workers)")
    print(f"load average after: {_load()}")
    with open(args.out, "w") as fh:
        json.dump({"rows": rows, "per_level": per_level, "predicted_core_hours": total / 3600,
                   "recorded_core_hours": None if recorded is None else recorded / 3600}, fh, indent=1)


if __name__ == "__main__":
    main()
