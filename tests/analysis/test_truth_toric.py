"""Glints of an astigmatic (toric) and of a decentred anterior cornea against the convex-mirror
equation (issue 15: "a toric cornea's two glint magnifications against the mirror equation in
each meridian").

The anterior cornea is a convex mirror. In each principal meridian of an astigmatic one
(radius R_flat along the flat meridian, at TABO ``axis_deg``, R_steep across it) a point source
at distance s in front of the vertex and H from the axis *in that meridian's plane* has, by the
mirror equation 1/s′ − 1/s = 1/f with f = R/2 (virtual image behind the mirror), its glint —
the virtual image — at depth s′ = s f / (s + f) behind the vertex and H′ = m H from the axis,
m = f / (s + f): paraxial optics separates into the two meridians, so a source in the flat
meridian's plane is imaged with f_flat = R_flat/2, one in the steep meridian's plane with
f_steep = R_steep/2. The truth (``eyelume.analysis.truth``: the chief ray the real cornea —
the compiled quadric, its intersection and normal — reflects to the LED) must put each glint
where the camera's chief ray through that virtual image point lands on the sensor. The camera
(paper2005's Double Gauss, entrance pupil 175 mm away on the eye's axis) is the same for both,
so its magnification and distortion cancel in the comparison.

Tolerance: the mirror equation is paraxial; the real reflection differs at third order, by a
relative amount of the order of the squared ray angles — the LEDs sit 3° off the axis and the
reflection points ~0.1 mm from the vertex (h/R ≈ 0.015), so (3°)² ≈ 2.7·10⁻³ bounds it; the
test takes 3·10⁻³ of each glint's offset from the axis image. The meridians' focal lengths
differ by 8 % (R 7.8 and 7.2 mm), so a glint imaged with the wrong meridian's f misses by ~25
times the tolerance (checked, so the test can fail).

Decentration: moving a mirror by d across its axis is moving the source by −d relative to it,
so the virtual image moves to m (L − d) + d: by d (1 − m) (the rotationally symmetric cornea,
decentred (0.3, −0.2) mm).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from eyelume.analysis.truth import _led_in_view, _view, eye_truth
from eyelume.compile import compile_scene
from eyelume.kernels import geometry as G
from eyelume.scene.io import apply_overrides, load_scene

S_MM = 40.0  # LEDs' distance in front of the corneal vertex (paper2005's camera lies 175 mm away)
ALPHA = math.radians(3.0)  # their angle off the eye's axis
R_FLAT, R_STEEP = 7.8, 7.2  # paper2005's anterior cornea radius, and a steep meridian (~3.6 D)
TOL = 3e-3


def _leds_along(axis_deg: float) -> list[list[float]]:
    """Four LEDs: ± along the flat meridian (TABO axis_deg), ± along the steep one."""
    th = math.radians(axis_deg)
    h = S_MM * math.tan(ALPHA)
    dirs = [(math.cos(th), math.sin(th)), (-math.sin(th), math.cos(th))]
    return [[sign * h * u, sign * h * v, S_MM] for u, v in dirs for sign in (1.0, -1.0)]


def _scene(cornea: dict, axis_deg: float = 0.0, which: str = "right"):
    over = {f"eye.cornea.{k}": v for k, v in cornea.items()}
    return apply_overrides(
        load_scene("paper2005"),
        {
            **over,
            "eye_pose.which": which,
            "leds.positions_mm": _leds_along(axis_deg),
            "leds.aim_at_mm": [0.0, 0.0, 0.0],
            "leds.body_diameter_mm": 1.0,
        },
    )


def _mirror_image(led: np.ndarray, vertex: np.ndarray, focal_mm: float) -> np.ndarray:
    """The convex mirror's virtual image of point ``led`` (camera frame = world here: the eye's
    axis is +z, its vertex at ``vertex``): H′ = m H, depth s′ behind the vertex."""
    vertex = np.asarray(vertex, dtype=float)
    rel = led - vertex
    s = rel[2]
    m = focal_mm / (s + focal_mm)
    return vertex + np.array([m * rel[0], m * rel[1], -s * m])


def _glint_and_prediction(cs, focal_for_led, vertex=(0.0, 0.0, 0.0)):
    truth = eye_truth(cs, ghosts=False)
    v = _view(cs, cs.camera)
    got, want = [], []
    for k, led in enumerate(cs.led.points):
        got.append(truth["glints"][k]["centre_px"])
        image = _mirror_image(led, vertex, focal_for_led[k])
        want.append(_led_in_view(v, k, image)["centre_px"])
    return np.array(got), np.array(want)


@pytest.mark.parametrize(("axis_deg", "which"), [(0.0, "right"), (30.0, "right"), (30.0, "left")])
def test_toric_glints_follow_the_mirror_equation_in_each_meridian(axis_deg, which):
    scene = _scene({"radius_steep_mm": R_STEEP, "axis_deg": axis_deg}, axis_deg, which)
    cs = compile_scene(scene)
    cornea = cs.surface_names.index("anterior cornea")
    assert cs.si[cornea, G.SHAPE] == G.SHAPE_QUADRIC
    focal = [R_FLAT / 2, R_FLAT / 2, R_STEEP / 2, R_STEEP / 2]
    got, want = _glint_and_prediction(cs, focal)
    # the axis's image (the LEDs lie in ± pairs about it): each glint's offset from it
    centre = want.mean(axis=0)
    for k in range(4):
        offset = np.linalg.norm(want[k] - centre)
        assert offset > 0.2  # px: a measurable glint displacement
        assert np.linalg.norm(got[k] - want[k]) <= TOL * offset, (k, got[k], want[k])
    # the test can fail: with the meridians swapped the glints miss by far more
    _, swapped = _glint_and_prediction(cs, focal[2:] + focal[:2])
    for k in range(4):
        offset = np.linalg.norm(want[k] - centre)
        assert np.linalg.norm(got[k] - swapped[k]) > 10 * TOL * offset


def test_each_meridian_magnifies_by_its_own_focal_length():
    """The glint pair along each meridian spans m = f/(s + f) of the LED pair, f = R/2 of that
    meridian: their ratio (flat over steep) is m_flat / m_steep, the camera's scale cancelling
    (both pairs equally far off the axis)."""
    cs = compile_scene(_scene({"radius_steep_mm": R_STEEP, "axis_deg": 0.0}))
    got = np.array([g["centre_px"] for g in eye_truth(cs, ghosts=False)["glints"]])
    flat = np.linalg.norm(got[0] - got[1])
    steep = np.linalg.norm(got[2] - got[3])
    s = cs.led.points[0][2]
    m = [f / (s + f) for f in (R_FLAT / 2, R_STEEP / 2)]
    # also the camera's depth: each virtual image lies s′ = s m behind the vertex, seen from
    # the entrance pupil at z_ep, so its apparent size scales as 1/(z_ep + s′)
    z_ep = cs.camera.entrance_pupil_z
    want = (m[0] / (z_ep + s * m[0])) / (m[1] / (z_ep + s * m[1]))
    assert flat / steep == pytest.approx(want, rel=2 * TOL)
    assert abs(flat / steep - 1.0) > 0.05  # the two meridians do differ


def test_symmetric_limit_compiles_to_the_same_conicoid():
    """R_steep = R_flat (and no decentration) is the rotationally symmetric cornea: the same
    surface table, float for float, as no ``eye.cornea`` at all."""
    base = load_scene("paper2005")
    same = apply_overrides(base, {"eye.cornea.radius_steep_mm": 7.8, "eye.cornea.axis_deg": 40})
    a, b = compile_scene(base), compile_scene(same)
    np.testing.assert_array_equal(a.sf, b.sf)
    np.testing.assert_array_equal(a.si, b.si)


def test_decentration_moves_the_glint_by_d_times_one_minus_m():
    d = np.array([0.3, -0.2, 0.0])
    cs0 = compile_scene(_scene({}))
    cs1 = compile_scene(_scene({"decentration_mm": [float(d[0]), float(d[1])]}))
    focal = [R_FLAT / 2] * 4
    got0, want0 = _glint_and_prediction(cs0, focal)
    got1, want1 = _glint_and_prediction(cs1, focal, vertex=d)
    moved, predicted = got1 - got0, want1 - want0
    s = cs0.led.points[0][2]
    m = (R_FLAT / 2) / (s + R_FLAT / 2)
    for k in range(4):
        size = np.linalg.norm(predicted[k])
        assert size > 0.3  # px: the decentration moves the glint measurably
        # each glint within TOL of its offset from its mirror's axis image (test above)
        tol = TOL * (
            np.linalg.norm(want0[k] - want0.mean(axis=0))
            + np.linalg.norm(want1[k] - want1.mean(axis=0))
        )
        assert np.linalg.norm(moved[k] - predicted[k]) <= tol, (k, moved[k], predicted[k])
        # the test resolves the factor (1 − m): a glint that moved with the mirror (by d
        # itself, m d more) would fail it
        assert m * size / (1 - m) > 5 * tol


def test_tilt_moves_the_glint_as_the_centre_of_curvature_moves():
    """A cornea tilted by τ about its apex is, to paraxial order, its sphere of curvature moved
    across by R sin τ (the centre of curvature C lies R behind the apex on the tilted axis):
    tilting the axis up (toward +y) moves C, and with it the glint's virtual image, down —
    the decentration law with d = C′ − C (the asphericity enters at third order, Q (h/R)² ≈
    2·10⁻⁴ here)."""
    tau = math.radians(1.5)
    cs0 = compile_scene(_scene({}))
    cs1 = compile_scene(_scene({"tilt_deg": [1.5, 0.0]}))
    focal = [R_FLAT / 2] * 4
    got0, want0 = _glint_and_prediction(cs0, focal)
    # the moved sphere's vertex toward the camera: C′ + R ẑ, C′ = −R (0, sin τ, cos τ)
    vertex = np.array([0.0, -R_FLAT * math.sin(tau), R_FLAT * (1.0 - math.cos(tau))])
    got1, want1 = _glint_and_prediction(cs1, focal, vertex=vertex)
    moved, predicted = got1 - got0, want1 - want0
    for k in range(4):
        size = np.linalg.norm(predicted[k])
        assert size > 0.3
        tol = TOL * (
            np.linalg.norm(want0[k] - want0.mean(axis=0))
            + np.linalg.norm(want1[k] - want1.mean(axis=0))
        )
        assert np.linalg.norm(moved[k] - predicted[k]) <= tol, (k, moved[k], predicted[k])
