"""Test FMU: a first-order lag whose output can turn non-finite at a set time.

    y' = (k u - y) / tau,  stepped exactly with u held: y <- k u + (y - k u) exp(-h / tau)

From ``nan_from`` on (0: never) the output y is NaN, so that a master's handling of a non-finite output can be
tested; the input u is the one connection. The FMU state covers y and time.
"""

import math

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real
from pythonfmu.enums import Fmi2Initial


class Lag(Fmi2Slave):
    """A first-order lag with gain k and time constant tau."""

    description = "first-order lag, its output NaN from nan_from on (test FMU)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.gain = 2.0
        self.time_constant = 0.01
        self.nan_from = 0.0
        self.u = 0.0
        self.y = 0.0
        self.time = 0.0
        fixed = dict(causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed)
        for name in ("gain", "time_constant", "nan_from"):
            self.register_variable(Real(name, **fixed))
        self.register_variable(Real("u", causality=Fmi2Causality.input, start=0.0))
        self.register_variable(Real("y", causality=Fmi2Causality.output, variability=Fmi2Variability.continuous,
                                    initial=Fmi2Initial.exact, start=0.0, getter=self._output))

    def _output(self):
        broken = 0 < self.nan_from <= self.time + 1e-12
        return math.nan if broken else self.y

    def do_step(self, current_time, step_size):
        target = self.gain * self.u
        self.y = target + (self.y - target) * math.exp(-step_size / self.time_constant)
        self.time = current_time + step_size
        return True

    def _get_fmu_state(self):
        return {"y": self.y, "u": self.u, "time": self.time}

    def _set_fmu_state(self, state):
        self.y, self.u, self.time = state["y"], state["u"], state["time"]
