"""The strip-draw model: 1D bar under a pad + interface law + debris transport + friction law, a binding over the
native core (``components/native/core/tc_stripdraw.c``, which states the equations; the same code as the FMU's).

Physics (paper Sec. 3-4, App. B-C; docs/model.md sections 1-4): the bar rho U_tt = E U_XX (Eq. 2) with lumped
masses, an elastic-perfectly-plastic Coulomb interface T_max = mu P (Eq. 4-5) under a uniform pressure, debris
beta with an Archard source, tool-carried transport and a cap (Eq. 12-14, 24, 37), and the friction law
mu(P, v, beta) (:mod:`.friction`). Integrators (``integrator``): ``explicit`` (the paper's central difference,
sub-cycled at ``cfl_safety`` times the stability limit) or ``implicit`` (generalized-alpha with a Newton
iteration on the stick/slip set, default).

A requested step is cut at the grid points k ``internal_step`` inside it (when > 0), each piece into coupling
intervals in which the pad slides at most ``window_courant`` elements; per interval mu is held, the bar advanced,
then the debris updated. Given the inputs' first and second time derivatives (``step(..., derivatives=...)``,
the FMU's ``fmi2SetRealInputDerivatives``), each interval takes the mean of the input polynomial over itself.

Outputs (one pad, one face; ``pull_force`` for the whole strip), functions of the state at the end of the step:

- ``pull_force`` = 2 x the axial force at the grip (Eq. 1: mu = pull_force / (2 normal_force));
- ``friction_force`` F_S = sum of the nodal friction forces (the return-mapped tractions at the current debris);
- ``mu_mean`` = F_S / F_N (Eq. 28), 0 when F_N = 0;
- ``sliding_distance``: contact-weighted mean displacement of the strip under the pad;
- ``beta_mean`` (contact-weighted, under the pad), ``beta_max`` (whole strip);
- ``contact_pressure`` P, ``grip_position`` (grip displacement), ``table_clamp_count``
  (cumulative number of nodal table lookups outside the table, under the clamp policy).

Inputs are checked as the FMU checks them: ``step`` refuses a missing input, an unknown name and a value that is
not a number (ParameterError, the state unchanged), and warns (:class:`tribocosim.errors.RangeWarning`) when a step
takes an input outside the range the component declares for it (:mod:`.ports`: a grip moving backwards), or when an
output leaves its range after a step (the grip beyond ``draw_length``: the strip's tail runs into the pad; a nominal
pressure above the hardness), once each time it leaves it; and once in the model's life when the least mu of the
state under the pad falls below the documented floor (:mod:`.friction_floor`), naming the setting that lets it.
"""

from __future__ import annotations

import ctypes
import numbers
import warnings
from dataclasses import dataclass

import numpy as np

from tribocosim.errors import ConvergenceError, ParameterError, RangeWarning, TableDomainError
from tribocosim.components.native.toolchain.compiler import NATIVE_DIR
from tribocosim.components.native.toolchain.library import DBL_P, TC_NOMEM, TC_OK, VP, Msg, core, ptr
from tribocosim.components.native.toolchain.prototypes import enums
from tribocosim.components.stripdraw.parameters import StripDrawParameters
from tribocosim.components.stripdraw.ports import INPUTS, OUTPUTS

# the core's indices, read from its header (tc_stripdraw.h): the outputs in enum tc_stripdraw_output's order, the
# nodal arrays and scalars of enum tc_stripdraw_nodal and tc_stripdraw_info, and what enum tc_stripdraw_refusal's
# kinds raise
_ENUMS = enums((NATIVE_DIR / "core" / "tc_stripdraw.h").read_text(encoding="utf-8"))
OUTPUT_NAMES = tuple(name[len("TC_STRIPDRAW_"):].lower() for name, _ in
                     sorted(_ENUMS["tc_stripdraw_output"].items(), key=lambda kv: kv[1]) if name != "TC_STRIPDRAW_N_OUTPUTS")
INPUT_NAMES = ("normal_force", "grip_velocity")
_UNITS = {p.name: p.unit for p in (*INPUTS, *OUTPUTS)}
_NODAL = {name: _ENUMS["tc_stripdraw_nodal"][f"TC_SD_NODAL_{name.upper()}"]
          for name in ("X", "U", "V", "A", "Up", "beta", "slip_rate", "contact_weight", "mass", "friction_limit",
                       "contact")}
_INFO = {name: _ENUMS["tc_stripdraw_info"][f"TC_SD_INFO_{name.upper()}"]
         for name in ("time", "n_steps", "clamp_count", "beta_removed", "beta_produced", "beta_cap",
                      "explicit_time_step", "element_length", "window_lo", "window_hi", "element_stiffness",
                      "shear_stiffness", "normal_force", "grip_velocity", "reaction", "mu_least")}
_REFUSALS = {_ENUMS["tc_stripdraw_refusal"][f"TC_REFUSED_{kind}"]: error
             for kind, error in (("INPUT", ParameterError), ("TABLE", TableDomainError), ("SOLVER", ConvergenceError))}


@dataclass(frozen=True)
class BarMesh:
    """Nodes, element size, lumped masses and stiffnesses of the half-model bar (paper App. B, Eq. 29-30)."""

    X: np.ndarray  # node positions [m], X[-1] is the grip
    element_length: float  # l_e [m]
    window_lo: float  # pad entry edge a [m]
    window_hi: float  # pad exit edge a + L_T [m]
    mass: np.ndarray  # lumped nodal masses [kg]
    element_stiffness: float  # k_e = E A / l_e [N/m]
    node_shear_stiffness: float  # k_s w_T l_e: penalty of one fully covered node [N/m]
    explicit_time_step: float  # cfl_safety x the explicit scheme's stability limit [s]

    @property
    def n_nodes(self) -> int:
        """Number of nodes."""
        return self.X.size


class StripDrawModel:
    """The strip-draw model with explicit state.

    Parameters
    ----------
    params : StripDrawParameters
        All parameters (validated).
    friction_law : FrictionLaw
        A law from :func:`tribocosim.components.stripdraw.friction.make_friction_law` (its table, if any, is
        kept alive by the model).
    beta_field : array_like, optional
        Initial nodal debris field (multi-pass runs); default ``params.beta_initial`` everywhere.
    """

    def __init__(self, params: StripDrawParameters, friction_law, beta_field=None):
        self.params = params
        self.law = friction_law
        c = self._core = core()
        self._struct = c.struct(params)
        self._handle = VP()
        bf = None if beta_field is None else np.ascontiguousarray(beta_field, dtype=float).ravel()
        c.call(c.lib.tc_stripdraw_create, ctypes.byref(self._struct), friction_law.native_table,
               None if bf is None else ptr(bf), 0 if bf is None else bf.size, ctypes.byref(self._handle))
        self.n_nodes = int(c.lib.tc_stripdraw_n_nodes(self._handle))
        info = self._info
        self.mesh = BarMesh(
            X=self._nodal("X"), element_length=info("element_length"), window_lo=info("window_lo"),
            window_hi=info("window_hi"), mass=self._nodal("mass"), element_stiffness=info("element_stiffness"),
            node_shear_stiffness=info("shear_stiffness") * params.tool_width * info("element_length"),
            explicit_time_step=info("explicit_time_step"),
        )
        self.beta_cap = info("beta_cap")
        # buffers reused by every step (a step's cost is mostly the calls' own)
        self._msg_buf = ctypes.create_string_buffer(2048)
        self._msg = Msg(ctypes.addressof(self._msg_buf), len(self._msg_buf))
        self._held = (ctypes.c_double * 2)()
        self._out = (ctypes.c_double * len(OUTPUT_NAMES))()
        self._out_p = ctypes.cast(self._out, DBL_P)
        self._held_p = ctypes.cast(self._held, DBL_P)
        # the declared ranges (ports.py) with their parameter bounds evaluated, and whether each is left now
        value_of = lambda name: float(getattr(params, name))  # noqa: E731
        self._bounds = [(is_input, port, *port.limits(value_of)) for is_input, ports in ((True, INPUTS), (False, OUTPUTS))
                        for port in ports if port.low is not None or port.high is not None]
        self._inputs = {p.name: float(p.start) for p in INPUTS}
        self._outside = [0] * len(self._bounds)
        self._floor_warned = False  # the floor is warned once per model (as once per FMU instance)

    def __del__(self):
        handle = getattr(self, "_handle", None)
        if handle:
            self._core.lib.tc_stripdraw_free(handle)
            self._handle = None

    # ------------------------------------------------------------------ access
    def _nodal(self, name: str) -> np.ndarray:
        out = np.empty(self.n_nodes)
        self._core.lib.tc_stripdraw_nodal(self._handle, _NODAL[name], ptr(out))
        return out

    def _info(self, name: str) -> float:
        return float(self._core.lib.tc_stripdraw_info(self._handle, _INFO[name]))

    time = property(lambda self: self._info("time"), doc="the model's time [s] (the sum of the steps)")
    n_steps = property(lambda self: int(self._info("n_steps")), doc="steps taken")
    clamp_count = property(lambda self: int(self._info("clamp_count")), doc="nodal table lookups outside the table")
    beta_removed = property(lambda self: self._info("beta_removed"), doc="sum over nodes of what the cap removed")
    beta_produced = property(lambda self: self._info("beta_produced"),
                             doc="sum over nodes of the debris produced (Archard source, Eq. 37)")
    normal_force = property(lambda self: self._info("normal_force"), doc="normal force of the last interval [N]")
    U = property(lambda self: self._nodal("U"), doc="nodal displacements [m] (a copy)")
    V = property(lambda self: self._nodal("V"), doc="nodal velocities [m/s] (a copy)")
    A = property(lambda self: self._nodal("A"), doc="nodal accelerations [m/s^2] (a copy)")
    Up = property(lambda self: self._nodal("Up"), doc="nodal plastic slips [m] (a copy)")
    beta = property(lambda self: self._nodal("beta"), doc="nodal debris area fractions (a copy)")
    slip_rate = property(lambda self: self._nodal("slip_rate"), doc="nodal slip rates of the last interval [m/s]")
    friction_limit = property(lambda self: self._nodal("friction_limit"), doc="mu P of the state [Pa]")
    mu_least = property(lambda self: self._info("mu_least"),
                        doc="the least mu of the state's friction limits under the pad (NaN: no node, no pressure)")

    @property
    def explicit_time_step(self) -> float:
        """The explicit scheme's step [s] (cfl_safety x the stability limit)."""
        return self.mesh.explicit_time_step

    # ------------------------------------------------------------------ state
    def get_state(self) -> np.ndarray:
        """The full state as bytes (a uint8 array); :meth:`set_state` restores the run bit-identically."""
        lib = self._core.lib
        buf = np.empty(lib.tc_stripdraw_state_size(self._handle), dtype=np.uint8)
        lib.tc_stripdraw_get_state(self._handle, buf.ctypes.data_as(VP))
        return buf

    def set_state(self, state) -> None:
        """Restore a state from :meth:`get_state`; ParameterError for bytes of another model."""
        buf = np.ascontiguousarray(state, dtype=np.uint8)
        self._core.call(self._core.lib.tc_stripdraw_set_state, self._handle, buf.ctypes.data_as(VP), buf.size)
        self._note_outside()

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
            Input name -> its first and second time derivatives at the start of the step, ``(d1, d2)``. The
            input is then u + d1 s + d2 s^2 / 2 of the time s into the step. Missing: held.

        Raises
        ------
        ParameterError
            For a missing input, an unknown input name, a value that is not a number, a non-finite or negative
            input or step, or a non-finite derivative; the state is unchanged.
        TableDomainError
            For a table lookup outside the table under ``table_policy = "error"``; the state is unchanged.
        ConvergenceError
            If the implicit solve fails even after step halving; the state is unchanged.

        Warns
        -----
        RangeWarning
            When the step takes an input outside its declared range, or an output leaves its range after it, or
            (once) when mu under the pad falls below the documented floor (module docstring).
        """
        c = self._core
        if isinstance(dt, bool) or not isinstance(dt, numbers.Real):
            raise ParameterError(f"dt = {dt!r} is not a number; allowed: a real number of seconds > 0")
        fn, v = _checked_inputs(inputs)
        if derivatives:
            _check_names(derivatives, "derivatives")
            try:
                dn = ptr(np.array(derivatives.get("normal_force", (0.0, 0.0)), dtype=float))
                dv = ptr(np.array(derivatives.get("grip_velocity", (0.0, 0.0)), dtype=float))
            except (TypeError, ValueError):
                raise ParameterError(f"derivatives = {derivatives!r}; allowed: input name -> (first, second) time "
                                     "derivatives, two numbers") from None
        else:
            dn = dv = self._held_p
        status = c.lib.tc_stripdraw_step_poly(self._handle, float(dt), fn, dn, v, dv, self._msg)
        if status != TC_OK:
            text = self._msg_buf.value.decode(errors="replace")
            if status == TC_NOMEM:
                raise MemoryError(text)
            raise _REFUSALS.get(c.lib.tc_stripdraw_refusal(self._handle), ParameterError)(text)
        self._inputs = {"normal_force": fn, "grip_velocity": v}
        out = self.outputs()
        self._warn_outside(out)
        self._warn_floor()
        return out

    def _warn_floor(self) -> None:
        """A RangeWarning, the first time in this model's life, when the least mu of the state lies below the
        documented floor, naming the setting that lets it (tc_stripdraw_floor_note; the native FMU's message)."""
        if self._floor_warned or not self._core.lib.tc_stripdraw_floor_note(self._handle, self._msg):
            return
        self._floor_warned = True
        warnings.warn(f"StripDrawModel: at t = {_repr(self.time)} s {self._msg_buf.value.decode(errors='replace')}",
                      RangeWarning, stacklevel=3)

    def _warn_outside(self, outputs: dict) -> None:
        """A RangeWarning for each declared range an input of the step is outside, or an output has just left
        (the native FMU's messages, tc_fmu_instance.c)."""
        for k, (is_input, port, low, high) in enumerate(self._bounds):
            value = self._inputs[port.name] if is_input else outputs[port.name]
            side = port.outside(value, low, high)
            if side and not self._outside[k]:
                bound, label = (low, port.low) if side < 0 else (high, port.high)
                unit = f" {port.unit}" if port.unit != "1" else ""
                named = f"{label} = " if isinstance(label, str) else ""
                where = f"in the step to t = {_repr(self.time)} s" if is_input else f"at t = {_repr(self.time)} s"
                warnings.warn(f"StripDrawModel: {where} {port.name} = {_repr(value)}{unit} is "
                              f"{'below' if side < 0 else 'above'} {named}{_repr(bound)}{unit}, the "
                              f"{'least' if side < 0 else 'largest'} {port.name} the model is built for "
                              f"({port.why or port.description}); the results from here on are outside what it "
                              "describes", RangeWarning, stacklevel=3)
            self._outside[k] = side

    def _note_outside(self) -> None:
        """Which ranges the state (and the last inputs) are outside now: a restored state warns only of what it
        leaves after it."""
        out = self.outputs()
        self._outside = [port.outside(self._inputs[port.name] if is_input else out[port.name], low, high)
                         for is_input, port, low, high in self._bounds]

    # ------------------------------------------------------------------ outputs
    def outputs(self) -> dict:
        """The outputs of the current state (see the module docstring)."""
        self._core.lib.tc_stripdraw_outputs(self._handle, self._out_p)
        return dict(zip(OUTPUT_NAMES, self._out))

    def fields(self) -> dict:
        """Nodal fields for plots: X, U, beta, slip (plastic slip U_p), contact weight."""
        return {"X": self._nodal("X"), "U": self._nodal("U"), "beta": self._nodal("beta"), "slip": self._nodal("Up"),
                "contact": self._nodal("contact_weight")}



def _check_names(values, what: str) -> None:
    """Refuse a mapping ``what`` that is not one, or holds a name that is not an input."""
    if not hasattr(values, "keys"):
        raise ParameterError(f"{what} = {values!r} is not a dict; allowed: a dict of the inputs "
                             f"{', '.join(f'{n} [{_UNITS[n]}]' for n in INPUT_NAMES)}")
    unknown = [k for k in values if k not in INPUT_NAMES]
    if unknown:
        raise ParameterError(f"{what} has {', '.join(map(repr, unknown))}, not an input of the strip-draw model; "
                             f"allowed: {', '.join(f'{n} [{_UNITS[n]}]' for n in INPUT_NAMES)}")


def _checked_inputs(inputs) -> tuple[float, float]:
    """(normal_force, grip_velocity) of a step's inputs, refused (ParameterError) when one is missing, a name is not
    an input, or a value is not a real number."""
    _check_names(inputs, "inputs")
    values = []
    for name in INPUT_NAMES:
        if name not in inputs:
            raise ParameterError(f"inputs has no {name!r} [{_UNITS[name]}]; allowed: a dict with every input, "
                                 f"{', '.join(f'{n} [{_UNITS[n]}]' for n in INPUT_NAMES)}")
        x = inputs[name]
        if isinstance(x, bool) or not isinstance(x, numbers.Real):
            raise ParameterError(f"inputs[{name!r}] = {x!r} is not a number; allowed: a real number [{_UNITS[name]}]")
        values.append(float(x))
    return values[0], values[1]


def _repr(x: float) -> str:
    """The shortest ``%g`` form that reads back as ``x``: the native FMU's tc_repr_double, so that a warning reads as
    the FMU's."""
    for digits in range(1, 18):
        text = f"{x:.{digits}g}"
        if float(text) == x:
            return text
    return text
