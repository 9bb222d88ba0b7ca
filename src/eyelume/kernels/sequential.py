"""Sequential trace through a rotationally symmetric lens whose axis is the world z axis.

Lens table ``lf[j, :]`` (filled by :mod:`eyelume.compile`), one row per surface in order:
vertex z (world mm), curvature c (1/mm), conic constant k, semi-diameter (mm), index before and
after, and for an *ideal* (thin, perfect) lens its power φ = 1/f (1/mm; 0 for a real surface),
radial distortion k1, k2 and which way the row is traced (+1 as light goes from the scene to the
sensor, −1 for the mirrored, reversed table the camera-side estimator traces). Every surface
transmits 100 % (ideal coatings); a ray outside a semi-diameter is stopped by the mount
(vignetting), one beyond the critical angle is lost to total internal reflection.

An ideal lens is a plane (c = 0) that turns a ray crossing it at height h⃗ = (x, y) with slope
s⃗ = (dx, dy)/dz into slope s⃗′ = D(s⃗) − φ h⃗ (scene → sensor), D(s⃗) = s⃗ (1 + k1 |s⃗|² + k2 |s⃗|⁴):
rays of equal slope meet at f D(s⃗) in the back focal plane, so every point of any object plane
images to one point (Zemax's paraxial surface, pbrt's thin lens). Traced the other way (mirrored
and reversed: the incoming slope is −s⃗′, the outgoing −s⃗) the same lens is
s⃗ = D⁻¹(s⃗_in − φ h⃗), D⁻¹ by Newton's method on the radius.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from eyelume.kernels.geometry import (
    conic_coefficients,
    conic_normal,
    on_vertex_branch,
    quadratic_roots,
)
from eyelume.kernels.interact import refract
from eyelume.kernels.jit import per_ray

L_Z, L_CURV, L_CONIC, L_SD, L_N0, L_N1, L_POWER, L_K1, L_K2, L_WAY = range(10)
N_LENS_COL = 10

LENS_PASSED, LENS_VIGNETTED, LENS_TIR = 0, 1, 2


@njit(cache=True, inline="always")
def conic_hit_sequential(c, k, px, py, pz, dx, dy, dz):
    """Parameter t of the ray's hit with a conicoid's vertex sheet (local frame), or NaN."""
    a, b, cc = conic_coefficients(c, k, px, py, pz, dx, dy, dz)
    t1, t2, n = quadratic_roots(a, b, cc)
    if n >= 1 and t1 > -1e-9 and on_vertex_branch(c, k, pz + t1 * dz):
        return t1
    if n == 2 and t2 > -1e-9 and on_vertex_branch(c, k, pz + t2 * dz):
        return t2
    return math.nan


@njit(cache=True, inline="always")
def distortion_gain(k1, k2, rho2):
    """D(s⃗)/s⃗ = 1 + k1 ρ² + k2 ρ⁴ at ρ² = |s⃗|²."""
    return 1.0 + rho2 * (k1 + k2 * rho2)


@njit(cache=True)
def undistorted_radius(k1, k2, rho_d):
    """ρ with ρ (1 + k1 ρ² + k2 ρ⁴) = ρ_d, by Newton's method from ρ_d (NaN when it does not
    converge: a distorted radius beyond the lens's monotonic range)."""
    rho = rho_d
    for _ in range(30):
        r2 = rho * rho
        f = rho * (1.0 + r2 * (k1 + k2 * r2)) - rho_d
        df = 1.0 + r2 * (3.0 * k1 + 5.0 * k2 * r2)
        if df <= 0.0:
            return math.nan
        step = f / df
        rho -= step
        if abs(step) < 1e-15 * (1.0 + abs(rho)):
            return rho
    return math.nan


@njit(cache=True, inline="always")
def ideal_lens(row, x, y, dx, dy, dz):
    """The unit direction after the ideal lens ``row`` (a row of ``lf``) of a ray crossing it
    at (x, y) with unit direction (dx, dy, dz), dz > 0 (module docstring). Returns (ok, dx, dy,
    dz); not ok when the distortion cannot be inverted there."""
    sx, sy = dx / dz, dy / dz
    phi, k1, k2 = row[L_POWER], row[L_K1], row[L_K2]
    if k1 != 0.0 or k2 != 0.0:
        if row[L_WAY] > 0.0:
            g = distortion_gain(k1, k2, sx * sx + sy * sy)
            sx, sy = g * sx - phi * x, g * sy - phi * y
        else:
            sx, sy = sx - phi * x, sy - phi * y
            rho_d = math.sqrt(sx * sx + sy * sy)
            if rho_d > 0.0:
                rho = undistorted_radius(k1, k2, rho_d)
                if math.isnan(rho):
                    return False, dx, dy, dz
                sx, sy = sx * rho / rho_d, sy * rho / rho_d
    else:
        sx, sy = sx - phi * x, sy - phi * y
    inv = 1.0 / math.sqrt(1.0 + sx * sx + sy * sy)
    return True, sx * inv, sy * inv, inv


@per_ray
def trace_lens(lf, x, y, z, dx, dy, dz, path, n_path, record):
    """Trace a world ray (unit direction, dz > 0) through all lens surfaces.

    Returns (status, x, y, z, dx, dy, dz, surfaces_met, n_path): the ray after the last surface
    when status is LENS_PASSED. With ``record`` the hit points are appended to ``path`` (which
    may be None when nothing is recorded: no buffer to allocate in a hot loop).
    """
    met = 0
    for j in range(lf.shape[0]):
        zv = lf[j, L_Z]
        c = lf[j, L_CURV]
        k = lf[j, L_CONIC]
        t = conic_hit_sequential(c, k, x, y, z - zv, dx, dy, dz)
        if math.isnan(t):
            return LENS_VIGNETTED, x, y, z, dx, dy, dz, met, n_path
        x += t * dx
        y += t * dy
        z += t * dz
        met += 1
        if path is not None and record and n_path < path.shape[0]:
            path[n_path, 0] = x
            path[n_path, 1] = y
            path[n_path, 2] = z
            n_path += 1
        if x * x + y * y > lf[j, L_SD] * lf[j, L_SD]:
            return LENS_VIGNETTED, x, y, z, dx, dy, dz, met, n_path
        if lf[j, L_POWER] != 0.0:
            ok, dx, dy, dz = ideal_lens(lf[j], x, y, dx, dy, dz)
            if not ok:
                return LENS_VIGNETTED, x, y, z, dx, dy, dz, met, n_path
            continue
        nx, ny, nz = conic_normal(c, k, x, y, z - zv)
        ok, dx, dy, dz = refract(dx, dy, dz, nx, ny, nz, lf[j, L_N0] / lf[j, L_N1])
        if not ok:
            return LENS_TIR, x, y, z, dx, dy, dz, met, n_path
    return LENS_PASSED, x, y, z, dx, dy, dz, met, n_path


@per_ray
def trace_lens_part(lf, j0, j1, x, y, z, dx, dy, dz, clip):
    """Trace a world ray (unit direction, dz > 0) through lens surfaces ``j0`` … ``j1`` − 1,
    with :func:`trace_lens`'s arithmetic, so that tracing 0 … k − 1 and then k … n − 1 gives
    the whole trace's numbers.

    With ``clip`` a hit outside its semi-diameter stops the ray (LENS_VIGNETTED), as in
    :func:`trace_lens`; without, the ray goes on (apertures open) and ``inside`` says whether
    every hit lay within its semi-diameter. Returns (status, x, y, z, dx, dy, dz, inside):
    status LENS_VIGNETTED also when a surface is missed, LENS_TIR on total internal
    reflection.
    """
    inside = True
    for j in range(j0, j1):
        zv = lf[j, L_Z]
        c = lf[j, L_CURV]
        k = lf[j, L_CONIC]
        t = conic_hit_sequential(c, k, x, y, z - zv, dx, dy, dz)
        if math.isnan(t):
            return LENS_VIGNETTED, x, y, z, dx, dy, dz, False
        x += t * dx
        y += t * dy
        z += t * dz
        if x * x + y * y > lf[j, L_SD] * lf[j, L_SD]:
            inside = False
            if clip:
                return LENS_VIGNETTED, x, y, z, dx, dy, dz, False
        if lf[j, L_POWER] != 0.0:
            ok, dx, dy, dz = ideal_lens(lf[j], x, y, dx, dy, dz)
            if not ok:
                return LENS_VIGNETTED, x, y, z, dx, dy, dz, False
            continue
        nx, ny, nz = conic_normal(c, k, x, y, z - zv)
        ok, dx, dy, dz = refract(dx, dy, dz, nx, ny, nz, lf[j, L_N0] / lf[j, L_N1])
        if not ok:
            return LENS_TIR, x, y, z, dx, dy, dz, False
    return LENS_PASSED, x, y, z, dx, dy, dz, inside


@njit(cache=True)
def _stop_point(lf, stop, x0, y0, ax, ay, path):
    """Where the ray from (x0, y0, 0) toward (ax, ay, z₁) (z₁ the first vertex) meets the stop;
    NaN if it fails before. ``lf`` should have open apertures."""
    dx, dy, dz = ax - x0, ay - y0, lf[0, L_Z]
    inv = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
    status, _, _, _, _, _, _, met, _ = trace_lens(
        lf[: stop + 1], x0, y0, 0.0, dx * inv, dy * inv, dz * inv, path, 0, True
    )
    if met <= stop:
        return math.nan, math.nan
    return path[stop, 0], path[stop, 1]


@njit(cache=True)
def rim_ray_heights(lf, stop, stop_radius, xs, ys, n_azimuth, pupil_mag, pupil_z):
    """Largest ray height at each surface over the rim rays of a set of field points.

    For each object point (x, y, 0) and each of ``n_azimuth`` points on the stop's rim, the ray
    through that rim point is found by real-ray aiming (Newton's method on the aim point in the
    first vertex plane, finite-difference Jacobian), started from the paraxial guess: the ray
    toward the rim point's image in the entrance pupil (magnification ``pupil_mag``, at world
    z = ``pupil_z``). ``lf`` must have open apertures. Returns the heights
    (mm) per surface and the number of rim rays found.
    """
    n = lf.shape[0]
    best = np.zeros(n)
    path = np.zeros((n, 3))
    found = 0
    h = 1e-5
    for x0 in xs:
        for y0 in ys:
            for k in range(n_azimuth):
                phi = 2.0 * math.pi * k / n_azimuth
                tx, ty = stop_radius * math.cos(phi), stop_radius * math.sin(phi)
                f = lf[0, L_Z] / pupil_z
                ax = x0 + (pupil_mag * tx - x0) * f
                ay = y0 + (pupil_mag * ty - y0) * f
                ok = False
                for _ in range(30):
                    sx, sy = _stop_point(lf, stop, x0, y0, ax, ay, path)
                    if math.isnan(sx):
                        break
                    ex, ey = sx - tx, sy - ty
                    if ex * ex + ey * ey < 1e-20:
                        ok = True
                        break
                    s1x, s1y = _stop_point(lf, stop, x0, y0, ax + h, ay, path)
                    s2x, s2y = _stop_point(lf, stop, x0, y0, ax, ay + h, path)
                    j11, j21 = (s1x - sx) / h, (s1y - sy) / h
                    j12, j22 = (s2x - sx) / h, (s2y - sy) / h
                    det = j11 * j22 - j12 * j21
                    if math.isnan(det) or det == 0.0:
                        break
                    ax -= (j22 * ex - j12 * ey) / det
                    ay -= (-j21 * ex + j11 * ey) / det
                if not ok:
                    continue
                dx, dy, dz = ax - x0, ay - y0, lf[0, L_Z]
                inv = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
                status, _, _, _, _, _, _, _, _ = trace_lens(
                    lf, x0, y0, 0.0, dx * inv, dy * inv, dz * inv, path, 0, True
                )
                if status != LENS_PASSED:
                    continue
                found += 1
                for j in range(n):
                    best[j] = max(best[j], math.sqrt(path[j, 0] ** 2 + path[j, 1] ** 2))
    return best, found
