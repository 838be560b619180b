"""What is imported on first use, so that importing a package, or running a command, stays cheap: package attributes
(:func:`lazy_exports`) and logging (:func:`log`, :func:`log_to_console`: a run that has nothing to say never imports
``logging``, some 18 million instructions with what it imports, callgrind)."""

from __future__ import annotations

import importlib
import sys

#: logging's levels by number (so that naming one imports nothing)
INFO, WARNING = 20, 30

#: the console configuration a command asked for while logging was not imported (:func:`log_to_console`)
_console: dict = {}


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


def log_to_console(fmt: str, level: int = WARNING) -> None:
    """Messages of ``level`` and above to stderr in ``fmt``, as ``logging.basicConfig(level=level, format=fmt)``: at
    once when logging is imported already, else with the first message :func:`log` passes on."""
    if "logging" in sys.modules:
        import logging

        logging.basicConfig(level=level, format=fmt)
    else:
        _console.update(level=level, format=fmt)


def log(name: str, level: int, message: str, *args) -> None:
    """``logging.getLogger(name).log(level, message, *args)``, logging imported (and configured as
    :func:`log_to_console` asked) with the first message."""
    import logging

    if _console:
        logging.basicConfig(**_console)
        _console.clear()
    logging.getLogger(name).log(level, message, *args)
