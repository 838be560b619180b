"""Bad inputs as a new user and real hosts give them, each run as a subprocess of the real command line or of fmpy on
the real StripDraw FMU: every one ends, within seconds, with a message that names the quantity, its value and what is
allowed (or with a result that is right), leaves no temporary folder behind and writes no half of anything.

- a table replaced after its resource form was written is refused by the FMU, not served from the old resource;
- absurd scene values (a normal force far above the hardness, NaN and inf inputs, a grip faster than the strip's
  waves, a stop time of 1e30 s) are scene problems (exit 2) before anything runs;
- an FMU step no step size can complete ends the host's simulation instead of being retried forever, and a grip at
  1e6 m/s does not make a step take seconds;
- the interface penalty's declared range is the range the solver handles;
- results that cannot be written, or a second run into the same folder, are refused before the run, and ``--set``
  overrides are recorded with the results;
- a truncated FMU binary is a scene problem, not a bus error; SIGTERM leaves no ``tribocosim-*`` folder.
"""

from __future__ import annotations

import json
import shutil
import signal
import subprocess
import sys
import textwrap
import time
import zipfile
from pathlib import Path

import pytest

from tribocosim.paths import DEFAULT_TABLE, SCENES_DIR

STRIPDRAW = SCENES_DIR / "stripdraw.toml"
TIMEOUT = 300


@pytest.fixture
def tmpdir_env(tmp_path, monkeypatch) -> Path:
    """A temporary folder of the test's own (``TMPDIR`` of the subprocesses), so that what they leave there is
    theirs alone."""
    folder = tmp_path / "tmp"
    folder.mkdir()
    monkeypatch.setenv("TMPDIR", str(folder))
    return folder


def tribocosim(*args, cwd=None, timeout=TIMEOUT) -> subprocess.CompletedProcess:
    """The console script (``python -m tribocosim.cli``) as a subprocess."""
    return subprocess.run([sys.executable, "-m", "tribocosim.cli", *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, cwd=cwd)


def python(script: str, *args, cwd=None, timeout=TIMEOUT) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(script), *map(str, args)], capture_output=True,
                          text=True, timeout=timeout, cwd=cwd)


def temp_folders(folder: Path) -> set[str]:
    """The ``tribocosim-*`` folders in a temporary folder (the extracted FMUs and packages of runs)."""
    return {p.name for p in folder.glob("tribocosim-*")}


@pytest.fixture(scope="module")
def strip_fmu() -> Path:
    """The StripDraw FMU (native, this machine's binary) from the FMU cache, built on first use."""
    from tribocosim.cosim.scene.fmucache import component_fmu

    return component_fmu("stripdraw")


# ------------------------------------------------------------------------------------------- the friction table
_STALE = """
    import sys
    from fmpy import simulate_fmu
    r = simulate_fmu(sys.argv[1], stop_time=0.01, step_size=1e-3, start_values={"table_file": sys.argv[2],
                     "normal_force": 36750.0})
    print("pull_force", r["pull_force"][-1])
"""


def test_a_table_replaced_after_its_resource_was_written_is_refused_by_the_fmu(strip_fmu, tmp_path):
    """`tribocosim fmu table-resource my.npz`, then another table saved as my.npz: fmpy ran the old table (pull
    force 7066.5 N where the new one gives 7488.1 N at 30 MPa). The FMU refuses it at initialization, naming the
    table, its resource and the command that rewrites it; rewritten, the new table is used."""
    from tribocosim.components.stripdraw.friction import closed_form_table
    from tribocosim.components.stripdraw.table import write_table

    table = tmp_path / "my.npz"
    shutil.copy(DEFAULT_TABLE, table)
    assert tribocosim("fmu", "table-resource", table).returncode == 0
    first = python(_STALE, strip_fmu, table)
    assert first.returncode == 0, first.stderr[-2000:]
    write_table(table, closed_form_table())  # another table under the same name
    stale = python(_STALE, strip_fmu, table)
    assert stale.returncode != 0 and "pull_force" not in stale.stdout
    assert f"friction table {table} has changed since its resource form {tmp_path / 'my.tca'} was written" in \
        stale.stdout + stale.stderr, (stale.stdout + stale.stderr)[-3000:]
    assert "tribocosim fmu table-resource" in stale.stdout + stale.stderr
    assert tribocosim("fmu", "table-resource", table).returncode == 0
    fresh = python(_STALE, strip_fmu, table)
    assert fresh.returncode == 0 and fresh.stdout.split()[-1] != first.stdout.split()[-1], fresh.stderr[-2000:]


# ------------------------------------------------------------------------------------------- absurd scene values
@pytest.mark.parametrize("setting, message", [
    ("fmus.strip.parameters.normal_force=1e30", "is a nominal pressure of 8.163e+32 Pa, above the strip's hardness "
                                                "8e+08 Pa"),
    ("fmus.strip.parameters.normal_force=nan", "normal_force = nan N is not finite; a finite number is required"),
    ("fmus.strip.parameters.normal_force=-inf", "normal_force = -inf N is not finite"),
    ("fmus.strip.parameters.grip_velocity=inf", "grip_velocity = inf m/s is not finite"),
    ("fmus.strip.parameters.grip_velocity=1e6", "grip_velocity = 1e+06 m/s is not below the wave speed "
                                                "sqrt(E / rho) = 5129.89 m/s"),
    ("fmus.strip.parameters.grip_velocity=-1e6", "grip_velocity = -1e+06 m/s is below 0 m/s"),
    ("fmus.strip.parameters.tool_length=nan", "tool_length = nan is not finite"),
    ("fmus.strip.parameters.shear_stiffness_factor=1e9", "shear_stiffness_factor = 1000000000.0 is out of range; "
                                                         "allowed: [1e-06, 10000]"),
    ("experiment.stop=1e30", "stop = 1e+30 s is 1e+33 steps of 0.001 s after start = 0.0 s; at most 1e+08 steps"),
])
def test_absurd_scene_values_are_scene_problems_before_anything_runs(tmp_path, tmpdir_env, setting, message):
    """Each ran to the end with one warning (1e30 N), failed late after 14 discard lines (NaN, inf), ran a step in
    seconds (1e6 m/s), or announced an ETA of 4e28 s (stop = 1e30): now each is exit 2 naming the key, the value
    and what is allowed, and nothing is written."""
    proc = tribocosim("run", STRIPDRAW, "--out", tmp_path / "out", "--quiet", "--set", setting)
    assert proc.returncode == 2 and message in proc.stderr, proc.stderr[-3000:]
    assert "Traceback" not in proc.stderr and "[discard]" not in proc.stderr
    assert not (tmp_path / "out" / "stripdraw.csv").exists()
    assert not temp_folders(tmpdir_env)


# ------------------------------------------------------------------------------------------- FMU steps in fmpy
_SIMULATE = """
    import sys, json
    import numpy as np
    from fmpy import simulate_fmu
    values, stop = json.loads(sys.argv[2]), float(sys.argv[3])
    ramp = values.pop("ramp", None)  # the grip ramped to 0.08 m/s over this time, as the demo's drive does
    inputs = None if ramp is None else np.array(
        [(0.0, 0.0), (ramp, 0.08), (stop, 0.08)], dtype=[("time", float), ("grip_velocity", float)])
    calls = []  # the doStep calls fmpy made (its FMI call log)
    log = lambda line: calls.append(1) if line.startswith("fmi2DoStep") else None
    try:
        r = simulate_fmu(sys.argv[1], stop_time=stop, step_size=1e-3, start_values=values, input=inputs,
                         output=["pull_force", "grip_position"], fmi_call_logger=log)
        print("ended", r["time"][-1], r["pull_force"][-1], len(calls))
    except Exception as exc:
        print("failed", exc, len(calls))
"""


@pytest.mark.parametrize("start_values, stop, outcome, message", [
    ({"normal_force": -5.0}, 0.01, "failed", "no step size can complete it"),
    ({"grip_velocity": 1e6}, 1.0, "failed", "grip_velocity = 1e+06 m/s is not below the strip's wave speed"),
    ({"internal_step": 1e-12}, 0.01, "ended 0.0", "repeats a step this FMU discarded, unchanged"),
    ({"shear_stiffness_factor": 5e3, "ramp": 0.02}, 0.05, "ended 0.05", ""),
    ({"shear_stiffness_factor": 1e9}, 0.01, "failed", "shear_stiffness_factor = 1e+09 is out of range; allowed: "
                                                      "[1e-06, 10000]"),
])
def test_fmpy_ends_every_simulation_of_the_fmu_within_seconds(strip_fmu, tmp_path, start_values, stop, outcome,
                                                              message):
    """fmpy's simulate_fmu repeats a discarded step until the FMU asks to end: a negative normal force, a step the
    model cannot cut small enough (internal_step 1e-12 s: 1e9 pieces per 1 ms step) or a stiff interface whose solve
    was refused (shear_stiffness_factor 5e3, declared valid up to 1e9) ran forever; a grip at 1e6 m/s took 2.7 s per
    step. Now: an error at once where no step size helps, Terminated where the same step is repeated unchanged, the
    stiff interface solved, and a penalty beyond the solver's range refused at initialization."""
    proc = python(_SIMULATE, strip_fmu, json.dumps(start_values), stop, cwd=tmp_path, timeout=120)
    out = proc.stdout + proc.stderr
    last = proc.stdout.strip().splitlines()[-1] if proc.stdout.strip() else ""
    assert proc.returncode == 0 and last.startswith(outcome), out[-3000:]
    assert int(last.split()[-1]) <= round(stop / 1e-3) + 1, "ended after the steps of the run at most (and one repeat)"
    if message:
        assert message in out, out[-3000:]


# ------------------------------------------------------------------------------------------- where results go
def test_results_that_cannot_be_written_are_refused_before_the_run(tmp_path):
    """An --out that is a file, under a file, or in /proc failed after the whole run with a raw traceback; a file
    name taken by a folder too. Each is exit 2 at once, naming the folder and the reason."""
    (tmp_path / "afile").write_text("in the way")
    (tmp_path / "taken" / "stripdraw.csv").mkdir(parents=True)
    for out, message in ((tmp_path / "afile", "a file of that name is in the way"),
                         (tmp_path / "afile" / "sub", "cannot make the output folder"),
                         (Path("/proc/tribocosim-out"), "cannot make the output folder /proc/tribocosim-out"),
                         (tmp_path / "taken", "stripdraw.csv: a folder of that name is in the way")):
        proc = tribocosim("run", STRIPDRAW, "--out", out, "--quiet")
        assert proc.returncode == 2 and message in proc.stderr and "Traceback" not in proc.stderr, proc.stderr[-2000:]


def test_a_second_run_into_the_same_folder_is_refused_and_overrides_are_recorded(tmp_path):
    """Two runs into one --out overwrote each other silently; the second is refused while the first runs, naming
    its process; the first's JSON records its --set overrides, and the lock is gone when it ends. The first run is
    the Python loop at 20 us steps (1.5 million steps, minutes unless stopped): it is still running when the second
    one starts."""
    out = tmp_path / "out"
    first = subprocess.Popen([sys.executable, "-m", "tribocosim.cli", "run", "demo", "--out", str(out), "--quiet",
                              "--set", "experiment.stop=30", "--set", "experiment.step=2e-5",
                              "--set", "master.extrapolation=1"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.time() + 120
        while not (out / ".tribocosim-run.lock").exists() and time.time() < deadline:
            time.sleep(0.1)
        second = tribocosim("run", "demo", "--out", out, "--quiet", "--set", "experiment.stop=0.1")
        assert second.returncode == 2, second.stderr[-2000:]
        assert f"another run (process {first.pid}) is writing into {out}" in second.stderr
    finally:
        first.send_signal(signal.SIGTERM)
        first.communicate(timeout=120)
    assert first.returncode == 128 + signal.SIGTERM and not (out / ".tribocosim-run.lock").exists()
    done = tribocosim("run", "stripdraw", "--out", out, "--quiet", "--set", "experiment.stop=0.01", "--set",
                      "fmus.strip.parameters.tool_length=0.07")
    assert done.returncode == 0, done.stderr[-2000:]
    meta = json.loads((out / "stripdraw.json").read_text())
    assert meta["overrides"] == {"experiment.stop": 0.01, "fmus.strip.parameters.tool_length": 0.07}


# ------------------------------------------------------------------------------------------- crashes and signals
def test_a_truncated_fmu_binary_is_a_scene_problem_not_a_bus_error(strip_fmu, tmp_path, tmpdir_env):
    """The StripDraw FMU with its linux64 library cut to a tenth crashed `tribocosim run` with a bus error (exit
    135) and left its extraction folder behind; cut to 90 % (only the section headers lost) it ran."""
    for fraction in (0.1, 0.9):
        broken = tmp_path / f"Cut{int(fraction * 100)}.fmu"
        with zipfile.ZipFile(strip_fmu) as z, zipfile.ZipFile(broken, "w", zipfile.ZIP_DEFLATED) as out:
            for info in z.infolist():
                data = z.read(info)
                if info.filename.startswith("binaries/") and info.filename.endswith(".so"):
                    data = data[:int(len(data) * fraction)]
                out.writestr(info, data)
        scene = tmp_path / "cut.toml"
        scene.write_text(f'[experiment]\nstop = 0.01\nstep = 1e-3\n[fmus.strip]\npath = "{broken}"\n'
                         'parameters = { normal_force = 12250.0, grip_velocity = 0.08 }\n')
        proc = tribocosim("run", scene, "--out", tmp_path / "out", "--quiet")
        assert proc.returncode == 2, (proc.returncode, proc.stderr[-2000:])
        assert f"{broken.name}: its library binaries/linux64/StripDraw.so is truncated or damaged" in proc.stderr
        assert not temp_folders(tmpdir_env)


def test_sigterm_ends_a_run_and_leaves_no_temporary_folder(tmp_path, tmpdir_env):
    """SIGTERM killed the process before Python's clean-up: the output folder's lock stayed. It ends the run as an
    exception does (exit 143): the lock is released, and no temporary folder stays (the FMUs are extracted into the
    FMU cache). The run is the demo at a millionth of a second (2.06 million steps, tens of seconds unless stopped),
    signalled once its progress bar shows the loop is under way."""
    proc = subprocess.Popen([sys.executable, "-m", "tribocosim.cli", "run", "demo", "--out", str(tmp_path / "out"),
                             "--set", "experiment.step=1e-6", "--set", 'output.variables=["strip.pull_force"]'],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    seen = b""
    while b"\r[" not in seen:
        chunk = proc.stderr.read1(65536)
        if not chunk:
            proc.wait(timeout=60)
            pytest.fail(f"the run ended before its progress showed (exit {proc.returncode}): {seen[-2000:]!r}")
        seen += chunk
    proc.send_signal(signal.SIGTERM)
    proc.communicate(timeout=120)
    assert proc.returncode == 128 + signal.SIGTERM
    assert not temp_folders(tmpdir_env), temp_folders(tmpdir_env)
    assert not (tmp_path / "out" / ".tribocosim-run.lock").exists()
