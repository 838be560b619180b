"""Integer time grid of the master: ``t = t0 + n * tick`` with an integer ``n``.

Time is never accumulated in floating point. Every communication point is an integer number of
ticks after the start, and its time is computed from that integer in one multiplication, so that
a run of ``N`` steps of size ``h`` ends at exactly ``t0 + N*h`` (as libcosim does with integer
nanosecond ticks).

- Fixed step ``h``: the tick is ``h / 2**FIXED_SUBDIVISION``; a macro step is ``2**S`` ticks,
  so a step that must be shrunk (an FMU discarded it, or returned non-finite outputs) can be
  halved up to ``S`` times and still land on the same grid. Because ``2**S`` is a power of two,
  ``(k * 2**S) * (h / 2**S)`` rounds to exactly the same double as ``k * h``.
- Variable step: the tick is ``min_step / 2**VARIABLE_SUBDIVISION`` and steps are even numbers
  of ticks (step doubling needs the half step on the grid).
"""

from __future__ import annotations

import math

from tribocosim.errors import ParameterError

from tribocosim.cosim.engine.schemes import FIXED_SUBDIVISION, VARIABLE_SUBDIVISION


class TimeGrid:
    """An integer time grid.

    Attributes
    ----------
    start : float
        Start time t0 [s].
    tick : float
        Grid resolution [s]; every communication point is ``start + n * tick``.
    end_ticks : int
        Number of ticks from start to stop.
    """

    __slots__ = ("start", "tick", "end_ticks")

    def __init__(self, start: float, tick: float, end_ticks: int) -> None:
        self.start, self.tick, self.end_ticks = start, tick, end_ticks

    def __repr__(self) -> str:
        return f"TimeGrid(start={self.start!r}, tick={self.tick!r}, end_ticks={self.end_ticks!r})"

    @classmethod
    def fixed(cls, start: float, stop: float, step: float) -> "TimeGrid":
        """The grid of a fixed-step run; the macro step is ``2**FIXED_SUBDIVISION`` ticks.

        If ``(stop - start) / step`` is not an integer (to 1e-9 relative), the last step is
        shortened so that the run ends at ``stop``.
        """
        _check_span(start, stop, step)
        tick = step / 2**FIXED_SUBDIVISION
        n_steps = (stop - start) / step
        whole = round(n_steps)
        if abs(n_steps - whole) <= 1e-9 * max(1.0, n_steps):
            end = whole * 2**FIXED_SUBDIVISION
        else:
            end = math.floor(n_steps) * 2**FIXED_SUBDIVISION + max(1, round((n_steps % 1.0) * 2**FIXED_SUBDIVISION))
        return cls(start, tick, int(end))

    @classmethod
    def variable(cls, start: float, stop: float, min_step: float) -> "TimeGrid":
        """The grid of a variable-step run: ``min_step`` is ``2**VARIABLE_SUBDIVISION`` ticks."""
        _check_span(start, stop, min_step)
        tick = min_step / 2**VARIABLE_SUBDIVISION
        return cls(start, tick, int(round((stop - start) / tick)))

    @property
    def macro_ticks(self) -> int:
        """Ticks of one fixed macro step."""
        return 2**FIXED_SUBDIVISION

    def time(self, n: int) -> float:
        """Time of tick ``n``: ``start + n * tick`` (one rounding, never accumulated)."""
        return self.start + n * self.tick

    def ticks(self, duration: float) -> int:
        """The whole number of ticks nearest to ``duration`` seconds (at least 1)."""
        return max(1, int(round(duration / self.tick)))

    def even_ticks(self, duration: float) -> int:
        """The even number of ticks nearest to ``duration`` (at least 2)."""
        return max(2, 2 * int(round(duration / (2.0 * self.tick))))


def _check_span(start: float, stop: float, step: float) -> None:
    if not (math.isfinite(start) and math.isfinite(stop) and stop > start):
        raise ParameterError(f"experiment: stop = {stop!r} must be finite and greater than start = {start!r}")
    if not (math.isfinite(step) and step > 0.0):
        raise ParameterError(f"experiment: step = {step!r} must be finite and > 0")
