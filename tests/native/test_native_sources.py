"""The layout of the native sources: every include resolves, the include graph has no cycle, a header declares only
what its own source defines, and the folders are layered (core <- resource_io <- fmi).

A module is a header and the source of the same name (``tc_table.h`` and ``tc_table.c``); module A depends on B when
a file of A includes B's header. Because a header declares only functions its own source defines, the include graph
is the graph of which code calls which: a cycle in it is two modules that need each other. The one header whose
functions are defined elsewhere is ``tc_fmu.h``, the interface that the FMI layer calls and every component's glue
implements.
"""

from __future__ import annotations

import graphlib
import re
from pathlib import Path

import pytest

from tribocosim.components import registry
from tribocosim.components.native.toolchain.compiler import INCLUDE_DIRS, NATIVE_DIR

#: headers the build generates (tribocosim.components.native.toolchain.declarations) and the FMI standard's, which
#: fmpy ships: quoted includes that are not files of the native folders
STANDARD = {"fmi2Functions.h", "fmi3Functions.h"}
#: the interface the FMI layer (tc_fmu_instance.c) calls and each component's glue defines
INTERFACES = {"tc_fmu.h"}
#: which folders a folder's files may include from
LAYERS = {"core": {"core"}, "resource_io": {"core", "resource_io"}, "fmi": {"core", "resource_io", "fmi"}}
#: headers that hold a model's members (no functions): only the files of that model include them, so that the model's
#: state is changed in its own files alone (the bar, its state image and backup, its debris transport)
PRIVATE = {"tc_stripdraw_model.h": {"tc_stripdraw.c", "tc_stripdraw_state.c", "tc_debris.c"}}


def generated_headers() -> set[str]:
    return {"tc_fmu_model.h"} | {c.native.params_header for c in registry.components().values() if c.native}


def source_files() -> dict[str, Path]:
    files = {}
    for folder in INCLUDE_DIRS:
        for path in sorted(folder.glob("*.[ch]")):
            assert path.name not in files, f"{path.name} is in two folders: one include path holds them all"
            files[path.name] = path
    return files


def code(path: Path) -> str:
    """The file without comments and preprocessor lines (continuations included)."""
    text = re.sub(r"/\*.*?\*/", " ", path.read_text(), flags=re.S)
    text = re.sub(r"//[^\n]*", " ", text)
    return re.sub(r"^[ \t]*#(?:[^\n]*\\\n)*[^\n]*", " ", text, flags=re.M)


def includes(path: Path) -> list[str]:
    return re.findall(r'^[ \t]*#[ \t]*include[ \t]*"([^"]+)"', path.read_text(), flags=re.M)


def file_scope(text: str) -> str:
    """``text`` with everything between braces removed (function bodies, struct and enum members)."""
    out, depth = [], 0
    for ch in text:
        depth -= ch == "}"
        if depth == 0:
            out.append(ch)
        depth += ch == "{"
    return "".join(out)


def declared(path: Path) -> set[str]:
    """The functions a file declares without defining them (prototypes at file scope, not typedefs)."""
    text = re.sub(r"[^;{}]*\{\}", ";", file_scope(code(path)))  # definitions and bodies end a statement
    names = set()
    for statement in text.split(";"):
        statement = " ".join(statement.split())
        m = re.match(r"^[\w\s\*]*?\b(tc_\w+)\s*\(", statement)
        if m and not statement.startswith("typedef"):
            names.add(m.group(1))
    return names


def defined(path: Path) -> set[str]:
    """The functions a file defines (a body follows the parameter list)."""
    return set(re.findall(r"^[A-Za-z_][\w \*]*?\b(tc_\w+)\s*\([^;{}]*\)\s*\{", code(path), flags=re.M))


def module_graph(files: dict[str, Path]) -> dict[str, set[str]]:
    graph = {}
    for name, path in files.items():
        stem = Path(name).stem
        targets = {Path(h).stem for h in includes(path) if h in files}
        graph.setdefault(stem, set()).update(targets - {stem})
    return graph


def cycle(graph: dict[str, set[str]]) -> list[str]:
    """A cycle of the graph (its nodes, the first repeated at the end), or [] when it has none."""
    try:
        graphlib.TopologicalSorter(graph).prepare()
    except graphlib.CycleError as exc:
        return list(exc.args[1])
    return []


def test_every_quoted_include_is_a_native_header_a_generated_one_or_the_standards():
    files = source_files()
    allowed = set(files) | generated_headers() | STANDARD
    unknown = {(name, h) for name, path in files.items() for h in includes(path) if h not in allowed}
    assert not unknown, f"includes of nothing the build provides: {sorted(unknown)}"
    assert {f.parent.name for f in files.values()} == set(LAYERS), "every source folder has its layer"
    assert all(f.parent.parent == NATIVE_DIR for f in files.values())


def test_the_include_graph_of_the_native_modules_has_no_cycle():
    found = cycle(module_graph(source_files()))
    assert not found, f"modules that include each other (directly or through others): {' -> '.join(found)}"


def test_a_header_declares_only_what_its_own_source_defines():
    files = source_files()
    definitions = {name: defined(path) for name, path in files.items()}
    wrong = []
    for name, path in files.items():
        if not name.endswith(".h") or name in INTERFACES:
            continue
        own = definitions.get(name[:-2] + ".c", set())
        for fn in sorted(declared(path) - own):
            where = sorted(f for f, d in definitions.items() if fn in d)
            wrong.append(f"{name} declares {fn}, defined in {where or 'no file'}")
    assert not wrong, "\n".join(wrong)
    for fn in declared(files["tc_fmu.h"]) - {"tc_component_array"}:  # the interface: every glue defines it
        glue = sorted(f for f, d in definitions.items() if fn in d)
        assert glue == ["tc_linear_glue.h", "tc_stripdraw_fmu.c"], (fn, glue)


def test_a_models_members_are_included_by_its_own_files_only():
    files = source_files()
    for header, allowed in PRIVATE.items():
        assert header in files and declared(files[header]) == set(), f"{header} declares no function"
        users = {name for name, path in files.items() if header in includes(path)}
        assert users == allowed, f"{header} is included by {sorted(users)}; only {sorted(allowed)} may"


@pytest.mark.parametrize("folder", sorted(LAYERS))
def test_a_folder_includes_only_from_its_own_layer_and_below(folder):
    files = source_files()
    wrong = [(name, h, files[h].parent.name) for name, path in files.items() if path.parent.name == folder
             for h in includes(path) if h in files and files[h].parent.name not in LAYERS[folder]]
    assert not wrong, f"{folder} files include from a layer above: {wrong}"


def test_the_checks_find_what_they_look_for(tmp_path):
    """The parsers and the cycle finder on a small made-up tree: a prototype, a typedef, a definition, a cycle."""
    h = tmp_path / "tc_a.h"
    h.write_text('#include "tc_b.h"\n/* tc_not(void); */\ntypedef void tc_fn_type(int x);\n'
                 "#define TC_X(n) \\\n    (n)\nint tc_a_run(size_t n,\n             double *x);\n")
    c = tmp_path / "tc_a.c"
    c.write_text('#include "tc_a.h"\nstatic int helper(void) { return 0; }\ntypedef struct tc_s { int n; } tc_s;\n'
                 "int tc_a_run(size_t n, double *x) {\n    int k = tc_b_go(n, x);\n    return k;\n}\n")
    assert declared(h) == {"tc_a_run"}
    assert declared(c) == set(), "a definition declares nothing else, calls in its body are not declarations"
    assert defined(c) == {"tc_a_run"}
    assert includes(h) == ["tc_b.h"]
    found = cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}})
    assert found[0] == found[-1] and sorted(found[:-1]) == ["a", "b", "c"]
    assert cycle({"a": {"b"}, "b": set()}) == []
