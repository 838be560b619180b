"""The native core library: the C models (strip draw, its friction law and table, press, machine, the field file)
built from the same sources as the FMUs and loaded with ctypes; the Python models are thin bindings over it.

Its sources are the model sources the components declare (:func:`sources`); the ctypes signatures of its
functions are read from their headers (:mod:`tribocosim.components.native.toolchain.prototypes`). The library is
compiled on first use with the C compiler of the ``ziglang`` package
(:mod:`tribocosim.components.native.toolchain.compiler`, the FMUs' compiler and flags, ``-DTC_EXPORT_CORE`` so that the
core functions are exported) into ``$TRIBOCOSIM_CACHE/core`` (default ``~/.cache/tribocosim/fmus/core``), under a
name that carries the digest of its sources, generated headers, flags and compiler version: a changed source
builds a new library, an unchanged one is loaded as it is. The build writes a temporary file and renames it into
place, so concurrent processes never load a half-written library.

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
from pathlib import Path

from tribocosim.atomic import replaced
from tribocosim.errors import ParameterError, TribocosimError

#: the C sources of the core library beside the components' model sources: the helpers every model uses
COMMON_SOURCES = ("core/tc_common.c",)
#: the status codes of tc_common.h
TC_OK = 0
TC_DISCARD = 1
TC_ERROR = 2
TC_NOMEM = 3
#: the shared-library suffix of this machine
SUFFIX = ".dll" if sys.platform.startswith("win") else ".dylib" if sys.platform == "darwin" else ".so"

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


def ptr(a, ctype=DBL_P):
    """A ctypes pointer to a contiguous array's data."""
    return a.ctypes.data_as(ctype)


# ------------------------------------------------------------------------------------------------ building
def sources() -> tuple[str, ...]:
    """The C sources of the core library: :data:`COMMON_SOURCES` and the model sources every native component
    declares (``Native.sources`` outside ``fmi/``, which holds its FMU glue), each once, in declaration order."""
    from tribocosim.components import registry

    out = list(COMMON_SOURCES)
    for comp in registry.components().values():
        if comp.native is not None:
            out += [s for s in comp.native.sources if not s.startswith("fmi/") and s not in out]
    return tuple(out)


def source_files() -> list[Path]:
    """The C files of the model folders (``core/``, ``resource_io/``): the files of :func:`sources`, found without
    importing a component (``tests/native/test_native_prototypes.py`` holds the two to each other), for the digest
    and the prototypes of a library that is loaded, not built."""
    from tribocosim.components.native.toolchain import compiler

    return sorted(p for folder in ("core", "resource_io") for p in (compiler.NATIVE_DIR / folder).glob("*.c"))


@functools.lru_cache(maxsize=1)
def prototypes() -> dict:
    """The functions the core library exports (``TC_API``), read from the headers of its sources
    (:func:`tribocosim.components.native.toolchain.prototypes.exported`)."""
    from tribocosim.components.native.toolchain.prototypes import exported

    return exported(p.with_suffix(".h") for p in source_files())


def cache_dir() -> Path:
    """The cache folder of built FMUs and of the core library: ``$TRIBOCOSIM_CACHE`` or
    ``~/.cache/tribocosim/fmus``."""
    env = os.environ.get("TRIBOCOSIM_CACHE")
    return Path(env).expanduser() if env else Path.home() / ".cache" / "tribocosim" / "fmus"


def _headers(folder: Path) -> None:
    from tribocosim.components import registry
    from tribocosim.components.native.toolchain.declarations import write_params_headers

    write_params_headers(folder, [c for c in registry.components().values() if c.native is not None])


def declaration_files(package: Path) -> set[Path]:
    """What the parameter headers are generated from, found without importing a component: each component's
    parameter module and declaration (``parameters.py``, ``component.py``: the fields, ``Native.constants``) and the
    modules of the components package they import at their top level (where a constant's value is defined)."""
    import re

    own = {*package.glob("*/parameters.py"), *package.glob("*/component.py")}
    imported = set()
    for path in own:
        for folder, module in re.findall(r"^from tribocosim\.components\.(\w+)\.(\w+) import", path.read_text(),
                                         re.MULTILINE):
            candidate = package / folder / f"{module}.py"
            if candidate.is_file():
                imported.add(candidate)
    return own | imported


def digest() -> str:
    """SHA-256 of what the library is made of: sources, headers, what generates the parameter headers
    (:func:`declaration_files`, the generator), flags, compiler. Imports no component."""
    from tribocosim.components.native.toolchain import compiler

    h = hashlib.sha256()
    package = compiler.NATIVE_DIR.parent
    for path in sorted({*source_files(), *compiler.headers(), Path(__file__).with_name("declarations.py"),
                        package / "params.py", *declaration_files(package)}):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    h.update(" ".join((*compiler.CFLAGS, compiler.zig_version())).encode())
    return h.hexdigest()


def build(output: str | os.PathLike, defines=()) -> Path:
    """Compile the core library for this machine into ``output`` (atomically); CoreBuildError saying why not."""
    import tempfile

    from tribocosim.components.native.toolchain import compiler

    platform = "win64" if sys.platform.startswith("win") else "darwin64" if sys.platform == "darwin" else "linux64"
    out = Path(output)
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="tribocosim-core-", dir=out.parent) as tmp, \
            replaced(out, out.suffix) as partial:
        _headers(Path(tmp))
        try:
            compiler.compile_shared(list(map(compiler.source, sources())), partial, platform,
                                     defines=["TC_EXPORT_CORE", *defines], include_dirs=[tmp])
        except compiler.CompileError as exc:
            raise CoreBuildError(f"the native core library cannot be built: {exc}") from exc
    return out


def library_path() -> Path:
    """The core library for this process: the cached build (built now if missing)."""
    path = cache_dir() / "core" / f"libtc_core-{digest()[:20]}{SUFFIX}"
    return path if path.is_file() else build(path)


# ------------------------------------------------------------------------------------------------ the library
class Core:
    """The loaded library, its prototypes and the status check."""

    def __init__(self, path: str | os.PathLike):
        from tribocosim.components.native.toolchain.prototypes import ctypes_signature

        try:
            self.lib = lib = ctypes.CDLL(str(path))
        except OSError as exc:
            raise CoreBuildError(f"the native core library {path} cannot be loaded: {exc}") from exc
        self.path = Path(path)
        for name, proto in prototypes().items():  # every TC_API function, typed from its header
            fn = getattr(lib, name)
            fn.restype, fn.argtypes = ctypes_signature(proto, Msg)

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
