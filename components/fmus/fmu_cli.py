"""``tribocosim fmu``: build the project's FMUs.

    tribocosim fmu build [--out DIR] [--only NAME ...] [--platform P ...] [--fmi {2,3}]
        the FMUs (C; binaries for linux64, win64, darwin64 (universal: Intel and Apple Silicon); with --fmi 3
        also aarch64-linux and aarch64-darwin), into build/fmus; one line on stderr before each FMU's compile for
        each platform and before its validation; the paths built on stdout;
        --fmi 3: FMI 3.0 co-simulation variants of the native FMUs, same file names (StripDraw.fmu...),
        into build/fmus/fmi3 unless --out is given
    tribocosim fmu list                                  the FMUs this project builds
    tribocosim fmu table-resource TABLE.npz [--out F]    the table's resource form for the native StripDraw FMU
        (TABLE.tca beside it unless --out is given), from the verified table
"""

from __future__ import annotations

import argparse
import sys

DEFAULT_OUT = "build/fmus"
#: where ``--fmi 3`` writes by default: the FMI 3.0 FMUs have the FMI 2.0 ones' file names
DEFAULT_OUT_FMI3 = "build/fmus/fmi3"


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="tribocosim fmu", description="Build the project's FMUs.")
    sub = parser.add_subparsers(dest="command", required=True)
    build = sub.add_parser("build", help="build FMUs (FMI 2.0 co-simulation, or 3.0 with --fmi 3)")
    build.add_argument("--out", help=f"destination folder (default: {DEFAULT_OUT}; with --fmi 3: {DEFAULT_OUT_FMI3})")
    build.add_argument("--only", nargs="+", metavar="NAME", help="build only these FMUs")
    build.add_argument("--platform", nargs="+", choices=("linux64", "win64", "darwin64", "aarch64-linux",
                                                         "aarch64-darwin"),
                       help="the platforms to compile for (default: all; FMI 2.0 has no ARM Linux folder "
                            "and runs Apple Silicon from the universal darwin64 binary)")
    build.add_argument("--fmi", type=int, choices=(2, 3), default=2,
                       help="the FMI version (default: 2). 3: FMI 3.0 co-simulation FMUs with the same "
                            f"names (StripDraw.fmu...) into {DEFAULT_OUT_FMI3} unless --out is given; StripDraw "
                            "also outputs the nodal fields beta, U, contact as arrays of n_nodes = n_elements + 1 "
                            "values (n_nodes and n_elements are structural parameters)")
    sub.add_parser("list", help="list the FMUs this project builds")
    res = sub.add_parser("table-resource", help="write a friction table's resource form (.tca), which the native "
                                                "StripDraw FMU reads when its table_file names the .npz")
    res.add_argument("table", help="the friction table (.npz)")
    res.add_argument("--out", help="the file to write (default: the table's path with the suffix .tca)")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``tribocosim fmu``; returns the exit code."""
    args = _parser().parse_args(sys.argv[1:] if argv is None else argv)
    from tribocosim.components import registry
    from tribocosim.components.fmus.native_build import PLATFORMS, FmuBuildError, build_native_fmus, fmus

    if args.command == "table-resource":
        from tribocosim.errors import TribocosimError
        from tribocosim.components.stripdraw.table import write_table_resource

        try:
            print(write_table_resource(args.table, args.out).resolve())
        except TribocosimError as exc:
            print(f"tribocosim fmu table-resource: {exc}", file=sys.stderr)
            return 1
        return 0
    if args.command == "list":
        for name, comp in fmus().items():
            print(f"{name}\t{registry.module_of(comp)}")
        return 0
    out = args.out or (DEFAULT_OUT_FMI3 if args.fmi == 3 else DEFAULT_OUT)
    try:
        built = build_native_fmus(out, args.only, args.platform or PLATFORMS, fmi_version=args.fmi,
                                  progress=lambda line: print(f"tribocosim fmu build: {line}", file=sys.stderr,
                                                              flush=True))
    except FmuBuildError as exc:
        print(f"tribocosim fmu build: {exc}", file=sys.stderr)
        return 1
    for path in built.values():
        print(path.resolve())
    return 0
