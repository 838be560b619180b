"""The paper report's uncertainty budget (tribocosim.cosim.reports.paper_budget): the signed intervals of its rows,
the totals of each side, the intervals within the model's bounds on known results; on the real model with a table of
known areas, that r only lowers the drops and no calibrated drop passes the floor's bound, that h_p enters as 1 / K,
and the floor scan (the whole report runs in .ci/run: tribocosim report paper --quick)."""

from __future__ import annotations

import math

import pytest

from tribocosim.components.stripdraw.friction_floor import MU_FLOOR
from tribocosim.components.stripdraw.table import write_table
from tribocosim.cosim.reports import paper, paper_budget as pb, paper_physics as pp
from tribocosim.cosim.studies.stripdraw_experiment import Point, draw


def _result(scale, drop3, drop140, coverage=0.2, bound=0.8):
    return {"scale": scale, "drops": [0.35, 0.5, drop3], "drop_140": drop140, "coverage": [coverage, 0.3, 0.4],
            "bound_3": bound, "bound_140": bound}


def _rows(nominal, varied):
    return {r["quantity"].split(" (")[0]: r for r in pb.budget(nominal, varied)}


def test_a_row_is_the_signed_interval_of_its_ends_changes():
    """Ends on either side: one change down, one up; both on one side: the larger, the other side 0; one end (the
    hardness): its change on its side; an end with an error: the row is an error."""
    nominal = _result(1.0, 0.7, 0.6)
    varied = {"k_low": _result(0.5, 0.72, 0.61, 0.1), "k_high": _result(2.0, 0.45, 0.4, 0.5),
              "zeta_low": _result(1.1, 0.71, 0.6), "zeta_high": _result(1.2, 0.75, 0.6),
              "h_low": _result(0.8, 0.69, 0.62), "mu0_low": {"error": "cannot be calibrated"},
              "mu0_high": _result(1.0, 0.7, 0.6)}
    rows = _rows(nominal, varied)
    k = rows["Archard K"]
    assert k["scale"] == pytest.approx((-0.5, 1.0)) and k["drop3"] == pytest.approx((-0.25, 0.02))
    assert k["drop140"] == pytest.approx((-0.2, 0.01)) and k["coverage"] == pytest.approx((-0.1, 0.3))
    assert not k["one_sided"]
    z = rows["zeta"]
    assert z["scale"] == pytest.approx((0.0, 0.2)) and z["drop3"] == pytest.approx((0.0, 0.05))
    h = rows["hardness H"]
    assert h["one_sided"] and h["scale"] == pytest.approx((-0.2, 0.0)) and h["drop140"] == pytest.approx((0.0, 0.02))
    assert rows["mu0"]["error"] == "cannot be calibrated" and "scale" not in rows["mu0"]


def test_the_shear_row_is_one_sided_and_names_the_r_that_cannot_give_the_35_percent():
    nominal = _result(1.6, 0.735, 0.633)
    upper = {**_result(3.1, 0.40, 0.38), "value": 0.5, "refused": [0.6]}
    (row,) = pb.budget(nominal, {"shear": upper})
    assert row["one_sided"] and row["drop3"] == pytest.approx((-0.335, 0.0))
    assert row["scale"] == pytest.approx((0.0, 1.5))
    assert row["range"] == "0.5 (0.6 cannot give the paper's 35 % one-pass drop with any s)"
    failed = pb.budget(nominal, {"shear": {"error": "no r", "refused": [0.6, 0.5, 0.4, 0.3]}})[0]
    assert failed["error"] == "no r" and failed["range"].startswith("none (")


def test_totals_sum_each_side_in_quadrature_and_intervals_keep_to_the_floors_bound():
    """Down and up apart (the quote on both sides of s); a drop's interval ends at the largest bound 1 - r mu0 /
    mu_bar(1 MPa) over the runs, not at value + up; the coverage at 1; s at 0."""
    rows = [{"scale": (-0.3, 0.4), "drop3": (-0.2, 0.03), "drop140": (-0.1, 0.0), "coverage": (-0.1, 0.5)},
            {"scale": (0.0, 0.3), "drop3": (-0.1, 0.04), "drop140": (0.0, 0.02), "coverage": (0.0, 0.7)},
            {"error": "cannot be calibrated"}]
    assert pb.budget_total(rows, "drop3") == pytest.approx((math.hypot(0.2, 0.1), 0.05))
    assert pb.budget_total(rows, "scale", 0.1) == pytest.approx((math.hypot(0.3, 0.1), math.sqrt(0.4**2 + 0.3**2
                                                                                                 + 0.1**2)))
    nominal = _result(1.0, 0.735, 0.633, coverage=0.4, bound=0.753)
    varied = {"a": _result(1.2, 0.7, 0.6, bound=0.76), "b": {"error": "x"}}
    bounds = pb.drop_bounds(nominal, varied)
    assert bounds == {"drop3": 0.76, "drop140": 0.76}
    total, spans = pb.intervals(nominal, rows, bounds, 0.0)
    assert spans["drop3"] == pytest.approx((0.735 - math.hypot(0.2, 0.1), 0.76))  # 0.735 + 0.05 would pass it
    assert spans["drop140"] == pytest.approx((0.533, 0.633 + 0.02))
    assert spans["coverage"] == pytest.approx((0.4 - 0.1, 1.0))
    assert pb.interval(0.4, (1.0, 0.5), 0.0, math.inf) == pytest.approx((0.0, 0.9))


def test_the_ranges_follow_their_evidence():
    """K and h_p over one decade each, mu0 with the floor held (r mu0 = MU_FLOOR at both ends), r one-sided from the
    default up; the observable is not an input of the budget."""
    by = {v.name: v for v in pb.VARIATIONS}
    k = [by["k_low"].parameters["archard_k"], by["k_high"].parameters["archard_k"]]
    assert k[1] / k[0] == pytest.approx(10.0) and math.sqrt(k[0] * k[1]) == pytest.approx(1e-4)
    h = [by["hp_thin"].parameters["particle_thickness"], by["hp_thick"].parameters["particle_thickness"]]
    assert h[1] / h[0] == pytest.approx(10.0) and h[1] <= 1e-6  # "sub-micron" flakes
    for name in ("mu0_low", "mu0_high"):
        p = by[name].parameters
        assert p["flake_shear_ratio"] * p["mu0"] == pytest.approx(MU_FLOOR, rel=1e-12)
    assert by["shear"].pair is None and by["shear"].parameters["flake_shear_ratio"] > 0.2
    assert "particle_area_rule" not in {k for v in pb.VARIATIONS for k in v.parameters}
    assert [v.table for v in pb.VARIATIONS if v.quantity == "form of the table"] == [pp.FORM_VARIANT]


def test_the_budget_names_the_domain_size_unless_a_table_on_another_size_varies_it():
    """Without the domain-size variant the budget says the input is not varied instead of leaving it out; with it,
    the row is the variation's."""
    from tribocosim.components.stripdraw.table import read_table
    from tribocosim.paths import DEFAULT_TABLE

    shipped = read_table(DEFAULT_TABLE)
    size = shipped.metadata["campaign"]["sweep"]["slide"]["size"]
    (row,) = pb.inputs_not_varied(shipped, {})
    assert row["quantity"] == "domain size of the slides" and f"{size * 1e6:g} um domain only" in row["range"]
    assert pb.inputs_not_varied(shipped, {"domain_128": "x.npz"}) == []
    assert pb.inputs_not_varied(shipped, {"domain_512": "x.npz"}) == []
    assert {v.table: v.quantity for v in pb.VARIATIONS if v.table in pp.DOMAIN_TABLES} == {
        "domain_128": "domain size of the slides", "domain_512": "domain size of the slides"}


@pytest.fixture(scope="module")
def known(tmp_path_factory, known_area_table):
    path = tmp_path_factory.mktemp("budget") / "t.npz"
    table = known_area_table
    write_table(path, table)
    runs = paper.Runs(workers=1)
    return runs, paper.config_params({"table_file": str(path)}, paper.Config("mesoscale", True)), table


def test_r_above_the_floor_only_lowers_the_drops_and_none_passes_its_bound(known):
    """Calibrated on the same 35 %, a larger r keeps (1 - r) s below the cap and raises mu where flakes carry the
    contact (mu = r mu0): its row has no upward change; every drop lies below 1 - r mu0 / mu_bar(1 MPa) <= 1 - r."""
    runs, params, table = known
    nominal = pp.calibrated_predictions(runs, params, table, paper.calibrate)
    scan = pb.floor_scan(runs, params, table, paper.calibrate)
    done = [r for r in scan["rows"] if "drop3" in r]
    assert [r["r"] for r in done][:2] == [0.2, 0.21] and done[0]["drop3"] == pytest.approx(nominal["drops"][2])
    for r in done:
        assert r["floor"] == pytest.approx(0.15 * r["r"]) and r["drop3"] <= r["bound_3"] <= 1.0 - r["r"]
    assert all(b["drop3"] < a["drop3"] for a, b in zip(done, done[1:])), "a larger r lowers the 3-pass drop"
    assert scan["drop3_per_0.01"] == pytest.approx((done[1]["drop3"] - done[0]["drop3"]) / 0.01 * 0.01)
    upper = pb.shear_upper_end(runs, params, table, paper.calibrate)
    (row,) = pb.budget(nominal, {"shear": upper})
    assert row["drop3"][1] == 0.0 and row["drop3"][0] < 0.0 and row["drop140"][1] == 0.0


def test_the_flake_thickness_enters_as_one_over_archard_k(known):
    """d beta / ds = K P / (H h_p) (Eq. 12): K with 2 h_p is K / 2 with h_p: the same mu_bar and coverage every pass;
    the debris weighed (beta h_p rho) doubles."""
    _, params, _ = known
    p = {**params, "particle_area_scale": 1.6}
    thick = draw(Point(25e6, 0.035, 3, {**p, "particle_thickness": 1e-6}))
    half_k = draw(Point(25e6, 0.035, 3, {**p, "archard_k": 5e-5}))
    for a, b in zip(thick, half_k):
        assert a["mu_bar"] == pytest.approx(b["mu_bar"], rel=1e-9) and a["beta_left"] == pytest.approx(
            b["beta_left"], rel=1e-9)
        assert a["debris_g_m2"] == pytest.approx(2.0 * b["debris_g_m2"], rel=1e-9)
