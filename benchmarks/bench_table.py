"""Friction-table accuracy vs cost: interpolation error at held-out meso points.

Three nested grids in (P, v) on the quick preset's slide settings (64^2, 128 um, the same two
debris levels, 3 placements, particle-free cases):

- ``coarse``: P {1, 30} MPa x v {2, 50} m/s
- ``quick``:  P {1, 2, 5, 10, 20, 30} MPa x v {2, 10, 50} m/s (the quick preset)
- ``fine``:   P {1, 2, 5, 10, 15, 20, 30} MPa x v {2, 5, 10, 25, 50} m/s

and held-out points on none of them: P {7.5, 12.5, 25} MPa x v {4, 35} m/s at every beta level
(0 and the two debris levels). All cases run once in one campaign folder (case ids are hashes of
the configurations, so the grids share their common cases, and a rerun resumes). For each grid the
table is built from its own cases, and mu interpolated at the held-out points is compared with the
held-out ensemble mean mu = tau0 (A_c - A_p)/(P A0) (with that table's tau0, so the error is the
interpolation's, not the calibration's). The cost of a grid is the sum of its cases' wall times
(core-seconds; on W workers the wall time is about that / W) plus the fit and table time.

Usage::

    python benchmarks/bench_table.py [--out DIR] [--workers 2] [--json bench_table.json]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

GRIDS = {
    "coarse": ([1e6, 30e6], [2.0, 50.0]),
    "quick": ([1e6, 2e6, 5e6, 10e6, 20e6, 30e6], [2.0, 10.0, 50.0]),
    "fine": ([1e6, 2e6, 5e6, 10e6, 15e6, 20e6, 30e6], [2.0, 5.0, 10.0, 25.0, 50.0]),
}
HOLDOUT = ([7.5e6, 12.5e6, 25e6], [4.0, 35.0])


def sweep_text(pressures, velocities, name: str) -> str:
    """The quick preset with another (P, v) grid."""
    from tribocosim.surrogate.sweep import preset_path

    lines = preset_path("quick").read_text().splitlines()
    out = []
    for line in lines:
        if line.startswith("pressure ="):
            line = f"pressure = {list(pressures)!r}"
        elif line.startswith("velocity ="):
            line = f"velocity = {list(velocities)!r}"
        elif line.startswith("name ="):
            line = f'name = "{name}"'
        elif line.startswith("low_velocities ="):
            line = "low_velocities = [0.0, 0.08]"
        out.append(line)
    return "\n".join(out) + "\n"


def _load_note() -> str:
    try:
        return "loadavg(1,5,15 min) = " + " ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:  # pragma: no cover
        return "loadavg unavailable"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default="bench_table_campaign", help="campaign folder (shared cases)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--json", default="bench_table.json")
    args = ap.parse_args(argv)

    from tribocosim.surrogate.campaign import CampaignStore, expand_cases, run_campaign
    from tribocosim.surrogate.executors import ProcessPoolCaseExecutor
    from tribocosim.surrogate.fit import ensemble
    from tribocosim.surrogate.sweep import parse_sweep
    from tribocosim.surrogate.table_build import build_table, surface_statistics

    sweeps = {name: parse_sweep(sweep_text(p, v, name), source=name) for name, (p, v) in GRIDS.items()}
    hold = parse_sweep(sweep_text(*HOLDOUT, "holdout"), source="holdout")
    cases = {}
    for sw in [*sweeps.values(), hold]:
        for c in expand_cases(sw):
            cases.setdefault(c.case_id, c)
    load0 = _load_note()
    t0 = time.perf_counter()
    rep = run_campaign(list(cases.values()), args.out, ProcessPoolCaseExecutor(args.workers),
                       sweep=None, progress=True)
    print(rep.summary(), file=sys.stderr)
    store = CampaignStore(args.out)

    def records(sw):
        recs, missing = [], []
        for c in expand_cases(sw):
            if store.is_finished(c.case_id):
                r = store.read_case(c.case_id)
                r["labels"] = c.labels
                recs.append(r)
            else:
                missing.append({"case_id": c.case_id, "labels": c.labels, "status": "failed"})
        return recs, missing

    stats = surface_statistics(hold.slide, list(hold.surfaces))
    hold_recs, hold_missing = records(hold)
    hold_ens = ensemble(hold_recs)
    rows = []
    for name, sw in sweeps.items():
        recs, missing = records(sw)
        manifest = {"sweep": sw.to_dict(), "cases": [{"case_id": c.case_id, "labels": c.labels}
                                                      for c in expand_cases(sw)]}
        tb = time.perf_counter()
        table, fits = build_table(recs, manifest, failed=missing, surface_stats=stats)
        t_fit = time.perf_counter() - tb
        tau0 = table.metadata["calibration"]["tau0"]
        errs, stds = [], []
        for (p, v, b), pt in hold_ens.items():
            mus = np.array([tau0 * (ac - ap) / p for _, ap, ac in pt.members])
            pred = float(table.interpolate(p, v, np.array([b]), "error")[0][0])
            errs.append(pred - mus.mean())
            stds.append(mus.std(ddof=1) / np.sqrt(mus.size) if mus.size > 1 else 0.0)
        errs = np.array(errs)
        core_s = float(sum(r["wall_s"] for r in recs))
        rows.append({"grid": name, "pressures_mpa": [p / 1e6 for p in sw.pressures],
                     "velocities": list(sw.velocities), "cases": len(recs), "failed": len(missing),
                     "case_core_seconds": core_s, "est_wall_s_on_2_workers": core_s / 2,
                     "fit_and_table_s": t_fit,
                     "rms_error": float(np.sqrt(np.mean(errs**2))), "max_abs_error": float(np.max(np.abs(errs))),
                     "holdout_mean_std_error_of_mean": float(np.mean(stds)),
                     "tau0_mpa": tau0 / 1e6, "alpha_law": fits.law.__dict__,
                     "mu_at_10mpa_0p08": [float(x) for x in table.interpolate(
                         10e6, 0.08, table.beta[:3], "clamp")[0]]})
    result = {"grids": rows, "holdout_points": len(hold_ens), "holdout_missing": len(hold_missing),
              "campaign_wall_s": time.perf_counter() - t0, "load_before": load0, "load_after": _load_note(),
              "campaign_report": rep.summary()}
    print(f"{'grid':<7} {'cases':>5} {'core-s':>8} {'~wall 2w':>8} {'rms err':>9} {'max err':>9} {'noise':>9}")
    for r in rows:
        print(f"{r['grid']:<7} {r['cases']:>5} {r['case_core_seconds']:>8.0f} {r['est_wall_s_on_2_workers']:>8.0f} "
              f"{r['rms_error']:>9.2e} {r['max_abs_error']:>9.2e} {r['holdout_mean_std_error_of_mean']:>9.2e}")
    print(result["load_before"], "|", result["load_after"])
    Path(args.json).write_text(json.dumps(result, indent=2, default=float))
    return 0


if __name__ == "__main__":
    sys.exit(main())
