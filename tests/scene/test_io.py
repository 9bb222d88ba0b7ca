"""Scene files: presets, TOML round trip, dotted overrides, and error messages."""

from __future__ import annotations

import pytest

from eyelume.scene.io import SceneError, apply_overrides, load_scene, preset_names, save_scene


def test_paper2005_is_a_preset_with_the_papers_values():
    assert "paper2005" in preset_names()
    s = load_scene("paper2005")
    assert (s.leds.count, s.leds.height_mm, s.leds.distance_mm, s.leds.pitch_deg) == (4, 30, 70, 20)
    assert s.leds.azimuths() == [0.0, 90.0, 180.0, 270.0]
    assert s.eye.cornea_reflectance == 0.024
    assert (s.eye.iris_reflectance, s.eye.sclera_reflectance, s.face.skin_reflectance) == (
        0.05,
        0.09,
        0.12,
    )
    assert [x.radius_mm for x in s.eye.surfaces] == [7.8, 6.5, 11.03, -5.72, -13.4]
    assert [x.paper_glass for x in s.lens.surfaces if x.glass] == [
        "BSM24",
        "SK1",
        "F15",
        "F15",
        "SK16",
        "SK16",
    ]
    assert (s.sensor.cols, s.sensor.rows, s.eye_plane.cols, s.eye_plane.rows) == (87, 65, 21, 15)


def test_toml_round_trip(tmp_path):
    s = load_scene("paper2005")
    path = tmp_path / "s.toml"
    save_scene(s, path)
    assert load_scene(path) == s


def test_overrides_are_typed_and_leave_the_original_alone():
    s = load_scene("paper2005")
    t = apply_overrides(s, {"leds.height_mm": "40", "lens.surfaces.0.conic": "0.5"})
    assert t.leds.height_mm == 40.0 and t.lens.surfaces[0].conic == 0.5
    assert s.leds.height_mm == 30.0 and s.lens.surfaces[0].conic == 0.48


@pytest.mark.parametrize(
    ("overrides", "words"),
    [
        ({"leds.height_mm": "-1"}, ["leds.height_mm", "-1"]),
        ({"lens.surfaces.99.conic": "1"}, ["lens.surfaces.99"]),
        ({"eye.cornea_reflectance": "0.9", "eye.cornea_absorptance": "0.2"}, ["exceeds 1"]),
        ({"lens.surfaces.0.radius_mm": "0"}, ["radius_mm is 0"]),
        ({"face.tissues.0.axis": "[0.0, 0.0, 0.0]"}, ["axis"]),
        ({"run.rays": "0"}, ["run.rays", "0"]),
        ({"leds.azimuths_deg": "[0.0]"}, ["azimuths_deg", "count"]),
        ({"eye.iris_outer_diameter_mm": "13"}, ["iris_outer_diameter_mm", "13"]),
        # absurd magnitudes (they overflowed squares into raw NumPy warnings and NaN variances)
        ({"leds.height_mm": "1e300"}, ["field 'leds.height_mm' = 1e+300", "1000000"]),
        ({"leds.radiant_intensity_w_sr": "1e300"}, ["field 'leds.radiant_intensity_w_sr' ="]),
        ({"eye_plane.height_mm": "1e300"}, ["field 'eye_plane.height_mm' = 1e+300"]),
        ({"head_offset_mm": "[0, 0, 1e300]"}, ["field 'head_offset_mm.2' = 1e+300"]),
    ],
)
def test_errors_name_the_field_and_value(overrides, words):
    with pytest.raises(SceneError) as info:
        load_scene("paper2005", overrides)
    message = str(info.value)
    assert "\n" not in message
    for w in words:
        assert w in message, message
