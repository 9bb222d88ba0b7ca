"""The anterior cornea's astigmatism and placement (``eye.cornea``, issue 15): what the scene
accepts and refuses (one line naming the field and the value; exit 2 from the CLI), the
flat meridian's TABO axis in the world, and the quadric's meridians (their radii and Q)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from typer.testing import CliRunner

import eyelume
from eyelume.cli import app
from eyelume.compile import compile_scene
from eyelume.errors import EyelumeError
from eyelume.kernels import geometry as G
from eyelume.scene.eye import anterior_cornea_points, anterior_quadric, meridian_sag


@pytest.mark.parametrize(
    ("over", "names"),
    [
        ({"eye.cornea.radius_steep_mm": 8.1}, "radius_steep_mm"),  # steeper than the flat one? no
        ({"eye.cornea.radius_steep_mm": -7.0}, "radius_steep_mm"),
        ({"eye.cornea.radius_steep_mm": float("nan")}, "radius_steep_mm"),
        ({"eye.cornea.radius_steep_mm": 4.0}, "radius_steep_mm"),  # Q_steep far below −1.5
        ({"eye.cornea.axis_deg": 190.0}, "axis_deg"),
        ({"eye.cornea.decentration_mm": [1.9, 0.0]}, "decentration_mm"),  # off the limbus
        ({"eye.cornea.tilt_deg": [0.0, 14.0]}, "tilt_deg"),
        ({"eye.cornea.tilt_deg": [0.0, 30.0]}, "tilt_deg"),  # beyond the field's range
    ],
)
def test_impossible_corneas_are_refused_in_one_line(over, names):
    with pytest.raises(EyelumeError) as info:
        eyelume.load_scene("paper2005", over)
    msg = str(info.value)
    assert "\n" not in msg
    assert names in msg, msg


def test_the_cli_refuses_a_bad_cornea_with_exit_2():
    args = ["info", "--scene", "paper2005", "--set", "eye.cornea.decentration_mm=[1.9, 0.0]"]
    res = CliRunner().invoke(app, args, prog_name="eyelume")
    assert res.exit_code == 2, res.output
    lines = [x for x in res.output.splitlines() if x.strip()]
    assert len(lines) == 1 and "decentration_mm" in lines[0], res.output


def test_typical_corneas_are_accepted():
    """A 3 D with-the-rule cornea, decentred 0.5 mm and tilted 3° (the order of a real eye's
    corneal apex and topographic axis off the pupil's), compiles."""
    scene = eyelume.load_scene(
        "paper2005",
        {
            "eye.cornea.radius_steep_mm": 7.3,
            "eye.cornea.axis_deg": 5.0,
            "eye.cornea.decentration_mm": [0.5, 0.2],
            "eye.cornea.tilt_deg": [3.0, -3.0],
        },
    )
    cs = compile_scene(scene)
    assert cs.si[cs.surface_names.index("anterior cornea"), G.SHAPE] == G.SHAPE_QUADRIC


def test_meridians_have_their_radii_and_asphericities():
    """The quadric's flat meridian is the conic (R_flat, Q); the steep one the conic (R_steep,
    Q_steep = (1 + Q) R_steep / R_flat − 1): its sag against the conic sag formula."""
    eye = eyelume.load_scene("paper2005", {"eye.cornea.radius_steep_mm": 7.4}).eye
    c1, c2, k = anterior_quadric(eye)
    assert (1 / c1, 1 / c2, k) == pytest.approx((7.8, 7.4, -0.25))
    h = np.linspace(0.0, 6.0, 13)
    q_steep = (1 + k) * 7.4 / 7.8 - 1

    def conic(r, q):
        return h * h / r / (1 + np.sqrt(1 - (1 + q) * h * h / r / r))

    np.testing.assert_allclose(meridian_sag(c1, c2, k, h, 0.0), conic(7.8, k), atol=1e-14)
    np.testing.assert_allclose(meridian_sag(c1, c2, k, h, math.pi / 2), conic(7.4, q_steep))


@pytest.mark.parametrize(("axis", "which"), [(0.0, "right"), (30.0, "right"), (30.0, "left")])
def test_the_flat_meridian_lies_at_its_tabo_axis_in_the_world(axis, which):
    """TABO: the flat meridian's axis counter-clockwise from the examiner's right (world +x)
    toward +y, facing the eye; a left eye mirrors the scene: 180° − axis. The compiled
    quadric's local x axis (its flat meridian) is that world direction (up to sign)."""
    scene = eyelume.load_scene(
        "paper2005",
        {
            "eye.cornea.radius_steep_mm": 7.4,
            "eye.cornea.axis_deg": axis,
            "eye_pose.which": which,
        },
    )
    cs = compile_scene(scene)
    s = cs.surface_names.index("anterior cornea")
    flat = cs.sf[s, G.R00 : G.R02 + 1]  # local x axis, camera frame = world on paper2005's rig
    th = math.radians(axis if which == "right" else 180.0 - axis)
    assert abs(abs(flat @ np.array([math.cos(th), math.sin(th), 0.0])) - 1.0) < 1e-12


def test_decentration_moves_the_apex_and_tilt_turns_the_axis():
    eye = eyelume.load_scene(
        "paper2005",
        {"eye.cornea.decentration_mm": [0.4, -0.3], "eye.cornea.tilt_deg": [2.0, 0.0]},
    ).eye
    apex = anterior_cornea_points(eye, 0.0, 0.0)  # eye frame: x′ = −x, z′ into the eye
    np.testing.assert_allclose(apex, [-0.4, -0.3, 0.0], atol=1e-15)
    # the surface's normal at its apex is its axis: tilted 2° up (toward +y in the file's
    # frame, which the eye frame shares)
    scene = eyelume.load_scene("paper2005", {"eye.cornea.tilt_deg": [2.0, 0.0]})
    cs = compile_scene(scene)
    s = cs.surface_names.index("anterior cornea")
    axis = -cs.sf[s, G.R20 : G.R22 + 1]  # local z points into the eye; out of it, world
    np.testing.assert_allclose(
        axis, [0.0, math.sin(math.radians(2.0)), math.cos(math.radians(2.0))], atol=1e-12
    )


def test_info_reports_the_meridians_cylinder_and_the_physical_axis():
    from eyelume.info import scene_info

    over = {"eye.cornea.radius_steep_mm": 7.5, "eye.cornea.axis_deg": 10.0}
    right = scene_info(eyelume.load_scene("paper2005", over))["eye"]["anterior_cornea"]
    left = scene_info(eyelume.load_scene("paper2005", {**over, "eye_pose.which": "left"}))
    assert right["cylinder_d"] == pytest.approx(337.5 / 7.5 - 337.5 / 7.8)
    assert right["q_steep"] == pytest.approx(0.75 * 7.5 / 7.8 - 1)
    assert (right["axis_deg_tabo"], left["eye"]["anterior_cornea"]["axis_deg_tabo"]) == (10, 170)
