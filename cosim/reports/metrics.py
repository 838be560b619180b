"""Error metrics of the accuracy report.

The error of a run against a reference is the largest deviation over the run, relative to the
largest magnitude of the reference (:func:`max_relative_error`)::

    e = max_t |y(t) - y_ref(t)| / max_t |y_ref(t)|

It is "the max relative error" of the issue, normalised by the signal's range rather than
pointwise: a pointwise relative error is undefined where the reference crosses zero (the
oscillator's x1 does, the pull force starts at 0). The run is compared on its own communication
points; the reference is linearly interpolated there when it is sampled on another grid (give it
on a grid fine enough, or on the same points, for the interpolation error to stay below the
errors measured).

:func:`cheapest_reaching` picks, for a family of (error, cost) points, the cheapest setting whose
error is at or below each target (the Markdown summary table).
"""

from __future__ import annotations

import math
from typing import Iterable, Sequence

import numpy as np


def max_relative_error(time, values, ref_time, ref_values, scale: float | None = None) -> float:
    """max |y - y_ref| / max |y_ref| over the run's points (see the module docstring).

    Parameters
    ----------
    time, values : array_like
        The run: times [s] and values.
    ref_time, ref_values : array_like
        The reference; interpolated linearly onto ``time`` (it must cover the run's span).
    scale : float, optional
        Normaliser instead of ``max |y_ref|`` (> 0).

    Returns
    -------
    float
        The relative error; ``inf`` if the run has a non-finite value.
    """
    t = np.asarray(time, dtype=float)
    y = np.asarray(values, dtype=float)
    tr = np.asarray(ref_time, dtype=float)
    yr = np.asarray(ref_values, dtype=float)
    if t.shape != y.shape or tr.shape != yr.shape or t.size == 0 or tr.size == 0:
        raise ValueError(f"time/value shapes differ or are empty: {t.shape}, {y.shape}, {tr.shape}, {yr.shape}")
    if t[0] < tr[0] - 1e-12 * max(1.0, abs(tr[0])) or t[-1] > tr[-1] + 1e-12 * max(1.0, abs(tr[-1])):
        raise ValueError(f"the reference covers [{tr[0]}, {tr[-1]}] s, the run [{t[0]}, {t[-1]}] s")
    if not np.all(np.isfinite(y)):
        return math.inf
    same = tr.shape == t.shape and np.allclose(tr, t, rtol=0.0, atol=1e-12 * max(1.0, float(abs(t).max())))
    ref = yr if same else np.interp(t, tr, yr)
    s = float(np.max(np.abs(yr))) if scale is None else float(scale)
    if not s > 0:
        raise ValueError("the reference is identically zero: give a scale")
    return float(np.max(np.abs(y - ref)) / s)


def relative_difference(value: float, reference: float) -> float:
    """|value - reference| / |reference| for scalars (mu_bar, A_c/A0)."""
    if reference == 0:
        raise ValueError("reference is zero")
    return abs(value - reference) / abs(reference) if math.isfinite(value) else math.inf


def cheapest_reaching(rows: Iterable[dict], targets: Sequence[float], *, error: str = "error",
                      cost: str = "wall_time", label: str = "setting") -> dict[float, dict | None]:
    """For each target, the row with the smallest ``cost`` among those with ``error <= target``.

    Returns ``{target: row or None}`` (None: no setting of the family reaches it).
    """
    rows = [r for r in rows if r.get(error) is not None and math.isfinite(r[error])]
    out: dict[float, dict | None] = {}
    for tgt in targets:
        ok = [r for r in rows if r[error] <= tgt]
        out[tgt] = min(ok, key=lambda r: (r[cost], r[error])) if ok else None
    return out
