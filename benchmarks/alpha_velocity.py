"""The alpha(v) study on the paper's terms (docs/physics/alpha_velocity.md).

alpha is Eq. 23 read per slide: alpha = <A_p>/A0 / (beta P / E*), with <A_p>/A0 the mean over the 2L of
sliding (Eq. 22), for two observables recorded on every slide: A_p of every load-bearing flake (ours: the
paper's cluster rule, the pinch and the hold rules of surrogate.coupling) and A_p of the flakes the paper's
cluster rule alone blocks (at least three overlap clusters with the tool, Fig. 8), the latter also at other
overlap thresholds (``CLUSTER_THRESHOLDS``, fractions of h_p; the rule itself reads 0).

Grid of every setting (``SETTINGS``):

- v0 = 1, 2, 5, 10, 20, 50 m/s (the paper's Fig. 15 range);
- 2 surface pairs x 5 placements = 10 members per point (mean, standard error);
- roll-off surfaces with the measured statistics (paper Sec. 2.4; docs/physics/surfaces.md), shortest
  wavelength 5 um and 6.25 um, the roll-off wavelengths solved for the grid;
- 128 x 128 um, 7 flakes of 12 um x 0.5 um (beta = 0.048), P = 10 MPa, dt_safety 0.25.

Settings: the oil's viscosity eta (Stokes drag of a thin disc, DampingRates.from_viscosity) at 0.028 Pa s
(ISO VG 32 at 40 C, the default), 0.0028 and 0.00028 Pa s (the damping per pixel of sliding Lambda from ~18
down to ~0.004: Lambda << 1 over the whole range), each with the penalty stiffness fixed by the Hertz rule at
50 m/s (``fixed``: one contact law for every speed) and with the paper's rule (``hertz_v0``: overlap 5 % of
h_p at the Hertz peak force of an impact at v0, so the stiffness scales with v0). ``refined`` settings repeat
the viscous ones with the fixed penalty on the grid of half the pixel size (256^2 on the same 128 um; 6
members): Lambda = gamma dx / v0 halves with the pixel, so the collapse of alpha on Lambda predicts
alpha(dx/2, v0) = alpha(dx, 2 v0).

The slides run as campaigns (surrogate.campaign: each finished case is written at once, a rerun resumes), one
folder per setting under ``--out``::

    python benchmarks/alpha_velocity.py run --out /tmp/alpha_v [--workers 2] [--settings oil_0028_fixed ...]
    python benchmarks/alpha_velocity.py report --out /tmp/alpha_v [--figures docs/images] [--json F]

``report`` prints the Markdown tables of the document (alpha per velocity as mean +- standard error, the
paired ratio alpha(50 m/s) / alpha(1 m/s) per member, the threshold sweep, the refinement) and writes the
figures; ``--json`` writes the per-velocity means for ``tribocosim report paper``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

VELOCITIES = (1.0, 2.0, 5.0, 10.0, 20.0, 50.0)
SEEDS = (11, 12, 13, 14, 15)
REFINED_SEEDS = (11, 12, 13)
#: (sheet seed, tool seed, shortest wavelength [m]) of the two surface pairs
SURFACE_PAIRS = ((1, 2, 5e-6), (3, 4, 6.25e-6))
SIZE, PRESSURE, N_FLAKES = 128e-6, 10e6, 7
SHEET, TOOL, SLOPE, HURST = (1.40e-6, 0.60e-6, 0.34, 0.8)
H_P = 0.5e-6
#: overlap thresholds of the cluster rule counted besides 0 (fractions of h_p)
CLUSTER_THRESHOLDS = (-0.05, 0.05, 0.1)
VISCOSITIES = {"oil_0028": (0.028, "eta = 0.028 Pa s (ISO VG 32, 40 C)"),
               "oil_00028": (0.0028, "eta = 0.0028 Pa s"),
               "oil_000028": (0.00028, "eta = 0.00028 Pa s")}
PENALTIES = {"fixed": "penalty at 50 m/s", "hertz_v0": "penalty at v0 (the paper's rule)"}
#: name -> (label, SlideConfig keys, grid points per side, seeds)
SETTINGS = {
    **{f"{o}_{p}": (f"{VISCOSITIES[o][1]}, {PENALTIES[p]}", {"oil_viscosity": VISCOSITIES[o][0], "penalty": p},
                    128, SEEDS)
       for o in VISCOSITIES for p in PENALTIES},
    **{f"{o}_refined": (f"{VISCOSITIES[o][1]}, penalty at 50 m/s, half the pixel",
                        {"oil_viscosity": VISCOSITIES[o][0], "penalty": "fixed"}, 256, REFINED_SEEDS)
       for o in ("oil_0028", "oil_00028")},
}


def base_configs(n: int = 128) -> list[dict]:
    """The SlideConfig keys of each surface pair on an n x n grid (roll-off wavelengths solved for it)."""
    from tribocosim.surrogate.surfaces import rolloff_wavelength

    pairs = []
    for sheet_seed, tool_seed, shortest in SURFACE_PAIRS:
        ratio = shortest / SIZE
        pairs.append({
            "n": n, "size": SIZE, "pressure": PRESSURE, "n_flakes": N_FLAKES, "hurst": HURST,
            "wavelength_ratio": ratio, "sheet_rms_height": SHEET, "tool_rms_height": TOOL,
            "sheet_rolloff_wavelength": rolloff_wavelength(SHEET, SLOPE, HURST, SIZE, n, ratio),
            "tool_rolloff_wavelength": rolloff_wavelength(TOOL, SLOPE, HURST, SIZE, n, ratio),
            "sheet_seed": sheet_seed, "tool_seed": tool_seed, "dt_safety": 0.25,
            "cluster_thresholds": tuple(f * H_P for f in CLUSTER_THRESHOLDS),
        })
    return pairs


def config(setting: str, surface: int, v0: float, seed: int):
    """The SlideConfig of one member of a setting at v0."""
    from tribocosim.surrogate.slide_config import SlideConfig

    _, keys, n, _ = SETTINGS[setting]
    keys = dict(keys)
    penalty = keys.pop("penalty")
    return SlideConfig(**{**base_configs(n)[surface], **keys, "v0": v0, "flake_seed": seed,
                          "penalty_velocity": 50.0 if penalty == "fixed" else v0})


def cases(setting: str) -> list:
    """The campaign cases of one setting, labelled by velocity, surface pair and seed."""
    from tribocosim.surrogate.campaign import Case

    out = []
    for s_idx in range(len(SURFACE_PAIRS)):
        for v in VELOCITIES:
            for seed in SETTINGS[setting][3]:
                cfg = config(setting, s_idx, v, seed)
                out.append(Case(cfg, {"velocity": v, "seed": seed, "surface": s_idx, "beta": cfg.beta,
                                      "pressure": PRESSURE}))
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
    """velocity -> {"all": {member: alpha}, "clusters": {...}, "t<k>": {...} per threshold, "wall": [...]}."""
    table: dict = {}
    for r in records:
        s, lab = r["summary"], r["labels"]
        x = s["beta"] * lab["pressure"] / r["config"]["e_star"]
        member = (lab["surface"], lab["seed"])
        row = table.setdefault(lab["velocity"], {"all": {}, "clusters": {}, "wall": []})
        row["all"][member] = s["mean_particle_fraction"] / x
        row["clusters"][member] = s["mean_particle_fraction_clusters"] / x
        for k, value in enumerate(s.get("mean_particle_fraction_cluster_thresholds", [])):
            row.setdefault(f"t{k}", {})[member] = value / x
        row["wall"].append(r.get("wall_s", math.nan))
    return table


def mean_se(values) -> tuple[float, float, int]:
    """Mean, standard error (std ddof 1 / sqrt n) and count."""
    a = np.asarray(list(values), dtype=float)
    if a.size == 0:
        return math.nan, math.nan, 0
    return float(a.mean()), (float(a.std(ddof=1) / math.sqrt(a.size)) if a.size > 1 else math.nan), int(a.size)


def paired_ratio(table: dict, key: str, hi: float = 50.0, lo: float = 1.0) -> tuple[float, float, int]:
    """alpha(hi) / alpha(lo) per member (same surfaces and placement), mean +- standard error."""
    a, b = table.get(hi, {}).get(key, {}), table.get(lo, {}).get(key, {})
    return mean_se(a[m] / b[m] for m in set(a) & set(b) if b[m] > 0)


def _cell(vals: dict) -> str:
    m, se, n = mean_se(vals.values())
    return "-" if n == 0 else f"{m:.3g} +- {se:.2g} ({n})"


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
    keys = [("all", "every load-bearing flake"), ("clusters", "cluster rule alone")]
    for key, what in keys:
        print(f"\nalpha of {what}, mean +- standard error (members):\n")
        print("| setting | " + " | ".join(f"{v:g} m/s" for v in VELOCITIES) + " | alpha(50)/alpha(1), paired | failed |")
        print("|---|" + "---|" * (len(VELOCITIES) + 2))
        for name, (table, failed) in results.items():
            cells = [_cell(table.get(v, {}).get(key, {})) for v in VELOCITIES]
            r = paired_ratio(table, key)
            ratio = "-" if r[2] == 0 else f"{r[0]:.3g} +- {r[1]:.2g} ({r[2]})"
            print(f"| {SETTINGS[name][0]} | " + " | ".join(cells) + f" | {ratio} | {len(failed)} |")
    print("\nthe cluster rule at other overlap thresholds (fractions of h_p), alpha at 1 and 50 m/s and the paired "
          "ratio:\n")
    print("| setting | threshold | 1 m/s | 50 m/s | alpha(50)/alpha(1) |")
    print("|---|---|---|---|---|")
    for name, (table, _) in results.items():
        for k, frac in [(None, 0.0)] + list(enumerate(CLUSTER_THRESHOLDS)):
            key = "clusters" if k is None else f"t{k}"
            r = paired_ratio(table, key)
            print(f"| {SETTINGS[name][0]} | {frac:+g} | {_cell(table.get(1.0, {}).get(key, {}))} | "
                  f"{_cell(table.get(50.0, {}).get(key, {}))} | "
                  + ("-" if r[2] == 0 else f"{r[0]:.3g} +- {r[1]:.2g}") + " |")
    print("\nmean wall time per slide [s]:\n")
    print("| setting | " + " | ".join(f"{v:g} m/s" for v in VELOCITIES) + " |")
    print("|---|" + "---|" * len(VELOCITIES))
    for name, (table, _) in results.items():
        cells = [f"{np.mean(table[v]['wall']):.1f}" if v in table else "-" for v in VELOCITIES]
        print(f"| {SETTINGS[name][0]} | " + " | ".join(cells) + " |")
    for name, (_, failed) in results.items():
        for f in failed:
            err = f.get("error", {})
            print(f"failed [{name}] {f.get('labels')}: {err.get('type')}: {err.get('message', '')[:160]}")
    if args.json:
        import time

        settings = {name: {"label": SETTINGS[name][0],
                           "lambda": {str(v): damping_per_pixel(name, v) for v in VELOCITIES},
                           **{key: {str(v): mean_se(table[v][key].values()) for v in VELOCITIES if v in table}
                              for key in ("all", "clusters")},
                           "ratio_50_1": {key: paired_ratio(table, key) for key in ("all", "clusters")}}
                    for name, (table, _) in results.items()}
        out = {"source": "python benchmarks/alpha_velocity.py run/report (docs/physics/alpha_velocity.md)",
               "created": time.strftime("%Y-%m-%d"), "velocities": list(VELOCITIES),
               "note": "alpha = <A_p>/A0 / (beta P / E*) per slide: mean, standard error and members per velocity, for "
                       "every load-bearing flake (all) and the paper's cluster rule alone (clusters); 128 um domain, "
                       "7 flakes of 12 um (beta 0.048), 10 MPa, 2 surface pairs",
               "settings": settings}
        Path(args.json).write_text(json.dumps(out, indent=1))
        print(f"wrote {args.json}")
    if args.figures:
        _figures(results, Path(args.figures))


def _figures(results: dict, folder: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, key, title in ((axes[0], "all", "A_p of every load-bearing flake"),
                           (axes[1], "clusters", "the paper's cluster rule alone")):
        for name, (table, _) in results.items():
            if name.endswith("_refined"):
                continue
            vs = [v for v in VELOCITIES if v in table]
            ms = [mean_se(table[v][key].values()) for v in vs]
            ax.errorbar(vs, [m for m, _, _ in ms], yerr=[2 * e for _, e, _ in ms], marker="o", capsize=3,
                        label=SETTINGS[name][0])
        ax.set_xscale("log")
        ax.set_xlabel("sliding velocity v0 [m/s]")
        ax.set_ylabel("alpha (Eq. 23)")
        ax.set_title(title)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle("alpha(v): roll-off surfaces, 128 um, 7 flakes, 10 MPa; mean +- 2 standard errors of 10 members")
    fig.tight_layout()
    path = folder / "alpha_velocity.png"
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for name, (table, _) in results.items():
        if name.endswith("_hertz_v0"):
            continue
        vs = [v for v in VELOCITIES if v in table]
        ms = [mean_se(table[v]["all"].values()) for v in vs]
        ax.errorbar([damping_per_pixel(name, v) for v in vs], [m for m, _, _ in ms], yerr=[2 * e for _, e, _ in ms],
                    marker="s" if name.endswith("_refined") else "o", capsize=3, label=SETTINGS[name][0])
    ax.set_xscale("log")
    ax.set_xlabel("damping per pixel of sliding  Lambda = gamma_plane dx / v0")
    ax.set_ylabel("alpha (Eq. 23), every load-bearing flake")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    path = folder / "alpha_damping_per_pixel.png"
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def damping_per_pixel(setting: str, v0: float) -> float:
    """Lambda = gamma_plane dx / v0: the in-plane damping rate times the time to slide one pixel (how much of a
    flake's in-plane velocity the oil takes away while the tool advances one pixel)."""
    from tribocosim.surrogate.dem import DampingRates, FlakeShape

    cfg = config(setting, 0, v0, SEEDS[0])
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
    p.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    (run if args.cmd == "run" else report)(args)


if __name__ == "__main__":
    main()
