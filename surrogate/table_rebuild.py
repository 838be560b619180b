"""A friction table rebuilt from the cases it records, and how far a rebuild may move each of its values.

:func:`rebuild_from_metadata` makes the table :func:`~tribocosim.surrogate.table_build.build_table` makes from the
cases a version 3 or 4 table records, with its recorded sweep and surface statistics: what the table was built from,
without the campaign folder.

A rebuild on another processor, or with another build of numpy, scipy or LAPACK, computes the same arithmetic in
another order and stops an iterative fit at another iterate. :func:`rebuild_tolerance` bounds what that may move at
every node, from the build itself:

- the project's arithmetic on the ensemble (means and standard deviations of m members, mu = mu0 (1 - A_p / A_c)): at
  most 16 max(m, 2) eps of each value (a sum of m rounded terms is within (m - 1) eps of its value; the factor covers
  the standard deviation's squares, the division and the share's amplification in mu, mu0 A_p / A_c);
- a node a row's fit fills: the fit's parameters may lie anywhere the fit's computation may leave them from the
  optimum of its data (:func:`tribocosim.surrogate.fit.parameter_shift`: the closed-form sums' round-off, the
  condition of the affine fit's normal equations, the tests that stop the langmuir fit), for two rebuilds twice that;
  the node's values are recomputed by the build's own code (``_Row.node``) with each parameter moved by that shift
  either way, and the largest change of each value, summed over the parameters (first order), is its tolerance.

Held nodes (a row whose fits do not all pass) hold a simulated node's values and have its tolerance.
:func:`rebuild_differences` lists the values of a rebuild that leave it.
"""

from __future__ import annotations

import numpy as np

from tribocosim.components.stripdraw.table import FrictionTable, mu_of_areas

from .fit import ensemble, parameter_shift, with_params
from .table_build import FILLED, Grid, build_table

#: the arrays of a table that a rebuild makes (the axes are compared exactly)
ARRAYS = ("mu", "contact_area", "particle_area", "contact_area_std", "particle_area_std", "simulated",
          "contact_area_se", "particle_area_se", "particle_area_clusters", "particle_area_clusters_se", "mu_se")
#: a rebuild makes two computations of a fit, each within the shift of the optimum
REBUILDS = 2.0
#: the round-off of the ensemble arithmetic per member (module docstring)
ROUNDOFF_PER_MEMBER = 16.0


def _records(metadata: dict, cases: list[dict] | None = None) -> tuple[list[dict], dict]:
    cases = metadata["cases"] if cases is None else cases
    # the code that computed the cases: known per case only when the table records one version for all of them
    digests, versions = metadata.get("case_source_digests") or [], metadata.get("case_code_versions") or []
    origin = {}
    if len(digests) == 1:
        origin["source_digest"] = digests[0]
    if len(versions) == 1:
        origin["code_version"] = versions[0]
    if len(metadata.get("case_numerics") or []) == 1:
        origin["numerics"] = metadata["case_numerics"][0]
    records = [{"case_id": c["case_id"], "labels": c["labels"], "wall_s": c.get("wall_s", 0.0), **origin,
                "summary": {"mean_particle_fraction": c["a_p"], "mean_contact_fraction": c["a_c"],
                            "mean_particle_fraction_clusters": c.get("a_p_clusters") or 0.0}} for c in cases]
    manifest = {"sweep": metadata["campaign"]["sweep"],
                "cases": [{"case_id": c["case_id"], "labels": c["labels"]} for c in cases]}
    return records, manifest


def rebuild_from_metadata(metadata: dict, cases: list[dict] | None = None) -> FrictionTable:
    """The table :func:`build_table` makes from the cases a version 3 or 4 table records (``metadata["cases"]``, or the
    subset ``cases`` of them) with its recorded sweep and surface statistics."""
    records, manifest = _records(metadata, cases)
    built = {"sweep", "cases_total", "cases_finished", "cases_failed", "case_cpu_seconds"}
    info = {k: v for k, v in metadata["campaign"].items() if k not in built}  # the executor's, as recorded
    table, _ = build_table(records, manifest, surface_stats=metadata["surfaces"], campaign_info=info)
    return table


def _values(node: dict, mu0: float) -> dict:
    out = {name: float(node[name]) for name in ARRAYS if name != "mu"}
    out["mu"] = float(mu_of_areas(mu0, np.array(node["particle_area"]), np.array(node["contact_area"])))
    return out


def rebuild_tolerance(metadata: dict) -> dict[str, np.ndarray]:
    """Per array of :data:`ARRAYS`, the largest difference a rebuild of the table from its recorded cases may make at
    each node (module docstring), in the array's units and layout."""
    records, manifest = _records(metadata)
    grid = Grid.of(manifest["sweep"])
    rows = grid.rows(ensemble(records))
    shape = (len(grid.pressures), len(grid.vel_axis), len(grid.beta_axis))
    tol = {name: np.zeros(shape) for name in ARRAYS}
    eps = np.finfo(float).eps
    for i, p in enumerate(grid.pressures):
        for j, v in enumerate(grid.vel_axis):
            row = rows[grid.row_key(p, v)]
            for k, b in enumerate(grid.beta_axis):
                node = row.node(b, grid.mu0)
                base = _values(node, grid.mu0)
                members = max(max((q.n for q in row.points.values() if q is not None), default=1), 2)
                for name, x in base.items():
                    tol[name][i, j, k] = ROUNDOFF_PER_MEMBER * members * eps * abs(x)
                tol["mu"][i, j, k] += (ROUNDOFF_PER_MEMBER * members * eps * grid.mu0 * base["particle_area"]
                                       / base["contact_area"] if base["contact_area"] > 0 else 0.0)
                if node["simulated"] == 1.0:
                    continue
                for name in FILLED:
                    fit = row.fill[name]
                    if fit is None:
                        continue
                    levels, sigma = row.fit_data[name]
                    shift = REBUILDS * parameter_shift(fit, levels, sigma)
                    for m, dp in enumerate(shift):
                        change = {key: 0.0 for key in base}
                        for sign in (-1.0, 1.0):
                            params = np.array(fit.params, float)
                            params[m] += sign * dp
                            moved = _values(row.node(b, grid.mu0, {**row.fill, name: with_params(
                                fit, levels, sigma, params)}), grid.mu0)
                            for key in base:
                                change[key] = max(change[key], abs(moved[key] - base[key]))
                        for key, c in change.items():
                            tol[key][i, j, k] += c
    return tol


def rebuild_differences(rebuilt: FrictionTable, table: FrictionTable, tolerance: dict) -> list[str]:
    """The values of ``rebuilt`` that differ from ``table``'s by more than ``tolerance`` (:func:`rebuild_tolerance`),
    and axes that differ at all: one line each (empty when the rebuild is the table)."""
    out = []
    for name in ("pressure", "velocity", "beta"):
        if not np.array_equal(getattr(rebuilt, name), getattr(table, name)):
            out.append(f"the {name} axis differs")
    if out:
        return out
    for name in ARRAYS:
        diff = np.abs(rebuilt.array(name) - table.array(name))
        for idx in zip(*np.nonzero(~(diff <= tolerance[name]))):
            i, j, k = (int(x) for x in idx)
            out.append(f"{name} at P = {table.pressure[i]:g} Pa, v = {table.velocity[j]:g} m/s, beta = "
                       f"{table.beta[k]:g}: {rebuilt.array(name)[idx]!r} against {table.array(name)[idx]!r} "
                       f"(difference {diff[idx]:.3g}, tolerance {tolerance[name][idx]:.3g})")
    return out
