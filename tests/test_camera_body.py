"""The camera's body: an LED inside it is refused; it shadows light in both estimators.

The shadow test: the camera on the eye's axis 30 mm out, its body (4 mm across, 5 mm deep)
behind the lens, one LED 25 mm behind the body's back, 1.5 mm off the axis (an LED on the axis
behind the lens is refused as overlapping the lens), aimed along −z. From the LED's emission
point E the body's back disk (radius R, centre C) casts on the eye plane the disk of centre
E + (C − E)·s, radius R·s, s = E_z / (E_z − C_z); the front face's disk casts one inside it
(checked below), so that disk is the body's whole shadow. Bins wholly inside the shadow get no
direct light: the fast estimator's direct irradiance is exactly 0 there and the forward tracer
counts no crossing toward the eye (the face is off and the scene's other surfaces reflect light
away from the eye). Bins wholly outside it see the bare point source, I₀ cosᵐα cos β / r²
(written here), within the stratified-jitter bound of ``test_eye_plane_receiver.py``. Without
the body (``enabled = false``) the shadowed bins are lit to the same formula (but for the bin
the lens's own small aperture shadows).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from typer.testing import CliRunner

from eyelume.cli import app
from eyelume.compile import compile_scene
from eyelume.errors import SceneError
from eyelume.estimators.fast_run import direct_eye_plane
from eyelume.render import RenderOptions, render
from eyelume.scene.io import apply_overrides, load_scene

CAMERA_Z = 30.0
BODY_R, BODY_L = 2.0, 5.0
LED = np.array([1.5, 0.0, CAMERA_Z + BODY_L + 25.0])  # body centre, mm
RB = 0.8
I0 = 0.001
HALF = 60.0


def _scene(body_enabled=True):
    return apply_overrides(
        load_scene("vr-offaxis"),
        {
            "face.enabled": False,
            "camera.position_mm": [0.0, 0.0, CAMERA_Z],
            "camera.look_at_mm": [0.0, 0.0, 0.0],
            "camera.ideal.focus_distance_mm": CAMERA_Z,
            "camera.body": {
                "enabled": body_enabled,
                "diameter_mm": 2 * BODY_R,
                "length_mm": BODY_L,
            },
            "leds.count": 1,
            "leds.positions_mm": [LED.tolist()],
            "leds.directions": [[0.0, 0.0, -1.0]],
            "leds.body_diameter_mm": 2 * RB,
            "leds.body_shape": "sphere",  # the sphere of radius RB (the preset's a cylinder)
            "leds.body_length_mm": None,
            "leds.radiant_intensity_w_sr": I0,
            "leds.profile.half_intensity_angle_deg": HALF,
        },
    )


def _shadow(z_disk, radius=BODY_R):
    """Centre (x, y) and radius of the shadow on the eye plane of an on-axis disk at z."""
    e = LED + RB * np.array([0.0, 0.0, -1.0])
    s = e[2] / (e[2] - z_disk)
    return e[:2] + (0.0 - e[:2]) * s, radius * s


def _bins(scene, centre):
    """Per bin: the point-source mean (24 × 24 midpoint rule), the spread Δ_b, and its nearest
    and farthest distance from the shadow's ``centre``."""
    m = math.log(0.5) / math.log(math.cos(math.radians(HALF)))
    emit = LED + RB * np.array([0.0, 0.0, -1.0])
    ep = scene.eye_plane
    bw, bh = ep.width_mm / ep.cols, ep.height_mm / ep.rows

    def irradiance(x, y):
        v = np.stack([x, y, np.zeros_like(x)], axis=-1) - emit
        r = np.linalg.norm(v, axis=-1)
        cos = -v[..., 2] / r  # the LED's axis is −z, the plane's normal +z: α = β
        return I0 * cos**m * cos / r**2

    k = (np.arange(24) + 0.5) / 24
    mean, spread = np.empty((ep.rows, ep.cols)), np.empty((ep.rows, ep.cols))
    rmin, rmax = np.empty_like(mean), np.empty_like(mean)
    for row in range(ep.rows):
        y0 = ep.height_mm / 2 - (row + 1) * bh
        for col in range(ep.cols):
            x0 = -ep.width_mm / 2 + col * bw
            xx, yy = np.meshgrid(x0 + k * bw, y0 + k * bh)
            mean[row, col] = irradiance(xx, yy).mean()
            cx, cy = x0 + np.array([0, 1, 0, 1, 0.5]) * bw, y0 + np.array([0, 0, 1, 1, 0.5]) * bh
            e = irradiance(cx, cy)
            spread[row, col] = e.max() - e.min()
            # nearest and farthest points of the bin from the shadow's centre
            nx = np.clip(centre[0], x0, x0 + bw) - centre[0]
            ny = np.clip(centre[1], y0, y0 + bh) - centre[1]
            rmin[row, col] = math.hypot(nx, ny)
            rmax[row, col] = max(
                math.hypot(px - centre[0], py - centre[1])
                for px in (x0, x0 + bw)
                for py in (y0, y0 + bh)
            )
    return mean, spread, rmin, rmax


@pytest.fixture(scope="module")
def shadow():
    scene = _scene()
    centre, shadow_r = _shadow(CAMERA_Z + BODY_L)
    front_c, front_r = _shadow(CAMERA_Z)
    assert np.hypot(*(front_c - centre)) + front_r < shadow_r  # the back disk's shadow is all
    return scene, shadow_r, _bins(scene, centre)


def test_the_body_shadows_the_eye_plane_in_both_estimators(shadow):
    scene, shadow_r, (mean, spread, rmin, rmax) = shadow
    cs = compile_scene(scene)
    inside, outside = rmax < shadow_r, rmin > shadow_r
    assert inside.sum() >= 9 and outside.sum() > 100
    n_sub = 16
    fast = direct_eye_plane(cs, seed=2, n_sub=n_sub)
    assert np.all(fast[inside] == 0.0)
    tol = 5 * spread / (2 * n_sub**2) + 1e-12 * mean.max()
    assert np.all(np.abs(fast - mean)[outside] <= tol[outside])
    fwd = render(cs, RenderOptions(rays=400_000, seed=4))
    assert np.all(fwd.plane_counts[inside] == 0)
    assert fwd.ledger["camera body"] > 0
    # the bins in the shadow would get 400k · p_b ≫ 1 rays without the body
    area = (scene.eye_plane.width_mm / scene.eye_plane.cols) ** 2
    m = math.log(0.5) / math.log(math.cos(math.radians(HALF)))
    expected = 400_000 * mean * area / (I0 * 2 * math.pi / (m + 1))
    assert expected[inside].min() > 50


def test_without_the_body_the_shadow_is_lit(shadow):
    scene, shadow_r, (mean, spread, rmin, rmax) = shadow
    cs = compile_scene(_scene(body_enabled=False))
    assert "camera body" not in cs.tallies
    n_sub = 16
    fast = direct_eye_plane(cs, seed=2, n_sub=n_sub)
    tol = 5 * spread / (2 * n_sub**2) + 1e-12 * mean.max()
    # the lens itself (its 0.29 mm clear aperture, the camera's entrance) still shadows a
    # ~0.6 mm spot: leave out the bin(s) it touches
    lens_c, lens_r = _shadow(CAMERA_Z, scene.camera.ideal.pupil_radius_mm)
    _, _, lens_rmin, _ = _bins(scene, lens_c)
    keep = lens_rmin > lens_r
    assert (~keep).sum() <= 4 and (keep & (rmax < shadow_r)).sum() >= 9
    assert np.all(np.abs(fast - mean)[keep] <= tol[keep])


def test_an_ideal_camera_has_a_default_body_and_the_paper_none():
    assert "camera body" in compile_scene(load_scene("vr-offaxis")).tallies
    assert "camera body" not in compile_scene(load_scene("paper2005")).tallies


def test_an_led_inside_the_camera_body_is_one_line_exit_2(tmp_path):
    inside = {
        "leds.count": 1,
        # 3 mm behind the lens along its axis, 2 mm off it (inside the 6 × 5 mm default body)
        "leds.positions_mm": [[22.66, -11.309, 23.0]],
        "leds.directions": [[0.0, 0.0, -1.0]],
    }
    with pytest.raises(SceneError) as err:
        compile_scene(apply_overrides(load_scene("vr-offaxis"), inside))
    msg = str(err.value)
    assert "inside the camera body" in msg and "camera.body" in msg and "LED 0" in msg
    assert "\n" not in msg
    args = ["info", "--scene", "vr-offaxis"]
    for k, v in inside.items():
        args += ["--set", f"{k}={v}".replace(" ", "")]
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 2, res.output
    assert "inside the camera body" in res.output


def test_a_body_narrower_than_the_lens_is_refused():
    scene = apply_overrides(load_scene("vr-offaxis"), {"camera.body.diameter_mm": 0.2})
    with pytest.raises(SceneError, match="camera.body.diameter_mm = 0.2"):
        compile_scene(scene)
