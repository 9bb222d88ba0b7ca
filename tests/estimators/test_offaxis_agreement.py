"""Fast against forward for a camera off the eye's axis (issue: any headset).

The ``glasses-frame`` preset (an ideal lens 40° off the eye's axis) with its lens opened to
F/0.6 and its picture binned 12 × 9, so that plain forward tracing collects enough rays in a
slow test (at F/2.4 it would need 16× more). Both estimators are unbiased estimators of the
same picture: per-bin z = (fast − forward) / √(var_fast + var_forward) over bins with at least
25 forward rays gives Σz² ~ χ² with one degree of freedom per bin, inside its central 99.8 %.
This checks the camera frame, the ideal lens's ray map (forward) against its radiance gain
(camera side) and the aiming for a camera anywhere.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import eyelume
from eyelume.compile import compile_scene
from eyelume.scene.io import apply_overrides, load_scene

MIN_COUNTS = 25


@pytest.mark.slow
def test_fast_and_forward_agree_off_axis():
    scene = apply_overrides(
        load_scene("glasses-frame"),
        {
            "camera.ideal.f_number": 0.6,
            "sensor.cols": 12,
            "sensor.rows": 9,
            "sensor.width_mm": 1.92,  # the chip's field (640 × 480 × 3 µm), binned 12 × 9
            "sensor.height_mm": 1.44,
        },
    )
    cs = compile_scene(scene)
    fwd = eyelume.render(cs, eyelume.RenderOptions(rays=60_000_000, seed=11))
    fast = eyelume.render(
        cs, eyelume.RenderOptions(estimator="fast", samples_per_pixel=256, seed=12)
    )
    keep = fwd.image_counts >= MIN_COUNTS
    n = int(keep.sum())
    assert n > 60  # the eye and the skin around it, not a corner
    z = (fast.eye_image - fwd.eye_image)[keep] / np.sqrt(
        (fast.eye_image_variance + fwd.eye_image_variance)[keep]
    )
    chi2 = float((z**2).sum())
    lo, hi = stats.chi2.ppf([0.001, 0.999], n)
    assert lo < chi2 < hi, f"Σz² = {chi2:.0f} over {n} bins, outside [{lo:.0f}, {hi:.0f}]"
