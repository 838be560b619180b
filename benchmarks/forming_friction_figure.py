"""The figure of docs/forming-friction.md: the exported mu(P) at a few debris levels with their band, as an FE code
reads the files, over tribocosim's law.

For each beta the shipped table is exported (``tribocosim.export_friction("table", ..., band=K)``, the neutral
table, whose grid is the LS-DYNA file's); the figure draws the nominal, upper and lower files at the test's
sliding speed as the FE code reads them (straight between the exported pressures, dots at the nodes) and the law
itself on a fine grid, and the script prints the numbers the page quotes::

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
SPEED = 80.0  # mm/s, the strip-draw test's


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

    law = load_law()
    fig, ax = plt.subplots(figsize=(7.0, 4.4))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    print(f"{'beta':>6} {'nodes':>5} {'accuracy %':>10} {'mu(1 MPa)':>10} {'mu(30 MPa)':>10} "
          f"{'band +- at 1 MPa':>17} {'at 30 MPa':>10}")
    with tempfile.TemporaryDirectory() as tmp:
        for beta, color in zip(BETAS, colors):
            result = tribocosim.export_friction("table", Path(tmp) / f"b{beta}.json",
                                                tribocosim.DebrisChoice(beta=(beta,)), band=args.band)
            nominal, upper, lower = (json.loads(f.path.read_text()) for f in result.files)
            p = np.array(nominal["axes"][0]["values"])
            j = nominal["axes"][1]["values"].index(SPEED)
            mu, up, lo = (np.array(d["mu"])[:, j] for d in (nominal, upper, lower))
            fine = np.linspace(p[0], p[-1], 400)
            exact, _ = law.mu(fine * 1e6, SPEED * 1e-3, beta)
            ax.fill_between(p, lo, up, color=color, alpha=0.18, lw=0)
            ax.plot(fine, exact, color=color, lw=3.0, alpha=0.35)
            ax.plot(p, mu, "o-", color=color, ms=3.5, lw=1.0, label=f"beta = {beta:g}")
            print(f"{beta:6g} {p.size:5d} {100 * nominal['interpolation']['accuracy']:10.3f} {mu[0]:10.4f} "
                  f"{mu[-1]:10.4f} {0.5 * (up[0] - lo[0]):17.4f} {0.5 * (up[-1] - lo[-1]):10.4f}")
    ax.set_xlabel("contact pressure [MPa]")
    ax.set_ylabel("mu")
    ax.set_xlim(0, 31)
    ax.set_title(f"exported mu(P) at {SPEED:g} mm/s: files (dots, straight between them), the law (wide line), "
                 f"+-{args.band:g} se band", fontsize=9)
    ax.set_ylim(top=ax.get_ylim()[1] + 0.012)
    ax.legend(fontsize=8, loc="upper center", ncol=len(BETAS))
    ax.grid(alpha=0.3)
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
