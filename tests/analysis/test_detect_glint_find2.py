"""Glint finding in JPEG pictures whose glints are dimmer than the sclera (session 22, defect 1
of the glint finding), on pictures made here.

:func:`eye` draws a 640 × 400 eye as the session-21 user did: skin 150, an eye opening of
sclera 190, an iris disc (radius 83) at 110, a pupil (radius 32, anti-aliased edge) at 20, four
unsaturated glints — Gaussian spots of σ 1.3 px and ``amp`` DN — 27 px right, up, left and down
of the pupil's centre (LEDs at 0°, 90°, 180°, 270°), blurred by σ 0.8 px, Gaussian noise σ 3,
clipped to 8 bits and saved as a JPEG. With ``amp`` 60–160 the glints peak at 60–130 DN, under
the sclera's 190: the picture's brightest pixels are the sclera's noise maxima.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from eyelume.analysis.tracking.detect import detect

LEDS = (0, 90, 180, 270)
CENTRE = (305.5, 195.2)
GR = 27.2
OFFSETS = ((GR, 0.0), (0.0, -GR), (-GR, 0.0), (0.0, GR))  # LED k's glint from the pupil


def eye(amp: float, seed: int) -> np.ndarray:
    """The picture of the module doc before JPEG coding (uint8)."""
    rng = np.random.default_rng(seed)
    rows, cols = 400, 640
    yy, xx = np.mgrid[0:rows, 0:cols].astype(float)
    cx, cy = CENTRE
    img = np.full((rows, cols), 150.0)
    opening = ((xx - cx) / 220) ** 2 + ((yy - cy) / 120) ** 2 < 1
    img[opening] = 190.0
    r = np.hypot(xx - cx, yy - cy)
    img[(r < 83) & opening] = 110.0
    a = np.clip(32.0 + 0.5 - r, 0, 1)
    img = img * (1 - a) + 20.0 * a
    for dx, dy in OFFSETS:
        img += amp * np.exp(-((xx - cx - dx) ** 2 + (yy - cy - dy) ** 2) / (2 * 1.3**2))
    img = cv2.GaussianBlur(img, (0, 0), 0.8)
    img += rng.normal(0.0, 3.0, img.shape)
    return np.round(np.clip(img, 0, 255)).astype(np.uint8)


def _jpeg(img: np.ndarray, quality: int) -> np.ndarray:
    ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, quality])
    assert ok
    return cv2.imdecode(buf, cv2.IMREAD_GRAYSCALE)


def _errors(d) -> dict[int, float]:
    out = {}
    for g in d.glints:
        if g.led is not None:
            dx, dy = OFFSETS[g.led]
            x, y = g.centre_px
            out[g.led] = math.hypot(x - CENTRE[0] - dx, y - CENTRE[1] - dy)
    return out


@pytest.mark.parametrize(("amp", "seed"), [(60, 1), (100, 2), (160, 3), (100, 4)])
def test_jpeg_sclera_specks_are_no_glints(amp, seed):
    """At JPEG quality 75 the picture's own noise σ (Immerkær's, from second differences) is
    0.5 DN — the coding removed the high frequencies it sees — while the sclera keeps specks
    8–10 DN over their surround: taken as glints 8 σ over the background, four of them
    (80–100 px from the glints) were matched to the four LEDs and answered ``ok`` (session 21's
    jq75_a100, jq75_a160), or the real glints were never looked for. Judged against the noise
    of their own surround (σ 1.5 DN) they are specks; the glints, found on the pupil, are
    matched, each within 1 px."""
    d = detect(_jpeg(eye(amp, seed), 75), led_azimuths_deg=LEDS)
    assert d.ok, d.failures
    err = _errors(d)
    assert sorted(err) == [0, 1, 2, 3], d.glints
    assert max(err.values()) < 1.0, err
