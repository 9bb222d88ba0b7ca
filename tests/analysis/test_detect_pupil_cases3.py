"""Session 21's new user's pupil cases (issue 13), made up here: a pupil a few σ of the pixel
noise under a dark iris with saturated glints just inside its edge, or at σ 6; a small lit
pupil dimmer than the sclera; bloomed glints beside a small pupil.

:func:`eye` draws a 640 × 400 frame as that user's generator did: skin, an eye opening of
sclera, an iris disc and a pupil ellipse (drawn 4× finer and averaged down: anti-aliased
edges), four Gaussian glints (σ ``gsig`` px, peak ``gamp`` DN before clipping) at
``glint_frac`` × the pupil's radius from its centre (0.85: 3–5 px inside its edge), a Gaussian
blur of ``blur`` px, Gaussian pixel noise, rounded and clipped to 8 bits. Each test asserts the
right answer or the refusal naming the cause, and says how the code before session 22 failed.

Tolerance (0.5 px), as tests/analysis/test_detect_pupil_cases2.py's: a pupil 10 DN under its
iris at σ 3; the edge is read on the picture smoothed by a 2 px Gaussian (noise ≈ 0.14 σ =
0.4 DN) where the edge's slope is ≈ 10 DN / 5 px, so each edge point is ≈ 0.2 px off,
correlated over ~4 px of the ~190 px outline: the centre is ≈ 0.05 px off. 0.5 px is 10× that
and half the 1 px the issue asks for.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from eyelume.analysis.tracking import detect

H, W, S = 400, 640, 4
LEDS = (0, 90, 180, 270)


def eye(  # noqa: PLR0913 - each option is one aspect of the made-up eye
    cx=320.0,
    cy=200.0,
    pa=30.0,
    pb=None,
    pang=0.0,
    pupil=20.0,
    iris=30.0,
    iris_r=80.0,
    iris_c=None,
    gamp=400.0,
    gsig=1.3,
    glint_frac=0.85,
    blur=0.8,
    noise=3.0,
    seed=5,
    iris_level=None,
):
    """The frame (uint8; see the module doc; the iris centred at ``iris_c``, default the
    pupil's centre). ``iris_level``: a function of d, the distance (px, array) from the pupil's
    ellipse along its normalised radius, (ρ − 1) √(a b) (0 inside), giving the iris's level
    there instead of the flat ``iris`` (tests/analysis/test_detect_pupil_gradual_iris.py)."""
    rng = np.random.default_rng(seed)
    pb = pa if pb is None else pb
    icx, icy = (cx, cy) if iris_c is None else iris_c
    xx = ((np.arange(W * S) + 0.5) / S - 0.5)[None, :]
    yy = ((np.arange(H * S) + 0.5) / S - 0.5)[:, None]
    img = np.full((H * S, W * S), 150.0)
    opening = ((xx - 320.0) / 220.0) ** 2 + ((yy - 200.0) / 120.0) ** 2 < 1
    img = np.where(opening, 190.0, img)
    c, s = math.cos(math.radians(pang)), math.sin(math.radians(pang))
    u, v = (xx - cx) * c + (yy - cy) * s, -(xx - cx) * s + (yy - cy) * c
    rho2 = (u / pa) ** 2 + (v / pb) ** 2
    if iris_level is not None:
        iris = iris_level(np.maximum(np.sqrt(rho2) - 1.0, 0.0) * math.sqrt(pa * pb))
    img = np.where((np.hypot(xx - icx, yy - icy) < iris_r) & opening, iris, img)
    img = np.where((rho2 < 1) & opening, pupil, img)
    img = cv2.resize(img, (W, H), interpolation=cv2.INTER_AREA)
    yl, xl = np.mgrid[0:H, 0:W].astype(float)
    for a in LEDS:
        gx = cx + glint_frac * pa * math.cos(math.radians(a))
        gy = cy - glint_frac * pa * math.sin(math.radians(a))
        img += gamp * np.exp(-((xl - gx) ** 2 + (yl - gy) ** 2) / (2 * gsig**2))
    if blur:
        img = cv2.GaussianBlur(img, (0, 0), blur)
    img = img + rng.normal(0, noise, img.shape)
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)


@pytest.mark.parametrize(
    "kw",
    [
        {"gamp": 400.0},
        {"gamp": 3000.0},
        {"gamp": 400.0, "blur": 0.0},
        {"gamp": 400.0, "iris": 34.0},
        {"gamp": 400.0, "pa": 40.0, "iris_r": 95.0, "cx": 330.6, "cy": 190.3},
        {"gamp": 400.0, "pa": 22.0, "iris": 34.0, "iris_r": 60.0, "cx": 250.6, "cy": 230.3},
    ],
)
def test_pupil_under_a_dark_iris_with_saturated_glints_is_found(kw):
    """A pupil 10–14 DN (3–5 σ of the pixel noise) under a dark iris, four saturated glints
    just inside its edge: the ladder's first blob is the pupil itself, whose step to its
    surround is tens of standard errors of a difference of medians over thousands of pixels.
    Before: refused "pupil merged with iris: … only 3.3 σ of the pixel noise darker than its
    surround (need 5 σ …)" — the step judged by the pixel noise, not by its own — or (3000 DN
    glints) the core found inside the iris refused as not compact (solidity 0.80): the
    saturated glints' grown discs notched it. The same pupil with unsaturated glints
    (``gamp`` 80) was found."""
    d = detect(eye(**kw), led_azimuths_deg=LEDS)
    cx, cy = kw.get("cx", 320.0), kw.get("cy", 200.0)
    pa = kw.get("pa", 30.0)
    assert d.ok, d.failures
    assert math.dist(d.pupil.centre_px, (cx, cy)) < 0.5
    # the pupil, not the iris around it (its axes within 2 px of the drawn 2 pa)
    assert abs(d.pupil.axes_px[0] - 2 * pa) < 2.0 and abs(d.pupil.axes_px[1] - 2 * pa) < 2.0


def test_unsaturated_glints_control():
    """Control (passes before and after): the same pupil with unsaturated glints (80 DN)."""
    d = detect(eye(gamp=80.0), led_azimuths_deg=LEDS)
    assert d.ok, d.failures
    assert math.dist(d.pupil.centre_px, (320.0, 200.0)) < 0.5


@pytest.mark.parametrize("seed", [1, 2])
def test_pupil_ten_dn_under_its_iris_at_sigma_six_is_not_the_iris(seed):
    """A 52 × 44 px pupil 10 DN under a 134 px iris at σ 6 (1.7 σ of the pixel noise): the
    ladder fits the iris, whose interior averaged over 5 × 5 px shows the pupil only 7.6 σ of
    the averages' spread under its median (a core needs 8); over 11 × 11 px (half the least
    pupil such an iris holds) it stands 16 σ out, and the pupil is found inside. Before: ok
    with the iris (axes 134 px) as the pupil."""
    kw = {"cx": 390.2, "cy": 180.4, "pa": 26.0, "pb": 22.0, "pang": 40.0, "iris_r": 67.6}
    d = detect(eye(noise=6.0, gamp=400.0, seed=seed, **kw), led_azimuths_deg=LEDS)
    assert d.ok, d.failures
    # (σ 6: the edge points ≈ 2× as noisy as the module doc's σ 3 case; 1 px is the issue's)
    assert math.dist(d.pupil.centre_px, (390.2, 180.4)) < 1.0
    assert abs(d.pupil.axes_px[0] - 52.0) < 2.0 and abs(d.pupil.axes_px[1] - 44.0) < 2.0


@pytest.mark.parametrize("level", [170.0, 200.0])
def test_small_bright_pupil_dimmer_than_the_sclera_is_named(level):
    """A lit pupil (170 or 200 DN, radius 20 px) in a 100 DN iris, sclera 190: refused as a
    bright-pupil picture. Before: "no pupil (merged with the iris?)" — the bright blob was
    looked for only over the 97th percentile (the sclera's level) and only when larger than the
    cap on a glint's area (1280 px here; the pupil is 1257 px, the glints ~30)."""
    img = eye(pupil=level, iris=100.0, pa=20.0, iris_r=60.0, glint_frac=1.5, noise=3.0)
    d = detect(img, led_azimuths_deg=LEDS)
    assert not d.ok
    assert d.failures[0].startswith("no dark pupil: bright-pupil image?"), d.failures


@pytest.mark.parametrize("pa,gsig", [(12.0, 2.0), (10.0, 1.5)])
def test_bloom_beside_a_small_pupil_is_named(pa, gsig):
    """Four 3000 DN glints (σ 1.5–2 px, blooming to ~6 px) 6 px outside a 20–24 px pupil:
    filled with the pupil's dark they join its blob, whose outline then lies mostly on them.
    Refused naming the glints. Before: "no pupil: the dark blob has no sharp edge"."""
    img = eye(
        pupil=20.0,
        iris=110.0,
        pa=pa,
        iris_r=70.0,
        gamp=3000.0,
        gsig=gsig,
        glint_frac=(pa + 6.0) / pa,
    )
    d = detect(img, led_azimuths_deg=LEDS)
    if d.ok:  # found after all: then right
        assert math.dist(d.pupil.centre_px, (320.0, 200.0)) < 0.5
    else:
        assert d.failures[0].startswith("pupil hidden by glints"), d.failures
