"""The eye in the headset: its pose (eye relief, lateral offset) and which eye it is.

Two independent checks of everything downstream of the pose (compile, truth, both estimators'
pictures, the eye-plane receiver):

* **Invariance under a common translation.** Moving the eye by d (``eye_pose``) and the camera
  and the LEDs by the same d leaves the scene the same up to a translation, so its camera-frame
  tables, hence the truth and the seeded renders, must agree. The tracers are deterministic for
  a seed and the tables differ only by the rounding of the translation (≈ 1e-15 mm), so the
  renders follow the same random paths: each pixel agrees within 1 % of its own standard
  error (rounding amplified by the glints' specular solves stays far below; a different scene
  would follow other paths and differ by ~1 σ).
* **A left eye is the mirror image of a right one** (x → −x about the headset's sagittal
  plane). Its truth must be the right eye's mirrored in the picture, column c ↦ (cols − 1) − c
  with the row unchanged, to the truth's root-solving tolerance; its render (other random
  paths: the scene is a different one) must agree with the right eye's flipped picture within
  the statistics of the two renders: z = (Σ_left − Σ_right) / √(Σvar_left + Σvar_right) over
  each half of the picture within ±4.5 (the nasal camera sees an asymmetric face, so a half
  that did not mirror would be off by far more).
"""

from __future__ import annotations

import numpy as np
import pytest

import eyelume
from eyelume.analysis.truth import eye_truth
from eyelume.compile import compile_scene
from eyelume.errors import SceneError
from eyelume.scene.io import apply_overrides, load_scene

#: vr-offaxis (an ideal camera 50° off the eye's axis, 8 LEDs) on an 80 × 80 chip of the same
#: size, so a seeded render is quick.
SMALL = {"sensor.cols": 80, "sensor.rows": 80, "sensor.pixel_pitch_um": 15.0}
D = np.array([1.5, -2.0, 3.0])  # mm


def _moved(base, d):
    cam = base.camera
    return {
        "eye_pose.lateral_offset_mm": [float(d[0]), float(d[1])],
        "eye_pose.relief_mm": float(-d[2]),
        "camera.position_mm": np.add(cam.position_mm, d).tolist(),
        "camera.look_at_mm": np.add(cam.look_at_mm, d).tolist(),
        "leds.ring_centre_mm": np.add(base.leds.ring_centre_mm, d).tolist(),
    }


@pytest.fixture(scope="module")
def pair():
    base = load_scene("vr-offaxis")
    gaze = {"eye.gaze_horizontal_deg": 8.0, "eye.gaze_vertical_deg": -5.0, **SMALL}
    a = apply_overrides(base, gaze)
    b = apply_overrides(base, {**gaze, **_moved(base, D)})
    return a, b


def _px(truth):
    pts = [truth["pupil"]["centre_px"]] + [g["centre_px"] for g in truth["glints"]]
    return np.array(pts, dtype=float)


def test_translating_eye_camera_and_leds_together_changes_no_truth(pair):
    a, b = pair
    ta, tb = eye_truth(compile_scene(a)), eye_truth(compile_scene(b))
    assert np.all(np.isfinite(_px(ta)))
    np.testing.assert_allclose(_px(tb), _px(ta), atol=1e-6)
    assert [g["visible"] for g in tb["glints"]] == [g["visible"] for g in ta["glints"]]
    np.testing.assert_allclose(tb["pupil"]["centre_mm"], np.add(ta["pupil"]["centre_mm"], D))


def test_translating_eye_camera_and_leds_together_changes_no_render(pair):
    a, b = pair
    opts = eyelume.RenderOptions(estimator="fast", samples_per_pixel=4, seed=5)
    ra, rb = eyelume.render(a, opts), eyelume.render(b, opts)
    sigma = np.sqrt(ra.eye_image_variance)
    assert ra.eye_image.mean() > 0 and np.mean(sigma > 0) > 0.5
    # the same random paths: every pixel within 1 % of its own standard error (other paths
    # would differ by ~1 σ; the translation's rounding, carried through the glints' specular
    # solves, moved one pixel in 6400 by 0.002 σ and the rest by < 1e-4 σ); a pixel with no
    # variance (the dark pupil) must be the same to 1e-9; the total to 1e-6. The diffraction
    # PSF (on for vr-offaxis) is convolved by FFT, whose round-off is ~1e-16 of the picture's
    # brightest pixel (a glint) in every pixel within its reach: 1e-14 of the peak allowed.
    diff = np.abs(rb.eye_image - ra.eye_image)
    fft_round_off = 1e-14 * ra.eye_image.max()
    assert np.all(diff <= 0.01 * sigma + 1e-9 * np.abs(ra.eye_image) + fft_round_off)
    assert rb.eye_image.sum() == pytest.approx(ra.eye_image.sum(), rel=1e-6)
    np.testing.assert_allclose(rb.eye_plane, ra.eye_plane, rtol=1e-9, atol=0)


def test_eye_pose_moves_the_eye_relative_to_a_fixed_camera():
    """The pose is not ignored: the eye moved 1 mm to +x (camera and LEDs fixed) moves its
    pupil's image by about 1 mm / pixel's size on the eye, toward the picture's +x as the
    camera sees it."""
    base = apply_overrides(load_scene("vr-offaxis"), SMALL)
    moved = apply_overrides(base, {"eye_pose.lateral_offset_mm": [1.0, 0.0]})
    p0 = np.array(eye_truth(compile_scene(base))["pupil"]["centre_mm"])
    p1 = np.array(eye_truth(compile_scene(moved))["pupil"]["centre_mm"])
    np.testing.assert_allclose(p1 - p0, [1.0, 0.0, 0.0], atol=1e-9)


def test_left_eye_truth_is_the_right_eyes_mirrored_in_the_picture():
    base = apply_overrides(
        load_scene("vr-offaxis"),
        {
            **SMALL,
            "eye.gaze_horizontal_deg": 10.0,
            "eye.gaze_vertical_deg": 4.0,
            "eye_pose.lateral_offset_mm": [1.0, -0.5],
            "eye_pose.relief_mm": 0.5,
        },
    )
    left = apply_overrides(base, {"eye_pose.which": "left"})
    tr, tl = eye_truth(compile_scene(base)), eye_truth(compile_scene(left))
    pr, pl = _px(tr), _px(tl)
    assert np.all(np.isfinite(pr))
    cols = base.sensor.cols
    np.testing.assert_allclose(pl[:, 0], (cols - 1) - pr[:, 0], atol=1e-6)
    np.testing.assert_allclose(pl[:, 1], pr[:, 1], atol=1e-6)
    assert [g["visible"] for g in tl["glints"]] == [g["visible"] for g in tr["glints"]]
    # the world positions mirror too (x → −x): the physical headset frame
    np.testing.assert_allclose(
        tl["pupil"]["centre_mm"], np.multiply(tr["pupil"]["centre_mm"], [-1, 1, 1]), atol=1e-9
    )
    assert tl["eye"] == "left"


def test_left_eye_render_is_the_right_eyes_flipped_within_statistics():
    # the traced pictures (no PSF): the sums' variances below take the pixels as independent
    sets = {**SMALL, "eye.gaze_horizontal_deg": 10.0, "camera.psf": "none"}
    base = apply_overrides(load_scene("vr-offaxis"), sets)
    left = apply_overrides(base, {"eye_pose.which": "left"})
    opts = eyelume.RenderOptions(estimator="fast", samples_per_pixel=16, seed=7)
    rr, rl = eyelume.render(base, opts), eyelume.render(left, opts)
    img_r, var_r = rr.eye_image[:, ::-1], rr.eye_image_variance[:, ::-1]
    half = base.sensor.cols // 2
    for cut in (np.s_[:, :half], np.s_[:, half:]):
        z = (rl.eye_image[cut].sum() - img_r[cut].sum()) / np.sqrt(
            rl.eye_image_variance[cut].sum() + var_r[cut].sum()
        )
        assert abs(z) < 4.5, z
    # the halves differ (the check above could not pass by symmetry alone)
    a, b = rr.eye_image[:, :half].sum(), rr.eye_image[:, half:].sum()
    sa = np.sqrt(rr.eye_image_variance[:, :half].sum() + rr.eye_image_variance[:, half:].sum())
    assert abs(a - b) > 10 * sa


@pytest.mark.parametrize(
    ("override", "field"),
    [
        ({"eye_pose.which": "middle"}, "eye_pose.which"),
        ({"eye_pose.relief_mm": float("nan")}, "eye_pose.relief_mm"),
        ({"eye_pose.lateral_offset_mm": [0.0, 1e9]}, "eye_pose.lateral_offset_mm"),
    ],
)
def test_bad_eye_pose_is_one_line_naming_the_field(override, field):
    with pytest.raises(SceneError) as err:
        apply_overrides(load_scene("vr-offaxis"), override)
    msg = str(err.value)
    assert "\n" not in msg and field in msg


def test_an_led_behind_the_moved_eye_plane_is_refused():
    """The LED–eye-plane check follows the eye: with 16 mm of relief the vertex is at
    z = −16, so the ring at z = 15 mm is clear of it, and a ring at z = −15.5 crosses it."""
    base = load_scene("vr-offaxis")
    ok = apply_overrides(base, {"eye_pose.relief_mm": 16.0, "camera.look_at_mm": [0, 0, -19.0]})
    compile_scene(ok)
    bad = apply_overrides(ok, {"leds.distance_mm": 0.5, "leds.ring_centre_mm": [0, 0, -16.0]})
    with pytest.raises(SceneError, match="crosses the eye plane z = -16"):
        compile_scene(bad)


def test_a_camera_that_sees_no_eye_follows_the_pose():
    """The camera is fixed in the headset; the eye moved 40 mm sideways leaves its view."""
    scene = apply_overrides(load_scene("vr-offaxis"), {"eye_pose.lateral_offset_mm": [-40.0, 0.0]})
    with pytest.raises(SceneError) as err:
        compile_scene(scene)
    assert "sees no eye" in str(err.value) and "\n" not in str(err.value)


def test_layout_and_info_follow_the_pose():
    """The layout's eye plane and cornea sit at the posed vertex; ``eyelume info`` reports it
    (mirrored for a left eye)."""
    from eyelume.info import scene_info
    from eyelume.layout import system_sections

    pose = {"eye_pose.lateral_offset_mm": [1.0, 2.0], "eye_pose.relief_mm": 3.0}
    scene = apply_overrides(load_scene("vr-offaxis"), pose)
    cs = compile_scene(scene)
    sections = {s.name: s for s in system_sections(cs, view="yz")}
    np.testing.assert_allclose(sections["eye plane"].z, [-3.0, -3.0])
    np.testing.assert_allclose(np.mean(sections["eye plane"].y), 2.0)
    cornea = sections["anterior cornea"]
    apex = np.argmax(cornea.z)
    assert cornea.z[apex] == pytest.approx(-3.0, abs=1e-3)
    assert cornea.y[apex] == pytest.approx(2.0, abs=0.05)
    eye = scene_info(scene)["eye"]
    np.testing.assert_allclose(eye["corneal_vertex_mm"], [1.0, 2.0, -3.0], atol=1e-12)
    left = scene_info(apply_overrides(scene, {"eye_pose.which": "left"}))
    np.testing.assert_allclose(left["eye"]["corneal_vertex_mm"], [-1.0, 2.0, -3.0], atol=1e-12)
    cam_r, cam_l = scene_info(scene)["camera"], left["camera"]
    np.testing.assert_allclose(cam_l["position_mm"], np.multiply(cam_r["position_mm"], [-1, 1, 1]))
