"""The cost of one VFRICTION call on a block of 136 contact points (Abaqus/Explicit's vector length) against 136 times
the StripDraw FMU's friction evaluation per node, in instructions counted by callgrind (repeatable under load).

The routine: ``tribocosim export vfriction`` (the shipped table, default parameters, mm-t-s), compiled with gfortran and
the system C compiler at -O2, driven by the stand-in for Abaqus/Explicit's side of the call
(tests/components/fe_harness/vfriction_harness.f90) over ``--calls`` increments of one block of 136 points sliding
0.08 mm per 1 ms increment (each point's state kept between calls, as the FE code keeps it); callgrind collects inside
``vfriction`` only (the Fortran shim, the C glue and the core: the pressure, the slip's magnitude, the law's lookup,
the cap, the debris update, the force). Two blocks: every point at 10 MPa (the strip-draw test's uniform pressure:
the points share the table's rows at that pressure, as the FMU's nodes do) and the points at 136 pressures spread
over 1-30 MPa (a forming part's contact: each point interpolates the table at its own pressure).

The FMU: the default draw (140 mm at 0.08 m/s, 1 ms steps, 150 elements) of the StripDraw FMU built with its symbol
table in the C host of tests/native/host, under callgrind as ``benchmarks/callgrind_fmu.py --where`` runs it; its
friction evaluation per node is the inclusive cost of ``tc_law_mu`` and ``tc_law_beta_cap`` over the draw (the lookups of
the friction limits and of the cap) divided by the nodal evaluations the draw makes (the nodes whose limits each step
looks up, counted on the Python binding's run of the same draw: the nodes with a friction limit after each step). The
debris update per node (tc_sd_debris_interval) is printed beside it and added in a second ratio.

    python benchmarks/bench_user_friction.py [--calls 200]

Needs valgrind and gfortran on the PATH. Prints the instructions per call, per point and the ratios (the issue's
target: at most 10).
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from callgrind_fmu import _host, inclusive_costs, symbol_library  # noqa: E402 (the FMU's callgrind run)

PROJECT_ROOT = Path(__file__).resolve().parents[1]
HARNESS = PROJECT_ROOT / "tests" / "components" / "fe_harness" / "vfriction_harness.f90"
BLOCK = 136
DT = 1e-3
SLIDE = 0.08  # mm per increment: 0.08 m/s
AREA = 1.533 * 35.0  # mm^2: a strip node's contact area (l_e w_T)


def _run(cmd, **kw):
    p = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, **kw)
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(map(str, cmd))} failed:\n{p.stderr[-3000:]}")
    return p


def _callgrind(cmd, out: Path, collect: tuple[str, ...]) -> int:
    vg = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", "--collect-atstart=no",
          *(f"--toggle-collect={f}" for f in collect)]
    _run(vg + [str(c) for c in cmd], env={"PATH": "/usr/bin:/bin"})
    for line in out.read_text().splitlines():
        if line.startswith("summary:"):
            return int(line.split()[1])
    raise SystemExit("no summary line in the callgrind output")


def routine_cost(tmp: Path, calls: int) -> dict[str, float]:
    """Instructions per VFRICTION call of the two blocks (module docstring)."""
    from tribocosim.cosim.apps.export_cli import main as export_main

    (tmp / "vaba_param.inc").write_text("      implicit real*8 (a-h,o-z)\n      parameter (nprecd=2)\n")
    if export_main(["vfriction", "-o", str(tmp / "vfr.f")]) != 0:
        raise SystemExit("the export failed")
    check = int(next(line for line in (tmp / "vfr.f").read_text().splitlines() if "check number" in line)
                .split("check number")[1].split()[0])
    _run(["gfortran", "-O2", "-I", tmp, "-c", tmp / "vfr.f", "-o", tmp / "vfr_f.o"])
    _run(["cc", "-std=c11", "-O2", "-c", tmp / "vfr.c", "-o", tmp / "vfr_c.o"])
    exe = tmp / "harness"
    _run(["gfortran", "-O2", HARNESS, tmp / "vfr_f.o", tmp / "vfr_c.o", "-lm", "-o", exe])
    out = {}
    blocks = {"every point at 10 MPa": np.full(BLOCK, 10.0),
              "points at 1-30 MPa": np.exp(np.linspace(np.log(1.0), np.log(30.0), BLOCK))}
    for label, pressure in blocks.items():
        lines = [f"{BLOCK} 3 1", f"{check}."]
        for _ in range(calls):
            lines.append(f"{DT!r} {BLOCK}")
            lines += [f"{i + 1} {float(p * AREA)!r} {AREA!r} {SLIDE!r} 0.0 0.0 1e300" for i, p in enumerate(pressure)]
        replay = tmp / "replay.txt"
        replay.write_text("\n".join(lines) + "\n")
        total = _callgrind([exe, replay], tmp / "routine.out", ("vfriction_",))
        out[label] = total / calls
    return out


def fmu_cost(tmp: Path) -> dict[str, float]:
    """The FMU's friction evaluation and debris update per node over the default draw (module docstring)."""
    from fmpy import read_model_description

    from tribocosim.components.fmus.native_build import build_native_fmus
    from tribocosim.components.stripdraw import StripDrawModel, StripDrawParameters, make_friction_law, read_table

    from bench_fmu import F10, N_DRAW, V0

    fmu = build_native_fmus(tmp / "native", names=["StripDraw"], platforms=["linux64"])["StripDraw"]
    cmd, unzipped = _host(tmp, fmu, N_DRAW, None, "unzipped")
    symbol_library(unzipped, read_model_description(str(fmu)).guid)
    out = tmp / "fmu.out"
    _callgrind(cmd, out, ("fmi2SetReal", "fmi2DoStep", "fmi2GetReal"))
    costs = inclusive_costs(out)
    params = StripDrawParameters()
    model = StripDrawModel(params, make_friction_law(params, read_table(PROJECT_ROOT / "models" / "friction_table.npz")))
    evaluations = under = 0
    for _ in range(N_DRAW):
        model.step(DT, {"normal_force": F10, "grip_velocity": V0})
        evaluations += int(np.count_nonzero(model.friction_limit))
        under += int(np.count_nonzero(model._nodal("contact_weight")))
    lookup = costs["tc_law_mu"] + costs["tc_law_beta_cap"]
    debris = costs["tc_sd_debris_interval"] - costs["tc_law_beta_cap"]
    return {"friction per node": lookup / evaluations, "debris per node": debris / max(under, 1),
            "nodes per step": evaluations / N_DRAW}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--calls", type=int, default=200, help="VFRICTION calls of each block")
    args = parser.parse_args(argv)
    for tool in ("valgrind", "gfortran", "cc"):
        if shutil.which(tool) is None:
            raise SystemExit(f"{tool} is not on the PATH")
    with tempfile.TemporaryDirectory(prefix="tribocosim-user-friction-") as tmp_:
        tmp = Path(tmp_)
        routine = routine_cost(tmp, args.calls)
        fmu = fmu_cost(tmp)
    per_node = fmu["friction per node"]
    both = per_node + fmu["debris per node"]
    print(f"StripDraw FMU, default draw (callgrind): friction evaluation {per_node:.0f} instructions per node "
          f"({fmu['nodes per step']:.1f} nodes per step), debris update {fmu['debris per node']:.0f} per node under "
          "the pad")
    for label, cost in routine.items():
        print(f"VFRICTION, block of {BLOCK} points, {label}: {cost:.0f} instructions per call ({cost / BLOCK:.0f} per "
              f"point); / ({BLOCK} x the FMU's friction evaluation) = {cost / (BLOCK * per_node):.2f}; / ({BLOCK} x "
              f"friction + debris) = {cost / (BLOCK * both):.2f} (target: at most 10)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
