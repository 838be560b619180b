"""The strip-draw friction law for a forming simulation: :func:`export_friction`, the function behind ``tribocosim
export`` (docs/forming-friction.md).

It reads the law the StripDraw FMU evaluates (the table or a calibration file, the strip-draw parameters), settles
the debris state (:mod:`tribocosim.cosim.apps.debris_state`) and writes the export
(:func:`tribocosim.components.friction_export.export_run.run_export`): LS-DYNA, Abaqus or a neutral JSON table, each
sampled so that the FE code's linear interpolation of the file reproduces tribocosim's mu within the tolerance
(0.5 %), with the band of the table's ensemble standard error when asked.
"""

from __future__ import annotations

from pathlib import Path

from tribocosim.errors import ParameterError
from tribocosim.components.friction_export.export_run import (DEFAULT_TOLERANCE, FORMATS, ExportRequest,
                                                             ExportResult, run_export)
from tribocosim.components.friction_export.export_units import DEFAULT_UNITS, unit_system
from tribocosim.components.friction_export.exported_law import load_law
from tribocosim.components.friction_export.lsdyna_deck import DEFAULT_TABLE_ID
from tribocosim.components.friction_export.abaqus_friction import DEFAULT_NAME
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
        The debris state: ``DebrisChoice(beta=(0.1,))``, or ``DebrisChoice(passes=(3,), pressure=25)`` (a strip-draw
        test, in ``units``); None: beta is an axis of the file (Abaqus field variable 1, the table's third axis).
    units : {"mm-t-s", "SI"}
        The unit system of the files and of every pressure, velocity and length given here.
    band : float, optional
        K: also write the files of mu + K se(mu) and mu - K se(mu) (``FILE.upper.SUFFIX``, ``FILE.lower.SUFFIX``).
    table, calibration : path, optional
        The friction table (default: the shipped one), or a calibration file of ``tribocosim calibrate``.
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
    law = load_law(table, calibration, {**chosen, **(settings or {})})
    if format in ROUTINES:
        from tribocosim.components.friction_export.export_run import code_version
        from tribocosim.components.friction_export.user_routines import write_routine

        return write_routine(format, law, system, out, command=command, code_version=code_version())
    states = debris_states(state or DebrisChoice(), law, system, log)
    prange = None if pressure_range is None else tuple(system.pressure_from_file(float(x)) for x in pressure_range)
    request = ExportRequest(format=format, out=Path(out), states=states, units=system, band=band,
                            pressure_range=prange, beta_levels=None if beta_levels is None else tuple(beta_levels),
                            allow_unsimulated=allow_unsimulated, tolerance=tolerance, table_id=table_id,
                            interaction_name=interaction_name, command=command, notes=notes)
    return run_export(law, request, log)


def _check_routine_request(format, state, band, pressure_range, beta_levels, allow_unsimulated, tolerance,
                           table_id, interaction_name) -> None:
    """ParameterError naming the first option a user friction routine does not take: it keeps beta per contact point
    as its state (no --beta or --passes: the deck's initial state is the debris the blank arrives with), evaluates
    the law itself (no sampling: --pressure-range, --beta-levels, --tolerance; no file band: --band; every lookup
    counted in state 3: --allow-unsimulated) and is no LS-DYNA table or Abaqus interaction file."""
    given = [("--beta", bool(state and state.beta)), ("--passes", bool(state and state.passes)),
             ("--band", band is not None), ("--pressure-range", pressure_range is not None),
             ("--beta-levels", beta_levels is not None), ("--allow-unsimulated", bool(allow_unsimulated)),
             ("--tolerance", tolerance != DEFAULT_TOLERANCE), ("--table-id", table_id != DEFAULT_TABLE_ID),
             ("--interaction-name", interaction_name != DEFAULT_NAME)]
    why = {"--beta": "the routine keeps beta per contact point (state 1); the deck's initial state is the debris "
                     "the blank arrives with",
           "--passes": "the routine keeps beta per contact point (state 1) and makes it as the sheet slides",
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
