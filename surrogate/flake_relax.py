"""Overdamped flake solver: the flakes relax to force and torque balance as the tool slides (Sec. 5, the
overdamped limit of Eq. 15-16).

Why. Eq. 15-16 with the damping of the oil (:mod:`tribocosim.surrogate.dem`) written per unit sliding
distance s = v0 t reads, for each coordinate x of a flake,

    x'' + (gamma / v0) x' = F / (m v0^2),

and the damping per pixel of slide is Lambda = gamma dx / v0: the distance over which a flake's velocity
decays, in pixels, is 1 / Lambda. At the strip-draw test's speed the flakes are overdamped: Lambda = 218
at 0.08 m/s and 35 at 0.5 m/s (VG 32 oil, 12 um flakes, 1 um pixels, the smallest of the four rates), and
the same placement slid at 0.08 and 0.5 m/s gives the same <A_p> within 0.2 % (docs/physics/table_domain.md).
The inertial DEM nevertheless resolves the contact vibrations of the penalty law, ~1,700 substeps per pixel
set by the penalty stiffness, not by the sliding. In the limit Lambda -> oo the inertia drops out:

    D x' = F(x, s) / v0,        D = diag(m gamma_v, I gamma_L) in the flake's principal axes,

(x the six coordinates of every flake, F the penalty forces and torques of both surfaces and the other
flakes), a gradient flow of the penalty energy E in the metric of the drag.

Method. The tool's shift and height and the sheet move through a pixel in ``n_sub`` equal substeps, as in
the DEM phase of the staggered loop (:mod:`tribocosim.surrogate.coupling`). At each substep the flakes move from
where they are to force and torque balance, F = 0, along the flow: Levenberg-Marquardt steps

    delta = (H + nu D)^-1 F,

H the Gauss-Newton Hessian of E (exact for the penalty energy k w d^2 / 2 up to terms in the overlap d times the
surfaces' curvature), per group of flakes in contact (a flake alone: 6 unknowns), with nu at least ~1e-8 of a face
point's stiffness over the drag and raised until the step moves no point of the group by more than the step
radius; a step is kept when the group's energy falls by at least 1e-4 of what the quadratic model predicts, and
nu follows the ratio of the two. Steps no longer than RADIUS_FRACTION h_p (10 nm) follow the path of the flow
rather than jump to whichever equilibrium the linearised contacts point at; on a straight stretch of the path (a
step the radius shortened, predicted well and in the direction of the one before) the radius doubles, up to half
a pixel. A substep ends when the step with the least nu moves no point of any flake by more than ``tol_move``
(1e-3 h_p; a point of a flake moves by at most |dx_c| + a |dtheta|). The contact law, its forces and its
Hessian are the DEM's (:mod:`tribocosim.surrogate.dem_kernels`), read again only where a flake or the surfaces
moved (:mod:`tribocosim.surrogate.relax_kernels`). A flake with no contact is not touched: it stays where it is,
as an overdamped flake with no force does.

The drag D enters only the direction of a step (the metric of the descent), not where the flow ends: the
overdamped flake's equilibrium under the physical drag, which at the test's speed is ~1e-7 of the contact
stiffness (D v0 / ds: 1 N/m against k_A pi a^2 = 6e6 N/m for a 12 um flake at 0.08 m/s), so the cost depends
neither on v0 nor on the penalty stiffness.

What it drops. Inertia: a flake released by a contact glides v/gamma (at most ~dx / Lambda, 5 nm at 0.08 m/s) in
the DEM and not at all here, and a flake that snaps from one equilibrium to another follows the drag-weighted
descent instead of an inertial path. Below Lambda ~ 1 (fast slides, thin oil: the velocity study of
docs/physics/alpha_velocity.md) that is wrong, and the inertial DEM is used: :data:`LAMBDA_MIN` bounds the regime
a slide may use this solver in, and docs/physics/flake_solvers.md compares the two solvers on paired placements
(and why they differ where they do: the DEM's similarity speed multiplies the drag forces).

Substeps. A substep's motion of the surfaces relative to a flake is at most slope x dx / n_sub + the tool's
vertical move (0.34 um / n_sub on the roll-off surfaces' RMS slope): with the default 8 substeps ~8 % of h_p. A
pixel whose iterations do not balance a substep within :data:`MAX_ITER` is redone from its start with twice the
substeps, up to :data:`MAX_REFINE` times.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tribocosim.errors import ConvergenceError, ParameterError

from . import relax_kernels as _k
from .dem import BLOWUP_FRACTION, DemBlowUpError, DemParams, DemState
from .flake_body import DampingRates

#: default substeps per pixel
RELAX_SUBSTEPS = 8
#: the Newton iteration stops when no flake moves by more than this fraction of h_p in an iteration
TOL_MOVE_FRACTION = 1e-3
#: least Levenberg-Marquardt damping nu D, as a fraction of the stiffness k_A dx^2 of one face point (module
#: docstring)
NU_FLOOR_FRACTION = 1e-8
#: largest displacement of a point of a flake in one iteration, as a fraction of h_p: small steps follow the
#: path of the drag-weighted descent, as the overdamped flake does, instead of jumping to another equilibrium;
#: on a straight stretch of the path it doubles, up to a fraction of the pixel (the bilinear surfaces are smooth
#: within a pixel, as far as a linearised contact can be trusted)
RADIUS_FRACTION = 0.02
RADIUS_MAX_FRACTION = 0.5
#: a partial reading of a flake's face considers the points that were within this fraction of h_p of
#: contact at its last full reading (:mod:`tribocosim.surrogate.relax_kernels`)
NEAR_FRACTION = 0.5
#: iterations per substep before the pixel is redone with more substeps
MAX_ITER = 1000
#: times a pixel is redone with twice the substeps before the solve is given up
MAX_REFINE = 4
#: smallest damping per pixel Lambda = gamma_min dx / v0 the overdamped solver accepts
LAMBDA_MIN = 20.0


def damping_per_pixel(rates: DampingRates, dx: float, v0: float) -> float:
    """Lambda = gamma dx / v0 of the least damped of the four motions (module docstring)."""
    return min(rates.as_tuple()) * dx / v0


@dataclass
class RelaxStats:
    """Work of the solver, accumulated over calls: refreshes of the forces, iterations, rejected component
    steps, the largest coupled group of flakes solved together, component solves, substeps, face parts read
    whole and in part, pair parts read and proven unchanged (:mod:`tribocosim.surrogate.relax_kernels`), and
    pixels redone with more substeps."""

    evaluations: int = 0
    iterations: int = 0
    rejected: int = 0
    largest_group: int = 0
    solves: int = 0
    substeps: int = 0
    face_reads: int = 0
    face_partial_reads: int = 0
    pair_reads: int = 0
    pair_skips: int = 0
    refinements: int = 0

    def add(self, counts: np.ndarray, refinements: int) -> None:
        self.evaluations += int(counts[_k._EVALS])
        self.iterations += int(counts[_k._ITERS])
        self.rejected += int(counts[_k._REJECTED])
        self.largest_group = max(self.largest_group, int(counts[_k._LARGEST]))
        self.solves += int(counts[_k._SOLVED])
        self.substeps += int(counts[_k._SUBSTEPS])
        self.face_reads += int(counts[_k._FACE_READS])
        self.pair_reads += int(counts[_k._PAIR_READS])
        self.face_partial_reads += int(counts[_k._FACE_PARTIAL])
        self.pair_skips += int(counts[_k._PAIR_SKIPS])
        self.refinements += refinements

    def as_dict(self) -> dict:
        return dict(vars(self))


@dataclass(frozen=True)
class Drag:
    """The drag of a flake, D = diag(m gamma_v, I gamma_L) in its principal axes (module docstring): the
    metric in which the flakes descend."""

    rates: DampingRates
    mass: float
    inertia: tuple[float, float]

    def __post_init__(self):
        if min(self.rates.as_tuple()) <= 0.0:
            raise ParameterError(
                f"damping rates {self.rates.as_tuple()} 1/s: the overdamped flake solver needs every rate > 0 "
                f"(an oil viscosity > 0); allowed: the inertial DEM (flake_solver = 'inertial') without damping")

    def coefficients(self) -> tuple[float, float, float, float]:
        """(m gamma_plane, m gamma_axial, I1 gamma_diameter, I3 gamma_axis) [kg/s, kg/s, kg m^2/s, kg m^2/s]."""
        i1, i3 = self.inertia
        r = self.rates
        return (self.mass * r.velocity_plane, self.mass * r.velocity_axial, i1 * r.angmom_diameter,
                i3 * r.angmom_axis)


def relax(state: DemState, params: DemParams, drag: Drag, h_low, h_top, n_sub: int,
          shift0: float = 0.0, dshift: float = 0.0, top_offset: float = 0.0, dtop: float = 0.0,
          dh_low=None, stats: RelaxStats | None = None, where: str = "") -> None:
    """Move the surfaces through ``n_sub`` substeps and relax ``state`` in place at each (module docstring).

    At substep s (1..n_sub) the tool is shifted by ``shift0 + s*dshift`` in +x and sits at
    ``top_offset + s*dtop``; the sheet is ``h_low + (s/n_sub) dh_low`` (``dh_low`` None: fixed). The
    arguments are those of :func:`tribocosim.surrogate.dem.advance`; ``params.dt`` and its damping are not
    used (the drag is ``drag``'s).

    Raises
    ------
    DemBlowUpError
        On a non-finite state or an overlap above 50 % of h_p at the end of a substep.
    ConvergenceError
        When a substep does not converge even with 2^MAX_REFINE times the substeps.
    """
    if n_sub < 1:
        raise ParameterError(f"substeps n_sub = {n_sub}; allowed: >= 1")
    sh = params.shape
    h_low = np.ascontiguousarray(h_low, dtype=np.float64)
    h_top = np.ascontiguousarray(h_top, dtype=np.float64)
    dh = np.zeros_like(h_low) if dh_low is None else np.ascontiguousarray(dh_low, dtype=np.float64)
    ramp = 0.0 if dh_low is None else 1.0
    nf = len(state.pos)
    force, torque, overlap = np.zeros((nf, 3)), np.zeros((nf, 3)), np.zeros(nf)
    pos0, quat0 = state.pos.copy(), state.quat.copy()
    shift_total, dtop_total = n_sub * dshift, n_sub * dtop
    coeffs = drag.coefficients()
    nu_floor = NU_FLOOR_FRACTION * params.k_area * params.dx**2 / coeffs[0]
    for refine in range(MAX_REFINE + 1):
        m = n_sub << refine
        counts = np.zeros(_k.N_STATS, dtype=np.int64)
        status, sub, flake = _k._relax(
            state.pos, state.quat, h_low, dh, ramp, h_top, float(shift0), shift_total / m,
            float(top_offset), dtop_total / m, params.dx, params.size, sh.a, sh.c, params.samples,
            params.weights, params.k_area, *coeffs, m, BLOWUP_FRACTION * sh.thickness,
            TOL_MOVE_FRACTION * sh.thickness, nu_floor, RADIUS_FRACTION * sh.thickness,
            RADIUS_MAX_FRACTION * params.dx, NEAR_FRACTION * sh.thickness,
            MAX_ITER, force, torque, overlap, *params.pair_points, counts)
        if stats is not None:
            stats.add(counts, refine)
        if status != 3:
            break
        state.pos[:], state.quat[:] = pos0, quat0  # redo the pixel with twice the substeps
    else:
        raise ConvergenceError(
            f"overdamped flake solver {where}: Newton did not converge in {MAX_ITER} iterations at substep "
            f"{sub} of {m} ({MAX_REFINE} refinements of {n_sub} substeps)")
    if status == 0:
        return
    if status == 1:
        raise DemBlowUpError(f"overdamped flakes {where}: non-finite position of flake {flake} at substep "
                             f"{sub} of {m}")
    raise DemBlowUpError(
        f"overdamped flakes {where}: overlap {overlap[flake]:.3e} m = {overlap[flake] / sh.thickness:.0%} of "
        f"h_p at substep {sub} of {m}, flake {flake}, exceeds the allowed {BLOWUP_FRACTION:.0%} "
        f"(pos = {state.pos[flake].tolist()})")

