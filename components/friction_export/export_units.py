"""The unit systems of an exported friction law: the numbers a forming deck is written in.

The law is evaluated in SI (Pa, m/s); a file holds its pressures and velocities in the deck's system:

==========  ===========================  ========  ========  ======
name        base units                   pressure  velocity  length
==========  ===========================  ========  ========  ======
``mm-t-s``  mm, tonne, s (force in N)    MPa       mm/s      mm
``SI``      m, kg, s (force in N)        Pa        m/s       m
==========  ===========================  ========  ========  ======

``mm-t-s`` is the default: most sheet-forming decks (LS-DYNA, Abaqus) are written in it. The coefficient of
friction mu and the debris area fraction beta have no unit.
"""

from __future__ import annotations

from dataclasses import dataclass

from tribocosim.errors import ParameterError


@dataclass(frozen=True)
class UnitSystem:
    """A deck's unit system: a value in the file is the SI value divided by the ``*_scale`` (1 MPa = 1e6 Pa)."""

    name: str
    description: str
    pressure: str
    pressure_scale: float
    velocity: str
    velocity_scale: float
    length: str
    length_scale: float

    def pressure_to_file(self, pascal):
        """Pressures [Pa] in the file's unit."""
        return pascal / self.pressure_scale

    def pressure_from_file(self, value):
        """Pressures in the file's unit as Pa."""
        return value * self.pressure_scale

    def velocity_to_file(self, metre_per_second):
        """Velocities [m/s] in the file's unit."""
        return metre_per_second / self.velocity_scale

    def velocity_from_file(self, value):
        """Velocities in the file's unit as m/s."""
        return value * self.velocity_scale

    def length_from_file(self, value):
        """Lengths in the file's unit as m."""
        return value * self.length_scale

    def header(self) -> str:
        """One line for a file's header."""
        return (f"units {self.name} ({self.description}): contact pressure in {self.pressure}, relative sliding "
                f"velocity in {self.velocity}; mu and beta have no unit")


UNIT_SYSTEMS = {
    "mm-t-s": UnitSystem("mm-t-s", "mm, tonne, s; force in N", "MPa", 1e6, "mm/s", 1e-3, "mm", 1e-3),
    "SI": UnitSystem("SI", "m, kg, s; force in N", "Pa", 1.0, "m/s", 1.0, "m", 1.0),
}
DEFAULT_UNITS = "mm-t-s"


def unit_system(name: str) -> UnitSystem:
    """The unit system called ``name`` (ParameterError naming ``--units`` otherwise)."""
    if name not in UNIT_SYSTEMS:
        raise ParameterError(f"--units {name!r} is not a unit system; choose {' or '.join(UNIT_SYSTEMS)}")
    return UNIT_SYSTEMS[name]
