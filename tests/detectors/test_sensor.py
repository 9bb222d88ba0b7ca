"""The sensor model: irradiance → electrons → DN, its noise statistics, clipping and outputs."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from PIL import Image

from eyelume.compile import compile_scene
from eyelume.detectors.sensor import camera_summary, digitize, electrons_per_w_mm2
from eyelume.render import RenderOptions, render, render_extras
from eyelume.report.outputs import write_render_outputs
from eyelume.scene.io import SceneError, load_scene
from eyelume.scene.model import Sensor

# Exact SI values (2019 redefinition), independent of scipy.constants.
H = 6.62607015e-34  # J s
C = 299_792_458.0  # m/s

#: A quiet, linear camera for statistics: no read noise, 1 e⁻/DN, no pedestal, a deep well, 16 bits.
LINEAR = dict(read_noise_e=0.0, gain_e_per_dn=1.0, black_level_dn=0.0, adc_bits=16)


def _sensor(**kw) -> Sensor:
    return Sensor(**{"full_well_e": 1e6, **LINEAR, **kw})


def _flat(sensor: Sensor, electrons: float, shape=(500, 500)) -> np.ndarray:
    """A flat irradiance field (W/mm²) whose mean photo-electron count is ``electrons``."""
    return np.full(shape, electrons / electrons_per_w_mm2(sensor, 850.0))


def test_mean_electrons_match_the_photon_count():
    # 0.13 W/m² on a 3 µm pixel for 4 ms at 850 nm, QE 0.35: N = E A t QE λ / (h c).
    sensor = _sensor(pixel_pitch_um=3.0, exposure_ms=4.0, quantum_efficiency=0.35)
    e_w_m2 = 0.13
    expected = e_w_m2 * (3e-6) ** 2 * 4e-3 * 0.35 / (H * C / 850e-9)  # 7009.3 e⁻
    d = digitize(np.full((4, 5), e_w_m2 * 1e-6), sensor, 850.0, seed=0)
    assert d.mean_electrons == pytest.approx(np.full((4, 5), expected), rel=1e-12)
    assert electrons_per_w_mm2(sensor, 850.0) * e_w_m2 * 1e-6 == pytest.approx(expected, rel=1e-12)
    assert d.photon_energy_j == pytest.approx(H * C / 850e-9, rel=1e-12)
    assert 7000 < expected < 7020


def test_shot_noise_variance_equals_the_mean():
    # With no read noise and 1 e⁻/DN the counts are Poisson(μ) draws. For n samples the sample
    # variance s² has sd μ·sqrt(2/(n−1) + 1/(μ n)) (Poisson excess kurtosis 1/μ), the sample mean
    # sd sqrt(μ/n). μ = 1000, n = 250 000: sd(s²) = 2.83, sd(mean) = 0.063; we allow 5 sd.
    sensor = _sensor()
    mu, n = 1000.0, 250_000
    counts = digitize(_flat(sensor, mu), sensor, 850.0, seed=7).counts.astype(np.float64)
    assert counts.size == n
    sd_var = mu * math.sqrt(2 / (n - 1) + 1 / (mu * n))
    assert abs(counts.var(ddof=1) - mu) < 5 * sd_var
    assert abs(counts.mean() - mu) < 5 * math.sqrt(mu / n)


def test_read_noise_alone():
    # E = 0: DN = round(1000 + N(0, σ)) with σ = 5 e⁻ = 5 DN; rounding adds a uniform error of
    # variance 1/12 (Sheppard), so the expected sd is sqrt(25 + 1/12). The sample sd of n normal
    # draws has sd ≈ s/sqrt(2(n−1)) = 0.0071 for n = 250 000; we allow 5 sd.
    sigma, n = 5.0, 250_000
    sensor = _sensor(read_noise_e=sigma, black_level_dn=1000.0)
    counts = digitize(np.zeros((500, 500)), sensor, 850.0, seed=3).counts.astype(np.float64)
    expected_sd = math.sqrt(sigma**2 + 1 / 12)
    assert abs(counts.std(ddof=1) - expected_sd) < 5 * expected_sd / math.sqrt(2 * (n - 1))
    assert abs(counts.mean() - 1000.0) < 5 * expected_sd / math.sqrt(n)


def test_full_well_saturates_and_is_flagged():
    sensor = _sensor(full_well_e=1000.0, adc_bits=12)
    irr = _flat(sensor, 100.0, shape=(1, 3))
    irr[0, 1] *= 1e4  # 10⁶ e⁻ expected: far over the 1000 e⁻ well
    irr[0, 2] = 1e3  # absurdly bright (W/mm²): still just a full well
    d = digitize(irr, sensor, 850.0, seed=1)
    assert d.counts[0, 1] == 1000 and d.counts[0, 2] == 1000
    assert d.saturated.tolist() == [[False, True, True]]
    assert d.saturated_pixels == 2
    assert d.counts.dtype == np.uint16


def test_adc_clips_at_full_scale():
    sensor = _sensor(adc_bits=8)  # deep well, 1 e⁻/DN: 1000 e⁻ would be 1000 DN > 255
    irr = _flat(sensor, 1000.0, shape=(1, 2))
    irr[0, 0] /= 10  # 100 e⁻: P(Poisson(100) ≥ 255) < 1e-30
    d = digitize(irr, sensor, 850.0, seed=1)
    assert d.full_scale_dn == 255
    assert d.counts[0, 1] == 255
    assert d.saturated.tolist() == [[False, True]]


def test_black_level_and_gain():
    sensor = _sensor(gain_e_per_dn=4.0, black_level_dn=64.0)
    d = digitize(np.zeros((1, 1)), sensor, 850.0, seed=0)
    assert d.counts[0, 0] == 64 and d.electrons_per_dn == 4.0


def test_same_seed_same_counts_other_seed_other_counts():
    sensor = Sensor()
    irr = _flat(sensor, 2000.0, shape=(65, 87))
    a = digitize(irr, sensor, 850.0, seed=11).counts
    b = digitize(irr, sensor, 850.0, seed=11).counts
    c = digitize(irr, sensor, 850.0, seed=12).counts
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


@pytest.mark.parametrize(
    ("value", "words"), [(np.nan, "NaN"), (np.inf, "infinite"), (-1e-9, "negative")]
)
def test_bad_irradiance_is_refused(value, words):
    irr = np.zeros((3, 3))
    irr[1, 1] = value
    with pytest.raises(ValueError, match=words):
        digitize(irr, Sensor(), 850.0, seed=0)


@pytest.mark.parametrize(
    ("overrides", "field"),
    [
        ({"sensor.exposure_ms": "-1"}, "sensor.exposure_ms"),
        ({"sensor.quantum_efficiency": "1.5"}, "sensor.quantum_efficiency"),
        ({"sensor.adc_bits": "0"}, "sensor.adc_bits"),
        ({"sensor.read_noise_e": "-2"}, "sensor.read_noise_e"),
        ({"sensor.gain_e_per_dn": "0"}, "sensor.gain_e_per_dn"),
        ({"sensor.adc_bits": "4", "sensor.black_level_dn": "15"}, "black_level_dn"),
    ],
)
def test_bad_sensor_values_name_the_field(overrides, field):
    with pytest.raises(SceneError, match=field.replace(".", r"\.")):
        load_scene("paper2005", overrides)


def test_render_writes_the_digital_image_and_camera_summary(tmp_path):
    scene = load_scene("paper2005", {"run.estimator": "forward"})
    result = render(scene, RenderOptions(rays=200_000, seed=1))
    write_render_outputs(result, render_extras(compile_scene(scene), result.seed), tmp_path)

    counts = np.load(tmp_path / "eye_image_digital.npy")
    assert counts.shape == (65, 87) and counts.dtype == np.uint16
    expected = digitize(result.eye_image, scene.sensor, scene.wavelength_nm, seed=1)
    assert np.array_equal(counts, expected.counts)

    # The PNG maps 0 … full scale (1023 DN) to 0 … 255 with no autoscaling (8× enlarged).
    with Image.open(tmp_path / "eye_image_digital.png") as im:
        assert im.mode == "L"
        grey = np.asarray(im)[::8, ::8]
    assert np.array_equal(grey, np.rint(counts * (255 / 1023)).astype(np.uint8))

    camera = json.loads((tmp_path / "summary.json").read_text())["camera"]
    assert camera["exposure_ms"] == scene.sensor.exposure_ms
    assert camera["adc_bits"] == 10 and camera["full_scale_dn"] == 1023
    assert camera["saturated_pixels"] == expected.saturated_pixels
    assert camera["median_dn"] == float(np.median(counts))
    assert camera["electrons_per_w_mm2"] == pytest.approx(
        electrons_per_w_mm2(scene.sensor, 850.0), rel=1e-12
    )


@pytest.mark.slow
def test_glints_saturate_and_skin_does_not_in_the_default_render():
    """The paper notes LightTools could not show saturation: in the default scene's camera
    reading the glints clip at the full well while the skin sits inside the range."""
    # enough light paths that a glint's peak pixel is known to ~5 % (its expected level is
    # ~1.2 full wells at the default exposure)
    scene = load_scene("paper2005", {"run.light_paths_per_pixel": 128})
    result = render(scene, RenderOptions(seed=3))
    dig = digitize(result.eye_image, scene.sensor, scene.wavelength_nm, seed=3)
    glints = [m for name, m in result.regions.items() if name.startswith("glint")]
    assert len(glints) == 4
    for m in glints:
        assert dig.saturated[m].any()
    any_glint = np.logical_or.reduce(glints)
    assert not dig.saturated[result.regions["skin"]].any()
    assert dig.saturated.sum() <= any_glint.sum()
    full = 2**scene.sensor.adc_bits - 1
    assert 0.2 * full < np.median(dig.counts[result.regions["skin"]]) < 0.8 * full


@pytest.mark.parametrize(("bits", "clip_e"), [(16, 6000.0), (8, (255 - 16 + 0.5) * 6.0)])
def test_saturation_beyond_the_estimates_noise(bits, clip_e):
    """Three kinds of pixel, the clipping level N_c the well (6000 e⁻) or, at 8 bits, the
    ADC's full scale (255 − 16 + ½ DN × 6 e⁻/DN = 1437 e⁻): 1.5 N_c ± 0.6 N_c (a forward
    pixel of ~6 rays: N̄ − 2σ = 0.3 N_c, saturated but not beyond the noise), 3 N_c ± 0.3 N_c
    (beyond: 2.4 N_c) and 0.5 N_c ± 0 (below). 40 % of the pixels are of the second kind."""
    sensor = Sensor(full_well_e=6000, read_noise_e=0.0, gain_e_per_dn=6.0,
                    black_level_dn=16.0, adc_bits=bits)  # fmt: skip
    per = electrons_per_w_mm2(sensor, 850.0)
    kind = np.tile(np.array([0, 1, 1, 2, 2, 0, 1, 1, 0, 0]), (30, 4))  # 0, 1, 2: 40, 40, 20 %
    electrons = np.choose(kind, [1.5 * clip_e, 3.0 * clip_e, 0.5 * clip_e])
    sigma = np.choose(kind, [0.6 * clip_e, 0.3 * clip_e, 0.0])
    digital = digitize(electrons / per, sensor, 850.0, seed=3)
    cam = camera_summary(sensor, 850.0, digital, estimate_std_w_mm2=sigma / per)
    assert cam["saturated_share_beyond_noise"] == pytest.approx(0.4)
    assert 0.79 < cam["saturated_share"] <= 0.8  # Poisson draws about 1.5 N_c: all but a few
    assert "saturated_share_beyond_noise" not in camera_summary(sensor, 850.0, digital)
