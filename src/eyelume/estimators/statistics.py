"""Statistics of Monte Carlo estimates: the relative standard error of a typical pixel.

Used by the fast estimator to stop at a target error (:mod:`.fast_run`) and by the region
statistics of a rendered image (:mod:`eyelume.analysis.regions`).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["median_pixel_rel_error"]


def median_pixel_rel_error(
    values: np.ndarray, variance: np.ndarray, dof: int | None = None
) -> float:
    """The relative standard error of a region's median pixel: √(median of variance/value²),
    corrected for the spread of the variance estimates.

    Each pixel's variance is estimated from independent sets; with ``dof`` degrees of freedom
    it is distributed as σ² χ²_dof / dof, whose median is below σ² (by 0.455 for one degree of
    freedom), so the median over many similar pixels is divided by median(χ²_dof)/dof. With
    ``dof`` None the estimates are taken as exact (many samples per pixel, or Poisson counts).
    A pixel with no signal (value ≤ 0) counts as an infinite relative error.

    >>> median_pixel_rel_error(np.array([1.0, 2.0, 4.0]), np.array([0.01, 0.04, 0.16]))
    0.1
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        rel_var = np.where(values > 0, variance / values**2, np.inf)
    med = float(np.median(rel_var))
    if dof is not None and math.isfinite(med):
        from scipy.stats import chi2

        med /= float(chi2.ppf(0.5, dof)) / dof
    return math.sqrt(med)
