"""The camera's pose: the rigid transform from the world frame to the camera's frame.

A left eye's scene is the mirror image of the file (x → −x, :func:`as_world`,
:func:`led_world_poses`; :class:`eyelume.scene.model.EyePose`).

The world frame (ARCHITECTURE.md §2) is the headset's: +z out of the eye toward the headset, +y
up, the eye's anterior corneal vertex in primary gaze at its pose (the origin by default;
:class:`eyelume.scene.model.EyePose`; a left eye's camera pose is mirrored first,
:func:`eyelume.compile.camera_pose`). The camera is placed in it
by ``[camera]`` (:class:`eyelume.scene.model.Camera`): the position of its lens (the first
vertex of a prescription), the point it looks at (or a direction) and a roll about its viewing
axis.

Everything the kernels trace is compiled into the **camera frame** (pbrt-v4 renders in a
"camera-world" space for the same reason: the lens stays a rotationally symmetric system on the
z axis, so the sequential lens trace, the picture grid and the camera-side estimator need no
change for a camera anywhere):

* +z_c = −d̂, the unit vector from the looked-at point toward the camera (d̂ the viewing
  direction);
* +x_c = d̂ × ŷ_w / |d̂ × ŷ_w| (to the right as seen from the camera, with world +y up; world +z
  replaces ŷ_w when the camera looks straight up or down), then turned with +y_c = ẑ_c × x̂_c by
  ``roll_deg`` about +z_c (right-handed: a positive roll turns x̂_c toward ŷ_c);
* origin O = P + L d̂: the point on the viewing axis at the lens's object distance L
  (``lens.object_distance_mm``) in front of the lens position P, so the lens's first vertex is
  at z_c = L as in the paper's rig.

A world point p has camera-frame coordinates p_c = R (p − O), R the matrix whose rows are
x̂_c, ŷ_c, ẑ_c. The paper's rig (camera at (0, 0, L) looking at the origin, no roll) is the
identity: R = I, O = 0.

OpenCV's camera frame (x right, y down, z forward along the view) is (x_c, −y_c, z₀ − z_c)
measured from a point z₀ of the lens axis: :func:`opencv_extrinsics` gives its rotation and
translation.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from eyelume.errors import GeometryError
from eyelume.scene.sources import led_poses

__all__ = ["MIRROR_X", "Frame", "as_world", "camera_frame", "led_world_poses", "opencv_extrinsics"]

#: A left eye's mirror about the headset's sagittal plane: x → −x (elementwise factors).
MIRROR_X = np.array([-1.0, 1.0, 1.0])


def as_world(scene, p) -> np.ndarray:
    """Points or directions (…, 3) as the scene file writes them (a right eye's headset) in
    the world frame: unchanged for a right eye; a left eye's scene is the mirror image,
    x → −x (:class:`eyelume.scene.model.EyePose`)."""
    p = np.asarray(p, dtype=float)
    return p if scene.eye_pose.which == "right" else p * MIRROR_X


def led_world_poses(scene) -> tuple[np.ndarray, np.ndarray]:
    """The LEDs' body centres (N, 3) mm and unit axes (N, 3) in the world frame
    (:func:`eyelume.scene.sources.led_poses`, mirrored for a left eye)."""
    centres, axes = led_poses(scene.leds)
    return as_world(scene, centres), as_world(scene, axes)


_PARALLEL = 1e-9  # |d̂ × ŷ| below this: the view is along ±y


class Frame(NamedTuple):
    """A rigid transform world → camera frame: p_c = ``rotation`` @ (p − ``origin``).

    ``rotation`` (3, 3), rows x̂_c, ŷ_c, ẑ_c in world coordinates; ``origin`` (3,) world mm."""

    rotation: np.ndarray
    origin: np.ndarray

    def point(self, p) -> np.ndarray:
        """World point(s) (…, 3) mm → camera frame (…, 3) mm."""
        return (np.asarray(p, dtype=float) - self.origin) @ self.rotation.T

    def vector(self, v) -> np.ndarray:
        """World direction(s) (…, 3) → camera frame (…, 3) (rotation only)."""
        return np.asarray(v, dtype=float) @ self.rotation.T

    def world_point(self, p) -> np.ndarray:
        """Camera-frame point(s) (…, 3) mm → world (…, 3) mm."""
        return np.asarray(p, dtype=float) @ self.rotation + self.origin

    def world_vector(self, v) -> np.ndarray:
        """Camera-frame direction(s) (…, 3) → world (…, 3)."""
        return np.asarray(v, dtype=float) @ self.rotation

    @property
    def is_identity(self) -> bool:
        """True when the camera frame is the world frame (the paper's rig)."""
        return bool(np.array_equal(self.rotation, np.eye(3)) and not np.any(self.origin))


def camera_frame(
    position_mm, view, roll_deg: float, object_distance_mm: float, field: str = "camera"
) -> Frame:
    """The world → camera-frame transform (module docstring).

    ``position_mm`` (3,) world mm: the lens (its first vertex); ``view`` (3,): the unit or
    non-unit viewing direction d (from the lens toward the scene); ``roll_deg`` about the
    viewing axis; ``object_distance_mm`` L > 0. Raises :class:`GeometryError` naming ``field``
    when the direction is zero or not finite."""
    p = np.asarray(position_mm, dtype=float)
    d = np.asarray(view, dtype=float)
    norm = float(np.linalg.norm(d))
    if not math.isfinite(norm) or norm == 0.0:
        raise GeometryError(f"{field}: the viewing direction {d.tolist()} has no direction")
    d = d / norm
    if d[2] == -1.0 and d[0] == 0.0 and d[1] == 0.0:
        x = np.array([1.0, 0.0, 0.0])  # the paper's rig, exactly (no rounding)
    else:
        x = np.cross(d, [0.0, 1.0, 0.0])
        if np.linalg.norm(x) < _PARALLEL:  # looking straight up or down: world +z is "up"
            x = np.cross(d, [0.0, 0.0, 1.0])
        x = x / np.linalg.norm(x)
    z = -d
    y = np.cross(z, x)
    if roll_deg:
        a = math.radians(roll_deg)
        x, y = math.cos(a) * x + math.sin(a) * y, -math.sin(a) * x + math.cos(a) * y
    rotation = np.stack([x, y, z])
    origin = p + object_distance_mm * d
    if d[2] == -1.0 and d[0] == 0.0 and d[1] == 0.0 and p[0] == 0.0 and p[1] == 0.0:
        origin = np.array([0.0, 0.0, p[2] - object_distance_mm])  # exact on the axis
    return Frame(rotation, origin)


def opencv_extrinsics(frame: Frame, origin_z_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """OpenCV's extrinsics (R, t) of the camera: a world point p (mm) has OpenCV camera
    coordinates R p + t (x right, y down, z along the view), with the origin at the point
    (0, 0, ``origin_z_mm``) of the camera frame on the lens axis (the lens position at the
    object distance L, or the entrance pupil for a pinhole model).

    Returns ``R`` (3, 3) and ``t`` (3,) mm."""
    flip = np.diag([1.0, -1.0, -1.0])
    r = flip @ frame.rotation
    # camera-frame point (0, 0, origin_z) ↦ OpenCV origin
    t = -r @ frame.origin + np.array([0.0, 0.0, origin_z_mm])
    return r, t
