"""Python API: ``tribocosim.cosim.run(scene) -> Result``, and the assembly of a master from a scene.

:func:`build` turns a validated :class:`~tribocosim.cosim.scene.validate.Plan` into a ready
:class:`~tribocosim.cosim.engine.master.Master` (FMUs extracted and wrapped in :class:`~tribocosim.cosim.engine.slave.FmpySlave`,
links, algorithm, step controller, recorder); :func:`run` loads a scene, runs it, and writes
the CSV and the metadata JSON. The command line (``tribocosim run``) is a thin layer over
:func:`run`.
"""

from __future__ import annotations

import atexit
import datetime as _dt
import hashlib
import json
import shutil
import tempfile
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from tribocosim.errors import ConvergenceError, CosimStepError, RunFailed
from tribocosim.cosim.engine.algorithms import ALGORITHMS, GaussSeidel
from tribocosim.cosim.engine.graph import gauss_seidel_order
from tribocosim.cosim.engine.master import Master
from tribocosim.cosim.engine.native_loop import NativeLoopStopped
from tribocosim.cosim.engine.recorder import Progress, Recorder
from tribocosim.cosim.engine.slave import FmpySlave
from tribocosim.cosim.engine.stepcontrol import ESTIMATORS, FixedStep
from tribocosim.cosim.engine.system import CoupledSystem, LinkSpec
from tribocosim.cosim.engine.timegrid import TimeGrid
from tribocosim.cosim.scene.validate import Plan


@dataclass
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
    """

    time: np.ndarray
    columns: dict[str, np.ndarray]
    metadata: dict[str, Any]
    csv_path: Path | None = None
    metadata_path: Path | None = None

    def __getitem__(self, name: str) -> np.ndarray:
        if name == "time":
            return self.time
        return self.columns[name]


@dataclass
class Build:
    """A master assembled from a plan, plus what is needed to clean up afterwards."""

    master: Master
    plan: Plan
    names: list[str]
    parameters: list[dict]
    notes: list[str] = field(default_factory=list)

    def close(self) -> None:
        """Terminate and free every slave."""
        for s in self.master.system.slaves:
            try:
                s.terminate()
            except Exception:  # keep freeing the others
                pass


#: FMU file (path, size, mtime) -> folder it is extracted to, for the life of the process
_EXTRACTED: dict[tuple[str, int, int], Path] = {}


def _cleanup_extracted() -> None:
    for d in _EXTRACTED.values():
        shutil.rmtree(d, ignore_errors=True)


atexit.register(_cleanup_extracted)


def extracted_fmu(path: Path) -> Path:
    """The folder ``path`` is extracted to, extracting it once per process (sweeps reuse it).

    The key includes the file's size and modification time, so a rebuilt FMU is extracted
    again. (pythonfmu FMUs import their Python class by module name, so a rebuilt pythonfmu
    FMU's code is only picked up by a new process.)
    """
    from fmpy import extract

    st = Path(path).stat()
    key = (str(Path(path).resolve()), st.st_size, st.st_mtime_ns)
    d = _EXTRACTED.get(key)
    if d is None or not d.is_dir():
        d = Path(tempfile.mkdtemp(prefix=f"tribocosim-{Path(path).stem}-"))
        extract(str(path), str(d))
        _EXTRACTED[key] = d
    return d


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
    scene = plan.scene
    names = list(plan.fmus)
    index = {n: i for i, n in enumerate(names)}
    slaves = []
    for n in names:
        model = plan.fmus[n]
        slaves.append(FmpySlave(n, extracted_fmu(model.path), model.md))

    links = []
    for l in plan.links:
        tmodel = plan.fmus[l.target.instance]
        der = tmodel.derivative_inputs.get(l.target.variable, {})
        links.append(LinkSpec(index[l.source.instance], l.source_vr, l.source_type, index[l.target.instance],
                              l.target_vr, l.target_type, l.continuous, f"{l.source} -> {l.target}",
                              (der.get(1), der.get(2))))
    m = len(links)
    structure = np.ones((m, m), dtype=bool)
    for k, lk in enumerate(plan.links):
        deps = plan.fmus[lk.source.instance].dependencies.get(lk.source.variable)
        for j, lj in enumerate(plan.links):
            same = lj.target.instance == lk.source.instance
            structure[k, j] = same and (deps is None or lj.target.variable in deps)
    feed = [plan.fmus[n].feedthrough for n in names]

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
    system = CoupledSystem(slaves, links, order, feed, structure)
    propagate = ms.output_update == "propagate"
    pairs = [(sp.source, sp.target) for sp in links]
    gs = gauss_seidel_order(len(names), pairs, [index[o] for o in ms.order] if ms.order else None)
    algorithm = ALGORITHMS[ms.algorithm].create(order, propagate, gs.order, ms.algorithm_settings)
    if isinstance(algorithm, GaussSeidel):
        for cycle in gs.cycles:
            back = [links[k].label for k in sorted(gs.backward) if links[k].target in cycle]
            notes.append(f"Gauss-Seidel: instances {' -> '.join(names[i] for i in cycle)} form a cycle; stepping order "
                         f"{', '.join(names[i] for i in gs.order)}, so {', '.join(back)} {'is' if len(back) == 1 else 'are'} "
                         "extrapolated")

    ex = scene.experiment
    if ms.adaptive is None:
        grid = TimeGrid.fixed(ex.start, ex.stop, ex.step)
        controller = FixedStep(grid.macro_ticks)
    else:
        grid = TimeGrid.variable(ex.start, ex.stop, ms.adaptive.min_step)
        controller = ESTIMATORS[ms.adaptive.estimator].create(ms.adaptive, grid, ex.step, p, plan.bonds)
    recorder = Recorder(slaves, index, plan.recorded, system)
    master = Master(system, algorithm, controller, grid, recorder, names, loop=loop)
    master.gauss_seidel = gs
    master.accuracy_order = p  # of the coupling error with exact subsystems (reported in the metadata)
    params = []
    for n in names:
        model = plan.fmus[n]
        d = {}
        for pname, value in scene.fmus[n].parameters.items():
            var = model.variables[pname]
            d[var.valueReference] = (var.type, native_resource(scene.fmus[n], pname, value))
        params.append(d)
    return Build(master, plan, names, params, notes)


def native_resource(spec, name: str, value):
    """The value of parameter ``name`` of a scene FMU as the FMU reads it: for a native FMU of a component whose
    parameter names a resource file the C code reads in another form (the strip's ``table_file``, a .npz table),
    that form, converted once into the cache; every other value as it is."""
    if spec.component is None or not isinstance(value, str) or not value:
        return value
    from tribocosim.components import registry

    comp = registry.find(spec.component)
    native = comp.native if comp is not None else None
    if native is None or native.convert_resource is None or name not in native.resource_parameters:
        return value
    source = Path(value)
    if not source.is_absolute() or not source.is_file():  # a file in the FMU's resources: converted by its build
        return value
    from tribocosim.cosim.scene.fmucache import cache_dir

    folder = cache_dir() / "resources" / hashlib.sha256(source.read_bytes()).hexdigest()[:20]
    converted = folder / f"{source.stem}.tca"
    if not converted.is_file():
        folder.mkdir(parents=True, exist_ok=True)
        native.convert_resource(source, folder)
    return str(converted)


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
        "auto": a fixed-step Jacobi or Gauss-Seidel run without extrapolation takes its steps in C
        (:mod:`tribocosim.cosim.engine.native_loop`, the same results); a step the C loop does not take (a discard,
        a non-finite value) repeats the run with the Python loop, which can roll back. "python": the Python loop.

    Returns
    -------
    Result
    """
    if not isinstance(scene, Plan):
        from tribocosim.paths import scene_file
        from tribocosim.cosim.scene.component_checks import load_component_scene

        # load_scene plus the parameters of component = "..." FMUs checked against their dataclasses
        scene = load_component_scene(scene_file(scene), overrides)
    plan = scene
    started = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
    t0 = time.perf_counter()
    try:
        b, failure, fmu_times, calls = _execute(plan, loop, progress)
    except NativeLoopStopped as stop:  # the C loop saves no state: the Python loop repeats the run and rolls back
        b, failure, fmu_times, calls = _execute(plan, "python", progress)
        b.notes.append(f"the native loop stopped ({stop}); the run was repeated with the Python loop, which can "
                       "roll back and halve the step")
    total = time.perf_counter() - t0
    m = b.master
    meta = _metadata(b, started, total, fmu_times, calls)
    if failure is not None:
        meta["failure"] = {"message": str(failure), "last_accepted_time": m.grid.time(m.n),
                           "recorded_rows": len(m.recorder.time)}
    result = Result(m.recorder.time, m.recorder.columns(), meta)
    if write:
        out = Path(out_dir) if out_dir is not None else default_out_dir(plan.scene.path)
        out.mkdir(parents=True, exist_ok=True)
        if plan.scene.output.file:
            result.csv_path = m.recorder.write_csv(out / plan.scene.output.file)
            result.metadata_path = result.csv_path.with_suffix(".json")
        else:
            result.metadata_path = out / f"{plan.scene.path.stem}.run.json"
        meta["outputs"]["csv"] = str(result.csv_path) if result.csv_path else None
        result.metadata_path.write_text(json.dumps(meta, indent=2, default=_json_default), encoding="utf-8")
    if failure is not None:
        raise RunFailed(f"{failure}; the run stopped at t = {m.grid.time(m.n):.9g} s", result) from failure
    return result


def _execute(plan: Plan, loop: str, progress: bool):
    """Build, initialize and run a master: ``(build, failure or None, FMU wall times, FMI call counts)``; the FMUs
    are freed. A step that could not be recovered (an FMU's refusal, a non-finite output, a coupling iteration that
    does not converge) is the failure, and what was accepted before it is kept."""
    b = build(plan, loop)
    m = b.master
    ex = plan.scene.experiment
    bar = Progress(ex.start, ex.stop) if progress else None
    if bar is not None:
        m.observers.append(bar)
    failure = None
    try:
        m.initialize(ex.start, ex.stop, b.parameters)
        m.run()
    except NativeLoopStopped:
        raise
    except (CosimStepError, ConvergenceError) as exc:
        failure = exc
    finally:
        if bar is not None:
            bar.close()
        fmu_times = {n: s.wall_time for n, s in zip(b.names, m.system.slaves)}
        calls = {n: dict(s.calls) for n, s in zip(b.names, m.system.slaves)}
        m.warnings.extend(_outside_table_warnings(b))
        b.close()
    return b, failure, fmu_times, calls


#: the output through which a strip-draw FMU counts its friction-table lookups outside the simulated range
CLAMP_OUTPUT = "table_clamp_count"


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
    except RunFailed as exc:
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
        result.metadata_path.write_text(json.dumps(meta, indent=2), encoding="utf-8")


def _outside_table_warnings(b: Build) -> list[str]:
    """A warning for every FMU whose ``table_clamp_count`` output ended above 0 (read at the end of the run)."""
    out = []
    for i, name in enumerate(b.names):
        var = b.plan.fmus[name].variables.get(CLAMP_OUTPUT)
        if var is None or var.causality != "output":
            continue
        try:
            slave = b.master.system.slaves[i]
            getter = slave.get_integer if var.type == "Integer" else slave.get_real
            count = float(getter([var.valueReference])[0])
        except Exception:  # noqa: BLE001 - an FMU that cannot answer after a failure says nothing here
            continue
        if count > 0:
            out.append(f"FMU instance '{name}': {count:.0f} friction-table lookups read values outside the table's "
                       f"simulated range ({CLAMP_OUTPUT}): there the friction rests on values the mesoscale "
                       "campaign did not simulate (docs/model.md section 4)")
    return out


def default_out_dir(scene_path: Path) -> Path:
    """Where a run writes when no folder is given: the scene's folder, or ``./<stem>`` for a packaged scene
    (an installed package's folder is no place for results)."""
    from tribocosim.paths import is_packaged

    return Path.cwd() / scene_path.stem if is_packaged(scene_path) else scene_path.parent


def _json_default(o):
    if isinstance(o, (np.floating, np.integer)):
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


def _metadata(b: Build, started: str, total: float, fmu_times: dict, calls: dict) -> dict:
    plan, m = b.plan, b.master
    scene = plan.scene
    sysm = m.system
    st = m.stats
    gs = m.gauss_seidel
    ms = scene.master
    return {
        "scene": str(scene.path),
        "scene_sha256": hashlib.sha256(scene.path.read_bytes()).hexdigest(),
        "overrides": dict(scene.overrides),
        "started": started,
        "versions": {"tribocosim": distribution_version("tribocosim"), "fmpy": distribution_version("fmpy")},
        "experiment": asdict(scene.experiment),
        "master": {
            "algorithm": ms.algorithm,
            "extrapolation": ms.extrapolation,
            "output_update": ms.output_update,
            "step_control": m.controller.name,
            "adaptive": asdict(ms.adaptive) if ms.adaptive else None,
            **({ms.algorithm: asdict(ms.algorithm_settings)} if ms.algorithm_settings is not None else {}),
            "order_of_accuracy": m.accuracy_order,
            "loop": m.loop_used,
            **({"python_loop_because": m.loop_reason} if m.loop_used == "python" else {}),
            "time_tick": m.grid.tick,
        },
        "fmus": {n: {"path": str(plan.fmus[n].path), "can_roll_back": plan.fmus[n].can_roll_back,
                     "feedthrough": sysm.feedthrough[i]} for i, n in enumerate(b.names)},
        "gauss_seidel": {
            "order": [b.names[i] for i in gs.order],
            "extrapolated_links": [sysm.links[k].label for k in sorted(gs.backward)],
            "cycles": [[b.names[i] for i in c] for c in gs.cycles],
        },
        "algebraic_loops": [{"links": [sysm.links[k].label for k in lp.links], "contraction": lp.contraction}
                            for lp in sysm.loops],
        "input_hold_mean": sorted(sysm.hold_mean),
        "steps": {
            "accepted": st.steps,
            "rejected_error": st.rejected_error,
            "rejected_failure": st.rejected_failures,
            "iterations": st.iterations,
            "observed_contraction": st.observed_contraction if st.observed_contraction == st.observed_contraction else None,
            "min_step": st.min_step if st.steps else None,
            "max_step": st.max_step if st.steps else None,
        },
        "fmi_calls": calls,
        "wall_time": {"total": total, "loop": st.wall_time, "fmus": fmu_times,
                      "master": total - sum(fmu_times.values())},
        "warnings": plan.warnings + m.warnings,
        "notes": b.notes,
        "outputs": {"columns": ["time", *m.recorder.names]},
    }
