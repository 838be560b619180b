"""The strip-draw model: 1D bar under a pad + interface law + debris transport + friction law.

Physics (paper Sec. 3-4, App. B-C; docs/model.md sections 1-4):

- bar: rho U_tt = E U_XX (Eq. 2), linear elements, lumped mass (:mod:`.mesh`);
- interface: elastic-perfectly-plastic Coulomb law with return mapping, T_max = mu P (Eq. 4-5),
  uniform pressure P = F_N / (L_T w_T) over the pad (the paper's choice);
- debris: beta transport with Archard source and tool-carried flux (Eq. 12-14, 37; :mod:`.transport`);
- friction: mu(P, v, beta) from a table, the closed form, or a constant (:mod:`.friction`).

Time integration. Two integrators for the bar, selected by ``integrator``:

``explicit``
    The paper's central-difference scheme (App. B) with the time step at ``cfl_safety`` times the
    stability limit (:meth:`BarMesh.critical_time_step`), sub-cycled inside every requested step.
    Resolves the elastic waves; ~1e7 steps for a 140 mm draw at 0.08 m/s.
``implicit``
    Generalized-alpha (Chung-Hulbert), unconditionally stable and second order, with a
    semi-smooth Newton iteration on the stick/slip set of the nodes under the pad, the bar outside the
    pad condensed onto it (:mod:`.galpha`). Chosen over a purely
    quasi-static solve because it keeps inertia (the grip is driven by a machine model whose
    dynamics the co-simulation resolves, and velocity steps are legal inputs) while its
    numerical damping (``rho_inf`` < 1) removes the unresolved elastic waves, so that at
    V0 << sqrt(E/rho) it converges to the quasi-static answer with steps of milliseconds.

Velocity in mu(P, v, beta) (``friction_velocity``). ``grip`` (default): the pulling speed |V0|,
the same for every node, as the paper does ("alpha was extrapolated from Figure 15 using the pulling
velocity v0 = 0.08 m/s", Fig. 19). ``slip_rate``: each node's own slip rate of the last coupling
interval (docs/model.md section 7 lists this as the open choice). With ``slip_rate`` a sticking node has
alpha = 0 and mu = mu0 whatever its debris, so at high debris coverage the law is strongly
velocity-weakening and the strip goes into stick-slip (measured: 70 mm pad at 30 MPa, mu swinging
between ~0 and 0.146); the paper's steady friction curves need ``grip``.

Coupling of bar, friction and debris (our choice; docs/model.md section 7): a requested step is split
into coupling intervals in which the pad slides at most ``window_courant`` elements. In each
interval mu is evaluated per node from (P, slip rate of the last interval, beta) and held, the bar
is advanced (sub-cycled explicit steps or one generalized-alpha step), then beta is updated from
the nodal slip increments (implicit upwind, exact mass balance) and capped where A_p reaches A_c
(Eq. 24) at the interval's pressure and grip speed (``law.beta_cap``; ``beta_threshold`` > 0
overrides it). Both integrators share this, so
their comparison measures the bar integrator alone.

Internal time grid (``internal_step`` tau > 0). Within a coupling interval mu and the contact overlaps are
held, so the outputs lag by a fraction of the interval: they are first order in the model's own step, and
co-simulation step doubling (one step H against two steps H/2), whose criterion is the error per unit
step, would measure that constant lag instead of the coupling error and shrink the step without end.
With tau > 0 the model integrates on the fixed absolute grid t_k = k tau (k an integer, t the model's
time, the sum of the requested steps): a step [t, t + dt] is first cut at the grid points strictly inside it
(:func:`grid_pieces`), and each piece is split into coupling intervals as above. An end of the step within
``GRID_TOLERANCE`` tau of a grid point counts as that grid point (no sliver piece), and a piece between two
grid points is exactly tau long. So one step H and two steps H/2 from a grid point take the same
intervals, bit for bit, whenever t + H/2 is a grid point too, and step doubling sees only the coupling
(the inputs) change. tau = 0 (default) leaves one piece, the requested step.

Inputs within a step. By default the inputs are held over the step. Given their first and second time
derivatives at the step's start (``step(..., derivatives=...)``; the FMU's ``fmi2SetRealInputDerivatives``,
canInterpolateInputs = true), each input is the polynomial u(s) = u + u' s + u'' s^2 / 2 of the time s into
the step, and each coupling interval [a, b] takes its mean (1/(b - a)) int_a^b u ds: the exact impulse of the
normal force and the exact grip displacement of a polynomial input. With tau > 0 the friction, the contact
overlaps and the debris then follow the inputs every tau within a communication step H, so the model's
response to a linearly extrapolated input is second order in H (a held input is first order: the end-of-step
outputs see the input of the start or the mean). A normal force interpolated below zero on an interval is a
pad that lifts off: pressure 0 there (the interface carries no tension); the input itself must be >= 0.

Outputs (one pad, one face; ``pull_force`` for the whole strip):

- ``pull_force`` = 2 x the axial force at the grip (Eq. 1: mu = pull_force / (2 normal_force));
- ``friction_force`` F_S = sum of nodal friction forces on the modelled face;
- ``mu_mean`` = F_S / F_N (Eq. 28), 0 when F_N = 0;
- ``sliding_distance``: contact-weighted mean displacement of the strip under the pad;
- ``beta_mean`` (contact-weighted, under the pad), ``beta_max`` (whole strip);
- ``contact_pressure`` P, ``grip_position`` (grip displacement), ``table_clamp_count``
  (cumulative number of nodal table lookups outside the table, under the clamp policy).
"""

from __future__ import annotations

import copy
import math

import numpy as np

from tribocosim.components.errors import ConvergenceError, ParameterError, check_finite
from tribocosim.components.stripdraw import galpha, kernels
from tribocosim.components.stripdraw.mesh import BarMesh
from tribocosim.components.stripdraw.parameters import StripDrawParameters
from tribocosim.components.stripdraw.transport import transport_step

OUTPUT_NAMES = (
    "pull_force",
    "friction_force",
    "mu_mean",
    "sliding_distance",
    "beta_mean",
    "beta_max",
    "contact_pressure",
    "grip_position",
    "table_clamp_count",
)
INPUT_NAMES = ("normal_force", "grip_velocity")

_ARRAYS = ("U", "V", "A", "Up", "contact", "beta", "slip_rate", "fprev")
_SCALARS = ("time", "n_steps", "friction_force", "reaction", "normal_force", "clamp_count", "beta_removed")
_MAX_HALVINGS = 12
_NEWTON_MAX_ITER = 60
_NEWTON_RTOL = 1e-10  # residual tolerance relative to the friction capacity + grip pull
_CHAIN_CACHE = 4  # step lengths whose elimination factors are kept (model._chain)
#: a step's end within this fraction of internal_step of a grid point is on the grid point (the model's time is
#: the float sum of the requested steps, whose rounding is many orders below it over any practical run)
GRID_TOLERANCE = 1e-6


def grid_pieces(t: float, dt: float, tau: float) -> list[tuple[float, int]]:
    """The pieces of the step [t, t + dt] cut at the grid points k * tau strictly inside it, as runs
    ``(length, count)`` in time order (``[(dt, 1)]`` when tau <= 0 or no grid point is inside).

    An end within ``GRID_TOLERANCE * tau`` of a grid point counts as that grid point; a piece between two
    grid points is ``tau`` exactly (not a difference of rounded times), so that the same grid interval has
    the same length whichever step it belongs to. The grid indices are integers held in floats (exact below
    2**53), as the native model holds them.
    """
    if not tau > 0:
        return [(dt, 1)]
    end = t + dt
    a = t / tau
    b = end / tau
    ka = float(round(a))
    kb = float(round(b))
    start_on = abs(a - ka) <= GRID_TOLERANCE
    end_on = abs(b - kb) <= GRID_TOLERANCE
    first = ka + 1.0 if start_on else math.floor(a) + 1.0  # first grid point inside
    last = kb - 1.0 if end_on else math.ceil(b) - 1.0  # last grid point inside
    if first > last:
        return [(tau, 1)] if start_on and end_on and kb == ka + 1.0 else [(dt, 1)]
    runs = [(tau if start_on else first * tau - t, 1)]
    if last > first:
        runs.append((tau, int(last - first)))
    runs.append((tau if end_on else end - last * tau, 1))
    return runs


def input_mean(poly: tuple[float, float, float], a: float, b: float) -> float:
    """Mean over [a, b] of the input polynomial u(s) = c0 + c1 s + c2 s^2 (its value at a when a == b).

    A coupling interval takes this mean: it carries the exact impulse of a force and the exact
    displacement of a velocity that vary as the polynomial (Taylor coefficients about the step's
    start, ``c2`` = half the second derivative).
    """
    c0, c1, c2 = poly
    return c0 + c1 * 0.5 * (a + b) + c2 * (a * a + a * b + b * b) / 3.0


class StripDrawModel:
    """The strip-draw model with explicit state.

    Parameters
    ----------
    params : StripDrawParameters
        All parameters (validated).
    friction_law : object
        A law from :func:`tribocosim.components.stripdraw.friction.make_friction_law`.
    beta_field : array_like, optional
        Initial nodal debris field (multi-pass runs); default ``params.beta_initial`` everywhere.
    """

    def __init__(self, params: StripDrawParameters, friction_law, beta_field=None):
        self.params = params
        self.law = friction_law
        self.mesh = BarMesh.build(params)
        cap = params.beta_threshold if params.beta_threshold > 0 else friction_law.beta_threshold
        self.beta_cap = float(cap)
        n = self.mesh.n_nodes
        self.U = np.zeros(n)
        self.V = np.zeros(n)
        self.A = np.zeros(n)
        self.Up = np.zeros(n)
        self.contact = np.zeros(n, dtype=np.int8)
        self.slip_rate = np.zeros(n)
        self.fprev = np.zeros(n)
        if beta_field is None:
            beta0 = np.full(n, params.beta_initial)
        else:
            beta0 = np.array(beta_field, dtype=float)
            if beta0.shape != (n,) or not np.all(np.isfinite(beta0)) or np.any(beta0 < 0):
                raise ParameterError(
                    f"beta_field must hold {n} finite values >= 0 (one per node); got shape {beta0.shape}"
                )
        if np.any(beta0 > self.beta_cap):
            raise ParameterError(
                f"initial beta = {float(beta0.max())!r} exceeds the cap beta_threshold = {self.beta_cap:g}"
            )
        self.beta = beta0
        self._w = self._weights(self.U)  # contact weights at the current U (derived, cached)
        self.time = 0.0
        self.n_steps = 0
        self.friction_force = 0.0
        self.reaction = 0.0
        self.normal_force = 0.0
        self.clamp_count = 0
        self.beta_removed = 0.0
        m = self.mesh
        self._minv = 1.0 / m.mass
        self._dt_explicit = params.cfl_safety * m.critical_time_step()
        r = params.rho_inf
        self._am = (2.0 * r - 1.0) / (r + 1.0)
        self._af = r / (r + 1.0)
        self._gamma = 0.5 - self._am + self._af
        self._beta_nm = 0.25 * (1.0 - self._am + self._af) ** 2
        self._chains: dict[float, np.ndarray] = {}  # galpha.chain_factors per implicit step length

    # ------------------------------------------------------------------ state
    def get_state(self) -> dict:
        """A deep copy of the full state; :meth:`set_state` restores the run bit-identically."""
        st = {k: getattr(self, k).copy() for k in _ARRAYS}
        st.update({k: copy.copy(getattr(self, k)) for k in _SCALARS})
        return st

    def set_state(self, state: dict) -> None:
        """Restore a state from :meth:`get_state` (copied, so the caller may keep using it)."""
        n = self.mesh.n_nodes
        for k in _ARRAYS:
            arr = np.asarray(state[k])
            if arr.shape != (n,):
                raise ParameterError(f"state array {k} has shape {arr.shape}; this model has {n} nodes")
            setattr(self, k, arr.astype(getattr(self, k).dtype, copy=True))
        for k in _SCALARS:
            setattr(self, k, type(getattr(self, k))(state[k]))
        self._w = self._weights(self.U)

    # ------------------------------------------------------------------ stepping
    def step(self, dt: float, inputs: dict, derivatives: dict | None = None) -> dict:
        """Advance by ``dt`` seconds; return the outputs.

        Parameters
        ----------
        dt : float
            Step length [s], > 0.
        inputs : dict
            ``normal_force`` [N] on one pad (>= 0) and ``grip_velocity`` [m/s] at the start of the step.
        derivatives : dict, optional
            Input name -> its first and second time derivatives at the start of the step, ``(d1, d2)``
            [unit/s, unit/s^2] (what ``fmi2SetRealInputDerivatives`` gives). The input is then the
            polynomial u(s) = u + d1 s + d2 s^2 / 2 of the time s into the step, and every coupling
            interval [a, b] takes its mean over the interval (:func:`input_mean`). Missing: held.

        Raises
        ------
        ParameterError
            For a non-finite or negative input or step, or a non-finite derivative; the state is unchanged.
        ConvergenceError
            If the implicit solve fails even after step halving; the state is unchanged.
        """
        dt = check_finite("dt", dt)
        if dt <= 0:
            raise ParameterError(f"dt = {dt!r} s must be > 0")
        fn = check_finite("normal_force", inputs["normal_force"])
        if fn < 0:
            raise ParameterError(f"normal_force = {fn!r} N must be >= 0")
        vg = check_finite("grip_velocity", inputs["grip_velocity"])
        polys = {}
        for name, value in (("normal_force", fn), ("grip_velocity", vg)):
            d1, d2 = (derivatives or {}).get(name, (0.0, 0.0))
            polys[name] = (value, check_finite(f"d({name})/dt", d1), 0.5 * check_finite(f"d2({name})/dt2", d2))
        saved = self.get_state()
        try:
            self._advance(dt, polys["normal_force"], polys["grip_velocity"])
            if not (np.all(np.isfinite(self.U)) and math.isfinite(self.reaction)):
                raise ConvergenceError(f"non-finite bar state at t = {self.time + dt:.9g} s")
        except BaseException:
            self.set_state(saved)
            raise
        self.time = saved["time"] + dt
        self.n_steps += 1
        return self.outputs()

    def _advance(self, dt: float, fn: tuple, vg: tuple) -> None:
        s = 0.0  # time into the step at the start of the piece
        for piece, count in grid_pieces(self.time, dt, self.params.internal_step):
            for _ in range(count):
                self._piece(s, piece, fn, vg)
                s += piece

    def _piece(self, s: float, piece: float, fn: tuple, vg: tuple) -> None:
        """One piece [s, s + piece] of the step, cut into coupling intervals in which the pad slides at most
        window_courant elements (at the largest grip speed of the piece's ends and middle)."""
        p, m = self.params, self.mesh
        speed = max(abs(input_mean(vg, x, x)) for x in (s, s + 0.5 * piece, s + piece))
        h_max = p.window_courant * m.element_length / speed if speed != 0 else math.inf
        n_int = max(1, math.ceil(piece / h_max - 1e-9))
        h = piece / n_int
        for j in range(n_int):
            a, b = s + j * h, s + (j + 1) * h
            # a normal force interpolated below zero is a pad that lifts off: no pressure (no adhesion)
            self.normal_force = max(0.0, input_mean(fn, a, b))
            self._interval(h, p.pressure(self.normal_force), input_mean(vg, a, b))

    def _interval(self, h: float, pressure: float, vg: float) -> None:
        p, m = self.params, self.mesh
        tmax = np.zeros(m.n_nodes)
        if pressure > 0:
            # only nodes that can be under the pad during this interval need mu: the pad slides
            # at most window_courant elements per interval
            inside = np.flatnonzero(self._w > 0)
            reach = math.ceil(p.window_courant) + 1
            lo, hi = 0, m.n_nodes
            if inside.size:
                lo, hi = max(0, inside[0] - reach), min(m.n_nodes, inside[-1] + 1 + reach)
            v = abs(vg) if p.friction_velocity == "grip" else self.slip_rate[lo:hi]
            mu, clamped = self.law.mu(pressure, v, self.beta[lo:hi])
            self.clamp_count += int(np.count_nonzero(clamped & (self._w[lo:hi] > 0)))
            tmax[lo:hi] = mu * pressure
        U0 = self.U.copy()
        w0 = self._w
        if p.integrator == "explicit":
            n_sub = max(1, math.ceil(h / self._dt_explicit - 1e-9))
            fric, reaction = kernels.explicit_kernel(
                n_sub, h / n_sub, self.U, self.V, self.A, self.Up, self.contact, m.X, self._minv,
                m.element_stiffness, p.shear_stiffness, p.tool_width, 0.5 * m.element_length,
                m.window_lo, m.window_hi, tmax, vg,
            )
        else:
            fric, reaction = self._implicit(h, w0 * m.element_length, tmax, vg, 0)
        self.friction_force, self.reaction = float(fric), float(reaction)
        dU = self.U - U0
        self.slip_rate = np.abs(dU) / h
        self._w = self._weights(self.U)
        weight = 0.5 * (w0 + self._w)
        cap = self.beta_cap if p.beta_threshold > 0 else min(self.beta_cap, self.law.beta_cap(pressure, abs(vg)))
        self.beta, removed = transport_step(self.beta, dU, weight, pressure, p, m.element_length, cap)
        self.beta_removed += removed

    def _implicit(self, h: float, ov: np.ndarray, tmax: np.ndarray, vg: float, depth: int):
        m, p = self.mesh, self.params
        it, fric, reaction = galpha.galpha_kernel(
            h, self.U, self.V, self.A, self.Up, self.contact, self.fprev, ov, m.mass,
            m.element_stiffness, p.shear_stiffness, p.tool_width, tmax, vg,
            self._am, self._af, self._beta_nm, self._gamma, _NEWTON_MAX_ITER, _NEWTON_RTOL, self._chain(h),
        )
        if it >= 0:
            return fric, reaction
        if depth >= _MAX_HALVINGS:
            raise ConvergenceError(
                f"implicit bar step did not converge (stick/slip set kept changing) at t = {self.time:.9g} s "
                f"even with the step halved {depth} times to {h:.3g} s"
            )
        self._implicit(0.5 * h, ov, tmax, vg, depth + 1)
        ov_mid = kernels.overlap_numpy(m.X, self.U, 0.5 * m.element_length, m.window_lo, m.window_hi)
        return self._implicit(0.5 * h, ov_mid, tmax, vg, depth + 1)

    def _chain(self, h: float) -> np.ndarray:
        """The elimination factors of the free bar for the step length h (galpha.chain_factors), kept for
        the last few step lengths (a run mostly repeats one; halvings and step doubling add a few)."""
        chain = self._chains.get(h)
        if chain is None:
            if len(self._chains) >= _CHAIN_CACHE:
                self._chains.pop(next(iter(self._chains)))
            cm = (1.0 - self._am) / (self._beta_nm * h * h)
            chain = self._chains[h] = galpha.chain_factors(cm, self.mesh.mass, (1.0 - self._af) * self.mesh.element_stiffness)
        return chain

    def _weights(self, U: np.ndarray) -> np.ndarray:
        m = self.mesh
        return kernels.overlap_numpy(m.X, U, 0.5 * m.element_length, m.window_lo, m.window_hi) / m.element_length

    # ------------------------------------------------------------------ outputs
    def outputs(self) -> dict:
        """The current outputs (see the module docstring)."""
        p = self.params
        w = self._w
        wsum = float(w.sum())
        fn = self.normal_force
        return {
            "pull_force": 2.0 * self.reaction,
            "friction_force": self.friction_force,
            "mu_mean": self.friction_force / fn if fn > 0 else 0.0,
            "sliding_distance": float(w @ self.U) / wsum if wsum > 0 else 0.0,
            "beta_mean": float(w @ self.beta) / wsum if wsum > 0 else 0.0,
            "beta_max": float(self.beta.max()),
            "contact_pressure": p.pressure(fn),
            "grip_position": float(self.U[-1]),
            "table_clamp_count": float(self.clamp_count),
        }

    def fields(self) -> dict:
        """Nodal fields for plots: X, U, beta, slip (plastic slip U_p), contact weight."""
        return {
            "X": self.mesh.X.copy(),
            "U": self.U.copy(),
            "beta": self.beta.copy(),
            "slip": self.Up.copy(),
            "contact": self._w.copy(),
        }

    @property
    def explicit_time_step(self) -> float:
        """The explicit scheme's step [s] (cfl_safety x the stability limit)."""
        return self._dt_explicit
