"""Test FMU: mass 2 of the two-mass oscillator plus the coupling spring-damper.

    m2 x2'' = -k3 x2 - c3 x2' - F,   F = k2 (x2 - x1) + c2 (x2' - v1)

F is the force the coupling element exerts on mass 1 (output ``force``, direct feedthrough from
the inputs x1, v1). Inputs x1, v1 with companion inputs ``der(x1)``, ``der(x1,2)``,
``der(v1)``, ``der(v1,2)``: over a step each input is the polynomial the master extrapolated;
the augmented linear system [x2, v2, x1, x1', x1'', v1, v1', v1''] is integrated exactly with a
matrix exponential (cached per step size). The FMU state covers x2, v2, the inputs and time.
"""

import numpy as np
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real
from pythonfmu.enums import Fmi2Initial

from tribocosim.components.fmus.pythonfmu_units import RealWithUnit, add_unit_definitions
from tribocosim.components.linear_model import expm


class OscMassB(Fmi2Slave):
    """Mass 2 with spring k3 / damper c3 to ground and the coupling k2 / c2 to mass 1."""

    description = "two-mass oscillator, mass 2 and coupling (test FMU)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.m = 1.0
        self.k3 = 20.0
        self.c3 = 0.3
        self.k2 = 10.0
        self.c2 = 0.5
        self.x0 = 0.5
        self.v0 = 0.0
        self.x = 0.0
        self.v = 0.0
        self.x1 = 0.0
        self.v1 = 0.0
        self.d = [0.0, 0.0, 0.0, 0.0]  # der(x1), der(x1,2), der(v1), der(v1,2)
        self.time = 0.0
        self._cache = {}
        fixed = dict(causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed)
        for name, unit in (("m", "kg"), ("k3", "N/m"), ("c3", "N s/m"), ("k2", "N/m"), ("c2", "N s/m"),
                           ("x0", "m"), ("v0", "m/s")):
            self.register_variable(RealWithUnit(name, unit=unit, **fixed))
        self.register_variable(RealWithUnit("x1", unit="m", causality=Fmi2Causality.input, start=0.0))
        self.register_variable(RealWithUnit("v1", unit="m/s", causality=Fmi2Causality.input, start=0.0))
        for j, name in enumerate(("der(x1)", "der(x1,2)", "der(v1)", "der(v1,2)")):
            self.register_variable(Real(name, causality=Fmi2Causality.input, start=0.0,
                                        getter=lambda j=j: self.d[j], setter=lambda v, j=j: self.d.__setitem__(j, v)))
        out = dict(causality=Fmi2Causality.output, variability=Fmi2Variability.continuous, initial=Fmi2Initial.exact)
        self.register_variable(RealWithUnit("force", unit="N", start=0.0, getter=self._force, **out))
        self.register_variable(RealWithUnit("x2", unit="m", start=0.0, getter=lambda: self.x, **out))
        self.register_variable(RealWithUnit("v2", unit="m/s", start=0.0, getter=lambda: self.v, **out))

    def _force(self):
        return self.k2 * (self.x - self.x1) + self.c2 * (self.v - self.v1)

    def to_xml(self, model_options=None):
        root = super().to_xml(model_options if model_options is not None else {})
        return add_unit_definitions(root, self.vars.values())

    def exit_initialization_mode(self):
        self.x, self.v = self.x0, self.v0

    def _propagator(self, h):
        e = self._cache.get(h)
        if e is None:
            m = self.m
            a = np.zeros((8, 8))
            a[0, 1] = 1.0
            a[1, 0] = -(self.k3 + self.k2) / m
            a[1, 1] = -(self.c3 + self.c2) / m
            a[1, 2] = self.k2 / m
            a[1, 5] = self.c2 / m
            a[2, 3] = a[3, 4] = 1.0
            a[5, 6] = a[6, 7] = 1.0
            e = expm(a * h)
            if len(self._cache) > 64:
                self._cache.clear()
            self._cache[h] = e
        return e

    def do_step(self, current_time, step_size):
        z0 = np.array([self.x, self.v, self.x1, self.d[0], self.d[1], self.v1, self.d[2], self.d[3]])
        z = self._propagator(step_size) @ z0
        self.x, self.v = float(z[0]), float(z[1])
        self.time = current_time + step_size
        return True

    def _get_fmu_state(self):
        return {"x": self.x, "v": self.v, "x1": self.x1, "v1": self.v1, "d": list(self.d), "time": self.time}

    def _set_fmu_state(self, state):
        self.x, self.v = state["x"], state["v"]
        self.x1, self.v1 = state["x1"], state["v1"]
        self.d = list(state["d"])
        self.time = state["time"]
