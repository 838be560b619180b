"""Where a slide's time goes: a light and a heavy case of the shipped table's preset, profiled.

For each debris level of ``--betas`` (default 0.0207 and 0.75: 12 and 435 flakes of 12 um on the quick preset's
256 um domain) the quick preset's case at ``--pressure`` (default 30 MPa), 0.08 m/s, surface pair 0, placement
11 slides ``--steps`` pixels (default 32; 0: the whole 2L) and prints

- per slide: the set-up (surfaces, first contact solve, placement) and per pixel the flake phase (DEM or
  overdamped relaxation), the contact solve (BEM: its iterations and FFT pairs per pixel) and the
  classification (footprints, blocking rules, the modified tool, A_p);
- per flake-phase step, measured on the state the slide ends in: for the inertial DEM the cost of one substep
  (``dem.advance`` over ``--substeps`` steps), of its force evaluation with the flake-flake pairs and without
  them (so the faces, the pairs and the integration apart); for the overdamped solver its work per pixel
  (substeps, iterations, face parts and pair parts read, component solves) and the cost of one face read and
  one pair read;
- the load average before and after.

``--solver`` chooses the flake solver (``inertial`` or ``overdamped``; a checkout without the overdamped solver
runs the inertial one only). The script reads only public functions and the kernels' documented arguments, so
the same file profiles an older checkout: ``PYTHONPATH=<that tree> python benchmarks/profile_slide.py``, or an
interpreter with that version installed. Set ``TRIBOCOSIM_FFTW_WISDOM`` to one file for both runs so that
both use the same FFT plans.

    python benchmarks/profile_slide.py [--betas 0.0207 0.75] [--steps 32] [--solver overdamped]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from dataclasses import replace

import numpy as np


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def _per_call(fn, min_time: float = 0.2) -> float:
    """Seconds per call of fn(), repeated for at least ``min_time`` seconds after one warm-up call."""
    fn()
    n, t0 = 0, time.perf_counter()
    while True:
        fn()
        n += 1
        el = time.perf_counter() - t0
        if el >= min_time:
            return el / n


def inertial_split(sim, substeps: int) -> dict:
    """Per DEM substep on the slide's current state: advance, forces with and without the pairs [us]."""
    from tribocosim.surrogate import dem
    from tribocosim.surrogate import dem_kernels as k

    st, prm = sim.state, sim.params
    sh = prm.shape
    nf = len(st.pos)

    def run_advance():
        s = st.copy()
        dem.advance(s, prm, sim.h_low, sim.h_tool0, substeps, shift0=sim.k * prm.dx,
                    dshift=prm.dx / sim.n_sub, top_offset=sim.z_top)

    pairs = np.empty((max(1, nf * (nf - 1) // 2), 2), dtype=np.int64)
    n_pairs = k._pair_candidates(st.pos, prm.size, (2.0 + k.PAIR_SKIN) * sh.a, pairs)
    zf = k._face_heights(prm.samples, sh.a, sh.c)
    out = [np.zeros((nf, 3)), np.zeros((nf, 3)), np.zeros(nf), np.empty((nf, 3, 3))]
    none = (np.empty((0, 2, k._RECORD)), np.empty((0, 2, len(prm.samples))), np.empty((0, 2, 3)),
            np.empty((0, 2, 1), dtype=np.int64), np.empty((nf, 2), dtype=np.int64), np.zeros((nf, 2)))

    def forces(np_):
        return lambda: k._forces(st.pos, st.quat, sim.h_low, sim.h_low, 0.0, 0.0, sim.h_tool0, sim.k * prm.dx,
                                 sim.z_top, prm.dx, prm.size, sh.a, sh.c, prm.samples, zf, prm.weights,
                                 prm.k_area, *out, *none, k.REACH_PX, pairs, np_, *prm.pair_points)

    step = _per_call(run_advance) / substeps
    full = _per_call(forces(n_pairs))
    faces = _per_call(forces(0))
    return {"substep_us": 1e6 * step, "forces_all_faces_us": 1e6 * faces,
            "forces_pairs_us": 1e6 * (full - faces), "integration_and_skips_us": 1e6 * (step - full),
            "pair_candidates": int(n_pairs),
            "note": "forces read every face here; inside advance, clearance records skip faces proven clear"}


def overdamped_split(sim) -> dict:
    """Cost of one face read and one pair read on the slide's current state [us]."""
    from tribocosim.surrogate import dem_kernels as dk
    from tribocosim.surrogate import relax_kernels as rk
    from tribocosim.surrogate import flake_relax as fr

    st, prm = sim.state, sim.params
    sh = prm.shape
    nf = len(st.pos)
    pairs = np.empty((max(1, nf * (nf - 1) // 2), 2), dtype=np.int64)
    n_pairs = dk._pair_candidates(st.pos, prm.size, (2.0 + dk.PAIR_SKIN) * sh.a, pairs)
    zf = dk._face_heights(prm.samples, sh.a, sh.c)
    rot, fp, fh, rec = np.empty((nf, 3, 3)), np.zeros((nf, 8)), np.zeros((nf, 1, 6, 6)), np.zeros((nf, rk._REC))
    pp, ph = np.zeros((max(1, n_pairs), 14)), np.zeros((max(1, n_pairs), 3, 6, 6))
    half = int(math.ceil(sh.a / prm.dx)) + 2 + dk.REACH_PX
    dh = np.zeros_like(sim.h_low)

    ns = prm.samples.shape[0]
    gaps, near = np.zeros((nf, 2, ns)), np.zeros((nf, 2, ns + 1), dtype=np.int64)
    bounds = rk.new_bounds(sim.h_low.shape)
    cap, tol = fr.NEAR_FRACTION * sh.thickness, fr.TOL_MOVE_FRACTION * sh.thickness

    def read_all():
        for i in range(nf):
            rk._read_faces(i, st.pos, st.quat, rot, sim.h_low, dh, 0.0, sim.h_tool0, sim.k * prm.dx, sim.z_top,
                           prm.dx, sh.a, prm.samples, zf, prm.weights, prm.k_area, half, cap, tol, fp, fh, rec,
                           gaps, near, bounds)

    def faces():  # full readings: every face point of every flake, the surfaces' bounds computed again
        rec[:] = 0.0
        bounds[:] = -1.0
        read_all()

    def faces_near():  # the readings while nothing has moved: the points within reach of contact only
        read_all()

    moved = np.zeros(nf)
    point_gaps = np.zeros((max(1, n_pairs), 2, len(prm.pair_points[0])))
    point_ref = np.full((max(1, n_pairs), 2), -1.0)

    def read_pairs():
        for m in range(n_pairs):
            rk._read_pair(m, pairs, st.pos, st.quat, rot, prm.size, sh.a, sh.c, *prm.pair_points, prm.k_area,
                          pp, ph, moved, point_gaps, point_ref, cap, tol)

    def pairs_full():  # full readings: every point of both discs
        point_ref[:] = -1.0
        read_pairs()

    def pairs_near():  # the readings while nothing has moved: the points within reach of contact only
        read_pairs()

    faces()
    pairs_full()
    return {"face_read_us": 1e6 * _per_call(faces) / max(nf, 1),
            "face_near_read_us": 1e6 * _per_call(faces_near) / max(nf, 1),
            "pair_read_us": 1e6 * _per_call(pairs_full) / max(n_pairs, 1),
            "pair_near_read_us": 1e6 * _per_call(pairs_near) / max(n_pairs, 1), "pair_candidates": int(n_pairs)}


def profile_case(beta: float, pressure: float, steps: int, solver: str, substeps: int) -> dict:
    from tribocosim.surrogate.campaign import make_case
    from tribocosim.surrogate.coupling import SlideSimulation
    from tribocosim.surrogate.sweep import load_preset

    sweep = load_preset("quick")
    size = sweep.base_config().size
    count = round(beta * size**2 / (math.pi * 36e-12))
    cfg = make_case(sweep, 0, pressure, 0.08, count, 12e-6, 11).config
    over = {"n_slide_steps": steps} if steps else {}
    if solver != "inertial":
        over["flake_solver"] = solver
    cfg = replace(cfg, **over)
    load0 = _load()
    t0 = time.perf_counter()
    sim = SlideSimulation(cfg)
    setup = time.perf_counter() - t0
    base = dict(sim.timings)
    iters, ffts = [], []
    for _ in range(cfg.steps):
        sim.step()
        iters.append(sim.last_result.iterations)
        ffts.append(sim.last_result.fft_pairs)
    wall = time.perf_counter() - t0
    px = cfg.steps
    row = {"beta": cfg.beta, "flakes": count, "pressure": pressure, "solver": solver, "pixels": px,
           "setup_s": setup, "wall_s": wall,
           "per_pixel_s": {k: (sim.timings[k] - base.get(k, 0.0)) / px for k in ("dem", "bem", "classify")},
           "bem_iterations_per_solve": float(np.mean(iters)), "fft_pairs_per_solve": float(np.mean(ffts)),
           "contact_resolves": sim.resolves, "load_before": load0}
    if solver == "inertial":
        row["dem_substeps_per_pixel"] = sim.n_sub
        row["per_substep"] = inertial_split(sim, substeps)
    else:
        row["relax_per_pixel"] = {k: v / px for k, v in sim.relax_stats.as_dict().items()
                                  if k not in ("largest_group",)}
        row["relax_largest_group"] = sim.relax_stats.largest_group
        row["per_read"] = overdamped_split(sim)
    row["load_after"] = _load()
    return row


def show(r: dict) -> None:
    pp = r["per_pixel_s"]
    print(f"beta {r['beta']:.4g} ({r['flakes']} flakes), {r['pressure'] / 1e6:g} MPa, {r['solver']}, {r['pixels']} "
          f"pixels: set-up {r['setup_s']:.2f} s, wall {r['wall_s']:.1f} s; per pixel: flakes {pp['dem']:.4f} s, "
          f"BEM {pp['bem']:.4f} s ({r['bem_iterations_per_solve']:.1f} iterations, "
          f"{r['fft_pairs_per_solve']:.1f} FFT pairs a solve; {r['contact_resolves']} solves repeated), "
          f"classification {pp['classify']:.4f} s  (load {r['load_before']} -> {r['load_after']})")
    if "per_substep" in r:
        s = r["per_substep"]
        print(f"  DEM: {r['dem_substeps_per_pixel']} substeps a pixel; a substep {s['substep_us']:.1f} us; a force "
              f"evaluation reading every face {s['forces_all_faces_us']:.1f} us + pairs {s['forces_pairs_us']:.1f} us "
              f"({s['pair_candidates']} candidate pairs); integration and the skipped faces' bookkeeping "
              f"{s['integration_and_skips_us']:.1f} us")
    else:
        w, c = r["relax_per_pixel"], r["per_read"]
        print(f"  overdamped, per pixel: {w['substeps']:.1f} substeps, {w['iterations']:.1f} iterations, "
              f"{w['face_reads']:.0f} full face reads x {c['face_read_us']:.1f} us, {w['face_partial_reads']:.0f} "
              f"partial x {c['face_near_read_us']:.1f} us, {w['pair_reads']:.0f} pair reads x "
              f"{c['pair_read_us']:.2f} us full, {c['pair_near_read_us']:.2f} us near, {w['solves']:.0f} component "
              f"solves (largest "
              f"{r['relax_largest_group']} flakes), {w['rejected']:.1f} steps rejected")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--betas", type=float, nargs="+", default=[0.0207, 0.75])
    ap.add_argument("--pressure", type=float, default=30e6)
    ap.add_argument("--steps", type=int, default=32, help="pixels to slide (0: the whole 2L)")
    ap.add_argument("--solver", default="inertial", choices=("inertial", "overdamped"))
    ap.add_argument("--substeps", type=int, default=200, help="DEM substeps timed on the final state")
    ap.add_argument("--out", default=None)
    args = ap.parse_args(argv)
    from tribocosim.surrogate import coupling

    print(f"code under test: {os.path.dirname(coupling.__file__)}", flush=True)
    rows = []
    for beta in args.betas:
        r = profile_case(beta, args.pressure, args.steps, args.solver, args.substeps)
        show(r)
        rows.append(r)
    out = args.out or f"profile_slide_{args.solver}.json"
    with open(out, "w") as fh:
        json.dump({"rows": rows, "code": os.path.dirname(coupling.__file__)}, fh, indent=1)
    print(f"written {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
