"""Tracking quality of given frames: detection against the truth, gaze estimates, statistics.

Each frame is a digital picture of the eye at a known gaze with the renderer's truth
(:func:`eyelume.analysis.truth.eye_truth`). :func:`analyse_frame` runs the paper's detection
pipeline (:mod:`.detect`) on it and compares with the truth: pupil-centre error (the detected
ellipse's centre against the centre of the ellipse through the true apparent pupil edge), glints
found and matched. :func:`analyse_frames` estimates gaze with two estimators (:mod:`.gaze`): the
PCCR polynomial, calibrated on a 3 × 3 grid of calibration frames and evaluated on the held-out
test frames, and the Guestrin–Eizenman geometric model from the glints, which needs no
calibration of its own beyond a one-point kappa: with calibration frames, the offset between the
central calibration target (0°, 0°) and the model's optical axis there is added to every
estimate (:func:`kappa_offset`; the angle kappa of the person, ``eye.kappa_deg``, and the
model's own bias at the centre). The frames' gazes are fixation targets of the visual axis
(:func:`eyelume.optimize.tracking.render_frame` turns the eye so its visual axis meets them), so
every error is against the visual axis. Both use the glints matched to LEDs only: a frame
with some LEDs' glints missing (off the cornea, under a lid) but ≥ 3 matched is answered
(:func:`~.detect.detect`); its PCCR reference is the glint pattern's centre from the found
glints and each LED's offset in the calibration frames (:func:`~.gaze.glint_offsets`), not
the mean of the found glints, which moves toward them. Rendering the frames over a gaze grid is
:mod:`eyelume.optimize.tracking`'s.

With optical elements (spectacles, a hot mirror), a detected glint matched to an LED may be a
spectacle ghost (:mod:`eyelume.analysis.ghosts`) taken for the corneal glint, and with sunlight
(``ambient.sun``) the sun's own corneal glint (truth ``sun_glint``):
:func:`false_glints` counts them per frame (``Frame.false_glints``) and the summary totals them.
A matched glint may also be a real spot that is not a whole corneal glint — one cut by the
cornea's rim (truth ``at_rim``: its centroid moved by ``rim.bias_px`` off where the gaze models
put the glint), counted by :func:`rim_glints` — or have no spot of its LED's in the truth at
all (off the cornea, hidden, not a ghost), counted by :func:`stray_glints`; the summary's
``clean_detection_rate`` is the share of frames answered ``ok`` with none of the three.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from eyelume.analysis.safety import eye_safety
from eyelume.analysis.tracking.detect import Detection, detect
from eyelume.analysis.tracking.gaze import (
    SPHERE_ZONE_DEG,
    GeometricGaze,
    PccrModel,
    PinholeCamera,
    glint_offsets,
    pupil_glint_vector,
)
from eyelume.scene.model import Scene

__all__ = [
    "FAILED_FRAME_DEG",
    "Frame",
    "TrackingReport",
    "analyse_frame",
    "analyse_frames",
    "error_map_rows",
    "false_glints",
    "rim_glints",
    "stray_glints",
    "pinhole_camera",
    "led_picture_azimuths",
    "led_picture_pattern",
    "picture_mm_per_px",
    "tracking_score",
]

#: The classic 9-point calibration: a 3 × 3 grid of gaze targets (degrees).
CALIBRATION_H = (-20.0, 0.0, 20.0)
CALIBRATION_V = (-15.0, 0.0, 15.0)
#: A matched glint this close (px) to a visible ghost's true centre — or within the ghost's
#: blur radius, if larger — may be the ghost (:func:`false_glints`). A detected centroid lies
#: within ~1 px of the spot's true centre (tests/analysis/test_detect.py); 3 px also covers a
#: ghost beside a glint merged into one blob, whose centroid lies between them.
FALSE_GLINT_PX = 3.0
#: The test grid of the issue: 7 × 5 gazes.
TEST_H = (-30.0, -20.0, -10.0, 0.0, 10.0, 20.0, 30.0)
TEST_V = (-20.0, -10.0, 0.0, 10.0, 20.0)


@dataclass
class Frame:
    """One rendered gaze: detection against truth, and the gaze estimates (degrees).
    ``glints_px`` holds one entry per LED: its matched glint (x, y) px or None."""

    gaze: tuple[float, float]
    detection: Detection
    truth: dict
    pupil_error_px: float = math.nan
    glints_found: int = 0
    glints_true: int = 0
    pg_vector: tuple[float, float] | None = None
    pccr: tuple[float, float] | None = None
    geometric: tuple[float, float] | None = None
    #: why the geometric model gave no estimate on a frame detected ``ok`` ("" otherwise):
    #: e.g. too few glints within its spherical cornea's validity zone
    geometric_refused: str = ""
    render_s: float = 0.0
    detect_ms: float = 0.0
    saturated_share: float = 0.0  # of the frame's pixels at the full well or full scale
    glints_px: list | None = None
    false_glints: int = 0  # matched glints that are element ghosts (false_glints)
    rim_glints: int = 0  # matched glints cut by the cornea's rim (rim_glints)
    stray_glints: int = 0  # matched glints of an LED without a spot in the truth (stray_glints)
    ambient: dict | None = None  # ambient.sun: the frame's signal to ambient (ambient_ratios)
    #: kept only when asked (``keep_picture``): what detection ran on, to run it again
    #: (:func:`eyelume.optimize.tracking.reanalyse_frame`): ``counts`` (rows, cols) the
    #: camera's digital picture (DN), ``led_azimuths_deg`` and ``led_pattern_px``
    picture: dict | None = None
    samples_per_pixel: int = 0  # camera samples per pixel its render used (0: not recorded)
    #: the test frame is the calibration frame of its gaze (same scene, seed and budget: the
    #: same picture), so its PCCR error is the fit's in-sample residual, not a measurement:
    #: left out of the PCCR statistics (:func:`summarise`) and marked "cal" on the error maps
    calibration: bool = False


@dataclass
class TrackingReport:
    """Frames of the test grid (and the calibration frames) with the summary statistics."""

    frames: list[Frame]
    calibration: list[Frame]
    mm_per_px: float
    summary: dict = field(default_factory=dict)


def pinhole_camera(scene: Scene) -> PinholeCamera:
    """The scene's camera as a pinhole at its entrance pupil, with its first-order
    magnification at the plane in focus and its pose (what the geometric gaze model assumes)."""
    from eyelume.compile import compile_scene

    cs = compile_scene(scene)
    fo = cs.first_order
    return PinholeCamera(
        node_mm=(0.0, 0.0, fo.entrance_pupil_z),
        cols=scene.sensor.cols,
        rows=scene.sensor.rows,
        sensor_width_mm=scene.sensor.field_mm[0],
        magnification=fo.magnification,
        frame=None if cs.frame.is_identity else cs.frame,
    )


def picture_mm_per_px(scene: Scene, camera: PinholeCamera | None = None) -> float:
    """Millimetres of the eye plane (z = 0, world) per picture pixel, the scale of the
    tracking summary's millimetre figures: the pinhole camera's on the plane in focus
    (:func:`pinhole_camera`, ``scale_mm``); with optical elements between the eye and the
    camera (an eyepiece magnifies, a fold mirror folds), the pinhole sees none of them, so the
    scale is taken from real chief rays instead — those of the sensor points ±ε along x and
    along y, past the elements (:func:`eyelume.analysis.truth._chief_ray`), met with the eye
    plane: the mean of the two spans over 2ε, times the sensor's millimetres per pixel."""
    if not scene.elements:
        return (camera or pinhole_camera(scene)).scale_mm
    from eyelume.analysis.truth import _chief_ray
    from eyelume.compile import compile_scene

    cs = compile_scene(scene)
    eps = 0.005  # mm on the sensor: paraxial, ~0.4 px of paper2005-integrated
    spans = []
    for axis in (0, 1):
        hits = []
        for sign in (-1.0, 1.0):
            xs = np.zeros(2)
            xs[axis] = sign * eps
            ray = _chief_ray(cs, cs.camera, *xs)
            if ray is None:
                return (camera or pinhole_camera(scene)).scale_mm
            p, d = cs.frame.world_point(ray[0]), cs.frame.world_vector(ray[1])
            hits.append(p - p[2] / d[2] * d)
        spans.append(float(np.linalg.norm(hits[1] - hits[0])) / (2 * eps))
    return float(np.mean(spans)) * cs.picture.width_mm / cs.picture.cols


def led_picture_azimuths(cs) -> list[float]:
    """The direction (degrees; 0° = picture +x, 90° = up) in which each LED's glint lies from
    the middle of the glints, for matching found glints to LEDs.

    The paper's rig (the camera on the eye's axis, the paper's ring): the LEDs' own azimuths.
    A camera or LEDs anywhere:
    LED k's glint lies where the corneal sphere (centre **c**, radius R, eye in primary gaze)
    has its normal along the bisector of the directions to the LED and to the camera's
    entrance pupil E, **g**ₖ = **c** + R · unit(unit(Lₖ − **c**) + unit(E − **c**)) (the law of
    reflection for a glint seen from E, in the small-glint limit); each is projected by the
    pinhole camera of :func:`pinhole_camera` and its direction taken from their mean."""
    scene = cs.scene
    paper_eye = scene.eye_pose.which == "right" and not any(scene.eye_pose.vertex_mm)
    if cs.frame.is_identity and scene.leds.is_paper_ring and paper_eye:
        return list(scene.leds.azimuths())
    g = led_picture_pattern(cs)
    return [math.degrees(math.atan2(-dy, dx)) % 360.0 for dx, dy in g]


def led_picture_pattern(cs) -> np.ndarray:
    """(k, 2) px: where each LED's glint lies relative to the glints' mean in the picture, the
    eye in primary gaze — the small-glint reflection points of :func:`led_picture_azimuths`
    projected by the pinhole camera of :func:`pinhole_camera`. The detector checks the matched
    glints against this layout when some are missing (``detect(led_pattern_px=…)``). The
    cornea here is the sphere of the flat meridian's radius on the optical axis: an astigmatic
    cornea (``eye.cornea``) squeezes the real pattern across its steep meridian by about
    R_steep/R_flat (4 % for 2 D) and a decentred one shifts it; whether the detector's
    pattern tolerance takes that has not been checked. With optical elements between the eye
    and the camera (an eyepiece magnifies the pattern, a fold mirror mirrors it) the pinhole
    does not see the glints where they are: the truth's glints (:func:`eyelume.analysis.truth.
    eye_truth`, followed through the elements) in primary gaze give the layout instead, when
    every LED has one."""
    from eyelume.compile import compile_scene, eye_point

    scene = cs.scene
    if scene.elements:
        from eyelume.analysis.truth import eye_truth

        eye = scene.eye.model_copy(update={"gaze_horizontal_deg": 0.0, "gaze_vertical_deg": 0.0})
        glints = eye_truth(compile_scene(scene.model_copy(update={"eye": eye})))["glints"]
        if glints and all(g["centre_px"] is not None for g in glints):
            at = np.array([g["centre_px"] for g in glints], float)
            return at - at.mean(axis=0)
    cam = pinhole_camera(scene)
    radius = scene.eye.surfaces[0].radius_mm
    c = cs.frame.point(eye_point(scene, [0.0, 0.0, -radius], 0.0, 0.0))
    e = np.array([0.0, 0.0, cs.first_order.entrance_pupil_z]) - c
    e /= np.linalg.norm(e)
    pts = []
    for led in cs.led.points:
        d = led - c
        n = d / np.linalg.norm(d) + e
        pts.append(cam.project(c + radius * n / np.linalg.norm(n)))
    return np.asarray(pts, float) - np.mean(pts, axis=0)


def _truth_ellipse_centre(truth: dict) -> tuple[float, float] | None:
    import cv2

    edge = np.asarray(truth["pupil"]["edge_px"], dtype=np.float32)
    if len(edge) < 5:
        return None
    (cx, cy), _, _ = cv2.fitEllipse(edge)
    return float(cx), float(cy)


def analyse_frame(
    gaze: tuple[float, float],
    counts: np.ndarray,
    truth: dict,
    led_azimuths_deg: Sequence[float],
    render_s: float = 0.0,
    led_pattern_px: np.ndarray | None = None,
) -> Frame:
    """Detect the pupil and glints on one digital picture ``counts`` (rows, cols) of the eye at
    ``gaze`` (h, v degrees) and compare with its ``truth`` (:func:`eyelume.analysis.truth.
    eye_truth`): pupil-centre error (px), glints found and matched, the pupil–glint vector.
    ``led_pattern_px``: the glints' predicted layout (:func:`led_picture_pattern`), checked
    when some are missing."""
    det = detect(counts, led_azimuths_deg=list(led_azimuths_deg), led_pattern_px=led_pattern_px)
    f = Frame(tuple(gaze), det, truth, render_s=render_s)
    f.detect_ms = float(det.timings_ms.get("total", math.nan))
    f.glints_true = sum(1 for g in truth["glints"] if g["visible"])
    f.glints_found = sum(1 for g in det.glints if g.led is not None)
    centre = _truth_ellipse_centre(truth)
    if det.pupil is not None and centre is not None:
        f.pupil_error_px = float(np.hypot(*(np.subtract(det.pupil.centre_px, centre))))
    glints: list = [None] * len(led_azimuths_deg)
    for g in det.glints:
        if g.led is not None:
            glints[g.led] = g.centre_px
    f.glints_px = glints
    ghosts = false_glints(det.glints, truth)
    f.false_glints = len(ghosts)
    f.rim_glints = len(rim_glints(det.glints, truth))
    f.stray_glints = len(stray_glints(det.glints, truth, ghosts))
    _set_pg_vector(f, None)
    return f


def rim_glints(glints, truth: dict) -> list[int]:
    """Indices into ``glints`` (detected, matched ones only) of those matched to an LED whose
    true glint the cornea's rim cuts (``truth["glints"][·]["at_rim"]``,
    :func:`eyelume.analysis.truth._rim_glint`): a real but partial spot, its centroid
    ``rim.bias_px`` off the whole glint's centre, which the gaze models take it for (one whose
    spot is hidden is a :func:`stray_glints`)."""
    cut = {g["led"] for g in truth["glints"] if g.get("at_rim")} & _spots(truth)
    return [i for i, g in enumerate(glints) if g.led is not None and g.led in cut]


def _spots(truth: dict) -> set[int]:
    """The LEDs with a spot in the truth: a visible glint, or a visible partial one at the rim."""
    return {
        g["led"]
        for g in truth["glints"]
        if g["visible"] or (g.get("at_rim") and (g.get("rim") or {}).get("visible"))
    }


def stray_glints(glints, truth: dict, ghosts: Sequence[int] = ()) -> list[int]:
    """Indices into ``glints`` of those matched to an LED that has no spot in the truth — its
    glint neither visible on the cornea nor a visible partial spot at the rim (off the cornea,
    hidden by a lid) — other than the element ghosts ``ghosts`` (:func:`false_glints`, counted
    there): a speck or a stray reflection taken for that LED's glint."""
    spot = _spots(truth)
    return [
        i
        for i, g in enumerate(glints)
        if g.led is not None and g.led not in spot and i not in set(ghosts)
    ]


def false_glints(glints, truth: dict, radius_px: float = FALSE_GLINT_PX) -> list[int]:
    """Indices into ``glints`` (detected, :class:`~.detect.Glint`: ``centre_px`` (x, y) px
    and ``led``) of those matched to an LED that are a false spot, not the corneal glint: an
    element's ghost (``truth["ghosts"]``, :mod:`eyelume.analysis.ghosts`) or the sun's own
    corneal glint (``truth["sun_glint"]``, :func:`eyelume.analysis.truth.eye_truth`): within
    max(``radius_px``, the ghost's ``blur_px``/2) of a visible one's true centre and nearer to
    it than to that LED's true glint (or the LED has no visible glint). A frame without
    either in its truth (no elements, no sun): []."""
    ghosts = [g for g in truth.get("ghosts", []) if g["visible"]]
    sun = truth.get("sun_glint")
    if sun is not None and sun["visible"] and sun["centre_px"] is not None:
        ghosts.append(sun)
    if not ghosts:
        return []
    true = {
        g["led"]: g["centre_px"]
        for g in truth["glints"]
        if g["visible"] and g["centre_px"] is not None
    }
    out = []
    for i, g in enumerate(glints):
        if g.led is None:
            continue
        own = true.get(g.led)
        d_own = math.inf if own is None else math.dist(g.centre_px, own)
        for e in ghosts:
            d = math.dist(g.centre_px, e["centre_px"])
            if d <= max(radius_px, 0.5 * (e.get("blur_px") or 0.0)) and d < d_own:
                out.append(i)
                break
    return out


def _set_pg_vector(f: Frame, offsets: np.ndarray | None) -> None:
    """The frame's pupil–glint vector from its matched glints (None when the detection is not
    ok or no usable glint): with ``offsets`` (:func:`~.gaze.glint_offsets`) from the glint
    pattern's centre, else from the mean of the matched glints."""
    det = f.detection
    f.pg_vector = None
    if not det.ok or det.pupil is None or not f.glints_px:
        return
    v = pupil_glint_vector(np.asarray(det.pupil.centre_px), f.glints_px, offsets=offsets)
    if np.isfinite(v).all():
        f.pg_vector = (float(v[0]), float(v[1]))


def _calibration_offsets(calibration: list[Frame]) -> np.ndarray | None:
    """Each LED's glint offset from the pattern's centre over the calibration frames answered
    ``ok`` (:func:`~.gaze.glint_offsets`), or None when there are none."""
    rows = [
        [[np.nan, np.nan] if g is None else g for g in f.glints_px]
        for f in calibration
        if f.detection.ok and f.glints_px
    ]
    return glint_offsets(np.asarray(rows, dtype=float)) if rows else None


def _geometric(model: GeometricGaze, frame: Frame, n_leds: int) -> tuple[float, float] | None:
    """The geometric model's gaze from the frame's matched glints only (None for the others)."""
    det = frame.detection
    if not det.ok or det.pupil is None:
        return None
    glints: list = [None] * n_leds
    for g in det.glints:
        if g.led is not None:
            glints[g.led] = g.centre_px
    est = model.estimate(det.pupil.centre_px, glints)
    frame.geometric_refused = "" if est.ok else est.reason
    return (est.h_deg, est.v_deg) if est.ok else None


#: The gaze of the geometric model's one-point kappa calibration frame (:func:`kappa_offset`).
KAPPA_GAZE = (0.0, 0.0)


def is_kappa_frame(frame: Frame) -> bool:
    """The test ``frame`` is the geometric model's own kappa calibration frame (the calibration
    frame at :data:`KAPPA_GAZE`, the same picture): its geometric error is 0 by construction,
    not a measurement, so it is left out of the geometric statistics and marked "cal"."""
    return bool(frame.calibration) and tuple(frame.gaze) == KAPPA_GAZE


def kappa_offset(
    model: GeometricGaze, calibration: list[Frame], n_leds: int, left: bool
) -> tuple[float, float] | None:
    """The geometric model's one-point kappa calibration (Guestrin & Eizenman's, as an additive
    angle offset): target − estimate (h, v degrees) at the central calibration frame (gaze
    (0°, 0°)); None without that frame or when the model gives no estimate there. ``left``:
    the model's angles mirrored as :func:`analyse_frames` does."""
    centre = [f for f in calibration if tuple(f.gaze) == KAPPA_GAZE]
    if not centre:
        return None
    est = _geometric(model, centre[0], n_leds)
    if est is None:
        return None
    h, v = (-est[0], est[1]) if left else est
    return (0.0 - h, 0.0 - v)


#: Why an element scene's summary has no geometric gaze (``gaze_geometric.not_applicable``).
GEOMETRIC_NOT_THROUGH_ELEMENTS = (
    "the geometric model's pinhole camera does not see through the scene's optical elements "
    "(eyepiece, mirror, glasses): use gaze_pccr"
)


def analyse_frames(
    scene: Scene, leds_mm: np.ndarray, frames: list[Frame], calibration: list[Frame]
) -> TrackingReport:
    """Gaze estimates and statistics of the test ``frames``: the PCCR polynomial fitted on the
    ``calibration`` frames (when at least 6 have a pupil–glint vector) and the geometric model
    of ``scene``'s camera with the LEDs at ``leds_mm`` (n, 3) in the camera frame (mm: the
    compiled scene's LED table, :mod:`eyelume.scene.pose`; the world frame for the paper's
    rig).

    The pupil–glint vectors of both are taken from the glint pattern's centre with the LEDs'
    offsets of the calibration frames (:func:`_calibration_offsets`), so a frame missing some
    glints keeps the reference of one with all."""
    offsets = _calibration_offsets(calibration)
    for f in [*calibration, *frames]:
        _set_pg_vector(f, offsets)
    usable = [f for f in calibration if f.pg_vector is not None]
    pccr = None
    if len(usable) >= 6:
        pccr = PccrModel.fit(
            np.array([f.pg_vector for f in usable]), np.array([f.gaze for f in usable])
        )
    camera = pinhole_camera(scene)
    # the geometric model's camera is a pinhole looking straight at the eye: through optical
    # elements (an eyepiece and fold, glasses) its glints' rays are not the camera's, and its
    # answer would be wrong, not approximate (108° mean on paper2005-integrated): none then.
    # Its cornea is a sphere: glints reflected farther than SPHERE_ZONE_DEG from the apex of
    # the real, aspheric cornea are left out (a frame with < 2 inside is refused)
    geometric = None if scene.elements else GeometricGaze(camera, leds_mm, zone_deg=SPHERE_ZONE_DEG)
    left = scene.eye_pose.which == "left"
    kappa = None if geometric is None else kappa_offset(geometric, calibration, len(leds_mm), left)
    for f in frames:
        if pccr is not None and f.pg_vector is not None:
            f.pccr = tuple(float(x) for x in pccr.predict(np.array([f.pg_vector]))[0])
        f.geometric = None if geometric is None else _geometric(geometric, f, len(leds_mm))
        if f.geometric is not None and left:
            # the model's angles are the world's (h toward +x); a left eye's scene gaze is
            # anatomical (h toward the nose, world −x): mirror to compare
            f.geometric = (-f.geometric[0], f.geometric[1])
        if f.geometric is not None and kappa is not None:
            f.geometric = (f.geometric[0] + kappa[0], f.geometric[1] + kappa[1])
    report = TrackingReport(frames, calibration, picture_mm_per_px(scene, camera))
    report.summary = summarise(report, pccr_calibrated=pccr is not None)
    report.summary["geometric_kappa_deg"] = None if kappa is None else list(kappa)
    if geometric is None:
        report.summary["gaze_geometric"]["not_applicable"] = GEOMETRIC_NOT_THROUGH_ELEMENTS
    report.summary["safety"] = eye_safety(scene)
    return report


def _errors(frames: list[Frame], attr: str) -> np.ndarray:
    out = []
    for f in frames:
        if attr == "pccr" and f.calibration:
            continue  # the PCCR polynomial was fitted on this very picture
        if attr == "geometric" and is_kappa_frame(f):
            continue  # the kappa offset was taken on this very picture: error 0 by construction
        est = getattr(f, attr)
        if est is not None:
            out.append(math.hypot(est[0] - f.gaze[0], est[1] - f.gaze[1]))
    return np.asarray(out)


def summarise(report: TrackingReport, pccr_calibrated: bool) -> dict:
    """Detection rate, pupil-centre error (px, mm), glints per frame, false glints (total,
    frames with any, mean per frame: :func:`false_glints`), glints cut by the cornea's rim
    and stray glints (total, frames with any, ok frames with any: :func:`rim_glints`,
    :func:`stray_glints`), ``clean_detection_rate`` (the share of frames answered ok with
    none of those three), gaze errors (°). The PCCR error's
    statistics leave out the test frames that are calibration frames (``Frame.calibration``:
    their error is the fit's in-sample residual), the geometric error's leave out the kappa
    calibration frame (:func:`is_kappa_frame`: error 0 by construction), each saying how many
    (``calibration_frames_excluded``)."""
    frames = report.frames
    ok = [f for f in frames if f.detection.ok]
    pe = np.array([f.pupil_error_px for f in ok if math.isfinite(f.pupil_error_px)])

    def stats(e: np.ndarray) -> dict:
        if e.size == 0:
            return {"frames": 0}
        return {
            "frames": int(e.size),
            "mean_deg": float(e.mean()),
            "p95_deg": float(np.percentile(e, 95)),
            "max_deg": float(e.max()),
        }

    return {
        "frames": len(frames),
        "detection_rate": len(ok) / len(frames) if frames else 0.0,
        "pupil_error_px": {
            "mean": float(pe.mean()) if pe.size else None,
            "p95": float(np.percentile(pe, 95)) if pe.size else None,
        },
        "pupil_error_mm": {
            "mean": float(pe.mean() * report.mm_per_px) if pe.size else None,
            "p95": float(np.percentile(pe, 95) * report.mm_per_px) if pe.size else None,
        },
        "glints_per_frame": {
            "found_mean": float(np.mean([f.glints_found for f in frames])),
            "true_mean": float(np.mean([f.glints_true for f in frames])),
        },
        "false_glints": {
            "total": int(sum(f.false_glints for f in frames)),
            "frames_with": int(sum(f.false_glints > 0 for f in frames)),
            "per_frame_mean": float(np.mean([f.false_glints for f in frames])) if frames else 0.0,
        },
        "rim_glints": {
            "total": int(sum(f.rim_glints for f in frames)),
            "frames_with": int(sum(f.rim_glints > 0 for f in frames)),
            "ok_frames_with": int(sum(f.rim_glints > 0 for f in ok)),
        },
        "stray_glints": {
            "total": int(sum(f.stray_glints for f in frames)),
            "frames_with": int(sum(f.stray_glints > 0 for f in frames)),
            "ok_frames_with": int(sum(f.stray_glints > 0 for f in ok)),
        },
        "clean_detection_rate": (
            sum(f.false_glints + f.rim_glints + f.stray_glints == 0 for f in ok) / len(frames)
            if frames
            else 0.0
        ),
        "gaze_pccr": (
            {
                **stats(_errors(frames, "pccr")),
                "calibration_frames_excluded": sum(f.calibration for f in frames),
            }
            if pccr_calibrated
            else {"frames": 0}
        ),
        "gaze_geometric": {
            **stats(_errors(frames, "geometric")),
            "calibration_frames_excluded": sum(is_kappa_frame(f) for f in frames),
            # frames detected ok that the model refused, e.g. with < 2 glints within its
            # spherical cornea's validity zone (GeometricGaze.zone_deg)
            "refused": sum(bool(f.geometric_refused) for f in ok),
            "refused_outside_zone": sum("validity zone" in f.geometric_refused for f in ok),
        },
        "render_s_per_frame": float(np.mean([f.render_s for f in frames])),
        "detect_ms_per_frame": float(np.nanmean([f.detect_ms for f in frames])),
        "saturated_share": float(np.mean([f.saturated_share for f in frames])) if frames else 0.0,
        **ambient_stats(frames),
        "failure_causes": failure_causes(frames),
        "failures": {
            f"{f.gaze[0]:+.0f},{f.gaze[1]:+.0f}": f.detection.failures
            for f in frames
            if f.detection.failures
        },
    }


#: The signal-to-ambient ratios a frame keeps (:func:`ambient_ratios`).
AMBIENT_RATIOS = (
    "glint_signal_to_ambient_min",
    "glint_peak_over_ambient_peak",
    "pupil_signal_to_ambient",
)


def ambient_ratios(rated: dict) -> dict:
    """A frame's ratios (:data:`AMBIENT_RATIOS`) from
    :func:`eyelume.analysis.ambient.signal_to_ambient`'s result."""
    pupil = rated.get("pupil")
    return {
        "glint_signal_to_ambient_min": rated["glint_signal_to_ambient_min"],
        "glint_peak_over_ambient_peak": rated["glint_peak_over_ambient_peak"],
        "pupil_signal_to_ambient": None if pupil is None else pupil["signal_to_ambient"],
    }


def ambient_stats(frames: list[Frame]) -> dict:
    """``{"signal_to_ambient": {ratio: {frames, min, median}}}`` over the frames rendered with
    sunlight (a ratio that is unbounded — no ambient on the pixel — or not rated is left out
    and not counted in ``frames``); {} when no frame had sunlight."""
    rated = [f.ambient for f in frames if f.ambient is not None]
    if not rated:
        return {}
    out = {}
    for key in AMBIENT_RATIOS:
        v = np.array([a[key] for a in rated if a.get(key) is not None], dtype=float)
        out[key] = (
            {"frames": int(v.size), "min": float(v.min()), "median": float(np.median(v))}
            if v.size
            else {"frames": 0}
        )
    return {"signal_to_ambient": out}


def failure_causes(frames: list[Frame]) -> dict[str, int]:
    """Frames per kind of detection failure (the text before the first colon: "glint lost",
    "pupil cut or hidden", …), most frequent first; warnings are not counted."""
    counts: dict[str, int] = {}
    for f in frames:
        if f.detection.ok:
            continue
        kinds = {x.split(":")[0] for x in f.detection.failures if not x.startswith("warning")}
        for k in kinds or {"no detection"}:
            counts[k] = counts.get(k, 0) + 1
    # Most frequent first, ties by name: the same frames give the same order whatever the
    # process's string hashing (a set's order; 'mostly …' named LED 2's cause in one run and
    # LED 0's in the next on identical frames).
    return dict(sorted(counts.items(), key=lambda kv: (-kv[1], kv[0])))


#: A share of saturated pixels above which saturation is named as the cause of lost frames: a
#: picture where most of the face is white has no pupil/iris contrast left to threshold.
SATURATED_CAUSE = 0.25


def failure_reason(summary: dict) -> str | None:
    """Why frames were lost, in a few words (None when every frame was detected): saturation
    when the frames' mean saturated share exceeds :data:`SATURATED_CAUSE`, else the most
    frequent cause with its count."""
    if summary.get("detection_rate", 1.0) >= 1.0:
        return None
    share = summary.get("saturated_share", 0.0)
    if share > SATURATED_CAUSE:
        return (
            f"saturation: {share:.0%} of the pixels at full scale (shorten sensor.exposure_ms "
            "or dim the LEDs)"
        )
    causes = summary.get("failure_causes") or {}
    if not causes:
        return None
    kind, n = next(iter(causes.items()))
    return f"mostly {kind} ({n} of {summary['frames']} frames)"


def mean_deg(stats: dict) -> str:
    """A gaze error's mean in degrees, or "no estimate" when no frame gave one."""
    mean = stats.get("mean_deg")
    return "no estimate" if mean is None or not math.isfinite(mean) else f"{mean:.2f}°"


#: Gaze error charged to a frame whose detection failed (degrees): a tracker that loses the eye
#: is worse than one that is a few degrees off.
FAILED_FRAME_DEG = 10.0


def tracking_score(report: TrackingReport) -> float:
    """One number for the optimiser (degrees, lower is better): the mean geometric gaze error
    over the test frames, each failed frame (no detection or no estimate) counted as
    FAILED_FRAME_DEG."""
    errs = []
    for f in report.frames:
        e = (
            None
            if f.geometric is None
            else math.hypot(f.geometric[0] - f.gaze[0], f.geometric[1] - f.gaze[1])
        )
        errs.append(FAILED_FRAME_DEG if e is None else min(e, FAILED_FRAME_DEG))
    return float(np.mean(errs)) if errs else math.inf


def _err(est: tuple[float, float] | None, gaze: tuple[float, float]) -> float | None:
    return None if est is None else math.hypot(est[0] - gaze[0], est[1] - gaze[1])


def _finite(x: float | None) -> float | None:
    return float(x) if x is not None and math.isfinite(x) else None


def error_map_rows(frames: Sequence[Frame]) -> list[dict]:
    """One plain row per frame for the error maps over the gaze grid: ``gaze`` (h, v °),
    ``pupil_error_px`` (None where detection failed), ``glints_found``, ``false_glints``
    (:func:`false_glints`), ``rim_glints``, ``stray_glints`` (:func:`rim_glints`,
    :func:`stray_glints`), ``pccr_error_deg`` and
    ``geometric_error_deg`` (None without an estimate), ``calibration`` (the frame is a
    calibration frame: its PCCR error is the fit's in-sample residual, ``Frame.calibration``),
    ``geometric_calibration`` (the frame is the geometric model's kappa calibration frame:
    :func:`is_kappa_frame`, its geometric error 0 by construction).
    JSON-ready: a study stores them."""
    return [
        {
            "gaze": [float(f.gaze[0]), float(f.gaze[1])],
            "pupil_error_px": _finite(f.pupil_error_px) if f.detection.ok else None,
            "glints_found": int(f.glints_found),
            "false_glints": int(f.false_glints),
            "rim_glints": int(f.rim_glints),
            "stray_glints": int(f.stray_glints),
            "pccr_error_deg": _finite(_err(f.pccr, f.gaze)),
            "geometric_error_deg": _finite(_err(f.geometric, f.gaze)),
            "calibration": bool(f.calibration),
            "geometric_calibration": is_kappa_frame(f),
        }
        for f in frames
    ]
