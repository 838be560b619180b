"""Observers of a run: the recorder of the scene's output variables, and a progress reporter.

The master notifies a list of observers (:class:`Observer`): after every successful attempt of a
macro step (an observer may refuse the values it read, e.g. non-finite outputs, and the attempt
then counts as failed), when a step is accepted, and around rollbacks (``mark``/``truncate``).

The recorder reads the variables named in ``[output] variables`` from the slaves at every
accepted communication point (one ``fmi2Get*`` call per slave) and keeps them in memory; rows
written after a snapshot are dropped again when the master rolls back to it. It writes a CSV
file in the FMI cross-check format that ``fmpy.util.read_csv`` reads: a header ``"time","a.x",...``
and one row per point, values with 17 significant digits (exact round trip).
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np

from tribocosim.cosim.engine.system import VariableRef
from tribocosim.cosim.engine.slave import Slave


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


class Recorder(Observer):
    """Samples named variables of the slaves at accepted communication points.

    Parameters
    ----------
    slaves : list of Slave
    index : dict
        Instance name -> slave index.
    variables : list of (VariableRef, value reference, type)
        In column order.
    """

    def __init__(self, slaves: list[Slave], index: dict[str, int], variables: list[tuple[VariableRef, int, str]],
                 system=None) -> None:
        self.slaves = slaves
        self.names = [str(ref) for ref, _, _ in variables]
        # recorded outputs that are also link sources are taken from the coupling values, which
        # are fresh whenever the recorder reads (after a step's output refresh): no extra call
        linked = {}
        if system is not None:
            for k, l in enumerate(system.links):
                if l.source_type == "Real":
                    linked.setdefault((l.source, l.source_vr), k)
        self._system = system
        self._from_y = []
        groups: dict[tuple[int, str], list[tuple[int, int]]] = {}
        for col, (ref, vr, kind) in enumerate(variables):
            kind = "Integer" if kind == "Enumeration" else kind
            k = linked.get((index[ref.instance], vr)) if kind == "Real" else None
            if k is not None:
                self._from_y.append((col, k))
                continue
            groups.setdefault((index[ref.instance], kind), []).append((col, vr))
        self._y_cols = np.array([c for c, _ in self._from_y], dtype=int)
        self._y_links = np.array([k for _, k in self._from_y], dtype=int)
        getters = {"Real": "get_real", "Integer": "get_integer", "Boolean": "get_boolean"}
        self._groups = [(i, getters[kind], [c for c, _ in cv], [v for _, v in cv]) for (i, kind), cv in groups.items()]
        self._times: list[float] = []
        self._rows: list[np.ndarray] = []
        self._pending: np.ndarray | None = None  # read after the last successful attempt

    def read(self) -> np.ndarray:
        """Read every recorded variable (one call per slave and type)."""
        row = np.empty(len(self.names))
        for i, getter, cols, vrs in self._groups:
            row[cols] = getattr(self.slaves[i], getter)(vrs)
        if self._from_y:
            row[self._y_cols] = self._system.y[self._y_links]
        return row

    def non_finite(self, row: np.ndarray) -> list[str]:
        """Names of the recorded variables that are NaN or infinite in ``row``."""
        if math.isfinite(float(row.sum())):  # one reduction for the common case
            return []
        return [self.names[j] for j in np.flatnonzero(~np.isfinite(row))]

    def append(self, t: float, row: np.ndarray) -> None:
        """Append a row at time t."""
        self._times.append(t)
        self._rows.append(row)

    def extend(self, times: np.ndarray, rows: np.ndarray) -> None:
        """Append the rows of a block of accepted points (``rows[j]`` at ``times[j]``)."""
        self._times.extend(times.tolist())
        self._rows.extend(np.array(rows, dtype=float))

    def sample(self, t: float) -> None:
        """Read every recorded variable and append a row at time t."""
        self.append(t, self.read())

    def step_attempted(self, t: float) -> list[str]:
        """Read the values after a successful attempt; the non-finite ones make it unusable."""
        row = self.read()
        bad = self.non_finite(row)
        self._pending = None if bad else row
        return bad

    def step_accepted(self, t: float) -> None:
        """Record the values read after the accepted attempt (or read them now)."""
        if self._pending is not None:
            self.append(t, self._pending)
            self._pending = None
        else:
            self.sample(t)

    def mark(self) -> int:
        """Current number of rows (to roll back to)."""
        return len(self._times)

    def truncate(self, mark: int) -> None:
        """Drop rows recorded after ``mark``."""
        del self._times[mark:]
        del self._rows[mark:]
        self._pending = None

    @property
    def time(self) -> np.ndarray:
        return np.array(self._times)

    def columns(self) -> dict[str, np.ndarray]:
        """Recorded columns by 'instance.variable'."""
        data = np.array(self._rows).reshape(len(self._rows), len(self.names))
        return {n: data[:, j].copy() for j, n in enumerate(self.names)}

    def write_csv(self, path: Path) -> Path:
        """Write ``time`` and the recorded columns (in the scene's order) to a CSV file."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(path.suffix + ".part")
        data = np.column_stack([self.time, np.array(self._rows).reshape(len(self._rows), len(self.names))])
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(",".join(f'"{n}"' for n in ["time", *self.names]) + "\n")
            f.write("".join(",".join(map(repr, row)) + "\n" for row in data.tolist()))
        tmp.replace(path)
        return path


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
