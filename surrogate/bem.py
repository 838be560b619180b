"""Periodic Fourier-BEM normal contact with plastic saturation (paper Sec. 5, Eq. 17-21).

Problem. A rigid profile with gap ``g(x)`` (Eq. 17/19: ``g* = h*_tool - h_def0``, any finite
values, metres) is pressed with the imposed mean pressure ``p`` onto a flat, periodic elastic
half-space of effective modulus E* whose surface already carries the accumulated plastic
displacement ``u_p``. Displacements are positive *into* the half-space (compression), so that the
deformed sheet is ``h_def = h_def0 - u_p - u_e`` (docs/model.md section 5), and the rigid body moves
towards the half-space by the approach ``delta`` (an unknown). The deformed gap is

    G = g + u_p + u_e - delta,        u_e = K t,   (K t)^(q) = 2 t^(q) / (E* |q|),  (K t)^(0) = 0

(Boussinesq kernel in Fourier space, sampled at q = 2 pi k / L: Stanley & Kato, J. Tribol. 119
(1997) 481, doi:10.1115/1.2833523; the mean of u_e is set to zero and carried by delta). The
tractions t solve Eq. 20-21, i.e. minimise ``0.5 t.K t + (g + u_p).t`` subject to

    0 <= t <= p_crit,   mean(t) = p,
    G >= 0 where t = 0,   G = 0 where 0 < t < p_crit,   G <= 0 where t = p_crit.

This is Eq. 21 ``g* - u_e - u_p >= 0`` with the rigid shift delta made explicit and the sign of
u flipped to "into the sheet". Where t = p_crit the surfaces would interpenetrate by -G: that
much plastic displacement is added (plastic saturation: Almqvist et al., Tribol. Int. 40 (2007)
574, doi:10.1016/j.triboint.2005.11.008, the paper's ref. [43]), so that the returned
``u_plastic = u_p + max(0, -G)`` leaves a gap >= 0 everywhere and accumulates over solves
(it never decreases: there is no elastic recovery of u_p).

Method. Polonsky & Keer's constrained conjugate gradient (Wear 231 (1999) 206,
doi:10.1016/S0043-1648(99)00113-1) on the free set F = {0 < t < p_crit}, with *both* bounds as
active sets (as with the ``hardness`` of ContactMechanics, contact.engineering; plasticity after
Almqvist et al. and Weber et al., Nat. Commun. 9 (2018) 888, doi:10.1038/s41467-018-02981-y):

1. CG step on F: direction d = r + beta d_old with r = G on F (mean-free, so that the mean
   pressure is kept), exact line search tau = r.d / d.Kd, t -= tau d, g -= tau K d.
2. Active-set change (Polonsky & Keer's projection, extended to the cap): F points that left
   [0, p_crit] are clipped, zero points with G < 0 and saturated points with G > 0 (the
   violators) take the gradient step -tau G, and the mean pressure is restored by the scaling
   t = min(c y, p_crit), c found by Newton on the concave sum (saturated points keep their
   penetration in y, so that the least-penetrating are the first to be released). If the
   contact points cannot carry p even at p_crit, a shift t = clip(y - lambda, 0, p_crit) over the
   whole grid brings in the zero points closest to contact. CG restarts unless only a few points
   changed. If a kept direction is no longer a descent direction (r.d <= 0, conjugacy lost in a
   kept active-set change), CG restarts with d = r instead of stopping there as if converged. The
   work of this step scales with |F| + |S| + #violators; the displacement is then
   corrected by direct summation of the real-space kernel when at most a dozen points changed,
   otherwise by one more FFT pair.

Saturated points sit at p_crit like zero points sit at 0, so the iteration count stays in the
elastic range: 5-9 iterations on fresh self-affine surfaces (E* h'_rms / p_crit ~ 55, where the
bearing-area start below is nearly the answer) and 15-30 in the sliding loop, where u_p has
flattened the contacts, against ~15,000 for the projected fixed point of Tamaas 2.9
(KatoSaturated, measured by the issue's author on a 256^2 case like the benchmark's). The cold
start is a
Hertz-like guess t ~ sqrt(level - g - u_p) on the lowest-gap points, with an area estimated from
Eq. 8 (kappa = 2) and at least p / p_crit; a warm start takes a previous traction (optionally
rolled by the sliding increment). The convergence measure is the RMS complementarity residual

    residual = sqrt(mean(r^2)) / max(rms(g + u_p), p dx / E*),
    r = G on F,  min(G, 0) where t = 0,  max(G, 0) where t = p_crit,

checked on an exact re-evaluation of K t (one FFT pair) before a result is returned. A
warm-started solve that ends unverified is redone once from the cold start (iterations and FFT
pairs of both are reported). On rare instances (seen on flake-modified gaps in the sliding
loop: a nearly fully plastic contact with 2 free points and 60 saturated ones) the active-set
changes cycle and the residual stops falling; when its best value has not dropped by 1 % in 200
iterations the CG stops and an accelerated projected gradient (:meth:`ContactSolver._projected_gradient`)
takes over from where it stopped, which converges on any instance of this convex problem
(``ContactResult.fallback`` says so). A solve that does not reach ``tol`` in ``max_iter``
iterations (the fallback has as many of its own) raises ``ConvergenceError`` (or, with
``on_failure="flag"``, returns ``converged=False`` and warns).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from tribocosim.errors import ConvergenceError, ParameterError, check_range

from .bem_kernels import (_FREE, _SAT, _ZERO, _apply_kernel, _candidates, _capped_sum, _classify, _direction,
                          _new_sets, _project, _shift_sum, _sparse_correct, _step_free, _step_gap, _violations)
from .fft import rfft2_pair
from .surfaces import validate_height_map

#: at most this many changed points are corrected by direct summation instead of an FFT pair
_SPARSE_MAX = 12
#: CG keeps its search direction when at most this many points change set
_NORESET_MAX = 8
#: the CG is stalled when its best residual has not fallen by _PROGRESS in this many iterations
#: (it converges in 5-30 iterations when it works; a stall cycles the active sets for ever)
_STALL_ITERATIONS = 200
_PROGRESS = 0.01
#: the projected-gradient fallback checks the residual every this many iterations (one FFT pair)
_PG_CHECK = 10


@dataclass(frozen=True)
class ContactResult:
    """Solution of one contact solve (arrays of shape (n, n)).

    Attributes
    ----------
    traction : ndarray
        Normal traction t [Pa], 0 <= t <= p_crit, mean equal to the imposed pressure.
    u_elastic : ndarray
        Elastic displacement u_e = K t of the half-space surface [m], positive into it, zero mean.
    u_plastic : ndarray
        Accumulated plastic displacement [m]: the input u_plastic plus this solve's increment.
    iterations : int
        Solver iterations.
    residual : float
        Relative complementarity residual (module docstring) of the returned tractions.
    converged : bool
        ``residual <= tol``.
    contact_area_fraction : float
        Fraction of pixels with t > 0 (A_c / A0).
    mean_gap : float
        Mean of the deformed gap max(G + increment, 0) over the domain [m].
    approach : float
        Rigid approach delta [m] (module docstring).
    saturated_area_fraction : float
        Fraction of pixels with t = p_crit.
    fft_pairs : int
        Number of rfft2/irfft2 pairs used.
    fallback : bool
        The conjugate gradient stalled and the accelerated projected gradient gave the result.
    """

    traction: np.ndarray
    u_elastic: np.ndarray
    u_plastic: np.ndarray
    iterations: int
    residual: float
    converged: bool
    contact_area_fraction: float
    mean_gap: float
    approach: float = 0.0
    saturated_area_fraction: float = 0.0
    fft_pairs: int = 0
    fallback: bool = False


def gap_against_flat(heights) -> np.ndarray:
    """Gap of a rigid rough surface (heights in m, peaks up) against a flat: ``max(h) - h``."""
    h = validate_height_map(heights, "heights")
    return h.max() - h


# ----------------------------------------------------------------------------- kernels
def _between(lo: float, hi: float, guess: float) -> float:
    """Approach when F is empty: any value between the saturated (lo) and zero (hi) gaps."""
    if math.isfinite(lo) and math.isfinite(hi):
        return 0.5 * (lo + hi)
    return lo if math.isfinite(lo) else (hi if math.isfinite(hi) else guess)


# ----------------------------------------------------------------------------- solver
class ContactSolver:
    """Polonsky-Keer Fourier-BEM solver with plastic saturation on an ``n x n`` periodic grid.

    Parameters
    ----------
    n : int
        Grid points per side (>= 2).
    size : float
        Period L [m] (> 0).
    e_star : float
        Effective modulus E* [Pa] (> 0).
    p_crit : float, optional
        Traction cap (plastic saturation) [Pa] (> 0); None for purely elastic contact.
    tol : float
        Tolerance on the relative residual (module docstring), in (0, 1).
    max_iter : int
        Iteration limit (>= 1).
    threads : int
        FFTW threads (>= 1).
    on_failure : {"raise", "flag"}
        Non-convergence raises ``ConvergenceError``, or returns ``converged=False`` with a
        ``RuntimeWarning``.

    Notes
    -----
    A solver owns work arrays: use one instance per thread.
    """

    def __init__(self, n: int, size: float, e_star: float, p_crit: float | None = None,
                 tol: float = 1e-8, max_iter: int = 10000, threads: int = 1, *,
                 on_failure: str = "raise"):
        if int(n) != n or n < 2:
            raise ParameterError(f"n = {n!r} is not allowed; an integer >= 2 is required")
        if int(max_iter) != max_iter or max_iter < 1:
            raise ParameterError(f"max_iter = {max_iter!r} is not allowed; "
                                 "an integer >= 1 is required")
        if on_failure not in ("raise", "flag"):
            raise ParameterError(f"on_failure = {on_failure!r} is not allowed; "
                                 "allowed: 'raise', 'flag'")
        self.n, self.max_iter, self.on_failure = int(n), int(max_iter), on_failure
        pos = dict(low=0.0, low_inclusive=False)
        self.size = check_range("size", size, unit="m", **pos)
        self.e_star = check_range("e_star", e_star, unit="Pa", **pos)
        self.p_crit = None if p_crit is None else check_range("p_crit", p_crit, unit="Pa", **pos)
        self.tol = check_range("tol", tol, 0.0, 1.0, low_inclusive=False, high_inclusive=False)
        self.threads = threads
        n = self.n
        self._fft = rfft2_pair(n, threads)
        qx = 2.0 * np.pi * np.fft.fftfreq(n, d=self.size / n)
        qy = 2.0 * np.pi * np.fft.rfftfreq(n, d=self.size / n)
        q = np.hypot(qx[:, None], qy[None, :])
        kern = np.divide(2.0, self.e_star * q, out=np.zeros_like(q), where=q > 0)
        self._kern = np.ascontiguousarray(kern / float(n * n))  # folds the 1/n^2 of irfft2
        self._even = n % 2 == 0
        full = 2.0 * kern.sum() - kern[:, 0].sum() - (kern[:, -1].sum() if self._even else 0.0)
        self._k_diag = full / float(n * n)  # K_ii, the self-compliance of one pixel
        self._k_max = float(kern.max())  # largest eigenvalue of K: 2 / (E* 2 pi / L)
        self._idx = np.zeros((3, _SPARSE_MAX), dtype=np.int64)
        self._val = np.zeros((2, _SPARSE_MAX))
        self._transforms = 0
        unit = np.zeros((n, n))
        unit[0, 0] = 1.0
        self._kr = np.empty_like(unit)  # real-space (periodic) kernel: K t = sum_j t_j Kr(x - x_j)
        self._apply(unit, self._kr)

    # -- the operator -----------------------------------------------------------------
    def _apply(self, x: np.ndarray | None, out: np.ndarray) -> float:
        """out = K x (x None: K of what is already in the FFT input); returns x.K x."""
        f = self._fft
        if x is not None:
            f.real_in[...] = x
        f.forward()
        xkx = _apply_kernel(f.spectrum, self._kern, self._even)
        f.backward()
        if out is not f.real_out:
            out[...] = f.real_out
        self._transforms += 2
        return xkx

    # -- public -------------------------------------------------------------------------
    def solve(self, gap, pressure: float, u_plastic=None, warm_start: ContactResult | None = None,
              *, warm_shift: tuple[int, int] = (0, 0)) -> ContactResult:
        """Solve Eq. 20-21 for the mean pressure ``pressure`` (module docstring).

        Parameters
        ----------
        gap : array_like, shape (n, n)
            Rigid gap profile g [m]; any finite values (only differences matter).
        pressure : float
            Imposed mean pressure p [Pa], 0 < p <= p_crit.
        u_plastic : array_like, shape (n, n), optional
            Accumulated plastic displacement from earlier solves [m] (default zero).
        warm_start : ContactResult, optional
            A previous solution whose traction is the starting guess.
        warm_shift : (int, int)
            Roll the warm-start traction by this many pixels along (axis 0, axis 1) first, e.g.
            the tool's sliding increment.

        Returns
        -------
        ContactResult
        """
        n, pc = self.n, (math.inf if self.p_crit is None else self.p_crit)
        g0 = validate_height_map(gap, "gap", n)
        p = check_range("pressure", pressure, 0.0, low_inclusive=False, unit="Pa")
        if p > pc:
            raise ParameterError(f"pressure = {pressure!r} Pa is above p_crit = {pc!r} Pa; "
                                 "allowed: 0 < pressure <= p_crit")
        up0 = (np.zeros((n, n)) if u_plastic is None
               else validate_height_map(u_plastic, "u_plastic", n))
        h = g0 + up0
        scale = max(float(np.sqrt(np.mean((h - h.mean()) ** 2))), p * self.size / (n * self.e_star))
        self._transforms = 0
        if p == pc:  # every point saturated: no elastic field, the profile is flattened to its top
            t = np.full((n, n), pc)
            delta = float(h.max())
            state = np.full(n * n, _SAT, np.uint8)
            return self._result(t, np.zeros((n, n)), up0, h, delta, 0, 0.0, state)
        if warm_start is not None:
            t = validate_height_map(warm_start.traction, "warm_start.traction", n)
            t = np.roll(t, tuple(int(s) for s in warm_shift), axis=(0, 1))
        else:
            t = self._initial_guess(h, p, pc)
        t = self._feasible(np.clip(t, 0.0, pc).ravel(), p, pc)
        used = failed = 0
        if warm_start is not None:
            out = self._iterate(t, h, up0, p, pc, scale)
            if out is not None:
                return out
            # the warm start did not lead to a verified solution: start again from the cold guess
            used, failed = self._transforms, self._failed_iterations
            t = self._feasible(np.clip(self._initial_guess(h, p, pc), 0.0, pc).ravel(), p, pc)
            self._transforms = 0
        out = self._iterate(t, h, up0, p, pc, scale)
        if out is None:  # the CG stalled: the projected gradient from where it stopped
            failed += self._failed_iterations
            out = self._projected_gradient(t, h, up0, p, pc, scale)
        if used or failed:
            out = dataclasses.replace(out, iterations=out.iterations + failed,
                                      fft_pairs=out.fft_pairs + used // 2)
        return out

    # -- internals ----------------------------------------------------------------------
    def _initial_guess(self, h: np.ndarray, p: float, pc: float) -> np.ndarray:
        """Hertz-like guess t ~ sqrt(level - h) on the estimated contact set (bearing area)."""
        n = self.n
        dx = self.size / n
        slope = math.sqrt(np.mean((np.roll(h, -1, 0) - h) ** 2 + (np.roll(h, -1, 1) - h) ** 2)) / dx
        frac = 2.0 * p / (self.e_star * slope) if slope > 0 else 1.0
        if math.isfinite(pc):
            frac = max(frac, 1.1 * p / pc)
        m = min(max(int(round(frac * n * n)), 1), n * n)
        flat = h.ravel()
        level = np.partition(flat, m - 1)[m - 1]
        x = np.sqrt(np.maximum(level - flat, 0.0))
        x[flat <= level] += 1e-300 + 1e-12 * (x.max() if x.max() > 0 else 1.0)
        return x

    def _feasible(self, y: np.ndarray, p: float, pc: float) -> np.ndarray:
        """Project y onto {0 <= t <= pc, mean t = p} (see :meth:`_mean_map`)."""
        t = np.zeros_like(y)
        c, lam, every = self._mean_map(y, p * y.size, pc)
        _project(y, c, lam, pc, every, t, self._idx[0], self._val[0], self._idx[1], self._val[1])
        return t

    def _mean_map(self, y: np.ndarray, target: float, pc: float) -> tuple[float, float, bool]:
        """(c, lam, every) with sum(t) = target for t = clip(c y - lam, 0, pc).

        Polonsky & Keer's scaling (lam = 0, zeros stay zero; with saturation c solves the
        concave sum(min(c y, p_crit)) = target by Newton). If the positive entries cannot carry
        the load even at p_crit, a shift of every entry (c = 1, ``every``) instead, which brings
        in the zero points closest to contact.
        """
        pos = y[y > 0.0]
        if pos.size * pc > target * (1.0 + 1e-14):
            f1, _ = _capped_sum(pos, 1.0, pc)
            if abs(f1 - target) <= 1e-13 * target:  # already balanced: keep saturated points
                return 1.0, 0.0, False
            c = target / float(pos.sum())
            if math.isfinite(pc):  # Newton from below on a concave increasing function: exact
                for _ in range(100):
                    fc, df = _capped_sum(pos, c, pc)
                    if abs(fc - target) <= 1e-15 * target or df <= 0.0:
                        break
                    c -= (fc - target) / df
            return c, 0.0, False
        return 1.0, self._shift(y, target, pc), True

    @staticmethod
    def _shift(y: np.ndarray, target: float, pc: float) -> float:
        """lambda with sum(clip(y - lambda, 0, pc)) = target (the Euclidean projection's shift)."""
        lo = float(y.min()) - (pc if math.isfinite(pc) else 0.0) - target / y.size
        lam = brentq(lambda x: _shift_sum(y, x, pc) - target, lo, float(y.max()), xtol=1e-300,
                     rtol=1e-15, maxiter=500)
        free = np.count_nonzero((y - lam > 0.0) & (y - lam < pc))
        if free:  # exact on the linear piece
            lam += (_shift_sum(y, lam, pc) - target) / free
        return lam

    def _projected_gradient(self, t, h, up0, p, pc, scale) -> ContactResult:
        """The fallback when the CG stalls: FISTA on the same problem, from ``t`` (feasible).

        Minimises 0.5 t.K t + (g + u_p).t over {0 <= t <= p_crit, mean t = p} by the accelerated
        projected gradient of Beck & Teboulle (SIAM J. Imaging Sci. 2 (2009) 183,
        doi:10.1137/080716542) with step 1 / max eig K = pi E* / L and the gradient restart of
        O'Donoghue & Candes (Found. Comput. Math. 15 (2015) 715, doi:10.1007/s10208-013-9150-3).
        The Euclidean projection onto the constraint set is t = clip(y - lambda, 0, p_crit) with
        the shift lambda that restores the mean. It converges for any convex instance, at a linear
        rate of about 1 - 1/sqrt(cond K) (cond K ~ n); the residual of the CG is checked every
        ``_PG_CHECK`` iterations, for at most ``max_iter`` iterations.
        """
        n, N = self.n, self.n * self.n
        hf = h.ravel()
        step = 1.0 / self._k_max
        x, y, theta = t.copy(), t.copy(), 1.0
        grad, g = np.empty(N), np.empty(N)
        state, vbuf = np.empty(N, dtype=np.uint8), np.empty(N, dtype=np.int64)
        res, delta, it = math.inf, 0.0, 0
        while it < self.max_iter:
            it += 1
            self._apply(y.reshape(n, n), grad.reshape(n, n))
            z = y - step * (grad + hf)
            x_new = np.clip(z - self._shift(z, p * N, pc), 0.0, pc)
            if float(np.dot(y - x_new, x_new - x)) > 0.0:  # momentum points uphill: restart
                theta, y = 1.0, x_new.copy()
            else:
                theta_new = 0.5 * (1.0 + math.sqrt(1.0 + 4.0 * theta * theta))
                y = x_new + ((theta - 1.0) / theta_new) * (x_new - x)
                theta = theta_new
            x = x_new
            if it % _PG_CHECK == 0 or it == self.max_iter:
                self._exact_gap(x, g, hf)
                delta, _, _, gn, viol, _ = self._refresh(x, g, state, pc, vbuf, None)
                res = math.sqrt((gn + viol) / N) / scale
                if res <= self.tol:
                    break
        u_e = (g - hf).reshape(n, n)
        out = self._result(x.reshape(n, n), u_e, up0, h, delta, it, res, state, res <= self.tol)
        return dataclasses.replace(out, fallback=True)

    def _iterate(self, t, h, up0, p, pc, scale) -> ContactResult | None:
        """The CG loop from the feasible t (updated in place); None if it did not converge."""
        n, N = self.n, self.n * self.n
        hf = h.ravel()
        f = self._fft
        self._d = d = f.real_in.ravel()  # the search direction lives in the FFT input buffer
        w = f.real_out.ravel()  # K d lands in the FFT output buffer
        g = np.empty(N)
        state = np.empty(N, dtype=np.uint8)
        vbuf = np.empty(N, dtype=np.int64)
        self._exact_gap(t, g, hf)
        delta, fidx, sidx, gn, viol, nv = self._refresh(t, g, state, pc, vbuf, None)
        beta_ok, gn_old, tau_v = False, 1.0, 1.0 / self._k_diag
        it, verified = 0, False
        res = math.sqrt((gn + viol) / N) / scale
        best, it_best = res, 0
        while True:
            if res < (1.0 - _PROGRESS) * best:
                best, it_best = res, it
            elif it - it_best >= _STALL_ITERATIONS:  # stalled (cycling active sets): give up
                break
            if res <= self.tol:  # verify on an exact K t before accepting
                self._exact_gap(t, g, hf)
                delta, fidx, sidx, gn, viol, nv = self._refresh(t, g, state, pc, vbuf, delta)
                res = math.sqrt((gn + viol) / N) / scale
                beta_ok = False
                if res <= self.tol:
                    verified = True
                    break
            if it >= self.max_iter:
                break
            it += 1
            ncross, stepped = 0, False
            if fidx.size > 1 and gn > 0.0:
                beta = gn / gn_old if beta_ok else 0.0
                rd = _direction(fidx, g, d, delta, beta)
                if rd <= 0.0 < beta:  # not a descent direction: restart CG (steepest descent)
                    rd = _direction(fidx, g, d, delta, 0.0)
                gn_old = gn
                dkd = self._apply(None, f.real_out)
                if dkd > 0.0 and rd > 0.0:
                    tau = tau_v = rd / dkd
                    sw, ncross = _step_free(fidx, t, d, w, tau, pc)
                    delta -= tau * sw / fidx.size
                    s1, s2, viol, nv = _step_gap(g, w, state, tau, delta, vbuf)
                    delta += s1 / fidx.size
                    gn = max(s2 - s1 * s1 / fidx.size, 0.0)
                    stepped = beta_ok = True
            if not stepped:
                d[fidx] = 0.0
                beta_ok = False
                viol, nv = _violations(g, state, delta, vbuf)
                if nv == 0:  # |F| <= 1 or no free residual, and no violation: done
                    res = math.sqrt((gn + viol) / N) / scale
                    if res > self.tol:
                        break
                    continue
            if ncross == 0 and nv == 0:
                res = math.sqrt((gn + viol) / N) / scale
                continue
            delta, fidx, sidx, gn, viol, keep = self._change(t, g, h, state, fidx, sidx, vbuf[:nv],
                                                             delta, tau_v, p, pc)
            beta_ok = beta_ok and keep
            res = math.sqrt((gn + viol) / N) / scale
        if not (verified and res <= self.tol):
            self._failed_iterations = it
            return None
        u_e = (g - hf).reshape(n, n)
        return self._result(t.reshape(n, n), u_e, up0, h, delta, it, res, state, verified)

    def _exact_gap(self, t, g, hf) -> None:
        """g = K t + h by one FFT pair (destroys the search direction)."""
        n = self.n
        self._apply(t.reshape(n, n), self._fft.real_out)
        np.add(self._fft.real_out.reshape(-1), hf, out=g)
        self._d[:] = 0.0

    def _change(self, t, g, h, state, fidx, sidx, viol_idx, delta, tau_v, p, pc):
        """Active-set change (module docstring); work ~ |F| + |S| + #violators when possible."""
        n, N = self.n, t.size
        idx, t_old, y = _candidates(t, g, state, fidx, viol_idx, sidx, delta, tau_v, pc)
        c, lam, every = self._mean_map(y, p * N, pc)
        if every:  # the contact points cannot carry p: redo over the whole grid
            idx, t_old = np.arange(N), t.copy()
            y = np.where(state == _FREE, t, np.where(state == _SAT, pc, 0.0) - tau_v * (g - delta))
            c, lam, every = self._mean_map(y, p * N, pc)
        ic, vc, i1, v1 = self._idx[0], self._val[0], self._idx[1], self._val[1]
        mc, m1 = _project(y, c, lam, pc, every, t_old, ic, vc, i1, v1)  # t_old <- t_new
        t[idx] = t_new = t_old
        use_c = lam == 0.0 and mc <= m1  # g = c g' + K(t - c t') or g' + K(t - t')
        m = mc if use_c else m1
        if m <= _SPARSE_MAX:
            k = 0 if use_c else 1
            self._idx[2, :m] = idx[self._idx[k, :m]]
            _sparse_correct(g.reshape(n, n), h, self._kr, self._idx[2], self._val[k], m,
                            c if use_c else 1.0)
        else:
            self._exact_gap(t, g, h.ravel())
        keep = m <= _NORESET_MAX
        fidx, sidx = _new_sets(idx, t_new, pc, state, fidx, keep, self._d)
        if fidx.size:
            gf = g[fidx]
            delta = float(gf.mean())
            gn = float(np.sum((gf - delta) ** 2))
        else:
            zero = state == _ZERO
            delta, gn = _between(float(g[sidx].max()) if sidx.size else -math.inf,
                                 float(g[zero].min()) if zero.any() else math.inf, delta), 0.0
        return delta, fidx, sidx, gn, 0.0, keep

    def _refresh(self, t, g, state, pc, vbuf, dguess):
        """Exact active sets, approach, squared free residual and squared violations."""
        if dguess is None or not math.isfinite(dguess):
            dguess = float(np.mean(g))
        cf, s1, s2, gmax_s, gmin_z = _classify(t, g, state, pc, dguess)
        if cf > 0 and abs(s1) > 1e-3 * math.sqrt(max(s2, 0.0) * cf):  # poor guess: redo centred
            dguess += s1 / cf
            cf, s1, s2, gmax_s, gmin_z = _classify(t, g, state, pc, dguess)
        if cf > 0:
            delta = dguess + s1 / cf
            gn = max(s2 - s1 * s1 / cf, 0.0)
        else:
            delta, gn = _between(gmax_s, gmin_z, dguess), 0.0
        viol, nv = _violations(g, state, delta, vbuf)
        fidx = np.flatnonzero(state == _FREE)
        sidx = np.flatnonzero(state == _SAT) if math.isfinite(pc) else fidx[:0]
        return delta, fidx, sidx, gn, viol, nv

    def _result(self, t, u_e, up0, h, delta, it, res, state, verified=True) -> ContactResult:
        gap = h + u_e - delta
        sat = state.reshape(t.shape) == _SAT
        inc = np.where(sat, np.maximum(-gap, 0.0), 0.0)
        converged = bool(verified and res <= self.tol)
        if not converged:
            msg = (f"ContactSolver.solve did not converge: residual {res:.3e} > tol {self.tol:g} "
                   f"after {it} iterations (max_iter {self.max_iter}, n {self.n})")
            if self.on_failure == "raise":
                raise ConvergenceError(msg)
            warnings.warn(msg, RuntimeWarning, stacklevel=3)
        return ContactResult(
            traction=np.array(t), u_elastic=np.array(u_e), u_plastic=up0 + inc, iterations=it,
            residual=float(res), converged=converged,
            contact_area_fraction=float(np.mean(t > 0.0)),
            mean_gap=float(np.mean(np.maximum(gap + inc, 0.0))), approach=float(delta),
            saturated_area_fraction=float(np.mean(sat)), fft_pairs=self._transforms // 2)
