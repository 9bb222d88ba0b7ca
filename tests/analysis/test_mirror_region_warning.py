"""The regions' warning about a mirror element (a fresh user's finding): it fired for a partial
mirror that transmits more than it reflects (R < T), whose transmitted view (the one the
region map follows) is the view the camera mostly sees. It fires where the mirror reflects
more than it transmits (the compile then follows the camera's line of sight folded), naming
R and T."""

from __future__ import annotations

import warnings

import pytest

import eyelume
from eyelume.analysis.regions import RegionWarning, region_masks
from eyelume.compile import compile_scene


def _partial(r: float, t: float, **coating) -> dict:
    return {
        "kind": "mirror",
        "name": "splitter",
        "position_mm": [0.0, 0.0, 20.0],
        "semi_diameter_mm": 18.0,
        "front": {"coating": {"model": "fixed", "reflectance": r, "transmittance": t, **coating}},
    }


def _masks(element: dict, **overrides):
    scene = eyelume.load_scene("paper2005", {"elements": [element], **overrides})
    return region_masks(compile_scene(scene))


@pytest.mark.parametrize(("r", "t"), [(0.3, 0.7), (0.5, 0.5)])
def test_a_mirror_transmitting_at_least_as_much_as_it_reflects_is_not_warned_about(r, t):
    with warnings.catch_warnings():
        warnings.simplefilter("error", RegionWarning)
        _masks(_partial(r, t))


#: vr-offaxis with the camera below, looking up at a 45 deg fold mirror (tests/test_elements.py)
FOLDED = {
    "camera.position_mm": [0.0, -30.0, 33.0],
    "camera.look_at_mm": [0.0, 0.0, 33.0],
    "camera.ideal.focus_distance_mm": 63.0,
}


@pytest.mark.parametrize(("r", "t"), [(0.9, 0.05), (1.0, 0.0)])
def test_a_mirror_folding_the_view_is_warned_about_naming_r_and_t(r, t):
    fold = _partial(r, t) | {"position_mm": [0.0, 0.0, 33.0], "direction": [0.0, -1.0, -1.0]}
    fold["semi_diameter_mm"] = 12.0
    scene = eyelume.load_scene("vr-offaxis", FOLDED | {"elements": [fold]})
    with pytest.warns(RegionWarning, match=rf"elements.0 is a mirror \(R = {r:g}, T = {t:g}\)"):
        region_masks(compile_scene(scene))


def test_a_hot_mirror_is_judged_at_the_leds_wavelengths():
    """Transmitting at 850 nm but reflecting above a 900 nm cut-off: an LED at 940 nm sees the
    folded view."""
    hot = _partial(0.95, 0.02, cutoff_nm=900.0, reflectance_below=0.02, transmittance_below=0.97)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RegionWarning)
        _masks(hot)
    with pytest.warns(RegionWarning, match=r"R = 0.95, T = 0.02"):
        _masks(hot, **{"leds.wavelength_nm": [850, 940, 850, 940]})
