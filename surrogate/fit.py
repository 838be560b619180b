"""Ensemble averages and the fits of Sec. 6 over the finished cases of a campaign.

- Ensemble (Sec. 6.2): per grid point (P, v, beta), the mean and standard deviation (ddof = 1)
  over the members (placement seeds x surfaces) of <A_p>/A0 (Eq. 22) and <A_c>/A0.
- Eq. 23 per velocity: <A_p>/A0 = alpha beta P / E*, a line through the origin in
  x = beta P / E* over every (P, beta > 0) point of that velocity: alpha = sum(x y) / sum(x^2),
  its standard error from the residuals, R^2 = 1 - SS_res / SS_tot (SS_tot about the mean of y;
  it can be negative for a poor fit), and, as in Fig. 15, the standard deviation of the alphas
  fitted to each member (placement seed) separately.
- Fig. 15: alpha(v) = b (1 - exp(-v / v_ref)) fitted to the alphas with
  ``scipy.optimize.curve_fit`` (weights: the member spread of alpha, absolute), b and v_ref with
  their standard uncertainties from the covariance. With two velocities the fit is exact and
  the uncertainties are not defined (reported as NaN).
- Eq. 8: <A_c>/A0 = s_c P through the origin (s_c [1/Pa], R^2). With the composite RMS slope
  h'_rms of the gap, kappa = s_c E* h'_rms (Eq. 8 read backwards). In the plastic regime of
  docs/model.md section 4 s_c ~ 1/p_crit.
- A_p(beta) at one (P, v) (:func:`fit_beta_forms`): the debris levels' ensemble means y_k with their
  standard errors sigma_k, fitted by weighted least squares with each form of :data:`BETA_FORMS`:
  ``linear`` y = a beta (Eq. 23 at one P and v) and ``langmuir`` y = a beta / (1 + c beta) (saturating;
  beta_s = 1/c is the level at which A_p is half its linear value, c = 0 is the linear form). Each fit
  gives chi^2 = sum ((y_k - f(beta_k)) / sigma_k)^2, Akaike's AIC = chi^2 + 2 k (k parameters, Gaussian
  errors of known sigma), the parameters' covariance (absolute sigma) and the standard error of the
  fitted value at any beta (first-order propagation). Its goodness of fit: the normalised residuals
  (y_k - f(beta_k)) / sigma_k, the degrees of freedom N - k, chi^2 / (N - k) and the probability of a chi^2 at least
  as large if the form were right (the chi^2 distribution's survival function); it passes at significance a when
  N - k >= 1 and that probability is at least a. :func:`fit_affine` fits A_c = c0 + c1 beta the same way.

Everything here is plain arithmetic on the case records: no I/O.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import asdict, dataclass

import numpy as np
from scipy.optimize import curve_fit
from scipy.stats import chi2 as chi2_distribution

from tribocosim.errors import ParameterError


@dataclass(frozen=True)
class EnsemblePoint:
    """Ensemble statistics at one grid point."""

    pressure: float
    velocity: float
    beta: float
    n: int
    ap_mean: float
    ap_std: float
    ac_mean: float
    ac_std: float
    members: tuple  # ((member key, ap, ac, ap by the cluster rule alone), ...)
    apc_mean: float = 0.0
    apc_std: float = 0.0

    @property
    def ap_se(self) -> float:
        """Standard error of ap_mean (member std / sqrt(n))."""
        return self.ap_std / math.sqrt(self.n) if self.n > 1 else math.inf


def _key(x: float) -> float:
    return float(f"{x:.12g}")


def member_key(labels: dict) -> str:
    """Which ensemble member a case is: surface index and placement seed."""
    return f"s{labels.get('surface', 0)}/f{labels.get('seed')}"


def ensemble(records: list[dict]) -> dict:
    """Group finished case records by (P, v, beta) -> :class:`EnsemblePoint`."""
    groups: dict = {}
    for r in records:
        lab, s = r["labels"], r["summary"]
        k = (_key(lab["pressure"]), _key(lab["velocity"]), _key(lab["beta"]))
        groups.setdefault(k, []).append((member_key(lab), float(s["mean_particle_fraction"]),
                                         float(s["mean_contact_fraction"]),
                                         float(s.get("mean_particle_fraction_clusters", 0.0))))
    out = {}
    for k, mem in sorted(groups.items()):
        ap, ac, apc = (np.array([m[i] for m in mem]) for i in (1, 2, 3))
        sd = (lambda a: float(np.std(a, ddof=1)) if a.size > 1 else 0.0)
        out[k] = EnsemblePoint(k[0], k[1], k[2], len(mem), float(ap.mean()), sd(ap),
                               float(ac.mean()), sd(ac), tuple(sorted(mem)), float(apc.mean()), sd(apc))
    return out


def _r2(y, yhat) -> float:
    y, yhat = np.asarray(y, float), np.asarray(yhat, float)
    ss_tot = float(np.sum((y - y.mean()) ** 2))
    ss_res = float(np.sum((y - yhat) ** 2))
    if ss_tot == 0.0:
        return 1.0 if ss_res == 0.0 else float("nan")
    return 1.0 - ss_res / ss_tot


def fit_through_origin(x, y) -> tuple[float, float, float]:
    """Least-squares slope of y = a x, its standard error and R^2."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    sxx = float(np.sum(x * x))
    if x.size == 0 or sxx == 0.0:
        raise ParameterError("a fit through the origin needs at least one point with x != 0")
    a = float(np.sum(x * y) / sxx)
    res = y - a * x
    se = float(math.sqrt(np.sum(res**2) / (x.size - 1) / sxx)) if x.size > 1 else float("nan")
    return a, se, _r2(y, a * x)


@dataclass(frozen=True)
class AlphaFit:
    """Eq. 23 at one velocity."""

    velocity: float
    alpha: float
    alpha_stderr: float
    alpha_member_std: float
    r2: float
    n_points: int
    member_alphas: dict


def fit_alpha(ens: dict, e_star: float) -> list[AlphaFit]:
    """Eq. 23 fitted per velocity over the points with beta > 0 (see the module docstring)."""
    fits = []
    for v in sorted({k[1] for k in ens}):
        pts = [p for k, p in ens.items() if k[1] == v and p.beta > 0]
        if not pts:
            continue
        x = np.array([p.beta * p.pressure / e_star for p in pts])
        y = np.array([p.ap_mean for p in pts])
        a, se, r2 = fit_through_origin(x, y)
        per_member: dict = {}
        for p in pts:
            for mk, ap, *_ in p.members:
                per_member.setdefault(mk, ([], []))
                per_member[mk][0].append(p.beta * p.pressure / e_star)
                per_member[mk][1].append(ap)
        member_alphas = {mk: fit_through_origin(xs, ys)[0] for mk, (xs, ys) in sorted(per_member.items())}
        vals = np.array(list(member_alphas.values()))
        msd = float(np.std(vals, ddof=1)) if vals.size > 1 else float("nan")
        fits.append(AlphaFit(v, a, se, msd, r2, len(pts), member_alphas))
    return fits


def alpha_law(v, b, v_ref):
    """alpha(v) = b (1 - exp(-v / v_ref)) (Fig. 15)."""
    return b * -np.expm1(-np.asarray(v, float) / v_ref)


@dataclass(frozen=True)
class AlphaLawFit:
    """b, v_ref of alpha(v) with standard uncertainties and R^2 over the per-velocity alphas."""

    b: float
    b_err: float
    v_ref: float
    v_ref_err: float
    r2: float
    n_velocities: int
    note: str = ""

    def __call__(self, v):
        if self.b == 0.0:
            return np.zeros(np.shape(v))
        return alpha_law(v, self.b, self.v_ref)


def fit_alpha_law(velocity, alpha, sigma=None) -> AlphaLawFit:
    """Fit alpha(v) = b (1 - exp(-v / v_ref)) to per-velocity alphas (``sigma``: their spreads).

    b >= 0 and v_ref > 0 are enforced through bounds. If every alpha is 0 (no blocked flake in
    the whole campaign), b = 0 and v_ref is undefined (NaN).
    """
    v = np.asarray(velocity, float)
    a = np.asarray(alpha, float)
    if v.size < 2:
        raise ParameterError(f"alpha(v) needs alphas at >= 2 velocities; got {v.size}")
    if np.all(a <= 0):
        return AlphaLawFit(0.0, 0.0, float("nan"), float("nan"), float("nan"), v.size,
                           "no blocked flake at any velocity: alpha = 0")
    s = None
    if sigma is not None:
        s = np.asarray(sigma, float)
        good = np.isfinite(s) & (s > 0)
        if not np.all(good):
            s = None if not np.any(good) else np.where(good, s, np.max(s[good]))
    # a saturated law (v_ref << min v) is the best fit when alpha does not grow: start from both
    # ends and keep the better one
    best = None
    for v_ref0 in (float(np.median(v)), float(v.min()) / 5.0, float(v.max())):
        p0 = (max(float(a.max()), 1e-30), v_ref0)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                popt, pcov = curve_fit(alpha_law, v, a, p0=p0, sigma=s, absolute_sigma=s is not None,
                                       bounds=([0.0, 1e-6 * float(v.min())], [np.inf, 1e3 * float(v.max())]),
                                       maxfev=20000)
        except (RuntimeError, ValueError):
            continue
        w = 1.0 if s is None else 1.0 / s**2
        cost = float(np.sum(w * (a - alpha_law(v, *popt)) ** 2))
        if best is None or cost < best[0]:
            best = (cost, popt, pcov)
    if best is None:
        raise ParameterError("the alpha(v) fit did not converge for any start value")
    _, popt, pcov = best
    err = np.sqrt(np.diag(pcov)) if np.all(np.isfinite(pcov)) else np.full(2, np.nan)
    err = np.array(err, dtype=float)
    if v.size <= 2:
        err = np.full(2, np.nan)
    note = ""
    if popt[1] < 0.5 * v.min():
        note = (f"v_ref = {popt[1]:.3g} m/s lies below the smallest campaign velocity "
                f"{v.min():g} m/s: alpha is saturated over the campaign and v_ref is only bounded "
                "from above by the data (its uncertainty is not defined)")
        err[1] = np.nan
    return AlphaLawFit(float(popt[0]), float(err[0]), float(popt[1]), float(err[1]),
                       _r2(a, alpha_law(v, *popt)), int(v.size), note)


@dataclass(frozen=True)
class ContactFit:
    """<A_c>/A0 = s_c P (Eq. 8 with the measured slope), and kappa = s_c E* h'_rms."""

    slope: float
    slope_err: float
    r2: float
    kappa: float
    rms_slope: float
    source: str
    n_points: int


def fit_contact(ens: dict, e_star: float, rms_slope: float) -> ContactFit:
    """s_c from the particle-free points if there are any, else from all points."""
    free = [p for p in ens.values() if p.beta == 0]
    pts, source = (free, "particle-free cases (beta = 0)") if free else (list(ens.values()), "all cases")
    s, se, r2 = fit_through_origin([p.pressure for p in pts], [p.ac_mean for p in pts])
    return ContactFit(s, se, r2, s * e_star * rms_slope, rms_slope, source, len(pts))


#: the forms of A_p(beta) at one (P, v) that the table build compares (module docstring)
BETA_FORMS = ("linear", "langmuir")
#: bounds of the langmuir form's (a, c)
LANGMUIR_BOUNDS = ([0.0, 0.0], [np.inf, 1e6])
#: when the langmuir fit stops (scipy's least_squares, method "trf", through curve_fit): its default tolerances,
#: named because what a rebuild of the table may move (:func:`parameter_shift`) follows from them
LANGMUIR_TERMINATION = {"ftol": 1e-8, "xtol": 1e-8, "gtol": 1e-8}


def beta_form(name: str, beta, params) -> np.ndarray:
    """The form ``name`` at ``beta`` with ``params`` ((a,) or (a, c); ``affine``: (c0, c1))."""
    b = np.asarray(beta, float)
    if name == "linear":
        return params[0] * b
    if name == "affine":
        return params[0] + params[1] * b
    return params[0] * b / (1.0 + params[1] * b)


def _beta_form_gradient(name: str, beta, params) -> np.ndarray:
    """d(form)/d(params) at ``beta``, shape (len(params), len(beta))."""
    b = np.atleast_1d(np.asarray(beta, float))
    if name == "linear":
        return b[None, :]
    if name == "affine":
        return np.stack([np.ones_like(b), b])
    den = 1.0 + params[1] * b
    return np.stack([b / den, -params[0] * b * b / den**2])


@dataclass(frozen=True)
class BetaFit:
    """One form of A_p(beta) fitted at one (P, v) (module docstring)."""

    form: str
    params: tuple
    covariance: tuple  # row-major k x k
    chi2: float
    aic: float
    n_points: int
    residuals: tuple = ()  # (y_k - f(beta_k)) / sigma_k at the fitted levels

    @property
    def dof(self) -> int:
        """Degrees of freedom: points minus parameters."""
        return self.n_points - len(self.params)

    @property
    def chi2_per_dof(self) -> float:
        """chi^2 / (N - k); NaN without a degree of freedom."""
        return self.chi2 / self.dof if self.dof > 0 else math.nan

    @property
    def p_value(self) -> float:
        """The probability of a chi^2 at least this large if the form were right; NaN without a degree of freedom."""
        return float(chi2_distribution.sf(self.chi2, self.dof)) if self.dof > 0 else math.nan

    def passes(self, significance: float) -> bool:
        """The goodness-of-fit test: at least one degree of freedom and ``p_value >= significance``."""
        return self.dof > 0 and self.p_value >= significance

    def __call__(self, beta) -> np.ndarray:
        return beta_form(self.form, beta, self.params)

    def stderr(self, beta) -> np.ndarray:
        """Standard error of the fitted value at ``beta`` (first-order propagation of the covariance)."""
        g = _beta_form_gradient(self.form, beta, self.params)
        cov = np.asarray(self.covariance, float).reshape(len(self.params), len(self.params))
        return np.sqrt(np.maximum(np.einsum("ik,ij,jk->k", g, cov, g), 0.0))

    def to_dict(self) -> dict:
        return {"form": self.form, "params": list(self.params), "covariance": list(self.covariance),
                "chi2": self.chi2, "aic": self.aic, "n_points": self.n_points, "dof": self.dof,
                "chi2_per_dof": self.chi2_per_dof, "p_value": self.p_value, "residuals": list(self.residuals)}


def fit_beta_forms(beta, y, sigma) -> dict:
    """Every form of :data:`BETA_FORMS` fitted to the level means ``y`` at ``beta`` (> 0) with standard
    errors ``sigma`` (> 0): ``{form: BetaFit}`` (module docstring)."""
    b, yv, sg = (np.asarray(x, float) for x in (beta, y, sigma))
    if b.size < 1 or np.any(b <= 0) or np.any(~(sg > 0)):
        raise ParameterError("a fit of A_p(beta) needs levels beta > 0 with standard errors > 0")
    w = 1.0 / sg**2
    out = {}
    a = float(np.sum(w * b * yv) / np.sum(w * b * b))
    var = 1.0 / float(np.sum(w * b * b))
    chi2 = float(np.sum(w * (yv - a * b) ** 2))
    out["linear"] = BetaFit("linear", (a,), (var,), chi2, chi2 + 2.0, int(b.size), _residuals(yv, a * b, sg))
    best = None
    if b.size >= 2 and a > 0:
        for c0 in (0.0, 1.0 / b.max(), 10.0 / b.max()):
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    popt, pcov = curve_fit(lambda x, a_, c_: a_ * x / (1.0 + c_ * x), b, yv, p0=(a * (1 + c0 * b.mean()), c0),
                                           sigma=sg, absolute_sigma=True, bounds=LANGMUIR_BOUNDS,
                                           maxfev=20000, **LANGMUIR_TERMINATION)
            except (RuntimeError, ValueError):
                continue
            c2 = float(np.sum(w * (yv - beta_form("langmuir", b, popt)) ** 2))
            if best is None or c2 < best[0]:
                best = (c2, popt, pcov)
    if best is not None and np.all(np.isfinite(best[2])):
        c2, popt, pcov = best
        out["langmuir"] = BetaFit("langmuir", (float(popt[0]), float(popt[1])),
                                  tuple(float(x) for x in np.asarray(pcov).ravel()), c2, c2 + 4.0, int(b.size),
                                  _residuals(yv, beta_form("langmuir", b, popt), sg))
    return out


def _residuals(y, fitted, sigma) -> tuple:
    return tuple(float(x) for x in (np.asarray(y) - np.asarray(fitted)) / np.asarray(sigma))


def fit_affine(x, y, sigma) -> BetaFit:
    """y = c0 + c1 x by weighted least squares (standard errors ``sigma`` > 0, at least two distinct x): the form
    ``affine`` with its chi^2, covariance and goodness of fit (module docstring)."""
    xv, yv, sg = (np.asarray(v, float) for v in (x, y, sigma))
    if xv.size < 2 or np.ptp(xv) == 0 or np.any(~(sg > 0)):
        raise ParameterError("an affine fit needs two distinct x and standard errors > 0")
    w = 1.0 / sg**2
    design = np.stack([np.ones_like(xv), xv], axis=1)
    cov = np.linalg.inv(design.T @ (w[:, None] * design))
    params = cov @ (design.T @ (w * yv))
    fitted = design @ params
    c2 = float(np.sum(w * (yv - fitted) ** 2))
    return BetaFit("affine", (float(params[0]), float(params[1])), tuple(float(v) for v in cov.ravel()), c2, c2 + 4.0,
                   int(xv.size), _residuals(yv, fitted, sg))


def parameter_shift(fit: BetaFit, beta, sigma) -> np.ndarray:
    """How far from the optimum of its data the computation of ``fit`` may leave each parameter: what a refit of the
    same data on another processor or another build of numpy, scipy and LAPACK may move (the data: the levels
    ``beta`` and their standard errors ``sigma``).

    - ``linear``: a closed-form ratio of two sums of n products: relative round-off at most 4 n eps (each sum of n
      rounded products within (n + 1) eps, the division one more);
    - ``affine``: the 2 x 2 normal equations solved through LAPACK (``numpy.linalg.inv``): at most
      8 kappa(N) eps ||p|| per parameter, kappa(N) the 2-norm condition number of the normal matrix;
    - ``langmuir``: an iterative least-squares fit that stops on the first of three tests
      (:data:`LANGMUIR_TERMINATION`), each of which bounds the distance to the optimum p* once the iteration
      converges superlinearly: the relative reduction of the cost F = chi^2 / 2 below ftol (F - F* <= ftol F, and
      chi^2 - chi^2* = dp^T C^-1 dp with C the covariance, so |dp_k| <= sqrt(ftol chi^2 C_kk)); the step below
      xtol (xtol + ||p||) (|dp_k| <= that bound); the gradient g = C^-1 dp of F below gtol in its largest component
      (|dp_k| <= gtol sum_j |C_kj|). The shift is the largest of the three, with the round-off of the parameters.
    """
    p = np.asarray(fit.params, float)
    eps = np.finfo(float).eps
    n = len(np.atleast_1d(beta))
    if fit.form == "linear":
        return 4.0 * n * eps * np.abs(p)
    cov = np.asarray(fit.covariance, float).reshape(p.size, p.size)
    if fit.form == "affine":
        w = 1.0 / np.asarray(sigma, float) ** 2
        design = np.stack([np.ones(n), np.asarray(beta, float)], axis=1)
        kappa = float(np.linalg.cond(design.T @ (w[:, None] * design)))
        return np.full(p.size, 8.0 * kappa * eps * float(np.linalg.norm(p)))
    t = LANGMUIR_TERMINATION
    by_cost = np.sqrt(t["ftol"] * max(fit.chi2, 0.0) * np.abs(np.diag(cov)))
    by_step = np.full(p.size, t["xtol"] * (t["xtol"] + float(np.linalg.norm(p))))
    by_gradient = t["gtol"] * np.abs(cov).sum(axis=1)
    return np.maximum.reduce([by_cost, by_step, by_gradient, 4.0 * n * eps * np.abs(p)])


def with_params(fit: BetaFit, beta, sigma, params) -> BetaFit:
    """``fit`` moved to ``params`` (within the form's bounds), with the covariance its fit would report there: the
    Gauss-Newton covariance (J^T J)^-1 of the residuals weighted by 1 / ``sigma`` at the levels ``beta`` (what
    scipy's curve_fit returns with absolute sigma; the linear and affine forms' does not depend on the parameters)."""
    p = np.asarray(params, float)
    if fit.form == "langmuir":
        p = np.clip(p, LANGMUIR_BOUNDS[0], LANGMUIR_BOUNDS[1])
        jac = _beta_form_gradient(fit.form, beta, p) / np.asarray(sigma, float)
        cov = tuple(float(x) for x in np.linalg.pinv(jac @ jac.T).ravel())
    else:
        cov = fit.covariance
    return dataclasses.replace(fit, params=tuple(float(x) for x in p), covariance=cov)


@dataclass(frozen=True)
class FitReport:
    """All fits of a campaign."""

    alpha: list
    law: AlphaLawFit
    contact: ContactFit

    def to_dict(self) -> dict:
        return {"alpha_per_velocity": [asdict(a) for a in self.alpha], "alpha_law": asdict(self.law),
                "contact_area": asdict(self.contact)}


def fit_all(ens: dict, e_star: float, rms_slope: float) -> FitReport:
    """Eq. 23 per velocity, alpha(v) and the A_c slope."""
    alphas = fit_alpha(ens, e_star)
    if len(alphas) < 2:
        raise ParameterError(f"alpha(v) needs results at >= 2 velocities with beta > 0; got {len(alphas)}")
    sig = [a.alpha_member_std if math.isfinite(a.alpha_member_std) and a.alpha_member_std > 0
           else a.alpha_stderr for a in alphas]
    law = fit_alpha_law([a.velocity for a in alphas], [a.alpha for a in alphas], sig)
    return FitReport(alphas, law, fit_contact(ens, e_star, rms_slope))
