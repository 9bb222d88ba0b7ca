"""Issue 13: the tracking evaluation does not let a frame look perfect when a matched glint is
not a whole corneal glint — one cut by the cornea's rim (truth ``at_rim``, :func:`rim_glints`)
or one whose LED has no spot in the truth (:func:`stray_glints`)."""

from __future__ import annotations

from eyelume.analysis.tracking.evaluate import (
    TrackingReport,
    analyse_frame,
    error_map_rows,
    summarise,
)
from tests.analysis.test_detect import LEDS, EyePicture, draw_eye, glint_positions
from tests.analysis.test_false_glints import _truth


def _rim(truth, led, centre, visible=True):
    """``truth`` with LED ``led``'s glint off the cornea but cut by the rim (a partial spot at
    ``centre``), as eye_truth writes it for paper2005's LED 2 at (30°, −20°)."""
    g = truth["glints"][led]
    g.update(
        centre_px=None,
        visible=False,
        on_cornea=False,
        at_rim=True,
        rim={
            "aperture_share": 0.48,
            "centre_px": list(centre),
            "bias_px": 0.98,
            "visible": visible,
        },
    )
    return truth


def test_rim_and_stray_glints_counted_in_frame_and_summary():
    true = glint_positions()
    img = draw_eye(EyePicture(glints=true, seed=3))
    whole = analyse_frame((0.0, 0.0), img, _truth(true, []), LEDS)
    assert whole.detection.ok, whole.detection.failures
    assert (whole.false_glints, whole.rim_glints, whole.stray_glints) == (0, 0, 0)
    # the same picture, LED 2's spot being a rim-cut partial glint in the truth
    rim = analyse_frame((0.0, 0.0), img, _rim(_truth(true, []), 2, true[2]), LEDS)
    assert rim.detection.ok
    assert (rim.false_glints, rim.rim_glints, rim.stray_glints) == (0, 1, 0)
    # ... and LED 2 with no spot at all in the truth (off the cornea, not at the rim)
    truth = _truth(true, [], visible=(True, True, False, True))
    truth["glints"][2]["centre_px"] = None
    stray = analyse_frame((0.0, 0.0), img, truth, LEDS)
    assert (stray.false_glints, stray.rim_glints, stray.stray_glints) == (0, 0, 1)
    # a rim spot the lid hides is no spot: the glint matched there is a stray
    hidden = analyse_frame((0.0, 0.0), img, _rim(_truth(true, []), 2, true[2], visible=False), LEDS)
    assert (hidden.rim_glints, hidden.stray_glints) == (0, 1)
    report = TrackingReport([whole, rim, stray, hidden], [], mm_per_px=0.05)
    s = summarise(report, pccr_calibrated=False)
    assert s["detection_rate"] == 1.0
    assert s["clean_detection_rate"] == 0.25  # only the first frame's glints are all whole
    assert s["rim_glints"] == {"total": 1, "frames_with": 1, "ok_frames_with": 1}
    assert s["stray_glints"] == {"total": 2, "frames_with": 2, "ok_frames_with": 2}
    rows = error_map_rows(report.frames)
    assert [(r["rim_glints"], r["stray_glints"]) for r in rows] == [(0, 0), (1, 0), (0, 1), (0, 1)]
