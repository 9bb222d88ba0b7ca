"""Tracking frames rendered in sunlight carry the signal to ambient; the summary's statistics."""

from __future__ import annotations

import math

from eyelume.analysis.tracking.detect import Detection
from eyelume.analysis.tracking.evaluate import AMBIENT_RATIOS, Frame, ambient_stats
from eyelume.optimize.tracking import render_frame
from eyelume.scene.io import load_scene


def _frame(ratios: dict | None) -> Frame:
    return Frame(gaze=(0.0, 0.0), detection=Detection(True, [], None, []), truth={}, ambient=ratios)


def test_stats_leave_out_unbounded_ratios_and_frames_without_sun():
    frames = [
        _frame({"glint_signal_to_ambient_min": 4.0, "glint_peak_over_ambient_peak": 0.5,
                "pupil_signal_to_ambient": None}),
        _frame({"glint_signal_to_ambient_min": 2.0, "glint_peak_over_ambient_peak": 0.1,
                "pupil_signal_to_ambient": None}),
        _frame({"glint_signal_to_ambient_min": None, "glint_peak_over_ambient_peak": 0.3,
                "pupil_signal_to_ambient": None}),
        _frame(None),
    ]  # fmt: skip
    s = ambient_stats(frames)["signal_to_ambient"]
    assert s["glint_signal_to_ambient_min"] == {"frames": 2, "min": 2.0, "median": 3.0}
    assert s["glint_peak_over_ambient_peak"] == {"frames": 3, "min": 0.1, "median": 0.3}
    assert s["pupil_signal_to_ambient"] == {"frames": 0}
    assert ambient_stats([_frame(None)]) == {}


def test_a_frame_in_sunlight_is_rated():
    scene = load_scene(
        "paper2005",
        {
            "ambient.sun.elevation_deg": 30.0,
            "sensor.quantum_efficiency": "nir-global-shutter",
            "sensor.filter.kind": "long_pass",
            "sensor.filter.cut_on_nm": 800.0,
        },
    )
    frame = render_frame(scene, 0.0, 0.0, samples=2, seed=1)
    assert set(frame.ambient) == set(AMBIENT_RATIOS)
    assert frame.ambient["pupil_signal_to_ambient"] > 0
    assert math.isfinite(frame.ambient["glint_peak_over_ambient_peak"])
    plain = render_frame(load_scene("paper2005"), 0.0, 0.0, samples=2, seed=1)
    assert plain.ambient is None
