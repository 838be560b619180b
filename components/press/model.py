"""Servo-hydraulic press that closes the strip-draw pads: a binding over the native core (``tc_press.c``).

States: piston/pad displacement x [m] and velocity v [m/s] (the stack compresses the frame),
actuator force F_a [N], integral of the force error I [N s].

    m_p v' = F_a - k_f x - c_f v                          (piston on the frame stiffness)
    F_N    = k_f x + c_f v                                (force on the pad: the output)
    tau_a F_a' = u - F_a                                  (first-order actuator lag)
    u      = F_set(t) + K_p (F_set - F_N) + K_i I,  I' = F_set - F_N   (PI with feed-forward)

The set-point ramps linearly from 0 to ``force_setpoint`` over ``ramp_time`` and then holds, or
follows ``setpoint_table`` ("t0 F0; t1 F1; ..." piecewise linear, held after the last point).
With integral action the steady state is F_N = F_set exactly. The system is linear and the
set-point piecewise linear, so each step is advanced exactly (matrix exponential of the augmented
system, split at the set-point's breakpoints; ``tc_linear.h``).
"""

from __future__ import annotations

from tribocosim.components.linear_model import NativeLinearModel
from tribocosim.components.press.parameters import PressParameters


class PressModel(NativeLinearModel):
    """The press with explicit state: ``step(dt, inputs) -> {"normal_force", "force_setpoint"}``."""

    OUTPUT_NAMES = ("normal_force", "force_setpoint")
    INPUT_NAMES = ()
    N_STATES = 4  # z = [x, v, F_a, I]
    PREFIX = "tc_press"

    def __init__(self, params: PressParameters):
        super().__init__(params)

