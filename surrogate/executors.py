"""Executors of campaign cases: a local process pool (default) or a Dask distributed cluster.

The interface is one method, :meth:`map_unordered`: it takes a picklable, importable function and
``(key, payload)`` pairs and yields ``(key, outcome)`` as cases finish, in any order, where
``outcome`` is the function's return value or the exception it raised (a failed case never stops
the others). Results come back to the calling process, which writes them: Dask workers need no
shared file system.

- :class:`ProcessPoolCaseExecutor`: ``concurrent.futures.ProcessPoolExecutor`` with the
  ``forkserver`` start method (workers do not inherit the caller's threads or FFTW plans).
- :class:`DaskCaseExecutor`: a ``distributed.Client`` connected to ``tcp://HOST:PORT`` (or given),
  from the ``dist`` extra (``pip install 'tribocosim[dist]'``).
"""

from __future__ import annotations

import multiprocessing
import os
import re
import uuid
from concurrent.futures import ProcessPoolExecutor, as_completed

from tribocosim.errors import ParameterError, TribocosimError

_ADDRESS = re.compile(r"^(tcp|tls|inproc|ws|wss)://[^\s:/]+(:\d+)?/?$")


class ProcessPoolCaseExecutor:
    """Cases on a local process pool of ``workers`` processes (default: the number of CPUs)."""

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
        items = list(items)
        if not items:
            return
        ctx = multiprocessing.get_context("forkserver")
        pool = ProcessPoolExecutor(max_workers=min(self.workers, len(items)), mp_context=ctx)
        clean = False
        try:
            futures = {pool.submit(fn, payload): key for key, payload in items}
            for fut in as_completed(futures):
                exc = fut.exception()
                yield futures[fut], (exc if exc is not None else fut.result())
            clean = True
        finally:
            pool.shutdown(wait=clean, cancel_futures=True)

    def close(self) -> None:
        """Nothing to release (the pool lives for one :meth:`map_unordered`)."""


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

        items = list(items)
        if not items:
            return
        session = uuid.uuid4().hex[:8]  # keys unique per submission: a rerun is a new task
        futures = {self.client.submit(fn, payload, key=f"tribocosim-case-{key}-{session}", pure=False): key
                   for key, payload in items}
        try:
            for fut in dask_completed(list(futures)):
                key = futures[fut]
                if fut.status == "error":
                    outcome = fut.exception()
                else:
                    try:
                        outcome = fut.result()
                    except Exception as exc:  # noqa: BLE001 - e.g. a cancelled future
                        outcome = exc
                fut.release()
                yield key, outcome
        finally:
            pending = [f for f in futures if not f.done()]
            if pending:
                self.client.cancel(pending)

    def close(self) -> None:
        """Close the client if this executor opened it."""
        if self._owns:
            self.client.close()


def make_executor(workers: int | None = None, scheduler: str | None = None):
    """A :class:`DaskCaseExecutor` if ``scheduler`` is given, else a process pool."""
    if scheduler:
        return DaskCaseExecutor(address=scheduler)
    return ProcessPoolCaseExecutor(workers)
