"""Glints on a bright or uneven surround (issue 11, glasses-frame at its own 640 × 480 chip):

* a well-exposed face whose brightest skin is within ``glint_min_contrast`` of full scale but
  covers under 5 % of the picture: the saturated glints were not looked for at all (neither
  the percentile floor nor the over-exposed floor applied) — "0 of 6 LEDs have a glint" on a
  glasses-frame render with six plainly saturated glints;
* a glint at the limbus, half on the dark iris and half on the bright sclera: one background
  level for the whole surround pulled its centroid 2.5 px toward the sclera.

The pictures are drawn here (10-bit, the same saturated Gaussian glints as
``tests/analysis/test_detect.py``), so the truth is the drawn centre.
"""

from __future__ import annotations

import math

import numpy as np

from eyelume.analysis.tracking import detect, glints
from eyelume.analysis.tracking.detect import DetectParams
from eyelume.analysis.tracking.glints import find_glints

FULL = 1023.0


def _glint(img, at, sigma=1.2, gain=3.0):
    rows, cols = img.shape
    yy, xx = np.mgrid[:rows, :cols]
    img += gain * FULL * np.exp(-((xx - at[0]) ** 2 + (yy - at[1]) ** 2) / (2 * sigma**2))


def _finish(img, noise, seed):
    img = np.minimum(img, FULL) + np.random.default_rng(seed).normal(0.0, noise, img.shape)
    return np.rint(np.clip(img, 0.0, FULL)).astype(np.uint16)


def _bright_face(seed: int) -> tuple[np.ndarray, list[tuple[float, float]]]:
    """640 × 480: skin ramping 600 → 930 DN (its top 2 % within 15 % of full scale), an iris
    disc of 150 DN with a 30 DN pupil, four saturated glints around the pupil."""
    rows, cols = 480, 640
    xx = np.arange(cols, dtype=float)
    img = np.tile(600.0 + 330.0 * (xx / (cols - 1)) ** 8, (rows, 1))
    yy, xg = np.mgrid[:rows, :cols]
    r2 = (xg - 320.3) ** 2 + (yy - 240.6) ** 2
    img[r2 <= 90.0**2] = 150.0
    img[r2 <= 35.0**2] = 30.0
    azimuths = np.radians([0, 90, 180, 270])
    glints = [(320.3 + 20 * math.cos(a), 240.6 - 20 * math.sin(a)) for a in azimuths]
    for g in glints:
        _glint(img, g, sigma=1.6)
    return _finish(img, 6.0, seed), glints


def test_saturated_glints_on_a_bright_face_are_found():
    img, glints = _bright_face(0)
    # The picture is the case: its skin's top is within the contrast of full scale, under 5 %
    # of the picture near the top.
    top = img.max()
    assert np.percentile(img, 99) > top - 0.15 * top
    assert np.mean(img > top - 0.15 * top) < 0.05
    found, _, floor = find_glints(
        img.astype(np.float64), (float(img.min()), float(img.max())), 6.0, DetectParams()
    )
    assert floor is not None
    centres = [b["centre_px"] for b in found]
    for g in glints:
        d = min(math.hypot(c[0] - g[0], c[1] - g[1]) for c in centres)
        assert d < 0.2, (g, centres)


def test_saturated_face_glints_matched_to_their_leds():
    for seed in range(3):
        img, glints = _bright_face(seed)
        d = detect(img, led_azimuths_deg=(0.0, 90.0, 180.0, 270.0))
        assert d.ok, d.failures
        for g in d.glints:
            if g.led is not None:
                assert math.hypot(*np.subtract(g.centre_px, glints[g.led])) < 0.2


def _limbus(seed: int, x0: float = 200.4, y0: float = 120.7):
    """240 × 400: iris 150 DN left of column 200.9, sclera 800 DN right of it, a saturated
    glint centred 0.5 px left of that edge."""
    rows, cols = 240, 400
    img = np.full((rows, cols), 150.0)
    xx = np.arange(cols) + 0.5
    img[:, :] = np.where(xx[None, :] > x0 + 0.5 + 0.5, 800.0, 150.0)
    _glint(img, (x0, y0), sigma=1.6)
    return _finish(img, 6.0, seed), (x0, y0)


def _near(found, at):
    return [b for b in found if math.dist(b["centre_px"], at) < 5]


def test_a_glint_at_the_limbus_is_not_pulled_toward_the_sclera(monkeypatch):
    """With the background interpolated under the spot the centroid is within 0.3 px of the
    drawn centre (noise 6 DN); with one background level for the whole surround (the
    uneven-surround step switched off) it lies > 1 px toward the sclera: the case the change
    is for."""
    params = DetectParams()
    for seed in range(4):
        img, at = _limbus(seed)
        img = img.astype(np.float64)
        found, _, _ = find_glints(img, (img.min(), img.max()), 6.0, params)
        near = _near(found, at)
        assert len(near) == 1, found
        c = near[0]["centre_px"]
        assert math.hypot(c[0] - at[0], c[1] - at[1]) < 0.3, (c, at)
        with monkeypatch.context() as mp:
            mp.setattr(glints, "_UNEVEN_SPREAD", math.inf)
            old, _, _ = find_glints(img, (img.min(), img.max()), 6.0, params)
        assert _near(old, at)[0]["centre_px"][0] - at[0] > 1.0, old


def test_a_glint_on_a_flat_surround_keeps_its_centroid(monkeypatch):
    """The same glint inside the iris (flat surround): the answer is the plain centroid's,
    bit for bit (the uneven-surround step does not apply)."""
    rows, cols = 240, 400
    img = np.full((rows, cols), 150.0)
    _glint(img, (200.4, 120.7), sigma=1.6)
    img = _finish(img, 6.0, 0).astype(np.float64)
    params = DetectParams()
    a, _, _ = find_glints(img, (img.min(), img.max()), 6.0, params)
    monkeypatch.setattr(glints, "_UNEVEN_SPREAD", math.inf)
    b, _, _ = find_glints(img, (img.min(), img.max()), 6.0, params)
    assert len(a) == 1 and [g["centre_px"] for g in a] == [g["centre_px"] for g in b]
