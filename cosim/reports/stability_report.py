"""Stability families of ``tribocosim report stability``: a matrix of cases x schemes, one function per family.

Every cell runs the case with the scheme at its nominal step and judges the run with the
criterion of :mod:`tribocosim.cosim.reports.stability_criterion` (stable / unstable with the reason / error with the
message), and finds the largest stable step by bisection (:func:`~tribocosim.cosim.reports.stability_criterion.largest_stable_step`).

``oscillator``
    The linear two-mass oscillator (FMUs of the tests), coupling stiffness k2 from 10 to 1e7 N/m;
    each run lasts 8 periods of the stiff mode (at least 200 steps; at most ``max_steps``, and
    never fewer than 3 periods). Bound: 10 x the closed form's max |.| of x1, x2 and the force.
    The Jacobi/0 column also shows the limit predicted from the exact one-step map
    (:mod:`tribocosim.cosim.reports.monodromy`).
``stiff_drive``
    ``models/scenes/stiff_drive.toml`` with the drawing machine's drive stiffness
    from 1e4 to 1e9 N/m. Bound: |pull_force| <= 10 x (2 mu0 F_N + 2 rho c A V0) (friction capacity plus the
    force of the elastic wave a velocity step launches) and |grip_velocity| <= 10 x the set-point.
``demo``
    ``models/scenes/demo.toml`` through the master: the nominal case, P_N just below p_crit, grip
    velocity set-point 0, and a step as large as the whole draw.
``stripdraw``
    The pure strip-draw model (where the integrator, not the coupling scheme, is the question):
    stiff cases (interface penalty k_s x 1e3, a bar mesh 8 x finer) and extreme cases (P_N from 1 kPa to
    just below p_crit, grip velocity 0, a reversing grip, K = 1 so that beta saturates at once,
    zeta = 0 and 1, a 140 mm pad with a 140 mm draw) x integrators (explicit; implicit with
    1 ms, 10 ms and one step as long as the whole draw). Bound: |pull_force| <= 10 x (2 mu0 F_N + 2 rho c A V0).
"""

from __future__ import annotations

import math
import time

import numpy as np

from tribocosim.cosim.reports.common import Family, Settings, instance_of, packaged_scene, scratch, started_at_once, timed
from tribocosim.cosim.reports.oscfmus import Unavailable, oscillator_fmus, oscillator_scene
from tribocosim.cosim.reports.stability_criterion import ERROR, STABLE, UNSTABLE, Criterion, Verdict, classify, largest_stable_step

CRITERION = Criterion()
#: a bisection through the master never tries steps longer than the run / MIN_STEPS (fewer points cannot show growth)
MIN_STEPS = 30
ALL_SCHEMES = [(a, q) for a in ("jacobi", "gauss-seidel", "iterative") for q in (0, 1, 2)]
#: full-mode schemes for the scenes of our components (each run costs seconds, not milliseconds)
SCENE_SCHEMES = [("jacobi", 0), ("jacobi", 1), ("jacobi", 2), ("gauss-seidel", 0), ("gauss-seidel", 1), ("iterative", 0),
                 ("iterative", 1)]


def _scheme_name(a: str, q: int) -> str:
    return f"{a}/{q}"


def step_limit(judge, nominal: float, nominal_verdict: Verdict, lo: float, hi: float, rel: float):
    """Largest stable step, anchored at the nominal step's verdict: above it when it is stable (up to
    ``hi``), below it when it is not (down to ``lo``, presumed stable and run only if reached)."""
    if nominal_verdict.stable:
        if nominal >= hi:
            return largest_stable_step(judge, nominal, nominal * 1.0001, rel=rel, lazy_lo=True)
        return largest_stable_step(judge, nominal, hi, rel=rel, lazy_lo=True)
    if nominal_verdict.status == ERROR and "Error" in nominal_verdict.reason and "Convergence" not in nominal_verdict.reason \
            and "CosimStep" not in nominal_verdict.reason:
        return None  # a setup error, not a step-size question
    return largest_stable_step(judge, min(lo, nominal / 2), nominal, rel=rel, lazy_lo=True, hi_verdict=nominal_verdict)


def _cell_row(case: str, scheme: str, verdict: Verdict, limit, **extra) -> dict:
    row = {"case": case, "scheme": scheme, "status": verdict.status, "reason": verdict.reason,
           "growth": verdict.growth, "peak_ratio": verdict.peak_ratio,
           "observed_contraction": verdict.extra.get("observed_contraction", math.nan)}
    if limit is not None:
        row.update({"stable_step": limit.stable_step, "unstable_step": limit.unstable_step,
                    "limit_reason": limit.reason, "evaluations": limit.evaluations})
    row.update(extra)
    return row


# --------------------------------------------------------------------------- oscillator
def _fast_period(k2: float) -> float:
    from tribocosim.cosim.studies.monolithic import TwoMassOscillator

    lam = np.linalg.eigvals(TwoMassOscillator(k2=k2).matrix())
    return 2 * math.pi / float(np.max(np.abs(lam.imag)))


@timed
def oscillator(settings: Settings) -> Family:
    """Two-mass oscillator, k2 = 10 ... 1e7: schemes x stiffness."""
    from tribocosim.cosim.studies.monolithic import TwoMassOscillator
    from tribocosim.cosim.reports.monodromy import jacobi0_limit
    from tribocosim.cosim.reports.runner import judged_run
    from tribocosim.cosim.scene.validate import load_scene

    title = "Two-mass oscillator: coupling stiffness k2 x scheme"
    try:
        fmus = oscillator_fmus()
    except Unavailable as exc:
        return Family.unavailable("oscillator", title, str(exc))
    quick = settings.quick
    k2s = (10.0, 1e3, 1e5) if quick else (10.0, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7)
    schemes = [("jacobi", 0), ("jacobi", 1), ("gauss-seidel", 0), ("iterative", 1)] if quick else ALL_SCHEMES
    max_steps = 20000 if quick else 100000
    rel = 0.05 if quick else 0.02
    h0 = 1e-3
    work = scratch(settings, "stability-oscillator")
    fam = Family("oscillator", title)
    fam.note = (f"Nominal step {h0:g} s. A run lasts 8 periods of the stiff mode (at least 200 steps, at most "
                f"{max_steps} steps but never fewer than 3 periods). Largest stable step: log bisection to "
                f"{100 * rel:g} % between 1e-5 x the stiff period (presumed stable, checked if the bisection reaches "
                f"it) and 0.2 s. Jacobi/0 'predicted': the spectral radius of the exact one-step map "
                f"(cosim.reports.monodromy).")
    for k2 in k2s:
        period = _fast_period(k2)
        ref = TwoMassOscillator(k2=k2)

        def judge(h, alg, q, k2=k2, period=period, ref=ref):
            t_end = max(8 * period, 200 * h)
            if t_end / h > max_steps:
                t_end = max(3 * period, max_steps * h)
            n = max(1, int(round(t_end / h)))
            scene = oscillator_scene(work, fmus, step=h, stop=n * h, algorithm=alg, extrapolation=q, k2=k2)
            ex = ref.solve(np.linspace(0.0, n * h, 4001))
            scales = {v: float(np.max(np.abs(ex[v]))) for v in ("a.x1", "b.x2", "b.force")}
            verdict, _ = judged_run(load_scene(scene), scales, CRITERION, budget=120.0)
            return verdict

        pred = jacobi0_limit(k2)
        for alg, q in schemes:
            t0 = time.perf_counter()
            v0 = judge(h0, alg, q)
            lim = step_limit(lambda h: judge(h, alg, q), h0, v0, 1e-5 * period, 0.2, rel)
            extra = {"k2": k2, "nominal_step": h0, "predicted_limit": pred if (alg, q) == ("jacobi", 0) else math.nan,
                     "wall_time": time.perf_counter() - t0}
            fam.rows.append(_cell_row(f"k2 = {k2:g} N/m", _scheme_name(alg, q), v0, lim, **extra))
            settings.log(f"  stability oscillator k2={k2:g} {alg}/{q}: {v0.short()}; limit {lim.describe()} "
                         f"({extra['wall_time']:.1f} s)")
    return fam


# --------------------------------------------------------------------------- scenes with our components
def _component_scales(plan) -> dict[str, float]:
    """Reference magnitudes: pull_force (:func:`pull_force_scale`), grip_velocity the larger of |set-point| and
    the release speed F / sqrt(k_d m) of the drive: a grip that breaks away lets the drivetrain (stiffness k_d)
    spring the carriage (mass m) forward with the pull force F it held, which near p_crit is far above the
    set-point (measured: the monolithic reference reaches 13 x the set-point at 0.99 p_crit; F / sqrt(k_d m)
    there is 15 x). Set-point and parameters from the scene or the defaults."""
    from tribocosim.cosim.scene.component_checks import component_of

    found = {name: comp for name, spec in plan.scene.fmus.items() if (comp := component_of(spec)) is not None}
    params = {name: comp.split(plan.scene.fmus[name].parameters)[0] for name, comp in found.items()}
    by_kind = {comp.name: params[name] for name, comp in found.items()}
    fn = by_kind["press"].force_setpoint if "press" in by_kind else None
    v = abs(by_kind["drawingmachine"].velocity_setpoint) if "drawingmachine" in by_kind else 0.08
    scales = {}
    strips = [name for name, comp in found.items() if comp.name == "stripdraw"]
    for name in strips:
        if fn:
            scales[f"{name}.pull_force"] = pull_force_scale(params[name], fn, v)
    force = max((scales.get(f"{name}.pull_force", 0.0) for name in strips), default=0.0)
    for name, comp in found.items():
        if comp.name == "drawingmachine" and v > 0:
            m = params[name]
            scales[f"{name}.grip_velocity"] = max(v, force / math.sqrt(m.drive_stiffness * m.carriage_mass))
    return scales


def _scene_cells(settings, fam, path, cases, schemes, stop, lo, hi, rel, budget):
    """Run each (case overrides) x scheme at the scene step, bisect the step; append rows."""
    from tribocosim.cosim.reports.runner import judged_run
    from tribocosim.cosim.scene.validate import load_scene

    for case, over, step in cases:
        for alg, q in schemes:
            t0 = time.perf_counter()
            base = {**over, "master.algorithm": alg, "master.extrapolation": q, "experiment.stop": stop}

            def judge(h, base=base):
                o = dict(base)
                o["experiment.step"] = h
                plan = load_scene(path, o)
                return judged_run(plan, _component_scales(plan), CRITERION, budget=budget)[0]

            try:
                h_nom = step if step is not None else load_scene(path, base).scene.experiment.step
                v0 = judge(h_nom)
                lim = step_limit(judge, h_nom, v0, lo, min(hi, stop / MIN_STEPS), rel) if lo else None
            except Exception as exc:  # a scene that cannot even be loaded
                v0, lim, h_nom = Verdict(ERROR, f"{type(exc).__name__}: {' '.join(str(exc).split())[:240]}"), None, math.nan
            fam.rows.append(_cell_row(case, _scheme_name(alg, q), v0, lim, nominal_step=h_nom,
                                      wall_time=time.perf_counter() - t0))
            settings.log(f"  stability {fam.name} {case} {alg}/{q}: {v0.short()}"
                         + (f"; limit {lim.describe()}" if lim else "") + f" ({time.perf_counter() - t0:.1f} s)")


@timed
def stiff_drive(settings: Settings) -> Family:
    """stiff_drive.toml: drive stiffness 1e4 ... 1e9 N/m x scheme."""
    from tribocosim.cosim.scene.validate import load_scene

    title = "Stiff drive: drivetrain stiffness x scheme (stiff_drive.toml)"
    path = packaged_scene("stiff_drive")
    try:
        plan = load_scene(path)
        drive = instance_of(plan, "drawingmachine")
    except Exception as exc:
        return Family.unavailable("stiff_drive", title, f"stiff_drive.toml does not load: {exc}")
    if drive is None:
        return Family.unavailable("stiff_drive", title, "stiff_drive.toml has no component = \"drawingmachine\" FMU")
    quick = settings.quick
    ks = (1e4, 1e6, 1e8, 1e9) if quick else (1e4, 1e5, 1e6, 1e7, 1e8, 1e9)
    schemes = [("jacobi", 0), ("gauss-seidel", 0), ("iterative", 1)] if quick else SCENE_SCHEMES
    stop = min(plan.scene.experiment.stop, 0.1 if quick else 0.4)
    fam = Family("stiff_drive", title)
    fam.note = (f"stiff_drive.toml with the creep started at once (start_time = 0) and fmus.{drive}.parameters."
                f"drive_stiffness overridden, stop = {stop:g} s, at the "
                f"scene's step; largest stable step by log bisection to {'20' if quick else '5'} % in "
                f"[1e-6 s, {stop / MIN_STEPS:g} s] (a run has at least {MIN_STEPS} steps).")
    at_once = started_at_once(plan)
    cases = [(f"k_d = {k:g} N/m", {**at_once, f"fmus.{drive}.parameters.drive_stiffness": k}, None) for k in ks]
    _scene_cells(settings, fam, path, cases, schemes, stop, 1e-6, stop, 0.2 if quick else 0.05,
                 budget=30.0 if quick else 120.0)
    for r in fam.rows:
        r["drive_stiffness"] = float(r["case"].split("=")[1].split()[0])
    return fam


@timed
def demo(settings: Settings) -> Family:
    """demo.toml through the master: nominal, P_N near p_crit, grip velocity 0, one step for the whole draw."""
    from tribocosim.cosim.scene.validate import load_scene

    title = "Demo scene through the master: extreme inputs x scheme"
    path = packaged_scene("demo")
    try:
        plan = load_scene(path)
        press, strip, drive = (instance_of(plan, c) for c in ("press", "stripdraw", "drawingmachine"))
    except Exception as exc:
        return Family.unavailable("demo", title, f"demo.toml does not load: {exc}")
    if None in (press, strip, drive):
        return Family.unavailable("demo", title, "demo.toml lacks one of the press / stripdraw / drawingmachine FMUs")
    quick = settings.quick
    full_stop = plan.scene.experiment.stop
    stop = 0.3 if quick else 0.6
    sp = plan.scene.fmus[strip].parameters
    area = float(sp.get("tool_length", 0.035)) * float(sp.get("tool_width", 0.035))
    schemes = [("jacobi", 0), ("gauss-seidel", 0), ("iterative", 1)] if quick else SCENE_SCHEMES
    fam = Family("demo", title)
    fam.note = (f"demo.toml with the drive started at once (start_time = 0: both ramps overlap), stop = {stop:g} s "
                f"(the last case: the whole {full_stop:g} s draw in one step). Largest "
                f"stable step by log bisection to {'20' if quick else '5'} % in [1e-4 s, {stop / MIN_STEPS:g} s] (a run "
                f"has at least {MIN_STEPS} steps). Near p_crit the strip takes the closed-form friction law "
                f"(friction_model = \"closed_form\", Eq. 9): the shipped friction table's pressure axis does not reach "
                f"337 MPa. Iterative coupling uses the default method, quasi-Newton; rho_obs is its largest observed "
                f"contraction in a step (the accuracy report's near_pcrit family compares it with fixed-point iteration). "
                f"Near p_crit the strip sticks, then breaks away (near t = 0.11 s) and the drive overshoots its set-point, "
                f"in the monolithic reference too (13 x at dt = 1e-4 s, measured): a cell flagged there for "
                f"|drive.grip_velocity| at every step is that overshoot meeting the criterion's 10 x bound, not the "
                f"coupling; a cell that passes may have broken away early (Jacobi/0 at 1 ms: at 0.027 s, 7 x).")
    near = 0.99 * 340e6
    # the shipped friction table's pressure axis ends far below p_crit (the scene check refuses the set-point); the
    # closed form (Eq. 9) has no pressure axis
    at_once = started_at_once(plan)
    cases = [("nominal (10 MPa)", at_once, None),
             (f"P_N = {near / 1e6:.1f} MPa (0.99 p_crit, closed-form friction)",
              {**at_once, f"fmus.{press}.parameters.force_setpoint": near * area,
               f"fmus.{strip}.parameters.friction_model": "closed_form"}, None),
             ("grip velocity set-point 0", {**at_once, f"fmus.{drive}.parameters.velocity_setpoint": 0.0}, None)]
    _scene_cells(settings, fam, path, cases, schemes, stop, 1e-4, stop, 0.2 if quick else 0.05,
                 budget=30.0 if quick else 120.0)
    _scene_cells(settings, fam, path, [("one step = whole draw", at_once, full_stop)], schemes, full_stop, None, None,
                 None, budget=60.0)
    return fam


# --------------------------------------------------------------------------- pure strip-draw model
def _strip_cases(quick: bool):
    """(name, parameter overrides, pressure [Pa], velocity(t) profile, draw [m])."""
    v0 = 0.08
    base_draw = 0.002 if quick else 0.01
    n0 = 100 if quick else 200

    def ramp(t, ramp_time=0.01):
        return v0 * min(1.0, t / ramp_time)

    def reverse(t, t_end):
        return ramp(t) if t < 0.5 * t_end else -v0 * min(1.0, (t - 0.5 * t_end) / 0.01)

    return [
        ("baseline (10 MPa)", {"n_elements": n0}, 10e6, "ramp", base_draw),
        ("k_s x 1e3", {"n_elements": n0, "shear_stiffness_factor": 1e3}, 10e6, "ramp", base_draw),
        (f"fine mesh ({8 * n0} elements)", {"n_elements": 8 * n0}, 10e6, "ramp", base_draw),
        ("P_N = 1 kPa", {"n_elements": n0}, 1e3, "ramp", base_draw),
        ("P_N = 336.6 MPa (0.99 p_crit)", {"n_elements": n0}, 0.99 * 340e6, "ramp", base_draw),
        ("grip velocity 0", {"n_elements": n0}, 10e6, "zero", base_draw),
        ("reversing grip velocity", {"n_elements": n0}, 10e6, "reverse", base_draw),
        ("K = 1 (beta saturates at once)", {"n_elements": n0, "archard_k": 1.0}, 10e6, "ramp", base_draw),
        ("zeta = 0", {"n_elements": n0, "zeta": 0.0}, 10e6, "ramp", base_draw),
        ("zeta = 1", {"n_elements": n0, "zeta": 1.0}, 10e6, "ramp", base_draw),
        ("140 mm pad, 140 mm draw", {"tool_length": 0.14}, 10e6, "ramp", 0.14),
    ], ramp, reverse


def pull_force_scale(p, normal_force: float, velocity: float = 0.08) -> float:
    """Reference magnitude of pull_force: friction capacity 2 mu0 F_N plus the elastic-wave force 2 rho c A v.

    A grip that changes its velocity by v launches a stress wave rho c v into the bar (both faces:
    twice the half model's area A), whatever the friction: without it the bound would flag the waves
    of a lightly pressed strip (1 kPa) as an instability.
    """
    return 2.0 * p.mu0 * normal_force + 2.0 * p.density * p.wave_speed * p.bar_area * abs(velocity)


def strip_run(params: dict, pressure: float, profile: str, draw: float, integrator: str, step: float,
              budget: float = 120.0):
    """Run the pure model; return (verdict, info). ``step`` is the model step (the whole draw allowed)."""
    from tribocosim.errors import TribocosimError
    from tribocosim.components.stripdraw.component import COMPONENT

    v0, ramp_time = 0.08, 0.01
    model = COMPONENT.make({**params, "draw_length": draw, "integrator": integrator}).model
    p = model.params
    fn = p.normal_force(pressure)
    t_end = draw / v0 + 0.5 * ramp_time
    n = max(1, int(round(t_end / step)))
    h = t_end / n
    times, pull, mu = [0.0], [0.0], [0.0]
    t0 = time.perf_counter()
    info = {"steps": n, "stopped": ""}
    try:
        for k in range(n):
            tm = (k + 0.5) * h
            if profile == "zero":
                v = 0.0
            elif profile == "reverse":
                v = v0 * min(1.0, tm / ramp_time) if tm < 0.5 * t_end else -v0 * min(1.0, (tm - 0.5 * t_end) / ramp_time)
            else:
                v = v0 * min(1.0, tm / ramp_time) if ramp_time > 0 else v0
            out = model.step(h, {"normal_force": fn, "grip_velocity": v})
            times.append((k + 1) * h)
            pull.append(out["pull_force"])
            mu.append(out["mu_mean"])
            if time.perf_counter() - t0 > budget:
                info["stopped"] = f"stopped at t = {(k + 1) * h:.4g} s: wall-time budget {budget:g} s spent"
                break
    except (TribocosimError, FloatingPointError) as exc:
        info["wall_time"] = time.perf_counter() - t0
        return Verdict(ERROR, f"{type(exc).__name__}: {' '.join(str(exc).split())[:200]}"), info
    info["wall_time"] = time.perf_counter() - t0
    info["explicit_dt"] = model.explicit_time_step
    info["beta_max"] = float(model.beta.max())
    v = classify(np.array(times), {"pull_force": np.array(pull), "mu_mean": np.array(mu)},
                 {"pull_force": pull_force_scale(p, fn), "mu_mean": p.mu0}, CRITERION)
    if info["stopped"]:
        v = Verdict(v.status, (v.reason + "; " if v.reason else "") + info["stopped"], v.growth, v.peak_ratio)
    return v, info


@timed
def stripdraw(settings: Settings) -> Family:
    """Pure strip-draw model: stiff and extreme cases x integrators."""
    quick = settings.quick
    cases, _, _ = _strip_cases(quick)
    title = "Strip-draw model (pure, no FMI): stiff and extreme cases x integrator"
    fam = Family("stripdraw", title)
    expl_cap = 0.002 if quick else 0.035
    fam.note = (f"Pure model, shipped friction table, 35 mm pad unless stated, velocity ramp 10 ms to 0.08 m/s, "
                f"draw {_strip_cases(quick)[0][0][4] * 1e3:g} mm unless stated ('reversing': +0.08 m/s for the first half, "
                f"then ramped to -0.08 m/s). Schemes: explicit central difference (sub-cycled at 0.9 x its stability limit "
                f"inside 1 ms steps; its draws are capped at {expl_cap * 1e3:g} mm, so in the 140 mm case it covers the first "
                f"{expl_cap * 1e3:g} mm: column 'draw' of the CSV), implicit generalized-alpha with 1 ms, "
                f"10 ms and one step as long as the whole draw (the model splits a step so that the pad slides at most one "
                f"element per coupling interval). Largest stable step (implicit): log bisection in [1 ms, whole draw].")
    for name, params, pressure, profile, draw in cases:
        t_draw = draw / 0.08 + 0.005
        for scheme, integ, step in (("explicit", "explicit", 1e-3), ("implicit 1 ms", "implicit", 1e-3),
                                    ("implicit 10 ms", "implicit", 1e-2), ("implicit whole draw", "implicit", t_draw)):
            d = min(draw, expl_cap) if integ == "explicit" else draw
            step_note = f" (first {d * 1e3:g} mm)" if integ == "explicit" and d < draw else ""
            t0 = time.perf_counter()
            st = min(step, d / 0.08 + 0.005)
            v, info = strip_run(params, pressure, profile, d, integ, st, budget=60.0 if quick else 600.0)
            lim = None
            if scheme == "implicit 1 ms":
                lim = step_limit(lambda h: strip_run(params, pressure, profile, draw, "implicit", h)[0], 1e-3, v,
                                 1e-5, t_draw, 0.25 if quick else 0.05)
            fam.rows.append(_cell_row(name, scheme, v, lim, nominal_step=st, draw=d,
                                      explicit_dt=info.get("explicit_dt", math.nan), beta_max=info.get("beta_max", math.nan),
                                      run_wall_time=info.get("wall_time", math.nan), wall_time=time.perf_counter() - t0))
            settings.log(f"  stability stripdraw {name} / {scheme}{step_note}: {v.short()}"
                         + (f"; limit {lim.describe()}" if lim else "") + f" ({time.perf_counter() - t0:.1f} s)")
    return fam


FAMILIES = {"oscillator": oscillator, "stiff_drive": stiff_drive, "demo": demo, "stripdraw": stripdraw}
