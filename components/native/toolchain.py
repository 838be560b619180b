"""Compile the native sources with the C compiler of the ``ziglang`` package (no system compiler needed).

``python -m ziglang cc`` is clang with zig's bundled C libraries, so one pip-installed toolchain
cross-compiles for every FMI 2.0 platform folder:

==========  ==========================  ============
platform    zig target                  library
==========  ==========================  ============
linux64     ``x86_64-linux-gnu.2.17``   ``.so``
win64       ``x86_64-windows-gnu``      ``.dll``
darwin64    ``x86_64-macos``            ``.dylib``
==========  ==========================  ============

(glibc 2.17: the library loads on any Linux from 2012 on.) Flags: C11, ``-O2``, all warnings as
errors, the baseline instruction set of each target (no ``-march=native``: a shipped FMU runs on any
x86-64). The first build for a target compiles zig's C library for it once (minutes for win64), kept in
zig's cache folder.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from tribocosim.components.errors import TribocosimError

#: FMI 2.0 platform folder -> (zig target, shared-library suffix)
PLATFORMS = {
    "linux64": ("x86_64-linux-gnu.2.17", ".so"),
    "win64": ("x86_64-windows-gnu", ".dll"),
    "darwin64": ("x86_64-macos", ".dylib"),
}

#: the warning and language flags every native source is compiled with
CFLAGS = ("-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Wshadow", "-Wconversion", "-Wno-sign-conversion",
          "-Werror", "-fno-fast-math", "-fvisibility=hidden")

#: where the C sources live (package data of this package)
SOURCE_DIR = Path(__file__).resolve().parent


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


def compile_shared(sources, output: str | os.PathLike, platform: str = "linux64", *, include_dirs=(),
                   defines=(), extra_flags=()) -> Path:
    """Compile C ``sources`` into the shared library ``output`` for an FMI platform folder.

    Parameters
    ----------
    sources : iterable of path
        C files.
    output : path
        The library to write (its folder is created).
    platform : {"linux64", "win64", "darwin64"}
    include_dirs, defines, extra_flags : iterables of str
        ``-I``, ``-D`` and further flags.

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
    cmd = [*zig_command(), "-target", target, *CFLAGS, "-shared"]
    if platform != "win64":
        cmd.append("-fPIC")
    cmd += [f"-I{d}" for d in (SOURCE_DIR, *include_dirs)]
    cmd += [f"-D{d}" for d in defines]
    cmd += [*extra_flags, "-o", str(out), *(str(s) for s in sources)]
    if platform != "win64":
        cmd.append("-lm")
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0 or not out.is_file():
        raise CompileError(f"compiling {out.name} for {platform} failed (exit {proc.returncode}):\n"
                           f"{' '.join(cmd)}\n{proc.stdout}{proc.stderr}")
    return out


def compile_executable(sources, output: str | os.PathLike, *, include_dirs=(), defines=(), extra_flags=(),
                       libs=()) -> Path:
    """Compile C ``sources`` into a linux64 executable (the tests' FMI hosts)."""
    out = Path(output)
    out.parent.mkdir(parents=True, exist_ok=True)
    target, _ = PLATFORMS["linux64"]
    cmd = [*zig_command(), "-target", target, *CFLAGS]
    cmd += [f"-I{d}" for d in (SOURCE_DIR, *include_dirs)]
    cmd += [f"-D{d}" for d in defines]
    cmd += [*extra_flags, "-o", str(out), *(str(s) for s in sources), "-lm", *libs]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0 or not out.is_file():
        raise CompileError(f"compiling {out.name} failed (exit {proc.returncode}):\n{' '.join(cmd)}\n"
                           f"{proc.stdout}{proc.stderr}")
    return out
