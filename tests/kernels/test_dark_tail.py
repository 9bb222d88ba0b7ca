"""A camera path's searches pass over the table's dark tail (``geometry.dark_tail``: the LED
packages, the camera's body and lens entrance, which end a camera path and send it no light)
unless a lit row is met (``geometry.nearest_lit_hit``). It must be the full search's answer
whenever that answer is a lit row or a dark row in front of one, and "nothing" exactly when
the full search meets no lit row; and the fast estimator's camera pass must be the same, bit
for bit, with the tail searched always (``dark_from`` = the row count)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import eyelume
from eyelume.compile import compile_scene
from eyelume.estimators import fast as F
from eyelume.estimators.fast_run import warm_up
from eyelume.kernels import geometry as G
from eyelume.kernels.sampling import about_axis
from tests.kernels.test_free_cone import _first_vertices
from tests.kernels.test_surface_groups import _rays


def _dark(sf, si, s) -> bool:
    return si[s, G.ACTION] == G.ACT_LENS or (
        si[s, G.ACTION] == G.ACT_OPAQUE and sf[s, G.RHO_A] <= 0.0 and sf[s, G.RHO_B] <= 0.0
    )


@pytest.mark.parametrize(
    ("preset", "first"), [("vr-offaxis", "LED 0 body"), ("paper2005", None), ("eyetrackvr", None)]
)
def test_dark_tail_is_the_last_dark_rows(preset, first):
    """Every row from ``dark_from`` on is dark, the row before it is not, and no group
    straddles it; on vr-offaxis it starts at the first LED's package."""
    cs = compile_scene(eyelume.load_scene(preset))
    sf, si = cs.sf, cs.si
    k = cs.camera.dark_from
    assert k == G.dark_tail(sf, si)
    assert 0 < k < sf.shape[0]
    assert all(_dark(sf, si, s) for s in range(k, sf.shape[0]))
    assert not _dark(sf, si, k - 1)
    assert all(si[s, G.GROUP_END] <= k for s in range(k))
    if first is not None:
        assert cs.surface_names[k] == first


def test_a_group_across_the_tail_is_searched_whole():
    """A group whose first rows are lit and last rows dark moves the tail to its end."""
    cs = compile_scene(eyelume.load_scene("vr-offaxis"))
    sf, si = cs.sf.copy(), cs.si.copy()
    k = G.dark_tail(sf, si)
    si[k - 1, G.GROUP_END] = k + 2  # the last lit row heads a group of it and two dark rows
    assert G.dark_tail(sf, si) == k + 2
    sf[sf.shape[0] - 1, G.RHO_B] = 0.3  # the last row lit: no tail
    assert G.dark_tail(sf, si) == sf.shape[0]


@pytest.mark.parametrize("preset", ["vr-offaxis", "glasses-frame", "eyetrackvr"])
def test_lit_search_answers_as_the_full_search(preset, rng):
    """For 3000 rays about the headset (hundreds meet an LED's or the camera's body) and rays
    from the vertices the camera sees (within-reach search): where the lit search names a row,
    it is the full search's (surface and distance, bit for bit); where it names none, the full
    search met nothing or a dark row, and nothing lit lies along the ray (the lit rows alone
    meet nothing)."""
    cs = compile_scene(eyelume.load_scene(preset))
    sf, si, k = cs.sf, cs.si, cs.camera.dark_from
    lit_sf, lit_si = sf[:k].copy(), si[:k].copy()
    dark_only = 0

    def check(full, got, x, y, z, d):
        nonlocal dark_only
        if got[0] >= 0:
            assert got == full
        else:
            assert got == (-1, math.inf)
            assert full[0] < 0 or full[0] >= k
            assert G.nearest_hit(lit_sf, lit_si, x, y, z, *d)[0] < 0
            dark_only += full[0] >= k

    for x, y, z, dx, dy, dz in _rays(cs, rng, 3000):
        d = (dx, dy, dz)
        check(
            G.nearest_hit(sf, si, x, y, z, *d),
            G.nearest_lit_hit(sf, si, x, y, z, *d, k),
            x,
            y,
            z,
            d,
        )
    assert dark_only > 100, dark_only

    gaps = np.empty(sf.shape[0])
    pixels = rng.choice(cs.picture.cols * cs.picture.rows, 60, replace=False)
    for s, (x, y, z), (nx, ny, nz) in _first_vertices(cs, pixels, False):
        G.free_cone_gaps(sf, si, s, x, y, z, nx, ny, nz, gaps)
        for u1, u2 in rng.uniform(size=(60, 2)):
            lz = math.sqrt(1.0 - u1)
            r = math.sqrt(u1)
            d = about_axis(
                r * math.cos(2 * math.pi * u2), r * math.sin(2 * math.pi * u2), lz, nx, ny, nz
            )
            got = G.nearest_lit_hit_within(sf, si, x, y, z, *d, gaps, lz, k)
            check(G.nearest_hit(sf, si, x, y, z, *d), got, x, y, z, d)


def test_camera_pass_is_the_same_with_the_tail_searched_always():
    """vr-offaxis, a quarter of its pixels, 2 sets: the camera pass's sums with the dark tail
    passed over equal, bit for bit, those with every row searched (``dark_from`` = the row
    count); and a tail that wrongly holds a lit row (the nose and the LEDs) changes them."""
    cs = compile_scene(eyelume.load_scene("vr-offaxis"))
    warm_up(cs)
    idx = np.arange(0, cs.picture.cols * cs.picture.rows, 16, dtype=np.int64)

    def sums(cam):
        s1, s2 = np.zeros(idx.size), np.zeros(idx.size)
        F.camera_pass(3, 0, 2, cs.tables, cam, 1, F.CameraSums(idx, s1, s2))
        return s1, s2

    a1, a2 = sums(cs.camera)
    b1, b2 = sums(cs.camera._replace(dark_from=cs.sf.shape[0]))
    assert np.array_equal(a1, b1) and np.array_equal(a2, b2)
    nose = cs.surface_names.index("nose")
    c1, _ = sums(cs.camera._replace(dark_from=nose))
    assert not np.array_equal(a1, c1)
