"""Scenes built from this project's components: every scene value checked once, against the component declaration.

A scene FMU given as ``component = "<name>"`` is the FMU of a component of :mod:`tribocosim.components.registry`,
whose declaration (:class:`~tribocosim.components.description.Component`) the FMU's model description derives
from. :func:`check_components` checks the scene's values of such an FMU against the declaration, each value once,
and the model description's ranges are not checked again (:mod:`tribocosim.cosim.scene.validate` does that for FMUs
given by path):

- every name is a parameter, a file or an input of the component;
- a resource file the C code reads (``Native.resource_parameters``: the strip's ``table_file``) given by a relative
  name is looked for beside the scene file first, then among the packaged files (``models/``, the component's
  ``resource_dir``); the file found replaces the name in the scene's values (a packaged file the FMU carries keeps its
  name), and a name found in neither is a problem naming both places;
- the parameters make the component's parameter dataclass, built once from the scene's values: each field's type,
  range or choices (:func:`tribocosim.components.params.validate_fields`), then the rules across fields (a
  malformed press ``setpoint_table``); every bad field is reported under its own key;
- the component's own ``check`` runs (the strip's table and field file, the cap of beta);
- an input held at a scene value is a finite number inside the range its port declares (``low``, ``high``: the
  strip is pulled, grip_velocity >= 0) and the component's ``input_limits`` (the strip's pressure at most its
  hardness, its grip slower than its waves);
- every connection from an output with known set-points (``setpoints``: the press's force, the drive's velocity)
  to an input is matched against the input's port range, its ``input_limits`` and the limits of ``check`` (the
  strip's table axes).

Its result holds, per instance, the scene's values as the FMU reads them (:func:`fmu_value`: an integer field as an
int; a resource file the C code reads in another form, the strip's ``table_file`` .npz, converted once into the
cache), which the plan sets into the FMU. :func:`end_warnings` gives the outputs a component declares to watch at the
end of a run (the strip's ``table_clamp_count``).

The monolithic reference of such a scene is :func:`tribocosim.cosim.studies.monolithic.reference_for_scene`.

This is, with :mod:`tribocosim.cosim.scene.fmucache`, where :mod:`tribocosim.cosim` imports
:mod:`tribocosim.components`.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

from tribocosim.components.params import bound_text, within_bounds
from tribocosim.errors import ParameterError, Problem
from tribocosim.cosim.scene.problems import Problems, known


def component_of(spec):
    """The component description of a scene FMU spec, or None (a ``path = ...`` FMU or an unknown name)."""
    if spec.component is None:
        return None
    from tribocosim.components import registry

    return registry.find(spec.component)


class Checked:
    """The component checks of a scene: every problem, and per component instance whose values are all good the
    scene's values as the FMU reads them (``{FMU variable: value}``)."""

    __slots__ = ("problems", "values")

    def __init__(self) -> None:
        self.problems: list[Problem] = []
        self.values: dict[str, dict] = {}


def _instance(cls, given: dict, add, key: str):
    """The dataclass ``cls`` made once from ``given``, or None after reporting a rule across fields that fails.

    A bad field is reported under its key and the dataclass is made again without the bad fields (their defaults
    instead), so that the checks that need an instance still run and a scene's problems are reported at once."""
    try:
        return cls(**given)
    except ParameterError as exc:
        if not exc.fields:  # a rule across fields
            add(key, str(exc))
            return None
        for name, message in exc.fields:
            add(f"{key}.{name}", message)
        bad = {name for name, _ in exc.fields}
    try:
        return cls(**{k: v for k, v in given.items() if k not in bad})
    except ParameterError:
        return None


def check_components(scene) -> Checked:
    """Check the component FMUs of ``scene`` (a :class:`tribocosim.cosim.scene.schema.Scene`, parsed, not
    necessarily valid) against their declarations; see the module docstring."""
    problems = Problems(scene.path)
    out = Checked()
    found = {name: comp for name, spec in scene.fmus.items() if (comp := component_of(spec)) is not None}
    limits: dict[str, dict] = {}
    setpoints: dict[str, dict] = {}
    physical: dict[str, dict] = {}
    for name, comp in found.items():
        key = f"fmus.{name}.parameters"
        before = len(problems)
        own = {f.name for f in dataclasses.fields(comp.parameters)}
        files_names = {f.name for f in dataclasses.fields(comp.files)} if comp.files is not None else set()
        inputs = {p.name: p for p in comp.inputs}
        given = scene.fmus[name].parameters
        missing = set()  # resource files found nowhere (the component's own check would say it again)
        for pname, file in _resource_files(comp, given, scene.path.parent).items():
            if isinstance(file, str):
                problems.add(f"{key}.{pname}", file)
                missing.add(pname)
            else:
                given[pname] = str(file)
        for pname, value in given.items():
            if pname in own or pname in files_names or pname in inputs:
                continue
            if any(p.name == pname for p in comp.outputs):
                problems.add(f"{key}.{pname}", f"{pname!r} is an output of component {comp.name!r}; only parameters "
                                               "and inputs can be set")
            else:
                problems.add(f"{key}.{pname}", f"unknown parameter of component {comp.name!r}; "
                                               f"{known([*own, *files_names, *inputs], pname)}")
        params = _instance(comp.parameters, {k: v for k, v in given.items() if k in own}, problems.add, key)
        files = (_instance(comp.files, {k: v for k, v in given.items() if k in files_names}, problems.add, key)
                 if comp.files is not None else None)
        for pname, port in inputs.items():  # inputs held at a scene value
            if pname in given and (isinstance(given[pname], bool) or not isinstance(given[pname], (int, float))):
                problems.add(f"{key}.{pname}", f"{pname!r} is an input of type Real; got {given[pname]!r}")
        if params is None or (comp.files is not None and files is None):
            continue
        if comp.check is not None:
            own_problems, limits[name] = comp.check(params, files, comp.resource_dir)
            for pname, message in own_problems:
                if pname not in missing:
                    problems.add(f"{key}.{pname}" if pname else key, message)
        if comp.setpoints is not None:
            setpoints[name] = comp.setpoints(params)
        if comp.input_limits is not None:
            physical[name] = comp.input_limits(params)
        for pname, port in inputs.items():
            value = given.get(pname)
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                label = f"{pname} = {bound_text(float(value))}{_unit(port)}"
                limit = physical.get(name, {}).get(pname)
                message = _outside_port(comp, given, port, float(value), label, f"{name}.{pname}") or (
                    limit(float(value), label, name) if limit else None)
                if message:
                    problems.add(f"{key}.{pname}", message)
        if len(problems) == before:
            out.values[name] = {pname: fmu_value(comp, pname, getattr(params, pname) if pname in own else
                                                 getattr(files, pname) if pname in files_names else value)
                                for pname, value in given.items()}
    for link in scene.connections:  # set-points of one instance against the inputs of another
        src, dst = link.source, link.target
        comp = found.get(dst.instance)
        port = next((p for p in comp.inputs if p.name == dst.variable), None) if comp is not None else None
        checks = [lim for lim in (limits.get(dst.instance, {}).get(dst.variable),
                                  physical.get(dst.instance, {}).get(dst.variable)) if lim is not None]
        for sp in setpoints.get(src.instance, {}).get(src.variable, []):
            messages = (_outside_port(comp, scene.fmus[dst.instance].parameters, port, sp.value, sp.label, str(dst))
                        if port is not None else None, *(lim(sp.value, sp.label, dst.instance) for lim in checks))
            for message in messages:
                if message:
                    problems.add(f"fmus.{src.instance}.parameters.{sp.parameter}", message)
    out.problems = problems.items
    return out


def _resource_files(comp, given: dict, folder: Path) -> dict:
    """``{parameter: the file found (Path), or why none is (str)}`` of the resource files ``given`` names relatively
    (see the module docstring); a name of a file the FMU carries is left out when no file of that name lies beside the
    scene (the FMU reads its own)."""
    native = comp.native
    if native is None:
        return {}
    carried = {name for _, name in comp.resources}
    out = {}
    for pname in native.resource_parameters:
        value = given.get(pname)
        if not isinstance(value, str) or not value or Path(value).is_absolute():
            continue
        beside, packaged = (folder / value).resolve(), Path(comp.resource_dir) / value
        if beside.is_file():
            out[pname] = beside
        elif packaged.is_file():
            if value not in carried:
                out[pname] = packaged.resolve()
        else:
            out[pname] = (f"file {value!r} not found: looked for it beside the scene ({beside}) and among the packaged "
                          f"files ({packaged}); give a path relative to the scene's folder, or an absolute one")
    return out


def component_problems(scene) -> list[Problem]:
    """The problems :func:`check_components` finds (``scene``: a parsed scene or a validated plan)."""
    return check_components(getattr(scene, "scene", scene)).problems


def fmu_value(comp, name: str, value):
    """The value of parameter ``name`` of component ``comp`` as its FMU reads it: a resource file its C code reads in
    another form (``Native.resource_parameters``, e.g. the strip's ``table_file`` .npz) converted once into the cache
    (``Native.convert_resource``; a relative name is a file of the FMU's resources, converted by its build); every
    other value as it is."""
    native = comp.native
    if native is None or native.convert_resource is None or name not in native.resource_parameters:
        return value
    source = Path(value) if isinstance(value, str) and value else None
    if source is None or not source.is_absolute() or not source.is_file():
        return value
    from tribocosim.components.native.toolchain.digests import file_sha256
    from tribocosim.components.native.toolchain.library import cache_dir

    folder = cache_dir() / "resources" / file_sha256(source)[:20]
    converted = folder / f"{source.stem}.tca"
    if not converted.is_file():
        folder.mkdir(parents=True, exist_ok=True)
        native.convert_resource(source, folder)
    return str(converted)


def end_warnings(comp) -> dict[str, str]:
    """``{output: what its value above 0 at the end of a run means}`` of a component (``Port.end_warning``)."""
    return {p.name: p.end_warning for p in comp.outputs if p.end_warning}


def _unit(port) -> str:
    return f" {port.unit}" if port.unit not in ("", "1") else ""


def _outside_port(comp, values: dict, port, value: float, label: str, where: str) -> str | None:
    """Why ``value`` (``label``: how to name it) lies outside the range input ``port`` of component ``comp``
    declares (:class:`~tribocosim.components.description.Port` ``low``/``high``, bounds that name a parameter
    taken from ``values``), or None. ``where``: the input, ``instance.variable``."""
    if not math.isfinite(value):
        return f"{label} is not finite; a finite number is required"
    try:
        low, high = comp.bounds(port, values)
    except (ParameterError, TypeError, ValueError):  # a bad bound parameter is reported as that parameter
        return None
    instance = where.split(".")[0]
    for bound, named, side, least, outside in ((low, port.low, "below", "least", not within_bounds(value, low=low)),
                                               (high, port.high, "above", "largest",
                                                not within_bounds(value, high=high))):
        if outside:  # beyond the bound by more than BOUND_RTOL of it, as the FMU's own check (tc_below, tc_above)
            of = f" ({named} of '{instance}')" if isinstance(named, str) else ""
            return (f"{label} is {side} {bound_text(bound)}{_unit(port)}{of}, the {least} {where} the model is built "
                    "for" + (f" ({port.why})" if port.why else ""))
    return None


__all__ = ["Checked", "check_components", "component_of", "component_problems", "end_warnings", "fmu_value"]
