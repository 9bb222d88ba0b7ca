"""Issue 13: a glint cut by the cornea's rim (truth.json's ``at_rim`` / ``rim``).

``paper2005`` at gaze (30°, −20°): LED 2's chief ray reflects 9 µm past the limbus (no glint by
the chief ray alone: "off the cornea"), yet the rays through about half of the camera's
25 mm entrance pupil reflect off the cap and form a partial spot, which the detector finds; LED
1's chief ray reflects on the cap 0.2 mm inside the limbus, but a fifth of its rays fall past it.
The truth's rim model (five traced stop points, a second-order model integrated over the stop,
:func:`eyelume.analysis.truth._rim_glint`) is checked here against tracing every point of a
25 × 25 grid over the stop.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import eyelume
from eyelume.analysis import truth as T
from eyelume.compile import compile_scene
from eyelume.kernels import geometry as G


@pytest.fixture(scope="module")
def turned():
    sc = eyelume.load_scene(
        "paper2005", {"eye.gaze_horizontal_deg": 30.0, "eye.gaze_vertical_deg": -20.0}
    )
    cs = compile_scene(sc)
    return cs, T.eye_truth(cs)


def test_rim_glint_reported_not_silently_off_the_cornea(turned):
    _, t = turned
    g = {e["led"]: e for e in t["glints"]}
    # LED 2: the chief ray's reflection is past the limbus (as before: on_cornea False, no
    # centre_px, counts unchanged) but the rim cuts a partial spot that does exist
    assert not g[2]["on_cornea"] and g[2]["centre_px"] is None and not g[2]["visible"]
    assert g[2]["at_rim"]
    rim = g[2]["rim"]
    assert rim["beyond_rim_mm"] > 0.0
    assert 0.0 < rim["aperture_share"] < 1.0
    assert rim["beyond_rim_mm"] < rim["reach_mm"]  # within the aperture's reach of the rim
    assert rim["centre_px"] is not None and rim["visible"]
    assert "cut by the cornea's rim" in g[2]["reason"]
    # the partial spot's centroid lies toward the part formed, away from the whole spot's
    assert rim["bias_px"] == pytest.approx(
        math.dist(rim["centre_px"], rim["full_centre_px"]), abs=1e-12
    )
    assert rim["bias_px"] > 0.0
    # LED 1: on the cap (its chief ray inside the limbus) but within reach of the rim
    assert g[1]["on_cornea"] and g[1]["visible"] and g[1]["at_rim"]
    assert g[1]["rim"]["beyond_rim_mm"] < 0.0 < g[1]["rim"]["aperture_share"] < 1.0
    # LEDs 0 and 3: whole glints
    for k in (0, 3):
        assert g[k]["on_cornea"] and not g[k]["at_rim"] and g[k]["rim"] is None
    assert (t["glints_on_cornea"], t["glints_visible"], t["glints_at_rim"]) == (3, 3, 2)


def test_no_rim_glint_at_primary_gaze():
    cs = compile_scene(eyelume.load_scene("paper2005"))
    t = T.eye_truth(cs)
    assert t["glints_at_rim"] == 0
    assert all(g["on_cornea"] and not g["at_rim"] and g["rim"] is None for g in t["glints"])


def _traced(cs, led, n_grid: int):
    """Every point of an n × n grid over the stop traced (no model): the share of them whose
    reflection toward ``led`` lies on the cap, and the mean sensor point (px) of those."""
    v = T._view(cs, cs.camera)
    cam, cornea = v.cam, v.cornea
    r_cap = math.sqrt(cs.sf[cornea, G.RMAX2])
    to_led = led - v.turned(np.array([0.0, 0.0, -cs.scene.eye.surfaces[0].radius_mm]))
    n = to_led / np.linalg.norm(to_led)
    g1, g2 = T._basis(n)

    def mirror(t, start):
        def residual(s):
            ray = T._stop_ray(cs, cam, s[0], s[1], *t)
            ray = None if ray is None else T._off_cornea(cs, cornea, *ray, sf=v.open_sf)
            return T._miss(ray, led, n, g1, g2)

        s = T._solve(residual, start)
        hit = T._off_cornea(cs, cornea, *T._stop_ray(cs, cam, *s, *t), sf=v.open_sf)
        return s, math.hypot(*G.to_local(v.open_sf, cornea, *hit[0])[:2])

    c_img = v.image_of(v.turned(np.array([0.0, 0.0, -3.9])))
    s0, _ = mirror((0.0, 0.0), c_img - 0.05 * abs(v.par_m) * led[:2])
    u = (np.arange(n_grid) + 0.5) / n_grid * 2 - 1
    a = cam.stop_radius
    got = [mirror((a * x, a * y), s0) for y in u for x in u if x * x + y * y <= 1]
    on = np.array([rho <= r_cap for _, rho in got])
    part = np.array([s for s, _ in got])[on].mean(axis=0)
    return float(on.mean()), T.sensor_to_pixel(cs, *part), len(got)


@pytest.mark.parametrize("k", [1, 2])
def test_rim_model_matches_tracing_the_whole_stop(turned, k):
    """The model's share of the stop and the partial spot's centroid against tracing all 489
    points of a 25 × 25 grid over the stop: the share within the grid's resolution (2 points'
    weight), the centroid within 0.05 px (a tenth of the detector's 0.5 px precision)."""
    cs, t = turned
    rim = {e["led"]: e for e in t["glints"]}[k]["rim"]
    share, centre, count = _traced(cs, cs.led.points[cs.led_indices.index(k)], 25)
    assert abs(share - rim["aperture_share"]) <= 2 / count
    assert math.dist(centre, rim["centre_px"]) <= 0.05
