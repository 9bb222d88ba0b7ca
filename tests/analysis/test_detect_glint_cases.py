"""Glint cases a new user found (session 19), on pictures made here.

:func:`eye` draws a 640 × 400 eye as the user did: skin 170, an eye opening of sclera 200, an
iris disc (radius 85) at 110, a pupil (anti-aliased edge) at 20, four glints — Gaussian spots
of σ 1.5 px and 400 DN peak, saturated — 25 px right, up, left and down of the pupil's centre
(LEDs at 0°, 90°, 180°, 270°), Gaussian noise σ 3, clipped to 8 bits.

A matched glint must lie within 0.5 px of its truth: the glints' centroids on these pictures
are 0.01-0.4 px off (the JPEG's blocks move them most); a compression speck or a stray taken
for an LED's glint lies 35-80 px away.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from eyelume.analysis.tracking.detect import Glint, _match_glints, detect

LEDS = (0, 90, 180, 270)
CENTRE = (320.3, 200.7)
OFFSETS = ((25.0, 0.0), (0.0, -25.0), (-25.0, 0.0), (0.0, 25.0))  # LED k's glint from the pupil


def eye(
    pupil_r: float = 30.0, seed: int = 0, glint_peak: float = 400.0, glints: bool = True
) -> np.ndarray:
    """The 8-bit picture of the module doc, with the pupil radius ``pupil_r`` px and the glints'
    peak ``glint_peak`` DN over their background (400: saturated), or no glints."""
    rng = np.random.default_rng(seed)
    rows, cols = 400, 640
    yy, xx = np.mgrid[0:rows, 0:cols].astype(float)
    img = np.full((rows, cols), 170.0)
    opening = ((xx - 320) / 200) ** 2 + ((yy - 200) / 110) ** 2 < 1
    img[opening] = 200.0
    cx, cy = CENTRE
    r = np.hypot(xx - cx, yy - cy)
    img[(r < 85) & opening] = 110.0
    a = np.clip(pupil_r + 0.5 - r, 0, 1)
    img = img * (1 - a) + 20.0 * a
    for dx, dy in OFFSETS if glints else ():
        img += glint_peak * np.exp(-((xx - cx - dx) ** 2 + (yy - cy - dy) ** 2) / (2 * 1.5**2))
    img += rng.normal(0.0, 3.0, img.shape)
    return np.clip(img, 0, 255).astype(np.uint8)


def _jpeg(img: np.ndarray, quality: int) -> np.ndarray:
    ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, quality])
    assert ok
    return cv2.imdecode(buf, cv2.IMREAD_GRAYSCALE)


def _assert_glints_matched(d, tol: float = 0.5) -> None:
    assert d.ok, d.failures
    found = {g.led: g.centre_px for g in d.glints if g.led is not None}
    assert sorted(found) == [0, 1, 2, 3], d.glints
    for k, (dx, dy) in enumerate(OFFSETS):
        x, y = found[k]
        err = math.hypot(x - CENTRE[0] - dx, y - CENTRE[1] - dy)
        assert err < tol, (k, found[k], err)


@pytest.mark.parametrize(("quality", "seed"), [(8, 0), (8, 2), (15, 1), (20, 0), (20, 1)])
def test_jpeg_specks_are_not_matched(quality, seed):
    """JPEG at quality 8-20 leaves specks 13-50 DN over the flat sclera, 40-90 px from the
    pupil; matched by direction alone they took LEDs from the saturated glints (defect 1 of
    session 20). The glints, rising ~225 DN over the pupil, are matched first."""
    d = detect(_jpeg(eye(seed=seed), quality), led_azimuths_deg=LEDS)
    _assert_glints_matched(d)


@pytest.mark.parametrize(("pupil_r", "seed"), [(5, 0), (4, 0), (5, 1)])
def test_small_pupil_keeps_its_glints(pupil_r, seed):
    """A 2 mm pupil (8-10 px across) with its glints 25 px out — 2.5-3 of its diameters, on
    the iris: out of the search radius scaled by the pupil (2 × its major axis) and over its
    size cap; they were all lost ("glint lost: 0 of 4", defect 3 of session 20)."""
    d = detect(eye(pupil_r=pupil_r, seed=seed), led_azimuths_deg=LEDS)
    _assert_glints_matched(d)


@pytest.mark.parametrize(("peak", "seed"), [(80, 0), (80, 1), (60, 0), (180, 0)])
def test_unsaturated_glints_are_found(peak, seed):
    """Glints 60-180 DN over the pupil (20 DN), σ 1.5 px, not saturated — 20-60 σ of the noise
    over their own background but below the sclera's level, where the glints' threshold (the
    99th percentile) sits: "glint lost: 0 of 4" (defect 2 of session 20). Found on the
    picture's white top-hat and matched, within the issue's 1 px for an ``ok`` answer (its
    centroid's noise grows as the peak falls: over seeds 0-5 median 0.22, largest 0.55 px at
    60 DN; 0.18 and 0.42 at 80; 0.09 and 0.19 at 180)."""
    d = detect(eye(glint_peak=peak, seed=seed), led_azimuths_deg=LEDS)
    _assert_glints_matched(d, tol=1.0)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_no_glints_no_specks(seed):
    """Without glints the top-hat search finds nothing in the noise (8 σ) nor at the pupil's or
    the iris's edges (broader than its disc): no glint near the pupil, the LEDs lost."""
    d = detect(eye(glints=False, seed=seed), led_azimuths_deg=LEDS)
    assert not d.ok
    assert d.glints == [], d.glints
    assert any(f.startswith("glint lost: 0 of 4") for f in d.failures), d.failures


def test_glint_at_the_valid_mask_edge_is_not_matched():
    """A valid-area mask cutting the picture at x = 300 (through the pupil): the sclera next to
    the cut stands out of the black fill, and with the noise read over the fill too (σ 0.5
    for 3) sclera specks of 5 DN passed the glint test and were matched to an LED (defect 5
    of session 20). No glint within 6 px of the cut is matched."""
    img = eye()
    valid = np.ones(img.shape, bool)
    valid[:, 300:] = False
    d = detect(img, led_azimuths_deg=LEDS, valid=valid)
    assert all(g.centre_px[0] < 294.0 for g in d.glints if g.led is not None), d.glints


def test_strong_glints_matched_before_weak_specks():
    """Four glints rising 230 DN on a ring of radius 25 px and four specks rising 30 DN 65 px
    out at the LEDs' azimuths: the glints get the LEDs; a speck gets none."""
    ring = _ring(25.0)
    far = _ring(65.0, turn=5.0)
    glints = [Glint(c, 6.0, 255.0, flux=4000.0, base=25.0) for c in ring]
    glints += [Glint(c, 12.0, 230.0, flux=1500.0, base=200.0) for c in far]
    order = [4, 0, 5, 1, 6, 2, 7, 3]
    mixed = [glints[i] for i in order]
    errors, missing = _match_glints(mixed, LEDS, _params())
    assert not errors and not missing
    for g in mixed:
        if g.base == 25.0:
            assert g.led == LEDS.index(_azimuth(g.centre_px)), g
        else:
            assert g.led is None, g


def test_weak_glint_fills_a_missing_led_where_the_pattern_puts_it():
    """Three strong glints and a weak one (a saturated glint over the bright sclera rises less)
    where their ring puts the fourth LED's glint: it is matched; a weak speck elsewhere is
    not."""
    ring = _ring(25.0)
    glints = [Glint(c, 6.0, 255.0, flux=4000.0, base=25.0) for c in ring[:3]]
    glints.append(Glint((ring[3][0] + 1.0, ring[3][1]), 6.0, 255.0, flux=900.0, base=200.0))
    glints.append(Glint((170.0, 40.0), 12.0, 230.0, flux=900.0, base=200.0))
    errors, missing = _match_glints(glints, LEDS, _params())
    assert [g.led for g in glints] == [0, 1, 2, 3, None]
    assert not errors and not missing


def _ring(radius: float, turn: float = 0.0) -> list[tuple[float, float]]:
    """Points ``radius`` px from (100, 100) at the LEDs' azimuths + ``turn`` degrees."""
    rad = [math.radians(a + turn) for a in LEDS]
    return [(100.0 + radius * math.cos(a), 100.0 - radius * math.sin(a)) for a in rad]


def _azimuth(xy) -> int:
    a = math.degrees(math.atan2(-(xy[1] - 100.0), xy[0] - 100.0)) % 360.0
    return min(LEDS, key=lambda k: abs((a - k + 180.0) % 360.0 - 180.0))


def _params():
    from eyelume.analysis.tracking.detect import DetectParams

    return DetectParams()
