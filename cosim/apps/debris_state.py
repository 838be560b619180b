"""The debris state an exported friction law is written at: a beta the user gives, the one a strip-draw test
reaches after N passes, or the one a sheet point makes sliding S under each pressure.

A tabulated friction law of an FE code has no beta (the area fraction of the strip covered by flakes, docs/model.md
section 3). In the model a sheet point makes its debris while it slides under pressure, within the stroke, in
proportion to its own pressure times its slide (d beta / ds = K P / (H h_p), Eq. 37): tens of millimetres over a die
radius or under a blankholder. The user routines (``export vfriction|fric|usrfrc``) keep that state per contact point;
a table holds one of these states, which the user chooses:

- ``--beta B`` (several: one file each);
- ``--slide S`` (several: one file each): at each contact pressure P and sliding velocity v of the file, the debris a
  sheet point makes sliding S at that (P, v) from the blank's debris (``beta_initial``, a strip-draw parameter: 0, a
  clean blank, unless ``--set`` gives it), keeping what it makes (no transport: zeta = 0), by the per-point update of
  the native core the strip's nodes and the user routines share (:meth:`~tribocosim.components.friction_export.
  exported_law.ExportedLaw.beta_after_slide`: the Archard production K P S / (H h_p), the sink if
  ``debris_sink_length`` is set, the cap of Eq. 24 at (P, v)). So beta rises with P and mu falls with it, as in the
  strip-draw test. The production does not depend on v; the cap does, through the table: each value of the file is
  the state of a point that slid S at that (P, v), the state the user routines reach for such a point, so that the
  file is what they would return there (for the shipped table the cap, like mu, is the same at every velocity);
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
    """The debris state asked for: ``beta`` values, ``passes`` of a strip-draw test at ``pressure`` (and
    ``velocity``, ``pad_length``; None: the paper's), or ``slide`` lengths, in the export's units; none: beta is an
    axis of the file. ``beta``, ``passes`` and ``slide`` take one value or a sequence of them
    (``DebrisChoice(beta=0.1)``, ``beta=(0, 0.1)``, ``slide=20``)."""

    beta: tuple = ()
    passes: tuple = ()
    pressure: float | None = None
    velocity: float | None = None
    pad_length: float | None = None
    slide: tuple = ()

    def __post_init__(self):
        for name in ("beta", "passes", "slide"):
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
    given = [name for name, on in (("--beta", choice.beta), ("--passes", choice.passes), ("--slide", choice.slide))
             if on]
    if len(given) > 1:
        raise ParameterError(f"{given[0]} and {given[1]} both given: the debris state is one of --beta, --passes and "
                             "--slide")
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
    if choice.slide:
        return tuple(_after_slide(s, law, units) for s in choice.slide)
    if not choice.passes:
        return (AXIS_STATE,)
    return _after_passes(choice, law, units, log)


def _after_slide(text, law: ExportedLaw, units: UnitSystem) -> DebrisState:
    """The state of ``--slide S`` (module docstring)."""
    u, prm = units, law.params
    shown = _finite("--slide", text)
    if shown < 0:
        raise ParameterError(f"--slide {shown:g} {u.length} is negative; a sheet point's slide is >= 0")
    slide = u.length_from_file(shown)
    beta0 = prm.beta_initial
    start = ("0, a clean blank (--set beta_initial=B: a blank that arrives with debris)" if beta0 == 0 else
             f"{beta0:g}, the debris the blank arrives with (beta_initial)")
    sink = (f"; with the sink of length lambda = {prm.debris_sink_length / u.length_scale:g} {u.length}: "
            "q lambda (1 - exp(-S / lambda)) above beta_initial exp(-S / lambda)" if prm.debris_sink_length > 0 else
            "")
    pressures = law.table.pressure
    at = law.beta_after_slide(pressures, V0, slide, beta0)
    listed = ", ".join(f"{u.pressure_to_file(p):g} {u.pressure} {b:.4g}" for p, b in zip(pressures, at))
    text = (f"beta = beta(P, S), the debris a sheet point makes sliding S = {shown:g} {u.length} at a constant "
            f"contact pressure P and sliding velocity v, at each (P, v) of the file, from beta_initial = {start}, "
            "keeping what it makes (no transport: zeta = 0): the per-point update the strip's nodes and the user "
            "routines share "
            f"(tc_node_slide, components/native/core/tc_node_friction.h): the Archard production K P S / (H h_p) "
            f"(Eq. 37; K = {prm.archard_k:g}, H = {prm.hardness / 1e6:g} MPa, h_p = {prm.particle_thickness * 1e6:g} "
            f"um){sink}, capped at the law's cap at (P, v) (Eq. 24); the production does not depend on v, the cap "
            "does through the table: each value is the state of a point that slid S at that (P, v), as the user "
            f"routines make it; beta at the table's pressures and {u.velocity_to_file(V0):g} {u.velocity}: {listed}")
    record = {"beta": None, "how": "slide", "slide": slide, "beta_initial": beta0, "units": "SI",
              "driver": "tc_node_slide (components/native/core/tc_node_friction.h)"}
    return DebrisState(None, f"slide{shown:g}", text, record, slide=slide, beta_initial=beta0)


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
