"""The coupled system: slaves, links, coupling values and their history.

:class:`CoupledSystem` is what the algorithms operate on. It owns

- the slaves (anything implementing :class:`tribocosim.cosim.engine.slave.Slave`) in scene order;
- the links (output -> input) as index arrays, and ``y``, the current value of every link's
  source output at the current communication point;
- the history of ``y`` at the last accepted communication points (for extrapolation);
- the direct-feedthrough structure and the loop Jacobian, measured at start by probing.

It knows how to apply a predicted input polynomial to a slave for one step (input values plus
``fmi2SetRealInputDerivatives`` when the FMU can interpolate inputs, or companion inputs
``der(u)``/``der(u,2)``, or else the step mean of the polynomial), how to refresh outputs at a
communication point (in feedthrough order), and how to save and restore the whole state for
rollback.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tribocosim.errors import CosimStepError
from tribocosim.cosim.engine.extrapolation import History, StepPolynomial
from tribocosim.cosim.engine.schemes import LinkSpec
from tribocosim.cosim.engine.graph import algebraic_loops, evaluation_order
from tribocosim.cosim.engine.slave import Slave


@dataclass
class Snapshot:
    """Everything needed to repeat a macro step: slave states, coupling values, history."""

    states: list
    y: np.ndarray
    history: History


_GET = {"Real": "get_real", "Integer": "get_integer", "Enumeration": "get_integer", "Boolean": "get_boolean"}
_SET = {"Real": "set_real", "Integer": "set_integer", "Enumeration": "set_integer", "Boolean": "set_boolean"}


def _getter(slave: Slave, kind: str):
    return getattr(slave, _GET[kind])


def _setter(slave: Slave, kind: str):
    return getattr(slave, _SET[kind])


class CoupledSystem:
    """Slaves plus links, with the coupling values and their history.

    Parameters
    ----------
    slaves : list of Slave
        In scene order.
    links : list of LinkSpec
    order : int
        Extrapolation order (history depth order + 1).
    feedthrough : list of bool or None
        Per slave: False if its outputs never depend directly on its inputs, True if they may,
        None if unknown (probed at start).
    structure : ndarray of bool, optional
        Declared dependencies, structure[k, j]: link k's source may depend on link j's target
        (from the model descriptions); masks the probed dependencies.
    """

    def __init__(self, slaves: list[Slave], links: list[LinkSpec], order: int, feedthrough: list[bool | None] | None = None,
                 structure: np.ndarray | None = None):
        self.slaves = slaves
        self.links = links
        self.order = order
        self.m = len(links)
        self.y = np.zeros(self.m)
        #: the input value each link's target FMU has at the end of the last step (energy control)
        self.u_end = np.zeros(self.m)
        self.history = History(depth=min(order, 2) + 1)
        self.feedthrough = list(feedthrough) if feedthrough is not None else [None] * len(slaves)
        self.structure = structure
        self.dep = np.zeros((self.m, self.m), dtype=bool)
        self.jacobian = np.zeros((self.m, self.m))
        self.loops = []
        self.hold_mean: set[str] = set()
        n = len(slaves)
        # per slave: incoming link indices grouped by target type, outgoing grouped by source type
        self._in: list[dict[str, list[int]]] = [{} for _ in range(n)]
        self._out: list[dict[str, list[int]]] = [{} for _ in range(n)]
        for k, l in enumerate(links):
            self._in[l.target].setdefault(l.target_type, []).append(k)
            self._out[l.source].setdefault(l.source_type, []).append(k)
        self._in_all = [[k for ks in d.values() for k in ks] for d in self._in]
        self._out_vrs = [{t: self._unique([links[k].source_vr for k in ks]) for t, ks in d.items()} for d in self._out]
        self.eval_order = list(range(n))
        #: per slave, the values its linked inputs were last set to (skips redundant sets)
        self._written: list[np.ndarray | None] = [None] * n

    @staticmethod
    def _unique(vrs: list[int]) -> tuple[list[int], np.ndarray]:
        uniq = sorted(set(vrs))
        pos = {v: i for i, v in enumerate(uniq)}
        return uniq, np.array([pos[v] for v in vrs], dtype=int)

    # --- reading and writing coupling values -------------------------------------------------
    def read_outputs(self, i: int, t: float) -> None:
        """Read slave i's linked outputs into ``y``; raise CosimStepError on non-finite values."""
        for kind, ks in self._out[i].items():
            vrs, idx = self._out_vrs[i][kind]
            vals = _getter(self.slaves[i], kind)(vrs)
            self.y[ks] = vals[idx]
        bad = [k for ks in self._out[i].values() for k in ks if not np.isfinite(self.y[k])]
        if bad:
            names = ", ".join(sorted({self.links[k].label.split(" -> ")[0] for k in bad}))
            raise NonFiniteOutput(i, f"non-finite output {names} = {self.y[bad[0]]!r} at t = {t:.9g} s")

    def write_inputs(self, i: int, values: np.ndarray) -> None:
        """Set slave i's linked inputs to ``values[k]`` for each incoming link k."""
        for kind, ks in self._in[i].items():
            _setter(self.slaves[i], kind)([self.links[k].target_vr for k in ks], values[ks])
        self._written[i] = values.copy()

    def _unchanged(self, i: int, values: np.ndarray) -> bool:
        """True if slave i's linked inputs already hold ``values`` (no need to set them again)."""
        w = self._written[i]
        if w is None:
            return False
        ks = self._in_all[i]
        return bool(np.array_equal(w[ks], values[ks]))

    def apply_step_inputs(self, i: int, poly: StepPolynomial, order: int) -> None:
        """Set slave i's inputs for one step from the predicted polynomial of every link.

        Real continuous links get the polynomial (value plus derivatives when the FMU takes
        them; else its step mean); other links get the value at the start of the step.
        """
        if not self._in[i]:
            return
        slave = self.slaves[i]
        if order == 0 and self._unchanged(i, poly.c0):
            self.u_end[self._in_all[i]] = poly.c0[self._in_all[i]]
            return
        self._written[i] = None
        end = poly.value(poly.h) if order > 0 else poly.c0
        for kind, ks in self._in[i].items():
            if kind != "Real" or order == 0:
                _setter(slave, kind)([self.links[k].target_vr for k in ks], poly.c0[ks])
                self.u_end[ks] = poly.c0[ks]
                continue
            vrs, vals, dvrs = [], [], {1: ([], []), 2: ([], [])}
            for k in ks:
                l = self.links[k]
                if not l.continuous:
                    vrs.append(l.target_vr)
                    vals.append(poly.c0[k])
                    self.u_end[k] = poly.c0[k]
                elif slave.can_interpolate_inputs:
                    vrs.append(l.target_vr)
                    vals.append(poly.c0[k])
                    self.u_end[k] = end[k]
                    for q in range(1, order + 1):
                        dvrs[q][0].append(l.target_vr)
                        dvrs[q][1].append(poly.derivative(q)[k])
                elif l.derivative_vrs[0] is not None:
                    vrs.append(l.target_vr)
                    vals.append(poly.c0[k])
                    self.u_end[k] = end[k]
                    for q in range(1, 3):
                        dv = l.derivative_vrs[q - 1]
                        if dv is not None:
                            vrs.append(dv)
                            vals.append(poly.derivative(q)[k] if q <= order else 0.0)
                else:
                    self.hold_mean.add(l.label)
                    vrs.append(l.target_vr)
                    vals.append(poly.mean()[k])
                    self.u_end[k] = vals[-1]
            slave.set_real(vrs, vals)
            if slave.can_interpolate_inputs:
                for q in range(1, order + 1):
                    if dvrs[q][0]:
                        slave.set_input_derivatives(dvrs[q][0], q, dvrs[q][1])
        if order == 0:
            self._written[i] = poly.c0.copy()

    def has_inputs(self, i: int) -> bool:
        return bool(self._in[i])

    def refresh(self, t: float, *, propagate: bool, values: np.ndarray | None = None) -> None:
        """Bring ``y`` up to date at a communication point.

        With ``propagate``, each slave (in feedthrough order) first gets its inputs set to the
        current values (``values`` if given, e.g. an iterate, else the sources' just-read
        outputs), then its outputs are read. Without it, outputs are read as they are (the
        inputs the slave stepped with), as fixed-step masters such as libcosim do.
        """
        for i in self.eval_order:
            if propagate and self._in[i] and self.feedthrough[i] is not False:
                self.write_inputs(i, self.y if values is None else values)
            self.read_outputs(i, t)

    # --- rollback ----------------------------------------------------------------------------
    def snapshot(self) -> Snapshot:
        """Save every slave's state, ``y`` and the history."""
        return Snapshot([s.get_state() for s in self.slaves], self.y.copy(), self.history.copy())

    def restore(self, snap: Snapshot) -> None:
        """Return to a snapshot (it stays valid for further restores)."""
        for s, st in zip(self.slaves, snap.states):
            s.set_state(st)
        self._written = [None] * len(self.slaves)
        self.y = snap.y.copy()
        self.history = snap.history.copy()

    def release(self, snap: Snapshot) -> None:
        """Free a snapshot's slave states."""
        for s, st in zip(self.slaves, snap.states):
            s.free_state(st)

    # --- feedthrough probing -----------------------------------------------------------------
    def probe_feedthrough(self, t: float) -> None:
        """Measure the loop Jacobian D[k, j] = d y_k / d u_j by perturbing each linked input.

        Sets ``dep`` (structural dependency; a declared structure, if given, masks it),
        ``jacobian``, ``loops`` (with contraction factors) and ``eval_order``. Slaves whose
        feedthrough is declared False are not probed.
        """
        base = self.y.copy()
        for j, l in enumerate(self.links):
            i = l.target
            if self.feedthrough[i] is False or l.target_type != "Real":
                continue
            u = base[j]
            delta = 1e-6 * max(1.0, abs(u))
            slave = self.slaves[i]
            slave.set_real([l.target_vr], [u + delta])
            self.read_outputs(i, t)
            pert = self.y.copy()
            slave.set_real([l.target_vr], [u])
            self.read_outputs(i, t)
            for k in self._out_links(i):
                d = (pert[k] - self.y[k]) / delta
                tol = 1e-8 * max(1.0, abs(self.y[k])) / max(1.0, abs(u))
                self.jacobian[k, j] = d
                self.dep[k, j] = abs(d) > tol
        if self.structure is not None:
            self.dep &= self.structure
            self.jacobian[~self.dep] = 0.0
        for i, ft in enumerate(self.feedthrough):
            if ft is None:
                outs = self._out_links(i)
                self.feedthrough[i] = bool(self.dep[outs].any()) if outs else False
        self._written = [None] * len(self.slaves)
        self.loops = algebraic_loops(self.dep, self.jacobian)
        pairs = [(l.source, l.target) for l in self.links]
        self.eval_order = evaluation_order(len(self.slaves), pairs, self.dep)
        self.y = base

    def _out_links(self, i: int) -> list[int]:
        return [k for ks in self._out[i].values() for k in ks]


class NonFiniteOutput(CosimStepError):
    """A slave returned NaN or infinity for a linked output (the step may be retried)."""

    def __init__(self, slave_index: int, message: str) -> None:
        super().__init__(message)
        self.slave_index = slave_index
