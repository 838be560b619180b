"""Reproduce a friction table from its recorded cases: rerun a sample of them and compare.

A table built by :func:`tribocosim.surrogate.table_build.build_table` records its sweep and every finished case
(labels and results). :func:`sample_cases` rebuilds a sample of those cases from the sweep
(:func:`tribocosim.surrogate.campaign.make_case`; the rebuilt case id must equal the recorded one, so the
configuration is the one that ran) and :func:`verify_cases` reruns them and compares <A_p>/A0, A_p of the
cluster rule and <A_c>/A0 with the recorded values. How depends on the code that reran the case:

- the same mesoscale code as the table's cases (the rerun's ``source_digest`` is the table's one
  ``case_source_digests``) on the same numerics (the rerun's ``numerics`` is the table's one ``case_numerics``: the
  processor the JIT compiles for, numpy, numba, pyFFTW; :func:`tribocosim.surrogate.campaign.numerics`): a slide is
  deterministic, so the rerun must be bit-identical (verdict ``identical``); any difference is ``differs``. The FFT
  plans are part of that determinism: FFTW measures its plans in every process, and two plans of one size may round
  differently in the last bit, which the DEM can carry to another trajectory. A campaign and its check on one FFTW
  wisdom file (``TRIBOCOSIM_FFTW_WISDOM``) use the same plans;
- another version of the mesoscale code, other numerics (another processor, another build of the numerical
  libraries), or a table that does not record one version and one set of numerics for its cases: the rerun may
  round differently and follow another trajectory of the same ensemble.
  Equal values are ``identical``; otherwise each value x (recorded x_r, rerun x_n) must satisfy
  ``|x_n - x_r| <= max(1 pixel, min(SPREAD_FACTOR sigma, REL_CAP min(|x_r|, |x_n|)))`` (verdict
  ``within_tolerance``), where sigma is the member standard deviation of the node's *other* members (the recorded
  value left out, so that a wrong value does not widen its own tolerance) or, with fewer than two others, the
  table's pooled relative member standard deviation (rms over the nodes with at least three members) times the
  others' mean. The cap REL_CAP = 0.5 keeps a value off by a factor of 2 or more out of any tolerance. The
  report says which code computed the cases and which reran them;
- anything else fails (``differs``).

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

#: a rerun by another code version lies within this many member standard deviations of its node's other members
SPREAD_FACTOR = 2.0
#: ... and at most this fraction of the smaller of the recorded and the rerun value (module docstring)
REL_CAP = 0.5
KEYS = (("a_p", "mean_particle_fraction"), ("a_p_clusters", "mean_particle_fraction_clusters"),
        ("a_c", "mean_contact_fraction"))


@dataclass(frozen=True)
class Recorded:
    """A case of a table's metadata and the one rebuilt from its sweep."""

    case: Case
    values: dict  # a_p, a_p_clusters, a_c as recorded
    wall_s: float
    sigma: dict  # a_p, a_p_clusters, a_c: member std of the node without this case (module docstring)


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
    pooled = {k: _pooled_relative_std([[m[k] for m in mem if m.get(k) is not None] for mem in nodes.values()])
              for k, _ in KEYS}
    out = []
    for c in cases:
        lab = c["labels"]
        case = make_case(sweep, lab["surface"], lab["pressure"], lab["velocity"], lab["n_flakes"],
                         lab["flake_diameter"], lab["seed"])
        if case.case_id != c["case_id"]:
            raise TableError(f"case {c['case_id']} ({lab}) rebuilds to id {case.case_id}: the sweep recorded with "
                             "the table does not give the configuration that ran")
        others = [m for m in nodes[(lab["pressure"], lab["velocity"], lab["n_flakes"])] if m is not c]
        sigma = {k: _sigma([m[k] for m in others if m.get(k) is not None], pooled[k]) for k, _ in KEYS}
        out.append(Recorded(case, {k: c.get(k) for k, _ in KEYS}, float(c.get("wall_s") or math.inf), sigma))
    return out


def _std(values) -> float:
    n = len(values)
    if n < 2:
        return 0.0
    mean = sum(values) / n
    return math.sqrt(sum((x - mean) ** 2 for x in values) / (n - 1))


def _pooled_relative_std(groups) -> float:
    """rms of std/mean over the groups with at least three values and a positive mean (0 if none)."""
    rel = [_std(g) / (sum(g) / len(g)) for g in groups if len(g) >= 3 and sum(g) > 0]
    return math.sqrt(sum(r * r for r in rel) / len(rel)) if rel else 0.0


def _sigma(others, pooled_rel: float) -> float:
    """The member std of a node estimated without the case itself (module docstring)."""
    if len(others) >= 2:
        return _std(others)
    return pooled_rel * abs(sum(others) / len(others)) if others else 0.0


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


def code_versions(table) -> list[str]:
    """The mesoscale code versions (source digests) that computed the table's cases, as the table records them."""
    return list(table.metadata.get("case_source_digests") or [])


def numerics_of(table) -> list[str]:
    """The numerics (:func:`tribocosim.surrogate.campaign.numerics`) of the table's cases, as the table records them."""
    return list(table.metadata.get("case_numerics") or [])


def verify_cases(sample: list[Recorded], executor, pixel: float, recorded_versions: list[str],
                 recorded_numerics: list[str] | None = None) -> list[dict]:
    """Rerun ``sample`` through ``executor`` and compare (module docstring); one result dict per case with
    ``verdict`` "identical", "within_tolerance" or "differs", the ``mode`` of the comparison ("exact" or
    "tolerance") and its ``reason``."""
    by_id = {r.case.case_id: r for r in sample}
    results = []
    for cid, outcome in executor.map_unordered(run_case, [(cid, r.case.payload()) for cid, r in by_id.items()]):
        rec = by_id[cid]
        entry = {"case_id": cid, "labels": rec.case.labels, "recorded_wall_s": rec.wall_s}
        if isinstance(outcome, BaseException) or outcome.get("status") != "done":
            err = outcome if isinstance(outcome, BaseException) else outcome.get("error", {}).get("message")
            results.append({**entry, "verdict": "differs", "error": str(err)})
            continue
        rerun_by = outcome.get("source_digest", "unknown")
        mode, reason = comparison(recorded_versions, rerun_by, recorded_numerics or [],
                                  outcome.get("numerics", "unknown"))
        got = {k: outcome["summary"].get(name) for k, name in KEYS}
        keys = [k for k, _ in KEYS if rec.values[k] is not None and got[k] is not None]
        diffs = {k: abs(got[k] - rec.values[k]) for k in keys}
        tolerance = {k: 0.0 if mode == "exact" else tolerance_of(rec.values[k], got[k], rec.sigma[k], pixel)
                     for k in keys}
        if all(got[k] == rec.values[k] for k in keys):
            verdict = "identical"
        elif mode == "tolerance" and all(diffs[k] <= tolerance[k] for k in keys):
            verdict = "within_tolerance"
        else:
            verdict = "differs"
        results.append({**entry, "verdict": verdict, "mode": mode, "reason": reason, "rerun_source_digest": rerun_by,
                        "recorded": rec.values, "rerun": got, "abs_diff": diffs, "tolerance": tolerance,
                        "wall_s": outcome.get("wall_s")})
    return results


def tolerance_of(recorded: float, rerun: float, sigma: float, pixel: float) -> float:
    """The tolerance of a rerun by another code version (module docstring)."""
    return max(pixel, min(SPREAD_FACTOR * sigma, REL_CAP * min(abs(recorded), abs(rerun))))


def comparison(recorded_versions: list[str], rerun_by: str, recorded_numerics: list[str] | None = None,
               rerun_numerics: str = "unknown") -> tuple[str, str]:
    """("exact" or "tolerance", why) for a rerun by code ``rerun_by`` on ``rerun_numerics`` of cases computed by
    ``recorded_versions`` on ``recorded_numerics``."""
    same_numerics = recorded_numerics == [rerun_numerics] and rerun_numerics != "unknown"
    if recorded_versions == [rerun_by] and same_numerics:
        return "exact", (f"the same mesoscale code ({rerun_by}) on the same numerics ({rerun_numerics}) computed the "
                         "recorded case: a rerun on the same FFT plans is bit-identical")
    if recorded_versions == [rerun_by]:
        recorded = ("are not recorded" if not recorded_numerics or recorded_numerics == ["unknown"]
                    else f"were {'; '.join(recorded_numerics)}")
        return "tolerance", (f"the same mesoscale code ({rerun_by}) computed the recorded cases, but their numerics "
                             f"{recorded} and this rerun's are {rerun_numerics}: another processor or build of the "
                             f"numerical libraries may round differently and follow another trajectory of the node's "
                             f"ensemble, so each value may differ by {SPREAD_FACTOR:g} member standard deviations of "
                             f"the node without the case, at most {REL_CAP:g} of the smaller value and at least one "
                             "contact pixel")
    if not recorded_versions:
        which = "a version of the mesoscale code the table does not record"
    elif len(recorded_versions) == 1:
        which = f"mesoscale code {recorded_versions[0]}"
    else:
        which = (f"{len(recorded_versions)} versions of the mesoscale code ({', '.join(recorded_versions)}; which "
                 "one computed this case is not recorded)")
    return "tolerance", (f"the recorded cases were computed by {which} and this rerun by {rerun_by}: another version "
                         f"may round differently and follow another trajectory of the node's ensemble, so each value "
                         f"may differ by {SPREAD_FACTOR:g} member standard deviations of the node without the case, at "
                         f"most {REL_CAP:g} of the smaller value and at least one contact pixel")
