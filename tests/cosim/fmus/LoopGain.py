"""Test FMU: a static gain with direct feedthrough, for algebraic loops.

    y(t) = gain * u(t) + offset + amplitude * sin(omega * t)

t is the FMU's current communication point. Two instances connected in a ring form a linear
algebraic loop with loop gain gain_1 * gain_2. The FMU state is (time, u).
"""

import math

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real
from pythonfmu.enums import Fmi2Initial


class LoopGain(Fmi2Slave):
    """y = gain u + offset + amplitude sin(omega t)."""

    description = "static gain with feedthrough (test FMU)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.gain = 0.5
        self.offset = 1.0
        self.amplitude = 0.0
        self.omega = 1.0
        self.u = 0.0
        self.time = 0.0
        fixed = dict(causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed)
        for name in ("gain", "offset", "amplitude", "omega"):
            self.register_variable(Real(name, **fixed))
        self.register_variable(Real("u", causality=Fmi2Causality.input, start=0.0))
        self.register_variable(Real("y", causality=Fmi2Causality.output, variability=Fmi2Variability.continuous,
                                    initial=Fmi2Initial.exact, start=0.0, getter=self._y))

    def _y(self):
        return self.gain * self.u + self.offset + self.amplitude * math.sin(self.omega * self.time)

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self.time = start_time

    def do_step(self, current_time, step_size):
        self.time = current_time + step_size
        return True

    def _get_fmu_state(self):
        return {"time": self.time, "u": self.u}

    def _set_fmu_state(self, state):
        self.time, self.u = state["time"], state["u"]
