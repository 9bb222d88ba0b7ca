"""Glints and pupil seen by an off-axis camera, against computations written out here
(issue: any headset).

For the ``vr-offaxis`` preset (an ideal lens 50° off the eye's axis) with the eye turned, each
LED's glint is where the chief ray — through the centre of the ideal lens, undeviated — meets
the cornea at the point P where the LED's light reflects toward the lens. P is found here by
Fermat's principle (P on the anterior corneal conicoid makes |LED − P| + |P − lens| stationary;
the convex mirror makes it a minimum) with SciPy, and projected by OpenCV's ``projectPoints``
with the intrinsics and extrinsics ``eyelume info`` reports: an independent check of
``truth.json`` and of the OpenCV export, with and without radial distortion.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from scipy import optimize

from eyelume.analysis.truth import eye_truth
from eyelume.compile import compile_scene
from eyelume.info import camera_info
from eyelume.scene.io import apply_overrides, load_scene
from eyelume.scene.sources import led_poses

GAZE = {"eye.gaze_horizontal_deg": 12.0, "eye.gaze_vertical_deg": -8.0}


def _rot(h_deg: float, v_deg: float) -> np.ndarray:
    """The gaze rotation of ARCHITECTURE.md §2: about x by −v (up positive), then about y by h."""
    v, h = math.radians(v_deg), math.radians(h_deg)
    rx = np.array([[1, 0, 0], [0, math.cos(-v), -math.sin(-v)], [0, math.sin(-v), math.cos(-v)]])
    ry = np.array([[math.cos(h), 0, math.sin(h)], [0, 1, 0], [-math.sin(h), 0, math.cos(h)]])
    return ry @ rx


def _cornea_point(scene, r: np.ndarray, a: float, b: float) -> np.ndarray:
    """World point of the anterior cornea at eye-frame (x′, y′) = (a, b), the eye turned by r."""
    s = scene.eye.surfaces[0]
    c, k = 1.0 / s.radius_mm, s.conic
    rr = a * a + b * b
    z_eye = c * rr / (1.0 + math.sqrt(1.0 - (1.0 + k) * c * c * rr))
    p = np.array([-a, b, -z_eye])  # eye frame (x′ = −x, z′ = −z) → primary-gaze world
    centre = np.array([0.0, 0.0, -scene.eye.rotation_centre_mm])
    return centre + r @ (p - centre)


@pytest.mark.parametrize(
    ("k1", "model"),
    [(0.0, "arizona"), (-0.2, "arizona"), (0.0, "navarro1999"), (0.0, "legrand1980")],
)
def test_glints_of_an_off_axis_camera_and_a_turned_eye(k1, model):
    # every library eye (issue 15): its own anterior cornea (Navarro 7.72 mm, k −0.26; Le Grand
    # 7.8 mm, a sphere) places the glints
    overrides = {**GAZE, "camera.ideal.k1": k1, "eye.model": model}
    scene = load_scene("vr-offaxis", overrides)
    assert scene.eye.model == model
    cs = compile_scene(scene)
    truth = eye_truth(cs)
    info = camera_info(cs)["opencv"]
    k_mat = np.array(info["K"])
    r_mat, t_vec = np.array(info["R"]), np.array(info["t_mm"])
    dist = np.array(info["dist"] + [0.0])  # k1, k2, p1, p2, k3
    lens = np.array(scene.camera.position_mm)  # the ideal lens: its centre is the chief ray's
    r = _rot(scene.eye.gaze_horizontal_deg, scene.eye.gaze_vertical_deg)
    centres, axes = led_poses(scene.leds)
    # light leaves a cylinder's front face's centre (a sphere's apex): half its length on
    emit = centres + axes * scene.leds.body_length_mm / 2
    assert scene.leds.body_shape == "cylinder"
    checked = 0
    for k, led in enumerate(emit):
        g = truth["glints"][k]
        res = optimize.minimize(
            lambda ab, led=led: (
                np.linalg.norm(led - _cornea_point(scene, r, *ab))
                + np.linalg.norm(lens - _cornea_point(scene, r, *ab))
            ),
            x0=np.zeros(2),
            method="Nelder-Mead",
            options={"xatol": 1e-10, "fatol": 1e-13, "maxiter": 4000},
        )
        p = _cornea_point(scene, r, *res.x)
        on_cap = math.hypot(*res.x) < scene.eye.surfaces[0].semi_diameter_mm
        if not on_cap:
            assert g["centre_px"] is None
            continue
        px, _ = cv2.projectPoints(p.reshape(1, 1, 3), cv2.Rodrigues(r_mat)[0], t_vec, k_mat, dist)
        assert g["centre_px"] is not None, f"LED {k}"
        # Newton to 1e-7 mm on the sensor (3 µm pixels) and Nelder–Mead to 1e-10 mm on the eye
        assert np.allclose(g["centre_px"], px.ravel(), atol=2e-3), (k, g["centre_px"], px)
        checked += 1
    assert checked >= 6  # most of the ring's glints lie on the cornea at this gaze


def test_pupil_centre_of_an_off_axis_camera_projects_through_the_cornea():
    """The apparent pupil centre is the image of the pupil's centre refracted by the cornea: it
    lies off the straight projection of the 3D centre, toward the corneal apex, by less than
    the cornea's refraction can shift it (a few tenths of a millimetre, ≈ 5 px here)."""
    scene = apply_overrides(load_scene("vr-offaxis"), GAZE)
    cs = compile_scene(scene)
    truth = eye_truth(cs)
    info = camera_info(cs)["opencv"]
    centre = np.array(truth["pupil"]["centre_mm"])
    px, _ = cv2.projectPoints(
        centre.reshape(1, 1, 3),
        cv2.Rodrigues(np.array(info["R"]))[0],
        np.array(info["t_mm"]),
        np.array(info["K"]),
        np.zeros(5),
    )
    shift = np.hypot(*(np.array(truth["pupil"]["centre_px"]) - px.ravel()))
    assert 0.5 < shift < 15.0


def test_ring_glints_slide_off_the_cornea_as_the_eye_turns_away():
    """vr-offaxis: the camera sits nasal (+x) and low; turning the eye 20° temporally (−x, away
    from the camera) moves ring glints off the corneal cap, toward the camera keeps them."""
    from eyelume.analysis.truth import glint_counts

    counts = glint_counts(load_scene("vr-offaxis"), gaze_h=(-20.0, 0.0, 20.0), gaze_v=(0.0,))
    on = counts["on_cornea"][0]
    assert counts["leds"] == 8
    assert on[1] == 8  # primary gaze: every LED's glint on the cornea
    assert on[0] < 8  # away from the camera: some slide off
    assert on[2] == 8  # toward the camera: none do
    assert all(v <= o for v, o in zip(counts["visible"][0], on, strict=True))


def test_leds_a_wide_lens_sees_directly_are_in_the_truth_and_the_picture():
    """eyetrackvr's 130° lens sits beside its LED ring and sees all four LEDs directly. Each
    one's truth pixel is the OpenCV projection of its emission point (the ideal lens's chief ray
    is undeviated: a pinhole at the lens's centre); its radiant intensity toward the lens is
    I₀ · I(α)/I₀ at the angle α between the LED's axis and the lens, computed here from the
    scene's profile; and in a render the brightest pixel near each truth position is within a
    pixel of it (the LED's own point image, blurred by defocus: it is 10–20 mm from the lens,
    focused at 27.7 mm)."""
    import eyelume
    from eyelume.scene.sources import relative_intensity

    scene = load_scene("eyetrackvr")
    cs = compile_scene(scene)
    truth = eye_truth(cs)
    info = camera_info(cs)["opencv"]
    centres, axes = led_poses(scene.leds)
    emit = centres + axes * scene.leds.body_diameter_mm / 2
    px, _ = cv2.projectPoints(
        emit.reshape(-1, 1, 3),
        cv2.Rodrigues(np.array(info["R"]))[0],
        np.array(info["t_mm"]),
        np.array(info["K"]),
        np.zeros(5),
    )
    px = px.reshape(-1, 2)
    seen = {e["led"]: e for e in truth["leds_in_view"]}
    assert sorted(seen) == [0, 1, 2, 3]
    lens = np.array(scene.camera.position_mm)
    profile = relative_intensity(scene.leds.profile)
    for k, e in seen.items():
        assert np.allclose(e["centre_px"], px[k], atol=2e-3), (k, e["centre_px"], px[k])
        to_lens = (lens - emit[k]) / np.linalg.norm(lens - emit[k])
        alpha = math.acos(float(to_lens @ axes[k]))
        want = scene.leds.radiant_intensity_w_sr * float(profile(np.array(alpha)))
        # the kernels' profile is a table linear in α: within 1e-3 of the closed form
        assert e["radiant_intensity_toward_lens_w_sr"] == pytest.approx(want, rel=1e-3)
        assert e["visible"]
    # the render at 1/4 of the resolution (60 × 60, 44 µm pixels)
    small = compile_scene(
        apply_overrides(scene, {"sensor.cols": 60, "sensor.rows": 60, "sensor.pixel_pitch_um": 44})
    )
    img = eyelume.render(
        small, eyelume.RenderOptions(estimator="fast", samples_per_pixel=4, seed=3)
    ).eye_image
    for e in eye_truth(small)["leds_in_view"]:
        c, r = e["centre_px"]
        r0, c0 = int(round(r)), int(round(c))
        win = img[max(r0 - 3, 0) : r0 + 4, max(c0 - 3, 0) : c0 + 4]
        rr, cc = np.unravel_index(np.argmax(win), win.shape)
        peak = (max(c0 - 3, 0) + cc, max(r0 - 3, 0) + rr)
        assert math.hypot(peak[0] - c, peak[1] - r) < 1.5, (e, peak)
        assert win.max() > 20 * np.median(img)  # a bright spot, not skin


@pytest.mark.parametrize("which", ["right", "left"])
def test_info_gives_the_cameras_view_direction_as_a_unit_vector(which):
    """vr-offaxis gives a look-at point: ``view_direction`` is the unit vector from the
    camera's position toward it (the file's 20.785, −12, 20 mm → 0, 0, −3 mm, mirrored in x for
    a left eye), and OpenCV's camera z axis (R's third row) is that same vector."""
    scene = load_scene("vr-offaxis", {"eye_pose.which": which})
    cam = camera_info(compile_scene(scene))
    way = np.subtract(scene.camera.look_at_mm, scene.camera.position_mm)
    if which == "left":
        way[0] = -way[0]
    np.testing.assert_allclose(cam["view_direction"], way / np.linalg.norm(way), atol=1e-12)
    np.testing.assert_allclose(cam["opencv"]["R"][2], cam["view_direction"], atol=1e-12)
