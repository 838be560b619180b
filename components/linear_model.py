"""The binding of the native linear models (press, drawing machine): one class, the model named by its prefix; and
the native matrix exponential (``tc_expm``: balancing, then scaling and squaring of a Taylor polynomial)."""

from __future__ import annotations

import ctypes

import numpy as np

from tribocosim.components.native.toolchain.library import DBL_P, VP, core, ptr


def expm(M) -> np.ndarray:
    """exp(M) of a square matrix of at most 16 rows (the native core's; ParameterError if it is not finite or too
    large to scale)."""
    M = np.ascontiguousarray(M, dtype=float)
    E = np.empty_like(M)
    c = core()
    c.call(c.lib.tc_expm, M.shape[0], ptr(M), ptr(E))
    return E


class NativeLinearModel:
    """``step(dt, inputs) -> outputs``, ``outputs()``, ``get_state()`` (bytes as a uint8 array), ``set_state()``
    and ``time`` over the native model ``PREFIX`` (``tc_press``, ``tc_machine``). A refused step raises
    ParameterError and leaves the state unchanged."""

    OUTPUT_NAMES: tuple[str, ...] = ()
    INPUT_NAMES: tuple[str, ...] = ()
    PREFIX = ""
    N_STATES = 0  # the state vector z, after the state image's 8-byte header

    def __init__(self, params):
        self.params = params
        c = self._core = core()
        self._fn = {name: getattr(c.lib, f"{self.PREFIX}_{name}") for name in (
            "create", "free", "step", "outputs", "state_size", "get_state", "set_state", "time")}
        self._struct = c.struct(params)
        self._handle = VP()
        c.call(self._fn["create"], ctypes.byref(self._struct), ctypes.byref(self._handle))

    @property
    def time(self) -> float:
        """The model's time [s] (the sum of the steps)."""
        return float(self._fn["time"](self._handle))

    def __del__(self):
        if getattr(self, "_handle", None):
            self._fn["free"](self._handle)
            self._handle = None

    def step(self, dt: float, inputs: dict | None = None) -> dict:
        """Advance by ``dt`` [s] with the inputs held; return the outputs."""
        args = [float((inputs or {})[name]) for name in self.INPUT_NAMES]
        self._core.call(self._fn["step"], self._handle, float(dt), *args)
        return self.outputs()

    def outputs(self) -> dict:
        """The outputs of the current state."""
        out = (ctypes.c_double * len(self.OUTPUT_NAMES))()
        self._fn["outputs"](self._handle, ctypes.cast(out, DBL_P))
        return dict(zip(self.OUTPUT_NAMES, out))

    @property
    def state(self) -> np.ndarray:
        """The state vector z (a copy)."""
        return np.frombuffer(self.get_state()[8:8 + 8 * self.N_STATES].tobytes(), dtype=np.float64).copy()

    def get_state(self) -> np.ndarray:
        """The state as bytes (a uint8 array)."""
        buf = np.empty(self._fn["state_size"](self._handle), dtype=np.uint8)
        self._fn["get_state"](self._handle, buf.ctypes.data_as(VP))
        return buf

    def set_state(self, state) -> None:
        """Restore a state from :meth:`get_state`."""
        buf = np.ascontiguousarray(state, dtype=np.uint8)
        self._core.call(self._fn["set_state"], self._handle, buf.ctypes.data_as(VP), buf.size)
