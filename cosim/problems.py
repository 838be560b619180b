"""The one collector of scene and sweep problems: every problem found, then one SceneError.

Each check adds :class:`~tribocosim.components.errors.Problem` items (file, dotted key, message)
instead of stopping at the first; :meth:`Problems.raise_if_any` raises them together. The parser,
the validation against the model descriptions, the component checks and the sweep reader all
collect into it, so a user sees everything wrong with a file at once.
"""

from __future__ import annotations

import difflib
from pathlib import Path

from tribocosim.components.errors import Problem, SceneError


def known(names, given: str | None = None, limit: int = 40) -> str:
    """'did you mean ...; known: a, b, c' for an unknown name."""
    names = sorted(names)
    hint = ""
    if given is not None:
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
