"""The camera as the fast estimator sees it: the lens traced backwards and the pupils to aim at.

The kernels here read the compiled scene's :class:`~eyelume.kernels.tables.CameraTables`
(``cs.camera``, built once by :func:`eyelume.compile._camera_tables`), all in world millimetres:

* ``lf_rev``: the lens table mirrored through z = 0 and reversed, so the forward sequential
  kernel traces a ray from the sensor back out into the scene (mirror z → −z on the way in and
  out);
* *stop aiming*: the real ray from a sensor point through a given point of the aperture stop,
  found by Newton's method on the ray's crossing of the last vertex plane (started from the
  paraxial exit pupil), with the Jacobian |∂(stop point)/∂(crossing)| that turns a uniform
  density over the stop into a density over directions at the sensor. Camera paths sample the
  stop uniformly, so no sample is wasted on a ray the stop would block;
* the surfaces (the iris and its root) whose light from the LEDs comes through the cornea,
  reached from the camera side by a specular connection (:mod:`.cornea_nee`);
* the *aim table*: for each Lambertian face of the scene, a disk whose line through a scatter
  point leaves toward the camera — the entrance pupil for faces in air, its paraxial image
  through the cornea for the iris — and the probability of aiming at it (0: cosine sampling
  only, for faces from which the camera is not reached in a straight or paraxially predictable
  line, e.g. the fundus).
"""

from __future__ import annotations

import math
from typing import NamedTuple

from numba import njit

from eyelume.kernels import sequential as Q
from eyelume.kernels.jit import per_ray

__all__ = [
    "into_scene",
    "aim_at_stop",
    "aim_chief",
    "aim_into_scene",
    "Mat2",
    "SceneRay",
    "StopAim",
    "ChiefRay",
]


class Mat2(NamedTuple):
    """A 2 × 2 matrix [[a11, a12], [a21, a22]] (a Jacobian ∂(stop point)/∂(q))."""

    a11: float
    a12: float
    a21: float
    a22: float


class SceneRay(NamedTuple):
    """A ray traced from the sensor out of the lens: ``passed`` the lens, its origin on the
    lens's first surface and unit direction into the scene (world mm), and ``g`` = cos²θ / d²
    (θ its angle with the axis at the sensor, d the sensor-to-last-vertex-plane distance)."""

    passed: bool
    x: float
    y: float
    z: float
    dx: float
    dy: float
    dz: float
    g: float


class StopAim(NamedTuple):
    """The ray from a sensor point through a stop point: ``found``, its crossing (qx, qy) of the
    last vertex plane and |det ∂(stop point)/∂(q)| there."""

    found: bool
    qx: float
    qy: float
    det: float


class ChiefRay(NamedTuple):
    """The chief ray of a sensor point (through the stop's centre): ``found``, its crossing
    (qx, qy) of the last vertex plane and the Jacobian J = ∂(stop point)/∂(q) there."""

    found: bool
    qx: float
    qy: float
    jac: Mat2


@njit(cache=True, inline="always")
def is_ideal(cam):
    """True when the camera is an ideal (thin) lens: one row, the stop, with power."""
    return cam.lf_rev.shape[0] == 1 and cam.lf_rev[0, Q.L_POWER] != 0.0


@njit(cache=True, inline="always")
def ideal_radiance_gain(row, dx, dy, dz, ex, ey, ez):
    """L_sensor / L_scene through the ideal lens ``row`` (:mod:`eyelume.kernels.sequential`)
    for the ray with sensor-side direction (dx, dy, dz) and scene-side direction (ex, ey, ez).

    The lens maps slopes s⃗ → s⃗′ = D(s⃗) − φ h⃗ at a fixed crossing h⃗, so it keeps the flux
    L cos θ dΩ dA = L dA d²s / (1 + |s⃗|²)² of a bundle while its slope area changes by
    |det ∂D/∂s⃗|: L′ = L (1 + |s⃗′|²)² / ((1 + |s⃗|²)² |det ∂D/∂s⃗|) = L cos⁴θ / (cos⁴θ′ |det|),
    with det = g (g + 2ρ² (k1 + 2 k2 ρ²)), g = 1 + k1 ρ² + k2 ρ⁴, ρ = |s⃗| (θ scene side, θ′
    sensor side). A real prescription needs no such factor (refraction keeps L / n²)."""
    s2 = (ex * ex + ey * ey) / (ez * ez)
    u2 = (dx * dx + dy * dy) / (dz * dz)
    k1, k2 = row[Q.L_K1], row[Q.L_K2]
    g = 1.0 + s2 * (k1 + k2 * s2)
    det = g * (g + 2.0 * s2 * (k1 + 2.0 * k2 * s2))
    r = (1.0 + u2) / (1.0 + s2)
    return r * r / abs(det)


@njit(cache=True, inline="always")
def into_scene(cam, xs, ys, qx, qy):
    """Trace the ray from sensor point (xs, ys) toward point (qx, qy) of the last vertex plane
    back out of the lens (``cam.lf_rev``: mirror z → −z on the way in and out). Returns a
    :class:`SceneRay`; for an ideal lens ``g`` includes :func:`ideal_radiance_gain`."""
    dx, dy, dz = qx - xs, qy - ys, cam.rear_z - cam.image_z
    d2 = dx * dx + dy * dy + dz * dz
    d = math.sqrt(d2)
    dx, dy, dz = dx / d, dy / d, dz / d
    status, x, y, z, ex, ey, ez, _, _ = Q.trace_lens(
        cam.lf_rev, xs, ys, -cam.image_z, dx, dy, -dz, None, 0, False
    )
    g = dz * dz / d2
    passed = status == Q.LENS_PASSED
    if passed and is_ideal(cam):
        g *= ideal_radiance_gain(cam.lf_rev[0], dx, dy, dz, ex, ey, ez)
    return SceneRay(passed, x, y, -z, ex, ey, -ez, g)


@per_ray
def _stop_crossing(cam, xs, ys, qx, qy):
    """Where the ray from sensor point (xs, ys) toward (qx, qy, rear_z) meets the stop (surface
    ``k_stop`` of the reversed lens, apertures open); NaN if it fails before."""
    dx, dy, dz = qx - xs, qy - ys, cam.rear_z - cam.image_z
    inv = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
    status, x, y, _, _, _, _, _, _ = Q.trace_lens(
        cam.lf_open[: cam.k_stop + 1],
        xs,
        ys,
        -cam.image_z,
        dx * inv,
        dy * inv,
        -dz * inv,
        None,
        0,
        False,
    )
    if status != Q.LENS_PASSED:
        return math.nan, math.nan
    return x, y


@njit(cache=True, inline="always")
def paraxial_crossing(cam, xs, ys, tx, ty):
    """First-order guess of the last-vertex-plane crossing of the ray from sensor point (xs, ys)
    through stop point (tx, ty): toward the stop point's image in the paraxial exit pupil."""
    s = (cam.image_z - cam.rear_z) / (cam.image_z - cam.exit_pupil_z)
    m = cam.exit_pupil_magnification
    return xs * (1.0 - s) + s * m * tx, ys * (1.0 - s) + s * m * ty


@per_ray
def stop_jacobian(cam, xs, ys, qx, qy):
    """Stop point (sx, sy) of the ray toward (qx, qy) and the Jacobian ∂(s)/∂(q) by forward
    differences (step 1e-4 mm). Returns (sx, sy, Mat2); NaN if the ray fails."""
    sx, sy = _stop_crossing(cam, xs, ys, qx, qy)
    return sx, sy, _jacobian_at(cam, xs, ys, qx, qy, sx, sy)


@per_ray
def _jacobian_at(cam, xs, ys, qx, qy, sx, sy):
    """:func:`stop_jacobian`'s Mat2 when the stop point (sx, sy) of the ray toward (qx, qy) is
    already known (two traces instead of three)."""
    h = 1e-4
    s1x, s1y = _stop_crossing(cam, xs, ys, qx + h, qy)
    s2x, s2y = _stop_crossing(cam, xs, ys, qx, qy + h)
    return Mat2((s1x - sx) / h, (s2x - sx) / h, (s1y - sy) / h, (s2y - sy) / h)


@per_ray
def _stop_ray(cam, xs, ys, qx, qy):
    """:func:`_stop_crossing`'s trace (the same numbers) through ``lf_rev``'s surfaces up to the
    stop with apertures open, returning its whole state there: (status, x, y, z, dx, dy, dz,
    inside), ``inside`` whether every hit lay within its semi-diameter."""
    dx, dy, dz = qx - xs, qy - ys, cam.rear_z - cam.image_z
    inv = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
    return Q.trace_lens_part(
        cam.lf_rev, 0, cam.k_stop + 1, xs, ys, -cam.image_z, dx * inv, dy * inv, -dz * inv, False
    )


@per_ray
def _aim(cam, xs, ys, tx, ty, qx, qy, a):
    """:func:`aim_at_stop` for a prescription lens; returns (StopAim, x, y, z, dx, dy, dz,
    inside): the ray's state at the stop (the reversed lens's frame) and whether it passed
    every aperture before it."""
    fail = StopAim(False, qx, qy, 0.0)
    a11, a12, a21, a22 = a.a11, a.a12, a.a21, a.a22
    det = a11 * a22 - a12 * a21
    if det == 0.0 or math.isnan(det):
        return fail, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, False
    psx = psy = dqx = dqy = 0.0
    for it in range(20):
        status, sx, sy, sz, dx, dy, dz, inside = _stop_ray(cam, xs, ys, qx, qy)
        if status != Q.LENS_PASSED:
            return StopAim(False, qx, qy, 0.0), sx, sy, sz, dx, dy, dz, False
        ex, ey = sx - tx, sy - ty
        if ex * ex + ey * ey < 1e-8:  # (sx, sy) is this q's stop point: not traced again
            j = _jacobian_at(cam, xs, ys, qx, qy, sx, sy)
            d = abs(j.a11 * j.a22 - j.a12 * j.a21)
            aim = StopAim(not math.isnan(d) and d > 0.0, qx, qy, d)
            return aim, sx, sy, sz, dx, dy, dz, inside
        if it > 0:
            # Broyden's update of the Jacobian by the last step (dq → ds): the chord steps
            # then converge superlinearly (3.0 traces a sample on paper2005, 3.7 without)
            rx = sx - psx - (a11 * dqx + a12 * dqy)
            ry = sy - psy - (a21 * dqx + a22 * dqy)
            nn = dqx * dqx + dqy * dqy
            a11 += rx * dqx / nn
            a12 += rx * dqy / nn
            a21 += ry * dqx / nn
            a22 += ry * dqy / nn
            det = a11 * a22 - a12 * a21
            if det == 0.0 or math.isnan(det):
                break
        dqx = -(a22 * ex - a12 * ey) / det
        dqy = -(-a21 * ex + a11 * ey) / det
        qx += dqx
        qy += dqy
        psx, psy = sx, sy
    return StopAim(False, qx, qy, 0.0), 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, False


@per_ray
def aim_at_stop(cam, xs, ys, tx, ty, qx, qy, a):
    """Crossing (qx, qy) of the last vertex plane by the ray from sensor point (xs, ys) through
    stop point (tx, ty), from the guess (qx, qy), and the Jacobian ∂(stop point)/∂(q) there.

    Quasi-Newton iterations — the first step with the approximate Jacobian ``a`` (a
    :class:`Mat2`), each next one with it updated by Broyden's rule from the step before — until
    the stop point is met within 1e-4 mm (a shift of the sampled stop point that changes its
    density by ~1e-5), then the Jacobian by forward differences at the solution. Returns a
    :class:`StopAim`.
    """
    if is_ideal(cam):  # the stop is the lens, in the last vertex plane: q is the stop point
        return StopAim(True, tx, ty, 1.0)
    return _aim(cam, xs, ys, tx, ty, qx, qy, a)[0]


@per_ray
def aim_into_scene(cam, xs, ys, tx, ty, qx, qy, a):
    """:func:`aim_at_stop` and then :func:`into_scene` of the ray it found, in one: the ray's
    trace up to the stop is the aim's last (the same surfaces and numbers, its apertures
    checked on the way), so only the surfaces after the stop are traced again. Returns
    (:class:`StopAim`, :class:`SceneRay`); the ray has ``passed`` False when the aim failed."""
    if is_ideal(cam):
        return StopAim(True, tx, ty, 1.0), into_scene(cam, xs, ys, tx, ty)
    aim, x, y, z, dx, dy, dz, inside = _aim(cam, xs, ys, tx, ty, qx, qy, a)
    if not (aim.found and inside):
        return aim, SceneRay(False, x, y, -z, dx, dy, -dz, 0.0)
    n = cam.lf_rev.shape[0]
    status, x, y, z, ex, ey, ez, _ = Q.trace_lens_part(
        cam.lf_rev, cam.k_stop + 1, n, x, y, z, dx, dy, dz, True
    )
    ux, uy, uz = aim.qx - xs, aim.qy - ys, cam.rear_z - cam.image_z
    d2 = ux * ux + uy * uy + uz * uz
    cz = uz / math.sqrt(d2)
    return aim, SceneRay(status == Q.LENS_PASSED, x, y, -z, ex, ey, -ez, cz * cz / d2)


@per_ray
def aim_chief(cam, xs, ys):
    """The chief ray of sensor point (xs, ys) — through the stop's centre — by Newton's method
    from the paraxial guess. Returns a :class:`ChiefRay`."""
    if is_ideal(cam):
        return ChiefRay(True, 0.0, 0.0, Mat2(1.0, 0.0, 0.0, 1.0))
    qx, qy = paraxial_crossing(cam, xs, ys, 0.0, 0.0)
    for _ in range(20):
        sx, sy, j = stop_jacobian(cam, xs, ys, qx, qy)
        det = j.a11 * j.a22 - j.a12 * j.a21
        if math.isnan(det) or det == 0.0:
            break
        if sx * sx + sy * sy < 1e-12:
            return ChiefRay(True, qx, qy, j)
        qx -= (j.a22 * sx - j.a12 * sy) / det
        qy -= (-j.a21 * sx + j.a11 * sy) / det
    return ChiefRay(False, qx, qy, Mat2(0.0, 0.0, 0.0, 0.0))
