"""``geometry.free_cone``: the cone about a Lambertian vertex's normal that meets nothing able to
send light back. The fast estimator's continuation samples only outside it, so a direction
inside that meets a lit surface would lose light: checked here by brute force, ray by ray, at
the vertices the camera sees on every preset (straight, and by the cornea's reflection), and
that the cone is not empty where it matters (the skin of vr-offaxis)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import eyelume
from eyelume.analysis.regions import region_masks
from eyelume.compile import compile_scene
from eyelume.estimators.camera import aim_chief, into_scene
from eyelume.kernels import geometry as G
from eyelume.kernels.bins import from_grid
from eyelume.kernels.interact import interface_at, reflect, refract
from eyelume.kernels.sampling import about_axis, uniform_cone


def _first_vertices(cs, pixels, reflected: bool):
    """(surface, point, normal toward the camera side) of the first opaque vertex along each
    pixel's chief ray, refracting at every interface, or reflecting at the first one."""
    sf, si = cs.sf, cs.si
    out = []
    for p in pixels:
        row, col = divmod(int(p), cs.picture.cols)
        xs, ys = from_grid(cs.tables.picture, col + 0.5, row + 0.5)
        chief = aim_chief(cs.camera, xs, ys)
        if not chief.found:
            continue
        ray = into_scene(cs.camera, xs, ys, chief.qx, chief.qy)
        if not ray.passed:
            continue
        x, y, z, dx, dy, dz = ray.x, ray.y, ray.z, ray.dx, ray.dy, ray.dz
        first = True
        for _ in range(16):
            s, t = G.nearest_hit(sf, si, x, y, z, dx, dy, dz)
            if s < 0 or si[s, G.ACTION] == G.ACT_LENS:
                break
            x, y, z = x + t * dx, y + t * dy, z + t * dz
            nx, ny, nz = G.surface_normal(sf, si, s, x, y, z)
            cos_d = dx * nx + dy * ny + dz * nz
            if si[s, G.ACTION] == G.ACT_OPAQUE:
                if cos_d > 0.0:
                    nx, ny, nz = -nx, -ny, -nz
                out.append((s, (x, y, z), (nx, ny, nz)))
                break
            if reflected and first:
                dx, dy, dz = reflect(dx, dy, dz, nx, ny, nz)
            else:
                f = interface_at(sf, si, s, cos_d)
                ok, tx, ty, tz = refract(dx, dy, dz, nx, ny, nz, f.n1 / f.n2)
                dx, dy, dz = (tx, ty, tz) if ok else reflect(dx, dy, dz, nx, ny, nz)
            first = False
    return out


def _sends_nothing(cs, s: int) -> bool:
    """A hit that gives a camera path nothing: none, the imaging lens, or black both sides."""
    if s < 0:
        return True
    if cs.si[s, G.ACTION] == G.ACT_LENS:
        return True
    return bool(
        cs.si[s, G.ACTION] == G.ACT_OPAQUE and cs.sf[s, G.RHO_A] <= 0.0 and cs.sf[s, G.RHO_B] <= 0.0
    )


@pytest.mark.parametrize(
    "preset", ["vr-offaxis", "paper2005", "eyetrackvr", "glasses-frame", "paper2005-integrated"]
)
def test_no_direction_in_the_free_cone_meets_a_lit_surface(preset, rng):
    cs = compile_scene(eyelume.load_scene(preset))
    pixels = rng.choice(cs.picture.cols * cs.picture.rows, 160, replace=False)
    vertices = _first_vertices(cs, pixels, False) + _first_vertices(cs, pixels, True)
    assert len(vertices) > 100
    culled = 0
    for s, (x, y, z), (nx, ny, nz) in vertices:
        s0 = G.free_cone(cs.sf, cs.si, s, x, y, z, nx, ny, nz)
        assert 0.0 <= s0 <= 1.0
        if s0 <= 0.0:
            continue
        culled += 1
        cos_max = math.sqrt(1.0 - s0)  # θ₀: sin²θ₀ = s0
        for u1, u2 in rng.uniform(size=(200, 2)):
            lx, ly, lz = uniform_cone(u1, u2, cos_max)
            dx, dy, dz = about_axis(lx, ly, lz, nx, ny, nz)
            hit, _ = G.nearest_hit(cs.sf, cs.si, x, y, z, dx, dy, dz)
            assert _sends_nothing(cs, hit), (preset, cs.surface_names[s], s0, hit)
    assert culled > 0


def test_the_free_cone_is_wide_on_the_periorbital_skin_of_vr_offaxis(rng):
    """Not empty where the continuation's misses are (the skin facing the open headset): its
    median share of the cosine-weighted hemisphere (sin²θ₀) is above 0.3 there (0.52 measured
    when written), so a cull that silently finds no cone fails."""
    cs = compile_scene(eyelume.load_scene("vr-offaxis"))
    skin = np.flatnonzero(region_masks(cs)["skin"].reshape(-1))
    row = cs.surface_names.index("periorbital skin")
    shares = [
        G.free_cone(cs.sf, cs.si, s, *x, *n)
        for s, x, n in _first_vertices(cs, rng.choice(skin, 200, replace=False), False)
        if s == row
    ]
    assert len(shares) > 50
    assert np.median(shares) > 0.3


@pytest.mark.parametrize(
    "preset", ["vr-offaxis", "paper2005", "eyetrackvr", "glasses-frame", "paper2005-integrated"]
)
def test_the_search_within_reach_finds_what_the_full_search_finds(preset, rng):
    """``nearest_hit_within`` skips, for a ray leaving a vertex at polar cosine cos θ, every
    surface whose gap (``free_cone_gaps``) is below cos θ: the same surface and the same
    distance as ``nearest_hit``, bit for bit (and ``occluded_within`` the same answer as
    ``occluded``), for cosine-distributed directions at the
    vertices the camera sees (straight and by the cornea's reflection) — the rays the fast
    estimator's continuation sends (half of them grazing, within 30° of the face), and
    ``free_cone_gaps`` gives ``free_cone``'s value."""
    cs = compile_scene(eyelume.load_scene(preset))
    pixels = rng.choice(cs.picture.cols * cs.picture.rows, 120, replace=False)
    vertices = _first_vertices(cs, pixels, False) + _first_vertices(cs, pixels, True)
    assert len(vertices) > 80
    gaps = np.empty(cs.sf.shape[0])
    skipped = hits = 0
    for s, (x, y, z), (nx, ny, nz) in vertices:
        s0 = G.free_cone_gaps(cs.sf, cs.si, s, x, y, z, nx, ny, nz, gaps)
        assert s0 == G.free_cone(cs.sf, cs.si, s, x, y, z, nx, ny, nz)
        for u1, u2 in rng.uniform(size=(100, 2)):
            u1 = u1 if u2 < 0.5 else 1.0 - 0.25 * u1  # half of them within 30° of the face
            lx, ly, lz = (
                math.sqrt(u1) * math.cos(6.2832 * u2),
                math.sqrt(u1) * math.sin(6.2832 * u2),
                math.sqrt(1.0 - u1),
            )
            d = about_axis(lx, ly, lz, nx, ny, nz)
            full = G.nearest_hit(cs.sf, cs.si, x, y, z, *d)
            within = G.nearest_hit_within(cs.sf, cs.si, x, y, z, *d, gaps, lz)
            assert within == full, (preset, cs.surface_names[s], full, within)
            t_max = 40.0 * u2  # a shadow ray's length (mm): the same answer as occluded
            assert G.occluded_within(cs.sf, cs.si, x, y, z, *d, t_max, gaps, lz) == G.occluded(
                cs.sf, cs.si, x, y, z, *d, t_max
            )
            skipped += int(np.sum(lz > gaps))
            hits += full[0] >= 0
    assert skipped > 0 and hits > 0
