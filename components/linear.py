"""Exact time stepping of small linear ODE systems x' = A x + B u(t), numpy only.

The press and the drawing machine are linear; their states are advanced exactly (to rounding)
over a step in which the input u is affine in time, u(t) = u0 + (t - t0) u1, by the matrix
exponential of the augmented system (Van Loan 1978, doi:10.1109/TAC.1978.1101743):

    d/dt [x, u, u1] = [[A, B, 0], [0, 0, I], [0, 0, 0]] [x, u, u1]

``expm`` balances the matrix (diagonal similarity by powers of 2), then uses scaling and squaring
of a Taylor polynomial (Moler & Van Loan 2003, doi:10.1137/S00361445024180); numpy has no expm
and an FMU may not import scipy. Tested against scipy.linalg.expm on the machine's matrix.
"""

from __future__ import annotations

import math

import numpy as np


def balance(M: np.ndarray) -> np.ndarray:
    """Diagonal scaling d (powers of 2) such that diag(1/d) M diag(d) has rows and columns of
    comparable norm (Parlett & Reinsch 1969, as LAPACK's gebal without permutations).

    Controller states in physical units (an integral of a velocity error next to forces of 1e4 N)
    give matrices whose entries span 15 decades; the exponential of the balanced matrix is
    accurate entry by entry, that of the raw one only relative to its largest entry.
    """
    A = np.array(M, dtype=float)
    n = A.shape[0]
    d = np.ones(n)
    for _ in range(100):
        converged = True
        for i in range(n):
            c = np.linalg.norm(np.delete(A[:, i], i), 1)
            r = np.linalg.norm(np.delete(A[i, :], i), 1)
            if c == 0.0 or r == 0.0:
                continue
            f = 1.0
            while c < r / 2.0:
                c, r, f = c * 2.0, r / 2.0, f * 2.0
            while c >= r * 2.0:
                c, r, f = c / 2.0, r * 2.0, f / 2.0
            if f != 1.0:
                converged = False
                d[i] *= f
                A[:, i] *= f
                A[i, :] /= f
        if converged:
            break
    return d


def expm(M: np.ndarray) -> np.ndarray:
    """Matrix exponential: balancing, then scaling and squaring of an 18-term Taylor polynomial."""
    M = np.asarray(M, dtype=float)
    d = balance(M)
    return _expm_taylor(M * d[None, :] / d[:, None]) * d[:, None] / d[None, :]


def _expm_taylor(M: np.ndarray) -> np.ndarray:
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
