"""One C file and one header from the project's native sources: the code a user friction routine links, the same
files the StripDraw FMU is compiled from (one implementation of the law, the table lookup and the debris production).

The header holds the project's headers the routine needs, in dependency order, with the parameter header generated
from the strip-draw component's declaration (:mod:`tribocosim.components.native.toolchain.declarations`); the C file
includes it and holds the sources, each as it is in the package, without its includes of project headers (they are
in the header). A static name defined in two of the sources would clash in one translation unit: it is refused
(:class:`AmalgamationError`), so a source that adds one is renamed before it ships.
"""

from __future__ import annotations

import re

from tribocosim.errors import TribocosimError

#: the headers a routine needs, in dependency order (None: the generated parameter header)
HEADERS = ("core/tc_common.h", None, "core/tc_pchip.h", "core/tc_table.h", "core/tc_table_lookup.h",
           "core/tc_friction.h", "core/tc_debris_node.h", "core/tc_node_friction.h", "fe/tc_fe_friction.h")
#: the sources a routine needs
SOURCES = ("core/tc_common.c", "core/tc_pchip.c", "core/tc_table.c", "core/tc_table_lookup.c", "core/tc_friction.c",
           "core/tc_node_friction.c", "fe/tc_fe_friction.c")

_PROJECT_INCLUDE = re.compile(r'^[ \t]*#[ \t]*include[ \t]*"[^"]+"[ \t]*\n', re.M)
_STATIC = re.compile(r"^static\s+(?:inline\s+)?(?:const\s+)?[\w\s\*]*?\b(\w+)\s*(?:\(|=|\[)", re.M)


class AmalgamationError(TribocosimError):
    """Two sources define the same static name."""


def _params_header() -> str:
    from tribocosim.components import registry
    from tribocosim.components.native.toolchain.declarations import params_header

    return params_header(registry.components()["stripdraw"])


def _text(name: str) -> str:
    from tribocosim.components.native.toolchain.compiler import NATIVE_DIR

    return (NATIVE_DIR / name).read_text(encoding="utf-8")


def _without_project_includes(text: str) -> str:
    return _PROJECT_INCLUDE.sub("", text)


def header_text() -> str:
    """The headers, one after the other (module docstring)."""
    parts = []
    for name in HEADERS:
        label = name or "tc_stripdraw_params.h (generated from components/stripdraw/parameters.py)"
        text = _params_header() if name is None else _text(name)
        parts.append(f"/* ---- {label} ---- */\n" + _without_project_includes(text).strip() + "\n")
    return "\n".join(parts)


def source_text() -> str:
    """The sources, one after the other (module docstring); AmalgamationError for a static name two of them define."""
    seen: dict[str, str] = {}
    parts = []
    for name in SOURCES:
        text = _text(name)
        for static in set(_STATIC.findall(text)):
            if static in seen:
                raise AmalgamationError(f"the static name {static!r} is defined in {seen[static]} and in {name}: "
                                        "one translation unit cannot hold both; rename one")
            seen[static] = name
        parts.append(f"/* ---- {name} ---- */\n" + _without_project_includes(text).strip() + "\n")
    return "\n".join(parts)
