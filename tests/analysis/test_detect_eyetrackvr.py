"""The ``eyetrackvr`` preset (issue 11): a 130° lens on a 240 × 240 chip sees a 9 px pupil at the
black level, glints of one saturated pixel each, the LED bodies and lit skin brighter than the
glints once smoothed. Before, ``detect`` answered none of its 35 test frames (the pupil's
outline hidden by skin patches taken for glints, the pupil merged with its iris on the ladder's
3× reduced picture, the glints lost to the smoothing and the LED bodies matched instead).

Checked: on synthetic pictures, that one-pixel glints next to a small pupil are found and
matched to their LEDs and that a speck over the lit lid is not taken for one; on the preset's
own renders (8 samples per pixel, seed 0, as ``eyelume evaluate-tracking --scene eyetrackvr
--samples 8 --seed 0``), that frames are answered and that every answer is right: the pupil
within 0.5 px of the truth (issue 13's bound for eyelume's renders) and every matched glint
within 1 px of its own LED's glint in ``truth.json``.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

import eyelume
from eyelume.analysis.tracking import detect
from eyelume.analysis.tracking.evaluate import (
    _truth_ellipse_centre,
    led_picture_azimuths,
    led_picture_pattern,
)
from eyelume.analysis.truth import eye_truth
from eyelume.compile import compile_scene
from eyelume.detectors.sensor import digitize
from eyelume.render import RenderOptions, render

GLINTS = ((127, 119), (120, 113), (114, 121), (121, 126))  # LEDs at 0°, 90°, 180°, 270°
CENTRE = (120.3, 119.6)


def _picture(speck=None, seed=0) -> np.ndarray:
    """240 × 240 DN: an unlit black surround (4 DN) touching the border, a lit face (190 DN),
    the eye's opening (120 DN), an iris (20 DN, 22 px across) and a pupil at the black level
    (9.2 × 8.4 px, centred at CENTRE), blurred (σ 0.6 px), a saturated patch of lid below the
    iris (60 px), noise σ 1 DN; each glint one saturated pixel (254) whose four neighbours the
    optics' spread lights by 20 DN. ``speck`` (x, y): one pixel at 215 DN, its neighbours
    10 DN over their surround."""
    rng = np.random.default_rng(seed)
    img = np.full((240, 240), 4.0)
    cv2.ellipse(img, ((130.0, 130.0), (150.0, 120.0), 20.0), 190.0, -1)
    cv2.ellipse(img, ((121.0, 119.0), (40.0, 24.0), 0.0), 120.0, -1)
    s = 10  # the iris and pupil drawn 10× finer, then averaged: sub-pixel edges
    y, x = (np.mgrid[0 : 240 * s, 0 : 240 * s] + 0.5) / s - 0.5
    iris = (x - CENTRE[0]) ** 2 + (y - CENTRE[1]) ** 2 <= 11.0**2
    pupil = (x - CENTRE[0]) ** 2 / 4.6**2 + (y - CENTRE[1]) ** 2 / 4.2**2 <= 1.0
    fi = iris.reshape(240, s, 240, s).mean(axis=(1, 3))
    fp = pupil.reshape(240, s, 240, s).mean(axis=(1, 3))
    img = img * (1 - fi) + 20.0 * (fi - fp) + 4.0 * fp
    img = cv2.GaussianBlur(img, (0, 0), 0.6)
    cv2.ellipse(img, ((121.0, 134.0), (14.0, 6.0), 0.0), 250.0, -1)
    img += rng.normal(0.0, 1.0, img.shape)
    spots = [(g, 254.0, 20.0) for g in GLINTS]
    if speck is not None:
        spots.append((speck, None, 10.0))
    for (gx, gy), peak, shoulder in spots:
        img[gy, gx] = 215.0 if peak is None else peak
        for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            img[gy + dy, gx + dx] += shoulder
    return np.clip(np.rint(img), 0, 254).astype(np.uint16)


def _assert_glints_on_their_leds(d) -> None:
    assert d.ok, d.failures
    assert math.hypot(d.pupil.centre_px[0] - CENTRE[0], d.pupil.centre_px[1] - CENTRE[1]) < 0.3
    matched = {g.led: g.centre_px for g in d.glints if g.led is not None}
    assert sorted(matched) == [0, 1, 2, 3]
    for k, (gx, gy) in enumerate(GLINTS):
        # one pixel with symmetric shoulders: its centroid is the pixel (noise: ≲ 0.1 px)
        assert math.hypot(matched[k][0] - gx, matched[k][1] - gy) < 0.2, (k, matched[k])


def test_one_pixel_glints_beside_a_small_pupil_found_and_matched():
    # Smoothed (σ 0.5 px at 240 rows) each glint peaks at ~0.6 × 254, under the lit face's
    # 99th percentile: before, none was found (and the lid patch was the only "glint").
    _assert_glints_on_their_leds(detect(_picture(), led_azimuths_deg=[0, 90, 180, 270]))


def test_a_speck_over_the_lid_is_no_glint():
    # 25 DN over the lit face just above the eye's opening, 16 px from the pupil: above the
    # picture's 99th percentile and halfway from its box mean (face and opening mixed) to the
    # top, but not halfway from its own background (190 DN) to the top: no glint, and the four
    # are still matched (taken for one, it was matched to LED 1 and the frame refused).
    d = detect(_picture(speck=(121, 104)), led_azimuths_deg=[0, 90, 180, 270])
    _assert_glints_on_their_leds(d)
    assert all(math.hypot(g.centre_px[0] - 121, g.centre_px[1] - 104) > 2 for g in d.glints)


def test_a_dim_one_pixel_spot_is_not_sought_unsmoothed():
    # 215 DN on the iris, 6 px from the pupil: the smoothing takes it under the glint floor,
    # as the glints; unsmoothed it is above the floor and stands out of the iris, but it is
    # not at the top of the scale, where a glint holding its LED's light in one pixel is
    # (within 2 %): not added (vr-offaxis at (0°, −20°) matched such a pixel of lit skin to
    # an LED whose glint the lid hides).
    d = detect(_picture(speck=(126, 124)), led_azimuths_deg=[0, 90, 180, 270])
    _assert_glints_on_their_leds(d)
    assert all(math.hypot(g.centre_px[0] - 126, g.centre_px[1] - 124) > 2 for g in d.glints)


def _render(h: float, v: float):
    sc = eyelume.load_scene(
        "eyetrackvr", {"eye.gaze_horizontal_deg": h, "eye.gaze_vertical_deg": v}
    )
    cs = compile_scene(sc)
    r = render(cs, RenderOptions(estimator="fast", samples_per_pixel=8, seed=0))
    counts = digitize(r.eye_image_at_scene_wavelength, sc.sensor, sc.wavelength_nm, 0).counts
    d = detect(
        counts, led_azimuths_deg=led_picture_azimuths(cs), led_pattern_px=led_picture_pattern(cs)
    )
    return d, eye_truth(cs)


def _right(d, truth) -> bool:
    """Whether ``d`` is ok; if it is, its pupil within 0.5 px and each matched glint within 1 px
    of its own LED's glint in the truth (assertions)."""
    if not d.ok:
        return False
    cx, cy = _truth_ellipse_centre(truth)
    assert math.hypot(d.pupil.centre_px[0] - cx, d.pupil.centre_px[1] - cy) <= 0.5, d.pupil
    spots = {g["led"]: g["centre_px"] for g in truth["glints"] if g["visible"]}
    for g in d.glints:
        if g.led is not None:
            assert g.led in spots, (g, "that LED has no glint in the truth")
            tx, ty = spots[g.led]
            assert math.hypot(g.centre_px[0] - tx, g.centre_px[1] - ty) <= 1.0, (g, spots)
    return True


@pytest.mark.slow
def test_eyetrackvr_renders_answered_and_right():
    # (0°, 0°): the frame; (10°, −10°), (20°, 10°), (−10°, −10°): four glints each;
    # (10°, −20°): the small pupil's blob notched by its one-pixel glints until they are filled
    # (find_pupil's ``sharp`` glints); (0°, 20°) and (30°, 20°): two glints on the cornea — too
    # few with two LEDs missing, refused (a wrong LED pair was matched at (30°, 20°) and must
    # not be answered).
    gazes = [(0, 0), (10, -10), (20, 10), (10, -20), (-10, -10), (0, 20), (30, 20)]
    answered = {g: _right(*_render(*g)) for g in gazes}
    assert all(answered[g] for g in [(0, 0), (10, -10), (20, 10), (10, -20)]), answered
    assert sum(answered.values()) >= 4
