"""Parameter dataclass fields with unit, description and allowed range, and their validation.

Every model's parameters are one frozen dataclass whose fields are declared with :func:`param`.
The metadata is the single source for validation messages and for the FMU variable declarations.

A value within :data:`BOUND_RTOL` of a bound (relative to the bound) is on it: :func:`within_bounds` is the one
comparison of a value with a declared bound or a table axis's end, here, in the friction table's lookups and in the C
checks generated from the declarations (``TC_BOUND_RTOL``, ``tc_below``/``tc_above`` of tc_common.h: the same
arithmetic, so both sides accept the same values). Round-off moves a value meant to be on a bound to either side of it:
12250 N on the 35 x 35 mm pad is 9999999.999999998 Pa, not 10 MPa.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import field

from tribocosim.errors import ParameterError, check_finite

#: a value within this of a bound, relative to the bound, is on it (TC_BOUND_RTOL of tc_common.h is the same)
BOUND_RTOL = 1e-9


def within_bounds(value: float, low: float | None = None, high: float | None = None) -> bool:
    """Whether ``value`` lies in ``[low, high]`` (a bound None is open), a value within :data:`BOUND_RTOL` of a bound
    (relative to it) counting as on it: ``low - BOUND_RTOL |low| <= value <= high + BOUND_RTOL |high|``, as the
    native checks compare (tc_below, tc_above). NaN is within no bounds."""
    if value != value:
        return False
    return ((low is None or value >= low - BOUND_RTOL * abs(low))
            and (high is None or value <= high + BOUND_RTOL * abs(high)))


def bound_text(x: float) -> str:
    """A bound for a message: its ``%g`` text, with more digits when that does not read back as the same number (the
    generated C checks print the same)."""
    for digits in range(6, 18):
        text = f"{x:.{digits}g}"
        if float(text) == x:
            return text
    return repr(float(x))


def outside_text(value: float, low: float | None, high: float | None, digits: int = 4) -> str:
    """``value`` for a message saying that it lies outside ``[low, high]``: with ``digits`` significant digits, or as
    many more as it takes for the printed number to lie outside too (12250 N on the 35 x 35 mm pad against an axis
    from 10.000001 MPa: "9.999999999999998", not "10")."""
    for d in range(digits, 18):
        text = f"{value:.{d}g}"
        if not within_bounds(float(text), low, high):
            return text
    return repr(float(value))


def range_text(low: float | None, high: float | None, unit: str = "") -> str:
    """``[low, high] unit`` (an open side as ``(-inf`` or ``inf)``) for a message."""
    lb = "(-inf" if low is None else f"[{bound_text(low)}"
    hb = "inf)" if high is None else f"{bound_text(high)}]"
    return f"{lb}, {hb}" + (f" {unit}" if unit else "")


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
    x = check_finite(f.name, value)
    if not within_bounds(x, meta["low"], meta["high"]):
        unit = meta["unit"] if meta["unit"] not in ("", "1") else ""
        raise ParameterError(f"{f.name} = {value!r}{' ' + unit if unit else ''} is out of range; allowed: "
                             f"{range_text(meta['low'], meta['high'], unit)}")
    return value
