"""Glints beside a sunlit lid cut by lashes (eyelume's own vr-offaxis renders at 850 nm with
the sun 40° up, session 20): the gaps between dark lashes on the saturated lid skin pass the
local glint tests — saturated, and their box mean holds the lashes — and were taken for
glints, while the true glints (a few saturated pixels on the dark iris, dimmed under the
99th-percentile floor by step 2's smoothing) were not even looked for.

:func:`eye` draws a 400 × 400 10-bit picture: skin at 500 DN, a dark iris disc (radius 90) at 80 DN,
a pupil (radius 25) at 12 DN, four glints — Gaussian spots of σ 0.7 px, 3000 DN peak,
clipped at 1016: 2-4 saturated pixels — 20 px right, up, left and down of the pupil's centre
(LEDs at 0°, 90°, 180°, 270°), and, 60-85 px above the pupil, a lid band at 1016 DN (saturated)
cut into strips by dark lashes (300 DN, 2 px wide every 5 px, slanted). Noise σ 3 DN.
"""

from __future__ import annotations

import numpy as np
import pytest

from eyelume.analysis.tracking.detect import detect
from eyelume.analysis.tracking.glints import in_bright_run

LEDS = (0, 90, 180, 270)
CENTRE = (200.4, 230.6)
OFFSETS = ((20.0, 0.0), (0.0, -20.0), (-20.0, 0.0), (0.0, 20.0))
TOP = 1016.0


def eye(seed: int = 0, lashes: bool = True) -> np.ndarray:
    """The picture of the module doc (uint16); ``lashes`` False: no lid band."""
    rng = np.random.default_rng(seed)
    n = 400
    yy, xx = np.mgrid[0:n, 0:n].astype(float)
    cx, cy = CENTRE
    r = np.hypot(xx - cx, yy - cy)
    img = np.full((n, n), 500.0)
    img[r < 90] = 80.0
    a = np.clip(25.0 + 0.5 - r, 0, 1)
    img = img * (1 - a) + 12.0 * a
    if lashes:
        band = (yy > cy - 85) & (yy < cy - 60) & (np.abs(xx - cx) < 90)
        img[band] = TOP
        lash = band & (((xx + 0.6 * yy) % 5.0) < 2.0)
        img[lash] = 300.0
    for dx, dy in OFFSETS:
        img += 3000.0 * np.exp(-((xx - cx - dx) ** 2 + (yy - cy - dy) ** 2) / (2 * 0.7**2))
    img += rng.normal(0.0, 3.0, img.shape)
    return np.clip(np.round(img), 0, TOP).astype(np.uint16)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_lash_gaps_are_not_glints(seed: int) -> None:
    """The four true glints matched within 0.5 px (their centroids on these pictures are
    ≤ 0.2 px off; a lash gap taken for one lies ≥ 40 px away), none of the lid's strips."""
    d = detect(eye(seed), led_azimuths_deg=LEDS)
    assert d.ok, d.failures
    found = {g.led: g.centre_px for g in d.glints if g.led is not None}
    assert sorted(found) == [0, 1, 2, 3], d.glints
    for k, (dx, dy) in enumerate(OFFSETS):
        x, y = found[k]
        assert np.hypot(x - CENTRE[0] - dx, y - CENTRE[1] - dy) < 0.5, (k, found[k])
    assert all(g.centre_px[1] > CENTRE[1] - 55 for g in d.glints), d.glints


def test_in_bright_run_tells_a_spot_from_a_lid_strip() -> None:
    """A glint's core stops within its skirt; a saturated strip between lashes runs on."""
    img = eye(0).astype(np.float64)
    cx, cy = CENTRE
    glint = {"centre_px": (cx + 20.0, cy), "area_px": 3.0, "peak": TOP, "base": 80.0}
    assert not in_bright_run(img, glint, 0.75, 24.0)
    # a saturated pixel inside the band, between two lashes
    ys, xs = np.nonzero(img[: int(cy - 62), :] >= TOP)
    i = int(np.argmin(np.hypot(xs - cx, ys - (cy - 72))))
    strip = {"centre_px": (float(xs[i]), float(ys[i])), "area_px": 3.0, "peak": TOP, "base": 550.0}
    assert in_bright_run(img, strip, 0.75, 24.0)


def test_same_glints_without_the_lid() -> None:
    """The control: the same eye without the lid band gives the same four glints."""
    d = detect(eye(0, lashes=False), led_azimuths_deg=LEDS)
    assert d.ok, d.failures
    assert sorted(g.led for g in d.glints if g.led is not None) == [0, 1, 2, 3]
