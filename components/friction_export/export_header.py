"""What every exported file says about itself: the provenance and the limits of the law it holds, as lines of text.

Each writer puts these lines in its comment syntax (LS-DYNA ``$``, Abaqus ``**``) or as the ``header`` of the
neutral table; the neutral table also holds them as structured data. The lines are at most :data:`WIDTH`
characters, so that they fit an 80-column keyword deck after the comment marker.
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass, field

from tribocosim.components.friction_export.grid_refinement import percent_up

WIDTH = 76


@dataclass(frozen=True)
class FileFacts:
    """What one file holds and how it was made."""

    format_title: str  # "LS-DYNA *DEFINE_TABLE / *DEFINE_CURVE include", ...
    role: str  # "nominal", "upper", "lower"
    fe_rule: str  # how the FE code reads the file
    fe_beyond: str  # what the FE code does beyond the range
    provenance: dict  # ExportedLaw.provenance()
    state: str  # the debris state, in words
    units_line: str
    range_lines: tuple
    accuracy: float
    largest: float
    tolerance: float
    checked: int
    floor: float = 0.0  # below this mu the deviation is taken relative to it
    band: str = ""  # the band, in words (upper and lower files)
    unsimulated: str = ""  # the lookups that read unsimulated nodes, in words ("" when none)
    warnings: tuple = ()
    code_version: str = ""
    command: str = ""
    notes: tuple = field(default_factory=tuple)


def _wrap(text: str, indent: str = "  ") -> list[str]:
    return textwrap.wrap(text, WIDTH, subsequent_indent=indent, break_long_words=True, break_on_hyphens=False) or [""]


def table_line(provenance: dict) -> str:
    """The table a law reads, by file name and content hash (:meth:`ExportedLaw.provenance`)."""
    table = provenance["table"]
    return (f"table: {table['file']} (content hash {table['content_hash']}, {table['provenance']}, format version "
            f"{table['format_version']})")


def calibration_line(provenance: dict) -> str:
    """The calibration of a law: a calibration file by name, file name and SHA-256, with what it was fitted on; a
    calibrated table's status, the scale fitted and its data by file name and SHA-256; or none, with the scale."""
    cal = provenance.get("calibration")
    if not cal:
        scale = float(provenance["parameters"].get("particle_area_scale", 1.0))
        return ("calibration: none: the table's areas as the mesoscale campaign simulated them, A_p scaled by "
                f"particle_area_scale = {scale:g}" + (" (uncalibrated; --calibration paper fits the paper's one-pass "
                                                      "drop)" if scale == 1 else " (given)"))
    scale = (cal.get("fitted") or {}).get("particle_area_scale")
    fitted = (f"s = {scale['value']:.6g}" + (f" +- {scale['stderr']:.2g}" if scale.get("stderr") is not None
                                               else "")) if scale else "s not fitted"
    if cal.get("sha256"):  # a calibration file (named_calibration.py)
        made = (cal.get("made_by") or {}).get("command")
        return (f"calibration {cal.get('name')} ({cal.get('file')}, SHA-256 {cal.get('sha256')}): {cal.get('title')}; "
                f"status {cal.get('status')}, {fitted}" + (f"; made by {made}" if made else ""))
    data = cal.get("data") or {}
    name = data.get("file") or (data.get("path") and data["path"].replace("\\", "/").rsplit("/", 1)[-1])
    return (f"calibration (tribocosim calibrate): status {cal.get('status')}, {fitted}; data {name} (SHA-256 "
            f"{data.get('sha256')})")


def header_lines(f: FileFacts) -> list[str]:
    """The header of one file (module docstring)."""
    prov = f.provenance
    out = _wrap(f"tribocosim friction export: {f.format_title}" + ("" if f.role == "nominal" else
                                                                  f" ({f.role} band)"))
    out += _wrap(f"written by tribocosim {f.code_version}" + (f" with: {f.command}" if f.command else ""))
    out += _wrap("law: mu = mu0 (1 - (1 - r) s A_p/A_c) of the strip-draw model (docs/model.md section 4), "
                 "evaluated by its native core (tc_friction.c), the code the StripDraw FMU runs")
    out += _wrap(table_line(prov))
    out += _wrap(calibration_line(prov))
    out += _wrap(f"debris state: {f.state}")
    out += _wrap(f.units_line)
    for line in f.range_lines:
        out += _wrap(line)
    out += _wrap(f"beyond it: {f.fe_beyond}")
    floor = f" (of {f.floor:g} where mu is below it)" if f.floor > 0 else ""
    out += _wrap(f"the FE code reads this file {f.fe_rule}; read that way it deviates from tribocosim's mu by at most "
                 f"{percent_up(f.accuracy)} % (target {100 * f.tolerance:g} %) of mu{floor} in the range: the largest "
                 f"deviation at {f.checked} points checked (nodes, points inside every interval, random points) is "
                 f"{percent_up(f.largest)} %, and the bound adds what a peak between them can add "
                 "(components/friction_export/grid_refinement.py)")
    if f.band:
        out += _wrap(f"band: {f.band}")
    out += _wrap(f"unsimulated: {f.unsimulated}" if f.unsimulated else
                 "every value rests on nodes the mesoscale campaign simulated (no lookup read an unsimulated node)")
    for note in f.notes:
        out += _wrap(note)
    for w in f.warnings:
        out += _wrap(f"WARNING: {w}")
    params = prov["parameters"]
    out += _wrap("parameters: " + ", ".join(f"{k}={v}" for k, v in params.items()))
    return out
