"""Native press and drawing machine (tc_press.c, tc_machine.c) against PressModel and MachineModel.

Both are advanced with the matrix exponential, whose products NumPy computes with BLAS; the states therefore
agree to rounding, amplified by the state's conditioning (the machine's positions of 0.1 m carry the
spring force in differences of 1e-5 m): measured below 3e-12 relative, held here to 1e-10. The set-points
are interpolated with NumPy's own operations and agree exactly.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tribocosim.components.errors import ParameterError
from tribocosim.components.machine import MachineModel, MachineParameters
from tribocosim.components.press import PressModel, PressParameters

TC_OK, TC_DISCARD, TC_ERROR = 0, 1, 2  # tc_common.h
RTOL = 1e-10


def _irregular_steps(rng, breakpoints, t_end=0.3):
    """Irregular step lengths up to t_end; steps end exactly on every other breakpoint and jump over the rest."""
    steps, t, k = [], 0.0, 0
    pending = sorted(b for b in breakpoints if b > 0)
    while t < t_end:
        dt = float(rng.uniform(1e-4, 7e-3))
        if pending and t + dt >= pending[0]:
            if k % 2 == 0 and t + (pending[0] - t) == pending[0] and pending[0] > t:
                dt = pending[0] - t  # lands on the breakpoint
            pending.pop(0)
            k += 1
        steps.append(dt)
        t += dt
    return steps


def _compare(py, nat, steps, inputs=None):
    a, b = [], []
    for k, dt in enumerate(steps):
        inp = inputs(k) if inputs else None
        ref, out = py.step(dt, inp), nat.step(dt, inp)
        a.append([ref[name] for name in nat.names])
        b.append([out[name] for name in nat.names])
    return np.array(a), np.array(b)


def _assert_agree(a, b, names, exact, label):
    for j, name in enumerate(names):
        if name in exact:
            np.testing.assert_array_equal(b[:, j], a[:, j], err_msg=f"{label}: {name}")
        else:
            nz = a[:, j] != 0
            err = np.max(np.abs(a[nz, j] - b[nz, j]) / np.abs(a[nz, j]), initial=0.0)
            assert err <= RTOL, f"{label}: {name} differs by {err:.3g} (relative)"


PRESS_CASES = {
    "ramp": PressParameters(),
    "no ramp": PressParameters(ramp_time=0.0),
    "table": PressParameters(setpoint_table="0 0; 0.01 5000; 0.013 5000; 0.05 12000; 0.0625 2e4; 0.2 1e3"),
    "one-point table": PressParameters(setpoint_table=" 0.02   8000 ;"),
    "table after t=0": PressParameters(setpoint_table="0.03 1000; 0.04 3000"),
}


@pytest.mark.parametrize("case", PRESS_CASES)
def test_press_matches_python_over_irregular_steps(native_core, case):
    p = PRESS_CASES[case]
    py, nat = PressModel(p), native_core.press(p)
    a, b = _compare(py, nat, _irregular_steps(np.random.default_rng(8), list(py._t_set)))
    _assert_agree(a, b, nat.names, {"force_setpoint"}, f"press, {case}")


MACHINE_CASES = {
    "ramp": MachineParameters(),
    "no ramp": MachineParameters(ramp_time=0.0),
    "reverse, slow ramp": MachineParameters(velocity_setpoint=-0.2, ramp_time=0.15, drive_damping=0.0),
}


@pytest.mark.parametrize("case", MACHINE_CASES)
def test_machine_matches_python_over_irregular_steps(native_core, case):
    p = MACHINE_CASES[case]
    py, nat = MachineModel(p), native_core.machine(p)
    steps = _irregular_steps(np.random.default_rng(9), [p.ramp_time])
    a, b = _compare(py, nat, steps, lambda k: {"pull_force": 3600.0 * min(1.0, k / 40) * (1 + 0.1 * math.sin(k))})
    _assert_agree(a, b, nat.names, {"velocity_setpoint"}, f"machine, {case}")
    assert np.sign(a[-1, 1]) == np.sign(p.velocity_setpoint), "the grip moved the set-point's way"


GOOD_TABLES = [
    "0 0; 1e-2 5_000; .02 6e3; 0.03 +7000.; 4E-2 inf",  # refused later: inf is not a finite force
    "\t0 0;\n 0.01   1000 ;;  ; 0.02 2000\r\n",
    "0\u00a00; 0.01\u20031000",  # Unicode spaces split like ASCII ones
]
BAD_TABLES = [
    ";",
    "   ",
    "0 0; 0.01",
    "0 0 1; 0.01 5",
    "0 0; 0.01 abc; 1 2 3",
    "0 0; 0.01 1_",
    "0 0; 0.01 1__0",
    "0 0; 0.01 0x10",
    "0 0; 0.01 1e",
    "0 0; 0.01 _1",
    "0 0; 0.01 1._5",
    "0 0; 0.01 -5",
    "0 0; 0 5",
    "0.02 0; 0.01 5",
    "0 nan",
    "nan 0",
    "0 0; 0.01 1e999",
    "0 0; 0.01 'quoted'",
    '0 0; 0.01 "x\\y"',
]


@pytest.mark.parametrize("text", GOOD_TABLES + BAD_TABLES)
def test_setpoint_table_is_read_like_python(native_core, text):
    try:
        p = PressParameters(setpoint_table=text)
    except ParameterError as exc:
        with pytest.raises(native_core.NativeError) as nexc:
            native_core.press(PressParameters(), setpoint_table=text)
        assert nexc.value.status == TC_ERROR
        assert nexc.value.message == str(exc)
        return
    py, nat = PressModel(p), native_core.press(p)
    a, b = _compare(py, nat, [2.5e-3] * 20)
    _assert_agree(a, b, nat.names, {"force_setpoint"}, repr(text))


@pytest.mark.parametrize("kind", ["press", "machine"])
def test_state_round_trip_and_bad_inputs(native_core, kind):
    if kind == "press":
        py, nat = PressModel(PressParameters()), native_core.press(PressParameters())
        inputs = {}
    else:
        py, nat = MachineModel(MachineParameters()), native_core.machine(MachineParameters())
        inputs = {"pull_force": 3000.0}
    for _ in range(7):
        nat.step(4e-3, inputs)
    saved = nat.get_state()
    first = [nat.step(dt, inputs) for dt in (1e-3, 3e-3, 0.04, 2e-3)]
    nat.set_state(saved)
    assert [nat.step(dt, inputs) for dt in (1e-3, 3e-3, 0.04, 2e-3)] == first
    for bad in (saved[:-1], b"\0" * len(saved)):
        with pytest.raises(native_core.NativeError):
            nat.set_state(bad)
    before = nat.get_state()
    bad_calls = [(dt, 3000.0) for dt in (math.nan, math.inf, -math.inf, 0.0, -0.0, -1e-3)]
    if kind == "machine":
        bad_calls += [(1e-3, f) for f in (math.nan, math.inf, -math.inf)]
    for dt, force in bad_calls:
        with pytest.raises(ParameterError) as exc:
            py.step(dt, {"pull_force": force})
        assert nat.step_status(dt, {"pull_force": force}) == TC_DISCARD
        assert native_core.last_message() == str(exc.value)
        assert nat.get_state() == before
    # a step lost in rounding against a large time (Python: ZeroDivisionError) is refused
    far = bytearray(before)
    at = len(far) - (8 if kind == "press" else 16)  # the time, after the state vector
    far[at:at + 8] = np.float64(1e17).tobytes()
    nat.set_state(bytes(far))
    assert nat.step_status(1e-3, {"pull_force": 0.0}) == TC_DISCARD
    assert nat.get_state() == bytes(far)
