"""The eyeglasses presets (issue 14): ``vr-offaxis-glasses`` (a −3 D CR-39 spectacle lens,
uncoated) and ``vr-offaxis-glasses-ar`` (the same with a visible AR coating), against
closed forms written here:

* the lens's back vertex power from its radii, thickness and CR-39's n_d (the ophthalmic
  convention): P₁/(1 − t P₁/n) + P₂ = −3.00 D;
* its placement: the back vertex 12 mm in front of the corneal vertex, the axis tilted 8°
  (pantoscopic);
* the AR coating's assumed 850 nm reflectance against a quarter-wave MgF₂ layer designed at
  550 nm on CR-39 (the thin-film closed form r = (r₁ + r₂ e^{−2iδ})/(1 + r₁r₂ e^{−2iδ}));
* the truth lists every LED's glint and the spectacle's ghosts: uncoated, R at the ghost's
  surface is Fresnel's at n(850 nm) (between normal incidence's 3.9 % and grazing), coated
  exactly 2.2 %; the coating moves no ghost.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import eyelume
from eyelume.analysis.truth import eye_truth
from eyelume.compile import compile_scene
from eyelume.scene.glass import load_catalog

NAMES = ("vr-offaxis-glasses", "vr-offaxis-glasses-ar")


def test_spectacle_lens_is_minus_three_dioptres_at_12_mm_tilted_8_degrees():
    sc = eyelume.load_scene("vr-offaxis-glasses")
    (el,) = sc.elements
    nd = load_catalog()["CR-39"].index(587.5618)
    assert nd == pytest.approx(1.498, abs=1e-9)
    p1 = (nd - 1) / (el.front.radius_mm / 1000)
    p2 = (1 - nd) / (el.back.radius_mm / 1000)
    t = el.thickness_mm / 1000
    assert p1 / (1 - t * p1 / nd) + p2 == pytest.approx(-3.0, abs=0.005)
    axis = np.array(el.direction) / np.linalg.norm(el.direction)
    back = np.array(el.position_mm) + el.thickness_mm * axis
    assert back == pytest.approx([0.0, 0.0, 12.0], abs=0.05)
    assert math.degrees(math.atan2(axis[1], -axis[2])) == pytest.approx(8.0, abs=0.01)


def test_ar_coating_reflectance_against_a_quarter_wave_mgf2_layer():
    sc = eyelume.load_scene("vr-offaxis-glasses-ar")
    coat = sc.elements[0].front.coating
    assert sc.elements[0].back.coating == coat
    n_s = load_catalog()["CR-39"].index(850.0)
    n1, design = 1.38, 550.0  # MgF2, quarter-wave at 550 nm
    delta = 2 * math.pi * n1 * (design / (4 * n1)) / 850.0
    r1, r2 = (1 - n1) / (1 + n1), (n1 - n_s) / (n1 + n_s)
    e = np.exp(-2j * delta)
    r = abs((r1 + r2 * e) / (1 + r1 * r2 * e)) ** 2
    assert coat.reflectance == pytest.approx(r, abs=0.001)
    assert coat.reflectance + coat.transmittance == pytest.approx(1.0)
    assert coat.reflectance < ((n_s - 1) / (n_s + 1)) ** 2  # below uncoated


@pytest.fixture(scope="module")
def truths():
    return {name: eye_truth(compile_scene(eyelume.load_scene(name))) for name in NAMES}


def test_truth_lists_glints_and_ghosts(truths):
    n = load_catalog()["CR-39"].index(850.0)
    r0 = ((n - 1) / (n + 1)) ** 2
    plain, ar = truths["vr-offaxis-glasses"], truths["vr-offaxis-glasses-ar"]
    for t in (plain, ar):
        assert t["glints_visible"] == 8
        assert t["ghosts_visible"] >= 1
        for g in t["ghosts"]:
            assert g["chain"][-1].startswith("spectacle ") or g["chain"][0].startswith("spectacle ")
            assert g["nearest_glint_px"] > 0
    for g in plain["ghosts"]:
        surface = [r for c, r in zip(g["chain"], g["reflectances"], strict=True) if c != "cornea"]
        assert r0 - 1e-9 <= surface[0] < 0.1, g
    for g in ar["ghosts"]:
        surface = [r for c, r in zip(g["chain"], g["reflectances"], strict=True) if c != "cornea"]
        assert surface[0] == pytest.approx(0.022, abs=1e-12)
    a = np.array([g["centre_px"] for g in plain["ghosts"]])
    b = np.array([g["centre_px"] for g in ar["ghosts"]])
    assert a.shape == b.shape and np.allclose(a, b, atol=1e-6)
