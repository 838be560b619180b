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
