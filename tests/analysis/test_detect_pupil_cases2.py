"""Session 20's new user's pupil cases (issue 13), made up here: a pupil a few σ of the pixel
noise under a dark iris, lashes touching or crossing the pupil, a dark mole on the skin.

:func:`eye` draws their 480 × 360 frame: skin, an eye opening of sclera, an iris disc and a
pupil disc (drawn 4× finer and averaged down: anti-aliased edges), four saturated glints 30 px
from the pupil's centre, optional lashes (2 px dark lines from above the iris) and Gaussian
pixel noise, rounded to 8 bits. Each test asserts the right answer or the refusal naming the
cause, and each failed on the code before session 21 (say which in its docstring).

Tolerance (0.5 px): the faintest pupil here is 8 DN under its iris at σ 4; the edge is read on
the picture smoothed by a 2 px Gaussian (noise ≈ 0.14 σ = 0.6 DN) where the edge's slope is ≈
8 DN / 5 px, so each edge point is ≈ 0.4 px off, correlated over ~4 px of the ~140 px outline:
the centre is ≈ 0.1 px off. 0.5 px is 5× that and half the 1 px the issue asks for.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from eyelume.analysis.tracking import detect

H, W, S = 360, 480, 4


def eye(  # noqa: PLR0913 - each option is one aspect of the made-up eye
    cx=200.6,
    cy=150.2,
    pupil_r=22.0,
    pupil=20.0,
    iris=100.0,
    iris_r=70.0,
    noise=3.0,
    seed=1,
    lashes=0,
    lash=8.0,
    mole=None,
):
    """The frame (uint8; see the module doc). ``mole``: (x, y, radius, level) of a dark disc
    on the skin."""
    rng = np.random.default_rng(seed)
    xx = ((np.arange(W * S) + 0.5) / S - 0.5)[None, :]
    yy = ((np.arange(H * S) + 0.5) / S - 0.5)[:, None]
    img = np.full((H * S, W * S), 160.0)
    opening = ((xx - cx) / (iris_r * 2.4)) ** 2 + ((yy - cy) / (iris_r * 1.3)) ** 2 < 1
    img = np.where(opening, 190.0, img)
    r = np.hypot(xx - cx, yy - cy)
    img = np.where((r < iris_r) & opening, iris, img)
    img = np.where(r < pupil_r, pupil, img)
    if mole is not None:
        mx, my, mr, level = mole
        img = np.where(np.hypot(xx - mx, yy - my) < mr, level, img)
    img = cv2.resize(img, (W, H), interpolation=cv2.INTER_AREA)
    yl, xl = np.mgrid[0:H, 0:W].astype(float)
    for a in (0, 90, 180, 270):
        gx, gy = cx + 30 * math.cos(math.radians(a)), cy - 30 * math.sin(math.radians(a))
        img += 400 * np.exp(-((xl - gx) ** 2 + (yl - gy) ** 2) / (2 * 1.4**2))
    for k in range(lashes):
        x0, y0 = int(cx - 90 + k * 9), int(cy - iris_r * 0.9)
        end = (x0 + int(rng.integers(-8, 8)), y0 + int(rng.integers(5, 45)))
        cv2.line(img, (x0, y0 - 25), end, lash, 2)
    img = img + rng.normal(0, noise, img.shape)
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)


@pytest.mark.parametrize(
    "pupil,iris,noise,seed",
    [(22, 32, 2.0, 1), (18, 26, 4.0, 2), (20, 26, 1.5, 4), (20, 30, 2.5, 3)],
)
def test_pupil_a_few_sigma_under_a_dark_iris_is_found(pupil, iris, noise, seed):
    """A pupil 2–5 σ of the pixel noise under a dark iris (30 px iris-to-pupil step in the
    sclera's 190 DN): the ladder cannot tell the two apart and fits the iris, which holds the
    pupil as a darker core; the core is then looked for inside it (averaged over many pixels it
    stands tens of standard errors out) and fitted. Before: refused as "pupil merged with iris"
    although the message had found the pupil."""
    d = detect(
        eye(pupil=pupil, iris=iris, noise=noise, seed=seed), led_azimuths_deg=(0, 90, 180, 270)
    )
    assert d.ok, d.failures
    assert math.dist(d.pupil.centre_px, (200.6, 150.2)) < 0.5
    # the pupil's outline (44 px across), not the iris's (140 px)
    assert 40 < d.pupil.axes_px[0] < 48


@pytest.mark.parametrize(
    "pupil,iris,cy,lashes,seed",
    [(20.0, 45.0, 150.2, 20, 51), (25.0, 70.0, 130.4, 24, 52)],
)
def test_pupil_with_lashes_darker_than_it_across_its_edge_is_found(pupil, iris, cy, lashes, seed):
    """Twenty-odd lashes (2 px strokes at 8 DN, darker than the 20–25 DN pupil) hang from above
    the iris, some into the pupil: at full resolution they join the pupil's blob (not compact),
    and the darkest chain of the ladder may be a lash over the sclera. The strokes are cut off
    by an opening and the ladder walked past the refused chain. Before: "no pupil: the darkest
    blob (… px) is not compact"."""
    img = eye(cy=cy, pupil=pupil, iris=iris, lashes=lashes, seed=seed)
    d = detect(img, led_azimuths_deg=(0, 90, 180, 270))
    # (the pupil only: a lash across a glint is the glints' matter)
    assert not [m for m in d.failures if "pupil" in m.split(":")[0]], d.failures
    assert d.pupil is not None
    assert math.dist(d.pupil.centre_px, (200.6, cy)) < 0.5


@pytest.mark.parametrize("radius", [12.0, 22.0])
def test_a_mole_darker_than_the_pupil_is_not_the_pupil(radius):
    """A dark mole (5 DN, darker than the 20 DN pupil) on the skin 265 px from the eye: the
    ladder's darkest chain, compact and whole, but with none of the picture's glints within 6
    of its radii; the pupil, walked past to, has four beside it. Before: answered with the
    mole as the pupil (without LEDs ``ok``)."""
    img = eye(mole=(420.0, 300.0, radius, 5.0), seed=100)
    for leds in (None, (0, 90, 180, 270)):
        d = detect(img, led_azimuths_deg=leds)
        assert d.ok, d.failures
        assert math.dist(d.pupil.centre_px, (200.6, 150.2)) < 0.5
