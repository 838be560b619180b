"""Tests of surrogate.executors: the local process pool and a real Dask LocalCluster on loopback
return results and exceptions per case, stop at once on a signal (tribocosim.interrupt) after handing over
what has finished, a crashed worker gives its case an outcome and is replaced, and the Dask path builds the
same friction table as the process pool from the same (tiny, real) campaign."""

from __future__ import annotations

import math
import multiprocessing
import os
import signal
import time
from pathlib import Path

import numpy as np
import pytest

from tribocosim.errors import CampaignInterrupted, ParameterError
from tribocosim import interrupt
from tribocosim.surrogate.campaign import expand_cases, load_records, run_campaign
from tribocosim.surrogate.executors import DaskCaseExecutor, ProcessPoolCaseExecutor, WorkerDied, make_executor
from tribocosim.surrogate.sweep import parse_sweep
from tribocosim.surrogate.table_build import build_table

distributed = pytest.importorskip("distributed")

TINY = (Path(__file__).parent / "data" / "tiny_sweep.toml").read_text().replace('"tiny"', '"tiny-dask"')


@pytest.fixture(scope="module", autouse=True)
def workers_import_this_module():
    """The items of the stop tests (_wait_for) are functions of this module, which pytest imports by its path as
    tests.surrogate.test_executors: a spawned worker (the pool's, a Dask worker's) unpickles them by that name, so
    the checkout's root is on the sys.path the workers inherit (set before the cluster fixture starts them)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.syspath_prepend(str(Path(__file__).resolve().parents[2]))
        yield


def test_process_pool_yields_results_and_exceptions_per_item():
    ex = ProcessPoolCaseExecutor(2)
    out = dict(ex.map_unordered(math.sqrt, [("a", 4.0), ("b", -1.0), ("c", 9.0)]))
    assert out["a"] == 2.0 and out["c"] == 3.0
    assert isinstance(out["b"], ValueError), "a raising case comes back as its exception"
    assert list(ex.map_unordered(math.sqrt, [])) == []
    with pytest.raises(ParameterError, match="workers = 0"):
        ProcessPoolCaseExecutor(0)


def _wait_for(files: tuple[str, str]) -> str:
    """An item that runs until the file files[0] exists (at once for a fast item), then writes files[1]: a slow
    item that ends only when the test lets it (after 600 s at most, so that no worker outlives a failed test)."""
    release, finished = files
    deadline = time.monotonic() + 600
    while not os.path.exists(release) and time.monotonic() < deadline:
        time.sleep(0.01)
    Path(finished).write_text("finished")
    return finished


def _stop_after_first_result(executor, folder: Path):
    """A fast and a slow item (_wait_for); SIGINT to this process when the first result arrives. The keys received,
    and whether the slow item had finished when the executor raised CampaignInterrupted: it cannot have unless the
    executor waited for it, since it runs until the test releases it (afterwards)."""
    (folder / "go").write_text("")
    items = [("fast", (str(folder / "go"), str(folder / "fast.done"))),
             ("slow", (str(folder / "release"), str(folder / "slow.done")))]
    got, sent = [], False
    with interrupt.stop_on_signals():
        with pytest.raises(CampaignInterrupted, match="stopped by SIGINT") as info:
            for key, _ in executor.map_unordered(_wait_for, items):
                got.append(key)
                if not sent:
                    sent = True
                    os.kill(os.getpid(), signal.SIGINT)
    slow_finished = (folder / "slow.done").exists()
    (folder / "release").write_text("")  # a slow item still running (a Dask thread) ends now
    assert info.value.signum == signal.SIGINT
    return got, slow_finished


def test_process_pool_stops_on_a_signal_and_kills_the_slides_in_progress(tmp_path):
    got, slow_finished = _stop_after_first_result(ProcessPoolCaseExecutor(2), tmp_path)
    assert got == ["fast"] and not slow_finished, "stopped without waiting for the slide in progress"
    assert multiprocessing.active_children() == [], "the worker of the slow item is gone"
    assert not (tmp_path / "slow.done").exists(), "killed, not left to finish"


def test_process_pool_replaces_a_worker_that_dies_and_names_how():
    out = dict(ProcessPoolCaseExecutor(1).map_unordered(os._exit, [("a", 3), ("b", 4)]))
    assert isinstance(out["a"], WorkerDied) and "exited with status 3" in str(out["a"])
    assert isinstance(out["b"], WorkerDied) and "exited with status 4" in str(out["b"]), "run by a new worker"


def test_bad_scheduler_address_is_refused_with_the_expected_form():
    with pytest.raises(ParameterError, match=r"scheduler = 'localhost:8786'.*tcp://HOST:PORT"):
        make_executor(scheduler="localhost:8786")
    assert make_executor(workers=1).describe() == {"executor": "process-pool", "workers": 1}


@pytest.fixture(scope="module")
def cluster(workers_import_this_module):
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=":0", silence_logs=40) as c:
        yield c


def test_dask_executor_yields_results_and_exceptions(cluster):
    ex = DaskCaseExecutor(address=cluster.scheduler_address)
    try:
        out = dict(ex.map_unordered(math.sqrt, [("a", 4.0), ("b", -1.0)]))
        assert out["a"] == 2.0 and isinstance(out["b"], ValueError)
        # the same keys again are new tasks, not the cached results of the first submission
        out2 = dict(ex.map_unordered(math.sqrt, [("a", 16.0)]))
        assert out2["a"] == 4.0
        info = ex.describe()
        assert info["executor"] == "dask" and info["scheduler"].startswith("tcp://127.0.0.1:")
        assert info["workers"] == 1
    finally:
        ex.close()


def test_dask_executor_stops_on_a_signal_and_cancels_what_runs(cluster, tmp_path):
    ex = DaskCaseExecutor(address=cluster.scheduler_address)
    try:
        got, slow_finished = _stop_after_first_result(ex, tmp_path)
        assert got == ["fast"] and not slow_finished, "stopped without waiting for the task in progress"
        assert dict(ex.map_unordered(math.sqrt, [("a", 4.0)])) == {"a": 2.0}, "the client works on"
    finally:
        ex.close()


def test_dask_cluster_builds_the_same_table_as_the_process_pool(cluster, tmp_path):
    sweep = parse_sweep(TINY)
    cases = expand_cases(sweep)
    tables = {}
    for name, ex in (("pool", ProcessPoolCaseExecutor(2)),
                     ("dask", DaskCaseExecutor(address=cluster.scheduler_address))):
        out = tmp_path / name
        try:
            rep = run_campaign(cases, out, ex, sweep=sweep, progress=False)
        finally:
            ex.close()
        assert not rep.failed and len(rep.computed) == len(cases)
        manifest, done, _ = load_records(out)
        stats = {"gap_rms_slope_mean": 0.3, "pairs": []}
        tables[name] = build_table(done, manifest, surface_stats=stats)[0]
        assert {r["summary"]["mean_contact_fraction"] > 0 for r in done} == {True}
    a, b = tables["pool"], tables["dask"]
    for axis in ("pressure", "velocity", "beta"):
        assert np.array_equal(getattr(a, axis), getattr(b, axis))
    # same seeds, same code: equal up to the last bits of FFTW plans measured in other processes
    np.testing.assert_allclose(a.mu, b.mu, rtol=1e-9, atol=1e-12)
    for name in ("particle_area_std", "particle_area_se", "contact_area_se"):
        np.testing.assert_allclose(a.array(name), b.array(name), rtol=1e-6, atol=1e-12, err_msg=name)
    assert a.beta_threshold == pytest.approx(b.beta_threshold, rel=1e-9)
