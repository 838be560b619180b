"""A component written in Python (docs/examples/measured_drive: a drive that plays a velocity profile, a pythonfmu
FMU of its own) run in a scene beside the project's native press and strip-draw FMUs."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from tribocosim.errors import RunFailed
from tribocosim.cosim import run

EXAMPLE = Path(__file__).resolve().parents[2] / "docs" / "examples" / "measured_drive"


@pytest.fixture(scope="module")
def example(tmp_path_factory) -> Path:
    """The example's folder as the user guide has it: the scene beside the FMU pythonfmu built from the script."""
    folder = tmp_path_factory.mktemp("measured_drive")
    proc = subprocess.run([sys.executable, "-m", "pythonfmu", "build", "-f", str(EXAMPLE / "MeasuredDrive.py"),
                           str(EXAMPLE / "velocity_profile.csv"), "--handle-state", "--dest", str(folder)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    shutil.copy(EXAMPLE / "measured_drive.toml", folder)
    return folder


def _exact_position(t: float, times: np.ndarray, velocities: np.ndarray) -> float:
    """int_0^t of the profile interpolated linearly (held outside its times): trapezoids between its knots."""
    knots = np.concatenate([[0.0], times[(times > 0.0) & (times < t)], [t]])
    return float(np.trapezoid(np.interp(knots, times, velocities), knots))


def test_the_python_drive_runs_beside_the_native_fmus(example):
    res = run(example / "measured_drive.toml", write=False)
    times, velocities = np.loadtxt(EXAMPLE / "velocity_profile.csv", delimiter=",", skiprows=1).T
    t = res.time
    assert len(t) == 1201 and res.metadata["master"]["loop"] == "native", "the C loop steps the Python FMU too"
    # the drive plays the profile, and its position is the profile's integral
    np.testing.assert_allclose(res["drive.grip_velocity"], np.interp(t, times, velocities), rtol=0, atol=1e-15)
    np.testing.assert_allclose(res["drive.grip_position"], [_exact_position(x, times, velocities) for x in t],
                               rtol=1e-12, atol=1e-15)
    # the strip takes the velocity of each communication point over the next step (Jacobi, held inputs): its grip
    # moves by sum v(t_n) h, a first-order approximation of the drive's own position
    h = 5e-4
    held = np.concatenate([[0.0], np.cumsum(res["drive.grip_velocity"][:-1]) * h])
    np.testing.assert_allclose(res["strip.grip_position"], held, rtol=1e-9, atol=1e-15)
    assert abs(res["strip.grip_position"][-1] - res["drive.grip_position"][-1]) <= 0.5 * h * 0.09
    # drawn, the strip slides: the pull force balances the friction of both faces, mu = F_pull / (2 F_N) (Eq. 1)
    pull, normal, mu = res["strip.pull_force"][-1], res["press.normal_force"][-1], res["strip.mu_mean"][-1]
    assert normal == pytest.approx(12250.0, rel=0.01) and 0.02 < mu < 0.5
    assert pull / (2 * normal) == pytest.approx(mu, rel=0.05)


def _bad_profile_scene(example: Path, folder: Path) -> tuple[Path, Path]:
    """(the scene, its profile file): the example's scene with a profile whose times do not increase."""
    bad = folder / "bad.csv"
    bad.write_text("time,velocity\n0.0,0.0\n0.0,0.1\n")
    fmu = example / "MeasuredDrive.fmu"
    scene = (example / "measured_drive.toml").read_text().replace(
        'path = "MeasuredDrive.fmu"', f'path = "{fmu}"\nparameters = {{ profile_file = "{bad}" }}')
    (folder / "bad.toml").write_text(scene)
    return folder / "bad.toml", bad


def test_a_bad_profile_file_stops_the_run_at_initialization_naming_it(example, tmp_path):
    scene, bad = _bad_profile_scene(example, tmp_path)
    with pytest.raises(RunFailed) as exc:
        run(scene, write=False)
    message = str(exc.value)
    assert "FMU instance 'drive': fmi2ExitInitializationMode failed" in message, message
    assert f"{bad}, row 3: time = 0.0 s" in message and "increasing times" in message, message


def test_a_python_component_that_raised_leaves_the_process_sound(example, tmp_path):
    """pythonfmu turns the component's exception into fmi2Fatal, after which no function of the FMU may be called
    (FMI 2.0.4, section 2.1.3): freeing the instance anyway releases its Python objects a second time (pythonfmu
    0.7), and the interpreter crashes at a later garbage collection. Failing runs of both masters and a collection
    in one process (a subprocess here, so that a crash fails this test alone), to the end of the process (its exit:
    the next test)."""
    scene, _ = _bad_profile_scene(example, tmp_path)
    code = textwrap.dedent("""
        import gc, sys
        from tribocosim.cosim import run
        from tribocosim.errors import RunFailed
        for loop in ("auto", "python", "auto"):
            try:
                run(sys.argv[1], write=False, loop=loop)
            except RunFailed as exc:
                assert "fmi2ExitInitializationMode failed" in str(exc), exc
            else:
                raise AssertionError("the run did not fail")
            gc.collect()
        print("sound")
        """)
    proc = subprocess.run([sys.executable, "-c", code, str(scene)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0 and proc.stdout.strip() == "sound", (proc.returncode, proc.stderr[-3000:])


def test_the_library_of_a_python_component_touches_no_freed_memory_to_the_end_of_the_process(example, tmp_path):
    """pythonfmu 0.7's library, still loaded when the process exits, releases its interpreter state twice in ``exit``:
    the static ``pyState``'s destructor frees it, then the library's destructor (``finalizePythonInterpreter``) writes
    into the freed block. That aborts the process only when glibc holds the block in one of its bins at that moment
    ("corrupted double-linked list", as the test above sees now and then); memcheck sees the write every time. After a
    run that succeeds (the C loop) and one that fails (the Python loop), to the end of the process, the library makes no
    access that memcheck refuses (:mod:`tribocosim.cosim.engine.libraries` releases the state once, at the interpreter's
    exit)."""
    if shutil.which("valgrind") is None:
        pytest.skip("valgrind is not installed")
    scene, _ = _bad_profile_scene(example, tmp_path)
    code = textwrap.dedent("""
        import sys
        from tribocosim.cosim import run
        from tribocosim.errors import RunFailed
        run(sys.argv[1], write=False)
        try:
            run(sys.argv[2], write=False, loop="python")
        except RunFailed:
            print("sound")
        """)
    env = {**os.environ, "PYTHONMALLOC": "malloc"}  # memcheck sees each of Python's blocks, not its arenas
    memcheck = ["valgrind", "--undef-value-errors=no", "--error-limit=no", "--num-callers=30"]
    proc = subprocess.run([*memcheck, sys.executable, "-c", code, str(example / "measured_drive.toml"), str(scene)],
                          capture_output=True, text=True, timeout=600, env=env)
    library = "/MeasuredDrive.so"  # the FMU's binaries/linux64/MeasuredDrive.so, as memcheck names it in a stack
    refused = [r for r in re.split(r"\n==\d+== \n", proc.stderr) if library in r]
    assert proc.returncode == 0 and proc.stdout.strip() == "sound", (proc.returncode, proc.stderr[-3000:])
    assert refused == [], "\n\n".join(refused)[-4000:]
