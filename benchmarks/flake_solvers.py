"""The overdamped flake solver against the inertial DEM on paired placements: the recorded cases of a table rerun.

``run``: the recorded cases of a friction table (default: the shipped one; its metadata lists every case with its
labels and results) are selected by velocity and debris level (``--per-level`` of each, drawn with ``--seed``) and
rerun with the configuration the table's preset gives them, changed by ``--set KEY=VALUE`` (slide configuration
keys, e.g. ``flake_solver=overdamped``, ``relax_substeps=32``, ``dem_velocity=2.0``) and ``--relax-constant
NAME=VALUE`` (the overdamped solver's module constants, for sensitivity studies). Each rerun is appended to
``--out`` as a JSON line with the recorded result beside it (``ref``): the same surfaces, placement, pressure,
velocity and debris level, so the pair differs only in what was set.

``report FILE...``: per velocity and debris level, the mean paired ratio rerun / recorded of <A_p>/A0 (every
load-bearing flake and the paper's cluster rule alone) and of <A_c>/A0, with its standard error and the member
standard deviation of the ratio, and the same pooled over levels; the markdown table of docs/physics/flake_solvers.md.

    python benchmarks/flake_solvers.py run --set flake_solver=overdamped --velocities 0.08 --per-level 6 \
        --out runs.jsonl [--workers 2]
    python benchmarks/flake_solvers.py report runs.jsonl
"""

from __future__ import annotations

import argparse
import json
import os
import random
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace

import numpy as np


def _value(text: str):
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return text


def _pairs(items) -> dict:
    out = {}
    for item in items or ():
        key, sep, value = item.partition("=")
        if not sep:
            raise SystemExit(f"{item!r}: expected KEY=VALUE")
        out[key] = _value(value)
    return out


def rerun(job: dict) -> dict:
    """One recorded case rerun with the settings of ``job``; its JSON line."""
    from tribocosim.surrogate import flake_relax
    from tribocosim.surrogate.campaign import make_case
    from tribocosim.surrogate.coupling import run_slide
    from tribocosim.surrogate.sweep import load_preset

    for name, value in job["constants"].items():
        setattr(flake_relax, name, value)
    lab = job["labels"]
    case = make_case(load_preset(job["preset"]), lab["surface"], lab["pressure"], lab["velocity"], lab["n_flakes"],
                     lab["flake_diameter"], lab["seed"])
    if case.case_id != job["case_id"]:
        raise SystemExit(f"case {job['case_id']}: the preset {job['preset']!r} makes {case.case_id} from its labels")
    cfg = replace(case.config, **job["set"])
    load0, t0, c0 = os.getloadavg()[0], time.perf_counter(), time.process_time()
    s = run_slide(cfg).summary()
    return {"case_id": job["case_id"], "labels": lab, "set": job["set"], "constants": job["constants"],
            "a_p": s["mean_particle_fraction"], "a_c": s["mean_contact_fraction"],
            "a_p_clusters": s["mean_particle_fraction_clusters"], "wall_s": time.perf_counter() - t0,
            "cpu_s": time.process_time() - c0, "load": [load0, os.getloadavg()[0]], "ref": job["ref"]}


def run(args) -> None:
    table = np.load(args.table)
    cases = json.loads(str(table["metadata"]))["cases"]
    chosen = [c for c in cases if c["labels"]["n_flakes"] and c["labels"]["velocity"] in args.velocities
              and (not args.betas or any(abs(c["labels"]["beta"] - b) < 1e-3 for b in args.betas))]
    levels = {}
    for c in chosen:
        levels.setdefault((c["labels"]["velocity"], round(c["labels"]["beta"], 4)), []).append(c)
    rng = random.Random(args.seed)
    jobs = []
    for key in sorted(levels):
        members = sorted(levels[key], key=lambda c: c["case_id"])
        rng.shuffle(members)
        for c in members[:args.per_level]:
            jobs.append({"preset": args.preset, "case_id": c["case_id"], "labels": c["labels"], "set": _pairs(args.set),
                         "constants": _pairs(args.relax_constant),
                         "ref": {k: c[k] for k in ("a_p", "a_c", "a_p_clusters", "wall_s")}})
    jobs.sort(key=lambda j: j["ref"]["wall_s"])
    print(f"{len(jobs)} recorded cases to rerun, {args.workers} at a time", flush=True)
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        for row in pool.map(rerun, jobs):
            with open(args.out, "a") as fh:
                fh.write(json.dumps(row) + "\n")
            lab, ref = row["labels"], row["ref"]
            print(f"{lab['pressure'] / 1e6:g} MPa, {lab['velocity']:g} m/s, beta {lab['beta']:.3f}, pair "
                  f"{lab['surface']}, placement {lab['seed']}: A_p {row['a_p'] / ref['a_p']:.4f}, A_c "
                  f"{row['a_c'] / ref['a_c']:.5f} of the recorded; {row['cpu_s']:.0f} s CPU (recorded "
                  f"{ref['wall_s']:.0f} s wall)", flush=True)


def _stat(x) -> tuple[float, float, float, int]:
    x = np.asarray([v for v in x if np.isfinite(v)], dtype=float)
    if x.size < 2:
        return (float(x.mean()) if x.size else float("nan"), float("nan"), float("nan"), int(x.size))
    return float(x.mean()), float(x.std(ddof=1) / np.sqrt(x.size)), float(x.std(ddof=1)), int(x.size)


def _cell(s) -> str:
    mean, se, sd, n = s
    return f"{mean:.4f} +- {se:.4f} ({sd:.4f})" if n > 1 else (f"{mean:.4f} (1)" if n else "-")


def report(args) -> None:
    rows = [json.loads(line) for f in args.files for line in open(f) if line.strip()]
    levels = {}
    for r in rows:
        levels.setdefault((r["labels"]["velocity"], round(r["labels"]["beta"], 4)), []).append(r)

    def ratios(rs, key):
        return [r[key] / r["ref"][key] if r["ref"][key] else float("nan") for r in rs]

    print("| v0 [m/s] | beta | pairs | A_p ratio | A_p ratio, cluster rule | A_c ratio |")
    print("|---|---|---|---|---|---|")
    for (v, b), rs in sorted(levels.items()):
        print(f"| {v:g} | {b:g} | {len(rs)} | {_cell(_stat(ratios(rs, 'a_p')))} | "
              f"{_cell(_stat(ratios(rs, 'a_p_clusters')))} | {_cell(_stat(ratios(rs, 'a_c')))} |")
    for v in sorted({k[0] for k in levels}):
        rs = [r for (vv, _), lst in levels.items() if vv == v for r in lst]
        print(f"| {v:g} | all | {len(rs)} | {_cell(_stat(ratios(rs, 'a_p')))} | "
              f"{_cell(_stat(ratios(rs, 'a_p_clusters')))} | {_cell(_stat(ratios(rs, 'a_c')))} |")
    print("(mean paired ratio +- its standard error (member standard deviation of the ratio); a ratio is left out "
          "where the recorded value is 0)")
    timed = [r for r in rows if r.get("cpu_s") is not None]
    ref = sum(r["ref"]["wall_s"] for r in rows)
    cpu = sum(r["cpu_s"] for r in timed)
    print(f"{len(rows)} reruns ({len(timed)} with their CPU time: {cpu / 3600:.2f} core-hours); the recorded cases "
          f"took {ref / 3600:.2f} core-hours of wall time")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="mode", required=True)
    r = sub.add_parser("run")
    r.add_argument("--table", default=None, help="a friction table with recorded cases (default: the shipped one)")
    r.add_argument("--preset", default="quick")
    r.add_argument("--velocities", type=float, nargs="+", default=[0.08])
    r.add_argument("--betas", type=float, nargs="*", default=None)
    r.add_argument("--per-level", type=int, default=6)
    r.add_argument("--seed", type=int, default=1)
    r.add_argument("--set", action="append", default=[], help="KEY=VALUE of the slide configuration")
    r.add_argument("--relax-constant", action="append", default=[], help="NAME=VALUE of flake_relax")
    r.add_argument("--workers", type=int, default=1)
    r.add_argument("--out", required=True)
    p = sub.add_parser("report")
    p.add_argument("files", nargs="+")
    args = ap.parse_args(argv)
    if args.mode == "run":
        if args.table is None:
            from tribocosim.paths import DEFAULT_TABLE

            args.table = DEFAULT_TABLE
        run(args)
    else:
        report(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
