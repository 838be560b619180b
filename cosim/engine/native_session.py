"""A fixed-step run on FMI 2.0 FMUs from instantiation to the last step, with the C master's library: no numpy, no
fmpy, no Python per step.

:class:`NativeSession` takes a run that the C loop takes (:func:`supported`: a fixed step, Jacobi or Gauss-Seidel
with held coupling values, Real links) and makes the FMI calls the Python master makes
(:class:`~tribocosim.cosim.engine.master.Master`, :class:`~tribocosim.cosim.engine.system.CoupledSystem`), in the
same order, with the same values:

1. each FMU's library loaded (ctypes), ``fmi2Instantiate`` with the library's logger (``tcm_logger``: the FMU's
   messages reach the logger :data:`LOG` as under :class:`~tribocosim.cosim.engine.slave.FmpySlave`), its parameters
   set by type (Real, Integer and Enumeration, Boolean, String), then ``fmi2SetupExperiment`` and
   ``fmi2EnterInitializationMode``;
2. as many output refreshes with propagation as there are slaves (``tcm_refresh``), ``fmi2ExitInitializationMode``,
   one more refresh; the feedthrough probe (``tcm_probe``), masked by the declared dependencies, from which the
   feedthrough of undeclared slaves, the algebraic loops and the evaluation order follow
   (:mod:`tribocosim.cosim.engine.graph`); one more refresh, and the start row recorded (``tcm_record_row``);
3. the loop (``tcm_run``), in chunks between which a progress reporter is told the time and a stop asked for by a
   signal (:mod:`tribocosim.interrupt`) ends the run at that communication point (:attr:`SessionResult.interrupted`);
4. the end-of-run outputs read, ``fmi2Terminate`` and ``fmi2FreeInstance``. The libraries stay loaded for the
   process (:func:`~tribocosim.cosim.engine.libraries.keep`: an FMU's extracted folder is named by its content, so a
   later run loads the same library again; an instance dropped after fmi2Fatal points into its library as long as
   the process lives; and a pythonfmu library's interpreter state is released at the interpreter's exit).

So its results are the Python loop's to the last bit (``tests/cosim/test_native_loop.py``). Anything it does not
take as the Python master would (an FMI status above warning, a discarded step, a non-finite value) frees the FMUs
and raises :class:`SessionStopped`: the caller (:func:`tribocosim.cosim.api.run`) then repeats the run with the
Python master, which reports or recovers it as it always does.
"""

from __future__ import annotations

import array
import ctypes
import itertools
import math
import sys
import time
from collections import deque
from pathlib import Path
from weakref import WeakValueDictionary

from tribocosim.errors import TribocosimError
from tribocosim.interrupt import stop_requested
from tribocosim.lazy import INFO, WARNING, log
from tribocosim.cosim.engine.graph import algebraic_loops, evaluation_order
from tribocosim.cosim.engine.libraries import keep
from tribocosim.cosim.engine.native_lib import (CHUNK, KINDS, SINK, TCM_DONE, TcmGet, TcmLogEnv, TcmRig, TcmSet,
                                                TcmSlave, TcmState, library, next_chunk)
from tribocosim.cosim.engine.schemes import LinkSpec, loop_message
from tribocosim.cosim.engine.timegrid import TimeGrid

LOG = "tribocosim.cosim"  # the logger of the FMUs' messages and the master's notes
_LABELS = ("ok", "warning", "discard", "error", "fatal", "pending")
_FATAL = 4
_VP, _I, _D, _SZ, _U = ctypes.c_void_p, ctypes.c_int, ctypes.c_double, ctypes.c_size_t, ctypes.c_uint
_PD, _PI, _PU, _PB = (ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_int), ctypes.POINTER(ctypes.c_uint),
                      ctypes.POINTER(ctypes.c_ubyte))


# FMU log messages: one sink for the whole process, and every instance's callbacks and environment kept for the
# process (a few dozen bytes each). An FMU may log after its instance was freed (a pythonfmu FMU's Python object,
# collected later in this interpreter): what it was given must still be readable and the sink still callable; a key
# whose instance is gone is dropped.
_FMUS: "WeakValueDictionary[int, _Fmu]" = WeakValueDictionary()
_KEYS = itertools.count(1)
_ENVS: list = []


def _dispatch(key, status, message) -> None:
    f = _FMUS.get(int(key or 0))
    if f is not None:
        f.log(status, message)


_SINK = SINK(_dispatch)


class SessionStopped(TribocosimError):
    """The session met something it leaves to the Python master (the message says what); the FMUs are freed."""


class _Callbacks(ctypes.Structure):
    """``fmi2CallbackFunctions``."""

    _fields_ = [("logger", _VP), ("allocateMemory", _VP), ("freeMemory", _VP), ("stepFinished", _VP),
                ("componentEnvironment", _VP)]


class SessionSlave:
    """One FMU instance of a session: its name, the folder its FMU is extracted to, its model identifier and GUID,
    the parameter values to set (``[(value reference, type, value), ...]``) and its declared feedthrough (None:
    probed)."""

    __slots__ = ("name", "folder", "model_identifier", "guid", "parameters", "feedthrough")

    def __init__(self, name: str, folder: Path, model_identifier: str, guid: str, parameters: list | None = None,
                 feedthrough: bool | None = None) -> None:
        self.name, self.folder, self.model_identifier, self.guid = name, folder, model_identifier, guid
        self.parameters = [] if parameters is None else parameters
        self.feedthrough = feedthrough


class SessionResult:
    """What a session did: the recorded rows (``times``; ``rows``: n_rows x n_columns, row after row), the counters
    and what the initialization found."""

    __slots__ = ("times", "rows", "steps", "min_step", "max_step", "feedthrough", "loops", "eval_order", "wall_times",
                 "do_steps", "loop_time", "warnings", "end_values", "interrupted", "fmu_warnings")

    def __init__(self, times: array.array, rows: array.array, steps: int, min_step: float, max_step: float,
                 feedthrough: list, loops: list, eval_order: list, wall_times: list, do_steps: list, loop_time: float,
                 warnings: list, end_values: list, interrupted: int | None = None,
                 fmu_warnings: list | None = None) -> None:
        self.times, self.rows, self.steps, self.min_step, self.max_step = times, rows, steps, min_step, max_step
        self.feedthrough, self.loops, self.eval_order, self.wall_times = feedthrough, loops, eval_order, wall_times
        self.do_steps, self.loop_time, self.warnings, self.end_values = do_steps, loop_time, warnings, end_values
        self.interrupted = interrupted  # the signal that stopped the run before the end of the grid, or None
        self.fmu_warnings = fmu_warnings or []  # per slave, the messages it logged as warnings or worse


def supported(algorithm: str, extrapolation: int, adaptive, links: list[LinkSpec]) -> str | None:
    """Why a run needs the Python master, or None when a session takes it."""
    if adaptive is not None:
        return "adaptive step control"
    if algorithm not in ("jacobi", "gauss-seidel"):
        return f"the {algorithm} scheme"
    if extrapolation != 0:
        return f"extrapolation order {extrapolation}"
    if any(l.source_type != "Real" or l.target_type != "Real" for l in links):
        return "an Integer or Boolean connection"
    return None


def _library_file(slave: SessionSlave) -> Path:
    platform = "win64" if sys.platform.startswith("win") else "darwin64" if sys.platform == "darwin" else "linux64"
    suffix = ".dll" if sys.platform.startswith("win") else ".dylib" if sys.platform == "darwin" else ".so"
    return slave.folder / "binaries" / platform / f"{slave.model_identifier}{suffix}"


class _Fmu:
    """One loaded FMU instance: the library, its life-cycle functions, its log, its wall time."""

    def __init__(self, slave: SessionSlave) -> None:
        self.slave = slave
        self.dll = keep(_library_file(slave))
        self.component = None
        self.wall_time = 0.0
        self.messages: deque[str] = deque(maxlen=20)
        self.warnings = 0  # messages logged with a status of warning or worse
        self.fatal = False  # a function returned fmi2Fatal: no function of the FMU's instances may be called again
        self.errored = False  # a function returned fmi2Error or fmi2Fatal: fmi2Terminate is not called
        key = next(_KEYS)
        _FMUS[key] = self
        self.env = TcmLogEnv(ctypes.cast(_SINK, _VP), key)
        _ENVS.append(self.env)
        f = self.dll
        f.fmi2Instantiate.restype = _VP
        f.fmi2Instantiate.argtypes = [ctypes.c_char_p, _I, ctypes.c_char_p, ctypes.c_char_p,
                                      ctypes.POINTER(_Callbacks), _I, _I]
        f.fmi2SetupExperiment.argtypes = [_VP, _I, _D, _D, _I, _D]
        for name in ("fmi2EnterInitializationMode", "fmi2ExitInitializationMode", "fmi2Terminate"):
            getattr(f, name).argtypes = [_VP]
        f.fmi2FreeInstance.argtypes = [_VP]
        f.fmi2FreeInstance.restype = None

    def log(self, status: int, message: bytes | None) -> None:
        """A message of the FMU (as :class:`~tribocosim.cosim.engine.slave.FmpySlave` keeps and logs them)."""
        text = (message or b"").decode("utf-8", "replace").strip()
        label = _LABELS[status] if 0 <= status < len(_LABELS) else str(status)
        self.messages.append(f"[{label}] {text}")
        if status >= 1:
            self.warnings += 1
            log(LOG, WARNING, "FMU %s: [%s] %s", self.slave.name, label, text)

    def call(self, function: str, *args) -> int:
        t0 = time.perf_counter()
        status = getattr(self.dll, function)(_VP(self.component), *args)
        self.wall_time += time.perf_counter() - t0
        if status > 1:
            self.fatal = self.fatal or status == _FATAL
            self.errored = self.errored or status >= _FATAL - 1
            label = _LABELS[status] if 0 <= status < len(_LABELS) else "illegal status"
            raise SessionStopped(f"FMU instance '{self.slave.name}': {function} returned {label}")
        return status

    def address(self, function: str) -> int:
        return ctypes.cast(getattr(self.dll, function), _VP).value

    def set_values(self, kind: str, vrs: list[int], values: list) -> None:
        n = len(vrs)
        refs = (_U * n)(*vrs)
        if kind == "Real":
            self.call("fmi2SetReal", refs, _SZ(n), (_D * n)(*values))
        elif kind == "Integer":
            self.call("fmi2SetInteger", refs, _SZ(n), (_I * n)(*[int(round(v)) for v in values]))
        elif kind == "Boolean":
            self.call("fmi2SetBoolean", refs, _SZ(n), (_I * n)(*[1 if v else 0 for v in values]))
        else:
            self.call("fmi2SetString", refs, _SZ(n), (ctypes.c_char_p * n)(*[str(v).encode() for v in values]))

    def get_value(self, kind: str, vr: int) -> float:
        ref = (_U * 1)(vr)
        if kind == "Real":
            out = (_D * 1)()
            self.call("fmi2GetReal", ref, _SZ(1), out)
            return float(out[0])
        out = (_I * 1)()
        self.call("fmi2GetBoolean" if kind == "Boolean" else "fmi2GetInteger", ref, _SZ(1), out)
        return float(out[0])


class NativeSession:
    """A fixed-step run in the C master's library (see the module docstring).

    Parameters
    ----------
    slaves : list of SessionSlave
        In scene order.
    links : list of LinkSpec
        Real to Real.
    structure : list of list of bool
        ``structure[k][j]``: link k's source may depend directly on link j's target (the model descriptions).
    recorded : list of (slave index, value reference, type)
        The recorded variables, in column order.
    algorithm : {"jacobi", "gauss-seidel"}
    propagate : bool
        ``output_update = "propagate"``.
    sequence : tuple of int
        The Gauss-Seidel order.
    grid : TimeGrid
        A fixed-step grid.
    stop : float
        The experiment's stop time (``fmi2SetupExperiment``).
    end_checks : list of (slave index, value reference, type)
        Outputs read after the last step (before the FMUs are freed).
    """

    def __init__(self, slaves: list[SessionSlave], links: list[LinkSpec], structure, recorded, algorithm: str,
                 propagate: bool, sequence, grid: TimeGrid, stop: float, end_checks=()) -> None:
        self.slaves, self.links, self.structure = slaves, links, structure
        self.recorded, self.algorithm, self.propagate = recorded, algorithm, propagate
        self.sequence, self.grid, self.stop, self.end_checks = list(sequence), grid, stop, list(end_checks)
        self.warnings: list[str] = []

    # --- the rig in the C library's structs ----------------------------------------------------
    def _array(self, ctype, values):
        values = list(values)
        arr = (ctype * max(1, len(values)))(*values)
        self._keep.append(arr)
        return arr

    def _get(self, slave: int, kind: int, vrs, pos, dst) -> TcmGet:
        return TcmGet(slave, kind, len(vrs), self._array(_U, vrs), len(dst), self._array(_I, pos),
                      self._array(_I, dst))

    def _rig(self, fmus: list[_Fmu]) -> None:
        n, m = len(self.slaves), len(self.links)
        self._keep: list = []
        self.c_slaves = (TcmSlave * n)()
        for i, f in enumerate(fmus):
            self.c_slaves[i] = TcmSlave(f.component, f.address("fmi2SetReal"), f.address("fmi2GetReal"),
                                        f.address("fmi2GetInteger"), f.address("fmi2GetBoolean"),
                                        f.address("fmi2DoStep"), 0.0, 0, self.grid.start)
        sets, set_first, gets, get_first = [], [0], [], [0]
        widest = max(m, 1)
        for i in range(n):  # as CoupledSystem: a slave's inputs in one batch, its linked outputs in one
            ins = [k for k, l in enumerate(self.links) if l.target == i]
            if ins:
                sets.append(TcmSet(i, len(ins), self._array(_U, [self.links[k].target_vr for k in ins]),
                                   self._array(_I, ins)))
            set_first.append(len(sets))
            outs = [k for k, l in enumerate(self.links) if l.source == i]
            if outs:
                vrs = sorted({self.links[k].source_vr for k in outs})
                pos = {v: j for j, v in enumerate(vrs)}
                gets.append(self._get(i, 0, vrs, [pos[self.links[k].source_vr] for k in outs], outs))
                widest = max(widest, len(vrs))
            get_first.append(len(gets))
        linked: dict[tuple[int, int], int] = {}
        for k, l in enumerate(self.links):  # as the Recorder: a recorded link source is read from the coupling values
            linked.setdefault((l.source, l.source_vr), k)
        self.from_y: list[tuple[int, int]] = []
        groups: dict[tuple[int, str], list[tuple[int, int]]] = {}
        for col, (i, vr, kind) in enumerate(self.recorded):
            kind = "Integer" if kind == "Enumeration" else kind
            k = linked.get((i, vr)) if kind == "Real" else None
            if k is not None:
                self.from_y.append((col, k))
            else:
                groups.setdefault((i, kind), []).append((col, vr))
        getters = {"Real": "get_real", "Integer": "get_integer", "Boolean": "get_boolean"}
        record = []
        for (i, kind), cv in groups.items():
            vrs = [v for _, v in cv]
            record.append(self._get(i, KINDS[getters[kind]], vrs, range(len(vrs)), [c for c, _ in cv]))
            widest = max(widest, len(vrs))
        self.has_inputs = [set_first[i + 1] > set_first[i] for i in range(n)]
        self.feeds = self._array(_I, [0] * n)
        self.eval_order = self._array(_I, range(n))
        g = self.grid
        self.rig = TcmRig(n, self.c_slaves, m, self._array(_I, [l.source for l in self.links]),
                          self._array(_SZ, set_first), self._array(TcmSet, sets), self._array(_SZ, get_first),
                          self._array(TcmGet, gets), self.feeds, self.eval_order, self._array(_I, self.sequence or
                                                                                              range(n)),
                          int(self.algorithm == "gauss-seidel"), 1, len(self.recorded), len(record),
                          self._array(TcmGet, record), len(self.from_y), self._array(_I, [c for c, _ in self.from_y]),
                          self._array(_I, [k for _, k in self.from_y]), g.start, g.tick, g.macro_ticks, g.end_ticks)
        capacity = -(-g.end_ticks // g.macro_ticks) + 1  # the start row and one row per step
        cols = max(1, len(self.recorded))
        self.times = array.array("d", bytes(8 * capacity))
        self.rows = array.array("d", bytes(8 * capacity * cols))
        scratch = {name: (ctype * size)() for name, ctype, size in (
            ("y", _D, max(m, 1)), ("written", _D, max(m, 1)), ("written_ok", ctypes.c_ubyte, n),
            ("stepped", ctypes.c_ubyte, n), ("values", _D, widest), ("held", _D, max(m, 1)), ("ints", _I, widest),
            ("row", _D, cols))}
        self._keep.append(scratch)
        address = lambda a, ptype: ctypes.cast(a.buffer_info()[0], ptype)  # noqa: E731
        self.y = scratch["y"]
        self.state = TcmState(0, scratch["y"], scratch["written"], scratch["written_ok"], scratch["stepped"],
                              scratch["values"], scratch["held"], scratch["ints"], scratch["row"],
                              address(self.times, _PD), address(self.rows, _PD), capacity, 0, 0, math.inf, 0.0,
                              -1, 0, None, 0.0)

    def _set_feeds(self, feedthrough: list) -> None:
        for i, ft in enumerate(feedthrough):
            self.feeds[i] = int(self.has_inputs[i] and ft is not False)

    def _c(self, function: str, *args) -> None:
        status = getattr(self.lib, function)(ctypes.byref(self.rig), ctypes.byref(self.state), *args)
        if status != TCM_DONE:
            st = self.state
            if st.failed_slave >= 0 and st.failed_status == _FATAL:
                self.fmus[st.failed_slave].fatal = True
            if st.failed_slave >= 0 and st.failed_status >= _FATAL - 1:
                self.fmus[st.failed_slave].errored = True
            what = st.failed_function.decode() if st.failed_function else "?"
            raise SessionStopped(f"{function}: {what} (slave {st.failed_slave}, status {st.failed_status})")

    # --- the run ---------------------------------------------------------------------------------
    def run(self, progress=None) -> SessionResult:
        """Run to the end of the grid (see the module docstring); SessionStopped where the Python master must."""
        self.lib = library()
        fmus: list[_Fmu] = []
        self.fmus = fmus

        callbacks = _Callbacks(*(ctypes.cast(getattr(self.lib, name), _VP).value
                                 for name in ("tcm_logger", "tcm_allocate_memory", "tcm_free_memory")), None, None)
        try:
            for s in self.slaves:
                f = _Fmu(s)
                fmus.append(f)
                cb = _Callbacks.from_buffer_copy(callbacks)
                cb.componentEnvironment = ctypes.addressof(f.env)
                f.callbacks = cb
                _ENVS.append(cb)  # the FMU may read its callbacks as long as it lives (see _ENVS)
                t0 = time.perf_counter()
                f.component = f.dll.fmi2Instantiate(s.name.encode(), 1, s.guid.encode(),
                                                    (s.folder / "resources").as_uri().encode(), ctypes.byref(cb), 0, 1)
                f.wall_time += time.perf_counter() - t0
                if not f.component:
                    raise SessionStopped(f"FMU instance '{s.name}': fmi2Instantiate failed")
                params = {vr: (kind, value) for vr, kind, value in s.parameters}
                for kind in ("Real", "Integer", "Boolean", "String"):
                    items = [(vr, v) for vr, (k, v) in params.items()
                             if k == kind or (kind == "Integer" and k == "Enumeration")]
                    if items:
                        f.set_values(kind, [vr for vr, _ in items], [v for _, v in items])
            for f in fmus:
                f.call("fmi2SetupExperiment", 0, 0.0, self.grid.start, 1, self.stop)
                f.call("fmi2EnterInitializationMode")
            return self._initialized_run(fmus, progress)
        finally:
            self._free(fmus)

    def _initialized_run(self, fmus: list[_Fmu], progress) -> SessionResult:
        n, m = len(self.slaves), len(self.links)
        self._rig(fmus)
        feedthrough = [s.feedthrough for s in self.slaves]
        self._set_feeds(feedthrough)
        for _ in range(max(1, n)):
            self._c("tcm_refresh")
        for f in fmus:
            f.call("fmi2ExitInitializationMode")
        self._c("tcm_refresh")
        jac = (_D * max(1, m * m))()
        dep = (ctypes.c_ubyte * max(1, m * m))()
        probe = [int(feedthrough[l.target] is not False) for l in self.links]
        self._c("tcm_probe", self._array(_I, [l.target for l in self.links]),
                self._array(_U, [l.target_vr for l in self.links]), self._array(ctypes.c_ubyte, probe), jac, dep,
                (_D * max(1, 2 * m))())
        D = [[bool(dep[k * m + j]) and bool(self.structure[k][j]) for j in range(m)] for k in range(m)]
        J = [[jac[k * m + j] if D[k][j] else 0.0 for j in range(m)] for k in range(m)]
        for i, ft in enumerate(feedthrough):
            if ft is None:
                outs = [k for k, l in enumerate(self.links) if l.source == i]
                feedthrough[i] = any(D[k][j] for k in outs for j in range(m)) if outs else False
        loops = algebraic_loops(D, J)
        order = evaluation_order(n, [(l.source, l.target) for l in self.links], D)
        for idx, i in enumerate(order):
            self.eval_order[idx] = i
        self._set_feeds(feedthrough)
        self._c("tcm_refresh")
        for loop in loops:
            msg, warn = loop_message(loop, ", ".join(self.links[k].label for k in loop.links), self.algorithm)
            if warn:
                self.warnings.append(msg)
                log(LOG, WARNING, msg)
            else:
                log(LOG, INFO, msg)
        self._c("tcm_record_row")
        self.rig.propagate = int(self.propagate)
        t0 = time.perf_counter()
        chunk, interrupted = CHUNK, None
        while self.state.n < self.grid.end_ticks:
            interrupted = stop_requested()
            if interrupted is not None:  # a signal: stop at this communication point
                break
            rows, started = self.state.n_rows, time.perf_counter()
            self._c("tcm_run", chunk)
            chunk = next_chunk(chunk, time.perf_counter() - started)
            if progress is not None and self.state.n_rows > rows:
                progress.step_accepted(self.times[self.state.n_rows - 1])
            if self.state.n_rows == rows:  # no room left for a row (not reached: one row per step)
                raise SessionStopped("the recorder's rows are full")
        loop_time = time.perf_counter() - t0
        end_values = [fmus[i].get_value(kind, vr) for i, vr, kind in self.end_checks]
        st = self.state
        cols = len(self.recorded)  # the buffer holds one column at least; a run that records none has no values
        return SessionResult(self.times[:st.n_rows], self.rows[:st.n_rows * cols], int(st.steps), st.min_step,
                             st.max_step, feedthrough, loops, order,
                             [f.wall_time + c.wall_time for f, c in zip(fmus, self.c_slaves)],
                             [int(c.do_steps) for c in self.c_slaves], loop_time, self.warnings, end_values,
                             interrupted, [f.warnings for f in fmus])

    def _free(self, fmus: list[_Fmu]) -> None:
        """``fmi2Terminate`` and ``fmi2FreeInstance`` of every instance; a failure here changes no result and is not
        reported (as the Python master's clean-up). After fmi2Fatal no function of any instance of that FMU is called
        (FMI 2.0.4, section 2.1.3): its instances are left as they are (a pythonfmu FMU releases the Python objects of
        an instance that raised once more when it is freed)."""
        dead = {f.slave.folder for f in fmus if f.fatal}
        for f in fmus:
            if not f.component or f.slave.folder in dead:
                continue
            try:
                if not f.errored:  # after fmi2Error only fmi2FreeInstance (FMI 2.0.4, section 2.1.5)
                    f.call("fmi2Terminate")
            except Exception:  # noqa: BLE001 - keep freeing the others
                pass
            if not f.fatal:
                try:
                    f.dll.fmi2FreeInstance(f.component)
                except Exception:  # noqa: BLE001
                    pass
            f.component = None
