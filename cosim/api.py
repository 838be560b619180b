"""Python API: ``tribocosim.cosim.run(scene) -> Result``, and the assembly of a master from a scene.

:func:`run` loads a scene (:func:`tribocosim.cosim.scene.validate.load_scene`: parsed once, each value checked once),
runs it, and writes the CSV and the metadata JSON. A fixed-step Jacobi or Gauss-Seidel run with held coupling values
(the demo's) runs whole in the C master (:class:`~tribocosim.cosim.engine.native_session.NativeSession`: no numpy,
no fmpy on its path); every other run, and one the C master leaves to Python, runs the master of
:mod:`tribocosim.cosim.engine` that :func:`build` assembles from a validated
:class:`~tribocosim.cosim.scene.validate.Plan` (FMUs extracted and wrapped in
:class:`~tribocosim.cosim.engine.slave.FmpySlave`, links, algorithm, step controller, recorder). Both make the same
FMI calls, so their results are the same to the last bit. The command line (``tribocosim run``) is a thin layer over
:func:`run`. Nothing here knows a component: what a scene sets and what it watches at the end of a run is in the
plan.
"""

from __future__ import annotations

import hashlib
import json
import time
from pathlib import Path

from tribocosim.errors import ConvergenceError, CosimStepError, Interrupted, ParameterError, RunFailed, RunInterrupted
from tribocosim.cosim.engine.graph import gauss_seidel_order
from tribocosim.cosim.engine.schemes import LinkSpec
from tribocosim.cosim.scene.validate import Plan


class Result:
    """The outcome of a run.

    Attributes
    ----------
    time : ndarray
        Times of the recorded communication points [s].
    columns : dict of str -> ndarray
        Recorded variables by 'instance.variable', in the scene's order.
    metadata : dict
        Scene, settings, steps taken and rejected, wall times (the content of the JSON file).
    csv_path, metadata_path : Path or None
        Files written, if any.

    A run of the C master keeps its rows as plain doubles (``recording``: times, rows row after row, names) and makes
    the arrays on first use, so that a run that only writes its files never imports numpy.
    """

    def __init__(self, time=None, columns=None, metadata=None, csv_path: Path | None = None,
                 metadata_path: Path | None = None, *, recording=None) -> None:
        self._time, self._columns, self._recording = time, columns, recording
        self.metadata: dict = metadata if metadata is not None else {}
        self.csv_path, self.metadata_path = csv_path, metadata_path

    @property
    def time(self):
        if self._time is None:
            import numpy as np

            self._time = np.array(self._recording[0], dtype=float)
        return self._time

    @property
    def columns(self) -> dict:
        if self._columns is None:
            import numpy as np

            times, rows, names = self._recording
            data = np.array(rows, dtype=float).reshape(len(times), len(names))
            self._columns = {n: data[:, j].copy() for j, n in enumerate(names)}
        return self._columns

    def series(self, name: str) -> list:
        """One recorded variable (or ``"time"``) as a list of floats, read without numpy from a run of the C master;
        KeyError as ``result[name]``."""
        if self._recording is not None and self._columns is None:
            times, rows, names = self._recording
            if name == "time":
                return list(times)
            if name not in names:
                raise KeyError(f"{name!r} is not recorded")
            j, n = names.index(name), len(names)
            return [rows[k * n + j] for k in range(len(times))]
        return [float(x) for x in self[name]]

    def __getitem__(self, name: str):
        if name == "time":
            return self.time
        columns = self.columns
        if name not in columns:
            raise KeyError(f"{name!r} is not recorded; the recorded columns: {', '.join(columns) or 'none'} (the "
                           "scene's output.variables says which are)")
        return columns[name]


def recorded_units(plan: Plan, columns) -> dict:
    """The unit each recorded ``instance.variable`` declares in its FMU's model description ("" when none)."""
    from tribocosim.cosim.scene.validate import unit_of

    out = {}
    for name in columns:
        inst, _, var = name.partition(".")
        model = plan.fmus.get(inst)
        v = model.variables.get(var) if model is not None else None
        out[name] = (unit_of(v) or "") if v is not None else ""
    return out


class Build:
    """A master assembled from a plan (:class:`~tribocosim.cosim.engine.master.Master`), the instance names, the
    parameter values to set into each instance, the notes on the coupling; and what is needed to clean up
    afterwards."""

    __slots__ = ("master", "plan", "names", "parameters", "notes")

    def __init__(self, master, plan: Plan, names: list[str], parameters: list[dict], notes: list[str]) -> None:
        self.master, self.plan, self.names, self.parameters, self.notes = master, plan, names, parameters, notes

    def close(self) -> None:
        """Terminate and free every slave; one whose FMU returned fmi2Fatal in any instance is only dropped
        (:meth:`~tribocosim.cosim.engine.slave.FmpySlave.abandon`)."""
        slaves = self.master.system.slaves
        dead = {s.unzip_dir for s in slaves if s.fatal}
        for s in slaves:
            if s.unzip_dir in dead:
                s.abandon()
                continue
            try:
                s.terminate()
            except Exception:  # keep freeing the others
                pass


class Coupling:
    """How a plan's FMUs are coupled, in index form (what both masters need): instance names, links, the declared
    dependency structure (``structure[k][j]``: link k's source may depend directly on link j's target), declared
    feedthrough, the Gauss-Seidel order (:class:`~tribocosim.cosim.engine.graph.StepOrder`), the order of accuracy of
    the coupling and the notes on it."""

    __slots__ = ("names", "links", "structure", "feedthrough", "gauss_seidel", "order_of_accuracy", "notes")

    def __init__(self, names: list[str], links: list[LinkSpec], structure: list[list[bool]], feedthrough: list,
                 gauss_seidel, order_of_accuracy: int, notes: list[str]) -> None:
        self.names, self.links, self.structure, self.feedthrough = names, links, structure, feedthrough
        self.gauss_seidel, self.order_of_accuracy, self.notes = gauss_seidel, order_of_accuracy, notes


def coupling(plan: Plan) -> Coupling:
    """The :class:`Coupling` of a validated plan."""
    scene = plan.scene
    names = list(plan.fmus)
    index = {n: i for i, n in enumerate(names)}
    links = []
    for l in plan.links:
        tmodel = plan.fmus[l.target.instance]
        der = tmodel.derivative_inputs.get(l.target.variable, {})
        links.append(LinkSpec(index[l.source.instance], l.source_vr, l.source_type, index[l.target.instance],
                              l.target_vr, l.target_type, l.continuous, f"{l.source} -> {l.target}",
                              (der.get(1), der.get(2))))
    structure = []
    for lk in plan.links:
        deps = plan.fmus[lk.source.instance].dependencies.get(lk.source.variable)
        structure.append([lj.target.instance == lk.source.instance and (deps is None or lj.target.variable in deps)
                          for lj in plan.links])
    ms = scene.master
    notes = list(plan.notes)
    order = ms.extrapolation
    mean_hold = [str(l.target) for l, spec in zip(plan.links, links) if spec.continuous and spec.derivative_vrs[0] is None
                 and not plan.fmus[l.target.instance].can_interpolate_inputs]
    p = order + 1
    if order >= 1 and mean_hold:
        notes.append(f"inputs {', '.join(mean_hold)} cannot take input derivatives (no canInterpolateInputs, no der() inputs): "
                     "they hold the step mean of the extrapolation polynomial, which caps the order at 2")
        p = min(p, 2)
    pairs = [(sp.source, sp.target) for sp in links]
    gs = gauss_seidel_order(len(names), pairs, [index[o] for o in ms.order] if ms.order else None)
    if ms.algorithm == "gauss-seidel":
        for cycle in gs.cycles:
            back = [links[k].label for k in sorted(gs.backward) if links[k].target in cycle]
            notes.append(f"Gauss-Seidel: instances {' -> '.join(names[i] for i in cycle)} form a cycle; stepping order "
                         f"{', '.join(names[i] for i in gs.order)}, so {', '.join(back)} {'is' if len(back) == 1 else 'are'} "
                         "extrapolated")
    return Coupling(names, links, structure, [plan.fmus[n].feedthrough for n in names], gs, p, notes)


def extracted_fmu(path: Path) -> Path:
    """The folder the FMU file ``path`` is extracted to (:func:`tribocosim.cosim.scene.fmu_files.extracted`)."""
    from tribocosim.cosim.scene.fmu_files import extracted

    return extracted(path)


def build(plan: Plan, loop: str = "auto") -> Build:
    """Assemble a master for a validated scene (FMUs extracted, not yet instantiated).

    Parameters
    ----------
    plan : Plan
        From :func:`tribocosim.cosim.scene.validate.load_scene`.
    loop : {"auto", "python"}
        The master's loop (:class:`~tribocosim.cosim.engine.master.Master`): the C loop where it takes the run, or
        always the Python one.
    """
    import numpy as np

    from tribocosim.cosim.engine import algorithms, stepcontrol
    from tribocosim.cosim.engine.master import Master
    from tribocosim.cosim.engine.recorder import Recorder
    from tribocosim.cosim.engine.slave import FmpySlave
    from tribocosim.cosim.engine.system import CoupledSystem
    from tribocosim.cosim.engine.timegrid import TimeGrid

    scene = plan.scene
    c = coupling(plan)
    index = {n: i for i, n in enumerate(c.names)}
    slaves = [FmpySlave(n, extracted_fmu(plan.fmus[n].path), plan.fmus[n].md) for n in c.names]
    ms = scene.master
    m = len(c.links)
    system = CoupledSystem(slaves, c.links, ms.extrapolation, c.feedthrough,
                           np.array(c.structure, dtype=bool).reshape(m, m))
    algorithm = algorithms.create(ms.algorithm, ms.extrapolation, ms.output_update == "propagate", c.gauss_seidel.order,
                                  ms.algorithm_settings)
    ex = scene.experiment
    if ms.adaptive is None:
        grid = TimeGrid.fixed(ex.start, ex.stop, ex.step)
        controller = stepcontrol.FixedStep(grid.macro_ticks)
    else:
        grid = TimeGrid.variable(ex.start, ex.stop, ms.adaptive.min_step)
        controller = stepcontrol.create_controller(ms.adaptive, grid, ex.step, c.order_of_accuracy, plan.bonds)
    recorder = Recorder(slaves, index, plan.recorded, system)
    master = Master(system, algorithm, controller, grid, recorder, c.names, loop=loop)
    master.gauss_seidel = c.gauss_seidel
    master.accuracy_order = c.order_of_accuracy  # of the coupling error with exact subsystems (in the metadata)
    params = [{vr: (kind, value) for vr, kind, value in plan.parameters.get(n, [])} for n in c.names]
    return Build(master, plan, c.names, params, c.notes)


def run(scene: str | Path | Plan, out_dir: str | Path | None = None, *, overrides: dict | None = None,
        progress: bool = False, write: bool = True, loop: str = "auto") -> Result:
    """Load, validate and run a scene.

    Parameters
    ----------
    scene : str, Path or Plan
        A scene file, the name of a packaged scene (``"demo"``, see
        :func:`tribocosim.paths.scene_file`), or an already validated plan.
    out_dir : str or Path, optional
        Folder for the output files; default: the scene file's folder, or ``./<scene name>`` for
        a packaged scene. ``[output] file`` is relative to it; the metadata JSON goes next to the
        CSV (same stem, ``.json``).
    overrides : dict, optional
        Dotted scene keys to override, e.g. ``{"master.extrapolation": 2}``.
    progress : bool
        Show a progress bar on stderr for runs longer than two seconds.
    write : bool
        Write the CSV and JSON files (False: only return the result).
    loop : {"auto", "python"}
        "auto": a fixed-step Jacobi or Gauss-Seidel run without extrapolation takes its steps in C (the whole run in
        :mod:`tribocosim.cosim.engine.native_session`, else the loop in :mod:`tribocosim.cosim.engine.native_loop`;
        the same results); a step the C loop does not take (a discard, a non-finite value) repeats the run with the
        Python loop, which can roll back. "python": the Python loop.

    Returns
    -------
    Result

    Raises
    ------
    ParameterError
        Before anything runs: ``overrides`` that is not a dict (or given with a plan, which is validated already), an
        output folder that is a file (the message of ``tribocosim run``).
    """
    if overrides is not None and (not isinstance(overrides, dict) or isinstance(scene, Plan)):
        why = ("a validated plan takes no overrides (give them to load_scene)" if isinstance(overrides, dict) else
               f"a {type(overrides).__name__}")
        raise ParameterError(f"overrides = {overrides!r}: {why}; allowed: a dict of dotted scene keys and values, "
                             "e.g. {'master.extrapolation': 1} (tribocosim run --set KEY=VALUE is its command-line "
                             "form)")
    if not isinstance(scene, Plan):
        from tribocosim.paths import scene_file
        from tribocosim.cosim.scene.validate import load_scene

        scene = load_scene(scene_file(scene), overrides)
    plan = scene
    if write:
        _check_out_dir(Path(out_dir) if out_dir is not None else default_out_dir(plan.scene.path))
    started = time.strftime("%Y-%m-%dT%H:%M:%S+00:00", time.gmtime())  # ISO 8601, UTC, as datetime.isoformat
    t0 = time.perf_counter()
    outcome = _session(plan, progress) if loop == "auto" else None
    if outcome is None:
        from tribocosim.cosim.engine.native_loop import NativeLoopStopped

        try:
            outcome = _execute(plan, loop, progress)
        except NativeLoopStopped as stop:  # the C loop saves no state: the Python loop repeats the run, rolls back
            outcome = _execute(plan, "python", progress)
            outcome.notes.append(f"the native loop stopped ({stop}); the run was repeated with the Python loop, which "
                                 "can roll back and halve the step")
    meta = _metadata(plan, outcome, started, time.perf_counter() - t0)
    failure = outcome.failure
    if failure is not None:
        meta["failure"] = {"message": str(failure), "last_accepted_time": outcome.end_time,
                           "recorded_rows": outcome.rows}
    if outcome.interrupted is not None:
        from tribocosim.interrupt import signal_name

        meta["interrupted"] = {"signal": signal_name(outcome.interrupted), "last_accepted_time": outcome.end_time,
                               "recorded_rows": outcome.rows, "steps": outcome.steps["accepted"],
                               "steps_of_the_run": _steps_of(plan)}
    result = outcome.result(meta)
    if write:
        out = Path(out_dir) if out_dir is not None else default_out_dir(plan.scene.path)
        _check_out_dir(out)
        out.mkdir(parents=True, exist_ok=True)
        if plan.scene.output.file:
            result.csv_path = outcome.write_csv(out / plan.scene.output.file)
            result.metadata_path = result.csv_path.with_suffix(".json")
        else:
            result.metadata_path = out / f"{plan.scene.path.stem}.run.json"
        meta["outputs"]["csv"] = str(result.csv_path) if result.csv_path else None
        write_json(result.metadata_path, meta)
    if failure is not None:
        raise RunFailed(f"{failure}; the run stopped at t = {outcome.end_time:.9g} s", result) from failure
    if outcome.interrupted is not None:
        raise RunInterrupted(f"stopped by {meta['interrupted']['signal']} at t = {outcome.end_time:.9g} s",
                             outcome.interrupted, result)
    return result


def _steps_of(plan: Plan) -> int | None:
    """The communication steps of a whole fixed-step run of ``plan`` (None for adaptive steps)."""
    if plan.scene.master.adaptive is not None:
        return None
    from tribocosim.cosim.engine.timegrid import TimeGrid

    ex = plan.scene.experiment
    grid = TimeGrid.fixed(ex.start, ex.stop, ex.step)
    return -(-grid.end_ticks // grid.macro_ticks)


def write_json(path: Path, data: dict) -> Path:
    """``data`` as indented JSON in ``path``, atomically (a ``.part`` file renamed into place)."""
    tmp = path.with_suffix(path.suffix + ".part")
    try:
        tmp.write_text(json.dumps(data, indent=2, default=_json_default), encoding="utf-8")
        tmp.replace(path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


class Outcome:
    """What a run did, whichever master ran it: what :func:`_metadata` reports and what the result holds. ``master``:
    the metadata's "master" entries that depend on the run; ``recording``: (times, rows row after row) of the C
    master; ``recorder``: the Python master's; ``failure``: what stopped the run early, or None; ``interrupted``: the
    signal that stopped it at a communication point, or None; ``fmu_warnings``: per instance the messages its FMU
    logged as warnings or worse; ``end_values``: the values of the plan's end checks (``{"instance.output":
    value}``)."""

    __slots__ = ("names", "columns", "notes", "warnings", "master", "feedthrough", "gauss_seidel", "link_labels",
                 "loops", "hold_mean", "steps", "calls", "fmu_times", "loop_time", "end_time", "rows", "failure",
                 "recording", "recorder", "interrupted", "fmu_warnings", "end_values")

    def __init__(self, names: list[str], columns: list[str], notes: list[str], warnings: list[str], master: dict,
                 feedthrough: list, gauss_seidel, link_labels: list[str], loops: list, hold_mean: list, steps: dict,
                 calls: dict, fmu_times: dict, loop_time: float, end_time: float, rows: int,
                 failure: Exception | None = None, recording=None, recorder=None, interrupted: int | None = None,
                 fmu_warnings: dict | None = None, end_values: dict | None = None) -> None:
        self.names, self.columns, self.notes, self.warnings, self.master = names, columns, notes, warnings, master
        self.feedthrough, self.gauss_seidel = feedthrough, gauss_seidel
        self.link_labels, self.loops = link_labels, loops
        self.hold_mean, self.steps, self.calls, self.fmu_times = hold_mean, steps, calls, fmu_times
        self.loop_time, self.end_time, self.rows, self.failure = loop_time, end_time, rows, failure
        self.recording, self.recorder, self.interrupted = recording, recorder, interrupted
        self.fmu_warnings, self.end_values = fmu_warnings or {}, end_values or {}

    def result(self, meta: dict) -> Result:
        if self.recorder is not None:
            return Result(self.recorder.time, self.recorder.columns(), meta)
        return Result(metadata=meta, recording=(*self.recording, self.columns))

    def write_csv(self, path: Path) -> Path:
        if self.recorder is not None:
            return self.recorder.write_csv(path)
        from tribocosim.cosim.engine.results_csv import write_csv

        return write_csv(path, self.columns, *self.recording)


def _end_checks(plan: Plan, values: list[float]) -> dict:
    """``{"instance.output": value}`` of the plan's end checks (the metadata's ``end_checks``)."""
    return {f"{check.instance}.{check.variable}": value for check, value in zip(plan.end_checks, values)}


def _end_warnings(plan: Plan, names: list[str], values: list[float]) -> list[str]:
    """The warnings of the plan's end checks (``Plan.end_checks``) whose outputs ended above 0."""
    return [f"FMU instance '{check.instance}': {value:.0f} {check.message}"
            for check, value in zip(plan.end_checks, values) if value > 0]


def _session(plan: Plan, progress: bool) -> Outcome | None:
    """The run in the C master (:class:`~tribocosim.cosim.engine.native_session.NativeSession`), or None when it
    does not take it or leaves it to the Python master."""
    from tribocosim.cosim.engine import native_session as ns

    ms, ex = plan.scene.master, plan.scene.experiment
    c = coupling(plan)
    if ns.supported(ms.algorithm, ms.extrapolation, ms.adaptive, c.links) is not None:
        return None
    from tribocosim.cosim.engine.observers import Progress
    from tribocosim.cosim.engine.timegrid import TimeGrid
    from tribocosim.cosim.scene.fmu_files import extracted

    index = {n: i for i, n in enumerate(c.names)}
    slaves = [ns.SessionSlave(n, extracted(plan.fmus[n].path), plan.fmus[n].summary.model_identifier,
                              plan.fmus[n].summary.guid, plan.parameters.get(n, []), plan.fmus[n].feedthrough)
              for n in c.names]
    grid = TimeGrid.fixed(ex.start, ex.stop, ex.step)
    session = ns.NativeSession(slaves, c.links, c.structure, [(index[r.instance], vr, t) for r, vr, t in plan.recorded],
                               ms.algorithm, ms.output_update == "propagate", c.gauss_seidel.order, grid, ex.stop,
                               [(index[e.instance], e.value_reference, e.type) for e in plan.end_checks])
    bar = Progress(ex.start, ex.stop) if progress else None
    try:
        r = session.run(bar)
    except ns.SessionStopped:
        return None
    finally:
        if bar is not None:
            bar.close()
    columns = [str(ref) for ref, _, _ in plan.recorded]
    n_rows = len(r.times)
    return Outcome(
        c.names, columns, c.notes, [*r.warnings, *_end_warnings(plan, c.names, r.end_values)],
        {"step_control": "fixed", "order_of_accuracy": c.order_of_accuracy, "loop": "native", "time_tick": grid.tick},
        r.feedthrough, c.gauss_seidel, [l.label for l in c.links],
        [{"links": [c.links[k].label for k in lp.links], "contraction": lp.contraction} for lp in r.loops], [],
        {"accepted": r.steps, "rejected_error": 0, "rejected_failure": 0, "iterations": r.steps,
         "observed_contraction": None, "min_step": r.min_step if r.steps else None,
         "max_step": r.max_step if r.steps else None},
        {n: {"doStep": d, "getFMUstate": 0, "setFMUstate": 0} for n, d in zip(c.names, r.do_steps)},
        dict(zip(c.names, r.wall_times)), r.loop_time, r.times[-1] if n_rows else grid.start, n_rows,
        recording=(r.times, r.rows), interrupted=r.interrupted, fmu_warnings=dict(zip(c.names, r.fmu_warnings)),
        end_values=_end_checks(plan, r.end_values))


def _execute(plan: Plan, loop: str, progress: bool) -> Outcome:
    """Build, initialize and run the Python master; the FMUs are freed. A step that could not be recovered (an FMU's
    refusal, a non-finite output, a coupling iteration that does not converge) is the failure, and what was accepted
    before it is kept. :class:`~tribocosim.cosim.engine.native_loop.NativeLoopStopped` goes to the caller."""
    from tribocosim.cosim.engine.native_loop import NativeLoopStopped
    from tribocosim.cosim.engine.observers import Progress

    b = build(plan, loop)
    m = b.master
    ex = plan.scene.experiment
    bar = Progress(ex.start, ex.stop) if progress else None
    if bar is not None:
        m.observers.append(bar)
    failure = interrupted = None
    try:
        m.initialize(ex.start, ex.stop, b.parameters)
        m.run()
    except NativeLoopStopped:
        raise
    except (CosimStepError, ConvergenceError) as exc:
        failure = exc
    except Interrupted as exc:  # a signal: the run ends at the last accepted communication point
        interrupted = exc.signum
    finally:
        if bar is not None:
            bar.close()
        fmu_times = {n: s.wall_time for n, s in zip(b.names, m.system.slaves)}
        calls = {n: dict(s.calls) for n, s in zip(b.names, m.system.slaves)}
        end_values = _end_values(b)
        m.warnings.extend(_end_warnings(plan, b.names, end_values))
        fmu_warnings = {n: s.warnings for n, s in zip(b.names, m.system.slaves)}
        b.close()
    sysm, st = m.system, m.stats
    return Outcome(
        b.names, list(m.recorder.names), b.notes, m.warnings,
        {"step_control": m.controller.name, "order_of_accuracy": m.accuracy_order, "loop": m.loop_used,
         **({"python_loop_because": m.loop_reason} if m.loop_used == "python" else {}), "time_tick": m.grid.tick},
        sysm.feedthrough, m.gauss_seidel, [l.label for l in sysm.links],
        [{"links": [sysm.links[k].label for k in lp.links], "contraction": lp.contraction} for lp in sysm.loops],
        sorted(sysm.hold_mean),
        {"accepted": st.steps, "rejected_error": st.rejected_error, "rejected_failure": st.rejected_failures,
         "iterations": st.iterations,
         "observed_contraction": st.observed_contraction if st.observed_contraction == st.observed_contraction else None,
         "min_step": st.min_step if st.steps else None, "max_step": st.max_step if st.steps else None},
        calls, fmu_times, st.wall_time, m.grid.time(m.n), len(m.recorder.time), failure, recorder=m.recorder,
        interrupted=interrupted, fmu_warnings=fmu_warnings, end_values=_end_checks(plan, end_values))


def _end_values(b: Build) -> list[float]:
    """The values of the plan's end checks, read from the Python master's slaves (0 where one cannot answer)."""
    out = []
    slaves = b.master.system.slaves
    dead = {s.unzip_dir for s in slaves if s.fatal}
    for check in b.plan.end_checks:
        try:
            slave = slaves[b.names.index(check.instance)]
            if slave.unzip_dir in dead:  # no call after fmi2Fatal (FMI 2.0.4, section 2.1.3)
                out.append(0.0)
                continue
            getter = slave.get_real if check.type == "Real" else slave.get_integer
            out.append(float(getter([check.value_reference])[0]))
        except Exception:  # noqa: BLE001 - an FMU that cannot answer after a failure says nothing here
            out.append(0.0)
    return out


def run_ssp(path: str | Path, out_dir: str | Path | None = None, overrides: dict | None = None, *,
            progress: bool = False, write: bool = True):
    """Run an SSP package with our master; as :func:`run`, output by default next to the package.

    The metadata names the package as the scene (``scene``, ``scene_sha256``) and keeps the
    translated scene's text under ``ssp.scene_toml``.
    """
    from tribocosim.cosim.ssp.reader import load_ssp

    ssp = Path(path).resolve()
    plan = load_ssp(ssp, overrides)
    try:
        result = run(plan, Path(out_dir) if out_dir is not None else ssp.parent, progress=progress, write=write)
    except (RunFailed, RunInterrupted) as exc:
        _note_package(exc.result, ssp, plan.scene.path)
        raise
    _note_package(result, ssp, plan.scene.path)
    return result


def _note_package(result, ssp: Path, scene: Path) -> None:
    note = {"scene": str(ssp), "scene_sha256": hashlib.sha256(ssp.read_bytes()).hexdigest(),
            "ssp": {"scene_toml": scene.read_text(encoding="utf-8")}}
    result.metadata.update(note)
    if result.metadata_path is not None and result.metadata_path.is_file():
        meta = json.loads(result.metadata_path.read_text(encoding="utf-8"))
        meta.update(note)
        write_json(result.metadata_path, meta)


def _check_out_dir(out: Path) -> None:
    """Refuse an output folder that a file is in the way of, before the run (the messages of ``tribocosim run``)."""
    if out.exists() and not out.is_dir():
        raise ParameterError(f"cannot write the results into {out}: a file of that name is in the way")
    above = next((p for p in out.parents if p.exists()), None)
    if above is not None and not above.is_dir():
        raise ParameterError(f"cannot make the output folder {out}: {above} is a file")


def default_out_dir(scene_path: Path) -> Path:
    """Where a run writes when no folder is given: the scene's folder, or ``./<stem>`` for a packaged scene
    (an installed package's folder is no place for results)."""
    from tribocosim.paths import is_packaged

    return Path.cwd() / scene_path.stem if is_packaged(scene_path) else scene_path.parent


def _json_default(o):
    if hasattr(o, "item") and callable(o.item):  # a numpy scalar
        return o.item()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serializable: {type(o).__name__}")


def distribution_version(name: str) -> str | None:
    """The version of an installed distribution, from the name of its ``.dist-info`` folder on ``sys.path`` (what
    :func:`importlib.metadata.version` reads, without importing its e-mail parser on the run path), or None."""
    import sys

    for entry in sys.path:
        folder = Path(entry or ".")
        found = sorted(folder.glob(f"{name}-*.dist-info")) if folder.is_dir() else []
        if found:
            return found[0].name[len(name) + 1:-len(".dist-info")]
    return None


def _metadata(plan: Plan, o: Outcome, started: str, total: float) -> dict:
    scene = plan.scene
    gs = o.gauss_seidel
    ms = scene.master
    return {
        "scene": str(scene.path),
        "scene_sha256": hashlib.sha256(scene.path.read_bytes()).hexdigest(),
        "overrides": dict(scene.overrides),
        "started": started,
        "versions": {"tribocosim": distribution_version("tribocosim"), "fmpy": distribution_version("fmpy")},
        "experiment": scene.experiment.as_dict(),
        "master": {
            "algorithm": ms.algorithm,
            "extrapolation": ms.extrapolation,
            "output_update": ms.output_update,
            "step_control": o.master["step_control"],
            "adaptive": ms.adaptive.as_dict() if ms.adaptive else None,
            **({ms.algorithm: ms.algorithm_settings.as_dict()} if ms.algorithm_settings is not None else {}),
            "order_of_accuracy": o.master["order_of_accuracy"],
            "loop": o.master["loop"],
            **({"python_loop_because": o.master["python_loop_because"]} if "python_loop_because" in o.master else {}),
            "time_tick": o.master["time_tick"],
        },
        "fmus": {n: {"path": str(plan.fmus[n].path), "can_roll_back": plan.fmus[n].can_roll_back,
                     "feedthrough": o.feedthrough[i]} for i, n in enumerate(o.names)},
        "gauss_seidel": {
            "order": [o.names[i] for i in gs.order],
            "extrapolated_links": [o.link_labels[k] for k in sorted(gs.backward)],
            "cycles": [[o.names[i] for i in c] for c in gs.cycles],
        },
        "algebraic_loops": o.loops,
        "input_hold_mean": o.hold_mean,
        "steps": o.steps,
        "fmi_calls": o.calls,
        "wall_time": {"total": total, "loop": o.loop_time, "fmus": o.fmu_times,
                      "master": total - sum(o.fmu_times.values())},
        "warnings": plan.warnings + o.warnings,
        "fmu_warnings": o.fmu_warnings,
        "end_checks": o.end_values,
        "notes": o.notes,
        "outputs": {"columns": ["time", *o.columns], "units": {"time": "s", **recorded_units(plan, o.columns)}},
    }
