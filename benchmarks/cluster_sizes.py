"""The paper's cluster rule at the paper's flake sizes: the summary of a ``cluster_sizes`` campaign.

The campaign (surrogate/presets/cluster_sizes.toml: flakes of 25, 50 and 100 um at beta ~0.1 on a 512 um domain,
10 MPa, 0.08 m/s, 2 surface pairs x 3 placements) is built as any preset is, resumable::

    tribocosim surrogate build --preset cluster_sizes --out DIR --workers 2
    python benchmarks/cluster_sizes.py DIR [--json models/cluster_rule_sizes.json]

For each flake diameter this prints, as mean +- standard error over the members, A_c/A0, A_p/A0 of every
load-bearing flake and of the flakes the paper's cluster rule alone blocks (>= 3 overlap clusters with the tool,
Fig. 8), the cluster rule's share of every load-bearing flake's A_p, and alpha two ways for both observables:

- Eq. 23 read per slide, alpha = <A_p>/A0 / (beta P / E*);
- alpha_eff = (A_p / A_c) kappa / (h'_rms beta), the share at the slide's own contact area expressed as the alpha
  of the paper's macro model (Eq. 8's A_c = kappa P / (E* h'_rms) times A_p / A_c; kappa 2, h'_rms 0.34, the
  strip-draw component's defaults): the quantity `tribocosim report paper` compares with the alpha that model
  needs for the 35 % drop (15.3).

The question it answers: with flakes of the paper's sizes, does the cluster rule's observable
reach an alpha of order 10, as the paper's Fig. 15 reports? ``--json`` writes the summary that the paper report
prints.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from alpha_velocity import mean_se  # noqa: E402 (the script beside this one)


def eq8_constants() -> tuple[float, float]:
    """kappa and h'_rms of Eq. 8: the strip-draw component's defaults, as the paper report reads them."""
    from tribocosim.components.stripdraw.component import COMPONENT

    return float(COMPONENT.defaults["kappa"]), float(COMPONENT.defaults["rms_slope"])


def summarise(done: list[dict], e_star: float) -> dict:
    """Per flake diameter (and the particle-free slides): the members' observables, mean +- standard error."""
    groups: dict = {}
    for rec in done:
        lab, s = rec["labels"], rec["summary"]
        key = "none" if not lab.get("n_flakes") else f"{lab['flake_diameter']:.6g}"
        groups.setdefault(key, []).append((lab, s, rec.get("wall_s", s.get("time_wall_s", math.nan))))
    kappa, rms_slope = eq8_constants()
    out = {}
    for key, members in sorted(groups.items(), key=lambda kv: -1.0 if kv[0] == "none" else float(kv[0])):
        lab0 = members[0][0]
        row = {"members": len(members), "n_flakes": int(lab0.get("n_flakes") or 0),
               "flake_diameter": lab0.get("flake_diameter") if key != "none" else None,
               "beta": float(lab0.get("beta") or 0.0), "pressure": float(lab0["pressure"]),
               "velocity": float(lab0["velocity"]), "wall_s": float(sum(m[2] for m in members))}
        a_c = [m[1]["mean_contact_fraction"] for m in members]
        row["contact_fraction"] = mean_se(a_c)[:2]
        if key != "none":
            beta, p = row["beta"], row["pressure"]
            a_p = {}
            for name, field in (("load_bearing", "mean_particle_fraction"),
                                ("clusters", "mean_particle_fraction_clusters")):
                a_p[name] = np.array([m[1][field] for m in members])
                share = a_p[name] / np.array(a_c)
                row[name] = {"particle_fraction": mean_se(a_p[name])[:2],
                             "alpha": mean_se(a_p[name] / (beta * p / e_star))[:2],
                             "alpha_eff": mean_se(share * kappa / (rms_slope * beta))[:2]}
            every = a_p["load_bearing"]
            row["cluster_share"] = mean_se(np.where(every > 0, a_p["clusters"] / np.where(every > 0, every, 1.0),
                                                    0.0))[:2]
        out[key] = row
    return out


def _cell(pair, fmt=".3g") -> str:
    m, se = pair
    return "-" if not math.isfinite(m) else f"{m:{fmt}} +- {se:.2g}"


def show(summary: dict) -> None:
    print("| d_p [um] | flakes | beta | members | A_c/A0 | A_p/A0 every load-bearing | A_p/A0 cluster rule | "
          "cluster rule / every | alpha (Eq. 23) every / cluster rule | alpha_eff every / cluster rule |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for key, r in summary.items():
        if key == "none":
            print(f"| no flakes | 0 | 0 | {r['members']} | {_cell(r['contact_fraction'], '.4g')} | - | - | - | - | - |")
            continue
        lb, cl = r["load_bearing"], r["clusters"]
        print(f"| {1e6 * r['flake_diameter']:g} | {r['n_flakes']} | {r['beta']:.3g} | {r['members']} | "
              f"{_cell(r['contact_fraction'], '.4g')} | {_cell(lb['particle_fraction'])} | "
              f"{_cell(cl['particle_fraction'])} | {_cell(r['cluster_share'])} | {_cell(lb['alpha'])} / "
              f"{_cell(cl['alpha'])} | {_cell(lb['alpha_eff'])} / {_cell(cl['alpha_eff'])} |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("campaign", help="folder of a cluster_sizes campaign (tribocosim surrogate build --out)")
    ap.add_argument("--json", default=None, help="write the summary here (e.g. models/cluster_rule_sizes.json)")
    args = ap.parse_args(argv)
    from tribocosim.surrogate.campaign import case_cpu_seconds, load_records

    manifest, done, failed = load_records(args.campaign)
    if not done:
        sys.exit(f"no finished case in {args.campaign}")
    e_star = float(done[0]["config"]["e_star"])
    summary = summarise(done, e_star)
    show(summary)
    print(f"\n{len(done)} of {len(manifest['cases'])} cases finished ({len(failed)} not: "
          f"{', '.join(sorted({f['status'] for f in failed})) or 'none'}); "
          f"{case_cpu_seconds(done) / 3600:.2f} core-hours (sum of the finished cases' wall times)")
    if args.json:
        doc = {"source": "benchmarks/cluster_sizes.py on a campaign of surrogate/presets/cluster_sizes.toml",
               "preset": manifest.get("sweep", {}).get("name", "cluster_sizes"),
               "code": sorted({r.get("source_digest", "unknown") for r in done}),
               "cases": len(manifest["cases"]), "finished": len(done),
               "core_hours": case_cpu_seconds(done) / 3600, "e_star": e_star,
               **dict(zip(("kappa", "rms_slope"), eq8_constants())), "sizes": summary}
        Path(args.json).write_text(json.dumps(doc, indent=1) + "\n")
        print(f"written {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
