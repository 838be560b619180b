"""Parameter dataclass fields with unit, description and allowed range, and their validation.

Every model's parameters are one frozen dataclass whose fields are declared with :func:`param`.
The metadata is the single source for validation messages and for the FMU variable declarations.
"""

from __future__ import annotations

import dataclasses
from dataclasses import field

from tribocosim.components.errors import ParameterError, check_range


def param(default, unit: str, description: str, low=None, high=None, low_inclusive=True, **extra):
    """A dataclass field with its unit, description and allowed range ``[low, high]`` in the metadata.

    Extra metadata: ``integer=True`` for integer fields, ``choices=(...)`` for string fields with a
    fixed set of values, ``text=True`` for free-form string fields.
    """
    meta = {"unit": unit, "description": description, "low": low, "high": high, "low_inclusive": low_inclusive}
    meta.update(extra)
    return field(default=default, metadata=meta)


def validate_fields(obj) -> None:
    """Check every field of the dataclass instance ``obj`` against its metadata.

    Raises
    ------
    ParameterError
        Naming the field, its value and what is allowed.
    """
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        meta = f.metadata
        if meta.get("text"):
            if not isinstance(value, str):
                raise ParameterError(f"{f.name} = {value!r} must be a string")
            continue
        if "choices" in meta:
            if value not in meta["choices"]:
                raise ParameterError(f"{f.name} = {value!r} is not allowed; choose one of {', '.join(meta['choices'])}")
            continue
        if meta.get("integer"):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or int(value) != value:
                raise ParameterError(f"{f.name} = {value!r} must be an integer")
            object.__setattr__(obj, f.name, int(value))
        elif isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ParameterError(f"{f.name} = {value!r} must be a number")
        check_range(
            f.name,
            value,
            meta["low"],
            meta["high"],
            low_inclusive=meta["low_inclusive"],
            unit=meta["unit"] if meta["unit"] not in ("", "1") else "",
        )
