"""Issue 14 (fresh user): a render that does not resolve a visible ghost of truth.json says so
in one line (RenderResult.ghost_warning, summary.json's ``ghost_warning``, the CLI's stderr)
instead of silently drawing it from one light path (3× its flux) or none."""

from __future__ import annotations

import pytest

import eyelume
from eyelume.compile import compile_scene
from tests.analysis.test_glint_regions_ghosts import _FRESH_ELEMENTS


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_warns_when_the_ghosts_are_not_drawn():
    """The fresh user's scene on a 40 × 30 sensor at 2 samples per pixel: its light paths
    (∝ pixels × samples) draw LED 0's and LED 2's spectacle-back ghosts not at all (~1e-9 W
    about each, the diffuse light, against 7.3e-8 W in the truth): the line names them and
    says what to raise."""
    scene = eyelume.load_scene(
        "paper2005-integrated",
        {"elements": _FRESH_ELEMENTS, "sensor.cols": 40, "sensor.rows": 30},
    )
    result = eyelume.render(
        compile_scene(scene), eyelume.RenderOptions(samples_per_pixel=2, seed=1)
    )
    line = result.ghost_warning
    assert line is not None and "\n" not in line
    assert "LED 0 (spectacle back)" in line and "LED 2 (spectacle back)" in line
    assert "raise --samples" in line
    assert result.summary()["ghost_warning"] == line


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_silent_when_the_ghost_is_resolved():
    """vr-offaxis-glasses at its README budget (forward, 2e6 rays): LED 7's back-surface ghost
    is drawn at 2.4e-8 ± 0.9e-8 W against the truth's 1.4e-8 W — consistent — so no line."""
    cs = compile_scene(eyelume.load_scene("vr-offaxis-glasses"))
    result = eyelume.render(cs, eyelume.RenderOptions(rays=2_000_000, seed=1, estimator="forward"))
    assert result.ghost_warning is None
    assert "ghost_warning" not in result.summary()


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_the_cli_prints_the_line_and_writes_it_to_the_summary(tmp_path):
    """The fresh user's own ``--set 'elements=[...]'`` (tests' copy) on a 40 × 30 sensor: the
    render's stderr has the one ``warning:`` line and summary.json its ``ghost_warning``."""
    import json

    from typer.testing import CliRunner

    from eyelume.cli import app

    # JSON's lists and objects with "key" = value are TOML inline arrays and tables
    elements = "elements=" + json.dumps(_FRESH_ELEMENTS).replace('": ', '" = ')
    out = tmp_path / "o"
    res = CliRunner().invoke(
        app,
        [
            "render",
            "--scene",
            "paper2005-integrated",
            "--set",
            elements,
            "--set",
            "sensor.cols=40",
            "--set",
            "sensor.rows=30",
            "--samples",
            "2",
            "--seed",
            "1",
            "--out",
            str(out),
        ],
    )
    assert res.exit_code == 0, res.output
    lines = [ln for ln in res.output.splitlines() if "visible ghosts in truth.json" in ln]
    assert len(lines) == 1 and lines[0].startswith("warning: "), res.output
    assert "LED 0 (spectacle back)" in lines[0]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["ghost_warning"] in lines[0]
