"""Configuration of one mesoscale sliding run (BEM-DEM, Sec. 5-6): a frozen dataclass in SI units.

A TOML file holds the same keys, either at the top level or under a ``[slide]`` table, e.g.::

    [slide]
    n = 256
    size = 500e-6          # m
    pressure = 10e6        # Pa
    flake_diameter = 12e-6 # m

Unknown keys are reported all at once.

The keys that shape a generated surface (``hurst``, ``wavelength_ratio``, ``sheet_rms_height``, ``tool_rms_height``
and the roll-off wavelengths) apply only to the sides generated, and are checked only for these: a pair of measured
files (``sheet_file``, ``tool_file``) leaves them unchecked, whatever their defaults (:attr:`SlideConfig.generated_sides`).

The roll-off wavelengths (``sheet_rolloff_wavelength``, ``tool_rolloff_wavelength``) default to None,
a pure power law, and :meth:`SlideConfig.to_dict` leaves them out while they are None; so is
``oil_viscosity`` when the expert override ``damping_rate`` is given instead.

Damping: by default the flakes are damped by the Stokes drag of the oil they move in,
``oil_viscosity`` = :data:`DEFAULT_OIL_VISCOSITY` (ISO VG 32 at 40 C); the one rate ``damping_rate``
[1/s] (e.g. 5e7) is an expert override. docs/physics/alpha_velocity.md gives the study
behind the default.
"""

from __future__ import annotations

import tomllib
from dataclasses import asdict, dataclass, fields
from pathlib import Path

from tribocosim.errors import ParameterError, check_range

from .flake_body import DEFAULT_OIL_VISCOSITY, DampingRates
from .measured_surfaces import MEASURED_KEYS, check_measured_keys

#: keys left out of to_dict() while None (see the module docstring)
OPTIONAL_KEYS = ("oil_viscosity", "sheet_rolloff_wavelength", "tool_rolloff_wavelength", "dem_velocity",
                 "placement_pressure", "placement", "pair_spacing_px", "cluster_thresholds", "flake_solver",
                 "relax_substeps", *MEASURED_KEYS)
#: how the flakes are laid into the gap at the start of a slide (:func:`tribocosim.surrogate.flakes.random_placement`)
PLACEMENTS = ("monolayer", "deposition")
#: how the flakes move during a DEM phase (:mod:`tribocosim.surrogate.dem`, :mod:`tribocosim.surrogate.flake_relax`)
FLAKE_SOLVERS = ("inertial", "overdamped", "auto")


@dataclass(frozen=True)
class SlideConfig:
    """Parameters of a sliding run (defaults: docs/model.md section 5-6 and the paper's Fig. 10 case).

    Attributes
    ----------
    n : int
        Grid points per side (pixel dx = size/n).
    size : float
        Side L of the periodic square domain [m].
    pressure : float
        Mean contact pressure p imposed on the tool [Pa].
    v0 : float
        Sliding velocity of the tool, +x [m/s].
    e_star, p_crit : float
        Effective modulus and plastic saturation pressure of the sheet [Pa].
    hurst : float
        Hurst exponent of both surfaces.
    wavelength_ratio : float
        Shortest wavelength of the surfaces / size.
    sheet_rms_height, tool_rms_height : float
        RMS heights of the aluminium sheet (below) and of the rigid tool (above) [m].
    sheet_rolloff_wavelength, tool_rolloff_wavelength : float or None
        Roll-off wavelength 2 pi / q_r [m] of each surface's PSD (flat above it, power law below it
        down to the shortest wavelength; :mod:`tribocosim.surrogate.surfaces`), in
        (wavelength_ratio * size, size]; :func:`tribocosim.surrogate.surfaces.rolloff_wavelength`
        finds the one that gives a target RMS slope. None (default): a pure power law from size.
        With a roll-off the shortest wavelength must span >= 4 pixels (wavelength_ratio >= 4/n).
    sheet_seed, tool_seed, flake_seed : int
        Seeds of the two surfaces and of the flake placement.
    sheet_file, tool_file : str or None
        A measured height map (any format SurfaceTopography reads) as the sheet or the tool instead of a
        generated surface (:mod:`tribocosim.surrogate.measured_surfaces`; the ``measured`` extra); the
        side's rms height, roll-off and seed (but for ``surface_periodization = "synthesis"``) do not apply.
    sheet_file_sha256, tool_file_sha256 : str or None
        SHA-256 of the file: a file whose bytes differ is refused (a sweep records it, and a campaign's case
        id holds it instead of the file's path).
    surface_detrend, surface_periodization, surface_fill_missing : str, str, bool or None
        How the measured files are prepared: ``"plane"`` (None), ``"curvature"`` or ``"mean"``;
        ``"smooth"`` (None), ``"synthesis"`` or ``"none"``; undefined points refused (None, False) or filled.
    n_flakes : int
        Number of flakes.
    flake_diameter, flake_thickness : float
        d_p and h_p [m].
    flake_density : float
        [kg/m^3] (Al: 2700).
    penalty_velocity : float
        Impact speed [m/s] of the Hertz rule that sets the flake penalty stiffness (and so the DEM
        time step); must be >= the speed the DEM runs at (v0, or ``dem_velocity`` when v0 is below it). It is one value for every run that is to be compared (default
        50 m/s, the paper's highest sliding speed): were it v0, the contact law itself would change
        with the sliding speed (k_A ~ v0^1.2), and so would the overlaps the blocking rules read.
    damping_rate : float or None
        gamma [1/s] of Eq. 15-16 (eta = gamma m, gamma I), one rate for translation and rotation: an
        expert override of ``oil_viscosity`` (e.g. 5e7); giving both is an
        error. None (default): the damping of ``oil_viscosity``.
    oil_viscosity : float or None
        Dynamic viscosity eta of the lubricant [Pa s] (>= 0): the flakes are damped by the Stokes drag
        of a thin disc, with separate translational and rotational rates
        (:meth:`tribocosim.surrogate.dem.DampingRates.from_viscosity`). None with no damping_rate
        means :data:`DEFAULT_OIL_VISCOSITY` (ISO VG 32 at 40 C, 0.0278 Pa s).
    dem_velocity : float or None
        Speed [m/s] at which the DEM slides when v0 is below it (None: always at v0). The flakes are then
        run at dem_velocity with every damping rate multiplied by dem_velocity / v0, which keeps the
        damping per pixel of sliding, Lambda = gamma dx / v0, the physical one: a flake's free motion
        written per unit sliding distance s, x'' + (gamma / v0) x' = F / (m v0^2), depends on the speed
        only through Lambda wherever the contact force F is not acting, and the contacts are stiff
        enough that their overlaps stay far below the pinch and crush thresholds at either speed
        (docs/physics/table_domain.md validates this similarity against direct runs at the slow speed).
        The DEM cost per pixel is that of dem_velocity, whatever v0: the slide's number of DEM steps
        grows as 1/v0 otherwise.
    placement_pressure : float or None
        Pressure [Pa] of the particle-free contact in whose gap the flakes are placed at the start (the
        tool then presses to ``pressure`` in the first contact solve, the flakes it meets becoming
        load-bearing); None: ``pressure``. Clipped to ``pressure`` when larger.
    placement : {"monolayer", "deposition"} or None
        ``monolayer`` (None): flakes lie flat side by side, centres at least d_p apart, which cannot
        exceed beta ~ 0.45 (random sequential adsorption of discs jams at 0.547); ``deposition``: each
        flake falls at a uniformly random (x, y) onto the sheet or onto the flakes already there
        (stacked flat, mid-planes h_p apart), so that beta = N a_p / A0 (Eq. 10) may approach and exceed
        the covered fraction (1 - exp(-beta) for independent positions).
    flake_solver : {"inertial", "overdamped", "auto"} or None
        ``inertial`` (None): the DEM of Eq. 15-16 with velocity-Verlet (:mod:`tribocosim.surrogate.dem`);
        ``overdamped``: the flakes relax to force and torque balance as the tool slides
        (:mod:`tribocosim.surrogate.flake_relax`), the limit of large damping per pixel, allowed where
        Lambda = gamma_min dx / v0 >= :data:`tribocosim.surrogate.flake_relax.LAMBDA_MIN` (the physical
        damping at the physical v0; ``dem_velocity`` and ``dt_safety`` do not apply); ``auto``: overdamped
        where Lambda allows it, inertial elsewhere (a sweep over velocities in one preset), resolved when the
        configuration is made, so that a case's dict and id name the solver that runs it.
    relax_substeps : int or None
        Substeps per pixel of the overdamped solver (None: its default, 8).
    dt_safety : float
        Safety factor on the Verlet limit 2/omega_max.
    sample_spacing_px : float
        Spacing of the flake-face sample points in pixels.
    pair_spacing_px : float or None
        Spacing in pixels of the points of the flake-flake contact (None: ``sample_spacing_px``). In
        a deposit of stacked flakes each flake presses on its neighbours over most of its area at
        every DEM step; a coarser set there costs less and changes no rule that reads the surfaces.
    pinch_overlap_fraction : float
        A flake into which the two surfaces (the tool over the coming pixel) cut by more than twice
        this fraction of h_p in sum does not fit between them and is blocked too, load-bearing in
        the contact solve (:func:`tribocosim.surrogate.coupling.pinched`). Default 0: touching
        both. It is the staggered scheme's non-penetration condition: with a threshold > 0 the tool
        may squeeze a flake the solve does not see, and on steep surfaces the DEM may then stop with
        a crushed flake. A_p by the paper's cluster rule alone is recorded in every run.
    cluster_thresholds : tuple of float or None
        Overlap thresholds [m] at which A_p of the paper's cluster rule alone is also counted on the same slide
        (a pixel overlaps the tool when the flake is above it by more than the threshold; the rule itself uses
        0); recorded per step and as slide means. None: none.
    n_slide_steps : int or None
        Number of one-pixel sliding steps; default 2n (the tool slides 2L).
    snapshot_every : int
        Store flakes and sheet every this many steps (0: first and last only).
    bem_tol, bem_max_iter, threads
        Passed to the contact solver.
    """

    n: int = 256
    size: float = 500e-6
    pressure: float = 10e6
    v0: float = 50.0
    e_star: float = 55e9
    p_crit: float = 340e6
    hurst: float = 0.8
    wavelength_ratio: float = 0.02
    sheet_rms_height: float = 1.40e-6
    tool_rms_height: float = 0.60e-6
    sheet_rolloff_wavelength: float | None = None
    tool_rolloff_wavelength: float | None = None
    sheet_seed: int = 1
    tool_seed: int = 2
    flake_seed: int = 3
    n_flakes: int = 20
    flake_diameter: float = 12e-6
    flake_thickness: float = 0.5e-6
    flake_density: float = 2700.0
    penalty_velocity: float = 50.0
    dem_velocity: float | None = None
    placement_pressure: float | None = None
    placement: str | None = None
    flake_solver: str | None = None
    relax_substeps: int | None = None
    damping_rate: float | None = None
    oil_viscosity: float | None = None
    dt_safety: float = 0.1
    sample_spacing_px: float = 1.0
    pair_spacing_px: float | None = None
    pinch_overlap_fraction: float = 0.0
    cluster_thresholds: tuple | None = None
    n_slide_steps: int | None = None
    snapshot_every: int = 0
    bem_tol: float = 1e-8
    bem_max_iter: int = 10000
    threads: int = 1
    sheet_file: str | None = None
    tool_file: str | None = None
    sheet_file_sha256: str | None = None
    tool_file_sha256: str | None = None
    surface_detrend: str | None = None
    surface_periodization: str | None = None
    surface_fill_missing: bool | None = None

    def __post_init__(self):
        _int("n", self.n, 8)
        pos = dict(low=0.0, low_inclusive=False)
        check_range("size", self.size, unit="m", **pos)
        check_range("pressure", self.pressure, high=self.p_crit, unit="Pa", **pos)
        check_range("v0", self.v0, unit="m/s", **pos)
        check_range("e_star", self.e_star, unit="Pa", **pos)
        check_range("p_crit", self.p_crit, unit="Pa", **pos)
        generated = self.generated_sides
        if generated:  # the keys that shape a generated surface: not checked for a measured pair (module docstring)
            check_range("hurst", self.hurst, 0.0, 1.0, low_inclusive=False)
            check_range("wavelength_ratio", self.wavelength_ratio, 2.0 / self.n, 1.0)
        for side in generated:
            check_range(f"{side}_rms_height", getattr(self, f"{side}_rms_height"), unit="m", **pos)
        for name in (f"{side}_rolloff_wavelength" for side in generated):
            value = getattr(self, name)
            if value is None:
                continue
            _number(name, value, "m")
            check_range(name, value, self.wavelength_ratio * self.size, self.size,
                        low_inclusive=False, unit="m")
            if self.wavelength_ratio * self.n < 4.0:
                raise ParameterError(
                    f"wavelength_ratio = {self.wavelength_ratio!r} puts the shortest wavelength on "
                    f"{self.wavelength_ratio * self.n:.3g} pixels; with {name} set, >= 4 pixels are "
                    f"required; allowed: wavelength_ratio >= 4/n = {4.0 / self.n:g}")
        _int("n_flakes", self.n_flakes, 0)
        check_range("flake_diameter", self.flake_diameter, high=0.5 * self.size,
                    high_inclusive=False, unit="m", **pos)
        check_range("flake_thickness", self.flake_thickness, high=self.flake_diameter,
                    high_inclusive=False, unit="m", **pos)
        check_range("flake_density", self.flake_density, unit="kg/m^3", **pos)
        if self.dem_velocity is not None:
            _number("dem_velocity", self.dem_velocity, "m/s")
            check_range("dem_velocity", self.dem_velocity, unit="m/s", **pos)
        check_range("penalty_velocity", self.penalty_velocity, low=self.run_velocity, unit="m/s")
        if self.placement_pressure is not None:
            _number("placement_pressure", self.placement_pressure, "Pa")
            check_range("placement_pressure", self.placement_pressure, unit="Pa", **pos)
        if self.placement is not None and self.placement not in PLACEMENTS:
            raise ParameterError(f"placement = {self.placement!r} is not known; allowed: "
                                 f"{', '.join(PLACEMENTS)}")
        if self.oil_viscosity is not None:
            _number("oil_viscosity", self.oil_viscosity, "Pa s")
            check_range("oil_viscosity", self.oil_viscosity, 0.0, unit="Pa s")
            if self.damping_rate is not None:
                raise ParameterError(
                    f"damping_rate = {self.damping_rate!r} 1/s and oil_viscosity = "
                    f"{self.oil_viscosity!r} Pa s are both given; allowed: one of them (damping_rate "
                    f"is an expert override of the damping from the oil's viscosity; "
                    f"dataclasses.replace(config, oil_viscosity=..., damping_rate=None) switches)")
        elif self.damping_rate is None:
            object.__setattr__(self, "oil_viscosity", DEFAULT_OIL_VISCOSITY)
        if self.damping_rate is not None:
            _number("damping_rate", self.damping_rate, "1/s")
            check_range("damping_rate", self.damping_rate, 0.0, unit="1/s")
        if self.flake_solver is not None and self.flake_solver not in FLAKE_SOLVERS:
            raise ParameterError(f"flake_solver = {self.flake_solver!r} is not known; allowed: "
                                 f"{', '.join(FLAKE_SOLVERS)}")
        if self.relax_substeps is not None:
            _int("relax_substeps", self.relax_substeps, 1)
        if self.flake_solver == "auto":
            from .flake_relax import LAMBDA_MIN

            solver = "overdamped" if self._damping_per_pixel() >= LAMBDA_MIN else "inertial"
            object.__setattr__(self, "flake_solver", solver)
        if self.flake_solver == "overdamped":
            self._check_overdamped()
        check_range("dt_safety", self.dt_safety, 0.0, 1.0, low_inclusive=False)
        check_range("sample_spacing_px", self.sample_spacing_px, 0.0, 4.0, low_inclusive=False)
        if self.pair_spacing_px is not None:
            _number("pair_spacing_px", self.pair_spacing_px, "pixels")
            check_range("pair_spacing_px", self.pair_spacing_px, 0.0, 4.0, low_inclusive=False)
        check_range("pinch_overlap_fraction", self.pinch_overlap_fraction, 0.0, 0.5)
        if self.cluster_thresholds is not None:
            if not isinstance(self.cluster_thresholds, (tuple, list)) or not all(
                    isinstance(x, (int, float)) and not isinstance(x, bool) and abs(x) < self.flake_thickness
                    for x in self.cluster_thresholds):
                raise ParameterError(f"cluster_thresholds = {self.cluster_thresholds!r}; allowed: a list of "
                                     f"thresholds [m] smaller in magnitude than flake_thickness = {self.flake_thickness!r}")
            object.__setattr__(self, "cluster_thresholds", tuple(float(x) for x in self.cluster_thresholds))
        check_measured_keys(self)
        if self.n_slide_steps is not None:
            _int("n_slide_steps", self.n_slide_steps, 1)
        _int("snapshot_every", self.snapshot_every, 0)
        check_range("bem_tol", self.bem_tol, 0.0, 1.0, low_inclusive=False)
        _int("bem_max_iter", self.bem_max_iter, 1)
        _int("threads", self.threads, 1)

    @property
    def generated_sides(self) -> tuple[str, ...]:
        """The sides ("sheet", "tool") generated as self-affine surfaces: those without a measured file. The keys that
        shape a generated surface (``hurst``, ``wavelength_ratio``, the side's ``*_rms_height`` and
        ``*_rolloff_wavelength``) apply to these only, and are checked for these only."""
        return tuple(side for side in ("sheet", "tool") if getattr(self, f"{side}_file") is None)

    @property
    def overdamped(self) -> bool:
        """True when the flakes move by the overdamped solver (``flake_solver``)."""
        return self.flake_solver == "overdamped"

    def _damping_per_pixel(self) -> float:
        """Lambda = gamma dx / v0 of the least damped flake motion at the physical v0."""
        from .flake_body import FlakeShape
        from .flake_relax import damping_per_pixel

        rates = self.damping(FlakeShape(self.flake_diameter, self.flake_thickness, self.flake_density))
        rates = rates if isinstance(rates, DampingRates) else DampingRates.uniform(rates)
        return damping_per_pixel(rates, self.dx, self.v0)

    def _check_overdamped(self) -> None:
        from .flake_relax import LAMBDA_MIN

        lam = self._damping_per_pixel()
        if not lam >= LAMBDA_MIN:
            raise ParameterError(
                f"flake_solver = 'overdamped' at v0 = {self.v0!r} m/s: the damping per pixel Lambda = gamma dx / v0 "
                f"= {lam:.3g} (the least damped motion); allowed: Lambda >= {LAMBDA_MIN:g} (a slower slide, "
                f"more viscous oil or larger pixels), or flake_solver = 'inertial'")

    @property
    def dx(self) -> float:
        """Pixel size [m]."""
        return self.size / self.n

    @property
    def steps(self) -> int:
        """Number of one-pixel sliding steps."""
        return 2 * self.n if self.n_slide_steps is None else self.n_slide_steps

    @property
    def run_velocity(self) -> float:
        """Speed [m/s] the DEM slides at: v0, or ``dem_velocity`` when v0 is below it."""
        if self.dem_velocity is not None and self.v0 < self.dem_velocity:
            return self.dem_velocity
        return self.v0

    @property
    def damping_scale(self) -> float:
        """Factor on the flakes' damping rates that keeps Lambda = gamma dx / v0 at run_velocity."""
        return self.run_velocity / self.v0

    @property
    def start_pressure(self) -> float:
        """Pressure [Pa] of the contact the flakes are placed in (``placement_pressure``, at most
        ``pressure``)."""
        if self.placement_pressure is None:
            return self.pressure
        return min(self.placement_pressure, self.pressure)

    @property
    def beta(self) -> float:
        """Flake area fraction beta = N_p pi (d_p/2)^2 / L^2 (Eq. 10)."""
        return self.n_flakes * 3.141592653589793 * (0.5 * self.flake_diameter) ** 2 / self.size**2

    def damping(self, shape):
        """The DEM damping for flakes of ``shape`` (a :class:`~tribocosim.surrogate.dem.FlakeShape`):
        the rate ``damping_rate`` [1/s], or the Stokes-drag rates of ``oil_viscosity``."""
        if self.oil_viscosity is not None:
            return DampingRates.from_viscosity(shape, self.oil_viscosity)
        return self.damping_rate

    def run_damping(self, shape):
        """:meth:`damping` scaled by :attr:`damping_scale` (the rates the DEM runs with)."""
        rates = self.damping(shape)
        k = self.damping_scale
        if isinstance(rates, DampingRates):
            return DampingRates(*(k * r for r in rates.as_tuple()))
        return k * rates

    def to_dict(self) -> dict:
        """Plain dict of the fields (for metadata); the :data:`OPTIONAL_KEYS` that are None are left
        out (module docstring)."""
        d = asdict(self)
        for key in OPTIONAL_KEYS:
            if d[key] is None:
                del d[key]
        return d

    @classmethod
    def from_dict(cls, data: dict, where: str = "the configuration") -> "SlideConfig":
        """Build from a dict, reporting every unknown key at once; an error about a key the dict does not hold says
        that the value is the default and that ``where`` sets it."""
        data = dict(data.get("slide", data))
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - names)
        if unknown:
            raise ParameterError(f"unknown slide configuration keys {unknown}; "
                                 f"allowed: {sorted(names)}")
        try:
            return cls(**data)
        except ParameterError as exc:
            key = error_key(exc)
            if key is None or key in data:
                raise
            raise ParameterError(f"{exc} ({key} is not set: this is its default; set {key} in {where})") from None

    @classmethod
    def from_toml(cls, path) -> "SlideConfig":
        """Read a TOML file (keys at the top level or under ``[slide]``)."""
        path = Path(path)
        try:
            with path.open("rb") as fh:
                data = tomllib.load(fh)
        except FileNotFoundError:
            raise ParameterError(f"configuration file {str(path)!r} does not exist") from None
        except tomllib.TOMLDecodeError as exc:
            raise ParameterError(f"configuration file {str(path)!r} is not valid TOML: {exc}") \
                from None
        return cls.from_dict(data, f"{path}")


def error_key(exc: ParameterError) -> str | None:
    """The SlideConfig key a ParameterError of :meth:`SlideConfig.__post_init__` is about (its messages start with
    the key), or None."""
    word = str(exc).split(" ", 1)[0]
    return word if word in {f.name for f in fields(SlideConfig)} else None


def _number(name: str, value, unit: str) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(f"{name} = {value!r} {unit} is not a number; allowed: a finite number")


def _int(name: str, value, low: int) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise ParameterError(f"{name} = {value!r} must be an integer >= {low}")
