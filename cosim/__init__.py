"""Co-simulation: scenes, the master algorithms on fmpy, results, reports and the CLI.

Public API (imported lazily, so that importing the package costs nothing)::

    from tribocosim.cosim import run, load_scene
    result = run("scene.toml")            # -> cosim.api.Result
    result["strip.pull_force"], result.metadata["steps"]
"""

from __future__ import annotations

__all__ = ["run", "load_scene", "Result"]


def __getattr__(name: str):
    if name in ("run", "Result"):
        from tribocosim.cosim import api

        return getattr(api, name)
    if name == "load_scene":
        from tribocosim.cosim.scene.validate import load_scene

        return load_scene
    raise AttributeError(f"module 'cosim' has no attribute {name!r}")
