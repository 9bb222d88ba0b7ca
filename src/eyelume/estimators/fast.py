"""The fast estimator: camera-side paths with next-event estimation, plus aimed light paths.

Every light path runs LED → … → camera. We split path space by how the path leaves its LED:

1. **First hit Lambertian** (skin, lids, sclera — most of the image), and **refracted by the
   anterior and posterior cornea onto the iris**: estimated from the camera. A camera path
   starts at a point of a pixel and a point of the aperture stop joined by the real ray (stop
   aiming, :mod:`.camera`), leaves the lens into the scene and, at the first interface it meets
   (the cornea), splits into its transmitted (× T, × (n₁/n₂)² for radiance) and reflected (× R)
   parts. At every Lambertian vertex it adds next-event estimation to each LED — the LED's
   radiant intensity I(α) cos θ / d² along a straight, unoccluded segment (to every LED at the
   first vertex, to one drawn at random, weighted by their number, at later ones) — and, on the
   iris, the light the cornea refracts onto it, by a specular connection (:mod:`.cornea_nee`). It
   then continues by cosine sampling (the first vertex always, with weight ρ, in IRIS_SPLIT
   directions on the iris; later ones by Russian roulette). LEDs are points, so a camera path
   never hits one: these connections are the only way it receives light.
2. **First hit the cornea, except the refracted paths of part 1** (the glints, the light the
   cornea reflects onto the face, whatever enters the pupil): estimated from the LEDs. A light
   path leaves an LED uniformly inside the cone that holds the anterior cornea's bounding sphere
   (weighted I(α)/pdf), is split at the cornea into its reflected (× R) and transmitted (× T)
   parts, and goes on through refraction; a transmitted path that the posterior cornea
   transmits onto the iris belongs to part 1 and ends there. At a Lambertian vertex it scatters
   into a mixture of directions aimed at the camera's entrance pupil (for the iris, its
   paraxial image through the cornea) and cosine directions (defensive mixture: weight
   (cos θ/π) / pdf_mix ≤ 1/(1 − p_aim)), so aimed rays the cornea bends away from the lens cost
   time, never bias. Paths reaching the sensor deposit their power in their pixel.

Why a specular connection for the iris: a straight connection from the iris to an LED does not
exist (refraction), and the LEDs are points, so neither plain NEE nor hitting the source works
from the camera side, while tracing it forward leaves each iris pixel with the few paths that
happen to scatter into the lens. The cornea maps LED directions to iris points one to one, so
Newton's method finds the refracted path and its Jacobian gives the irradiance exactly; light
paths give the rest (glints among it) without a manifold solve. The two parts cover disjoint
sets of paths, so their sum is unbiased. Not covered by either: light an LED sends straight
into the lens (impossible for LEDs facing the eye). The agreement test against the plain
forward estimator checks all of it.

Variance: each pixel keeps Σm and Σm² over independent stratified sets of camera samples, and
Σc and Σc² of the light paths' deposits, so every pixel has its own variance estimate.
Light-path deposits are accumulated in 64-bit fixed point and camera sets are added one at a
time in order, so sums do not depend on threads or rounds: results depend on (scene, samples,
paths, seed) only.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from eyelume.kernels import geometry as G
from eyelume.kernels.interact import fresnel_reflectance, reflect, refract
from eyelume.kernels.rng import mix64, next_uniform, stream_start
from eyelume.kernels.sampling import (
    about_axis,
    cosine_hemisphere,
    orthonormal_basis,
    relative_intensity_at,
)
from eyelume.kernels.sequential import LENS_PASSED, trace_lens

from .camera import A_P, A_R, A_X, A_Y, A_Z, aim_at_stop, aim_chief, into_scene
from .cornea_nee import irradiance_through_cornea

__all__ = [
    "camera_pass",
    "light_pass",
    "direct_irradiance",
    "primary_surfaces",
]

_INV_PI = 1.0 / math.pi
_LIGHT_TAG = 0x4C49474854  # separates the light paths' streams from the camera paths'
_PLANE_TAG = 0x504C414E45  # … and the eye-plane points'


@njit(cache=True)
def led_irradiance(sf, si, leds, k, i0, alpha_grid, intensity_grid, x, y, z, nx, ny, nz):
    """Irradiance (W/mm²) at world point (x, y, z) on a face with unit normal n (toward the
    light's side) from LED k, if it sees the point along a straight unoccluded segment:
    I₀ f(α) cos θ / d²."""
    vx, vy, vz = leds[k, 0] - x, leds[k, 1] - y, leds[k, 2] - z
    d2 = vx * vx + vy * vy + vz * vz
    d = math.sqrt(d2)
    ux, uy, uz = vx / d, vy / d, vz / d
    cos_s = ux * nx + uy * ny + uz * nz
    if cos_s <= 0.0:
        return 0.0
    cos_a = -(ux * leds[k, 3] + uy * leds[k, 4] + uz * leds[k, 5])
    if cos_a <= 0.0:
        return 0.0
    s, t = G.nearest_hit(sf, si, x, y, z, ux, uy, uz)
    if s >= 0 and t < d * (1.0 - 1e-9) - 1e-6:
        return 0.0
    return i0 * relative_intensity_at(cos_a, alpha_grid, intensity_grid) * cos_s / d2


@njit(cache=True)
def direct_irradiance(sf, si, leds, i0, alpha_grid, intensity_grid, x, y, z, nx, ny, nz):
    """Irradiance (W/mm²) at world point (x, y, z) on a face with unit normal n (toward the
    light's side) from every LED that sees it along a straight unoccluded segment."""
    e = 0.0
    for k in range(leds.shape[0]):
        e += led_irradiance(sf, si, leds, k, i0, alpha_grid, intensity_grid, x, y, z, nx, ny, nz)
    return e


@njit(cache=True, inline="always")
def _specular(state, sf, si, s, dx, dy, dz, nx, ny, nz, cos_d, from_b):
    """Analog choice at a refracting interface, as in the forward tracer.

    Returns (state, alive, transmitted, dx, dy, dz)."""
    state, u = next_uniform(state)
    n1 = sf[s, G.N_B] if from_b else sf[s, G.N_A]
    n2 = sf[s, G.N_A] if from_b else sf[s, G.N_B]
    ok, tx, ty, tz = refract(dx, dy, dz, nx, ny, nz, n1 / n2)
    if not ok:
        rx, ry, rz = reflect(dx, dy, dz, nx, ny, nz)
        return state, True, False, rx, ry, rz
    r = fresnel_reflectance(cos_d, n1, n2) if si[s, G.FRESNEL] else sf[s, G.REFL]
    if u < r:
        rx, ry, rz = reflect(dx, dy, dz, nx, ny, nz)
        return state, True, False, rx, ry, rz
    if u < r + sf[s, G.ABSORB]:
        return state, False, False, dx, dy, dz
    return state, True, True, tx, ty, tz


@njit(cache=True)
def _camera_branch(
    state,
    sf,
    si,
    leds,
    i0,
    ag,
    ig,
    cornea,
    through,
    x,
    y,
    z,
    dx,
    dy,
    dz,
    beta,
    split,
    first_vertex,
    max_events,
):
    """Follow one camera path from (x, y, z) along (dx, dy, dz) with throughput ``beta``.

    With ``split``, the first refracting interface met before any Lambertian vertex is not
    chosen between by chance: the path goes on transmitted (× T) and the reflected part (× R)
    is handed back to be followed next. With ``first_vertex`` the path stops after the NEE at
    its first Lambertian vertex and hands that vertex back for its continuation; otherwise
    every vertex continues by Russian roulette. Returns (state, radiance, has_branch, branch
    origin xyz, branch direction xyz, branch throughput, vertex surface (−1: none), vertex xyz,
    its normal xyz, throughput × ρ there)."""
    radiance = 0.0
    bx = by = bz = bdx = bdy = bdz = bbeta = 0.0
    has_branch = False
    diffuse = 0
    for _ in range(max_events):
        s, t = G.nearest_hit(sf, si, x, y, z, dx, dy, dz)
        if s < 0:
            break
        action = si[s, G.ACTION]
        if action == G.ACT_LENS:
            break
        x += t * dx
        y += t * dy
        z += t * dz
        nx, ny, nz = G.surface_normal(sf, si, s, x, y, z)
        cos_d = dx * nx + dy * ny + dz * nz
        from_b = cos_d < 0.0
        if action == G.ACT_OPAQUE:
            rho = sf[s, G.RHO_B] if from_b else sf[s, G.RHO_A]
            if rho <= 0.0:
                break
            if not from_b:
                nx, ny, nz = -nx, -ny, -nz
            if first_vertex:
                e = direct_irradiance(sf, si, leds, i0, ag, ig, x, y, z, nx, ny, nz)
            else:  # interreflections: one LED drawn at random, its light × the LED count
                state, u = next_uniform(state)
                k = min(int(u * leds.shape[0]), leds.shape[0] - 1)
                e = leds.shape[0] * led_irradiance(sf, si, leds, k, i0, ag, ig, x, y, z, nx, ny, nz)
            if through[s]:
                e1, e2 = orthonormal_basis(nx, ny, nz)
                e += irradiance_through_cornea(
                    sf, si, cornea, s, leds, i0, ag, ig, x, y, z, nx, ny, nz, e1, e2
                )
            radiance += beta * rho * _INV_PI * e
            diffuse += 1
            if first_vertex:
                return (
                    state,
                    radiance,
                    has_branch,
                    bx,
                    by,
                    bz,
                    bdx,
                    bdy,
                    bdz,
                    bbeta,
                    s,
                    x,
                    y,
                    z,
                    nx,
                    ny,
                    nz,
                    beta * rho,
                )
            state, u = next_uniform(state)
            if u >= rho:
                break
            state, u1 = next_uniform(state)
            state, u2 = next_uniform(state)
            lx, ly, lz = cosine_hemisphere(u1, u2)
            dx, dy, dz = about_axis(lx, ly, lz, nx, ny, nz)
        else:
            n1 = sf[s, G.N_B] if from_b else sf[s, G.N_A]
            n2 = sf[s, G.N_A] if from_b else sf[s, G.N_B]
            if split and not has_branch:
                ok, tx, ty, tz = refract(dx, dy, dz, nx, ny, nz, n1 / n2)
                rx, ry, rz = reflect(dx, dy, dz, nx, ny, nz)
                if not ok:  # total internal reflection: nothing to split
                    dx, dy, dz = rx, ry, rz
                else:
                    r = fresnel_reflectance(cos_d, n1, n2) if si[s, G.FRESNEL] else sf[s, G.REFL]
                    has_branch = True
                    bx, by, bz, bdx, bdy, bdz, bbeta = x, y, z, rx, ry, rz, beta * r
                    # radiance / n² is what refraction conserves
                    beta *= (1.0 - r - sf[s, G.ABSORB]) * (n1 / n2) ** 2
                    dx, dy, dz = tx, ty, tz
            else:
                state, alive, transmitted, dx, dy, dz = _specular(
                    state, sf, si, s, dx, dy, dz, nx, ny, nz, cos_d, from_b
                )
                if not alive:
                    break
                if transmitted:
                    beta *= (n1 / n2) ** 2
        inv = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
        dx *= inv
        dy *= inv
        dz *= inv
    return (
        state,
        radiance,
        has_branch,
        bx,
        by,
        bz,
        bdx,
        bdy,
        bdz,
        bbeta,
        -1,
        x,
        y,
        z,
        0.0,
        0.0,
        1.0,
        0.0,
    )


#: Continuation rays from the first Lambertian vertex of a camera path: 1, or IRIS_SPLIT on
#: the surfaces lit through the cornea — the iris, whose light is mostly the face's, reflected
#: (it is shadowed by the cornea, the skin around it is not).
IRIS_SPLIT = 8


@njit(cache=True)
def _path_radiance(
    state, sf, si, leds, i0, ag, ig, cornea, through, x, y, z, dx, dy, dz, beta, split, max_events
):
    """A camera path with its first Lambertian vertex's continuation(s); see _camera_branch."""
    out = _camera_branch(
        state,
        sf,
        si,
        leds,
        i0,
        ag,
        ig,
        cornea,
        through,
        x,
        y,
        z,
        dx,
        dy,
        dz,
        beta,
        split,
        True,
        max_events,
    )
    state, radiance = out[0], out[1]
    s = out[10]
    if s >= 0:
        vx, vy, vz, nx, ny, nz, cbeta = (
            out[11],
            out[12],
            out[13],
            out[14],
            out[15],
            out[16],
            out[17],
        )
        k = IRIS_SPLIT if through[s] else 1
        for _ in range(k):
            state, u1 = next_uniform(state)
            state, u2 = next_uniform(state)
            lx, ly, lz = cosine_hemisphere(u1, u2)
            ex, ey, ez = about_axis(lx, ly, lz, nx, ny, nz)
            more = _camera_branch(
                state,
                sf,
                si,
                leds,
                i0,
                ag,
                ig,
                cornea,
                through,
                vx,
                vy,
                vz,
                ex,
                ey,
                ez,
                cbeta / k,
                False,
                False,
                max_events,
            )
            state = more[0]
            radiance += more[1]
    return state, radiance, out[2], out[3], out[4], out[5], out[6], out[7], out[8], out[9]


@njit(cache=True)
def _camera_radiance(
    state, sf, si, leds, i0, ag, ig, cornea, through, x, y, z, dx, dy, dz, max_events
):
    """Radiance (W/(mm²·sr)) arriving at the lens along −(dx, dy, dz) from (x, y, z).

    At a Lambertian vertex on a surface with ``through[s]`` (the iris), the light refracted by
    the cornea (surfaces ``cornea``, ``cornea + 1``) is added by a specular connection
    (:mod:`.cornea_nee`); the light paths skip exactly those paths. The camera path is split
    at the first interface it meets (the cornea's 2.4 % reflection would otherwise be a rare,
    bright event in every pupil and iris pixel)."""
    state, radiance, has_branch, bx, by, bz, bdx, bdy, bdz, bbeta = _path_radiance(
        state,
        sf,
        si,
        leds,
        i0,
        ag,
        ig,
        cornea,
        through,
        x,
        y,
        z,
        dx,
        dy,
        dz,
        1.0,
        True,
        max_events,
    )
    if has_branch and bbeta > 0.0:
        state, more, _, _, _, _, _, _, _, _ = _path_radiance(
            state,
            sf,
            si,
            leds,
            i0,
            ag,
            ig,
            cornea,
            through,
            bx,
            by,
            bz,
            bdx,
            bdy,
            bdz,
            bbeta,
            False,
            max_events,
        )
        radiance += more
    return state, radiance


@njit(cache=True, inline="always")
def _pixel_point(row, col, u1, u2, sensor):
    """Sensor-plane point (x, y) of picture pixel (row, col) at fractions (u1, u2): the
    picture is the sensor turned by 180° (see the forward tracer)."""
    sw, sh, sc, sr = sensor[0], sensor[1], sensor[2], sensor[3]
    return 0.5 * sw - (col + u1) * sw / sc, (row + u2) * sh / sr - 0.5 * sh


@njit(cache=True, parallel=True)
def camera_pass(
    seed,
    first_set,
    n_sets,
    sf,
    si,
    leds,
    i0,
    ag,
    ig,
    cornea,
    through,
    lf_rev,
    lf_open,
    k_stop,
    stop_r,
    image_z,
    rear_z,
    xp_z,
    xp_m,
    sensor,
    max_events,
    grid,
    pixels,
    out_sum,
    out_sq,
):
    """Add stratified sample sets ``first_set`` … ``first_set + n_sets − 1`` of each pixel in
    ``pixels`` (flat indices, row × cols + col): ``out_sum[i]`` += Σ m, ``out_sq[i]`` += Σ m²
    over the sets, m the mean of a set's grid² samples. A pixel's samples depend on its index
    and the seed only.

    A set stratifies the stop in ``grid`` equal-area rings × ``grid`` sectors and the pixel in a
    grid × grid array of cells, paired with the stop's strata by a random odd stride.

    A sample is a uniform point of the pixel and a uniform point of the stop joined by the real
    ray (:func:`aim_at_stop`); its value c = A_stop cos²θ / (d² |det J|) · L, L the radiance the
    lens receives along that ray, is an unbiased estimate of the pixel's mean irradiance
    (W/mm²); so is m, and the sets are independent, so their spread gives the variance.
    """
    cols = int(sensor[2])
    area = math.pi * stop_r * stop_r
    for i in prange(pixels.shape[0]):
        p = pixels[i]
        row = p // cols
        col = p - row * cols
        # the chief ray of the pixel centre and its Jacobian seed every sample's aim
        xc, yc = _pixel_point(row, col, 0.5, 0.5, sensor)
        found, qcx, qcy, a11, a12, a21, a22 = aim_chief(
            lf_open, k_stop, image_z, rear_z, xp_z, xp_m, xc, yc
        )
        if not found:
            continue
        adet = a11 * a22 - a12 * a21
        shift = 1.0 - (image_z - rear_z) / (image_z - xp_z)
        pseed = mix64(mix64(np.uint64(seed)) + np.uint64(p))
        for m in range(first_set, first_set + n_sets):
            state = stream_start(pseed, m)
            state, ua = next_uniform(state)
            state, ub = next_uniform(state)
            strata = grid * grid
            stride = 2 * int(ua * strata / 2) + 1
            offset = int(ub * strata)
            total = 0.0
            for k in range(strata):
                state, u1 = next_uniform(state)
                state, u2 = next_uniform(state)
                state, u3 = next_uniform(state)
                state, u4 = next_uniform(state)
                cell = (k * stride + offset) % strata
                xs, ys = _pixel_point(
                    row, col, (cell % grid + u1) / grid, (cell // grid + u2) / grid, sensor
                )
                r = stop_r * math.sqrt((k // grid + u3) / grid)
                phi = 2.0 * math.pi * (k % grid + u4) / grid
                tx, ty = r * math.cos(phi), r * math.sin(phi)
                found, qx, qy, det = aim_at_stop(
                    lf_open,
                    k_stop,
                    image_z,
                    rear_z,
                    xs,
                    ys,
                    tx,
                    ty,
                    qcx + shift * (xs - xc) + (a22 * tx - a12 * ty) / adet,
                    qcy + shift * (ys - yc) + (-a21 * tx + a11 * ty) / adet,
                    a11,
                    a12,
                    a21,
                    a22,
                )
                if not found:
                    continue
                ok, x, y, z, dx, dy, dz, g = into_scene(lf_rev, image_z, xs, ys, qx, qy, rear_z)
                if not ok:
                    continue
                state, radiance = _camera_radiance(
                    state,
                    sf,
                    si,
                    leds,
                    i0,
                    ag,
                    ig,
                    cornea,
                    through,
                    x,
                    y,
                    z,
                    dx,
                    dy,
                    dz,
                    max_events,
                )
                total += area * g / det * radiance
            mean = total / strata
            # one addition per set, in set order: the sums do not depend on how the sets
            # were split into rounds
            out_sum[i] += mean
            out_sq[i] += mean * mean


@njit(cache=True, inline="always")
def _aim_pdf(aim_row, x, y, z, dx, dy, dz):
    """Density per steradian of the aimed sampler at direction d from (x, y, z)."""
    if aim_row[A_P] <= 0.0 or dz <= 0.0:
        return 0.0
    t = (aim_row[A_Z] - z) / dz
    hx = x + t * dx - aim_row[A_X]
    hy = y + t * dy - aim_row[A_Y]
    rr = aim_row[A_R] * aim_row[A_R]
    if hx * hx + hy * hy > rr:
        return 0.0
    return t * t / (math.pi * rr * dz)


@njit(cache=True)
def _scatter(state, aim_row, x, y, z, nx, ny, nz):
    """A direction from the aim/cosine mixture about unit normal n.

    Returns (state, dx, dy, dz, weight = (cos θ / π) / pdf_mix; 0 when below the face)."""
    p = aim_row[A_P]
    state, u0 = next_uniform(state)
    state, u1 = next_uniform(state)
    state, u2 = next_uniform(state)
    if u0 < p:
        r = aim_row[A_R] * math.sqrt(u1)
        phi = 2.0 * math.pi * u2
        vx = aim_row[A_X] + r * math.cos(phi) - x
        vy = aim_row[A_Y] + r * math.sin(phi) - y
        vz = aim_row[A_Z] - z
        inv = math.copysign(1.0, vz) / math.sqrt(vx * vx + vy * vy + vz * vz)
        dx, dy, dz = vx * inv, vy * inv, vz * inv
    else:
        lx, ly, lz = cosine_hemisphere(u1, u2)
        dx, dy, dz = about_axis(lx, ly, lz, nx, ny, nz)
    cos_n = dx * nx + dy * ny + dz * nz
    if cos_n <= 0.0:
        return state, dx, dy, dz, 0.0
    pdf = (1.0 - p) * cos_n * _INV_PI + p * _aim_pdf(aim_row, x, y, z, dx, dy, dz)
    return state, dx, dy, dz, cos_n * _INV_PI / pdf


WEAK_SURVIVAL = 0.125


@njit(cache=True)
def _follow(state, w, x, y, z, dx, dy, dz, arrays, img, img2, glint, led, q, q2, chain):
    """Carry a light path of weight ``w`` (W per unit path) until it ends; deposit at the
    sensor. ``glint`` ≥ 0 while the path has met no Lambertian face (LED index). ``chain`` is 1
    when the path has just been transmitted by the anterior cornea: if it is then transmitted by
    the posterior cornea and meets a ``through`` surface, the camera paths' specular connection
    has it, and it ends here; −1 when it has just been reflected by the cornea: at its first
    Lambertian face it survives with probability WEAK_SURVIVAL (weight / WEAK_SURVIVAL)."""
    sf, si, lf, image_z, sensor, aim, max_events, cornea, through = arrays
    first_diffuse = True
    for _ in range(max_events):
        s, t = G.nearest_hit(sf, si, x, y, z, dx, dy, dz)
        if s < 0:
            return state
        action = si[s, G.ACTION]
        if action == G.ACT_LENS:
            nx, ny, nz = G.surface_normal(sf, si, s, x + t * dx, y + t * dy, z + t * dz)
            if dx * nx + dy * ny + dz * nz < 0.0:
                return state
            status, x, y, z, dx, dy, dz, _, _ = trace_lens(lf, x, y, z, dx, dy, dz, None, 0, False)
            if status != LENS_PASSED:
                return state
            t = (image_z - z) / dz
            x += t * dx
            y += t * dy
            sw, sh, sc, sr = sensor[0], sensor[1], int(sensor[2]), int(sensor[3])
            col = int(math.floor((0.5 * sw - x) / sw * sc))
            row = int(math.floor((y + 0.5 * sh) / sh * sr))
            if 0 <= col < sc and 0 <= row < sr:
                c = w * sc * sr / (sw * sh)  # W per unit path → W/mm² in the pixel
                img[row, col] += np.int64(c / q + 0.5)
                img2[row, col] += np.int64(c * c / q2 + 0.5)
                if glint >= 0:
                    led[glint, row, col] += np.int64(c / q + 0.5)
            return state
        x += t * dx
        y += t * dy
        z += t * dz
        nx, ny, nz = G.surface_normal(sf, si, s, x, y, z)
        cos_d = dx * nx + dy * ny + dz * nz
        from_b = cos_d < 0.0
        if action == G.ACT_OPAQUE:
            if chain == 2 and through[s]:
                return state
            rho = sf[s, G.RHO_B] if from_b else sf[s, G.RHO_A]
            if rho <= 0.0:
                return state
            glint = -1
            if chain == -1:  # the cornea's 2.4 % reflection onto the face: a faint part of
                # the skin's light, which the camera paths give well; thin it by roulette
                state, u = next_uniform(state)
                if u >= WEAK_SURVIVAL:
                    return state
                w /= WEAK_SURVIVAL
            chain = 0
            if first_diffuse:
                w *= rho
                first_diffuse = False
            else:
                state, u = next_uniform(state)
                if u >= rho:
                    return state
            if not from_b:
                nx, ny, nz = -nx, -ny, -nz
            state, dx, dy, dz, f = _scatter(state, aim[s, 1 if from_b else 0], x, y, z, nx, ny, nz)
            if f <= 0.0:
                return state
            w *= f
        else:
            state, alive, transmitted, dx, dy, dz = _specular(
                state, sf, si, s, dx, dy, dz, nx, ny, nz, cos_d, from_b
            )
            if not alive:
                return state
            chain = 2 if chain == 1 and transmitted and s == cornea + 1 and not from_b else 0
        inv = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
        dx *= inv
        dy *= inv
        dz *= inv
    return state


@njit(cache=True)
def _light_path(i, seed, cornea, leds, i0, ag, ig, arrays, img, img2, led_img, q, q2):
    """Light path ``i``: LED i mod N toward the cornea, split there (see module docstring)."""
    sf, si = arrays[0], arrays[1]
    k = i % leds.shape[0]
    state = stream_start(seed, i)
    px, py, pz = leds[k, 0], leds[k, 1], leds[k, 2]
    wx, wy, wz = sf[cornea, G.BX] - px, sf[cornea, G.BY] - py, sf[cornea, G.BZ] - pz
    dist = math.sqrt(wx * wx + wy * wy + wz * wz)
    rb = sf[cornea, G.BR]
    cos_max = math.sqrt(1.0 - rb * rb / (dist * dist))
    state, u1 = next_uniform(state)
    state, u2 = next_uniform(state)
    ct = 1.0 - u1 * (1.0 - cos_max)
    st = math.sqrt(max(0.0, 1.0 - ct * ct))
    phi = 2.0 * math.pi * u2
    dx, dy, dz = about_axis(
        st * math.cos(phi), st * math.sin(phi), ct, wx / dist, wy / dist, wz / dist
    )
    cos_a = dx * leds[k, 3] + dy * leds[k, 4] + dz * leds[k, 5]
    # path i serves LED i mod N: a share 1/N of the paths estimates each LED's light
    w = leds.shape[0] * i0 * relative_intensity_at(cos_a, ag, ig) * 2.0 * math.pi * (1.0 - cos_max)
    if w <= 0.0:
        return
    s, t = G.nearest_hit(sf, si, px, py, pz, dx, dy, dz)
    if s != cornea:
        return  # first hit elsewhere: the camera paths' share (or nothing)
    x, y, z = px + t * dx, py + t * dy, pz + t * dz
    nx, ny, nz = G.surface_normal(sf, si, s, x, y, z)
    cos_d = dx * nx + dy * ny + dz * nz
    if cos_d <= 0.0:
        return
    n1, n2 = sf[s, G.N_A], sf[s, G.N_B]
    _, tx, ty, tz = refract(dx, dy, dz, nx, ny, nz, n1 / n2)
    r = fresnel_reflectance(cos_d, n1, n2) if si[s, G.FRESNEL] else sf[s, G.REFL]
    rx, ry, rz = reflect(dx, dy, dz, nx, ny, nz)
    state = _follow(state, w * r, x, y, z, rx, ry, rz, arrays, img, img2, k, led_img, q, q2, -1)
    tau = 1.0 - r - sf[s, G.ABSORB]
    _follow(state, w * tau, x, y, z, tx, ty, tz, arrays, img, img2, k, led_img, q, q2, 1)


@njit(cache=True, parallel=True)
def light_pass(seed, first, count, cornea, leds, i0, ag, ig, arrays, img, img2, led_img, q, q2):
    """Trace light paths ``first`` … ``first + count − 1``; chunk c adds to img[c], img2[c],
    led_img[c] (fixed-point Σc and Σc² in units q and q2 of W/mm² per unit path)."""
    n_chunks = img.shape[0]
    lseed = mix64(np.uint64(seed) ^ np.uint64(_LIGHT_TAG))
    for c in prange(n_chunks):
        lo = first + (count * c) // n_chunks
        hi = first + (count * (c + 1)) // n_chunks
        for i in range(lo, hi):
            _light_path(
                i, lseed, cornea, leds, i0, ag, ig, arrays, img[c], img2[c], led_img[c], q, q2
            )


@njit(cache=True, parallel=True)
def primary_surfaces(
    sf, si, lf_rev, lf_open, k_stop, image_z, rear_z, xp_z, xp_m, sensor, row0, labels, sides
):
    """The surface each pixel sees in the ideal (refraction-only) image: the chief ray from the
    pixel centre through the stop's centre, always refracting (never reflecting), to the first
    opaque surface (``labels``; −1: nothing, or no chief ray) and the side it meets (``sides``:
    1 = side B, the side the surface's normal points to). ``labels`` and ``sides`` hold the band
    of sensor rows from ``row0`` (so a large sensor is mapped band by band)."""
    rows, cols = labels.shape
    for p in prange(rows * cols):
        band_row = p // cols
        col = p - band_row * cols
        row = row0 + band_row
        xs, ys = _pixel_point(row, col, 0.5, 0.5, sensor)
        labels[band_row, col] = -1
        found, qx, qy, _, _, _, _ = aim_chief(lf_open, k_stop, image_z, rear_z, xp_z, xp_m, xs, ys)
        if not found:
            continue
        ok, x, y, z, dx, dy, dz, _ = into_scene(lf_rev, image_z, xs, ys, qx, qy, rear_z)
        if not ok:
            continue
        for _ in range(32):
            s, t = G.nearest_hit(sf, si, x, y, z, dx, dy, dz)
            if s < 0 or si[s, G.ACTION] != G.ACT_REFRACT:
                labels[band_row, col] = s
                if s >= 0:
                    nx, ny, nz = G.surface_normal(sf, si, s, x + t * dx, y + t * dy, z + t * dz)
                    sides[band_row, col] = 1 if dx * nx + dy * ny + dz * nz < 0.0 else 0
                break
            x += t * dx
            y += t * dy
            z += t * dz
            nx, ny, nz = G.surface_normal(sf, si, s, x, y, z)
            cos_d = dx * nx + dy * ny + dz * nz
            n1 = sf[s, G.N_B] if cos_d < 0.0 else sf[s, G.N_A]
            n2 = sf[s, G.N_A] if cos_d < 0.0 else sf[s, G.N_B]
            ok, dx, dy, dz = refract(dx, dy, dz, nx, ny, nz, n1 / n2)
            if not ok:
                break


@njit(cache=True, parallel=True)
def plane_direct(seed, sf, si, leds, i0, ag, ig, plane, n_sub, out):
    """Direct LED irradiance (W/mm²) toward the eye on the eye-plane bins (row 0 at +y): the
    mean over n_sub × n_sub jittered points per bin (one uniform point in each cell, so the
    mean is unbiased where an occluder's edge cuts the bin), each lit by the LEDs that see it."""
    pw, ph, pc, pr = plane[0], plane[1], int(plane[2]), int(plane[3])
    for p in prange(pr * pc):
        row = p // pc
        col = p - row * pc
        state = stream_start(mix64(np.uint64(seed) ^ np.uint64(_PLANE_TAG)), p)
        acc = 0.0
        for a in range(n_sub):
            for b in range(n_sub):
                state, u1 = next_uniform(state)
                state, u2 = next_uniform(state)
                x = (col + (a + u1) / n_sub) * pw / pc - 0.5 * pw
                y = 0.5 * ph - (row + (b + u2) / n_sub) * ph / pr
                acc += direct_irradiance(sf, si, leds, i0, ag, ig, x, y, 0.0, 0.0, 0.0, 1.0)
        out[row, col] = acc / (n_sub * n_sub)
