"""The native reader of the friction table file (tc_table_file.c with tc_npz, tc_json, tc_sha256) against
table.read_table, the format's owner: same values bit for bit, same hash, the same refusals with messages
that name the path; SHA-256 against hashlib; the lexical derivation of the hashed metadata text against
json.dumps; and a fuzz run (in a subprocess, so that a crash fails the test instead of killing pytest) on a
build that traps undefined behaviour and counts allocations.
"""

from __future__ import annotations

import ctypes
import hashlib
import io
import json
import os
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

from tribocosim.components.errors import TableError
from tribocosim.components.native import toolchain
from tribocosim.components.paths import DEFAULT_TABLE
from tribocosim.components.stripdraw.friction import closed_form_table
from tribocosim.components.stripdraw.table import AREAS, FrictionTable, read_table, write_table

SOURCES = ("tc_common.c", "tc_table.c", "tc_table_file.c", "tc_sha256.c", "tc_npz.c", "tc_json.c")
TC_OK, TC_ERROR, TC_NOMEM = 0, 2, 3
MSG_SIZE = 1024

# Test-only allocator shim for the fuzz build: every malloc/calloc/realloc/free of the C sources goes through
# these counters (forced include), so a leak shows as live allocations after a read, and the n-th
# allocation can be made to fail.



class _Table(ctypes.Structure):
    _fields_ = [("n_pressure", ctypes.c_size_t), ("n_velocity", ctypes.c_size_t), ("n_beta", ctypes.c_size_t),
                ("pressure", ctypes.POINTER(ctypes.c_double)), ("velocity", ctypes.POINTER(ctypes.c_double)),
                ("beta", ctypes.POINTER(ctypes.c_double)), ("mu", ctypes.POINTER(ctypes.c_double)),
                *[(a, ctypes.POINTER(ctypes.c_double)) for a in AREAS],
                ("beta_threshold", ctypes.c_double), ("format_version", ctypes.c_int),
                ("content_hash", ctypes.c_char * 65), ("provenance", ctypes.c_char * 32)]


class _Msg(ctypes.Structure):
    _fields_ = [("text", ctypes.c_char_p), ("size", ctypes.c_size_t)]


def _load(path: Path, counting: bool = False) -> ctypes.CDLL:
    lib = ctypes.CDLL(str(path))
    lib.tc_table_read.argtypes = [ctypes.c_char_p, ctypes.POINTER(ctypes.POINTER(_Table)), _Msg]
    lib.tc_table_free.argtypes = [ctypes.POINTER(_Table)]
    lib.tc_table_free.restype = None
    for name in ("tc_sha256_init", "tc_sha256_update", "tc_sha256_final", "tc_sha256_hex"):
        getattr(lib, name).restype = None
    lib.tc_sha256_update.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_size_t]
    lib.tc_json_hashed_text.argtypes = [ctypes.c_char_p, ctypes.c_size_t, ctypes.c_char_p, ctypes.c_char_p,
                                        ctypes.POINTER(ctypes.c_size_t), _Msg]
    lib.tc_json_check_object.argtypes = [ctypes.c_char_p, ctypes.c_size_t, _Msg]
    if counting:
        lib.tc_count_live.restype = ctypes.c_long
        lib.tc_count_fail_after.argtypes = [ctypes.c_long]
        lib.tc_count_fail_after.restype = None
    return lib


def _msg():
    buf = ctypes.create_string_buffer(MSG_SIZE)
    return buf, _Msg(ctypes.cast(buf, ctypes.c_char_p), MSG_SIZE)


def c_read(lib, path):
    """``(status, message, table)``: the table as a dict of copies (or None); the C table is freed."""
    buf, msg = _msg()
    ptr = ctypes.POINTER(_Table)()
    rc = lib.tc_table_read(os.fsencode(str(path)), ctypes.byref(ptr), msg)
    if rc != TC_OK:
        assert not ptr, "a refused read must leave the table NULL"
        return rc, buf.value.decode(errors="replace"), None
    t = ptr.contents
    sizes = {"pressure": t.n_pressure, "velocity": t.n_velocity, "beta": t.n_beta}
    out = {name: np.ctypeslib.as_array(getattr(t, name), (n,)).copy() for name, n in sizes.items()}
    shape = (t.n_pressure, t.n_velocity, t.n_beta)
    for name in ("mu", *(AREAS if t.format_version == 2 else ())):
        out[name] = np.ctypeslib.as_array(getattr(t, name), (int(np.prod(shape)),)).copy().reshape(shape)
    if t.format_version != 2:
        assert not any(getattr(t, a) for a in AREAS), "a version 1 table must leave the areas NULL"
    out.update(beta_threshold=t.beta_threshold, format_version=t.format_version,
               content_hash=t.content_hash.decode(), provenance=t.provenance.decode())
    lib.tc_table_free(ptr)
    return rc, buf.value.decode(), out


def same_as_python(c_table: dict, table: FrictionTable) -> list[str]:
    """What differs between the C reading and read_table's (bit for bit for the arrays)."""
    bad = [name for name in ("pressure", "velocity", "beta", *table.arrays())
           if name not in c_table or c_table[name].shape != getattr(table, name).shape
           or not np.array_equal(c_table[name].view(np.uint64), getattr(table, name).view(np.uint64))]
    if c_table["beta_threshold"] != table.beta_threshold:
        bad.append("beta_threshold")
    if c_table["provenance"] != table.provenance[:31]:
        bad.append("provenance")
    if c_table["content_hash"] != table.metadata["content_hash"] or c_table["format_version"] != table.version:
        bad.append("content_hash")
    return bad


# ---- fixtures --------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def table_file_dir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("native_table_file")


@pytest.fixture(scope="module")
def table_file_lib(table_file_dir):
    out = toolchain.compile_shared([toolchain.SOURCE_DIR / s for s in SOURCES], table_file_dir / "libtc_table_file.so",
                                   "linux64", defines=["TC_EXPORT_CORE"])
    return _load(out)


@pytest.fixture(scope="module")
def table_file_fuzz_lib(table_file_dir, native_checked_compile) -> Path:
    """The same sources with undefined behaviour trapping and the allocation-counting shim."""
    return native_checked_compile(SOURCES, table_file_dir, "libtc_fuzz.so")


@pytest.fixture(scope="module")
def closed_form_file(table_file_dir) -> Path:
    path = table_file_dir / "closed_form.npz"
    write_table(path, closed_form_table())
    return path


def _arrays(path) -> dict:
    with np.load(path) as data:
        return {k: data[k] for k in data.files}


def _rewrite(src, dst, change) -> Path:
    """``src``'s members, changed by ``change(arrays, meta)`` (in place), saved to ``dst`` with np.savez."""
    arrays = _arrays(src)
    meta = json.loads(str(arrays["metadata"]))
    change(arrays, meta)
    arrays["metadata"] = np.array(json.dumps(meta, sort_keys=True))
    np.savez(dst, **arrays)
    return Path(dst)


# ---- reading ---------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def version1_file(table_file_dir) -> Path:
    """A version 1 table (mu only): the closed form's, without its areas."""
    base = closed_form_table()
    path = table_file_dir / "version1.npz"
    write_table(path, FrictionTable(base.pressure, base.velocity, base.beta, base.mu, dict(base.metadata)))
    return path


@pytest.mark.parametrize("which", ["shipped", "closed_form", "version1"])
def test_reads_tables_exactly_as_read_table(table_file_lib, closed_form_file, version1_file, which):
    path = {"shipped": DEFAULT_TABLE, "closed_form": closed_form_file, "version1": version1_file}[which]
    rc, msg, table = c_read(table_file_lib, path)
    assert rc == TC_OK, msg
    reference = read_table(path)
    assert same_as_python(table, reference) == []
    assert table["content_hash"] == reference.content_hash()
    if which != "shipped":
        assert table["format_version"] == (1 if which == "version1" else 2)
    assert table["provenance"] == ("mesoscale" if which == "shipped" else "closed_form")


@pytest.mark.parametrize("key, value",
                         [("format_version", 2.0), ("beta_threshold", " 0.25 "), ("beta_threshold", True)])
def test_metadata_values_compare_like_python(table_file_lib, table_file_dir, closed_form_file, key, value):
    """read_table's ``format_version in (1, 2)`` takes 2.0 for 2, and ``float(beta_threshold)`` reads a numeric string
    or a bool: files so written (with their hash) are read by both readers alike."""
    arrays = _arrays(closed_form_file)
    meta = json.loads(str(arrays["metadata"]))
    meta.pop("content_hash")
    meta[key] = value
    meta["content_hash"] = FrictionTable(arrays["pressure"], arrays["velocity"], arrays["beta"], arrays["mu"],
                                         meta, **{a: arrays[a] for a in AREAS}).content_hash()
    arrays["metadata"] = np.array(json.dumps(meta, sort_keys=True))
    path = table_file_dir / f"{key}_{type(value).__name__}.npz"
    np.savez(path, **arrays)
    rc, msg, table = c_read(table_file_lib, path)
    assert rc == TC_OK, msg
    assert same_as_python(table, read_table(path)) == []


# ---- refusals --------------------------------------------------------------------------------------------


def _wrong_name(arrays, meta):
    meta["format"] = "other-table"


def _wrong_version(arrays, meta):
    meta["format_version"] = 3


def _area_missing(arrays, meta):
    del arrays["particle_area_std"]


def _area_wrong_shape(arrays, meta):
    arrays["contact_area"] = arrays["contact_area"][:, :, :-1].copy()


def _area_negative(arrays, meta):
    arrays["particle_area"] = arrays["particle_area"].copy()
    arrays["particle_area"][0, 1, 2] = -1e-300


def _modified_value(arrays, meta):
    arrays["mu"] = arrays["mu"].copy()
    arrays["mu"][1, 2, 3] = np.nextafter(arrays["mu"][1, 2, 3], 1.0)


def _modified_metadata(arrays, meta):
    meta["parameters"]["mu0"] = meta["parameters"]["mu0"] + 0.01


def _missing_member(arrays, meta):
    del arrays["beta"]


def _wrong_dtype(arrays, meta):
    arrays["mu"] = arrays["mu"].astype(np.float32)


def _wrong_shape(arrays, meta):
    arrays["mu"] = np.ascontiguousarray(arrays["mu"].transpose(1, 0, 2))


def _axis_not_1d(arrays, meta):
    arrays["beta"] = arrays["beta"].reshape(1, -1)


def _beta_threshold_missing(arrays, meta):
    del meta["beta_threshold"]


REFUSALS = {
    # name: (change, part of the message); read_table refuses each of them too
    "wrong format name": (_wrong_name, "has format 'other-table' version 1; this version reads "
                          "'tribocosim-friction-table' versions 1 and 2"),
    "wrong format version": (_wrong_version, "has format 'tribocosim-friction-table' version 3; this version "
                             "reads 'tribocosim-friction-table' versions 1 and 2"),
    "modified value": (_modified_value, "fails its content hash check (modified or corrupt)"),
    "modified metadata": (_modified_metadata, "fails its content hash check (modified or corrupt)"),
    "missing member": (_missing_member, "is malformed: there is no item named 'beta.npy' in the archive"),
    "wrong dtype": (_wrong_dtype, "is malformed: 'mu.npy' has dtype '<f4'; the table needs '<f8'"),
    "wrong shape": (_wrong_shape, "is malformed: table mu has shape (41, 13, 21); the axes need (13, 41, 21)"),
    "axis not 1-D": (_axis_not_1d, "is malformed: table axis beta must be a non-empty 1-D array, got shape (1, 21)"),
    "beta_threshold missing": (_beta_threshold_missing, "is malformed: table metadata beta_threshold = None; a value "
                               "in (0, 1] is required"),
}


VERSION2_REFUSALS = {
    "area missing": (_area_missing, "is malformed: there is no item named 'particle_area_std.npy' in the archive"),
    "area wrong shape": (_area_wrong_shape, "is malformed: table contact_area has shape (13, 41, 20); the axes "
                         "need (13, 41, 21)"),
    "area negative": (_area_negative, "is malformed: table particle_area must be finite and >= 0 everywhere"),
}


@pytest.mark.parametrize("case", [*REFUSALS, *VERSION2_REFUSALS])
def test_refuses_a_bad_table_naming_path_and_problem(table_file_lib, table_file_dir, closed_form_file, version1_file,
                                                     case):
    change, expected = REFUSALS.get(case) or VERSION2_REFUSALS[case]
    base = closed_form_file if case in VERSION2_REFUSALS else version1_file
    path = _rewrite(base, table_file_dir / f"bad_{case.replace(' ', '_')}.npz", change)
    rc, msg, _ = c_read(table_file_lib, path)
    assert rc == TC_ERROR
    assert msg.startswith(f"friction table {path} ") and expected in msg, msg
    with pytest.raises(TableError):
        read_table(path)


def test_refuses_missing_file_non_zip_and_compressed(table_file_lib, table_file_dir, closed_form_file):
    missing = table_file_dir / "no_such_table.npz"
    assert c_read(table_file_lib, missing)[:2] == (TC_ERROR, f"friction table file not found: {missing}")
    rc, msg, _ = c_read(table_file_lib, table_file_dir)  # a folder
    assert rc == TC_ERROR and msg.startswith(f"friction table file not found: {table_file_dir}"), msg

    text = table_file_dir / "not_a_zip.npz"
    text.write_text("pressure,velocity,beta,mu\n")
    rc, msg, _ = c_read(table_file_lib, text)
    assert rc == TC_ERROR and msg.startswith(f"friction table {text} is malformed: not a zip archive"), msg

    compressed = table_file_dir / "compressed.npz"
    np.savez_compressed(compressed, **_arrays(closed_form_file))
    rc, msg, _ = c_read(table_file_lib, compressed)
    assert rc == TC_ERROR and msg.startswith(f"friction table {compressed} is malformed: 'pressure.npy' is "
                                             "compressed (deflate"), msg
    assert "np.savez_compressed" in msg


def test_refuses_metadata_not_in_json_dumps_form(table_file_lib, table_file_dir, closed_form_file):
    """Metadata that json.loads reads but json.dumps would not write: refused by name, not by a hash mismatch."""
    arrays = _arrays(closed_form_file)
    arrays["metadata"] = np.array(str(arrays["metadata"]).replace('"closed_form"', '"closed\\u005fform"'))
    path = table_file_dir / "escaped.npz"
    np.savez(path, **arrays)
    rc, msg, _ = c_read(table_file_lib, path)
    assert rc == TC_ERROR
    assert msg.startswith(f"friction table {path} is malformed: its metadata JSON is not in the form write_table "
                          "writes (a \\u escape of a character json.dumps writes otherwise at character"), msg
    read_table(path)  # Python re-serialises the metadata and reads it: a difference documented in tc_json.h


@pytest.mark.parametrize("which", ["closed_form", "version1"])
def test_allocation_failures_leak_nothing(table_file_fuzz_lib, closed_form_file, version1_file, which):
    lib = _load(table_file_fuzz_lib, counting=True)
    path = closed_form_file if which == "closed_form" else version1_file
    statuses = []
    for n in range(100):
        lib.tc_count_fail_after(n)
        rc, msg, _ = c_read(lib, path)
        lib.tc_count_fail_after(-1)
        assert lib.tc_count_live() == 0, f"allocation {n} failing leaks"
        statuses.append(rc)
        if rc == TC_OK:
            break
        assert rc == TC_NOMEM and str(path) in msg and "memory" in msg, msg
    assert statuses[-1] == TC_OK and len(statuses) > 5


# ---- SHA-256 and the hashed metadata text ----------------------------------------------------------------


def _sha256(lib, chunks) -> tuple[bytes, str]:
    ctx = ctypes.create_string_buffer(256)
    lib.tc_sha256_init(ctx)
    for chunk in chunks:
        lib.tc_sha256_update(ctx, chunk, len(chunk))
    digest, hexbuf = ctypes.create_string_buffer(32), ctypes.create_string_buffer(65)
    lib.tc_sha256_final(ctx, digest)
    lib.tc_sha256_hex(digest, hexbuf)
    return digest.raw, hexbuf.value.decode()


def test_sha256_matches_hashlib(table_file_lib):
    rng = np.random.default_rng(7)
    lengths = [0, 1, 3, 55, 56, 57, 63, 64, 65, 119, 120, 121, 127, 128, 129, 1000, 4103,
               *rng.integers(0, 3000, 20)]
    for n in lengths:
        data = rng.integers(0, 256, int(n), dtype=np.uint8).tobytes()
        want = hashlib.sha256(data)
        assert _sha256(table_file_lib, [data]) == (want.digest(), want.hexdigest()), n
        cuts = np.sort(rng.integers(0, len(data) + 1, 4))
        chunks = [data[a:b] for a, b in zip([0, *cuts], [*cuts, len(data)])]
        assert _sha256(table_file_lib, chunks)[1] == want.hexdigest(), (n, cuts)


def c_hashed_text(lib, stored: str) -> tuple[int, str]:
    raw = bytes(ord(c) if ord(c) < 0x80 else 0x80 for c in stored)  # as tc_table_file narrows the UTF-32 text
    out = ctypes.create_string_buffer(max(len(raw), 1))
    out_n = ctypes.c_size_t()
    buf, msg = _msg()
    rc = lib.tc_json_hashed_text(raw, len(raw), b"content_hash", out, ctypes.byref(out_n), msg)
    return rc, out.raw[:out_n.value].decode() if rc == TC_OK else buf.value.decode()


def python_hashed_text(stored: str) -> str:
    meta = json.loads(stored)
    return json.dumps({k: v for k, v in meta.items() if k != "content_hash"}, sort_keys=True, separators=(",", ":"))


def _random_value(rng, depth=0):
    kind = int(rng.integers(0, 10 if depth < 3 else 7))
    if kind == 0:  # any finite double, from random bits
        while not np.isfinite(x := float(rng.integers(0, 2**63, dtype=np.int64).view(np.float64))):
            pass
        return -x if rng.random() < 0.5 else x
    if kind == 1:
        return float(rng.choice([0.0, -0.0, 0.1, 0.3, 1e16, 1e15, 123.0, 1e-4, 1e-5, 5e-324, 2.2250738585072014e-308,
                                 1.7976931348623157e308, 1e22, 1e23, 9007199254740993.0, 0.1 + 0.2, 2.0**-1074 * 3]))
    if kind == 2:
        return int(rng.choice([0, -1, 7, 2**53 + 1, -(2**70), 10**30]))
    if kind == 3:
        alphabet = list('ab z"\\/\n\t\b\f\r\x00\x1f\x7f~é\u2028\uffff😀') + ["\ud800"]
        return "".join(rng.choice(alphabet, int(rng.integers(0, 8))))
    if kind == 4:
        return [True, False, None][int(rng.integers(0, 3))]
    if kind == 5:
        return float(rng.choice([np.nan, np.inf, -np.inf]))
    if kind == 6:
        return float(rng.uniform(-1e6, 1e6)) * 10.0 ** int(rng.integers(-30, 30))
    if kind in (7, 8):  # dict with keys that sort differently by code point and by UTF-16 unit
        keys = ["a", "b", "B", "é", "\uffff", "😀", "content_hash", "a\u0000", "", "aa"]
        return {str(rng.choice(keys)): _random_value(rng, depth + 1) for _ in range(int(rng.integers(0, 5)))}
    return [_random_value(rng, depth + 1) for _ in range(int(rng.integers(0, 5)))]


def test_hashed_text_is_derived_lexically_as_json_dumps_writes_it(table_file_lib, closed_form_file):
    """The claim behind the native hash: for text json.dumps(sort_keys=True) wrote, dropping whitespace outside
    strings and the top-level content_hash gives the compact re-serialisation, without re-serialising numbers."""
    stored = [str(_arrays(p)["metadata"]) for p in (DEFAULT_TABLE, closed_form_file)]
    rng = np.random.default_rng(3)
    for _ in range(400):
        meta = {str(k): _random_value(rng) for k in rng.choice(["a", "content_hash", "z", "é", "x"], 3)}
        stored.append(json.dumps(meta, sort_keys=True))
    doubles = rng.integers(0, 2**64, 5000, dtype=np.uint64).view(np.float64)
    scaled = rng.normal(0, 1, 1000) * 10.0 ** rng.integers(-20, 20, 1000)
    stored.append(json.dumps({"doubles": [float(x) for x in doubles if np.isfinite(x)],
                              "floats": [float(x) for x in scaled]}))
    stored.append(json.dumps(json.loads(stored[1]), sort_keys=True, indent=2))  # any whitespace: the same text
    for text in stored:
        rc, got = c_hashed_text(table_file_lib, text)
        assert rc == TC_OK, (got, text[:200])
        assert got == python_hashed_text(text), text[:200]


@pytest.mark.parametrize("text, problem", [
    ('{"a": 1.50}', "repr(float)"), ('{"a": 1e16}', "repr(float)"), ('{"a": 1E+16}', "repr(float)"),
    ('{"a": 0.00001}', "repr(float)"), ('{"a": 0.10000000000000001}', "repr(float)"),
    ('{"a": 100000000000000000.0}', "repr(float)"), ('{"a": 1e400}', "repr(float)"), ('{"a": -0}', "-0"),
    ('{"b": 1, "a": 2}', "sorted"), ('{"a": 1, "a": 2}', "repeated"),
    ('{"\\uffff": 1, "\\ud83d\\ude00": 2, "\\ud800": 3}', "sorted"),  # code point order, not UTF-16 order
    ('{"a": "\\/"}', "slash"), ('{"a": "\\u0041"}', "\\u escape"), ('{"a": "\\u000a"}', "\\u escape"),
    ('{"a": "\\u00E9"}', "uppercase"), ('{"a": "\x7f"}', "DEL"), ('{"a": "é"}', "non-ASCII"),
])
def test_names_what_json_dumps_would_write_differently(table_file_lib, text, problem):
    json.loads(text)  # valid JSON that json.dumps(sort_keys=True) would not write so
    rc, message = c_hashed_text(table_file_lib, text)
    assert rc == TC_ERROR and problem in message, message


@pytest.mark.parametrize("text", [
    "", " ", "[]", "1", '"x"', '{"a": }', '{"a": 1,}', '{"a": 01}', '{"a": 1.}', '{"a": .5}', '{"a": "\x01"}',
    '{"a" 1}', '{"a": 1} x', '{"a": "\\x"}', '{"a": "\\u12"}', '{a: 1}', "{'a': 1}", '{"a": nan}', '{"a": -NaN}',
    '{"a": [1 2]}', '{"a": tru}', '{"a": NaN, "b": -Infinity, "c": [Infinity]}', '{"a": 1e5, "b": -0.0E-0}',
    ' \t\n{"a":\r[{}, [], ""]}\n', '{"a": "\\ud800\\udc00\\ud800"}', '{"a": 1' + "0" * 4301 + "}",
    "[" * 100 + "]" * 100, '{"a": ' + "[" * 126 + "]" * 126 + "}"])
def test_accepts_the_json_that_json_loads_accepts(table_file_lib, text):
    raw = text.encode()
    buf, msg = _msg()
    rc = table_file_lib.tc_json_check_object(raw, len(raw), msg)
    try:
        python_ok = isinstance(json.loads(text), dict)
    except ValueError:
        python_ok = False
    assert (rc == TC_OK) == python_ok, (text[:60], buf.value)


# ---- fuzz ------------------------------------------------------------------------------------------------


def _mutants(raw: bytes, rng, n: int):
    """``n`` (kind, bytes) variants of a table file: truncations, bit flips and byte overwrites (half of them in
    the zip and .npy headers), random files, and members rewritten with a valid CRC after a change to their
    .npy header or metadata text (these reach the parsers behind the CRC check)."""
    with zipfile.ZipFile(io.BytesIO(raw)) as z:
        members = {i.filename: z.read(i) for i in z.infolist()}
        heads = [(i.header_offset, i.header_offset + 30 + len(i.filename) + 20 + 128) for i in z.infolist()]
    cd = raw.find(b"PK\x01\x02")  # the central directory, to the end of the file
    heads.append((cd, len(raw)))
    interesting = [0x00, 0xFF, 0x7F, 0x80, 0x20, 0x22, 0x5C, 0x2C, 0x3A, 0x7B, 0x7D, 0x5B, 0x5D, 0x2E, 0x65, 0x2D,
                   0x30, 0x39, 0x27, 0x28, 0x29]

    def where():
        if rng.random() < 0.5:
            a, b = heads[int(rng.integers(0, len(heads)))]
            return int(rng.integers(max(a, 0), max(min(b, len(raw)), a + 1)))
        return int(rng.integers(0, len(raw)))

    def rezip(name, data):
        buf = io.BytesIO()
        with zipfile.ZipFile(buf, "w", zipfile.ZIP_STORED) as z:
            for k, v in members.items():
                z.writestr(k, data if k == name else v)
        return buf.getvalue()

    for i in range(n):
        kind = ("truncate", "bitflip", "overwrite", "random", "npy-header", "metadata-text")[i % 6]
        b = bytearray(raw)
        if kind == "truncate":
            if rng.random() < 0.5:  # the end is lost
                cut = where() if rng.random() < 0.7 else len(raw) - int(rng.integers(1, 200))
                yield kind, bytes(b[:max(cut, 0)])
            else:  # bytes go missing before the central directory: its offsets now point astray
                at = int(rng.integers(0, cd))
                yield kind, bytes(b[:at] + b[min(at + int(rng.integers(1, 300)), cd):])
        elif kind == "bitflip":
            for _ in range(int(rng.integers(1, 4))):
                b[min(where(), len(b) - 1)] ^= 1 << int(rng.integers(0, 8))
            yield kind, bytes(b)
        elif kind == "overwrite":
            at = where()
            for k in range(int(rng.integers(1, 9))):
                if at + k < len(b):
                    b[at + k] = int(rng.choice(interesting)) if rng.random() < 0.5 else int(rng.integers(0, 256))
            yield kind, bytes(b)
        elif kind == "random":
            junk = rng.integers(0, 256, int(rng.integers(0, 3000)), dtype=np.uint8).tobytes()
            choice = rng.random()
            yield kind, (b"PK\x03\x04" + junk if choice < 0.4 else junk + raw[-22:] if choice < 0.7 else junk)
        elif kind == "npy-header":
            name = list(members)[int(rng.integers(0, len(members)))]
            m = bytearray(members[name])
            for _ in range(int(rng.integers(1, 4))):
                at = int(rng.integers(0, min(len(m), 140)))
                m[at] = int(rng.choice(interesting)) if rng.random() < 0.5 else m[at] ^ (1 << int(rng.integers(0, 8)))
            if rng.random() < 0.2:
                m = m[:int(rng.integers(0, len(m)))]
            yield kind, rezip(name, bytes(m))
        else:
            m = bytearray(members["metadata.npy"])
            start = m.index(b"\n") + 1  # the header ends with a newline; UTF-32LE code units follow
            units = (len(m) - start) // 4
            for _ in range(int(rng.integers(1, 3))):
                at = start + 4 * int(rng.integers(0, units))
                choice = rng.random()
                if choice < 0.6:
                    m[at:at + 4] = int(rng.choice(interesting + [0x61, 0x75, 0x4E, 0x49, 0x09])).to_bytes(4, "little")
                elif choice < 0.8:
                    del m[at:at + 4]
                    m += b"\0\0\0\0"  # keep the item size: numpy strips trailing NULs
                else:
                    m[at:at + 4] = int(rng.integers(0, 0x110000)).to_bytes(4, "little")
            yield kind, rezip("metadata.npy", bytes(m))


def _fuzz_main(lib_path: str, workdir: str, per_file: int, seed: int, *bases: str) -> None:
    """Runs in a subprocess: prints a JSON summary; any crash kills only this process."""
    lib = _load(Path(lib_path), counting=True)
    rng = np.random.default_rng(seed)
    # the variant file lives in memory where there is a tmpfs: thousands of writes to disk would dominate
    path = Path("/dev/shm" if os.path.isdir("/dev/shm") and os.access("/dev/shm", os.W_OK) else workdir)
    path = path / f"tc_fuzz_{os.getpid()}.npz"
    print(f"variant file: {path} (kept if this process crashes)", file=sys.stderr, flush=True)
    summary = {"variants": 0, "c_ok": 0, "c_refused": 0, "violations": [], "python_only": {}, "python_raised": {}}
    for base in bases:
        raw = Path(base).read_bytes()
        reference = read_table(base)
        for i, (kind, data) in enumerate(_mutants(raw, rng, per_file)):
            path.write_bytes(data)
            print(f"{Path(base).name} #{i} {kind}", file=sys.stderr, flush=True)  # the last line names a crash
            rc, msg, table = c_read(lib, path)
            summary["variants"] += 1
            try:
                python = read_table(path)
                python_error = None
            except TableError as exc:
                python, python_error = None, str(exc)
            except Exception as exc:  # noqa: BLE001 - read_table lets some errors through; count them
                python, python_error = None, f"{type(exc).__name__}: {str(exc)[:80]}"
                summary["python_raised"].setdefault(type(exc).__name__, []).append(python_error)
            problems = []
            if lib.tc_count_live() != 0:
                problems.append(f"{lib.tc_count_live()} allocations leaked")
            if rc == TC_OK:
                summary["c_ok"] += 1
                if same_as_python(table, reference):
                    problems.append(f"accepted with changed content: {same_as_python(table, reference)}")
                if python is None:
                    problems.append(f"accepted, but read_table refuses: {python_error}")
            else:
                summary["c_refused"] += 1
                if rc != TC_ERROR or not msg.startswith("friction table ") or str(path) not in msg:
                    problems.append(f"status {rc}, message {msg!r}")
                if python is not None:  # read_table accepts what C refuses: tally by the C message's reason
                    reason = msg.split(": ", 1)[-1].split(" at character")[0][:90]
                    summary["python_only"][reason] = summary["python_only"].get(reason, 0) + 1
            if problems:
                bad = Path(workdir) / f"violation_{len(summary['violations'])}.npz"
                bad.write_bytes(data)
                summary["violations"].append(f"{Path(base).name} #{i} {kind} ({bad}): {'; '.join(problems)}")
    path.unlink(missing_ok=True)
    summary["python_raised"] = {k: (len(v), v[:3]) for k, v in summary["python_raised"].items()}
    print(json.dumps(summary))


def test_fuzzed_files_are_refused_or_intact_never_crash_nor_leak(table_file_fuzz_lib, table_file_dir, closed_form_file,
                                                                 version1_file):
    per_file = 900
    workdir = table_file_dir / "fuzz"
    workdir.mkdir(exist_ok=True)
    code = ("import importlib.util, sys; spec = importlib.util.spec_from_file_location('t', sys.argv[1]); "
            "m = importlib.util.module_from_spec(spec); spec.loader.exec_module(m); "
            "m._fuzz_main(sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5]), *sys.argv[6:])")
    t0 = time.perf_counter()
    args = [str(table_file_fuzz_lib), str(workdir), str(per_file), "11", str(closed_form_file), str(version1_file),
            str(DEFAULT_TABLE)]
    proc = subprocess.run([sys.executable, "-c", code, __file__, *args], capture_output=True, text=True, timeout=300)
    seconds = time.perf_counter() - t0
    lines = proc.stderr.strip().splitlines() or [""]
    assert proc.returncode == 0, (f"the fuzz run died (status {proc.returncode}); {lines[0]}; last variants: "
                                  f"{lines[-3:]}\n{proc.stderr[-1500:]}")
    summary = json.loads(proc.stdout.strip().splitlines()[-1])
    print(f"fuzz: {summary['variants']} variants in {seconds:.1f} s, {summary['c_ok']} read intact, "
          f"{summary['c_refused']} refused; read_table accepted {sum(summary['python_only'].values())} of the "
          f"refused ones: {summary['python_only']}; read_table raised non-TableError: {summary['python_raised']}")
    assert summary["variants"] == 3 * per_file
    assert summary["violations"] == []
    assert summary["c_refused"] > 0.5 * summary["variants"]


# ---- other platforms -------------------------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("platform", ["win64", "darwin64"])
def test_builds_clean_for_windows_and_macos(tmp_path, platform):
    suffix = toolchain.PLATFORMS[platform][1]
    out = toolchain.compile_shared([toolchain.SOURCE_DIR / s for s in SOURCES], tmp_path / f"tc_table_file{suffix}",
                                   platform, defines=["TC_EXPORT_CORE"])
    assert out.stat().st_size > 0
