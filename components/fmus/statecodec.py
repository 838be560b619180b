"""Bytes for an FMU state: nested dicts of numpy arrays and Python scalars, restored bit-identically.

pythonfmu serialises an FMU state with ``json.dumps``, which cannot carry numpy arrays. The
adapters serialise their state through :func:`encode` / :func:`decode` instead (the hooks
``_fmu_state_to_bytes`` / ``_fmu_state_from_bytes`` of ``pythonfmu.Fmi2Slave``).

Format (version 1): the magic ``b"TRIBOCOSIM-FMUSTATE\\x00"``, then an uncompressed ``.npz``
archive read with ``allow_pickle=False`` (so decoding never runs code). The archive holds one
array per numpy leaf (``a0``, ``a1``, ...) and ``__tree__``: the UTF-8 JSON of the structure,
in which every node is tagged:

- ``{"t": "dict", "items": [[key, node], ...]}`` (string keys, order kept),
- ``{"t": "list"|"tuple", "items": [node, ...]}``,
- ``{"t": "ndarray"|"npscalar", "key": "a0"}`` (dtype and shape travel in the ``.npy`` entry),
- ``{"t": "float"|"int"|"bool"|"str"|"none", "v": value}``.

Python floats go through ``repr`` in the JSON, which round-trips every float64 exactly
(including ``nan``, ``inf`` and ``-0.0``); arrays keep their bytes. Only numpy and the standard
library are used, so the codec runs inside the FMU.
"""

from __future__ import annotations

import io
import json

import numpy as np

MAGIC = b"TRIBOCOSIM-FMUSTATE\x00"
VERSION = 1


class StateCodecError(ValueError):
    """A state that cannot be encoded, or bytes that are not an encoded state."""


def encode(state) -> bytes:
    """Encode ``state`` (nested dict/list/tuple of numpy arrays and Python scalars) to bytes."""
    arrays: dict[str, np.ndarray] = {}

    def node(x):
        if isinstance(x, dict):
            items = []
            for k, v in x.items():
                if not isinstance(k, str):
                    raise StateCodecError(f"state dict keys must be str; got {k!r} ({type(k).__name__})")
                items.append([k, node(v)])
            return {"t": "dict", "items": items}
        if isinstance(x, (list, tuple)):
            return {"t": type(x).__name__, "items": [node(v) for v in x]}
        if isinstance(x, (np.ndarray, np.generic)):
            arr = np.asarray(x)
            if arr.dtype.hasobject:
                raise StateCodecError("state arrays must not hold Python objects (dtype=object)")
            key = f"a{len(arrays)}"
            arrays[key] = arr
            return {"t": "ndarray" if isinstance(x, np.ndarray) else "npscalar", "key": key}
        if x is None:
            return {"t": "none", "v": None}
        for typ in (bool, int, float, str):  # bool before int: bool is an int subclass
            if type(x) is typ:
                return {"t": typ.__name__, "v": x}
        raise StateCodecError(f"cannot encode a state value of type {type(x).__name__}")

    tree = {"version": VERSION, "root": node(state)}
    buf = io.BytesIO()
    buf.write(MAGIC)
    tree_bytes = np.frombuffer(json.dumps(tree, allow_nan=True).encode("utf-8"), dtype=np.uint8)
    np.savez(buf, __tree__=tree_bytes, **arrays)
    return buf.getvalue()


def decode(data: bytes):
    """Inverse of :func:`encode`; raises :class:`StateCodecError` on anything else."""
    data = bytes(data)
    if not data.startswith(MAGIC):
        raise StateCodecError("not a tribocosim FMU state (bad magic bytes)")
    try:
        with np.load(io.BytesIO(data[len(MAGIC):]), allow_pickle=False) as npz:
            arrays = {k: npz[k] for k in npz.files}
        tree = json.loads(arrays.pop("__tree__").tobytes().decode("utf-8"))
    except Exception as exc:  # noqa: BLE001 - any parse failure means corrupt bytes
        raise StateCodecError(f"corrupt FMU state: {exc}") from exc
    if tree.get("version") != VERSION:
        raise StateCodecError(f"FMU state version {tree.get('version')!r}; this code reads version {VERSION}")

    def value(n):
        t = n["t"]
        if t == "dict":
            return {k: value(v) for k, v in n["items"]}
        if t == "list":
            return [value(v) for v in n["items"]]
        if t == "tuple":
            return tuple(value(v) for v in n["items"])
        if t == "ndarray":
            return arrays[n["key"]]
        if t == "npscalar":
            return arrays[n["key"]][()]
        if t == "float":
            return float(n["v"])
        if t in ("int", "bool", "str", "none"):
            return n["v"]
        raise StateCodecError(f"corrupt FMU state: unknown node type {t!r}")

    try:
        return value(tree["root"])
    except (KeyError, TypeError) as exc:
        raise StateCodecError(f"corrupt FMU state: {exc!r}") from exc
