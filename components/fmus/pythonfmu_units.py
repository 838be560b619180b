"""Units for a component written in Python as a pythonfmu FMU: Real variables that declare their unit and range.

pythonfmu (0.7) writes no ``unit``, ``min`` or ``max`` and 16 digits of a start value. :class:`RealWithUnit` writes
them (the start value with ``repr``, which round-trips a float64), and :func:`add_unit_definitions` adds the
``<UnitDefinitions>`` of those units (SI base-unit exponents,
:func:`tribocosim.components.fmus.modeldescription.unit_definitions`), so that a scene's connections to the
project's FMUs are checked for equal units. Used in the slave's ``to_xml``::

    def to_xml(self, model_options=None):
        root = super().to_xml(model_options if model_options is not None else {})
        return add_unit_definitions(root, self.vars.values())

The FMU then imports tribocosim at run time: its host needs tribocosim installed.
"""

from __future__ import annotations

from xml.etree.ElementTree import Element

from pythonfmu import Real

from tribocosim.components.fmus.modeldescription import unit_definitions


class RealWithUnit(Real):
    """A pythonfmu ``Real`` that also writes ``unit``, ``min`` and ``max`` into the XML, and its start value with
    ``repr``."""

    def __init__(self, name, unit, low=None, high=None, **kwargs):
        super().__init__(name, **kwargs)
        self.unit, self.low, self.high = unit, low, high

    def to_xml(self) -> Element:
        node = super().to_xml()
        real = node.find("Real")
        if self.start is not None:
            real.set("start", repr(float(self.start)))
        real.set("unit", self.unit)
        if self.low is not None:
            real.set("min", repr(float(self.low)))
        if self.high is not None:
            real.set("max", repr(float(self.high)))
        return node


def add_unit_definitions(root: Element, variables, owner: str = "FMU") -> Element:
    """Insert ``<UnitDefinitions>`` (after ``<CoSimulation>``) for the units of the :class:`RealWithUnit`
    variables."""
    units = unit_definitions({v.unit for v in variables if isinstance(v, RealWithUnit)}, owner)
    root.insert(list(root).index(root.find("CoSimulation")) + 1, units)
    return root
