"""The floor's prediction at 25 MPa (docs/model.md, "The floor under debris"): what five passes and a seeded strip
would show for the default model, the paper's model and the other multi-pass options.

Every option of :data:`tribocosim.cosim.reports.paper_physics.OPTIONS` runs at the s it was calibrated with on the
paper's 35 % one-pass drop (so all of them agree on the first pass), on the 35 mm pad with the pure model of
:mod:`tribocosim.cosim.studies.stripdraw_experiment`:

- Five passes over one strip without cleaning (:func:`five_passes`) at 25 MPa (and 1 MPa for the drop): mu_bar and
  the debris weighed after each pass (beta h_p rho over the strip that was under the pad). With flake-borne shear
  (r > 0) mu_bar levels off near r mu0 once flakes carry the contact; the paper's model (r = 0) with every flake
  carried over keeps falling toward 0; a sink or a partial carry-over levels off where the debris made balances the
  debris lost, at a mu_bar set by how much stays.
- A seeded strip (:func:`seeded_strip`): one pass at 25 MPa over a clean strip, re-oiled, seeded with a known debris
  beta0 (``beta_initial``, at most the law's largest cap over the table, which the model checks; the cap at 25 MPa,
  Eq. 24, takes what exceeds it there), reported as the debris seeded, beta0 h_p rho.
  The seeding fixes the debris whatever the options' balances: mu_bar against the debris seeded levels at r mu0 with
  r > 0 and falls toward 0 with r = 0; the carry-over option is then the paper's model, and a sink takes part of
  the seeded debris during the pass.

How well each tells them apart is measured by
:func:`tribocosim.cosim.reports.paper_discriminators.separations`: at 25 MPa the floor, a 35 mm sink and half the
debris carried over level off near each other over passes 4-5 (the weakest of the records; the report gives by how
much), while
the seeded strip holds r mu0 against a sink's lower plateau and the frictionless flakes' fall; the seeded debris
stands for a coverage only through the assumed h_p.
"""

from __future__ import annotations

from pathlib import Path

from tribocosim.cosim.studies.stripdraw_experiment import FLAKE_DENSITY, Point
from tribocosim.cosim.reports.paper_physics import CAL_PAD, CAL_PRESSURE, LOW_PRESSURE, OPTIONS

#: the passes of the prediction
PASSES = 5
#: debris area fractions seeded on a clean strip (the cap takes what exceeds it)
SEEDED_BETAS = (0.0, 0.1, 0.2, 0.3, 0.45, 0.6, 0.8, 1.0)


def seeded_g_m2(beta: float, particle_thickness: float = 0.5e-6) -> float:
    """The debris seeded on the strip, weighed per unit area [g/m^2]: beta h_p rho (flakes of Al)."""
    return 1e3 * beta * particle_thickness * FLAKE_DENSITY


def _options(options: dict, params: dict) -> list[tuple]:
    """(option, its parameters at its calibrated s) for every option that could be calibrated."""
    out = []
    for opt in OPTIONS:
        result = options.get(opt.name, {})
        if "scale" in result:
            out.append((opt, {**params, **opt.parameters, "particle_area_scale": result["scale"]}))
    return out


def five_passes(runs, options: dict, params: dict) -> dict:
    """Per option: mu_bar, the drop against 1 MPa and the debris weighed after passes 1-5 at 25 MPa (module
    docstring); ``options`` are paper_physics.calibrated_predictions per option name, ``params`` the report's
    strip-draw parameters."""
    tests = {opt.name: (Point(CAL_PRESSURE, CAL_PAD, PASSES, p), Point(LOW_PRESSURE, CAL_PAD, PASSES, p))
             for opt, p in _options(options, params)}
    runs.run([pt for pair in tests.values() for pt in pair])
    out = {}
    for name, (high, low) in tests.items():
        passes = range(1, PASSES + 1)
        out[name] = {"mu_bar": [runs.mu(high, k) for k in passes],
                     "drop": [1.0 - runs.mu(high, k) / runs.mu(low, k) for k in passes],
                     "debris_g_m2": [runs.result(high, k)["debris_g_m2"] for k in passes],
                     "clamps": sum(runs.result(pt, k)["table_clamps"] for pt in (high, low) for k in passes)}
    return out


def largest_cap(params: dict) -> float:
    """The law's largest cap of beta over the table's nodes (``beta_threshold``), which bounds the initial debris."""
    from tribocosim.components.stripdraw.component import COMPONENT

    return float(COMPONENT.make(params).model.law.beta_threshold)


def seeded_strip(runs, options: dict, params: dict) -> dict:
    """Per option: mu_bar of one pass at 25 MPa over a strip seeded with each of :data:`SEEDED_BETAS`, at most the
    option's :func:`largest_cap` (module docstring), and the debris seeded and left."""
    tests = {}
    for opt, p in _options(options, params):
        cap = largest_cap(p)
        tests[opt.name] = [Point(CAL_PRESSURE, CAL_PAD, 1, {**p, "beta_initial": min(b, cap)}) for b in SEEDED_BETAS]
    runs.run([pt for pts in tests.values() for pt in pts])
    return {name: {"seeded_g_m2": [seeded_g_m2(pt.parameters["beta_initial"]) for pt in pts],
                   "mu_bar": [runs.mu(pt) for pt in pts],
                   "debris_left_g_m2": [runs.result(pt)["debris_g_m2"] for pt in pts],
                   "clamps": sum(runs.result(pt)["table_clamps"] for pt in pts)}
            for name, pts in tests.items()}


def plot(prediction: dict, floor: float, out: Path) -> str:
    """floor.png: mu_bar against the pass at 25 MPa, and against the debris seeded on a clean strip, per option,
    with the documented floor."""
    from tribocosim.cosim.studies.plotting import _pyplot

    plt = _pyplot()
    labels = {o.name: o.label for o in OPTIONS}
    fig, (a, b) = plt.subplots(1, 2, figsize=(9.0, 3.6))
    for name, r in prediction["five_passes"].items():
        a.plot(range(1, PASSES + 1), r["mu_bar"], "o-", ms=3, lw=1.2, label=labels[name])
    for name, r in prediction["seeded"].items():
        b.plot(r["seeded_g_m2"], r["mu_bar"], "o-", ms=3, lw=1.2, label=labels[name])
    for ax, xlabel, title in ((a, "pass", "five passes without cleaning, 25 MPa"),
                              (b, "debris seeded on a clean re-oiled strip [g/m^2]", "one pass over a seeded strip, "
                                                                                     "25 MPa")):
        ax.axhline(floor, color="k", lw=0.8, ls="--")
        ax.text(ax.get_xlim()[0], floor, " documented floor", va="bottom", fontsize=7)
        ax.set_xlabel(xlabel)
        ax.set_title(title, fontsize=9)
        ax.set_ylim(bottom=0.0)
        ax.grid(True, alpha=0.3)
    a.set_ylabel("mu_bar (35 mm pad)")
    a.legend(fontsize=6.5)
    fig.suptitle("Each option at its s calibrated on the paper's 35 % one-pass drop", fontsize=9)
    fig.tight_layout()
    fig.savefig(out / "floor.png", dpi=110)
    plt.close(fig)
    return "floor.png"
