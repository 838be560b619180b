"""Periodizing a non-periodic scan for the Fourier BEM: the contact area against a larger patch of the same
surface (docs/physics/measured_surfaces.md).

A large periodic roll-off surface (the quick preset's first sheet: RMS height 1.40 um, roll-off wavelength
49.19 um, shortest wavelength 5 um, H = 0.8, 1 um pixels) of ``--tiles`` x ``--tiles`` domains of 256 um is
the "larger patch": its BEM contact (rigid rough surface against the flat sheet, E* = 55 GPa, elastic, and
elastic-plastic with p_crit = 340 MPa as the slides) is exact, because it is periodic. It is cut into
``--tiles^2`` non-periodic scans of 256 um, each written to an X3P file and read back through
:func:`tribocosim.surrogate.measured_surfaces.read_scan` (plane detrended, as a measured scan would be), then made
periodic by each method and solved on its own 256^2 domain:

- ``wrap``: the scan taken as it is (its edges meet with steps);
- ``smooth``: Moisan's periodic component (the product's default);
- ``synthesis``: IAAFT, the scan's PSD and height distribution with random phases;
- ``mirror``: the central half of the scan mirrored into 2 x 2 (SurfaceTopography's ``mirror_stitch``);
- ``window``: a Hann window (SurfaceTopography's ``window``, mean square 1).

Printed per contact law and pressure: A_c/A0 of the large surface, and per method the mean over the scans of A_c/A0, its
difference from the large surface's (the bias; the scans tile the large surface, so their local areas in its
solve average to its A_c/A0 exactly) with the standard error of that mean, and the RMS difference of a scan's
A_c/A0 from the area the large solve gives inside the scan's window; and the mean RMS slope of the periodized
scans (periodic finite differences: the edges count) next to the large surface's.

Usage::

    python benchmarks/periodization.py [--tiles 4] [--pressures 1e6 10e6 30e6] [--surface rolloff|powerlaw]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time

import numpy as np

N, PIXEL = 256, 1e-6
SHEET = dict(hurst=0.8, rms_height=1.40e-6, rolloff=49.1928e-6, shortest=5e-6)
E_STAR, P_CRIT = 55e9, 340e6
METHODS = ("wrap", "smooth", "synthesis", "mirror", "window")


def periodized(method: str, scan, seed: int) -> np.ndarray:
    """The 256^2 periodic map of one scan (read and plane-detrended) by ``method``."""
    from SurfaceTopography import Topography

    from tribocosim.surrogate import measured_surfaces as ms

    h = scan.heights
    if method == "wrap":
        return h
    if method == "smooth":
        return ms.periodic_smooth_decomposition(h)[0]
    if method == "synthesis":
        return ms.iaaft_surface(h, seed)
    half = N // 2
    if method == "mirror":
        c = h[half // 2:half // 2 + half, half // 2:half // 2 + half]
        return Topography(c, (half * PIXEL,) * 2, unit="m").mirror_stitch().heights()
    if method == "window":
        return Topography(h, (N * PIXEL,) * 2, unit="m", periodic=False).window("hann").heights()
    raise ValueError(method)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tiles", type=int, default=4, help="scans per side of the large surface")
    ap.add_argument("--pressures", type=float, nargs="+", default=[1e6, 10e6, 30e6])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--surface", choices=("rolloff", "powerlaw"), default="rolloff",
                    help="the quick preset's roll-off sheet, or a pure power law from the large surface's side "
                         "(most of its height in wavelengths longer than a scan: large edge steps)")
    args = ap.parse_args(argv)
    from tribocosim.surrogate import measured_surfaces as ms
    from tribocosim.surrogate.bem import ContactSolver, gap_against_flat
    from tribocosim.surrogate.surfaces import rms_slope, self_affine_surface, surface_wavenumbers

    big_n = args.tiles * N
    big_size = big_n * PIXEL
    rolloff = SHEET["rolloff"] if args.surface == "rolloff" else None
    q_roll, q_cut = surface_wavenumbers(big_size, SHEET["shortest"] / big_size, rolloff)
    big = self_affine_surface(big_n, big_size, SHEET["hurst"], q_roll, q_cut, rms_height=SHEET["rms_height"],
                              seed=args.seed)
    laws = {"elastic": None, "elastic-plastic": P_CRIT}
    keys = [(law, p) for law in laws for p in args.pressures]
    t0 = time.perf_counter()
    big_mask = {}
    for law, p_crit in laws.items():
        big_solver = ContactSolver(big_n, big_size, E_STAR, p_crit=p_crit)
        for p in args.pressures:
            big_mask[(law, p)] = big_solver.solve(gap_against_flat(big), p).traction > 0
    t_big = time.perf_counter() - t0
    solvers = {law: ContactSolver(N, N * PIXEL, E_STAR, p_crit=p_crit) for law, p_crit in laws.items()}
    rows = {(m, k): [] for m in METHODS for k in keys}
    slopes = {m: [] for m in METHODS}
    local = {k: [] for k in keys}
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.tiles):
            for j in range(args.tiles):
                cut = np.s_[i * N:(i + 1) * N, j * N:(j + 1) * N]
                path = os.path.join(tmp, f"scan_{i}_{j}.x3p")
                ms.write_x3p(big[cut], N * PIXEL, path, periodic=False)
                scan = ms.read_scan(path, detrend="plane")
                for k in keys:
                    local[k].append(float(big_mask[k][cut].mean()))
                for m in METHODS:
                    h = periodized(m, scan, seed=100 + i * args.tiles + j)
                    slopes[m].append(rms_slope(h, N * PIXEL, "finite_difference"))
                    gap = gap_against_flat(h)
                    for law, p in keys:
                        rows[(m, (law, p))].append(solvers[law].solve(gap, p).contact_area_fraction)
    t_scans = time.perf_counter() - t0
    print(f"{args.surface} large surface {big_n}^2 of {big_size * 1e6:.0f} um, {args.tiles ** 2} scans of {N}^2 of "
          f"{N * PIXEL * 1e6:.0f} um; solves {t_big:.0f} s (large) + {t_scans:.0f} s (scans); "
          f"load {os.getloadavg()[0]:.2f}")
    print(f"RMS slope (periodic finite differences, what the grid presents): large surface "
          f"{rms_slope(big, big_size, 'finite_difference'):.4f}; scans' mean: "
          + ", ".join(f"{m} {np.mean(slopes[m]):.4f}" for m in METHODS))
    print("| contact | P [MPa] | large A_c/A0 | method | scans' mean A_c/A0 | bias (mean - large) +- s.e. | "
          "relative bias | RMS vs local window |")
    print("|---|---|---|---|---|---|---|---|")
    for law, p in keys:
        ref = float(big_mask[(law, p)].mean())
        loc = np.array(local[(law, p)])
        for m in METHODS:
            a = np.array(rows[(m, (law, p))])
            se = float(np.std(a - loc, ddof=1) / np.sqrt(a.size))
            print(f"| {law} | {p / 1e6:g} | {ref:.4f} | {m} | {a.mean():.4f} | {a.mean() - ref:+.4f} +- {se:.4f} | "
                  f"{(a.mean() - ref) / ref:+.1%} | {np.sqrt(np.mean((a - loc) ** 2)):.4f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
