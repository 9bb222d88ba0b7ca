"""A study's best run, evaluated anew and stored beside its results for the report.

The report (:mod:`eyelume.report.html`) only reads stored results. What it shows of the best run
beyond its metrics — the eye-plane pattern, the eye image and, when the study measured tracking,
the tracking errors over the gaze grid — is computed here and stored in the study's folder:

- ``best_run.npz``: ``eye_plane`` (rows, cols) W/mm² (closed form,
  :func:`eyelume.estimators.closed_form.eye_plane_irradiance`) and ``eye_image`` (rows, cols)
  W/mm² (fast estimator, 16 samples per pixel, seed 0);
- ``best_run.json``: the run's index, overrides, the merit it is best by and its value, the
  scene, ``seed`` and ``samples_per_pixel`` of the eye image and the tracking frames, and
  ``tracking_rows`` (:func:`eyelume.analysis.tracking.evaluate.error_map_rows` over the 3 × 3
  gaze grid of :mod:`.tracking`) or null, ``eye_plane_mm`` and ``picture_mm`` (width, height
  mm of the eye-plane receiver and of the picture on the sensor: the figures' mm axes).

The best run is the one with the lowest value of the first merit in :data:`MERITS` the study
measured among the runs within the IEC 62471 exempt group (:func:`over_limit`); a run over the
limit is ranked after every compliant one, so it is "best" only when no run is compliant
(``best_run.json`` then says ``"over_limit": true`` and the report says so).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from eyelume.json_files import write_json

__all__ = ["BEST_RUN_FILES", "MERITS", "best_runs", "over_limit", "save_best_run"]

#: The merits a study's runs are ranked by, in order of preference (lower is better).
MERITS = ("eye_image_merit", "eye_plane_merit")
#: The files :func:`save_best_run` writes into the study's folder.
BEST_RUN_FILES = ("best_run.npz", "best_run.json")
#: The best run's eye image: seed and camera samples per pixel; its tracking frames' samples.
_SEED, _SPP, _TRACKING_SPP = 0, 16, 8


def over_limit(row: dict) -> bool:
    """The stored run is over an IEC 62471 exempt-group limit (its ``within_exempt_group``
    metric is false; a run that did not measure it is not counted as over)."""
    return row["metrics"].get("within_exempt_group") is False


def best_runs(rows: list[dict], count: int = 5) -> tuple[str | None, list[dict]]:
    """(merit, the ``count`` best rows by it) of a study's stored rows; (None, []) when the study
    measured no merit of :data:`MERITS`. Runs within the eye-safety limit come first (by merit),
    then the runs over it (:func:`over_limit`, by merit): an over-limit run is never ranked
    above a compliant one, whatever its merit or a tie."""
    measured = {k for r in rows for k, v in r["metrics"].items() if _is_number(v)}
    merit = next((m for m in MERITS if m in measured), None)
    if merit is None:
        return None, []
    scored = [r for r in rows if _is_number(r["metrics"].get(merit))]
    return merit, sorted(scored, key=lambda r: (over_limit(r), r["metrics"][merit]))[:count]


def _is_number(v) -> bool:
    """A finite number (a NaN merit must never rank first: it compares false with everything)."""
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def _stored_rows(folder: Path) -> list[dict]:
    """The committed runs, read read-only (a study may still be writing)."""
    from eyelume.optimize.store import read_rows

    return read_rows(folder)[0]


def save_best_run(folder: str | Path, scene: str) -> Path | None:
    """Evaluate the best run of the study in ``folder`` on its base scene ``scene`` (a preset
    name or a TOML file) and store ``best_run.npz`` and ``best_run.json`` there (module doc).
    Returns the JSON's path, or None when the study measured no merit to rank by.

    Raises StoreError when the folder holds no study, SceneError for a bad scene."""
    import eyelume
    from eyelume.analysis.tracking.evaluate import error_map_rows
    from eyelume.estimators.closed_form import eye_plane_irradiance
    from eyelume.optimize.tracking import GAZE_H, GAZE_V, evaluate_tracking

    folder = Path(folder)
    rows = _stored_rows(folder)
    merit, best = best_runs(rows, 1)
    if not best:
        return None
    run = best[0]
    sc = eyelume.load_scene(scene, run["overrides"])
    pattern = eye_plane_irradiance(sc)
    image = eyelume.render(sc, eyelume.RenderOptions(samples_per_pixel=_SPP, seed=_SEED)).eye_image
    tracking = None
    if any("tracking_score_deg" in r["metrics"] for r in rows):
        rep = evaluate_tracking(sc, GAZE_H, GAZE_V, _TRACKING_SPP, _SEED, calibrate=False)
        tracking = error_map_rows(rep.frames)
    np.savez(folder / BEST_RUN_FILES[0], eye_plane=pattern, eye_image=image)
    value = run["metrics"][merit]
    meta = {
        "index": run["index"],
        "overrides": run["overrides"],
        "merit": merit,
        "value": value if math.isfinite(value) else None,
        "over_limit": over_limit(run),  # true only when no run of the study is within the limit
        "scene": str(scene),
        "scene_name": sc.name,
        "seed": _SEED,
        "samples_per_pixel": _SPP,
        "tracking_samples_per_pixel": _TRACKING_SPP if tracking is not None else None,
        "tracking_rows": tracking,
        "eye_plane_mm": [sc.eye_plane.width_mm, sc.eye_plane.height_mm],
        "picture_mm": list(sc.sensor.field_mm),
    }
    path = folder / BEST_RUN_FILES[1]
    write_json(path, meta)
    return path
