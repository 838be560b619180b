"""Parameters of the press model (one frozen dataclass, SI units, validated on creation).

The field metadata (unit, description, range) is the single source for validation messages and for
the FMU variable declarations (:mod:`tribocosim.components.press.component`).
"""

from __future__ import annotations

import math
import re

from tribocosim.errors import ParameterError
from tribocosim.components.params import param, parameters, validate_fields


#: the grammar of one set-point table entry (the native press reads the same, tc_press.c): a time and a force,
#: decimal numbers separated by spaces or tabs
_NUMBER = r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
_ENTRY = re.compile(rf"[ \t]*{_NUMBER}[ \t]+{_NUMBER}[ \t]*")


@parameters
class PressParameters:
    """Parameters of the press (SI units)."""

    force_setpoint: float = param(12250.0, "N", "normal force to hold on one pad (10 MPa on 35 x 35 mm)", 0.0, 1e8)
    ramp_time: float = param(0.05, "s", "time to ramp the set-point from 0 to force_setpoint", 0.0, 1e4)
    setpoint_table: str = param("", "", "optional set-point table 't0 F0; t1 F1; ...' [s N], overrides the ramp: "
                                "entries separated by ';', each a time and a force, decimal numbers separated by "
                                "spaces", text=True)
    kp: float = param(0.5, "1", "proportional gain of the force controller", 0.0, 1e3)
    ki: float = param(200.0, "1/s", "integral gain of the force controller", 0.0, 1e6)
    actuator_time_constant: float = param(5e-3, "s", "first-order lag of the hydraulic actuator", 1e-6, 10.0)
    frame_stiffness: float = param(5e8, "N/m", "stiffness of frame, tools and pad stack", 1.0, 1e13)
    frame_damping: float = param(2e5, "N s/m", "damping of the frame/pad stack", 0.0, 1e10)
    piston_mass: float = param(20.0, "kg", "moving mass of piston and tool", 1e-3, 1e5)

    def __post_init__(self) -> None:
        validate_fields(self)
        try:
            self.setpoints()  # parse now: a malformed table is a parameter error (of that field)
        except ParameterError as exc:
            raise ParameterError(str(exc), fields=[("setpoint_table", str(exc))]) from None

    def setpoints(self) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """Breakpoints (times [s], forces [N]) of the piecewise-linear set-point."""
        if not self.setpoint_table:
            if self.ramp_time == 0:
                return (0.0,), (float(self.force_setpoint),)
            return (0.0, float(self.ramp_time)), (0.0, float(self.force_setpoint))
        entries = [item for item in self.setpoint_table.split(";") if item.strip(" \t")]
        if not entries:
            raise ParameterError(f"setpoint_table = '{self.setpoint_table}' is malformed: it has no entry")
        if not all(_ENTRY.fullmatch(item) for item in entries):
            raise ParameterError(f"setpoint_table = '{self.setpoint_table}' is malformed: each entry is a time and a "
                                 "force, two decimal numbers separated by spaces (entries separated by ';')")
        pairs = [[float(x) for x in item.split()] for item in entries]
        t, f = tuple(p[0] for p in pairs), tuple(p[1] for p in pairs)
        if (not all(map(math.isfinite, t + f)) or any(b <= a for a, b in zip(t, t[1:]))
                or any(x < 0 for x in f)):
            raise ParameterError(
                f"setpoint_table = '{self.setpoint_table}': times must increase and forces be finite and >= 0"
            )
        return t, f
