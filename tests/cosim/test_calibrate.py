"""``tribocosim calibrate``: the fit recovers parameters the model itself generated (the scale of A_p from mu_bar,
the debris balance from the debris weighed after passes and pads, both at once), within their standard errors; it
says when the data cannot separate the parameters, fails when the data push a parameter against its bound, and
names bad data."""

from __future__ import annotations

import numpy as np
import pytest

from tribocosim.errors import ParameterError
from tribocosim.components.stripdraw.friction import closed_form_table
from tribocosim.components.stripdraw.parameters import StripDrawParameters
from tribocosim.components.stripdraw.table import read_table, write_table
from tribocosim.cosim.apps.calibrate import calibrate, main, read_measurements
from tribocosim.cosim.studies.stripdraw_experiment import Point, draw, run_points

#: a coarse strip (fast) with enough debris for a visible effect; Eq. 23 with alpha = 40
FAST = {"n_elements": 60, "draw_length": 0.02, "archard_k": 5e-4, "contact_area": "eq8"}


@pytest.fixture(scope="module")
def eq23_table(tmp_path_factory):
    """Eq. 23 tabulated up to beta = 1, beyond the cap of every scale the tests fit: no draw reads it clamped."""
    path = tmp_path_factory.mktemp("cal") / "eq23.npz"
    write_table(path, closed_form_table(StripDrawParameters(alpha_b=40.0), beta=np.linspace(0.0, 1.0, 41)))
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
    ([(1e6, 0.035, 1)], "pressure,tool_length,passes", "missing column(s) an observable (mu_bar, debris_g_m2, beta)"),
    ([(1e6, 0.035, 1, 0.1, 0.2)], "pressure,tool_length,passes,mu_bar,debris_g_m2",
     "row 2: mu_bar has no mu_bar_std; data that mix observables"),
    ([(1e6, 0.035, 1, "", "")], "pressure,tool_length,passes,mu_bar,beta", "row 2: no measured value"),
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
    assert "the fit failed (not converged)" in err and "the fit has not converged in 1 iterations" in err, err
    assert "particle_area_scale = " in err
    assert "Nothing written" in err and not out.exists()
    assert main([*args, "--keep-unconverged"]) == 0
    captured = capsys.readouterr()
    assert "as asked (--keep-unconverged)" in captured.err and "NOT CONVERGED" in captured.out
    cal = read_table(out).metadata["strip_draw_calibration"]
    assert cal["converged"] is False and cal["status"] == "not converged" and cal["iterations"] == 1
    assert abs(cal["last_change"]["particle_area_scale"]) > 1e-3, cal["last_change"]


def test_a_fit_held_at_its_bound_fails_names_the_bound_exits_1_and_writes_nothing(tmp_path, eq23_table, capsys):
    """A measured mu_bar of 0.5 above mu0 = 0.15: only s < 0 could raise mu above mu0, so s ends on its lower bound 0.
    That is a failed fit (exit 1, no table, the bound named), not a converged one with s = 0 +- 10."""
    data = _write(tmp_path / "data.csv", [(5e6, 0.035, 1, 0.5, 0.01), (20e6, 0.035, 1, 0.5, 0.01)])
    out = tmp_path / "calibrated.npz"
    args = ["--measured", str(data), "--out", str(out), "--table", str(eq23_table), "--contact-area", "eq8",
            "--workers", "1", *(x for k, v in FAST.items() if k != "contact_area" for x in ("--set", f"{k}={v}"))]
    assert main(args) == 1
    err = capsys.readouterr().err
    assert "the fit failed (at bound)" in err and "particle_area_scale = 0 is held at its lower bound" in err, err
    assert not out.exists()
    assert main([*args, "--keep-unconverged"]) == 0
    cal = read_table(out).metadata["strip_draw_calibration"]
    assert cal["status"] == "at bound" and cal["at_bound"] == {"particle_area_scale": "lower"}
    assert cal["fitted"]["particle_area_scale"] == {"value": 0.0, "stderr": None, "at_bound": "lower"}
    assert "(at its lower bound), AT BOUND" in capsys.readouterr().out


#: debris after passes 1-3 on the 35 mm pad and after one pass on the 70 mm pad, at 20 MPa
DEBRIS_POINTS = [(20e6, 0.035, 1), (20e6, 0.035, 2), (20e6, 0.035, 3), (20e6, 0.07, 1)]


def _generated(params, points, observables, rel_std, seed):
    """Rows (P, pad, passes, value, std, ...) of the strip-draw model at ``params``, with Gaussian noise of
    ``rel_std`` times each value."""
    rng = np.random.default_rng(seed)
    runs = {(p, L): draw(Point(p, L, max(n for q, M, n in points if (q, M) == (p, L)), params))
            for p, L, _ in points}
    rows = []
    for p, L, n in points:
        cells = []
        for name, key in observables:
            value = runs[(p, L)][n - 1][key]
            cells += [value * (1 + rel_std * rng.standard_normal()), rel_std * value]
        rows.append((p, L, n, *cells))
    return rows


def test_round_trip_of_the_debris_balance_from_debris_weighed_after_passes_and_pads(tmp_path, eq23_table):
    """K and the carried-over share that made the debris data (2e-4, 0.7; 1 % noise) come back from the start values
    (1e-4, 1) within three standard errors, and the data separate them (pass 1 sets K, the later passes the share)."""
    truth = {"archard_k": 2e-4, "debris_carry_over": 0.7}
    params = {**FAST, "table_file": str(eq23_table), **truth}
    rows = _generated(params, DEBRIS_POINTS, [("debris_g_m2", "debris_g_m2")], 0.01, seed=3)
    data = read_measurements(_write(tmp_path / "debris.csv", rows,
                                    "pressure,tool_length,passes,debris_g_m2,debris_g_m2_std"))
    start = {**params, "archard_k": 1e-4, "debris_carry_over": 1.0}
    f = calibrate(data, start, ("archard_k", "debris_carry_over"), workers=1)
    print(f"\nfitted {dict(zip(f.names, f.values))} +- {f.stderr} (truth {truth}); chi^2 {f.chi2:.3g} on {f.dof}")
    assert f.succeeded, f.status()
    for name, value, se in zip(f.names, f.values, f.stderr):
        assert abs(value - truth[name]) <= 3 * se and se < 0.1 * truth[name], (name, value, se)


@pytest.mark.slow
def test_round_trip_of_the_particle_area_and_the_debris_balance_at_once(tmp_path, eq23_table):
    """s, K and the carried-over share (0.6, 2e-4, 0.7) from mu_bar after passes 1-3 at 5 and 20 MPa and the debris
    weighed after them (0.5 % and 1 % noise), from the start (1, 1e-4, 1): within three standard errors each."""
    truth = {"particle_area_scale": 0.6, "archard_k": 2e-4, "debris_carry_over": 0.7}
    params = {**FAST, "table_file": str(eq23_table), **truth}
    points = [(p, 0.035, n) for p in (5e6, 20e6) for n in (1, 2, 3)]
    rows = _generated(params, points, [("mu_bar", "mu_bar")], 0.005, seed=4)
    rows = [r + d[3:] for r, d in zip(rows, _generated(params, points, [("debris_g_m2", "debris_g_m2")], 0.01,
                                                          seed=5))]
    data = read_measurements(_write(tmp_path / "both.csv", rows,
                                    "pressure,tool_length,passes,mu_bar,mu_bar_std,debris_g_m2,debris_g_m2_std"))
    f = calibrate(data, {**params, "particle_area_scale": 1.0, "archard_k": 1e-4, "debris_carry_over": 1.0},
                  tuple(truth), workers=2)
    print(f"\nfitted {dict(zip(f.names, f.values))} +- {f.stderr} (truth {truth}); chi^2 {f.chi2:.3g} on {f.dof}")
    assert f.succeeded, f.status()
    for name, value, se in zip(f.names, f.values, f.stderr):
        assert abs(value - truth[name]) <= 3 * se, (name, value, se)


def test_the_command_says_when_the_data_cannot_separate_the_parameters(tmp_path, eq23_table, capsys):
    """Debris after one pass at two pressures: the carried-over share acts only from the second pass on (its column of
    the Jacobian is zero). mu_bar after one pass with the closed form (Eq. 9 with Eq. 23): mu falls with s alpha beta
    and beta grows with K, so only s K is determined. The command names what it cannot separate, exits 1 and writes
    nothing."""
    params = {**FAST, "table_file": str(eq23_table)}
    sets = [x for k, v in FAST.items() if k != "contact_area" for x in ("--set", f"{k}={v}")]
    out = tmp_path / "calibrated.npz"
    rows = _generated(params, [(5e6, 0.035, 1), (20e6, 0.035, 1)], [("debris_g_m2", "debris_g_m2")], 0.01, seed=1)
    data = _write(tmp_path / "one_pass.csv", rows, "pressure,tool_length,passes,debris_g_m2,debris_g_m2_std")
    base = ["--out", str(out), "--table", str(eq23_table), "--contact-area", "eq8", "--workers", "1", *sets]
    assert main(["--measured", str(data), *base, "--fit", "archard_k", "debris_carry_over"]) == 1
    err = capsys.readouterr().err
    assert "(not separable)" in err and "the data do not determine the combination (debris_carry_over" in err, err
    rows = _generated(params, [(5e6, 0.035, 1), (20e6, 0.035, 1)], [("mu_bar", "mu_bar")], 0.002, seed=2)
    data = _write(tmp_path / "mu.csv", rows, "pressure,tool_length,passes,mu_bar,mu_bar_std")
    assert main(["--measured", str(data), *base, "--fit", "particle_area_scale", "archard_k"]) == 1
    err = capsys.readouterr().err
    assert "(not separable)" in err and ("particle_area_scale and archard_k" in err or "combination" in err), err
    assert not out.exists()


def test_help_names_the_format_versions_it_takes(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "format version 2 or later" in text and "debris_g_m2" in text and "archard_k" in text


#: mu_bar after passes 1-5 at 5, 20 and 30 MPa on the 35 mm pad
FIVE_PASSES = [(p, 0.035, n) for p in (5e6, 20e6, 30e6) for n in range(1, 6)]


def test_round_trip_of_the_flake_shear_ratio_and_the_scale_from_five_passes(tmp_path, eq23_table):
    """s and r (1.2, 0.3) from mu_bar after passes 1-5 at 5, 20 and 30 MPa (0.5 % noise), started at (1, the default
    r): the later passes reach the cap, where mu = r mu0, so the data separate r from s; each comes back within three
    standard errors, and so does (1 - r) s. With s held at its true value, r alone comes back too."""
    truth = {"particle_area_scale": 1.2, "flake_shear_ratio": 0.3}
    params = {**FAST, "table_file": str(eq23_table), **truth}
    rows = _generated(params, FIVE_PASSES, [("mu_bar", "mu_bar")], 0.005, seed=11)
    data = read_measurements(_write(tmp_path / "five.csv", rows))
    f = calibrate(data, {**params, "particle_area_scale": 1.0, "flake_shear_ratio": 0.2}, tuple(truth), workers=1)
    print(f"\nfitted {dict(zip(f.names, f.values))} +- {f.stderr} (truth {truth}); chi^2 {f.chi2:.3g} on {f.dof}; "
          f"(1 - r) s = {f.shear_scale}")
    assert f.succeeded, (f.status(), f.inseparable)
    for name, value, se in zip(f.names, f.values, f.stderr):
        assert abs(value - truth[name]) <= 3 * se and se < 0.05 * truth[name], (name, value, se)
    q = (1 - truth["flake_shear_ratio"]) * truth["particle_area_scale"]
    assert abs(f.shear_scale["value"] - q) <= 3 * f.shear_scale["stderr"], f.shear_scale
    alone = calibrate(data, {**params, "flake_shear_ratio": 0.2}, ("flake_shear_ratio",), workers=1)
    assert alone.succeeded and abs(alone.values[0] - 0.3) <= 3 * alone.stderr[0], (alone.values, alone.stderr)


def test_the_command_says_in_one_line_when_the_data_cannot_separate_r_from_s(tmp_path, eq23_table, capsys):
    """mu_bar after one pass at 2-4 MPa: the debris stays far below the cap, where mu depends on s and r only through
    (1 - r) s. Fitting both, the command says so in one line with that product (within three of its standard errors
    of the true one), exits 1 and writes nothing."""
    truth = {"particle_area_scale": 1.2, "flake_shear_ratio": 0.3}
    params = {**FAST, "table_file": str(eq23_table), **truth}
    rows = _generated(params, [(p, 0.035, 1) for p in (2e6, 3e6, 4e6)], [("mu_bar", "mu_bar")], 0.005, seed=12)
    data = _write(tmp_path / "one_pass.csv", rows)
    out = tmp_path / "calibrated.npz"
    sets = [x for k, v in FAST.items() if k != "contact_area" for x in ("--set", f"{k}={v}")]
    assert main(["--measured", str(data), "--out", str(out), "--table", str(eq23_table), "--contact-area", "eq8",
                 "--workers", "1", *sets, "--fit", "particle_area_scale", "flake_shear_ratio"]) == 1
    err = capsys.readouterr().err
    line = "the data determine only (1 - flake_shear_ratio) particle_area_scale = "
    assert "(not separable)" in err and err.count(line) == 1, err
    assert "cannot separate particle_area_scale and flake_shear_ratio" not in err, "one line, not two messages"
    value, stderr = (float(x) for x in err.split(line)[1].split(" (")[0].split(" +- "))
    assert abs(value - 0.7 * 1.2) <= 3 * stderr, (value, stderr)
    assert not out.exists()


@pytest.mark.slow
def test_round_trip_of_r_and_s_on_the_shipped_table_from_five_passes_and_the_debris_weighed(tmp_path):
    """The shipped table, 140 mm draws: s and r (1.28, 0.3) from mu_bar (0.5 % noise) and the debris weighed (1 %)
    after passes 1-5 at 20, 25 and 30 MPa, started at (1.5, 0.1), where the model's debris reaches the cap (below
    s = 1 / max A_p/A_c, about 1.14 here, no debris reaches it and only (1 - r) s is seen): within three standard
    errors each."""
    from tribocosim.paths import DEFAULT_TABLE

    truth = {"particle_area_scale": 1.28, "flake_shear_ratio": 0.3}
    params = {"table_file": str(DEFAULT_TABLE), **truth}
    points = [(p, 0.035, n) for p in (20e6, 25e6, 30e6) for n in range(1, 6)]
    rows = _generated(params, points, [("mu_bar", "mu_bar")], 0.005, seed=21)
    rows = [r + d[3:] for r, d in zip(rows, _generated(params, points, [("debris_g_m2", "debris_g_m2")], 0.01,
                                                          seed=22))]
    data = read_measurements(_write(tmp_path / "shipped.csv", rows,
                                    "pressure,tool_length,passes,mu_bar,mu_bar_std,debris_g_m2,debris_g_m2_std"))
    f = calibrate(data, {**params, "particle_area_scale": 1.5, "flake_shear_ratio": 0.1}, tuple(truth), workers=2)
    print(f"\nfitted {dict(zip(f.names, f.values))} +- {f.stderr} (truth {truth}); chi^2 {f.chi2:.3g} on {f.dof}")
    assert f.succeeded, (f.status(), f.inseparable)
    for name, value, se in zip(f.names, f.values, f.stderr):
        assert abs(value - truth[name]) <= 3 * se, (name, value, se)
