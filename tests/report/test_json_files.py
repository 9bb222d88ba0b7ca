"""Every JSON file eyelume writes is strict JSON: no bare Infinity or NaN (issue 12)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from eyelume.cli import app
from eyelume.json_files import dumps, finite_or_null, write_json


def strict_loads(text: str):
    """json.loads that refuses the non-JSON tokens Python would otherwise accept."""

    def refuse(token):
        raise ValueError(f"non-JSON token {token}")

    return json.loads(text, parse_constant=refuse)


def test_non_finite_numbers_become_null():
    data = {
        "margin": math.inf,
        "low": -math.inf,
        "mean": float("nan"),
        "np": np.float64("inf"),
        "arr": np.array([1.0, np.nan]),
        "nested": [{"x": (2.0, math.inf)}],
        "n": np.int64(7),
    }
    out = strict_loads(dumps(data))
    assert out == {
        "margin": None,
        "low": None,
        "mean": None,
        "np": None,
        "arr": [1.0, None],
        "nested": [{"x": [2.0, None]}],
        "n": 7,
    }
    assert finite_or_null(1.5) == 1.5 and finite_or_null(None) is None


def test_write_json_is_strict(tmp_path):
    p = write_json(tmp_path / "a.json", {"v": math.inf})
    assert "Infinity" not in p.read_text() and strict_loads(p.read_text()) == {"v": None}


@pytest.mark.slow
def test_render_summary_with_an_infinite_margin_is_strict_json(tmp_path):
    """An LED that faces sideways (+x) above the eye sends the corneal vertex nothing (it lies
    behind the LED's front) though its cone still grazes the eyeball (LEDs whose cones miss the
    eye entirely are refused): the corneal margin is infinite, written as null; summary.json
    and truth.json parse with a strict parser."""
    out = tmp_path / "r"
    result = CliRunner().invoke(
        app,
        [
            "render", "--samples", "1", "--seed", "1", "--out", str(out),
            "--set", "sensor.cols=16", "--set", "sensor.rows=12", "--set", "leds.count=1",
            "--set", "leds.positions_mm=[[0.0, 25.0, 40.0]]",
            "--set", "leds.directions=[[1.0, 0.0, 0.0]]",
        ],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    summary = strict_loads((out / "summary.json").read_text())
    assert summary["safety"]["corneal_margin"] is None
    strict_loads((out / "truth.json").read_text())


@pytest.mark.parametrize("args", [["info", "--json"]])
def test_cli_json_listing_is_strict(args):
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0
    strict_loads(result.stdout)
