"""Running the fast estimator: rounds of camera samples and light paths, a per-pixel variance,
and stopping at a ray budget or at a target relative error (see :mod:`.fast` for the physics)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numba
import numpy as np

from eyelume.compile import CompiledScene
from eyelume.errors import BudgetError, GeometryError
from eyelume.estimators import fast as F
from eyelume.estimators.camera import CameraTables, camera_tables
from eyelume.estimators.interrupt import interrupt_between_batches
from eyelume.estimators.statistics import median_pixel_rel_error

__all__ = [
    "FastEstimate",
    "direct_eye_plane",
    "estimate_median_rel_error",
    "primary_surface_map",
    "trace_fast",
]

_MAX_SETS = 1 << 16


@dataclass
class FastEstimate:
    """What the fast estimator returns (W/mm² unless stated).

    ``image`` is the mean image-plane irradiance per pixel and ``variance`` the estimated
    variance of that mean, from the second moments of independent samples. ``glint_images``
    (n_leds, rows, cols) is the part carried by paths that met no Lambertian face, per LED.
    """

    image: np.ndarray
    variance: np.ndarray
    glint_images: np.ndarray
    samples_per_pixel: int
    light_paths: int
    interrupted: bool
    variance_dof: int  # degrees of freedom of each pixel's variance estimate (sets − 1)


#: Stratification grids: sets of 4 × 4 camera samples from 32 samples per pixel on, else of 2 × 2.
#: Larger sets stratify better; two sets at least are needed for a variance.
GRID_FINE, GRID_COARSE = 4, 2


class _Run:
    """Σm, Σm² of the camera sets and fixed-point sums of the light paths' deposits, and the
    rounds that add to them."""

    def __init__(self, cs: CompiledScene, cam: CameraTables, grid: int, seed: int) -> None:
        rows, cols = int(cs.sensor[3]), int(cs.sensor[2])
        nled = cs.leds.shape[0]
        chunks = numba.get_num_threads()
        self.grid = grid
        self.seed = seed
        self.cam_sum = np.zeros((rows, cols))
        self.cam_sq = np.zeros((rows, cols))
        self.light = np.zeros((chunks, rows, cols), dtype=np.int64)
        self.light_sq = np.zeros((chunks, rows, cols), dtype=np.int64)
        self.led = np.zeros((chunks, nled, rows, cols), dtype=np.int64)
        self.sets = 0
        self.paths = 0
        sf = cs.sf
        self.cornea = cornea = cs.surface_names.index(cs.scene.eye.surfaces[0].name)
        self.i0 = i0 = cs.scene.leds.radiant_intensity_w_sr
        centre, rb = sf[cornea, 19:22], sf[cornea, 22]
        dist = np.linalg.norm(cs.leds[:, :3] - centre, axis=1)
        if np.any(dist <= rb):
            raise GeometryError("an LED lies inside the cornea's bounding sphere")
        cone = 2 * math.pi * (1 - np.sqrt(1 - (rb / dist) ** 2))
        per_mm2 = cs.sensor[2] * cs.sensor[3] / (cs.sensor[0] * cs.sensor[1])
        c_typ = i0 * nled * float(cone.max()) * per_mm2
        self.q = c_typ * 2.0**-24
        self.q2 = c_typ * c_typ * 2.0**-20
        self.cs = cs
        self.light_args = (
            cornea,
            cs.leds,
            i0,
            cs.alpha_grid,
            cs.intensity_grid,
            (
                sf,
                cs.si,
                cs.lf,
                cs.image_z,
                cs.sensor,
                cam.aim,
                cs.scene.run.max_events,
                cornea,
                cam.through_cornea,
            ),
        )
        self.cam_args = (
            sf,
            cs.si,
            cs.leds,
            i0,
            cs.alpha_grid,
            cs.intensity_grid,
            cornea,
            cam.through_cornea,
            cam.lf_rev,
            cam.lf_open,
            cam.k_stop,
            cam.stop_radius,
            cs.image_z,
            cam.rear_z,
            cam.exit_pupil_z,
            cam.exit_pupil_magnification,
            cs.sensor,
            cs.scene.run.max_events,
            grid,
        )

    @property
    def samples_per_pixel(self) -> int:
        return self.sets * self.grid * self.grid

    def add(self, n_sets: int, paths_per_sample: float) -> None:
        """Add ``n_sets`` camera sets to every pixel and light paths in proportion."""
        every = np.arange(self.cam_sum.size, dtype=np.int64)
        F.camera_pass(
            self.seed,
            self.sets,
            n_sets,
            *self.cam_args,
            every,
            self.cam_sum.reshape(-1),
            self.cam_sq.reshape(-1),
        )
        self.sets += n_sets
        n_paths = int(round(paths_per_sample * self.samples_per_pixel)) - self.paths
        if n_paths > 0:
            F.light_pass(
                self.seed,
                self.paths,
                n_paths,
                *self.light_args,
                self.light,
                self.light_sq,
                self.led,
                self.q,
                self.q2,
            )
            self.paths += n_paths

    def estimate(self, interrupted: bool) -> FastEstimate:
        n = max(self.sets, 2)
        mean_c = self.cam_sum / n
        # the variance of a mean of n independent sets: the unbiased sample variance / n
        var_c = np.maximum(self.cam_sq - n * mean_c**2, 0.0) / (n * (n - 1))
        if self.paths:
            m = self.paths
            total, total_sq = self.light.sum(axis=0), self.light_sq.sum(axis=0)
            if max(total.max(initial=0), total_sq.max(initial=0)) > (1 << 62):
                raise BudgetError("fixed-point light sums near overflow: use fewer light paths")
            mean_l = total.astype(float) * (self.q / m)
            s2 = total_sq.astype(float) * self.q2
            var_l = np.maximum(s2 - m * mean_l**2, 0.0) / (m * max(m - 1, 1))
            glints = self.led.sum(axis=0).astype(float) * (self.q / m)
        else:
            mean_l = var_l = np.zeros_like(mean_c)
            glints = np.zeros(self.led.shape[1:])
        return FastEstimate(
            mean_c + mean_l,
            var_c + var_l,
            glints,
            self.samples_per_pixel,
            self.paths,
            interrupted,
            max(self.sets - 1, 1),
        )


#: Images with more pixels than this size their first round by a pilot on a sample of pixels.
_PILOT_ABOVE = 50_000
_PILOT_PIXELS = 2048


def _pilot(
    cs: CompiledScene, cam: CameraTables, seed: int, target: np.ndarray, rel_error: float
) -> tuple[int, int]:
    """(grid, sets) expected to reach ``rel_error`` in the median target pixel at the least
    cost, from 4 sets of 2 × 2 and 2 sets of 4 × 4 on up to 2048 target pixels (their own
    samples: a pixel's samples depend on its index and the seed only). The prediction aims at
    the target itself; if the first round falls short, the run adds a round."""
    idx = np.flatnonzero(target.reshape(-1))
    if idx.size > _PILOT_PIXELS:
        idx = np.sort(np.random.default_rng(seed).choice(idx, _PILOT_PIXELS, replace=False))
    best = (GRID_FINE, 2, math.inf)
    for grid, n in ((GRID_COARSE, 4), (GRID_FINE, 2)):
        s1, s2 = np.zeros(idx.size), np.zeros(idx.size)
        run = _Run(cs, cam, grid, seed)
        F.camera_pass(seed, 0, n, *run.cam_args, idx.astype(np.int64), s1, s2)
        mean = s1 / n
        var = np.maximum(s2 - n * mean**2, 0.0) / (n * (n - 1))
        err = median_pixel_rel_error(mean[mean > 0], var[mean > 0], n - 1)
        sets = max(2, math.ceil(n * (err / rel_error) ** 2))
        cost = sets * grid * grid
        if cost < best[2]:
            best = (grid, sets, cost)
    return best[0], min(best[1], _MAX_SETS)


def trace_fast(
    cs: CompiledScene,
    samples_per_pixel: int,
    light_paths: int,
    seed: int,
    rel_error: float | None = None,
    progress: Callable[[str], None] | None = None,
    target_pixels: np.ndarray | None = None,
) -> FastEstimate:
    """Run the fast estimator.

    With ``rel_error`` None: ``samples_per_pixel`` camera samples (in sets of 4 × 4 from 32
    on, else 2 × 2; rounded up to whole sets, at least two) and ``light_paths`` light paths,
    in rounds. With ``rel_error``: the same ratio of light paths to camera samples, and camera
    sets added until the median pixel's relative standard error over ``target_pixels`` (a
    boolean mask; default all pixels with signal) is at most ``rel_error``: the first round is
    the ``samples_per_pixel`` budget (its grid as above), each next round sized from the error
    so far.
    Ctrl-C ends the run after the round in flight (``interrupted``).
    ``progress(message)`` is called after each round.
    """
    if samples_per_pixel < 1:
        raise BudgetError(f"samples_per_pixel = {samples_per_pixel}: must be ≥ 1")
    if light_paths < 0:
        raise BudgetError(f"light_paths = {light_paths}: must be ≥ 0")
    if rel_error is not None and not 0.0 < rel_error < 1.0:
        raise BudgetError(f"rel_error = {rel_error}: must be in (0, 1)")
    cam = camera_tables(cs)
    ratio = light_paths / samples_per_pixel  # light paths per camera sample

    def say(run: _Run, err: float | None = None) -> None:
        if progress:
            tail = "" if err is None else f": median relative error {err:.4f}"
            progress(f"{run.samples_per_pixel} samples per pixel{tail}")

    with interrupt_between_batches() as stop:
        if rel_error is None:
            grid = GRID_FINE if samples_per_pixel >= 2 * GRID_FINE**2 else GRID_COARSE
            run = _Run(cs, cam, grid, seed)
            sets = max(2, math.ceil(samples_per_pixel / grid**2))
            step = max(1, math.ceil(sets / 8))
            while run.sets < sets and not stop.requested:
                run.add(min(step, sets - run.sets), ratio)
                say(run)
        else:
            grid, sets = GRID_FINE if samples_per_pixel >= 2 * GRID_FINE**2 else GRID_COARSE, 0
            pixels = int(cs.sensor[2] * cs.sensor[3])
            if pixels > _PILOT_ABOVE and target_pixels is not None and target_pixels.any():
                grid, sets = _pilot(cs, cam, seed, target_pixels, rel_error)
                if progress:
                    progress(f"pilot: {grid}×{grid} sets, {sets * grid * grid} samples per pixel")
            run = _Run(cs, cam, grid, seed)
            run.add(max(2, sets or math.ceil(samples_per_pixel / grid**2)), ratio)
            err = estimate_median_rel_error(run.estimate(False), target_pixels)
            say(run, err)
            while err > rel_error and run.sets < _MAX_SETS and not stop.requested:
                need = run.sets * (err / rel_error) ** 2 * 1.1
                n_more = int(min(max(need - run.sets, 1), 4 * run.sets, _MAX_SETS - run.sets))
                run.add(n_more, ratio)
                err = estimate_median_rel_error(run.estimate(False), target_pixels)
                say(run, err)
    if run.sets == 0:
        raise KeyboardInterrupt
    return run.estimate(stop.requested)


def estimate_median_rel_error(est: FastEstimate, pixels: np.ndarray | None = None) -> float:
    """The median pixel's relative standard error of an estimate over ``pixels`` (default:
    every pixel with signal), corrected for the spread of few-set variance estimates
    (:func:`eyelume.estimators.statistics.median_pixel_rel_error`)."""
    mask = est.image > 0 if pixels is None else (pixels & (est.image > 0))
    if not mask.any():
        return math.inf
    return median_pixel_rel_error(est.image[mask], est.variance[mask], est.variance_dof)


def primary_surface_map(
    cs: CompiledScene, cam: CameraTables | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) index of the surface each pixel sees in the ideal image (−1: none), and
    the side it is seen from (1: side B, where the surface normal points)."""
    cam = cam or camera_tables(cs)
    shape = (int(cs.sensor[3]), int(cs.sensor[2]))
    labels = np.empty(shape, dtype=np.int64)
    sides = np.zeros(shape, dtype=np.int64)
    F.primary_surfaces(
        cs.sf,
        cs.si,
        cam.lf_rev,
        cam.lf_open,
        cam.k_stop,
        cs.image_z,
        cam.rear_z,
        cam.exit_pupil_z,
        cam.exit_pupil_magnification,
        cs.sensor,
        labels,
        sides,
    )
    return labels, sides


def direct_eye_plane(cs: CompiledScene, seed: int, n_sub: int = 16) -> np.ndarray:
    """Direct LED irradiance (W/mm²) toward the eye over the eye-plane bins, row 0 at +y
    (n_sub² jittered points per bin, each with shadow rays to the LEDs)."""
    out = np.empty((int(cs.plane[3]), int(cs.plane[2])))
    F.plane_direct(
        seed,
        cs.sf,
        cs.si,
        cs.leds,
        cs.scene.leds.radiant_intensity_w_sr,
        cs.alpha_grid,
        cs.intensity_grid,
        cs.plane,
        n_sub,
        out,
    )
    return out
