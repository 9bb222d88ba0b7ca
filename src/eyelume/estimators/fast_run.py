"""Running the fast estimator: rounds of camera samples and light paths, a per-pixel variance,
and stopping at a ray budget or at a target relative error (see :mod:`.fast` for the physics)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numba
import numpy as np

from eyelume.compile import CompiledScene
from eyelume.errors import BudgetError, GeometryError
from eyelume.estimators import fast as F
from eyelume.estimators.interrupt import interrupt_between_batches
from eyelume.estimators.statistics import median_pixel_rel_error
from eyelume.kernels import geometry as G
from eyelume.kernels.tables import G_COS, G_P, INDIRECT_COLS

__all__ = [
    "FastEstimate",
    "RunControl",
    "direct_eye_plane",
    "estimate_median_rel_error",
    "primary_surface_map",
    "trace_fast",
    "with_indirect_cache",
]

_MAX_SETS = 1 << 16


@dataclass
class FastEstimate:
    """What the fast estimator returns (W/mm² unless stated).

    ``image`` is the mean image-plane irradiance per pixel and ``variance`` the estimated
    variance of that mean, from the second moments of independent samples. ``glint_images``
    (n_leds, rows, cols) is the part carried by paths that met no Lambertian face, per LED.

    A run interrupted after a single camera set has an unbiased ``image`` (the mean of that
    set and of the light paths done) but no spread to estimate a variance from: ``variance``
    is then +inf everywhere and ``variance_dof`` 0 ("unknown").

    A run interrupted inside its first round keeps the pixels that round finished
    (``covered_pixels`` < rows × cols, in row-major order from the top row): their values
    are unbiased (their camera sets, plus the light paths traced alongside, in proportion);
    the other pixels are NaN (missing).
    """

    image: np.ndarray
    variance: np.ndarray
    glint_images: np.ndarray
    samples_per_pixel: int
    light_paths: int
    interrupted: bool
    variance_dof: int  # degrees of freedom of each pixel's variance (sets − 1; 0: unknown)
    target_reached: bool | None = None  # rel_error runs: whether the target was reached
    rel_error_achieved: float | None = None  # rel_error runs: the median error reached
    covered_pixels: int | None = None  # first round interrupted: pixels finished (else None)
    #: (2, rows, cols): the glint light's centroid in each pixel, pixels from its centre
    #: (columns, rows; 0 where it has none): where the PSF spreads it from (detectors.psf)
    glint_offsets: np.ndarray | None = None


#: Work between two looks at the Ctrl-C flag: camera samples (pixels × sets × grid²) and light
#: paths per kernel call — a fraction of a second each on this project's 2-core machine, so an
#: interrupt is answered within about a second even in a 4096 × 4096 render. Chunking changes no
#: result: a pixel's camera samples depend on its index and the seed only, and light paths add
#: integer fixed-point sums.
CHUNK_SAMPLES = 1 << 15
CHUNK_PATHS = 1 << 16

#: Stratification grids: sets of 4 × 4 camera samples from 32 samples per pixel on, else of 2 × 2.
#: Larger sets stratify better; two sets at least are needed for a variance.
GRID_FINE, GRID_COARSE, GRID_SINGLE = 4, 2, 1


class _Run:
    """Σm, Σm² of the camera sets and fixed-point sums of the light paths' deposits, and the
    rounds that add to them."""

    def __init__(self, cs: CompiledScene, grid: int, seed: int) -> None:
        rows, cols = cs.picture.rows, cs.picture.cols
        nled = cs.led.points.shape[0]
        chunks = numba.get_num_threads()
        self.grid = grid
        self.seed = seed
        self.cam_sum = np.zeros((rows, cols))
        self.cam_sq = np.zeros((rows, cols))
        self.light = np.zeros((chunks, rows, cols), dtype=np.int64)
        self.light_sq = np.zeros((chunks, rows, cols), dtype=np.int64)
        self.led = np.zeros((chunks, nled, rows, cols), dtype=np.int64)
        self.moment = np.zeros((chunks, 2, rows, cols), dtype=np.int64)
        self.sets = 0
        self.paths = 0
        self.covered = 0  # first round stopped: pixels (flat, row-major) it finished
        self.covered_sets = 0
        sf, cornea = cs.sf, cs.camera.cornea
        i0 = float(np.max(cs.led.i0))  # the brightest LED's: a bound on every deposit's scale
        centre, rb = sf[cornea, G.BX : G.BZ + 1], sf[cornea, G.BR]
        dist = np.linalg.norm(cs.led.points - centre, axis=1)
        if np.any(dist <= rb):
            raise GeometryError("an LED lies inside the cornea's bounding sphere")
        cone = 2 * math.pi * (1 - np.sqrt(1 - (rb / dist) ** 2))
        pic = cs.picture
        per_mm2 = pic.cols * pic.rows / (pic.width_mm * pic.height_mm)
        c_typ = i0 * nled * float(cone.max()) * per_mm2
        # a draw aimed at a glint (CameraTables.glint_aim) weighs its cone's solid angle over
        # its probability, ~2⁻¹¹ of a whole-cornea draw's on vr-offaxis: the units follow the
        # smallest, so that its deposit (× R) and square keep 18 and 9 bits
        ga = cs.camera.glint_aim
        aimed = ga[:, G_P] > 0.0
        if aimed.any():
            ratio = 2 * math.pi * (1 - ga[aimed, G_COS]) / ga[aimed, G_P] / cone[aimed]
            c_typ *= min(1.0, float(ratio.min()))
        self.q = c_typ * 2.0**-24
        self.q2 = c_typ * c_typ * 2.0**-20
        self.cs = cs

    def tally(self) -> F.Tally:
        """The light paths' sums as :func:`~eyelume.estimators.fast.light_pass` takes them."""
        return F.Tally(self.light, self.light_sq, self.led, self.moment, self.q, self.q2)

    @property
    def samples_per_pixel(self) -> int:
        return self.sets * self.grid * self.grid

    def add(
        self,
        n_sets: int,
        paths_per_sample: float,
        stop=None,
        tick: Callable[[int], None] | None = None,
    ) -> bool:
        """Add ``n_sets`` camera sets to every pixel and light paths in proportion, in chunks
        (:data:`CHUNK_SAMPLES`, :data:`CHUNK_PATHS`), looking at ``stop.requested`` between
        chunks. A round stopped among its camera chunks is undone (every pixel keeps the same
        sets) and False returned — except the first round, which keeps the pixels it finished
        (``covered``; :class:`FastEstimate`), its light paths traced after each camera chunk in
        proportion to the pixels done, so that what it finished is whole. Stopped among its
        light chunks, the paths done are kept (each is an independent sample). The order of
        the chunks changes no result (a pixel's samples depend on its index, its set and the
        seed; a path's on its index and the seed). ``tick(units)`` after each chunk: camera
        samples or paths."""
        every = np.arange(self.cam_sum.size, dtype=np.int64)
        flat_sum, flat_sq = self.cam_sum.reshape(-1), self.cam_sq.reshape(-1)
        per = max(1, CHUNK_SAMPLES // (n_sets * self.grid * self.grid))
        threads = numba.get_num_threads()
        first = self.sets == 0
        paths_end = int(round(paths_per_sample * (self.sets + n_sets) * self.grid**2))
        saved = []
        for a in range(0, every.size, per):
            b = min(every.size, a + per)
            if stop is not None and stop.requested:
                if first:  # keep the pixels finished: nothing else to fall back on
                    self.covered, self.covered_sets = a, n_sets
                    return False
                for a0, s, q in saved:  # undo the partial round
                    flat_sum[a0 : a0 + s.size] = s
                    flat_sq[a0 : a0 + s.size] = q
                return False
            if stop is not None and not first:
                saved.append((a, flat_sum[a:b].copy(), flat_sq[a:b].copy()))
            # each thread takes an equal run of the pixels handed to the kernel, and a pixel can
            # cost several times its neighbour rows' (the iris): dealt round-robin, every
            # thread's run spans the whole chunk (the sums are per pixel: same result)
            idx = np.concatenate([every[a + t : b : threads] for t in range(threads)])
            sums = F.CameraSums(idx, flat_sum[idx], flat_sq[idx])
            cs = self.cs
            F.camera_pass(self.seed, self.sets, n_sets, cs.tables, cs.camera, self.grid, sums)
            flat_sum[idx], flat_sq[idx] = sums.total, sums.squares
            if tick:
                tick((b - a) * n_sets * self.grid * self.grid)
            if first:
                self._light_to(paths_end * b // every.size, stop, tick)
        del saved
        self.sets += n_sets
        self._light_to(paths_end, stop, tick)
        return True

    def _light_to(self, end: int, stop, tick) -> None:
        """Light paths up to path index ``end``, in chunks, until ``stop.requested``."""
        while self.paths < end and not (stop is not None and stop.requested):
            c = min(CHUNK_PATHS, end - self.paths)
            F.light_pass(self.seed, self.paths, c, self.cs.tables, self.cs.camera, self.tally())
            self.paths += c
            if tick:
                tick(c)

    def estimate(self, interrupted: bool) -> FastEstimate:
        n = self.sets or self.covered_sets
        if n < 1 or (self.sets == 0 and self.covered == 0):
            raise ValueError("no camera set has finished: nothing to estimate")
        mean_c = self.cam_sum / n
        if n >= 2:
            # the variance of a mean of n independent sets: the unbiased sample variance / n
            var_c = np.maximum(self.cam_sq - n * mean_c**2, 0.0) / (n * (n - 1))
        else:  # one set: the mean is unbiased, its variance unknown
            var_c = np.full_like(mean_c, np.inf)
        if self.sets == 0:  # the first round stopped: the pixels it did not reach are missing
            mean_c.reshape(-1)[self.covered :] = np.nan
            var_c.reshape(-1)[self.covered :] = np.nan
        if self.paths:
            m = self.paths
            total, total_sq = self.light.sum(axis=0), self.light_sq.sum(axis=0)
            if max(total.max(initial=0), total_sq.max(initial=0)) > (1 << 62):
                raise BudgetError("fixed-point light sums near overflow: use fewer light paths")
            mean_l = total.astype(float) * (self.q / m)
            s2 = total_sq.astype(float) * self.q2
            var_l = np.maximum(s2 - m * mean_l**2, 0.0) / (m * max(m - 1, 1))
            led = self.led.sum(axis=0)
            glints = led.astype(float) * (self.q / m)
            total_g = led.sum(axis=0).astype(float)
            offsets = self.moment.sum(axis=0) / np.where(total_g > 0, total_g, 1.0)
        else:
            mean_l = var_l = np.zeros_like(mean_c)
            glints = np.zeros(self.led.shape[1:])
            offsets = np.zeros((2, *mean_c.shape))
        return FastEstimate(
            mean_c + mean_l,
            var_c + var_l,
            glints,
            n * self.grid * self.grid,
            self.paths,
            interrupted,
            n - 1,
            covered_pixels=None if self.sets else self.covered,
            glint_offsets=offsets,
        )


#: Images with more pixels than this size a ``rel_error`` run's first round by a pilot on a
#: sample of :data:`_PILOT_PIXELS` target pixels (:func:`_pilot`).
PILOT_ABOVE = 50_000
_PILOT_PIXELS = 2048
#: The pilot's trials, in increasing order of grid: (grid, sets traced on each pilot pixel).
PILOT_OPTIONS = ((GRID_SINGLE, 4), (GRID_COARSE, 4), (GRID_FINE, 2))


def _pilot(  # noqa: PLR0913
    cs: CompiledScene,
    seed: int,
    target: np.ndarray,
    rel_error: float,
    variance_ratio: float,
    max_grid: int = GRID_FINE,
) -> tuple[int, int]:
    """(grid, sets) expected to reach ``rel_error`` in the median target pixel at the least
    cost, from 4 sets of 1 × 1, 4 sets of 2 × 2 and 2 sets of 4 × 4 on up to 2048 target pixels
    (their own samples: a pixel's samples depend on its index and the seed only). The pilot's
    pixels are scattered, so the delivered picture's error is predicted from the traced one's
    by ``variance_ratio`` (:class:`RunControl`). The prediction aims at the target itself; if
    the first round falls short, the run adds a round.

    A grid's choice costs two sets at least (2 × grid² samples per pixel): a grid whose least
    cost is not below the best choice so far is not traced, as it could not be chosen (a tie
    keeps the earlier, smaller grid) — the same choice, without the pilot's most expensive
    sets when a smaller grid already needs few samples (vr-offaxis: 4 per pixel, where the
    4 × 4 sets alone cost 32 samples on each of the 2048 pixels, ~10 % of the render). Grids
    finer than ``max_grid`` are not tried: their two sets would be over the run's cap of
    samples per pixel (:func:`_largest_grid`)."""
    idx = np.flatnonzero(target.reshape(-1))
    if idx.size > _PILOT_PIXELS:
        idx = np.sort(np.random.default_rng(seed).choice(idx, _PILOT_PIXELS, replace=False))
    best = (max_grid, 2, math.inf)
    for grid, n in PILOT_OPTIONS:
        if grid > max_grid or 2 * grid * grid >= best[2]:
            continue
        s1, s2 = np.zeros(idx.size), np.zeros(idx.size)
        sums = F.CameraSums(idx.astype(np.int64), s1, s2)
        F.camera_pass(seed, 0, n, cs.tables, cs.camera, grid, sums)
        mean = s1 / n
        var = np.maximum(s2 - n * mean**2, 0.0) / (n * (n - 1))
        err = median_pixel_rel_error(mean[mean > 0], var[mean > 0], n - 1)
        err *= math.sqrt(variance_ratio)
        sets = max(2, math.ceil(min(n * _squared_ratio(err, rel_error), _MAX_SETS + 1)))
        cost = sets * grid * grid
        if cost < best[2]:
            best = (grid, sets, cost)
    return best[0], min(best[1], _MAX_SETS)


def _largest_grid(cap: int) -> int:
    """The finest camera grid whose two sets (the fewest a variance needs) stay within ``cap``
    samples per pixel: 2 × grid² ≤ cap (cap ≥ 2, :func:`trace_fast` checks it).

    >>> [_largest_grid(c) for c in (2, 7, 8, 31, 32, 4096)]
    [1, 1, 2, 2, 4, 4]
    """
    return next(g for g in (GRID_FINE, GRID_COARSE, GRID_SINGLE) if 2 * g * g <= cap)


def first_round(samples_per_pixel: int, cap: int) -> tuple[int, int]:
    """(grid, sets) of a ``rel_error`` run's first round when no pilot sizes it: the budget's
    (:func:`planned_sets`) on a grid no finer than :func:`_largest_grid` of ``cap``, and never
    more sets than fit under the cap (two at least).

    >>> [first_round(32, 4096), first_round(32, 16), first_round(8, 4), first_round(8, 2)]
    [(4, 2), (2, 4), (1, 4), (1, 2)]
    """
    grid = min(planned_sets(samples_per_pixel)[0], _largest_grid(cap))
    return grid, max(2, min(math.ceil(samples_per_pixel / grid**2), cap // grid**2))


def planned_sets(samples_per_pixel: int) -> tuple[int, int]:
    """(grid, sets) of a fixed budget: sets of 4 × 4 camera samples from 32 samples per pixel on,
    else of 2 × 2, rounded up to whole sets and two at least (a variance needs two), so the
    samples rendered are ``sets × grid²`` ≥ the samples asked (1 → 8, 9 → 12, 33 → 48).

    >>> [planned_sets(n) for n in (1, 8, 9, 31, 32, 33)]
    [(2, 2), (2, 2), (2, 3), (2, 8), (4, 2), (4, 3)]
    """
    grid = GRID_FINE if samples_per_pixel >= 2 * GRID_FINE**2 else GRID_COARSE
    return grid, max(2, math.ceil(samples_per_pixel / grid**2))


def array_bytes(cs: CompiledScene) -> int:
    """Bytes of the fast estimator's per-pixel arrays for ``cs``: Σm and Σm² of the camera sets
    (and their undo copies for a round stopped by Ctrl-C), and each Numba thread's fixed-point
    light and per-LED glint sums and the glints' two moments — what grows with the picture (a
    4096 × 4096 picture, 4 LEDs, 2 threads: 2.7 GB)."""
    pixels = cs.picture.cols * cs.picture.rows
    chunks = numba.get_num_threads()
    return 8 * pixels * (4 + chunks * (4 + int(cs.led.points.shape[0])))


def pilot_rates(
    cs: CompiledScene, seed: int, grid: int, pixels: int = 256, paths: int = 4096
) -> tuple[float, float]:
    """(camera samples per second, light paths per second) of this scene on this machine: one
    set on ``pixels`` evenly spread pixels and ``paths`` light paths, into throwaway sums (the
    light paths onto a 1 × 1 pixel array of the same sensor), so a run's own samples are not
    touched. A projection, not a promise: the machine's load varies. Call it after
    :func:`warm_up`, or it times the compilation."""
    import time

    total = cs.picture.cols * cs.picture.rows
    idx = np.unique(np.linspace(0, total - 1, min(pixels, total)).astype(np.int64))
    # pixel indices address the full sensor; the sums are throwaway arrays of idx's length
    tiny = _tiny(cs)
    run = _Run(tiny, grid, seed)  # its sums without full-size arrays
    s1, s2 = np.zeros(idx.size), np.zeros(idx.size)
    t0 = time.perf_counter()
    F.camera_pass(seed, 0, 1, cs.tables, cs.camera, grid, F.CameraSums(idx, s1, s2))
    cam_rate = idx.size * grid * grid / max(time.perf_counter() - t0, 1e-9)
    t0 = time.perf_counter()
    F.light_pass(seed, 0, paths, tiny.tables, tiny.camera, run.tally())
    return cam_rate, paths / max(time.perf_counter() - t0, 1e-9)


def kernels_cached(dispatchers: tuple | None = None) -> bool | None:
    """Whether Numba's on-disk cache holds the kernels (default: the fast estimator's; False:
    the first call compiles them, ~45 s on this project's machine; None: cannot tell). True
    also when they are already loaded in this process."""
    disp = dispatchers or (F.camera_pass, F.light_pass)
    if all(d.signatures for d in disp):
        return True
    try:
        return all(bool(d._cache._cache_file._load_index()) for d in disp)
    except Exception:  # noqa: BLE001 - Numba internals: unknown rather than wrong
        return None


def warm_up(cs: CompiledScene) -> float:
    """Compile (or load from Numba's cache) the fast estimator's kernels with calls that do no
    work; returns the seconds it took (0 when already loaded in this process), so that render
    times exclude compilation."""
    import time

    if all(d.signatures for d in (F.camera_pass, F.light_pass, F.plane_direct)):
        return 0.0
    t0 = time.perf_counter()
    tiny = _tiny(cs)
    run = _Run(tiny, GRID_COARSE, 0)  # the kernels' arguments, 1 × 1 pixel arrays
    none = F.CameraSums(np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0))
    F.camera_pass(0, 0, 1, tiny.tables, tiny.camera, GRID_COARSE, none)
    F.light_pass(0, 0, 0, tiny.tables, tiny.camera, run.tally())
    direct_eye_plane(tiny, 0, n_sub=1)
    if cs.scene.run.indirect == "cache":
        F.indirect_cache(0, tiny.tables, tiny.camera, 1.0, 1, np.zeros((0, 0, INDIRECT_COLS)))
    return time.perf_counter() - t0


def _tiny(cs: CompiledScene) -> CompiledScene:
    """``cs`` with a 1 × 1 sensor and eye plane (only array sizes differ: the same kernel
    types, so the same compiled code)."""
    import dataclasses

    t = cs.tables
    one = {"cols": 1, "rows": 1}
    tables = t._replace(picture=t.picture._replace(**one), eye_plane=t.eye_plane._replace(**one))
    return dataclasses.replace(cs, tables=tables)


#: The command line's default cap on the camera samples per pixel of a ``--rel-error`` render
#: (``--max-samples``): 23 M camera samples at 87 × 65. The API's default cap is the hard limit of
#: 65 536 sets per pixel.
MAX_SAMPLES_REL_ERROR = 4096


@dataclass
class RunControl:
    """How a fast run reports its work and where a ``rel_error`` run stops.

    ``advance(done, planned)`` is called after each chunk of work, in camera samples plus light
    paths (``planned`` grows with ``rel_error`` rounds); ``max_samples_per_pixel`` caps a
    ``rel_error`` run (None: 65 536 sets, the hard limit): at least 2, and the run's grid is the
    finest whose two sets fit under it (:func:`_largest_grid`), so that no run renders more.

    ``deliver(image, variance)`` maps the traced picture's mean and variance (rows, cols; W/mm²,
    (W/mm²)²) to the picture the caller delivers — :func:`eyelume.render.render` passes the
    camera's PSF, which averages neighbouring pixels' independent noise — so a ``rel_error`` run
    stops when the *delivered* picture's median target pixel reaches the target (the error its
    result reports). ``variance_ratio`` is that map's ratio of a pixel's relative variance after
    to before among similar neighbours (Σ K² for a kernel K of sum 1), used by the pilot, whose
    scattered pixels cannot be convolved. None and 1.0: the traced picture is delivered."""

    advance: Callable[[int, int], None] | None = None
    max_samples_per_pixel: int | None = None
    deliver: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]] | None = None
    variance_ratio: float = 1.0


class _Work:
    """Work done and planned, in camera samples plus light paths, for ``advance``."""

    def __init__(self, pixels: int, ratio: float, advance) -> None:
        self.pixels, self.ratio, self.advance = pixels, ratio, advance
        self.done = self.planned = 0

    def plan(self, run: _Run, sets_total: int) -> None:
        spp = sets_total * run.grid * run.grid
        self.planned = spp * self.pixels + int(round(self.ratio * spp))

    def tick(self, units: int) -> None:
        self.done += units
        if self.advance:
            self.advance(self.done, max(self.planned, self.done))


def _say(progress, run: _Run, err: float | None = None) -> None:
    if progress:
        tail = "" if err is None else f": median relative error {err:.4f}"
        progress(f"{run.samples_per_pixel} samples per pixel{tail}")


def _squared_ratio(err: float, rel_error: float) -> float:
    """(err / rel_error)², the factor of samples a target still needs; inf beyond 10¹⁸, where
    the float square would overflow (a target of 1e-160 raised OverflowError)."""
    r = err / rel_error
    return r * r if r < 1e9 else math.inf


def _over_cap(progress, rel_error: float, samples: float, cap: int) -> None:
    if progress and samples > cap:
        if not math.isfinite(samples):
            need = "an unknown number of"
        else:
            need = f"~{int(samples):,}" if samples < 1e9 else f"~{samples:.2g}"
        progress(
            f"the target {rel_error:g} needs {need} samples per pixel, over the cap "
            f"of {cap}: rendering to the cap"
        )


def _fixed_budget(args: tuple, stop, work: _Work, progress) -> _Run:
    """Rounds of a fixed budget; ``args`` = (cs, samples_per_pixel, ratio, seed)."""
    cs, samples_per_pixel, ratio, seed = args
    grid, sets = planned_sets(samples_per_pixel)
    run = _Run(cs, grid, seed)
    work.plan(run, sets)
    step = max(1, math.ceil(sets / 8))
    while run.sets < sets and not stop.requested:
        run.add(min(step, sets - run.sets), ratio, stop, work.tick)
        _say(progress, run)
    return run


def _to_target(args: tuple, stop, work: _Work, progress, target: tuple, control: RunControl):
    """(run, error reached): rounds until ``target = (rel_error, pixels)`` is met by the
    delivered picture (``control.deliver``) or ``cap`` samples per pixel; ``args`` = (cs,
    samples_per_pixel, ratio, seed, cap)."""
    cs, samples_per_pixel, ratio, seed, cap = args
    rel_error, target_pixels = target

    def judged(est: FastEstimate) -> float:
        if control.deliver is not None:
            image, variance = control.deliver(est.image, est.variance)
            est = replace(est, image=image, variance=variance)
        return estimate_median_rel_error(est, target_pixels)

    max_grid = _largest_grid(cap)
    grid, sets = first_round(samples_per_pixel, cap)
    if (
        cs.picture.cols * cs.picture.rows > PILOT_ABOVE
        and target_pixels is not None
        and (target_pixels.any())
    ):
        grid, sets = _pilot(cs, seed, target_pixels, rel_error, control.variance_ratio, max_grid)
        if progress:
            progress(f"pilot: {grid}×{grid} sets, {sets * grid * grid} samples per pixel")
        _over_cap(progress, rel_error, sets * grid * grid, cap)
    max_sets = max(2, min(_MAX_SETS, cap // (grid * grid)))
    run = _Run(cs, grid, seed)
    first = max(2, min(sets, max_sets))
    work.plan(run, first)
    err = math.inf
    if run.add(first, ratio, stop, work.tick):
        err = judged(run.estimate(False))
        _say(progress, run, err)
        if err > rel_error:
            _over_cap(
                progress, rel_error, run.samples_per_pixel * _squared_ratio(err, rel_error), cap
            )
    while err > rel_error and run.sets < max_sets and not stop.requested:
        need = run.sets * _squared_ratio(err, rel_error) * 1.1
        n_more = int(min(max(need - run.sets, 1), 4 * run.sets, max_sets - run.sets))
        work.plan(run, run.sets + n_more)
        if not run.add(n_more, ratio, stop, work.tick):
            break
        err = judged(run.estimate(False))
        _say(progress, run, err)
    # The glints are the light paths' alone (a point LED's specular image cannot be met by a
    # camera path) and the stopping rule looks at the skin; each LED's light paths aim a share
    # of their draws at its glint (CameraTables.glint_aim), so a run that stops at 2 or 3
    # samples per pixel gives each glint ~1e4 paths: on vr-offaxis a glint's power to 1.3–4.4 %
    # from 320 000 paths, where 640 000 drawn over the whole cornea gave 42–89 % (a floor of
    # light paths once made up for that; no longer needed).
    return run, err


def trace_fast(
    cs: CompiledScene,
    samples_per_pixel: int,
    light_paths: int,
    seed: int,
    rel_error: float | None = None,
    progress: Callable[[str], None] | None = None,
    target_pixels: np.ndarray | None = None,
    control: RunControl | None = None,
) -> FastEstimate:
    """Run the fast estimator.

    With ``rel_error`` None: ``samples_per_pixel`` camera samples (:func:`planned_sets`:
    whole sets of 4 × 4 from 32 on, else 2 × 2, at least two) and ``light_paths`` light paths,
    in rounds. With ``rel_error``: the same ratio of light paths to camera samples, and camera
    sets added until the median pixel's relative standard error over ``target_pixels`` (a
    boolean mask; default all pixels with signal) is at most ``rel_error``: the first round is
    the ``samples_per_pixel`` budget (its grid as above), each next round sized from the error
    so far — but never beyond ``control.max_samples_per_pixel`` (:class:`RunControl`): a
    target that needs more stops there (``target_reached`` False, ``rel_error_achieved`` the
    error reached, and ``progress`` says so as soon as the projection shows it).

    Ctrl-C (SIGINT) or SIGTERM is looked at between chunks of a fraction of a second
    (:data:`CHUNK_SAMPLES`): it ends the run with the whole rounds finished (``interrupted``;
    a round stopped half way is undone, so every pixel holds the same sets). With one camera
    set finished the image is that set's unbiased mean and the variance unknown (+inf,
    ``variance_dof`` 0); with none, KeyboardInterrupt (nothing usable finished).
    ``progress(message)`` is called after each round, ``control.advance`` after each chunk.
    """
    control = control or RunControl()
    cap = control.max_samples_per_pixel
    cap = _MAX_SETS * GRID_FINE**2 if cap is None else cap
    if samples_per_pixel < 1:
        raise BudgetError(f"samples_per_pixel = {samples_per_pixel}: must be ≥ 1")
    if light_paths < 0:
        raise BudgetError(f"light_paths = {light_paths}: must be ≥ 0")
    if rel_error is not None and not 0.0 < rel_error < 1.0:
        raise BudgetError(f"rel_error = {rel_error}: must be in (0, 1)")
    if cap < 2:
        raise BudgetError(
            f"max_samples_per_pixel = {cap}: must be ≥ 2 (a rel_error run's error is the "
            "scatter between two sample sets at least)"
        )
    ratio = light_paths / samples_per_pixel  # light paths per camera sample
    cs = with_indirect_cache(cs, seed)
    work = _Work(cs.picture.cols * cs.picture.rows, ratio, control.advance)
    args = (cs, samples_per_pixel, ratio, seed)
    with interrupt_between_batches() as stop:
        if rel_error is None:
            run, err = _fixed_budget(args, stop, work, progress), math.inf
        else:
            target = (rel_error, target_pixels)
            run, err = _to_target((*args, cap), stop, work, progress, target, control)
    if run.sets == 0 and run.covered == 0:
        raise KeyboardInterrupt("interrupted before a camera set finished: nothing usable")
    est = run.estimate(stop.requested)
    if rel_error is not None:
        est.target_reached = err <= rel_error
        est.rel_error_achieved = err if math.isfinite(err) else None
    return est


#: The irradiance cache reads a point from a vertex at most this many times the distance to
#: the farthest of its neighbours (the next points along the picture's rows and columns) on
#: the same face with a normal alike (:data:`~eyelume.estimators.fast.CACHE_MIN_COS`).
CACHE_REACH = 1.5
_CACHE_SEED_TAG = 0x1CAC


def with_indirect_cache(cs: CompiledScene, seed: int) -> CompiledScene:
    """``cs`` with its irradiance cache (``run.indirect = "cache"``;
    :func:`eyelume.estimators.fast.indirect_cache`) built for this picture and ``seed`` into
    ``cs.camera.indirect``, or ``cs`` itself (``run.indirect = "paths"``, or built already).
    Points every ``run.indirect_cache_spacing`` pixels, ``run.indirect_cache_grid``² rays
    each. A point's reach is :data:`CACHE_REACH` × the distance to its farthest neighbour on
    the same face with a normal alike (a point with none is read by no vertex);
    ``indirect_tol`` the median reach (mm). The cache's seed is derived from ``seed``, so the
    same seed gives the same cache whatever the threads."""
    run = cs.scene.run
    if run.indirect != "cache" or cs.camera.indirect.shape[0] > 0:
        return cs
    import dataclasses

    from eyelume.estimators.fast import CACHE_MIN_COS

    k = int(run.indirect_cache_spacing)
    nx = -(-cs.picture.cols // k) + 1
    ny = -(-cs.picture.rows // k) + 1
    out = np.zeros((ny, nx, INDIRECT_COLS))
    cseed = int(np.random.SeedSequence([seed, _CACHE_SEED_TAG]).generate_state(1)[0] >> 1)
    F.indirect_cache(cseed, cs.tables, cs.camera, float(k), int(run.indirect_cache_grid), out)
    far = np.zeros((ny, nx))
    on = out[..., 7] >= 0
    for axis in (0, 1):
        a = [slice(None)] * 2
        b = [slice(None)] * 2
        a[axis], b[axis] = slice(1, None), slice(None, -1)
        pa, pb = out[tuple(a)], out[tuple(b)]
        alike = (
            (pa[..., 7] == pb[..., 7])
            & on[tuple(a)]
            & ((pa[..., 3:6] * pb[..., 3:6]).sum(axis=-1) >= CACHE_MIN_COS)
        )
        d = np.where(alike, np.linalg.norm(pa[..., :3] - pb[..., :3], axis=-1), 0.0)
        far[tuple(a)] = np.maximum(far[tuple(a)], d)
        far[tuple(b)] = np.maximum(far[tuple(b)], d)
    out[..., 9] = CACHE_REACH * far
    reach = out[..., 9][on & (far > 0)]
    tol = float(np.median(reach)) if reach.size else 0.0
    camera = cs.camera._replace(indirect=out, indirect_spacing=float(k), indirect_tol=tol)
    return dataclasses.replace(cs, camera=camera)


def estimate_median_rel_error(est: FastEstimate, pixels: np.ndarray | None = None) -> float:
    """The median pixel's relative standard error of an estimate over ``pixels`` (default:
    every pixel with signal), corrected for the spread of few-set variance estimates
    (:func:`eyelume.estimators.statistics.median_pixel_rel_error`)."""
    mask = est.image > 0 if pixels is None else (pixels & (est.image > 0))
    if not mask.any():
        return math.inf
    return median_pixel_rel_error(est.image[mask], est.variance[mask], est.variance_dof)


def primary_surface_map(cs: CompiledScene) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) index of the surface each pixel sees in the ideal image (−1: none), and
    the side it is seen from (1: side B, where the surface normal points), through the
    optical elements along the camera's view (``cs.view_branch``). Mapped in bands of
    rows (about :data:`CHUNK_SAMPLES` × 4 pixels each), so Ctrl-C interrupts a large sensor's
    map between bands instead of minutes later."""
    shape = (cs.picture.rows, cs.picture.cols)
    labels = np.empty(shape, dtype=np.int64)
    sides = np.zeros(shape, dtype=np.int64)
    band = max(1, (4 * CHUNK_SAMPLES) // shape[1])
    view = cs.view_branch
    if view is None:
        view = np.full(cs.sf.shape[0], -1, dtype=np.int64)
    for r0 in range(0, shape[0], band):
        band_labels, band_sides = labels[r0 : r0 + band], sides[r0 : r0 + band]
        F.primary_surfaces(cs.tables, cs.camera, view, r0, band_labels, band_sides)
    return labels, sides


def direct_eye_plane(cs: CompiledScene, seed: int, n_sub: int = 16) -> np.ndarray:
    """Direct LED irradiance (W/mm²) toward the eye over the eye-plane bins, row 0 at +y
    (n_sub² jittered points per bin, each with shadow rays to the LEDs)."""
    out = np.empty((cs.eye_plane.rows, cs.eye_plane.cols))
    F.plane_direct(seed, cs.tables, cs.camera, n_sub, out)
    return out
