"""Tests of cosim.scene.fmucache (``component = "..."`` scenes) and of a StripDraw scene end to end.

The cache logic is tested with the press (the cheapest FMU to compile); the StripDraw path builds the project's StripDraw FMU and runs ``tribocosim run`` on it in a subprocess.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from fmpy.util import read_csv

from tribocosim.errors import SceneError
from tribocosim.cosim.scene import fmucache

ROOT = Path(__file__).resolve().parents[2]


def test_component_is_built_once_and_cached(tmp_path):
    from tribocosim.components.fmus import native_build

    cache = tmp_path / "cache"
    first = fmucache.component_fmu("press", cache=cache)
    stamp = first.stat().st_mtime_ns
    second = fmucache.component_fmu("PRESS", cache=cache)
    assert first == second and first.is_file() and first.parent.parent == cache
    assert second.stat().st_mtime_ns == stamp, "the second request uses the cache"
    assert first.parent.name == f"Press-native-{native_build.source_digest('Press')[:16]}", "keyed by the source digest"
    assert not [p for p in cache.iterdir() if p.name.startswith(".")], "no temporary folders left"


def test_a_component_without_a_c_implementation_is_a_scene_error_that_says_what_to_do(tmp_path, monkeypatch):
    import dataclasses

    from tribocosim.components import registry

    python_only = dataclasses.replace(registry.find("press"), name="pylag", model_identifier="PyLag", native=None)
    monkeypatch.setitem(registry._REGISTERED, "pylag", python_only)  # a component written in Python only
    with pytest.raises(SceneError, match="no native implementation.*pythonfmu FMU of its own, named by path"):
        fmucache.component_fmu("pylag", cache=tmp_path)


def test_unknown_component_is_a_scene_error(tmp_path):
    with pytest.raises(SceneError, match="unknown component 'presss'; this installation builds: "):
        fmucache.component_fmu("presss", cache=tmp_path)


SCENE = ROOT / "models" / "scenes" / "stripdraw.toml"


@pytest.fixture(scope="module")
def strip_run(tmp_path_factory):
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
    # mu = pull_force / (2 normal_force) reads like Eq. 1 once sliding (docs/model.md section 2)
    assert abs(traj["strip.pull_force"][-1] / (2 * 12250.0) - 0.15) < 0.01, traj["strip.pull_force"]
    assert len(list((folder / "cache").glob("StripDraw-*/StripDraw.fmu"))) == 1


def test_stripdraw_run_exits_cleanly(strip_run):
    """Regression: an earlier StripDraw build crashed the host at exit (heap corruption)."""
    _, proc = strip_run
    assert proc.returncode == 0, proc.stderr[-2000:]


def test_the_remembered_digest_is_keyed_by_the_checkouts_sources(tmp_path, monkeypatch):
    """Two checkouts may share one cache: the digest remembered for the other checkout's files (its record still
    valid, those files unchanged) is not this checkout's. The key holds the components folder, and the cache looks a
    digest up under the builder's own key."""
    from tribocosim.components.fmus import cache_key, native_build
    from tribocosim.components.native.toolchain import digests

    monkeypatch.setenv("TRIBOCOSIM_CACHE", str(tmp_path / "cache"))
    here = native_build.digest_key("Press")
    assert str(cache_key.SOURCES) in here and cache_key.SOURCES == (ROOT / "components").resolve()
    other = here.replace(str(cache_key.SOURCES), "/elsewhere/components")
    stale = tmp_path / "other_checkout_file"
    stale.write_text("x")
    digests.memo(other, [stale], lambda: "f" * 64)  # a digest another checkout remembered
    fmu = fmucache.component_fmu("press", cache=tmp_path / "fmus")
    assert fmu.parent.name == f"Press-native-{native_build.source_digest('Press')[:16]}" != f"Press-native-{'f' * 16}"
