"""The sensor's QE(λ) curve and the LEDs' spectral width (issue 15, part 3): photo-electrons per
watt ∫ QE(λ) λ/(hc) S(λ) dλ against closed forms and scipy's quad; a single-number QE and no
width give exactly the plain formula; bad QE tables are one line naming file and field, exit 2."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from scipy.constants import c, h
from scipy.integrate import quad
from scipy.stats import norm
from typer.testing import CliRunner

from eyelume.cli import app
from eyelume.detectors.sensor import (
    SPECTRUM_HALF_WIDTH_SIGMA,
    count_weights,
    electrons_per_w_mm2,
    gaussian_spectrum_sigma_nm,
    quantum_efficiency_at,
    quantum_efficiency_curve,
    spectral_response_nm,
)
from eyelume.errors import InputFileError, SceneError
from eyelume.scene.io import load_scene
from eyelume.scene.model import Sensor

runner = CliRunner()


def _table(tmp_path, rows, name="qe.csv"):
    path = tmp_path / name
    path.write_text(
        "# test QE table\nwavelength_nm,quantum_efficiency\n"
        + "".join(f"{a},{b}\n" for a, b in rows),
        encoding="utf-8",
    )
    return path


def _plain(sensor: Sensor, qe: float, lam_nm: float) -> float:
    """p² t QE λ / (h c), written out here."""
    return (
        (sensor.pixel_pitch_um * 1e-3) ** 2
        * sensor.exposure_ms
        * 1e-3
        * qe
        * lam_nm
        * 1e-9
        / (h * c)
    )


def test_one_number_and_no_width_is_todays_formula_exactly():
    s = Sensor(quantum_efficiency=0.3)
    pitch_mm = s.pixel_pitch_um * 1e-3
    today = pitch_mm**2 * s.exposure_ms * 1e-3 * 0.3 / (h * c / (850.0 * 1e-9))
    assert electrons_per_w_mm2(s, 850.0) == today
    assert electrons_per_w_mm2(s, 850.0, 0.0) == today
    assert count_weights(s, [850.0, 940.0], 0.0, 850.0) == [1.0, 940.0 / 850.0]
    assert quantum_efficiency_curve(s) is None and quantum_efficiency_at(s, 400.0) == 0.3


def test_a_table_is_interpolated_at_each_wavelength(tmp_path):
    s = Sensor(quantum_efficiency=str(_table(tmp_path, [(800, 0.4), (900, 0.2), (1000, 0.1)])))
    assert quantum_efficiency_at(s, 850.0) == pytest.approx(0.3, rel=1e-15)
    assert quantum_efficiency_at(s, 940.0) == pytest.approx(0.16, rel=1e-14)
    assert electrons_per_w_mm2(s, 940.0) == pytest.approx(_plain(s, 0.16, 940.0), rel=1e-14)
    w = count_weights(s, [850.0, 940.0], 0.0, 850.0)
    assert w == pytest.approx([1.0, 0.16 * 940 / (0.3 * 850)], rel=1e-14)


@pytest.mark.parametrize("fwhm", [10.0, 35.0, 50.0])
def test_a_flat_qe_gives_the_plain_formula(tmp_path, fwhm):
    """QE constant over the spectrum: ∫ QE λ S dλ = QE λ₀ (S symmetric about λ₀), for a
    single number and for a flat table alike."""
    flat = Sensor(quantum_efficiency=str(_table(tmp_path, [(500, 0.4), (1200, 0.4)])))
    one = Sensor(quantum_efficiency=0.4)
    for s in (flat, one):
        assert spectral_response_nm(s, 870.0, fwhm) == pytest.approx(0.4 * 870.0, rel=1e-13)
        assert electrons_per_w_mm2(s, 870.0, fwhm) == pytest.approx(
            _plain(s, 0.4, 870.0), rel=1e-13
        )


@pytest.mark.parametrize(("lam0", "fwhm"), [(850.0, 35.0), (940.0, 50.0)])
def test_a_linear_qe_against_the_closed_form(tmp_path, lam0, fwhm):
    """QE(λ) = a + b λ over the spectrum: ∫ QE S dλ = QE(λ₀) exactly, and
    ∫ QE λ S dλ = QE(λ₀) λ₀ + b σ_t², σ_t² the variance of the Gaussian truncated at ±kσ,
    σ² (1 − 2 k φ(k) / (2 Φ(k) − 1)). The trapezoid rule on 4001 points over ±5σ is exact for
    the odd part and errs by ~h²/12 · f′ at the ends (f′ ~ 1e-5): 1e-10 is far above it."""
    a, b = 1.2, -1.0e-3  # QE 0.35 at 850, 0.26 at 940 nm
    s = Sensor(quantum_efficiency=str(_table(tmp_path, [(600, a + b * 600), (1200, a + b * 1200)])))
    sigma = gaussian_spectrum_sigma_nm(fwhm)
    k = SPECTRUM_HALF_WIDTH_SIGMA
    var_t = sigma**2 * (1 - 2 * k * norm.pdf(k) / (2 * norm.cdf(k) - 1))
    expected = (a + b * lam0) * lam0 + b * var_t
    assert spectral_response_nm(s, lam0, fwhm) == pytest.approx(expected, rel=1e-10)
    # the spectrum's width lowers the count here (b < 0) by b σ_t² / (QE λ₀), about 0.3 %
    assert spectral_response_nm(s, lam0, fwhm) < (a + b * lam0) * lam0


@pytest.mark.parametrize(("lam0", "fwhm"), [(850.0, 35.0), (940.0, 50.0), (980.0, 40.0)])
def test_the_built_in_curve_against_quad(lam0, fwhm):
    """The piecewise-linear built-in curve over a Gaussian, against scipy.integrate.quad with
    the table's knots as break points (written here, not the module's grid). The module's
    trapezoid rule errs at each knot by at most h²/8 · |Δslope| · λ S (h = 10σ/4000 nm):
    relative ≲ 1e-7; 1e-6 allows it."""
    s = Sensor(quantum_efficiency="nir-global-shutter")
    lam_t, q_t = quantum_efficiency_curve(s)
    sigma = gaussian_spectrum_sigma_nm(fwhm)
    lo, hi = lam0 - 5 * sigma, lam0 + 5 * sigma

    def g(x):
        return math.exp(-0.5 * ((x - lam0) / sigma) ** 2)

    knots = [x for x in lam_t if lo < x < hi]
    num = quad(lambda x: np.interp(x, lam_t, q_t) * x * g(x), lo, hi, points=knots, limit=200)
    den = quad(g, lo, hi, limit=200)
    expected = num[0] / den[0]
    assert spectral_response_nm(s, lam0, fwhm) == pytest.approx(expected, rel=1e-6)
    assert electrons_per_w_mm2(s, lam0, fwhm) == pytest.approx(
        _plain(s, 1.0, 1.0) * expected, rel=1e-6
    )


def test_the_built_in_curve_is_calibrated_and_silicon_like():
    """The model's file: QE(850) = 0.30 (its calibration), falling monotonically into the NIR
    (silicon absorbs ever less), QE(940)/QE(850) ≈ 0.42."""
    s = Sensor(quantum_efficiency="nir-global-shutter")
    lam, q = quantum_efficiency_curve(s)
    assert quantum_efficiency_at(s, 850.0) == 0.30
    assert np.all(np.diff(q) < 0) and lam[0] <= 700 and lam[-1] >= 1100
    assert quantum_efficiency_at(s, 940.0) / 0.30 == pytest.approx(0.42, abs=0.01)


@pytest.mark.parametrize(
    ("rows", "message"),
    [
        ([(800, 0.3), (800, 0.2)], "must increase strictly"),
        ([(900, 0.3), (800, 0.2)], "must increase strictly"),
        ([(800, 0.3), (900, 1.2)], "outside [0, 1]"),
        ([(800, -0.1), (900, 0.2)], "outside [0, 1]"),
        ([(800, "nan"), (900, 0.2)], "outside [0, 1]"),
        ([(800, 0.3)], "at least two"),
        ([(-5, 0.3), (900, 0.2)], "finite and > 0"),
    ],
)
def test_bad_tables_are_one_line_naming_file_and_field(tmp_path, rows, message):
    path = _table(tmp_path, rows)
    with pytest.raises(InputFileError) as err:
        quantum_efficiency_at(Sensor(quantum_efficiency=str(path)), 850.0)
    text = str(err.value)
    assert message in text and "qe.csv" in text and "sensor.quantum_efficiency" in text
    assert "\n" not in text


def test_a_wavelength_or_spectrum_outside_the_table(tmp_path):
    s = Sensor(quantum_efficiency=str(_table(tmp_path, [(800, 0.4), (1000, 0.1)])))
    with pytest.raises(SceneError, match=r"1050 nm lies outside the QE curve's 800-1000 nm"):
        quantum_efficiency_at(s, 1050.0)
    with pytest.raises(SceneError, match="the LED spectrum .* lies outside"):
        electrons_per_w_mm2(s, 960.0, 40.0)  # 960 ± 85 nm
    zero = Sensor(quantum_efficiency=str(_table(tmp_path, [(800, 0.0), (1000, 0.1)], "z.csv")))
    with pytest.raises(SceneError, match="is 0 at the scene's wavelength"):
        count_weights(zero, [900.0], 0.0, 800.0)


@pytest.mark.parametrize("value", [0, 1.5, -0.2, "", True, "0.3", float("nan")])
def test_bad_single_values_refused(value):
    with pytest.raises(ValueError):
        Sensor(quantum_efficiency=value)


def test_scene_file_path_is_relative_to_it(tmp_path):
    """A CSV path in a scene file is taken relative to the file's folder; a built-in curve's
    name is left as it is."""
    from eyelume.scene.io import _resolve_paths

    data = {"sensor": {"quantum_efficiency": "tables/my_qe.csv"}}
    _resolve_paths(data, tmp_path)
    assert data["sensor"]["quantum_efficiency"] == str((tmp_path / "tables/my_qe.csv").resolve())
    named = {"sensor": {"quantum_efficiency": "nir-global-shutter"}}
    _resolve_paths(named, tmp_path)
    assert named["sensor"]["quantum_efficiency"] == "nir-global-shutter"
    sc = load_scene("vr-offaxis", {"sensor.quantum_efficiency": "nir-global-shutter"})
    assert sc.sensor.quantum_efficiency == "nir-global-shutter"


def test_eye_image_counts_each_group_with_its_qe_and_spectrum(tmp_path):
    """RenderResult.eye_image_at_scene_wavelength = Σ_g E_g w_g with w_g the ratio of
    electrons_per_w_mm2 (λ_g, FWHM) to that at the scene's wavelength: a result built by hand
    from two group images (no tracing needed)."""
    from eyelume.render import GroupRender, RenderResult

    scene = load_scene(
        "vr-offaxis",
        {
            "sensor.quantum_efficiency": "nir-global-shutter",
            "leds.spectral_width_nm": [35.0] * 4 + [50.0] * 4,
            "leds.wavelength_nm": [850.0] * 4 + [940.0] * 4,
        },
    )
    rng = np.random.default_rng(0)
    e850, e940 = rng.random((2, 3, 4))
    fields = {f.name for f in dataclasses.fields(GroupRender)}
    assert {"wavelength_nm", "eye_image"} <= fields

    class _G:
        def __init__(self, lam, img):
            self.wavelength_nm, self.eye_image = lam, img

    r = RenderResult.__new__(RenderResult)
    object.__setattr__(r, "scene", scene)
    object.__setattr__(r, "eye_image", e850 + e940)
    object.__setattr__(r, "groups", [_G(850.0, e850), _G(940.0, e940)])
    ref = electrons_per_w_mm2(scene.sensor, 850.0)
    want = (
        e850 * electrons_per_w_mm2(scene.sensor, 850.0, 35.0)
        + e940 * electrons_per_w_mm2(scene.sensor, 940.0, 50.0)
    ) / ref
    np.testing.assert_allclose(r.eye_image_at_scene_wavelength, want, rtol=1e-13)
    # one wavelength, a width: the image scaled by its spectrum's count over the line's
    object.__setattr__(r, "groups", None)
    w = electrons_per_w_mm2(scene.sensor, 850.0, 35.0) / ref  # the 850 nm LEDs' width
    np.testing.assert_allclose(r.eye_image_at_scene_wavelength, (e850 + e940) * w, rtol=1e-13)
    assert w != 1.0


def test_cli_bad_qe_table_exit_2_one_line(tmp_path):
    bad = _table(tmp_path, [(800, 0.3), (900, 0.3), (850, 0.2)])
    out = tmp_path / "r"
    res = runner.invoke(
        app,
        ["render", "--scene", "vr-offaxis", "--samples", "1", "--out", str(out), "--set",
         f"sensor.quantum_efficiency={json.dumps(str(bad))}"],
    )  # fmt: skip
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and "qe.csv" in lines[0] and "must increase strictly" in lines[0]
    assert "sensor.quantum_efficiency" in lines[0]
    assert not out.exists() or not (out / "summary.json").exists()  # failed before tracing
    assert "Traceback" not in res.output


def test_cli_wavelength_outside_the_table_exit_2(tmp_path):
    short = _table(tmp_path, [(800, 0.3), (900, 0.2)])
    res = runner.invoke(
        app,
        ["render", "--scene", "vr-offaxis", "--samples", "1", "--out", str(tmp_path / "r"),
         "--set", f"sensor.quantum_efficiency={json.dumps(str(short))}",
         "--set", "leds.wavelength_nm=940"],
    )  # fmt: skip
    assert res.exit_code == 2, res.output
    assert "sensor.quantum_efficiency" in res.output and "940 nm lies outside" in res.output


def test_spectral_width_per_led():
    """One width per LED, the same within a wavelength; a different width in one wavelength
    group, a bad item or a wrong count is refused naming the item."""
    sc = load_scene(
        "paper2005",
        {"leds.wavelength_nm": [850, 940, 850, 940], "leds.spectral_width_nm": [35, 50, 35, 50]},
    )
    assert sc.leds.spectral_width_at(940.0, 850.0) == 50.0
    assert sc.leds.spectral_width_at(850.0, 850.0) == 35.0 and sc.leds.has_spectral_width
    assert not load_scene("paper2005").leds.has_spectral_width
    bad = [
        ({"leds.spectral_width_nm": [35, 50, 35, 50]}, r"spectral_width_nm\[1\] = 50 differs"),
        ({"leds.spectral_width_nm": [35, 35]}, "has 2 entries but there are 4 LEDs"),
        ({"leds.spectral_width_nm": [35, -1, 35, 35]}, r"spectral_width_nm\[1\] = -1"),
        ({"leds.spectral_width_nm": 500}, "0-200 nm"),
    ]
    for overrides, message in bad:
        with pytest.raises(SceneError, match=message):
            load_scene("paper2005", overrides)


def test_cli_render_reports_each_groups_qe(tmp_path):
    """A two-wavelength render with the built-in curve and per-wavelength widths: summary.json
    gives each group's QE, width and count weight, as the sensor module computes them."""
    out = tmp_path / "r"
    sets = {
        "sensor.cols": 32, "sensor.rows": 32, "sensor.pixel_pitch_um": 25.0,
        "sensor.quantum_efficiency": "nir-global-shutter",
        "leds.wavelength_nm": [850.0] * 4 + [940.0] * 4,
        "leds.spectral_width_nm": [35.0] * 4 + [50.0] * 4,
    }  # fmt: skip
    args = ["render", "--scene", "vr-offaxis", "--samples", "2", "--seed", "1", "--out", str(out)]
    for k, v in sets.items():
        args += ["--set", f"{k}={json.dumps(v)}"]
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    summary = json.loads((out / "summary.json").read_text())
    s = Sensor(quantum_efficiency="nir-global-shutter")
    weights = count_weights(s, [850.0, 940.0], [35.0, 50.0], 850.0)
    said = [g["sensor"] for g in summary["wavelength_groups"]]
    assert [g["quantum_efficiency"] for g in said] == [0.30, quantum_efficiency_at(s, 940.0)]
    assert [g["spectral_width_nm"] for g in said] == [35.0, 50.0]
    got = [g["electrons_relative_to_scene_wavelength"] for g in said]
    assert got == pytest.approx(weights, rel=1e-15)
    assert 0.3 < weights[1] < 0.6  # QE 0.127 x 940/850 / 0.30, spectrum-averaged
