"""The StripDraw FMU's field file: ``field_output`` (beta, U, contact over X and time) and ``field_input``.

Driven through fmpy (the session's FMUs from ``tribocosim fmu build``, conftest.py). References:
the pure strip-draw model stepped with the same inputs (the FMU runs the same code, so the
recorded fields must be identical), and the FMU's own scalar outputs (beta_max).
"""

from __future__ import annotations

import numpy as np

from tribocosim.components.native.resource_io.field_file import read_fields
import pytest
from fmpy.fmi1 import FMICallException
from numpy.testing import assert_array_equal

from tribocosim.components.stripdraw import StripDrawModel, StripDrawParameters, make_friction_law, read_table
from tribocosim.paths import DEFAULT_TABLE

CHEAP = {"n_elements": 60, "draw_length": 0.02, "tool_length": 0.035}
F10 = 10e6 * 0.035 * 0.035
DT = 2e-3


def schedule(n):
    return [(DT, F10, 0.08 * min(1.0, (k + 1) * DT / 0.01)) for k in range(n)]


def pure_fields(parameters, rows, beta_field=None):
    p = StripDrawParameters(**parameters)
    model = StripDrawModel(p, make_friction_law(p, read_table(DEFAULT_TABLE)), beta_field=beta_field)
    fields = [model.fields()]
    for dt, fn, v in rows:
        model.step(dt, {"normal_force": fn, "grip_velocity": v})
        fields.append(model.fields())
    return model, fields


def test_field_output_holds_the_models_fields_at_the_recorded_times(stripdraw_fmu_instance, tmp_path):
    path = tmp_path / "sub" / "field.npz"
    inst = stripdraw_fmu_instance("rec", {**CHEAP, "field_output": str(path), "field_output_interval": 3.5 * DT})
    inst.initialize()
    rows = schedule(40)
    for dt, fn, v in rows:
        inst.step(dt, fn, v)
    assert not path.exists(), "the file is written at terminate, not before"
    beta_max = inst.outputs()[5]
    inst.slave.terminate()
    data = read_fields(path)
    model, fields = pure_fields(CHEAP, rows)
    # rows: t = 0, then every 4th step (the first step at least 3.5 steps after the last row), and the end
    expected_steps = [0, 4, 8, 12, 16, 20, 24, 28, 32, 36, 40]
    np.testing.assert_allclose(data["time"], [k * DT for k in expected_steps], rtol=1e-12, atol=1e-15)
    assert_array_equal(data["X"], model.mesh.X)
    for key in ("beta", "U", "contact"):
        assert data[key].shape == (len(expected_steps), model.mesh.n_nodes), key
        assert_array_equal(data[key], np.array([fields[k][key] for k in expected_steps]), err_msg=key)
    assert_array_equal(data["window"], [model.mesh.window_lo, model.mesh.window_hi])
    assert data["beta"][-1].max() == pytest.approx(beta_max, rel=1e-15), "last row = the FMU's final state"
    c = data["contact"][-1]
    assert data["beta"][-1].max() > 0 and c.min() >= 0 and 0 < c.max() <= 1.0 + 1e-9, "contact weights in [0, 1]"


def test_a_rolled_back_step_is_dropped_from_the_file(stripdraw_fmu_instance, tmp_path):
    path = tmp_path / "field.npz"
    inst = stripdraw_fmu_instance("rollback", {**CHEAP, "field_output": str(path)})
    inst.initialize()
    rows = schedule(12)
    for dt, fn, v in rows[:6]:
        inst.step(dt, fn, v)
    state = inst.slave.getFMUState()
    for dt, fn, v in rows[6:9]:  # a trial the master rejects ...
        inst.step(dt, 2 * fn, v)
    inst.slave.setFMUState(state)
    inst.time = 6 * DT
    for dt, fn, v in rows[6:]:  # ... and the accepted steps
        inst.step(dt, fn, v)
    inst.slave.freeFMUState(state)
    inst.slave.terminate()
    f = read_fields(path)
    time, beta = f["time"], f["beta"]
    np.testing.assert_allclose(time, DT * np.arange(13), rtol=1e-12, atol=1e-15)
    _, fields = pure_fields(CHEAP, rows)
    assert_array_equal(beta, np.array([f["beta"] for f in fields]), err_msg="rows of the rejected trial remain")


def test_no_field_file_by_default(stripdraw_fmu_instance, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    inst = stripdraw_fmu_instance("plain", dict(CHEAP))
    inst.initialize()
    for dt, fn, v in schedule(5):
        inst.step(dt, fn, v)
    inst.slave.terminate()
    assert list(tmp_path.iterdir()) == []


def test_field_input_starts_a_later_pass_from_the_last_beta_row(stripdraw_fmu_instance, tmp_path):
    first = tmp_path / "pass1.npz"
    inst = stripdraw_fmu_instance("pass1", {**CHEAP, "field_output": str(first), "field_output_interval": 1.0})
    inst.initialize()
    rows = schedule(30)
    for dt, fn, v in rows:
        inst.step(dt, fn, v)
    inst.slave.terminate()
    left = read_fields(first)["beta"][-1]
    second = stripdraw_fmu_instance("pass2", {**CHEAP, "field_input": str(first)})
    second.initialize()
    assert second.outputs()[5] == pytest.approx(left.max(), rel=1e-15), "beta_max at the start of pass 2"
    got = np.array([second.step(dt, fn, v) for dt, fn, v in rows])
    model, _ = pure_fields(CHEAP, [], beta_field=left)
    ref = np.array([list(model.step(dt, {"normal_force": fn, "grip_velocity": v}).values()) for dt, fn, v in rows])
    assert_array_equal(got[:, :8], ref[:, :8], err_msg="pass 2 through the FMU vs the model started from the field")


def test_field_input_of_another_mesh_is_refused_naming_the_parameter(stripdraw_fmu_instance, tmp_path):
    path = tmp_path / "coarse.npz"
    inst = stripdraw_fmu_instance("coarse", {**CHEAP, "n_elements": 40, "field_output": str(path)})
    inst.initialize()
    inst.slave.terminate()
    bad = stripdraw_fmu_instance("bad", {**CHEAP, "field_input": str(path)})
    with pytest.raises(FMICallException) as exc:
        bad.initialize()
    assert exc.value.status == 3, "fmi2Error at the end of initialization"
    text = " ".join(m for _, m in bad.messages)
    assert "field_input" in text and "another mesh" in text and "41 nodes" in text, text
