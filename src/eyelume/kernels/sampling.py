"""Samplers, each with its probability density, and the one evaluator of an LED's I(α).

Every sampler maps uniforms u ∈ [0, 1)ᵏ to a point or a direction and has a ``*_pdf`` beside it
(per steradian for directions, per mm² for points), as Mitsuba's ``warp::square_to_X`` /
``square_to_X_pdf`` pairs; ``tests/kernels/test_samplers.py`` checks every pair with the one χ²
harness of ``tests/kernels/chi2.py``. The estimators draw the uniforms (:mod:`.rng`) and weight
by the pdf.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from eyelume.kernels.tables import A_AX, A_AY, A_AZ, A_KIND, A_P, A_R, A_X, A_Y, A_Z, AIM_DISK

_INV_PI = 1.0 / math.pi


@njit(cache=True, inline="always")
def orthonormal_basis(nx, ny, nz):
    """Two unit vectors completing unit n to a right-handed basis (t, b, n).

    Branchless construction of Duff et al., JCGT 6(1), 2017.
    """
    sign = math.copysign(1.0, nz)
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    return (1.0 + sign * nx * nx * a, sign * b, -sign * nx), (b, sign + ny * ny * a, -ny)


@njit(cache=True, inline="always")
def cosine_hemisphere(u1, u2):
    """Cosine-weighted direction about +z (local): pdf(ω) = cos θ / π (Malley's method)."""
    r = math.sqrt(u1)
    phi = 2.0 * math.pi * u2
    return r * math.cos(phi), r * math.sin(phi), math.sqrt(max(0.0, 1.0 - u1))


@njit(cache=True, inline="always")
def cosine_hemisphere_pdf(cos_theta):
    """Density per steradian of :func:`cosine_hemisphere` at polar cosine ``cos_theta``."""
    return cos_theta / math.pi if cos_theta > 0.0 else 0.0


@njit(cache=True, inline="always")
def about_axis(lx, ly, lz, ax, ay, az):
    """Rotate a local direction (about +z) into the frame whose z axis is unit (ax, ay, az)."""
    t, b = orthonormal_basis(ax, ay, az)
    return (
        lx * t[0] + ly * b[0] + lz * ax,
        lx * t[1] + ly * b[1] + lz * ay,
        lx * t[2] + ly * b[2] + lz * az,
    )


@njit(cache=True, inline="always")
def profile_polar_angle(u, alpha_grid, cdf_grid):
    """Polar angle α (rad) from an LED axis, drawn with density ∝ I(α) sin α.

    ``cdf_grid`` is the normalised cumulative ∫₀^α I sin α' dα' on ``alpha_grid`` (increasing,
    cdf 0 → 1); the inverse is linear within each grid cell.
    """
    n = cdf_grid.shape[0]
    lo = 0
    hi = n - 1
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        if cdf_grid[mid] <= u:
            lo = mid
        else:
            hi = mid
    span = cdf_grid[hi] - cdf_grid[lo]
    f = (u - cdf_grid[lo]) / span if span > 0.0 else 0.0
    return alpha_grid[lo] + f * (alpha_grid[hi] - alpha_grid[lo])


@njit(cache=True, inline="always")
def uniform_cone(u1, u2, cos_max):
    """Direction uniform in the cone of half-angle acos(cos_max) about +z (local):
    pdf(ω) = 1 / (2π (1 − cos_max))."""
    ct = 1.0 - u1 * (1.0 - cos_max)
    st = math.sqrt(max(0.0, 1.0 - ct * ct))
    phi = 2.0 * math.pi * u2
    return st * math.cos(phi), st * math.sin(phi), ct


@njit(cache=True, inline="always")
def uniform_cone_pdf(cos_theta, cos_max):
    """Density per steradian of :func:`uniform_cone` at polar cosine ``cos_theta``."""
    return 1.0 / (2.0 * math.pi * (1.0 - cos_max)) if cos_theta >= cos_max else 0.0


@njit(cache=True, inline="always")
def uniform_disk(u1, u2, radius):
    """Point uniform on the disk of ``radius`` about the origin (x, y): pdf = 1 / (π r²)."""
    r = radius * math.sqrt(u1)
    phi = 2.0 * math.pi * u2
    return r * math.cos(phi), r * math.sin(phi)


@njit(cache=True, inline="always")
def uniform_disk_pdf(x, y, radius):
    """Density per mm² of :func:`uniform_disk` (and of :func:`disk_stratum` over its strata)."""
    return 1.0 / (math.pi * radius * radius) if x * x + y * y <= radius * radius else 0.0


@njit(cache=True, inline="always")
def disk_stratum(k, grid, u1, u2, radius):
    """Point uniform in stratum ``k`` of the disk's ``grid`` equal-area rings × ``grid`` equal
    sectors (k // grid the ring, k % grid the sector). Over k uniform in [0, grid²) its density
    is :func:`uniform_disk_pdf`."""
    r = radius * math.sqrt((k // grid + u1) / grid)
    phi = 2.0 * math.pi * (k % grid + u2) / grid
    return r * math.cos(phi), r * math.sin(phi)


@njit(cache=True, inline="always")
def aimed_disk_pdf(aim_row, x, y, z, dx, dy, dz):
    """Density per steradian, at direction d from (x, y, z), of aiming at a uniform point of the
    disk ``aim_row`` (centre A_X, A_Y, A_Z, radius A_R, normal world +z; columns in
    :mod:`.tables`): dA cos / t² ⇒ p = t² / (π r² |d_z|). 0 off the disk or below it."""
    if aim_row[A_P] <= 0.0 or dz <= 0.0:
        return 0.0
    t = (aim_row[A_Z] - z) / dz
    hx = x + t * dx - aim_row[A_X]
    hy = y + t * dy - aim_row[A_Y]
    rr = aim_row[A_R] * aim_row[A_R]
    if hx * hx + hy * hy > rr:
        return 0.0
    return t * t / (math.pi * rr * dz)


@njit(cache=True, inline="always")
def image_cone(aim_row, x, y, z):
    """The cone :func:`aimed_mixture` draws from for an ``AIM_IMAGE`` row, seen from P = (x, y,
    z): (wx, wy, wz, cos_max), w its unit axis, cos_max = √(1 − r²/|C − P|²) (−1, the whole
    sphere, when P is within r of C). The camera's rays that leave the elements along the
    row's axis a all pass through the pupil's image C (paraxially), so the light from P that
    reaches the pupil runs along the line CP: toward C when C lies behind P on the camera's
    rays ((C − P) · a ≤ 0: a virtual image, or a real one the rays crossed before P), away
    from C when they reach P first and converge at C beyond it."""
    vx, vy, vz = aim_row[A_X] - x, aim_row[A_Y] - y, aim_row[A_Z] - z
    dist = math.sqrt(vx * vx + vy * vy + vz * vz)
    r = aim_row[A_R]
    if dist <= r:
        return 0.0, 0.0, 1.0, -1.0
    s = 1.0 / dist
    if vx * aim_row[A_AX] + vy * aim_row[A_AY] + vz * aim_row[A_AZ] > 0.0:
        s = -s
    return vx * s, vy * s, vz * s, math.sqrt(1.0 - r * r / (dist * dist))


@njit(cache=True, inline="always")
def aimed_pdf(aim_row, x, y, z, dx, dy, dz):
    """Density per steradian of the aimed part of :func:`aimed_mixture` at unit direction d:
    :func:`aimed_disk_pdf` for an ``AIM_DISK`` row, else uniform in :func:`image_cone`."""
    if aim_row[A_KIND] == AIM_DISK:
        return aimed_disk_pdf(aim_row, x, y, z, dx, dy, dz)
    if aim_row[A_P] <= 0.0:
        return 0.0
    wx, wy, wz, cos_max = image_cone(aim_row, x, y, z)
    return uniform_cone_pdf(dx * wx + dy * wy + dz * wz, cos_max)


@njit(cache=True, inline="always")
def aimed_mixture(u0, u1, u2, aim_row, x, y, z, nx, ny, nz):
    """Direction from (x, y, z) drawn from the defensive mixture: with probability p =
    aim_row[A_P] toward a uniform point of the aim disk (``AIM_DISK``) or uniformly in the
    cone of the pupil's image (``AIM_IMAGE``, :func:`image_cone`), else cosine-weighted about
    unit n. Density :func:`aimed_mixture_pdf`."""
    if u0 < aim_row[A_P] and aim_row[A_KIND] != AIM_DISK:
        wx, wy, wz, cos_max = image_cone(aim_row, x, y, z)
        lx, ly, lz = uniform_cone(u1, u2, cos_max)
        return about_axis(lx, ly, lz, wx, wy, wz)
    if u0 < aim_row[A_P]:
        r = aim_row[A_R] * math.sqrt(u1)
        phi = 2.0 * math.pi * u2
        vx = aim_row[A_X] + r * math.cos(phi) - x
        vy = aim_row[A_Y] + r * math.sin(phi) - y
        vz = aim_row[A_Z] - z
        inv = math.copysign(1.0, vz) / math.sqrt(vx * vx + vy * vy + vz * vz)
        return vx * inv, vy * inv, vz * inv
    lx, ly, lz = cosine_hemisphere(u1, u2)
    return about_axis(lx, ly, lz, nx, ny, nz)


@njit(cache=True, inline="always")
def aimed_mixture_pdf(aim_row, x, y, z, nx, ny, nz, dx, dy, dz):
    """Density per steradian of :func:`aimed_mixture`: (1 − p) cos θ/π + p · aimed_disk_pdf
    (0 below the face, where the cosine part vanishes and the weight is 0 anyway)."""
    cos_n = dx * nx + dy * ny + dz * nz
    if cos_n <= 0.0:
        return 0.0
    p = aim_row[A_P]
    return (1.0 - p) * cos_n * _INV_PI + p * aimed_pdf(aim_row, x, y, z, dx, dy, dz)


@njit(cache=True, inline="always")
def led_index(leds, u):
    """The LED a forward ray of uniform ``u`` leaves: LED k with probability Φₖ / Σ Φ (its
    share of the emitted power, ``leds.power_cdf``); ⌊u N⌋ when all emit alike."""
    n = leds.points.shape[0]
    if leds.equal_power:
        return min(int(u * n), n - 1)
    for k in range(n - 1):
        if u < leds.power_cdf[k]:
            return k
    return n - 1


@njit(cache=True, inline="always")
def led_direction(leds, k, u1, u2):
    """Emission direction of LED ``k`` (an :class:`~.tables.LedTable`): polar angle from its
    profile (:func:`profile_polar_angle`), azimuth uniform, about its axis. Density
    :func:`led_direction_pdf`."""
    alpha = profile_polar_angle(u1, leds.alpha_grid, leds.cdf_grid[k])
    phi = 2.0 * math.pi * u2
    sa = math.sin(alpha)
    return about_axis(
        sa * math.cos(phi),
        sa * math.sin(phi),
        math.cos(alpha),
        leds.axes[k, 0],
        leds.axes[k, 1],
        leds.axes[k, 2],
    )


@njit(cache=True, inline="always")
def led_cos_alpha(leds, k, dx, dy, dz):
    """cos α of unit direction d (from LED ``k``) with the LED's axis."""
    return dx * leds.axes[k, 0] + dy * leds.axes[k, 1] + dz * leds.axes[k, 2]


@njit(cache=True, inline="always")
def radiant_intensity(leds, k, dx, dy, dz):
    """Radiant intensity I(α) = I₀ₖ · Iₖ(α)/I₀ₖ (W/sr) of LED ``k`` toward unit direction d
    (from the LED), with that LED's own I₀ and profile: the one evaluator of the LEDs' angular
    profiles in the kernels. 0 behind."""
    return leds.i0[k] * relative_intensity_at(
        led_cos_alpha(leds, k, dx, dy, dz), leds.alpha_grid, leds.intensity_grid[k]
    )


@njit(cache=True, inline="always")
def relative_intensity_at(cos_a, alpha_grid, intensity_grid):
    """I(α)/I₀ at cos α, linear in α on the uniform grid of the compiled scene; 0 behind."""
    if cos_a <= 0.0:
        return 0.0
    a = math.acos(min(1.0, cos_a))
    n = alpha_grid.shape[0]
    f = a / alpha_grid[n - 1] * (n - 1)
    i = int(f)
    if i >= n - 1:
        return intensity_grid[n - 1]
    frac = f - i
    return intensity_grid[i] * (1.0 - frac) + intensity_grid[i + 1] * frac


def profile_tables(relative_intensity, n: int = 4097) -> tuple[np.ndarray, np.ndarray, float]:
    """Sampling tables for an LED profile and its solid-angle integral.

    Parameters
    ----------
    relative_intensity
        Vectorised I(α)/I(0) for α in radians, 0 ≤ α ≤ π/2.
    n
        Grid points on [0, π/2].

    Returns
    -------
    alpha_grid, cdf_grid, omega_eff
        ``omega_eff`` = ∫ I/I(0) dΩ = 2π ∫ I(α)/I(0) sin α dα (sr), so that the emitted power is
        Φ = I(0) · omega_eff (W). Integrated by Simpson's rule.
    """
    from scipy.integrate import cumulative_simpson

    alpha = np.linspace(0.0, math.pi / 2, n)
    density = np.asarray(relative_intensity(alpha), dtype=float) * np.sin(alpha)
    cum = cumulative_simpson(density, x=alpha, initial=0.0)
    cum = np.maximum.accumulate(cum)
    total = cum[-1]
    return alpha, cum / total, 2.0 * math.pi * total


def cos_power_tables(m: float, n: int = 4097) -> tuple[np.ndarray, np.ndarray, float]:
    """Closed-form sampling tables of I(α) = I₀ cosᵐ α: CDF(α) = 1 − cos^{m+1} α and
    Ω_eff = 2π / (m + 1) sr, on the same grid as :func:`profile_tables`."""
    alpha = np.linspace(0.0, math.pi / 2, n)
    cdf = 1.0 - np.cos(alpha) ** (m + 1.0)
    cdf[-1] = 1.0
    return alpha, cdf, 2.0 * math.pi / (m + 1.0)


def profile_pdf(alpha, relative_intensity, omega_eff: float):
    """Density per steradian of directions drawn by the LED sampler: p(ω) = I(α)/I(0) / Ω_eff."""
    return np.asarray(relative_intensity(np.asarray(alpha)), dtype=float) / omega_eff


@njit(cache=True, inline="always")
def led_direction_pdf(leds, k, omega_eff, dx, dy, dz):
    """Density per steradian of :func:`led_direction` for LED ``k``: Iₖ(α)/I₀ₖ / Ω_eff,k
    (Ω_eff,k in sr, the compiled scene's ``omega_eff[k]``), with Iₖ(α)/I₀ₖ interpolated on the
    profile grid."""
    cos_a = led_cos_alpha(leds, k, dx, dy, dz)
    return relative_intensity_at(cos_a, leds.alpha_grid, leds.intensity_grid[k]) / omega_eff
