"""Tests of cosim.reference: the closed form against scipy, the monolithic runner against the closed form."""

import numpy as np
from scipy.integrate import solve_ivp

from tribocosim.cosim.reference import CoupledModels, MassCouplingPart, MassPart, TwoMassOscillator


def test_closed_form_matches_scipy_and_the_issue_values(exact_t10):
    osc = TwoMassOscillator()
    a = osc.matrix()
    sol = solve_ivp(lambda t, z: a @ z, (0.0, 10.0), [0.0, 0.0, 0.5, 0.0], method="DOP853", rtol=1e-13, atol=1e-15)
    z = osc.states([10.0])[0]
    np.testing.assert_allclose(z, sol.y[:, -1], rtol=0, atol=1e-11, err_msg="closed form vs DOP853 at t = 10")
    np.testing.assert_allclose([z[0], z[2]], exact_t10, rtol=0, atol=5e-13,
                               err_msg="x1, x2 at t = 10 against the values given in issue 7")
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
