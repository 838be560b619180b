"""The drawing-machine component: its FMU variables and how the model is made
(:mod:`tribocosim.components.description`).

Variables
    One parameter per field of :class:`~tribocosim.components.machine.parameters.MachineParameters`;
    input ``pull_force`` [N], the load of the strip on the grip, held over a step (connect the
    strip-draw FMU's ``pull_force``); outputs ``grip_velocity`` [m/s] and ``grip_position`` [m]
    (connect ``grip_velocity`` to the strip-draw FMU), ``velocity_reference`` [m/s], the set-point
    v_set(t) at the current time (the model's ``velocity_setpoint`` output; the FMU variable
    ``velocity_setpoint`` is the parameter, the velocity to hold after the ramp), and ``motor_force`` [N].

Errors
    A NaN/inf ``pull_force`` or a step size <= 0 discards the step (state unchanged); a bad
    parameter (e.g. a negative ``drive_stiffness``) is an initialization error naming it.
"""

from __future__ import annotations

from pathlib import Path

from tribocosim.components.description import Built, Component, Native, Port, SetPoint
from tribocosim.components.machine.parameters import MachineParameters


def build(params: MachineParameters, files, resources: Path) -> Built:
    """The drawing-machine model."""
    from tribocosim.components.machine.model import MachineModel

    return Built(MachineModel(params))


def setpoints(params: MachineParameters) -> dict[str, list[SetPoint]]:
    """The velocity ``grip_velocity`` will follow, with its sign (negative: the grip moves back)."""
    v = params.velocity_setpoint
    return {"grip_velocity": [SetPoint(v, f"velocity_setpoint = {v:g} m/s", "velocity_setpoint")]}


COMPONENT = Component(
    name="drawingmachine",
    model_identifier="DrawingMachine",
    summary=("Drawing machine pulling the strip: servo motor with PI speed control and current-loop lag, ball "
             "screw, drivetrain spring and damper, grip carriage; stepped exactly (FMI 2.0 co-simulation)"),
    parameters=MachineParameters,
    inputs=(Port("pull_force", "N", "load of the strip on the grip (the strip's pull force), held over a step"),),
    outputs=(
        Port("grip_velocity", "m/s", "velocity of the grip carriage v_g"),
        Port("grip_position", "m", "position of the grip carriage x_g from its start"),
        Port("velocity_reference", "m/s", "velocity set-point v_set(t) now: 0 until start_time, then the ramp to "
             "velocity_setpoint", key="velocity_setpoint"),
        Port("motor_force", "N", "force of the servo motor at the ball-screw nut F_m"),
    ),
    build=build,
    setpoints=setpoints,
    native=Native(prefix="tc_machine", sources=("core/tc_machine.c", "core/tc_linear.c", "fmi/tc_machine_fmu.c"),
                  params_header="tc_machine_params.h"),
)
