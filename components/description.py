"""One description per runtime component: everything else (FMUs, scene checks, reference) derives from it.

A component is a pure model (``step(dt, inputs) -> outputs``, ``outputs()``, ``get_state()``,
``set_state()``, the state unchanged when ``step`` raises) plus one :class:`Component` next to
it (``tribocosim/components/<name>/component.py``, module attribute ``COMPONENT``) that says

- its names: the scene name (``component = "stripdraw"``) and the FMU's model identifier;
- its parameters: the model's frozen parameter dataclass, and a second dataclass of the FMU-only
  parameters (files: a friction table, field files), both declared with
  :func:`tribocosim.components.params.param` (unit, description, default, range or choices);
- its inputs and outputs (:class:`Port`: unit, description, start value, the model's key);
- the resource files an FMU carries (copied to the root of ``resources/``), as
  ``(package, file name)`` pairs of package data (resolved only when building, so that a bundled
  FMU, which has them in its ``resources/``, never looks for the package);
- how to make the model: ``build(parameters, files, resources) -> Built`` (loads the table, reads a
  field file, ...); ``resources`` is the folder those files are in (an FMU's ``resources/``, or the
  installed package data in process);
- optionally: its own scene checks (``check(parameters, files, resources) -> (problems, limits)``:
  problems of a parameter set that only the model can see, e.g. an unreadable table, as
  ``(parameter name or "", message)``, and the ranges its inputs accept as ``{input: Limit}``) and
  the set-points its outputs will follow (``setpoints``), which the scene checks match across
  connections; the ranges its inputs can take whatever drives them (``input_limits(parameters) ->
  {input: Limit}``: ranges that depend on several parameters, e.g. the strip's nominal pressure at most its
  hardness), checked against a value held in the scene and against connected set-points;
  an ``observer`` for side outputs (the strip's field file); and its native implementation
  (``native``: C sources and the prefix of its C functions).

:mod:`tribocosim.components.registry` finds the descriptions: the FMU build and its model
descriptions, the scene checks, the monolithic reference, the demo and the
reports all read them. Adding a component is writing its model and its description.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path

from tribocosim.errors import ParameterError

# The description's records are plain classes with slots: every run that checks a scene imports them, and a class made
# by ``dataclasses`` costs the import the compilation of its generated methods (3 to 4 million instructions a class).

#: a value is outside a port's bound when it is beyond it by more than this share of the bound: round-off, not a
#: longer draw (a draw of exactly draw_length ends 2.2e-15 m beyond it after 1750 steps)
BOUND_SLACK = 1e-9


class Port:
    """An input or output: FMU variable name, unit, description (without the unit), start value.

    ``key`` is the model's name of the quantity when the FMU variable is named differently (e.g.
    because a parameter has the model's name); ``integer`` declares an output as an FMI Integer.

    ``low`` and ``high`` bound the values the model is built for, each a number or the name of a
    parameter whose value is the bound (``high="draw_length"``), and ``why`` says what lies outside.
    They are not the FMU's ``min``/``max`` (a host may pass through them: the model still computes):
    a set-point (:class:`SetPoint`) connected to an input outside them is a scene error, and an output
    outside them after a step is a warning of the native FMU (logged; the step returns Warning).

    ``initial_inputs`` names the inputs an output depends on at the end of initialization (the native FMU
    computes its outputs there from the inputs set during initialization: the model description's
    InitialUnknown dependencies); empty: the parameters alone.

    ``end_warning``: an output whose value at the end of a run says something went outside what the model rests
    on when it is above 0 (a count), and what: a run that ends with the output above 0 warns
    ``FMU instance '<name>': <value> <end_warning>``.
    """

    __slots__ = ("name", "unit", "description", "start", "key", "integer", "low", "high", "why", "initial_inputs",
                 "end_warning")

    def __init__(self, name: str, unit: str, description: str, start: float = 0.0, key: str | None = None,
                 integer: bool = False, low: float | str | None = None, high: float | str | None = None,
                 why: str = "", initial_inputs: tuple = (), end_warning: str = "") -> None:
        self.name, self.unit, self.description, self.start, self.key = name, unit, description, start, key
        self.integer, self.low, self.high, self.why = integer, low, high, why
        self.initial_inputs, self.end_warning = initial_inputs, end_warning

    def __repr__(self) -> str:
        return f"Port({self.name!r}, {self.unit!r})"

    @property
    def model_key(self) -> str:
        """The key of the quantity in the model's inputs or outputs dict."""
        return self.key or self.name

    def limits(self, value_of: Callable[[str], float]) -> tuple[float | None, float | None]:
        """``(low, high)``, a bound that names a parameter replaced by ``value_of(name)``."""
        return tuple(value_of(b) if isinstance(b, str) else b for b in (self.low, self.high))

    def outside(self, value: float, low: float | None, high: float | None) -> int:
        """-1 when ``value`` is below ``low``, +1 when above ``high``, by more than :data:`BOUND_SLACK` of the bound
        (as the native FMU compares, tc_fmu_instance.c), else 0."""
        if low is not None and value < low - BOUND_SLACK * abs(low):
            return -1
        if high is not None and value > high + BOUND_SLACK * abs(high):
            return 1
        return 0


class SetPoint:
    """A value an output will follow (e.g. the press's force set-point), for the scene checks.

    ``label`` names it in a message ("the set-point, 12250 N"); ``parameter`` is the parameter
    that sets it (the key the problem is reported under).
    """

    __slots__ = ("value", "label", "parameter")

    def __init__(self, value: float, label: str, parameter: str) -> None:
        self.value, self.label, self.parameter = value, label, parameter

    def __repr__(self) -> str:
        return f"SetPoint({self.value!r}, {self.label!r}, {self.parameter!r})"


#: ``limit(value, label, instance) -> message or None``: whether an input accepts a set-point
Limit = Callable[[float, str, str], "str | None"]


class Built:
    """What :attr:`Component.build` returns: the model and the facts a restored FMU state must match.

    ``fingerprint`` maps a description (e.g. ``"friction table hash"``) to a value; an FMU state
    is restored only into an instance with the same fingerprint.
    """

    __slots__ = ("model", "fingerprint", "notes")

    def __init__(self, model: object, fingerprint: dict[str, object] | None = None, notes: list[str] | None = None):
        self.model = model
        self.fingerprint = {} if fingerprint is None else fingerprint
        self.notes = [] if notes is None else notes


class ArraySize:
    """The length of a native FMU's array outputs (FMI 3.0): the UInt64 structural parameter ``name``,
    equal to the integer parameter ``parameter`` plus ``offset``. ``parameter`` is a structural
    parameter of the FMI 3.0 FMU too; setting either sets both (e.g. ``n_nodes = n_elements + 1``).
    """

    __slots__ = ("name", "parameter", "offset", "description")

    def __init__(self, name: str, parameter: str, offset: int, description: str) -> None:
        self.name, self.parameter, self.offset, self.description = name, parameter, offset, description


class Native:
    """The C implementation of a component (sources in :mod:`tribocosim.components.native`).

    ``prefix`` names its C functions (``<prefix>_create``, ``_step``, ...); ``sources`` are the C
    files of the model and of its FMU glue (``tc_<name>_fmu.c``: the component functions of
    ``tc_fmu.h``), beside the shared ones (``tc_common.c``, the FMI wrapper); ``params_header`` is
    the header the build generates with the parameter struct (``<prefix>_params``). ``arrays`` are
    outputs only the FMI 3.0 FMU has: Float64 arrays of ``array_size`` values (the glue's
    ``tc_component_array``). ``interpolates_inputs``: the model takes its inputs' time derivatives at the
    step's start (FMI 2.0 ``canInterpolateInputs``, ``fmi2SetRealInputDerivatives``, orders 1 and 2).
    ``convert_resource(source, folder) -> path``: writes a resource file in the form the C code reads (the
    friction table's array file, ``<stem>.tca``) into ``folder``; the native FMU carries what it writes instead of
    the source, and a scene that sets one of ``resource_parameters`` to a file passes the native FMU its
    converted form. ``constants``: ``(name, value, what)`` of numbers the C code uses whose single definition is in
    Python (e.g. the documented friction floor), written into ``params_header`` as ``<PREFIX>_<NAME>``.
    """

    __slots__ = ("prefix", "sources", "params_header", "arrays", "array_size", "interpolates_inputs",
                 "convert_resource", "resource_parameters", "constants")

    def __init__(self, prefix: str, sources: tuple[str, ...], params_header: str, arrays: tuple[Port, ...] = (),
                 array_size: ArraySize | None = None, interpolates_inputs: bool = False,
                 convert_resource: Callable[[Path, Path], Path] | None = None,
                 resource_parameters: tuple[str, ...] = (),
                 constants: tuple[tuple[str, float, str], ...] = ()) -> None:
        self.prefix, self.sources, self.params_header, self.arrays = prefix, sources, params_header, arrays
        self.array_size, self.interpolates_inputs = array_size, interpolates_inputs
        self.convert_resource, self.resource_parameters = convert_resource, resource_parameters
        self.constants = constants


class Component:
    """The description of one runtime component (see the module docstring)."""

    __slots__ = ("name", "model_identifier", "summary", "parameters", "inputs", "outputs", "build", "files",
                 "resources", "check", "setpoints", "input_limits", "observer", "native", "default_experiment",
                 "author")

    def __init__(self, name: str, model_identifier: str, summary: str, parameters: type, inputs: tuple[Port, ...],
                 outputs: tuple[Port, ...], build: Callable[[object, object, Path], Built], files: type | None = None,
                 resources: tuple[tuple[str, str], ...] = (),
                 check: Callable[[object, object, Path], tuple[list[tuple[str, str]], dict[str, Limit]]] | None = None,
                 setpoints: Callable[[object], dict[str, list[SetPoint]]] | None = None,
                 input_limits: Callable[[object], dict[str, Limit]] | None = None,
                 observer: Callable[[object, object, dict], object] | None = None, native: Native | None = None,
                 default_experiment: tuple[float, float, float] = (0.0, 1.75, 1e-3),
                 author: str = "tribocosim") -> None:
        self.name, self.model_identifier, self.summary, self.parameters = name, model_identifier, summary, parameters
        self.inputs, self.outputs, self.build, self.files, self.resources = inputs, outputs, build, files, resources
        self.check, self.setpoints, self.input_limits, self.observer = check, setpoints, input_limits, observer
        self.native, self.default_experiment, self.author = native, default_experiment, author

    def __repr__(self) -> str:
        return f"Component({self.name!r})"

    def replace(self, **changes) -> "Component":
        """A copy with ``changes`` (``{attribute: value}``)."""
        return Component(**{**{k: getattr(self, k) for k in self.__slots__}, **changes})

    # ------------------------------------------------------------------ derived
    @property
    def parameter_fields(self) -> tuple[dataclasses.Field, ...]:
        """Every FMU parameter: the model's fields, then the FMU-only ones (one variable each)."""
        extra = dataclasses.fields(self.files) if self.files is not None else ()
        return (*dataclasses.fields(self.parameters), *extra)

    @property
    def defaults(self) -> dict[str, object]:
        """Default value of every FMU parameter, by name."""
        return {f.name: f.default for f in self.parameter_fields}

    @property
    def resource_files(self) -> tuple[Path, ...]:
        """The resource files in this installation (an FMU has them at the root of ``resources/``): each in the folder
        of its package."""
        import importlib

        return tuple(Path(importlib.import_module(package).__path__[0]) / name for package, name in self.resources)

    @property
    def resource_dir(self) -> Path:
        """The folder the resource files are in, in this installation."""
        folders = {p.parent for p in self.resource_files}
        if len(folders) > 1:
            raise ParameterError(f"component {self.name}: resources must share one folder, got {sorted(folders)}")
        return folders.pop() if folders else Path(".")

    def split(self, values: dict[str, object]) -> tuple[object, object]:
        """(parameters, files) dataclass instances from ``{name: value}`` (missing names take their defaults). The
        names of inputs are allowed and left out (a scene's parameters hold the values of inputs it does not
        connect); any other name is refused. Raises ParameterError naming the unknown names, or the first bad
        field."""
        own = {f.name for f in dataclasses.fields(self.parameters)}
        names = {f.name for f in dataclasses.fields(self.files)} if self.files is not None else set()
        inputs = {p.name for p in self.inputs}
        unknown = [k for k in values if k not in own and k not in names and k not in inputs]
        if unknown:
            import difflib  # only for the message: a run that checks its scene never needs it

            outputs = {p.name for p in self.outputs}
            why = [f"{k!r} is an output" if k in outputs else
                   f"{k!r}" + (f" (did you mean {close[0]!r}?)" if (close := difflib.get_close_matches(
                       k, [*own, *names, *inputs], n=1)) else "") for k in unknown]
            raise ParameterError(f"component {self.name}: unknown parameter{'s' if len(unknown) > 1 else ''} "
                                 f"{', '.join(why)}; allowed: the parameters {', '.join(sorted(own))}"
                                 + (f", the files {', '.join(sorted(names))}" if names else "")
                                 + (f" and the inputs {', '.join(sorted(inputs))}" if inputs else ""))
        params = self.parameters(**{k: v for k, v in values.items() if k in own})
        files = self.files(**{k: v for k, v in values.items() if k in names}) if self.files is not None else None
        return params, files

    def make(self, values: dict[str, object], resources: Path | None = None) -> Built:
        """The model for parameter ``values`` (``{name: value}``), resources from ``resources``
        (default: :attr:`resource_dir`)."""
        params, files = self.split(values)
        return self.build(params, files, Path(resources) if resources is not None else self.resource_dir)

    def output(self, name: str) -> Port:
        """The output port ``name``."""
        return next(p for p in self.outputs if p.name == name)

    def bounds(self, port: Port, values: dict[str, object]) -> tuple[float | None, float | None]:
        """``(low, high)`` of a port for parameter ``values`` (``{name: value}``; missing names take their
        defaults): a bound that names a parameter is that parameter's value."""
        defaults = self.defaults

        def value(bound: str) -> float:
            if bound not in defaults:
                raise ParameterError(f"component {self.name}: the bound {bound!r} of {port.name} is not a parameter")
            return float(values.get(bound, defaults[bound]))

        return port.limits(value)
