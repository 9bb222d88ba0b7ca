"""Illumination chosen for tracking itself: LED placements scored by the gaze error of the
whole pipeline (render → camera → detection → geometric gaze), against the paper's proxies.

Each placement is rendered over a 3 × 3 grid of gazes (±20° horizontal, ±10° vertical) and scored
by :func:`eyelume.analysis.tracking.evaluate.tracking_score` (mean geometric gaze error, a failed
frame counted as 10°). The grid of placements is coarse (Y 20/30/40 mm, Z 50/60/70 mm, θ 0/15/30°:
27 placements), each scored with the same seed; the δ-optimal placement of the generator and the
paper's placement are scored the same way for comparison.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from eyelume.analysis.tracking.evaluate import evaluate_tracking, tracking_score
from eyelume.optimize.delta_study import PAPER_CHOICE, with_placement
from eyelume.scene.io import SceneError
from eyelume.scene.model import Scene

__all__ = ["PlacementScore", "score_placement", "sweep_tracking"]

GAZE_H = (-20.0, 0.0, 20.0)
GAZE_V = (-10.0, 0.0, 10.0)


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
        rep = evaluate_tracking(placed, GAZE_H, GAZE_V, samples, seed, calibrate=False)
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
    """The grid's scores, its best, the δ-optimal placement's and the paper's."""
    rows = []
    for y in heights:
        for z in distances:
            for th in pitches:
                rows.append(score_placement(scene, y, z, th, samples, seed, "grid"))
                if progress:
                    r = rows[-1]
                    progress(
                        f"Y {y:g} Z {z:g} θ {th:g}: score {r.score_deg:.2f}° "
                        f"(detection {r.detection_rate:.0%})"
                    )
    best = min(rows, key=lambda r: r.score_deg)
    dopt = score_placement(scene, *delta_optimal, samples, seed, "δ-optimal (generator)")
    pc = PAPER_CHOICE
    paper = score_placement(
        scene, pc["height_mm"], pc["distance_mm"], pc["pitch_deg"], samples, seed, "paper"
    )
    return rows, best, dopt, paper
