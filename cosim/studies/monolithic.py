"""Monolithic references: the same model without the FMI layer and without coupling delay.

A co-simulation master introduces a coupling error (extrapolated inputs, a communication
step). To measure it for any master setting, a scene built from this project's components can be
run *monolithically*: the pure model classes (``step(dt, inputs) -> outputs``,
``get_state``/``set_state``, ARCHITECTURE.md) are coupled directly, with a tiny step and the
coupling solved at every step, so that what remains is the models' own discretization.

Interface
    :class:`Reference`: ``variables`` (the 'instance.variable' names it can produce) and
    ``solve(times) -> {name: values}``. :func:`coupling_error` compares a master
    :class:`~tribocosim.cosim.api.Result` with a reference.

Implementations
    :class:`TwoMassOscillator`: closed form of the linear two-mass oscillator
    (m1 x1'' = -k1 x1 - c1 x1' + F, m2 x2'' = -k3 x2 - c3 x2' - F,
    F = k2 (x2 - x1) + c2 (x2' - x1')), z(t) = V exp(Lambda t) V^-1 z0 by eigen-decomposition
    of the 4x4 system matrix. Used by the tests of the coupling orders.

    :class:`CoupledModels`: the general monolithic runner for pure models: every tiny step
    ``dt`` all models step from the same state with the coupling values held at their end-of-step
    value, repeated (states restored) until the coupling values agree to ``tol``
    (implicit coupling, no delay; the remaining error is O(dt)). Tested against
    :class:`TwoMassOscillator` with the pure parts :class:`MassPart` and :class:`MassCouplingPart`.

The strip-draw scenes: :func:`reference_for_scene` maps each ``component = ...`` FMU of a scene to its model
(``Component.make``, the same function the FMU calls: the bindings of the native core, the FMUs' own code) with the
scene's parameters, connected as the scene connects the FMUs, unconnected inputs held at their scene value (a
parameter of the input's name) or else the FMU's start value, and couples them with :class:`CoupledModels`.
Variables are named like the FMUs' (``press.force_reference``, ``drive.velocity_reference``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from tribocosim.errors import ConvergenceError, SceneError


class Reference(Protocol):
    """A solution to compare a co-simulation with."""

    variables: tuple[str, ...]

    def solve(self, times: np.ndarray) -> dict[str, np.ndarray]:
        """Values of every variable at ``times``."""


def coupling_error(result, reference: Reference, variables: list[str] | None = None) -> dict[str, float]:
    """Largest absolute deviation over the recorded points, per variable.

    Parameters
    ----------
    result : cosim.api.Result
    reference : Reference
    variables : list of str, optional
        Default: the recorded columns the reference provides.
    """
    names = variables or [n for n in result.columns if n in reference.variables]
    ref = reference.solve(result.time)
    return {n: float(np.max(np.abs(result.columns[n] - ref[n]))) for n in names}


@dataclass(frozen=True)
class TwoMassOscillator:
    """Closed form of the linear two-mass oscillator (instances 'a' and 'b' of the test scenes).

    Attributes are SI: masses [kg], stiffnesses [N/m], dampings [N s/m], initial positions [m]
    and velocities [m/s]. ``names`` maps the quantities x1, v1, x2, v2, force to the scene's
    'instance.variable' names.
    """

    m1: float = 1.0
    m2: float = 1.0
    k1: float = 10.0
    k2: float = 10.0
    k3: float = 20.0
    c1: float = 0.2
    c2: float = 0.5
    c3: float = 0.3
    x1: float = 0.0
    v1: float = 0.0
    x2: float = 0.5
    v2: float = 0.0
    names: tuple[tuple[str, str], ...] = (("x1", "a.x1"), ("v1", "a.v1"), ("x2", "b.x2"), ("v2", "b.v2"),
                                          ("force", "b.force"))

    @property
    def variables(self) -> tuple[str, ...]:
        return tuple(n for _, n in self.names)

    def matrix(self) -> np.ndarray:
        """A of z' = A z with z = (x1, v1, x2, v2)."""
        m1, m2, k1, k2, k3, c1, c2, c3 = self.m1, self.m2, self.k1, self.k2, self.k3, self.c1, self.c2, self.c3
        return np.array([
            [0.0, 1.0, 0.0, 0.0],
            [-(k1 + k2) / m1, -(c1 + c2) / m1, k2 / m1, c2 / m1],
            [0.0, 0.0, 0.0, 1.0],
            [k2 / m2, c2 / m2, -(k2 + k3) / m2, -(c2 + c3) / m2],
        ])

    def states(self, times) -> np.ndarray:
        """z(t) for each t (shape (len(times), 4)), exact: V exp(Lambda t) V^-1 z0."""
        lam, vec = np.linalg.eig(self.matrix())
        coef = np.linalg.solve(vec, np.array([self.x1, self.v1, self.x2, self.v2], dtype=complex))
        t = np.atleast_1d(np.asarray(times, dtype=float))
        z = (vec[None, :, :] * (coef[None, :] * np.exp(np.outer(t, lam)))[:, None, :]).sum(axis=2)
        return z.real

    def solve(self, times) -> dict[str, np.ndarray]:
        z = self.states(times)
        q = {"x1": z[:, 0], "v1": z[:, 1], "x2": z[:, 2], "v2": z[:, 3],
             "force": self.k2 * (z[:, 2] - z[:, 0]) + self.c2 * (z[:, 3] - z[:, 1])}
        return {name: q[key] for key, name in self.names}


class PureModel(Protocol):
    """What :class:`CoupledModels` needs of a model (the components' model convention)."""

    def step(self, dt: float, inputs: dict[str, float]) -> dict[str, float]: ...

    def get_state(self): ...

    def set_state(self, state) -> None: ...


class CoupledModels:
    """Monolithic run of pure models: tiny step, coupling solved at every step.

    Parameters
    ----------
    models : dict of str -> PureModel
        Instance name -> model.
    connections : list of (str, str)
        ('instance.output', 'instance.input') pairs.
    initial_outputs : dict of str -> float
        Coupling values at the start ('instance.output' -> value).
    dt : float
        The tiny step [s].
    tol : float
        Convergence of the coupling values per step: |change| <= tol (1 + m), with m the largest magnitude of
        the value so far in the run (this step's included). Scaling by the value itself would ask a force
        passing through zero for more digits than it has: the strip's pull force is a difference of two
        displacements of the size of the draw times the element stiffness, resolved to ~1e-8 N whatever its
        value (measured: at 0.99 p_crit with friction gone, a 0.6 N pull force cycled between two values
        3.6e-8 N apart with the grip position one ulp apart, and the fixed point never met 1e-10 x 1.6 N).
    """

    def __init__(self, models: dict[str, PureModel], connections: list[tuple[str, str]],
                 initial_outputs: dict[str, float], dt: float, tol: float = 1e-12, max_iterations: int = 100) -> None:
        self.models = models
        self.connections = connections
        self.initial = dict(initial_outputs)
        self.dt = dt
        self.tol = tol
        self.max_iterations = max_iterations

    @property
    def variables(self) -> tuple[str, ...]:
        return tuple(self.initial)

    def solve(self, times) -> dict[str, np.ndarray]:
        times = np.atleast_1d(np.asarray(times, dtype=float))
        values = dict(self.initial)
        self._magnitude = {n: abs(v) for n, v in values.items()}
        out = {n: np.empty(len(times)) for n in values}
        n_now = 0
        for i, t_target in enumerate(times):
            n_target = int(round((t_target - times[0]) / self.dt))
            while n_now < n_target:
                values = self._step(values)
                for n, v in values.items():
                    self._magnitude[n] = max(self._magnitude[n], abs(v))
                n_now += 1
            for n in out:
                out[n][i] = values[n]
        return out

    def _step(self, values: dict[str, float]) -> dict[str, float]:
        saved = {n: m.get_state() for n, m in self.models.items()}
        guess = dict(values)
        for _ in range(self.max_iterations):
            inputs: dict[str, dict[str, float]] = {n: {} for n in self.models}
            for src, dst in self.connections:
                inst, var = dst.split(".", 1)
                inputs[inst][var] = guess[src]
            new = {}
            for n, model in self.models.items():
                model.set_state(saved[n])
                for var, v in model.step(self.dt, inputs[n]).items():
                    new[f"{n}.{var}"] = v
            new = {k: new.get(k, guess[k]) for k in guess}
            if all(abs(new[k] - guess[k]) <= self.tol * (1.0 + max(abs(guess[k]), self._magnitude[k])) for k in guess):
                return new
            guess = new
        raise ConvergenceError(f"monolithic reference: the coupling did not converge in {self.max_iterations} iterations")


class MassPart:
    """Pure model of mass 1 (k1, c1 to ground) driven by a force (exact step for a constant force)."""

    def __init__(self, m: float, k: float, c: float, x: float, v: float) -> None:
        self.a = np.array([[0.0, 1.0, 0.0], [-k / m, -c / m, 1.0 / m], [0.0, 0.0, 0.0]])
        self.z = np.array([x, v])
        self._cache: dict[float, np.ndarray] = {}

    def step(self, dt: float, inputs: dict[str, float]) -> dict[str, float]:
        e = _propagator(self._cache, self.a, dt)
        self.z = (e @ np.array([self.z[0], self.z[1], inputs["force"]]))[:2]
        return {"x1": float(self.z[0]), "v1": float(self.z[1])}

    def get_state(self):
        return self.z.copy()

    def set_state(self, state) -> None:
        self.z = np.array(state)


class MassCouplingPart:
    """Pure model of mass 2 (k3, c3 to ground) plus the coupling (k2, c2); outputs the force on mass 1."""

    def __init__(self, m: float, k3: float, c3: float, k2: float, c2: float, x: float, v: float) -> None:
        self.k2, self.c2 = k2, c2
        self.a = np.array([[0.0, 1.0, 0.0, 0.0], [-(k3 + k2) / m, -(c3 + c2) / m, k2 / m, c2 / m],
                           [0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0]])
        self.z = np.array([x, v])
        self._cache: dict[float, np.ndarray] = {}

    def step(self, dt: float, inputs: dict[str, float]) -> dict[str, float]:
        e = _propagator(self._cache, self.a, dt)
        x1, v1 = inputs["x1"], inputs["v1"]
        self.z = (e @ np.array([self.z[0], self.z[1], x1, v1]))[:2]
        force = self.k2 * (self.z[0] - x1) + self.c2 * (self.z[1] - v1)
        return {"x2": float(self.z[0]), "v2": float(self.z[1]), "force": float(force)}

    def get_state(self):
        return self.z.copy()

    def set_state(self, state) -> None:
        self.z = np.array(state)


def _propagator(cache: dict, a: np.ndarray, dt: float) -> np.ndarray:
    """expm(a dt), cached per dt."""
    e = cache.get(dt)
    if e is None:
        from scipy.linalg import expm

        e = cache[dt] = expm(a * dt)
    return e


# ------------------------------------------------------------------ scenes of components
class ComponentModel:
    """A pure model seen through its FMU's names: fixed (unconnected) inputs merged in, outputs renamed."""

    def __init__(self, model, fixed_inputs: dict[str, float], outputs: dict[str, str]):
        self.model = model
        self.fixed = dict(fixed_inputs)
        self.names = dict(outputs)

    def step(self, dt: float, inputs: dict[str, float]) -> dict[str, float]:
        out = self.model.step(dt, {**self.fixed, **inputs})
        return {fmu: float(out[key]) for fmu, key in self.names.items()}

    def outputs(self) -> dict[str, float]:
        out = self.model.outputs()
        return {fmu: float(out[key]) for fmu, key in self.names.items()}

    def get_state(self):
        return self.model.get_state()

    def set_state(self, state) -> None:
        self.model.set_state(state)


def make_model(component: str, parameters: dict[str, Any]):
    """The pure model of ``component`` for scene parameters (the FMU's files included), as its FMU makes it."""
    from tribocosim.components import registry

    return registry.get(component).make(parameters).model


def reference_for_scene(scene, dt: float, *, tol: float = 1e-10, max_iterations: int = 100):
    """The monolithic reference of a scene whose FMUs are all components.

    Parameters
    ----------
    scene : str, Path, cosim.scene.validate.Plan or cosim.scene.schema.Scene
        The scene (a file is loaded and validated, FMUs built on demand).
    dt : float
        The tiny step of the reference [s].
    tol, max_iterations : float, int
        Convergence of the coupling values per step (:class:`CoupledModels`).

    Returns
    -------
    CoupledModels
        ``solve(times)`` gives every output of every instance, named ``instance.output``.

    Raises
    ------
    SceneError
        If an FMU of the scene is not one of this project's components.
    """
    from tribocosim.components import registry
    from tribocosim.cosim.scene.component_checks import component_of

    if isinstance(scene, (str, Path)):
        from tribocosim.cosim.scene.validate import load_scene

        scene = load_scene(scene)
    plan = scene if hasattr(scene, "scene") else None
    sc = plan.scene if plan is not None else scene
    others = [n for n, s in sc.fmus.items() if component_of(s) is None]
    if others:
        raise SceneError(f"scene {sc.path}: no monolithic reference for {', '.join(others)}: only component = "
                         f"\"{'|'.join(registry.components())}\" FMUs map to pure models")
    connected = {(c.target.instance, c.target.variable) for c in sc.connections}
    models, initial = {}, {}
    for name, spec in sc.fmus.items():
        comp = component_of(spec)
        fixed = {}
        for port in comp.inputs:
            if (name, port.name) in connected:
                continue
            fixed[port.model_key] = float(spec.parameters.get(port.name, _fmu_start(plan, name, port)))
        outputs = {p.name: p.model_key for p in comp.outputs}
        model = ComponentModel(comp.make(spec.parameters).model, fixed, outputs)
        models[name] = model
        initial.update({f"{name}.{k}": v for k, v in model.outputs().items()})
    pairs = [(str(c.source), str(c.target)) for c in sc.connections]
    return CoupledModels(models, pairs, initial, dt, tol=tol, max_iterations=max_iterations)


def _fmu_start(plan, instance: str, port) -> float:
    """Start value of an FMU input: from the model description if the plan has it, else the description's."""
    if plan is not None and instance in plan.fmus:
        var = plan.fmus[instance].variables.get(port.name)
        if var is not None and var.start is not None:
            return float(var.start)
    return float(port.start)
