"""The camera as the fast estimator sees it: the lens traced backwards and the pupils to aim at.

Three things, all in world millimetres, computed once per compiled scene:

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
from dataclasses import dataclass

import numpy as np
from numba import njit

from eyelume.compile import CompiledScene, eye_paraxial, lens_paraxial
from eyelume.kernels import geometry as G
from eyelume.kernels import sequential as Q
from eyelume.scene.optics import ParaxialSystem

__all__ = [
    "CameraTables",
    "camera_tables",
    "into_scene",
    "aim_at_stop",
    "aim_chief",
    "AIM_PROBABILITY",
]

#: Share of scatter directions aimed at the pupil (the rest cosine-sampled, which keeps the
#: estimator unbiased where refraction bends an aimed ray away from the lens).
AIM_PROBABILITY = 0.8
_PUPIL_MARGIN = 1.15  # real pupils of off-axis points are larger and shifted: aim a bit wider

#: The surfaces lit and seen through the cornea: the iris and its root (compile.py).
_IRIS = ("iris", "iris root")

# aim table columns: disk centre xyz (its normal is world +z), radius, probability
A_X, A_Y, A_Z, A_R, A_P = range(5)
N_AIM = 5


@dataclass
class CameraTables:
    """See the module docstring. ``aim[s, side]`` with side 0 = A, 1 = B."""

    lf_rev: np.ndarray
    lf_open: np.ndarray  # lf_rev with open apertures (for aiming)
    k_stop: int  # the stop's row in lf_rev
    stop_radius: float
    rear_z: float
    exit_pupil_z: float
    exit_pupil_magnification: float
    entrance_pupil_z: float
    entrance_pupil_radius: float
    aim: np.ndarray  # (n_surfaces, 2, N_AIM)
    through_cornea: np.ndarray  # (n_surfaces,) 1 where NEE goes through the cornea (the iris)


def _mirrored_lens(lf: np.ndarray) -> np.ndarray:
    rev = lf[::-1].copy()
    rev[:, Q.L_Z] = -rev[:, Q.L_Z]
    rev[:, Q.L_CURV] = -rev[:, Q.L_CURV]
    rev[:, Q.L_N0], rev[:, Q.L_N1] = lf[::-1, Q.L_N1].copy(), lf[::-1, Q.L_N0].copy()
    return np.ascontiguousarray(rev)


@njit(cache=True, inline="always")
def into_scene(lf_rev, image_z, xs, ys, qx, qy, rear_z):
    """Trace the ray from sensor point (xs, ys) toward point (qx, qy) of the last vertex plane
    back out of the lens. Returns (passed, x, y, z, dx, dy, dz, cos²θ / d²) with the ray leaving
    the lens's first surface into the scene, θ its angle with the axis at the sensor and d the
    sensor-to-plane distance along it."""
    dx, dy, dz = qx - xs, qy - ys, rear_z - image_z
    d2 = dx * dx + dy * dy + dz * dz
    d = math.sqrt(d2)
    dx, dy, dz = dx / d, dy / d, dz / d
    status, x, y, z, ex, ey, ez, _, _ = Q.trace_lens(
        lf_rev, xs, ys, -image_z, dx, dy, -dz, None, 0, False
    )
    return status == Q.LENS_PASSED, x, y, -z, ex, ey, -ez, dz * dz / d2


@njit(cache=True)
def _stop_crossing(lf_open, k_stop, image_z, xs, ys, qx, qy, rear_z):
    """Where the ray from sensor point (xs, ys) toward (qx, qy, rear_z) meets the stop (surface
    ``k_stop`` of the reversed lens, apertures open); NaN if it fails before."""
    dx, dy, dz = qx - xs, qy - ys, rear_z - image_z
    inv = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
    status, x, y, _, _, _, _, _, _ = Q.trace_lens(
        lf_open[: k_stop + 1], xs, ys, -image_z, dx * inv, dy * inv, -dz * inv, None, 0, False
    )
    if status != Q.LENS_PASSED:
        return math.nan, math.nan
    return x, y


@njit(cache=True, inline="always")
def paraxial_crossing(image_z, rear_z, xp_z, xp_m, xs, ys, tx, ty):
    """First-order guess of the last-vertex-plane crossing of the ray from sensor point (xs, ys)
    through stop point (tx, ty): toward the stop point's image in the paraxial exit pupil (z
    ``xp_z``, magnification ``xp_m``)."""
    s = (image_z - rear_z) / (image_z - xp_z)
    return xs * (1.0 - s) + s * xp_m * tx, ys * (1.0 - s) + s * xp_m * ty


@njit(cache=True)
def stop_jacobian(lf_open, k_stop, image_z, rear_z, xs, ys, qx, qy):
    """Stop point (sx, sy) of the ray toward (qx, qy) and the Jacobian ∂(s)/∂(q) by forward
    differences (step 1e-4 mm). Returns (sx, sy, j11, j12, j21, j22); NaN if the ray fails."""
    h = 1e-4
    sx, sy = _stop_crossing(lf_open, k_stop, image_z, xs, ys, qx, qy, rear_z)
    s1x, s1y = _stop_crossing(lf_open, k_stop, image_z, xs, ys, qx + h, qy, rear_z)
    s2x, s2y = _stop_crossing(lf_open, k_stop, image_z, xs, ys, qx, qy + h, rear_z)
    return sx, sy, (s1x - sx) / h, (s2x - sx) / h, (s1y - sy) / h, (s2y - sy) / h


@njit(cache=True)
def aim_at_stop(lf_open, k_stop, image_z, rear_z, xs, ys, tx, ty, qx, qy, a11, a12, a21, a22):
    """Crossing (qx, qy) of the last vertex plane by the ray from sensor point (xs, ys) through
    stop point (tx, ty), from the guess (qx, qy), and the Jacobian ∂(stop point)/∂(q) there.

    Chord iterations with the approximate Jacobian (a11 … a22) until the stop point is met
    within 1e-4 mm (a shift of the sampled stop point that changes its density by ~1e-5), then
    the Jacobian by forward differences at the solution.
    Returns (found, qx, qy, |det ∂(stop point)/∂(q)|).
    """
    det = a11 * a22 - a12 * a21
    if det == 0.0 or math.isnan(det):
        return False, qx, qy, 0.0
    for _ in range(20):
        sx, sy = _stop_crossing(lf_open, k_stop, image_z, xs, ys, qx, qy, rear_z)
        if math.isnan(sx):
            return False, qx, qy, 0.0
        ex, ey = sx - tx, sy - ty
        if ex * ex + ey * ey < 1e-8:
            _, _, j11, j12, j21, j22 = stop_jacobian(
                lf_open, k_stop, image_z, rear_z, xs, ys, qx, qy
            )
            d = abs(j11 * j22 - j12 * j21)
            return not math.isnan(d) and d > 0.0, qx, qy, d
        qx -= (a22 * ex - a12 * ey) / det
        qy -= (-a21 * ex + a11 * ey) / det
    return False, qx, qy, 0.0


@njit(cache=True)
def aim_chief(lf_open, k_stop, image_z, rear_z, xp_z, xp_m, xs, ys):
    """The chief ray of sensor point (xs, ys) — through the stop's centre — by Newton's method
    from the paraxial guess. Returns (found, qx, qy, j11, j12, j21, j22), J = ∂(stop)/∂(q)."""
    qx, qy = paraxial_crossing(image_z, rear_z, xp_z, xp_m, xs, ys, 0.0, 0.0)
    for _ in range(20):
        sx, sy, j11, j12, j21, j22 = stop_jacobian(lf_open, k_stop, image_z, rear_z, xs, ys, qx, qy)
        det = j11 * j22 - j12 * j21
        if math.isnan(det) or det == 0.0:
            break
        if sx * sx + sy * sy < 1e-12:
            return True, qx, qy, j11, j12, j21, j22
        qx -= (j22 * sx - j12 * sy) / det
        qy -= (-j21 * sx + j11 * sy) / det
    return False, qx, qy, 0.0, 0.0, 0.0, 0.0


def _exit_pupil(cs: CompiledScene) -> tuple[float, float]:
    """World z and signed magnification of the paraxial exit pupil (the stop imaged by the
    surfaces after it)."""
    par = lens_paraxial(cs.scene, cs.lens_indices)
    st = cs.stop_index
    rear = ParaxialSystem(par.curvatures[st + 1 :], par.gaps[st + 1 :], par.indices[st + 1 :])
    xp_z = float(cs.lf[-1, Q.L_Z] + rear.image_distance(par.gaps[st]))
    return xp_z, float(rear.magnification(par.gaps[st]))


def _cornea_image(cs: CompiledScene, pupil_z: float, pupil_r: float) -> tuple[float, float]:
    """World z and radius of the entrance pupil's paraxial image through the cornea."""
    eye = eye_paraxial(cs.scene)
    cornea = ParaxialSystem(eye.curvatures[:2], eye.gaps[:1], eye.indices[:3])
    image = cornea.image_distance(pupil_z)  # beyond the posterior cornea, eye frame
    mag = cornea.magnification(pupil_z)
    z_eye = cs.scene.eye.surfaces[0].thickness_mm + image
    return -z_eye, abs(mag) * pupil_r


def camera_tables(cs: CompiledScene) -> CameraTables:
    """Build the camera tables of a compiled scene."""
    sc = cs.scene
    par = lens_paraxial(sc, cs.lens_indices)
    ep_z = sc.lens.object_distance_mm + par.entrance_pupil_position(cs.stop_index)
    ep_r = par.efl / sc.lens.f_number / 2.0 * _PUPIL_MARGIN
    lf_rev = _mirrored_lens(cs.lf)
    lf_open = lf_rev.copy()
    lf_open[:, Q.L_SD] = np.inf
    xp_z, xp_m = _exit_pupil(cs)
    k_stop = cs.lf.shape[0] - 1 - cs.stop_index
    aim = np.zeros((cs.sf.shape[0], 2, N_AIM))
    iris_z, iris_r = _cornea_image(cs, ep_z, ep_r)
    through = np.array([name in _IRIS for name in cs.surface_names], dtype=np.int64)
    for s, name in enumerate(cs.surface_names):
        if cs.si[s, G.ACTION] != G.ACT_OPAQUE:
            continue
        for side, rho_col in ((0, G.RHO_A), (1, G.RHO_B)):
            if cs.sf[s, rho_col] <= 0.0:
                continue
            if name in _IRIS:
                aim[s, side] = (0.0, 0.0, iris_z, iris_r, AIM_PROBABILITY)
            elif name == "retina" or (name == "sclera" and side == 0):
                continue  # inside the eye behind the crystalline lens: cosine sampling
            else:
                aim[s, side] = (0.0, 0.0, ep_z, ep_r, AIM_PROBABILITY)
    return CameraTables(
        lf_rev,
        lf_open,
        k_stop,
        float(cs.lf[cs.stop_index, Q.L_SD]),
        float(cs.lf[-1, Q.L_Z]),
        xp_z,
        xp_m,
        ep_z,
        ep_r,
        aim,
        through,
    )
