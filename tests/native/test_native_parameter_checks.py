"""The parameter checks of the native cores against the component declarations: the C checks are generated from the
declarations (``<prefix>_params_check`` of the generated ``<prefix>_params.h``, components/native/toolchain/
declarations.py), each core's create function calls them, and they accept and refuse what the Python validation
(components/params.py) does. Every parameter of every native component is probed at its declared bounds, within the
bound tolerance of them (BOUND_RTOL, 1e-9 relative), just beyond it, and every choice index; a hand-written check in C
that differs from the declaration (the strip draw's n_elements accepted from 1 to 1e8 against the declared 4 to
200000) fails here."""

from __future__ import annotations

import ctypes
import dataclasses
import math

import pytest

from tribocosim.components import registry
from tribocosim.components.native.toolchain.library import Msg, core
from tribocosim.components.params import BOUND_RTOL, check_field, within_bounds
from tribocosim.errors import ParameterError

#: the native components and their exported check (TC_API wrapper of the generated <prefix>_params_check)
COMPONENTS = ("stripdraw", "press", "drawingmachine")


def probes(f: dataclasses.Field):
    """(value for Python, value for the C struct, allowed) around the declaration of field f."""
    meta = f.metadata
    if "choices" in meta:
        choices = meta["choices"]
        yield from ((c, k, True) for k, c in enumerate(choices))
        yield from (("not-a-choice", k, False) for k in (-1, len(choices)))
        return
    if meta.get("text"):
        return
    low, high = meta.get("low"), meta.get("high")
    if meta.get("integer"):
        for bound, step in ((low, -1), (high, +1)):
            if bound is not None:
                yield int(bound), int(bound), True
                yield int(bound) + step, int(bound) + step, False
        return
    for bound, side in ((low, -1.0), (high, +1.0)):
        if bound is None:
            continue
        yield bound, bound, True
        if bound != 0.0:
            inside = bound + side * 0.5 * BOUND_RTOL * abs(bound)  # round-off beyond the bound: on it
            beyond = bound + side * 2.0 * BOUND_RTOL * abs(bound)
        else:
            inside, beyond = None, side * 1e-300
        if inside is not None:
            yield inside, inside, True
        yield beyond, beyond, False
    yield math.nan, math.nan, False
    yield math.inf, math.inf, False


def c_check(comp, struct) -> tuple[int, str]:
    buf = ctypes.create_string_buffer(512)
    fn = getattr(core().lib, f"{comp.native.prefix}_check_params")
    status = fn(ctypes.byref(struct), Msg(ctypes.addressof(buf), len(buf)))
    return status, buf.value.decode()


def with_value(comp, field: str, value):
    """The C parameter struct of the component's defaults with one member set."""
    struct = core().struct(comp.parameters())
    setattr(struct, field, value)
    return struct


@pytest.mark.parametrize("name", COMPONENTS)
def test_the_c_checks_accept_and_refuse_what_the_declaration_does(name):
    comp = registry.components()[name]
    probed = 0
    for f in dataclasses.fields(comp.parameters):
        for py_value, c_value, allowed in probes(f):
            status, message = c_check(comp, with_value(comp, f.name, c_value))
            assert (status == 0) == allowed, (f.name, c_value, message)
            if not allowed:
                assert status == 2 and message.startswith(f"{f.name} = "), (f.name, message)
            try:
                check_field(f, py_value)
                python_allowed = True
            except ParameterError:
                python_allowed = False
            assert python_allowed == allowed, (f.name, py_value)
            probed += 1
    assert probed >= 4 * len([f for f in dataclasses.fields(comp.parameters) if not f.metadata.get("text")])


@pytest.mark.parametrize("name", COMPONENTS)
def test_create_refuses_every_value_the_declaration_refuses(name):
    """The create function of each core runs the generated check first: a refused probe is refused by create with the
    check's message (create may refuse an allowed value for a reason of its own, e.g. the table law without a table,
    which is not probed here)."""
    comp = registry.components()[name]
    lib = core().lib
    prefix = comp.native.prefix
    for f in dataclasses.fields(comp.parameters):
        for _, c_value, allowed in probes(f):
            if allowed:
                continue
            struct = with_value(comp, f.name, c_value)
            _, expected = c_check(comp, struct)
            buf = ctypes.create_string_buffer(512)
            handle = ctypes.c_void_p()
            msg = Msg(ctypes.addressof(buf), len(buf))
            if name == "stripdraw":
                status = lib.tc_stripdraw_create(ctypes.byref(struct), None, None, 0, ctypes.byref(handle), msg)
            else:
                status = getattr(lib, f"{prefix}_create")(ctypes.byref(struct), ctypes.byref(handle), msg)
            assert status == 2 and not handle.value, (f.name, c_value)
            assert buf.value.decode() == expected


def test_the_strip_draws_mesh_is_the_declared_one():
    """n_elements: 4 and 200000 are allowed, 3 and 200001 are not (the core took 1 to 1e8), with the declaration's
    range in the message."""
    comp = registry.components()["stripdraw"]
    assert c_check(comp, with_value(comp, "n_elements", 4))[0] == 0
    assert c_check(comp, with_value(comp, "n_elements", 200000))[0] == 0
    for bad in (3, 200001):
        assert c_check(comp, with_value(comp, "n_elements", bad)) == (
            2, f"n_elements = {bad} is out of range; allowed: [4, 200000]")


def test_a_value_on_a_bound_to_round_off_is_on_it():
    """within_bounds, the one comparison with a bound: 12250 N on the 35 x 35 mm pad is 9999999.999999998 Pa, on an
    axis that starts at 10 MPa; 1e-9 of the bound beyond it is the tolerance, 2e-9 is outside; a bound 0 is exact."""
    pressure = 12250.0 / (0.035 * 0.035)
    assert pressure < 1e7 and within_bounds(pressure, 1e7, 3e7)
    assert within_bounds(3e7 * (1 + 0.9e-9), 1e7, 3e7) and not within_bounds(3e7 * (1 + 2e-9), 1e7, 3e7)
    assert within_bounds(0.0, 0.0, None) and not within_bounds(-1e-300, 0.0, None)
    assert not within_bounds(math.nan, None, None)
