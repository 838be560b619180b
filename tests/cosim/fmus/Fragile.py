"""Test FMU: a first-order lag that refuses long steps inside a time window.

    x' = (u - x) / tau,  y = x      (exact update for a constant input over the step)

Inside [t_on, t_off) a step longer than ``max_step`` is refused: with ``mode = 0`` the FMU
returns fmi2Discard (do_step returns False) and leaves its state unchanged; with ``mode = 1`` it
takes the step but its output becomes NaN until a step of acceptable length is taken
(non-finite output). Counts refused steps in the output ``refusals``.
"""

import math

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real
from pythonfmu.enums import Fmi2Initial


class Fragile(Fmi2Slave):
    """First-order lag with a window where only short steps are accepted."""

    description = "first-order lag refusing long steps in a window (test FMU)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.tau = 0.5
        self.max_step = 0.01
        self.t_on = 0.3
        self.t_off = 0.6
        self.mode = 0
        self.u = 1.0
        self.x = 0.0
        self.bad = False
        self.refusals = 0
        fixed = dict(causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed)
        for name in ("tau", "max_step", "t_on", "t_off"):
            self.register_variable(Real(name, **fixed))
        self.register_variable(Integer("mode", **fixed))
        self.register_variable(Real("u", causality=Fmi2Causality.input, start=1.0))
        out = dict(causality=Fmi2Causality.output, initial=Fmi2Initial.exact)
        self.register_variable(Real("y", start=0.0, variability=Fmi2Variability.continuous,
                                    getter=lambda: float("nan") if self.bad else self.x, **out))
        self.register_variable(Integer("refusals", start=0, variability=Fmi2Variability.discrete, **out))

    def do_step(self, current_time, step_size):
        in_window = self.t_on <= current_time + 0.5 * step_size < self.t_off
        too_long = in_window and step_size > self.max_step * (1.0 + 1e-12)
        if too_long:
            self.refusals += 1
            if self.mode == 0:
                return False
        self.x = self.u + (self.x - self.u) * math.exp(-step_size / self.tau)
        self.bad = too_long
        return True

    def _get_fmu_state(self):
        return {"x": self.x, "u": self.u, "bad": self.bad, "refusals": self.refusals}

    def _set_fmu_state(self, state):
        self.x, self.u, self.bad = state["x"], state["u"], state["bad"]
        self.refusals = state["refusals"]
