"""Tests of surrogate.sweep and surrogate.campaign with real slides (tiny: 16^2, 4 sliding steps),
a real process pool and real files: deterministic case ids, every case written, a rerun skips
finished cases, a failing case is recorded and skipped, and a campaign killed with SIGKILL resumes
with every case computed exactly once."""

from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import pytest

from tribocosim.errors import ParameterError
from tribocosim.surrogate.campaign import (Case, CampaignStore, Progress, case_id, expand_cases, load_records,
                                run_campaign)
from tribocosim.surrogate.executors import ProcessPoolCaseExecutor
from tribocosim.surrogate.sweep import load_preset, parse_sweep

#: a 16^2 sweep of 2 P x 2 v x (particle-free + 3 seeds) that runs in seconds (shared with the
#: executor and CLI tests; the line numbers of its keys are asserted below)
TINY = (Path(__file__).parent / "data" / "tiny_sweep.toml").read_text()


def test_case_ids_are_deterministic_distinct_and_particle_free_cases_deduplicated():
    a, b = expand_cases(parse_sweep(TINY)), expand_cases(parse_sweep(TINY))
    assert [c.case_id for c in a] == [c.case_id for c in b]
    assert len({c.case_id for c in a}) == len(a) == 2 * 2 * (1 + 3), "P x v x (free + 3 seeds)"
    assert all(len(c.case_id) == 16 and int(c.case_id, 16) >= 0 for c in a)
    c0 = a[1].config
    assert case_id(replace(c0, flake_seed=c0.flake_seed + 1)) != case_id(c0)
    free = [c for c in a if c.labels["n_flakes"] == 0]
    assert len(free) == 4 and all(c.labels["beta"] == 0.0 and c.labels["seed"] is None for c in free)


@pytest.mark.parametrize("text, match", [
    (TINY.replace("velocity =", "velocty ="), r"line 5: \[grid\] velocty: unknown key"),
    (TINY.replace("n_slide_steps = 4", "n_slide_steps = 4\npressure = 1e6"),
     r"line 15: \[slide\] pressure: is swept"),
    (TINY.replace("seeds = [1, 2, 3]", "seeds = [1]"), r"line 6: \[grid\] seeds: .*= 1 member\(s\).*at least 2"),
    (TINY.replace("pressure = [5e6, 20e6]", "pressure = [5e6, 400e6]"), r"line 4: \[grid\] pressure: .*p_crit"),
    (TINY.replace("count = 2", "count = 2\ncolour = 1"), r"line 9: \[\[flakes\]\] entry 1 colour"),
    (TINY.replace("count = 2", "count = 0"), r"line 8: \[\[flakes\]\] entry 1 count: = 0"),
    (TINY.replace("n = 16", "n = 7"), r"line 11: \[slide\] n: n = 7"),
    (TINY.replace("diameter = 12e-6", "diameter = 12e-6\nvelocities = [7.0]"),
     r"line 10: \[\[flakes\]\] entry 1 velocities: has the value 7.0 m/s; grid velocities"),
    (TINY.replace("diameter = 12e-6", "diameter = 12e-6\nmin_pressure = 50e6"),
     r"line 10: \[\[flakes\]\] entry 1 min_pressure: selects no grid point"),
    (TINY.replace("quasi_static_row = true", "low_velocities = [0.0]"), r"\[table\] low_velocities: unknown key"),
    (TINY.replace("[grid]", "[grid"), r"not valid TOML.*line 3"),
])
def test_malformed_sweep_names_the_key_and_line(text, match):
    with pytest.raises(ParameterError, match=match):
        parse_sweep(text, source="s.toml")


def test_presets_quick_and_paper():
    """The shipped table's preset covers the strip draw's domain (1-30 MPa, the test's 0.08 m/s, debris up to
    beta ~ 1 where the scenes reach it) on a 256 um domain; the paper preset the same on the paper's scale."""
    quick, paper = load_preset("quick"), load_preset("paper")
    for sweep, size in ((quick, 256e-6), (paper, 512e-6)):
        assert (min(sweep.pressures), max(sweep.pressures)) == (1e6, 30e6)
        assert 0.08 in sweep.velocities and sweep.table.quasi_static_row
        betas = [sweep.flake_beta(f.count, f.diameter) for f in sweep.flakes]
        assert min(betas) < 0.03 and max(betas) >= 0.99 and len(betas) >= 6
        assert sweep.base_config().size == size and len(sweep.surfaces) == 2
        assert sweep.adaptive is not None and sweep.adaptive.target_relative_se <= 0.1
        assert sweep.slide["dem_velocity"] == 10.0 and sweep.slide["placement"] == "deposition"
    assert max(paper.velocities) == 50.0
    with pytest.raises(ParameterError, match="preset = 'huge' is not known"):
        load_preset("huge")


def test_progress_line_has_counts_and_eta():
    buf = io.StringIO()
    bar = Progress(10, skipped=4, stream=buf)
    assert "ETA --:--" in bar.line()
    bar.update(True)
    bar.update(False)
    bar.render(final=True)
    line = buf.getvalue().strip().splitlines()[-1]
    assert "6/10 cases (4 skipped, 1 failed)" in line and "ETA 0:0" in line


@pytest.fixture(scope="module")
def pool():
    return ProcessPoolCaseExecutor(2)


def test_campaign_writes_every_case_and_rerun_skips_them(tmp_path, pool):
    sweep = parse_sweep(TINY)
    cases = expand_cases(sweep)
    rep = run_campaign(cases, tmp_path, pool, sweep=sweep, progress=False)
    assert sorted(rep.computed) == sorted(c.case_id for c in cases) and not rep.failed
    store = CampaignStore(tmp_path)
    for c in cases:
        rec = store.read_case(c.case_id)
        assert rec["status"] == "done" and rec["config"] == c.config.to_dict()
        assert 0 < rec["summary"]["mean_contact_fraction"] < 1 and rec["labels"] == c.labels
        assert (tmp_path / "cases" / f"{c.case_id}.npz").is_file()
    assert not list((tmp_path / "cases").glob(".*tmp")), "no temporary file left behind"
    stamps = {p.name: p.stat().st_mtime_ns for p in (tmp_path / "cases").glob("*.json")}
    rep2 = run_campaign(cases, tmp_path, pool, sweep=sweep, progress=False)
    assert rep2.computed == [] and len(rep2.skipped) == len(cases)
    assert stamps == {p.name: p.stat().st_mtime_ns for p in (tmp_path / "cases").glob("*.json")}
    manifest, done, failed = load_records(tmp_path)
    assert len(done) == len(cases) and failed == [] and manifest["sweep"]["name"] == "tiny"
    events = [json.loads(x)["event"] for x in (tmp_path / "campaign.log").read_text().splitlines()]
    assert events.count("done") == len(cases) and events.count("start") == 2


def test_failing_case_is_recorded_and_does_not_stop_the_others(tmp_path, pool):
    good = expand_cases(parse_sweep(TINY))[:3]
    bad = Case(replace(good[1].config, bem_max_iter=1), {**good[1].labels, "note": "bem_max_iter=1"})
    cases = [good[0], bad, good[1], good[2]]
    rep = run_campaign(cases, tmp_path, pool, progress=False)
    assert rep.failed == [bad.case_id] and sorted(rep.computed) == sorted(c.case_id for c in good)
    err = json.loads((tmp_path / "cases" / f"{bad.case_id}.error.json").read_text())
    assert err["error"]["type"] == "ConvergenceError" and "converge" in err["error"]["message"]
    assert err["config"]["bem_max_iter"] == 1 and "Traceback" in err["error"]["traceback"]
    assert not (tmp_path / "cases" / f"{bad.case_id}.json").exists()
    # a rerun leaves it alone when asked, and retries it by default (it fails again)
    rep2 = run_campaign(cases, tmp_path, pool, progress=False, retry_failed=False)
    assert rep2.computed == [] and rep2.failed == [bad.case_id] and len(rep2.skipped) == 3
    rep3 = run_campaign(cases, tmp_path, pool, progress=False)
    assert rep3.failed == [bad.case_id] and rep3.computed == []
    _, done, failed = load_records(tmp_path)
    assert len(done) == 3 and [f["case_id"] for f in failed] == [bad.case_id]


RESUME = TINY.replace("pressure = [5e6, 20e6]", "pressure = [5e6, 10e6, 20e6]").replace(
    "n_slide_steps = 4", "n_slide_steps = 8")


def _log_ids(path: Path) -> list[str]:
    return [line.split()[0] for line in path.read_text().splitlines()] if path.exists() else []


def test_campaign_killed_with_sigkill_resumes_and_computes_every_case_once(tmp_path):
    sweep_file = tmp_path / "sweep.toml"
    sweep_file.write_text(RESUME)
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "tribocosim.surrogate.surrogate_cli", "build", "--sweep", str(sweep_file),
           "--out", str(out), "--workers", "1", "--no-table", "--quiet"]
    total = len(expand_cases(parse_sweep(RESUME)))
    log1, log2 = tmp_path / "computed1.log", tmp_path / "computed2.log"
    proc = subprocess.Popen(cmd, env={**os.environ, "TRIBOCOSIM_CASE_LOG": str(log1)},
                            start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 60
    while len(list(out.glob("cases/*.json"))) < 3:
        assert proc.poll() is None, f"campaign ended early: {proc.stderr.read().decode()}"
        assert time.monotonic() < deadline, "no case finished within 60 s"
        time.sleep(0.01)
    os.killpg(proc.pid, signal.SIGKILL)  # the driver and its workers, as when a job is killed
    proc.wait(timeout=10)
    before = {p.stem: (p.stat().st_mtime_ns, json.loads(p.read_text())["token"])
              for p in out.glob("cases/*.json")}
    assert 3 <= len(before) < total, f"kill came too late to test resuming ({len(before)}/{total})"
    done1 = _log_ids(log1)
    assert len(done1) == len(set(done1)), "no case computed twice within the first run"

    res = subprocess.run(cmd, env={**os.environ, "TRIBOCOSIM_CASE_LOG": str(log2)},
                         capture_output=True, text=True, timeout=180)
    assert res.returncode == 0, res.stderr
    after = {p.stem: (p.stat().st_mtime_ns, json.loads(p.read_text())["token"])
             for p in out.glob("cases/*.json")}
    assert len(after) == total
    assert all(after[cid] == before[cid] for cid in before), "finished cases were not rewritten"
    done2 = _log_ids(log2)
    assert len(done2) == len(set(done2)) == total - len(before)
    assert not set(done2) & set(before), "a finished case was computed again"
    assert set(done2) | set(before) == set(after)
    tokens = [t for _, t in after.values()]
    assert len(set(tokens)) == total
    events = [json.loads(x) for x in (out / "campaign.log").read_text().splitlines()]
    starts = [e for e in events if e["event"] == "start"]
    assert starts[-1]["skipped"] == len(before) and starts[-1]["todo"] == total - len(before)
