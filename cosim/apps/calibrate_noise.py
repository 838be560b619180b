"""Whether the residual of a ``tribocosim calibrate`` fit is the data's noise, or says the model does not describe them.

A fit of n parameters to N values with residuals r_i = (model_i - measured_i) / sigma_i is judged by one of:

- the stated standard deviations (every value has one): chi^2 = sum r_i^2 follows a chi^2 distribution with
  N - n degrees of freedom when the model describes the data and the sigma_i are their noise (to first order in the
  parameters); the probability P(chi^2_{N-n} >= chi^2) below :data:`SIGNIFICANCE` says the residual is larger than the
  noise the data state;
- replicated tests (no standard deviations; rows with the same pressure, pad and passes, as the paper's three tests
  per condition): the classical lack-of-fit test against pure error. The model gives every replicate the same value,
  so the residual sum of squares splits exactly into the pure error SS_pe = sum_g sum_k (y_gk - ybar_g)^2 on
  sum_g (n_g - 1) degrees of freedom and the lack of fit SS_lof = sum_g n_g (ybar_g - model_g)^2 on G - n (G distinct
  tests); F = (SS_lof / (G - n)) / (SS_pe / sum_g (n_g - 1)) follows an F distribution when the model describes the
  means, and P(F_{G-n, sum(n_g-1)} >= F) below :data:`SIGNIFICANCE` says it does not;
- neither (no standard deviations, no replicates, or no degrees of freedom left): the data carry no measure of their
  noise, so the residual is reported (its RMS relative to the data) and not judged. No noise level is assumed: a
  strip-draw campaign's scatter is a property of its machine and strips, and the paper gives none for mu_bar.

At :data:`SIGNIFICANCE` = 0.01 a model that describes the data is called inadequate for one data set in a hundred.
"""

from __future__ import annotations

import dataclasses

import numpy as np

#: a residual whose probability under the data's noise is below this says the model does not describe the data
SIGNIFICANCE = 0.01
#: how many of the largest normalised residuals a judgement names
WORST = 3


@dataclasses.dataclass(frozen=True)
class ResidualTest:
    """The residual of a fit against the data's noise (module docstring)."""

    method: str | None  # "chi2" (stated standard deviations), "replicates" (lack of fit), None (not judged)
    statistic: float | None  # chi^2 or F
    dof: tuple  # (N - n,) or (G - n, pure-error degrees of freedom)
    probability: float | None
    rms: float  # RMS of the residuals relative to the measured values
    worst: tuple  # (row, observable, residual): the largest, in units of sigma (weighted) or of the value
    weighted: bool
    reason: str = ""  # why the residual is not judged

    @property
    def describes(self) -> bool | None:
        """True when the residual is the data's noise, False when it is larger, None when it is not judged."""
        return None if self.probability is None else bool(self.probability >= SIGNIFICANCE)

    def line(self, with_rms: bool = True) -> str:
        """The judgement in words (with the residual's RMS relative to the data)."""
        rms = f"RMS residual {100 * self.rms:.3g} % of the data" if with_rms else "the residual"
        if self.method is None:
            return f"{rms}; {self.reason}: whether it is their noise is not judged"
        verdict = (f"at least {SIGNIFICANCE:g}: the residual is the data's noise" if self.describes
                   else f"below {SIGNIFICANCE:g}: the residual is larger than the data's noise")
        if self.method == "chi2":
            what = (f"chi^2 = {self.statistic:.4g} on {self.dof[0]} degrees of freedom, a value the stated standard "
                    f"deviations exceed with probability {self.probability:.3g}")
        else:
            what = (f"lack of fit F = {self.statistic:.4g} on ({self.dof[0]}, {self.dof[1]}) degrees of freedom "
                    f"against the spread of the replicated tests, exceeded with probability {self.probability:.3g}")
        return f"{what} ({verdict})" + (f"; {rms}" if with_rms else "")

    def worst_line(self) -> str:
        """The largest residuals, by row and observable."""
        if self.weighted:
            return ", ".join(f"row {row} {name} {r:+.3g} sigma" for row, name, r in self.worst)
        return ", ".join(f"row {row} {name} {100 * r:+.3g} %" for row, name, r in self.worst)

    def as_dict(self) -> dict:
        return {"method": self.method, "statistic": self.statistic, "dof": list(self.dof),
                "probability": self.probability, "significance": SIGNIFICANCE, "describes": self.describes,
                "rms_relative": self.rms, "worst": [list(w) for w in self.worst], "text": self.line()}


def residual_test(tests: list[tuple], keys: list[tuple], measured, values, sigma, weighted: bool,
                  n_parameters: int) -> ResidualTest:
    """The judgement of the residual ``values - measured`` (module docstring): ``tests`` holds each value's test
    (pressure, pad, passes), ``keys`` its (row, observable)."""
    from scipy.stats import chi2 as chi2_distribution, f as f_distribution

    measured, values, sigma = (np.asarray(x, dtype=float) for x in (measured, values, sigma))
    residual = values - measured
    relative = residual / np.where(measured != 0, np.abs(measured), 1.0)
    rms = float(np.sqrt(np.mean(relative**2)))
    shown = residual / sigma if weighted else relative
    order = np.argsort(-np.abs(shown))[:WORST]
    worst = tuple((int(keys[k][0]), str(keys[k][1]), float(shown[k])) for k in order)
    dof = len(measured) - n_parameters
    if weighted:
        if dof < 1:
            return ResidualTest(None, None, (dof,), None, rms, worst, True, f"{len(measured)} values fit by "
                                f"{n_parameters} parameters leave no degree of freedom to judge the residual by")
        chi2 = float(np.sum((residual / sigma) ** 2))
        return ResidualTest("chi2", chi2, (dof,), float(chi2_distribution.sf(chi2, dof)), rms, worst, True)
    groups: dict[tuple, list[int]] = {}
    for k, (test, key) in enumerate(zip(tests, keys)):
        groups.setdefault((*test, key[1]), []).append(k)
    pure = float(sum(np.sum((measured[g] - measured[g].mean()) ** 2) for g in groups.values()))
    dof_pure = sum(len(g) - 1 for g in groups.values())
    dof_lack = len(groups) - n_parameters
    if dof_pure < 1 or dof_lack < 1 or not pure > 0:
        reason = ("the data give no standard deviations and no replicated tests" if dof_pure < 1 else
                  f"{len(groups)} distinct tests fit by {n_parameters} parameters leave no degree of freedom for the "
                  "lack of fit" if dof_lack < 1 else "the replicated tests agree exactly")
        return ResidualTest(None, None, (dof_lack, dof_pure), None, rms, worst, False, reason)
    lack = max(float(np.sum(residual**2)) - pure, 0.0)
    statistic = (lack / dof_lack) / (pure / dof_pure)
    return ResidualTest("replicates", statistic, (dof_lack, dof_pure),
                        float(f_distribution.sf(statistic, dof_lack, dof_pure)), rms, worst, False)
