"""Press and drawing machine: set-point holding, velocity reached, force balance, state, bad input."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tribocosim.errors import ParameterError
from tribocosim.components.machine import MachineModel, MachineParameters
from tribocosim.components.press import PressModel, PressParameters


def test_press_holds_its_setpoint_in_steady_state():
    press = PressModel(PressParameters(force_setpoint=12250.0, ramp_time=0.05))
    outs = [press.step(1e-3) for _ in range(400)]
    force = np.array([o["normal_force"] for o in outs])
    assert np.all(np.abs(force[200:] - 12250.0) <= 0.01 * 12250.0), "within 1 % after 0.2 s"
    assert_allclose(force[-1], 12250.0, rtol=1e-6, err_msg="integral action: no steady-state error")


def test_press_follows_a_setpoint_table_and_steps_exactly():
    p = PressParameters(setpoint_table="0 0; 0.05 5000; 0.3 5000; 0.35 9000")
    a, b = PressModel(p), PressModel(p)
    for _ in range(600):
        a.step(1e-3)
    for _ in range(300):
        b.step(2e-3)  # the set-point is piecewise linear and the model linear: exact at any step
    assert_allclose(a.outputs()["normal_force"], b.outputs()["normal_force"], rtol=1e-10)
    assert_allclose(a.outputs()["normal_force"], 9000.0, rtol=1e-3)


def test_machine_reaches_its_velocity_setpoint_under_load():
    machine = MachineModel(MachineParameters(velocity_setpoint=0.08, ramp_time=0.02))
    for k in range(600):
        out = machine.step(1e-3, {"pull_force": 3700.0 * min(1.0, k / 50)})
    assert_allclose(out["grip_velocity"], 0.08, rtol=1e-3)
    p = machine.params
    x_m, x_g = machine.state[0], machine.state[2]
    assert_allclose(p.drive_stiffness * (x_m - x_g), 3700.0, rtol=1e-3, err_msg="drivetrain carries the pull")


def test_state_round_trip_and_bad_input():
    machine = MachineModel(MachineParameters())
    machine.step(0.01, {"pull_force": 100.0})
    st = machine.get_state()
    first = machine.step(0.01, {"pull_force": 100.0})
    machine.set_state(st)
    assert machine.step(0.01, {"pull_force": 100.0}) == first
    with pytest.raises(ParameterError, match="pull_force"):
        machine.step(0.01, {"pull_force": float("nan")})
    with pytest.raises(ParameterError, match="drive_stiffness = -1"):
        MachineParameters(drive_stiffness=-1.0)
    with pytest.raises(ParameterError, match="setpoint_table"):
        PressParameters(setpoint_table="0 1; 0.5")


@pytest.mark.parametrize("ramp_time", [0.02, 0.0])
def test_machine_held_until_its_start_time_then_runs_as_one_started_at_zero(ramp_time):
    """The drive is linear and time-invariant: with start_time t_s the set-point is 0 before t_s, so the grip stays
    exactly at rest, and after t_s it follows the trajectory of a drive started at 0, shifted by t_s (a pull that
    starts with the motion). dt and t_s are powers of two, so the times add up exactly."""
    dt, hold = 2.0**-10, 128
    held = MachineModel(MachineParameters(velocity_setpoint=0.08, ramp_time=ramp_time, start_time=hold * dt))
    fresh = MachineModel(MachineParameters(velocity_setpoint=0.08, ramp_time=ramp_time))
    for k in range(hold):
        out = held.step(dt, {"pull_force": 0.0})
        assert out["grip_velocity"] == 0.0 and out["grip_position"] == 0.0
        at_start = k == hold - 1 and ramp_time == 0  # at t_s a stepped set-point has its value after the step
        assert out["velocity_setpoint"] == (0.08 if at_start else 0.0)
    for k in range(300):
        pull = {"pull_force": 3700.0 * min(1.0, k / 50)}
        a, b = held.step(dt, pull), fresh.step(dt, pull)
        for name in ("grip_velocity", "grip_position", "velocity_setpoint", "motor_force"):
            assert_allclose(a[name], b[name], rtol=1e-12, atol=1e-15, err_msg=f"{name} at step {k}")
    assert_allclose(b["grip_velocity"], 0.08, rtol=0.05)


def test_machine_step_set_point_at_its_start_time_splits_the_step():
    """ramp_time = 0: the set-point steps from 0 to velocity_setpoint at start_time; a step across it equals the two
    steps that end and start there (the step is split at the jump, not averaged over it)."""
    p = MachineParameters(velocity_setpoint=0.08, ramp_time=0.0, start_time=0.25)
    one, two = MachineModel(p), MachineModel(p)
    one.step(0.5, {"pull_force": 100.0})
    two.step(0.25, {"pull_force": 100.0})
    assert two.outputs()["velocity_setpoint"] == 0.08, "the set-point at start_time is the value after the step"
    two.step(0.25, {"pull_force": 100.0})
    assert_allclose(one.state, two.state, rtol=1e-11, atol=1e-15)
