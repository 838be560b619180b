"""The ``tribocosim`` console script (tribocosim/cli.py) as a user runs it: a separate process, its exit code, and
nothing left in the temporary folder afterwards."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest



def _console(args, tmp: Path, cwd: Path) -> subprocess.CompletedProcess:
    """``tribocosim ARGS`` in a new process whose temporary folder (TMPDIR) is ``tmp``."""
    exe = shutil.which("tribocosim") or pytest.skip("tribocosim console script not installed")
    env = {**os.environ, "TMPDIR": str(tmp), "MPLBACKEND": "Agg"}
    return subprocess.run([exe, *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=600)


def test_a_run_with_pythonfmu_fmus_leaves_nothing_in_the_temp_folder(tmp_path, osc_scene):
    """The console script ends with os._exit after a pythonfmu FMU ran (cli.console): the extracted FMUs must be
    removed before that."""
    scene = osc_scene(tmp_path, stop=0.2, step=0.01)
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    proc = _console(["run", str(scene), "--quiet", "--out", str(tmp_path / "out")], tmp, tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "out" / "results.csv").is_file()
    assert sorted(p.name for p in tmp.iterdir()) == [], "files left in the temporary folder"


def test_ssp_export_and_run_leave_nothing_in_the_temp_folder(tmp_path, osc_scene):
    scene = osc_scene(tmp_path, stop=0.2, step=0.01)
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    ssp = tmp_path / "osc.ssp"
    proc = _console(["ssp", "export", str(scene), "-o", str(ssp)], tmp, tmp_path)
    assert proc.returncode == 0, proc.stderr
    proc = _console(["run", str(ssp), "--quiet", "--out", str(tmp_path / "out")], tmp, tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert sorted(p.name for p in tmp.iterdir()) == [], "files left in the temporary folder"
