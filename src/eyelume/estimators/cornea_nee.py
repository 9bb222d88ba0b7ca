"""Next-event estimation through a specular chain: the LED light that reaches a point of a
Lambertian face after a fixed sequence of specular events — refraction at the anterior and
posterior cornea onto the iris, through the two surfaces of a plate or a diverging lens
element, by a plane mirror (a "manifold" connection).

A straight shadow ray from the receiver to an LED crosses the cornea (or the element), where
light bends, so the light that actually arrives comes along a different path. For a point x on
a Lambertian face and an LED at P, we find that path by Newton's method: the emission direction
is parametrised by the point a where it crosses a plane (:class:`Plane`: for the cornea the
plane through its vertex normal to its axis, else the plane through the straight guess at the
distance of x, normal to it), the ray is refracted or reflected by each surface of the chain
(:class:`Chain`) and meets the tangent plane of the face at x at h(a); we solve h(a) = x. The
irradiance at x is then

    E = I(α) · Π T_j or R_j · (cos γ / |a − P|²) / |det ∂h/∂a|,

the LED's radiant intensity times each event's transmittance or reflectance times the solid
angle per unit area of the face (cos γ / |a − P|² is dω/dA at the plane, γ the direction's
angle with its normal). The path counts only when each leg meets what it should: the emission
ray first meets the chain's first surface inside its aperture (no lid or LED body in the way),
then each next one, then the face at x from its lit side. The chains used map directions to
receiver points one to one (the cornea, convex and well before its focus; a plate; a diverging
lens; a plane mirror), so the root is unique; what a converging element or a curved mirror
sends on is left to the light paths (:mod:`.fast`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

from numba import njit

from eyelume.kernels import geometry as G
from eyelume.kernels.interact import interface_at, reflect, refract
from eyelume.kernels.jit import per_ray
from eyelume.kernels.sampling import led_cos_alpha, orthonormal_basis, radiant_intensity
from eyelume.kernels.tables import CHAIN_STEPS, REFLECT, TRANSMIT_A, Ray

__all__ = [
    "irradiance_through_cornea",
    "led_through_cornea",
    "led_through_chain",
    "Chain",
    "Plane",
    "Receiver",
    "chain_row",
    "straight_plane",
]

_TOL2 = 1e-10  # mm²: converged when h(a) is within 1e-5 mm of x


class Chain(NamedTuple):
    """A sequence of ``n`` specular events: surface rows ``surf`` and modes ``mode``
    (:data:`~eyelume.kernels.tables.TRANSMIT_A`, ``TRANSMIT``, ``REFLECT``), the first ``n``
    of each used."""

    n: int
    surf: tuple
    mode: tuple


class Plane(NamedTuple):
    """Where the emission direction is parametrised: the direction from the LED toward
    o + a₁ e1 + a₂ e2 (mm), w the plane's unit normal; Newton starts where the segment from
    the LED to point g crosses it."""

    o: tuple
    e1: tuple
    e2: tuple
    w: tuple
    g: tuple


class Receiver(NamedTuple):
    """A point x on a Lambertian face: position (mm), unit normal n toward the light and the
    tangent basis e1, e2 in which the refracted ray's miss h(a) is measured."""

    x: float
    y: float
    z: float
    nx: float
    ny: float
    nz: float
    e1: tuple
    e2: tuple


class ChainHit(NamedTuple):
    """The ray toward plane point a through the chain: ``ok``, its miss (u, v) in the
    receiver's tangent plane, the product of the events' T or R, the initial direction and
    the plane point (mm)."""

    ok: bool
    u: float
    v: float
    trans: float
    dx: float
    dy: float
    dz: float
    qx: float
    qy: float
    qz: float


@njit(cache=True, inline="always")
def chain_row(row, n):
    """The :class:`Chain` of the first ``n`` steps of a chain row
    (:attr:`~eyelume.kernels.tables.CameraTables.chains`)."""
    k = CHAIN_STEPS
    return Chain(
        n,
        (row[2], row[3], row[4], row[5]),
        (row[2 + k], row[3 + k], row[4 + k], row[5 + k]),
    )


@njit(cache=True, inline="always")
def _event(surfaces, s, mode, ray):
    """The specular event ``mode`` of ``ray`` (its origin on surface s). Returns (ok, dx, dy,
    dz, T or R)."""
    x, y, z, dx, dy, dz = ray
    nx, ny, nz = G.surface_normal(surfaces.sf, surfaces.si, s, x, y, z)
    cos_d = dx * nx + dy * ny + dz * nz
    if cos_d <= 0.0 and mode == TRANSMIT_A:
        return False, dx, dy, dz, 0.0
    f = interface_at(surfaces.sf, surfaces.si, s, cos_d)
    if mode == REFLECT:
        rx, ry, rz = reflect(dx, dy, dz, nx, ny, nz)
        return True, rx, ry, rz, f.reflectance
    ok, tx, ty, tz = refract(dx, dy, dz, nx, ny, nz, f.n1 / f.n2)
    return ok, tx, ty, tz, 1.0 - f.reflectance - f.absorptance


class ChainJacobian(NamedTuple):
    """:func:`_through_jacobian`'s answer: the :class:`ChainHit` and ∂(u, v)/∂(a₁, a₂)
    (mm/mm): ``j11`` = ∂u/∂a₁, ``j21`` = ∂v/∂a₁, ``j12`` = ∂u/∂a₂, ``j22`` = ∂v/∂a₂."""

    hit: ChainHit
    j11: float
    j21: float
    j12: float
    j22: float


@njit(cache=True, inline="always")
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True, inline="always")
def _axpy(a, x, y):
    """a x + y for 3-vectors."""
    return (a * x[0] + y[0], a * x[1] + y[1], a * x[2] + y[2])


@njit(cache=True, inline="always")
def _normal_derivative(sf, si, s, x, y, z, dp):
    """dn: the change of surface ``s``'s world unit normal n at its point (x, y, z) when the
    point moves along the surface by dp (world): n = m/|m|, m the gradient
    :func:`~eyelume.kernels.geometry.surface_normal` normalises, whose change in the local frame
    is diag(D) · dp_local (D per shape), so dn = (dm − n (n · dm)) / |m|."""
    px, py, pz = G.to_local(sf, s, x, y, z)
    qx, qy, qz = G.dir_to_local(sf, s, dp[0], dp[1], dp[2])
    shape = si[s, G.SHAPE]
    if shape == G.SHAPE_CONIC or shape == G.SHAPE_QUADRIC:
        c = sf[s, G.CURV]
        cy = sf[s, G.CURV_Y] if shape == G.SHAPE_QUADRIC else c
        e = c * (1.0 + sf[s, G.CONIC])
        mx, my, mz = -c * px, -cy * py, 1.0 - e * pz
        dmx, dmy, dmz = -c * qx, -cy * qy, -e * qz
    elif shape == G.SHAPE_SPHERE:
        mx, my, mz = px, py, pz
        dmx, dmy, dmz = qx, qy, qz
    elif shape == G.SHAPE_LASHES:
        m2 = sf[s, G.CURV] * sf[s, G.CURV]
        mx, my, mz = px, py, -m2 * pz
        dmx, dmy, dmz = qx, qy, -m2 * qz
    else:  # cylinder
        mx, my, mz = px, py, 0.0
        dmx, dmy, dmz = qx, qy, 0.0
    inv = 1.0 / math.sqrt(mx * mx + my * my + mz * mz)
    lx, ly, lz = mx * inv, my * inv, mz * inv
    k = lx * dmx + ly * dmy + lz * dmz
    wx, wy, wz = G.dir_to_world(
        sf, s, (dmx - k * lx) * inv, (dmy - k * ly) * inv, (dmz - k * lz) * inv
    )
    return (wx, wy, wz)


@njit(cache=True, inline="always")
def _event_derivative(mode, eta, r, n, dr, dn):
    """The change of the direction leaving a specular event (``mode``; refraction with n₁/n₂ =
    ``eta``, as :func:`~eyelume.kernels.interact.refract` computes it, or reflection) when
    the arriving unit direction r changes by dr and the unit normal n by dn."""
    if mode == REFLECT:  # r' = r − 2 (r·n) n
        rn = _dot(r, n)
        drn = _dot(dr, n) + _dot(r, dn)
        return (
            dr[0] - 2.0 * (drn * n[0] + rn * dn[0]),
            dr[1] - 2.0 * (drn * n[1] + rn * dn[1]),
            dr[2] - 2.0 * (drn * n[2] + rn * dn[2]),
        )
    cos_i = -_dot(r, n)
    sign = 1.0
    if cos_i < 0.0:  # refract flips n toward the incoming ray
        sign = -1.0
        cos_i = -cos_i
    nx, ny, nz = sign * n[0], sign * n[1], sign * n[2]
    dnx, dny, dnz = sign * dn[0], sign * dn[1], sign * dn[2]
    dcos_i = -(dr[0] * nx + dr[1] * ny + dr[2] * nz + r[0] * dnx + r[1] * dny + r[2] * dnz)
    cos_t = math.sqrt(max(0.0, 1.0 - eta * eta * max(0.0, 1.0 - cos_i * cos_i)))
    k = eta * cos_i - cos_t  # t = eta r + k n
    dk = eta * dcos_i - eta * eta * cos_i * dcos_i / cos_t
    return (
        eta * dr[0] + dk * nx + k * dnx,
        eta * dr[1] + dk * ny + k * dny,
        eta * dr[2] + dk * nz + k * dnz,
    )


@njit(cache=True, inline="always")
def _event_jacobian(surfaces, s, mode, ray, t, do1, do2, dr1, dr2):  # noqa: PLR0913
    """:func:`_event` at surface ``s`` for ``ray`` (its origin the hit, reached after a leg of
    length t), and the changes of the hit point and of the leaving direction with a₁ and a₂,
    from those of the leg's origin (``do1``, ``do2``) and direction (``dr1``, ``dr2``).
    Returns (ok, dx, dy, dz, T or R, do1, do2, dr1, dr2)."""
    sf, si = surfaces.sf, surfaces.si
    ox, oy, oz, rx, ry, rz = ray
    nx, ny, nz = G.surface_normal(sf, si, s, ox, oy, oz)
    cos_d = rx * nx + ry * ny + rz * nz
    zero = (0.0, 0.0, 0.0)
    if cos_d <= 0.0 and mode == TRANSMIT_A:
        return False, rx, ry, rz, 0.0, zero, zero, zero, zero
    f = interface_at(sf, si, s, cos_d)
    if mode == REFLECT:
        ok = True
        tx, ty, tz = reflect(rx, ry, rz, nx, ny, nz)
        tr = f.reflectance
    else:
        ok, tx, ty, tz = refract(rx, ry, rz, nx, ny, nz, f.n1 / f.n2)
        tr = 1.0 - f.reflectance - f.absorptance
    if not ok:
        return False, rx, ry, rz, 0.0, zero, zero, zero, zero
    n = (nx, ny, nz)
    r = (rx, ry, rz)
    # the hit point's change: dO' = dO + dt r + t dr, dt = −n·(dO + t dr)/(n·r)
    w1 = _axpy(t, dr1, do1)
    w2 = _axpy(t, dr2, do2)
    do1 = _axpy(-_dot(n, w1) / cos_d, r, w1)
    do2 = _axpy(-_dot(n, w2) / cos_d, r, w2)
    dn1 = _normal_derivative(sf, si, s, ox, oy, oz, do1)
    dn2 = _normal_derivative(sf, si, s, ox, oy, oz, do2)
    eta = f.n1 / f.n2
    dr1 = _event_derivative(mode, eta, r, n, dr1, dn1)
    dr2 = _event_derivative(mode, eta, r, n, dr2, dn2)
    return True, tx, ty, tz, tr, do1, do2, dr1, dr2


@per_ray
def _through_jacobian(surfaces, chain, led, plane, a1, a2, rc):
    """The ray from LED point ``led`` (px, py, pz) toward plane point a = (a1, a2) through the
    chain, met with the receiver's tangent plane (its miss (u, v) there), and the Jacobian
    ∂(u, v)/∂(a₁, a₂) of the miss, carried along the chain by differentiating each step (ray
    differentials, Igehy 1999): the emission direction d = (q − P)/|q − P|, each
    intersection (the point stays on the surface: dt = −n · (dO + t dr)/(n · r)), each
    refraction or reflection with the normal's change along the surface
    (:func:`_normal_derivative`), and the receiver's tangent plane. One trace instead of the
    three a forward-difference Jacobian needs. Returns a :class:`ChainJacobian`."""
    sf, si = surfaces.sf, surfaces.si
    px, py, pz = led
    o, e1, e2 = plane.o, plane.e1, plane.e2
    qx = o[0] + a1 * e1[0] + a2 * e2[0]
    qy = o[1] + a1 * e1[1] + a2 * e2[1]
    qz = o[2] + a1 * e1[2] + a2 * e2[2]
    dx, dy, dz = qx - px, qy - py, qz - pz
    inv = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
    dx, dy, dz = dx * inv, dy * inv, dz * inv
    fail = ChainJacobian(ChainHit(False, 0.0, 0.0, 0.0, dx, dy, dz, qx, qy, qz), 0.0, 0.0, 0.0, 0.0)
    d = (dx, dy, dz)
    # ∂d/∂a_i = (e_i − d (d · e_i)) / |q − P|
    dr1 = _axpy(-_dot(d, e1), d, e1)
    dr1 = (dr1[0] * inv, dr1[1] * inv, dr1[2] * inv)
    dr2 = _axpy(-_dot(d, e2), d, e2)
    dr2 = (dr2[0] * inv, dr2[1] * inv, dr2[2] * inv)
    do1 = (0.0, 0.0, 0.0)
    do2 = (0.0, 0.0, 0.0)
    ox, oy, oz = px, py, pz
    rx, ry, rz = dx, dy, dz
    trans = 1.0
    for j in range(chain.n):
        s = chain.surf[j]
        t = G.intersect_surface(sf, si, s, ox, oy, oz, rx, ry, rz, math.inf)
        if t < 0.0:
            return fail
        ox, oy, oz = ox + t * rx, oy + t * ry, oz + t * rz
        ok, tx, ty, tz, tr, do1, do2, dr1, dr2 = _event_jacobian(
            surfaces, s, chain.mode[j], Ray(ox, oy, oz, rx, ry, rz), t, do1, do2, dr1, dr2
        )
        if not ok:
            return fail
        rx, ry, rz = tx, ty, tz
        trans *= tr
    den = rx * rc.nx + ry * rc.ny + rz * rc.nz
    if den >= 0.0:  # must arrive on the lit side, against n
        return fail
    t = ((rc.x - ox) * rc.nx + (rc.y - oy) * rc.ny + (rc.z - oz) * rc.nz) / den
    hx, hy, hz = ox + t * rx - rc.x, oy + t * ry - rc.y, oz + t * rz - rc.z
    u = hx * rc.e1[0] + hy * rc.e1[1] + hz * rc.e1[2]
    v = hx * rc.e2[0] + hy * rc.e2[1] + hz * rc.e2[2]
    # the miss's change: dH = dO + dt r + t dr, dt = −(n_r·dO + t n_r·dr)/(n_r·r)
    nr = (rc.nx, rc.ny, rc.nz)
    r = (rx, ry, rz)
    dh1 = _axpy(-(_dot(nr, do1) + t * _dot(nr, dr1)) / den, r, _axpy(t, dr1, do1))
    dh2 = _axpy(-(_dot(nr, do2) + t * _dot(nr, dr2)) / den, r, _axpy(t, dr2, do2))
    hit = ChainHit(t > 0.0, u, v, trans, dx, dy, dz, qx, qy, qz)
    return ChainJacobian(
        hit, _dot(dh1, rc.e1), _dot(dh1, rc.e2), _dot(dh2, rc.e1), _dot(dh2, rc.e2)
    )


@per_ray
def _path_is_clear(surfaces, chain, target, ray, rc):
    """Whether the path from the LED (``ray``) meets, in turn, each surface of the chain and
    then surface ``target`` at the receiver point with nothing else in between (``target``
    −1: a receiver on no surface, the eye plane: nothing in the way up to it)."""
    sf, si = surfaces.sf, surfaces.si
    ox, oy, oz, dx, dy, dz = ray
    for j in range(chain.n):
        s = chain.surf[j]
        hit, t = G.nearest_hit(sf, si, ox, oy, oz, dx, dy, dz)
        if hit != s:
            return False
        ox, oy, oz = ox + t * dx, oy + t * dy, oz + t * dz
        ok, dx, dy, dz, _ = _event(surfaces, s, chain.mode[j], Ray(ox, oy, oz, dx, dy, dz))
        if not ok:
            return False
    if target < 0:
        ex, ey, ez = rc.x - ox, rc.y - oy, rc.z - oz
        d = math.sqrt(ex * ex + ey * ey + ez * ez)
        return not G.occluded(sf, si, ox, oy, oz, dx, dy, dz, d * (1.0 - 1e-9) - 1e-6)
    hit, t = G.nearest_hit(sf, si, ox, oy, oz, dx, dy, dz)
    if hit != target:
        return False
    ex, ey, ez = ox + t * dx - rc.x, oy + t * dy - rc.y, oz + t * dz - rc.z
    return ex * ex + ey * ey + ez * ez < 1e-6


@per_ray
def led_through_chain(surfaces, chain, plane, target, leds, k, rc):
    """Irradiance (W/mm²) at receiver point ``rc`` (a :class:`Receiver`) on surface ``target``
    (−1: none, the eye plane) from LED ``k`` of ``leds``
    (:class:`~eyelume.kernels.tables.LedTable`) along the path through ``chain`` (a
    :class:`Chain`), its emission direction parametrised on ``plane`` (a :class:`Plane`); 0
    when there is none. See the module docstring."""
    led = (leds.points[k, 0], leds.points[k, 1], leds.points[k, 2])
    px, py, pz = led
    o, e1, e2, w, g = plane
    # straight-line guess: where the segment LED → g crosses the plane
    f = (w[0] * (o[0] - px) + w[1] * (o[1] - py) + w[2] * (o[2] - pz)) / (
        w[0] * (g[0] - px) + w[1] * (g[1] - py) + w[2] * (g[2] - pz)
    )
    gx = px + (g[0] - px) * f - o[0]
    gy = py + (g[1] - py) * f - o[1]
    gz = pz + (g[2] - pz) * f - o[2]
    a1 = gx * e1[0] + gy * e1[1] + gz * e1[2]
    a2 = gx * e2[0] + gy * e2[1] + gz * e2[2]
    found = False
    for _ in range(30):
        hj = _through_jacobian(surfaces, chain, led, plane, a1, a2, rc)
        h = hj.hit
        if not h.ok:
            break
        j11, j21, j12, j22 = hj.j11, hj.j21, hj.j12, hj.j22
        det = j11 * j22 - j12 * j21
        if det == 0.0 or math.isnan(det):
            break
        if h.u * h.u + h.v * h.v < _TOL2:
            found = True
            break
        a1 -= (j22 * h.u - j12 * h.v) / det
        a2 -= (-j21 * h.u + j11 * h.v) / det
    if not found:
        return 0.0
    dx, dy, dz = h.dx, h.dy, h.dz
    if led_cos_alpha(leds, k, dx, dy, dz) <= 0.0:
        return 0.0
    if not _path_is_clear(surfaces, chain, target, Ray(px, py, pz, dx, dy, dz), rc):
        return 0.0
    d2 = (h.qx - px) ** 2 + (h.qy - py) ** 2 + (h.qz - pz) ** 2
    dw_da = abs(dx * w[0] + dy * w[1] + dz * w[2]) / d2  # solid angle per unit plane area at a
    return radiant_intensity(leds, k, dx, dy, dz) * h.trans * dw_da / abs(det)


@njit(cache=True, inline="always")
def _eye_plane(surfaces, cornea, rc):
    """The cornea's parametrisation plane: through the anterior cornea's vertex (surface
    ``cornea``'s origin), normal to its axis w, e1 the camera frame's x made normal to w,
    e2 = e1 × w; Newton starting on the segment from the LED to the receiver point. Every LED
    lit ray toward the iris crosses it steeply near the cornea, wherever the camera is — the
    camera frame's z = 0 (used before) lies 97 mm beyond the eye for a camera whose view a
    mirror folds (paper2005-integrated), behind some LEDs, so their connection failed. For the
    paper's rig (vertex at the origin, w = −z) it is that plane: e1 = x, e2 = y exactly."""
    sf = surfaces.sf
    o = (sf[cornea, G.OX], sf[cornea, G.OY], sf[cornea, G.OZ])
    wx, wy, wz = sf[cornea, G.R20], sf[cornea, G.R21], sf[cornea, G.R22]
    ax, ay, az = 1.0 - wx * wx, -wx * wy, -wx * wz  # x − (x·w) w
    norm = math.sqrt(ax * ax + ay * ay + az * az)
    if norm < 1e-6:  # the axis along x: start from y instead
        ax, ay, az = -wy * wx, 1.0 - wy * wy, -wy * wz
        norm = math.sqrt(ax * ax + ay * ay + az * az)
    ax, ay, az = ax / norm, ay / norm, az / norm
    e2 = (ay * wz - az * wy, az * wx - ax * wz, ax * wy - ay * wx)
    return Plane(o, (ax, ay, az), e2, (wx, wy, wz), (rc.x, rc.y, rc.z))


@per_ray
def straight_plane(leds, k, chain, surfaces, rc):
    """The parametrisation plane of an element's chain for LED k and receiver ``rc``: normal
    to the straight guess — from the LED toward x, or toward x mirrored in a plane mirror of
    the chain (its vertex plane) — through that point, Newton starting there."""
    px, py, pz = leds.points[k, 0], leds.points[k, 1], leds.points[k, 2]
    x, y, z = rc.x, rc.y, rc.z
    sf = surfaces.sf
    for j in range(chain.n - 1, -1, -1):
        if chain.mode[j] == REFLECT:
            s = chain.surf[j]
            mx, my, mz = sf[s, G.R20], sf[s, G.R21], sf[s, G.R22]
            d = (x - sf[s, G.OX]) * mx + (y - sf[s, G.OY]) * my + (z - sf[s, G.OZ]) * mz
            x, y, z = x - 2.0 * d * mx, y - 2.0 * d * my, z - 2.0 * d * mz
    wx, wy, wz = x - px, y - py, z - pz
    dist = math.sqrt(wx * wx + wy * wy + wz * wz)
    wx, wy, wz = wx / dist, wy / dist, wz / dist
    e1, e2 = orthonormal_basis(wx, wy, wz)
    return Plane((x, y, z), e1, e2, (wx, wy, wz), (x, y, z))


@per_ray
def led_through_cornea(surfaces, cornea, target, leds, k, rc):
    """Irradiance (W/mm²) at receiver point ``rc`` (a :class:`Receiver`) on surface ``target``
    from LED ``k`` of ``leds`` (:class:`~eyelume.kernels.tables.LedTable`) along the path
    refracted by the anterior (surface ``cornea``) and posterior (``cornea + 1``) cornea, its
    direction parametrised on the plane through the corneal vertex normal to its axis
    (:func:`_eye_plane`); 0 when there is none. See the module docstring."""
    chain = Chain(2, (cornea, cornea + 1, 0, 0), (TRANSMIT_A, TRANSMIT_A, 0, 0))
    return led_through_chain(surfaces, chain, _eye_plane(surfaces, cornea, rc), target, leds, k, rc)


@per_ray
def irradiance_through_cornea(surfaces, cornea, target, leds, rc):
    """Irradiance (W/mm²) at receiver point ``rc`` (a :class:`Receiver`) on surface ``target``
    from every LED (:class:`~eyelume.kernels.tables.LedTable`), along paths refracted by the
    anterior (surface ``cornea``) and posterior (``cornea + 1``) cornea: the sum of
    :func:`led_through_cornea`. See the module docstring."""
    e_total = 0.0
    for k in range(leds.points.shape[0]):
        e = led_through_cornea(surfaces, cornea, target, leds, k, rc)
        if e != 0.0:
            e_total += e
    return e_total
