"""The text of the paper report (``paper.md``): the paper-vs-model table and the sections of
:mod:`tribocosim.cosim.reports.paper_physics` (options, the uncertainty budget and the observable chosen beside it,
the drawing speed, alpha of both observables, the table's checks) and of :mod:`tribocosim.cosim.reports.paper_floor`
(the floor's prediction at 25 MPa; their text and the budget's: :mod:`.paper_text_predictions`), from the numbers :func:`tribocosim.cosim.reports.paper.run_report` computed."""

from __future__ import annotations

import math
from pathlib import Path

from tribocosim.components.stripdraw.friction_floor import FLAKE_SHEAR_RATIO_DEFAULT, MU_FLOOR
from tribocosim.cosim.studies.stripdraw_experiment import V0
from tribocosim.cosim.reports import paper_text_predictions as ptp
from tribocosim.cosim.reports.paper_text_predictions import pct as _pct
from tribocosim.cosim.reports import paper_physics as pp
from tribocosim.cosim.reports.paper_physics import CAL_PRESSURE




#: an entry is set by the floor when its mu_bar at the high pressure lies within this factor of r mu0
FLOOR_MARGIN = 1.1


def _set_by_floor(mu: float, floor: float) -> str:
    """" (floor)" when ``mu`` lies within :data:`FLOOR_MARGIN` of the floor r mu0 > 0: the entry is the floor the
    project sets re-expressed, not a prediction."""
    return " (floor)" if floor > 0 and mu <= FLOOR_MARGIN * floor else ""


def _row_values(m: dict, cal, grid, shear: float, floor: float) -> dict[str, str]:
    at = m["drop_at_mpa"]
    pads = m["mu_by_pad"]
    return {
        "shear": f"{shear:g}",
        "scale": (f"{cal.scale:.4g} +- {cal.stderr:.2g}" if cal else "1"),
        "drop1": _pct(m["drop_1pass"]) + (" (calibrated)" if cal else ""),
        "drop3": _pct(m["drop_by_pass"][grid.passes]) + _set_by_floor(m["mu_at_drop"][grid.passes], floor),
        "pads": " / ".join(_pct(m["drop_by_pad"][p]) + _set_by_floor(pads[p][at], floor) for p in grid.pads),
        "order": f"{'yes' if m['pad_order_holds'][0] == m['pad_order_holds'][1] else 'no'} "
                 f"({m['pad_order_holds'][0]} of {m['pad_order_holds'][1]} pressures)",
        "zeta": ("falls: " if m["zeta_falls"] else "does not fall: ")
                + " / ".join(f"{m['mu_by_zeta'][z]:.4f}" + _set_by_floor(m["mu_by_zeta"][z], floor)
                             for z in grid.zetas),
        "k": ("falls" if m["k_falls"] else "does not fall") + ", "
             + ("saturates" if m["k_saturates"] else "does not saturate") + ": "
             + " / ".join(f"{m['mu_by_k'][K]:.4f}" + _set_by_floor(m["mu_by_k"][K], floor) for K in grid.ks),
        "mu_low": f"{m['mu_low']:.4f}",
        "beta": f"{m['beta_max_3pass']:.3g} ({m['beta_max']:.3g})",
        "clamps": str(m["table_clamps"]),
        "_at": at,
    }


def table_contact_ratio(table, kappa: float = 2.0, rms_slope: float = 0.34, e_star: float = 55e9) -> float | None:
    """A_c of Eq. 8 (kappa P / (h'_rms E*), the strip model's defaults) over the table's particle-free A_c at 25 MPa
    and the test's velocity."""
    if table.version < 2:
        return None
    ac, _ = table.interpolate_array(table.contact_area, CAL_PRESSURE, V0, 0.0)
    return float(kappa * CAL_PRESSURE / (rms_slope * e_star) / ac) if ac > 0 else None


def results_table(results: dict, cals: dict, grid) -> list[str]:
    """The paper-vs-model table: one column per configuration, entries the floor sets marked "(floor)"."""
    configs = list(results)
    shear = {c: 0.0 if c.paper_model else FLAKE_SHEAR_RATIO_DEFAULT for c in configs}
    values = {c: _row_values(results[c]["metrics"], cals.get(c.key) if c.calibrated else None, grid, shear[c],
                             pp.floor_of({"flake_shear_ratio": shear[c]})) for c in configs}
    at = grid.pressures[-2] if 25 not in grid.pressures else 25
    pads = " / ".join(f"{1000 * p:g}" for p in grid.pads)
    rows = [
        ("flake-borne shear ratio r", "0 (frictionless flakes)", "shear"),
        ("A_p scale s (+- standard error)", "-", "scale"),
        (f"mu_bar drop at {at} MPa, 1 pass, 35 mm pad", "35 %", "drop1"),
        (f"mu_bar drop at {at} MPa after {grid.passes} passes, 35 mm pad", "up to 72 %", "drop3"),
        (f"mu_bar drop at {at} MPa, 1 pass, {pads} mm pads", "grows with pad length (Fig. 19b)", "pads"),
        ("pad ordering mu(35) > mu(70) > mu(140) above 1 MPa", "yes (Figs. 2a, 19b)", "order"),
        (f"mu_bar at {grid.trend_at:g} MPa for zeta = " + " / ".join(f"{z:g}" for z in grid.zetas),
         "falls with zeta (Fig. 17b)", "zeta"),
        (f"mu_bar at {grid.trend_at:g} MPa for K = " + " / ".join(f"{K:g}" for K in grid.ks),
         "falls with K and saturates (Fig. 18b)", "k"),
        (f"mu_bar at {min(grid.pressures)} MPa, 35 mm pad", "-", "mu_low"),
        (f"largest beta after {grid.passes} passes at {at} MPa (in any test)", "-", "beta"),
        ("table lookups outside the table's axes or simulated range (clamped)", "-", "clamps"),
    ]
    lines = ["| quantity | paper | " + " | ".join(c.label for c in configs) + " |", "|---|---|" + "---|" * len(configs)]
    for title, paper, key in rows:
        lines.append(f"| {title} | {paper} | " + " | ".join(values[c][key] for c in configs) + " |")
    return lines


def table_note() -> str:
    """What the table's entries are: which one is fitted, which the floor sets, which are predicted."""
    return ("Drops are 1 - mu_bar(P) / mu_bar(1 MPa) on the same curve (same pad, same pass). Only the one-pass drop at "
            "25 MPa is fitted (by s, per column). The columns without the paper's model use the default "
            f"r = {FLAKE_SHEAR_RATIO_DEFAULT:g}: flake-borne shear at the floor mu = {MU_FLOOR:g} the project sets, a "
            "bound chosen, not measured (docs/model.md, the floor under debris). An entry marked (floor) is set by "
            f"that choice, not predicted: its mu_bar at the high pressure lies within {100 * (FLOOR_MARGIN - 1):.0f} % "
            "of r mu0, where flakes carry the whole contact, so the value is the floor re-expressed (a 3-pass drop at "
            "most 1 - r mu0 / mu_bar(1 MPa), the report's floor scan). The other entries are predictions.")


def markdown(results: dict, cals: dict, grid, table, table_path: Path, header: str, files: list[str]) -> str:
    """The report text: the paper-vs-model table, the calibrations, links to the figures and data."""
    lines = [header, "", *results_table(results, cals, grid)]
    ratio = table_contact_ratio(table)
    lines += ["", table_note() + f" The table's beta axis ends at {table.beta[-1]:.4g}."
              + (f" The eq8 column is the first up to the factor A_c(Eq. 8) / A_c(table) = {ratio:.3g} at 25 MPa "
                 f"on A_p / A_c: its s is {cals['eq8'].scale / cals['mesoscale'].scale:.3g} times the first's."
                 if ratio and "eq8" in cals and "mesoscale" in cals else ""), ""]
    for conv, cal in cals.items():
        lines.append(f"- `{conv}`: s = {cal.scale:.6g}, standard error {cal.stderr:.3g} (quote of the 35 %: "
                     f"{cal.stderr_quote:.3g}, through d drop/ds = {cal.slope:.4g}; ensemble means of the table: "
                     f"{cal.stderr_ensemble:.3g}); drop reached {_pct(cal.drop)} in {cal.evaluations} strip-draw "
                     "tests.")
    from tribocosim.paths import DEFAULT_TABLE

    shipped = Path(table_path).resolve() == Path(DEFAULT_TABLE).resolve()
    table_text = "`models/friction_table.npz` (the shipped one)" if shipped else f"`{table_path}`"
    lines += ["", f"Friction table: {table_text}. Figures: " + ", ".join(f"[{f}]({f})" for f in files)
              + "; every test's mu_bar: [paper.csv](paper.csv), the numbers: [paper.json](paper.json).", ""]
    return "\n".join(lines)


def physics_markdown(extra: dict, cals: dict, grid, m: dict, clamps: dict) -> list[str]:
    """The sections after the paper-vs-model table (paper_physics): options, budget, the observable chosen, speed,
    alpha, checks; ``m`` the calibrated mesoscale column's metrics, ``clamps`` its clamped lookups per figure."""

    lines = ["", "## Multi-pass options", "",
             "Each option calibrated on the one-pass 35 % alone (A_c from the table); the paper: 35 % after one pass, up "
             "to 72 % after three. The default model has flake-borne shear at the floor the project sets; the sink and the "
             "partial carry-over are shown on the paper's model (r = 0), as other ways than a floor to limit the "
             "multi-pass drop. What would tell them apart: the spacing of the 2- and 3-pass drops, the 140 mm pad's "
             "drop, the debris weighed on the strip after each pass (beta h_p rho over the strip that was under the "
             "pad), and the predictions at the end of this report (five passes, a seeded strip, the drops against "
             "pressure, the coverage after one pass, the start of mu(t)).", "",
             "| option | why these values | s | drop 1 / 2 / 3 passes at 25 MPa | 3-pass minus 2-pass | 140 mm pad, 1 pass "
             "| debris after pass 1 / 2 / 3 [g/m^2] | clamped lookups |", "|---|---|---|---|---|---|---|---|"]
    for opt in pp.OPTIONS:
        r = extra["options"].get(opt.name, {})
        if "error" in r:
            lines.append(f"| {opt.label} | {opt.why} | cannot be calibrated: {r['error']} | | | | | |")
            continue
        lines.append(f"| {opt.label} | {opt.why} | {r['scale']:.4g} | " + " / ".join(_pct(d) for d in r["drops"])
                     + f" | {100 * r['spacing_3_2']:.1f} points | {_pct(r['drop_140'])} | "
                     + " / ".join(f"{g:.3g}" for g in r["debris_g_m2"]) + f" | {r['clamps']} |")
    nominal = extra["options"]["default"]
    cal = cals["mesoscale"]
    band = extra["budget"]["intervals"]
    lines += ptp.budget_markdown(extra["budget"], nominal, cal)
    lines += ptp.floor_scan_markdown(extra["budget"]["floor_scan"])
    lines += paper_model_beside(extra["options"].get("paper", {}), nominal)
    lines += ptp.prediction_markdown(extra["prediction"]) + [""]
    lines += ptp.discriminators_markdown(extra["discriminators"]) + [""]
    lines += observable_markdown(extra["observable"], nominal)
    lines += ["## Drawing speed", "",
              f"mu_bar at 25 MPa on the 35 mm pad (s = {cal.scale:.3g}, over its interval {band['scale'][0]:.3g} to "
              f"{band['scale'][1]:.3g}: the range in brackets), and the drop against 1 MPa at the same speed. The "
              "table's A_p (every load-bearing flake, the default observable) is simulated at "
              f"{' / '.join(f'{v:g}' for v in extra['simulated_velocities']) or 'no recorded'} m/s, where it does not "
              "depend on v0 (docs/physics/table_domain.md); the paper's alpha(v) (Fig. 15, its cluster rule, "
              "1-50 m/s), rising with v0, would make the debris effect grow from 0.08 to 0.5 m/s, which nothing "
              "simulated here at these speeds shows.", "",
              "| V0 [m/s] | mu_bar, 1 pass | drop, 1 pass | mu_bar, 3 passes | drop, 3 passes |", "|---|---|---|---|---|"]
    for r in extra["speed"]:
        lines.append(f"| {r['velocity']:g} | {r['mu_1']:.4f} [{r['mu_1_band'][0]:.4f}, {r['mu_1_band'][1]:.4f}] | "
                     f"{_pct(r['drop_1'])} | {r['mu_3']:.4f} [{r['mu_3_band'][0]:.4f}, {r['mu_3_band'][1]:.4f}] | "
                     f"{_pct(r['drop_3'])} |")
    by_v = {r["velocity"]: r for r in extra["speed"]}
    if 0.08 in by_v and 0.5 in by_v and by_v[0.08]["drop_1"] > 0:
        lines += ["", f"The one-pass drop at 0.5 m/s is {by_v[0.5]['drop_1'] / by_v[0.08]['drop_1']:.3f} times that at "
                      f"0.08 m/s, the three-pass drop {by_v[0.5]['drop_3'] / by_v[0.08]['drop_3']:.3f} times."]
    lines += ["", "## alpha of both observables", ""]
    if not extra["alpha"]["load_bearing"]:
        lines.append("The friction table is format version 2: it holds A_p of every load-bearing flake only, not that "
                     "of the paper's cluster rule; a version 3 or 4 table gives alpha of both here.")
    else:
        lines += ["Eq. 23's alpha = A_p / A0 / (beta P / E*) at the table's first debris level, mean over the pressures "
                  "(+- standard error), for every load-bearing flake (the observable the model uses) and for the "
                  "paper's cluster rule alone (the observable of the paper's Fig. 15):", "",
                  "| v [m/s] | every load-bearing flake | cluster rule alone |", "|---|---|---|"]
    for a, c in zip(extra["alpha"]["load_bearing"], extra["alpha"]["clusters"]):
        lines.append(f"| {a['velocity']:g} | {a['alpha']:.4g} +- {a['stderr']:.2g} | {c['alpha']:.3g} +- "
                     f"{c['stderr']:.2g} |")
    study = extra["alpha"].get("study")
    if study:
        lines += ["", f"The alpha(v) study ({study.get('source', 'docs/physics/alpha_velocity.md')}), 1-50 m/s, "
                      "mean +- standard error:", "", "| setting | observable | " + " | ".join(
                          f"{float(v):g} m/s" for v in study["velocities"]) + " | alpha(50)/alpha(1) |",
                  "|---|---|" + "---|" * (len(study["velocities"]) + 1)]
        for name, entry in study["settings"].items():
            for key, label in (("all", "every load-bearing flake"), ("clusters", "cluster rule alone")):
                cells = [f"{entry[key][str(v)][0]:.3g} +- {entry[key][str(v)][1]:.2g}" if str(v) in entry[key] else "-"
                         for v in study["velocities"]]
                ratio = entry["ratio_50_1"][key]
                lines.append(f"| {entry['label']} | {label} | " + " | ".join(cells)
                             + f" | {ratio[0]:.3g} +- {ratio[1]:.2g} |")
        ratios = [e["ratio_50_1"]["all"][0] for e in study["settings"].values()]
        cluster = [v[0] for e in study["settings"].values() for v in e["clusters"].values()]
        lines += ["", f"Every load-bearing flake: alpha(50)/alpha(1) from {min(ratios):.3g} to {max(ratios):.3g} over "
                      "the settings, below 1 wherever the oil damps the flakes (docs/physics/alpha_velocity.md). The "
                      f"cluster rule alone: alpha {max(cluster):.2g} at most, zero in {sum(c == 0 for c in cluster)} of "
                      f"{len(cluster)} cells: too sparse to test the shape of Fig. 15; where it is non-zero at the least "
                      "damping it grows with v0, as Fig. 15 does, within the standard errors shown."]
    lines += sizes_markdown(extra["alpha"].get("sizes"))
    lines += ["", "## The friction table's checks", ""]
    checks = extra.get("direct_slides", [])
    if checks:
        lines += ["Direct slides at points between the table's nodes (the table's own sweep settings) against the "
                  "table's interpolation, on A_p and on mu = mu0 (1 - A_p / A_c): within two combined standard errors?",
                  "", "| P [MPa] | v [m/s] | beta | members | A_p/A0 direct | A_p/A0 table | A_p: difference / combined "
                  "SE | mu direct | mu table | mu: difference / combined SE | nodes read all simulated | passes |",
                  "|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for c in checks:
            mu = (f"{c['mu_direct']:.4g} +- {c['mu_direct_se']:.2g} | {c['mu_table']:.4g} +- {c['mu_table_se']:.2g} | "
                  f"{c['mu_difference_over_combined_se']:+.2f}" if c.get("mu_table_se") is not None
                  and c["mu_table_se"] == c["mu_table_se"] else "- | - | -")
            lines.append(f"| {c['pressure'] / 1e6:g} | {c['velocity']:g} | {c['beta']:.3g} | {c['members']} | "
                         f"{c['a_p_direct']:.4g} +- {c['a_p_direct_se']:.2g} | {c['a_p_table']:.4g} +- "
                         f"{c['a_p_table_se']:.2g} | {c['difference_over_combined_se']:+.2f} | {mu} | "
                         f"{'yes' if c['all_nodes_simulated'] else 'no'} | {'yes' if c['passed'] else 'NO'} |")
    else:
        lines.append("The table is not version 3 or 4 with its campaign recorded: no direct-slide check.")
    lines += ["", "Clamped lookups (outside the table's axes or its simulated range) in every test of the calibrated "
                  "column, by figure: " + ", ".join(f"{k}: {v}" for k, v in clamps.items()) + ".", "",
              "mu_bar(P) on the three pads (calibrated column):", "",
              "| P [MPa] | " + " | ".join(f"{1000 * pad:g} mm" for pad in grid.pads) + " |",
              "|---|" + "---|" * len(grid.pads)]
    for P in grid.pressures:
        lines.append(f"| {P:g} | " + " | ".join(f"{m['mu_by_pad'][pad][P]:.4f}" for pad in grid.pads) + " |")
    return lines


def paper_model_beside(paper: dict, nominal: dict) -> list[str]:
    """The paper's model (r = 0) beside the budget's default model."""
    if "error" in paper:
        return [f"The paper's model (r = 0) cannot be calibrated on the 35 %: {paper['error']}", ""]
    return [f"The paper's model (frictionless flakes, r = 0, below r's sourced range and so not an end of its row), "
            f"calibrated the same way: s = {paper['scale']:.3g}, the 3-pass drop {_pct(paper['drops'][2])} and the "
            f"140 mm pad's one-pass drop {_pct(paper['drop_140'])}, against {_pct(nominal['drops'][2])} and "
            f"{_pct(nominal['drop_140'])} of the default model (the budget's other inputs are not varied for it).", ""]


def observable_markdown(observable: dict, nominal: dict) -> list[str]:
    """The section on the observable: the choice, its evidence, and the predictions of the other choice."""
    ev, other = observable["evidence"], observable["choice"]
    lines = ["## Model choice: the observable", "",
             "Which flakes carry A_p in Eq. 7 is a choice of the model (`particle_area_rule`): every load-bearing "
             "flake (the default: the cluster rule of Fig. 8, pinched and held flakes; docs/model.md section 4) or the "
             "paper's cluster rule alone. It is not an input with a range, so it is not summed into the budget. The "
             "evidence, at the level the paper's macro model reads:", ""]
    lines.append(f"- The paper's own macro model (A_c of Eq. 8 with kappa = {ev['kappa']:g}, h'_rms = "
                 f"{ev['rms_slope']:g}, Eq. 23 linear in beta, Eq. 9: the closed-form law) needs alpha = "
                 f"{ev['alpha_needed']:.3g} at {ev['velocity']:g} m/s for the 35 % one-pass drop at 25 MPa.")
    for rule, label in (("load_bearing", "every load-bearing flake"), ("clusters", "the cluster rule alone")):
        e = ev.get(rule)
        if e:
            lines.append(f"- The share A_p / A_c of {label} in the table at its first debris level (beta = "
                         f"{ev['beta']:.3g}, {ev['velocity']:g} m/s) times Eq. 8's A_c gives alpha_eff = "
                         f"(A_p / A_c) kappa / (h'_rms beta) = {e['alpha_eff_25mpa']:.3g} at 25 MPa "
                         f"({e['alpha_eff_min']:.3g} to {e['alpha_eff_max']:.3g} over the table's pressures).")
    lines += ["", "At the contact area the macro model reads, the load-bearing share gives the alpha that model needs, "
              "the cluster rule's is orders of magnitude below it.", ""]
    if "error" in other:
        lines += [f"With the cluster rule alone the 35 % cannot be reached: {other['error']}", ""]
    else:
        lines += [f"With the cluster rule alone, s = {other['scale']:.4g} is needed for the 35 % (against "
                  f"{nominal['scale']:.4g}), and the model predicts the 3-pass drop {_pct(other['drops'][2])} (against "
                  f"{_pct(nominal['drops'][2])}) and the 140 mm pad's one-pass drop {_pct(other['drop_140'])} (against "
                  f"{_pct(nominal['drop_140'])}).", ""]
    return lines


def sizes_markdown(sizes: dict | None) -> list[str]:
    """The cluster rule at the paper's flake sizes (models/cluster_rule_sizes.json), or nothing when not shipped."""
    if not sizes:
        return []
    rows = {k: r for k, r in sizes["sizes"].items() if k != "none"}
    if not rows:
        return []
    r0 = next(iter(rows.values()))
    lines = ["", f"The paper's flake sizes ({sizes['source']}; {sizes['finished']} of {sizes['cases']} slides, "
                 f"{r0['pressure'] / 1e6:g} MPa, {r0['velocity']:g} m/s, a 512 um domain, mean +- standard error over "
                 "the members): alpha of Eq. 23 and alpha_eff = (A_p / A_c) kappa / (h'_rms beta), the alpha of the "
                 "paper's macro model at the slide's own contact area, for both observables:", "",
             "| d_p [um] | beta | members | cluster rule / every load-bearing | alpha, every | alpha, cluster rule | "
             "alpha_eff, every | alpha_eff, cluster rule |", "|---|---|---|---|---|---|---|---|"]

    def cell(pair):
        m, se = pair
        return "-" if m is None or not math.isfinite(m) else f"{m:.3g} +- {se:.2g}"

    for r in rows.values():
        lb, cl = r["load_bearing"], r["clusters"]
        lines.append(f"| {1e6 * r['flake_diameter']:g} | {r['beta']:.3g} | {r['members']} | {cell(r['cluster_share'])} "
                     f"| {cell(lb['alpha'])} | {cell(cl['alpha'])} | {cell(lb['alpha_eff'])} | "
                     f"{cell(cl['alpha_eff'])} |")
    return lines

