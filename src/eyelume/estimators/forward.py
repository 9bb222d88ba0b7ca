"""The plain forward Monte Carlo estimator: what LightTools does, and the unbiased reference.

Every ray leaves an LED with the same power w = Φ_total / N and keeps it (LED k is drawn with
probability Φₖ / Φ_total, its own share): at a partial reflector
it reflects with probability R (else refracts, or is absorbed with probability A), at a Lambertian
face it scatters with probability ρ into a cosine-weighted direction (else is absorbed). Each ray
thus ends in exactly one ledger entry, every bin counts whole rays, and a result is an integer
count times w — independent of summation order, hence of thread count and batch size.

Non-sequential among eye, face and LED bodies (nearest hit among all surfaces); a ray that meets
the imaging lens's first surface from the eye side continues sequentially to the image plane.
The eye-plane receiver counts every crossing of z = 0 toward the eye without touching the ray.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numba
import numpy as np
from numba import njit, prange

from eyelume.compile import (
    TALLY_ESCAPED,
    TALLY_LIMIT,
    TALLY_OFF_SENSOR,
    TALLY_SENSOR,
    TALLY_TIR,
    TALLY_VIGNETTED,
    CompiledScene,
)
from eyelume.errors import BudgetError
from eyelume.estimators.interrupt import interrupt_between_batches
from eyelume.kernels import geometry as G
from eyelume.kernels.bins import bin_of, plane_coordinates, to_grid
from eyelume.kernels.interact import interface_at, reflect, refract
from eyelume.kernels.jit import per_ray
from eyelume.kernels.rng import next_uniform, stream_start
from eyelume.kernels.sampling import about_axis, cosine_hemisphere, led_direction, led_index
from eyelume.kernels.sequential import LENS_PASSED, LENS_TIR, trace_lens
from eyelume.kernels.tables import SceneTables, scene_parts

__all__ = ["ForwardCounts", "trace_forward", "trace_paths"]

_ESCAPE_DRAW_MM = 60.0  # length drawn for an escaping ray in a recorded path


@njit(cache=True, inline="always")
def _record(path, n, x, y, z, record):
    if record and n < path.shape[0]:
        path[n, 0] = x
        path[n, 1] = y
        path[n, 2] = z
        n += 1
    return n


class Emission(NamedTuple):
    """A ray's birth: its stream state, origin and unit direction (world mm)."""

    state: np.uint64
    x: float
    y: float
    z: float
    dx: float
    dy: float
    dz: float


class Traced(NamedTuple):
    """How a traced ray ended: ledger entry, surface interactions, recorded path length."""

    entry: int
    interactions: int
    npath: int


#: Fixed-point unit of the glint rays' offsets inside their pixel (pixels): exact integer sums,
#: whatever the order the chunks add them in.
MOMENT_UNIT = 2.0**-20


class Counts(NamedTuple):
    """Where a forward trace counts: rays per picture pixel, eye-plane crossings per bin, rays
    per ledger entry; of the rays per pixel, those that met no Lambertian face (``glint``) and
    their offsets from the pixel's centre summed (``moment`` (2, rows, cols): columns, rows; in
    :data:`MOMENT_UNIT` pixels) (int64 arrays)."""

    image: np.ndarray
    plane: np.ndarray
    tallies: np.ndarray
    glint: np.ndarray
    moment: np.ndarray


@per_ray
def emit_ray(i, seed, leds):
    """Birth of ray ``i``: an LED of ``leds`` (:class:`~eyelume.kernels.tables.LedTable`) drawn
    with probability its share of the emitted power (:func:`~eyelume.kernels.sampling.led_index`,
    so every ray carries the same power), a direction from its angular profile about its axis
    (:func:`~eyelume.kernels.sampling.led_direction`). Returns an :class:`Emission`."""
    state = stream_start(seed, i)
    state, u = next_uniform(state)
    led = led_index(leds, u)
    state, u1 = next_uniform(state)
    state, u2 = next_uniform(state)
    dx, dy, dz = led_direction(leds, led, u1, u2)
    return Emission(
        state, leds.points[led, 0], leds.points[led, 1], leds.points[led, 2], dx, dy, dz
    )


@per_ray
def trace_ray(i, seed, scene, counts, path, record):
    """Trace ray ``i`` of ``scene`` (the compiled scene's
    :class:`~eyelume.kernels.tables.SceneTables`) from birth to its end, adding to ``counts``
    (a :class:`Counts`); with ``record`` its vertices go to ``path``. Returns a :class:`Traced`.
    """
    sf, si = scene.surfaces.sf, scene.surfaces.si
    tallies = counts.tallies
    state, x, y, z, dx, dy, dz = emit_ray(i, seed, scene.leds)
    npath = _record(path, 0, x, y, z, record)
    interactions = 0
    specular = True  # no Lambertian face met yet: a point's image (a glint) on the sensor
    for _ in range(scene.max_events):
        s, t = G.nearest_hit(sf, si, x, y, z, dx, dy, dz)
        ep = scene.eye_plane
        _, _, h = plane_coordinates(ep, x, y, z)
        hd = ep.nx * dx + ep.ny * dy + ep.nz * dz
        if hd < 0.0 and h > 0.0:  # crosses the eye plane toward the eye before its next hit?
            t0 = -h / hd
            if t0 < t:
                px, py, _ = plane_coordinates(ep, x + t0 * dx, y + t0 * dy, z + t0 * dz)
                col, row, inside = bin_of(ep, px, py)
                if inside:
                    counts.plane[row, col] += 1
        if s < 0:
            tallies[TALLY_ESCAPED] += 1
            npath = _record(
                path,
                npath,
                x + _ESCAPE_DRAW_MM * dx,
                y + _ESCAPE_DRAW_MM * dy,
                z + _ESCAPE_DRAW_MM * dz,
                record,
            )
            return Traced(TALLY_ESCAPED, interactions, npath)
        action = si[s, G.ACTION]
        if action == G.ACT_LENS:
            nx, ny, nz = G.surface_normal(sf, si, s, x + t * dx, y + t * dy, z + t * dz)
            if dx * nx + dy * ny + dz * nz < 0.0:  # met from behind: the lens's back and mount
                tallies[si[s, G.TALLY_B]] += 1
                npath = _record(path, npath, x + t * dx, y + t * dy, z + t * dz, record)
                return Traced(si[s, G.TALLY_B], interactions + 1, npath)
            status, x, y, z, dx, dy, dz, met, npath = trace_lens(
                scene.lens.lf, x, y, z, dx, dy, dz, path, npath, record
            )
            interactions += met
            if status != LENS_PASSED:
                entry = TALLY_TIR if status == LENS_TIR else TALLY_VIGNETTED
                tallies[entry] += 1
                return Traced(entry, interactions, npath)
            t = (scene.lens.image_z - z) / dz
            x += t * dx
            y += t * dy
            z = scene.lens.image_z
            npath = _record(path, npath, x, y, z, record)
            # the picture is the sensor image turned by 180°, as a camera's readout shows it:
            # world +y at the top (row 0), world +x to the right (as seen from the camera)
            u, v = to_grid(scene.picture, x, y)
            col, row = int(math.floor(u)), int(math.floor(v))
            if 0 <= col < scene.picture.cols and 0 <= row < scene.picture.rows:
                counts.image[row, col] += 1
                if specular:
                    counts.glint[row, col] += 1
                    su, sv = (u - col - 0.5) / MOMENT_UNIT, (v - row - 0.5) / MOMENT_UNIT
                    counts.moment[0, row, col] += np.int64(math.floor(su + 0.5))
                    counts.moment[1, row, col] += np.int64(math.floor(sv + 0.5))
                tallies[TALLY_SENSOR] += 1
                return Traced(TALLY_SENSOR, interactions, npath)
            tallies[TALLY_OFF_SENSOR] += 1
            return Traced(TALLY_OFF_SENSOR, interactions, npath)

        x += t * dx
        y += t * dy
        z += t * dz
        interactions += 1
        npath = _record(path, npath, x, y, z, record)
        nx, ny, nz = G.surface_normal(sf, si, s, x, y, z)
        cos_d = dx * nx + dy * ny + dz * nz
        from_b = cos_d < 0.0  # the normal points to side B, so the ray arrives from B
        state, u = next_uniform(state)
        if action == G.ACT_OPAQUE:
            rho = sf[s, G.RHO_B] if from_b else sf[s, G.RHO_A]
            if u >= rho:
                entry = si[s, G.TALLY_B] if from_b else si[s, G.TALLY_A]
                tallies[entry] += 1
                return Traced(entry, interactions, npath)
            if not from_b:
                nx, ny, nz = -nx, -ny, -nz
            specular = False
            state, u1 = next_uniform(state)
            state, u2 = next_uniform(state)
            lx, ly, lz = cosine_hemisphere(u1, u2)
            dx, dy, dz = about_axis(lx, ly, lz, nx, ny, nz)
        else:  # refracting interface with a partial reflection
            f = interface_at(sf, si, s, cos_d)
            ok, tx, ty, tz = refract(dx, dy, dz, nx, ny, nz, f.n1 / f.n2)
            if not ok:  # total internal reflection: all of it, whatever R and A say
                dx, dy, dz = reflect(dx, dy, dz, nx, ny, nz)
            else:
                if u < f.reflectance:
                    dx, dy, dz = reflect(dx, dy, dz, nx, ny, nz)
                elif u < f.reflectance + f.absorptance:
                    entry = si[s, G.TALLY_B] if from_b else si[s, G.TALLY_A]
                    tallies[entry] += 1
                    return Traced(entry, interactions, npath)
                else:
                    dx, dy, dz = tx, ty, tz
        norm = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
        dx *= norm
        dy *= norm
        dz *= norm
    tallies[TALLY_LIMIT] += 1
    return Traced(TALLY_LIMIT, interactions, npath)


@njit(cache=True)
def _trace_batch(start, count, seed, scene, chunked, interactions):
    """Trace rays ``start`` … ``start + count − 1`` in chunks, one per leading index of the
    arrays of ``chunked`` (:class:`Counts`): chunk c adds to each one's item c and to
    ``interactions[c]``."""
    _trace_chunks(start, count, seed, *scene_parts(scene), chunked, interactions)


@njit(cache=True, parallel=True)
def _trace_chunks(  # noqa: PLR0913 - the scene's parts as arguments (numba#10139)
    start, count, seed, surfaces, lens, leds, picture, eye_plane, max_events, chunked, interactions
):
    """:func:`_trace_batch` with the scene's parts (:func:`~eyelume.kernels.tables.scene_parts`)."""
    n_chunks = chunked.image.shape[0]
    for c in prange(n_chunks):
        tables = SceneTables(surfaces, lens, leds, picture, eye_plane, max_events)
        lo = start + (count * c) // n_chunks
        hi = start + (count * (c + 1)) // n_chunks
        path = np.zeros((1, 3))
        counts = Counts(
            chunked.image[c], chunked.plane[c], chunked.tallies[c], chunked.glint[c],
            chunked.moment[c],
        )  # fmt: skip
        inter = 0
        for i in range(lo, hi):
            inter += trace_ray(i, seed, tables, counts, path, False).interactions
        interactions[c] += inter


@dataclass
class ForwardCounts:
    """Integer tallies of a forward run: every ray counted exactly once in ``tallies``.

    ``interrupted`` is True when Ctrl-C stopped the run between batches: ``rays`` is then the
    number traced so far, a complete unbiased sample of its own.
    """

    image: np.ndarray  # (rows, cols) rays reaching each sensor pixel
    plane: np.ndarray  # (rows, cols) eye-plane crossings toward the eye
    tallies: np.ndarray  # (n_entries,) rays ending in each ledger entry
    interactions: int
    rays: int
    interrupted: bool = False
    glint: np.ndarray | None = None  # (rows, cols) of image: rays that met no Lambertian face
    #: (2, rows, cols) those rays' mean offset from their pixel's centre (pixels; columns,
    #: rows; 0 where there are none): where the PSF spreads them from (detectors.psf)
    glint_offsets: np.ndarray | None = None


def trace_forward(
    cs: CompiledScene,
    rays: int,
    seed: int,
    batch_size: int | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> ForwardCounts:
    """Trace ``rays`` rays of the compiled scene, in batches so memory stays flat.

    ``progress(done, total)`` is called after each batch. Results depend on (scene, rays, seed)
    only. Ctrl-C (SIGINT, in the main thread) ends the run after the batch in flight and returns
    the finished batches, marked ``interrupted``; a second Ctrl-C aborts at once.
    """
    if rays < 1:
        raise BudgetError(f"rays = {rays}: must be ≥ 1")
    batch = int(batch_size or cs.scene.run.batch_size)
    n_chunks = 4 * numba.get_num_threads()
    rows, cols = cs.picture.rows, cs.picture.cols
    prow, pcol = cs.eye_plane.rows, cs.eye_plane.cols
    chunked = Counts(
        np.zeros((n_chunks, rows, cols), dtype=np.int64),
        np.zeros((n_chunks, prow, pcol), dtype=np.int64),
        np.zeros((n_chunks, len(cs.tallies)), dtype=np.int64),
        np.zeros((n_chunks, rows, cols), dtype=np.int64),
        np.zeros((n_chunks, 2, rows, cols), dtype=np.int64),
    )
    inter = np.zeros(n_chunks, dtype=np.int64)
    done = 0
    with interrupt_between_batches() as stop:
        while done < rays and not stop.requested:
            n = min(batch, rays - done)
            _trace_batch(done, n, seed, cs.tables, chunked, inter)
            done += n
            if progress is not None:
                progress(done, rays)
    if done == 0:
        raise KeyboardInterrupt
    image, plane, tallies, glint, moment = (a.sum(axis=0) for a in chunked)
    offsets = moment * MOMENT_UNIT / np.where(glint > 0, glint, 1)
    return ForwardCounts(image, plane, tallies, int(inter.sum()), done, done < rays, glint, offsets)


class PathSearch(NamedTuple):
    """Which recorded rays :func:`_trace_paths` keeps: born within ``section_tol`` mm of the
    section plane n · p = ``plane_offset`` (``plane_normal`` n (3,), unit, camera frame), up to
    ``want_detected`` that reach the sensor and ``want_other`` that do not; into ``out``
    (k, max_len, 3) with ``lengths`` and ``kinds`` (1: detected)."""

    section_tol: float
    plane_normal: np.ndarray
    plane_offset: float
    want_detected: int
    want_other: int
    out: np.ndarray
    lengths: np.ndarray
    kinds: np.ndarray


@njit(cache=True)
def _trace_paths(start, n, seed, scene, n_tallies, want):
    pic, pl = scene.picture, scene.eye_plane
    counts = Counts(
        np.zeros((pic.rows, pic.cols), dtype=np.int64),
        np.zeros((pl.rows, pl.cols), dtype=np.int64),
        np.zeros(n_tallies, dtype=np.int64),
        np.zeros((pic.rows, pic.cols), dtype=np.int64),
        np.zeros((2, pic.rows, pic.cols), dtype=np.int64),
    )
    path = np.zeros((want.out.shape[1], 3))
    got_d = 0
    got_o = 0
    k = 0
    for i in range(start, start + n):
        entry, _, npath = trace_ray(i, seed, scene, counts, path, True)
        n = want.plane_normal
        off = path[0, 0] * n[0] + path[0, 1] * n[1] + path[0, 2] * n[2] - want.plane_offset
        if abs(off) > want.section_tol:
            continue  # born off the section: its projection would mislead
        detected = entry == TALLY_SENSOR
        if (detected and got_d < want.want_detected) or (not detected and got_o < want.want_other):
            want.out[k, :npath] = path[:npath]
            want.lengths[k] = npath
            want.kinds[k] = 1 if detected else 0
            k += 1
            if detected:
                got_d += 1
            else:
                got_o += 1
        if got_d >= want.want_detected and got_o >= want.want_other:
            break
    return k


def trace_paths(
    cs: CompiledScene,
    seed: int,
    detected: int = 24,
    other: int = 24,
    search: int = 4_000_000,
    section_tol: float = 1.0,
    plane: tuple[np.ndarray, float] | None = None,
) -> list[tuple[np.ndarray, bool]]:
    """Record the vertices of a few rays for drawing: up to ``detected`` rays that reach the
    sensor and ``other`` that do not, among the first ``search`` rays of the seed's stream,
    keeping only rays born within ``section_tol`` mm of the section plane ``plane`` = (unit
    normal n (3,), offset d) in the camera frame, n · p = d (default: the y–z section x_c = 0).

    Returns a list of ((k, 3) camera-frame vertices in mm, reached_sensor).
    """
    normal, offset = (np.array([1.0, 0.0, 0.0]), 0.0) if plane is None else plane
    max_len = cs.scene.run.max_events + cs.lf.shape[0] + 4
    out = np.zeros((detected + other, max_len, 3))
    lengths = np.zeros(detected + other, dtype=np.int64)
    kinds = np.zeros(detected + other, dtype=np.int64)
    want = PathSearch(
        float(section_tol),
        np.ascontiguousarray(normal, dtype=np.float64),
        float(offset),
        int(detected),
        int(other),
        out,
        lengths,
        kinds,
    )
    k = _trace_paths(0, search, seed, cs.tables, len(cs.tallies), want)
    return [(out[j, : lengths[j]].copy(), bool(kinds[j])) for j in range(k)]
