"""``tribocosim meso``: mesoscale tools (rough surfaces, BEM contact, BEM-DEM sliding).

Subcommands (each prints JSON on stdout; the key names are a stable contract):

- ``surface``: generate a periodic self-affine surface (:mod:`tribocosim.surrogate.surfaces`) and save its
  heights [m] to ``.npy``; prints one object with the parameters and the measured RMS height,
  RMS slopes (spectral and finite-difference) and the file name.
- ``contact``: load a height map (``.npy`` or text, metres), build the gap of the rigid rough
  surface against a flat (``max(h) - h``), solve the elastic or elastic-plastic contact
  (:mod:`tribocosim.surrogate.bem`) for each ``--pressure`` from the undeformed state, and print one object
  per pressure with the keys ``pressure, contact_area_fraction, mean_gap, n_clusters,
  mean_cluster_distance, max_traction, iterations, residual, converged, wall_time_s`` (SI
  units; ``mean_cluster_distance`` is null with fewer than two clusters). Exit status 1 if a
  solve did not converge (the object says so), 2 on bad input.
- ``slide``: the BEM-DEM sliding run, implemented in :mod:`tribocosim.surrogate.slide_cli`.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import sys
import time

from tribocosim.errors import TribocosimError

_SUBCOMMANDS = {"surface": "generate a periodic self-affine rough surface (.npy)",
                "contact": "BEM contact of a rough surface against a flat at given pressures",
                "slide": "one BEM-DEM sliding run over 2L (paper Fig. 7)"}


def _usage() -> str:
    lines = ["usage: tribocosim meso SUBCOMMAND [ARGS...]", "", "subcommands:"]
    lines += [f"  {k:<9} {v}" for k, v in _SUBCOMMANDS.items()]
    return "\n".join(lines)


def _surface_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="tribocosim meso surface",
                                 description="periodic isotropic self-affine surface, PSD "
                                 "~ q^(-2(1+H)) between q_roll and q_cut (heights in m)")
    ap.add_argument("--n", type=int, required=True, help="grid points per side")
    ap.add_argument("--size", type=float, required=True, help="side length L [m]")
    ap.add_argument("--hurst", type=float, default=0.8, help="Hurst exponent H (default 0.8)")
    ap.add_argument("--q-roll", type=float, required=True,
                    help="roll-off wavenumber [rad/m] (2 pi / wavelength; flat PSD below)")
    ap.add_argument("--q-cut", type=float, required=True,
                    help="cutoff wavenumber [rad/m] (zero PSD above; <= pi n / L)")
    norm = ap.add_mutually_exclusive_group(required=True)
    norm.add_argument("--rms-slope", type=float, help="RMS slope of the result [-]")
    norm.add_argument("--rms-height", type=float, help="RMS height of the result [m]")
    ap.add_argument("--slope-definition", choices=("spectral", "finite_difference"),
                    default="spectral", help="definition used by --rms-slope")
    ap.add_argument("--seed", type=int, default=0, help="seed of the random phases")
    ap.add_argument("-o", "--output", required=True, help="output .npy file")
    return ap


def _contact_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="tribocosim meso contact",
                                 description="Fourier-BEM contact of a rigid rough surface "
                                 "against a flat elastic(-plastic) half-space, one JSON object "
                                 "per pressure")
    ap.add_argument("--surface", required=True, help="height map (.npy or text grid) [m]")
    ap.add_argument("--size", type=float, required=True, help="side length L [m]")
    ap.add_argument("--e-star", type=float, required=True, help="effective modulus E* [Pa]")
    ap.add_argument("--pressure", type=float, action="append", required=True,
                    help="mean pressure [Pa]; repeat for several")
    ap.add_argument("--p-crit", type=float, default=None,
                    help="traction cap (plastic saturation) [Pa]; default: elastic")
    ap.add_argument("--tol", type=float, default=1e-8, help="relative residual tolerance")
    ap.add_argument("--max-iter", type=int, default=10000, help="iteration limit")
    ap.add_argument("--threads", type=int, default=1, help="FFTW threads")
    ap.add_argument("--json", action="store_true", help="JSON lines (default: a table)")
    return ap


def _surface(argv: list[str]) -> int:
    args = _surface_parser().parse_args(argv)
    import numpy as np

    from .surfaces import rms_height, rms_slope, self_affine_surface

    h = self_affine_surface(args.n, args.size, args.hurst, args.q_roll, args.q_cut,
                            rms_height=args.rms_height, rms_slope=args.rms_slope, seed=args.seed,
                            slope_definition=args.slope_definition)
    out = args.output if args.output.endswith(".npy") else args.output + ".npy"
    np.save(out, h)
    print(json.dumps({"n": args.n, "size": args.size, "hurst": args.hurst,
                      "q_roll": args.q_roll, "q_cut": args.q_cut, "seed": args.seed,
                      "rms_height": rms_height(h),
                      "rms_slope_spectral": rms_slope(h, args.size, "spectral"),
                      "rms_slope_finite_difference": rms_slope(h, args.size, "finite_difference"),
                      "output": out}))
    return 0


def _contact(argv: list[str]) -> int:
    args = _contact_parser().parse_args(argv)
    from .bem import ContactSolver, gap_against_flat
    from .clusters import cluster_statistics
    from .surfaces import load_height_map

    h = load_height_map(args.surface)
    gap = gap_against_flat(h)
    solver = ContactSolver(h.shape[0], args.size, args.e_star, p_crit=args.p_crit, tol=args.tol,
                           max_iter=args.max_iter, threads=args.threads, on_failure="flag")
    status = 0
    if not args.json:
        print(f"{'pressure[Pa]':>13} {'A_c/A0':>10} {'mean_gap[m]':>12} {'N_c':>6} "
              f"{'d_c[m]':>10} {'max_t[Pa]':>11} {'iter':>6} {'residual':>9} conv {'wall[s]':>8}")
    for p in args.pressure:
        t0 = time.perf_counter()
        res = solver.solve(gap, p)
        wall = time.perf_counter() - t0
        stats = cluster_statistics(res.traction, args.size)
        dc = stats["mean_cluster_distance"]
        rec = {"pressure": p, "contact_area_fraction": res.contact_area_fraction,
               "mean_gap": res.mean_gap, "n_clusters": stats["n_clusters"],
               "mean_cluster_distance": dc if math.isfinite(dc) else None,
               "max_traction": float(res.traction.max()), "iterations": res.iterations,
               "residual": res.residual, "converged": res.converged, "wall_time_s": wall}
        status = status if res.converged else 1
        if args.json:
            print(json.dumps(rec), flush=True)
        else:
            dcs = f"{dc:10.3e}" if math.isfinite(dc) else f"{'-':>10}"
            print(f"{p:13.4e} {rec['contact_area_fraction']:10.4e} {rec['mean_gap']:12.4e} "
                  f"{rec['n_clusters']:6d} {dcs} {rec['max_traction']:11.4e} "
                  f"{rec['iterations']:6d} {rec['residual']:9.2e} "
                  f"{'yes' if res.converged else 'NO ':>4} "
                  f"{wall:8.3f}", flush=True)
    return status


def _slide(argv: list[str]) -> int:
    try:
        module = importlib.import_module("tribocosim.surrogate.slide_cli")
    except ImportError as exc:
        print(f"tribocosim meso slide: not available yet in this version ({exc})", file=sys.stderr)
        return 2
    return int(module.main(argv) or 0)


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``tribocosim meso``."""
    args = list(sys.argv[1:] if argv is None else argv)
    if not args or args[0] in ("-h", "--help", "help"):
        print(_usage())
        return 0 if args else 2
    name, rest = args[0], args[1:]
    handlers = {"surface": _surface, "contact": _contact, "slide": _slide}
    if name not in handlers:
        print(f"tribocosim meso: unknown subcommand {name!r}; known: {', '.join(handlers)}",
              file=sys.stderr)
        return 2
    try:
        return handlers[name](rest)
    except (TribocosimError, OSError) as exc:
        print(f"tribocosim meso {name}: error: {exc}", file=sys.stderr)
        return 2
