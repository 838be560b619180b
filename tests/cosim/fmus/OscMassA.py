"""Test FMU: mass 1 of the two-mass oscillator, driven by the coupling force.

    m1 x1'' = -k1 x1 - c1 x1' + F(t)

Input ``force`` F with companion inputs ``der(force)`` and ``der(force,2)``: over a step the
force is the polynomial F + F' tau + F'' tau^2 / 2 (the master's extrapolation), and the step is
integrated exactly: the augmented linear system z = [x1, v1, F, F', F''] has z' = M z, so
z(h) = expm(M h) z(0) (the native core's expm, cached per h).
Outputs x1, v1 (no direct feedthrough). The FMU state covers x1, v1, the inputs and time.
"""

import numpy as np
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real
from pythonfmu.enums import Fmi2Initial

from tribocosim.components.fmus.pythonfmu_units import RealWithUnit, add_unit_definitions
from tribocosim.components.linear_model import expm


class OscMassA(Fmi2Slave):
    """Mass 1 with spring k1 and damper c1 to ground."""

    description = "two-mass oscillator, mass 1 (test FMU)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.m = 1.0
        self.k = 10.0
        self.c = 0.2
        self.x0 = 0.0
        self.v0 = 0.0
        self.x = 0.0
        self.v = 0.0
        self.force = 0.0
        self.dforce = 0.0
        self.ddforce = 0.0
        self.time = 0.0
        self._cache = {}
        fixed = dict(causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed)
        self.register_variable(RealWithUnit("m", unit="kg", **fixed))
        self.register_variable(RealWithUnit("k", unit="N/m", **fixed))
        self.register_variable(RealWithUnit("c", unit="N s/m", **fixed))
        self.register_variable(RealWithUnit("x0", unit="m", **fixed))
        self.register_variable(RealWithUnit("v0", unit="m/s", **fixed))
        self.register_variable(RealWithUnit("force", unit="N", causality=Fmi2Causality.input, start=0.0))
        self.register_variable(Real("der(force)", causality=Fmi2Causality.input, start=0.0,
                                    getter=lambda: self.dforce, setter=lambda v: setattr(self, "dforce", v)))
        self.register_variable(Real("der(force,2)", causality=Fmi2Causality.input, start=0.0,
                                    getter=lambda: self.ddforce, setter=lambda v: setattr(self, "ddforce", v)))
        out = dict(causality=Fmi2Causality.output, variability=Fmi2Variability.continuous, initial=Fmi2Initial.exact)
        self.register_variable(RealWithUnit("x1", unit="m", start=0.0, getter=lambda: self.x, **out))
        self.register_variable(RealWithUnit("v1", unit="m/s", start=0.0, getter=lambda: self.v, **out))

    def to_xml(self, model_options=None):
        root = super().to_xml(model_options if model_options is not None else {})
        return add_unit_definitions(root, self.vars.values())

    def exit_initialization_mode(self):
        self.x, self.v = self.x0, self.v0

    def _propagator(self, h):
        e = self._cache.get(h)
        if e is None:
            m, k, c = self.m, self.k, self.c
            a = np.zeros((5, 5))
            a[0, 1] = 1.0
            a[1, 0], a[1, 1], a[1, 2] = -k / m, -c / m, 1.0 / m
            a[2, 3] = 1.0
            a[3, 4] = 1.0
            e = expm(a * h)
            if len(self._cache) > 64:
                self._cache.clear()
            self._cache[h] = e
        return e

    def do_step(self, current_time, step_size):
        z = self._propagator(step_size) @ np.array([self.x, self.v, self.force, self.dforce, self.ddforce])
        self.x, self.v = float(z[0]), float(z[1])
        self.time = current_time + step_size
        return True

    def _get_fmu_state(self):
        return {"x": self.x, "v": self.v, "force": self.force, "dforce": self.dforce,
                "ddforce": self.ddforce, "time": self.time}

    def _set_fmu_state(self, state):
        self.x, self.v = state["x"], state["v"]
        self.force, self.dforce, self.ddforce = state["force"], state["dforce"], state["ddforce"]
        self.time = state["time"]
