"""Step-size control: fixed step, step doubling (Richardson), energy residual (ECCO-style).

Each controller advances the master by one accepted step (possibly after rejected attempts)
and returns the number of grid ticks it advanced. They use the master's primitives
``attempt`` (one macro step of the coupling algorithm, returns False on a discarded step or a
non-finite output), ``snapshot``/``restore``/``release`` and ``accept``.

Fixed step
    The macro step is ``2**S`` ticks. If an attempt fails and every FMU can roll back, the
    macro step is redone as two half steps, and so on (at most S halvings); without rollback
    the run stops with an error naming the FMU.
Step doubling (Richardson extrapolation; Arnold, Clauss & Schierz 2013,
doi:10.2478/meceng-2013-0005; MasterSim's and PyFMI's error control)
    From the saved state take one step H (coupling values Y1), roll back, take two steps H/2
    (Y2). With a scheme of global order p the local error of Y2 is estimated as
    e = (Y2 - Y1) / (2**p - 1). The criterion is the error per unit step (Shampine 1994,
    *Numerical Solution of ODEs*, sec. 5.1): err = max |e_i| / (H (atol + rtol |Y2_i|)) <= 1,
    so that the tolerance bounds the error committed per second of simulated time and the
    global error is proportional to it (measured on the two-mass oscillator: about 0.5 tol).
    The run continues from Y2; the next step is H * min(4, max(0.2, safety * err**(-1/p))),
    since err ~ H**p. Rejected steps are rolled back and retried with the smaller step.
    With ``step_quantum`` q every step is a whole multiple of 2 q (rounded to the nearest, within
    [min_step, max_step] rounded inwards), so every step starts and every half step ends on the grid
    k q: an FMU that integrates on that grid internally (the strip-draw model's ``internal_step``) then
    takes the same internal steps for H and for 2 x H/2, and the estimate sees the coupling error
    alone, not the FMU's own discretization (which is first order in its step and would hold the error
    per unit step constant as H shrinks).
Energy (Sadjina, Kyllingstad, Skjong & Pedersen 2017, Eng. with Computers 33:607-620,
doi:10.1007/s00366-016-0492-8)
    Rollback-free. For each power bond (effort link e from B to A, flow link f from A to B)
    the power A receives, u_e y_f, and the power B delivers, y_e u_f, differ only through the
    coupling (the inputs are extrapolated while the outputs move). At the end of each step the
    energy residual dE = h (u_e(t+h) y_f(t+h) - y_e(t+h) u_f(t+h)), with u the input the
    FMU used at the end of the step, is normalised by atol + rtol h max(|P_A|, |P_B|); the
    RMS over the bonds, eps, drives a PI controller
    h_new = h * safety * eps**(-(kI + kP)) * eps_prev**kP (kP = 0.2, kI = 0.15), clamped to
    [0.2 h, 2 h] and [min_step, max_step]. Steps are never rejected.
"""

from __future__ import annotations

import math

import numpy as np

from tribocosim.cosim.engine.schemes import ESTIMATORS, Adaptive


class FixedStep:
    """Fixed macro step on the integer grid, with halving on failure when FMUs can roll back."""

    name = "fixed"

    def __init__(self, macro_ticks: int) -> None:
        self.macro = macro_ticks
        self.sub = macro_ticks

    def advance(self, master, n: int) -> int:
        end_macro = (n // self.macro + 1) * self.macro
        k = min(self.sub, end_macro - n, master.grid.end_ticks - n)
        while True:
            snap = master.snapshot() if master.can_roll_back else None
            ok = master.attempt(n, k)
            if ok:
                if snap is not None:
                    master.release(snap)
                master.accept(n + k)
                if n + k >= end_macro:
                    self.sub = self.macro
                return k
            if snap is None:
                master.fail_without_rollback()
            if k == 1:
                master.release(snap)
                master.fail_at_minimum(n, k)
            master.restore(snap)
            master.release(snap)
            master.stats.rejected_failures += 1
            k = max(1, k // 2)
            self.sub = k


class StepDoubling:
    """Richardson error estimate from one step H and two steps H/2; rollback on rejection."""

    name = "step-doubling"

    def __init__(self, settings: Adaptive, initial_ticks: int, order: int) -> None:
        self.s = settings
        self.k = initial_ticks
        self.p = order

    def advance(self, master, n: int) -> int:
        grid = master.grid
        hmin = grid.even_ticks(self.s.min_step)
        hmax = grid.even_ticks(self.s.max_step)
        q2 = 2 * grid.ticks(self.s.step_quantum) if self.s.step_quantum else 0
        if q2:  # whole multiples of 2 quanta: the bounds rounded inwards, the step to the nearest
            hmin = q2 * max(1, -(-hmin // q2))
            hmax = max(hmin, q2 * (hmax // q2))
        while True:
            k = min(max(self.k, hmin), hmax)
            if q2:
                k = q2 * max(1, round(k / q2))
            remaining = grid.end_ticks - n
            if k >= remaining:
                k = remaining
            half = k // 2
            snap = master.snapshot()
            if half < 1 or k < 2:  # a last sliver shorter than two ticks: one plain step
                ok = master.attempt(n, k)
                if not ok:
                    master.release(snap)
                    master.fail_at_minimum(n, k)
                master.release(snap)
                master.accept(n + k)
                return k
            ok = master.attempt(n, k)
            y1 = master.system.y.copy()
            master.restore(snap)
            if ok and master.attempt(n, half):
                master.accept(n + half)
                ok = master.attempt(n + half, k - half)
            else:
                ok = False
            if not ok:
                master.restore(snap)
                master.release(snap)
                master.stats.rejected_failures += 1
                if k <= hmin:
                    master.fail_at_minimum(n, k)
                self.k = max(hmin, k // 4)
                continue
            y2 = master.system.y
            cont = master.continuous
            e = (y2 - y1)[cont] / (2.0**self.p - 1.0)
            scale = self.s.atol + self.s.tolerance * np.abs(y2[cont])
            h = k * grid.tick
            err = float(np.max(np.abs(e) / scale)) / h if e.size else 0.0
            factor = 4.0 if err == 0.0 else min(4.0, max(0.2, self.s.safety * err ** (-1.0 / self.p)))
            if err <= 1.0 or k <= hmin:
                master.release(snap)
                master.accept(n + k)
                master.stats.error_estimates.append(err)
                self.k = grid.even_ticks(k * grid.tick * factor)
                return k
            master.restore(snap)
            master.release(snap)
            master.stats.rejected_error += 1
            self.k = grid.even_ticks(k * grid.tick * factor)
            if q2:  # rounded to whole quanta the smaller step could come back as k: shrink by one at least
                self.k = min(self.k, k - q2)


class EnergyControl:
    """Rollback-free step control from the energy residual of the power bonds (ECCO)."""

    name = "energy"
    KP = 0.2
    KI = 0.15

    def __init__(self, settings: Adaptive, initial_ticks: int, bonds: list[tuple[int, int]]) -> None:
        self.s = settings
        self.k = initial_ticks
        self.bonds = bonds
        self.prev_eps = None
        self.residuals: list[float] = []

    def advance(self, master, n: int) -> int:
        grid = master.grid
        k = min(max(self.k, grid.ticks(self.s.min_step)), grid.ticks(self.s.max_step), grid.end_ticks - n)
        ok = master.attempt(n, k)
        if not ok:
            master.fail_without_rollback()
        h = k * grid.tick
        eps = self._eps(master, h)
        master.accept(n + k)
        master.stats.error_estimates.append(eps)
        if eps > 0.0 and math.isfinite(eps):
            gain = self.s.safety * eps ** (-(self.KI + self.KP))
            if self.prev_eps:
                gain *= self.prev_eps**self.KP
            gain = min(2.0, max(0.2, gain))
            self.prev_eps = eps
        else:
            gain = 2.0
        self.k = grid.ticks(h * gain)
        return k

    def _eps(self, master, h: float) -> float:
        sysm = master.system
        y, u = sysm.y, master.last_inputs_at_end
        sq = []
        for e, f in self.bonds:
            p_a = u[e] * y[f]  # power the effort receiver takes in
            p_b = y[e] * u[f]  # power the effort source gives out
            de = h * (p_a - p_b)
            level = h * max(abs(p_a), abs(p_b))
            sq.append((de / (self.s.atol + self.s.tolerance * level)) ** 2)
            self.residuals.append(de)
        return float(np.sqrt(np.mean(sq))) if sq else 0.0



#: the controller of every error estimator of :data:`~tribocosim.cosim.engine.schemes.ESTIMATORS`, by its scene name
ESTIMATOR_CLASSES = {cls.name: cls for cls in (StepDoubling, EnergyControl)}
assert set(ESTIMATOR_CLASSES) == set(ESTIMATORS), "every estimator of schemes.ESTIMATORS has its controller here"


def create_controller(settings: Adaptive, grid, step: float, order: int, bonds) -> "StepDoubling | EnergyControl":
    """The adaptive step controller of ``settings.estimator`` for a run starting with ``step``."""
    if settings.estimator == StepDoubling.name:
        return StepDoubling(settings, grid.even_ticks(step), order)
    return ESTIMATOR_CLASSES[settings.estimator](settings, grid.ticks(step), bonds)
