"""FMI 2.0 co-simulation adapter of the strip-draw model (pythonfmu): variables in, ``step``, outputs out.

No physics here: every number comes from :class:`components.stripdraw.model.StripDrawModel`,
and no FMI plumbing either: variable declaration from the parameter dataclass, error handling
(nothing escapes into pythonfmu 0.7.0; a rejected step is fmi2Discard with the state unchanged;
a bad parameter makes every step refused with a message naming it), FMU state and its
serialization, the exit guard and logging are :class:`components.fmus.adapter.ModelAdapter`'s
(see :mod:`components.fmus.adapter` for the measured pythonfmu bugs behind them).

Variables
    One parameter per field of :class:`~components.stripdraw.parameters.StripDrawParameters`
    (name, unit, description, default, range), then ``table_file``, the inputs
    ``normal_force`` [N] and ``grip_velocity`` [m/s], and the outputs (:data:`OUTPUTS`;
    ``table_clamp_count`` is an Integer).

``table_file``
    Used when ``friction_model = "table"``. A relative path is taken relative to the FMU's
    ``resources/`` folder, where the default table ``friction_table.npz`` is bundled; an absolute
    path is used as is. A missing or malformed table file is an initialization error naming the
    path. The table's content hash is part of the FMU state: a state is restored only into an
    instance that uses the same table.

Errors particular to this model
    NaN/inf/negative ``normal_force``, NaN/inf ``grip_velocity``, a table lookup outside the table
    under ``table_policy = "error"``, an implicit solve that does not converge: the step is
    discarded. Lookups outside the table's axes under ``table_policy = "clamp"`` (the default)
    are evaluated at the nearest edge and counted in the output ``table_clamp_count``
    (cumulative number of nodal lookups that were clamped).
"""

from __future__ import annotations

from pathlib import Path

from pythonfmu import Fmi2Causality, Fmi2Variability, String
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Status

from components.fmus.adapter import ModelAdapter, Var

#: Default table, bundled at ``resources/friction_table.npz`` by :mod:`components.fmus.build`.
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
        super().__init__(**kwargs)

    def parameter_fields(self):
        from components.stripdraw.parameters import parameter_fields

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

    def make_model(self, parameters: dict):
        """Validate the parameters, load the table (if used) and build the model."""
        from components.stripdraw.friction import make_friction_law
        from components.stripdraw.model import StripDrawModel
        from components.stripdraw.parameters import StripDrawParameters
        from components.stripdraw.table import read_table

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
        return StripDrawModel(params, make_friction_law(params, table))

    def fingerprint(self) -> dict:
        return {"table_hash": None if self._model is None else self._table_hash}

    def table_path(self) -> Path:
        """``table_file`` resolved against the FMU's resources folder."""
        path = Path(self._params["table_file"])
        if not path.is_absolute():
            path = Path(self.resources or ".") / path
        return path
