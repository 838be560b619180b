"""Coupling algorithms: one macro step from t to t + h on a :class:`~tribocosim.cosim.engine.system.CoupledSystem`.

Jacobi
    Every slave gets the extrapolated inputs (polynomial of degree q through the last q + 1
    communication points), all slaves step, then the outputs are refreshed in feedthrough order.
Gauss-Seidel
    Slaves step one after the other in an order from the instance graph
    (:func:`tribocosim.cosim.engine.graph.gauss_seidel_order`); a slave whose input comes from a slave already
    stepped gets the *interpolation* through that slave's new output, other inputs are
    extrapolated. Same order of accuracy as Jacobi, smaller error constant, and better stability
    for stiff couplings when the "soft" subsystem goes first (Busch 2016,
    doi:10.1002/zamm.201500196; Kübler & Schiehlen 2000, doi:10.1023/A:1009810318420).
Iterative
    The macro step is repeated from the saved state until the coupling values x at t + h are a
    fixed point of the step map G (the linked outputs after a step whose inputs interpolate x):
    ``|G(x) - x| <= tol (1 + |x|)`` component-wise. Updates:

    - fixed point with constant relaxation, x <- x + w (G(x) - x); converges iff the
      spectral radius of I - w (I - G') is below 1; for an algebraic loop with w = 1 this is
      the loop's contraction factor rho(D);
    - fixed point with Aitken's dynamic relaxation (Irons & Tuck 1969; Küttler & Wall 2008,
      doi:10.1007/s00466-008-0255-5);
    - quasi-Newton IQN-ILS (Degroote, Bathe & Vierendeels 2009,
      doi:10.1016/j.compstruc.2008.11.013), equivalently Anderson mixing: with residual
      differences dR and output differences dG, gamma = argmin |r_k - dR gamma| and
      x_{k+1} = G(x_k) - dG gamma. For a linear coupling of m values it converges in at most
      m + 1 iterations whatever the contraction; columns from the last ``reuse`` steps are kept.

    With interpolation degree 0 the inputs over the step are the end values (an implicit-Euler
    coupling), with degree 1 the straight line from the start to the end values (trapezoidal
    coupling, second order and much more stable for stiff couplings).

The first step of a degree-2 scheme has only one history point; if every slave can roll back
the step is taken once more with the interpolation through its own result (one corrector
pass), which keeps the startup error at O(h^3) and hence the global order 3.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tribocosim.errors import ConvergenceError
from tribocosim.cosim.engine.extrapolation import StepPolynomial
from tribocosim.cosim.engine.schemes import ALGORITHMS, Iterative
from tribocosim.cosim.engine.slave import DISCARD
from tribocosim.cosim.engine.system import CoupledSystem

@dataclass
class StepResult:
    """Outcome of one macro step attempt.

    Attributes
    ----------
    ok : bool
        False if a slave discarded the step (``discarded_by`` names it).
    iterations : int
        Passes over the slaves (1 for non-iterative schemes).
    residual : float
        Final scaled coupling residual (iterative), else 0.
    """

    ok: bool = True
    discarded_by: int | None = None
    iterations: int = 1
    residual: float = 0.0
    contraction: float = float("nan")


def _mix(a: StepPolynomial, b: StepPolynomial, use_b: np.ndarray) -> StepPolynomial:
    return StepPolynomial(a.h, np.where(use_b, b.c0, a.c0), np.where(use_b, b.c1, a.c1), np.where(use_b, b.c2, a.c2))


class Algorithm:
    """Base: the settings every scheme shares.

    Every scheme is made with ``(order, propagate, sequence, settings)``: the extrapolation order,
    whether outputs are propagated through direct feedthrough after a step, the Gauss-Seidel
    sequence of slaves, and the scheme's own settings (its ``[master.<name>]`` table).
    """

    name = "base"

    def __init__(self, order: int, propagate: bool = True, sequence: tuple[int, ...] = (), settings=None) -> None:
        self.order = order
        self.propagate = propagate

    def step(self, sys: CoupledSystem, t: float, h: float, tick: float) -> StepResult:
        """One macro step; the first step of a degree-2 scheme gets one corrector pass (if it can roll back)."""
        if not (self.order >= 2 and len(sys.history.ticks) == 1 and all(s.can_roll_back for s in sys.slaves)):
            return self._pass(sys, t, h, tick, None)
        snap = sys.snapshot()
        try:
            res = self._pass(sys, t, h, tick, None)
            if res.ok:
                end = sys.y.copy()
                sys.restore(snap)
                res = self._pass(sys, t, h, tick, sys.history.interpolate(1, tick, h, end))
                res.iterations = 2
            return res
        finally:
            sys.release(snap)

    def _pass(self, sys: CoupledSystem, t: float, h: float, tick: float, first: StepPolynomial | None) -> StepResult:
        """One pass over the slaves; ``first`` replaces the predicted inputs (corrector)."""
        raise NotImplementedError  # pragma: no cover


class Jacobi(Algorithm):
    """All slaves step in parallel on extrapolated inputs."""

    name = "jacobi"

    def _pass(self, sys: CoupledSystem, t: float, h: float, tick: float, first: StepPolynomial | None) -> StepResult:
        poly = first if first is not None else sys.history.extrapolate(self.order, tick, h)
        for i in range(len(sys.slaves)):
            sys.apply_step_inputs(i, poly, self.order)
        for i, s in enumerate(sys.slaves):
            if s.do_step(t, h) == DISCARD:
                return StepResult(False, discarded_by=i)
        sys.refresh(t + h, propagate=self.propagate)
        return StepResult()


class GaussSeidel(Algorithm):
    """Slaves step in sequence; later slaves interpolate the new outputs of earlier ones."""

    name = "gauss-seidel"

    def __init__(self, order: int, propagate: bool = True, sequence: tuple[int, ...] = (), settings=None) -> None:
        super().__init__(order, propagate)
        self.sequence = sequence

    def _pass(self, sys: CoupledSystem, t: float, h: float, tick: float, first: StepPolynomial | None) -> StepResult:
        ext = first if first is not None else sys.history.extrapolate(self.order, tick, h)
        stepped = np.zeros(len(sys.slaves), dtype=bool)
        src = np.array([l.source for l in sys.links], dtype=int)
        for i in self.sequence:
            use_new = stepped[src] if sys.m else np.zeros(0, dtype=bool)
            poly = ext
            if use_new.any():
                order = 1 if first is not None else self.order
                poly = _mix(ext, sys.history.interpolate(order, tick, h, sys.y), use_new)
            sys.apply_step_inputs(i, poly, self.order)
            if sys.slaves[i].do_step(t, h) == DISCARD:
                return StepResult(False, discarded_by=i)
            if self.propagate and sys.has_inputs(i):
                sys.write_inputs(i, np.where(use_new, sys.y, poly.value(h)))
            sys.read_outputs(i, t + h)
            stepped[i] = True
        sys.refresh(t + h, propagate=self.propagate)
        return StepResult()


@dataclass
class _Secants:
    """Difference columns of IQN-ILS: residual and output differences, oldest first."""

    dr: list[np.ndarray] = field(default_factory=list)
    dg: list[np.ndarray] = field(default_factory=list)


class IterativeCoupling(Algorithm):
    """Repeat the macro step from the saved state until the coupling values converge."""

    name = "iterative"

    def __init__(self, order: int, propagate: bool = True, sequence: tuple[int, ...] = (),
                 settings: Iterative | None = None) -> None:
        super().__init__(min(order, 2), propagate=True)
        self.settings = settings if settings is not None else Iterative()
        self.reused: list[_Secants] = []

    def step(self, sys: CoupledSystem, t: float, h: float, tick: float) -> StepResult:
        st = self.settings
        snap = sys.snapshot()
        x = sys.history.extrapolate(self.order, tick, h).value(h)
        cont = np.array([l.continuous for l in sys.links], dtype=bool)
        x = np.where(cont, x, sys.y)
        own = _Secants()
        prev_r = prev_g = None
        omega = 1.0 if st.relaxation == "aitken" else float(st.relaxation)
        errs: list[float] = []  # scaled residuals (convergence test)
        norms: list[float] = []  # max |G(x) - x| (contraction and divergence)
        try:
            for k in range(st.max_iterations):
                if k > 0:
                    sys.restore(snap)
                poly = sys.history.interpolate(self.order, tick, h, x)
                for i in range(len(sys.slaves)):
                    sys.apply_step_inputs(i, poly, self.order)
                for i, s in enumerate(sys.slaves):
                    if s.do_step(t, h) == DISCARD:
                        sys.restore(snap)
                        return StepResult(False, discarded_by=i, iterations=k + 1)
                sys.refresh(t + h, propagate=True, values=x)
                g = sys.y.copy()
                r = g - x
                scale = st.tolerance * (1.0 + np.abs(x))
                err = float(np.max(np.abs(r) / scale)) if sys.m else 0.0
                errs.append(err)
                norms.append(float(np.max(np.abs(r))) if sys.m else 0.0)
                if err <= 1.0:
                    self._remember(own)
                    return StepResult(True, iterations=k + 1, residual=err, contraction=_rate(norms))
                self._check_divergence(norms, t, sys, r, scale)
                if prev_r is not None:
                    own.dr.append(r - prev_r)
                    own.dg.append(g - prev_g)
                if st.method == "quasi-newton" and (own.dr or any(s.dr for s in self.reused)):
                    x_new = self._iqn_ils(own, r, g, scale)
                elif st.relaxation == "aitken" and prev_r is not None:
                    dr = r - prev_r
                    denom = float(dr @ dr)
                    if denom > 0.0:
                        omega = float(np.clip(-omega * float(prev_r @ dr) / denom, -2.0, 2.0))
                    x_new = x + omega * r
                else:
                    x_new = x + omega * r
                prev_r, prev_g = r, g
                x = np.where(cont, x_new, g)
            raise ConvergenceError(
                f"iterative coupling did not converge in {st.max_iterations} iterations at t = {t:.9g} s "
                f"(h = {h:.3g} s): scaled residual {errs[-1]:.3g} > 1; estimated contraction factor "
                f"{_rate(norms):.3g}; largest residual in {_worst(sys, r, scale)}",
                contraction=_rate(norms), iterations=len(norms),
            )
        finally:
            sys.release(snap)

    def _check_divergence(self, norms: list[float], t: float, sys: CoupledSystem, r, scale) -> None:
        """Raise if the residual |G(x) - x| grew over the last three iterations and beyond the first one."""
        if len(norms) < 8:
            return
        a, b, c = norms[-3:]
        if not (norms[-1] > norms[0] and a <= b <= c) and np.isfinite(norms[-1]):
            return
        rate = _rate(norms[-7:])  # an even window: loops alternate between their links
        raise ConvergenceError(
            f"iterative coupling diverges at t = {t:.9g} s: the residual grew from {norms[0]:.3g} to "
            f"{norms[-1]:.3g} in {len(norms)} iterations (observed contraction factor {rate:.3g} >= 1: the "
            f"coupling map is not a contraction); largest residual in {_worst(sys, r, scale)}. A fixed-point "
            "iteration cannot converge here; use method = \"quasi-newton\"",
            contraction=rate, iterations=len(norms),
        )

    def _iqn_ils(self, own: _Secants, r: np.ndarray, g: np.ndarray, scale: np.ndarray) -> np.ndarray:
        dr = [c for s in self.reused for c in s.dr] + own.dr
        dg = [c for s in self.reused for c in s.dg] + own.dg
        keep = max(1, 2 * len(r))
        dr, dg = dr[-keep:], dg[-keep:]
        V = np.column_stack(dr) / scale[:, None]
        W = np.column_stack(dg)
        gamma, *_ = np.linalg.lstsq(V, r / scale, rcond=1e-12)
        return g - W @ gamma

    def _remember(self, own: _Secants) -> None:
        if self.settings.reuse <= 0 or not own.dr:
            return
        self.reused.append(own)
        del self.reused[: -self.settings.reuse]


def _rate(norms: list[float]) -> float:
    """Geometric-mean ratio of successive residuals (the observed contraction factor)."""
    e = [x for x in norms if x > 0 and np.isfinite(x)]
    if len(e) < 2:
        return float("nan")
    return float((e[-1] / e[0]) ** (1.0 / (len(e) - 1)))


def _worst(sys: CoupledSystem, r: np.ndarray, scale: np.ndarray) -> str:
    if not sys.m:
        return "(no links)"
    k = int(np.argmax(np.abs(r) / scale))
    return f"{sys.links[k].label} (residual {r[k]:.3g})"


#: the class of every coupling scheme of :data:`~tribocosim.cosim.engine.schemes.ALGORITHMS`, by its scene name
ALGORITHM_CLASSES: dict[str, type[Algorithm]] = {cls.name: cls for cls in (Jacobi, GaussSeidel, IterativeCoupling)}
assert set(ALGORITHM_CLASSES) == set(ALGORITHMS), "every scheme of schemes.ALGORITHMS has its class here"


def create(name: str, order: int, propagate: bool, sequence: tuple[int, ...], settings) -> Algorithm:
    """The scheme ``name`` (a key of :data:`ALGORITHMS`) for a run: extrapolation ``order``, output propagation,
    Gauss-Seidel ``sequence`` and its ``[master.<name>]`` settings."""
    return ALGORITHM_CLASSES[name](order, propagate, sequence, settings)
