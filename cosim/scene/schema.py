"""Scene files (TOML): the schema, its records and the first validation pass.

A scene names the FMUs of a co-simulation, their parameters, the connections, the master
settings and the outputs to record; nothing else is loaded, computed or written. Example::

    [experiment]
    start = 0.0
    stop = 1.75
    step = 1e-3                 # communication step; the initial one when adaptive

    [master]
    algorithm = "jacobi"        # jacobi | gauss-seidel | iterative
    extrapolation = 0           # input extrapolation (interpolation for iterative) order: 0, 1, 2
    # output_update = "propagate"   # or "none": outputs read right after doStep (as libcosim)
    # order = ["press", "strip"]    # Gauss-Seidel order (default: from the connection graph)

    # [master.adaptive]            # tribocosim.cosim.engine.stepcontrol.Adaptive
    # tolerance = 1e-4
    # min_step = 1e-7
    # max_step = 1e-2
    # estimator = "step-doubling"   # or "energy" (needs [[power_bonds]])
    # step_quantum = 2.5e-5         # step doubling: steps are multiples of 2 x this (an FMU's internal step,
                                    # e.g. the strip's internal_step), min_step = 2 x it

    # [master.iterative]           # settings of the algorithm of that name (tribocosim.cosim.engine.algorithms)
    # method = "quasi-newton"       # or "fixed-point"
    # relaxation = 1.0              # fixed-point relaxation factor, or "aitken"
    # tolerance = 1e-8
    # max_iterations = 50

    [fmus.strip]
    path = "StripDraw.fmu"      # relative to the scene file, or: component = "stripdraw"
    parameters = { tool_length = 0.035 }
    # feedthrough = false       # outputs never depend directly on inputs (default: from the
                                # model description, else probed numerically at the start)

    [[connections]]
    from = "press.normal_force"
    to = "strip.normal_force"

    # [[power_bonds]]           # effort/flow pairs, for the energy estimator
    # effort = ["press.force", "strip.force"]
    # flow = ["strip.velocity", "press.velocity"]

    [output]
    file = "results.csv"        # columns: time, then "instance.variable" in the order given
    variables = ["strip.pull_force", "strip.mu_mean"]

:func:`parse_scene` checks the structure (keys, types, ranges) and returns every problem it
found together with whatever could be parsed; :mod:`tribocosim.cosim.scene.validate` then checks the scene
against the FMUs' model descriptions and raises one :class:`~tribocosim.errors.SceneError`
listing all problems, each with the file and the key (:mod:`tribocosim.cosim.scene.problems`).
"""

from __future__ import annotations

from pathlib import Path

from tribocosim.cosim.engine.schemes import ALGORITHMS, ESTIMATORS, Adaptive, VariableRef
from tribocosim.cosim.scene.documents import TomlError, parse_toml, read_toml
from tribocosim.cosim.scene.problems import Problems
from tribocosim.errors import SceneError

OUTPUT_UPDATES = ("propagate", "none")

_TOP_KEYS = ("experiment", "master", "fmus", "connections", "power_bonds", "output")
_EXPERIMENT_KEYS = ("start", "stop", "step")
#: the most communication steps of one run: (stop - start) / step (1e8 steps are hours to days of master time at tens
#: of microseconds per step; stop = 1e30 s at 1 ms was accepted and announced an ETA of 4e28 s)
MAX_STEPS = 1e8
_MASTER_KEYS = ("algorithm", "extrapolation", "output_update", "order", "adaptive",
                *(name for name, spec in ALGORITHMS.items() if spec.settings is not None))
_FMU_KEYS = ("path", "component", "variant", "parameters", "feedthrough")
#: the one value ``variant`` may have: a component's FMU is built in C (the key is accepted, and does nothing, so that
#: scenes that name it keep running)
VARIANTS = ("native",)
_CONNECTION_KEYS = ("from", "to")
_BOND_KEYS = ("effort", "flow")
_OUTPUT_KEYS = ("file", "variables")


class Experiment:
    """[experiment]: start and stop time [s], communication step [s] (initial step if adaptive)."""

    __slots__ = ("start", "stop", "step")

    def __init__(self, start: float = 0.0, stop: float = 1.0, step: float = 1e-3) -> None:
        self.start, self.stop, self.step = start, stop, step

    def as_dict(self) -> dict:
        """``{"start": ..., "stop": ..., "step": ...}`` (as the results' metadata records it)."""
        return {"start": self.start, "stop": self.stop, "step": self.step}

    def __repr__(self) -> str:
        return f"Experiment(start={self.start!r}, stop={self.stop!r}, step={self.step!r})"


class MasterSettings:
    """[master]: the algorithm (a name of :data:`tribocosim.cosim.engine.schemes.ALGORITHMS`) and its
    settings (its ``[master.<name>]`` table), the input extrapolation, and the step control."""

    __slots__ = ("algorithm", "extrapolation", "output_update", "order", "adaptive", "algorithm_settings")

    def __init__(self, algorithm: str = "jacobi", extrapolation: int = 0, output_update: str = "propagate",
                 order: tuple[str, ...] | None = None, adaptive: Adaptive | None = None,
                 algorithm_settings=None) -> None:
        self.algorithm, self.extrapolation, self.output_update = algorithm, extrapolation, output_update
        self.order, self.adaptive, self.algorithm_settings = order, adaptive, algorithm_settings


class FmuSpec:
    """[fmus.NAME]: where the FMU comes from (a file, resolved; or a component's name) and the parameters to set
    before initialization; ``feedthrough`` as declared in the scene (None: from the model description)."""

    __slots__ = ("name", "path", "component", "parameters", "feedthrough")

    def __init__(self, name: str, path: Path | None = None, component: str | None = None,
                 parameters: dict | None = None, feedthrough: bool | None = None) -> None:
        self.name, self.path, self.component = name, path, component
        self.parameters = {} if parameters is None else parameters
        self.feedthrough = feedthrough


class Connection:
    """[[connections]]: an output feeding an input; ``key`` is where the scene says it."""

    __slots__ = ("source", "target", "key")

    def __init__(self, source: VariableRef, target: VariableRef, key: str = "") -> None:
        self.source, self.target, self.key = source, target, key


class PowerBond:
    """[[power_bonds]]: an effort connection and the opposite flow connection."""

    __slots__ = ("effort", "flow", "key")

    def __init__(self, effort: Connection, flow: Connection, key: str = "") -> None:
        self.effort, self.flow, self.key = effort, flow, key


class OutputSpec:
    """[output]: the CSV file and the recorded variables (in column order)."""

    __slots__ = ("file", "variables")

    def __init__(self, file: str | None = None, variables: tuple[VariableRef, ...] = ()) -> None:
        self.file, self.variables = file, variables


class Scene:
    """A parsed scene; ``overrides``: the dotted keys set over the file's (``--set``), as given (recorded with the
    results)."""

    __slots__ = ("path", "experiment", "master", "fmus", "connections", "power_bonds", "output", "overrides")

    def __init__(self, path: Path, experiment: Experiment, master: MasterSettings, fmus: dict[str, FmuSpec],
                 connections: tuple[Connection, ...], power_bonds: tuple[PowerBond, ...], output: OutputSpec,
                 overrides: dict | None = None) -> None:
        self.path, self.experiment, self.master, self.fmus = path, experiment, master, fmus
        self.connections, self.power_bonds, self.output = connections, power_bonds, output
        self.overrides = {} if overrides is None else overrides

    @property
    def folder(self) -> Path:
        return self.path.parent


def parse_ref(p: Problems, text, key: str) -> VariableRef | None:
    """Parse 'instance.variable' (reports a problem and returns None if malformed)."""
    if not isinstance(text, str) or "." not in text or text.startswith(".") or text.endswith("."):
        p.add(key, f"must be 'instance.variable', got {text!r}")
        return None
    inst, var = text.split(".", 1)
    return VariableRef(inst, var)


def parse_overrides(items: list[str]) -> dict:
    """``--set KEY=VALUE`` items as ``{dotted key: value}``: the value in TOML syntax (``1e-3``, ``"jacobi"``,
    ``[1, 2]``), else the text as it is; SceneError for an item that is not ``KEY=VALUE``."""
    from tribocosim.name_value import split_settings

    out = {}
    for key, value in split_settings(items, "--set", "KEY", SceneError).items():
        try:
            out[key] = parse_toml(f"v = {value}")["v"]
        except TomlError:
            out[key] = value
    return out


def apply_overrides(doc: dict, overrides: dict) -> dict:
    """Set dotted keys (``"master.extrapolation"``) in a parsed TOML document, in place."""
    for dotted, value in overrides.items():
        node = doc
        *parents, last = dotted.split(".")
        for part in parents:
            node = node.setdefault(part, {})
        node[last] = value
    return doc


def read_document(path: str | Path) -> dict | None:
    """The TOML document of a scene or sweep file, or None when it cannot be read as TOML (:func:`parse_scene` then
    says why)."""
    try:
        return read_toml(path)
    except (OSError, UnicodeDecodeError, TomlError):
        return None


def is_sweep(document: dict | None) -> bool:
    """True for the document of a sweep file (a ``[sweep]`` table over a base scene)."""
    return isinstance(document, dict) and isinstance(document.get("sweep"), dict)


def parse_scene(path: str | Path, overrides: dict | None = None,
                document: dict | None = None) -> tuple[Scene | None, list[str]]:
    """Read and structurally check a scene file.

    Parameters
    ----------
    path : str or Path
        The TOML scene file.
    overrides : dict, optional
        Dotted keys to set before checking, e.g. ``{"experiment.step": 1e-2}`` (for sweeps).
    document : dict, optional
        The file's TOML document when it was read already (:func:`read_document`; the overrides are set in it).

    Returns
    -------
    scene : Scene or None
        What could be parsed (None if the file is unreadable or not TOML).
    problems : list of Problem
        Every structural problem (file, key, message).
    """
    path = Path(path).resolve()
    p = Problems(path)
    try:
        doc = document if document is not None else read_toml(path)
    except FileNotFoundError:
        p.add("(file)", "scene file not found")
        return None, p.items
    except (OSError, UnicodeDecodeError) as exc:
        p.add("(file)", f"cannot read: {exc}")
        return None, p.items
    except TomlError as exc:
        p.add("(syntax)", f"not valid TOML: {exc}")
        return None, p.items
    if overrides:
        apply_overrides(doc, overrides)

    p.unknown_keys(doc, _TOP_KEYS, "")
    exp = p.table(doc, "experiment", "experiment")
    p.unknown_keys(exp, _EXPERIMENT_KEYS, "experiment")
    for k in ("stop", "step"):
        if k not in exp:
            p.add(f"experiment.{k}", "missing (required)")
    start = p.number(exp, "start", "experiment", 0.0)
    stop = p.number(exp, "stop", "experiment", start + 1.0)
    step = p.number(exp, "step", "experiment", 1e-3, positive=True)
    if stop <= start:
        p.add("experiment.stop", f"must be greater than start = {start!r}, got {stop!r}")
        stop = start + 1.0
    elif step > stop - start:
        p.add("experiment.step", f"{step!r} is longer than the experiment ({stop - start!r} s)")
    elif (stop - start) / step > MAX_STEPS:
        p.add("experiment.stop", f"stop = {stop!r} s is {(stop - start) / step:.3g} steps of {step!r} s after start = "
                                 f"{start!r} s; at most {MAX_STEPS:.0e} steps are allowed (a longer run: a longer step)")
        stop = start + step
    experiment = Experiment(float(start), float(stop), float(step))

    master = _parse_master(p, p.table(doc, "master", "master"), experiment)

    fmus: dict[str, FmuSpec] = {}
    fmu_doc = p.table(doc, "fmus", "fmus")
    if not fmu_doc:
        p.add("fmus", "no FMUs given; add at least one [fmus.NAME] table")
    for name, spec in fmu_doc.items():
        key = f"fmus.{name}"
        if "." in name or not name:
            p.add(key, "instance names must be non-empty and contain no '.'")
            continue
        if not isinstance(spec, dict):
            p.add(key, "must be a table")
            continue
        p.unknown_keys(spec, _FMU_KEYS, key)
        fpath, comp = spec.get("path"), spec.get("component")
        if (fpath is None) == (comp is None):
            p.add(key, "give exactly one of 'path' (an .fmu file) or 'component' (built on demand)")
        if fpath is not None and not isinstance(fpath, str):
            p.add(f"{key}.path", f"must be a string, got {fpath!r}")
            fpath = None
        if comp is not None and not isinstance(comp, str):
            p.add(f"{key}.component", f"must be a string, got {comp!r}")
            comp = None
        params = spec.get("parameters", {})
        if not isinstance(params, dict):
            p.add(f"{key}.parameters", "must be a table of name = value")
            params = {}
        ft = spec.get("feedthrough")
        if ft is not None and not isinstance(ft, bool):
            p.add(f"{key}.feedthrough", f"must be true or false, got {ft!r}")
            ft = None
        if "variant" in spec and spec["variant"] not in VARIANTS:
            p.add(f"{key}.variant", f"{spec['variant']!r} is not allowed: the project builds the FMUs of its components "
                                    "in C only (variant = \"native\", which need not be given); a component written "
                                    "in Python is an FMU of its own, named by path = ...")
        elif "variant" in spec and comp is None:
            p.add(f"{key}.variant", "applies to component = \"...\" FMUs only")
        resolved = (path.parent / fpath).resolve() if fpath else None
        fmus[name] = FmuSpec(name, resolved, comp, dict(params), ft)

    connections = []
    conn_doc = doc.get("connections", [])
    if not isinstance(conn_doc, list):
        p.add("connections", "must be an array of tables ([[connections]])")
        conn_doc = []
    for i, c in enumerate(conn_doc):
        key = f"connections[{i}]"
        if not isinstance(c, dict):
            p.add(key, "must be a table with 'from' and 'to'")
            continue
        p.unknown_keys(c, _CONNECTION_KEYS, key)
        src = parse_ref(p, c.get("from"), f"{key}.from")
        dst = parse_ref(p, c.get("to"), f"{key}.to")
        if src and dst:
            connections.append(Connection(src, dst, key))

    bonds = []
    bond_doc = doc.get("power_bonds", [])
    if not isinstance(bond_doc, list):
        p.add("power_bonds", "must be an array of tables ([[power_bonds]])")
        bond_doc = []
    for i, b in enumerate(bond_doc):
        key = f"power_bonds[{i}]"
        if not isinstance(b, dict):
            p.add(key, "must be a table with 'effort' and 'flow'")
            continue
        p.unknown_keys(b, _BOND_KEYS, key)
        pair = {}
        for part in _BOND_KEYS:
            v = b.get(part)
            if not (isinstance(v, list) and len(v) == 2):
                p.add(f"{key}.{part}", f"must be [\"from.instance_variable\", \"to.instance_variable\"], got {v!r}")
                continue
            src, dst = parse_ref(p, v[0], f"{key}.{part}[0]"), parse_ref(p, v[1], f"{key}.{part}[1]")
            if src and dst:
                pair[part] = Connection(src, dst, f"{key}.{part}")
        if len(pair) == 2:
            bonds.append(PowerBond(pair["effort"], pair["flow"], key))

    out = p.table(doc, "output", "output")
    p.unknown_keys(out, _OUTPUT_KEYS, "output")
    ofile = out.get("file")
    if ofile is not None and not isinstance(ofile, str):
        p.add("output.file", f"must be a file name, got {ofile!r}")
        ofile = None
    ovars = out.get("variables", [])
    refs = []
    if not isinstance(ovars, list):
        p.add("output.variables", "must be an array of 'instance.variable' strings")
        ovars = []
    for i, v in enumerate(ovars):
        r = parse_ref(p, v, f"output.variables[{i}]")
        if r:
            refs.append(r)

    scene = Scene(path, experiment, master, fmus, tuple(connections), tuple(bonds), OutputSpec(ofile, tuple(refs)),
                  dict(overrides or {}))
    if master.adaptive is not None and ESTIMATORS[master.adaptive.estimator].needs_bonds and not bonds:
        p.add("master.adaptive.estimator", f"'{master.adaptive.estimator}' needs at least one [[power_bonds]] entry")
    return scene, p.items


def _parse_master(p: Problems, m: dict, experiment: Experiment) -> MasterSettings:
    p.unknown_keys(m, _MASTER_KEYS, "master")
    algorithm = p.choice(m, "algorithm", "master", tuple(ALGORITHMS), "jacobi")
    extrapolation = p.choice(m, "extrapolation", "master", (0, 1, 2), 0)
    output_update = p.choice(m, "output_update", "master", OUTPUT_UPDATES, "propagate")
    order = m.get("order")
    if order is not None and not (isinstance(order, list) and all(isinstance(o, str) for o in order)):
        p.add("master.order", f"must be a list of instance names, got {order!r}")
        order = None
    adaptive = Adaptive.parse(p, p.table(m, "adaptive", "master.adaptive"), "master.adaptive", experiment.step) \
        if "adaptive" in m else None
    settings = {name: spec.settings.parse(p, p.table(m, name, f"master.{name}"), f"master.{name}")
                for name, spec in ALGORITHMS.items() if spec.settings is not None}
    return MasterSettings(algorithm, int(extrapolation), output_update, tuple(order) if order else None, adaptive,
                          settings.get(algorithm))
