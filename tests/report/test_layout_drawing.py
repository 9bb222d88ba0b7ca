"""The layout drawing's sections (eyelume.layout): lens elements as closed outlines, tissues
clipped at the skin, and an off-axis camera drawn where it is, in both views."""

from __future__ import annotations

import numpy as np
import pytest

from eyelume.compile import compile_scene
from eyelume.kernels import sequential as Q
from eyelume.layout import system_sections
from eyelume.scene.io import load_scene


@pytest.fixture(scope="module")
def paper():
    return compile_scene(load_scene("paper2005"))


def test_camera_lens_elements_are_closed_outlines(paper):
    lf = paper.lf
    secs = {s.name: s for s in system_sections(paper) if s.category == "lens"}
    for j in range(lf.shape[0] - 1):
        if lf[j, Q.L_N1] > 1.0 + 1e-6:  # glass after surface j: an element's two faces
            edges = [s for s in system_sections(paper) if s.name == f"lens S{j + 1}-S{j + 2} edge"]
            assert len(edges) == 2
            front, back = secs[f"lens S{j + 1}"], secs[f"lens S{j + 2}"]
            for e in edges:  # each edge joins an end of the front face to an end of the back
                ends_f = {
                    (round(z, 6), round(y, 6))
                    for z, y in zip(front.z[[0, -1]], front.y[[0, -1]], strict=True)
                }
                ends_b = {
                    (round(z, 6), round(y, 6))
                    for z, y in zip(back.z[[0, -1]], back.y[[0, -1]], strict=True)
                }
                assert (round(e.z[0], 6), round(e.y[0], 6)) in ends_f
                assert (round(e.z[1], 6), round(e.y[1], 6)) in ends_b
        else:
            assert not [
                s for s in system_sections(paper) if s.name == f"lens S{j + 1}-S{j + 2} edge"
            ]


@pytest.mark.parametrize("view", ["yz", "xz"])
def test_tissues_are_not_drawn_behind_the_skin(paper, view):
    secs = system_sections(paper, view=view)
    skin_z = [s.z for s in secs if s.name == "periorbital skin"]
    assert skin_z and np.allclose(np.concatenate(skin_z), skin_z[0][0])
    z0 = skin_z[0][0]
    lids = [s for s in secs if s.name in ("upper eyelid", "lower eyelid", "brow", "cheek")]
    assert lids or view == "xz"  # still drawn in front of the skin (the y = 0 cut misses them)
    for s in lids:
        assert s.z.min() >= z0 - 1e-9, s.name
    # the eye itself is drawn whole (it is behind the skin plane)
    assert min(s.z.min() for s in secs if s.name == "sclera") < z0 - 10


def test_an_off_axis_camera_is_drawn_where_it_is_in_both_views():
    cs = compile_scene(load_scene("vr-offaxis"))
    for view, axis in (("yz", 1), ("xz", 0)):
        secs = system_sections(cs, view=view)
        sensor = [s for s in secs if s.name == "sensor"]
        field = [s for s in secs if s.name == "field of view"]
        assert len(sensor) == 1 and len(field) == 2
        pupil = np.array([[f.z[0], f.y[0]] for f in field])
        assert np.allclose(pupil[0], pupil[1])
        # and the pupil is where the camera is placed in the world: off the eye's axis
        world = cs.frame.world_point(np.array([0.0, 0.0, cs.first_order.entrance_pupil_z]))
        assert np.allclose(pupil[0], [world[2], world[axis]], atol=1e-6)
    assert abs(world[0]) > 5 or abs(world[1]) > 5  # off-axis indeed


@pytest.mark.parametrize("view", ["yz", "xz"])
def test_the_camera_body_is_one_closed_outline_labelled_camera(view):
    """vr-offaxis's camera body (a cylinder) is drawn as one closed outline of category
    "camera" spanning an area (its front ring alone cut to two parallel strokes labelled
    "lens"); no "camera body" piece is a lens."""
    cs = compile_scene(load_scene("vr-offaxis"))
    secs = system_sections(cs, view=view)
    assert not [s for s in secs if s.name.startswith("camera body") and s.category != "camera"]
    body = [s for s in secs if s.category == "camera"]
    assert len(body) == 1
    z, y = body[0].z, body[0].y
    assert (z[0], y[0]) == (z[-1], y[-1]) and len(z) >= 4  # closed, spans an area
    area = 0.5 * abs(np.dot(z[:-1], y[1:]) - np.dot(z[1:], y[:-1]))
    assert area > 1.0  # mm²: a body, not two strokes
