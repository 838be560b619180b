"""Our Fourier-BEM solver against the reference implementation of the method, Tamaas.

Tamaas (Frerot, Anciaux, Rey, Pham-Ba & Molinari, JOSS 2020, doi:10.21105/joss.02121) is the C++
library the paper used. Its PolonskyKeerRey solver, pressure-controlled, elastic, on the same
periodic self-affine surface and mean pressure must give our contact area and traction field.
"""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tribocosim.surrogate.bem import ContactSolver, gap_against_flat
from tribocosim.surrogate.surfaces import self_affine_surface

tm = pytest.importorskip("tamaas")


@pytest.mark.parametrize("pressure", [10e6, 30e6])
def test_elastic_contact_matches_tamaas_polonsky_keer(pressure):
    n, size, e_star = 128, 500e-6, 55e9
    q0 = 2 * np.pi / size
    heights = self_affine_surface(n, size, 0.8, 2 * q0, 32 * q0, rms_slope=0.34, seed=3)
    model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [size, size], [n, n])
    model.E = e_star  # nu = 0: E* = E / (1 - nu^2) = E
    model.nu = 0.0
    solver = tm.PolonskyKeerRey(model, heights.copy(), 1e-12, tm.PolonskyKeerRey.pressure, tm.PolonskyKeerRey.pressure)
    solver.solve(pressure)
    reference = np.array(model.traction).reshape(n, n)
    ours = ContactSolver(n, size, e_star, tol=1e-12).solve(gap_against_flat(heights), pressure)
    assert ours.converged
    assert np.array_equal(ours.traction > 0, reference > 0), "same contact pixels"
    assert_allclose(ours.traction, reference, rtol=0, atol=1e-5 * pressure, err_msg="traction field")
