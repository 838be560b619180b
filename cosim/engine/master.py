"""The execution: initialization, the time loop, rejection and rollback, statistics.

:class:`Master` owns a :class:`~tribocosim.cosim.engine.system.CoupledSystem`, a coupling algorithm
(:mod:`tribocosim.cosim.engine.algorithms`), a step controller (:mod:`tribocosim.cosim.engine.stepcontrol`), the integer time
grid and the recorder. Its primitives are what the controllers use:

- ``attempt(n, k)``: one macro step from tick n over k ticks; False if an FMU discarded the
  step or returned a non-finite linked output (the reason is kept for the error message);
- ``snapshot()`` / ``restore()`` / ``release()``: FMU states, coupling values, history and
  the observers' positions (recorded rows), for rollback;
- ``accept(n)``: the step ending at tick n is final: push the coupling values into the
  history and notify the observers (:class:`~tribocosim.cosim.engine.recorder.Observer`: the recorder,
  a progress bar).

Initialization follows FMI 2.0: instantiate, set parameters, set up the experiment, enter
initialization mode, propagate initial values through the links (as many passes as there are
slaves), exit initialization mode; then the direct feedthrough is probed and algebraic loops
are reported with their contraction factor (a warning if a non-iterative scheme cannot be
stable, i.e. rho >= 1).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

from tribocosim.errors import ConvergenceError, CosimStepError, Interrupted
from tribocosim.interrupt import raise_if_stopped
from tribocosim.lazy import INFO, WARNING, log
from tribocosim.cosim.engine.algorithms import Algorithm
from tribocosim.cosim.engine.schemes import loop_message
from tribocosim.cosim.engine.observers import Observer
from tribocosim.cosim.engine.recorder import Recorder
from tribocosim.cosim.engine.system import CoupledSystem, NonFiniteOutput
from tribocosim.cosim.engine.timegrid import TimeGrid

LOG = "tribocosim.cosim"  # the logger of the master's notes
#: the loops a master can run: "auto" (the C loop where it takes the run) or "python"
LOOPS = ("auto", "python")


@dataclass
class RunStats:
    """Counters of one run.

    ``steps`` counts accepted communication points (for step doubling both halves of a step),
    ``rejected_error`` steps rejected by the error estimate, ``rejected_failures`` attempts
    refused by an FMU (discard) or with a non-finite output, ``iterations`` passes over the
    slaves (> steps for iterative coupling and start-up correctors), ``observed_contraction`` the
    largest contraction factor an iterated step showed (the step whose iteration failed included; NaN
    if no step was iterated).
    """

    steps: int = 0
    rejected_error: int = 0
    rejected_failures: int = 0
    iterations: int = 0
    min_step: float = float("inf")
    max_step: float = 0.0
    error_estimates: list[float] = field(default_factory=list)
    observed_contraction: float = float("nan")
    wall_time: float = 0.0


class Master:
    """Runs a coupled system on an integer time grid.

    Parameters
    ----------
    system : CoupledSystem
    algorithm : Algorithm
    controller : FixedStep, StepDoubling or EnergyControl
    grid : TimeGrid
    recorder : Recorder
        The first observer (the results of the run).
    names : list of str
        Instance names (for messages).
    observers : list of Observer, optional
        Notified after the recorder (e.g. a progress bar).
    loop : {"auto", "python"}
        "auto": the fixed-step loop in C (:mod:`tribocosim.cosim.engine.native_loop`) where it takes the run,
        else the Python loop; "python": always the Python loop.
    """

    def __init__(self, system: CoupledSystem, algorithm: Algorithm, controller, grid: TimeGrid, recorder: Recorder,
                 names: list[str], observers: list[Observer] = (), loop: str = "auto") -> None:
        self.system = system
        self.algorithm = algorithm
        self.controller = controller
        self.grid = grid
        self.recorder = recorder
        self.observers: list[Observer] = [recorder, *observers]
        self.names = names
        self.stats = RunStats()
        self.n = 0
        self.can_roll_back = all(s.can_roll_back for s in system.slaves)
        self.continuous = [l.continuous for l in system.links]
        self.last_failure = ""
        self.last_inputs_at_end = system.u_end
        self.warnings: list[str] = []
        if loop not in LOOPS:
            raise ValueError(f"loop = {loop!r} is not one of {', '.join(LOOPS)}")
        self.loop = loop
        #: the loop that ran: "native" (:mod:`.native_loop`) or "python", and why not native
        self.loop_used = "python"
        self.loop_reason = "not run yet"

    # --- initialization ----------------------------------------------------------------------
    def initialize(self, start: float, stop: float, parameters: list[dict[int, tuple[str, object]]]) -> None:
        """Instantiate, set parameters, initialize, propagate initial values, probe feedthrough.

        ``parameters[i]`` maps value reference -> (type, value) for slave i.
        """
        sysm = self.system
        for s, params in zip(sysm.slaves, parameters):
            s.instantiate()
            for kind in ("Real", "Integer", "Boolean", "String"):
                items = [(vr, v) for vr, (k, v) in params.items() if k == kind or (kind == "Integer" and k == "Enumeration")]
                if items:
                    setter = {"Real": s.set_real, "Integer": s.set_integer, "Boolean": s.set_boolean, "String": s.set_string}[kind]
                    setter([vr for vr, _ in items], [v for _, v in items])
        for s in sysm.slaves:
            s.setup(start, stop)
        for _ in range(max(1, len(sysm.slaves))):
            sysm.refresh(start, propagate=True)
        for s in sysm.slaves:
            s.exit_initialization()
        sysm.refresh(start, propagate=True)
        sysm.probe_feedthrough(start)
        sysm.refresh(start, propagate=True)
        for loop in sysm.loops:
            msg, warn = loop_message(loop, ", ".join(sysm.links[k].label for k in loop.links), self.algorithm.name)
            if warn:
                self.warnings.append(msg)
                log(LOG, WARNING, msg)
            else:
                log(LOG, INFO, msg)
        self.accept(0)
        self.stats.steps = 0

    # --- primitives for the controllers ------------------------------------------------------
    def attempt(self, n: int, k: int) -> bool:
        """One macro step from tick n over k ticks; False on discard or non-finite output."""
        t = self.grid.time(n)
        h = k * self.grid.tick
        try:
            res = self.algorithm.step(self.system, t, h, self.grid.tick)
        except NonFiniteOutput as exc:
            self.last_failure = f"FMU instance '{self.names[exc.slave_index]}': {exc}"
            return False
        except ConvergenceError as exc:  # the run stops; its stats say how far from a contraction it was
            self.stats.iterations += exc.iterations
            self._observe_contraction(exc.contraction)
            raise
        self.stats.iterations += res.iterations
        if res.ok:
            bad = [name for obs in self.observers for name in obs.step_attempted(t + h)]
            if bad:
                insts = ", ".join(sorted({f"'{b.split('.', 1)[0]}'" for b in bad}))
                self.last_failure = (f"FMU instance {insts}: non-finite output {', '.join(bad)} at t = {t + h:.9g} s "
                                     f"(step from t = {t:.9g} s)")
                return False
        self._observe_contraction(res.contraction)
        if not res.ok:
            i = res.discarded_by
            msgs = list(self.system.slaves[i].messages)[-3:]
            self.last_failure = (f"FMU instance '{self.names[i]}' discarded the step from t = {t:.9g} s over h = {h:.6g} s"
                                 + (f" (FMU log: {' | '.join(msgs)})" if msgs else ""))
            return False
        return True

    def _observe_contraction(self, rate: float) -> None:
        if rate == rate:  # not NaN: an iterated step
            c = self.stats.observed_contraction
            self.stats.observed_contraction = rate if c != c else max(c, rate)

    def snapshot(self):
        """Save FMU states, coupling values, history, the observers' positions and the step count."""
        return self.system.snapshot(), [obs.mark() for obs in self.observers], self.n, self.stats.steps

    def restore(self, snap) -> None:
        """Return to a snapshot (it stays valid until released)."""
        sys_snap, marks, self.n, self.stats.steps = snap
        self.system.restore(sys_snap)
        for obs, mark in zip(self.observers, marks):
            obs.truncate(mark)

    def release(self, snap) -> None:
        """Free a snapshot's FMU states."""
        self.system.release(snap[0])

    def accept(self, n: int) -> None:
        """Make the state at tick n final: history, recorder, counters."""
        if n > self.n:
            h = (n - self.n) * self.grid.tick
            self.stats.min_step = min(self.stats.min_step, h)
            self.stats.max_step = max(self.stats.max_step, h)
        self.n = n
        self.system.history.push(n, self.system.y)
        for obs in self.observers:
            obs.step_accepted(self.grid.time(n))
        self.stats.steps += 1

    def fail_without_rollback(self):
        """Raise for the last failed attempt when the FMUs cannot roll back."""
        cannot = [nm for nm, s in zip(self.names, self.system.slaves) if not s.can_roll_back]
        raise CosimStepError(f"{self.last_failure}; the step cannot be retried with a smaller step because "
                             f"{', '.join(cannot)} cannot roll back (canGetAndSetFMUstate = false)")

    def fail_at_minimum(self, n: int, k: int):
        """Raise for the last failed attempt when the step cannot be shrunk further."""
        raise CosimStepError(f"{self.last_failure}; still failing at the smallest allowed step "
                             f"({k * self.grid.tick:.3g} s at t = {self.grid.time(n):.9g} s)")

    # --- the loop ----------------------------------------------------------------------------
    def run(self) -> RunStats:
        """Advance to the end of the grid; return the statistics.

        With ``loop = "auto"`` the C loop takes the run where it can
        (:class:`~tribocosim.cosim.engine.native_loop.NativeLoop`); it raises
        :class:`~tribocosim.cosim.engine.native_loop.NativeLoopStopped` at a step only the Python loop can take (the
        run is then repeated with ``loop = "python"``).
        """
        t0 = time.perf_counter()
        try:
            if self.loop == "auto" and self.n < self.grid.end_ticks:
                from tribocosim.cosim.engine import native_loop

                self.loop_reason = native_loop.unsupported(self)
                if self.loop_reason is None:
                    self.loop_used = "native"
                    native_loop.NativeLoop(self).run(self)
            else:
                self.loop_reason = "loop = \"python\""
            self._python_loop()
        finally:
            self.stats.wall_time = time.perf_counter() - t0
        return self.stats

    def _python_loop(self) -> None:
        while self.n < self.grid.end_ticks:
            raise_if_stopped(Interrupted)  # a signal: the run stops at this communication point
            self.controller.advance(self, self.n)
