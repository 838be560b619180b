"""Friction laws: calibration, the cap of Eq. 24, and the table built from the closed form."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tribocosim.components.errors import ParameterError
from tribocosim.components.stripdraw.friction import closed_form_law, closed_form_table, make_friction_law
from tribocosim.components.stripdraw.parameters import StripDrawParameters


def test_closed_form_limits():
    p = StripDrawParameters(friction_model="closed_form", mu0=0.15, kappa=2.0, rms_slope=0.34, alpha_b=20, alpha_v_ref=0.05)
    law = make_friction_law(p)
    # no debris: the particle-free coefficient mu0 (Eq. 6); no sliding: alpha = 0 -> mu0
    assert_allclose(law.mu(1e7, 0.08, 0.0)[0], 0.15)
    assert_allclose(law.mu(1e7, 0.0, 0.2)[0], 0.15)
    # Eq. 24 with the saturated alpha = b: beta_thres = kappa / (b h'), and mu -> 0 there at v >> v_ref
    assert_allclose(law.beta_threshold, 2.0 / (20 * 0.34))
    assert_allclose(law.mu(1e7, 1e3, law.beta_threshold)[0], 0.0, atol=1e-15)
    # Eq. 9: linear in beta with slope -mu0 alpha(v) h'/kappa
    v = 0.08
    alpha = 20 * (1 - np.exp(-v / 0.05))
    mu = law.mu(1e7, v, np.array([0.0, 0.1]))[0]
    assert_allclose(mu[1] - mu[0], -0.15 * alpha * 0.34 / 2.0 * 0.1, rtol=1e-12)


def test_table_law_matches_closed_form_on_its_nodes():
    p = StripDrawParameters(friction_model="table")
    table = closed_form_table(p)
    law = make_friction_law(p, table)
    ref = closed_form_law(p)
    PP, VV, BB = np.meshgrid(table.pressure, table.velocity, table.beta, indexing="ij")
    assert_allclose(law.mu(PP, VV, BB)[0], ref.mu(PP, VV, BB)[0], atol=1e-15)


def test_table_law_needs_a_table():
    with pytest.raises(ParameterError, match="table"):
        make_friction_law(StripDrawParameters(friction_model="table"))
