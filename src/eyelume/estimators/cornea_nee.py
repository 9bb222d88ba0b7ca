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

from numba import njit

from eyelume.kernels import geometry as G
from eyelume.kernels.interact import fresnel_reflectance, refract
from eyelume.kernels.sampling import relative_intensity_at

__all__ = ["irradiance_through_cornea"]

_H = 1e-4  # mm: forward-difference step on the eye plane
_TOL2 = 1e-10  # mm²: converged when h(a) is within 1e-5 mm of x


@njit(cache=True, inline="always")
def _transmit(sf, si, s, x, y, z, dx, dy, dz):
    """Refract at surface s (the ray arrives from side A). Returns (ok, dx, dy, dz, T)."""
    nx, ny, nz = G.surface_normal(sf, si, s, x, y, z)
    cos_d = dx * nx + dy * ny + dz * nz
    if cos_d <= 0.0:
        return False, dx, dy, dz, 0.0
    n1, n2 = sf[s, G.N_A], sf[s, G.N_B]
    ok, tx, ty, tz = refract(dx, dy, dz, nx, ny, nz, n1 / n2)
    r = fresnel_reflectance(cos_d, n1, n2) if si[s, G.FRESNEL] else sf[s, G.REFL]
    return ok, tx, ty, tz, 1.0 - r - sf[s, G.ABSORB]


@njit(cache=True)
def _through(sf, si, cornea, px, py, pz, ax, ay, x, y, z, nx, ny, nz, e1, e2):
    """The ray from (px, py, pz) toward (ax, ay, 0) through both cornea surfaces, met with the
    plane through (x, y, z) of normal n. Returns (ok, u, v, T, dx, dy, dz) with (u, v) the hit
    in the plane's basis (e1, e2) from (x, y, z) and (dx, dy, dz) the initial direction."""
    dx, dy, dz = ax - px, ay - py, -pz
    inv = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
    dx, dy, dz = dx * inv, dy * inv, dz * inv
    ox, oy, oz = px, py, pz
    rx, ry, rz = dx, dy, dz
    trans = 1.0
    for s in (cornea, cornea + 1):
        t = G.intersect_surface(sf, si, s, ox, oy, oz, rx, ry, rz, math.inf)
        if t < 0.0:
            return False, 0.0, 0.0, 0.0, dx, dy, dz
        ox, oy, oz = ox + t * rx, oy + t * ry, oz + t * rz
        ok, rx, ry, rz, tr = _transmit(sf, si, s, ox, oy, oz, rx, ry, rz)
        if not ok:
            return False, 0.0, 0.0, 0.0, dx, dy, dz
        trans *= tr
    den = rx * nx + ry * ny + rz * nz
    if den >= 0.0:  # must arrive on the lit side, against n
        return False, 0.0, 0.0, 0.0, dx, dy, dz
    t = ((x - ox) * nx + (y - oy) * ny + (z - oz) * nz) / den
    hx, hy, hz = ox + t * rx - x, oy + t * ry - y, oz + t * rz - z
    u = hx * e1[0] + hy * e1[1] + hz * e1[2]
    v = hx * e2[0] + hy * e2[1] + hz * e2[2]
    return t > 0.0, u, v, trans, dx, dy, dz


@njit(cache=True)
def _path_is_clear(sf, si, cornea, target, px, py, pz, dx, dy, dz, x, y, z):
    """Whether the refracted path from the LED meets, in turn, the anterior cornea, the
    posterior cornea and surface ``target`` at (x, y, z) with nothing else in between."""
    ox, oy, oz = px, py, pz
    for s in (cornea, cornea + 1):
        hit, t = G.nearest_hit(sf, si, ox, oy, oz, dx, dy, dz)
        if hit != s:
            return False
        ox, oy, oz = ox + t * dx, oy + t * dy, oz + t * dz
        ok, dx, dy, dz, _ = _transmit(sf, si, s, ox, oy, oz, dx, dy, dz)
        if not ok:
            return False
    hit, t = G.nearest_hit(sf, si, ox, oy, oz, dx, dy, dz)
    if hit != target:
        return False
    ex, ey, ez = ox + t * dx - x, oy + t * dy - y, oz + t * dz - z
    return ex * ex + ey * ey + ez * ez < 1e-6


@njit(cache=True)
def irradiance_through_cornea(
    sf, si, cornea, target, leds, i0, ag, ig, x, y, z, nx, ny, nz, e1, e2
):
    """Irradiance (W/mm²) at (x, y, z) on surface ``target`` (unit normal n toward the light,
    tangent basis e1, e2) from every LED, along paths refracted by the anterior (surface
    ``cornea``) and posterior (``cornea + 1``) cornea. See the module docstring."""
    e_total = 0.0
    for k in range(leds.shape[0]):
        px, py, pz = leds[k, 0], leds[k, 1], leds[k, 2]
        # straight-line guess: where the segment LED → x crosses the eye plane
        f = pz / (pz - z)
        ax, ay = px + (x - px) * f, py + (y - py) * f
        found = False
        for _ in range(30):
            ok, u, v, trans, dx, dy, dz = _through(
                sf, si, cornea, px, py, pz, ax, ay, x, y, z, nx, ny, nz, e1, e2
            )
            if not ok:
                break
            ok1, u1, v1, _, _, _, _ = _through(
                sf, si, cornea, px, py, pz, ax + _H, ay, x, y, z, nx, ny, nz, e1, e2
            )
            ok2, u2, v2, _, _, _, _ = _through(
                sf, si, cornea, px, py, pz, ax, ay + _H, x, y, z, nx, ny, nz, e1, e2
            )
            if not (ok1 and ok2):
                break
            j11, j21 = (u1 - u) / _H, (v1 - v) / _H
            j12, j22 = (u2 - u) / _H, (v2 - v) / _H
            det = j11 * j22 - j12 * j21
            if det == 0.0 or math.isnan(det):
                break
            if u * u + v * v < _TOL2:
                found = True
                break
            ax -= (j22 * u - j12 * v) / det
            ay -= (-j21 * u + j11 * v) / det
        if not found:
            continue
        cos_a = dx * leds[k, 3] + dy * leds[k, 4] + dz * leds[k, 5]
        if cos_a <= 0.0:
            continue
        if not _path_is_clear(sf, si, cornea, target, px, py, pz, dx, dy, dz, x, y, z):
            continue
        d2 = (ax - px) ** 2 + (ay - py) ** 2 + pz * pz
        dw_da = abs(dz) / d2  # solid angle per unit eye-plane area at a
        e_total += i0 * relative_intensity_at(cos_a, ag, ig) * trans * dw_da / abs(det)
    return e_total
