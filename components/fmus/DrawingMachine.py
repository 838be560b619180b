"""FMI 2.0 co-simulation adapter of the drawing machine (pythonfmu): ``pull_force`` in, ``step``, outputs out.

No physics here: every number comes from :class:`tribocosim.components.machine.MachineModel`; the FMI
plumbing (declaration from the parameter dataclass, no-raise error handling, FMU state and its
serialization, exit guard, logging) is :class:`tribocosim.components.fmus.adapter.ModelAdapter`'s.

Variables
    One parameter per field of :class:`~tribocosim.components.machine.MachineParameters`; input
    ``pull_force`` [N], the load of the strip on the grip, held over a step (connect the
    strip-draw FMU's ``pull_force``); outputs ``grip_velocity`` [m/s] and ``grip_position`` [m]
    (connect ``grip_velocity`` to the strip-draw FMU), ``velocity_reference`` [m/s], the
    set-point v_set(t) at the current time (the model's ``velocity_setpoint`` output; the FMU
    variable ``velocity_setpoint`` is the parameter, the velocity to hold after the ramp), and
    ``motor_force`` [N].

Errors
    A NaN/inf ``pull_force`` or a step size <= 0 discards the step (state unchanged); a bad
    parameter (e.g. a negative ``drive_stiffness``) makes every ``fmi2DoStep`` return
    fmi2Discard with a message naming it.
"""

from __future__ import annotations

import dataclasses

from pythonfmu.default_experiment import DefaultExperiment

from tribocosim.components.fmus.adapter import ModelAdapter, Var


class DrawingMachine(ModelAdapter):
    """The drawing-machine FMU: servo motor with PI speed control, ball screw, drivetrain, carriage."""

    author = "tribocosim"
    description = (
        "Drawing machine pulling the strip: servo motor with PI speed control and current-loop lag, ball "
        "screw, drivetrain spring and damper, grip carriage; stepped exactly (FMI 2.0 co-simulation)"
    )
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=1.75, step_size=1e-3)
    INPUTS = {
        "pull_force": Var("N", "load of the strip on the grip (the strip's pull force), held over a step"),
    }
    OUTPUTS = {
        "grip_velocity": Var("m/s", "velocity of the grip carriage v_g"),
        "grip_position": Var("m", "position of the grip carriage x_g from its start"),
        "velocity_reference": Var(
            "m/s", "velocity set-point v_set(t) now: the ramp to velocity_setpoint", key="velocity_setpoint"
        ),
        "motor_force": Var("N", "force of the servo motor at the ball-screw nut F_m"),
    }

    def parameter_fields(self):
        from tribocosim.components.machine import MachineParameters

        return dataclasses.fields(MachineParameters)

    def make_model(self, parameters: dict):
        from tribocosim.components.machine import MachineModel, MachineParameters

        return MachineModel(MachineParameters(**parameters))
