"""Benchmark of the Fourier-BEM contact solver.

For each grid n (default 256, 512, 1024, 2048) a self-affine surface (L = 500 um, H = 0.8,
RMS slope 0.34, PSD between q_roll = 2 (2 pi / L) and q_cut = 50 (2 pi / L), i.e. wavelengths
250 um to 10 um) is pressed on a flat (E* = 55 GPa) at p = 10 and 30 MPa, elastic and with
p_crit = 340 MPa, tolerance 1e-8. Printed per case, as it goes:

- wall and CPU time of a cold solve (minimum over --repeat runs), iterations, FFT pairs used;
- ``t_it/t_fft``: wall time per iteration divided by the wall time of one pyFFTW rfft2+irfft2
  pair on the same grid (measured in a tight loop; target <= 1.5);
- ``sat/el``: iterations of the saturated solve over those of the elastic one (target <= 3);
- ``warm/cold``: wall time of a re-solve after rolling the gap by one pixel, warm-started from the
  previous result, over the cold solve (target <= 0.25), and the same with ``warm_shift=(1, 0)``
  (the shift is known to the sliding loop; for a rigidly shifted gap the shifted solution is
  exact);
- kappa = (A_c/A0) / (p / (E* h'_rms)) of the elastic solves (Eq. 8).

The machine's load average is printed at the start and the end: timings on a shared machine
are upper bounds. Usage::

    python benchmarks/bench_bem.py [--sizes 256 512] [--repeat 3] [--threads 1] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import time

import numpy as np

from tribocosim.surrogate.bem import ContactSolver, gap_against_flat
from tribocosim.surrogate.fft import RFFT2Pair
from tribocosim.surrogate.surfaces import rms_slope, self_affine_surface

SIZE, HURST, SLOPE, E_STAR, P_CRIT = 500e-6, 0.8, 0.34, 55e9, 340e6
K_ROLL, K_CUT = 2, 50


def fft_pair_time(n: int, threads: int) -> float:
    """Median wall time of one rfft2 + irfft2 pair (pyFFTW, FFTW_MEASURE plans)."""
    pair = RFFT2Pair(n, threads)
    pair.real_in[...] = np.random.default_rng(0).standard_normal((n, n))
    reps = max(5, int(3e7 / (n * n)))
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(reps):
            pair.forward()
            pair.backward()
        times.append((time.perf_counter() - t0) / reps)
    return statistics.median(times)


def timed_solve(solver, gap, p, repeat, **kw):
    """(result, min wall time, min CPU time) over ``repeat`` solves."""
    best_wall = best_cpu = math.inf
    for _ in range(repeat):
        w0, c0 = time.perf_counter(), time.process_time()
        res = solver.solve(gap, p, **kw)
        best_wall = min(best_wall, time.perf_counter() - w0)
        best_cpu = min(best_cpu, time.process_time() - c0)
    return res, best_wall, best_cpu


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[256, 512, 1024, 2048])
    ap.add_argument("--pressures", type=float, nargs="+", default=[10e6, 30e6])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--tol", type=float, default=1e-8)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--json", help="also write the rows to this JSON file")
    args = ap.parse_args(argv)

    ContactSolver(32, SIZE, E_STAR, p_crit=P_CRIT).solve(np.zeros((32, 32)), 1e6)  # JIT warm-up
    load0 = os.getloadavg()
    print(f"# load average at start: {load0[0]:.2f} {load0[1]:.2f} {load0[2]:.2f} "
          f"({os.cpu_count()} CPUs), threads={args.threads}, tol={args.tol:g}", flush=True)
    hdr = (f"{'n':>5} {'p[MPa]':>6} {'p_crit':>6} {'wall[s]':>8} {'cpu[s]':>7} {'iter':>5} "
           f"{'pairs':>5} {'t_fft[ms]':>9} {'t_it/t_fft':>10} {'sat/el':>6} {'warm/cold':>9} "
           f"{'warm_it':>7} {'shift/cold':>10} {'A_c/A0':>8} {'kappa':>6}")
    print(hdr, flush=True)
    rows = []
    for n in args.sizes:
        h = self_affine_surface(n, SIZE, HURST, K_ROLL * 2 * math.pi / SIZE,
                                K_CUT * 2 * math.pi / SIZE, rms_slope=SLOPE, seed=args.seed)
        gap = gap_against_flat(h)
        slope = rms_slope(gap, SIZE)
        moved = np.roll(gap, 1, axis=0)
        t_fft = fft_pair_time(n, args.threads)
        for p in args.pressures:
            elastic_iters = None
            for pc in (None, P_CRIT):
                solver = ContactSolver(n, SIZE, E_STAR, p_crit=pc, tol=args.tol,
                                       threads=args.threads)
                cold, wall, cpu = timed_solve(solver, gap, p, args.repeat)
                warm, wwall, _ = timed_solve(solver, moved, p, args.repeat, warm_start=cold)
                hint, hwall, _ = timed_solve(solver, moved, p, args.repeat, warm_start=cold,
                                             warm_shift=(1, 0))
                if pc is None:
                    elastic_iters = cold.iterations
                kappa = cold.contact_area_fraction / (p / (E_STAR * slope)) if pc is None else None
                row = {"n": n, "pressure": p, "p_crit": pc, "wall_s": wall, "cpu_s": cpu,
                       "iterations": cold.iterations, "fft_pairs": cold.fft_pairs,
                       "residual": cold.residual, "t_fft_s": t_fft,
                       "t_iter_over_t_fft": wall / max(cold.iterations, 1) / t_fft,
                       "sat_over_elastic_iters": (cold.iterations / elastic_iters
                                                  if pc is not None else None),
                       "warm_over_cold": wwall / wall, "warm_iterations": warm.iterations,
                       "warm_shift_over_cold": hwall / wall,
                       "contact_area_fraction": cold.contact_area_fraction, "kappa": kappa}
                rows.append(row)
                sat = f"{row['sat_over_elastic_iters']:6.2f}" if pc is not None else f"{'-':>6}"
                kap = f"{kappa:6.3f}" if kappa is not None else f"{'-':>6}"
                print(f"{n:5d} {p / 1e6:6.1f} {('-' if pc is None else f'{pc / 1e6:.0f}'):>6} "
                      f"{wall:8.3f} {cpu:7.3f} {cold.iterations:5d} {cold.fft_pairs:5d} "
                      f"{t_fft * 1e3:9.3f} {row['t_iter_over_t_fft']:10.2f} {sat} "
                      f"{row['warm_over_cold']:9.2f} {warm.iterations:7d} "
                      f"{row['warm_shift_over_cold']:10.2f} {cold.contact_area_fraction:8.5f} "
                      f"{kap}", flush=True)
    load1 = os.getloadavg()
    print(f"# load average at end: {load1[0]:.2f} {load1[1]:.2f} {load1[2]:.2f}", flush=True)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"load_start": load0, "load_end": load1, "rows": rows}, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
