"""Is the friction table's extrapolation in beta within the mesoscale ensemble's noise?

The quick preset simulates debris levels up to beta = 0.048 (7 flakes of 12 um on the 128 um domain);
above that the table's nodes are extrapolated with A_p linear in beta and A_c held (surrogate/
table_build.py, ``axes.beta.measured_max``), while the strip draws reach beta of 0.2-0.6 on the long
pads. This runs the quick preset's slide at a level in that range (44 flakes: beta = 0.304) for the
same three placements, and compares the ensemble mean of A_p/A0, A_c/A0 and mu = mu0 (1 - A_p/A_c) with
the table interpolated at the same (P, v, beta). Verdict per quantity: |table - mean| against the
standard error of the mean (member std / sqrt(3)) and against the member std.

A case at 30 MPa takes about 14 minutes on one core (4.4 million DEM steps); the campaign folder
keeps finished cases, so a rerun resumes.

Usage::

    python benchmarks/bench_beta_extrapolation.py [--out DIR] [--workers 2] [--pressures 30e6 ...]
        [--velocity 2.0] [--flakes 44] [--table models/friction_table.npz] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np


def sweep_text(pressures, velocity: float, flakes: int) -> str:
    """The quick preset at (pressures, velocity) with one debris level of ``flakes`` flakes of 12 um."""
    from tribocosim.surrogate.sweep import preset_path

    out, skip = [], False
    for line in preset_path("quick").read_text().splitlines():
        if line.startswith("[[flakes]]"):
            if not skip:
                out += ["[[flakes]]", f"count = {flakes}", "diameter = 12e-6", ""]
            skip = True
            continue
        if skip and (line.startswith("count") or line.startswith("diameter") or not line.strip()):
            continue
        skip = skip and not line.startswith("[")
        if line.startswith("pressure ="):
            line = f"pressure = {[float(p) for p in pressures]!r}"
        elif line.startswith("velocity ="):
            line = f"velocity = [{float(velocity)!r}]"
        elif line.startswith("particle_free ="):
            line = "particle_free = false"
        elif line.startswith("name ="):
            line = 'name = "beta_extrapolation"'
        out.append(line)
    return "\n".join(out) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default="bench_beta_extrapolation_campaign")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--pressures", type=float, nargs="+", default=[30e6])
    ap.add_argument("--velocity", type=float, default=2.0)
    ap.add_argument("--flakes", type=int, default=44)
    ap.add_argument("--table", help="friction table (default: the shipped one)")
    ap.add_argument("--json", default="bench_beta_extrapolation.json")
    args = ap.parse_args(argv)

    from tribocosim.paths import DEFAULT_TABLE
    from tribocosim.components.stripdraw.table import read_table
    from tribocosim.surrogate.campaign import CampaignStore, expand_cases, run_campaign
    from tribocosim.surrogate.executors import ProcessPoolCaseExecutor
    from tribocosim.surrogate.sweep import parse_sweep

    table = read_table(args.table or DEFAULT_TABLE)
    if table.version != 2:
        print("the table must be format version 2 (with the areas)", file=sys.stderr)
        return 2
    mu0 = float(table.metadata.get("calibration", {}).get("mu0", 0.15))
    sweep = parse_sweep(sweep_text(args.pressures, args.velocity, args.flakes), source="beta_extrapolation")
    cases = expand_cases(sweep)
    t0 = time.perf_counter()
    rep = run_campaign(cases, args.out, ProcessPoolCaseExecutor(args.workers), sweep=None, progress=True)
    print(rep.summary(), file=sys.stderr)
    store = CampaignStore(args.out)
    groups: dict[tuple, list] = {}
    for c in cases:
        if store.is_finished(c.case_id):
            s = store.read_case(c.case_id)["summary"]
            key = (c.labels["pressure"], c.labels["velocity"], c.labels["beta"])
            groups.setdefault(key, []).append((s["mean_particle_fraction"], s["mean_contact_fraction"]))
    rows = []
    for (p, v, b), members in sorted(groups.items()):
        ap_, ac_ = np.array(members).T
        mu = mu0 * (1.0 - ap_ / ac_)
        n = len(members)
        tab = {name: float(table.interpolate_array(getattr(table, name), p, v, np.array([b]))[0][0])
               for name in ("particle_area", "contact_area")}
        tab_mu = mu0 * (1.0 - tab["particle_area"] / tab["contact_area"])
        row = {"pressure": p, "velocity": v, "beta": b, "members": n,
               "measured_max": table.metadata.get("axes", {}).get("beta", {}).get("measured_max")}
        for name, values, pred in (("particle_area", ap_, tab["particle_area"]),
                                   ("contact_area", ac_, tab["contact_area"]), ("mu", mu, tab_mu)):
            std = float(values.std(ddof=1)) if n > 1 else math.nan
            row[name] = {"mean": float(values.mean()), "member_std": std, "stderr": std / math.sqrt(n),
                         "table": pred, "difference": pred - float(values.mean()),
                         "in_stderr_units": (pred - float(values.mean())) / (std / math.sqrt(n))}
        rows.append(row)
    result = {"rows": rows, "wall_s": time.perf_counter() - t0, "table": str(args.table or DEFAULT_TABLE),
              "campaign_report": rep.summary()}
    Path(args.json).write_text(json.dumps(result, indent=2), encoding="utf-8")
    print(f"{'P [MPa]':>8} {'v':>5} {'beta':>6} {'quantity':>14} {'mean':>10} {'+- SE':>9} {'table':>10} "
          f"{'diff/SE':>8} {'diff/std':>8}")
    for r in rows:
        for name in ("particle_area", "contact_area", "mu"):
            q = r[name]
            print(f"{r['pressure'] / 1e6:>8g} {r['velocity']:>5g} {r['beta']:>6.3f} {name:>14} {q['mean']:>10.5f} "
                  f"{q['stderr']:>9.2e} {q['table']:>10.5f} {q['in_stderr_units']:>8.2f} "
                  f"{q['difference'] / q['member_std']:>8.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
