"""Parameter sweeps and chained passes over a base scene, run in parallel processes.

A sweep file (TOML, with a ``[sweep]`` table; ``tribocosim run SWEEP.toml`` recognises it) names a
base scene and what to vary::

    [sweep]
    scene = "demo.toml"          # base scene: a file relative to this one, or a packaged scene by name
    passes = 1                   # > 1: chained passes over the same strip (see below)
    field_instance = "strip"     # the StripDraw instance whose beta field is recorded / handed over
    field_interval = 0.02        # [s] between recorded field rows (0: every step); needs field_instance
    workers = 0                  # processes (0: one per CPU, at most one per case)

    [sweep.variables]            # the grid: every combination, in this order (first varies slowest)
    tool_length = [0.035, 0.07, 0.14]
    pressure_mpa = [1, 5, 10, 30]

    [sweep.set]                  # scene keys (dotted) set in every case: a value, or {expr = "..."}
    "experiment.step" = 2e-3
    "fmus.strip.parameters.tool_length" = { expr = "tool_length" }
    "fmus.press.parameters.force_setpoint" = { expr = "pressure_mpa * 1e6 * tool_length * 0.035" }

    [sweep.summary]              # one number per run: the mean (or std) of an expression of the
    mu_bar = { mean = "strip.pull_force / (2 * press.normal_force)", last = 0.2 }   # recorded columns
    mu_std = { std = "strip.pull_force / (2 * press.normal_force)", last = 0.2 }    # over the last
    beta = { final = "strip.beta_mean" }                                            # 20 %, or the end

    [sweep.plot]                 # --plot: summary y against variable x, one curve per series
    x = "pressure_mpa"
    y = "mu_bar"
    series = "tool_length"
    maps = { pressure_mpa = 30 } # also beta(X, t) maps of the cases matching these values
    flag = "mu_std"              # hollow markers where this summary exceeds 5 % of y (not steady)

Expressions are arithmetic (``+ - * / **``, parentheses, numbers, ``abs``/``min``/``max``) of the
sweep variables (in ``[sweep.set]``) or of the recorded columns ``instance.variable`` (in
``[sweep.summary]``); nothing else is evaluated.

Passes (paper Fig. 2b): with ``passes = n`` every case is a chain of n runs of the scene; pass
k + 1 starts from the debris field pass k left on the strip (the StripDraw FMU's ``field_input``
reads the ``field_output`` file of the previous pass), with the machine and press started afresh,
as when the strip is drawn again without cleaning.

Output folder: ``cases/case-NNN/`` per case (the run's CSV and JSON per pass, the field files,
``summary.json`` written last and atomically: a case with a ``summary.json`` of the same settings
is not run again, so an interrupted sweep resumes), then ``sweep.csv`` (one row per case and
pass: the variables, ``pass``, the summaries, then what the run counted (:func:`run_counts`): ``warnings``, the
FMUs' warning messages, and the outputs the components watch at the end of a run, e.g.
``strip.table_clamp_count``, the friction-table lookups outside the table's axes), ``sweep.json`` and, with
``--plot``, ``sweep.png`` (the runs with a count above 0 marked) and ``maps.png``. A run that warned or read the
table outside its axes rests on values the model or its table does not cover: ``tribocosim run`` says how many did.

Cases run in the local worker processes of :class:`tribocosim.surrogate.executors.ProcessPoolCaseExecutor`
(spawned, so no FMU is ever forked; they ignore SIGINT and SIGTERM and die with the sweep); the FMUs are built or
found in the cache once, before the workers start. A SIGINT or SIGTERM (:mod:`tribocosim.interrupt`) stops the
sweep: the finished cases are kept, the workers and their cases in progress killed (a rerun resumes).
"""

from __future__ import annotations

import ast
import hashlib
import itertools
import json
import math
import operator
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from tribocosim.atomic import write_text
from tribocosim.errors import Interrupted, RunInterrupted, SceneError, SweepInterrupted
from tribocosim.interrupt import raise_if_stopped

_SWEEP_KEYS = ("scene", "title", "passes", "field_instance", "field_interval", "workers", "variables", "set",
               "summary", "plot")
_PLOT_KEYS = ("x", "y", "series", "maps", "xlabel", "ylabel", "title", "flag")


# ------------------------------------------------------------------ safe arithmetic
_BIN = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
        ast.Pow: operator.pow}
_UN = {ast.USub: operator.neg, ast.UAdd: operator.pos}
_FUNCS = {"abs": np.abs, "min": np.minimum, "max": np.maximum}


class Expression:
    """An arithmetic expression of named values (``name`` or ``instance.variable``)."""

    def __init__(self, text: str) -> None:
        self.text = text
        try:
            self._tree = ast.parse(text, mode="eval").body
        except SyntaxError as exc:
            raise ValueError(f"not an expression: {exc.msg}") from None
        self.names = set()
        self._check(self._tree)

    def _check(self, node) -> None:
        if isinstance(node, ast.BinOp) and type(node.op) in _BIN:
            self._check(node.left)
            self._check(node.right)
        elif isinstance(node, ast.UnaryOp) and type(node.op) in _UN:
            self._check(node.operand)
        elif isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
            pass
        elif isinstance(node, ast.Name):
            self.names.add(node.id)
        elif isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
            self.names.add(f"{node.value.id}.{node.attr}")
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in _FUNCS and not node.keywords:
            for a in node.args:
                self._check(a)
        else:
            raise ValueError(f"only + - * / **, numbers, names and abs/min/max are allowed, not {ast.unparse(node)!r}")

    def __call__(self, values: dict[str, Any]):
        return self._eval(self._tree, values)

    def _eval(self, node, values):
        if isinstance(node, ast.BinOp):
            return _BIN[type(node.op)](self._eval(node.left, values), self._eval(node.right, values))
        if isinstance(node, ast.UnaryOp):
            return _UN[type(node.op)](self._eval(node.operand, values))
        if isinstance(node, ast.Constant):
            return node.value
        if isinstance(node, ast.Call):
            return _FUNCS[node.func.id](*(self._eval(a, values) for a in node.args))
        name = node.id if isinstance(node, ast.Name) else f"{node.value.id}.{node.attr}"
        return values[name]


# ------------------------------------------------------------------ the sweep file
@dataclass(frozen=True)
class Summary:
    """One number per run: ``mean`` or ``std`` of an expression over the ``last`` fraction, or its ``final`` value."""

    name: str
    expression: Expression
    kind: str  # "mean" | "std" | "final"
    last: float = 0.2

    def evaluate(self, result) -> float:
        values = {"time": result.time, **result.columns}
        with np.errstate(divide="ignore", invalid="ignore"):
            y = np.broadcast_to(np.asarray(self.expression(values), dtype=float), result.time.shape)
        if self.kind == "final":
            return float(y[-1])
        t = result.time
        sel = t >= t[-1] - self.last * (t[-1] - t[0]) - 1e-12
        return float(np.std(y[sel]) if self.kind == "std" else np.mean(y[sel]))


@dataclass(frozen=True)
class Case:
    """One point of the grid: its variables and the scene overrides that make it."""

    index: int
    variables: dict[str, float]
    overrides: dict[str, Any]

    @property
    def name(self) -> str:
        return f"case-{self.index:03d}"


@dataclass
class Sweep:
    """A parsed sweep file."""

    path: Path
    scene: Path
    title: str
    passes: int
    field_instance: str | None
    field_interval: float
    workers: int
    variables: dict[str, list]
    settings: dict[str, Any]
    summaries: list[Summary]
    plot: dict[str, Any] = field(default_factory=dict)

    def cases(self) -> list[Case]:
        """The grid, first variable varying slowest."""
        names = list(self.variables)
        out = []
        for i, combo in enumerate(itertools.product(*(self.variables[n] for n in names))):
            values = dict(zip(names, combo))
            over = {k: (v(values) if isinstance(v, Expression) else v) for k, v in self.settings.items()}
            over = {k: (float(v) if isinstance(v, (np.floating, np.integer)) else v) for k, v in over.items()}
            out.append(Case(i, values, over))
        return out


def is_sweep_file(path: str | Path) -> bool:
    """True if ``path`` is a TOML file with a ``[sweep]`` table (False for scenes and unreadable files)."""
    from tribocosim.cosim.scene.schema import is_sweep, read_document

    return is_sweep(read_document(path))


def load_sweep(path: str | Path) -> Sweep:
    """Parse and check a sweep file; raise one SceneError listing every problem (file: key: message)."""
    from tribocosim.cosim.scene.problems import Problems

    path = Path(path).resolve()
    problems = Problems(path, "sweep")
    add = problems.add

    from tribocosim.cosim.scene.documents import TomlError, read_toml

    try:
        doc = read_toml(path)
    except (OSError, UnicodeDecodeError, TomlError) as exc:
        raise SceneError(f"sweep file {path}: cannot read: {exc}") from None
    for k in doc:
        if k != "sweep":
            add(k, "unknown top-level key in a sweep file (only [sweep] and its sub-tables)")
    s = doc.get("sweep", {})
    problems.unknown_keys(s, _SWEEP_KEYS, "sweep")
    scene = s.get("scene")
    if not isinstance(scene, str):
        add("sweep.scene", f"must name the base scene file, got {scene!r}")
        scene = ""
    scene_path = (path.parent / scene).resolve()
    if scene and not scene_path.exists():  # a packaged scene by name ("demo" or "demo.toml"), as tribocosim run takes
        from tribocosim.paths import SCENES_DIR

        packaged = SCENES_DIR / (scene if scene.endswith(".toml") else f"{scene}.toml")
        scene_path = packaged if "/" not in scene and packaged.is_file() else scene_path
    if scene and scene_path.is_dir():
        add("sweep.scene", f"{scene_path} is a folder, not a scene file")
    elif scene and not scene_path.is_file():
        add("sweep.scene", f"scene file not found: {scene_path}")
    passes = s.get("passes", 1)
    if isinstance(passes, bool) or not isinstance(passes, int) or passes < 1:
        add("sweep.passes", f"must be an integer >= 1, got {passes!r}")
        passes = 1
    finst = s.get("field_instance")
    if finst is not None and not isinstance(finst, str):
        add("sweep.field_instance", f"must be an instance name, got {finst!r}")
        finst = None
    if passes > 1 and finst is None:
        add("sweep.field_instance", "passes > 1 hands the debris field over: name the StripDraw instance")
    fint = s.get("field_interval", 0.0)
    if isinstance(fint, bool) or not isinstance(fint, (int, float)) or not fint >= 0:
        add("sweep.field_interval", f"must be a number >= 0 [s], got {fint!r}")
        fint = 0.0
    workers = s.get("workers", 0)
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 0:
        add("sweep.workers", f"must be an integer >= 0 (0: one per CPU), got {workers!r}")
        workers = 0
    variables = {}
    for name, values in (s.get("variables") or {}).items():
        if not name.isidentifier():
            add(f"sweep.variables.{name}", "variable names must be identifiers")
        elif not (isinstance(values, list) and values and all(isinstance(v, (int, float, str)) and not isinstance(v, bool)
                                                            for v in values)):
            add(f"sweep.variables.{name}", f"must be a non-empty list of numbers or strings, got {values!r}")
        else:
            variables[name] = values
    settings: dict[str, Any] = {}
    for key, value in (s.get("set") or {}).items():
        if isinstance(value, dict):
            if set(value) != {"expr"} or not isinstance(value["expr"], str):
                add(f"sweep.set.{key}", f"a table here must be {{ expr = \"...\" }}, got {value!r}")
                continue
            try:
                e = Expression(value["expr"])
            except ValueError as exc:
                add(f"sweep.set.{key}", str(exc))
                continue
            unknown = sorted(e.names - set(variables))
            if unknown:
                add(f"sweep.set.{key}", f"unknown variables {unknown}; known: {', '.join(variables) or '(none)'}")
                continue
            settings[key] = e
        else:
            settings[key] = value
    summaries = []
    for name, spec in (s.get("summary") or {}).items():
        kinds = [k for k in ("mean", "std", "final") if k in (spec if isinstance(spec, dict) else {})]
        if not isinstance(spec, dict) or len(kinds) != 1 or set(spec) - {"mean", "std", "final", "last"}:
            add(f"sweep.summary.{name}", f"must be {{ mean = \"expr\", last = 0.2 }}, {{ std = \"expr\", last = 0.2 }} "
                f"or {{ final = \"expr\" }}, got {spec!r}")
            continue
        last = spec.get("last", 0.2)
        if isinstance(last, bool) or not isinstance(last, (int, float)) or not 0 < last <= 1:
            add(f"sweep.summary.{name}.last", f"must be a fraction in (0, 1], got {last!r}")
            continue
        try:
            summaries.append(Summary(name, Expression(str(spec[kinds[0]])), kinds[0], float(last)))
        except ValueError as exc:
            add(f"sweep.summary.{name}", str(exc))
    if not summaries:
        add("sweep.summary", "give at least one summary, e.g. mu_bar = { mean = \"strip.mu_mean\", last = 0.2 }")
    plot = s.get("plot") or {}
    problems.unknown_keys(plot, _PLOT_KEYS, "sweep.plot")
    axes = set(variables) | {"pass"}
    for k in ("x", "series"):
        if k in plot and plot[k] not in axes:
            add(f"sweep.plot.{k}", f"{plot[k]!r} is not a sweep variable; known: {', '.join(sorted(axes))}")
    for k in ("y", "flag"):
        if k in plot and plot[k] not in {x.name for x in summaries}:
            add(f"sweep.plot.{k}", f"{plot[k]!r} is not a summary; known: {', '.join(x.name for x in summaries)}")
    if "maps" in plot and (not isinstance(plot["maps"], dict) or set(plot["maps"]) - set(variables) or finst is None):
        add("sweep.plot.maps", "must be { variable = value, ... } of sweep variables, and needs field_instance")
    problems.raise_if_any()
    title = s.get("title") or path.stem
    return Sweep(path, scene_path, str(title), passes, finst, float(fint), workers, variables, settings, summaries, plot)


# ------------------------------------------------------------------ running
#: the layout of a case's summary rows (in its key: a case summarised in another layout runs again)
ROW_FORMAT = 2


def _case_key(sweep: Sweep, case: Case, plan, folder: Path) -> str:
    """What a finished case depends on: the scene text, the case's settings, and the bytes of every
    FMU the scene loads and of every file a parameter names (a friction table, say), except the
    case's own files in ``folder``; a rebuilt FMU or a changed table makes the case run again."""
    deps = {}
    own = folder.resolve()
    for name, model in plan.fmus.items():
        deps[f"fmus.{name}"] = file_digest(model.path)
        for pname, value in plan.scene.fmus[name].parameters.items():
            if not (isinstance(value, str) and value and Path(value).is_absolute() and Path(value).is_file()):
                continue
            if Path(value).resolve().is_relative_to(own):  # field files the case itself writes
                continue
            deps[f"fmus.{name}.parameters.{pname}"] = file_digest(Path(value))
    blob = json.dumps({"format": ROW_FORMAT, "scene": sweep.scene.read_text(encoding="utf-8"),
                       "overrides": case.overrides, "passes": sweep.passes,
                       "field": [sweep.field_instance, sweep.field_interval],
                       "summaries": [(x.name, x.expression.text, x.kind, x.last) for x in sweep.summaries],
                       "dependencies": deps}, sort_keys=True, default=str)
    return hashlib.sha256(blob.encode()).hexdigest()


#: (path, size, mtime) -> SHA-256 of the file, for the life of the process
_DIGESTS: dict[tuple[str, int, int], str] = {}


def file_digest(path: Path) -> str:
    """SHA-256 of a file's bytes (cached per process by path, size and modification time)."""
    st = Path(path).stat()
    key = (str(Path(path).resolve()), st.st_size, st.st_mtime_ns)
    if key not in _DIGESTS:
        _DIGESTS[key] = hashlib.sha256(Path(path).read_bytes()).hexdigest()
    return _DIGESTS[key]


def pass_overrides(sweep: Sweep, case: Case, folder: Path, k: int) -> dict:
    """The overrides of pass ``k`` (1-based) of ``case``: the case's, plus the field files."""
    over = dict(case.overrides)
    if sweep.field_instance:
        base = f"fmus.{sweep.field_instance}.parameters"
        over[f"{base}.field_output"] = str(folder / f"pass-{k}.field.csv")
        over[f"{base}.field_output_interval"] = sweep.field_interval
        if k > 1:
            over[f"{base}.field_input"] = str(folder / f"pass-{k - 1}.field.csv")
    return over


def run_case(sweep: Sweep, case: Case, out: Path) -> list[dict]:
    """Run every pass of one case in this process; write and return its summary rows."""
    from tribocosim.cosim.api import run
    from tribocosim.cosim.scene.validate import load_scene

    folder = out / "cases" / case.name
    done = folder / "summary.json"
    key = _case_key(sweep, case, load_scene(sweep.scene, pass_overrides(sweep, case, folder, 1)), folder)
    if done.is_file():
        try:
            old = json.loads(done.read_text())
            if old.get("key") == key:
                return old["rows"]
        except (OSError, ValueError):
            pass
    folder.mkdir(parents=True, exist_ok=True)
    rows = []
    for k in range(1, sweep.passes + 1):
        plan = load_scene(sweep.scene, pass_overrides(sweep, case, folder, k))
        t0 = time.perf_counter()
        result = run(plan, folder / f"pass-{k}", write=True)
        row = {**case.variables, "pass": k}
        row.update({x.name: x.evaluate(result) for x in sweep.summaries})
        row.update(run_counts(result.metadata))
        row["wall_time"] = time.perf_counter() - t0
        rows.append(row)
    write_text(done, json.dumps({"key": key, "case": case.name, "variables": case.variables,
                                 "overrides": case.overrides, "rows": rows}, indent=2, default=str))
    return rows


def run_counts(metadata: dict) -> dict:
    """What a run's metadata counts that a sweep's summary shows per case: ``warnings``, the messages its FMUs logged
    as warnings or worse (the strip leaving its valid range: a grip moving back, a draw past its length), and the
    value of every output its components watch at the end of a run (``instance.output``: the strip's
    ``table_clamp_count``, its friction-table lookups outside the table's axes). Above 0, the case's summaries rest
    on values outside what the model or its table covers."""
    return {"warnings": int(sum(metadata.get("fmu_warnings", {}).values())),
            **{name: int(value) for name, value in metadata.get("end_checks", {}).items()}}


def count_columns(sweep: Sweep, rows: list[dict]) -> list[str]:
    """The columns of :func:`run_counts` in the sweep's rows (those that are neither a variable, ``pass``, a summary
    nor ``wall_time``)."""
    other = {*sweep.variables, "pass", *(x.name for x in sweep.summaries), "wall_time"}
    return [n for n in (rows[0] if rows else {}) if n not in other]


def _worker(payload: tuple[str, int, str]) -> list[dict]:
    sweep_path, index, out = payload
    sweep = load_sweep(sweep_path)
    return run_case(sweep, sweep.cases()[index], Path(out))


@dataclass
class SweepResult:
    """Rows (one per case and pass) and where they were written."""

    sweep: Sweep
    rows: list[dict]
    csv_path: Path
    json_path: Path
    wall_time: float
    plots: list[Path] = field(default_factory=list)
    #: the columns of :func:`run_counts` (``warnings``, the end checks): a row with one above 0 is marked
    counts: list[str] = field(default_factory=list)
    #: the unit of each column whose unit the FMUs declare (:func:`column_units`)
    units: dict[str, str] = field(default_factory=dict)

    def marked(self) -> list[dict]:
        """The rows (runs) with warnings or with lookups outside the friction table (any count above 0)."""
        return [r for r in self.rows if any(r[c] for c in self.counts)]

    def column(self, name: str) -> np.ndarray:
        return np.array([r[name] for r in self.rows])


def run_sweep(path: str | Path, out: str | Path | None = None, *, workers: int | None = None,
              plot: bool = False, progress=None) -> SweepResult:
    """Run a sweep file: every case (in parallel processes), then the table and, optionally, the plots.

    Parameters
    ----------
    path : str or Path
        The sweep file.
    out : str or Path, optional
        Output folder; default ``./<sweep file stem>``.
    workers : int, optional
        Processes; default the file's ``workers`` (0: one per CPU), never more than cases.
    plot : bool
        Also write ``sweep.png`` (and ``maps.png`` when ``[sweep.plot] maps`` is given).
    progress : callable, optional
        ``progress(done, total, rows)`` after each finished case.

    Raises
    ------
    SceneError
        For problems in the sweep file or in the scene of any case (all checked before running).
    """
    from tribocosim.cosim.scene.problems import Problems
    from tribocosim.cosim.scene.validate import load_scene

    sweep = load_sweep(path)
    out = Path(out) if out is not None else Path.cwd() / sweep.path.stem
    out.mkdir(parents=True, exist_ok=True)
    cases = sweep.cases()
    problems = Problems(sweep.path, "sweep")
    first = None
    for case in cases:  # every case checked before any runs (the first builds the FMUs); a later pass's
        try:            # field_input is the file its previous pass writes
            plan = load_scene(sweep.scene, pass_overrides(sweep, case, out / "cases" / case.name, 1))
            first = first or plan
        except SceneError as exc:
            for p in exc.problems or [None]:
                problems.add(f"{case.name}" + (f": {p.key}" if p else ""),
                             f"{p.message if p else exc} (case {case.variables}, scene {sweep.scene})")
    problems.raise_if_any()
    n = workers if workers is not None else sweep.workers
    n = max(1, min(n or os.cpu_count() or 1, len(cases)))
    t0 = time.perf_counter()
    by_case: dict[int, list[dict]] = {}
    failures: list[tuple[int, BaseException]] = []
    try:
        if n == 1:
            for case in cases:
                raise_if_stopped(Interrupted)
                by_case[case.index] = run_case(sweep, case, out)
                if progress:
                    progress(len(by_case), len(cases), by_case[case.index])
        else:
            from tribocosim.surrogate.executors import ProcessPoolCaseExecutor  # not on the path of a single run

            items = [(c.index, (str(sweep.path), c.index, str(out))) for c in cases]
            for index, outcome in ProcessPoolCaseExecutor(n).map_unordered(_worker, items):
                if isinstance(outcome, BaseException):
                    failures.append((index, outcome))
                    continue
                by_case[index] = outcome
                if progress:
                    progress(len(by_case), len(cases), outcome)
    except (Interrupted, RunInterrupted) as exc:  # the cases finished before the signal are on disk
        from tribocosim.interrupt import signal_name

        raise SweepInterrupted(f"stopped by {signal_name(exc.signum)}", exc.signum, len(by_case), len(cases)) from None
    if failures:  # every other case finished and is kept; the first failure stops the sweep
        index, exc = min(failures, key=lambda f: f[0])
        raise exc
    rows = [r for i in sorted(by_case) for r in by_case[i]]
    wall = time.perf_counter() - t0
    counts = count_columns(sweep, rows)
    names = list(rows[0])
    csv_path = out / "sweep.csv"
    lines = [",".join(f'"{n}"' for n in names)]
    lines += [",".join(repr(r[n]) if not isinstance(r[n], str) else f'"{r[n]}"' for n in names) for r in rows]
    csv_path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    json_path = out / "sweep.json"
    marked = [r for r in rows if any(r[c] for c in counts)]
    json_path.write_text(json.dumps({"sweep": str(sweep.path), "scene": str(sweep.scene), "cases": len(cases),
                                     "passes": sweep.passes, "workers": n, "wall_time": wall,
                                     "counts": {c: sum(r[c] for r in rows) for c in counts},
                                     "runs_with_warnings_or_clamps": len(marked), "rows": rows},
                                    indent=2, default=str), encoding="utf-8")
    result = SweepResult(sweep, rows, csv_path, json_path, wall, counts=counts, units=column_units(sweep, first))
    if plot:
        from tribocosim.cosim.studies.plotting import plot_beta_maps, plot_sweep

        result.plots.append(plot_sweep(result, out / "sweep.png"))
        maps = sweep.plot.get("maps")
        if maps:
            chosen = [c for c in cases if all(_same(c.variables[k], v) for k, v in maps.items())]
            files, labels = [], []
            for c in chosen:
                for k in range(1, sweep.passes + 1):
                    files.append(out / "cases" / c.name / f"pass-{k}.field.csv")
                    free = {n: v for n, v in c.variables.items() if n not in maps}
                    labels.append(", ".join([f"{n} = {v:g}" if not isinstance(v, str) else f"{n} = {v}"
                                             for n, v in free.items()] + ([f"pass {k}"] if sweep.passes > 1 else [])))
            mu_name = sweep.plot.get("y")
            mus = [r.get(mu_name) for c in chosen for r in by_case[c.index]] if mu_name else None
            result.plots.append(plot_beta_maps(files, labels, out / "maps.png", mu_bar=mus,
                                               title=f"{sweep.title}: beta(X, t) at "
                                               + ", ".join(f"{k} = {v}" for k, v in maps.items())))
    return result


def column_units(sweep: Sweep, plan) -> dict[str, str]:
    """The units of a sweep's columns that the FMUs declare: a variable set as it is to one FMU parameter
    (``"fmus.I.parameters.P" = { expr = "v" }``) has P's unit, a summary of one recorded variable (``mean``, ``std``
    or ``final`` of ``"I.V"``) V's; the others (an expression of several, or of a variable with a factor) none."""
    from tribocosim.cosim.scene.validate import unit_of

    def unit(inst, var):
        model = plan.fmus.get(inst)
        v = model.variables.get(var) if model is not None else None
        return unit_of(v) or "" if v is not None else ""

    out = {}
    for key, value in sweep.settings.items():
        parts = key.split(".")
        if isinstance(value, Expression) and len(parts) == 4 and parts[0] == "fmus" and parts[2] == "parameters" \
                and value.text.strip() in sweep.variables:
            out[value.text.strip()] = unit(parts[1], parts[3])
    for s in sweep.summaries:
        text = s.expression.text.strip()
        if text.count(".") == 1 and text.replace(".", "").replace("_", "").isalnum():
            out[s.name] = unit(*text.split("."))
    return out


def _same(a, b) -> bool:
    if isinstance(a, str) or isinstance(b, str):
        return a == b
    return math.isclose(float(a), float(b), rel_tol=1e-9)


def main(args) -> int:
    """``tribocosim run SWEEP.toml [--out DIR] [--plot] [--quiet] [--workers N]`` (from
    :mod:`tribocosim.cosim.apps.run_cli`, which maps a SceneError to exit 2). A signal stops it (exit 128 + its number) with its finished cases kept."""
    import sys

    def progress(done, total, rows):
        if not args.quiet:
            what = ", ".join(f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}" for k, v in rows[-1].items()
                             if k != "wall_time")
            print(f"[{done}/{total}] {what}", file=sys.stderr, flush=True)

    try:
        res = run_sweep(args.scene, args.out, workers=getattr(args, "workers", None), plot=args.plot,
                        progress=progress)
    except SweepInterrupted as exc:
        out = Path(args.out) if args.out is not None else Path.cwd() / Path(args.scene).stem
        print(f"tribocosim run: {exc}: {exc.finished} of {exc.total} cases are finished and kept in {out / 'cases'} "
              "(the cases in progress were discarded); run the same command again to resume", file=sys.stderr)
        return 128 + exc.signum
    marked = res.marked()
    if marked:
        total = {c: sum(r[c] for r in res.rows) for c in res.counts}
        what = ", ".join(f"{v} {c}" for c, v in total.items() if v)
        print(f"warning:  {len(marked)} of {len(res.rows)} runs warned or read the friction table outside its axes "
              f"({what}): their summaries rest on values the model or its table does not cover (columns "
              f"{', '.join(res.counts)} of {res.csv_path.name}; marked in the plot)", file=sys.stderr)
    if not args.quiet:
        s = res.sweep
        print(f"sweep:    {s.path} ({len(s.cases())} cases x {s.passes} pass(es), base scene {s.scene.name})")
        print(f"time:     {res.wall_time:.1f} s")
        print(f"table:    {res.csv_path}")
        for p in res.plots:
            print(f"plot:     {p}")
    return 0
