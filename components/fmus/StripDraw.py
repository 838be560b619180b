"""FMI 2.0 co-simulation adapter of the strip-draw model (pythonfmu): variables in, ``step``, outputs out.

No physics here: every number comes from :class:`components.stripdraw.model.StripDrawModel`.
The FMU's variables are generated from the fields of
:class:`~components.stripdraw.parameters.StripDrawParameters` (name, unit, description, default,
range), so the two cannot drift; on top of those come ``table_file``, the inputs and the outputs.

Life cycle
    ``__init__`` only registers variables (pythonfmu instantiates the class at build time).
    ``exit_initialization_mode`` validates the parameters, loads the friction table (once) and
    builds the model. ``do_step`` calls ``model.step(step_size, inputs)``.

``table_file``
    Used when ``friction_model = "table"``. A relative path is taken relative to the FMU's
    ``resources/`` folder, where the default table ``friction_table.npz`` is bundled; an absolute
    path is used as is.

Errors
    pythonfmu 0.7.0 turns a Python exception escaping an FMI callback into fmi2Fatal, and the
    instance is then broken beyond repair: terminating or freeing it and carrying on crashed the
    host process (segfault, measured with fmpy). So nothing escapes this adapter; the only failure status pythonfmu can return
    otherwise is fmi2Discard, from a ``do_step`` that returns False. Hence:

    - NaN/inf/negative ``normal_force``, NaN/inf ``grip_velocity``, a step size <= 0, a table
      lookup outside the table under ``table_policy = "error"``, an implicit solve that does not
      converge: ``fmi2DoStep`` returns fmi2Discard, a message (status error) names the variable
      and its value, and the FMU state is unchanged: the master may fix the input, shorten the
      step, or restore a state, and retry.
    - Parameters out of range, an unknown ``friction_model``/``integrator``/``table_policy``, a
      missing or malformed table file (the message names the path): detected in
      ``fmi2ExitInitializationMode``, which logs the error (status error) but, for the reason
      above, cannot fail; the instance is then unusable and every ``fmi2DoStep`` returns
      fmi2Discard with the same message. The same holds for a state that cannot be restored.
    - pythonfmu 0.7.0 passes log messages to the importer only when logging is on (fmpy:
      ``--debug-logging``), so errors are also written to stderr.
    - Lookups outside the table's axes under ``table_policy = "clamp"`` (the default) are
      evaluated at the nearest edge and counted in the output ``table_clamp_count``
      (cumulative number of nodal lookups that were clamped).
    - A parameter set after initialization (they are all ``fixed``) is ignored with a warning.

FMU state
    ``fmi2GetFMUstate`` captures the parameters, inputs, outputs and the model's full state
    (its numpy arrays included); ``fmi2SerializeFMUstate`` writes it with
    :mod:`components.fmus.statecodec` instead of pythonfmu's JSON. Restoring a state continues
    the run bit-identically, in the same instance or in another instance of the same FMU.

Imports
    In an FMU the ``components`` package is the copy bundled in ``resources/`` (pythonfmu puts
    that folder first on ``sys.path``). In a Python host that has already imported
    ``components`` (e.g. a test that also runs the pure model), Python reuses that package; the
    adapter logs which one it uses.

Process exit
    :mod:`components.fmus.exitguard` works around a use-after-free in pythonfmu 0.7.0's library
    destructor that made Python hosts abort at exit after freeing the FMU.
"""

from __future__ import annotations

import dataclasses
import os
import sys
from pathlib import Path
from xml.etree.ElementTree import Element, SubElement

from pythonfmu import Fmi2Causality, Fmi2Initial, Fmi2Slave, Fmi2Variability, Integer, Real, String
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Status

from components.errors import TableError, TribocosimError
from components.fmus import statecodec
from components.fmus.exitguard import guard_pythonfmu_exit
from components.stripdraw.parameters import parameter_fields

#: Default table, bundled at ``resources/friction_table.npz`` by :mod:`components.fmus.build`.
DEFAULT_TABLE_FILE = "friction_table.npz"
#: Start values of the inputs: the paper's test at P_N = 10 MPa on the default 35 x 35 mm pad.
DEFAULT_NORMAL_FORCE = 12250.0  # N = 10 MPa x 0.035 m x 0.035 m
DEFAULT_GRIP_VELOCITY = 0.08

#: name -> (unit, description) of the inputs
INPUTS = {
    "normal_force": ("N", "normal force F_N on one pad (>= 0)"),
    "grip_velocity": ("m/s", "velocity of the grip pulling the strip"),
}
#: name -> (unit, description) of the outputs; the model's OUTPUT_NAMES, in its order
OUTPUTS = {
    "pull_force": ("N", "pull force on the whole strip (both faces); mu = pull_force / (2 normal_force)"),
    "friction_force": ("N", "friction force F_S on the modelled face (sum of nodal friction forces)"),
    "mu_mean": ("1", "mean friction coefficient F_S / F_N (Eq. 28)"),
    "sliding_distance": ("m", "contact-weighted mean displacement of the strip under the pad"),
    "beta_mean": ("1", "contact-weighted mean debris area fraction under the pad"),
    "beta_max": ("1", "largest debris area fraction on the strip"),
    "contact_pressure": ("Pa", "nominal contact pressure P = F_N / (tool_length tool_width)"),
    "grip_position": ("m", "displacement of the grip"),
    "table_clamp_count": ("1", "cumulative number of nodal table lookups outside the table (clamped)"),
}
INTEGER_OUTPUTS = ("table_clamp_count",)

#: SI base-unit exponents of every unit the variables use (FMI 2.0 UnitDefinitions)
_BASE_UNITS = {
    "1": {},
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "N": {"kg": 1, "m": 1, "s": -2},
    "Pa": {"kg": 1, "m": -1, "s": -2},
    "kg/m3": {"kg": 1, "m": -3},
}


def _describe(description: str, unit: str) -> str:
    """The variable description with its unit, e.g. ``"pad length [m]"``."""
    return f"{description} [{unit or '1'}]"


class _RealWithUnit(Real):
    """A pythonfmu ``Real`` that also writes ``unit``, ``min`` and ``max`` into the XML, and its
    start value with ``repr`` (pythonfmu's 16 digits do not always round-trip a float64)."""

    def __init__(self, name, unit, low=None, high=None, **kwargs):
        super().__init__(name, **kwargs)
        self.unit, self.low, self.high = unit, low, high

    def to_xml(self) -> Element:
        node = super().to_xml()
        real = node.find("Real")
        if self.start is not None:
            real.set("start", repr(float(self.start)))
        real.set("unit", self.unit)
        if self.low is not None:
            real.set("min", repr(float(self.low)))
        if self.high is not None:
            real.set("max", repr(float(self.high)))
        return node


class StripDraw(Fmi2Slave):
    """The strip-draw FMU (one pad, one face; ``pull_force`` for the whole strip)."""

    author = "tribocosim"
    description = (
        "Flat strip-draw test with wear debris: 1D bar under a rigid pad, Coulomb interface law, "
        "debris transport and a friction table mu(P, v, beta) (FMI 2.0 co-simulation)"
    )
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=1.75, step_size=1e-3)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        guard_pythonfmu_exit(self.resources, type(self).__name__)  # see components/fmus/exitguard.py
        self._fields = parameter_fields()
        self._params = {f.name: f.default for f in self._fields}
        self._params["table_file"] = DEFAULT_TABLE_FILE
        self._inputs = {"normal_force": DEFAULT_NORMAL_FORCE, "grip_velocity": DEFAULT_GRIP_VELOCITY}
        self._outputs = {name: 0.0 for name in OUTPUTS}
        self._model = None
        self._table_hash = None
        self._failure = None  # why the instance is unusable (failed initialization or state)
        for f in self._fields:
            self._register_parameter(f)
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
                setter=lambda v: self._set_parameter("table_file", str, v),
            )
        )
        for name, (unit, desc) in INPUTS.items():
            self.register_variable(
                _RealWithUnit(
                    name,
                    unit,
                    causality=Fmi2Causality.input,
                    variability=Fmi2Variability.continuous,
                    description=_describe(desc, unit),
                    getter=lambda n=name: self._inputs[n],
                    setter=lambda v, n=name: self._inputs.__setitem__(n, float(v)),
                )
            )
        for name, (unit, desc) in OUTPUTS.items():
            common = dict(
                causality=Fmi2Causality.output,
                initial=Fmi2Initial.exact,
                description=_describe(desc, unit),
            )
            if name in INTEGER_OUTPUTS:
                var = Integer(
                    name,
                    variability=Fmi2Variability.discrete,
                    getter=lambda n=name: int(self._outputs[n]),
                    **common,
                )
            else:
                var = _RealWithUnit(
                    name,
                    unit,
                    variability=Fmi2Variability.continuous,
                    getter=lambda n=name: self._outputs[n],
                    **common,
                )
            self.register_variable(var)
        #: value reference -> getter of every Real variable: the fast path of get_real
        self._real_getters = {vr: v.getter for vr, v in self.vars.items() if isinstance(v, Real)}

    # ------------------------------------------------------------------ declaration
    def _register_parameter(self, f: dataclasses.Field) -> None:
        """One FMU parameter from one dataclass field (type from the field's metadata)."""
        meta = f.metadata
        name = f.name
        common = dict(
            causality=Fmi2Causality.parameter,
            variability=Fmi2Variability.fixed,
            getter=lambda: self._params[name],
        )
        if "choices" in meta:
            var = String(
                name,
                description=f"{meta['description']} [text]",
                setter=lambda v: self._set_parameter(name, str, v),
                **common,
            )
        elif meta.get("integer"):
            var = Integer(
                name,
                description=_describe(meta["description"], meta["unit"]),
                setter=lambda v: self._set_parameter(name, int, v),
                **common,
            )
        else:
            var = _RealWithUnit(
                name,
                meta["unit"] or "1",
                low=meta.get("low"),
                high=meta.get("high"),
                description=_describe(meta["description"], meta["unit"]),
                setter=lambda v: self._set_parameter(name, float, v),
                **common,
            )
        self.register_variable(var)

    def to_xml(self, model_options=None) -> Element:
        """pythonfmu's model description plus the UnitDefinitions the variables refer to."""
        root = super().to_xml(model_options or {})
        used = sorted({v.unit for v in self.vars.values() if isinstance(v, _RealWithUnit)})
        units = Element("UnitDefinitions")
        for unit in used:
            node = SubElement(units, "Unit", {"name": unit})
            if _BASE_UNITS[unit]:
                SubElement(node, "BaseUnit", {k: str(e) for k, e in _BASE_UNITS[unit].items()})
        position = list(root).index(root.find("CoSimulation")) + 1
        root.insert(position, units)
        return root

    def get_real(self, vrs):
        """pythonfmu's ``get_real`` without its per-variable type dispatch (called every step)."""
        getters = self._real_getters
        if all(vr in getters for vr in vrs):
            return [getters[vr]() for vr in vrs]
        return super().get_real(vrs)

    # ------------------------------------------------------------------ life cycle
    def exit_initialization_mode(self):
        try:
            self._build_model()
        except TribocosimError as exc:
            self._fail(f"initialization failed: {exc}")
        except Exception as exc:  # noqa: BLE001 - nothing may escape into pythonfmu (see module doc)
            self._fail(f"initialization failed: {type(exc).__name__}: {exc}")

    def do_step(self, current_time: float, step_size: float) -> bool:
        if self._failure is not None:
            self._error(f"doStep refused: the FMU is not usable ({self._failure})")
            return False
        if self._model is None:
            self._error("doStep refused: the FMU has not left initialization mode")
            return False
        try:
            self._outputs = self._model.step(step_size, self._inputs)
        except Exception as exc:  # noqa: BLE001 - the model restores its state on any error
            fn, vg = self._inputs["normal_force"], self._inputs["grip_velocity"]
            what = str(exc) if isinstance(exc, TribocosimError) else f"{type(exc).__name__}: {exc}"
            self._error(
                f"doStep from t = {current_time!r} s by {step_size!r} s rejected: {what} "
                f"(inputs normal_force = {fn!r} N, grip_velocity = {vg!r} m/s); "
                "the FMU state is unchanged"
            )
            return False
        return True

    def _error(self, message: str) -> None:
        """Log ``message`` with status error, and echo it on stderr.

        pythonfmu 0.7.0 passes no message at all to the importer's logger unless logging is on
        (``fmpy simulate --debug-logging``), so stderr is the only place a user would see why a
        step was refused.
        """
        self.log(message, Fmi2Status.error)
        print(f"StripDraw [{self.instance_name}] error: {message}", file=sys.stderr, flush=True)

    def _fail(self, message: str) -> None:
        """Mark the instance unusable (every doStep is refused with ``message``) and report it."""
        self._failure = message
        self._model = None
        self._error(message)

    def _set_parameter(self, name: str, convert, value) -> None:
        """Setter of a parameter: ``fixed`` variability, so it is ignored after initialization."""
        if self._model is not None or self._failure is not None:
            self.log(
                f"parameter {name} is fixed after initialization; the new value {value!r} is ignored",
                Fmi2Status.warning,
            )
            return
        self._params[name] = convert(value)

    def _build_model(self) -> None:
        """Validate the parameters, load the table (if used) and build the model."""
        import components
        from components.stripdraw.friction import make_friction_law
        from components.stripdraw.model import OUTPUT_NAMES, StripDrawModel
        from components.stripdraw.parameters import StripDrawParameters
        from components.stripdraw.table import read_table

        if tuple(OUTPUTS) != tuple(OUTPUT_NAMES):
            raise TribocosimError(  # a packaging error, not a user error: name both lists
                f"the adapter declares outputs {tuple(OUTPUTS)} but the model has {tuple(OUTPUT_NAMES)}"
            )
        params = StripDrawParameters(**{f.name: self._params[f.name] for f in self._fields})
        table = None
        if params.friction_model == "table":
            path = self.table_path()
            table = read_table(path)
            self.log(
                f"friction table {path}: provenance {table.provenance}, "
                f"content hash {table.metadata.get('content_hash')}",
                Fmi2Status.ok,
            )
        self._table_hash = None if table is None else table.metadata.get("content_hash")
        self._model = StripDrawModel(params, make_friction_law(params, table))
        self._outputs = self._model.outputs()
        self._failure = None
        self.log(f"model code from {os.path.dirname(components.__file__)}", Fmi2Status.ok)

    def table_path(self) -> Path:
        """``table_file`` resolved against the FMU's resources folder."""
        path = Path(self._params["table_file"])
        if not path.is_absolute():
            path = Path(self.resources or ".") / path
        return path

    # ------------------------------------------------------------------ FMU state
    def _get_fmu_state(self) -> dict:
        return {
            "parameters": dict(self._params),
            "inputs": dict(self._inputs),
            "outputs": dict(self._outputs),
            "table_hash": self._table_hash,
            "failure": self._failure,
            "model": None if self._model is None else self._model.get_state(),
        }

    def _set_fmu_state(self, state: dict) -> None:
        try:
            self._restore(state)
        except Exception as exc:  # noqa: BLE001 - nothing may escape into pythonfmu (see module doc)
            what = str(exc) if isinstance(exc, TribocosimError) else f"{type(exc).__name__}: {exc}"
            self._fail(f"setFMUstate failed: {what}")

    def _restore(self, state: dict) -> None:
        if "invalid" in state:
            raise TribocosimError(state["invalid"])
        if state["parameters"] != self._params or (self._model is None) != (state["model"] is None):
            # a state of another configuration: rebuild the model for the state's parameters
            self._params = dict(state["parameters"])
            self._model = None
            self._table_hash = None
            if state["model"] is not None:
                self._build_model()
        if state["table_hash"] != self._table_hash:
            raise TableError(
                f"the FMU state was taken with friction table hash {state['table_hash']}; this "
                f"instance uses {self._table_hash}"
            )
        if self._model is not None:
            self._model.set_state(state["model"])
        self._inputs = dict(state["inputs"])
        self._outputs = dict(state["outputs"])
        self._failure = state["failure"]

    @staticmethod
    def _fmu_state_to_bytes(state: dict) -> bytes:
        return statecodec.encode(state)

    @staticmethod
    def _fmu_state_from_bytes(data: bytes) -> dict:
        try:
            return statecodec.decode(data)
        except Exception as exc:  # noqa: BLE001 - reported by _set_fmu_state, which can log
            return {"invalid": f"cannot deserialize the FMU state: {exc}"}
