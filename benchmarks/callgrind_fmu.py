"""Instructions per step of the native StripDraw FMU in the C host, counted by callgrind (repeatable under load).

The wall-clock figure of ``bench_fmu.py`` depends on what else runs on the machine; the number of
instructions the host's stepping loop executes does not. This script builds the native FMU (linux64), the
C host of ``tests/native/host/fmi2_host.c``, and runs the default draw (140 mm at 0.08 m/s, 1 ms steps, the
FMU's default parameters and inputs: 10 MPa on the 35 x 35 mm pad) under ``valgrind --tool=callgrind`` with
collection switched on only inside ``fmi2SetReal``, ``fmi2DoStep`` and ``fmi2GetReal``: the host loop's
work (set the inputs, step, get the outputs). Printed: total instructions collected and instructions per step.

    python benchmarks/callgrind_fmu.py [--steps 1750] [--n-elements N]

Needs valgrind on the PATH. The count is the same from run to run up to a few instructions per step.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

N_DRAW = 1750  # steps: 140 mm at 0.08 m/s


def count(steps: int, n_elements: int | None, keep: Path | None = None) -> tuple[int, float]:
    """(instructions collected in the host loop, per step); ``keep``: copy callgrind's output file there (for
    callgrind_annotate)."""
    from fmpy import extract, read_model_description

    from bench_fmu import host_command  # the same host and draw as the wall-clock figure

    from tribocosim.components.fmus.native_build import build_native_fmus

    if shutil.which("valgrind") is None:
        raise SystemExit("valgrind is not on the PATH")
    with tempfile.TemporaryDirectory(prefix="tribocosim-callgrind-") as tmp_:
        tmp = Path(tmp_)
        fmu = build_native_fmus(tmp / "native", names=["StripDraw"], platforms=["linux64"])["StripDraw"]
        md = read_model_description(str(fmu))
        unzipped = str(extract(str(fmu), str(tmp / "unzipped")))
        cmd = host_command(tmp, unzipped, md, steps)
        vr = {v.name: v.valueReference for v in md.modelVariables}
        if n_elements is not None:
            cmd += ["--set", f"i:{vr['n_elements']}={n_elements}"]
        out = tmp / "callgrind.out"
        vg = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", "--collect-atstart=no",
              "--toggle-collect=fmi2SetReal", "--toggle-collect=fmi2DoStep", "--toggle-collect=fmi2GetReal"]
        proc = subprocess.run(vg + cmd, capture_output=True, text=True, env={"PATH": "/usr/bin:/bin"})
        if proc.returncode != 0:
            raise SystemExit(f"callgrind run failed:\n{proc.stderr[-2000:]}")
        if keep is not None:
            shutil.copy2(out, keep)
        match = re.search(r"^summary:\s+(\d+)", out.read_text(), re.MULTILINE)
        if match is None:
            raise SystemExit("no summary line in the callgrind output")
        total = int(match.group(1))
    return total, total / steps


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=N_DRAW)
    parser.add_argument("--n-elements", type=int, default=None, help="mesh (default: the FMU's default)")
    parser.add_argument("--keep", type=Path, default=None, help="copy callgrind's output file here")
    args = parser.parse_args(argv)
    total, per = count(args.steps, args.n_elements, args.keep)
    print(f"callgrind, C host loop (fmi2SetReal + fmi2DoStep + fmi2GetReal), {args.steps} steps of the default draw: "
          f"{total} instructions, {per:.0f} per step")
    return 0


if __name__ == "__main__":
    sys.exit(main())
