"""Each LED its own radiant intensity, profile, wavelength and body (issue 11, part 2): the scene
syntax (one value for every LED, or a list of one per LED) and every ambiguous input refused in
one line naming the field and the value."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from eyelume.cli import app
from eyelume.errors import SceneError
from eyelume.scene.io import apply_overrides, load_scene, save_scene
from eyelume.scene.model import LedProfile

runner = CliRunner()

TWO_BY_POSITION = {
    "leds.count": 2,
    "leds.positions_mm": [[20.0, 0.0, 60.0], [-20.0, 0.0, 60.0]],
    "leds.aim_at_mm": [0.0, 0.0, 0.0],
}


def test_one_value_is_every_leds_and_a_list_is_one_per_led():
    scene = load_scene("paper2005")
    assert scene.leds.intensities_w_sr() == [0.015] * 4
    assert scene.leds.profiles() == [scene.leds.profile] * 4
    assert scene.leds.wavelengths_nm(scene.wavelength_nm) == [850.0] * 4
    per = apply_overrides(
        scene,
        {
            "leds.radiant_intensity_w_sr": [0.01, 0.02, 0.03, 0.04],
            "leds.profile": [{"half_intensity_angle_deg": h} for h in (10, 20, 30, 40)],
            "leds.wavelength_nm": 850,
        },
    )
    assert per.leds.intensities_w_sr() == [0.01, 0.02, 0.03, 0.04]
    assert [p.half_intensity_angle_deg for p in per.leds.profiles()] == [10, 20, 30, 40]
    assert not per.leds.all_alike and scene.leds.all_alike


def test_a_scene_with_lists_reads_back(tmp_path):
    scene = apply_overrides(
        load_scene("paper2005"),
        {
            **TWO_BY_POSITION,
            "leds.radiant_intensity_w_sr": [0.01, 0.03],
            "leds.profile": [{"half_intensity_angle_deg": 15.0}, {"half_intensity_angle_deg": 30}],
        },
    )
    save_scene(scene, tmp_path / "s.toml")
    import tomllib

    leds = tomllib.loads((tmp_path / "s.toml").read_text())["leds"]
    assert leds["radiant_intensity_w_sr"] == [0.01, 0.03] and len(leds["profile"]) == 2
    assert "height_mm" not in leds and "pitch_deg" not in leds  # no ring: not written
    again = load_scene(tmp_path / "s.toml")
    assert again == scene


def test_profile_tables_in_a_list_are_found_beside_the_scene(tmp_path):
    (tmp_path / "wide.csv").write_text("angle,rel\n0,1\n45,0.5\n90,0\n")
    scene_file = tmp_path / "s.toml"
    save_scene(load_scene("paper2005", {**TWO_BY_POSITION}), scene_file)
    text = scene_file.read_text().replace("[leds.profile]\n", "[[leds.profile]]\n")
    text += '\n[[leds.profile]]\nkind = "table"\ntable_csv = "wide.csv"\n'
    scene_file.write_text(text)
    profiles = load_scene(scene_file).leds.profiles()
    assert profiles[0].kind == "cos_power"
    assert profiles[1] == LedProfile(kind="table", table_csv=str(tmp_path / "wide.csv"))


@pytest.mark.parametrize(
    ("overrides", "words"),
    [
        ({"leds.radiant_intensity_w_sr": [0.01, 0.02]}, "radiant_intensity_w_sr has 2 entries"),
        ({"leds.radiant_intensity_w_sr": [0.01, 0.02, -0.03, 0.04]}, "[2] = -0.03"),
        ({"leds.radiant_intensity_w_sr": [0.01, 0.02, "x", 0.04]}, "[2] = 'x'"),
        ({"leds.radiant_intensity_w_sr": []}, "radiant_intensity_w_sr = []"),
        ({"leds.profile": [{}, {}, {}]}, "profile has 3 entries"),
        ({"leds.profile": [{}, {"half_intensity_angle_deg": 95}, {}, {}]}, "profile[1]"),
        ({"leds.profile": [{}, {}, {"kind": "table"}, {}]}, "needs table_csv"),
        ({"leds.wavelength_nm": -940}, "'leds.wavelength_nm' = -940: must be > 0"),
        ({"leds.wavelength_nm": [850, 850, 0, 850]}, "wavelength_nm[2] = 0: must be > 0"),
        ({"leds.wavelength_nm": [850, 850, 850]}, "wavelength_nm has 3 entries"),
        ({**TWO_BY_POSITION, "leds.height_mm": 40}, "height_mm = 40.0 given beside"),
        ({**TWO_BY_POSITION, "leds.pitch_deg": 10}, "pitch_deg = 10.0 given beside"),
        ({**TWO_BY_POSITION, "leds.ring_axis": [0, 1, 0]}, "ring_axis = (0.0, 1.0, 0.0) given"),
        ({**TWO_BY_POSITION, "leds.azimuths_deg": [0, 180]}, "azimuths_deg = [0.0, 180.0] given"),
    ],
)
def test_ambiguous_per_led_input_is_one_line(overrides, words):
    with pytest.raises(SceneError) as e:
        apply_overrides(load_scene("paper2005"), overrides)
    line = str(e.value)
    assert words in line and "\n" not in line, line


def test_a_ring_field_beside_positions_in_a_file_is_refused_with_exit_2(tmp_path):
    """The fresh-user finding: a ring's height written beside positions_mm was ignored."""
    scene_file = tmp_path / "s.toml"
    save_scene(load_scene("paper2005", TWO_BY_POSITION), scene_file)
    text = scene_file.read_text().replace("[leds]\n", "[leds]\nheight_mm = 25.0\n")
    scene_file.write_text(text)
    res = runner.invoke(app, ["info", "--scene", str(scene_file)])
    assert res.exit_code == 2
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and "height_mm = 25.0 given beside positions_mm" in lines[0], lines


def test_a_wavelength_unlike_the_scenes_is_rendered_as_its_own_group():
    """Once refused (one wavelength traced); now each LED its own wavelength
    (tests/test_wavelength_groups.py renders it)."""
    res = runner.invoke(app, ["info", "--json", "--set", "leds.wavelength_nm=[850, 850, 850, 940]"])
    assert res.exit_code == 0, res.output
    per = json.loads(res.stdout)["leds"]["per_led"]
    assert [e["wavelength_nm"] for e in per] == [850.0, 850.0, 850.0, 940.0]


def test_info_shows_every_leds_own_figures_and_no_ring_for_positions():
    res = runner.invoke(
        app,
        [
            "info",
            "--json",
            "--set",
            "leds.count=2",
            "--set",
            "leds.positions_mm=[[20.0, 0.0, 60.0], [-20.0, 0.0, 60.0]]",
            "--set",
            "leds.aim_at_mm=[0.0, 0.0, 0.0]",
            "--set",
            "leds.radiant_intensity_w_sr=[0.01, 0.03]",
            "--set",
            "leds.profile=[{half_intensity_angle_deg = 15.0}, {half_intensity_angle_deg = 30.0}]",
        ],
    )
    assert res.exit_code == 0, res.output
    leds = json.loads(res.stdout)["leds"]
    assert "ring" not in leds and "height_mm" not in json.dumps(leds)
    a, b = leds["per_led"]
    assert a["position_mm"] == [20.0, 0.0, 60.0] and b["position_mm"] == [-20.0, 0.0, 60.0]
    assert (a["radiant_intensity_w_sr"], b["radiant_intensity_w_sr"]) == (0.01, 0.03)
    assert a["profile"]["half_intensity_angle_deg"] == 15.0
    assert b["profile"]["spread_full_angle_deg"] == 60.0
    assert a["wavelength_nm"] == b["wavelength_nm"] == 850.0
    # Φ = I₀ · 2π/(m + 1) for cosᵐ, each LED its own
    for led in (a, b):
        m = led["profile"]["cos_power_exponent"]
        assert led["power_w"] == pytest.approx(
            led["radiant_intensity_w_sr"] * 6.283185307 / (m + 1)
        )
    assert leds["total_power_w"] == pytest.approx(a["power_w"] + b["power_w"], rel=1e-12)
    ring = json.loads(runner.invoke(app, ["info", "--json"]).stdout)["leds"]
    assert ring["ring"]["height_mm"] == 30.0 and ring["ring"]["pitch_deg"] == 20.0


def test_each_led_its_own_body():
    """bodies of 5 mm and 2 mm: each LED emits from its own body's apex (centre + r·axis),
    each body is a sphere of its own radius, and the overlap test adds the two radii."""
    from eyelume.compile import compile_scene
    from eyelume.kernels import geometry as G
    from eyelume.scene.sources import led_poses

    scene = load_scene("paper2005", {**TWO_BY_POSITION, "leds.body_diameter_mm": [5.0, 2.0]})
    assert scene.leds.body_radii_mm() == [2.5, 1.0]
    cs = compile_scene(scene)
    c, a = led_poses(scene.leds)
    assert np.allclose(cs.led.points, c + a * np.array([[2.5], [1.0]]), atol=1e-8)
    for k, r in enumerate((2.5, 1.0)):
        row = cs.surface_names.index(f"LED {k} body")
        assert cs.sf[row, G.RADIUS] == r
    # centres 4 mm apart: radii 2.5 + 1.0 = 3.5 clear them; 2.5 + 1.6 = 4.1 do not
    near = {"leds.positions_mm": [[20.0, 0.0, 60.0], [20.0, 4.0, 60.0]]}
    compile_scene(apply_overrides(scene, near))
    with pytest.raises(SceneError, match="bodies overlap"):
        compile_scene(apply_overrides(scene, {**near, "leds.body_diameter_mm": [5.0, 3.2]}))
    with pytest.raises(SceneError, match="body_diameter_mm has 3 entries"):
        apply_overrides(scene, {"leds.body_diameter_mm": [5.0, 2.0, 1.0]})
