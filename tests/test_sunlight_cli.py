"""``eyelume render`` with sunlight: the signal-to-ambient line, summary.json and truth.json,
the sunlight's picture beside the LEDs', and no sun by default."""

from __future__ import annotations

import json

import numpy as np
from typer.testing import CliRunner

from eyelume.cli import app

runner = CliRunner()

SUN = [
    "ambient.sun.elevation_deg=30",
    "ambient.sun.azimuth_deg=20",
    "sensor.quantum_efficiency=nir-global-shutter",
    "sensor.filter.kind=long_pass",
    "sensor.filter.cut_on_nm=800",
]


def _render(out, sets):
    args = ["render", "--scene", "paper2005", "--out", str(out), "--samples", "2", "--seed", "3"]
    for s in sets:
        args += ["--set", s]
    return runner.invoke(app, args, prog_name="eyelume")


def test_render_reports_the_signal_to_ambient(tmp_path):
    res = _render(tmp_path / "sun", SUN)
    assert res.exit_code == 0, res.output
    text = " ".join(res.stderr.split())  # the console wraps long lines
    assert "sunlight am1.5-direct (202 W/m² through the filter, 800-1100 nm); glint/ambient" in text
    assert "pupil-iris contrast/ambient" in text
    summary = json.loads((tmp_path / "sun" / "summary.json").read_text())
    amb = summary["ambient"]
    assert amb["sun"]["band_nm"] == [800.0, 1100.0]
    cam = summary["camera"]
    assert cam["filter"] == {"kind": "long_pass", "cut_on_nm": 800.0, "transmittance": 1.0}
    assert cam["filter_transmittance_at_wavelength"] == 1.0
    assert len(amb["glints"]) == 4 and amb["pupil"]["signal_to_ambient"] > 0
    truth = json.loads((tmp_path / "sun" / "truth.json").read_text())
    assert truth["ambient"] == amb
    led = np.load(tmp_path / "sun" / "eye_image.npy")
    ambient = np.load(tmp_path / "sun" / "ambient_image.npy")
    assert ambient.shape == led.shape and ambient.max() > 0
    # the ratios are of the two pictures (QE and filter alike: no wavelength groups here)
    k = amb["ambient_peak_pixel"]
    assert ambient[k[0], k[1]] == amb["ambient_peak_w_mm2"] == ambient.max()


def test_no_sun_no_ambient(tmp_path):
    res = _render(tmp_path / "plain", [])
    assert res.exit_code == 0, res.output
    assert "sunlight" not in res.stderr
    assert "ambient" not in json.loads((tmp_path / "plain" / "summary.json").read_text())
    assert not (tmp_path / "plain" / "ambient_image.npy").exists()
