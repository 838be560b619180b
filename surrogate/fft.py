"""Real 2D FFT pairs through pyFFTW, with plans built once per grid and reused.

A Fourier-BEM iteration is dominated by one forward real FFT (``rfft2``) and one inverse
(``irfft2``) of an ``n x n`` field. :class:`RFFT2Pair` owns SIMD-aligned work buffers and the two
FFTW plans bound to them, so that a transform is a bare ``execute()`` without allocation or
re-planning. :func:`rfft2_pair` caches one pair per ``(n, threads)`` and thread.

Plans and reproducibility. Two plans of one transform round differently (2e-15 relative on a 256^2 grid), and a
slide amplifies round-off, so a rerun is bit for bit only on the same plans. By default the plans are FFTW's
estimate (``FFTW_ESTIMATE``: chosen without timing, the same in every process on one machine), so that a case
resumed, rerun by ``surrogate verify`` or computed by another worker gives the same numbers. Measured plans
(``FFTW_MEASURE``) are about a quarter faster on a 256^2 grid (0.26 against 0.33-0.35 ms a transform pair here)
but chosen by timing, so that two processes under load plan differently: they are used when the environment
variable ``TRIBOCOSIM_FFTW_WISDOM`` names a wisdom file, which is loaded before the first plan of the process and
rewritten after each new plan, so that every process reading that file takes the same plans
(:func:`export_wisdom`, :func:`import_wisdom`).

Conventions: the forward transform is unnormalised, ``F[k] = sum_x f[x] exp(-2 pi i k.x / n)``,
and so is the backward one (FFTW's ``execute`` does not divide by ``n**2``): callers fold the
``1/n**2`` into their spectral multipliers.

Reference: M. Frigo and S. G. Johnson, "The design and implementation of FFTW3",
Proc. IEEE 93 (2005) 216, doi:10.1109/JPROC.2004.840301.
"""

from __future__ import annotations

import json
import os
import threading

import numpy as np
import pyfftw

from tribocosim.errors import ParameterError

#: environment variable naming an FFTW wisdom file (optional)
WISDOM_ENV = "TRIBOCOSIM_FFTW_WISDOM"

_local = threading.local()
_wisdom_lock = threading.Lock()
_wisdom_loaded = False


class RFFT2Pair:
    """Forward ``rfft2`` and backward ``irfft2`` plans on an ``n x n`` grid with their buffers.

    Parameters
    ----------
    n : int
        Grid points per side (>= 2).
    threads : int
        FFTW threads (>= 1).
    flags : tuple of str or None
        FFTW planner flags; None: ``FFTW_MEASURE`` with a wisdom file named by ``TRIBOCOSIM_FFTW_WISDOM``,
        ``FFTW_ESTIMATE`` without (module docstring).

    Attributes
    ----------
    real_in : ndarray, shape (n, n), float64
        Input of the forward transform (preserved by it).
    spectrum : ndarray, shape (n, n // 2 + 1), complex128
        Output of the forward and input of the backward transform (destroyed by the latter).
    real_out : ndarray, shape (n, n), float64
        Output of the backward transform (unnormalised).
    """

    def __init__(self, n: int, threads: int = 1, flags: tuple[str, ...] | None = None):
        if int(n) != n or n < 2:
            raise ParameterError(f"n = {n!r} is not allowed; an integer >= 2 is required")
        if int(threads) != threads or threads < 1:
            raise ParameterError(f"threads = {threads!r} is not allowed; "
                                 "an integer >= 1 is required")
        n, threads = int(n), int(threads)
        if flags is None:  # module docstring: measured plans only with a shared wisdom file
            flags = ("FFTW_MEASURE",) if os.environ.get(WISDOM_ENV) else ("FFTW_ESTIMATE",)
        _maybe_load_env_wisdom()
        self.n, self.threads = n, threads
        self.real_in = pyfftw.zeros_aligned((n, n), dtype=np.float64)
        self.spectrum = pyfftw.zeros_aligned((n, n // 2 + 1), dtype=np.complex128)
        self.real_out = pyfftw.zeros_aligned((n, n), dtype=np.float64)
        common = dict(axes=(0, 1), threads=threads, flags=tuple(flags))
        self._fwd = pyfftw.FFTW(self.real_in, self.spectrum, direction="FFTW_FORWARD", **common)
        self._bwd = pyfftw.FFTW(self.spectrum, self.real_out, direction="FFTW_BACKWARD", **common)
        _maybe_save_env_wisdom()

    def forward(self) -> np.ndarray:
        """Transform ``real_in`` into ``spectrum`` (unnormalised) and return ``spectrum``."""
        self._fwd.execute()
        return self.spectrum

    def backward(self) -> np.ndarray:
        """Transform ``spectrum`` into ``real_out`` (unnormalised: ``n**2`` times ``irfft2``)."""
        self._bwd.execute()
        return self.real_out


def rfft2_pair(n: int, threads: int = 1) -> RFFT2Pair:
    """Return the cached :class:`RFFT2Pair` of this thread for ``(n, threads)``.

    The pair's buffers are shared by every caller in the thread: use it for one transform at a
    time (the contact solver copies what it keeps out of ``real_out``).
    """
    cache = getattr(_local, "pairs", None)
    if cache is None:
        cache = _local.pairs = {}
    key = (int(n), int(threads))
    if key not in cache:
        cache[key] = RFFT2Pair(n, threads)
    return cache[key]


def export_wisdom(path: str | os.PathLike) -> None:
    """Write the process's FFTW wisdom to ``path`` (JSON list of FFTW's wisdom texts).

    The file is written to a temporary name and renamed, so concurrent writers never leave a
    truncated file.
    """
    texts = [w.decode("latin-1") for w in pyfftw.export_wisdom()]
    from tribocosim.atomic import write_text

    write_text(path, json.dumps(texts), encoding="latin-1")


def import_wisdom(path: str | os.PathLike) -> bool:
    """Load FFTW wisdom written by :func:`export_wisdom`; return False if the file is missing."""
    try:
        with open(path, encoding="latin-1") as fh:
            texts = json.load(fh)
    except FileNotFoundError:
        return False
    pyfftw.import_wisdom(tuple(t.encode("latin-1") for t in texts))
    return True


def _maybe_load_env_wisdom() -> None:
    global _wisdom_loaded
    path = os.environ.get(WISDOM_ENV)
    with _wisdom_lock:
        if path and not _wisdom_loaded:
            import_wisdom(path)
        _wisdom_loaded = True


def _maybe_save_env_wisdom() -> None:
    path = os.environ.get(WISDOM_ENV)
    if path:
        with _wisdom_lock:
            export_wisdom(path)
