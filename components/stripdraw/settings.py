"""Strip-draw parameters set on a command line (``tribocosim export --set``, ``tribocosim calibrate --set``): each
value typed as the parameter's declaration takes it (docs/fmu-reference.md), checked once here."""

from __future__ import annotations

import dataclasses

from tribocosim.errors import ParameterError
from tribocosim.name_value import split_settings

from .parameters import StripDrawParameters


def typed_setting(name: str, value, option: str = "--set"):
    """The value of strip-draw parameter ``name`` as the parameter dataclass takes it (text as given for a text or
    a choice, a number from its text); ParameterError naming ``option`` for a name that is not a parameter or a value
    that is not a number."""
    fields = {f.name: f for f in dataclasses.fields(StripDrawParameters)}
    if name not in fields:
        hint = " (the table is --table, a calibration file --calibration)" if name == "table_file" else ""
        raise ParameterError(f"{option} {name}={value}: {name!r} is not a strip-draw parameter{hint}; the parameters "
                             "are the fields of StripDrawParameters (docs/fmu-reference.md)")
    meta = fields[name].metadata
    if not isinstance(value, str) or meta.get("text") or "choices" in meta:
        return value
    try:
        return int(value) if meta.get("integer") else float(value)
    except ValueError:
        kind = "an integer" if meta.get("integer") else "a number"
        raise ParameterError(f"{option} {name}={value}: {value!r} is not {kind}") from None


def parse_settings(items, option: str = "--set") -> dict:
    """``NAME=VALUE`` items as ``{strip-draw parameter: typed value}`` (:func:`typed_setting`)."""
    return {name: typed_setting(name, value, option) for name, value in split_settings(items, option).items()}
