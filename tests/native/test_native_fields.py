"""The native field file (tc_fields.c) against stripdraw/fields.py, the format's owner.

Writing: the C writer's files are byte for byte those write_fields writes (np.savez) for the same arrays, and
read back by read_fields / np.load bit for bit; the C recorder follows FieldRecorder's rules (interval,
truncation after a rollback, the final row at finish) row for row over random runs; the ZIP64 paths (past
zipfile's ZIP64_LIMIT) are compared the same way on a build with a lowered limit. Reading: the last beta row
of Python-written files, and read_initial_beta's refusals with its messages. Robustness: allocation failures
leak nothing; fuzzed files (in a subprocess) never crash the reader and are accepted only when intact.
"""

from __future__ import annotations

import ctypes
import dataclasses
import io
import json
import math
import os
import subprocess
import sys
import time
import zipfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from tribocosim.components.errors import ParameterError
from tribocosim.components.native import toolchain
from tribocosim.components.paths import DEFAULT_TABLE
from tribocosim.components.stripdraw.component import StripDrawFiles
from tribocosim.components.stripdraw.fields import FieldRecorder, read_fields, read_initial_beta, write_fields
from tribocosim.components.stripdraw.parameters import StripDrawParameters

SOURCES = ("tc_fields.c", "tc_common.c", "tc_npz.c", "tc_linear.c", "tc_json.c")
TC_OK, TC_ERROR, TC_NOMEM = 0, 2, 3
MSG_SIZE = 2048
ZIP64_TEST_LIMIT = 1000  # TC_FIELDS_ZIP64_LIMIT of the checked build

_D = ctypes.POINTER(ctypes.c_double)




class _Msg(ctypes.Structure):
    _fields_ = [("text", ctypes.c_char_p), ("size", ctypes.c_size_t)]


def _p(a: np.ndarray):
    return a.ctypes.data_as(_D)


def _f8(a) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=float)


class Fields:
    """The library with its prototypes and Python-shaped wrappers."""

    def __init__(self, path: Path, counting: bool = False):
        self.lib = lib = ctypes.CDLL(str(path))
        vp, sz, dbl, i, s = ctypes.c_void_p, ctypes.c_size_t, ctypes.c_double, ctypes.c_int, ctypes.c_char_p
        proto = {
            "tc_field_recorder_create": (i, [s, dbl, sz, _D, _D, s, ctypes.POINTER(vp), _Msg]),
            "tc_field_recorder_record": (i, [vp, dbl, _D, _D, _D, i, _Msg]),
            "tc_field_recorder_truncate": (None, [vp, dbl]),
            "tc_field_recorder_write": (i, [vp, _Msg]),
            "tc_field_recorder_finish": (i, [vp, dbl, _D, _D, _D, _Msg]),
            "tc_field_recorder_rows": (sz, [vp]),
            "tc_field_recorder_last_time": (dbl, [vp]),
            "tc_field_recorder_free": (None, [vp]),
            "tc_fields_write": (i, [s, sz, sz, _D, _D, _D, _D, _D, _D, s, _Msg]),
            "tc_field_read_initial_beta": (i, [s, sz, _D, _D, _Msg]),
            "tc_format_g": (s, [dbl, s]),
        }
        if counting:
            proto["tc_count_live"] = (ctypes.c_long, [])
            proto["tc_count_fail_after"] = (None, [ctypes.c_long])
        for name, (res, args) in proto.items():
            getattr(lib, name).restype = res
            getattr(lib, name).argtypes = args
        self.buf = ctypes.create_string_buffer(MSG_SIZE)

    def msg(self) -> _Msg:
        self.buf.value = b""
        return _Msg(ctypes.cast(self.buf, ctypes.c_char_p), MSG_SIZE)

    @property
    def message(self) -> str:
        return self.buf.value.decode(errors="replace")

    def write_fields(self, path, time_, X, beta, U, contact, window, meta_text: str) -> tuple[int, str]:
        t, X, b, u, c, w = (_f8(a) for a in (time_, X, beta, U, contact, window))
        rc = self.lib.tc_fields_write(os.fsencode(str(path)), t.size, X.size, _p(t), _p(X), _p(b), _p(u), _p(c),
                                      _p(w), meta_text.encode(), self.msg())
        return rc, self.message

    def read_initial_beta(self, path, X) -> tuple[int, str, np.ndarray | None]:
        X = _f8(X)
        out = np.full(X.size, -7.0)
        rc = self.lib.tc_field_read_initial_beta(os.fsencode(str(path)), X.size, _p(X), _p(out), self.msg())
        return rc, self.message, out if rc == TC_OK else None

    def format_g(self, x: float) -> str:
        buf = ctypes.create_string_buffer(32)
        return self.lib.tc_format_g(x, buf).decode()

    def recorder(self, path, interval, X, window, meta_text) -> "CRecorder":
        return CRecorder(self, path, interval, X, window, meta_text)


class CRecorder:
    """A tc_field_recorder; create raises ParameterError with the C message (as FieldRecorder.start would)."""

    def __init__(self, f: Fields, path, interval, X, window, meta_text):
        self.f, self.X = f, _f8(X)
        self.handle = ctypes.c_void_p()
        self.rc = f.lib.tc_field_recorder_create(os.fsencode(str(path)), interval, self.X.size, _p(self.X),
                                                 _p(_f8(window)), meta_text.encode(), ctypes.byref(self.handle),
                                                 f.msg())
        if self.rc != TC_OK:
            assert not self.handle, "a refused create must leave the recorder NULL"
            raise ParameterError(f.message)

    def record(self, t, fields, force=False) -> int:
        b, u, c = (_f8(fields[k]) for k in ("beta", "U", "contact"))
        return self.f.lib.tc_field_recorder_record(self.handle, t, _p(b), _p(u), _p(c), int(force), self.f.msg())

    def truncate(self, t) -> None:
        self.f.lib.tc_field_recorder_truncate(self.handle, t)

    def write(self) -> int:
        return self.f.lib.tc_field_recorder_write(self.handle, self.f.msg())

    def finish(self, t, fields) -> int:
        b, u, c = (_f8(fields[k]) for k in ("beta", "U", "contact"))
        return self.f.lib.tc_field_recorder_finish(self.handle, t, _p(b), _p(u), _p(c), self.f.msg())

    @property
    def rows(self) -> int:
        return self.f.lib.tc_field_recorder_rows(self.handle)

    @property
    def last_time(self) -> float:
        return self.f.lib.tc_field_recorder_last_time(self.handle)

    def free(self) -> None:
        if self.handle:
            self.f.lib.tc_field_recorder_free(self.handle)
            self.handle = ctypes.c_void_p()


class FakeModel:
    """What FieldRecorder reads of a StripDrawModel: time, mesh.X, mesh.window_lo/hi and fields() (fresh arrays)."""

    def __init__(self, n_nodes: int, rng):
        self.rng = rng
        X = np.linspace(0.0, 0.23, n_nodes)
        self.mesh = SimpleNamespace(X=X, window_lo=0.145, window_hi=0.18000000000000002)
        self.time = 0.0
        self.advance(0.0)

    def advance(self, t: float) -> None:
        self.time = t
        m = self.mesh.X.size
        beta = self.rng.random(m)
        beta[self.rng.integers(0, m)] = float(self.rng.choice([-0.0, 5e-324, np.nan, np.inf, 1e300]))
        self.state = {"beta": beta, "U": self.rng.normal(0, 1e-4, m), "contact": (self.rng.random(m) < 0.3) * 1.0}

    def fields(self) -> dict:
        return {k: v.copy() for k, v in self.state.items()}


def _parameters() -> dict:
    return {**dataclasses.asdict(StripDrawParameters()), "field_output_interval": 0.0, "note": 'a "quoted" \\ \t é'}


def _meta_text(parameters: dict) -> str:
    return json.dumps(parameters, sort_keys=True)


def _same_arrays(a: dict, b: dict) -> list[str]:
    """Keys whose arrays differ in dtype, shape or bits (NaN payloads and -0.0 included)."""
    bad = [k for k in a if k != "metadata" and (a[k].dtype != b[k].dtype or a[k].shape != b[k].shape
                                                 or a[k].tobytes() != b[k].tobytes())]
    return bad + ([] if a.get("metadata") == b.get("metadata") else ["metadata"])


# ---- fixtures --------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def fields_dir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("native_fields")


@pytest.fixture(scope="module")
def native_fields(fields_dir) -> Fields:
    out = toolchain.compile_shared([toolchain.SOURCE_DIR / s for s in SOURCES], fields_dir / "libtc_fields.so",
                                   "linux64", defines=["TC_EXPORT_CORE"])
    return Fields(out)


@pytest.fixture(scope="module")
def checked_build(fields_dir, native_checked_compile) -> Path:
    """The same sources with undefined behaviour trapping, the allocation-counting shim and a ZIP64 limit of
    ZIP64_TEST_LIMIT bytes (so that small files take every ZIP64 path)."""
    return native_checked_compile(SOURCES, fields_dir, "libtc_checked.so",
                                  defines=[f"TC_FIELDS_ZIP64_LIMIT={ZIP64_TEST_LIMIT}"])


@pytest.fixture(scope="module")
def checked_fields(checked_build) -> Fields:
    return Fields(checked_build, counting=True)


# ---- writing ---------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n_rows, n_nodes", [(1, 5), (0, 3), (157, 101)])
def test_writes_the_bytes_write_fields_writes(native_fields, tmp_path, n_rows, n_nodes):
    rng = np.random.default_rng(n_rows)
    arrays = dict(time=np.arange(n_rows) * 1e-3, X=np.linspace(0.0, 0.23, n_nodes), beta=rng.random((n_rows, n_nodes)),
                  U=rng.normal(0, 1e-4, (n_rows, n_nodes)), contact=(rng.random((n_rows, n_nodes)) < 0.5) * 1.0,
                  window=np.array([0.145, 0.18000000000000002]))
    flat = arrays["beta"].reshape(-1)  # a view: special values, bit patterns kept
    flat[::7] = np.resize([np.nan, -0.0, 5e-324, np.inf], flat[::7].size)
    parameters = _parameters()
    rc, msg = native_fields.write_fields(tmp_path / "c.npz", *arrays.values(), _meta_text(parameters))
    assert rc == TC_OK, msg
    write_fields(tmp_path / "py.npz", *arrays.values(), parameters)
    assert (tmp_path / "c.npz").read_bytes() == (tmp_path / "py.npz").read_bytes()

    got = read_fields(tmp_path / "c.npz")
    assert got["metadata"] == parameters
    assert _same_arrays(got, {**arrays, "metadata": parameters}) == []
    with np.load(tmp_path / "c.npz", allow_pickle=False) as data:
        assert data.files == ["time", "X", "beta", "U", "contact", "window", "metadata"]
        assert data["metadata"].dtype == np.dtype(f"<U{len(_meta_text(parameters))}") and data["metadata"].shape == ()
        assert all(data[k].dtype == np.dtype("<f8") for k in arrays)
        assert data["beta"].shape == (n_rows, n_nodes) and data["beta"].flags.c_contiguous
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.npz", "py.npz"]


def _run_both(f: Fields, tmp_path: Path, interval: float, seed: int, steps: int, n_nodes: int = 23):
    """The C recorder and FieldRecorder driven alike: steps of 1-3 ticks of an integer time grid, rollbacks to
    an earlier step's start (truncate), forced rows, then finish. Returns the two files."""
    rng = np.random.default_rng(seed)
    model = FakeModel(n_nodes, rng)
    parameters = _parameters()
    h, tick = 1e-3, 0
    py = FieldRecorder.start(tmp_path / "py.npz", interval, model, parameters)
    c = f.recorder(tmp_path / "c.npz", interval, model.mesh.X, (model.mesh.window_lo, model.mesh.window_hi),
                   _meta_text(parameters))
    try:
        assert c.record(model.time, model.fields(), force=True) == TC_OK
        starts = [0]
        for _ in range(steps):
            r = rng.random()
            if r < 0.08:  # a rejected step: the state goes back to an earlier step's start
                tick = starts[int(rng.integers(max(0, len(starts) - 5), len(starts)))]
                model.advance(tick * h)
                py.truncate(model.time)
                c.truncate(model.time)
            else:
                starts.append(tick)
                tick += int(rng.choice([1, 1, 1, 2, 3]))
                model.advance(tick * h)
                force = r > 0.97
                py.record(model, force=force)
                assert c.record(model.time, model.fields(), force=force) == TC_OK
            assert c.rows == len(py.times) and c.last_time == py.times[-1]
        if rng.random() < 0.5:  # sometimes the final state is already the last row
            py.record(model, force=True)
            c.record(model.time, model.fields(), force=True)
        py.finish(model)
        assert c.finish(model.time, model.fields()) == TC_OK, f.message
        assert c.rows == len(py.times)
    finally:
        c.free()
    return tmp_path / "c.npz", tmp_path / "py.npz"


@pytest.mark.parametrize("interval", [0.0, 1e-3, 2e-3, 3.5e-3, 0.0101])
def test_recorder_follows_field_recorder_row_for_row(native_fields, tmp_path, interval):
    c_file, py_file = _run_both(native_fields, tmp_path, interval, seed=int(interval * 1e4), steps=400)
    assert c_file.read_bytes() == py_file.read_bytes()
    got = read_fields(c_file)
    assert got["time"].size > 1 and got["metadata"] == _parameters()


def test_interval_and_truncation_rules_at_their_edges(native_fields, tmp_path):
    """The two tolerances, at the last double on either side, against FieldRecorder itself."""
    model = FakeModel(3, np.random.default_rng(0))
    model.time = 0.1
    py = FieldRecorder.start(tmp_path / "p.npz", 0.01, model, {})
    c = native_fields.recorder(tmp_path / "c.npz", 0.01, model.mesh.X, (0.0, 1.0), "{}")
    c.record(model.time, model.fields(), force=True)
    edge = 0.1 + 0.01 * (1.0 - 1e-9)
    for t in (np.nextafter(edge, 0), edge, np.nextafter(edge, 1), 0.12, 0.13, 0.14):
        model.time = float(t)
        py.record(model)
        c.record(float(t), model.fields())
        assert c.rows == len(py.times) and c.last_time == py.times[-1], t
    assert c.rows == 5
    rows = len(py.times)
    for t in (0.14, 0.13 * (1 + 1e-12), np.nextafter(0.13 / (1 + 1e-12), 0), 0.12, 0.0, -1.0):
        py.truncate(float(t))
        c.truncate(float(t))
        assert c.rows == len(py.times), t
        assert c.rows < rows or t == 0.14
    assert c.rows == 0 and math.isnan(c.last_time)
    assert c.write() == TC_OK, native_fields.message  # no rows: empty arrays of the right widths
    empty = read_fields(tmp_path / "c.npz")
    assert empty["time"].shape == (0,) and empty["beta"].shape == empty["contact"].shape == (0, 3)
    # near zero the absolute 1e-15 decides
    for t0 in (0.0, 1e-15, 2e-15, 3e-15):
        c.record(t0, model.fields(), force=True)
        py.times.append(t0)
        py.rows.append(None)
    for t in (2e-15, 1e-15, 0.0):
        py.truncate(t)
        c.truncate(t)
        assert c.rows == len(py.times), t
    c.free()


@pytest.mark.parametrize("interval", [-1.0, -0.0 - 1e-300, float("nan"), float("inf")])
def test_refuses_a_bad_interval_with_pythons_message(native_fields, tmp_path, interval):
    with pytest.raises(ParameterError) as c_err:
        native_fields.recorder(tmp_path / "f.npz", interval, np.zeros(3), (0.0, 1.0), "{}")
    if math.isinf(interval):  # FieldRecorder takes inf; the FMU's parameter check refuses it before
        with pytest.raises(ParameterError) as py_err:
            StripDrawFiles(field_output_interval=interval)
    else:
        with pytest.raises(ParameterError) as py_err:
            FieldRecorder.start(tmp_path / "f.npz", interval, None, {})
    assert str(c_err.value) == str(py_err.value)


@pytest.mark.parametrize("text, problem", [("", "not a JSON object"), ("[1]", "not a JSON object"),
                                           ('{"a": }', "not a JSON object"), ('{"a": "é"}', "not ASCII")])
def test_refuses_metadata_that_would_not_read_back(native_fields, tmp_path, text, problem):
    with pytest.raises(ParameterError, match=problem):
        native_fields.recorder(tmp_path / "f.npz", 0.0, np.zeros(3), (0.0, 1.0), text)


def test_write_is_atomic_and_creates_folders(native_fields, tmp_path):
    rng = np.random.default_rng(5)
    target = tmp_path / "a" / "b" / "c" / "fields.npz"
    for k in range(2):  # a new file, then one replaced
        arrays = (np.arange(k + 1.0), np.zeros(4), rng.random((k + 1, 4)), np.zeros((k + 1, 4)), np.ones((k + 1, 4)),
                  np.array([0.0, 1.0]))
        rc, msg = native_fields.write_fields(target, *arrays, '{"k": %d}' % k)
        assert rc == TC_OK, msg
        assert [p.name for p in target.parent.iterdir()] == ["fields.npz"]  # no temporary file left
        assert read_fields(target)["metadata"] == {"k": k} and read_fields(target)["time"].size == k + 1

    blocker = tmp_path / "file.txt"
    blocker.write_text("x")
    rc, msg = native_fields.write_fields(blocker / "sub" / "f.npz", *arrays, "{}")
    with pytest.raises(OSError) as python_error:  # the folder cannot be made: the same reason as Python's mkdir
        write_fields(blocker / "sub" / "f.npz", *arrays, {})
    assert (rc, msg) == (TC_ERROR, f"field_output = {str(blocker / 'sub' / 'f.npz')!r} cannot be written: "
                                   f"{python_error.value}")

    folder = tmp_path / "taken.npz"  # the target is a folder: the rename fails, the temporary file goes
    folder.mkdir()
    rc, msg = native_fields.write_fields(folder, *arrays, "{}")
    assert rc == TC_ERROR and msg.startswith(f"field_output = {str(folder)!r} cannot be written: [Errno 21]"), msg
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a", "file.txt", "taken.npz"]


def test_zip64_records_past_the_limit_match_zipfile(checked_fields, tmp_path, monkeypatch):
    """With the limit lowered on both sides, the central directory's ZIP64 fields and the ZIP64 end records
    come out as zipfile writes them, and both readers read them."""
    rng = np.random.default_rng(9)
    arrays = (np.arange(9.0), np.linspace(0, 1, 17), rng.random((9, 17)), rng.random((9, 17)), rng.random((9, 17)),
              np.array([0.2, 0.3]))
    meta = {"x": 1}
    rc, msg = checked_fields.write_fields(tmp_path / "c.npz", *arrays, _meta_text(meta))
    assert rc == TC_OK, msg
    monkeypatch.setattr(zipfile, "ZIP64_LIMIT", ZIP64_TEST_LIMIT)
    write_fields(tmp_path / "py.npz", *arrays, meta)
    monkeypatch.undo()
    raw = (tmp_path / "c.npz").read_bytes()
    assert raw == (tmp_path / "py.npz").read_bytes()
    # the ZIP64 end records, and central-directory extras with sizes and offset (U, contact) or offset only
    assert b"PK\x06\x06" in raw and b"PK\x06\x07" in raw
    assert raw.count(b"\x01\x00\x18\x00") == 2 and raw.count(b"\x01\x00\x08\x00") == 2
    assert _same_arrays(read_fields(tmp_path / "c.npz"), {**dict(zip(
        ("time", "X", "beta", "U", "contact", "window"), arrays)), "metadata": meta}) == []
    rc, msg, beta = checked_fields.read_initial_beta(tmp_path / "c.npz", arrays[1])
    assert rc == TC_OK and beta.tobytes() == arrays[2][-1].tobytes(), msg


# ---- reading ---------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def python_field_file(fields_dir) -> Path:
    """A file of the Python FieldRecorder (41 nodes, a dozen rows)."""
    model = FakeModel(41, np.random.default_rng(11))
    rec = FieldRecorder.start(fields_dir / "python_fields.npz", 2e-3, model, _parameters())
    for k in range(1, 25):
        model.advance(k * 1e-3)
        rec.record(model)
    rec.finish(model)
    return rec.path


def _python_beta(path, X):
    """(message, beta) of read_initial_beta: message None if it reads."""
    try:
        return None, read_initial_beta(path, np.asarray(X, dtype=float))
    except ParameterError as exc:
        return str(exc), None


def test_reads_the_last_row_of_python_files(native_fields, python_field_file, tmp_path):
    X = read_fields(python_field_file)["X"]
    rc, msg, beta = native_fields.read_initial_beta(python_field_file, X)
    assert rc == TC_OK, msg
    assert beta.tobytes() == read_initial_beta(python_field_file, X).tobytes()
    # a mesh equal to 1e-12 is the same mesh
    near = X + np.where(np.arange(X.size) % 2, 0.9e-12, -0.9e-12)
    assert native_fields.read_initial_beta(python_field_file, near)[2].tobytes() == beta.tobytes()
    assert _python_beta(python_field_file, near)[0] is None
    # Fortran order (np.savez of a Fortran array) reads the same row
    with np.load(python_field_file) as data:
        arrays = {k: data[k] for k in data.files}
    np.savez(tmp_path / "fortran.npz", **{**arrays, "beta": np.asfortranarray(arrays["beta"])})
    assert b"'fortran_order': True" in (tmp_path / "fortran.npz").read_bytes()
    rc, msg, got = native_fields.read_initial_beta(tmp_path / "fortran.npz", X)
    assert rc == TC_OK and got.tobytes() == beta.tobytes(), msg


def _savez(path, arrays: dict, **changes) -> Path:
    out = {**arrays, **changes}
    np.savez(path, **{k: v for k, v in out.items() if v is not None})
    return path


def _truncated_member(path, arrays: dict, key: str, keep: int) -> Path:
    """A valid zip whose member key.npy keeps only `keep` bytes of its data (its header claims them all)."""
    buf = io.BytesIO()
    np.lib.format.write_array(buf, arrays[key])
    raw = buf.getvalue()
    header_len = raw.index(b"\n") + 1
    with zipfile.ZipFile(path, "w") as z:
        for k, v in arrays.items():
            if k == key:
                z.writestr(f"{k}.npy", raw[:header_len + keep])
            else:
                b = io.BytesIO()
                np.lib.format.write_array(b, v)
                z.writestr(f"{k}.npy", b.getvalue())
    return path


def test_refuses_what_read_initial_beta_refuses_with_its_message(native_fields, python_field_file, tmp_path):
    with np.load(python_field_file) as data:
        arrays = {k: data[k] for k in data.files}
    X, beta = arrays["X"], arrays["beta"]
    (tmp_path / "text.npz").write_text("time,X,beta\n")
    big = {**arrays, "X": np.linspace(0, 1, 40000), "beta": np.zeros((2, 40000))}
    cases = {
        "missing file": (tmp_path / "nothing.npz", X),
        "a folder": (tmp_path, X),
        "not an npz": (tmp_path / "text.npz", X),
        "a friction table": (DEFAULT_TABLE, X),
        "no beta": (_savez(tmp_path / "no_beta.npz", arrays, beta=None), X),
        "no X": (_savez(tmp_path / "no_X.npz", arrays, X=None), X),
        "beta 1-D": (_savez(tmp_path / "b1.npz", arrays, beta=beta[-1]), X),
        "beta no rows": (_savez(tmp_path / "b0.npz", arrays, beta=beta[:0]), X),
        "beta other width": (_savez(tmp_path / "bw.npz", arrays, beta=beta[:, 1:]), X),
        "beta 3-D": (_savez(tmp_path / "b3.npz", arrays, beta=beta[None]), X),
        "fewer nodes": (python_field_file, X[:-1]),
        "shifted mesh": (python_field_file, X + 2e-12),
        "odd bounds": (python_field_file, np.linspace(-1.2345678e-5, 123456789.0, X.size)),
        "NaN in X": (_savez(tmp_path / "nan.npz", arrays, X=np.where(np.arange(X.size) == 3, np.nan, X)), X),
        "X truncated": (_truncated_member(tmp_path / "tx.npz", arrays, "X", 8 * X.size - 5), X),
        "beta truncated in chunk 2": (_truncated_member(tmp_path / "tb.npz", big, "beta", 300000), big["X"]),
        "beta truncated at a chunk": (_truncated_member(tmp_path / "tc.npz", big, "beta", 2**18), big["X"]),
    }
    for case, (path, mesh) in cases.items():
        rc, msg, _ = native_fields.read_initial_beta(path, mesh)
        expected, _ = _python_beta(path, mesh)
        assert expected is not None, case
        assert (rc, msg) == (TC_ERROR, expected), case


def test_refusals_of_files_that_are_not_field_files(native_fields, python_field_file, tmp_path):
    """An empty file, a broken zip, a bad CRC, a .npy file: both readers refuse each with the field_input
    message (read_initial_beta let EOFError, zipfile.BadZipFile and TypeError through until this test found
    them); a big-endian X Python converts, the C reader refuses."""
    X = read_fields(python_field_file)["X"]
    raw = python_field_file.read_bytes()
    (tmp_path / "empty.npz").write_bytes(b"")
    (tmp_path / "cut.npz").write_bytes(raw[: len(raw) // 2])
    flipped = bytearray(raw)
    flipped[raw.index(b"beta.npy") + 30 + 200] ^= 1  # in beta's data
    (tmp_path / "crc.npz").write_bytes(bytes(flipped))
    np.save(tmp_path / "one.npy", X)
    with np.load(python_field_file) as data:
        arrays = {k: data[k] for k in data.files}
    _savez(tmp_path / "f8be.npz", arrays, X=X.astype(">f8"))
    cases = {"empty.npz": ("No data left in file", EOFError),
             "cut.npz": ("not a zip archive: no end of central directory record", zipfile.BadZipFile),
             "crc.npz": ("bad CRC-32 for file 'beta.npy'", zipfile.BadZipFile),
             "one.npy": ("it holds one .npy array, not an .npz archive of arrays", TypeError),
             "f8be.npz": ("'X.npy' has dtype '>f8'; a field file holds '<f8' (little-endian float64)", None)}
    for name, (reason, python_raises) in cases.items():
        path = tmp_path / name
        rc, msg, _ = native_fields.read_initial_beta(path, X)
        assert (rc, msg) == (TC_ERROR, f"field_input = {str(path)!r} cannot be read as a field_output file: "
                                       f"{reason}"), name
        if python_raises is None:
            read_initial_beta(path, X)
        else:
            with pytest.raises(ParameterError, match="field_input = .* cannot be read as a field_output file"):
                read_initial_beta(path, X)


def test_format_g_is_pythons(native_fields):
    rng = np.random.default_rng(2)
    values = [0.0, -0.0, 1.0, 0.1, 1e-5, 1e-4, 123456.0, 1234567.0, 0.23, 5e-324, 1.7976931348623157e308, 1e16,
              -2.5e-7, 999999.5, 9.999995e-5, float("nan"), float("-nan"), float("inf"), float("-inf")]
    values += list(rng.integers(0, 2**64, 3000, dtype=np.uint64).view(np.float64))
    values += list(rng.normal(0, 1, 1000) * 10.0 ** rng.integers(-12, 12, 1000))
    for x in values:
        assert native_fields.format_g(float(x)) == format(float(x), "g"), repr(x)


# ---- robustness ------------------------------------------------------------------------------------------------


def test_allocation_failures_leak_nothing(checked_fields, python_field_file, tmp_path):
    f = checked_fields
    X = read_fields(python_field_file)["X"]
    model = FakeModel(X.size, np.random.default_rng(4))
    window = (0.1, 0.2)

    def attempt(action):
        """Fail the n-th allocation for n = 0, 1, ... until the action succeeds; each failure is TC_NOMEM."""
        for n in range(50):
            f.lib.tc_count_fail_after(n)
            rc = action()
            f.lib.tc_count_fail_after(-1)
            if rc == TC_OK:
                return n
            assert rc == TC_NOMEM and "memory" in f.message, f.message
        raise AssertionError("never succeeded")

    made = []

    def create():
        try:
            made.append(f.recorder(tmp_path / "f.npz", 0.0, X, window, "{}"))
            return TC_OK
        except ParameterError:
            assert f.lib.tc_count_live() == 0
            return TC_NOMEM if "memory" in f.message else TC_ERROR

    assert attempt(create) > 2
    rec = made[0]
    for k in range(16):  # the first block of rows
        assert rec.record(k * 1e-3, model.fields()) == TC_OK
    live = f.lib.tc_count_live()
    assert attempt(lambda: rec.record(0.016, model.fields())) > 3  # growing: four arrays
    assert rec.rows == 17 and rec.last_time == 0.016
    assert attempt(rec.write) == 2  # the temporary file's name and the write buffer
    assert f.lib.tc_count_live() == live
    rec.free()
    assert f.lib.tc_count_live() == 0
    assert attempt(lambda: f.read_initial_beta(python_field_file, X)[0]) >= 1
    assert f.lib.tc_count_live() == 0


def _mutants(raw: bytes, rng, n: int):
    """(kind, bytes, rezipped) variants of a field file: truncations, bit flips, byte overwrites (half of them
    in the zip and .npy headers), random bytes, and members rewritten with a valid CRC after a change to their
    .npy header or data (these reach the parsers and checks behind the CRC)."""
    with zipfile.ZipFile(io.BytesIO(raw)) as z:
        members = {i.filename: z.read(i) for i in z.infolist()}
        heads = [(i.header_offset, i.header_offset + 30 + len(i.filename) + 20 + 128) for i in z.infolist()]
    cd = raw.find(b"PK\x01\x02")
    heads.append((cd, len(raw)))
    interesting = [0x00, 0xFF, 0x7F, 0x80, 0x20, 0x27, 0x28, 0x29, 0x2C, 0x3A, 0x30, 0x31, 0x39, 0x3C, 0x3E, 0x66,
                   0x38, 0x34]

    def where():
        if rng.random() < 0.5:
            a, b = heads[int(rng.integers(0, len(heads)))]
            return int(rng.integers(a, max(min(b, len(raw)), a + 1)))
        return int(rng.integers(0, len(raw)))

    def rezip(name, data):
        buf = io.BytesIO()
        with zipfile.ZipFile(buf, "w", zipfile.ZIP_STORED) as z:
            for k, v in members.items():
                z.writestr(k, data if k == name else v)
        return buf.getvalue()

    for i in range(n):
        kind = ("truncate", "bitflip", "overwrite", "random", "npy-header", "npy-data")[i % 6]
        b = bytearray(raw)
        if kind == "truncate":
            if rng.random() < 0.5:
                yield kind, bytes(b[:max(where(), 0)]), False
            else:
                at = int(rng.integers(0, cd))
                yield kind, bytes(b[:at] + b[min(at + int(rng.integers(1, 300)), cd):]), False
        elif kind == "bitflip":
            for _ in range(int(rng.integers(1, 4))):
                b[min(where(), len(b) - 1)] ^= 1 << int(rng.integers(0, 8))
            yield kind, bytes(b), False
        elif kind == "overwrite":
            at = where()
            for k in range(int(rng.integers(1, 9))):
                if at + k < len(b):
                    b[at + k] = int(rng.choice(interesting)) if rng.random() < 0.5 else int(rng.integers(0, 256))
            yield kind, bytes(b), False
        elif kind == "random":
            junk = rng.integers(0, 256, int(rng.integers(0, 2000)), dtype=np.uint8).tobytes()
            choice = rng.random()
            yield kind, (b"PK\x03\x04" + junk if choice < 0.4 else junk + raw[-22:] if choice < 0.7 else junk), False
        else:
            name = ("X.npy", "beta.npy")[int(rng.integers(0, 2))]
            m = bytearray(members[name])
            start = m.index(b"\n") + 1
            for _ in range(int(rng.integers(1, 4))):
                if kind == "npy-header":
                    at = int(rng.integers(0, start))
                    flip = m[at] ^ (1 << int(rng.integers(0, 8)))
                    m[at] = int(rng.choice(interesting)) if rng.random() < 0.6 else flip
                else:
                    at = int(rng.integers(start, len(m)))
                    m[at] ^= 1 << int(rng.integers(0, 8))
            if rng.random() < 0.2:
                m = m[:int(rng.integers(0, len(m)))]
            yield kind, rezip(name, bytes(m)), True


def _fuzz_main(lib_path: str, workdir: str, per_file: int, seed: int, *bases: str) -> None:
    """Runs in a subprocess: prints a JSON summary; a crash kills only this process."""
    f = Fields(Path(lib_path), counting=True)
    rng = np.random.default_rng(seed)
    folder = Path("/dev/shm" if os.path.isdir("/dev/shm") and os.access("/dev/shm", os.W_OK) else workdir)
    path = folder / f"tc_fields_fuzz_{os.getpid()}.npz"
    print(f"variant file: {path} (kept if this process crashes)", file=sys.stderr, flush=True)
    summary = {"variants": 0, "c_ok": 0, "c_refused": 0, "violations": [], "python_only": {}, "python_raised": {}}
    for base in bases:
        raw = Path(base).read_bytes()
        X = read_fields(base)["X"]
        intact = read_initial_beta(base, X)
        for i, (kind, data, rezipped) in enumerate(_mutants(raw, rng, per_file)):
            path.write_bytes(data)
            print(f"{Path(base).name} #{i} {kind}", file=sys.stderr, flush=True)  # the last line names a crash
            rc, msg, beta = f.read_initial_beta(path, X)
            summary["variants"] += 1
            try:
                python, python_error = read_initial_beta(path, X), None
            except ParameterError as exc:
                python, python_error = None, str(exc)
            except Exception as exc:  # noqa: BLE001 - read_initial_beta lets zipfile's and numpy's errors through
                python, python_error = None, f"{type(exc).__name__}: {str(exc)[:80]}"
                summary["python_raised"][type(exc).__name__] = summary["python_raised"].get(type(exc).__name__, 0) + 1
            problems = []
            if f.lib.tc_count_live() != 0:
                problems.append(f"{f.lib.tc_count_live()} allocations leaked")
            if rc == TC_OK:
                summary["c_ok"] += 1
                if python is None:
                    problems.append(f"accepted, but read_initial_beta refuses: {python_error}")
                elif beta.tobytes() != python.tobytes():
                    problems.append("accepted with values other than read_initial_beta's")
                if not rezipped and beta.tobytes() != intact.tobytes():
                    problems.append("accepted a damaged file with changed values")
            else:
                summary["c_refused"] += 1
                if rc != TC_ERROR or not msg.startswith(f"field_input = {str(path)!r}"):
                    problems.append(f"status {rc}, message {msg!r}")
                if python is not None:
                    reason = msg.split(": ", 1)[-1][:90]
                    summary["python_only"][reason] = summary["python_only"].get(reason, 0) + 1
            if problems:
                bad = Path(workdir) / f"violation_{len(summary['violations'])}.npz"
                bad.write_bytes(data)
                summary["violations"].append(f"{Path(base).name} #{i} {kind} ({bad}): {'; '.join(problems)}")
    path.unlink(missing_ok=True)
    print(json.dumps(summary))


def test_fuzzed_files_are_refused_or_intact_never_crash_nor_leak(checked_build, checked_fields, fields_dir):
    per_file = 1500
    workdir = fields_dir / "fuzz"
    workdir.mkdir(exist_ok=True)
    rng = np.random.default_rng(1)
    bases = []
    for name, rows, nodes, f in (("c_plain.npz", 6, 31, None), ("c_zip64.npz", 4, 40, checked_fields)):
        arrays = (np.arange(rows) * 1e-3, np.linspace(0, 0.2, nodes), rng.random((rows, nodes)),
                  rng.random((rows, nodes)), rng.random((rows, nodes)), np.array([0.1, 0.2]))
        if f is None:  # the plain writer's layout, which np.savez shares
            write_fields(fields_dir / name, *arrays, {"a": 1})
        else:  # the checked build's ZIP64 central directory and end records
            assert f.write_fields(fields_dir / name, *arrays, '{"a": 1}')[0] == TC_OK
        bases.append(str(fields_dir / name))
    code = ("import importlib.util, sys; spec = importlib.util.spec_from_file_location('t', sys.argv[1]); "
            "m = importlib.util.module_from_spec(spec); spec.loader.exec_module(m); "
            "m._fuzz_main(sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5]), *sys.argv[6:])")
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", code, __file__, str(checked_build), str(workdir), str(per_file), "13",
                           *bases], capture_output=True, text=True, timeout=300)
    seconds = time.perf_counter() - t0
    lines = proc.stderr.strip().splitlines() or [""]
    assert proc.returncode == 0, (f"the fuzz run died (status {proc.returncode}); {lines[0]}; last variants: "
                                  f"{lines[-3:]}\n{proc.stderr[-1500:]}")
    summary = json.loads(proc.stdout.strip().splitlines()[-1])
    print(f"fuzz: {summary['variants']} variants in {seconds:.1f} s, {summary['c_ok']} read intact, "
          f"{summary['c_refused']} refused; read_initial_beta accepted {sum(summary['python_only'].values())} of the "
          f"refused ones: {summary['python_only']}; it raised other than ParameterError: {summary['python_raised']}")
    assert summary["variants"] == 2 * per_file
    assert summary["violations"] == []
    assert summary["c_refused"] > 0.5 * summary["variants"] and summary["c_ok"] > 0


# ---- other platforms -------------------------------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("platform", ["win64", "darwin64"])
def test_builds_clean_for_windows_and_macos(tmp_path, platform):
    suffix = toolchain.PLATFORMS[platform][1]
    out = toolchain.compile_shared([toolchain.SOURCE_DIR / s for s in SOURCES], tmp_path / f"tc_fields{suffix}",
                                   platform, defines=["TC_EXPORT_CORE"])
    assert out.stat().st_size > 0
