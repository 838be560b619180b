"""The paper calibration the package ships: the calibration of the shipped table (its content hash), what the paper
report's calibration makes of it today, and the paper's one-pass 35 % drop at 25 MPa it reproduces within its fit's
tolerance; the one-pass drop an export states for an uncalibrated law."""

from __future__ import annotations

import json

import pytest

from tribocosim.components.friction_export.exported_law import load_law
from tribocosim.components.friction_export.named_calibration import DEFAULT, read_calibration
from tribocosim.components.stripdraw.table import read_table
from tribocosim.cosim.apps.paper_calibration import COMMAND, calibration_record, one_pass_drop
from tribocosim.cosim.reports.paper import DROP_TOL, PAPER_DROP_1PASS
from tribocosim.paths import DEFAULT_TABLE, MODELS_DIR

SHIPPED = MODELS_DIR / "calibration_paper.json"


@pytest.fixture(scope="module")
def shipped():
    return read_calibration(SHIPPED)


def test_it_is_the_calibration_of_the_shipped_table_and_says_how_it_was_made(shipped):
    record = shipped.record
    assert record["table"] == {"file": DEFAULT_TABLE.name,
                               "content_hash": read_table(DEFAULT_TABLE).metadata["content_hash"]}
    assert shipped.table_path == DEFAULT_TABLE.resolve()
    assert record["made_by"]["command"] == COMMAND
    assert "tribocosim.cosim.reports.paper.calibrate_drop" in record["made_by"]["function"]
    data = record["data"]
    assert (data["drop"], data["pressure"], data["reference_pressure"], data["tool_length"], data["passes"]) == (
        0.35, 25e6, 1e6, 0.035, 1)
    fitted = record["fitted"]["particle_area_scale"]
    assert fitted["value"] == record["parameters"]["particle_area_scale"] == shipped.scale > 1
    assert 0 < fitted["stderr"] < 0.1 * fitted["value"]
    prm = record["parameters"]  # the default model of the paper report's first column
    assert (prm["contact_area"], prm["flake_shear_ratio"], prm["zeta"], prm["archard_k"]) == ("mesoscale", 0.2, 0.2,
                                                                                              1e-4)
    assert record["status"] == "converged"


def test_the_shipped_calibration_reproduces_the_papers_one_pass_drop_within_its_fits_tolerance(shipped):
    law = load_law(calibration_path=DEFAULT)
    assert law.params.particle_area_scale == shipped.scale and not law.departures()
    drop = one_pass_drop(law)
    assert abs(drop - PAPER_DROP_1PASS) < DROP_TOL, drop
    assert drop == pytest.approx(shipped.record["fit"]["reached"], abs=1e-9)  # the draws the fit's last step made


def test_the_paper_reports_calibration_makes_the_shipped_scale_today(shipped):
    """The report's calibration rerun on the shipped table: its s within the fit's tolerance in s (|drop - 0.35| <
    1e-4 over d drop / d s) of the shipped one."""
    record = calibration_record()
    fit = shipped.record["fit"]
    tolerance_in_s = fit["tolerance"] / fit["slope"]
    assert abs(record["fitted"]["particle_area_scale"]["value"] - shipped.scale) <= tolerance_in_s
    assert record["table"] == shipped.record["table"]


def test_an_uncalibrated_law_gives_a_smaller_drop_and_the_calibrations_first_step_says_the_same(shipped):
    """s = 1, the campaign's A_p as simulated: the drop is the calibration's own first evaluation (s = 1)."""
    first = next(h for h in shipped.record["fit"]["history"] if h["particle_area_scale"] == 1.0)
    drop = one_pass_drop(load_law())
    assert drop == pytest.approx(first["drop"], abs=1e-9)
    assert drop < PAPER_DROP_1PASS - 0.05


def test_a_calibration_of_another_table_is_refused(tmp_path, shipped):
    import shutil

    from tribocosim.errors import ParameterError

    shutil.copy(MODELS_DIR / "friction_table_128um.npz", tmp_path / DEFAULT_TABLE.name)  # another table, same name
    (tmp_path / "cal.json").write_text(SHIPPED.read_text())
    with pytest.raises(ParameterError, match="was fitted on the table friction_table.npz with content hash"):
        load_law(calibration_path=tmp_path / "cal.json")
    (tmp_path / "other.json").write_text(json.dumps({"format": "something else"}))
    with pytest.raises(ParameterError, match="is not a calibration file of format 'tribocosim-calibration'"):
        load_law(calibration_path=tmp_path / "other.json")
