"""Periodic self-affine rough surfaces and their statistics (paper Sec. 5, 6.1; docs/model.md section 5).

Generation. On an ``n x n`` periodic grid of side ``L`` the height field is a sum of Fourier modes
with wavevectors ``q = 2 pi k / L`` (``k`` integer pairs). The isotropic power spectral density is

    C(q) = C0                                  for 2 pi / L <= |q| < q_r   (roll-off plateau)
    C(q) = C0 (|q| / q_r) ** (-2 (1 + H))      for q_r <= |q| <= q_s        (self-affine part)
    C(q) = 0                                   for |q| > q_s and for q = 0  (cutoff, zero mean)

with Hurst exponent H (paper: H = 0.8, shortest-to-longest wavelength ratio 1/100 to 4/100). Each
mode gets the amplitude ``sqrt(C(q))`` and a random phase (the phase of the FFT of seeded white
noise, which is Hermitian so that the surface is real); ``C0`` is then fixed by the requested RMS
height or RMS slope. This is the spectral method of Hyun et al., Phys. Rev. E 70 (2004) 026117,
doi:10.1103/PhysRevE.70.026117, and of Persson et al., J. Phys.: Condens. Matter 17 (2005) R1,
doi:10.1088/0953-8984/17/1/R01, with deterministic amplitudes (random phases only), which makes
the PSD of every realisation exactly the prescribed one.

Statistics (Jacobs, Junge & Pastewka, Surf. Topogr.: Metrol. Prop. 5 (2017) 013001,
doi:10.1088/2051-672X/aa51f8):

- RMS height ``h_rms = sqrt(<(h - <h>)^2>)``.
- RMS slope ``h'_rms = sqrt(<|grad h|^2>)`` (both gradient components, the h'_rms of Eq. 8 and 24),
  with two definitions: ``"spectral"``, the gradient of the trigonometric interpolant,
  ``h'_rms^2 = sum_q |q|^2 |h_q|^2 / n^4`` (``h_q`` = unnormalised DFT), and
  ``"finite_difference"``, periodic forward differences
  ``((h[i+1, j] - h[i, j])^2 + (h[i, j+1] - h[i, j])^2) / dx^2`` averaged over the grid. The
  finite-difference value is the smaller one (each mode is weighted by
  ``(2 sin(q dx / 2) / dx)^2 <= q^2``).
- PSD ``C(q) = L^2 |h_q|^2 / n^4``, normalised so that ``h_rms^2 = sum_q C(q) / L^2 = (2 pi)^-2 *
  integral C(q) d^2q``: SurfaceTopography's ``power_spectrum_from_area`` (the ``measured`` extra;
  :func:`tribocosim.surrogate.measured_surfaces.library_statistics`) computes it and its radial average,
  with the RMS curvature.

- Summit density: pixels higher than all 8 periodic neighbours, per unit area (the discrete summit
  definition of Greenwood, Proc. R. Soc. A 393 (1984) 133, doi:10.1098/rspa.1984.0050; it depends on
  the pixel size, so it is only comparable between maps of the same dx).

The RMS height and both RMS slopes are computed here as well as by SurfaceTopography
(``rms_height_from_area``, ``rms_gradient``, the second moment of the PSD) because the generator and the
core install, which does not need that library, use them; tests/surrogate/test_measured_surfaces.py holds
the two equal. The summit density and everything below are not in the library.

Because the amplitudes are deterministic, the RMS height and both RMS slopes of a generated surface
are functions of the PSD alone (the same for every seed): ``h_rms^2 = C0 sum_q C(q) / C0``,
``h'_rms^2 = C0 sum_q |q|^2 C(q) / C0`` and, for finite differences,
``C0 sum_q ((2 sin(q_x dx/2))^2 + (2 sin(q_y dx/2))^2) / dx^2 C(q) / C0`` (sums over the grid's modes,
the moments of the discrete PSD). :func:`predicted_rms_slopes` evaluates them and
:func:`rolloff_wavelength` solves them for the roll-off wavelength 2 pi / q_r that gives a target RMS
slope with a target RMS height: the ratio h'_rms / h_rms grows from its pure power-law value
(q_r = 2 pi / L) to that of a flat spectrum up to q_s (q_r -> q_s). Measured targets that a pure power law
on the domain cannot meet (paper Sec. 2.4: h_rms 1.40 um and h'_rms 0.34 with H = 0.8 on 500 um; see
docs/physics/surfaces.md) are met this way; the grid must then resolve the shortest wavelength
2 pi / q_s with at least 4 pixels (:data:`MIN_PIXELS_PER_WAVELENGTH`), because the slope is carried by
the short wavelengths.

Axis convention: ``h[i, j]`` is the height at ``x = i L / n`` (axis 0, the sliding direction of
the coupling loop) and ``y = j L / n``. Heights are in metres.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from tribocosim.errors import ParameterError, check_range

#: the two RMS-slope definitions
SLOPE_DEFINITIONS = ("spectral", "finite_difference")
#: pixels per shortest wavelength required of a surface with a roll-off
MIN_PIXELS_PER_WAVELENGTH = 4.0


def validate_height_map(h, name: str = "heights", n: int | None = None) -> np.ndarray:
    """Return ``h`` as a C-contiguous float64 square array, or raise ``ParameterError``.

    Parameters
    ----------
    h : array_like
        A 2D height (or gap, traction, displacement) map.
    name : str
        Argument name used in error messages.
    n : int, optional
        Required side length.
    """
    a = np.asarray(h)
    if a.ndim != 2 or a.shape[0] != a.shape[1] or a.shape[0] < 2:
        want = f"({n}, {n})" if n is not None else "a square (n, n) array with n >= 2"
        raise ParameterError(f"{name} has shape {a.shape}; {want} is required")
    if n is not None and a.shape != (n, n):
        raise ParameterError(f"{name} has shape {a.shape}; ({n}, {n}) is required")
    if not np.issubdtype(a.dtype, np.number) or np.iscomplexobj(a):
        raise ParameterError(f"{name} has dtype {a.dtype}; real numbers are required")
    a = np.ascontiguousarray(a, dtype=np.float64)
    if not np.all(np.isfinite(a)):
        bad = int(np.size(a) - np.count_nonzero(np.isfinite(a)))
        raise ParameterError(f"{name} has {bad} non-finite value(s); all values must be finite")
    return a


def _wavenumbers(n: int, size: float) -> np.ndarray:
    """|q| [rad/m] on the rfft2 half-grid, shape (n, n // 2 + 1)."""
    qx = 2.0 * np.pi * np.fft.fftfreq(n, d=size / n)
    qy = 2.0 * np.pi * np.fft.rfftfreq(n, d=size / n)
    return np.hypot(qx[:, None], qy[None, :])


def _rfft_weights(n: int) -> np.ndarray:
    """Multiplicity of each rfft2 column in the full spectrum (1 for the self-conjugate ones)."""
    w = np.full(n // 2 + 1, 2.0)
    w[0] = 1.0
    if n % 2 == 0:
        w[-1] = 1.0
    return w


def self_affine_surface(n: int, size: float, hurst: float, q_roll: float, q_cut: float,
                        rms_height: float | None = None, rms_slope: float | None = None,
                        seed: int = 0, slope_definition: str = "spectral") -> np.ndarray:
    """Periodic isotropic self-affine random surface (heights in m), see the module docstring.

    Parameters
    ----------
    n : int
        Grid points per side (>= 4).
    size : float
        Side length L of the periodic square [m] (> 0).
    hurst : float
        Hurst exponent H, in (0, 1].
    q_roll : float
        Roll-off wavenumber q_r [rad/m] (> 0): the PSD is flat from 2 pi / L to q_r. A value
        <= 2 pi / L gives a pure power law from the longest wavelength L.
    q_cut : float
        Short-wavelength cutoff q_s [rad/m]: q_r < q_s <= pi n / L (the grid's Nyquist
        wavenumber, so that the spectrum stays isotropic), and q_s >= 2 pi / L.
    rms_height, rms_slope : float, optional
        Exactly one of them: the RMS height [m] or the RMS slope [-] of the result.
    seed : int
        Seed of the random phases (``numpy.random.default_rng``).
    slope_definition : {"spectral", "finite_difference"}
        Definition used when ``rms_slope`` is given (see :func:`rms_slope`).

    Returns
    -------
    ndarray, shape (n, n)
        Zero-mean heights [m].
    """
    if int(n) != n or n < 4:
        raise ParameterError(f"n = {n!r} is not allowed; an integer >= 4 is required")
    n = int(n)
    size = check_range("size", size, 0.0, low_inclusive=False, unit="m")
    hurst = check_range("hurst", hurst, 0.0, 1.0, low_inclusive=False)
    q_roll = check_range("q_roll", q_roll, 0.0, low_inclusive=False, unit="rad/m")
    q_nyq = math.pi * n / size
    q_cut = check_range("q_cut", q_cut, max(q_roll, 2.0 * math.pi / size), q_nyq * (1 + 1e-12),
                        low_inclusive=False, unit="rad/m")
    if (rms_height is None) == (rms_slope is None):
        raise ParameterError(f"rms_height = {rms_height!r}, rms_slope = {rms_slope!r}: give "
                             "exactly one of them")
    if slope_definition not in SLOPE_DEFINITIONS:
        raise ParameterError(f"slope_definition = {slope_definition!r} is not allowed; "
                             f"allowed: {SLOPE_DEFINITIONS}")
    psd = _model_psd(_wavenumbers(n, size), hurst, q_roll, q_cut)
    noise = np.fft.rfft2(np.random.default_rng(seed).standard_normal((n, n)))
    mag = np.abs(noise)
    phase = np.divide(noise, mag, out=np.ones_like(noise), where=mag > 0)
    h = np.fft.irfft2(np.sqrt(psd) * phase, s=(n, n))
    if rms_height is not None:
        target = check_range("rms_height", rms_height, 0.0, low_inclusive=False, unit="m")
        current = _rms(h)
    else:
        target = check_range("rms_slope", rms_slope, 0.0, low_inclusive=False)
        current = _slope(h, size, slope_definition)
    return h * (target / current)


def _model_psd(q: np.ndarray, hurst: float, q_roll: float, q_cut: float) -> np.ndarray:
    """C(q) / C0 of the module docstring on the wavenumbers ``q``."""
    psd = np.zeros_like(q)
    mask = (q > 0) & (q <= q_cut)
    psd[mask] = np.where(q[mask] < q_roll, 1.0, (q[mask] / q_roll) ** (-2.0 * (1.0 + hurst)))
    return psd


def rms_height(h) -> float:
    """RMS height about the mean, ``sqrt(<(h - <h>)^2>)`` [units of h]."""
    return _rms(validate_height_map(h, "h"))


def _rms(h: np.ndarray) -> float:
    return float(np.sqrt(np.mean((h - h.mean()) ** 2)))


def rms_slope(h, size: float, definition: str = "spectral") -> float:
    """RMS slope ``sqrt(<|grad h|^2>)`` of a periodic map (both gradient components).

    Parameters
    ----------
    h : array_like, shape (n, n)
        Heights [m].
    size : float
        Side length L [m].
    definition : {"spectral", "finite_difference"}
        Gradient of the trigonometric interpolant, or periodic forward differences (module
        docstring).
    """
    h = validate_height_map(h, "h")
    size = check_range("size", size, 0.0, low_inclusive=False, unit="m")
    return _slope(h, size, definition)


def _slope(h: np.ndarray, size: float, definition: str) -> float:
    n = h.shape[0]
    if definition == "spectral":
        spec = np.fft.rfft2(h)
        q = _wavenumbers(n, size)
        s2 = np.sum(_rfft_weights(n)[None, :] * q**2 * np.abs(spec) ** 2) / float(n) ** 4
    elif definition == "finite_difference":
        dx = size / n
        s2 = np.mean((np.roll(h, -1, 0) - h) ** 2 + (np.roll(h, -1, 1) - h) ** 2) / dx**2
    else:
        raise ParameterError(f"definition = {definition!r} is not allowed; "
                             f"allowed: {SLOPE_DEFINITIONS}")
    return float(np.sqrt(s2))


def surface_wavenumbers(size: float, wavelength_ratio: float,
                        rolloff_wavelength: float | None = None) -> tuple[float, float]:
    """(q_r, q_s) [rad/m] of a surface on a domain of side ``size``, as the slide generates it.

    q_s = (2 pi / L) / wavelength_ratio (the shortest wavelength is ``wavelength_ratio * L``); q_r is
    2 pi / ``rolloff_wavelength``, or 2 pi / L (a pure power law from the longest wavelength) when it is
    None. One function for the slide and for :func:`rolloff_wavelength`, so that both evaluate the
    same float wavenumbers (modes that sit on a cutoff are counted alike).
    """
    q_long = 2.0 * math.pi / size
    q_roll = q_long if rolloff_wavelength is None else 2.0 * math.pi / rolloff_wavelength
    return q_roll, q_long / wavelength_ratio


def _psd_moments(n: int, size: float, hurst: float, q_roll: float, q_cut: float):
    """sum C, sum |q|^2 C and the finite-difference analogue over the grid's modes (C0 = 1)."""
    dx = size / n
    w = _rfft_weights(n)[None, :] * _model_psd(_wavenumbers(n, size), hurst, q_roll, q_cut)
    qx = 2.0 * np.pi * np.fft.fftfreq(n, d=dx)
    qy = 2.0 * np.pi * np.fft.rfftfreq(n, d=dx)
    fd = ((2.0 * np.sin(0.5 * qx * dx) / dx) ** 2)[:, None] \
        + ((2.0 * np.sin(0.5 * qy * dx) / dx) ** 2)[None, :]
    return float(w.sum()), float(np.sum(w * _wavenumbers(n, size) ** 2)), float(np.sum(w * fd))


def predicted_rms_slopes(n: int, size: float, hurst: float, q_roll: float, q_cut: float,
                         rms_height: float) -> dict:
    """RMS slopes of ``self_affine_surface(n, size, hurst, q_roll, q_cut, rms_height=...)``.

    Exact for every seed (deterministic amplitudes; module docstring), from the moments of the PSD.

    Returns
    -------
    dict
        ``{"spectral": ..., "finite_difference": ...}`` [-].
    """
    m0, m2, m2_fd = _psd_moments(int(n), size, hurst, q_roll, q_cut)
    return {"spectral": rms_height * math.sqrt(m2 / m0),
            "finite_difference": rms_height * math.sqrt(m2_fd / m0)}


def rolloff_wavelength(rms_height: float, rms_slope: float, hurst: float, size: float, n: int,
                       wavelength_ratio: float, slope_definition: str = "spectral") -> float:
    """Roll-off wavelength [m] at which a surface of RMS height ``rms_height`` has the RMS slope
    ``rms_slope``.

    The PSD is that of :func:`self_affine_surface` with q_r = 2 pi / result and the short cutoff of
    :func:`surface_wavenumbers`; the ratio h'_rms / h_rms of its moments (module docstring) is solved
    for q_r by Brent's method on log(wavelength) between the shortest wavelength and L.

    Parameters
    ----------
    rms_height : float
        Target RMS height [m] (> 0).
    rms_slope : float
        Target RMS slope [-] (> 0), in the definition ``slope_definition``.
    hurst : float
        Hurst exponent H, in (0, 1].
    size : float
        Side L of the periodic domain [m].
    n : int
        Grid points per side.
    wavelength_ratio : float
        Shortest wavelength / L; the shortest wavelength must span at least
        :data:`MIN_PIXELS_PER_WAVELENGTH` pixels of L / n.
    slope_definition : {"spectral", "finite_difference"}

    Returns
    -------
    float
        Roll-off wavelength 2 pi / q_r [m], between the shortest wavelength and L.

    Raises
    ------
    ParameterError
        On bad input, or when the target lies outside what this PSD can give (the message names the
        reachable range).
    """
    if isinstance(n, bool) or int(n) != n or n < 4:
        raise ParameterError(f"n = {n!r} is not allowed; an integer >= 4 is required")
    n = int(n)
    rms_height = check_range("rms_height", rms_height, 0.0, low_inclusive=False, unit="m")
    rms_slope = check_range("rms_slope", rms_slope, 0.0, low_inclusive=False)
    hurst = check_range("hurst", hurst, 0.0, 1.0, low_inclusive=False)
    size = check_range("size", size, 0.0, low_inclusive=False, unit="m")
    check_range("wavelength_ratio", wavelength_ratio, 0.0, 1.0, low_inclusive=False,
                high_inclusive=False)
    pixels = wavelength_ratio * n
    if pixels < MIN_PIXELS_PER_WAVELENGTH:
        raise ParameterError(
            f"wavelength_ratio = {wavelength_ratio!r} puts the shortest wavelength on {pixels:.3g} "
            f"pixels of the {n}-point grid; allowed: >= {MIN_PIXELS_PER_WAVELENGTH:g} pixels, i.e. "
            f"wavelength_ratio >= {MIN_PIXELS_PER_WAVELENGTH / n:g}")
    if slope_definition not in SLOPE_DEFINITIONS:
        raise ParameterError(f"slope_definition = {slope_definition!r} is not allowed; "
                             f"allowed: {SLOPE_DEFINITIONS}")
    shortest = wavelength_ratio * size
    _, q_cut = surface_wavenumbers(size, wavelength_ratio)

    def slope_at(log_wavelength: float) -> float:
        q_roll, _ = surface_wavenumbers(size, wavelength_ratio, math.exp(log_wavelength))
        return predicted_rms_slopes(n, size, hurst, q_roll, q_cut, rms_height)[slope_definition]

    lo, hi = math.log(shortest), math.log(size)
    s_flat, s_power = slope_at(lo), slope_at(hi)
    if not s_power < rms_slope < s_flat:
        raise ParameterError(
            f"rms_slope = {rms_slope!r} ({slope_definition}) with rms_height = {rms_height!r} m is out "
            f"of reach of a roll-off PSD with H = {hurst:g}, L = {size:g} m, shortest wavelength "
            f"{shortest:g} m on {n} points; allowed: ({s_power:.4g}, {s_flat:.4g}) (a pure power law "
            f"from L to a flat spectrum up to the cutoff); a steeper surface needs a shorter shortest "
            f"wavelength (and a finer grid)")
    root = brentq(lambda x: slope_at(x) - rms_slope, lo, hi, xtol=1e-12, rtol=1e-14)
    return math.exp(root)


@dataclass(frozen=True)
class SurfaceStatistics:
    """Statistics of one periodic height map (definitions in the module docstring).

    Attributes
    ----------
    rms_height : float
        RMS height about the mean [m].
    rms_slope_psd : float
        RMS slope from the map's PSD (``"spectral"``: second moment of the PSD) [-].
    rms_slope_fd : float
        RMS slope from periodic forward differences on the grid (``"finite_difference"``) [-].
    summit_count : int
        Pixels higher than their 8 periodic neighbours.
    summit_density : float
        ``summit_count / L^2`` [1/m^2].
    """

    rms_height: float
    rms_slope_psd: float
    rms_slope_fd: float
    summit_count: int
    summit_density: float


def surface_statistics(h, size: float) -> SurfaceStatistics:
    """RMS height, RMS slope (PSD and finite differences) and summit density of a periodic map.

    Parameters
    ----------
    h : array_like, shape (n, n)
        Heights [m].
    size : float
        Side length L [m].
    """
    h = validate_height_map(h, "h")
    size = check_range("size", size, 0.0, low_inclusive=False, unit="m")
    count = summit_count(h)
    return SurfaceStatistics(_rms(h), _slope(h, size, "spectral"),
                             _slope(h, size, "finite_difference"), count, count / size**2)


def summit_count(h) -> int:
    """Number of pixels strictly higher than all 8 periodic neighbours."""
    h = validate_height_map(h, "h")
    peak = np.ones(h.shape, dtype=bool)
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            if di or dj:
                peak &= h > np.roll(h, (di, dj), axis=(0, 1))
    return int(peak.sum())


def height_map_side(path) -> int | None:
    """Points per side of the height map in a file, from its header alone (what :func:`load_height_map` will
    allocate): an ``.npy`` file's first dimension, a text grid's numbers on its first line of data; None when the
    file does not tell (:func:`load_height_map` then says what is wrong with it)."""
    p = os.fspath(path)
    try:
        with open(p, "rb") as fh:
            if p.lower().endswith(".npy"):
                version = np.lib.format.read_magic(fh)
                shape = (np.lib.format.read_array_header_1_0(fh) if version == (1, 0)
                         else np.lib.format.read_array_header_2_0(fh))[0]
                return int(shape[0]) if shape else None
            for raw in fh:
                line = raw.decode("utf-8", errors="replace").split("#", 1)[0].strip()
                if line:
                    return len(line.replace(",", " ").split())
    except (OSError, ValueError):
        return None
    return None


def load_height_map(path) -> np.ndarray:
    """Load a measured or generated height map (m) from ``.npy`` or a plain-text grid.

    Text files are read with ``numpy.loadtxt`` (whitespace- or comma-separated numbers, ``#``
    comments). The map must be square, at least 2 x 2, and finite; it is treated as periodic.

    Parameters
    ----------
    path : str or os.PathLike
        File name.

    Returns
    -------
    ndarray, shape (n, n), float64
    """
    p = os.fspath(path)
    if not os.path.isfile(p):
        raise ParameterError(f"path = {p!r} does not name an existing file")
    try:
        if p.lower().endswith(".npy"):
            data = np.load(p, allow_pickle=False)
        else:
            with open(p, encoding="utf-8") as fh:
                first = next((ln for ln in fh
                              if ln.strip() and not ln.lstrip().startswith("#")), "")
            data = np.loadtxt(p, delimiter="," if "," in first else None, ndmin=2)
    except (ValueError, OSError) as exc:
        raise ParameterError(f"path = {p!r} is not a readable .npy or text height map: "
                             f"{exc}") from exc
    return validate_height_map(data, f"height map {p!r}")
