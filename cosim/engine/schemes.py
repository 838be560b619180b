"""What a scene can ask of the master, without the master: the names of the coupling schemes and step estimators,
their settings tables, and what the scene checks must know of them (numpy-free, so that reading a scene imports no
numerical code).

- :data:`ALGORITHMS`: every coupling scheme by its scene name (``[master] algorithm``), with the class of its
  ``[master.<name>]`` table and whether it rolls back or solves algebraic loops; the classes that run them are
  :data:`tribocosim.cosim.engine.algorithms.ALGORITHM_CLASSES`.
- :data:`ESTIMATORS`: every error estimator of adaptive steps by its scene name (``[master.adaptive] estimator``);
  the controllers are :data:`tribocosim.cosim.engine.stepcontrol.ESTIMATOR_CLASSES`.
- :class:`Iterative` and :class:`Adaptive`: the ``[master.iterative]`` and ``[master.adaptive]`` settings.
- :class:`VariableRef`: ``instance.variable``, the name of an FMU variable in a scene; :class:`LinkSpec`: a
  connection in index form, as the master couples it.
"""

from __future__ import annotations

#: a fixed macro step is 2**FIXED_SUBDIVISION ticks (room for this many halvings; :mod:`.timegrid`)
FIXED_SUBDIVISION = 10
#: ticks per minimum step in variable-step runs (:mod:`.timegrid`)
VARIABLE_SUBDIVISION = 6
ITERATION_METHODS = ("fixed-point", "quasi-newton")

# The records of the run path are plain classes with slots: a class made by ``dataclasses`` costs the import of its
# module the compilation of its generated methods, 3 to 4 million instructions a class (callgrind), which is more
# than a run spends on most of its scene checks.


class VariableRef:
    """``instance.variable`` (the instance name is everything before the first dot); equal and hashed as the pair."""

    __slots__ = ("instance", "variable")

    def __init__(self, instance: str, variable: str) -> None:
        self.instance, self.variable = instance, variable

    def __str__(self) -> str:
        return f"{self.instance}.{self.variable}"

    def __repr__(self) -> str:
        return f"VariableRef({self.instance!r}, {self.variable!r})"

    def __eq__(self, other) -> bool:
        if other.__class__ is not VariableRef:
            return NotImplemented
        return self.instance == other.instance and self.variable == other.variable

    def __hash__(self) -> int:
        return hash((self.instance, self.variable))


class LinkSpec:
    """One link in index form (what the master needs from a validated connection): source and target instance
    index, value reference and FMI type, whether it carries a continuous Real, its label, and the value references
    of the target's derivative inputs ``der(u)``, ``der(u, 2)`` (None where there is none)."""

    __slots__ = ("source", "source_vr", "source_type", "target", "target_vr", "target_type", "continuous", "label",
                 "derivative_vrs")

    def __init__(self, source: int, source_vr: int, source_type: str, target: int, target_vr: int, target_type: str,
                 continuous: bool, label: str, derivative_vrs: tuple[int | None, int | None] = (None, None)) -> None:
        self.source, self.source_vr, self.source_type = source, source_vr, source_type
        self.target, self.target_vr, self.target_type = target, target_vr, target_type
        self.continuous, self.label, self.derivative_vrs = continuous, label, derivative_vrs

    def __repr__(self) -> str:
        return f"LinkSpec({self.label!r})"


class Iterative:
    """[master.iterative]: the fixed-point / quasi-Newton iteration of a macro step."""

    __slots__ = ("method", "relaxation", "tolerance", "max_iterations", "reuse")
    #: the keys of the table, in order
    FIELDS = __slots__

    def __init__(self, method: str = "quasi-newton", relaxation: float | str = 1.0, tolerance: float = 1e-8,
                 max_iterations: int = 50, reuse: int = 2) -> None:
        self.method, self.relaxation, self.tolerance = method, relaxation, tolerance
        self.max_iterations, self.reuse = max_iterations, reuse

    def as_dict(self) -> dict:
        """The settings by key (as the results' metadata records them)."""
        return {k: getattr(self, k) for k in self.FIELDS}

    def __repr__(self) -> str:
        return f"Iterative({', '.join(f'{k}={v!r}' for k, v in self.as_dict().items())})"

    @classmethod
    def parse(cls, p, table: dict, key: str) -> "Iterative":
        """The settings of a ``[master.iterative]`` table; problems go to the collector ``p``."""
        p.unknown_keys(table, cls.FIELDS, key)
        d = cls()
        method = p.choice(table, "method", key, ITERATION_METHODS, d.method)
        relax = table.get("relaxation", d.relaxation)
        if relax != "aitken" and (isinstance(relax, bool) or not isinstance(relax, (int, float)) or not 0 < relax <= 2):
            p.add(f"{key}.relaxation", f"must be a number in (0, 2] or \"aitken\", got {relax!r}")
            relax = d.relaxation
        return cls(
            method,
            relax if relax == "aitken" else float(relax),
            float(p.number(table, "tolerance", key, d.tolerance, positive=True)),
            int(p.number(table, "max_iterations", key, d.max_iterations, positive=True, integer=True)),
            int(p.number(table, "reuse", key, d.reuse, integer=True)),
        )


class Adaptive:
    """[master.adaptive]: error-controlled variable step.

    ``tolerance`` is relative, ``absolute_tolerance`` (default: ``tolerance``) absolute.
    Step doubling accepts a step H whose local error estimates e_i of the coupling signals y_i
    satisfy max_i |e_i| / (H (absolute_tolerance + tolerance |y_i|)) <= 1 (error per unit
    step: the tolerance is per second of simulated time); the energy estimator normalises the
    energy residual of each power bond by absolute_tolerance + tolerance * energy level.
    ``estimator`` is a name of :data:`ESTIMATORS`. ``step_quantum`` (step doubling; default none):
    steps are whole multiples of twice it, so that half steps land on the grid k * step_quantum
    (set it to the strip's ``internal_step``); it must be a whole number of grid ticks
    (min_step / 2**VARIABLE_SUBDIVISION), e.g. min_step = 2 * step_quantum.
    """

    __slots__ = ("tolerance", "absolute_tolerance", "min_step", "max_step", "estimator", "safety", "step_quantum")
    #: the keys of the table, in order
    FIELDS = __slots__

    def __init__(self, tolerance: float = 1e-4, absolute_tolerance: float | None = None, min_step: float = 1e-7,
                 max_step: float = 1e-2, estimator: str = "step-doubling", safety: float = 0.9,
                 step_quantum: float | None = None) -> None:
        self.tolerance, self.absolute_tolerance, self.min_step, self.max_step = (tolerance, absolute_tolerance,
                                                                                 min_step, max_step)
        self.estimator, self.safety, self.step_quantum = estimator, safety, step_quantum

    @property
    def atol(self) -> float:
        return self.tolerance if self.absolute_tolerance is None else self.absolute_tolerance

    def as_dict(self) -> dict:
        """The settings by key (as the results' metadata records them)."""
        return {k: getattr(self, k) for k in self.FIELDS}

    def __repr__(self) -> str:
        return f"Adaptive({', '.join(f'{k}={v!r}' for k, v in self.as_dict().items())})"

    @classmethod
    def parse(cls, p, table: dict, key: str, step: float) -> "Adaptive":
        """The settings of a ``[master.adaptive]`` table for the experiment's ``step``; problems go to ``p``."""
        p.unknown_keys(table, cls.FIELDS, key)
        d = cls()
        tol = p.number(table, "tolerance", key, d.tolerance, positive=True)
        atol = p.number(table, "absolute_tolerance", key, None, positive=True)
        hmin = p.number(table, "min_step", key, min(d.min_step, step), positive=True)
        hmax = p.number(table, "max_step", key, max(d.max_step, step), positive=True)
        est = p.choice(table, "estimator", key, tuple(ESTIMATORS), d.estimator)
        safety = p.number(table, "safety", key, d.safety, positive=True)
        quantum = p.number(table, "step_quantum", key, None, positive=True)
        if not hmin <= step <= hmax:
            p.add(key, f"need min_step <= experiment.step <= max_step, got {hmin!r} <= {step!r} <= {hmax!r}")
        if safety >= 1.0:
            p.add(f"{key}.safety", f"must be in (0, 1), got {safety!r}")
        if quantum is not None:
            tick = hmin / 2**VARIABLE_SUBDIVISION
            ratio = quantum / tick
            if est != "step-doubling":
                p.add(f"{key}.step_quantum", f"is used by the step-doubling estimator only, not by {est!r}")
            elif ratio < 0.5 or abs(ratio - round(ratio)) > 1e-9 * ratio:
                p.add(f"{key}.step_quantum", f"must be a whole number of grid ticks (min_step / "
                      f"{2**VARIABLE_SUBDIVISION} = {tick!r} s), e.g. min_step = 2 * step_quantum; got {quantum!r}")
            elif 2 * quantum > hmax * (1 + 1e-12):
                p.add(f"{key}.step_quantum", f"two quanta ({2 * quantum!r} s) exceed max_step = {hmax!r}")
        return cls(float(tol), atol if atol is None else float(atol), float(hmin), float(hmax), est, float(safety),
                   quantum if quantum is None else float(quantum))


class AlgorithmSpec:
    """A coupling scheme as the scene checks see it: the class of its ``[master.<name>]`` table (or None), and
    whether it repeats every macro step from saved FMU states or converges algebraic loops within a step."""

    __slots__ = ("settings", "rolls_back", "solves_loops")

    def __init__(self, settings: type | None = None, rolls_back: bool = False, solves_loops: bool = False) -> None:
        self.settings, self.rolls_back, self.solves_loops = settings, rolls_back, solves_loops


class EstimatorSpec:
    """An error estimator of adaptive steps as the scene checks see it: whether it rejects steps by restoring saved
    FMU states, whether it needs [[power_bonds]]."""

    __slots__ = ("rolls_back", "needs_bonds")

    def __init__(self, rolls_back: bool, needs_bonds: bool) -> None:
        self.rolls_back, self.needs_bonds = rolls_back, needs_bonds


#: every coupling scheme by its scene name (``[master] algorithm``): the one list of them
ALGORITHMS: dict[str, AlgorithmSpec] = {
    "jacobi": AlgorithmSpec(),
    "gauss-seidel": AlgorithmSpec(),
    "iterative": AlgorithmSpec(Iterative, rolls_back=True, solves_loops=True),
}

def loop_message(loop, labels: str, algorithm: str) -> tuple[str, bool]:
    """What a master says of an algebraic loop through the links ``labels`` before it runs ``algorithm``, and
    whether that is a warning: a loop whose contraction factor rho is >= 1 cannot be stable under a scheme that
    breaks it with a one-step delay (y_n+1 = D y_n + s)."""
    msg = f"algebraic loop through {labels}: contraction factor rho = {loop.contraction:.4g}"
    if ALGORITHMS[algorithm].solves_loops or loop.contraction < 1.0:
        return msg, False
    solvers = " or ".join(f'"{name}"' for name, a in ALGORITHMS.items() if a.solves_loops)
    return (msg + f" >= 1: {algorithm} cannot be stable here (the loop is broken with a one-step delay, "
            f"y_n+1 = D y_n + s); use algorithm = {solvers}"), True


#: every error estimator by its scene name (``[master.adaptive] estimator``)
ESTIMATORS: dict[str, EstimatorSpec] = {
    "step-doubling": EstimatorSpec(rolls_back=True, needs_bonds=False),
    "energy": EstimatorSpec(rolls_back=False, needs_bonds=True),
}
