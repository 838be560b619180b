"""Geometry and lumped matrices of the 1D bar under the pad (paper Sec. 3, App. B, Eq. 29-30).

The bar is the half model of the strip (one face, half the thickness). Material coordinate X runs
from the bar's free tail (X = 0) to the grip (X = L_B). The pad is fixed in space over
[a, a + L_T]; the strip is pulled towards +X, so material enters the pad at its left edge.
The bar is long enough for the whole draw: L_B = lead + draw_length + L_T + free_length with
a = lead + draw_length, so the tail never reaches the pad within draw_length (lead = 5 mm).

Linear 2-node elements of equal length l_e = L_B / n_elements. Mass is LUMPED (row sums of the
consistent mass matrix: rho A l_e per interior node, half at the ends): the explicit scheme then
needs no solve, and for the implicit scheme it keeps the system tridiagonal. The paper uses the
consistent mass; lumping changes wave dispersion at the element scale, not the friction result.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tribocosim.components.stripdraw.parameters import StripDrawParameters

LEAD_LENGTH = 0.005  # m of strip behind the material that is under the pad at the end of the draw


@dataclass(frozen=True)
class BarMesh:
    """Nodes, element size, lumped masses and stiffnesses of the half-model bar."""

    X: np.ndarray  # node positions [m], X[-1] is the grip
    element_length: float  # l_e [m]
    window_lo: float  # pad entry edge a [m]
    window_hi: float  # pad exit edge a + L_T [m]
    mass: np.ndarray  # lumped nodal masses [kg]
    element_stiffness: float  # k_e = E A / l_e [N/m]
    node_shear_stiffness: float  # k_s w_T l_e: penalty of one fully covered node [N/m]

    @classmethod
    def build(cls, p: StripDrawParameters) -> "BarMesh":
        """Mesh for the parameters ``p``."""
        length = LEAD_LENGTH + p.draw_length + p.tool_length + p.free_length
        n = p.n_elements
        le = length / n
        X = np.arange(n + 1) * le
        X[-1] = length
        m = np.full(n + 1, p.density * p.bar_area * le)
        m[0] *= 0.5
        m[-1] *= 0.5
        a = LEAD_LENGTH + p.draw_length
        return cls(
            X=X,
            element_length=le,
            window_lo=a,
            window_hi=a + p.tool_length,
            mass=m,
            element_stiffness=p.youngs_modulus * p.bar_area / le,
            node_shear_stiffness=p.shear_stiffness * p.tool_width * le,
        )

    @property
    def n_nodes(self) -> int:
        """Number of nodes."""
        return self.X.size

    def critical_time_step(self) -> float:
        """Stability limit of the explicit scheme, 2 / omega_max.

        omega_max^2 is bounded by Gershgorin's theorem: max_i (4 k_e + k_s w_T l_e) / m_i over the
        interior nodes (the end nodes give the same bound). Without the interface penalty this is
        exactly the CFL limit l_e / sqrt(E / rho).
        """
        m = self.mass[1]
        return 2.0 / math.sqrt((4.0 * self.element_stiffness + self.node_shear_stiffness) / m)
