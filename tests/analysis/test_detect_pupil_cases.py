"""A new user's pupil cases (issue 13, session 19's check), made up here: a 2 px pupil, a bright
pupil, a large NaN hole in the pupil, a valid-area mask across the pupil and a faint close-up.

:func:`eye` draws their 640 × 400 frame: skin, an eye opening of sclera, an iris disc and a
pupil disc with a 1 px anti-aliased edge, four saturated glints 25 px from the pupil's centre
and Gaussian pixel noise, rounded to 8 bits. Each test asserts the right answer or the refusal
naming the cause; each failed on the code before session 20 (the iris answered as the pupil,
or another cause named).

Tolerance of the NaN-hole test: the pupil's edge (a 90 DN step at noise σ 3, no blur but the
1 px anti-aliasing) puts each edge point ≈ 0.05 px off and the centre of ~300 points ≈ 0.01
px; 0.25 px (as tests/analysis/test_detect_kinds.py) is far above that and far below the
12 px by which a fit to the hole's rim or a cut blob would miss.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from eyelume.analysis.tracking import detect

H, W = 400, 640
CENTRE = (320.3, 200.7)


def eye(
    pupil_r=30.0,
    pupil=20.0,
    iris=110.0,
    centre=CENTRE,
    skin=170.0,
    sclera=200.0,
    noise=3.0,
    seed=0,
):
    """The frame as float DN before rounding (see the module doc); ``pupil`` may be brighter
    than the iris (a bright-pupil picture)."""
    yy, xx = np.mgrid[0:H, 0:W].astype(float)
    img = np.full((H, W), skin)
    opening = ((xx - 320) / 200) ** 2 + ((yy - 200) / 110) ** 2 < 1
    img[opening] = sclera
    img[(np.hypot(xx - CENTRE[0], yy - CENTRE[1]) < 85) & opening] = iris
    a = np.clip(pupil_r + 0.5 - np.hypot(xx - centre[0], yy - centre[1]), 0, 1)
    img = img * (1 - a) + pupil * a
    for dx, dy in [(25, 0), (0, -25), (-25, 0), (0, 25)]:
        img += 400 * np.exp(-((xx - centre[0] - dx) ** 2 + (yy - centre[1] - dy) ** 2) / 4.5)
    img += np.random.default_rng(seed).normal(0, noise, img.shape)
    return img


def u8(img):
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("offset", [(0, 0), (8.0, -3.5)])
def test_two_px_pupil_in_its_iris_is_too_small_not_the_iris(seed, offset):
    """A 2 px pupil (~13 px of area) inside a 170 px iris: the iris, a dark disc with a darker
    core, was answered as the pupil; now the core is named as a pupil too small."""
    centre = (CENTRE[0] + offset[0], CENTRE[1] + offset[1])
    d = detect(u8(eye(pupil_r=2.0, centre=centre, seed=seed)), led_azimuths_deg=[0, 90, 180, 270])
    assert not d.ok and d.pupil is None, d.failures
    assert d.failures[0].startswith("pupil too small: "), d.failures


@pytest.mark.parametrize("pupil_r", [4.0, 7.0])
def test_small_pupils_above_the_least_are_still_found(pupil_r):
    """4 and 7 px pupils (50 and 154 px of area) are found, centred within 0.25 px."""
    d = detect(u8(eye(pupil_r=pupil_r)))
    assert d.pupil is not None, d.failures
    assert np.hypot(*np.subtract(d.pupil.centre_px, CENTRE)) < 0.25
    assert d.pupil.axes_px[0] < 2 * pupil_r + 3


@pytest.mark.parametrize("iris", [110.0, 60.0])
@pytest.mark.parametrize("offset", [(0, 0), (8.0, -3.5)])
def test_bright_pupil_is_refused_by_name(iris, offset):
    """A pupil at 240 DN (lit on-axis) inside a darker iris, with skin (170) and sclera (200)
    darker than the pupil: refused as a bright-pupil image, never the iris as the pupil."""
    centre = (CENTRE[0] + offset[0], CENTRE[1] + offset[1])
    d = detect(u8(eye(pupil=240.0, iris=iris, centre=centre)))
    assert not d.ok and d.pupil is None, d.failures
    assert d.failures[0].startswith("no dark pupil: bright-pupil image?"), d.failures


@pytest.mark.parametrize(("pupil", "iris"), [(120.0, 60.0), (125.0, 90.0), (120.0, 110.0)])
@pytest.mark.parametrize("seed", [0, 1])
def test_bright_pupil_a_little_over_its_iris_is_refused_by_name(pupil, iris, seed):
    """A lit pupil only 10-65 DN over its iris (σ 3), under the halfway level from the iris to
    the sclera that the 240 DN pupil above crosses: the iris with the lit pupil inside was
    answered as the pupil (session 20's new user, 13 of 17 contrasts); now refused by name
    from the interior averaged over 5 × 5 px (a plateau 15-90 σ of those averages over its
    median)."""
    d = detect(u8(eye(pupil=pupil, iris=iris, seed=seed)), led_azimuths_deg=[0, 90, 180, 270])
    assert not d.ok and d.pupil is None, d.failures
    assert d.failures[0].startswith("no dark pupil: bright-pupil image?"), d.failures


def _blurred(img, blur):
    return cv2.GaussianBlur(img, (0, 0), blur) if blur else img


SMALL_LIT = [  # (iris, pupil over it, pupil radius, noise σ, blur σ): DN, DN, px, DN, px
    (70.0, 20.0, 15.0, 3.0, 0.0),
    (110.0, 10.0, 15.0, 3.0, 0.0),
    (40.0, 10.0, 15.0, 3.0, 1.5),
    (110.0, 30.0, 15.0, 1.5, 1.5),
    (70.0, 20.0, 30.0, 1.5, 1.5),
    (40.0, 30.0, 30.0, 1.5, 1.5),
    (40.0, 10.0, 45.0, 1.5, 1.5),
]


@pytest.mark.parametrize(("iris", "over", "radius", "noise", "blur"), SMALL_LIT)
def test_small_or_blurred_lit_pupil_over_its_iris_is_refused_by_name(
    iris, over, radius, noise, blur
):
    """A lit pupil 10-30 DN over its iris, 15 px in radius (4 % of the 85 px iris's
    interior: too few pixels to move its 95th percentile) or blurred by σ 1.5 px (an 8-bit
    iris rounded to one value, whose averages have no spread): 46 of 108 such pictures were
    answered `ok` with the iris (170 px) as the pupil; now refused by name
    (:func:`eyelume.analysis.tracking.pupil._small_bright_core`, and an integer floor on the
    averages' σ)."""
    img = _blurred(eye(pupil=iris + over, iris=iris, pupil_r=radius, noise=noise), blur)
    d = detect(u8(img), led_azimuths_deg=[0, 90, 180, 270])
    assert not d.ok and d.pupil is None, (d.failures, d.pupil)
    assert d.failures[0].startswith("no dark pupil: bright-pupil image?"), d.failures


@pytest.mark.parametrize(("iris", "radius", "blur"), [(40.0, 15.0, 1.5), (110.0, 15.0, 0.0)])
@pytest.mark.parametrize("seed", [0, 1])
def test_small_dark_pupil_with_the_same_looks_is_found(iris, radius, blur, seed):
    """The control: the same pupils dark (20 DN) are found, centred within 0.25 px (as
    above): the lit-core test asks for a flat top brighter than the interior's median, which
    a dark pupil's glints (left out with their margin) and noise do not make."""
    img = _blurred(eye(pupil=20.0, iris=iris, pupil_r=radius, noise=3.0, seed=seed), blur)
    d = detect(u8(img), led_azimuths_deg=[0, 90, 180, 270])
    assert d.pupil is not None, d.failures
    assert np.hypot(*np.subtract(d.pupil.centre_px, CENTRE)) < 0.25


@pytest.mark.parametrize("quality", [12, 25])
def test_dark_pupil_in_a_jpeg_is_not_taken_for_a_bright_one(quality):
    """The control: a dark pupil whose glints a JPEG smears into its interior (ringing a few DN
    over the pupil around each) is still found; the averaged bright-core test leaves the grown
    glints out and asks for a plateau larger than any glint."""
    ok, buf = cv2.imencode(".jpg", u8(eye()), [cv2.IMWRITE_JPEG_QUALITY, quality])
    img = cv2.imdecode(buf, cv2.IMREAD_GRAYSCALE)
    d = detect(img, led_azimuths_deg=[0, 90, 180, 270])
    assert d.pupil is not None, d.failures
    assert np.hypot(*np.subtract(d.pupil.centre_px, CENTRE)) < 0.5


def test_nan_hole_in_the_pupil_is_fitted_from_its_outline():
    """A 25 × 25 px hole of NaN in the pupil's centre (the whole edge visible): the pupil is
    fitted from its outline, not refused as merged with the iris."""
    img = eye().astype(np.float32)
    img[190:215, 305:330] = np.nan
    d = detect(img, led_azimuths_deg=[0, 90, 180, 270])
    assert d.ok, d.failures
    assert np.hypot(*np.subtract(d.pupil.centre_px, CENTRE)) < 0.25
    assert abs(d.pupil.axes_px[0] - 60.0) < 1.5  # the 60 px disc


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_valid_area_mask_across_the_pupil_is_named(seed):
    """A valid-area mask ending 20 px left of the pupil's centre (a sixth of its width left):
    the sliver is named as a pupil cut by the missing pixels, not a blob without a sharp edge
    or dark on one side only (a strip beside a lid)."""
    valid = np.ones((H, W), bool)
    valid[:, 300:] = False
    d = detect(u8(eye(seed=seed)), valid=valid)
    assert not d.ok and d.pupil is None, d.failures
    assert d.failures[0].startswith("pupil cut or hidden: "), d.failures
    assert "missing pixels" in d.failures[0], d.failures


@pytest.mark.parametrize("seed", [0, 1])
def test_faint_close_up_running_off_the_frame_is_found_not_cut(seed):
    """A 200 × 200 close-up: a 70 px pupil at 12 DN in an iris of 18 DN (2 σ of the noise σ
    3) that runs off the frame, skin 150 in the corners. Bright skin taken as glints is
    filled with the dark around it at the frame's edge; that was called a pupil cut by the
    frame, then (session 20) "pupil merged with iris": its 6 DN step was judged against the
    pixel noise (5 σ needed). Since session 22 the step is judged by its own standard error
    (a difference of medians over ~3900 and ~900 px: ≈ 0.14 DN, the step ≈ 40 of them) and the
    pupil is found. Tolerance as the module's (0.5 px)."""
    n = 200
    yy, xx = np.mgrid[0:n, 0:n].astype(float)
    r = np.hypot(xx - 100.3, yy - 99.6)
    img = np.full((n, n), 150.0)
    a = np.clip(120.5 - r, 0, 1)
    img = img * (1 - a) + 18.0 * a
    a = np.clip(35.5 - r, 0, 1)
    img = img * (1 - a) + 12.0 * a
    img = cv2.GaussianBlur(img, (0, 0), 1.0)
    img += np.random.default_rng(seed).normal(0, 3.0, img.shape)
    d = detect(u8(img))
    assert d.ok, d.failures
    assert np.hypot(*np.subtract(d.pupil.centre_px, (100.3, 99.6))) < 0.5


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_jpeg_ringing_in_a_pupil_is_no_small_core(seed):
    """The same frame saved as a JPEG at quality 8: the pupil's noise is flattened and the
    ringing beside a glint dips to the black level, ~13 DN under the pupil; that is no pupil
    inside an iris (the pupil is still found, within the issue's 0.5 px)."""
    ok, buf = cv2.imencode(".jpg", u8(eye(seed=seed)), [cv2.IMWRITE_JPEG_QUALITY, 8])
    d = detect(cv2.imdecode(buf, cv2.IMREAD_GRAYSCALE))
    assert d.pupil is not None, d.failures
    assert np.hypot(*np.subtract(d.pupil.centre_px, CENTRE)) < 0.5
