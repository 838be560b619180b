"""Tests of cosim.fmucache (``component = "..."`` scenes) and of a StripDraw scene end to end.

The cache logic is tested with a stand-in builder (a pure unit test: it copies a test FMU);
the real path builds the project's StripDraw FMU with components.fmus.build and runs
``tribocosim run`` on it in a subprocess.
"""

import json
import os
import shutil
import subprocess
import sys
import types
from pathlib import Path

import pytest
from fmpy.util import read_csv

from tribocosim.components.errors import SceneError
from tribocosim.cosim import fmucache

ROOT = Path(__file__).resolve().parents[2]


def fake_builder(fmu_dir, calls, digest="abc123"):
    def build_fmus(out_dir, names=None):
        calls.append(list(names or []))
        dst = Path(out_dir) / "Demo.fmu"
        shutil.copy(fmu_dir / "LoopGain.fmu", dst)
        return {"Demo": dst}

    return types.SimpleNamespace(FMUS={"Demo": None}, build_fmus=build_fmus, source_digest=lambda name: digest * 8)


def test_component_is_built_once_and_cached(tmp_path, fmu_dir, monkeypatch):
    calls = []
    monkeypatch.setenv("TRIBOCOSIM_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(fmucache, "_builder", lambda: fake_builder(fmu_dir, calls))
    first = fmucache.component_fmu("demo")
    second = fmucache.component_fmu("DEMO")
    assert first == second and first.is_file() and first.parent.parent == tmp_path / "cache"
    assert calls == [["Demo"]], "the second request uses the cache"
    monkeypatch.setattr(fmucache, "_builder", lambda: fake_builder(fmu_dir, calls, digest="def456"))
    third = fmucache.component_fmu("demo")
    assert third != first and len(calls) == 2, "a changed source digest rebuilds into a new entry"
    assert not [p for p in (tmp_path / "cache").iterdir() if p.name.startswith(".")], "no temporary folders left"


def test_unknown_component_and_missing_builder_are_scene_errors(tmp_path, fmu_dir, monkeypatch):
    monkeypatch.setattr(fmucache, "_builder", lambda: fake_builder(fmu_dir, []))
    with pytest.raises(SceneError, match="unknown component 'press'; this installation builds: Demo"):
        fmucache.component_fmu("press", cache=tmp_path)
    monkeypatch.undo()
    import tribocosim.components.fmus

    # the import fails: no module, and no attribute left by an earlier import in this session
    monkeypatch.delattr(tribocosim.components.fmus, "build", raising=False)
    monkeypatch.setitem(sys.modules, "tribocosim.components.fmus.build", None)
    with pytest.raises(SceneError, match="FMU builder tribocosim.components.fmus.build is not available"):
        fmucache.component_fmu("stripdraw", cache=tmp_path)


SCENE = ROOT / "models" / "scenes" / "stripdraw.toml"


@pytest.fixture(scope="module")
def strip_run(tmp_path_factory):
    if not (ROOT / "components" / "fmus" / "build.py").is_file():
        pytest.skip("the StripDraw builder (components/fmus/build.py) is not in this tree")
    folder = tmp_path_factory.mktemp("strip")
    env = dict(os.environ, TRIBOCOSIM_CACHE=str(folder / "cache"))
    cmd = [sys.executable, "-m", "tribocosim.cli", "run", str(SCENE), "--out", str(folder / "out"),
           "--set", "experiment.stop=0.02", "--set", 'fmus.strip.parameters.friction_model="constant"',
           "--set", "fmus.strip.parameters.mu_const=0.15"]
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600, cwd=str(ROOT))
    return folder, proc


def test_stripdraw_scene_builds_on_demand_and_runs(strip_run):
    folder, proc = strip_run
    out = folder / "out"
    assert (out / "stripdraw.csv").is_file(), f"no results; stderr:\n{proc.stderr}"
    traj = read_csv(out / "stripdraw.csv")
    assert traj.dtype.names == ("time", "strip.pull_force", "strip.friction_force", "strip.mu_mean", "strip.beta_mean",
                                "strip.contact_pressure", "strip.grip_position")
    assert len(traj) == 21
    # constant friction law: mu_mean = 0.15 once the strip slides; the grip moves at its start velocity
    assert abs(traj["strip.mu_mean"][-1] - 0.15) < 1e-3, traj["strip.mu_mean"]
    assert abs(traj["strip.grip_position"][-1] - 0.08 * 0.02) < 1e-9
    meta = json.loads((out / "stripdraw.json").read_text())
    assert meta["steps"]["accepted"] == 20
    assert "input strip.normal_force is not connected; its scene value 12250.0 is used" in meta["warnings"]
    # mu = pull_force / (2 normal_force) reads like Eq. 1 once sliding (MODEL.md section 2)
    assert abs(traj["strip.pull_force"][-1] / (2 * 12250.0) - 0.15) < 0.01, traj["strip.pull_force"]
    assert len(list((folder / "cache").glob("StripDraw-*/StripDraw.fmu"))) == 1


def test_stripdraw_run_exits_cleanly(strip_run):
    """Regression: an earlier StripDraw build crashed the host at exit (heap corruption)."""
    _, proc = strip_run
    assert proc.returncode == 0, proc.stderr[-2000:]
