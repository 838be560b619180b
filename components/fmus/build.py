"""Build the project's FMUs with pythonfmu: one subprocess per FMU, resources limited to what runs.

For each FMU the build

1. finds the modules under ``components`` that its adapter imports, transitively
   (:class:`modulefinder.ModuleFinder`, a static scan that runs nothing), and refuses to build if
   one of them is missing;
2. stages the adapter, those modules and the FMU's data files (the default friction table) in a
   temporary folder;
3. runs ``python -m pythonfmu build --handle-state --serialize-state`` on the staged adapter in a
   subprocess (pythonfmu imports the adapter by module name and caches it in the process, so
   every FMU needs its own process);
4. checks the result with ``fmpy.validate_fmu`` and moves it into place atomically (a reader
   never sees a half-written FMU), next to a small JSON record of its source digest.

Before building anything, every selected FMU's files and import closure are checked, so that a
missing file fails the whole build without leaving some of the FMUs built.

An FMU's ``resources/`` then holds its adapter, ``components/__init__.py``, ``errors.py``, the
shared plumbing ``components/fmus/{adapter,statecodec,exitguard}.py``, the model modules the
adapter imports (StripDraw: ``components/stripdraw/*`` and ``friction_table.npz``; Press:
``press.py``, ``linear.py``, ``params.py``; DrawingMachine: ``machine.py``, ``linear.py``,
``params.py``), plus the copy of pythonfmu's Python files that pythonfmu always adds; nothing
from ``surrogate/`` or ``cosim/``, and no numba, scipy, pyfftw or matplotlib.

Python API: :func:`build_fmus`; command line: ``tribocosim fmu build [--out DIR]``.
"""

from __future__ import annotations

import hashlib
import json
import modulefinder
import os
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from components.errors import TribocosimError

#: Root of the source tree (holds ``components/`` and ``models/``).
PROJECT_ROOT = Path(__file__).resolve().parents[2]


class FmuBuildError(TribocosimError):
    """An FMU could not be built (missing file, pythonfmu failure, validation problems)."""


@dataclass(frozen=True)
class FmuSpec:
    """What one FMU is made of, relative to :data:`PROJECT_ROOT`."""

    adapter: str  # the pythonfmu script; its stem is the FMU's model identifier
    data: tuple[str, ...] = ()  # files copied to the root of resources/


#: Every FMU of the project, by model identifier.
FMUS: dict[str, FmuSpec] = {
    "StripDraw": FmuSpec(adapter="components/fmus/StripDraw.py", data=("models/friction_table.npz",)),
    "Press": FmuSpec(adapter="components/fmus/Press.py"),
    "DrawingMachine": FmuSpec(adapter="components/fmus/DrawingMachine.py"),
}


def runtime_files(name: str, root: Path = PROJECT_ROOT) -> list[Path]:
    """The files under ``components/`` that FMU ``name`` needs at run time (paths under ``root``).

    Raises
    ------
    FmuBuildError
        If the adapter imports a ``components`` module that does not exist.
    """
    spec = _spec(name)
    finder = modulefinder.ModuleFinder(path=[str(root)])
    finder.run_script(str(root / spec.adapter))
    missing, _maybe = finder.any_missing_maybe()
    missing = sorted(m for m in missing if m.split(".")[0] == "components")
    if missing:
        raise FmuBuildError(f"FMU {name}: the adapter imports missing modules: {', '.join(missing)}")
    files = {
        Path(mod.__file__).resolve()
        for mod_name, mod in finder.modules.items()
        if mod_name.split(".")[0] == "components" and mod.__file__
    }
    return sorted(files)


def source_digest(name: str, root: Path = PROJECT_ROOT) -> str:
    """SHA-256 over the adapter, its runtime modules and data files of FMU ``name``."""
    spec = _spec(name)
    h = hashlib.sha256()
    paths = [root / spec.adapter, *runtime_files(name, root), *(root / d for d in spec.data)]
    for path in paths:
        h.update(str(path.relative_to(root)).encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def build_fmus(out_dir: str | os.PathLike, names=None, *, root: str | os.PathLike = PROJECT_ROOT) -> dict[str, Path]:
    """Build FMUs into ``out_dir`` (created if needed) and return ``{name: path to .fmu}``.

    Parameters
    ----------
    out_dir : path
        Destination folder; an existing ``<name>.fmu`` is replaced atomically.
    names : iterable of str, optional
        Model identifiers to build (keys of :data:`FMUS`); default all.
    root : path, optional
        Source tree to build from (default: the tree this module belongs to).

    Raises
    ------
    FmuBuildError
        Naming the FMU and the cause (missing file, pythonfmu's error output, validation problems).
    """
    out = Path(out_dir).resolve()  # the build subprocess runs in another folder
    out.mkdir(parents=True, exist_ok=True)
    root = Path(root).resolve()
    selected = list(FMUS) if names is None else list(names)
    for name in selected:
        _spec(name)
    for name in selected:  # every FMU's files and imports, before building any of them
        _check_files(name, root)
        runtime_files(name, root)
    return {name: _build_one(name, out, root) for name in selected}


def _spec(name: str) -> FmuSpec:
    try:
        return FMUS[name]
    except KeyError:
        raise FmuBuildError(f"unknown FMU {name!r}; this project builds: {', '.join(FMUS)}") from None


def _check_files(name: str, root: Path) -> None:
    spec = _spec(name)
    for rel in (spec.adapter, *spec.data):
        if not (root / rel).is_file():
            raise FmuBuildError(f"FMU {name}: required file {root / rel} is missing")


def _build_one(name: str, out: Path, root: Path) -> Path:
    spec = _spec(name)
    _check_files(name, root)
    digest = source_digest(name, root)
    with tempfile.TemporaryDirectory(prefix=f"tribocosim-fmu-{name}-") as tmp:
        stage = Path(tmp) / "stage"
        script = stage / Path(spec.adapter).name
        stage.mkdir()
        shutil.copy2(root / spec.adapter, script)
        for path in runtime_files(name, root):
            dest = stage / path.relative_to(root)
            dest.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(path, dest)
        data = []
        for rel in spec.data:
            shutil.copy2(root / rel, stage / Path(rel).name)
            data.append(str(stage / Path(rel).name))
        partial = out / f".{name}.{os.getpid()}.partial.fmu"
        cmd = [
            sys.executable, "-m", "pythonfmu", "build",
            "-f", str(script), "--dest", str(partial),
            "--handle-state", "--serialize-state",
            str(stage / "components"), *data,
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
