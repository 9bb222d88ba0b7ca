"""Paraxial (first-order) optics of rotationally symmetric systems: the y–nu trace.

A system is a list of surface curvatures c (1/mm), the axial gaps between successive surfaces
(mm) and the indices n₀ (object space), n₁, …, n_k after each surface. At each surface
n′u′ = n u − y c (n′ − n); between surfaces y ← y + t u′ (paraxial angles in radians).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["ParaxialSystem", "curvature", "sag"]


def curvature(radius_mm: float) -> float:
    """c = 1/R in 1/mm; 0 for a flat surface (R = ±inf)."""
    return 0.0 if math.isinf(radius_mm) else 1.0 / radius_mm


def sag(c: float, k: float, r):
    """Sag z(r) = c r² / (1 + √(1 − (1+k) c² r²)) in mm of a conicoid with curvature c (1/mm)
    and conic constant k; NaN beyond the conicoid's extent. ``r`` may be an array.

    Examples
    --------
    >>> round(float(sag(1 / 7.8, -0.25, 6.0)), 4)
    2.6437
    """
    r = np.asarray(r, dtype=float)
    arg = 1.0 - (1.0 + k) * c * c * r * r
    with np.errstate(invalid="ignore"):
        out = c * r * r / (1.0 + np.sqrt(arg))
    return np.where(arg < 0.0, np.nan, out)


@dataclass(frozen=True)
class ParaxialSystem:
    """A rotationally symmetric system, first order.

    Attributes
    ----------
    curvatures : sequence of float
        c = 1/R of each surface (1/mm; 0 for a plane).
    gaps : sequence of float
        Axial distance from each surface to the next (mm), one fewer than surfaces.
    indices : sequence of float
        n₀ (object space) then the index after each surface.
    """

    curvatures: tuple[float, ...]
    gaps: tuple[float, ...]
    indices: tuple[float, ...]

    def trace(self, y: float, u: float) -> tuple[np.ndarray, np.ndarray]:
        """Heights y at each surface and angles u′ after it, for a ray entering at (y, u)."""
        ys, us = [], []
        n = self.indices[0]
        for j, c in enumerate(self.curvatures):
            n1 = self.indices[j + 1]
            u = (n * u - y * c * (n1 - n)) / n1
            n = n1
            ys.append(y)
            us.append(u)
            if j < len(self.gaps):
                y = y + self.gaps[j] * u
        return np.asarray(ys), np.asarray(us)

    @property
    def power(self) -> float:
        """Optical power Φ = −n_k u′_k / y₁ for a ray parallel to the axis (1/mm)."""
        ys, us = self.trace(1.0, 0.0)
        return -self.indices[-1] * us[-1] / ys[0]

    @property
    def efl(self) -> float:
        """Effective focal length n₀/Φ in object-space units (mm); 1/Φ in air."""
        return self.indices[0] / self.power

    @property
    def back_focal_distance(self) -> float:
        """Last vertex to the paraxial focus for an object at infinity (mm)."""
        ys, us = self.trace(1.0, 0.0)
        return -ys[-1] / us[-1]

    def image_distance(self, object_distance: float) -> float:
        """Last vertex to the paraxial image of an axial point ``object_distance`` before the
        first vertex (mm; positive to the right)."""
        ys, us = self.trace(object_distance * 1e-3, 1e-3)
        return -ys[-1] / us[-1]

    def magnification(self, object_distance: float) -> float:
        """Transverse magnification m = n₀u₀ / (n_k u′_k) of that conjugate (Lagrange)."""
        _, us = self.trace(object_distance * 1e-3, 1e-3)
        return self.indices[0] * 1e-3 / (self.indices[-1] * us[-1])

    def stop_semi_diameter_for_epd(self, stop: int, epd: float) -> float:
        """Semi-diameter of surface ``stop`` that gives an entrance pupil of diameter ``epd``
        for an object at infinity (the paraxial marginal ray at height epd/2)."""
        ys, _ = self.trace(epd / 2.0, 0.0)
        return abs(float(ys[stop]))

    def entrance_pupil_position(self, stop: int) -> float:
        """Distance from the first vertex to the entrance pupil, the paraxial image of surface
        ``stop`` in object space (mm, positive toward the system): where a ray aimed through the
        stop's centre crosses the axis before the first surface."""
        a = self.trace(1.0, 0.0)[0][stop]  # stop height per unit entrance height
        b = self.trace(0.0, 1.0)[0][stop]  # stop height per unit entrance angle
        return b / a

    def working_f_number(
        self, object_distance: float, stop: int, stop_semi_diameter: float
    ) -> float:
        """Paraxial working F-number 1 / (2 n_k |u′_k|) of the marginal ray from the axial object
        point that grazes the stop's rim."""
        ys, us = self.trace(object_distance * 1e-3, 1e-3)
        scale = stop_semi_diameter / abs(ys[stop])
        return 1.0 / (2.0 * self.indices[-1] * abs(us[-1]) * scale)
