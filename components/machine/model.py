"""Drawing machine: the servo drive that pulls the strip, a binding over the native core (``tc_machine.c``).

A servo motor drives a ball screw; the motor's rotor inertia J_m appears at the screw nut as the
mass m_m = J_m (2 pi / lead)^2 (the motor side). The drivetrain (screw, coupling, frame) is a
spring ``drive_stiffness`` k_d with damper ``drive_damping`` c_d between the motor side and the
grip carriage of mass m_g, which the strip loads with ``pull_force`` F_p (the input).

    m_m x_m'' = F_m - k_d (x_m - x_g) - c_d (v_m - v_g)
    m_g x_g'' = k_d (x_m - x_g) + c_d (v_m - v_g) - F_p
    tau_i F_m' = F_c - F_m                                  (current loop: first-order lag)
    F_c = K_p (v_set - v_m) + K_i I,   I' = v_set - v_m     (PI speed control on the motor encoder)

The velocity set-point is 0 until ``start_time``, ramps to ``velocity_setpoint`` over ``ramp_time``
and then holds.
With integral action the steady state is v_g = v_m = v_set, k_d (x_m - x_g) = F_p. Outputs:
``grip_velocity`` v_g and ``grip_position`` x_g. Linear, advanced exactly per step with F_p held
and the set-point affine (split at the ramp's start and end; ``tc_linear.h``).
"""

from __future__ import annotations

from tribocosim.components.machine.parameters import MachineParameters
from tribocosim.components.linear_model import NativeLinearModel


class MachineModel(NativeLinearModel):
    """The drive with explicit state: ``step(dt, {"pull_force"}) -> {"grip_velocity", "grip_position", ...}``."""

    OUTPUT_NAMES = ("grip_velocity", "grip_position", "velocity_setpoint", "motor_force")
    INPUT_NAMES = ("pull_force",)
    N_STATES = 6  # z = [x_m, v_m, x_g, v_g, F_m, I]
    PREFIX = "tc_machine"

    def __init__(self, params: MachineParameters):
        super().__init__(params)

