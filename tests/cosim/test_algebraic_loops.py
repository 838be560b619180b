"""Algebraic loops: two feedthrough FMUs in a ring, loop gain 0.5, 0.99 and 2.

p: y_p = g u_p + 1 + 0.5 sin(2 t),  q: y_q = u_q + 0.5,  u_p = y_q, u_q = y_p
=> y_p = (1 + 0.5 sin(2 t) + 0.5 g) / (1 - g) whenever the loop is solved.

The master measures the loop Jacobian at the start; its spectral radius rho (contraction factor
of a Jacobi sweep) satisfies rho^2 = |g| for this two-link loop. A fixed-point iteration
converges iff rho < 1 and reports divergence otherwise; quasi-Newton solves the linear loop for
any g != 1; a non-iterative scheme breaks the loop with a one-step delay and is warned about when
rho >= 1.
"""

import numpy as np
import pytest

from tribocosim.errors import ConvergenceError, RunFailed
from tribocosim.cosim import run


def loop_scene(make_scene, folder, fmu_dir, gain, algorithm="iterative", method="fixed-point", stop=0.01, step=0.01,
               tolerance=1e-8, max_iterations=6000):
    return make_scene(folder, f"loop_{gain}_{algorithm}_{method}.toml", f"""
        [experiment]
        stop = {stop!r}
        step = {step!r}

        [master]
        algorithm = "{algorithm}"

        [master.iterative]
        method = "{method}"
        relaxation = 1.0
        tolerance = {tolerance!r}
        max_iterations = {max_iterations}
        reuse = 0

        [fmus.p]
        path = "{fmu_dir / 'LoopGain.fmu'}"
        parameters = {{ gain = {gain!r}, offset = 1.0, amplitude = 0.5, omega = 2.0 }}

        [fmus.q]
        path = "{fmu_dir / 'LoopGain.fmu'}"
        parameters = {{ gain = 1.0, offset = 0.5, amplitude = 0.0 }}

        [[connections]]
        from = "p.y"
        to = "q.u"

        [[connections]]
        from = "q.y"
        to = "p.u"

        [output]
        variables = ["p.y", "q.y"]
        """)


def exact_yp(t, g):
    return (1.0 + 0.5 * np.sin(2.0 * t) + 0.5 * g) / (1.0 - g)


@pytest.mark.parametrize("gain", [0.5, 0.99, 2.0])
def test_loop_is_detected_with_its_contraction_factor(tmp_path, make_scene, fmu_dir, gain):
    res = run(loop_scene(make_scene, tmp_path, fmu_dir, gain, algorithm="jacobi", stop=0.02), write=False)
    loops = res.metadata["algebraic_loops"]
    assert len(loops) == 1 and sorted(loops[0]["links"]) == ["p.y -> q.u", "q.y -> p.u"]
    np.testing.assert_allclose(loops[0]["contraction"] ** 2, gain, rtol=1e-6, err_msg="rho^2 = loop gain")
    warned = [w for w in res.metadata["warnings"] if "cannot be stable" in w]
    assert bool(warned) == (gain >= 1.0), f"warning for gain {gain}: {res.metadata['warnings']}"


@pytest.mark.parametrize("gain", [0.5, 0.99])
def test_fixed_point_iteration_converges_where_the_loop_contracts(tmp_path, make_scene, fmu_dir, gain):
    res = run(loop_scene(make_scene, tmp_path, fmu_dir, gain), write=False)
    np.testing.assert_allclose(res["p.y"][-1], exact_yp(res.time[-1], gain), rtol=1e-6,
                               err_msg=f"loop solution for gain {gain}")
    rho = np.sqrt(gain)
    its = res.metadata["steps"]["iterations"]
    # iterations ~ log(tol / initial residual) / log(rho): hundreds for 0.5, thousands for 0.99
    assert (its < 200) if gain == 0.5 else (1000 < its < 6000), f"{its} iterations for rho = {rho:.3f}"
    np.testing.assert_allclose(res.metadata["steps"]["observed_contraction"], rho, rtol=0.05,
                               err_msg="observed residual ratio vs the measured contraction factor")


def test_fixed_point_iteration_reports_divergence_without_contraction(tmp_path, make_scene, fmu_dir):
    with pytest.raises(RunFailed) as info:  # the run stops and keeps its work
        run(loop_scene(make_scene, tmp_path, fmu_dir, 2.0), write=False)
    assert isinstance(info.value.__cause__, ConvergenceError)
    msg = str(info.value)
    assert "diverges" in msg and "contraction factor" in msg and "quasi-newton" in msg, msg
    rate = float(msg.split("observed contraction factor ")[1].split()[0])
    np.testing.assert_allclose(rate, np.sqrt(2.0), rtol=0.05, err_msg="reported growth rate per iteration")


def test_quasi_newton_solves_the_loop_even_without_contraction(tmp_path, make_scene, fmu_dir):
    res = run(loop_scene(make_scene, tmp_path, fmu_dir, 2.0, method="quasi-newton", stop=0.05, tolerance=1e-12), write=False)
    np.testing.assert_allclose(res["p.y"][1:], exact_yp(res.time[1:], 2.0), rtol=1e-9, err_msg="loop gain 2 solved")
    assert res.metadata["steps"]["iterations"] <= 4 * 5, "at most m + 2 = 4 passes per step for m = 2 links"


def test_non_iterative_delay_converges_only_with_contraction(tmp_path, make_scene, fmu_dir):
    ok = run(loop_scene(make_scene, tmp_path, fmu_dir, 0.5, algorithm="jacobi", stop=1.0, step=0.01), write=False)
    # y_n+1 = D y_n + s(t_n+1): the delayed loop tracks the solution with an O(h) lag once the start-up has decayed
    late = ok.time > 0.5
    np.testing.assert_allclose(ok["p.y"][late], exact_yp(ok.time[late], 0.5), rtol=0.05,
                               err_msg="delayed loop with rho < 1 follows the loop solution")
    bad = run(loop_scene(make_scene, tmp_path, fmu_dir, 2.0, algorithm="jacobi", stop=1.0, step=0.01), write=False)
    assert abs(bad["p.y"][-1]) > 1e10, "with rho = sqrt(2) the delayed loop grows without bound"
