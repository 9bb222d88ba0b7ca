"""``true``/``false`` where a number is asked is refused, naming the field (pydantic's lax mode
would read ``count = true`` as one LED and ``cols = false`` as no column); a switch still takes
them, and a study may vary a switch over [true, false]."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

import eyelume
from eyelume.cli import app
from eyelume.errors import SceneError
from eyelume.optimize.study import load_study


@pytest.mark.parametrize(
    ("path", "value"),
    [
        ("leds.count", True),
        ("sensor.cols", False),
        ("eye_pose.relief_mm", True),
        ("run.seed", False),
        ("camera.position_mm", [True, 0.0, 60.0]),
    ],
)
def test_a_bool_for_a_number_is_refused_naming_the_field(path, value):
    with pytest.raises(SceneError) as info:
        eyelume.load_scene("paper2005", {path: value})
    assert path in str(info.value) and "true/false" in str(info.value), str(info.value)


def test_a_switch_still_takes_a_bool():
    assert eyelume.load_scene("paper2005", {"camera.body.enabled": True}).camera.body.enabled


def test_the_command_line_says_it_in_one_line_with_exit_2(tmp_path):
    res = CliRunner().invoke(app, ["info", "--set", "leds.count=true"])
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and "leds.count" in lines[0] and "true/false" in lines[0], res.output


def test_a_study_refuses_a_bool_count_and_keeps_bool_values(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "s"\nseed = true\n', encoding="utf-8")
    with pytest.raises(SceneError) as info:
        load_study(bad)
    assert "seed" in str(info.value) and "true/false" in str(info.value), str(info.value)
    good = tmp_path / "good.toml"
    good.write_text(
        'name = "s"\n[[vary]]\npath = "camera.body.enabled"\nvalues = [true, false]\n',
        encoding="utf-8",
    )
    assert load_study(good).vary[0].values == [True, False]
