"""What the model descriptions of the FMI 2.0 and 3.0 FMUs share: units, descriptions, unit definitions.

Both declare the variables of the component's description with the same descriptions and units; the builder
writes each whole model description from :func:`tribocosim.components.native.toolchain.declarations.variables`.
"""

from __future__ import annotations

from xml.etree.ElementTree import Element, SubElement

from tribocosim.errors import TribocosimError

#: SI base-unit exponents of every unit the variables may use (FMI 2.0 UnitDefinitions)
BASE_UNITS = {
    "1": {},
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "s": {"s": 1},
    "1/s": {"s": -1},
    "kg": {"kg": 1},
    "kg m2": {"kg": 1, "m": 2},
    "kg/m3": {"kg": 1, "m": -3},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N/m": {"kg": 1, "s": -2},
    "N s/m": {"kg": 1, "s": -1},
    "Pa": {"kg": 1, "m": -1, "s": -2},
}


#: How a native FMU's outputs depend on its inputs, for the model descriptions' ModelStructure. The native FMI
#: layer (components/native/fmi/tc_fmu_instance.c) computes the outputs in doStep and at the end of initialization
#: only; fmi2SetReal/fmi3SetFloat64 of an input changes no output until the next doStep. So no output has direct
#: feedthrough (FMI 2.0 section 2.2.8 Outputs, FMI 3.0 section 2.4.8 Output: dependencies=""); at the end of
#: initialization an output depends on the inputs its Port names in ``initial_inputs`` (the strip's
#: contact_pressure on normal_force) and otherwise on the parameters alone (InitialUnknown dependencies=""):
#: outputs are initial="calculated", the model's values after initialization (FMI 2.0 section 2.2.7, FMI 3.0
#: section 2.4.7).
OUTPUT_DEPENDENCIES = ""
INITIAL_DEPENDENCIES = ""


def describe(description: str, unit: str) -> str:
    """The variable description with its unit, e.g. ``"pad length [m]"``."""
    return f"{description} [{unit or '1'}]"


def unit_definitions(units, owner: str = "FMU") -> Element:
    """``<UnitDefinitions>`` for ``units`` (sorted), with their SI base-unit exponents from :data:`BASE_UNITS`."""
    used = sorted(set(units))
    unknown = [u for u in used if u not in BASE_UNITS]
    if unknown:  # a packaging error, found at build time
        raise TribocosimError(f"{owner}: units {unknown} are missing from modeldescription.BASE_UNITS")
    node = Element("UnitDefinitions")
    for unit in used:
        u = SubElement(node, "Unit", {"name": unit})
        if BASE_UNITS[unit]:
            SubElement(u, "BaseUnit", {k: str(e) for k, e in BASE_UNITS[unit].items()})
    return node
