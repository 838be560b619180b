"""Tests of surrogate.executors: the local process pool and a real Dask LocalCluster on loopback
return results and exceptions per case, and the Dask path builds the same friction table as the
process pool from the same (tiny, real) campaign."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from tribocosim.errors import ParameterError
from tribocosim.surrogate.campaign import expand_cases, load_records, run_campaign
from tribocosim.surrogate.executors import DaskCaseExecutor, ProcessPoolCaseExecutor, make_executor
from tribocosim.surrogate.sweep import parse_sweep
from tribocosim.surrogate.table_build import build_table

distributed = pytest.importorskip("distributed")

TINY = (Path(__file__).parent / "data" / "tiny_sweep.toml").read_text().replace('"tiny"', '"tiny-dask"')


def test_process_pool_yields_results_and_exceptions_per_item():
    ex = ProcessPoolCaseExecutor(2)
    out = dict(ex.map_unordered(math.sqrt, [("a", 4.0), ("b", -1.0), ("c", 9.0)]))
    assert out["a"] == 2.0 and out["c"] == 3.0
    assert isinstance(out["b"], ValueError), "a raising case comes back as its exception"
    assert list(ex.map_unordered(math.sqrt, [])) == []
    with pytest.raises(ParameterError, match="workers = 0"):
        ProcessPoolCaseExecutor(0)


def test_bad_scheduler_address_is_refused_with_the_expected_form():
    with pytest.raises(ParameterError, match=r"scheduler = 'localhost:8786'.*tcp://HOST:PORT"):
        make_executor(scheduler="localhost:8786")
    assert make_executor(workers=1).describe() == {"executor": "process-pool", "workers": 1}


@pytest.fixture(scope="module")
def cluster():
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
