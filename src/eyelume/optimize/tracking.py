"""Tracking evaluated by rendering: the eye over a grid of gazes, rendered, read out by the
sensor and analysed (:mod:`eyelume.analysis.tracking.evaluate`); and illumination chosen for
tracking itself.

:func:`evaluate_tracking` renders each gaze of a calibration grid (3 × 3) and a test grid (7 × 5
by default) with the fast estimator, digitises it (:func:`eyelume.detectors.sensor.digitize`),
and hands the pictures with the renderer's truth (:func:`eyelume.analysis.truth.eye_truth`) to
the analysis. :func:`evaluate_population` does it for each member of a population.

:func:`sweep_tracking` scores LED placements by the gaze error of the whole pipeline (render →
camera → detection → geometric gaze), against the paper's proxies. Each placement is rendered
over a 3 × 3 grid of gazes (±20° horizontal, ±10° vertical) and scored by
:func:`eyelume.analysis.tracking.evaluate.tracking_score` (mean geometric gaze error, a failed
frame counted as 10°). The grid of placements is coarse (Y 20/30/40 mm, Z 50/60/70 mm, θ
0/15/30°: 27 placements), each scored with the same seed; the δ-optimal placement of the
generator and the paper's placement are scored the same way for comparison.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from eyelume.analysis.ambient import signal_to_ambient
from eyelume.analysis.tracking.evaluate import (
    CALIBRATION_H,
    CALIBRATION_V,
    TEST_H,
    TEST_V,
    Frame,
    TrackingReport,
    ambient_ratios,
    analyse_frame,
    analyse_frames,
    failure_reason,
    led_picture_azimuths,
    led_picture_pattern,
    mean_deg,
    tracking_score,
)
from eyelume.analysis.truth import eye_truth
from eyelume.compile import compile_scene
from eyelume.detectors.sensor import digitize
from eyelume.errors import SceneError
from eyelume.estimators.interrupt import PartialRun, run_unit
from eyelume.optimize.delta_study import PAPER_CHOICE, with_placement
from eyelume.render import RenderOptions, render
from eyelume.scene.io import apply_overrides
from eyelume.scene.model import Scene

__all__ = [
    "POPULATION",
    "PlacementScore",
    "evaluate_population",
    "evaluate_tracking",
    "render_frame",
    "score_placement",
    "sweep_tracking",
]

GAZE_H = (-20.0, 0.0, 20.0)
GAZE_V = (-10.0, 0.0, 10.0)


def render_frame(scene: Scene, h: float, v: float, samples: int, seed: int) -> Frame:
    """Render the eye at gaze (``h``, ``v``) degrees (fast estimator, ``samples`` per pixel),
    read it out with the sensor model and analyse the picture against the truth."""
    sc = apply_overrides(scene, {"eye.gaze_horizontal_deg": h, "eye.gaze_vertical_deg": v})
    cs = compile_scene(sc)
    result = render(cs, RenderOptions(estimator="fast", samples_per_pixel=samples, seed=seed))
    digital = digitize(result.eye_image_at_scene_wavelength, sc.sensor, sc.wavelength_nm, seed)
    azimuths = led_picture_azimuths(cs)
    frame = analyse_frame(
        (h, v),
        digital.counts,
        eye_truth(cs),
        azimuths,
        render_s=result.wall_time_s,
        led_pattern_px=led_picture_pattern(cs),
    )
    frame.saturated_share = digital.saturated_pixels / max(digital.counts.size, 1)
    if result.ambient is not None:  # ambient.sun: the LEDs' signal against the sunlight's
        rated = signal_to_ambient(
            result.led_image_at_scene_wavelength, result.ambient.eye_image, result.regions
        )
        frame.ambient = ambient_ratios(rated)
    return frame


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
    only the geometric model (which needs no calibration) estimates gaze.

    ``progress(message)`` once per frame, calibration frames first (:func:`frame_count`
    frames; a progress bar counts them). Ctrl-C or SIGTERM stops it after the frames finished:
    :class:`~eyelume.estimators.interrupt.PartialRun` whose ``done`` is the report over the
    test gazes finished (None when none had: the calibration alone estimates nothing)."""
    grid = [(h, v) for v in CALIBRATION_V for h in CALIBRATION_H] if calibrate else []
    tests = [(h, v) for v in test_v for h in test_h]
    calib: list = []
    frames: list = []
    try:
        for h, v in grid:
            cal = calibration_scene or scene
            calib.append(run_unit(render_frame, cal, h, v, samples_per_pixel, seed))
            if progress:
                progress(f"calibration gaze ({h:+.0f}°, {v:+.0f}°)")
        for h, v in tests:
            frames.append(run_unit(render_frame, scene, h, v, samples_per_pixel, seed))
            if progress:
                f = frames[-1]
                progress(
                    f"gaze ({h:+.0f}°, {v:+.0f}°): "
                    + ("ok" if f.detection.ok else "; ".join(f.detection.failures))
                )
    except KeyboardInterrupt:
        done = None
        if frames:
            done = analyse_frames(scene, compile_scene(scene).led.points, frames, calib)
        raise PartialRun(done, len(frames), len(tests), "test gazes") from None
    leds = compile_scene(scene).led.points
    return analyse_frames(scene, leds, frames, calib)


def frame_count(test_h=TEST_H, test_v=TEST_V, calibrate: bool = True) -> int:
    """Frames :func:`evaluate_tracking` renders: the calibration grid's and the test grid's."""
    calib = len(CALIBRATION_H) * len(CALIBRATION_V) if calibrate else 0
    return calib + len(test_h) * len(test_v)


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
    whether the user calibrates in that state — False for a slip after calibration).

    ``progress(message)`` once per frame of every member, "name: …" (a progress bar counts
    them; each member's summary is in its report). Ctrl-C or SIGTERM stops it after the
    members finished: :class:`~eyelume.estimators.interrupt.PartialRun` with their reports
    (the member in flight is dropped)."""
    out: dict[str, TrackingReport] = {}
    for name, overrides, recalibrate in population:
        member = apply_overrides(scene, overrides) if overrides else scene
        try:
            out[name] = evaluate_tracking(
                member,
                test_h,
                test_v,
                samples_per_pixel,
                seed,
                calibration_scene=None if recalibrate else scene,
                progress=None if progress is None else _prefixed(progress, name),
            )
        except KeyboardInterrupt:
            raise PartialRun(out, len(out), len(population), "population members") from None
    return out


def member_line(name: str, report: TrackingReport) -> str:
    """One line of a population member's result: detection, gaze errors and the reason for
    lost frames."""
    s = report.summary
    why = failure_reason(s)
    return (
        f"{name}: detection {s['detection_rate']:.0%}, geometric gaze "
        f"{mean_deg(s['gaze_geometric'])} mean, PCCR {mean_deg(s['gaze_pccr'])}"
        + (f" — {why}" if why else "")
    )


def _prefixed(progress: Callable[[str], None], name: str) -> Callable[[str], None]:
    return lambda message: progress(f"{name}: {message}")


@dataclass
class PlacementScore:
    """A placement's tracking quality."""

    label: str
    height_mm: float
    distance_mm: float
    pitch_deg: float
    score_deg: float
    detection_rate: float
    geometric_mean_deg: float


def score_placement(
    scene: Scene, y: float, z: float, th: float, samples: int, seed: int, label: str = ""
) -> PlacementScore:
    """Tracking score of the LEDs at (Y, Z, θ); an impossible placement scores +inf."""
    try:
        placed = with_placement(scene, y, z, th)
        rep = run_unit(evaluate_tracking, placed, GAZE_H, GAZE_V, samples, seed, calibrate=False)
    except SceneError:
        return PlacementScore(label, y, z, th, float("inf"), 0.0, float("nan"))
    g = rep.summary["gaze_geometric"]
    return PlacementScore(
        label,
        y,
        z,
        th,
        tracking_score(rep),
        rep.summary["detection_rate"],
        g.get("mean_deg", float("nan")),
    )


def sweep_tracking(
    scene: Scene,
    delta_optimal: tuple[float, float, float],
    heights: Sequence[float] = (20.0, 30.0, 40.0),
    distances: Sequence[float] = (50.0, 60.0, 70.0),
    pitches: Sequence[float] = (0.0, 15.0, 30.0),
    samples: int = 8,
    seed: int = 0,
    progress: Callable[[str], None] | None = None,
) -> tuple[list[PlacementScore], PlacementScore, PlacementScore, PlacementScore]:
    """The grid's scores, its best, the δ-optimal placement's and the paper's.

    ``progress(message)`` once per placement: the grid's, then the δ-optimal and the paper's
    (a progress bar counts them). Ctrl-C or SIGTERM stops it after the placements finished:
    :class:`~eyelume.estimators.interrupt.PartialRun` whose ``done`` is (grid rows, δ-optimal
    row or None, paper row or None)."""
    grid = [(y, z, th) for y in heights for z in distances for th in pitches]
    total = len(grid) + 2

    def say(r: PlacementScore) -> None:
        if progress:
            progress(
                f"{r.label} Y {r.height_mm:g} Z {r.distance_mm:g} θ {r.pitch_deg:g}: score "
                f"{r.score_deg:.2f}° (detection {r.detection_rate:.0%})"
            )

    rows: list[PlacementScore] = []
    dopt = paper = None
    pc = PAPER_CHOICE
    try:
        for y, z, th in grid:
            rows.append(run_unit(score_placement, scene, y, z, th, samples, seed, "grid"))
            say(rows[-1])
        dopt = run_unit(
            score_placement, scene, *delta_optimal, samples, seed, "δ-optimal (generator)"
        )
        say(dopt)
        paper = run_unit(score_placement, scene, pc["height_mm"], pc["distance_mm"],
                         pc["pitch_deg"], samples, seed, "paper")  # fmt: skip
        say(paper)
    except KeyboardInterrupt:
        count = len(rows) + (dopt is not None)
        raise PartialRun((rows, dopt, paper), count, total, "placements") from None
    best = min(rows, key=lambda r: r.score_deg)
    return rows, best, dopt, paper
