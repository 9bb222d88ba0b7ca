"""The eye-plane receiver is the world's eye plane for a camera anywhere.

On an off-axis rig (``vr-offaxis``: the camera 50° off the eye's axis, so the camera frame is
turned and shifted from the world's) with the eye moved in the headset (``eye_pose``), one LED
lights the eye plane: the world plane through the eye's nominal corneal vertex V normal to the
headset's z axis, bins from V (column 0 at −x, row 0 at +y). The reference is written here, not
taken from eyelume: a point source of on-axis radiant intensity I₀ with profile cosᵐα
(m = ln ½ / ln cos θ½) gives at a plane point P the irradiance

    E(P) = I₀ cosᵐα · cos β / r²,   r = |P − L|, cos β = (L − P)·ẑ / r, cos α = (P − L)·â / r,

L the emission point (the body's apex), â the LED's axis; a bin's mean is its 24 × 24
midpoint-rule average (the integrand is smooth on the bin, the rule's error ≪ the tolerances
below). The face is off, so nothing but the LED lights the plane from the headset side.

* The forward tracer's crossings: each of N rays crosses bin b toward the eye with probability
  p_b = ∫_b E dA / (I₀ Ω), Ω = 2π / (m + 1) (∫ cosᵐα dΩ), so the counts are multinomial and
  Σ (n_b − N p_b)² / (N p_b) over the lit bins follows χ² with one degree of freedom per bin
  (less the one constraint, a conservative rounding): the test takes its central 99.8 %.
* The fast estimator's direct irradiance (``plane_direct``): one jittered point in each of
  n_sub² cells of a bin, so its error is at most the sum over cells of their spread; with E's
  spread over the bin Δ_b (taken from the bin's corners and centre) a cell spreads ≤ Δ_b / n_sub
  and the mean's standard deviation is ≤ Δ_b / (2 n_sub²): the test allows 5 of those.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

import eyelume
from eyelume.compile import compile_scene
from eyelume.estimators.fast_run import direct_eye_plane
from eyelume.scene.io import apply_overrides, load_scene

VERTEX = np.array([2.0, -1.5, -1.0])  # the eye's nominal vertex in the headset (mm)
LED_CENTRE = np.array([-7.0, 9.0, 10.0])  # mm, world
HALF_ANGLE = 60.0
I0 = 0.001  # W/sr
RB = 0.8  # body radius, mm


@pytest.fixture(scope="module")
def rig():
    aim = VERTEX - LED_CENTRE
    scene = apply_overrides(
        load_scene("vr-offaxis"),
        {
            "face.enabled": False,
            "eye_pose.lateral_offset_mm": VERTEX[:2].tolist(),
            "eye_pose.relief_mm": float(-VERTEX[2]),
            "leds.count": 1,
            "leds.positions_mm": [LED_CENTRE.tolist()],
            "leds.directions": [aim.tolist()],
            "leds.body_diameter_mm": 2 * RB,
            "leds.body_shape": "sphere",  # the sphere of radius RB (the preset's a cylinder)
            "leds.body_length_mm": None,
            "leds.radiant_intensity_w_sr": I0,
            "leds.profile.kind": "cos_power",
            "leds.profile.half_intensity_angle_deg": HALF_ANGLE,
        },
    )
    cs = compile_scene(scene)
    assert not np.allclose(cs.frame.rotation, np.eye(3))  # a turned camera frame
    return scene, cs


def _reference(scene):
    """(rows, cols) bin means of E (W/mm²) and their spreads Δ_b, from the formula above."""
    m = math.log(0.5) / math.log(math.cos(math.radians(HALF_ANGLE)))
    axis = (VERTEX - LED_CENTRE) / np.linalg.norm(VERTEX - LED_CENTRE)
    emit = LED_CENTRE + RB * axis
    ep = scene.eye_plane
    bw, bh = ep.width_mm / ep.cols, ep.height_mm / ep.rows

    def irradiance(x, y):
        p = np.stack([VERTEX[0] + x, VERTEX[1] + y, np.full_like(x, VERTEX[2])], axis=-1)
        v = p - emit
        r = np.linalg.norm(v, axis=-1)
        cos_a = np.clip(v @ axis / r, 0.0, None)
        cos_b = -v[..., 2] / r
        return I0 * cos_a**m * cos_b / r**2

    mean = np.empty((ep.rows, ep.cols))
    spread = np.empty_like(mean)
    k = (np.arange(24) + 0.5) / 24
    for row in range(ep.rows):
        y0 = ep.height_mm / 2 - (row + 1) * bh  # row 0 at +y
        for col in range(ep.cols):
            x0 = -ep.width_mm / 2 + col * bw  # column 0 at −x
            xx, yy = np.meshgrid(x0 + k * bw, y0 + k * bh)
            mean[row, col] = irradiance(xx, yy).mean()
            cx = x0 + np.array([0, 1, 0, 1, 0.5]) * bw
            cy = y0 + np.array([0, 0, 1, 1, 0.5]) * bh
            e = irradiance(cx, cy)
            spread[row, col] = e.max() - e.min()
    return mean, spread, 2 * math.pi / (m + 1)


def test_forward_crossings_of_the_world_eye_plane_match_a_point_source(rig):
    scene, cs = rig
    mean, _, omega = _reference(scene)
    rays = 4_000_000
    res = eyelume.render(cs, eyelume.RenderOptions(rays=rays, seed=21))
    bin_area = (scene.eye_plane.width_mm / scene.eye_plane.cols) * (
        scene.eye_plane.height_mm / scene.eye_plane.rows
    )
    expected = rays * mean * bin_area / (I0 * omega)
    keep = expected >= 25
    n = int(keep.sum())
    assert n > 100  # most of the plane is lit
    chi2 = float(((res.plane_counts - expected)[keep] ** 2 / expected[keep]).sum())
    lo, hi = stats.chi2.ppf([0.001, 0.999], n)
    assert lo < chi2 < hi, f"χ² = {chi2:.0f} over {n} bins, outside [{lo:.0f}, {hi:.0f}]"


def test_fast_direct_irradiance_on_the_world_eye_plane_matches_a_point_source(rig):
    scene, cs = rig
    mean, spread, _ = _reference(scene)
    n_sub = 16
    got = direct_eye_plane(cs, seed=3, n_sub=n_sub)
    tol = 5 * spread / (2 * n_sub**2) + 1e-12 * mean.max()
    assert np.all(np.abs(got - mean) <= tol), np.max(np.abs(got - mean) / tol)
    assert np.mean(mean > 0) > 0.9  # the comparison covers the lit plane
