"""Tracking evaluated on rendered frames (optimize/tracking.py renders, analysis/tracking/
evaluate.py analyses): detection against the renderer's truth, gaze estimates, a
hidden pupil reported as a failure, and the evaluate-tracking command end to end (small grid)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

import eyelume
from eyelume.cli import app
from eyelume.optimize.tracking import evaluate_tracking, render_frame


def test_detection_recovers_the_true_pupil_and_glints_in_primary_gaze():
    """At 87 × 65 (0.46 mm of eye per pixel) the detected pupil centre lies within 0.5 px of the
    centre of the true apparent pupil outline, and each glint within 0.5 px of its truth."""
    f = render_frame(eyelume.load_scene("paper2005"), 0.0, 0.0, 16, 1)
    assert f.detection.ok, f.detection.failures
    assert f.pupil_error_px < 0.5
    truth = {g["led"]: g["centre_px"] for g in f.truth["glints"]}
    found = {g.led: g.centre_px for g in f.detection.glints if g.led is not None}
    assert set(found) == {0, 1, 2, 3}
    for k, xy in found.items():
        assert np.hypot(xy[0] - truth[k][0], xy[1] - truth[k][1]) < 0.5


def test_a_pupil_hidden_by_the_eyelid_is_a_failure_not_a_gaze():
    """Lower the upper lid's margin to 2 mm below the corneal vertex: the pupil is mostly
    covered; the frame must be reported as failed."""
    scene = eyelume.load_scene("paper2005", {"face.tissues.0.clip_z_mm": [-2.0, 14.0]})
    f = render_frame(scene, 0.0, 0.0, 16, 1)
    assert not f.detection.ok
    assert f.pg_vector is None
    assert any("pupil" in r for r in f.detection.failures)


@pytest.mark.slow
def test_evaluate_tracking_small_grid():
    scene = eyelume.load_scene("paper2005")
    rep = evaluate_tracking(scene, test_h=(-20.0, 10.0), test_v=(0.0,), samples_per_pixel=8)
    assert len(rep.frames) == 2 and len(rep.calibration) == 9
    s = rep.summary
    # (−20°, 0°) is a calibration gaze, rendered alike: the same picture the PCCR polynomial
    # was fitted on, flagged and left out of the PCCR statistics (its error is in-sample)
    assert [f.calibration for f in rep.frames] == [True, False]
    assert s["gaze_pccr"]["calibration_frames_excluded"] == 1
    assert s["gaze_pccr"]["frames"] == (rep.frames[1].pccr is not None)
    assert 0 <= s["detection_rate"] <= 1
    for f in rep.frames:
        if f.detection.ok:
            assert f.pccr is not None and f.geometric is not None
            # at 87 × 65 one pixel of pupil–glint vector is ~10° of gaze: a few degrees is
            # what this resolution allows (see the gaze tests)
            assert np.hypot(f.pccr[0] - f.gaze[0], f.pccr[1] - f.gaze[1]) < 5
            assert np.hypot(f.geometric[0] - f.gaze[0], f.geometric[1] - f.gaze[1]) < 8


@pytest.mark.slow
def test_the_geometric_kappa_frame_is_left_out_of_the_geometric_statistics(tmp_path):
    """The test frame at (0°, 0°) is the geometric model's one-point kappa calibration frame
    (the same picture): its geometric error is 0 by construction, so it is flagged
    ``geometric_calibration`` for the error maps and left out of ``gaze_geometric``, which
    says so; (10°, 0°) is a measurement."""
    from eyelume.analysis.tracking.evaluate import error_map_rows

    scene = eyelume.load_scene("paper2005")
    rep = evaluate_tracking(scene, test_h=(0.0, 10.0), test_v=(0.0,), samples_per_pixel=8)
    centre, other = rep.frames
    assert centre.geometric is not None
    assert np.hypot(*centre.geometric) < 1e-9  # target − estimate added back: exactly on target
    g = rep.summary["gaze_geometric"]
    assert g["calibration_frames_excluded"] == 1
    assert g["frames"] == (other.geometric is not None)
    if other.geometric is not None:
        err = np.hypot(other.geometric[0] - 10.0, other.geometric[1])
        assert g["mean_deg"] == pytest.approx(err)
    # frames.csv flags it, so its rows reproduce the summary (a fresh user could not)
    import csv

    from eyelume.report.tracking_outputs import write_tracking_outputs

    write_tracking_outputs(rep, {}, tmp_path)
    with open(tmp_path / "frames.csv", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert [r["geometric_calibration_frame"] for r in rows] == ["1", "0"]
    # why the geometric model refused a frame detected ok: empty where it answered
    assert [r["geometric_refused"] == "" for r in rows] == [
        f.geometric is not None or not f.detection.ok for f in rep.frames
    ]
    assert [r["geometric_calibration"] for r in error_map_rows(rep.frames)] == [True, False]


def test_track_command_on_a_rendered_image(tmp_path):
    scene = eyelume.load_scene("paper2005")
    from eyelume.detectors.sensor import digitize

    r = eyelume.render(scene, eyelume.RenderOptions(seed=2))
    path = tmp_path / "frame.npy"
    np.save(path, digitize(r.eye_image, scene.sensor, scene.wavelength_nm, seed=2).counts)
    res = CliRunner().invoke(app, ["track", str(path), "--leds", "0,90,180,270"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    assert data["ok"] and len([g for g in data["glints"] if g["led"] is not None]) == 4
    bad = CliRunner().invoke(app, ["track", str(tmp_path / "missing.png")])
    assert bad.exit_code == 2 and "missing.png" in bad.stderr


@pytest.mark.slow
def test_population_slip_after_calibration_and_the_tracking_score():
    """A slip after calibration moves the pupil–glint vector little (both move with the eye)
    but the geometric model needs no calibration; the score charges failed frames 10°."""
    from eyelume.analysis.tracking.evaluate import FAILED_FRAME_DEG, tracking_score
    from eyelume.optimize.tracking import evaluate_population

    scene = eyelume.load_scene("paper2005")
    members = evaluate_population(
        scene,
        population=(("nominal", {}, True), ("slip", {"head_offset_mm": [2.0, 0.0, 0.0]}, False)),
        test_h=(0.0,),
        test_v=(0.0,),
        samples_per_pixel=8,
    )
    assert set(members) == {"nominal", "slip"}
    slip = members["slip"].frames[0]
    # the slipped eye's truth moved by ~2 mm × 1.144 / 0.529 mm ≈ 4.3 px
    nominal = members["nominal"].frames[0]
    dx = slip.truth["pupil"]["centre_px"][0] - nominal.truth["pupil"]["centre_px"][0]
    assert 4.0 < dx < 4.7
    for rep in members.values():
        s = tracking_score(rep)
        assert 0 <= s <= FAILED_FRAME_DEG


def test_score_placement_of_an_impossible_placement_is_infinite():
    from eyelume.optimize.tracking import score_placement

    # Z = 2 mm: the LED bodies (5 mm) cross the eye plane
    r = score_placement(eyelume.load_scene("paper2005"), 30.0, 2.0, 10.0, 8, 0)
    assert r.score_deg == float("inf")


def test_a_kept_frame_is_analysed_again_to_the_same_answer():
    """``render_frame(..., keep_picture=True)`` keeps the digital picture and the LEDs' layout;
    :func:`reanalyse_frame` runs detection on them again: with the same detector, the same
    answer (pupil, glints, errors) and the render's measurements carried over. A frame kept
    without its picture cannot be analysed again."""
    import dataclasses

    from eyelume.optimize.tracking import reanalyse_frame

    sc = eyelume.load_scene("paper2005")
    f = render_frame(sc, 0.0, 0.0, 16, 1, keep_picture=True)
    assert f.detection.ok, f.detection.failures
    assert f.picture["counts"].shape == (sc.sensor.rows, sc.sensor.cols)
    g = reanalyse_frame(f)
    assert g.detection.ok and g.detection.failures == f.detection.failures
    assert g.detection.pupil.centre_px == f.detection.pupil.centre_px
    assert [x.centre_px for x in g.detection.glints] == [x.centre_px for x in f.detection.glints]
    assert g.glints_px == f.glints_px and g.pupil_error_px == f.pupil_error_px
    assert (g.samples_per_pixel, g.saturated_share, g.render_s) == (
        f.samples_per_pixel, f.saturated_share, f.render_s
    )  # fmt: skip
    with pytest.raises(ValueError, match="kept no picture"):
        reanalyse_frame(dataclasses.replace(f, picture=None))
