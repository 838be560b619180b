"""Fault injection into real campaigns (tiny 16^2 slides, real worker processes, real files, the real CLI):

- campaign data are checked: a case record whose numbers were edited, a garbage or truncated series file, or a
  record without a digest that disagrees with its series is refused when a table is built (the message names the
  file) and computed again when the campaign resumes;
- a table build that fails or exits 1 leaves the old table byte for byte, and names only files that exist; a
  resumed campaign drops the temporary files of a writer that died before its rename;
- ``tribocosim surrogate build`` stopped by SIGINT (once or twice, to the process group as a terminal's Ctrl-C
  sends it), SIGTERM or SIGKILL (to the driver alone) ends without waiting for the slides in progress (nothing of
  them is written) with 128 + the signal's number, keeps every finished case intact, and leaves no process of its
  session and nothing in its temporary folder (SIGINT twice and SIGTERM are marked slow: ~7 s each).

Only the CLI, the files and /proc are read, so every test also runs against an older checkout.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from tribocosim.surrogate import surrogate_cli

DATA = Path(__file__).parent / "data"
#: 1 P x 1 v x (particle-free + 3 placements), 16^2 pixels, 4 steps: two members with A_p > 0
SMALL = (DATA / "tiny_sweep.toml").read_text().replace('"tiny"', '"tiny-faults"').replace(
    "pressure = [5e6, 20e6]", "pressure = [20e6]").replace("velocity = [5.0, 50.0]", "velocity = [5.0]")
#: two slides at 0.005 m/s that run for minutes and two at 50 m/s that end in a fraction of a second
SIGNALS = (DATA / "signal_sweep.toml").read_text()


def _cli(*args) -> int:
    return surrogate_cli.main([str(a) for a in args])


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    d = tmp_path_factory.mktemp("faults")
    (d / "sweep.toml").write_text(SMALL)
    assert _cli("build", "--sweep", d / "sweep.toml", "--out", d / "out", "--workers", 1, "--quiet") == 0
    return d


@pytest.fixture()
def copy(campaign, tmp_path):
    """A fresh copy of the finished campaign (sweep, cases, table) for one test to damage."""
    shutil.copy(campaign / "sweep.toml", tmp_path / "sweep.toml")
    shutil.copytree(campaign / "out", tmp_path / "out")
    return tmp_path


def _records(out: Path) -> dict[Path, dict]:
    return {p: json.loads(p.read_text()) for p in sorted((out / "cases").glob("*.json"))
            if not p.name.endswith(".error.json")}


def _with_particles(out: Path) -> tuple[Path, dict]:
    """The record with the largest <A_p>/A0 (> 0)."""
    path, rec = max(_records(out).items(), key=lambda kv: kv[1]["summary"]["mean_particle_fraction"])
    assert rec["summary"]["mean_particle_fraction"] > 0
    return path, rec


def _named_paths(text: str) -> list[Path]:
    return [Path(m) for m in re.findall(r"(/\S+?\.(?:json|npz))\b", text)]


def test_edited_case_record_is_refused_by_the_table_and_computed_again_on_resume(copy, capsys, monkeypatch):
    out, table = copy / "out", copy / "out" / "friction_table.npz"
    before = table.read_bytes()
    path, rec = _with_particles(out)
    original = rec["summary"]["mean_particle_fraction"]
    rec["summary"]["mean_particle_fraction"] = 2 * original  # valid JSON, A_p doubled
    path.write_text(json.dumps(rec, indent=1, sort_keys=True))

    assert _cli("table", "--out", out) == 1
    err = capsys.readouterr().err
    assert f"{path} does not match its digest" in err and "1 refused" in err
    assert table.read_bytes() == before, "the old table is left byte for byte"

    log = copy / "computed.log"
    monkeypatch.setenv("TRIBOCOSIM_CASE_LOG", str(log))
    assert _cli("build", "--sweep", copy / "sweep.toml", "--out", out, "--workers", 1, "--quiet") == 0
    err = capsys.readouterr().err
    assert f"{path} does not match its digest" in err and "computed again" in err
    assert log.read_text().split()[0] == path.stem, "the edited case, and only it, is computed again"
    assert json.loads(path.read_text())["summary"]["mean_particle_fraction"] == original


@pytest.mark.parametrize("damage", ["garbage", "truncated"])
def test_damaged_series_file_is_refused_and_its_case_computed_again(copy, capsys, monkeypatch, damage):
    out, table = copy / "out", copy / "out" / "friction_table.npz"
    before = table.read_bytes()
    npz = _with_particles(out)[0].with_suffix(".npz")
    data = npz.read_bytes()
    npz.write_bytes(b"not an npz file" if damage == "garbage" else data[: len(data) // 2])

    assert _cli("table", "--out", out) == 1
    err = capsys.readouterr().err
    assert f"case series {npz} cannot be read" in err and table.read_bytes() == before

    log = copy / "computed.log"
    monkeypatch.setenv("TRIBOCOSIM_CASE_LOG", str(log))
    assert _cli("build", "--sweep", copy / "sweep.toml", "--out", out, "--workers", 1, "--quiet", "--no-table") == 0
    assert log.read_text().split()[0] == npz.stem, "the damaged case is not counted as finished"
    with np.load(npz) as z:
        assert z["particle_fraction"].size == 4


def test_failed_table_build_keeps_the_old_table_and_names_only_files_that_exist(copy, capsys):
    out, table = copy / "out", copy / "out" / "friction_table.npz"
    before = table.read_bytes()
    cases = sorted(p for p, r in _records(out).items() if r["labels"]["n_flakes"])
    cases[0].unlink()  # a case that never finished: no file at all
    failed = cases[1].with_name(cases[1].stem + ".error.json")  # a case that failed: its error file
    failed.write_text(json.dumps({"case_id": cases[1].stem, "status": "failed",
                                  "error": {"type": "ConvergenceError", "message": "did not converge"}}))
    cases[1].unlink()

    assert _cli("table", "--out", out) == 1
    err = capsys.readouterr().err
    assert table.read_bytes() == before, "the old table is left byte for byte"
    assert "2 of 4 cases" in err and f"{failed}: ConvergenceError" in err and cases[0].stem in err
    named = _named_paths(err)
    assert failed in named and all(p.exists() for p in named), f"named files that do not exist: {named}"
    assert sorted(p.name for p in out.iterdir()) == ["campaign.json", "campaign.log", "cases", "fits.json",
                                                     "friction_table.npz"], "no temporary file left behind"

    assert _cli("table", "--out", out, "--allow-failed") == 0  # the finished members, on request
    assert table.read_bytes() != before


def test_records_without_digest_are_checked_against_their_series(copy, capsys):
    out = copy / "out"
    for path, rec in _records(out).items():  # as an older version wrote them
        for key in ("digest", "series_names"):
            rec.pop(key, None)
        path.write_text(json.dumps(rec, indent=1, sort_keys=True))
    assert _cli("table", "--out", out, "--table", copy / "legacy.npz") == 0
    assert "4 case record(s) carry no digest" in capsys.readouterr().err

    path, rec = _with_particles(out)
    rec["summary"]["mean_particle_fraction"] *= 2
    path.write_text(json.dumps(rec, indent=1, sort_keys=True))
    assert _cli("table", "--out", out, "--table", copy / "legacy.npz") == 1
    assert f"{path} (no digest) gives mean_particle_fraction" in capsys.readouterr().err


def test_a_resumed_campaign_drops_the_temporary_files_of_a_writer_that_died(copy):
    """A process ended at once (a second Ctrl-C, SIGKILL) between writing a temporary file and renaming it."""
    dead = subprocess.Popen(["true"])
    dead.wait()
    out = copy / "out"
    stale = out / "cases" / f".0123456789abcdef.json.{dead.pid}.tmp"
    live = out / "cases" / f".0123456789abcdef.npz.{os.getpid()}.tmp"
    stale.write_text("{")
    live.write_text("{")
    assert _cli("build", "--sweep", copy / "sweep.toml", "--out", out, "--no-table", "--quiet") == 0
    assert not stale.exists() and live.exists(), "only the files of a writer that is gone"


# --- signals ------------------------------------------------------------------------------------------------------

def _session(sid: int) -> dict[int, str]:
    """The live (not zombie) processes of session ``sid``, read from /proc: pid -> command line."""
    found = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            cmd = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2:].split()
        if int(fields[3]) == sid and fields[0] != "Z":
            found[int(entry.name)] = cmd[:100]
    return found


def _session_after_exit(sid: int) -> dict[int, str]:
    """The processes of session ``sid`` still alive 5 s after its leader ended (none should be)."""
    for _ in range(50):
        left = _session(sid)
        if not left:
            break
        time.sleep(0.1)
    return left


@pytest.mark.parametrize("how", ["SIGINT", pytest.param("SIGINT twice", marks=pytest.mark.slow),
                                 pytest.param("SIGTERM", marks=pytest.mark.slow), "SIGKILL"])
def test_build_stopped_by_a_signal_keeps_finished_cases_and_leaves_nothing_behind(tmp_path, how):
    """Three workers: two start the slow slides, the third runs both fast ones; once those are written the signal
    comes. SIGINT goes to the process group (a terminal's Ctrl-C), SIGTERM and SIGKILL to the driver alone."""
    sweep, out, tmp = tmp_path / "sweep.toml", tmp_path / "out", tmp_path / "tmp"
    sweep.write_text(SIGNALS)
    tmp.mkdir()
    proc = subprocess.Popen([sys.executable, "-m", "tribocosim.surrogate.surrogate_cli", "build", "--sweep",
                             str(sweep), "--out", str(out), "--workers", "3", "--no-table", "--quiet"],
                            env={**os.environ, "TMPDIR": str(tmp)}, start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while len(list(out.glob("cases/*.json"))) < 2:
            assert proc.poll() is None, f"the build ended early: {proc.stderr.read()}"
            assert time.monotonic() < deadline, "the fast cases did not finish within 120 s"
            time.sleep(0.05)
        finished = {p.name: p.read_bytes() for p in out.glob("cases/*")}
        assert len(_session(proc.pid)) >= 4, "the driver and its three workers"
        if how.startswith("SIGINT"):
            os.killpg(proc.pid, signal.SIGINT)
            if how == "SIGINT twice":
                time.sleep(0.1)
                os.killpg(proc.pid, signal.SIGINT)
        else:
            os.kill(proc.pid, getattr(signal, how))
        try:
            _, err = proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            pytest.fail(f"{how}: the build did not end within 30 s")
        left = _session_after_exit(proc.pid)
    finally:
        for pid in [proc.pid] * (proc.poll() is None) + list(_session(proc.pid)):  # whatever this test started
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
        proc.wait()
    signum = signal.SIGINT if how.startswith("SIGINT") else getattr(signal, how)
    assert proc.returncode == (-signal.SIGKILL if how == "SIGKILL" else 128 + signum), err
    if how in ("SIGINT", "SIGTERM"):
        assert f"stopped by {how}: 2 of 4 cases of {out} are finished and kept" in err
        assert json.loads((out / "campaign.log").read_text().splitlines()[-1])["event"] == "interrupted"
    after = {p.name: p.read_bytes() for p in out.glob("cases/*")}
    assert after == finished, "the finished cases are kept as they were; nothing of the slides in progress"
    assert not left, f"{how}: processes left behind: {left}"
    assert list(tmp.iterdir()) == [], f"{how}: left in the temporary folder: {list(tmp.iterdir())}"


#: the overdamped solver on a tiny campaign (Lambda = 140 at 0.5 m/s with 4 um pixels)
OVERDAMPED = """name = "tiny-overdamped"
[grid]
pressure = [20e6]
velocity = [0.5]
seeds = [1, 2, 3]
[[flakes]]
count = 6
diameter = 12e-6
[slide]
n = 16
size = 64e-6
wavelength_ratio = 0.25
n_slide_steps = 6
flake_solver = "auto"
[table]
quasi_static_row = true
"""


def test_a_resumed_overdamped_campaign_builds_the_same_table_and_verify_reruns_it_exactly(tmp_path, capsys,
                                                                                        monkeypatch):
    """Cases computed again in other worker processes after an interruption (finished cases kept, the others
    lost) give the uninterrupted campaign's table array for array, bit for bit, and verify's reruns are identical:
    the slides are deterministic, FFT plans included (no shared wisdom file)."""
    monkeypatch.delenv("TRIBOCOSIM_FFTW_WISDOM", raising=False)
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(OVERDAMPED)
    full, cut = tmp_path / "full", tmp_path / "cut"
    for out in (full, cut):
        assert _cli("build", "--sweep", sweep, "--out", out, "--workers", 2, "--quiet") == 0
    lost = sorted((cut / "cases").glob("*.json"))[::2]  # as if the campaign had stopped before these
    for path in lost:
        path.unlink()
        path.with_suffix(".npz").unlink()
    (cut / "friction_table.npz").unlink()
    assert _cli("build", "--sweep", sweep, "--out", cut, "--workers", 1, "--quiet") == 0
    a, b = np.load(full / "friction_table.npz"), np.load(cut / "friction_table.npz")
    arrays = [k for k in a.files if k != "metadata"]
    assert arrays and all(np.array_equal(a[k], b[k], equal_nan=True) for k in arrays)
    assert np.asarray(a["particle_area"]).max() > 0, "the flakes must carry load for the check to mean anything"
    solvers = {json.loads(p.read_text())["config"].get("flake_solver") for p in (cut / "cases").glob("*.json")}
    assert solvers == {"overdamped"}
    capsys.readouterr()
    assert _cli("verify", cut / "friction_table.npz", "--workers", 1, "--budget-s", 1e6) == 0
    out = capsys.readouterr().out
    m = re.search(r"(\d+) recorded cases rerun in .*: (\d+) identical, 0 within .*, 0 differ", out)
    assert m and int(m[1]) == int(m[2]) >= 2, out
