"""SSP 1.0 packages (System Structure and Parameterization, Modelica Association, 2019): the names both
directions share.

An SSP package is a zip with ``SystemStructure.ssd`` (the system: components, connectors,
connections, parameter bindings, default experiment) and, under ``resources/``, the FMUs and the
parameter sets (``.ssv``). :mod:`tribocosim.cosim.ssp.export` writes a scene as one;
:mod:`tribocosim.cosim.ssp.reader` reads one back as a scene for our master (``tribocosim run RIG.ssp``).

The fixed master step is not part of SSP 1.0: it travels in the Open Simulation Platform's
annotation of ``ssd:DefaultExperiment`` (``osp:FixedStepAlgorithm baseStepSize``), which libcosim
reads, and in OMSimulator's annotation of the ``ssd:System`` (``oms:FixedStepMaster stepSize``), which
OMSimulator needs to make the system at all. Our master's settings and the recorded outputs (the
scene's ``[master]``, ``[[power_bonds]]`` and ``[output]`` tables, as TOML text) travel in a
``org.tribocosim.scene`` annotation of the ``ssd:System``, which other tools ignore.

This module holds the namespaces, the small TOML writer both directions use, and the parameter set FMPy applies
(:func:`fmpy_parameter_set`). The command ``tribocosim ssp export SCENE -o RIG.ssp`` is
:mod:`tribocosim.cosim.apps.ssp_cli`.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

#: the SSP 1.0 namespaces by their customary prefixes (libcosim's parser matches the prefixes literally)
NS = {
    "ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
    "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
    "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
    "ssm": "http://ssp-standard.org/SSP1/SystemStructureParameterMapping",
    "ssb": "http://ssp-standard.org/SSP1/SystemStructureSignalDictionary",
    "osp": "http://opensimulationplatform.com/SSP/OSPAnnotations",
    "oms": "https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/schema/oms.xsd",
    "tc": "https://tribocosim.org/SSP/SceneAnnotation",
}
SSD_NAME = "SystemStructure.ssd"
FMU_TYPE = "application/x-fmu-sharedlibrary"
PARAMETER_SET_TYPE = "application/x-ssp-parameter-set"
OSP_ANNOTATION = "com.opensimulationplatform"
OMS_ANNOTATION = "org.openmodelica"
SCENE_ANNOTATION = "org.tribocosim.scene"
#: scene tables carried in the ``org.tribocosim.scene`` annotation (the rest is in the SSD proper)
SCENE_TABLES = ("master", "power_bonds", "output")


def q(name: str) -> str:
    """``"ssd:System"`` -> ``"{http://...}System"`` (ElementTree's qualified name)."""
    prefix, local = name.split(":")
    return f"{{{NS[prefix]}}}{local}"


def prefixed(tag: str) -> str:
    """``"{http://...}System"`` -> ``"ssd:System"`` (for messages); unknown namespaces as they are."""
    for prefix, uri in NS.items():
        if tag.startswith(f"{{{uri}}}"):
            return f"{prefix}:{tag[len(uri) + 2:]}"
    return tag


def fmpy_parameter_set(path: str | Path):
    """The parameter bindings of an SSP package's components as one fmpy ``ParameterSet`` with
    ``component.variable`` names, the form fmpy's ``simulate_ssp(..., parameter_set=...)`` applies
    (fmpy 0.3 reads the bindings but applies only the set it is given)::

        simulate_ssp("rig.ssp", stop_time=2.06, step_size=1e-3, parameter_set=fmpy_parameter_set("rig.ssp"))
    """
    from fmpy.ssp.ssd import ParameterSet, find_components, read_ssd

    merged = ParameterSet(name=Path(path).stem)
    for comp in find_components(read_ssd(str(path)).system):
        for binding in comp.parameterBindings:
            for pset in binding.parameterValues:
                for p in pset.parameters:
                    p.name = f"{comp.name}.{p.name}"
                    merged.parameters.append(p)
    return merged


# ------------------------------------------------------------------ TOML text
_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")


def toml_text(doc: dict) -> str:
    """A TOML document for ``doc`` (tables, arrays of tables, str/int/float/bool values and lists).

    ``tomllib.loads(toml_text(doc)) == doc`` for such documents; floats are written with ``repr``,
    so they read back bit for bit.
    """
    lines: list[str] = []
    _table(lines, [], doc)
    return "\n".join(lines).lstrip("\n") + "\n"


def _table(lines: list[str], path: list[str], table: dict) -> None:
    body, subtables, arrays = [], [], []
    for k, v in table.items():
        if isinstance(v, dict):
            subtables.append((k, v))
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            arrays.append((k, v))
        else:
            body.append(f"{_key(k)} = {_value(v)}")
    if path and (body or not (subtables or arrays)):
        lines += ["", f"[{'.'.join(map(_key, path))}]"]
    lines += body
    for k, v in subtables:
        _table(lines, path + [k], v)
    for k, items in arrays:
        for item in items:
            lines += ["", f"[[{'.'.join(map(_key, path + [k]))}]]"]
            lines += [f"{_key(ik)} = {_value(iv)}" for ik, iv in item.items()]


def _key(k: str) -> str:
    return k if _BARE_KEY.match(k) else _string(k)


def _string(s: str) -> str:
    return json.dumps(s, ensure_ascii=False).replace("\x7f", "\\u007f")


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v) if math.isfinite(v) else ("nan" if math.isnan(v) else ("inf" if v > 0 else "-inf"))
    if isinstance(v, str):
        return _string(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"no TOML value for {v!r} ({type(v).__name__})")
