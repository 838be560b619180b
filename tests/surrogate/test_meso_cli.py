"""``tribocosim meso surface`` / ``contact`` / ``slide`` dispatch."""

import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tribocosim.surrogate import meso_cli
from tribocosim.surrogate.surfaces import rms_slope

CONTACT_KEYS = {"pressure", "contact_area_fraction", "mean_gap", "n_clusters",
                "mean_cluster_distance", "max_traction", "iterations", "residual", "converged",
                "wall_time_s"}
SIZE = 500e-6
Q0 = 2 * math.pi / SIZE


def _surface(tmp_path, n=64):
    out = tmp_path / "surf.npy"
    argv = ["surface", "--n", str(n), "--size", str(SIZE), "--hurst", "0.8",
            "--q-roll", str(2 * Q0), "--q-cut", str(16 * Q0), "--rms-slope", "0.34",
            "--seed", "1", "-o", str(out)]
    return out, argv


def test_surface_then_contact(tmp_path, capsys):
    out, argv = _surface(tmp_path)
    assert meso_cli.main(argv) == 0
    info = json.loads(capsys.readouterr().out)
    h = np.load(out)
    assert h.shape == (64, 64) and info["output"] == str(out)
    assert_allclose(rms_slope(h, SIZE), 0.34, rtol=1e-12, err_msg="--rms-slope not applied")
    assert_allclose(info["rms_slope_spectral"], 0.34, rtol=1e-12, err_msg="reported slope")
    rc = meso_cli.main(["contact", "--surface", str(out), "--size", str(SIZE), "--e-star", "55e9",
                        "--pressure", "10e6", "--pressure", "30e6", "--p-crit", "340e6", "--json"])
    lines = capsys.readouterr().out.strip().splitlines()
    assert rc == 0 and len(lines) == 2
    recs = [json.loads(line) for line in lines]
    for rec, p in zip(recs, (10e6, 30e6)):
        assert set(rec) == CONTACT_KEYS
        assert rec["pressure"] == p and rec["converged"] and rec["residual"] <= 1e-8
        assert rec["max_traction"] <= 340e6 and rec["n_clusters"] >= 1
        # saturated regime (E* h' / p_crit ~ 55): A_c/A0 close to p / p_crit from above
        assert p / 340e6 <= rec["contact_area_fraction"] < 1.2 * p / 340e6
    assert recs[1]["mean_gap"] < recs[0]["mean_gap"], "the gap closes with pressure"


def test_contact_table_and_bad_input(tmp_path, capsys):
    out, argv = _surface(tmp_path, n=32)
    meso_cli.main(argv)
    capsys.readouterr()
    assert meso_cli.main(["contact", "--surface", str(out), "--size", str(SIZE),
                          "--e-star", "55e9", "--pressure", "5e6"]) == 0
    assert "A_c/A0" in capsys.readouterr().out
    rc = meso_cli.main(["contact", "--surface", str(out), "--size", str(SIZE),
                        "--e-star", "55e9", "--pressure", "400e6", "--p-crit", "340e6"])
    assert rc == 2 and "p_crit" in capsys.readouterr().err
    bad = tmp_path / "bad.txt"
    bad.write_text("1 2 3\n4 5 6\n")
    rc = meso_cli.main(["contact", "--surface", str(bad), "--size", str(SIZE), "--e-star", "55e9",
                        "--pressure", "1e6"])
    assert rc == 2 and "bad.txt" in capsys.readouterr().err
    assert meso_cli.main(["nonsense"]) == 2


def test_slide_is_dispatched_lazily(monkeypatch, capsys):
    import importlib

    real = importlib.import_module

    def fake(name, *a, **k):
        if name == "tribocosim.surrogate.slide_cli":
            raise ImportError("no module")
        return real(name, *a, **k)

    monkeypatch.setattr(meso_cli.importlib, "import_module", fake)
    assert meso_cli.main(["slide", "--config", "x.toml"]) == 2
    assert "not available yet" in capsys.readouterr().err
    seen = {}

    class FakeSlideCli:
        @staticmethod
        def main(argv):
            seen["argv"] = argv
            return 0

    monkeypatch.setattr(meso_cli.importlib, "import_module", lambda name: FakeSlideCli)
    assert meso_cli.main(["slide", "--config", "x.toml"]) == 0
    assert seen["argv"] == ["--config", "x.toml"], "arguments passed through to slide_cli.main"


def test_console_script_end_to_end(tmp_path):
    exe = shutil.which("tribocosim", path=str(Path(sys.executable).parent))
    if exe is None:
        pytest.skip("tribocosim console script not installed")
    out = tmp_path / "s.npy"
    run = subprocess.run([exe, "meso", "surface", "--n", "32", "--size", "500e-6",
                          "--q-roll", str(2 * Q0), "--q-cut", str(8 * Q0), "--rms-height", "1e-6",
                          "-o", str(out)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    run = subprocess.run([exe, "meso", "contact", "--surface", str(out), "--size", "500e-6",
                          "--e-star", "55e9", "--pressure", "10e6", "--json"],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert set(json.loads(run.stdout)) == CONTACT_KEYS


def test_output_folders_and_os_errors_are_named_as_given(tmp_path, capsys):
    """-o naming a folder is refused as a folder (not written as DIR.npy); an OS error names the path the user gave,
    not a temporary name, in one line; meso slide's --out that is a file is refused before the slide."""
    _, argv = _surface(tmp_path)
    folder = tmp_path / "maps"
    folder.mkdir()
    cases = [([*argv[:-1], str(folder)], f"-o {folder}: {folder} is a folder"),
             ([*argv[:-1], str(tmp_path / "absent" / "s")], f"the folder {tmp_path / 'absent'} does not exist")]
    if Path("/proc").is_dir():
        cases.append(([*argv[:-1], "/proc/surf"], "cannot write /proc/surf.npy: "))
    for args, words in cases:
        assert meso_cli.main(args) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and words in err and ".partial" not in err, err
    assert list(folder.iterdir()) == [] and not (tmp_path / "maps.npy").exists()
    config = tmp_path / "slide.toml"
    config.write_text("n = 16\nsize = 64e-6\nwavelength_ratio = 0.25\nn_flakes = 1\nn_slide_steps = 2\n")
    blocker = tmp_path / "results"
    blocker.write_text("")
    assert meso_cli.main(["slide", "--config", str(config), "--out", str(blocker), "--quiet"]) == 2
    assert f"--out {blocker} is a file" in capsys.readouterr().err
    if Path("/proc").is_dir():
        assert meso_cli.main(["slide", "--config", str(config), "--out", "/proc/slide", "--quiet"]) == 2
        err = capsys.readouterr().err.strip()
        assert err.splitlines()[-1] == ("tribocosim meso slide: error: cannot write the results into /proc/slide: "
                                        "No such file or directory"), err
