"""Where the shipped data lives: the package ``tribocosim.models`` (a wheel's or the source tree's).

Found as the folder of that package, so the same code works from a wheel installed in site-packages and from an
editable install of the repository (where ``tribocosim.models`` is the ``models/`` folder); the package is a folder
of files in both (numpy, the C code and the FMU build read them by path).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

from tribocosim.errors import SceneError

MODELS_DIR = Path(importlib.util.find_spec("tribocosim.models").submodule_search_locations[0])
DEFAULT_TABLE = MODELS_DIR / "friction_table.npz"
SCENES_DIR = MODELS_DIR / "scenes"


def packaged_scenes() -> list[str]:
    """Names (file stems) of the scenes shipped in ``tribocosim.models/scenes``."""
    return sorted(p.stem for p in SCENES_DIR.glob("*.toml"))


def scene_file(scene) -> Path:
    """A scene argument as a file: an existing path, else a packaged scene's name (``"demo"`` or ``"demo.toml"``).

    Raises
    ------
    SceneError
        If ``scene`` is neither a file nor the name of a packaged scene (the message lists the packaged scenes), a
        folder (the message names the scene files in it), or an FMU (the message says how to run one).
    """
    path = Path(scene)
    if path.is_file() and path.suffix.lower() == ".fmu":
        raise SceneError(f"{scene} is an FMU, not a scene: write a scene file (TOML) that names it, e.g. [experiment] "
                         f"stop = 1.0, step = 1e-3 and [fmus.{_instance(path)}] path = \"{path.name}\", and run that "
                         "(docs/scene-format.md)")
    if path.is_file():
        return path
    name = path.name if path.suffix == ".toml" else f"{path.name}.toml"
    packaged = SCENES_DIR / name
    if path.parent == Path(".") and packaged.is_file():  # a packaged scene's name, also where its results went (./NAME)
        return packaged
    if path.is_dir():
        inside = sorted(p.name for p in path.iterdir() if p.suffix.lower() in (".toml", ".ssp") and p.is_file())
        raise SceneError(f"{scene} is a folder, not a scene file: give a scene (TOML) or an SSP package (.ssp)"
                         + (f"; it holds {', '.join(inside[:10])}{', ...' if len(inside) > 10 else ''}" if inside
                            else ""))
    raise SceneError(f"scene file not found: {scene} (and it is not one of the packaged scenes: "
                     f"{', '.join(packaged_scenes())})")


def _instance(fmu: Path) -> str:
    """An instance name for the FMU file ``fmu`` in a scene (its stem in lower case, dots and spaces as ``_``)."""
    return fmu.stem.lower().replace(".", "_").replace(" ", "_") or "fmu"


def is_packaged(path) -> bool:
    """Whether ``path`` is one of the packaged scenes (their folder is no place for results)."""
    try:
        return Path(path).resolve().parent == SCENES_DIR.resolve()
    except OSError:
        return False
