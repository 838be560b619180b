"""Exact time stepping of small linear ODE systems x' = A x + B u(t), numpy only.

The press and the drawing machine are linear; their states are advanced exactly (to rounding)
over a step in which the input u is affine in time, u(t) = u0 + (t - t0) u1, by the matrix
exponential of the augmented system (Van Loan 1978, doi:10.1109/TAC.1978.1101743):

    d/dt [x, u, u1] = [[A, B, 0], [0, 0, I], [0, 0, 0]] [x, u, u1]

``expm`` uses scaling and squaring of a Taylor polynomial (Moler & Van Loan 2003,
doi:10.1137/S00361445024180), enough for the few-state, well-scaled systems here; numpy has no
expm and an FMU may not import scipy.
"""

from __future__ import annotations

import math

import numpy as np


def expm(M: np.ndarray) -> np.ndarray:
    """Matrix exponential by scaling and squaring with an 18-term Taylor polynomial."""
    M = np.asarray(M, dtype=float)
    norm = np.linalg.norm(M, 1)
    s = max(0, int(math.ceil(math.log2(norm / 0.25)))) if norm > 0 else 0
    X = M / 2.0**s
    term = np.eye(M.shape[0])
    E = term.copy()
    for k in range(1, 19):
        term = term @ X / k
        E = E + term
    for _ in range(s):
        E = E @ E
    return E


class AffineInputPropagator:
    """Advance x' = A x + B u(t) exactly over steps with inputs affine in time.

    Propagators are cached per step length, so a fixed communication step costs one matrix
    product per step.
    """

    def __init__(self, A: np.ndarray, B: np.ndarray):
        self.A = np.asarray(A, float)
        self.B = np.asarray(B, float).reshape(self.A.shape[0], -1)
        self._cache: dict[float, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}

    def _matrices(self, dt: float):
        hit = self._cache.get(dt)
        if hit is None:
            n, m = self.B.shape
            big = np.zeros((n + 2 * m, n + 2 * m))
            big[:n, :n] = self.A
            big[:n, n:n + m] = self.B
            big[n:n + m, n + m:] = np.eye(m)
            E = expm(big * dt)
            hit = (E[:n, :n], E[:n, n:n + m], E[:n, n + m:])
            if len(self._cache) > 64:
                self._cache.clear()
            self._cache[dt] = hit
        return hit

    def step(self, x: np.ndarray, dt: float, u0, u1=None) -> np.ndarray:
        """State after ``dt`` with input u(t0 + s) = u0 + s u1 (u1 defaults to 0)."""
        Phi, G0, G1 = self._matrices(float(dt))
        u0 = np.atleast_1d(np.asarray(u0, float))
        out = Phi @ x + G0 @ u0
        if u1 is not None:
            out = out + G1 @ np.atleast_1d(np.asarray(u1, float))
        return out
