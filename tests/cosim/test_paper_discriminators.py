"""The discriminating predictions (tribocosim.cosim.reports.paper_discriminators): the separations on known numbers,
and on the real model with a table of known areas the coverage after one pass against the conservation of debris,
the start of mu(t) against the debris a few millimetres of slide can make, and the floor's bound on the 3-pass drop
against pressure."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tribocosim.components.stripdraw.table import write_table
from tribocosim.errors import RangeWarning
from tribocosim.cosim.reports import paper, paper_discriminators as pd, paper_physics as pp


def _option(mu2, mu3, five, coverage):
    return {"mu_bar_2": mu2, "mu_bar_3": mu3, "five": {"mu_bar": five}, "coverage": coverage}


def test_separations_take_the_most_telling_point_and_the_nearer_competitor():
    """Per record the largest max/min - 1 over its points, the smaller over the sink and the carry-over; five passes
    count passes 4-5 only; equal values separate nothing; sorted from the clearest."""
    n = len(pd.PRESSURES)
    predicted = {"options": {
        "default": _option([0.1] * n, [0.05] * n, [0.1, 0.06, 0.04, 0.030, 0.030], [0.1] * 5),
        "sink_35": _option([0.1] * n, [0.05] * (n - 1) + [0.075], [0.1, 0.07, 0.06, 0.060, 0.066], [0.05] * 5),
        "carry_0.5": _option([0.12] * n, [0.05] * n, [9.0, 9.0, 9.0, 0.045, 0.033], [0.1] * 5)}}
    five_25 = {"default": {"mu_bar": [1, 1, 1, 0.030, 0.030]}, "sink_35": {"mu_bar": [1, 1, 1, 0.033, 0.036]},
               "carry_0.5": {"mu_bar": [1, 1, 1, 0.036, 0.0345]}}
    seeded = {k: {"mu_bar": v, "seeded_g_m2": [0.0, 1.0]} for k, v in
              {"default": [0.09, 0.03], "sink_35": [0.09, 0.015], "carry_0.5": [0.09, 0.0]}.items()}
    seps = {s["record"]: s for s in pd.separations(predicted, five_25, seeded)}
    assert seps["fig2b"]["separation"] == pytest.approx(0.2) and seps["fig2b"]["nearer"] == "carry_0.5"
    assert seps["fig2b"]["by_option"]["sink_35"]["separation"] == pytest.approx(0.5)
    assert seps["five_10"]["separation"] == pytest.approx(0.5) and seps["five_10"]["nearer"] == "carry_0.5"
    assert seps["five_10"]["by_option"]["carry_0.5"]["at"] == "pass 4"  # passes 1-3 are not the record's own
    assert seps["five_25"]["separation"] == pytest.approx(0.2) and seps["five_25"]["nearer"] == "sink_35"
    assert seps["seeded"]["separation"] == pytest.approx(1.0) and math.isinf(
        seps["seeded"]["by_option"]["carry_0.5"]["separation"])
    assert seps["coverage"]["separation"] == 0.0
    order = [s["separation"] for s in pd.separations(predicted, five_25, seeded)]
    assert order == sorted(order, reverse=True)


SHARE = 3000.0 * 300e6 / 55e9  # A_p / A_c per unit beta in _table


@pytest.fixture(scope="module")
def predicted(tmp_path_factory, known_area_table):
    path = tmp_path_factory.mktemp("discriminators") / "t.npz"
    table = known_area_table
    write_table(path, table)
    runs = paper.Runs(workers=1)
    params = paper.config_params({"table_file": str(path)}, paper.Config("mesoscale", True))
    with pytest.warns(RangeWarning, match="flake_shear_ratio = 0 with mu0"):  # the paper's model passes the floor
        options = {o.name: pp.calibrated_predictions(runs, {**params, **o.parameters}, table, paper.calibrate)
                   for o in pp.OPTIONS if o.name in ("default", "paper", "sink_35")}
        return pd.predict(runs, options, params), options


def test_the_coverage_after_one_pass_is_the_debris_made_over_the_strip_that_passed(predicted):
    """Without a sink the debris is conserved: K P D L_T / (H h_p) over D + L_T of strip, whatever r; a sink
    leaves less."""
    d, _ = predicted
    want = [pd.coverage_without_sink(P * 1e6, 0.035, 1e-4, 0.8e9, 0.5e-6, 0.14) for P in pd.COVERAGE_PRESSURES]
    np.testing.assert_allclose(d["coverage_closed_form"], want, rtol=1e-12)
    for name in ("default", "paper"):
        np.testing.assert_allclose(d["options"][name]["coverage"], want, rtol=3e-3)
    assert all(c < 0.9 * w for c, w in zip(d["options"]["sink_35"]["coverage"], want))


def test_the_start_of_mu_t_is_near_mu0_at_every_pressure(predicted):
    """After a slide x the pad holds at most K P x / (H h_p) of debris per area and mu is linear in beta here, so
    mu >= mu0 (1 - (1 - r) s C K P x / (H h_p)) (and <= mu0) in the window 1-2 mm at every pressure, while mu_bar
    falls with pressure by far more than the start does."""
    d, options = predicted
    default = d["options"]["default"]
    s = options["default"]["scale"]
    window = pd.WINDOWS.index((1e-3, 2e-3))
    spread_start = []
    for P, w in default["start"].items():
        made = 1e-4 * float(P) * 1e6 * 2e-3 / (0.8e9 * 0.5e-6)
        assert 0.15 * (1.0 - 0.8 * s * SHARE * made) - 1e-4 <= w[window] <= 0.15 * (1 + 1e-6), P
        spread_start.append(w[window])
    steady = list(default["mu_bar_1"].values())
    assert max(spread_start) - min(spread_start) < 0.25 * (max(steady) - min(steady))
    curves = d["start_curves"]
    assert set(curves) == set(default["start"]) and max(curves["30"]["draw"]) <= 0.02 + 1e-12


def test_the_3_pass_drop_against_pressure_keeps_to_the_floor(predicted):
    """The floor's 3-pass drop at every pressure lies below 1 - r mu0 / mu_bar(1 MPa, 3 passes); the paper's model
    (r = 0) has no such bound and falls further at the highest pressure."""
    d, options = predicted
    default, papers = d["options"]["default"], d["options"]["paper"]
    mu1 = [(1 - x) / m for x, m in zip(default["drops"]["3"], default["mu_bar_3"])]  # 1 / mu_bar(1 MPa)
    assert max(mu1) == pytest.approx(min(mu1), rel=1e-12)
    bound = 1.0 - 0.2 * 0.15 * mu1[0]
    assert max(default["drops"]["3"]) <= bound
    assert papers["drops"]["3"][-1] > default["drops"]["3"][-1]
    assert len(default["five"]["mu_bar"]) == pd.PASSES and min(default["five"]["mu_bar"]) >= 0.2 * 0.15 - 1e-6
