"""The one collector of scene and sweep problems: every problem found, then one SceneError.

Each check adds :class:`~tribocosim.errors.Problem` items (file, dotted key, message)
instead of stopping at the first; :meth:`Problems.raise_if_any` raises them together. The parser,
the validation against the model descriptions, the component checks and the sweep reader all
collect into it, so a user sees everything wrong with a file at once.
"""

from __future__ import annotations

import math
from pathlib import Path

from tribocosim.errors import Problem, SceneError


def known(names, given: str | None = None, limit: int = 40) -> str:
    """'did you mean ...; known: a, b, c' for an unknown name."""
    names = sorted(names)
    hint = ""
    if given is not None:
        import difflib

        close = difflib.get_close_matches(given, names, n=3, cutoff=0.6)
        if close:
            hint = "did you mean " + " or ".join(repr(c) for c in close) + "? "
    shown = ", ".join(names[:limit]) + (f", ... ({len(names)} in all)" if len(names) > limit else "")
    return f"{hint}known: {shown or '(none)'}"


class Problems:
    """Problems of one file, in the order found."""

    def __init__(self, path: str | Path, kind: str = "scene") -> None:
        self.path = path
        self.kind = kind
        self.items: list[Problem] = []

    def add(self, key: str, message: str) -> None:
        """Record a problem of ``key``."""
        self.items.append(Problem(str(self.path), key, message))

    def extend(self, problems, skip_known_keys: bool = False) -> None:
        """Add other problems (of this file); with ``skip_known_keys`` not those of a key already reported."""
        keys = {p.key for p in self.items}
        self.items.extend(p for p in problems if not (skip_known_keys and p.key in keys))

    def unknown_keys(self, table: dict, allowed, key: str) -> None:
        """A problem for every key of ``table`` that is not ``allowed``."""
        for k in table:
            if k not in allowed:
                self.add(f"{key}.{k}" if key else k, f"unknown key; {known(allowed, k)}")

    # --- typed values of a TOML table: the value, or the default after recording a problem
    def number(self, table: dict, name: str, key: str, default, *, positive=False, integer=False):
        """``table[name]`` as a finite number (``> 0`` if ``positive``, an int if ``integer``)."""
        if name not in table:
            return default
        v = table[name]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or (integer and not isinstance(v, int)):
            self.add(f"{key}.{name}", f"must be {'an integer' if integer else 'a number'}, got {v!r}")
            return default
        if not math.isfinite(v) or (positive and v <= 0):
            self.add(f"{key}.{name}", f"must be finite{' and > 0' if positive else ''}, got {v!r}")
            return default
        return v

    def choice(self, table: dict, name: str, key: str, choices, default):
        """``table[name]`` if it is one of ``choices``."""
        if name not in table:
            return default
        v = table[name]
        if v not in choices:
            self.add(f"{key}.{name}", f"{v!r} is not allowed; allowed: {', '.join(map(str, choices))}")
            return default
        return v

    def table(self, doc: dict, name: str, key: str) -> dict:
        """``doc[name]`` if it is a table (default empty)."""
        v = doc.get(name, {})
        if not isinstance(v, dict):
            self.add(key, f"must be a table, got {type(v).__name__}")
            return {}
        return v

    def error(self) -> SceneError:
        """The SceneError listing every problem."""
        return SceneError(self.items, f"{self.kind} {self.path}")

    def raise_if_any(self) -> None:
        """Raise :meth:`error` if there is a problem."""
        if self.items:
            raise self.error()

    def __bool__(self) -> bool:
        return bool(self.items)

    def __len__(self) -> int:
        return len(self.items)
