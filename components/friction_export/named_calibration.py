"""A calibration as a small file beside its table, and the calibrations the package ships by name.

A calibration of ``tribocosim calibrate`` is a whole table with its A_p scaled (an .npz with the record in its
metadata). This form holds the fit alone (JSON, ``format`` ``tribocosim-calibration``, ``format_version`` 1):

===================  =====================================================================================
key                  value
===================  =====================================================================================
``name``             what it is called (``--calibration NAME`` for a shipped one)
``title``            what it is, in words
``table``            ``file`` (the table's file name, read from the calibration file's folder) and
                     ``content_hash`` (the table's; checked when read: a rebuilt or replaced table is refused
                     rather than used with a scale fitted on another)
``parameters``       every strip-draw parameter the fit was made with, ``particle_area_scale`` the fitted s
``fitted``           ``particle_area_scale``: ``value`` and ``stderr`` (and the parts of the standard error)
``status``           ``converged`` when the fit reached its tolerance
``contact_area``,    as ``parameters`` says (what :func:`~.exported_law.load_law` reads of every calibration)
``particle_area_rule``
``data``             what it was fitted on (for the paper's: the quote of the paper's text, the test)
``fit``              the fitted quantity's target, value reached and tolerance, the evaluations and the history
``made_by``          the command that writes the file, the function that fits, the code version
``note``             how the law is used: the table with ``parameters``
===================  =====================================================================================

The law of such a calibration is its table with its ``parameters`` (``particle_area_scale`` = s), then ``--set``.

Named calibrations (``--calibration NAME``): ``paper`` (``models/calibration_paper.json``, written by
``python -m tribocosim.cosim.apps.paper_calibration``), the paper report's calibration of the default model (A_c from
the table, r at the documented floor, zeta 0.2, K 1e-4) on the paper's one number for it, the one-pass drop of mu_bar
at 25 MPa against 1 MPa on the 35 mm pad, 35 % (Sec. 2.1); ``none``: no calibration, the shipped table's A_p as the
mesoscale campaign simulated it (particle_area_scale = 1).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

from tribocosim.errors import ParameterError

FORMAT = "tribocosim-calibration"
FORMAT_VERSION = 1
#: the calibrations the package ships, by name: their files in tribocosim.models
NAMED = {"paper": "calibration_paper.json"}
#: the name of no calibration: the shipped table as the campaign made it
NONE = "none"
#: the calibration an export uses when it is given neither a table nor a calibration (nor particle_area_scale)
DEFAULT = "paper"


@dataclass(frozen=True)
class ScaleCalibration:
    """A calibration file read and checked: its path, the file's SHA-256, its record and the table it names."""

    path: Path
    sha256: str
    record: dict
    table_path: Path

    @property
    def scale(self) -> float:
        return float(self.record["fitted"]["particle_area_scale"]["value"])

    def law_record(self) -> dict:
        """The record a law carries (:attr:`ExportedLaw.calibration`): the file's, with its name and SHA-256, and the
        table as ``source_table``."""
        return {**self.record, "file": self.path.name, "sha256": self.sha256, "source_table": self.record["table"]}


def named_path(text) -> Path | None:
    """The file of a shipped calibration's name (``paper``), or None for anything else (a path)."""
    if text is None or str(text) not in NAMED:
        return None
    from tribocosim.paths import MODELS_DIR

    return MODELS_DIR / NAMED[str(text)]


def is_calibration_json(path: Path) -> bool:
    return path.suffix.lower() == ".json"


def read_calibration(path, option: str = "--calibration") -> ScaleCalibration:
    """The calibration file at ``path`` (module docstring), with its table found beside it and its content hash
    checked; ParameterError naming ``option`` for a file that is missing, not this format, or whose table is missing
    or is not the one it was fitted on."""
    from tribocosim.components.stripdraw.table import read_table

    path = Path(path)
    if not path.is_file():
        names = ", ".join(sorted((*NAMED, NONE)))
        raise ParameterError(f"{option} {path}: no such file, and not a calibration's name ({names})")
    data = path.read_bytes()
    try:
        record = json.loads(data)
    except ValueError as exc:
        raise ParameterError(f"{option} {path} is not a calibration file: not JSON ({exc})") from None
    if not isinstance(record, dict) or record.get("format") != FORMAT or record.get("format_version") != FORMAT_VERSION:
        raise ParameterError(f"{option} {path} is not a calibration file of format {FORMAT!r} version {FORMAT_VERSION} "
                             "(a calibration of tribocosim calibrate is the .npz it writes)")
    try:
        table_file, table_hash = record["table"]["file"], record["table"]["content_hash"]
        scale = float(record["fitted"]["particle_area_scale"]["value"])
        parameters = dict(record["parameters"])
    except (KeyError, TypeError, ValueError) as exc:
        raise ParameterError(f"{option} {path}: the calibration record lacks {exc}") from None
    if not (scale >= 0 and parameters.get("particle_area_scale") == scale):
        raise ParameterError(f"{option} {path}: its parameters' particle_area_scale is not its fitted s = {scale!r}")
    table_path = path.parent / Path(table_file).name
    if not table_path.is_file():
        raise ParameterError(f"{option} {path}: its table {table_file} is not beside it ({path.parent})")
    actual = read_table(table_path).metadata.get("content_hash")
    if actual != table_hash:
        raise ParameterError(f"{option} {path} was fitted on the table {table_file} with content hash {table_hash}; "
                             f"{table_path} has {actual}: refit it on this table (its s holds for the other)")
    return ScaleCalibration(path.resolve(), hashlib.sha256(data).hexdigest(), record, table_path.resolve())


def calibration_text(record: dict) -> str:
    """The file's text of a record (module docstring): indented JSON, keys in the order given."""
    return json.dumps({"format": FORMAT, "format_version": FORMAT_VERSION, **record}, indent=1, allow_nan=False) + "\n"
