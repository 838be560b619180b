"""Which nodes of the friction table the strip-draw tests read, and the shape of mu_bar(P) they give.

The families of the paper report's strip-draw tests (cosim/studies/stripdraw_experiment.py: V0 = 0.08 m/s, 140 mm
draw, the grip ramped over 10 ms, constant normal force), default parameters (s = 1 unless --scale, zeta 0.2,
K 1e-4): 1, 2 and 3 passes on the 35 mm pad and one pass on the 70 and 140 mm pads, at every pressure from 1 to 30 MPa in 1 MPa steps.

Reads: per family and pressure, the lookups the model counts as clamped (``table_clamp_count``: outside the axes, or
a node the campaign did not simulate read with a weight above 1e-9) and which unsimulated nodes (P, v, beta) they
read. The model counts inside its native step; the nodes are found by repeating, before every step, the lookup of
every node in contact (contact weight > 0) at the step's pressure, grip speed and the node's debris
(FrictionTable.read_nodes, the native rule): that is the lookup the model makes when a step is one coupling interval
(the pad slides 0.08 mm in a 1 ms step, a twentieth of an element), so both counts are printed and should agree. The
summary lists every unsimulated node read: the nodes a campaign must simulate for these tests to read none.

Slopes (``--slopes``): mu_bar(P) of each family at P_k - h, P_k, P_k + h (h = 0.25 MPa) around every interior pressure
node P_k of the table, the slopes on either side and their ratio: a kink of the interpolation in P shows as a ratio
away from 1 that does not shrink with h. Also whether mu_bar(P) falls at every 1 MPa step.

Usage::

    python benchmarks/table_reads.py [--table models/friction_table.npz] [--workers 2] [--scale S] [--slopes]
        [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections import Counter

import numpy as np

FAMILIES = {"35 mm, pass 1": (0.035, 1), "35 mm, pass 2": (0.035, 2), "35 mm, pass 3": (0.035, 3),
            "70 mm, pass 1": (0.07, 1), "140 mm, pass 1": (0.14, 1)}
PRESSURES_MPA = tuple(range(1, 31))
SLOPE_H_MPA = 0.25


def draw_with_reads(task):
    """Every pass of one strip-draw test (as stripdraw_experiment.draw), with the model's clamp count per pass and the
    unsimulated nodes the lookups of the contact nodes read before every step."""
    table_file, pressure, pad, passes, scale = task
    from tribocosim.components.stripdraw.component import COMPONENT
    from tribocosim.components.stripdraw.model import StripDrawModel
    from tribocosim.components.stripdraw.table import read_table
    from tribocosim.cosim.studies.stripdraw_experiment import LAST, RAMP, STEP, V0

    table = read_table(table_file)
    sim = table.array("simulated") if table.version >= 3 else np.ones_like(table.mu)
    first = COMPONENT.make({"table_file": table_file, "tool_length": pad, "particle_area_scale": scale}).model
    out, beta = [], None
    for _ in range(passes):
        model = first if beta is None else StripDrawModel(first.params, first.law, beta_field=beta)
        fn = model.params.normal_force(pressure)
        p = fn / (model.params.tool_length * model.params.tool_width)
        n = int(round((model.params.draw_length / V0 + 0.5 * RAMP) / STEP))
        mus, reads, counted, before = np.empty(n), Counter(), 0, model.clamp_count
        for k in range(n):
            v = V0 * min(1.0, (k + 0.5) * STEP / RAMP)
            b = model.beta[model._nodal("contact_weight") > 0]
            flagged = b[table.interpolate_array(sim, p, v, b)[1]]  # outside an axis or reading an unsimulated node
            counted += flagged.size
            for bi in flagged:
                for node, _ in table.read_nodes(p, v, bi)[0]:
                    if sim[node] == 0.0:
                        reads[(float(table.pressure[node[0]]), float(table.velocity[node[1]]),
                               float(table.beta[node[2]]))] += 1
            mus[k] = model.step(STEP, {"normal_force": fn, "grip_velocity": v})["pull_force"] / (2.0 * fn)
        out.append({"mu_bar": float(mus[int((1.0 - LAST) * n):].mean()), "clamps": model.clamp_count - before,
                    "reconstructed": counted, "beta_max": float(model.beta.max()),
                    "reads": {f"{k[0] / 1e6:g} MPa, {k[1]:g} m/s, beta {k[2]:.3g}": c
                              for k, c in sorted(reads.items())}})
        beta = model.beta.copy()
    return out


def run(tasks, workers):
    if workers == 1:
        return [draw_with_reads(t) for t in tasks]
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn")) as pool:
        return list(pool.map(draw_with_reads, tasks))


def families(table_file: str, pressures_mpa, workers: int, scale: float) -> dict:
    """{family: {P [MPa]: pass result}} of every family at the pressures."""
    tasks = [(table_file, P * 1e6, pad, passes, scale) for P in pressures_mpa
             for pad, passes in ((0.035, 3), (0.07, 1), (0.14, 1))]
    done = dict(zip(tasks, run(tasks, workers)))
    return {name: {P: done[(table_file, P * 1e6, pad, 3 if pad == 0.035 else 1, scale)][k - 1]
                   for P in pressures_mpa} for name, (pad, k) in FAMILIES.items()}


def main(argv=None) -> int:
    from tribocosim.paths import DEFAULT_TABLE

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--table", default=str(DEFAULT_TABLE))
    ap.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    ap.add_argument("--scale", type=float, default=1.0, help="particle_area_scale s (default 1)")
    ap.add_argument("--slopes", action="store_true", help="also the slopes of mu_bar(P) on either side of the nodes")
    ap.add_argument("--json", default=None, help="write the figures to this file")
    args = ap.parse_args(argv)
    from tribocosim.components.stripdraw.table import read_table

    table = read_table(args.table)
    t0 = time.perf_counter()
    load0 = os.getloadavg()
    res = families(args.table, PRESSURES_MPA, args.workers, args.scale)
    print(f"table {args.table} (format version {table.version}, sha256 {table.metadata.get('content_hash', '')[:16]}), "
          f"particle_area_scale {args.scale:g}")
    print(f"{len(PRESSURES_MPA)} pressures x {len(FAMILIES)} families in {time.perf_counter() - t0:.0f} s "
          f"(load {load0[0]:.1f} before, {os.getloadavg()[0]:.1f} after, {args.workers} workers)\n")
    every = Counter()
    for name, rows in res.items():
        print(f"{name}: clamped lookups (model / reconstructed) and the unsimulated nodes read")
        for P, r in rows.items():
            if r["clamps"] or r["reconstructed"]:
                print(f"  {P:2d} MPa: {r['clamps']:6d} / {r['reconstructed']:6d}  beta_max {r['beta_max']:.3f}  "
                      + "; ".join(f"{k}: {c}" for k, c in r["reads"].items()))
            every.update(r["reads"])
        mus = np.array([rows[P]["mu_bar"] for P in PRESSURES_MPA])
        rises = [PRESSURES_MPA[i + 1] for i in np.flatnonzero(np.diff(mus) >= 0)]
        falls = "yes" if not rises else "no, it rises to " + ", ".join(f"{P} MPa" for P in rises)
        print(f"  none elsewhere; mu_bar(P) falls at every 1 MPa step: {falls}")
    print("\nevery unsimulated node read (lookups over all families):")
    for k, c in sorted(every.items(), key=lambda kc: kc[0]):
        print(f"  {k}: {c}")
    if not every:
        print("  none")
    out = {"table": args.table, "content_hash": table.metadata.get("content_hash"), "families": res,
           "unsimulated_nodes_read": dict(every)}
    if args.slopes:
        nodes = [float(p) / 1e6 for p in table.pressure[1:-1]]
        pts = sorted({round(P + d * SLOPE_H_MPA, 6) for P in nodes for d in (-1, 0, 1)})
        t0 = time.perf_counter()
        sl = families(args.table, pts, args.workers, args.scale)
        print(f"\nslopes of mu_bar(P) on either side of the pressure nodes (h = {SLOPE_H_MPA} MPa; "
              f"{time.perf_counter() - t0:.0f} s, load {os.getloadavg()[0]:.1f}): left / right [1/MPa], ratio")
        out["slopes"] = {}
        for name, rows in sl.items():
            cells = []
            for P in nodes:
                lo, mid, hi = (rows[round(P + d * SLOPE_H_MPA, 6)]["mu_bar"] for d in (-1, 0, 1))
                left, right = (mid - lo) / SLOPE_H_MPA, (hi - mid) / SLOPE_H_MPA
                out["slopes"].setdefault(name, {})[P] = {"left": left, "right": right, "ratio": right / left}
                cells.append(f"{P:g} MPa: {left:.3e} / {right:.3e}, {right / left:.3f}")
            print(f"  {name}: " + "; ".join(cells))
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(out, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
