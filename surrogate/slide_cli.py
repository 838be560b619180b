"""``tribocosim meso slide``: one BEM-DEM sliding run (Fig. 7) from a TOML configuration.

Writes to ``--out DIR``:

- ``slide.npz``: per-step series (slide_distance [m], contact_fraction A_c/A0,
  particle_fraction A_p/A0 and particle_fraction_clusters (cluster rule only), n_blocked,
  n_blocked_clusters, bem_iterations, tool_height [m]), the snapshots
  (``snap_<k>_pos``, ``snap_<k>_quat``, ``snap_<k>_sheet``, ``snap_<k>_blocked``) and
  ``metadata`` (a JSON string: configuration, code version, units, timings);
- ``summary.json``: <A_p>/A0 (Eq. 22), <A_c>/A0, fraction of steps with a blocked flake, wall
  and split timings;
- with ``--plot``: ``flakes.png`` (Fig. 9 style) and ``particle_area.png`` (Fig. 10 style).

Files are written to a temporary name and renamed, so a finished file is always complete.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from tribocosim.errors import MemoryLimitError, ParameterError, TribocosimError

UNITS = {"slide_distance": "m", "contact_fraction": "1", "particle_fraction": "1",
         "particle_fraction_clusters": "1", "n_blocked": "1", "n_blocked_clusters": "1",
         "bem_iterations": "1", "tool_height": "m"}


def _version() -> str:
    try:
        from importlib.metadata import version

        return version("tribocosim")
    except Exception:  # pragma: no cover - not installed
        return "unknown"


def _atomic(path: Path, write) -> None:
    from tribocosim.atomic import replaced

    try:
        with replaced(path) as tmp:
            write(tmp)
    except OSError as exc:  # named by the file the user asked for, not by the temporary one
        raise OSError(exc.errno, exc.strerror, str(path)) from None


def write_result(result, out: Path) -> dict:
    """Write ``slide.npz`` and ``summary.json`` into ``out``; return the summary."""
    out.mkdir(parents=True, exist_ok=True)
    summary = result.summary()
    meta = {"config": result.config.to_dict(), "units": UNITS, "code_version": _version(),
            "summary": summary, "equations": "Fig. 7, Eq. 17-19, 22 (see surrogate.coupling)"}
    arrays = {k: getattr(result, k) for k in UNITS}
    for k, snap in result.snapshots.items():
        for name in ("pos", "quat", "sheet", "blocked"):
            if name in snap:
                arrays[f"snap_{k}_{name}"] = np.asarray(snap[name])
    arrays["metadata"] = np.array(json.dumps(meta))

    def save_npz(tmp):
        with open(tmp, "wb") as fh:
            np.savez_compressed(fh, **arrays)

    _atomic(out / "slide.npz", save_npz)
    _atomic(out / "summary.json", lambda tmp: tmp.write_text(json.dumps(summary, indent=2)))
    return summary


def plot_result(result, out: Path) -> list[Path]:
    """Fig. 9-style flakes on the sheet (first and last snapshot) and Fig. 10-style A_p/A0."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Ellipse

    from .flake_body import rotation_matrices

    c = result.config
    keys = sorted(result.snapshots)
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.6), constrained_layout=True)
    for ax, k in zip(axes, (keys[0], keys[-1])):
        snap = result.snapshots[k]
        ext = np.array([0, c.size, 0, c.size]) * 1e6
        im = ax.imshow(np.asarray(snap["sheet"]).T * 1e6, origin="lower", extent=ext, cmap="gray")
        blocked = snap.get("blocked", np.zeros(len(snap["pos"]), dtype=bool))
        for p, R, b in zip(snap["pos"], rotation_matrices(snap["quat"]), blocked):
            ang = np.degrees(np.arctan2(R[0, 2], -R[1, 2]))  # major axis normal to the tilt
            minor = c.flake_diameter * abs(R[2, 2])  # projected width of a tilted flake
            ax.add_patch(Ellipse((p[0] * 1e6, p[1] * 1e6), c.flake_diameter * 1e6,
                                 max(minor, c.flake_thickness) * 1e6, angle=ang,
                                 fc="red" if b else "cyan", ec="k", lw=0.5))
        ax.set(title=f"slide {k * c.dx / c.size:.2f} L", xlabel="x [um]", ylabel="y [um]")
        fig.colorbar(im, ax=ax, label="sheet height [um]")
    p1 = out / "flakes.png"
    fig.savefig(p1, dpi=120)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(6, 3.5), constrained_layout=True)
    x = result.slide_distance / c.size
    ax.plot(x, 100 * result.particle_fraction, "o", ms=3, label="A_p/A0")
    ax.axhline(100 * np.mean(result.particle_fraction), ls="--", c="k", label="<A_p>/A0 (Eq. 22)")
    ax.set(xlabel="sliding distance / L", ylabel="A_p/A0 [%]",
           title=f"p = {c.pressure / 1e6:g} MPa, d_p = {c.flake_diameter * 1e6:g} um, "
                 f"{c.n_flakes} flakes, v0 = {c.v0:g} m/s")
    ax.legend()
    p2 = out / "particle_area.png"
    fig.savefig(p2, dpi=120)
    plt.close(fig)
    return [p1, p2]


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``tribocosim meso slide``."""
    ap = argparse.ArgumentParser(prog="tribocosim meso slide",
                                 description="one BEM-DEM sliding run over 2L (paper Fig. 7)")
    ap.add_argument("--config", required=True, help="TOML file with SlideConfig keys (SI units)")
    ap.add_argument("--out", required=True, help="output directory")
    ap.add_argument("--plot", action="store_true", help="also write Fig. 9/10-style PNGs")
    ap.add_argument("--quiet", action="store_true", help="no progress lines")
    ap.add_argument("--max-memory", default=None, metavar="SIZE",
                    help="refuse when the estimated peak memory exceeds SIZE (e.g. 8G, 512M; powers of 1024) instead "
                         "of the memory available (MemAvailable)")
    args = ap.parse_args(argv)

    from . import memory
    from .slide_config import SlideConfig

    def progress(k, rec):
        if not args.quiet and (k % 16 == 0 or k == cfg.steps):
            print(f"step {k}/{cfg.steps}: A_c/A0 = {rec['contact_fraction']:.4f}, "
                  f"A_p/A0 = {rec['particle_fraction']:.5f}, blocked = {rec['n_blocked']}",
                  flush=True)

    out = Path(args.out)
    try:
        if out.exists() and not out.is_dir():
            raise ParameterError(f"--out {args.out} is a file; allowed: a folder (made if missing)")
        cfg = SlideConfig.from_toml(args.config)
        limit = None if args.max_memory is None else memory.parse_bytes(args.max_memory)
        memory.check(slide_need(cfg, args.config), limit, "a smaller n, or fewer snapshots")
    except MemoryLimitError as exc:
        print(f"tribocosim meso slide: error: {exc}", file=sys.stderr)
        return 2
    except TribocosimError as exc:
        print(f"tribocosim meso slide: error: {exc}", file=sys.stderr)
        return 2
    from .coupling import run_slide

    try:
        result = run_slide(cfg, progress=progress)
    except TribocosimError as exc:
        print(f"tribocosim meso slide: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"tribocosim meso slide: interrupted by SIGINT: the slide is discarded, nothing is written into "
              f"{args.out}", file=sys.stderr)
        return 130
    try:
        summary = write_result(result, out)
        if args.plot:
            plot_result(result, out)
    except OSError as exc:
        print(f"tribocosim meso slide: error: cannot write the results into {args.out}: {exc.strerror or exc}",
              file=sys.stderr)
        return 2
    print(json.dumps(summary, indent=2))
    return 0


def slide_need(cfg, source: str):
    """What the slide of ``cfg`` (read from ``source``) will allocate (:func:`tribocosim.surrogate.memory.
    slide_bytes`), with its measured files' points."""
    from . import memory
    from .measured_surfaces import scan_points

    points = {side: scan_points(getattr(cfg, f"{side}_file")) for side in ("sheet", "tool")
              if getattr(cfg, f"{side}_file") is not None}
    how = (f"{memory.grids(cfg.n, memory.SLIDE_GRIDS)} in a sliding step, and the slide's compiled code"
           + (f"; measured scans of {', '.join(str(v) for v in points.values())} points" if points else ""))
    return memory.Need(f"n = {cfg.n} ({source})", memory.slide_bytes(cfg, points), how)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
