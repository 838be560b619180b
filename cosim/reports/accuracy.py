"""Work-precision families of ``tribocosim report accuracy``: error against cost, one function per family.

Each family can run alone (``family(settings) -> Family``); :data:`FAMILIES` lists them in
report order. Errors are relative (:mod:`tribocosim.cosim.reports.metrics`); costs are wall times on the
machine the report runs on (the load average is recorded with them) and, for the master, the
number of ``doStep`` calls summed over the FMUs (rejected attempts and step-doubling probes
included).

``oscillator``
    The linear two-mass oscillator of the tests (k2 = 10, 10 s) split into two FMUs; every
    algorithm x extrapolation order x fixed step, and the two adaptive estimators x tolerance
    (Jacobi, extrapolation 1). Error: max |x1 - x1_exact| / max |x1_exact| against the closed
    form (:class:`tribocosim.cosim.studies.monolithic.TwoMassOscillator`).
``demo``
    ``models/scenes/demo.toml`` (press + strip + drawing machine) shortened in quick mode; the
    same settings. Error: max |F - F_ref| / max |F_ref| of ``strip.pull_force`` against the
    monolithic reference (:func:`tribocosim.cosim.studies.monolithic.reference_for_scene`, the pure
    models coupled implicitly with a tiny step ``dt_ref``), interpolated linearly onto the
    communication points. The step-doubling rows run the strip on its internal time grid
    (``internal_step`` = :data:`DEMO_INTERNAL_STEP`, with ``step_quantum`` the same and ``min_step``
    twice it: without the grid the strip's outputs are first order in its own step and the step collapses to
    min_step) and are measured against a reference with the same ``internal_step``; the
    other rows keep the scene's strip (no grid) and its reference.
``stripdraw``
    The pure strip-draw model (no FMI), explicit central difference vs generalized-alpha
    ("implicit", 1 ms steps) x number of elements, on a short draw. Errors against a fine explicit
    run: relative error of mu_bar (mean mu over the last 20 % of the draw) and max |beta -
    beta_ref| / max beta_ref of the final debris field (interpolated linearly onto the
    reference's material coordinates).
``surrogate``
    Friction-table grid density x interpolation error at held-out mesoscale points x build cost,
    read from the result file of ``benchmarks/bench_table.py``; the report does not run
    mesoscale campaigns.
``bem``
    The Fourier-BEM contact solver on one band-limited self-affine surface sampled on n x n grids:
    the surface is generated once on the finest grid with its spectrum cut at q_s = 16 (2 pi / L),
    below the Nyquist wavenumber of the coarsest grid (32 (2 pi / L) at n = 64), and each coarser grid
    takes every k-th point, so every grid holds exact samples of the same physical surface.
    Error: |A_c/A0 - A_c/A0(finest)| / A_c/A0(finest) at p = 10 MPa (p_crit = 340 MPa); cost: solve
    wall time.
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

import numpy as np

from tribocosim.cosim.reports.common import Family, Settings, packaged_scene, scratch, started_at_once, timed
from tribocosim.cosim.reports.coupling_order import coupling_order
from tribocosim.cosim.reports.metrics import max_relative_error, relative_difference
from tribocosim.cosim.reports.near_pcrit import near_pcrit
from tribocosim.cosim.reports.oscfmus import Unavailable, oscillator_fmus, oscillator_scene
from tribocosim.cosim.reports.runner import failed_row, master_row

TARGETS = (1e-2, 1e-3, 1e-4)
#: demo: the errors after the ramps are measured from this time on [s]
T_STEADY = 0.1
#: demo, step-doubling rows: the strip's internal_step [s], also the controller's step_quantum (min_step twice it).
#: Without the grid the strip's outputs are first order in its own step, the error per unit step that step
#: doubling controls does not fall as the step shrinks and the step collapses to min_step.
DEMO_INTERNAL_STEP = 5e-5
#: demo: convergence of the reference's coupling per step (relative). The strip's Newton solve stops at 1e-10 of its
#: force scale, so its pull force is defined to a few 1e-10 only; at 1e-10 the fixed point can cycle between two
#: such answers (measured: a 2-cycle of 1.6e-10 at t = 1.676 s with internal_step = 2.5e-5 s, dt_ref = 5e-5 s).
DEMO_REFERENCE_TOL = 1e-9
#: demo: finer fixed steps of Jacobi with extrapolation 1 (the adaptive rows' scheme) [s]
DEMO_FINE_STEPS = (2e-4, 1e-4, 5e-5)
SCHEMES = [(a, q) for a in ("jacobi", "gauss-seidel", "iterative") for q in (0, 1, 2)]


def _master_settings(quick: bool, steps_quick, steps_full, tols_quick, tols_full, estimators):
    steps = steps_quick if quick else steps_full
    out = [(f"{a}/{q}", f"{a} q={q} h={h:g}", dict(algorithm=a, extrapolation=q, step=h, adaptive=None))
           for a, q in SCHEMES for h in steps]
    for est in estimators:
        for tol in (tols_quick if quick else tols_full):
            out.append((f"adaptive {est}", f"{est} tol={tol:g}",
                        dict(algorithm="jacobi", extrapolation=1, step=None, adaptive=dict(tolerance=tol, estimator=est))))
    return out


@timed
def oscillator(settings: Settings) -> Family:
    """The two-mass oscillator (k2 = 10): master settings vs the closed form."""
    from tribocosim.cosim.studies.monolithic import TwoMassOscillator
    from tribocosim.cosim.reports.runner import run_plan
    from tribocosim.cosim.scene.validate import load_scene

    title = "Two-mass oscillator (k2 = 10 N/m, 10 s): error of x1 against wall time"
    try:
        fmus = oscillator_fmus()
    except Unavailable as exc:
        return Family.unavailable("oscillator", title, str(exc))
    stop = 10.0
    budget = 30.0 if settings.quick else 300.0
    work = scratch(settings, "accuracy-oscillator")
    ref = TwoMassOscillator()
    run_plan(load_scene(oscillator_scene(work, fmus, step=0.1, stop=0.2)))  # warm-up: extraction, imports
    fam = Family("oscillator", title, curve="curve", error="error", cost="wall_time", label="setting")
    fam.note = ("Error: max |x1 - x1_exact| / max |x1_exact| over the communication points (closed form: "
                "tribocosim.cosim.studies.monolithic.TwoMassOscillator). Cost: wall time of the run (building the master, instantiation, initialization, loop; after a warm-up run) and "
                "doStep calls of both FMUs. Adaptive runs: Jacobi with extrapolation 1, initial step 0.01 s, "
                f"min_step 1e-6 s, max_step 1 s. A run is stopped after {budget:g} s of wall time.")
    for curve, setting, s in _master_settings(settings.quick, (0.1, 0.05, 0.02, 0.01),
                                              (0.2, 0.1, 0.05, 0.02, 0.01, 0.005, 0.002, 0.001),
                                              (1e-2, 1e-3, 1e-4), (1e-2, 1e-3, 1e-4, 1e-5, 1e-6),
                                              ("step-doubling", "energy")):
        ad = None
        if s["adaptive"]:
            ad = dict(tolerance=s["adaptive"]["tolerance"], min_step=1e-6, max_step=1.0,
                      estimator=s["adaptive"]["estimator"])
        scene = oscillator_scene(work, fmus, step=s["step"] or 0.01, stop=stop, algorithm=s["algorithm"],
                                 extrapolation=s["extrapolation"], adaptive=ad)
        try:
            res = run_plan(load_scene(scene), budget=budget)
            t = res["time"]
            err = max_relative_error(t, res["columns"]["a.x1"], t, ref.solve(t)["a.x1"])
            fam.rows.append(master_row(curve, setting, res, err))
        except Exception as exc:  # an unstable or failing setting is a data point, not a crash
            fam.rows.append(failed_row(curve, setting, exc))
        settings.log(f"  oscillator {setting}: error {fam.rows[-1]['error']:.3g}")
    return fam


@timed
def demo(settings: Settings) -> Family:
    """demo.toml: master settings vs the monolithic reference."""
    from tribocosim.cosim.studies.monolithic import reference_for_scene
    from tribocosim.cosim.reports.runner import run_plan
    from tribocosim.cosim.scene.validate import load_scene

    quick = settings.quick
    budget = 20.0 if quick else 60.0
    title = "Demo scene (press + strip + drawing machine): error of pull_force against wall time"
    path = packaged_scene("demo")
    stop = 0.3 if quick else 1.76
    # 5e-5 s in both modes: at 1e-4 s the reference is itself ~6e-4 off at the start of the draw, and at
    # dt_ref = DEMO_INTERNAL_STEP the step-doubling rows' reference is the same run (computed once)
    dt_ref = 5e-5
    over = {"experiment.stop": stop, **started_at_once(load_scene(path))}
    grid_over = {**over, "fmus.strip.parameters.internal_step": DEMO_INTERNAL_STEP}
    n_ref = int(round(stop / dt_ref))
    t_ref = dt_ref * np.arange(n_ref + 1)
    f_refs, ref_times = {}, {}
    for key, o in (("plain", over), ("grid", grid_over)):  # the scene's strip; on the internal grid
        if key == "grid" and dt_ref == DEMO_INTERNAL_STEP:  # each reference step is one grid interval: the grid
            f_refs[key], ref_times[key] = f_refs["plain"], ref_times["plain"]  # cuts nothing (bit-identical)
            continue
        t0 = time.perf_counter()
        try:
            reference = reference_for_scene(load_scene(path, o), dt_ref, tol=DEMO_REFERENCE_TOL)
            f_refs[key] = reference.solve(t_ref)["strip.pull_force"]
        except Exception as exc:
            return Family.unavailable("demo", title, f"the monolithic reference failed: {type(exc).__name__}: {exc}")
        ref_times[key] = time.perf_counter() - t0
    ref_time = ref_times["plain"]
    grid_ref_note = ("the same as the other: with dt_ref = internal_step each reference step is one grid interval"
                     if f_refs["grid"] is f_refs["plain"] else
                     f"{ref_times['grid']:.1f} s to compute; it differs from the other by "
                     f"{float(np.max(np.abs(f_refs['grid'] - f_refs['plain'])) / np.max(np.abs(f_refs['plain']))):.2g} "
                     f"of max |F_ref|")
    settings.log(f"  demo: reference (dt = {dt_ref:g} s) in {ref_time:.1f} s; with internal_step = "
                 f"{DEMO_INTERNAL_STEP:g} s: {grid_ref_note}")
    fam = Family("demo", title, curve="curve", error="error", cost="wall_time", label="setting",
                 errors=("error", "error_after_ramps"),
                 summary_curves=("jacobi/1", "adaptive step-doubling", "adaptive energy"))
    fam.note = (f"demo.toml with the drive started at once (start_time = 0: both ramps overlap) and stop = {stop} s"
                f"{' (quick mode: the velocity ramp and the start of the steady draw)' if quick else ''}. "
                f"Error: max |F - F_ref| / max |F_ref| of strip.pull_force over the communication points; F_ref is the "
                f"monolithic reference (cosim.studies.monolithic.reference_for_scene: pure models, coupling solved every "
                f"step to {DEMO_REFERENCE_TOL:g}, dt_ref = {dt_ref:g} s, {ref_time:.1f} s to compute), interpolated linearly (the "
                f"reference's own error at the start of the draw, measured against dt_ref = 2.5e-5 s: about 2e-4 at "
                f"dt_ref = 5e-5 s, 6e-4 at 1e-4 s, so errors below 2e-4 are not resolved); error_after_ramps: the same "
                f"over t >= {T_STEADY:g} s (after the press's 50 ms force ramp and the drive's 20 ms velocity ramp; the "
                f"largest errors are at the start of the draw, t ~ 10 ms, where they fall only as O(h)). In the fixed-step "
                f"and energy rows the strip's own discretization follows the communication step (its implicit integrator "
                f"takes the step it is given), so the error is coupling + strip time discretization. Adaptive runs: Jacobi, "
                f"extrapolation 1, initial step 1 ms, max_step 0.05 s; energy: min_step 1e-6 s, the power bond "
                f"strip.pull_force -> drive.pull_force / drive.grip_velocity -> strip.grip_velocity; step doubling: the "
                f"strip on its internal time grid, internal_step = {DEMO_INTERNAL_STEP:g} s, step_quantum the same, "
                f"min_step {2 * DEMO_INTERNAL_STEP:g} s, so that one step H and two steps H/2 take the same strip intervals "
                f"and the estimate sees the coupling error alone (without the grid the strip's first-order lag holds the "
                f"error per unit step constant and the step collapses to min_step); its error is against a "
                f"reference with the same internal_step ({grid_ref_note}). A run is stopped after {budget:g} s of wall "
                f"time (error reported as inf, the status says so).")
    run_plan(load_scene(path, {"experiment.stop": 0.01}))  # warm-up: FMU extraction, imports, compilation
    bond = [{"effort": ["strip.pull_force", "drive.pull_force"], "flow": ["drive.grip_velocity", "strip.grip_velocity"]}]
    plan_rows = _master_settings(quick, (4e-3, 2e-3, 1e-3), (8e-3, 4e-3, 2e-3, 1e-3, 5e-4), (1e-2, 1e-3),
                                 (1e-2, 1e-3, 1e-4), ("step-doubling", "energy"))
    # the adaptive rows' scheme down to the fixed steps that reach 0.1 % over the whole run (the start of the draw)
    last = max(i for i, row in enumerate(plan_rows) if row[0] == "jacobi/1")
    plan_rows[last + 1:last + 1] = [("jacobi/1", f"jacobi q=1 h={h:g}", dict(algorithm="jacobi", extrapolation=1, step=h,
                                                                            adaptive=None)) for h in DEMO_FINE_STEPS]
    for curve, setting, s in plan_rows:
        doubling = bool(s["adaptive"]) and s["adaptive"]["estimator"] == "step-doubling"
        o = dict(grid_over if doubling else over)
        o.update({"master.algorithm": s["algorithm"], "master.extrapolation": s["extrapolation"],
                  "experiment.step": s["step"] or 1e-3})
        if doubling:
            o["master.adaptive"] = dict(tolerance=s["adaptive"]["tolerance"], min_step=2 * DEMO_INTERNAL_STEP,
                                        max_step=0.05, estimator="step-doubling", step_quantum=DEMO_INTERNAL_STEP)
        elif s["adaptive"]:
            o["master.adaptive"] = dict(tolerance=s["adaptive"]["tolerance"], min_step=1e-6, max_step=0.05,
                                        estimator=s["adaptive"]["estimator"])
            o["power_bonds"] = bond
        o = {k: v for k, v in o.items() if v is not None}
        f_ref = f_refs["grid" if doubling else "plain"]
        try:
            res = run_plan(load_scene(path, o), budget=budget)
            t, f = res["time"], res["columns"]["strip.pull_force"]
            err = max_relative_error(t, f, t_ref, f_ref)
            late = t >= T_STEADY
            err_late = (max_relative_error(t[late], f[late], t_ref, f_ref, scale=float(np.max(np.abs(f_ref))))
                        if late.any() else math.nan)
            fam.rows.append(master_row(curve, setting, res, err, error_after_ramps=err_late if not res["stopped"]
                                        else math.inf, internal_step=DEMO_INTERNAL_STEP if doubling else 0.0))
        except Exception as exc:
            fam.rows.append(failed_row(curve, setting, exc, internal_step=DEMO_INTERNAL_STEP if doubling else 0.0))
        settings.log(f"  demo {setting}: error {fam.rows[-1]['error']:.3g} in {fam.rows[-1]['wall_time']:.2f} s")
    return fam


def _strip_run(integrator: str, n: int, draw: float, step: float = 1e-3):
    from tribocosim.cosim.studies.stripdraw_experiment import run_strip_draw, steady_mean

    t0 = time.perf_counter()
    _, outs, model = run_strip_draw(integrator=integrator, draw_length=draw, n_elements=n, step=step)
    wall = time.perf_counter() - t0
    return wall, steady_mean(outs), model.mesh.X.copy(), model.beta.copy(), model


@timed
def stripdraw(settings: Settings) -> Family:
    """The strip-draw bar: explicit vs implicit x mesh, against a fine explicit run."""
    quick = settings.quick
    draw = 0.01 if quick else 0.035
    meshes = (25, 50, 100, 200) if quick else (30, 60, 120, 240, 480)
    n_ref = 400 if quick else 960
    title = f"Strip-draw bar ({draw * 1e3:.0f} mm draw, 35 mm pad, 10 MPa): explicit vs implicit x mesh"
    _strip_run("explicit", 20, 0.001)  # load the core library outside the timings
    _strip_run("implicit", 20, 0.001)
    w_ref, mu_ref, x_ref, b_ref, m_ref = _strip_run("explicit", n_ref, draw)
    settings.log(f"  stripdraw: reference explicit n = {n_ref} in {w_ref:.1f} s, mu_bar = {mu_ref:.6f}")
    fam = Family("stripdraw", title, curve="curve", error="error_mu_bar", cost="wall_time", label="setting")
    fam.errors = ("error_mu_bar", "error_beta")
    fam.note = (f"Pure model (no FMI), shipped friction table, velocity ramp 10 ms, output step 1 ms (the implicit "
                f"integrator's step; the explicit one sub-cycles at 0.9 x its stability limit). Reference: explicit, "
                f"{n_ref} elements ({w_ref:.1f} s, mu_bar = {mu_ref:.6f}). error_mu_bar = |mu_bar - mu_bar_ref| / "
                f"mu_bar_ref (mean of mu_mean over the last 20 % of the draw); error_beta = max |beta - beta_ref| / "
                f"max beta_ref of the final field, on the reference's nodes (linear interpolation in the material "
                f"coordinate).")
    for integ in ("explicit", "implicit"):
        for n in meshes:
            wall, mu, x, beta, model = _strip_run(integ, n, draw)
            eb = float(np.max(np.abs(np.interp(x_ref, x, beta) - b_ref)) / np.max(np.abs(b_ref)))
            fam.rows.append({"curve": integ, "setting": f"{integ} n={n}", "n_elements": n, "wall_time": wall,
                             "mu_bar": mu, "error_mu_bar": relative_difference(mu, mu_ref), "error_beta": eb,
                             "explicit_dt": model.explicit_time_step if integ == "explicit" else math.nan})
            settings.log(f"  stripdraw {integ} n={n}: {wall:.2f} s, mu error {fam.rows[-1]['error_mu_bar']:.2e}, "
                         f"beta error {eb:.2e}")
    return fam


def _rel(path: Path, root: Path) -> str:
    try:
        return str(Path(path).resolve().relative_to(root))
    except ValueError:
        return str(path)


SURROGATE_RESULTS = ("docs/reports/bench_table.json", "benchmarks/bench_table.json", "bench_table.json")


@timed
def surrogate(settings: Settings, result_file: str | Path | None = None) -> Family:
    """Friction-table grid density vs hold-out interpolation error, from benchmarks/bench_table.py's JSON."""
    title = "Friction table: grid density x hold-out interpolation error x build cost"
    root = Path(__file__).resolve().parents[2]
    cands = [Path(result_file)] if result_file else [root / c for c in SURROGATE_RESULTS]
    found = next((c for c in cands if c.is_file()), None)
    if found is None:
        return Family.unavailable("surrogate", title, "no result of the hold-out measurement (benchmarks/bench_table.py) "
                                  "was found at " + ", ".join(_rel(c, root) for c in cands) + "; produce it with "
                                  "`python benchmarks/bench_table.py --json docs/reports/bench_table.json` and rerun")
    data = json.loads(found.read_text())
    fam = Family("surrogate", title, curve="curve", error="error", cost="build_core_seconds", label="setting")
    rows = data.get("grids", [])
    for r in rows:
        mu_ref = (r.get("mu_at_10mpa_0p08") or [math.nan])[0]
        fam.rows.append({"curve": "table grid", "setting": f"{r['grid']} ({len(r['pressures_mpa'])} P x "
                                                           f"{len(r['velocities'])} v)",
                         "cases": r["cases"], "build_core_seconds": r["case_core_seconds"] + r["fit_and_table_s"],
                         "rms_abs_error": r["rms_error"], "max_abs_error": r["max_abs_error"],
                         "error": r["max_abs_error"] / mu_ref if mu_ref and math.isfinite(mu_ref) else math.nan,
                         "holdout_noise": r.get("holdout_mean_std_error_of_mean", math.nan)})
    fam.note = (f"Read from {_rel(found, root)} ({data.get('holdout_points')} held-out points; {data.get('load_before', '')}). "
                "error = max |mu_table - mu_meso| at the held-out points / mu of that table at 10 MPa, 0.08 m/s, "
                "beta = 0; cost = core-seconds of the grid's mesoscale cases + fit and table build. holdout_noise is "
                "the mean standard error of the held-out ensemble means (errors below it are not resolved).")
    return fam


@timed
def bem(settings: Settings) -> Family:
    """Fourier-BEM: grid size vs error in A_c/A0 against the finest grid vs solve time."""
    title = "Fourier-BEM contact: grid size x error in A_c/A0 (against the finest grid) x solve time"
    try:
        from tribocosim.surrogate.bem import ContactSolver, gap_against_flat
        from tribocosim.surrogate.surfaces import self_affine_surface
    except ImportError as exc:
        return Family.unavailable("bem", title, f"tribocosim.surrogate.bem cannot be imported: {exc}")
    quick = settings.quick
    grids = (64, 128, 256, 512) if quick else (64, 128, 256, 512, 1024, 2048)
    size, q0 = 500e-6, 2 * math.pi / 500e-6
    n_f = grids[-1]
    h = self_affine_surface(n_f, size, 0.8, 2 * q0, 16 * q0, rms_slope=0.34, seed=1)
    p, pc, e_star = 10e6, 340e6, 55e9
    res = {}
    for n in grids:
        k = n_f // n
        gap = gap_against_flat(h[::k, ::k])
        solver = ContactSolver(n, size, e_star, pc, tol=1e-8)
        best = math.inf
        for _ in range(1 if quick or n >= 1024 else 3):
            t0 = time.perf_counter()
            r = solver.solve(gap, p)
            best = min(best, time.perf_counter() - t0)
        res[n] = (r, best)
        settings.log(f"  bem n={n}: A_c/A0 = {r.contact_area_fraction:.5f} in {best:.3f} s ({r.iterations} iterations)")
    ac_ref = res[n_f][0].contact_area_fraction
    fam = Family("bem", title, curve="curve", error="error", cost="wall_time", label="setting")
    fam.note = (f"One surface: L = 500 um, H = 0.8, RMS slope 0.34 (spectral), PSD from q_r = 2 (2 pi/L) to q_s = 16 "
                f"(2 pi/L), seed 1, generated on the {n_f}^2 grid and downsampled by taking every k-th point (the spectrum "
                f"is below every grid's Nyquist wavenumber, so each grid samples the same band-limited surface). E* = "
                f"55 GPa, p = 10 MPa, p_crit = 340 MPa, tolerance 1e-8; the {n_f}^2 grid is the reference "
                f"(A_c/A0 = {ac_ref:.5f}). Wall time: best of 3 solves ({'1 in quick mode' if quick else '1 at 1024^2 and above'}).")
    for n in grids[:-1]:
        r, wall = res[n]
        fam.rows.append({"curve": "BEM grid", "setting": f"n={n}", "n": n, "wall_time": wall,
                         "iterations": r.iterations, "contact_area_fraction": r.contact_area_fraction,
                         "error": relative_difference(r.contact_area_fraction, ac_ref)})
    r, wall = res[n_f]
    fam.rows.append({"curve": "reference", "setting": f"n={n_f} (reference)", "n": n_f, "wall_time": wall,
                     "iterations": r.iterations, "contact_area_fraction": r.contact_area_fraction, "error": math.nan})
    return fam


#: report order: name -> family function
FAMILIES = {"oscillator": oscillator, "demo": demo, "coupling_order": coupling_order, "near_pcrit": near_pcrit,
            "stripdraw": stripdraw, "surrogate": surrogate, "bem": bem}
