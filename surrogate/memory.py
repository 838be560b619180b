"""The peak memory of the mesoscale commands, estimated before they allocate, and the limit it is checked against.

Every command that allocates from a size the user gives (``meso surface``, ``meso contact``, ``meso slide``, the
cases of ``surrogate build`` and ``surrogate verify``, the table build of ``surrogate build`` and ``surrogate
table``) estimates its peak first and refuses, naming the size and the estimate, when the estimate exceeds the
limit: the memory available (:func:`available`: ``MemAvailable`` of ``/proc/meminfo``, else the free physical
pages of ``sysconf``), or the ``--max-memory`` the user gives instead (:func:`parse_bytes`). A campaign's local
workers run at the same time, so they are counted together: workers x (a worker's own code + a case's peak).

How the estimates are made. The arrays that scale with the grid are counted from the code, in *grids*: one grid is
an ``n x n`` float64 array, ``8 n^2`` bytes; an ``rfft2`` spectrum (``n x (n/2 + 1)`` complex128) is one grid
too (``16 n (n/2 + 1)`` bytes), a ``uint8`` or ``bool`` map an eighth of one. Each estimate below names the arrays
alive at the command's peak, where it is and how many grids they make; :data:`OVERHEAD` adds what does not scale
with the grid (FFTW's plans and twiddle factors, the flakes' arrays, Python objects) and :data:`SLACK` what the C
allocator keeps of blocks freed before the peak. Four terms are measured, not counted: the slack, what
SurfaceTopography holds while it reads and detrends a scan (:data:`SCAN_COPIES`) and while it computes a map's
statistics (:data:`LIBRARY_STATISTICS_GRIDS`), and the resident size of a process that has imported and compiled
the slide's code (:data:`SLIDE_CODE_BYTES`).
tests/surrogate/test_memory.py runs each computation on a grid large enough that the grids dominate and holds its
measured peak (the growth of the resident size's high-water mark over the resident size before the run, in a fresh
process) between 2/3 of the estimate and the estimate.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass

from tribocosim.errors import MemoryLimitError, ParameterError

#: bytes a command allocates besides the arrays that scale with the grid (FFTW's plans, flakes, Python objects)
OVERHEAD = 16 * 2**20
#: the share of the counted grids that the C allocator may hold besides them: glibc serves blocks below its mmap
#: threshold (raised up to 32 MiB by the first large block freed) from its heap, and a block freed under a live one
#: stays resident (measured: 0.52 grids beside the surface generator's 6, the wavenumbers freed below the PSD)
SLACK = 0.125
#: resident size of a process that has imported and compiled the slide's code before it allocates a grid (numpy,
#: scipy, pyFFTW, numba and the slide's compiled kernels: 238 MiB measured on Linux x86-64, Python 3.11)
SLIDE_CODE_BYTES = 256 * 2**20
#: float64 copies of a measured scan that SurfaceTopography's reader and its detrending hold at once (measured: the
#: resident size grows by 12.0 and 12.5 copies in ``read_scan`` of X3P scans of 1024^2 and 2048^2 points; 8 of them
#: are numpy arrays, the others the reader's own buffers)
SCAN_COPIES = 13
#: grids SurfaceTopography's statistics of a map (:func:`tribocosim.surrogate.measured_surfaces.library_statistics`:
#: its RMS gradient and curvature) hold beside the map (measured: 18.0 on a 1000^2 map)
LIBRARY_STATISTICS_GRIDS = 18.0
#: grids alive at the peak of each computation (module docstring; the functions below list them)
SURFACE_GRIDS = 6.0
CONTACT_GRIDS = 22.75
SLIDE_GRIDS = 30.75
TABLE_PAIR_GRIDS = 7.0
#: grids of making a measured patch periodic, by periodization (:func:`measured_bytes`)
MEASURED_GRIDS = {"smooth": 9.0, "synthesis": 12.0, "none": 3.0}

_UNITS = {"": 1, "k": 2**10, "m": 2**20, "g": 2**30, "t": 2**40}


def grid_bytes(n: int) -> int:
    """Bytes of one ``n x n`` float64 grid."""
    return 8 * int(n) * int(n)


def _grids(n: int, count: float) -> int:
    """Bytes of ``count`` grids of side ``n`` with the allocator's :data:`SLACK`."""
    return int((1.0 + SLACK) * count * grid_bytes(n))


def surface_bytes(n: int) -> int:
    """Peak of generating a self-affine surface (:func:`tribocosim.surrogate.surfaces.self_affine_surface`): 6 grids.

    At ``irfft2`` of the spectrum: the PSD (half a grid: ``n (n/2 + 1)`` doubles), the noise's spectrum (1), its
    modulus (1/2), the unit phases (1), their product with ``sqrt(psd)`` (1), and inside ``irfft2`` its complex
    intermediate (1) and the real output (1). The statistics ``meso surface`` prints afterwards hold fewer.
    """
    return _grids(n, SURFACE_GRIDS) + OVERHEAD


def contact_bytes(n: int, pressures: int = 1) -> int:
    """Peak of ``meso contact`` on an ``n x n`` map (:class:`tribocosim.surrogate.bem.ContactSolver`): 22.75 grids,
    3 more from the second pressure on (the previous result is held while the next is solved).

    At the end of a solve (``ContactSolver._result``) that the projected-gradient fallback finished (the conjugate
    gradient's ending holds 2 grids fewer): the height map and its gap (2); the solver's FFT input, output and
    spectrum, its half-grid kernel and its real-space kernel (4.5); the solve's plastic displacement, ``g + u_p``
    and the tractions (3); the fallback's iterate, extrapolated point and gradient (3), its gap, the active-set
    states (1/8) and the violators' index buffer (2.125); the elastic displacement, the deformed gap, the saturated
    mask (1/8), the plastic increment, the three arrays of the result and the two temporaries of the mean gap
    (8.125).
    """
    return _grids(n, CONTACT_GRIDS + (3.0 if pressures > 1 else 0.0)) + OVERHEAD


def measured_bytes(n: int, scan_points: int, periodization: str = "smooth") -> int:
    """Peak of preparing a measured map of ``scan_points`` points as the ``n x n`` periodic grid
    (:func:`tribocosim.surrogate.measured_surfaces.prepared_heights`): the larger of reading the scan
    (:data:`SCAN_COPIES` float64 copies, measured) and making the patch periodic beside the scan's heights (one
    copy), by periodization:

    - ``"smooth"``, 9 grids, inside the inverse FFT of the periodic-plus-smooth decomposition: the patch, the jump
      source, the Poisson denominator (3), the smooth part's spectrum (2: full complex), the transform's complex
      intermediate and output (4);
    - ``"synthesis"``, 12 grids, at the inverse FFT of an IAAFT iteration: the patch, the decomposition's periodic
      part and its complex smooth part (4), the sorted heights, the amplitudes (1/2) and the current map (2.5), the
      spectrum, its modulus (1/2), the phases and their product with the amplitudes (3.5), the transform's
      intermediate and output (2);
    - ``"none"``, 3 grids (measured: ``scipy.signal.resample``'s complex spectra and output).
    """
    grids = MEASURED_GRIDS.get(periodization, max(MEASURED_GRIDS.values()))
    scan = 8 * int(scan_points)
    return int(max(SCAN_COPIES * scan, scan + _grids(n, grids))) + OVERHEAD


def measured_surface_bytes(n: int, scan_points: int, periodization: str = "smooth") -> int:
    """Peak of ``meso surface --from``: preparing the scan (:func:`measured_bytes`), then SurfaceTopography's
    statistics of the result beside it (1 + :data:`LIBRARY_STATISTICS_GRIDS`), whichever is larger."""
    return max(measured_bytes(n, scan_points, periodization), _grids(n, 1.0 + LIBRARY_STATISTICS_GRIDS) + OVERHEAD)


def slide_bytes(config, scan_points: dict | None = None) -> int:
    """Peak of one BEM-DEM slide of ``config`` (:class:`tribocosim.surrogate.coupling.SlideSimulation`), with the
    code it runs (:data:`SLIDE_CODE_BYTES`); ``scan_points`` maps ``"sheet"``/``"tool"`` to the points of their
    measured files.

    The peak is at the end of a contact solve in a sliding step (30.75 grids): the slide's surfaces, deformed
    sheet, its last contact result (tractions, elastic and plastic displacements) and modified tool (7); the step's
    tool, its envelope over the coming pixel, the modified tool and its gap to the sheet (4); the contact solver's
    buffers (4.5), the solve's ``g + u_p`` and warm-started tractions (2), its fallback's iterate, gap and buffers
    (5.125) and its result (8.125), as in :func:`contact_bytes`. The DEM phase holds less (the sheet's change over
    the step, and the overdamped solver's 3 grids of slope bounds, beside the state). Each stored snapshot adds a
    float32 sheet (half a grid). Preparing a measured side (:func:`measured_bytes`) comes before the contact state
    and counts when it is larger.
    """
    steps = config.steps
    snapshots = 1 + (steps // config.snapshot_every if config.snapshot_every else 1)
    peak = _grids(config.n, SLIDE_GRIDS + 0.5 * snapshots)
    for side, points in (scan_points or {}).items():
        held = grid_bytes(config.n) if side == "tool" else 0  # the sheet, prepared first
        peak = max(peak, held + measured_bytes(config.n, points, config.surface_periodization or "smooth") - OVERHEAD)
    return peak + OVERHEAD + SLIDE_CODE_BYTES


def table_bytes(n: int, scan_points: int = 0, periodization: str = "smooth") -> int:
    """Peak of a table build's surface statistics (:func:`tribocosim.surrogate.table_build.surface_statistics`):
    one pair at a time, 7 grids: the sheet while the tool is generated (1 + :func:`surface_bytes`' 6); the
    statistics after it hold the sheet, the tool, their gap and ``rms_slope``'s spectrum, wavenumbers and products
    (at most 6). A measured side: :func:`measured_bytes` beside the sheet."""
    peak = _grids(n, TABLE_PAIR_GRIDS)
    if scan_points:
        peak = max(peak, grid_bytes(n) + measured_bytes(n, scan_points, periodization) - OVERHEAD)
    return peak + OVERHEAD


def parse_bytes(text: str) -> int:
    """``--max-memory`` as bytes: a number with an optional unit K, M, G or T (powers of 1024, an optional ``B``
    or ``iB`` after it): ``"8G"``, ``"512MiB"``, ``"1.5GB"``, ``"1000000"`` (bytes)."""
    m = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)\s*([kKmMgGtT]?)(?:i?[bB])?\s*", str(text))
    value = float(m.group(1)) * _UNITS[m.group(2).lower()] if m else math.nan
    if not (math.isfinite(value) and value >= 1):
        raise ParameterError(f"--max-memory = {text!r} is not a memory size; allowed: a number of bytes >= 1 with an "
                             "optional unit K, M, G or T (powers of 1024), e.g. 8G or 512M")
    return int(value)


def format_bytes(n: float) -> str:
    """``n`` bytes in the largest binary unit below it, 3 significant digits (``"1.5 GiB"``)."""
    for unit, size in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{int(n)} B"


def available(meminfo: str = "/proc/meminfo") -> tuple[int | None, str]:
    """The memory a command may take, and where the figure comes from (for a message): ``MemAvailable`` of
    ``meminfo`` (Linux: what
    can be allocated without swapping, page cache that can be dropped included), else the free physical pages of
    ``sysconf`` (other Unix systems; a lower figure, without the page cache), else ``(None, "")`` (unknown: no
    check unless ``--max-memory`` is given)."""
    try:
        with open(meminfo, encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024, f"{meminfo}: MemAvailable"
    except (OSError, ValueError, IndexError):
        pass
    try:
        pages, page = os.sysconf("SC_AVPHYS_PAGES"), os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, ValueError, OSError):
        return None, ""
    if pages > 0 and page > 0:
        return pages * page, "free physical pages, sysconf SC_AVPHYS_PAGES"
    return None, ""


@dataclass(frozen=True)
class Need:
    """What a command will allocate: ``size`` names the size the user gave (``"--n 60000"``), ``bytes`` the
    estimate, ``how`` how it is made up (``"6 grids of 60000 x 60000 float64 values"``)."""

    size: str
    bytes: int
    how: str = ""


def check(need: Need, max_memory: int | None = None, remedy: str = "a smaller size") -> None:
    """Refuse ``need`` when it exceeds ``max_memory`` (the user's ``--max-memory``, in bytes) or, without it, the
    memory :func:`available`.

    Raises
    ------
    MemoryLimitError
        One line: the size, the estimate, the limit and where it comes from, and what is allowed.
    """
    if max_memory is not None:
        limit = int(max_memory)
        than = f"the limit of {format_bytes(limit)} (--max-memory)"
    else:
        limit, source = available()
        than = f"the {format_bytes(limit or 0)} available ({source})"
    if limit is None or need.bytes <= limit:
        return
    how = f" ({need.how})" if need.how else ""
    raise MemoryLimitError(
        f"{need.size} needs about {format_bytes(need.bytes)} of memory at its peak{how}, more than {than}; allowed: "
        f"at most {format_bytes(limit)}: {remedy}, or another limit with --max-memory", need=need.bytes, limit=limit)


def grids(n: int, count: float) -> str:
    """How ``count`` grids of side ``n`` read in a message."""
    return f"{count:g} arrays of {n} x {n} float64 values, {format_bytes(grid_bytes(n))} each"


def case_need(configs, label: str) -> Need:
    """The largest :func:`slide_bytes` over slide configurations ``configs`` (one per surface pair of a sweep, or the
    cases to rerun), with their measured files' points; ``label`` names where they come from."""
    from .measured_surfaces import scan_points

    worst, n = 0, 0
    for cfg in configs:
        points = {side: scan_points(getattr(cfg, f"{side}_file")) for side in ("sheet", "tool")
                  if getattr(cfg, f"{side}_file") is not None}
        size = slide_bytes(cfg, points)
        if size > worst:
            worst, n = size, cfg.n
    return Need(f"a case of n = {n} ({label})", worst, f"{grids(n, SLIDE_GRIDS)} in a sliding step, and the "
                f"slide's compiled code, {format_bytes(SLIDE_CODE_BYTES)}")


def workers_need(case: Need, workers: int) -> Need:
    """``workers`` local processes running a case each at once: their peaks add up."""
    return Need(f"{workers} worker(s) x {case.size}", workers * case.bytes,
                f"{workers} x {format_bytes(case.bytes)}: {case.how}")
