"""The uncertainty budget of the paper report's default model, the floor scan and the check that h_p enters as 1 / K.

Every run is the report's: a strip-draw test of the pure model, s recalibrated on the paper's 35 % one-pass drop at
25 MPa (:func:`tribocosim.cosim.reports.paper.calibrate`), then the predictions of
:func:`tribocosim.cosim.reports.paper_physics.predictions` (the 3-pass drop at 25 MPa, the 140 mm pad's one-pass drop,
the coverage beta after one pass at 25 MPa).

Each chosen input is varied over the range its evidence gives (:data:`VARIATIONS`; docs/model.md section 8):

- Archard's K: the paper's 1e-4 is an order-of-magnitude choice: one decade around it, 1e-4 x/ sqrt(10);
- the flake thickness h_p: the paper assumes 0.5 um for flakes whose thickness "appears to be sub-micron" (its
  Sec. 2.3): the decade below a micron, 0.1-1 um. h_p enters the model only through the production rate
  K P / (H h_p) (Eq. 12, 37), so h_p times c is K over c (:func:`thickness_check` runs both); K and h_p are
  independent inputs and each is counted;
- mu0: no measurement of this test's particle-free coefficient was found: 0.15 +- 20 %, a stated choice, with the
  floor held (r = MU_FLOOR / mu0): mu0 multiplies every mu of the law, so at a fixed r it moves the drops only
  through the bar's mechanics, and with the floor held it moves them through r;
- r, one-sided: the default 0.2 is the floor the project sets (MU_FLOOR / mu0, docs/model.md section 8); r below it
  is excluded and a larger r only lowers the drops. Its upper end is the sourced 0.6 (0.09 / 0.15) or the largest r
  on a grid of :data:`SHEAR_STEP` with which an s gives the 35 % (:func:`shear_upper_end`);
- the table's ensemble noise, the hardness (one-sided: the HB 69 handbook value below HV 84), zeta, the surface pair,
  the slides' domain size, the table's form and the velocity in the lookup, as the tables allow.

A row is the signed interval of its ends' changes, (min(0, changes), max(0, changes)) (:func:`budget`): ends on
either side of the nominal give one change down and one up, ends on one side the larger one, a one-sided input its
one change on its side. The total (:func:`budget_total`) is the quadrature sum of the downward changes and, apart,
of the upward ones (the quote of the 35 % adds to both sides of s), and a prediction's interval (:func:`interval`)
is value - down to value + up within the model's own bounds: a drop lies in [0, bound] with bound the largest
1 - r mu0 / mu_bar(1 MPa) over the budget's runs (mu >= r mu0 wherever flakes carry the contact: the floor caps every
drop), the coverage in [0, 1], s in [0, inf).

The floor scan (:func:`floor_scan`) recalibrates the default model at r = :data:`FLOOR_SCAN`: the 3-pass drop at
25 MPa against the floor r mu0, its bound, and how much each 0.01 of r moves it.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

from tribocosim.components.stripdraw.friction_floor import FLAKE_SHEAR_RATIO_RANGE, MU_FLOOR
from tribocosim.cosim.reports import paper_physics as pp

R_LOW, R_HIGH = FLAKE_SHEAR_RATIO_RANGE
K0, H_P0, MU0 = 1e-4, 0.5e-6, 0.15  # the defaults the ranges are around (the paper's K and h_p, the design's mu0)
K_FACTOR = math.sqrt(10.0)  # K over one decade around the paper's value
H_P_RANGE = (0.1e-6, 1.0e-6)  # h_p over the decade below a micron (the paper's "sub-micron")
MU0_RANGE = (0.12, 0.18)  # mu0 +- 20 % (no measurement found: a stated choice)
#: the budget's variation of r: its upper end is the largest r of the sourced range on a grid of SHEAR_STEP that the
#: calibration can reach the paper's 35 % with (:func:`shear_upper_end`)
SHEAR_VARIATION, SHEAR_STEP = "shear", 0.1
#: the shear ratios of the floor scan: the default, one step of 0.01 (the slope there), and up its sourced range
FLOOR_SCAN = (0.2, 0.21, 0.3, 0.4, 0.5, 0.6)
#: the predictions the budget follows: name -> how to read it from a calibrated prediction
KEYS = {"scale": lambda r: r["scale"], "drop3": lambda r: r["drops"][2], "drop140": lambda r: r["drop_140"],
        "coverage": lambda r: r["coverage"][0]}


@dataclasses.dataclass(frozen=True)
class Variation:
    """One input of the uncertainty budget varied: the strip-draw parameters it sets or the table it uses."""

    name: str
    quantity: str
    value: str
    parameters: dict = dataclasses.field(default_factory=dict)
    table: str | None = None  # a table variant (:func:`tribocosim.cosim.reports.paper_physics.table_variants`)
    pair: str | None = None  # the name of the other end of a two-sided range


_K = "Archard K (the paper's 1e-4, an order-of-magnitude choice: one decade)"
_HP = "flake thickness h_p (the paper's 0.5 um for flakes that appear sub-micron: one decade)"
_MU0 = f"mu0 (0.15, no measurement found: +-20 %), the floor held at {MU_FLOOR:g} (r = {MU_FLOOR:g} / mu0)"
VARIATIONS = (
    Variation("ensemble_low", "ensemble noise of the table", "A_p - 1 standard error at every node",
              table="ensemble_low", pair="ensemble_high"),
    Variation("ensemble_high", "ensemble noise of the table", "A_p + 1 standard error at every node",
              table="ensemble_high", pair="ensemble_low"),
    Variation("k_low", _K, f"{K0 / K_FACTOR:.3g} (/ sqrt 10)", {"archard_k": K0 / K_FACTOR}, pair="k_high"),
    Variation("k_high", _K, f"{K0 * K_FACTOR:.2e} (x sqrt 10)", {"archard_k": K0 * K_FACTOR}, pair="k_low"),
    Variation("hp_thin", _HP, f"{H_P_RANGE[0] * 1e6:g} um", {"particle_thickness": H_P_RANGE[0]}, pair="hp_thick"),
    Variation("hp_thick", _HP, f"{H_P_RANGE[1] * 1e6:g} um", {"particle_thickness": H_P_RANGE[1]}, pair="hp_thin"),
    Variation("h_low", "hardness H (handbook HV 84: 0.8 GPa)", "0.68 GPa (HB 69)", {"hardness": 0.68e9}),
    Variation("zeta_low", "zeta (the paper's fit to another model: 0.2)", "0.1", {"zeta": 0.1}, pair="zeta_high"),
    Variation("zeta_high", "zeta (the paper's fit to another model: 0.2)", "0.3", {"zeta": 0.3}, pair="zeta_low"),
    Variation("mu0_low", _MU0, f"{MU0_RANGE[0]:g} (r = {MU_FLOOR / MU0_RANGE[0]:.3g})",
              {"mu0": MU0_RANGE[0], "flake_shear_ratio": MU_FLOOR / MU0_RANGE[0]}, pair="mu0_high"),
    Variation("mu0_high", _MU0, f"{MU0_RANGE[1]:g} (r = {MU_FLOOR / MU0_RANGE[1]:.3g})",
              {"mu0": MU0_RANGE[1], "flake_shear_ratio": MU_FLOOR / MU0_RANGE[1]}, pair="mu0_low"),
    Variation("pair_1", "surface pair", "the table of the first pair alone", table="pair_0", pair="pair_2"),
    Variation("pair_2", "surface pair", "the table of the second pair alone", table="pair_1", pair="pair_1"),
    Variation("domain_128", "domain size of the slides", "128 um instead of 256 um at 1, 20 and 30 MPa (0.08 m/s)",
              table="domain_128", pair="domain_512"),
    Variation("domain_512", "domain size of the slides", "512 um", table="domain_512", pair="domain_128"),
    Variation("form", "form of the table", "each row's fit (smaller AIC) at its simulated nodes instead of the "
              "ensemble means", table=pp.FORM_VARIANT),
    Variation("velocity", "velocity in the lookup", "each node's slip rate instead of the grip's",
              {"friction_velocity": "slip_rate"}),
    Variation(SHEAR_VARIATION, f"flake-borne shear ratio r (one-sided: r >= {R_LOW:g}, the floor; sourced up to "
              f"{R_HIGH:g})", f"{R_HIGH:g}", {"flake_shear_ratio": R_HIGH}),
)


def inputs_not_varied(table, variants: dict) -> list[dict]:
    """The chosen inputs of the uncertainty budget that no variation covers, named so that the budget's total is not
    read as covering them: the domain size of the table's slides when there is no table on another domain size
    (``variants`` has none of the domain tables; docs/physics/table_domain.md)."""
    if any(name in variants for name in pp.DOMAIN_TABLES):
        return []
    size = table.metadata.get("campaign", {}).get("sweep", {}).get("slide", {}).get("size")
    where = f"the table's {size * 1e6:g} um domain only" if size else "the table's one domain size"
    return [{"quantity": "domain size of the slides", "range": where,
             "why": "no table on a second domain size at the nodes the 3-pass test reads"}]


def shear_upper_end(runs, params: dict, table, calibrate) -> dict:
    """:func:`~tribocosim.cosim.reports.paper_physics.calibrated_predictions` at the upper end of r's sourced range,
    or, where no s gives the paper's 35 % one-pass drop there (flakes that shear at r tau0 cannot lower mu_bar at
    25 MPa by 35 % against 1 MPa when r is large), at the largest r below it on a grid of :data:`SHEAR_STEP` that can;
    the r taken and the ones refused are recorded (``value``, ``refused``). An error when no r above the default
    can."""
    refused = []
    r = R_HIGH
    while r > R_LOW + 1e-9:
        result = pp.calibrated_predictions(runs, {**params, "flake_shear_ratio": r}, table, calibrate)
        if "error" not in result:
            return {**result, "value": r, "refused": refused}
        refused.append(r)
        r = round(r - SHEAR_STEP, 10)
    return {"error": f"no r in ({R_LOW:g}, {R_HIGH:g}] on a grid of {SHEAR_STEP:g} gives the 35 % one-pass drop",
            "refused": refused}


def budget(nominal: dict, varied: dict) -> list[dict]:
    """The budget's rows: per quantity varied, the signed interval (down <= 0, up >= 0) of the changes of s, of the
    3-pass drop, of the 140 mm drop and of the coverage after one pass (:data:`KEYS`) over the ends of its range
    (module docstring). An end absent from ``varied`` leaves the other end alone; an end with an error makes the row
    an error."""
    rows, seen = [], set()
    for v in VARIATIONS:
        if v.name in seen or v.name not in varied:
            continue
        ends = [v] + [w for w in VARIATIONS if w.name == v.pair and w.name in varied]
        seen.update(w.name for w in ends)
        results = [varied[w.name] for w in ends]
        row = {"quantity": v.quantity, "range": " / ".join(w.value for w in ends), "one_sided": len(ends) == 1}
        if v.name == SHEAR_VARIATION and varied[v.name].get("refused"):
            found = varied[v.name]
            taken = (f"{found['value']:g}" if "value" in found else "none")
            row["range"] = (f"{taken} (" + ", ".join(f"{x:g}" for x in found["refused"])
                            + " cannot give the paper's 35 % one-pass drop with any s)")
        if any("error" in r for r in results):
            row["error"] = "; ".join(r["error"] for r in results if "error" in r)
            rows.append(row)
            continue
        for key, get in KEYS.items():
            changes = [get(r) - get(nominal) for r in results]
            row[key] = (min(0.0, *changes), max(0.0, *changes))
        rows.append(row)
    return rows


def budget_total(rows: list[dict], key: str, quote: float = 0.0) -> tuple[float, float]:
    """(down, up): the quadrature sums of the rows' downward and upward changes of ``key``, with ``quote`` (a
    symmetric standard error) on both sides; rows with an error are left out (the report names them)."""
    down = math.sqrt(quote**2 + sum(r[key][0] ** 2 for r in rows if key in r))
    up = math.sqrt(quote**2 + sum(r[key][1] ** 2 for r in rows if key in r))
    return down, up


def interval(value: float, total: tuple[float, float], low: float = 0.0, high: float = 1.0) -> tuple[float, float]:
    """value - down to value + up (``total``), within [low, high]: the model's bounds."""
    return max(low, value - total[0]), min(high, value + total[1])


def drop_bounds(nominal: dict, varied: dict) -> dict[str, float]:
    """The largest drop the floor allows over the budget's runs (the nominal and every end that was calibrated):
    1 - r mu0 / mu_bar(1 MPa) of the 3-pass test and of the 140 mm pad's one-pass test."""
    runs = [nominal] + [r for r in varied.values() if "error" not in r]
    return {"drop3": max(r["bound_3"] for r in runs), "drop140": max(r["bound_140"] for r in runs)}


def intervals(nominal: dict, rows: list[dict], bounds: dict, quote: float) -> tuple[dict, dict]:
    """The totals and the intervals of every prediction of :data:`KEYS` (``quote``: the standard error of s from
    the rounding of the 35 %)."""
    total = {key: budget_total(rows, key, quote if key == "scale" else 0.0) for key in KEYS}
    highs = {"scale": math.inf, "coverage": 1.0, **bounds}
    out = {key: interval(KEYS[key](nominal), total[key], 0.0, highs[key]) for key in KEYS}
    return total, out


def run_variations(runs, params: dict, table, tables: dict, calibrate) -> dict:
    """Every variation calibrated and predicted (``tables``: the table variants written, name -> path): name -> the
    calibrated predictions, or the reason it could not be run."""
    varied = {}
    for v in VARIATIONS:
        if v.table in pp.DOMAIN_TABLES and v.table not in tables:
            continue  # no table on that domain size: the other end alone, or named as not varied (inputs_not_varied)
        if v.table is not None and v.table not in tables:
            needs = "version 4" if v.table == pp.FORM_VARIANT else "version 3 or 4"
            varied[v.name] = {"error": f"needs a {needs} table that records its campaign"}
            continue
        if v.name == SHEAR_VARIATION:
            varied[v.name] = shear_upper_end(runs, params, table, calibrate)
            continue
        p = {**params, **({"table_file": tables[v.table]} if v.table else {}), **v.parameters}
        varied[v.name] = pp.calibrated_predictions(runs, p, table, calibrate)
    return varied


def thickness_check(runs, params: dict, table, calibrate, varied: dict) -> dict:
    """h_p enters as 1 / K: the thick end of h_p's range run again with h_p at its default and K divided by the same
    factor; the largest difference of s and of the predictions between the two (round-off, if h_p enters only
    through K / h_p)."""
    thick = varied.get("hp_thick", {})
    factor = H_P_RANGE[1] / H_P0
    k = float(params.get("archard_k", K0)) / factor
    same = pp.calibrated_predictions(runs, {**params, "archard_k": k}, table, calibrate)
    if "error" in thick or "error" in same or not thick:
        return {"error": thick.get("error") or same.get("error") or "not run"}
    return {"particle_thickness": H_P_RANGE[1], "archard_k": k,
            "largest_difference": max(abs(get(thick) - get(same)) for get in KEYS.values())}


def floor_scan(runs, params: dict, table, calibrate) -> dict:
    """The default model recalibrated at every r of :data:`FLOOR_SCAN` (mu0 as in ``params``): per r the floor r mu0,
    s, the 3-pass drop at 25 MPa and its bound 1 - r mu0 / mu_bar(1 MPa, 3 passes), the 140 mm pad's one-pass drop (or
    why no s gives the 35 %); and the change of the 3-pass drop per 0.01 of r from the first step."""
    rows = []
    for r in FLOOR_SCAN:
        res = pp.calibrated_predictions(runs, {**params, "flake_shear_ratio": r}, table, calibrate)
        row = {"r": r}
        if "error" in res:
            row["error"] = res["error"]
        else:
            row.update(floor=res["floor"], scale=res["scale"], drop3=res["drops"][2], bound_3=res["bound_3"],
                       drop140=res["drop_140"])
        rows.append(row)
    a, b = rows[0], rows[1]
    per = ((b["drop3"] - a["drop3"]) / (b["r"] - a["r"]) * 0.01) if "drop3" in a and "drop3" in b else math.nan
    return {"rows": rows, "drop3_per_0.01": per}


def run_budget(runs, params: dict, base_table: Path, table, calibrate, nominal: dict, quote: float,
               log=None) -> dict:
    """The whole budget of the default model (``nominal``: its calibrated predictions), with the table variants
    written into a scratch folder: rows, totals, intervals, the bounds, the inputs not varied, the h_p check and the
    floor scan."""
    from tribocosim.paths import DEFAULT_TABLE

    with pp.scratch_folder() as folder:
        # the domain-size variation's tables are the shipped table's (the same slides on 128 and 512 um domains)
        shipped = Path(base_table).resolve() == Path(DEFAULT_TABLE).resolve()
        domains = {name: Path(DEFAULT_TABLE).with_name(file) for name, file in pp.DOMAIN_TABLES.items()}
        tables = pp.table_variants(table, Path(folder),
                                   {name: path for name, path in domains.items() if shipped and path.is_file()})
        varied = run_variations(runs, params, table, tables, calibrate)
    rows = budget(nominal, varied)
    bounds = drop_bounds(nominal, varied)
    total, spans = intervals(nominal, rows, bounds, quote)
    if log:
        log("the floor scan and the h_p check ...")
    return {"rows": rows, "total": total, "intervals": spans, "bounds": bounds,
            "not_varied": inputs_not_varied(table, tables),
            "thickness_check": thickness_check(runs, params, table, calibrate, varied),
            "floor_scan": floor_scan(runs, params, table, calibrate)}
