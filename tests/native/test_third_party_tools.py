"""Third-party tools on the native FMUs and the exported SSP rig: the FMU Compliance Checker and OMSimulator.

Neither comes from a package registry (OMSimulator's pip package downloads its binary when it is installed; the
checker, modelica-tools/FMUComplianceChecker, is built from source with FMI Library 2.0.3), so both are found
through environment variables naming their executables: ``TRIBOCOSIM_FMUCHECK`` (``fmuCheck.linux64``) and
``TRIBOCOSIM_OMSIMULATOR`` (OMSimulator's command line). A test whose tool is not named is skipped.

- fmuCheck, on each FMI 2.0 FMU (it reads FMI 1.0 and 2.0 only): the XML check and a co-simulation of the FMU's
  default experiment at its step (1 ms to 1.75 s, every step recorded) report 0 warnings and 0 errors, from the
  FMU's logger and from the checker, and the outputs at every step are fmpy's for the same FMU and step;
- OMSimulator, on each FMU alone, both FMI versions (its default experiment): exit 0, no error or warning line,
  the run reaches 1.75 s, and the outputs at every step are fmpy's. Not StripDraw's FMI 3.0 FMU: OMSimulator
  reads every FMI 3 variable as one value (fmi3GetFloat64 with nValues = 1), and StripDraw's nodal fields beta,
  U, contact are arrays of n_nodes values, which the FMU refuses with fmi3Error as FMI 3.0 requires;
- OMSimulator, on the rig of tests/cosim/test_ssp.py as ``tribocosim ssp export`` writes it (400 steps of 1 ms,
  press force, pad width and drive ramp not the FMUs' defaults): the pull force at every step, the last one
  included, is fmpy ``simulate_ssp``'s, and the press runs with the package's force set point.

Tolerance of the comparisons with fmpy. The hosts step the same FMUs with the same step h and the same inputs
(the rig: Jacobi, every output exchanged after the step, no FMU with direct feedthrough), so their coupling
error is the same; they differ in the times they pass: the checker and OMSimulator add h to a running time,
t_k = fl(t_(k-1) + h), fmpy uses k h, so |t_k - k h| <= N ulp(T) / 2 for N steps to T. A time shift dt moves an
output y by about |dy/dt| dt <= max_k |y_(k+1) - y_k| / h dt (fmpy's trajectory). Added to that is how the tool
prints: the checker 17 significant digits (exact), OMSimulator 12 (%.12g: half a unit of the 12th digit).
Where the running time falls short of T after N steps (1750 x 1 ms sums to 1.749999999999918), OMSimulator adds a
step of T - t_N (8e-14 s), which no other host takes: even that short a step moved StripDraw's pull force by
1.2e-7 N in OMSimulator's run (4e-11 of it, within the bar solve's tolerance NEWTON_RTOL = 1e-10 in
tc_stripdraw.c). The rows before that step are compared, and the run is checked to end at T.
"""

from __future__ import annotations

import csv
import math
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

from tribocosim.cli import main as tribocosim

NAMES = ("DrawingMachine", "Press", "StripDraw")
STOP, STEP = 1.75, 1e-3  # every native FMU's DefaultExperiment
#: the short demo rig of tests/cosim/test_ssp.py (press force, pad width and drive ramp not the FMUs' defaults)
RIG = {"experiment.stop": 0.4, "experiment.step": 1e-3, "fmus.press.parameters.force_setpoint": 9800.0,
       "fmus.strip.parameters.tool_width": 0.03, "fmus.drive.parameters.ramp_time": 0.03,
       "fmus.drive.parameters.start_time": 0.1}
RIG_STEPS = 400

def _tool(variable: str, what: str) -> Path:
    path = os.environ.get(variable)
    if not path:
        pytest.skip(f"{variable} is not set (the path of {what})")
    tool = Path(path)
    assert tool.is_file() and os.access(tool, os.X_OK), f"{variable} = {path!r} is not an executable file"
    return tool


@pytest.fixture(scope="module")
def fmucheck() -> Path:
    return _tool("TRIBOCOSIM_FMUCHECK", "the FMU Compliance Checker's fmuCheck.linux64")


@pytest.fixture(scope="module")
def omsimulator() -> Path:
    return _tool("TRIBOCOSIM_OMSIMULATOR", "OMSimulator's command-line executable")


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> dict[int, dict[str, Path]]:
    """``{2: FMI 2.0 FMUs, 3: FMI 3.0 FMUs}`` of the three components, linux64 (as tests/native/test_native_fmi3.py)."""
    from tribocosim.components.fmus.native_build import build_native_fmus

    return {v: build_native_fmus(tmp_path_factory.mktemp(f"fmi{v}"), platforms=["linux64"], fmi_version=v)
            for v in (2, 3)}


@pytest.fixture(scope="module")
def fmpy_run(built):
    """``run(version, name) -> structured array``: fmpy's simulate_fmu of the FMU's default experiment, a row a
    step."""
    from fmpy import simulate_fmu

    runs = {}

    def run(version: int, name: str):
        if (version, name) not in runs:
            runs[version, name] = simulate_fmu(str(built[version][name]), stop_time=STOP, step_size=STEP,
                                               output_interval=STEP)
        return runs[version, name]

    return run


@pytest.fixture(scope="module")
def rig(tmp_path_factory) -> Path:
    """The short demo rig exported by ``tribocosim ssp export``."""
    ssp = tmp_path_factory.mktemp("ssp") / "rig.ssp"
    sets = [x for k, v in RIG.items() for x in ("--set", f"{k}={v!r}")]
    assert tribocosim(["ssp", "export", "demo", "-o", str(ssp), *sets]) == 0
    return ssp


# ----------------------------------------------------------------------------------------------- helpers
def _read_csv(path: Path) -> tuple[list[str], np.ndarray]:
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return [h.strip() for h in rows[0]], np.array([[float(x) for x in r] for r in rows[1:]])


def _tolerance(reference: np.ndarray, step: float, stop: float, digits: int | None) -> np.ndarray:
    """Per value of ``reference`` (fmpy's trajectory of one output, a value per step to ``stop``): the time-shift
    bound N ulp(T) / 2 max |dy| / h, plus half a unit of the last printed digit (``digits`` significant; None:
    printed exactly)."""
    steps = round(stop / step)
    rate = np.max(np.abs(np.diff(reference))) / step
    shift = steps * math.ulp(stop) / 2 * rate
    if digits is None:
        return np.full(len(reference), shift)
    magnitude = np.where(reference != 0.0, np.floor(np.log10(np.abs(np.where(reference != 0.0, reference, 1.0)))),
                         -np.inf)
    return shift + 0.5 * 10.0 ** (magnitude - (digits - 1))


def _assert_outputs_match(names, table, reference, digits, what: str):
    """Every output column of the tool's ``table`` (row k at t_k) against fmpy's ``reference`` rows."""
    outputs = [n for n in reference.dtype.names if n != "time" and n in names]
    assert outputs, f"{what}: no output of fmpy's run in the tool's columns {names}"
    for name in outputs:
        got, ref = table[:, names.index(name)], np.asarray(reference[name], dtype=float)
        assert len(got) == len(ref) == round(STOP / STEP) + 1, (what, name, len(got), len(ref))
        tol = _tolerance(ref, STEP, STOP, digits)
        worst = int(np.argmax(np.abs(got - ref) - tol))
        assert np.all(np.abs(got - ref) <= tol), (
            f"{what}: {name} at step {worst}: {got[worst]!r} vs fmpy {ref[worst]!r} (tolerance {tol[worst]:.3g})")


def _first_row_per_step(table: np.ndarray, step: float) -> np.ndarray:
    """OMSimulator may write a time more than once (v3.0.0-114: before and after the inputs are updated; and at T
    after its last step of T - t_N): the first row of each step k = round(t / step), the values the step ended
    with."""
    k = np.rint(table[:, 0] / step).astype(int)
    first = np.flatnonzero(np.concatenate([[True], np.diff(k) != 0]))
    assert np.array_equal(k[first], np.arange(len(first))), "one row at least per step, in order"
    return table[first]


# ----------------------------------------------------------------------------------------------- fmuCheck
@pytest.mark.parametrize("name", NAMES)
def test_fmucheck_reports_no_warning_or_error_and_fmpy_s_outputs(fmucheck, built, fmpy_run, name, tmp_path):
    log, out = tmp_path / "check.log", tmp_path / "out.csv"
    # -l 3: warnings and errors only; -h: the default experiment's step; -n 0: a row per step
    proc = subprocess.run([str(fmucheck), "-l", "3", "-h", repr(STEP), "-n", "0", "-e", str(log), "-o", str(out),
                           "-t", str(tmp_path), str(built[2][name])],
                          capture_output=True, text=True, timeout=600)
    text = log.read_text()
    assert proc.returncode == 0, f"fmuCheck exit {proc.returncode}:\n{text}\n{proc.stdout}\n{proc.stderr}"
    assert text.split() == ("FMU check summary: FMU reported: 0 warning(s) and error(s) "
                            "Checker reported: 0 Warning(s) 0 Error(s)").split(), text
    names, table = _read_csv(out)
    assert table[-1, 0] == STOP, "the default experiment's stop time"
    _assert_outputs_match(names, table, fmpy_run(2, name), None, f"fmuCheck {name}")


# ----------------------------------------------------------------------------------------------- OMSimulator
def _omsimulator(omsimulator: Path, target: Path, folder: Path, *args: str) -> tuple[list[str], np.ndarray]:
    result = folder / "result.csv"
    proc = subprocess.run([str(omsimulator), str(target), f"--resultFile={result.name}", *args], cwd=folder,
                          capture_output=True, text=True, timeout=600)
    output = proc.stdout + proc.stderr
    assert proc.returncode == 0, f"OMSimulator exit {proc.returncode}:\n{output}"
    problems = [line for line in output.splitlines() if line.startswith(("error:", "warning:"))]
    assert not problems, "\n".join(problems[:10])
    return _read_csv(result)


@pytest.mark.parametrize("version, name", [(2, n) for n in NAMES] + [(3, "DrawingMachine"), (3, "Press")])
def test_omsimulator_runs_each_fmu_s_default_experiment_as_fmpy(omsimulator, built, fmpy_run, version, name,
                                                                 tmp_path):
    names, table = _omsimulator(omsimulator, built[version][name], tmp_path)
    assert table[-1, 0] == STOP, "the run reaches the default experiment's stop time"
    _assert_outputs_match(names, _first_row_per_step(table, STEP), fmpy_run(version, name), 12,
                          f"OMSimulator FMI {version} {name}")


def test_omsimulator_runs_the_exported_rig_as_fmpy(omsimulator, rig, tmp_path):
    from fmpy.ssp.simulation import simulate_ssp

    from tribocosim.cosim.ssp.names import fmpy_parameter_set

    stop = RIG["experiment.stop"]
    # the stop time on the command line: OMSimulator's own default (1 s) otherwise, not the package's
    names, table = _omsimulator(omsimulator, rig, tmp_path, f"--stopTime={stop!r}")
    assert table[-1, 0] == stop
    system = "demo.demo."  # OMSimulator's names: model.system.component.variable, both named after the scene
    rows = _first_row_per_step(table, RIG["experiment.step"])
    assert len(rows) == RIG_STEPS + 1
    got = rows[:, names.index(system + "strip.pull_force")]
    res = simulate_ssp(str(rig), stop_time=stop, step_size=RIG["experiment.step"],
                       parameter_set=fmpy_parameter_set(rig))
    ref = np.concatenate([[0.0], res["strip.pull_force"][:RIG_STEPS]])  # fmpy's row k: after the step from t_k
    tol = _tolerance(ref, RIG["experiment.step"], stop, 12)
    diff = np.abs(got - ref)
    print(f"OMSimulator vs fmpy simulate_ssp (Jacobi, 1 ms, {RIG_STEPS} steps): max |d pull_force| = "
          f"{diff.max()!r} N, final {got[-1]!r} vs {ref[-1]!r} N (tolerance {tol[-1]:.3g} N)")
    assert diff[-1] <= tol[-1], (got[-1], ref[-1], tol[-1])
    assert np.all(diff <= tol), int(np.argmax(diff - tol))
    assert table[-1, names.index(system + "press.force_reference")] == RIG["fmus.press.parameters.force_setpoint"], \
        "the press's parameter set"
