"""The nodal-field file of the strip (``field_output`` / ``field_input``): its format and its Python reader.

Written by the StripDraw FMU (native or Python, through the one writer of the native core, ``tc_fields.c``,
which :class:`FieldRecorder` binds), read by the next pass (``field_input``: its last beta row is the strip's
initial debris field), the plots and any tool that reads CSV.

File layout (CSV, numbers with 17 significant digits, so they read back exactly)::

    # tribocosim strip-draw nodal fields, format 1
    # X [m]: X_0,X_1,...,X_M                  material coordinates of the M + 1 nodes
    # window [m]: a,b                         the pad's place in space: node i is under the pad when
                                              a <= X_i + U_i <= b
    # parameter NAME: VALUE                   one line per FMU parameter
    time,beta_0,...,beta_M,U_0,...,U_M,contact_0,...,contact_M
    0,0,...                                   one row per recorded time [s]: the debris area fraction,
                                              the displacements [m] and the contact weights (1 under the pad,
                                              0 outside) of the nodes

In pandas: ``pandas.read_csv(path, comment="#")``; :func:`read_fields` gives every array.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tribocosim.errors import ParameterError
from tribocosim.components.native.toolchain.library import VP, core, ptr

HEADER = "# tribocosim strip-draw nodal fields, format 1"
QUANTITIES = ("beta", "U", "contact")


def read_fields(path) -> dict:
    """Every array of a field file: ``time`` (n,), ``X`` (m,), ``beta``, ``U``, ``contact`` (n, m), ``window``
    (2,) and ``metadata`` (parameter name -> value text); ParameterError naming the file if it is not one."""
    try:
        lines = Path(path).read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise ParameterError(f"field file {str(path)!r} cannot be read: {exc}") from exc
    if not lines or lines[0] != HEADER:
        raise ParameterError(f"field file {str(path)!r} is not a field file (its first line is not {HEADER!r})")
    comments = {}
    metadata = {}
    k = 1
    while k < len(lines) and lines[k].startswith("#"):
        key, _, value = lines[k][2:].partition(": ")
        if key.startswith("parameter "):
            metadata[key[len("parameter "):]] = value
        else:
            comments[key] = value
        k += 1
    try:
        X = np.array([float(x) for x in comments["X [m]"].split(",")])
        window = np.array([float(x) for x in comments["window [m]"].split(",")])
        rows = np.array([[float(x) for x in line.split(",")] for line in lines[k + 1:] if line], dtype=float)
    except (KeyError, ValueError) as exc:
        raise ParameterError(f"field file {str(path)!r} is malformed: {exc}") from exc
    m = X.size
    rows = rows.reshape(-1, 1 + 3 * m)
    out = {"time": rows[:, 0].copy(), "X": X, "window": window, "metadata": metadata}
    for q, name in enumerate(QUANTITIES):
        out[name] = rows[:, 1 + q * m:1 + (q + 1) * m].copy()
    return out


def read_initial_beta(path, X: np.ndarray) -> np.ndarray:
    """The last beta row of a field file, checked against the mesh ``X`` it will start (a later pass): the native
    reader the FMU uses. ParameterError if the file cannot be read or was written for another mesh."""
    X = np.ascontiguousarray(X, dtype=float)
    beta = np.empty(X.size)
    c = core()
    c.call(c.lib.tc_field_read_initial_beta, str(path).encode(), X.size, ptr(X), ptr(beta))
    return beta


@dataclass
class FieldRecorder:
    """Rows of nodal fields (beta, U, contact) at the recorded times, written as one field file by the native
    recorder (the interval rule, the rows dropped by a rolled-back step, the atomic write: ``tc_fields.h``)."""

    path: Path
    handle: VP

    @classmethod
    def start(cls, path, interval: float, model, parameters: dict) -> "FieldRecorder":
        """A recorder with the model's initial fields as its first row."""
        if not interval >= 0:
            raise ParameterError(f"field_output_interval = {interval!r} s must be >= 0")
        c = core()
        X = np.ascontiguousarray(model.mesh.X, dtype=float)
        window = np.array([model.mesh.window_lo, model.mesh.window_hi])
        lines = "".join(f"{k}: {v}\n" for k, v in sorted(parameters.items()))
        handle = VP()
        c.call(c.lib.tc_field_recorder_create, str(path).encode(), float(interval), X.size, ptr(X), ptr(window),
               lines.encode(), ctypes.byref(handle))
        rec = cls(Path(path), handle)
        rec.record(model, force=True)
        return rec

    def __del__(self):
        if getattr(self, "handle", None):
            core().lib.tc_field_recorder_free(self.handle)
            self.handle = None

    @staticmethod
    def _rows(model):
        f = model.fields()
        return [np.ascontiguousarray(f[k]) for k in QUANTITIES]

    def record(self, model, force: bool = False) -> None:
        """Record the model's fields if the interval has passed since the last row (or ``force``)."""
        c = core()
        c.call(c.lib.tc_field_recorder_record, self.handle, float(model.time), *(ptr(a) for a in self._rows(model)),
               int(force))

    def truncate(self, t: float) -> None:
        """Drop the rows recorded after time ``t`` (a rolled-back step)."""
        core().lib.tc_field_recorder_truncate(self.handle, float(t))

    def finish(self, model=None) -> str:
        """Write the file with the model's current state as the last row; returns a log line."""
        c = core()
        if model is not None:
            c.call(c.lib.tc_field_recorder_finish, self.handle, float(model.time),
                   *(ptr(a) for a in self._rows(model)))
        else:
            c.call(c.lib.tc_field_recorder_write, self.handle)
        return f"field_output: {c.lib.tc_field_recorder_rows(self.handle)} rows written to {self.path}"
