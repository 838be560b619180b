"""The shipped table's slides on three domain sizes: A_p / A_c at the rows the 3-pass and 140 mm tests read.

Reads the shipped table (256 um, ``models/friction_table.npz``) and the domain-size variation's tables beside it
(``cosim.reports.paper_physics.DOMAIN_TABLES``: the same preset's slides on 128 and 512 um domains of 1 um pixels,
docs/physics/table_domain.md). Per pressure row at 0.08 m/s and per debris level of each other table, prints
A_p / A_c as the ensemble mean of that node's table (A_p +- its standard error, divided by A_c) beside the 256 um
table's A_p / A_c interpolated to the same beta by its own interpolation, with their ratio (mu = mu0 (1 - A_p /
A_c) reads the share), and the particle-free A_c / A0 of each::

    python benchmarks/domain_size.py [--velocity 0.08]

Numbers only from the shipped files; nothing is simulated.
"""

from __future__ import annotations

import argparse

import numpy as np


def _tables():
    from tribocosim.components.stripdraw.table import read_table
    from tribocosim.cosim.reports.paper_physics import DOMAIN_TABLES
    from tribocosim.paths import DEFAULT_TABLE, MODELS_DIR

    out = {"256 um": read_table(DEFAULT_TABLE)}
    for file in DOMAIN_TABLES.values():
        path = MODELS_DIR / file
        if path.is_file():
            t = read_table(path)
            out[f"{t.metadata['campaign']['sweep']['slide']['size'] * 1e6:g} um"] = t
    return out


def _row(table, pressure: float, velocity: float):
    i = int(np.flatnonzero(table.pressure == pressure)[0])
    j = int(np.flatnonzero(table.velocity == velocity)[0])
    return i, j


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--velocity", type=float, default=0.08, help="the velocity row [m/s]")
    args = ap.parse_args(argv)
    from tribocosim.surrogate.campaign import case_cpu_seconds

    tables = _tables()
    ref = tables.pop("256 um")
    for name, t in tables.items():
        cases = t.metadata.get("cases", [])
        cost = case_cpu_seconds(cases)
        print(f"\n{name} table: {len(cases)} slides, {cost:.0f} core-s ({cost / 3600:.2f} core-hours) recorded")
        for p in t.pressure:
            if p not in ref.pressure or args.velocity not in t.velocity:
                continue
            i, j = _row(t, p, args.velocity)
            ri, rj = _row(ref, p, args.velocity)
            sim = t.array("simulated")[i, j] == 1.0
            print(f"  {p / 1e6:g} MPa, {args.velocity:g} m/s: A_c/A0 at beta 0 {t.contact_area[i, j, 0]:.5f} "
                  f"(256 um {ref.contact_area[ri, rj, 0]:.5f})")
            print("    beta      A_p/A_c (+- se)      256 um A_p/A_c   ratio")
            for k, b in enumerate(t.beta):
                if b == 0.0 or not sim[k]:
                    continue
                apk, se, ac = t.particle_area[i, j, k], t.array("particle_area_se")[i, j, k], t.contact_area[i, j, k]
                ref_ap, ref_ac = (float(np.ravel(ref.interpolate_array(a, p, args.velocity, b, "error"))[0])
                                  for a in (ref.particle_area, ref.contact_area))
                print(f"    {b:7.4f}  {apk / ac:.4f} +- {se / ac:.4f}    {ref_ap / ref_ac:.4f}          "
                      f"{apk / ac / (ref_ap / ref_ac):.3f}")


if __name__ == "__main__":
    main()
