"""A flake as a rigid body: its shape and mass (:class:`FlakeShape`), its orientation (unit quaternions and their
rotation matrices) and the damping of its motion by the oil it moves in (:class:`DampingRates`, the Stokes drag of a
thin disc; the equations and their validity are in the module docstring of :mod:`tribocosim.surrogate.dem`).

Shared by the DEM (:mod:`tribocosim.surrogate.dem`), the flake geometry on the grid (:mod:`tribocosim.surrogate.flakes`)
and the slide configuration (:mod:`tribocosim.surrogate.slide_config`); it imports none of them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tribocosim.errors import ParameterError, check_range

#: dynamic viscosity [Pa s] of the oil when neither oil_viscosity nor damping_rate is given: ISO 3448
#: grade VG 32 (32 mm^2/s at 40 C) x a mineral-oil density of 870 kg/m^3 (surrogate.dem docstring)
DEFAULT_OIL_VISCOSITY = 32e-6 * 870.0
#: Stokes resistance coefficients of a thin disc (module docstring): force / (eta a v) broadside and
#: edgewise, torque / (eta a^3 omega) about a diameter and about the axis
DISC_BROADSIDE = 16.0
DISC_EDGEWISE = 32.0 / 3.0
DISC_ROTATION = 32.0 / 3.0
#: reference dynamic viscosity [Pa s]: ISO 3448 VG 32 (32 mm^2/s at 40 C) x 870 kg/m^3
VG32_VISCOSITY_40C = DEFAULT_OIL_VISCOSITY


@dataclass(frozen=True)
class FlakeShape:
    """Shape and material of the (identical) flakes.

    Attributes
    ----------
    diameter : float
        In-plane diameter d_p [m].
    thickness : float
        Thickness h_p [m], smaller than the diameter.
    density : float
        Mass density [kg/m^3] (Al: 2700).
    """

    diameter: float = 12e-6
    thickness: float = 0.5e-6
    density: float = 2700.0

    def __post_init__(self):
        check_range("flake diameter d_p", self.diameter, 0.0, None, low_inclusive=False, unit="m")
        check_range("flake thickness h_p", self.thickness, 0.0, self.diameter,
                    low_inclusive=False, high_inclusive=False, unit="m")
        check_range("flake density", self.density, 0.0, None, low_inclusive=False, unit="kg/m^3")

    @property
    def a(self) -> float:
        """In-plane semi-axis [m]."""
        return 0.5 * self.diameter

    @property
    def c(self) -> float:
        """Half-thickness [m]."""
        return 0.5 * self.thickness

    @property
    def area(self) -> float:
        """Cross-section area a_p = pi a^2 [m^2]."""
        return math.pi * self.a**2

    @property
    def mass(self) -> float:
        """Mass [kg]."""
        return self.density * 4.0 / 3.0 * math.pi * self.a**2 * self.c

    @property
    def inertia(self) -> tuple[float, float]:
        """Principal moments (I1 = I2 in-plane axes, I3 symmetry axis) [kg m^2]."""
        m = self.mass
        return m * (self.a**2 + self.c**2) / 5.0, 2.0 * m * self.a**2 / 5.0


@dataclass(frozen=True)
class DampingRates:
    """Damping rates [1/s] of a flake in its principal axes (the module docstring of :mod:`tribocosim.surrogate.dem`).

    Attributes
    ----------
    velocity_plane, velocity_axial : float
        Rates of the velocity components in the flake's plane and along its symmetry axis.
    angmom_diameter, angmom_axis : float
        Rates of the angular-momentum components about a diameter and about the symmetry axis.
    """

    velocity_plane: float
    velocity_axial: float
    angmom_diameter: float
    angmom_axis: float

    def __post_init__(self):
        for name in ("velocity_plane", "velocity_axial", "angmom_diameter", "angmom_axis"):
            check_nonnegative(f"damping rate {name}", getattr(self, name), "1/s")

    @classmethod
    def uniform(cls, gamma: float) -> "DampingRates":
        """One rate for every component (the integrator of Eq. 15-16 with one gamma)."""
        check_nonnegative("damping rate gamma", gamma, "1/s")
        return cls(gamma, gamma, gamma, gamma)

    @classmethod
    def from_viscosity(cls, shape: FlakeShape, viscosity: float) -> "DampingRates":
        """Stokes drag of a thin disc of radius a = d_p/2 in an oil of dynamic viscosity ``viscosity``
        [Pa s] (the module docstring of :mod:`tribocosim.surrogate.dem`: formulas, validity, reference values)."""
        eta = check_nonnegative("oil viscosity eta", viscosity, "Pa s")
        a, m = shape.a, shape.mass
        i1, i3 = shape.inertia
        return cls(DISC_EDGEWISE * eta * a / m, DISC_BROADSIDE * eta * a / m,
                   DISC_ROTATION * eta * a**3 / i1, DISC_ROTATION * eta * a**3 / i3)

    @property
    def is_uniform(self) -> bool:
        """True when all four rates are equal (the one-rate integrator)."""
        return self.velocity_plane == self.velocity_axial == self.angmom_diameter == self.angmom_axis

    def as_tuple(self) -> tuple[float, float, float, float]:
        """(velocity_plane, velocity_axial, angmom_diameter, angmom_axis), the kernel's order."""
        return (float(self.velocity_plane), float(self.velocity_axial), float(self.angmom_diameter),
                float(self.angmom_axis))


def check_nonnegative(name: str, value, unit: str) -> float:
    """A finite number >= 0, or ``ParameterError`` naming the quantity, the value and the range."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise ParameterError(f"{name} = {value!r} is not a number; allowed: a finite number in "
                             f"[0, inf) {unit}")
    return check_range(name, value, 0.0, None, unit=unit)


def rotation_matrices(quat) -> np.ndarray:
    """Rotation matrices (nf, 3, 3), body -> space, of unit quaternions (w, x, y, z)."""
    q = np.asarray(quat, dtype=np.float64).reshape(-1, 4)
    w, x, y, z = q.T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], axis=1)


def axis_angle_quaternion(axis, angle) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation by ``angle`` [rad] about ``axis``."""
    u = np.asarray(axis, dtype=np.float64)
    u = u / np.linalg.norm(u)
    return np.concatenate([[math.cos(0.5 * angle)], math.sin(0.5 * angle) * u])
