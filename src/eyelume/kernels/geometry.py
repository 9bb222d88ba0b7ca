"""Ray–surface intersections and normals, and the nearest hit among a table of surfaces.

Surfaces live in a float table ``sf[s, :]`` and an int table ``si[s, :]`` (columns below, filled by
:mod:`eyelume.compile`). Each surface has a local frame: ``local = R (world − origin)``, with the
rows of R the local axes in world coordinates. Shapes, in their local frame:

* conicoid (plane when c = 0): sag z = c r² / (1 + √(1 − (1+k) c² r²)), vertex at the origin;
* astigmatic quadric (an astigmatic cornea, Navarro's "general ellipsoid"): c x² + c_y y² +
  (1+k) c z² − 2 z = 0, apical curvatures c along x and c_y along y, vertex at the origin (the
  conicoid when c_y = c; kept a shape of its own so that the conicoid's arithmetic, and the
  rotationally symmetric renders, stay bit for bit what they were);
* sphere: |p| = radius;  cylinder: x² + y² = radius² about local z;
* eyelash fringe: the cone x² + y² = m² z² (m = ``CURV``, apex at the origin, the nappe z > 0)
  that exists only on its lashes: ``LASH_COUNT`` strands spaced by ``LASH_PITCH`` (rad) in
  azimuth ψ = atan2(y, x), centred on local +x (ψ = 0), each a ribbon of half-width
  ``LASH_HALF_WIDTH`` (mm) measured across it in the cone (|ψ − ψ_i| · r ≤ half-width at the
  distance r from the axis). A ray crossing the cone between the lashes goes on; one crossing a
  lash meets an opaque surface (:func:`on_lash`). The lash columns follow the geometry's
  (``N_FLOAT``; only a fringe's row has them, the table is padded with zeros).

Each exists where the local radial distance r ∈ [rmin, rmax] and local z ∈ [zlo, zhi]. Normals
point toward *side B*: +z for a conicoid (the side light reaches after it, lens-design
convention), outward for a sphere or cylinder; side A is the other one.
"""

from __future__ import annotations

import math

from numba import njit

from eyelume.kernels.jit import per_ray

# --- float columns of the surface table -------------------------------------------------------
OX, OY, OZ = 0, 1, 2
R00, R01, R02, R10, R11, R12, R20, R21, R22 = 3, 4, 5, 6, 7, 8, 9, 10, 11
CURV, CONIC, RADIUS = 12, 13, 14
CURV_Y = RADIUS  # an astigmatic quadric's curvature along local y (it has no radius)
RMIN2, RMAX2, ZLO, ZHI = 15, 16, 17, 18
BX, BY, BZ, BR = 19, 20, 21, 22  # bounding sphere, world frame
N_A, N_B = 23, 24  # refractive index on sides A and B
REFL, ABSORB = 25, 26  # fixed reflectance and absorptance of a refracting interface
RHO_A, RHO_B = 27, 28  # Lambertian reflectance of the faces of an opaque surface
GBX, GBY, GBZ, GBR = 29, 30, 31, 32  # a group head's sphere about the whole group (GROUP_END)
N_FLOAT = 33
# an eyelash fringe's strands (SHAPE_LASHES), in columns after the geometry's
LASH_COUNT, LASH_PITCH, LASH_HALF_WIDTH = N_FLOAT, N_FLOAT + 1, N_FLOAT + 2
N_FLOAT_WITH_LASHES = N_FLOAT + 3

# --- int columns -------------------------------------------------------------------------------
SHAPE, ACTION, FRESNEL, TALLY_A, TALLY_B = 0, 1, 2, 3, 4
#: On the first row of a group (the rows of one small body: an LED's package, the camera's lens
#: and body), the row after the group's last; 0 on every other row. The searches below skip the
#: whole group when a ray misses the sphere (GBX, GBY, GBZ, GBR) that holds every member's
#: bounding sphere: one test instead of one per member for most rays.
GROUP_END = 5
N_INT = 6

SHAPE_CONIC, SHAPE_SPHERE, SHAPE_CYLINDER, SHAPE_QUADRIC, SHAPE_LASHES = 0, 1, 2, 3, 4
ACT_REFRACT, ACT_OPAQUE, ACT_LENS = 0, 1, 2

T_MIN = 1e-7  # mm: a hit closer than this to a ray's origin is the surface it just left


@njit(cache=True, inline="always")
def dir_to_local(sf, s, x, y, z):
    """World direction → local frame of surface ``s``."""
    return (
        sf[s, R00] * x + sf[s, R01] * y + sf[s, R02] * z,
        sf[s, R10] * x + sf[s, R11] * y + sf[s, R12] * z,
        sf[s, R20] * x + sf[s, R21] * y + sf[s, R22] * z,
    )


@njit(cache=True, inline="always")
def to_local(sf, s, x, y, z):
    """World point → local frame of surface ``s``."""
    return dir_to_local(sf, s, x - sf[s, OX], y - sf[s, OY], z - sf[s, OZ])


@njit(cache=True, inline="always")
def dir_to_world(sf, s, x, y, z):
    """Local direction of surface ``s`` → world (the transpose of the rotation)."""
    return (
        sf[s, R00] * x + sf[s, R10] * y + sf[s, R20] * z,
        sf[s, R01] * x + sf[s, R11] * y + sf[s, R21] * z,
        sf[s, R02] * x + sf[s, R12] * y + sf[s, R22] * z,
    )


@njit(cache=True, inline="always")
def quadratic_roots(a, b, c):
    """Real roots (t1, t2, n) of a t² + b t + c = 0, numerically stable; n = number of roots.

    Degenerates to the linear root when a = 0 (a plane, or a ray along a paraboloid's axis).
    """
    if a == 0.0:
        if b == 0.0:
            return 0.0, 0.0, 0
        return -c / b, 0.0, 1
    disc = b * b - 4.0 * a * c
    if disc < 0.0:
        return 0.0, 0.0, 0
    q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
    t1 = q / a
    t2 = c / q if q != 0.0 else t1
    if t1 > t2:
        t1, t2 = t2, t1
    return t1, t2, 2


@njit(cache=True, inline="always")
def conic_coefficients(c, k, px, py, pz, dx, dy, dz):
    """Coefficients of the conicoid c (x² + y² + (1+k) z²) − 2 z = 0 along p + t d."""
    e = 1.0 + k
    a = c * (dx * dx + dy * dy + e * dz * dz)
    b = 2.0 * (c * (px * dx + py * dy + e * pz * dz) - dz)
    cc = c * (px * px + py * py + e * pz * pz) - 2.0 * pz
    return a, b, cc


@njit(cache=True, inline="always")
def quadric_coefficients(c, cy, k, px, py, pz, dx, dy, dz):
    """Coefficients of the astigmatic quadric c x² + c_y y² + (1+k) c z² − 2 z = 0 along
    p + t d (:func:`conic_coefficients` when c_y = c)."""
    e = (1.0 + k) * c
    a = c * dx * dx + cy * dy * dy + e * dz * dz
    b = 2.0 * (c * px * dx + cy * py * dy + e * pz * dz - dz)
    cc = c * px * px + cy * py * py + e * pz * pz - 2.0 * pz
    return a, b, cc


@njit(cache=True, inline="always")
def quadric_normal(c, cy, k, x, y, z):
    """Unit normal of the astigmatic quadric at a local point, toward +z at the vertex: the
    gradient of 2 z − c x² − c_y y² − (1+k) c z², halved."""
    nx, ny, nz = -c * x, -cy * y, 1.0 - c * (1.0 + k) * z
    inv = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz)
    return nx * inv, ny * inv, nz * inv


@njit(cache=True, inline="always")
def on_vertex_branch(c, k, z):
    """Whether a point of the conicoid lies on the sheet through the vertex: (1+k) c z ≤ 1."""
    return (1.0 + k) * c * z <= 1.0


@njit(cache=True, inline="always")
def conic_normal(c, k, x, y, z):
    """Unit normal of the conicoid at a local point, pointing toward +z at the vertex."""
    nx, ny, nz = -c * x, -c * y, 1.0 - c * (1.0 + k) * z
    inv = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz)
    return nx * inv, ny * inv, nz * inv


@njit(cache=True, inline="always")
def on_lash(count, pitch, half_width, x, y):
    """Whether the local point (x, y, ·) of an eyelash fringe lies on one of its ``count``
    lashes: the strand i nearest its azimuth ψ = atan2(y, x) sits at ψ_i = (i + ½ − count/2)
    · pitch (i = 0 … count − 1) and covers |ψ − ψ_i| · r ≤ ``half_width`` (mm), r = √(x² + y²).
    The fringe covers the fraction 2 · half_width / (r · pitch) of its span at r."""
    psi = math.atan2(y, x)
    u = psi / pitch + 0.5 * count
    i = math.floor(u)
    if i < 0 or i >= count:
        return False
    off = (u - i - 0.5) * pitch  # rad from the strand's centre
    return abs(off) * math.sqrt(x * x + y * y) <= half_width


@njit(cache=True, inline="always")
def _valid(sf, s, shape, x, y, z):
    r2 = x * x + y * y
    if r2 < sf[s, RMIN2] or r2 > sf[s, RMAX2] or z < sf[s, ZLO] or z > sf[s, ZHI]:
        return False
    if shape == SHAPE_CONIC or shape == SHAPE_QUADRIC:
        return on_vertex_branch(sf[s, CURV], sf[s, CONIC], z)
    if shape == SHAPE_LASHES:
        return on_lash(sf[s, LASH_COUNT], sf[s, LASH_PITCH], sf[s, LASH_HALF_WIDTH], x, y)
    return True


@per_ray
def intersect_surface(sf, si, s, x, y, z, dx, dy, dz, t_max):
    """Nearest valid hit of a world ray with surface ``s`` beyond T_MIN and before ``t_max``.

    Returns t (mm), or -1.0 if none.
    """
    px, py, pz = to_local(sf, s, x, y, z)
    ux, uy, uz = dir_to_local(sf, s, dx, dy, dz)
    shape = si[s, SHAPE]
    if shape == SHAPE_CONIC:
        a, b, c = conic_coefficients(sf[s, CURV], sf[s, CONIC], px, py, pz, ux, uy, uz)
    elif shape == SHAPE_SPHERE:
        a = 1.0
        b = 2.0 * (px * ux + py * uy + pz * uz)
        c = px * px + py * py + pz * pz - sf[s, RADIUS] * sf[s, RADIUS]
    elif shape == SHAPE_QUADRIC:
        a, b, c = quadric_coefficients(
            sf[s, CURV], sf[s, CURV_Y], sf[s, CONIC], px, py, pz, ux, uy, uz
        )
    elif shape == SHAPE_LASHES:
        m2 = sf[s, CURV] * sf[s, CURV]
        a = ux * ux + uy * uy - m2 * uz * uz
        b = 2.0 * (px * ux + py * uy - m2 * pz * uz)
        c = px * px + py * py - m2 * pz * pz
    else:
        a = ux * ux + uy * uy
        b = 2.0 * (px * ux + py * uy)
        c = px * px + py * py - sf[s, RADIUS] * sf[s, RADIUS]
    t1, t2, n = quadratic_roots(a, b, c)
    if n >= 1 and T_MIN < t1 < t_max:
        if _valid(sf, s, shape, px + t1 * ux, py + t1 * uy, pz + t1 * uz):
            return t1
    if n == 2 and T_MIN < t2 < t_max:
        if _valid(sf, s, shape, px + t2 * ux, py + t2 * uy, pz + t2 * uz):
            return t2
    return -1.0


@per_ray
def surface_normal(sf, si, s, x, y, z):
    """World unit normal (toward side B) of surface ``s`` at world point (x, y, z) on it."""
    px, py, pz = to_local(sf, s, x, y, z)
    shape = si[s, SHAPE]
    if shape == SHAPE_CONIC:
        nx, ny, nz = conic_normal(sf[s, CURV], sf[s, CONIC], px, py, pz)
    elif shape == SHAPE_SPHERE:
        inv = 1.0 / sf[s, RADIUS]
        nx, ny, nz = px * inv, py * inv, pz * inv
    elif shape == SHAPE_QUADRIC:
        nx, ny, nz = quadric_normal(sf[s, CURV], sf[s, CURV_Y], sf[s, CONIC], px, py, pz)
    elif shape == SHAPE_LASHES:  # away from the cone's axis
        m2 = sf[s, CURV] * sf[s, CURV]
        nx, ny, nz = px, py, -m2 * pz
        inv = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz)
        nx, ny, nz = nx * inv, ny * inv, nz * inv
    else:
        inv = 1.0 / math.sqrt(px * px + py * py)
        nx, ny, nz = px * inv, py * inv, 0.0
    return dir_to_world(sf, s, nx, ny, nz)


@njit(cache=True, inline="always")
def _beyond_sphere(sf, s, c, x, y, z, dx, dy, dz, t_far):
    """Whether the ray (origin x, unit d) surely misses what row ``s``'s sphere holds before
    ``t_far``: the sphere in columns c … c + 3 (centre, radius: ``BX`` for the row's bounding
    sphere, ``GBX`` for its group's) lies off the line, behind the origin or beyond t_far."""
    cx, cy, cz = sf[s, c] - x, sf[s, c + 1] - y, sf[s, c + 2] - z
    tc = cx * dx + cy * dy + cz * dz
    br = sf[s, c + 3]
    d2 = cx * cx + cy * cy + cz * cz - tc * tc
    return d2 > br * br or tc + br < 0.0 or tc - br > t_far


@per_ray
def _nearest_in(sf, si, first, last, x, y, z, dx, dy, dz, best_s, best_t):
    """The nearest hit nearer than ``best_t`` among rows ``first`` … ``last`` − 1 (``first`` a
    group's first row or a row outside any group), or (``best_s``, ``best_t``) if none: the
    search loop of :func:`nearest_hit`. A group that reaches past ``last`` is searched whole."""
    s = first
    while s < last:
        end = si[s, GROUP_END]
        if end > s:  # a group: all its members are missed if its sphere is
            if _beyond_sphere(sf, s, GBX, x, y, z, dx, dy, dz, best_t):
                s = end
                continue
        if not _beyond_sphere(sf, s, BX, x, y, z, dx, dy, dz, best_t):
            t = intersect_surface(sf, si, s, x, y, z, dx, dy, dz, best_t)
            if t > 0.0:
                best_t = t
                best_s = s
        s += 1
    return best_s, best_t


@per_ray
def _nearest_in_within(sf, si, first, last, x, y, z, dx, dy, dz, gaps, cos_t, best_s, best_t):  # noqa: PLR0913
    """:func:`_nearest_in` skipping the rows (and groups) out of reach
    (:func:`nearest_hit_within`)."""
    s = first
    while s < last:
        end = si[s, GROUP_END]
        if end > s:
            if cos_t > gaps[s]:
                s = end
                continue
            if _beyond_sphere(sf, s, GBX, x, y, z, dx, dy, dz, best_t):
                s = end
                continue
        elif cos_t > gaps[s]:
            s += 1
            continue
        if not _beyond_sphere(sf, s, BX, x, y, z, dx, dy, dz, best_t):
            t = intersect_surface(sf, si, s, x, y, z, dx, dy, dz, best_t)
            if t > 0.0:
                best_t = t
                best_s = s
        s += 1
    return best_s, best_t


@per_ray
def nearest_hit(sf, si, x, y, z, dx, dy, dz):
    """Non-sequential search: (surface, t) of the nearest hit along the ray, or (-1, inf).

    A bounding sphere per surface rejects most candidates before the exact test, and one per
    group of rows (``GROUP_END``) rejects the whole group at once.
    """
    return _nearest_in(sf, si, 0, sf.shape[0], x, y, z, dx, dy, dz, -1, math.inf)


@per_ray
def nearest_hit_within(sf, si, x, y, z, dx, dy, dz, gaps, cos_t):
    """:func:`nearest_hit` for a ray whose direction makes polar cosine ``cos_t`` with the
    normal n of the point it leaves, given ``gaps`` (:func:`free_cone_gaps` at that point and
    n): surface s is skipped when cos_t > gaps[s] (the direction lies within the cone about n
    that surely misses it; a group's first row holds the whole group's, so the group is
    skipped), the others tested as :func:`nearest_hit` tests them — the same answer, bit for
    bit, at the cost of one comparison for each surface out of reach (most of a skin vertex's
    continuation rays meet nothing, ~80 % on vr-offaxis)."""
    n = sf.shape[0]
    return _nearest_in_within(sf, si, 0, n, x, y, z, dx, dy, dz, gaps, cos_t, -1, math.inf)


@per_ray
def nearest_lit_hit(sf, si, x, y, z, dx, dy, dz, dark_from):
    """:func:`nearest_hit` for a camera path, to which the rows from ``dark_from`` on are dark
    (:func:`dark_tail`: each one ends the path and sends it no light): those rows are searched
    only when a lit row is met, and only nearer than it, since a ray that meets no lit row
    brings nothing back whether or not it meets a dark one. (surface, t) as :func:`nearest_hit`
    when a lit row is met — a dark row in front of it included — else (-1, inf), where
    :func:`nearest_hit` may name a dark row: to the camera path the same (nothing)."""
    s, t = _nearest_in(sf, si, 0, dark_from, x, y, z, dx, dy, dz, -1, math.inf)
    if s < 0:
        return s, t
    return _nearest_in(sf, si, dark_from, sf.shape[0], x, y, z, dx, dy, dz, s, t)


@per_ray
def nearest_lit_hit_within(sf, si, x, y, z, dx, dy, dz, gaps, cos_t, dark_from):  # noqa: PLR0913
    """:func:`nearest_lit_hit` with :func:`nearest_hit_within`'s skipping of the rows out of
    reach."""
    s, t = _nearest_in_within(sf, si, 0, dark_from, x, y, z, dx, dy, dz, gaps, cos_t, -1, math.inf)
    if s < 0:
        return s, t
    n = sf.shape[0]
    return _nearest_in_within(sf, si, dark_from, n, x, y, z, dx, dy, dz, gaps, cos_t, s, t)


def dark_tail(sf, si) -> int:
    """The first row of the table's dark tail: the longest run of last rows each of which ends
    a camera path without sending it light — the lens's entrance (``ACT_LENS``) or an opaque
    surface black on both faces (``RHO_A`` = ``RHO_B`` = 0: the LED packages and the camera's
    body; :func:`_sends_nothing`) — moved up to a group's end if it falls inside one.
    ``sf.shape[0]`` when the last row is not dark. Read by :func:`nearest_lit_hit`
    (``CameraTables.dark_from``)."""
    first = sf.shape[0]
    while first > 0 and _sends_nothing(sf, si, first - 1):
        first -= 1
    for s in range(first):
        if si[s, GROUP_END] > first:  # a group that straddles it is searched whole
            first = int(si[s, GROUP_END])
    return int(first)


@per_ray
def occluded(sf, si, x, y, z, dx, dy, dz, t_max):
    """Whether any surface meets the ray at a distance in (T_MIN, ``t_max``): the shadow-ray
    test of next-event estimation. The same answer as ``nearest_hit``'s ``t < t_max`` (a hit
    before ``t_max`` exists exactly when the nearest one is before it), but it prunes every
    bounding sphere (and group sphere) that lies beyond ``t_max`` from the start and stops at
    the first hit."""
    n = sf.shape[0]
    s = 0
    while s < n:
        end = si[s, GROUP_END]
        if end > s:
            if _beyond_sphere(sf, s, GBX, x, y, z, dx, dy, dz, t_max):
                s = end
                continue
        if not _beyond_sphere(sf, s, BX, x, y, z, dx, dy, dz, t_max):
            if intersect_surface(sf, si, s, x, y, z, dx, dy, dz, t_max) > 0.0:
                return True
        s += 1
    return False


@per_ray
def occluded_within(sf, si, x, y, z, dx, dy, dz, t_max, gaps, cos_t):
    """:func:`occluded` for a ray leaving a vertex at polar cosine ``cos_t`` about its normal,
    skipping the surfaces (and groups) out of its reach (``gaps``, as
    :func:`nearest_hit_within`): the same answer, bit for bit."""
    n = sf.shape[0]
    s = 0
    while s < n:
        end = si[s, GROUP_END]
        if end > s:
            if cos_t > gaps[s]:
                s = end
                continue
            if _beyond_sphere(sf, s, GBX, x, y, z, dx, dy, dz, t_max):
                s = end
                continue
        elif cos_t > gaps[s]:
            s += 1
            continue
        if not _beyond_sphere(sf, s, BX, x, y, z, dx, dy, dz, t_max):
            if intersect_surface(sf, si, s, x, y, z, dx, dy, dz, t_max) > 0.0:
                return True
        s += 1
    return False


#: Longest clipped cylinder (in radii) :func:`free_cone` covers by spheres; a longer one (an
#: unclipped cylinder) is bounded by its bounding sphere.
_MAX_PIECES = 32


@njit(cache=True, inline="always")
def _sphere_gap(cx, cy, cz, r, x, y, z, nx, ny, nz):
    """cos(β − α) for the sphere (centre c, radius r) seen from x: β the angle between unit n
    and the direction toward c, α = asin(r/|c − x|) the sphere's angular radius, so every
    direction within β − α of n misses the sphere. 2.0 when they overlap (β ≤ α, or x inside
    the sphere: no direction about n is safe). On the sphere (x on another surface of the same
    sphere, to 1e-12 of r) its cone is the half-space of directions toward c (α = 90°)."""
    vx, vy, vz = cx - x, cy - y, cz - z
    d2 = vx * vx + vy * vy + vz * vz
    if d2 <= r * r:
        d = math.sqrt(d2)
        if d < r * (1.0 - 1e-12):
            return 2.0
        # on the sphere (to rounding): it is met by the directions toward its inside only
        cb = (vx * nx + vy * ny + vz * nz) / d
        return math.sqrt(1.0 - cb * cb) if cb < 0.0 else 2.0
    d = math.sqrt(d2)
    cb = (vx * nx + vy * ny + vz * nz) / d
    sa = r / d
    ca = math.sqrt(1.0 - sa * sa)
    if cb >= ca:
        return 2.0
    return cb * ca + math.sqrt(max(0.0, 1.0 - cb * cb)) * sa


@njit(cache=True, inline="always")
def _sends_nothing(sf, si, s):
    """Whether surface ``s`` ends a camera path with nothing: the imaging lens, or opaque and
    black on both faces (ρ = 0: LED and camera bodies, the retina)."""
    action = si[s, ACTION]
    if action == ACT_LENS:
        return True
    return action == ACT_OPAQUE and sf[s, RHO_A] <= 0.0 and sf[s, RHO_B] <= 0.0


@njit(cache=True, inline="always")
def _surface_gap(sf, si, s, own, x, y, z, nx, ny, nz):
    """cos θ below which a direction about n at x surely misses surface ``s`` (the shapes of
    :func:`free_cone`): −2.0 when ``s`` can be skipped, 2.0 when no cone about n is safe."""
    if _sends_nothing(sf, si, s):
        return -2.0
    return _shape_gap(sf, si, s, own, x, y, z, nx, ny, nz)


@njit(cache=True, inline="always")
def _shape_gap(sf, si, s, own, x, y, z, nx, ny, nz):
    """:func:`_surface_gap` for any surface, whatever it sends back."""
    shape = si[s, SHAPE]
    ox, oy, oz = sf[s, OX], sf[s, OY], sf[s, OZ]
    ax, ay, az = sf[s, R20], sf[s, R21], sf[s, R22]  # local z: plane normal, cylinder axis
    if shape == SHAPE_CONIC and sf[s, CURV] == 0.0:
        if s == own:
            return -2.0
        # both the half-space of directions toward its plane and the cone of its bounding
        # sphere hold every direction that meets it: the narrower bound counts
        c = _sphere_gap(sf[s, BX], sf[s, BY], sf[s, BZ], sf[s, BR], x, y, z, nx, ny, nz)
        h = (x - ox) * ax + (y - oy) * ay + (z - oz) * az
        cb = -(nx * ax + ny * ay + nz * az) if h > 0.0 else nx * ax + ny * ay + nz * az
        if abs(h) >= 1e-9 and cb < 0.0:  # n points away from the plane
            c = min(c, math.sqrt(1.0 - cb * cb))  # cos(β − 90°)
        return c
    if shape == SHAPE_SPHERE:
        if s == own and (x - ox) * nx + (y - oy) * ny + (z - oz) * nz > 0.0:
            return -2.0
        return _sphere_gap(ox, oy, oz, sf[s, RADIUS], x, y, z, nx, ny, nz)
    if shape != SHAPE_CYLINDER:
        return _sphere_gap(sf[s, BX], sf[s, BY], sf[s, BZ], sf[s, BR], x, y, z, nx, ny, nz)
    px, py, pz = x - ox, y - oy, z - oz
    pa = px * ax + py * ay + pz * az
    if s == own and (px - pa * ax) * nx + (py - pa * ay) * ny + (pz - pa * az) * nz > 0.0:
        return -2.0
    r = sf[s, RADIUS]
    length = sf[s, ZHI] - sf[s, ZLO]
    if not length <= _MAX_PIECES * r:
        return _sphere_gap(sf[s, BX], sf[s, BY], sf[s, BZ], sf[s, BR], x, y, z, nx, ny, nz)
    m = max(1, math.ceil(length / r))
    step = length / m
    rp = math.sqrt(r * r + 0.25 * step * step)
    c = -1.0
    for i in range(m):
        t = sf[s, ZLO] + (i + 0.5) * step
        c = max(c, _sphere_gap(ox + t * ax, oy + t * ay, oz + t * az, rp, x, y, z, nx, ny, nz))
    return c


@per_ray
def free_cone(sf, si, own, x, y, z, nx, ny, nz):
    """sin²θ₀ of a cone about unit normal n at point x on surface ``own`` (−1: none) whose
    directions meet nothing that can send light back along them: the rays from x within θ₀ of
    n miss every surface but the imaging lens (``ACT_LENS``, where a camera path ends) and the
    opaque ones black on both sides (ρ = 0: LED and camera bodies, the retina), so what they
    carry is exactly 0. 0.0 when no such cone is found; 1.0 when nothing lies within 90° of n
    (the whole hemisphere about n is empty).

    Each surface is bounded by shapes whose angular extent from x is exact: a plane (conic of
    curvature 0) by its bounding sphere or its whole plane — the half-space of directions
    toward it — whichever is narrower, except ``own`` (a ray leaving a plane never meets it
    again); a sphere by its whole sphere; a clipped
    cylinder by spheres covering its clipped length in pieces of at most one radius (radius
    ≤ √(R² + (R/2)²)); any other surface, and a cylinder longer than ``_MAX_PIECES`` radii, by
    its bounding sphere. ``own`` being a sphere or cylinder seen from outside (n away from its
    centre or axis) is skipped too: a ray leaving a convex surface outward never meets it
    again. A direction within θ₀ of n is then at more than each shape's angular radius from
    it (θ₀ = min over shapes of β − α, :func:`_sphere_gap`). Deterministic in (x, n), so a
    continuation sampled only outside the cone, with its density renormalised, stays
    unbiased (:func:`eyelume.estimators.fast._path_radiance`)."""
    cmax = -1.0  # cos θ₀ so far: the largest cos(β − α) over the shapes
    for s in range(sf.shape[0]):
        c = _surface_gap(sf, si, s, own, x, y, z, nx, ny, nz)
        if c > 1.0:
            return 0.0
        cmax = max(cmax, c)
    if cmax <= 0.0:
        return 1.0
    return 1.0 - cmax * cmax


@per_ray
def free_cone_gaps(sf, si, own, x, y, z, nx, ny, nz, gaps):
    """:func:`free_cone` (the same value), and into ``gaps`` (n_surfaces,) for each surface s
    the polar cosine about n above which a direction from x surely misses it (2.0: none
    does; −2.0: ``own``, which a ray leaving it never meets again), what
    :func:`nearest_hit_within` skips by; on a group's first row (``GROUP_END``) the largest
    over the group, so that a direction beyond it misses every member. The surfaces
    :func:`free_cone` leaves out because they send nothing back (the lens, the black bodies)
    are bounded all the same — a ray meeting one ends there, so skipping it is not the same
    answer — except that a cheap test stands in for their shapes: their bounding sphere
    (they are small)."""
    cmax = -1.0
    blocked = False
    for s in range(sf.shape[0]):
        if _sends_nothing(sf, si, s):
            gaps[s] = _sphere_gap(sf[s, BX], sf[s, BY], sf[s, BZ], sf[s, BR], x, y, z, nx, ny, nz)
            continue
        c = _shape_gap(sf, si, s, own, x, y, z, nx, ny, nz)
        gaps[s] = c
        if c > 1.0:
            blocked = True
        cmax = max(cmax, c)
    for s in range(sf.shape[0]):  # a group's first row: the gap of the whole group
        for m in range(s + 1, si[s, GROUP_END]):
            gaps[s] = max(gaps[s], gaps[m])
    if blocked:
        return 0.0
    if cmax <= 0.0:
        return 1.0
    return 1.0 - cmax * cmax
