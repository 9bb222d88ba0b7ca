"""A tracking frame is rendered without the eye plane's receiver (``render_budget.NO_EYE_PLANE``,
one bin): the picture it digitises and analyses is the one the scene's full receiver gives, bit
for bit, and so is the sensor-noise pilot's target."""

from __future__ import annotations

import numpy as np

import eyelume
from eyelume.analysis.truth import optical_gaze_for
from eyelume.detectors.sensor import digitize
from eyelume.optimize.render_budget import NO_EYE_PLANE, sensor_noise_target
from eyelume.optimize.tracking import render_frame
from eyelume.render import RenderOptions, render
from eyelume.scene.io import apply_overrides


def test_a_frame_without_the_eye_plane_digitises_the_same_picture():
    scene = eyelume.load_scene("paper2005")
    h, v, spp, seed = 10.0, -5.0, 8, 2
    frame = render_frame(scene, h, v, spp, seed, keep_picture=True)
    gh, gv = optical_gaze_for(scene, h, v)
    sc = apply_overrides(scene, {"eye.gaze_horizontal_deg": gh, "eye.gaze_vertical_deg": gv})
    assert sc.eye_plane.cols * sc.eye_plane.rows > 1  # the full receiver, as before
    full = render(sc, RenderOptions(estimator="fast", samples_per_pixel=spp, seed=seed))
    counts = digitize(full.eye_image_at_scene_wavelength, sc.sensor, sc.wavelength_nm, seed).counts
    assert np.array_equal(frame.picture["counts"], counts)


def test_the_pilot_target_does_not_depend_on_the_eye_plane():
    scene = eyelume.load_scene("paper2005")
    small = apply_overrides(scene, NO_EYE_PLANE)
    wide = apply_overrides(scene, {"eye_plane.cols": 41, "eye_plane.rows": 31})
    assert sensor_noise_target(small, 4) == sensor_noise_target(wide, 4)
