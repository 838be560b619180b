"""The FMI 3.0 model description of a native FMU, from the same component description as the FMI 2.0 one.

Every variable of the FMI 2.0 model description (:func:`tribocosim.components.native.toolchain.declarations.variables`)
appears with the same name, value reference, causality, unit, description, start value and range: Real
becomes ``<Float64>``, Integer ``<Int32>``, String ``<String>`` with a ``<Start value=...>`` element.
After them (:func:`~tribocosim.components.native.toolchain.declarations.fmi3_variables`) come the independent
variable ``time`` and, for a component with array outputs (the strip's nodal fields ``beta``, ``U``,
``contact``), the UInt64 structural parameter of their length (``n_nodes``) and the arrays, each with a
``<Dimension valueReference=...>`` on it. The integer parameter the length derives from
(``n_elements``) is a structural parameter here (in FMI 2.0 a plain parameter): it fixes the mesh.
Outputs, the arrays too, have ``initial = calculated`` (computed at the end of initialization) and are
initial unknowns; no output depends directly on an input (:data:`~tribocosim.components.fmus.modeldescription.
OUTPUT_DEPENDENCIES`).
"""

from __future__ import annotations

from xml.etree.ElementTree import Element, SubElement, indent, tostring

from tribocosim.components.description import Component
from tribocosim.components.fmus.modeldescription import (INITIAL_DEPENDENCIES, OUTPUT_DEPENDENCIES, describe,
                                                         unit_definitions)
from tribocosim.components.native.toolchain import declarations

#: FMI 2.0 variable kinds -> FMI 3.0 element names
_TYPES = {"real": "Float64", "integer": "Int32", "string": "String", "uint64": "UInt64"}


def _number(x) -> str:
    return repr(float(x))


def _integer(x) -> str:
    return str(int(x))


def _variable(parent: Element, v: dict, vr: int, structural: set[str]) -> None:
    """One ``<Float64>``/``<Int32>``/``<String>``/``<UInt64>`` element for a variable of declarations."""
    kind, causality = v["kind"], v["causality"]
    text = kind == "string"
    unit = "" if text else v["unit"]
    attrs = {"name": v["name"], "valueReference": str(vr),
             "description": f"{v['description']} [text]" if text else describe(v["description"], unit),
             "causality": "structuralParameter" if v["name"] in structural else causality}
    if causality in ("parameter", "structuralParameter"):
        attrs["variability"] = "fixed"
    elif causality in ("input", "independent") or kind == "real":
        attrs["variability"] = "continuous"
    else:
        attrs["variability"] = "discrete"
    if causality == "output":
        attrs["initial"] = "calculated"
    number = _integer if kind in ("integer", "uint64") else _number
    if not text and causality not in ("independent", "output"):
        attrs["start"] = number(v["start"])
    if kind == "real":
        attrs["unit"] = unit
    if v.get("low") is not None:
        attrs["min"] = number(v["low"])
    if v.get("high") is not None:
        attrs["max"] = number(v["high"])
    node = SubElement(parent, _TYPES[kind], attrs)
    if text:
        SubElement(node, "Start", {"value": str(v["start"])})
    if "dimension" in v:
        SubElement(node, "Dimension", {"valueReference": str(v["dimension"])})


def model_description(comp: Component, token: str) -> str:
    """The FMI 3.0 model description of a component's native FMU (see the module docstring)."""
    from tribocosim import __name__ as package

    start, stop, step = comp.default_experiment
    root = Element("fmiModelDescription", {
        "fmiVersion": "3.0", "modelName": comp.model_identifier, "instantiationToken": token,
        "description": comp.summary.replace("FMI 2.0", "FMI 3.0"), "author": comp.author,
        "generationTool": f"{package} (native)", "variableNamingConvention": "structured",
    })
    SubElement(root, "CoSimulation", {
        "modelIdentifier": comp.model_identifier, "needsExecutionTool": "false",
        "canBeInstantiatedOnlyOncePerProcess": "false", "canGetAndSetFMUState": "true",
        "canSerializeFMUState": "true", "providesDirectionalDerivatives": "false",
        "providesAdjointDerivatives": "false", "providesPerElementDependencies": "false",
        "canHandleVariableCommunicationStepSize": "true", "maxOutputDerivativeOrder": "0",
        "providesIntermediateUpdate": "false", "mightReturnEarlyFromDoStep": "false",
        "canReturnEarlyAfterIntermediateUpdate": "false", "hasEventMode": "false",
        "providesEvaluateDiscreteStates": "false",
    })
    common, extra = declarations.variables(comp), declarations.fmi3_variables(comp)
    structural = {v["structural_parameter"] for v in extra if "structural_parameter" in v}
    units = {v["unit"] for v in (*common, *extra) if v["kind"] not in ("string", "uint64")}
    root.append(unit_definitions(units, comp.model_identifier))
    cats = SubElement(root, "LogCategories")
    for status in ("OK", "Warning", "Discard", "Error", "Fatal"):
        SubElement(cats, "Category", {"name": f"logStatus{status}",
                                      "description": f"messages with status fmi3{status}"})
    SubElement(root, "DefaultExperiment", {"startTime": _number(start), "stopTime": _number(stop),
                                           "stepSize": _number(step)})
    mv = SubElement(root, "ModelVariables")
    numbered = [*enumerate(common), *((v["vr"], v) for v in extra)]
    for vr, v in numbered:
        _variable(mv, v, vr, structural)
    structure = SubElement(root, "ModelStructure")
    for vr, v in numbered:
        if v["causality"] == "output":
            SubElement(structure, "Output", {"valueReference": str(vr), "dependencies": OUTPUT_DEPENDENCIES})
    for vr, v in numbered:
        if v["causality"] == "output":
            deps = declarations.initial_dependencies(common, v, 0) if "initial_inputs" in v else ""
            SubElement(structure, "InitialUnknown", {"valueReference": str(vr),
                                                     "dependencies": deps or INITIAL_DEPENDENCIES})
    indent(root, "  ")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + tostring(root, encoding="unicode") + "\n"
