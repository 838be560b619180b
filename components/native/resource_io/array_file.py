"""The array file: named float64 arrays and texts in one flat little-endian binary file (extension ``.tca``).

The format the native code reads (``tc_arrays.c``); Python writes it from the general formats it reads
(the friction table's ``.npz``: :func:`tribocosim.components.stripdraw.table.write_table_resource`). Generic:
a reader looks entries up by name and skips the ones it does not know, so a file may gain entries without a
change to any reader.

Layout (all integers unsigned, little-endian)::

    magic        8 bytes   b"TCARRAYS"
    version      uint32    1
    count        uint32    number of entries
    count x entry:
      name_len   uint16    1..255
      name       name_len bytes, ASCII
      kind       uint8     0: float64 array, 1: UTF-8 text
      ndim       uint8     0..8 (text: 0)
      shape      ndim x uint64
      size       uint64    bytes of data that follow: 8 x prod(shape) (float64), the text's length (text)
      data       size bytes: float64 little-endian in C order, or the text

A scalar is a 0-d array (one value). Names are unique within a file.
"""

from __future__ import annotations

import os
import struct
from pathlib import Path

import numpy as np

from tribocosim.errors import ParameterError

MAGIC = b"TCARRAYS"
VERSION = 1
FLOAT64, TEXT = 0, 1
MAX_NDIM = 8


def encode(entries: dict) -> bytes:
    """The bytes of an array file holding ``entries`` (name -> float array or scalar, or str), in their order."""
    out = [MAGIC, struct.pack("<II", VERSION, len(entries))]
    for name, value in entries.items():
        raw = name.encode("ascii")
        if not 0 < len(raw) < 256:
            raise ParameterError(f"array file entry name {name!r} must have 1 to 255 ASCII characters")
        if isinstance(value, str):
            data = value.encode("utf-8")
            out += [struct.pack("<H", len(raw)), raw, struct.pack("<BB", TEXT, 0), struct.pack("<Q", len(data)), data]
            continue
        a = np.array(value, dtype="<f8", order="C")  # (ascontiguousarray would make a scalar 1-D)
        if a.ndim > MAX_NDIM:
            raise ParameterError(f"array file entry {name!r} has {a.ndim} dimensions; at most {MAX_NDIM} are allowed")
        out += [struct.pack("<H", len(raw)), raw, struct.pack("<BB", FLOAT64, a.ndim),
                struct.pack(f"<{a.ndim}Q", *a.shape), struct.pack("<Q", a.nbytes), a.tobytes()]
    return b"".join(out)


def write_arrays(path: str | os.PathLike, entries: dict) -> Path:
    """Write an array file atomically (a temporary file renamed into place)."""
    from tribocosim.atomic import write_bytes

    return write_bytes(path, encode(entries))


def read_arrays(path: str | os.PathLike) -> dict:
    """Every entry of an array file (float arrays as numpy arrays, 0-d for scalars; texts as str).

    Raises
    ------
    ParameterError
        Naming the file, if it is not an array file or is truncated.
    """
    data = Path(path).read_bytes()
    try:
        return decode(data)
    except (struct.error, ValueError, UnicodeDecodeError) as exc:
        raise ParameterError(f"array file {str(path)!r} is malformed: {exc}") from exc


def decode(data: bytes) -> dict:
    """The entries of array-file bytes (see :func:`read_arrays`)."""
    if data[:8] != MAGIC:
        raise ValueError("it does not start with TCARRAYS")
    version, count = struct.unpack_from("<II", data, 8)
    if version != VERSION:
        raise ValueError(f"format version {version}; this code reads version {VERSION}")
    pos, out = 16, {}
    for _ in range(count):
        (n,) = struct.unpack_from("<H", data, pos)
        name = data[pos + 2:pos + 2 + n].decode("ascii")
        pos += 2 + n
        kind, ndim = struct.unpack_from("<BB", data, pos)
        pos += 2
        shape = struct.unpack_from(f"<{ndim}Q", data, pos)
        pos += 8 * ndim
        (size,) = struct.unpack_from("<Q", data, pos)
        pos += 8
        body = data[pos:pos + size]
        if len(body) != size:
            raise ValueError(f"entry {name!r} is truncated")
        pos += size
        if kind == TEXT:
            out[name] = body.decode("utf-8")
        elif kind == FLOAT64:
            if size != 8 * int(np.prod(shape, dtype=np.int64)):
                raise ValueError(f"entry {name!r} has {size} bytes for shape {shape}")
            out[name] = np.frombuffer(body, dtype="<f8").reshape(shape).astype(float)
        else:
            raise ValueError(f"entry {name!r} has kind {kind}")
    return out
