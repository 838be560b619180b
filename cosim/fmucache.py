"""FMUs of this project's components, built on demand and cached (scene key ``component = "..."``).

``component = "stripdraw"`` in a scene means: the FMU the project builds from its own
components (``tribocosim.components.fmus.build.build_fmus``), built the first time it is needed and kept in
a cache folder, ``$TRIBOCOSIM_CACHE`` or ``~/.cache/tribocosim/fmus``. The cache entry is keyed
by the builder's source digest (adapter, the model modules it imports and its data files), so
editing the model rebuilds the FMU and nothing else does. The build goes to a temporary folder
that is renamed into place, so concurrent runs never see a half-written FMU.

This is one of the two places where :mod:`cosim` imports :mod:`components` (the other is the
monolithic reference), and it does so lazily: a scene that names only ``path = ...`` FMUs
never imports the builder.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import tempfile
from pathlib import Path

from tribocosim.components.errors import SceneError


def cache_dir() -> Path:
    """The FMU cache folder: ``$TRIBOCOSIM_CACHE`` or ``~/.cache/tribocosim/fmus``."""
    env = os.environ.get("TRIBOCOSIM_CACHE")
    return Path(env).expanduser() if env else Path.home() / ".cache" / "tribocosim" / "fmus"


def _normal(name: str) -> str:
    return name.lower().replace("_", "").replace("-", "")


def _builder():
    try:
        from tribocosim.components.fmus import build
    except ImportError as exc:
        raise SceneError(
            "the FMU builder tribocosim.components.fmus.build is not available in this installation "
            f"({exc}); build the FMU elsewhere and give its file with path = \"...\" instead"
        ) from exc
    if not hasattr(build, "build_fmus"):
        raise SceneError("tribocosim.components.fmus.build has no build_fmus(out_dir) function; cannot build components")
    return build


def _digest(build, name: str) -> str:
    if hasattr(build, "source_digest"):
        return build.source_digest(name)
    root = Path(build.__file__).resolve().parents[1]
    h = hashlib.sha256()
    for p in sorted(root.rglob("*.py")):
        h.update(str(p.relative_to(root)).encode())
        h.update(p.read_bytes())
    return h.hexdigest()


def component_fmu(component: str, cache: Path | None = None) -> Path:
    """Return the path of the cached FMU of ``component``, building it if needed.

    Parameters
    ----------
    component : str
        Component name, matched case-insensitively against the builder's FMU names
        (``"stripdraw"`` -> ``StripDraw``).
    cache : Path, optional
        Cache folder (default :func:`cache_dir`).

    Raises
    ------
    SceneError
        If the builder is missing, does not know the component, or the build fails.
    """
    build = _builder()
    names = list(getattr(build, "FMUS", {}) or [])
    matches = [n for n in names if _normal(n) == _normal(component)] if names else [component]
    if not matches:
        raise SceneError(f"unknown component {component!r}; this installation builds: {', '.join(names)}")
    name = matches[0]
    root = Path(cache) if cache is not None else cache_dir()
    try:
        digest = _digest(build, name)[:16]
    except Exception as exc:
        raise SceneError(f"component {component!r}: cannot compute the source digest: {exc}") from exc
    entry = root / f"{name}-{digest}"
    fmu = entry / f"{name}.fmu"
    if fmu.is_file():
        return fmu
    root.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{name}-", dir=root))
    try:
        built = build.build_fmus(tmp, names=[name]) if names else build.build_fmus(tmp)
        src = next((Path(p) for n, p in built.items() if _normal(n) == _normal(name)), None)
        if src is None or not src.is_file():
            raise SceneError(f"component {component!r}: the builder returned {sorted(built)} but no {name}.fmu")
        if src.name != fmu.name:
            src.rename(tmp / fmu.name)
        try:
            os.rename(tmp, entry)
        except OSError:
            if not fmu.is_file():  # someone else won the race with a broken entry
                raise
    except SceneError:
        raise
    except Exception as exc:
        raise SceneError(f"component {component!r}: building {name}.fmu failed: {exc}") from exc
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    return fmu
