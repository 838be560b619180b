"""Scenes built from this project's components: their parameters checked against the component descriptions.

A scene FMU given as ``component = "<name>"`` is the FMU of a component of
:mod:`tribocosim.components.registry`, whose description
(:class:`~tribocosim.components.description.Component`) this module reads to

- check the parameters before anything runs (:func:`component_problems`): the FMUs declare
  min/max for Reals, which :mod:`tribocosim.cosim.scene.validate` checks, but no choices for Strings
  (``friction_model = "tabel"``), no cross-field rules (a malformed press ``setpoint_table``) and
  nothing that spans instances. Each parameter is checked against its dataclass, then the
  component's own ``check`` runs (e.g. the strip's table and field file, the cap of beta), and
  every connection from an output with known set-points (``setpoints``: the press's force, the
  drive's velocity) to an input is matched against the range the input's port declares (``low``,
  ``high``: the strip is pulled, grip_velocity >= 0), the component's ``input_limits`` (the strip's
  pressure at most its hardness, its grip slower than its waves) and the limits of ``check`` (the strip's
  table axes); an input held at a scene value is matched against the first two, and must be finite.

The monolithic reference of such a scene is :func:`tribocosim.cosim.apps.monolithic.reference_for_scene`.

This is, with :mod:`tribocosim.cosim.scene.fmucache`, where :mod:`tribocosim.cosim` imports
:mod:`tribocosim.components`; the imports are lazy, and a scene of FMU files imports none of it.
"""

from __future__ import annotations

import dataclasses
import math

from tribocosim.errors import ParameterError, Problem, SceneError


def component_of(spec):
    """The component description of a scene FMU spec, or None (a ``path = ...`` FMU or an unknown name)."""
    if spec.component is None:
        return None
    from tribocosim.components import registry

    return registry.find(spec.component)


def _split(comp, given: dict, add, key: str):
    """(parameters, files) of ``given`` (the FMU's parameters), each bad field reported by name."""
    instances = []
    for cls in (comp.parameters, comp.files):
        if cls is None:
            instances.append(None)
            continue
        names = {f.name for f in dataclasses.fields(cls)}
        default = cls()
        ok = {}
        for name, value in given.items():  # one field at a time: the message names the culprit
            if name not in names:
                continue
            try:
                dataclasses.replace(default, **{name: value})
                ok[name] = value
            except ParameterError as exc:
                add(f"{key}.{name}", str(exc))
            except TypeError as exc:
                add(f"{key}.{name}", f"{name} = {value!r}: {exc}")
        try:
            instances.append(cls(**ok))
        except ParameterError as exc:  # a rule across fields
            add(key, str(exc))
            instances.append(None)
    return instances


def component_problems(scene) -> list[Problem]:
    """Problems of the component parameters of a scene.

    ``scene`` is a :class:`tribocosim.cosim.scene.schema.Scene` (parsed, not necessarily valid) or a validated plan.
    """
    from tribocosim.cosim.scene.problems import Problems

    scene = getattr(scene, "scene", scene)
    problems = Problems(scene.path)
    found = {name: comp for name, spec in scene.fmus.items() if (comp := component_of(spec)) is not None}
    limits: dict[str, dict] = {}
    setpoints: dict[str, dict] = {}
    physical: dict[str, dict] = {}
    for name, comp in found.items():
        key = f"fmus.{name}.parameters"
        params, files = _split(comp, scene.fmus[name].parameters, problems.add, key)
        if params is None or (comp.files is not None and files is None):
            continue
        if comp.check is not None:
            own, limits[name] = comp.check(params, files, comp.resource_dir)
            for pname, message in own:
                problems.add(f"{key}.{pname}" if pname else key, message)
        if comp.setpoints is not None:
            setpoints[name] = comp.setpoints(params)
        if comp.input_limits is not None:
            physical[name] = comp.input_limits(params)
    for name, comp in found.items():  # inputs held at a scene value
        given = scene.fmus[name].parameters
        for port in comp.inputs:
            value = given.get(port.name)
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                label = f"{port.name} = {value:g}{_unit(port)}"
                limit = physical.get(name, {}).get(port.name)
                message = _outside_port(comp, given, port, float(value), label, f"{name}.{port.name}") or (
                    limit(float(value), label, name) if limit else None)
                if message:
                    problems.add(f"fmus.{name}.parameters.{port.name}", message)
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
    return problems.items


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
    for bound, named, side, least, outside in ((low, port.low, "below", "least", low is not None and value < low),
                                               (high, port.high, "above", "largest",
                                                high is not None and value > high)):
        if outside:
            of = f" ({named} of '{instance}')" if isinstance(named, str) else ""
            return (f"{label} is {side} {bound:g}{_unit(port)}{of}, the {least} {where} the model is built for"
                    + (f" ({port.why})" if port.why else ""))
    return None


def load_component_scene(path, overrides: dict | None = None):
    """:func:`tribocosim.cosim.scene.validate.load_scene` plus :func:`component_problems`, all problems in one SceneError.

    (The component checks run on the parsed scene even when the FMU-level validation fails, and
    a key that both report is listed once.)
    """
    from tribocosim.cosim.scene.problems import Problems
    from tribocosim.cosim.scene.schema import parse_scene
    from tribocosim.cosim.scene.validate import load_scene

    scene, _ = parse_scene(path, overrides)
    extra = component_problems(scene) if scene is not None else []
    try:
        plan = load_scene(path, overrides)
    except SceneError as exc:
        problems = Problems(scene.path if scene is not None else path)
        problems.extend(exc.problems)
        problems.extend(extra, skip_known_keys=True)
        raise problems.error() from None
    if extra:
        problems = Problems(plan.scene.path)
        problems.extend(extra)
        problems.raise_if_any()
    return plan


__all__ = ["component_of", "component_problems", "load_component_scene"]
