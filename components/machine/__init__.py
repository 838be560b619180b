"""The drawing machine: model, parameters and component description.

``MachineParameters`` and ``MachineModel`` are imported on first use.
"""

from __future__ import annotations

import importlib

_API = {"MachineParameters": "parameters", "MachineModel": "model"}

__all__ = sorted(_API)


def __getattr__(name: str):
    if name not in _API:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{_API[name]}"), name)
    globals()[name] = value
    return value
