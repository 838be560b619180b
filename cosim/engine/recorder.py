"""The recorder of a run's output variables, an observer of the master (:mod:`tribocosim.cosim.engine.observers`).

The recorder reads the variables named in ``[output] variables`` from the slaves at every
accepted communication point (one ``fmi2Get*`` call per slave) and keeps them in memory; rows
written after a snapshot are dropped again when the master rolls back to it. It writes a CSV
file in the FMI cross-check format (:mod:`tribocosim.cosim.engine.results_csv`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from tribocosim.cosim.engine.observers import Observer
from tribocosim.cosim.engine.results_csv import write_csv
from tribocosim.cosim.engine.schemes import VariableRef
from tribocosim.cosim.engine.slave import Slave


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
        """Write ``time`` and the recorded columns (in the scene's order) to a CSV file
        (:func:`tribocosim.cosim.engine.results_csv.write_csv`)."""
        data = np.array(self._rows, dtype=float).reshape(len(self._rows), len(self.names))
        return write_csv(path, self.names, self._times, np.ascontiguousarray(data).ravel())
