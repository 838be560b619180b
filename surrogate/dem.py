"""DEM of rigid, frictionless oblate flakes between two periodic height fields (Sec. 5, Eq. 15-16).

Geometry. A flake is an oblate spheroid with in-plane semi-axis a = d_p/2 and half-thickness
c = h_p/2 (c < a). In its body frame (symmetry axis = body z) its lower/upper face over the
in-plane point (x_b, y_b), r^2 = x_b^2 + y_b^2 <= a^2, is at z_b = -/+ c sqrt(1 - r^2/a^2).
Mass m = rho (4/3) pi a^2 c; principal moments I1 = I2 = m (a^2 + c^2)/5, I3 = 2 m a^2/5
(rho = 2700 kg/m^3 for Al by default).

Equations of motion (Eq. 15-16), with the damping written as a rate gamma [1/s]
(eta = gamma m for translation and gamma I for rotation, so both relax on the same time 1/gamma):

    m dv/dt = f_DEM + f_surface - gamma m v,       dL/dt = tau_DEM + tau_surface - gamma L,

L = I omega the angular momentum in the space frame. Gravity is neglected (it is ~1e-9 of the
contact forces).

Damping from the lubricant (the default, :meth:`DampingRates.from_viscosity`). The paper's single eta for
translation and rotation cannot be one physical coefficient (a force per velocity and a torque per
angular velocity differ by a length squared); the flakes move in the oil film, so the damping can
instead be the quasi-steady Stokes drag of a thin disc of radius a (thickness << a) in a Newtonian
fluid of dynamic viscosity eta at rest (Happel & Brenner, Low Reynolds Number Hydrodynamics,
Prentice-Hall 1965, Ch. 4-5; Kim & Karrila, Microhydrodynamics, Butterworth-Heinemann 1991, Ch. 3: the
oblate spheroid for c/a -> 0; tests/surrogate/test_dem_damping.py recovers all four from the ellipsoid
integrals of Oberbeck, J. reine angew. Math. 81 (1876) 62, and Jeffery, Proc. R. Soc. A 102 (1922) 161,
doi:10.1098/rspa.1922.0078):

    broadside (velocity along the symmetry axis n):  F = -16 eta a v_n
    edgewise (velocity in the flake's plane):         F = -(32/3) eta a v_p
    rotation about a diameter and about the axis:     T = -(32/3) eta a^3 omega

(At the flake's own c/a = 0.04 the spheroid's resistances exceed these by 0.1-5 %.)
These are the principal resistances, so no orientation average is needed: the damping acts in the
flake's principal axes with four rates,

    gamma_v,axial = 16 eta a / m,                gamma_v,plane = (32/3) eta a / m,
    gamma_L,diameter = (32/3) eta a^3 / I1,      gamma_L,axis = (32/3) eta a^3 / I3,

the components of v and L along n decaying at the axial rates, the rest at the others (L = I omega
with I1 about a diameter, I3 about the axis). (The orientation-averaged translational resistance, the
harmonic mean 12 eta a, would be the single coefficient of an isotropic model.) Reference viscosity
(the default of a slide, ``SlideConfig.oil_viscosity``): ISO 3448 grade VG 32, 32 mm^2/s
at 40 C, times a mineral-oil density of ~870 kg/m^3, is 0.028 Pa s (:data:`tribocosim.surrogate.flake_body.VG32_VISCOSITY_40C`);
mineral oils span ~0.01-0.5 Pa s at 40 C (VG 10 to VG 460). For a 12 um flake in VG 32 the rates are
1.8e7 (plane), 2.6e7 (axial), 8.7e7 (diameter) and 4.4e7 (axis) 1/s.

Validity, and why these rates are a lower bound: (i) low Reynolds number, Re = rho_oil |v| a / eta:
0.19 per m/s of flake speed for a = 6 um in VG 32, so ~0.4 at 2 m/s but ~9 at 50 m/s, where the real
drag is larger (Oseen correction, then form drag); (ii) quasi-steady flow, i.e. motions slower than the
viscous diffusion time rho_oil a^2 / eta ~ 1 us, whereas the flake relaxes in 1/gamma ~ 10-60 ns, so
the neglected added mass (broadside (8/3) rho_oil a^3, ~5 flake masses) and Basset history force
resist fast transients further; (iii) unbounded fluid, whereas the paper's 1.12 g/m^2 of oil is a
mean film of ~1.3 um, thinner than the flake is wide: a flake at a gap delta < a from a wall feels the
Couette drag eta pi a^2 / delta per face in its plane and the squeeze-film force
(3 pi / 2) eta a^4 / delta^3 broadside (Reynolds lubrication), at delta = 1 um and a = 6 um ~3.5 and
~60 times the values above; (iv) the oil is taken at rest in the sheet's frame (it is sheared
between sheet and tool, mean speed ~v0/2).

Contact (frictionless penalty). The face is sampled at ns body-frame points on concentric rings
(the last one on the rim), each carrying its share dA of the area pi a^2. The face looking down
(the body face whose outward normal has a negative z component) is tested against the lower
surface h_low(x, y), the other against the tool
h_top(x - s(t), y) + z_top (the tool slides by s(t) = v0 t in +x). With the vertical overlap
d = h_low - z (resp. z - h_top) the penalty energy of a point is k_A dA d^2 / 2 and its force is
the exact gradient, k_A dA d (-dh/dx, -dh/dy, 1) (resp. k_A dA d (dh/dx, dh/dy, -1)): along the
surface normal, applied at the point (hence a torque). Heights and gradients come from the
periodic bilinear interpolant of the pixel values (sub-pixel sliding included). Within
:func:`advance`, a face point is not read while the gap it had when last read, less the most the
flake, the tool and the sheet can have moved towards each other since, is still positive, nor a
flake pair whose centres are provably further apart than 2a (:mod:`tribocosim.surrogate.dem_kernels`;
this changes no number, bit for bit).
Flake-flake contact approximates each flake by a sphere-swept mid-plane disc (core radius a - c,
sweep radius c): the points of one disc are tested against the other disc, overlap
d = 2c - distance, force k_A dA d / 2 along the separation (both flakes of a pair are sampled,
hence the half), equal and opposite on the closest point of the other disc (linear and angular
momentum are conserved).

Penalty stiffness rule (paper: overlap <= 5 % of h_p at the Hertz-estimated peak force): the
peak force is Hertz's for the flake's pole (radius of curvature R = a^2/c) hitting a flat
half-space of modulus E* normally at v_ref = v0 (Johnson, Contact Mechanics, 1985, Sec. 11.4):
d_H = (15 m v^2 / (16 E* sqrt(R)))^(2/5), F_H = (4/3) E* sqrt(R) d_H^(3/2). With the penalty
pressure k_A d, the pole contact carries F(d) = k_A pi R d^2 (paraboloid), stores
U(d) = k_A pi R d^3/3, so F(d_a) = F_H at the allowed overlap d_a = 0.05 h_p needs
k_A = F_H / (pi R d_a^2) (static rule); and U(d_a) >= m v^2/2 (the impact stops within d_a) needs
a factor 1.2 d_H/d_a when that exceeds 1 (dynamic rule):
k_A = F_H / (pi R d_a^2) * max(1, 1.2 d_H/d_a).

Time step: the stiffest contact is a flake pressed flat on both faces (translational stiffness
2 k_A pi a^2, rocking stiffness 2 k_A pi a^4 / 4 over I1 ~ m a^2/5, i.e. omega^2 = 2.5 k_A pi a^2/m),
doubled to cover simultaneous flake-flake contacts: omega_max = sqrt(5 k_A pi a^2 / m);
dt = safety * 2/omega_max with safety = 0.1 (Verlet is stable up to 2/omega; 0.1 keeps the
energy error of a flake bouncing between two flat surfaces below 0.3 %, 0.2 gives ~1.2 %). In the sliding loop
dt is further reduced so that an integer number of steps covers one pixel (n_sub v0 dt = dx).

Integrator (symmetric Strang splitting; second order, time-reversible): per step
damping half-flow (v, L *= exp(-gamma dt/2); with four rates the same per principal component, exact
as the orientation is fixed in this sub-flow), half kick (v += dt f/2m, L += dt tau/2), drift
(x += dt v, exact torque-free rotation over dt), forces, half kick, damping half-flow. For gamma = 0
the translation is exactly velocity-Verlet. The torque-free motion of an axisymmetric body is
integrated exactly: the flows of |L|^2/2I1 and L3^2 (1/I3 - 1/I1)/2 commute, i.e. a rotation
by |L| dt/I1 about the space-fixed L followed by a rotation by L3 (1/I3 - 1/I1) dt about the body
symmetry axis (Landau & Lifshitz, Mechanics, Sec. 33; the splitting is that of Dullweber,
Leimkuhler & McLachlan, J. Chem. Phys. 107 (1997) 5840, doi:10.1063/1.474310, with the exact
symmetric-top flow as the free step).

A run stops with :class:`DemBlowUpError` (naming the step and the flake) when a state becomes
non-finite or an overlap exceeds 50 % of h_p.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tribocosim.errors import ParameterError, TribocosimError, check_range

from . import dem_kernels as _k
from .flake_body import DampingRates, FlakeShape, check_nonnegative, rotation_matrices

#: allowed overlap (fraction of h_p) at the Hertz-estimated peak force
OVERLAP_FRACTION = 0.05
#: overlap (fraction of h_p) above which a run is stopped as a blow-up
BLOWUP_FRACTION = 0.5
#: safety factor on the Verlet stability limit 2/omega_max
DT_SAFETY = 0.1


class DemBlowUpError(TribocosimError):
    """The DEM state became non-finite or an overlap exceeded 50 % of the flake thickness."""


def face_samples(shape: FlakeShape, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Body-frame in-plane sample points of a flake face and their areas.

    Concentric rings r_k = k a/K, k = 0..K (K = ceil(a/spacing), at least 3): the centre, and
    n_k = max(6, round(2 pi r_k/Delta)) points on ring k (Delta = a/K, alternate rings rotated by
    half a spacing), the outermost ring on the rim r = a. A point of ring k carries the area of
    the annulus [r_k - Delta/2, r_k + Delta/2] (clipped to [0, a]) divided by n_k, so the areas
    sum to pi a^2 and the rim (which meets other flakes edge-on) is always sampled.

    Parameters
    ----------
    shape : FlakeShape
    spacing : float
        Target spacing of the points [m] (default in :meth:`DemParams.build`: one pixel, as the
        surfaces are bilinear between pixels).

    Returns
    -------
    points : ndarray, shape (ns, 2)
    weights : ndarray, shape (ns,)
        Areas [m^2].
    """
    check_range("sample spacing", spacing, 0.0, None, low_inclusive=False, unit="m")
    a = shape.a
    n_rings = max(3, int(math.ceil(a / spacing)))
    delta = a / n_rings
    pts, wts = [np.zeros((1, 2))], [np.array([math.pi * (0.5 * delta) ** 2])]
    for k in range(1, n_rings + 1):
        r = k * delta
        n_k = max(6, int(round(2.0 * math.pi * r / delta)))
        r_in, r_out = r - 0.5 * delta, min(a, r + 0.5 * delta)
        phi = 2.0 * math.pi * (np.arange(n_k) + 0.5 * (k % 2)) / n_k
        pts.append(np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1))
        wts.append(np.full(n_k, math.pi * (r_out**2 - r_in**2) / n_k))
    return np.ascontiguousarray(np.concatenate(pts)), np.ascontiguousarray(np.concatenate(wts))


def penalty_stiffness(shape: FlakeShape, e_star: float, v_ref: float,
                      overlap_fraction: float = OVERLAP_FRACTION) -> float:
    """Penalty pressure per unit overlap k_A [N/m^3] from the Hertz rule (module docstring).

    Parameters
    ----------
    shape : FlakeShape
    e_star : float
        Effective modulus of the flake-surface contact [Pa].
    v_ref : float
        Impact speed of the Hertz estimate [m/s] (the tool speed v0).
    overlap_fraction : float
        Allowed overlap as a fraction of h_p at the peak force.
    """
    check_range("E*", e_star, 0.0, None, low_inclusive=False, unit="Pa")
    check_range("v_ref", v_ref, 0.0, None, low_inclusive=False, unit="m/s")
    m, radius = shape.mass, shape.a**2 / shape.c
    d_a = overlap_fraction * shape.thickness
    d_h = (15.0 * m * v_ref**2 / (16.0 * e_star * math.sqrt(radius))) ** 0.4
    f_h = 4.0 / 3.0 * e_star * math.sqrt(radius) * d_h**1.5
    return f_h / (math.pi * radius * d_a**2) * max(1.0, 1.2 * d_h / d_a)


def stable_time_step(shape: FlakeShape, k_area: float, safety: float = DT_SAFETY) -> float:
    """Time step safety * 2/omega_max, omega_max = sqrt(5 k_A pi a^2/m) (module docstring)."""
    check_range("dt safety factor", safety, 0.0, 1.0, low_inclusive=False)
    return safety * 2.0 / math.sqrt(5.0 * k_area * shape.area / shape.mass)


@dataclass(frozen=True)
class DemParams:
    """Everything the DEM kernels need besides the state and the two height fields.

    Attributes
    ----------
    shape : FlakeShape
    size : float
        Side L of the periodic square domain [m].
    dx : float
        Pixel size of the height fields [m].
    k_area : float
        Penalty pressure per unit overlap k_A [N/m^3].
    damping : float or DampingRates
        One damping rate gamma [1/s] (>= 0) for every component, or the rates in the flake's
        principal axes (:meth:`DampingRates.from_viscosity`).
    dt : float
        Time step [s].
    samples : ndarray
        Face sample points (ns, 2) [m], from :func:`face_samples`.
    weights : ndarray
        Their areas (ns,) [m^2], from :func:`face_samples`.
    pair_samples, pair_weights : ndarray or None
        The points and areas of a flake's disc in flake-flake contact (None: ``samples`` and
        ``weights``), from :func:`face_samples` at a coarser spacing when given.
    """

    shape: FlakeShape
    size: float
    dx: float
    k_area: float
    damping: float | DampingRates
    dt: float
    samples: np.ndarray
    weights: np.ndarray
    pair_samples: np.ndarray | None = None
    pair_weights: np.ndarray | None = None

    @classmethod
    def build(cls, shape: FlakeShape, size: float, dx: float, e_star: float, v_ref: float,
              damping: float | DampingRates, dt: float | None = None, spacing: float | None = None,
              dt_safety: float = DT_SAFETY, pair_spacing: float | None = None) -> "DemParams":
        """Parameters from the documented rules: Hertz penalty, stable dt, one-pixel sampling (of the
        flake-flake contact too unless ``pair_spacing`` is given)."""
        k = penalty_stiffness(shape, e_star, v_ref)
        dt = stable_time_step(shape, k, dt_safety) if dt is None else dt
        pts, wts = face_samples(shape, dx if spacing is None else spacing)
        pair = (None, None) if pair_spacing is None else face_samples(shape, pair_spacing)
        return cls(shape, size, dx, k, damping, dt, pts, wts, *pair)

    @property
    def pair_points(self) -> tuple[np.ndarray, np.ndarray]:
        """The points and areas of the flake-flake contact (module docstring)."""
        if self.pair_samples is None:
            return self.samples, self.weights
        return self.pair_samples, self.pair_weights

    def __post_init__(self):
        check_range("domain size L", self.size, 0.0, None, low_inclusive=False, unit="m")
        check_range("pixel size dx", self.dx, 0.0, self.size, low_inclusive=False, unit="m")
        check_range("penalty k_A", self.k_area, 0.0, None, low_inclusive=False, unit="N/m^3")
        if not isinstance(self.damping, DampingRates):
            check_nonnegative("damping rate", self.damping, "1/s")
        check_range("DEM time step", self.dt, 0.0, None, low_inclusive=False, unit="s")
        if self.shape.diameter >= 0.5 * self.size:
            raise ParameterError(
                f"flake diameter d_p = {self.shape.diameter:g} m does not fit the domain "
                f"L = {self.size:g} m; allowed: d_p < L/2")

    @property
    def rates(self) -> DampingRates:
        """The damping as rates in the principal axes (four equal rates for a scalar gamma)."""
        if isinstance(self.damping, DampingRates):
            return self.damping
        return DampingRates.uniform(self.damping)


@dataclass
class DemState:
    """Mutable state of nf flakes (space frame, SI units).

    Attributes
    ----------
    pos : ndarray (nf, 3)   centre positions [m]; x, y kept in [0, L)
    quat : ndarray (nf, 4)  unit quaternions (w, x, y, z), body -> space
    vel : ndarray (nf, 3)   centre velocities [m/s]
    angmom : ndarray (nf, 3) angular momenta about the centres, space frame [kg m^2/s]
    """

    pos: np.ndarray
    quat: np.ndarray
    vel: np.ndarray
    angmom: np.ndarray

    def __post_init__(self):
        self.pos = np.ascontiguousarray(self.pos, dtype=np.float64).reshape(-1, 3)
        nf = len(self.pos)
        self.quat = np.ascontiguousarray(self.quat, dtype=np.float64).reshape(nf, 4)
        self.vel = np.ascontiguousarray(self.vel, dtype=np.float64).reshape(nf, 3)
        self.angmom = np.ascontiguousarray(self.angmom, dtype=np.float64).reshape(nf, 3)

    @classmethod
    def at_rest(cls, pos, quat=None) -> "DemState":
        """Flakes at rest at ``pos``; flat (identity orientation) unless ``quat`` is given."""
        pos = np.asarray(pos, dtype=np.float64).reshape(-1, 3)
        nf = len(pos)
        if quat is None:
            quat = np.tile([1.0, 0.0, 0.0, 0.0], (nf, 1))
        return cls(pos, quat, np.zeros((nf, 3)), np.zeros((nf, 3)))

    def copy(self) -> "DemState":
        """A deep copy."""
        return DemState(self.pos.copy(), self.quat.copy(), self.vel.copy(), self.angmom.copy())


def angular_velocity(state: DemState, shape: FlakeShape) -> np.ndarray:
    """omega = L/I1 + (L.n)(1/I3 - 1/I1) n, n the body symmetry axis in space (nf, 3)."""
    i1, i3 = shape.inertia
    n = rotation_matrices(state.quat)[:, :, 2]
    l3 = np.sum(state.angmom * n, axis=1)
    return state.angmom / i1 + (l3 * (1.0 / i3 - 1.0 / i1))[:, None] * n


def kinetic_energy(state: DemState, shape: FlakeShape) -> float:
    """Translational plus rotational kinetic energy [J]."""
    om = angular_velocity(state, shape)
    return float(0.5 * shape.mass * np.sum(state.vel**2) + 0.5 * np.sum(om * state.angmom))


def _field(h) -> np.ndarray:
    return np.ascontiguousarray(h, dtype=np.float64)


def compute_forces(state: DemState, params: DemParams, h_low, h_top, top_shift=0.0,
                   top_offset=0.0):
    """Penalty forces on every flake for the current configuration.

    Parameters
    ----------
    state : DemState
    params : DemParams
    h_low, h_top : ndarray (n, n)
        Lower surface and tool heights [m], indexed [ix, iy], periodic.
    top_shift : float
        Tool displacement s in +x [m]: the tool height at (x, y) is h_top(x - s, y) + top_offset.
    top_offset : float
        Vertical position of the tool [m].

    Returns
    -------
    force, torque : ndarray (nf, 3)
        Space-frame forces [N] and torques about the centres [N m].
    overlap : ndarray (nf,)
        Largest overlap of each flake [m].
    energy : float
        Penalty energy [J].
    """
    nf = len(state.pos)
    force, torque, overlap = np.zeros((nf, 3)), np.zeros((nf, 3)), np.zeros(nf)
    sh = params.shape
    h_low, h_top = _field(h_low), _field(h_top)
    pairs = np.ascontiguousarray(np.stack(np.triu_indices(nf, 1), axis=1), dtype=np.int64)
    energy = _k._forces(state.pos, state.quat, h_low, h_low, 0.0, 0.0, h_top, float(top_shift),
                        float(top_offset), params.dx, params.size, sh.a, sh.c, params.samples,
                        _k._face_heights(params.samples, sh.a, sh.c), params.weights, params.k_area,
                        force, torque, overlap, np.empty((nf, 3, 3)), np.empty((0, 2, _k._RECORD)),
                        np.empty((0, 2, len(params.samples))), np.empty((0, 2, 3)),
                        np.empty((0, 2, 1), dtype=np.int64), np.empty((nf, 2), dtype=np.int64),
                        np.zeros((nf, 2)), _k.REACH_PX, pairs, len(pairs), *params.pair_points)
    return force, torque, overlap, float(energy)


def advance(state: DemState, params: DemParams, h_low, h_top, n_steps: int, shift0: float = 0.0,
            dshift: float = 0.0, top_offset: float = 0.0, dtop: float = 0.0,
            dh_low=None, step_offset: int = 0, clearance: bool = True) -> None:
    """Advance ``state`` in place by ``n_steps`` steps of ``params.dt``.

    At step s (0..n_steps) of this call the tool is shifted by ``shift0 + s*dshift`` in +x and
    sits at the height ``top_offset + s*dtop``; the lower surface is ``h_low + (s/n_steps) dh_low``
    (``dh_low`` None: fixed).

    ``clearance``: skip reading the faces that a clearance record proves out of contact (module
    docstring; the result is the same bit for bit). False reads every face at every step (the
    reference path of the tests).

    Raises
    ------
    DemBlowUpError
        On a non-finite state or an overlap above 50 % of h_p; the message names the global
        step (``step_offset`` + step within the call) and the flake; ``state`` is left at the
        offending step.
    """
    if n_steps < 0:
        raise ParameterError(f"n_steps = {n_steps} is negative; allowed: >= 0")
    nf = len(state.pos)
    force, torque, overlap = np.zeros((nf, 3)), np.zeros((nf, 3)), np.zeros(nf)
    sh = params.shape
    i1, i3 = sh.inertia
    limit = BLOWUP_FRACTION * sh.thickness
    h_low, h_top = _field(h_low), _field(h_top)
    dh = np.zeros_like(h_low) if dh_low is None else _field(dh_low)
    status, step, flake = _k._advance(
        state.pos, state.quat, state.vel, state.angmom, h_low, dh,
        0.0 if dh_low is None else 1.0, h_top, float(shift0), float(dshift), float(top_offset),
        float(dtop), params.dx, params.size, sh.a, sh.c,
        params.samples, params.weights, params.k_area, sh.mass, i1, i3, *params.rates.as_tuple(),
        params.dt, int(n_steps), limit, force, torque, overlap, bool(clearance), *params.pair_points)
    if status == 0:
        return
    where = f"at DEM step {step_offset + step} (step {step} of this call), flake {flake}"
    if status == 1:
        raise DemBlowUpError(f"DEM blow-up {where}: non-finite position/velocity "
                             f"(pos = {state.pos[flake].tolist()})")
    raise DemBlowUpError(
        f"DEM blow-up {where}: overlap {overlap[flake]:.3e} m = "
        f"{overlap[flake] / sh.thickness:.0%} of h_p exceeds the allowed "
        f"{BLOWUP_FRACTION:.0%} (pos = {state.pos[flake].tolist()})")
