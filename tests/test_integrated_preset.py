"""The ``paper2005-integrated`` preset (issue 14; the paper's Fig. 1): the eye imaged through
a Thorlabs LA1131-B eyepiece and a 45° hot mirror onto an ideal camera.

* Its magnification from real chief rays (the camera's, folded by the mirror and refracted by
  the eyepiece, down to the eye plane z = 0) against a paraxial calculation written here: the
  y–nu trace of the plano-convex eyepiece (N-BK7 at 850 nm) gives the eye plane's virtual image
  (distance q before the plane side, magnification m_e); the fold keeps distances, so the camera
  sees it D = 50 − q away (20 mm eyepiece → mirror, 30 mm mirror → camera) and its thin lens
  (f, focused at s) images it with the chief-ray magnification v / D, v = 1/(1/f − 1/s).
* The preset's focus distance is that D (the picture is in focus on the eye plane).
* The truth: the four LEDs' glints seen, the pupil centred on the axis, ghosts searched.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

import eyelume
from eyelume.analysis.ghosts import _chief_ray
from eyelume.analysis.regions import region_masks
from eyelume.analysis.truth import _through_elements, eye_truth
from eyelume.compile import compile_scene
from eyelume.scene.glass import load_catalog


@pytest.fixture(scope="module")
def integrated():
    scene = eyelume.load_scene("paper2005-integrated")
    return scene, compile_scene(scene)


def _paraxial(scene):
    """(m_e, q, D): the eyepiece's magnification of the eye plane, its virtual image's
    distance from the plane side (negative: before it), the camera's object distance."""
    eyepiece, mirror = scene.elements
    n = load_catalog()["N-BK7"].index(scene.wavelength_nm)
    r1, t, z1 = eyepiece.front.radius_mm, eyepiece.thickness_mm, eyepiece.position_mm[2]

    def trace(y, u):  # y-nu: object plane z = 0 -> S1 (R1) -> S2 (plane), air after
        y = y + z1 * u
        u = (u - y * (n - 1) / r1) / n
        y = y + t * u
        return y, n * u

    y, u = trace(0.0, 1.0)
    q = -y / u
    h, uh = trace(1.0, 0.0)
    m_e = h + q * uh
    back = z1 + t
    to_mirror = mirror.position_mm[2] - back
    to_camera = math.dist(scene.camera.position_mm, mirror.position_mm)
    return m_e, q, to_mirror + to_camera - q


def test_focus_on_the_eyepiece_image_of_the_eye_plane(integrated):
    scene, _ = integrated
    m_e, q, d = _paraxial(scene)
    assert q < 0 and m_e > 1  # virtual, magnified: the eye inside the eyepiece's focal length
    assert scene.camera.ideal.focus_distance_mm == pytest.approx(d, abs=0.01)
    assert 20.0 <= scene.elements[0].position_mm[2] <= 70.0  # the paper's eye relief range


def test_magnification_against_the_paraxial_eyepiece_mirror_camera(integrated):
    scene, cs = integrated
    m_e, _, d = _paraxial(scene)
    f, s = scene.camera.ideal.efl_mm, scene.camera.ideal.focus_distance_mm
    v = 1.0 / (1.0 / f - 1.0 / s)
    expect = m_e * v / d
    eps = 0.005  # mm on the sensor (~2.5 pixels' worth): paraxial, central differences
    for axis in (0, 1):
        hits = []
        for sign in (-1.0, 1.0):
            xs = np.zeros(2)
            xs[axis] = sign * eps
            p, dvec = _chief_ray(cs, cs.camera, *xs)
            p, dvec = _through_elements(cs, p, dvec)
            pw, dw = cs.frame.world_point(p), cs.frame.world_vector(dvec)
            assert dw[2] < 0  # folded by the mirror, through the eyepiece, toward the eye
            hits.append(pw - pw[2] / dw[2] * dw)
        shift = np.linalg.norm(hits[1] - hits[0])
        assert 2 * eps / shift == pytest.approx(expect, rel=1e-4), axis  # 4e-6 found


def test_truth_glints_pupil_and_ghosts(integrated):
    scene, cs = integrated
    t = eye_truth(cs)
    assert t["glints_visible"] == 4
    cx, cy = t["pupil"]["centre_px"]
    assert cx == pytest.approx((scene.sensor.cols - 1) / 2, abs=0.01)
    assert cy == pytest.approx((scene.sensor.rows - 1) / 2, abs=0.01)
    assert "ghosts" in t and t["ghosts_visible"] == sum(g["visible"] for g in t["ghosts"])
    # the glints lie about the pupil centre, the four LEDs' layout (a ring about the axis)
    radii = [math.dist(g["centre_px"], (cx, cy)) for g in t["glints"]]
    assert max(radii) - min(radii) < 0.01 * max(radii)


def test_glint_layout_for_matching_follows_the_fold(integrated):
    """The layout the detector matches glints against (``led_picture_azimuths``): through the
    45° fold mirror the picture is mirrored left to right, so LED k at ring azimuth a_k (0° =
    +x, toward the nose) has its glint at picture azimuth 180° − a_k (the pinhole model of
    the camera without the elements put it at a_k, 0.32 × too close: every frame of
    evaluate-tracking then lost or mismatched glints)."""
    from eyelume.analysis.tracking.evaluate import led_picture_azimuths, led_picture_pattern

    scene, cs = integrated
    got = led_picture_azimuths(cs)
    for a, g in zip(scene.leds.azimuths(), got, strict=True):
        assert (g - (180.0 - a)) % 360.0 == pytest.approx(0.0, abs=0.5) or (
            g - (180.0 - a)
        ) % 360.0 == pytest.approx(360.0, abs=0.5)
    t = eye_truth(cs)
    seen = np.array([g["centre_px"] for g in t["glints"]], float)
    assert np.allclose(led_picture_pattern(cs), seen - seen.mean(axis=0), atol=1e-9)


def test_truth_through_the_fold_at_the_gaze_grids_edge(integrated):
    """evaluate-tracking's test grid reaches ±30°: there the picture's centre looks past the
    turned cornea's cap, and the truth's Newton solves for the pupil (from the straight guess,
    then the picture's centre) failed — no pupil and no glints in truth.json for the 10 frames
    at ±30°, nothing to compare detection with. Started from the point's image without the
    cornea they converge. The truth's pupil outline encloses the picture's pupil region (the
    render's surface map, an independent trace: their centroids within 0.5 px, a fraction of
    the region's pixelisation over its ~40 px outline) and the pupil moves across the picture
    mirrored by the fold (gaze toward +x: picture −x)."""
    from eyelume.analysis.regions import region_masks
    from eyelume.scene.io import apply_overrides

    scene, _ = integrated
    xs = []
    for h in (-30.0, 0.0, 20.0, 30.0):
        cs = compile_scene(apply_overrides(scene, {"eye.gaze_horizontal_deg": h}))
        t = eye_truth(cs, ghosts=False)
        assert t["pupil"]["centre_px"] is not None, h
        assert len(t["pupil"]["edge_px"]) == 72, h
        assert t["glints_visible"] == 4, h
        pupil = region_masks(cs, reflections=False)["pupil"]
        rows, cols = np.nonzero(pupil)
        m = cv2.moments(np.asarray(t["pupil"]["edge_px"], np.float32))  # the outline's area
        outline = (m["m10"] / m["m00"], m["m01"] / m["m00"])
        assert math.dist((cols.mean(), rows.mean()), outline) < 0.5, h
        xs.append(t["pupil"]["centre_px"][0])
    assert xs[0] > xs[1] > xs[2] > xs[3]


@pytest.mark.slow
@pytest.mark.parametrize("gaze", [(20.0, 0.0), (-20.0, 10.0)])
def test_tracking_frames_find_every_glint_at_its_truth(gaze):
    """evaluate-tracking's frame (render at 4 samples/pixel, sensor, detect) on
    paper2005-integrated: every LED's glint found, matched to its own LED through the fold's
    mirrored layout and within 1 px of the truth's, nothing else taken for a glint, and no
    pixel saturated but glints. With the preset's former 20 ms exposure 66 % of the pixels
    saturated (the iris hid the glints over it; saturated skin between dark areas was taken
    for glints), and with 16 light paths per pixel a glint got ~2–3 light paths, some none
    (at (20°, 0°) LEDs 0 and 1 had no glint in the picture)."""
    from eyelume.optimize.tracking import render_frame

    scene = eyelume.load_scene("paper2005-integrated")
    frame = render_frame(scene, *gaze, samples=4, seed=0)
    det = frame.detection
    assert det.ok, det.failures
    assert all(g.led is not None for g in det.glints), [g.centre_px for g in det.glints]
    truth = {g["led"]: g["centre_px"] for g in frame.truth["glints"] if g["visible"]}
    assert sorted(truth) == [0, 1, 2, 3]
    assert sorted(g.led for g in det.glints) == [0, 1, 2, 3]
    for g in det.glints:
        assert math.dist(g.centre_px, truth[g.led]) < 1.0, (g.led, g.centre_px, truth[g.led])
    pixels = scene.sensor.cols * scene.sensor.rows
    assert frame.saturated_share * pixels <= sum(g.area_px for g in det.glints)


def test_tracking_millimetres_see_through_the_eyepiece(integrated):
    """The tracking summary's millimetre figures (pupil error) take the eye plane's mm per
    pixel: through the eyepiece and the fold, the paraxial calculation's total magnification
    (eyepiece m_e × camera v / D), not the pinhole camera's own (2.46 × too small a scale);
    without elements the pinhole's, unchanged."""
    from eyelume.analysis.tracking.evaluate import picture_mm_per_px, pinhole_camera

    scene, cs = integrated
    m_e, _, d = _paraxial(scene)
    f, s = scene.camera.ideal.efl_mm, scene.camera.ideal.focus_distance_mm
    v = 1.0 / (1.0 / f - 1.0 / s)
    pitch = cs.picture.width_mm / cs.picture.cols
    assert picture_mm_per_px(scene) == pytest.approx(pitch / (m_e * v / d), rel=1e-4)
    paper = eyelume.load_scene("paper2005")
    assert picture_mm_per_px(paper) == pinhole_camera(paper).scale_mm


def test_no_geometric_gaze_through_elements(monkeypatch):
    """The geometric gaze model's pinhole camera looks straight at the eye: through the
    eyepiece and fold its answers were 108° off on average (not an approximation, a wrong
    answer). An element scene's summary has no geometric figure and says why; a scene without
    elements keeps the model."""
    import warnings

    from eyelume.analysis.tracking import evaluate as ev

    built = []
    real = ev.GeometricGaze

    def spy(*a, **k):
        built.append(1)
        return real(*a, **k)

    monkeypatch.setattr(ev, "GeometricGaze", spy)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # the means of no frames
        rep = ev.analyse_frames(
            eyelume.load_scene("paper2005-integrated"), np.zeros((4, 3)), [], []
        )
        assert not built
        g = rep.summary["gaze_geometric"]
        assert g["not_applicable"] == ev.GEOMETRIC_NOT_THROUGH_ELEMENTS and g["frames"] == 0
        rep = ev.analyse_frames(eyelume.load_scene("paper2005"), np.zeros((4, 3)), [], [])
        assert built and "not_applicable" not in rep.summary["gaze_geometric"]


# -- the fold as a beamsplitter (R ≤ T) and a hot mirror with its cut-off on the wrong side --

_TINY = {"sensor.cols": 40, "sensor.rows": 30}
_HOT_R = 0.92  # the preset's hot mirror at 850 nm (paper2005-integrated.toml)


def _fold(r: float | None = None, t: float | None = None, **more):
    """paper2005-integrated on a 40 × 30 picture, its hot mirror's R and T at 850 nm set."""
    sets = dict(_TINY)
    if r is not None:
        sets |= {
            "elements.1.front.coating.reflectance": r,
            "elements.1.front.coating.transmittance": t,
        }
    return eyelume.load_scene("paper2005-integrated", sets | more)


@pytest.fixture(scope="module")
def hot_render():
    cs = compile_scene(_fold())
    return cs, eye_truth(cs), eyelume.render(cs, eyelume.RenderOptions(samples_per_pixel=1, seed=5))


@pytest.mark.parametrize(("r", "t"), [(0.5, 0.5), (0.45, 0.55)])
def test_a_beamsplitter_fold_sees_the_eye_where_the_hot_mirror_does(hot_render, r, t):
    """A 45° beamsplitter in the hot mirror's place (R = T = 0.5, and R = 0.45 < T = 0.55)
    was refused ("sees no eye": the compile followed only the stronger branch, straight
    through into nothing). Both branches are followed now: the reflected one reaches the
    eye, so it compiles, the view is folded there (``view_branch`` 1 at the mirror), and the
    picture's geometry does not depend on R: the truth's pupil centre and glints, and the
    pupil, iris, sclera and skin masks (the geometric ones: the renders' own take out the
    glints' pixels as rendered), are the 92/8 mirror's. Its brightness does: the eye
    is lit straight by the LEDs (on the eye side of the eyepiece, none of their light meets
    the fold first) and seen once through the fold, so every region's mean scales by
    R / 0.92 (the eyepiece's two passes the same in both) — checked within 4 σ of the two
    renders' own reported errors of the means (same seed: correlated, so conservative)."""
    cs92, truth92, img92 = hot_render
    cs = compile_scene(_fold(r, t))
    mirror = cs.surface_names.index("element 1 (hot mirror) front")
    assert cs.view_branch[mirror] == 1
    truth = eye_truth(cs)
    np.testing.assert_allclose(
        truth["pupil"]["centre_px"], truth92["pupil"]["centre_px"], atol=1e-9
    )
    np.testing.assert_allclose(
        [g["centre_px"] for g in truth["glints"]],
        [g["centre_px"] for g in truth92["glints"]],
        atol=1e-9,
    )
    masks, masks92 = region_masks(cs, reflections=False), region_masks(cs92, reflections=False)
    img = eyelume.render(cs, eyelume.RenderOptions(samples_per_pixel=1, seed=5))
    got, ref = img.region_stats(), img92.region_stats()
    for name in ("pupil", "iris", "sclera", "skin"):
        assert np.array_equal(masks[name], masks92[name]), name
        a, b = got[name], ref[name]
        ratio = a["mean_w_mm2"] / b["mean_w_mm2"]
        sigma = ratio * math.hypot(a["mean_rel_error"], b["mean_rel_error"])
        assert abs(ratio - r / _HOT_R) < 4 * sigma, (name, ratio, r / _HOT_R, sigma)
