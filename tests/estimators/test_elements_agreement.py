"""The fast estimator against the plain forward one with optical elements in the scene (issue
14, "both estimators handle them"), on vr-offaxis (8 LEDs, an ideal lens 50° off the eye's
axis) with

* (a) a thin N-BK7 plate in front of the eye, between it and the LEDs (every LED's light to
  the eye crosses it, and the camera looks through it);
* (b) a 45° plane mirror folding the camera's view onto the eye (the camera below the eye,
  looking up);
* (c) a −3 D spectacle lens 12 mm from the cornea, 8° pantoscopic tilt (N-BK7 standing in for
  CR-39, as tests/test_ghosts.py; the LEDs' light to the eye and the camera's view cross it).

As tests/estimators/test_offaxis_agreement.py: the lens opened (F/0.6, EFL 5 mm so the
forward rays collect enough in a slow test) and its picture binned coarsely, the traced
pictures compared (``camera.psf = "none"``). Both are unbiased estimators of the same picture:
per-bin z = (fast − forward) / √(var_fast + var_forward) over bins with at least 25 forward
rays gives Σz² ~ χ² with one degree of freedom per bin, inside its central 99.8 %. This checks
the camera paths through and off the elements, next-event estimation through them (Newton's
method), the light paths' element legs and their balance-heuristic weights (glints seen through
the plate and the lens, the spectacle's ghosts). The light paths are many
(``run.light_paths_per_pixel`` 2000): a ghost the element legs draw rarely would otherwise be
missed by a run's few thousand paths and its variance with it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

import eyelume
from eyelume.compile import compile_scene
from eyelume.scene.io import apply_overrides, load_scene

MIN_COUNTS = 25
PANTO = math.radians(8.0)
N_SPEC = 0.51  # N-BK7 at 850 nm, rounded: the radii for -3 D, (n - 1)(1/R1 - 1/R2)

PLATE = {
    "kind": "plate",
    "name": "window",
    "position_mm": [0.0, 0.0, 8.0],
    "thickness_mm": 2.0,
    "glass": "N-BK7",
    "semi_diameter_mm": 16.0,
}
FOLD = {
    "kind": "mirror",
    "name": "fold",
    "position_mm": [0.0, 0.0, 33.0],
    "direction": [0.0, -1.0, -1.0],
    "semi_diameter_mm": 12.0,
}
FOLDED = {
    "camera.position_mm": [0.0, -30.0, 33.0],
    "camera.look_at_mm": [0.0, 0.0, 33.0],
    "camera.ideal.focus_distance_mm": 63.0,
}
SPECTACLE = {
    "kind": "lens",
    "name": "spectacle",
    "position_mm": [0.0, 0.0, 14.0],
    "direction": [0.0, math.sin(PANTO), -math.cos(PANTO)],
    "thickness_mm": 2.0,
    "glass": "N-BK7",
    "semi_diameter_mm": 20.0,
    "front": {"radius_mm": N_SPEC / 4.0 * 1000.0},
    "back": {"radius_mm": N_SPEC / 7.0 * 1000.0},
}

#: case: (scene overrides, forward rays, how many bins must collect 25 forward rays)
CASES = {
    "plate": ({"elements": [PLATE]}, 20e6, 40),
    "fold-mirror": ({"elements": [FOLD], **FOLDED}, 20e6, 40),
    "spectacle": ({"elements": [SPECTACLE]}, 20e6, 40),
}


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore::eyelume.analysis.regions.RegionWarning")
@pytest.mark.parametrize("case", sorted(CASES))
def test_fast_and_forward_agree_with_elements(case):
    extra, rays, min_bins = CASES[case]
    scene = apply_overrides(
        load_scene("vr-offaxis"),
        {
            "camera.ideal.f_number": 0.6,
            "camera.ideal.efl_mm": 5.0,
            "camera.body.diameter_mm": 12.0,
            "camera.psf": "none",  # the traced pictures: independent bins
            "sensor.cols": 8,
            "sensor.rows": 8,
            "sensor.width_mm": 3.6,
            "sensor.height_mm": 3.6,
            "run.light_paths_per_pixel": 2000.0,
            **extra,
        },
    )
    cs = compile_scene(scene)
    fwd = eyelume.render(cs, eyelume.RenderOptions(estimator="forward", rays=int(rays), seed=11))
    fast = eyelume.render(
        cs, eyelume.RenderOptions(estimator="fast", samples_per_pixel=64, seed=12)
    )
    keep = fwd.image_counts >= MIN_COUNTS
    n = int(keep.sum())
    assert n >= min_bins  # the test covers the picture, not a corner of it
    z = (fast.eye_image - fwd.eye_image)[keep] / np.sqrt(
        (fast.eye_image_variance + fwd.eye_image_variance)[keep]
    )
    chi2 = float((z**2).sum())
    lo, hi = stats.chi2.ppf([0.001, 0.999], n)
    assert lo < chi2 < hi, f"{case}: Σz² = {chi2:.1f} over {n} bins, outside [{lo:.1f}, {hi:.1f}]"
    # the forward ledger stays exact with the elements in it
    assert sum(fwd.ledger.values()) == pytest.approx(fwd.emitted_w, rel=1e-9)
