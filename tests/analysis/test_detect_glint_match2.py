"""Glint matching (session 22): a candidate far from where the other glints put its LED's glint.

Pictures drawn here: a 480 × 360 eye (skin 160, sclera 190, iris 100 of radius 70, pupil 20 of
radius 30 at (200.6, 150.2)), glints as Gaussian spots (amplitude 400 DN, σ 1.3 px, clipped at
255) on a ring of radius 25.5 px toward the LEDs at azimuths 0, 90, 180, 270°, noise σ 3 DN.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from eyelume.analysis.tracking import detect
from eyelume.analysis.tracking.detect import DetectParams, Glint, _off_the_others
from tests.analysis.test_detect_glint_match import _eye as _match_eye

CENTRE = (200.6, 150.2)
LEDS = (0.0, 90.0, 180.0, 270.0)
RING = 25.5


def _at(azimuth_deg: float, r: float = RING, centre=CENTRE) -> tuple[float, float]:
    """The point ``r`` px from ``centre`` toward ``azimuth_deg`` (90° = picture up)."""
    a = math.radians(azimuth_deg)
    return centre[0] + r * math.cos(a), centre[1] - r * math.sin(a)


def _eye(spots, seed=0) -> np.ndarray:
    """The eye picture (module doc: a 30 px pupil) with ``spots`` (x, y, amplitude DN, σ px)
    added (test_detect_glint_match's picture)."""
    return _match_eye(spots, seed, pupil_r=30.0)


@pytest.mark.parametrize(
    "stray", [_at(20.0), _at(30.0), _at(45.0), (CENTRE[0] + 40.0, CENTRE[1] + 2.0)]
)
def test_a_stray_off_a_missing_leds_place_is_not_its_glint(stray):
    """LED 0's glint absent, a stray spot 20°, 30° or 45° off its direction on the ring (8.9–
    19.5 px from where the other three put it), or at its azimuth 14.5 px too far out: the
    matching by direction gave it LED 0 and answered ok (session 21's user). The other
    three glints' fit puts LED 0's glint within a few px (their scatter ~0): the stray is
    left out of LED 0 and the frame refused, naming it."""
    truth = {k: _at(a) for k, a in enumerate(LEDS) if k != 0}
    spots = [(x, y, 400.0, 1.3) for x, y in truth.values()] + [(*stray, 400.0, 1.3)]
    d = detect(_eye(spots), led_azimuths_deg=LEDS)
    assert all(g.led != 0 for g in d.glints), d.glints
    named = [f for f in d.failures if f.startswith("glint lost: the glint at (")]
    assert len(named) == 1 and " matched to LED 0 lies " in named[0], d.failures
    x, y = (float(v) for v in named[0].split("(")[1].split(")")[0].split(", "))
    assert math.dist((x, y), stray) < 0.5, named
    assert not d.ok
    for g in d.glints:
        if g.led is not None:
            assert math.dist(g.centre_px, truth[g.led]) < 0.5


def test_every_glint_found_stays_matched():
    """The same picture with LED 0's glint present (and no stray): all four matched, ok."""
    truth = [_at(a) for a in LEDS]
    d = detect(_eye([(x, y, 400.0, 1.3) for x, y in truth]), led_azimuths_deg=LEDS)
    assert d.ok, d.failures
    assert sorted(g.led for g in d.glints if g.led is not None) == [0, 1, 2, 3]


@pytest.mark.parametrize("n", [4, 6, 8])
@pytest.mark.parametrize("squeeze", [1.0, 0.8, 0.7])
def test_a_foreshortened_ring_is_no_stray(n, squeeze):
    """A ring seen off-axis is an ellipse, which the model t + s p_k (a circle) does not fit:
    the others' scatter shows that misfit, so no glint of a ring squeezed to 70 % across is
    taken for a stray."""
    az = [360.0 * k / n for k in range(n)]
    at = [(200 + 30 * math.cos(math.radians(a)), 150 - 30 * squeeze * math.sin(math.radians(a)))
          for a in az]  # fmt: skip
    gl = [Glint(p, 5.0, 255.0, led=k, flux=1.0) for k, p in enumerate(at)]
    assert _off_the_others(gl, az, None, DetectParams()) is None


def test_the_allowance_follows_the_others_scatter():
    """Six glints with 1 px of scatter and one 4 px off: within what the others' scatter
    allows (not a stray); the same glint 12 px off is beyond it and named."""
    az = [0.0, 60.0, 120.0, 180.0, 240.0, 300.0]
    rng = np.random.default_rng(3)
    base = np.array([_at(a, 30.0) for a in az]) + rng.normal(0.0, 1.0, (6, 2))
    for shift, flagged in ((4.0, False), (12.0, True)):
        c = base.copy()
        c[0, 1] += shift
        gl = [Glint(tuple(p), 5.0, 255.0, led=k, flux=1.0) for k, p in enumerate(c)]
        off = _off_the_others(gl, az, None, DetectParams())
        assert (off is not None) == flagged, off
        if flagged:
            assert off[0] == 0 and off[1] > off[2]


def test_a_block_of_stuck_pixels_without_a_skirt_is_no_glint():
    """A 2 × 2 block at 230 DN where LED 1's glint is absent, beside glints of σ 1.3 px: it
    was matched to LED 1. A point source's image has the optics' blur (the other glints'
    edges, σ ≈ 1.3 px); the block falls from its top to the background in one pixel: left
    out, named; the other three are used."""
    truth = {k: _at(a) for k, a in enumerate(LEDS) if k != 1}
    img = _eye([(x, y, 400.0, 1.3) for x, y in truth.values()])
    x1, y1 = _at(90.0)
    img[round(y1) : round(y1) + 2, round(x1) : round(x1) + 2] = 230
    d = detect(img, led_azimuths_deg=LEDS)
    assert all(g.led != 1 for g in d.glints), d.glints
    assert any("no blur skirt" in f for f in d.failures), d.failures
    assert d.ok and d.missing_leds == [1], d.failures
