"""The staggered BEM-DEM sliding loop (Sec. 5, Fig. 7; Eq. 17-19, 22).

Frames and signs. z points up; all heights are in the lab frame of the sheet. The sheet (elastic-
plastic, below) has the undeformed profile h_def0 and, after a contact solve, the surface
h_low = h_def0 - u_p - (u_e - <u_e>) (u positive into the sheet; the mean of the periodic
elastic field is the rigid approach and is carried by the tool instead). The rigid tool (above)
has the profile h_tool0 (tool frame), slides by s in +x and sits at the height z_top:
h_top(x, y) = h_tool0(x - s, y) + z_top. After one pixel of sliding (integer shift k, on the
grid: h_tool0 rolled by k along x) the loop

1. DEM (:mod:`tribocosim.surrogate.dem`) with both surfaces rigid while the tool advances one pixel at v0,
   n_sub steps with n_sub v0 dt = dx;
2. classifies each flake: *blocked* if the pixels of its footprint where its upper surface
   z_hi exceeds the tool h_top form >= 3 spatially distinct 8-connected clusters (Fig. 8), else
   free. Our addition (docs/model.md section 7 leaves the criterion open): a flake is also
   blocked when it is *pinched*, i.e. it does not fit between the sheet h_low and the tool's
   *envelope over the coming pixel*, h_env = min(h_top(k), h_top(k + 1)) (the lowest the tool comes
   at each pixel during the next DEM phase): the depths by which they cut into it, max(z_hi - h_env)
   and max(h_low - z_lo) over its footprint (grid), add up to more than 2
   ``pinch_overlap_fraction`` h_p, default 0 (touching both, or cut by one surface deeper than its
   clearance to the other). The rule is the non-penetration condition of the staggered
   scheme, not a friction criterion: during a DEM phase both surfaces are rigid, so a flake that
   the contact solve did not see is squeezed kinematically wherever the gap closes below h_p.
   A smooth tool asperity wider than the flake overlaps it in one cluster only, however hard it
   squeezes it, and on steep (roll-off) surfaces a tool flank can close the gap by ~slope x dx
   = 0.34 um within one pixel: a flake ignored by the solve was then crushed (overlap > 50 % h_p,
   the DEM stops; measured on the roll-off surfaces with the rule read at h_top(k) and a 10 %
   threshold). A pinched flake made part of the tool lets the solve dent the sheet under it
   (u_p), which is the sheet's real answer. A blocked flake also stays blocked while the tool
   still touches it (>= 1 overlap cluster): released earlier, the elastic part of its dent springs
   back and crushes it against the tool again. A_p counts every load-bearing (blocked) flake; A_p
   by the paper's cluster rule alone is recorded too (``particle_fraction_clusters``);
3. builds the modified tool (Eq. 18) h*_top = min(h_top, min_j z_lo_j) over the blocked flakes j
   (z_lo: the flake's lower surface: the blocked flake becomes part of the tool). A blocked flake
   enters the solve attached to the tool's underside (Fig. 7: "the particles are rigidly
   attached to the tool"): moved down by the depth the tool's envelope h_env cuts into it (so that
   it still fits under the tool after the coming pixel), so that the rigid tool + flake body has no
   interpenetration and the solve dents the sheet by the flake's full thickness; its faces are
   rasterised pixel-consistently with the DEM's bilinear surfaces (:func:`attach_to_tool`). The DEM
   flake itself is not moved: the tool's cut pushes it into the dent as the sheet moves there in
   the next DEM phase. Without this a flake sitting in its dent while the tool slides over it is
   cut deeper at each pixel
   (by about slope * dx) until the DEM stops; with it the flake is pressed (ploughed) into the
   sheet step by step;
4. solves the contact (Eq. 19-21) of the rigid profile g* = h*_top - h_def0 (Eq. 19; gap
   between the modified tool and the *undeformed* sheet) pressed with the mean pressure p on a
   flat elastic half-space with plastic saturation p_crit, passing and receiving the accumulated
   u_p; the new tool height z_top is the one where the modified tool meets the new sheet
   surface h_low at the contact pixels. Neither surface jumps there: during the next DEM phase
   the tool height moves linearly from the old to the new z_top and the sheet from the old to
   the new h_low (the surfaces move continuously; a jump of the order of h_p, e.g. the elastic
   spring-back under a released flake or the tool landing after it, would otherwise hit the
   flakes at once). The blocked flakes are not moved
   by the solve: the DEM pushes them with the tool into the sheet's dent. The set of load-bearing
   flakes must agree with the solve's answer: a flake the solve did not see that its new tool
   (envelope) and sheet pinch is added and the solve repeated from the same state (``resolves``
   counts these; the set only grows, so at most n_flakes repeats). Without this, at low pressure a
   flake that carries much of the load flip-flops: blocked, it lifts the tool off itself (by
   0.3 um = 0.6 h_p at 2 MPa on the roll-off surfaces), is released at the next pixel, and the
   solve without it drops the tool onto it; two such cycles crushed it (measured);
5. measures A_c = area with traction > 0 and A_p = area with traction > 0 under a blocked flake
   (Sec. 6.2).

<A_p>/A0 is the mean of A_p/A0 over the steps (Eq. 22).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import ndimage

from tribocosim.errors import ConvergenceError

from . import dem
from . import footprint_kernels as _k
from .flake_body import DampingRates
from .flake_relax import RELAX_SUBSTEPS, Drag, RelaxStats, relax
from .flakes import Footprint, Footprints, footprints, random_placement
from .slide_config import SlideConfig

#: a flake is blocked when it overlaps the tool in at least this many distinct clusters
MIN_CLUSTERS_BLOCKED = 3
_EIGHT = np.ones((3, 3), dtype=bool)


def overlap_clusters(fp: Footprint, h_top) -> int:
    """Number of 8-connected clusters of the footprint pixels where z_hi > h_top (Fig. 8)."""
    window = h_top[np.ix_(fp.ix, fp.iy)]
    mask = fp.inside & (np.nan_to_num(fp.z_hi, nan=-np.inf) > window)
    # the window is smaller than the domain, so the periodic labelling reduces to a plain one
    return int(ndimage.label(mask, structure=_EIGHT)[1])


def classify(fps, h_top, threshold: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Blocked flags (cluster rule, Fig. 8) and overlap-cluster counts against the tool ``h_top``
    (:func:`overlap_clusters` of every flake, labelled in one call); a pixel overlaps when the flake's upper
    surface is above the tool by more than ``threshold`` [m] (0: the paper's rule; negative: within that
    distance below it)."""
    fps = Footprints.of(fps)
    if not len(fps):
        return np.zeros(0, dtype=bool), np.zeros(0, dtype=np.int64)
    field = np.ascontiguousarray(h_top, dtype=np.float64)
    counts = _k._overlap_clusters(fps.flat_indices(field.shape[0]), fps.inside, fps.z_hi, field.reshape(-1),
                                  float(threshold))
    return counts >= MIN_CLUSTERS_BLOCKED, counts


def attach_to_tool(fp: Footprint, h_top, drop: float | None = None) -> tuple[Footprint, float]:
    """The footprint of a blocked flake as the contact solve sees it, and its drop [m].

    Pixel-consistent rasterisation: the DEM reads the surfaces by bilinear interpolation, so a
    surface lying below a flake's lower face at the pixels can still cut it between them (at the
    steep rim by up to ~c). The flake's lower face is therefore replaced by its 3 x 3 pixel
    minimum (grey erosion; the footprint grows by one pixel ring) and its upper face by its
    3 x 3 maximum. The flake is dropped by the depth that dilated upper face cuts into the tool
    (if positive), lower face included, or by ``drop`` when given (the drop of the stack it belongs
    to, :func:`stack_groups`).
    """
    z_lo = ndimage.minimum_filter(np.nan_to_num(fp.z_lo, nan=np.inf), size=3, mode="constant",
                                  cval=np.inf)
    z_hi = ndimage.maximum_filter(np.nan_to_num(fp.z_hi, nan=-np.inf), size=3, mode="constant",
                                  cval=-np.inf)
    if drop is None:
        drop = max(0.0, float(np.max(z_hi - h_top[np.ix_(fp.ix, fp.iy)])))
    z_lo = np.where(np.isfinite(z_lo), z_lo - drop, np.nan)
    z_hi = np.where(np.isfinite(z_hi), z_hi - drop, np.nan)
    return Footprint(fp.ix, fp.iy, z_lo, z_hi), drop


def stack_groups(fps, n: int) -> np.ndarray:
    """Label of the stack each flake belongs to: flakes whose footprints share a pixel (one lies on
    the other there) are in one stack, transitively; a flake alone is a stack of one.

    A stack meets the surfaces as one rigid body in :func:`pinched` and :func:`attach_stacks`: a
    flake resting on another is pressed into the sheet through it, so the pinch test reads the
    stack's top against the tool and its bottom against the sheet, and a blocked flake makes its
    whole stack load-bearing."""
    fps = Footprints.of(fps)
    if not len(fps):
        return np.zeros(0, dtype=np.int64)
    return _k._stack_labels(fps.flat_indices(n), fps.inside, n * n)


def _per_stack_max(values: np.ndarray, groups: np.ndarray | None) -> np.ndarray:
    """Each flake's ``values`` replaced by the largest over its stack (``groups`` None: unchanged)."""
    if groups is None or values.size == 0:
        return values
    top = np.full(int(groups.max()) + 1, -np.inf)
    np.maximum.at(top, groups, values)
    return top[groups]


def spread_to_stacks(flags: np.ndarray, groups: np.ndarray | None) -> np.ndarray:
    """Flags set for every flake of a stack in which one flake is flagged."""
    if groups is None or flags.size == 0:
        return flags
    return _per_stack_max(flags.astype(float), groups) > 0.0


def pinched(fps, h_top, h_low, limit: float, groups=None) -> np.ndarray:
    """Flakes that do not fit between the tool and the sheet: the depths by which the tool and the
    sheet cut into the flake (maxima over its footprint, grid) add up to more than 2 ``limit`` [m].
    A flake touching only one surface with a gap to the other larger than the cut fits (the DEM moves
    it into the gap); one touching both, or cut by one deeper than its clearance to the other, does
    not. With ``groups`` (:func:`stack_groups`) the test is that of each stack as one rigid body: the
    largest cut of the tool into any of its flakes plus the largest cut of the sheet."""
    fps = Footprints.of(fps)
    if not len(fps):
        return np.zeros(0, dtype=bool)
    h_top = np.ascontiguousarray(h_top, dtype=np.float64)
    flat = fps.flat_indices(h_top.shape[0])
    top = _k._largest_cut(flat, fps.inside, fps.z_hi, h_top.reshape(-1), 1)
    h_low = np.ascontiguousarray(h_low, dtype=np.float64)
    low = _k._largest_cut(flat, fps.inside, fps.z_lo, h_low.reshape(-1), -1)
    return _per_stack_max(top, groups) + _per_stack_max(low, groups) > 2.0 * limit


def attach_stacks(fps, blocked, h_top, groups=None) -> Footprints:
    """The footprints as the contact solve sees them: every blocked flake attached to the tool
    (:func:`attach_to_tool`, all at once with the same minima and maxima), dropped by the largest drop in its
    stack so that the stack moves as one body; the others unchanged."""
    fps = Footprints.of(fps)
    idx = np.flatnonzero(blocked)
    if idx.size == 0:
        return fps
    h_top = np.ascontiguousarray(h_top, dtype=np.float64)
    z_lo, z_hi = _k._grown_faces(fps.z_lo, fps.z_hi, idx)  # 3 x 3 minimum and maximum (attach_to_tool)
    drops = np.zeros(len(fps))
    # the depth by which each grown upper face cuts into the tool, at least 0
    cut = _k._largest_cut(fps.flat_indices(h_top.shape[0])[idx], np.isfinite(z_hi), z_hi, h_top.reshape(-1), 1)
    drops[idx] = np.maximum(0.0, cut)
    drop = _per_stack_max(np.where(blocked, drops, -np.inf), groups)[idx]
    out_lo, out_hi = fps.z_lo.copy(), fps.z_hi.copy()
    _k._dropped(z_lo, z_hi, drop, idx, out_lo, out_hi)
    return fps.with_faces(out_lo, out_hi)


def modified_tool(h_top, fps, blocked) -> np.ndarray:
    """Eq. 18: min of the tool and the lower surface of every blocked flake."""
    h_star = np.array(h_top, dtype=np.float64, copy=True)
    sel = Footprints.of(fps).take(np.flatnonzero(np.asarray(blocked, dtype=bool)))
    np.minimum.at(h_star.reshape(-1), sel.flat_indices(h_star.shape[0])[sel.inside], sel.z_lo[sel.inside])
    return h_star


def blocked_mask(fps, blocked, n: int) -> np.ndarray:
    """Boolean (n, n) mask of the pixels under a blocked flake."""
    mask = np.zeros((n, n), dtype=bool)
    sel = Footprints.of(fps).take(np.flatnonzero(np.asarray(blocked, dtype=bool)))
    mask.reshape(-1)[sel.flat_indices(n)[sel.inside]] = True
    return mask


def particle_area_fraction(traction, mask) -> float:
    """A_p/A0: fraction of pixels with traction > 0 under a blocked flake (Sec. 6.2)."""
    return float(np.count_nonzero((np.asarray(traction) > 0.0) & mask)) / mask.size


@dataclass
class SlideResult:
    """Time series of a slide (one entry per one-pixel step) and optional snapshots."""

    config: SlideConfig
    slide_distance: np.ndarray
    contact_fraction: np.ndarray
    particle_fraction: np.ndarray
    particle_fraction_clusters: np.ndarray
    n_blocked: np.ndarray
    n_blocked_clusters: np.ndarray
    bem_iterations: np.ndarray
    tool_height: np.ndarray
    particle_fraction_cluster_thresholds: np.ndarray | None = None  # (steps, len(config.cluster_thresholds))
    snapshots: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)
    info: dict = field(default_factory=dict)

    def summary(self) -> dict:
        """<A_p>/A0 (Eq. 22; all blocked flakes, and by the cluster rule alone), <A_c>/A0,
        fraction of steps with a blocked flake, timings."""
        extra = {}
        if self.particle_fraction_cluster_thresholds is not None and self.particle_fraction_cluster_thresholds.size:
            extra["mean_particle_fraction_cluster_thresholds"] = [
                float(x) for x in np.mean(self.particle_fraction_cluster_thresholds, axis=0)]
            extra["cluster_thresholds"] = [float(x) for x in self.config.cluster_thresholds]
        return {
            **extra,
            "mean_particle_fraction": float(np.mean(self.particle_fraction)),
            "mean_particle_fraction_clusters": float(np.mean(self.particle_fraction_clusters)),
            "mean_contact_fraction": float(np.mean(self.contact_fraction)),
            "fraction_steps_blocked": float(np.mean(self.n_blocked > 0)),
            "beta": self.config.beta,
            "steps": int(len(self.slide_distance)),
            **{f"time_{k}_s": v for k, v in self.timings.items()},
            **self.info,
        }


class SlideSimulation:
    """One BEM-DEM slide (Fig. 7) for a :class:`SlideConfig`.

    Parameters
    ----------
    config : SlideConfig
    solver : object, optional
        A contact solver with ``solve(gap, pressure, u_plastic=, warm_start=)`` returning an
        object with ``traction``, ``u_elastic``, ``u_plastic``, ``converged``, ``iterations``
        (default: :class:`tribocosim.surrogate.bem.ContactSolver` built from the configuration).
    surfaces : (ndarray, ndarray), optional
        (h_def0, h_tool0) instead of generated self-affine surfaces.
    """

    def __init__(self, config: SlideConfig, solver=None, surfaces=None):
        self.cfg = c = config
        if surfaces is None:
            surfaces = _generate_surfaces(c)
        self.h_def0 = np.ascontiguousarray(surfaces[0], dtype=np.float64)
        self.h_tool0 = np.ascontiguousarray(surfaces[1], dtype=np.float64)
        if solver is None:
            from .bem import ContactSolver

            solver = ContactSolver(c.n, c.size, c.e_star, p_crit=c.p_crit, tol=c.bem_tol,
                                   max_iter=c.bem_max_iter, threads=c.threads)
        self.solver = solver
        self.shape = dem.FlakeShape(c.flake_diameter, c.flake_thickness, c.flake_density)
        damping = c.run_damping(self.shape)  # scaled when the DEM runs faster than v0 (SlideConfig)
        params = dem.DemParams.build(self.shape, c.size, c.dx, c.e_star, c.penalty_velocity,
                                     damping,
                                     spacing=c.sample_spacing_px * c.dx, dt_safety=c.dt_safety,
                                     pair_spacing=None if c.pair_spacing_px is None else c.pair_spacing_px * c.dx)
        if c.overdamped:  # the flakes relax as the tool slides (flake_relax): no time step
            self.n_sub = RELAX_SUBSTEPS if c.relax_substeps is None else c.relax_substeps
            self.params = params
            self.drag = Drag(c.damping(self.shape) if c.damping_rate is None else
                             DampingRates.uniform(c.damping_rate), self.shape.mass, self.shape.inertia)
            self.relax_stats = RelaxStats()
        else:
            v_run = c.run_velocity
            self.n_sub = max(1, math.ceil(c.dx / (v_run * params.dt)))
            self.params = replace(params, dt=c.dx / (v_run * self.n_sub))
        self.k = 0  # pixels slid so far
        self.u_p = np.zeros_like(self.h_def0)
        self.z_top = 0.0
        self.z_prev = 0.0  # tool height at the start of the next DEM phase
        self._last = None
        self.resolves = 0  # contact solves repeated because a flake the solve did not see was pinched
        self.timings = {"dem": 0.0, "bem": 0.0, "classify": 0.0}
        t0 = time.perf_counter()
        # the flakes are laid into the gap of the particle-free contact at the placement pressure; the
        # first contact solve presses to c.pressure, and the DEM phase after it moves both surfaces there
        self.traction = self._contact(self.h_tool0 + self.z_top, c.start_pressure)
        self.z_prev, self.h_low_prev = self.z_top, self.h_low
        self.timings["bem"] += time.perf_counter() - t0
        pos = random_placement(c.n_flakes, self.shape, c.size, self.h_low, self.tool_grid(),
                               c.flake_seed, stacked=c.placement == "deposition")
        self.state = dem.DemState.at_rest(pos)
        self.blocked_prev = np.zeros(len(pos), dtype=bool)

    def tool_envelope(self, h_top) -> np.ndarray:
        """The lowest the tool comes at each pixel during the next DEM phase (shift k -> k+1)."""
        return np.minimum(h_top, np.roll(self.h_tool0, self.k + 1, axis=0) + self.z_top)

    def tool_grid(self) -> np.ndarray:
        """The tool on the grid at the current integer shift, lab frame [m]."""
        return np.roll(self.h_tool0, self.k, axis=0) + self.z_top

    def _contact(self, h_star, pressure: float | None = None) -> np.ndarray:
        """Step 4: solve on g* = h* - h_def0 at ``pressure`` (default the slide's), update u_p, h_low
        and z_top."""
        pressure = self.cfg.pressure if pressure is None else pressure
        try:
            res = self.solver.solve(h_star - self.h_def0, pressure, u_plastic=self.u_p,
                                    warm_start=self._last)
        except ConvergenceError as exc:
            raise ConvergenceError(f"contact solve at sliding step {self.k}: {exc}") from exc
        if not res.converged:
            raise ConvergenceError(
                f"contact solver did not converge at sliding step {self.k}: residual "
                f"{res.residual:.3e} after {res.iterations} iterations (tol {self.cfg.bem_tol:g})")
        self._last = res
        self.u_p = np.asarray(res.u_plastic, dtype=np.float64)
        u_e = np.asarray(res.u_elastic, dtype=np.float64)
        self.h_low = np.ascontiguousarray(self.h_def0 - self.u_p - (u_e - u_e.mean()))
        touching = np.asarray(res.traction) > 0.0
        dz = float(np.median((self.h_low - h_star)[touching])) if touching.any() else 0.0
        self.z_top += dz
        self.h_star = h_star + dz  # the modified tool where the solve left it
        self.last_result = res
        return np.asarray(res.traction)

    def step(self) -> dict:
        """One iteration of Fig. 7 (one pixel of sliding); returns the step's record."""
        self.dem_phase()
        return self.contact_phase()

    def dem_phase(self) -> None:
        """Step 1: DEM with rigid surfaces while the tool advances one pixel."""
        c = self.cfg
        t0 = time.perf_counter()
        motion = dict(shift0=self.k * c.dx, dshift=c.dx / self.n_sub, top_offset=self.z_prev,
                      dtop=(self.z_top - self.z_prev) / self.n_sub, dh_low=self.h_low - self.h_low_prev)
        try:
            if c.overdamped:
                relax(self.state, self.params, self.drag, self.h_low_prev, self.h_tool0, self.n_sub,
                      stats=self.relax_stats, where=f"at sliding step {self.k + 1}", **motion)
            else:
                dem.advance(self.state, self.params, self.h_low_prev, self.h_tool0, self.n_sub,
                            step_offset=self.k * self.n_sub, **motion)
        except dem.DemBlowUpError as exc:
            raise dem.DemBlowUpError(f"sliding step {self.k + 1} of {c.steps}: {exc}") from None
        self.z_prev = self.z_top
        self.h_low_prev = self.h_low
        self.k += 1
        self.timings["dem"] += time.perf_counter() - t0

    def contact_phase(self) -> dict:
        """Steps 2-5: classify, modified tool (Eq. 18), contact solve, A_c and A_p."""
        c = self.cfg
        t1 = time.perf_counter()
        h_top = self.tool_grid()
        h_env = self.tool_envelope(h_top)
        fps = footprints(self.state.pos, self.state.quat, self.shape, c.n, c.size)
        groups = stack_groups(fps, c.n)
        by_clusters, counts = classify(fps, h_top)
        blocked = by_clusters.copy()
        # load-bearing: pinched between the sheet and the tool of the coming pixel (module docstring)
        limit = c.pinch_overlap_fraction * c.flake_thickness
        blocked |= pinched(fps, h_env, self.h_low, limit, groups)
        held = self.blocked_prev & spread_to_stacks(counts >= 1, groups)
        blocked = spread_to_stacks(blocked | held, groups)  # held until the tool lets go of its stack
        attached = attach_stacks(fps, blocked, h_env, groups)  # attached to the tool's underside
        t2 = time.perf_counter()
        before = (self.u_p, self.h_low, self.z_top)
        while True:  # until the solve's tool and sheet pinch no flake it did not see (docstring, 4)
            self.traction = self._contact(modified_tool(h_top, attached, blocked))
            missed = ~blocked & pinched(fps, self.tool_envelope(self.tool_grid()), self.h_low, limit,
                                        groups)
            if not missed.any():
                break
            blocked = spread_to_stacks(blocked | missed, groups)
            attached = attach_stacks(fps, blocked, h_env, groups)
            self.u_p, self.h_low, self.z_top = before
            self.resolves += 1
        self.blocked_prev = blocked
        t3 = time.perf_counter()
        mask = blocked_mask(fps, blocked, c.n)
        self.timings["classify"] += t2 - t1 + time.perf_counter() - t3
        self.timings["bem"] += t3 - t2
        # A_p of the cluster rule alone with other overlap thresholds (a count on the same slide)
        by_thresholds = [particle_area_fraction(self.traction, blocked_mask(fps, classify(fps, h_top, th)[0], c.n))
                         for th in c.cluster_thresholds or ()]
        return {
            "slide_distance": self.k * c.dx,
            "contact_fraction": float(np.mean(self.traction > 0.0)),
            "particle_fraction": particle_area_fraction(self.traction, mask),
            "particle_fraction_clusters": particle_area_fraction(
                self.traction, blocked_mask(fps, by_clusters, c.n)),
            "particle_fraction_cluster_thresholds": by_thresholds,
            "n_blocked": int(blocked.sum()),
            "n_blocked_clusters": int(by_clusters.sum()),
            "bem_iterations": int(self.last_result.iterations),
            "tool_height": self.z_top,
            "blocked": blocked,
        }

    def snapshot(self) -> dict:
        """Flake state and the deformed sheet (float32) at the current step."""
        return {"step": self.k, "pos": self.state.pos.copy(), "quat": self.state.quat.copy(),
                "sheet": self.h_low.astype(np.float32)}

    def run(self, progress=None) -> SlideResult:
        """Slide ``config.steps`` pixels; ``progress(k, record)`` is called after each step."""
        c = self.cfg
        wall0 = time.perf_counter()
        recs, snaps = [], {0: self.snapshot()}
        init = {"contact_fraction0": float(np.mean(self.traction > 0.0))}
        for _ in range(c.steps):
            rec = self.step()
            recs.append(rec)
            if (c.snapshot_every and self.k % c.snapshot_every == 0) or self.k == c.steps:
                snap = self.snapshot()
                snap["blocked"] = rec["blocked"]
                snaps[self.k] = snap
            if progress is not None:
                progress(self.k, rec)
        self.timings["wall"] = time.perf_counter() - wall0
        keys = ("slide_distance", "contact_fraction", "particle_fraction",
                "particle_fraction_clusters", "n_blocked", "n_blocked_clusters",
                "bem_iterations", "tool_height")
        cols = {k: np.array([r[k] for r in recs]) for k in keys}
        if c.cluster_thresholds:
            cols["particle_fraction_cluster_thresholds"] = np.array(
                [r["particle_fraction_cluster_thresholds"] for r in recs], dtype=float)
        info = {**init, "contact_resolves": self.resolves, "dem_steps_per_pixel": self.n_sub,
                "penalty_k_area": self.params.k_area, "face_samples": len(self.params.samples)}
        if c.overdamped:
            info.update({f"relax_{k}": v for k, v in self.relax_stats.as_dict().items()})
        else:
            info["dem_dt"] = self.params.dt
        return SlideResult(c, **cols, snapshots=snaps, timings=dict(self.timings), info=info)


def _generate_surfaces(c: SlideConfig):
    from .measured_surfaces import slide_surface
    from .surfaces import self_affine_surface, surface_wavenumbers

    def side(name: str) -> np.ndarray:
        if getattr(c, f"{name}_file") is not None:
            return slide_surface(c, name)[0]
        q_roll, q_cut = surface_wavenumbers(c.size, c.wavelength_ratio, getattr(c, f"{name}_rolloff_wavelength"))
        return self_affine_surface(c.n, c.size, c.hurst, q_roll, q_cut, rms_height=getattr(c, f"{name}_rms_height"),
                                   seed=getattr(c, f"{name}_seed"))

    return side("sheet"), side("tool")


def run_slide(config: SlideConfig, solver=None, surfaces=None, progress=None) -> SlideResult:
    """Build a :class:`SlideSimulation` and run it to the end."""
    return SlideSimulation(config, solver=solver, surfaces=surfaces).run(progress)
