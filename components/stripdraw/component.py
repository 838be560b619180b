"""The strip-draw component: its FMU variables, files, resources and how the model is made.

The one description of the StripDraw FMU, the scene checks and the monolithic reference
(:mod:`tribocosim.components.description`).

Variables
    One parameter per field of :class:`~tribocosim.components.stripdraw.parameters.StripDrawParameters`,
    then the FMU's files (:class:`StripDrawFiles`), the inputs ``normal_force`` [N] and
    ``grip_velocity`` [m/s], and the outputs (:data:`OUTPUTS`, the model's ``OUTPUT_NAMES`` in order;
    both declared in :mod:`tribocosim.components.stripdraw.ports`;
    ``table_clamp_count`` is an Integer). The native FMI 3.0 FMU also outputs the nodal fields
    (:data:`FIELDS`: ``beta``, ``U``, ``contact``) as Float64 arrays of ``n_nodes = n_elements + 1``
    values; ``n_elements`` and ``n_nodes`` are its structural parameters (setting either sets both).

``table_file``
    Used when ``friction_model = "table"``. A relative path is taken relative to the FMU's
    ``resources/`` folder, where the default table ``friction_table.npz`` is bundled; an absolute
    path is used as is. The native FMU reads a table ``X.npz`` in its resource form ``X.tca``
    (:func:`tribocosim.components.stripdraw.table.write_table_resource`; the build converts the bundled
    table). A missing or malformed table file is an initialization error naming the path. The table's
    content hash is part of the FMU state: a state is restored only into an instance that uses the same
    table.

``field_output``, ``field_output_interval``, ``field_input`` (the debris field, for maps and passes)
    When ``field_output`` names a file (relative: to the importer's working directory), the FMU
    records the nodal fields at initialization and then after every step that ends at least
    ``field_output_interval`` seconds after the last recorded row (0: every step), and writes them
    at ``fmi2Terminate`` (atomically, the final state always included; the format:
    :mod:`tribocosim.components.native.resource_io.field_file`); a rolled-back step drops the rows after the
    restored time. ``field_input`` names such
    a file: the strip starts from its last ``beta`` row (a later pass over the same strip without
    cleaning, paper Fig. 2b); it must have been written for this mesh.

Input derivatives (native FMI 2.0 FMU: ``canInterpolateInputs = true``)
    ``fmi2SetRealInputDerivatives`` (orders 1 and 2) gives ``normal_force`` and ``grip_velocity`` as
    polynomials over the next step (the model's ``step(..., derivatives=...)``): with ``internal_step`` > 0
    friction and debris then follow the inputs within a communication step and Jacobi or Gauss-Seidel with
    extrapolation 1 are second-order. The derivatives apply to the next ``fmi2DoStep`` only and are zero
    again after it or after ``fmi2SetReal`` of the input.

Errors particular to this model
    NaN/inf/negative ``normal_force``, NaN/inf ``grip_velocity``, a table lookup outside the table
    under ``table_policy = "error"``, an implicit solve that does not converge: the step is
    discarded. Lookups outside the table's axes under ``table_policy = "clamp"`` (the default)
    are evaluated at the nearest edge and counted in ``table_clamp_count``.
"""

from __future__ import annotations

from pathlib import Path

from tribocosim.components.description import ArraySize, Built, Component, Native, Port
from tribocosim.errors import ParameterError
from tribocosim.components.params import (BOUND_RTOL, bound_text, outside_text, param, parameters, validate_fields,
                                         within_bounds)
from tribocosim.components.stripdraw.friction_floor import MU_FLOOR
from tribocosim.components.stripdraw.parameters import StripDrawParameters
from tribocosim.components.stripdraw.ports import (  # noqa: F401 - the declaration's public names
    DEFAULT_GRIP_VELOCITY, DEFAULT_NORMAL_FORCE, INPUTS, OUTPUTS)

#: The shipped friction table (package data), bundled at the root of the FMU's ``resources/``.
TABLE_RESOURCE = ("tribocosim.models", "friction_table.npz")
# INPUTS and OUTPUTS (units, start values, the ranges the model is built for) are in ports.py, which the binding
# reads too


@parameters
class StripDrawFiles:
    """The StripDraw FMU's files (parameters that are not the model's)."""

    table_file: str = param(
        TABLE_RESOURCE[1], "", "friction table (.npz) used when friction_model = table: a path relative to the "
        "FMU's resources folder, or absolute", text=True)
    field_output: str = param(
        "", "", "file (CSV) to write the nodal fields time, X, beta, U, contact to at terminate; empty: none "
        "(relative paths: to the working directory)", text=True)
    field_output_interval: float = param(0.0, "s", "least time between two recorded rows of field_output; "
                                         "0: every step", 0.0, None)
    field_input: str = param(
        "", "", "field file (CSV, from field_output) whose last beta row is the initial debris field (a later "
        "pass); empty: beta_initial everywhere", text=True)

    def __post_init__(self) -> None:
        validate_fields(self)

    def table_path(self, resources: Path) -> Path:
        """``table_file`` resolved against the resources folder (absolute paths as they are)."""
        path = Path(self.table_file)
        return path if path.is_absolute() else Path(resources) / path


#: the nodal fields (as in field_output), array outputs of the FMI 3.0 FMU (one value per node)
FIELDS = (
    Port("beta", "1", "debris area fraction at the nodes"),
    Port("U", "m", "displacement of the nodes"),
    Port("contact", "1", "contact weight of the nodes (1 under the pad, 0 outside)"),
)


def _table(params: StripDrawParameters, files: StripDrawFiles, resources: Path):
    """The friction table the parameters ask for (None unless friction_model = table)."""
    from tribocosim.components.stripdraw.table import read_table

    return read_table(files.table_path(resources)) if params.friction_model == "table" else None


def build(params: StripDrawParameters, files: StripDrawFiles, resources: Path) -> Built:
    """The model: the table loaded (if used), the initial debris field read (if given)."""
    from tribocosim.components.native.resource_io.field_file import read_initial_beta
    from tribocosim.components.stripdraw.friction import make_friction_law
    from tribocosim.components.stripdraw.model import StripDrawModel

    table = _table(params, files, resources)
    law = make_friction_law(params, table)
    model = StripDrawModel(params, law)
    if files.field_input:  # a later pass: the strip starts from the last beta row of an earlier one
        model = StripDrawModel(params, law, beta_field=read_initial_beta(files.field_input, model.mesh.X))
    if table is None:
        return Built(model, {"friction table hash": None})
    digest = table.metadata.get("content_hash")
    note = f"friction table {files.table_path(resources)}: provenance {table.provenance}, content hash {digest}"
    return Built(model, {"friction table hash": digest}, [note])


def convert_resource(source: Path, folder: Path) -> Path:
    """The friction table's resource form for the native FMU (``friction_table.npz`` -> ``friction_table.tca``)."""
    from tribocosim.components.stripdraw.table import RESOURCE_SUFFIX, write_table_resource

    return write_table_resource(source, Path(folder) / (Path(source).stem + RESOURCE_SUFFIX))


def law_facts(params: StripDrawParameters, files: StripDrawFiles, resources: Path) -> dict:
    """What the scene checks need of the friction law the parameters make: ``table_error`` (why the table cannot be
    used, or None), ``law_error`` (why the law cannot be made), ``cap`` (its cap of beta, Eq. 24,
    ``beta_threshold``), ``pressure`` and ``velocity_max`` (the table's pressure axis [Pa] and largest velocity
    [m/s]). Making the law reads the table and evaluates the law natively, so the facts are remembered in the cache
    for these parameters while the table file is unchanged (:func:`tribocosim.components.native.toolchain.digests.
    memo`)."""
    from tribocosim.components.native.toolchain.digests import memo

    path = files.table_path(resources) if params.friction_model == "table" else None

    def compute() -> dict:
        from tribocosim.components.stripdraw.friction import make_friction_law

        facts = {"table_error": None, "law_error": None, "cap": None, "pressure": None, "velocity_max": None}
        table = None
        if path is not None:
            try:
                table = _table(params, files, resources)
            except Exception as exc:  # noqa: BLE001 - any unreadable table is a scene problem
                facts["table_error"] = f"friction table {path} cannot be used: {exc}"
                return facts
            facts["pressure"] = [float(table.pressure[0]), float(table.pressure[-1])]
            facts["velocity_max"] = float(table.velocity[-1])
        try:
            facts["cap"] = float(make_friction_law(params, table).beta_threshold)
        except ParameterError as exc:
            facts["law_error"] = str(exc)
        return facts

    return memo(f"stripdraw law {params!r} {path}", [path] if path is not None else [], compute)


def check(params: StripDrawParameters, files: StripDrawFiles, resources: Path):
    """Scene problems only the model sees (the table, the field file, the cap), and the input limits
    the table sets: the normal force's nominal pressure and the grip speed must lie on its axes."""
    problems, limits = [], {}
    facts = law_facts(params, files, resources)
    if facts["table_error"]:
        problems.append(("table_file", facts["table_error"]))
    if files.field_input and not Path(files.field_input).is_file():
        problems.append(("field_input", f"field file {files.field_input} does not exist (the field_output of an "
                                        "earlier pass)"))
    if facts["law_error"]:
        problems.append(("", facts["law_error"]))
    cap = facts["cap"]
    if params.beta_threshold > 0:
        cap = params.beta_threshold
    if cap is not None and params.beta_initial > cap:
        problems.append(("beta_initial", f"beta_initial = {params.beta_initial!r} exceeds the cap of beta, {cap:.6g} "
                                         "(Eq. 24; from the friction law or beta_threshold)"))
    if facts["pressure"] is not None:
        lo, hi = facts["pressure"]
        vmax = facts["velocity_max"]
        pad = f"{params.tool_length * 1e3:g} x {params.tool_width * 1e3:g} mm pad"

        def force_limit(force: float, label: str, instance: str) -> str | None:
            pressure = params.pressure(force)
            if within_bounds(pressure, lo, hi):  # on an axis end to round-off: on the axis (BOUND_RTOL)
                return None
            shown = outside_text(pressure / 1e6, lo / 1e6, hi / 1e6)
            return (f"{label} on the {pad} of '{instance}', is a nominal pressure of {shown} MPa, outside the "
                    f"friction table's pressure axis [{bound_text(lo / 1e6)}, {bound_text(hi / 1e6)}] MPa (by more "
                    f"than {BOUND_RTOL:g} of its end)")

        def velocity_limit(v: float, label: str, instance: str) -> str | None:
            if within_bounds(abs(v), None, vmax):
                return None
            return (f"{label} is above the friction table's velocity axis (up to {bound_text(vmax)} m/s) of "
                    f"'{instance}' (by more than {BOUND_RTOL:g} of its end)")

        limits = {"normal_force": force_limit, "grip_velocity": velocity_limit}
    return problems, limits


def input_limits(params: StripDrawParameters) -> dict:
    """The ranges the inputs can take whatever drives them: a nominal pressure F_N / (L_T w_T) at most the
    hardness (above it every asperity is flattened: no strip-draw contact), and a grip speed below the bar's wave
    speed sqrt(E / rho) (its elastic waves carry the pull to the pad; the FMU refuses a faster grip)."""

    def force_limit(force: float, label: str, instance: str) -> str | None:
        pressure = params.pressure(force)
        if within_bounds(pressure, None, params.hardness):
            return None
        return (f"{label} on the {params.tool_length * 1e3:g} x {params.tool_width * 1e3:g} mm pad of '{instance}' is "
                f"a nominal pressure of {outside_text(pressure, None, params.hardness)} Pa, above the strip's hardness "
                f"{bound_text(params.hardness)} Pa "
                f"(the largest normal force is {params.normal_force(params.hardness):.6g} N): no strip-draw contact")

    def velocity_limit(v: float, label: str, instance: str) -> str | None:
        if abs(v) < params.wave_speed:
            return None
        return (f"{label} is not below the wave speed sqrt(E / rho) = {params.wave_speed:.6g} m/s of the strip of "
                f"'{instance}': its elastic waves cannot carry a faster pull to the pad")

    return {"normal_force": force_limit, "grip_velocity": velocity_limit}


def observer(model, files: StripDrawFiles, values: dict):
    """The field recorder when ``field_output`` names a file, else None."""
    if not files.field_output:
        return None
    from tribocosim.components.native.resource_io.field_file import FieldRecorder

    return FieldRecorder.start(files.field_output, files.field_output_interval, model, values)


COMPONENT = Component(
    name="stripdraw",
    model_identifier="StripDraw",
    summary=("Flat strip-draw test with wear debris: 1D bar under a rigid pad, Coulomb interface law, "
             "debris transport and a friction table mu(P, v, beta) (FMI 2.0 co-simulation)"),
    parameters=StripDrawParameters,
    files=StripDrawFiles,
    inputs=INPUTS,
    outputs=OUTPUTS,
    resources=(TABLE_RESOURCE,),
    build=build,
    check=check,
    input_limits=input_limits,
    observer=observer,
    native=Native(prefix="tc_stripdraw",
                  sources=("core/tc_stripdraw.c", "core/tc_stripdraw_state.c", "core/tc_galpha.c", "core/tc_explicit.c",
                           "core/tc_kernels.c", "core/tc_step_kernels.c", "core/tc_step_kernels_avx.c", "core/tc_cpu.c",
                           "core/tc_debris.c", "core/tc_friction.c", "core/tc_table.c", "core/tc_table_lookup.c",
                           "core/tc_pchip.c", "core/tc_node_friction.c", "resource_io/tc_table_file.c",
                           "resource_io/tc_sha256.c", "resource_io/tc_arrays.c", "resource_io/tc_fields.c",
                           "fmi/tc_stripdraw_fmu.c"),
                  params_header="tc_stripdraw_params.h", arrays=FIELDS,
                  array_size=ArraySize("n_nodes", "n_elements", 1, "number of nodes of the bar, n_elements + 1"),
                  interpolates_inputs=True, convert_resource=convert_resource,
                  resource_parameters=("table_file",),
                  constants=(("mu_floor", MU_FLOOR, "the documented floor of mu (friction_floor.MU_FLOOR): a lookup "
                              "below it is warned"),)),
    default_experiment=(0.0, 1.75, 1e-3),
)
