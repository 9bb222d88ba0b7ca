"""The camera's pose (eyelume.scene.pose and the [camera] section): the world → camera-frame
transform against its definition, written out here by hand, and OpenCV's extrinsics."""

from __future__ import annotations

import math

import numpy as np
import pytest

from eyelume.errors import SceneError
from eyelume.scene.io import apply_overrides, load_scene
from eyelume.scene.pose import camera_frame, opencv_extrinsics


def test_paper_rig_is_the_identity():
    f = camera_frame((0.0, 0.0, 70.0), (0.0, 0.0, -70.0), 0.0, 70.0)
    assert np.array_equal(f.rotation, np.eye(3))
    assert np.array_equal(f.origin, np.zeros(3))
    assert f.is_identity


def test_default_camera_of_the_paper_scene_is_the_identity():
    scene = load_scene("paper2005")
    pos, view = scene.camera.pose(scene.lens.object_distance_mm)
    assert pos == (0.0, 0.0, 70.0)
    assert camera_frame(pos, view, 0.0, 70.0).is_identity


@pytest.mark.parametrize("roll", [0.0, 30.0, -125.0])
def test_off_axis_frame_against_its_definition(roll):
    # a camera below and to the nasal side, looking at a point behind the corneal vertex
    p = np.array([15.0, -20.0, 22.0])
    target = np.array([0.5, -0.3, -3.6])
    d = (target - p) / np.linalg.norm(target - p)
    f = camera_frame(p, target - p, roll, 31.0)
    r = f.rotation
    assert np.allclose(r @ r.T, np.eye(3), atol=1e-14)
    assert np.linalg.det(r) == pytest.approx(1.0, abs=1e-14)
    # z_c points from the scene to the camera
    assert np.allclose(r[2], -d, atol=1e-15)
    # without roll x_c is horizontal (world y component 0) and to the right as seen from the
    # camera; roll turns it by `roll` about z_c
    x0 = np.cross(d, [0.0, 1.0, 0.0])
    x0 /= np.linalg.norm(x0)
    y0 = np.cross(-d, x0)
    a = math.radians(roll)
    assert np.allclose(r[0], math.cos(a) * x0 + math.sin(a) * y0, atol=1e-14)
    assert y0[1] > 0  # the camera's up has world +y in it
    # the lens sits on the camera frame's z axis at the object distance
    assert np.allclose(f.point(p), [0.0, 0.0, 31.0], atol=1e-12)
    # and the look-at direction maps to −z
    assert np.allclose(f.vector(d), [0.0, 0.0, -1.0], atol=1e-14)
    # round trips
    q = np.array([[1.0, 2.0, 3.0], [-4.0, 5.0, -6.0]])
    assert np.allclose(f.world_point(f.point(q)), q, atol=1e-12)
    assert np.allclose(f.world_vector(f.vector(q)), q, atol=1e-12)


def test_looking_straight_down_uses_world_z_as_up():
    f = camera_frame((0.0, 40.0, 0.0), (0.0, -1.0, 0.0), 0.0, 40.0)
    assert np.all(np.isfinite(f.rotation))
    assert np.allclose(f.rotation @ f.rotation.T, np.eye(3), atol=1e-14)
    assert np.allclose(f.rotation[2], [0.0, 1.0, 0.0])


def test_opencv_extrinsics_project_like_a_pinhole():
    p = np.array([10.0, -25.0, 20.0])
    f = camera_frame(p, -p, 12.0, float(np.linalg.norm(p)))
    r, t = opencv_extrinsics(f, float(np.linalg.norm(p)))
    # the lens is the OpenCV origin; the looked-at point lies on +z at the object distance
    assert np.allclose(r @ p + t, 0.0, atol=1e-12)
    assert np.allclose(r @ np.zeros(3) + t, [0.0, 0.0, np.linalg.norm(p)], atol=1e-12)
    # OpenCV's y is down: a point above the target (world +y, camera roughly upright) has y < 0
    assert (r @ np.array([0.0, 5.0, 0.0]) + t)[1] < 0
    assert np.allclose(r @ r.T, np.eye(3), atol=1e-14)


@pytest.mark.parametrize(
    ("overrides", "field"),
    [
        (
            {"camera.position_mm": [0.0, 0.0, 40.0], "camera.look_at_mm": [0.0, 0.0, 40.0]},
            "look_at",
        ),
        ({"camera.direction": [0.0, 0.0, 0.0]}, "direction"),
        ({"camera.direction": [0.0, 0.0, -1.0], "camera.look_at_mm": [0.0, 0.0, 0.0]}, "not both"),
        ({"camera.roll_deg": float("nan")}, "roll_deg"),
    ],
)
def test_bad_poses_are_one_line_scene_errors(overrides, field):
    with pytest.raises(SceneError) as e:
        apply_overrides(load_scene("paper2005"), overrides)
    msg = str(e.value)
    assert "camera" in msg and field in msg and "\n" not in msg
