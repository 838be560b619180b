"""The stability criterion of the stability report, growth detection and the bisection for the largest stable step.

Definition (checked on every run; the report states it with its numbers)
    A run is **stable** when

    1. every recorded output is finite (no NaN, no inf);
    2. every checked output stays bounded: ``max |y| <= bound_factor * scale``, with ``scale`` a
       stated reference magnitude of that output (the closed-form solution's maximum for the
       oscillator, ``2 mu0 F_N`` for a pull force, ...), ``bound_factor`` = 10 by default;
    3. no growing oscillation: the ratio of successive peak amplitudes, measured as below, is
       below ``1 + growth_tol`` (``growth_tol`` = 1e-4: a margin for round-off and for the
       noise of the fit; a neutral oscillation has ratio 1 and counts as stable).

    A run that stops with an error (a discarded step the master cannot retry, an FMU error, a
    non-converging implicit solve) is **error**, with the message. Every unstable cell names its
    first failed test (the NaN and where, the bound and the value reached, the growth factor).

Growth detection (:func:`growth_factor`)
    The extrema of the sampled signal are its sign changes of the first difference. A *swing* is
    the difference between two successive extrema (twice the amplitude of an oscillation, and
    insensitive to a slower trend or a slower second mode superposed on it). Over the swings of
    the last ``tail`` fraction of the run that are above the noise floor ``floor * max |y|``
    (and only if the largest of them reaches ``significance * max |y|``: a ripple of 0.1 % is not
    judged), the
    slope s of log(swing) against the swing index is fitted by least squares; two swings make one
    period, so the ratio of successive peak amplitudes is ``exp(2 s)``. The oscillation grows when
    that ratio exceeds ``1 + growth_tol`` *and* its lower 95 % bound ``exp(2 (s - 2 se(s)))`` exceeds
    1 (a sampled, aliased ripple whose swings scatter randomly has no significant trend), *and* the
    largest swing lies in the last quarter of the fitted swings (an oscillation that is still growing
    at the end of the run; a kick that rings down after decaying noise is not growth). Fewer than
    ``min_swings`` swings above the floor: no oscillation to judge (ratio NaN, not growing).

Largest stable step (:func:`largest_stable_step`)
    Bisection in log(h) between a step known stable and one known unstable, until their ratio is
    at most ``1 + rel``; the returned step is the last stable one (a lower bound of the limit
    within ``rel``). Optionally a coarse log scan first (``scan_per_decade``), which finds the
    first instability when stability is not monotone in h.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Mapping

import numpy as np

STABLE, UNSTABLE, ERROR = "stable", "unstable", "error"


@dataclass(frozen=True)
class Criterion:
    """Thresholds of the stability definition (module docstring).

    Attributes
    ----------
    bound_factor : float
        Outputs must stay within this multiple of their reference magnitude.
    growth_tol : float
        A peak-amplitude ratio above ``1 + growth_tol`` per period is growth.
    tail : float
        Fraction of the run (the end) over which the growth is measured.
    floor : float
        Swings below ``floor * max |y|`` are noise and ignored (1e-6: above round-off and the
        iterative scheme's coupling tolerance, so a ringing that decays into noise is not fitted
        together with the noise).
    relative_floor : float
        Swings below ``relative_floor`` x the largest swing are ignored too (noise left after a
        ringing decayed).
    significance : float
        Growth is judged only when the largest swing in the window reaches ``significance * max |y|``
        (a ripple of 0.1 % of the signal, such as the one nodes entering and leaving the pad make,
        is not an oscillation that can threaten stability; a growing one crosses this level).
    min_swings : int
        Swings needed for a growth estimate.
    """

    bound_factor: float = 10.0
    growth_tol: float = 1e-4
    tail: float = 0.5
    floor: float = 1e-6
    min_swings: int = 6
    significance: float = 1e-3
    relative_floor: float = 1e-3

    def describe(self) -> str:
        return (f"stable = all outputs finite; |output| <= {self.bound_factor:g} x its reference magnitude; ratio of "
                f"successive peak amplitudes (log-linear fit over the last {100 * self.tail:.0f} % of the run, swings "
                f"above {self.floor:g} x max|y| and {self.relative_floor:g} x the largest swing; judged when the largest swing reaches {self.significance:g} x max|y|) <= "
                f"1 + {self.growth_tol:g}, with the fitted trend significant (95 % lower bound above 1) and the largest swing "
                f"in the last quarter of the window")


@dataclass(frozen=True)
class Verdict:
    """Outcome of one run under the criterion."""

    status: str
    reason: str = ""
    growth: float = float("nan")
    peak_ratio: float = float("nan")  # max |y| / scale of the worst output
    extra: dict = field(default_factory=dict)

    @property
    def stable(self) -> bool:
        return self.status == STABLE

    def short(self) -> str:
        return self.status if not self.reason else f"{self.status}: {self.reason}"


def _extrema(y: np.ndarray) -> np.ndarray:
    """Indices of the local extrema (sign changes of the first difference; flat runs skipped)."""
    d = np.diff(y)
    nz = np.flatnonzero(d != 0)
    if nz.size < 2:
        return np.array([], dtype=int)
    s = np.sign(d[nz])
    change = np.flatnonzero(s[1:] != s[:-1])
    return nz[change + 1]  # the sample after which the direction changes (the extremum)


def swings(values) -> np.ndarray:
    """Successive extremum-to-extremum differences |y(e_{i+1}) - y(e_i)| of a sampled signal."""
    y = np.asarray(values, dtype=float)
    e = _extrema(y)
    return np.abs(np.diff(y[e])) if e.size >= 2 else np.array([])


def growth_factor(values, criterion: Criterion = Criterion()) -> float:
    """Ratio of successive peak amplitudes per period (module docstring); NaN if there is no oscillation."""
    return growth_bounds(values, criterion)[0]


def growth_bounds(values, criterion: Criterion = Criterion()) -> tuple[float, float]:
    """(fitted ratio per period, its lower 95 % bound: exp(2 (slope - 2 standard errors))); NaNs if no oscillation."""
    y = np.asarray(values, dtype=float)
    if y.size < 4 or not np.all(np.isfinite(y)):
        return float("nan"), float("nan")
    start = int((1.0 - criterion.tail) * y.size)
    y = y[max(0, start - 1):]
    sw = swings(y)
    scale = float(np.max(np.abs(y))) if y.size else 0.0
    if scale == 0 or sw.size == 0 or sw.max() < criterion.significance * scale:
        return float("nan"), float("nan")
    keep = sw > max(criterion.floor * scale, criterion.relative_floor * sw.max())
    if keep.sum() < criterion.min_swings:
        return float("nan"), float("nan")
    idx = np.flatnonzero(keep)
    ratio, lower = _fit_ratio(idx.astype(float), np.log(sw[keep]))
    if np.argmax(sw[keep]) < 0.75 * (idx.size - 1):
        lower = min(lower, 1.0)  # the largest swing is not at the end: a kick that rings down, not growth
    return ratio, lower


def _fit_ratio(x: np.ndarray, logs: np.ndarray) -> tuple[float, float]:
    """Least-squares slope of log(swing) per swing -> (ratio per period, lower 95 % bound)."""
    xm = x - x.mean()
    sxx = float(xm @ xm)
    slope = float(xm @ (logs - logs.mean())) / sxx
    res = logs - logs.mean() - slope * xm
    se = math.sqrt(float(res @ res) / max(1, x.size - 2) / sxx)
    return math.exp(2.0 * slope), math.exp(2.0 * (slope - 2.0 * se))


def classify(time, columns: Mapping[str, np.ndarray], scales: Mapping[str, float],
             criterion: Criterion = Criterion()) -> Verdict:
    """Apply the criterion to recorded outputs.

    Parameters
    ----------
    time : array_like
        Recorded times [s] (for the messages).
    columns : mapping name -> values
        The outputs to check.
    scales : mapping name -> float
        Reference magnitude of each output for the bound (outputs without one are only checked
        for finiteness and growth).
    """
    t = np.asarray(time, dtype=float)
    for name, v in columns.items():
        v = np.asarray(v, dtype=float)
        bad = np.flatnonzero(~np.isfinite(v))
        if bad.size:
            at = f" at t = {t[bad[0]]:.6g} s" if t.size == v.size else ""
            return Verdict(UNSTABLE, f"non-finite {name} ({v[bad[0]]}){at}")
    worst, worst_ratio = None, 0.0
    for name, v in columns.items():
        s = scales.get(name)
        if s is None or not s > 0:
            continue
        ratio = float(np.max(np.abs(v))) / s
        if ratio > worst_ratio:
            worst, worst_ratio = name, ratio
    if worst is not None and worst_ratio > criterion.bound_factor:
        return Verdict(UNSTABLE, f"|{worst}| reached {worst_ratio:.3g} x its reference magnitude "
                                 f"(bound {criterion.bound_factor:g} x)", peak_ratio=worst_ratio)
    g_worst, g_low, g_name = float("nan"), float("nan"), None
    for name, v in columns.items():
        g, low = growth_bounds(v, criterion)
        if math.isfinite(g) and (g_name is None or low > g_low):
            g_worst, g_low, g_name = g, low, name
    if g_name is not None and g_worst > 1.0 + criterion.growth_tol and g_low > 1.0:
        return Verdict(UNSTABLE, f"growing oscillation in {g_name}: peak ratio {g_worst:.6g} per period "
                                 f"(95 % lower bound {g_low:.6g})", growth=g_worst, peak_ratio=worst_ratio)
    return Verdict(STABLE, "", growth=g_worst, peak_ratio=worst_ratio)


@dataclass(frozen=True)
class StepLimit:
    """Result of :func:`largest_stable_step`.

    Attributes
    ----------
    stable_step : float
        Largest step found stable (0 if even ``lo`` is not stable).
    unstable_step : float
        Smallest step found not stable (inf if ``hi`` is stable).
    reason : str
        Why ``unstable_step`` is not stable (its verdict), or a note.
    evaluations : int
        Runs made.
    """

    stable_step: float
    unstable_step: float
    reason: str
    evaluations: int
    trail: tuple = ()

    def describe(self) -> str:
        if self.stable_step == 0.0:
            return f"not stable even at {self.unstable_step:.3g} s ({self.reason})"
        if math.isinf(self.unstable_step):
            return f">= {self.stable_step:.3g} s (stable over the whole range scanned)"
        return f"{self.stable_step:.3g} s (unstable at {self.unstable_step:.3g} s: {self.reason})"


def largest_stable_step(judge: Callable[[float], Verdict], lo: float, hi: float, *, rel: float = 0.02,
                        scan_per_decade: int = 0, max_evaluations: int = 60, lazy_lo: bool = False,
                        hi_verdict: Verdict | None = None) -> StepLimit:
    """Largest step h in [lo, hi] with ``judge(h).stable``, by log bisection (module docstring).

    Parameters
    ----------
    judge : callable h -> Verdict
    lo, hi : float
        Search interval [s], 0 < lo < hi.
    rel : float
        Stop when unstable / stable <= 1 + rel.
    scan_per_decade : int
        If > 0, first scan upwards from lo on a log grid with this many points per decade and
        bisect below the first step that is not stable.
    lazy_lo : bool
        Presume ``lo`` stable and run it only if the bisection ends there (runs at tiny steps are
        the expensive ones).
    hi_verdict : Verdict, optional
        The verdict at ``hi`` if already known (not run again).
    """
    if not (0 < lo < hi):
        raise ValueError(f"need 0 < lo < hi, got {lo!r}, {hi!r}")
    trail = []
    n = 0

    def ev(h):
        nonlocal n
        n += 1
        v = judge(h)
        trail.append((h, v.status, v.reason))
        return v

    if not lazy_lo:
        v = ev(lo)
        if not v.stable:
            return StepLimit(0.0, lo, v.reason or v.status, n, tuple(trail))
    a, b, why = lo, None, ""
    if scan_per_decade > 0:
        grid = np.logspace(math.log10(lo), math.log10(hi), int(math.ceil(scan_per_decade * math.log10(hi / lo))) + 1)
        for h in grid[1:]:
            v = ev(float(h))
            if v.stable:
                a = float(h)
            else:
                b, why = float(h), v.reason or v.status
                break
        if b is None:
            return StepLimit(a, math.inf, "stable at every scanned step", n, tuple(trail))
    else:
        v = hi_verdict if hi_verdict is not None else ev(hi)
        if v.stable:
            return StepLimit(hi, math.inf, "stable at the upper end of the range", n, tuple(trail))
        b, why = hi, v.reason or v.status
    while b / a > 1.0 + rel and n < max_evaluations:
        mid = math.sqrt(a * b)
        v = ev(mid)
        if v.stable:
            a = mid
        else:
            b, why = mid, v.reason or v.status
    if lazy_lo and a == lo:
        v = ev(lo)
        if not v.stable:
            return StepLimit(0.0, lo, v.reason or v.status, n, tuple(trail))
    return StepLimit(a, b, why, n, tuple(trail))
