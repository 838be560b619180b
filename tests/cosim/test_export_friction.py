"""The export in the package's API: ``tribocosim.export_friction`` with a debris state, a calibration file and its
band, the units of its arguments."""

from __future__ import annotations

import json

import numpy as np
import pytest

import tribocosim
from tribocosim.errors import ParameterError
from tribocosim.paths import DEFAULT_TABLE
from tribocosim.components.friction_export.exported_law import load_law
from tribocosim.components.stripdraw.table import read_table, write_table


def test_the_api_writes_the_law_at_a_state_the_strip_draw_test_reaches(tmp_path):
    result = tribocosim.export_friction("table", tmp_path / "f.json",
                                        tribocosim.DebrisChoice(passes=(2,), pressure=20e6, pad_length=0.035),
                                        units="SI")
    (f,) = result.files
    doc = json.loads(f.path.read_text())
    assert doc["debris_state"]["how"] == "passes" and doc["debris_state"]["after_pass"] == 2
    assert doc["debris_state"]["beta"] == f.state.beta > 0
    assert doc["units"]["pressure"] == "Pa" and doc["axes"][0]["values"][0] == 1e6


def test_an_unknown_format_is_refused_before_any_strip_draw_test_runs(tmp_path, monkeypatch):
    import tribocosim.cosim.apps.debris_state as debris_state

    monkeypatch.setattr(debris_state, "draw", lambda point: pytest.fail("the strip-draw test ran"))
    with pytest.raises(ParameterError, match="FORMAT 'nastran'"):
        tribocosim.export_friction("nastran", tmp_path / "f", tribocosim.DebrisChoice(passes=(1,), pressure=25))


def test_a_calibration_files_band_holds_the_interval_of_its_scale(tmp_path):
    from tribocosim.cosim.apps.calibrate import scaled_table

    record = {"fitted": {"particle_area_scale": {"value": 1.5, "stderr": 0.3}}, "status": "converged",
              "contact_area": "mesoscale", "particle_area_rule": "load_bearing", "parameters": {}}
    cal = tmp_path / "calibrated.npz"
    write_table(cal, scaled_table(read_table(DEFAULT_TABLE), 1.5, 0.15, "load_bearing", record))
    calibrated = tribocosim.export_friction("table", tmp_path / "cal.json", tribocosim.DebrisChoice(beta=(0.1,)),
                                            band=1.0, calibration=cal)
    b = json.loads(calibrated.files[0].path.read_text())
    p, v = np.meshgrid(*(np.array(a["values"]) for a in b["axes"]), indexing="ij")
    plain = load_law(settings={"particle_area_scale": 1.5})  # the same law without the calibration's interval
    np.testing.assert_allclose(b["mu"], plain.mu(p * 1e6, v * 1e-3, 0.1)[0], rtol=1e-12)
    assert np.all(np.array(b["mu_se"]) > plain.standard_error(p * 1e6, v * 1e-3, 0.1)), "the scale's 20 % widens it"
    upper = json.loads(calibrated.files[1].path.read_text())
    assert "status converged, s = 1.5 +- 0.3" in " ".join(" ".join(b["header"]).split())
    assert "the calibration's scale s = 1.5 +- 0.3 (in quadrature)" in upper["band"]["definition"]


def test_a_multi_pass_option_of_the_paper_report_sets_the_law_and_the_passes(tmp_path):
    """debris_sink_length = 35 mm (the report's sink_35) takes debris out while it slides under the pad: less of it
    after three passes than with the paper's model, and the option is written in the header."""
    from tribocosim.components.stripdraw.multipass_options import OPTIONS

    state = tribocosim.DebrisChoice(passes=(3,), pressure=25)
    paper = tribocosim.export_friction("table", tmp_path / "paper.json", state, pressure_range=(10, 30))
    sink = tribocosim.export_friction("table", tmp_path / "sink.json", state, option="sink_35")
    doc = json.loads(sink.files[0].path.read_text())
    assert doc["provenance"]["parameters"]["debris_sink_length"] == dict(
        (o.name, o.parameters) for o in OPTIONS)["sink_35"]["debris_sink_length"]
    assert 0 < sink.files[0].state.beta < paper.files[0].state.beta
    assert any("multi-pass option sink_35 of the paper report" in line for line in doc["header"])
    overridden = tribocosim.export_friction("table", tmp_path / "o.json", tribocosim.DebrisChoice(beta=(0.1,)),
                                            option="sink_35", settings={"debris_sink_length": "0.07"})
    assert json.loads(overridden.files[0].path.read_text())["provenance"]["parameters"]["debris_sink_length"] == 0.07
    with pytest.raises(ParameterError, match="--option 'nope' is not a multi-pass option"):
        tribocosim.export_friction("table", tmp_path / "x.json", option="nope")


def test_an_export_is_calibrated_by_default_and_says_so_in_its_header(tmp_path):
    """Neither a table nor a calibration: the paper calibration, named in the header by file and SHA-256 with the
    reason; no note on the law. --calibration none and --table: the campaign's law, with the note."""
    from tribocosim.components.friction_export.named_calibration import DEFAULT, read_calibration
    from tribocosim.cosim.apps.paper_calibration import one_pass_drop
    from tribocosim.paths import MODELS_DIR

    shipped = read_calibration(MODELS_DIR / "calibration_paper.json")
    result = tribocosim.export_friction("table", tmp_path / "d.json", tribocosim.DebrisChoice(beta=0.1))
    doc = json.loads(result.files[0].path.read_text())
    assert doc["provenance"]["parameters"]["particle_area_scale"] == shipped.scale
    assert doc["provenance"]["calibration"]["name"] == DEFAULT == "paper"
    assert doc["provenance"]["calibration"]["sha256"] == shipped.sha256
    header = " ".join(" ".join(doc["header"]).split())
    assert f"calibration paper (calibration_paper.json, SHA-256 {shipped.sha256})" in header
    assert "why calibrated (the default of every export)" in header and "gives 21.5 %" in header
    assert result.notes == ()
    drop = one_pass_drop(load_law())
    for kw in ({"calibration": "none"}, {"table": DEFAULT_TABLE}):
        plain = tribocosim.export_friction("table", tmp_path / "p.json", tribocosim.DebrisChoice(beta=0.1), **kw)
        (note,) = plain.notes
        assert note.startswith("the law is the mesoscale campaign's (friction_table.npz), uncalibrated")
        assert f"on the 35 mm pad (the paper's test, 0.08 m/s) is {100 * drop:.1f} %, where the paper measures 35 %" \
            in note
        doc = json.loads(plain.files[0].path.read_text())
        assert "calibration" not in doc["provenance"] and doc["provenance"]["parameters"]["particle_area_scale"] == 1
        assert note in " ".join(" ".join(doc["header"]).split())


def test_a_parameter_the_calibration_was_not_fitted_with_is_a_note_with_the_drop_it_gives(tmp_path):
    from tribocosim.cosim.apps.paper_calibration import one_pass_drop

    result = tribocosim.export_friction("table", tmp_path / "k.json", tribocosim.DebrisChoice(beta=0.1),
                                        settings={"archard_k": "2e-4"})
    (note,) = result.notes
    law = load_law(calibration_path="paper", settings={"archard_k": "2e-4"})
    assert law.departures() == {"archard_k": (1e-4, 2e-4)}
    assert note.startswith("the law's parameters are not those its calibration (paper) was fitted with: "
                           "archard_k = 0.0002 (fitted with 0.0001); ")
    assert f"is {100 * one_pass_drop(law):.1f} %, where the calibration is fitted on 35 %" in note
    by_hand = tribocosim.export_friction("table", tmp_path / "s.json", tribocosim.DebrisChoice(beta=0.1),
                                         settings={"particle_area_scale": "1.3"})
    assert by_hand.notes == ()  # a scale set by hand is the user's calibration: the law is the table's with it
    doc = json.loads(by_hand.files[0].path.read_text())
    assert "calibration" not in doc["provenance"] and doc["provenance"]["parameters"]["particle_area_scale"] == 1.3


def test_a_calibration_file_and_the_calibrated_table_of_the_same_fit_are_one_law(tmp_path):
    """The shipped calibration (the table with particle_area_scale = s) and a table of tribocosim calibrate's form
    with A_p times s (particle_area_scale = 1) give the same mu and the same se(mu), the scale's interval included."""
    from tribocosim.cosim.apps.calibrate import scaled_table

    cal = load_law(calibration_path="paper")
    s, se_s = cal.scale_interval
    record = {"fitted": {"particle_area_scale": {"value": s, "stderr": se_s}}, "status": "converged",
              "contact_area": "mesoscale", "particle_area_rule": "load_bearing",
              "parameters": {"zeta": 0.2, "archard_k": 1e-4}}
    path = tmp_path / "scaled.npz"
    write_table(path, scaled_table(read_table(DEFAULT_TABLE), s, 0.15, "load_bearing", record))
    scaled = load_law(calibration_path=path)
    rng = np.random.default_rng(2)
    p, v, b = rng.uniform(1e6, 3e7, 500), rng.uniform(0, 0.5, 500), rng.uniform(0, 0.3, 500)
    np.testing.assert_allclose(cal.mu(p, v, b)[0], scaled.mu(p, v, b)[0], rtol=1e-13)
    np.testing.assert_allclose(cal.standard_error(p, v, b), scaled.standard_error(p, v, b), rtol=1e-9, atol=1e-15)
