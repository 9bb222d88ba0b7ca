"""Groups of surface rows (``geometry.GROUP_END``): the rows of one small body — an LED's flat
package (front disk and side), the camera's lens entrance and body — are skipped at once by
the searches when a ray misses one sphere about the body. It must give the same hits, bit for
bit, as testing every row: checked against the same table with the groups undone, for rays aimed
at the bodies (so that many meet a member) and rays in every direction, from the vertices the
camera sees and from around the headset; and a group sphere too small to hold its body is
caught by the same comparison (the test can fail)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import eyelume
from eyelume.compile import compile_scene
from eyelume.kernels import geometry as G
from eyelume.kernels.sampling import about_axis
from tests.kernels.test_free_cone import _first_vertices


def _groups(si: np.ndarray) -> list[tuple[int, int]]:
    return [(s, int(si[s, G.GROUP_END])) for s in range(si.shape[0]) if si[s, G.GROUP_END] > s]


def _ungrouped(si: np.ndarray) -> np.ndarray:
    out = si.copy()
    out[:, G.GROUP_END] = 0
    return out


def _rays(cs, rng, n: int) -> np.ndarray:
    """(n, 6) rays: origins on a 45 mm sphere about the scene's bounding spheres' centroid and
    at the camera's lens, half aimed at a point inside a random group's sphere, half in
    uniform directions."""
    sf, si = cs.sf, cs.si
    groups = _groups(si)
    centre = np.mean(sf[:, G.BX : G.BZ + 1], axis=0)
    v = rng.normal(size=(n, 3))
    origins = centre + 45.0 * v / np.linalg.norm(v, axis=1, keepdims=True)
    origins[: n // 4] = sf[groups[-1][0], G.BX : G.BZ + 1] + rng.normal(scale=8.0, size=(n // 4, 3))
    d = rng.normal(size=(n, 3))
    for k in range(n // 2):
        s, _ = groups[rng.integers(len(groups))]
        c, r = sf[s, G.GBX : G.GBZ + 1], sf[s, G.GBR]
        d[k] = c + r * rng.uniform(-1.0, 1.0, size=3) - origins[k]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return np.hstack([origins, d])


def _mismatches(cs, si_grouped, rays, rng) -> tuple[int, int, int]:
    """(rays whose nearest hit or shadow answer differs, rays that met a grouped row, rays
    whose search skipped a group) between the grouped table and the same table ungrouped."""
    sf, flat = cs.sf, _ungrouped(cs.si)
    member = np.zeros(sf.shape[0], dtype=bool)
    for s, e in _groups(si_grouped):
        member[s:e] = True
    bad = met = skipped = 0
    for x, y, z, dx, dy, dz in rays:
        full = G.nearest_hit(sf, flat, x, y, z, dx, dy, dz)
        got = G.nearest_hit(sf, si_grouped, x, y, z, dx, dy, dz)
        t_max = rng.uniform(1.0, 80.0)
        shadow = G.occluded(sf, flat, x, y, z, dx, dy, dz, t_max)
        bad += got != full or G.occluded(sf, si_grouped, x, y, z, dx, dy, dz, t_max) != shadow
        met += full[0] >= 0 and member[full[0]]
        for s, _ in _groups(si_grouped):
            cx, cy, cz = sf[s, G.GBX] - x, sf[s, G.GBY] - y, sf[s, G.GBZ] - z
            tc = cx * dx + cy * dy + cz * dz
            if cx * cx + cy * cy + cz * cz - tc * tc > sf[s, G.GBR] ** 2:
                skipped += 1
                break
    return bad, met, skipped


@pytest.mark.parametrize("preset", ["vr-offaxis", "glasses-frame", "eyetrackvr"])
def test_groups_give_the_hits_of_the_full_search(preset, rng):
    """Bit for bit the same nearest hit (surface and distance) and shadow answer with and
    without the groups, for 3000 rays of which hundreds meet an LED's or the camera's body
    and most skip a group; and the within-reach searches (``nearest_hit_within``,
    ``occluded_within``, whose gaps on a group's first row hold the group's) the same as the
    full search without groups from the vertices the camera sees."""
    cs = compile_scene(eyelume.load_scene(preset))
    groups = _groups(cs.si)
    assert groups and all(e - s >= 2 for s, e in groups)
    bad, met, skipped = _mismatches(cs, cs.si, _rays(cs, rng, 3000), rng)
    assert bad == 0 and met > 100 and skipped > 1000, (bad, met, skipped)

    flat = _ungrouped(cs.si)
    pixels = rng.choice(cs.picture.cols * cs.picture.rows, 60, replace=False)
    gaps = np.empty(cs.sf.shape[0])
    for s, (x, y, z), (nx, ny, nz) in _first_vertices(cs, pixels, False):
        G.free_cone_gaps(cs.sf, cs.si, s, x, y, z, nx, ny, nz, gaps)
        for u1, u2 in rng.uniform(size=(60, 2)):
            lz = math.sqrt(1.0 - u1)
            d = about_axis(
                math.sqrt(u1) * math.cos(2 * math.pi * u2),
                math.sqrt(u1) * math.sin(2 * math.pi * u2),
                lz,
                nx,
                ny,
                nz,
            )
            full = G.nearest_hit(cs.sf, flat, x, y, z, *d)
            assert G.nearest_hit_within(cs.sf, cs.si, x, y, z, *d, gaps, lz) == full
            t_max = 60.0 * u2
            assert G.occluded_within(cs.sf, cs.si, x, y, z, *d, t_max, gaps, lz) == G.occluded(
                cs.sf, flat, x, y, z, *d, t_max
            )


def test_a_group_sphere_that_cuts_its_body_is_caught(rng):
    """The comparison above fails when a group's sphere is too small to hold its body (each
    radius × 0.7): rays that met an LED's package are then lost."""
    cs = compile_scene(eyelume.load_scene("vr-offaxis"))
    sf = cs.sf.copy()
    for s, _ in _groups(cs.si):
        sf[s, G.GBR] *= 0.7
    rays = _rays(cs, rng, 2000)
    bad = 0
    flat = _ungrouped(cs.si)
    for x, y, z, dx, dy, dz in rays:
        bad += G.nearest_hit(sf, cs.si, x, y, z, dx, dy, dz) != G.nearest_hit(
            sf, flat, x, y, z, dx, dy, dz
        )
    assert bad > 10, bad
