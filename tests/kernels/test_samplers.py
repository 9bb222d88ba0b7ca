"""Every sampler of :mod:`eyelume.kernels.sampling` against its pdf with the one χ² harness
(``chi2.py``), table-driven as scipy's ``test_continuous_basic``; plus normalisation and
inverse round trips.

Threshold: a correct sampler fails a χ² test with probability α; over the table's k tests the
family-wise false-alarm rate is held at 1e-3 by Bonferroni, α = 1e-3 / k. Samples come from
fixed seeds, so the outcome is deterministic.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest
from chi2 import SPHERE, ChiSquareTest, disk
from numba import njit

from eyelume.kernels.sampling import (
    about_axis,
    aimed_mixture,
    aimed_mixture_pdf,
    cos_power_tables,
    cosine_hemisphere,
    cosine_hemisphere_pdf,
    disk_stratum,
    led_direction,
    led_direction_pdf,
    profile_tables,
    uniform_cone,
    uniform_cone_pdf,
    uniform_disk,
    uniform_disk_pdf,
)
from eyelume.kernels.tables import A_AZ, A_KIND, A_P, A_R, A_Z, AIM_IMAGE, N_AIM, LedTable

FAMILY_ALPHA = 1e-3
M_LED = 8.76  # cos^m of a 22.5° half-intensity half-angle
COS_MAX = 0.8  # the cone sampler's half-angle: acos 0.8 ≈ 36.9°
DISK_R = 2.5
STRATA = 3  # disk_stratum: 3 rings × 3 sectors
TILT = np.array([0.3, -0.2, 1.0]) / np.linalg.norm([0.3, -0.2, 1.0])
NORMAL = np.array([0.2, -0.1, 1.0]) / np.linalg.norm([0.2, -0.1, 1.0])
TABLE_KNOTS = np.radians([0.0, 20.0, 40.0, 60.0, 90.0])  # a tabulated profile's angles
AIM_Z, AIM_R = 150.0, 25.0  # the aim disk, centred above the scatter point at the origin


def _uniforms(n: int, k: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).random((n, k))


# --- njit batch wrappers: the kernels are scalar -------------------------------------------------


@njit(cache=True)
def _cosine(us):
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
def _cone(us, cos_max):
    out = np.empty((us.shape[0], 3))
    for i in range(us.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = uniform_cone(us[i, 0], us[i, 1], cos_max)
    return out


@njit(cache=True)
def _cone_pdf(v, cos_max):
    out = np.empty(v.shape[0])
    for i in range(v.shape[0]):
        out[i] = uniform_cone_pdf(v[i, 2], cos_max)
    return out


@njit(cache=True)
def _disk(us, radius):
    out = np.empty((us.shape[0], 2))
    for i in range(us.shape[0]):
        out[i, 0], out[i, 1] = uniform_disk(us[i, 0], us[i, 1], radius)
    return out


@njit(cache=True)
def _stratum(us, grid, radius):
    out = np.empty((us.shape[0], 2))
    for i in range(us.shape[0]):
        k = min(int(us[i, 2] * grid * grid), grid * grid - 1)
        out[i, 0], out[i, 1] = disk_stratum(k, grid, us[i, 0], us[i, 1], radius)
    return out


@njit(cache=True)
def _disk_pdf(p, radius):
    out = np.empty(p.shape[0])
    for i in range(p.shape[0]):
        out[i] = uniform_disk_pdf(p[i, 0], p[i, 1], radius)
    return out


@njit(cache=True)
def _led(us, leds):
    out = np.empty((us.shape[0], 3))
    for i in range(us.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = led_direction(leds, 0, us[i, 0], us[i, 1])
    return out


@njit(cache=True)
def _led_pdf(v, leds, omega):
    out = np.empty(v.shape[0])
    for i in range(v.shape[0]):
        out[i] = led_direction_pdf(leds, 0, omega, v[i, 0], v[i, 1], v[i, 2])
    return out


@njit(cache=True)
def _mixture(us, aim, n):
    out = np.empty((us.shape[0], 3))
    for i in range(us.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = aimed_mixture(
            us[i, 0], us[i, 1], us[i, 2], aim, 0.0, 0.0, 0.0, n[0], n[1], n[2]
        )
    return out


@njit(cache=True)
def _mixture_pdf(v, aim, n):
    out = np.empty(v.shape[0])
    for i in range(v.shape[0]):
        out[i] = aimed_mixture_pdf(aim, 0.0, 0.0, 0.0, n[0], n[1], n[2], v[i, 0], v[i, 1], v[i, 2])
    return out


# --- the table -------------------------------------------------------------------------------


def _led_table(profile: str, axis: np.ndarray) -> tuple[LedTable, float]:
    if profile == "cos_power":
        ag, cdf, omega = cos_power_tables(M_LED)
        ig = np.cos(ag) ** M_LED
    else:  # a tabulated profile: piecewise linear, 0 at 90°

        def shape(a):
            return np.interp(a, TABLE_KNOTS, [1.0, 0.8, 0.3, 0.05, 0.0])

        ag, cdf, omega = profile_tables(shape)
        ig = shape(ag)
    one = np.ones(1)
    leds = LedTable(
        np.zeros((1, 3)), np.ascontiguousarray([axis]), one, ag, cdf[None], ig[None], one, True
    )
    return leds, omega


def _aim_row(p: float) -> np.ndarray:
    row = np.zeros(N_AIM)
    row[A_Z], row[A_R], row[A_P] = AIM_Z, AIM_R, p
    return row


def _image_row(z: float) -> np.ndarray:
    """An AIM_IMAGE row: the pupil's image, a sphere of radius AIM_R about (0, 0, z), the
    camera's rays leaving the elements along −z — at z > 0 (behind the origin on those rays)
    the light is aimed toward it, at z < 0 (a real image they meet after the origin) away from
    it: a cone about +z either way."""
    row = np.zeros(N_AIM)
    row[A_Z], row[A_R], row[A_P], row[A_KIND], row[A_AZ] = z, AIM_R, 0.8, AIM_IMAGE, -1.0
    return row


@dataclass
class Case:
    name: str
    make: object  # () → ChiSquareTest


def _cases() -> list[Case]:
    cases = [
        Case(
            "cosine_hemisphere",
            lambda: ChiSquareTest(SPHERE, lambda n: _cosine(_uniforms(n, 2, 1)), _cosine_pdf),
        ),
        Case(
            "uniform_cone",
            lambda: ChiSquareTest(
                SPHERE,
                lambda n: _cone(_uniforms(n, 2, 2), COS_MAX),
                lambda v: _cone_pdf(v, COS_MAX),
                a_edges=(COS_MAX,),
            ),
        ),
        Case(
            "uniform_disk",
            lambda: ChiSquareTest(
                disk(DISK_R),
                lambda n: _disk(_uniforms(n, 2, 3), DISK_R),
                lambda p: _disk_pdf(p, DISK_R),
            ),
        ),
        Case(
            "disk_stratum",
            lambda: ChiSquareTest(
                disk(DISK_R),
                lambda n: _stratum(_uniforms(n, 3, 4), STRATA, DISK_R),
                lambda p: _disk_pdf(p, DISK_R),
            ),
        ),
    ]
    # the tabulated profile about +z: its kinks (cos of the knots) on cell edges; linear in α
    # near the axis, it goes as √(1 − cos θ) in the cell parameter, which Gauss–Legendre
    # integrates slowly: 24 nodes per cell bring the top cell's error below 1e-6
    kinks = tuple(np.cos(TABLE_KNOTS[1:-1]))
    for profile, axis, seed, edges, ires in (
        ("cos_power", TILT, 5, (), 6),
        ("table", np.array([0.0, 0.0, 1.0]), 6, kinks, 24),
    ):
        leds, omega = _led_table(profile, axis)
        cases.append(
            Case(
                f"led_direction ({profile})",
                lambda leds=leds, omega=omega, seed=seed, edges=edges, ires=ires: ChiSquareTest(
                    SPHERE,
                    lambda n: _led(_uniforms(n, 2, seed), leds),
                    lambda v: _led_pdf(v, leds, omega),
                    res=(40, 40),
                    ires=ires,
                    a_edges=edges,
                ),
            )
        )
    # the aim disk seen from the origin: a cone about +z of cos half-angle Z / √(Z² + R²)
    rim = AIM_Z / math.hypot(AIM_Z, AIM_R)
    for p, seed in ((0.8, 7), (0.0, 8)):
        row = _aim_row(p)
        cases.append(
            Case(
                f"aimed_mixture (p = {p})",
                lambda row=row, seed=seed: ChiSquareTest(
                    SPHERE,
                    lambda n: _mixture(_uniforms(n, 3, seed), row, NORMAL),
                    lambda v: _mixture_pdf(v, row, NORMAL),
                    a_edges=(rim,),
                    res=(40, 40),
                ),
            )
        )
    # the pupil's image through elements: a uniform cone of cos half-angle √(1 − R²/Z²)
    cone_rim = math.sqrt(1.0 - (AIM_R / AIM_Z) ** 2)
    for z, seed in ((AIM_Z, 10), (-AIM_Z, 11)):
        row = _image_row(z)
        cases.append(
            Case(
                f"aimed_mixture (pupil image at z = {z:g})",
                lambda row=row, seed=seed: ChiSquareTest(
                    SPHERE,
                    lambda n: _mixture(_uniforms(n, 3, seed), row, NORMAL),
                    lambda v: _mixture_pdf(v, row, NORMAL),
                    a_edges=(cone_rim,),
                    res=(40, 40),
                ),
            )
        )
    return cases


CASES = _cases()
ALPHA = FAMILY_ALPHA / len(CASES)


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_sampler_matches_its_pdf(case):
    result = case.make().run()
    assert result.impossible == 0, f"{case.name}: samples where the pdf is 0"
    assert result.p_value > ALPHA, f"{case.name}: χ² = {result.statistic:.1f}, dof {result.dof}"


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_pdf_is_normalised(case):
    # Gauss–Legendre with 6 nodes per cell is exact to ~1e-12 on these smooth cell integrands
    # (jumps and kinks sit on cell edges); the LED tables interpolate I(α) linearly on 4097
    # points and Ω_eff is Simpson's on the same grid: their mismatch is O(h²) ≈ 1e-7.
    assert abs(case.make().expected_probabilities().sum() - 1.0) < 1e-6


def test_the_harness_rejects_a_wrong_pdf():
    """The harness has power: cosine samples against the uniform-hemisphere pdf."""
    t = ChiSquareTest(
        SPHERE,
        lambda n: _cosine(_uniforms(n, 2, 9)),
        lambda v: np.where(v[:, 2] >= 0.0, 1.0 / (2 * math.pi), 0.0),
    )
    assert t.run().p_value < 1e-12


# --- inverses: uniforms recovered from the samples (closed forms of each map) ------------------


def test_uniform_cone_inverse():
    us = _uniforms(20_000, 2, 10)
    v = _cone(us, COS_MAX)
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose((1.0 - v[:, 2]) / (1.0 - COS_MAX), us[:, 0], atol=1e-12)
    u2 = np.mod(np.arctan2(v[:, 1], v[:, 0]) / (2 * math.pi), 1.0)
    d = np.abs(u2 - us[:, 1])
    assert np.all(np.minimum(d, 1.0 - d) < 1e-12)


def test_uniform_disk_and_stratum_inverses():
    us = _uniforms(20_000, 3, 11)
    p = _disk(us, DISK_R)
    np.testing.assert_allclose((p[:, 0] ** 2 + p[:, 1] ** 2) / DISK_R**2, us[:, 0], atol=1e-12)
    q = _stratum(us, STRATA, DISK_R)
    k = np.minimum((us[:, 2] * STRATA**2).astype(int), STRATA**2 - 1)
    ring = (q[:, 0] ** 2 + q[:, 1] ** 2) / DISK_R**2 * STRATA
    sector = np.mod(np.arctan2(q[:, 1], q[:, 0]), 2 * math.pi) / (2 * math.pi) * STRATA
    # the point lies in its stratum (ring k // grid, sector k % grid), at its fractions u1, u2
    np.testing.assert_allclose(ring, k // STRATA + us[:, 0], atol=1e-9)
    s = sector - (k % STRATA) - us[:, 1]
    assert np.all(np.abs(s - np.round(s / STRATA) * STRATA) < 1e-9)


def test_led_direction_is_about_the_axis():
    leds, _ = _led_table("cos_power", TILT)
    us = _uniforms(2000, 2, 12)
    v = _led(us, leds)
    local = _led(us, _led_table("cos_power", np.array([0.0, 0.0, 1.0]))[0])
    # the same polar angle about the tilted axis as about +z
    np.testing.assert_allclose(v @ TILT, local[:, 2], atol=1e-12)
    np.testing.assert_allclose(about_axis(*local[0], *TILT), v[0], atol=1e-12)
