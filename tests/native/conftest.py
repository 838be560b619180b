"""Session fixtures of the native (C) model tests: the sources compiled once, loaded with ctypes.

- ``native_core``: the core library (strip draw, table lookup, linear algebra, press, machine) built for
  linux64 with ``-DTC_EXPORT_CORE`` from :data:`CORE_SOURCES` into a session temp folder, wrapped in
  :class:`Core` (ctypes prototypes, parameter structs generated from the Python dataclasses, and small
  wrappers with the Python models' interface).

The table-file reader (``tc_table_file.c`` and its helpers) is not part of this library; its tests build
their own. Fixture names start with ``native_`` so that they do not collide with other fixtures here.
"""

from __future__ import annotations

import ctypes
from pathlib import Path
import dataclasses

import numpy as np
import pytest

from tribocosim.components.native.toolchain import SOURCE_DIR, compile_shared

#: the C sources of the core library, listed explicitly (not the table-file reader)
CORE_SOURCES = (
    "tc_common.c",
    "tc_table.c",
    "tc_table_lookup.c",
    "tc_stripdraw.c",
    "tc_galpha.c",
    "tc_linear.c",
    "tc_press.c",
    "tc_machine.c",
)

TC_OK, TC_DISCARD, TC_ERROR, TC_NOMEM = 0, 1, 2, 3
N_STRIPDRAW_OUTPUTS = 9

_dbl_p = ctypes.POINTER(ctypes.c_double)
_byte_p = ctypes.POINTER(ctypes.c_byte)
_ubyte_p = ctypes.POINTER(ctypes.c_ubyte)
_size = ctypes.c_size_t
_dbl = ctypes.c_double
_int = ctypes.c_int
_vp = ctypes.c_void_p


class Msg(ctypes.Structure):
    """``tc_msg``: a message buffer (text, capacity) passed by value."""

    _fields_ = [("text", ctypes.c_void_p), ("size", ctypes.c_size_t)]


class NativeError(Exception):
    """A native call returned a status other than TC_OK; ``status`` and the message are kept."""

    def __init__(self, status: int, message: str):
        super().__init__(f"status {status}: {message}")
        self.status = status
        self.message = message


def params_struct(cls):
    """A ctypes Structure with one member per field of the parameter dataclass ``cls``, in its order:
    float -> double, integer -> int, choices -> int (index), text -> const char * (the C headers' rule)."""
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
    """Fill a params struct from a parameter dataclass instance (choices as their index)."""
    s = struct_cls()
    for f in dataclasses.fields(params):
        value = getattr(params, f.name)
        if "choices" in f.metadata:
            value = f.metadata["choices"].index(value)
        elif f.metadata.get("text"):
            value = value.encode()
        setattr(s, f.name, value)
    return s


def _ptr(a: np.ndarray, ctype=_dbl_p):
    return a.ctypes.data_as(ctype)


class Core:
    """The core library with its prototypes, and helpers that call it like the Python models.

    :class:`NativeError` is an attribute, so that the test modules need not import this file (they are
    imported with ``--import-mode=importlib``)."""

    NativeError = NativeError

    def __init__(self, path):
        from tribocosim.components.machine import MachineParameters
        from tribocosim.components.press import PressParameters
        from tribocosim.components.stripdraw.parameters import StripDrawParameters

        self.path = path
        self.lib = lib = ctypes.CDLL(str(path))
        self.StripDrawParams = params_struct(StripDrawParameters)
        self.PressParams = params_struct(PressParameters)
        self.MachineParams = params_struct(MachineParameters)
        proto = {
            "tc_table_from_arrays": (_int, [_size, _size, _size, _dbl_p, _dbl_p, _dbl_p, _dbl_p, _dbl,
                                            ctypes.POINTER(_vp), Msg]),
            "tc_table_set_areas": (_int, [_vp, _dbl_p, _dbl_p, _dbl_p, _dbl_p, Msg]),
            "tc_table_free": (None, [_vp]),
            "tc_table_mu": (_int, [_vp, _dbl, _size, _dbl_p, _dbl_p, _int, _dbl_p, _ubyte_p, Msg]),
            "tc_table_lookup2": (_int, [_vp, _dbl_p, _dbl_p, _dbl, _size, _dbl_p, _dbl_p, _int, _dbl_p, _dbl_p, _ubyte_p,
                                        Msg]),
            "tc_stripdraw_create": (_int, [ctypes.POINTER(self.StripDrawParams), _vp, _dbl_p, _size,
                                           ctypes.POINTER(_vp), Msg]),
            "tc_stripdraw_free": (None, [_vp]),
            "tc_stripdraw_step": (_int, [_vp, _dbl, _dbl, _dbl, Msg]),
            "tc_stripdraw_step_poly": (_int, [_vp, _dbl, _dbl, _dbl_p, _dbl, _dbl_p, Msg]),
            "tc_stripdraw_outputs": (None, [_vp, _dbl_p]),
            "tc_stripdraw_state_size": (_size, [_vp]),
            "tc_stripdraw_get_state": (None, [_vp, _vp]),
            "tc_stripdraw_set_state": (_int, [_vp, _vp, _size, Msg]),
            "tc_stripdraw_n_nodes": (_size, [_vp]),
            "tc_stripdraw_fields": (None, [_vp, _dbl_p, _dbl_p, _dbl_p, _dbl_p, _dbl_p]),
            "tc_stripdraw_window": (None, [_vp, _dbl_p]),
            "tc_stripdraw_time": (_dbl, [_vp]),
            "tc_stripdraw_beta_cap": (_dbl, [_vp]),
            "tc_stripdraw_explicit_time_step": (_dbl, [_vp]),
            "tc_sd_positive_range": (_int, [_size, _dbl_p, ctypes.POINTER(_size), ctypes.POINTER(_size)]),
            "tc_pairwise_sum_range": (_dbl, [_dbl_p, _size, _size, _size]),
            "tc_sd_overlap": (None, [_size, _dbl_p, _dbl_p, _dbl, _dbl, _dbl, _dbl_p]),
            "tc_thomas": (None, [_size, _dbl_p, _dbl_p, _dbl_p, _dbl_p, _dbl_p, _dbl_p]),
            "tc_sd_explicit": (None, [_size, ctypes.c_longlong, _dbl, _dbl_p, _dbl_p, _dbl_p, _dbl_p, _byte_p,
                                      _dbl_p, _dbl_p, _dbl, _dbl, _dbl, _dbl, _dbl, _dbl, _dbl_p, _dbl, _dbl_p,
                                      _dbl_p, _dbl_p]),
            "tc_sd_galpha": (_int, [_size, _dbl, _dbl_p, _dbl_p, _dbl_p, _dbl_p, _byte_p, _dbl_p, _dbl_p, _dbl_p,
                                    _dbl, _dbl, _dbl, _dbl_p, _dbl, _dbl, _dbl, _dbl, _dbl, _int, _dbl, _dbl_p,
                                    _dbl_p, _dbl_p, _dbl_p, _byte_p]),
            "tc_sd_chain_factors": (None, [_size, _dbl, _dbl_p, _dbl, _dbl_p]),
            "tc_sd_advect": (None, [_size, _dbl_p, _dbl_p, _dbl_p, _dbl, _dbl, _dbl_p, _dbl_p]),
            "tc_balance": (None, [_size, _dbl_p, _dbl_p]),
            "tc_expm": (_int, [_size, _dbl_p, _dbl_p, Msg]),
            "tc_press_create": (_int, [ctypes.POINTER(self.PressParams), ctypes.POINTER(_vp), Msg]),
            "tc_press_free": (None, [_vp]),
            "tc_press_step": (_int, [_vp, _dbl, Msg]),
            "tc_press_outputs": (None, [_vp, _dbl_p]),
            "tc_press_state_size": (_size, [_vp]),
            "tc_press_get_state": (None, [_vp, _vp]),
            "tc_press_set_state": (_int, [_vp, _vp, _size, Msg]),
            "tc_machine_create": (_int, [ctypes.POINTER(self.MachineParams), ctypes.POINTER(_vp), Msg]),
            "tc_machine_free": (None, [_vp]),
            "tc_machine_step": (_int, [_vp, _dbl, _dbl, Msg]),
            "tc_machine_outputs": (None, [_vp, _dbl_p]),
            "tc_machine_state_size": (_size, [_vp]),
            "tc_machine_get_state": (None, [_vp, _vp]),
            "tc_machine_set_state": (_int, [_vp, _vp, _size, Msg]),
        }
        for name, (res, args) in proto.items():
            fn = getattr(lib, name)
            fn.restype = res
            fn.argtypes = args
        self._buf = ctypes.create_string_buffer(1024)

    # -------------------------------------------------------------------------------- messages
    def msg(self) -> Msg:
        """A fresh message buffer (cleared)."""
        self._buf.value = b""
        return Msg(ctypes.addressof(self._buf), len(self._buf))

    def last_message(self) -> str:
        return self._buf.value.decode()

    def check(self, status: int) -> None:
        if status != TC_OK:
            raise NativeError(status, self.last_message())

    # -------------------------------------------------------------------------------- objects
    def table(self, table):
        """A native table (freed with the returned handle's owner) from a FrictionTable."""
        return NativeTable(self, table)

    def stripdraw(self, params, table=None, beta_field=None):
        return NativeStripDraw(self, params, table, beta_field)

    def press(self, params, **overrides):
        """A native press; ``overrides`` set struct members (e.g. a setpoint_table PressParameters refuses)."""
        return NativeLinearModel(self, "press", params, self.PressParams, overrides)

    def machine(self, params, **overrides):
        return NativeLinearModel(self, "machine", params, self.MachineParams, overrides)


class NativeTable:
    """A ``tc_table`` built with tc_table_from_arrays from a FrictionTable (and tc_table_set_areas for a
    version 2 table)."""

    def __init__(self, core: Core, table):
        self.core = core
        self.arrays = [np.ascontiguousarray(a, dtype=float) for a in (table.pressure, table.velocity, table.beta,
                                                                      table.mu)]
        p, v, b, mu = self.arrays
        handle = _vp()
        core.check(core.lib.tc_table_from_arrays(p.size, v.size, b.size, _ptr(p), _ptr(v), _ptr(b), _ptr(mu),
                                                 table.beta_threshold, ctypes.byref(handle), core.msg()))
        self.handle = handle
        if table.version == 2:
            areas = [np.ascontiguousarray(getattr(table, name), dtype=float)
                     for name in ("contact_area", "particle_area", "contact_area_std", "particle_area_std")]
            self.arrays += areas
            core.check(core.lib.tc_table_set_areas(handle, *(_ptr(a) for a in areas), core.msg()))

    def mu(self, pressure: float, velocity, beta, policy: int):
        """tc_table_mu -> (mu, clamped); raises NativeError with the C message."""
        v = np.ascontiguousarray(velocity, dtype=float)
        b = np.ascontiguousarray(beta, dtype=float)
        mu = np.zeros(v.size)
        clamped = np.zeros(v.size, dtype=np.uint8)
        self.core.check(self.core.lib.tc_table_mu(self.handle, pressure, v.size, _ptr(v), _ptr(b), policy, _ptr(mu),
                                                  _ptr(clamped, _ubyte_p), self.core.msg()))
        return mu, clamped.astype(bool)

    def lookup2(self, a, b_values, pressure: float, velocity, beta, policy: int):
        """tc_table_lookup2 of two arrays laid out like mu -> (a, b, clamped); raises NativeError."""
        a, b_values = (np.ascontiguousarray(x, dtype=float) for x in (a, b_values))
        v = np.ascontiguousarray(velocity, dtype=float)
        b = np.ascontiguousarray(beta, dtype=float)
        out_a, out_b = np.zeros(v.size), np.zeros(v.size)
        clamped = np.zeros(v.size, dtype=np.uint8)
        self.core.check(self.core.lib.tc_table_lookup2(self.handle, _ptr(a), _ptr(b_values), pressure, v.size, _ptr(v),
                                                       _ptr(b), policy, _ptr(out_a), _ptr(out_b),
                                                       _ptr(clamped, _ubyte_p), self.core.msg()))
        return out_a, out_b, clamped.astype(bool)

    def __del__(self):
        if getattr(self, "handle", None):
            self.core.lib.tc_table_free(self.handle)
            self.handle = None


class NativeStripDraw:
    """tc_stripdraw with the interface of StripDrawModel (step -> outputs dict, get/set state, fields)."""

    def __init__(self, core: Core, params, table=None, beta_field=None):
        from tribocosim.components.stripdraw.model import OUTPUT_NAMES

        self.core = core
        self.names = OUTPUT_NAMES
        self.table = core.table(table) if table is not None else None
        self._params = to_struct(core.StripDrawParams, params)
        bf = None if beta_field is None else np.ascontiguousarray(beta_field, dtype=float)
        handle = _vp()
        status = core.lib.tc_stripdraw_create(ctypes.byref(self._params), self.table.handle if self.table else None,
                                              None if bf is None else _ptr(bf), 0 if bf is None else bf.size,
                                              ctypes.byref(handle), core.msg())
        core.check(status)
        self.handle = handle
        self.n_nodes = core.lib.tc_stripdraw_n_nodes(handle)

    def step_status(self, dt, normal_force, grip_velocity) -> int:
        """The raw status of one step (the message is in core.last_message())."""
        return self.core.lib.tc_stripdraw_step(self.handle, dt, normal_force, grip_velocity, self.core.msg())

    def step(self, dt, inputs: dict, derivatives: dict | None = None) -> dict:
        if derivatives is None:
            self.core.check(self.step_status(dt, inputs["normal_force"], inputs["grip_velocity"]))
        else:
            d = {k: np.ascontiguousarray(derivatives.get(k, (0.0, 0.0)), dtype=float)
                 for k in ("normal_force", "grip_velocity")}
            self.core.check(self.core.lib.tc_stripdraw_step_poly(
                self.handle, dt, inputs["normal_force"], _ptr(d["normal_force"]), inputs["grip_velocity"],
                _ptr(d["grip_velocity"]), self.core.msg()))
        return self.outputs()

    def outputs(self) -> dict:
        out = np.zeros(N_STRIPDRAW_OUTPUTS)
        self.core.lib.tc_stripdraw_outputs(self.handle, _ptr(out))
        return dict(zip(self.names, out.tolist()))

    def get_state(self) -> bytes:
        buf = ctypes.create_string_buffer(self.core.lib.tc_stripdraw_state_size(self.handle))
        self.core.lib.tc_stripdraw_get_state(self.handle, buf)
        return buf.raw

    def set_state(self, state: bytes) -> None:
        self.core.check(self.core.lib.tc_stripdraw_set_state(self.handle, state, len(state), self.core.msg()))

    def fields(self) -> dict:
        n = self.n_nodes
        arrays = {k: np.zeros(n) for k in ("X", "U", "beta", "slip", "contact")}
        self.core.lib.tc_stripdraw_fields(self.handle, *(_ptr(arrays[k]) for k in ("X", "U", "beta", "slip",
                                                                                     "contact")))
        return arrays

    def window(self):
        w = np.zeros(2)
        self.core.lib.tc_stripdraw_window(self.handle, _ptr(w))
        return w

    @property
    def time(self) -> float:
        return self.core.lib.tc_stripdraw_time(self.handle)

    @property
    def beta_cap(self) -> float:
        return self.core.lib.tc_stripdraw_beta_cap(self.handle)

    @property
    def explicit_time_step(self) -> float:
        return self.core.lib.tc_stripdraw_explicit_time_step(self.handle)

    def __del__(self):
        if getattr(self, "handle", None):
            self.core.lib.tc_stripdraw_free(self.handle)
            self.handle = None


class NativeLinearModel:
    """tc_press / tc_machine with the interface of PressModel / MachineModel."""

    def __init__(self, core: Core, kind: str, params, struct_cls, overrides=None):
        from tribocosim.components.machine import MachineModel
        from tribocosim.components.press import PressModel

        self.core, self.kind = core, kind
        self.names = (PressModel if kind == "press" else MachineModel).OUTPUT_NAMES
        self._params = to_struct(struct_cls, params)
        for name, value in (overrides or {}).items():
            setattr(self._params, name, value.encode() if isinstance(value, str) else value)
        self._fn = {name: getattr(core.lib, f"tc_{kind}_{name}") for name in (
            "create", "free", "step", "outputs", "state_size", "get_state", "set_state")}
        handle = _vp()
        core.check(self._fn["create"](ctypes.byref(self._params), ctypes.byref(handle), core.msg()))
        self.handle = handle

    def step_status(self, dt, inputs=None) -> int:
        if self.kind == "press":
            return self._fn["step"](self.handle, dt, self.core.msg())
        return self._fn["step"](self.handle, dt, inputs["pull_force"], self.core.msg())

    def step(self, dt, inputs=None) -> dict:
        self.core.check(self.step_status(dt, inputs))
        return self.outputs()

    def outputs(self) -> dict:
        out = np.zeros(len(self.names))
        self._fn["outputs"](self.handle, _ptr(out))
        return dict(zip(self.names, out.tolist()))

    def get_state(self) -> bytes:
        buf = ctypes.create_string_buffer(self._fn["state_size"](self.handle))
        self._fn["get_state"](self.handle, buf)
        return buf.raw

    def set_state(self, state: bytes) -> None:
        self.core.check(self._fn["set_state"](self.handle, state, len(state), self.core.msg()))

    def __del__(self):
        if getattr(self, "handle", None):
            self._fn["free"](self.handle)
            self.handle = None


@pytest.fixture(scope="session")
def native_headers(tmp_path_factory) -> Path:
    """A folder with the parameter headers generated from the component descriptions (as the FMU build does)."""
    from tribocosim.components import registry
    from tribocosim.components.native.declarations import write_params_headers

    folder = tmp_path_factory.mktemp("native_headers")
    write_params_headers(folder, registry.components().values())
    return folder


@pytest.fixture(scope="session")
def native_core(tmp_path_factory, native_headers) -> Core:
    """The core library, compiled once per session for linux64 and loaded with ctypes."""
    out = tmp_path_factory.mktemp("native") / "libtc_core.so"
    compile_shared([SOURCE_DIR / name for name in CORE_SOURCES], out, "linux64", defines=["TC_EXPORT_CORE"],
                   include_dirs=[native_headers])
    return Core(out)


@pytest.fixture(scope="session")
def native_core_newton(tmp_path_factory, native_headers):
    """``build(max_iter) -> Core``: the core library with the Newton iteration limit of the generalized-alpha
    step lowered to ``max_iter`` (-DTC_STRIPDRAW_NEWTON_MAX_ITER), so that the step halving runs; built once
    per value."""
    cache: dict[int, Core] = {}

    def build(max_iter: int) -> Core:
        if max_iter not in cache:
            out = tmp_path_factory.mktemp(f"native_newton{max_iter}") / "libtc_core.so"
            compile_shared([SOURCE_DIR / name for name in CORE_SOURCES], out, "linux64",
                           defines=["TC_EXPORT_CORE", f"TC_STRIPDRAW_NEWTON_MAX_ITER={max_iter}"],
                           include_dirs=[native_headers])
            cache[max_iter] = Core(out)
        return cache[max_iter]

    return build


# Test-only allocator shim of the checked builds: live allocations are counted and the n-th allocation can be
# made to fail (tc_count_live, tc_count_fail_after), so that the tests can check that nothing leaks on any path.
_COUNT_H = r"""
#include <stdlib.h>
#include "tc_common.h"
TC_API void *tc_count_malloc(size_t n);
TC_API void *tc_count_calloc(size_t a, size_t b);
TC_API void *tc_count_realloc(void *p, size_t n);
TC_API void tc_count_free(void *p);
#define malloc(n) tc_count_malloc(n)
#define calloc(a, b) tc_count_calloc(a, b)
#define realloc(p, n) tc_count_realloc(p, n)
#define free(p) tc_count_free(p)
"""
_COUNT_C = r"""
#undef malloc
#undef calloc
#undef realloc
#undef free
static long live = 0, countdown = -1;
static int granted(void) {
    if (countdown == 0) return 0;
    if (countdown > 0) --countdown;
    return 1;
}
TC_API void *tc_count_malloc(size_t n) { void *p = granted() ? malloc(n) : NULL; if (p) ++live; return p; }
TC_API void *tc_count_calloc(size_t a, size_t b) { void *p = granted() ? calloc(a, b) : NULL; if (p) ++live; return p; }
TC_API void *tc_count_realloc(void *p, size_t n) {
    void *q = granted() ? realloc(p, n) : NULL;
    if (q && !p) ++live;
    return q;
}
TC_API void tc_count_free(void *p) { if (p) { --live; free(p); } }
TC_API long tc_count_live(void) { return live; }
TC_API void tc_count_fail_after(long n) { countdown = n; }
"""


@pytest.fixture(scope="session")
def native_checked_compile():
    """``build(sources, folder, name, defines=()) -> Path``: C sources (names in the native folder) compiled for
    linux64 with undefined behaviour trapping and the allocation-counting shim (test builds only)."""

    def build(sources, folder: Path, name: str, defines=()) -> Path:
        (folder / "tc_count.h").write_text(_COUNT_H)
        (folder / "tc_count.c").write_text(_COUNT_C)
        return compile_shared([*(SOURCE_DIR / s for s in sources), folder / "tc_count.c"], folder / name, "linux64",
                              defines=["TC_EXPORT_CORE", *defines],
                              extra_flags=["-include", str(folder / "tc_count.h"), "-fsanitize=undefined",
                                           "-fsanitize-trap=undefined"])

    return build
