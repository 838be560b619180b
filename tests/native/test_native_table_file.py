"""The friction table's resource form: the array file (components/native/resource_io/array_file.py, tc_arrays.c) and the table
reader on it (tc_table_file.c).

The resource written from a table file reads back into the same table: every lookup of the strip-draw law on the
resource equals the lookup on the table made from the .npz's arrays, bit for bit (the same C code on the same
numbers). Entries the reader does not know are skipped (the format grows without a change to the reader); bad
files are refused naming the path and the problem; allocation failures leak nothing; fuzzed files are refused or
read, never crash.
"""

from __future__ import annotations

import ctypes
import subprocess
import sys

import numpy as np
import pytest

from tribocosim.errors import ParameterError
from tribocosim.components.native.resource_io import array_file as arrays
from tribocosim.components.native.toolchain import compiler
from tribocosim.components.native.toolchain.library import VP, core, ptr
from tribocosim.paths import DEFAULT_TABLE
from tribocosim.components.stripdraw.friction import closed_form_table, make_friction_law
from tribocosim.components.stripdraw.parameters import StripDrawParameters
from tribocosim.components.stripdraw.table import read_table, resource_entries, write_table, write_table_resource

SOURCES = ("core/tc_common.c", "core/tc_table.c", "core/tc_table_lookup.c", "core/tc_pchip.c",
           "resource_io/tc_table_file.c", "resource_io/tc_sha256.c", "resource_io/tc_arrays.c")


def read_resource(path):
    """tc_table_read: a handle, or ParameterError with the C message."""
    c = core()
    handle = VP()
    c.call(c.lib.tc_table_read, str(path).encode(), ctypes.byref(handle))
    return handle


def law_mu(handle, params: StripDrawParameters, grid) -> np.ndarray:
    """tc_law_mu of the strip-draw law on the native table ``handle`` at every (P, v, beta) of grid."""
    c = core()
    struct = c.struct(params)
    p, v, b = grid
    out = np.empty(v.size)
    for pk in np.unique(p):
        at = np.flatnonzero(p == pk)
        vq, bq = np.ascontiguousarray(v[at]), np.ascontiguousarray(b[at])
        o, work = np.empty(vq.size), np.empty(vq.size)
        c.call(c.lib.tc_law_mu, ctypes.byref(struct), handle, float(pk), vq.size, ptr(vq), ptr(bq), ptr(o), None,
               ptr(work), None)
        out[at] = o
    return out


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("tables")


def _version4_table():
    """A version 4 table on the shipped axes with the shipped areas and a staircase of unsimulated nodes."""
    from tribocosim.components.stripdraw.table import FrictionTable

    t = read_table(DEFAULT_TABLE)
    extras = {name: t.array(name) for name in ("simulated", "contact_area_se", "particle_area_se",
                                               "particle_area_clusters", "particle_area_clusters_se")}
    extras["mu_se"] = np.zeros_like(t.mu)
    return FrictionTable(t.pressure, t.velocity, t.beta, t.mu, t.metadata, contact_area=t.contact_area,
                         particle_area=t.particle_area, contact_area_std=t.contact_area_std,
                         particle_area_std=t.particle_area_std, extras=extras)


@pytest.mark.parametrize("which", ["shipped", "version4", "closed_form", "version1"])
def test_the_resource_reads_back_as_the_table(folder, which):
    if which == "shipped":
        source = DEFAULT_TABLE
    elif which == "version4":
        source = folder / "version4.npz"
        write_table(source, _version4_table())
    else:
        t = closed_form_table()
        if which == "version1":
            t = type(t)(t.pressure, t.velocity, t.beta, t.mu, t.metadata)
        source = folder / f"{which}.npz"
        write_table(source, t)
    table = read_table(source)
    res = write_table_resource(source, folder / f"{which}.tca")
    handle = read_resource(res)
    try:
        rng = np.random.default_rng(3)
        n = 400
        grid = (np.repeat(rng.choice(table.pressure, 4), n // 4) * rng.uniform(0.8, 1.3),
                rng.uniform(0, 1.2 * table.velocity[-1], n), rng.uniform(0, 1.1 * table.beta[-1], n))
        # flake-borne shear where the table has the areas (the default r); a version 1 table holds mu of the paper's
        # frictionless flakes and serves r = 0 alone
        params = StripDrawParameters(**({} if table.version >= 2 else {"flake_shear_ratio": 0.0}))
        lost = 1.0 - params.flake_shear_ratio  # mu = mu0 (1 - (1 - r) A_p / A_c)
        law = make_friction_law(params, table)
        ours = law_mu(handle, params, grid)
        assert np.array_equal(ours, law_mu(law.native_table, params, grid)), "the resource is the .npz's table"
        if table.version >= 4:  # the law interpolates the share A_p / A_c
            share = np.where(table.contact_area > 0, table.particle_area / np.where(table.contact_area > 0,
                                                                                   table.contact_area, 1.0), 0.0)
            ref = np.array([params.mu0 * max(0.0, 1.0 - lost * table.interpolate_array(share, *q)[0])
                            for q in zip(*grid)])
        elif table.version >= 2:  # an oracle in NumPy: mu0 (1 - A_p / A_c) of FrictionTable.interpolate_array
            ap = np.concatenate([table.interpolate_array(table.particle_area, pk, grid[1][grid[0] == pk],
                                                         grid[2][grid[0] == pk])[0] for pk in np.unique(grid[0])])
            ac = np.concatenate([table.interpolate_array(table.contact_area, pk, grid[1][grid[0] == pk],
                                                         grid[2][grid[0] == pk])[0] for pk in np.unique(grid[0])])
            order = np.concatenate([np.flatnonzero(grid[0] == pk) for pk in np.unique(grid[0])])
            ref = np.empty(ours.size)
            ref[order] = params.mu0 * np.maximum(0.0, 1.0 - lost * ap / ac)
        else:
            ref, _ = table.interpolate(grid[0], grid[1], grid[2])
        np.testing.assert_allclose(ours, ref, rtol=1e-12, atol=1e-15, err_msg="against NumPy's lookup")
    finally:
        core().lib.tc_table_free(handle)


def test_an_npz_name_reads_its_resource_beside_it(folder):
    write_table(folder / "named.npz", closed_form_table())
    with pytest.raises(ParameterError, match=r"named\.npz: the native model reads its resource form .*named\.tca"):
        read_resource(folder / "named.npz")
    write_table_resource(folder / "named.npz")
    core().lib.tc_table_free(read_resource(folder / "named.npz"))


def test_a_table_replaced_after_its_resource_was_written_is_refused(folder):
    """X.tca records the SHA-256 of the X.npz it was made from: another table saved as X.npz is refused (naming both
    files and the command that rewrites the resource), not served from the old resource; the rewritten resource is
    read again, and a resource without the record is refused while its .npz is there."""
    import hashlib
    import shutil

    shutil.copy(DEFAULT_TABLE, folder / "swapped.npz")
    write_table_resource(folder / "swapped.npz")
    recorded = arrays.read_arrays(folder / "swapped.tca")["source_sha256"]
    assert recorded == hashlib.sha256((folder / "swapped.npz").read_bytes()).hexdigest()
    core().lib.tc_table_free(read_resource(folder / "swapped.npz"))
    write_table(folder / "swapped.npz", closed_form_table())  # another table under the same name
    with pytest.raises(ParameterError, match=r"swapped\.npz has changed since its resource form .*swapped\.tca was "
                                             r"written.*tribocosim fmu table-resource .*swapped\.npz"):
        read_resource(folder / "swapped.npz")
    core().lib.tc_table_free(read_resource(folder / "swapped.tca"))  # the resource named as itself is not compared
    write_table_resource(folder / "swapped.npz")
    core().lib.tc_table_free(read_resource(folder / "swapped.npz"))
    entries = arrays.read_arrays(folder / "swapped.tca")
    del entries["source_sha256"]
    arrays.write_arrays(folder / "swapped.tca", entries)
    with pytest.raises(ParameterError, match=r"does not record which table it was made from"):
        read_resource(folder / "swapped.npz")


@pytest.mark.parametrize("size", [0, 3, 55, 56, 64, 119, 1000, 70000])
def test_the_native_sha256_is_hashlibs(folder, size):
    import hashlib

    data = np.random.default_rng(size).integers(0, 256, size, dtype=np.uint8).tobytes()
    (folder / "bytes.bin").write_bytes(data)
    hexd = ctypes.create_string_buffer(65)
    core().call(core().lib.tc_sha256_file, str(folder / "bytes.bin").encode(), hexd)
    assert hexd.value.decode() == hashlib.sha256(data).hexdigest()


def test_the_command_line_writes_the_resource(folder):
    write_table(folder / "cli.npz", closed_form_table())
    proc = subprocess.run([sys.executable, "-m", "tribocosim.cli", "fmu", "table-resource", str(folder / "cli.npz")],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0 and proc.stdout.strip() == str((folder / "cli.tca").resolve()), proc.stderr
    core().lib.tc_table_free(read_resource(folder / "cli.npz"))
    (folder / "broken.npz").write_bytes(b"not a table")
    proc = subprocess.run([sys.executable, "-m", "tribocosim.cli", "fmu", "table-resource",
                           str(folder / "broken.npz")], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 1 and "broken.npz is not a friction table: a text file" in proc.stderr
    assert not (folder / "broken.tca").exists()


def test_unknown_entries_are_skipped(folder):
    """A table resource may gain arrays the native model does not read (another observable, a per-(P, v) array)."""
    entries = resource_entries(read_table(DEFAULT_TABLE))
    t = read_table(DEFAULT_TABLE)
    entries = {"largest_simulated_beta": np.ones((t.pressure.size, t.velocity.size)), **entries,
               "particle_area_wide": t.particle_area * 0.99, "note": "a text entry"}
    arrays.write_arrays(folder / "grown.tca", entries)
    core().lib.tc_table_free(read_resource(folder / "grown.tca"))


def test_a_resource_without_its_format_version_reads_as_the_version_of_its_arrays(folder):
    """A resource written before version 4 (no format_version entry) reads as before: multilinear, its version that
    of its arrays; the same arrays saying version 4 read monotone cubic."""
    entries = resource_entries(_version4_table())
    old = {k: v for k, v in entries.items() if k not in ("format_version", "mu_se")}
    arrays.write_arrays(folder / "old.tca", old)
    arrays.write_arrays(folder / "new.tca", entries)
    params = StripDrawParameters()
    grid = (np.full(50, 7e6), np.full(50, 0.08), np.linspace(0.0, 0.3, 50))
    handles = [read_resource(folder / name) for name in ("old.tca", "new.tca")]
    try:
        mu_old, mu_new = (law_mu(h, params, grid) for h in handles)
    finally:
        for h in handles:
            core().lib.tc_table_free(h)
    assert not np.allclose(mu_old, mu_new, rtol=1e-6), "the two versions interpolate differently"
    resource = _version4_table()
    t3 = type(resource)(resource.pressure, resource.velocity, resource.beta, resource.mu, resource.metadata,
                        contact_area=resource.contact_area, particle_area=resource.particle_area,
                        contact_area_std=resource.contact_area_std, particle_area_std=resource.particle_area_std,
                        extras={k: v for k, v in resource.extras.items() if k != "mu_se"})
    assert np.array_equal(mu_old, make_friction_law(params, t3).mu(*grid)[0])
    assert np.array_equal(mu_new, make_friction_law(params, resource).mu(*grid)[0])


def _variants(entries):
    """(label, entries or raw bytes, the message expected)."""
    good = arrays.encode(entries)
    yield "no mu", {k: v for k, v in entries.items() if k != "mu"}, "no array 'mu'"
    yield "no threshold", {k: v for k, v in entries.items() if k != "beta_threshold"}, "no scalar 'beta_threshold'"
    yield "3 areas", {k: v for k, v in entries.items() if k != "particle_area_std"}, "3 of the 4 area arrays"
    yield "half of version 3", {**{k: v for k, v in entries.items() if k != "particle_area_clusters"},
                                "simulated": np.ones_like(entries["mu"])}, "version 3 needs simulated"
    yield "simulated not 0 or 1", {**entries, "simulated": np.full_like(entries["mu"], 0.5),
                                   "particle_area_clusters": np.zeros_like(entries["mu"])}, "simulated must be 0 or 1"
    yield "mu shape", {**entries, "mu": entries["mu"][:, :, :-1]}, "no array 'mu' of shape"
    yield "axis order", {**entries, "beta": entries["beta"][::-1].copy()}, "strictly increasing"
    yield "negative mu", {**entries, "mu": -entries["mu"]}, "finite and >= 0"
    yield "threshold", {**entries, "beta_threshold": 1.5}, r"beta_threshold = 1\.5"
    yield "newer version", {**entries, "format_version": 5.0}, "format version 5; this reader takes versions 1 to 4"
    version2 = {k: v for k, v in entries.items() if k not in ("simulated", "particle_area_clusters")}
    yield "version of other arrays", version2, "says format version 4 and holds the arrays of version 2"
    yield "magic", b"TCARRAYX" + good[8:], "not an array file"
    yield "version", good[:8] + (2).to_bytes(4, "little") + good[12:], "format version 2"
    yield "truncated", good[:-9], "truncated"
    yield "empty", b"", "not an array file"


@pytest.mark.parametrize("case", range(13))
def test_a_bad_resource_is_refused_naming_path_and_problem(folder, case):
    entries = resource_entries(_version4_table())
    label, content, message = list(_variants(entries))[case]
    path = folder / f"bad{case}.tca"
    path.write_bytes(content if isinstance(content, bytes) else arrays.encode(content))
    with pytest.raises(ParameterError, match=message) as exc:
        read_resource(path)
    assert str(path) in str(exc.value), label
    with pytest.raises(ParameterError, match="file not found"):
        read_resource(folder / "missing.tca")


def test_python_reads_what_it_writes(folder):
    entries = {"a": np.arange(6.0).reshape(2, 3), "s": 2.5, "t": "text \u00e9", "e": np.zeros((0, 4))}
    back = arrays.read_arrays(arrays.write_arrays(folder / "rt.tca", entries))
    assert back["t"] == entries["t"] and back["s"].shape == () and float(back["s"]) == 2.5
    assert np.array_equal(back["a"], entries["a"]) and back["e"].shape == (0, 4)


@pytest.fixture(scope="module")
def checked(folder, native_checked_compile, native_headers):
    lib = ctypes.CDLL(str(native_checked_compile(SOURCES, folder, "libtc_tablefile.so", include_dirs=[native_headers])))
    lib.tc_count_live.restype = ctypes.c_long
    lib.tc_count_fail_after.argtypes = [ctypes.c_long]
    return lib


def test_allocation_failures_leak_nothing(folder, checked):
    path = write_table_resource(DEFAULT_TABLE, folder / "leak.tca")
    buf = ctypes.create_string_buffer(512)

    class Msg(ctypes.Structure):
        _fields_ = [("text", ctypes.c_void_p), ("size", ctypes.c_size_t)]

    for n in range(60):
        checked.tc_count_fail_after(n)
        handle = VP()
        status = checked.tc_table_read(str(path).encode(), ctypes.byref(handle), Msg(ctypes.addressof(buf), 512))
        checked.tc_count_fail_after(-1)
        if status == 0:
            checked.tc_table_free(handle)
        assert checked.tc_count_live() == 0, f"allocation {n} failing leaks"
        if status == 0:
            break
    else:
        pytest.fail("never read the table")


_FUZZ = """
import ctypes, sys, numpy as np
lib = ctypes.CDLL(sys.argv[1])
class Msg(ctypes.Structure):
    _fields_ = [("text", ctypes.c_void_p), ("size", ctypes.c_size_t)]
lib.tc_count_live.restype = ctypes.c_long
good = open(sys.argv[2], "rb").read()
rng = np.random.default_rng(7)
buf = ctypes.create_string_buffer(512)
ok = refused = 0
for k in range(int(sys.argv[4])):
    b = bytearray(good)
    if k % 3 == 0:
        b = b[:int(rng.integers(0, len(b)))]
    else:
        for _ in range(int(rng.integers(1, 6))):
            b[int(rng.integers(0, min(len(b), 600)))] = int(rng.integers(0, 256))
    open(sys.argv[3], "wb").write(bytes(b))
    h = ctypes.c_void_p()
    if lib.tc_table_read(sys.argv[3].encode(), ctypes.byref(h), Msg(ctypes.addressof(buf), 512)) == 0:
        ok += 1
        lib.tc_table_free(h)
    else:
        refused += 1
    assert lib.tc_count_live() == 0
print(ok, refused)
"""


def test_fuzzed_resources_are_refused_or_read_never_crash(folder, checked):
    path = write_table_resource(DEFAULT_TABLE, folder / "fuzz.tca")
    proc = subprocess.run([sys.executable, "-c", _FUZZ, checked._name, str(path), str(folder / "fuzzed.tca"), "600"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    ok, refused = map(int, proc.stdout.split())
    assert refused > 100 and ok + refused == 600


@pytest.mark.slow
@pytest.mark.parametrize("platform", ["win64", "darwin64"])
def test_builds_clean_for_windows_and_macos(tmp_path, platform, native_headers):
    suffix = compiler.PLATFORMS[platform][1]
    out = compiler.compile_shared(list(map(compiler.source, SOURCES)), tmp_path / f"tc_table{suffix}",
                                   platform, defines=["TC_EXPORT_CORE"], include_dirs=[native_headers])
    assert out.stat().st_size > 0
