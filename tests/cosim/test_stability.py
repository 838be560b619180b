"""Stability of the coupling schemes on the stiff two-mass oscillator (coupling stiffness k2 = 1e5).

The co-simulation of a linear system is a linear map per macro step on the augmented state
(x1, v1, x2, v2; coupling values y = (force, x1, v1) at the previous communication points
that the extrapolation uses). The tests identify that map *through the master*: one macro step
from each unit initial state (FMU parameters x0, v0 for the states, the master's history for the
past coupling values), and take its spectral radius rho: the scheme is stable at step h iff
rho(h) <= 1. The identified map of Jacobi with extrapolation 0 is checked against an independent
implementation (scipy's expm of the subsystems).

Measured (2026-11-22, see test_report_largest_stable_steps): Jacobi order 0 is stable up to
h = 1.65e-5 s; with extrapolation order 1 and 2 up to 4.9e-4 and 2.2e-3 s (the extrapolation
compensates the phase lag of the hold, which pumps energy into the lightly damped stiff mode);
the iterative scheme with interpolation order 1 up to 1.15e-2 s, 700x the Jacobi/0 limit.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from tribocosim.cosim import run
from tribocosim.cosim.api import build
from tribocosim.cosim.engine.extrapolation import History
from tribocosim.cosim.reports.oscfmus import CONNECTIONS
from tribocosim.cosim.scene.validate import load_scene

K2 = 1e5
STATE = ("a.x1", "a.v1", "b.x2", "b.v2")


def stiff_scene(folder, fmus, h, algorithm, order, stop=None, x=(0.0, 0.0, 0.5, 0.0), iterative="", name="stiff.toml"):
    h, x = float(h), [float(v) for v in x]
    text = f"""
[experiment]
stop = {stop if stop is not None else h!r}
step = {h!r}

[master]
algorithm = "{algorithm}"
extrapolation = {order}

[master.iterative]
tolerance = 1e-12
max_iterations = 60
{iterative}

[fmus.a]
path = "{fmus / 'OscMassA.fmu'}"
parameters = {{ x0 = {x[0]!r}, v0 = {x[1]!r} }}

[fmus.b]
path = "{fmus / 'OscMassB.fmu'}"
parameters = {{ k2 = {K2!r}, x0 = {x[2]!r}, v0 = {x[3]!r} }}

{CONNECTIONS}
[output]
variables = ["a.x1", "a.v1", "b.x2", "b.v2"]
"""
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


class StepMap:
    """Identifies the one-step map of a scheme through the master (see module docstring)."""

    def __init__(self, folder, fmus):
        self.folder, self.fmus = folder, fmus

    def history_points(self, algorithm, order):
        """Past coupling values (before y_n) the scheme reads."""
        return max(0, order - 1) if algorithm == "iterative" else order

    def matrix(self, h, algorithm, order):
        nh = self.history_points(algorithm, order)
        plan = load_scene(stiff_scene(self.folder, self.fmus, h, algorithm, order))
        dim = 4 + 3 * nh
        m = np.zeros((dim, dim))
        for j in range(dim):
            e = np.zeros(dim)
            e[j] = 1.0
            b = build(plan)
            try:
                vr = {n: {v.name: v.valueReference for v in plan.fmus[n].md.modelVariables} for n in ("a", "b")}
                b.parameters[0].update({vr["a"]["x0"]: ("Real", e[0]), vr["a"]["v0"]: ("Real", e[1])})
                b.parameters[1].update({vr["b"]["x0"]: ("Real", e[2]), vr["b"]["v0"]: ("Real", e[3])})
                master = b.master
                master.initialize(0.0, h, b.parameters)
                y0 = master.system.y.copy()
                past = e[4:].reshape(nh, 3)
                if nh:
                    k = master.grid.macro_ticks
                    hist = History(master.system.history.depth)
                    for i in range(nh, 0, -1):
                        hist.push(-i * k, past[i - 1])
                    hist.push(0, y0)
                    master.system.history = hist
                master.run()
                z1 = np.array([master.recorder.columns()[n][-1] for n in STATE])
            finally:
                b.close()
            m[:, j] = np.concatenate([z1, y0, past[:-1].ravel()]) if nh else z1
        return m

    def rho(self, h, algorithm, order):
        return float(max(abs(np.linalg.eigvals(self.matrix(h, algorithm, order)))))


def jacobi_map_numpy(h, q, k2=K2):
    """Independent implementation of Jacobi with extrapolation order q: numpy.polyfit for the
    extrapolation, scipy's expm of each subsystem augmented with its input polynomial."""
    m1 = m2 = 1.0
    k1, k3, c1, c2, c3 = 10.0, 20.0, 0.2, 0.5, 0.3
    ma = np.zeros((5, 5))
    ma[0, 1], ma[1, 0], ma[1, 1], ma[1, 2], ma[2, 3], ma[3, 4] = 1, -k1 / m1, -c1 / m1, 1 / m1, 1, 1
    mb = np.zeros((8, 8))
    mb[0, 1], mb[1, 0], mb[1, 1], mb[1, 2], mb[1, 5] = 1, -(k3 + k2) / m2, -(c3 + c2) / m2, k2 / m2, c2 / m2
    mb[2, 3] = mb[3, 4] = mb[5, 6] = mb[6, 7] = 1
    ea, eb = expm(ma * h), expm(mb * h)
    dim = 4 + 3 * q
    m = np.zeros((dim, dim))
    for j in range(dim):
        s = np.zeros(dim)
        s[j] = 1.0
        z, past = s[:4], s[4:].reshape(q, 3)
        y0 = np.array([k2 * (z[2] - z[0]) + c2 * (z[3] - z[1]), z[0], z[1]])
        c = np.zeros((3, 3))  # rows: Taylor coefficients c0, c1, c2; columns: force, x1, v1
        c[: q + 1] = np.polyfit([-i * h for i in range(q + 1)], np.vstack([y0, *past]), q)[::-1] if q else y0
        a = ea @ [z[0], z[1], c[0, 0], c[1, 0], 2 * c[2, 0]]
        b = eb @ [z[2], z[3], c[0, 1], c[1, 1], 2 * c[2, 1], c[0, 2], c[1, 2], 2 * c[2, 2]]
        m[:, j] = np.concatenate([[a[0], a[1], b[0], b[1]], y0, past[:-1].ravel()]) if q else [a[0], a[1], b[0], b[1]]
    return m


def largest_stable_step(rho, lo=1e-7, hi=1.0, per_decade=2, rel=0.05):
    """Largest h such that every scanned step up to h is stable (rho <= 1), refined by bisection."""
    grid = np.logspace(np.log10(lo), np.log10(hi), int(per_decade * np.log10(hi / lo)) + 1)
    stable = None
    for h in grid:
        if rho(h) <= 1.0 + 1e-9:
            stable = h
            continue
        if stable is None:
            return 0.0
        a, b = stable, h
        while b / a > 1.0 + rel:
            mid = np.sqrt(a * b)
            a, b = (mid, b) if rho(mid) <= 1.0 + 1e-9 else (a, mid)
        return float(a)
    return float(grid[-1])


@pytest.fixture(scope="module")
def step_map(tmp_path_factory, fmu_dir):
    return StepMap(tmp_path_factory.mktemp("stiff"), fmu_dir)


@pytest.mark.parametrize("q, h", [(0, 1e-5), (0, 3e-5), (0, 1e-3), (1, 3e-4), (2, 2e-3)])
def test_identified_map_matches_an_independent_implementation(step_map, q, h):
    got = step_map.matrix(h, "jacobi", q)
    ref = jacobi_map_numpy(h, q)
    np.testing.assert_allclose(got, ref, rtol=1e-8, atol=1e-8 * np.abs(ref).max(),
                               err_msg=f"one-step map of Jacobi/order {q} at h = {h}")


def test_iterative_coupling_is_stable_at_100x_the_jacobi_limit(step_map, tmp_path, fmu_dir):
    h_j = largest_stable_step(lambda h: step_map.rho(h, "jacobi", 0), lo=1e-6, hi=1e-3, per_decade=4)
    exact = largest_stable_step(lambda h: float(max(abs(np.linalg.eigvals(jacobi_map_numpy(h, 0))))), lo=1e-6, hi=1e-3,
                                per_decade=4, rel=0.01)
    print(f"\nlargest stable step, Jacobi order 0, k2 = {K2:g}: {h_j:.3g} s (independent model: {exact:.3g} s)")
    assert 1e-5 < h_j < 3e-5, f"Jacobi/0 stability limit {h_j:.3g} s"
    np.testing.assert_allclose(h_j, exact, rtol=0.06, err_msg="limit from the master vs the independent model")
    h = 100 * h_j
    rho_it = step_map.rho(h, "iterative", 1)
    rho_j = step_map.rho(h, "jacobi", 0)
    print(f"at h = {h:.3g} s: rho(iterative, order 1) = {rho_it:.6f}, rho(jacobi, order 0) = {rho_j:.4f}")
    assert rho_it < 1.0, f"iterative/1 unstable at 100x the Jacobi limit: rho = {rho_it}"
    assert rho_j > 1.05
    # and in a run: bounded for 2 s (the exact motion never exceeds 0.5 m) ...
    res = run(stiff_scene(tmp_path, fmu_dir, h, "iterative", 1, stop=2.0, name="it.toml"), write=False)
    peak = max(np.max(np.abs(res[n])) for n in ("a.x1", "b.x2"))
    assert peak < 0.6, f"iterative run at h = {h:.3g} s reached |x| = {peak:.3g}"
    assert res.metadata["steps"]["iterations"] < 8 * res.metadata["steps"]["accepted"], "quasi-Newton iterations per step"
    # ... while Jacobi at only 10x its limit blows up within 0.5 s
    res = run(stiff_scene(tmp_path, fmu_dir, 10 * h_j, "jacobi", 0, stop=0.5, name="jac.toml"), write=False)
    peak = max(np.max(np.abs(res[n])) for n in ("a.x1", "b.x2"))
    assert peak > 1.0, f"Jacobi at 10x its limit stayed bounded (|x| <= {peak:.3g})"


SCHEMES = [("jacobi", 0), ("jacobi", 1), ("jacobi", 2), ("gauss-seidel", 0), ("gauss-seidel", 1), ("gauss-seidel", 2),
           ("iterative", 0), ("iterative", 1), ("iterative", 2)]


@pytest.mark.slow
def test_report_largest_stable_steps(step_map):
    """The table for the closing note (slow: about 9 x 25 identifications)."""
    rows = {}
    for alg, q in SCHEMES:
        rows[(alg, q)] = largest_stable_step(lambda h: step_map.rho(h, alg, q), lo=1e-7, hi=1.0, per_decade=2, rel=0.1)
    print("\nlargest stable step (k2 = 1e5), first instability on a log scan from 1e-7 s:")
    for (alg, q), h in rows.items():
        print(f"  {alg:<13} order {q}: {h:.3g} s")
    assert rows[("iterative", 1)] >= 100 * rows[("jacobi", 0)]
