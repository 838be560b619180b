"""The checks behind the shipped table's settings (docs/physics/table_domain.md).

The quick preset (surrogate/presets/quick.toml) slides at the strip-draw test's 0.08 m/s by running the DEM
at ``dem_velocity`` = 10 m/s with the damping per pixel of the physical speed, Lambda = gamma dx / v0, and
with two cheaper numerics (``dt_safety`` 0.5, flake-flake points 2 px apart). Each set below runs the
preset's own slide settings and surfaces with one thing changed, as a resumable campaign
(``surrogate.campaign``: each finished slide is written at once, a rerun resumes), each slide over
``STEPS`` = 128 pixels (half the domain; the comparisons are member by member over the same slide):

``similarity``
    10 MPa, beta = 0.1: direct runs at v0 = 0.5 m/s (4 members) and 0.08 m/s (2 members) (the DEM at v0 with the
    oil's damping) against the same members run through the similarity (the DEM at 10 m/s, damping x 10 / v0).
``numerics``
    30 MPa, beta = 0.5 (a deposit with stacks), v0 = 0.08 m/s: dt_safety 0.25 with flake-flake points
    1 px apart against the preset's 0.5 and 2 px.
``plateau``
    10 MPa, beta = 0.1 and 30 MPa, beta = 0.3: v0 = 0.02, 0.08, 0.5 and 2 m/s with the preset's settings: where
    the damping per pixel Lambda is large, A_p should not depend on v0.

Members: 2 surface pairs x the seeds of the set (two placements). ``report`` prints, per set and point, <A_p>/A0, <A_c>/A0
and alpha = <A_p>/A0 / (beta P / E*) as member mean +- standard error, the paired differences, and the
cost (wall seconds of the slides)::

    python benchmarks/table_domain.py run --out /tmp/table_domain [--sets similarity numerics plateau] [--workers 1]
    python benchmarks/table_domain.py report --out /tmp/table_domain
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

E_STAR = 55e9


def _preset():
    from tribocosim.surrogate.sweep import load_preset

    return load_preset("quick")


#: pixels slid by the checks' slides: half the domain (the comparisons are paired, member by member, over the
#: same slide; the table's slides go 2L = 512 pixels)
STEPS = 128


def _case(sweep, surface: int, pressure: float, v0: float, n_flakes: int, seed: int, label: str, **over):
    from tribocosim.surrogate.campaign import Case
    from tribocosim.surrogate.slide_config import SlideConfig

    cfg = SlideConfig(**{**sweep.slide, **sweep.surfaces[surface], "pressure": pressure, "v0": v0,
                         "n_flakes": n_flakes, "flake_seed": seed, "n_slide_steps": STEPS, **over})
    return Case(cfg, {"setting": label, "pressure": pressure, "velocity": v0, "beta": cfg.beta,
                      "n_flakes": n_flakes, "seed": seed, "surface": surface})


def cases(name: str) -> list:
    """The cases of one set (module docstring)."""
    sweep = _preset()
    surfaces = range(len(sweep.surfaces))
    out = []
    if name == "similarity":
        for s in surfaces:
            for seed in (11, 12):
                for v0 in (0.5, 0.08) if seed == 11 else (0.5,):  # a direct slide at 0.08 m/s costs ~6 at 0.5
                    out.append(_case(sweep, s, 10e6, v0, 58, seed, "direct", dem_velocity=None))
                    out.append(_case(sweep, s, 10e6, v0, 58, seed, "similarity"))
    elif name == "numerics":
        for s in surfaces:
            out.append(_case(sweep, s, 30e6, 0.08, 290, 11, "fine", dt_safety=0.25, pair_spacing_px=None))
            out.append(_case(sweep, s, 30e6, 0.08, 290, 11, "preset"))
    elif name == "plateau":
        for s in surfaces:
            for seed in (11, 12):
                for pressure, count in ((10e6, 58), (30e6, 174)):
                    for v0 in (0.02, 0.08, 0.5, 2.0):
                        out.append(_case(sweep, s, pressure, v0, count, seed, "preset"))
    else:
        raise SystemExit(f"unknown set {name!r}; known: similarity, numerics, plateau")
    return out


SETS = ("numerics", "plateau", "similarity")


def run(args) -> None:
    from tribocosim.surrogate.campaign import run_campaign
    from tribocosim.surrogate.executors import make_executor

    executor = make_executor(args.workers)
    try:
        for name in args.sets:
            report = run_campaign(cases(name), Path(args.out) / name, executor, progress=False)
            print(f"[{name}] {report.summary()}", flush=True)
    finally:
        executor.close()


def _stats(values) -> tuple[float, float, int]:
    a = np.asarray(values, dtype=float)
    se = float(a.std(ddof=1) / math.sqrt(a.size)) if a.size > 1 else math.nan
    return float(a.mean()), se, int(a.size)


def report(args) -> None:
    from tribocosim.surrogate.campaign import load_records

    for name in args.sets:
        folder = Path(args.out) / name
        if not (folder / "campaign.json").exists():
            continue
        _, done, failed = load_records(folder)
        print(f"\n## {name}: {len(done)} slides finished, {len(failed)} failed or missing\n")
        groups: dict = {}
        for r in done:
            lab = r["labels"]
            key = (lab["pressure"], lab["beta"], lab["velocity"], lab["setting"])
            groups.setdefault(key, []).append(r)
        print("| P [MPa] | beta | v0 [m/s] | setting | <A_p>/A0 | <A_c>/A0 | alpha | members | wall s / slide |")
        print("|---|---|---|---|---|---|---|---|---|")
        for (p, beta, v0, setting), recs in sorted(groups.items()):
            ap = _stats([r["summary"]["mean_particle_fraction"] for r in recs])
            ac = _stats([r["summary"]["mean_contact_fraction"] for r in recs])
            x = beta * p / E_STAR
            wall = np.mean([r["wall_s"] for r in recs])
            print(f"| {p / 1e6:g} | {beta:.3f} | {v0:g} | {setting} | {ap[0]:.4g} +- {ap[1]:.2g} | "
                  f"{ac[0]:.4g} +- {ac[1]:.2g} | {ap[0] / x:.0f} +- {ap[1] / x:.0f} | {ap[2]} | {wall:.0f} |")
        _paired(groups)
        for f in failed:
            err = f.get("error", {}).get("message", f.get("status"))
            print(f"- failed: {f.get('labels')}: {err}")


def _paired(groups: dict) -> None:
    """Member-by-member ratios of A_p between the two settings of a point (same surfaces and seeds)."""
    points: dict = {}
    for (p, beta, v0, setting), recs in groups.items():
        points.setdefault((p, beta, v0), {})[setting] = {
            (r["labels"]["surface"], r["labels"]["seed"]): r["summary"]["mean_particle_fraction"] for r in recs}
    lines = []
    for key, by in sorted(points.items()):
        if len(by) != 2:
            continue
        (na, a), (nb, b) = sorted(by.items())
        common = sorted(set(a) & set(b))
        if len(common) < 2:
            continue
        ratio = _stats([b[m] / a[m] for m in common if a[m] > 0])
        lines.append(f"- P = {key[0] / 1e6:g} MPa, beta = {key[1]:.3f}, v0 = {key[2]:g} m/s: A_p({nb}) / "
                     f"A_p({na}) = {ratio[0]:.3f} +- {ratio[1]:.3f} (paired, {ratio[2]} members)")
    if lines:
        print("\n" + "\n".join(lines))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    for cmd in ("run", "report"):
        p = sub.add_parser(cmd)
        p.add_argument("--out", required=True, type=Path)
        p.add_argument("--sets", nargs="+", default=list(SETS), choices=SETS)
        if cmd == "run":
            p.add_argument("--workers", type=int, default=1)
    args = ap.parse_args(argv)
    (run if args.cmd == "run" else report)(args)


if __name__ == "__main__":
    main()
