"""The eye is closed except for its pupil (issue 12): rays traced by the kernels from outside.

Between the iris's outer edge (r 5.5 mm, 3.6 mm deep) and the sclera sphere (r 7.41 mm in that
plane) a real eye has the iris root; without it, rays through the corneal edge reached the
inside of the eyeball. Here rays start on a hemisphere in front of the eye (where the camera and
the LEDs are), aim at random points over the cornea and the limbus, and are followed by the
compiled scene's own intersection and refraction kernels (always transmitted at an interface,
reflected on total internal reflection, stopped at the first opaque face). Every ray that
reaches the inside of the eyeball — the crystalline lens, the retina or the fundus (the sclera
from inside) — must have crossed the iris plane inside the pupil.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import eyelume
from eyelume.compile import compile_scene
from eyelume.errors import GeometryError
from eyelume.kernels import geometry as G
from eyelume.kernels.interact import reflect, refract

N_RAYS = 6000


def _trace(cs, iris, inside, start, direction):
    """Follow one ray from ``start`` along ``direction`` (world mm). Returns (surface it
    stopped on or −1, from side B, crossed the iris plane inside the pupil before, crossed it
    outside the pupil)."""
    x, y, z = start
    dx, dy, dz = direction
    r_pupil2 = cs.sf[iris, G.RMIN2]
    through_pupil = through_other = False
    for _ in range(64):
        s, t = G.nearest_hit(cs.sf, cs.si, x, y, z, dx, dy, dz)
        end = (
            (x + t * dx, y + t * dy, z + t * dz)
            if s >= 0
            else (x + 60 * dx, y + 60 * dy, z + 60 * dz)
        )
        # crossing of the iris plane (local z = 0 of the iris surface) along this segment
        a = G.to_local(cs.sf, iris, x, y, z)
        b = G.to_local(cs.sf, iris, *end)
        if (a[2] < 0.0) != (b[2] < 0.0):
            f = a[2] / (a[2] - b[2])
            r2 = (a[0] + f * (b[0] - a[0])) ** 2 + (a[1] + f * (b[1] - a[1])) ** 2
            if r2 < r_pupil2:
                through_pupil = True
            else:
                through_other = True
        if s < 0:
            return -1, False, through_pupil, through_other
        x, y, z = end
        nx, ny, nz = G.surface_normal(cs.sf, cs.si, s, x, y, z)
        cos_d = dx * nx + dy * ny + dz * nz
        from_b = cos_d < 0.0
        if s in inside or cs.si[s, G.ACTION] != G.ACT_REFRACT:
            return s, from_b, through_pupil, through_other
        n1 = cs.sf[s, G.N_B] if from_b else cs.sf[s, G.N_A]
        n2 = cs.sf[s, G.N_A] if from_b else cs.sf[s, G.N_B]
        ok, tx, ty, tz = refract(dx, dy, dz, nx, ny, nz, n1 / n2)
        dx, dy, dz = (tx, ty, tz) if ok else reflect(dx, dy, dz, nx, ny, nz)
        norm = math.sqrt(dx * dx + dy * dy + dz * dz)
        dx, dy, dz = dx / norm, dy / norm, dz / norm
    return -1, False, through_pupil, through_other


def _shoot(cs, seed):
    """Trace N_RAYS rays from a 40 mm hemisphere about the eye (polar angle up to 80° from the
    eye's axis) toward random points of a 7.5 mm disc just in front of the corneal vertex
    (beyond the limbus at 6 mm), half of them of its ring r 5-6.2 mm. Returns the outcomes per
    ray."""
    rng = np.random.default_rng(seed)
    names = cs.surface_names
    eye = cs.scene.eye
    iris = names.index("iris")
    inside = {names.index(s.name) for s in eye.surfaces[2:]} | {names.index("sclera")}
    # the eye's frame: the iris surface's rows are its local axes in world coordinates (local
    # z points into the eye), its origin the iris centre
    rot = cs.sf[iris, G.R00 : G.R22 + 1].reshape(3, 3)
    vertex = cs.sf[iris, G.OX : G.OZ + 1] - rot[2] * 3.6
    out = []
    for _ in range(N_RAYS):
        theta = math.radians(80.0) * math.sqrt(rng.uniform())
        phi = rng.uniform(0, 2 * math.pi)
        local_start = 40.0 * np.array(
            [math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), -math.cos(theta)]
        )
        # half the rays at the corneal edge (r 5-6.2 mm), where the ring used to let light in
        rr = 7.5 * math.sqrt(rng.uniform()) if rng.uniform() < 0.5 else rng.uniform(5.0, 6.2)
        pp = rng.uniform(0, 2 * math.pi)
        local_aim = np.array([rr * math.cos(pp), rr * math.sin(pp), -0.5])
        start = vertex + rot.T @ local_start
        aim = vertex + rot.T @ local_aim
        d = (aim - start) / np.linalg.norm(aim - start)
        s, from_b, pupil, other = _trace(cs, iris, inside, start, d)
        reached_inside = s in inside and not (names[s] == "sclera" and from_b)
        out.append((names[s] if s >= 0 else "", reached_inside, pupil, other))
    return out


@pytest.mark.parametrize("gaze", [(0.0, 0.0), (25.0, -15.0)])
def test_no_ray_enters_the_eyeball_except_through_the_pupil(gaze):
    scene = eyelume.load_scene(
        "paper2005", {"eye.gaze_horizontal_deg": gaze[0], "eye.gaze_vertical_deg": gaze[1]}
    )
    cs = compile_scene(scene)
    outcomes = _shoot(cs, seed=12)
    inside = [o for o in outcomes if o[1]]
    leaks = [o for o in inside if not o[2]]
    # the test covers what it claims: many rays get in (through the pupil), and many meet the
    # iris root, the ring where rays through the corneal edge used to pass into the eye
    assert len(inside) > 500
    assert sum(o[0] == "iris root" for o in outcomes) > 30
    assert not leaks, f"{len(leaks)} of {len(inside)} rays reached {leaks[0][0]!r} past the pupil"


def test_iris_root_spans_iris_edge_to_sclera(paper_compiled):
    """The root is the annulus from the iris's outer edge to the sclera sphere in the iris
    plane: r_root = √(R² − (z_c − z_i)²) = 7.41 mm for the paper's eye (by hand: z_l = sag of
    the cornea at 6 mm = 2.6437, z_c = z_l + √(12² − 6²) = 13.0360, z_i = 0.55 + 3.05)."""
    names = paper_compiled.surface_names
    root = names.index("iris root")
    sf = paper_compiled.sf
    z_c = 2.64371 + math.sqrt(144 - 36)
    r_root = math.sqrt(144 - (z_c - 3.6) ** 2)
    assert math.sqrt(sf[root, G.RMIN2]) == pytest.approx(5.5)
    assert math.sqrt(sf[root, G.RMAX2]) == pytest.approx(r_root, abs=1e-4)
    assert r_root == pytest.approx(7.41, abs=0.01)
    assert sf[root, G.RHO_A] == paper_compiled.scene.eye.iris_reflectance
    assert sf[root, G.RHO_B] == 0.0  # its back, like the iris's, absorbs (pigment epithelium)


def test_iris_plane_in_front_of_the_limbus_is_refused():
    with pytest.raises(GeometryError, match=r"eye.iris_surface = 1: the iris plane"):
        compile_scene(eyelume.load_scene("paper2005", {"eye.iris_surface": 1}))
