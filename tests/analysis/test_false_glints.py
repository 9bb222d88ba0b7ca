"""False glints (issue 14): a detected glint matched to an LED that is an element's ghost, not
the corneal glint (:func:`eyelume.analysis.tracking.evaluate.false_glints`), on constructed
detections and on a drawn picture whose LED 2 glint is replaced by a ghost beside it."""

from __future__ import annotations

import math

import numpy as np

from eyelume.analysis.tracking.detect import Glint
from eyelume.analysis.tracking.evaluate import (
    FALSE_GLINT_PX,
    TrackingReport,
    analyse_frame,
    error_map_rows,
    false_glints,
    summarise,
)
from tests.analysis.test_detect import AXES, CENTRE, LEDS, EyePicture, draw_eye, glint_positions


def _truth(glints, ghosts, visible=(True, True, True, True)):
    """A truth dict as eye_truth writes it: the pupil's edge (the drawn ellipse, unrotated:
    only its centre is used), each LED's glint, the ghosts."""
    t = np.linspace(0, 2 * math.pi, 72, endpoint=False)
    edge = [
        [CENTRE[0] + AXES[0] / 2 * math.cos(a), CENTRE[1] + AXES[1] / 2 * math.sin(a)] for a in t
    ]
    return {
        "pupil": {"centre_px": list(CENTRE), "edge_px": edge},
        "glints": [
            {"led": k, "centre_px": list(g), "visible": v}
            for k, (g, v) in enumerate(zip(glints, visible, strict=True))
        ],
        "ghosts": ghosts,
    }


def _ghost(led, at, blur=2.0, visible=True):
    return {"led": led, "centre_px": list(at), "visible": visible, "blur_px": blur}


def test_a_matched_glint_on_a_ghost_is_false_and_the_rest_are_not():
    true = [(100.0, 100.0), (130.0, 70.0), (160.0, 100.0), (130.0, 130.0)]
    found = [
        Glint((100.3, 100.1), 9, 1000, led=0),  # its own glint
        Glint((140.5, 70.2), 9, 1000, led=1),  # 0.55 px from LED 1's ghost, 10.5 from its glint
        Glint((140.0, 130.0), 9, 1000, led=None),  # on a ghost but matched to no LED: not counted
        Glint((160.0, 100.0), 9, 1000, led=2),  # on its glint, which a ghost overlaps
        Glint((130.0, 130.0 + FALSE_GLINT_PX + 0.5), 9, 1000, led=3),  # 3.5 px: not a ghost
    ]
    ghosts = [
        _ghost(1, (140.0, 70.0)),
        _ghost(3, (140.0, 130.0)),
        _ghost(2, (160.5, 100.0)),  # nearer the glint than the ghost: the glint
        _ghost(0, (130.0, 130.0)),
    ]
    assert false_glints(found, _truth(true, ghosts)) == [1]
    # LED 3's spot is 3.5 px from the 4th ghost: outside 3 px, inside its blur disc of 8 px
    # (radius 4), but as near its own glint (3.5 px): a tie is not false
    ghosts[3]["blur_px"] = 8.0
    assert false_glints(found, _truth(true, ghosts)) == [1]
    ghosts[3]["centre_px"] = [130.0, 133.0]  # 0.5 px from the spot: nearer than its glint
    assert false_glints(found, _truth(true, ghosts)) == [1, 4]
    # an LED without a visible glint: any spot on a ghost is false; an invisible ghost is none
    assert false_glints(found, _truth(true, ghosts, (True, False, True, True))) == [1, 4]
    ghosts[3]["visible"] = False
    assert false_glints(found, _truth(true, ghosts)) == [1]
    # no ghosts in the truth (no elements): nothing is false
    assert false_glints(found, {"glints": _truth(true, [])["glints"]}) == []


def test_detected_ghost_in_place_of_a_lost_glint_is_counted_in_the_frame_and_summary():
    """LED 2's corneal glint is lost (off the cornea); a spectacle ghost of LED 2 lies 2 px
    from where its glint would be: the detector matches it to LED 2 (the pattern fits), and
    the evaluation counts one false glint; the same picture with no ghost in the truth, 0."""
    true = glint_positions()
    ghost_at = (true[2][0] + 1.5, true[2][1] - 1.3)
    img = draw_eye(EyePicture(glints=[true[0], true[1], ghost_at, true[3]], seed=3))
    truth = _truth(true, [_ghost(2, ghost_at)], visible=(True, True, False, True))
    f = analyse_frame((0.0, 0.0), img, truth, LEDS)
    assert f.detection.ok, f.detection.failures
    assert [g.led for g in f.detection.glints][:4] == [0, 1, 2, 3]
    assert f.false_glints == 1
    clean = analyse_frame((0.0, 0.0), img, {**truth, "ghosts": []}, LEDS)
    assert clean.false_glints == 0
    report = TrackingReport([f, clean, f], [], mm_per_px=0.05)
    s = summarise(report, pccr_calibrated=False)
    assert s["false_glints"] == {"total": 2, "frames_with": 2, "per_frame_mean": 2 / 3}
    assert [r["false_glints"] for r in error_map_rows(report.frames)] == [1, 0, 1]


def test_the_suns_glint_matched_to_an_led_is_a_false_glint():
    """The sun's corneal glint (``truth["sun_glint"]``) taken for LED 1's glint (3.5 px from
    it, nearer the sun's spot) is a false glint; LED 0's own glint is not; a sun glint not
    visible, or none, counts nothing."""
    true = [(40.0, 30.0), (50.0, 30.0), (60.0, 30.0), (50.0, 40.0)]
    sun = {"centre_px": [52.0, 27.0], "visible": True, "on_cornea": True, "reason": ""}
    truth = _truth(true, []) | {"sun_glint": sun}
    found = [Glint((40.1, 30.0), 4, 255.0, led=0), Glint((52.2, 27.1), 9, 255.0, led=1)]
    assert false_glints(found, truth) == [1]
    assert false_glints(found, truth | {"sun_glint": sun | {"visible": False}}) == []
    assert false_glints(found, _truth(true, [])) == []
