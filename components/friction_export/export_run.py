"""One export: the law sampled for the FE code's interpolation, checked, and written in a format, for every debris
state asked for and for the band.

For every debris state (a beta, or none: beta is then an axis, Abaqus' field variable 1) the grid is chosen by
:func:`~tribocosim.components.friction_export.grid_refinement.sample` over the range (the table's pressure axis or
``--pressure-range``, its velocity axis, and for a beta axis the beta nodes up to the highest level simulated at
every pressure and velocity of the range, or ``--beta-levels``), with the band's upper and lower mu on the same
grid. A lookup anywhere in the range that reads a table node the mesoscale campaign did not simulate makes the
export fail with the reason, unless ``allow_unsimulated`` asks for it to be written and marked. Then every file of
the export is written, or none (:mod:`.file_set`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from tribocosim.errors import ParameterError
from tribocosim.components.friction_export import abaqus_friction, lsdyna_deck, neutral_table
from tribocosim.components.friction_export.export_header import FileFacts, header_lines
from tribocosim.components.friction_export.exported_law import ExportedLaw, value_warnings
from tribocosim.components.friction_export.export_units import UnitSystem
from tribocosim.components.friction_export.file_set import check_target, tagged, write_all
from tribocosim.components.friction_export.grid_refinement import (AxisSpec, percent_up, relative_deviation,
                                                                   sample)

#: the deviation of the FE code's reading from the law, relative to mu (0.005: 0.5 %)
DEFAULT_TOLERANCE = 0.005
#: deviations are taken relative to max(mu, this): below it, absolute (a law that reaches mu = 0)
ACCURACY_FLOOR = 1e-3
#: a point of the range is on an axis end within this (relative), as the table's lookup takes it
END_TOLERANCE = 1e-9
#: mu equal at every velocity of the grid within this (relative, the round-off of the lookup's sums): the law does not
#: depend on the velocity, and the file writes one
VELOCITY_RTOL = 1e-12


@dataclass(frozen=True)
class Format:
    """A target: its title, file suffix, whether it needs a debris state, how its FE code reads it."""

    name: str
    title: str
    suffix: str
    needs_state: bool
    rule: str


FORMATS = {
    "lsdyna": Format("lsdyna", "LS-DYNA include: *DEFINE_TABLE of contact pressures with one *DEFINE_CURVE of mu "
                     "against relative sliding velocity each (contact FS = 2, FD = the table id)", lsdyna_deck.SUFFIX,
                     True, "linearly between the table's pressures and along each curve"),
    "abaqus": Format("abaqus", "Abaqus *SURFACE INTERACTION with a tabulated *FRICTION (mu against slip rate and "
                     "contact pressure)", abaqus_friction.SUFFIX, False,
                     "linearly in slip rate and contact pressure (and in field variable 1, beta)"),
    "table": Format("table", "neutral JSON table of mu and its standard error", neutral_table.SUFFIX, False,
                    neutral_table.RULE),
}


@dataclass(frozen=True)
class DebrisState:
    """One debris state of an export: its beta (None: beta is an axis of the file, or the state is a slide), its tag
    in the file names when an export has several states, what it is in words, how it was chosen (a JSON record), and
    for a slide (``--slide``) its length [m] and the beta the point starts from: the file's beta at each (P, v) is then
    the debris a sheet point makes sliding that far there (:meth:`ExportedLaw.beta_after_slide`)."""

    beta: float | None
    label: str
    description: str
    record: dict = field(default_factory=dict)
    slide: float | None = None
    beta_initial: float = 0.0

    @property
    def is_axis(self) -> bool:
        """Whether beta is an axis of the file (no debris state chosen)."""
        return self.beta is None and self.slide is None

    def beta_at(self, law: ExportedLaw, pressure, velocity):
        """The state's beta at the points (SI, broadcast together): its beta, or its slide's debris there."""
        if self.slide is not None:
            return law.beta_after_slide(pressure, velocity, self.slide, self.beta_initial)
        return float(self.beta)


AXIS_STATE = DebrisState(None, "", "none chosen: beta is an axis of the file", {"beta": None,
                                                                                  "how": "an axis of the file"})


@dataclass(frozen=True)
class ExportRequest:
    """What to export (SI throughout; ``units`` is the files' system)."""

    format: str
    out: Path
    states: tuple
    units: UnitSystem
    band: float | None = None
    pressure_range: tuple | None = None
    beta_levels: tuple | None = None
    allow_unsimulated: bool = False
    tolerance: float = DEFAULT_TOLERANCE
    table_id: int = lsdyna_deck.DEFAULT_TABLE_ID
    interaction_name: str = abaqus_friction.DEFAULT_NAME
    command: str = ""
    notes: tuple = ()  # further lines for every header (the multi-pass option chosen, ...)


@dataclass(frozen=True)
class ExportedFile:
    """One file written: its path, role (nominal, upper, lower), debris state, grid size, the accuracy reached, and
    whether it writes one velocity (the law does not depend on it: :func:`velocity_free`)."""

    path: Path
    role: str
    state: DebrisState
    shape: tuple
    accuracy: float
    tolerance: float
    checked: int
    unsimulated: str
    warnings: tuple
    one_velocity: bool = False


@dataclass(frozen=True)
class ExportResult:
    """The files of an export and what the command says about them (``notes``: lines about the law, for the error
    stream: an uncalibrated law and its one-pass drop, :mod:`tribocosim.cosim.apps.export_friction`)."""

    files: tuple
    range_line: str
    beyond: str
    velocity_line: str = ""
    notes: tuple = ()

    def summary(self) -> list[str]:
        """Lines for the command's output (its warnings apart: :meth:`warning_lines`)."""
        out = []
        for f in self.files:
            sizes = [f"{f.shape[0]} pressures",
                     "1 velocity (mu does not depend on it)" if f.one_velocity else f"{f.shape[1]} velocities",
                     *(f"{n} beta levels" for n in f.shape[2:])]
            out.append(f"wrote {f.path} ({f.role}; {' x '.join(sizes)}): the FE code's linear interpolation of it "
                       f"reproduces tribocosim's mu within {percent_up(f.accuracy)} % (target {100 * f.tolerance:g} "
                       f"%) in the range ({f.checked} points checked)")
            out += [f"  unsimulated: {f.unsimulated}"] if f.unsimulated else []
        return out + ([self.velocity_line] if self.velocity_line else []) + [self.range_line,
                                                                             f"beyond it: {self.beyond}"]

    def warning_lines(self) -> list[str]:
        """One line per warning of a file written (the files are written all the same; each holds its warnings in
        its header): ``<file>: <warning>``, for the command's error stream."""
        return [f"{f.path.name}: {w}" for f in self.files for w in f.warnings]


def _nodes_in(axis: np.ndarray, low: float, high: float) -> tuple:
    """``low``, the axis's nodes strictly inside (low, high), ``high``."""
    inner = [float(x) for x in axis if low * (1 + END_TOLERANCE) < x < high * (1 - END_TOLERANCE)]
    return tuple([low, *inner, high]) if high > low else (low,)


def code_version() -> str:
    """The package's version and the native core library's name, for a file's header."""
    return _code_version()


def _code_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    from tribocosim.components.native.toolchain.library import core

    try:
        v = version("tribocosim")
    except PackageNotFoundError:  # pragma: no cover - a source tree without an install
        v = "(not installed)"
    return f"{v} (native core {core().path.name})"


def _pressure_range(law: ExportedLaw, request: ExportRequest) -> tuple[float, float]:
    lo_axis, hi_axis = law.pressure_axis
    if request.pressure_range is None:
        return lo_axis, hi_axis
    lo, hi = (float(x) for x in request.pressure_range)
    u = request.units
    shown = f"{u.pressure_to_file(lo):g} {u.pressure_to_file(hi):g}"
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ParameterError(f"--pressure-range {shown} {u.pressure}: two finite pressures, the lower first")
    if lo < lo_axis * (1 - END_TOLERANCE) or hi > hi_axis * (1 + END_TOLERANCE):
        raise ParameterError(f"--pressure-range {shown} {u.pressure} leaves the table's pressure axis "
                             f"[{u.pressure_to_file(lo_axis):g}, {u.pressure_to_file(hi_axis):g}] {u.pressure}")
    return max(lo, lo_axis), min(hi, hi_axis)


def check_request(law: ExportedLaw, request: ExportRequest) -> Format:
    """The request's format; ParameterError naming the option of a request that cannot be written (checked before
    anything is sampled)."""
    if request.format not in FORMATS:
        raise ParameterError(f"FORMAT {request.format!r} is not an export format; choose one of {', '.join(FORMATS)}")
    fmt = FORMATS[request.format]
    if not (math.isfinite(request.tolerance) and 0 < request.tolerance <= 0.5):
        raise ParameterError(f"--tolerance {request.tolerance!r}: a relative deviation in (0, 0.5] is required")
    if request.band is not None:
        if not (math.isfinite(request.band) and request.band > 0):
            raise ParameterError(f"--band {request.band!r}: a number of standard errors above 0 is required")
        law.check_band()
    if not request.states:
        raise ParameterError("no debris state: give --beta or --passes, or none for a beta axis")
    if fmt.needs_state and any(s.is_axis for s in request.states):
        raise ParameterError(f"FORMAT {fmt.name} needs a debris state, --beta B, --passes N or --slide S: an LS-DYNA "
                             "friction table has no axis for the debris (several states: several files)")
    if request.beta_levels is not None and any(not s.is_axis for s in request.states):
        raise ParameterError("--beta-levels gives the levels of a beta axis; with --beta, --passes or --slide the file "
                             "holds one debris state")
    if not 1 <= int(request.table_id) <= lsdyna_deck.MAX_ID - 10_000:
        raise ParameterError(f"--table-id {request.table_id}: an id in [1, {lsdyna_deck.MAX_ID - 10_000}] is required "
                             "(the curves take the ids after it)")
    check_target(request.out)
    return fmt


def _beta_nodes(law: ExportedLaw, request: ExportRequest, prange, vrange, cap: float) -> AxisSpec:
    """The beta axis of a file without a debris state: ``--beta-levels`` as given, or the table's beta nodes up to
    the highest level simulated everywhere in the range (the table's last with ``allow_unsimulated``), below the
    cap."""
    b0, b1 = law.beta_axis
    if request.beta_levels is not None:
        levels = np.unique(np.asarray(request.beta_levels, dtype=float))
        if levels.size < 2 or not np.all(np.isfinite(levels)):
            raise ParameterError(f"--beta-levels {list(request.beta_levels)}: at least two finite levels")
        bad = levels[(levels < b0) | (levels > min(b1, cap))]
        if bad.size:
            raise ParameterError(f"--beta-levels: {bad[0]:g} is outside the table's beta axis [{b0:g}, {b1:g}] or "
                                 f"above the cap of beta in the range, {cap:.6g} (Eq. 24)")
        return AxisSpec("beta", tuple(levels), refine=False)
    top = b1 if request.allow_unsimulated else law.simulated_beta_top(prange, vrange)
    top = min(top, cap)
    return AxisSpec("beta", _nodes_in(law.table.beta, b0, top))


def _check_beta(law: ExportedLaw, beta: float, cap: float, state: DebrisState) -> None:
    b0, b1 = law.beta_axis
    how = "--beta" if state.record.get("how") == "given" else f"the debris state {state.description!r}"
    if not math.isfinite(beta) or beta < b0 or beta > b1 * (1 + END_TOLERANCE):
        raise ParameterError(f"{how}: beta = {beta!r} is outside the table's beta axis [{b0:g}, {b1:g}]")
    if beta > cap * (1 + END_TOLERANCE):
        raise ParameterError(f"{how}: beta = {beta!r} is above the cap of beta in the range, {cap:.6g} (Eq. 24: "
                             "where the flake-borne area reaches the contact area); the strip-draw model never "
                             "holds more debris")


class _Flags:
    """The points of an export's evaluations whose lookups read unsimulated nodes."""

    def __init__(self):
        self.count, self.total = 0, 0
        self.pressure = [math.inf, -math.inf]
        self.beta = [math.inf, -math.inf]

    def add(self, flagged: np.ndarray, pressure: np.ndarray, beta) -> None:
        self.total += flagged.size
        if not flagged.any():
            return
        self.count += int(flagged.sum())
        p = pressure[flagged]
        b = np.broadcast_to(beta, flagged.shape)[flagged]
        self.pressure = [min(self.pressure[0], p.min()), max(self.pressure[1], p.max())]
        self.beta = [min(self.beta[0], b.min()), max(self.beta[1], b.max())]

    def where(self, units: UnitSystem) -> str:
        p0, p1 = (units.pressure_to_file(x) for x in self.pressure)
        text = f"contact pressure {p0:.4g}-{p1:.4g} {units.pressure}"
        return text + (f", beta {self.beta[0]:.4g}-{self.beta[1]:.4g}" if self.beta[1] > self.beta[0] else
                       f", beta {self.beta[0]:.4g}")


def _refusal(law: ExportedLaw, request: ExportRequest, state: DebrisState, flags: _Flags, prange) -> str:
    u = request.units
    how = state.record.get("how")
    if how == "given":
        what = f"--beta {state.beta:g}"
    elif how == "passes":
        what = f"--passes {state.record.get('after_pass')} (beta = {state.beta:.6g} after that pass)"
    elif how == "slide":
        what = f"--slide {state.slide / u.length_scale:g} {u.length}"
    elif request.beta_levels is not None:
        what = f"the beta axis (--beta-levels {' '.join(f'{b:g}' for b in request.beta_levels)})"
    else:
        what = "the beta axis"
    hint = ""
    above = law.table.pressure[law.table.pressure > flags.pressure[1] * (1 + END_TOLERANCE)]
    if not state.is_axis and above.size and flags.pressure[0] <= prange[0] * (1 + END_TOLERANCE):
        hint = (f"--pressure-range {u.pressure_to_file(above[0]):g} {u.pressure_to_file(prange[1]):g} exports the "
                "range where it was simulated; ")
    return (f"{what}: {flags.count} of {flags.total} lookups in the exported range read friction-table nodes the "
            f"mesoscale campaign did not simulate ({flags.where(u)}; the table's simulated levels: "
            "docs/physics/table_domain.md); " + hint + "--allow-unsimulated writes them marked")


def _range_line(units: UnitSystem, prange, vrange, betas) -> str:
    u = units
    text = (f"range: contact pressure {u.pressure_to_file(prange[0]):g}-{u.pressure_to_file(prange[1]):g} "
            f"{u.pressure}, relative sliding velocity {u.velocity_to_file(vrange[0]):g}-"
            f"{u.velocity_to_file(vrange[1]):g} {u.velocity}")
    return text + (f", beta {betas[0]:.6g}-{betas[-1]:.6g}" if betas is not None else "")


def _beyond(fmt: Format, units: UnitSystem, prange, vrange, betas, one_velocity: bool = False) -> str:
    u = units
    code = {"lsdyna": "LS-DYNA", "abaqus": "Abaqus", "table": "a reader following the rule"}[fmt.name]
    p0, p1 = (f"{u.pressure_to_file(x):g} {u.pressure}" for x in prange)
    v1 = f"{u.velocity_to_file(vrange[1]):g} {u.velocity}"
    text = (f"{code} holds the end values (clamps): below {p0} it reads mu at {p0}, above {p1} mu at {p1}, "
            + (f"at any velocity (above {v1} too) mu of its one velocity" if one_velocity else
               f"above {v1} mu at {v1}"))
    if betas is not None:
        text += f", beta outside {betas[0]:.6g}-{betas[-1]:.6g} the end level"
    return text + "; tribocosim's table holds no simulation there"


def run_export(law: ExportedLaw, request: ExportRequest, log=None) -> ExportResult:
    """Sample, check and write the export (module docstring); ParameterError naming the option when the request
    cannot be written, and then no file is written. ``log`` (one line of text) hears of the progress of an export
    that samples long (several debris states, a refinement that passes its first rounds)."""
    fmt = check_request(law, request)
    units = request.units
    prange = _pressure_range(law, request)
    vrange = law.velocity_axis
    p_nodes = _nodes_in(law.table.pressure, *prange)
    v_nodes = _nodes_in(law.table.velocity, *vrange)
    cap = min(law.cap(p, v) for p in p_nodes for v in v_nodes)
    several = len(request.states) > 1
    roles = ("nominal",) if request.band is None else ("nominal", "upper", "lower")
    code_version = _code_version()
    contents, files = {}, []
    range_line = beyond = velocity_line = ""
    next_id = int(request.table_id)  # several states share a deck: each its own table and curve ids, own name
    for state in request.states:
        specs = [AxisSpec("pressure", p_nodes, geometric=True), AxisSpec("velocity", v_nodes)]
        if state.is_axis:
            specs.append(_beta_nodes(law, request, prange, vrange, cap))
        elif state.slide is None:
            _check_beta(law, float(state.beta), cap, state)
        flags = _Flags()

        def evaluate(points, state=state, flags=flags):
            p, v = points[0], points[1]
            b = points[2] if state.is_axis else state.beta_at(law, p, v)
            mu, flagged = law.mu(p, v, b)
            flags.add(flagged, p, b)
            columns = [mu]
            if request.band is not None:
                columns += list(law.band(p, v, b, request.band))
            return np.stack(columns, axis=-1)

        if several and log is not None:
            log(f"sampling {state.description} ({len(files) // len(roles) + 1} of {len(request.states)})")
        grid = sample(evaluate, specs, request.tolerance, ACCURACY_FLOOR, log=log)
        if flags.count and not request.allow_unsimulated:
            raise ParameterError(_refusal(law, request, state, flags, prange))
        betas = grid.axes[2] if state.is_axis else None
        range_line = _range_line(units, prange, vrange, betas)
        one_velocity = velocity_free(grid)
        beyond = _beyond(fmt, units, prange, vrange, betas, one_velocity)
        if one_velocity:
            velocity_line = _velocity_line(units, vrange, grid.axes[1], betas is not None, fmt)
            grid = _one_velocity(grid)
        mesh = np.meshgrid(*grid.axes, indexing="ij")
        node_beta = mesh[2] if betas is not None else state.beta_at(law, mesh[0], mesh[1])
        _, node_flagged = law.mu(mesh[0], mesh[1], node_beta)
        unsimulated = "" if not flags.count else (
            f"{flags.count} of {flags.total} lookups in the range read friction-table nodes the mesoscale campaign "
            f"did not simulate ({flags.where(units)}); written as asked (--allow-unsimulated), "
            f"{int(node_flagged.sum())} of the file's {node_flagged.size} nodes marked")
        for r, role in enumerate(roles):
            path = tagged(request.out, state.label if several else "", "" if role == "nominal" else role)
            values = grid.values[..., r]
            warnings = tuple(value_warnings(law, values)) + _accuracy_warning(grid, request)
            facts = FileFacts(
                format_title=fmt.title, role=role, fe_rule=fmt.rule, fe_beyond=beyond,
                provenance=law.provenance(), state=state.description, units_line=units.header(),
                range_lines=(range_line,), accuracy=grid.accuracy, largest=grid.largest, tolerance=grid.tolerance,
                checked=grid.checked, floor=ACCURACY_FLOOR,
                band=_band_words(law, request.band, role), unsimulated=unsimulated, warnings=warnings,
                code_version=code_version, command=request.command,
                notes=request.notes + _notes(law) + ((velocity_line,) if one_velocity else ()))
            contents[path] = _render(fmt, facts, grid, values, law, request, state, node_flagged, next_id,
                                     _interaction_name(request.interaction_name, state.label if several else ""),
                                     vrange if one_velocity else None)
            files.append(ExportedFile(path, role, state, tuple(a.size for a in grid.axes), grid.accuracy,
                                      grid.tolerance, grid.checked, unsimulated, warnings, one_velocity))
        next_id += grid.axes[0].size + 1  # the table's id, then one curve id per pressure
        if next_id > lsdyna_deck.MAX_ID:
            raise ParameterError(f"--table-id {request.table_id}: the tables and curves of {len(request.states)} "
                                 f"debris states need ids up to {next_id - 1}, above {lsdyna_deck.MAX_ID}")
    write_all(contents)
    return ExportResult(tuple(files), range_line, beyond,
                        velocity_line if all(f.one_velocity for f in files) else "")


def velocity_free(grid) -> bool:
    """Whether the law of a sampled grid does not depend on the velocity: mu (and the band's) at every pressure and
    beta of the grid equal at every velocity of it (the table's velocity nodes in the range and any the refinement
    added) within :data:`VELOCITY_RTOL`. Then the FE code's reading of the grid is the same with one velocity, and the
    check of the grid (at points between the nodes and at random points of the range, :mod:`.grid_refinement`) holds
    for it. The table law is linear in v between the table's velocity nodes, so a law equal at them is constant in v
    over the range."""
    values = grid.values
    if grid.axes[1].size < 2:
        return False
    spread = relative_deviation(values, values[:, :1], ACCURACY_FLOOR)
    return bool(np.all(spread <= VELOCITY_RTOL))


def _one_velocity(grid):
    """The grid with its velocity axis reduced to the range's lower end (the law does not depend on it)."""
    return dataclasses.replace(grid, axes=(grid.axes[0], grid.axes[1][:1], *grid.axes[2:]),
                               values=grid.values[:, :1])


def _velocity_line(units: UnitSystem, vrange, velocities, with_beta: bool, fmt: Format) -> str:
    u = units
    at = ", ".join(f"{u.velocity_to_file(v):g}" for v in velocities)
    how = {"lsdyna": f"each curve holds two equal points, at {u.velocity_to_file(vrange[0]):g} and "
                     f"{u.velocity_to_file(vrange[1]):g} {u.velocity}: an LS-DYNA curve has two points or more",
           "abaqus": f"one line per pressure{' and beta level' if with_beta else ''}, the slip rate left blank: no "
                     "slip-rate dependence",
           "table": "the velocity axis holds one value, its range beside it"}[fmt.name]
    return (f"velocity: mu does not depend on the relative sliding velocity over {u.velocity_to_file(vrange[0]):g}-"
            f"{u.velocity_to_file(vrange[1]):g} {u.velocity}: at every pressure{' and beta' if with_beta else ''} of "
            f"the file it is the same at {at} {u.velocity} (within {VELOCITY_RTOL:g} of mu), because the table is: its "
            "slides do not depend on v in the overdamped regime (docs/physics/table_domain.md) and no hydrodynamic "
            f"effect is modelled; one velocity is written ({how})")


def _interaction_name(name: str, label: str) -> str:
    """The *SURFACE INTERACTION name of a debris state when an export has several (``NAME_BETA0_1``): Abaqus names
    are letters, digits and underscores."""
    if not label:
        return name
    return f"{name}_" + "".join(c if c.isalnum() else "_" for c in label.upper())


def _accuracy_warning(grid, request: ExportRequest) -> tuple:
    if grid.reached:
        return ()
    why = ("the --beta-levels given are too far apart for it" if request.beta_levels is not None else
           "the refinement stopped at its limits (grid_refinement.py)")
    return (f"the FE code's reading of this file deviates from tribocosim's mu by up to {percent_up(grid.accuracy)} %, "
            f"above the target {100 * grid.tolerance:g} %: {why}",)


def _band_words(law: ExportedLaw, k: float | None, role: str) -> str:
    if k is None:
        return ""
    scale = law.scale_interval
    extra = (f" and the calibration's scale s = {scale[0]:.6g} +- {scale[1]:.2g} (in quadrature)" if scale else "")
    held = {"nominal": f"mu; its .upper and .lower files hold mu +- {k:g} se(mu)", "upper": f"mu + {k:g} se(mu)",
            "lower": f"mu - {k:g} se(mu)"}[role]
    return (f"this file holds {held}, clipped to [0, mu0], se(mu) from the table's ensemble standard error{extra} "
            "(components/friction_export/exported_law.py); the three files share ids and nodes")


def _notes(law: ExportedLaw) -> tuple:
    notes = ["velocity: the FE code's relative sliding velocity of the contact; the strip-draw test's is the "
             "drawing speed (friction_velocity = grip)"]
    vmeta = law.table.metadata.get("axes", {}).get("velocity", {})
    if vmeta.get("quasi_static_row"):
        notes.append(f"the table's velocity row at 0 holds the values of its slowest simulated velocity "
                     f"({min(vmeta.get('campaign', [float('nan')])):g} m/s): mu is constant below it")
    return tuple(notes)


def _render(fmt: Format, facts: FileFacts, grid, values, law: ExportedLaw, request: ExportRequest,
            state: DebrisState, node_flagged: np.ndarray, table_id: int, interaction_name: str,
            one_velocity: tuple | None) -> str:
    """The text of one file; ``one_velocity``: the velocity range of a law that does not depend on it (the grid holds
    one velocity, written as each format allows: :func:`_velocity_line`)."""
    u = request.units
    header = header_lines(facts)
    pressures = u.pressure_to_file(grid.axes[0])
    velocities = u.velocity_to_file(grid.axes[1])
    mesh = np.meshgrid(*grid.axes, indexing="ij")
    node_beta = mesh[2] if state.is_axis else np.broadcast_to(state.beta_at(law, mesh[0], mesh[1]), mesh[0].shape)
    if fmt.name == "lsdyna":
        comments = {}
        for i in range(pressures.size):
            text = []
            if state.slide is not None:
                lo, hi = float(node_beta[i].min()), float(node_beta[i].max())
                text.append(f"the debris after the slide: beta = {lo:.6g}" + (f"-{hi:.6g} over the velocities"
                                                                               if hi > lo else ""))
            if node_flagged[i].any():
                text.append("UNSIMULATED: lookups at this pressure read table nodes not simulated")
            if text:
                comments[i] = text
        if one_velocity is not None:  # a curve has two points or more: the range's ends, mu equal at both
            velocities = u.velocity_to_file(np.asarray(one_velocity, dtype=float))
            values = np.repeat(values, 2, axis=1)
        return lsdyna_deck.render(header, pressures, velocities, values, table_id, u, comments)
    if fmt.name == "abaqus":
        betas = grid.axes[2] if state.is_axis else None
        return abaqus_friction.render(header, None if one_velocity is not None else velocities, pressures, values, u,
                                      betas, interaction_name)
    velocity_axis = {"name": "velocity", "unit": u.velocity, "values": velocities.tolist()}
    if one_velocity is not None:
        velocity_axis.update(independent=True, range=u.velocity_to_file(np.asarray(one_velocity)).tolist())
    axes = [{"name": "pressure", "unit": u.pressure, "values": pressures.tolist()}, velocity_axis]
    if state.is_axis:
        axes.append({"name": "beta", "unit": "1", "values": grid.axes[2].tolist()})
    mu_se = law.standard_error(mesh[0], mesh[1], node_beta) if law.table.version >= 3 else None
    table_axes = (law.table.pressure, law.table.velocity, law.table.beta)
    on_node = [np.isclose(m[..., None], ax, rtol=END_TOLERANCE, atol=0).any(axis=-1)
               for m, ax in zip(mesh, table_axes)]
    if not state.is_axis:
        on_node.append(np.isclose(np.asarray(node_beta)[..., None], law.table.beta, rtol=END_TOLERANCE,
                                  atol=0).any(axis=-1))
    provenance = {**law.provenance(), "code_version": facts.code_version, "command": facts.command}
    band = None if request.band is None else {"k": request.band, "role": facts.role, "definition": facts.band}
    debris = {"beta": state.beta, "description": state.description, **state.record}
    if state.slide is not None:
        debris["beta_at_nodes"] = np.asarray(node_beta).tolist()
    return neutral_table.render(
        role=facts.role, axes=axes, mu=values, mu_se=mu_se, simulated=~node_flagged,
        table_node=np.logical_and.reduce(on_node), accuracy=grid.accuracy, tolerance=grid.tolerance,
        checked=grid.checked, debris_state=debris, units=u, provenance=provenance, band=band,
        warnings=list(facts.warnings), header=header)
