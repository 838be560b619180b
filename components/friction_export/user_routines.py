"""User friction routines for forming FE codes: ``tribocosim export vfriction|fric|usrfrc -o FILE.f``.

Each export writes three files with FILE's stem, all or none (:mod:`.file_set`): ``FILE.f``, the routine the FE code
calls (:mod:`.fortran_routines`: Abaqus/Explicit VFRICTION, Abaqus/Standard FRIC, or an LS-DYNA contact-node routine),
``FILE.h`` and ``FILE.c``, the project's C core for it (:mod:`.c_amalgamation`: the strip-draw law, its table lookup,
the debris production, ``tc_node_friction.c`` and the FE glue ``tc_fe_friction.c``) with the law as constant data
(:mod:`.table_source`: the table, bit for bit the FMU's, and the parameters). The law is the export's: ``--table`` or
``--calibration``, then ``--set``, read by :func:`~tribocosim.components.friction_export.exported_law.load_law`, the
path every format takes; ``--units`` sets the deck's units.

Per contact point the routine keeps the debris state (state 1 beta, state 2 the accumulated slip, state 3 the lookups
outside the table or on unsimulated nodes) and per increment evaluates mu(P, |slip rate|, beta) at the increment's start
(P = normal force / contact area), then adds the Archard production of the increment's slip at P, with the sink and
the cap (components/native/core/tc_node_friction.h states it), and returns the friction force mu F_N opposite to the
slip, limited by the force that sticks the point (VFRICTION), or the friction stress with an elastic stick (FRIC), or
mu as LS-DYNA's coefficients (LS-DYNA). The tool-carried share zeta of the strip model moves debris between nodes; a
point's own state cannot: the routine's physics is the strip's with zeta = 0 (stated in every header).
"""

from __future__ import annotations

import ctypes
import hashlib
from dataclasses import dataclass
from pathlib import Path

from tribocosim.errors import ParameterError
from tribocosim.components.friction_export import c_amalgamation, fortran_routines, table_source
from tribocosim.components.friction_export.export_header import WIDTH, calibration_line, table_line
from tribocosim.components.friction_export.exported_law import ExportedLaw
from tribocosim.components.friction_export.export_units import UnitSystem
from tribocosim.components.friction_export.file_set import check_target, write_all

#: the number of states a routine keeps per point (the deck's DEPVAR or history variable count)
N_STATES = 3


@dataclass(frozen=True)
class Routine:
    """One target: its FE code, the routine's name, the Fortran writer, the keyword lines and the build."""

    name: str
    code: str
    routine: str
    writer: object
    entry: str


ROUTINES = {
    "vfriction": Routine("vfriction", "Abaqus/Explicit", "VFRICTION", fortran_routines.vfriction,
                         "tribocosim_vfriction"),
    "fric": Routine("fric", "Abaqus/Standard", "FRIC", fortran_routines.fric, "tribocosim_fric"),
    "usrfrc": Routine("usrfrc", "LS-DYNA", "tcdynafric (called from usrfrc)", fortran_routines.lsdyna,
                      "tribocosim_usrfrc"),
}

#: the C entry point of each routine (the Fortran interfaces of :mod:`.fortran_routines` call them)
_ENTRIES = {
    "vfriction": ("void tribocosim_vfriction(int n_block, int n_dir, int n_fric_dir, int n_states, int n_nod_state, "
                  "const double *props, int n_props, double dt, const double *dslip, const double *fstick, "
                  "const double *fnormal, const double *area, double *state, double *ftang, int *status)",
                  "*status = tc_fe_vfriction(&TRIBOCOSIM_LAW, n_block, n_dir, n_fric_dir, n_states, n_nod_state, "
                  "props, n_props, dt, dslip, fstick, fnormal, area, state, ftang);"),
    "fric": ("void tribocosim_fric(int *lm, double *tau, double *ddtddg, double *ddtddp, const double *dgam, "
             "double press, double dtime, double chrlngth, int nfdir, double *statev, int nstatv, const double *props, "
             "int nprops, int *status)",
             "*status = tc_fe_fric(&TRIBOCOSIM_LAW, lm, tau, ddtddg, ddtddp, dgam, press, dtime, chrlngth, nfdir, "
             "statev, nstatv, props, nprops);"),
    "usrfrc": ("void tribocosim_usrfrc(double fnormal, double area, const double *dslip, int n_dir, double dt, "
               "double *hsv, int n_hsv, const double *uc, int n_uc, double *fric, int *status)",
               "*status = tc_fe_node(&TRIBOCOSIM_LAW, fnormal, area, dslip, n_dir, dt, hsv, n_hsv, uc, n_uc, fric);"),
}


@dataclass(frozen=True)
class RoutineResult:
    """The files of a routine export and what the command says about them."""

    files: tuple
    routine: Routine
    check: int
    notes: tuple = ()  # lines about the law for the error stream (cosim/apps/export_friction.py)

    def summary(self) -> list[str]:
        """Every file written, one line each."""
        f, c, h = self.files
        return [f"wrote {f} ({self.routine.code} {self.routine.routine}; property 1, the check number: {self.check})",
                f"wrote {c} (tribocosim's C core for it, with the law as constant data)",
                f"wrote {h} (the header of {c.name})"]

    def warning_lines(self) -> list[str]:
        """None: the routine evaluates the law itself (what a lookup reads is counted per point, state 3)."""
        return []


def check_number(law: ExportedLaw, units: UnitSystem) -> int:
    """The export's check number (property 1 of the deck): 24 bits of the SHA-256 of the table's content hash, the
    parameters and the units, an integer a double holds exactly and a deck writes as it is."""
    prov = law.provenance()
    text = f"{prov['table']['content_hash']}|{sorted(prov['parameters'].items())}|{units.name}"
    return int(hashlib.sha256(text.encode()).hexdigest()[:6], 16)


def _law_cap(law: ExportedLaw) -> float:
    from tribocosim.components.native.toolchain.library import core

    c = core()
    s = c.struct(law.params)
    return float(c.lib.tc_node_law_cap(ctypes.byref(s), law.table.native.handle))


def _keywords(routine: Routine, check: int, units: UnitSystem) -> list[str]:
    if routine.name == "vfriction":
        return ["keyword lines (Abaqus/Explicit, general contact; DEPVAR on *FRICTION is the state count):",
                "  *SURFACE INTERACTION, NAME=TRIBOCOSIM",
                f"  *FRICTION, USER=FRICTION, DEPVAR={N_STATES}, PROPERTIES=1",
                f"  {check}.",
                "  *CONTACT / *CONTACT PROPERTY ASSIGNMENT naming TRIBOCOSIM for the sheet-tool pairs",
                "run in double precision (abaqus ... double=both): the routine's reals are real*8"]
    if routine.name == "fric":
        return ["keyword lines (Abaqus/Standard):",
                "  *SURFACE INTERACTION, NAME=TRIBOCOSIM",
                f"  *FRICTION, USER, DEPVAR={N_STATES}, PROPERTIES=1",
                f"  {check}.",
                "  *CONTACT PAIR, INTERACTION=TRIBOCOSIM naming the sheet and tool surfaces"]
    return ["keyword lines (LS-DYNA; UNVERIFIED card layouts, see below):",
            "  *CONTROL_CONTACT card 2: USRFRC = storage per contact interface for the user friction subroutine "
            "(ansys-dyna-core 0.12.1's *CONTROL_CONTACT: 'Storage per contact interface for user supplied interface "
            "friction subroutine')",
            f"  *USER_INTERFACE_FRICTION for the sheet-tool contact, with {N_STATES} history variables per contact "
            f"node and the user constant {check}. (the check number) as the first",
            f"  *DATABASE_EXTENT_INTFOR, NHUF = {N_STATES}: the user friction history variables in intfor (MPP only; "
            "ansys-dyna-core 0.12.1)"]


def _build(routine: Routine, stem: str) -> list[str]:
    if routine.name == "usrfrc":
        return ["build (LS-DYNA user object version, the usermat package of your release): copy "
                f"{stem}.f, {stem}.c and {stem}.h into its folder, call tcdynafric from the body of usrfrc "
                "(below), add the two files to the makefile's objects (the C file with the C compiler and "
                "-std=c11 -O2), make (Linux) or nmake (Windows): a new LS-DYNA executable",
                "in usrfrc, for each contact node in contact: call tcdynafric(normal force, contact area, slip "
                "increment(3), 3, time step, the node's history variables, their count, the interface's user "
                "constants, their count, the four friction coefficients usrfrc returns)"]
    return [f"build (Linux): cc -std=c11 -O2 -fPIC -c {stem}.c -o {stem}_c.o ; ifort -c -fPIC -O2 {stem}.f -o "
            f"{stem}_f.o (the Fortran compiler of your Abaqus release, with its include folder holding "
            f"{'vaba_param.inc' if routine.name == 'vfriction' else 'aba_param.inc'}: -I <abaqus>/code/include) ; "
            f"ld -r {stem}_f.o {stem}_c.o -o {stem}_user.o ; "
            f"abaqus job=JOB user={stem}_user.o" + (" double=both" if routine.name == "vfriction" else ""),
            "(abaqus job=... user={source-file | object-file}: Abaqus Analysis User's Guide, 'User subroutines: "
            "overview'; one object holds the routine and its C core)",
            f"build (Windows): cl /O2 /c {stem}.c, then link {stem}.obj with the routine's object as the Abaqus "
            "environment file's link command allows (link_sl)"]


def header(routine: Routine, law: ExportedLaw, units: UnitSystem, check: int, stem: str, command: str,
           code_version: str, notes: tuple = ()) -> list[str]:
    """The header of the three files (lines of at most :data:`WIDTH` characters before wrapping)."""
    prov = law.provenance()
    prm = law.params
    lines = [f"tribocosim user friction routine: {routine.code} {routine.routine}",
             f"written by tribocosim {code_version}" + (f" with: {command}" if command else ""),
             f"files: {stem}.f (the routine), {stem}.c and {stem}.h (tribocosim's C core: the StripDraw FMU's "
             "law, table lookup and debris production, generated from the project's sources)",
             "law: mu = mu0 (1 - (1 - r) s A_p/A_c) of the strip-draw model (docs/model.md section 4), evaluated by "
             "its native core (tc_friction.c), the code the StripDraw FMU runs",
             "per contact point and increment (components/native/core/tc_node_friction.h): P = normal force / "
             "contact area; v = |slip increment| / time increment; mu = mu(P, v, beta) at the increment's start; "
             "then beta += K P |ds| / (H h_p) (Eq. 37), with the sink of length lambda integrated exactly, capped at "
             "the law's cap at (P, v) (Eq. 24); the friction force is mu times the normal force, opposite to the "
             "slip" + (", at most the force that sticks the point" if routine.name == "vfriction" else ""),
             f"states per point ({N_STATES}): 1 beta, the debris area fraction; 2 the accumulated slip "
             f"[{units.length}]; 3 the increments whose lookup left the table's axes or read a node the mesoscale "
             "campaign did not simulate (the law holds its edge values there). The FE code's initial state (zero: a "
             "clean blank, or the deck's initial conditions) is the debris the blank arrives with",
             f"properties (1): the check number {check} of this export; the routine stops the analysis when the "
             "deck gives another or fewer than 2 states",
             "what a point's own state cannot hold: in the strip model the tool carries the share zeta of the debris "
             f"with it from point to point under the pad (Eq. 13-14; zeta = {prm.zeta:g} in these parameters); the "
             "routine keeps the debris a point makes at that point: its physics is the strip model's with zeta = 0",
             *_keywords(routine, check, units),
             *_build(routine, stem),
             f"{table_line(prov)}, embedded as constant data in {stem}.c"]
    lines.append(calibration_line(prov))
    lines += list(notes)
    lines.append(f"units {units.name} ({units.description}): forces N, lengths {units.length}, pressures "
                 f"{units.pressure}, time s; mu and beta have no unit")
    lines += _sources(routine)
    lines.append("parameters: " + ", ".join(f"{k}={v}" for k, v in prov["parameters"].items()))
    return lines


def _sources(routine: Routine) -> list[str]:
    if routine.name == "vfriction":
        return ["argument list: Abaqus User Subroutines Reference, VFRICTION (Abaqus/Explicit, general contact), "
                "41 arguments in the order of its template (as in the public VFRICTION of the WZL friction model, "
                "JStaWZL/USR_VFriction_WZLReibmodell, Abaqus 6.14); fTangential(1) is along the slip increment, "
                "in [-fStickForce, 0]; rData(3) is the time increment"]
    if routine.name == "fric":
        return ["argument list: Abaqus User Subroutines Reference, FRIC (Abaqus/Standard), 39 arguments (the "
                "2016-2017 editions); LM 0 = relative motion allowed, 2 = open; TAU the friction stress along "
                "DGAM, elastic stick with the stiffness mu p / (0.005 CHRLNGTH); STATEV at the increment's start "
                "on every iteration"]
    return ["UNVERIFIED: the argument list of LS-DYNA's usrfrc (the user object's dyn21 files) and the card layout "
            "of *USER_INTERFACE_FRICTION; no public text of the LS-DYNA Keyword User's Manual (Vol. I, "
            "*USER_INTERFACE_FRICTION and the appendix on user defined interface friction) or of dyn21 was found. "
            "tcdynafric's own argument list is documented here; check against the manual and your release's "
            "usrfrc: what usrfrc receives (normal force or pressure at the node, its contact area, the slip "
            "increment or the relative velocity, the time step, the history variables and their count, the user "
            "constants), and that it returns the four coefficients FS, FD, DC, VC (what tcdynafric writes: mu, "
            "mu, 0, 0) rather than a force"]


def _banner(lines: list[str]) -> str:
    import textwrap

    out = []
    for line in lines:
        out += textwrap.wrap(line, WIDTH, subsequent_indent="  ", break_long_words=True,
                             break_on_hyphens=False) or [""]
    return "/* " + "\n * ".join(x.replace("*/", "* /") for x in out) + "\n */\n"


def render(routine: Routine, law: ExportedLaw, units: UnitSystem, out: Path, command: str = "",
           code_version: str = "", notes: tuple = ()) -> tuple[dict, int]:
    """``({path: text}, check number)`` of the three files (module docstring); ``notes``: further header lines."""
    stem = out.stem
    check = check_number(law, units)
    lines = header(routine, law, units, check, stem, command, code_version, notes)
    guard = f"TRIBOCOSIM_{''.join(ch if ch.isalnum() else '_' for ch in stem.upper())}_H"
    proto, body = _ENTRIES[routine.name]
    h_text = (_banner(lines) + f"#ifndef {guard}\n#define {guard}\n\n" + c_amalgamation.header_text() +
              f"\n/* ---- the entry point {routine.routine} calls (bind(C) in {stem}.f) ---- */\n{proto};\n\n"
              f"#endif\n")
    image, table_name = table_source.table_image(law.table, "tribocosim")
    cap = _law_cap(law)
    law_c = (f"/* ---- the law: the table and the parameters ---- */\n{image}\n"
             f"static const tc_fe_law TRIBOCOSIM_LAW = {{\n"
             f"    .law = {{.p = {table_source.params_initializer(law.params)},\n"
             f"            .table = &{table_name}, .beta_cap = {table_source.c_double(cap)}}},\n"
             f"    .length_scale = {table_source.c_double(units.length_scale)}, "
             f".pressure_scale = {table_source.c_double(units.pressure_scale)},\n"
             f"    .check = {table_source.c_double(float(check))}}};\n")
    c_text = (_banner(lines) + f'#include "{stem}.h"\n\n' + c_amalgamation.source_text() + "\n" + law_c +
              f"\n/* ---- the entry point ---- */\n{proto} {{\n    {body}\n}}\n")
    f_text = routine.writer(lines, check)
    files = {out.with_suffix(".f"): f_text, out.with_suffix(".c"): c_text, out.with_suffix(".h"): h_text}
    return files, check


def write_routine(name: str, law: ExportedLaw, units: UnitSystem, out, *, command: str = "",
                  code_version: str = "", notes: tuple = ()) -> RoutineResult:
    """Write the routine ``name`` (a key of :data:`ROUTINES`) for ``law`` to ``out`` (FILE.f) and FILE.c, FILE.h beside
    it, all or none; ParameterError naming ``-o`` when they cannot be written."""
    routine = ROUTINES[name]
    out = Path(out)
    check_target(out)
    if out.suffix.lower() not in (".f", ".for"):
        raise ParameterError(f"-o {out}: a user friction routine is a fixed-form Fortran file, FILE.f (or FILE.for); "
                             f"FILE.c and FILE.h are written beside it")
    files, check = render(routine, law, units, out, command, code_version, notes)
    written = write_all(files)
    return RoutineResult(tuple(written), routine, check)
