"""Measured height maps (profilometer, confocal and AFM files) as the periodic surfaces of a slide.

The files are read through SurfaceTopography (Pastewka group, https://github.com/ContactEngineering/
SurfaceTopography; the optional extra ``measured``: ``pip install "tribocosim[measured]"``), which reads
ISO 25178-72 X3P, Digital Surf SUR, Zygo DATX, Sensofar PLU, Wyko OPD, Alicona AL3D and about 35 more
formats. A map becomes the ``n x n`` periodic grid of side ``size`` of a slide in five stated steps
(:func:`prepared_heights`):

1. Read: the file's first height channel, converted to metres; a line scan, a non-uniform or
   non-square-pixel map and a map without lateral sizes are refused.
2. Missing points (optical instruments leave some undefined): refused with their count and fraction, or,
   with ``fill_missing``, filled by the library's harmonic interpolation (the Laplace equation solved over
   the missing points with the measured ones as boundary values).
3. Detrend over the whole map (``detrend``): ``"plane"`` subtracts the plane that minimises the RMS height
   (the instrument's tilt), ``"curvature"`` the second-order polynomial that does (tilt and form, e.g. a
   sheet's bow), ``"mean"`` only the mean height (for a map that is periodic already).
4. Resample to the grid's pixel ``dx = size / n`` by band-limited interpolation of the map's even (mirror)
   extension: with the orthonormal DCT-II coefficients ``a_kl`` of the ``N x M`` map of pixel ``d``,

       h(x, y) = sum_kl w_k w_l a_kl cos(pi k (x/d + 1/2) / N) cos(pi l (y/d + 1/2) / M),
       w_0 = sqrt(1/N), w_k = sqrt(2/N),

   which passes through every measured point and, unlike a Fourier series, does not wrap the map's edges
   onto each other. Modes above the grid's Nyquist wavenumber pi / dx are dropped (no aliasing when the
   grid is coarser than the scan). It is evaluated on the ``n x n`` grid points of the patch centred in the
   map, which must fit in it.
5. Periodize (``periodization``):

   - ``"smooth"`` (the default): the periodic component ``p`` of the periodic-plus-smooth decomposition
     ``u = p + s`` of the patch (L. Moisan, J. Math. Imaging Vis. 39 (2011) 161, doi:10.1007/
     s10851-010-0227-1). ``s`` solves the periodic discrete Poisson equation ``Lap s = v`` whose source
     ``v`` holds the jumps across the patch's opposite edges (``v[0, :] = u[-1, :] - u[0, :]``,
     ``v[-1, :] = -v[0, :]``, likewise along axis 1, zero inside), and ``p = u - s`` has the patch's own
     discrete Laplacian everywhere: the measured asperities are kept, the edge steps the Fourier BEM would
     see are spread over the patch as a smooth, long-wavelength correction. docs/physics/
     measured_surfaces.md measures its effect on the contact area against a larger patch.
   - ``"synthesis"``: a periodic surface with the patch's height distribution and the PSD of ``p`` (its shape;
     its integral is the patch's variance), by
     iterated amplitude-adjusted Fourier transforms (IAAFT: T. Schreiber and A. Schmitz, Phys. Rev. Lett. 77
     (1996) 635, doi:10.1103/PhysRevLett.77.635) from random phases (``seed``): statistically like the
     scan, with other asperities; one scan gives as many surfaces as seeds.
   - ``"none"``: the map is periodic already (e.g. a generated one written to a file): its side must be the
     domain's, it is resampled by its Fourier series, and only ``detrend = "mean"`` keeps it periodic.

The result has zero mean (as the generated surfaces of :mod:`tribocosim.surrogate.surfaces`). A tool is
measured face up like any other surface; it faces the sheet turned over about the sliding axis x, so its
profile in the slide's frame (above the sheet, :mod:`tribocosim.surrogate.coupling`) is
``h_tool0(x, y) = -h_scan(x, -y)`` (``side = "tool"``).

Statistics of a map through the library: :func:`library_statistics`.
"""

from __future__ import annotations

import hashlib
import math
import os
import warnings
from dataclasses import dataclass

import numpy as np

from tribocosim.errors import ParameterError, TribocosimError

#: how to install the optional dependency (named by every error that needs it)
INSTALL_HINT = 'pip install "tribocosim[measured]" (from a source tree: pip install -e ".[measured]")'
#: detrending of a map: our name -> SurfaceTopography's detrend_mode
DETRENDS = {"mean": "center", "plane": "height", "curvature": "curvature"}
#: ways of making a patch periodic (module docstring)
PERIODIZATIONS = ("smooth", "synthesis", "none")
#: relative tolerance on equal pixel sizes and sides (a map used as it is)
SAME = 1e-9
#: IAAFT iterations of the "synthesis" periodization
IAAFT_ITERATIONS = 200
#: the SlideConfig keys of measured surfaces (all None by default: a generated pair)
MEASURED_KEYS = ("sheet_file", "tool_file", "sheet_file_sha256", "tool_file_sha256", "surface_detrend",
                 "surface_periodization", "surface_fill_missing")
#: the keys a case id leaves out when the file's SHA-256 is recorded (where a file lies is not what it is)
PATH_KEYS = {"sheet_file": "sheet_file_sha256", "tool_file": "tool_file_sha256"}


def surface_topography():
    """The SurfaceTopography package, or a :class:`TribocosimError` that says how to install it."""
    try:
        import SurfaceTopography
    except ImportError as exc:
        raise TribocosimError(f"reading measured surfaces needs the package SurfaceTopography ({exc}); "
                              f"install it with {INSTALL_HINT}") from None
    return SurfaceTopography


def file_sha256(path) -> str:
    """SHA-256 (hex) of a file's bytes: the identity of a measured surface in a case's configuration."""
    p = _existing(path)
    h = hashlib.sha256()
    with open(p, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _existing(path) -> str:
    p = os.fspath(path)
    if not os.path.isfile(p):
        raise ParameterError(f"measured surface file = {p!r} does not name an existing file")
    return p


@dataclass(frozen=True)
class Scan:
    """A measured map after reading, filling and detrending (steps 1-3 of the module docstring).

    Attributes
    ----------
    heights : ndarray, shape (N, M)
        Heights [m], axis 0 along x.
    pixel : float
        Pixel size [m] (square pixels).
    path, sha256 : str
        The file and the SHA-256 of its bytes.
    detrend : str
        The detrending applied (a key of :data:`DETRENDS`).
    n_missing : int
        Undefined points of the file (filled when > 0).
    """

    heights: np.ndarray
    pixel: float
    path: str
    sha256: str
    detrend: str
    n_missing: int

    @property
    def sides(self) -> tuple:
        """Sides of the map [m] (pixel x points)."""
        return tuple(self.pixel * k for k in self.heights.shape)


def read_scan(path, detrend: str = "plane", fill_missing: bool = False, sha256: str | None = None) -> Scan:
    """Read, fill and detrend a measured map (module docstring, steps 1-3).

    Parameters
    ----------
    path : str or os.PathLike
        A file in any format SurfaceTopography reads.
    detrend : {"plane", "curvature", "mean"}
    fill_missing : bool
        Fill undefined points by harmonic interpolation instead of refusing the file.
    sha256 : str, optional
        The expected SHA-256 of the file (a case's configuration records it): a file that has changed since
        is refused.
    """
    if detrend not in DETRENDS:
        raise ParameterError(f"detrend = {detrend!r} is not allowed; allowed: {', '.join(DETRENDS)}")
    p = _existing(path)
    digest = file_sha256(p)
    if sha256 is not None and digest != sha256:
        raise ParameterError(f"measured surface file {p!r} has SHA-256 {digest}, not the {sha256} the "
                             "configuration records: the file has changed since the case was defined")
    st = surface_topography()
    topo = _read(p, st, lambda reader: reader.topography())
    if topo.dim != 2:
        raise ParameterError(f"measured surface file {p!r} holds a line scan (dimension {topo.dim}); "
                             "allowed: an areal map (dimension 2)")
    if not topo.is_uniform:
        raise ParameterError(f"measured surface file {p!r} holds a non-uniform map; allowed: a map on a "
                             "uniform grid")
    if topo.unit is None:
        raise ParameterError(f"measured surface file {p!r} states no length unit; allowed: a map with "
                             "lateral sizes and a unit")
    topo = topo.to_unit("m")
    dx, dy = (s / k for s, k in zip(topo.physical_sizes, topo.nb_grid_pts))
    if abs(dx - dy) > SAME * max(dx, dy):
        raise ParameterError(f"measured surface file {p!r} has pixels of {dx:g} m x {dy:g} m; allowed: "
                             "square pixels")
    n_missing = 0
    if topo.has_undefined_data:
        n_missing = int(np.ma.count_masked(topo.heights()))
        total = int(np.prod(topo.nb_grid_pts))
        if not fill_missing:
            raise ParameterError(
                f"measured surface file {p!r} has {n_missing} undefined point(s) of {total} "
                f"({100.0 * n_missing / total:.3g} %); allowed: none, or fill_missing = true (harmonic "
                "interpolation over the undefined points)")
        topo = topo.interpolate_undefined_data("harmonic")
    topo = topo.detrend(detrend_mode=DETRENDS[detrend])
    heights = np.ascontiguousarray(np.ma.getdata(topo.heights()), dtype=np.float64)
    if not np.all(np.isfinite(heights)):
        raise ParameterError(f"measured surface file {p!r} has non-finite heights after reading; allowed: "
                             "finite heights (undefined points are masked in the file)")
    if min(heights.shape) < 2:
        raise ParameterError(f"measured surface file {p!r} has {heights.shape} points; allowed: >= 2 x 2")
    return Scan(heights, float(dx), p, digest, detrend, n_missing)


def _read(p: str, st, what):
    """``what(reader)`` of the file's SurfaceTopography reader; ParameterError naming the file when it cannot be
    read."""
    ext = os.path.splitext(p)[1].lower().lstrip(".")
    known = {reader.format() for reader in st.IO.readers}
    try:  # a known extension names its reader (whose message then says what is wrong with the file)
        return what(st.open_topography(p, format=ext if ext in known else None))
    except Exception as exc:  # noqa: BLE001 - the readers raise many types; all mean 'not readable'
        if isinstance(exc, st.Exceptions.CannotDetectFileFormat):
            why = f"no reader of the {len(known)} formats recognises it"
        else:
            lines = str(exc).strip().splitlines()
            why = f"{type(exc).__name__}: {lines[0] if lines else ''}{' ...' if len(lines) > 1 else ''}"
        raise ParameterError(f"measured surface file {p!r} is not a height map SurfaceTopography can read "
                             f"({why}); allowed: the formats of SurfaceTopography.open_topography (X3P, SUR, "
                             "DATX, PLU, OPD, AL3D, ...)") from None


def scan_points(path) -> int:
    """Number of points of a measured map, from its file's header (the data are not read): what reading it
    allocates (:func:`tribocosim.surrogate.memory.measured_bytes`)."""
    p = _existing(path)
    return _read(p, surface_topography(), lambda reader: math.prod(reader.default_channel.nb_grid_pts))


def resample_centred(h: np.ndarray, pixel: float, n: int, new_pixel: float) -> np.ndarray:
    """The ``n x n`` grid of pixel ``new_pixel`` centred in the map ``h`` of pixel ``pixel``, by band-limited
    interpolation of the map's even extension (module docstring, step 4).

    Raises ``ParameterError`` when the patch does not fit in the map.
    """
    from scipy.fft import dctn

    extent = [(k - 1) * pixel for k in h.shape]
    need = (n - 1) * new_pixel
    if min(extent) < need * (1.0 - SAME):
        raise ParameterError(
            f"the measured map spans {extent[0]:g} m x {extent[1]:g} m between its first and last points; "
            f"a grid of {n} points of {new_pixel:g} m needs {need:g} m; allowed: a map at least that large "
            "(or a smaller domain)")
    if abs(new_pixel - pixel) <= SAME * pixel:
        i0, j0 = ((k - n) // 2 for k in h.shape)
        return np.ascontiguousarray(h[i0:i0 + n, j0:j0 + n])
    def basis(k: int, ext: float) -> tuple[np.ndarray, np.ndarray]:
        """Cosine basis of one axis at the new points, and which modes it keeps."""
        modes = np.arange(k)
        keep = modes * math.pi / (k * pixel) < math.pi / new_pixel  # below the grid's Nyquist wavenumber
        x = 0.5 * (ext - need) + new_pixel * np.arange(n)  # the patch centred in the map
        w = np.where(modes == 0, math.sqrt(1.0 / k), math.sqrt(2.0 / k))[keep]
        return w * np.cos(math.pi * np.outer(x / pixel + 0.5, modes[keep]) / k), keep

    bx, keep_x = basis(h.shape[0], extent[0])
    by, keep_y = basis(h.shape[1], extent[1])
    coef = dctn(h, type=2, norm="ortho")[np.ix_(keep_x, keep_y)]
    return np.ascontiguousarray(bx @ coef @ by.T)


def fourier_resample(h: np.ndarray, n: int) -> np.ndarray:
    """A periodic square map resampled to ``n x n`` points of the same side by its Fourier series
    (``scipy.signal.resample`` along each axis: modes above the coarser grid's Nyquist wavenumber dropped)."""
    from scipy.signal import resample

    if h.shape[0] == n:
        return h.copy()
    return np.ascontiguousarray(resample(resample(h, n, axis=0), n, axis=1))


def periodic_smooth_decomposition(u) -> tuple[np.ndarray, np.ndarray]:
    """Moisan's periodic-plus-smooth decomposition ``u = p + s`` (module docstring, ``"smooth"``).

    Returns
    -------
    p, s : ndarray
        The periodic component (with the mean of ``u``) and the smooth one (zero mean).
    """
    u = np.asarray(u, dtype=np.float64)
    m, n = u.shape
    v = np.zeros_like(u)
    v[0, :] += u[-1, :] - u[0, :]
    v[-1, :] += u[0, :] - u[-1, :]
    v[:, 0] += u[:, -1] - u[:, 0]
    v[:, -1] += u[:, 0] - u[:, -1]
    den = (2.0 * np.cos(2.0 * np.pi * np.arange(m) / m)[:, None]
           + 2.0 * np.cos(2.0 * np.pi * np.arange(n) / n)[None, :] - 4.0)
    den[0, 0] = 1.0
    s_hat = np.fft.fft2(v) / den
    s_hat[0, 0] = 0.0
    s = np.real(np.fft.ifft2(s_hat))
    return u - s, s


def iaaft_surface(patch: np.ndarray, seed: int, iterations: int = IAAFT_ITERATIONS) -> np.ndarray:
    """A periodic map with the height distribution of ``patch`` and the PSD of its periodic component, scaled
    to the patch's variance (IAAFT from random phases of ``seed``; module docstring, ``"synthesis"``).

    The last step imposes the distribution exactly (a rank-order remap); the PSD is then met to within the
    IAAFT's convergence (docs/physics/measured_surfaces.md gives the residual).
    """
    p, _ = periodic_smooth_decomposition(patch)
    values = np.sort((patch - patch.mean()).ravel())
    # the PSD's shape from p (no edge leakage), its integral the patch's variance (that of the distribution)
    amplitude = np.abs(np.fft.rfft2(p - p.mean())) * (np.std(values) / np.std(p))
    rng = np.random.default_rng(seed)
    h = rng.permutation(values).reshape(patch.shape)
    for _ in range(iterations):
        spec = np.fft.rfft2(h)
        mag = np.abs(spec)
        phase = np.divide(spec, mag, out=np.ones_like(spec), where=mag > 0)
        h = np.fft.irfft2(amplitude * phase, s=patch.shape)
        ranks = np.empty(h.size, dtype=np.int64)
        ranks[np.argsort(h, axis=None, kind="stable")] = np.arange(h.size)
        h = values[ranks].reshape(patch.shape)
    return h


def prepared_heights(path, n: int, size: float, *, detrend: str = "plane", periodization: str = "smooth",
                     fill_missing: bool = False, seed: int = 0, side: str = "sheet",
                     sha256: str | None = None) -> tuple[np.ndarray, dict]:
    """A measured map as the ``n x n`` periodic surface of side ``size`` of a slide (module docstring).

    Parameters
    ----------
    path : str or os.PathLike
        The file (any format SurfaceTopography reads).
    n : int
        Grid points per side (>= 4).
    size : float
        Side L of the periodic domain [m].
    detrend : {"plane", "curvature", "mean"}
    periodization : {"smooth", "synthesis", "none"}
    fill_missing : bool
        Fill undefined points (harmonic interpolation) instead of refusing the file.
    seed : int
        Random phases of the ``"synthesis"`` periodization.
    side : {"sheet", "tool"}
        A tool is turned over about x: ``h(x, y) -> -h(x, -y)``.
    sha256 : str, optional
        The file's expected SHA-256.

    Returns
    -------
    heights : ndarray, shape (n, n)
        Zero-mean heights [m].
    info : dict
        What was done: file, sha256, scan shape and pixel [m], detrend, periodization, missing points
        filled, the patch's RMS height before periodization [m].
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 4:
        raise ParameterError(f"n = {n!r} is not allowed; an integer >= 4 is required")
    if not (isinstance(size, (int, float)) and math.isfinite(size) and size > 0):
        raise ParameterError(f"size = {size!r} m is not allowed; a finite length > 0 is required")
    if periodization not in PERIODIZATIONS:
        raise ParameterError(f"periodization = {periodization!r} is not allowed; allowed: "
                             f"{', '.join(PERIODIZATIONS)}")
    if side not in ("sheet", "tool"):
        raise ParameterError(f"side = {side!r} is not allowed; allowed: sheet, tool")
    if periodization == "none" and detrend != "mean":
        raise ParameterError(f"detrend = {detrend!r} with periodization = 'none': subtracting a plane or a "
                             "polynomial makes a periodic map non-periodic; allowed: detrend = 'mean'")
    scan = read_scan(path, detrend, fill_missing, sha256)
    dx = size / n
    if periodization == "none":
        a, b = scan.sides
        if scan.heights.shape[0] != scan.heights.shape[1] or abs(a - size) > SAME * size:
            raise ParameterError(
                f"periodization = 'none' takes the map as one period of the domain, but it is {a:g} m x {b:g} m "
                f"({scan.heights.shape[0]} x {scan.heights.shape[1]} points) and size = {size:g} m; allowed: "
                "a square map of side size (or periodization = 'smooth' or 'synthesis')")
        patch = fourier_resample(scan.heights, n)
        h = patch
    else:
        patch = resample_centred(scan.heights, scan.pixel, n, dx)
        if periodization == "smooth":
            h, _ = periodic_smooth_decomposition(patch)
        else:
            h = iaaft_surface(patch, seed)
    h = h - h.mean()
    if side == "tool":
        h = -np.roll(h[:, ::-1], 1, axis=1)  # y -> -y on the periodic grid (index j -> -j mod n)
    info = {"file": scan.path, "sha256": scan.sha256, "scan_points": list(scan.heights.shape),
            "scan_pixel": scan.pixel, "detrend": detrend, "periodization": periodization,
            "missing_points_filled": scan.n_missing, "patch_rms_height": float(np.std(patch)), "side": side}
    return np.ascontiguousarray(h), info


def check_measured_keys(config) -> None:
    """Validate the :data:`MEASURED_KEYS` of a SlideConfig (types and combinations; no file is read).

    Raises ``ParameterError`` naming the key, its value and what is allowed.
    """
    files = [side for side in ("sheet", "tool") if getattr(config, f"{side}_file") is not None]
    for side in ("sheet", "tool"):
        path, digest = getattr(config, f"{side}_file"), getattr(config, f"{side}_file_sha256")
        if path is not None and (not isinstance(path, str) or not path):
            raise ParameterError(f"{side}_file = {path!r}; allowed: a file name (a non-empty string)")
        if digest is not None:
            if path is None:
                raise ParameterError(f"{side}_file_sha256 = {digest!r} without {side}_file; allowed: with a file")
            if not (isinstance(digest, str) and len(digest) == 64 and all(c in "0123456789abcdef" for c in digest)):
                raise ParameterError(f"{side}_file_sha256 = {digest!r}; allowed: 64 lower-case hex digits")
        if path is not None and getattr(config, f"{side}_rolloff_wavelength") is not None:
            raise ParameterError(f"{side}_rolloff_wavelength = {getattr(config, f'{side}_rolloff_wavelength')!r} "
                                 f"m shapes a generated {side}, and {side}_file = {path!r} gives a measured one; "
                                 "allowed: one of them")
    options = {"surface_detrend": (config.surface_detrend, tuple(DETRENDS)),
               "surface_periodization": (config.surface_periodization, PERIODIZATIONS),
               "surface_fill_missing": (config.surface_fill_missing, (True, False))}
    for key, (value, allowed) in options.items():
        if value is None:
            continue
        if not files:
            raise ParameterError(f"{key} = {value!r} prepares a measured file, and neither sheet_file nor "
                                 "tool_file is given; allowed: with a file")
        if value not in allowed or isinstance(value, bool) != (key == "surface_fill_missing"):
            raise ParameterError(f"{key} = {value!r} is not allowed; allowed: {', '.join(map(repr, allowed))}")
    if config.surface_periodization == "none" and config.surface_detrend != "mean":
        raise ParameterError(f"surface_detrend = {config.surface_detrend!r} with surface_periodization = "
                             "'none': a plane or polynomial makes a periodic map non-periodic; allowed: 'mean'")


def slide_surface(config, side: str) -> tuple[np.ndarray, dict]:
    """The measured ``side`` ("sheet" or "tool") of a SlideConfig on its grid (:func:`prepared_heights`)."""
    return prepared_heights(getattr(config, f"{side}_file"), config.n, config.size,
                            detrend=config.surface_detrend or "plane",
                            periodization=config.surface_periodization or "smooth",
                            fill_missing=bool(config.surface_fill_missing), seed=getattr(config, f"{side}_seed"),
                            side=side, sha256=getattr(config, f"{side}_file_sha256"))


def identity(config_dict: dict) -> dict:
    """A configuration's dict without the paths of the files whose SHA-256 it records (a case id's input)."""
    return {k: v for k, v in config_dict.items() if not (k in PATH_KEYS and config_dict.get(PATH_KEYS[k]))}


def write_x3p(heights, size: float, path, periodic: bool = True) -> None:
    """Write a square height map [m] of side ``size`` [m] to an ISO 25178-72 X3P file (64-bit floats),
    through SurfaceTopography's ``Topography.to_x3p``."""
    st = surface_topography()
    h = np.asarray(heights, dtype=np.float64)
    ny = h.shape[1]
    topo = st.Topography(h, (size, size * ny / h.shape[0]), unit="m", periodic=periodic)
    topo.to_x3p(os.fspath(path), dtype="D")


def library_statistics(heights, size: float, periodic: bool = True) -> dict:
    """RMS height, RMS gradient (finite differences and spectral), RMS curvature and the radially averaged
    PSD of a square map, all computed by SurfaceTopography.

    ``rms_slope_finite_difference`` is the library's ``rms_gradient`` (upwind differences, periodic for a
    periodic map), ``rms_slope_spectral`` the square root of the second moment of its PSD,
    ``rms_curvature`` half its RMS Laplacian (the mean curvature). ``psd_q`` [rad/m] and ``psd`` [m^4] are
    ``power_spectrum_from_area`` on its default logarithmic bins.
    """
    st = surface_topography()
    h = np.asarray(heights, dtype=np.float64)
    topo = st.Topography(h, (size, size * h.shape[1] / h.shape[0]), unit="m", periodic=periodic)
    q, psd = topo.power_spectrum_from_area()
    with warnings.catch_warnings():  # SurfaceTopography 1.27's rms_height_from_area warns that its alias Sq is deprecated
        warnings.filterwarnings("ignore", message="Function/property `Sq` is deprecated", category=DeprecationWarning)
        sq = float(topo.rms_height_from_area())
    return {"rms_height": sq,
            "rms_slope_finite_difference": float(topo.rms_gradient()),
            "rms_slope_spectral": float(math.sqrt(topo.moment_power_spectrum(order=2))),
            "rms_curvature": float(topo.rms_curvature_from_area()),
            "psd_q": np.asarray(q).tolist(), "psd": np.asarray(psd).tolist()}
