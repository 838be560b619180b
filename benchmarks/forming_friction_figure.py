"""The figure of docs/forming-friction.md: the exported mu(P) of the default law (the paper calibration) at a few
debris levels and at the debris of a few slides, with their band, as an FE code reads the files, over tribocosim's law.

For each beta (``--beta``) and each slide (``--slide``: the debris a sheet point makes sliding S under each pressure) the
shipped table is exported with the default calibration (``tribocosim.export_friction("table", ..., band=K)``, the
neutral table, whose grid is the LS-DYNA file's); the figure draws the nominal, upper and lower files (their one
velocity: the law does not depend on it) as the FE code reads them (straight between the exported pressures, dots at
the nodes) and the law itself on a fine grid, and the script prints the numbers the page quotes::

    python benchmarks/forming_friction_figure.py --out PNG [--band 2]   # docs/images/forming_friction_band.png: the
                                                                        # tracked figure
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

BETAS = (0.05, 0.1, 0.2, 0.3)
SLIDES = (10.0, 20.0, 35.0)  # mm: a die radius' worth of slide to the pad's width
SPEED = 80.0  # mm/s, the strip-draw test's


def _exported(tmp: Path, name: str, choice, band: float):
    """The nominal, upper and lower neutral tables of one debris choice: pressures [MPa], and mu at the file's first
    velocity of each."""
    import tribocosim

    result = tribocosim.export_friction("table", tmp / f"{name}.json", choice, band=band)
    nominal, upper, lower = (json.loads(f.path.read_text()) for f in result.files)
    p = np.array(nominal["axes"][0]["values"])
    mu, up, lo = (np.array(d["mu"])[:, 0] for d in (nominal, upper, lower))
    return p, mu, up, lo, nominal["interpolation"]["accuracy"]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, required=True, help="the figure to write (PNG)")
    parser.add_argument("--band", type=float, default=2.0)
    args = parser.parse_args(argv)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import tribocosim
    from tribocosim.components.friction_export.exported_law import load_law
    from tribocosim.components.friction_export.named_calibration import DEFAULT

    law = load_law(calibration_path=DEFAULT)
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.4), sharey=True)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    print(f"{'state':>14} {'nodes':>5} {'accuracy %':>10} {'mu(1 MPa)':>10} {'mu(30 MPa)':>10} "
          f"{'band +- at 1 MPa':>17} {'at 30 MPa':>10}")
    cases = [(axes[0], f"beta = {b:g}", tribocosim.DebrisChoice(beta=(b,)), b, None) for b in BETAS]
    cases += [(axes[1], f"slide {s:g} mm", tribocosim.DebrisChoice(slide=(s,)), None, s) for s in SLIDES]
    with tempfile.TemporaryDirectory() as tmp:
        for k, (ax, label, choice, beta, slide) in enumerate(cases):
            color = colors[k % len(colors)]
            p, mu, up, lo, accuracy = _exported(Path(tmp), f"case{k}", choice, args.band)
            fine = np.linspace(p[0], p[-1], 400)
            at = beta if slide is None else law.beta_after_slide(fine * 1e6, SPEED * 1e-3, slide * 1e-3)
            exact, _ = law.mu(fine * 1e6, SPEED * 1e-3, at)
            ax.fill_between(p, lo, up, color=color, alpha=0.18, lw=0)
            ax.plot(fine, exact, color=color, lw=3.0, alpha=0.35)
            ax.plot(p, mu, "o-", color=color, ms=3.5, lw=1.0, label=label)
            print(f"{label:>14} {p.size:5d} {100 * accuracy:10.3f} {mu[0]:10.4f} "
                  f"{mu[-1]:10.4f} {0.5 * (up[0] - lo[0]):17.4f} {0.5 * (up[-1] - lo[-1]):10.4f}")
    axes[0].set_title("at a fixed debris state: mu rises with P", fontsize=9)
    axes[1].set_title("at the debris a point makes sliding S under P: mu falls with P", fontsize=9)
    for ax in axes:
        ax.set_xlabel("contact pressure [MPa]")
        ax.set_xlim(0, 31)
        ax.legend(fontsize=8, loc="upper center", ncol=4)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("mu")
    axes[0].set_ylim(top=axes[0].get_ylim()[1] + 0.015)
    fig.suptitle(f"exported mu(P), the paper calibration: files (dots, straight between them), the law (wide line), "
                 f"+-{args.band:g} se band", fontsize=9)
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
