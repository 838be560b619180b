"""The strip-draw friction law for a forming simulation: :func:`export_friction`, the function behind ``tribocosim
export`` (docs/forming-friction.md).

It reads the law the StripDraw FMU evaluates (the table or a calibration, the strip-draw parameters), settles
the debris state (:mod:`tribocosim.cosim.apps.debris_state`) and writes the export
(:func:`tribocosim.components.friction_export.export_run.run_export`): LS-DYNA, Abaqus or a neutral JSON table, each
sampled so that the FE code's linear interpolation of the file reproduces tribocosim's mu within the tolerance
(0.5 %), with the band of the table's ensemble standard error when asked; or a user friction routine.

Calibrated by default: an export given neither a table, nor a calibration, nor ``particle_area_scale`` takes the
shipped paper calibration (``--calibration paper``, :mod:`tribocosim.components.friction_export.named_calibration`):
the mesoscale campaign leaves the load share of blocked flakes at the test's speed open (the scale s of A_p), and the
paper gives one number that fixes it, the one-pass drop of mu_bar at 25 MPa on the 35 mm pad, 35 % (Sec. 2.1); with
s = 1 the model gives a smaller drop (the note below says how much), so a forming simulation would carry a law weaker
in pressure than the test it comes from. The calibration holds for the parameters it was fitted with (the default
model: r = 0.2, zeta = 0.2, K = 1e-4, A_c from the table). :func:`law_notes` says on the error stream, in one line and
in the files' headers, when the law is the campaign's uncalibrated one (``--table``, ``--calibration none``) or its
parameters are not those of its calibration, with the one-pass drop that law gives in the paper's test (two
strip-draw runs, :func:`tribocosim.cosim.apps.paper_calibration.one_pass_drop`).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from tribocosim.errors import ParameterError
from tribocosim.components.friction_export.export_run import (DEFAULT_TOLERANCE, FORMATS, ExportRequest,
                                                             ExportResult, check_request, run_export)
from tribocosim.components.friction_export.export_units import DEFAULT_UNITS, unit_system
from tribocosim.components.friction_export.exported_law import load_law
from tribocosim.components.friction_export.lsdyna_deck import DEFAULT_TABLE_ID
from tribocosim.components.friction_export.abaqus_friction import DEFAULT_NAME
from tribocosim.components.friction_export import named_calibration
from tribocosim.cosim.apps.debris_state import DebrisChoice, debris_states


def export_friction(format: str, out, state: DebrisChoice | None = None, *, units: str = DEFAULT_UNITS,
                    band: float | None = None, table=None, calibration=None, settings: dict | None = None,
                    option: str | None = None,
                    pressure_range=None, beta_levels=None, allow_unsimulated: bool = False,
                    tolerance: float = DEFAULT_TOLERANCE, table_id: int = DEFAULT_TABLE_ID,
                    interaction_name: str = DEFAULT_NAME, command: str = "", log=None) -> ExportResult:
    """Write the strip-draw friction law for an FE code; returns what was written (:class:`ExportResult`).

    Parameters
    ----------
    format : {"lsdyna", "abaqus", "table"}
        The target.
    out : path
        The file to write (several debris states or a band: files named after it, ``friction.pass2.upper.k``).
    state : DebrisChoice, optional
        The debris state: ``DebrisChoice(beta=(0.1,))``, ``DebrisChoice(passes=(3,), pressure=25)`` (a strip-draw
        test, in ``units``), or ``DebrisChoice(slide=(20,))`` (the debris a sheet point makes sliding 20 mm under each
        pressure); None: beta is an axis of the file (Abaqus field variable 1, the table's third axis).
    units : {"mm-t-s", "SI"}
        The unit system of the files and of every pressure, velocity and length given here.
    band : float, optional
        K: also write the files of mu + K se(mu) and mu - K se(mu) (``FILE.upper.SUFFIX``, ``FILE.lower.SUFFIX``).
    table, calibration : path, optional
        The friction table (uncalibrated), or a calibration: a shipped one's name (``paper``; ``none``: the shipped
        table uncalibrated), a calibration file, or a table of ``tribocosim calibrate``. Neither (and no
        ``particle_area_scale`` in ``settings`` or ``option``): the paper calibration (module docstring).
    settings : dict, optional
        Strip-draw parameters (name -> value) on top of the table's or calibration's (and of ``option``'s).
    option : str, optional
        A multi-pass option by name (:data:`tribocosim.components.stripdraw.multipass_options.OPTIONS`:
        ``shear_0.6``, ``sink_35``, ``carry_0.5``, ...): its strip-draw parameters, for the law and the passes.
    pressure_range : (low, high), optional
        The pressures to export (default: the table's axis), in ``units``.
    beta_levels : sequence, optional
        The levels of a beta axis (default: refined up to the highest level simulated in the range).
    allow_unsimulated : bool
        Write values whose lookups read table nodes the mesoscale campaign did not simulate, marked, instead of
        refusing them.
    tolerance : float
        The largest relative deviation of the FE code's reading from tribocosim's mu (0.005: 0.5 %).
    table_id : int
        LS-DYNA: the *DEFINE_TABLE's id; the curves take the ids after it.
    interaction_name : str
        Abaqus: the *SURFACE INTERACTION's name.
    command : str
        The command line, recorded in the headers.
    log : callable, optional
        Progress messages (the strip-draw test of ``passes``).

    Raises
    ------
    ParameterError
        A bad request, naming the option; nothing is written then. TableError for a table that cannot be read.
    """
    from tribocosim.components.friction_export.user_routines import ROUTINES

    if format not in FORMATS and format not in ROUTINES:
        raise ParameterError(f"FORMAT {format!r} is not an export format; choose one of "
                             f"{', '.join((*FORMATS, *ROUTINES))}")
    system = unit_system(units)
    chosen, notes = multipass_option(option)
    if format in ROUTINES:
        _check_routine_request(format, state, band, pressure_range, beta_levels, allow_unsimulated, tolerance,
                               table_id, interaction_name)
    given = {**chosen, **(settings or {})}
    if table is None and calibration is None and "particle_area_scale" not in given:
        calibration = named_calibration.DEFAULT
    law = load_law(table, calibration, given)
    if format in ROUTINES:
        from tribocosim.components.friction_export.export_run import code_version
        from tribocosim.components.friction_export.user_routines import write_routine

        law_lines = law_notes(law)
        result = write_routine(format, law, system, out, command=command, code_version=code_version(),
                               notes=law_lines + calibration_argument(law))
        return dataclasses.replace(result, notes=law_lines)
    states = debris_states(state or DebrisChoice(), law, system, log)
    prange = None if pressure_range is None else tuple(system.pressure_from_file(float(x)) for x in pressure_range)
    request = ExportRequest(format=format, out=Path(out), states=states, units=system, band=band,
                            pressure_range=prange, beta_levels=None if beta_levels is None else tuple(beta_levels),
                            allow_unsimulated=allow_unsimulated, tolerance=tolerance, table_id=table_id,
                            interaction_name=interaction_name, command=command, notes=notes)
    check_request(law, request)  # a request refused runs no strip-draw test for the notes
    law_lines = law_notes(law)
    request = dataclasses.replace(request, notes=notes + law_lines + calibration_argument(law))
    return dataclasses.replace(run_export(law, request, log), notes=law_lines)


def calibration_argument(law) -> tuple:
    """The header line that says why the default calibration is the default (module docstring), for a law of the
    shipped one; none otherwise. The drop with s = 1 is the calibration's own first evaluation, in its record."""
    cal = law.calibration or {}
    if cal.get("name") != named_calibration.DEFAULT:
        return ()
    history = (cal.get("fit") or {}).get("history") or []
    at_one = next((h["drop"] for h in history if h.get("particle_area_scale") == 1.0), None)
    campaign = (f"; the campaign's A_p as simulated (s = 1) gives {100 * at_one:.1f} % (the calibration's first "
                "evaluation)" if at_one is not None else "")
    return ("why calibrated (the default of every export): the mesoscale campaign leaves the load share of blocked "
            "flakes at the test's speed open (the scale s of A_p), and the paper gives one number that fixes it, the "
            f"one-pass drop of mu_bar at 25 MPa on the 35 mm pad, 35 %{campaign}: with that law a forming simulation "
            "would carry a friction weaker in pressure than the test's. The fit holds for the parameters it was made "
            "with (the default model); --calibration none writes the campaign's law",)


def law_notes(law) -> tuple:
    """One line about the law when it is not a calibration's fitted model (module docstring), else none: the
    campaign's uncalibrated law (particle_area_scale = 1, no calibration) or a calibrated law whose parameters differ
    from the fit's, each with the one-pass drop of mu_bar at 25 MPa it gives in the paper's test. A scale set by hand
    (``--set particle_area_scale``) is the user's own calibration: nothing is said."""
    import warnings

    from tribocosim.cosim.apps.paper_calibration import one_pass_drop
    from tribocosim.cosim.reports.paper_physics import CAL_PRESSURE, LOW_PRESSURE
    from tribocosim.errors import TribocosimError

    cal = law.calibration
    if cal is None and law.params.particle_area_scale != 1.0:
        return ()
    departures = law.departures()
    if cal is not None and not departures:
        return ()
    lo, hi = law.pressure_axis
    if not (lo * (1 - 1e-9) <= LOW_PRESSURE and CAL_PRESSURE <= hi * (1 + 1e-9)):
        drop = (f"cannot be computed: the test's 1 and 25 MPa leave the table's pressure axis [{lo / 1e6:g}, "
                f"{hi / 1e6:g}] MPa")
    else:
        try:
            with warnings.catch_warnings():  # what the test's draws warn of concerns them, not the export
                warnings.simplefilter("ignore")
                drop = f"is {100 * one_pass_drop(law):.1f} %"
        except TribocosimError as exc:  # the paper's test cannot be run with these parameters
            drop = f"cannot be computed with these parameters ({exc})"
    test = "its one-pass drop of mu_bar at 25 MPa against 1 MPa on the 35 mm pad (the paper's test, 0.08 m/s) " + drop
    if cal is None:
        source = (f"the mesoscale campaign's ({law.table_path.name})" if law.table.provenance == "mesoscale" else
                  f"that of the table {law.table_path.name} (provenance {law.table.provenance})")
        return (f"the law is {source}, uncalibrated (particle_area_scale = 1, A_p as the "
                f"table holds it): {test}, where the paper measures 35 % (--calibration paper, the default, is fitted "
                "on it)",)
    name = cal.get("name") or cal.get("file") or law.table_path.name
    changed = ", ".join(f"{k} = {b} (fitted with {a})" for k, (a, b) in departures.items())
    target = cal.get("fit", {}).get("target")
    aim = f", where the calibration is fitted on {100 * target:g} %" if target is not None else ""
    return (f"the law's parameters are not those its calibration ({name}) was fitted with: {changed}; {test}{aim} "
            "(recalibrate for these parameters: tribocosim calibrate)",)


def _check_routine_request(format, state, band, pressure_range, beta_levels, allow_unsimulated, tolerance,
                           table_id, interaction_name) -> None:
    """ParameterError naming the first option a user friction routine does not take: it keeps beta per contact point
    as its state (no --beta or --passes: the deck's initial state is the debris the blank arrives with), evaluates
    the law itself (no sampling: --pressure-range, --beta-levels, --tolerance; no file band: --band; every lookup
    counted in state 3: --allow-unsimulated) and is no LS-DYNA table or Abaqus interaction file."""
    given = [("--beta", bool(state and state.beta)), ("--passes", bool(state and state.passes)),
             ("--slide", bool(state and state.slide)),
             ("--band", band is not None), ("--pressure-range", pressure_range is not None),
             ("--beta-levels", beta_levels is not None), ("--allow-unsimulated", bool(allow_unsimulated)),
             ("--tolerance", tolerance != DEFAULT_TOLERANCE), ("--table-id", table_id != DEFAULT_TABLE_ID),
             ("--interaction-name", interaction_name != DEFAULT_NAME)]
    why = {"--beta": "the routine keeps beta per contact point (state 1); the deck's initial state is the debris "
                     "the blank arrives with",
           "--passes": "the routine keeps beta per contact point (state 1) and makes it as the sheet slides",
           "--slide": "the routine makes each point's debris from its own slide (state 1)",
           "--band": "the routine evaluates the nominal law",
           "--allow-unsimulated": "the routine counts the lookups on unsimulated nodes per point (state 3)"}
    for option, on in given:
        if on:
            reason = why.get(option, "the routine evaluates the law itself, nothing is sampled into a file")
            raise ParameterError(f"{option} does not apply to FORMAT {format}: {reason}")


def multipass_option(name: str | None) -> tuple[dict, tuple]:
    """The strip-draw parameters of the paper report's multi-pass option ``name`` and a header line saying so;
    ``({}, ())`` for None; ParameterError naming ``--option`` for another name."""
    if name is None:
        return {}, ()
    from tribocosim.components.stripdraw.multipass_options import OPTIONS

    found = {o.name: o for o in OPTIONS}
    if name not in found:
        raise ParameterError(f"--option {name!r} is not a multi-pass option of the paper report; choose one of "
                             f"{', '.join(found)}")
    o = found[name]
    values = ", ".join(f"{k} = {v}" for k, v in o.parameters.items()) or "the defaults"
    return dict(o.parameters), (f"multi-pass option {o.name} of the paper report: {o.label} ({values}): {o.why}",)
