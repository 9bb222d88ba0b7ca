"""JPEGs whose unsaturated glints are dimmer than the sclera (issue 13's open defect, session 25),
on pictures made here.

:func:`eye` draws a 640 × 400 eye, its figures drawn per picture from a seeded generator: skin
150–175, an eye opening (semi-axes 220 × 120 px) of sclera 200–230, an iris disc (radius 85) at
90–120, a pupil (radius 32–40 px, anti-aliased edge) at 20–40, and 4 or 8 unsaturated glints —
Gaussian spots of σ 1.2–1.6 px peaking at 150–200 DN, on a ring of radius 20 px to the pupil's
radius − 8 about the pupil's centre at the LEDs' azimuths (k · 360° / n) — blurred by σ 0.8 px,
Gaussian noise σ 2–3.5, rounded to 8 bits and coded as a JPEG by OpenCV (the IJG's coder) at
quality 15–70. The glints peak under the sclera, so the picture's brightest pixels are the
sclera's and the coding's ringing along its edges.

On main before this session, of 48 such pictures (seeds 0–3, 4 and 8 LEDs, q15–70) 14 were
answered ``ok`` with a glint 3–231 px off (13 of them ≥ 94 px: the coding's specks matched to
LEDs) and 6 right; the PNG of each was right (≤ 0.08 px), and still is, unchanged.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from eyelume.analysis.tracking.detect import detect
from eyelume.analysis.tracking.glints import jpeg_dc_step


def eye(seed: int, n_leds: int):
    """The picture of the module doc before coding (uint8), the LEDs' azimuths (degrees), the
    pupil's centre (x, y) px and each LED's glint offset from it (px)."""
    rng = np.random.default_rng(1000 * n_leds + seed)
    rows, cols = 400, 640
    yy, xx = np.mgrid[0:rows, 0:cols].astype(float)
    cx, cy = 320 + rng.uniform(-20, 20), 200 + rng.uniform(-10, 10)
    skin, sclera = rng.uniform(150, 175), rng.uniform(200, 230)
    iris, pupil = rng.uniform(90, 120), rng.uniform(20, 40)
    pr = rng.uniform(32, 40)
    ring = rng.uniform(20, pr - 8)
    peak, sig, noise = rng.uniform(150, 200), rng.uniform(1.2, 1.6), rng.uniform(2, 3.5)
    img = np.full((rows, cols), skin)
    opening = ((xx - cx) / 220) ** 2 + ((yy - cy) / 120) ** 2 < 1
    img[opening] = sclera
    r = np.hypot(xx - cx, yy - cy)
    img[(r < 85) & opening] = iris
    a = np.clip(pr + 0.5 - r, 0, 1)
    img = img * (1 - a) + pupil * a
    leds = [k * 360.0 / n_leds for k in range(n_leds)]
    offsets = [(ring * math.cos(math.radians(t)), -ring * math.sin(math.radians(t))) for t in leds]
    for dx, dy in offsets:
        img += (peak - pupil) * np.exp(-((xx - cx - dx) ** 2 + (yy - cy - dy) ** 2) / (2 * sig**2))
    img = cv2.GaussianBlur(img, (0, 0), 0.8)
    img += rng.normal(0.0, noise, img.shape)
    return np.round(np.clip(img, 0, 255)).astype(np.uint8), leds, (cx, cy), offsets


def _jpeg(img: np.ndarray, quality: int) -> np.ndarray:
    ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, quality])
    assert ok
    return cv2.imdecode(buf, cv2.IMREAD_GRAYSCALE)


def _errors(d, centre, offsets) -> tuple[float, dict[int, float]]:
    """The pupil's centre error and each matched glint's (px)."""
    e_pupil = math.dist(d.pupil.centre_px, centre)
    glints = {
        g.led: math.dist(
            g.centre_px, (centre[0] + offsets[g.led][0], centre[1] + offsets[g.led][1])
        )
        for g in d.glints
        if g.led is not None
    }
    return e_pupil, glints


def _ijg_dc_quantiser(quality: int) -> int:
    """The IJG's luminance DC quantiser at ``quality`` (jcparam.c: 16 scaled by 5000 / q below
    50, 200 − 2q from 50, rounded, ≥ 1)."""
    scale = 5000 // quality if quality < 50 else 200 - 2 * quality
    return max(1, (16 * scale + 50) // 100)


@pytest.mark.parametrize("quality", [5, 15, 25, 35, 45, 55, 70, 75, 80])
def test_jpeg_dc_step_reads_the_quantiser(quality):
    """The DC quantiser read off the decoded blocks is the coder's own, exactly (its doc's
    lattice test: a wrong Q fits ≥ 90 % of ~4000 blocks only by chance)."""
    img, *_ = eye(0, 4)
    assert jpeg_dc_step(_jpeg(img, quality)) == _ijg_dc_quantiser(quality) / 8.0


def test_jpeg_dc_step_is_zero_off_jpegs():
    """No grid, no step: the uncoded picture, its nearest-neighbour enlargements by 2, 4 and 8
    (steps only on lines of the 8 × 8 grid, but none within its 2 × 2 squares), a float copy
    of a JPEG (the test reads 8-bit pictures only), and a picture coded at q90 (Q₀₀ = 3 is
    under the lattice test's reach; its step, 0.4 DN, under the noise)."""
    img, *_ = eye(1, 4)
    assert jpeg_dc_step(img) == 0.0
    for k in (2, 4, 8):
        big = np.kron(img[: 400 // k, : 640 // k], np.ones((k, k), np.uint8))
        assert jpeg_dc_step(big) == 0.0, k
    assert jpeg_dc_step(_jpeg(img, 25).astype(np.float32)) == 0.0
    assert jpeg_dc_step(_jpeg(img, 90)) == 0.0


CASES = [(n, s, q) for n in (4, 8) for s in (0, 1, 2, 3) for q in (15, 25, 35, 45, 55, 70)]


@pytest.mark.parametrize(("n_leds", "seed", "quality"), CASES)
def test_jpeg_dim_glints_ok_only_when_right(n_leds, seed, quality):
    """An ``ok`` answer has the pupil and every matched glint within the issue's 1 px of the
    truth: on these pictures the matched glints are ≤ 0.39 px off (46 ``ok`` answers of 48)
    (the coding moves a lone glint's centroid ≤ 0.46 px at q15, 300 trials), and a coding
    speck taken for a glint lies 1.2–231 px off. A refusal must name the glints (``glint
    ...``) — the pupils here are 32–40 px discs, found in every picture — or the pupil's own
    known failure (``pupil merged with iris`` on seed 0 at q55 with 4 LEDs)."""
    img, leds, centre, offsets = eye(seed, n_leds)
    d = detect(_jpeg(img, quality), led_azimuths_deg=leds)
    if not d.ok:
        assert d.failures[0].startswith(("glint", "pupil merged with iris")), d.failures[0]
        return
    e_pupil, e_glints = _errors(d, centre, offsets)
    assert e_pupil < 1.0, e_pupil
    assert len(e_glints) >= 2, e_glints
    assert max(e_glints.values()) < 1.0, (e_glints, d.glints)


FOUND = [(n, s, 70) for n in (4, 8) for s in (0, 1, 2, 3)] + [
    (n, s, 55) for n in (4, 8) for s in (0, 1, 2, 3) if (n, s) != (4, 0)
]


@pytest.mark.parametrize(("n_leds", "seed", "quality"), FOUND)
def test_jpeg_dim_glints_found_at_q55_and_up(n_leds, seed, quality):
    """At q55 and q70 every LED's glint is found and matched, each within 1 px (≤ 0.18 px
    here), and the frame answered ``ok`` — all 16 but seed 0 with 4 LEDs at q55, whose pupil
    is refused as merged with its iris (a pupil defect, on main too). On main 8 of these 15
    were refused (broken up, or a coding speck leaving an LED uncertain) and one answered
    with a glint 3 px off. Below q55, 31 of 32 pictures here are found too (not asserted: fewer
    trials); seed 0 with 4 LEDs at q45 is refused by name (two LEDs left without a glint)."""
    img, leds, centre, offsets = eye(seed, n_leds)
    d = detect(_jpeg(img, quality), led_azimuths_deg=leds)
    assert d.ok, d.failures[0]
    e_pupil, e_glints = _errors(d, centre, offsets)
    assert e_pupil < 1.0, e_pupil
    assert sorted(e_glints) == list(range(n_leds)), d.glints
    assert max(e_glints.values()) < 1.0, e_glints
