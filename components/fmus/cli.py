"""``tribocosim fmu``: build the project's FMUs.

    tribocosim fmu build [--out DIR] [--only NAME ...] [--python] [--platform P ...]
        native FMUs (C; binaries for linux64, win64 and darwin64) by default, into build/fmus;
        --python: the pythonfmu variants (the physics in Python; the host needs Python and numpy)
    tribocosim fmu list                                  the FMUs this project builds
"""

from __future__ import annotations

import argparse
import sys

DEFAULT_OUT = "build/fmus"


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="tribocosim fmu", description="Build the project's FMUs.")
    sub = parser.add_subparsers(dest="command", required=True)
    build = sub.add_parser("build", help="build FMUs (FMI 2.0 co-simulation; native unless --python)")
    build.add_argument("--out", default=DEFAULT_OUT, help=f"destination folder (default: {DEFAULT_OUT})")
    build.add_argument("--only", nargs="+", metavar="NAME", help="build only these FMUs")
    build.add_argument("--python", action="store_true",
                       help="build the pythonfmu variants (change the physics in Python; need Python and numpy in the host)")
    build.add_argument("--platform", nargs="+", choices=("linux64", "win64", "darwin64"),
                       help="native: the platforms to compile for (default: all three)")
    sub.add_parser("list", help="list the FMUs this project builds")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``tribocosim fmu``; returns the exit code."""
    args = _parser().parse_args(sys.argv[1:] if argv is None else argv)
    from tribocosim.components import registry
    from tribocosim.components.fmus.build import FmuBuildError, build_fmus, fmus
    from tribocosim.components.fmus.native import PLATFORMS, build_native_fmus

    if args.command == "list":
        for name, comp in fmus().items():
            print(f"{name}\t{registry.module_of(comp)}")
        return 0
    try:
        if args.python:
            built = build_fmus(args.out, args.only)
        else:
            built = build_native_fmus(args.out, args.only, args.platform or PLATFORMS)
    except FmuBuildError as exc:
        print(f"tribocosim fmu build: {exc}", file=sys.stderr)
        return 1
    for path in built.values():
        print(path.resolve())
    return 0
