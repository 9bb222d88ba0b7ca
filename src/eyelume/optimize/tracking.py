"""Tracking evaluated by rendering: the eye over a grid of gazes, rendered, read out by the
sensor and analysed (:mod:`eyelume.analysis.tracking.evaluate`); and illumination chosen for
tracking itself.

:func:`evaluate_tracking` renders each gaze of a calibration grid (3 × 3) and a test grid (7 × 5
by default) with the fast estimator, digitises it (:func:`eyelume.detectors.sensor.digitize`),
and hands the pictures with the renderer's truth (:func:`eyelume.analysis.truth.eye_truth`) to
the analysis. :func:`evaluate_population` does it for each member of a fixed, named population
(iris, skin, lids, slip extremes); :func:`evaluate_people` for each person sampled from the
anatomy distributions (:mod:`eyelume.scene.population`), on smaller grids, and
:func:`population_summary` gives the distribution over them (mean, p95, share tracked).

:func:`sweep_tracking` scores LED placements by the gaze error of the whole pipeline (render →
camera → detection → geometric gaze), against the paper's proxies. Each placement is rendered
over a 3 × 3 grid of gazes (±20° horizontal, ±10° vertical) and scored by
:func:`eyelume.analysis.tracking.evaluate.tracking_score` (mean geometric gaze error, a failed
frame counted as 10°). The grid of placements is coarse (Y 20/30/40 mm, Z 50/60/70 mm, θ
0/15/30°: 27 placements), each scored with the same seed; the δ-optimal placement of the
generator and the paper's placement are scored the same way for comparison.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from eyelume.analysis.ambient import signal_to_ambient
from eyelume.analysis.tracking.evaluate import (
    CALIBRATION_H,
    CALIBRATION_V,
    FAILED_FRAME_DEG,
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
from eyelume.analysis.truth import eye_truth, optical_gaze_for
from eyelume.compile import compile_scene
from eyelume.detectors.sensor import digitize
from eyelume.errors import SceneError
from eyelume.estimators.interrupt import PartialRun, run_unit
from eyelume.optimize.delta_study import PAPER_CHOICE, with_placement
from eyelume.optimize.render_budget import MAX_SAMPLES_PER_PIXEL, NO_EYE_PLANE, noise_options
from eyelume.render import RenderOptions, render
from eyelume.scene.io import apply_overrides
from eyelume.scene.model import Scene

__all__ = [
    "POPULATION",
    "TRACKED_DEG",
    "PersonResult",
    "PlacementScore",
    "evaluate_people",
    "evaluate_population",
    "people_frame_count",
    "population_summary",
    "evaluate_tracking",
    "render_frame",
    "reanalyse_frame",
    "reanalyse_report",
    "score_placement",
    "sweep_tracking",
]

GAZE_H = (-20.0, 0.0, 20.0)
GAZE_V = (-10.0, 0.0, 10.0)


def render_frame(  # noqa: PLR0913 - the frame, its budget, and whether to keep its picture
    scene: Scene,
    h: float,
    v: float,
    samples: int,
    seed: int,
    rel_error: float | None = None,
    max_samples: int = MAX_SAMPLES_PER_PIXEL,
    ambient_rel_error: float | None = None,
    keep_picture: bool = False,
) -> Frame:
    """Render the eye at gaze (``h``, ``v``) degrees (fast estimator, ``samples`` per pixel —
    or, with ``rel_error``, until the median skin pixel's relative standard error is at most
    that, capped at ``max_samples`` per pixel; the sunlight's render, with ``ambient.sun``, to
    ``ambient_rel_error``, default ``rel_error``), read it out with the sensor model and
    analyse the picture against the truth. The frame's ``samples_per_pixel`` is what the LEDs'
    render used.

    (``h``, ``v``) is the target the person fixates: the eye turns so that its visual axis has
    these angles (:func:`eyelume.analysis.truth.optical_gaze_for`; the optical axis itself
    when ``eye.kappa_deg`` is 0), and the frame's errors are against it. GeometryError when
    the optical gaze needed lies beyond the eye's ±30°. ``keep_picture``: the frame keeps the
    digital picture and the LEDs' layout (``Frame.picture``) for :func:`reanalyse_frame`."""
    gh, gv = optical_gaze_for(scene, h, v)
    # the eye plane's receiver shrunk to one bin: no frame reads it (NO_EYE_PLANE)
    gaze = {"eye.gaze_horizontal_deg": gh, "eye.gaze_vertical_deg": gv}
    sc = apply_overrides(scene, {**gaze, **NO_EYE_PLANE})
    cs = compile_scene(sc)
    if rel_error is None:
        opts = RenderOptions(estimator="fast", samples_per_pixel=samples, seed=seed)
    else:
        opts = RenderOptions(
            estimator="fast", rel_error=rel_error, max_samples_per_pixel=max_samples, seed=seed,
            ambient_rel_error=ambient_rel_error,
        )  # fmt: skip
    result = render(cs, opts)
    digital = digitize(result.eye_image_at_scene_wavelength, sc.sensor, sc.wavelength_nm, seed)
    azimuths = led_picture_azimuths(cs)
    pattern = led_picture_pattern(cs)
    frame = analyse_frame(
        (h, v),
        digital.counts,
        eye_truth(cs),
        azimuths,
        render_s=result.wall_time_s,
        led_pattern_px=pattern,
    )
    if keep_picture:
        frame.picture = {
            "counts": digital.counts,
            "led_azimuths_deg": list(azimuths),
            "led_pattern_px": pattern,
        }
    frame.saturated_share = digital.saturated_pixels / max(digital.counts.size, 1)
    frame.samples_per_pixel = int(result.samples_per_pixel)
    if result.ambient is not None:  # ambient.sun: the LEDs' signal against the sunlight's
        rated = signal_to_ambient(
            result.led_image_at_scene_wavelength, result.ambient.eye_image, result.regions
        )
        frame.ambient = ambient_ratios(rated)
    return frame


def reanalyse_frame(frame: Frame) -> Frame:
    """Detection run again on a frame kept with its picture (:func:`render_frame`'s
    ``keep_picture``): a new :class:`Frame` from :func:`~eyelume.analysis.tracking.evaluate.
    analyse_frame` on the same digital picture, truth and LED layout, with what the render
    measured (time, samples per pixel, saturated share, signal to ambient, calibration flag)
    carried over — to score a changed detector on the same renders. ValueError when the frame
    kept no picture."""
    if frame.picture is None:
        raise ValueError("the frame kept no picture (render_frame(..., keep_picture=True))")
    pic = frame.picture
    new = analyse_frame(
        frame.gaze,
        pic["counts"],
        frame.truth,
        pic["led_azimuths_deg"],
        render_s=frame.render_s,
        led_pattern_px=pic["led_pattern_px"],
    )
    new.saturated_share = frame.saturated_share
    new.samples_per_pixel = frame.samples_per_pixel
    new.ambient = frame.ambient
    new.calibration = frame.calibration
    new.picture = pic
    return new


def reanalyse_report(scene: Scene, report: TrackingReport) -> TrackingReport:
    """A tracking report whose frames were kept with their pictures (``keep_pictures``), with
    detection and the gaze estimates run again on the same pictures (:func:`reanalyse_frame`,
    then :func:`~eyelume.analysis.tracking.evaluate.analyse_frames` in ``scene``, the scene the
    frames were rendered in: its LEDs for the geometric model). The render budget's summary is
    carried over. ValueError when a frame kept no picture."""
    frames = [reanalyse_frame(f) for f in report.frames]
    calib = [reanalyse_frame(f) for f in report.calibration]
    new = analyse_frames(scene, compile_scene(scene).led.points, frames, calib)
    new.summary["render_budget"] = report.summary.get("render_budget")
    return new


def evaluate_tracking(  # noqa: PLR0913 - grids, budget, calibration: one option each
    scene: Scene,
    test_h: Sequence[float] = TEST_H,
    test_v: Sequence[float] = TEST_V,
    samples_per_pixel: int = 16,
    seed: int = 0,
    progress: Callable[[str], None] | None = None,
    calibration_scene: Scene | None = None,
    calibrate: bool | tuple[Sequence[float], Sequence[float]] = True,
    render_noise: str | float | None = None,
    keep_pictures: bool = False,
) -> TrackingReport:
    """Render, detect and estimate gaze over the calibration and test grids (module doc).

    ``calibration_scene`` (default ``scene``) is the scene the PCCR calibration is rendered in:
    pass the nominal scene to measure a headset slip after calibration. Without ``calibrate``
    only the geometric model (which needs no calibration) estimates gaze, without its kappa
    offset; ``calibrate = (h values, v values)`` calibrates on that grid instead of the 3 × 3
    default (:data:`~eyelume.analysis.tracking.evaluate.CALIBRATION_H`, ``CALIBRATION_V``).

    ``progress(message)`` once per frame, calibration frames first (:func:`frame_count`
    frames; a progress bar counts them). Ctrl-C or SIGTERM stops it after the frames finished:
    :class:`~eyelume.estimators.interrupt.PartialRun` whose ``done`` is the report over the
    test gazes finished (None when none had: the calibration alone estimates nothing).

    ``render_noise`` (default None: ``samples_per_pixel`` for every frame): "sensor" renders
    every frame to the sensor's own shot noise on the skin, a number to that relative error
    (:mod:`eyelume.optimize.render_budget`; at most :data:`~eyelume.optimize.render_budget.
    MAX_SAMPLES_PER_PIXEL` per pixel). The sensor's
    target comes from one pilot per scene (the scene and the calibration scene), not per
    frame: the skin's photo-electrons do not follow the gaze. The report's
    ``summary["render_budget"]`` says what was asked and the samples per pixel used.
    ``keep_pictures``: every frame keeps its picture (:func:`render_frame`)."""
    budgets: dict[int, tuple[float | None, dict]] = {}
    keep = {"keep_picture": True} if keep_pictures else {}

    def frame(sc: Scene, h: float, v: float):
        if render_noise is None:
            return run_unit(render_frame, sc, h, v, samples_per_pixel, seed, **keep)
        if id(sc) not in budgets:
            budgets[id(sc)] = run_unit(noise_options, sc, render_noise, seed)
        target, facts = budgets[id(sc)]
        sun = facts.get("ambient_target_rel_error")
        return run_unit(render_frame, sc, h, v, samples_per_pixel, seed, target,
                        ambient_rel_error=sun, **keep)  # fmt: skip

    cal_h, cal_v = calibrate if isinstance(calibrate, tuple) else (CALIBRATION_H, CALIBRATION_V)
    grid = [(h, v) for v in cal_v for h in cal_h] if calibrate else []
    tests = [(h, v) for v in test_v for h in test_h]
    calib: list = []
    frames: list = []
    try:
        for h, v in grid:
            cal = calibration_scene or scene
            calib.append(frame(cal, h, v))
            if progress:
                progress(f"calibration gaze ({h:+.0f}°, {v:+.0f}°)")
        # a test gaze of the calibration grid, rendered in the calibration's scene with the
        # same seed and budget, is the same picture: its PCCR error is the fit's in-sample residual
        same = calibration_scene is None or calibration_scene == scene
        for h, v in tests:
            frames.append(frame(scene, h, v))
            frames[-1].calibration = same and (h, v) in grid
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
            done.summary["render_budget"] = _budget_summary(
                render_noise, samples_per_pixel, budgets, frames + calib
            )
        raise PartialRun(done, len(frames), len(tests), "test gazes") from None
    leds = compile_scene(scene).led.points
    report = analyse_frames(scene, leds, frames, calib)
    report.summary["render_budget"] = _budget_summary(
        render_noise, samples_per_pixel, budgets, frames + calib
    )
    return report


def _budget_summary(noise, samples: int, budgets: dict, frames: list) -> dict:
    """What the frames' renders were asked (``render_noise`` or ``samples_per_pixel``), each
    scene's budget facts (:func:`eyelume.optimize.render_budget.noise_options`) and the
    samples per pixel the frames used (min, max)."""
    used = [f.samples_per_pixel for f in frames]
    out: dict = {"render_noise": noise}
    if noise is None:
        out["samples_per_pixel_asked"] = samples
    else:
        out["scenes"] = [facts for _, facts in budgets.values()]
    out["samples_per_pixel_used"] = [min(used), max(used)] if used else None
    return out


def frame_count(test_h=TEST_H, test_v=TEST_V, calibrate: bool | tuple = True) -> int:
    """Frames :func:`evaluate_tracking` renders: the calibration grid's (``calibrate`` as
    there) and the test grid's."""
    cal_h, cal_v = calibrate if isinstance(calibrate, tuple) else (CALIBRATION_H, CALIBRATION_V)
    calib = len(cal_h) * len(cal_v) if calibrate else 0
    return calib + len(test_h) * len(test_v)


# --- sampled people (issue 15 part 2) ------------------------------------------------------------

#: A person's grids (degrees of the visual axis). Calibration 3 × 3 at ±15° h, ±10° v, so that
#: a kappa up to the population's bound (13°, population.toml) keeps the optical axis within the
#: eye's ±30°; tests 3 × 2 between the calibration targets (not on them: PCCR is not judged on
#: the points it was fitted to).
PEOPLE_CALIBRATION_H = (-15.0, 0.0, 15.0)
PEOPLE_CALIBRATION_V = (-10.0, 0.0, 10.0)
PEOPLE_TEST_H = (-10.0, 0.0, 10.0)
PEOPLE_TEST_V = (-5.0, 5.0)
#: A person is tracked when every test gaze is detected and every PCCR gaze error (the
#: per-user calibrated estimator) is at most this (degrees). ASSUMPTION: 2°, twice the ~1°
#: accuracy headset trackers specify, to leave room for the coarse per-frame budget.
TRACKED_DEG = 2.0


@dataclass
class PersonResult:
    """One person's tracking: ``index`` in the population, ``values`` (the sampled
    parameters, :class:`eyelume.scene.population.Person`), ``report`` (their frames and
    summary)."""

    index: int
    values: dict
    report: TrackingReport
    not_applied: tuple = ()

    def row(self, tracked_deg: float = TRACKED_DEG) -> dict:
        """The person's results: detection rate, PCCR and geometric gaze errors (mean, max;
        None without an estimate), ``score_deg`` (mean PCCR error over the test gazes, a gaze
        without an estimate counted as :data:`FAILED_FRAME_DEG`), ``tracked``
        (:data:`TRACKED_DEG`)."""
        frames = self.report.frames
        err = [_error(f.pccr, f.gaze) for f in frames]
        geo = [e for e in (_error(f.geometric, f.gaze) for f in frames) if e is not None]
        got = [e for e in err if e is not None]
        detected = all(f.detection.ok for f in frames)
        return {
            "person": self.index,
            "parameters": self.values,
            "not_applied": list(self.not_applied),
            "frames": len(frames),
            "detection_rate": self.report.summary["detection_rate"],
            "pccr_mean_deg": float(np.mean(got)) if got else None,
            "pccr_max_deg": float(np.max(got)) if got else None,
            "geometric_mean_deg": float(np.mean(geo)) if geo else None,
            "score_deg": float(np.mean([FAILED_FRAME_DEG if e is None else e for e in err])),
            "render_budget": self.report.summary.get("render_budget"),
            "tracked": bool(
                frames and detected and len(got) == len(frames) and max(got) <= tracked_deg
            ),
        }


def _error(est, gaze) -> float | None:
    return None if est is None else math.hypot(est[0] - gaze[0], est[1] - gaze[1])


def evaluate_people(
    people: Sequence,
    samples_per_pixel: int = 8,
    seed: int = 0,
    progress: Callable[[str], None] | None = None,
    render_noise: str | float | None = None,
    workers: int = 1,
    keep_pictures: bool = False,
) -> list[PersonResult]:
    """:func:`evaluate_tracking` for each sampled person (:func:`eyelume.scene.population.
    sample_people`, built with scenes) on the person grids (:data:`PEOPLE_CALIBRATION_H` …):
    each calibrates in their own eye, every frame with render seed ``seed``. A person's result
    depends on their scene and ``seed`` alone, so a chunk of people (a worker's) gives the same
    rows as the whole.

    ``render_noise`` as in :func:`evaluate_tracking` ("sensor": one pilot per person, in their
    own scene; None: ``samples_per_pixel`` for every frame).

    ``workers`` > 1 evaluates the people on that many processes (the study's executor,
    :func:`eyelume.optimize.runner.run_tasks`; a person is one task): the same rows, in the
    people's order, as in one process; ``progress`` then tells the frames of each person as
    the person finishes.

    ``progress(message)`` once per frame, "person i: …" (:func:`people_frame_count` frames).
    Ctrl-C or SIGTERM stops it after the people finished:
    :class:`~eyelume.estimators.interrupt.PartialRun` with their results. ``keep_pictures``:
    every frame keeps its picture (:func:`render_frame`)."""
    if workers > 1 and len(people) > 1:
        return _people_on_workers(
            people, samples_per_pixel, seed, progress, render_noise, workers, keep_pictures
        )
    out: list[PersonResult] = []
    for person in people:
        say = None if progress is None else _prefixed(progress, f"person {person.index}")
        try:
            rep = evaluate_tracking(
                person.scene, PEOPLE_TEST_H, PEOPLE_TEST_V, samples_per_pixel, seed,
                progress=say, calibrate=(PEOPLE_CALIBRATION_H, PEOPLE_CALIBRATION_V),
                render_noise=render_noise, keep_pictures=keep_pictures,
            )  # fmt: skip
        except KeyboardInterrupt:
            raise PartialRun(out, len(out), len(people), "people") from None
        out.append(PersonResult(person.index, person.values, rep, person.not_applied))
    return out


def _person_task(
    person, samples_per_pixel: int, seed: int, render_noise, keep_pictures: bool = False
) -> PersonResult:
    """One person's evaluation on a worker (module level: pickled by name)."""
    return evaluate_people(
        [person], samples_per_pixel, seed, render_noise=render_noise, keep_pictures=keep_pictures
    )[0]


def _people_on_workers(  # noqa: PLR0913 - evaluate_people's arguments
    people, samples_per_pixel, seed, progress, render_noise, workers, keep_pictures=False
):
    """:func:`evaluate_people` with each person a task of :func:`~eyelume.optimize.runner.
    run_tasks` on ``workers`` processes; Ctrl-C or SIGTERM stops the workers:
    :class:`PartialRun` with the people finished, in their order."""
    from eyelume.optimize.runner import run_tasks

    done: dict[int, PersonResult] = {}
    per = people_frame_count()

    def commit(k: int, result: PersonResult) -> None:
        done[k] = result
        if progress:
            for _ in range(per):
                progress(f"person {result.index}: done")

    tasks = (
        (k, (p, samples_per_pixel, seed, render_noise, keep_pictures)) for k, p in enumerate(people)
    )
    try:
        run_tasks(_person_task, tasks, commit, workers=workers)
    except KeyboardInterrupt:
        finished = [done[k] for k in sorted(done)]
        raise PartialRun(finished, len(finished), len(people), "people") from None
    return [done[k] for k in range(len(people))]


def people_frame_count() -> int:
    """Frames :func:`evaluate_people` renders per person."""
    return frame_count(PEOPLE_TEST_H, PEOPLE_TEST_V, (PEOPLE_CALIBRATION_H, PEOPLE_CALIBRATION_V))


def population_summary(rows: Sequence[dict], tracked_deg: float = TRACKED_DEG) -> dict:
    """The distribution over people of :meth:`PersonResult.row` rows: how many, the share
    tracked, the score (mean and 95th percentile over people, numpy's linear interpolation),
    the PCCR mean error (mean and p95 over the people who have one) and the detection rate
    (mean, and the 5th percentile: the worst people's)."""
    n = len(rows)
    score = np.array([r["score_deg"] for r in rows], dtype=float)
    pccr = np.array([r["pccr_mean_deg"] for r in rows if r["pccr_mean_deg"] is not None])
    det = np.array([r["detection_rate"] for r in rows], dtype=float)

    def stat(a: np.ndarray, q: float) -> float | None:
        return float(np.percentile(a, q)) if a.size else None

    return {
        "people": n,
        "tracked_deg": tracked_deg,
        "tracked_definition": (
            "every test gaze detected and every PCCR gaze error (the visual axis against the "
            f"fixated target) at most {tracked_deg:g} deg"
        ),
        "share_tracked": float(np.mean([r["tracked"] for r in rows])) if n else None,
        "score_deg": {"mean": float(score.mean()) if n else None, "p95": stat(score, 95)},
        "pccr_mean_deg": {
            "people": int(pccr.size),
            "mean": float(pccr.mean()) if pccr.size else None,
            "p95": stat(pccr, 95),
        },
        "detection_rate": {"mean": float(det.mean()) if n else None, "p5": stat(det, 5)},
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
    render_noise: str | float | None = None,
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
                render_noise=render_noise,
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
