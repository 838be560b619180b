"""FMI 2.0 co-simulation adapter of the press (pythonfmu): parameters in, ``step``, outputs out.

No physics here: every number comes from :class:`tribocosim.components.press.PressModel`; the FMI
plumbing (declaration from the parameter dataclass, no-raise error handling, FMU state and its
serialization, exit guard, logging) is :class:`tribocosim.components.fmus.adapter.ModelAdapter`'s.

Variables
    One parameter per field of :class:`~tribocosim.components.press.PressParameters` (``setpoint_table``
    is a String, ``"t0 F0; t1 F1; ..."`` in s and N, empty for the ramp); no inputs; outputs
    ``normal_force`` [N], the force of the press on one pad (connect it to the strip-draw
    FMU's ``normal_force``), and ``force_reference`` [N], the set-point F_set(t) at the current
    time (the model's ``force_setpoint`` output; the FMU variable ``force_setpoint`` is the
    parameter, the force to hold after the ramp).

Errors
    A bad parameter (out of range, malformed ``setpoint_table``) makes every ``fmi2DoStep``
    return fmi2Discard with a message naming it; a step size <= 0 is discarded.
"""

from __future__ import annotations

import dataclasses

from pythonfmu.default_experiment import DefaultExperiment

from tribocosim.components.fmus.adapter import ModelAdapter, Var


class Press(ModelAdapter):
    """The press FMU: force set-point, PI force control, actuator lag, frame stiffness."""

    author = "tribocosim"
    description = (
        "Servo-hydraulic press closing the strip-draw pads: force set-point ramp or table, PI force "
        "controller, first-order actuator lag, frame stiffness; stepped exactly (FMI 2.0 co-simulation)"
    )
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=1.75, step_size=1e-3)
    OUTPUTS = {
        "normal_force": Var("N", "force of the press on one pad, F_N = k_f x + c_f v (frame spring and damper)"),
        "force_reference": Var(
            "N", "force set-point F_set(t) now: the ramp to force_setpoint, or setpoint_table", key="force_setpoint"
        ),
    }

    def parameter_fields(self):
        from tribocosim.components.press import PressParameters

        return dataclasses.fields(PressParameters)

    def make_model(self, parameters: dict):
        from tribocosim.components.press import PressModel, PressParameters

        return PressModel(PressParameters(**parameters))
