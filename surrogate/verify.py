"""Reproduce a friction table from its recorded cases: rerun a sample of them and compare.

A table built by :func:`tribocosim.surrogate.table_build.build_table` records its sweep and every finished case
(labels and results). :func:`sample_cases` rebuilds a sample of those cases from the sweep
(:func:`tribocosim.surrogate.campaign.make_case`; the rebuilt case id must equal the recorded one, so the
configuration is the one that ran) and :func:`verify_cases` reruns them and compares <A_p>/A0, A_p of the
cluster rule and <A_c>/A0 with the recorded values:

- ``identical``: every value equal to 1e-12 (absolute): the same code on the same FFT plans (a slide is
  deterministic for given plans: the FFTW wisdom file of ``TRIBOCOSIM_FFTW_WISDOM``);
- ``within_spread``: a rerun on other FFT plans rounds differently in the last bits, and the DEM carries the
  difference to another trajectory of the same ensemble: then each value must lie within twice the member
  standard deviation of its node (the recorded ensemble), at least one contact pixel;
- anything else fails.

The sample: the cheapest recorded case of every debris level (and one particle-free case), cheapest first, as
long as the recorded wall times add up to at most ``budget_s`` (at least one case). A format 2 table records no
wall times; its cases are ordered by the cost of a slide instead (the fastest velocity, then the highest pressure:
the shortest DEM run and the fewest flakes per contact patch first) and every debris level is sampled once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from tribocosim.errors import TableError

from .campaign import Case, make_case, run_case
from .sweep import parse_sweep_dict

#: values of a rerun equal to the recorded ones within this (absolute, fractions of A0)
IDENTICAL_ATOL = 1e-12
KEYS = (("a_p", "mean_particle_fraction"), ("a_p_clusters", "mean_particle_fraction_clusters"),
        ("a_c", "mean_contact_fraction"))


@dataclass(frozen=True)
class Recorded:
    """A case of a table's metadata and the one rebuilt from its sweep."""

    case: Case
    values: dict  # a_p, a_p_clusters, a_c as recorded
    wall_s: float
    spread: dict  # a_p, a_c: member std of the node


def recorded_cases(table) -> list[Recorded]:
    """Every case of ``table``'s metadata, rebuilt from its sweep (TableError if one does not rebuild to its
    recorded id)."""
    meta = table.metadata
    camp = meta.get("campaign", {})
    if "sweep" not in camp or "cases" not in meta:
        raise TableError("the table records no campaign (sweep and cases); it cannot be verified by rerunning")
    sweep = parse_sweep_dict(camp["sweep"])
    cases = meta["cases"]
    nodes: dict = {}
    for c in cases:
        lab = c["labels"]
        nodes.setdefault((lab["pressure"], lab["velocity"], lab["n_flakes"]), []).append(c)
    out = []
    for c in cases:
        lab = c["labels"]
        case = make_case(sweep, lab["surface"], lab["pressure"], lab["velocity"], lab["n_flakes"],
                         lab["flake_diameter"], lab["seed"])
        if case.case_id != c["case_id"]:
            raise TableError(f"case {c['case_id']} ({lab}) rebuilds to id {case.case_id}: the sweep recorded with "
                             "the table does not give the configuration that ran")
        members = nodes[(lab["pressure"], lab["velocity"], lab["n_flakes"])]
        spread = {k: _std([m[k] for m in members if m.get(k) is not None]) for k, _ in KEYS}
        out.append(Recorded(case, {k: c.get(k) for k, _ in KEYS}, float(c.get("wall_s") or math.inf), spread))
    return out


def _std(values) -> float:
    n = len(values)
    if n < 2:
        return 0.0
    mean = sum(values) / n
    return math.sqrt(sum((x - mean) ** 2 for x in values) / (n - 1))


def sample_cases(recorded: list[Recorded], budget_s: float) -> list[Recorded]:
    """The cheapest case of every debris level (module docstring), within ``budget_s`` of recorded wall time."""
    def cost(r: Recorded):
        return (r.wall_s, -r.case.labels["velocity"], -r.case.labels["pressure"])

    by_level: dict = {}
    for r in sorted(recorded, key=cost):
        by_level.setdefault(r.case.labels["n_flakes"], r)
    chosen, total = [], 0.0
    for r in sorted(by_level.values(), key=cost):
        if chosen and math.isfinite(r.wall_s) and total + r.wall_s > budget_s:
            break
        chosen.append(r)
        total += r.wall_s
    return chosen


def verify_cases(sample: list[Recorded], executor, pixel: float) -> list[dict]:
    """Rerun ``sample`` through ``executor`` and compare (module docstring); one result dict per case with
    ``verdict`` "identical", "within_spread" or "differs"."""
    by_id = {r.case.case_id: r for r in sample}
    results = []
    for cid, outcome in executor.map_unordered(run_case, [(cid, r.case.payload()) for cid, r in by_id.items()]):
        rec = by_id[cid]
        entry = {"case_id": cid, "labels": rec.case.labels, "recorded_wall_s": rec.wall_s}
        if isinstance(outcome, BaseException) or outcome.get("status") != "done":
            err = outcome if isinstance(outcome, BaseException) else outcome.get("error", {}).get("message")
            results.append({**entry, "verdict": "differs", "error": str(err)})
            continue
        got = {k: outcome["summary"].get(name) for k, name in KEYS}
        diffs = {k: abs(got[k] - rec.values[k]) for k, _ in KEYS if rec.values[k] is not None and got[k] is not None}
        if all(d <= IDENTICAL_ATOL for d in diffs.values()):
            verdict = "identical"
        elif all(d <= max(2.0 * rec.spread[k], pixel) for k, d in diffs.items()):
            verdict = "within_spread"
        else:
            verdict = "differs"
        results.append({**entry, "verdict": verdict, "recorded": rec.values, "rerun": got, "abs_diff": diffs,
                        "tolerance": {k: max(2.0 * rec.spread[k], pixel) for k in diffs},
                        "wall_s": outcome.get("wall_s")})
    return results
