"""A defocused picture (issue 13; README's Open list since session 29): the tests' picture
(``test_detect.draw_eye``: 640 × 480, 10 bit, pupil 112 × 100 px at 30 DN in an iris at
170, four saturated glints, noise σ 8 DN) blurred by a Gaussian of σ 4–8 px was answered `ok`
with the centre right but the axes up to 23 px small.

The cause: :func:`eyelume.analysis.tracking.pupil.edge_offset` fits its blurred-step model
over a window that ends 1 px past the peak of the edge's line spread. A step blurred by σ 6–8
has a spread whose top is flat to within the median profile's noise, and the first local
peak the walk from the fitted ¼ iso-line met lay 3–5 px inside the edge: the true step was
outside the search, and the fit settled inside it. Since session 30 the window is centred on
the spread's centroid where the top is flat (``pupil._spread_middle``).

Measured on 16 pictures per blur (seeds 0–7, the ellipse at 20° and 70°): before, the major
axis's error ran −7.8…+1.6 px at σ 4, −16.3…+0.3 at σ 6 and −22.9…+0.4 at σ 8; after,
−0.6…+1.6 (mean +0.16, SD 0.52) at σ 4 and −1.4…−0.4 (mean −0.88, SD 0.31) at σ 6, the minor
axis alike. At σ 8 still −5.1…+1.4 (mean −2.6, SD 1.9): left in the Open list, not tested
here. Tolerance: 2 px on each full axis, ≥ 3.5 SD from the mean at both blurs; the centre
0.5 px (found within 0.15 px at every blur).
"""

from __future__ import annotations

import math

import pytest

from eyelume.analysis.tracking import detect
from tests.analysis.test_detect import EyePicture, draw_eye

LEDS = (0.0, 90.0, 180.0, 270.0)


@pytest.mark.parametrize("blur", [4.0, 6.0])
@pytest.mark.parametrize("seed", [0, 1, 2, 3])
@pytest.mark.parametrize("angle", [20.0, 70.0])
def test_defocused_pupil_keeps_its_axes(blur, seed, angle):
    pic = EyePicture(blur=blur, seed=seed, angle=angle)
    d = detect(draw_eye(pic), led_azimuths_deg=LEDS)
    assert d.ok, d.failures
    assert math.dist(d.pupil.centre_px, pic.centre) < 0.5
    major, minor = d.pupil.axes_px
    assert abs(major - pic.axes[0]) < 2.0, (major, minor)
    assert abs(minor - pic.axes[1]) < 2.0, (major, minor)
