"""The paper calibration the package ships (``models/calibration_paper.json``, ``--calibration paper``), and the
one-pass drop of mu_bar a law gives in the paper's test.

    python -m tribocosim.cosim.apps.paper_calibration [--out FILE]

The paper report (:mod:`tribocosim.cosim.reports.paper`, ``tribocosim report paper``) calibrates the default model, A_c
from the table (``mesoscale``) with the flake-borne shear ratio at the documented floor (r = 0.2), zeta = 0.2 and
K = 1e-4 (Fig. 19), on the one number of the paper's text for it (Sec. 2.1): after one pass on the 35 x 35 mm pad,
mu_bar at 25 MPa is 35 % below its 1 MPa value. The scale s of A_p (``particle_area_scale``) solves drop(s) = 0.35 to
|drop - 0.35| < 1e-4 (:func:`tribocosim.cosim.reports.paper.calibrate_drop`, the report's own function, on the
shipped table); its standard error combines the quote's rounding and the table's ensemble noise, as the report gives
it. This module runs that calibration and writes its record (:mod:`tribocosim.components.friction_export.
named_calibration`): the table by file name and content hash, every strip-draw parameter of the fit, s with its
standard error, the data, the fit's history and the command. Rerun it when the shipped table changes (the file names
the table's hash, and a calibration whose table has another is refused).

:func:`one_pass_drop` is that drop for any exported law: the paper's test (1 and 25 MPa, one pass, 35 mm pad,
0.08 m/s, the strip-draw test of :mod:`tribocosim.cosim.studies.stripdraw_experiment`) with the law's parameters.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

from tribocosim.errors import TribocosimError

COMMAND = "python -m tribocosim.cosim.apps.paper_calibration --out models/calibration_paper.json"


def one_pass_drop(law) -> float:
    """1 - mu_bar(25 MPa) / mu_bar(1 MPa) after one pass on the 35 mm pad at 0.08 m/s (the paper's test, Sec. 2.1)
    with the parameters of ``law`` (an :class:`~tribocosim.components.friction_export.exported_law.ExportedLaw`: its
    table and its parameters, the pad aside), two draws in this process."""
    from tribocosim.cosim.reports.paper_physics import CAL_PAD, CAL_PRESSURE, LOW_PRESSURE
    from tribocosim.cosim.studies.stripdraw_experiment import Point, draw

    parameters = {**dataclasses.asdict(law.params), "table_file": str(law.table_path)}
    parameters.pop("tool_length")
    low, high = (draw(Point(p, CAL_PAD, 1, parameters))[0]["mu_bar"] for p in (LOW_PRESSURE, CAL_PRESSURE))
    return 1.0 - high / low


def calibration_record(workers: int | None = 1, log=None) -> dict:
    """Run the paper report's calibration of the default model on the shipped table and return its record (module
    docstring)."""
    from importlib.metadata import PackageNotFoundError, version

    from tribocosim.components.stripdraw.parameters import StripDrawParameters
    from tribocosim.components.stripdraw.table import read_table
    from tribocosim.cosim.reports import paper
    from tribocosim.cosim.reports.paper_physics import CAL_PAD, CAL_PRESSURE, LOW_PRESSURE
    from tribocosim.cosim.studies.stripdraw_experiment import V0
    from tribocosim.paths import DEFAULT_TABLE

    table = read_table(DEFAULT_TABLE)
    config = paper.Config("mesoscale", True)
    base = {"table_file": str(DEFAULT_TABLE.resolve())}
    cal = paper.calibrate_drop(paper.Runs(workers, log), base, config, table, log=log)
    fit_params = {k: v for k, v in paper.config_params(base, config).items() if k != "table_file"}
    parameters = dataclasses.asdict(StripDrawParameters(**fit_params, particle_area_scale=cal.scale))
    try:
        code = version("tribocosim")
    except PackageNotFoundError:  # pragma: no cover - a source tree without an install
        code = "(not installed)"
    return {
        "name": "paper",
        "title": ("the paper report's calibration of the default model (A_c mesoscale, r = "
                  f"{parameters['flake_shear_ratio']:g}, zeta = {parameters['zeta']:g}, K = "
                  f"{parameters['archard_k']:g}) on the paper's one-pass drop of mu_bar, 35 % at 25 MPa on the 35 mm pad"),
        "table": {"file": DEFAULT_TABLE.name, "content_hash": table.metadata.get("content_hash")},
        "status": "converged" if abs(cal.drop - paper.PAPER_DROP_1PASS) < paper.DROP_TOL else "not converged",
        "contact_area": parameters["contact_area"],
        "particle_area_rule": parameters["particle_area_rule"],
        "fitted": {"particle_area_scale": {"value": cal.scale, "stderr": cal.stderr,
                                           "stderr_quote": cal.stderr_quote, "stderr_ensemble": cal.stderr_ensemble}},
        "data": {"source": "the paper, Sec. 2.1: after one pass on the 35 x 35 mm pad, mu_bar at 25 MPa is 35 % below "
                           "its 1 MPa value",
                 "observable": "drop = 1 - mu_bar(25 MPa) / mu_bar(1 MPa), one pass",
                 "drop": paper.PAPER_DROP_1PASS, "drop_std": paper.QUOTE_STD,
                 "drop_std_why": "35 % rounded to a whole percent: a uniform error of +-0.5 points",
                 "pressure": CAL_PRESSURE, "reference_pressure": LOW_PRESSURE, "tool_length": CAL_PAD,
                 "velocity": V0, "passes": 1, "units": "SI"},
        "fit": {"target": paper.PAPER_DROP_1PASS, "reached": cal.drop, "tolerance": paper.DROP_TOL,
                "slope": cal.slope, "evaluations": cal.evaluations,
                "history": [{"particle_area_scale": s, "drop": d} for s, d in cal.history],
                "method": "bracketing and false position (Illinois) on drop(s) = 0.35"},
        "parameters": parameters,
        "made_by": {"command": COMMAND, "function": "tribocosim.cosim.reports.paper.calibrate_drop "
                                                    "(tribocosim report paper: its column A_c mesoscale, s fitted)",
                    "code_version": code},
        "note": (f"the law is the table {DEFAULT_TABLE.name} with these parameters (particle_area_scale = "
                 f"{cal.scale:.6g}); the fit holds for them: a parameter changed (--set, --option) is a law it was "
                 "not fitted for, and the export says so with that law's one-pass drop"),
    }


def write_calibration(out: Path, workers: int | None = 1, log=None) -> dict:
    """Run the calibration and write its file to ``out`` (whole or not at all); returns the record."""
    from tribocosim.atomic import write_text
    from tribocosim.components.friction_export.named_calibration import calibration_text

    record = calibration_record(workers, log)
    write_text(out, calibration_text(record))
    return record


def main(argv: list[str] | None = None) -> int:
    from tribocosim.paths import MODELS_DIR

    p = argparse.ArgumentParser(prog="python -m tribocosim.cosim.apps.paper_calibration",
                                description="Run the paper report's calibration of the default model and write the "
                                            "shipped calibration file.")
    p.add_argument("--out", type=Path, default=MODELS_DIR / "calibration_paper.json", help="the file to write "
                   "(default: the package's models/calibration_paper.json)")
    args = p.parse_args(argv)
    try:
        record = write_calibration(args.out, log=lambda s: print(s, file=sys.stderr))
    except TribocosimError as exc:
        print(f"paper_calibration: {exc}", file=sys.stderr)
        return 2
    s = record["fitted"]["particle_area_scale"]
    print(f"wrote {args.out}: particle_area_scale = {s['value']:.6g} +- {s['stderr']:.2g} (drop "
          f"{100 * record['fit']['reached']:.3f} %, target {100 * record['fit']['target']:g} %)")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
