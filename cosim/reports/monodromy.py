"""The exact one-step (monodromy) map of Jacobi with zero-order hold on the two-mass oscillator.

With extrapolation order 0 a Jacobi macro step of length h holds the coupling values of t_n:
mass 1 is driven by the constant force F_n = k2 (x2 - x1) + c2 (v2 - v1) (all at t_n) and mass 2
by the constant x1_n, v1_n. Each subsystem is linear with a constant input, so its step is exact
through the matrix exponential of the system augmented with the input; the master's state
z = (x1, v1, x2, v2) then evolves as z_{n+1} = M(h) z_n, and the scheme is stable iff the
spectral radius rho(M(h)) <= 1. :func:`jacobi0_limit` bisects rho(M(h)) = 1 (used in the stability
report as the prediction for the Jacobi/0 column; the tests use their own derivation).
"""

from __future__ import annotations

import math

import numpy as np


def jacobi0_map(h: float, k2: float, m1=1.0, m2=1.0, k1=10.0, k3=20.0, c1=0.2, c2=0.5, c3=0.3) -> np.ndarray:
    """M(h) of z = (x1, v1, x2, v2) for Jacobi with extrapolation 0 (outputs refreshed after the step)."""
    from scipy.linalg import expm

    ea = expm(np.array([[0.0, 1.0, 0.0], [-k1 / m1, -c1 / m1, 1.0 / m1], [0.0, 0.0, 0.0]]) * h)
    eb = expm(np.array([[0.0, 1.0, 0.0, 0.0], [-(k2 + k3) / m2, -(c2 + c3) / m2, k2 / m2, c2 / m2],
                        [0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0]]) * h)
    m = np.zeros((4, 4))
    for j in range(4):
        z = np.eye(4)[j]
        f = k2 * (z[2] - z[0]) + c2 * (z[3] - z[1])
        a = ea @ np.array([z[0], z[1], f])
        b = eb @ np.array([z[2], z[3], z[0], z[1]])
        m[:, j] = [a[0], a[1], b[0], b[1]]
    return m


def spectral_radius(m: np.ndarray) -> float:
    return float(np.max(np.abs(np.linalg.eigvals(m))))


def jacobi0_limit(k2: float, lo: float = 1e-9, hi: float = 1.0, rel: float = 1e-4) -> float:
    """Largest h with rho(M(h)) <= 1, by log bisection from ``lo`` (stable) to the first unstable point."""
    grid = np.logspace(math.log10(lo), math.log10(hi), 8 * int(round(math.log10(hi / lo))) + 1)
    a = None
    for h in grid:
        if spectral_radius(jacobi0_map(h, k2)) <= 1.0:
            a = h
            continue
        if a is None:
            return 0.0
        b = h
        while b / a > 1.0 + rel:
            mid = math.sqrt(a * b)
            a, b = (mid, b) if spectral_radius(jacobi0_map(mid, k2)) <= 1.0 else (a, mid)
        return float(a)
    return float(grid[-1])
