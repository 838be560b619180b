"""``tribocosim report accuracy|stability|paper [--quick] --out DIR [--only FAMILY ...]``.

``accuracy`` writes work-precision data (error against wall time and doStep calls) of the master on
the two-mass oscillator and the demo scene, of the strip-draw bar integrators, of the friction table
and of the BEM solver; ``stability`` writes the matrix of stiff and extreme cases x schemes with the
largest stable steps. Each writes ``accuracy.md`` / ``stability.md``, one CSV and one PNG per family,
and ``<report>.json`` (settings, timings, load, the families that were not available and why)
into ``--out``. ``--quick`` runs small sweeps (CI: under 5 minutes on 2 cores); without it the
full report runs (a benchmark: tens of minutes). ``paper`` writes ``paper.md`` with the paper's macro
results against the model's for both contact-area conventions (:mod:`tribocosim.cosim.reports.paper`;
``--table`` another friction table, ``--workers`` processes).
"""

from __future__ import annotations

import argparse
import datetime as _dt
import json
import sys
import tempfile
import time
from pathlib import Path


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="tribocosim report", description=__doc__.splitlines()[0])
    ap.add_argument("kind", choices=("accuracy", "stability", "paper"), help="which report")
    ap.add_argument("--quick", action="store_true", help="small sweeps (CI mode, < 5 min on 2 cores)")
    ap.add_argument("--out", required=True, help="output folder (created)")
    ap.add_argument("--only", nargs="+", metavar="FAMILY", help="run only these families")
    ap.add_argument("--surrogate-results", help="JSON of benchmarks/bench_table.py (default: searched in docs/reports, "
                                                "benchmarks, the working directory)")
    ap.add_argument("--table", help="paper: the friction table (default: the shipped one)")
    ap.add_argument("--workers", type=int, help="paper: worker processes (default: one per core)")
    ap.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    return ap


def _paper(args) -> int:
    from tribocosim.errors import TribocosimError
    from tribocosim.cosim.reports.paper import run_report

    def log(msg):
        if not args.quiet:
            print(msg, file=sys.stderr, flush=True)

    try:
        summary = run_report(Path(args.out), args.table, args.quick, args.workers, log)
    except TribocosimError as exc:
        print(f"tribocosim report paper: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {Path(args.out) / 'paper.md'}")
    failed = [c for c in summary.get("direct_slides", []) if not c["passed"]]
    for c in failed:
        print(f"tribocosim report paper: the table fails its direct-slide check at P = {c['pressure'] / 1e6:g} MPa, "
              f"v = {c['velocity']:g} m/s, beta = {c['beta']:.3g}: direct {c['a_p_direct']:.4g}, table "
              f"{c['a_p_table']:.4g}, {c['difference_over_combined_se']:+.2f} combined standard errors; mu "
              f"{c.get('mu_direct', float('nan')):.4g} against {c.get('mu_table', float('nan')):.4g}, "
              f"{c.get('mu_difference_over_combined_se', float('nan')):+.2f}"
              + ("" if c["all_nodes_simulated"] else "; the interpolation reads nodes the campaign did not simulate"),
              file=sys.stderr)
    return 1 if failed else 0


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    if args.kind == "paper":
        return _paper(args)
    from tribocosim.cosim.reports import markdown
    from tribocosim.cosim.reports.common import Settings, load_average

    if args.kind == "accuracy":
        from tribocosim.cosim.reports.accuracy import FAMILIES
    else:
        from tribocosim.cosim.reports.stability_report import CRITERION, FAMILIES
    names = args.only or list(FAMILIES)
    unknown = [n for n in names if n not in FAMILIES]
    if unknown:
        print(f"tribocosim report: unknown family {', '.join(unknown)}; known: {', '.join(FAMILIES)}", file=sys.stderr)
        return 2
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    def log(msg):
        if not args.quiet:
            print(msg, file=sys.stderr, flush=True)

    started = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
    load0 = load_average()
    t0 = time.perf_counter()
    fams, files = [], {}
    with tempfile.TemporaryDirectory(prefix="tribocosim-report-") as work:
        settings = Settings(args.quick, Path(work), log)
        for n in names:
            log(f"{args.kind}: {n} ...")
            fn = FAMILIES[n]
            fam = fn(settings, args.surrogate_results) if n == "surrogate" and args.kind == "accuracy" else fn(settings)
            fams.append(fam)
            written = []
            if fam.rows:
                written.append(markdown.write_csv(fam, out / f"{fam.name}.csv"))
                plot = markdown.plot_accuracy if args.kind == "accuracy" else markdown.plot_stability
                png = plot(fam, out / f"{fam.name}.png")
                if png:
                    written.append(png)
            files[fam.name] = written
            log(f"{args.kind}: {n}: " + (f"{len(fam.rows)} rows in {fam.wall_time:.1f} s" if fam.available else fam.note))
    total = time.perf_counter() - t0
    mode = "quick" if args.quick else "full"
    header = (f"# {'Accuracy: error against run time' if args.kind == 'accuracy' else 'Numerical stability'} "
              f"({mode} report)\n\nGenerated by `tribocosim report {args.kind}{' --quick' if args.quick else ''}` on "
              f"{started} in {total:.0f} s; load average (1, 5, 15 min) at the start {load0}, at the end "
              f"{load_average()}, on {_cpus()} cores. Wall times are from a shared machine: upper bounds, compare them "
              f"within one report.")
    if args.kind == "accuracy":
        text = markdown.accuracy_markdown(fams, files, header)
    else:
        text = markdown.stability_markdown(fams, files, header, CRITERION.describe())
    (out / f"{args.kind}.md").write_text(text, encoding="utf-8")
    meta = {"kind": args.kind, "mode": mode, "started": started, "wall_time": total, "load_start": load0,
            "load_end": load_average(),
            "families": {f.name: {"available": f.available, "note": f.note, "rows": len(f.rows),
                                  "wall_time": f.wall_time, "load": f.load} for f in fams}}
    (out / f"{args.kind}.json").write_text(json.dumps(meta, indent=2), encoding="utf-8")
    log(f"wrote {out / (args.kind + '.md')} ({total:.0f} s)")
    return 0


def _cpus() -> int:
    import os

    return os.cpu_count() or 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
