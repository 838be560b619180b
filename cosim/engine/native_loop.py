"""The fixed-step loop in C: Jacobi and Gauss-Seidel with held coupling values, run natively for the Python master.

:class:`Master` hands its loop to :class:`NativeLoop` when the run is one the C loop (``native/tc_master.c``) takes
exactly as the Python loop would: a fixed step, Jacobi or Gauss-Seidel with extrapolation order 0, every slave an
FMI 2.0 FMU loaded by :class:`~tribocosim.cosim.engine.slave.FmpySlave`, every link Real to Real, and no observer
but the recorder and progress reporters. The Python master has loaded, instantiated, parameterized and initialized
the FMUs and probed their feedthrough; the C loop then calls the FMI functions of their libraries through the same
function pointers, with the same batches, in the same order, on the same integer time grid, so that its results
are the Python loop's to the last bit (``tests/cosim/test_native_loop.py``). It records the scene's outputs into
memory, in chunks of steps (:func:`~tribocosim.cosim.engine.native_lib.next_chunk`) between which the progress
reporters are told the time and a stop asked for by a signal ends the run (:mod:`tribocosim.interrupt`).

The C loop saves no FMU state. A step it cannot take (an FMU discards it, or a linked or recorded output is not
finite) raises :class:`NativeLoopStopped`; :func:`tribocosim.cosim.api.run` then repeats the run with the Python
loop, which rolls back and halves the step where the FMUs can, or stops with its message where they cannot. An FMI
error stops the run as under the Python loop (:class:`~tribocosim.errors.CosimStepError`, naming the instance, the
function and the time). Every other run (adaptive steps, iterative coupling, extrapolation orders 1 and 2, Integer
or Boolean links, other slaves) runs the Python loop; :func:`unsupported` says why.

The library and its ctypes structures are :mod:`.native_lib`.
"""

from __future__ import annotations

import ctypes
import time

import numpy as np

from tribocosim.errors import CosimStepError, Interrupted, TribocosimError
from tribocosim.interrupt import raise_if_stopped, stop_requested
from tribocosim.cosim.engine.native_lib import (CHUNK, KINDS, STATUS_LABELS, TCM_DONE, TCM_FMI_ERROR, TCM_STOPPED,
                                                TcmGet, TcmRig, TcmSet, TcmSlave, TcmState, library, next_chunk)

_I, _SZ = ctypes.c_int, ctypes.c_size_t
_PD, _PB, _PI = ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_ubyte), ctypes.POINTER(ctypes.c_int)


class NativeLoopStopped(CosimStepError):
    """The C loop met a step it does not take (a discard or a non-finite value): the run is repeated in Python."""


# ------------------------------------------------------------------------------------------------ the loop
def unsupported(master) -> str | None:
    """Why ``master``'s run needs the Python loop, or None when the C loop takes it."""
    from tribocosim.cosim.engine.algorithms import GaussSeidel, Jacobi
    from tribocosim.cosim.engine.recorder import Recorder
    from tribocosim.cosim.engine.slave import FmpySlave
    from tribocosim.cosim.engine.stepcontrol import FixedStep

    sysm = master.system
    if type(master.controller) is not FixedStep:
        return f"{master.controller.name} step control"
    if type(master.algorithm) not in (Jacobi, GaussSeidel):
        return f"the {master.algorithm.name} scheme"
    if master.algorithm.order != 0:
        return f"extrapolation order {master.algorithm.order}"
    if not all(type(s) is FmpySlave and s.loaded for s in sysm.slaves):
        return "a slave that is not an FMI 2.0 FMU"
    if any(l.source_type != "Real" or l.target_type != "Real" for l in sysm.links):
        return "an Integer or Boolean connection"
    if not isinstance(master.observers[0], Recorder) or not all(getattr(o, "sampled", False)
                                                                 for o in master.observers[1:]):
        return "an observer of every step"
    try:
        library()
    except (TribocosimError, OSError) as exc:
        return f"the native loop's library is not available ({exc})"
    return None


class NativeLoop:
    """The C loop's view of a master: the ctypes structs and the arrays they point to (kept alive here)."""

    def __init__(self, master) -> None:
        self.lib = library()
        sysm, rec = master.system, master.recorder
        n, m = len(sysm.slaves), sysm.m
        self._keep: list = []
        self.slaves = (TcmSlave * n)()
        for i, s in enumerate(sysm.slaves):
            f = s.fmi_functions()
            self.slaves[i] = TcmSlave(s.component_address(), f["fmi2SetReal"], f["fmi2GetReal"], f["fmi2GetInteger"],
                                      f["fmi2GetBoolean"], f["fmi2DoStep"], 0.0, 0, s.current_time)
        sets, set_first, gets, get_first = [], [0], [], [0]
        widest = max(m, 1)
        for i in range(n):
            for kind, ks in sysm._in[i].items():
                sets.append(TcmSet(i, len(ks), self._array([sysm.links[k].target_vr for k in ks], ctypes.c_uint),
                                   self._array(ks, _I)))
            set_first.append(len(sets))
            for kind, ks in sysm._out[i].items():
                vrs, idx = sysm._out_vrs[i][kind]
                gets.append(self._get(i, 0, vrs, idx, ks))
                widest = max(widest, len(vrs))
            get_first.append(len(gets))
        record = []
        for i, getter, cols, vrs in rec._groups:
            record.append(self._get(i, KINDS[getter], vrs, range(len(vrs)), cols))
            widest = max(widest, len(vrs))
        alg = master.algorithm
        sequence = getattr(alg, "sequence", range(n))
        feeds = [int(bool(sysm._in[i]) and sysm.feedthrough[i] is not False) for i in range(n)]
        grid = master.grid
        self.rig = TcmRig(
            n, self.slaves, m, self._array([l.source for l in sysm.links], _I),
            self._array(set_first, _SZ), self._structs(TcmSet, sets), self._array(get_first, _SZ),
            self._structs(TcmGet, gets), self._array(feeds, _I), self._array(sysm.eval_order, _I),
            self._array(sequence, _I), int(alg.name == "gauss-seidel"), int(alg.propagate), len(rec.names),
            len(record), self._structs(TcmGet, record), len(rec._from_y),
            self._array([c for c, _ in rec._from_y], _I), self._array([k for _, k in rec._from_y], _I),
            grid.start, grid.tick, grid.macro_ticks, grid.end_ticks)
        self.written = np.zeros(m)
        written_ok = np.zeros(n, dtype=np.uint8)
        for i, w in enumerate(sysm._written):
            if w is not None:
                self.written[:] = np.where([l.target == i for l in sysm.links], w, self.written)
                written_ok[i] = 1
        self.written_ok = written_ok
        self.y = sysm.y
        if self.y.dtype != np.float64 or not self.y.flags.c_contiguous:
            raise ValueError("the coupling values must be a contiguous float64 array")
        steps = -(-(grid.end_ticks - master.n) // grid.macro_ticks) + 1
        self.times = np.zeros(steps)
        self.rows = np.zeros((steps, len(rec.names)))
        self.scratch = [np.zeros(widest), np.zeros(max(m, 1)), np.zeros(max(len(rec.names), 1)),
                        np.zeros(n, dtype=np.uint8), np.zeros(widest, dtype=np.intc)]
        values, held, row, stepped, ints = self.scratch
        dp = lambda a: a.ctypes.data_as(_PD)  # noqa: E731
        self.state = TcmState(master.n, dp(self.y), dp(self.written), written_ok.ctypes.data_as(_PB),
                              stepped.ctypes.data_as(_PB), dp(values), dp(held), ints.ctypes.data_as(_PI), dp(row),
                              dp(self.times), dp(self.rows), steps, 0, 0, master.stats.min_step,
                              master.stats.max_step, -1, 0, None, 0.0)

    def _array(self, values, ctype):
        values = list(values)
        arr = (ctype * max(1, len(values)))(*values)
        self._keep.append(arr)
        return arr

    def _structs(self, cls, items):
        arr = (cls * max(1, len(items)))(*items)
        self._keep.append(arr)
        return arr

    def _get(self, slave: int, kind: int, vrs, pos, dst) -> TcmGet:
        return TcmGet(slave, kind, len(vrs), self._array(vrs, ctypes.c_uint), len(dst), self._array(pos, _I),
                      self._array(dst, _I))

    def run(self, master) -> None:
        """Take the master to the end of its grid; raise on an FMI error or where the Python loop must take over."""
        sysm, rec = master.system, master.recorder
        others = master.observers[1:]
        status, chunk = TCM_DONE, CHUNK
        while status == TCM_DONE and self.state.n < master.grid.end_ticks and stop_requested() is None:
            before, started = self.state.n_rows, time.perf_counter()
            status = self.lib.tcm_run(ctypes.byref(self.rig), ctypes.byref(self.state), chunk)
            chunk = next_chunk(chunk, time.perf_counter() - started)
            rows = self.state.n_rows
            rec.extend(self.times[before:rows], self.rows[before:rows])
            if rows > before:
                for obs in others:
                    obs.step_accepted(float(self.times[rows - 1]))
            if rows == before and status == TCM_DONE:  # no room left for a row (not reached: one row per step)
                break
        st = self.state
        master.n = int(st.n)
        master.stats.steps += int(st.steps)
        master.stats.iterations += int(st.steps)
        master.stats.min_step, master.stats.max_step = st.min_step, st.max_step
        sysm.history.push(master.n, sysm.y)
        sysm._written = [self.written.copy() if ok else None for ok in self.written_ok]
        for s, c in zip(sysm.slaves, self.slaves):
            s.wall_time += c.wall_time
            s.calls["doStep"] += int(c.do_steps)
            s.current_time = c.current_time
        if status == TCM_FMI_ERROR:
            slave = sysm.slaves[st.failed_slave]
            label = STATUS_LABELS[st.failed_status] if 0 <= st.failed_status < len(STATUS_LABELS) else "illegal status"
            raise CosimStepError(slave._failure(st.failed_function.decode(), f"status {st.failed_status}, {label}"))
        if status == TCM_STOPPED:
            what = st.failed_function.decode()
            who = f"FMU instance '{master.names[st.failed_slave]}'" if st.failed_slave >= 0 else "a recorded variable"
            raise NativeLoopStopped(f"{who}: {what} in the step from t = {st.failed_time:.9g} s")
        raise_if_stopped(Interrupted)  # a signal: the run stops at this communication point
