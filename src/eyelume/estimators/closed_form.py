"""Closed-form eye-plane irradiance of an LED configuration in free space (paper §4.1.2).

The paper's generator traces "the simple LED–eye plane system": the LEDs and the eye-plane
receiver, nothing else (no eye, no face, no lens). Its irradiance needs no rays. A point source of
radiant intensity I(α) = I₀ f(α) (each LED its own I₀ and f) at the emission point **e** (the
apex of the LED body, ``centre + axis · body_radius``, where the tracers emit) lights a point
**p** of the plane z = 0 with

    E(p) = I₀ f(α) cos β / r²,      r = |p − e|,  cos α = (p − e)·a / r,  cos β = e_z / r,

(a the unit LED axis, β the angle of incidence on the plane, whose normal is +z), and f = 0 behind
the LED (α > 90°) as the tracers emit into the forward hemisphere only. A bin records its mean
irradiance, (1/A) ∫∫_bin Σ_LEDs E dA in W/mm², integrated here by an ``order`` × ``order``
Gauss–Legendre rule per bin and LED (Numba, parallel over configurations and rows).

Accuracy: the integrand is analytic over a bin except where r → 0 or at the LED's horizon, so the
rule converges geometrically at a rate set by (bin size / distance to the source) and, for narrow
beams, by the exponent m. The order is chosen per call (:func:`auto_order`: the smallest of 4, 8,
16, … whose doubling changes no bin of the hardest configuration by more than 1e-9 relative): 4 on
the paper's 21 × 15 bins for every configuration of its grid (Y 20–40, Z 20–70, θ 0–30; doubling
then changes no bin by more than ~1e-10), 16 for a 5° half-angle LED there. A tabulated profile is
piecewise linear in α and a bin across one of its nodes converges only algebraically: such
profiles use order :data:`TABLE_ORDER` = 16 (a few 1e-4 relative for a datasheet-like table; pass a
higher ``order`` if that matters).

Units and frame as everywhere (ARCHITECTURE.md §2): mm, W/sr, W/mm²; LED i at azimuth φ has its body
centre at (Y cos φ, Y sin φ, Z) and its axis (−sin θ cos φ, −sin θ sin φ, −cos θ)
(:func:`eyelume.scene.sources.led_poses`). Row 0 of a plane is at +y, column 0 at −x.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numba import njit, prange

from eyelume.errors import GeometryError
from eyelume.kernels.bins import eye_plane_grid, from_grid
from eyelume.scene.model import EyePlane, LedArray, LedProfile, Scene
from eyelume.scene.sources import (
    bodies_overlap,
    body_support,
    cos_power_exponent,
    led_bodies,
    led_poses,
    read_profile_table,
    ring_basis,
    ring_poses,
)

__all__ = [
    "AUTO_RTOL",
    "TABLE_ORDER",
    "auto_order",
    "bin_irradiance",
    "configuration_irradiance",
    "eye_plane_irradiance",
    "geometry_problem",
    "geometry_problems",
    "led_emitters",
    "plane_edges",
    "product_grid",
    "sweep_irradiance",
]

#: Largest relative change of any bin that :func:`auto_order` accepts when doubling the order.
AUTO_RTOL = 1e-9
#: Gauss–Legendre order for tabulated (piecewise linear) profiles.
TABLE_ORDER = 16

_KIND_COS_POWER = 0
_KIND_TABLE = 1


# --- geometry ------------------------------------------------------------------------------------


def product_grid(
    heights: Sequence[float], distances: Sequence[float], pitches: Sequence[float]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every configuration of the grid heights × distances × pitches, flattened in C order
    (Y slowest, θ fastest): three (n,) float arrays.

    >>> y, z, t = product_grid([20, 25], [30], [0, 5, 10])
    >>> y.tolist(), t.tolist()
    ([20.0, 20.0, 20.0, 25.0, 25.0, 25.0], [0.0, 5.0, 10.0, 0.0, 5.0, 10.0])
    """
    axes = [np.asarray(list(v), dtype=float).ravel() for v in (heights, distances, pitches)]
    grid = np.meshgrid(*axes, indexing="ij")
    return tuple(np.ascontiguousarray(g.ravel()) for g in grid)  # type: ignore[return-value]


def geometry_problems(
    leds: LedArray,
    heights: Sequence[float],
    distances: Sequence[float],
    pitches: Sequence[float],
) -> list[str | None]:
    """For each configuration (Y[i], Z[i], θ[i]), why ``leds`` cannot sit there, or None.

    The rules of :func:`eyelume.compile._check_leds` that hold in the LED–eye plane system: a body
    (a sphere of ``body_diameter_mm`` about its centre at axial distance Z) must not reach the
    eye plane (Z − r_body > 0), two bodies must not overlap (centres ≥ 2 r_body apart), and the
    pitch must lie in the scene model's range (−90°, 90°). The full scene also rejects a body
    inside the imaging lens; the free-space system has no lens, so that is left to compile.
    LEDs with a cylindrical body (``body_shape``) are placed at each configuration
    (:func:`~eyelume.scene.sources.ring_poses`) and tested as compile tests them: each body's
    reach toward the eye plane along −n̂ (:func:`~eyelume.scene.sources.body_support`) and
    each pair (:func:`~eyelume.scene.sources.bodies_overlap`).
    """
    if "cylinder" in leds.body_shapes():
        return _body_problems(leds, heights, distances, pitches)
    rb = max(leds.body_radii_mm())  # the largest body: a bound for unlike bodies
    phi = np.radians(np.asarray(leds.azimuths(), dtype=float))
    chord = math.inf  # the smallest distance between two LED centres at Y = 1 mm
    if len(phi) > 1:
        xy = np.stack([np.cos(phi), np.sin(phi)], axis=1)
        d = np.linalg.norm(xy[:, None, :] - xy[None, :, :], axis=2)
        d[np.diag_indices(len(phi))] = np.inf
        chord = float(d.min())
    out: list[str | None] = []
    for y, z, t in zip(heights, distances, pitches, strict=True):
        y, z, t = float(y), float(z), float(t)
        if not (math.isfinite(y) and math.isfinite(z) and math.isfinite(t)):
            out.append(f"(Y, Z, θ) = ({y}, {z}, {t}) is not finite")
        elif y < 0:
            out.append(f"height Y = {y} mm is negative")
        elif not -90 < t < 90:
            out.append(f"pitch θ = {t} deg is outside (−90, 90)")
        elif z - rb <= 0:
            out.append(f"LED body (centre Z = {z} mm, radius {rb} mm) crosses the eye plane z = 0")
        elif y * chord < 2 * rb:
            out.append(
                f"LED bodies overlap at height Y = {y} mm (centres {y * chord:.2f} mm apart, "
                f"body diameter up to {2 * rb} mm)"
            )
        else:
            out.append(None)
    return out


def _placement_problem(y: float, z: float, t: float) -> str | None:
    """Why (Y, Z, θ) is no placement at all (not finite, Y < 0, θ outside (−90°, 90°))."""
    if not (math.isfinite(y) and math.isfinite(z) and math.isfinite(t)):
        return f"(Y, Z, θ) = ({y}, {z}, {t}) is not finite"
    if y < 0:
        return f"height Y = {y} mm is negative"
    if not -90 < t < 90:
        return f"pitch θ = {t} deg is outside (−90, 90)"
    return None


def _bodies_problem(leds: LedArray, y: float, z: float, t: float) -> str | None:
    """Why the bodies of ``leds`` at (Y, Z, θ) cannot be (module :func:`geometry_problems`)."""
    ring_c, _, _, n_hat = ring_basis(leds)
    if leds.positions_mm is None:
        centres, axes = ring_poses(leds, [y], [z], [t])
        centres, axes = centres[0], axes[0]
    else:
        centres, axes = led_poses(leds)
    bodies = led_bodies(leds, centres, axes)
    for k, b in enumerate(bodies):
        zc = float((b.centre - ring_c) @ n_hat)  # the ring's Z of this LED's centre
        if zc - body_support(b.shape, b.axis, b.radius, b.length, -n_hat) <= 0:
            return f"LED {k} body (centre Z = {zc:g} mm, {b.words()}) crosses the eye plane z = 0"
    for i in range(len(bodies)):
        for j in range(i):
            if bodies_overlap(bodies[i], bodies[j]):
                return (
                    f"LED bodies overlap at height Y = {y} mm (LED {i} and LED {j}: "
                    f"{bodies[i].words()} and {bodies[j].words()})"
                )
    return None


def _body_problems(
    leds: LedArray,
    heights: Sequence[float],
    distances: Sequence[float],
    pitches: Sequence[float],
) -> list[str | None]:
    """:func:`geometry_problems` for LEDs of which one at least is a cylinder."""
    out: list[str | None] = []
    for y, z, t in zip(heights, distances, pitches, strict=True):
        y, z, t = float(y), float(z), float(t)
        out.append(_placement_problem(y, z, t) or _bodies_problem(leds, y, z, t))
    return out


def geometry_problem(
    leds: LedArray, height_mm: float, distance_mm: float, pitch_deg: float
) -> str | None:
    """Why ``leds`` cannot sit at (Y, Z, θ), or None if they can (see :func:`geometry_problems`).

    >>> from eyelume.scene.model import LedArray
    >>> geometry_problem(LedArray(), 30, 2, 0)
    'LED body (centre Z = 2.0 mm, radius 2.5 mm) crosses the eye plane z = 0'
    """
    return geometry_problems(leds, [height_mm], [distance_mm], [pitch_deg])[0]


def led_emitters(
    leds: LedArray, heights: np.ndarray, distances: np.ndarray, pitches: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Emission points and unit axes, (n, N, 3) each, of ``leds`` at n configurations (Y, Z, θ).

    The placement of :func:`eyelume.scene.sources.ring_poses` (the LEDs one by one: their
    fixed positions at every configuration); the emission point is the front of the body,
    centre + axis · offset (a sphere's radius, half a cylinder's length:
    :meth:`~eyelume.scene.model.LedArray.emission_offsets_mm`), as in :mod:`eyelume.compile`.
    """
    rb = np.asarray(leds.emission_offsets_mm())[:, None]  # (N, 1): each LED's own body
    if leds.positions_mm is not None:  # one by one: nothing to vary
        centres, axes = led_poses(leds)
        n = np.asarray(heights).size
        centres, axes = (
            np.broadcast_to(centres, (n, *centres.shape)),
            np.broadcast_to(axes, (n, *axes.shape)),
        )
    else:
        centres, axes = ring_poses(leds, heights, distances, pitches)
    return np.ascontiguousarray(centres + axes * rb), np.ascontiguousarray(axes)


def plane_edges(plane: EyePlane) -> tuple[np.ndarray, np.ndarray]:
    """Bin edges of the eye plane (mm): x from −w/2 (column 0) and y from +h/2 (row 0), by the
    one definition of its bins (:mod:`eyelume.kernels.bins`)."""
    g = eye_plane_grid(plane.width_mm, plane.height_mm, plane.cols, plane.rows)
    x, _ = from_grid.py_func(g, np.arange(plane.cols + 1.0), 0.0)
    _, y = from_grid.py_func(g, 0.0, np.arange(plane.rows + 1.0))
    return x, y


# --- the integral --------------------------------------------------------------------------------


class Profile(NamedTuple):
    """An LED profile for the integral: ``kind`` (cos^m or table), m, and the table's angles
    (rad) and relative intensities (unused for cos^m)."""

    kind: int
    m: float
    alpha_t: np.ndarray
    value_t: np.ndarray


class Quadrature(NamedTuple):
    """Gauss–Legendre nodes (bins, order) and weights of the x (columns) and y (rows) bins."""

    xn: np.ndarray
    xw: np.ndarray
    yn: np.ndarray
    yw: np.ndarray


class Emitters(NamedTuple):
    """Emission points and unit axes (configurations, LEDs, 3), world mm."""

    emit: np.ndarray
    axes: np.ndarray


def _profile_args(profile: LedProfile) -> Profile:
    if profile.kind == "cos_power":
        m = cos_power_exponent(profile.half_intensity_angle_deg)
        return Profile(_KIND_COS_POWER, m, np.zeros(2), np.zeros(2))
    alpha_t, value_t = read_profile_table(profile.table_csv)  # the tracers' table
    return Profile(_KIND_TABLE, 0.0, np.ascontiguousarray(alpha_t), np.ascontiguousarray(value_t))


@functools.lru_cache(maxsize=16)
def _leggauss(order: int) -> tuple[np.ndarray, np.ndarray]:
    return np.polynomial.legendre.leggauss(order)


def _nodes(edges: np.ndarray, order: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Legendre nodes (bins, order) and weights normalised to a mean (each row sums to 1)."""
    g, w = _leggauss(order)
    lo, hi = edges[:-1, None], edges[1:, None]
    nodes = 0.5 * (lo + hi) + 0.5 * (hi - lo) * g[None, :]
    weights = np.broadcast_to(0.5 * w[None, :], nodes.shape)
    return np.ascontiguousarray(nodes), np.ascontiguousarray(weights)


@njit(cache=True, inline="always")
def _table_value(c: float, alpha_t: np.ndarray, value_t: np.ndarray) -> float:
    """f(α) of a table (linear in α, 0 past its last angle) at cos α = c ∈ (0, 1]."""
    alpha = math.acos(min(c, 1.0))
    n = alpha_t.shape[0]
    if alpha > alpha_t[n - 1]:
        return 0.0
    k = np.searchsorted(alpha_t, alpha, side="right") - 1
    if k >= n - 1:
        return value_t[n - 1]
    t = (alpha - alpha_t[k]) / (alpha_t[k + 1] - alpha_t[k])
    return value_t[k] + t * (value_t[k + 1] - value_t[k])


@njit(cache=True, error_model="numpy")
def _row_means(c, r, quad, emitters, profile, out):
    """out[c, r, :] = mean over each bin of row r of Σ_l f(α) cos β / r² (1/mm²), config c."""
    xn, xw, yn, yw = quad
    emit, axes = emitters
    kind, m, alpha_t, value_t = profile
    cols = out.shape[2]
    nled = emit.shape[1]
    order_x = xn.shape[1]
    order_y = yn.shape[1]
    half_m = 0.5 * m
    for k in range(cols):
        acc = 0.0
        for led in range(nled):
            ex = emit[c, led, 0]
            ey = emit[c, led, 1]
            ez = emit[c, led, 2]
            ax = axes[c, led, 0]
            ay = axes[c, led, 1]
            az = axes[c, led, 2]
            for j in range(order_y):
                dy = yn[r, j] - ey
                s = 0.0
                for i in range(order_x):
                    dx = xn[k, i] - ex
                    r2 = dx * dx + dy * dy + ez * ez
                    dot = dx * ax + dy * ay - ez * az  # (p − e)·a, with p_z − e_z = −e_z
                    if dot > 0.0:
                        inv_r3 = 1.0 / (r2 * math.sqrt(r2))
                        if kind == 0:
                            # cos^m α = (dot² / r²)^(m/2)
                            f = math.exp(half_m * math.log(dot * dot / r2))
                        else:
                            f = _table_value(dot / math.sqrt(r2), alpha_t, value_t)
                        s += xw[k, i] * f * ez * inv_r3
                acc += yw[r, j] * s
        out[c, r, k] = acc


@njit(cache=True, parallel=True)
def _bin_means_parallel(quad, emitters, profile, out):
    # flat structs of arrays and scalars, arguments of this function: a prange body takes them
    # as they are (only nested ones, numba#10139, must be taken apart; kernels/tables.py)
    n, rows = out.shape[0], out.shape[1]
    for task in prange(n * rows):
        c = task // rows
        _row_means(c, task - c * rows, quad, emitters, profile, out)


@njit(cache=True)
def _bin_means_serial(quad, emitters, profile, out):
    n, rows = out.shape[0], out.shape[1]
    for task in range(n * rows):
        c = task // rows
        _row_means(c, task - c * rows, quad, emitters, profile, out)


#: Below this many bin integrals (configurations × bins × LEDs × points) one thread is quicker
#: than waking the pool.
_PARALLEL_MIN_WORK = 200_000


def _rel_change(a: np.ndarray, b: np.ndarray) -> float:
    """Largest |a − b| / |b| over bins, bins below 1e-12 of the largest counting as that floor."""
    floor = 1e-12 * float(np.max(np.abs(b))) + 1e-300
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), floor)))


def _means(xe, ye, emit, axes, profile_args, order) -> np.ndarray:
    xn, xw = _nodes(xe, order)
    yn, yw = _nodes(ye, order)
    out = np.empty((emit.shape[0], yn.shape[0], xn.shape[0]))
    work = out.size * emit.shape[1] * order * order
    kernel = _bin_means_parallel if work >= _PARALLEL_MIN_WORK else _bin_means_serial
    kernel(Quadrature(xn, xw, yn, yw), Emitters(emit, axes), profile_args, out)
    return out


def auto_order(
    x_edges: np.ndarray,
    y_edges: np.ndarray,
    emitters: np.ndarray,
    axes: np.ndarray,
    profile: LedProfile | Sequence[LedProfile],
    rtol: float = AUTO_RTOL,
) -> int:
    """The Gauss–Legendre order :func:`bin_irradiance` uses when none is given.

    A cos^m profile: the smallest n in 4, 8, 16, 32, 64 whose result doubling the order changes
    by at most ``rtol`` in every bin, probed on the configurations hardest to integrate (the one
    whose nearest emitter is closest to the plane, and the closest among the most pitched ones);
    the rule converges geometrically, so the other configurations are closer still. A tabulated
    profile: :data:`TABLE_ORDER` (its kinks converge only algebraically, see the module docstring).
    LEDs of different profiles (a sequence, one per LED): the largest order any of them needs.
    """
    if not isinstance(profile, LedProfile):
        return max(auto_order(x_edges, y_edges, emitters, axes, p, rtol) for p in set(profile))
    if profile.kind != "cos_power":
        return TABLE_ORDER
    emit = np.asarray(emitters, dtype=float).reshape(-1, *np.shape(emitters)[-2:])
    ax = np.asarray(axes, dtype=float).reshape(emit.shape)
    lowest = emit[..., 2].min(axis=1)
    tilt = np.abs(ax[..., 2]).min(axis=1)  # cos of the largest pitch in each configuration
    most_pitched = np.flatnonzero(tilt <= tilt.min() + 1e-12)
    probe = sorted({int(np.argmin(lowest)), int(most_pitched[np.argmin(lowest[most_pitched])])})
    e, a = np.ascontiguousarray(emit[probe]), np.ascontiguousarray(ax[probe])
    args = _profile_args(profile)
    xe, ye = np.asarray(x_edges, dtype=float), np.asarray(y_edges, dtype=float)
    order = 4
    coarse = _means(xe, ye, e, a, args, order)
    while order < 64:
        fine = _means(xe, ye, e, a, args, 2 * order)
        if _rel_change(coarse, fine) <= rtol:
            break
        order, coarse = 2 * order, fine
    return order


def bin_irradiance(
    x_edges: np.ndarray,
    y_edges: np.ndarray,
    emitters: np.ndarray,
    axes: np.ndarray,
    intensity_w_sr: float | Sequence[float],
    profile: LedProfile | Sequence[LedProfile],
    order: int | None = None,
) -> np.ndarray:
    """Mean irradiance (W/mm²) over the bins of the plane z = 0 from point LEDs in free space.

    Parameters
    ----------
    x_edges, y_edges
        Bin edges (mm), (cols + 1,) and (rows + 1,), monotonic; row i lies between
        ``y_edges[i]`` and ``y_edges[i + 1]`` (descending edges put row 0 at +y).
    emitters, axes
        (n, N, 3) emission points (z > 0) and unit axes of N LEDs at n configurations, or (N, 3)
        for one configuration.
    intensity_w_sr
        On-axis radiant intensity I₀ (W/sr): one for every LED, or (N,) one per LED.
    profile
        The angular profile f(α) = I(α)/I₀: one for every LED, or N, one per LED. The integral
        is linear in the LEDs: LEDs alike are integrated together, each group × its I₀.
    order
        Gauss–Legendre points per bin along each axis; None chooses it (:func:`auto_order`).

    Returns
    -------
    (n, rows, cols) array, or (rows, cols) for (N, 3) inputs:
    (1/A_bin) ∫∫_bin Σ_LEDs I₀ₖ fₖ(α) cos β / r² dA.

    Raises
    ------
    ValueError
        Shapes that do not match, an emission point on or below the plane, a bad order.
    """
    emitters = np.asarray(emitters, dtype=float)
    single = emitters.ndim == 2
    emit = np.ascontiguousarray(emitters[None] if single else emitters)
    ax = np.asarray(axes, dtype=float)
    ax = np.ascontiguousarray(ax[None] if single else ax)
    if emit.shape != ax.shape or emit.ndim != 3 or emit.shape[2] != 3:
        raise ValueError(f"emitters {emitters.shape} and axes {np.shape(axes)} must be (n, N, 3)")
    if np.any(emit[..., 2] <= 0):
        raise ValueError("every emission point must lie above the plane (z > 0)")
    xe, ye = np.asarray(x_edges, dtype=float), np.asarray(y_edges, dtype=float)
    groups = _led_groups(intensity_w_sr, profile, emit.shape[1])
    if order is None:
        order = auto_order(xe, ye, emit, ax, [g[1] for g in groups])
    if not (isinstance(order, int | np.integer) and 1 <= order <= 256):
        raise ValueError(f"order = {order!r}: must be an integer in 1 … 256")
    if len(groups) == 1:  # every LED alike: one integral (the paper's floats)
        out = _means(xe, ye, emit, ax, _profile_args(groups[0][1]), int(order))
        out *= groups[0][0]
    else:
        out = np.zeros((emit.shape[0], len(ye) - 1, len(xe) - 1))
        for i0, prof, idx in groups:
            sub = (np.ascontiguousarray(emit[:, idx]), np.ascontiguousarray(ax[:, idx]))
            out += i0 * _means(xe, ye, *sub, _profile_args(prof), int(order))
    return out[0] if single else out


def _led_groups(intensity_w_sr, profile, n_leds: int) -> list[tuple[float, LedProfile, list]]:
    """The LEDs grouped by (I₀, profile): [(I₀, profile, LED indices)], in first-seen order."""
    i0 = np.broadcast_to(np.asarray(intensity_w_sr, dtype=float), (n_leds,))
    profiles = [profile] * n_leds if isinstance(profile, LedProfile) else list(profile)
    if len(profiles) != n_leds:
        raise ValueError(f"{len(profiles)} profiles for {n_leds} LEDs")
    groups: dict[tuple[float, LedProfile], list[int]] = {}
    for k in range(n_leds):
        groups.setdefault((float(i0[k]), profiles[k]), []).append(k)
    return [(a, p, idx) for (a, p), idx in groups.items()]


# --- the public entry points ---------------------------------------------------------------------


def _scene_of(scene) -> Scene:
    return getattr(scene, "scene", scene)  # a CompiledScene carries its Scene


def configuration_irradiance(
    scene: Scene,
    heights: Sequence[float],
    distances: Sequence[float],
    pitches: Sequence[float],
    *,
    order: int | None = None,
) -> np.ndarray:
    """Eye-plane irradiance (n, rows, cols) in W/mm² of the scene's LEDs at n configurations
    (Y[i], Z[i], θ[i]) given as three equal-length sequences (mm, mm, degrees).

    The plane is the eye plane the tracers bin: through the eye's nominal corneal vertex
    (``eye_pose``) normal to the headset's z axis, its x, y measured from that vertex; a left
    eye's LEDs are mirrored (x → −x) as :func:`eyelume.compile.as_world` does. The geometry
    checks (:func:`geometry_problems`) stay in the ring's own frame (the eye at its centre).

    Raises GeometryError (a ValueError) naming the first configuration whose geometry is
    impossible (:func:`geometry_problem`).
    """
    sc = _scene_of(scene)
    y, z, t = (
        np.atleast_1d(np.asarray(v, dtype=float)).ravel() for v in (heights, distances, pitches)
    )
    if not len(y) == len(z) == len(t):
        raise ValueError(f"heights, distances, pitches have lengths {len(y)}, {len(z)}, {len(t)}")
    if sc.leds.positions_mm is not None:
        if len(y) != 1:
            raise GeometryError(
                "the LEDs are placed one by one (leds.positions_mm): there is no ring (Y, Z, θ) "
                "to vary",
                field="leds.positions_mm",
            )
    else:
        for i, why in enumerate(geometry_problems(sc.leds, y, z, t)):
            if why is not None:
                raise GeometryError(
                    f"configuration {i} (Y, Z, θ) = ({y[i]}, {z[i]}, {t[i]}): {why}"
                )
    emit, axes = led_emitters(sc.leds, y, z, t)
    pose = sc.eye_pose
    if any(pose.vertex_mm):  # the eye plane is centred on the eye's nominal vertex
        emit = np.ascontiguousarray(emit - np.asarray(pose.vertex_mm, dtype=float))
    if pose.which == "left":  # a left eye's scene is the mirror image (x → −x)
        flip = np.array([-1.0, 1.0, 1.0])
        emit, axes = np.ascontiguousarray(emit * flip), np.ascontiguousarray(axes * flip)
    xe, ye = plane_edges(sc.eye_plane)
    return bin_irradiance(xe, ye, emit, axes, sc.leds.intensities_w_sr(), sc.leds.profiles(), order)


def sweep_irradiance(
    scene: Scene,
    heights: Sequence[float],
    distances: Sequence[float],
    pitches: Sequence[float],
    *,
    order: int | None = None,
) -> np.ndarray:
    """Eye-plane irradiance (n, rows, cols) in W/mm² at every configuration of the product grid
    heights × distances × pitches, in C order (Y slowest, θ fastest; see :func:`product_grid`).

    The paper's 385-configuration grid (Y 20–40, Z 20–70, θ 0–30 in steps of 5) takes well under
    a second after compilation (``benchmarks/sweep.py``).

    >>> import eyelume
    >>> scene = eyelume.load_scene("paper2005")
    >>> sweep_irradiance(scene, [20, 30], [50, 70], [0, 10, 20]).shape
    (12, 15, 21)
    """
    return configuration_irradiance(scene, *product_grid(heights, distances, pitches), order=order)


def eye_plane_irradiance(
    scene: Scene,
    height_mm: float | None = None,
    distance_mm: float | None = None,
    pitch_deg: float | None = None,
    *,
    order: int | None = None,
) -> np.ndarray:
    """Eye-plane irradiance (rows, cols) in W/mm² of the scene's LEDs in free space (no eye, no
    face): the paper's LED–eye plane system, row 0 at +y.

    Y, Z, θ default to the scene's ``leds.height_mm``, ``distance_mm``, ``pitch_deg``.

    >>> import eyelume
    >>> scene = eyelume.load_scene("paper2005")
    >>> e = eye_plane_irradiance(scene)
    >>> e.shape, bool(np.allclose(e, e[::-1, ::-1]))   # four LEDs at 0/90/180/270°: symmetric
    ((15, 21), True)
    """
    sc = _scene_of(scene)
    leds = sc.leds
    if leds.positions_mm is not None and (height_mm, distance_mm, pitch_deg) != (None,) * 3:
        raise GeometryError(
            "the LEDs are placed one by one (leds.positions_mm): give no ring (Y, Z, θ)",
            field="leds.positions_mm",
        )
    y = leds.height_mm if height_mm is None else height_mm
    z = leds.distance_mm if distance_mm is None else distance_mm
    t = leds.pitch_deg if pitch_deg is None else pitch_deg
    return configuration_irradiance(sc, [y], [z], [t], order=order)[0]
