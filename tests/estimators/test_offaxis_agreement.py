"""Fast against forward for a camera off the eye's axis (issue: any headset), on every
off-axis preset.

Each preset (``glasses-frame``, ``vr-offaxis``, ``eyetrackvr``: ideal lenses 40–50° off the
eye's axis) with its lens opened to F/0.6 and its picture binned 6 × 6 to 12 × 9, so that
plain forward tracing collects enough rays in a slow test (at F/2–2.9 it would need 11–23×
more). Both estimators are unbiased estimators of the
same picture: per-bin z = (fast − forward) / √(var_fast + var_forward) over bins with at least
25 forward rays gives Σz² ~ χ² with one degree of freedom per bin, inside its central 99.8 %.
This checks the camera frame, the ideal lens's ray map (forward) against its radiance gain
(camera side) and the aiming for a camera anywhere. The traced pictures are compared
(``camera.psf = "none"``): the diffraction PSF is one linear map applied alike to both
(tests/detectors/test_psf.py) and would correlate neighbouring bins, which the per-bin χ² takes
as independent.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import eyelume
from eyelume.compile import compile_scene
from eyelume.scene.io import apply_overrides, load_scene

MIN_COUNTS = 25


#: Each off-axis preset with its lens opened to F/0.6 and its chip's field (pitch × cols × rows,
#: given as width and height) binned coarsely; the forward rays; and how many bins must collect
#: 25 forward rays (the lit eye and skin: eyetrackvr's 130° lens sees mostly unlit face).
PRESETS = {
    "glasses-frame": ({"sensor.width_mm": 1.92, "sensor.height_mm": 1.44}, (12, 9), 60e6, 60),
    "vr-offaxis": ({"sensor.width_mm": 1.2, "sensor.height_mm": 1.2}, (6, 6), 30e6, 30),
    "eyetrackvr": ({"sensor.width_mm": 2.64, "sensor.height_mm": 2.64}, (10, 10), 60e6, 20),
}


@pytest.mark.slow
@pytest.mark.parametrize("preset", sorted(PRESETS))
def test_fast_and_forward_agree_off_axis(preset):
    field, (cols, rows), rays, min_bins = PRESETS[preset]
    scene = apply_overrides(
        load_scene(preset),
        {
            "camera.ideal.f_number": 0.6,
            "camera.psf": "none",  # the traced pictures: independent bins (module docstring)
            "sensor.cols": cols,
            "sensor.rows": rows,
            **field,
        },
    )
    cs = compile_scene(scene)
    fwd = eyelume.render(cs, eyelume.RenderOptions(rays=int(rays), seed=11))
    fast = eyelume.render(
        cs, eyelume.RenderOptions(estimator="fast", samples_per_pixel=256, seed=12)
    )
    keep = fwd.image_counts >= MIN_COUNTS
    n = int(keep.sum())
    assert n >= min_bins, f"{n} bins with {MIN_COUNTS} forward rays"
    z = (fast.eye_image - fwd.eye_image)[keep] / np.sqrt(
        (fast.eye_image_variance + fwd.eye_image_variance)[keep]
    )
    chi2 = float((z**2).sum())
    lo, hi = stats.chi2.ppf([0.001, 0.999], n)
    assert lo < chi2 < hi, f"Σz² = {chi2:.0f} over {n} bins, outside [{lo:.0f}, {hi:.0f}]"
