"""Reference solutions for normal contact: closed forms and a brute-force periodic solver.

The tests and reports of :mod:`tribocosim.surrogate.bem` compare against these. Conventions as in
:mod:`tribocosim.surrogate.bem`: gap g >= 0 between a rigid profile and a flat elastic half-space of
effective modulus E* (plane-strain modulus of the pair), tractions positive in compression.

Westergaard (1939): a 1D sinusoidal gap ``g(x) = g0 (1 - cos(2 pi x / lambda))`` pressed with the
mean pressure p (H. M. Westergaard, J. Appl. Mech. 6 (1939) A49; K. L. Johnson, Contact
Mechanics, Cambridge University Press 1985, Sec. 13.2, doi:10.1017/CBO9781139171731):

    p* = pi E* g0 / lambda                                 full-contact pressure
    p / p* = sin^2(pi a / lambda)                          contact half-width a (p < p*)
    t(x) = 2 p cos(pi x / lambda) / sin^2(pi a / lambda)
           * sqrt(sin^2(pi a / lambda) - sin^2(pi x / lambda))      |x| < a
    t(x) = p + p* cos(2 pi x / lambda)                     p >= p* (full contact)

Hertz (Johnson 1985, Sec. 4.2): a paraboloid ``g = r^2 / (2 R)`` under the force F:

    a = (3 F R / (4 E*))^(1/3),   p0 = 3 F / (2 pi a^2),   t(r) = p0 sqrt(1 - r^2 / a^2)

Rigid-perfectly-plastic limit of the saturated model (E* -> infinity in Eq. 20-21): every contact
point carries p_crit, so the contact area is F / p_crit, the contact set is the part of the rigid
profile below a level (the bearing area) and the plastic displacement fills the profile up to it.
For the paraboloid: ``a = sqrt(F / (pi p_crit))`` and ``u_p(r) = (a^2 - r^2) / (2 R)``.

:func:`projected_gradient_contact` solves Eq. 20-21 on small periodic grids by plain projected
gradient descent with the fixed step 1/||K|| (convergent for any convex quadratic) and the exact
Euclidean projection onto {0 <= t <= p_crit, mean(t) = p}; it shares no code with the production
solver (NumPy complex FFTs, its own kernel), so agreement between the two checks both.
"""

from __future__ import annotations

import math

import numpy as np

from tribocosim.errors import ConvergenceError, ParameterError, check_range


def westergaard_full_contact_pressure(e_star: float, amplitude: float, wavelength: float) -> float:
    """Pressure p* = pi E* g0 / lambda above which the sinusoid is in full contact [Pa]."""
    return math.pi * e_star * amplitude / wavelength


def westergaard_half_width(pressure: float, p_star: float, wavelength: float) -> float:
    """Contact half-width a = (lambda / pi) asin(sqrt(p / p*)) (lambda / 2 when p >= p*) [m]."""
    if pressure >= p_star:
        return 0.5 * wavelength
    return wavelength / math.pi * math.asin(math.sqrt(pressure / p_star))


def westergaard_traction(x, pressure: float, p_star: float, wavelength: float) -> np.ndarray:
    """Westergaard traction at positions ``x`` (gap minimum at x = 0) [Pa]."""
    x = np.asarray(x, dtype=float)
    if pressure >= p_star:
        return pressure + p_star * np.cos(2.0 * np.pi * x / wavelength)
    s2a = pressure / p_star
    c = np.cos(np.pi * x / wavelength)
    arg = s2a - np.sin(np.pi * x / wavelength) ** 2
    return np.where(arg > 0, 2.0 * pressure * np.abs(c) / s2a * np.sqrt(np.maximum(arg, 0)), 0.0)


def hertz_contact_radius(force: float, radius: float, e_star: float) -> float:
    """Hertz contact radius a = (3 F R / (4 E*))^(1/3) [m]."""
    return (3.0 * force * radius / (4.0 * e_star)) ** (1.0 / 3.0)


def hertz_peak_pressure(force: float, radius: float, e_star: float) -> float:
    """Hertz peak pressure p0 = 3 F / (2 pi a^2) [Pa]."""
    a = hertz_contact_radius(force, radius, e_star)
    return 3.0 * force / (2.0 * math.pi * a * a)


def rigid_plastic_paraboloid(force: float, radius: float, p_crit: float) -> tuple[float, float]:
    """Contact radius sqrt(F / (pi p_crit)) and central plastic depth a^2 / (2 R) [m, m]."""
    a = math.sqrt(force / (math.pi * p_crit))
    return a, a * a / (2.0 * radius)


def _project(x: np.ndarray, pressure: float, p_crit: float) -> np.ndarray:
    """Euclidean projection onto {0 <= t <= p_crit, mean(t) = pressure}: t = clip(x - lam)."""
    target = pressure * x.size
    hi_cap = p_crit if math.isfinite(p_crit) else 0.0
    lo, hi = float(x.min()) - hi_cap - pressure, float(x.max())
    for _ in range(200):  # bisection on the monotone sum(clip(x - lam))
        lam = 0.5 * (lo + hi)
        if np.clip(x - lam, 0.0, p_crit).sum() > target:
            lo = lam
        else:
            hi = lam
        if hi - lo <= 4e-16 * max(abs(lo), abs(hi), 1e-300):
            break
    lam = 0.5 * (lo + hi)
    free = ((x - lam) > 0) & ((x - lam) < p_crit)
    if free.any():  # exact on the linear piece
        lam += (np.clip(x - lam, 0.0, p_crit).sum() - target) / free.sum()
    return np.clip(x - lam, 0.0, p_crit)


def projected_gradient_contact(gap, size: float, e_star: float, pressure: float,
                               p_crit: float | None = None, u_plastic=None,
                               tol: float = 1e-13, max_iter: int = 200000) -> dict:
    """Brute-force periodic normal contact (Eq. 20-21) for small grids.

    Minimises ``0.5 t.K t + (g + u_p).t`` over ``0 <= t <= p_crit``, ``mean(t) = p`` by
    ``t <- P(t - s (K t + g + u_p))`` with ``s = 1 / max(K) = pi E* / L``.

    Parameters
    ----------
    gap : array_like, shape (n, n)
        Rigid gap profile [m].
    size, e_star, pressure : float
        Period L [m], effective modulus E* [Pa], mean pressure p [Pa].
    p_crit : float, optional
        Traction cap [Pa] (None: elastic).
    u_plastic : array_like, optional
        Accumulated plastic displacement added to the gap [m].
    tol : float
        Stop when the largest traction change of an iteration is below ``tol * pressure``.
    max_iter : int
        Iteration limit (``ConvergenceError`` beyond it).

    Returns
    -------
    dict
        ``traction``, ``u_elastic`` (zero mean), ``approach``, ``u_plastic`` (input plus the
        penetration of saturated points), ``iterations``.
    """
    g = np.asarray(gap, dtype=float)
    n = g.shape[0]
    if g.ndim != 2 or g.shape != (n, n):
        raise ParameterError(f"gap has shape {g.shape}; a square (n, n) array is required")
    pc = math.inf if p_crit is None else check_range("p_crit", p_crit, pressure)
    h = g + (0.0 if u_plastic is None else np.asarray(u_plastic, dtype=float))
    k = 2.0 * np.pi * np.fft.fftfreq(n, d=size / n)
    q = np.hypot(k[:, None], k[None, :])
    kern = np.divide(2.0, e_star * q, out=np.zeros_like(q), where=q > 0)

    def apply(t):
        return np.real(np.fft.ifft2(np.fft.fft2(t) * kern))

    step = 1.0 / kern.max()
    t = np.full((n, n), pressure)
    for it in range(1, max_iter + 1):
        t_new = _project(t - step * (apply(t) + h), pressure, pc)
        change = np.max(np.abs(t_new - t))
        t = t_new
        if change < tol * pressure:
            break
    else:
        raise ConvergenceError(f"projected_gradient_contact: no convergence in {max_iter} "
                               "iterations")
    u = apply(t)
    free = (t > 0) & (t < pc)
    approach = float(np.mean((u + h)[free])) if free.any() else float(np.max((u + h)[t > 0]))
    sat = t >= pc
    du = np.where(sat, np.maximum(approach - u - h, 0.0), 0.0)
    up0 = 0.0 if u_plastic is None else np.asarray(u_plastic, dtype=float)
    return {"traction": t, "u_elastic": u, "approach": approach, "u_plastic": up0 + du,
            "iterations": it}
