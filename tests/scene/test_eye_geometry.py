"""Impossible eye geometry is refused on loading (issue 12): one line naming the field and
its value, exit 2 from the command line — and real eyes are not."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

import eyelume
import eyelume.analysis.masks
import eyelume.optimize.delta_study
import eyelume.optimize.tracking
import eyelume.render  # noqa: F401  (bound compile_scene at import, before any test patches it)
from eyelume.cli import app
from eyelume.errors import GeometryError

IMPOSSIBLE = [
    # (override, field named, what it breaks)
    ({"eye.surfaces.0.radius_mm": -7.8}, "eye.surfaces.0.radius_mm", "convex"),
    ({"eye.surfaces.0.thickness_mm": 0.0}, "eye.surfaces.0.thickness_mm", "touch"),
    ({"eye.surfaces.2.thickness_mm": 0.1}, "eye.surfaces.2.thickness_mm", "cross"),
    ({"eye.surfaces.1.thickness_mm": 0.5}, "eye.surfaces.1.thickness_mm", "cross"),
    ({"eye.surfaces.1.radius_mm": 20.0}, "eye.surfaces.0.thickness_mm", "cross"),
    ({"eye.surfaces.2.radius_mm": -8.0}, "eye.surfaces.1.thickness_mm", "cross"),
    ({"eye.pupil_diameter_mm": 10.0}, "eye.pupil_diameter_mm", "lens"),
    ({"eye.surfaces.3.thickness_mm": 1.0}, "eye.sclera_radius_mm", "eyeball"),
    ({"eye.sclera_radius_mm": 10.0}, "eye.sclera_radius_mm", "eyeball"),
    ({"eye.surfaces.3.semi_diameter_mm": 6.0, "eye.surfaces.3.conic": 0.0},
     "eye.surfaces.3.semi_diameter_mm", "conicoid"),
]  # fmt: skip


@pytest.mark.parametrize(("overrides", "field", "word"), IMPOSSIBLE)
def test_an_impossible_eye_is_refused_on_loading(overrides, field, word):
    with pytest.raises(GeometryError) as info:
        eyelume.load_scene("paper2005", overrides)
    line = str(info.value)
    assert field in line and word in line and "\n" not in line, line


@pytest.mark.parametrize(
    ("overrides", "field", "word"), [*IMPOSSIBLE[:3], IMPOSSIBLE[6], IMPOSSIBLE[8]]
)
def test_an_impossible_eye_is_one_line_and_exit_2_before_any_render(
    tmp_path, monkeypatch, overrides, field, word
):
    def no_work(*a, **k):
        raise AssertionError("compiled an impossible eye")

    monkeypatch.setattr("eyelume.compile.compile_scene", no_work)
    sets = [a for k, v in overrides.items() for a in ("--set", f"{k}={v}")]
    res = CliRunner().invoke(app, ["render", *sets, "--out", str(tmp_path / "o")])
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error:"), res.output
    text = " ".join(res.output.split())
    value = next(iter(overrides.values()))
    assert field in text and repr(float(value)) in text, text
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    "overrides",
    [
        {},
        {"eye.pupil_diameter_mm": 2.0},  # a bright-light pupil
        {"eye.pupil_diameter_mm": 9.0},  # dilated, inside the lens's 9.5 mm
        {"eye.surfaces.1.radius_mm": 9.0},  # a flatter posterior cornea: thicker at the edge
        {"eye.surfaces.3.thickness_mm": 14.0},  # a shorter (hyperopic) eye
        {"eye.sclera_radius_mm": 12.5},
        {"eye.gaze_horizontal_deg": 30.0, "eye.gaze_vertical_deg": -30.0},
    ],
)
def test_real_eyes_load(overrides):
    eyelume.load_scene("paper2005", overrides)
