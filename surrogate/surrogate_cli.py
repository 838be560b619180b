"""``tribocosim surrogate``: mesoscale campaigns and the friction table.

Subcommands::

    tribocosim surrogate build (--sweep FILE | --preset NAME) --out DIR [--workers N]
                               [--scheduler tcp://HOST:PORT] [--table PATH] [--no-retry-failed] [--quiet]
    tribocosim surrogate table --out DIR [--table PATH]   # fits + table from the finished cases only
    tribocosim surrogate show TABLE [--plot PNG | --no-plot]
    tribocosim surrogate compare TABLE_A TABLE_B          # node by node, against their standard errors
    tribocosim surrogate verify TABLE [--budget-s S] [--workers N]   # rerun a sample of its recorded cases
    tribocosim surrogate presets                          # list the presets

``build`` runs every unfinished case (a rerun resumes an interrupted campaign and retries failed
cases), then fits and writes the table (default ``DIR/friction_table.npz``) and ``DIR/fits.json``.
Exit status: 0 on success; 1 on bad input or when cases failed (the table is still written when
every grid point has a finished case); 2 on usage errors.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from tribocosim.errors import TribocosimError

PROG = "tribocosim surrogate"


def _usage() -> str:
    return (f"usage: {PROG} {{build,table,show,compare,verify,presets}} [ARGS...]\n\n"
            "  build    run a campaign (sweep file or preset), fit, write the friction table\n"
            "  table    fit and write the table from the finished cases of a campaign folder\n"
            "  show     print a table's summary and plot mu vs P per beta\n"
            "  compare  compare two tables node by node against their recorded uncertainty\n"
            "  verify   rerun a sample of a table's recorded cases and compare with the recorded results\n"
            "  presets  list the sweep presets\n")


def _make_table(out: Path, table_path: Path | None, campaign_info: dict | None = None) -> int:
    from tribocosim.components.stripdraw.table import read_table, write_table

    from .campaign import load_records, write_json
    from .table_build import build_table, describe, json_clean

    manifest, done, failed = load_records(out)
    table, fits = build_table(done, manifest, failed=failed, campaign_info=campaign_info)
    path = table_path or out / "friction_table.npz"
    path.parent.mkdir(parents=True, exist_ok=True)
    digest = write_table(path, table)
    write_json(out / "fits.json", json_clean({"table": str(path), "content_hash": digest, **fits}))

    print(describe(read_table(path)))
    print(f"wrote {path} (sha256 {digest[:16]}...)")
    if failed:
        print(f"{PROG}: warning: {len(failed)} case(s) failed or are missing; the table uses the "
              f"remaining members (see {out / 'cases'}/*.error.json)", file=sys.stderr)
        return 1
    return 0


def _build(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(prog=f"{PROG} build", description="run a campaign and build the table")
    src = ap.add_mutually_exclusive_group(required=True)
    src.add_argument("--sweep", help="sweep definition (TOML)")
    src.add_argument("--preset", help="a preset sweep (see 'presets'): quick, paper, ...")
    ap.add_argument("--out", required=True, help="campaign folder (cases, fits, table)")
    ap.add_argument("--workers", type=int, default=None, help="local worker processes (default: CPUs)")
    ap.add_argument("--scheduler", default=None, help="Dask scheduler address tcp://HOST:PORT")
    ap.add_argument("--table", default=None, help="table path (default OUT/friction_table.npz)")
    ap.add_argument("--no-retry-failed", action="store_true", help="leave earlier failed cases alone")
    ap.add_argument("--no-table", action="store_true", help="run the cases only")
    ap.add_argument("--quiet", action="store_true", help="no progress bar")
    args = ap.parse_args(argv)

    from .campaign import run_sweep
    from .executors import make_executor
    from .sweep import load_preset, load_sweep

    try:
        sweep = load_preset(args.preset) if args.preset else load_sweep(args.sweep)
        executor = make_executor(args.workers, args.scheduler)
    except TribocosimError as exc:
        print(f"{PROG} build: error: {exc}", file=sys.stderr)
        return 1
    out = Path(args.out)
    t0 = time.perf_counter()
    try:
        report = run_sweep(sweep, out, executor, retry_failed=not args.no_retry_failed,
                           progress=not args.quiet)
    finally:
        executor.close()
    print(report.summary(), file=sys.stderr)
    from .campaign import case_cpu_seconds, load_records

    done = load_records(out)[1]
    print(f"campaign cost: {case_cpu_seconds(done) / 3600:.3g} core-hours in {len(done)} finished cases "
          f"(the sum of their wall times; this run {report.wall_s / 3600:.3g} h on {report.executor})", file=sys.stderr)
    if args.no_table:
        return 1 if report.failed else 0
    info = {"executor": report.executor, "campaign_wall_s": report.wall_s,
            "cases_computed_this_run": len(report.computed),
            "cases_skipped_this_run": len(report.skipped)}
    try:
        status = _make_table(out, Path(args.table) if args.table else None, info)
    except TribocosimError as exc:
        print(f"{PROG} build: error: {exc}", file=sys.stderr)
        return 1
    print(f"build wall time {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    return 1 if report.failed else status


def _table(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(prog=f"{PROG} table", description="fits and table from finished cases")
    ap.add_argument("--out", required=True, help="campaign folder")
    ap.add_argument("--table", default=None, help="table path (default OUT/friction_table.npz)")
    args = ap.parse_args(argv)
    try:
        return _make_table(Path(args.out), Path(args.table) if args.table else None)
    except TribocosimError as exc:
        print(f"{PROG} table: error: {exc}", file=sys.stderr)
        return 1


def _show(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(prog=f"{PROG} show", description="summary and mu-vs-P plot of a table")
    ap.add_argument("table", help="friction table (.npz)")
    ap.add_argument("--plot", default=None, help="PNG path (default ./<table stem>_mu_vs_P.png)")
    ap.add_argument("--no-plot", action="store_true")
    args = ap.parse_args(argv)
    from tribocosim.components.stripdraw.table import read_table

    from .table_build import describe, plot_table

    try:
        table = read_table(args.table)
    except TribocosimError as exc:
        print(f"{PROG} show: error: {exc}", file=sys.stderr)
        return 1
    print(describe(table))
    if not args.no_plot:
        png = Path(args.plot) if args.plot else Path(f"{Path(args.table).stem}_mu_vs_P.png")
        plot_table(table, png)
        print(f"plot: {png}")
    return 0


def _compare(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(prog=f"{PROG} compare",
                                 description="compare two tables against A's recorded ensemble std")
    ap.add_argument("a")
    ap.add_argument("b")
    args = ap.parse_args(argv)
    from tribocosim.components.stripdraw.table import read_table

    from .table_build import compare_tables

    try:
        res = compare_tables(read_table(args.a), read_table(args.b))
    except TribocosimError as exc:
        print(f"{PROG} compare: error: {exc}", file=sys.stderr)
        return 1
    print(json.dumps(res, indent=2))
    return 0 if res["within_uncertainty"] else 1


def _verify(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(prog=f"{PROG} verify",
                                 description="rerun a sample of a table's recorded cases and compare")
    ap.add_argument("table", help="friction table (.npz) with its campaign in the metadata")
    ap.add_argument("--budget-s", type=float, default=300.0,
                    help="recorded wall seconds the sample may add up to (default 300)")
    ap.add_argument("--workers", type=int, default=None, help="local worker processes (default: CPUs)")
    ap.add_argument("--json", default=None, help="write the per-case results here")
    args = ap.parse_args(argv)
    from tribocosim.components.stripdraw.table import read_table

    from .campaign import write_json
    from .executors import make_executor
    from .table_build import json_clean
    from .verify import recorded_cases, sample_cases, verify_cases

    t0 = time.perf_counter()
    try:
        table = read_table(args.table)
        sample = sample_cases(recorded_cases(table), args.budget_s)
        n = table.metadata["campaign"]["sweep"]["slide"].get("n", 256)
        executor = make_executor(args.workers)
        try:
            results = verify_cases(sample, executor, 1.0 / (n * n))
        finally:
            executor.close()
    except TribocosimError as exc:
        print(f"{PROG} verify: error: {exc}", file=sys.stderr)
        return 1
    for r in results:
        lab = r["labels"]
        diff = " ".join(f"{k} {v:.2e}/{r['tolerance'][k]:.2e}" for k, v in r.get("abs_diff", {}).items())
        print(f"{r['verdict']:<13} P = {lab['pressure'] / 1e6:g} MPa, v = {lab['velocity']:g} m/s, beta = "
              f"{lab['beta']:.4g}, surface {lab['surface']}, seed {lab['seed']}: |diff|/tolerance {diff}"
              + (f" error: {r['error']}" if "error" in r else ""))
    bad = [r for r in results if r["verdict"] == "differs"]
    print(f"{PROG} verify: {len(results)} recorded cases rerun in {time.perf_counter() - t0:.1f} s: "
          f"{sum(r['verdict'] == 'identical' for r in results)} identical, "
          f"{sum(r['verdict'] == 'within_spread' for r in results)} within the ensemble spread, {len(bad)} differ")
    if args.json:
        write_json(Path(args.json), json_clean(results))
    return 1 if bad else 0


def _presets(argv: list[str]) -> int:
    from .campaign import expand_cases
    from .sweep import PRESET_DIR, load_sweep

    for path in sorted(PRESET_DIR.glob("*.toml")):
        sw = load_sweep(path)
        n = len(expand_cases(sw))
        print(f"{path.stem:<8} {n:>5} cases  {sw.description}")
    return 0


COMMANDS = {"build": _build, "table": _table, "show": _show, "compare": _compare, "verify": _verify,
            "presets": _presets}


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``tribocosim surrogate``."""
    args = list(sys.argv[1:] if argv is None else argv)
    if not args or args[0] in ("-h", "--help", "help"):
        print(_usage())
        return 0
    if args[0] not in COMMANDS:
        print(f"{PROG}: unknown subcommand {args[0]!r}; known: {', '.join(COMMANDS)}", file=sys.stderr)
        return 2
    try:
        return int(COMMANDS[args[0]](args[1:]) or 0)
    except SystemExit as exc:  # argparse
        return int(exc.code or 0)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
