"""Issue 13 (speed): the robust fit's run hypotheses stop once they can no longer matter
(pupil._best_run: a 50 % run holding ≥ 85 % of the outline ends the search; the 30 % runs are
left out when the best holds ≥ 60 %). A quality rule: on constructed lid-cut outlines (an
ellipse of a 640 × 400 headset frame's pupil, its edge points in outline order, those below a
lid replaced by the lid's straight edge, Gaussian noise) the answer must be the full search's
(every run fitted), with fewer fits."""

from __future__ import annotations

import math

import numpy as np
import pytest

import eyelume.analysis.tracking.pupil as pupil
from eyelume.analysis.tracking.detect import DetectParams

A, B, CX, CY = 29.0, 25.0, 320.0, 200.0


def _outline(lid_frac: float, noise: float, seed: int):
    """Edge points ~1 px apart round the ellipse (outline order); the lowest ``lid_frac`` of
    its height cut by a straight lid (the points there moved onto it), noise σ px."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 2 * math.pi, 1.0 / max(A, B))
    x, y = CX + A * np.cos(t), CY + B * np.sin(t)
    lid_y = CY + B - 2 * B * lid_frac
    y = np.minimum(y, lid_y)  # y down: the lid hides the bottom
    return x + rng.normal(0, noise, len(x)), y + rng.normal(0, noise, len(y))


def _run(x, y, monkeypatch, full: bool):
    calls = []
    fit_points = pupil._fit_points

    def counted(pts, diam):
        calls.append(len(pts))
        return fit_points(pts, diam)

    with monkeypatch.context() as m:
        m.setattr(pupil, "_fit_points", counted)
        if full:
            m.setattr(pupil, "_RUN_STOP_SHARE", math.inf)
            m.setattr(pupil, "_RUN_SKIP_SHARE", math.inf)
        e, inl, sigma = pupil._robust_fit(x, y, 2 * math.sqrt(A * B), DetectParams())
    return e, inl, sigma, len(calls)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("lid_frac", [0.15, 0.25, 0.35])
def test_run_stop_gives_the_full_search_answer(monkeypatch, lid_frac, seed):
    x, y = _outline(lid_frac, 0.3, seed)
    e, inl, _, n_fast = _run(x, y, monkeypatch, full=False)
    e_full, inl_full, _, n_full = _run(x, y, monkeypatch, full=True)
    assert e is not None and e_full is not None
    # the whole outline is not one ellipse: the run search ran, every run in the full one
    assert n_full >= 26
    assert n_fast < n_full
    assert (e.cx, e.cy, e.a, e.b, e.theta) == (
        e_full.cx,
        e_full.cy,
        e_full.a,
        e_full.b,
        e_full.theta,
    )
    assert np.array_equal(inl, inl_full)
    # and it is the pupil's ellipse, not the lid's
    assert math.hypot(e.cx - CX, e.cy - CY) < 0.5
