"""Wall time of exporting the shipped friction table (the target: under 2 s).

Each case runs ``tribocosim export`` as a user does, in a new process (interpreter start, imports, the native core
loaded from the cache, the law sampled, checked and written), ``--repeat`` times; the script prints the median and
the largest wall time, the grid and the accuracy the export states. Run it on a quiet machine::

    python benchmarks/bench_export.py [--repeat 5] [--json bench_export.json]

The cases: LS-DYNA at one beta with the band (three files), Abaqus with beta as field variable 1 (the largest grid),
the neutral table at one beta, LS-DYNA at the state after three strip-draw passes (which runs the three passes of the
140 mm test first), and LS-DYNA at the debris of a 20 mm slide under each pressure.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

CASES = {
    "lsdyna, beta 0.1, band 2": ["lsdyna", "-o", "friction.k", "--beta", "0.1", "--band", "2"],
    "abaqus, beta axis": ["abaqus", "-o", "friction.inp"],
    "table, beta 0.1": ["table", "-o", "friction.json", "--beta", "0.1"],
    "lsdyna, after 3 passes at 25 MPa": ["lsdyna", "-o", "friction.k", "--passes", "3", "--pressure", "25",
                                         "--pressure-range", "10", "30"],
    "lsdyna, slide 20 mm": ["lsdyna", "-o", "friction.k", "--slide", "20"],
}
TARGET = 2.0  # s


def run_case(args: list[str], folder: Path) -> tuple[float, str]:
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "tribocosim.cli", "export", *args], cwd=folder, capture_output=True,
                          text=True, timeout=600)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"tribocosim export {' '.join(args)} failed:\n{proc.stderr}")
    return wall, proc.stdout


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args(argv)
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        run_case(CASES["table, beta 0.1"], Path(tmp))  # builds the native core into the cache if it is missing
        for name, case in CASES.items():
            walls, out = [], ""
            for _ in range(args.repeat):
                wall, out = run_case(case, Path(tmp))
                walls.append(wall)
            first = next(line for line in out.splitlines() if line.startswith("wrote"))
            results[name] = {"median_s": statistics.median(walls), "max_s": max(walls), "runs": len(walls),
                             "command": "tribocosim export " + " ".join(case), "first_file": first}
            print(f"{name:<36} median {statistics.median(walls):6.2f} s   max {max(walls):6.2f} s   "
                  f"({'within' if max(walls) < TARGET else 'ABOVE'} the {TARGET:g} s target)")
            print(f"    {first}")
    if args.json:
        args.json.write_text(json.dumps(results, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
