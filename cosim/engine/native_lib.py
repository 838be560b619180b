"""The C master's library (``native/tc_master.c``): its build, its loading and the ctypes structures it takes.

The library holds the fixed-step loop of Jacobi and Gauss-Seidel with held coupling values (``tcm_run``), the output
refresh and the feedthrough probe of the master's initialization (``tcm_refresh``, ``tcm_probe``), the start row of
the recorder (``tcm_record_row``), the FMI 2.0 callbacks a host passes to ``fmi2Instantiate`` (``tcm_logger``,
which formats an FMU's variadic log message and hands it to a sink; ``tcm_allocate_memory``, ``tcm_free_memory``),
and the rows of the results CSV (``native/tc_csv.c``, ``tcm_csv_rows``: :mod:`.results_csv`).
:mod:`.native_loop` runs the loop for the Python master, :mod:`.native_session` a whole run in it. Nothing here
imports numpy or fmpy.

The library is compiled on first use with the project's C compiler (:mod:`tribocosim.components.native.toolchain.
compiler`) into ``$TRIBOCOSIM_CACHE/master`` under a name carrying the digest of its sources, the FMI headers,
the flags and the compiler version, as the core library is.
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import importlib.util
import os
import sys
from pathlib import Path

#: the C sources of the library and their headers
NATIVE_DIR = Path(__file__).resolve().parent / "native"
SOURCES = ("tc_master.c", "tc_csv.c")
HEADERS = ("tc_master.h", "tc_csv.h")
#: accepted steps of the first call of the C loop, and the most of any call: between two calls the progress reporters
#: are told the time and a stop asked for by a signal is seen (:mod:`tribocosim.interrupt`), so later calls take as
#: many steps as last about POLL_S seconds (:func:`next_chunk`)
CHUNK = 256
MAX_CHUNK = 65536
#: tcm_status
TCM_DONE, TCM_STOPPED, TCM_FMI_ERROR = 0, 1, 2
#: tcm_kind of each FMI type the recorder reads
KINDS = {"get_real": 0, "get_integer": 1, "get_boolean": 2}
#: FMI 2.0 status names by value
STATUS_LABELS = ("ok", "warning", "discard", "error", "fatal", "pending")

_I, _SZ, _D, _I64, _VP = ctypes.c_int, ctypes.c_size_t, ctypes.c_double, ctypes.c_int64, ctypes.c_void_p
_PI, _PD, _PU = ctypes.POINTER(ctypes.c_int), ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_uint)
_PSZ, _PB = ctypes.POINTER(ctypes.c_size_t), ctypes.POINTER(ctypes.c_ubyte)


class TcmSlave(ctypes.Structure):
    """``tcm_slave``."""

    _fields_ = [("component", _VP), ("set_real", _VP), ("get_real", _VP), ("get_integer", _VP),
                ("get_boolean", _VP), ("do_step", _VP), ("wall_time", _D), ("do_steps", _I64),
                ("current_time", _D)]


class TcmGet(ctypes.Structure):
    """``tcm_get``."""

    _fields_ = [("slave", _I), ("kind", _I), ("n_vrs", _SZ), ("vrs", _PU), ("n_dst", _SZ), ("pos", _PI),
                ("dst", _PI)]


class TcmSet(ctypes.Structure):
    """``tcm_set``."""

    _fields_ = [("slave", _I), ("n", _SZ), ("vrs", _PU), ("link", _PI)]


class TcmRig(ctypes.Structure):
    """``tcm_rig``."""

    _fields_ = [("n_slaves", _SZ), ("slaves", ctypes.POINTER(TcmSlave)), ("n_links", _SZ), ("link_source", _PI),
                ("set_first", _PSZ), ("sets", ctypes.POINTER(TcmSet)), ("get_first", _PSZ),
                ("gets", ctypes.POINTER(TcmGet)), ("feeds", _PI), ("eval_order", _PI), ("sequence", _PI),
                ("gauss_seidel", _I), ("propagate", _I), ("n_columns", _SZ), ("n_record_gets", _SZ),
                ("record_gets", ctypes.POINTER(TcmGet)), ("n_from_links", _SZ), ("from_link_column", _PI),
                ("from_link", _PI), ("start", _D), ("tick", _D), ("macro_ticks", _I64), ("end_ticks", _I64)]


class TcmState(ctypes.Structure):
    """``tcm_state``."""

    _fields_ = [("n", _I64), ("y", _PD), ("written", _PD), ("written_ok", _PB), ("stepped", _PB), ("values", _PD),
                ("held", _PD), ("ints", _PI), ("row", _PD), ("times", _PD), ("rows", _PD), ("capacity", _SZ),
                ("n_rows", _SZ), ("steps", _I64), ("min_step", _D), ("max_step", _D), ("failed_slave", _I),
                ("failed_status", _I), ("failed_function", ctypes.c_char_p), ("failed_time", _D)]


class TcmLogEnv(ctypes.Structure):
    """``tcm_log_env``: the component environment of an FMU instance whose logger is ``tcm_logger``."""

    _fields_ = [("sink", _VP), ("key", _VP)]


#: ``tcm_sink``: what ``tcm_logger`` hands a formatted message to (key, status, message)
SINK = ctypes.CFUNCTYPE(None, _VP, _I, ctypes.c_char_p)

#: every ctypes structure of the library by its C name (tests/cosim/test_native_loop.py holds them to the header)
STRUCTS = {"tcm_slave": TcmSlave, "tcm_get": TcmGet, "tcm_set": TcmSet, "tcm_rig": TcmRig, "tcm_state": TcmState,
           "tcm_log_env": TcmLogEnv}


def next_chunk(steps: int, seconds: float) -> int:
    """The steps of the next call of the C loop after one of ``steps`` steps took ``seconds``: as many as last about
    :data:`tribocosim.interrupt.POLL_S` (the chunks change when the loop looks up from its steps, not what it
    computes)."""
    from tribocosim.interrupt import POLL_S

    if seconds <= 0.0:
        return MAX_CHUNK
    return max(1, min(MAX_CHUNK, int(steps * POLL_S / seconds)))


# ------------------------------------------------------------------------------------------------ the library
def fmi_headers() -> Path:
    """The folder of the FMI 2.0 headers that fmpy ships (``fmi2FunctionTypes.h``; found without importing fmpy)."""
    spec = importlib.util.find_spec("fmpy")
    return Path(spec.origin).resolve().parent / "c-code"


def digest() -> str:
    """SHA-256 of what the library is made of: its sources, the FMI headers, the flags and the compiler version
    (remembered while none of the files changed: :func:`tribocosim.components.native.toolchain.digests.memo`)."""
    from tribocosim.components.native.toolchain import compiler
    from tribocosim.components.native.toolchain.digests import memo

    folder = fmi_headers()
    files = (*(NATIVE_DIR / s for s in (*SOURCES, *HEADERS)), folder / "fmi2FunctionTypes.h",
             folder / "fmi2TypesPlatform.h")
    flags = " ".join((*compiler.CFLAGS, compiler.zig_version()))

    def compute() -> str:
        h = hashlib.sha256()
        for path in files:
            h.update(path.name.encode())
            h.update(path.read_bytes())
        h.update(flags.encode())
        return h.hexdigest()

    return memo(f"master {flags}", files, compute)


def build(output: str | os.PathLike) -> Path:
    """Compile the loop's library for this machine into ``output`` (atomically)."""
    from tribocosim.atomic import replaced

    from tribocosim.components.native.toolchain import compiler

    platform = "win64" if sys.platform.startswith("win") else "darwin64" if sys.platform == "darwin" else "linux64"
    out = Path(output)
    out.parent.mkdir(parents=True, exist_ok=True)
    with replaced(out, out.suffix) as partial:
        compiler.compile_shared([NATIVE_DIR / s for s in SOURCES], partial, platform,
                                include_dirs=[str(NATIVE_DIR), str(fmi_headers())])
    return out


@functools.lru_cache(maxsize=1)
def library() -> ctypes.CDLL:
    """The loop's library of this process, built on first use into the cache."""
    from tribocosim.components.native.toolchain.library import cache_dir

    suffix = ".dll" if sys.platform.startswith("win") else ".dylib" if sys.platform == "darwin" else ".so"
    path = cache_dir() / "master" / f"libtc_master-{digest()[:20]}{suffix}"
    lib = ctypes.CDLL(str(path if path.is_file() else build(path)))
    lib.tcm_run.restype = _I
    lib.tcm_run.argtypes = [ctypes.POINTER(TcmRig), ctypes.POINTER(TcmState), _I64]
    lib.tcm_refresh.restype = _I
    lib.tcm_refresh.argtypes = [ctypes.POINTER(TcmRig), ctypes.POINTER(TcmState)]
    lib.tcm_probe.restype = _I
    lib.tcm_probe.argtypes = [ctypes.POINTER(TcmRig), ctypes.POINTER(TcmState), _PI, _PU, _PB, _PD, _PB, _PD]
    lib.tcm_record_row.restype = _I
    lib.tcm_record_row.argtypes = [ctypes.POINTER(TcmRig), ctypes.POINTER(TcmState)]
    lib.tcm_csv_rows.restype = _SZ
    lib.tcm_csv_rows.argtypes = [_PD, _PD, _SZ, _SZ, ctypes.c_char_p, _SZ, _PSZ]
    return lib
