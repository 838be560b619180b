"""Benchmark: the bar mesh of the default 140 mm draw against a fine reference (the default's evidence).

The demo draw (default parameters, shipped table, 10 MPa, 0.08 m/s after a 10 ms ramp, 1 ms steps) is run
with the Python model for several ``n_elements`` and compared with the finest mesh:

- error_mu_bar = |mu_bar - mu_bar_ref| / mu_bar_ref, mu_bar the mean of mu_mean over the last 20 % of the
  draw;
- error_beta_max = max |beta - beta_ref| / max beta_ref and error_beta_rms = ||beta - beta_ref||_2 /
  ||beta_ref||_2 of the final debris field, beta read at the reference's nodes by linear interpolation in the
  material coordinate.

It prints one row per mesh with the wall time of the Python model (the native step's cost per node is in
bench_fmu.py). Measured on the 2-core machine: 0.32-0.39 s per mesh, 0.44 s for the reference.

Usage: python benchmarks/bench_mesh.py [--meshes 1800 900 450 300 225 150 100]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from tribocosim.paths import DEFAULT_TABLE
from tribocosim.components.stripdraw.friction import make_friction_law
from tribocosim.components.stripdraw.model import StripDrawModel
from tribocosim.components.stripdraw.parameters import StripDrawParameters
from tribocosim.components.stripdraw.table import read_table

STEP = 1e-3  # s
N_STEPS = 1750  # 140 mm at 0.08 m/s
PRESSURE = 10e6  # Pa
RAMP = 0.01  # s


def draw(n_elements: int, table):
    """The demo draw on ``n_elements``: (mu_bar, node positions X, final beta, wall time)."""
    p = StripDrawParameters(n_elements=n_elements)
    model = StripDrawModel(p, make_friction_law(p, table))
    fn = PRESSURE * p.tool_length * p.tool_width
    mu = np.empty(N_STEPS)
    t0 = time.perf_counter()
    for k in range(N_STEPS):
        t_mid = (k + 0.5) * STEP
        out = model.step(STEP, {"normal_force": fn, "grip_velocity": 0.08 * min(1.0, t_mid / RAMP)})
        mu[k] = out["mu_mean"]
    wall = time.perf_counter() - t0
    return float(mu[-N_STEPS // 5:].mean()), model.mesh.X.copy(), model.beta.copy(), wall


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", type=int, nargs="+", default=[1800, 900, 450, 300, 225, 150, 100])
    args = ap.parse_args(argv)
    table = read_table(DEFAULT_TABLE)
    meshes = sorted(args.meshes, reverse=True)
    draw(meshes[-1], table)  # warm up (the core library)
    ref_mu, ref_X, ref_beta, ref_wall = draw(meshes[0], table)
    print(f"reference n_elements = {meshes[0]}: mu_bar = {ref_mu:.6f}, max beta = {ref_beta.max():.5f}, "
          f"{ref_wall:.2f} s")
    print(f"{'n_elements':>10} {'mu_bar':>9} {'error_mu_bar':>12} {'error_beta_max':>14} {'error_beta_rms':>14} "
          f"{'wall [s]':>8}")
    for n in meshes[1:]:
        mu, X, beta, wall = draw(n, table)
        diff = np.interp(ref_X, X, beta) - ref_beta
        e_max = np.abs(diff).max() / ref_beta.max()
        e_rms = np.sqrt(np.mean(diff ** 2)) / np.sqrt(np.mean(ref_beta ** 2))
        print(f"{n:>10d} {mu:>9.6f} {abs(mu - ref_mu) / ref_mu:>12.2e} {e_max:>14.3f} {e_rms:>14.4f} {wall:>8.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
