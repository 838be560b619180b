"""Executors of campaign cases: local worker processes (default) or a Dask distributed cluster.

The interface is one method, :meth:`map_unordered`: it takes a picklable, importable function and
``(key, payload)`` pairs and yields ``(key, outcome)`` as cases finish, in any order, where
``outcome`` is the function's return value or the exception it raised (a failed case never stops
the others). Results come back to the calling process, which writes them: Dask workers need no
shared file system. Both executors look at the stop flag of :mod:`tribocosim.interrupt`
while they wait: on a stop they yield the results already finished, discard the slides in progress and
raise :class:`~tribocosim.errors.CampaignInterrupted`.

- :class:`ProcessPoolCaseExecutor`: worker processes of this machine (module docstring of the class).
- :class:`DaskCaseExecutor`: a ``distributed.Client`` connected to ``tcp://HOST:PORT`` (or given),
  from the ``dist`` extra (``pip install 'tribocosim[dist]'``).
"""

from __future__ import annotations

import collections
import ctypes
import multiprocessing
import os
import re
import signal
import sys
import threading
import time
import traceback
import uuid
from multiprocessing.connection import wait as wait_ready

from tribocosim.errors import ParameterError, TribocosimError

from tribocosim import interrupt

_ADDRESS = re.compile(r"^(tcp|tls|inproc|ws|wss)://[^\s:/]+(:\d+)?/?$")
_PR_SET_PDEATHSIG = 1  # linux/prctl.h


class WorkerDied(TribocosimError):
    """The worker process running a case ended before it returned (a crash of the process, not an error of the
    slide: those come back as the case's outcome)."""


class RemoteTraceback(Exception):
    """The traceback of an exception raised in a worker process (set as the exception's ``__cause__``)."""


class ProcessPoolCaseExecutor:
    """Cases on ``workers`` local processes (default: the number of CPUs).

    Each worker is a fresh interpreter (the ``spawn`` start method: it inherits neither the caller's threads nor
    its FFTW plans, and needs no temporary folder) that runs one case at a time, handed to it over a pipe. The
    workers ignore SIGINT and SIGTERM: a Ctrl-C in a terminal reaches the whole process group, and the caller
    decides (:mod:`tribocosim.interrupt`); on a stop or any exception in the caller they are killed
    (SIGKILL; the slides in progress are discarded). They also die with the process that started them
    (PR_SET_PDEATHSIG = SIGKILL on Linux, set by the worker for the thread that started it; a watchdog on the
    parent's pid elsewhere), so that a killed campaign leaves no worker behind. A worker that dies while it runs
    a case (a crash) gives that case a :class:`WorkerDied` outcome and is replaced.
    """

    name = "process-pool"

    def __init__(self, workers: int | None = None):
        if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
            raise ParameterError(f"workers = {workers!r} is not allowed; an integer >= 1 is required")
        self.workers = workers or os.cpu_count() or 1

    def describe(self) -> dict:
        """What ran the cases (for the metadata)."""
        return {"executor": self.name, "workers": self.workers}

    def map_unordered(self, fn, items):
        """Yield ``(key, result or exception)`` for ``fn(payload)`` over ``items`` as they finish."""
        interrupt.raise_if_stopped()
        queue = collections.deque(items)
        if not queue:
            return
        ctx = multiprocessing.get_context("spawn")
        workers: list[_Worker] = []
        clean = False
        try:
            for _ in range(min(self.workers, len(queue))):
                workers.append(_Worker(ctx, fn))
                workers[-1].assign(queue.popleft())
            while any(w.key is not None for w in workers):
                if interrupt.stop_requested() is not None:
                    for w in workers:  # the results already sent are finished slides: hand them over
                        if w.key is not None and w.has_result():
                            yield w.collect()
                    interrupt.raise_if_stopped()
                busy = [w for w in workers if w.key is not None]
                ready = set(wait_ready([w.conn for w in busy] + [w.proc.sentinel for w in busy],
                                       timeout=interrupt.POLL_S))
                for i, w in enumerate(workers):
                    if w.key is None or not (w.conn in ready or w.proc.sentinel in ready):
                        continue
                    key, outcome = w.collect()
                    if not w.proc.is_alive():
                        w.stop(kill=True)
                        workers[i] = w = _Worker(ctx, fn)
                    if queue:
                        w.assign(queue.popleft())
                    yield key, outcome
            clean = True
        finally:
            for w in workers:
                w.stop(kill=not clean)

    def close(self) -> None:
        """Nothing to release (the workers live for one :meth:`map_unordered`)."""


class _Worker:
    """One worker process and the parent's end of its pipe."""

    def __init__(self, ctx, fn):
        self.conn, child = ctx.Pipe()
        self.proc = ctx.Process(target=_worker_main, args=(child, fn, os.getpid()), daemon=True,
                                name="tribocosim-case-worker")
        self.key = None
        masked = hasattr(signal, "pthread_sigmask")
        if masked:  # the child starts with SIGINT/SIGTERM blocked until it ignores them (no KeyboardInterrupt
            old = signal.pthread_sigmask(signal.SIG_BLOCK, interrupt.SIGNALS)  # while it starts up)
        try:
            self.proc.start()
        finally:
            if masked:
                signal.pthread_sigmask(signal.SIG_SETMASK, old)
            child.close()
        interrupt.register_worker(self.proc.pid)

    def assign(self, item) -> None:
        self.key = item[0]
        self.conn.send(item)

    def has_result(self) -> bool:
        try:
            return self.conn.poll()
        except OSError:
            return False

    def collect(self):
        """``(key, outcome)`` of the case in progress: what the worker sent, or :class:`WorkerDied`."""
        key, self.key = self.key, None
        try:
            if self.conn.poll():
                _, status, value, tb = self.conn.recv()
                if status == "error" and tb:
                    value.__cause__ = RemoteTraceback(tb)
                return key, value
        except (EOFError, OSError):
            pass
        self.proc.join(timeout=5)
        code = self.proc.exitcode
        how = (f"was killed by {interrupt.signal_name(-code)}" if code is not None and code < 0
               else f"exited with status {code}")
        return key, WorkerDied(f"the worker process (pid {self.proc.pid}) running case {key} {how} before the "
                               "case ended")

    def stop(self, kill: bool) -> None:
        """End the worker: ask it to exit (``kill`` False; killed if it has not after 10 s) or kill it."""
        if not kill:
            try:
                self.conn.send(None)
            except OSError:
                pass
            self.proc.join(timeout=10)
        if self.proc.is_alive():
            self.proc.kill()
            self.proc.join(timeout=10)
        self.conn.close()
        interrupt.unregister_worker(self.proc.pid)


def _worker_main(conn, fn, parent_pid: int) -> None:
    """A worker's loop: run ``fn`` on each ``(key, payload)`` received, send back ``(key, status, value, tb)``."""
    _die_with_parent(parent_pid)
    for sig in interrupt.SIGNALS:
        signal.signal(sig, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, interrupt.SIGNALS)
    while True:
        try:
            item = conn.recv()
        except EOFError:
            return
        if item is None:
            return
        key, payload = item
        try:
            msg = (key, "ok", fn(payload), "")
        except BaseException as exc:  # noqa: BLE001 - every error is the case's outcome
            msg = (key, "error", exc, traceback.format_exc())
        try:
            conn.send(msg)
        except Exception as exc:  # noqa: BLE001 - e.g. an outcome that does not pickle
            conn.send((key, "error", TribocosimError(f"the outcome of case {key} cannot be sent back: "
                                                     f"{type(exc).__name__}: {exc}"), msg[3]))


def _die_with_parent(parent_pid: int) -> None:
    """Make this process end when ``parent_pid`` (its parent) does: PR_SET_PDEATHSIG = SIGKILL on Linux, a watchdog
    thread polling the parent's pid elsewhere. Exits at once if the parent is already gone."""
    armed = False
    if sys.platform.startswith("linux"):
        try:
            armed = ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0
        except (OSError, AttributeError):
            armed = False
    if os.getppid() != parent_pid:
        os._exit(1)
    if not armed:
        def watch():
            while os.getppid() == parent_pid:
                time.sleep(1.0)
            os._exit(1)
        threading.Thread(target=watch, name="parent-watchdog", daemon=True).start()


class DaskCaseExecutor:
    """Cases on a Dask distributed cluster.

    Parameters
    ----------
    address : str, optional
        Scheduler address ``tcp://HOST:PORT``.
    client : distributed.Client, optional
        An existing client instead (it is not closed by :meth:`close`).
    """

    name = "dask"

    def __init__(self, address: str | None = None, client=None):
        if (address is None) == (client is None):
            raise ParameterError("DaskCaseExecutor needs exactly one of address or client")
        try:
            import distributed
        except ImportError:  # pragma: no cover - the test extra installs it
            raise TribocosimError("--scheduler needs dask[distributed]: pip install 'tribocosim[dist]'") \
                from None
        self._owns = client is None
        if client is None:
            if not _ADDRESS.match(address):
                raise ParameterError(f"scheduler = {address!r} is not an address; "
                                     "tcp://HOST:PORT is expected")
            try:
                client = distributed.Client(address, timeout="20s")
            except (OSError, TimeoutError) as exc:
                raise TribocosimError(f"cannot connect to the Dask scheduler {address}: {exc}") from None
        self.client = client
        self.address = getattr(client.scheduler, "address", address)

    def describe(self) -> dict:
        """What ran the cases (for the metadata)."""
        try:
            n = len(self.client.scheduler_info().get("workers", {}))
        except Exception:  # noqa: BLE001 - informational only
            n = None
        return {"executor": self.name, "scheduler": str(self.address), "workers": n}

    def map_unordered(self, fn, items):
        """Yield ``(key, result or exception)`` for ``fn(payload)`` over ``items`` as they finish."""
        from distributed import as_completed as dask_completed

        interrupt.raise_if_stopped()
        items = list(items)
        if not items:
            return
        session = uuid.uuid4().hex[:8]  # keys unique per submission: a rerun is a new task
        futures = {self.client.submit(fn, payload, key=f"tribocosim-case-{key}-{session}", pure=False): key
                   for key, payload in items}
        ready = dask_completed(list(futures))
        try:
            while not ready.is_empty():
                stopping = interrupt.stop_requested() is not None
                if stopping:  # cancel what runs; hand over what has finished
                    self.client.cancel([f for f in futures if not f.done()])
                batch = ready.next_batch(block=False)
                for fut in batch:
                    if stopping and fut.status != "finished":
                        continue
                    yield futures[fut], self._outcome(fut)
                if stopping:
                    interrupt.raise_if_stopped()
                if not batch:
                    time.sleep(0.05)
        finally:
            pending = [f for f in futures if not f.done()]
            if pending:
                self.client.cancel(pending)

    @staticmethod
    def _outcome(fut):
        if fut.status == "error":
            outcome = fut.exception()
        else:
            try:
                outcome = fut.result()
            except Exception as exc:  # noqa: BLE001 - e.g. a cancelled future
                outcome = exc
        fut.release()
        return outcome

    def close(self) -> None:
        """Close the client if this executor opened it."""
        if self._owns:
            self.client.close()


def make_executor(workers: int | None = None, scheduler: str | None = None):
    """A :class:`DaskCaseExecutor` if ``scheduler`` is given, else a process pool."""
    if scheduler:
        return DaskCaseExecutor(address=scheduler)
    return ProcessPoolCaseExecutor(workers)
