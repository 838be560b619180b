"""The native core library: the C models (strip draw, its friction law and table, press, machine, the field file)
built from the same sources as the FMUs and loaded with ctypes; the Python models are thin bindings over it.

The library is compiled on first use with the C compiler of the ``ziglang`` package
(:mod:`tribocosim.components.native.toolchain.compiler`, the FMUs' compiler and flags, ``-DTC_EXPORT_CORE`` so that the
core functions are exported) into ``$TRIBOCOSIM_CACHE/core`` (default ``~/.cache/tribocosim/fmus/core``), under a
name that carries the digest of its sources, generated headers, flags and compiler version: a changed source
builds a new library, an unchanged one is loaded as it is. The build writes a temporary file and renames it into
place, so concurrent processes never load a half-written library. A Python FMU carries the library it was built
with (:data:`BUNDLED`), used instead of a build.

Calls return a status (``TC_OK``, ``TC_DISCARD``, ``TC_ERROR``, ``TC_NOMEM``) and a message; :meth:`Core.check`
raises the matching exception.
"""

from __future__ import annotations

import ctypes
import dataclasses
import functools
import hashlib
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

from tribocosim.errors import ParameterError, TribocosimError

#: the C sources of the core library (the models and what they read and write; not the FMI layer)
SOURCES = ("core/tc_common.c", "core/tc_table.c", "core/tc_table_lookup.c", "core/tc_friction.c",
           "core/tc_stripdraw.c", "core/tc_galpha.c", "core/tc_kernels.c", "core/tc_linear.c", "core/tc_press.c",
           "core/tc_machine.c", "resource_io/tc_table_file.c", "resource_io/tc_arrays.c", "resource_io/tc_fields.c")
#: the status codes of tc_common.h
TC_OK = 0
TC_DISCARD = 1
TC_ERROR = 2
TC_NOMEM = 3
#: a library shipped beside this module (a Python FMU's), used instead of building one
BUNDLED = Path(__file__).resolve().parent / f"libtc_core{'.dll' if sys.platform.startswith('win') else '.so'}"

DBL_P = ctypes.POINTER(ctypes.c_double)
UBYTE_P = ctypes.POINTER(ctypes.c_ubyte)
VP = ctypes.c_void_p


class CoreBuildError(TribocosimError):
    """The native core library could not be built or loaded; the message says what failed."""


class Msg(ctypes.Structure):
    """``tc_msg``: a message buffer (text, capacity) passed by value."""

    _fields_ = [("text", ctypes.c_void_p), ("size", ctypes.c_size_t)]


def params_struct(cls):
    """A ctypes Structure with one member per field of the parameter dataclass ``cls``, in its order, as the
    generated C header declares it: float -> double, integer -> int, choices -> int (the index), text -> char *."""
    fields = []
    for f in dataclasses.fields(cls):
        meta = f.metadata
        if meta.get("text"):
            ctype = ctypes.c_char_p
        elif "choices" in meta or meta.get("integer"):
            ctype = ctypes.c_int
        else:
            ctype = ctypes.c_double
        fields.append((f.name, ctype))
    return type(f"c_{cls.__name__}", (ctypes.Structure,), {"_fields_": fields})


def to_struct(struct_cls, params):
    """The C parameter struct of a parameter dataclass instance (choices as their index)."""
    s = struct_cls()
    for f in dataclasses.fields(params):
        value = getattr(params, f.name)
        if "choices" in f.metadata:
            value = f.metadata["choices"].index(value)
        elif f.metadata.get("text"):
            value = value.encode()
        setattr(s, f.name, value)
    return s


def ptr(a: np.ndarray, ctype=DBL_P):
    """A ctypes pointer to a contiguous array's data."""
    return a.ctypes.data_as(ctype)


# ------------------------------------------------------------------------------------------------ building
def cache_dir() -> Path:
    """The cache folder of built FMUs and of the core library: ``$TRIBOCOSIM_CACHE`` or
    ``~/.cache/tribocosim/fmus``."""
    env = os.environ.get("TRIBOCOSIM_CACHE")
    return Path(env).expanduser() if env else Path.home() / ".cache" / "tribocosim" / "fmus"


def _headers(folder: Path) -> None:
    from tribocosim.components import registry
    from tribocosim.components.native.toolchain.declarations import write_params_headers

    write_params_headers(folder, [c for c in registry.components().values() if c.native is not None])


def digest() -> str:
    """SHA-256 of what the library is made of: sources, headers, what generates the parameter headers (the
    parameter modules of the package's components and the generator), flags, compiler. Imports no component."""
    from tribocosim.components.native.toolchain import compiler

    h = hashlib.sha256()
    package = compiler.NATIVE_DIR.parent
    for path in sorted({*map(compiler.source, SOURCES), *compiler.headers(), Path(__file__).with_name("declarations.py"),
                        package / "params.py", *package.glob("*/parameters.py")}):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    try:
        from importlib.metadata import version

        zig = version("ziglang")
    except Exception:  # noqa: BLE001 - the build says what is missing
        zig = "?"
    h.update(" ".join((*compiler.CFLAGS, zig)).encode())
    return h.hexdigest()


def build(output: str | os.PathLike, defines=()) -> Path:
    """Compile the core library for this machine into ``output`` (atomically); CoreBuildError saying why not."""
    from tribocosim.components.native.toolchain import compiler

    platform = "win64" if sys.platform.startswith("win") else "darwin64" if sys.platform == "darwin" else "linux64"
    out = Path(output)
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="tribocosim-core-", dir=out.parent) as tmp:
        _headers(Path(tmp))
        partial = Path(tmp) / out.name
        try:
            compiler.compile_shared(list(map(compiler.source, SOURCES)), partial, platform,
                                     defines=["TC_EXPORT_CORE", *defines], include_dirs=[tmp])
        except compiler.CompileError as exc:
            raise CoreBuildError(f"the native core library cannot be built: {exc}") from exc
        os.replace(partial, out)
    return out


def library_path() -> Path:
    """The core library for this process: the bundled one, else the cached build (built now if missing)."""
    if BUNDLED.is_file():
        return BUNDLED
    path = cache_dir() / "core" / f"libtc_core-{digest()[:20]}{BUNDLED.suffix}"
    return path if path.is_file() else build(path)


# ------------------------------------------------------------------------------------------------ the library
class Core:
    """The loaded library, its prototypes and the status check."""

    def __init__(self, path: str | os.PathLike):
        try:
            self.lib = lib = ctypes.CDLL(str(path))
        except OSError as exc:
            raise CoreBuildError(f"the native core library {path} cannot be loaded: {exc}") from exc
        self.path = Path(path)
        i, d, sz, msg = ctypes.c_int, ctypes.c_double, ctypes.c_size_t, Msg
        sd_p = pr_p = ma_p = VP  # the parameter structs, passed by reference (Core.struct)
        out = ctypes.POINTER(VP)
        proto = {
            "tc_table_from_arrays": (i, [sz, sz, sz, DBL_P, DBL_P, DBL_P, DBL_P, d, out, msg]),
            "tc_table_set_areas": (i, [VP, DBL_P, DBL_P, DBL_P, DBL_P, msg]),
            "tc_table_set_extras": (i, [VP, DBL_P, DBL_P, msg]),
            "tc_table_read": (i, [ctypes.c_char_p, out, msg]),
            "tc_table_free": (None, [VP]),
            "tc_table_set_cubic": (i, [VP, msg]),
            "tc_table_lookup": (i, [VP, DBL_P, d, sz, DBL_P, DBL_P, i, DBL_P, UBYTE_P, msg]),
            "tc_table_read_nodes": (sz, [VP, d, d, d, ctypes.POINTER(sz), DBL_P, ctypes.POINTER(i)]),
            "tc_table_beta_line": (i, [VP, DBL_P, d, d, DBL_P, DBL_P, DBL_P, msg]),
            "tc_table_first_crossing": (i, [sz, DBL_P, DBL_P, DBL_P, DBL_P, d, DBL_P]),
            "tc_law_check": (i, [sd_p, VP, msg]),
            "tc_law_mu": (i, [sd_p, VP, d, sz, DBL_P, DBL_P, DBL_P, UBYTE_P, DBL_P, msg]),
            "tc_law_beta_threshold": (d, [sd_p, VP]),
            "tc_law_beta_cap": (d, [sd_p, VP, d, d]),
            "tc_law_alpha": (d, [sd_p, d]),
            "tc_stripdraw_create": (i, [sd_p, VP, DBL_P, sz, out, msg]),
            "tc_stripdraw_free": (None, [VP]),
            "tc_stripdraw_step_poly": (i, [VP, d, d, DBL_P, d, DBL_P, msg]),
            "tc_stripdraw_refusal": (i, [VP]),
            "tc_stripdraw_outputs": (None, [VP, DBL_P]),
            "tc_stripdraw_state_size": (sz, [VP]),
            "tc_stripdraw_get_state": (None, [VP, VP]),
            "tc_stripdraw_set_state": (i, [VP, VP, sz, msg]),
            "tc_stripdraw_n_nodes": (sz, [VP]),
            "tc_stripdraw_nodal": (None, [VP, i, DBL_P]),
            "tc_stripdraw_info": (d, [VP, i]),
            "tc_thomas": (None, [sz, DBL_P, DBL_P, DBL_P, DBL_P, DBL_P, DBL_P]),
            "tc_sd_advect": (None, [sz, DBL_P, DBL_P, DBL_P, d, d, DBL_P, DBL_P]),
            "tc_expm": (i, [sz, DBL_P, DBL_P, msg]),
            "tc_field_recorder_create": (i, [ctypes.c_char_p, d, sz, DBL_P, DBL_P, ctypes.c_char_p, out, msg]),
            "tc_field_recorder_record": (i, [VP, d, DBL_P, DBL_P, DBL_P, i, msg]),
            "tc_field_recorder_truncate": (None, [VP, d]),
            "tc_field_recorder_finish": (i, [VP, d, DBL_P, DBL_P, DBL_P, msg]),
            "tc_field_recorder_write": (i, [VP, msg]),
            "tc_field_recorder_rows": (sz, [VP]),
            "tc_field_recorder_free": (None, [VP]),
            "tc_field_read_initial_beta": (i, [ctypes.c_char_p, sz, DBL_P, DBL_P, msg]),
            "tc_press_create": (i, [pr_p, out, msg]),
            "tc_press_free": (None, [VP]),
            "tc_press_step": (i, [VP, d, msg]),
            "tc_press_outputs": (None, [VP, DBL_P]),
            "tc_press_state_size": (sz, [VP]),
            "tc_press_get_state": (None, [VP, VP]),
            "tc_press_set_state": (i, [VP, VP, sz, msg]),
            "tc_press_time": (d, [VP]),
            "tc_machine_create": (i, [ma_p, out, msg]),
            "tc_machine_free": (None, [VP]),
            "tc_machine_step": (i, [VP, d, d, msg]),
            "tc_machine_outputs": (None, [VP, DBL_P]),
            "tc_machine_state_size": (sz, [VP]),
            "tc_machine_get_state": (None, [VP, VP]),
            "tc_machine_set_state": (i, [VP, VP, sz, msg]),
            "tc_machine_time": (d, [VP]),
        }
        for name, (res, args) in proto.items():
            fn = getattr(lib, name)
            fn.restype = res
            fn.argtypes = args

    @staticmethod
    @functools.lru_cache(maxsize=None)
    def params_class(cls):
        """The C parameter struct type of a parameter dataclass (made once per class)."""
        return params_struct(cls)

    def struct(self, params):
        """The C parameter struct of a parameter dataclass instance (pass it with ctypes.byref)."""
        return to_struct(self.params_class(type(params)), params)

    def call(self, fn, *args, error=ParameterError, discard=None) -> None:
        """Call ``fn(*args, msg)`` and raise on a status other than TC_OK: ``discard`` (default ``error``) for
        TC_DISCARD, ``error`` for TC_ERROR, MemoryError for TC_NOMEM, with the C message."""
        buf = ctypes.create_string_buffer(2048)
        status = fn(*args, Msg(ctypes.addressof(buf), len(buf)))
        if status == TC_OK:
            return
        text = buf.value.decode(errors="replace")
        if status == TC_NOMEM:
            raise MemoryError(text)
        raise (discard or error)(text) if status == TC_DISCARD else error(text)


@functools.lru_cache(maxsize=1)
def core() -> Core:
    """The core library of this process (built on first use; see the module docstring)."""
    return Core(library_path())
