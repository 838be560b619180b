"""The scene pipeline: a scene file parsed once, each value checked once, every FMU's model description read.

:func:`load_scene` parses a scene (:func:`tribocosim.cosim.scene.schema.parse_scene`), checks the FMUs built from
the project's components against their declarations (:func:`tribocosim.cosim.scene.component_checks.check_components`),
reads the model description of every FMU it names (:func:`tribocosim.cosim.scene.fmu_files.summary`: once per
file content; no shared library is loaded), and checks

- FMU files: present, FMI 2.0, co-simulation, with a complete library for this machine
  (:mod:`tribocosim.cosim.scene.binaries`: a truncated one crashed the process with a bus error);
- parameters of an FMU given by path: known, settable (causality parameter or input), of the right type, finite,
  inside a declared min/max (those of a component's FMU were checked against its declaration, from which its
  model description's ranges derive);
- connections: known instances and variables, output -> input causality, compatible types,
  equal units where both sides declare one, one connection per input;
- outputs to record: known, numeric;
- master settings against FMU capabilities (schemes that roll back need
  ``canGetAndSetFMUstate``), Gauss-Seidel order, power bonds.

All problems are collected and raised in one :class:`~tribocosim.errors.SceneError`, each
line naming the file and the key. Unconnected inputs are warnings that give the start value
used. The result, :class:`Plan`, holds everything the master needs with value references
resolved: the values to set into each FMU (as it reads them) and the outputs to watch at the end of the run.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

from tribocosim.components.params import within_bounds
from tribocosim.errors import SceneError
from tribocosim.cosim.engine.schemes import ALGORITHMS, ESTIMATORS, VariableRef
from tribocosim.cosim.scene.component_checks import check_components, component_of, end_warnings
from tribocosim.cosim.scene.fmu_files import FmuFileError, FmuSummary, summary
from tribocosim.cosim.scene.problems import Problems, known
from tribocosim.cosim.scene.schema import Scene, parse_scene

_NUMERIC = ("Real", "Integer", "Boolean", "Enumeration")
_DER = re.compile(r"^der\((?P<name>.+?)(?:,\s*(?P<order>\d+))?\)$")


class FmuModel:
    """One FMU of a scene with its model description.

    Attributes
    ----------
    name : str
        Instance name.
    path : Path
        The .fmu file.
    summary : FmuSummary
        What its model description says that a run needs (:mod:`tribocosim.cosim.scene.fmu_files`).
    variables : dict
        Name -> :class:`~tribocosim.cosim.scene.fmu_files.Variable`.
    dependencies : dict
        Output name -> set of input names it depends on directly, or None when the model
        description does not say (then the master probes it numerically).
    derivative_inputs : dict
        Input name -> {order: value reference} of companion inputs ``der(u)``/``der(u,2)``.
    feedthrough : bool or None
        As the scene declares it (None: from the model description, else probed).
    """

    __slots__ = ("name", "path", "summary", "variables", "dependencies", "derivative_inputs", "feedthrough", "_md")

    def __init__(self, name: str, path: Path, summary: FmuSummary, variables: dict, dependencies: dict,
                 derivative_inputs: dict, feedthrough: bool | None = None) -> None:
        self.name, self.path, self.summary, self.variables = name, path, summary, variables
        self.dependencies, self.derivative_inputs, self.feedthrough = dependencies, derivative_inputs, feedthrough
        self._md = None

    def __repr__(self) -> str:
        return f"FmuModel({self.name!r}, {str(self.path)!r})"

    @property
    def can_roll_back(self) -> bool:
        return self.summary.can_get_and_set_fmu_state

    @property
    def can_interpolate_inputs(self) -> bool:
        return self.summary.can_interpolate_inputs

    @property
    def md(self):
        """fmpy's model description of the FMU (read on first use: unit definitions, declared types, ...)."""
        if self._md is None:
            from fmpy import read_model_description

            self._md = read_model_description(str(self.path))
        return self._md


class EndCheck:
    """An output (``variable``) to read at the end of a run: above 0 it means ``FMU instance '<instance>': <value>
    <message>``."""

    __slots__ = ("instance", "value_reference", "type", "message", "variable")

    def __init__(self, instance: str, value_reference: int, type: str, message: str,  # noqa: A002
                 variable: str = "") -> None:
        self.instance, self.value_reference, self.type, self.message = instance, value_reference, type, message
        self.variable = variable


class Link:
    """A resolved connection: source output -> target input, with value references and FMI types, whether it
    carries a continuous Real, and the scene key of the connection."""

    __slots__ = ("source", "target", "source_vr", "target_vr", "source_type", "target_type", "continuous", "key")

    def __init__(self, source: VariableRef, target: VariableRef, source_vr: int, target_vr: int, source_type: str,
                 target_type: str, continuous: bool, key: str) -> None:
        self.source, self.target, self.source_vr, self.target_vr = source, target, source_vr, target_vr
        self.source_type, self.target_type, self.continuous, self.key = source_type, target_type, continuous, key

    def __repr__(self) -> str:
        return f"Link({self.source} -> {self.target})"


class Plan:
    """A validated scene with every reference resolved: the FMUs, the links, the recorded variables (``[(ref, value
    reference, type), ...]`` in column order), the power bonds as pairs of link indices, warnings and notes, per
    instance the scene's parameter values as the FMU reads them (``[(value reference, type, value), ...]``), and the
    outputs to read at the end of the run."""

    __slots__ = ("scene", "fmus", "links", "recorded", "bonds", "warnings", "notes", "parameters", "end_checks")

    def __init__(self, scene: Scene, fmus: dict[str, FmuModel], links: list[Link], recorded: list) -> None:
        self.scene, self.fmus, self.links, self.recorded = scene, fmus, links, recorded
        self.bonds: list[tuple[int, int]] = []
        self.warnings: list[str] = []
        self.notes: list[str] = []
        self.parameters: dict[str, list] = {}
        self.end_checks: list[EndCheck] = []


def unit_of(var) -> str | None:
    """The declared unit of a variable (own attribute, else its declared type's; fmpy's variables and
    :class:`~tribocosim.cosim.scene.fmu_files.Variable`)."""
    if getattr(var, "unit", None):
        return var.unit
    dt = getattr(var, "declaredType", None)
    return getattr(dt, "unit", None) or None


def load_scene(path: str | Path, overrides: dict | None = None, document: dict | None = None) -> Plan:
    """Parse and validate a scene; raise one SceneError listing every problem.

    Parameters
    ----------
    path : str or Path
        The scene file.
    overrides : dict, optional
        Dotted keys to set before validation (see :func:`tribocosim.cosim.scene.schema.apply_overrides`).
    document : dict, optional
        The file's TOML document when it was read already (:func:`tribocosim.cosim.scene.schema.read_document`).

    Returns
    -------
    Plan
        The validated scene with resolved FMUs, connections and recorded variables.

    Raises
    ------
    SceneError
        With every problem (``.problems``: file, key, message), one line each in the message.
    """
    scene, parsed = parse_scene(path, overrides, document)
    problems = Problems(scene.path if scene is not None else Path(path).resolve())
    problems.extend(parsed)
    if scene is None:
        problems.raise_if_any()
    checked = check_components(scene)
    problems.extend(checked.problems)
    plan = Plan(scene, {}, [], [])
    add = problems.add

    for name, spec in scene.fmus.items():
        key = f"fmus.{name}"
        fmu_path = spec.path
        if spec.component is not None:
            from tribocosim.cosim.scene.fmucache import component_fmu

            try:
                fmu_path = component_fmu(spec.component)
            except SceneError as exc:
                add(f"{key}.component", str(exc))
                continue
        if fmu_path is None:
            continue
        if fmu_path.is_dir():
            add(f"{key}.path", f"{fmu_path} is a folder, not an FMU file: give the .fmu file (the zip archive of an "
                               "FMU's folder)")
            continue
        if not fmu_path.is_file():
            add(f"{key}.path", f"FMU file not found: {fmu_path}")
            continue
        try:
            info = summary(fmu_path)
        except FmuFileError as exc:
            add(f"{key}.path", f"cannot read the model description of {fmu_path.name}: {exc}")
            continue
        if info.fmi_version != "2.0":
            add(f"{key}.path", f"{fmu_path.name} is FMI {info.fmi_version}; the master runs FMI 2.0 co-simulation FMUs")
            continue
        if info.model_identifier is None:
            add(f"{key}.path", f"{fmu_path.name} has no co-simulation interface (model exchange only)")
            continue
        if info.binary_problem:
            add(f"{key}.path", info.binary_problem)
            continue
        plan.fmus[name] = model = _fmu_model(name, fmu_path, info, spec.feedthrough)
        comp = component_of(spec)
        if comp is not None:  # checked against the declaration (check_components); the values as the FMU reads them
            values = checked.values.get(name, {})
            for pname, value in values.items():
                var = model.variables.get(pname)
                if var is None:
                    add(f"{key}.parameters.{pname}", f"{fmu_path.name} has no variable {pname!r} though component "
                                                     f"{comp.name!r} declares it: rebuild the FMU")
                    continue
                plan.parameters.setdefault(name, []).append((var.valueReference, var.type, value))
        else:
            comp = None
            if info.generation_tool.startswith("tribocosim"):  # our FMU run by path (an SSP package's)
                from tribocosim.components import registry

                comp = registry.find(info.model_identifier)
            for pname, value in spec.parameters.items():
                if _check_parameter(add, f"{key}.parameters.{pname}", model, pname, value):
                    var = model.variables[pname]
                    plan.parameters.setdefault(name, []).append((var.valueReference, var.type, value))
        for output, message in (end_warnings(comp) if comp is not None else {}).items():
            var = model.variables.get(output)
            if var is not None and var.causality == "output":
                plan.end_checks.append(EndCheck(name, var.valueReference, var.type, message, output))

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


def _fmu_model(name: str, path: Path, info: FmuSummary, feedthrough: bool | None) -> FmuModel:
    variables = {v.name: v for v in info.variables}
    deps = {out: (None if inputs is None else set(inputs)) for out, inputs in info.dependencies.items()}
    derivs: dict[str, dict[int, int]] = {}
    for v in info.variables:
        m = _DER.match(v.name)
        if m and v.causality == "input" and v.type == "Real":
            base = variables.get(m.group("name"))
            if base is not None and base.causality == "input":
                derivs.setdefault(base.name, {})[int(m.group("order") or 1)] = v.valueReference
    return FmuModel(name, path, info, variables, deps, derivs, feedthrough)


def _check_parameter(add, key: str, model: FmuModel, pname: str, value) -> bool:
    """Check a scene value of a parameter of an FMU given by path against its model description; False after
    reporting a problem."""
    var = model.variables.get(pname)
    if var is None:
        settable = [n for n, v in model.variables.items() if v.causality in ("parameter", "input")]
        add(key, f"unknown parameter of {model.path.name}; {known(settable, pname)}")
        return False
    if var.causality not in ("parameter", "input") or var.variability == "constant":
        add(key, f"{pname!r} has causality {var.causality!r} and variability {var.variability!r}; only parameters and inputs can be set")
        return False
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
        return False
    if t == "Real" and not math.isfinite(value):
        add(key, f"{pname} = {value!r} is not finite; a finite number is required")
        return False
    if t in ("Real", "Integer"):
        lo, hi = (None if x is None else float(x) for x in (var.min, var.max))
        if t == "Real" and model.summary.generation_tool.startswith("tribocosim"):
            inside = within_bounds(value, lo, hi)  # as the FMU's own check: on a bound to BOUND_RTOL of it
        else:  # FMI's inclusive min and max, as another tool's FMU may check them
            inside = (lo is None or value >= lo) and (hi is None or value <= hi)
        if not inside:
            add(key, f"{pname} = {value!r} is outside the declared range [{var.min}, {var.max}]")
            return False
    return True


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
        for v in model.variables.values():
            if v.causality != "input" or (name, v.name) in connected or v.valueReference in derivative_vrs:
                continue
            value = params.get(v.name, v.start)
            origin = "scene value" if v.name in params else "start value"
            plan.warnings.append(f"input {name}.{v.name} is not connected; its {origin} {value} is used")

