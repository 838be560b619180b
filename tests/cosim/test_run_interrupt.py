"""``tribocosim run`` stopped by SIGINT (Ctrl-C) or SIGTERM, as a user stops it: a real process, signalled once it shows
progress (the progress bar, or a finished case of a sweep, on stderr; no sleep of a guessed length).

A run stops at the next communication point, writes the steps accepted up to there (the CSV as always, the JSON with an
``interrupted`` entry at the same last time) and says so in one line, with exit status 128 + the signal's number; a
sweep keeps its finished cases (a rerun takes them as they are) and leaves no worker process behind.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

#: the demo at a millionth of a second: 2.06 million steps, some tens of seconds unless stopped (one recorded column,
#: so the rows take 16 MB)
LONG = ["--set", "experiment.step=1e-6", "--set", 'output.variables=["strip.pull_force"]']


def _console() -> str:
    return shutil.which("tribocosim") or pytest.skip("tribocosim console script not installed")


def _children(pid: int) -> set[int]:
    """The processes ``pid`` started (Linux /proc)."""
    found = set()
    try:
        for task in os.listdir(f"/proc/{pid}/task"):
            with open(f"/proc/{pid}/task/{task}/children") as f:
                found |= {int(x) for x in f.read().split()}
    except OSError:
        pass
    return found


def _wait_gone(pids: set[int], timeout: float = 30.0) -> list[int]:
    """The processes of ``pids`` still running after they had ``timeout`` seconds to end (a process that ends with
    its parent, e.g. multiprocessing's resource tracker, takes a moment after it)."""
    end = time.monotonic() + timeout
    alive = list(pids)
    while alive and time.monotonic() < end:
        alive = [p for p in alive if os.path.exists(f"/proc/{p}") and "Z" not in _state(p)]
        if alive:
            time.sleep(0.05)
    return alive


def _state(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0]
    except OSError:
        return "Z"


def _signalled(args: list[str], cwd: Path, marker: bytes, signum: int, group: bool = False):
    """Start ``tribocosim ARGS`` in ``cwd``, wait for ``marker`` on its stderr, send ``signum`` (to its process group
    as a terminal's Ctrl-C does, when ``group``); return (exit status, stderr, the processes it had started)."""
    env = {**os.environ, "MPLBACKEND": "Agg"}
    proc = subprocess.Popen([_console(), *args], cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True)
    seen = b""
    while marker not in seen:
        chunk = proc.stderr.read1(65536)
        if not chunk:
            proc.wait(timeout=60)
            pytest.fail(f"ended before {marker!r} (exit {proc.returncode}):\n{seen.decode(errors='replace')}")
        seen += chunk
    children = _children(proc.pid)
    if group:
        os.killpg(proc.pid, signum)
    else:
        proc.send_signal(signum)
    _, rest = proc.communicate(timeout=120)
    return proc.returncode, (seen + rest).decode(errors="replace"), children


@pytest.mark.parametrize("signum, loop", [(signal.SIGINT, []), (signal.SIGTERM, []),
                                          (signal.SIGINT, ["--set", "master.extrapolation=1", "--set",
                                                           "experiment.step=2e-5"])],
                         ids=["SIGINT, C loop", "SIGTERM, C loop", "SIGINT, Python loop"])
def test_a_stopped_run_writes_its_accepted_steps_marked_interrupted(tmp_path, signum, loop):
    out = tmp_path / "out"
    code, err, children = _signalled(["run", "demo", "--out", str(out), *LONG, *loop], tmp_path, b"\r[", signum)
    name = signal.Signals(signum).name
    assert code == 128 + signum, err
    assert "Traceback" not in err
    last = err.strip().splitlines()[-1]
    assert last.startswith(f"tribocosim run: stopped by {name} at t = "), err
    assert "the accepted steps are written" in last and "(marked interrupted)" in last
    meta = json.loads((out / "demo.json").read_text())
    mark = meta["interrupted"]
    assert mark["signal"] == name
    lines = (out / "demo.csv").read_text().splitlines()
    assert lines[0] == '"time","strip.pull_force"'
    rows = [[float(x) for x in line.split(",")] for line in lines[1:]]
    assert len(rows) == mark["recorded_rows"] == mark["steps"] + 1 and 0 < mark["steps"] < mark["steps_of_the_run"]
    assert rows[-1][0] == mark["last_accepted_time"], "the CSV and the JSON end at the same communication point"
    assert f"t = {mark['last_accepted_time']:.9g} s after {mark['steps']} of {mark['steps_of_the_run']} steps" in last
    assert all(math.isfinite(v) for row in rows for v in row)
    step = float(meta["experiment"]["step"])
    assert [r[0] for r in rows[-3:]] == pytest.approx([(mark["steps"] - k) * step for k in (2, 1, 0)], rel=1e-12)
    assert not list(out.glob(".tribocosim-run.lock")) and not list(out.glob("*.part")), "lock and temporaries gone"
    assert children == set() or _wait_gone(children) == []


def test_a_stopped_sweep_keeps_its_finished_cases_leaves_no_worker_and_resumes(tmp_path):
    """Four cases on two workers: the first (the demo's step) finishes at once, the others (a step 250 times
    shorter) are in progress when the sweep's process group gets SIGINT, as from a terminal."""
    from tribocosim.paths import scene_file

    shutil.copy(scene_file("demo"), tmp_path / "demo.toml")
    (tmp_path / "slow.toml").write_text("""
[sweep]
scene = "demo.toml"
workers = 2

[sweep.variables]
step = [5e-4, 2e-6, 2e-6, 2e-6]

[sweep.set]
"experiment.step" = { expr = "step" }
"output.variables" = ["strip.pull_force", "press.normal_force"]

[sweep.summary]
mu_bar = { mean = "strip.pull_force / (2 * press.normal_force)", last = 0.2 }
""", encoding="utf-8")
    out = tmp_path / "out"
    code, err, children = _signalled(["run", "slow.toml", "--out", str(out)], tmp_path, b"[1/4]", signal.SIGINT,
                                     group=True)
    assert code == 130, err
    assert "Traceback" not in err
    assert err.strip().splitlines()[-1] == (f"tribocosim run: stopped by SIGINT: 1 of 4 cases are finished and kept in "
                                            f"{out / 'cases'} (the cases in progress were discarded); run the same "
                                            "command again to resume"), err
    assert len(children) >= 2, "the workers were running"
    assert _wait_gone(children) == [], "no worker left behind"
    finished = sorted(p.parent.name for p in (out / "cases").glob("*/summary.json"))
    assert finished == ["case-000"] and not (out / "sweep.csv").exists()

    # a rerun takes the finished case as it is (same settings, same key) and runs only the others
    from tribocosim.cosim.apps.scene_sweep import load_sweep, run_case

    summary = out / "cases" / "case-000" / "summary.json"
    stamp = summary.stat().st_mtime_ns
    sweep = load_sweep(tmp_path / "slow.toml")
    rows = run_case(sweep, sweep.cases()[0], out)
    assert summary.stat().st_mtime_ns == stamp and rows == json.loads(summary.read_text())["rows"]
    assert rows[0]["warnings"] == 0 and rows[0]["strip.table_clamp_count"] == 0
