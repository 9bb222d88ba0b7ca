"""LEDs anywhere (issue: any headset): a ring about any axis, aimed at a point, or LEDs placed
one by one — each against its definition written out here, and the paper's ring unchanged."""

from __future__ import annotations

import math

import numpy as np
import pytest

from eyelume.errors import GeometryError, SceneError
from eyelume.estimators.closed_form import configuration_irradiance, eye_plane_irradiance
from eyelume.scene.io import apply_overrides, load_scene
from eyelume.scene.sources import led_poses


def test_paper_ring_is_fig8():
    leds = load_scene("paper2005").leds
    c, a = led_poses(leds)
    th = math.radians(leds.pitch_deg)
    for k, phi in enumerate(np.radians(leds.azimuths())):
        assert np.array_equal(
            c[k], [leds.height_mm * math.cos(phi), leds.height_mm * math.sin(phi), 70.0]
        )
        assert np.allclose(
            a[k], [-math.sin(th) * math.cos(phi), -math.sin(th) * math.sin(phi), -math.cos(th)],
            atol=0.0, rtol=0.0,
        )  # fmt: skip


def test_aim_point_on_the_axis_equals_the_pitch():
    """Aiming every LED at the axis point where the pitched axes cross gives the same axes."""
    scene = load_scene("paper2005")
    y, z, th = 30.0, 70.0, 20.0
    crossing = z - y / math.tan(math.radians(th))
    aimed = apply_overrides(scene, {"leds.aim_at_mm": [0.0, 0.0, crossing]}).leds
    c0, a0 = led_poses(scene.leds)
    c1, a1 = led_poses(aimed)
    assert np.allclose(c0, c1, atol=1e-12) and np.allclose(a0, a1, atol=1e-12)


def test_ring_about_another_axis():
    """A ring of 6 about an axis tilted 30° down toward −y, centred 2 mm below the vertex,
    aimed at the corneal vertex: each LED at Y from the axis, Z along it, axis to the vertex."""
    n = np.array([0.0, -math.sin(math.radians(30)), math.cos(math.radians(30))])
    centre = np.array([0.0, -2.0, 0.0])
    scene = apply_overrides(
        load_scene("vr-offaxis"),
        {
            "leds.count": 6,
            "leds.ring_axis": n.tolist(),
            "leds.ring_centre_mm": centre.tolist(),
            "leds.aim_at_mm": [0.0, 0.0, 0.0],
        },
    )
    c, a = led_poses(scene.leds)
    rel = c - centre
    along = rel @ n
    across = np.linalg.norm(rel - np.outer(along, n), axis=1)
    assert np.allclose(along, scene.leds.distance_mm, atol=1e-12)
    assert np.allclose(across, scene.leds.height_mm, atol=1e-12)
    assert np.allclose(a, -c / np.linalg.norm(c, axis=1, keepdims=True), atol=1e-12)
    # evenly spaced: neighbours 60° apart about the axis
    u = rel - np.outer(along, n)
    cosines = np.sum(u * np.roll(u, -1, axis=0), axis=1) / scene.leds.height_mm**2
    assert np.allclose(cosines, 0.5, atol=1e-12)


def test_leds_one_by_one_replicate_the_ring():
    """The paper's ring given LED by LED (positions and directions) is the same system: the same
    compiled LED table and the same closed-form eye-plane irradiance."""
    from eyelume.compile import compile_scene

    scene = load_scene("paper2005")
    c, a = led_poses(scene.leds)
    one_by_one = apply_overrides(
        scene, {"leds.positions_mm": c.tolist(), "leds.directions": a.tolist()}
    )
    p0 = compile_scene(scene).led
    p1 = compile_scene(one_by_one).led
    assert np.allclose(p0.points, p1.points, atol=1e-12)
    assert np.allclose(p0.axes, p1.axes, atol=1e-12)
    e0 = eye_plane_irradiance(scene)
    e1 = eye_plane_irradiance(one_by_one)
    assert np.allclose(e0, e1, rtol=1e-12, atol=0.0)
    # there is no ring to vary
    with pytest.raises(GeometryError, match="one by one"):
        configuration_irradiance(one_by_one, [20.0, 30.0], [70.0, 70.0], [10.0, 20.0])
    with pytest.raises(GeometryError, match="one by one"):
        eye_plane_irradiance(one_by_one, height_mm=40.0)


@pytest.mark.parametrize(
    ("overrides", "words"),
    [
        ({"leds.positions_mm": [[1.0, 2.0, 20.0]]}, "positions_mm has 1 entries"),
        ({"leds.count": 1, "leds.positions_mm": [[1.0, 2.0, 20.0]]}, "need aim_at_mm"),
        (
            {
                "leds.count": 1,
                "leds.positions_mm": [[1.0, 2.0, 20.0]],
                "leds.aim_at_mm": [1.0, 2.0, 20.0],
            },
            "aim_at_mm equals",
        ),
        ({"leds.ring_axis": [0.0, 0.0, 0.0]}, "ring_axis"),
    ],
)
def test_bad_led_placements_are_one_line_errors(overrides, words):
    with pytest.raises(SceneError) as e:
        apply_overrides(load_scene("paper2005"), overrides)
    assert words in str(e.value) and "\n" not in str(e.value)


def test_leds_one_by_one_without_count_are_as_many_as_their_positions():
    """A scene file placing six LEDs by positions_mm and no count has six LEDs (the ring's
    default count of 4 refused it: "positions_mm has 6 entries but count is 4", a new user's
    finding); a count that disagrees is still refused."""
    from eyelume.scene.model import LedArray

    ring = [[20.0 * np.cos(a), 20.0 * np.sin(a), 12.0] for a in np.radians(np.arange(6) * 60.0)]
    leds = LedArray(positions_mm=ring, aim_at_mm=[0.0, 0.0, 0.0])
    assert leds.count == 6
    with pytest.raises(ValueError, match="positions_mm has 6 entries but count is 5"):
        LedArray(positions_mm=ring, aim_at_mm=[0.0, 0.0, 0.0], count=5)
