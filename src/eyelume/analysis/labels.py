"""The labels of one picture of a synthetic eye dataset (issue 17): segmentation, apparent pupil
and iris ellipses, glints and reflections with their flags, eye openness, the eye's centres and
axes in the camera frame, the camera's OpenCV model and the LEDs' poses.

Everything comes from the scene's own geometry (the truth's chief rays,
:mod:`eyelume.analysis.truth`, and the primary surface map of
:mod:`eyelume.analysis.regions`) and from the picture's sensor data (the saturated pixels);
nothing is detected in the picture. The fields, their units, frames and conventions are
documented in ``dataset_label.schema.json`` beside this module (:data:`SCHEMA_PATH`).

Conventions (the schema repeats them):

* **Pixels** (OpenCV): pixel (c, r) is centred at (x, y) = (c, r), x right, y down, origin at
  the centre of the top-left pixel of the upright picture.
* **Ellipse** E = ``{"center_px": [x, y], "semi_axes_px": [a, b], "angle_deg": θ}`` with
  a ≥ b and θ the angle of the a axis from +x toward +y (image down), in (−90°, 90°]: the
  points (x, y) = c + a cos t (cos θ, sin θ) + b sin t (−sin θ, cos θ).
* **Camera frame** (OpenCV): x right, y down, z forward along the view, mm; a world (headset
  frame) point p has camera coordinates R p + t. eyelume's own camera frame
  (:class:`eyelume.scene.pose.Frame`, ARCHITECTURE.md §2) has +z from the scene toward the
  camera and +y up; :func:`eyelume.scene.pose.opencv_extrinsics` turns it into OpenCV's.

This module's top level imports only NumPy (and the standard library), so the report layer can
use :data:`SEGMENTATION_CLASSES` and :func:`openeds_map` without loading anything that traces
rays; what needs the compiled scene imports it inside the function.
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path

import numpy as np

__all__ = [
    "SCHEMA_PATH",
    "SEGMENTATION_CLASSES",
    "camera_intrinsics",
    "ellipse_mask",
    "eye_openness",
    "fit_ellipse",
    "openeds_map",
    "picture_labels",
    "primary_classes",
    "segmentation_map",
]

#: The segmentation's class ids and names: 0–3 are OpenEDS' (Garbin et al. 2019), 4–7 eyelume's.
#: 4 skin: face tissue other than the lids; 5 eyelid: the upper and lower eyelid tissues and the
#: lashes; 6 glint: a corneal glint's region (:func:`eyelume.analysis.regions.with_glints`);
#: 7 reflection: a spurious reflection (an optical element's ghost of an LED, or an LED the
#: camera sees directly).
SEGMENTATION_CLASSES: dict[int, str] = {
    0: "background",
    1: "sclera",
    2: "iris",
    3: "pupil",
    4: "skin",
    5: "eyelid",
    6: "glint",
    7: "reflection",
}
_CLASS = {name: k for k, name in SEGMENTATION_CLASSES.items()}

#: The label schema (JSON Schema draft 2020-12), shipped with the package.
SCHEMA_PATH = Path(__file__).with_name("dataset_label.schema.json")

#: Face tissues counted as eyelid (class 5) besides the lashes: by name, as the presets call
#: them (``"upper eyelid"``, ``"lower eyelid"``); any tissue whose name contains "eyelid".
EYELID_WORD = "eyelid"

#: The half-width (px) of the neighbourhood of a glint's position in which a saturated pixel
#: makes the glint ``saturated``: 1 (the 3 × 3 pixels about it).
SATURATION_NEIGHBOURHOOD_PX = 1

PIXEL_CONVENTION = (
    "OpenCV: pixel (c, r) centred at (x, y) = (c, r), x right, y down, origin at the centre "
    "of the top-left pixel"
)


# --------------------------------------------------------------------------- segmentation


def _eyelid_names(scene) -> set[str]:
    """The face tissues of class 5 (eyelid): those named with "eyelid", the lashes' lid, and
    the lashes themselves."""
    from eyelume.compile import LASHES_NAME

    if not scene.face.enabled:
        return set()
    names = {t.name for t in scene.face.tissues if EYELID_WORD in t.name.lower()}
    lashes = getattr(scene.face, "lashes", None)
    if lashes is not None and getattr(lashes, "enabled", False):
        names |= {lashes.lid, LASHES_NAME}
    return names | {LASHES_NAME}


def primary_classes(cs) -> np.ndarray:
    """(rows, cols) uint8 class ids 0–5 of the primary surface map: the surface each pixel's
    chief ray meets first after refraction (:func:`eyelume.estimators.fast_run.primary_surface_map`,
    :func:`eyelume.analysis.regions.surface_masks`), glints and reflections ignored; skin split
    into eyelid (5: the eyelid tissues and the lashes) and other skin (4)."""
    from eyelume.analysis.regions import surface_masks
    from eyelume.estimators.fast_run import primary_surface_map

    labels, sides = primary_surface_map(cs)
    m = surface_masks(cs, labels, sides)
    out = np.zeros(labels.shape, dtype=np.uint8)
    out[m["sclera"]] = _CLASS["sclera"]
    out[m["iris"]] = _CLASS["iris"]
    out[m["pupil"]] = _CLASS["pupil"]
    out[m["skin"]] = _CLASS["skin"]
    lid_rows = [i for i, n in enumerate(cs.surface_names) if n in _eyelid_names(cs.scene)]
    if lid_rows:
        out[m["skin"] & np.isin(labels, lid_rows)] = _CLASS["eyelid"]
    return out


def _leds_seen_mask(cs, truth: dict | None) -> np.ndarray:
    """(rows, cols) bool: a disc about each LED the camera sees directly (truth's
    ``leds_in_view``, visible ones), of the radius :func:`eyelume.analysis.regions.reflection_mask`
    gives a ghost: half its geometric defocus blur (:func:`eyelume.analysis.ghosts._blur_px`
    at the LED's distance from the entrance pupil: an LED beside the lens is far from the
    plane in focus) plus the Airy radius, at least 1 px."""
    from eyelume.analysis.ghosts import _blur_px
    from eyelume.analysis.regions import reflection_mask

    ep_z = cs.first_order.entrance_pupil_z
    seen = [
        {
            "visible": True,
            "centre_px": e["centre_px"],
            "blur_px": _blur_px(cs, ep_z - cs.led.points[cs.led_indices.index(e["led"])][2]),
        }
        for e in (truth or {}).get("leds_in_view", [])
        if e["visible"]
    ]
    if not seen:
        return np.zeros((cs.picture.rows, cs.picture.cols), dtype=bool)
    return reflection_mask(cs, seen)


def _maps(cs, masks: dict, truth: dict | None) -> tuple[np.ndarray, np.ndarray]:
    """(segmentation, primary classes), both (rows, cols) uint8."""
    under = primary_classes(cs)
    seg = under.copy()
    for name, m in masks.items():
        if name.startswith("glint"):
            seg[m] = _CLASS["glint"]
    spurious = _leds_seen_mask(cs, truth)
    if "reflection" in masks:
        spurious = spurious | masks["reflection"]
    seg[spurious] = _CLASS["reflection"]
    return seg, under


def segmentation_map(cs, masks: dict[str, np.ndarray], truth: dict | None = None) -> np.ndarray:
    """(rows, cols) uint8 class ids (:data:`SEGMENTATION_CLASSES`) of a picture.

    The primary surface map's classes (:func:`primary_classes`: background, sclera, iris,
    pupil, skin, eyelid), then each ``glint k`` mask of ``masks``
    (:func:`eyelume.analysis.regions.region_masks` with glints) as 6, then the ``reflection``
    mask (element ghosts) and each LED the camera sees directly (``truth["leds_in_view"]``,
    :func:`eyelume.analysis.truth.eye_truth`; a disc of the Airy radius, at least 1 px) as 7.
    ``masks`` must be of the picture's shape (rows, cols)."""
    _check_shape(cs, masks)
    return _maps(cs, masks, truth)[0]


def _check_shape(cs, masks: dict) -> None:
    shape = (cs.picture.rows, cs.picture.cols)
    for name, m in masks.items():
        if np.shape(m) != shape:
            raise ValueError(f"masks[{name!r}] has shape {np.shape(m)}, the picture is {shape}")


def openeds_map(seg: np.ndarray, primary: np.ndarray | None = None) -> np.ndarray:
    """The OpenEDS view of a segmentation (uint8, ids 0–3): skin and eyelid (4, 5) → 0
    (background), glint and reflection pixels (6, 7) → the class under them, as OpenEDS'
    annotators labelled the eye region through its glints.

    ``primary`` (rows, cols) uint8, the primary surface map's classes
    (:func:`primary_classes`): the class under a glint exactly. Without it (a segmentation
    read from a file), each glint or reflection pixel takes the class of the nearest pixel
    that is neither (Euclidean distance, :func:`scipy.ndimage.distance_transform_edt`); a
    picture that is all glint maps to 0.

    Examples
    --------
    A glint (6) on the iris (2), skin (4) and an eyelid (5) in the corners:

    >>> seg = np.array([[4, 2, 2], [2, 6, 2], [5, 2, 3]], dtype=np.uint8)
    >>> openeds_map(seg).tolist()
    [[0, 2, 2], [2, 2, 2], [0, 2, 3]]
    """
    seg = np.asarray(seg)
    spurious = seg >= _CLASS["glint"]
    if primary is not None:
        if np.shape(primary) != seg.shape:
            raise ValueError(f"primary has shape {np.shape(primary)}, seg {seg.shape}")
        src = np.asarray(primary).copy()
    elif spurious.any() and not spurious.all():
        from scipy.ndimage import distance_transform_edt

        idx = distance_transform_edt(spurious, return_distances=False, return_indices=True)
        src = seg[tuple(idx)]
    else:
        src = np.where(spurious, 0, seg)
    out = np.where(spurious, src, seg).astype(np.uint8)
    out[(out == _CLASS["skin"]) | (out == _CLASS["eyelid"]) | (out >= _CLASS["glint"])] = 0
    return out


# ------------------------------------------------------------------------------- ellipses


def fit_ellipse(points) -> dict | None:
    """The least-squares ellipse through (n, 2) points (px), n ≥ 6: the direct ellipse-specific
    conic fit of Fitzgibbon, Pilu & Fisher (1999) in the numerically stable form of Halíř &
    Flusser (1998), on points centred and scaled to unit spread. Returns the ellipse in this
    module's convention (module doc: centre, semi-axes a ≥ b, angle of a from +x toward +y in
    (−90°, 90°]) with ``rms_px``, the RMS algebraic-to-geometric distance estimate of the
    points from it (|Q(p)| / |∇Q(p)|), or None when fewer than 6 points or no ellipse fits.

    Examples
    --------
    An ellipse 10 × 4 px about (20, 15), its long axis 30° below +x (image y down):

    >>> t = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    >>> th = np.radians(30.0)
    >>> x = 20 + 10 * np.cos(t) * np.cos(th) - 4 * np.sin(t) * np.sin(th)
    >>> y = 15 + 10 * np.cos(t) * np.sin(th) + 4 * np.sin(t) * np.cos(th)
    >>> e = fit_ellipse(np.column_stack([x, y]))
    >>> [round(v, 6) for v in (*e["center_px"], *e["semi_axes_px"], e["angle_deg"])]
    [20.0, 15.0, 10.0, 4.0, 30.0]
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    if len(pts) < 6 or not np.all(np.isfinite(pts)):
        return None
    mean = pts.mean(axis=0)
    scale = float(np.sqrt(((pts - mean) ** 2).sum(axis=1).mean())) or 1.0
    x, y = ((pts - mean) / scale).T
    d1 = np.column_stack([x * x, x * y, y * y])
    d2 = np.column_stack([x, y, np.ones_like(x)])
    s1, s2, s3 = d1.T @ d1, d1.T @ d2, d2.T @ d2
    try:
        t = -np.linalg.solve(s3, s2.T)
    except np.linalg.LinAlgError:
        return None
    m = s1 + s2 @ t
    m = np.array([m[2] / 2, -m[1], m[0] / 2])
    w, v = np.linalg.eig(m)
    v = np.real(v)
    cond = 4 * v[0] * v[2] - v[1] ** 2
    if not np.any(cond > 0):
        return None
    a1 = v[:, int(np.argmax(cond))]
    A, B, C, D, E, F = np.concatenate([a1, t @ a1])  # noqa: N806 (the conic's usual names)
    q = np.array([[A, B / 2], [B / 2, C]])
    try:
        c = np.linalg.solve(2 * q, [-D, -E])
    except np.linalg.LinAlgError:
        return None
    fc = A * c[0] ** 2 + B * c[0] * c[1] + C * c[1] ** 2 + D * c[0] + E * c[1] + F
    lam, vec = np.linalg.eigh(q)
    axes2 = -fc / lam
    if np.any(axes2 <= 0):
        return None
    axes = np.sqrt(axes2)
    major = int(np.argmax(axes))
    ux, uy = vec[:, major]
    angle = math.degrees(math.atan2(uy, ux))
    angle = angle - 180.0 if angle > 90.0 else angle + 180.0 if angle <= -90.0 else angle
    # distance estimate of each point from the conic: |Q(p)| / |∇Q(p)|
    qv = A * x * x + B * x * y + C * y * y + D * x + E * y + F
    gx, gy = 2 * A * x + B * y + D, B * x + 2 * C * y + E
    dist = np.abs(qv) / np.maximum(np.hypot(gx, gy), 1e-300)
    return {
        "center_px": (c * scale + mean).tolist(),
        "semi_axes_px": [float(axes[major] * scale), float(axes[1 - major] * scale)],
        "angle_deg": float(angle),
        "rms_px": float(np.sqrt(np.mean(dist**2)) * scale),
    }


def ellipse_mask(ellipse: dict, shape: tuple[int, int]) -> np.ndarray:
    """(rows, cols) bool: the pixels whose centres (c, r) lie inside ``ellipse`` (this module's
    convention): ((u/a)² + (w/b)² ≤ 1 with u, w the centre's coordinates along the a and b
    axes)."""
    rows, cols = shape
    r, c = np.mgrid[0:rows, 0:cols].astype(float)
    cx, cy = ellipse["center_px"]
    a, b = ellipse["semi_axes_px"]
    th = math.radians(ellipse["angle_deg"])
    u = (c - cx) * math.cos(th) + (r - cy) * math.sin(th)
    w = -(c - cx) * math.sin(th) + (r - cy) * math.cos(th)
    return (u / a) ** 2 + (w / b) ** 2 <= 1.0


def _ellipse_label(points) -> dict | None:
    e = fit_ellipse(points)
    if e is None:
        return None
    return {k: e[k] for k in ("center_px", "semi_axes_px", "angle_deg")} | {
        "fit_rms_px": e["rms_px"]
    }


# ------------------------------------------------------------------------------ openness


def eye_openness(primary: np.ndarray, limbus: dict | None) -> float | None:
    """The share of the iris's height that the lids leave visible, in the picture; in [0, 1]
    by construction.

    In the pixel column c nearest the limbus ellipse's centre (cx, cy) the iris spans
    y ∈ [cy − h/2, cy + h/2], h = 2 / √(sin²θ/a² + cos²θ/b²) its vertical chord through the
    centre (px); the lids leave open the unbroken run of eyeball pixels (sclera, iris, pupil
    of the primary map ``primary``, :func:`primary_classes`, glints taken as what is under
    them) through the centre's row, rows top to bottom, i.e. y ∈ [top − ½, bottom + ½].
    Openness = the length of the overlap of the two intervals over h:

    * 1: neither lid covers any of the iris's height in that column (wide open; sclera showing
      above or below the iris is not counted, so a wider aperture is still 1);
    * 0: the lids cover the iris's centre (closed, or all but closed);
    * e.g. about 0.8 for the paper rig's open eye in primary gaze (lid margins 4.5 mm above and
      5.5 mm below a 12 mm limbus: each lid covers a band of the iris).

    (The point at y = cy + t of the centre's column is on the ellipse when
    (t sin θ)²/a² + (t cos θ)²/b² = 1, the module's ellipse convention; before issue 17's
    review the chord had sin and cos swapped — the horizontal chord for an upright ellipse.)

    This is the "visible iris height" measure of eye-openness labels (the lid aperture over the
    iris diameter, capped at the iris). None when there is no limbus ellipse or its centre is
    outside the picture."""
    if limbus is None:
        return None
    rows, cols = primary.shape
    cx, cy = limbus["center_px"]
    c, r = int(round(cx)), int(round(cy))
    if not (0 <= c < cols and 0 <= r < rows):
        return None
    a, b = limbus["semi_axes_px"]
    th = math.radians(limbus["angle_deg"])
    chord = 2.0 / math.sqrt(math.sin(th) ** 2 / a**2 + math.cos(th) ** 2 / b**2)
    eyeball = np.isin(primary[:, c], [_CLASS["sclera"], _CLASS["iris"], _CLASS["pupil"]])
    if not eyeball[r]:
        return 0.0
    top = r
    while top > 0 and eyeball[top - 1]:
        top -= 1
    bottom = r
    while bottom < rows - 1 and eyeball[bottom + 1]:
        bottom += 1
    seen = min(bottom + 0.5, cy + chord / 2) - max(top - 0.5, cy - chord / 2)
    return float(min(1.0, max(0.0, seen / chord)))


# -------------------------------------------------------------------------------- camera

_CAMERA_CACHE: dict[str, dict] = {}

#: The chief-ray samples the camera model is fitted to: a grid of this many × this many
#: sensor points over the picture, each imaging points at the depths below.
CALIBRATION_GRID = 13
#: Depths (mm, eyelume's camera frame z, the object plane at 0) of the calibration points:
#: the eye region, from 15 mm behind the object plane to 5 mm in front of it.
CALIBRATION_DEPTHS_MM = (-15.0, -10.0, -5.0, 0.0, 5.0)


def _camera_key(scene) -> str:
    """What the camera model depends on: the camera, its lens, the sensor's geometry, the
    wavelength (a prescription's indices) and which eye (a left eye's mirror)."""
    s = scene.sensor
    parts = {
        "camera": scene.camera.model_dump(mode="json"),
        "lens": None if scene.lens is None else scene.lens.model_dump(mode="json"),
        "sensor": [s.cols, s.rows, *s.field_mm],
        "wavelength_nm": scene.wavelength_nm,
        "eye": scene.eye_pose.which,
        "object_distance_mm": scene.object_distance_mm,
    }
    return hashlib.sha256(json.dumps(parts, sort_keys=True).encode()).hexdigest()


def _chief_samples(cs) -> tuple[np.ndarray, np.ndarray]:
    """Points (n, 3) in eyelume's camera frame (mm) and their pixels (n, 2): each chief ray of
    a :data:`CALIBRATION_GRID`² grid of pixel positions over the picture (the camera alone,
    no optical elements), followed into the scene to each depth of
    :data:`CALIBRATION_DEPTHS_MM` in front of the entrance pupil."""
    from eyelume.detectors.receivers import BinnedPlane
    from eyelume.estimators.camera import aim_chief, into_scene

    cam, plane = cs.camera, BinnedPlane(cs.picture)
    cols, rows = cs.picture.cols, cs.picture.rows
    pts, pix = [], []
    for r in np.linspace(-0.5, rows - 0.5, CALIBRATION_GRID):
        for c in np.linspace(-0.5, cols - 0.5, CALIBRATION_GRID):
            xs, ys = (float(u) for u in plane.from_pixel(c, r))
            chief = aim_chief(cam, xs, ys)
            if not chief.found:
                continue
            ok, x, y, z, dx, dy, dz, _ = into_scene(cam, xs, ys, chief.qx, chief.qy)
            if not ok or dz >= 0:
                continue
            for depth in CALIBRATION_DEPTHS_MM:
                if depth >= cam.entrance_pupil_z - 1.0:
                    continue
                t = (depth - z) / dz
                pts.append([x + t * dx, y + t * dy, depth])
                pix.append([c, r])
    return np.array(pts), np.array(pix)


def camera_intrinsics(cs, *, fit: bool | None = None) -> dict:
    """The camera's OpenCV model: ``K`` (3 × 3, px), ``dist`` (k1, k2, p1, p2, k3), ``R``
    (3 × 3), ``t_mm`` (3,) with x_cam = R x_world + t (world: the headset frame; camera:
    OpenCV's, x right, y down, z forward, mm), ``image_size`` [cols, rows],
    ``intrinsics_fit_rms_px`` and ``model`` (how it was obtained).

    The truth of the camera is its chief rays (:func:`eyelume.estimators.camera.aim_chief`,
    the rays the truth's pixels come from): :func:`_chief_samples` gives points in the eye
    region and the pixels they image at; ``intrinsics_fit_rms_px`` is the RMS reprojection
    error (px) of the returned model over them.

    * An ideal lens (``camera.optics = "ideal"``): exact by construction. Its chief ray
      crosses the lens's centre and leaves with slope D(s⃗) = s⃗ (1 + k1 |s⃗|² + k2 |s⃗|⁴)
      (:class:`eyelume.scene.model.IdealLens`), s⃗ the object-side slope = OpenCV's
      normalised coordinates (X/Z, Y/Z), to the sensor at the image distance v: fx = v / p_x,
      fy = v / p_y (p the picture's pixel pitch on the sensor: field / (cols, rows)),
      (cx, cy) = ((cols − 1)/2, (rows − 1)/2) (the sensor is centred on the axis), dist =
      (k1, k2, 0, 0, 0), the pinhole at the lens (its entrance pupil).
    * A prescription (e.g. the paper's Double Gauss): :func:`cv2.calibrateCamera` on the
      samples (one non-planar view in OpenCV camera coordinates about the paraxial entrance
      pupil; an intrinsic guess from the paraxial pinhole |m| × the entrance pupil's distance;
      the principal point fixed at the picture's centre and no tangential distortion — the lens
      is rotationally symmetric about an axis through the sensor's centre; the aspect ratio
      fixed by the pixel pitch); the view's fitted pose (a shift of the pinhole along the axis
      to where the chief rays best converge) is folded into R and t.

    ``fit``: None (default) as above; True fits with :func:`cv2.calibrateCamera` whatever the
    optics (an ideal lens's fit recovers its exact model: a check of the fitting path).

    Cached per camera (:func:`_camera_key`): pictures that vary the eye, LEDs or exposure
    share one fit."""
    ideal = cs.scene.camera.optics == "ideal"
    if fit is False and not ideal:
        raise ValueError("camera_intrinsics(fit=False): only an ideal lens has an exact model")
    fit = not ideal if fit is None else bool(fit)
    key = f"{_camera_key(cs.scene)}-{fit}"
    if key not in _CAMERA_CACHE:
        _CAMERA_CACHE[key] = _fit_camera(cs, fit)
    return json.loads(json.dumps(_CAMERA_CACHE[key]))  # a copy the caller may change


def _fit_camera(cs, fit: bool) -> dict:
    import cv2

    from eyelume.scene.pose import opencv_extrinsics

    scene, fo = cs.scene, cs.first_order
    cols, rows = scene.sensor.cols, scene.sensor.rows
    width, height = scene.sensor.field_mm
    px, py = width / cols, height / rows
    r_w, t_w = opencv_extrinsics(cs.frame, fo.entrance_pupil_z)
    pts_c, pix = _chief_samples(cs)
    obj = cs.frame.world_point(pts_c) @ r_w.T + t_w  # OpenCV camera coordinates
    if not fit:
        ideal = scene.camera.ideal
        v = ideal.image_distance_mm
        k = np.array([[v / px, 0.0, (cols - 1) / 2], [0.0, v / py, (rows - 1) / 2], [0, 0, 1.0]])
        dist = np.array([ideal.k1, ideal.k2, 0.0, 0.0, 0.0])
        r, t = r_w, t_w
        model = "ideal lens: exact (fx = v/p_x, fy = v/p_y, centre, k1, k2 of the lens)"
    else:
        pinhole = abs(fo.magnification) * fo.entrance_pupil_z
        k0 = np.array(
            [[pinhole / px, 0.0, (cols - 1) / 2], [0.0, pinhole / py, (rows - 1) / 2], [0, 0, 1.0]]
        )
        flags = (
            cv2.CALIB_USE_INTRINSIC_GUESS
            | cv2.CALIB_FIX_PRINCIPAL_POINT
            | cv2.CALIB_ZERO_TANGENT_DIST
            | cv2.CALIB_FIX_ASPECT_RATIO
        )
        crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-12)
        _, k, dist, rvecs, tvecs = cv2.calibrateCamera(
            [obj.astype(np.float32)],
            [pix.astype(np.float32)],
            (cols, rows),
            k0,
            np.zeros(5),
            flags=flags,
            criteria=crit,
        )
        dist = np.asarray(dist, dtype=float).ravel()[:5]
        r_fit = cv2.Rodrigues(rvecs[0])[0]
        r, t = r_fit @ r_w, r_fit @ t_w + np.asarray(tvecs[0], dtype=float).ravel()
        model = (
            "cv2.calibrateCamera on the chief rays (principal point fixed at the centre, "
            "no tangential distortion, aspect ratio of the pixel pitch)"
        )
    world = cs.frame.world_point(pts_c)
    rvec = cv2.Rodrigues(r)[0]
    proj = cv2.projectPoints(world.reshape(-1, 1, 3), rvec, t, k, dist)[0].reshape(-1, 2)
    rms = float(np.sqrt(np.mean(np.sum((proj - pix) ** 2, axis=1))))
    return {
        "K": np.asarray(k, dtype=float).tolist(),
        "dist": np.asarray(dist, dtype=float).tolist(),
        "R": np.asarray(r, dtype=float).tolist(),
        "t_mm": np.asarray(t, dtype=float).tolist(),
        "image_size": [cols, rows],
        "intrinsics_fit_rms_px": rms,
        "model": model,
    }


# ---------------------------------------------------------------------------------- eye


def _to_camera(camera: dict, p) -> list[float]:
    return (np.asarray(camera["R"]) @ np.asarray(p, dtype=float) + camera["t_mm"]).tolist()


def _dir_to_camera(camera: dict, v) -> list[float]:
    d = np.asarray(camera["R"]) @ np.asarray(v, dtype=float)
    return (d / np.linalg.norm(d)).tolist()


def _camera_frame(cs, truth: dict, camera: dict) -> dict:
    """The eye's centres and axes in OpenCV's camera frame (mm, unit vectors out of the eye)."""
    from eyelume.compile import eye_point
    from eyelume.scene.eye import anterior_cornea_pose

    scene, eye = cs.scene, cs.scene.eye
    flip = np.array([-1.0, 1.0, -1.0])  # eye frame (x′ = −x, z′ = −z) ↔ the file's frame
    apex, rot = anterior_cornea_pose(eye)
    centre_eye = apex + eye.surfaces[0].radius_mm * rot[2]  # along the quadric's axis
    return {
        "eyeball_center_mm": _to_camera(
            camera, eye_point(scene, [0.0, 0.0, -eye.rotation_centre_mm])
        ),
        "cornea_center_mm": _to_camera(camera, eye_point(scene, flip * centre_eye)),
        "pupil_center_mm": _to_camera(camera, truth["pupil"]["centre_mm"]),
        "optical_axis": _dir_to_camera(camera, truth["optical_axis"]),
        "visual_axis": _dir_to_camera(camera, truth["visual_axis"]),
    }


# ------------------------------------------------------------------------------- glints


def _saturated_at(saturated: np.ndarray | None, xy) -> bool:
    if saturated is None or xy is None:
        return False
    rows, cols = saturated.shape
    c, r = int(round(xy[0])), int(round(xy[1]))
    h = SATURATION_NEIGHBOURHOOD_PX
    win = saturated[max(r - h, 0) : min(r + h + 1, rows), max(c - h, 0) : min(c + h + 1, cols)]
    return bool(win.any())


def _inside(cs, xy) -> bool:
    return (
        xy is not None
        and -0.5 <= xy[0] < cs.picture.cols - 0.5
        and -0.5 <= xy[1] < cs.picture.rows - 0.5
    )


def _glints(cs, truth: dict, saturated: np.ndarray | None) -> list[dict]:
    """One entry per LED (truth's ``glints``, :func:`eyelume.analysis.truth._glint_truth`): a
    glint a lid or a lash hides over part of the camera's stop (``partly_blocked``) is placed
    at the clear part's centroid, the spot in the picture (≤ 0.22 px from the whole spot's on
    the design run's frames)."""
    from eyelume.analysis.truth import sclera_reflection

    out = []
    for g in truth["glints"]:
        pos = g["centre_px"]
        on_sclera = False
        if not g["on_cornea"]:
            s = sclera_reflection(cs, g["led"])
            on_sclera = s is not None and _inside(cs, s)
            pos = s if on_sclera else None
        part = g.get("partly_blocked")
        if g["visible"] and part and part["centre_px"] is not None:
            pos = part["centre_px"]  # a lid or a lash over part of the stop: the spot seen
        blocked = g["on_cornea"] and not g["visible"] and g["reason"].startswith("blocked")
        visible = bool(g["visible"] and _inside(cs, pos))
        out.append(
            {
                "led": int(g["led"]),
                "position_px": None if pos is None else [float(pos[0]), float(pos[1])],
                "on_cornea": bool(g["on_cornea"]),
                "on_sclera": bool(on_sclera),
                "hidden": bool(blocked),
                "saturated": bool(visible and _saturated_at(saturated, pos)),
                "visible": visible,
            }
        )
    return out


def _reflections(truth: dict) -> list[dict]:
    """Element ghosts (truth's ``ghosts``) and LEDs seen directly (``leds_in_view``)."""
    out = [
        {
            "led": int(e["led"]),
            "kind": "ghost",
            "chain": list(e["chain"]),
            "position_px": [float(x) for x in e["centre_px"]],
            "visible": bool(e["visible"]),
        }
        for e in truth.get("ghosts", [])
    ]
    out += [
        {
            "led": int(e["led"]),
            "kind": "led in view",
            "chain": [],
            "position_px": [float(x) for x in e["centre_px"]],
            "visible": bool(e["visible"]),
        }
        for e in truth.get("leds_in_view", [])
    ]
    return out


def _leds(cs) -> list[dict]:
    """Every LED's emission point and unit axis (world mm), wavelength and on-axis I₀."""
    from eyelume.scene.pose import led_world_poses

    scene = cs.scene
    _, axes = led_world_poses(scene)
    points = cs.frame.world_point(cs.led.points)
    ids = cs.led_indices
    lam = scene.leds.wavelengths_nm(scene.wavelength_nm)
    i0 = scene.leds.intensities_w_sr()
    return [
        {
            "id": int(k),
            "position_mm": points[row].tolist(),
            "direction": axes[k].tolist(),
            "wavelength_nm": float(lam[k]),
            "radiant_intensity_w_sr": float(i0[k]),
        }
        for row, k in enumerate(ids)
    ]


# ------------------------------------------------------------------------------ picture


def picture_labels(
    cs,
    digital_counts: np.ndarray | None,
    saturated: np.ndarray | None,
    irradiance: np.ndarray | None,
    masks: dict[str, np.ndarray],
    truth: dict,
    openeds: bool = False,
) -> tuple[dict, np.ndarray] | tuple[dict, np.ndarray, np.ndarray]:
    """The labels of one picture and its segmentation (with ``openeds``, also its exact
    OpenEDS map: :func:`openeds_map` with the primary surface map, the class under every glint
    and reflection pixel as the scene has it).

    Parameters
    ----------
    cs : CompiledScene
        The picture's scene, compiled (its nominal compile: the scene's wavelength, every LED).
    digital_counts, irradiance : (rows, cols) arrays or None
        The sensor's digital numbers and the linear irradiance (W/mm²); only their shapes are
        checked (the labels come from the geometry, not from the picture's values).
    saturated : (rows, cols) bool or None
        The sensor's saturated pixels (:func:`eyelume.detectors.sensor.digitize`): a visible
        glint with one within :data:`SATURATION_NEIGHBOURHOOD_PX` of its position is
        ``saturated``.
    masks : dict
        The regions (:func:`eyelume.analysis.regions.region_masks` with ``glint k`` masks and,
        with elements, ``reflection``), (rows, cols) bool each.
    truth : dict
        :func:`eyelume.analysis.truth.eye_truth` of ``cs`` (with its ``iris``).

    Returns
    -------
    (dict, (rows, cols) uint8)
        The label (every key of ``dataset_label.schema.json`` but the bookkeeping ones ds-core
        adds: index, seed, the file names, image_bits, varied, person, glasses, render) and the
        segmentation (:func:`segmentation_map`).

    Raises
    ------
    ValueError
        An array whose shape is not the picture's (rows, cols).
    """
    _check_shape(cs, masks)
    for name, a in (("digital_counts", digital_counts), ("saturated", saturated)):
        if a is not None:
            _check_shape(cs, {name: a})
    if irradiance is not None:
        _check_shape(cs, {"irradiance": irradiance})
    seg, under = _maps(cs, masks, truth)
    camera = camera_intrinsics(cs)
    pupil = _ellipse_label(truth["pupil"]["edge_px"])
    iris_t = truth.get("iris")
    iris = None if iris_t is None else _ellipse_label(iris_t["edge_px"])
    label = {
        "size_px": [cs.picture.cols, cs.picture.rows],
        "pixel_convention": PIXEL_CONVENTION,
        "gaze_deg": {k: float(v) for k, v in truth["visual_axis_deg"].items()},
        "optical_gaze_deg": {k: float(v) for k, v in truth["gaze_deg"].items()},
        "pupil": {
            "ellipse": pupil,
            "center_px": truth["pupil"]["centre_px"],
            "diameter_mm": float(truth["pupil"]["diameter_mm"]),
            "visible_share": float(truth["pupil"]["visible_fraction"]),
        },
        "iris": None
        if iris_t is None
        else {
            "ellipse": iris,
            "diameter_mm": float(iris_t["diameter_mm"]),
            "visible_share": float(iris_t["visible_fraction"]),
        },
        "glints": _glints(cs, truth, saturated),
        "reflections": _reflections(truth),
        "eye_openness": eye_openness(under, iris),
        "camera_frame": _camera_frame(cs, truth, camera),
        "camera": {k: camera[k] for k in ("K", "dist", "R", "t_mm", "intrinsics_fit_rms_px")},
        "leds": _leds(cs),
    }
    if openeds:
        return label, seg, openeds_map(seg, under)
    return label, seg
