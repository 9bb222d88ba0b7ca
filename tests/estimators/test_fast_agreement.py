"""The fast estimator against the plain forward one on the default scene (issue 3, part 2).

The forward render is the 80 M-ray Figure 6b render the image tests share; the fast render uses
64 samples per pixel. Both are unbiased estimators of the same image, so

* per-bin z-scores z = (fast − forward) / √(var_fast + var_forward), at 3 × 3 binning (29 × 21
  bins, ~70 forward rays in a skin bin) over bins with at least 25 forward rays (where the
  Poisson count is close enough to normal), give Σz² distributed as χ² with one degree of
  freedom per bin: it must lie inside the central 99.8 % interval;
* the mean irradiance of each region — pupil, iris, sclera, skin — and each glint's flux agree
  within 1 % or 3σ, whichever is larger (σ the combined standard error of the two means).

The variances are each estimator's own: Poisson for the forward counts, the spread of
independent sample sets and light paths for the fast one.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

import eyelume
from eyelume.analysis.regions import region_stats

FAST_SAMPLES = 64
MIN_COUNTS = 25


@pytest.fixture(scope="module")
def fast_render(paper_compiled):
    return eyelume.render(
        paper_compiled,
        eyelume.RenderOptions(estimator="fast", samples_per_pixel=FAST_SAMPLES, seed=2005),
    )


def bin3(a: np.ndarray) -> np.ndarray:
    r, c = a.shape[0] // 3 * 3, a.shape[1] // 3 * 3
    return a[:r, :c].reshape(r // 3, 3, c // 3, 3).sum(axis=(1, 3))


@pytest.mark.slow
def test_per_bin_z_scores_are_noise(fig6b_render, fast_render):
    fwd, fast = fig6b_render, fast_render
    counts = bin3(fwd.image_counts)
    keep = counts >= MIN_COUNTS
    diff = bin3(fast.eye_image) - bin3(fwd.eye_image)
    var = bin3(fast.eye_image_variance) + bin3(fwd.eye_image_variance)
    z = diff[keep] / np.sqrt(var[keep])
    n = int(keep.sum())
    assert n > 400  # the test covers the image, not a corner of it
    chi2 = float((z**2).sum())
    lo, hi = stats.chi2.ppf([0.001, 0.999], n)
    assert lo < chi2 < hi, f"Σz² = {chi2:.0f} over {n} bins, outside [{lo:.0f}, {hi:.0f}]"


@pytest.mark.slow
@pytest.mark.parametrize(
    "region", ["pupil", "iris", "sclera", "skin", "glint 0", "glint 1", "glint 2", "glint 3"]
)
def test_region_means_agree(fig6b_render, fast_render, region):
    masks = fast_render.regions
    area = fast_render.pixel_area_mm2
    a = region_stats(fig6b_render.eye_image, fig6b_render.eye_image_variance, masks, area)
    b = region_stats(fast_render.eye_image, fast_render.eye_image_variance, masks, area)
    ra, rb = a[region], b[region]
    assert ra["pixels"] >= 10
    ma, mb = ra["mean_w_mm2"], rb["mean_w_mm2"]
    sigma = math.hypot(ma * ra["mean_rel_error"], mb * rb["mean_rel_error"])
    tol = max(0.01 * ma, 3.0 * sigma)
    assert abs(mb - ma) <= tol, f"{region}: fast {mb:.4e}, forward {ma:.4e} ± {sigma:.1e} W/mm²"
