"""Parameters of the machine model (one frozen dataclass, SI units, validated on creation).

The field metadata (unit, description, range) is the single source for validation messages and for
the FMU variable declarations (:mod:`tribocosim.components.machine.component`).
"""

from __future__ import annotations

import math

from tribocosim.components.params import param, parameters, validate_fields


@parameters
class MachineParameters:
    """Parameters of the drawing machine (SI units)."""

    velocity_setpoint: float = param(0.08, "m/s", "drawing velocity to hold", -10.0, 10.0)
    ramp_time: float = param(0.02, "s", "time to ramp the velocity set-point from 0", 0.0, 1e4)
    motor_inertia: float = param(1e-3, "kg m2", "rotor inertia of the servo motor", 1e-9, 10.0)
    screw_lead: float = param(0.01, "m", "ball-screw lead (travel per motor revolution)", 1e-5, 1.0)
    carriage_mass: float = param(200.0, "kg", "mass of grip carriage and grip", 1e-3, 1e5)
    drive_stiffness: float = param(5e7, "N/m", "drivetrain stiffness between motor side and grip", 1.0, 1e13)
    drive_damping: float = param(2e4, "N s/m", "drivetrain damping between motor side and grip", 0.0, 1e10)
    speed_kp: float = param(4e5, "N s/m", "proportional gain of the speed controller", 0.0, 1e12)
    speed_ki: float = param(2e7, "N/m", "integral gain of the speed controller", 0.0, 1e14)
    current_time_constant: float = param(5e-4, "s", "lag of the motor force behind its command", 1e-7, 10.0)
    start_time: float = param(0.0, "s", "time after the start at which the velocity ramp begins (0 before: the "
                              "strip is held while the press closes)", 0.0, 1e4)

    def __post_init__(self) -> None:
        validate_fields(self)

    @property
    def motor_side_mass(self) -> float:
        """m_m = J_m (2 pi / lead)^2 [kg]."""
        return self.motor_inertia * (2.0 * math.pi / self.screw_lead) ** 2
