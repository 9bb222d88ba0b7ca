"""The regions' warning about a mirror element. The region map follows each mirror's stronger
branch (its transmitted view where T ≥ R, the view folded where R > T: 96dbce2; the folded
regions are checked against the truth in tests/test_elements.py::
test_regions_follow_a_mirror_fold), so a mirror is warned about only where its stronger branch
is not the same at every LED wavelength (a hot mirror's cut-off between them), naming R and T."""

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
def test_a_mirror_folding_the_view_at_every_wavelength_is_not_warned_about(r, t):
    """The regions follow the fold (R > T at the one LED wavelength): nothing to warn about,
    and the folded view's pupil is found (the camera sees the eye only through the mirror)."""
    fold = _partial(r, t) | {"position_mm": [0.0, 0.0, 33.0], "direction": [0.0, -1.0, -1.0]}
    fold["semi_diameter_mm"] = 12.0
    scene = eyelume.load_scene("vr-offaxis", FOLDED | {"elements": [fold]})
    with warnings.catch_warnings():
        warnings.simplefilter("error", RegionWarning)
        masks = region_masks(compile_scene(scene), reflections=False)
    assert masks["pupil"].sum() > 0


def test_a_hot_mirror_is_judged_at_the_leds_wavelengths():
    """Transmitting at 850 nm but reflecting above a 900 nm cut-off: an LED at 940 nm sees the
    folded view."""
    hot = _partial(0.95, 0.02, cutoff_nm=900.0, reflectance_below=0.02, transmittance_below=0.97)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RegionWarning)
        _masks(hot)
    with pytest.warns(RegionWarning, match=r"R = 0.95, T = 0.02"):
        _masks(hot, **{"leds.wavelength_nm": [850, 940, 850, 940]})
