"""Glint finding on pictures a new user made (session 21 defects), on pictures made here.

:func:`eye` draws a 480 × 360 eye as the user did: skin 160, an eye opening of sclera 190, an
iris disc (radius 70) at 100, a pupil (radius 22, anti-aliased edge) at 20, four glints —
Gaussian spots of σ 1.4 px and 400 DN peak, saturated — 30 px right, up, left and down of the
pupil's centre (LEDs at 0°, 90°, 180°, 270°), Gaussian noise σ 3, clipped to 8 bits.

A matched glint must lie within 1 px of its truth (the issue's bound for ``ok``).
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from eyelume.analysis.tracking.detect import detect

LEDS = (0, 90, 180, 270)
CENTRE = (200.6, 150.2)
OFFSETS = ((30.0, 0.0), (0.0, -30.0), (-30.0, 0.0), (0.0, 30.0))  # LED k's glint from the pupil


def eye(seed: int = 0, shift: float = 0.0) -> np.ndarray:
    """The picture of the module doc (float, before clipping to 8 bits), the pupil and glints
    moved ``shift`` px along x and y."""
    rng = np.random.default_rng(seed)
    rows, cols = 360, 480
    yy, xx = np.mgrid[0:rows, 0:cols].astype(float)
    cx, cy = CENTRE[0] + shift, CENTRE[1] + shift
    img = np.full((rows, cols), 160.0)
    opening = ((xx - cx) / 168) ** 2 + ((yy - cy) / 91) ** 2 < 1
    img[opening] = 190.0
    r = np.hypot(xx - cx, yy - cy)
    img[(r < 70) & opening] = 100.0
    a = np.clip(22.0 + 0.5 - r, 0, 1)
    img = img * (1 - a) + 20.0 * a
    for dx, dy in OFFSETS:
        img += 400.0 * np.exp(-((xx - cx - dx) ** 2 + (yy - cy - dy) ** 2) / (2 * 1.4**2))
    img += rng.normal(0.0, 3.0, img.shape)
    return np.clip(img, 0, 255)


def _errors(d, shift: float = 0.0) -> dict[int, float]:
    found = {g.led: g.centre_px for g in d.glints if g.led is not None}
    out = {}
    for k, (x, y) in found.items():
        dx, dy = OFFSETS[k]
        out[k] = math.hypot(x - CENTRE[0] - shift - dx, y - CENTRE[1] - shift - dy)
    return out


@pytest.mark.parametrize(("sigma", "seed"), [(3.0, 0), (3.0, 1), (4.0, 2), (2.5, 3)])
def test_defocused_glints_found_within_a_pixel(sigma, seed):
    """A picture blurred by a Gaussian of σ 2.5-4 px (defocus): the saturated glints become
    broad bumps ~50 DN over the iris, under the picture's 99th percentile and wider than the
    top-hat's disc; all four were lost ("glint lost: 0 of 4", defect 1 of session 21). They
    are found with wider discs and centred by a fit, within 1 px."""
    shift = 0.37 * seed
    img = cv2.GaussianBlur(eye(seed, shift), (0, 0), sigma)
    d = detect(np.round(img).astype(np.uint8), led_azimuths_deg=LEDS)
    assert d.ok, d.failures
    err = _errors(d, shift)
    assert sorted(err) == [0, 1, 2, 3], d.glints
    assert max(err.values()) < 1.0, err


def test_glints_beside_a_stripe_of_missing_pixels_are_kept():
    """A column of missing pixels (NaN) 6 px from two glints, 3 px across each: their spots are
    whole, but the square around each, where the background is read, held a missing pixel, and
    both were dropped (2 of 4, defect 2 of session 21). They are kept, centred within 1 px, with
    a warning that names the missing pixels."""
    img = eye(4).astype(np.float32)
    img[:, 190:195] = np.nan
    d = detect(img, led_azimuths_deg=LEDS)
    assert d.ok, d.failures
    err = _errors(d)
    assert sorted(err) == [0, 1, 2, 3], d.glints
    assert max(err.values()) < 1.0, err
    kept = [m for m in d.failures if "missing pixel" in m and "kept" in m]
    assert kept, d.failures


def test_glint_cut_by_missing_pixels_is_dropped_with_a_warning():
    """A block of missing pixels over half of LED 2's glint: its visible part's centroid is off
    the glint; it is dropped, and the warning says missing pixels cut its spot. The three
    whole glints are matched."""
    img = eye(5).astype(np.float32)
    img[140:160, 170:185] = np.nan
    d = detect(img, led_azimuths_deg=LEDS)
    assert d.ok, d.failures
    err = _errors(d)
    assert sorted(err) == [0, 1, 3], d.glints
    assert max(err.values()) < 1.0, err
    assert d.missing_leds == [2]
    assert any("dropped" in m and "missing pixel" in m for m in d.failures), d.failures


def _lit_lid(seed: int, level: float) -> np.ndarray:
    """A 480 × 360 eye as :func:`eye` but with a 30 px pupil, its glints 40 px out, and a lit
    highlight — a disc of radius 14 px at ``level`` DN, ~60 over the sclera at 190 — 95 px
    right of the pupil: as bright per pixel as the glints, with ten times their light."""
    rng = np.random.default_rng(seed)
    rows, cols = 360, 480
    yy, xx = np.mgrid[0:rows, 0:cols].astype(float)
    cx, cy = CENTRE
    img = np.full((rows, cols), 160.0)
    opening = ((xx - cx) / 168) ** 2 + ((yy - cy) / 91) ** 2 < 1
    img[opening] = 190.0
    r = np.hypot(xx - cx, yy - cy)
    img[(r < 70) & opening] = 100.0
    a = np.clip(30.5 - r, 0, 1)
    img = img * (1 - a) + 20.0 * a
    h = np.clip(14.5 - np.hypot(xx - cx - 95, yy - cy), 0, 1)
    img = img * (1 - h) + level * h
    for dx, dy in OFFSETS:
        img += 400.0 * np.exp(-((xx - cx - 4 * dx / 3) ** 2 + (yy - cy - 4 * dy / 3) ** 2) / 3.92)
    img += rng.normal(0.0, 3.0, img.shape)
    return np.clip(img, 0, 255).astype(np.uint8)


@pytest.mark.parametrize(("seed", "level"), [(0, 250.0), (1, 252.0), (1, 250.0)])
def test_a_broad_highlight_does_not_make_the_glints_specks(seed, level):
    """A broad highlight as bright per pixel as the glints (a lit lid) but rising only ~60 DN
    over its surround, against the glints' ~235: taken as the brightest glint, its light made
    the four real glints specks ("glint lost: 0 of 4"; glasses-frame's eye_image.png at gaze
    (10°, −5°): 0 of 6). The glints are matched within 1 px."""
    d = detect(_lit_lid(seed, level), led_azimuths_deg=LEDS)
    assert d.ok, d.failures
    found = {g.led: g.centre_px for g in d.glints if g.led is not None}
    assert sorted(found) == [0, 1, 2, 3], d.glints
    for k, (x, y) in found.items():
        dx, dy = OFFSETS[k]
        err = math.hypot(x - CENTRE[0] - 4 * dx / 3, y - CENTRE[1] - 4 * dy / 3)
        assert err < 1.0, (k, found[k], err)


def _faint(seed: int) -> np.ndarray:
    """A 640 × 400 eye (session 19's user's: skin 170, sclera 200, iris radius 85 at 110, pupil
    radius 30 at 20 centred at (320.3, 200.7)) with four unsaturated glints — Gaussian spots of
    σ 1.5 px and 30 DN, 10 σ of the noise — 25 px right, up, left and down of the pupil's
    centre, inside it 5 px from its edge."""
    rng = np.random.default_rng(seed)
    rows, cols = 400, 640
    yy, xx = np.mgrid[0:rows, 0:cols].astype(float)
    cx, cy = 320.3, 200.7
    img = np.full((rows, cols), 170.0)
    opening = ((xx - 320) / 200) ** 2 + ((yy - 200) / 110) ** 2 < 1
    img[opening] = 200.0
    r = np.hypot(xx - cx, yy - cy)
    img[(r < 85) & opening] = 110.0
    a = np.clip(30.5 - r, 0, 1)
    img = img * (1 - a) + 20.0 * a
    for dx, dy in OFFSETS:
        img += 30.0 * np.exp(-((xx - cx - 5 * dx / 6) ** 2 + (yy - cy - 5 * dy / 6) ** 2) / 4.5)
    img += rng.normal(0.0, 3.0, img.shape)
    return np.clip(img, 0, 255).astype(np.uint8)


@pytest.mark.parametrize("seed", [22, 38, 55])
def test_unsaturated_glints_within_a_pixel(seed):
    """Glints 10 σ over the pupil: their top-hat centroid, which weighs the noise of every
    pixel above half the glint test, was 1.1-2.2 px off in 4 of 48 seeds (these, answered
    ``ok``; session 19's gl30.png: 1.3 px). Centred by a Gaussian fit over a plane: within
    1 px."""
    d = detect(_faint(seed), led_azimuths_deg=LEDS)
    assert d.ok, d.failures
    found = {g.led: g.centre_px for g in d.glints if g.led is not None}
    assert sorted(found) == [0, 1, 2, 3], d.glints
    for k, (x, y) in found.items():
        dx, dy = OFFSETS[k]
        err = math.hypot(x - 320.3 - 5 * dx / 6, y - 200.7 - 5 * dy / 6)
        assert err < 1.0, (k, found[k], err)
