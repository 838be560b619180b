"""The native FMUs' binaries for every platform (compiler.PLATFORMS): what each is built for and what it exports,
read from the files, and the aarch64-linux one run under qemu-user against the x86_64 one.

- FMI 2.0: linux64 and win64 x86_64, darwin64 a universal Mach-O with an x86_64 and an arm64 slice (Intel and
  Apple Silicon Macs; FMI 2.0 has one macOS folder), each slice exporting every fmi2 function; FMI 2.0 names no
  folder for ARM Linux, so an FMI 2.0 FMU has none;
- FMI 3.0: one thin binary per platform tuple (x86_64-linux, x86_64-windows, x86_64-darwin, aarch64-linux,
  aarch64-darwin), each of its architecture and exporting every fmi3 function;
- the aarch64-linux binary, run by an aarch64 build of the C host (tests/native/host/fmi3_host.c) under
  qemu-aarch64 (Debian's qemu-user, the aarch64 glibc from libc6-arm64-cross), draws the strip as the x86_64
  binary does: the same outputs and nodal fields, to the last bit or within 1e-12 relative (libm may round an
  exp or pow differently on the two CPUs; -ffp-contract=off keeps the arithmetic itself identical);
- the win64 DLL, run by a Windows host (tests/native/host/fmi2_host_windows.c) under wine (Debian's wine64), draws as
  the linux64 library does (within 1e-12 relative), and a build of it with the SSE2 step kernels only
  (-DTC_NO_AVX) gives the same bits as the shipped one, which chooses the AVX kernels on a processor with AVX.

The cross-builds take minutes the first time (zig builds each C library once): slow, run by .ci/run.
"""

from __future__ import annotations

import importlib.util
import re
import shutil
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tribocosim.components.native.toolchain import compiler

HERE = Path(__file__).resolve().parent
NAMES = ("DrawingMachine", "Press", "StripDraw")
#: the aarch64 glibc (and its loader) qemu-aarch64 runs a dynamically linked aarch64 program with
AARCH64_SYSROOT = Path("/usr/aarch64-linux-gnu")


def _exports():
    spec = importlib.util.spec_from_file_location("native_exports", HERE / "exports.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _functions(version: int) -> set[str]:
    """Every function of the FMI standard, from the header fmpy ships."""
    from tribocosim.components.fmus.native_build import fmi2_headers

    text = (fmi2_headers() / f"fmi{version}Functions.h").read_text()
    return set(re.findall(rf"#define (fmi{version}\w+)\s+fmi{version}FullName\(", text))


def _macho(cputype: int, size: int) -> bytes:
    """A minimal 64-bit Mach-O header of a CPU type, padded (the slices write_universal joins)."""
    return struct.pack("<Iii", 0xFEEDFACF, cputype, 3) + bytes(size - 12)


def test_write_universal_joins_slices_as_lipo_does(tmp_path):
    """The fat header: magic, count, per slice its CPU type and subtype copied from the slice, offset aligned to
    2**14, size; the slices' bytes unchanged; two slices of one CPU type refused."""
    ex = _exports()
    x86, arm = tmp_path / "x86", tmp_path / "arm"
    x86.write_bytes(_macho(0x01000007, 5000))
    arm.write_bytes(_macho(0x0100000C, 70000))
    out = compiler.write_universal([x86, arm], tmp_path / "fat.dylib")
    data = out.read_bytes()
    assert struct.unpack_from(">II", data, 0) == (0xCAFEBABE, 2)
    arches = [struct.unpack_from(">iiIII", data, 8 + 20 * k) for k in range(2)]
    assert [(a[0], a[1], a[4]) for a in arches] == [(0x01000007, 3, 14), (0x0100000C, 3, 14)]
    assert all(a[2] % 16384 == 0 for a in arches) and arches[1][2] >= arches[0][2] + arches[0][3]
    assert [part for _, part in ex.fat_slices(data)] == [x86.read_bytes(), arm.read_bytes()]
    assert ex.architectures(out) == ["x86_64", "arm64"]
    with pytest.raises(compiler.CompileError, match="same CPU type"):
        compiler.write_universal([x86, x86], tmp_path / "bad.dylib")
    with pytest.raises(compiler.CompileError, match="not a 64-bit little-endian Mach-O"):
        compiler.write_universal([tmp_path / "fat.dylib"], tmp_path / "bad.dylib")


@pytest.fixture(scope="module")
def every_platform(tmp_path_factory) -> dict[int, Path]:
    """``tribocosim fmu build`` for every platform, FMI 2.0 and FMI 3.0: ``{version: folder of the FMUs}``."""
    out = {}
    for version in (2, 3):
        folder = tmp_path_factory.mktemp(f"all{version}")
        proc = subprocess.run([sys.executable, "-m", "tribocosim.cli", "fmu", "build", "--fmi", str(version), "--out",
                               str(folder)], capture_output=True, text=True, timeout=3600)
        assert proc.returncode == 0, proc.stdout + proc.stderr
        out[version] = folder
    return out


EXPECTED = {
    2: {"linux64": ["x86_64"], "win64": ["x86_64"], "darwin64": ["x86_64", "arm64"]},
    3: {"x86_64-linux": ["x86_64"], "x86_64-windows": ["x86_64"], "x86_64-darwin": ["x86_64"],
        "aarch64-linux": ["aarch64"], "aarch64-darwin": ["arm64"]},
}


@pytest.mark.slow
@pytest.mark.parametrize("version", (2, 3))
def test_every_binary_is_built_for_its_platform_and_exports_every_function(every_platform, tmp_path, version):
    import zipfile

    ex = _exports()
    functions = _functions(version)
    for name in NAMES:
        with zipfile.ZipFile(every_platform[version] / f"{name}.fmu") as zf:
            binaries = [m for m in zf.namelist() if m.startswith("binaries/") and not m.endswith("/")]
            zf.extractall(tmp_path / name)
        folders = {m.split("/")[1]: tmp_path / name / m for m in binaries}
        assert set(folders) == set(EXPECTED[version]), (name, sorted(folders))
        for folder, path in folders.items():
            assert ex.architectures(path) == EXPECTED[version][folder], (name, folder)
            missing = functions - ex.exported_functions(path)  # a universal file: every slice's
            assert not missing, (name, folder, sorted(missing))


def _load_commands(data: bytes) -> dict:
    """A thin 64-bit Mach-O file's minimum macOS (LC_BUILD_VERSION minos) and install name (LC_ID_DYLIB)."""
    (ncmds,) = struct.unpack_from("<I", data, 16)
    pos, out = 32, {}
    for _ in range(ncmds):
        cmd, size = struct.unpack_from("<II", data, pos)
        if cmd == 0x32:
            (minos,) = struct.unpack_from("<I", data, pos + 12)
            out["minos"] = (minos >> 16, (minos >> 8) & 0xFF)
        elif cmd == 0xD:
            (offset,) = struct.unpack_from("<I", data, pos + 8)
            out["id"] = data[pos + offset:pos + size].split(b"\0")[0].decode()
        pos += size
    return out


#: the oldest macOS each Mach-O architecture's binaries load on: 10.15 on Intel, 11.0 (the first) on Apple Silicon
MACOS_MINIMUM = {"x86_64": (10, 15), "arm64": (11, 0)}


@pytest.mark.slow
@pytest.mark.parametrize("version", (2, 3))
def test_the_binaries_hold_no_build_path_and_load_on_older_macs(every_platform, version):
    """The Mach-O slices required macOS 15 (zig's default, the newest) and named the build's temporary folder as
    their install name (LC_ID_DYLIB); the ELF files carried debug information with the absolute paths of the sources.
    Now each slice requires macOS 10.15 (x86_64) or 11.0 (arm64) and is named @rpath/<file>; no binary holds the
    path of the installation or of a temporary folder; the FMU's JSON record lists the platforms its zip holds (the
    FMI 2.0 one listed aarch64 platforms it has no folder for)."""
    import json
    import tempfile
    import zipfile

    ex = _exports()
    native = str(compiler.NATIVE_DIR).encode()
    for name in NAMES:
        fmu = every_platform[version] / f"{name}.fmu"
        with zipfile.ZipFile(fmu) as zf:
            binaries = {m: zf.read(m) for m in zf.namelist() if m.startswith("binaries/") and not m.endswith("/")}
        for member, data in binaries.items():
            assert native not in data and tempfile.gettempdir().encode() + b"/tribocosim" not in data, member
            if member.endswith(".so"):
                assert b".debug_info" not in data and b".symtab" not in data, member
            if member.endswith(".dylib"):
                slices = (ex.fat_slices(data) if data[:4] == b"\xca\xfe\xba\xbe"
                          else [(struct.unpack_from("<i", data, 4)[0], data)])
                for cpu, part in slices:
                    arch = ex.MACHO_CPUS[cpu]
                    commands = _load_commands(part)
                    assert commands == {"minos": MACOS_MINIMUM[arch], "id": f"@rpath/{Path(member).name}"}, (
                        member, arch, commands)
        record = json.loads((every_platform[version] / f"{name}.fmu.json").read_text())
        folders = {m.split("/")[1] for m in binaries}
        assert len(record["platforms"]) == len(folders), (record["platforms"], folders)


@pytest.mark.slow
@pytest.mark.parametrize("version", (2, 3))
def test_two_builds_of_the_same_sources_are_byte_identical(every_platform, tmp_path, version):
    """Two builds differed (zip time stamps, the DLL's link time and CodeView GUID, the temporary build path in the
    Mach-O install names and the ELF debug information): every FMU of every platform is now the same file."""
    proc = subprocess.run([sys.executable, "-m", "tribocosim.cli", "fmu", "build", "--fmi", str(version), "--out",
                           str(tmp_path)], capture_output=True, text=True, timeout=3600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    for name in NAMES:
        assert (tmp_path / f"{name}.fmu").read_bytes() == (every_platform[version] / f"{name}.fmu").read_bytes(), name


@pytest.mark.slow
def test_the_scene_check_reads_every_platforms_library_and_refuses_a_truncated_one(every_platform):
    """cosim/scene/binaries.py on the ELF, PE and Mach-O (universal and thin) libraries of the FMUs: whole, none
    is refused; cut at a tenth, at half or by one byte of its content, each is, naming what lies beyond the end."""
    import zipfile

    from tribocosim.cosim.scene.binaries import truncation

    seen = set()
    for version in (2, 3):
        with zipfile.ZipFile(every_platform[version] / "StripDraw.fmu") as zf:
            for member in (m for m in zf.namelist() if m.startswith("binaries/") and not m.endswith("/")):
                data = zf.read(member)
                seen.add(data[:4])
                assert truncation(data) is None, member
                universal = data[:4] == b"\xca\xfe\xba\xbe"  # its last slice is padded to 16 KiB: cut into it
                last = max(o + n for _, _, o, n, _ in (struct.unpack_from(">iiIII", data, 8 + 20 * k) for k in range(
                    struct.unpack_from(">I", data, 4)[0]))) if universal else len(data)
                for cut in (len(data) // 10, len(data) // 2, last - 1):
                    assert truncation(data[:cut]), (member, cut)
    assert {b"\x7fELF", b"\xca\xfe\xba\xbe", b"\xcf\xfa\xed\xfe"} <= seen and any(k[:2] == b"MZ" for k in seen)


def _run_host(host: Path, folder: Path, md, steps, prefix=()) -> np.ndarray:
    vr = {v.name: v.valueReference for v in md.modelVariables}
    outputs = ",".join(f"{'i' if n == 'table_clamp_count' else 'r'}:{vr[n]}" for n in (
        "pull_force", "friction_force", "mu_mean", "beta_max", "sliding_distance", "table_clamp_count"))
    steps_file = folder.parent / f"steps-{host.name}.txt"
    steps_file.write_text("\n".join(",".join(repr(float(x)) for x in row) for row in steps) + "\n")
    cmd = [*prefix, str(host), str(folder), "StripDraw", md.guid, "--set", f"u:{vr['n_nodes']}=61",
           "--inputs", f"{vr['normal_force']},{vr['grip_velocity']}", "--outputs", outputs,
           "--arrays", f"{vr['n_nodes']}:{vr['beta']},{vr['U']}", "--steps", str(steps_file), "--replay", "100"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=1200, env={"PATH": "/usr/bin:/bin"})
    assert proc.returncode == 0, f"{' '.join(cmd[:3])}: exit {proc.returncode}\n{proc.stderr[-3000:]}"
    return np.array([[float(x) for x in line.split(",")] for line in proc.stdout.split()])


@pytest.mark.slow
def test_the_aarch64_linux_binary_under_qemu_draws_as_the_x86_64_one(every_platform, tmp_path):
    from fmpy import extract, read_model_description

    from tribocosim.components.fmus.native_build import fmi3_headers

    qemu = shutil.which("qemu-aarch64")
    assert qemu, "qemu-aarch64 (Debian: apt-get install qemu-user) runs the aarch64 binary"
    assert (AARCH64_SYSROOT / "lib" / "ld-linux-aarch64.so.1").is_file(), \
        "the aarch64 glibc (Debian: apt-get install libc6-arm64-cross)"
    fmu = every_platform[3] / "StripDraw.fmu"
    folder = Path(extract(str(fmu), str(tmp_path / "StripDraw")))
    md = read_model_description(str(fmu))
    flags = ["-isystem", str(fmi3_headers())]
    hosts = {p: compiler.compile_executable([HERE / "host" / "fmi3_host.c"], tmp_path / p / "fmi3_host",
                                             extra_flags=flags, libs=["-ldl"], platform=p)
             for p in ("linux64", "aarch64-linux")}
    ex = _exports()
    assert ex.architectures(hosts["aarch64-linux"]) == ["aarch64"]
    # the demo's pressure and grip speed for 200 steps of 1 ms, the grip reversing for the last 50
    steps = [(1e-3, 12250.0, 0.08 if k < 150 else -0.04) for k in range(200)]
    native = _run_host(hosts["linux64"], folder, md, steps)
    emulated = _run_host(hosts["aarch64-linux"], folder, md, steps, prefix=(qemu, "-L", str(AARCH64_SYSROOT)))
    assert native.shape == emulated.shape == (200, 1 + 6 + 2 * 61)
    scale = np.maximum(np.max(np.abs(native), axis=0), 1e-300)
    rel = np.max(np.abs(emulated - native) / scale)
    same = np.array_equal(emulated, native)
    print(f"\naarch64-linux (qemu) vs x86_64-linux, 200 steps, {native.shape[1] - 1} values per step: "
          f"{'bit-identical' if same else f'max relative difference {rel:.3g}'}")
    assert same or rel <= 1e-12, rel
    assert np.max(native[:, 1]) > 100.0, "a real draw: the pull force is there"


def _wine() -> str | None:
    """Debian's wine64 (apt-get install wine64): the command, or None."""
    found = shutil.which("wine64")
    return found or ("/usr/lib/wine/wine64" if Path("/usr/lib/wine/wine64").is_file() else None)


@pytest.mark.slow
def test_the_win64_binary_under_wine_draws_as_the_x86_64_linux_one_with_either_step_kernels(every_platform, tmp_path):
    """The FMI 2.0 win64 DLL in a Windows host (tests/native/host/fmi2_host_windows.c) under wine: the default draw's
    outputs those of the linux64 library to round-off (another C library's exp and log), and a win64 DLL built with
    -DTC_NO_AVX (the SSE2 step kernels whatever the processor, components/native/core/tc_cpu.h) gives the same bits as
    the shipped one (which runs the AVX kernels where the processor has AVX): the variant chosen at run time is
    exercised on Windows too."""
    from fmpy import extract, read_model_description

    from tribocosim.components.fmus import native_build
    from tribocosim.components.native.toolchain import declarations

    wine = _wine()
    assert wine, "wine64 (Debian: apt-get install wine64) runs the win64 binary"
    fmu = every_platform[2] / "StripDraw.fmu"
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    folders = {label: Path(extract(str(fmu), str(tmp_path / label))) for label in ("shipped", "no_avx")}
    comp = native_build.component("StripDraw")
    include = tmp_path / "include"
    declarations.write_params_headers(include, [comp])
    (include / "tc_fmu_model.h").write_text(declarations.model_header(comp, md.guid), encoding="ascii")
    dll = native_build.binary_path("StripDraw", "win64")
    compiler.compile_shared(native_build.sources(comp), folders["no_avx"] / dll, "win64",
                            include_dirs=[include, native_build.fmi2_headers()], defines=["TC_NO_AVX"])
    host = compiler.compile_executable([HERE / "host" / "fmi2_host_windows.c"], tmp_path / "fmi2_host_windows.exe",
                                       extra_flags=["-isystem", str(native_build.fmi2_headers())], platform="win64")
    outputs = [str(vr[n]) for n in ("pull_force", "friction_force", "mu_mean", "beta_max", "sliding_distance")]
    inputs = [f"{vr['normal_force']}=12250", f"{vr['grip_velocity']}=0.08"]

    def windows(label: str) -> np.ndarray:
        folder = folders[label]
        cmd = [wine, str(host), "Z:" + str(folder / dll).replace("/", "\\"), md.guid,
               (folder / "resources").as_uri().replace("file://", "file:///Z:"), "300", "0.001", *inputs, *outputs]
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600,
                              env={"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), "WINEDEBUG": "-all"})
        assert proc.returncode == 0, f"{label}: exit {proc.returncode}\n{proc.stderr[-3000:]}"
        return np.array([[float(x) for x in line.split(",")] for line in proc.stdout.split()])

    shipped, no_avx = windows("shipped"), windows("no_avx")
    assert shipped.shape == (300, 5) and np.array_equal(shipped, no_avx)
    linux_host = compiler.compile_executable([HERE / "host" / "fmi2_host.c"], tmp_path / "fmi2_host",
                                             extra_flags=["-isystem", str(native_build.fmi2_headers())], libs=["-ldl"])
    steps = [(1e-3, 12250.0, 0.08)] * 300
    steps_file = tmp_path / "steps.txt"
    steps_file.write_text("\n".join(",".join(repr(x) for x in row) for row in steps) + "\n")
    linux_folder = Path(extract(str(fmu), str(tmp_path / "linux")))
    proc = subprocess.run([str(linux_host), str(linux_folder), "StripDraw", md.guid, "--inputs",
                           f"{vr['normal_force']},{vr['grip_velocity']}", "--outputs",
                           ",".join(f"r:{o}" for o in outputs), "--steps", str(steps_file)],
                          capture_output=True, text=True, timeout=600, env={"PATH": "/usr/bin:/bin"})
    assert proc.returncode == 0, proc.stderr[-3000:]
    linux = np.array([[float(x) for x in line.split(",")[1:]] for line in proc.stdout.split()])
    scale = np.maximum(np.max(np.abs(linux), axis=0), 1e-300)
    rel = np.max(np.abs(shipped - linux) / scale)
    print(f"\nwin64 (wine) vs x86_64-linux, 300 steps: max relative difference {rel:.3g}; the win64 DLL with the SSE2 "
          "step kernels only: bit-identical")
    assert rel <= 1e-12, rel
    assert np.max(linux[:, 0]) > 100.0, "a real draw: the pull force is there"
