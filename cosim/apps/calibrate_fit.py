"""The fit behind ``tribocosim calibrate``: strip-draw parameters by weighted least squares on measured mu_bar and
debris (docs/model.md section 4).

Data (:func:`read_measurements`): one row per test, ``pressure`` [Pa], ``tool_length`` [m], ``passes`` (1, 2, 3...: a
later pass starts from the debris the previous one left), and any of the observables of :data:`OBSERVABLES` after
that pass, each with an optional standard deviation (``<name>_std``): ``mu_bar`` (the steady-state friction
coefficient), ``debris_g_m2`` (the debris left on the strip that passed under the pad, weighed per unit area
[g/m^2]), ``beta`` (its coverage, the area fraction of flakes). Every row is simulated with the pure strip-draw model
(:func:`tribocosim.cosim.studies.stripdraw_experiment.draw`, one draw per pressure and pad gives all its passes).

Parameters (:data:`FITTABLE`): the scale s of the table's A_p (``particle_area_scale``), the flake-borne shear ratio
r (``flake_shear_ratio``: mu = mu0 (1 - (1 - r) s A_p / A_c), docs/model.md section 4), and the debris balance: the
production K / H (``archard_k``, the hardness fixed: only K / H enters, Eq. 33-37), the share of the debris the tool
carries (``zeta``), the share kept between passes (``debris_carry_over``) or a sink (``debris_sink_length``), each
within its bounds (the strip-draw parameter's declared range; a sink length above 0). Residuals
r_i = (model_i - measured_i) / sigma_i; Gauss-Newton with a forward-difference Jacobian J (steps of 1e-3 times the
value or the parameter's scale), the step solved in units of the parameters' scales without the directions the data
do not see (below :data:`SINGULAR_RATIO` of the largest singular value), clipped to the bounds and halved while it
does not lower sum r^2 (:data:`HALVINGS` times at most; when none does, the iteration keeps its point). Covariance
C = (J^T J)^-1, scaled by chi^2 / (N - n) when the data give no standard deviations (one observable only: without them
observables of different units cannot be weighed against each other).

**The cap search (s and r fitted together).** Below the cap mu = mu0 (1 - (1 - r) s A_p / A_c) depends on s and r only
through q = (1 - r) s, and so does everything the model computes from mu (the strip's slip, the debris): along the
valley (1 - r) s = q the model's values are the same, bit for bit, until s A_p reaches A_c somewhere (the cap's onset,
where the cap starts removing debris); beyond it mu = r mu0 where flakes carry the whole contact, and the data see r. A
fit that starts below the onset (the shipped table's largest A_p / A_c is 0.878: no debris reaches the cap at s < 1.14,
the default s = 1 included) sees q alone, and Gauss-Newton cannot leave the valley's flat part: its Jacobian has no
component along it. So when the fit from the start does not succeed, :func:`search_the_cap` evaluates the valley through
its q at r = 0, 0.05, ..., 0.95 (:data:`CAP_SEARCH_RATIOS`, s = q / (1 - r), the other fitted parameters as fitted), in
one batch of 20 model evaluations run in parallel: the starts whose values differ from the r = 0 start's are beyond the
onset, found exactly whatever the data's noise, and Gauss-Newton starts from the one of them with the least chi^2; the
outcome is the better of the two fits. Why this and not several starts or a global bounded method: the model's structure
says where the unknown lies (one bounded number, r in [0, 1], once q is fitted), so a grid over r's range costs 20
evaluations, where each extra Gauss-Newton start costs a run (10-20 evaluations for two parameters in the review's case
below) and a global method spends its evaluations over the whole box; and from beyond the onset Gauss-Newton reached the
data's (s, r) from every start tried (in the review's case six, from (1.215, 0.3) to (3.0, 0.7), in 10-20 evaluations
each; the tests' starts beyond the onset). Measured on the review's case (mu_bar after passes 1-5 at 1, 10, 25 and 30
MPa on the 35 mm pad, made by the default strip at s = 1.28, r = 0.3, no noise; tests/cosim/test_calibrate.py, ``pytest
-m slow -s -k reviews``): from the default start the fit sees q = 0.8507 only (RMS residual 6.9 %), 14 of the 20 starts
reach the cap (r >= 0.3), and the fit from r = 0.3 ends at (1.28, 0.3) to 1e-6 after 4 iterations, 45 model evaluations
in all (the fit from the start alone: 2 iterations, 13 evaluations, ending at q). What it does not do: an onset beyond r
= 0.95 (s > 20 q) is not found; it runs along one valley, that of the fit from the start, with the other fitted
parameters at their values there in every start (Gauss-Newton then moves them all); and only when s and r are both
fitted, the pair only the cap separates.

The outcome (:class:`Fit`) says what the data determine, every judgement at the fit the outcome reports:

- converged: an iteration that changes every parameter by at most 1e-6 of its value (of its scale below it), or
  whose change is at most 1 % of a standard error in the metric of the covariance, sqrt(d^T C^-1 d) <= 0.01 (for one
  parameter |d| / its standard error; a change along a direction the data hardly see counts as little as they see
  it, one along the directions they see in full); a fit that reaches the iteration limit without it is not converged;
- at a bound: a parameter on its bound whose unconstrained Gauss-Newton step points beyond it; the data ask for a
  value the model does not allow (measured mu_bar above mu0 needs s < 0), so the fit has failed, whatever its
  changes; its standard error is not given;
- the residual against the data's noise (:mod:`tribocosim.cosim.apps.calibrate_noise`): chi^2 against its
  distribution on N - n degrees of freedom when the data state their standard deviations, the lack of fit against
  the spread of replicated tests when they do not, not judged (and said so) when they carry neither; a residual the
  noise gives with probability below 0.01 says the model does not describe the data: that fit has failed, with the
  residual and the largest residuals named, whatever the Jacobian;
- separable: the singular values of the Jacobian with each column in units of its parameter's scale; the data
  cannot separate the parameters when the smallest is below 1e-6 of the largest (a direction the residuals do not
  see: fewer independent data than parameters, or a parameter the data do not touch), when two parameters'
  correlation C_ij / sqrt(C_ii C_jj) exceeds 0.99 in magnitude (only a combination of them is determined), or when a
  bounded parameter's standard error exceeds the width of its range (the data barely touch it: the debris left on
  the strip hardly depends on zeta, which moves the debris under the pad). s and r fitted together: when their
  correlation exceeds 0.99 at the best fit (after the cap search: no start on the valley that reaches the cap fits
  better) the outcome says in one line that the data determine only (1 - r) s, with its value and standard error
  (:func:`shear_scale_product`), in place of the general messages for that pair. "Not separable" is the status only
  when the residual is the data's noise or cannot be judged (the outcome then says so); a residual beyond the noise
  is the misfit above.
"""

from __future__ import annotations

import csv
import dataclasses
import math
from pathlib import Path

import numpy as np

from tribocosim.errors import ParameterError
from tribocosim.cosim.apps.calibrate_noise import ResidualTest, residual_test

KEYS = ("pressure", "tool_length", "passes")
#: measured quantity -> (the strip draw's pass result it is, the check of a value, what is allowed)
OBSERVABLES = {
    "mu_bar": ("mu_bar", lambda x: 0 < x < 1, "it must lie in (0, 1)"),
    "debris_g_m2": ("debris_g_m2", lambda x: x >= 0, "it must be >= 0 [g/m^2]"),
    "beta": ("beta_left", lambda x: 0 <= x <= 1, "it must lie in [0, 1]"),
}
#: fittable parameter -> (lower bound, upper bound, scale: the size of a change that matters)
FITTABLE = {
    "particle_area_scale": (0.0, 1e6, 1.0),
    "flake_shear_ratio": (0.0, 1.0, 0.1),
    "archard_k": (0.0, 1.0, 1e-4),
    "zeta": (0.0, 1.0, 0.1),
    "debris_carry_over": (0.0, 1.0, 0.1),
    "debris_sink_length": (1e-4, 1e3, 0.01),
}
#: the start of a sink length given as 0 (no sink): one draw length [m]
SINK_START = 0.14
RTOL = 1e-6
STDERR_FRACTION = 0.01
MAX_ITERATIONS = 20
#: halvings of a step that does not lower chi^2 before the iteration keeps its start
HALVINGS = 6
#: the data cannot separate the parameters below this ratio of the Jacobian's singular values, or above this
#: correlation of two parameters
SINGULAR_RATIO, CORRELATION_MAX = 1e-6, 0.99


@dataclasses.dataclass(frozen=True)
class Measurement:
    """One row of the data file: its test and the observables measured after its pass (name -> value, std)."""

    pressure: float
    tool_length: float
    passes: int
    values: dict
    stds: dict
    row: int

    @property
    def mu_bar(self) -> float | None:
        return self.values.get("mu_bar")


def read_measurements(path: str | Path) -> list[Measurement]:
    """The rows of a measurement file; ParameterError naming the file, row and column of a bad value."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise ParameterError(f"measurement file {path} cannot be read: {exc}") from exc
    reader = csv.DictReader(text.splitlines())
    header = [h.strip() for h in (reader.fieldnames or [])]
    missing = [c for c in KEYS if c not in header]
    measured = [c for c in OBSERVABLES if c in header]
    if missing or not measured:
        need = ", ".join(missing) if missing else f"an observable ({', '.join(OBSERVABLES)})"
        raise ParameterError(f"{path}: missing column(s) {need}; the header needs {', '.join(KEYS)} and at least one "
                             f"of {', '.join(OBSERVABLES)} (each with an optional <name>_std); it has "
                             f"{', '.join(header) or 'nothing'}")
    rows = []
    for k, raw in enumerate(reader, start=2):  # line 1 is the header
        rec = {key.strip(): (value or "").strip() for key, value in raw.items() if key is not None}
        if not any(rec.values()):
            continue

        def number(name: str, check, allowed: str, integer: bool = False):
            text = rec.get(name, "")
            try:
                x = float(text)
                if integer and x != int(x):
                    raise ValueError
            except (ValueError, OverflowError):
                raise ParameterError(f"{path}, row {k}, column {name}: {text!r} is not "
                                     f"{'an integer' if integer else 'a number'}") from None
            if not (np.isfinite(x) and check(x)):
                raise ParameterError(f"{path}, row {k}, column {name}: {text} is not allowed; {allowed}")
            return int(x) if integer else x

        values, stds = {}, {}
        for name in measured:
            if not rec.get(name):
                continue
            _, check, allowed = OBSERVABLES[name]
            values[name] = number(name, check, allowed)
            if rec.get(name + "_std"):
                stds[name] = number(name + "_std", lambda x: x > 0, "it must be > 0")
        if not values:
            raise ParameterError(f"{path}, row {k}: no measured value; give at least one of {', '.join(measured)}")
        rows.append(Measurement(number("pressure", lambda x: x > 0, "it must be > 0 [Pa]"),
                                number("tool_length", lambda x: x > 0, "it must be > 0 [m]"),
                                number("passes", lambda x: x >= 1, "it must be an integer >= 1", integer=True),
                                values, stds, k))
    if not rows:
        raise ParameterError(f"{path}: no data rows")
    kinds = {n for r in rows for n in r.values}
    unweighted = [(r.row, n) for r in rows for n in r.values if n not in r.stds]
    if len(kinds) > 1 and unweighted:
        row, name = unweighted[0]
        raise ParameterError(f"{path}, row {row}: {name} has no {name}_std; data that mix observables "
                             f"({', '.join(sorted(kinds))}) need the standard deviation of every value to weigh them")
    return rows


@dataclasses.dataclass
class Fit:
    """The outcome of :func:`fit` (module docstring)."""

    names: tuple[str, ...]
    values: np.ndarray
    stderr: np.ndarray  # NaN for a parameter at its bound
    residuals: list[dict]  # per row and observable: measured, model, residual (model - measured)
    iterations: int  # of the Gauss-Newton run that gave these values
    evaluations: int  # of the model, every run and the cap search's starts together
    converged: bool
    last_change: np.ndarray
    at_bound: dict  # name -> "lower" or "upper"
    singular_values: np.ndarray  # of the Jacobian in units of the parameters' scales
    correlation: np.ndarray
    separable: bool
    inseparable: list[str]  # what the data cannot separate, in words
    chi2: float
    dof: int
    shear_scale: dict | None = None  # (1 - r) s with its standard error when s and r are fitted together
    residual_test: ResidualTest | None = None  # the residual against the data's noise
    search: dict | None = None  # the cap search (:func:`search_the_cap`), when it ran

    @property
    def describes(self) -> bool | None:
        """Whether the residual is the data's noise (None: not judged, :mod:`calibrate_noise`)."""
        return None if self.residual_test is None else self.residual_test.describes

    @property
    def succeeded(self) -> bool:
        """Converged, inside the bounds, a residual not larger than the data's noise, and every parameter separated
        by the data."""
        return self.converged and not self.at_bound and self.describes is not False and self.separable

    @property
    def misfit(self) -> list[str]:
        """The one line that says the model does not describe the data, when it does not."""
        if self.describes is not False:
            return []
        values = ", ".join(f"{n} = {v:.6g}" for n, v in zip(self.names, self.values))
        if not self.separable:
            values += "; there the data do not separate the parameters"
        return [f"the model does not describe the data: at the best fit found ({values}), "
                f"{self.residual_test.line(with_rms=False)}; the largest residuals: "
                f"{self.residual_test.worst_line()}. The "
                "strip-draw model with these parameters free cannot follow these data: fit other parameters (the "
                "debris balance: archard_k, debris_carry_over, debris_sink_length) or check the data's standard "
                "deviations"]

    @property
    def problems(self) -> list[str]:
        """Why the fit did not succeed beyond the bounds and the convergence, in words: the misfit, or what the data
        cannot separate (with a word on the residual when the data carry no measure of their noise)."""
        if self.misfit:
            return self.misfit
        note = ([f"{self.residual_test.reason}: whether the residual is their noise is not judged (give each value's "
                 "<name>_std, or repeat tests, to judge it)"]
                if self.inseparable and self.residual_test is not None and self.describes is None else [])
        return self.inseparable + note

    def as_dict(self) -> dict:
        return {n: {"value": float(v), "stderr": None if not math.isfinite(e) else float(e),
                    **({"at_bound": self.at_bound[n]} if n in self.at_bound else {})}
                for n, v, e in zip(self.names, self.values, self.stderr)}

    def status(self) -> str:
        if self.at_bound:
            return "at bound"
        if not self.converged:
            return "not converged"
        if self.describes is False:
            return "does not describe the data"
        if not self.separable:
            return "not separable"
        return "converged"


def start_values(parameters: dict, names, defaults: dict) -> np.ndarray:
    """The start of every fitted parameter: its value in ``parameters`` (or the default), moved inside its bounds
    (a zero scale s starts at 1, a zero sink length, no sink, at :data:`SINK_START`)."""
    theta = np.array([float(parameters.get(n, defaults[n])) for n in names])
    for j, n in enumerate(names):
        if n == "particle_area_scale" and theta[j] == 0:
            theta[j] = 1.0
        if n == "debris_sink_length" and theta[j] == 0:
            theta[j] = SINK_START
        lo, hi, _ = FITTABLE[n]
        theta[j] = min(max(theta[j], lo), hi)
    return theta


class _Problem:
    """One weighted least-squares problem: the measured values in order (row, observable), their standard deviations,
    the fitted parameters' bounds and scales, and the model, whose evaluations it counts."""

    def __init__(self, data: list[Measurement], parameters: dict, names: tuple[str, ...], model):
        self.names, self.parameters, self.model = names, parameters, model
        self.keys = [(d.row, n) for d in data for n in d.values]
        self.tests = [(d.pressure, d.tool_length, d.passes) for d in data for _ in d.values]
        self.measured = np.array([d.values[n] for d in data for n in d.values])
        self.sigma = np.array([d.stds.get(n, 1.0) for d in data for n in d.values])
        self.weighted = all(n in d.stds for d in data for n in d.values)
        self.lo, self.hi, self.scale = (np.array([FITTABLE[n][i] for n in names]) for i in range(3))
        self.evaluations = 0

    def run(self, thetas) -> list[np.ndarray]:
        """The model's values at each parameter vector."""
        self.evaluations += len(thetas)
        out = self.model([{**self.parameters, **dict(zip(self.names, map(float, th)))} for th in thetas])
        return [np.array([o[k] for k in self.keys]) for o in out]

    def cost(self, values) -> float:
        return float(np.sum(((values - self.measured) / self.sigma) ** 2))


@dataclasses.dataclass
class _Run:
    """The end of one Gauss-Newton run: the parameters, the model's values there, the last Jacobian."""

    theta: np.ndarray
    values: np.ndarray
    J: np.ndarray
    iterations: int
    converged: bool
    change: np.ndarray  # of the last iteration
    delta: np.ndarray  # the last unconstrained step


def gauss_newton(problem: _Problem, theta, max_iterations: int, log=None, values=None) -> _Run:
    """Gauss-Newton from ``theta`` (the model's ``values`` there, when known) to convergence or ``max_iterations``
    (module docstring)."""
    p = problem
    current = p.run([theta])[0] if values is None else values
    it, converged, change, delta = 0, False, np.zeros_like(theta), np.zeros_like(theta)
    J = np.zeros((len(p.keys), len(p.names)))
    for it in range(1, max_iterations + 1):
        steps = 1e-3 * np.maximum(np.abs(theta), p.scale)
        probes = []
        for j in range(len(p.names)):
            t = theta.copy()
            t[j] = t[j] + steps[j] if t[j] + steps[j] <= p.hi[j] else t[j] - steps[j]
            probes.append(t)
        cols = p.run(probes)
        J = np.column_stack([(c - current) / (q[j] - theta[j]) for j, (c, q) in enumerate(zip(cols, probes))])
        r = (current - p.measured) / p.sigma
        # the step in units of the parameters' scales, directions the data do not see (singular values below
        # SINGULAR_RATIO of the largest) left out
        step, *_ = np.linalg.lstsq(J / p.sigma[:, None] * p.scale[None, :], -r, rcond=SINGULAR_RATIO)
        delta = step * p.scale
        new = np.clip(theta + delta, p.lo, p.hi)
        trial = p.run([new])[0]
        if p.cost(trial) > p.cost(current) * (1 + 1e-12):  # no progress: half steps; none lowers chi^2: stay
            for _ in range(HALVINGS):
                new = 0.5 * (theta + new)
                trial = p.run([new])[0]
                if p.cost(trial) <= p.cost(current):
                    break
            else:
                new, trial = theta, current
        change = new - theta
        converged = bool(np.all(np.abs(change) <= RTOL * np.maximum(np.abs(theta), p.scale))
                         or _standard_errors(J, p.sigma, (trial - p.measured) / p.sigma, p.weighted, change)
                         <= STDERR_FRACTION)
        theta, current = new, trial
        if log:
            log(f"  iteration {it}: " + ", ".join(f"{n} = {v:.6g}" for n, v in zip(p.names, theta))
                + f", chi^2 {p.cost(current):.4g}")
        if converged:
            break
    return _Run(theta, current, J, it, converged, change, delta)


def judge(problem: _Problem, run: _Run) -> Fit:
    """The :class:`Fit` at the end of ``run``: bounds, standard errors, separability and the residual against the
    data's noise, all at that point (module docstring)."""
    p, theta, names = problem, run.theta, problem.names
    at_bound = {n: ("lower" if theta[j] <= p.lo[j] else "upper") for j, n in enumerate(names)
                if (theta[j] <= p.lo[j] and run.delta[j] < 0) or (theta[j] >= p.hi[j] and run.delta[j] > 0)}
    r = (run.values - p.measured) / p.sigma
    stderr = _stderr(run.J, p.sigma, r, p.weighted)
    stderr[[names.index(n) for n in at_bound]] = np.nan
    Jw = run.J / p.sigma[:, None]
    singular, correlation, inseparable = separability(Jw, names, p.scale)
    inseparable += [f"the data do not determine {n}: its standard error {e:.3g} exceeds its range [{a:g}, {b:g}]"
                    for n, e, a, b in zip(names, stderr, p.lo, p.hi) if np.isfinite(b - a) and e > b - a]
    product = shear_scale_product(names, theta, Jw, r, p.weighted)
    if product is not None and abs(product["correlation"]) > CORRELATION_MAX:
        others = [n for n in names if n not in SHEAR_SCALE]
        inseparable = [product_line(product)] + [m for m in inseparable if not any(n in m for n in SHEAR_SCALE)
                                                 or any(n in m for n in others)]
    rows = [{"row": k[0], "observable": k[1], "measured": float(m), "model": float(v), "residual": float(v - m),
             "std": float(s) if p.weighted else None} for k, m, v, s in zip(p.keys, p.measured, run.values, p.sigma)]
    test = residual_test(p.tests, p.keys, p.measured, run.values, p.sigma, p.weighted, len(names))
    return Fit(tuple(names), theta, stderr, rows, run.iterations, p.evaluations, run.converged, run.change, at_bound,
               singular, correlation, not inseparable, inseparable, float(np.sum(r**2)), len(p.keys) - len(names),
               product, test)


def fit(data: list[Measurement], parameters: dict, names: tuple[str, ...], model, log=None,
        max_iterations: int = MAX_ITERATIONS) -> Fit:
    """Least-squares fit of the parameters ``names`` to ``data`` (module docstring): Gauss-Newton from the start,
    and with s and r fitted together, when that fit does not succeed, the cap search (:func:`search_the_cap`).

    ``model(list of parameter dicts) -> list of {(row, observable): value}`` evaluates the strip-draw model for every
    measurement at each parameter set (:func:`strip_draw_model`); ``parameters`` holds the start values and the
    parameters held fixed.
    """
    from tribocosim.components.stripdraw.component import COMPONENT

    unknown = [n for n in names if n not in FITTABLE]
    if unknown or not names or len(set(names)) != len(names):
        raise ParameterError(f"--fit {' '.join(names)}: fit one or more of {', '.join(FITTABLE)}, each once")
    if isinstance(max_iterations, bool) or not isinstance(max_iterations, int) or max_iterations < 1:
        raise ParameterError(f"max_iterations = {max_iterations!r} is not allowed; an integer >= 1 is required")
    n_values = sum(len(d.values) for d in data)
    if n_values < len(names):
        raise ParameterError(f"{n_values} measured value(s) cannot determine {len(names)} parameters "
                             f"({', '.join(names)}): measure more tests or passes, or fit fewer")
    problem = _Problem(data, parameters, tuple(names), model)
    run = gauss_newton(problem, start_values(parameters, names, COMPONENT.defaults), max_iterations, log)
    outcome = judge(problem, run)
    if all(n in names for n in SHEAR_SCALE) and not outcome.succeeded:
        outcome = search_the_cap(problem, run, outcome, max_iterations, log)
    outcome.evaluations = problem.evaluations
    return outcome


#: the cap search's starts: r on this grid over its range, s = q / (1 - r) holding (1 - r) s = q
CAP_SEARCH_RATIOS = tuple(round(0.05 * k, 2) for k in range(20))
#: model values that differ by more than this (relative) from those the valley gives below the cap's onset
CAP_SEEN = 1e-9


def search_the_cap(problem: _Problem, run: _Run, outcome: Fit, max_iterations: int, log=None) -> Fit:
    """The fit of s and r where the model's debris reaches the cap (module docstring): the starts along the valley
    (1 - r) s = q of ``run``'s q, r on :data:`CAP_SEARCH_RATIOS`, the other fitted parameters at ``run``'s values,
    all evaluated in one batch; those whose model values differ from the r = 0 start's (below the onset every start
    of the valley gives the same values) reach the cap, and Gauss-Newton starts from the one of them with the least
    chi^2. The outcome is the better (lower chi^2) of that fit and ``outcome``, with the search's record."""
    p = problem
    i, j = (p.names.index(n) for n in SHEAR_SCALE)
    q = (1.0 - run.theta[j]) * run.theta[i]
    starts = []
    for r in CAP_SEARCH_RATIOS:
        t = run.theta.copy()
        t[j], t[i] = r, min(max(q / (1.0 - r), p.lo[i]), p.hi[i])
        starts.append(t)
    values = p.run(starts)
    costs = [p.cost(v) for v in values]
    below = [k for k, v in enumerate(values) if np.all(np.abs(v - values[0]) <= CAP_SEEN * np.abs(values[0]))]
    reach = [k not in below or len(below) == 1 for k in range(len(starts))]
    record = {"product": float(q), "flake_shear_ratio": [float(t[j]) for t in starts],
              "particle_area_scale": [float(t[i]) for t in starts], "chi2": costs, "reaches_cap": reach,
              "from_start": {"values": dict(zip(p.names, map(float, run.theta))), "chi2": outcome.chi2,
                             "status": outcome.status(), "iterations": run.iterations}}
    candidates = [k for k in range(len(starts)) if reach[k]]
    if log:
        log(f"  from the start: {outcome.status()} (chi^2 {outcome.chi2:.4g}); the cap search along (1 - r) s = "
            f"{q:.4g}, r = {CAP_SEARCH_RATIOS[0]:g}-{CAP_SEARCH_RATIOS[-1]:g}: {len(candidates)} of {len(starts)} "
            f"starts reach the cap" + (f" (r >= {min(starts[k][j] for k in candidates):g})" if candidates else ""))
    if not candidates:
        record["chosen"] = "start"
        return dataclasses.replace(outcome, search=record)
    best = min(candidates, key=lambda k: costs[k])
    record["from"] = dict(zip(p.names, map(float, starts[best])))
    if log:
        log(f"  from r = {starts[best][j]:g}, s = {starts[best][i]:.4g} (chi^2 {costs[best]:.4g}):")
    searched = judge(p, gauss_newton(p, starts[best], max_iterations, log, values[best]))
    chosen = searched if searched.chi2 < outcome.chi2 else outcome
    record["chosen"] = "search" if chosen is searched else "start"
    return dataclasses.replace(chosen, search=record)


#: the parameters that enter mu below the cap only through (1 - r) s
SHEAR_SCALE = ("particle_area_scale", "flake_shear_ratio")


def shear_scale_product(names, theta, Jw: np.ndarray, residuals, weighted: bool) -> dict | None:
    """With s and r both fitted: the combination q = (1 - r) s the data determine below the cap (mu = mu0 (1 - q A_p /
    A_c)), its standard error and the correlation of s and r; None when they are not both fitted.

    The correlation is that of the covariance C = (J^T J)^-1. When it exceeds :data:`CORRELATION_MAX` the data see q
    alone (J_s = (1 - r) dmu/dq, J_r = -s dmu/dq), and q's standard error is that of a fit of q in place of the pair:
    its column ((1 - r) J_s - s J_r) / ((1 - r)^2 + s^2) beside the other fitted parameters'; otherwise it is
    sqrt(g C g) with the gradient g = (1 - r, -s)."""
    if not all(n in names for n in SHEAR_SCALE):
        return None
    i, j = (list(names).index(n) for n in SHEAR_SCALE)
    dof_scale = 1.0 if weighted else float(np.sum(np.asarray(residuals) ** 2)) / max(1, Jw.shape[0] - Jw.shape[1])
    cov = np.linalg.pinv(Jw.T @ Jw) * dof_scale
    s, r = float(theta[i]), float(theta[j])
    pair = cov[np.ix_([i, j], [i, j])]
    d = np.sqrt(np.maximum(np.diag(pair), 1e-300))
    correlation = float(pair[0, 1] / (d[0] * d[1]))
    if abs(correlation) > CORRELATION_MAX:
        q_column = ((1.0 - r) * Jw[:, i] - s * Jw[:, j]) / ((1.0 - r) ** 2 + s**2)
        reduced = np.column_stack([q_column] + [Jw[:, k] for k in range(Jw.shape[1]) if k not in (i, j)])
        variance = float(np.linalg.pinv(reduced.T @ reduced)[0, 0]) * dof_scale
    else:
        grad = np.array([1.0 - r, -s])
        variance = float(grad @ pair @ grad)
    return {"value": (1.0 - r) * s, "stderr": float(np.sqrt(max(variance, 0.0))), "correlation": correlation}


def product_line(product: dict) -> str:
    """The one line that says the data cannot separate r from s (:func:`shear_scale_product`)."""
    return (f"the data determine only (1 - flake_shear_ratio) particle_area_scale = {product['value']:.4g} +- "
            f"{product['stderr']:.2g} (correlation of the two {product['correlation']:+.4f}): below the cap mu = mu0 "
            "(1 - (1 - r) s A_p / A_c) depends on them only through that product, so they cannot be separated; fix one "
            "(--set) or add tests whose debris reaches the cap, where mu = r mu0 (more passes, higher pressure, a "
            "longer pad)")


def _standard_errors(J, sigma, r, weighted: bool, change) -> float:
    """The length of ``change`` in standard errors: sqrt(d^T C^-1 d) with C^-1 = J_w^T J_w (divided by chi^2 / (N - n)
    unless the data give their standard deviations), the change of the model it makes in units of the data's noise.
    One parameter: |d| / its standard error; several: at least |d_i| / se_i for each, and the change along a
    direction the data hardly see counts as little as they see it."""
    Jw = J / sigma[:, None]
    moved = float(np.sum((Jw @ change) ** 2))
    if not weighted:
        moved /= max(float(np.sum(r**2)) / max(1, J.shape[0] - J.shape[1]), 1e-300)
    return math.sqrt(moved)


def _stderr(J, sigma, r, weighted: bool) -> np.ndarray:
    """sqrt(diag((J^T J)^-1)) of the weighted problem, scaled by chi^2 / (N - n) unless the data give their standard
    deviations."""
    Jw = J / sigma[:, None]
    cov = np.linalg.pinv(Jw.T @ Jw)
    if not weighted:
        cov = cov * float(np.sum(r**2)) / max(1, J.shape[0] - J.shape[1])
    return np.sqrt(np.maximum(np.diag(cov), 0.0))


def separability(Jw: np.ndarray, names, scale) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """The singular values of the weighted Jacobian in units of the parameters' scales, the parameters' correlation
    matrix, and what the data cannot separate, in words (module docstring)."""
    Js = Jw * np.asarray(scale)[None, :]
    u, s, vt = np.linalg.svd(Js, full_matrices=False)
    problems = []
    if s.size and (s[-1] <= SINGULAR_RATIO * s[0] or not np.all(np.isfinite(s))):
        v = vt[-1]
        weights = ", ".join(f"{n} {c:+.2f}" for n, c in zip(names, v) if abs(c) > 0.1)
        problems.append(f"the data do not determine the combination ({weights}) of the parameters in units of their "
                        f"scales (smallest singular value {s[-1]:.3g}, largest {s[0]:.3g})")
    cov = np.linalg.pinv(Js.T @ Js)
    d = np.sqrt(np.maximum(np.diag(cov), 1e-300))
    corr = cov / np.outer(d, d)
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            if abs(corr[i, j]) > CORRELATION_MAX and not problems:
                problems.append(f"the data cannot separate {names[i]} and {names[j]} (correlation {corr[i, j]:+.4f}): "
                                "only a combination of them is determined")
    return s, corr, problems


def strip_draw_model(data: list[Measurement], workers: int | None = None):
    """``model(parameter sets)`` for :func:`fit`: every (pressure, pad) of ``data`` drawn once per parameter set with
    as many passes as its rows need (in parallel processes), each row's observables read from its pass."""
    from tribocosim.cosim.studies.stripdraw_experiment import Point, draw, run_points

    tests = {}
    for d in data:
        tests[(d.pressure, d.tool_length)] = max(tests.get((d.pressure, d.tool_length), 0), d.passes)

    def model(parameter_sets: list[dict]) -> list[dict]:
        points = [Point(p, pad, n, params) for params in parameter_sets for (p, pad), n in tests.items()]
        done = run_points(points, workers, draw)
        out = []
        for s in range(len(parameter_sets)):
            passes = dict(zip(tests, done[s * len(tests):(s + 1) * len(tests)]))
            out.append({(d.row, n): passes[(d.pressure, d.tool_length)][d.passes - 1][OBSERVABLES[n][0]]
                        for d in data for n in d.values})
        return out

    return model
