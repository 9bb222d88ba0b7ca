"""Eye safety figures against a hand calculation for one LED at a known distance."""

from __future__ import annotations

import math

import pytest

import eyelume
from eyelume.analysis.safety import eye_safety, retinal_thermal_limit


def one_led(**over):
    base = {
        "leds.count": 1,
        "leds.azimuths_deg": [0.0],
        "leds.height_mm": 0.0001,
        "leds.distance_mm": 52.5,  # body centre: the apex is 52.5 − 2.5 = 50 mm from the eye
        "leds.pitch_deg": 0.0,
        "leds.radiant_intensity_w_sr": 0.02,
        "leds.emitter_diameter_mm": 1.0,
    }
    return eyelume.load_scene("paper2005", {**base, **over})


def test_one_led_on_axis_at_50_mm():
    """E = I/d² = 0.02 W/sr / (0.05 m)² = 8 W/m²; L = I/(π r²) = 0.02 / (π · 0.0005²)
    = 25 465 W/(m²·sr); α = 1 mm / 50 mm = 0.02 rad, limit 6000/0.02 = 300 000."""
    s = eye_safety(one_led())
    assert s["corneal_irradiance_w_m2"] == pytest.approx(8.0, rel=1e-6)
    assert s["corneal_margin"] == pytest.approx(100.0 / 8.0, rel=1e-6)
    assert s["retinal_radiance_w_m2_sr"] == pytest.approx(0.02 / (math.pi * 0.0005**2), rel=1e-9)
    assert s["angular_subtense_rad"] == pytest.approx(0.02, rel=1e-6)
    assert s["retinal_limit_w_m2_sr"] == pytest.approx(300_000.0, rel=1e-6)
    assert s["within_exempt_group"]


def test_a_strong_close_led_exceeds_the_corneal_limit():
    # 0.5 W/sr at 50 mm: 200 W/m² > 100 W/m²
    s = eye_safety(one_led(**{"leds.radiant_intensity_w_sr": 0.5}))
    assert s["corneal_irradiance_w_m2"] == pytest.approx(200.0, rel=1e-6)
    assert s["corneal_margin"] < 1 and not s["within_exempt_group"]


def test_angular_subtense_is_clamped_as_the_standard_says():
    assert retinal_thermal_limit(0.001) == pytest.approx(6000 / 0.011)
    assert retinal_thermal_limit(1.0) == pytest.approx(6000 / 0.1)


def test_default_scene_margin_and_summary():
    scene = eyelume.load_scene("paper2005")
    s = eye_safety(scene)
    # four 15 mW/sr LEDs ~76 mm away, each ~3° off its axis: ≈ 4 · 0.015 / 0.0762² ≈ 10 W/m²
    assert 9.0 < s["corneal_irradiance_w_m2"] < 11.0
    assert s["within_exempt_group"]
    summary = eyelume.render(scene, samples_per_pixel=8, seed=1).summary()
    assert summary["safety"]["corneal_margin"] == pytest.approx(s["corneal_margin"])
