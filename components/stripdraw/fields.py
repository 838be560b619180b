"""The nodal-field file of the strip (``field_output`` / ``field_input``): the one module that writes and reads it.

Written by the StripDraw FMU (the Python one through :class:`FieldRecorder`, the native one in C,
byte layout as here), read by the next pass (``field_input``: its last beta row is the strip's
initial debris field), the plots and the monolithic reference.

File layout (numpy ``.npz``, read with ``allow_pickle=False``):

============  =============  ==================================================================
key           shape          meaning
============  =============  ==================================================================
``time``      (n,)           recorded times [s]
``X``         (m,)           material coordinates of the nodes [m]
``beta``      (n, m)         debris area fraction [-]
``U``         (n, m)         displacements [m]
``contact``   (n, m)         contact weight of each node (1 under the pad, 0 outside)
``window``    (2,)           the pad's position [a, a + L_T] in space [m] (node i is under the pad
                             when a <= X_i + U_i <= a + L_T)
``metadata``  0-d str        JSON: the FMU's parameters
============  =============  ==================================================================
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tribocosim.components.errors import ParameterError

KEYS = ("time", "X", "beta", "U", "contact", "window", "metadata")


def write_fields(path, time, X, beta, U, contact, window, metadata: dict) -> Path:
    """Write a field file atomically (a temporary file renamed into place); folders are created."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.partial")
    with open(tmp, "wb") as fh:
        np.savez(
            fh, time=np.asarray(time, float), X=np.asarray(X, float), beta=np.asarray(beta, float),
            U=np.asarray(U, float), contact=np.asarray(contact, float), window=np.asarray(window, float),
            metadata=np.array(json.dumps(metadata, sort_keys=True)),
        )  # fmt: skip
    os.replace(tmp, path)
    return path


def read_fields(path) -> dict:
    """Every array of a field file (``metadata`` as a dict); ParameterError naming the file if unusable."""
    try:
        with np.load(path, allow_pickle=False) as data:
            out = {k: np.array(data[k]) for k in data.files}
    except Exception as exc:  # noqa: BLE001 - any file numpy cannot read as ours
        raise ParameterError(f"field file {str(path)!r} cannot be read: {exc}") from exc
    missing = [k for k in ("time", "X", "beta") if k not in out]
    if missing:
        raise ParameterError(f"field file {str(path)!r} has no {', '.join(missing)}")
    if "metadata" in out:
        out["metadata"] = json.loads(str(out["metadata"]))
    return out


def read_initial_beta(path, X: np.ndarray) -> np.ndarray:
    """The last beta row of a field file, checked against the mesh ``X`` it will start (a later pass).

    Raises
    ------
    ParameterError
        If the file cannot be read, or was written for another mesh (other geometry or n_elements).
    """
    try:
        with np.load(path, allow_pickle=False) as data:
            Xf, beta = np.array(data["X"], dtype=float), np.array(data["beta"], dtype=float)
    except Exception as exc:  # noqa: BLE001 - any file numpy cannot read as ours (fuzzed: BadZipFile, EOFError...)
        raise ParameterError(f"field_input = {str(path)!r} cannot be read as a field_output file: {exc}") from exc
    if beta.ndim != 2 or beta.shape[0] < 1 or beta.shape[1] != Xf.size:
        raise ParameterError(f"field_input = {str(path)!r}: beta has shape {beta.shape}, X has {Xf.size} nodes")
    if Xf.shape != X.shape or not np.allclose(Xf, X, rtol=0, atol=1e-12):
        raise ParameterError(
            f"field_input = {str(path)!r} was written for another mesh "
            f"({Xf.size} nodes over [{Xf[0]:g}, {Xf[-1]:g}] m; this strip has {X.size} nodes over "
            f"[{X[0]:g}, {X[-1]:g}] m): use the same geometry and n_elements"
        )
    return beta[-1].copy()


@dataclass
class FieldRecorder:
    """Rows of nodal fields (beta, U, contact) at the recorded times, written as one field file.

    I/O only (no physics): the model's :meth:`fields` are copied at the start, after steps at
    least ``interval`` seconds after the last recorded row, and at the end. A rolled-back step
    (:meth:`truncate`) drops the rows after the restored time, so the file holds the accepted
    trajectory only.
    """

    path: Path
    interval: float
    X: np.ndarray
    window: tuple[float, float]
    parameters: dict

    @classmethod
    def start(cls, path, interval: float, model, parameters: dict) -> "FieldRecorder":
        """A recorder with the model's initial fields as its first row."""
        if not interval >= 0:
            raise ParameterError(f"field_output_interval = {interval!r} s must be >= 0")
        rec = cls(Path(path), float(interval), model.mesh.X.copy(),
                  (float(model.mesh.window_lo), float(model.mesh.window_hi)), dict(parameters))
        rec.times, rec.rows = [], []
        rec.record(model, force=True)
        return rec

    def record(self, model, force: bool = False) -> None:
        """Record the model's fields if ``interval`` has passed since the last row (or ``force``)."""
        t = float(model.time)
        if not force and self.times and t < self.times[-1] + self.interval * (1.0 - 1e-9):
            return
        f = model.fields()
        self.times.append(t)
        self.rows.append((f["beta"], f["U"], f["contact"]))

    def truncate(self, t: float) -> None:
        """Drop the rows recorded after time ``t`` (a rolled-back step)."""
        while self.times and self.times[-1] > t * (1.0 + 1e-12) + 1e-15:
            self.times.pop()
            self.rows.pop()

    def finish(self, model=None) -> str:
        """Write the file with the model's current state as the last row; returns a log line."""
        if model is not None and (not self.times or model.time > self.times[-1]):
            self.record(model, force=True)
        beta, U, contact = (np.array([r[i] for r in self.rows]) for i in range(3))
        write_fields(self.path, self.times, self.X, beta, U, contact, self.window, self.parameters)
        return f"field_output: {len(self.times)} rows written to {self.path}"
