"""Polynomial extrapolation and interpolation of coupling signals over a macro step.

A non-iterative master does not know an FMU's input over the step [t_n, t_n + h]; it
predicts it with the polynomial of degree q through the last q + 1 communication points
(extrapolation), or, for an FMU that is stepped after the FMU producing the signal
(Gauss-Seidel) and for iterative coupling, through the new end value and the last q points
(interpolation). With exact subsystems, degree q gives a global coupling error O(h^(q+1))
(Kübler & Schiehlen 2000, Multibody System Dynamics 4:107-126, doi:10.1023/A:1009810318420;
Arnold, Clauss & Schierz 2013, Archive of Mech. Eng. 60:75-94, doi:10.2478/meceng-2013-0005).

The polynomial is returned as Taylor coefficients about the start of the step,
p(tau) = c0 + c1 tau + c2 tau^2 with tau = t - t_n, which is what an FMU takes through
``fmi2SetRealInputDerivatives`` (derivative k = k! c_k). For an FMU that cannot take input
derivatives the master holds the mean of p over the step, (1/h) int_0^h p dtau
= c0 + c1 h/2 + c2 h^2/3, which keeps second order (the constant that matches p's integral
over the step) but caps the order at 2.

Points with unequal spacing (variable step) are handled by Newton's divided differences.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def taylor_coefficients(taus: list[float], values: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Taylor coefficients at tau = 0 of the polynomial through ``(taus[i], values[i])``.

    Parameters
    ----------
    taus : list of float
        1 to 3 distinct abscissae relative to the start of the step [s].
    values : list of ndarray
        The signal vector at each abscissa (same shape).

    Returns
    -------
    c0, c1, c2 : ndarray
        ``p(tau) = c0 + c1 tau + c2 tau**2``; unused higher coefficients are zero.
    """
    n = len(taus)
    if n == 0 or n > 3 or n != len(values):
        raise ValueError(f"need 1 to 3 points with one value each, got {n} abscissae and {len(values)} values")
    d0 = np.asarray(values[0], dtype=float)
    zero = np.zeros_like(d0)
    if n == 1:
        return d0.copy(), zero, zero.copy()
    t0, t1 = taus[0], taus[1]
    d01 = (np.asarray(values[1], dtype=float) - d0) / (t1 - t0)
    if n == 2:
        return d0 - d01 * t0, d01, zero
    t2 = taus[2]
    d12 = (np.asarray(values[2], dtype=float) - np.asarray(values[1], dtype=float)) / (t2 - t1)
    d012 = (d12 - d01) / (t2 - t0)
    # p = d0 + d01 (tau - t0) + d012 (tau - t0)(tau - t1)
    c2 = d012
    c1 = d01 - d012 * (t0 + t1)
    c0 = d0 - d01 * t0 + d012 * t0 * t1
    return c0, c1, c2


@dataclass
class StepPolynomial:
    """The predicted coupling signal over one step, p(tau) = c0 + c1 tau + c2 tau^2, tau in [0, h]."""

    h: float
    c0: np.ndarray
    c1: np.ndarray
    c2: np.ndarray

    def value(self, tau: float) -> np.ndarray:
        """p(tau)."""
        return self.c0 + tau * (self.c1 + tau * self.c2)

    def derivative(self, order: int) -> np.ndarray:
        """The ``order``-th time derivative at tau = 0 (1 or 2)."""
        if order == 1:
            return self.c1
        if order == 2:
            return 2.0 * self.c2
        raise ValueError(f"derivative order {order} is not 1 or 2")

    def mean(self) -> np.ndarray:
        """(1/h) int_0^h p(tau) dtau, the constant an FMU without input derivatives holds."""
        h = self.h
        return self.c0 + self.c1 * (h / 2.0) + self.c2 * (h * h / 3.0)


@dataclass
class History:
    """The last few accepted communication points of the coupling signals.

    Attributes
    ----------
    depth : int
        Points kept (order + 1, at most 3).
    ticks : list of int
        Grid ticks of the stored points, newest last.
    values : list of ndarray
        The coupling values at those points.
    """

    depth: int
    ticks: list[int] = field(default_factory=list)
    values: list[np.ndarray] = field(default_factory=list)

    def push(self, tick: int, values: np.ndarray) -> None:
        """Append an accepted point, replacing a point at the same tick."""
        if self.ticks and self.ticks[-1] == tick:
            self.values[-1] = np.array(values, dtype=float)
            return
        self.ticks.append(int(tick))
        self.values.append(np.array(values, dtype=float))
        if len(self.ticks) > self.depth:
            del self.ticks[0]
            del self.values[0]

    def copy(self) -> "History":
        """An independent copy (for rollback); stored arrays are never modified in place, so they are shared."""
        return History(self.depth, list(self.ticks), list(self.values))

    def latest(self) -> np.ndarray:
        """The newest point's values."""
        return self.values[-1]

    def extrapolate(self, order: int, tick_size: float, h: float) -> StepPolynomial:
        """Degree-min(order, points - 1) extrapolation from the newest points over a step h."""
        q = min(order, len(self.ticks) - 1)
        if q == 0:  # hold (the common fixed-step case): no fitting
            latest = self.values[-1]
            zero = np.zeros_like(latest)
            return StepPolynomial(h, latest, zero, zero)
        pts = range(len(self.ticks) - 1, len(self.ticks) - 2 - q, -1)
        n0 = self.ticks[-1]
        taus = [(self.ticks[i] - n0) * tick_size for i in pts]
        c0, c1, c2 = taylor_coefficients(taus, [self.values[i] for i in pts])
        return StepPolynomial(h, c0, c1, c2)

    def interpolate(self, order: int, tick_size: float, h: float, end: np.ndarray) -> StepPolynomial:
        """Degree-min(order, points) interpolation through ``end`` at tau = h and the newest points."""
        q = min(order, len(self.ticks))
        n0 = self.ticks[-1]
        taus = [h]
        vals = [np.asarray(end, dtype=float)]
        for i in range(len(self.ticks) - 1, len(self.ticks) - 1 - q, -1):
            taus.append((self.ticks[i] - n0) * tick_size)
            vals.append(self.values[i])
        c0, c1, c2 = taylor_coefficients(taus, vals)
        return StepPolynomial(h, c0, c1, c2)
