"""Tests of the slide configuration and of ``tribocosim meso slide`` (surrogate.slide_cli)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tribocosim.errors import ParameterError
from tribocosim.surrogate import slide_cli
from tribocosim.surrogate.slide_config import SlideConfig


def test_config_defaults_match_model_and_beta():
    c = SlideConfig()
    assert (c.n, c.size, c.e_star, c.p_crit, c.flake_thickness) == (256, 500e-6, 55e9, 340e6, 0.5e-6)
    assert c.steps == 2 * c.n, "the tool slides 2L by default"
    np.testing.assert_allclose(c.beta, 20 * np.pi * 6e-6**2 / 500e-6**2, rtol=1e-14,
                               err_msg="beta = N pi a^2 / L^2 (Eq. 10)")


@pytest.mark.parametrize("bad, match", [
    ({"flake_diameter": -1e-6}, "flake_diameter"),
    ({"flake_diameter": 300e-6}, "flake_diameter"),
    ({"flake_thickness": 20e-6}, "flake_thickness"),
    ({"v0": 0.0}, "v0"),
    ({"pressure": 400e6}, "pressure"),
    ({"n": 7}, "n = 7"),
    ({"n_flakes": 2.5}, "n_flakes"),
])
def test_config_rejects_bad_values_with_named_quantity(bad, match):
    with pytest.raises(ParameterError, match=match):
        SlideConfig(**bad)


def test_config_from_toml_and_unknown_keys(tmp_path):
    f = tmp_path / "run.toml"
    f.write_text("[slide]\nn = 64\npressure = 5e6\nflake_diameter = 6e-6\nwavelength_ratio = 0.1\n")
    c = SlideConfig.from_toml(f)
    assert (c.n, c.pressure, c.flake_diameter) == (64, 5e6, 6e-6)
    f.write_text("n = 64\npresure = 5e6\nspeed = 3\n")
    with pytest.raises(ParameterError, match=r"\['presure', 'speed'\]"):
        SlideConfig.from_toml(f)
    with pytest.raises(ParameterError, match="does not exist"):
        SlideConfig.from_toml(tmp_path / "missing.toml")


def test_cli_reports_bad_config_without_traceback(tmp_path, capsys):
    f = tmp_path / "run.toml"
    f.write_text("v0 = -3.0\n")
    assert slide_cli.main(["--config", str(f), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "v0 = -3.0" in err and "out of range" in err
    assert not (tmp_path / "o").exists(), "nothing is written for a failed run"




def test_cli_slide_writes_series_summary_and_plots(tmp_path, capsys):
    f = tmp_path / "run.toml"
    f.write_text("[slide]\nn = 64\nsize = 125e-6\nwavelength_ratio = 0.1\nn_flakes = 4\n"
                 "n_slide_steps = 4\nsnapshot_every = 2\npressure = 20e6\n")
    out = tmp_path / "out"
    assert slide_cli.main(["--config", str(f), "--out", str(out), "--plot", "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    with np.load(out / "slide.npz") as z:
        meta = json.loads(str(z["metadata"]))
        ap = z["particle_fraction"]
        assert len(ap) == 4 and np.all(np.isfinite(ap))
        assert "snap_2_pos" in z and "snap_4_sheet" in z and "snap_0_pos" in z
    assert meta["config"]["n"] == 64 and meta["units"]["slide_distance"] == "m"
    np.testing.assert_allclose(summary["mean_particle_fraction"], np.mean(ap), rtol=1e-12,
                               err_msg="<A_p>/A0 is the mean over the steps (Eq. 22)")
    assert (out / "flakes.png").stat().st_size > 0 and (out / "particle_area.png").exists()
