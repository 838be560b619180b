"""Stopping a campaign on SIGINT (Ctrl-C) or SIGTERM: the first signal asks for a stop, a second exits at once.

:func:`stop_on_signals` (a context manager; it acts in the main thread only) installs handlers for SIGINT and
SIGTERM. The first signal sets a flag that the executors (:mod:`tribocosim.surrogate.executors`) check at least
every :data:`POLL_S` seconds while they wait for slides: they hand over the results that have already arrived
(so that every finished slide is written), stop their workers (the slides in progress are discarded: a slide
keeps nothing before it ends) and raise :class:`~tribocosim.errors.CampaignInterrupted`. A second signal while
that happens kills the worker processes registered here and ends the process at once with status
128 + the signal's number, so that stopping can never hang.

Local worker processes also die with the process that started them, however it ends (the executors set
PR_SET_PDEATHSIG on Linux and run a watchdog on the parent elsewhere).
"""

from __future__ import annotations

import os
import signal
import threading
from contextlib import contextmanager

from tribocosim.errors import CampaignInterrupted

#: how often the executors look at the flag while they wait [s]
POLL_S = 0.25
SIGNALS = (signal.SIGINT, signal.SIGTERM)

_stop_signum: int | None = None
_worker_pids: set[int] = set()


def signal_name(signum: int) -> str:
    """``"SIGINT"`` for 2, ..."""
    try:
        return signal.Signals(signum).name
    except ValueError:
        return f"signal {signum}"


def stop_requested() -> int | None:
    """The number of the signal that asked for a stop, or None."""
    return _stop_signum


def raise_if_stopped() -> None:
    """Raise :class:`CampaignInterrupted` if a signal asked for a stop."""
    if _stop_signum is not None:
        raise CampaignInterrupted(f"stopped by {signal_name(_stop_signum)}", _stop_signum)


def register_worker(pid: int) -> None:
    """A local worker process to kill on a second signal."""
    _worker_pids.add(pid)


def unregister_worker(pid: int) -> None:
    _worker_pids.discard(pid)


def _say(text: str) -> None:
    try:  # os.write: a handler may run while the main thread is inside a write to sys.stderr
        os.write(2, text.encode())
    except OSError:
        pass


def _handler(signum, frame) -> None:
    global _stop_signum
    name = signal_name(signum)
    if _stop_signum is None:
        _stop_signum = signum
        _say(f"\n{name}: stopping; every finished case is kept, the slides in progress are discarded "
             f"(a second {name} ends the process at once)\n")
        return
    _say(f"\n{name} again: ending at once\n")
    for pid in list(_worker_pids):
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass
    os._exit(128 + signum)


@contextmanager
def stop_on_signals():
    """Within the block, SIGINT and SIGTERM ask for a stop (module docstring); the previous handlers and a clear
    flag afterwards. Does nothing outside the main thread (Python delivers signals to it only)."""
    global _stop_signum
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {sig: signal.getsignal(sig) for sig in SIGNALS}
    _stop_signum = None
    for sig in SIGNALS:
        signal.signal(sig, _handler)
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        _stop_signum = None
