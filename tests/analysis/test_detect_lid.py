"""Issue 13: an eyelid's edge fitted as the pupil's (detect._straight_arc) — on constructed edge
points: a circle of radius 7 px (paper2005's pupil at 87 × 65) whose lower part is cut by a
straight lid, the cut's points all within the robust fit's inlier tolerance."""

from __future__ import annotations

import math

import numpy as np

from eyelume.analysis.tracking.detect import DetectParams, _straight_arc
from eyelume.analysis.tracking.pupil import PupilFit, _fit, support_of

R, CX, CY = 7.0, 50.0, 40.0


def _fit_of(x, y, noise) -> PupilFit:
    e = _fit(x, y, 2 * R)
    support, gap = support_of(e, x, y)
    return PupilFit(e, support=support, gap=gap, inliers=(x, y), edge_noise_px=noise)


def _cut(lid_y: float, noise: float, seed: int = 0):
    """Edge points 1 px apart round the circle, those below ``lid_y`` replaced by the lid's
    straight edge between the circle's crossings, with Gaussian noise σ = ``noise`` px."""
    rng = np.random.default_rng(seed)
    t = np.arange(0, 2 * math.pi, 1 / R)
    x, y = CX + R * np.cos(t), CY + R * np.sin(t)
    keep = y <= lid_y
    half = math.sqrt(max(R * R - (lid_y - CY) ** 2, 0.0))
    lx = np.arange(CX - half + 0.5, CX + half, 1.0)
    x = np.concatenate((x[keep], lx))
    y = np.concatenate((y[keep], np.full(len(lx), lid_y)))
    return x + rng.normal(0, noise, len(x)), y + rng.normal(0, noise, len(y))


def test_lid_edge_found_and_left_out():
    # the lid 4 px below the centre hides the lowest 22 % of the edge (its sagitta 3 px)
    x, y = _cut(CY + 4.0, 0.2)
    fit = _fit_of(x, y, 0.2)
    assert math.hypot(fit.ellipse.cx - CX, fit.ellipse.cy - CY) > 0.5  # pulled by the lid
    got = _straight_arc(fit, DetectParams())
    assert got is not None
    new, note = got
    assert note.startswith("warning: ") and "straight arc" in note
    assert math.hypot(new.ellipse.cx - CX, new.ellipse.cy - CY) < 0.3
    assert new.support < fit.support and len(new.inliers[0]) < len(x)


def test_lid_cut_too_deep_refused():
    # the lid 1 px below the centre: without its edge less than 45 % of the outline is backed
    x, y = _cut(CY + 1.0, 0.2)
    got = _straight_arc(_fit_of(x, y, 0.2), DetectParams())
    assert got is not None and got[1].startswith("pupil cut by an eyelid"), got


def test_whole_noisy_pupil_has_no_lid():
    """A whole circle with edge noise up to 0.46 px (the 4-sample render's): no arc of a
    quarter of it is straight to within the noise and straighter than the ellipse, over 200
    noise draws (without the noise bound 58 of them had one)."""
    for seed in range(200):
        x, y = _cut(CY + R + 1.0, 0.46, seed)
        assert _straight_arc(_fit_of(x, y, 0.46), DetectParams()) is None, seed
