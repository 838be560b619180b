"""Regenerate the golden outputs of the runtime models (run on purpose only, after a change of the physics that
has been checked against the verification tests; commit the files with the reason in the message).

    python tests/components/golden/regenerate.py

Writes, beside this script, one CSV per case of :data:`CASES` (tests/components/test_golden_outputs.py reads them):
the default strip draw (the shipped table, implicit, 150 elements) at 10 MPa and 0.08 m/s, the same draw with the
paper's frictionless flakes (flake_shear_ratio = 0), the default draw with the explicit integrator over 20 mm, the
press and the drawing machine with their default parameters. Every ``EVERY``-th step is kept, with 17 significant
digits.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
EVERY = 25
F_N = 12250.0  # N: 10 MPa on the 35 x 35 mm pad
V0 = 0.08  # m/s


def _strip(**kw):
    from tribocosim.paths import DEFAULT_TABLE
    from tribocosim.components.stripdraw import StripDrawModel, StripDrawParameters, make_friction_law, read_table

    p = StripDrawParameters(**kw)
    return StripDrawModel(p, make_friction_law(p, read_table(DEFAULT_TABLE)))


def stripdraw_default():
    m = _strip()
    for k in range(1750):
        yield k + 1, m.step(1e-3, {"normal_force": F_N, "grip_velocity": V0 * min(1.0, (k + 0.5) / 10)})


def stripdraw_paper():
    """The default draw with the paper's frictionless flakes (flake_shear_ratio = 0)."""
    m = _strip(flake_shear_ratio=0.0)
    for k in range(1750):
        yield k + 1, m.step(1e-3, {"normal_force": F_N, "grip_velocity": V0 * min(1.0, (k + 0.5) / 10)})


def stripdraw_explicit():
    m = _strip(integrator="explicit", draw_length=0.02)
    for k in range(250):
        yield k + 1, m.step(1e-3, {"normal_force": F_N, "grip_velocity": V0 * min(1.0, (k + 0.5) / 10)})


def press_default():
    from tribocosim.components.press import PressModel, PressParameters

    m = PressModel(PressParameters())
    for k in range(500):
        yield k + 1, m.step(1e-3)


def machine_default():
    from tribocosim.components.machine import MachineModel, MachineParameters

    m = MachineModel(MachineParameters())
    for k in range(500):
        yield k + 1, m.step(1e-3, {"pull_force": 3000.0 * min(1.0, k / 50)})


CASES = {"stripdraw_default": stripdraw_default, "stripdraw_paper": stripdraw_paper,
         "stripdraw_explicit": stripdraw_explicit,
         "press_default": press_default, "machine_default": machine_default}


def rows(case: str) -> tuple[list[str], np.ndarray]:
    """The kept steps of a case: (column names, values)."""
    kept = [(k, out) for k, out in CASES[case]() if k % EVERY == 0]
    names = ["step", *kept[0][1]]
    return names, np.array([[k, *out.values()] for k, out in kept], dtype=float)


def main() -> int:
    for case in CASES:
        names, values = rows(case)
        np.savetxt(HERE / f"{case}.csv", values, delimiter=",", header=",".join(names), comments="", fmt="%.17g")
        print(f"{case}: {len(values)} rows")
    return 0


if __name__ == "__main__":
    sys.exit(main())
