"""The fast estimator: camera-side paths with next-event estimation, plus aimed light paths.

Every light path runs LED → … → camera. We split path space by the path's first segment:

1. **First hit Lambertian** (skin, lids, sclera — most of the image): estimated from the camera.
   A camera path starts at a uniform point of a pixel toward a uniform point of the lens's rear
   disk (:mod:`eyelume.estimators.camera`), is traced back through the lens into the scene, takes
   the cornea's partial reflection and refraction by analog choices, and at every Lambertian
   vertex adds next-event estimation to each LED — the LED's radiant intensity I(α) cos θ / d²
   along a straight, unoccluded segment — then continues by cosine sampling: always after the
   first Lambertian vertex (weight ρ), with probability ρ after later ones.
   LEDs are points, so a camera path can never hit one: the NEE term is the only way this
   estimator receives light, and it is exact for the direct segment.
2. **First hit the cornea** (the glints, the iris and pupil seen through the cornea, light the
   cornea reflects onto the face): estimated from the LEDs. A light path leaves an LED uniformly
   inside the cone that holds the anterior cornea's bounding sphere (weighted I(α)/pdf), is split
   at the cornea into its reflected (× R) and transmitted (× T) parts, and goes on through
   refraction. At a Lambertian vertex it scatters into a mixture of directions aimed at the
   camera's pupil — for the iris, at the pupil's paraxial image through the cornea — and
   cosine directions (defensive mixture: weight (cos θ/π) / pdf_mix ≤ 1/(1 − p_aim)), so aimed
   rays the cornea bends away from the lens only cost time, never bias. Paths reaching the
   sensor deposit their power in their pixel.

Why this split for the light that reaches the iris through the cornea: a straight connection
from the iris to an LED does not exist (refraction), and the LEDs are points, so neither NEE nor
hitting the source works from the camera side. Tracing that light forward is exact through any
number of refractions and needs no manifold solve; the aim toward the pupil's image makes most
of those paths reach the lens. The two parts cover disjoint sets of paths (first segment ends on
a Lambertian face or on the cornea), so their sum is unbiased. Not covered by either: light an
LED sends straight into the lens (impossible for LEDs facing the eye; checked by the agreement
test against the plain forward estimator).

Variance: each pixel keeps Σc and Σc² of its camera samples (independent streams), and of the
light paths' deposits, so every pixel has its own variance estimate. Light-path deposits are
accumulated in 64-bit fixed point, so sums do not depend on the order threads add them:
results depend on (scene, samples, paths, seed) only.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from eyelume.kernels import geometry as G
from eyelume.kernels.interact import fresnel_reflectance, reflect, refract
from eyelume.kernels.rng import mix64, next_uniform, stream_start
from eyelume.kernels.sampling import about_axis, cosine_hemisphere
from eyelume.kernels.sequential import LENS_PASSED, trace_lens

from .camera import A_P, A_R, A_X, A_Y, A_Z, aim_at_stop, aim_chief, into_scene

__all__ = [
    "camera_pass",
    "light_pass",
    "direct_irradiance",
    "primary_surfaces",
    "relative_intensity_at",
]

_INV_PI = 1.0 / math.pi
_LIGHT_TAG = 0x4C49474854  # separates the light paths' streams from the camera paths'
_PLANE_TAG = 0x504C414E45  # … and the eye-plane points'


@njit(cache=True, inline="always")
def relative_intensity_at(cos_a, alpha_grid, intensity_grid):
    """I(α)/I₀ at cos α, linear in α on the uniform grid of the compiled scene; 0 behind."""
    if cos_a <= 0.0:
        return 0.0
    a = math.acos(min(1.0, cos_a))
    n = alpha_grid.shape[0]
    f = a / alpha_grid[n - 1] * (n - 1)
    i = int(f)
    if i >= n - 1:
        return intensity_grid[n - 1]
    frac = f - i
    return intensity_grid[i] * (1.0 - frac) + intensity_grid[i + 1] * frac


@njit(cache=True)
def direct_irradiance(sf, si, leds, i0, alpha_grid, intensity_grid, x, y, z, nx, ny, nz):
    """Irradiance (W/mm²) at world point (x, y, z) on a face with unit normal n (toward the
    light's side) from every LED that sees it along a straight unoccluded segment."""
    e = 0.0
    for k in range(leds.shape[0]):
        vx, vy, vz = leds[k, 0] - x, leds[k, 1] - y, leds[k, 2] - z
        d2 = vx * vx + vy * vy + vz * vz
        d = math.sqrt(d2)
        ux, uy, uz = vx / d, vy / d, vz / d
        cos_s = ux * nx + uy * ny + uz * nz
        if cos_s <= 0.0:
            continue
        cos_a = -(ux * leds[k, 3] + uy * leds[k, 4] + uz * leds[k, 5])
        if cos_a <= 0.0:
            continue
        s, t = G.nearest_hit(sf, si, x, y, z, ux, uy, uz)
        if s >= 0 and t < d * (1.0 - 1e-9) - 1e-6:
            continue
        e += i0 * relative_intensity_at(cos_a, alpha_grid, intensity_grid) * cos_s / d2
    return e


@njit(cache=True, inline="always")
def _specular(state, sf, si, s, dx, dy, dz, nx, ny, nz, cos_d, from_b):
    """Analog choice at a refracting interface, as in the forward tracer.

    Returns (state, alive, dx, dy, dz)."""
    state, u = next_uniform(state)
    n1 = sf[s, G.N_B] if from_b else sf[s, G.N_A]
    n2 = sf[s, G.N_A] if from_b else sf[s, G.N_B]
    ok, tx, ty, tz = refract(dx, dy, dz, nx, ny, nz, n1 / n2)
    if not ok:
        rx, ry, rz = reflect(dx, dy, dz, nx, ny, nz)
        return state, True, rx, ry, rz
    r = fresnel_reflectance(cos_d, n1, n2) if si[s, G.FRESNEL] else sf[s, G.REFL]
    if u < r:
        rx, ry, rz = reflect(dx, dy, dz, nx, ny, nz)
        return state, True, rx, ry, rz
    if u < r + sf[s, G.ABSORB]:
        return state, False, dx, dy, dz
    return state, True, tx, ty, tz


@njit(cache=True)
def _camera_radiance(state, sf, si, leds, i0, ag, ig, x, y, z, dx, dy, dz, max_events):
    """Radiance (W/(mm²·sr)) arriving at the lens along −(dx, dy, dz) from (x, y, z)."""
    radiance = 0.0
    beta = 1.0  # path throughput
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
            radiance += (
                beta
                * rho
                * _INV_PI
                * direct_irradiance(sf, si, leds, i0, ag, ig, x, y, z, nx, ny, nz)
            )
            diffuse += 1
            if diffuse == 1:  # always follow the first bounce (it carries the interreflections)
                beta *= rho
            else:  # later ones by Russian roulette
                state, u = next_uniform(state)
                if u >= rho:
                    break
            state, u1 = next_uniform(state)
            state, u2 = next_uniform(state)
            lx, ly, lz = cosine_hemisphere(u1, u2)
            dx, dy, dz = about_axis(lx, ly, lz, nx, ny, nz)
        else:
            state, alive, dx, dy, dz = _specular(
                state, sf, si, s, dx, dy, dz, nx, ny, nz, cos_d, from_b
            )
            if not alive:
                break
        inv = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
        dx *= inv
        dy *= inv
        dz *= inv
    return state, radiance


@njit(cache=True, inline="always")
def _pixel_point(row, col, u1, u2, sensor):
    """Sensor-plane point (x, y) of picture pixel (row, col) at fractions (u1, u2): the
    picture is the sensor turned by 180° (see the forward tracer)."""
    sw, sh, sc, sr = sensor[0], sensor[1], sensor[2], sensor[3]
    return 0.5 * sw - (col + u1) * sw / sc, (row + u2) * sh / sr - 0.5 * sh


#: Camera samples come in stratified sets of STRATA: the stop in 4 equal-area rings × 4 sectors,
#: the pixel in a 4 × 4 grid paired with the rings and sectors by a random odd stride.
STRATA = 16


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
    out_sum,
    out_sq,
):
    """Add stratified sample sets ``first_set`` … ``first_set + n_sets − 1`` of every pixel:
    ``out_sum`` += Σ m, ``out_sq`` += Σ m² over the sets, m the mean of a set's STRATA samples.

    A sample is a uniform point of the pixel and a uniform point of the stop joined by the real
    ray (:func:`aim_at_stop`); its value c = A_stop cos²θ / (d² |det J|) · L, L the radiance the
    lens receives along that ray, is an unbiased estimate of the pixel's mean irradiance
    (W/mm²); so is m, and the sets are independent, so their spread gives the variance.
    """
    rows, cols = out_sum.shape
    area = math.pi * stop_r * stop_r
    for p in prange(rows * cols):
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
            stride = 2 * int(ua * 8) + 1
            offset = int(ub * STRATA)
            total = 0.0
            for k in range(STRATA):
                state, u1 = next_uniform(state)
                state, u2 = next_uniform(state)
                state, u3 = next_uniform(state)
                state, u4 = next_uniform(state)
                cell = (k * stride + offset) % STRATA
                xs, ys = _pixel_point(
                    row, col, (cell % 4 + u1) / 4.0, (cell // 4 + u2) / 4.0, sensor
                )
                r = stop_r * math.sqrt((k // 4 + u3) / 4.0)
                phi = 2.0 * math.pi * (k % 4 + u4) / 4.0
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
                    state, sf, si, leds, i0, ag, ig, x, y, z, dx, dy, dz, max_events
                )
                total += area * g / det * radiance
            mean = total / STRATA
            # one addition per set, in set order: the sums do not depend on how the sets
            # were split into rounds
            out_sum[row, col] += mean
            out_sq[row, col] += mean * mean


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


@njit(cache=True)
def _follow(state, w, x, y, z, dx, dy, dz, arrays, img, img2, glint, led, q, q2):
    """Carry a light path of weight ``w`` (W per unit path) until it ends; deposit at the
    sensor. ``glint`` ≥ 0 while the path has met no Lambertian face (LED index)."""
    sf, si, lf, image_z, sensor, aim, max_events = arrays
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
            path = np.empty((1, 3))
            status, x, y, z, dx, dy, dz, _, _ = trace_lens(lf, x, y, z, dx, dy, dz, path, 0, False)
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
            rho = sf[s, G.RHO_B] if from_b else sf[s, G.RHO_A]
            if rho <= 0.0:
                return state
            glint = -1
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
            state, alive, dx, dy, dz = _specular(
                state, sf, si, s, dx, dy, dz, nx, ny, nz, cos_d, from_b
            )
            if not alive:
                return state
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
    state = _follow(state, w * r, x, y, z, rx, ry, rz, arrays, img, img2, k, led_img, q, q2)
    tau = 1.0 - r - sf[s, G.ABSORB]
    _follow(state, w * tau, x, y, z, tx, ty, tz, arrays, img, img2, k, led_img, q, q2)


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
    sf, si, lf_rev, lf_open, k_stop, image_z, rear_z, xp_z, xp_m, sensor, labels, sides
):
    """The surface each pixel sees in the ideal (refraction-only) image: the chief ray from the
    pixel centre through the stop's centre, always refracting (never reflecting), to the first
    opaque surface (``labels``; −1: nothing, or no chief ray) and the side it meets (``sides``:
    1 = side B, the side the surface's normal points to)."""
    rows, cols = labels.shape
    for p in prange(rows * cols):
        row = p // cols
        col = p - row * cols
        xs, ys = _pixel_point(row, col, 0.5, 0.5, sensor)
        labels[row, col] = -1
        found, qx, qy, _, _, _, _ = aim_chief(lf_open, k_stop, image_z, rear_z, xp_z, xp_m, xs, ys)
        if not found:
            continue
        ok, x, y, z, dx, dy, dz, _ = into_scene(lf_rev, image_z, xs, ys, qx, qy, rear_z)
        if not ok:
            continue
        for _ in range(32):
            s, t = G.nearest_hit(sf, si, x, y, z, dx, dy, dz)
            if s < 0 or si[s, G.ACTION] != G.ACT_REFRACT:
                labels[row, col] = s
                if s >= 0:
                    nx, ny, nz = G.surface_normal(sf, si, s, x + t * dx, y + t * dy, z + t * dz)
                    sides[row, col] = 1 if dx * nx + dy * ny + dz * nz < 0.0 else 0
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
