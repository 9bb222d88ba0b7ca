"""Direction samplers against their densities: χ² goodness of fit (after Mitsuba's chi2 tests),
inverse round trips, frames, and the LED-profile tables.

χ² tests draw from the counter-based streams with fixed seeds, so they are deterministic; they
reject at p < 1e-3, the usual threshold for this style of test. They use the one χ² harness,
``chi2.py`` (cells expecting fewer than 5 pooled into one, as Mitsuba does, so that the χ²
approximation holds).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from chi2 import SPHERE, ChiSquareTest, pearson_1d
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit
from scipy.integrate import quad

from eyelume.kernels.rng import next_uniform, stream_start
from eyelume.kernels.sampling import (
    about_axis,
    cosine_hemisphere,
    cosine_hemisphere_pdf,
    orthonormal_basis,
    profile_pdf,
    profile_polar_angle,
    profile_tables,
)

P_REJECT = 1e-3
N_SAMPLES = 200_000
M_LED = 8.76  # cos^m profile of an LED with a 22.5° half-intensity half-angle
ROUND = 1e-12  # a few ulp of O(1) quantities, with ample headroom

# A tabulated profile: piecewise-linear I(α) through these knots (a "triangle" with shoulders).
TABLE_ALPHA = np.radians([0.0, 20.0, 40.0, 60.0, 90.0])
TABLE_I = np.array([1.0, 0.8, 0.3, 0.05, 0.0])


def _cos_m(alpha):
    return np.cos(alpha) ** M_LED


def _table_profile(alpha):
    return np.interp(alpha, TABLE_ALPHA, TABLE_I)


@njit(cache=True)
def _uniform_pairs(seed, n):
    out = np.empty((n, 2))
    for i in range(n):
        state = stream_start(seed, i)
        state, out[i, 0] = next_uniform(state)
        state, out[i, 1] = next_uniform(state)
    return out


@njit(cache=True)
def _cosine_samples(us):
    out = np.empty((us.shape[0], 3))
    for i in range(us.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = cosine_hemisphere(us[i, 0], us[i, 1])
    return out


@njit(cache=True)
def _cosine_pdf(v):
    out = np.empty(v.shape[0])
    for i in range(v.shape[0]):
        out[i] = cosine_hemisphere_pdf(v[i, 2])
    return out


@njit(cache=True)
def _polar_samples(us, alpha_grid, cdf_grid):
    out = np.empty(us.shape[0])
    for i in range(us.shape[0]):
        out[i] = profile_polar_angle(us[i], alpha_grid, cdf_grid)
    return out


# --- cosine-weighted hemisphere -----------------------------------------------------------------


def test_cosine_hemisphere_chi2():
    # The counter-based streams' uniforms (tests/kernels/test_samplers.py draws numpy's) into
    # the one harness, against the kernel's own cosine_hemisphere_pdf: cells of 0.05 in cos θ
    # (40 over [−1, 1]) by 9° in φ; Gauss–Legendre integrates the linear pdf exactly.
    test = ChiSquareTest(
        SPHERE,
        lambda n: _cosine_samples(_uniform_pairs(1, n)),
        _cosine_pdf,
        sample_count=N_SAMPLES,
        res=(40, 40),
    )
    result = test.run()
    assert result.impossible == 0  # no sample below the horizon
    assert result.p_value > P_REJECT
    for c in np.linspace(0.0, 1.0, 11):
        assert cosine_hemisphere_pdf(c) == c / math.pi
    assert cosine_hemisphere_pdf(-0.5) == 0.0


def test_cosine_hemisphere_pdf_integrates_to_one():
    # ∫ pdf dΩ = 2π ∫₀¹ pdf(μ) dμ; quad is exact to ~1e-14 on this polynomial
    total = 2 * math.pi * quad(cosine_hemisphere_pdf, 0.0, 1.0)[0]
    assert abs(total - 1.0) < 1e-12


def test_cosine_hemisphere_unit_and_inverse_round_trip():
    us = _uniform_pairs(2, 20_000)
    v = _cosine_samples(us)
    assert np.all(np.abs(np.linalg.norm(v, axis=1) - 1.0) < ROUND)
    assert np.all(v[:, 2] >= 0.0)
    # inverse of Malley's map: u1 = x² + y² (= sin²θ), u2 = φ/2π
    u1 = v[:, 0] ** 2 + v[:, 1] ** 2
    u2 = np.mod(np.arctan2(v[:, 1], v[:, 0]) / (2 * np.pi), 1.0)
    np.testing.assert_allclose(u1, us[:, 0], rtol=0, atol=ROUND)
    du2 = np.abs(u2 - us[:, 1])
    assert np.all(np.minimum(du2, 1.0 - du2) < ROUND)  # u2 is circular: 0 ≡ 1


# --- frames -------------------------------------------------------------------------------------


def _unit(cos_polar: float, azimuth: float) -> np.ndarray:
    s = math.sqrt(max(0.0, 1.0 - cos_polar * cos_polar))
    return np.array([s * math.cos(azimuth), s * math.sin(azimuth), cos_polar])


SPECIAL_AXES = [
    (0.0, 0.0, 1.0),
    (0.0, 0.0, -1.0),
    (1.0, 0.0, 0.0),
    (1.0, 0.0, -0.0),
    (0.0, -1.0, 0.0),
    (-0.0, -0.0, -1.0),
    # next to the poles, where the branchless formula divides by sign + n_z ≈ 2 or is nearest 0
    (1e-8, 0.0, -math.sqrt(1.0 - 1e-16)),
    (0.0, 3e-9, math.sqrt(1.0 - 9e-18)),
    (math.sqrt(0.5), 0.0, -math.sqrt(0.5)),
]

axes = st.one_of(
    st.sampled_from(SPECIAL_AXES).map(np.array),
    st.builds(_unit, st.floats(-1.0, 1.0), st.floats(0.0, 2.0 * math.pi)),
)


def _check_frame(t, b, n):
    for v in (t, b):
        assert abs(np.linalg.norm(v) - 1.0) < ROUND
    assert abs(t @ b) < ROUND
    assert abs(t @ n) < ROUND
    assert abs(b @ n) < ROUND
    np.testing.assert_allclose(np.cross(t, b), n, atol=ROUND)  # right-handed (t, b, n)


@settings(derandomize=True, max_examples=200, deadline=None)
@given(axes)
def test_orthonormal_basis_right_handed(n):
    n = n / np.linalg.norm(n)
    t, b = orthonormal_basis(*n)
    _check_frame(np.array(t), np.array(b), n)


@settings(derandomize=True, max_examples=200, deadline=None)
@given(axes, st.builds(_unit, st.floats(-1.0, 1.0), st.floats(0.0, 2.0 * math.pi)))
def test_about_axis_is_a_rotation_taking_z_to_the_axis(n, local):
    n = n / np.linalg.norm(n)
    np.testing.assert_allclose(about_axis(0.0, 0.0, 1.0, *n), n, atol=ROUND)
    images = [np.array(about_axis(*e, *n)) for e in np.eye(3)]
    _check_frame(images[0], images[1], images[2])
    w = np.array(about_axis(*local, *n))
    np.testing.assert_allclose(w, np.column_stack(images) @ local, atol=ROUND)
    assert abs(w @ n - local[2]) < ROUND  # the polar angle about the axis is kept


# --- LED profiles -------------------------------------------------------------------------------


def _alpha_chi2(profile, cell_probs_of, seed):
    alpha_grid, cdf_grid, _ = profile_tables(profile)
    u = _uniform_pairs(seed, N_SAMPLES)[:, 0]
    alpha = _polar_samples(u, alpha_grid, cdf_grid)
    assert alpha.min() >= 0.0 and alpha.max() <= math.pi / 2
    edges = np.linspace(0.0, math.pi / 2, 46)  # 2° cells
    return pearson_1d(alpha, edges, cell_probs_of(edges))


def test_profile_polar_angle_cos_m_chi2():
    # density ∝ cos^m α sin α; ∫ cos^m α sin α dα = (1 − cos^{m+1} α)/(m + 1), so a cell has
    # probability cos^{m+1}(a) − cos^{m+1}(b). (The table's linear inverse deviates from this
    # by ≲ h²·max|cdf''| ≈ 1e-6 per cell, h = (π/2)/4096, far below the cell's standard error
    # ~ √(p/N) ≈ 5e-4.)
    def probs(edges):
        return -np.diff(np.cos(edges) ** (M_LED + 1))

    assert _alpha_chi2(_cos_m, probs, seed=3) > P_REJECT


def test_profile_polar_angle_table_chi2():
    def probs(edges):
        def dens(a):
            return float(_table_profile(a)) * math.sin(a)

        def integral(a, b):
            return quad(dens, a, b, points=[x for x in TABLE_ALPHA if a < x < b])[0]

        cells = np.array([integral(a, b) for a, b in zip(edges[:-1], edges[1:], strict=True)])
        return cells / integral(0.0, math.pi / 2)

    assert _alpha_chi2(_table_profile, probs, seed=4) > P_REJECT


def test_profile_polar_angle_inverts_the_tables():
    alpha_grid, cdf_grid, _ = profile_tables(_cos_m)
    assert profile_polar_angle(0.0, alpha_grid, cdf_grid) == 0.0
    # at the grid's cdf values the inverse returns the grid's angles (up to the last-bit rounding
    # of the interpolation, ~ε·π/2)
    for j in (1, 10, 500, 2000, 4000):
        assert abs(profile_polar_angle(cdf_grid[j], alpha_grid, cdf_grid) - alpha_grid[j]) < 1e-15
    u = np.linspace(0.0, 1.0 - 2.0**-53, 1001)
    a = _polar_samples(u, alpha_grid, cdf_grid)
    assert np.all(np.diff(a) >= 0.0)  # monotone
    # The closed-form inverse of the cos^m cdf: cos α = (1 − u)^{1/(m+1)}. Interpolating α
    # linearly in u over a cell of width h in α errs by ≈ h²/8·|p'/p| with p ∝ cos^m α sin α,
    # p'/p = cot α − m tan α, h = (π/2)/4096. For u in [0.01, 0.99] (α in [0.045, 0.90] rad)
    # |p'/p| ≤ 23, so the error is ≤ 4.2e-7 rad; near the ends p'/p diverges.
    exact = np.arccos((1.0 - u) ** (1.0 / (M_LED + 1)))
    inner = (u >= 0.01) & (u <= 0.99)
    assert np.max(np.abs(a[inner] - exact[inner])) < 1e-6


def test_omega_eff_closed_form():
    # Ω_eff = 2π ∫₀^{π/2} cos^m α sin α dα = 2π/(m + 1). Simpson's error on 4097 points is
    # O(h⁴ f⁗) ≈ (3.8e-4)⁴ · O(10²) ≈ 1e-12 relative; 1e-9 leaves margin.
    for m in (1.0, 2.0, M_LED, 30.0):
        _, cdf, omega = profile_tables(lambda a, m=m: np.cos(a) ** m)
        assert math.isclose(omega, 2 * math.pi / (m + 1), rel_tol=1e-9), m
        assert cdf[0] == 0.0 and cdf[-1] == 1.0 and np.all(np.diff(cdf) >= 0.0)
    # Lambertian: Φ = π I₀
    assert math.isclose(profile_tables(np.cos)[2], math.pi, rel_tol=1e-9)


def test_profile_pdf_integrates_to_one():
    # ∫ p dΩ = 2π ∫ p(α) sin α dα with p = I/I₀/Ω_eff. For cos^m, Ω_eff is good to ~1e-12
    # (above) and quad to ~1e-13: tolerance 1e-9. For the table, Simpson straddles the three
    # kinks of I: its error there is ≲ h²·Σ|Δ slope of I sin α| ≈ 1.5e-7 × 2.2 ≈ 3e-7 on an
    # integral ≈ 0.3, i.e. ≲ 1e-6 relative: tolerance 3e-6.
    for profile, tol in ((_cos_m, 1e-9), (_table_profile, 3e-6)):
        _, _, omega = profile_tables(profile)

        def f(a, profile=profile, omega=omega):
            return float(profile_pdf(a, profile, omega)) * math.sin(a)

        total = 2 * math.pi * quad(f, 0.0, math.pi / 2, points=TABLE_ALPHA[1:-1], epsabs=1e-13)[0]
        assert abs(total - 1.0) < tol, (profile, total)


def test_cos_power_closed_form_tables_match_the_numeric_ones():
    """The default profile's closed-form CDF and Ω_eff against the Simpson-integrated tables of
    the same cosᵐ curve (Simpson's error on 4097 points is ~1e-12 here)."""
    from eyelume.kernels.sampling import cos_power_tables

    m = math.log(0.5) / math.log(math.cos(math.radians(22.5)))
    a1, c1, w1 = cos_power_tables(m)
    a2, c2, w2 = profile_tables(lambda a: np.cos(a) ** m)
    np.testing.assert_array_equal(a1, a2)
    np.testing.assert_allclose(c1, c2, atol=1e-9)
    assert w1 == pytest.approx(w2, rel=1e-9)
