"""The LS-DYNA form of the friction law: an include file with one *DEFINE_TABLE and its *DEFINE_CURVEs.

What LS-DYNA reads (the keyword texts Ansys ships in the PyPI package ansys-dyna-core 0.12.1,
``ansys/dyna/core/keywords/keyword_classes/auto/``):

- ``contact/contact_forming_one_way_surface_to_surface.py``: card 2 holds FS FD DC VC VDC PENCHK BT DT, eight fields
  of 10 columns; FS = 2 makes the dynamic coefficient of friction a table, FD its id, "giving the coefficient of
  friction as a function of the relative velocity and pressure"; card 3's FSF (columns 61-70) scales the Coulomb
  coefficient (mu_sc = FSF mu_c).
- ``define/define_table.py``: card 1 TBID, SFA, OFFA (10 columns each), then one value per line in a 20-column
  field, each the value of the *DEFINE_CURVE that follows in the same order (here: a contact pressure).
- ``define/define_curve.py``: card 1 LCID SIDR SFA SFO OFFA OFFO DATTYP LCINT (10 columns each), then one point per
  line, abscissa and ordinate in two 20-column fields (here: relative sliding velocity, mu).

LS-DYNA interpolates linearly between the table's values and along each curve and holds the end values outside them
(the rule :mod:`.grid_refinement` samples for). A curve has two points or more (LS-DYNA rediscretizes each curve over
its abscissa's span into LCINT intervals: the LS-DYNA support FAQ on the discretization of curves; Oasys PRIMER's
manual: "lists of two or more (x, y) data points"): a law that does not depend on the velocity is written as a curve
of two equal points per pressure, at the ends of the velocity range. Every number is written right-aligned in its
field with at least one blank before it (20-column reals as ``%20.12E``: 13 significant digits), ids as integers in
10 columns.
"""

from __future__ import annotations

import numpy as np

#: the default id of the *DEFINE_TABLE; its curves take the ids that follow. Tables and curves share one id space
#: in LS-DYNA; ids in the 9,450,000s are far from those pre-processors number parts, sets and curves with.
DEFAULT_TABLE_ID = 9_450_000
MAX_ID = 99_999_999  # an id fills at most the 10 columns of its field (8 digits keep a blank before it)
SUFFIX = ".k"


def real20(x: float) -> str:
    """A real in a 20-column field: 13 significant digits (fewer where a sign and a three-digit exponent need the
    room), a blank before it."""
    digits = 12
    while len(text := f"{x:.{digits}E}") > 19:
        digits -= 1
    return text.rjust(20)


def real10(x: float) -> str:
    """A short real (a scale factor, an offset) in a 10-column field."""
    text = f"{x:.6G}"
    if "." not in text and "E" not in text:
        text += ".0"
    if len(text) > 9:
        text = f"{x:.3E}"
    return text.rjust(10)


def int10(n: int) -> str:
    return f"{int(n):10d}"


def contact_card(table_id: int) -> list[str]:
    """The commented *CONTACT_FORMING_ONE_WAY_SURFACE_TO_SURFACE card that reads the table (FS = 2, FD = its id;
    FSF = 1 keeps the coefficients as written)."""
    return [
        "$ The contact that reads this table (its surfaces are the deck's: SURFA the",
        "$ blank, SURFB the tools; FS = 2: FD is the table's id; FSF = 1):",
        "$*CONTACT_FORMING_ONE_WAY_SURFACE_TO_SURFACE",
        "$#   surfa     surfb  surfatyp  surfbtyp   saboxid   sbboxid      sapr      sbpr",
        "$  (blank)   (tools)         3         3                             0         0",
        "$#      fs        fd        dc        vc       vdc    penchk        bt        dt",
        "$" + "2.0".rjust(9) + int10(table_id) + "       0.0       0.0       0.0         0       0.0     1E+20",
        "$#    sfsa      sfsb      sast      sbst     sfsat     sfsbt       fsf       vsf",
        "$      1.0       1.0                           1.0       1.0       1.0       1.0",
    ]


def render(header: list[str], pressures: np.ndarray, velocities: np.ndarray, mu: np.ndarray, table_id: int,
           units, marked: dict | None = None) -> str:
    """The include file: ``header`` as comments, the commented contact card, the *DEFINE_TABLE of ``pressures``
    (file units, increasing) and one *DEFINE_CURVE per pressure, mu (``mu[i, j]``) against ``velocities`` (file
    units). ``marked``: pressure index -> comment lines put before that pressure's curve (its debris state, that its
    lookups read unsimulated nodes)."""
    marked = marked or {}
    lines = ["*KEYWORD", *(f"$ {h}" for h in header), "$", *contact_card(table_id), "$"]
    lines += ["*DEFINE_TABLE",
              "$#    tbid       sfa      offa",
              int10(table_id) + real10(1.0) + real10(0.0),
              f"$# contact pressure [{units.pressure}]: one line per *DEFINE_CURVE below, in their order"]
    lines += [real20(p) for p in pressures]
    for i, p in enumerate(pressures):
        lines.append("*DEFINE_CURVE")
        lines.append(f"$ mu against sliding velocity [{units.velocity}] at contact pressure {p:.10g} "
                     f"{units.pressure}")
        lines += [f"$ {text}" for text in marked.get(i, ())]
        lines.append("$#    lcid      sidr       sfa       sfo      offa      offo    dattyp     lcint")
        lines.append(int10(table_id + 1 + i) + int10(0) + real10(1.0) + real10(1.0) + real10(0.0) + real10(0.0)
                     + int10(0) + int10(0))
        lines.append("$#                a1                  o1")
        lines += [real20(v) + real20(m) for v, m in zip(velocities, mu[i])]
    lines.append("*END")
    return "\n".join(lines) + "\n"
