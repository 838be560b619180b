"""The paper report's figures that docs/model.md shows, redrawn from a report's numbers (its ``paper.json``) into
docs/images: the discriminating predictions (``discriminating_predictions.png``, the report's ``discriminators.png``)
and the floor's prediction at 25 MPa (``floor_prediction.png``, the report's ``floor.png``). No test is run::

    python benchmarks/paper_figures.py [docs/reports/paper/paper.json] [--out docs/images]
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
from pathlib import Path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("report", type=Path, nargs="?", default=Path("docs/reports/paper/paper.json"))
    parser.add_argument("--out", type=Path, default=Path("docs/images"))
    args = parser.parse_args(argv)
    from tribocosim.cosim.reports import paper_discriminators, paper_floor

    if not args.report.is_file():
        print(f"paper_figures: no report numbers at {args.report} (tribocosim report paper --out DIR writes "
              "DIR/paper.json)", file=sys.stderr)
        return 2
    summary = json.loads(args.report.read_text(encoding="utf-8"))
    if "discriminators" not in summary:
        print(f"paper_figures: {args.report} has no discriminating predictions (a report of an older code)",
              file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    floor = summary["floor"]["mu_floor"]
    paper_discriminators.plot(summary["discriminators"], args.out, "discriminating_predictions.png", floor)
    with tempfile.TemporaryDirectory() as tmp:  # paper_floor.plot names its file floor.png
        shutil.move(str(Path(tmp) / paper_floor.plot(summary["prediction"], floor, Path(tmp))),
                    args.out / "floor_prediction.png")
    print(f"wrote {args.out / 'discriminating_predictions.png'} and {args.out / 'floor_prediction.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
