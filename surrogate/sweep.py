"""The sweep of a mesoscale campaign: a TOML file over P, v, beta, placements and surfaces.

A sweep names the grid of the friction table (Sec. 6; docs/model.md section 4-5) and the settings shared
by every slide. Example (SI units everywhere)::

    name = "quick"
    description = "64^2, 250 um: the default table"

    [grid]
    pressure = [5e6, 15e6, 30e6]   # mean contact pressure p [Pa]
    velocity = [1.0, 10.0, 50.0]   # sliding velocity v0 [m/s]
    seeds = [11, 12, 13]           # flake placements per point (>= 3, Sec. 6.2)
    particle_free = true           # also run n_flakes = 0 (beta = 0) per (P, v, surface)

    [[flakes]]                     # one debris level each: beta = count pi (d/2)^2 / L^2 (Eq. 10)
    count = 5
    diameter = 12e-6
    # optional: min_pressure = 10e6   only at grid pressures >= this [Pa]
    #           velocities = [0.08]   only at these grid velocities [m/s]
    #           seeds = [11]          placements of this level (default: the grid's)

    [[surfaces]]                   # surface pairs; the ensemble runs over surfaces x seeds
    sheet_seed = 1
    tool_seed = 2                  # optional: wavelength_ratio, hurst, *_rms_height, *_rolloff_wavelength
                                   # (they shape generated sides only: a measured pair does not check them)

    [[surfaces]]                   # a measured sheet (any format SurfaceTopography reads; the measured extra)
    sheet_file = "scans/sheet.x3p" # relative to the sweep file's folder
    tool_seed = 2                  # a generated tool (or tool_file = "...")
    # optional: surface_detrend = "plane" | "curvature" | "mean", surface_periodization = "smooth" |
    #           "synthesis" | "none", surface_fill_missing = false (tribocosim.surrogate.measured_surfaces)

    [slide]                        # every other SlideConfig key (surrogate.slide_config)
    n = 64
    size = 250e-6

    [table]
    mu0 = 0.15                     # particle-free friction coefficient (calibration, Eq. 6)
    quasi_static_row = false       # a v = 0 row: the slowest grid velocity's values (the plateau)

    [adaptive]                     # optional: more placements where the ensemble is noisy
    target_relative_se = 0.10      # standard error of <A_p> / <A_p> at a node
    extra_seeds = [14, 15, 16]     # added one at a time (on every surface pair) while above target

A measured file's path is resolved against the sweep file's folder and its SHA-256 recorded with it
(``sheet_file_sha256``, ``tool_file_sha256``): the case ids hold the files' contents, and a file that
changes later is refused by the slide that reads it. The keys that the grid sweeps (``pressure``, ``v0``,
``n_flakes``, ``flake_diameter``, ``flake_seed``, ``sheet_seed``, ``tool_seed``, and the files and their hashes)
are refused in ``[slide]``. Every problem is reported as a :class:`~tribocosim.errors.ParameterError`
naming the file, the line, the key, its value and what is allowed.

Presets live in ``surrogate/presets/<name>.toml`` (:func:`preset_path`).
"""

from __future__ import annotations

import math
import re
import tomllib
from dataclasses import asdict, dataclass, fields
from pathlib import Path

from tribocosim.errors import ParameterError

from .measured_surfaces import MEASURED_KEYS, file_sha256
from .slide_config import SlideConfig, error_key

PRESET_DIR = Path(__file__).resolve().parent / "presets"

#: SlideConfig keys the grid sets per case (not allowed in [slide])
SWEPT_KEYS = ("pressure", "v0", "n_flakes", "flake_diameter", "flake_seed", "sheet_seed", "tool_seed",
              "sheet_file", "tool_file", "sheet_file_sha256", "tool_file_sha256")
#: SlideConfig keys a [[surfaces]] entry may set besides the two seeds
SURFACE_KEYS = ("sheet_seed", "tool_seed", "wavelength_ratio", "hurst", "sheet_rms_height",
                "tool_rms_height", "sheet_rolloff_wavelength", "tool_rolloff_wavelength", *MEASURED_KEYS)
_TOP_KEYS = ("name", "description", "grid", "flakes", "surfaces", "slide", "table", "adaptive")
_GRID_KEYS = ("pressure", "velocity", "seeds", "particle_free")
_FLAKE_KEYS = ("count", "diameter", "min_pressure", "velocities", "seeds")
_TABLE_KEYS = ("mu0", "quasi_static_row")
_ADAPTIVE_KEYS = ("target_relative_se", "extra_seeds")
#: members (placements x surface pairs) a debris level needs at every grid point
MIN_MEMBERS = 2


@dataclass(frozen=True)
class TableSettings:
    """How the table is made from the campaign (see :mod:`tribocosim.surrogate.table_build`).

    Attributes
    ----------
    mu0 : float
        Particle-free friction coefficient, the calibration of tau0 (Eq. 6, docs/model.md section 4).
    quasi_static_row : bool
        Add a v = 0 row holding the slowest grid velocity's values: the quasi-static limit, where A_p has
        reached its plateau (the sweep must show it: docs/physics/table_domain.md).
    """

    mu0: float = 0.15
    quasi_static_row: bool = False


@dataclass(frozen=True)
class FlakeLevel:
    """One debris level of a sweep and where it is simulated.

    Attributes
    ----------
    count : int
        Flakes per slide.
    diameter : float
        d_p [m].
    min_pressure : float
        Simulated only at grid pressures >= this [Pa] (0: every pressure).
    velocities : tuple of float or None
        Simulated only at these grid velocities [m/s] (None: every one).
    seeds : tuple of int or None
        Placement seeds of this level (None: the grid's).
    """

    count: int
    diameter: float
    min_pressure: float = 0.0
    velocities: tuple | None = None
    seeds: tuple | None = None

    def at(self, pressure: float, velocity: float) -> bool:
        """True when this level is simulated at (pressure, velocity)."""
        return pressure >= self.min_pressure and (self.velocities is None or velocity in self.velocities)


@dataclass(frozen=True)
class AdaptiveSettings:
    """More placements where a node's ensemble is noisy (:func:`tribocosim.surrogate.campaign.adaptive_cases`).

    Attributes
    ----------
    target_relative_se : float
        The standard error of the member mean of <A_p>/A0 over that mean, at every node with flakes.
    extra_seeds : tuple of int
        Placement seeds added one at a time, on every surface pair, to the nodes above the target.
    """

    target_relative_se: float = 0.10
    extra_seeds: tuple = ()


@dataclass(frozen=True)
class Sweep:
    """A validated sweep definition (see the module docstring for the file format)."""

    name: str
    description: str
    pressures: tuple
    velocities: tuple
    seeds: tuple
    flakes: tuple  # (FlakeLevel, ...)
    surfaces: tuple  # (dict of SURFACE_KEYS, ...)
    slide: dict
    particle_free: bool = True
    table: TableSettings = TableSettings()
    adaptive: AdaptiveSettings | None = None
    source: str = ""

    def base_config(self) -> SlideConfig:
        """The SlideConfig of the [slide] section with the first surface pair: the domain, moduli and other settings
        every slide shares (a pair's keys apply to its generated sides, which [slide] alone does not know)."""
        return SlideConfig(**{**self.slide, **self.surfaces[0]})

    def flake_beta(self, count: int, diameter: float) -> float:
        """beta = count pi (d/2)^2 / L^2 (Eq. 10) on this sweep's domain."""
        size = self.base_config().size
        return count * math.pi * (0.5 * diameter) ** 2 / size**2

    def to_dict(self) -> dict:
        """Plain dict (JSON-serialisable) of the whole definition, for the table metadata."""
        d = asdict(self)
        d["flakes"] = [{**asdict(fl), "beta": self.flake_beta(fl.count, fl.diameter)} for fl in self.flakes]
        return d


def parse_sweep_dict(data: dict) -> Sweep:
    """The :class:`Sweep` of its :meth:`Sweep.to_dict` (as recorded in a table's metadata)."""
    try:
        flakes = tuple(FlakeLevel(int(f["count"]), float(f["diameter"]), float(f.get("min_pressure", 0.0)),
                                  None if f.get("velocities") is None else tuple(f["velocities"]),
                                  None if f.get("seeds") is None else tuple(f["seeds"]))
                       for f in data["flakes"])
        tset = data.get("table") or {}
        ad = data.get("adaptive")
        return Sweep(name=data["name"], description=data.get("description", ""),
                     pressures=tuple(data["pressures"]), velocities=tuple(data["velocities"]),
                     seeds=tuple(data["seeds"]), flakes=flakes, surfaces=tuple(dict(x) for x in data["surfaces"]),
                     slide=dict(data["slide"]), particle_free=bool(data.get("particle_free", True)),
                     table=TableSettings(float(tset.get("mu0", TableSettings.mu0)),
                                         bool(tset.get("quasi_static_row", False))),
                     adaptive=None if ad is None else AdaptiveSettings(float(ad["target_relative_se"]),
                                                                       tuple(ad["extra_seeds"])),
                     source=data.get("source", ""))
    except (KeyError, TypeError, ValueError) as exc:
        raise ParameterError(f"recorded sweep is incomplete ({exc!r}); it cannot be rebuilt") from None


def preset_path(name: str) -> Path:
    """Path of the preset ``name`` (``surrogate/presets/<name>.toml``)."""
    known = sorted(p.stem for p in PRESET_DIR.glob("*.toml"))
    if name not in known:
        raise ParameterError(f"preset = {name!r} is not known; available: {known}")
    return PRESET_DIR / f"{name}.toml"


def load_sweep(path: str | Path) -> Sweep:
    """Read and validate a sweep file.

    Raises
    ------
    ParameterError
        Naming the file, the line, the key, its value and what is allowed.
    """
    path = Path(path)
    try:
        text = path.read_text()
    except FileNotFoundError:
        raise ParameterError(f"sweep file {str(path)!r} does not exist") from None
    return parse_sweep(text, source=str(path))


def load_preset(name: str) -> Sweep:
    """The sweep of the preset ``name``."""
    return load_sweep(preset_path(name))


class _Lines:
    """Line numbers of the keys of a TOML text: (section, entry index, key) -> line."""

    _header = re.compile(r"^\s*(\[\[?)\s*([A-Za-z0-9_.\-]+)\s*\]\]?")
    _key = re.compile(r"^\s*([A-Za-z0-9_\-]+|\"[^\"]*\")\s*=")

    def __init__(self, text: str):
        self.lines: dict = {}
        self.headers: dict = {}
        section, index, counts = "", 0, {}
        for no, line in enumerate(text.splitlines(), start=1):
            m = self._header.match(line)
            if m:
                section = m.group(2)
                if m.group(1) == "[[":
                    index = counts.get(section, -1) + 1
                    counts[section] = index
                else:
                    index = 0
                self.headers.setdefault((section, index), no)
                continue
            m = self._key.match(line)
            if m:
                self.lines.setdefault((section, index, m.group(1).strip('"')), no)

    def of(self, section: str, key: str | None = None, index: int = 0) -> int | None:
        if key is None:
            return self.headers.get((section, index))
        return self.lines.get((section, index, key)) or self.headers.get((section, index))


class _Checker:
    def __init__(self, text: str, source: str):
        self.where = _Lines(text)
        self.source = source

    def fail(self, section: str, key: str | None, message: str, index: int = 0):
        line = self.where.of(section, key, index)
        at = f", line {line}" if line else ""
        sec = f"[{section}]" if section else "top level"
        if section in ("flakes", "surfaces"):
            sec = f"[[{section}]] entry {index + 1}"
        name = f" {key}" if key else ""
        raise ParameterError(f"sweep file {self.source}{at}: {sec}{name}: {message}")

    def unknown(self, section: str, data: dict, allowed, index: int = 0):
        bad = sorted(set(data) - set(allowed))
        if bad:
            self.fail(section, bad[0], f"unknown key {bad[0]!r}; allowed: {sorted(allowed)}", index)

    def numbers(self, section, key, value, *, positive=True, allow_zero=False, integer=False,
                min_len=1, unique=True, index=0) -> tuple:
        kind = "integers" if integer else "numbers"
        if not isinstance(value, list) or len(value) < min_len:
            self.fail(section, key, f"= {value!r}; a list of at least {min_len} {kind} is required", index)
        for x in value:
            ok_type = (isinstance(x, int) and not isinstance(x, bool)) if integer else (
                isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x))
            if not ok_type or (positive and (x < 0 or (x == 0 and not allow_zero))):
                need = ">= 0" if allow_zero else "> 0"
                self.fail(section, key, f"has the value {x!r}; every entry must be one of the "
                          f"finite {kind} {need}" if positive else f"has the value {x!r}", index)
        if unique and len(set(value)) != len(value):
            self.fail(section, key, f"= {value!r} has repeated values; each value once", index)
        return tuple(sorted(value)) if not integer else tuple(value)


def _measured_file(chk: _Checker, entry: dict, side: str, folder: Path, index: int) -> None:
    """Resolve a [[surfaces]] entry's ``{side}_file`` against ``folder`` and record (or check) its SHA-256."""
    key = f"{side}_file"
    name = entry[key]
    if not isinstance(name, str) or not name:
        chk.fail("surfaces", key, f"= {name!r}; a file name is required", index)
    path = (folder / name).resolve()
    if not path.is_file():
        chk.fail("surfaces", key, f"= {name!r}: {str(path)!r} is not a file", index)
    digest = file_sha256(path)
    recorded = entry.get(f"{key}_sha256")
    if recorded is not None and recorded != digest:
        chk.fail("surfaces", f"{key}_sha256", f"= {recorded!r}, but {str(path)!r} has SHA-256 {digest}: the "
                 "file has changed", index)
    entry[key], entry[f"{key}_sha256"] = str(path), digest


def _surfaces(chk: _Checker, data: dict, slide: dict, source: str) -> list[dict]:
    """The [[surfaces]] entries, each checked together with [slide] as the slides of the pair will be made: the keys
    that shape a generated surface apply to the pair's generated sides only (:attr:`SlideConfig.generated_sides`),
    so [slide] is never checked alone. An error about a key neither sets is about its default and says so."""
    defaults = {f.name: f.default for f in fields(SlideConfig)}
    surfaces_raw = data.get("surfaces", [{"sheet_seed": defaults["sheet_seed"], "tool_seed": defaults["tool_seed"]}])
    if not isinstance(surfaces_raw, list) or not surfaces_raw:
        chk.fail("", "surfaces", "must be one or more [[surfaces]] entries")
    surfaces = []
    for i, s in enumerate(surfaces_raw):
        if not isinstance(s, dict):
            chk.fail("surfaces", None, f"= {s!r}; a table of keys is required", i)
        chk.unknown("surfaces", s, SURFACE_KEYS, i)
        s = dict(s)
        for side in ("sheet", "tool"):
            key = f"{side}_seed"
            if key not in s and f"{side}_file" not in s:
                chk.fail("surfaces", None, f"key {key!r} (or {side}_file) is missing", i)
            if key in s and (isinstance(s[key], bool) or not isinstance(s[key], int) or s[key] < 0):
                chk.fail("surfaces", key, f"= {s[key]!r}; an integer >= 0 is required", i)
            if f"{side}_file" in s:
                _measured_file(chk, s, side, Path(source).parent if source != "<string>" else Path.cwd(), i)
        try:
            SlideConfig(**{**slide, **s})
        except ParameterError as exc:
            key = error_key(exc)
            if key in s:
                chk.fail("surfaces", key, str(exc), i)
            elif key in slide:
                chk.fail("slide", key, str(exc))
            elif key is not None:
                where = "[slide] or in this [[surfaces]] entry" if key in SURFACE_KEYS else "[slide]"
                chk.fail("surfaces", None, f"{exc} ({key} is not set: this is its default; set {key} in {where})", i)
            chk.fail("slide", None, str(exc))
        except TypeError as exc:  # pragma: no cover - unknown keys are caught above
            chk.fail("slide", None, str(exc))
        if dict(s) in surfaces:
            chk.fail("surfaces", "sheet_seed", "entry is repeated", i)
        surfaces.append(dict(s))
    return surfaces


def parse_sweep(text: str, source: str = "<string>") -> Sweep:
    """Validate the TOML ``text`` of a sweep (``source`` names it in messages)."""
    chk = _Checker(text, source)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"sweep file {source}: not valid TOML: {exc}") from None
    chk.unknown("", data, _TOP_KEYS)
    for key in ("name", "description"):
        if key in data and not isinstance(data[key], str):
            chk.fail("", key, f"= {data[key]!r}; a string is required")
    for key in ("grid", "slide", "table"):
        if key in data and not isinstance(data[key], dict):
            chk.fail("", key, f"must be a table [{key}]")
    grid = data.get("grid")
    if grid is None:
        chk.fail("", "grid", "the [grid] table (pressure, velocity, seeds) is missing")
    chk.unknown("grid", grid, _GRID_KEYS)
    for key in ("pressure", "velocity", "seeds"):
        if key not in grid:
            chk.fail("grid", None, f"key {key!r} is missing")

    slide = dict(data.get("slide", {}))
    allowed_slide = {f.name for f in fields(SlideConfig)} - set(SWEPT_KEYS)
    for key in slide:
        if key in SWEPT_KEYS:
            chk.fail("slide", key, f"is swept by the grid/flakes/surfaces and is not allowed in [slide]")
    chk.unknown("slide", slide, allowed_slide)
    surfaces = _surfaces(chk, data, slide, source)
    base = SlideConfig(**{**slide, **surfaces[0]})  # size and p_crit: [slide]'s, the same for every pair

    pressures = chk.numbers("grid", "pressure", grid["pressure"])
    for p in pressures:
        if p > base.p_crit:
            chk.fail("grid", "pressure", f"has the value {p!r} Pa; pressures in (0, p_crit = "
                     f"{base.p_crit:g}] Pa are allowed")
    velocities = chk.numbers("grid", "velocity", grid["velocity"])
    seeds = chk.numbers("grid", "seeds", grid["seeds"], integer=True, allow_zero=True)
    particle_free = grid.get("particle_free", True)
    if not isinstance(particle_free, bool):
        chk.fail("grid", "particle_free", f"= {particle_free!r}; true or false is required")

    flakes_raw = data.get("flakes")
    if not isinstance(flakes_raw, list) or not flakes_raw:
        chk.fail("", "flakes", "at least one [[flakes]] entry (count, diameter) is required")
    flakes = []
    for i, fl in enumerate(flakes_raw):
        chk.unknown("flakes", fl, _FLAKE_KEYS, i)
        for key in ("count", "diameter"):
            if key not in fl:
                chk.fail("flakes", None, f"key {key!r} is missing", i)
        c, d = fl["count"], fl["diameter"]
        if isinstance(c, bool) or not isinstance(c, int) or c < 1:
            chk.fail("flakes", "count", f"= {c!r}; an integer >= 1 is required", i)
        if isinstance(d, bool) or not isinstance(d, (int, float)) or not (0 < d < 0.5 * base.size):
            chk.fail("flakes", "diameter", f"= {d!r} m; a diameter in (0, size/2 = "
                     f"{0.5 * base.size:g}) m is required", i)
        if any((c, float(d)) == (f.count, f.diameter) for f in flakes):
            chk.fail("flakes", "count", f"entry (count {c}, diameter {d!r}) is repeated", i)
        min_p = fl.get("min_pressure", 0.0)
        if isinstance(min_p, bool) or not isinstance(min_p, (int, float)) or not min_p >= 0:
            chk.fail("flakes", "min_pressure", f"= {min_p!r} Pa; a pressure >= 0 is required", i)
        level_v = None
        if "velocities" in fl:
            level_v = chk.numbers("flakes", "velocities", fl["velocities"], index=i)
            for v in level_v:
                if v not in velocities:
                    chk.fail("flakes", "velocities", f"has the value {v!r} m/s; grid velocities "
                             f"{list(velocities)} are allowed", i)
        level_seeds = None
        if "seeds" in fl:
            level_seeds = tuple(chk.numbers("flakes", "seeds", fl["seeds"], integer=True, allow_zero=True,
                                            index=i))
        level = FlakeLevel(c, float(d), float(min_p), None if level_v is None else tuple(level_v), level_seeds)
        if not any(level.at(p, v) for p in pressures for v in velocities):
            chk.fail("flakes", "min_pressure", "selects no grid point", i)
        flakes.append(level)

    tbl = data.get("table", {})
    chk.unknown("table", tbl, _TABLE_KEYS)
    mu0 = tbl.get("mu0", TableSettings.mu0)
    if isinstance(mu0, bool) or not isinstance(mu0, (int, float)) or not (0 < mu0 <= 5):
        chk.fail("table", "mu0", f"= {mu0!r}; a friction coefficient in (0, 5] is required")
    qs_row = tbl.get("quasi_static_row", False)
    if not isinstance(qs_row, bool):
        chk.fail("table", "quasi_static_row", f"= {qs_row!r}; true or false is required")

    adaptive = None
    if "adaptive" in data:
        ad = data["adaptive"]
        if not isinstance(ad, dict):
            chk.fail("", "adaptive", "must be a table [adaptive]")
        chk.unknown("adaptive", ad, _ADAPTIVE_KEYS)
        target = ad.get("target_relative_se", AdaptiveSettings.target_relative_se)
        if isinstance(target, bool) or not isinstance(target, (int, float)) or not (0 < target < 1):
            chk.fail("adaptive", "target_relative_se", f"= {target!r}; a number in (0, 1) is required")
        extra = chk.numbers("adaptive", "extra_seeds", ad.get("extra_seeds", []), integer=True,
                            allow_zero=True, min_len=0)
        adaptive = AdaptiveSettings(float(target), tuple(int(x) for x in extra))

    for i, fl in enumerate(flakes):
        used = fl.seeds if fl.seeds is not None else seeds
        extra = adaptive.extra_seeds if adaptive else ()
        if set(used) & set(extra):
            chk.fail("adaptive", "extra_seeds", f"repeats a seed of [[flakes]] entry {i + 1}: {sorted(set(used) & set(extra))}")
        if len(used) * len(surfaces) < MIN_MEMBERS:
            chk.fail("flakes" if fl.seeds is not None else "grid", "seeds",
                     f"give {len(used)} placement(s) x {len(surfaces)} surface pair(s) = "
                     f"{len(used) * len(surfaces)} member(s) per grid point; at least {MIN_MEMBERS} are "
                     "required (an ensemble spread)", i)

    return Sweep(
        name=data.get("name", Path(source).stem),
        description=data.get("description", ""),
        pressures=tuple(float(p) for p in pressures),
        velocities=tuple(float(v) for v in velocities),
        seeds=tuple(int(s) for s in seeds),
        flakes=tuple(flakes),
        surfaces=tuple(surfaces),
        slide=slide,
        particle_free=particle_free,
        table=TableSettings(float(mu0), qs_row),
        adaptive=adaptive,
        source=source,
    )
