"""Sunlight (``ambient.sun``) rendered beside the LEDs, against closed forms and the forward
estimator.

* A Lambertian disk of reflectance ρ filling the view of an ideal camera, lit by the sun at
  incidence θ, has radiance L = ρ E cos θ / π (E the sun's equivalent irradiance at the scene's
  wavelength, :func:`eyelume.detectors.sensor.sunlight_band`); the camera equation on the axis
  (tests/estimators/test_ideal_camera.py) gives the image irradiance π L sin²θ_a / m².
* Through 40 nm band-pass filters at 850 and 940 nm the sunlight's photo-electrons are in the
  ratio of ∫ E_λ QE λ dλ over the two bands, computed here from the data files directly.
* Fast and forward agree per bin (χ²) on a scene with the sun.
"""

from __future__ import annotations

import math
from importlib import resources

import numpy as np
import pytest
from scipy import stats

import eyelume
from eyelume.compile import SunSource, compile_scene
from eyelume.detectors.sensor import electrons_per_w_mm2, sunlight_band
from eyelume.scene.io import apply_overrides, load_scene
from eyelume.scene.model import Scene

FOCUS, RHO, ELEVATION = 31.0, 0.5, 40.0


def disk_scene(**sensor) -> Scene:
    """paper2005's eye behind a Lambertian disk (z = 0.5 mm, normal +z, radius 40 mm, ρ 0.5)
    seen by an ideal camera on the axis focused at 31 mm; a 5 × 5 picture near the axis; the
    sun at 40° elevation straight ahead (incidence θ = 40° on the disk)."""
    d = load_scene("paper2005").model_dump()
    d["camera"] = {
        "optics": "ideal",
        "ideal": {"efl_mm": 1.646, "f_number": 2.88, "focus_distance_mm": FOCUS},
        "position_mm": [0.0, 0.0, FOCUS],
        "psf": "none",
    }
    d["lens"] = None
    d["sensor"].update(width_mm=None, height_mm=None, cols=5, rows=5, **sensor)
    d["face"] = {
        "tissues": [
            {
                "name": "plate",
                "shape": "disk",
                "center_mm": [0.0, 0.0, 0.5],
                "axis": [0.0, 0.0, 1.0],
                "radius_mm": 40.0,
                "reflectance": RHO,
            }
        ]
    }
    d["ambient"] = {"sun": {"elevation_deg": ELEVATION, "azimuth_deg": 0.0}}
    return Scene.model_validate(d)


def test_lambertian_disk_is_the_camera_equation():
    scene = disk_scene(quantum_efficiency="nir-global-shutter")
    r = eyelume.render(
        scene, eyelume.RenderOptions(estimator="fast", samples_per_pixel=256, seed=3)
    )
    amb = r.ambient
    assert amb is not None and not amb.interrupted
    band = sunlight_band(scene.sensor, scene.ambient.sun, scene.wavelength_nm)
    ideal = scene.camera.ideal
    a, v = ideal.pupil_radius_mm, ideal.image_distance_mm
    sin2 = a * a / (FOCUS**2 + a * a)
    m = -v / FOCUS
    cos_i = math.cos(math.radians(ELEVATION))  # ŝ = (0, sin e, cos e), disk normal +z
    expected = RHO * band.irradiance_w_mm2 * cos_i * sin2 / (m * m)
    mean = amb.eye_image.mean()
    se = math.sqrt(amb.eye_image_variance.sum()) / amb.eye_image.size
    # the closed form holds to ~1e-4 here (the sun 10 m away: 1/r² and its direction vary by
    # < 1e-4 over the 5 × 5 pixels' 0.01 mm² patch; cos⁴ of their field angle < 1e-5)
    assert abs(mean - expected) < 4 * se + 2e-4 * expected, (mean, expected, se)
    assert se < 0.02 * expected  # the test has power
    # the LEDs' picture is apart; the sensor counts both
    assert np.allclose(r.eye_image_at_scene_wavelength, r.eye_image + amb.eye_image)


def _numbers(path) -> np.ndarray:
    """A data file's numeric rows (its '#' lines and header row left out)."""
    rows = [
        line.split(",")
        for line in path.read_text(encoding="utf-8").splitlines()
        if line.strip() and not line.startswith("#") and line[0].isdigit()
    ]
    return np.array(rows, dtype=float)


def test_850_against_940_nm_follows_the_table():
    """The same disk through a 40 nm band-pass filter at 850 and at 940 nm: the ratio of the
    sunlight's photo-electrons is ∫ E_λ QE λ dλ over 830-870 over that over 920-960 nm (QE the
    built-in curve), integrated here from the two files on a 0.01 nm grid."""
    electrons = {}
    for lam, (lo, hi) in ((850.0, (830.0, 870.0)), (940.0, (920.0, 960.0))):
        f = {"kind": "band_pass", "cut_on_nm": lo, "cut_off_nm": hi}
        scene = apply_overrides(
            disk_scene(quantum_efficiency="nir-global-shutter", filter=f),
            {"wavelength_nm": lam},
        )
        r = eyelume.render(
            scene, eyelume.RenderOptions(estimator="fast", samples_per_pixel=256, seed=5)
        )
        e = r.ambient.eye_image
        rel_se = math.sqrt(r.ambient.eye_image_variance.sum()) / e.sum()
        electrons[lam] = (e.mean() * electrons_per_w_mm2(scene.sensor, lam), rel_se)
    presets = resources.files("eyelume.scene.presets")
    sun = _numbers(presets / "solar" / "astm_g173_03.csv")
    qe = _numbers(presets / "sensors" / "nir-global-shutter.csv")

    def counted(lo, hi):
        x = np.linspace(lo, hi, 4001)
        return np.trapezoid(
            np.interp(x, sun[:, 0], sun[:, 3]) * np.interp(x, qe[:, 0], qe[:, 1]) * x, x
        )

    expected = counted(830, 870) / counted(920, 960)
    (n850, s850), (n940, s940) = electrons[850.0], electrons[940.0]
    # the two renders trace the disk at 849.2 and 935.3 nm alike (a Lambertian disk's
    # picture does not depend on the wavelength): the ratio carries their noise only
    tol = 4 * math.hypot(s850, s940) + 1e-4
    assert n850 / n940 == pytest.approx(expected, rel=tol)
    # 4.77 = 2.31 (sunlight over the two 40 nm bands) × 2.06 (the built-in curve's QE λ)
    assert expected == pytest.approx(4.77, abs=0.01)


@pytest.mark.parametrize(("which", "sign"), [("right", 1.0), ("left", -1.0)])
def test_the_sun_is_placed_along_its_direction_and_mirrored_for_a_left_eye(which, sign):
    """The compiled sun: 10 m from the eye's vertex along ŝ = (cos e sin a, sin e, cos e cos a)
    (a left eye's scene mirrored, x → −x), aimed back at it, I = E d²."""
    scene = apply_overrides(
        load_scene("paper2005"),
        {"eye_pose.which": which, "ambient.sun.elevation_deg": 30, "ambient.sun.azimuth_deg": 50},
    )
    sun = SunSource(scene.ambient.sun.direction(), 1e-5, 850.0)
    cs = compile_scene(scene, sun=sun)
    e, a = math.radians(30), math.radians(50)
    s_world = np.array([sign * math.cos(e) * math.sin(a), math.sin(e), math.cos(e) * math.cos(a)])
    vertex = cs.frame.point(np.zeros(3)) if not cs.frame.is_identity else np.zeros(3)
    s_cam = cs.frame.vector(s_world) if not cs.frame.is_identity else s_world
    np.testing.assert_allclose(cs.tables.leds.points[0], vertex + 1e4 * s_cam, atol=1e-9)
    np.testing.assert_allclose(cs.tables.leds.axes[0], -s_cam, atol=1e-12)
    assert cs.tables.leds.i0[0] == pytest.approx(1e-5 * 1e8)
    assert cs.led_ids == () and cs.sun == sun


@pytest.mark.slow
def test_fast_and_forward_agree_with_the_sun():
    """glasses-frame's lens opened to F/0.6, its picture's central 1.44 mm square binned 6 × 6,
    the sun at 35° elevation from 30° to the side (its compile alone: the sunlight's picture):
    per-bin z = (fast − forward) / √(var_fast + var_forward) over bins with ≥ 25 forward rays;
    Σz² inside the χ² distribution's central 99.8 %."""
    scene = apply_overrides(
        load_scene("glasses-frame"),
        {
            "camera.ideal.f_number": 0.6,
            "camera.psf": "none",
            "sensor.cols": 6,
            "sensor.rows": 6,
            "sensor.width_mm": 1.44,
            "sensor.height_mm": 1.44,
            "sensor.quantum_efficiency": "nir-global-shutter",
            "ambient.sun.elevation_deg": 35.0,
            "ambient.sun.azimuth_deg": 30.0,
        },
    )
    band = sunlight_band(scene.sensor, scene.ambient.sun, scene.wavelength_nm)
    # the sun's light narrowed to 40 mm about the eye (150 by default) so that forward rays
    # reach the picture 14× as often; both estimators trace the same compiled source
    sun = SunSource(
        scene.ambient.sun.direction(), band.irradiance_w_mm2, band.trace_wavelength_nm, 40.0
    )
    cs = compile_scene(scene, sun=sun, nominal=compile_scene(scene))
    fwd = eyelume.render(cs, eyelume.RenderOptions(rays=30_000_000, seed=11))
    fast = eyelume.render(
        cs, eyelume.RenderOptions(estimator="fast", samples_per_pixel=256, seed=12)
    )
    keep = fwd.image_counts >= 25
    n = int(keep.sum())
    assert n >= 15
    diff = fast.eye_image[keep] - fwd.eye_image[keep]
    chi2 = float(np.sum(diff**2 / (fast.eye_image_variance[keep] + fwd.eye_image_variance[keep])))
    lo, hi = stats.chi2.ppf([0.001, 0.999], n)
    assert lo < chi2 < hi, (chi2, n)
