"""Accuracy-report family ``coupling_order``: the order of the coupling error on the demo rig.

``models/scenes/demo.toml`` with the strip on its internal time grid (``internal_step`` =
:data:`INTERNAL_STEP`): friction, contact overlaps and debris are updated every internal step, also within
a communication step H, and the native StripDraw FMU takes its inputs' time derivatives
(``canInterpolateInputs``; the master passes the extrapolation polynomial's Taylor coefficients through
``fmi2SetRealInputDerivatives``, :mod:`tribocosim.cosim.engine.system`). The press and the drawing machine hold
their inputs at the polynomial's mean over the step. The strip's own time discretization is then the same
for every H, so what changes with H is the coupling alone, and its error is

    e(H) = max_{t >= T_STEADY} |F_H(t) - F_tau(t)| / max |F_tau|

of ``strip.pull_force``, where F_tau is the same scheme at H = ``internal_step`` (the limit of the coupling
for this discretization: with H = tau every input is sampled at every internal step). The observed order is
the least-squares slope of log e against log H over the steps of a curve. Polynomial extrapolation of degree
q gives global order q + 1 for smooth signals (Kübler & Schiehlen 2000); after the press's force ramp and the
drive's velocity ramp (which have kinks: t < T_STEADY) the signals are smooth, so Jacobi and Gauss-Seidel
with q = 1 should show order 2 and q = 0 order 1.

The fixed-step rows of the ``demo`` family measure the same runs against the monolithic reference instead,
whose own first-order time discretization floors their error (its difference from F_tau is in the note).
"""

from __future__ import annotations

import math

import numpy as np

from tribocosim.cosim.reports.common import Family, Settings, packaged_scene, started_at_once, timed
from tribocosim.cosim.reports.runner import failed_row, master_row, run_plan

#: the strip's internal step [s] (as the demo family's step-doubling rows)
INTERNAL_STEP = 5e-5
#: the errors are measured from this time on [s]: after the 50 ms force ramp and the 20 ms velocity ramp
T_STEADY = 0.1
STOP = 0.3
#: (algorithm, extrapolation) of the curves
CURVES = (("jacobi", 1), ("gauss-seidel", 1), ("jacobi", 0))
STEPS_FULL = (4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4)
STEPS_QUICK = (4e-3, 2e-3, 1e-3)


def fitted_order(steps, errors) -> float:
    """Least-squares slope of log(error) against log(step); NaN with fewer than two finite positive errors."""
    pts = [(math.log(h), math.log(e)) for h, e in zip(steps, errors) if e > 0 and math.isfinite(e)]
    if len(pts) < 2:
        return math.nan
    x, y = np.array(pts).T
    return float(np.polyfit(x, y, 1)[0])


@timed
def coupling_order(settings: Settings) -> Family:
    """The demo rig on the strip's internal grid: coupling error against the communication step, fitted order."""
    from tribocosim.cosim.reports.metrics import max_relative_error
    from tribocosim.cosim.scene.validate import load_scene

    title = "Demo rig, strip on its internal grid: coupling error against the communication step (order)"
    path = packaged_scene("demo")
    steps = STEPS_QUICK if settings.quick else STEPS_FULL
    base = {"experiment.stop": STOP, "fmus.strip.parameters.internal_step": INTERNAL_STEP,
            **started_at_once(load_scene(path))}  # the drive at once: the ramps and the start of the draw
    fam = Family("coupling_order", title, curve="curve", error="error", cost="wall_time", label="setting")
    orders = {}
    for algorithm, q in CURVES:
        curve = f"{algorithm}/{q}"

        def run(h):
            return run_plan(load_scene(path, {**base, "master.algorithm": algorithm, "master.extrapolation": q,
                                              "experiment.step": h}), budget=120.0)

        try:
            ref = run(INTERNAL_STEP)
        except Exception as exc:  # noqa: BLE001 - one failed curve is a row, not the end of the report
            fam.rows.append(failed_row(curve, f"{algorithm} q={q} h={INTERNAL_STEP:g} (reference)", exc))
            continue
        t_ref, f_ref = ref["time"], ref["columns"]["strip.pull_force"]
        late_ref = t_ref >= T_STEADY
        scale = float(np.max(np.abs(f_ref)))
        errors = []
        for h in steps:
            setting = f"{algorithm} q={q} h={h:g}"
            try:
                res = run(h)
                t, f = res["time"], res["columns"]["strip.pull_force"]
                late = t >= T_STEADY
                err = max_relative_error(t[late], f[late], t_ref[late_ref], f_ref[late_ref], scale=scale)
                fam.rows.append(master_row(curve, setting, res, err, step=h,
                                           error_whole_run=max_relative_error(t, f, t_ref, f_ref)))
            except Exception as exc:  # noqa: BLE001
                fam.rows.append(failed_row(curve, setting, exc, step=h))
            errors.append(fam.rows[-1]["error"])
            settings.log(f"  coupling_order {setting}: error {errors[-1]:.3g}")
        orders[curve] = fitted_order(steps, errors)
    lines = ["| curve | fitted order (after the ramps) | steps [ms] |", "|---|---|---|"]
    for curve, p in orders.items():
        lines.append(f"| {curve} | {p:.2f} | {', '.join(f'{h * 1e3:g}' for h in steps)} |")
    fam.extra_md = "Observed order of the coupling error (slope of log e against log H):\n\n" + "\n".join(lines) + "\n"
    fam.note = (f"demo.toml, stop = {STOP} s, strip internal_step = {INTERNAL_STEP:g} s (friction, contact and debris "
                f"updated every internal step within a communication step; the native strip takes the extrapolated "
                f"inputs' derivatives through fmi2SetRealInputDerivatives, the press and the drive hold the step mean). "
                f"Error: max |F_H - F_tau| / max |F_tau| of strip.pull_force over t >= {T_STEADY:g} s, F_tau the same "
                f"scheme with H = internal_step (the coupling's limit for this strip discretization); "
                f"error_whole_run: the same from t = 0 (ramps included). Order: least-squares slope of log e against "
                f"log H. " + "; ".join(f"{c}: order {p:.2f}" for c, p in orders.items()) + ".")
    return fam
