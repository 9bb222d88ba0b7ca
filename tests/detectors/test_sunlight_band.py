"""The sensor filter and the sunlight's count (detectors/sensor.py), and their bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest
from typer.testing import CliRunner

from eyelume.cli import app
from eyelume.detectors.sensor import (
    electrons_per_w_mm2,
    filter_transmittance,
    spectral_response_nm,
    sunlight_band,
)
from eyelume.errors import InputFileError, SceneError
from eyelume.scene.io import load_scene
from eyelume.scene.model import Sensor, Sun
from eyelume.scene.solar import solar_spectrum

runner = CliRunner()


def test_band_pass_filter_scales_the_led_count_by_its_transmittance():
    plain = Sensor(quantum_efficiency="nir-global-shutter")
    f = Sensor(
        quantum_efficiency="nir-global-shutter",
        filter={"kind": "band_pass", "cut_on_nm": 820, "cut_off_nm": 880, "transmittance": 0.9},
    )
    assert electrons_per_w_mm2(f, 850.0) == pytest.approx(0.9 * electrons_per_w_mm2(plain, 850.0))
    # an LED spectrum half outside the band: T times the share of QE λ S inside it
    assert spectral_response_nm(f, 880.0, 40.0) < 0.9 * spectral_response_nm(plain, 880.0, 40.0)
    assert filter_transmittance(f, [819.9, 820.0, 880.0, 880.1]).tolist() == [0, 0.9, 0.9, 0]


def test_single_qe_with_a_band_pass_is_the_plain_integral():
    """QE 0.3 everywhere and a 900-980 nm band-pass of T = 0.8: E_eq = 0.8 · 0.3 ∫ E λ dλ /
    (0.3 · 0.8 · λ_s), the integral by the trapezoid rule on the table's 1 nm rows."""
    s = Sensor(
        quantum_efficiency=0.3,
        filter={"kind": "band_pass", "cut_on_nm": 900, "cut_off_nm": 980, "transmittance": 0.8},
    )
    band = sunlight_band(s, Sun(spectrum="am1.5-global", scale=0.5), 940.0)
    lam, e = solar_spectrum("am1.5-global")
    m = (lam >= 900) & (lam <= 980)
    expected = 0.5 * np.trapezoid(e[m] * lam[m], lam[m]) / 940.0 * 1e-6
    assert band.irradiance_w_mm2 == pytest.approx(expected, rel=1e-12)
    assert band.band_nm == (900.0, 980.0)
    assert band.seen_w_m2 == pytest.approx(0.5 * 0.8 * np.trapezoid(e[m], lam[m]), rel=1e-12)
    assert 900 < band.trace_wavelength_nm < 980


def test_filter_table_and_its_bad_rows(tmp_path):
    good = tmp_path / "t.csv"
    good.write_text("wavelength_nm,transmittance\n800,0\n840,0.9\n860,0.9\n900,0\n")
    s = Sensor(
        quantum_efficiency="nir-global-shutter", filter={"kind": "table", "table_csv": str(good)}
    )
    assert filter_transmittance(s, [790.0, 850.0, 880.0]).tolist() == pytest.approx([0, 0.9, 0.45])
    with pytest.raises(SceneError, match="outside the filter table"):
        electrons_per_w_mm2(s, 940.0)  # an LED outside the table: not extrapolated
    bad = tmp_path / "bad.csv"
    bad.write_text("800,0\n860,0.9\n840,0.9\n")
    s = Sensor(
        quantum_efficiency="nir-global-shutter", filter={"kind": "table", "table_csv": str(bad)}
    )
    with pytest.raises(InputFileError, match="must increase strictly"):
        filter_transmittance(s, 850.0)


@pytest.mark.parametrize(
    ("overrides", "says"),
    [
        ({"ambient.sun.elevation_deg": 95}, "ambient.sun.elevation_deg"),
        ({"ambient.sun.spectrum": "am0"}, "ambient.sun.spectrum"),
        ({"ambient.sun.scale": math.nan}, "ambient.sun.scale"),
        (
            {"sensor.filter.kind": "band_pass", "sensor.filter.cut_on_nm": 900,
             "sensor.filter.cut_off_nm": 800},
            "cut_on_nm = 900 must be below cut_off_nm = 800",
        ),
        ({"sensor.filter.kind": "long_pass"}, "needs cut_on_nm"),
    ],
)  # fmt: skip
def test_bad_scene_values_are_one_line(overrides, says):
    with pytest.raises(SceneError) as err:
        load_scene("paper2005", overrides)
    assert says in str(err.value) and "\n" not in str(err.value)


def test_single_qe_without_a_band_is_refused():
    with pytest.raises(SceneError, match="single-number QE"):
        sunlight_band(Sensor(quantum_efficiency=0.3), Sun(), 850.0)


def _cli(tmp_path, *sets):
    args = ["render", "--scene", "paper2005", "--out", str(tmp_path / "o"), "--samples", "1"]
    for s in sets:
        args += ["--set", s]
    return runner.invoke(app, args, prog_name="eyelume")


@pytest.mark.parametrize(
    ("sets", "says"),
    [
        (["ambient.sun.elevation_deg=30"], "single-number QE"),
        (["ambient.sun.azimuth_deg=400"], "ambient.sun.azimuth_deg"),
        (
            ["sensor.filter.kind=band_pass", "sensor.filter.cut_on_nm=900",
             "sensor.filter.cut_off_nm=1000"],
            "the filter blocks the scene's wavelength_nm = 850",
        ),
    ],
)  # fmt: skip
def test_cli_refuses_in_one_line_before_tracing(tmp_path, sets, says):
    res = _cli(tmp_path, *sets)
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and says in lines[0], res.stderr
    assert not (tmp_path / "o" / "summary.json").exists()
