"""Interactions at a surface: Snell refraction, specular reflection, Fresnel reflectance.

Property-based (hypothesis, derandomised) against the laws themselves, written out in the test
with numpy rather than reusing the kernel's algebra.

Tolerances: every quantity below is a handful of float64 operations on O(1) numbers, so its
rounding error is a few ulp (ε = 2.2e-16) times a factor of at most ~2 (η ≤ 2); 1e-12 leaves
three orders of magnitude above that and is still far below any physical error (a wrong sign,
a missing η, a swapped n₁/n₂ all show up at ≥ 1e-3).
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from eyelume.kernels.interact import fresnel_reflectance, reflect, refract

ROUND = 1e-12  # a few ulp of O(1) quantities, with ample headroom (module docstring)

SETTINGS = settings(derandomize=True, max_examples=200, deadline=None)


def _unit(cos_polar: float, azimuth: float) -> np.ndarray:
    s = math.sqrt(max(0.0, 1.0 - cos_polar * cos_polar))
    return np.array([s * math.cos(azimuth), s * math.sin(azimuth), cos_polar])


def _tangent_basis(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    t1 = np.cross(n, helper)
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(n, t1)


unit_vectors = st.builds(
    _unit, st.floats(-1.0, 1.0), st.floats(0.0, 2.0 * math.pi, exclude_max=True)
)


@st.composite
def incidences(draw, max_theta: float = math.pi / 2):
    """(d, n, θi): unit direction d meeting the unit normal n (which may face either side) at θi."""
    n = draw(unit_vectors)
    theta = draw(st.floats(0.0, max_theta, exclude_max=True))
    psi = draw(st.floats(0.0, 2.0 * math.pi))
    t1, t2 = _tangent_basis(n)
    d = -math.cos(theta) * n + math.sin(theta) * (math.cos(psi) * t1 + math.sin(psi) * t2)
    d /= np.linalg.norm(d)
    if draw(st.booleans()):  # the kernel must accept the normal facing either side
        n = -n
    return d, n, theta


def _refract(d, n, eta):
    ok, tx, ty, tz = refract(*d, *n, eta)
    return ok, np.array([tx, ty, tz])


# --- refraction ---------------------------------------------------------------------------------


@SETTINGS
@given(incidences(), st.floats(0.5, 2.0))
def test_refract_unit_coplanar_snell(inc, eta):
    d, n, _ = inc
    sin_i = np.linalg.norm(np.cross(d, n))
    assume(eta * sin_i < 1.0 - 1e-9)  # transmitted (TIR is tested separately)
    ok, t = _refract(d, n, eta)
    assert ok
    assert abs(np.linalg.norm(t) - 1.0) < ROUND
    # in the plane of incidence spanned by d and n
    assert abs(np.dot(t, np.cross(d, n))) < ROUND
    # Snell's law, both sines from cross products: n₁ sin θi = n₂ sin θt ⇔ η sin θi = sin θt.
    # |t × n| = η |d × n| exactly in real arithmetic; rounding ~ε·(1+η) ≪ 1e-10.
    sin_t = np.linalg.norm(np.cross(t, n))
    assert abs(eta * sin_i - sin_t) < 1e-10
    # transmitted, not reflected: stays on the same side of the interface as the ray's travel
    assert np.dot(t, n) * np.dot(d, n) >= 0.0


@SETTINGS
@given(incidences(), st.floats(0.5, 2.0))
def test_refract_tir_exactly_beyond_critical_angle(inc, eta):
    d, n, _ = inc
    sin_i = np.linalg.norm(np.cross(d, n))
    # exclude a ±1e-9 band about the critical angle, where rounding (~1e-16) may decide either way
    assume(abs(eta * sin_i - 1.0) > 1e-9)
    ok, _ = _refract(d, n, eta)
    assert ok == (eta * sin_i <= 1.0)


def test_refract_tir_on_either_side_of_critical_angle():
    # Targeted: random draws rarely land close to θc; step 1e-6 rad either side of it.
    rng = np.random.default_rng(7)
    for eta in (1.0 / 0.75, 1.5, 1.7, 2.0):
        theta_c = math.asin(1.0 / eta)
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        t1, _ = _tangent_basis(n)
        for delta, expected in ((-1e-6, True), (1e-6, False)):
            th = theta_c + delta
            d = -math.cos(th) * n + math.sin(th) * t1
            for normal in (n, -n):
                ok, t = _refract(d, normal, eta)
                assert ok is expected
                if ok:  # just below θc the ray leaves almost grazing: sin θt ≈ 1
                    assert abs(np.linalg.norm(np.cross(t, n)) - eta * math.sin(th)) < 1e-10


@SETTINGS
@given(unit_vectors, st.floats(0.5, 2.0), st.booleans())
def test_refract_normal_incidence_passes_straight(n, eta, along):
    d = n.copy() if along else -n  # the normal facing either way
    ok, t = _refract(d, n, eta)
    assert ok
    np.testing.assert_allclose(t, d, rtol=0, atol=ROUND)


@SETTINGS
@given(incidences(), st.floats(0.5, 2.0))
def test_refract_is_reversible(inc, eta):
    # Helmholtz reciprocity: refracting −t back with 1/η returns −d.
    d, n, _ = inc
    sin_i = np.linalg.norm(np.cross(d, n))
    # Keep cos θi and cos θt ≥ 1e-3: near grazing either way the reversal is ill-conditioned
    # (a cosine recomputed as √(1 − sin²) carries an absolute error ~ε/cos).
    assume(abs(np.dot(d, n)) > 1e-3 and eta * sin_i < math.sqrt(1.0 - 1e-6))
    ok, t = _refract(d, n, eta)
    assert ok
    ok2, back = _refract(-t, n, 1.0 / eta)
    assert ok2
    # error of the recomputed cosines ≲ ε/1e-3 ≈ 2e-13, times O(η) ≤ 2: 1e-9 leaves headroom
    np.testing.assert_allclose(back, -d, rtol=0, atol=1e-9)


# --- reflection ---------------------------------------------------------------------------------


@SETTINGS
@given(incidences())
def test_reflect_law(inc):
    d, n, _ = inc
    r = np.array(reflect(*d, *n))
    assert abs(np.linalg.norm(r) - 1.0) < ROUND
    # angle of reflection = angle of incidence, on the incident side: r·n = −d·n
    assert abs(np.dot(r, n) + np.dot(d, n)) < ROUND
    # r − d is along the normal (tangential component unchanged)
    np.testing.assert_allclose(np.cross(r - d, n), 0.0, atol=ROUND)
    # involution
    rr = np.array(reflect(*r, *n))
    np.testing.assert_allclose(rr, d, rtol=0, atol=ROUND)


# --- Fresnel ------------------------------------------------------------------------------------

indices = st.floats(1.0, 2.5)


@SETTINGS
@given(indices, indices)
def test_fresnel_normal_incidence(n1, n2):
    expected = ((n1 - n2) / (n1 + n2)) ** 2
    for cos_i in (1.0, -1.0):  # |cos θi| is what counts
        assert math.isclose(
            fresnel_reflectance(cos_i, n1, n2), expected, rel_tol=ROUND, abs_tol=1e-18
        )


@SETTINGS
@given(indices, indices)
def test_fresnel_brewster_angle(n1, n2):
    assume(abs(n1 - n2) > 1e-3)
    # tan θB = n2/n1 → cos θB = n1/√(n1² + n2²); there R_p = 0 and r_s = (n1² − n2²)/(n1² + n2²)
    cos_b = n1 / math.hypot(n1, n2)
    rs_closed = ((n1 * n1 - n2 * n2) / (n1 * n1 + n2 * n2)) ** 2
    got = fresnel_reflectance(cos_b, n1, n2)
    assert math.isclose(got, rs_closed / 2.0, rel_tol=1e-10)


@SETTINGS
@given(indices, indices, st.floats(0.0, 1.0))
def test_fresnel_total_beyond_critical_angle(n1, n2, frac):
    n1, n2 = max(n1, n2), min(n1, n2)
    assume(n1 / n2 > 1.0 + 1e-6)
    sin_c = n2 / n1
    sin_i = sin_c + (1.0 - sin_c) * frac
    assume(sin_i > sin_c * (1.0 + 1e-9))  # outside the rounding band at θc
    cos_i = math.sqrt(1.0 - sin_i * sin_i)
    assert fresnel_reflectance(cos_i, n1, n2) == 1.0


def _transmittance(cos_i: float, n1: float, n2: float) -> float:
    """T from the Fresnel amplitude transmission coefficients (independent of the kernel's r)."""
    sin_t = n1 / n2 * math.sqrt(1.0 - cos_i * cos_i)
    cos_t = math.sqrt(1.0 - sin_t * sin_t)
    ts = 2.0 * n1 * cos_i / (n1 * cos_i + n2 * cos_t)
    tp = 2.0 * n1 * cos_i / (n2 * cos_i + n1 * cos_t)
    return (n2 * cos_t) / (n1 * cos_i) * (ts * ts + tp * tp) / 2.0


@SETTINGS
@given(indices, indices, st.floats(0.0, 1.0))
def test_fresnel_energy_conservation(n1, n2, frac):
    # θi in [0, θmax) with θmax the critical angle (or 90°); stay 1e-6 inside it
    theta_max = math.asin(n2 / n1) if n1 > n2 else math.pi / 2
    theta = frac * theta_max * (1.0 - 1e-6)
    cos_i = math.cos(theta)
    assume(cos_i > 1e-6)
    r = fresnel_reflectance(cos_i, n1, n2)
    assert 0.0 <= r <= 1.0
    assert abs(r + _transmittance(cos_i, n1, n2) - 1.0) < 1e-10


@SETTINGS
@given(indices, indices, st.floats(0.0, 1.0))
def test_fresnel_reciprocity(n1, n2, frac):
    # R is the same seen from either side along the same ray path: R(θi; n1→n2) = R(θt; n2→n1)
    theta_max = math.asin(n2 / n1) if n1 > n2 else math.pi / 2
    theta = frac * theta_max * (1.0 - 1e-6)
    sin_t = n1 / n2 * math.sin(theta)
    cos_t = math.sqrt(1.0 - sin_t * sin_t)
    cos_i = math.cos(theta)
    # Each call recomputes the other side's cosine as √(1 − sin²), whose absolute error is
    # ~ε/cos; keep both cosines ≥ 1e-3 so it is ≤ 2.2e-13, and |dR/dcos| ≤ ~10 there.
    assume(min(cos_i, cos_t) > 1e-3)
    a = fresnel_reflectance(cos_i, n1, n2)
    b = fresnel_reflectance(cos_t, n2, n1)
    assert abs(a - b) < 1e-10


def test_fresnel_anterior_cornea():
    # Air → cornea (n = 1.376) at normal incidence: R = (0.376/2.376)² = 0.02504, i.e. 2.5 %.
    # The paper's 2.4 % is the same closed form rounded for n ≈ 1.37 ((0.37/2.37)² = 0.0244).
    r = fresnel_reflectance(1.0, 1.0, 1.376)
    assert math.isclose(r, (0.376 / 2.376) ** 2, rel_tol=ROUND)
    assert round(100.0 * r, 1) == 2.5
    assert round(100.0 * fresnel_reflectance(1.0, 1.0, 1.37), 1) == 2.4
