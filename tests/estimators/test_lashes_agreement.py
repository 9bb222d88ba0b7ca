"""The fast estimator against the plain forward one with eyelashes (``face.lashes``): both
trace the fringe through the same surface table (``kernels/geometry.py`` ``SHAPE_LASHES``), so
lashes shadow the LEDs' light on the lid, the eye and the glints in both, and reflect their
own light. Set-up of tests/estimators/test_toric_agreement.py (vr-offaxis, whose camera looks
up at the upper lid from below; the lens opened so the forward rays collect enough; the traced
pictures, ``camera.psf = "none"``); the lashes made coarse and pale (60 lashes 0.3 mm wide
reflecting 30 %: at the root they cover ~70 % of the margin) so that they shape the picture.
Per-bin z = (fast − forward) / √(var_fast + var_forward) over bins with ≥ 25 forward rays:
Σz² ~ χ² with one degree of freedom per bin, inside its central 99.8 %.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import eyelume
from eyelume.compile import compile_scene
from eyelume.scene.io import apply_overrides, load_scene

MIN_COUNTS = 25

SETUP = {
    "camera.ideal.f_number": 0.6,
    "camera.ideal.efl_mm": 5.0,
    "camera.body.diameter_mm": 12.0,
    "camera.psf": "none",
    "sensor.cols": 12,
    "sensor.rows": 12,
    "sensor.width_mm": 3.6,
    "sensor.height_mm": 3.6,
}
LASHES = {
    "face.lashes.enabled": True,
    "face.lashes.count": 60,
    "face.lashes.width_mm": 0.3,
    "face.lashes.reflectance": 0.3,
}


@pytest.mark.slow
def test_fast_and_forward_agree_with_eyelashes():
    scene = apply_overrides(load_scene("vr-offaxis"), {**SETUP, **LASHES})
    cs = compile_scene(scene)
    fwd = eyelume.render(cs, eyelume.RenderOptions(estimator="forward", rays=20_000_000, seed=21))
    fast = eyelume.render(
        cs, eyelume.RenderOptions(estimator="fast", samples_per_pixel=64, seed=22)
    )
    # the lashes are in the picture: they absorb a share of the LEDs' power in the forward ledger
    assert fwd.ledger["eyelashes"] > 0.01 * fwd.emitted_w
    keep = fwd.image_counts >= MIN_COUNTS
    n = int(keep.sum())
    assert n >= 60
    z = (fast.eye_image - fwd.eye_image)[keep] / np.sqrt(
        (fast.eye_image_variance + fwd.eye_image_variance)[keep]
    )
    chi2 = float((z**2).sum())
    lo, hi = stats.chi2.ppf([0.001, 0.999], n)
    assert lo < chi2 < hi, f"Σz² = {chi2:.1f} over {n} bins, outside [{lo:.1f}, {hi:.1f}]"
    assert sum(fwd.ledger.values()) == pytest.approx(fwd.emitted_w, rel=1e-9)
