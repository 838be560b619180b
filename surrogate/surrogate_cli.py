"""``tribocosim surrogate``: mesoscale campaigns and the friction table.

Subcommands::

    tribocosim surrogate build (--sweep FILE | --preset NAME) --out DIR [--workers N]
                               [--scheduler tcp://HOST:PORT] [--table PATH] [--no-retry-failed] [--allow-failed]
                               [--max-memory SIZE] [--quiet]
    tribocosim surrogate table --out DIR [--table PATH] [--allow-failed] [--max-memory SIZE]
                                                          # fits + table from the finished cases
    tribocosim surrogate show TABLE [--out DIR | --plot PNG | --no-plot]
    tribocosim surrogate compare TABLE_A TABLE_B          # node by node, against their standard errors
    tribocosim surrogate verify TABLE [--budget-s S] [--workers N]   # rerun a sample of its recorded cases
    tribocosim surrogate presets                          # list the presets

``build`` runs every unfinished case (a rerun resumes an interrupted campaign and retries failed
cases), then fits and writes the table (default ``DIR/friction_table.npz``) and ``DIR/fits.json``.
The table is written only when every case of the campaign is finished and intact (``--allow-failed``: from the
finished ones), to a temporary name that replaces the old table only once it reads back: a build or ``table``
that fails leaves the old table as it was. SIGINT (Ctrl-C) or SIGTERM stops ``build`` within a second: the cases
finished before it are kept, the slides in progress discarded (:mod:`tribocosim.interrupt`).
Before any case runs, ``build`` and ``verify`` estimate the memory of their local workers together (workers x the
peak of a case, :mod:`tribocosim.surrogate.memory`), and ``build`` and ``table`` that of the table build, and
refuse when it exceeds the memory available or ``--max-memory``.
Exit status, as every tribocosim command: 0 on success; 1 when the work ran and did not succeed: cases failed, are
missing or refused (no table is written then, unless ``--allow-failed``), ``verify`` found a rerun that differs,
``compare`` found the tables apart; 2 on bad input (usage, a file or a value that cannot be read or is not allowed)
and on a refusal for memory; 128 + the signal's number when a signal stopped it.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from tribocosim.errors import CampaignInterrupted, MemoryLimitError, TableError, TribocosimError

PROG = "tribocosim surrogate"
#: at most this many files are named per kind of unfinished case
LIST_MAX = 8


def _usage() -> str:
    return (f"usage: {PROG} {{build,table,show,compare,verify,presets}} [ARGS...]\n\n"
            "  build    run a campaign (sweep file or preset), fit, write the friction table\n"
            "  table    fit and write the table from the finished cases of a campaign folder\n"
            "  show     print a table's summary and plot mu vs P per beta\n"
            "  compare  compare two tables node by node against their recorded uncertainty\n"
            "  verify   rerun a sample of a table's recorded cases and compare with the recorded results\n"
            "  presets  list the sweep presets\n")


def _make_table(out: Path, table_path: Path | None, campaign_info: dict | None = None, *,
                allow_failed: bool = False, command: str = "table", max_memory: int | None = None) -> int:
    from tribocosim.components.stripdraw.table import read_table

    from .campaign import load_records
    from .case_record import DIGEST_KEY
    from .table_build import build_table, describe

    manifest, done, unfinished = load_records(out)
    _check_table_memory(manifest, max_memory)
    path = table_path or out / "friction_table.npz"
    legacy = sum(1 for r in done if DIGEST_KEY not in r)
    if legacy:
        print(f"{PROG} {command}: warning: {legacy} case record(s) carry no digest (written before case digests): "
              "checked against their series only", file=sys.stderr)
    if unfinished and not allow_failed:
        kept = f"{path} is left as it was" if path.exists() else f"{path} is not written"
        print(f"{PROG} {command}: error: {len(unfinished)} of {len(manifest['cases'])} cases of {out} are not "
              f"finished; no table is built ({kept}):\n" + _describe_unfinished(unfinished)
              + f"\nRun the campaign again (tribocosim surrogate build with its sweep and --out {out}: "
              + _what_a_rerun_does(unfinished) + "), or build the table from the finished cases with --allow-failed.",
              file=sys.stderr)
        return 1
    table, fits = build_table(done, manifest, failed=unfinished, campaign_info=campaign_info)
    digest = _write_table(path, table, out / "fits.json", fits)

    print(describe(read_table(path)))
    print(f"wrote {path} (sha256 {digest[:16]}...)")
    if unfinished:
        print(f"{PROG} {command}: warning: the table uses the finished cases only (--allow-failed); "
              f"{len(unfinished)} case(s) are not finished (listed in its metadata):\n"
              + _describe_unfinished(unfinished), file=sys.stderr)
    return 0


def _check_table_memory(manifest: dict, max_memory: int | None) -> None:
    """Refuse a table build whose surface statistics (every pair generated on the sweep's grid) exceed the limit."""
    from . import memory
    from .measured_surfaces import scan_points
    from .slide_config import SlideConfig

    sweep = manifest.get("sweep") or {}
    slide, worst, n = sweep.get("slide", {}), 0, 0
    for surf in sweep.get("surfaces", []):
        cfg = SlideConfig(**{**slide, **surf})
        files = [scan_points(getattr(cfg, f"{side}_file")) for side in ("sheet", "tool")
                 if getattr(cfg, f"{side}_file") is not None]
        size = memory.table_bytes(cfg.n, max(files, default=0), cfg.surface_periodization or "smooth")
        if size > worst:
            worst, n = size, cfg.n
    if worst:
        memory.check(memory.Need(f"the table build's surface statistics on the n = {n} grid", worst,
                                 memory.grids(n, memory.TABLE_PAIR_GRIDS)), max_memory, "a smaller grid")


def _check_campaign_memory(configs, n_cases: int, label: str, executor, max_memory: int | None) -> None:
    """Refuse a campaign whose local workers, each running a case, would exceed the limit together; on a Dask
    cluster (whose workers' memory is not known here) one case against ``--max-memory`` when it is given."""
    from . import memory

    case = memory.case_need(configs, label)
    workers = getattr(executor, "workers", None)
    if workers is None:
        if max_memory is not None:
            memory.check(case, max_memory, "a smaller grid")
        return
    memory.check(memory.workers_need(case, min(workers, max(n_cases, 1))), max_memory,
                 "fewer --workers or a smaller grid")


def _max_memory(ap: argparse.ArgumentParser) -> None:
    ap.add_argument("--max-memory", default=None, metavar="SIZE",
                    help="refuse when the estimated peak memory exceeds SIZE (e.g. 8G, 512M; powers of 1024) instead "
                         "of the memory available (MemAvailable)")


def _describe_unfinished(unfinished: list[dict]) -> str:
    """One block per kind of unfinished case (load_records' statuses), naming the files that exist."""
    lines = []
    failed = [u for u in unfinished if u.get("status") == "failed"]
    invalid = [u for u in unfinished if u.get("status") == "invalid"]
    missing = [u for u in unfinished if u.get("status") not in ("failed", "invalid")]
    if failed:
        lines.append(f"  {len(failed)} failed; the error of each is in its file:")
        lines += [f"    {u['file']}: {u.get('error', {}).get('type')}: {u.get('error', {}).get('message')}"
                  for u in failed[:LIST_MAX]]
    if invalid:
        lines.append(f"  {len(invalid)} refused (files that cannot be read or do not match their digest):")
        lines += [f"    {u['error']['message']}" for u in invalid[:LIST_MAX]]
    if missing:
        lines.append(f"  {len(missing)} missing (never computed, or stopped before they finished; no file): "
                     + ", ".join(u["case_id"] for u in missing[:LIST_MAX]))
    more = len(failed[LIST_MAX:]) + len(invalid[LIST_MAX:]) + len(missing[LIST_MAX:])
    if more:
        lines.append(f"  ({more} more not listed)")
    return "\n".join(lines)


def _what_a_rerun_does(unfinished: list[dict]) -> str:
    kinds = {u.get("status") for u in unfinished}
    parts = (["it computes the missing and refused cases"] if kinds - {"failed"} else []) + \
        (["it retries the failed ones unless --no-retry-failed"] if "failed" in kinds else [])
    return "; ".join(parts)


def _write_table(path: Path, table, fits_path: Path, fits: dict) -> str:
    """Write the table and its fits beside temporary names, read the table back (hash check), then rename both
    over the old files; on any error the old files stay as they were and no temporary file is left."""
    from tribocosim.components.stripdraw.table import read_table, write_table

    from .campaign import write_json
    from .table_build import json_clean

    from tribocosim.atomic import replaced

    path.parent.mkdir(parents=True, exist_ok=True)
    with replaced(fits_path) as fits_tmp, replaced(path, ".npz") as tmp:
        digest = write_table(tmp, table)
        read_table(tmp)
        write_json(fits_tmp, json_clean({"table": str(path), "content_hash": digest, **fits}))
    return digest


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
    ap.add_argument("--allow-failed", action="store_true",
                    help="build the table from the finished cases when others failed or are missing")
    ap.add_argument("--no-table", action="store_true", help="run the cases only")
    ap.add_argument("--quiet", action="store_true", help="no progress bar")
    _max_memory(ap)
    args = ap.parse_args(argv)

    from tribocosim import interrupt
    from . import memory
    from .campaign import case_cpu_seconds, expand_cases, load_records, run_sweep
    from .executors import make_executor
    from .sweep import load_preset, load_sweep

    try:
        sweep = load_preset(args.preset) if args.preset else load_sweep(args.sweep)
        limit = None if args.max_memory is None else memory.parse_bytes(args.max_memory)
        executor = make_executor(args.workers, args.scheduler)
        cases = expand_cases(sweep)
        pairs = {c.labels.get("surface"): c.config for c in cases}  # the grid and files of each surface pair
        _check_campaign_memory(list(pairs.values()), len(cases), f"sweep {sweep.name}", executor, limit)
    except MemoryLimitError as exc:
        print(f"{PROG} build: error: {exc}", file=sys.stderr)
        return 2
    except TribocosimError as exc:
        print(f"{PROG} build: error: {exc}", file=sys.stderr)
        return 2
    out = Path(args.out)
    t0 = time.perf_counter()
    with interrupt.stop_on_signals():
        try:
            try:
                report = run_sweep(sweep, out, executor, retry_failed=not args.no_retry_failed,
                                   progress=not args.quiet)
            finally:
                executor.close()
            interrupt.raise_if_stopped()
        except CampaignInterrupted as exc:
            return _interrupted(exc, out)
    print(report.summary(), file=sys.stderr)
    done = load_records(out)[1]
    print(f"campaign cost: {case_cpu_seconds(done) / 3600:.3g} core-hours in {len(done)} finished cases "
          f"(the sum of their wall times; this run {report.wall_s / 3600:.3g} h on {report.executor})", file=sys.stderr)
    if args.no_table:
        return 1 if report.failed else 0
    info = {"executor": report.executor, "campaign_wall_s": report.wall_s,
            "cases_computed_this_run": len(report.computed),
            "cases_skipped_this_run": len(report.skipped)}
    try:
        status = _make_table(out, Path(args.table) if args.table else None, info, allow_failed=args.allow_failed,
                             command="build", max_memory=limit)
    except MemoryLimitError as exc:
        print(f"{PROG} build: error: {exc}", file=sys.stderr)
        return 2
    except TribocosimError as exc:
        print(f"{PROG} build: error: {exc}", file=sys.stderr)
        return 1 if isinstance(exc, TableError) else 2  # the campaign's results make no table, or bad input
    print(f"build wall time {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    return status


def _interrupted(exc: CampaignInterrupted, out: Path) -> int:
    """Say what a stopped campaign keeps; the exit status 128 + the signal's number."""
    from .campaign import load_records

    report = getattr(exc, "report", None)
    try:
        manifest, done, _ = load_records(out)
        kept = f"{len(done)} of {len(manifest['cases'])} cases of {out} are finished and kept"
    except TribocosimError:
        kept = f"the finished cases in {out} are kept"
    this_run = f" ({len(report.computed)} computed in this run)" if report is not None else ""
    print(f"{PROG} build: {exc}: {kept}{this_run}; the slides in progress were discarded. Run the same command "
          "again to resume.", file=sys.stderr)
    return 128 + exc.signum


def _table(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(prog=f"{PROG} table", description="fits and table from finished cases")
    ap.add_argument("--out", required=True, help="campaign folder")
    ap.add_argument("--table", default=None, help="table path (default OUT/friction_table.npz)")
    ap.add_argument("--allow-failed", action="store_true",
                    help="build the table from the finished cases when others failed or are missing")
    _max_memory(ap)
    args = ap.parse_args(argv)
    from . import memory

    try:
        return _make_table(Path(args.out), Path(args.table) if args.table else None, allow_failed=args.allow_failed,
                           max_memory=None if args.max_memory is None else memory.parse_bytes(args.max_memory))
    except MemoryLimitError as exc:
        print(f"{PROG} table: error: {exc}", file=sys.stderr)
        return 2
    except TribocosimError as exc:
        print(f"{PROG} table: error: {exc}", file=sys.stderr)
        return 1 if isinstance(exc, TableError) else 2  # the campaign's results make no table, or bad input


def _show(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(prog=f"{PROG} show", description="summary and mu-vs-P plot of a table")
    ap.add_argument("table", help="friction table (.npz)")
    where = ap.add_mutually_exclusive_group()
    where.add_argument("--out", default=None, metavar="DIR",
                       help="folder of the plot <table stem>_mu_vs_P.png (default: the table's folder)")
    where.add_argument("--plot", default=None, metavar="PNG", help="the plot's file")
    where.add_argument("--no-plot", action="store_true")
    args = ap.parse_args(argv)
    from tribocosim.components.stripdraw.table import read_table
    from tribocosim.paths import MODELS_DIR

    from .table_build import describe, plot_table

    try:
        table = read_table(args.table)
    except TribocosimError as exc:
        print(f"{PROG} show: error: {exc}", file=sys.stderr)
        return 2
    print(describe(table))
    if args.no_plot:
        return 0
    name = f"{Path(args.table).stem}_mu_vs_P.png"
    if args.plot:
        png = Path(args.plot)
    elif args.out:
        png = Path(args.out) / name
    elif Path(args.table).resolve().parent == MODELS_DIR.resolve():  # the package's own folder: not a place to write
        print(f"{PROG} show: the plot is not written beside a table of the package ({MODELS_DIR}); --out DIR or "
              "--plot PNG writes it", file=sys.stderr)
        return 0
    else:
        png = Path(args.table).parent / name
    try:
        png.parent.mkdir(parents=True, exist_ok=True)
        plot_table(table, png)
    except OSError as exc:
        print(f"{PROG} show: error: cannot write the plot {png}: {exc.strerror or exc}", file=sys.stderr)
        return 2
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
        return 2
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
    _max_memory(ap)
    args = ap.parse_args(argv)
    from tribocosim.components.stripdraw.table import read_table

    from tribocosim import interrupt
    from . import memory
    from .campaign import write_json
    from .executors import make_executor
    from .table_build import json_clean
    from .verify import code_versions, numerics_of, recorded_cases, sample_cases, verify_cases

    t0 = time.perf_counter()
    with interrupt.stop_on_signals():
        try:
            table = read_table(args.table)
            sample = sample_cases(recorded_cases(table), args.budget_s)
            n = table.metadata["campaign"]["sweep"]["slide"].get("n", 256)
            executor = make_executor(args.workers)
            _check_campaign_memory([r.case.config for r in sample], len(sample), f"the sample of {args.table}", executor,
                                   None if args.max_memory is None else memory.parse_bytes(args.max_memory))
            try:
                results = verify_cases(sample, executor, 1.0 / (n * n), code_versions(table), numerics_of(table))
            finally:
                executor.close()
        except CampaignInterrupted as exc:
            print(f"{PROG} verify: {exc}; nothing compared", file=sys.stderr)
            return 128 + exc.signum
        except MemoryLimitError as exc:
            print(f"{PROG} verify: error: {exc}", file=sys.stderr)
            return 2
        except TribocosimError as exc:
            print(f"{PROG} verify: error: {exc}", file=sys.stderr)
            return 2
    for reason in dict.fromkeys(r["reason"] for r in results if "reason" in r):
        print(f"comparison: {reason}")
    for r in results:
        lab = r["labels"]
        diff = " ".join(f"{k} {v:.2e}/{r['tolerance'][k]:.2e}" for k, v in r.get("abs_diff", {}).items())
        print(f"{r['verdict']:<16} P = {lab['pressure'] / 1e6:g} MPa, v = {lab['velocity']:g} m/s, beta = "
              f"{lab['beta']:.4g}, surface {lab['surface']}, seed {lab['seed']}: |diff|/tolerance {diff}"
              + (f" error: {r['error']}" if "error" in r else ""))
    bad = [r for r in results if r["verdict"] == "differs"]
    print(f"{PROG} verify: {len(results)} recorded cases rerun in {time.perf_counter() - t0:.1f} s: "
          f"{sum(r['verdict'] == 'identical' for r in results)} identical, "
          f"{sum(r['verdict'] == 'within_tolerance' for r in results)} within the tolerance for another code "
          f"version, {len(bad)} differ")
    if args.json:
        write_json(Path(args.json), json_clean(results))
    return 1 if bad else 0


def _presets(argv: list[str]) -> int:
    """Each preset with its number of cases before adaptive placements, and the recorded cost of the table
    shipped from it (the sum of its cases' wall times)."""
    from .campaign import expand_cases
    from .sweep import PRESET_DIR, load_sweep

    shipped = _shipped_costs()
    for path in sorted(PRESET_DIR.glob("*.toml")):
        sw = load_sweep(path)
        n = len(expand_cases(sw))
        cases = f"{n:>5} cases" + (" + adaptive" if sw.adaptive is not None else "")
        print(f"{path.stem:<13} {cases:<21} {sw.description}")
        if sw.name in shipped:
            print(f"{'':<13} shipped as {shipped[sw.name]}")
    return 0


def _shipped_costs() -> dict:
    """Sweep name -> 'models/X.npz: N slides, H core-hours' of every table in models/ built from a campaign."""
    from tribocosim.components.stripdraw.table import read_table
    from tribocosim.paths import MODELS_DIR

    out = {}
    for path in sorted(MODELS_DIR.glob("*.npz")):
        try:
            meta = read_table(path).metadata
        except TribocosimError:
            continue
        name = meta.get("campaign", {}).get("sweep", {}).get("name")
        cases = meta.get("cases")
        if name and cases and name not in out:
            hours = sum(c.get("wall_s") or 0.0 for c in cases) / 3600
            out[name] = f"models/{path.name}: {len(cases)} slides, {hours:.3g} core-hours (recorded)"
    return out


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
    except KeyboardInterrupt:
        print(f"{PROG} {args[0]}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
