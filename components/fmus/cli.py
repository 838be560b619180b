"""``tribocosim fmu``: build the project's FMUs.

    tribocosim fmu build [--out DIR] [--only NAME ...]   build FMUs (default: all, into build/fmus)
    tribocosim fmu list                                  the FMUs this project builds
"""

from __future__ import annotations

import argparse
import sys

DEFAULT_OUT = "build/fmus"


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="tribocosim fmu", description="Build the project's FMUs.")
    sub = parser.add_subparsers(dest="command", required=True)
    build = sub.add_parser("build", help="build FMUs (FMI 2.0 co-simulation, pythonfmu)")
    build.add_argument("--out", default=DEFAULT_OUT, help=f"destination folder (default: {DEFAULT_OUT})")
    build.add_argument("--only", nargs="+", metavar="NAME", help="build only these FMUs")
    sub.add_parser("list", help="list the FMUs this project builds")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``tribocosim fmu``; returns the exit code."""
    args = _parser().parse_args(sys.argv[1:] if argv is None else argv)
    from tribocosim.components import registry
    from tribocosim.components.fmus.build import FmuBuildError, build_fmus, fmus

    if args.command == "list":
        for name, comp in fmus().items():
            print(f"{name}\t{registry.module_of(comp)}")
        return 0
    try:
        built = build_fmus(args.out, args.only)
    except FmuBuildError as exc:
        print(f"tribocosim fmu build: {exc}", file=sys.stderr)
        return 1
    for path in built.values():
        print(path.resolve())
    return 0
