"""The package's modules: every one imports, none is part of an import loop, the layers import only downwards, and no
two modules share a name.

The import graph is read from the source (every ``import`` statement, at module level or inside a function, and the
names ``lazy_exports`` maps to modules), so a loop hidden by deferring an import into a function is still a loop.
An edge from a module to a package that contains it (importing a submodule runs its package's ``__init__``) is not a
loop.
"""

from __future__ import annotations

import ast
import graphlib
import subprocess
import sys
import tomllib
from collections import defaultdict
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

#: the layers, lowest first: a module imports only from its own layer and the layers below it. The package roots
#: (``tribocosim``, ``tribocosim.cosim`` and the console script ``tribocosim.cli``) are facades over every layer.
LAYERS = (
    ("tribocosim.atomic", "tribocosim.errors", "tribocosim.interrupt", "tribocosim.lazy", "tribocosim.paths",
     "tribocosim.name_value", "tribocosim.public"),
    ("tribocosim.components", "tribocosim.models"),
    ("tribocosim.surrogate",),
    ("tribocosim.cosim.engine",),
    ("tribocosim.cosim.scene",),
    ("tribocosim.cosim.ssp",),
    ("tribocosim.cosim.api",),
    ("tribocosim.cosim.studies",),
    ("tribocosim.cosim.apps", "tribocosim.cosim.reports"),
)
FACADES = {"tribocosim", "tribocosim.cli", "tribocosim.cosim"}
#: module names several modules share by design: a component's folder holds its description, model and parameters
#: under these names (tribocosim.components.registry finds the components by them)
CONVENTION = {"__init__", "component", "model", "parameters"}


def package_modules(root: Path = ROOT) -> dict[str, Path]:
    """``{module name: source file}`` of every module of the distribution (pyproject's package-dir)."""
    mapping = tomllib.loads((root / "pyproject.toml").read_text())["tool"]["setuptools"]["package-dir"]
    out = {}
    for package, folder in mapping.items():
        for path in sorted((root / folder).rglob("*.py")):
            parts = list(path.relative_to(root / folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join([package, *parts])] = path
    return out


def _resolve(name: str, modules) -> str | None:
    """The module ``name`` is, or is inside of (``a.b.attr`` -> ``a.b``); None outside the package."""
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name or None


def imports(name: str, path: Path, modules) -> dict[str, int]:
    """``{imported module: line}`` of one module."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = {}

    def add(target: str, line: int):
        module = _resolve(target, modules)
        if module and module != name and not name.startswith(module + "."):
            found.setdefault(module, line)

    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                add(alias.name, node.lineno)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                base = f"{anchor}.{base}" if base else anchor
            for alias in node.names:
                add(f"{base}.{alias.name}", node.lineno)
        elif isinstance(node, ast.Call) and getattr(node.func, "id", None) == "lazy_exports" and len(node.args) == 2:
            if isinstance(node.args[1], ast.Dict):
                for value in node.args[1].values:
                    if isinstance(value, ast.Constant) and isinstance(value.value, str):
                        add(f"{name}{value.value}" if value.value.startswith(".") else value.value, node.lineno)
    return found


def graph(modules) -> dict[str, dict[str, int]]:
    return {name: imports(name, path, modules) for name, path in modules.items()}


def loop(edges) -> list[str]:
    """An import loop (its modules, the first repeated at the end), or [] when there is none."""
    try:
        graphlib.TopologicalSorter(edges).prepare()
    except graphlib.CycleError as exc:
        return list(exc.args[1])
    return []


def layer(name: str) -> int | None:
    for k, prefixes in enumerate(LAYERS):
        if any(name == p or name.startswith(p + ".") for p in prefixes):
            return k
    return None


@pytest.fixture(scope="module")
def modules():
    return package_modules()


def test_every_module_of_the_package_imports(modules):
    """All of them in one fresh interpreter (a module that cannot be imported, e.g. after a move, fails here)."""
    script = ("import importlib, sys\n"
              "bad = []\n"
              "for name in sys.argv[1:]:\n"
              "    try:\n"
              "        importlib.import_module(name)\n"
              "    except Exception as exc:\n"
              "        bad.append(f'{name}: {type(exc).__name__}: {exc}')\n"
              "print('\\n'.join(bad))\n"
              "sys.exit(1 if bad else 0)\n")
    proc = subprocess.run([sys.executable, "-c", script, *sorted(modules)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, f"modules that do not import:\n{proc.stdout}{proc.stderr[-3000:]}"
    assert len(modules) > 100 and "tribocosim.cosim.engine.master" in modules


def test_no_module_is_part_of_an_import_loop(modules):
    edges = graph(modules)
    found = loop(edges)
    detail = [f"{b} imports {a} (line {edges[b][a]})" for a, b in zip(found, found[1:])]
    assert not found, "an import loop (fix it and run again: there may be more):\n" + "\n".join(detail)


def test_layers_import_only_downwards(modules):
    up = []
    for a, targets in graph(modules).items():
        if a in FACADES:
            continue
        assert layer(a) is not None, f"{a} belongs to no layer of LAYERS"
        up += [f"{a} -> {b} (line {line})" for b, line in targets.items()
               if b not in FACADES and layer(b) > layer(a)]
    assert not up, "imports of a higher layer:\n" + "\n".join(up)


def test_no_two_modules_share_a_name(modules):
    by_name = defaultdict(list)
    for name, path in modules.items():
        stem = path.stem if path.name != "__init__.py" else "__init__"
        by_name[stem].append(name)
    shared = {stem: names for stem, names in by_name.items() if len(names) > 1 and stem not in CONVENTION}
    assert not shared, f"module names used twice: {shared}"
    components = ROOT / "components"
    for stem in CONVENTION - {"__init__"}:
        places = {modules[n].parent.parent for n in by_name[stem]}
        assert places <= {components}, f"{stem}.py outside a component's folder: {by_name[stem]}"


def test_the_checks_find_a_loop_hidden_in_a_function(tmp_path):
    """A made-up package: b imports a inside a function, a imports b at the top; c is outside the loop."""
    (tmp_path / "pyproject.toml").write_text('[tool.setuptools]\npackage-dir = { "pkg" = "pkg" }\n')
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from pkg.b import f\n")
    (pkg / "b.py").write_text("def f():\n    from . import a\n    return a\n")
    (pkg / "c.py").write_text("import pkg.a\nfrom pkg import lazy\nX = lazy.lazy_exports(__name__, {'y': '.d'})\n")
    mods = package_modules(tmp_path)
    assert sorted(mods) == ["pkg", "pkg.a", "pkg.b", "pkg.c"]
    edges = graph(mods)
    assert edges["pkg.b"] == {"pkg.a": 2} and edges["pkg.a"] == {"pkg.b": 1}
    found = loop(edges)
    assert found[0] == found[-1] and sorted(found[:-1]) == ["pkg.a", "pkg.b"]
    assert loop({"x": {"y": 1}, "y": {}}) == []
