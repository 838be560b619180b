"""Package attributes imported on first use (so that importing a package stays cheap)."""

from __future__ import annotations

import importlib


def lazy_exports(package: str, names: dict[str, str]):
    """``(__getattr__, __all__)`` for ``package``: attribute ``name`` is ``module.name`` where
    ``names[name]`` is ``module`` (absolute, or relative to the package when it starts with a dot)."""

    def __getattr__(name: str):
        if name not in names:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        module = names[name]
        value = getattr(importlib.import_module(f"{package}{module}" if module.startswith(".") else module), name)
        setattr(importlib.import_module(package), name, value)
        return value

    return __getattr__, sorted(names)
