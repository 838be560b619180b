"""The nodal-field file (CSV; tc_fields.c written through FieldRecorder, read by read_fields and, for a later
pass, by the native reader read_initial_beta).

What is written reads back exactly (17 significant digits); the recorder's interval and rollback rules; the write
is atomic and makes its folders; the reader refuses a file of another mesh or no field file at all, naming it;
allocation failures leak nothing.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass, field

import numpy as np
import pytest

from tribocosim.errors import ParameterError
from tribocosim.components.native.toolchain import compiler
from tribocosim.components.native.resource_io.field_file import FieldRecorder, read_fields, read_initial_beta

SOURCES = ("core/tc_common.c", "resource_io/tc_fields.c")


@dataclass
class FakeModel:
    """What the recorder reads of a model: time, mesh and fields."""

    X: np.ndarray
    time: float = 0.0
    rng: np.random.Generator = field(default_factory=lambda: np.random.default_rng(0))

    @property
    def mesh(self):
        return type("Mesh", (), {"X": self.X, "window_lo": 0.145, "window_hi": 0.18})

    def fields(self):
        n = self.X.size
        self.last = {"beta": self.rng.random(n) * 0.3, "U": self.rng.normal(size=n) * 1e-3 + 0.1 * self.time,
                     "contact": (self.rng.random(n) > 0.5).astype(float)}
        return self.last


def test_what_is_written_reads_back_exactly(tmp_path):
    path = tmp_path / "sub" / "dir" / "f.csv"  # folders are made
    model = FakeModel(np.linspace(0.0, 0.23, 9))
    rec = FieldRecorder.start(path, 0.0, model, {"n_elements": 8, "table_file": "x.npz", "mu0": 0.15})
    written = [(0.0, model.last)]
    for k in range(1, 5):
        model.time = k * 1e-3
        rec.record(model)
        written.append((model.time, model.last))
    assert rec.finish().startswith("field_output: 5 rows")
    back = read_fields(path)
    assert np.array_equal(back["X"], model.X) and np.array_equal(back["window"], [0.145, 0.18])
    assert np.array_equal(back["time"], [t for t, _ in written])
    for q in ("beta", "U", "contact"):
        assert np.array_equal(back[q], np.array([f[q] for _, f in written])), q
    assert back["metadata"] == {"mu0": "0.15", "n_elements": "8", "table_file": "x.npz"}
    assert np.array_equal(read_initial_beta(path, model.X), written[-1][1]["beta"])
    assert [p.name for p in path.parent.iterdir()] == ["f.csv"], "no temporary file is left"


def test_interval_and_rollback_rules(tmp_path):
    model = FakeModel(np.linspace(0.0, 0.23, 5))
    rec = FieldRecorder.start(tmp_path / "f.csv", 2e-3, model, {})
    for k in range(1, 10):  # rows at 0, 2, 4, 6, 8 ms: each at least the interval after the last
        model.time = k * 1e-3
        rec.record(model)
    rec.truncate(5e-3)  # a rolled-back step to 5 ms drops the 6 and 8 ms rows
    model.time = 5.5e-3
    rec.finish(model)  # the final state is always the last row
    assert np.allclose(read_fields(tmp_path / "f.csv")["time"], [0.0, 2e-3, 4e-3, 5.5e-3], rtol=0, atol=1e-15)


def test_the_reader_refuses_another_mesh_and_what_is_no_field_file(tmp_path):
    X = np.linspace(0.0, 0.23, 6)
    rec = FieldRecorder.start(tmp_path / "f.csv", 0.0, FakeModel(X), {})
    rec.finish()
    with pytest.raises(ParameterError, match="was written for another mesh .6 nodes over .0, 0.23. m; this strip "
                                             "has 7 nodes"):
        read_initial_beta(tmp_path / "f.csv", np.linspace(0.0, 0.23, 7))
    (tmp_path / "other.csv").write_text("time,x\n0,1\n")
    with pytest.raises(ParameterError, match="is not a field_output file"):
        read_initial_beta(tmp_path / "other.csv", X)
    with pytest.raises(ParameterError, match="cannot be read"):
        read_initial_beta(tmp_path / "missing.csv", X)
    text = (tmp_path / "f.csv").read_text()
    (tmp_path / "cut.csv").write_text(text[:-40])
    with pytest.raises(ParameterError, match="no complete row"):
        read_initial_beta(tmp_path / "cut.csv", X)
    with pytest.raises(ParameterError, match="not a field file"):
        read_fields(tmp_path / "other.csv")
    with pytest.raises(ParameterError, match="field_output_interval"):
        FieldRecorder.start(tmp_path / "g.csv", -1.0, FakeModel(X), {})


def test_a_write_that_cannot_happen_names_the_file(tmp_path):
    (tmp_path / "file").write_text("")
    rec = FieldRecorder.start(tmp_path / "file" / "f.csv", 0.0, FakeModel(np.linspace(0, 1, 3)), {})
    with pytest.raises(ParameterError, match=r"field_output = '.*f\.csv' cannot be written"):
        rec.finish()


def test_allocation_failures_leak_nothing(tmp_path, native_checked_compile):
    lib = ctypes.CDLL(str(native_checked_compile(SOURCES, tmp_path, "libtc_fields.so")))
    lib.tc_count_live.restype = ctypes.c_long
    lib.tc_count_fail_after.argtypes = [ctypes.c_long]

    class Msg(ctypes.Structure):
        _fields_ = [("text", ctypes.c_void_p), ("size", ctypes.c_size_t)]

    buf = ctypes.create_string_buffer(512)
    msg = Msg(ctypes.addressof(buf), 512)
    X = np.linspace(0.0, 0.23, 20)
    P = ctypes.POINTER(ctypes.c_double)
    beta = np.random.default_rng(1).random(20)
    window = np.array([0.1, 0.2])
    path = str(tmp_path / "f.csv").encode()
    for n in range(60):
        lib.tc_count_fail_after(n)
        rec = ctypes.c_void_p()
        ok = lib.tc_field_recorder_create(path, ctypes.c_double(0.0), ctypes.c_size_t(20), X.ctypes.data_as(P),
                                          window.ctypes.data_as(P), b"a: 1\n", ctypes.byref(rec), msg) == 0
        for k in range(40 if ok else 0):
            if lib.tc_field_recorder_record(rec, ctypes.c_double(k * 1e-3), *(beta.ctypes.data_as(P),) * 3, 0, msg):
                break
        if ok:
            lib.tc_field_recorder_write(rec, msg)
            lib.tc_field_recorder_free(rec)
        out = np.empty(20)
        lib.tc_field_read_initial_beta(path, ctypes.c_size_t(20), X.ctypes.data_as(P), out.ctypes.data_as(P), msg)
        lib.tc_count_fail_after(-1)
        assert lib.tc_count_live() == 0, f"allocation {n} failing leaks"


@pytest.mark.slow
@pytest.mark.parametrize("platform", ["win64", "darwin64"])
def test_builds_clean_for_windows_and_macos(tmp_path, platform):
    suffix = compiler.PLATFORMS[platform][1]
    out = compiler.compile_shared(list(map(compiler.source, SOURCES)), tmp_path / f"tc_fields{suffix}",
                                   platform, defines=["TC_EXPORT_CORE"])
    assert out.stat().st_size > 0
