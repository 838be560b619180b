"""The shipped scenes (models/scenes) through the master with the real FMUs: the paper's trends,
the equalities of the coupled rig, the sweep and multi-pass machinery, and bad input.

Cheap settings (a 50 mm draw on a 100-element bar, 1 ms communication step) keep the runs short;
the trends are those of the paper (Sec. 2.1, 7; Fig. 2, 17-19): mu_bar falls with P_N and with pad
length; more debris sticking to the tool (zeta) and more wear (K) lower it, saturating at large K
(beta at its cap under the whole pad); a second and a third pass over the same strip lower it.
Sweeps run in parallel processes (cosim.apps.scene_sweep), every case written to its own folder.
"""

from __future__ import annotations

import json
import textwrap
import tomllib
from pathlib import Path

import numpy as np
import pytest

from tribocosim.errors import SceneError
from tribocosim.paths import DEFAULT_TABLE
from tribocosim.components.stripdraw.table import read_table
from tribocosim.cosim.api import run
from tribocosim.cli import main as tribocosim
from tribocosim.cosim.studies.stripdraw_experiment import steady_ratio
from tribocosim.cosim.scene.validate import load_scene
from tribocosim.cosim.apps.scene_sweep import load_sweep, run_sweep

SCENES = Path(__file__).resolve().parents[2] / "models" / "scenes"
DEMO = SCENES / "demo.toml"
DRAW = 0.05  # m
HOLD = tomllib.loads(DEMO.read_text())["fmus"]["drive"]["parameters"]["start_time"]  # s: the press closes first
CHEAP = {
    "fmus.strip.parameters.n_elements": 100,
    "fmus.strip.parameters.draw_length": DRAW,
    "experiment.stop": HOLD + DRAW / 0.08 + 0.01,
    "experiment.step": 1e-3,
}


def cheap_sweep(folder: Path, name: str, body: str) -> Path:
    """A sweep file over the shipped demo scene with the cheap settings."""
    sets = "\n".join(f'"{k}" = {v!r}' for k, v in CHEAP.items())
    text = textwrap.dedent(body).replace("[sweep.set]", f"[sweep.set]\n{sets}")
    path = folder / name
    path.write_text(f'[sweep]\nscene = "{DEMO}"\n' + text, encoding="utf-8")
    return path


def by(rows, key, **where):
    """{row[key]: row['mu_bar']} over the rows matching ``where``."""
    return {r[key]: r["mu_bar"] for r in rows if all(r[k] == v for k, v in where.items())}


@pytest.fixture(scope="module")
def demo_run():
    """The demo scene at the cheap settings (Jacobi, 1 ms)."""
    return run(load_scene(DEMO, CHEAP), write=False)


def test_shipped_scenes_and_sweeps_are_valid():
    for path in sorted(SCENES.glob("*.toml")):
        doc = tomllib.loads(path.read_text())
        if "sweep" in doc:
            sweep = load_sweep(path)
            assert sweep.scene.is_file() and sweep.cases(), path.name
        else:
            load_scene(path)  # raises SceneError on any problem
    names = {p.stem for p in SCENES.glob("*.toml")}
    assert {"demo", "pressure_sweep", "multipass", "zeta_sweep", "archard_sweep", "stiff_drive"} <= names


def test_pull_force_over_twice_the_normal_force_is_the_strips_mu(demo_run):
    r = demo_run
    ratio = steady_ratio(r.time, r["strip.pull_force"], r["press.normal_force"])
    t = r.time
    steady = t >= t[-1] - 0.2 * (t[-1] - t[0])
    mu_mean = float(np.mean(r["strip.mu_mean"][steady]))
    # Eq. 1 against Eq. 28: the grip reaction equals the friction force in (quasi-)steady sliding
    np.testing.assert_allclose(ratio, mu_mean, rtol=2e-3, err_msg="pull_force / (2 F_N) vs the strip's mu_mean")
    # between the table's fully covered (beta_threshold) and particle-free values at the demo's
    # 10 MPa and pulling speed (the scene's strip uses the shipped table)
    table = read_table(DEFAULT_TABLE)
    lo, hi = table.interpolate(10e6, 0.08, np.array([table.beta_threshold, 0.0]), "error")[0]
    assert lo < ratio < hi, f"mu_bar {ratio} outside the table's range [{lo}, {hi}] at 10 MPa"


def test_press_holds_its_setpoint_and_the_drive_reaches_its_velocity(demo_run):
    r = demo_run
    t = r.time
    start = HOLD  # the drive's start_time: the strip is held while the press closes and settles
    held, steady = t <= start - 0.01, t >= start + 0.3
    assert np.all(r["drive.grip_velocity"][held] == 0.0) and np.all(r["drive.grip_position"][held] == 0.0)
    fn, fset = r["press.normal_force"][t >= start], r["press.force_reference"][t >= start]
    assert np.all(np.abs(fn - fset) <= 0.01 * fset), f"press off by {np.max(np.abs(fn / fset - 1)):.2%}"
    assert fset[-1] == 12250.0
    v, vset = r["drive.grip_velocity"][steady], r["drive.velocity_reference"][steady]
    assert vset[-1] == 0.08 and np.all(np.abs(v - vset) <= 0.01 * vset), f"drive off by {np.max(np.abs(v / vset - 1)):.2%}"
    # the machine pulled the strip through: the grip travelled the draw (+ the ramp's lag)
    assert r["drive.grip_position"][-1] == pytest.approx(0.08 * (t[-1] - start - 0.01), rel=0.01)


def test_mu_bar_falls_with_pressure_and_pad_length(tmp_path):
    path = cheap_sweep(tmp_path, "p.toml", """
        workers = 2
        [sweep.variables]
        tool_length = [0.035, 0.07]
        pressure_mpa = [2, 10, 20]
        [sweep.set]
        "fmus.strip.parameters.tool_length" = { expr = "tool_length" }
        "fmus.press.parameters.force_setpoint" = { expr = "pressure_mpa * 1e6 * tool_length * 0.035" }
        [sweep.summary]
        mu_bar = { mean = "strip.pull_force / (2 * press.normal_force)", last = 0.2 }
        """)
    res = run_sweep(path, tmp_path / "out")
    for length in (0.035, 0.07):
        mu = by(res.rows, "pressure_mpa", tool_length=length)
        assert mu[2] > mu[10] > mu[20], f"pad {length}: {mu}"
    for p in (2, 10, 20):
        mu = by(res.rows, "tool_length", pressure_mpa=p)
        assert mu[0.035] > mu[0.07], f"{p} MPa: {mu}"
    # every case written to its own folder, the table in sweep.csv; a second call reuses them
    cases = sorted((tmp_path / "out" / "cases").iterdir())
    assert len(cases) == 6 and all((c / "summary.json").is_file() and (c / "pass-1" / "demo.csv").is_file()
                                   for c in cases)
    assert res.csv_path.read_text().count("\n") == 7
    stamp = [(c / "summary.json").stat().st_mtime_ns for c in cases]
    again = run_sweep(path, tmp_path / "out", workers=1)
    assert [(c / "summary.json").stat().st_mtime_ns for c in cases] == stamp, "finished cases are not run again"
    assert [r["mu_bar"] for r in again.rows] == [r["mu_bar"] for r in res.rows]


def test_zeta_and_archard_k_lower_mu_bar_with_saturation_at_large_k(tmp_path):
    zeta = cheap_sweep(tmp_path, "zeta.toml", """
        workers = 2
        [sweep.variables]
        zeta = [0.0, 0.5, 1.0]
        [sweep.set]
        "fmus.strip.parameters.zeta" = { expr = "zeta" }
        [sweep.summary]
        mu_bar = { mean = "strip.mu_mean", last = 0.2 }
        """)
    mu = by(run_sweep(zeta, tmp_path / "zeta").rows, "zeta")
    assert mu[0.0] > mu[0.5] > mu[1.0], mu
    k = cheap_sweep(tmp_path, "k.toml", """
        workers = 2
        [sweep.variables]
        archard_k = [1e-5, 1e-4, 1e-2, 1e-1]
        [sweep.set]
        "fmus.strip.parameters.archard_k" = { expr = "archard_k" }
        "fmus.press.parameters.force_setpoint" = 36750.0
        [sweep.summary]
        mu_bar = { mean = "strip.mu_mean", last = 0.2 }
        beta = { final = "strip.beta_mean" }
        """)
    res = run_sweep(k, tmp_path / "k")
    mu = by(res.rows, "archard_k")
    assert mu[1e-5] > mu[1e-4] > mu[1e-2], mu
    # saturated: the last decade of K moves mu by < 2 % of the drop from the smallest K (beta at its cap,
    # where A_p nearly reaches A_c and mu itself is small)
    assert abs(mu[1e-1] - mu[1e-2]) < 0.02 * (mu[1e-5] - mu[1e-2]), f"no saturation at large K: {mu}"
    beta = {r["archard_k"]: r["beta"] for r in res.rows}
    assert beta[1e-1] == pytest.approx(beta[1e-2], rel=0.02) and beta[1e-1] > 0.2, f"beta at the cap: {beta}"


def test_each_later_pass_has_lower_mu_bar(tmp_path):
    path = cheap_sweep(tmp_path, "passes.toml", """
        passes = 3
        field_instance = "strip"
        field_interval = 0.05
        [sweep.set]
        [sweep.summary]
        mu_bar = { mean = "strip.pull_force / (2 * press.normal_force)", last = 0.2 }
        beta_start = { mean = "strip.beta_max", last = 1.0 }
        """)
    rows = run_sweep(path, tmp_path / "out").rows
    mu = [r["mu_bar"] for r in rows]
    assert [r["pass"] for r in rows] == [1, 2, 3]
    assert mu[0] > mu[1] > mu[2], f"mu_bar per pass: {mu}"
    # pass k + 1 really started from what pass k left: its field file's first row is pass k's last
    folder = tmp_path / "out" / "cases" / "case-000"
    from tribocosim.components.native.resource_io.field_file import read_fields

    for k in (1, 2):
        a, b = read_fields(folder / f"pass-{k}.field.csv"), read_fields(folder / f"pass-{k + 1}.field.csv")
        np.testing.assert_array_equal(b["beta"][0], a["beta"][-1], err_msg=f"hand-over {k} -> {k + 1}")


BAD = {
    "fmus.drive.parameters.drive_stiffness": (-5e7, "is out of range; allowed: [1, 1e+13] N/m"),
    "fmus.press.parameters.force_setpoint": (150e3, "outside the friction table's pressure axis"),
    "fmus.strip.parameters.friction_model": ("tabel", "is not allowed; choose one of table"),
    "fmus.press.parameters.setpoint_table": ("0 0; 0.1", "is malformed"),
    "fmus.strip.parameters.beta_initial": (1.5, "is out of range; allowed: [0, 1]"),
}


def test_impossible_parameters_stop_before_running_naming_scene_instance_and_parameter(tmp_path, capsys):
    out = tmp_path / "out"
    args = ["run", str(DEMO), "--out", str(out), "--quiet"]
    for key, (value, _) in BAD.items():
        args += ["--set", f"{key}={json.dumps(value)}"]
    assert tribocosim(args) == 2
    err = capsys.readouterr().err
    assert f"{len(BAD)} problems in scene {DEMO}" in err, err
    for key, (_, message) in BAD.items():
        line = next((ln for ln in err.splitlines() if f"{DEMO}: {key}: " in ln), None)
        assert line is not None and message in line, f"{key}: {err}"
    assert not out.exists(), "nothing ran, nothing was written"


def test_initial_debris_above_the_tables_cap_is_refused(tmp_path):
    from tribocosim.components.stripdraw import StripDrawParameters, closed_form_table, write_table

    closed = tmp_path / "closed.npz"
    table = closed_form_table(StripDrawParameters())
    write_table(closed, table)
    cap = table.beta_threshold  # Eq. 24 with the closed form's alpha: below 1
    over = {"fmus.strip.parameters.table_file": str(closed),
            "fmus.strip.parameters.beta_initial": min(1.0, 1.5 * cap)}
    with pytest.raises(SceneError, match=r"fmus.strip.parameters.beta_initial: beta_initial = .* exceeds the cap of beta"):
        load_scene(DEMO, over)
    load_scene(DEMO, {**over, "fmus.strip.parameters.beta_initial": 0.5 * cap})


def test_drive_faster_than_the_table_covers_is_refused(tmp_path):
    from tribocosim.components.stripdraw import StripDrawParameters, closed_form_table, write_table

    small = tmp_path / "small.npz"
    write_table(small, closed_form_table(StripDrawParameters(), velocity=np.linspace(0.0, 1.0, 5)))
    over = {"fmus.strip.parameters.table_file": str(small), "fmus.drive.parameters.velocity_setpoint": 2.0}
    with pytest.raises(SceneError, match=r"fmus.drive.parameters.velocity_setpoint: velocity_setpoint = 2 m/s is "
                                         r"above the friction table's velocity axis \(up to 1 m/s\)"):
        load_scene(DEMO, over)
    load_scene(DEMO, {**over, "fmus.drive.parameters.velocity_setpoint": 0.5})


@pytest.mark.parametrize("key, value, message", [
    ("fmus.drive.parameters.velocity_setpoint", -0.3, "velocity_setpoint = -0.3 m/s is below 0 m/s, the least "
     "strip.grip_velocity the model is built for (the grip pulls the strip"),
    ("fmus.drive.parameters.velocity_setpoint", -0.08, "velocity_setpoint = -0.08 m/s is below 0 m/s"),
])
def test_a_set_point_outside_the_range_the_input_is_built_for_is_named(key, value, message):
    """The drive runs either way (its declared range is [-10, 10] m/s), but the strip it is connected to is pulled:
    the scene check matches the drive's set-point, with its sign, against the range the strip's input port
    declares (Port.low), and names the set-point's parameter."""
    with pytest.raises(SceneError) as exc:
        load_scene(DEMO, {key: value})
    assert [p.key for p in exc.value.problems] == [key], exc.value
    assert message in exc.value.problems[0].message, exc.value
    load_scene(DEMO, {key: 0.5})


def test_every_declared_port_bound_is_a_number_or_a_parameter():
    from tribocosim.components import registry

    for comp in registry.components().values():
        for port in (*comp.inputs, *comp.outputs):
            low, high = comp.bounds(port, {})
            assert low is None or high is None or low < high, (comp.name, port.name)
            assert (low, high) == (None, None) or port.why, f"{comp.name}.{port.name}: say why the range"


def test_sweep_file_problems_are_reported_at_once(tmp_path):
    path = tmp_path / "bad_sweep.toml"
    path.write_text(textwrap.dedent(f"""
        [sweep]
        scene = "{DEMO}"
        passes = 0
        [sweep.variables]
        p = [1, 2]
        [sweep.set]
        "fmus.press.parameters.force_setpoint" = {{ expr = "q * 1e6" }}
        "fmus.strip.parameters.zeta" = {{ expr = "__import__('os')" }}
        [sweep.summary]
        mu_bar = {{ average = "strip.mu_mean" }}
        """))
    with pytest.raises(SceneError) as exc:
        load_sweep(path)
    text = str(exc.value)
    for key in ("sweep.passes", "sweep.set.fmus.press.parameters.force_setpoint", "sweep.set.fmus.strip.parameters.zeta",
                "sweep.summary.mu_bar"):
        assert f"{path}: {key}:" in text, text
    assert "unknown variables ['q']" in text


def test_stiff_drive_needs_a_small_step_or_the_iterative_scheme():
    """models/scenes/stiff_drive.toml: the strip sticks (creep draw), its free length is a 2e8 N/m
    spring on a 20 kg grip through the coupling. Jacobi at 1 ms rings at the friction limit;
    Jacobi at 50 us and the iterative scheme at 1 ms give the smooth build-up of the pull force."""
    scene = SCENES / "stiff_drive.toml"
    creep = tomllib.loads(scene.read_text())["fmus"]["drive"]["parameters"]["start_time"]  # after the press closes
    small = run(load_scene(scene, {"experiment.step": 5e-5}), write=False)
    pull = small["strip.pull_force"]
    assert np.all(pull[small.time <= creep] == 0.0), "nothing moves while the press closes"
    assert np.all(np.diff(pull[small.time > creep + 0.05]) > 0) and 150 < pull[-1] < 300, "smooth build-up while sticking"
    jac = run(load_scene(scene), write=False)
    assert np.max(np.abs(jac["strip.pull_force"])) > 10 * pull[-1], "Jacobi at 1 ms should ring (unstable loop)"
    assert np.min(jac["drive.grip_velocity"]) < -0.01, "... with the grip reversing"
    it = run(load_scene(scene, {"master.algorithm": "iterative"}), write=False)
    np.testing.assert_allclose(it["strip.pull_force"][-1], pull[-1], rtol=0.1, err_msg="iterative at 1 ms")
    ref = np.interp(it.time, small.time, pull)
    assert np.max(np.abs(it["strip.pull_force"] - ref)) < 0.1 * pull[-1]


def test_a_finished_case_is_reused_only_while_its_table_and_fmus_are_unchanged(tmp_path):
    """The case key covers the bytes of the files the scene's parameters name (here a friction
    table) and of the FMUs: a changed table runs the case again. The changed table holds mu alone (format version 1,
    mu of frictionless flakes), so the sweep runs the paper's model (flake_shear_ratio = 0)."""
    from tribocosim.paths import DEFAULT_TABLE
    from tribocosim.components.stripdraw.table import read_table, write_table

    table = tmp_path / "my_table.npz"
    write_table(table, read_table(DEFAULT_TABLE))
    path = cheap_sweep(tmp_path, "t.toml", f"""
        workers = 1
        [sweep.variables]
        pressure_mpa = [10]
        [sweep.set]
        "fmus.strip.parameters.table_file" = "{table}"
        "fmus.strip.parameters.flake_shear_ratio" = 0.0
        [sweep.summary]
        mu_bar = {{ mean = "strip.pull_force / (2 * press.normal_force)", last = 0.2 }}
        """)
    first = run_sweep(path, tmp_path / "out")
    summary = tmp_path / "out" / "cases" / "case-000" / "summary.json"
    stamp = summary.stat().st_mtime_ns
    run_sweep(path, tmp_path / "out")
    assert summary.stat().st_mtime_ns == stamp, "unchanged: reused"
    t = read_table(table)
    write_table(table, type(t)(t.pressure, t.velocity, t.beta, 0.5 * t.mu, t.metadata))
    second = run_sweep(path, tmp_path / "out")
    assert summary.stat().st_mtime_ns != stamp, "a changed table must run the case again"
    assert second.rows[0]["mu_bar"] == pytest.approx(0.5 * first.rows[0]["mu_bar"], rel=0.05)


def test_a_scene_is_read_once_and_each_component_value_checked_once(tmp_path, monkeypatch):
    """``tribocosim run``: one read of the scene file's document (parsed once per content,
    :mod:`tribocosim.cosim.scene.documents`), and one range check of ``tool_length`` in Python (the component
    declaration's; the model description's min/max derive from it and are not checked again)."""
    from tribocosim.components import params
    from tribocosim.cosim.scene import schema

    tribocosim(["run", str(DEMO), "--out", str(tmp_path / "warm"), "--quiet", "--set", "experiment.stop=0.01"])
    reads, checked = [], []
    read_toml, check_field = schema.read_toml, params.check_field
    monkeypatch.setattr(schema, "read_toml", lambda path: (reads.append(Path(path)), read_toml(path))[1])
    monkeypatch.setattr(params, "check_field", lambda f, value: (checked.append(f.name), check_field(f, value))[1])
    assert tribocosim(["run", str(DEMO), "--out", str(tmp_path / "out"), "--quiet",
                       "--set", "experiment.stop=0.01"]) == 0
    assert [p.resolve() for p in reads] == [DEMO.resolve()], "the scene file is read once"
    assert checked.count("tool_length") == 1, checked


def test_the_variant_key_accepts_native_and_refuses_the_rest(tmp_path):
    load_scene(DEMO, {**CHEAP, "fmus.strip.variant": "native"})  # scenes of earlier versions keep running
    with pytest.raises(SceneError, match="fmus.strip.variant: 'python' is not allowed: the project builds the FMUs of "
                                         "its components in C only"):
        load_scene(DEMO, {**CHEAP, "fmus.strip.variant": "python"})


RINGING = """
workers = 1
[sweep.variables]
tool_length = [0.035, 0.14]
pressure_mpa = [10, 30]
[sweep.set]
"experiment.step" = 2e-3
"fmus.strip.parameters.tool_length" = { expr = "tool_length" }
"fmus.press.parameters.force_setpoint" = { expr = "pressure_mpa * 1e6 * tool_length * 0.035" }
[sweep.summary]
mu_bar = { mean = "strip.pull_force / (2 * press.normal_force)", last = 0.2 }
[sweep.plot]
x = "pressure_mpa"
y = "mu_bar"
series = "tool_length"
"""


def test_a_sweep_counts_each_runs_warnings_and_clamped_lookups_and_marks_them(tmp_path, capsys, monkeypatch):
    """At 2 ms the Jacobi coupling of the demo rig rings where the strip sticks under the long pad: the grip moves
    back (the strip FMU warns) and, at 30 MPa on the 140 mm pad, the friction table is read outside its axes. The
    35 mm pad at 10 MPa runs clean. sweep.csv, sweep.json and the plot say which run is which, as each run's own
    JSON counts it."""
    from tribocosim.cosim.studies import plotting

    sweep = tmp_path / "ringing.toml"
    sweep.write_text(f'[sweep]\nscene = "{DEMO}"\n' + RINGING, encoding="utf-8")
    figures = []
    save = plotting._save
    monkeypatch.setattr(plotting, "_save", lambda fig, path, **kw: (figures.append(fig), save(fig, path, **kw))[1])
    assert tribocosim(["run", str(sweep), "--out", str(tmp_path / "out"), "--plot", "--quiet"]) == 0
    out = tmp_path / "out"
    header, *lines = (out / "sweep.csv").read_text().splitlines()
    names = [n.strip('"') for n in header.split(",")]
    assert names[-3:] == ["warnings", "strip.table_clamp_count", "wall_time"]
    rows = [dict(zip(names, map(float, line.split(",")))) for line in lines]
    for i, row in enumerate(rows):  # each count is the run's own
        meta = json.loads((out / "cases" / f"case-{i:03d}" / "pass-1" / "demo.json").read_text())
        assert row["warnings"] == sum(meta["fmu_warnings"].values())
        assert row["strip.table_clamp_count"] == meta["end_checks"]["strip.table_clamp_count"]
    clean = [r for r in rows if r["warnings"] == 0 and r["strip.table_clamp_count"] == 0]
    assert [(r["tool_length"], r["pressure_mpa"]) for r in clean] == [(0.035, 10)], rows
    long_30 = next(r for r in rows if (r["tool_length"], r["pressure_mpa"]) == (0.14, 30))
    assert long_30["warnings"] > 0 and long_30["strip.table_clamp_count"] > 0
    assert all(r["strip.table_clamp_count"] == 0 for r in rows if r is not long_30)
    summary = json.loads((out / "sweep.json").read_text())
    assert summary["runs_with_warnings_or_clamps"] == 3
    assert summary["counts"] == {"warnings": sum(r["warnings"] for r in rows),
                                 "strip.table_clamp_count": long_30["strip.table_clamp_count"]}
    err = capsys.readouterr().err
    assert "warning:  3 of 4 runs warned or read the friction table outside its axes" in err
    crosses = [line for line in figures[0].axes[0].get_lines() if line.get_marker() == "x" and len(line.get_xdata())]
    assert len(crosses) == 1 and sorted(zip(crosses[0].get_xdata(), crosses[0].get_ydata())) == sorted(
        (r["pressure_mpa"], r["mu_bar"]) for r in rows if r not in clean), "the plot crosses exactly the warned runs"


def test_the_guides_sweep_example_runs_without_warnings_or_clamped_lookups(tmp_path):
    """docs/scene-format.md's sweep file, as written, over the demo scene beside it."""
    import re
    import shutil

    guide = (Path(__file__).resolve().parents[2] / "docs" / "scene-format.md").read_text(encoding="utf-8")
    example = re.search(r"```toml\n(\[sweep\].*?)```", guide, re.S).group(1)
    shutil.copy(DEMO, tmp_path / "demo.toml")
    (tmp_path / "example.toml").write_text(example, encoding="utf-8")
    result = run_sweep(tmp_path / "example.toml", tmp_path / "out", workers=2)
    assert len(result.rows) == 12 and result.counts == ["warnings", "strip.table_clamp_count"]
    assert result.marked() == [], [r for r in result.marked()]


def test_a_relative_table_file_is_found_beside_the_scene_then_among_the_packaged_tables(tmp_path):
    """A table next to the scene (its friction halved) is the one the run reads; a packaged table's name finds it in
    models/; the bundled default stays the FMU's own unless a file of its name lies beside the scene; a name found
    nowhere is one problem naming both places. The halved table holds mu alone (format version 1, mu of frictionless
    flakes): the runs are the paper's model (flake_shear_ratio = 0)."""
    import shutil

    from tribocosim.paths import MODELS_DIR

    scene = tmp_path / "scene.toml"
    shutil.copy(DEMO, scene)
    t = read_table(DEFAULT_TABLE)
    from tribocosim.components.stripdraw.table import write_table

    write_table(tmp_path / "halved.npz", type(t)(t.pressure, t.velocity, t.beta, 0.5 * t.mu, t.metadata))

    paper = {**CHEAP, "fmus.strip.parameters.flake_shear_ratio": 0.0}

    def table(value):
        plan = load_scene(scene, {**paper, "fmus.strip.parameters.table_file": value})
        return plan, plan.scene.fmus["strip"].parameters["table_file"]

    plan, found = table("halved.npz")
    assert found == str(tmp_path / "halved.npz")
    halved = run(plan, write=False)
    full = run(load_scene(scene, paper), write=False)
    ratio = halved["strip.mu_mean"][-1] / full["strip.mu_mean"][-1]
    assert ratio == pytest.approx(0.5, rel=0.05), "the table beside the scene is the one read"
    assert table("friction_table_128um.npz")[1] == str((MODELS_DIR / "friction_table_128um.npz").resolve())
    assert table("friction_table.npz")[1] == "friction_table.npz", "the bundled table: the FMU's own"
    shutil.copy(tmp_path / "halved.npz", tmp_path / "friction_table.npz")
    assert table("friction_table.npz")[1] == str(tmp_path / "friction_table.npz"), "beside the scene first"
    with pytest.raises(SceneError) as info:
        table("missing.npz")
    assert len(info.value.problems) == 1
    message = str(info.value.problems[0])
    assert "fmus.strip.parameters.table_file: file 'missing.npz' not found" in message
    assert str(tmp_path / "missing.npz") in message and str(MODELS_DIR / "missing.npz") in message


def test_results_and_sweeps_carry_the_units_the_fmus_declare(demo_run):
    """The plots label axes and legends with units: a run records each column's unit from its FMU's model description,
    and a sweep its variables set as they are to one parameter and its summaries of one recorded variable (the
    pressure sweep: the pad length in m; mu_bar, an expression of two outputs, none)."""
    from tribocosim.cosim.apps.scene_sweep import column_units
    from tribocosim.cosim.studies.plotting import labelled
    from tribocosim.paths import scene_file

    units = demo_run.metadata["outputs"]["units"]
    assert units["time"] == "s" and units["strip.pull_force"] == "N" and units["drive.grip_velocity"] == "m/s"
    assert labelled("strip.pull_force", "N") == "strip.pull_force [N]" and labelled("strip.mu_mean", "1") == \
        "strip.mu_mean"
    sweep = load_sweep(scene_file("pressure_sweep"))
    case = sweep.cases()[0]
    plan = load_scene(sweep.scene, case.overrides)
    got = column_units(sweep, plan)
    assert got["tool_length"] == "m" and "mu_bar" not in got and "pressure_mpa" not in got, got
    assert got["beta_end"] == units["strip.beta_mean"]
