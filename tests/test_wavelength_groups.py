"""LEDs of several wavelengths (issue 11, item 2): a render is the sum over wavelength groups,
each compiled and traced at its own wavelength with only its LEDs emitting; the sensor counts
the groups' photo-electrons; truth glints are the union of the groups'; each LED's safety
weight is at its own wavelength; bad wavelengths are one line, exit 2."""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest
from typer.testing import CliRunner

from eyelume.analysis.safety import burn_hazard_weight, eye_safety
from eyelume.analysis.truth import eye_truth
from eyelume.cli import app
from eyelume.compile import compile_scene, lens_indices, single_wavelength, wavelength_groups
from eyelume.detectors.sensor import digitize, electrons_per_w_mm2
from eyelume.errors import SceneError
from eyelume.kernels import sequential as Q
from eyelume.render import RenderOptions, group_seed, render
from eyelume.scene.io import apply_overrides, load_scene

runner = CliRunner()

SMALL = {"sensor.cols": 48, "sensor.rows": 48, "sensor.pixel_pitch_um": 25.0}  # the 400 × 400 field
TWO = {"leds.wavelength_nm": [850.0] * 4 + [940.0] * 4}  # vr-offaxis: 8 LEDs


@pytest.fixture(scope="module")
def vr_two():
    return load_scene("vr-offaxis", {**SMALL, **TWO})


@pytest.fixture(scope="module")
def fast_two(vr_two):
    """The two-wavelength render, and each group rendered alone with its seed."""
    cs = compile_scene(vr_two)
    opt = {"estimator": "fast", "samples_per_pixel": 32}  # enough light paths for glints
    whole = render(cs, RenderOptions(seed=3, **opt))
    alone = [
        render(
            compile_scene(vr_two, g, nominal=cs), RenderOptions(seed=group_seed(3, g.index), **opt)
        )
        for g in wavelength_groups(vr_two)
    ]
    return whole, alone


def test_groups_by_wavelength():
    scene = load_scene("paper2005", {"leds.wavelength_nm": [940, 850, 940, 850]})
    groups = wavelength_groups(scene)
    assert [(g.index, g.wavelength_nm, g.leds) for g in groups] == [
        (0, 850.0, (1, 3)),
        (1, 940.0, (0, 2)),
    ]
    assert not single_wavelength(scene)
    assert single_wavelength(load_scene("paper2005", {"leds.wavelength_nm": 850}))
    one_other = load_scene("paper2005", {"leds.wavelength_nm": 940})
    assert not single_wavelength(one_other) and len(wavelength_groups(one_other)) == 1


def test_group_seeds_are_fixed_and_distinct():
    """The documented derivation, recomputed here: SeedSequence([seed, tag, g]) → 63 bits."""
    s = np.random.SeedSequence([7, 0x57A7E1E6, 1]).generate_state(1, dtype=np.uint64)[0]
    assert group_seed(7, 1) == int(s) >> 1
    seeds = {group_seed(seed, g) for seed in (0, 1, 2) for g in (0, 1, 2)}
    assert len(seeds) == 9 and all(0 <= x < 2**63 for x in seeds)


def test_a_group_is_traced_at_its_wavelength_with_its_leds():
    """The 940 nm group of paper2005 (a dispersive Double Gauss): lens indices at 940 nm (the
    glass catalog's formula, as a whole scene at 940 nm gets them), the eye's surfaces as the
    940 nm scene's, the lens's clear apertures those of the lens as built at 850 nm, and only
    LEDs 0 and 2 emitting, from the same points as in the nominal compile."""
    scene = load_scene("paper2005", {"leds.wavelength_nm": [940, 850, 940, 850]})
    nominal = compile_scene(scene)
    at940 = apply_overrides(scene, {"wavelength_nm": 940.0, "leds.wavelength_nm": 940.0})
    ref = compile_scene(at940)
    g940 = wavelength_groups(scene)[1]
    cg = compile_scene(scene, g940, nominal=nominal)
    assert cg.scene.wavelength_nm == 940.0 and cg.led_ids == (0, 2)
    assert cg.lens_indices == lens_indices(at940)[0] != nominal.lens_indices
    np.testing.assert_array_equal(cg.lf[:, Q.L_SD], nominal.lf[:, Q.L_SD])
    np.testing.assert_array_equal(cg.lf[:, Q.L_N1], ref.lf[:, Q.L_N1])
    eye = [cg.surface_names.index(n) for n in ("anterior cornea", "posterior cornea")]
    assert not np.array_equal(cg.sf[eye], nominal.sf[eye])  # the eye disperses too
    np.testing.assert_array_equal(cg.sf[eye], ref.sf[eye])
    np.testing.assert_array_equal(cg.led.points, nominal.led.points[[0, 2]])
    assert cg.emitted_w == pytest.approx(nominal.emitted_w / 2, rel=1e-12)
    # every LED's body is still there (an absorber whichever LEDs emit)
    assert all(f"LED {k} body" in cg.surface_names for k in range(4))
    # the entrance pupil: the fixed stop imaged at 940 nm, within the dispersion of EFL / N
    fo, fn = cg.first_order, nominal.first_order
    assert fo.entrance_pupil_radius == pytest.approx(fn.entrance_pupil_radius, rel=5e-3)
    assert fo.entrance_pupil_radius != fn.entrance_pupil_radius


def test_the_render_is_the_sum_of_its_groups(fast_two):
    """Fast estimator: image, variance (independent groups), eye plane, power and glint masks
    of the two-wavelength render are exactly those of the groups rendered alone with the
    documented seeds."""
    whole, (a, b) = fast_two
    np.testing.assert_array_equal(whole.eye_image, a.eye_image + b.eye_image)
    np.testing.assert_array_equal(
        whole.eye_image_variance, a.eye_image_variance + b.eye_image_variance
    )
    np.testing.assert_array_equal(whole.eye_plane, a.eye_plane + b.eye_plane)
    assert whole.emitted_w == a.emitted_w + b.emitted_w
    assert whole.rays == a.rays + b.rays
    assert [g.wavelength_nm for g in whole.groups] == [850.0, 940.0]
    assert [g.seed for g in whole.groups] == [group_seed(3, 0), group_seed(3, 1)]
    for k in range(8):  # LED k: row k of group 0 or k - 4 of group 1
        alone = a if k < 4 else b
        np.testing.assert_array_equal(whole.regions[f"glint {k}"], alone.regions[f"glint {k % 4}"])
    assert whole.summary()["wavelength_groups"][1]["leds"] == [4, 5, 6, 7]


def test_the_sensor_counts_each_groups_photons(fast_two, vr_two):
    """N̄ = Σ_g E_g p² t QE λ_g / (h c): the digitised picture's mean electrons against
    electrons_per_w_mm2 at each group's wavelength (QE one number for both)."""
    whole, (a, b) = fast_two
    mean = a.eye_image * electrons_per_w_mm2(
        vr_two.sensor, 850.0
    ) + b.eye_image * electrons_per_w_mm2(vr_two.sensor, 940.0)
    dig = digitize(whole.eye_image_at_scene_wavelength, vr_two.sensor, vr_two.wavelength_nm, 1)
    np.testing.assert_allclose(dig.mean_electrons, mean, rtol=1e-12)
    assert not np.allclose(
        dig.mean_electrons, whole.eye_image * electrons_per_w_mm2(vr_two.sensor, 850.0)
    )


def test_deterministic(vr_two, fast_two):
    opt = {"estimator": "fast", "samples_per_pixel": 4}
    once, again = (render(vr_two, RenderOptions(seed=3, **opt)) for _ in range(2))
    np.testing.assert_array_equal(again.eye_image, once.eye_image)
    np.testing.assert_array_equal(again.eye_image_variance, once.eye_image_variance)
    other = render(vr_two, RenderOptions(seed=4, **opt))
    assert not np.array_equal(other.eye_image, once.eye_image)


def test_forward_is_the_sum_of_its_groups(vr_two):
    """Forward Monte Carlo: the rays shared by power (here equal), ledger and counts add up."""
    cs = compile_scene(vr_two)
    whole = render(cs, RenderOptions(estimator="forward", rays=40_000, seed=5))
    parts = [
        render(
            compile_scene(vr_two, g, nominal=cs),
            RenderOptions(estimator="forward", rays=20_000, seed=group_seed(5, g.index)),
        )
        for g in wavelength_groups(vr_two)
    ]
    assert whole.rays == 40_000
    np.testing.assert_array_equal(whole.image_counts, parts[0].image_counts + parts[1].image_counts)
    np.testing.assert_allclose(whole.eye_image, parts[0].eye_image + parts[1].eye_image, rtol=1e-12)
    np.testing.assert_allclose(whole.eye_plane, parts[0].eye_plane + parts[1].eye_plane, rtol=1e-12)
    for name, w in whole.ledger.items():
        assert w == pytest.approx(
            parts[0].ledger[name] + parts[1].ledger[name], rel=1e-12, abs=1e-18
        )
    assert sum(whole.ledger.values()) == pytest.approx(whole.emitted_w, rel=1e-9)


def test_skin_agrees_with_one_wavelength_within_statistics(vr_two):
    """An independent check of the sum: with an ideal (dispersion-free) camera the skin's light
    hardly depends on the wavelength (only through the eye's indices), so the two-wavelength
    render's mean skin irradiance equals the all-850 nm scene's (the path without groups)
    within 4 combined standard errors."""
    one = apply_overrides(vr_two, {"leds.wavelength_nm": 850.0})
    opt = RenderOptions(estimator="fast", samples_per_pixel=8, seed=11)
    r2, r1 = render(vr_two, opt), render(one, opt)
    assert r1.groups is None and r2.groups is not None
    s1, s2 = r1.region_stats()["skin"], r2.region_stats()["skin"]
    m1, m2 = s1["mean_w_mm2"], s2["mean_w_mm2"]
    se = math.hypot(s1["mean_rel_error"] * m1, s2["mean_rel_error"] * m2)
    assert abs(m2 - m1) < 4 * se, (s1, s2)


def test_truth_glints_are_each_groups():
    """paper2005 (a dispersive lens) with LEDs at 850, 940, 850, 940 nm: each glint is where
    the truth of a scene all at that LED's wavelength puts it, marked with its wavelength."""
    scene = load_scene("paper2005", {"leds.wavelength_nm": [850, 940, 850, 940]})
    t = eye_truth(compile_scene(scene))
    t850 = eye_truth(compile_scene(apply_overrides(scene, {"leds.wavelength_nm": 850.0})))
    at940 = apply_overrides(scene, {"wavelength_nm": 940.0, "leds.wavelength_nm": 940.0})
    t940 = eye_truth(compile_scene(at940))
    assert [g["led"] for g in t["glints"]] == [0, 1, 2, 3]
    for k, g in enumerate(t["glints"]):
        ref = (t850 if k % 2 == 0 else t940)["glints"][k]
        assert g["wavelength_nm"] == (850.0 if k % 2 == 0 else 940.0)
        assert g["on_cornea"] == ref["on_cornea"] and g["visible"] == ref["visible"]
        np.testing.assert_allclose(g["centre_px"], ref["centre_px"], atol=1e-6)
    # the lens's dispersion moves the 940 nm glints (a little): the groups are not all at 850
    assert not np.allclose(t["glints"][1]["centre_px"], t850["glints"][1]["centre_px"], atol=1e-9)
    assert t["pupil"] == t850["pupil"]  # the pupil at the scene's wavelength
    assert t["glints_on_cornea"] == sum(g["on_cornea"] for g in t["glints"])


def test_rendered_glints_sit_at_the_truth(fast_two, vr_two):
    """Every glint mask the two-wavelength render finds lies within a pixel of its LED's true
    glint, and each group has glints found (at 32 samples per pixel some of the eight glints
    get no light path: their masks are empty)."""
    whole, _ = fast_two
    truth = eye_truth(compile_scene(vr_two))
    found = set()
    for g in truth["glints"]:
        mask = whole.regions[f"glint {g['led']}"]
        if not mask.any():
            continue
        rows, cols = np.nonzero(mask)
        c, r = g["centre_px"]
        assert np.all(np.abs(cols - c) <= 1.5) and np.all(np.abs(rows - r) <= 1.5), g
        found.add(g["led"])
    assert found & {0, 1, 2, 3} and found & {4, 5, 6, 7}, found


def test_each_leds_safety_at_its_own_wavelength():
    """Retinal radiance L_k = I₀ / (π (D_k/2)²) · R(λ_k), each LED its own λ and emitter."""
    scene = load_scene(
        "paper2005",
        {
            "leds.wavelength_nm": [850, 940, 850, 1550],
            "leds.emitter_diameter_mm": [1.0, 1.0, 0.5, 1.0],
        },
    )
    s = eye_safety(scene)
    i0 = 0.015
    for k, (lam, d) in enumerate(((850, 1.0), (940, 1.0), (850, 0.5), (1550, 1.0))):
        led = s["per_led"][k]
        assert led["wavelength_nm"] == lam and led["emitter_diameter_mm"] == d
        r = d / 2 * 1e-3
        expect = i0 / (math.pi * r * r) * burn_hazard_weight(lam)
        assert led["retinal_radiance_w_m2_sr"] == pytest.approx(expect, rel=1e-12)
    assert s["per_led"][3]["retinal_margin"] == math.inf  # 1550 nm: no retinal thermal hazard
    assert s["retinal_worst_led"] == 2  # the smallest die: 4× the radiance, half the subtense
    assert s["burn_hazard_weight"] == burn_hazard_weight(850)


@pytest.mark.parametrize(
    ("value", "words"),
    [
        ("nan", "leds.wavelength_nm"),
        ("-850", "must be > 0"),
        ("0", "must be > 0"),
        ("[850, 850, nan, 850]", "wavelength_nm[2] = nan"),
        ("[850, 850, 850, -940]", "wavelength_nm[3] = -940"),
        ("[850, 850, 850, 9000]", "wavelength_nm[3] = 9000: must lie in 300 … 2500 nm"),
    ],
)
def test_bad_wavelength_is_one_line_exit_2(value, words):
    res = runner.invoke(app, ["info", "--set", f"leds.wavelength_nm={value}"])
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and words in lines[0] and "wavelength_nm" in lines[0], lines


def test_bad_wavelength_in_a_file_is_one_line_exit_2(tmp_path):
    from eyelume.scene.io import save_scene

    f = tmp_path / "s.toml"
    save_scene(load_scene("paper2005"), f)
    f.write_text(
        f.read_text().replace("[leds]\n", "[leds]\nwavelength_nm = [850, 850, 850, nan]\n")
    )
    res = runner.invoke(app, ["info", "--scene", str(f)])
    assert res.exit_code == 2
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and "wavelength_nm[3] = nan" in lines[0], lines


@pytest.mark.filterwarnings("ignore:lens. the sensor")  # 2400 nm also moves the focus
def test_a_wavelength_beyond_a_glass_range_warns_in_its_group():
    """paper2005's glasses: an LED at 2400 nm lies beyond a catalog's stated range: the existing
    warning, from that group's compile (the 850 nm nominal compile has none)."""
    scene = load_scene("paper2005", {"leds.wavelength_nm": [850, 850, 850, 2400]})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        nominal = compile_scene(scene)
    with pytest.warns(UserWarning, match="2400 nm lies outside its catalog's stated range"):
        compile_scene(scene, wavelength_groups(scene)[1], nominal=nominal)


def test_cli_render_of_two_wavelengths(tmp_path):
    out = tmp_path / "r"
    args = ["render", "--scene", "vr-offaxis", "--samples", "4", "--seed", "2", "--out", str(out)]
    for k, v in {**SMALL, **TWO}.items():
        args += ["--set", f"{k}={json.dumps(v)}"]
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    summary = json.loads((out / "summary.json").read_text())
    assert [g["wavelength_nm"] for g in summary["wavelength_groups"]] == [850.0, 940.0]
    truth = json.loads((out / "truth.json").read_text())
    assert [g["wavelength_nm"] for g in truth["glints"]] == [850.0] * 4 + [940.0] * 4
    assert [e["wavelength_nm"] for e in summary["safety"]["per_led"]] == TWO["leds.wavelength_nm"]


def test_emitter_diameter_per_led():
    scene = load_scene("paper2005", {"leds.emitter_diameter_mm": [1.0, 0.5, 1.0, 2.0]})
    assert scene.leds.emitter_diameters_mm() == [1.0, 0.5, 1.0, 2.0]
    assert load_scene("paper2005").leds.emitter_diameters_mm() == [1.0] * 4
    with pytest.raises(SceneError, match="emitter_diameter_mm has 3 entries"):
        apply_overrides(scene, {"leds.emitter_diameter_mm": [1.0, 0.5, 1.0]})
    with pytest.raises(SceneError, match=r"emitter_diameter_mm\[1\] = -0.5"):
        apply_overrides(scene, {"leds.emitter_diameter_mm": [1.0, -0.5, 1.0, 1.0]})
    s = eye_safety(scene)
    # α_k = D_k / d_k at the same distance; L_k ∝ 1 / D_k²
    d = [e["distance_mm"] for e in s["per_led"]]
    assert d == pytest.approx([d[0]] * 4)
    rad = [e["retinal_radiance_w_m2_sr"] for e in s["per_led"]]
    assert rad[1] == pytest.approx(4 * rad[0], rel=1e-12) and rad[3] == pytest.approx(rad[0] / 4)
    assert s["retinal_worst_led"] == 1


def test_info_lists_the_groups_at_their_wavelengths():
    """paper2005 at 850 and 940 nm: glass indices fall with wavelength (normal dispersion), so
    the Double Gauss's EFL grows; each group names its LEDs."""
    res = runner.invoke(app, ["info", "--json", "--set", "leds.wavelength_nm=[850, 940, 850, 940]"])
    assert res.exit_code == 0, res.output
    groups = json.loads(res.stdout)["wavelength_groups"]
    assert [(g["wavelength_nm"], g["leds"]) for g in groups] == [(850.0, [0, 2]), (940.0, [1, 3])]
    a, b = groups
    assert b["effective_focal_length_mm"] > a["effective_focal_length_mm"]
    for name, glass in b["glasses"].items():
        assert glass["index"] < a["glasses"][name]["index"], name
    assert b["eye_indices"][1] < a["eye_indices"][1]  # the cornea disperses too
    assert "wavelength_groups" not in json.loads(runner.invoke(app, ["info", "--json"]).stdout)


def test_interrupted_before_the_last_group_keeps_no_picture(vr_two, monkeypatch):
    """Ctrl-C in the first of two groups: KeyboardInterrupt naming the group, not a picture
    missing the second group's light."""
    import sys

    R = sys.modules["eyelume.render"]  # the module (eyelume.render is also the function)
    real = R.trace_fast

    def stopped(*args, **kwargs):
        est = real(*args, **kwargs)
        est.interrupted = True
        return est

    monkeypatch.setattr(R, "trace_fast", stopped)
    with pytest.raises(KeyboardInterrupt, match="wavelength group 1 of 2"):
        render(vr_two, RenderOptions(estimator="fast", samples_per_pixel=4, seed=1))


@pytest.mark.slow
def test_forward_and_fast_agree_with_three_wavelengths():
    """Both estimators through the wavelength groups: ``glasses-frame``'s six LEDs at 810, 850
    and 940 nm, its lens opened to F/0.6 and binned 8 × 6 (as the six-unlike-LEDs agreement
    test): per-bin z over bins with ≥ 25 forward rays, Σz² inside the central 99.8 % of χ²."""
    from scipy import stats

    scene = apply_overrides(
        load_scene("glasses-frame"),
        {
            "camera.ideal.f_number": 0.6,
            "camera.psf": "none",  # the traced pictures: the χ² takes the bins as independent
            "sensor.cols": 8,
            "sensor.rows": 6,
            "sensor.width_mm": 1.92,
            "sensor.height_mm": 1.44,
            "leds.wavelength_nm": [850.0, 940.0, 810.0, 850.0, 940.0, 850.0],
        },
    )
    cs = compile_scene(scene)
    fwd = render(cs, RenderOptions(rays=10_000_000, seed=11))
    fast = render(cs, RenderOptions(estimator="fast", samples_per_pixel=256, seed=12))
    assert len(fwd.groups) == len(fast.groups) == 3
    assert sum(fwd.ledger.values()) == pytest.approx(cs.emitted_w, rel=1e-9)
    keep = fwd.image_counts >= 25
    n = int(keep.sum())
    assert n > 25
    z = (fast.eye_image - fwd.eye_image)[keep] / np.sqrt(
        (fast.eye_image_variance + fwd.eye_image_variance)[keep]
    )
    chi2 = float((z**2).sum())
    lo, hi = stats.chi2.ppf([0.001, 0.999], n)
    assert lo < chi2 < hi, f"Σz² = {chi2:.0f} over {n} bins, outside [{lo:.0f}, {hi:.0f}]"
