"""Scenes built from this project's components: parameter checks and the monolithic reference.

A scene FMU given as ``component = "stripdraw" | "press" | "drawingmachine"`` is this project's
FMU of a pure model (:mod:`components`). For such scenes this module

- checks the parameters against the model's parameter dataclass before anything runs
  (:func:`component_problems`, :func:`check_component_scene`): the FMUs declare min/max for
  Reals, which :mod:`tribocosim.cosim.validate` checks, but no choices for Strings (``friction_model =
  "tabel"``), no cross-field rules (a malformed press ``setpoint_table``) and nothing that spans
  instances: a press set-point whose nominal pressure on the connected strip's pad lies outside
  the friction table's pressure axis, a drive velocity outside its velocity axis, an initial
  debris field above the table's cap, a ``field_input`` file that does not exist. Every problem
  is one line ``file: fmus.INSTANCE.parameters.NAME: message``, all in one SceneError;
- builds the monolithic reference (:func:`reference_for_scene`): each component instance becomes
  its pure model (``StripDrawModel`` with the table read through
  :func:`tribocosim.components.stripdraw.table.read_table`, ``PressModel``, ``MachineModel``) with the
  scene's parameters, connected as the scene connects the FMUs, unconnected inputs held at their
  scene value (a parameter of the input's name) or else the FMU's start value, stepped by
  :class:`tribocosim.cosim.reference.CoupledModels` with a tiny step and the coupling solved every step.
  Variables are named like the FMUs' (``press.force_reference``, ``drive.velocity_reference``).

This is, with :mod:`tribocosim.cosim.fmucache`, where :mod:`cosim` imports :mod:`components`
(ARCHITECTURE.md: "nothing in cosim/ imports components/ except the reference solution and
scene helpers"); the imports are lazy.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from tribocosim.components.errors import ParameterError, SceneError


@dataclass(frozen=True)
class ComponentInfo:
    """What the checks and the reference need to know about one component."""

    parameters: Callable[[], type]  # the parameter dataclass (imported lazily)
    inputs: tuple[str, ...]
    outputs: dict[str, str]  # FMU output name -> the model's output key
    extra: dict[str, Any]  # FMU parameters that are not dataclass fields -> default


def _strip_params():
    from tribocosim.components.stripdraw.parameters import StripDrawParameters

    return StripDrawParameters


def _press_params():
    from tribocosim.components.press import PressParameters

    return PressParameters


def _machine_params():
    from tribocosim.components.machine import MachineParameters

    return MachineParameters


#: component name (normalised: lower case, no '_' or '-') -> its description
COMPONENTS: dict[str, ComponentInfo] = {
    "stripdraw": ComponentInfo(
        _strip_params, ("normal_force", "grip_velocity"),
        {n: n for n in ("pull_force", "friction_force", "mu_mean", "sliding_distance", "beta_mean", "beta_max",
                        "contact_pressure", "grip_position", "table_clamp_count")},
        {"table_file": "friction_table.npz", "field_output": "", "field_output_interval": 0.0, "field_input": ""},
    ),
    "press": ComponentInfo(_press_params, (), {"normal_force": "normal_force", "force_reference": "force_setpoint"}, {}),
    "drawingmachine": ComponentInfo(
        _machine_params, ("pull_force",),
        {"grip_velocity": "grip_velocity", "grip_position": "grip_position", "velocity_reference": "velocity_setpoint",
         "motor_force": "motor_force"},
        {},
    ),
}


def _normal(name: str) -> str:
    return name.lower().replace("_", "").replace("-", "")


def component_of(spec) -> str | None:
    """The normalised component name of a scene FMU spec, or None (a ``path = ...`` FMU or unknown)."""
    if spec.component is None:
        return None
    c = _normal(spec.component)
    return c if c in COMPONENTS else None


def table_path(value: str) -> Path:
    """``table_file`` as the StripDraw FMU resolves it: relative names refer to the bundled data
    (the shipped ``models/`` folder here), absolute paths are used as they are."""
    from tribocosim.components.paths import MODELS_DIR

    p = Path(value)
    return p if p.is_absolute() else MODELS_DIR / p


def _parameters(info: ComponentInfo, given: dict, add, key: str):
    """The dataclass instance of ``given`` (dataclass fields only), reporting each bad field by name."""
    cls = info.parameters()
    names = {f.name for f in dataclasses.fields(cls)}
    fields = {k: v for k, v in given.items() if k in names}
    default = cls()
    ok = {}
    for name, value in fields.items():  # one field at a time: the message names the culprit
        try:
            dataclasses.replace(default, **{name: value})
            ok[name] = value
        except ParameterError as exc:
            add(f"{key}.{name}", str(exc))
        except TypeError as exc:
            add(f"{key}.{name}", f"{name} = {value!r}: {exc}")
    try:
        return cls(**ok)
    except ParameterError as exc:  # a rule across fields
        add(key, str(exc))
        return None


def component_problems(scene) -> list[str]:
    """Problems of the component parameters of a scene (``file: key: message`` lines).

    ``scene`` is a :class:`tribocosim.cosim.scene.Scene` (parsed, not necessarily valid) or a validated plan.
    """
    scene = getattr(scene, "scene", scene)
    problems: list[str] = []
    if not any(component_of(spec) for spec in scene.fmus.values()):
        return problems  # FMU files only: nothing of the components is imported
    from tribocosim.components.stripdraw.friction import make_friction_law
    from tribocosim.components.stripdraw.table import read_table

    def add(key: str, msg: str) -> None:
        problems.append(f"{scene.path}: {key}: {msg}")

    params: dict[str, Any] = {}
    tables: dict[str, Any] = {}
    for name, spec in scene.fmus.items():
        comp = component_of(spec)
        if comp is None:
            continue
        info = COMPONENTS[comp]
        key = f"fmus.{name}.parameters"
        p = _parameters(info, spec.parameters, add, key)
        params[name] = p
        if comp != "stripdraw" or p is None:
            continue
        extra = {**info.extra, **{k: v for k, v in spec.parameters.items() if k in info.extra}}
        table = None
        if p.friction_model == "table":
            path = table_path(str(extra["table_file"]))
            try:
                table = read_table(path)
            except Exception as exc:  # noqa: BLE001 - any unreadable table is a scene problem
                add(f"{key}.table_file", f"friction table {path} cannot be used: {exc}")
        tables[name] = table
        fin = str(extra["field_input"])
        if fin and not Path(fin).is_file():
            add(f"{key}.field_input", f"field file {fin} does not exist (the field_output of an earlier pass)")
        try:
            cap = make_friction_law(p, table).beta_threshold if (table is not None or p.friction_model != "table") else None
        except ParameterError as exc:
            add(key, str(exc))
            cap = None
        if p.beta_threshold > 0:
            cap = p.beta_threshold
        if cap is not None and p.beta_initial > cap:
            add(f"{key}.beta_initial", f"beta_initial = {p.beta_initial!r} exceeds the cap of beta, {cap:.6g} "
                "(Eq. 24; from the friction law or beta_threshold)")

    # set-points of the connected press and drive against the strip's friction table
    for link in scene.connections:
        src, dst = link.source, link.target
        s_spec, d_spec = scene.fmus.get(src.instance), scene.fmus.get(dst.instance)
        if s_spec is None or d_spec is None or component_of(d_spec) != "stripdraw":
            continue
        strip, table = params.get(dst.instance), tables.get(dst.instance)
        source = params.get(src.instance)
        if strip is None or table is None or source is None:
            continue
        comp = component_of(s_spec)
        if comp == "press" and src.variable == "normal_force" and dst.variable == "normal_force":
            _, forces = source.setpoints()
            area = strip.tool_length * strip.tool_width
            positive = [float(f) for f in forces if f > 0]
            checks = [(max(positive or [0]), "the largest set-point"), (min(positive or [0]), "the smallest non-zero set-point")]
            if not positive:
                checks = []
            elif len(set(positive)) == 1:
                checks = [(positive[0], "the set-point")]
            for f, label in checks:
                pressure = f / area
                lo, hi = float(table.pressure[0]), float(table.pressure[-1])
                if not lo <= pressure <= hi:
                    which = "force_setpoint" if not source.setpoint_table else "setpoint_table"
                    add(f"fmus.{src.instance}.parameters.{which}",
                        f"{label}, {f:g} N on the {strip.tool_length * 1e3:g} x {strip.tool_width * 1e3:g} mm pad of "
                        f"'{dst.instance}', is a nominal pressure of {pressure / 1e6:.4g} MPa, outside the friction "
                        f"table's pressure axis [{lo / 1e6:g}, {hi / 1e6:g}] MPa")
        if comp == "drawingmachine" and src.variable == "grip_velocity" and dst.variable == "grip_velocity":
            v = abs(source.velocity_setpoint)
            vmax = float(table.velocity[-1])
            if v > vmax:
                add(f"fmus.{src.instance}.parameters.velocity_setpoint",
                    f"|velocity_setpoint| = {v:g} m/s is above the friction table's velocity axis (up to {vmax:g} m/s) "
                    f"of '{dst.instance}'")
    return problems


def check_component_scene(plan) -> None:
    """Raise one SceneError listing every :func:`component_problems` of ``plan`` (if any)."""
    problems = component_problems(plan)
    if problems:
        raise SceneError(_report(plan.scene.path, problems))


def _report(path, problems: list[str]) -> str:
    n = len(problems)
    return f"{n} problem{'s' if n > 1 else ''} in scene {path}:\n  " + "\n  ".join(problems)


def load_component_scene(path, overrides: dict | None = None):
    """:func:`tribocosim.cosim.validate.load_scene` plus :func:`component_problems`, all problems in one SceneError.

    (The component checks run on the parsed scene even when the FMU-level validation fails, and
    a key that both report is listed once.)
    """
    from tribocosim.cosim.scene import parse_scene
    from tribocosim.cosim.validate import load_scene

    scene, _ = parse_scene(path, overrides)
    extra = component_problems(scene) if scene is not None else []
    try:
        plan = load_scene(path, overrides)
    except SceneError as exc:
        lines = [ln.strip() for ln in str(exc).splitlines()[1:] if ln.strip()]
        keys = {ln.rsplit(": ", 1)[0].split(": ")[1] for ln in lines if ln.count(": ") >= 2}
        lines += [ln for ln in extra if ln.split(": ")[1] not in keys]
        raise SceneError(_report(scene.path if scene is not None else path, lines)) from None
    if extra:
        raise SceneError(_report(plan.scene.path, extra))
    return plan


# ------------------------------------------------------------------ monolithic reference
class ComponentModel:
    """A pure model seen through its FMU's names: fixed (unconnected) inputs merged in, outputs renamed."""

    def __init__(self, model, fixed_inputs: dict[str, float], outputs: dict[str, str]):
        self.model = model
        self.fixed = dict(fixed_inputs)
        self.names = dict(outputs)

    def step(self, dt: float, inputs: dict[str, float]) -> dict[str, float]:
        out = self.model.step(dt, {**self.fixed, **inputs})
        return {fmu: float(out[key]) for fmu, key in self.names.items()}

    def outputs(self) -> dict[str, float]:
        out = self.model.outputs()
        return {fmu: float(out[key]) for fmu, key in self.names.items()}

    def get_state(self):
        return self.model.get_state()

    def set_state(self, state) -> None:
        self.model.set_state(state)


def make_model(component: str, parameters: dict[str, Any]):
    """The pure model of ``component`` for the scene parameters (FMU-only extras handled here)."""
    comp = _normal(component)
    info = COMPONENTS[comp]
    cls = info.parameters()
    names = {f.name for f in dataclasses.fields(cls)}
    p = cls(**{k: v for k, v in parameters.items() if k in names})
    if comp == "press":
        from tribocosim.components.press import PressModel

        return PressModel(p)
    if comp == "drawingmachine":
        from tribocosim.components.machine import MachineModel

        return MachineModel(p)
    import numpy as np

    from tribocosim.components.stripdraw.friction import make_friction_law
    from tribocosim.components.stripdraw.model import StripDrawModel
    from tribocosim.components.stripdraw.table import read_table

    extra = {**info.extra, **{k: v for k, v in parameters.items() if k in info.extra}}
    table = read_table(table_path(str(extra["table_file"]))) if p.friction_model == "table" else None
    beta = None
    if extra["field_input"]:
        with np.load(extra["field_input"], allow_pickle=False) as data:
            beta = np.array(data["beta"][-1], dtype=float)
    return StripDrawModel(p, make_friction_law(p, table), beta_field=beta)


def reference_for_scene(scene, dt: float, *, tol: float = 1e-10, max_iterations: int = 100):
    """The monolithic reference of a scene whose FMUs are all components.

    Parameters
    ----------
    scene : str, Path, cosim.validate.Plan or cosim.scene.Scene
        The scene (a file is loaded and validated, FMUs built on demand).
    dt : float
        The tiny step of the reference [s].
    tol, max_iterations : float, int
        Convergence of the coupling values per step (:class:`tribocosim.cosim.reference.CoupledModels`).

    Returns
    -------
    cosim.reference.CoupledModels
        ``solve(times)`` gives every output of every instance, named ``instance.output``.

    Raises
    ------
    SceneError
        If an FMU of the scene is not one of this project's components.
    """
    from tribocosim.cosim.reference import CoupledModels

    if isinstance(scene, (str, Path)):
        from tribocosim.cosim.validate import load_scene

        scene = load_scene(scene)
    plan = scene if hasattr(scene, "scene") else None
    sc = plan.scene if plan is not None else scene
    others = [n for n, s in sc.fmus.items() if component_of(s) is None]
    if others:
        raise SceneError(f"scene {sc.path}: no monolithic reference for {', '.join(others)}: only component = "
                         f"\"{'|'.join(COMPONENTS)}\" FMUs map to pure models")
    connected = {(c.target.instance, c.target.variable) for c in sc.connections}
    models, initial = {}, {}
    for name, spec in sc.fmus.items():
        comp = component_of(spec)
        info = COMPONENTS[comp]
        fixed = {}
        for inp in info.inputs:
            if (name, inp) in connected:
                continue
            if inp in spec.parameters:
                fixed[inp] = float(spec.parameters[inp])
            else:
                fixed[inp] = _fmu_start(plan, name, inp, comp)
        model = ComponentModel(make_model(comp, spec.parameters), fixed, info.outputs)
        models[name] = model
        initial.update({f"{name}.{k}": v for k, v in model.outputs().items()})
    pairs = [(str(c.source), str(c.target)) for c in sc.connections]
    return CoupledModels(models, pairs, initial, dt, tol=tol, max_iterations=max_iterations)


def _fmu_start(plan, instance: str, variable: str, component: str) -> float:
    """Start value of an FMU input: from the model description if the plan has it, else the adapter's."""
    if plan is not None and instance in plan.fmus:
        var = plan.fmus[instance].variables.get(variable)
        if var is not None and var.start is not None:
            return float(var.start)
    if component == "stripdraw":
        from tribocosim.components.fmus.StripDraw import INPUTS

        return float(INPUTS[variable].start)
    return 0.0


def steady_ratio(time, pull_force, normal_force, last: float = 0.2) -> float:
    """Mean of pull_force / (2 normal_force) (Eq. 1) over the last fraction of the run."""
    import numpy as np

    t = np.asarray(time)
    sel = (t >= t[-1] - last * (t[-1] - t[0]) - 1e-12) & (np.asarray(normal_force) > 0)
    return float(np.mean(np.asarray(pull_force)[sel] / (2.0 * np.asarray(normal_force)[sel])))


__all__ = ["COMPONENTS", "ComponentModel", "check_component_scene", "component_problems", "load_component_scene",
           "make_model",
           "reference_for_scene", "steady_ratio", "table_path"]
