"""tribocosim.components.fmus.statecodec: FMU-state bytes that restore nested numpy states bit-identically."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from tribocosim.components.fmus import statecodec


def _same(a, b, path="state"):
    """Structural, type and bit equality (NaN == NaN, -0.0 != 0.0)."""
    assert type(a) is type(b), f"{path}: {type(a).__name__} != {type(b).__name__}"
    if isinstance(a, dict):
        assert list(a) == list(b), f"{path}: keys {list(a)} != {list(b)}"
        for k in a:
            _same(a[k], b[k], f"{path}[{k!r}]")
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _same(x, y, f"{path}[{i}]")
    elif isinstance(a, (np.ndarray, np.generic)):
        assert (a.dtype, a.shape) == (b.dtype, b.shape), path
        assert np.asarray(a).tobytes() == np.asarray(b).tobytes(), f"{path}: bytes differ"
    elif isinstance(a, float):
        assert math.copysign(1, a) == math.copysign(1, b) and (a == b or (a != a and b != b)), f"{path}: {a} {b}"
    else:
        assert a == b, f"{path}: {a!r} != {b!r}"


def test_round_trip_is_bit_identical():
    rng = np.random.default_rng(7)
    state = {
        "U": rng.standard_normal(451),
        "contact": (rng.random(451) > 0.5).astype(np.int8),
        "empty": np.zeros((0, 3)),
        "matrix": np.asfortranarray(rng.standard_normal((3, 4))),
        "time": 0.1 + 0.2,  # not a short decimal
        "tiny": 5e-324,
        "specials": [math.nan, math.inf, -math.inf, -0.0],
        "n_steps": 2**62 + 1,
        "flag": True,
        "name": "table \u03bc",
        "nothing": None,
        "np_scalar": np.float64(1 / 3),
        "np_int": np.int64(-5),
        "nested": {"inputs": {"normal_force": 12250.000000000002}, "pair": (1, 2.5)},
    }
    blob = statecodec.encode(state)
    assert isinstance(blob, bytes) and blob.startswith(statecodec.MAGIC)
    _same(statecodec.decode(blob), state)
    assert statecodec.encode(statecodec.decode(blob)) == blob, "encoding is not deterministic"


def test_decoded_arrays_are_independent_of_the_bytes():
    blob = statecodec.encode({"U": np.arange(4.0)})
    first = statecodec.decode(blob)
    first["U"][0] = 99.0
    assert_array_equal(statecodec.decode(blob)["U"], np.arange(4.0), err_msg="decode shares memory")


@pytest.mark.parametrize(
    "bad, message",
    [
        (b"", "bad magic"),
        (b"XYZ" + b"\0" * 40, "bad magic"),
        (statecodec.MAGIC + b"truncated", "corrupt"),
    ],
)
def test_decode_refuses_foreign_or_corrupt_bytes(bad, message):
    with pytest.raises(statecodec.StateCodecError, match=message):
        statecodec.decode(bad)


def test_decode_refuses_other_versions_and_object_arrays(monkeypatch):
    blob = statecodec.encode({"x": 1.0})
    with pytest.raises(statecodec.StateCodecError, match="CRC"):  # the zip checksums guard the bytes
        statecodec.decode(blob.replace(b"1.0", b"2.0"))
    monkeypatch.setattr(statecodec, "VERSION", 9)
    future = statecodec.encode({"x": 1.0})
    monkeypatch.undo()
    with pytest.raises(statecodec.StateCodecError, match="version 9"):
        statecodec.decode(future)
    with pytest.raises(statecodec.StateCodecError, match="dtype=object"):
        statecodec.encode({"x": np.array([{}], dtype=object)})
    with pytest.raises(statecodec.StateCodecError, match="keys must be str"):
        statecodec.encode({1: 2.0})
    with pytest.raises(statecodec.StateCodecError, match="type set"):
        statecodec.encode({"x": {1, 2}})
