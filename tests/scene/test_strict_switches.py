"""A switch (a ``bool`` scene field) takes only ``true`` or ``false``: pydantic's lax mode read
1, 0, "yes", "off" as switches (a fresh user's finding); each is one line naming the field and
the value, exit code 2."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

import eyelume
from eyelume.cli import app
from eyelume.errors import SceneError


@pytest.mark.parametrize(
    ("path", "value"),
    [
        ("face.enabled", 1),
        ("face.enabled", 0),
        ("face.enabled", "yes"),
        ("camera.body.enabled", "off"),
        ("camera.body.enabled", 1.0),
        ("lens.surfaces.0.stop", 1),
    ],
)
def test_a_switch_refuses_what_is_not_true_or_false(path, value):
    with pytest.raises(SceneError) as info:
        eyelume.load_scene("paper2005", {path: value})
    msg = str(info.value)
    assert path in msg and repr(value) in msg and "must be true or false" in msg, msg


@pytest.mark.parametrize(
    ("path", "value"), [("face.enabled", False), ("camera.body.enabled", None)]
)
def test_a_switch_takes_true_false_and_unset_where_allowed(path, value):
    eyelume.load_scene("paper2005", {path: value})


def test_the_command_line_says_it_in_one_line_with_exit_2():
    res = CliRunner().invoke(app, ["info", "--set", 'face.enabled="yes"'])
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1, lines
    assert "face.enabled" in lines[0] and "'yes'" in lines[0] and "true or false" in lines[0]
