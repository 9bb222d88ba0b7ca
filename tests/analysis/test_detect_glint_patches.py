"""A lit patch matched as an LED's glint (issue 13; population frames of issue 15's 850/940 nm
design run): a piece of bright sclera pinched between the dark iris and a shadow, tens of px,
matched to an LED whose glint is off the cornea, and the frame answered ``ok``.

The ring's glints are images of like point sources through the same optics, so their light
over their rise above the background (flux / (peak − base), 2πσ² for a Gaussian spot, × (1 +
ln(P/C)) when clipped at C) is alike; a blob no brighter than the others that spreads its light
over more than 3 × their median is no LED's image (``detect._lit_patches``), and the matching,
with strays about, is refused by name.

Pictures: :func:`test_detect.draw_eye` (10-bit, noise σ 4 DN, optics blur σ 1 px) with three
saturated glints of σ 1 px (13.4 px² each) and, at the fourth LED's place, a Gaussian spot of
σ 3 px rising 600 DN over the iris (58 px², 4.3 ×: refused), of σ 1 px rising 400 DN (an
unsaturated glint: kept) or 2000 DN (saturated: kept), or of σ 2 px rising 500 DN (a glint
twice as wide as the others, 2 ×, within the margin: kept). Tolerance of the kept glint's
centre: 0.2 px (the drawn spot's centre; the tests' other glints are within 0.1 px).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from eyelume.analysis.tracking import detect
from tests.analysis.test_detect import LEDS, EyePicture, draw_eye, glint_positions


def _picture(sigma: float, rise: float) -> np.ndarray:
    truth = glint_positions()
    img = draw_eye(
        EyePicture(
            glints=[truth[0], truth[1], truth[3]],
            seed=5,
            noise=4.0,
            glint_sigma=1.0,
            blur=1.0,
            dtype=np.float64,
        )
    )
    yy, xx = np.mgrid[: img.shape[0], : img.shape[1]]
    gx, gy = truth[2]
    img = img + rise * np.exp(-((xx - gx) ** 2 + (yy - gy) ** 2) / (2.0 * sigma**2))
    return np.rint(np.minimum(img, 1023.0)).astype(np.uint16)


def test_a_lit_patch_at_an_leds_place_is_refused_by_name():
    d = detect(_picture(3.0, 600.0), led_azimuths_deg=LEDS)
    assert not d.ok, d.failures
    assert any(f.startswith("glint lost:") and "lit patch" in f for f in d.failures), d.failures


@pytest.mark.parametrize(("sigma", "rise"), [(1.0, 400.0), (1.0, 2000.0), (2.0, 500.0)])
def test_glints_of_the_ring_are_not_lit_patches(sigma, rise):
    d = detect(_picture(sigma, rise), led_azimuths_deg=LEDS)
    assert d.ok, d.failures
    assert sorted(g.led for g in d.glints if g.led is not None) == [0, 1, 2, 3]
    g = next(g for g in d.glints if g.led == 2)
    assert math.dist(g.centre_px, glint_positions()[2]) < 0.2, g
