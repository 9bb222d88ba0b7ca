"""Next-event estimation through the cornea: the LED light that reaches a point of the iris by
refraction at the anterior and posterior cornea (a specular, "manifold" connection).

A straight shadow ray from the iris to an LED crosses the cornea, where light bends, so the
light that actually arrives comes along a different, refracted path. For a point x on a
Lambertian face behind the cornea and an LED at P, we find that path by Newton's method: the
emission direction is parametrised by the point a where it crosses the eye plane z = 0, the ray
is refracted by both cornea surfaces (always transmitted) and meets the tangent plane of the
face at x at h(a); we solve h(a) = x. The irradiance at x is then

    E = I(α) · T · (cos γ / |a − P|²) / |det ∂h/∂a|,

the LED's radiant intensity times the transmittance T of the two interfaces times the solid
angle per unit area of the face (cos γ / |a − P|² is dω/dA at the eye plane, γ the direction's
angle with its normal). The path counts only when each leg meets what it should: the emission
ray first meets the anterior cornea inside its aperture (no lid or LED body in the way), then
the posterior cornea, then the face at x from its lit side. The cornea, convex and well before
its focus, maps directions to iris points one to one, so the root is unique.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from numba import njit

from eyelume.kernels import geometry as G
from eyelume.kernels.interact import interface_at, refract
from eyelume.kernels.jit import per_ray
from eyelume.kernels.sampling import led_cos_alpha, radiant_intensity
from eyelume.kernels.tables import Ray

__all__ = ["irradiance_through_cornea", "led_through_cornea"]

_H = 1e-4  # mm: forward-difference step on the eye plane
_TOL2 = 1e-10  # mm²: converged when h(a) is within 1e-5 mm of x


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


class CorneaHit(NamedTuple):
    """The ray toward eye-plane point a through both cornea surfaces: ``ok``, its miss (u, v) in
    the receiver's tangent plane, the transmittance T and the initial direction."""

    ok: bool
    u: float
    v: float
    trans: float
    dx: float
    dy: float
    dz: float


@njit(cache=True, inline="always")
def _transmit(surfaces, s, ray):
    """Refract ``ray`` (its origin on surface s, arriving from side A). Returns (ok, dx, dy,
    dz, T)."""
    x, y, z, dx, dy, dz = ray
    nx, ny, nz = G.surface_normal(surfaces.sf, surfaces.si, s, x, y, z)
    cos_d = dx * nx + dy * ny + dz * nz
    if cos_d <= 0.0:
        return False, dx, dy, dz, 0.0
    f = interface_at(surfaces.sf, surfaces.si, s, cos_d)
    ok, tx, ty, tz = refract(dx, dy, dz, nx, ny, nz, f.n1 / f.n2)
    return ok, tx, ty, tz, 1.0 - f.reflectance - f.absorptance


@per_ray
def _through(surfaces, cornea, led, ax, ay, rc):
    """The ray from LED point ``led`` (px, py, pz) toward (ax, ay, 0) through both cornea
    surfaces, met with the receiver's tangent plane. Returns a :class:`CorneaHit`."""
    px, py, pz = led
    dx, dy, dz = ax - px, ay - py, -pz
    inv = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
    dx, dy, dz = dx * inv, dy * inv, dz * inv
    ox, oy, oz = px, py, pz
    rx, ry, rz = dx, dy, dz
    trans = 1.0
    for s in (cornea, cornea + 1):
        t = G.intersect_surface(surfaces.sf, surfaces.si, s, ox, oy, oz, rx, ry, rz, math.inf)
        if t < 0.0:
            return CorneaHit(False, 0.0, 0.0, 0.0, dx, dy, dz)
        ox, oy, oz = ox + t * rx, oy + t * ry, oz + t * rz
        ok, rx, ry, rz, tr = _transmit(surfaces, s, Ray(ox, oy, oz, rx, ry, rz))
        if not ok:
            return CorneaHit(False, 0.0, 0.0, 0.0, dx, dy, dz)
        trans *= tr
    den = rx * rc.nx + ry * rc.ny + rz * rc.nz
    if den >= 0.0:  # must arrive on the lit side, against n
        return CorneaHit(False, 0.0, 0.0, 0.0, dx, dy, dz)
    t = ((rc.x - ox) * rc.nx + (rc.y - oy) * rc.ny + (rc.z - oz) * rc.nz) / den
    hx, hy, hz = ox + t * rx - rc.x, oy + t * ry - rc.y, oz + t * rz - rc.z
    u = hx * rc.e1[0] + hy * rc.e1[1] + hz * rc.e1[2]
    v = hx * rc.e2[0] + hy * rc.e2[1] + hz * rc.e2[2]
    return CorneaHit(t > 0.0, u, v, trans, dx, dy, dz)


@per_ray
def _path_is_clear(surfaces, cornea, target, ray, rc):
    """Whether the refracted path from the LED (``ray``) meets, in turn, the anterior cornea,
    the posterior cornea and surface ``target`` at the receiver point with nothing else in
    between."""
    sf, si = surfaces.sf, surfaces.si
    ox, oy, oz, dx, dy, dz = ray
    for s in (cornea, cornea + 1):
        hit, t = G.nearest_hit(sf, si, ox, oy, oz, dx, dy, dz)
        if hit != s:
            return False
        ox, oy, oz = ox + t * dx, oy + t * dy, oz + t * dz
        ok, dx, dy, dz, _ = _transmit(surfaces, s, Ray(ox, oy, oz, dx, dy, dz))
        if not ok:
            return False
    hit, t = G.nearest_hit(sf, si, ox, oy, oz, dx, dy, dz)
    if hit != target:
        return False
    ex, ey, ez = ox + t * dx - rc.x, oy + t * dy - rc.y, oz + t * dz - rc.z
    return ex * ex + ey * ey + ez * ez < 1e-6


@per_ray
def led_through_cornea(surfaces, cornea, target, leds, k, rc):
    """Irradiance (W/mm²) at receiver point ``rc`` (a :class:`Receiver`) on surface ``target``
    from LED ``k`` of ``leds`` (:class:`~eyelume.kernels.tables.LedTable`) along the path
    refracted by the anterior (surface ``cornea``) and posterior (``cornea + 1``) cornea; 0
    when there is none. See the module docstring."""
    x, y, z = rc.x, rc.y, rc.z
    led = (leds.points[k, 0], leds.points[k, 1], leds.points[k, 2])
    px, py, pz = led
    # straight-line guess: where the segment LED → x crosses the eye plane
    f = pz / (pz - z)
    ax, ay = px + (x - px) * f, py + (y - py) * f
    found = False
    for _ in range(30):
        h = _through(surfaces, cornea, led, ax, ay, rc)
        if not h.ok:
            break
        h1 = _through(surfaces, cornea, led, ax + _H, ay, rc)
        h2 = _through(surfaces, cornea, led, ax, ay + _H, rc)
        if not (h1.ok and h2.ok):
            break
        j11, j21 = (h1.u - h.u) / _H, (h1.v - h.v) / _H
        j12, j22 = (h2.u - h.u) / _H, (h2.v - h.v) / _H
        det = j11 * j22 - j12 * j21
        if det == 0.0 or math.isnan(det):
            break
        if h.u * h.u + h.v * h.v < _TOL2:
            found = True
            break
        ax -= (j22 * h.u - j12 * h.v) / det
        ay -= (-j21 * h.u + j11 * h.v) / det
    if not found:
        return 0.0
    dx, dy, dz = h.dx, h.dy, h.dz
    if led_cos_alpha(leds, k, dx, dy, dz) <= 0.0:
        return 0.0
    if not _path_is_clear(surfaces, cornea, target, Ray(px, py, pz, dx, dy, dz), rc):
        return 0.0
    d2 = (ax - px) ** 2 + (ay - py) ** 2 + pz * pz
    dw_da = abs(dz) / d2  # solid angle per unit eye-plane area at a
    return radiant_intensity(leds, k, dx, dy, dz) * h.trans * dw_da / abs(det)


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
