"""The floor under debris (components/stripdraw/friction_floor.py, docs/model.md): the default flake-borne shear ratio
is the documented floor over the default mu0, the law gives r mu0 where flakes carry the whole contact and nothing
below it, and the paper's model (r = 0) is one setting away."""

from __future__ import annotations

import numpy as np
import pytest

from tribocosim.paths import DEFAULT_TABLE
from tribocosim.components.stripdraw import StripDrawParameters, make_friction_law, read_table
from tribocosim.components.stripdraw.friction_floor import (FLAKE_SHEAR_RATIO_DEFAULT, FLAKE_SHEAR_RATIO_RANGE,
                                                           MU_FLOOR, PAPER_MODEL, below_floor, floor_note,
                                                           mu_at_full_coverage)


def test_the_default_ratio_is_the_floor_over_the_default_mu0_and_the_lower_end_of_its_range():
    p = StripDrawParameters()
    assert p.flake_shear_ratio == FLAKE_SHEAR_RATIO_DEFAULT == FLAKE_SHEAR_RATIO_RANGE[0]
    assert mu_at_full_coverage(p.mu0, p.flake_shear_ratio) == pytest.approx(MU_FLOOR, rel=1e-12)
    assert 0.0 < FLAKE_SHEAR_RATIO_RANGE[0] < FLAKE_SHEAR_RATIO_RANGE[1] < 1.0
    assert StripDrawParameters(**PAPER_MODEL).flake_shear_ratio == 0.0


@pytest.mark.parametrize("pressure", [10e6, 25e6, 30e6])
def test_the_table_law_reaches_r_mu0_at_the_cap_and_nothing_below(pressure):
    """s = 2 makes the shipped table's flakes carry the whole contact inside its beta axis: at the cap (found from
    below, s A_p < A_c) mu is r mu0 to the cap's tolerance, and no debris level gives less; the paper's model goes
    to 0 there."""
    table = read_table(DEFAULT_TABLE)
    for r in (FLAKE_SHEAR_RATIO_DEFAULT, 0.0):
        p = StripDrawParameters(particle_area_scale=2.0, flake_shear_ratio=r)
        law = make_friction_law(p, table)
        cap = law.beta_cap(pressure, 0.08)
        assert cap < table.beta[-1]
        beta = np.linspace(0.0, cap, 400)
        mu = law.mu(pressure, 0.08, beta)[0]
        assert mu[-1] == pytest.approx(mu_at_full_coverage(p.mu0, r), abs=1e-9)
        assert mu.min() >= mu_at_full_coverage(p.mu0, r) - 1e-12
    assert mu[-1] < MU_FLOOR  # the paper's model falls through the floor


def test_the_note_names_the_setting_that_lets_mu_fall_below_the_floor():
    assert not below_floor(MU_FLOOR) and below_floor(0.5 * MU_FLOOR)
    assert floor_note(0.05, 0.15, 0.2) is None
    note = floor_note(0.004, 0.15, 0.0)
    assert note.startswith("mu = 0.004 is below the documented floor 0.03"), note
    assert "flake_shear_ratio = 0 with mu0 = 0.15" in note, note
    note = floor_note(0.02, 0.15, 0.2)
    assert "at least 0.03 at full flake coverage" in note and "another setting" in note
