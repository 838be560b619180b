"""The digest of a finished campaign case, and the check of its files against it.

A finished case is two files in ``OUT/cases`` (:mod:`tribocosim.surrogate.campaign`): ``<id>.json``, the record
(labels, configuration, the slide's summary, wall time, host, code version, ...), and ``<id>.npz``, its per-step
series. The record carries ``digest``, the SHA-256 (hex) of

    ``b"tribocosim case digest 1\\n"`` + the canonical JSON of the record without ``digest`` (sorted keys, no
    spaces) + for every series in name order: its name, dtype, shape and bytes,

so that a number edited in either file, a truncated or garbage ``.npz`` and a record whose ``.npz`` is gone are
found. JSON numbers read back to the same floats, so the canonical text of a record read from disk is the one
that was hashed. :func:`check_case` reads both files and recomputes the digest; it raises
:class:`~tribocosim.errors.CaseRecordError` naming the file and what is wrong.

Records without ``digest`` (written by versions before case digests) are *legacy*. They are checked by what
they hold: the summary's mean areas are the means of the series in the ``.npz`` (``SlideResult.summary``:
<A_p>/A0 from ``particle_fraction``, A_p of the cluster rule from ``particle_fraction_clusters``, <A_c>/A0 from
``contact_fraction``), equal to 1e-12 relative; a record that passes is accepted as legacy (a campaign warns
that its other numbers, e.g. the wall time, cannot be checked), one that fails or has no ``.npz`` is refused.
"""

from __future__ import annotations

import hashlib
import json
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tribocosim.errors import CaseRecordError

DIGEST_KEY = "digest"
_PREFIX = b"tribocosim case digest 1\n"
#: summary value -> the series it is the mean of (the legacy check)
MEANS_OF_SERIES = {"mean_particle_fraction": "particle_fraction",
                   "mean_particle_fraction_clusters": "particle_fraction_clusters",
                   "mean_contact_fraction": "contact_fraction"}
LEGACY_RTOL = 1e-12


def canonical_json(record: dict) -> str:
    """The record without its digest as canonical JSON (sorted keys, no spaces; NaN as JSON's ``NaN``)."""
    body = {k: v for k, v in record.items() if k != DIGEST_KEY}
    return json.dumps(json.loads(json.dumps(body)), sort_keys=True, separators=(",", ":"))


def case_digest(record: dict, series: dict | None) -> str:
    """SHA-256 (hex) of a case record (without ``digest``) and its series arrays (module docstring)."""
    h = hashlib.sha256(_PREFIX)
    h.update(canonical_json(record).encode())
    for name in sorted(series or {}):
        a = np.ascontiguousarray(series[name])
        h.update(f"\n{name} {a.dtype.str} {a.shape}\n".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def read_series(path: Path) -> dict:
    """Every array of a case's ``.npz`` (CaseRecordError if it cannot be read)."""
    if not zipfile.is_zipfile(path):
        raise CaseRecordError(f"case series {path} cannot be read: it is not an .npz file (no zip archive; "
                              "truncated or overwritten)", path)
    try:
        with np.load(path, allow_pickle=False) as z:
            return {k: np.array(z[k]) for k in z.files}
    except Exception as exc:  # noqa: BLE001 - a truncated or foreign file fails in many ways
        raise CaseRecordError(f"case series {path} cannot be read ({type(exc).__name__}: {exc}): it is "
                              "truncated or not the .npz the campaign wrote", path) from None


@dataclass(frozen=True)
class CheckedCase:
    """A case record that passed :func:`check_case`; ``legacy``: it has no digest (module docstring)."""

    record: dict
    legacy: bool


def check_case(json_path: Path, case_id: str) -> CheckedCase:
    """Read ``json_path`` (and the ``.npz`` beside it) and check them (module docstring).

    Raises
    ------
    FileNotFoundError
        If ``json_path`` does not exist (the case is not finished).
    CaseRecordError
        If a file cannot be read, the record is not the one of ``case_id``, or the files do not match the digest.
    """
    json_path = Path(json_path)
    npz_path = json_path.with_suffix(".npz")
    try:
        text = json_path.read_text()
    except FileNotFoundError:
        raise
    except OSError as exc:
        raise CaseRecordError(f"case record {json_path} cannot be read: {exc}", json_path) from None
    try:
        record = json.loads(text)
    except ValueError as exc:
        raise CaseRecordError(f"case record {json_path} is not valid JSON ({exc}): it is truncated or was edited",
                              json_path) from None
    if not isinstance(record, dict) or record.get("case_id") != case_id:
        found = record.get("case_id") if isinstance(record, dict) else type(record).__name__
        raise CaseRecordError(f"case record {json_path} is the record of {found!r}, not of case {case_id}", json_path)
    series = read_series(npz_path) if npz_path.exists() else None
    recorded = record.get(DIGEST_KEY)
    if recorded is None:
        _check_legacy(json_path, npz_path, record, series)
        return CheckedCase(record, legacy=True)
    if series is None and record.get("series_names"):
        raise CaseRecordError(f"case series {npz_path} is missing (the record {json_path.name} lists "
                              f"{len(record['series_names'])} series)", npz_path)
    computed = case_digest(record, series)
    if computed != recorded:
        raise CaseRecordError(
            f"case record {json_path} does not match its digest (sha256 {str(recorded)[:16]}... recorded, "
            f"{computed[:16]}... computed from {json_path.name}"
            + (f" and {npz_path.name}" if series is not None else "")
            + "): a value in one of them was changed after the slide wrote it", json_path)
    return CheckedCase(record, legacy=False)


def _check_legacy(json_path: Path, npz_path: Path, record: dict, series: dict | None) -> None:
    if series is None:
        raise CaseRecordError(f"case record {json_path} has no digest and its series {npz_path.name} is missing: "
                              "it cannot be checked", json_path)
    summary = record.get("summary")
    if not isinstance(summary, dict):
        raise CaseRecordError(f"case record {json_path} has no summary", json_path)
    for key, name in MEANS_OF_SERIES.items():
        if key not in summary or name not in series:
            continue
        value, mean = summary[key], float(np.mean(series[name]))
        if not isinstance(value, (int, float)) or abs(value - mean) > LEGACY_RTOL * max(abs(value), abs(mean)):
            raise CaseRecordError(f"case record {json_path} (no digest) gives {key} = {value!r}, but the mean of "
                                  f"its series {npz_path.name}:{name} is {mean!r}: the record was changed after "
                                  "the slide wrote it", json_path)
