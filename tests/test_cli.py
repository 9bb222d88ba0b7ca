"""The command line: outputs of render and info, and test 9 — bad input gives one line naming
the field and the value, exit code 2, no traceback."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from eyelume.cli import app
from eyelume.scene.io import load_scene, save_scene

runner = CliRunner()


def test_render_writes_every_output(tmp_path):
    out = tmp_path / "out"
    res = runner.invoke(app, ["render", "--rays", "300000", "--seed", "4", "--out", str(out)])
    assert res.exit_code == 0, res.output
    img = np.load(out / "eye_image.npy")
    plane = np.load(out / "eye_plane.npy")
    assert img.shape == (65, 87) and img.dtype == np.float64
    assert plane.shape == (15, 21) and plane.dtype == np.float64
    for name in (
        "eye_image.png",
        "eye_plane.png",
        "eye_image_plot.png",
        "eye_image_digital_plot.png",
        "eye_plane_plot.png",
        "layout.png",
        "layout_xz.png",
    ):
        assert (out / name).stat().st_size > 1000, name
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scene"] == "paper2005" and summary["rays"] == 300000 and summary["seed"] == 4
    p = summary["power_w"]
    total = p["sensor"] + p["escaped"] + sum(p["absorbed"].values())
    assert total == pytest.approx(p["emitted"], rel=1e-9)
    assert summary["wall_time_s"] > 0


@pytest.mark.slow
def test_set_overrides_a_field(tmp_path):
    out = tmp_path / "o"
    two = ["--set", "leds.count=2", "--set", "leds.azimuths_deg=[0.0, 180.0]"]
    res = runner.invoke(
        app, ["render", "--rays", "20000", "--set", "leds.height_mm=40", *two, "--out", str(out)]
    )
    assert res.exit_code == 0, res.output
    emitted_two = json.loads((out / "summary.json").read_text())["power_w"]["emitted"]
    res = runner.invoke(app, ["info", "--json"])
    data = json.loads(res.stdout)["leds"]
    assert data["count"] == 4 and data["ring"]["height_mm"] == 30.0
    # two LEDs of the same intensity emit half the power of four
    assert emitted_two == pytest.approx(data["total_power_w"] / 2, rel=1e-12)


def test_info_json():
    res = runner.invoke(app, ["info", "--json"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    lens = data["imaging_lens"]
    for key in (
        "effective_focal_length_mm",
        "paraxial_image_distance_mm",
        "eye_plane_magnification",
        "working_f_number",
    ):
        assert np.isfinite(lens[key]), key
    assert lens["working_f_number"] > lens["f_number_efl_over_epd"]  # finite conjugate is slower
    assert 55 < data["eye"]["power_d"] < 65
    assert set(data["glasses"]) == {"BSM24", "P-SK60", "F5", "N-SK16"}
    for g in data["glasses"].values():
        assert 1.5 < g["index"] < 1.7
        assert g["nd_from_formula"] == pytest.approx(g["nd_catalog"], abs=2e-5)


def _scene_file(tmp_path, edit):
    path = tmp_path / "scene.toml"
    save_scene(load_scene("paper2005"), path)
    text = path.read_text()
    path.write_text(edit(text))
    return str(path)


BAD = {
    "malformed TOML": (lambda t: t.replace("[leds]", "[leds", 1), ["not valid TOML", "line"]),
    "unknown field": (lambda t: t.replace("[leds]\n", "[leds]\ncolour = 3\n", 1), ["leds.colour"]),
    "negative distance": (
        lambda t: t.replace("distance_mm = 70.0", "distance_mm = -5.0", 1),
        ["leds.distance_mm", "-5"],
    ),
    "zero thickness of image": (
        lambda t: t.replace("thickness_mm = 200.46", "thickness_mm = 0.0"),
        ["thickness_mm"],
    ),
    "pupil wider than iris": (
        lambda t: t.replace("pupil_diameter_mm = 7.0", "pupil_diameter_mm = 12.0"),
        ["pupil_diameter_mm", "12"],
    ),
    "missing glass": (
        lambda t: t.replace('glass = "BSM24"', 'glass = "UNOBTAINIUM"', 1),
        ["scene.toml", "lens.surfaces.0.glass", "UNOBTAINIUM"],  # (the file named: session 34)
    ),
    "NaN": (
        lambda t: t.replace("height_mm = 30.0", "height_mm = nan", 1),
        ["leds.height_mm", "nan"],
    ),
}


@pytest.mark.parametrize("case", list(BAD))
def test_bad_scene_file_one_line_exit_2(tmp_path, case):
    edit, words = BAD[case]
    path = _scene_file(tmp_path, edit)
    res = runner.invoke(
        app, ["render", "--scene", path, "--rays", "1000", "--out", str(tmp_path / "o")]
    )
    assert res.exit_code == 2, res.output
    message = res.stderr.strip()
    assert "Traceback" not in res.output and "Traceback" not in message
    assert len(message.splitlines()) == 1, message
    for w in words:
        assert w.lower() in message.lower(), (w, message)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--set", "leds.height_mm=-3"], ["leds.height_mm", "-3"]),
        (["--set", "leds.distance_mm=0"], ["leds.distance_mm", "0"]),
        (["--set", "eye.pupil_diameter_mm=nan"], ["eye.pupil_diameter_mm", "nan"]),
        (["--set", "leds.nope=1"], ["override 'leds.nope'"]),  # (the override, not the preset)
        (["--set", "leds.height_mm"], ["leds.height_mm", "key=value"]),
        (["--scene", "no_such_scene"], ["no_such_scene"]),
        (["--set", "leds.distance_mm=2"], ["LED", "eye plane"]),
        (["--set", "leds.height_mm=20", "--set", "leds.distance_mm=73"], ["overlaps", "lens"]),
        (["--rays", "0"], ["--rays", "0"]),
    ],
)
def test_bad_overrides_one_line_exit_2(tmp_path, args, words):
    res = runner.invoke(
        app,
        ["render", *args, "--rays", "1000", "--out", str(tmp_path / "o")]
        if "--rays" not in args
        else ["render", *args, "--out", str(tmp_path / "o")],
    )
    assert res.exit_code == 2, res.output
    message = res.stderr.strip()
    assert "Traceback" not in res.output
    assert len(message.splitlines()) == 1, message
    for w in words:
        assert w.lower() in message.lower(), (w, message)


@pytest.mark.parametrize(
    ("csv", "words"),
    [
        ("angle,rel\n0,1\n20,oops\n", ["table_csv", "led.csv", "row 3"]),
        ("0,1\n50,0.5\n30,0.2\n", ["table_csv", "increase"]),
        ("0,1\n20,nan\n", ["table_csv", "nan"]),
    ],
)
def test_bad_led_profile_csv_one_line_exit_2(tmp_path, csv, words):
    path = tmp_path / "led.csv"
    path.write_text(csv, encoding="utf-8")
    sets = ["--set", 'leds.profile.kind="table"', "--set", f'leds.profile.table_csv="{path}"']
    res = runner.invoke(app, ["render", *sets, "--rays", "1000", "--out", str(tmp_path / "o")])
    assert res.exit_code == 2, res.output
    message = res.stderr.strip()
    assert len(message.splitlines()) == 1, message
    for w in words:
        assert w.lower() in message.lower(), (w, message)


def test_render_a_scene_file(tmp_path):
    """A user's TOML file renders like the preset it was saved from (same seed, same arrays)."""
    path = tmp_path / "mine.toml"
    save_scene(load_scene("paper2005"), path)
    a, b = tmp_path / "a", tmp_path / "b"
    common = ["--rays", "50000", "--seed", "9"]
    assert (
        runner.invoke(app, ["render", "--scene", str(path), *common, "--out", str(a)]).exit_code
        == 0
    )
    assert runner.invoke(app, ["render", *common, "--out", str(b)]).exit_code == 0
    assert np.array_equal(np.load(a / "eye_image.npy"), np.load(b / "eye_image.npy"))


def test_render_fast_default_writes_noise_and_digital_image(tmp_path):
    out = tmp_path / "fast"
    res = runner.invoke(
        app, ["render", "--set", "sensor.cols=29", "--set", "sensor.rows=22", "--out", str(out)]
    )
    assert res.exit_code == 0, res.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["estimator"] == "fast" and summary["samples_per_pixel"] == 32
    skin = summary["regions"]["skin"]
    assert 0 < skin["median_pixel_rel_error"] < 0.05 and skin["mean_w_mm2"] > 0
    assert {"pupil", "iris", "sclera", "glint 0"} <= set(summary["regions"])
    std = np.load(out / "eye_image_std.npy")
    img = np.load(out / "eye_image.npy")
    assert std.shape == img.shape == (22, 29) and (std >= 0).all()
    assert np.load(out / "eye_image_digital.npy").dtype == np.uint16


def test_render_rel_error_stops_at_the_target(tmp_path):
    out = tmp_path / "target"
    sets = ["--set", "sensor.cols=29", "--set", "sensor.rows=22"]
    res = runner.invoke(app, ["render", *sets, "--rel-error", "0.003", "--out", str(out)])
    assert res.exit_code == 0, res.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["regions"]["skin"]["median_pixel_rel_error"] <= 0.003
    assert summary["samples_per_pixel"] > 32


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--rel-error", "2"], ["--rel-error", "2"]),
        (["--rel-error", "0.01", "--estimator", "forward"], ["--rel-error", "fast"]),
        (["--samples", "0"], ["--samples", "0"]),
        (["--estimator", "magic"], ["--estimator", "magic"]),
        (["--rays", "100", "--estimator", "fast"], ["--rays", "forward"]),
        (["--set", "run.samples_per_pixel=-1"], ["run.samples_per_pixel", "-1"]),
    ],
)
def test_bad_estimator_options_one_line_exit_2(tmp_path, args, words):
    res = runner.invoke(app, ["render", *args, "--out", str(tmp_path / "o")])
    assert res.exit_code == 2, res.output
    message = res.stderr.strip()
    assert len(message.splitlines()) == 1, message
    for w in words:
        assert w.lower() in message.lower(), (w, message)


def test_render_warns_when_the_leds_exceed_the_exempt_group(tmp_path):
    sets = ["--set", "sensor.cols=16", "--set", "sensor.rows=12"]
    res = runner.invoke(
        app,
        ["render", *sets, "--set", "leds.radiant_intensity_w_sr=1.0", "--samples", "8",
         "--out", str(tmp_path / "o")],
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    assert "IEC 62471" in res.stderr and "corneal" in res.stderr
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert summary["safety"]["corneal_margin"] < 1
