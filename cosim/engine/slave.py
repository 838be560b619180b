"""The slave protocol (one FMU instance as the master sees it) and its fmpy implementation.

The master and its algorithms talk to sub-models only through :class:`Slave`: instantiate,
set up, set/get values, do a step, get/set/free the state, terminate. :class:`FmpySlave` implements
it for FMI 2.0 co-simulation FMUs through fmpy: fmpy extracts the FMU, loads its library and
declares the C signatures; the hot calls (get/set values, doStep, state) then go straight to the
loaded functions, without fmpy's per-call Python wrapper.

Every FMI status is checked in one place, :meth:`FmpySlave._check`: ``fmi2Discard`` from
``doStep`` comes back as :data:`DISCARD` (the master may roll back and shrink the step); any
other failure raises :class:`~tribocosim.errors.CosimStepError` naming the instance, the FMI
function, the time and the FMU's last log messages.

Wall time spent inside each slave's FMI calls is accumulated in ``slave.wall_time`` so that the
master can report its own overhead separately.
"""

from __future__ import annotations

import ctypes
import itertools
import time
import weakref
from collections import deque
from pathlib import Path
from typing import Any, Protocol, Sequence, runtime_checkable

import numpy as np
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Slave,
    calloc,
    fmi2Boolean,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    fmi2FMUstate,
    fmi2Integer,
    fmi2Real,
    fmi2ValueReference,
    free,
)

from tribocosim.errors import CosimStepError
from tribocosim.lazy import WARNING, log
from tribocosim.cosim.engine.libraries import keep

LOG = "tribocosim.cosim"  # the logger of the FMUs' messages

#: do_step outcomes
OK = 0
DISCARD = 2
#: the FMI 2.0 status after which no function of any instance of the FMU may be called (FMI 2.0.4, section 2.1.3)
ERROR, FATAL = 3, 4

#: FMI functions called on hot paths without fmpy's Python wrapper
_HOT = ("fmi2SetReal", "fmi2GetReal", "fmi2SetInteger", "fmi2GetInteger", "fmi2SetBoolean", "fmi2GetBoolean",
        "fmi2DoStep", "fmi2GetFMUstate", "fmi2SetFMUstate", "fmi2FreeFMUstate")
_LABELS = ("ok", "warning", "discard", "error", "fatal", "pending")

# FMU log messages: one logger function for the whole process. fmpy's native proxy (which
# formats the variadic arguments) keeps the *last* registered logger in a global, so a logger
# per slave would leave that global pointing at a freed callback once the slave is collected.
# The single logger dispatches on the component environment, which carries the slave's key.
_SLAVES: "weakref.WeakValueDictionary[int, FmpySlave]" = weakref.WeakValueDictionary()
_KEYS = itertools.count(1)


def _dispatch_log(env, instance, status, category, message) -> None:
    slave = _SLAVES.get(env or 0)
    if slave is not None:
        slave._log(status, message)


_LOGGER = fmi2CallbackLoggerTYPE(_dispatch_log)
# The callbacks of the instances dropped without fmi2FreeInstance (FmpySlave.abandon): such an instance lives, with the
# address of its callbacks (pythonfmu keeps it in the instance's logger, fmi2.cpp), as long as the process does.
_ABANDONED: list = []


@runtime_checkable
class Slave(Protocol):
    """What the master needs of one sub-model instance."""

    name: str
    can_roll_back: bool
    can_interpolate_inputs: bool
    wall_time: float
    calls: dict[str, int]  # FMI calls made, by function (doStep, getFMUstate, ...)
    messages: Sequence[str]  # the last log messages of the FMU (for error messages)
    unzip_dir: Path  # the FMU's folder: the instances of one FMU share its library
    fatal: bool  # a function returned fmi2Fatal: no function of any instance of the FMU may be called again

    def instantiate(self) -> None: ...

    def setup(self, start: float, stop: float | None, tolerance: float | None = None) -> None:
        """``fmi2SetupExperiment`` and ``fmi2EnterInitializationMode``."""

    def exit_initialization(self) -> None: ...

    def set_real(self, refs: Sequence[int], values: Sequence[float]) -> None: ...

    def get_real(self, refs: Sequence[int]) -> np.ndarray: ...

    def set_integer(self, refs: Sequence[int], values: Sequence[int]) -> None: ...

    def get_integer(self, refs: Sequence[int]) -> np.ndarray: ...

    def set_boolean(self, refs: Sequence[int], values: Sequence[bool]) -> None: ...

    def get_boolean(self, refs: Sequence[int]) -> np.ndarray: ...

    def set_string(self, refs: Sequence[int], values: Sequence[str]) -> None: ...

    def get_string(self, refs: Sequence[int]) -> list[str]: ...

    def set_input_derivatives(self, refs: Sequence[int], order: int, values: Sequence[float]) -> None: ...

    def do_step(self, t: float, h: float) -> int:
        """Advance from t to t + h; return :data:`OK` or :data:`DISCARD`."""

    def get_state(self) -> Any: ...

    def set_state(self, state: Any) -> None: ...

    def free_state(self, state: Any) -> None: ...

    def terminate(self) -> None: ...

    def abandon(self) -> None:
        """Drop the instance without an FMI call (after fmi2Fatal of its FMU)."""


class FmpySlave:
    """An FMI 2.0 co-simulation FMU instance driven through fmpy.

    Parameters
    ----------
    name : str
        Instance name (from the scene).
    unzip_dir : Path
        Folder the FMU was extracted to.
    model_description : fmpy.model_description.ModelDescription
        The FMU's model description (already read and validated).
    """

    def __init__(self, name: str, unzip_dir: Path, model_description) -> None:
        cs = model_description.coSimulation
        self.name = name
        self.model_description = model_description
        self.unzip_dir = Path(unzip_dir)
        self.can_roll_back = bool(cs.canGetAndSetFMUstate)
        self.can_interpolate_inputs = bool(cs.canInterpolateInputs)
        self.wall_time = 0.0
        self.calls = {"doStep": 0, "getFMUstate": 0, "setFMUstate": 0}
        self.messages: deque[str] = deque(maxlen=20)
        self.warnings = 0  # messages logged with a status of warning or worse
        #: an FMI function of this instance returned fmi2Fatal
        self.fatal = False
        #: an FMI function of this instance returned fmi2Error or fmi2Fatal: fmi2Terminate is not called
        self.errored = False
        self.current_time = float("nan")
        self._fmu = None
        self._callbacks = None  # the fmi2CallbackFunctions given to fmi2Instantiate
        self._dll: dict[str, Any] = {}
        self._arrays: dict[tuple, Any] = {}

    # --- FMI status handling: the one place that turns FMI failures into exceptions ----------
    def _check(self, function: str, status: int) -> int:
        """Return ``status`` if ok/warning (or discard from doStep); raise CosimStepError otherwise."""
        if status <= 1 or (status == DISCARD and function == "fmi2DoStep"):
            return status
        self.fatal = self.fatal or status == FATAL
        self.errored = self.errored or status >= ERROR
        label = _LABELS[status] if 0 <= status < len(_LABELS) else "illegal status"
        raise CosimStepError(self._failure(function, f"status {status}, {label}"))

    def _raw(self, function: str, *args) -> int:
        """Call an FMI function of the loaded library directly (hot paths), time it, check it."""
        t0 = time.perf_counter()
        status = self._dll[function](*args)
        self.wall_time += time.perf_counter() - t0
        return status if status <= 1 else self._check(function, status)

    def _call(self, function: str, fn, *args):
        """Call one of fmpy's FMI wrappers (life cycle), time it, turn its exception into ours."""
        t0 = time.perf_counter()
        try:
            return fn(*args)
        except FMICallException as exc:
            return self._check(function, exc.status)
        except OSError as exc:  # crash inside the shared library
            raise CosimStepError(self._failure(function, str(exc))) from exc
        finally:
            self.wall_time += time.perf_counter() - t0

    def _failure(self, function: str, what: str) -> str:
        msg = f"FMU instance '{self.name}': {function} failed ({what}) at t = {self.current_time:.9g} s"
        if self.messages:
            msg += "; last FMU messages:\n  " + "\n  ".join(list(self.messages)[-5:])
        return msg

    def _log(self, status: int, message: bytes | None) -> None:
        text = (message or b"").decode("utf-8", "replace").strip()
        label = _LABELS[status] if 0 <= status < len(_LABELS) else str(status)
        self.messages.append(f"[{label}] {text}")
        if status >= 1:
            self.warnings += 1
            log(LOG, WARNING, "FMU %s: [%s] %s", self.name, label, text)

    def _refs(self, refs: Sequence[int]):
        key = tuple(refs)
        arr = self._arrays.get(key)
        if arr is None:
            arr = self._arrays[key] = (fmi2ValueReference * len(refs))(*refs)
        return arr

    # --- life cycle --------------------------------------------------------------------------
    def instantiate(self) -> None:
        """Load the shared library and ``fmi2Instantiate`` (FMU log messages go to ``messages``)."""
        md = self.model_description
        t0 = time.perf_counter()
        try:
            self._fmu = FMU2Slave(
                guid=md.guid,
                unzipDirectory=str(self.unzip_dir),
                modelIdentifier=md.coSimulation.modelIdentifier,
                instanceName=self.name,
            )
            keep(self._fmu.dll._name)  # the library stays loaded to the end of the process (libraries.keep)
            key = next(_KEYS)
            _SLAVES[key] = self
            cb = fmi2CallbackFunctions()
            cb.logger = _LOGGER
            cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
            cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
            cb.componentEnvironment = key
            try:
                from fmpy.logging import addLoggerProxy

                addLoggerProxy(ctypes.byref(cb))
            except Exception:  # pragma: no cover - the proxy only formats variadic messages
                pass
            self._callbacks = cb  # keep alive as long as the instance
            self._fmu.instantiate(callbacks=cb, loggingOn=True)
        except Exception as exc:
            raise CosimStepError(f"FMU instance '{self.name}': cannot load or instantiate: {exc}") from exc
        finally:
            self.wall_time += time.perf_counter() - t0
        self._c = self._fmu.component
        self._dll = {name: getattr(self._fmu.dll, name) for name in _HOT}

    def setup(self, start: float, stop: float | None, tolerance: float | None = None) -> None:
        """Set up the experiment and enter initialization mode."""
        self.current_time = start
        self._call("fmi2SetupExperiment", self._fmu.setupExperiment, tolerance, start, stop)
        self._call("fmi2EnterInitializationMode", self._fmu.enterInitializationMode)

    def exit_initialization(self) -> None:
        """Leave initialization mode (the FMU is then in step mode)."""
        self._call("fmi2ExitInitializationMode", self._fmu.exitInitializationMode)

    def terminate(self) -> None:
        """``fmi2Terminate`` and free the instance as the FMI 2.0 state machine allows (section 2.1.5): after
        fmi2Error only ``fmi2FreeInstance``, after fmi2Fatal nothing (:meth:`abandon`). Errors while freeing are
        logged only."""
        if self._fmu is None:
            return
        try:
            if not self.errored:
                self._call("fmi2Terminate", self._fmu.terminate)
        finally:
            if self.fatal:
                self.abandon()
            else:
                try:
                    self._fmu.freeInstance()
                except Exception as exc:  # pragma: no cover
                    log(LOG, WARNING, "FMU %s: freeInstance failed: %s", self.name, exc)
                self._fmu = None
                self._dll = {}

    def abandon(self) -> None:
        """Drop the instance without an FMI call: after fmi2Fatal of any instance of its FMU, no function of any of
        them may be called (FMI 2.0.4, section 2.1.3), fmi2FreeInstance included (a pythonfmu FMU releases the Python
        objects of an instance that raised once more when it is freed). The instance, its library (kept by
        :func:`~tribocosim.cosim.engine.libraries.keep`) and the callbacks it was given stay for the process."""
        if self._fmu is not None and self._callbacks is not None:
            _ABANDONED.append(self._callbacks)
        self._fmu = None
        self._dll = {}

    @property
    def loaded(self) -> bool:
        """True between :meth:`instantiate` and :meth:`terminate`."""
        return self._fmu is not None

    def fmi_functions(self) -> dict[str, int]:
        """The addresses of the hot FMI functions of the loaded library (for a native loop that calls them)."""
        return {name: ctypes.cast(fn, ctypes.c_void_p).value for name, fn in self._dll.items()}

    def component_address(self) -> int:
        """The address of the FMI instance (``fmi2Component``)."""
        return int(self._c)

    # --- values ------------------------------------------------------------------------------
    def set_real(self, refs: Sequence[int], values: Sequence[float]) -> None:
        n = len(refs)
        if n:
            self._raw("fmi2SetReal", self._c, self._refs(refs), n, (fmi2Real * n)(*values))

    def get_real(self, refs: Sequence[int]) -> np.ndarray:
        n = len(refs)
        out = (fmi2Real * n)()
        if n:
            self._raw("fmi2GetReal", self._c, self._refs(refs), n, out)
        return np.frombuffer(out, dtype=np.float64).copy()

    def set_integer(self, refs: Sequence[int], values: Sequence[int]) -> None:
        n = len(refs)
        if n:
            vals = (fmi2Integer * n)(*[int(round(v)) for v in values])
            self._raw("fmi2SetInteger", self._c, self._refs(refs), n, vals)

    def get_integer(self, refs: Sequence[int]) -> np.ndarray:
        n = len(refs)
        out = (fmi2Integer * n)()
        if n:
            self._raw("fmi2GetInteger", self._c, self._refs(refs), n, out)
        return np.array(list(out), dtype=float)

    def set_boolean(self, refs: Sequence[int], values: Sequence[bool]) -> None:
        n = len(refs)
        if n:
            vals = (fmi2Boolean * n)(*[1 if v else 0 for v in values])
            self._raw("fmi2SetBoolean", self._c, self._refs(refs), n, vals)

    def get_boolean(self, refs: Sequence[int]) -> np.ndarray:
        n = len(refs)
        out = (fmi2Boolean * n)()
        if n:
            self._raw("fmi2GetBoolean", self._c, self._refs(refs), n, out)
        return np.array([1.0 if v else 0.0 for v in out])

    def set_string(self, refs: Sequence[int], values: Sequence[str]) -> None:
        if refs:
            self._call("fmi2SetString", self._fmu.setString, list(refs), [str(v) for v in values])

    def get_string(self, refs: Sequence[int]) -> list[str]:
        if not refs:
            return []
        raw = self._call("fmi2GetString", self._fmu.getString, list(refs))
        return [v.decode("utf-8") if isinstance(v, bytes) else str(v) for v in raw]

    def set_input_derivatives(self, refs: Sequence[int], order: int, values: Sequence[float]) -> None:
        """``fmi2SetRealInputDerivatives`` (only for FMUs with ``canInterpolateInputs``)."""
        if refs:
            self._call("fmi2SetRealInputDerivatives", self._fmu.setRealInputDerivatives,
                       list(refs), [order] * len(refs), list(values))

    # --- stepping and state ------------------------------------------------------------------
    def do_step(self, t: float, h: float) -> int:
        """``fmi2DoStep(t, h)``; returns :data:`OK` or :data:`DISCARD`, raises on error."""
        self.current_time = t
        self.calls["doStep"] += 1
        return DISCARD if self._raw("fmi2DoStep", self._c, t, h, 1) == DISCARD else OK

    def get_state(self) -> Any:
        """``fmi2GetFMUstate`` into a new state handle (refused if the FMU does not declare it)."""
        if not self.can_roll_back:
            raise CosimStepError(f"FMU instance '{self.name}': fmi2GetFMUstate is not allowed, the FMU cannot roll back "
                                 "(canGetAndSetFMUstate = false)")
        self.calls["getFMUstate"] += 1
        state = fmi2FMUstate()
        self._raw("fmi2GetFMUstate", self._c, ctypes.byref(state))
        return state

    def set_state(self, state: Any) -> None:
        """``fmi2SetFMUstate`` (the handle stays valid)."""
        self.calls["setFMUstate"] += 1
        self._raw("fmi2SetFMUstate", self._c, state)

    def free_state(self, state: Any) -> None:
        """``fmi2FreeFMUstate``."""
        self._raw("fmi2FreeFMUstate", self._c, ctypes.byref(state))
