"""Direction samplers, each with its probability density (per steradian) for tests and weights."""

from __future__ import annotations

import math

import numpy as np
from numba import njit


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
