"""The FMI 2.0 co-simulation plumbing shared by the project's pythonfmu adapters (bundled into every FMU).

An adapter (``components/fmus/<ModelIdentifier>.py``) is a subclass of :class:`ModelAdapter`
that states only what is particular to its model: the parameter dataclass, the inputs and
outputs (:class:`Var`), and how to build the model. Everything else is here, once:

Variables
    One FMU parameter per dataclass field (:func:`tribocosim.components.params.param` metadata): a
    ``Real`` with ``unit``/``min``/``max``, an ``Integer`` (``integer=True``), or a ``String``
    (``choices=...`` or ``text=True``); all ``fixed``. Then the adapter's extra parameters
    (:meth:`ModelAdapter.register_extra_parameters`), the inputs (``Real``, ``continuous``) and
    the outputs (``initial = exact``, start value from :class:`Var`). Every description ends
    with its unit in brackets (``[text]`` for strings), and the model description gets the
    ``UnitDefinitions`` of the units used (:data:`BASE_UNITS`).

Life cycle
    ``__init__`` only registers variables (pythonfmu instantiates the class at build time).
    ``exit_initialization_mode`` builds the model (:meth:`ModelAdapter.make_model`, which
    validates the parameters); ``do_step`` calls ``model.step(step_size, inputs)``.
    Optional hooks for side outputs (the strip-draw FMU's ``field_output`` file):
    :meth:`~ModelAdapter.after_initialization`, :meth:`~ModelAdapter.after_step` (after every
    successful step), :meth:`~ModelAdapter.after_restore` (after ``fmi2SetFMUstate``) and
    :meth:`~ModelAdapter.on_terminate` (``fmi2Terminate``); all default to doing nothing.

Errors
    pythonfmu 0.7.0 turns a Python exception escaping an FMI callback into fmi2Fatal, and the
    instance is then broken beyond repair: terminating or freeing it and carrying on crashed the
    host process (segfault, measured with fmpy). So nothing escapes an adapter; the only
    failure status pythonfmu can return otherwise is fmi2Discard, from a ``do_step`` that
    returns False. Hence:

    - a step the model rejects (NaN/inf input, step size <= 0, a model error): ``fmi2DoStep``
      returns fmi2Discard, a message (status error) names the cause, the inputs and the time,
      and the FMU state is unchanged (the models change their state only after a successful
      step): the master may fix the input, shorten the step, or restore a state, and retry;
    - a bad parameter (out of range, unknown choice, malformed table...): detected in
      ``fmi2ExitInitializationMode``, which logs the error (status error) but, for the reason
      above, cannot fail; the instance is then unusable and every ``fmi2DoStep`` returns
      fmi2Discard with the same message. The same holds for a state that cannot be restored;
    - pythonfmu 0.7.0 passes log messages to the importer only when logging is on (fmpy:
      ``--debug-logging``), so errors are also written to stderr;
    - a parameter set after initialization (they are all ``fixed``) is ignored with a warning.

FMU state
    ``fmi2GetFMUstate`` captures the parameters, inputs, outputs, the adapter's
    :meth:`~ModelAdapter.fingerprint` (e.g. the friction table's hash) and the model's full
    state (its numpy arrays included); ``fmi2SerializeFMUstate`` writes it with
    :mod:`tribocosim.components.fmus.statecodec` instead of pythonfmu's JSON. Restoring a state continues
    the run bit-identically, in the same instance or in another instance of the same FMU (a
    state of other parameters rebuilds the model for them).

Modules in one process
    pythonfmu puts each FMU's ``resources/`` first on ``sys.path`` and Python imports a module
    once per process, so all FMUs of this project in one process share one ``components``
    package: the host's, if it has imported it (e.g. a test that also runs the pure model), or
    else the copy bundled in the first FMU instantiated. Each FMU bundles only the modules it
    imports, so :func:`use_bundled_packages` adds an FMU's folders to the search path of
    packages it shares with an earlier FMU and that lack one of its modules (a Press after a
    StripDraw finds ``components/press.py`` in its own bundle). FMUs built from different
    versions of the project therefore share the first copy of their common modules.

Process exit
    :mod:`tribocosim.components.fmus.exitguard` works around a use-after-free in pythonfmu 0.7.0's library
    destructor that made Python hosts abort at exit after freeing an FMU.
"""

from __future__ import annotations

import dataclasses
import sys
from dataclasses import dataclass
from pathlib import Path
from xml.etree.ElementTree import Element, SubElement

from pythonfmu import Fmi2Causality, Fmi2Initial, Fmi2Slave, Fmi2Variability, Integer, Real, String
from pythonfmu.enums import Fmi2Status

from tribocosim.components.errors import TribocosimError
from tribocosim.components.fmus import statecodec
from tribocosim.components.fmus.exitguard import guard_pythonfmu_exit

#: SI base-unit exponents of every unit the variables may use (FMI 2.0 UnitDefinitions)
BASE_UNITS = {
    "1": {},
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "s": {"s": 1},
    "1/s": {"s": -1},
    "kg": {"kg": 1},
    "kg m2": {"kg": 1, "m": 2},
    "kg/m3": {"kg": 1, "m": -3},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N/m": {"kg": 1, "s": -2},
    "N s/m": {"kg": 1, "s": -1},
    "Pa": {"kg": 1, "m": -1, "s": -2},
}


@dataclass(frozen=True)
class Var:
    """An input or output of an FMU: unit, description (without the unit), start value.

    ``key`` is the model's name of the quantity when the FMU variable is named differently
    (e.g. because a parameter has the model's name).
    """

    unit: str
    description: str
    start: float = 0.0
    key: str | None = None


def describe(description: str, unit: str) -> str:
    """The variable description with its unit, e.g. ``"pad length [m]"``."""
    return f"{description} [{unit or '1'}]"


class RealWithUnit(Real):
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


def add_unit_definitions(root: Element, variables, owner: str = "FMU") -> Element:
    """Insert ``<UnitDefinitions>`` (after ``<CoSimulation>``) for the units of the
    :class:`RealWithUnit` variables, with their SI base-unit exponents from :data:`BASE_UNITS`."""
    used = sorted({v.unit for v in variables if isinstance(v, RealWithUnit)})
    unknown = [u for u in used if u not in BASE_UNITS]
    if unknown:  # a packaging error, found at build time
        raise TribocosimError(f"{owner}: units {unknown} are missing from adapter.BASE_UNITS")
    units = Element("UnitDefinitions")
    for unit in used:
        node = SubElement(units, "Unit", {"name": unit})
        if BASE_UNITS[unit]:
            SubElement(node, "BaseUnit", {k: str(e) for k, e in BASE_UNITS[unit].items()})
    root.insert(list(root).index(root.find("CoSimulation")) + 1, units)
    return root


def use_bundled_packages(resources: str | None, package: str = "tribocosim") -> list[str]:
    """Let the already imported ``package`` (and its imported subpackages) find this FMU's modules.

    For every imported package ``package[.sub...]`` not loaded from ``resources``: if the FMU's
    copy ``resources/<package>/<sub...>/`` holds a module or subpackage that none of the
    package's ``__path__`` entries holds, that folder is appended to ``__path__``. Returns the
    folders appended (none in a host whose package is complete, e.g. this project's).
    """
    if not resources:
        return []
    bundle = Path(resources) / package
    added = []
    for name, module in list(sys.modules.items()):
        if name != package and not name.startswith(package + "."):
            continue
        paths = getattr(module, "__path__", None)
        mine = bundle.joinpath(*name.split(".")[1:])
        if not isinstance(paths, list) or not mine.is_dir() or str(mine) in paths:
            continue  # not a package, a namespace package, or nothing of ours
        entries = {p.name for p in mine.iterdir() if p.suffix == ".py" or (p / "__init__.py").is_file()}
        missing = [e for e in entries if not any((Path(p) / e).exists() for p in paths)]
        if missing:
            paths.append(str(mine))
            added.append(str(mine))
    return added


class ModelAdapter(Fmi2Slave):
    """Base of the project's FMU adapters (see the module docstring); subclasses set:

    - ``INPUTS`` / ``OUTPUTS``: ``{variable name: Var}``; ``OUTPUTS`` in the order of the
      model's ``outputs()`` dict; ``INTEGER_OUTPUTS``: names of outputs declared ``Integer``;
    - :meth:`parameter_fields` and :meth:`make_model`; optionally
      :meth:`register_extra_parameters` and :meth:`fingerprint` (with ``FINGERPRINT_NAMES``);
    - ``author``, ``description``, ``default_experiment`` (pythonfmu's class attributes).

    The model must offer ``step(dt, inputs) -> outputs``, ``outputs()``, ``get_state()`` and
    ``set_state(state)``, and leave its state unchanged when ``step`` raises.
    """

    INPUTS: dict[str, Var] = {}
    OUTPUTS: dict[str, Var] = {}
    INTEGER_OUTPUTS: tuple[str, ...] = ()
    #: key of :meth:`fingerprint` -> what it identifies (for the message of a mismatching state)
    FINGERPRINT_NAMES: dict[str, str] = {}

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        guard_pythonfmu_exit(self.resources, type(self).__name__)  # see components/fmus/exitguard.py
        self._bundle_paths = use_bundled_packages(self.resources)
        self._fields = tuple(self.parameter_fields())
        self._params = {f.name: f.default for f in self._fields}
        self._inputs = {name: float(var.start) for name, var in self.INPUTS.items()}
        self._outputs = {self._key(name): float(var.start) for name, var in self.OUTPUTS.items()}
        self._model = None
        self._failure = None  # why the instance is unusable (failed initialization or state)
        for f in self._fields:
            self._register_field(f)
        self.register_extra_parameters()
        for name, var in self.INPUTS.items():
            self.register_variable(
                RealWithUnit(
                    name,
                    var.unit,
                    causality=Fmi2Causality.input,
                    variability=Fmi2Variability.continuous,
                    description=describe(var.description, var.unit),
                    getter=lambda n=name: self._inputs[n],
                    setter=lambda v, n=name: self._inputs.__setitem__(n, float(v)),
                )
            )
        for name, var in self.OUTPUTS.items():
            common = dict(
                causality=Fmi2Causality.output,
                initial=Fmi2Initial.exact,
                description=describe(var.description, var.unit),
            )
            key = self._key(name)
            if name in self.INTEGER_OUTPUTS:
                out = Integer(
                    name, variability=Fmi2Variability.discrete, getter=lambda k=key: int(self._outputs[k]), **common
                )
            else:
                out = RealWithUnit(
                    name,
                    var.unit,
                    variability=Fmi2Variability.continuous,
                    getter=lambda k=key: self._outputs[k],
                    **common,
                )
            self.register_variable(out)
        #: value reference -> getter of every Real variable: the fast path of get_real
        self._real_getters = {vr: v.getter for vr, v in self.vars.items() if isinstance(v, Real)}

    # ------------------------------------------------------------------ hooks
    def parameter_fields(self) -> tuple[dataclasses.Field, ...]:
        """The fields of the model's parameter dataclass (one FMU parameter each)."""
        raise NotImplementedError

    def register_extra_parameters(self) -> None:
        """Register parameters that are not dataclass fields (after the fields, before the inputs)."""

    def make_model(self, parameters: dict):
        """Build the model from the parameter values (``{name: value}``, extras included).

        Raise :class:`~tribocosim.components.errors.TribocosimError` (e.g. ``ParameterError``) with a
        message naming the culprit if the parameters are not usable.
        """
        raise NotImplementedError

    def fingerprint(self) -> dict:
        """Facts about the model's data that a restored FMU state must match (e.g. a table hash)."""
        return {}

    def after_initialization(self) -> None:
        """Called once the model is built (end of initialization); may raise TribocosimError."""

    def after_step(self) -> None:
        """Called after every successful ``doStep`` (e.g. to record a field); must be cheap
        when it has nothing to do. An exception marks the instance unusable."""

    def after_restore(self) -> None:
        """Called after ``fmi2SetFMUstate`` restored the model (e.g. to drop recorded rows)."""

    def on_terminate(self) -> None:
        """Called by ``fmi2Terminate`` (e.g. to write a result file); errors are logged."""

    # ------------------------------------------------------------------ declaration
    def _key(self, output_name: str) -> str:
        return self.OUTPUTS[output_name].key or output_name

    def _register_field(self, f: dataclasses.Field) -> None:
        """One FMU parameter from one dataclass field (type from the field's metadata)."""
        meta = f.metadata
        name = f.name
        common = dict(
            causality=Fmi2Causality.parameter,
            variability=Fmi2Variability.fixed,
            getter=lambda: self._params[name],
        )
        if "choices" in meta or meta.get("text"):
            var = String(
                name,
                description=f"{meta['description']} [text]",
                setter=lambda v: self.set_parameter(name, str, v),
                **common,
            )
        elif meta.get("integer"):
            var = Integer(
                name,
                description=describe(meta["description"], meta["unit"]),
                setter=lambda v: self.set_parameter(name, int, v),
                **common,
            )
        else:
            var = RealWithUnit(
                name,
                meta["unit"] or "1",
                low=meta.get("low"),
                high=meta.get("high"),
                description=describe(meta["description"], meta["unit"]),
                setter=lambda v: self.set_parameter(name, float, v),
                **common,
            )
        self.register_variable(var)

    def to_xml(self, model_options=None) -> Element:
        """pythonfmu's model description plus the UnitDefinitions the variables refer to."""
        return add_unit_definitions(super().to_xml(model_options or {}), self.vars.values(), type(self).__name__)

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
            self.after_initialization()
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
        except Exception as exc:  # noqa: BLE001 - the model keeps its state on any error
            what = str(exc) if isinstance(exc, TribocosimError) else f"{type(exc).__name__}: {exc}"
            shown = ", ".join(f"{n} = {self._inputs[n]!r} {v.unit}" for n, v in self.INPUTS.items())
            self._error(
                f"doStep from t = {current_time!r} s by {step_size!r} s rejected: {what} "
                + (f"(inputs {shown}); " if shown else "; ")
                + "the FMU state is unchanged"
            )
            return False
        try:
            self.after_step()
        except Exception as exc:  # noqa: BLE001 - nothing may escape into pythonfmu (see module doc)
            what = str(exc) if isinstance(exc, TribocosimError) else f"{type(exc).__name__}: {exc}"
            self._fail(f"after the step to t = {current_time + step_size!r} s: {what}")
            return False
        return True

    def terminate(self):
        try:
            self.on_terminate()
        except Exception as exc:  # noqa: BLE001 - nothing may escape into pythonfmu (see module doc)
            what = str(exc) if isinstance(exc, TribocosimError) else f"{type(exc).__name__}: {exc}"
            self._error(f"terminate: {what}")

    def set_parameter(self, name: str, convert, value) -> None:
        """Setter of a parameter: ``fixed`` variability, so it is ignored after initialization."""
        if self._model is not None or self._failure is not None:
            self.log(
                f"parameter {name} is fixed after initialization; the new value {value!r} is ignored",
                Fmi2Status.warning,
            )
            return
        self._params[name] = convert(value)

    def _error(self, message: str) -> None:
        """Log ``message`` with status error, and echo it on stderr.

        pythonfmu 0.7.0 passes no message at all to the importer's logger unless logging is on
        (``fmpy simulate --debug-logging``), so stderr is the only place a user would see why a
        step was refused.
        """
        self.log(message, Fmi2Status.error)
        print(f"{type(self).__name__} [{self.instance_name}] error: {message}", file=sys.stderr, flush=True)

    def _fail(self, message: str) -> None:
        """Mark the instance unusable (every doStep is refused with ``message``) and report it."""
        self._failure = message
        self._model = None
        self._error(message)

    def _build_model(self) -> None:
        """Build the model for the current parameters and take its initial outputs."""
        model = self.make_model(dict(self._params))
        outputs = model.outputs()
        declared = tuple(self._key(n) for n in self.OUTPUTS)
        if tuple(outputs) != declared:
            raise TribocosimError(  # a packaging error, not a user error: name both lists
                f"the adapter declares outputs {declared} but the model has {tuple(outputs)}"
            )
        self._model, self._outputs, self._failure = model, outputs, None
        source = getattr(sys.modules.get(type(model).__module__), "__file__", "?")
        extra = f"; bundle folders added to the package path: {self._bundle_paths}" if self._bundle_paths else ""
        self.log(f"model code {type(model).__module__} from {source}{extra}", Fmi2Status.ok)

    # ------------------------------------------------------------------ FMU state
    def _get_fmu_state(self) -> dict:
        return {
            "parameters": dict(self._params),
            "inputs": dict(self._inputs),
            "outputs": dict(self._outputs),
            **self.fingerprint(),
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
            if state["model"] is not None:
                self._build_model()
        for key, mine in self.fingerprint().items():
            if state.get(key) != mine:
                raise TribocosimError(
                    f"the FMU state was taken with {self.FINGERPRINT_NAMES.get(key, key)} {state.get(key)}; "
                    f"this instance uses {mine}"
                )
        if self._model is not None:
            self._model.set_state(state["model"])
        self._inputs = dict(state["inputs"])
        self._outputs = dict(state["outputs"])
        self._failure = state["failure"]
        self.after_restore()

    @staticmethod
    def _fmu_state_to_bytes(state: dict) -> bytes:
        return statecodec.encode(state)

    @staticmethod
    def _fmu_state_from_bytes(data: bytes) -> dict:
        try:
            return statecodec.decode(data)
        except Exception as exc:  # noqa: BLE001 - reported by _set_fmu_state, which can log
            return {"invalid": f"cannot deserialize the FMU state: {exc}"}
