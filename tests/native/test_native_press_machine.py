"""The press and the drawing machine (tc_press.c, tc_machine.c, tc_linear.c) through their bindings.

Oracles: the matrix exponential against SciPy's (an independent implementation: Pade with scaling and squaring)
and closed forms; the exact stepping of a linear system (one step equals any split of it); the set-point table
grammar read alike by the Python check (PressParameters) and the C reader.
"""

from __future__ import annotations

import ctypes
import math

import numpy as np
import pytest
import scipy.linalg

from tribocosim.errors import ParameterError
from tribocosim.components.machine import MachineModel, MachineParameters
from tribocosim.components.native.toolchain.library import VP, core
from tribocosim.components.linear_model import expm
from tribocosim.components.press import PressModel, PressParameters


def test_expm_closed_forms():
    t = 0.7
    rotation = np.array([[0.0, -t], [t, 0.0]])
    np.testing.assert_allclose(expm(rotation), [[math.cos(t), -math.sin(t)], [math.sin(t), math.cos(t)]], rtol=1e-14,
                               atol=1e-15)
    nilpotent = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0]]) * 3.0
    np.testing.assert_allclose(expm(nilpotent), [[1, 3, 4.5], [0, 1, 3], [0, 0, 1]], rtol=1e-14)
    np.testing.assert_allclose(expm(np.diag([-1.0, 2.0])), np.diag(np.exp([-1.0, 2.0])), rtol=1e-14)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_expm_agrees_with_scipy_on_a_badly_scaled_controller_matrix(seed):
    """Entries over 15 decades (a velocity-error integral next to forces of 1e4 N): balanced, the exponential is
    accurate entry by entry, to 1e-10 of each entry (SciPy's own accuracy there)."""
    rng = np.random.default_rng(seed)
    scales = 10.0 ** rng.uniform(-7, 7, 6)
    M = (rng.normal(size=(6, 6)) - 3 * np.eye(6)) * 1e-3
    M = M * scales[:, None] / scales[None, :]
    E, ref = expm(M), scipy.linalg.expm(M)
    np.testing.assert_allclose(E, ref, rtol=1e-10, atol=1e-12 * np.abs(ref).max())


def test_press_holds_its_setpoint_and_steps_exactly():
    """Integral action: F_N -> F_set exactly; a linear model with a piecewise-linear set-point is stepped exactly,
    so 300 steps of 2 ms end where 600 steps of 1 ms do (to rounding)."""
    p = PressParameters(force_setpoint=9000.0, ramp_time=0.05)
    a, b = PressModel(p), PressModel(p)
    for _ in range(600):
        a.step(1e-3)
    for _ in range(300):
        b.step(2e-3)
    np.testing.assert_allclose(a.outputs()["normal_force"], b.outputs()["normal_force"], rtol=1e-10)
    np.testing.assert_allclose(a.outputs()["normal_force"], 9000.0, rtol=1e-3)
    assert a.outputs()["force_setpoint"] == 9000.0 and a.time == pytest.approx(0.6)


def test_machine_carries_the_pull_in_its_drivetrain():
    m = MachineModel(MachineParameters(velocity_setpoint=0.08, ramp_time=0.02))
    for k in range(600):
        out = m.step(1e-3, {"pull_force": 3700.0 * min(1.0, k / 50)})
    np.testing.assert_allclose(out["grip_velocity"], 0.08, rtol=1e-3)
    z = m.state
    np.testing.assert_allclose(m.params.drive_stiffness * (z[0] - z[2]), 3700.0, rtol=1e-3)


GOOD_TABLES = ["0 0; 0.01 1000; 0.05 12250", "\t0 0;  0.01   1000 ;;  ; 0.02 2000", "0 0; 1e-2 5000; .02 6e3; 0.03 +7000.",
               "0.0 1.5E3"]
BAD_TABLES = [";", "   ", "0 0; 0.01", "0 0 1; 0.01 5", "0 0; 0.01 abc", "0 0; 0.01 1_000", "0 0; 0.01 0x10",
              "0 0; 0.01 1e", "0 0; 0.01 -5", "0 0; 0 5", "0.02 0; 0.01 5", "0 nan", "0 inf", "0 0; 0.01 1e999",
              "0\u00a00", "0 0;\n0.01 5"]


def _native_press(text: str):
    """A native press with ``setpoint_table`` = text, the Python check bypassed (the C reader's own verdict)."""
    c = core()
    struct = c.struct(PressParameters())
    struct.setpoint_table = text.encode()
    handle = VP()
    c.call(c.lib.tc_press_create, ctypes.byref(struct), ctypes.byref(handle))
    return handle


@pytest.mark.parametrize("text", GOOD_TABLES + BAD_TABLES)
def test_setpoint_table_grammar_is_read_alike_in_python_and_c(text):
    try:
        PressParameters(setpoint_table=text)
        python_ok = True
    except ParameterError:
        python_ok = False
    try:
        core().lib.tc_press_free(_native_press(text))
        c_ok = True
    except ParameterError as exc:
        assert "setpoint_table" in str(exc)
        c_ok = False
    assert python_ok == c_ok == (text in GOOD_TABLES)


def test_setpoint_table_is_followed():
    p = PressParameters(setpoint_table="0 0; 0.1 5000; 0.2 5000; 0.3 2000")
    press = PressModel(p)
    seen = {}
    for k in range(400):
        out = press.step(1e-3)
        seen[k + 1] = out["force_setpoint"]
    assert seen[50] == pytest.approx(2500.0) and seen[150] == 5000.0 and seen[250] == pytest.approx(3500.0)
    assert seen[400] == 2000.0  # held after the last point
    np.testing.assert_allclose(press.outputs()["normal_force"], 2000.0, rtol=1e-3)


@pytest.mark.parametrize("kind", ["press", "machine"])
def test_state_round_trip_and_bad_inputs(kind):
    model = PressModel(PressParameters()) if kind == "press" else MachineModel(MachineParameters())
    inputs = {"pull_force": 3000.0}
    for _ in range(7):
        model.step(4e-3, inputs)
    saved = model.get_state()
    first = [model.step(dt, inputs) for dt in (1e-3, 3e-3, 0.04, 2e-3)]
    model.set_state(saved)
    assert [model.step(dt, inputs) for dt in (1e-3, 3e-3, 0.04, 2e-3)] == first
    for bad in (saved[:-1], np.zeros_like(saved)):
        with pytest.raises(ParameterError):
            model.set_state(bad)
    before = model.get_state()
    bad_calls = [(dt, 3000.0) for dt in (math.nan, math.inf, -math.inf, 0.0, -1e-3)]
    if kind == "machine":
        bad_calls += [(1e-3, f) for f in (math.nan, math.inf, -math.inf)]
    for dt, force in bad_calls:
        with pytest.raises(ParameterError):
            model.step(dt, {"pull_force": force})
        assert np.array_equal(model.get_state(), before)
