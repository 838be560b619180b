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
    assert "at least 0.03 where flakes carry the whole contact" in note and "debris beyond the law's cap" in note


def test_below_floor_takes_the_projects_relative_tolerance():
    """A value within BOUND_RTOL (1e-9) of the floor is on it, as tc_below of the native checks: 0.03 (1 - 1e-12) is
    round-off of r mu0 = 0.2 x 0.15 at the cap, not below; 0.0299 is below by 3e-3 of it."""
    assert not below_floor(MU_FLOOR * (1.0 - 1e-12)) and not below_floor(MU_FLOOR)
    assert below_floor(0.0299) and below_floor(MU_FLOOR * (1.0 - 2e-9))
    assert floor_note(MU_FLOOR * (1.0 - 1e-12), 0.15, 0.2) is None


def _native_note(mu: float, **settings) -> str | None:
    """The native model's note (tc_law_floor_note of tc_friction.c) for mu under the parameters ``settings``."""
    import ctypes

    from tribocosim.components.native.toolchain.library import Msg, core

    c = core()
    buf = ctypes.create_string_buffer(2048)
    struct = c.struct(StripDrawParameters(**settings))
    below = c.lib.tc_law_floor_note(ctypes.byref(struct), float(mu), Msg(ctypes.addressof(buf), len(buf)))
    return buf.value.decode() if below else None


@pytest.mark.parametrize("mu, settings", [
    (0.0, {"flake_shear_ratio": 0.0}),
    (0.0123, {"flake_shear_ratio": 0.1, "mu0": 0.2}),
    (0.02, {}),
    (0.01, {"mu0": 0.02, "flake_shear_ratio": 1.0}),
    (0.01, {"friction_model": "constant", "mu_const": 0.01}),
    (MU_FLOOR * (1.0 - 1e-12), {}),
    (0.0299, {"friction_model": "closed_form"}),
])
def test_the_native_note_is_the_python_note(mu, settings):
    """The FMU and the Python model report the floor with the native note, the export with floor_note: one text, the
    floor generated into C from MU_FLOOR (TC_STRIPDRAW_MU_FLOOR) and the same tolerance."""
    p = StripDrawParameters(**settings)
    expected = floor_note(mu, p.mu0, p.flake_shear_ratio,
                          mu_const=p.mu_const if p.friction_model == "constant" else None)
    assert _native_note(mu, **settings) == expected
    if settings.get("friction_model") == "constant":
        assert "friction_model = constant with mu_const = 0.01" in expected
    if settings.get("mu0") == 0.02:
        assert "mu0 = 0.02 is below it" in expected


def _closed_form_draw(steps: int, **settings):
    """The strip-draw model with the closed-form law (its cap of beta, kappa / (s b h'_rms) = 0.0283, is reached in
    the first pass) drawn ``steps`` ms at the default force and speed; per step the least mu of the state
    (mu_least), the least mu of the closed form over the nodes under the pad from their beta; the warnings; the
    model's times."""
    import warnings

    from tribocosim.components.stripdraw.model import StripDrawModel

    p = StripDrawParameters(friction_model="closed_form", **settings)
    model = StripDrawModel(p, make_friction_law(p, None))
    least, from_beta, times = [], [], []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for _ in range(steps):
            model.step(1e-3, {"normal_force": 12250.0, "grip_velocity": 0.08})
            least.append(model.mu_least)
            times.append(model.time)
            under = model.fields()["contact"] > 0
            # Eq. 9 with r: mu = mu0 (1 - (1 - r) s alpha beta h'_rms / kappa), alpha = b (v_ref = 0)
            mu = p.mu0 * (1 - (1 - p.flake_shear_ratio) * p.particle_area_scale * p.alpha_b * model.beta[under]
                          * p.rms_slope / p.kappa)
            from_beta.append(mu.min())
    return model, np.array(least), np.array(from_beta), caught, times


def test_the_default_ratio_at_the_cap_gives_the_floor_and_no_warning():
    """The default r = 0.2 at the cap gives mu = r mu0 = 0.03, the floor itself (to round-off): a draw whose debris
    reaches the cap under the pad warns nothing."""
    from tribocosim.errors import RangeWarning

    model, least, from_beta, caught, _ = _closed_form_draw(400)
    assert model.outputs()["beta_max"] == pytest.approx(model.beta_cap, rel=1e-12)
    np.testing.assert_allclose(least, from_beta, rtol=1e-12)
    assert least.min() == pytest.approx(MU_FLOOR, rel=1e-12)
    assert not [w for w in caught if issubclass(w.category, RangeWarning)], [str(w.message) for w in caught]


def test_the_papers_model_warns_once_naming_flake_shear_ratio_at_the_first_step_below_the_floor():
    """r = 0 (the paper's model): mu = mu0 (1 - alpha beta h'_rms / kappa) < 0.03 where beta > 0.8 kappa / (b h'_rms)
    = 0.0226 under the pad; the model warns once (RangeWarning), at the end of the first step where a node under the
    pad holds that much, naming flake_shear_ratio = 0 with mu0, and not again while mu stays below."""
    from tribocosim.errors import RangeWarning

    model, least, from_beta, caught, times = _closed_form_draw(300, flake_shear_ratio=0.0)
    np.testing.assert_allclose(least, from_beta, rtol=1e-9, atol=1e-15)
    below = np.flatnonzero(from_beta < MU_FLOOR * (1 - 1e-9))
    assert below.size > 10 and below[-1] == 299, "mu stays below the floor to the end"
    first = below[0]
    warned = [w for w in caught if issubclass(w.category, RangeWarning)]
    assert len(warned) == 1, [str(w.message) for w in warned]
    text = str(warned[0].message)
    assert text.startswith(f"StripDrawModel: at t = {times[first]!r} s mu = {from_beta[first]:.4g} is below"), text
    assert "flake_shear_ratio = 0 with mu0 = 0.15 lets mu fall to 0 where flakes carry the whole contact" in text
    assert "flake_shear_ratio >= 0.2 keeps mu at or above it" in text
