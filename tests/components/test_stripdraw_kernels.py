"""Every compiled kernel against its NumPy reference (numba-stats style oracle tests)."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tribocosim.components.stripdraw import StripDrawModel, StripDrawParameters, kernels, make_friction_law

pytest.importorskip("numba")


def test_thomas_matches_a_dense_solve():
    rng = np.random.default_rng(1)
    n = 57
    sub, sup = -rng.uniform(0.1, 1, n), -rng.uniform(0.1, 1, n)
    diag = 3 + rng.uniform(0, 1, n)
    rhs = rng.normal(size=n)
    dense = np.diag(diag) + np.diag(sub[1:], -1) + np.diag(sup[:-1], 1)
    assert_allclose(kernels.thomas(sub, diag, sup, rhs), np.linalg.solve(dense, rhs), rtol=1e-12)
    assert_allclose(kernels.thomas_numpy(sub, diag, sup, rhs), np.linalg.solve(dense, rhs), rtol=1e-12)


def _sliding_state(integrator):
    """A model mid-draw, with sticking and slipping nodes and nodes about to enter the pad."""
    p = StripDrawParameters(friction_model="closed_form", integrator=integrator, draw_length=0.01, n_elements=90)
    model = StripDrawModel(p, make_friction_law(p))
    fn = 1e7 * 0.035**2
    for k in range(6):
        model.step(1e-3, {"normal_force": fn, "grip_velocity": 0.08 * (k + 0.5) / 6})
    mu, _ = model.law.mu(1e7, model.slip_rate, model.beta)
    return model, mu * 1e7


def test_explicit_kernel_matches_numpy_reference():
    model, tmax = _sliding_state("explicit")
    m, p = model.mesh, model.params
    runs = []
    for kernel in (kernels.explicit_loop, kernels.explicit_numpy):
        st = model.get_state()
        args = (st["U"], st["V"], st["A"], st["Up"], st["contact"], m.X, 1.0 / m.mass, m.element_stiffness,
                p.shear_stiffness, p.tool_width, 0.5 * m.element_length, m.window_lo, m.window_hi, tmax, 0.09)
        fric, reaction = kernel(300, model.explicit_time_step, *args)
        runs.append((fric, reaction, st))
    (f1, r1, s1), (f2, r2, s2) = runs
    assert_allclose([f1, r1], [f2, r2], rtol=1e-9)
    for k in ("U", "V", "A", "Up"):
        assert_allclose(s1[k], s2[k], rtol=1e-9, atol=1e-18, err_msg=k)
    assert np.array_equal(s1["contact"], s2["contact"])
