"""Interactions at a surface: one physical law per function, unit vectors in, unit vectors out;
and :func:`interface_at`, the one place that reads a refracting interface of the surface table
(which side the ray comes from, the indices either side, its reflectance and absorptance).

A refracting interface's reflectance comes from its int column ``FRESNEL`` (of
:mod:`.geometry`), a code: :data:`R_FIXED` (0: the fixed ``REFL``), :data:`R_FRESNEL` (1: the
unpolarised Fresnel reflectance) or :data:`R_TABLE` (2: a coating's measured R(θ), linearly
interpolated in the angle of incidence θ between its nodes, stored in the float columns after
the geometry's: the node count at :data:`R_TABLE_COUNT`, the angles (rad, 0 first, π/2 last)
from :data:`R_TABLE_ANGLE`, R from :data:`R_TABLE_VALUE`, :data:`R_TABLE_NODES` at most; the
compiled table has :data:`N_FLOAT_WITH_TABLE` columns when a surface uses one, else the
geometry's ``N_FLOAT``).
"""

from __future__ import annotations

import math
from typing import NamedTuple

from numba import njit

from eyelume.kernels import geometry as G


@njit(cache=True, inline="always")
def reflect(dx, dy, dz, nx, ny, nz):
    """Specular reflection r = d − 2 (d·n) n (either orientation of the unit normal n)."""
    k = 2.0 * (dx * nx + dy * ny + dz * nz)
    return dx - k * nx, dy - k * ny, dz - k * nz


@njit(cache=True, inline="always")
def refract(dx, dy, dz, nx, ny, nz, eta):
    """Refraction by Snell's law n₁ sin θ₁ = n₂ sin θ₂, ``eta`` = n₁/n₂.

    The unit normal may face either side. Returns (ok, tx, ty, tz); ok is False on total internal
    reflection (then the direction returned is meaningless).
    """
    cos_i = -(dx * nx + dy * ny + dz * nz)
    if cos_i < 0.0:  # normal on the far side: flip it toward the incoming ray
        nx, ny, nz, cos_i = -nx, -ny, -nz, -cos_i
    sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i)
    if sin2_t > 1.0:
        return False, dx, dy, dz
    cos_t = math.sqrt(1.0 - sin2_t)
    k = eta * cos_i - cos_t
    return True, eta * dx + k * nx, eta * dy + k * ny, eta * dz + k * nz


@njit(cache=True, inline="always")
def fresnel_reflectance(cos_i, n1, n2):
    """Unpolarised Fresnel power reflectance R = (R_s + R_p)/2 at a smooth dielectric interface.

    ``cos_i`` is |cos| of the angle of incidence in medium n1. Returns 1 beyond the critical angle.
    """
    cos_i = min(abs(cos_i), 1.0)
    sin2_t = (n1 / n2) ** 2 * (1.0 - cos_i * cos_i)
    if sin2_t >= 1.0:
        return 1.0
    cos_t = math.sqrt(1.0 - sin2_t)
    rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t)
    rp = (n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i)
    return 0.5 * (rs * rs + rp * rp)


#: Codes of the ``FRESNEL`` int column: how a refracting interface's reflectance is found.
R_FIXED, R_FRESNEL, R_TABLE = 0, 1, 2
#: Largest number of nodes of an R(θ) table.
R_TABLE_NODES = 128
#: Float columns of an R(θ) table, after the geometry's.
R_TABLE_COUNT = G.N_FLOAT
R_TABLE_ANGLE = R_TABLE_COUNT + 1
R_TABLE_VALUE = R_TABLE_ANGLE + R_TABLE_NODES
N_FLOAT_WITH_TABLE = R_TABLE_VALUE + R_TABLE_NODES


@njit(cache=True, inline="always")
def table_reflectance(sf, s, cos_i):
    """R(θ) of surface ``s``'s table at θ = acos |cos_i|: linear between the two nodes that
    bracket θ (the nodes span 0 … π/2, so every θ is bracketed)."""
    theta = math.acos(min(abs(cos_i), 1.0))
    n = int(sf[s, R_TABLE_COUNT])
    for j in range(1, n):
        a1 = sf[s, R_TABLE_ANGLE + j]
        if theta <= a1 or j == n - 1:
            a0 = sf[s, R_TABLE_ANGLE + j - 1]
            r0 = sf[s, R_TABLE_VALUE + j - 1]
            r1 = sf[s, R_TABLE_VALUE + j]
            w = min(max((theta - a0) / (a1 - a0), 0.0), 1.0)
            return r0 + w * (r1 - r0)
    return sf[s, R_TABLE_VALUE]


class Interface(NamedTuple):
    """A refracting interface as a ray arriving at it sees it: indices n₁ (its side) and n₂ (the
    far side), reflectance R (Fresnel or the surface's fixed value) and absorptance A; the rest,
    T = 1 − R − A, is transmitted."""

    n1: float
    n2: float
    reflectance: float
    absorptance: float


@njit(cache=True, inline="always")
def interface_at(sf, si, s, cos_d):
    """The interface of surface ``s`` for a ray with cos_d = d · n (n the normal toward side B):
    it arrives from side B when cos_d < 0, else from side A. R by the surface's FRESNEL code:
    the unpolarised Fresnel reflectance at |cos_d| (R_FRESNEL), its R(θ) table at the angle of
    incidence (R_TABLE, :func:`table_reflectance`), else its fixed REFL."""
    from_b = cos_d < 0.0
    n1 = sf[s, G.N_B] if from_b else sf[s, G.N_A]
    n2 = sf[s, G.N_A] if from_b else sf[s, G.N_B]
    mode = si[s, G.FRESNEL]
    if mode == R_FRESNEL:
        r = fresnel_reflectance(cos_d, n1, n2)
    elif mode == R_TABLE:
        r = table_reflectance(sf, s, cos_d)
    else:
        r = sf[s, G.REFL]
    return Interface(n1, n2, r, sf[s, G.ABSORB])
