"""The debris state of an export: given, the one the strip-draw test reaches after N passes (the multi-pass runs of
the calibration and the paper report, with the export's parameters and units), or the one a sheet point makes
sliding S under each pressure (the per-point update of the native core)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tribocosim.errors import ParameterError
from tribocosim.components.friction_export.export_units import UNIT_SYSTEMS
from tribocosim.components.friction_export.exported_law import load_law
from tribocosim.cosim.apps.debris_state import DebrisChoice, debris_states
from tribocosim.cosim.studies.stripdraw_experiment import Point, draw

MM, SI = UNIT_SYSTEMS["mm-t-s"], UNIT_SYSTEMS["SI"]


@pytest.fixture(scope="module")
def law():
    return load_law()


def test_the_state_after_n_passes_is_the_debris_the_strip_draw_test_leaves(law):
    states = debris_states(DebrisChoice(passes=(1, 2), pressure=25, velocity=80, pad_length=35), law, MM)
    parameters = {"table_file": str(law.table_path)}
    reference = draw(Point(25e6, 0.035, 2, parameters, 0.08))
    assert [s.beta for s in states] == [r["beta_left"] for r in reference]
    assert [s.label for s in states] == ["pass1", "pass2"]
    assert 0 < states[0].beta < states[1].beta, "debris builds up over passes (all of it carried over)"
    record = states[1].record
    assert record["after_pass"] == 2 and record["test"]["pressure"] == 25e6 and record["test"]["velocity"] == 0.08
    assert record["test"]["passes"][1]["mu_bar"] == reference[1]["mu_bar"]
    assert "after 2 pass(es) of the strip-draw test at 25 MPa, 80 mm/s, 35 mm pad" in states[1].description
    si = debris_states(DebrisChoice(passes=(1,), pressure=25e6), law, SI)
    assert si[0].beta == states[0].beta, "the same test in SI units (the paper's 0.08 m/s and 35 mm by default)"


def test_the_multi_pass_options_are_the_exports_parameters():
    """With none of the debris carried into the next pass (debris_carry_over = 0), every pass starts clean."""
    law = load_law(settings={"debris_carry_over": "0"})
    first, second = debris_states(DebrisChoice(passes=(1, 2), pressure=10), law, MM)
    assert second.beta == pytest.approx(first.beta, rel=1e-12)


def test_given_betas_and_the_beta_axis(law):
    states = debris_states(DebrisChoice(beta=(0.05, "0.1")), law, MM)
    assert [(s.beta, s.label, s.record["how"]) for s in states] == [(0.05, "beta0.05", "given"),
                                                                     (0.1, "beta0.1", "given")]
    (axis,) = debris_states(DebrisChoice(), law, MM)
    assert axis.beta is None


def test_a_slide_state_is_the_debris_a_sheet_point_makes_under_each_pressure(law):
    """--slide 20 (mm): beta(P, S) = K P S / (H h_p) below the cap at every pressure and velocity, from the blank's
    beta_initial; the same state given in SI; one state per slide."""
    states = debris_states(DebrisChoice(slide=(20, "5")), law, MM)
    assert [s.label for s in states] == ["slide20", "slide5"]
    assert [s.slide for s in states] == [0.02, 0.005] and all(s.is_axis is False for s in states)
    prm = law.params
    p = law.table.pressure[:, None]
    for v in law.table.velocity:
        expected = prm.archard_k * p * 0.02 / (prm.hardness * prm.particle_thickness)
        np.testing.assert_allclose(states[0].beta_at(law, p, v), expected, rtol=8 * 2.0**-53, atol=0)
    assert states[0].record == {"beta": None, "how": "slide", "slide": 0.02, "beta_initial": 0.0, "units": "SI",
                                "driver": "tc_node_slide (components/native/core/tc_node_friction.h)"}
    assert "sliding S = 20 mm" in states[0].description and "30 MPa 0.15" in states[0].description
    (si,) = debris_states(DebrisChoice(slide=0.02), law, SI)
    assert si.slide == 0.02 and si.label == "slide0.02"
    arriving = load_law(settings={"beta_initial": "0.03"})
    (s,) = debris_states(DebrisChoice(slide=20), arriving, MM)
    np.testing.assert_allclose(s.beta_at(arriving, 10e6, 0.08), 0.03 + 0.05, rtol=1e-15)
    assert "from beta_initial = 0.03, the debris the blank arrives with" in s.description


@pytest.mark.parametrize("choice, message", [
    (DebrisChoice(beta=(0.1,), slide=(20,)), "--beta and --slide both given"),
    (DebrisChoice(passes=(1,), pressure=25, slide=(20,)), "--passes and --slide both given"),
    (DebrisChoice(slide=(-1,)), "--slide -1 mm is negative"),
    (DebrisChoice(slide=("nan",)), "--slide nan is not finite"),
    (DebrisChoice(slide=(20,), velocity=80), "--velocity describes the strip-draw test of --passes"),
    (DebrisChoice(passes=(2,)), "--passes needs --pressure"),
    (DebrisChoice(pressure=25), "--pressure describes the strip-draw test of --passes"),
    (DebrisChoice(beta=(0.1,), passes=(1,), pressure=25), "--beta and --passes both given"),
    (DebrisChoice(passes=(0,), pressure=25), r"--passes 0: a number of passes is an integer >= 1"),
    (DebrisChoice(passes=("1.5",), pressure=25), r"--passes 1.5: a number of passes is an integer"),
    (DebrisChoice(beta=(-0.1,)), "--beta -0.1 is negative"),
    (DebrisChoice(beta=("nan",)), "--beta nan is not finite"),
    (DebrisChoice(beta=("x",)), "--beta 'x' is not a number"),
    (DebrisChoice(passes=(1,), pressure=60), r"--pressure 60 MPa is outside the table's pressure axis \[1, 30\]"),
    (DebrisChoice(passes=(1,), pressure=25, velocity=0), r"--velocity 0 mm/s: the drawing speed must lie in \(0, 500\]"),
    (DebrisChoice(passes=(1,), pressure=25, pad_length=-35), "--pad-length -35 mm"),
    (DebrisChoice(passes=(1,), pressure=math.inf), "--pressure inf is not finite"),
])
def test_a_bad_choice_names_the_option(law, choice, message):
    with pytest.raises(ParameterError, match=message):
        debris_states(choice, law, MM)


def test_a_debris_choice_takes_one_value_or_a_sequence():
    from tribocosim.cosim.apps.debris_state import DebrisChoice

    assert DebrisChoice(beta=0.1).beta == (0.1,) and DebrisChoice(beta=[0.0, 0.1]).beta == (0.0, 0.1)
    assert DebrisChoice(passes=3).passes == (3,) and DebrisChoice(beta="0.2").beta == ("0.2",)
