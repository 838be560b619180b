"""Servo-hydraulic press that closes the strip-draw pads (issue 8), a pure physics model.

States: piston/pad displacement x [m] and velocity v [m/s] (the stack compresses the frame),
actuator force F_a [N], integral of the force error I [N s].

    m_p v' = F_a - k_f x - c_f v                          (piston on the frame stiffness)
    F_N    = k_f x + c_f v                                (force on the pad: the output)
    tau_a F_a' = u - F_a                                  (first-order actuator lag)
    u      = F_set(t) + K_p (F_set - F_N) + K_i I,  I' = F_set - F_N   (PI with feed-forward)

The set-point ramps linearly from 0 to ``force_setpoint`` over ``ramp_time`` and then holds, or
follows ``setpoint_table`` ("t0 F0; t1 F1; ..." piecewise linear, held after the last point).
With integral action the steady state is F_N = F_set exactly. The system is linear and the
set-point piecewise linear, so each step is advanced exactly (matrix exponential, split at the
set-point's breakpoints; :mod:`tribocosim.components.linear`).
"""

from __future__ import annotations

import numpy as np

from tribocosim.components.errors import ParameterError, check_finite
from tribocosim.components.linear import AffineInputPropagator
from tribocosim.components.press.parameters import PressParameters


class PressModel:
    """The press with explicit state: ``step(dt, inputs) -> {"normal_force", "force_setpoint"}``."""

    OUTPUT_NAMES = ("normal_force", "force_setpoint")

    def __init__(self, params: PressParameters):
        self.params = p = params
        self._t_set, self._f_set = p.setpoints()
        m, k, c, tau = p.piston_mass, p.frame_stiffness, p.frame_damping, p.actuator_time_constant
        # state z = [x, v, F_a, I]; input w = F_set
        A = np.array([
            [0.0, 1.0, 0.0, 0.0],
            [-k / m, -c / m, 1.0 / m, 0.0],
            [-(p.kp * k) / tau, -(p.kp * c) / tau, -1.0 / tau, p.ki / tau],
            [-k, -c, 0.0, 0.0],
        ])
        B = np.array([[0.0], [0.0], [(1.0 + p.kp) / tau], [1.0]])
        self._prop = AffineInputPropagator(A, B)
        self.state = np.zeros(4)
        self.time = 0.0

    def setpoint(self, t: float) -> float:
        """Force set-point at time t [N]."""
        return float(np.interp(t, self._t_set, self._f_set))

    def step(self, dt: float, inputs: dict | None = None) -> dict:
        """Advance by dt [s] (the press has no inputs); return the outputs."""
        dt = check_finite("dt", dt)
        if dt <= 0:
            raise ParameterError(f"dt = {dt!r} s must be > 0")
        t0, t1 = self.time, self.time + dt
        cuts = [t0] + [t for t in self._t_set if t0 < t < t1] + [t1]
        z = self.state
        for a, b in zip(cuts[:-1], cuts[1:]):
            fa, fb = self.setpoint(a), self.setpoint(b)
            z = self._prop.step(z, b - a, fa, (fb - fa) / (b - a))
        if not np.all(np.isfinite(z)):  # pragma: no cover - a linear stable system stays finite
            raise ParameterError("press state became non-finite")
        self.state, self.time = z, t1
        return self.outputs()

    def outputs(self) -> dict:
        """normal_force [N] (on the pad) and the current set-point [N]."""
        p = self.params
        x, v = self.state[0], self.state[1]
        return {"normal_force": float(p.frame_stiffness * x + p.frame_damping * v), "force_setpoint": self.setpoint(self.time)}

    def get_state(self) -> dict:
        """Deep copy of the state."""
        return {"state": self.state.copy(), "time": self.time}

    def set_state(self, state: dict) -> None:
        """Restore a state from :meth:`get_state`."""
        self.state = np.array(state["state"], dtype=float)
        self.time = float(state["time"])

