"""benchmarks/design_850_940.py's table (issue 15 item 4) from its definitions: the scenes at
each wavelength, and the summary of people's results (detection mean, share tracked, gaze
error p95 over the tracked people's test frames, glint signal to ambient per person's worst
frame, the safety margins)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import design_850_940 as D  # noqa: E402


@pytest.mark.parametrize("wavelength", D.WAVELENGTHS)
def test_the_scene_follows_the_wavelength(wavelength):
    from eyelume.analysis.safety import burn_hazard_weight, eye_safety

    sc = D.scene_at("vr-offaxis", wavelength)
    assert sc.wavelength_nm == wavelength
    assert sc.leds.wavelengths_nm(sc.wavelength_nm) == [wavelength] * sc.leds.count
    assert sc.sensor.quantum_efficiency == "nir-global-shutter"
    lo, hi = D.FILTERS[wavelength]
    assert sc.sensor.filter.cut_on_nm == lo and sc.sensor.filter.cut_off_nm == hi
    assert sc.ambient.sun is not None
    safety = eye_safety(sc)
    assert safety["burn_hazard_weight"] == pytest.approx(burn_hazard_weight(wavelength))


def _done(tracked, detection, errors, ratios):
    row = {"tracked": tracked, "detection_rate": detection}
    return {"row": row, "pccr_errors_deg": errors, "glint_signal_to_ambient": ratios,
            "samples_per_pixel": [4, 6], "cpu_s": 10.0}  # fmt: skip


def test_summary_follows_its_definitions():
    done = [
        _done(True, 1.0, [0.5, 1.0, 1.5], [30.0, 20.0]),
        _done(True, 1.0, [0.2, 0.4, None], [50.0]),
        _done(False, 0.5, [9.0, None, 3.0], [5.0, 8.0]),
        _done(False, 0.0, [None, None, None], []),
    ]
    safety = {"corneal_margin": 8.3, "retinal_margin": 72.9, "burn_hazard_weight": 0.5,
              "corneal_irradiance_w_m2": 12.0}  # fmt: skip
    t = D.summarise(done, safety)
    assert t["people"] == 4 and t["tracked_people"] == 2
    assert t["detection_rate_mean"] == pytest.approx(0.625)
    assert t["share_tracked"] == pytest.approx(0.5)
    tracked_errors = [0.5, 1.0, 1.5, 0.2, 0.4]  # the untracked people's frames left out
    assert t["gaze_error_p95_tracked_deg"] == pytest.approx(np.percentile(tracked_errors, 95))
    worst = [20.0, 50.0, 5.0]  # each person's weakest glint over their frames; none: left out
    assert t["glint_signal_to_ambient_median"] == pytest.approx(np.median(worst))
    assert t["glint_signal_to_ambient_p5"] == pytest.approx(np.percentile(worst, 5))
    assert t["people_with_ratio"] == 3
    assert t["corneal_margin_summed_leds"] == 8.3 and t["retinal_margin_worst_led"] == 72.9
    assert t["samples_per_pixel_range"] == [4, 6]


def test_kept_frames_are_analysed_again_to_the_same_result(tmp_path):
    """``--keep``/``--redetect``: a person's frames saved with their pictures and truth and
    analysed again by the same code give the same row, PCCR errors and signal to ambient (a
    changed detector can then be scored on the same renders without rendering them again)."""
    import eyelume
    from eyelume.optimize.tracking import evaluate_people
    from eyelume.scene.population import sample_people

    (person,) = sample_people(eyelume.load_scene("paper2005"), 1, 1)
    (res,) = evaluate_people([person], 4, 0, keep_pictures=True)
    first = D.person_result(res, 1.0, 2.0)
    stem = tmp_path / "person000_850nm"
    D.save_frames(stem, res.report, first)
    again = D.redetect_person(stem, person)
    assert again["row"] == first["row"]
    assert again["pccr_errors_deg"] == first["pccr_errors_deg"]
    assert again["glint_signal_to_ambient"] == first["glint_signal_to_ambient"]
    assert (again["cpu_s"], again["samples_per_pixel"]) == (2.0, first["samples_per_pixel"])
