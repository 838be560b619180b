"""``tribocosim demo`` end to end: FMUs built on demand into an empty cache, the demo scene run, its
results and three figures written, mu_bar printed; and a failed build reported with its cause.

mu_bar of the co-simulation is checked against the pure strip-draw model driven at the same
velocity ramp and force (no FMI, no machine, no press): at 1 ms with the machine holding 0.08 m/s
and the press 12250 N the two must agree closely.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from fmpy.util import read_csv

from tribocosim.cosim.apps import demo
from tribocosim.cosim.studies.stripdraw_experiment import run_strip_draw, steady_mean

ROOT = Path(__file__).resolve().parents[2]


def test_demo_builds_the_fmus_runs_and_writes_results_and_figures(tmp_path):
    env = dict(os.environ, TRIBOCOSIM_CACHE=str(tmp_path / "cache"), MPLBACKEND="Agg")
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "tribocosim.cli", "demo", "--out", str(tmp_path / "demo")],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    wall = time.perf_counter() - t0
    assert proc.returncode == 0, proc.stdout + proc.stderr
    out = proc.stdout
    print(f"\ntribocosim demo (empty FMU cache): {wall:.1f} s, load {os.getloadavg()[0]:.1f}\n{out}")
    assert len(list((tmp_path / "cache").glob("*/*.fmu"))) == 3, "the three FMUs were built into the cache"
    assert out.count("built ") == 3, out
    mu_bar = float(re.search(r"mu_bar = ([0-9.]+)", out).group(1))
    res = read_csv(tmp_path / "demo" / "demo.csv")
    t = res["time"]
    assert t[-1] == pytest.approx(2.06) and len(t) == 4121
    steady = t >= t[-1] - 0.2 * t[-1]
    ratio = np.mean(res["strip.pull_force"][steady] / (2 * res["press.normal_force"][steady]))
    assert mu_bar == pytest.approx(ratio, abs=5e-5), "printed mu_bar = Eq. 1 over the last 20 % of the CSV"
    assert res["strip.sliding_distance"][-1] == pytest.approx(0.14, abs=0.002), "140 mm drawn"
    for name in ("mu_vs_sliding_distance.png", "beta_map.png", "forces.png"):
        f = tmp_path / "demo" / name
        assert f.is_file() and f.stat().st_size > 20_000, name
        assert str(f) in out, f"{name} location printed"
    from tribocosim.components.native.resource_io.field_file import read_fields

    field = read_fields(tmp_path / "demo" / "beta_field.csv")
    assert field["beta"].shape == (207, field["X"].size), "rows every 10 ms (+ t = 0)"
    assert field["beta"][-1].max() == pytest.approx(res["strip.beta_max"][-1], rel=1e-12)
    # the same test with the pure model (prescribed velocity ramp and force): same mu_bar
    _, outs, _ = run_strip_draw(10e6, 0.035, ramp_time=0.02)
    np.testing.assert_allclose(mu_bar, steady_mean(outs), rtol=2e-3,
                               err_msg="co-simulated mu_bar vs the strip-draw model alone")


def test_demo_says_why_when_the_fmus_cannot_be_built(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("TRIBOCOSIM_CACHE", str(tmp_path / "empty"))

    from tribocosim.components.fmus import native_build

    def build_native_fmus(out_dir, names=None, platforms=None):
        raise native_build.FmuBuildError("compiling Press.so for linux64 failed (exit 1): no C compiler found")

    monkeypatch.setattr(native_build, "build_native_fmus", build_native_fmus)
    assert demo.main(["--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    assert "the FMUs could not be built" in err and "no C compiler found" in err and "Press.fmu" in err, err
    assert not (tmp_path / "out").exists()


def test_the_readme_states_the_demo_mu_bar_of_the_default_model_and_of_the_papers():
    """The README's mu_bar of the demo (the default model, and the paper's frictionless flakes) is the strip-draw model's
    at the demo's force and velocity ramp, to the 2e-3 the co-simulation keeps to it (above) and the four digits
    printed; its Python example's mu_bar is that example's own (the grip ramped over 10 ms), to the digits printed."""
    readme = re.sub(r"<!--.*?-->", "", (ROOT / "README.md").read_text(), flags=re.S)  # the figures, not their markers
    text = " ".join(readme.split())
    default = float(re.search(r"last 20 % of the draw: ([0-9.]+) with the shipped friction table and the default", text)
                     .group(1))
    papers = float(re.search(r"\(([0-9.]+) with the paper's frictionless flakes", text).group(1))
    for stated, r in ((default, None), (papers, 0.0)):
        _, outs, _ = run_strip_draw(10e6, 0.035, ramp_time=0.02, **({} if r is None else {"flake_shear_ratio": r}))
        assert stated == pytest.approx(steady_mean(outs), rel=2e-3, abs=5e-5), (stated, r)
    example = float(re.search(r"^mu_bar = ([0-9.]+)$", readme, re.M).group(1))  # what the Python example prints
    assert example == default
    from tribocosim import DEFAULT_TABLE, StripDrawModel, StripDrawParameters, make_friction_law, read_table

    p = StripDrawParameters()
    model = StripDrawModel(p, make_friction_law(p, read_table(DEFAULT_TABLE)))
    mu = [model.step(1e-3, {"normal_force": 12250.0, "grip_velocity": 0.08 * min(1.0, (k + 1) / 10)})["pull_force"]
          / (2 * 12250.0) for k in range(1750)]
    assert example == pytest.approx(np.mean(mu[-350:]), abs=5e-5)
