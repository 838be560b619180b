"""Second validation pass: the scene against the FMUs' model descriptions.

:func:`load_scene` parses a scene (:func:`tribocosim.cosim.scene.schema.parse_scene`), reads the model
description of every FMU it names (no shared library is loaded), and checks

- FMU files: present, FMI 2.0, co-simulation, with a complete library for this machine
  (:mod:`tribocosim.cosim.scene.binaries`: a truncated one crashed the process with a bus error);
- parameters: known, settable (causality parameter or input), of the right type, finite, inside a
  declared min/max;
- connections: known instances and variables, output -> input causality, compatible types,
  equal units where both sides declare one, one connection per input;
- outputs to record: known, numeric;
- master settings against FMU capabilities (schemes that roll back need
  ``canGetAndSetFMUstate``), Gauss-Seidel order, power bonds.

All problems are collected and raised in one :class:`~tribocosim.errors.SceneError`, each
line naming the file and the key. Unconnected inputs are warnings that give the start value
used. The result, :class:`Plan`, holds everything the master needs with value references
resolved.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from fmpy import read_model_description

from tribocosim.errors import SceneError
from tribocosim.cosim.engine.algorithms import ALGORITHMS
from tribocosim.cosim.scene.binaries import fmu_binary_problem
from tribocosim.cosim.scene.problems import Problems, known
from tribocosim.cosim.engine.stepcontrol import ESTIMATORS
from tribocosim.cosim.engine.system import VariableRef
from tribocosim.cosim.scene.schema import Scene, parse_scene

_NUMERIC = ("Real", "Integer", "Boolean", "Enumeration")
_DER = re.compile(r"^der\((?P<name>.+?)(?:,\s*(?P<order>\d+))?\)$")


@dataclass
class FmuModel:
    """One FMU of a scene with its model description.

    Attributes
    ----------
    name : str
        Instance name.
    path : Path
        The .fmu file.
    md : fmpy.model_description.ModelDescription
    variables : dict
        Name -> fmpy ModelVariable.
    dependencies : dict
        Output name -> set of input names it depends on directly, or None when the model
        description does not say (then the master probes it numerically).
    derivative_inputs : dict
        Input name -> {order: value reference} of companion inputs ``der(u)``/``der(u,2)``.
    """

    name: str
    path: Path
    md: object
    variables: dict
    dependencies: dict
    derivative_inputs: dict
    feedthrough: bool | None = None

    @property
    def can_roll_back(self) -> bool:
        return bool(self.md.coSimulation.canGetAndSetFMUstate)

    @property
    def can_interpolate_inputs(self) -> bool:
        return bool(self.md.coSimulation.canInterpolateInputs)


@dataclass(frozen=True)
class Link:
    """A resolved connection: source output -> target input, with value references."""

    source: VariableRef
    target: VariableRef
    source_vr: int
    target_vr: int
    source_type: str
    target_type: str
    continuous: bool
    key: str


@dataclass
class Plan:
    """A validated scene with every reference resolved."""

    scene: Scene
    fmus: dict[str, FmuModel]
    links: list[Link]
    recorded: list[tuple[VariableRef, int, str]]
    bonds: list[tuple[int, int]] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


def unit_of(var) -> str | None:
    """The declared unit of a variable (own attribute, else its declared type's)."""
    if getattr(var, "unit", None):
        return var.unit
    dt = getattr(var, "declaredType", None)
    return getattr(dt, "unit", None) or None


def load_scene(path: str | Path, overrides: dict | None = None) -> Plan:
    """Parse and validate a scene; raise one SceneError listing every problem.

    Parameters
    ----------
    path : str or Path
        The scene file.
    overrides : dict, optional
        Dotted keys to set before validation (see :func:`tribocosim.cosim.scene.schema.apply_overrides`).

    Returns
    -------
    Plan
        The validated scene with resolved FMUs, connections and recorded variables.

    Raises
    ------
    SceneError
        With every problem (``.problems``: file, key, message), one line each in the message.
    """
    scene, parsed = parse_scene(path, overrides)
    problems = Problems(scene.path if scene is not None else Path(path).resolve())
    problems.extend(parsed)
    if scene is None:
        problems.raise_if_any()
    plan = Plan(scene, {}, [], [])
    add = problems.add

    for name, spec in scene.fmus.items():
        key = f"fmus.{name}"
        fmu_path = spec.path
        if spec.component is not None:
            from tribocosim.cosim.scene.fmucache import component_fmu

            try:
                fmu_path = component_fmu(spec.component, variant=spec.variant)
            except SceneError as exc:
                add(f"{key}.component", str(exc))
                continue
        if fmu_path is None:
            continue
        if not fmu_path.is_file():
            add(f"{key}.path", f"FMU file not found: {fmu_path}")
            continue
        try:
            md = read_model_description(str(fmu_path), validate=True)
        except Exception as exc:
            add(f"{key}.path", f"cannot read the model description of {fmu_path.name}: {exc}")
            continue
        if md.fmiVersion != "2.0":
            add(f"{key}.path", f"{fmu_path.name} is FMI {md.fmiVersion}; the master runs FMI 2.0 co-simulation FMUs")
            continue
        if md.coSimulation is None:
            add(f"{key}.path", f"{fmu_path.name} has no co-simulation interface (model exchange only)")
            continue
        broken = fmu_binary_problem(fmu_path, md.coSimulation.modelIdentifier)
        if broken:
            add(f"{key}.path", broken)
            continue
        plan.fmus[name] = model = _fmu_model(name, fmu_path, md, spec.feedthrough)
        for pname, value in spec.parameters.items():
            _check_parameter(add, f"{key}.parameters.{pname}", model, pname, value)

    def lookup(ref: VariableRef, key: str, causalities: tuple[str, ...], role: str):
        if ref.instance not in scene.fmus:
            add(key, f"unknown instance {ref.instance!r}; {known(scene.fmus, ref.instance)}")
            return None
        model = plan.fmus.get(ref.instance)
        if model is None:
            return None  # its FMU already has a problem
        var = model.variables.get(ref.variable)
        names = [n for n, v in model.variables.items() if v.causality in causalities]
        if var is None:
            add(key, f"unknown variable {ref.variable!r} in instance {ref.instance!r} ({model.path.name}); {role}: {known(names, ref.variable)}")
            return None
        if var.causality not in causalities:
            add(key, f"{ref} has causality {var.causality!r}; {role} need causality {' or '.join(causalities)}; {known(names)}")
            return None
        return var

    connected: dict[tuple[str, str], str] = {}
    for c in scene.connections:
        src = lookup(c.source, f"{c.key}.from", ("output",), "outputs")
        dst = lookup(c.target, f"{c.key}.to", ("input",), "inputs")
        if src is None or dst is None:
            continue
        tkey = (c.target.instance, c.target.variable)
        if tkey in connected:
            add(f"{c.key}.to", f"input {c.target} is already connected by {connected[tkey]}")
            continue
        connected[tkey] = c.key
        if src.type == "String" or dst.type == "String":
            add(c.key, f"string connections are not supported ({c.source} -> {c.target})")
            continue
        if not (src.type == dst.type or (src.type in ("Integer", "Enumeration", "Boolean") and dst.type == "Real")):
            add(c.key, f"type mismatch: {c.source} is {src.type}, {c.target} is {dst.type}")
            continue
        us, ud = unit_of(src), unit_of(dst)
        if us and ud and us != ud:
            add(c.key, f"unit mismatch: {c.source} is in {us!r}, {c.target} in {ud!r}")
            continue
        continuous = src.type == "Real" and dst.type == "Real" and src.variability == "continuous"
        plan.links.append(Link(c.source, c.target, src.valueReference, dst.valueReference, src.type, dst.type, continuous, c.key))

    for i, ref in enumerate(scene.output.variables):
        var = lookup(ref, f"output.variables[{i}]", ("output", "local", "parameter", "calculatedParameter", "input"), "variables")
        if var is None:
            continue
        if var.type not in _NUMERIC:
            add(f"output.variables[{i}]", f"{ref} is a {var.type}; only numeric variables can be recorded")
            continue
        plan.recorded.append((ref, var.valueReference, var.type))

    _check_master(add, plan)
    _check_bonds(add, plan)
    _warn_unconnected(plan, connected)
    problems.raise_if_any()
    return plan


def _fmu_model(name: str, path: Path, md, feedthrough: bool | None) -> FmuModel:
    variables = {v.name: v for v in md.modelVariables}
    deps: dict[str, set[str] | None] = {}
    listed = {u.variable.name: u for u in (md.outputs or [])}
    for v in md.modelVariables:
        if v.causality != "output":
            continue
        u = listed.get(v.name)
        if u is None or u.dependencies is None:
            deps[v.name] = None
        else:
            deps[v.name] = {d.name for d in u.dependencies if d.causality == "input"}
    derivs: dict[str, dict[int, int]] = {}
    for v in md.modelVariables:
        m = _DER.match(v.name)
        if m and v.causality == "input" and v.type == "Real":
            base = variables.get(m.group("name"))
            if base is not None and base.causality == "input":
                derivs.setdefault(base.name, {})[int(m.group("order") or 1)] = v.valueReference
    return FmuModel(name, path, md, variables, deps, derivs, feedthrough)


def _check_parameter(add, key: str, model: FmuModel, pname: str, value) -> None:
    var = model.variables.get(pname)
    if var is None:
        settable = [n for n, v in model.variables.items() if v.causality in ("parameter", "input")]
        add(key, f"unknown parameter of {model.path.name}; {known(settable, pname)}")
        return
    if var.causality not in ("parameter", "input") or var.variability == "constant":
        add(key, f"{pname!r} has causality {var.causality!r} and variability {var.variability!r}; only parameters and inputs can be set")
        return
    t = var.type
    ok = {
        "Real": isinstance(value, (int, float)) and not isinstance(value, bool),
        "Integer": isinstance(value, int) and not isinstance(value, bool),
        "Enumeration": isinstance(value, int) and not isinstance(value, bool),
        "Boolean": isinstance(value, bool),
        "String": isinstance(value, str),
    }.get(t, False)
    if not ok:
        add(key, f"{pname!r} is a {t}; got {value!r}")
        return
    if t == "Real" and not math.isfinite(value):
        add(key, f"{pname} = {value!r} is not finite; a finite number is required")
        return
    if t in ("Real", "Integer"):
        lo = var.min if var.min is not None else getattr(var.declaredType, "min", None)
        hi = var.max if var.max is not None else getattr(var.declaredType, "max", None)
        if (lo is not None and value < float(lo)) or (hi is not None and value > float(hi)):
            add(key, f"{pname} = {value!r} is outside the declared range [{lo}, {hi}]")


def _check_master(add, plan: Plan) -> None:
    m = plan.scene.master
    if m.order is not None:
        for i, n in enumerate(m.order):
            if n not in plan.scene.fmus:
                add(f"master.order[{i}]", f"unknown instance {n!r}; {known(plan.scene.fmus, n)}")
        missing = set(plan.scene.fmus) - set(m.order)
        if missing:
            add("master.order", f"does not list {', '.join(sorted(missing))}; give every instance once")
    cannot = sorted(n for n, f in plan.fmus.items() if not f.can_roll_back)
    if not cannot:
        return
    names = ", ".join(cannot)
    if ALGORITHMS[m.algorithm].rolls_back:
        add("master.algorithm", f"'{m.algorithm}' repeats each macro step from a saved state, but {names} cannot roll "
            "back (canGetAndSetFMUstate = false); use " + " or ".join(n for n, a in ALGORITHMS.items() if not a.rolls_back))
    if m.adaptive is not None and ESTIMATORS[m.adaptive.estimator].rolls_back:
        others = " or ".join(f'estimator = "{n}"' for n, e in ESTIMATORS.items() if not e.rolls_back)
        add("master.adaptive.estimator", f"'{m.adaptive.estimator}' rejects steps by rolling back, but {names} cannot "
            f"roll back (canGetAndSetFMUstate = false); use {others} (rollback-free) or a fixed step")
    plan.notes.append(f"FMU(s) {names} cannot roll back (canGetAndSetFMUstate = false): the scheme runs without "
                      "rollback; a discarded step or a non-finite output stops the run with an error")


def _check_bonds(add, plan: Plan) -> None:
    index = {(str(l.source), str(l.target)): i for i, l in enumerate(plan.links)}
    for b in plan.scene.power_bonds:
        found = []
        for part, c in (("effort", b.effort), ("flow", b.flow)):
            i = index.get((str(c.source), str(c.target)))
            if i is None:
                add(f"{b.key}.{part}", f"{c.source} -> {c.target} is not one of the [[connections]]")
            found.append(i)
        e, f = b.effort, b.flow
        if e.target.instance != f.source.instance or e.source.instance != f.target.instance:
            add(b.key, f"effort {e.source} -> {e.target} and flow {f.source} -> {f.target} must join the same two instances in opposite directions")
            continue
        if None not in found:
            plan.bonds.append((found[0], found[1]))


def _warn_unconnected(plan: Plan, connected: dict) -> None:
    for name, model in plan.fmus.items():
        derivative_vrs = {vr for d in model.derivative_inputs.values() for vr in d.values()}
        params = plan.scene.fmus[name].parameters
        for v in model.md.modelVariables:
            if v.causality != "input" or (name, v.name) in connected or v.valueReference in derivative_vrs:
                continue
            value = params.get(v.name, v.start)
            origin = "scene value" if v.name in params else "start value"
            plan.warnings.append(f"input {name}.{v.name} is not connected; its {origin} {value} is used")

