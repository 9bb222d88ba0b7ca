"""Glints on the pupil's edge (issue 13): a saturated glint straddling the blurred step from the
dark pupil to the iris is centred over the edge's own profile as its background
(``detect._edge_backed_glints``), not over one background level, which pulled it toward the
iris.

The pictures are the tests' (:func:`draw_eye`, truth exact): an oval pupil 112 × 96 px at 30°,
four saturated Gaussian glints (σ 1.5–4 px) on its outline or σ inside or outside it, the
optics' blur σ 1–3 px, noise σ 8 DN. A glint of the same picture away from the edge is found
within 0.1 px (``test_detect.py``); on the edge, before this change, 0.23–1.24 px off, every
frame answered ``ok``; now ≤ 0.11 px. The bound, 0.25 px: the edge's profile is a median over
the outline, so the glint's own spot and the iris's shading under it are not in it; on the
round pupils the change was chosen on (``_EDGE_GLINT_SKIRT_PX``), ≤ 0.14 px.
"""

from __future__ import annotations

import importlib
import math

import numpy as np
import pytest

from eyelume.analysis.tracking import detect
from tests.analysis.test_detect import CENTRE, LEDS, EyePicture, draw_eye

AXES, ANGLE = (112.0, 96.0), 30.0


def _on_outline(inset: float) -> list[tuple[float, float]]:
    """Each LED's glint on the pupil's outline (``inset`` px inside it along the ray from the
    centre) in the LED's direction (90° = picture up)."""
    a, b, th = AXES[0] / 2, AXES[1] / 2, math.radians(ANGLE)
    out = []
    for az in LEDS:
        ux, uy = math.cos(math.radians(az)), -math.sin(math.radians(az))
        # the ray's direction in the ellipse's own frame, and its distance to the outline
        lx, ly = ux * math.cos(th) + uy * math.sin(th), -ux * math.sin(th) + uy * math.cos(th)
        r = 1.0 / math.sqrt((lx / a) ** 2 + (ly / b) ** 2) - inset
        out.append((CENTRE[0] + r * ux, CENTRE[1] + r * uy))
    return out


@pytest.mark.parametrize("blur", [1.0, 3.0])
@pytest.mark.parametrize("sigma", [1.5, 2.5, 4.0])
@pytest.mark.parametrize("inset_frac", [-0.5, 0.0, 0.5])
def test_saturated_glint_on_the_pupil_edge_is_centred(blur, sigma, inset_frac):
    glints = _on_outline(inset_frac * 2.0 * sigma)
    for seed in (1, 2):
        picture = EyePicture(axes=AXES, angle=ANGLE, glints=glints, glint_sigma=sigma,
                             blur=blur, seed=seed)  # fmt: skip
        d = detect(draw_eye(picture), led_azimuths_deg=LEDS)
        assert d.ok, d.failures
        assert sorted(g.led for g in d.glints if g.led is not None) == [0, 1, 2, 3]
        for g in d.glints:
            tx, ty = glints[g.led]
            err = math.hypot(g.centre_px[0] - tx, g.centre_px[1] - ty)
            assert err <= 0.25, (blur, sigma, inset_frac, seed, g.led, err)


def test_glints_off_the_edge_keep_their_centroid():
    """Glints well inside the pupil (the tests' default picture) are not touched: the region
    the edge background would weigh does not reach the outline."""
    d = detect(draw_eye(), led_azimuths_deg=LEDS)
    assert d.ok
    D = importlib.import_module("eyelume.analysis.tracking.detect")
    fit_glints = [g.centre_px for g in d.glints]
    # the same answer with the correction switched off by a skirt that reaches nothing
    old = D._EDGE_GLINT_SKIRT_PX
    try:
        D._EDGE_GLINT_SKIRT_PX = -1e9
        d0 = detect(draw_eye(), led_azimuths_deg=LEDS)
    finally:
        D._EDGE_GLINT_SKIRT_PX = old
    assert [g.centre_px for g in d0.glints] == fit_glints


@pytest.mark.parametrize("lid_offset", [-2.0, 0.0, 1.0])
def test_a_lid_beside_a_glint_on_the_edge_leaves_it_as_found(lid_offset):
    """The skin of a lid whose edge runs by the top glint (``lid_offset`` px below its centre):
    the edge's median profile does not hold it, so the top glint is not centred over it and
    keeps the centroid ``_blob`` found (≤ 0.5 px); the other three are centred over the
    profile. Centred over it regardless, the top glint moved 1.1–1.24 px off."""
    D = importlib.import_module("eyelume.analysis.tracking.detect")
    glints = _on_outline(0.0)
    picture = EyePicture(axes=AXES, angle=ANGLE, glints=glints, glint_sigma=2.0, blur=1.7,
                         seed=3, eyelid_y=glints[1][1] + lid_offset)  # fmt: skip

    def found():
        d = detect(draw_eye(picture), led_azimuths_deg=LEDS)
        assert d.ok, d.failures
        return {g.led: g.centre_px for g in d.glints if g.led is not None}

    got = found()
    err = {k: math.hypot(c[0] - glints[k][0], c[1] - glints[k][1]) for k, c in got.items()}
    assert sorted(err) == [0, 1, 2, 3]
    assert err[1] <= 0.5, err
    assert max(err[k] for k in (0, 2, 3)) <= 0.25, err
    old = D._EDGE_GLINT_SKIRT_PX
    try:
        D._EDGE_GLINT_SKIRT_PX = -1e9  # no glint re-centred
        as_found = found()
    finally:
        D._EDGE_GLINT_SKIRT_PX = old
    assert got[1] == as_found[1]


def test_the_warning_says_which_glints_were_centred_over_the_edge():
    glints = _on_outline(0.0)
    picture = EyePicture(axes=AXES, angle=ANGLE, glints=glints, glint_sigma=2.5, seed=1)
    d = detect(draw_eye(picture), led_azimuths_deg=LEDS)
    edge = [m for m in d.failures if "on the pupil edge" in m]
    assert len(edge) == 4, d.failures
    assert all(m.startswith("warning") and "centred over the edge's profile" in m for m in edge)


def _eight_bit(iris: float, shade: float, sigma: float, seed: int = 5):
    """The oval pupil of this module in an 8-bit picture (a new user's, session 28): pupil 12,
    iris ``iris``, skin 230 of 255, the iris lit unevenly (± ``shade`` DN as the cosine of the
    direction from the pupil, brightest near LED 0), four glints of σ ``sigma`` on the
    outline clipped at 255, noise σ 2 DN."""
    glints = _on_outline(0.0)
    img = draw_eye(EyePicture(axes=AXES, angle=ANGLE, glints=[], noise=0.0, blur=1.5))
    lv = np.interp(img.astype(float), [30, 170, 500], [12, iris, 230])
    yy, xx = np.mgrid[: lv.shape[0], : lv.shape[1]]
    ang = np.arctan2(-(yy - CENTRE[1]), xx - CENTRE[0])
    lv += ((lv > 60) & (lv < 225)) * shade * np.cos(ang - 0.3)
    for gx, gy in glints:
        lv += 3 * 255 * np.exp(-((xx - gx) ** 2 + (yy - gy) ** 2) / (2 * sigma**2))
    lv = np.minimum(lv, 255) + np.random.default_rng(seed).normal(0, 2.0, lv.shape)
    return np.rint(np.clip(lv, 0, 255)).astype(np.uint8), glints


@pytest.mark.parametrize(
    ("iris", "shade", "sigma"), [(200, 0, 2.5), (160, 0, 2.5), (160, 44, 1.0), (160, 44, 1.5)]
)
def test_a_bright_or_unevenly_lit_iris_does_not_move_the_glints(iris, shade, sigma):
    """A new user's pictures (session 28) that a first version of the re-centring moved: an
    iris at 160–200 of 255 leaves a clipped glint little room over it on the iris side, so
    weighing its top by clip − B pulled the glints 0.41–0.72 px toward the pupil; an iris lit
    unevenly (± 44 DN), read at the profile's median level, pushed LED 0's glint 0.95–1.21 px
    out. Now the iris's level is fitted about each glint and the re-centring is kept to irides
    whose step is ≤ 0.3 of the room to the clip; these glints stay within 0.5 px (they were
    0.07–0.31 px with one background level)."""
    img, glints = _eight_bit(iris, shade, sigma)
    d = detect(img, led_azimuths_deg=LEDS)
    assert d.ok, d.failures
    err = {
        g.led: math.hypot(g.centre_px[0] - glints[g.led][0], g.centre_px[1] - glints[g.led][1])
        for g in d.glints
        if g.led is not None
    }
    assert sorted(err) == [0, 1, 2, 3]
    assert max(err.values()) <= 0.5, err
