"""The paper report's text for its budget and its predictions (``paper.md``): the uncertainty budget and the floor
scan (:mod:`tribocosim.cosim.reports.paper_budget`), the floor's prediction at 25 MPa
(:mod:`tribocosim.cosim.reports.paper_floor`) and the discriminating predictions
(:mod:`tribocosim.cosim.reports.paper_discriminators`), from the numbers
:func:`tribocosim.cosim.reports.paper.run_report` computed."""

from __future__ import annotations

import math

from tribocosim.components.stripdraw.friction_floor import FLAKE_SHEAR_RATIO_DEFAULT, MU_FLOOR
from tribocosim.cosim.reports import paper_discriminators as pd, paper_floor
from tribocosim.cosim.reports import paper_physics as pp


def pct(x: float) -> str:
    return f"{100 * x:.1f} %"


def _span(pair, scale: float = 100.0, digits: int = 1) -> str:
    """A row's signed interval (down <= 0, up >= 0) as "-a / +b" in ``scale`` units."""
    return f"-{abs(scale * pair[0]):.{digits}f} / +{scale * pair[1]:.{digits}f}"


def budget_markdown(budget: dict, nominal: dict, cal) -> list[str]:
    """The uncertainty budget: its rows, totals and intervals within the model's bounds, the h_p check."""
    rows, tot, missing = budget["rows"], budget["total"], budget["not_varied"]
    lines = ["", f"## Uncertainty budget (the default model, r = {FLAKE_SHEAR_RATIO_DEFAULT:g}, A_c from the table)", "",
             "Each chosen input varied over the range its evidence gives (docs/model.md section 8; an input not varied "
             "is named in the table, and the totals leave it out), s recalibrated on the 35 % at every end, and each "
             "row the signed changes over its ends, down / up (ends on either side of the default: one change each "
             "way; on one side: the larger; a one-sided input: its one change). r is one-sided: the default is the "
             "floor the project sets, r cannot go below it and a larger r only lowers the drops. The totals are the "
             "quadrature sums of each side apart (with the quote of the 35 %, which alone gives s a standard error "
             f"of {cal.stderr_quote:.2g}). The observable A_p stands for is a model choice, not an input with a "
             "range: it is stated with its evidence in its own section and not summed here.", "",
             "| input | range | s | 3-pass drop [points] | 140 mm drop [points] | coverage after one pass at 25 MPa |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        if "error" in r:
            lines.append(f"| {r['quantity']} | {r['range']} | {r['error']} | | | |")
        else:
            lines.append(f"| {r['quantity']} | {r['range']} | {_span(r['scale'], 1.0, 3)} | {_span(r['drop3'])} | "
                         f"{_span(r['drop140'])} | {_span(r['coverage'], 1.0, 3)} |")
    for m in missing:
        lines.append(f"| {m['quantity']} | {m['range']} | not varied: {m['why']} | - | - | - |")
    not_in = f", without the {', '.join(m['quantity'] for m in missing)}" if missing else ""
    lines += [f"| **total** (quadrature of each side, with the quote{not_in}) | | **{_span(tot['scale'], 1.0, 3)}** | "
              f"**{_span(tot['drop3'])}** | **{_span(tot['drop140'])}** | **{_span(tot['coverage'], 1.0, 3)}** |", "",
              "So " + budget_summary(budget, nominal, cal), ""]
    check = budget["thickness_check"]
    if "error" not in check:
        diff = check["largest_difference"]
        lines += [f"h_p enters only as K / h_p: h_p = {check['particle_thickness'] * 1e6:g} um with the paper's K and "
                  f"K = {check['archard_k']:.3g} with h_p = 0.5 um, each calibrated on the 35 %, give s and the "
                  "predictions above " + ("bit for bit the same." if diff == 0 else f"within {diff:.1g} of each other."),
                  ""]
    return lines


def budget_summary(budget: dict, nominal: dict, cal) -> str:
    """The budget in one paragraph: s and each prediction with its interval, within the floor's bounds."""
    band, bounds, missing = budget["intervals"], budget["bounds"], budget["not_varied"]
    return (f"s = {cal.scale:.3g} (interval {band['scale'][0]:.3g} to {band['scale'][1]:.3g}), the 3-pass drop "
            f"{pct(nominal['drops'][2])} (interval {pct(band['drop3'][0])} to {pct(band['drop3'][1])}; the paper: up "
            f"to 72 %), the 140 mm pad's one-pass drop {pct(nominal['drop_140'])} (interval "
            f"{pct(band['drop140'][0])} to {pct(band['drop140'][1])}), the coverage after one pass at 25 MPa "
            f"{nominal['coverage'][0]:.3g} (interval {band['coverage'][0]:.3g} to {band['coverage'][1]:.3g}): the "
            "value less the downward total to the value plus the upward one, within the model's bounds. A drop is "
            "at most what the floor allows, 1 - r mu0 / mu_bar(1 MPa) of the same test: "
            f"{pct(nominal['bound_3'])} after three passes and {pct(nominal['bound_140'])} on the 140 mm pad at the "
            f"default settings, {pct(bounds['drop3'])} and {pct(bounds['drop140'])} at most over the budget's runs "
            "(a larger mu0 with the floor held lowers r)"
            + (f"; the {', '.join(m['quantity'] for m in missing)} is not varied, so these intervals leave "
               f"{'it' if len(missing) == 1 else 'them'} out." if missing else "."))


def floor_scan_markdown(scan: dict) -> list[str]:
    """The floor scan: the 3-pass drop against the floor r mu0 the project sets."""
    rows = scan["rows"]
    lines = ["## The floor scan: the 3-pass drop against the floor", "",
             "The floor r mu0 is a bound the project sets (docs/model.md section 8), not a measurement. Where flakes "
             "carry the whole contact mu = r mu0, so a drop at 25 MPa is at most 1 - r mu0 / mu_bar(1 MPa) of the same "
             "test, and at most 1 - r whatever s and the debris (mu_bar(1 MPa) <= mu0). The default model "
             "recalibrated on the 35 % at each r:", "",
             "| r | floor r mu0 | s | 3-pass drop at 25 MPa | its bound 1 - r mu0 / mu_bar(1 MPa, 3 passes) | 1 - r | "
             "140 mm pad's one-pass drop |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        if "error" in r:
            lines.append(f"| {r['r']:g} | {r['r'] * pp.floor_of({'flake_shear_ratio': 1.0}):.3g} | no s gives the "
                         "35 % | | | | |")
        else:
            lines.append(f"| {r['r']:g} | {r['floor']:.3g} | {r['scale']:.4g} | {pct(r['drop3'])} | {pct(r['bound_3'])} "
                         f"| {pct(1 - r['r'])} | {pct(r['drop140'])} |")
    per = scan["drop3_per_0.01"]
    ok = [r for r in rows if "drop3" in r]
    at72 = _crossing(ok, 0.72)
    lines += ["", f"Each 0.01 of r moves the 3-pass drop by {100 * abs(per):.2f} points at r = {rows[0]['r']:g}"
              + (f"; it equals the paper's 72 % at r = {at72:.3g} (linear between the scan's neighbours)"
                 if at72 is not None else "") + ". The 3-pass drop at the default is the floor re-expressed, not a "
              "prediction of it.", ""]
    return lines


def _crossing(rows: list[dict], target: float) -> float | None:
    """r where the 3-pass drop crosses ``target``, linear between the neighbouring rows of the scan."""
    for a, b in zip(rows, rows[1:]):
        if (a["drop3"] - target) * (b["drop3"] - target) <= 0 and a["drop3"] != b["drop3"]:
            return a["r"] + (b["r"] - a["r"]) * (a["drop3"] - target) / (a["drop3"] - b["drop3"])
    return None


def prediction_markdown(prediction: dict) -> list[str]:
    """The floor's prediction at 25 MPa (paper_floor): five passes and a seeded strip, per option."""
    five, seeded = prediction["five_passes"], prediction["seeded"]
    labels = {o.name: o.label for o in pp.OPTIONS}
    passes = range(1, paper_floor.PASSES + 1)
    lines = ["", "## Five passes and a seeded strip at 25 MPa", "",
             f"Each option at its s calibrated on the 35 % (the table above), 35 mm pad, 25 MPa ([floor.png](floor.png);"
             f" the floor mu = {MU_FLOOR:g} the project sets, docs/model.md). Five passes over one strip without "
             "cleaning: mu_bar and the debris weighed after each pass (the drop against 1 MPa in brackets). With "
             "flake-borne shear (r > 0) mu_bar levels off near r mu0 once flakes carry the contact; the paper's model "
             "with every flake carried over keeps falling; a sink or a partial carry-over levels off where the debris "
             "made balances the debris lost.", "",
             "| option | " + " | ".join(f"mu_bar, pass {k}" for k in passes)
             + " | debris after pass " + " / ".join(str(k) for k in passes) + " [g/m^2] | clamped lookups |",
             "|---|" + "---|" * (paper_floor.PASSES + 2)]
    for name, r in five.items():
        lines.append(f"| {labels[name]} | " + " | ".join(f"{mu:.4f} ({pct(d)})" for mu, d in zip(r["mu_bar"],
                                                                                              r["drop"]))
                     + " | " + " / ".join(f"{g:.3g}" for g in r["debris_g_m2"]) + f" | {r['clamps']} |")
    levels = [paper_floor.seeded_g_m2(b) for b in paper_floor.SEEDED_BETAS]
    lines += ["", "One pass over a clean strip, re-oiled, seeded with a known debris (weighed: beta0 h_p rho, so the "
              "mass stands for a coverage only through the assumed h_p): mu_bar against the debris seeded. The seeding "
              "fixes the debris whatever the options' balances: the carry-over option is the paper's model here, and "
              "a sink takes part of the seeded debris during the pass. An option's seeding stops at its largest cap of "
              "beta (the model refuses more; a cell above it holds the cap's, in brackets the debris seeded), and the "
              "cap at 25 MPa takes what exceeds it there.", "",
              "| option | " + " | ".join(f"{g:.3g} g/m^2" for g in levels) + " | clamped lookups |",
              "|---|" + "---|" * (len(levels) + 1)]
    for name, r in seeded.items():
        cells = [f"{mu:.4f}" + ("" if abs(g - want) < 1e-12 else f" ({g:.3g})")
                 for mu, g, want in zip(r["mu_bar"], r["seeded_g_m2"], levels)]
        lines.append(f"| {labels[name]} | " + " | ".join(cells) + f" | {r['clamps']} |")
    lines += ["", "How well these and the other records tell the floor from a sink or a partial carry-over is in the "
              "next section."]
    return lines


def discriminators_markdown(d: dict) -> list[str]:
    """The discriminating predictions (paper_discriminators): drops against pressure, five passes at 10 MPa, the
    coverage after one pass, the start of mu(t), and how far each record separates the floor from its competitors."""
    opts = d["options"]
    P = d["pressures"]
    lines = ["## Discriminating predictions", "",
             "Each option at its s calibrated on the 35 %, 35 mm pad ([discriminators.png](discriminators.png)).", "",
             "The drop against 1 MPa after 2 and 3 passes against pressure (the curves of the paper's Fig. 2b), and "
             "the rise of the 3-pass drop from 15 to 30 MPa: with the floor it levels off where flakes carry the "
             "contact; a sink or a partial carry-over keeps it rising.", "",
             "| option | passes | " + " | ".join(f"{p} MPa" for p in P) + " | 3-pass rise 15 -> 30 MPa | clamped "
             "lookups |", "|---|---|" + "---|" * (len(P) + 2)]
    for name, r in opts.items():
        for k in ("2", "3"):
            rise = (f"{100 * (r['drops']['3'][P.index(30)] - r['drops']['3'][P.index(15)]):.1f} points"
                    if k == "3" and 15 in P and 30 in P else "")
            lines.append(f"| {r['label']} | {k} | " + " | ".join(pct(x) for x in r["drops"][k]) + f" | {rise} | "
                         + (f"{r['clamps']} |" if k == "3" else " |"))
    five_p = d["five_pass_pressure"]
    lines += ["", f"Five passes at {five_p} MPa: mu_bar after each pass (the drop against 1 MPa in brackets).", "",
              "| option | " + " | ".join(f"pass {k}" for k in range(1, pd.PASSES + 1)) + " |",
              "|---|" + "---|" * pd.PASSES]
    for r in opts.values():
        lines.append(f"| {r['label']} | " + " | ".join(f"{m:.4f} ({pct(x)})" for m, x in zip(r["five"]["mu_bar"],
                                                                                            r["five"]["drop"])) + " |")
    cp = d["coverage_pressures"]
    lines += ["", "The coverage beta after one pass (the mean over the strip that passed under the pad). Without a sink "
              "the debris is conserved and it is K P D L_T / (H h_p (D + L_T)) over a draw D, whatever r, zeta and the "
              "carry-over: a coverage measured by image analysis measures K / (H h_p), and tells a sink from none.", "",
              "| option | " + " | ".join(f"{p} MPa" for p in cp) + " |", "|---|" + "---|" * len(cp)]
    closed = d.get("coverage_closed_form")
    if closed:
        lines.append("| K P D L_T / (H h_p (D + L_T)) | " + " | ".join(f"{c:.4f}" for c in closed) + " |")
    for r in opts.values():
        lines.append(f"| {r['label']} | " + " | ".join(f"{c:.4f}" for c in r["coverage"]) + " |")
    lines += start_markdown(d)
    lines += separations_markdown(d.get("separations", []))
    return lines


def start_markdown(d: dict) -> list[str]:
    """The start of mu(t) at every pressure (the default model), against its steady mean."""
    default = d["options"].get(pd.FLOOR_OPTION)
    if not default:
        return []
    mu0 = d["mu0"]
    heads = [f"{1e3 * a:g}-{1e3 * b:g} mm" for a, b in pd.WINDOWS]
    lines = ["", f"The start of mu(t), pass 1 of the default model: its mean over windows of the draw, over mu0 = "
                 f"{mu0:g}, and mu_bar (the last 20 % of the draw) beside it. A strip point there carries the debris "
                 "of a few millimetres of slide, so debris as the sole cause predicts mu near mu0 at every pressure "
                 "there and the pressure trend growing over the draw; a pressure trend in the measured mu(t) from the "
                 "first millimetres (after the break-away peak the paper reports) would refute debris as its sole "
                 "cause.", "",
             "| P [MPa] | " + " | ".join(heads) + " | mu_bar |", "|---|" + "---|" * (len(heads) + 1)]
    for P, w in default["start"].items():
        lines.append(f"| {P} | " + " | ".join(f"{x / mu0:.4f}" for x in w) + f" | {default['mu_bar_1'][P] / mu0:.4f} |")
    cols = list(zip(*default["start"].values()))
    steady = list(default["mu_bar_1"].values())
    spreads = [(max(c) - min(c)) / mu0 for c in cols]
    lines += ["", f"Over 1-{max(d['pressures'])} MPa mu / mu0 spans {100 * spreads[1]:.1f} % of mu0 at "
              f"{heads[1]}, against {100 * (max(steady) - min(steady)) / mu0:.1f} % in mu_bar."]
    return lines


def separations_markdown(seps: list[dict]) -> list[str]:
    """How far each record separates the floor from a 35 mm sink and from half the debris carried over."""
    if not seps:
        return []
    labels = {o.name: o.label for o in pp.OPTIONS}
    lines = ["", "What tells the floor from the other ways to stop the multi-pass fall (a 35 mm sink, half the debris "
                 "carried over): per record, the largest ratio of the two options' mu_bar (or coverage) over the points "
                 "the record adds, less 1, for the nearer of the two (paper_discriminators.separations), from the "
                 "clearest to the weakest:", "",
             "| record | in the paper's records | separation | at | the floor | the nearer option |", "|---|---|---|---|---|---|"]
    for s in seps:
        near = s["by_option"][s["nearer"]]
        sep = "none" if s["separation"] == 0 else (f"{100 * s['separation']:.0f} %" if math.isfinite(s["separation"])
                                                   else "total")
        lines.append(f"| {s['what']} | {'yes' if s['in_paper'] else 'no'} | {sep} | {near['at']} | "
                     f"{near['floor']:.4g} | {labels[s['nearer']]}: {near['other']:.4g} |")
    weakest = [s for s in seps if s["record"] != "coverage"][-1]
    lines += ["", f"Of the records that tell the floor from both, the weakest is {weakest['what']}; the coverage after "
              "one pass tells a sink only, and measures K / (H h_p)."]
    return lines
