"""What would tell the multi-pass options apart, and debris from a debris-free cause of the one-pass trend
(docs/model.md section 8): predictions of every option of
:data:`tribocosim.cosim.reports.paper_physics.OPTIONS` at the s it was calibrated with on the paper's 35 % one-pass
drop, 35 mm pad, with the pure model of :mod:`tribocosim.cosim.studies.stripdraw_experiment`:

- The drop against pressure (:data:`PRESSURES`, 5-30 MPa, each against 1 MPa on the same pass), after 1, 2 and 3
  passes: the curves of the paper's Fig. 2b. Where flakes carry the contact the floor holds mu_bar at r mu0, so the
  3-pass drop levels off at 1 - r mu0 / mu_bar(1 MPa); a sink or a partial carry-over keeps less debris and the drop
  keeps rising with pressure; the paper's model (r = 0) rises toward 100 %.
- Five passes at :data:`FIVE_PASS_PRESSURE` (10 MPa): mu_bar and the drop after each pass.
- The coverage after one pass (the mean debris fraction beta over the strip that passed under the pad) at 5-25 MPa.
  Without a sink the debris is conserved: the pad makes K P / (H h_p) per unit slide over its area (Eq. 12, 37),
  D L_T of slide-area over a draw D, and all of it ends on the D + L_T of strip that passed under the pad, so
  beta = K P D L_T / (H h_p (D + L_T)) whatever r, zeta or the carry-over: a coverage measured by image analysis
  measures K / (H h_p), the budget's largest chosen input, and tells a sink (less, and bent in P) from none; the
  debris weighed needs h_p besides (beta h_p rho).
- The start of mu(t) at every pressure (the first ``START_LENGTH`` of pass 1, default model; :data:`WINDOWS`): a
  strip point there carries the debris of a few millimetres of slide (beta <= K P x / (H h_p), 0.006 at 25 MPa
  after 1 mm), so a debris-only cause predicts mu near mu0 at every pressure there and the pressure trend growing
  over the draw; a pressure trend present from the start (mu falling with P within the first millimetres) would
  refute debris as its sole cause.

:func:`separations` compares the floor (the default model) with the two options that also stop the multi-pass fall
short of 100 % (a 35 mm sink, half the debris carried over), per record, at the record's most telling point: the
largest ratio of the two options' mu_bar (or coverage) over the record's points, less 1, the smaller over the two
options. A record's points are what it adds: passes 4-5 for five passes (passes 1-3 are the 3-pass test's), the
2- and 3-pass curves at 5-30 MPa for Fig. 2b.
"""

from __future__ import annotations

from pathlib import Path

from tribocosim.cosim.reports.paper_physics import CAL_PAD, OPTIONS
from tribocosim.cosim.studies.stripdraw_experiment import START_LENGTH, Point

#: the pressures of the drop curves [MPa] (each against 1 MPa on the same pass)
PRESSURES = (5, 10, 15, 20, 25, 30)
#: the pressures of the coverage after one pass [MPa]
COVERAGE_PRESSURES = (5, 10, 15, 20, 25)
#: the pressure of the five-pass prediction [MPa] and its passes
FIVE_PASS_PRESSURE, PASSES = 10, 5
#: the windows of draw [m] over which the start of mu(t) is averaged
WINDOWS = ((0.5e-3, 1e-3), (1e-3, 2e-3), (2e-3, 5e-3), (5e-3, 10e-3), (10e-3, START_LENGTH))
#: the options the floor is compared with: the other ways to stop the multi-pass fall
COMPETITORS = ("sink_35", "carry_0.5")
FLOOR_OPTION = "default"
MPA = 1e6


def _points(params: dict) -> dict[int, Point]:
    """An option's tests: 3 passes at every pressure, five at the five-pass pressure and at 1 MPa."""
    return {P: Point(P * MPA, CAL_PAD, PASSES if P in (1, FIVE_PASS_PRESSURE) else 3, params)
            for P in (1, *PRESSURES)}


def predict(runs, options: dict, params: dict) -> dict:
    """Per option (calibrated, ``options`` as paper_physics.calibrated_predictions per name): the drops after passes
    1-3 against pressure, five passes at :data:`FIVE_PASS_PRESSURE`, the coverage after one pass, the start of mu(t)
    per pressure and the clamped lookups of these tests (module docstring). JSON-able: string keys, lists."""
    tests = {}
    for opt in OPTIONS:
        result = options.get(opt.name, {})
        if "scale" in result:
            tests[opt.name] = _points({**params, **opt.parameters, "particle_area_scale": result["scale"]})
    runs.run([p for pts in tests.values() for p in pts.values()])
    from tribocosim.components.stripdraw.component import COMPONENT

    labels = {o.name: o.label for o in OPTIONS}
    out = {"mu0": float(params.get("mu0", COMPONENT.defaults["mu0"])), "pressures": list(PRESSURES), "coverage_pressures": list(COVERAGE_PRESSURES),
           "five_pass_pressure": FIVE_PASS_PRESSURE, "options": {}}
    for name, pts in tests.items():
        low = pts[1]
        drops = {str(k): [1.0 - runs.mu(pts[P], k) / runs.mu(low, k) for P in PRESSURES] for k in (1, 2, 3)}
        five = pts[FIVE_PASS_PRESSURE]
        first = {str(P): runs.result(pts[P], 1) for P in (1, *PRESSURES)}
        out["options"][name] = {
            "label": labels[name], "drops": drops,
            "mu_bar_3": [runs.mu(pts[P], 3) for P in PRESSURES],
            "mu_bar_2": [runs.mu(pts[P], 2) for P in PRESSURES],
            "five": {"mu_bar": [runs.mu(five, k) for k in range(1, PASSES + 1)],
                     "drop": [1.0 - runs.mu(five, k) / runs.mu(low, k) for k in range(1, PASSES + 1)]},
            "coverage": [first[str(P)]["beta_left"] for P in COVERAGE_PRESSURES],
            "start": {P: _windows(r) for P, r in first.items()},
            "mu_bar_1": {P: r["mu_bar"] for P, r in first.items()},
            "clamps": sum(runs.result(p, k)["table_clamps"] for p in pts.values() for k in range(1, p.passes + 1))}
    c = {n: float(params.get(n, COMPONENT.defaults[n]))
         for n in ("archard_k", "hardness", "particle_thickness", "draw_length")}
    out["coverage_closed_form"] = [coverage_without_sink(P * MPA, CAL_PAD, **c) for P in COVERAGE_PRESSURES]
    if FLOOR_OPTION in tests:
        first = {str(P): runs.result(p, 1) for P, p in tests[FLOOR_OPTION].items()}
        out["start_curves"] = {P: {"draw": r["draw_start"], "mu": r["mu_start"]} for P, r in first.items()}
    return out


def coverage_without_sink(pressure: float, tool_length: float, archard_k: float, hardness: float,
                          particle_thickness: float, draw_length: float) -> float:
    """The mean beta over the strip that passed under the pad after one pass without a sink (module docstring):
    K P D L_T / (H h_p (D + L_T))."""
    return (archard_k * pressure * draw_length * tool_length
            / (hardness * particle_thickness * (draw_length + tool_length)))


def _windows(result: dict) -> list[float]:
    """The means of mu(t) over :data:`WINDOWS` of a pass's start."""
    x, mu = result["draw_start"], result["mu_start"]
    out = []
    for a, b in WINDOWS:
        sel = [m for xi, m in zip(x, mu) if a <= xi < b]
        out.append(sum(sel) / len(sel) if sel else float("nan"))
    return out


def _ratio(a: float, b: float) -> float:
    """max(a, b) / min(a, b) - 1 (inf when one is 0 and the other not)."""
    lo, hi = sorted((abs(a), abs(b)))
    return hi / lo - 1.0 if lo > 0 else (0.0 if hi == 0 else float("inf"))


def separations(predicted: dict, five_25: dict, seeded: dict) -> list[dict]:
    """Per record, how far the floor (the default model) lies from the nearer of :data:`COMPETITORS` at the record's
    most telling point (module docstring), with the two options' values there; ``five_25`` and ``seeded`` are
    paper_floor's five passes at 25 MPa and seeded strip. Sorted from the clearest to the weakest."""
    opts = predicted["options"]
    if FLOOR_OPTION not in opts or not all(c in opts for c in COMPETITORS):
        return []
    records = {
        "fig2b": ("the 2- and 3-pass mu_bar at 5-30 MPa (the paper's Fig. 2b)", True,
                  lambda n: opts[n]["mu_bar_2"] + opts[n]["mu_bar_3"],
                  [f"{P} MPa, pass {k}" for k in (2, 3) for P in PRESSURES]),
        "five_10": (f"five passes at {FIVE_PASS_PRESSURE} MPa, passes 4-5 (a new test)", False,
                    lambda n: opts[n]["five"]["mu_bar"][3:], ["pass 4", "pass 5"]),
        "five_25": ("five passes at 25 MPa, passes 4-5 (a new test)", False,
                    lambda n: five_25[n]["mu_bar"][3:], ["pass 4", "pass 5"]),
        "seeded": ("one pass over a seeded strip, every seeding (a new test, debris harvested and weighed)", False,
                   lambda n: seeded[n]["mu_bar"], [f"{g:.3g} g/m^2" for g in seeded[FLOOR_OPTION]["seeded_g_m2"]]),
        "coverage": ("the coverage after one pass at 5-25 MPa (a new test: image analysis)", False,
                     lambda n: opts[n]["coverage"], [f"{P} MPa" for P in COVERAGE_PRESSURES]),
    }
    out = []
    for key, (what, in_paper, values, points) in records.items():
        if key in ("five_25", "seeded") and not all(n in (five_25 if key == "five_25" else seeded)
                                                    for n in (FLOOR_OPTION, *COMPETITORS)):
            continue
        floor = values(FLOOR_OPTION)
        best = {}
        for c in COMPETITORS:
            ratios = [_ratio(f, o) for f, o in zip(floor, values(c))]
            i = max(range(len(ratios)), key=ratios.__getitem__)
            best[c] = {"separation": ratios[i], "at": points[i], "floor": floor[i], "other": values(c)[i]}
        nearer = min(COMPETITORS, key=lambda c: best[c]["separation"])
        out.append({"record": key, "what": what, "in_paper": in_paper, "separation": best[nearer]["separation"],
                    "nearer": nearer, "by_option": best})
    return sorted(out, key=lambda r: -r["separation"])


def plot(predicted: dict, out: Path, name: str = "discriminators.png", floor: float | None = None) -> str:
    """The figure (from :func:`predict`'s JSON-able result): the 3-pass drop against pressure, five passes at
    10 MPa, the coverage after one pass, and mu(t) / mu0 over the first millimetres at each pressure (the default
    model: near 1 at every pressure where little debris has formed yet)."""
    from tribocosim.cosim.studies.plotting import _pyplot

    plt = _pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(9.4, 7.0))
    (a, b), (c, d) = axes
    P = predicted["pressures"]
    for n, r in predicted["options"].items():
        a.plot(P, [100 * x for x in r["drops"]["3"]], "o-", ms=3, lw=1.2, label=r["label"])
        b.plot(range(1, len(r["five"]["mu_bar"]) + 1), r["five"]["mu_bar"], "o-", ms=3, lw=1.2, label=r["label"])
        c.plot(predicted["coverage_pressures"], r["coverage"], "o-", ms=3, lw=1.2, label=r["label"])
    a.plot([25], [72], "k*", ms=9, label="the paper: up to 72 % at 25 MPa")
    a.set(xlabel="P_N [MPa]", ylabel="3-pass drop against 1 MPa [%]", title="the 3-pass drop against pressure "
          "(Fig. 2b's curve)")
    b.set(xlabel="pass", ylabel="mu_bar", title=f"five passes at {predicted['five_pass_pressure']} MPa",
          xticks=range(1, PASSES + 1))
    if floor:
        b.axhline(floor, color="k", lw=0.8, ls="--")
        b.text(1, floor, " the floor r mu0", va="bottom", fontsize=7)
    b.set_ylim(bottom=0.0)
    c.set(xlabel="P_N [MPa]", ylabel="coverage beta after one pass", title="coverage after one pass")
    for P, curve in predicted.get("start_curves", {}).items():
        d.plot([1e3 * x for x in curve["draw"]], [m / predicted["mu0"] for m in curve["mu"]], lw=1.0,
               label=f"{P} MPa")
    d.set(xlabel="draw [mm]", ylabel="mu(t) / mu0", title="the start of mu(t), the default model",
          ylim=(0.6, 1.05))
    for ax in (a, b, c, d):
        ax.grid(True, alpha=0.3)
        ax.title.set_fontsize(9)
    a.legend(fontsize=6)
    d.legend(fontsize=6, ncol=2)
    fig.suptitle("Each option at its s calibrated on the paper's 35 % one-pass drop (35 mm pad)", fontsize=9)
    fig.tight_layout()
    fig.savefig(Path(out) / name, dpi=110)
    plt.close(fig)
    return name
