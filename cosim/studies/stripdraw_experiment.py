"""The strip-draw test with the pure model: one draw, or several passes over the same strip, and its mu_bar.

The paper's macro experiment (Sec. 2.1, 7): the strip pulled at V0 = 0.08 m/s (velocity ramped over
10 ms; another drawing speed by ``Point.velocity``) for 140 mm under a constant normal force
F_N = P_N L_T w_T on each pad; mu(t) = pull_force / (2 F_N) (Eq. 1) and mu_bar its mean over the last 20 % of
the draw, the steady-state region. A later pass starts from the debris field the previous one left (paper
Fig. 2b; the share ``debris_carry_over`` of it), with the strip's mechanics afresh. After each pass the debris
left on the strip is weighed: the mean of beta over the nodes that were under the pad in the pass, times
h_p rho (flakes of Al, rho = 2700 kg/m^3) per unit area, and the start of mu(t) is kept: its first
``START_LENGTH`` of draw, where the strip under the pad carries the debris of a few millimetres of slide only. Used by the calibration (:mod:`tribocosim.cosim.apps.calibrate`) and the paper report; runs in
worker processes (:func:`run_points`). :func:`run_strip_draw` and :func:`steady_mean`: one draw with its outputs at
every step (the accuracy report and the benchmarks).
"""

from __future__ import annotations

import functools
import os
import re
import warnings
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field

import numpy as np

from tribocosim.cosim.studies.steady_state import steady_ratio  # noqa: F401 - the studies' mu_bar

V0 = 0.08  # m/s
RAMP = 0.01  # s
STEP = 1e-3  # s
LAST = 0.2  # the steady-state fraction of the draw
FLAKE_DENSITY = 2700.0  # kg/m^3 (Al)
START_LENGTH = 0.02  # m: the draw over which each pass's mu(t) is kept (``mu_start``)


@dataclass(frozen=True)
class Point:
    """One strip-draw experiment: nominal pressure [Pa], pad length [m], passes, and the strip-draw
    component's parameters (``table_file`` included) that differ from the defaults."""

    pressure: float
    tool_length: float
    passes: int = 1
    parameters: dict = field(default_factory=dict)
    velocity: float = V0  # drawing speed [m/s]


def mu_bar(point: Point) -> list[float]:
    """mu_bar of every pass of ``point`` (the last one is the measured value after ``passes`` passes)."""
    return [p["mu_bar"] for p in draw(point)]


def draw(point: Point) -> list[dict]:
    """Every pass of ``point``: ``mu_bar``, ``beta_max`` (the largest debris fraction on the strip at the
    end of the pass), ``table_clamps`` (nodal table lookups outside the table's axes or its simulated range in
    the pass), ``beta_left`` (the mean debris fraction on the strip that passed under the pad) and
    ``debris_g_m2`` (that debris weighed: beta_left h_p rho [g/m^2]), ``draw_start`` and ``mu_start`` (the grip's
    draw [m] and mu = pull_force / (2 F_N) at every step of the first :data:`START_LENGTH` of the pass)."""
    from tribocosim.components.stripdraw.component import COMPONENT
    from tribocosim.components.stripdraw.model import StripDrawModel

    first = COMPONENT.make({**point.parameters, "tool_length": point.tool_length}).model
    out = []
    beta = None
    for _ in range(point.passes):
        model = first if beta is None else StripDrawModel(first.params, first.law, beta_field=beta)
        fn = model.params.normal_force(point.pressure)
        draw = model.params.draw_length
        n = int(round((draw / point.velocity + 0.5 * RAMP) / STEP))
        mus = np.empty(n)
        drawn = np.empty(n)
        before = model.mesh.X + model.U <= model.mesh.window_hi  # not yet past the pad's exit edge
        for k in range(n):
            v = point.velocity * min(1.0, (k + 0.5) * STEP / RAMP)
            drawn[k] = v * STEP + (drawn[k - 1] if k else 0.0)
            mus[k] = model.step(STEP, {"normal_force": fn, "grip_velocity": v})["pull_force"] / (2.0 * fn)
        passed = before & (model.mesh.X + model.U >= model.mesh.window_lo)  # was under the pad in this pass
        left = float(model.beta[passed].mean()) if passed.any() else 0.0
        out.append({"mu_bar": float(mus[int((1.0 - LAST) * n):].mean()), "beta_max": float(model.beta.max()),
                    "table_clamps": int(model.clamp_count), "beta_left": left,
                    "debris_g_m2": 1e3 * left * model.params.particle_thickness * FLAKE_DENSITY,
                    "draw_start": drawn[drawn <= START_LENGTH].tolist(), "mu_start": mus[drawn <= START_LENGTH].tolist()})
        beta = model.beta.copy()
    return out


def _recorded(fn, point: Point) -> tuple:
    """``fn(point)`` and the warnings it raised, as (category, message) pairs, so that :func:`run_points` reports
    them once for all points (each draw's model warns in its own words, with its own time)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fn(point)
    return result, [(w.category, str(w.message)) for w in caught]


def _report(caught: list[tuple], n_points: int) -> None:
    """Warn once per distinct message (the time a model warned at and the value it names left out), saying in how
    many of the points it arose."""
    counts: dict[tuple, list] = {}
    for category, message in caught:
        key = (category, re.sub(r"\bat t = \S+ s (mu = \S+ )?", "", message))
        counts.setdefault(key, [message, 0])[1] += 1
    for (category, _), (first, count) in counts.items():
        more = f" (the first of {count} of the {n_points} draws that warned so)" if count > 1 else ""
        warnings.warn(first + more, category, stacklevel=3)


def point_pool(workers: int | None = None) -> ProcessPoolExecutor:
    """A pool of spawned worker processes for :func:`run_points` to reuse over many calls (a caller that runs many
    small batches, such as a root finder's steps, saves the start of the processes at every call)."""
    import multiprocessing

    return ProcessPoolExecutor(max_workers=max(1, workers or os.cpu_count() or 1),
                               mp_context=multiprocessing.get_context("spawn"))


def run_points(points: list[Point], workers: int | None = None, fn=mu_bar, pool=None) -> list:
    """``fn`` (:func:`mu_bar` or :func:`draw`) of every point, in parallel processes: in ``pool`` (a
    :func:`point_pool`, for a caller that runs many small batches) when given, otherwise at most one per point on the
    project's local executor, whose workers ignore SIGINT and SIGTERM and are killed on a stop
    (:class:`tribocosim.surrogate.executors.ProcessPoolCaseExecutor`). Within :func:`tribocosim.interrupt.
    stop_on_signals` a signal stops the latter between draws with :class:`~tribocosim.errors.Interrupted` (the draws in
    progress are discarded). The warnings of the draws are given once per distinct message, with the number of draws
    that raised it; a draw that raises raises here."""
    from tribocosim import interrupt
    from tribocosim.errors import Interrupted

    n = max(1, min(workers or os.cpu_count() or 1, len(points)))
    if pool is not None and len(points) > 1:
        done = list(pool.map(functools.partial(_recorded, fn), points))
    elif n == 1:
        done = []
        for p in points:
            interrupt.raise_if_stopped(Interrupted)
            done.append(_recorded(fn, p))
    else:
        from tribocosim.surrogate.executors import ProcessPoolCaseExecutor

        outcomes = dict(ProcessPoolCaseExecutor(n).map_unordered(functools.partial(_recorded, fn),
                                                                 list(enumerate(points))))
        for outcome in outcomes.values():
            if isinstance(outcome, BaseException):
                raise outcome
        done = [outcomes[i] for i in range(len(points))]
    _report([w for _, caught in done for w in caught], len(points))
    return [result for result, _ in done]


def run_strip_draw(
    pressure: float = 10e6,
    tool_length: float = 0.035,
    velocity: float = 0.08,
    draw_length: float = 0.14,
    step: float = 1e-3,
    ramp_time: float = 0.01,
    **parameters,
):
    """Run one strip draw with the pure model; return (time, outputs per step, model).

    Parameters
    ----------
    pressure : float
        Nominal contact pressure P_N [Pa]; the normal force is P_N L_T w_T.
    tool_length : float
        Pad length L_T [m].
    velocity : float
        Drawing velocity V0 [m/s].
    draw_length : float
        Draw length [m].
    step : float
        Output step [s].
    ramp_time : float
        Time over which the grip velocity ramps up [s].
    **parameters
        Further parameters of the StripDraw component: :class:`StripDrawParameters` fields and its
        files (``table_file``: default the shipped table).
    """
    from tribocosim.components.stripdraw.component import COMPONENT

    model = COMPONENT.make({"tool_length": tool_length, "draw_length": draw_length, **parameters}).model
    p = model.params
    normal_force = p.normal_force(pressure)
    t_end = draw_length / velocity + 0.5 * ramp_time
    n = int(round(t_end / step))
    times = step * np.arange(1, n + 1)
    outs = []
    for k in range(n):
        v = velocity * min(1.0, (k + 0.5) * step / ramp_time) if ramp_time > 0 else velocity
        outs.append(model.step(step, {"normal_force": normal_force, "grip_velocity": v}))
    return times, outs, model


def steady_mean(outs, key: str = "mu_mean", fraction: float = 0.2) -> float:
    """Mean of an output over the last ``fraction`` of the run (the steady-state region)."""
    values = np.array([o[key] for o in outs])
    return float(values[int((1.0 - fraction) * values.size):].mean())
