"""Test 3: one LED alone — eye-plane irradiance per bin against the closed-form integral.

E_bin = (1/A_bin) ∫∫_bin I(α) cos β / r² dA, with r the distance from the emission point, β the
angle to the plane's normal (cos β = z_s / r) and α the angle from the LED axis. With the face
removed nothing but the LED's direct light crosses z = 0 toward the eye, so the forward estimate
must agree bin by bin within its multinomial noise.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

import eyelume
from eyelume.compile import compile_scene
from eyelume.scene.sources import relative_intensity

RAYS = 3_000_000


def closed_form_eye_plane(cs) -> np.ndarray:
    """Flux per bin (W) by 16 × 16 Gauss–Legendre quadrature of I(α) cos β / r² over each bin."""
    sc = cs.scene
    f = relative_intensity(sc.leds.profile)
    i0 = sc.leds.radiant_intensity_w_sr
    src, axis = cs.led.points[0], cs.led.axes[0]
    w, h, nc, nr = (
        sc.eye_plane.width_mm,
        sc.eye_plane.height_mm,
        sc.eye_plane.cols,
        sc.eye_plane.rows,
    )
    g, gw = np.polynomial.legendre.leggauss(16)
    flux = np.zeros((nr, nc))
    bw, bh = w / nc, h / nr
    for row in range(nr):
        y0 = h / 2 - (row + 1) * bh
        for col in range(nc):
            x0 = -w / 2 + col * bw
            xs = x0 + (g + 1) * bw / 2
            ys = y0 + (g + 1) * bh / 2
            X, Y = np.meshgrid(xs, ys)
            dx, dy, dz = X - src[0], Y - src[1], -src[2]
            r = np.sqrt(dx * dx + dy * dy + dz * dz)
            cos_a = (dx * axis[0] + dy * axis[1] + dz * axis[2]) / r
            alpha = np.arccos(np.clip(cos_a, -1, 1))
            inten = np.where(alpha <= math.pi / 2, i0 * f(np.minimum(alpha, math.pi / 2)), 0.0)
            integrand = inten * (src[2] / r) / r**2
            flux[row, col] = np.einsum("i,j,ij->", gw, gw, integrand) * bw * bh / 4
    return flux


@pytest.mark.parametrize("profile", ["cos_power", "table"])
def test_single_led_eye_plane_matches_closed_form(tmp_path, profile):
    overrides = {
        "leds.count": 1,
        "leds.azimuths_deg": "[90.0]",
        "face.enabled": "false",
    }
    if profile == "table":
        # a datasheet-like curve: flat top, shoulder, long tail (angle deg, relative intensity)
        csv = tmp_path / "led.csv"
        csv.write_text(
            "angle_deg,relative\n0,1\n10,0.97\n20,0.72\n30,0.38\n40,0.15\n60,0.03\n90,0\n",
            encoding="utf-8",
        )
        overrides |= {"leds.profile.kind": '"table"', "leds.profile.table_csv": f'"{csv}"'}
    scene = eyelume.load_scene("paper2005", overrides)
    cs = compile_scene(scene)
    result = eyelume.render(cs, eyelume.RenderOptions(rays=RAYS, seed=7))

    expected_flux = closed_form_eye_plane(cs)
    p = expected_flux / cs.emitted_w  # probability that a ray lands in each bin
    expected = RAYS * p
    sigma = np.sqrt(RAYS * p * (1 - p))  # multinomial: each ray lands in at most one bin once
    z = (result.plane_counts - expected) / sigma
    # Bonferroni: family-wise false-alarm 1e-3 over all bins.
    z_max = stats.norm.isf(1e-3 / 2 / z.size)
    assert np.all(expected > 25), "every bin must be well populated for the normal approximation"
    assert np.max(np.abs(z)) < z_max, f"worst bin z = {np.max(np.abs(z)):.2f}"
    chi2 = float(np.sum(z**2))
    assert stats.chi2.sf(chi2, df=z.size) > 1e-3, f"chi2 = {chi2:.1f} for {z.size} bins"
    # and the irradiance in physical units: W/mm² = flux / bin area
    area = (40 / 21) * (30 / 15)
    np.testing.assert_allclose(result.eye_plane, result.plane_counts * result.ray_power_w / area)
