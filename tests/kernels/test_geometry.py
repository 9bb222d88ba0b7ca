"""Ray–surface intersections against an independent brute-force root search and closed forms.

The brute force (``_reference_hit``) knows nothing of the kernel's quadratic: it evaluates the
surface's implicit equation G(q) = 0 at points q = p + t d of the ray written in the surface's
local frame (computed here with numpy), brackets sign changes on a fine grid over [T_MIN, t_max]
and refines each with ``scipy.optimize.brentq``; then it keeps the roots that lie on the surface
as clipped (aperture, z range, the conicoid's vertex sheet (1+k) c z ≤ 1) and takes the smallest.
Along a ray G is a polynomial of degree ≤ 2 in t, so its two roots are separated by its stationary
point; that point is added to the grid, which makes the bracketing complete.

Tolerance on t: forward error = backward error × condition. Both the kernel and the reference
evaluate G with a relative backward error of a few ulp of the magnitudes of its terms, S(t), and
the transform to the local frame perturbs q by ~ε·L (L the length scale of the ray), which moves G
by |∇G|·ε·L. A perturbation δG moves the root by δG/|G'(t)|. So

    |t − t_ref| ≤ 1e-12 + 64 ε (S(t) + |∇G| L) / |G'(t)|,

64 ulp being a generous count of the operations. Rays whose roots are ill-posed (nearly tangent,
or a root within 1e-9 of a clip boundary, where rounding alone decides existence) are left out
of the comparison; the test asserts that they are few, so it cannot pass vacuously.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from eyelume.compile import SurfaceSpec
from eyelume.kernels import geometry as G
from eyelume.kernels.geometry import (
    T_MIN,
    conic_normal,
    intersect_surface,
    nearest_hit,
    quadratic_roots,
    surface_normal,
)

EPS = np.finfo(float).eps
HUGE_BOUND = ((0.0, 0.0, 0.0), 1e12)


# --- building surface tables ----------------------------------------------------------------------


def _surface(shape, *, origin=(0.0, 0.0, 0.0), rot=None, bound=HUGE_BOUND, **fields):
    """A surface as eyelume.compile builds it (:class:`eyelume.compile.SurfaceSpec`): at the
    origin, unrotated, with a huge bounding sphere unless told; ``fields`` are SurfaceSpec's
    (``curv``, ``conic``, ``radius``, ``clip_r``, ``clip_z``, ...)."""
    rot = np.eye(3) if rot is None else np.asarray(rot)
    return SurfaceSpec("surface", shape, np.asarray(origin, dtype=float), rot, bound, **fields)


def _table(*surfaces):
    """The float and int tables of ``surfaces``, packed by SurfaceSpec as compile does."""
    sf = np.array([s.float_row() for s in surfaces])
    si = np.array([s.int_row(0, 0) for s in surfaces])
    return sf, si


def _random_rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[2] = -q[2]
    return q


def _sag(c, k, r):
    """Sag of the vertex sheet, written out from the formula (NaN beyond the conicoid)."""
    arg = 1.0 - (1.0 + k) * c * c * r * r
    with np.errstate(invalid="ignore"):
        return c * r * r / (1.0 + np.sqrt(arg))


# --- the independent reference ------------------------------------------------------------------


def _implicit(f, shape, q):
    """G(q), the magnitude of its terms S(q), and ∇G(q), at local points q (..., 3)."""
    x, y, z = q[..., 0], q[..., 1], q[..., 2]
    if shape == G.SHAPE_CONIC:
        c, k = f[G.CURV], f[G.CONIC]
        g = c * (x * x + y * y) + (1.0 + k) * c * z * z - 2.0 * z
        s = abs(c) * (x * x + y * y) + abs((1.0 + k) * c) * z * z + 2.0 * abs(z)
        grad = np.stack([2 * c * x, 2 * c * y, 2 * (1.0 + k) * c * z - 2.0], axis=-1)
    elif shape == G.SHAPE_QUADRIC:
        c, cy, k = f[G.CURV], f[G.CURV_Y], f[G.CONIC]
        g = c * x * x + cy * y * y + (1.0 + k) * c * z * z - 2.0 * z
        s = abs(c) * x * x + abs(cy) * y * y + abs((1.0 + k) * c) * z * z + 2.0 * abs(z)
        grad = np.stack([2 * c * x, 2 * cy * y, 2 * (1.0 + k) * c * z - 2.0], axis=-1)
    elif shape == G.SHAPE_SPHERE:
        r2 = f[G.RADIUS] ** 2
        g = x * x + y * y + z * z - r2
        s = x * x + y * y + z * z + r2
        grad = 2.0 * np.stack([x, y, z], axis=-1)
    else:
        r2 = f[G.RADIUS] ** 2
        g = x * x + y * y - r2
        s = x * x + y * y + r2
        grad = 2.0 * np.stack([x, y, np.zeros_like(z)], axis=-1)
    return g, s, grad


def _boundary_distance(f, shape, q):
    """Smallest relative distance of a local point to the edge of the clipped surface (≥ 0 inside,
    negative outside)."""
    x, y, z = q
    r2 = x * x + y * y
    scale_r = max(1.0, f[G.RMAX2] if math.isfinite(f[G.RMAX2]) else r2)
    d = [(r2 - f[G.RMIN2]) / scale_r, (f[G.RMAX2] - r2) / scale_r]
    d += [(z - f[G.ZLO]) / (1.0 + abs(z)), (f[G.ZHI] - z) / (1.0 + abs(z))]
    if shape in (G.SHAPE_CONIC, G.SHAPE_QUADRIC):
        d.append(1.0 - (1.0 + f[G.CONIC]) * f[G.CURV] * z)
    return min(d)


def _reference_hit(f, shape, p, d, t_max, n_grid=2001):
    """Brute-force nearest valid hit: (t or None, ill_posed, tolerance)."""
    rot = f[G.R00 : G.R22 + 1].reshape(3, 3)
    origin = f[G.OX : G.OZ + 1]
    pl = rot @ (np.asarray(p) - origin)
    dl = rot @ np.asarray(d)

    def g_of(t):
        return _implicit(f, shape, pl + np.multiply.outer(t, dl))[0]

    ts = np.linspace(T_MIN, t_max, n_grid)
    # G(t) = A t² + B t + C exactly; A, B from three values (used only to place the stationary
    # point and to flag near-tangent rays, never as the answer).
    g0, gp, gm = g_of(np.array([0.0, 1.0, -1.0]))
    a_fit, b_fit = (gp + gm - 2 * g0) / 2.0, (gp - gm) / 2.0
    if a_fit != 0.0:
        t_star = -b_fit / (2 * a_fit)
        if T_MIN < t_star < t_max:
            ts = np.sort(np.append(ts, t_star))
        disc = b_fit * b_fit - 4 * a_fit * g0
        if abs(disc) < 1e-8 * (b_fit * b_fit + abs(4 * a_fit * g0)):
            return None, True, 0.0  # nearly tangent: existence is decided by rounding
    gs = g_of(ts)
    roots = list(ts[gs == 0.0])
    for i in np.nonzero(np.sign(gs[:-1]) * np.sign(gs[1:]) < 0)[0]:
        roots.append(brentq(g_of, ts[i], ts[i + 1], xtol=1e-14, rtol=4 * EPS))
    length = np.linalg.norm(np.asarray(p) - origin) + t_max
    best, tol = None, 0.0
    for t in sorted(roots):
        q = pl + t * dl
        edge = _boundary_distance(f, shape, q)
        if abs(edge) < 1e-9 or abs(t - T_MIN) < 1e-9 or abs(t - t_max) < 1e-9 * t_max:
            return None, True, 0.0
        if edge > 0.0 and best is None:
            _, s, grad = _implicit(f, shape, q)
            dg = abs(grad @ dl)
            best = t
            tol = 1e-12 + 64 * EPS * (s + np.linalg.norm(grad) * length) / dg
    return best, False, tol


def _aimed_rays(rng, n, target_of):
    """Rays from a box toward points near the surface (local frame), some in random directions."""
    origins = np.column_stack(
        [rng.uniform(-30, 30, n), rng.uniform(-30, 30, n), rng.uniform(-60, 60, n)]
    )
    dirs = target_of(n) + rng.normal(scale=0.5, size=(n, 3)) - origins
    wild = rng.random(n) < 0.25
    dirs[wild] = rng.normal(size=(wild.sum(), 3))
    return origins, dirs / np.linalg.norm(dirs, axis=1, keepdims=True)


def _to_world(rot, origin, pts, dirs):
    return pts @ rot + origin, dirs @ rot  # local = R (world − o) → world = Rᵀ local + o


def _compare_with_reference(sf, si, rays, t_max=300.0):
    """Kernel vs brute force on every ray; returns the hits (world points) and the skip count."""
    f, shape = sf[0], si[0, G.SHAPE]
    skipped, hits = 0, []
    for p, d in zip(*rays, strict=True):
        t_ref, ill_posed, tol = _reference_hit(f, shape, p, d, t_max)
        if ill_posed:
            skipped += 1
            continue
        t = intersect_surface(sf, si, 0, *p, *d, t_max)
        if t_ref is None:
            assert t == -1.0, (p, d, t)
        else:
            assert t > 0.0, (p, d, t_ref)
            assert abs(t - t_ref) <= tol, (p, d, t, t_ref, tol)
            hits.append(p + t * d)
    return np.array(hits), skipped


# --- conicoids ----------------------------------------------------------------------------------

CONICS = [  # (c 1/mm, k, aperture radius mm); apertures stay inside the rim of closed conicoids
    (1 / 10, 0.0, 9.0),  # convex sphere
    (-1 / 25, 0.0, 20.0),  # concave sphere
    (1 / 8, -0.5, 10.0),  # prolate ellipsoid (rim r = 11.3)
    (1 / 12, 0.8, 8.0),  # oblate ellipsoid (rim r = 8.9)
    (1 / 15, -1.0, 25.0),  # paraboloid
    (1 / 10, -3.0, 20.0),  # hyperboloid
    (-1 / 1279.02, -2709.0, 25.0),  # the paper's lens, surface 2
    (-1 / 549.41, 58.87, 25.0),  # the paper's lens, surface 10 (oblate)
    (0.0, 0.0, 15.0),  # plane
]


def test_conicoid_hits_match_brute_force():
    rng = np.random.default_rng(20050801)
    n_rays, total_skipped, total_hits = 120, 0, 0
    for c, k, ap in CONICS:
        rot, origin = _random_rotation(rng), rng.uniform(-5, 5, 3)
        surface = _surface(G.SHAPE_CONIC, origin=origin, rot=rot, curv=c, conic=k, clip_r=(0.0, ap))
        sf, si = _table(surface)

        def targets(n, c=c, k=k, ap=ap):
            r = ap * np.sqrt(rng.random(n)) * 1.3  # some beyond the aperture
            phi = rng.uniform(0, 2 * np.pi, n)
            z = np.nan_to_num(_sag(c, k, np.minimum(r, ap)))
            return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])

        p, d = _to_world(rot, origin, *_aimed_rays(rng, n_rays, targets))
        hits, skipped = _compare_with_reference(sf, si, (p, d))
        total_skipped += skipped
        total_hits += len(hits)
        assert len(hits) > n_rays // 4, (c, k)  # the comparison is not vacuous

        for h in hits:
            x, y, z = rot @ (h - origin)
            r = math.hypot(x, y)
            # on the sag of the vertex sheet: rounding of the point ~ε·300 mm ≈ 1e-13 mm times
            # the slope (≤ 3 inside these apertures); 1e-9 mm leaves ample headroom
            assert abs(z - _sag(c, k, r)) < 1e-9, (c, k, r, z)
            _check_conic_normal(surface, sf, si, x, y, h)
    assert total_skipped <= 0.02 * n_rays * len(CONICS)
    assert total_hits > n_rays * len(CONICS) // 3


def _check_conic_normal(surface, sf, si, x, y, h):
    """The conic normal at local (x, y) of ``surface`` (world hit ``h``; tables ``sf``, ``si``)."""
    rot, c, k = surface.rot, surface.curv, surface.conic
    n = np.array(conic_normal(c, k, x, y, _sag(c, k, math.hypot(x, y))))
    assert abs(np.linalg.norm(n) - 1.0) < 1e-12
    assert n[2] >= 0.0  # toward +z (side B) on the vertex sheet
    # Orthogonal to the surface's tangents, by central differences of (x, y, sag(r)) with step
    # h = 1e-4 mm: truncation h²/6·|sag'''| ≲ 2e-8 · |sag'''| (|sag'''| ≲ 10 here), rounding
    # ε·|z|/h ≲ 1e-10; both ≪ 1e-6.
    step = 1e-4

    def surf(u, v):
        return np.array([u, v, _sag(c, k, math.hypot(u, v))])

    tx = (surf(x + step, y) - surf(x - step, y)) / (2 * step)
    ty = (surf(x, y + step) - surf(x, y - step)) / (2 * step)
    assert abs(n @ tx) / np.linalg.norm(tx) < 1e-6
    assert abs(n @ ty) / np.linalg.norm(ty) < 1e-6
    # surface_normal is the same normal carried to the world frame (Rᵀ n)
    nw = np.array(surface_normal(sf, si, 0, *h))
    np.testing.assert_allclose(nw, rot.T @ n, atol=1e-9)


def test_conic_along_paraboloid_axis_and_plane_parallel():
    # a = 0 in the quadratic: the linear root
    sf, si = _table(_surface(G.SHAPE_CONIC, curv=1 / 20, conic=-1.0, clip_r=(0.0, 30.0)))
    # from z = −5 up the axis: the vertex, t = 5 (exactly representable)
    assert intersect_surface(sf, si, 0, 0.0, 0.0, -5.0, 0.0, 0.0, 1.0, math.inf) == 5.0
    # parallel to the axis at r = 10: z = r²/(2R) = 2.5 → t = 7.5
    t = intersect_surface(sf, si, 0, 10.0, 0.0, -5.0, 0.0, 0.0, 1.0, math.inf)
    assert abs(t - 7.5) < 1e-13
    # a ray in a plane's plane never meets it
    sf, si = _table(_surface(G.SHAPE_CONIC, clip_r=(0.0, 10.0)))
    assert intersect_surface(sf, si, 0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, math.inf) == -1.0
    t = intersect_surface(sf, si, 0, 1.0, 2.0, 3.0, 0.6, 0.0, -0.8, math.inf)
    assert abs(t - 3.0 / 0.8) < 1e-14


def test_conic_other_sheet_is_not_a_hit():
    # A sphere's far hemisphere is the other sheet of c(x²+y²+z²) − 2z = 0: from inside the
    # sphere R = 10 moving +z, the kernel must not return the back of the sphere (z = 20).
    sf, si = _table(_surface(G.SHAPE_CONIC, curv=0.1, clip_r=(0.0, 10.0)))
    assert intersect_surface(sf, si, 0, 0.0, 0.0, 5.0, 0.0, 0.0, 1.0, math.inf) == -1.0
    # … but coming from behind it finds the vertex
    t = intersect_surface(sf, si, 0, 0.0, 0.0, 25.0, 0.0, 0.0, -1.0, math.inf)
    assert t == 25.0


# --- astigmatic quadrics (a toric cornea) --------------------------------------------------------

QUADRICS = [  # (c 1/mm along x, c_y 1/mm along y, k, aperture radius mm)
    (1 / 7.8, 1 / 7.4, -0.25, 6.0),  # a cornea with ~2.3 D of astigmatism
    (1 / 7.8, 1 / 6.5, -0.25, 6.0),  # strongly astigmatic
    (1 / 8.0, 1 / 7.9, 0.3, 5.5),  # oblate flat meridian
    (1 / 12.0, 1 / 6.0, -1.0, 5.0),  # paraboloid-like in z
    (-1 / 20.0, 1 / 15.0, 0.0, 8.0),  # a saddle (curvatures of opposite signs)
]


def _quadric_sag(c, cy, k, x, y):
    """Vertex-sheet z of c x² + c_y y² + (1+k) c z² − 2 z = 0, solved from the formula."""
    q = c * x * x + cy * y * y
    arg = 1.0 - (1.0 + k) * c * q
    with np.errstate(invalid="ignore"):
        return q / (1.0 + np.sqrt(arg))


def test_quadric_hits_and_normals_match_brute_force():
    """The astigmatic quadric (SHAPE_QUADRIC) against the brute-force root search, its hits on
    the vertex sheet, its normals orthogonal to the tangents (central differences)."""
    rng = np.random.default_rng(15)
    n_rays, total_skipped = 120, 0
    for c, cy, k, ap in QUADRICS:
        rot, origin = _random_rotation(rng), rng.uniform(-5, 5, 3)
        surface = _surface(
            G.SHAPE_QUADRIC, origin=origin, rot=rot, curv=c, conic=k, radius=cy, clip_r=(0, ap)
        )
        sf, si = _table(surface)

        def targets(n, c=c, cy=cy, k=k, ap=ap):
            r = ap * np.sqrt(rng.random(n)) * 1.3
            phi = rng.uniform(0, 2 * np.pi, n)
            x, y = np.minimum(r, ap) * np.cos(phi), np.minimum(r, ap) * np.sin(phi)
            z = np.nan_to_num(_quadric_sag(c, cy, k, x, y))
            return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])

        p, d = _to_world(rot, origin, *_aimed_rays(rng, n_rays, targets))
        hits, skipped = _compare_with_reference(sf, si, (p, d))
        total_skipped += skipped
        assert len(hits) > n_rays // 4, (c, cy, k)
        step = 1e-4  # as _check_conic_normal: truncation and rounding ≪ 1e-6
        for h in hits:
            x, y, z = rot @ (h - origin)
            assert abs(z - _quadric_sag(c, cy, k, x, y)) < 1e-9, (c, cy, k, x, y, z)
            n = rot @ np.array(surface_normal(sf, si, 0, *h))
            assert abs(np.linalg.norm(n) - 1.0) < 1e-12 and n[2] > 0.0

            def surf(u, v, c=c, cy=cy, k=k):
                return np.array([u, v, _quadric_sag(c, cy, k, u, v)])

            tx = (surf(x + step, y) - surf(x - step, y)) / (2 * step)
            ty = (surf(x, y + step) - surf(x, y - step)) / (2 * step)
            assert abs(n @ tx) / np.linalg.norm(tx) < 1e-6
            assert abs(n @ ty) / np.linalg.norm(ty) < 1e-6
    assert total_skipped <= 0.02 * n_rays * len(QUADRICS)


def test_quadric_with_equal_curvatures_is_the_conicoid():
    """c_y = c: the quadric is the conicoid — the same hits and normals to rounding (the
    rotationally symmetric cornea is compiled as SHAPE_CONIC, so its renders are untouched;
    this checks the two shapes describe the same surface)."""
    rng = np.random.default_rng(7)
    c, k, ap = 1 / 7.8, -0.25, 6.0
    rot, origin = _random_rotation(rng), rng.uniform(-5, 5, 3)
    conic = _surface(G.SHAPE_CONIC, origin=origin, rot=rot, curv=c, conic=k, clip_r=(0, ap))
    quad = _surface(
        G.SHAPE_QUADRIC, origin=origin, rot=rot, curv=c, conic=k, radius=c, clip_r=(0, ap)
    )
    sf, si = _table(conic, quad)

    def targets(n):
        r = ap * np.sqrt(rng.random(n))
        phi = rng.uniform(0, 2 * np.pi, n)
        return np.column_stack([r * np.cos(phi), r * np.sin(phi), _sag(c, k, r)])

    p, d = _to_world(rot, origin, *_aimed_rays(rng, 400, targets))
    met = 0
    for pi, di in zip(p, d, strict=True):
        t0 = intersect_surface(sf, si, 0, *pi, *di, math.inf)
        t1 = intersect_surface(sf, si, 1, *pi, *di, math.inf)
        assert (t0 > 0) == (t1 > 0)
        if t0 > 0:
            met += 1
            assert abs(t0 - t1) <= 1e-12 * max(1.0, t0)
            q = pi + t0 * di
            np.testing.assert_allclose(
                surface_normal(sf, si, 1, *q), surface_normal(sf, si, 0, *q), atol=1e-13
            )
    assert met > 100


# --- spheres and cylinders ----------------------------------------------------------------------


def _clips(rng, shape, radius):
    if shape == G.SHAPE_SPHERE:
        rmin = rng.choice([0.0, rng.uniform(0, 0.6 * radius)])
        rmax = rng.choice([math.inf, rng.uniform(0.6 * radius, radius)])
        zlo = rng.choice([-math.inf, rng.uniform(-radius, 0.3 * radius)])
        zhi = rng.choice([math.inf, rng.uniform(-0.3 * radius, radius)])
        zlo, zhi = min(zlo, zhi), max(zlo, zhi)
        return dict(clip_r=(rmin, rmax), clip_z=(zlo, zhi))
    zlo = rng.uniform(-20, 5)
    return dict(clip_z=(zlo, zlo + rng.uniform(1, 25)))


def test_sphere_and_cylinder_hits_match_brute_force_and_closed_form():
    rng = np.random.default_rng(5875)
    n_rays, surfaces, total_skipped = 60, 0, 0
    for shape in (G.SHAPE_SPHERE, G.SHAPE_CYLINDER):
        for _ in range(6):
            radius = rng.uniform(2, 15)
            rot, origin = _random_rotation(rng), rng.uniform(-5, 5, 3)
            clips = _clips(rng, shape, radius)
            sf, si = _table(_surface(shape, origin=origin, rot=rot, radius=radius, **clips))

            def targets(n, radius=radius, shape=shape):
                v = rng.normal(size=(n, 3))
                v[:, :2] *= radius / np.linalg.norm(v[:, :2], axis=1, keepdims=True)
                if shape == G.SHAPE_SPHERE:
                    v *= radius / np.linalg.norm(v, axis=1, keepdims=True)
                else:
                    v[:, 2] = rng.uniform(-20, 30, n)
                return v

            p, d = _to_world(rot, origin, *_aimed_rays(rng, n_rays, targets))
            hits, skipped = _compare_with_reference(sf, si, (p, d))
            total_skipped += skipped
            surfaces += 1
            for h in hits:
                q = rot @ (h - origin)
                # closed-form distance to the surface; the point's rounding is ~ε·L with
                # L ≲ 300 mm, i.e. ≲ 1e-13 mm (tangential t errors move it along the surface)
                dist = np.linalg.norm(q) if shape == G.SHAPE_SPHERE else math.hypot(*q[:2])
                assert abs(dist - radius) < 1e-10
                assert _boundary_distance(sf[0], shape, q) > -1e-12
                # normals: outward, unit
                nw = np.array(surface_normal(sf, si, 0, *h))
                nl = q / radius if shape == G.SHAPE_SPHERE else np.array([*q[:2], 0.0]) / radius
                np.testing.assert_allclose(nw, rot.T @ nl, atol=1e-12)
    assert total_skipped <= 0.02 * n_rays * surfaces


def test_sphere_clip_rejects_first_root_returns_second():
    sf, si = _table(_surface(G.SHAPE_SPHERE, radius=10.0))
    ray = (0.0, 0.0, -20.0, 0.0, 0.0, 1.0)  # meets z = −10 at t = 10 and z = +10 at t = 30
    assert intersect_surface(sf, si, 0, *ray, math.inf) == 10.0
    for clips, expected in (
        (dict(clip_z=(0.0, math.inf)), 30.0),
        (dict(clip_z=(-math.inf, 0.0)), 10.0),
        (dict(clip_z=(-5.0, 5.0)), -1.0),
    ):
        sf, si = _table(_surface(G.SHAPE_SPHERE, radius=10.0, **clips))
        assert intersect_surface(sf, si, 0, *ray, math.inf) == expected, clips
    # t_max is exclusive and respected
    sf, si = _table(_surface(G.SHAPE_SPHERE, radius=10.0))
    assert intersect_surface(sf, si, 0, *ray, 10.0) == -1.0
    assert intersect_surface(sf, si, 0, *ray, 20.0) == 10.0
    # radial clip: a tilted ray meets the sphere at two different radii (closed form below)
    p = np.array([-20.0, 0.0, -3.0])
    d = np.array([1.0, 0.0, 0.2]) / math.hypot(1.0, 0.2)
    b = p @ d
    t1, t2 = -b - math.sqrt(b * b - (p @ p - 100.0)), -b + math.sqrt(b * b - (p @ p - 100.0))
    r1, r2 = (math.hypot(*(p + t * d)[:2]) for t in (t1, t2))
    assert abs(r1 - r2) > 0.1  # room to place a clip radius between them
    for rmin, rmax, expected in (
        (0.5 * (r1 + r2), math.inf, t2 if r2 > r1 else t1),
        (0.0, 0.5 * (r1 + r2), t1 if r1 < r2 else t2),
        (max(r1, r2) + 0.1, math.inf, None),
    ):
        sf, si = _table(_surface(G.SHAPE_SPHERE, radius=10.0, clip_r=(rmin, rmax)))
        t = intersect_surface(sf, si, 0, *p, *d, math.inf)
        if expected is None:
            assert t == -1.0
        else:  # closed-form roots agree to a few ulp of |p| = 20
            assert abs(t - expected) < 1e-12


def test_cylinder_clip_and_distance():
    radius = 5.0
    sf, si = _table(_surface(G.SHAPE_CYLINDER, radius=radius))
    p = np.array([-20.0, 0.0, -10.0])
    d = np.array([1.0, 0.0, 0.5]) / math.hypot(1.0, 0.5)
    # closed form: x = −20 + t dx = ∓5 → t = 15/dx, 25/dx; z = −10 + t dz
    t1, t2 = 15.0 / d[0], 25.0 / d[0]
    z1, z2 = p[2] + t1 * d[2], p[2] + t2 * d[2]
    assert abs(intersect_surface(sf, si, 0, *p, *d, math.inf) - t1) < 1e-12
    for clips, expected in (
        (dict(clip_z=(0.5 * (z1 + z2), math.inf)), t2),
        (dict(clip_z=(-math.inf, 0.5 * (z1 + z2))), t1),
        (dict(clip_z=(z2 + 0.1, math.inf)), None),
    ):
        sf, si = _table(_surface(G.SHAPE_CYLINDER, radius=radius, **clips))
        t = intersect_surface(sf, si, 0, *p, *d, math.inf)
        if expected is None:
            assert t == -1.0
        else:
            assert abs(t - expected) < 1e-12
    # a ray along the axis never meets the mantle (a = 0, b = 0)
    sf, si = _table(_surface(G.SHAPE_CYLINDER, radius=radius))
    assert intersect_surface(sf, si, 0, 1.0, 1.0, -50.0, 0.0, 0.0, 1.0, math.inf) == -1.0


# --- nearest hit among several surfaces ---------------------------------------------------------


def _sphere(centre, radius, **clips):
    return _surface(
        G.SHAPE_SPHERE,
        origin=centre,
        radius=radius,
        bound=(centre, radius * (1 + 1e-6)),
        **clips,
    )


def test_nearest_hit_three_spheres_on_a_line():
    # listed far → near so that the search must replace its best candidate
    sf, si = _table(
        _sphere((0.0, 0.0, 50.0), 3.0),
        _sphere((0.0, 0.0, 30.0), 3.0),
        _sphere((0.0, 0.0, 10.0), 3.0),
    )
    assert nearest_hit(sf, si, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0) == (2, 7.0)
    assert nearest_hit(sf, si, 0.0, 0.0, 20.0, 0.0, 0.0, 1.0) == (1, 7.0)
    assert nearest_hit(sf, si, 0.0, 0.0, 30.0, 0.0, 0.0, 1.0) == (1, 3.0)  # from inside
    assert nearest_hit(sf, si, 0.0, 0.0, 100.0, 0.0, 0.0, -1.0) == (0, 47.0)
    assert nearest_hit(sf, si, 0.0, 0.0, 60.0, 0.0, 0.0, 1.0) == (-1, math.inf)
    assert nearest_hit(sf, si, 0.0, 3.5, 0.0, 0.0, 0.0, 1.0) == (-1, math.inf)  # passes beside


def _random_scene(rng):
    rows = []
    for _ in range(3):
        centre = rng.uniform(-20, 20, 3)
        radius = rng.uniform(2, 8)
        rows.append(_sphere(centre, radius, clip_z=(rng.uniform(-radius, 0.0), math.inf)))
    for _ in range(2):
        rot, origin = _random_rotation(rng), rng.uniform(-20, 20, 3)
        radius, zlo = rng.uniform(1, 5), rng.uniform(-10, 0)
        zhi = zlo + rng.uniform(2, 15)
        centre = origin + rot[2] * 0.5 * (zlo + zhi)
        bound = (centre, math.hypot(radius, 0.5 * (zhi - zlo)) * (1 + 1e-6))
        rows.append(
            _surface(
                G.SHAPE_CYLINDER,
                origin=origin,
                rot=rot,
                radius=radius,
                clip_z=(zlo, zhi),
                bound=bound,
            )
        )
    for c, k, ap in (
        (1 / 12, 0.0, 8.0),
        (-1 / 20, -1.0, 10.0),
        (1 / 9, -0.5, 6.0),
        (0.0, 0.0, 7.0),
    ):
        rot, origin = _random_rotation(rng), rng.uniform(-20, 20, 3)
        s = float(_sag(c, k, ap))
        bound = (origin + rot[2] * s / 2, math.hypot(ap, s / 2) * (1 + 1e-6))
        rows.append(
            _surface(
                G.SHAPE_CONIC,
                origin=origin,
                rot=rot,
                curv=c,
                conic=k,
                clip_r=(0.0, ap),
                bound=bound,
            )
        )
    return _table(*rows)


def test_nearest_hit_equals_exhaustive_search():
    # Culling by bounding spheres must never change the answer: compare with intersect_surface
    # on every surface (t_max = ∞). Same arithmetic on both sides, so the match is exact.
    rng = np.random.default_rng(2005)
    hits = 0
    for _ in range(4):
        sf, si = _random_scene(rng)
        n = sf.shape[0]
        for _ in range(300):
            p = rng.uniform(-40, 40, 3)
            aim = sf[rng.integers(n), G.BX : G.BZ + 1] + rng.normal(scale=3.0, size=3)
            d = aim - p if rng.random() < 0.8 else rng.normal(size=3)
            d /= np.linalg.norm(d)
            ts = np.array([intersect_surface(sf, si, s, *p, *d, math.inf) for s in range(n)])
            ts[ts < 0] = math.inf
            s_ref = int(np.argmin(ts)) if np.isfinite(ts.min()) else -1
            s, t = nearest_hit(sf, si, *p, *d)
            assert (s, t) == (s_ref, ts.min()), (p, d)
            hits += s >= 0
    assert hits > 400  # most rays are aimed at something


# --- quadratic roots ----------------------------------------------------------------------------


def _exact_roots(a, b, c):
    from decimal import Decimal, getcontext

    getcontext().prec = 60
    a, b, c = Decimal(a), Decimal(b), Decimal(c)
    s = (b * b - 4 * a * c).sqrt()
    return sorted([float((-b - s) / (2 * a)), float((-b + s) / (2 * a))])


def test_quadratic_roots_catastrophic_cancellation():
    # b² ≫ 4ac: the textbook (−b + √disc)/2a loses all digits of the small root (for b = 1e8
    # it is off by ~1e-8 relative); the stable form has no cancellation, so each root carries
    # only the rounding of ~5 operations: ≤ 8ε relative.
    cases = [
        (1.0, 1e8, 1.0),
        (1.0, -1e8, 1.0),
        (1e-3, 1e5, 1e-3),
        (2.0, 3e9, -5.0),
        (-3.0, 7e7, 0.25),
        (1e-12, 1.0, 1e-3),  # nearly linear: the far root is huge, the near one ≈ −c/b
    ]
    for a, b, c in cases:
        t1, t2, n = quadratic_roots(a, b, c)
        assert n == 2
        assert t1 <= t2
        for got, want in zip((t1, t2), _exact_roots(a, b, c), strict=True):
            assert abs(got - want) <= 8 * EPS * abs(want), (a, b, c, got, want)
    # and the naive formula would have failed the same check (the test has teeth)
    a, b, c = 1.0, 1e8, 1.0
    naive = (-b + math.sqrt(b * b - 4 * a * c)) / (2 * a)
    assert abs(naive - _exact_roots(a, b, c)[1]) > 1e3 * EPS * abs(_exact_roots(a, b, c)[1])


def test_quadratic_roots_random_well_separated():
    rng = np.random.default_rng(11)
    for _ in range(2000):
        a, b, c = rng.normal(size=3) * 10.0 ** rng.uniform(-6, 6, 3)
        disc, scale = b * b - 4 * a * c, b * b + abs(4 * a * c)
        t1, t2, n = quadratic_roots(a, b, c)
        if disc < -1e-10 * scale:  # clearly complex (beyond the rounding of disc)
            assert n == 0
            continue
        if disc < 0.25 * scale:
            continue  # close roots are ill-conditioned; below, their condition number is ≤ ~4
        assert n == 2 and t1 <= t2
        for got, want in zip((t1, t2), _exact_roots(a, b, c), strict=True):
            assert abs(got - want) <= 16 * EPS * abs(want), (a, b, c, got, want)


def test_quadratic_roots_degenerate():
    assert quadratic_roots(0.0, 2.0, -3.0)[::2] == (1.5, 1)  # linear: one root
    assert quadratic_roots(0.0, 0.0, 1.0)[2] == 0  # no equation left
    assert quadratic_roots(1.0, 0.0, 1.0)[2] == 0  # complex roots
    assert quadratic_roots(1.0, 0.0, 0.0) == (0.0, 0.0, 2)  # double root at 0
    t1, t2, n = quadratic_roots(1.0, 0.0, -4.0)
    assert (t1, t2, n) == (-2.0, 2.0, 2)
    t1, t2, n = quadratic_roots(1.0, -3.0, 0.0)  # c = 0: one root exactly 0
    assert (t1, t2, n) == (0.0, 3.0, 2)
