"""A clone of the repository imported as the package ``tribocosim``.

Python imports a folder named like a package from the current directory before any installed package: from the folder
that holds a clone named ``tribocosim``, ``import tribocosim`` reads this folder, not the installed package. This file
makes the folder the package the clone holds, laid out as pyproject.toml's package-dir lays out a wheel: the
subpackages ``tribocosim.components``, ``.cosim``, ``.surrogate`` and ``.models`` are the folders here, and the
package's own modules (``tribocosim.cli``, ``.errors``, ...) those of ``tribocosim/``; the names ``import tribocosim``
offers are those of ``tribocosim/__init__.py`` (``tribocosim/public.py``). An installed tribocosim is not read then:
the clone's code runs.
"""

import os as _os

_ROOT = _os.path.dirname(_os.path.abspath(__file__))
__path__ = [_os.path.join(_ROOT, "tribocosim"), _ROOT]

from tribocosim.lazy import lazy_exports as _lazy_exports  # noqa: E402 - found through __path__
from tribocosim.public import NAMES as _NAMES  # noqa: E402

__getattr__, __all__ = _lazy_exports(__name__, _NAMES)
