"""The ctypes signatures of the core library, read from the C headers: one declaration of each function, in C.

The core library (:mod:`.library`) exports the functions its headers mark ``TC_API``. :func:`exported` reads those
prototypes from the headers of the library's sources (a header declares what the source of its name defines) and
:func:`ctypes_signature` turns each into a ctypes signature by a fixed table of C types, so that the binding can
never disagree with the C code on a parameter's type or count. A C type outside the table is an error naming the
function and the parameter (:class:`PrototypeError`), not a guess:

=====================================  ==============================================
C                                      ctypes
=====================================  ==============================================
``void`` (result)                      ``None``
``int``, ``enum ...``                  ``c_int``
``double``, ``size_t``                 ``c_double``, ``c_size_t``
``tc_msg`` (by value)                  :class:`~.library.Msg`
``double *``, ``double x[N]``          ``POINTER(c_double)`` (``const`` or not)
``size_t *``, ``int *``                ``POINTER(c_size_t)``, ``POINTER(c_int)``
``unsigned char *``                    ``POINTER(c_ubyte)``
``char *``, ``char x[N]``              ``c_char_p``
``void *``, ``tc_<struct> *``          ``c_void_p`` (opaque objects and parameter structs, by reference)
``tc_<struct> **``                     ``POINTER(c_void_p)`` (an object created for the caller)
=====================================  ==============================================
"""

from __future__ import annotations

import ctypes
import re
from dataclasses import dataclass
from pathlib import Path

from tribocosim.errors import TribocosimError

#: a TC_API declaration: result type and name, then the parameter list (up to the closing parenthesis)
_DECLARATION = re.compile(r"\bTC_API\s+(?P<result>[^;(]*?)\b(?P<name>tc_\w+)\s*\((?P<params>[^)]*)\)\s*;", re.S)
#: a parameter: its type, its name and an optional array extent
_PARAMETER = re.compile(r"^(?P<type>.*?)(?P<name>\w+)\s*(?P<array>\[[^\]]*\])?$", re.S)


class PrototypeError(TribocosimError):
    """A header declares a function whose C types the binding has no ctypes type for."""


@dataclass(frozen=True)
class Prototype:
    """One exported C function: its result type and the types of its parameters, as the header spells them
    (whitespace normalized, ``const`` kept, an array parameter as a pointer)."""

    name: str
    result: str
    params: tuple[str, ...]
    header: str


def code(text: str) -> str:
    """C text without comments and preprocessor lines."""
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    text = re.sub(r"//[^\n]*", " ", text)
    return re.sub(r"^[ \t]*#(?:[^\n]*\\\n)*[^\n]*", " ", text, flags=re.M)


def _normalize(ctype: str) -> str:
    ctype = re.sub(r"\s*\*\s*", " * ", ctype)
    return " ".join(ctype.split()).replace("* *", "**")


def parse(text: str, header: str = "<text>") -> list[Prototype]:
    """The TC_API prototypes of a header's text, in order."""
    found = []
    for m in _DECLARATION.finditer(code(text)):
        params = []
        raw = " ".join(m.group("params").split())
        if raw not in ("", "void"):
            for part in raw.split(","):
                p = _PARAMETER.match(part.strip())
                if p is None or not p.group("type").strip():
                    raise PrototypeError(f"{header}: {m.group('name')}: cannot read the parameter {part.strip()!r}")
                ctype = p.group("type") + (" *" if p.group("array") else "")
                params.append(_normalize(ctype))
        found.append(Prototype(m.group("name"), _normalize(m.group("result")), tuple(params), header))
    return found


#: an enum with a tag: its name and the body of its members
_ENUM = re.compile(r"\benum\s+(?P<name>\w+)\s*\{(?P<body>[^}]*)\}", re.S)


def enums(text: str) -> dict[str, dict[str, int]]:
    """The tagged enums of a header's text: ``{tag: {member: value}}``, values as C assigns them (an explicit integer,
    else one more than the member before, 0 for the first)."""
    out = {}
    for m in _ENUM.finditer(code(text)):
        members, value = {}, -1
        for item in m.group("body").split(","):
            item = item.strip()
            if not item:
                continue
            name, eq, given = (x.strip() for x in item.partition("="))
            value = int(given, 0) if eq else value + 1
            members[name] = value
        out[m.group("name")] = members
    return out


def exported(headers) -> dict[str, Prototype]:
    """Every TC_API prototype of the given header files by function name (a name declared twice is an error)."""
    out: dict[str, Prototype] = {}
    for path in headers:
        path = Path(path)
        for proto in parse(path.read_text(encoding="utf-8"), path.name):
            if proto.name in out:
                raise PrototypeError(f"{proto.name} is declared in {out[proto.name].header} and in {path.name}")
            out[proto.name] = proto
    return out


def ctypes_type(ctype: str, *, result: bool = False, msg_type=None, where: str = ""):
    """The ctypes type of one C type of a prototype (see the module's table); PrototypeError for any other."""
    base = ctype.replace("const ", "").replace(" const", "").strip()
    stars = base.count("*")
    base = base.replace("*", "").strip()
    if stars == 0:
        if base == "void" and result:
            return None
        if base == "int" or base.startswith("enum "):
            return ctypes.c_int
        if base in ("double", "size_t"):
            return ctypes.c_double if base == "double" else ctypes.c_size_t
        if base == "tc_msg" and msg_type is not None:
            return msg_type
    elif stars == 1:
        table = {"double": ctypes.POINTER(ctypes.c_double), "size_t": ctypes.POINTER(ctypes.c_size_t),
                 "int": ctypes.POINTER(ctypes.c_int), "unsigned char": ctypes.POINTER(ctypes.c_ubyte),
                 "char": ctypes.c_char_p, "void": ctypes.c_void_p}
        if base in table:
            return table[base]
        if re.fullmatch(r"tc_\w+", base) and base != "tc_msg":
            return ctypes.c_void_p
    elif stars == 2 and re.fullmatch(r"tc_\w+", base) and base != "tc_msg":
        return ctypes.POINTER(ctypes.c_void_p)
    raise PrototypeError(f"{where}: the C type {ctype!r} has no ctypes type in the binding's table "
                         "(components/native/toolchain/prototypes.py)")


def ctypes_signature(proto: Prototype, msg_type) -> tuple[object, list]:
    """``(restype, argtypes)`` of a prototype; ``msg_type`` is the ctypes structure of ``tc_msg``."""
    where = f"{proto.header}: {proto.name}"
    restype = ctypes_type(proto.result, result=True, msg_type=msg_type, where=f"{where} (result)")
    argtypes = [ctypes_type(p, msg_type=msg_type, where=f"{where} (parameter {i + 1})")
                for i, p in enumerate(proto.params)]
    return restype, argtypes
