"""Work-around for a crash at process exit in pythonfmu 0.7.0 FMUs on Linux (bundled into the FMUs).

The bug (pythonfmu 0.7.0, ``pythonfmu-export``, Linux): the FMU's shared library keeps its
Python-state object in a static ``std::shared_ptr pyState`` and resets it from a library
destructor, ``finalizePythonInterpreter`` (``__attribute__((destructor))``). The library
exports ``STB_GNU_UNIQUE`` symbols, so ``dlclose`` never unloads it; it is still loaded when the
process exits, and ``exit()`` destroys C++ statics (``__cxa_atexit``) *before* it runs library
destructors (``_dl_fini``). If the importer has freed every instance, the static's destructor
frees the state object, then ``finalizePythonInterpreter`` releases it a second time: a
use-after-free (seen with valgrind) that corrupts the heap. Whether the process then aborts
depends on the heap layout; with this project's FMU in this project's environment (numba and
scipy loaded) ``fmpy simulate`` aborted at exit ("corrupted double-linked list", exit 134) in
about one run out of three, after writing its results.

The guard: in a Python host, a Python ``atexit`` handler calls ``finalizePythonInterpreter``
itself. Python runs it in ``Py_FinalizeEx``, before ``exit()``, while the static is intact: the
state is released once, the static is left empty, and the two later calls at exit do nothing.
In a Python host the state object owns no interpreter (the host's is reused), so releasing it
early runs no Python code. Only Linux has the destructor, and only a Python host is guarded:
in a non-Python host the interpreter itself is finalized from that destructor, and calling it
again from inside would re-enter it.
"""

from __future__ import annotations

import atexit
import ctypes
import sys
from pathlib import Path

_guarded: set[str] = set()


def guard_pythonfmu_exit(resources: str | None, model_identifier: str) -> bool:
    """Register the exit guard once per FMU binary; return whether it is registered.

    ``resources`` is the FMU's resources folder (the adapter's ``self.resources``); the binary
    is ``../binaries/linux64/<model_identifier>.so`` next to it. Nothing is done at build time
    (no binary), outside Linux, or in a non-Python host (``sys.orig_argv`` empty).
    """
    if not resources or not sys.platform.startswith("linux") or not getattr(sys, "orig_argv", None):
        return False
    binary = Path(resources).parent / "binaries" / "linux64" / f"{model_identifier}.so"
    if not binary.is_file():
        return False
    key = str(binary.resolve())
    if key not in _guarded:
        _guarded.add(key)
        atexit.register(_release_python_state, key)
    return True


def _release_python_state(binary: str) -> None:
    try:
        ctypes.CDLL(binary).finalizePythonInterpreter()
    except (OSError, AttributeError):  # pragma: no cover - another pythonfmu version: nothing to do
        pass
