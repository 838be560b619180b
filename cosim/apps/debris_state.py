"""The debris state an exported friction law is written at: a beta the user gives, or the one a strip-draw test
reaches after N passes.

An FE code has no beta (the area fraction of the strip covered by flakes, docs/model.md section 3): within one stroke
a point of the tool slides little, while debris builds up over strokes. So the user chooses the state:

- ``--beta B`` (several: one file each);
- ``--passes N`` with the test's ``--pressure`` (and ``--velocity``, ``--pad-length``; the paper's 0.08 m/s and 35
  mm pad by default): the strip-draw test run through the same native core
  (:func:`tribocosim.cosim.studies.stripdraw_experiment.draw`, the multi-pass runs of the calibration and the paper
  report, with the export's parameters: the multi-pass options ``debris_carry_over``, ``debris_sink_length``,
  ``flake_shear_ratio`` are strip-draw parameters, ``--set``, or the paper report's named options, ``--option``). The state after pass N is the debris the strip
  carries then: the mean beta over the strip that passed under the pad (``beta_left``), the debris a tool meets at
  the start of pass N + 1. Several N: one draw, one file per N.

Values are in the export's unit system (``--units``: MPa, mm/s, mm by default).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from tribocosim.errors import ParameterError
from tribocosim.components.friction_export.export_run import AXIS_STATE, DebrisState
from tribocosim.components.friction_export.export_units import UnitSystem
from tribocosim.components.friction_export.exported_law import ExportedLaw
from tribocosim.cosim.studies.stripdraw_experiment import V0, Point, draw


@dataclass(frozen=True)
class DebrisChoice:
    """The debris state asked for: ``beta`` values, or ``passes`` of a strip-draw test at ``pressure`` (and
    ``velocity``, ``pad_length``; None: the paper's), in the export's units; neither: beta is an axis of the file.
    ``beta`` and ``passes`` take one value or a sequence of them (``DebrisChoice(beta=0.1)``, ``beta=(0, 0.1)``)."""

    beta: tuple = ()
    passes: tuple = ()
    pressure: float | None = None
    velocity: float | None = None
    pad_length: float | None = None

    def __post_init__(self):
        for name in ("beta", "passes"):
            value = getattr(self, name)
            if isinstance(value, (str, bytes)) or not hasattr(value, "__iter__"):
                value = (value,)
            object.__setattr__(self, name, tuple(value))


def _finite(option: str, value) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{option} {value!r} is not a number") from None
    if not math.isfinite(x):
        raise ParameterError(f"{option} {value} is not finite; a finite number is required")
    return x


def debris_states(choice: DebrisChoice, law: ExportedLaw, units: UnitSystem, log=None) -> tuple[DebrisState, ...]:
    """The states of an export (module docstring); ParameterError naming the option of a bad choice."""
    test = {"--pressure": choice.pressure, "--velocity": choice.velocity, "--pad-length": choice.pad_length}
    if choice.beta and choice.passes:
        raise ParameterError("--beta and --passes both given: the debris state is one or the other")
    if not choice.passes:
        given = [k for k, v in test.items() if v is not None]
        if given:
            raise ParameterError(f"{given[0]} describes the strip-draw test of --passes, which is not given")
    if choice.beta:
        states = []
        for b in choice.beta:
            beta = _finite("--beta", b)
            if beta < 0:
                raise ParameterError(f"--beta {beta:g} is negative; the debris area fraction lies in [0, 1]")
            states.append(DebrisState(beta, f"beta{beta:g}", f"beta = {beta:g}, given (--beta)",
                                      {"beta": beta, "how": "given"}))
        return tuple(states)
    if not choice.passes:
        return (AXIS_STATE,)
    return _after_passes(choice, law, units, log)


def _after_passes(choice: DebrisChoice, law: ExportedLaw, units: UnitSystem, log) -> tuple[DebrisState, ...]:
    passes = []
    for n in choice.passes:
        x = _finite("--passes", n)
        if x < 1 or x != int(x):
            raise ParameterError(f"--passes {n}: a number of passes is an integer >= 1 (a clean strip is --beta 0)")
        passes.append(int(x))
    if choice.pressure is None:
        raise ParameterError("--passes needs --pressure, the nominal pressure of the strip-draw test "
                             f"[{units.pressure}]")
    u = units
    pressure = u.pressure_from_file(_finite("--pressure", choice.pressure))
    lo, hi = law.pressure_axis
    if not lo * (1 - 1e-9) <= pressure <= hi * (1 + 1e-9):
        raise ParameterError(f"--pressure {choice.pressure} {u.pressure} is outside the table's pressure axis "
                             f"[{u.pressure_to_file(lo):g}, {u.pressure_to_file(hi):g}] {u.pressure}")
    velocity = V0 if choice.velocity is None else u.velocity_from_file(_finite("--velocity", choice.velocity))
    vmax = law.velocity_axis[1]
    if not 0 < velocity <= vmax * (1 + 1e-9):
        raise ParameterError(f"--velocity {choice.velocity} {u.velocity}: the drawing speed must lie in (0, "
                             f"{u.velocity_to_file(vmax):g}] {u.velocity}, the table's velocity axis")
    pad = law.params.tool_length if choice.pad_length is None else u.length_from_file(
        _finite("--pad-length", choice.pad_length))
    field = next(f for f in dataclasses.fields(law.params) if f.name == "tool_length")
    if not field.metadata["low"] <= pad <= field.metadata["high"]:
        raise ParameterError(f"--pad-length {choice.pad_length} {u.length}: the pad length lies in "
                             f"[{field.metadata['low'] / u.length_scale:g}, {field.metadata['high'] / u.length_scale:g}]"
                             f" {u.length}")
    parameters = {**dataclasses.asdict(law.params), "table_file": str(law.table_path)}
    parameters.pop("tool_length")
    test = (f"{max(passes)} pass(es) of the strip-draw test at {u.pressure_to_file(pressure):g} {u.pressure}, "
            f"{u.velocity_to_file(velocity):g} {u.velocity}, {pad / u.length_scale:g} {u.length} pad")
    if log:
        log(f"running {test} ...")
    results = draw(Point(pressure, pad, max(passes), parameters, velocity))
    record_test = {"pressure": pressure, "velocity": velocity, "pad_length": pad, "units": "SI",
                   "driver": "tribocosim.cosim.studies.stripdraw_experiment.draw",
                   "passes": [{k: r[k] for k in ("mu_bar", "beta_left", "beta_max", "debris_g_m2", "table_clamps")}
                              for r in results]}
    states = []
    for n in passes:
        r = results[n - 1]
        beta = float(r["beta_left"])
        text = (f"beta = {beta:.6g}, the debris the strip carries after {n} pass(es) of the strip-draw test at "
                f"{u.pressure_to_file(pressure):g} {u.pressure}, {u.velocity_to_file(velocity):g} {u.velocity}, "
                f"{pad / u.length_scale:g} {u.length} pad (the mean beta over the strip that passed under the pad; "
                f"that pass's mu_bar {r['mu_bar']:.4f}, largest beta {r['beta_max']:.4g}, "
                f"{r['table_clamps']} clamped lookups)")
        states.append(DebrisState(beta, f"pass{n}", text, {"beta": beta, "how": "passes", "after_pass": n,
                                                            "test": record_test}))
    return tuple(states)
