"""First-order lag y' = (k u - y) / tau, stepped exactly with u held: y <- k u + (y - k u) exp(-dt / tau)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from tribocosim.errors import ParameterError, check_finite
from tribocosim.components.params import param, validate_fields


@dataclass(frozen=True)
class LagParameters:
    """Gain and time constant of the lag."""

    gain: float = param(2.0, "1", "static gain k", -1e6, 1e6)
    time_constant: float = param(0.01, "s", "time constant tau", 1e-9, 1e6)
    nan_from: float = param(0.0, "s", "from this time on y is NaN (to test how a master handles a non-finite "
                            "output); 0: never", 0.0, 1e6)

    def __post_init__(self) -> None:
        validate_fields(self)


class LagModel:
    """The lag with explicit state."""

    def __init__(self, params: LagParameters):
        self.params = params
        self.y = 0.0
        self.time = 0.0

    def step(self, dt: float, inputs: dict) -> dict:
        dt = check_finite("dt", dt)
        if dt <= 0:
            raise ParameterError(f"dt = {dt!r} s must be > 0")
        target = self.params.gain * check_finite("u", inputs["u"])
        self.y = target + (self.y - target) * math.exp(-dt / self.params.time_constant)
        self.time += dt
        return self.outputs()

    def outputs(self) -> dict:
        broken = 0 < self.params.nan_from <= self.time + 1e-12
        return {"y": math.nan if broken else self.y}

    def get_state(self) -> dict:
        return {"y": self.y, "time": self.time}

    def set_state(self, state: dict) -> None:
        self.y = float(state["y"])
        self.time = float(state["time"])
