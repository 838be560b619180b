"""``tribocosim ssp export SCENE -o RIG.ssp``: a scene written as an SSP 1.0 package (:mod:`tribocosim.cosim.ssp.export`)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="tribocosim ssp", description="SSP 1.0 packages of co-simulation scenes.")
    sub = p.add_subparsers(dest="action", required=True)
    ex = sub.add_parser("export", help="write a scene as an SSP package (SystemStructure.ssd + FMUs + .ssv)",
                        description="Write a scene as an SSP 1.0 package: the system, its FMUs (from the FMU cache "
                                    "for component = \"...\" FMUs), the parameters as .ssv parameter sets and the "
                                    "default experiment. Run it with 'tribocosim run RIG.ssp', fmpy or libcosim.")
    ex.add_argument("scene", help="scene file (TOML), or the name of a packaged scene (e.g. demo)")
    ex.add_argument("-o", "--output", type=Path, default=None, help="the .ssp file (default: ./SCENE.ssp)")
    ex.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="override a scene key first, e.g. --set experiment.stop=0.5 (TOML value syntax)")
    return p


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``tribocosim ssp``."""
    args = _parser().parse_args(argv)
    from tribocosim.cosim.scene.schema import parse_overrides
    from tribocosim.cosim.ssp.export import export_ssp
    from tribocosim.errors import SceneError, TribocosimError
    from tribocosim.paths import scene_file

    try:
        scene = scene_file(args.scene)
        out = args.output if args.output is not None else Path.cwd() / f"{scene.stem}.ssp"
        package = export_ssp(scene, out, parse_overrides(args.set))
    except SceneError as exc:
        print(f"tribocosim ssp export: {exc}", file=sys.stderr)
        return 2
    except (TribocosimError, OSError) as exc:
        print(f"tribocosim ssp export: {exc}", file=sys.stderr)
        return 1
    print(f"wrote {package.path}: {len(package.components)} components ({', '.join(package.components)}), "
          f"{package.connections} connections, {package.parameters} parameter values, "
          f"resources {', '.join(package.resources)}")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
