"""The neutral form of the friction law: one self-describing JSON file for in-house converters.

Layout (``format`` ``tribocosim-friction-export``, ``format_version`` 1):

===================  =====================================================================================
key                  value
===================  =====================================================================================
``role``             ``nominal``, or ``upper`` / ``lower`` (a band's file)
``axes``             list of ``{"name", "unit", "values"}``: ``pressure``, ``velocity`` (the relative sliding
                     velocity) and, without a debris state, ``beta``; increasing
``mu``               nested lists, one level per axis in that order (``mu[i][j]`` or ``mu[i][j][k]``)
``mu_se``            the ensemble standard error of mu at every node (same shape; null for a table without
                     standard errors)
``simulated``        at every node: true when tribocosim's lookup there reads only table nodes the mesoscale
                     campaign simulated
``table_node``       at every node: true when it is a node of the source table (its values exactly)
``interpolation``    ``rule`` (how the values are meant to be read), ``beyond`` (outside the axes), ``accuracy``
                     (the largest relative deviation of that reading from tribocosim's mu), ``tolerance``,
                     ``checked_points``
``debris_state``     the beta of the file and how it was chosen (``beta`` null with a beta axis)
``units``            the unit system and the unit of every quantity
``provenance``       the table (path, content hash), the calibration, every strip-draw parameter, the code version,
                     the command
``band``             the band's K and definition (a band's files), else null
``warnings``         list of strings
``header``           the header lines the other formats carry as comments
===================  =====================================================================================
"""

from __future__ import annotations

import json

import numpy as np

FORMAT = "tribocosim-friction-export"
FORMAT_VERSION = 1
SUFFIX = ".json"
RULE = ("multilinear: linear in each axis between its values (in pressure and velocity as written, not in their "
        "logarithms)")
BEYOND = "each axis holds its end values beyond them (clamped), as the FE codes do"


def _nested(a) -> list:
    return np.asarray(a).tolist()


def render(*, role: str, axes: list[dict], mu: np.ndarray, mu_se: np.ndarray | None, simulated: np.ndarray,
           table_node: np.ndarray, accuracy: float, tolerance: float, checked: int, debris_state: dict, units,
           provenance: dict, band: dict | None, warnings: list[str], header: list[str]) -> str:
    """The JSON text of one file (module docstring)."""
    doc = {
        "format": FORMAT, "format_version": FORMAT_VERSION, "role": role,
        "axes": axes,
        "mu": _nested(mu),
        "mu_se": None if mu_se is None else _nested(mu_se),
        "simulated": _nested(np.asarray(simulated, dtype=bool)),
        "table_node": _nested(np.asarray(table_node, dtype=bool)),
        "interpolation": {"rule": RULE, "beyond": BEYOND, "accuracy": accuracy, "tolerance": tolerance,
                          "checked_points": checked},
        "debris_state": debris_state,
        "units": {"system": units.name, "description": units.description, "pressure": units.pressure,
                  "velocity": units.velocity, "mu": "1", "beta": "1"},
        "provenance": provenance,
        "band": band,
        "warnings": list(warnings),
        "header": list(header),
    }
    return json.dumps(doc, indent=1, allow_nan=False) + "\n"
