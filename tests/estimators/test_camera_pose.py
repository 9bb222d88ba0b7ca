"""A camera placed by a pose renders the scene it sees from there (issue: any headset).

* Rolled by 180° about its axis, the camera sees the same scene turned by 180°: the picture is
  the paper rig's picture turned (statistically, each pixel's own noise), its region masks too.
* Moved off the axis and aimed at the pupil, the pupil's true image lies at the picture's centre
  and the compiled scene holds the eye where the pose puts it (p_c = R (p − O), written out here).
"""

from __future__ import annotations

import numpy as np
import pytest

import eyelume
from eyelume.analysis.truth import eye_truth
from eyelume.compile import compile_scene
from eyelume.kernels import geometry as G
from eyelume.scene.io import apply_overrides

SPP = 24


@pytest.fixture(scope="module")
def base(paper_scene):
    return apply_overrides(paper_scene, {"run.samples_per_pixel": SPP, "run.seed": 7})


def test_roll_180_turns_the_picture(base):
    a = eyelume.render(base)
    again = eyelume.render(apply_overrides(base, {"run.seed": 8}))
    b = eyelume.render(apply_overrides(base, {"camera.roll_deg": 180.0}))
    turned = b.eye_image[::-1, ::-1]
    skin = a.regions["skin"] & b.regions["skin"][::-1, ::-1]
    # The reference is the same rig rendered again with another seed: the turned picture must
    # differ from the paper rig's no more than a re-render does. Over n skin pixels the spread
    # of the differences has a relative standard error ≈ 1/√(2n) (1 % here): allow 5 of them;
    # the mean difference must be within 5 standard errors of a mean of n.
    ref = (a.eye_image - again.eye_image)[skin]
    diff = (a.eye_image - turned)[skin]
    n = diff.size
    assert n > 3000
    assert abs(diff.std() / ref.std() - 1.0) < 5.0 / np.sqrt(2 * n)
    assert abs(diff.mean()) < 5.0 * diff.std() / np.sqrt(n)
    for name in ("iris", "sclera", "skin"):
        assert np.array_equal(a.regions[name], b.regions[name][::-1, ::-1]), name

    # the pupil less the glints' pixels (5 % of each noisy glint's peak): the union is exact
    def pupil_and_glints(r):
        return r.regions["pupil"] | np.any([m for k, m in r.regions.items() if "glint" in k], 0)

    assert np.array_equal(pupil_and_glints(a), pupil_and_glints(b)[::-1, ::-1])


def test_off_axis_camera_sees_the_eye_where_the_pose_puts_it(paper_scene):
    pupil = np.array([0.0, 0.0, -3.6])  # the Arizona eye's pupil centre, world mm
    position = np.array([0.0, -35.0, 60.6])  # 30° below the eye's axis
    scene = apply_overrides(
        paper_scene,
        {
            "camera.position_mm": position.tolist(),
            "camera.look_at_mm": pupil.tolist(),
            # the LEDs out of the way of the paper's large lens (25.8 mm semi-diameter)
            "leds.height_mm": 45.0,
            "leds.azimuths_deg": [45.0, 135.0, 225.0, 315.0],
        },
    )
    cs = compile_scene(scene)
    d = (pupil - position) / np.linalg.norm(pupil - position)
    x = np.cross(d, [0.0, 1.0, 0.0])
    x /= np.linalg.norm(x)
    r = np.stack([x, np.cross(-d, x), -d])
    o = position + scene.lens.object_distance_mm * d
    cornea = cs.surface_names.index("anterior cornea")
    assert np.allclose(cs.sf[cornea, G.OX : G.OZ + 1], r @ (np.zeros(3) - o), atol=1e-12)
    # world → cornea local = EYE_AXIS_ROT; camera frame → local = EYE_AXIS_ROT Rᵀ
    local = cs.sf[cornea, G.R00 : G.R22 + 1].reshape(3, 3)
    assert np.allclose(local @ r, np.diag([-1.0, 1.0, -1.0]), atol=1e-12)
    phi, th = np.radians(135.0), np.radians(20.0)
    axis = np.array([-np.sin(th) * np.cos(phi), -np.sin(th) * np.sin(phi), -np.cos(th)])
    led_world = np.array([45.0 * np.cos(phi), 45.0 * np.sin(phi), 70.0]) + 2.5 * axis
    assert np.allclose(cs.led.points[1], r @ (led_world - o), atol=1e-6)
    assert np.allclose(cs.led.axes[1], r @ axis, atol=1e-12)
    truth = eye_truth(cs)
    cols, rows = scene.sensor.cols, scene.sensor.rows
    # aimed at the pupil's centre: its apparent image sits at the picture's centre, to within
    # the cornea's refraction of an oblique view (the pupil seen 30° off the axis is displaced
    # toward the cornea's apex by well under a millimetre: < 2 px at 0.46 mm/px)
    cx, cy = truth["pupil"]["centre_px"]
    assert abs(cx - (cols - 1) / 2) < 0.5
    assert abs(cy - (rows - 1) / 2) < 2.0
    assert np.allclose(truth["pupil"]["centre_mm"], pupil, atol=1e-9)
    # the apparent pupil of an eye seen 30° below its axis is an ellipse squeezed vertically
    edge = np.asarray(truth["pupil"]["edge_px"])
    width = np.ptp(edge[:, 0])
    height = np.ptp(edge[:, 1])
    assert height / width == pytest.approx(np.cos(np.radians(30)), abs=0.08)
