"""Generated surface statistics next to the measured targets (docs/physics/surfaces.md).

For every surface pair of the given presets (default: ``rolloff`` and, for contrast, ``paper``, whose
surfaces are pure power laws from the domain size) the sheet and the tool are generated as the slide
generates them (surrogate.coupling), for the pair's own seeds and ``--seeds - 1`` more, and their
statistics (surrogate.surfaces.surface_statistics) are printed as a Markdown table: RMS height, RMS
slope from the PSD and from finite differences on the grid, and the density of 8-neighbour summits
(mean and standard deviation over the seeds). RMS height and slopes do not depend on the seed (the
generator's amplitudes are deterministic); the largest relative spread over the seeds is printed too.
Targets: paper Sec. 2.4 (sheet 1.40 um and 0.34; tool 0.60 um, slope not given, 0.34 assumed).

Usage::

    python benchmarks/surface_statistics.py [--presets rolloff paper] [--seeds 5]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys

import numpy as np

TARGETS = {"sheet": (1.40e-6, 0.34), "tool": (0.60e-6, 0.34)}


def pair_rows(preset: str, index: int, pair: dict, slide: dict, n_seeds: int) -> list[dict]:
    """Statistics of the sheet and the tool of one surface pair over ``n_seeds`` seeds."""
    from tribocosim.surrogate.coupling import _generate_surfaces
    from tribocosim.surrogate.slide_config import SlideConfig
    from tribocosim.surrogate.surfaces import surface_statistics

    cfg = SlideConfig(**{**slide, **pair})
    stats = {"sheet": [], "tool": []}
    for k in range(n_seeds):
        c = dataclasses.replace(cfg, sheet_seed=cfg.sheet_seed + 1000 * k,
                                tool_seed=cfg.tool_seed + 1000 * k)
        sheet, tool = _generate_surfaces(c)
        stats["sheet"].append(surface_statistics(sheet, cfg.size))
        stats["tool"].append(surface_statistics(tool, cfg.size))
    rows = []
    for name, sts in stats.items():
        arr = np.array([[s.rms_height, s.rms_slope_psd, s.rms_slope_fd, s.summit_density] for s in sts])
        rolloff = getattr(cfg, f"{name}_rolloff_wavelength")
        rows.append({
            "surface": f"{preset} #{index + 1} {name}",
            "n": cfg.n, "dx": cfg.dx, "shortest": cfg.wavelength_ratio * cfg.size,
            "rolloff": cfg.size if rolloff is None else rolloff,
            "target_h": TARGETS[name][0], "target_s": TARGETS[name][1],
            "h": arr[0, 0], "s_psd": arr[0, 1], "s_fd": arr[0, 2],
            "summits": arr[:, 3].mean(), "summits_std": arr[:, 3].std(ddof=1) if n_seeds > 1 else 0.0,
            "spread": float(np.max(np.abs(arr[:, :3] / arr[0, :3] - 1.0))),
        })
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--presets", nargs="+", default=["rolloff", "paper"])
    ap.add_argument("--seeds", type=int, default=5, help="realisations per surface (>= 1)")
    args = ap.parse_args(argv)
    if args.seeds < 1:
        print("--seeds must be >= 1", file=sys.stderr)
        return 2
    from tribocosim.surrogate.sweep import load_preset

    rows = []
    for preset in args.presets:
        sweep = load_preset(preset)
        for i, pair in enumerate(sweep.surfaces):
            rows += pair_rows(preset, i, pair, sweep.slide, args.seeds)
    print(f"| surface | grid | shortest / roll-off wavelength [um] | h_rms [um] target / generated | "
          f"RMS slope target / PSD / FD | summits [1/mm^2], {args.seeds} seeds |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['surface']} | {r['n']}^2, dx {r['dx'] * 1e6:.3g} um | "
              f"{r['shortest'] * 1e6:.3g} ({r['shortest'] / r['dx']:.2f} px) / {r['rolloff'] * 1e6:.4g} | "
              f"{r['target_h'] * 1e6:.2f} / {r['h'] * 1e6:.4f} | "
              f"{r['target_s']:.2f} / {r['s_psd']:.4f} / {r['s_fd']:.4f} | "
              f"{r['summits'] * 1e-6:.0f} +- {r['summits_std'] * 1e-6:.0f} |")
    print(f"\nlargest relative spread of h_rms and the slopes over the seeds: "
          f"{max(r['spread'] for r in rows):.1e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
