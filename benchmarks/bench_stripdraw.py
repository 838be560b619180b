"""Benchmark: full 140 mm strip draws at 0.08 m/s, explicit vs implicit bar integrator.

For pad lengths 35, 70 and 140 mm (P_N = 10 MPa, default mesh, shipped friction table) it prints
the wall time, the real-time factor (simulated / wall time) and mu_bar (mean over the last 20 % of
the draw) of each integrator, and the relative mu_bar difference between them. Wall times are
the best of 3 runs for the implicit integrator (one run for the explicit one), after a warm-up
run that loads the native core (built on first use).

Targets: implicit >= 50x faster than real time; explicit finishes the 35 mm case in under
5 minutes; mu_bar of the two agree within 1 %.

Usage: python benchmarks/bench_stripdraw.py [--pads 0.035 0.07 0.14] [--no-explicit]
"""

from __future__ import annotations

import argparse
import time

from tribocosim.cosim.studies.stripdraw_experiment import run_strip_draw, steady_mean


def one(tool_length: float, integrator: str, step: float, repeats: int):
    """Run one draw ``repeats`` times; return (best wall time, simulated time, mu_bar)."""
    run_strip_draw(tool_length=tool_length, integrator=integrator, draw_length=0.002, step=step)  # warm up (the core library)
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        times, outs, _ = run_strip_draw(tool_length=tool_length, integrator=integrator, step=step)
        best = min(best, time.perf_counter() - t0)
    return best, float(times[-1]), steady_mean(outs)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pads", type=float, nargs="+", default=[0.035, 0.07, 0.14])
    ap.add_argument("--no-explicit", action="store_true")
    args = ap.parse_args()
    print(f"{'pad [mm]':>8} {'integrator':>10} {'step [ms]':>9} {'wall [s]':>9} {'RTF':>8} {'mu_bar':>8}")
    for pad in args.pads:
        results = {}
        runs = [("implicit", 1e-3), ("implicit", 1e-2)]
        if not args.no_explicit:
            runs.append(("explicit", 1e-3))
        for integrator, step in runs:
            wall, sim, mu_bar = one(pad, integrator, step, 3 if integrator == "implicit" else 1)
            results[(integrator, step)] = mu_bar
            print(f"{pad * 1e3:8.0f} {integrator:>10} {step * 1e3:9.0f} {wall:9.3f} {sim / wall:8.1f} {mu_bar:8.5f}", flush=True)
        if ("explicit", 1e-3) in results:
            ref = results[("explicit", 1e-3)]
            for key in (("implicit", 1e-3), ("implicit", 1e-2)):
                diff = (results[key] - ref) / ref
                print(f"{'':8} mu_bar(implicit, {key[1] * 1e3:.0f} ms) - mu_bar(explicit): {100 * diff:+.3f} %")


if __name__ == "__main__":
    main()
