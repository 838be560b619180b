"""The strip-draw model: 1D bar under a pad, interface law, debris transport, friction law.

Pure physics (numpy; numba optional): no FMI, no printing. The table module is the one place
that reads and writes friction-table files.

The names below are imported on first use, so that importing a light module of this package
(``parameters``, ``table``) does not import the model and its compiled kernels.
"""

from __future__ import annotations

import importlib

_API = {
    "INPUT_NAMES": "model",
    "OUTPUT_NAMES": "model",
    "StripDrawModel": "model",
    "StripDrawParameters": "parameters",
    "FrictionTable": "table",
    "read_table": "table",
    "write_table": "table",
    "closed_form_table": "friction",
    "make_friction_law": "friction",
}

__all__ = sorted(_API)


def __getattr__(name: str):
    if name not in _API:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{_API[name]}"), name)
    globals()[name] = value
    return value
