"""``tribocosim meso``: mesoscale tools (rough surfaces, BEM contact, BEM-DEM sliding).

Subcommands (each prints JSON on stdout; the key names are a stable contract):

- ``surface``: generate a periodic self-affine surface (:mod:`tribocosim.surrogate.surfaces`), or, with
  ``--from FILE``, prepare a measured map (X3P and the other formats SurfaceTopography reads; the
  ``measured`` extra) as the periodic grid of a slide (:mod:`tribocosim.surrogate.measured_surfaces`), and
  save its heights [m] to ``.npy``; prints one object with the parameters and the measured RMS height,
  RMS slopes (spectral and finite-difference) and the file name; with ``--from`` also what was done to the
  file (``measured``: file, sha256, scan points and pixel, detrend, periodization, missing points filled)
  and the library's statistics of the result (``library``: RMS height, both slopes, RMS curvature).
- ``contact``: load a height map (``.npy`` or text, metres), build the gap of the rigid rough
  surface against a flat (``max(h) - h``), solve the elastic or elastic-plastic contact
  (:mod:`tribocosim.surrogate.bem`) for each ``--pressure`` from the undeformed state, and print one object
  per pressure with the keys ``pressure, contact_area_fraction, mean_gap, n_clusters,
  mean_cluster_distance, max_traction, iterations, residual, converged, wall_time_s`` (SI
  units; ``mean_cluster_distance`` is null with fewer than two clusters). Exit status 1 if a
  solve did not converge (the object says so), 2 on bad input.
- ``slide``: the BEM-DEM sliding run, implemented in :mod:`tribocosim.surrogate.slide_cli`.

Each estimates its peak memory before it allocates and refuses (exit 2, one line naming the size and the estimate)
above the memory available or ``--max-memory`` (:mod:`tribocosim.surrogate.memory`). Files are written through a
temporary name and a rename; an error names the path as the user gave it.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import sys
import time
from pathlib import Path

from tribocosim.errors import ParameterError, TribocosimError

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
                                 "~ q^(-2(1+H)) between q_roll and q_cut (heights in m); or, with --from, "
                                 "a measured map made the periodic grid of a slide")
    ap.add_argument("--n", type=int, required=True, help="grid points per side")
    ap.add_argument("--size", type=float, required=True, help="side length L [m]")
    gen = ap.add_argument_group("generated surface (without --from)")
    gen.add_argument("--hurst", type=float, default=None, help="Hurst exponent H (default 0.8)")
    gen.add_argument("--q-roll", type=float, help="roll-off wavenumber [rad/m] (2 pi / wavelength; flat PSD below)")
    gen.add_argument("--q-cut", type=float, help="cutoff wavenumber [rad/m] (zero PSD above; <= pi n / L)")
    norm = gen.add_mutually_exclusive_group()
    norm.add_argument("--rms-slope", type=float, help="RMS slope of the result [-]")
    norm.add_argument("--rms-height", type=float, help="RMS height of the result [m]")
    gen.add_argument("--slope-definition", choices=("spectral", "finite_difference"),
                     default=None, help="definition used by --rms-slope")
    ap.add_argument("--seed", type=int, default=0, help="seed of the random phases (generation, or --periodization "
                    "synthesis)")
    meas = ap.add_argument_group("measured surface (the measured extra: pip install -e \".[measured]\")")
    meas.add_argument("--from", dest="source", metavar="FILE",
                      help="a measured height map: X3P or another format SurfaceTopography reads")
    meas.add_argument("--detrend", choices=("plane", "curvature", "mean"), default=None,
                      help="subtracted from the whole map (default plane; mean for --periodization none)")
    meas.add_argument("--periodization", choices=("smooth", "synthesis", "none"), default=None,
                      help="periodic-plus-smooth (default), IAAFT synthesis, or none (a periodic map)")
    meas.add_argument("--fill-missing", action="store_true",
                      help="fill undefined points by harmonic interpolation (default: refuse the file)")
    meas.add_argument("--side", choices=("sheet", "tool"), default="sheet",
                      help="a tool is turned over about x: h(x, y) -> -h(x, -y)")
    ap.add_argument("-o", "--output", required=True, help="output .npy file (.npy is added when missing)")
    _max_memory(ap)
    return ap


def _max_memory(ap: argparse.ArgumentParser) -> None:
    ap.add_argument("--max-memory", default=None, metavar="SIZE",
                    help="refuse when the estimated peak memory exceeds SIZE (e.g. 8G, 512M; powers of 1024) instead "
                         "of the memory available (MemAvailable)")


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
    _max_memory(ap)
    return ap


_GENERATION = ("hurst", "q_roll", "q_cut", "rms_slope", "rms_height", "slope_definition")
_MEASURED = ("detrend", "periodization")


def _output_file(name: str) -> Path:
    """The ``.npy`` file ``-o`` names, refused when it (or its ``.npy`` name) is a folder or its folder is missing."""
    out = Path(name if name.endswith(".npy") else name + ".npy")
    given = Path(name)
    if given.is_dir() or out.is_dir():
        folder = given if given.is_dir() else out
        raise ParameterError(f"-o {name}: {folder} is a folder; allowed: a file name (e.g. {folder / 'surface.npy'})")
    if not out.parent.is_dir():
        raise ParameterError(f"-o {name}: the folder {out.parent} does not exist; allowed: a file in an existing folder")
    return out


def _save_npy(out: Path, heights) -> None:
    """Save ``heights`` to ``out`` through a temporary name in its folder and a rename (no partial file is left)."""
    import numpy as np

    from tribocosim.atomic import replaced

    try:
        with replaced(out) as tmp, open(tmp, "wb") as fh:
            np.save(fh, heights)
    except OSError as exc:
        raise TribocosimError(f"cannot write {out}: {exc.strerror or exc}") from None


def _surface(argv: list[str]) -> int:
    ap = _surface_parser()
    args = ap.parse_args(argv)
    import numpy as np

    from . import memory
    from .surfaces import rms_height, rms_slope, self_affine_surface

    given = [f"--{k.replace('_', '-')}" for k in (_GENERATION if args.source else _MEASURED)
             if getattr(args, k) is not None]
    if args.source is None:
        given += [flag for flag, on in (("--fill-missing", args.fill_missing), ("--side", args.side != "sheet")) if on]
    if given:
        why = ("not allowed with --from (they shape a generated surface)" if args.source
               else "allowed only with --from FILE (a measured map)")
        ap.error(f"{', '.join(given)}: {why}")
    limit = None if args.max_memory is None else memory.parse_bytes(args.max_memory)
    out = _output_file(args.output)
    if args.source:
        from .measured_surfaces import library_statistics, prepared_heights, scan_points

        periodization = args.periodization or "smooth"
        points = scan_points(args.source)
        memory.check(memory.Need(f"--n {args.n} with --from {args.source} ({points} points)",
                                 memory.measured_surface_bytes(args.n, points, periodization),
                                 f"the scan's {points} points, then up to "
                                 f"{memory.grids(args.n, 1 + memory.LIBRARY_STATISTICS_GRIDS)}"), limit, "a smaller --n")
        detrend = args.detrend or ("mean" if args.periodization == "none" else "plane")
        h, info = prepared_heights(args.source, args.n, args.size, detrend=detrend,
                                   periodization=args.periodization or "smooth", fill_missing=args.fill_missing,
                                   seed=args.seed, side=args.side)
        lib = library_statistics(h, args.size)
        record = {"n": args.n, "size": args.size, "seed": args.seed, "measured": info,
                  "library": {k: v for k, v in lib.items() if not k.startswith("psd")}}
    else:
        missing = [f"--{k.replace('_', '-')}" for k in ("q_roll", "q_cut") if getattr(args, k) is None]
        if args.rms_slope is None and args.rms_height is None:
            missing.append("--rms-slope or --rms-height")
        if missing:
            ap.error(f"a generated surface needs {', '.join(missing)} (or --from FILE for a measured one)")
        hurst = 0.8 if args.hurst is None else args.hurst
        memory.check(memory.Need(f"--n {args.n}", memory.surface_bytes(args.n), memory.grids(args.n, memory.SURFACE_GRIDS)),
                     limit, "a smaller --n")
        h = self_affine_surface(args.n, args.size, hurst, args.q_roll, args.q_cut,
                                rms_height=args.rms_height, rms_slope=args.rms_slope, seed=args.seed,
                                slope_definition=args.slope_definition or "spectral")
        record = {"n": args.n, "size": args.size, "hurst": hurst, "q_roll": args.q_roll, "q_cut": args.q_cut,
                  "seed": args.seed}
    _save_npy(out, h)
    print(json.dumps({**record, "rms_height": rms_height(h),
                      "rms_slope_spectral": rms_slope(h, args.size, "spectral"),
                      "rms_slope_finite_difference": rms_slope(h, args.size, "finite_difference"),
                      "output": str(out)}))
    return 0


def _contact(argv: list[str]) -> int:
    args = _contact_parser().parse_args(argv)
    from . import memory
    from .bem import ContactSolver, gap_against_flat
    from .clusters import cluster_statistics
    from .surfaces import height_map_side, load_height_map

    limit = None if args.max_memory is None else memory.parse_bytes(args.max_memory)
    n = height_map_side(args.surface)
    if n is not None:  # else load_height_map says what is wrong with the file
        grids = memory.CONTACT_GRIDS + (3.0 if len(args.pressure) > 1 else 0.0)
        memory.check(memory.Need(f"--surface {args.surface} ({n} x {n} points)", memory.contact_bytes(n, len(args.pressure)),
                                 memory.grids(n, grids)), limit, "a smaller map")
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
    except TribocosimError as exc:
        print(f"tribocosim meso {name}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # the path as the user gave it, the reason in words
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"tribocosim meso {name}: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return 2
