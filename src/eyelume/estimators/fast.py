"""The fast estimator: camera-side paths with next-event estimation, plus aimed light paths.

Every light path runs LED → … → camera. We split path space by how the path leaves its LED:

1. **First hit Lambertian** (skin, lids, sclera — most of the image), and **refracted by the
   anterior and posterior cornea onto the iris**: estimated from the camera. A camera path
   starts at a point of a pixel and a point of the aperture stop joined by the real ray (stop
   aiming, :mod:`.camera`), leaves the lens into the scene and, at the first interface it meets
   (the cornea), splits into its transmitted (× T, × (n₁/n₂)² for radiance) and reflected (× R)
   parts. At every Lambertian vertex it adds next-event estimation to the LEDs — the LED's
   radiant intensity I(α) cos θ / d² along a straight, unoccluded segment: to every LED at the
   first vertex; at later ones to one LED drawn in proportion to its unshadowed irradiance
   (:func:`sampled_irradiance`: one shadow ray, noisy only where a shadow falls; a uniform
   draw × the LED count was most of a vr-offaxis skin pixel's noise) — and, on the
   iris, the light the cornea refracts onto it, by a specular connection (:mod:`.cornea_nee`):
   from every LED at the first vertex, from one LED drawn uniformly (× the LED count) at later
   ones (a continuation ray the cornea reflects back onto the iris: ~0.1 % of an iris pixel's
   light, which cost ~40 % of a vr-offaxis iris sample with every LED's Newton solve). It
   then continues by cosine sampling: the first vertex always, with weight ρ, in g²
   directions, one in each of g × g strata of the cosine-weighted hemisphere (the light faces
   send each other is most of what varies between samples; g = ``run.continuation_grid``, on
   the iris ``run.iris_continuation_grid``, by default at least 3; in one direction for the
   part the cornea reflects, a ~2 % share),
   the strata spread only over the directions outside the vertex's free cone
   (:func:`~eyelume.kernels.geometry.free_cone`: the cone about the normal whose rays meet
   nothing that can send light back, so carry exactly 0 — on vr-offaxis about half the
   cosine-weighted hemisphere over the periorbital skin, where ~80 % of the rays met
   nothing), each weighted by that region's share 1 − sin²θ₀; later ones by Russian
   roulette. LEDs are points, so a camera path never hits one: these connections are the
   only way it receives light. Before its first Lambertian vertex, it also splits at each
   optical element's surface, the weaker part followed after it (:func:`_camera_branch`).
2. **First hit the cornea, except the refracted paths of part 1** (the glints, the light the
   cornea reflects onto the face, whatever enters the pupil): estimated from the LEDs. A light
   path leaves an LED uniformly inside the cone that holds the anterior cornea's bounding sphere
   or, with a small probability, inside the narrow cone about the direction to the LED's glint
   (the cornea point that reflects it into the entrance pupil), weighted I(α)/pdf_mix
   (:func:`_light_path`: the glints, formed by light paths alone, then need ~100 × fewer of
   them), is split at the cornea into its reflected (× R) and transmitted (× T)
   parts, and goes on through refraction; a transmitted path that the posterior cornea
   transmits onto the iris belongs to part 1 and ends there. At a Lambertian vertex it scatters
   into a mixture of directions aimed at the camera's entrance pupil (for the iris, its
   paraxial image through the cornea; seen through optical elements, its image through
   them) and cosine directions (defensive mixture: weight
   (cos θ/π) / pdf_mix ≤ 1/(1 − p_aim)), so aimed rays the cornea bends away from the lens cost
   time, never bias. Paths reaching the sensor deposit their power in their pixel.
3. **Straight into the lens** (an LED the camera sees, beside a wide lens): estimated from the
   LEDs too, by a second leg of every light path, aimed uniformly inside the cone of the lens's
   first surface, counted only when the lens is what it meets first.

Why a specular connection for the iris: a straight connection from the iris to an LED does not
exist (refraction), and the LEDs are points, so neither plain NEE nor hitting the source works
from the camera side, while tracing it forward leaves each iris pixel with the few paths that
happen to scatter into the lens. The cornea maps LED directions to iris points one to one, so
Newton's method finds the refracted path and its Jacobian gives the irradiance exactly; light
paths give the rest (glints among it) without a manifold solve. The three parts cover disjoint
sets of paths, so their sum is unbiased. The agreement test against the plain forward
estimator, on every preset, checks all of it.

Variance: each pixel keeps Σm and Σm² over independent stratified sets of camera samples, and
Σc and Σc² of the light paths' deposits, so every pixel has its own variance estimate.
Light-path deposits are accumulated in 64-bit fixed point and camera sets are added one at a
time in order, so sums do not depend on threads or rounds: results depend on (scene, samples,
paths, seed) only.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit, prange

from eyelume.kernels import geometry as G
from eyelume.kernels.bins import from_grid, plane_point, to_grid
from eyelume.kernels.interact import interface_at, reflect, refract
from eyelume.kernels.jit import per_ray
from eyelume.kernels.rng import mix64, next_uniform, side_uniform, stream_start
from eyelume.kernels.sampling import (
    about_axis,
    aimed_mixture,
    aimed_mixture_pdf,
    cosine_hemisphere,
    disk_stratum,
    led_cos_alpha,
    orthonormal_basis,
    radiant_intensity,
    uniform_cone,
    uniform_cone_pdf,
)
from eyelume.kernels.sequential import LENS_PASSED, trace_lens
from eyelume.kernels.tables import (
    CHAIN_STEPS,
    G_AX,
    G_AY,
    G_AZ,
    G_COS,
    G_P,
    IRIS_GRID,
    REFLECT,
    TRANSMIT_A,
    Facet,
    Ray,
    SceneTables,
    scene_parts,
)

from .camera import aim_chief, aim_into_scene, into_scene
from .cornea_nee import (
    Receiver,
    chain_row,
    irradiance_through_cornea,
    led_through_chain,
    led_through_cornea,
    straight_plane,
)

__all__ = [
    "camera_pass",
    "light_pass",
    "direct_irradiance",
    "primary_surfaces",
    "plane_direct",
    "indirect_cache",
]

_INV_PI = 1.0 / math.pi
_LIGHT_TAG = 0x4C49474854  # separates the light paths' streams from the camera paths'
_DIRECT_TAG = 0x444952454354  # the light paths' direct legs (LED → lens) have their own
_PLANE_TAG = 0x504C414E45  # … and the eye-plane points'
_CORNEA_TAG = 0x434F524E4541  # the LED of a later vertex's connection through the cornea
_CHAIN_TAG = 0x434841494E  # … and through an element
_ELEMENT_TAG = 0x454C454D  # the light paths' legs toward an element surface (+ its row)
_GHOST_TAG = 0x47484F5354  # … and toward the lens's pupil mirrored in it (+ its row)
_CACHE_TAG = 0x4952524144  # the irradiance cache's points (indirect_cache)
_NOWHERE = (-1.0, -1.0)  # a path that reads no irradiance cache
#: The irradiance cache's interpolation reads a point only when its normal is within this
#: cosine of the vertex's (~18°; Ward et al. 1988 reject by the normal's change as well)
CACHE_MIN_COS = 0.95


class Branch(NamedTuple):
    """The part of a camera path split off at the first refracting interface (the reflected
    ray and its throughput); ``beta`` 0 when there is none."""

    ray: Ray
    beta: float


#: The most element branches a camera path keeps (:class:`Scratch`): one per element
#: surface its first leg meets before its first Lambertian vertex (three in
#: paper2005-integrated: the hot mirror and the eyepiece's two faces). Beyond it, an element
#: surface is chosen between by chance (unbiased either way).
ELEMENT_BRANCHES = 6


class Scratch(NamedTuple):
    """A camera pass's per-pixel scratch space: ``e_led`` (n_leds,) for
    :func:`sampled_irradiance`, and the weaker parts split off at optical elements' surfaces
    by one camera path (:func:`_camera_branch`), followed after it: ``rays``
    (ELEMENT_BRANCHES, 7) rows of (x, y, z, dx, dy, dz, throughput), ``count`` (1,) int64 the
    rows in use; ``gaps`` (n_surfaces,) the first vertex's
    :func:`~eyelume.kernels.geometry.free_cone_gaps`, by which its continuation rays' first
    nearest-hit search skips the surfaces out of their reach."""

    e_led: np.ndarray
    rays: np.ndarray
    count: np.ndarray
    gaps: np.ndarray


class Vertex(NamedTuple):
    """The first Lambertian vertex of a camera path: surface ``s`` (−1: none), the point, its
    normal toward the arriving light, the throughput × ρ there and its free cone's sin²θ₀
    (:func:`~eyelume.kernels.geometry.free_cone_gaps`, the gaps in the path's scratch)."""

    s: int
    x: float
    y: float
    z: float
    nx: float
    ny: float
    nz: float
    beta: float
    s0: float


class CameraPath(NamedTuple):
    """What :func:`_camera_branch` hands back: the stream state, the radiance gathered, the
    split-off branch (``has_branch``) and the first Lambertian vertex."""

    state: np.uint64
    radiance: float
    has_branch: bool
    branch: Branch
    vertex: Vertex


class Specular(NamedTuple):
    """The analog choice at a refracting interface: stream state, whether the path goes on
    (not absorbed), whether it was transmitted, and its new direction."""

    state: np.uint64
    alive: bool
    transmitted: bool
    dx: float
    dy: float
    dz: float


@per_ray
def led_irradiance(surfaces, leds, k, facet):
    """Irradiance (W/mm²) at a :class:`~eyelume.kernels.tables.Facet` (a world point on a face
    and its unit normal toward the light's side) from LED k of ``leds``
    (:class:`~eyelume.kernels.tables.LedTable`), if it sees the point along a straight
    unoccluded segment: I(α) cos θ / d²."""
    x, y, z, nx, ny, nz = facet
    vx, vy, vz = leds.points[k, 0] - x, leds.points[k, 1] - y, leds.points[k, 2] - z
    d2 = vx * vx + vy * vy + vz * vz
    d = math.sqrt(d2)
    ux, uy, uz = vx / d, vy / d, vz / d
    cos_s = ux * nx + uy * ny + uz * nz
    if cos_s <= 0.0:
        return 0.0
    if led_cos_alpha(leds, k, -ux, -uy, -uz) <= 0.0:
        return 0.0
    if G.occluded(surfaces.sf, surfaces.si, x, y, z, ux, uy, uz, d * (1.0 - 1e-9) - 1e-6):
        return 0.0
    return radiant_intensity(leds, k, -ux, -uy, -uz) * cos_s / d2


@per_ray
def _unshadowed(leds, k, facet):
    """LED k's irradiance (W/mm²) at the facet were nothing in the way: I(α) cos θ / d²."""
    x, y, z, nx, ny, nz = facet
    vx, vy, vz = leds.points[k, 0] - x, leds.points[k, 1] - y, leds.points[k, 2] - z
    d2 = vx * vx + vy * vy + vz * vz
    d = math.sqrt(d2)
    ux, uy, uz = vx / d, vy / d, vz / d
    cos_s = ux * nx + uy * ny + uz * nz
    if cos_s <= 0.0 or led_cos_alpha(leds, k, -ux, -uy, -uz) <= 0.0:
        return 0.0
    return radiant_intensity(leds, k, -ux, -uy, -uz) * cos_s / d2


@per_ray
def sampled_irradiance(state, surfaces, leds, facet, e_led):
    """An unbiased one-shadow-ray estimate of :func:`direct_irradiance`: LED k drawn with
    probability p_k = E_k / ΣE, E_k its unshadowed irradiance (:func:`_unshadowed`), and
    E_k V_k / p_k = ΣE · V_k returned (V_k = 1 if nothing is in the way). Its only variance is
    from shadows. ``e_led`` (n_leds,) is scratch space the caller owns: each E_k is evaluated
    once (an arccosine of the LED's profile each) and read back for the draw. Returns (state,
    irradiance W/mm²)."""
    n = leds.points.shape[0]
    total = 0.0
    for k in range(n):
        e = _unshadowed(leds, k, facet)
        e_led[k] = e
        total += e
    if total <= 0.0:
        return state, 0.0
    state, u = next_uniform(state)
    target = u * total
    acc = 0.0
    pick = -1
    for k in range(n):
        e = e_led[k]
        if e > 0.0:
            pick = k
            acc += e
            if target < acc:
                break
    x, y, z = facet[0], facet[1], facet[2]
    vx, vy, vz = leds.points[pick, 0] - x, leds.points[pick, 1] - y, leds.points[pick, 2] - z
    d = math.sqrt(vx * vx + vy * vy + vz * vz)
    if G.occluded(
        surfaces.sf, surfaces.si, x, y, z, vx / d, vy / d, vz / d, d * (1.0 - 1e-9) - 1e-6
    ):
        return state, 0.0
    return state, total


@per_ray
def direct_irradiance(surfaces, leds, facet):
    """Irradiance (W/mm²) at a :class:`~eyelume.kernels.tables.Facet` from every LED that sees
    it along a straight unoccluded segment."""
    e = 0.0
    for k in range(leds.points.shape[0]):
        e += led_irradiance(surfaces, leds, k, facet)
    return e


@per_ray
def direct_irradiance_within(surfaces, leds, facet, gaps):
    """:func:`direct_irradiance` at a vertex whose ``gaps``
    (:func:`~eyelume.kernels.geometry.free_cone_gaps`) are known: each shadow ray skips the
    surfaces out of its reach (:func:`~eyelume.kernels.geometry.occluded_within`). The same
    value, bit for bit."""
    x, y, z, nx, ny, nz = facet
    e = 0.0
    for k in range(leds.points.shape[0]):
        vx, vy, vz = leds.points[k, 0] - x, leds.points[k, 1] - y, leds.points[k, 2] - z
        d2 = vx * vx + vy * vy + vz * vz
        d = math.sqrt(d2)
        ux, uy, uz = vx / d, vy / d, vz / d
        cos_s = ux * nx + uy * ny + uz * nz
        if cos_s <= 0.0:
            continue
        if led_cos_alpha(leds, k, -ux, -uy, -uz) <= 0.0:
            continue
        t_max = d * (1.0 - 1e-9) - 1e-6
        if G.occluded_within(surfaces.sf, surfaces.si, x, y, z, ux, uy, uz, t_max, gaps, cos_s):
            continue
        e += radiant_intensity(leds, k, -ux, -uy, -uz) * cos_s / d2
    return e


@per_ray
def _is_element(cam, s):
    """Whether surface row ``s`` belongs to an optical element (they come last in the table)."""
    return cam.element_rows.shape[0] > 0 and s >= cam.element_rows[0]


@per_ray
def led_through_elements(surfaces, cam, s, leds, k, rc):
    """Irradiance (W/mm²) at receiver ``rc`` (a :class:`~.cornea_nee.Receiver`) on surface
    ``s`` (−1: none, the eye plane) from LED k through each of its element chains
    (``cam.chains``, :mod:`.cornea_nee`): the element's own chain, or on a surface seen through
    the cornea (the iris) the element's and then the cornea's."""
    e = 0.0
    iris = s >= 0 and cam.through_cornea[s] != 0
    for c in range(cam.chains.shape[1]):
        row = cam.chains[k, c]
        n = row[1] if iris else row[0]
        if n == 0:
            continue
        chain = chain_row(row, n)
        plane = straight_plane(leds, k, chain, surfaces, rc)
        e += led_through_chain(surfaces, chain, plane, s, leds, k, rc)
    return e


@per_ray
def _connects(surfaces, cam, s, leds, k, row, n, facet):
    """Whether next-event estimation at ``facet`` (its normal toward the light's side) on
    surface ``s`` finds LED k's path through the first ``n`` steps of chain ``row`` (and it
    carries light): exactly the light paths that are then the camera paths' — a light path
    that followed the chain to a face ends there only if so, so a root Newton's method misses
    (a start that misses the element near its edge) stays the light paths', never lost."""
    x, y, z, nx, ny, nz = facet
    e1, e2 = orthonormal_basis(nx, ny, nz)
    rc = Receiver(x, y, z, nx, ny, nz, e1, e2)
    chain = chain_row(row, n)
    plane = straight_plane(leds, k, chain, surfaces, rc)
    return led_through_chain(surfaces, chain, plane, s, leds, k, rc) > 0.0


@per_ray
def _element_nee(state, surfaces, cam, s, leds, facet, every_led):
    """Next-event estimation through the elements at a Lambertian vertex (``facet``, its
    normal toward the arriving path) on surface ``s`` (−1: the eye plane): from every LED
    (``every_led``) or from one drawn uniformly beside the stream ``state`` (× the LED count).
    W/mm²."""
    x, y, z, nx, ny, nz = facet
    e1, e2 = orthonormal_basis(nx, ny, nz)
    rc = Receiver(x, y, z, nx, ny, nz, e1, e2)
    n_leds = leds.points.shape[0]
    if every_led:
        e = 0.0
        for k in range(n_leds):
            e += led_through_elements(surfaces, cam, s, leds, k, rc)
        return e
    k = min(int(side_uniform(state, _CHAIN_TAG) * n_leds), n_leds - 1)
    return n_leds * led_through_elements(surfaces, cam, s, leds, k, rc)


@njit(cache=True, inline="always")
def _specular(state, f, dx, dy, dz, nx, ny, nz):
    """Analog choice at a refracting interface ``f`` (:func:`interface_at`), as in the forward
    tracer: total internal reflection, else reflect (R), absorb (A) or transmit. Returns a
    :class:`Specular`."""
    state, u = next_uniform(state)
    ok, tx, ty, tz = refract(dx, dy, dz, nx, ny, nz, f.n1 / f.n2)
    if not ok:
        rx, ry, rz = reflect(dx, dy, dz, nx, ny, nz)
        return Specular(state, True, False, rx, ry, rz)
    if u < f.reflectance:
        rx, ry, rz = reflect(dx, dy, dz, nx, ny, nz)
        return Specular(state, True, False, rx, ry, rz)
    if u < f.reflectance + f.absorptance:
        return Specular(state, False, False, dx, dy, dz)
    return Specular(state, True, True, tx, ty, tz)


@njit(cache=True, inline="always")
def _glint_choice(state, f, dx, dy, dz, nx, ny, nz):
    """A choice at a refracting interface ``f`` that reflects with probability 1/2, returning
    (:class:`Specular`, weight factor): reflected, weight 2R; else absorbed or transmitted in
    proportion A : T, transmitted with weight 2 (T + A); total internal reflection, weight 1.
    Unbiased: each outcome's weight × its probability is its R, T or A."""
    ok, tx, ty, tz = refract(dx, dy, dz, nx, ny, nz, f.n1 / f.n2)
    rx, ry, rz = reflect(dx, dy, dz, nx, ny, nz)
    if not ok:
        return Specular(state, True, False, rx, ry, rz), 1.0
    state, u = next_uniform(state)
    if u < 0.5:
        return Specular(state, True, False, rx, ry, rz), 2.0 * f.reflectance
    rest = 1.0 - f.reflectance
    if rest <= 0.0:
        return Specular(state, False, False, dx, dy, dz), 0.0
    if (u - 0.5) * 2.0 * rest < f.absorptance:
        return Specular(state, False, False, dx, dy, dz), 0.0
    return Specular(state, True, True, tx, ty, tz), 2.0 * rest


@per_ray
def _camera_branch(state, scene, cam, ray, beta, split, first_vertex, scratch, cos0):  # noqa: PLR0913
    """Follow one camera path along ``ray`` with throughput ``beta``.

    With ``split``, the first refracting interface of the eye met before any Lambertian
    vertex is not chosen between by chance: the path goes on transmitted (× T) and the
    reflected part (× R) is handed back to be followed next. Each optical element's surface
    met before it is split too: the path goes on along its stronger part (× R or × T) and the
    weaker one is pushed on ``scratch`` (:class:`Scratch`, while it has room; else the
    surface is chosen between by chance). A choice by chance there was nearly all of
    paper2005-integrated's noise: the hot mirror's 8 % transmission and the eyepiece's two
    0.5 % reflections see nothing lit, so a sample was 0 or 1/0.92 of its mean — a relative
    standard deviation of √(0.08/0.92 + 2 × 0.005/0.995) ≈ 31 % per sample in its median skin
    pixel (measured 32.8 %, camera paths alone, 128 samples per pixel), against 1.8 % with the
    surfaces made ideal (R or T = 1) and 1.8 % split; to 1 % it took 800 samples per pixel, 8
    split (benchmarks/integrated.py). Later interfaces, and those of the
    paths followed without ``split``, are chosen between by chance (R, A, T). With
    ``first_vertex`` the path stops after the NEE at its first Lambertian vertex and hands
    that vertex back for its continuation; otherwise every vertex continues by Russian
    roulette. ``cos0`` > −2: the ray leaves a vertex whose ``scratch.gaps`` are set, at polar
    cosine ``cos0`` about its normal, and its first search skips what it cannot reach
    (:func:`~eyelume.kernels.geometry.nearest_hit_within`: the same hit). Returns a
    :class:`CameraPath`."""
    sf, si = scene.surfaces.sf, scene.surfaces.si
    leds = scene.leds
    x, y, z, dx, dy, dz = ray
    radiance = 0.0
    branch = Branch(Ray(0.0, 0.0, 0.0, 0.0, 0.0, 0.0), 0.0)
    has_branch = False
    s0 = 0.0
    for event in range(scene.max_events):
        # a camera path's searches pass over the dark tail unless a lit row is met (the
        # same light: a ray that meets only the dark rows ends with nothing, as one that
        # meets nothing does)
        if event == 0 and cos0 > -2.0:
            s, t = G.nearest_lit_hit_within(
                sf, si, x, y, z, dx, dy, dz, scratch.gaps, cos0, cam.dark_from
            )
        else:
            s, t = G.nearest_lit_hit(sf, si, x, y, z, dx, dy, dz, cam.dark_from)
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
                # the vertex's reach, for its shadow rays and its continuation's first search
                s0 = G.free_cone_gaps(sf, si, s, x, y, z, nx, ny, nz, scratch.gaps)
                facet = Facet(x, y, z, nx, ny, nz)
                e = direct_irradiance_within(scene.surfaces, leds, facet, scratch.gaps)
            else:
                facet = Facet(x, y, z, nx, ny, nz)
                state, e = sampled_irradiance(state, scene.surfaces, leds, facet, scratch.e_led)
            if cam.through_cornea[s]:
                e1, e2 = orthonormal_basis(nx, ny, nz)
                rc = Receiver(x, y, z, nx, ny, nz, e1, e2)
                if first_vertex:
                    e += irradiance_through_cornea(scene.surfaces, cam.cornea, s, leds, rc)
                else:
                    # later vertices (a continuation ray the cornea sent back onto the
                    # iris): one LED, drawn uniformly beside the stream, × the LED count
                    n_leds = leds.points.shape[0]
                    k = min(int(side_uniform(state, _CORNEA_TAG) * n_leds), n_leds - 1)
                    e += n_leds * led_through_cornea(scene.surfaces, cam.cornea, s, leds, k, rc)
            if cam.chains.shape[1] > 0:
                facet = Facet(x, y, z, nx, ny, nz)
                e += _element_nee(state, scene.surfaces, cam, s, leds, facet, first_vertex)
            radiance += beta * rho * _INV_PI * e
            if first_vertex:
                vertex = Vertex(s, x, y, z, nx, ny, nz, beta * rho, s0)
                return CameraPath(state, radiance, has_branch, branch, vertex)
            state, u = next_uniform(state)
            if u >= rho:
                break
            state, u1 = next_uniform(state)
            state, u2 = next_uniform(state)
            lx, ly, lz = cosine_hemisphere(u1, u2)
            dx, dy, dz = about_axis(lx, ly, lz, nx, ny, nz)
        else:
            f = interface_at(sf, si, s, cos_d)
            n_extra = scratch.count[0]
            if split and _is_element(cam, s) and n_extra < ELEMENT_BRANCHES:
                ok, tx, ty, tz = refract(dx, dy, dz, nx, ny, nz, f.n1 / f.n2)
                rx, ry, rz = reflect(dx, dy, dz, nx, ny, nz)
                if not ok:  # total internal reflection: nothing to split
                    dx, dy, dz = rx, ry, rz
                else:
                    tau = 1.0 - f.reflectance - f.absorptance
                    beta_r = beta * f.reflectance
                    beta_t = beta * tau * (f.n1 / f.n2) ** 2  # radiance / n² is conserved
                    if f.reflectance >= tau:  # on along the stronger part, the other kept
                        beta, dx, dy, dz = beta_r, rx, ry, rz
                        weak, wx, wy, wz = beta_t, tx, ty, tz
                    else:
                        beta, dx, dy, dz = beta_t, tx, ty, tz
                        weak, wx, wy, wz = beta_r, rx, ry, rz
                    if weak > 0.0:
                        row = scratch.rays[n_extra]
                        row[0], row[1], row[2] = x, y, z
                        row[3], row[4], row[5], row[6] = wx, wy, wz, weak
                        scratch.count[0] = n_extra + 1
                    if beta <= 0.0:
                        break
            elif split and not has_branch and not _is_element(cam, s):
                ok, tx, ty, tz = refract(dx, dy, dz, nx, ny, nz, f.n1 / f.n2)
                rx, ry, rz = reflect(dx, dy, dz, nx, ny, nz)
                if not ok:  # total internal reflection: nothing to split
                    dx, dy, dz = rx, ry, rz
                else:
                    has_branch = True
                    branch = Branch(Ray(x, y, z, rx, ry, rz), beta * f.reflectance)
                    # radiance / n² is what refraction conserves
                    beta *= (1.0 - f.reflectance - f.absorptance) * (f.n1 / f.n2) ** 2
                    dx, dy, dz = tx, ty, tz
            else:
                c = _specular(state, f, dx, dy, dz, nx, ny, nz)
                state, dx, dy, dz = c.state, c.dx, c.dy, c.dz
                if not c.alive:
                    break
                if c.transmitted:
                    beta *= (f.n1 / f.n2) ** 2
        inv = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
        dx *= inv
        dy *= inv
        dz *= inv
    vertex = Vertex(-1, x, y, z, 0.0, 0.0, 1.0, 0.0, 0.0)
    return CameraPath(state, radiance, has_branch, branch, vertex)


# IRIS_GRID (kernels/tables.py, so that compile reads it without importing an estimator):
# the continuation grid on the surfaces lit through the cornea (the iris, whose light is
# mostly the face's, reflected: it is shadowed by the cornea, the skin around it is not; 8
# unstratified rays before the grid) when the scene does not give one: the camera path's own
# grid there is ``run.iris_continuation_grid``, by default the others' but at least this
# (:func:`eyelume.compile` sets ``cam.iris_grid``), and the branches followed in one direction
# (the cornea's reflection, an element's weaker part) take this one on the iris. On
# vr-offaxis the light through the cornea is most of an iris pixel's and the continuation
# ~2.5 % of the median iris pixel's camera-path light, yet all of its sample-to-sample noise
# and ~57 % of its cost with 16 rays of ~1.3 µs out through the cornea (24ba11f): the preset
# takes 2 (4 rays; README, issue 11). On the other faces the grid is ``run.continuation_grid``:
# a skin pixel's direct light (NEE to every LED) hardly varies between samples, the light the
# faces send each other (~8 % of a vr-offaxis skin pixel) does, and it is cheap to sample again
# from the same vertex: on vr-offaxis (100 × 100 of 12 µm pixels, 8 sets of 2 × 2 samples) one
# continuation ray (and a uniformly drawn LED at later vertices) gave a per-sample relative
# standard deviation of 20.6 % in the median skin pixel at 102 k samples per CPU-second, 16
# stratified ones (and :func:`sampled_irradiance`) 3.6 % at 49 k: 15 × the efficiency.


@per_ray
def _path_radiance(state, scene, cam, ray, beta, split, grid, iris_grid, scratch, at):  # noqa: PLR0913
    """A camera path with its first Lambertian vertex's continuation(s) in ``grid``² strata,
    ``iris_grid``² on the surfaces lit through the cornea; see _camera_branch. ``at`` (u, v):
    the sample's point on the picture, in pixels (u < 0: none): with an irradiance cache
    (``cam.indirect``) the first vertex's indirect light is read from it there
    (:func:`_cached_indirect`) when it can be, instead of continuing. Returns (state,
    radiance, has_branch, branch)."""
    out = _camera_branch(state, scene, cam, ray, beta, split, True, scratch, -3.0)
    state, radiance = out.state, out.radiance
    v = out.vertex
    if v.s >= 0 and at[0] >= 0.0 and cam.indirect_spacing > 0.0:
        found, value = _cached_indirect(cam, at[0], at[1], v)
        if found:
            return state, radiance + v.beta * value, out.has_branch, out.branch
    if v.s >= 0:
        g = iris_grid if cam.through_cornea[v.s] else grid
        k = g * g
        # the directions within θ₀ of the normal meet nothing that sends light (free_cone):
        # sample only sin²θ ∈ [s0, 1] (cosine-weighted there), × its share 1 − s0
        s0 = v.s0
        share = 1.0 - s0
        if share <= 0.0:
            k = 0
        for j in range(k):
            state, u1 = next_uniform(state)
            state, u2 = next_uniform(state)
            # stratum j: ring j // g of equal area, sector j % g (Malley: r = √u1, φ = 2π u2)
            lx, ly, lz = cosine_hemisphere(s0 + share * (j // g + u1) / g, (j % g + u2) / g)
            ex, ey, ez = about_axis(lx, ly, lz, v.nx, v.ny, v.nz)
            b = v.beta * share / k
            cont = Ray(v.x, v.y, v.z, ex, ey, ez)
            more = _camera_branch(state, scene, cam, cont, b, False, False, scratch, lz)
            state = more.state
            radiance += more.radiance
    return state, radiance, out.has_branch, out.branch


@per_ray
def _camera_radiance(state, scene, cam, ray, scratch, at):
    """Radiance (W/(mm²·sr)) arriving at the lens along −d from the origin of ``ray``, the
    camera sample at picture point ``at`` (u, v) pixels (for the irradiance cache, read by the
    main path's first vertex only; u < 0: none).

    At a Lambertian vertex on a surface with ``cam.through_cornea[s]`` (the iris), the light
    refracted by the cornea (surfaces ``cam.cornea``, ``cam.cornea + 1``) is added by a
    specular connection (:mod:`.cornea_nee`); the light paths skip exactly those paths. The
    camera path is split at the first interface it meets (the cornea's 2.4 % reflection would
    otherwise be a rare, bright event in every pupil and iris pixel), and at each optical
    element's surface before it (:func:`_camera_branch`); ``scratch``: :class:`Scratch`."""
    scratch.count[0] = 0
    state, radiance, has_branch, branch = _path_radiance(
        state, scene, cam, ray, 1.0, True, cam.split_grid, cam.iris_grid, scratch, at
    )
    if has_branch and branch.beta > 0.0:
        # the reflected branch (beta = R, ~2 %) continues in one direction, not g²
        state, more, _, _ = _path_radiance(
            state, scene, cam, branch.ray, branch.beta, False, 1, IRIS_GRID, scratch, _NOWHERE
        )
        radiance += more
    # the elements' weaker parts (none without elements: the same stream as before), in one
    # direction each and unsplit, so they push nothing more
    for b in range(scratch.count[0]):
        row = scratch.rays[b]
        weak = Ray(row[0], row[1], row[2], row[3], row[4], row[5])
        state, more, _, _ = _path_radiance(
            state, scene, cam, weak, row[6], False, 1, IRIS_GRID, scratch, _NOWHERE
        )
        radiance += more
    return state, radiance


@per_ray
def _cached_indirect(cam, u, v, vertex):
    """The irradiance cache's estimate of a first vertex's indirect radiance per unit
    throughput (W/(mm²·sr)): the four cache points about picture point (u, v) (pixels),
    weighted bilinearly in the picture, each read only if it lies on the vertex's surface,
    within its reach (its column 9, mm) of it and its normal within :data:`CACHE_MIN_COS` of the
    vertex's — an edge, a fold, a lash or a depth step in between rejects it. Returns (found,
    value); found False (every point rejected, or the vertex on a surface the cache leaves to
    paths): the caller continues by paths, as without a cache."""
    tab = cam.indirect
    ny, nx = tab.shape[0], tab.shape[1]
    if ny < 2 or nx < 2:
        return False, 0.0
    a = u / cam.indirect_spacing
    b = v / cam.indirect_spacing
    i0 = min(max(int(math.floor(a)), 0), nx - 2)
    j0 = min(max(int(math.floor(b)), 0), ny - 2)
    fa = min(max(a - i0, 0.0), 1.0)
    fb = min(max(b - j0, 0.0), 1.0)
    w_sum = 0.0
    acc = 0.0
    for c in range(4):
        di, dj = c & 1, c >> 1
        p = tab[j0 + dj, i0 + di]
        if int(p[7]) != vertex.s:
            continue
        if p[3] * vertex.nx + p[4] * vertex.ny + p[5] * vertex.nz < CACHE_MIN_COS:
            continue
        ex, ey, ez = p[0] - vertex.x, p[1] - vertex.y, p[2] - vertex.z
        if ex * ex + ey * ey + ez * ez > p[9] * p[9]:
            continue
        w = (fa if di else 1.0 - fa) * (fb if dj else 1.0 - fb)
        w_sum += w
        acc += w * p[6]
    if w_sum <= 0.0:
        return False, 0.0
    return True, acc / w_sum


@njit(cache=True)
def indirect_cache(seed, scene, cam, spacing, grid, out):
    """Fill ``out`` (ny, nx, INDIRECT_COLS; :class:`~eyelume.kernels.tables.CameraTables`'s
    ``indirect``) with the irradiance cache's points: point (j, i) at picture point
    (i × ``spacing``, j × ``spacing``) pixels, where the chief ray (the stop's centre)
    transmitted by the eye's interfaces meets its first Lambertian face, and there the mean
    radiance arriving over the hemisphere, cosine-weighted — the indirect light a camera
    path's continuation estimates, per unit throughput, E_ind/π — from ``grid``² stratified
    continuation rays (outside the vertex's free cone, as :func:`_path_radiance`), and a
    conservative estimate of its variance from pairs of neighbouring strata. Surface −1 where
    the ray meets no Lambertian face or meets one lit through the cornea (the iris keeps its
    paths). A point's rays depend on its index and ``seed`` only (threads change nothing)."""
    _indirect_cache(seed, *scene_parts(scene), cam, spacing, grid, out)


@njit(cache=True, parallel=True)
def _indirect_cache(  # noqa: PLR0913 - the scene's parts as arguments (numba#10139)
    seed, surfaces, lens, leds, picture, eye_plane, max_events, camera, spacing, grid, out
):
    """:func:`indirect_cache` with the scene's parts (:func:`scene_parts`, numba#10139)."""
    ny, nx = out.shape[0], out.shape[1]
    cseed = mix64(np.uint64(seed) ^ np.uint64(_CACHE_TAG))
    for p in prange(ny * nx):
        tables = SceneTables(surfaces, lens, leds, picture, eye_plane, max_events)
        scratch = Scratch(
            np.empty(leds.points.shape[0]),
            np.empty((ELEMENT_BRANCHES, 7)),
            np.zeros(1, dtype=np.int64),
            np.empty(surfaces.sf.shape[0]),
        )
        j = p // nx
        _cache_point(stream_start(cseed, p), tables, camera, spacing, grid, p - j * nx, j,
                     scratch, out[j, p - j * nx])  # fmt: skip


@per_ray
def _cache_point(state, tables, camera, spacing, grid, i, j, scratch, row):  # noqa: PLR0913
    """Cache point (j, i) of :func:`indirect_cache` into ``row`` (INDIRECT_COLS,)."""
    for c in range(row.shape[0]):
        row[c] = 0.0
    row[7] = -1.0
    xs, ys = from_grid(tables.picture, i * spacing, j * spacing)
    chief = aim_chief(camera, xs, ys)
    if not chief.found:
        return
    ok, x, y, z, dx, dy, dz, _ = into_scene(camera, xs, ys, chief.qx, chief.qy)
    if not ok:
        return
    scratch.count[0] = 0
    out = _camera_branch(state, tables, camera, Ray(x, y, z, dx, dy, dz), 1.0, True, True,
                         scratch, -3.0)  # fmt: skip
    state = out.state
    v = out.vertex
    if v.s < 0 or camera.through_cornea[v.s]:
        return
    s0 = v.s0
    share = 1.0 - s0
    k = grid * grid
    total = 0.0
    pairs = 0.0
    last = 0.0
    if share > 0.0:
        for q in range(k):
            state, u1 = next_uniform(state)
            state, u2 = next_uniform(state)
            lx, ly, lz = cosine_hemisphere(s0 + share * (q // grid + u1) / grid,
                                           (q % grid + u2) / grid)  # fmt: skip
            ex, ey, ez = about_axis(lx, ly, lz, v.nx, v.ny, v.nz)
            cont = Ray(v.x, v.y, v.z, ex, ey, ez)
            more = _camera_branch(state, tables, camera, cont, 1.0, False, False, scratch, lz)
            state = more.state
            total += more.radiance
            if q & 1:
                pairs += (more.radiance - last) ** 2
            last = more.radiance
    row[0], row[1], row[2] = v.x, v.y, v.z
    row[3], row[4], row[5] = v.nx, v.ny, v.nz
    row[6] = share * total / k
    row[7] = v.s
    # the strata paired (0, 1), (2, 3), …: Var(Σ y) ≈ Σ (y_a − y_b)², conservative for
    # stratified draws (an odd k's last stratum in proportion); × (share / k)² for the mean
    if k >= 2:
        row[8] = pairs * k / (2 * (k // 2)) * (share / k) ** 2


@njit(cache=True)
def camera_pass(seed, first_set, n_sets, scene, cam, grid, sums):
    """Add stratified sample sets ``first_set`` … ``first_set + n_sets − 1`` of each pixel in
    ``sums.pixels`` (a :class:`CameraSums`; flat indices, row × cols + col): ``sums.total[i]``
    += Σ m, ``sums.squares[i]`` += Σ m² over the sets, m the mean of a set's grid² samples. A
    pixel's samples depend on its index and the seed only. ``scene`` is the compiled scene's
    :class:`~eyelume.kernels.tables.SceneTables`, ``cam`` its
    :class:`~eyelume.kernels.tables.CameraTables`.

    A set stratifies the stop in ``grid`` equal-area rings × ``grid`` sectors and the pixel in a
    grid × grid array of cells, paired with the stop's strata by a random odd stride.

    A sample is a uniform point of the pixel and a uniform point of the stop joined by the real
    ray (:func:`~.camera.aim_into_scene`); its value c = A_stop cos²θ / (d² |det J|) · L, L the
    radiance the lens receives along that ray, is an unbiased estimate of the pixel's mean
    irradiance (W/mm²); so is m, and the sets are independent, so their spread gives the variance.
    """
    _camera_pass(seed, first_set, n_sets, *scene_parts(scene), cam, grid, sums)


@njit(cache=True, parallel=True)
def _camera_pass(  # noqa: PLR0913 - the scene's parts as arguments (numba#10139)
    seed,
    first_set,
    n_sets,
    surfaces,
    lens,
    leds,
    picture,
    eye_plane,
    max_events,
    camera,
    grid,
    sums,
):
    """:func:`camera_pass` with the scene's parts (:func:`scene_parts`, numba#10139)."""
    pixels, out_sum, out_sq = sums
    cols = picture.cols
    stop_r = camera.stop_radius
    cam_z, rear_z, xp_z = camera.image_z, camera.rear_z, camera.exit_pupil_z
    area = math.pi * stop_r * stop_r
    for i in prange(pixels.shape[0]):
        tables = SceneTables(surfaces, lens, leds, picture, eye_plane, max_events)
        p = pixels[i]
        row = p // cols
        col = p - row * cols
        # the chief ray of the pixel centre and its Jacobian seed every sample's aim
        xc, yc = from_grid(tables.picture, col + 0.5, row + 0.5)
        chief = aim_chief(camera, xc, yc)
        if not chief.found:
            continue
        a = chief.jac
        adet = a.a11 * a.a22 - a.a12 * a.a21
        shift = 1.0 - (cam_z - rear_z) / (cam_z - xp_z)
        pseed = mix64(mix64(np.uint64(seed)) + np.uint64(p))
        scratch = Scratch(  # per pixel
            np.empty(leds.points.shape[0]),
            np.empty((ELEMENT_BRANCHES, 7)),
            np.zeros(1, dtype=np.int64),
            np.empty(surfaces.sf.shape[0]),
        )
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
                pu = col + (cell % grid + u1) / grid
                pv = row + (cell // grid + u2) / grid
                xs, ys = from_grid(tables.picture, pu, pv)
                tx, ty = disk_stratum(k, grid, u3, u4, stop_r)
                # first guess: the chief ray's crossing, moved with the sensor point and the
                # stop point to first order
                gx = chief.qx + shift * (xs - xc) + (a.a22 * tx - a.a12 * ty) / adet
                gy = chief.qy + shift * (ys - yc) + (-a.a21 * tx + a.a11 * ty) / adet
                aim, r = aim_into_scene(camera, xs, ys, tx, ty, gx, gy, a)
                if not (aim.found and r.passed):
                    continue
                state, radiance = _camera_radiance(
                    state, tables, camera, Ray(r.x, r.y, r.z, r.dx, r.dy, r.dz), scratch, (pu, pv)
                )
                total += area * r.g / aim.det * radiance
            mean = total / strata
            # one addition per set, in set order: the sums do not depend on how the sets
            # were split into rounds
            out_sum[i] += mean
            out_sq[i] += mean * mean


@per_ray
def _scatter(state, aim_row, x, y, z, nx, ny, nz):
    """A direction from the aim/cosine mixture about unit normal n
    (:func:`~eyelume.kernels.sampling.aimed_mixture`).

    Returns (state, dx, dy, dz, weight = (cos θ / π) / pdf_mix; 0 when below the face)."""
    state, u0 = next_uniform(state)
    state, u1 = next_uniform(state)
    state, u2 = next_uniform(state)
    dx, dy, dz = aimed_mixture(u0, u1, u2, aim_row, x, y, z, nx, ny, nz)
    cos_n = dx * nx + dy * ny + dz * nz
    if cos_n <= 0.0:
        return state, dx, dy, dz, 0.0
    pdf = aimed_mixture_pdf(aim_row, x, y, z, nx, ny, nz, dx, dy, dz)
    return state, dx, dy, dz, cos_n * _INV_PI / pdf


WEAK_SURVIVAL = 0.125


class CameraSums(NamedTuple):
    """Where :func:`camera_pass` adds: the flat pixel indices it samples and, per index, Σ m
    and Σ m² over its sample sets (W/mm², (W/mm²)²)."""

    pixels: np.ndarray
    total: np.ndarray
    squares: np.ndarray


class Tally(NamedTuple):
    """Where light paths deposit: fixed-point Σc, Σc² (units q, q2 of W/mm² per unit path) per
    pixel, the glint part per LED (n_leds, rows, cols) and the glint part's first moments
    inside its pixel, Σc·s (2, rows, cols; s the point's offset from the pixel's centre in
    pixels, columns then rows; units q); :func:`light_pass` takes one with a leading chunk axis
    on the arrays."""

    img: np.ndarray
    img2: np.ndarray
    led: np.ndarray
    moment: np.ndarray
    q: float
    q2: float


@per_ray
def _step_matches(row, j, s, transmitted, from_b):
    """Whether a specular event (surface s, transmitted or not, arriving from side B or not)
    is step j of chain row ``row`` (``cam.chains``)."""
    if row[2 + j] != s:
        return False
    mode = row[2 + CHAIN_STEPS + j]
    if mode == REFLECT:
        return not transmitted
    if mode == TRANSMIT_A:
        return transmitted and not from_b
    return transmitted


@per_ray
def _track(chains, k, track, s, transmitted, from_b):
    """The next state of a light path's match against LED k's element chains after a
    specular event: ``track`` −2 before its first event, c × 8 + j once the path has followed
    the first j steps of chain c, −1 once it has left every chain."""
    if track == -2:
        for c in range(chains.shape[1]):
            row = chains[k, c]
            if row[1] > 0 and _step_matches(row, 0, s, transmitted, from_b):
                return c * 8 + 1
        return -1
    c, j = track // 8, track % 8
    row = chains[k, c]
    if j < row[1] and _step_matches(row, j, s, transmitted, from_b):
        return track + 1
    return -1


@per_ray
def _follow(state, w, ray, scene, cam, tally, glint, chain, track):  # noqa: PLR0913 - three flags
    """Carry a light path of weight ``w`` (W per unit path) until it ends; deposit at the
    sensor. ``glint`` ≥ 0 while the path has met no Lambertian face (LED index). ``chain`` is 1
    when the path has just been transmitted by the anterior cornea: if it is then transmitted by
    the posterior cornea and meets a ``cam.through_cornea`` surface, the camera paths' specular
    connection has it, and it ends here; −1 when it has just been reflected by the cornea: at
    its first Lambertian face it survives with probability WEAK_SURVIVAL (weight /
    WEAK_SURVIVAL). ``track`` (−1: off; −2 for a path leaving LED ``glint`` toward an element,
    :func:`_track`): a path that has followed one of its LED's element chains (``cam.chains``)
    to its end and then meets a Lambertian face — the element's own chain, any face but the
    iris; with the cornea's steps, the iris — where the camera paths' next-event estimation
    (:func:`led_through_elements`) finds it (:func:`_connects`) is theirs and ends here."""
    sf, si = scene.surfaces.sf, scene.surfaces.si
    x, y, z, dx, dy, dz = ray
    first_diffuse = True
    for _ in range(scene.max_events):
        s, t = G.nearest_hit(sf, si, x, y, z, dx, dy, dz)
        if s < 0:
            return state
        action = si[s, G.ACTION]
        if action == G.ACT_LENS:
            nx, ny, nz = G.surface_normal(sf, si, s, x + t * dx, y + t * dy, z + t * dz)
            if dx * nx + dy * ny + dz * nz < 0.0:
                return state
            status, x, y, z, dx, dy, dz, _, _ = trace_lens(
                scene.lens.lf, x, y, z, dx, dy, dz, None, 0, False
            )
            if status != LENS_PASSED:
                return state
            t = (scene.lens.image_z - z) / dz
            x += t * dx
            y += t * dy
            pic = scene.picture
            u, v = to_grid(pic, x, y)
            col, row = int(math.floor(u)), int(math.floor(v))
            if 0 <= col < pic.cols and 0 <= row < pic.rows:
                # W per unit path → W/mm² in the pixel
                c = w * pic.cols * pic.rows / (pic.width_mm * pic.height_mm)
                tally.img[row, col] += np.int64(c / tally.q + 0.5)
                tally.img2[row, col] += np.int64(c * c / tally.q2 + 0.5)
                if glint >= 0:  # a point's image: where in the pixel it fell (the PSF's)
                    tally.led[glint, row, col] += np.int64(c / tally.q + 0.5)
                    cq = c / tally.q
                    tally.moment[0, row, col] += np.int64(math.floor(cq * (u - col - 0.5) + 0.5))
                    tally.moment[1, row, col] += np.int64(math.floor(cq * (v - row - 0.5) + 0.5))
            return state
        x += t * dx
        y += t * dy
        z += t * dz
        nx, ny, nz = G.surface_normal(sf, si, s, x, y, z)
        cos_d = dx * nx + dy * ny + dz * nz
        from_b = cos_d < 0.0
        if action == G.ACT_OPAQUE:
            if chain == 2 and cam.through_cornea[s]:
                return state
            if track >= 0:
                row = cam.chains[glint, track // 8]
                done = row[1] if cam.through_cornea[s] else row[0]
                if track % 8 == done:
                    m = 1.0 if from_b else -1.0  # the normal toward the side it arrives on
                    facet = Facet(x, y, z, m * nx, m * ny, m * nz)
                    if _connects(scene.surfaces, cam, s, scene.leds, glint, row, done, facet):
                        return state
                track = -1
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
            aim_row = cam.aim[s, 1 if from_b else 0]
            state, dx, dy, dz, f = _scatter(state, aim_row, x, y, z, nx, ny, nz)
            if f <= 0.0:
                return state
            w *= f
        else:
            f = interface_at(sf, si, s, cos_d)
            if glint >= 0 and s == cam.cornea and not from_b and cam.element_rows.shape[0] > 0:
                # a light path from an element meets the cornea unsplit: reflect with
                # probability 1/2 (× 2R), else transmit or absorb (× 2T, 2A): a glint seen
                # through an element is then drawn 1/(2R) ≈ 20 × as often as by chance
                c, gain = _glint_choice(state, f, dx, dy, dz, nx, ny, nz)
                w *= gain
            else:
                c = _specular(state, f, dx, dy, dz, nx, ny, nz)
            state, dx, dy, dz = c.state, c.dx, c.dy, c.dz
            if not c.alive:
                return state
            if track != -1:
                track = _track(cam.chains, glint, track, s, c.transmitted, from_b)
            through = c.transmitted and s == cam.cornea + 1 and not from_b
            chain = 2 if chain == 1 and through else 0
        inv = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
        dx *= inv
        dy *= inv
        dz *= inv
    return state


@per_ray
def _sphere_cone_pdf(centre, rb, ray):
    """Density per steradian of direction (dx, dy, dz) of ``ray`` from its origin P drawn
    uniformly inside the cone that holds the sphere (``centre``, radius rb; the whole sphere
    of directions when P is inside it), as the light paths' legs draw it."""
    px, py, pz, dx, dy, dz = ray
    wx, wy, wz = centre[0] - px, centre[1] - py, centre[2] - pz
    dist = math.sqrt(wx * wx + wy * wy + wz * wz)
    if dist <= rb:
        return 1.0 / (4.0 * math.pi)
    cos_max = math.sqrt(1.0 - rb * rb / (dist * dist))
    return uniform_cone_pdf((dx * wx + dy * wy + dz * wz) / dist, cos_max)


@per_ray
def _cone_pdf(sf, row, ray):
    """:func:`_sphere_cone_pdf` of surface ``row``'s bounding sphere."""
    return _sphere_cone_pdf((sf[row, G.BX], sf[row, G.BY], sf[row, G.BZ]), sf[row, G.BR], ray)


@per_ray
def _mirrored_port(sf, si, row, port, px, py, pz):
    """Where the lens surface ``port``'s bounding-sphere centre appears, seen from the LED at
    P in element surface ``row``: mirrored in the surface's tangent plane at the point the
    LED's reflection toward it leaves from — three fixed-point steps from the vertex plane
    (exact for a plane surface; a deterministic function of P, so a density). (cx, cy, cz)."""
    cx, cy, cz = sf[port, G.BX], sf[port, G.BY], sf[port, G.BZ]
    ox, oy, oz = sf[row, G.OX], sf[row, G.OY], sf[row, G.OZ]
    ax, ay, az = sf[row, G.R20], sf[row, G.R21], sf[row, G.R22]
    for _ in range(3):
        h = (cx - ox) * ax + (cy - oy) * ay + (cz - oz) * az
        mx, my, mz = cx - 2.0 * h * ax - px, cy - 2.0 * h * ay - py, cz - 2.0 * h * az - pz
        d = math.sqrt(mx * mx + my * my + mz * mz)
        if d <= 0.0:
            break
        mx, my, mz = mx / d, my / d, mz / d
        t = G.intersect_surface(sf, si, row, px, py, pz, mx, my, mz, math.inf)
        if t < 0.0:
            break
        ox, oy, oz = px + t * mx, py + t * my, pz + t * mz
        ax, ay, az = G.surface_normal(sf, si, row, ox, oy, oz)
    h = (cx - ox) * ax + (cy - oy) * ay + (cz - oz) * az
    return cx - 2.0 * h * ax, cy - 2.0 * h * ay, cz - 2.0 * h * az


@per_ray
def _mirror_pdf(sf, si, row, port, ray):
    """Density of :func:`_ghost_path`'s directions (the cone about the mirrored pupil)."""
    centre = _mirrored_port(sf, si, row, port, ray.x, ray.y, ray.z)
    return _sphere_cone_pdf(centre, sf[port, G.BR], ray)


@per_ray
def _element_share(sf, si, cam, port, s, k, ray, pdf):
    """The balance-heuristic weight (Veach 1997) of a light path's first leg, drawn with
    density ``pdf``, whose first hit is element surface ``s``: four legs draw such paths —
    the cornea leg, surface s's own leg (:func:`_element_path`), and with a lens (``port`` ≥
    0) the lens leg (:func:`_direct_path`) and s's ghost leg (:func:`_ghost_path`) — and
    each weights them pdf / Σ pdf, so that together they count each path once (the cornea
    leg's density LED k's mixture, :func:`_cornea_leg_pdf`)."""
    total = _cornea_leg_pdf(sf, cam, k, ray) + _cone_pdf(sf, s, ray)
    if port >= 0:
        total += _cone_pdf(sf, port, ray) + _mirror_pdf(sf, si, s, port, ray)
    return pdf / total


@per_ray
def _cornea_leg_pdf(sf, cam, k, ray):
    """Density per steradian of the cornea leg's direction (dx, dy, dz) of ``ray`` from LED k
    (:func:`_light_path`): the mixture (1 − p) U_cornea + p U_glint of the cone that holds the
    anterior cornea's bounding sphere and LED k's glint cone (``cam.glint_aim[k]``, drawn with
    probability p; U uniform in a cone)."""
    a = cam.glint_aim[k]
    pdf = _cone_pdf(sf, cam.cornea, ray)
    p = a[G_P]
    if p <= 0.0:
        return pdf
    cos_t = ray.dx * a[G_AX] + ray.dy * a[G_AY] + ray.dz * a[G_AZ]
    return (1.0 - p) * pdf + p * uniform_cone_pdf(cos_t, a[G_COS])


@per_ray
def _light_path(i, seed, scene, cam, tally, port):
    """Light path ``i``: LED i mod N toward the cornea, split there (see module docstring).

    Its first direction is drawn from a mixture: with probability p = ``cam.glint_aim[k, G_P]``
    uniformly in the small cone about the direction to LED k's glint's specular point (the
    cornea point that reflects it into the entrance pupil: every such draw the cornea reflects
    toward the lens), else uniformly in the cone that holds the anterior cornea's bounding
    sphere; weighted I(α) / pdf_mix (:func:`_cornea_leg_pdf`; one-sample multiple importance
    sampling with the balance heuristic, Veach 1997 §9.2.4), so unbiased wherever the aim is
    off. With p = 0 the draws are the whole-cornea cone's alone, as before."""
    sf, si = scene.surfaces.sf, scene.surfaces.si
    leds = scene.leds
    cornea = cam.cornea
    n_leds = leds.points.shape[0]
    k = i % n_leds
    state = stream_start(seed, i)
    px, py, pz = leds.points[k, 0], leds.points[k, 1], leds.points[k, 2]
    wx, wy, wz = sf[cornea, G.BX] - px, sf[cornea, G.BY] - py, sf[cornea, G.BZ] - pz
    dist = math.sqrt(wx * wx + wy * wy + wz * wz)
    rb = sf[cornea, G.BR]
    cos_max = math.sqrt(1.0 - rb * rb / (dist * dist))
    state, u1 = next_uniform(state)
    state, u2 = next_uniform(state)
    aim = cam.glint_aim[k]
    p_aim = aim[G_P]
    if p_aim <= 0.0:
        lx, ly, lz = uniform_cone(u1, u2, cos_max)
        dx, dy, dz = about_axis(lx, ly, lz, wx / dist, wy / dist, wz / dist)
        # path i serves LED i mod N: a share 1/N of the paths estimates each LED's light;
        # 2π (1 − cos_max) = 1 / uniform_cone_pdf
        w = n_leds * radiant_intensity(leds, k, dx, dy, dz) * 2.0 * math.pi * (1.0 - cos_max)
        pdf = 1.0 / (2.0 * math.pi * (1.0 - cos_max))
    else:
        # the mixture: u1 below p_aim draws in the glint's cone (u1 / p_aim), else in the
        # cornea's ((u1 − p_aim) / (1 − p_aim)); each draw's density in the other cone by its
        # polar cosine there
        pdf_c = 1.0 / (2.0 * math.pi * (1.0 - cos_max))
        pdf_g = 1.0 / (2.0 * math.pi * (1.0 - aim[G_COS]))
        if u1 < p_aim:
            lx, ly, lz = uniform_cone(u1 / p_aim, u2, aim[G_COS])
            dx, dy, dz = about_axis(lx, ly, lz, aim[G_AX], aim[G_AY], aim[G_AZ])
            cos_c = (dx * wx + dy * wy + dz * wz) / dist
            pdf = p_aim * pdf_g + (1.0 - p_aim) * uniform_cone_pdf(cos_c, cos_max)
        else:
            lx, ly, lz = uniform_cone((u1 - p_aim) / (1.0 - p_aim), u2, cos_max)
            dx, dy, dz = about_axis(lx, ly, lz, wx / dist, wy / dist, wz / dist)
            cos_g = dx * aim[G_AX] + dy * aim[G_AY] + dz * aim[G_AZ]
            pdf = (1.0 - p_aim) * pdf_c + p_aim * uniform_cone_pdf(cos_g, aim[G_COS])
        w = n_leds * radiant_intensity(leds, k, dx, dy, dz) / pdf
    if w <= 0.0:
        return
    s, t = G.nearest_hit(sf, si, px, py, pz, dx, dy, dz)
    if s != cornea:
        if s >= 0 and si[s, G.ACTION] == G.ACT_REFRACT and _is_element(cam, s):
            # first hit an element's surface: one of three legs that draw these paths (the
            # glints seen through an element are mostly drawn here, aimed at the cornea)
            w *= _element_share(sf, si, cam, port, s, k, Ray(px, py, pz, dx, dy, dz), pdf)
            _follow(state, w, Ray(px, py, pz, dx, dy, dz), scene, cam, tally, k, 0, -2)
        return  # first hit elsewhere: the camera paths' share (or nothing)
    x, y, z = px + t * dx, py + t * dy, pz + t * dz
    nx, ny, nz = G.surface_normal(sf, si, s, x, y, z)
    cos_d = dx * nx + dy * ny + dz * nz
    if cos_d <= 0.0:
        return
    f = interface_at(sf, si, s, cos_d)
    _, tx, ty, tz = refract(dx, dy, dz, nx, ny, nz, f.n1 / f.n2)
    rx, ry, rz = reflect(dx, dy, dz, nx, ny, nz)
    r = f.reflectance
    state = _follow(state, w * r, Ray(x, y, z, rx, ry, rz), scene, cam, tally, k, -1, -1)
    tau = 1.0 - r - f.absorptance
    _follow(state, w * tau, Ray(x, y, z, tx, ty, tz), scene, cam, tally, k, 1, -1)


@per_ray
def _direct_path(i, seed, scene, cam, tally, port):
    """Light path ``i``'s second leg: LED i mod N straight into the lens (its first surface,
    table row ``port``), the light of an LED the camera sees directly (a wide lens beside the
    LED ring). Uniform inside the cone that holds the lens surface's bounding sphere (the whole
    sphere of directions if the LED is inside it), weighted I(α)/pdf like the cornea leg; it
    counts only when the lens is the first thing it meets, so it shares no path with the cornea
    leg or the camera paths — or an optical element's surface (the LED seen through a window
    or by a mirror), weighted then by :func:`_element_share`. Its own random stream, so the
    other legs' numbers do not change; an LED that sends nothing toward the lens (I(α) = 0,
    the paper's ring) costs one profile evaluation."""
    sf, si = scene.surfaces.sf, scene.surfaces.si
    leds = scene.leds
    n_leds = leds.points.shape[0]
    k = i % n_leds
    px, py, pz = leds.points[k, 0], leds.points[k, 1], leds.points[k, 2]
    wx, wy, wz = sf[port, G.BX] - px, sf[port, G.BY] - py, sf[port, G.BZ] - pz
    dist = math.sqrt(wx * wx + wy * wy + wz * wz)
    rb = sf[port, G.BR]
    cos_max = math.sqrt(1.0 - rb * rb / (dist * dist)) if dist > rb else -1.0
    state = stream_start(seed, i)
    state, u1 = next_uniform(state)
    state, u2 = next_uniform(state)
    lx, ly, lz = uniform_cone(u1, u2, cos_max)
    if dist > 0.0:
        dx, dy, dz = about_axis(lx, ly, lz, wx / dist, wy / dist, wz / dist)
    else:
        dx, dy, dz = lx, ly, lz
    w = n_leds * radiant_intensity(leds, k, dx, dy, dz) * 2.0 * math.pi * (1.0 - cos_max)
    if w <= 0.0:
        return
    s, _ = G.nearest_hit(sf, si, px, py, pz, dx, dy, dz)
    if s >= 0 and s != port and si[s, G.ACTION] == G.ACT_REFRACT and _is_element(cam, s):
        # an element in the way: the LED seen through it or by it (one of three legs)
        pdf = _cone_pdf(sf, port, Ray(px, py, pz, dx, dy, dz))
        w *= _element_share(sf, si, cam, port, s, k, Ray(px, py, pz, dx, dy, dz), pdf)
        _follow(state, w, Ray(px, py, pz, dx, dy, dz), scene, cam, tally, k, 0, -2)
        return
    if s != port:
        return
    _follow(state, w, Ray(px, py, pz, dx, dy, dz), scene, cam, tally, -1, 0, -1)


@per_ray
def _element_path(i, seed, scene, cam, tally, row, port):
    """Light path ``i``'s leg toward element surface ``row``: LED i mod N uniformly inside the
    cone that holds the surface's bounding sphere (all directions if the LED is inside it),
    weighted I(α)/pdf, counted only when that surface is the first thing it meets — so the legs
    of the surfaces, the lens leg and the camera paths' straight next-event estimation share
    no path; the cornea leg's and the lens leg's draws that meet the surface first count too,
    all weighted by the balance heuristic (:func:`_element_share`). It then goes on like any
    light path (:func:`_follow`), the glints and ghosts seen through or by the elements among
    them, except what the camera paths' connections through an element take (its ``track``).
    Its own random stream per surface."""
    sf, si = scene.surfaces.sf, scene.surfaces.si
    leds = scene.leds
    n_leds = leds.points.shape[0]
    k = i % n_leds
    px, py, pz = leds.points[k, 0], leds.points[k, 1], leds.points[k, 2]
    wx, wy, wz = sf[row, G.BX] - px, sf[row, G.BY] - py, sf[row, G.BZ] - pz
    dist = math.sqrt(wx * wx + wy * wy + wz * wz)
    rb = sf[row, G.BR]
    cos_max = math.sqrt(1.0 - rb * rb / (dist * dist)) if dist > rb else -1.0
    state = stream_start(seed, i)
    state, u1 = next_uniform(state)
    state, u2 = next_uniform(state)
    lx, ly, lz = uniform_cone(u1, u2, cos_max)
    if dist > 0.0:
        dx, dy, dz = about_axis(lx, ly, lz, wx / dist, wy / dist, wz / dist)
    else:
        dx, dy, dz = lx, ly, lz
    w = n_leds * radiant_intensity(leds, k, dx, dy, dz) * 2.0 * math.pi * (1.0 - cos_max)
    if w <= 0.0:
        return
    s, _ = G.nearest_hit(sf, si, px, py, pz, dx, dy, dz)
    if s != row:
        return
    pdf = _cone_pdf(sf, row, Ray(px, py, pz, dx, dy, dz))
    w *= _element_share(sf, si, cam, port, row, k, Ray(px, py, pz, dx, dy, dz), pdf)
    _follow(state, w, Ray(px, py, pz, dx, dy, dz), scene, cam, tally, k, 0, -2)


@per_ray
def _ghost_path(i, seed, scene, cam, tally, row, port):
    """Light path ``i``'s leg toward the camera's pupil mirrored in element surface ``row``
    (:func:`_mirrored_port`): the ghosts (LED → surface → lens) and, for a mirror, the LED
    seen by it, which the surface's own leg draws rarely (its cone holds the whole element).
    Uniform inside the cone of the mirrored lens surface's bounding sphere, weighted I(α)/pdf
    and by :func:`_element_share`, counted only when ``row`` is the first thing it meets. Its
    own random stream per surface."""
    sf, si = scene.surfaces.sf, scene.surfaces.si
    leds = scene.leds
    n_leds = leds.points.shape[0]
    k = i % n_leds
    px, py, pz = leds.points[k, 0], leds.points[k, 1], leds.points[k, 2]
    cx, cy, cz = _mirrored_port(sf, si, row, port, px, py, pz)
    wx, wy, wz = cx - px, cy - py, cz - pz
    dist = math.sqrt(wx * wx + wy * wy + wz * wz)
    rb = sf[port, G.BR]
    cos_max = math.sqrt(1.0 - rb * rb / (dist * dist)) if dist > rb else -1.0
    state = stream_start(seed, i)
    state, u1 = next_uniform(state)
    state, u2 = next_uniform(state)
    lx, ly, lz = uniform_cone(u1, u2, cos_max)
    if dist > 0.0:
        dx, dy, dz = about_axis(lx, ly, lz, wx / dist, wy / dist, wz / dist)
    else:
        dx, dy, dz = lx, ly, lz
    w = n_leds * radiant_intensity(leds, k, dx, dy, dz)
    if w <= 0.0:
        return
    s, _ = G.nearest_hit(sf, si, px, py, pz, dx, dy, dz)
    if s != row:
        return
    pdf = _mirror_pdf(sf, si, row, port, Ray(px, py, pz, dx, dy, dz))
    w *= _element_share(sf, si, cam, port, row, k, Ray(px, py, pz, dx, dy, dz), pdf) / pdf
    _follow(state, w, Ray(px, py, pz, dx, dy, dz), scene, cam, tally, k, 0, -2)


@njit(cache=True)
def light_pass(seed, first, count, scene, cam, sums):
    """Trace light paths ``first`` … ``first + count − 1``; chunk c adds to ``sums``' (a
    :class:`Tally` of (chunks, …) arrays) img[c], img2[c], led[c], moment[c] (fixed-point Σc,
    Σc² and Σc·s in units q, q2 and q of W/mm² per unit path)."""
    _light_pass(seed, first, count, *scene_parts(scene), cam, sums)


@njit(cache=True, parallel=True)
def _light_pass(  # noqa: PLR0913 - the scene's parts as arguments (numba#10139)
    seed, first, count, surfaces, lens, leds, picture, eye_plane, max_events, camera, sums
):
    """:func:`light_pass` with the scene's parts (:func:`scene_parts`, numba#10139)."""
    img, img2, led_img, moment, q, q2 = sums
    n_chunks = img.shape[0]
    lseed = mix64(np.uint64(seed) ^ np.uint64(_LIGHT_TAG))
    dseed = mix64(np.uint64(seed) ^ np.uint64(_DIRECT_TAG))
    port = -1
    for s in range(surfaces.si.shape[0]):
        if surfaces.si[s, G.ACTION] == G.ACT_LENS:
            port = s
    for c in prange(n_chunks):
        tables = SceneTables(surfaces, lens, leds, picture, eye_plane, max_events)
        lo = first + (count * c) // n_chunks
        hi = first + (count * (c + 1)) // n_chunks
        tally = Tally(img[c], img2[c], led_img[c], moment[c], q, q2)
        for i in range(lo, hi):
            _light_path(i, lseed, tables, camera, tally, port)
            if port >= 0:
                _direct_path(i, dseed, tables, camera, tally, port)
            for r in camera.element_rows:
                eseed = mix64(np.uint64(seed) ^ np.uint64(_ELEMENT_TAG + r))
                _element_path(i, eseed, tables, camera, tally, r, port)
                if port >= 0:
                    gseed = mix64(np.uint64(seed) ^ np.uint64(_GHOST_TAG + r))
                    _ghost_path(i, gseed, tables, camera, tally, r, port)


@njit(cache=True)
def primary_surfaces(scene, cam, view, row0, labels, sides):
    """The surface each pixel sees in the ideal image: the chief ray from the pixel centre
    through the stop's centre, refracting at the eye's surfaces (never reflecting) and taking
    at an optical element the camera's view's branch (``view`` (n_surfaces,) int64, the
    compile's ``view_branch``: 1 reflected, a mirror's or a beamsplitter's fold; 0 refracted;
    −1 the stronger part, reflected where R > T; as
    :func:`eyelume.analysis.truth._through_elements`), to the first opaque surface (``labels``;
    −1: nothing, or no chief ray) and the side it meets (``sides``: 1 = side B, the side the
    surface's normal points to). ``labels`` and ``sides`` hold the band of picture rows from
    ``row0`` (so a large sensor is mapped band by band)."""
    _primary_surfaces(scene.surfaces, scene.picture, cam, view, row0, labels, sides)


@njit(cache=True, parallel=True)
def _primary_surfaces(surfaces, picture, camera, view, row0, labels, sides):
    """:func:`primary_surfaces` with the scene's parts it reads (numba#10139)."""
    sf, si = surfaces
    rows, cols = labels.shape
    for p in prange(rows * cols):
        band_row = p // cols
        col = p - band_row * cols
        row = row0 + band_row
        xs, ys = from_grid(picture, col + 0.5, row + 0.5)
        labels[band_row, col] = -1
        chief = aim_chief(camera, xs, ys)
        if not chief.found:
            continue
        ok, x, y, z, dx, dy, dz, _ = into_scene(camera, xs, ys, chief.qx, chief.qy)
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
            f = interface_at(sf, si, s, dx * nx + dy * ny + dz * nz)
            ok, tx, ty, tz = refract(dx, dy, dz, nx, ny, nz, f.n1 / f.n2)
            if _is_element(camera, s) and (
                not ok
                or view[s] == 1
                or (view[s] < 0 and f.reflectance > 1.0 - f.reflectance - f.absorptance)
            ):
                # the view's branch at an element (a mirror's fold), as the truth takes it
                dx, dy, dz = reflect(dx, dy, dz, nx, ny, nz)
                continue
            if not ok:
                break
            dx, dy, dz = tx, ty, tz


@njit(cache=True)
def plane_direct(seed, scene, cam, n_sub, out):
    """Direct LED irradiance (W/mm²) toward the eye on the eye-plane bins (row 0 at +y): the
    mean over n_sub × n_sub jittered points per bin (one uniform point in each cell, so the
    mean is unbiased where an occluder's edge cuts the bin), each lit by the LEDs that see it,
    straight or through an element's chain (``cam``'s, :func:`led_through_elements`)."""
    _plane_direct(seed, scene.surfaces, scene.leds, scene.eye_plane, cam, n_sub, out)


@njit(cache=True, parallel=True)
def _plane_direct(seed, surfaces, leds, g, cam, n_sub, out):
    """:func:`plane_direct` with the scene's parts it reads (numba#10139)."""
    ec = g.cols
    for p in prange(g.rows * ec):
        row = p // ec
        col = p - row * ec
        state = stream_start(mix64(np.uint64(seed) ^ np.uint64(_PLANE_TAG)), p)
        acc = 0.0
        for a in range(n_sub):
            for b in range(n_sub):
                state, u1 = next_uniform(state)
                state, u2 = next_uniform(state)
                x, y = from_grid(g, col + (a + u1) / n_sub, row + (b + u2) / n_sub)
                px, py, pz = plane_point(g, x, y)
                acc += direct_irradiance(surfaces, leds, Facet(px, py, pz, g.nx, g.ny, g.nz))
                if cam.chains.shape[1] > 0:
                    facet = Facet(px, py, pz, g.nx, g.ny, g.nz)
                    acc += _element_nee(state, surfaces, cam, -1, leds, facet, True)
        out[row, col] = acc / (n_sub * n_sub)
