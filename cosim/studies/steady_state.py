"""mu_bar of a strip-draw test from recorded signals, the paper's measured quantity (Sec. 2.1, 7): the mean of
mu(t) = F_pull / (2 F_N) (Eq. 1) over the steady-state region at the end of the draw, the last 20 % of the run's
time, where the normal force is positive. Plain Python on any sequences (numpy arrays or the C master's rows), so
that ``tribocosim run`` says it without importing numpy."""

from __future__ import annotations

import math

#: the steady-state fraction of the run's time at its end
LAST = 0.2


def steady_ratio(time, pull_force, normal_force, last: float = LAST) -> float:
    """mu_bar: the mean of pull_force / (2 normal_force) over the samples in the last ``last`` of the run's time
    (within 1e-12 s) with normal_force > 0 (NaN when there is none)."""
    t = [float(x) for x in time]
    start = t[-1] - last * (t[-1] - t[0]) - 1e-12
    mus = [float(f) / (2.0 * float(n)) for ti, f, n in zip(t, pull_force, normal_force) if ti >= start and n > 0]
    return math.fsum(mus) / len(mus) if mus else math.nan


def strip_mu_bars(scene, result) -> list[tuple[str, float]]:
    """``(instance, mu_bar)`` of every strip-draw instance of ``scene`` whose pull force the run recorded together
    with the normal force it read: its ``normal_force`` input, or the output connected to it."""
    out = []
    for name, spec in scene.fmus.items():
        if (spec.component or "").lower() != "stripdraw":
            continue
        sources = [f"{c.source}" for c in scene.connections if f"{c.target}" == f"{name}.normal_force"]
        for normal in (f"{name}.normal_force", *sources):
            try:
                pull, fn = result.series(f"{name}.pull_force"), result.series(normal)
            except KeyError:
                continue
            out.append((name, steady_ratio(result.series("time"), pull, fn)))
            break
    return out
