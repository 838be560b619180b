"""What the master tells its observers, and the progress bar of a run.

The master notifies a list of observers (:class:`Observer`): after every successful attempt of a macro step (an
observer may refuse the values it read, e.g. non-finite outputs, and the attempt then counts as failed), when a step
is accepted, and around rollbacks (``mark``/``truncate``). The recorder of the scene's outputs is one
(:class:`tribocosim.cosim.engine.recorder.Recorder`); :class:`Progress` shows a run's progress on stderr.
"""

from __future__ import annotations

import sys
import time


class Observer:
    """What the master calls on its observers (a base that does nothing).

    An observer with ``sampled = True`` needs only the time of the latest accepted step now and then (a progress
    reporter), so the native loop (:mod:`tribocosim.cosim.engine.native_loop`) may tell it once per chunk of steps.
    """

    sampled = False

    def step_attempted(self, t: float) -> list[str]:
        """A macro step to ``t`` succeeded in the FMUs; return the names of values that make it unusable."""
        return []

    def step_accepted(self, t: float) -> None:
        """The step to ``t`` is final."""

    def mark(self):
        """A position to roll back to."""
        return None

    def truncate(self, mark) -> None:
        """Forget what was observed after ``mark``."""


class Progress(Observer):
    """A one-line progress bar on stderr, shown once a run has taken longer than ``delay`` seconds."""

    sampled = True

    def __init__(self, start: float, stop: float, delay: float = 2.0, stream=None) -> None:
        self.start, self.stop, self.delay = start, stop, delay
        self.stream = stream if stream is not None else sys.stderr
        self.t0 = time.perf_counter()
        self.last = 0.0
        self.shown = False

    def __call__(self, t: float) -> None:
        now = time.perf_counter()
        if now - self.t0 < self.delay or now - self.last < 0.2:
            return
        self.last = now
        frac = min(1.0, max(0.0, (t - self.start) / (self.stop - self.start)))
        eta = (now - self.t0) * (1.0 - frac) / frac if frac > 0 else float("nan")
        bar = "#" * int(30 * frac)
        self.stream.write(f"\r[{bar:<30}] {100 * frac:5.1f}%  t = {t:.6g} s  eta {eta:6.1f} s")
        self.stream.flush()
        self.shown = True

    def step_accepted(self, t: float) -> None:
        self(t)

    def close(self) -> None:
        if self.shown:
            self.stream.write("\n")
            self.stream.flush()
