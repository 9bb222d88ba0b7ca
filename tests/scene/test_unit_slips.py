"""Inputs a fresh user found accepted or crashing (session 6), each now one line naming the
field and the value: an element surface of radius 0 (was a ZeroDivisionError traceback), an
LED emitter wider than its body (a µm-for-mm slip that made the retinal margin 470 instead of
0.35), and ``track --leds`` with two LEDs at one azimuth or an empty item (was ``ok``)."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

import eyelume
from eyelume.cli import app
from eyelume.errors import SceneError

LENS = (
    '[{kind="lens", position_mm=[0,0,20], thickness_mm=3, glass="N-BK7", semi_diameter_mm=10, '
    "front={radius_mm=%s}, back={radius_mm=-50}}]"
)


@pytest.mark.parametrize("radius", ["0", "-0.0"])
def test_an_element_surface_of_radius_zero_is_one_line(radius):
    res = CliRunner().invoke(app, ["info", "--set", f"elements={LENS % radius}"])
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and "elements.0.front.radius_mm" in lines[0], res.output


@pytest.mark.parametrize(
    ("value", "named"),
    [(100.0, "emitter_diameter_mm = 100"), ([1.0, 1.0, 7.0, 1.0], "emitter_diameter_mm[2] = 7")],
)
def test_an_emitter_wider_than_its_led_body_is_refused(value, named):
    with pytest.raises(SceneError) as info:
        eyelume.load_scene("paper2005", {"leds.emitter_diameter_mm": value})
    assert named in str(info.value) and "body_diameter_mm = 5" in str(info.value), info.value


def test_an_emitter_as_wide_as_its_body_is_kept():
    sc = eyelume.load_scene("paper2005", {"leds.emitter_diameter_mm": 5.0})
    assert sc.leds.emitter_diameters_mm() == [5.0] * 4


@pytest.mark.parametrize("leds", ["0,0,0", "0,90,180,270,360", "0,,90"])
def test_track_refuses_two_leds_at_one_azimuth_or_an_empty_item(tmp_path, leds):
    picture = tmp_path / "p.npy"
    np.save(picture, np.full((40, 50), 100.0))
    res = CliRunner().invoke(app, ["track", str(picture), "--leds", leds])
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and "--leds" in lines[0], res.output
