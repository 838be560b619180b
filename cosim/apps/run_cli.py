"""``tribocosim run SCENE [--out DIR] [--plot]``: run a co-simulation scene, or an SSP package (``RIG.ssp``).

A thin layer over :func:`tribocosim.cosim.api.run`: validates the scene (all problems at once), runs it
with a progress bar on stderr for runs longer than two seconds, writes the CSV and the metadata
JSON, and prints a summary. ``--plot`` also writes a PNG of the recorded variables. A sweep file (a ``[sweep]`` table over a
base scene, :mod:`tribocosim.cosim.apps.scene_sweep`) runs its cases in parallel processes instead.

Before the run the output folder is made and checked writable, and locked against a second run into it
(:mod:`tribocosim.cosim.apps.run_output`); the result JSON records the ``--set`` overrides (``overrides``).

Exit codes: 0 success, 1 the run failed (an FMU error, or a discarded step or non-finite output that a
smaller step does not recover; the message names the FMU, the variable, the time and the step, and what
was accepted up to then is written, with a ``failure`` entry in the JSON), 2 the scene has problems, or its
results cannot be written where asked (a file in the way, a folder that cannot be written, another run there),
130 and 143 a SIGINT (Ctrl-C) or SIGTERM stopped it (:mod:`tribocosim.interrupt`): the run stops at the next
communication point (the C loop looks up from its steps every quarter second) and writes the steps accepted up to
there, the CSV as always and the JSON with an ``interrupted`` entry (the signal, the last time, the rows and steps),
and one line says so; a sweep keeps its finished cases (a rerun resumes). A second signal ends the process at once.

An SSP 1.0 package (``.ssp``, :mod:`tribocosim.cosim.ssp.reader`) runs with its default experiment and
our master; ``--set`` overrides the keys of the scene it is read as (``master.*``, ``experiment.*``, ...).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from tribocosim.errors import Interrupted, RunFailed, RunInterrupted, SceneError, TribocosimError
from tribocosim.lazy import log_to_console


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="tribocosim run",
                                description="Run a co-simulation scene (TOML) or SSP package (.ssp).")
    p.add_argument("scene", help="scene file (TOML), SSP 1.0 package (.ssp), or the name of a packaged scene "
                                 "(e.g. demo, pressure_sweep)")
    p.add_argument("--out", type=Path, default=None,
                   help="output folder (default: the scene's or package's folder; ./NAME for a packaged scene); "
                        "[output] file is written there")
    p.add_argument("--plot", action="store_true", help="also write a PNG plot of the recorded variables")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scene key, e.g. --set master.extrapolation=1 (TOML value syntax)")
    p.add_argument("--workers", type=int, default=None,
                   help="sweep files ([sweep] table, cosim.apps.scene_sweep): parallel processes (default: the file's, else one per CPU)")
    return p


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``tribocosim run``."""
    args = _parser().parse_args(argv)
    log_to_console("tribocosim: %(message)s")
    from tribocosim import interrupt

    with interrupt.stop_on_signals(None):  # the first SIGINT/SIGTERM stops at a communication point (module docstring)
        return _main(args)


def _main(args) -> int:
    from tribocosim.interrupt import raise_if_stopped
    from tribocosim.cosim.api import run, run_ssp
    from tribocosim.cosim.scene.schema import is_sweep, parse_overrides, read_document
    from tribocosim.paths import scene_file

    from tribocosim.cosim.apps.run_output import OutputError, OutputFolder, run_files

    png = plan = None
    try:
        args.scene = scene_file(args.scene)
        if args.scene.suffix.lower() == ".ssp":  # an SSP package, read as a scene (cosim.ssp.reader)
            out = Path(args.out) if args.out is not None else args.scene.resolve().parent
            with OutputFolder(out, []):
                raise_if_stopped(Interrupted)
                result = run_ssp(args.scene, out, parse_overrides(args.set), progress=not args.quiet)
                png = _plot(args, result)
        elif is_sweep(document := read_document(args.scene)):  # a sweep or chained passes over a base scene
            if args.set:
                raise SceneError("--set applies to scenes; put the keys in the sweep file's [sweep.set]")
            from tribocosim.cosim.apps.scene_sweep import main as sweep_main

            return sweep_main(args)
        else:
            from tribocosim.cosim.api import default_out_dir
            from tribocosim.cosim.scene.validate import load_scene

            # parsed once, each value checked once (the component declarations, the model descriptions)
            plan = load_scene(args.scene, parse_overrides(args.set), document)
            out = Path(args.out) if args.out is not None else default_out_dir(plan.scene.path)
            with OutputFolder(out, run_files(plan, out, args.plot)):  # writable, and no other run writes there
                raise_if_stopped(Interrupted)
                result = run(plan, out, progress=not args.quiet)
                png = _plot(args, result)
    except (SceneError, OutputError) as exc:
        print(f"tribocosim run: {exc}", file=sys.stderr)
        return 2
    except RunFailed as exc:
        r = exc.result
        print(f"tribocosim run: the run failed: {exc}", file=sys.stderr)
        print(f"tribocosim run: what was accepted is written ({_kept(r)}): {_written(r)}", file=sys.stderr)
        return 1
    except RunInterrupted as exc:
        r = exc.result
        mark = r.metadata["interrupted"]
        of = f" of {mark['steps_of_the_run']}" if mark["steps_of_the_run"] is not None else ""
        files = [f"{r.csv_path} ({_kept(r)})" if r.csv_path else None,
                 f"{r.metadata_path} (marked interrupted)" if r.metadata_path else None]
        print(f"tribocosim run: {exc} after {mark['steps']}{of} steps; the accepted steps are written: "
              f"{', '.join(f for f in files if f)}", file=sys.stderr)
        return 128 + exc.signum
    except Interrupted as exc:  # before the run started
        print(f"tribocosim run: {exc} before the run started; nothing was written", file=sys.stderr)
        return 128 + exc.signum
    try:
        raise_if_stopped(Interrupted)
    except Interrupted as exc:  # after the last step: every result is written, the run is whole
        print(f"tribocosim run: {exc} after the last step; the results are whole and written", file=sys.stderr)
        return 128 + exc.signum
    except TribocosimError as exc:
        print(f"tribocosim run: the run failed: {exc}", file=sys.stderr)
        return 1
    except OSError as exc:  # the results could not be written after all (a full disk, the folder removed meanwhile)
        print(f"tribocosim run: writing the results failed: {exc}", file=sys.stderr)
        return 1
    meta = result.metadata
    if png is not None and not args.quiet:
        print(f"plot:     {png}")
    if not args.quiet:
        st, wt = meta["steps"], meta["wall_time"]
        for w in meta["warnings"]:
            print(f"warning:  {w}", file=sys.stderr)
        for n in meta["notes"]:
            print(f"note:     {n}", file=sys.stderr)
        print(f"scene:    {meta['scene']}")
        print(f"master:   {meta['master']['algorithm']}, extrapolation {meta['master']['extrapolation']}, "
              f"{meta['master']['step_control']} step")
        print(f"steps:    {st['accepted']} accepted, {st['rejected_error']} rejected (error), "
              f"{st['rejected_failure']} rejected (discard / non-finite)")
        fmus = ", ".join(f"{n} {t:.3f} s" for n, t in wt["fmus"].items())
        print(f"time:     {wt['total']:.3f} s (master {wt['master']:.3f} s; {fmus})")
        if result.csv_path is not None:
            print(f"results:  {result.csv_path}")
        print(f"metadata: {result.metadata_path}")
        if plan is not None:
            from tribocosim.cosim.studies.steady_state import strip_mu_bars

            for name, mu in strip_mu_bars(plan.scene, result):
                print(f"mu_bar:   {mu:.4f}   ({name}.pull_force / (2 normal_force), last 20 % of the run)")
    return 0


def _kept(result) -> str:
    """How much of a run a result holds: its rows and the time of the last."""
    rows = len(result.time)
    return f"{rows} row{'s' if rows != 1 else ''} up to t = {result.time[-1]:.9g} s" if rows else "no rows"


def _written(result) -> str:
    return ", ".join(str(p) for p in (result.csv_path, result.metadata_path) if p is not None)


def _plot(args, result):
    """The PNG of the recorded variables when --plot asks for it (None otherwise)."""
    if not args.plot or result.csv_path is None:
        return None
    from tribocosim.cosim.studies.plotting import plot_result

    return plot_result(result, result.csv_path.with_suffix(".png"))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
