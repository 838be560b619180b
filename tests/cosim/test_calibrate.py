"""``tribocosim calibrate``: the fit recovers a factor the model itself generated, and bad data are named."""

from __future__ import annotations

import numpy as np
import pytest

from tribocosim.errors import ParameterError
from tribocosim.components.stripdraw.friction import closed_form_table
from tribocosim.components.stripdraw.parameters import StripDrawParameters
from tribocosim.components.stripdraw.table import read_table, write_table
from tribocosim.cosim.apps.calibrate import main, read_measurements
from tribocosim.cosim.apps.stripdraw_experiment import Point, run_points

#: a coarse strip (fast) with enough debris for a visible effect; Eq. 23 with alpha = 40
FAST = {"n_elements": 60, "draw_length": 0.02, "archard_k": 5e-4, "contact_area": "eq8"}


@pytest.fixture(scope="module")
def eq23_table(tmp_path_factory):
    path = tmp_path_factory.mktemp("cal") / "eq23.npz"
    write_table(path, closed_form_table(StripDrawParameters(alpha_b=40.0)))
    return path


def _write(path, rows, header="pressure,tool_length,passes,mu_bar,mu_bar_std"):
    path.write_text(header + "\n" + "\n".join(",".join(str(x) for x in r) for r in rows) + "\n")
    return path


def test_calibration_recovers_a_known_factor_within_its_standard_error(tmp_path, eq23_table, capsys):
    true_scale, sigma = 0.6, 2e-4
    points = [(5e6, 0.035, 1), (20e6, 0.035, 1), (20e6, 0.07, 1), (10e6, 0.035, 2)]
    params = {**FAST, "table_file": str(eq23_table), "particle_area_scale": true_scale}
    clean = [m[-1] for m in run_points([Point(p, L, n, params) for p, L, n in points], workers=1)]
    noisy = np.array(clean) + np.random.default_rng(7).normal(0, sigma, len(clean))
    assert min(clean) < 0.14, "the debris must lower mu for the factor to be identifiable"
    data = _write(tmp_path / "data.csv", [(p, L, n, m, sigma) for (p, L, n), m in zip(points, noisy)])
    out = tmp_path / "calibrated.npz"
    args = ["--measured", str(data), "--out", str(out), "--table", str(eq23_table), "--contact-area", "eq8",
            "--workers", "1", *(x for k, v in FAST.items() if k != "contact_area" for x in ("--set", f"{k}={v}"))]
    assert main(args) == 0
    cal = read_table(out).metadata["strip_draw_calibration"]
    assert cal["converged"] is True and cal["iterations"] < 20
    fitted = cal["fitted"]["particle_area_scale"]
    print(f"\nfitted particle_area_scale {fitted['value']:.5f} +- {fitted['stderr']:.2g} (true {true_scale})")
    assert abs(fitted["value"] - true_scale) <= 3 * fitted["stderr"], fitted
    assert 0 < fitted["stderr"] < 0.1 * true_scale
    assert cal["contact_area"] == "eq8" and len(cal["points"]) == 4 and len(cal["data"]["sha256"]) == 64
    assert [p["measured"] for p in cal["points"]] == pytest.approx(list(noisy))
    # the written table is the calibrated model at particle_area_scale = 1
    np.testing.assert_allclose(read_table(out).particle_area, fitted["value"] * read_table(eq23_table).particle_area,
                               rtol=1e-12)
    assert "particle_area_scale = " in capsys.readouterr().out


@pytest.mark.parametrize("rows, header, message", [
    ([(1e6, 0.035, 1)], "pressure,tool_length,passes", "missing column(s) mu_bar"),
    ([(0.0, 0.035, 1, 0.1)], "pressure,tool_length,passes,mu_bar", "row 2, column pressure: 0.0 is not allowed"),
    ([(1e6, 0.035, 1, 0.1), (1e6, 0.035, 1, 1.5)], "pressure,tool_length,passes,mu_bar",
     "row 3, column mu_bar: 1.5 is not allowed; it must lie in (0, 1)"),
    ([(1e6, 0.035, 1.5, 0.1)], "pressure,tool_length,passes,mu_bar", "row 2, column passes: '1.5' is not an integer"),
    ([(1e6, "x", 1, 0.1)], "pressure,tool_length,passes,mu_bar", "row 2, column tool_length: 'x' is not a number"),
])
def test_bad_data_are_named_by_row_and_column(tmp_path, rows, header, message):
    path = _write(tmp_path / "bad.csv", rows, header)
    with pytest.raises(ParameterError) as exc:
        read_measurements(path)
    assert message in str(exc.value) and str(path) in str(exc.value)


def test_an_unconverged_fit_says_so_exits_1_and_writes_nothing_unless_asked(tmp_path, eq23_table, capsys):
    """One Gauss-Newton iteration from s = 1 cannot reach s = 0.6: the command names the fit as unconverged, exits
    with 1 and writes no table; --keep-unconverged writes the last iterate, marked as such, and exits with 0."""
    points = [(5e6, 0.035, 1), (20e6, 0.035, 1)]
    params = {**FAST, "table_file": str(eq23_table), "particle_area_scale": 0.6}
    clean = [m[-1] for m in run_points([Point(p, L, n, params) for p, L, n in points], workers=1)]
    data = _write(tmp_path / "data.csv", [(p, L, n, m, 1e-4) for (p, L, n), m in zip(points, clean)])
    out = tmp_path / "calibrated.npz"
    args = ["--measured", str(data), "--out", str(out), "--table", str(eq23_table), "--contact-area", "eq8",
            "--workers", "1", "--max-iterations", "1",
            *(x for k, v in FAST.items() if k != "contact_area" for x in ("--set", f"{k}={v}"))]
    assert main(args) == 1
    err = capsys.readouterr().err
    assert "the fit has not converged in 1 iterations" in err and "particle_area_scale = " in err, err
    assert "Nothing written" in err and not out.exists()
    assert main([*args, "--keep-unconverged"]) == 0
    captured = capsys.readouterr()
    assert "as asked (--keep-unconverged)" in captured.err and "NOT CONVERGED" in captured.out
    cal = read_table(out).metadata["strip_draw_calibration"]
    assert cal["converged"] is False and cal["iterations"] == 1
    assert abs(cal["last_change"]["particle_area_scale"]) > 1e-3, cal["last_change"]
