"""Parameter dataclass fields with unit, description and allowed range, and their validation.

Every model's parameters are one frozen dataclass whose fields are declared with :func:`param`.
The metadata is the single source for validation messages and for the FMU variable declarations.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import field

from tribocosim.errors import ParameterError, check_range


def param(default, unit: str, description: str, low=None, high=None, low_inclusive=True, **extra):
    """A dataclass field with its unit, description and allowed range ``[low, high]`` in the metadata.

    Both bounds are inclusive, as an FMU's ``min`` and ``max`` (FMI 2.0 section 2.2.7: min <= value <= max),
    which they become: a host offers them as valid values. A quantity that must be positive gets a small
    positive ``low`` that the model accepts.

    Extra metadata: ``integer=True`` for integer fields, ``choices=(...)`` for string fields with a
    fixed set of values, ``text=True`` for free-form string fields.
    """
    if not low_inclusive:
        raise ParameterError(f"{description!r}: low = {low!r} declared exclusive (low_inclusive=False); an FMU's min is "
                             "inclusive (min <= value): declare the least value the model accepts as low")
    meta = {"unit": unit, "description": description, "low": low, "high": high}
    meta.update(extra)
    return field(default=default, metadata=meta)


def validate_fields(obj) -> None:
    """Check every field of the dataclass instance ``obj`` against its metadata (each field once).

    Raises
    ------
    ParameterError
        Naming the field, its value and what is allowed; when several fields are bad, its ``fields`` lists each
        with its message and the message names them all.
    """
    bad = []
    for f in dataclasses.fields(obj):
        try:
            value = check_field(f, getattr(obj, f.name))
        except ParameterError as exc:
            bad.append((f.name, str(exc)))
            continue
        if value is not getattr(obj, f.name):
            object.__setattr__(obj, f.name, value)
    if bad:
        raise ParameterError("; ".join(message for _, message in bad), fields=bad)


def check_field(f: dataclasses.Field, value):
    """``value`` of field ``f`` as the dataclass keeps it (an integer field's value as an int), or ParameterError
    naming the field, the value and what its metadata allows."""
    meta = f.metadata
    if meta.get("text"):
        if not isinstance(value, str):
            raise ParameterError(f"{f.name} = {value!r} must be a string")
        return value
    if "choices" in meta:
        if value not in meta["choices"]:
            raise ParameterError(f"{f.name} = {value!r} is not allowed; choose one of {', '.join(meta['choices'])}")
        return value
    if meta.get("integer"):
        if (isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value)
                or int(value) != value):
            raise ParameterError(f"{f.name} = {value!r} must be an integer")
        value = int(value)
    elif isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(f"{f.name} = {value!r} must be a number")
    check_range(f.name, value, meta["low"], meta["high"], unit=meta["unit"] if meta["unit"] not in ("", "1") else "")
    return value
