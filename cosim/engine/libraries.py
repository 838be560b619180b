"""The shared libraries of the FMUs a process instantiates: each loaded once and kept to the end of the process, and
the exit of those that pythonfmu built made sound.

Both masters load an FMU's library through :func:`keep` (:class:`~tribocosim.cosim.engine.slave.FmpySlave` beside
fmpy's own handle, :class:`~tribocosim.cosim.engine.native_session.NativeSession` for its calls). A library stays
loaded from its first instance to the end of the process: an FMU's extracted folder is named by its content, so a
later run loads the same library again, and an instance that is never freed (after fmi2Fatal no function of any
instance of its FMU may be called, FMI 2.0.4, section 2.1.3) keeps pointing into its library as long as the process
lives.

pythonfmu 0.7's library (``pythonfmu-export``, ``src/pythonfmu/PySlaveInstance.cpp``) holds the state of the
interpreter it runs the component in as a static ``std::shared_ptr<PyState> pyState``, made by the first
``fmi2Instantiate``, and releases it twice when the process exits with the library loaded. ``exit`` first runs the
C++ destructors registered with ``__cxa_atexit``, the static's among them: the ``PyState`` and its control block (one
128-byte heap block, ``make_shared``) are freed, and the static keeps its two pointers. Then ``_dl_fini`` runs the
library's ``__attribute__((destructor)) onLibraryUnload``, which calls ``finalizePythonInterpreter``:
``pyState = nullptr`` releases the stale pointer once more and decrements the use count at offset 8 of the freed
block. There glibc keeps the ``bk`` link of a free chunk in its bins: the next ``free`` that unlinks a neighbour
finds the link off by one and aborts the process with "corrupted double-linked list" (SIGABRT) after the program
has ended. Whether the block is the head of a binned chunk at that moment (abort), in the tcache or merged into a
neighbour (the write goes unnoticed) depends on the heap's layout at exit: on the size of the environment, the
paths, the scheduling of the library's helper thread. (``dlclose`` runs the two in the other order, the library's
destructor first, and the state is released once.)

So the interpreter calls ``finalizePythonInterpreter`` of every pythonfmu library kept here from an ``atexit``
handler (:func:`_release_pythonfmu_states`), before ``exit``: the state is released once, while the static is
intact, and the static's destructor and the library's destructor then find it empty. The hook is pythonfmu's own
unload function, not an FMI function; it touches no instance (it destroys the ``PyState``, whose thread ended when it
found the host's interpreter running), and the library runs it at exit in any case, after fmi2Fatal too: only its
order changes. A later ``fmi2Instantiate`` would make a new state.
"""

from __future__ import annotations

import atexit
import ctypes
from pathlib import Path

#: the kept libraries, by path
_LIBRARIES: dict[str, ctypes.CDLL] = {}
#: ``finalizePythonInterpreter`` of each kept library that pythonfmu built
_PYTHONFMU_HOOKS: list = []


def keep(path: str | Path) -> ctypes.CDLL:
    """The library at ``path``, loaded on first use and kept to the end of the process (its handle is never closed);
    a pythonfmu library's interpreter state is released at the interpreter's exit (see the module docstring)."""
    key = str(path)
    lib = _LIBRARIES.get(key)
    if lib is None:
        lib = ctypes.CDLL(key)
        try:
            hook = lib.finalizePythonInterpreter
        except AttributeError:  # not a pythonfmu library
            pass
        else:
            hook.argtypes, hook.restype = [], None
            _PYTHONFMU_HOOKS.append(hook)
        _LIBRARIES[key] = lib
    return lib


@atexit.register
def _release_pythonfmu_states() -> None:
    """``finalizePythonInterpreter`` of every kept pythonfmu library, once: each releases its ``pyState`` while the
    static is intact, so that neither of the two releases at ``exit`` finds anything to release."""
    while _PYTHONFMU_HOOKS:
        _PYTHONFMU_HOOKS.pop()()
