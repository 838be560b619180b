"""Compile the native sources with the C compiler of the ``ziglang`` package (no system compiler needed).

``python -m ziglang cc`` is clang with zig's bundled C libraries, so one pip-installed toolchain
cross-compiles for every platform an FMU has a binary for:

==============  ==================================================  ============
platform        zig target                                          library
==============  ==================================================  ============
linux64         ``x86_64-linux-gnu.2.17``                           ``.so``
win64           ``x86_64-windows-gnu``                              ``.dll``
darwin64        ``x86_64-macos.10.15`` and ``aarch64-macos.11.0``   ``.dylib``, universal (both slices)
x86_64-darwin   ``x86_64-macos.10.15``                              ``.dylib``
aarch64-linux   ``aarch64-linux-gnu.2.17``                          ``.so``
aarch64-darwin  ``aarch64-macos.11.0``                              ``.dylib``
==============  ==================================================  ============

FMI 2.0 knows one macOS folder, darwin64, for every Mac: its binary is a universal Mach-O that holds an x86_64
and an arm64 slice (Apple Silicon loads the arm64 one), each compiled by zig and joined by
:func:`write_universal`, a fat-header writer (zig ships no ``lipo``). FMI 3.0 has a folder per platform tuple,
thin binaries each. (glibc 2.17: the library loads on any Linux from 2012 on; macOS 10.15 on Intel, 11.0, the
first with Apple Silicon, on arm64: zig's default, the newest macOS, made the libraries refuse every older one.)
Flags: C11, ``-O2``, all warnings as errors, the baseline instruction set of each target (no ``-march=native``: a
shipped FMU runs on any machine of its architecture), no debug information (``-g0``; zig's C compiler adds it by
default, with the absolute paths of the sources) and, on ELF, no symbol table beyond the exported functions (``-s``),
and a Mach-O library's install name is ``@rpath/<its file name>`` (not the build's temporary path). So a binary
holds no path of the machine that built it, and two builds of the same sources are byte-identical. The first build for a target compiles zig's C library for it once (minutes for win64), kept in
zig's cache folder.
"""

from __future__ import annotations

import os
import struct
import sys
from pathlib import Path

from tribocosim.errors import TribocosimError

#: platform -> (zig target, or the targets of a universal Mach-O's slices; shared-library suffix)
PLATFORMS = {
    "linux64": ("x86_64-linux-gnu.2.17", ".so"),
    "win64": ("x86_64-windows-gnu", ".dll"),
    "darwin64": (("x86_64-macos.10.15", "aarch64-macos.11.0"), ".dylib"),
    "x86_64-darwin": ("x86_64-macos.10.15", ".dylib"),
    "aarch64-linux": ("aarch64-linux-gnu.2.17", ".so"),
    "aarch64-darwin": ("aarch64-macos.11.0", ".dylib"),
}

#: the warning and language flags every native source is compiled with
CFLAGS = ("-std=c11", "-O2", "-g0", "-Wall", "-Wextra", "-Wpedantic", "-Wshadow", "-Wconversion",
          "-Wno-sign-conversion", "-Werror", "-fno-fast-math", "-fvisibility=hidden")

#: the native package: its C sources are package data, in one folder per role
NATIVE_DIR = Path(__file__).resolve().parents[1]
#: the folders of the C sources, by role: the models' physics (core), the FMI layer and the component glue (fmi), and
#: the files the C code reads and writes (resource_io); every one is on the include path of every compile
SOURCE_FOLDERS = ("core", "fmi", "resource_io")
INCLUDE_DIRS = tuple(NATIVE_DIR / folder for folder in SOURCE_FOLDERS)


def source(name: str) -> Path:
    """The C source ``name``, given relative to the native package (``"core/tc_stripdraw.c"``)."""
    return NATIVE_DIR / name


def headers() -> list[Path]:
    """Every C header of the native sources, in a fixed order."""
    return sorted(h for d in INCLUDE_DIRS for h in d.glob("*.h"))


class CompileError(TribocosimError):
    """The C compiler failed; the message carries its output."""


def zig_command() -> list[str]:
    """The command that runs zig's C compiler (``python -m ziglang cc``)."""
    try:
        import ziglang  # noqa: F401
    except ImportError as exc:
        raise CompileError("the C compiler package 'ziglang' is not installed (pip install ziglang); it builds the "
                           "native FMUs") from exc
    return [sys.executable, "-m", "ziglang", "cc"]


def zig_dist_info() -> Path | None:
    """The dist-info folder of the installed ``ziglang`` package (its name carries the version), or None."""
    import importlib.util

    spec = importlib.util.find_spec("ziglang")
    if spec is None or spec.origin is None:
        return None
    found = sorted(Path(spec.origin).resolve().parent.parent.glob("ziglang-*.dist-info"))
    return found[-1] if found else None


def zig_version() -> str:
    """The version of the installed ``ziglang`` package (from its dist-info folder's name: no metadata import), or
    ``"?"`` when it is not installed."""
    folder = zig_dist_info()
    return folder.name[len("ziglang-"):-len(".dist-info")] if folder is not None else "?"


def compile_shared(sources, output: str | os.PathLike, platform: str = "linux64", *, include_dirs=(),
                   defines=(), extra_flags=(), symbols: bool = False) -> Path:
    """Compile C ``sources`` into the shared library ``output`` for a platform of :data:`PLATFORMS`.

    Parameters
    ----------
    sources : iterable of path
        C files.
    output : path
        The library to write (its folder is created).
    platform : str
        A key of :data:`PLATFORMS` (``linux64``, ``win64``, ``darwin64`` (universal), ``x86_64-darwin``,
        ``aarch64-linux``, ``aarch64-darwin``).
    include_dirs, defines, extra_flags : iterables of str
        ``-I``, ``-D`` and further flags.
    symbols : bool
        Keep the symbol table of an ELF library (no ``-s``): the same code, with every function named for a profiler
        (``benchmarks/callgrind_fmu.py``); a shipped library has none.

    Raises
    ------
    CompileError
        With the compiler's output when it fails.
    """
    if platform not in PLATFORMS:
        raise CompileError(f"platform = {platform!r} is not one of {', '.join(PLATFORMS)}")
    target, _ = PLATFORMS[platform]
    out = Path(output)
    out.parent.mkdir(parents=True, exist_ok=True)
    sources = list(sources)
    if isinstance(target, tuple):  # a universal Mach-O: one slice per target, joined
        slices = [out.with_name(f".{out.name}.{t}") for t in target]
        try:
            for t, part in zip(target, slices):
                _compile(sources, part, t, platform, include_dirs, defines, extra_flags, out.name, symbols)
            write_universal(slices, out)
        finally:
            for part in slices:
                part.unlink(missing_ok=True)
        return out
    return _compile(sources, out, target, platform, include_dirs, defines, extra_flags, out.name, symbols)


def _command(target: str, include_dirs, defines, extra_flags) -> list[str]:
    return [*zig_command(), "-target", target, *CFLAGS, *(f"-I{d}" for d in (*INCLUDE_DIRS, *include_dirs)),
            *(f"-D{d}" for d in defines), *extra_flags]


def _run(cmd: list[str], out: Path, what: str) -> Path:
    import subprocess

    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0 or not out.is_file():
        raise CompileError(f"compiling {what} failed (exit {proc.returncode}):\n{' '.join(cmd)}\n"
                           f"{proc.stdout}{proc.stderr}")
    return out


def _link_flags(target: str, name: str, symbols: bool = False) -> list[str]:
    """The flags of a shared library for a target: position-independent code off Windows, the install name
    ``@rpath/<name>`` of a Mach-O library, no symbol table beyond the exported one in an ELF library (unless
    ``symbols``)."""
    if "windows" in target:
        return []
    if "macos" in target:
        return ["-fPIC", f"-Wl,-install_name,@rpath/{name}"]
    return ["-fPIC"] if symbols else ["-fPIC", "-s"]


def _compile(sources, out: Path, target: str, platform: str, include_dirs, defines, extra_flags, name: str,
             symbols: bool = False) -> Path:
    posix = "windows" not in target
    cmd = [*_command(target, include_dirs, defines, extra_flags), "-shared", *_link_flags(target, name, symbols),
           "-o", str(out), *(str(s) for s in sources), *(["-lm"] if posix else [])]
    _run(cmd, out, f"{out.name} for {platform} ({target})")
    return out if posix else reproducible_pe(out)


def reproducible_pe(path: str | os.PathLike) -> Path:
    """Replace the fields of a PE library (a Windows DLL) that zig's linker fills from the clock with a hash of the
    rest of the file, as ``lld-link /Brepro`` does, so that two builds of the same sources are byte-identical.

    The fields (Microsoft PE format: COFF file header, optional header data directory 6 "Debug",
    IMAGE_DEBUG_DIRECTORY, the CodeView "RSDS" record): the header's TimeDateStamp (4 bytes at PE + 8), each debug
    directory entry's TimeDateStamp (4 bytes at 4 of its 28), and the CodeView record's GUID (16 bytes after
    "RSDS"). They are set to 0, the file hashed (SHA-256), then the stamps set to the hash's first 4 bytes and the
    GUID to its first 16. The optional header's CheckSum is 0 (not computed) and stays so."""
    import hashlib

    path = Path(path)
    d = bytearray(path.read_bytes())
    (pe,) = struct.unpack_from("<I", d, 60)
    nsections, optional_size = struct.unpack_from("<H", d, pe + 6)[0], struct.unpack_from("<H", d, pe + 20)[0]
    opt = pe + 24
    directories = opt + (112 if struct.unpack_from("<H", d, opt)[0] == 0x20B else 96)  # PE32+ or PE32
    debug_rva, debug_size = struct.unpack_from("<II", d, directories + 8 * 6)
    stamps, guids = [pe + 8], []
    for k in range(nsections):
        vsize, va, _, raw = struct.unpack_from("<IIII", d, opt + optional_size + 40 * k + 8)
        if debug_size and va <= debug_rva < va + vsize:
            first = debug_rva - va + raw
            for entry in range(first, first + debug_size, 28):
                stamps.append(entry + 4)
                kind, size, _, data = struct.unpack_from("<IIII", d, entry + 12)
                if kind == 2 and size >= 20 and d[data:data + 4] == b"RSDS":  # CodeView
                    guids.append(data + 4)
    for at in stamps:
        d[at:at + 4] = bytes(4)
    for at in guids:
        d[at:at + 16] = bytes(16)
    digest = hashlib.sha256(d).digest()
    for at in stamps:
        d[at:at + 4] = digest[:4]
    for at in guids:
        d[at:at + 16] = digest[:16]
    path.write_bytes(bytes(d))
    return path


#: Mach-O: the 64-bit header's magic (little-endian) and the fat header's (big-endian)
MH_MAGIC_64, FAT_MAGIC = 0xFEEDFACF, 0xCAFEBABE
#: log2 of the alignment of every slice in a universal file: 16 KiB, arm64's page size (x86_64's 4 KiB divides it)
SLICE_ALIGN = 14


def write_universal(slices, output: str | os.PathLike) -> Path:
    """Join thin 64-bit Mach-O files into one universal ("fat") file, as ``lipo -create`` does.

    The layout (<mach-o/fat.h>; every field a big-endian uint32): ``fat_header {magic = 0xcafebabe,
    nfat_arch}``, then per slice ``fat_arch {cputype, cpusubtype, offset, size, align}``, then the slices,
    each at an offset that is a multiple of ``2**align``. cputype and cpusubtype are copied from each slice's
    own header (``mach_header_64``, little-endian: magic 0xfeedfacf, cputype, cpusubtype). The loader of each
    Mac picks the slice of its CPU.
    """
    parts = [Path(p).read_bytes() for p in slices]
    arches = []
    for path, data in zip(slices, parts):
        if len(data) < 32 or struct.unpack_from("<I", data, 0)[0] != MH_MAGIC_64:
            raise CompileError(f"{path}: not a 64-bit little-endian Mach-O file; a universal file joins such slices")
        arches.append(struct.unpack_from("<ii", data, 4))
    if len({a[0] for a in arches}) != len(arches):
        raise CompileError(f"two slices of {output} have the same CPU type {arches}")
    align = 1 << SLICE_ALIGN
    offset = -(-(8 + 20 * len(parts)) // align) * align
    header = struct.pack(">II", FAT_MAGIC, len(parts))
    body = b""
    for (cputype, cpusubtype), data in zip(arches, parts):
        header += struct.pack(">iiIII", cputype, cpusubtype, offset + len(body), len(data), SLICE_ALIGN)
        body += data + b"\0" * (-len(data) % align)
    out = Path(output)
    out.write_bytes(header + b"\0" * (offset - len(header)) + body)
    return out


def compile_executable(sources, output: str | os.PathLike, *, include_dirs=(), defines=(), extra_flags=(),
                       libs=(), platform: str = "linux64") -> Path:
    """Compile C ``sources`` into an executable (the tests' FMI hosts: linux64, aarch64-linux to run under qemu-user,
    or win64 to run under wine)."""
    if platform not in ("linux64", "aarch64-linux", "win64"):
        raise CompileError(f"platform = {platform!r}: executables are built for linux64, aarch64-linux or win64")
    out = Path(output)
    out.parent.mkdir(parents=True, exist_ok=True)
    cmd = [*_command(PLATFORMS[platform][0], include_dirs, defines, extra_flags), "-o", str(out),
           *(str(s) for s in sources), "-lm", *libs]
    return _run(cmd, out, out.name)
