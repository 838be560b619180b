"""tribocosim: friction with wear debris in sheet-metal strip drawing, as FMI co-simulation components.

One import name for the whole project (the repository's folders are its subpackages):

- :mod:`tribocosim.components`: the runtime models (strip draw, press, drawing machine) and their FMUs;
- :mod:`tribocosim.cosim`: scenes, the co-simulation master, results, reports;
- :mod:`tribocosim.surrogate`: the offline mesoscale model (BEM-DEM) and the friction-table pipeline;
- :mod:`tribocosim.models`: the shipped friction table and scenes (package data).

The names below are imported on first use, so ``import tribocosim`` costs nothing::

    import tribocosim
    result = tribocosim.run("demo")                 # a packaged scene name, or a scene file; nothing written
    result["strip.pull_force"], result.metadata["steps"]
    tribocosim.run("demo", "results")               # the CSV and JSON written into results/

    p = tribocosim.StripDrawParameters(tool_length=0.07)
    table = tribocosim.read_table(tribocosim.DEFAULT_TABLE)  # the shipped friction table
    model = tribocosim.StripDrawModel(p, tribocosim.make_friction_law(p, table))

    # the friction law for a forming simulation (docs/forming-friction.md)
    tribocosim.export_friction("lsdyna", "friction.k", tribocosim.DebrisChoice(beta=(0.1,)))
"""

from __future__ import annotations

from tribocosim.lazy import lazy_exports
from tribocosim.public import NAMES

__getattr__, __all__ = lazy_exports(__name__, NAMES)
