"""Parameter dataclass fields with unit, description and allowed range, and their validation.

Every model's parameters are one frozen dataclass (:func:`parameters`) whose fields are declared with :func:`param`.
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


def parameters(cls):
    """``cls`` as ``dataclasses.dataclass(frozen=True)`` makes it (its fields for ``dataclasses.fields``, ``replace``
    and ``asdict``; ``__init__`` by position or name with the defaults, then ``__post_init__``; the same ``repr``,
    equality and hash of the field values; assignment raises ``dataclasses.FrozenInstanceError``), with methods shared
    by every parameter class instead of methods generated for each: ``dataclass`` writes a class's methods as text and
    compiles them when the class is made, some 28 million instructions (callgrind) for the four parameter classes
    every ``tribocosim run`` of the demo imports to check its scene, more than the run's scene checks cost."""
    cls = dataclasses.dataclass(init=False, repr=False, eq=False)(cls)
    cls._field_names = tuple(f.name for f in dataclasses.fields(cls))
    for name, method in (("__init__", _init), ("__repr__", _repr), ("__eq__", _eq), ("__hash__", _hash),
                         ("__setattr__", _frozen), ("__delattr__", _frozen)):
        if cls.__dict__.get(name) is None:  # not the class's own (a __hash__ of None: Python's beside an own __eq__)
            setattr(cls, name, method)
    return cls


def _init(self, *args, **kwargs) -> None:
    cls = type(self)
    names = cls._field_names
    if len(args) > len(names):
        raise TypeError(f"{cls.__qualname__}.__init__() takes {len(names) + 1} positional arguments but "
                        f"{len(args) + 1} were given")
    values = dict(zip(names, args))
    for name, value in kwargs.items():
        if name not in names:
            raise TypeError(f"{cls.__qualname__}.__init__() got an unexpected keyword argument {name!r}")
        if name in values:
            raise TypeError(f"{cls.__qualname__}.__init__() got multiple values for argument {name!r}")
        values[name] = value
    for f in dataclasses.fields(cls):
        if f.name in values:
            value = values[f.name]
        elif f.default is not dataclasses.MISSING:
            value = f.default
        elif f.default_factory is not dataclasses.MISSING:
            value = f.default_factory()
        else:
            raise TypeError(f"{cls.__qualname__}.__init__() missing 1 required argument: {f.name!r}")
        object.__setattr__(self, f.name, value)
    post_init = getattr(self, "__post_init__", None)
    if post_init is not None:
        post_init()


def _repr(self) -> str:
    fields = ", ".join(f"{f.name}={getattr(self, f.name)!r}" for f in dataclasses.fields(self) if f.repr)
    return f"{type(self).__qualname__}({fields})"


def _values(obj) -> tuple:
    return tuple(getattr(obj, name) for name in obj._field_names)


def _eq(self, other):
    if other.__class__ is not self.__class__:
        return NotImplemented
    return _values(self) == _values(other)


def _hash(self) -> int:
    return hash(_values(self))


def _frozen(self, name, *value):
    raise dataclasses.FrozenInstanceError(f"cannot assign to field {name!r}" if value else
                                          f"cannot delete field {name!r}")


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
