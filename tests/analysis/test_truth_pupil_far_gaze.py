"""The pupil's truth where the eye turns far from an off-axis camera (issue 13: a pupil "cut by
the cornea's rim" in the README's Open list was the truth's, not the picture's).

On ``vr-offaxis`` at gaze (−30°, 20°) the paraxial guess's chief ray, from which
``_View.image_of`` starts Newton's method, meets the sclera rather than the cornea, so 45 of the
pupil's 72 edge points and its centre had no image: ``truth.json`` listed a 27-point arc
(``visible_fraction`` 0.375, ``centre_px`` None), and the ellipse fitted to that arc, which the
tracking evaluation takes for the true centre, was 0.55 px off the whole outline's — while the
detector, which sees the whole pupil (92 % of its outline backed), was scored against it.
Every edge point's chief ray does pass the cornea there (a 101 × 101 scan of the sensor finds
rays landing all round the pupil's circle); from a neighbour's image Newton converges in 2–3
steps. Checked here: the whole outline and the centre are found, and they form one closed,
evenly spaced curve about the centre (no point converged on another root). On
``glasses-frame`` at (−30°, 0°) and (−20°, 20°) no start converged at all (no edge point, no
centre) while a scan of the picture finds the pupil's chief rays through the cornea all round
it: a coarse scan's nearest ray starts the centre there (``truth._scan_start``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from eyelume.analysis.truth import eye_truth
from eyelume.compile import compile_scene
from eyelume.scene.io import apply_overrides, load_scene


@pytest.mark.parametrize(
    ("preset", "gaze"),
    [
        ("vr-offaxis", (-30.0, 20.0)),
        ("vr-offaxis", (30.0, 20.0)),
        ("vr-offaxis", (-30.0, -20.0)),
        ("glasses-frame", (-30.0, 0.0)),
        ("glasses-frame", (-20.0, 20.0)),
    ],
)
def test_the_whole_pupil_outline_has_an_image(preset, gaze):
    scene = apply_overrides(
        load_scene(preset),
        {"eye.gaze_horizontal_deg": gaze[0], "eye.gaze_vertical_deg": gaze[1]},
    )
    pupil = eye_truth(compile_scene(scene))["pupil"]
    edge = np.array(pupil["edge_px"])
    assert len(edge) == 72
    assert pupil["centre_px"] is not None
    # one closed curve, evenly spaced: the 5° steps of the circle's points each map to a step
    # of the same order in the picture (a point on another root would jump)
    steps = np.hypot(*np.diff(np.vstack([edge, edge[:1]]), axis=0).T)
    assert steps.max() < 3.0 * np.median(steps)
    # the centre inside it: the outline winds once round it
    rel = edge - np.array(pupil["centre_px"])
    turn = np.diff(np.unwrap(np.arctan2(rel[:, 1], rel[:, 0]), period=2 * math.pi))
    winding = (
        turn.sum()
        + math.remainder(
            math.atan2(rel[0, 1], rel[0, 0]) - math.atan2(rel[-1, 1], rel[-1, 0]), 2 * math.pi
        )
    ) / (2 * math.pi)
    assert abs(abs(winding) - 1.0) < 1e-6
