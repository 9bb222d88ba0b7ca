"""Ground truth against independent estimates from the renders: the apparent pupil's centre
against the centroid of the pupil region the chief rays label, and each glint's position against
the centroid of the light that reached the sensor by reflection at the cornea alone (the fast
estimator's light paths), at several gaze angles."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy import ndimage

import eyelume
from eyelume.analysis.regions import region_masks
from eyelume.analysis.truth import eye_truth
from eyelume.compile import compile_scene
from eyelume.estimators.fast_run import trace_fast

FINE = {"sensor.cols": 348, "sensor.rows": 260}  # 0.13 mm pixels: centroids to ~0.1 px


def polygon_centroid(p: np.ndarray) -> tuple[float, float]:
    """Area centroid of a closed polygon (shoelace formula)."""
    x, y = p[:, 0], p[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    a = cross.sum() / 2
    return float(((x + xn) * cross).sum() / (6 * a)), float(((y + yn) * cross).sum() / (6 * a))


@pytest.mark.parametrize("gaze", [(0.0, 0.0), (20.0, 0.0), (0.0, 15.0), (-20.0, -10.0)])
def test_pupil_truth_matches_the_labelled_pupil(gaze):
    scene = eyelume.load_scene(
        "paper2005", {**FINE, "eye.gaze_horizontal_deg": gaze[0], "eye.gaze_vertical_deg": gaze[1]}
    )
    cs = compile_scene(scene)
    truth = eye_truth(cs)
    pupil = region_masks(cs)["pupil"]
    cy, cx = ndimage.center_of_mass(pupil)
    px, py = polygon_centroid(np.array(truth["pupil"]["edge_px"]))
    # the area centroid of the projected edge polygon vs the labelled pixels' centroid;
    # pixelisation of a ~55 px wide disc moves the labelled centroid by < 0.1 px
    assert truth["pupil"]["visible_fraction"] > 0.9
    assert np.hypot(px - cx, py - cy) < 0.25
    # the apparent centre (image of the 3D centre) sits inside the pupil, near the edge's mean
    x, y = truth["pupil"]["centre_px"]
    assert np.hypot(x - cx, y - cy) < 1.0


#: An astigmatic (~2.3 D at 30°), decentred and tilted anterior cornea (issue 15): its glints
#: lie 3.6–4.7 px from the symmetric cornea's here, so the 0.5 px check below resolves them.
TORIC = {
    "eye.cornea.radius_steep_mm": 7.4,
    "eye.cornea.axis_deg": 30.0,
    "eye.cornea.decentration_mm": [0.4, -0.3],
    "eye.cornea.tilt_deg": [1.0, 1.0],
}


@pytest.mark.slow
@pytest.mark.parametrize(("gaze", "cornea"), [((15.0, 10.0), {}), ((0.0, 0.0), TORIC)])
def test_glint_truth_matches_the_rendered_glints(gaze, cornea):
    scene = eyelume.load_scene(
        "paper2005",
        {
            **FINE,
            **cornea,
            "eye.gaze_horizontal_deg": gaze[0],
            "eye.gaze_vertical_deg": gaze[1],
        },
    )
    cs = compile_scene(scene)
    truth = eye_truth(cs)
    est = trace_fast(cs, 8, 1_500_000, 4)
    checked = 0
    for g in truth["glints"]:
        if g["centre_px"] is None or not g["visible"]:
            continue
        img = est.glint_images[g["led"]]
        cy, cx = ndimage.center_of_mass(img)
        # the chief ray meets the centre of the defocus blur disc of an aberration-free lens;
        # the disc is ~17 px wide here, its centroid noise < 0.1 px
        assert np.hypot(g["centre_px"][0] - cx, g["centre_px"][1] - cy) < 0.5, g
        checked += 1
    assert checked >= 3


def test_head_offset_moves_the_pupil_by_the_magnified_offset():
    """A 2 mm head offset moves the apparent pupil by 2 mm × |m| / pixel pitch on the picture
    (paraxial magnification 1.144, 0.529 mm pixels: 4.33 px), to within perspective (the pupil
    lies 3 mm behind the focused plane: < 2 %)."""
    base = eye_truth(compile_scene(eyelume.load_scene("paper2005")))["pupil"]["centre_px"]
    moved = eye_truth(
        compile_scene(eyelume.load_scene("paper2005", {"head_offset_mm": [2, -2, 0]}))
    )
    dx = moved["pupil"]["centre_px"][0] - base[0]
    dy = moved["pupil"]["centre_px"][1] - base[1]
    expected = 2.0 * 1.144 / (46.0 / 87)
    assert dx == pytest.approx(expected, rel=0.02) and dy == pytest.approx(expected, rel=0.02)


def test_a_glint_the_led_sends_no_light_to_is_not_visible(tmp_path):
    """A glint is 'visible' only where the LED's profile sends light toward the cornea: with a
    profile that is zero beyond 0.5° from the axis (a table), no glint's emission direction lies
    inside it, so none is visible and each says why; the same LEDs with the paper's profile show
    theirs. The glints' positions do not depend on the profile."""
    table = tmp_path / "pencil.csv"
    table.write_text("angle,rel\n0,1\n0.5,0\n90,0\n", encoding="utf-8")
    pencil = {"leds.profile.kind": "table", "leds.profile.table_csv": str(table)}
    lit = eye_truth(compile_scene(eyelume.load_scene("paper2005")))["glints"]
    dark = eye_truth(compile_scene(eyelume.load_scene("paper2005", pencil)))["glints"]
    assert all(g["visible"] for g in lit)
    for a, b in zip(lit, dark, strict=True):
        assert b["centre_px"] == a["centre_px"]
        assert not b["visible"] and "sends no light" in b["reason"], b


def test_nothing_is_visible_behind_an_opaque_element():
    """A plate with R = T = 0 between the eye and the camera passes no light: the truth keeps the
    positions but sees neither the pupil nor any glint (a fresh user found them all 'visible'
    while the render put 0 W on the sensor); a clear plate there keeps them visible."""
    plate = (
        '{kind="plate", position_mm=[0,0,40], thickness_mm=1, glass="N-BK7", semi_diameter_mm=25%s}'
    )
    black = ', front={coating={model="fixed", reflectance=0, transmittance=0}}'
    seen = {}
    for name, extra in (("clear", ""), ("black", black)):
        sc = eyelume.load_scene("paper2005", {"elements": [_toml_table(plate % extra)]})
        seen[name] = eye_truth(compile_scene(sc), ghosts=False)
    assert seen["clear"]["pupil"]["visible_fraction"] > 0.9
    assert all(g["visible"] for g in seen["clear"]["glints"])
    assert seen["black"]["pupil"]["visible_fraction"] == 0.0
    for g in seen["black"]["glints"]:
        assert not g["visible"] and "opaque element" in g["reason"], g


def _toml_table(text: str) -> dict:
    import tomllib

    return tomllib.loads(f"t = {text}")["t"]


@pytest.mark.slow
def test_the_suns_corneal_glint_is_where_the_sunlight_render_draws_it():
    """With ``ambient.sun`` the cornea reflects the sun (the renderer traces it as a point
    source 10 m away): a saturated spot no LED's glint is. ``truth.json``'s ``sun_glint`` is
    found as an LED's glint is, for that source; checked against the sunlight's own render
    (paper2005, the sun 30° up): the spot's background-subtracted centroid over 9 × 9 px lies
    within 0.3 px of it (the spot spans ~3 px; a centroid of a pixel-sampled blur is biased by
    well under half a pixel, and its Monte Carlo noise at 2 samples per pixel is ~0.05 px: the
    spot is 170 × its surround). Without a sun there is no such key."""
    from eyelume.render import RenderOptions, render

    sc = eyelume.load_scene(
        "paper2005",
        {
            "ambient.sun.elevation_deg": 30.0,
            "ambient.sun.azimuth_deg": 0.0,
            "sensor.quantum_efficiency": "nir-global-shutter",
        },
    )
    cs = compile_scene(sc)
    sun = eye_truth(cs)["sun_glint"]
    assert sun["visible"] and sun["on_cornea"], sun
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the sunlight's band traced at 800 nm: a focus warning
        r = render(cs, RenderOptions(estimator="fast", samples_per_pixel=2, seed=0))
    a = r.ambient.eye_image
    x0, y0 = sun["centre_px"]
    xi, yi = round(x0), round(y0)
    w = a[yi - 4 : yi + 5, xi - 4 : xi + 5]
    base = np.median(a[yi - 8 : yi + 9, xi - 8 : xi + 9])
    assert w.max() > 50 * base
    ww = np.clip(w - base, 0.0, None)
    yy, xx = np.mgrid[yi - 4 : yi + 5, xi - 4 : xi + 5]
    c = ((ww * xx).sum() / ww.sum(), (ww * yy).sum() / ww.sum())
    assert math.hypot(c[0] - x0, c[1] - y0) < 0.3, (c, sun["centre_px"])
    no_sun = eye_truth(compile_scene(eyelume.load_scene("paper2005")))
    assert "sun_glint" not in no_sun
