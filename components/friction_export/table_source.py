"""The friction law of a user friction routine as C data: the table a routine looks up, constant, and the law's
parameters, with the table's content hash.

A routine's table is the one the StripDraw FMU reads: the table file through its owner
(:mod:`tribocosim.components.stripdraw.table`), made in the native core as the FMU's resource conversion makes it
(``tc_table_from_arrays``, ``tc_table_set_areas``, ``tc_table_set_extras``, ``tc_table_set_cubic``:
:class:`~tribocosim.components.stripdraw.table.NativeTable`). Every array of that ``tc_table``, those it was made of
and those the core computed from them (ln P, the shares A_p / A_c and the monotone cubic forms of a version 4 table),
is read back from the core (``tc_table_part``, ``tc_table_scalars``) and written as a ``static const`` array of exact
hexadecimal doubles, and the ``tc_table`` itself as a ``static const`` struct pointing at them. So a routine's lookups
are those of the FMU's table bit for bit, without building anything at run time: no allocation, no global mutable
state, nothing computed on the first call (a lazily built shared table would be global mutable state; building the
table on every call would redo the cubic forms of every array each time). The struct's pointer members are not
``const`` (``tc_table`` is also the FMU's, which owns and frees its arrays), so the image casts the constant arrays'
addresses to them; nothing writes through them: a lookup only reads its table.
"""

from __future__ import annotations

import ctypes
import dataclasses
import math

from tribocosim.components.stripdraw.table import FrictionTable

#: the members of ``enum tc_table_part`` (tc_table.h), in its order: the table's arrays a lookup may read
PARTS = ("pressure", "velocity", "beta", "mu", "contact_area", "particle_area", "contact_area_std", "particle_area_std",
         "unsimulated", "particle_area_clusters", "log_pressure", "share", "share_clusters")
#: the members of one monotone cubic form (``TC_TABLE_PART_CUBIC + 6 k + i``)
CUBIC_PARTS = ("values", "beta_slope", "value_piece[0]", "value_piece[1]", "slope_piece[0]", "slope_piece[1]")
#: ``tc_table_scalars``: the members it returns, in its order
SCALARS = ("pressure_lo", "pressure_hi", "velocity_lo", "velocity_hi", "beta_lo", "beta_hi", "beta_threshold",
           "format_version", "interpolation")
N_CUBIC = 4  # TC_TABLE_N_CUBIC


def c_double(x: float) -> str:
    """An exact C literal of a double (C99 hexadecimal: ``0x1.4p+3``; HUGE_VAL for infinities)."""
    x = float(x)
    if math.isinf(x):
        return "HUGE_VAL" if x > 0 else "-HUGE_VAL"
    if math.isnan(x):
        raise ValueError("a NaN has no place in a routine's law")
    return x.hex()


def _array(name: str, values) -> str:
    lines, row = [], []
    for v in values:
        row.append(c_double(v))
        if len(row) == 4:
            lines.append("    " + ", ".join(row) + ",")
            row = []
    if row:
        lines.append("    " + ", ".join(row) + ",")
    return f"static const double {name}[{len(values)}] = {{\n" + "\n".join(lines) + "\n};"


def table_image(table: FrictionTable, prefix: str) -> tuple[str, str]:
    """``(C text, name)``: the table's arrays and ``static const tc_table <prefix>_table`` (module docstring)."""
    native = table.native
    lib = native._core.lib
    count = ctypes.c_size_t(0)

    def part(which: int):
        p = lib.tc_table_part(native.handle, which, ctypes.byref(count))
        if not p:
            return None, 0
        return p, int(count.value)

    out, names, addresses = [], {}, {}
    for which, member in enumerate(PARTS):
        p, n = part(which)
        if p is None:
            continue
        name = f"{prefix}_{member}"
        out.append(_array(name, p[:n]))
        names[member] = name
        addresses[ctypes.cast(p, ctypes.c_void_p).value] = name
    cubic_lines = []
    for k in range(N_CUBIC):
        fields = []
        for i, member in enumerate(CUBIC_PARTS):
            p, n = part(len(PARTS) + 6 * k + i)
            if p is None:
                fields.append("NULL")
                continue
            if i == 0:  # the form's values: one of the table's arrays, the same object
                fields.append(f"{addresses[ctypes.cast(p, ctypes.c_void_p).value]}")
                continue
            name = f"{prefix}_cubic{k}_{member.replace('[', '').replace(']', '')}"
            out.append(_array(name, p[:n]))
            fields.append(f"(double *){name}")
        if all(f == "NULL" for f in fields):
            cubic_lines.append("        {NULL, NULL, {NULL, NULL}, {NULL, NULL}},")
        else:
            cubic_lines.append(f"        {{{fields[0]}, {fields[1]}, {{{fields[2]}, {fields[3]}}}, "
                               f"{{{fields[4]}, {fields[5]}}}}},")
    scalars = (ctypes.c_double * len(SCALARS))()
    lib.tc_table_scalars(native.handle, scalars)
    sc = dict(zip(SCALARS, scalars))
    digest = str(table.metadata.get("content_hash", ""))
    provenance = table.provenance.encode("ascii", "replace").decode()[:31]
    member = lambda m: f"(double *){names[m]}" if m in names else "NULL"  # noqa: E731
    body = [
        f"static const tc_table {prefix}_table = {{",
        f"    .n_pressure = {table.pressure.size}, .n_velocity = {table.velocity.size}, .n_beta = {table.beta.size},",
        *(f"    .{m} = {member(m)}," for m in PARTS),
        "    .cubic = {",
        *cubic_lines,
        "    },",
        *(f"    .{m} = {c_double(sc[m])}," for m in SCALARS[:7]),
        f"    .format_version = {int(sc['format_version'])},",
        f"    .interpolation = {int(sc['interpolation'])},",
        f"    .content_hash = \"{digest}\",",
        f"    .provenance = \"{provenance}\",",
        "};",
    ]
    out.append("\n".join(body))
    return "\n\n".join(out) + "\n", f"{prefix}_table"


def params_initializer(params) -> str:
    """A designated initializer of ``tc_stripdraw_params`` (the generated header of
    :mod:`tribocosim.components.native.toolchain.declarations`) with every field of ``params``: floats as exact
    literals, integers as they are, choices as their index."""
    items = []
    for f in dataclasses.fields(params):
        value = getattr(params, f.name)
        meta = f.metadata
        if meta.get("text"):
            continue
        if "choices" in meta:
            text = str(meta["choices"].index(value))
        elif meta.get("integer"):
            text = str(int(value))
        else:
            text = c_double(value)
        items.append(f".{f.name} = {text}")
    lines, row = [], ""
    for item in items:
        if len(row) + len(item) > 100:
            lines.append(row.rstrip())
            row = ""
        row += item + ", "
    lines.append(row.rstrip().rstrip(","))
    return "{\n        " + "\n        ".join(lines) + "}"
