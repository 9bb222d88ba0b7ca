"""Tracking quality of an illumination scheme: render the eye over a grid of gazes, detect the
pupil and glints on the camera's digital images, estimate gaze, and compare with the truth.

For each gaze the scene is rendered (fast estimator), read out by the sensor model, run through
the paper's detection pipeline (:mod:`.detect`) and compared with the renderer's own truth
(:func:`eyelume.analysis.truth.eye_truth`): pupil-centre error (the detected ellipse's centre
against the centre of the ellipse through the true apparent pupil edge), glints found and
matched. Gaze comes from two estimators (:mod:`.gaze`): the PCCR polynomial, calibrated on a
3 × 3 grid of gazes rendered for that purpose and evaluated on the held-out test grid, and the
Guestrin–Eizenman geometric model from the glints, which needs no calibration.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from eyelume.analysis.safety import eye_safety
from eyelume.analysis.tracking.detect import Detection, detect
from eyelume.analysis.tracking.gaze import GeometricGaze, PccrModel, PinholeCamera
from eyelume.analysis.truth import eye_truth
from eyelume.compile import compile_scene
from eyelume.detectors.sensor import digitize
from eyelume.render import render
from eyelume.scene.io import apply_overrides
from eyelume.scene.model import Scene

__all__ = [
    "POPULATION",
    "Frame",
    "TrackingReport",
    "evaluate_population",
    "evaluate_tracking",
    "pinhole_camera",
    "tracking_score",
]

#: The classic 9-point calibration: a 3 × 3 grid of gaze targets (degrees).
CALIBRATION_H = (-20.0, 0.0, 20.0)
CALIBRATION_V = (-15.0, 0.0, 15.0)
#: The test grid of the issue: 7 × 5 gazes.
TEST_H = (-30.0, -20.0, -10.0, 0.0, 10.0, 20.0, 30.0)
TEST_V = (-20.0, -10.0, 0.0, 10.0, 20.0)


@dataclass
class Frame:
    """One rendered gaze: detection against truth, and the gaze estimates (degrees)."""

    gaze: tuple[float, float]
    detection: Detection
    truth: dict
    pupil_error_px: float = math.nan
    glints_found: int = 0
    glints_true: int = 0
    pg_vector: tuple[float, float] | None = None
    pccr: tuple[float, float] | None = None
    geometric: tuple[float, float] | None = None
    render_s: float = 0.0
    detect_ms: float = 0.0


@dataclass
class TrackingReport:
    """Frames of the test grid (and the calibration frames) with the summary statistics."""

    frames: list[Frame]
    calibration: list[Frame]
    mm_per_px: float
    summary: dict = field(default_factory=dict)


def pinhole_camera(scene: Scene) -> PinholeCamera:
    """The scene's camera as a pinhole at its entrance pupil, with its paraxial magnification
    at the eye plane (what the geometric gaze model assumes)."""
    from eyelume.compile import lens_indices, lens_paraxial

    par = lens_paraxial(scene, lens_indices(scene)[0])
    stop = next(j for j, s in enumerate(scene.lens.surfaces) if s.stop)
    node = scene.lens.object_distance_mm + par.entrance_pupil_position(stop)
    return PinholeCamera(
        node_mm=(0.0, 0.0, node),
        cols=scene.sensor.cols,
        rows=scene.sensor.rows,
        sensor_width_mm=scene.sensor.width_mm,
        magnification=par.magnification(scene.lens.object_distance_mm),
    )


def _truth_ellipse_centre(truth: dict) -> tuple[float, float] | None:
    import cv2

    edge = np.asarray(truth["pupil"]["edge_px"], dtype=np.float32)
    if len(edge) < 5:
        return None
    (cx, cy), _, _ = cv2.fitEllipse(edge)
    return float(cx), float(cy)


def _frame(scene: Scene, h: float, v: float, samples: int, seed: int) -> Frame:
    sc = apply_overrides(scene, {"eye.gaze_horizontal_deg": h, "eye.gaze_vertical_deg": v})
    cs = compile_scene(sc)
    result = render(cs, estimator="fast", samples_per_pixel=samples, seed=seed)
    counts = digitize(result.eye_image, sc.sensor, sc.wavelength_nm, seed=seed).counts
    det = detect(counts, led_azimuths_deg=list(sc.leds.azimuths()))
    truth = eye_truth(cs)
    f = Frame((h, v), det, truth, render_s=result.wall_time_s)
    f.detect_ms = float(det.timings_ms.get("total", math.nan))
    f.glints_true = sum(1 for g in truth["glints"] if g["visible"])
    f.glints_found = sum(1 for g in det.glints if g.led is not None)
    centre = _truth_ellipse_centre(truth)
    if det.pupil is not None and centre is not None:
        f.pupil_error_px = float(np.hypot(*(np.subtract(det.pupil.centre_px, centre))))
    if det.ok and det.pupil is not None:
        matched = [g.centre_px for g in det.glints if g.led is not None]
        if matched:
            mean = np.mean(np.asarray(matched), axis=0)
            f.pg_vector = (det.pupil.centre_px[0] - mean[0], det.pupil.centre_px[1] - mean[1])
    return f


def _geometric(model: GeometricGaze, frame: Frame, n_leds: int) -> tuple[float, float] | None:
    det = frame.detection
    if not det.ok or det.pupil is None:
        return None
    glints: list = [None] * n_leds
    for g in det.glints:
        if g.led is not None:
            glints[g.led] = g.centre_px
    est = model.estimate(det.pupil.centre_px, glints)
    return (est.h_deg, est.v_deg) if est.ok else None


def evaluate_tracking(
    scene: Scene,
    test_h: Sequence[float] = TEST_H,
    test_v: Sequence[float] = TEST_V,
    samples_per_pixel: int = 16,
    seed: int = 0,
    progress: Callable[[str], None] | None = None,
    calibration_scene: Scene | None = None,
    calibrate: bool = True,
) -> TrackingReport:
    """Render, detect and estimate gaze over the calibration and test grids (module doc).

    ``calibration_scene`` (default ``scene``) is the scene the PCCR calibration is rendered in:
    pass the nominal scene to measure a headset slip after calibration. Without ``calibrate``
    only the geometric model (which needs no calibration) estimates gaze."""
    calib = []
    for v in CALIBRATION_V if calibrate else ():
        for h in CALIBRATION_H:
            calib.append(_frame(calibration_scene or scene, h, v, samples_per_pixel, seed))
    frames = []
    for v in test_v:
        for h in test_h:
            frames.append(_frame(scene, h, v, samples_per_pixel, seed))
            if progress:
                f = frames[-1]
                progress(
                    f"gaze ({h:+.0f}°, {v:+.0f}°): "
                    + ("ok" if f.detection.ok else "; ".join(f.detection.failures))
                )
    usable = [f for f in calib if f.pg_vector is not None]
    pccr = None
    if len(usable) >= 6:
        pccr = PccrModel.fit(
            np.array([f.pg_vector for f in usable]), np.array([f.gaze for f in usable])
        )
    leds = compile_scene(scene).leds[:, :3]
    geometric = GeometricGaze(pinhole_camera(scene), leds)
    for f in frames:
        if pccr is not None and f.pg_vector is not None:
            f.pccr = tuple(float(x) for x in pccr.predict(np.array([f.pg_vector]))[0])
        f.geometric = _geometric(geometric, f, len(leds))
    mm_per_px = pinhole_camera(scene).scale_mm  # eye-plane mm per pixel
    report = TrackingReport(frames, calib, mm_per_px)
    report.summary = summarise(report, pccr_calibrated=pccr is not None)
    report.summary["safety"] = eye_safety(scene)
    return report


def _errors(frames: list[Frame], attr: str) -> np.ndarray:
    out = []
    for f in frames:
        est = getattr(f, attr)
        if est is not None:
            out.append(math.hypot(est[0] - f.gaze[0], est[1] - f.gaze[1]))
    return np.asarray(out)


def summarise(report: TrackingReport, pccr_calibrated: bool) -> dict:
    """Detection rate, pupil-centre error (px, mm), glints per frame, gaze errors (°)."""
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
        "gaze_pccr": stats(_errors(frames, "pccr")) if pccr_calibrated else {"frames": 0},
        "gaze_geometric": stats(_errors(frames, "geometric")),
        "render_s_per_frame": float(np.mean([f.render_s for f in frames])),
        "detect_ms_per_frame": float(np.nanmean([f.detect_ms for f in frames])),
        "failures": {
            f"{f.gaze[0]:+.0f},{f.gaze[1]:+.0f}": f.detection.failures
            for f in frames
            if f.detection.failures
        },
    }


#: The population of the issue: iris dark to light, skin reflectance range, eyelid aperture,
#: headset slip of ± 2 mm (after calibration: the PCCR polynomial is the nominal user's).
#: Reflectances: dark brown iris ~2 %, light blue/grey ~15 % at 850 nm; skin 6–35 % across skin
#: types in the near infrared (the paper's Table 2 gives 12 % for its Caucasian skin).
POPULATION: tuple[tuple[str, dict, bool], ...] = (
    ("nominal", {}, True),
    ("dark iris", {"eye.iris_reflectance": 0.02}, True),
    ("light iris", {"eye.iris_reflectance": 0.15}, True),
    ("dark skin", {"face.skin_reflectance": 0.06}, True),
    ("light skin", {"face.skin_reflectance": 0.35}, True),
    (
        "narrow lids",
        {"face.tissues.0.clip_z_mm": [3.0, 14.0], "face.tissues.1.clip_z_mm": [4.0, 14.0]},
        True,
    ),
    ("slip +2 mm x", {"head_offset_mm": [2.0, 0.0, 0.0]}, False),
    ("slip -2 mm y", {"head_offset_mm": [0.0, -2.0, 0.0]}, False),
)


def evaluate_population(
    scene: Scene,
    population: Sequence[tuple[str, dict, bool]] = POPULATION,
    test_h: Sequence[float] = TEST_H,
    test_v: Sequence[float] = TEST_V,
    samples_per_pixel: int = 16,
    seed: int = 0,
    progress: Callable[[str], None] | None = None,
) -> dict[str, TrackingReport]:
    """:func:`evaluate_tracking` for each member of ``population``: (name, scene overrides,
    whether the user calibrates in that state — False for a slip after calibration)."""
    out = {}
    for name, overrides, recalibrate in population:
        member = apply_overrides(scene, overrides) if overrides else scene
        out[name] = evaluate_tracking(
            member,
            test_h,
            test_v,
            samples_per_pixel,
            seed,
            calibration_scene=None if recalibrate else scene,
        )
        if progress:
            s = out[name].summary
            progress(
                f"{name}: detection {s['detection_rate']:.0%}, geometric gaze "
                f"{s['gaze_geometric'].get('mean_deg', math.nan):.2f}° mean, PCCR "
                f"{s['gaze_pccr'].get('mean_deg', math.nan):.2f}°"
            )
    return out


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
