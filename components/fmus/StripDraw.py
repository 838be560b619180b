"""FMI 2.0 co-simulation adapter of the strip-draw model (pythonfmu): variables in, ``step``, outputs out.

No physics here: every number comes from :class:`tribocosim.components.stripdraw.model.StripDrawModel`,
and no FMI plumbing either: variable declaration from the parameter dataclass, error handling
(nothing escapes into pythonfmu 0.7.0; a rejected step is fmi2Discard with the state unchanged;
a bad parameter makes every step refused with a message naming it), FMU state and its
serialization, the exit guard and logging are :class:`tribocosim.components.fmus.adapter.ModelAdapter`'s
(see :mod:`tribocosim.components.fmus.adapter` for the measured pythonfmu bugs behind them).

Variables
    One parameter per field of :class:`~tribocosim.components.stripdraw.parameters.StripDrawParameters`
    (name, unit, description, default, range), then ``table_file``, the inputs
    ``normal_force`` [N] and ``grip_velocity`` [m/s], and the outputs (:data:`OUTPUTS`;
    ``table_clamp_count`` is an Integer).

``table_file``
    Used when ``friction_model = "table"``. A relative path is taken relative to the FMU's
    ``resources/`` folder, where the default table ``friction_table.npz`` is bundled; an absolute
    path is used as is. A missing or malformed table file is an initialization error naming the
    path. The table's content hash is part of the FMU state: a state is restored only into an
    instance that uses the same table.

``field_output``, ``field_output_interval``, ``field_input`` (the debris field, for maps and passes)
    Scalar outputs are the default and cost nothing else. When ``field_output`` names a file
    (``.npz``; a relative path is taken relative to the importer's working directory, folders are
    created), the FMU records the nodal fields at initialization and then after every step that
    ends at least ``field_output_interval`` seconds (0: every step) after the last recorded one,
    and writes them at ``fmi2Terminate`` (atomically: a temporary file renamed into place), the
    final state always included. A rolled-back step (``fmi2SetFMUstate``) drops the rows recorded
    after the restored time, so the file holds the accepted trajectory only. Keys: ``time`` (n,)
    [s], ``X`` (m,) material coordinates of the nodes [m], ``beta`` (n, m) [-], ``U`` (n, m)
    displacements [m], ``contact`` (n, m) the contact weight of each node (1 under the pad, 0
    outside), ``window`` (2,) the pad's position [a, a + L_T] in space [m] (node i is under the
    pad when a <= X_i + U_i <= a + L_T), ``metadata`` (JSON: the FMU's parameters).
    ``field_input`` names such a file: the strip then starts from the last ``beta`` row in it
    instead of ``beta_initial`` everywhere (a later pass over the same strip without cleaning,
    paper Fig. 2b); the file's ``X`` must be this FMU's mesh (same geometry and ``n_elements``).

Errors particular to this model
    NaN/inf/negative ``normal_force``, NaN/inf ``grip_velocity``, a table lookup outside the table
    under ``table_policy = "error"``, an implicit solve that does not converge: the step is
    discarded. Lookups outside the table's axes under ``table_policy = "clamp"`` (the default)
    are evaluated at the nearest edge and counted in the output ``table_clamp_count``
    (cumulative number of nodal lookups that were clamped).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from pythonfmu import Fmi2Causality, Fmi2Variability, String
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Status

from tribocosim.components.errors import ParameterError
from tribocosim.components.fmus.adapter import ModelAdapter, RealWithUnit, Var

#: Default table, bundled at ``resources/friction_table.npz`` by :mod:`tribocosim.components.fmus.build`.
DEFAULT_TABLE_FILE = "friction_table.npz"
#: Start values of the inputs: the paper's test at P_N = 10 MPa on the default 35 x 35 mm pad.
DEFAULT_NORMAL_FORCE = 12250.0  # N = 10 MPa x 0.035 m x 0.035 m
DEFAULT_GRIP_VELOCITY = 0.08

INPUTS = {
    "normal_force": Var("N", "normal force F_N on one pad (>= 0)", DEFAULT_NORMAL_FORCE),
    "grip_velocity": Var("m/s", "velocity of the grip pulling the strip", DEFAULT_GRIP_VELOCITY),
}
#: the model's OUTPUT_NAMES, in its order
OUTPUTS = {
    "pull_force": Var("N", "pull force on the whole strip (both faces); mu = pull_force / (2 normal_force)"),
    "friction_force": Var("N", "friction force F_S on the modelled face (sum of nodal friction forces)"),
    "mu_mean": Var("1", "mean friction coefficient F_S / F_N (Eq. 28)"),
    "sliding_distance": Var("m", "contact-weighted mean displacement of the strip under the pad"),
    "beta_mean": Var("1", "contact-weighted mean debris area fraction under the pad"),
    "beta_max": Var("1", "largest debris area fraction on the strip"),
    "contact_pressure": Var("Pa", "nominal contact pressure P = F_N / (tool_length tool_width)"),
    "grip_position": Var("m", "displacement of the grip"),
    "table_clamp_count": Var("1", "cumulative number of nodal table lookups outside the table (clamped)"),
}


class StripDraw(ModelAdapter):
    """The strip-draw FMU (one pad, one face; ``pull_force`` for the whole strip)."""

    author = "tribocosim"
    description = (
        "Flat strip-draw test with wear debris: 1D bar under a rigid pad, Coulomb interface law, "
        "debris transport and a friction table mu(P, v, beta) (FMI 2.0 co-simulation)"
    )
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=1.75, step_size=1e-3)
    INPUTS = INPUTS
    OUTPUTS = OUTPUTS
    INTEGER_OUTPUTS = ("table_clamp_count",)
    FINGERPRINT_NAMES = {"table_hash": "friction table hash"}

    def __init__(self, **kwargs):
        self._table_hash = None
        self._field = None  # FieldRecorder when field_output names a file
        super().__init__(**kwargs)

    def parameter_fields(self):
        from tribocosim.components.stripdraw.parameters import parameter_fields

        return parameter_fields()

    def register_extra_parameters(self) -> None:
        self._params["table_file"] = DEFAULT_TABLE_FILE
        self.register_variable(
            String(
                "table_file",
                causality=Fmi2Causality.parameter,
                variability=Fmi2Variability.fixed,
                description=(
                    "friction table (.npz) used when friction_model = table: a path relative to the "
                    "FMU's resources folder, or absolute [text]"
                ),
                getter=lambda: self._params["table_file"],
                setter=lambda v: self.set_parameter("table_file", str, v),
            )
        )
        texts = {
            "field_output": "file (.npz) to write the nodal fields time, X, beta, U, contact to at terminate; "
            "empty: none (relative paths: to the working directory)",
            "field_input": "field file (.npz, from field_output) whose last beta row is the initial debris field "
            "(a later pass); empty: beta_initial everywhere",
        }
        for name, text in texts.items():
            self._params[name] = ""
            self.register_variable(
                String(
                    name,
                    causality=Fmi2Causality.parameter,
                    variability=Fmi2Variability.fixed,
                    description=f"{text} [text]",
                    getter=lambda n=name: self._params[n],
                    setter=lambda v, n=name: self.set_parameter(n, str, v),
                )
            )
        self._params["field_output_interval"] = 0.0
        self.register_variable(
            RealWithUnit(
                "field_output_interval",
                "s",
                low=0.0,
                causality=Fmi2Causality.parameter,
                variability=Fmi2Variability.fixed,
                description="least time between two recorded rows of field_output; 0: every step [s]",
                getter=lambda: self._params["field_output_interval"],
                setter=lambda v: self.set_parameter("field_output_interval", float, v),
            )
        )

    def make_model(self, parameters: dict):
        """Validate the parameters, load the table (if used) and build the model."""
        from tribocosim.components.stripdraw.friction import make_friction_law
        from tribocosim.components.stripdraw.model import StripDrawModel
        from tribocosim.components.stripdraw.parameters import StripDrawParameters
        from tribocosim.components.stripdraw.table import read_table

        params = StripDrawParameters(**{f.name: parameters[f.name] for f in self._fields})
        self._table_hash = None
        table = None
        if params.friction_model == "table":
            path = self.table_path()
            table = read_table(path)
            self.log(
                f"friction table {path}: provenance {table.provenance}, "
                f"content hash {table.metadata.get('content_hash')}",
                Fmi2Status.ok,
            )
            self._table_hash = table.metadata.get("content_hash")
        beta_field = None
        if parameters.get("field_input"):
            import numpy as np

            from tribocosim.components.stripdraw.mesh import BarMesh

            X, beta_field = read_field_input(parameters["field_input"])
            mine = BarMesh.build(params).X
            if X.shape != mine.shape or not np.allclose(X, mine, rtol=0, atol=1e-12):
                raise ParameterError(
                    f"field_input = {parameters['field_input']!r} was written for another mesh "
                    f"({X.size} nodes over [{X[0]:g}, {X[-1]:g}] m; this strip has {mine.size} nodes over "
                    f"[{mine[0]:g}, {mine[-1]:g}] m): use the same geometry and n_elements"
                )
        return StripDrawModel(params, make_friction_law(params, table), beta_field=beta_field)

    # ------------------------------------------------------------------ field output
    def after_initialization(self) -> None:
        self._field = None
        path = self._params.get("field_output", "")
        if path:
            interval = float(self._params["field_output_interval"])
            if not interval >= 0:
                raise ParameterError(f"field_output_interval = {interval!r} s must be >= 0")
            self._field = FieldRecorder(Path(path), interval, self._model, dict(self._params))

    def after_step(self) -> None:
        if self._field is not None:
            self._field.record(self._model)

    def after_restore(self) -> None:
        if self._field is not None and self._model is not None:
            self._field.truncate(self._model.time)

    def on_terminate(self) -> None:
        if self._field is not None:
            path = self._field.write(self._model)
            self.log(f"field_output: {len(self._field.times)} rows written to {path}", Fmi2Status.ok)

    def fingerprint(self) -> dict:
        return {"table_hash": None if self._model is None else self._table_hash}

    def table_path(self) -> Path:
        """``table_file`` resolved against the FMU's resources folder."""
        path = Path(self._params["table_file"])
        if not path.is_absolute():
            path = Path(self.resources or ".") / path
        return path


def read_field_input(path) -> tuple:
    """(X, last beta row) of a ``field_output`` file; ParameterError naming the file if unusable."""
    import numpy as np

    try:
        with np.load(path, allow_pickle=False) as data:
            X, beta = np.array(data["X"], dtype=float), np.array(data["beta"], dtype=float)
    except (OSError, KeyError, ValueError) as exc:
        raise ParameterError(f"field_input = {str(path)!r} cannot be read as a field_output file: {exc}") from exc
    if beta.ndim != 2 or beta.shape[0] < 1 or beta.shape[1] != X.size:
        raise ParameterError(f"field_input = {str(path)!r}: beta has shape {beta.shape}, X has {X.size} nodes")
    return X, beta[-1].copy()


class FieldRecorder:
    """Rows of nodal fields (beta, U, contact) at the recorded times, written as one ``.npz``.

    I/O only (no physics): the strip-draw model's :meth:`fields` are copied at initialization,
    after steps at least ``interval`` seconds apart, and at the end.
    """

    def __init__(self, path: Path, interval: float, model, parameters: dict):
        self.path, self.interval = path, interval
        self.X = model.mesh.X.copy()
        self.window = (float(model.mesh.window_lo), float(model.mesh.window_hi))
        self.parameters = parameters
        self.times: list[float] = []
        self.rows: list[tuple] = []
        self.record(model, force=True)

    def record(self, model, force: bool = False) -> None:
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

    def write(self, model=None) -> Path:
        """Write the file (atomically), with the model's current state as the last row."""
        import numpy as np

        if model is not None and (not self.times or model.time > self.times[-1]):
            self.record(model, force=True)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.path.with_name(f".{self.path.name}.{os.getpid()}.partial")
        beta, U, contact = (np.array([r[i] for r in self.rows]) for i in range(3))
        with open(tmp, "wb") as fh:
            np.savez(
                fh, time=np.array(self.times), X=self.X, beta=beta, U=U, contact=contact,
                window=np.array(self.window), metadata=np.array(json.dumps(self.parameters, sort_keys=True)),
            )  # fmt: skip
        os.replace(tmp, self.path)
        return self.path
