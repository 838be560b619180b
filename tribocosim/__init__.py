"""tribocosim: friction with wear debris in sheet-metal strip drawing, as FMI co-simulation components.

One import name for the whole project (the repository's folders are its subpackages):

- :mod:`tribocosim.components`: the runtime models (strip draw, press, drawing machine) and their FMUs;
- :mod:`tribocosim.cosim`: scenes, the co-simulation master, results, reports;
- :mod:`tribocosim.surrogate`: the offline mesoscale model (BEM-DEM) and the friction-table pipeline;
- :mod:`tribocosim.models`: the shipped friction table and scenes (package data).

The names below are imported on first use, so ``import tribocosim`` costs nothing::

    import tribocosim
    result = tribocosim.run("demo")                 # a packaged scene name, or a scene file
    result["strip.pull_force"], result.metadata["steps"]

    p = tribocosim.StripDrawParameters(tool_length=0.07)
    table = tribocosim.read_table(tribocosim.DEFAULT_TABLE)
    model = tribocosim.StripDrawModel(p, tribocosim.make_friction_law(p, table))
"""

from __future__ import annotations

import importlib

#: public name -> (module, attribute)
_API = {
    "run": ("tribocosim.cosim.api", "run"),
    "Result": ("tribocosim.cosim.api", "Result"),
    "load_scene": ("tribocosim.cosim.validate", "load_scene"),
    "StripDrawModel": ("tribocosim.components.stripdraw.model", "StripDrawModel"),
    "StripDrawParameters": ("tribocosim.components.stripdraw.parameters", "StripDrawParameters"),
    "make_friction_law": ("tribocosim.components.stripdraw.friction", "make_friction_law"),
    "FrictionTable": ("tribocosim.components.stripdraw.table", "FrictionTable"),
    "read_table": ("tribocosim.components.stripdraw.table", "read_table"),
    "write_table": ("tribocosim.components.stripdraw.table", "write_table"),
    "DEFAULT_TABLE": ("tribocosim.components.paths", "DEFAULT_TABLE"),
    "scene_file": ("tribocosim.components.paths", "scene_file"),
    "TribocosimError": ("tribocosim.components.errors", "TribocosimError"),
}

__all__ = sorted(_API)


def __getattr__(name: str):
    try:
        module, attribute = _API[name]
    except KeyError:
        raise AttributeError(f"module 'tribocosim' has no attribute {name!r}") from None
    value = getattr(importlib.import_module(module), attribute)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_API))
