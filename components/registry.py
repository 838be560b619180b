"""Where the component descriptions are found: every ``tribocosim/components/<name>/component.py``.

A subpackage of :mod:`tribocosim.components` that has a ``component`` module holding a
:class:`~tribocosim.components.description.Component` named ``COMPONENT`` is a component; nothing
else lists it. :func:`register` adds a description from elsewhere (a user's own component, a test's),
for this process. Names are matched case-insensitively and without ``_``/``-``
(``"drawing_machine"`` finds ``drawingmachine``).

Only the ``component`` modules are imported (they import parameter dataclasses, not the models),
so that looking a component up stays cheap.
"""

from __future__ import annotations

import importlib
import os

from tribocosim.components.description import Component
from tribocosim.errors import SceneError

_REGISTERED: dict[str, Component] = {}
_FOUND: dict[str, Component] | None = None


def normal(name: str) -> str:
    """The lookup form of a component name: lower case, no ``_`` or ``-``."""
    return name.lower().replace("_", "").replace("-", "")


def _discover() -> dict[str, Component]:
    global _FOUND
    if _FOUND is None:
        import tribocosim.components as package

        found = {}
        folders = sorted({entry.name for root in package.__path__ for entry in os.scandir(root)
                          if entry.is_dir() and os.path.isfile(os.path.join(entry.path, "component.py"))
                          and os.path.isfile(os.path.join(entry.path, "__init__.py"))})
        for name in folders:
            comp = importlib.import_module(f"{package.__name__}.{name}.component").COMPONENT
            found[normal(comp.name)] = comp
        _FOUND = found
    return _FOUND


def components() -> dict[str, Component]:
    """Every known component by its normalised name: the built-in ones, then the registered ones."""
    return {**_discover(), **_REGISTERED}


def register(component: Component) -> Component:
    """Make ``component`` known in this process (replacing one of the same name); returns it.

    Its description must be the ``COMPONENT`` of an importable module (the one that defines its
    ``build`` function): a Python FMU's generated script imports it from there.
    """
    module_of(component)
    _REGISTERED[normal(component.name)] = component
    return component


def module_of(component: Component) -> str:
    """The module whose ``COMPONENT`` is ``component`` (the module that defines its ``build``)."""
    name = component.build.__module__
    module = importlib.import_module(name)
    if getattr(module, "COMPONENT", None) is not component:
        raise SceneError(f"component {component.name}: its description must be the COMPONENT of module {name}, "
                         "the module that defines its build function")
    return name


def unregister(name: str) -> None:
    """Forget a component added by :func:`register`."""
    _REGISTERED.pop(normal(name), None)


def find(name: str) -> Component | None:
    """The component called ``name`` (scene name or model identifier), or None."""
    key = normal(name)
    known = components()
    if key in known:
        return known[key]
    return next((c for c in known.values() if normal(c.model_identifier) == key), None)


def get(name: str) -> Component:
    """The component called ``name``; SceneError listing the known ones if there is none."""
    comp = find(name)
    if comp is None:
        raise SceneError(f"unknown component {name!r}; this installation has: {', '.join(components())}")
    return comp
