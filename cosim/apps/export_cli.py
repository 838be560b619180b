"""``tribocosim export``: the strip-draw friction law for a forming simulation (LS-DYNA, Abaqus, a neutral table, user
friction routines).

    tribocosim export FORMAT -o FILE [--beta B ... | --slide S ... |
                                      --passes N ... --pressure P [--velocity V] [--pad-length L]]
                     [--units mm-t-s|SI] [--band K] [--table T | --calibration paper|none|C] [--set NAME=VALUE ...]
                     [--option NAME]
                     [--pressure-range LO HI] [--beta-levels B ...] [--allow-unsimulated] [--tolerance X]
                     [--table-id N] [--interaction-name NAME]

FORMAT: ``lsdyna`` (an include file: *DEFINE_TABLE and its *DEFINE_CURVEs for contact FS = 2), ``abaqus`` (a *SURFACE
INTERACTION with a tabulated *FRICTION; without a debris state beta is field variable 1), ``table`` (a neutral JSON
table), ``vfriction``, ``fric``, ``usrfrc`` (user friction routines for Abaqus/Explicit, Abaqus/Standard and LS-DYNA:
FILE.f with FILE.c and FILE.h beside it, the debris state kept per contact node; they take --table, --calibration,
--set, --option and --units). Every pressure, velocity and length is in the ``--units`` system. Bad input is one line
naming the option on stderr, exit code 2, and no file written. A warning about what a file holds (its accuracy short
of the target, mu below the documented floor of the strip-draw contact, naming the setting that lets it) is one line on
stderr per file, ``tribocosim export: warning: <file>: ...``, and in the file's header; the file is written and the
exit code is 0. A note about the law (uncalibrated, or with parameters other than its calibration's, and the one-pass
drop it gives in the paper's test) is one line on stderr, ``tribocosim export: note: ...``, and in the headers.

The law is calibrated by default: without --table, --calibration or --set particle_area_scale it is the shipped
paper calibration (--calibration paper: the scale s of the flakes' load share fitted so that the model's one-pass drop
of mu_bar at 25 MPa on the 35 mm pad is the paper's 35 %; the mesoscale campaign's law as simulated, s = 1, gives a
smaller one, and a forming simulation would carry a law weaker in pressure than the test's). --slide S writes the law
at the debris a sheet point makes sliding S under each pressure (mu falls with pressure, as in the test). A law that
does not depend on the velocity (the shipped table's) is written at one velocity, and the output says so.
docs/forming-friction.md is the guide.
"""

from __future__ import annotations

import argparse
import shlex
import sys

from tribocosim.components.stripdraw.multipass_options import option_names
from tribocosim.errors import TribocosimError

FORMATS = ("lsdyna", "abaqus", "table", "vfriction", "fric", "usrfrc")


class _ArgumentError(Exception):
    pass


class _Parser(argparse.ArgumentParser):
    """argparse whose usage errors are one line (exit 2), without the usage text."""

    def error(self, message):
        raise _ArgumentError(message)


def _parser() -> argparse.ArgumentParser:
    from tribocosim.components.friction_export.abaqus_friction import DEFAULT_NAME
    from tribocosim.components.friction_export.export_run import DEFAULT_TOLERANCE
    from tribocosim.components.friction_export.export_units import DEFAULT_UNITS, UNIT_SYSTEMS
    from tribocosim.components.friction_export.lsdyna_deck import DEFAULT_TABLE_ID

    p = _Parser(prog="tribocosim export", description=__doc__.split("\n\n")[2].strip(),
                epilog=__doc__.split("\n\n")[3].strip())
    p.add_argument("format", metavar="FORMAT", help=f"one of {', '.join(FORMATS)}")
    p.add_argument("-o", "--out", required=True, help="the file to write")
    state = p.add_argument_group("debris state (none: beta is an axis of the file; abaqus and table only)")
    state.add_argument("--beta", nargs="+", default=[], metavar="B", help="debris area fraction(s): one file each")
    state.add_argument("--slide", nargs="+", default=[], metavar="S", help="slide(s) in the --units system's length "
                       "(mm in mm-t-s, m in SI): at each pressure P and velocity of the file, the debris a sheet point "
                       "makes sliding S there from a clean blank (--set beta_initial=B: the blank's debris), keeping "
                       "what it makes (zeta = 0): beta = K P S / (H h_p) below the cap (Eq. 24), with the sink if "
                       "debris_sink_length is set; e.g. 20 for a die radius; one file each")
    state.add_argument("--passes", nargs="+", default=[], metavar="N",
                       help="the state a strip-draw test reaches after N passes: one file each")
    state.add_argument("--pressure", default=None, help="--passes: the test's nominal pressure in the --units system "
                       "(required; MPa in mm-t-s, Pa in SI)")
    state.add_argument("--velocity", default=None, help="--passes: the drawing speed in the --units system (default: "
                       "the paper's 0.08 m/s, which is 80 in mm-t-s and 0.08 in SI)")
    state.add_argument("--pad-length", default=None, help="--passes: the pad length in the --units system (default: "
                       "tool_length, 35 mm, which is 35 in mm-t-s and 0.035 in SI)")
    p.add_argument("--units", default=DEFAULT_UNITS, help=f"{' or '.join(UNIT_SYSTEMS)} (default {DEFAULT_UNITS}: "
                   "N, MPa, mm/s, mm)")
    p.add_argument("--band", default=None, metavar="K", help="also write FILE.upper.SUFFIX and FILE.lower.SUFFIX: mu "
                   "+- K standard errors")
    law = p.add_mutually_exclusive_group()
    law.add_argument("--table", default=None, help="a friction table, its law uncalibrated (particle_area_scale = 1 "
                     "unless --set gives it)")
    law.add_argument("--calibration", default=None, metavar="C", help="paper (the default, without --table and --set "
                     "particle_area_scale: the shipped table with the paper report's calibration on the paper's "
                     "one-pass 35 %% drop at 25 MPa, models/calibration_paper.json), none (the shipped table "
                     "uncalibrated, A_p as the mesoscale campaign simulated it), or a calibration file (a table "
                     "written by tribocosim calibrate, or a calibration's JSON file)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="a strip-draw parameter")
    p.add_argument("--option", default=None, metavar="NAME", help="a multi-pass option of the paper report "
                   f"({', '.join(option_names())}): its parameters for the law and the passes; --set overrides them")
    p.add_argument("--pressure-range", nargs=2, default=None, metavar=("LO", "HI"),
                   help="the pressures to export (default: the table's axis)")
    p.add_argument("--beta-levels", nargs="+", default=None, metavar="B",
                   help="the levels of the beta axis (default: refined up to the highest level simulated in the range)")
    p.add_argument("--allow-unsimulated", action="store_true", help="write, marked, values whose lookups read table "
                   "nodes the mesoscale campaign did not simulate (refused without it)")
    p.add_argument("--tolerance", default=str(DEFAULT_TOLERANCE), help="largest relative deviation of the FE code's "
                   f"linear interpolation from tribocosim's mu (default {DEFAULT_TOLERANCE})")
    p.add_argument("--table-id", default=str(DEFAULT_TABLE_ID), help="lsdyna: the *DEFINE_TABLE id; its curves take "
                   f"the ids after it (default {DEFAULT_TABLE_ID})")
    p.add_argument("--interaction-name", default=DEFAULT_NAME, help=f"abaqus: the *SURFACE INTERACTION's name "
                   f"(default {DEFAULT_NAME})")
    return p


def _number(option: str, text, integer: bool = False):
    from tribocosim.errors import ParameterError

    try:
        value = float(text)
        if integer and value != int(value):
            raise ValueError
    except (TypeError, ValueError):
        raise ParameterError(f"{option} {text!r} is not {'an integer' if integer else 'a number'}") from None
    return int(value) if integer else value


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``tribocosim export``."""
    parser = _parser()
    args_list = list(sys.argv[1:] if argv is None else argv)
    try:
        args = parser.parse_args(args_list)
    except _ArgumentError as exc:
        print(f"tribocosim export: {exc}", file=sys.stderr)
        return 2
    from tribocosim.components.stripdraw.settings import parse_settings
    from tribocosim.cosim.apps.debris_state import DebrisChoice
    from tribocosim.cosim.apps.export_friction import export_friction

    try:
        state = DebrisChoice(beta=tuple(args.beta), passes=tuple(args.passes), pressure=args.pressure,
                             velocity=args.velocity, pad_length=args.pad_length, slide=tuple(args.slide))
        result = export_friction(
            args.format, args.out, state, units=args.units,
            band=None if args.band is None else _number("--band", args.band),
            table=args.table, calibration=args.calibration, settings=parse_settings(args.set), option=args.option,
            pressure_range=None if args.pressure_range is None else
            tuple(_number("--pressure-range", x) for x in args.pressure_range),
            beta_levels=None if args.beta_levels is None else tuple(_number("--beta-levels", x)
                                                                    for x in args.beta_levels),
            allow_unsimulated=args.allow_unsimulated, tolerance=_number("--tolerance", args.tolerance),
            table_id=_number("--table-id", args.table_id, integer=True), interaction_name=args.interaction_name,
            command=shlex.join(["tribocosim", "export", *args_list]),
            log=lambda s: print(s, file=sys.stderr))
    except TribocosimError as exc:
        print(f"tribocosim export: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("tribocosim export: interrupted by SIGINT: no file is written", file=sys.stderr)
        return 130
    print("\n".join(result.summary()))
    for line in result.notes:  # what the law is, when it is not a calibration's fitted model
        print(f"tribocosim export: note: {line}", file=sys.stderr)
    for line in result.warning_lines():  # the files are written; what they hold that the user should know
        print(f"tribocosim export: warning: {line}", file=sys.stderr)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
