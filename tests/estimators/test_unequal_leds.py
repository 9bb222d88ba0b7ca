"""LEDs of unequal radiant intensity and profile (issue 11, part 2): every estimator uses each
LED's own I₀ and I(α).

* closed form: the eye-plane irradiance of two unlike LEDs against a brute-force sum of
  I₀ₖ fₖ(α) cos β / r² written here, and linearity (a·E_A(1) + b·E_B(1));
* forward: a ray picks LED k with probability Φₖ / Φ (χ² on the counts), so the render's
  power is Σ Φₖ;
* fast: the glint of each LED scales with its own I₀ (the same paths, I₀ changed), and two
  mirror-image LEDs of I₀ and 3 I₀ give glint fluxes in the ratio 3 within their scatter;
* forward against fast on a headset with six unlike LEDs (χ² per bin);
* an LED whose cone misses the eye: a warning naming it; all of them: refused.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy import stats
from typer.testing import CliRunner

import eyelume
from eyelume.cli import app
from eyelume.compile import LedAimWarning, compile_scene
from eyelume.errors import GeometryError
from eyelume.estimators.closed_form import eye_plane_irradiance, plane_edges
from eyelume.estimators.fast_run import trace_fast
from eyelume.estimators.forward import emit_ray
from eyelume.scene.io import apply_overrides, load_scene
from eyelume.scene.sources import cos_power_exponent, led_poses

TWO = {
    "leds.count": 2,
    "leds.positions_mm": [[25.0, 5.0, 60.0], [-15.0, -20.0, 45.0]],
    "leds.aim_at_mm": [0.0, 0.0, 0.0],
}


def _table(tmp_path):
    path = tmp_path / "led.csv"
    path.write_text("angle_deg,relative\n0,1\n20,0.9\n40,0.45\n60,0.1\n75,0\n")
    return str(path)


def test_closed_form_two_unlike_leds_against_a_brute_force_sum(tmp_path):
    """E(p) = Σₖ I₀ₖ fₖ(αₖ) cos βₖ / rₖ², fₖ: cos^m (half angle 12°) and a table; each bin's mean
    by a 24 × 24 midpoint sum (its error ~1e-4 here, far below the LEDs' difference)."""
    a, b = 0.004, 0.05
    scene = load_scene(
        "paper2005",
        {
            **TWO,
            "leds.radiant_intensity_w_sr": [a, b],
            "leds.profile": [
                {"kind": "cos_power", "half_intensity_angle_deg": 12.0},
                {"kind": "table", "table_csv": _table(tmp_path)},
            ],
        },
    )
    e = eye_plane_irradiance(scene)
    centres, axes = led_poses(scene.leds)
    emit = centres + axes * scene.leds.body_diameter_mm / 2
    m = cos_power_exponent(12.0)
    ang, rel = np.radians([0, 20, 40, 60, 75]), np.array([1, 0.9, 0.45, 0.1, 0.0])
    profiles = [lambda al: np.cos(al) ** m, lambda al: np.interp(al, ang, rel, right=0.0)]
    xe, ye = plane_edges(scene.eye_plane)
    n = 24
    checked = 0
    for r, c in [(7, 10), (3, 4), (11, 16), (5, 14), (9, 2)]:
        fx = (np.arange(n) + 0.5) / n
        x = xe[c] + fx * (xe[c + 1] - xe[c])
        y = ye[r] + fx * (ye[r + 1] - ye[r])
        px, py = np.meshgrid(x, y)
        total = 0.0
        for k, i0 in enumerate((a, b)):
            v = np.stack([px - emit[k, 0], py - emit[k, 1], -emit[k, 2] * np.ones_like(px)])
            dist = np.linalg.norm(v, axis=0)
            cos_a = np.einsum("i...,i->...", v, axes[k]) / dist
            f = np.where(cos_a > 0, profiles[k](np.arccos(np.clip(cos_a, -1, 1))), 0.0)
            total += float(np.mean(i0 * f * (emit[k, 2] / dist) / dist**2))
        assert e[r, c] == pytest.approx(total, rel=2e-3), (r, c)
        checked += 1
    assert checked == 5


def test_closed_form_is_linear_in_each_leds_intensity():
    base = load_scene("paper2005", TWO)
    a, b = 0.007, 0.031
    both = eye_plane_irradiance(apply_overrides(base, {"leds.radiant_intensity_w_sr": [a, b]}))
    one = {"leds.count": 1, "leds.radiant_intensity_w_sr": 1.0}
    only_a = eye_plane_irradiance(
        apply_overrides(base, {**one, "leds.positions_mm": [TWO["leds.positions_mm"][0]]})
    )
    only_b = eye_plane_irradiance(
        apply_overrides(base, {**one, "leds.positions_mm": [TWO["leds.positions_mm"][1]]})
    )
    assert np.allclose(both, a * only_a + b * only_b, rtol=1e-12, atol=0.0)
    assert not np.allclose(both, 0.5 * (a + b) * (only_a + only_b), rtol=1e-3)


def test_forward_rays_leave_each_led_by_its_share_of_the_power():
    """LED k emits Φₖ = I₀ₖ Ω_eff,k; a forward ray carries Φ/N, so it must leave LED k with
    probability Φₖ/Φ. 60 000 rays: χ² with 3 degrees of freedom."""
    scene = load_scene(
        "paper2005",
        {
            "leds.radiant_intensity_w_sr": [0.01, 0.04, 0.01, 0.02],
            "leds.profile": [{"half_intensity_angle_deg": h} for h in (22.5, 22.5, 40.0, 10.0)],
        },
    )
    cs = compile_scene(scene)
    m = [cos_power_exponent(h) for h in (22.5, 22.5, 40.0, 10.0)]
    power = np.array([0.01, 0.04, 0.01, 0.02]) * 2 * math.pi / (np.array(m) + 1)
    assert np.allclose(cs.led_powers_w, power, rtol=1e-9)
    assert cs.emitted_w == pytest.approx(power.sum(), rel=1e-9)
    n = 60_000
    pts = cs.led.points
    counts = np.zeros(4)
    for i in range(n):
        em = emit_ray(i, 3, cs.led)
        counts[np.argmin(np.abs(pts[:, 0] - em.x) + np.abs(pts[:, 1] - em.y))] += 1
    expected = n * power / power.sum()
    chi2 = float(((counts - expected) ** 2 / expected).sum())
    assert chi2 < stats.chi2.ppf(0.999, 3), (counts, expected)


def _symmetric_pair(i0):
    return load_scene(
        "paper2005",
        {"leds.count": 2, "leds.azimuths_deg": [0.0, 180.0], "leds.radiant_intensity_w_sr": i0},
    )


def test_fast_glints_scale_with_each_leds_own_intensity():
    """The same seed traces the same light paths whatever I₀; a path's deposit is I₀ₖ times
    its geometry, so each LED's glint image scales by its own I₀ (to the fixed-point step)."""
    unit = trace_fast(compile_scene(_symmetric_pair([1.0, 1.0])), 8, 200_000, seed=4)
    cs = compile_scene(_symmetric_pair([0.015, 0.06]))
    est = trace_fast(cs, 8, 200_000, seed=4)
    for k, i0 in enumerate((0.015, 0.06)):
        assert unit.glint_images[k].sum() > 0
        scaled = i0 * unit.glint_images[k]
        # fixed-point deposits: a step of 2⁻²⁴ of the brightest LED's typical one
        assert np.abs(est.glint_images[k] - scaled).max() <= 1e-6 * scaled.max()
        assert est.glint_images[k].sum() == pytest.approx(scaled.sum(), rel=1e-6)


def test_fast_glint_fluxes_of_mirror_leds_are_in_the_ratio_of_their_intensities():
    """LEDs at azimuth 0° and 180° are mirror images about the camera's axis (eye, lens and
    sensor are symmetric in x): glint flux ∝ I₀ (linearity), so with I₀ = 0.015 and 0.045 W/sr
    the fluxes G₀, G₁ satisfy G₁ − 3 G₀ = 0 in expectation. Over five seeds (independent,
    unbiased estimates; a ratio of sums of rare deposits would be biased at this budget) the
    mean of G₁ − 3 G₀ lies within 4 standard errors of 0, and that error is small enough to
    tell a ratio of 3 from 2.7."""
    cs = compile_scene(_symmetric_pair([0.015, 0.045]))
    g0, g1 = [], []
    for seed in range(5):
        g = trace_fast(cs, 8, 300_000, seed=seed).glint_images
        g0.append(g[0].sum())
        g1.append(g[1].sum())
        # the mirror image: LED 1's glint sits where LED 0's is, reflected in x
        assert np.argmax(g[1].sum(axis=0)) == g.shape[2] - 1 - np.argmax(g[0].sum(axis=0))
    d = np.array(g1) - 3.0 * np.array(g0)
    mean, se = d.mean(), d.std(ddof=1) / math.sqrt(d.size)
    assert 4 * se < 0.1 * np.mean(g1), (g0, g1)
    assert abs(mean) < 4 * se, (g0, g1, mean, se)


MIN_COUNTS = 25


@pytest.mark.slow
def test_forward_and_fast_agree_with_six_unlike_leds():
    """``glasses-frame`` with its six LEDs of I₀ 0.5–4 mW/sr and half angles 20–60°, its lens
    opened to F/0.6 and binned 8 × 6 (as the off-axis agreement test): per-bin z over bins with
    ≥ 25 forward rays, Σz² inside the central 99.8 % of χ²."""
    scene = apply_overrides(
        load_scene("glasses-frame"),
        {
            "camera.ideal.f_number": 0.6,
            "camera.psf": "none",  # the traced pictures: the χ² takes the bins as independent
            "sensor.cols": 8,
            "sensor.rows": 6,
            "sensor.width_mm": 1.92,
            "sensor.height_mm": 1.44,
            "leds.radiant_intensity_w_sr": [0.0005, 0.004, 0.001, 0.002, 0.0005, 0.003],
            "leds.profile": [
                {"half_intensity_angle_deg": h} for h in (60.0, 20.0, 60.0, 40.0, 60.0, 30.0)
            ],
        },
    )
    cs = compile_scene(scene)
    fwd = eyelume.render(cs, eyelume.RenderOptions(rays=10_000_000, seed=11))
    fast = eyelume.render(
        cs, eyelume.RenderOptions(estimator="fast", samples_per_pixel=256, seed=12)
    )
    assert fwd.ledger is not None
    assert sum(fwd.ledger.values()) == pytest.approx(cs.emitted_w, rel=1e-12)
    keep = fwd.image_counts >= MIN_COUNTS
    n = int(keep.sum())
    assert n > 25
    z = (fast.eye_image - fwd.eye_image)[keep] / np.sqrt(
        (fast.eye_image_variance + fwd.eye_image_variance)[keep]
    )
    chi2 = float((z**2).sum())
    lo, hi = stats.chi2.ppf([0.001, 0.999], n)
    assert lo < chi2 < hi, f"Σz² = {chi2:.0f} over {n} bins, outside [{lo:.0f}, {hi:.0f}]"


def _aim_warnings(scene) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        compile_scene(scene)
    return [str(w.message) for w in caught if issubclass(w.category, LedAimWarning)]


def test_an_led_facing_away_is_named_in_a_warning():
    scene = load_scene(
        "paper2005",
        {
            "leds.count": 2,
            "leds.positions_mm": TWO["leds.positions_mm"],
            "leds.directions": [[-0.4, -0.1, -1.0], [0.0, 0.0, 1.0]],
        },
    )
    lines = _aim_warnings(scene)
    assert len(lines) == 1 and lines[0].startswith("leds: LED 1 "), lines
    assert "misses the eye" in lines[0] and "\n" not in lines[0]


def test_a_narrow_table_led_aimed_past_the_eye_is_named(tmp_path):
    """A profile that reaches 0 at 10° (a table), aimed 45° past the eye, misses it although
    it faces it: the cone is the profile's, not the hemisphere; the same aim with a cosᵐ
    profile (> 0 up to 90°) does not."""
    scene = load_scene("paper2005")
    c, _ = led_poses(scene.leds)
    aim = -c / np.linalg.norm(c, axis=1, keepdims=True)
    past = math.cos(math.radians(45)) * aim[0] + math.sin(math.radians(45)) * np.cross(
        [0.0, 1.0, 0.0], aim[0]
    )
    assert past[2] < 0  # still toward the eye's side
    table = tmp_path / "narrow.csv"
    table.write_text("0,1\n5,0.5\n10,0\n")
    placed = {"leds.positions_mm": c.tolist(), "leds.directions": [list(past), *aim[1:].tolist()]}
    assert _aim_warnings(apply_overrides(scene, placed)) == []
    narrow = apply_overrides(
        scene,
        {**placed, "leds.profile": [{"kind": "table", "table_csv": str(table)}, {}, {}, {}]},
    )
    lines = _aim_warnings(narrow)
    assert len(lines) == 1 and lines[0].startswith("leds: LED 0 "), lines
    assert "emits only to 10.0 deg" in lines[0]


def test_leds_all_facing_away_are_refused(tmp_path):
    with pytest.raises(GeometryError, match="every LED's cone misses the eye"):
        compile_scene(load_scene("paper2005", {"leds.pitch_deg": -80.0}))  # turned outward
    res = CliRunner().invoke(
        app, ["render", "--rays", "1000", "--set", "leds.pitch_deg=-80", "--out", str(tmp_path)]
    )
    assert res.exit_code == 2
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and "every LED's cone misses the eye" in lines[0], lines
