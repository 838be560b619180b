"""One case of the shipped table's preset, whole slide, set-up included: wall and CPU time and its results.

Default: the quick preset's case at 30 MPa, beta 0.75 (435 flakes), 0.08 m/s, surface pair 0, placement 11,
with the flake solver the preset chooses (``--solver`` overrides it: ``inertial`` or ``overdamped``).

Side by side: ``--against PYTHON`` runs the same case with another interpreter (e.g. one with an older
checkout installed) and with this one in turn, ``--rounds`` times, each in a fresh process, and prints the
ratio of each round and the load before and after each run; an older checkout without the overdamped solver
runs the inertial DEM. Set ``TRIBOCOSIM_FFTW_WISDOM`` to one file so that both use the same FFT plans.

    python benchmarks/bench_case.py [--pressure 30e6] [--beta 0.75] [--surface 0] [--seed 11]
    python benchmarks/bench_case.py --against /path/to/other/venv/bin/python [--rounds 1]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from dataclasses import replace


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def run(args) -> dict:
    """The case in this process; returns its timings and results."""
    load0 = _load()
    t0, c0 = time.perf_counter(), time.process_time()
    from tribocosim.surrogate.campaign import make_case
    from tribocosim.surrogate.coupling import run_slide
    from tribocosim.surrogate.slide_config import SlideConfig
    from tribocosim.surrogate.sweep import load_preset

    sweep = load_preset(args.preset)
    count = round(args.beta * sweep.base_config().size ** 2 / (math.pi * (0.5 * args.diameter) ** 2))
    cfg = make_case(sweep, args.surface, args.pressure, args.velocity, count, args.diameter, args.seed).config
    if args.solver is not None:
        try:
            from tribocosim.surrogate.slide_config import FLAKE_SOLVERS  # noqa: F401 (a checkout that has them)
            cfg = replace(cfg, flake_solver=args.solver)
        except ImportError:
            pass  # a checkout with the inertial DEM only runs it (its result says "inertial")
    res = run_slide(cfg)
    s = res.summary()
    return {"solver": getattr(cfg, "flake_solver", None) or "inertial", "flakes": count, "beta": cfg.beta,
            "wall_s": time.perf_counter() - t0, "cpu_s": time.process_time() - c0,
            "a_p": s["mean_particle_fraction"], "a_c": s["mean_contact_fraction"],
            "a_p_clusters": s["mean_particle_fraction_clusters"], "load_before": load0, "load_after": _load(),
            "code": os.path.dirname(sys.modules[SlideConfig.__module__].__file__)}


def show(r: dict, who: str) -> None:
    print(f"{who}: {r['solver']}, {r['flakes']} flakes: wall {r['wall_s']:.1f} s, CPU {r['cpu_s']:.1f} s, "
          f"<A_p>/A0 {r['a_p']:.6g}, <A_c>/A0 {r['a_c']:.6g}, cluster rule {r['a_p_clusters']:.4g} "
          f"(load {r['load_before']} -> {r['load_after']}; {r['code']})", flush=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", default="quick")
    ap.add_argument("--pressure", type=float, default=30e6)
    ap.add_argument("--beta", type=float, default=0.75)
    ap.add_argument("--diameter", type=float, default=12e-6)
    ap.add_argument("--velocity", type=float, default=0.08)
    ap.add_argument("--surface", type=int, default=0)
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--solver", default=None, help="inertial or overdamped (default: the preset's)")
    ap.add_argument("--against", default=None, help="another Python interpreter to run the case with, in turn")
    ap.add_argument("--rounds", type=int, default=1)
    ap.add_argument("--json", action="store_true", help="print one JSON line (used by --against)")
    args = ap.parse_args(argv)
    if args.against is None:
        r = run(args)
        if args.json:
            print(json.dumps(r))
        else:
            show(r, "this")
        return 0
    own = [a for a in (argv if argv is not None else sys.argv[1:]) if a not in ("--against", args.against)]
    rows = []
    for k in range(args.rounds):
        pair = {}
        for who, python in (("other", args.against), ("this", sys.executable)):
            out = subprocess.run([python, os.path.abspath(__file__), *own, "--json"], capture_output=True,
                                 text=True, check=True)
            pair[who] = json.loads(out.stdout.strip().splitlines()[-1])
            show(pair[who], f"round {k + 1}, {who}")
        ratio = pair["other"]["wall_s"] / pair["this"]["wall_s"]
        print(f"round {k + 1}: other / this = {ratio:.1f} (wall, set-up included), "
              f"{pair['other']['cpu_s'] / pair['this']['cpu_s']:.1f} (CPU); A_p this / other = "
              f"{pair['this']['a_p'] / pair['other']['a_p']:.4f}", flush=True)
        rows.append(pair)
    return 0


if __name__ == "__main__":
    sys.exit(main())
