"""The press component: its FMU variables and how the model is made (:mod:`tribocosim.components.description`).

Variables
    One parameter per field of :class:`~tribocosim.components.press.parameters.PressParameters`
    (``setpoint_table`` is a String, ``"t0 F0; t1 F1; ..."`` in s and N, empty for the ramp); no
    inputs; outputs ``normal_force`` [N], the force of the press on one pad (connect it to the
    strip-draw FMU's ``normal_force``), and ``force_reference`` [N], the set-point F_set(t) at the
    current time (the model's ``force_setpoint`` output; the FMU variable ``force_setpoint`` is the
    parameter, the force to hold after the ramp).

Errors
    A bad parameter (out of range, malformed ``setpoint_table``) is an initialization error naming
    it; a step size <= 0 is discarded.
"""

from __future__ import annotations

from pathlib import Path

from tribocosim.components.description import Built, Component, Native, Port, SetPoint
from tribocosim.components.press.parameters import PressParameters


def build(params: PressParameters, files, resources: Path) -> Built:
    """The press model."""
    from tribocosim.components.press.model import PressModel

    return Built(PressModel(params))


def setpoints(params: PressParameters) -> dict[str, list[SetPoint]]:
    """The forces ``normal_force`` will follow: the set-point, or the extremes of the set-point table."""
    _, forces = params.setpoints()
    positive = sorted({float(f) for f in forces if f > 0})
    which = "force_setpoint" if not params.setpoint_table else "setpoint_table"
    if not positive:
        return {}
    if len(positive) == 1:
        return {"normal_force": [SetPoint(positive[0], f"the set-point, {positive[0]:g} N", which)]}
    return {"normal_force": [SetPoint(positive[-1], f"the largest set-point, {positive[-1]:g} N", which),
                             SetPoint(positive[0], f"the smallest non-zero set-point, {positive[0]:g} N", which)]}


COMPONENT = Component(
    name="press",
    model_identifier="Press",
    summary=("Servo-hydraulic press closing the strip-draw pads: force set-point ramp or table, PI force "
             "controller, first-order actuator lag, frame stiffness; stepped exactly (FMI 2.0 co-simulation)"),
    parameters=PressParameters,
    inputs=(),
    outputs=(
        Port("normal_force", "N", "force of the press on one pad, F_N = k_f x + c_f v (frame spring and damper)"),
        Port("force_reference", "N", "force set-point F_set(t) now: the ramp to force_setpoint, or setpoint_table",
             key="force_setpoint"),
    ),
    build=build,
    setpoints=setpoints,
    native=Native(prefix="tc_press", sources=("core/tc_press.c", "core/tc_linear.c", "fmi/tc_press_fmu.c"),
                  params_header="tc_press_params.h"),
)
