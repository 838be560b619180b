"""Judged runs: a scene run through the master under the stability criterion, with early stops.

:func:`judged_run` builds the master from a validated plan (:func:`tribocosim.cosim.api.build`) and advances
it step by step like :meth:`tribocosim.cosim.engine.master.Master.run`, but every ``check_every`` accepted steps it
reads the recorded outputs and stops early when one is non-finite or beyond the bound (an unstable
run would otherwise grow until the FMUs slow down or fail), or when the wall-time budget is
spent (the verdict is then taken on the part run, and says so). The verdict is
:func:`tribocosim.cosim.reports.stability_criterion.classify` on the recorded outputs; a master error
(:class:`~tribocosim.errors.CosimStepError`, an FMU error) gives an "error" verdict with the message.
A fixed-step run in which the master had to halve a step (a discarded step or a non-finite output,
retried by rollback) is unstable at the requested step, whatever the outputs.
"""

from __future__ import annotations

import math
import time

import numpy as np

from tribocosim.cosim.reports.stability_criterion import ERROR, STABLE, UNSTABLE, Criterion, Verdict, classify


def master_row(curve, setting, res, err, **extra) -> dict:
    """A report row from :func:`run_plan`'s dict and the run's error."""
    status = "ok" if not res["stopped"] else res["stopped"]
    return {"curve": curve, "setting": setting, "error": err if not res["stopped"] else math.inf,
            "wall_time": res["wall_time"], "do_steps": res["do_steps"], "steps": res["steps"],
            "rejected": res["rejected"], "iterations": res["iterations"], "status": status, **extra}


def failed_row(curve, setting, exc, **extra) -> dict:
    """The report row of a run that raised ``exc``."""
    msg = " ".join(str(exc).split())[:200]
    return {"curve": curve, "setting": setting, "error": math.inf, "wall_time": math.nan, "do_steps": 0,
            "steps": 0, "rejected": 0, "iterations": 0, "status": f"error: {type(exc).__name__}: {msg}", **extra}


def run_plan(plan, *, budget: float = math.inf, monitor=None, check_every: int = 10) -> dict:
    """Run a validated plan like :func:`tribocosim.cosim.run` (no files), with a wall-time budget.

    ``monitor(row) -> str`` (optional) is called with the recorded outputs every ``check_every``
    accepted steps; a non-empty string stops the run early with that message.

    Returns a dict: ``time``, ``columns``, ``wall_time`` (build + initialization + loop), ``do_steps``
    (summed over the FMUs, rejected attempts included), ``steps``, ``rejected``, ``iterations``,
    ``observed_contraction`` (iterative coupling: the largest contraction factor of a step, else NaN),
    ``halvings``, ``t_end``, ``stopped`` ('' if the run reached the end), ``last_failure``,
    ``controller``. Raises what the master raises (CosimStepError, ConvergenceError, FMU errors).
    """
    from tribocosim.cosim.api import build

    t0 = time.perf_counter()
    b = build(plan)
    m = b.master
    ex = plan.scene.experiment
    out = {"stopped": ""}
    try:
        m.initialize(ex.start, ex.stop, b.parameters)
        k = 0
        while m.n < m.grid.end_ticks:
            m.controller.advance(m, m.n)
            k += 1
            if k % check_every == 0:
                if monitor is not None:
                    msg = monitor(m.recorder.read())
                    if msg:
                        out["stopped"] = f"stopped early at t = {m.grid.time(m.n):.6g} s ({msg})"
                        break
                if time.perf_counter() - t0 > budget:
                    out["stopped"] = f"stopped at t = {m.grid.time(m.n):.6g} s: wall-time budget {budget:g} s spent"
                    break
    finally:
        out["wall_time"] = time.perf_counter() - t0
        st = m.stats
        out.update(steps=st.steps, rejected=st.rejected_error + st.rejected_failures, halvings=st.rejected_failures,
                   iterations=st.iterations, observed_contraction=st.observed_contraction,
                   t_end=m.grid.time(m.n), last_failure=m.last_failure,
                   controller=m.controller.name,
                   do_steps=int(sum(getattr(s, "calls", {}).get("doStep", 0) for s in m.system.slaves)))
        b.close()
    out["time"] = m.recorder.time
    out["columns"] = m.recorder.columns()
    return out


def judged_run(plan, scales: dict[str, float], criterion: Criterion = Criterion(), *, budget: float = 60.0,
               check_every: int = 10) -> tuple[Verdict, dict]:
    """Run ``plan`` and judge it; returns (verdict, the dict of :func:`run_plan`, without the arrays on error).

    The verdict's ``extra["observed_contraction"]`` is the run's largest observed contraction factor of
    an iterated step (from the master's stats, or from the ConvergenceError that stopped it); absent for
    schemes that do not iterate.
    """
    bounds = {n: criterion.bound_factor * s for n, s in scales.items() if s and s > 0}
    cols = {}

    def monitor(row):
        if not cols:
            cols.update({n: j for j, n in enumerate(names)})
        if not np.all(np.isfinite(row)):
            return "non-finite output"
        for n, bd in bounds.items():
            if n in cols and abs(row[cols[n]]) > bd:
                return f"|{n}| = {abs(row[cols[n]]):.3g} beyond the bound {bd:.3g}"
        return ""

    names = [str(ref) for ref, _, _ in plan.recorded]
    try:
        info = run_plan(plan, budget=budget, monitor=monitor, check_every=check_every)
    except Exception as exc:  # FMU errors, CosimStepError, ConvergenceError: the cell says which
        msg = " ".join(str(exc).split())
        rate = getattr(exc, "contraction", math.nan)
        return Verdict(ERROR, f"{type(exc).__name__}: {msg[:240]}",
                       extra={"observed_contraction": rate} if rate == rate else {}), {}
    checked = {n: v for n, v in info["columns"].items() if n in scales}
    v = classify(info["time"], checked, scales, criterion)
    if v.stable and info["halvings"] and info["controller"] == "fixed":
        v = Verdict(UNSTABLE, f"the master halved the step {info['halvings']} times after failed attempts "
                              f"({info['last_failure'][:160]})", v.growth, v.peak_ratio)
    if v.stable and info["stopped"].startswith("stopped early"):
        v = Verdict(UNSTABLE, info["stopped"], v.growth, v.peak_ratio)
    elif info["stopped"] and v.status != ERROR and info["stopped"] not in v.reason:
        v = Verdict(v.status, (v.reason + "; " if v.reason else "") + info["stopped"], v.growth, v.peak_ratio)
    if info["observed_contraction"] == info["observed_contraction"]:
        v.extra["observed_contraction"] = info["observed_contraction"]
    return v, info


__all__ = ["judged_run", "run_plan", "STABLE", "UNSTABLE", "ERROR"]
