"""Tests of cosim.engine.algorithms.

- with the real test FMUs: the two-mass oscillator split into two FMUs (force-displacement
  coupling); the error at t = 10 against the exact solution falls at order q + 1 for
  extrapolation order q = 0, 1, 2 (slope of log error over log step, within 0.15), for Jacobi,
  Gauss-Seidel and the iterative scheme;
- with mock slaves (pure unit tests of the master logic): which input values Jacobi and
  Gauss-Seidel hand over, the exactness of polynomial inputs, and IQN-ILS on a linear loop.
"""

import numpy as np
import pytest

from tribocosim.cosim import run
from tribocosim.cosim.engine.algorithms import GaussSeidel, IterativeCoupling, Jacobi
from tribocosim.cosim.engine.master import Master
from tribocosim.cosim.engine.recorder import Recorder
from tribocosim.cosim.engine.schemes import Iterative, LinkSpec, VariableRef
from tribocosim.cosim.engine.slave import OK
from tribocosim.cosim.engine.stepcontrol import FixedStep
from tribocosim.cosim.engine.system import CoupledSystem
from tribocosim.cosim.engine.timegrid import TimeGrid

SWEEPS = {0: [0.01, 0.005, 0.0025], 1: [0.02, 0.01, 0.005], 2: [0.04, 0.02, 0.01]}


@pytest.mark.parametrize("algorithm", ["jacobi", "gauss-seidel", "iterative"])
@pytest.mark.parametrize("order", [0, 1, 2])
def test_convergence_order_on_the_two_mass_oscillator(tmp_path, osc_scene, exact_t10, algorithm, order):
    errors = []
    for h in SWEEPS[order]:
        scene = osc_scene(tmp_path, step=h, algorithm=algorithm, extrapolation=order,
                          extra_master="[master.iterative]\ntolerance = 1e-11")
        res = run(scene, write=False)
        assert res.time[-1] == 10.0
        errors.append(max(abs(res["a.x1"][-1] - exact_t10[0]), abs(res["b.x2"][-1] - exact_t10[1])))
    slope = np.polyfit(np.log(SWEEPS[order]), np.log(errors), 1)[0]
    np.testing.assert_allclose(slope, order + 1, atol=0.15,
                               err_msg=f"{algorithm}, extrapolation {order}: errors {errors} at steps {SWEEPS[order]}")
    assert res.metadata["master"]["order_of_accuracy"] == order + 1


# --- mock slaves ---------------------------------------------------------------------------
class MockIntegrator:
    """x' = u(t) integrated exactly for a polynomial input u = u0 + u1 tau + u2 tau^2 / 2.

    Value references: 0 input u, 1 output x, 2 output 'ramp' = t (the slave's own time).
    """

    can_roll_back = True
    can_interpolate_inputs = True

    def __init__(self, name, discard_longer_than=None):
        self.name = name
        self.wall_time = 0.0
        self.messages = []
        self.calls = {"doStep": 0}
        self.u = [0.0, 0.0, 0.0]
        self.x = 0.0
        self.t = 0.0
        self.limit = discard_longer_than
        self.steps = []

    def instantiate(self):
        pass

    def setup(self, start, stop, tolerance=None):
        self.t = start

    def exit_initialization(self):
        pass

    def set_real(self, refs, values):
        for r, v in zip(refs, values):
            assert r == 0, "only the input can be set"
            self.u[0] = float(v)

    def get_real(self, refs):
        return np.array([{1: self.x, 2: self.t}[r] for r in refs])

    def set_input_derivatives(self, refs, order, values):
        for r, v in zip(refs, values):
            self.u[order] = float(v)

    def do_step(self, t, h):
        if self.limit is not None and h > self.limit:
            return 2
        self.steps.append((t, h))
        u0, u1, u2 = self.u
        self.x += u0 * h + u1 * h * h / 2 + u2 * h**3 / 6
        self.t = t + h
        return OK

    def get_state(self):
        return (self.x, self.t, list(self.u))

    def set_state(self, s):
        self.x, self.t, self.u = s[0], s[1], list(s[2])

    def free_state(self, s):
        pass

    def terminate(self):
        pass


def _chain_master(algorithm, h=0.1, stop=1.0, limit=None):
    """Slave 'a' integrates u = 1 (unconnected, set to 1), slave 'b' integrates a's output."""
    a, b = MockIntegrator("a"), MockIntegrator("b", limit)
    a.u = [1.0, 0.0, 0.0]
    links = [LinkSpec(0, 1, "Real", 1, 0, "Real", True, "a.x -> b.u")]
    system = CoupledSystem([a, b], links, algorithm.order, [False, False])
    grid = TimeGrid.fixed(0.0, stop, h)
    rec = Recorder([a, b], {"a": 0, "b": 1}, [(VariableRef("a", "x"), 1, "Real"), (VariableRef("b", "x"), 1, "Real")])
    master = Master(system, algorithm, FixedStep(grid.macro_ticks), grid, rec, ["a", "b"])
    master.initialize(0.0, stop, [{}, {}])
    return master, a, b


def test_jacobi_hands_over_start_values_and_gauss_seidel_end_values():
    h, n = 0.1, 10
    mj, _, bj = _chain_master(Jacobi(0), h)
    mj.run()
    mg, _, bg = _chain_master(GaussSeidel(0, sequence=(0, 1)), h)
    mg.run()
    # x_a = t; Jacobi holds x_a(t_k) over step k, Gauss-Seidel x_a(t_k+1)
    np.testing.assert_allclose(bj.x, h * h * n * (n - 1) / 2, rtol=1e-12, err_msg="Jacobi: sum of h * x_a(t_k)")
    np.testing.assert_allclose(bg.x, h * h * n * (n + 1) / 2, rtol=1e-12, err_msg="Gauss-Seidel: sum of h * x_a(t_k+1)")


def test_linear_extrapolation_is_exact_for_a_ramp_after_the_first_step():
    h = 0.1
    m, _, b = _chain_master(Jacobi(1), h)
    m.run()
    # first step: one history point -> constant hold of x_a(0) = 0; afterwards the ramp is exact
    np.testing.assert_allclose(b.x, 0.5 * 1.0**2 - 0.5 * h * h, rtol=1e-12, err_msg="t^2/2 minus the startup step")


def test_fixed_step_halves_a_discarded_step_and_stays_on_the_grid():
    h = 0.1
    m, a, b = _chain_master(Jacobi(0), h, stop=0.3, limit=0.03)
    m.run()
    hs = {round(s[1], 12) for s in b.steps}
    assert hs == {0.025}, f"step halved twice (0.1 -> 0.05 -> 0.025), got {hs}"
    assert m.stats.rejected_failures == 3 * 2, "two failed attempts per macro step"
    np.testing.assert_allclose(m.recorder.time[-1], 0.3, rtol=0, atol=1e-15, err_msg="ends on the grid")
    np.testing.assert_allclose(a.x, 0.3, rtol=1e-12, err_msg="the undisturbed slave integrates t exactly")


class LinearLoop(MockIntegrator):
    """Static map y = g u + s (value reference 1 = y), for algebraic loops."""

    def __init__(self, name, g, s):
        super().__init__(name)
        self.g, self.s = g, s

    def get_real(self, refs):
        return np.array([self.g * self.u[0] + self.s for _ in refs])


@pytest.mark.parametrize("gain", [0.5, 2.0, -3.0])
def test_quasi_newton_solves_a_linear_loop_in_few_iterations(gain):
    p, q = LinearLoop("p", gain, 1.0), LinearLoop("q", 1.0, 0.5)
    links = [LinkSpec(0, 1, "Real", 1, 0, "Real", True, "p.y -> q.u"), LinkSpec(1, 1, "Real", 0, 0, "Real", True, "q.y -> p.u")]
    system = CoupledSystem([p, q], links, 0, [True, True])
    alg = IterativeCoupling(0, settings=Iterative(method="quasi-newton", tolerance=1e-12, reuse=0))
    grid = TimeGrid.fixed(0.0, 0.3, 0.1)
    m = Master(system, alg, FixedStep(grid.macro_ticks), grid, Recorder([p, q], {"p": 0, "q": 1}, []), ["p", "q"])
    m.initialize(0.0, 0.3, [{}, {}])
    m.run()
    y_p = (gain * 0.5 + 1.0) / (1.0 - gain)
    np.testing.assert_allclose(system.y[0], y_p, rtol=1e-10, err_msg=f"loop solution for gain {gain}")
    assert m.stats.iterations <= 3 * 4, f"IQN-ILS needs at most m + 2 = 4 passes per step, used {m.stats.iterations}"


def test_fmus_without_input_derivatives_hold_the_step_mean():
    """Linear extrapolation of a ramp, held at its step mean, integrates the ramp exactly."""
    h = 0.1
    m, _, b = _chain_master(Jacobi(1), h)
    b.can_interpolate_inputs = False  # and no der() companion inputs: the master holds the mean
    m.run()
    assert m.system.hold_mean == {"a.x -> b.u"}
    np.testing.assert_allclose(b.x, 0.5 - 0.5 * h * h, rtol=1e-12, err_msg="mean of the extrapolated ramp per step")
