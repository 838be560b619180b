"""Tests of cosim.studies.monolithic: the closed form against scipy, the monolithic runner against the closed form."""

import numpy as np
from scipy.integrate import solve_ivp

from tribocosim.cosim.studies.monolithic import CoupledModels, MassCouplingPart, MassPart, TwoMassOscillator


def test_closed_form_matches_scipy_and_the_issue_values(exact_t10):
    osc = TwoMassOscillator()
    a = osc.matrix()
    sol = solve_ivp(lambda t, z: a @ z, (0.0, 10.0), [0.0, 0.0, 0.5, 0.0], method="DOP853", rtol=1e-13, atol=1e-15)
    z = osc.states([10.0])[0]
    np.testing.assert_allclose(z, sol.y[:, -1], rtol=0, atol=1e-11, err_msg="closed form vs DOP853 at t = 10")
    np.testing.assert_allclose([z[0], z[2]], exact_t10, rtol=0, atol=5e-13,
                               err_msg="x1, x2 at t = 10 against the stored exact values")
    # the coupling force is what FMU b outputs
    f = osc.solve([0.0])["b.force"][0]
    np.testing.assert_allclose(f, 10.0 * 0.5, rtol=1e-15, err_msg="F(0) = k2 (x2 - x1)")


def test_monolithic_runner_converges_to_closed_form_at_first_order():
    osc = TwoMassOscillator()
    times = np.linspace(0.0, 2.0, 5)
    exact = osc.solve(times)
    errs = []
    for dt in (2e-3, 1e-3):
        ref = CoupledModels(
            {"a": MassPart(1.0, 10.0, 0.2, 0.0, 0.0), "b": MassCouplingPart(1.0, 20.0, 0.3, 10.0, 0.5, 0.5, 0.0)},
            [("b.force", "a.force"), ("a.x1", "b.x1"), ("a.v1", "b.v1")],
            {"a.x1": 0.0, "a.v1": 0.0, "b.x2": 0.5, "b.v2": 0.0, "b.force": 5.0},
            dt,
        )
        got = ref.solve(times)
        errs.append(max(np.max(np.abs(got[n] - exact[n])) for n in ("a.x1", "b.x2")))
    assert errs[1] < 2e-3, f"monolithic error {errs[1]:.3g} at dt = 1e-3"
    np.testing.assert_allclose(np.log2(errs[0] / errs[1]), 1.0, atol=0.1,
                               err_msg="implicit end-value coupling per tiny step is first order in dt")


class _Quantized:
    """y = s(t) - q sign(x - s(t)) with s = 1000 in the first step and 0.6 after: a decreasing jump of height
    2 q at the fixed point (the rounding of a force computed from draw-sized displacements, as the strip's), so
    the fixed point iteration alternates between two values 2 q apart."""

    def __init__(self, q: float, first: float) -> None:
        self.q, self.first, self.k = q, first, 0

    def s(self) -> float:
        return self.first if self.k == 0 else 0.6

    def step(self, dt, inputs):
        s = self.s()
        self.k += 1
        return {"y": s - self.q * (1.0 if inputs["x"] > s else -1.0)}

    def get_state(self):
        return self.k

    def set_state(self, state):
        self.k = state


class _Follower:
    """x = y: closes the loop (with a, the fixed point iteration of x = y(x))."""

    def step(self, dt, inputs):
        return {"x": inputs["y"]}

    def get_state(self):
        return None

    def set_state(self, state):
        pass


def test_coupling_tolerance_is_relative_to_the_values_magnitude_over_the_run():
    """A coupling value that passes near zero is converged to tol x its magnitude so far in the run, not to tol x
    itself: a 2e-8 alternation of a value of 0.6 that was 1000 one step before is within 1e-10 x 1000; the same
    alternation of a value that was never larger than 1 is not, and the run says so."""
    import pytest

    from tribocosim.errors import ConvergenceError

    def run(first):
        ref = CoupledModels({"a": _Quantized(1e-8, first), "b": _Follower()}, [("a.y", "b.y"), ("b.x", "a.x")],
                            {"a.y": first, "b.x": first}, 1e-3, tol=1e-10, max_iterations=50)
        return ref.solve(np.array([0.0, 1e-3, 2e-3, 3e-3]))

    got = run(1000.0)
    assert abs(got["a.y"][-1] - 0.6) <= 1.5e-8  # one side of the alternation, 0.6 +- q
    with pytest.raises(ConvergenceError, match="did not converge in 50 iterations"):
        run(1.0)
