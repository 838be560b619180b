"""The alpha(v) study of issue 17, item 3 (docs/physics/alpha_velocity.md).

alpha is Eq. 23 read per slide: alpha = <A_p>/A0 / (beta P / E*), with <A_p>/A0 the mean over the
2L of sliding (Eq. 22). For each damping setting the same grid of slides is run:

- velocity v0 = 1, 2, 5, 10, 20, 50 m/s (the paper's Fig. 15 range);
- 2 surface pairs x 3 flake placements = 6 members per point (mean and standard deviation, ddof 1);
- roll-off surfaces with the measured statistics (paper Sec. 2.4; docs/physics/surfaces.md): sheet
  1.40 um / slope 0.34, tool 0.60 um / slope 0.34, H = 0.8, shortest wavelength 5 um and 6.25 um,
  the roll-off wavelengths solved by ``surfaces.rolloff_wavelength`` for this grid;
- a reduced domain: 128 x 128 pixels of 1 um (L = 128 um; the paper's is 500 um), 7 flakes of
  12 um x 0.5 um (beta = 0.048), P = 10 MPa, one flake contact law (penalty_velocity 50 m/s).

Settings (``SETTINGS``): the oil's viscosity eta (Stokes drag of a thin disc,
``DampingRates.from_viscosity``) from 0 (no damping: the low-damping limit) over the mineral-oil range,
to 100 x VG 32 (2.8 Pa s: the drag of a flake in a film ~1 um thin is ~3.5-60 x the unbounded
Stokes drag, surrogate.dem docstring), and the one-rate gamma = 5e7 1/s of the tables built before
issue 17 for reference. Every run records A_p of every
load-bearing flake (the paper's cluster rule with our pinch/hold rules) and A_p of the flakes the
cluster rule alone blocks (item 3 b).

The slides run as campaigns (``surrogate.campaign``: each finished case is written at once, a rerun
resumes), one folder per setting under ``--out``::

    python benchmarks/alpha_velocity.py run --out /tmp/alpha_v [--workers 2] [--settings oil_0028 ...]
    python benchmarks/alpha_velocity.py report --out /tmp/alpha_v [--figures docs/images]

``report`` prints the Markdown tables of the document and writes its figures.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

VELOCITIES = (1.0, 2.0, 5.0, 10.0, 20.0, 50.0)
SEEDS = (11, 12, 13)
#: (sheet seed, tool seed, shortest wavelength [m]) of the two surface pairs
SURFACE_PAIRS = ((1, 2, 5e-6), (3, 4, 6.25e-6))
N, SIZE, PRESSURE, N_FLAKES = 128, 128e-6, 10e6, 7
SHEET, TOOL, SLOPE, HURST = (1.40e-6, 0.60e-6, 0.34, 0.8)
#: name -> (label, SlideConfig damping keys)
SETTINGS = {
    "oil_0": ("eta = 0 (no damping)", {"oil_viscosity": 0.0}),
    "oil_00028": ("eta = 0.0028 Pa s", {"oil_viscosity": 0.0028}),
    "oil_0028": ("eta = 0.028 Pa s (ISO VG 32, 40 C)", {"oil_viscosity": 0.028}),
    "oil_028": ("eta = 0.28 Pa s", {"oil_viscosity": 0.28}),
    "oil_28": ("eta = 2.8 Pa s (thin-film bound)", {"oil_viscosity": 2.8}),
    "gamma_5e7": ("gamma = 5e7 1/s (old default)", {"damping_rate": 5e7}),
}


def base_configs() -> list[dict]:
    """The SlideConfig keys of each surface pair (roll-off wavelengths solved for this grid)."""
    from tribocosim.surrogate.surfaces import rolloff_wavelength

    pairs = []
    for sheet_seed, tool_seed, shortest in SURFACE_PAIRS:
        ratio = shortest / SIZE
        pairs.append({
            "n": N, "size": SIZE, "pressure": PRESSURE, "n_flakes": N_FLAKES, "hurst": HURST,
            "wavelength_ratio": ratio, "sheet_rms_height": SHEET, "tool_rms_height": TOOL,
            "sheet_rolloff_wavelength": rolloff_wavelength(SHEET, SLOPE, HURST, SIZE, N, ratio),
            "tool_rolloff_wavelength": rolloff_wavelength(TOOL, SLOPE, HURST, SIZE, N, ratio),
            "sheet_seed": sheet_seed, "tool_seed": tool_seed,
            "penalty_velocity": 50.0, "dt_safety": 0.25,
        })
    return pairs


def cases(setting: str) -> list:
    """The campaign cases of one setting, labelled by velocity, surface pair and seed."""
    from tribocosim.surrogate.campaign import Case
    from tribocosim.surrogate.slide_config import SlideConfig

    damping = SETTINGS[setting][1]
    out = []
    for s_idx, pair in enumerate(base_configs()):
        for v in VELOCITIES:
            for seed in SEEDS:
                cfg = SlideConfig(**{**pair, **damping, "v0": v, "flake_seed": seed})
                out.append(Case(cfg, {"velocity": v, "seed": seed, "surface": s_idx,
                                      "beta": cfg.beta, "pressure": PRESSURE}))
    return out


def run(args) -> None:
    from tribocosim.surrogate.campaign import run_campaign
    from tribocosim.surrogate.executors import make_executor

    executor = make_executor(args.workers)
    try:
        for name in args.settings:
            print(f"[{name}] {SETTINGS[name][0]}", flush=True)
            report = run_campaign(cases(name), Path(args.out) / name, executor, progress=False)
            print(f"  {report.summary()}", flush=True)
    finally:
        executor.close()


def member_alphas(records: list[dict]) -> dict:
    """velocity -> {"all": [...], "clusters": [...], "wall": [...]}: alpha of every finished member."""
    table: dict = {}
    for r in records:
        s = r["summary"]
        x = s["beta"] * r["labels"]["pressure"] / r["config"]["e_star"]
        row = table.setdefault(r["labels"]["velocity"], {"all": [], "clusters": [], "wall": []})
        row["all"].append(s["mean_particle_fraction"] / x)
        row["clusters"].append(s["mean_particle_fraction_clusters"] / x)
        row["wall"].append(r.get("wall_s", math.nan))
    return table


def _mean_std(values) -> tuple[float, float]:
    a = np.asarray(values, dtype=float)
    return float(a.mean()), (float(a.std(ddof=1)) if a.size > 1 else math.nan)


def report(args) -> None:
    from tribocosim.surrogate.campaign import load_records

    results = {}
    for name in SETTINGS:
        folder = Path(args.out) / name
        if not (folder / "campaign.json").exists():
            continue
        _, done, failed = load_records(folder)
        results[name] = (member_alphas(done), [f for f in failed if f.get("status") != "missing"])
    if not results:
        sys.exit(f"no campaign under {args.out}; run first")
    print("| setting | " + " | ".join(f"{v:g} m/s" for v in VELOCITIES) + " | failed |")
    print("|---|" + "---|" * (len(VELOCITIES) + 1))
    for key, what in (("all", "A_p of every load-bearing flake"), ("clusters", "cluster rule alone")):
        for name, (table, failed) in results.items():
            cells = []
            for v in VELOCITIES:
                vals = table.get(v, {}).get(key, [])
                if not vals:
                    cells.append("-")
                    continue
                m, sd = _mean_std(vals)
                cells.append(f"{m:.3g} +- {sd:.2g} ({len(vals)})")
            print(f"| {SETTINGS[name][0]}, {what} | " + " | ".join(cells) + f" | {len(failed)} |")
    print()
    print("| setting | " + " | ".join(f"{v:g} m/s" for v in VELOCITIES) + " |")
    print("|---|" + "---|" * len(VELOCITIES))
    for name, (table, _) in results.items():
        cells = [f"{np.mean(table[v]['wall']):.1f}" if v in table else "-" for v in VELOCITIES]
        print(f"| {SETTINGS[name][0]}: mean wall time per case [s] | " + " | ".join(cells) + " |")
    print()
    print("| setting | gamma_plane [1/s] | Lambda at 1 m/s | Lambda at 50 m/s |")
    print("|---|---|---|---|")
    for name in results:
        lam1 = damping_per_pixel(name, 1.0)
        print(f"| {SETTINGS[name][0]} | {lam1 / base_configs()[0]['size'] * N:.3g} | {lam1:.3g} | "
              f"{damping_per_pixel(name, 50.0):.3g} |")
    for name, (_, failed) in results.items():
        for f in failed:
            err = f.get("error", {})
            print(f"failed [{name}] {f.get('labels')}: {err.get('type')}: {err.get('message', '')[:160]}")
    if args.figures:
        _figures(results, Path(args.figures))


def _figures(results: dict, folder: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=False)
    for ax, key, title in ((axes[0], "all", "A_p of every load-bearing flake"),
                           (axes[1], "clusters", "the paper's cluster rule alone")):
        for name, (table, _) in results.items():
            vs = [v for v in VELOCITIES if v in table]
            ms = [_mean_std(table[v][key]) for v in vs]
            ax.errorbar(vs, [m for m, _ in ms], yerr=[s for _, s in ms], marker="o", capsize=3,
                        label=SETTINGS[name][0])
        ax.set_xscale("log")
        ax.set_xlabel("sliding velocity v0 [m/s]")
        ax.set_ylabel("alpha (Eq. 23)")
        ax.set_title(title)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle("alpha(v): roll-off surfaces, 128 um, 7 flakes, 10 MPa; mean +- std of 6 members")
    fig.tight_layout()
    path = folder / "alpha_velocity.png"
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for name, (table, _) in results.items():
        vs = [v for v in VELOCITIES if v in table]
        if not vs or damping_per_pixel(name, 1.0) == 0.0:
            continue
        ms = [_mean_std(table[v]["all"]) for v in vs]
        ax.errorbar([damping_per_pixel(name, v) for v in vs], [m for m, _ in ms],
                    yerr=[s for _, s in ms], marker="o", capsize=3, label=SETTINGS[name][0])
    ax.set_xscale("log")
    ax.set_xlabel("damping per pixel of sliding  Lambda = gamma_plane dx / v0")
    ax.set_ylabel("alpha (Eq. 23), every load-bearing flake")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    path = folder / "alpha_damping_per_pixel.png"
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def damping_per_pixel(setting: str, v0: float) -> float:
    """Lambda = gamma_plane dx / v0: the in-plane damping rate times the time to slide one pixel (how
    much of a flake's in-plane velocity the oil takes away while the tool advances one pixel)."""
    from tribocosim.surrogate.dem import DampingRates, FlakeShape
    from tribocosim.surrogate.slide_config import SlideConfig

    cfg = SlideConfig(**{**base_configs()[0], **SETTINGS[setting][1], "v0": v0})
    damping = cfg.damping(FlakeShape(cfg.flake_diameter, cfg.flake_thickness, cfg.flake_density))
    rate = damping.velocity_plane if isinstance(damping, DampingRates) else float(damping)
    return rate * cfg.dx / v0


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--out", required=True)
    r.add_argument("--workers", type=int, default=2)
    r.add_argument("--settings", nargs="+", default=list(SETTINGS), choices=list(SETTINGS))
    p = sub.add_parser("report")
    p.add_argument("--out", required=True)
    p.add_argument("--figures", default=None)
    args = ap.parse_args(argv)
    (run if args.cmd == "run" else report)(args)


if __name__ == "__main__":
    main()
