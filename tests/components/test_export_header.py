"""The header every exported file carries: its provenance and limits, in lines that fit an 80-column deck."""

from __future__ import annotations

from tribocosim.components.friction_export.export_header import WIDTH, FileFacts, header_lines


def _facts(**changes):
    base = dict(
        format_title="LS-DYNA include", role="nominal", fe_rule="linearly", fe_beyond="LS-DYNA holds the end values",
        provenance={"table": {"file": "friction_table.npz", "content_hash": "ab" * 32,
                              "provenance": "mesoscale", "format_version": 4},
                    "parameters": {f"name_{k}": k * 1.5 for k in range(30)}},
        state="beta = 0.1, given (--beta)", units_line="units mm-t-s", range_lines=("range: 1-30 MPa",),
        accuracy=0.0031, largest=0.00305, tolerance=0.005, checked=20969, code_version="0.1.0")
    base.update(changes)
    return FileFacts(**base)


def test_every_line_fits_and_the_provenance_is_there():
    lines = header_lines(_facts())
    assert all(len(line) <= WIDTH for line in lines)
    text = " ".join(line.strip() for line in lines)
    for needed in ("table: friction_table.npz (content hash " + "ab" * 32, "mesoscale", "format version 4", "beta = 0.1, given (--beta)", "units mm-t-s",
                   "range: 1-30 MPa", "beyond it: LS-DYNA holds the end values", "by at most 0.310 % (target 0.5 %)",
                   "20969 points checked", "name_29=43.5", "every value rests on nodes the mesoscale campaign simulated"):
        assert needed in text, needed


def test_a_band_file_says_what_it_holds_and_warnings_are_marked():
    lines = header_lines(_facts(role="upper", band="this file holds mu + 2 se(mu)", warnings=("mu below a floor",),
                                unsimulated="12 of 100 lookups read unsimulated nodes"))
    text = " ".join(line.strip() for line in lines)
    assert lines[0].endswith("(upper band)")
    assert "band: this file holds mu + 2 se(mu)" in text and "WARNING: mu below a floor" in text
    assert "unsimulated: 12 of 100 lookups" in text


def test_the_calibration_data_are_named_by_file_and_hash_not_by_the_writers_folders():
    cal = {"status": "converged", "fitted": {"particle_area_scale": {"value": 1.6, "stderr": 0.03}},
           "data": {"file": "strip_draw.csv", "sha256": "cd" * 32}}
    lines = header_lines(_facts(provenance={**_facts().provenance, "calibration": cal}))
    text = " ".join(line.strip() for line in lines)
    assert f"data strip_draw.csv (SHA-256 {'cd' * 32})" in text and "/" not in text.split("written by")[0]
