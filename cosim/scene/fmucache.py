"""FMUs of this project's components, built on demand and cached (scene key ``component = "..."``).

``component = "stripdraw"`` in a scene means: the FMU the project builds from that component's
description (:mod:`tribocosim.components.registry`), in C (this machine's binary), built the first time it
is needed and kept in a cache folder, ``$TRIBOCOSIM_CACHE`` or ``~/.cache/tribocosim/fmus``. The cache entry is keyed
by the builder's source digest (the FMU's code, its model modules and its resource files, e.g. the
friction table), so editing the model or replacing the table rebuilds the FMU and nothing else
does. The build goes to a temporary folder that is renamed into place, so concurrent runs never
see a half-written FMU.

This is one of the two places where :mod:`tribocosim.cosim` imports :mod:`tribocosim.components`
(the other is :mod:`tribocosim.cosim.scene.component_checks`), and it does so lazily: a scene that
names only ``path = ...`` FMUs never imports the builder.
"""

from __future__ import annotations

import os
from pathlib import Path

from tribocosim.errors import SceneError, TribocosimError
from tribocosim.components.native.toolchain.library import cache_dir
from tribocosim.cosim.scene.binaries import host_platform


def component_fmu(component: str, cache: Path | None = None) -> Path:
    """Return the path of the cached FMU of ``component``, building it if needed.

    Parameters
    ----------
    component : str
        Component name (``"stripdraw"``) or model identifier (``"StripDraw"``), case-insensitive.
    cache : Path, optional
        Cache folder (default :func:`cache_dir`).

    Raises
    ------
    SceneError
        If the component is unknown or the build fails (with the builder's message).
    """
    from tribocosim.components import registry
    from tribocosim.components.fmus.cache_key import digest_key
    from tribocosim.components.native.toolchain.digests import remembered

    comp = registry.find(component)
    if comp is None:
        raise SceneError(f"unknown component {component!r}; this installation builds: "
                         f"{', '.join(c.name for c in registry.components().values())}")
    name = comp.model_identifier
    if comp.native is None:
        raise SceneError(f"component {component!r} has no native implementation: the project builds its FMUs in C; "
                         "a component written in Python is a pythonfmu FMU of its own, named by path = ... "
                         "(docs/user-guide.md)")
    root = Path(cache) if cache is not None else cache_dir()
    digest = remembered(digest_key(name))  # native_build.digest_key: found without importing the builder
    if digest is None:
        from tribocosim.components.fmus import native_build

        try:
            digest = native_build.source_digest(name)
        except TribocosimError as exc:
            raise SceneError(f"component {component!r}: {exc}") from exc
    entry = root / f"{name}-native-{digest[:16]}"
    fmu = entry / f"{name}.fmu"
    if fmu.is_file():
        return fmu
    import shutil
    import tempfile

    root.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{name}-", dir=root))
    try:
        from tribocosim.components.fmus import native_build

        native_build.build_native_fmus(tmp, names=[name], platforms=[host_platform()])
        try:
            os.rename(tmp, entry)
        except OSError:
            if not fmu.is_file():  # someone else won the race with a broken entry
                raise
    except TribocosimError as exc:
        raise SceneError(f"component {component!r}: building {name}.fmu failed: {exc}") from exc
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    return fmu
