"""Benchmark: the full accuracy and stability reports, written to docs/reports/.

Runs ``tribocosim report accuracy --out docs/reports/accuracy`` and ``tribocosim report stability
--out docs/reports/stability`` (full sweeps, not ``--quick``), printing the wall time and the load
average before and after each. On 2 cores expect tens of minutes; the machine's load is recorded in
each report's Markdown and JSON because wall times on a shared machine are upper bounds.

Usage::

    python benchmarks/bench_reports.py --out DIR [--quick] [--only accuracy|stability]   # DIR = docs/reports: the
                                                                                          # tracked reports
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="the folder of the reports (docs/reports rewrites the tracked ones)")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--only", choices=("accuracy", "stability"))
    args = ap.parse_args(argv)
    from tribocosim.cosim.apps.report_cli import main as report

    for kind in ([args.only] if args.only else ["accuracy", "stability"]):
        load0 = os.getloadavg()
        t0 = time.perf_counter()
        rc = report([kind, "--out", str(Path(args.out) / kind)] + (["--quick"] if args.quick else []))
        print(f"{kind}: exit {rc}, {time.perf_counter() - t0:.0f} s, load {load0[0]:.2f} -> {os.getloadavg()[0]:.2f}",
              flush=True)
        if rc:
            return rc
    return 0


if __name__ == "__main__":
    sys.exit(main())
