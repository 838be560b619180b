"""The table against direct slides at points between its nodes (docs/physics/table_domain.md).

At an off-node point (P, v, beta) inside the simulated domain, a set of slides with the table's own sweep
settings (:func:`tribocosim.surrogate.campaign.make_case`: surfaces, domain, damping, placement; the flake
count that gives beta on the domain, Eq. 10) gives <A_p>/A0 with its standard error s_d (member std /
sqrt(members)) and mu = mu0 (1 - <A_p> / <A_c>) with its standard error (the members' A_p and A_c, first order).
The table gives its interpolation of A_p and of mu (the strip-draw law's, at s = 1) with the interpolated standard
errors s_t of the tabulated values. The check passes when both differences are within two combined standard
errors, |direct - table| <= 2 sqrt(s_d^2 + s_t^2), at every point, and the interpolation reads no node the campaign
did not simulate.

:data:`POINTS`: one point at moderate debris (P = 3 MPa, beta = 0.15), one at beta >= 0.3 (P = 15 MPa, beta = 0.4),
both at the strip-draw test's 0.08 m/s, and two at beta >= 0.5 between the nodes of every axis (25 MPa, 0.2 m/s,
beta 0.6; 25 MPa, 0.3 m/s, beta 0.9), each between pressure nodes and between debris levels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tribocosim.errors import TableError
from tribocosim.components.stripdraw.friction import make_friction_law
from tribocosim.components.stripdraw.parameters import StripDrawParameters

from .campaign import make_case, run_case
from .sweep import parse_sweep_dict

#: (P [Pa], v [m/s], beta) of the standing check (module docstring)
POINTS = ((3e6, 0.08, 0.15), (15e6, 0.08, 0.4), (25e6, 0.2, 0.6), (25e6, 0.3, 0.9))
#: placement seeds of the check's slides (none of them a table seed of the shipped preset)
SEEDS = (101, 102, 103)


@dataclass(frozen=True)
class CheckResult:
    """One point of the check."""

    pressure: float
    velocity: float
    beta: float  # of the flake count used
    members: int
    direct: float
    direct_se: float
    table: float
    table_se: float
    all_nodes_simulated: bool
    wall_s: float
    mu_direct: float = math.nan
    mu_direct_se: float = math.nan
    mu_table: float = math.nan
    mu_table_se: float = math.nan

    @property
    def combined_se(self) -> float:
        return math.hypot(self.direct_se, self.table_se)

    @property
    def mu_combined_se(self) -> float:
        return math.hypot(self.mu_direct_se, self.mu_table_se)

    @property
    def passed(self) -> bool:
        within = abs(self.direct - self.table) <= 2.0 * self.combined_se
        mu_within = (not math.isfinite(self.mu_combined_se)  # a table without mu's standard error (version 3)
                     or abs(self.mu_direct - self.mu_table) <= 2.0 * self.mu_combined_se)
        return self.all_nodes_simulated and within and mu_within

    def to_dict(self) -> dict:
        def ratio(d, se):
            return d / se if se > 0 else math.inf

        return {"pressure": self.pressure, "velocity": self.velocity, "beta": self.beta, "members": self.members,
                "a_p_direct": self.direct, "a_p_direct_se": self.direct_se, "a_p_table": self.table,
                "a_p_table_se": self.table_se, "combined_se": self.combined_se,
                "difference_over_combined_se": ratio(self.direct - self.table, self.combined_se),
                "mu_direct": self.mu_direct, "mu_direct_se": self.mu_direct_se, "mu_table": self.mu_table,
                "mu_table_se": self.mu_table_se,
                "mu_difference_over_combined_se": ratio(self.mu_direct - self.mu_table, self.mu_combined_se),
                "all_nodes_simulated": self.all_nodes_simulated, "passed": self.passed, "wall_s": self.wall_s}


def check_cases(table, points=POINTS, seeds=SEEDS) -> list:
    """The slides of the check: every point x surface pair x seed, from the table's recorded sweep."""
    camp = table.metadata.get("campaign", {})
    if table.version < 3 or "sweep" not in camp:
        raise TableError("the direct-slide check needs a version 3 table that records its sweep")
    sweep = parse_sweep_dict(camp["sweep"])
    size = sweep.base_config().size
    diameter = sweep.flakes[0].diameter
    cases = []
    for p, v, beta in points:
        count = max(1, round(beta * size**2 / (math.pi * (0.5 * diameter) ** 2)))
        for s in range(len(sweep.surfaces)):
            for seed in seeds:
                cases.append(make_case(sweep, s, p, v, count, diameter, seed))
    return cases


def run_check(table, executor, points=POINTS, seeds=SEEDS) -> list[CheckResult]:
    """Run the check's slides through ``executor`` and compare them with ``table`` (module docstring)."""
    cases = {c.case_id: c for c in check_cases(table, points, seeds)}
    done: dict = {}
    for cid, outcome in executor.map_unordered(run_case, [(cid, c.payload()) for cid, c in cases.items()]):
        if isinstance(outcome, BaseException) or outcome.get("status") != "done":
            err = outcome if isinstance(outcome, BaseException) else outcome.get("error", {}).get("message")
            raise TableError(f"a slide of the direct-slide check failed ({cases[cid].labels}): {err}")
        done[cid] = outcome
    results = []
    mu0 = table.metadata["calibration"]["mu0"]
    for p, v, _ in points:
        recs = [(cases[cid], out) for cid, out in done.items()
                if cases[cid].labels["pressure"] == p and cases[cid].labels["velocity"] == v]
        beta = recs[0][0].labels["beta"]
        ap = np.array([out["summary"]["mean_particle_fraction"] for _, out in recs])
        ac = np.array([out["summary"]["mean_contact_fraction"] for _, out in recs])
        n = ap.size
        share = ap.mean() / ac.mean()
        if n > 1:
            cov = np.cov(ap, ac, ddof=1)
            mu_se = mu0 * math.sqrt(max(cov[0, 0] - 2 * share * cov[0, 1] + share**2 * cov[1, 1], 0.0)
                                    / (ac.mean() ** 2 * n))
        else:
            mu_se = math.inf
        t_ap = float(table.interpolate_array(table.particle_area, p, v, beta, "error")[0])
        t_se = float(table.interpolate_array(table.array("particle_area_se"), p, v, beta, "error")[0])
        # the slides' mu is that of frictionless flakes, the table's mu (flake-borne shear is the strip's option)
        t_mu = float(make_friction_law(StripDrawParameters(mu0=mu0, flake_shear_ratio=0.0), table).mu(p, v, beta)[0])
        t_mu_se = (float(table.interpolate_array(table.array("mu_se"), p, v, beta, "error")[0])
                   if "mu_se" in table.arrays() else math.nan)
        results.append(CheckResult(p, v, beta, n, float(ap.mean()),
                                   float(ap.std(ddof=1) / math.sqrt(n)) if n > 1 else math.inf,
                                   t_ap, t_se, not table.reads_unsimulated(p, v, beta),
                                   float(sum(out["wall_s"] for _, out in recs)),
                                   mu0 * max(0.0, 1.0 - share), mu_se, t_mu, t_mu_se))
    return results
