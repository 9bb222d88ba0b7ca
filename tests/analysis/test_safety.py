"""Eye safety figures against a hand calculation for one LED at a known distance."""

from __future__ import annotations

import math

import pytest

import eyelume
from eyelume.analysis.safety import burn_hazard_weight, eye_safety, retinal_thermal_limit


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
    = 25 464.79 W/(m²·sr), weighted by R(850 nm) = 10^(−150/500) = 0.501187 (IEC 62471 Table
    4.2): L_IR = 12 762.6 W/(m²·sr); α = 1 mm / 50 mm = 0.02 rad, limit 6000/0.02 = 300 000,
    margin 23.506 (11.78 without the weighting)."""
    s = eye_safety(one_led())
    assert s["corneal_irradiance_w_m2"] == pytest.approx(8.0, rel=1e-6)
    assert s["corneal_margin"] == pytest.approx(100.0 / 8.0, rel=1e-6)
    assert s["source_radiance_w_m2_sr"] == pytest.approx(25_464.79, rel=1e-6)
    assert s["burn_hazard_weight"] == pytest.approx(0.501187, rel=1e-6)
    assert s["retinal_radiance_w_m2_sr"] == pytest.approx(12_762.6, rel=1e-5)
    assert s["retinal_margin"] == pytest.approx(23.506, rel=1e-4)
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
    summary = eyelume.render(scene, eyelume.RenderOptions(samples_per_pixel=8, seed=1)).summary()
    assert summary["safety"]["corneal_margin"] == pytest.approx(s["corneal_margin"])


def test_burn_hazard_weight_follows_iec_62471_table_4_2():
    # 10^((700 − λ)/500) from 700 to 1050 nm, then 0.2, 0.2·10^(0.02(1150 − λ)), 0.02
    assert burn_hazard_weight(700.0) == pytest.approx(1.0)
    assert burn_hazard_weight(850.0) == pytest.approx(0.501187, rel=1e-6)
    assert burn_hazard_weight(1000.0) == pytest.approx(10**-0.6, rel=1e-12)
    assert burn_hazard_weight(1050.0) == pytest.approx(10**-0.7, rel=1e-12)  # 0.1995 ≈ 0.2
    assert burn_hazard_weight(1100.0) == 0.2
    assert burn_hazard_weight(1175.0) == pytest.approx(0.2 * 10**-0.5, rel=1e-12)
    assert burn_hazard_weight(1200.0) == pytest.approx(0.02, rel=1e-12)
    assert burn_hazard_weight(1300.0) == 0.02
    assert burn_hazard_weight(1500.0) == 0.0  # no retinal hazard beyond 1400 nm
    assert burn_hazard_weight(550.0) == 10.0  # the table's maximum: an upper bound


def test_weighting_follows_the_scene_wavelength():
    """At 940 nm R = 10^(−240/500) = 0.331131; beyond 1400 nm there is no retinal thermal
    hazard: the margin is infinite (null in JSON) and the LED within the exempt group."""
    s = eye_safety(one_led(wavelength_nm=940.0))
    assert s["retinal_radiance_w_m2_sr"] == pytest.approx(25_464.79 * 0.331131, rel=1e-5)
    far = eye_safety(one_led(wavelength_nm=1550.0))
    assert far["retinal_radiance_w_m2_sr"] == 0.0 and far["retinal_margin"] == math.inf


def test_unequal_leds_sum_each_with_its_own_intensity_and_profile():
    """Two LEDs placed one by one (body radius 2.5 mm):

    * LED 0, body centre (0, 0, 52.5) aimed along −z: apex 50 mm from the vertex, on its axis;
      I₀ = 0.02 W/sr, cos^m (22.5°): E₀ = 0.02 / 0.05² = 8 W/m².
    * LED 1, body centre (30, 0, 40) aimed along −z: apex (30, 0, 37.5), d = √(30² + 37.5²)
      = 48.0234 mm, cos α = 37.5 / d = 0.780869; I₀ = 0.05 W/sr, cos^m with half angle 30°,
      m = ln ½ / ln cos 30° = 4.81884: E₁ = 0.05 · 0.780869^4.81884 / 0.0480234² = 6.58286 W/m².
    * E_IR = 14.58286 W/m², margin 100 / 14.58286 = 6.85737.
    * Retinal, per LED: L = I₀ / (π (0.5 mm)²) · R(850) (0.501187); α = 1 mm / d. LED 0:
      L = 12 762.6, limit 6000 / 0.02 = 300 000, margin 23.506. LED 1: L = 31 906.5, α =
      0.0208232, limit 288 140.6, margin 9.03076 — the worse: LED 1 is reported.
    """
    scene = eyelume.load_scene(
        "paper2005",
        {
            "leds.count": 2,
            "leds.positions_mm": [[0.0, 0.0, 52.5], [30.0, 0.0, 40.0]],
            "leds.directions": [[0.0, 0.0, -1.0], [0.0, 0.0, -1.0]],
            "leds.radiant_intensity_w_sr": [0.02, 0.05],
            "leds.profile": [{"half_intensity_angle_deg": 22.5}, {"half_intensity_angle_deg": 30}],
            "leds.emitter_diameter_mm": 1.0,
        },
    )
    s = eye_safety(scene)
    d1 = math.hypot(30.0, 37.5)
    m1 = math.log(0.5) / math.log(math.cos(math.radians(30)))
    e1 = 0.05 * (37.5 / d1) ** m1 / (d1 * 1e-3) ** 2
    assert e1 == pytest.approx(6.58286, rel=1e-5)  # the figure in the docstring
    assert s["per_led"][0]["corneal_irradiance_w_m2"] == pytest.approx(8.0, rel=1e-9)
    assert s["per_led"][1]["corneal_irradiance_w_m2"] == pytest.approx(e1, rel=1e-9)
    assert s["corneal_irradiance_w_m2"] == pytest.approx(8.0 + e1, rel=1e-9)
    assert s["corneal_margin"] == pytest.approx(6.85737, rel=1e-5)
    assert s["per_led"][0]["retinal_margin"] == pytest.approx(23.506, rel=1e-4)
    assert s["retinal_worst_led"] == 1
    assert s["source_radiance_w_m2_sr"] == pytest.approx(0.05 / (math.pi * 0.0005**2), rel=1e-9)
    assert s["angular_subtense_rad"] == pytest.approx(1.0 / d1, rel=1e-9)
    assert s["retinal_margin"] == pytest.approx(9.03076, rel=1e-5)
