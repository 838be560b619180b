"""Stopping long work on SIGINT (Ctrl-C) or SIGTERM: the first signal asks for a stop, a second ends the process at
once.

:func:`stop_on_signals` (a context manager; it acts in the main thread only) installs handlers for SIGINT and
SIGTERM. The first signal sets a flag and says on stderr what stopping keeps; the work looks at the flag
(:func:`stop_requested`, :func:`raise_if_stopped`) where it can stop with what it has:

- a campaign's executors (:mod:`tribocosim.surrogate.executors`) at least every :data:`POLL_S` seconds while they
  wait for slides: they hand over the results that have already arrived (so that every finished slide is written),
  stop their workers (the slides in progress are discarded: a slide keeps nothing before it ends) and raise
  :class:`~tribocosim.errors.CampaignInterrupted`;
- a co-simulation run (``tribocosim run``) at every communication point, or after every chunk of steps of the C loop
  (a chunk takes about :data:`POLL_S` seconds): the accepted steps are written, marked interrupted
  (:mod:`tribocosim.cosim.api`), and a sweep's finished cases are kept.

A second signal while that happens kills the worker processes registered here and ends the process at once with
status 128 + the signal's number, so that stopping can never hang. Local worker processes also die with the process
that started them, however it ends (the executors set PR_SET_PDEATHSIG on Linux and run a watchdog on the parent
elsewhere).
"""

from __future__ import annotations

import os
import signal
from contextlib import contextmanager

from tribocosim.errors import CampaignInterrupted

#: how often work that waits looks at the flag [s]
POLL_S = 0.25
SIGNALS = (signal.SIGINT, signal.SIGTERM)
#: what a stop keeps, said when the first signal arrives (a campaign's, unless the caller says otherwise)
CAMPAIGN = "every finished case is kept, the slides in progress are discarded"

_stop_signum: int | None = None
_kept: str | None = CAMPAIGN
_depth = 0  # stop_on_signals blocks entered
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


def raise_if_stopped(error: type = CampaignInterrupted) -> None:
    """Raise ``error("stopped by SIGINT", signum)`` (a :class:`~tribocosim.errors.Interrupted`) if a signal asked for
    a stop."""
    if _stop_signum is not None:
        raise error(f"stopped by {signal_name(_stop_signum)}", _stop_signum)


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
        if _kept is not None:
            _say(f"\n{name}: stopping; {_kept} (a second {name} ends the process at once)\n")
        return
    _say(f"\n{name} again: ending at once\n")
    for pid in list(_worker_pids):
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass
    os._exit(128 + signum)


@contextmanager
def stop_on_signals(kept: str | None = CAMPAIGN):
    """Within the block, SIGINT and SIGTERM ask for a stop (module docstring; ``kept``: what stopping keeps, said
    with the first signal, or None: nothing said then, the work says it when it has stopped); the previous handlers and
    a clear flag afterwards. Within another such block only what is said changes (its handlers and flag stay). Does
    nothing outside the main thread (Python delivers signals to it only)."""
    global _stop_signum, _kept, _depth
    before = _kept
    _kept = kept
    if _depth:
        try:
            yield
        finally:
            _kept = before
        return
    _stop_signum = None
    try:
        previous = {sig: signal.signal(sig, _handler) for sig in SIGNALS}
    except ValueError:  # not the main thread: signals do not reach it
        _kept = before
        yield
        return
    _depth = 1
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        _stop_signum, _kept, _depth = None, before, 0
