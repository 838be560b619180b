"""The core library's binding against its C headers (components/native/toolchain/prototypes.py, library.py): every
exported prototype is read and typed from the header, every function the bindings call is one of them, and the
library's sources are the ones the components declare."""

from __future__ import annotations

import ctypes
import re
from pathlib import Path

import pytest

from tribocosim.components import registry
from tribocosim.components.native.toolchain import compiler, library
from tribocosim.components.native.toolchain.prototypes import (PrototypeError, code, ctypes_signature, exported,
                                                               parse)

COMPONENTS = Path(library.__file__).resolve().parents[2]


def headers() -> list[Path]:
    return [compiler.source(s).with_suffix(".h") for s in library.sources()]


def test_every_tc_api_declaration_of_the_librarys_headers_is_read():
    for path in headers():
        text = path.read_text()
        declared = len(re.findall(r"\bTC_API\b", code(text)))
        assert len(parse(text, path.name)) == declared, f"{path.name}: {declared} TC_API declarations"
    assert len(library.prototypes()) >= 49


def test_the_loaded_functions_carry_the_headers_types():
    lib = library.core().lib
    for name, proto in library.prototypes().items():
        fn = getattr(lib, name)
        restype, argtypes = ctypes_signature(proto, library.Msg)
        assert fn.restype is restype and list(fn.argtypes) == argtypes, name
    law = library.prototypes()["tc_law_mu"]
    assert law.params == ("const tc_stripdraw_params *", "const tc_table *", "double", "size_t", "const double *",
                          "const double *", "double *", "unsigned char *", "double *", "tc_table_rows *", "tc_msg")
    assert ctypes_signature(library.prototypes()["tc_stripdraw_create"], library.Msg)[1][4] == \
        ctypes.POINTER(ctypes.c_void_p), "tc_stripdraw **out"


def test_every_function_the_bindings_call_is_exported_by_a_header():
    exported_names = set(library.prototypes())
    called = set()
    for path in COMPONENTS.rglob("*.py"):
        called |= set(re.findall(r"\blib\.(tc_\w+)", path.read_text()))
    for comp in registry.components().values():  # the linear models call <prefix>_create, _step, ...
        if comp.native is not None and comp.native.prefix in ("tc_press", "tc_machine"):
            called |= {f"{comp.native.prefix}_{s}" for s in ("create", "free", "step", "outputs", "state_size",
                                                            "get_state", "set_state", "time")}
    assert called, "the scan finds the bindings' calls"
    assert called <= exported_names, f"called but not exported: {sorted(called - exported_names)}"


def test_a_changed_prototype_changes_the_binding_and_an_unknown_type_is_refused(tmp_path):
    text = "TC_API int tc_f(const double *x, size_t n, double out[3], tc_thing **made, tc_msg msg);"
    (proto,) = parse(text)
    assert ctypes_signature(proto, library.Msg)[1] == [ctypes.POINTER(ctypes.c_double), ctypes.c_size_t,
                                                       ctypes.POINTER(ctypes.c_double),
                                                       ctypes.POINTER(ctypes.c_void_p), library.Msg]
    (changed,) = parse(text.replace("size_t n", "double n"))
    assert ctypes_signature(changed, library.Msg)[1][1] is ctypes.c_double
    with pytest.raises(PrototypeError, match=r"tc_g \(parameter 1\).*'float'"):
        ctypes_signature(parse("TC_API int tc_g(float y, tc_msg msg);", "x.h")[0], library.Msg)
    (tmp_path / "a.h").write_text(text)
    (tmp_path / "b.h").write_text(text)
    with pytest.raises(PrototypeError, match="declared in a.h and in b.h"):
        exported([tmp_path / "a.h", tmp_path / "b.h"])


def test_the_librarys_sources_are_the_components_model_sources():
    declared = {s for c in registry.components().values() if c.native for s in c.native.sources}
    assert set(library.sources()) == {*library.COMMON_SOURCES, *(s for s in declared if not s.startswith("fmi/"))}
    on_disk = {f"{p.parent.name}/{p.name}" for folder in ("core", "resource_io")
               for p in (compiler.NATIVE_DIR / folder).glob("*.c")}
    assert on_disk == set(library.sources()), "every model source is declared by a component (no orphan file)"


def test_the_binding_reads_the_cores_indices_from_its_header():
    """The strip-draw binding's output order, nodal and info indices and refusal kinds are the header's enums: the
    outputs in the component's declared order (the FMU's too), a C enum's implicit values counted as C counts them."""
    from tribocosim.components.native.toolchain.prototypes import enums
    from tribocosim.components.stripdraw import model
    from tribocosim.components.stripdraw.ports import OUTPUTS

    assert enums("enum e { A = 3, B, /* c */ C = 0x10, D };") == {"e": {"A": 3, "B": 4, "C": 16, "D": 17}}
    assert model.OUTPUT_NAMES == tuple(o.name for o in OUTPUTS)
    assert sorted(model._NODAL.values()) == list(range(len(model._NODAL)))
    assert sorted(model._INFO.values()) == list(range(len(model._INFO)))
