"""The grid an export writes: nodes chosen so that the FE code's own interpolation of the file reproduces the law.

An FE code reads a tabulated friction law multilinearly: linear in each axis between the nodes of the file, the end
values held beyond them (LS-DYNA's *DEFINE_TABLE and its curves, Abaqus' tabular *FRICTION data). tribocosim's law
is a monotone cubic in ln P and in beta and linear in v between the table's nodes (docs/model.md section 4), so the
FE code's reading of the table's own nodes misses it between them. :func:`sample` chooses the nodes:

1. start from the table's nodes inside the range and the range's ends (a node of the table is reproduced exactly);
2. per axis, with the other axes at their nodes, compare the linear interpolant of the node values with the law at
   :data:`PROBES` of every interval and split each interval whose relative deviation exceeds the refinement
   tolerance (at the geometric mean of its ends on a pressure axis, else at its middle); repeat until no interval is
   split;
3. check the whole grid: the multilinear interpolant (:func:`multilinear`, the FE code's rule) against the law on
   the tensor grid of the nodes and ``n`` points inside every interval of every axis, and at :data:`RANDOM_POINTS`
   random points of the range (on :data:`RANDOM_LINES` random values of the first axis); when a point deviates by
   more than the tolerance, the intervals it lies in are split, the refinement tolerance halved, and 2-3 repeated,
   unless the round brought the largest deviation down by less than :data:`STALL` (it comes from an axis that is
   not refined: given levels).

The deviation is relative: |mu_FE - mu| / max(mu, floor), the floor keeping it finite where mu approaches 0. Between
the check's points the deviation can exceed the largest one found: an error peak of the quadratic shape of linear
interpolation's, c t (1 - t) in an interval's fraction t, sampled every 1 / (n + 1), is missed by at most c / (2 (n +
1))^2, 1 / (n + 1)^2 of the peak c / 4. So the accuracy the export reached (:attr:`Sampling.accuracy`, stated in
every file's header and held to the tolerance) is the largest deviation found times 1 + 1 / (n + 1)^2, n the points
inside every interval on the check's tensor grid (:data:`CHECK_INTERIOR`: 1.6 % more with two axes, 6.3 % with
three). Several functions (a band's upper and lower mu beside the nominal one) share one grid: the
deviation is the largest of theirs.
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass

import numpy as np

#: where step 2 probes each interval (fractions of it)
PROBES = (0.25, 0.5, 0.75)
#: the refinement tolerance starts at this fraction of the target (step 2), so that the check usually passes at once
REFINE_FRACTION = 0.8
#: points inside every interval of every axis in the check's tensor grid (step 3): by the number of axes
CHECK_INTERIOR = {1: 15, 2: 7, 3: 3}
#: random points of the check (step 3): RANDOM_LINES values of the first axis, each with RANDOM_POINTS / RANDOM_LINES
#: random points of the others (the law is evaluated per value of the first axis, the pressure)
RANDOM_POINTS, RANDOM_LINES = 20_000, 200
#: at most this many nodes on one axis, and rounds of steps 2-3
MAX_NODES, MAX_ROUNDS = 400, 6
#: at most this many points in the check's tensor grid (step 3): an interval is not split when the split would take
#: the grid past it (a law with a kink across the range, mu clipped at 0, would else fill every axis with nodes at the
#: kink: 400^3 nodes and 1600^3 check points, gigabytes); what the grid then reaches is stated as its accuracy
MAX_CHECK_POINTS = 2_000_000
#: an interval narrower than this fraction of its axis's span is not split
MIN_WIDTH = 1e-6
#: a round of steps 2-3 that leaves the largest deviation above this fraction of the last round's is the last
STALL = 0.9

#: a sampling that takes longer than this [s] reports each further round (``sample``'s log)
PROGRESS_AFTER_S = 2.0


@dataclass(frozen=True)
class AxisSpec:
    """One axis of the grid: its name, its first nodes (increasing, the range's ends first and last), whether it is
    refined, and whether its intervals are split at their geometric mean (a pressure axis, the law being smooth in
    ln P)."""

    name: str
    nodes: tuple
    refine: bool = True
    geometric: bool = False


@dataclass(frozen=True)
class Sampling:
    """The chosen grid: its axes, the values at its nodes (shape: the axes' sizes, then one per function), and what
    the check found."""

    axes: tuple
    values: np.ndarray
    accuracy: float  # bound of the relative deviation of the FE code's interpolation from the law in the range
    largest: float  # the largest relative deviation found at the check's points
    worst: tuple  # the point (one coordinate per axis) where it is
    checked: int  # points checked
    tolerance: float
    floor: float
    rounds: int

    @property
    def reached(self) -> bool:
        """Whether the accuracy is within the tolerance."""
        return self.accuracy <= self.tolerance


def multilinear(axes, values: np.ndarray, points) -> np.ndarray:
    """The multilinear interpolant of ``values`` (the axes' sizes, then any trailing dimensions) at ``points`` (one
    array per axis, broadcast together), each coordinate held at its axis's ends beyond them (the FE codes'
    rule)."""
    points = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in points))
    index, frac = [], []
    for axis, x in zip(axes, points):
        axis = np.asarray(axis, dtype=float)
        if axis.size == 1:
            index.append(np.zeros(x.shape, dtype=int))
            frac.append(np.zeros(x.shape))
            continue
        x = np.clip(x, axis[0], axis[-1])
        i = np.clip(np.searchsorted(axis, x, side="right") - 1, 0, axis.size - 2)
        index.append(i)
        frac.append((x - axis[i]) / (axis[i + 1] - axis[i]))
    trailing = values.shape[len(axes):]
    out = np.zeros(points[0].shape + trailing)
    for corner in itertools.product((0, 1), repeat=len(axes)):
        weight = np.ones(points[0].shape)
        at = []
        for c, i, t, axis in zip(corner, index, frac, axes):
            weight = weight * (t if c else 1.0 - t)
            at.append(np.minimum(i + c, np.asarray(axis).size - 1))
        out += weight.reshape(weight.shape + (1,) * len(trailing)) * values[tuple(at)]
    return out


def relative_deviation(approx: np.ndarray, exact: np.ndarray, floor: float) -> np.ndarray:
    """|approx - exact| / max(|exact|, floor)."""
    return np.abs(approx - exact) / np.maximum(np.abs(exact), floor)


def _mesh(axes):
    return np.meshgrid(*axes, indexing="ij")


def _check_size(axes) -> int:
    """The points of the check's tensor grid on ``axes`` (step 3; its random points aside)."""
    inner = CHECK_INTERIOR.get(len(axes), 3)
    return math.prod((inner + 1) * (axis.size - 1) + 1 if axis.size > 1 else axis.size for axis in axes)


def _grows(axes, a: int, grown: np.ndarray) -> bool:
    """Whether axis ``a`` may become ``grown``: more nodes, at most :data:`MAX_NODES` on it and the check's grid within
    :data:`MAX_CHECK_POINTS`."""
    trial = [grown if b == a else axis for b, axis in enumerate(axes)]
    return axes[a].size < grown.size <= MAX_NODES and _check_size(trial) <= MAX_CHECK_POINTS


def _split(axis: np.ndarray, intervals: np.ndarray, geometric: bool) -> np.ndarray:
    """``axis`` with a node inserted in each of ``intervals`` (indices) wider than :data:`MIN_WIDTH` of the span."""
    lo, hi = axis[intervals], axis[intervals + 1]
    wide = hi - lo > MIN_WIDTH * (axis[-1] - axis[0])
    lo, hi = lo[wide], hi[wide]
    mid = np.sqrt(lo * hi) if geometric and np.all(lo > 0) else 0.5 * (lo + hi)
    return np.union1d(axis, mid)


def _refine_axes(evaluate, specs, axes, tol: float, floor: float) -> list:
    """Step 2 of the module docstring: split the intervals of each refined axis until none deviates above ``tol``."""
    for _ in range(MAX_NODES):
        changed = False
        for a, spec in enumerate(specs):
            axis = axes[a]
            if not spec.refine or axis.size < 2 or axis.size >= MAX_NODES:
                continue
            values = evaluate(_mesh(axes))
            f = np.asarray(PROBES)
            x = (axis[:-1, None] + f[None, :] * np.diff(axis)[:, None]).ravel()
            exact = evaluate(_mesh([x if b == a else axes[b] for b in range(len(axes))]))
            lo = np.take(values, np.repeat(np.arange(axis.size - 1), f.size), axis=a)
            hi = np.take(values, np.repeat(np.arange(1, axis.size), f.size), axis=a)
            w = np.tile(f, axis.size - 1).reshape([-1 if b == a else 1 for b in range(values.ndim)])
            dev = relative_deviation((1.0 - w) * lo + w * hi, exact, floor)
            per_point = np.moveaxis(dev, a, 0).reshape(x.size, -1).max(axis=1)
            per_interval = per_point.reshape(axis.size - 1, f.size).max(axis=1)
            bad = np.flatnonzero(per_interval > tol)
            if bad.size:
                grown = _split(axis, bad, spec.geometric)
                if _grows(axes, a, grown):
                    axes[a] = grown
                    changed = True
        if not changed:
            return axes
    return axes


def _check_points(axes, specs, rng) -> tuple:
    """The check's points (step 3): the tensor grid of the nodes and points inside every interval, and random
    points (uniform in ln x on a geometric axis)."""
    inner = CHECK_INTERIOR.get(len(axes), 3)
    lines = []
    for axis in axes:
        if axis.size < 2:
            lines.append(axis)
            continue
        f = np.arange(1, inner + 1) / (inner + 1)
        lines.append(np.union1d(axis, (axis[:-1, None] + f[None, :] * np.diff(axis)[:, None]).ravel()))
    grid = [m.ravel() for m in _mesh(lines)]
    extra = []
    for a, (axis, spec) in enumerate(zip(axes, specs)):
        n = RANDOM_LINES if a == 0 else RANDOM_POINTS
        if spec.geometric and axis[0] > 0:
            x = np.exp(rng.uniform(np.log(axis[0]), np.log(axis[-1]), n))
        else:
            x = rng.uniform(axis[0], axis[-1], n)
        extra.append(np.repeat(x, RANDOM_POINTS // RANDOM_LINES) if a == 0 else x)
    return tuple(np.concatenate([g, e]) for g, e in zip(grid, extra))


def sample(evaluate, specs, tolerance: float, floor: float, seed: int = 0, log=None) -> Sampling:
    """The grid of the module docstring.

    Parameters
    ----------
    evaluate : callable
        ``evaluate(points) -> values``: the law at points given as one array per axis (same shape), values of that
        shape with one trailing dimension (one entry per function).
    specs : sequence of AxisSpec
        The axes.
    tolerance : float
        The largest relative deviation allowed (0.005: 0.5 %).
    floor : float
        The least |mu| a deviation is taken relative to.
    seed : int
        Seed of the check's random points.
    log : callable, optional
        Told in one line of each round that did not reach the tolerance once the sampling has taken
        :data:`PROGRESS_AFTER_S` (its grid and deviation): a long refinement says how far it is.
    """
    started = time.monotonic()
    rng = np.random.default_rng(seed)
    axes = [np.asarray(s.nodes, dtype=float) for s in specs]
    tol = REFINE_FRACTION * tolerance
    previous = math.inf
    for rounds in range(1, MAX_ROUNDS + 1):
        axes = _refine_axes(evaluate, specs, axes, tol, floor)
        values = evaluate(_mesh(axes))
        points = _check_points(axes, specs, rng)
        dev = relative_deviation(multilinear(axes, values, points), evaluate(points), floor).max(axis=-1)
        k = int(np.argmax(dev))
        largest = float(dev[k])
        accuracy = largest * (1.0 + 1.0 / (CHECK_INTERIOR.get(len(axes), 3) + 1) ** 2)
        if accuracy <= tolerance or rounds == MAX_ROUNDS or largest > STALL * previous:
            break
        if log is not None and time.monotonic() - started > PROGRESS_AFTER_S:
            log(f"  refining the grid: round {rounds} of at most {MAX_ROUNDS}, {' x '.join(str(a.size) for a in axes)} "
                f"nodes, deviation up to {percent_up(accuracy)} % (target {100 * tolerance:g} %)")
        previous = largest
        failing = dev * (accuracy / largest) > tolerance
        for a, spec in enumerate(specs):  # the intervals the failing points lie in
            axis = axes[a]
            if not spec.refine or axis.size < 2:
                continue
            x = points[a][failing]
            i = np.clip(np.searchsorted(axis, x, side="right") - 1, 0, axis.size - 2)
            interior = (x > axis[i]) & (x < axis[i + 1])
            grown = _split(axis, np.unique(i[interior]), spec.geometric)
            if _grows(axes, a, grown):
                axes[a] = grown
        tol *= 0.5
    return Sampling(tuple(axes), values, accuracy, largest, tuple(float(p[k]) for p in points), int(dev.size),
                    tolerance, floor, rounds)


def percent_up(x: float, digits: int = 3) -> str:
    """``x`` (a fraction) in percent, rounded up to ``digits`` significant digits (a bound stays a bound)."""
    if x <= 0:
        return "0"
    value = 100.0 * x
    step = 10.0 ** (math.floor(math.log10(value)) - digits + 1)
    return f"{math.ceil(value / step - 1e-9) * step:.{max(0, digits - 1 - math.floor(math.log10(value)))}f}"
