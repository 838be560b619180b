"""Drawing machine: the servo drive that pulls the strip (issue 8), a pure physics model.

A servo motor drives a ball screw; the motor's rotor inertia J_m appears at the screw nut as the
mass m_m = J_m (2 pi / lead)^2 (the motor side). The drivetrain (screw, coupling, frame) is a
spring ``drive_stiffness`` k_d with damper ``drive_damping`` c_d between the motor side and the
grip carriage of mass m_g, which the strip loads with ``pull_force`` F_p (the input).

    m_m x_m'' = F_m - k_d (x_m - x_g) - c_d (v_m - v_g)
    m_g x_g'' = k_d (x_m - x_g) + c_d (v_m - v_g) - F_p
    tau_i F_m' = F_c - F_m                                  (current loop: first-order lag)
    F_c = K_p (v_set - v_m) + K_i I,   I' = v_set - v_m     (PI speed control on the motor encoder)

The velocity set-point ramps from 0 to ``velocity_setpoint`` over ``ramp_time`` and then holds.
With integral action the steady state is v_g = v_m = v_set, k_d (x_m - x_g) = F_p. Outputs:
``grip_velocity`` v_g and ``grip_position`` x_g. Linear, advanced exactly per step with F_p held
and the set-point affine (split at the ramp's end; :mod:`tribocosim.components.linear`).
"""

from __future__ import annotations

import numpy as np

from tribocosim.components.errors import ParameterError, check_finite
from tribocosim.components.linear import AffineInputPropagator
from tribocosim.components.machine.parameters import MachineParameters


class MachineModel:
    """The drive with explicit state: ``step(dt, {"pull_force"}) -> {"grip_velocity", "grip_position", ...}``."""

    OUTPUT_NAMES = ("grip_velocity", "grip_position", "velocity_setpoint", "motor_force")

    def __init__(self, params: MachineParameters):
        self.params = p = params
        mm, mg, k, c = p.motor_side_mass, p.carriage_mass, p.drive_stiffness, p.drive_damping
        tau, kp, ki = p.current_time_constant, p.speed_kp, p.speed_ki
        # z = [x_m, v_m, x_g, v_g, F_m, I]; inputs w = [v_set, F_p]
        A = np.array([
            [0, 1, 0, 0, 0, 0],
            [-k / mm, -c / mm, k / mm, c / mm, 1 / mm, 0],
            [0, 0, 0, 1, 0, 0],
            [k / mg, c / mg, -k / mg, -c / mg, 0, 0],
            [0, -kp / tau, 0, 0, -1 / tau, ki / tau],
            [0, -1, 0, 0, 0, 0],
        ], dtype=float)
        B = np.array([
            [0, 0],
            [0, 0],
            [0, 0],
            [0, -1 / mg],
            [kp / tau, 0],
            [1, 0],
        ], dtype=float)
        self._prop = AffineInputPropagator(A, B)
        self.state = np.zeros(6)
        self.time = 0.0
        self.pull_force = 0.0

    def setpoint(self, t: float) -> float:
        """Velocity set-point at time t [m/s]."""
        p = self.params
        if p.ramp_time == 0:
            return p.velocity_setpoint
        return p.velocity_setpoint * min(1.0, t / p.ramp_time)

    def step(self, dt: float, inputs: dict) -> dict:
        """Advance by dt [s] with ``pull_force`` [N] held; return the outputs."""
        dt = check_finite("dt", dt)
        if dt <= 0:
            raise ParameterError(f"dt = {dt!r} s must be > 0")
        fp = check_finite("pull_force", inputs["pull_force"])
        t0, t1 = self.time, self.time + dt
        cuts = [t0] + ([self.params.ramp_time] if t0 < self.params.ramp_time < t1 else []) + [t1]
        z = self.state
        for a, b in zip(cuts[:-1], cuts[1:]):
            va, vb = self.setpoint(a), self.setpoint(b)
            z = self._prop.step(z, b - a, [va, fp], [(vb - va) / (b - a), 0.0])
        if not np.all(np.isfinite(z)):
            raise ParameterError(f"pull_force = {fp!r} N drove the drive state to non-finite values at t = {t1:.9g} s")
        self.state, self.time, self.pull_force = z, t1, fp
        return self.outputs()

    def outputs(self) -> dict:
        """grip_velocity [m/s], grip_position [m], the set-point [m/s] and the motor force [N]."""
        z = self.state
        return {
            "grip_velocity": float(z[3]),
            "grip_position": float(z[2]),
            "velocity_setpoint": self.setpoint(self.time),
            "motor_force": float(z[4]),
        }

    def get_state(self) -> dict:
        """Deep copy of the state."""
        return {"state": self.state.copy(), "time": self.time, "pull_force": self.pull_force}

    def set_state(self, state: dict) -> None:
        """Restore a state from :meth:`get_state`."""
        self.state = np.array(state["state"], dtype=float)
        self.time = float(state["time"])
        self.pull_force = float(state["pull_force"])
