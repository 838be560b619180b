"""Build the project's FMUs with pythonfmu: one subprocess per FMU, resources limited to what runs.

For each FMU the build

1. finds the ``tribocosim`` modules that its adapter imports, transitively (:func:`runtime_modules`:
   a static scan of the import statements, resolved with :func:`importlib.util.find_spec`, so it
   works the same from a wheel and from an editable install), and refuses to build if one of
   them is missing;
2. stages the adapter, those modules (at their package paths, ``tribocosim/components/...``) and
   the FMU's data files (the default friction table) in a temporary folder;
3. runs ``python -m pythonfmu build --handle-state --serialize-state`` on the staged adapter in a
   subprocess (pythonfmu imports the adapter by module name and caches it in the process, so
   every FMU needs its own process);
4. checks the result with ``fmpy.validate_fmu`` and moves it into place atomically (a reader
   never sees a half-written FMU), next to a small JSON record of its source digest.

Before building anything, every selected FMU's files and import closure are checked, so that a
missing file fails the whole build without leaving some of the FMUs built.

An FMU's ``resources/`` then holds its adapter, ``tribocosim/__init__.py``,
``tribocosim/components/__init__.py``, ``errors.py``, the shared plumbing
``tribocosim/components/fmus/{adapter,statecodec,exitguard}.py``, the model modules the adapter
imports (StripDraw: ``stripdraw/*`` and ``friction_table.npz``; Press: ``press.py``, ``linear.py``,
``params.py``; DrawingMachine: ``machine.py``, ``linear.py``, ``params.py``), plus the copy of
pythonfmu's Python files that pythonfmu always adds; nothing from ``surrogate`` or ``cosim``, and no
numba, scipy, pyfftw or matplotlib.

Python API: :func:`build_fmus`; command line: ``tribocosim fmu build [--out DIR]``.
"""

from __future__ import annotations

import ast
import hashlib
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from tribocosim.components.errors import TribocosimError
from tribocosim.components.paths import DEFAULT_TABLE

#: the package whose modules an FMU bundles (nothing outside it is staged)
PACKAGE = "tribocosim"


class FmuBuildError(TribocosimError):
    """An FMU could not be built (missing file, pythonfmu failure, validation problems)."""


@dataclass(frozen=True)
class FmuSpec:
    """What one FMU is made of: its adapter module and the data files for the root of ``resources/``."""

    adapter: str  # module of the pythonfmu script; its last part is the FMU's model identifier
    data: tuple[Path, ...] = ()


#: Every FMU of the project, by model identifier.
FMUS: dict[str, FmuSpec] = {
    "StripDraw": FmuSpec(adapter="tribocosim.components.fmus.StripDraw", data=(DEFAULT_TABLE,)),
    "Press": FmuSpec(adapter="tribocosim.components.fmus.Press"),
    "DrawingMachine": FmuSpec(adapter="tribocosim.components.fmus.DrawingMachine"),
}


def module_file(name: str) -> Path | None:
    """The source file of module ``name`` (``__init__.py`` for a package), or None if there is none."""
    try:
        spec = importlib.util.find_spec(name)
    except (ImportError, ValueError):
        return None
    if spec is None or not spec.origin or not spec.origin.endswith(".py"):
        return None
    return Path(spec.origin).resolve()


def _imported_names(path: Path) -> set[str]:
    """Every absolute module name an ``import`` statement in ``path`` may load (``from a import b``
    gives ``a`` and ``a.b``: ``b`` may be a submodule)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return names


def runtime_modules(name: str) -> dict[str, Path]:
    """The ``tribocosim`` modules FMU ``name`` needs at run time: ``{module name: source file}``.

    The import closure of the adapter, found statically (nothing is run), plus the ``__init__``
    of every package on the way. The adapter itself is not included.

    Raises
    ------
    FmuBuildError
        If the adapter, or a module it imports, imports a ``tribocosim`` module that does not exist.
    """
    spec = _spec(name)
    adapter = module_file(spec.adapter)
    if adapter is None:
        raise FmuBuildError(f"FMU {name}: the adapter module {spec.adapter} is missing")
    found: dict[str, Path] = {}
    missing: set[str] = set()
    todo = [(adapter, spec.adapter)]
    while todo:
        path, importer = todo.pop()
        for mod in sorted(_imported_names(path)):
            if mod.split(".")[0] != PACKAGE or mod in found or mod == spec.adapter:
                continue
            parts = mod.split(".")
            for k in range(1, len(parts) + 1):
                prefix = ".".join(parts[:k])
                if prefix in found:
                    continue
                src = module_file(prefix)
                if src is None:
                    if not _is_attribute(prefix):
                        missing.add(prefix)
                    break
                found[prefix] = src
                todo.append((src, prefix))
    if missing:
        raise FmuBuildError(f"FMU {name}: the adapter imports missing modules: {', '.join(sorted(missing))}")
    return dict(sorted(found.items()))


def _is_attribute(name: str) -> bool:
    """Whether ``a.b.c`` is a name defined in module ``a.b`` (``from a.b import c``) rather than a module."""
    parent, _, attr = name.rpartition(".")
    path = module_file(parent)
    if path is None:
        return False
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.ClassDef, ast.AsyncFunctionDef)) and node.name == attr:
            return True
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == attr for t in node.targets):
            return True
        if isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) and node.target.id == attr:
            return True
        if isinstance(node, (ast.Import, ast.ImportFrom)) and any((a.asname or a.name.split(".")[0]) == attr
                                                                  for a in node.names):
            return True
    return False


def runtime_files(name: str) -> list[Path]:
    """The source files of :func:`runtime_modules` (sorted)."""
    return sorted(runtime_modules(name).values())


def resource_paths(name: str) -> list[str]:
    """The paths, relative to ``resources/``, of the modules FMU ``name`` bundles (``tribocosim/...``)."""
    return sorted(_staged_path(m, p).as_posix() for m, p in runtime_modules(name).items())


def _staged_path(module: str, source: Path) -> Path:
    """Where module ``module`` goes in an FMU's ``resources/``: its package path."""
    parts = module.split(".")
    if source.name == "__init__.py":
        return Path(*parts, "__init__.py")
    return Path(*parts[:-1], f"{parts[-1]}.py")


def source_digest(name: str) -> str:
    """SHA-256 over the adapter, its runtime modules and data files of FMU ``name``."""
    spec = _spec(name)
    h = hashlib.sha256()
    entries = [(spec.adapter, module_file(spec.adapter)), *runtime_modules(name).items(),
               *((d.name, Path(d)) for d in spec.data)]
    for label, path in entries:
        h.update(str(label).encode())
        h.update(Path(path).read_bytes())
    return h.hexdigest()


def build_fmus(out_dir: str | os.PathLike, names=None) -> dict[str, Path]:
    """Build FMUs into ``out_dir`` (created if needed) and return ``{name: path to .fmu}``.

    Parameters
    ----------
    out_dir : path
        Destination folder; an existing ``<name>.fmu`` is replaced atomically.
    names : iterable of str, optional
        Model identifiers to build (keys of :data:`FMUS`); default all.

    Raises
    ------
    FmuBuildError
        Naming the FMU and the cause (missing file, pythonfmu's error output, validation problems).
    """
    out = Path(out_dir).resolve()  # the build subprocess runs in another folder
    out.mkdir(parents=True, exist_ok=True)
    selected = list(FMUS) if names is None else list(names)
    for name in selected:
        _spec(name)
    for name in selected:  # every FMU's files and imports, before building any of them
        _check_files(name)
        runtime_modules(name)
    return {name: _build_one(name, out) for name in selected}


def _spec(name: str) -> FmuSpec:
    try:
        return FMUS[name]
    except KeyError:
        raise FmuBuildError(f"unknown FMU {name!r}; this project builds: {', '.join(FMUS)}") from None


def _check_files(name: str) -> None:
    spec = _spec(name)
    for path in spec.data:
        if not Path(path).is_file():
            raise FmuBuildError(f"FMU {name}: required file {path} is missing")


def _build_one(name: str, out: Path) -> Path:
    spec = _spec(name)
    _check_files(name)
    digest = source_digest(name)
    identifier = spec.adapter.rsplit(".", 1)[-1]
    with tempfile.TemporaryDirectory(prefix=f"tribocosim-fmu-{name}-") as tmp:
        stage = Path(tmp) / "stage"
        script = stage / f"{identifier}.py"
        stage.mkdir()
        shutil.copy2(module_file(spec.adapter), script)
        for module, path in runtime_modules(name).items():
            dest = stage / _staged_path(module, path)
            dest.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(path, dest)
        data = []
        for path in spec.data:
            shutil.copy2(path, stage / Path(path).name)
            data.append(str(stage / Path(path).name))
        partial = out / f".{name}.{os.getpid()}.partial.fmu"
        cmd = [
            sys.executable, "-m", "pythonfmu", "build",
            "-f", str(script), "--dest", str(partial),
            "--handle-state", "--serialize-state",
            str(stage / PACKAGE), *data,
        ]  # fmt: skip
        env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
        env.pop("PYTHONPATH", None)  # the staged copy, not another tree, must be imported
        proc = subprocess.run(cmd, cwd=stage, env=env, capture_output=True, text=True)
        if proc.returncode != 0 or not partial.is_file():
            partial.unlink(missing_ok=True)
            tail = "\n".join((proc.stdout + proc.stderr).strip().splitlines()[-20:])
            raise FmuBuildError(
                f"FMU {name}: pythonfmu build (exit {proc.returncode}) produced no {partial}:\n{tail}"
            )
    try:
        from fmpy.validation import validate_fmu

        problems = validate_fmu(str(partial))
        if problems:
            raise FmuBuildError(f"FMU {name}: fmpy validate found problems:\n" + "\n".join(problems))
        target = out / f"{name}.fmu"
        os.replace(partial, target)
    finally:
        partial.unlink(missing_ok=True)
    record = {"name": name, "source_digest": digest, "python": sys.version.split()[0]}
    tmp_json = out / f".{name}.{os.getpid()}.partial.json"
    tmp_json.write_text(json.dumps(record, indent=2) + "\n")
    os.replace(tmp_json, out / f"{name}.fmu.json")
    return target
