"""Render a scene: eye image with its per-pixel noise, eye-plane irradiance, region statistics.

This is the Python API behind ``eyelume render``::

    import eyelume
    scene = eyelume.load_scene("paper2005", {"leds.height_mm": 40})
    from eyelume import RenderOptions
    result = eyelume.render(scene, RenderOptions(seed=1))          # the fast estimator
    result = eyelume.render(scene, RenderOptions(rel_error=0.01))  # … to 1 % in the median skin
    result = eyelume.render(scene, RenderOptions(estimator="forward", rays=2_000_000))  # forward MC
    result.eye_image          # (rows, cols) W/mm², row 0 at the top of the picture
    result.ledger             # forward only: {"sensor": W, "iris": W, ..., "escaped": W}

LEDs of several wavelengths (``leds.wavelength_nm`` a list) are rendered as a sum over
wavelength groups (:func:`eyelume.compile.wavelength_groups`): each group is compiled at its own
wavelength with only its LEDs emitting (:func:`eyelume.compile.compile_scene`) and rendered
with its own seed (:func:`group_seed`); the images, eye planes, variances (the groups are
independent), ledgers and glints add up, and the sensor's photo-electrons are the groups'
sum (:attr:`RenderResult.eye_image_at_scene_wavelength`). A scene whose LEDs all shine at its
``wavelength_nm`` renders as one, exactly as before groups existed.

Sunlight (``ambient.sun``) is rendered apart, after the LEDs: the scene compiled with the sun
as its only source (:func:`eyelume.compile.compile_scene` with ``sun``; its irradiance the
equivalent one at the scene's wavelength, :func:`eyelume.detectors.sensor.sunlight_band`), by
the same estimator and budget with its own seed (:func:`sun_seed`), kept in
:attr:`RenderResult.ambient`. ``eye_image`` stays the LEDs' picture; the sensor counts both
(:attr:`RenderResult.eye_image_at_scene_wavelength`), and the summary reports the glints' and
the pupil's signal to ambient (:func:`eyelume.analysis.ambient.signal_to_ambient`).
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from eyelume.analysis.ambient import signal_to_ambient
from eyelume.analysis.regions import glint_centres, region_masks, region_stats, with_glints
from eyelume.analysis.safety import eye_safety
from eyelume.analysis.truth import eye_truth
from eyelume.compile import (
    CONVERGING_SHARE_LIMIT,
    CompiledScene,
    SunSource,
    compile_scene,
    connected_by_newton,
    element_index,
    element_light_shares,
    single_wavelength,
    wavelength_groups,
)
from eyelume.detectors.psf import (
    PixelPsf,
    camera_psf,
    convolve_irradiance,
    convolve_variance,
    convolve_with_points,
    region_mean_variance,
)
from eyelume.detectors.receivers import BinnedPlane
from eyelume.detectors.sensor import (
    SunlightBand,
    count_weights,
    quantum_efficiency_at,
    sunlight_band,
)
from eyelume.errors import EyelumeWarning, SceneError
from eyelume.estimators.fast_run import RunControl, direct_eye_plane, trace_fast, warm_up
from eyelume.estimators.forward import trace_forward, trace_paths
from eyelume.estimators.statistics import median_pixel_rel_error
from eyelume.layout import VIEWS, Section, system_sections
from eyelume.scene.eye_models import DISPERSION_RANGE_NM
from eyelume.scene.model import Scene

__all__ = [
    "AmbientRender",
    "GroupRender",
    "RenderExtras",
    "RenderOptions",
    "RenderResult",
    "check_sensor_spectra",
    "group_seed",
    "render",
    "render_extras",
    "sun_seed",
]


#: Mixed into a wavelength group's seed (:func:`group_seed`) so its stream is apart from any
#: other use of the scene's seed.
_GROUP_SEED_TAG = 0x57A7E1E6


def group_seed(seed: int, index: int) -> int:
    """The seed of wavelength group ``index`` (0, 1, … in order of increasing wavelength) of a
    render with ``seed``, in a scene whose LEDs have several wavelengths: the first 63 bits of
    ``numpy.random.SeedSequence([seed, 0x57A7E1E6, index])``'s first 64-bit word — distinct,
    independent streams for the groups, the same for the same seed on any machine. (A scene of
    one wavelength group uses ``seed`` itself.)

    >>> group_seed(1, 0) == group_seed(1, 0) != group_seed(1, 1)
    True
    """
    state = np.random.SeedSequence([int(seed), _GROUP_SEED_TAG, int(index)])
    return int(state.generate_state(1, dtype=np.uint64)[0] >> np.uint64(1))


#: Mixed into the sunlight's seed (:func:`sun_seed`).
_SUN_SEED_TAG = 0x5A11CE


def sun_seed(seed: int) -> int:
    """The seed of the sunlight's render beside a render with ``seed``: the first 63 bits of
    ``numpy.random.SeedSequence([seed, 0x5A11CE])``'s first 64-bit word (a stream apart from
    the LEDs' and every wavelength group's).

    >>> sun_seed(1) == sun_seed(1) != sun_seed(2)
    True
    """
    state = np.random.SeedSequence([int(seed), _SUN_SEED_TAG])
    return int(state.generate_state(1, dtype=np.uint64)[0] >> np.uint64(1))


@dataclass
class AmbientRender:
    """The sunlight's picture beside a render's LEDs (:func:`render`, ``ambient.sun``).

    ``band``: how the sensor counts it (:class:`eyelume.detectors.sensor.SunlightBand`);
    ``eye_image`` and ``eye_image_variance`` ((rows, cols), W/mm² and (W/mm²)²): the sunlight's
    image-plane irradiance as light at the scene's wavelength giving the same photo-electrons
    (PSF applied at the sun's trace wavelength); ``seed``, ``rays`` (forward rays or camera
    samples plus light paths), ``interrupted``; ``direction_world``: unit vector toward the sun
    in the world frame (mirrored for a left eye)."""

    band: SunlightBand
    eye_image: np.ndarray
    eye_image_variance: np.ndarray
    seed: int
    rays: int
    interrupted: bool
    direction_world: tuple[float, float, float]

    def summary(self) -> dict:
        return {
            "sun": self.band.summary(),
            "direction_world": list(self.direction_world),
            "seed": self.seed,
            "rays": self.rays,
            "interrupted": self.interrupted,
        }


@dataclass
class GroupRender:
    """One wavelength group's share of a render (:func:`render`): its ``wavelength_nm``, its
    LEDs (``leds``, scene indices), the ``seed`` it was rendered with, its LEDs' power
    ``emitted_w`` (W), its eye image and that image's variance ((rows, cols), W/mm² and
    (W/mm²)²), and the rays (forward) or camera samples plus light paths (fast) it took."""

    wavelength_nm: float
    leds: tuple[int, ...]
    seed: int
    emitted_w: float
    eye_image: np.ndarray
    eye_image_variance: np.ndarray
    rays: int
    samples_per_pixel: int | None = None

    def summary(self) -> dict:
        out = {
            "wavelength_nm": self.wavelength_nm,
            "leds": list(self.leds),
            "seed": self.seed,
            "emitted_w": self.emitted_w,
            "rays": self.rays,
        }
        if self.samples_per_pixel is not None:
            out["samples_per_pixel"] = self.samples_per_pixel
        return out


@dataclass
class RenderResult:
    """What a render produces.

    Attributes
    ----------
    estimator : "forward" or "fast"
    eye_image : (rows, cols) float64
        Image-plane irradiance (W/mm²) binned over the sensor; row 0 is the top of the picture as
        a person views it (world +y), columns run with world +x as seen from the camera. The
        traced (geometric) irradiance convolved with the camera's point-spread function
        (``camera.psf``, :mod:`eyelume.detectors.psf`; each wavelength group with its own)
        when ``psf_parts`` is set.
    eye_image_variance : (rows, cols) float64
        Estimated variance of each pixel's value ((W/mm²)²): Poisson for the forward counts, the
        spread of independent samples for the fast estimator; with a PSF, K² ⊗ the traced
        pixels' variance (neighbouring pixels are then correlated: a region's mean takes its
        variance from the traced variance through the kernel, :meth:`region_stats`).
    psf_parts : list of (PixelPsf, (rows, cols) float64) or None
        The point-spread function applied and the traced pixels' variance before it, per
        wavelength group (one for a scene of one wavelength). None: ``camera.psf = "none"``,
        or a first round cut short, whose missing pixels leave nothing to convolve
        (``psf_skipped``).
    eye_plane : (rows, cols) float64
        Eye-plane irradiance (W/mm²) toward the eye over the receiver; row 0 at +y. Forward: all
        light crossing the plane toward the eye; fast: the LEDs' direct light (shadowed).
    regions : dict[str, (rows, cols) bool]
        Pupil, iris, sclera, skin and glint masks (:mod:`eyelume.analysis.regions`).
    rays : int
        Forward: rays traced. Fast: camera samples plus light paths.
    image_counts, plane_counts : int64 arrays or None
        Forward only: rays behind each bin.
    ledger : dict[str, float] or None
        Forward only: where the emitted power ended (W), summing to ``emitted_w``.
    picture_extent_mm, plane_extent_mm : (left, right, bottom, top)
        Millimetre coordinates of the picture (the sensor plane turned by 180°, so x_picture =
        −x_sensor and y_picture = −y_sensor) and of the eye plane (world x, y measured from
        the eye's nominal corneal vertex, :class:`eyelume.scene.model.EyePose`).
    """

    scene: Scene
    estimator: str
    rays: int
    seed: int
    wall_time_s: float
    emitted_w: float
    eye_image: np.ndarray
    eye_image_variance: np.ndarray
    eye_plane: np.ndarray
    regions: dict[str, np.ndarray]
    interrupted: bool
    picture_extent_mm: tuple[float, float, float, float]
    plane_extent_mm: tuple[float, float, float, float]
    ray_power_w: float | None = None
    image_counts: np.ndarray | None = None
    plane_counts: np.ndarray | None = None
    ledger: dict[str, float] | None = None
    interactions: int | None = None
    samples_per_pixel: int | None = None
    light_paths: int | None = None
    variance_dof: int | None = None
    kernel_load_s: float | None = None
    target_reached: bool | None = None
    rel_error_achieved: float | None = None
    covered_pixels: int | None = None  # fast, first round interrupted: pixels finished
    groups: list[GroupRender] | None = None  # LEDs of several wavelengths: each group's share
    psf_parts: list[tuple[PixelPsf, np.ndarray]] | None = None
    psf_skipped: bool = False  # the scene asks for a PSF but missing pixels left it unapplied
    ambient: AmbientRender | None = None  # ambient.sun: the sunlight's picture, apart
    # with elements: one line naming the truth's visible ghosts the picture does not resolve
    ghost_warning: str | None = None

    @property
    def psf(self) -> PixelPsf | None:
        """The PSF applied (the first wavelength group's), or None."""
        return self.psf_parts[0][0] if self.psf_parts else None

    @property
    def eye_image_at_scene_wavelength(self) -> np.ndarray:
        """The picture as the sensor counts it, LEDs and sunlight: :attr:`led_image_at_scene_
        wavelength` plus the ambient's picture (already counted at the scene's wavelength,
        :class:`AmbientRender`), (rows, cols) W/mm². Without ``ambient.sun``, the LEDs'."""
        led = self.led_image_at_scene_wavelength
        return led if self.ambient is None else led + self.ambient.eye_image

    @property
    def led_image_at_scene_wavelength(self) -> np.ndarray:
        """The LEDs' eye image as the sensor counts it: the irradiance at the scene's
        ``wavelength_nm`` that gives the same mean photo-electrons, (rows, cols) W/mm².

        A pixel's mean photo-electrons are Σ_g E_g p² t QE(λ_g) / (h c / λ_g) over the
        wavelength groups g (:mod:`eyelume.detectors.sensor`; with an LED spectral width, QE λ
        averaged over each group's spectrum), so this is Σ_g E_g w_g with
        w_g = :func:`eyelume.detectors.sensor.count_weights` (λ_g QE(λ_g) / (λ QE(λ)); λ_g / λ
        for a single-number QE), ready for :func:`eyelume.detectors.sensor.digitize` at the
        scene's wavelength. One wavelength, one QE number, no spectral width: ``eye_image``
        itself.

        Raises InputFileError or SceneError for a bad QE table or a wavelength outside it
        (:func:`render` checks these before tracing)."""
        sc = self.scene
        lam = float(sc.wavelength_nm)
        line = (
            isinstance(sc.sensor.quantum_efficiency, float)
            and not sc.leds.has_spectral_width
            and sc.sensor.filter is None
        )
        if not self.groups:
            if line:
                return self.eye_image
            (w,) = count_weights(sc.sensor, [lam], sc.leds.spectral_width_at(lam, lam), lam)
            return self.eye_image * w
        if line:
            return sum(g.eye_image * (g.wavelength_nm / lam) for g in self.groups)
        lams = [g.wavelength_nm for g in self.groups]
        widths = [sc.leds.spectral_width_at(x, lam) for x in lams]
        weights = count_weights(sc.sensor, lams, widths, lam)
        return sum(g.eye_image * w for g, w in zip(self.groups, weights, strict=True))

    @property
    def missing_pixels(self) -> int:
        """Pixels with no value (NaN): those an interrupted first round did not reach."""
        if self.covered_pixels is None:
            return 0
        return self.eye_image.size - self.covered_pixels

    @property
    def pixel_area_mm2(self) -> float:
        return BinnedPlane.picture(self.scene.sensor).bin_area_mm2

    def region_stats(self) -> dict[str, dict]:
        """Mean, median pixel and their relative standard errors per region."""
        finished = np.isfinite(self.eye_image)  # all but a cut first round's missing pixels
        mean_variance = None
        parts = self.psf_parts
        if parts and all(np.all(np.isfinite(v)) for _, v in parts):

            def mean_variance(mask: np.ndarray) -> float:
                return sum(region_mean_variance(mask, v, k) for k, v in parts)

        return region_stats(
            np.where(finished, self.eye_image, 0.0),
            np.where(finished, self.eye_image_variance, 0.0),
            {k: m & finished for k, m in self.regions.items()},
            self.pixel_area_mm2,
            self.variance_dof,
            mean_variance,
        )

    def _groups_summary(self) -> list[dict]:
        """Each wavelength group's summary, with how the sensor counts it: QE at its
        wavelength, its LEDs' spectral width and its photo-electrons per watt relative to
        light at the scene's wavelength (:func:`eyelume.detectors.sensor.count_weights`)."""
        sc, lam = self.scene, float(self.scene.wavelength_nm)
        lams = [g.wavelength_nm for g in self.groups or []]
        widths = [sc.leds.spectral_width_at(x, lam) for x in lams]
        weights = count_weights(sc.sensor, lams, widths, lam)
        out = []
        for g, w, k in zip(self.groups or [], widths, weights, strict=True):
            entry = g.summary()
            entry["sensor"] = {
                "quantum_efficiency": quantum_efficiency_at(sc.sensor, g.wavelength_nm),
                "spectral_width_nm": w,
                "electrons_relative_to_scene_wavelength": k,
            }
            out.append(entry)
        return out

    def ambient_summary(self) -> dict:
        """The sunlight's render and the signal to ambient (:mod:`eyelume.analysis.ambient`)."""
        amb = self.ambient
        assert amb is not None
        out = amb.summary()
        out.update(
            signal_to_ambient(self.led_image_at_scene_wavelength, amb.eye_image, self.regions)
        )
        if self.estimator == "forward":
            out["note"] = "the forward estimator labels no glint regions: glints not rated"
        out["units"] = "W/mm^2 of light at the scene's wavelength giving the same photo-electrons"
        return out

    def _psf_summary(self) -> dict | list | None:
        """The PSF applied (each wavelength group's kernel), or why not, or None."""
        if self.psf_parts:
            kernels = [k.summary() for k, _ in self.psf_parts]
            return kernels[0] if len(kernels) == 1 else kernels
        if self.psf_skipped:
            return {
                "kind": self.scene.camera.psf_used,
                "applied": False,
                "note": "not applied: the interrupted first round left pixels missing",
            }
        return None

    def summary(self) -> dict:
        """The run's summary as plain JSON-ready data (``summary.json``)."""
        out = {
            "scene": self.scene.name,
            "estimator": self.estimator,
            "rays": self.rays,
            "seed": self.seed,
            "interrupted": self.interrupted,
            "wall_time_s": round(self.wall_time_s, 4),
        }
        if self.kernel_load_s is not None:
            out["kernel_compile_s"] = round(self.kernel_load_s, 4)
        if self.estimator == "fast":
            out["samples_per_pixel"] = self.samples_per_pixel
            out["light_paths"] = self.light_paths
            if self.variance_dof == 0:
                out["note"] = (
                    "interrupted after one camera sample set: each pixel's value is the "
                    "unbiased mean of that set, but its variance is unknown (no spread of sets)"
                )
            if self.covered_pixels is not None:
                rows = self.covered_pixels // self.eye_image.shape[1]
                out["missing_pixels"] = self.missing_pixels
                out["note"] = (
                    f"interrupted in the first round: the first {self.covered_pixels} pixels "
                    f"(rows 0 to {rows - 1} whole, from the top) finished — camera samples and "
                    "light paths in proportion, unbiased; the other "
                    f"{self.missing_pixels} are missing (NaN in the .npy files, 0 DN in the "
                    "digital picture); region statistics cover the finished pixels"
                    + ("" if self.variance_dof else "; the variance is unknown (one set)")
                )
            if self.target_reached is not None:
                out["rel_error_target_reached"] = self.target_reached
                out["rel_error_achieved"] = self.rel_error_achieved
        else:
            out["surface_interactions"] = self.interactions
        if self.groups:
            out["wavelength_groups"] = self._groups_summary()
        sensor = float(self.eye_image.sum()) * self.pixel_area_mm2
        # a partial picture (missing pixels are NaN) has no sensor total: null, not NaN
        power = {"emitted": self.emitted_w, "sensor": sensor if math.isfinite(sensor) else None}
        if self.ledger is not None:
            power["absorbed"] = {
                k: v for k, v in self.ledger.items() if k not in ("sensor", "escaped") and v > 0
            }
            power["escaped"] = self.ledger["escaped"]
            power["sum"] = float(sum(self.ledger.values()))
        out["power_w"] = power
        psf = self._psf_summary()
        if psf is not None:
            out["psf"] = psf
        out["regions"] = self.region_stats()
        out.update({"ghost_warning": self.ghost_warning} if self.ghost_warning else {})
        if self.ambient is not None:
            out["ambient"] = self.ambient_summary()
        out["safety"] = eye_safety(self.scene)
        out["units"] = {"eye_image": "W/mm^2", "eye_plane": "W/mm^2", "power": "W"}
        return out


def warm_up_forward(cs: CompiledScene) -> float | None:
    """Compile (or load from Numba's cache) the forward tracer's kernel with a call that traces
    no ray; the seconds it took, 0 when already loaded, None when the kernel is not found (then
    the first batch compiles it, inside the render's time)."""
    from eyelume.estimators import forward

    kernel = getattr(forward, "_trace_batch", None)
    if kernel is None or not hasattr(kernel, "signatures"):
        return None
    if kernel.signatures:
        return 0.0
    t0 = time.perf_counter()
    z = np.zeros
    empty = forward.Counts(z((1, 1, 1), np.int64), z((1, 1, 1), np.int64),
                           z((1, len(cs.tallies)), np.int64), z((1, 1, 1), np.int64),
                           z((1, 2, 1, 1), np.int64))  # fmt: skip
    kernel(0, 0, 0, cs.tables, empty, z(1, np.int64))
    return time.perf_counter() - t0


@dataclass(frozen=True)
class RenderOptions:
    """The run options of :func:`render`: which estimator, its budget and the seed.

    Every field left ``None`` takes the scene's ``[run]`` value (:class:`eyelume.scene.model.Run`)
    when the render starts; the result depends on the scene and these options only, never on the
    progress callbacks given beside the options.

    Attributes
    ----------
    estimator : "fast", "forward" or None
        ``"fast"`` (:mod:`eyelume.estimators.fast`) or ``"forward"`` (plain forward Monte Carlo);
        default ``"forward"`` when ``rays`` is given, else the scene's ``run.estimator``. Any
        other value raises ``ValueError`` from :func:`render`.
    seed : int or None
        Random seed; default ``run.seed``.
    rays : int or None
        Forward: rays to trace (default ``run.rays``).
    batch_size : int or None
        Forward: rays per batch (default ``run.batch_size``); the result does not depend on it.
    samples_per_pixel : int or None
        Fast: camera samples per pixel (default ``run.samples_per_pixel``; with
        ``run.light_paths_per_pixel`` light paths per pixel and per 16 samples).
    rel_error : float or None
        Fast: keep adding rounds until the median skin pixel's relative standard error is this
        (a fraction, e.g. 0.01) or ``max_samples_per_pixel`` is reached (``target_reached``); in
        a picture that holds no skin pixel, the median pixel with signal's (an
        :class:`~eyelume.errors.EyelumeWarning` says so).
    max_samples_per_pixel : int or None
        Fast, with ``rel_error``: the cap on samples per pixel, at least 2 (else
        :class:`~eyelume.errors.BudgetError`; default: no cap below the fast run's hard limit,
        :class:`eyelume.estimators.fast_run.RunControl`; the CLI passes
        :data:`eyelume.estimators.fast_run.MAX_SAMPLES_REL_ERROR`).
    ambient_rel_error : float or None
        Fast, with ``rel_error`` and ``ambient.sun``: the sunlight's render's own target (its
        picture's median skin pixel, as ``rel_error`` for the LEDs'); default ``rel_error``.
        The two renders' noises are independent and add in variance, as the two sources'
        shot noises do (:func:`eyelume.optimize.render_budget.sensor_noise_target` gives each
        its own).

    Examples
    --------
    >>> RenderOptions(estimator="forward", rays=2_000_000, seed=1).rays
    2000000
    """

    estimator: str | None = None
    seed: int | None = None
    rays: int | None = None
    batch_size: int | None = None
    samples_per_pixel: int | None = None
    rel_error: float | None = None
    max_samples_per_pixel: int | None = None
    ambient_rel_error: float | None = None


#: What to do about a scene the fast estimator refuses, in a command that renders with it only
#: (evaluate-tracking, dataset): a forward render is no way out there (hundreds of frames at a
#: tracking budget: ~10³ × the fast estimator's time for the same noise through an element,
#: benchmarks/integrated.py), so the advice is the scene's. ``{element}`` names the element.
FAST_ONLY_ADVICE = (
    "{command} renders its frames with the fast estimator only (a forward render of each "
    "at its budget would be noise): move the LEDs so that less of their light meets "
    "{element} first (beside it on the eye side, as paper2005-integrated's ring sits beside "
    "its eyepiece), or take it out (--set elements=[])"
)


def check_estimator(
    scene: Scene,
    estimator: str,
    compiled: CompiledScene | None = None,
    *,
    command: str | None = None,
) -> None:
    """Refuse (SceneError) an estimator that cannot render ``scene`` well: the fast one for a
    scene where a converging lens or a curved mirror (an element whose LED light is not
    connected by Newton's method, :func:`eyelume.compile.connected_by_newton`: several roots)
    takes more than :data:`eyelume.compile.CONVERGING_SHARE_LIMIT` of some LED's flux first
    (:func:`eyelume.compile.element_light_shares`, computed on ``compiled`` or on the scene
    compiled here). Below it, that light (an LED beside an eyepiece grazing its front) is the
    light paths' alone — unbiased, as the forward agreement on paper2005-integrated checks
    (tests/estimators/test_integrated_agreement.py) — while every camera path through and off
    the element is traced from the camera, whatever its power.

    ``command``: a command that renders with the fast estimator only (evaluate-tracking,
    dataset): the refusal advises moving the LEDs (:data:`FAST_ONLY_ADVICE`), not ``eyelume
    render --estimator forward``, render's own way out."""
    if estimator != "fast" or not scene.elements:
        return
    curved = [
        k
        for k, el in enumerate(scene.elements)
        if not connected_by_newton(el, element_index(scene, k, el))
    ]
    if not curved:
        return
    cs = compiled if compiled is not None else compile_scene(scene)
    shares = element_light_shares(cs)
    for k in curved:
        led = int(np.argmax(shares[:, k]))
        share = float(shares[led, k])
        if share > CONVERGING_SHARE_LIMIT:
            el = scene.elements[k]
            what = "a curved mirror" if el.kind == "mirror" else "a converging lens"
            advice = (
                "render it with `eyelume render --estimator forward`"
                if command is None
                else FAST_ONLY_ADVICE.format(command=command, element=f"elements.{k}")
            )
            raise SceneError(
                f"estimator = 'fast': elements.{k} ({el.name or el.kind}) is {what} that takes "
                f"{share:.2%} of LED {cs.led_indices[led]}'s light first (more than "
                f"{CONVERGING_SHARE_LIMIT:.1%}), which the fast estimator leaves to its light "
                f"paths: {advice}"
            )


def check_sensor_spectra(scene: Scene) -> None:
    """Read and check the sensor's QE curve at every LED wavelength and spectrum and at the
    scene's wavelength (:func:`eyelume.detectors.sensor.count_weights`), so that a bad table
    fails before any tracing; and the sunlight's count (``ambient.sun``,
    :func:`eyelume.detectors.sensor.sunlight_band`). Raises InputFileError or SceneError (one
    line)."""
    lam = float(scene.wavelength_nm)
    leds_nm = sorted(set(scene.leds.wavelengths_nm(lam)))
    widths = [scene.leds.spectral_width_at(x, lam) for x in leds_nm]
    count_weights(scene.sensor, leds_nm, widths, lam)
    if scene.ambient.sun is not None:
        sunlight_band(scene.sensor, scene.ambient.sun, lam)


def render(
    scene: Scene | CompiledScene,
    options: RenderOptions | None = None,
    *,
    progress: Callable[[int, int], None] | None = None,
    status: Callable[[str], None] | None = None,
    advance: Callable[[int, int], None] | None = None,
) -> RenderResult:
    """Render a scene's eye image and eye-plane irradiance, and its sunlight apart
    (``ambient.sun``: module docstring; :attr:`RenderResult.ambient`).

    The LEDs' render is :func:`_render_leds` (its parameters and errors); the sunlight's band
    (:func:`eyelume.detectors.sensor.sunlight_band`) is checked before any tracing. A render
    interrupted (``interrupted``) in the LEDs' part, or in the sunlight's first round (pixels
    missing), has no sunlight (``ambient`` None); interrupted later, the sunlight's finished
    sample sets (unbiased) are kept.
    """
    opt = RenderOptions() if options is None else options
    cs = scene if isinstance(scene, CompiledScene) else compile_scene(scene)
    sc = cs.scene
    sun = sc.ambient.sun
    band = None
    if sun is not None and cs.sun is None and cs.led_ids is None:
        band = sunlight_band(sc.sensor, sun, float(sc.wavelength_nm))
    result = _render_leds(cs, opt, progress=progress, status=status, advance=advance)
    if sc.elements and not result.interrupted:
        result.ghost_warning = unresolved_ghosts(cs, result)
    if band is None or result.interrupted:
        return result
    if status is not None:
        status(f"sunlight ({band.spectrum}, traced at {band.trace_wavelength_nm:g} nm)")
    lam = band.trace_wavelength_nm
    if sc.eye.dispersion == "atchison_smith_2005" or sc.eye.cornea_reflection == "tear_film":
        lam = min(max(lam, DISPERSION_RANGE_NM[0]), DISPERSION_RANGE_NM[1])
    source = SunSource(sun.direction(), band.irradiance_w_mm2, lam)
    cs_sun = compile_scene(sc, sun=source, nominal=cs)
    seed = sun_seed(result.seed)
    sun_opt = replace(opt, seed=seed)
    if opt.rel_error is not None and opt.ambient_rel_error is not None:
        sun_opt = replace(sun_opt, rel_error=opt.ambient_rel_error)
    try:
        sub = _render_leds(cs_sun, sun_opt, progress=progress, status=status, advance=advance)
    except KeyboardInterrupt:  # stopped before the sunlight had a sample: the LEDs' picture stays
        result.interrupted = True
        return result
    result.interrupted = sub.interrupted  # Ctrl-C in the sunlight's part: a partial result
    if sub.covered_pixels is not None:  # its first round cut: pixels missing, no sunlight kept
        return result
    direction = cs_sun.tables.leds.axes[0]
    world = -cs.frame.rotation.T @ direction  # camera frame → world (a rotation's inverse)
    result.ambient = AmbientRender(
        band=band,
        eye_image=sub.eye_image,
        eye_image_variance=sub.eye_image_variance,
        seed=seed,
        rays=sub.rays,
        interrupted=sub.interrupted,
        direction_world=tuple(float(x) for x in world),
    )
    return result


#: A visible ghost is resolved when the power rendered about it is within 3 standard errors
#: + 30 % of the truth's ``flux_w`` (:data:`GHOST_TOLERANCE`) and known to 50 % (its pixels'
#: summed relative error, :data:`GHOST_REL_ERROR`: a ghost drawn by a single light path has
#: ~100 %; vr-offaxis-glasses' at its README budget, forward 2e6 rays, ~37 %).
GHOST_TOLERANCE = 0.3
GHOST_REL_ERROR = 0.5


def unresolved_ghosts(cs: CompiledScene, result: RenderResult) -> str | None:
    """One line naming each visible ghost of the truth (:func:`eyelume.analysis.ghosts.
    ghost_truth`) whose light the picture does not resolve, or None when all are.

    About each visible ghost, the pixels within ρ + 1.5 px of its ``centre_px`` (ρ: its
    ``reflection`` disc's radius, :func:`eyelume.analysis.regions.reflection_mask`), less
    any glint region's, hold P = Σ (E − b) A (W): E the pixels' irradiance (W/mm²), b the
    median of the ring 1.5–3.5 px outside them (the diffuse light under the ghost), A the
    pixel area (mm²); its standard error σ = A √Σ var (pixels taken as independent: with a
    PSF, an under-estimate). F is the truth's ``flux_w`` of the visible ghosts whose centres
    lie in those pixels. The ghost is unresolved when |P − F| > 3σ + 0.3 F — e.g. drawn by
    one light path (P a multiple of F) or by none (P ≈ 0) — or σ > 0.5 P
    (:data:`GHOST_TOLERANCE`, :data:`GHOST_REL_ERROR`)."""
    from eyelume.analysis.ghosts import ghost_truth
    from eyelume.analysis.regions import REFLECTION_MIN_RADIUS_PX
    from eyelume.analysis.truth import _view
    from eyelume.detectors.psf import camera_psf

    ghosts = [g for g in ghost_truth(_view(cs, cs.camera)) if g["visible"]]
    if not ghosts:
        return None
    image, var = result.eye_image, result.eye_image_variance
    area = result.pixel_area_mm2
    psf = camera_psf(cs)
    airy = 0.0 if psf is None else psf.airy_radius_mm / psf.pitch_mm[0]
    glint = np.zeros(image.shape, dtype=bool)
    for name, m in result.regions.items():
        if name.startswith("glint "):
            glint |= m
    r, c = np.mgrid[0 : image.shape[0], 0 : image.shape[1]]
    bad = []
    for g in ghosts:
        x, y = g["centre_px"]
        rho = max(REFLECTION_MIN_RADIUS_PX, 0.5 * (g.get("blur_px") or 0.0) + airy) + 1.5
        d2 = (c - x) ** 2 + (r - y) ** 2
        near = (d2 <= rho * rho) & ~glint & np.isfinite(image)
        ring = (d2 > rho * rho) & (d2 <= (rho + 2.0) ** 2) & ~glint & np.isfinite(image)
        if not near.any():
            continue
        back = float(np.median(image[ring])) if ring.any() else 0.0
        p = float((image[near] - back).sum() * area)
        sigma = float(math.sqrt(max(float(var[near].sum()), 0.0)) * area)
        f = sum(
            h["flux_w"]
            for h in ghosts
            if near[
                min(max(int(round(h["centre_px"][1])), 0), image.shape[0] - 1),
                min(max(int(round(h["centre_px"][0])), 0), image.shape[1] - 1),
            ]
        )
        f = f or g["flux_w"]
        if abs(p - f) > 3 * sigma + GHOST_TOLERANCE * f or sigma > GHOST_REL_ERROR * abs(p):
            chain = " → ".join(g["chain"])
            bad.append(f"LED {g['led']} ({chain}) {p:.2g} ± {sigma:.1g} W vs {f:.2g} W")
    if not bad:
        return None
    return (
        f"{len(bad)} of {len(ghosts)} visible ghosts in truth.json not resolved in the picture "
        f"(rendered about each vs the truth's flux): {'; '.join(bad)} — too few light paths "
        "drew them: raise --samples (fast) or --rays (forward)"
    )


def _render_leds(
    scene: Scene | CompiledScene,
    options: RenderOptions | None = None,
    *,
    progress: Callable[[int, int], None] | None = None,
    status: Callable[[str], None] | None = None,
    advance: Callable[[int, int], None] | None = None,
) -> RenderResult:
    """Render a scene's eye image and eye-plane irradiance (its LEDs', or a sun compile's
    sunlight).

    Parameters
    ----------
    scene
        A :class:`Scene` (compiled here) or an already compiled scene.
    options
        The estimator, its budget and the seed (:class:`RenderOptions`); default
        ``RenderOptions()``, the scene's ``[run]`` table.
    progress
        Forward: ``progress(rays_done, rays_total)`` after each batch.
    status, advance
        Fast: ``status(message)`` after each round, ``advance(done, planned)`` every fraction
        of a second (:func:`eyelume.estimators.fast_run.trace_fast`).

    The kernels' compilation (or loading from Numba's cache), the first time in a process, is
    timed apart in ``kernel_load_s`` and not counted in ``wall_time_s``.

    Raises
    ------
    ValueError
        ``options.estimator`` is neither ``"fast"`` nor ``"forward"``.
    InputFileError, SceneError
        A bad sensor QE table, or a wavelength (an LED spectrum) outside it, before tracing.
    """
    opt = RenderOptions() if options is None else options
    rays, seed, samples_per_pixel = opt.rays, opt.seed, opt.samples_per_pixel
    cs = scene if isinstance(scene, CompiledScene) else compile_scene(scene)
    sc = cs.scene
    seed = sc.run.seed if seed is None else int(seed)
    estimator = opt.estimator or ("forward" if rays is not None else sc.run.estimator)
    check_estimator(sc, estimator, cs)
    if cs.sun is None:  # a sun compile's wavelength is its own trace wavelength, not counted
        check_sensor_spectra(sc)  # a bad QE table fails now, not after the tracing
    if cs.led_ids is None and not single_wavelength(sc):
        if estimator not in ("fast", "forward"):
            raise ValueError(f"estimator = {estimator!r}: must be 'fast' or 'forward'")
        return _render_groups(cs, opt, estimator, seed, (progress, status, advance))
    picture, eye_plane = BinnedPlane(cs.picture), BinnedPlane(cs.eye_plane)
    extents = {"picture_extent_mm": picture.extent_mm, "plane_extent_mm": eye_plane.extent_mm}
    px_area = picture.bin_area_mm2
    if estimator == "fast":
        kernel_s = warm_up(cs) or None
        t0 = time.perf_counter()
        spp = sc.run.samples_per_pixel if samples_per_pixel is None else int(samples_per_pixel)
        pixels = sc.sensor.cols * sc.sensor.rows
        light = int(round(sc.run.light_paths_per_pixel * pixels * spp / 16))
        regions = region_masks(cs)
        est = trace_fast(
            cs,
            spp,
            light,
            seed,
            opt.rel_error,
            status,
            _judged_pixels(regions, opt),
            control=_run_control(cs, advance, opt),
        )
        plane = direct_eye_plane(cs, seed)
        blur = _Blur(cs, est.image, est.glint_images.sum(axis=0), est.glint_offsets)
        wall = time.perf_counter() - t0
        return RenderResult(
            scene=sc,
            estimator="fast",
            rays=est.samples_per_pixel * pixels + est.light_paths,
            seed=seed,
            wall_time_s=wall,
            emitted_w=cs.emitted_w,
            eye_image=blur.image(est.image),
            eye_image_variance=blur.variance(est.variance),
            eye_plane=plane,
            regions=with_glints(regions, blur.glints(est.glint_images), glint_centres(cs)),
            interrupted=est.interrupted,
            samples_per_pixel=est.samples_per_pixel,
            light_paths=est.light_paths,
            variance_dof=est.variance_dof,
            kernel_load_s=kernel_s,
            target_reached=est.target_reached,
            rel_error_achieved=est.rel_error_achieved,
            covered_pixels=est.covered_pixels,
            **_Blur.facts([blur], [est.variance]),
            **extents,
        )
    if estimator != "forward":
        raise ValueError(f"estimator = {estimator!r}: must be 'fast' or 'forward'")
    rays = sc.run.rays if rays is None else int(rays)
    kernel_s = warm_up_forward(cs) or None
    t0 = time.perf_counter()
    fc = trace_forward(cs, rays, seed, opt.batch_size, progress)
    w = cs.emitted_w / fc.rays
    image, variance = fc.image * (w / px_area), fc.image * (w / px_area) ** 2
    blur = _Blur(cs, image, fc.glint * (w / px_area), fc.glint_offsets)
    wall = time.perf_counter() - t0
    pl_area = eye_plane.bin_area_mm2
    return RenderResult(
        scene=sc,
        estimator="forward",
        rays=fc.rays,
        seed=seed,
        wall_time_s=wall,
        emitted_w=cs.emitted_w,
        eye_image=blur.image(image),
        eye_image_variance=blur.variance(variance),
        eye_plane=fc.plane * (w / pl_area),
        regions=region_masks(cs),
        interrupted=fc.interrupted,
        ray_power_w=w,
        image_counts=fc.image,
        plane_counts=fc.plane,
        ledger={name: float(n) * w for name, n in zip(cs.tallies, fc.tallies, strict=True)},
        interactions=fc.interactions,
        kernel_load_s=kernel_s,
        **_Blur.facts([blur], [variance]),
        **extents,
    )


def _judged_pixels(regions: dict, opt: RenderOptions) -> np.ndarray | None:
    """The pixels whose median relative error a ``rel_error`` render is judged by: the skin's
    (``regions["skin"]``), or — a picture that holds no skin, e.g. a small sensor on the eye —
    None, every pixel with signal, with an :class:`~eyelume.errors.EyelumeWarning` saying so
    (the skin's median would never be known, and the run would go on to its cap)."""
    skin = regions["skin"]
    if opt.rel_error is None or skin.any():
        return skin
    warnings.warn(
        "the picture holds no skin pixel: rel_error is judged by the median pixel with signal",
        EyelumeWarning,
        stacklevel=4,
    )
    return None


def _run_control(cs: CompiledScene, advance, opt: RenderOptions) -> RunControl:
    """The fast run's control: progress, the sample cap, and — for a ``rel_error`` run — the
    camera's PSF as the map from the traced picture to the delivered one, so the run stops
    when the picture the result holds (and whose error it reports) meets the target. (The
    map takes all light as uniform over its pixel; the result spreads glint light from its
    place in the pixel — the same power, moved within a few pixels of the glints, which the
    target's skin pixels do not hold.)"""
    psf = camera_psf(cs)
    if psf is None or opt.rel_error is None:
        return RunControl(advance, opt.max_samples_per_pixel)

    def deliver(image: np.ndarray, variance: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return convolve_irradiance(image, psf), convolve_variance(variance, psf)

    ratio = float(np.sum(psf.kernel**2))
    return RunControl(advance, opt.max_samples_per_pixel, deliver, ratio)


class _Blur:
    """The camera's PSF (:func:`eyelume.detectors.psf.camera_psf`, at the compiled scene's
    wavelength: a wavelength group's own) applied to a render's traced picture — the one place
    both estimators' pictures pass through before the sensor. ``points`` (rows, cols; the
    traced picture's units) is its part that met no Lambertian face (glints: point images) and
    ``offsets`` (2, rows, cols) that light's centroid in each pixel: spread from there, the rest
    as uniform over its pixel (:func:`eyelume.detectors.psf.convolve_with_points`). Skipped
    (``psf_skipped``) when the picture has missing pixels (a cut first round)."""

    def __init__(
        self,
        cs: CompiledScene,
        image: np.ndarray,
        points: np.ndarray | None = None,
        offsets: np.ndarray | None = None,
    ) -> None:
        psf = camera_psf(cs)
        self.skipped = psf is not None and not bool(np.all(np.isfinite(image)))
        self.psf = None if self.skipped else psf
        self.points, self.offsets = points, offsets

    def image(self, irradiance: np.ndarray, points: np.ndarray | None = None) -> np.ndarray:
        """The delivered picture of ``irradiance`` whose point part is ``points`` (default:
        the one given at construction, in the same units)."""
        points = self.points if points is None else points
        if self.psf is None or points is None or self.offsets is None:
            return convolve_irradiance(irradiance, self.psf)
        return convolve_with_points(irradiance, points, self.offsets, self.psf)

    def variance(self, variance: np.ndarray) -> np.ndarray:
        return convolve_variance(variance, self.psf)

    def glints(self, glint_images: np.ndarray) -> np.ndarray:
        """Each LED's glint image (n, rows, cols) spread alike (for the glint regions)."""
        if self.psf is None or not len(glint_images):
            return glint_images
        return np.stack([self.image(g, g) for g in glint_images])

    @staticmethod
    def facts(blurs: list[_Blur], variances: list[np.ndarray]) -> dict:
        """The RenderResult fields of the PSF: each group's kernel and traced variance."""
        parts = [(b.psf, v) for b, v in zip(blurs, variances, strict=True) if b.psf is not None]
        return {"psf_parts": parts or None, "psf_skipped": any(b.skipped for b in blurs)}


class _Groups:
    """A render's wavelength groups (:func:`_render_groups`): each one's compile and seed,
    the nominal compile's region masks and the result's extents."""

    def __init__(self, cs: CompiledScene, seed: int) -> None:
        self.cs, self.seed = cs, seed
        self.list = wavelength_groups(cs.scene)
        self.compiled = [compile_scene(cs.scene, g, nominal=cs) for g in self.list]
        many = len(self.list) > 1
        self.seeds = [group_seed(seed, g.index) if many else seed for g in self.list]
        picture, plane = BinnedPlane(cs.picture), BinnedPlane(cs.eye_plane)
        self.extents = {"picture_extent_mm": picture.extent_mm, "plane_extent_mm": plane.extent_mm}
        self.areas = picture.bin_area_mm2, plane.bin_area_mm2
        self.regions = region_masks(cs)
        self.centres = glint_centres(cs)
        self.shape = (cs.picture.rows, cs.picture.cols)
        self.plane_shape = (cs.eye_plane.rows, cs.eye_plane.cols)

    def __iter__(self):
        return iter(zip(self.list, self.compiled, self.seeds, strict=True))

    def check_whole(self, group, interrupted: bool) -> None:
        """KeyboardInterrupt when a group before the last was interrupted."""
        if interrupted and group.index < len(self.list) - 1:
            raise KeyboardInterrupt(
                f"interrupted in wavelength group {group.index + 1} of {len(self.list)} "
                f"({group.wavelength_nm:g} nm): the later groups' light is missing, no usable "
                "picture"
            )


def _render_groups(
    cs: CompiledScene, opt: RenderOptions, estimator: str, seed: int, callbacks: tuple
) -> RenderResult:
    """:func:`render` of a scene whose LEDs have several wavelengths: the sum over wavelength
    groups (module docstring). ``cs`` is the nominal compile (the scene's wavelength, every
    LED): its region masks are the result's.

    Each group gets the whole budget (``samples_per_pixel`` and light paths, or ``rel_error``,
    each on its own; the forward ``rays`` are shared in proportion to the groups' power, so
    every ray carries about the same power): G groups cost about G renders. A run interrupted
    (Ctrl-C, SIGTERM) before the last group has none of the later groups' light: it raises
    KeyboardInterrupt rather than return a picture without them; interrupted in the last
    group, the groups finished and that group's partial (unbiased) estimate are summed."""
    groups = _Groups(cs, seed)
    if estimator == "fast":
        return _groups_fast(groups, opt, callbacks[1], callbacks[2])
    return _groups_forward(groups, opt, callbacks[0])


def _groups_fast(groups: _Groups, opt: RenderOptions, status, advance) -> RenderResult:
    """The fast estimator over the wavelength groups (:func:`_render_groups`)."""
    sc = groups.cs.scene
    kernel_s = warm_up(groups.compiled[0]) or None
    t0 = time.perf_counter()
    spp = int(sc.run.samples_per_pixel if opt.samples_per_pixel is None else opt.samples_per_pixel)
    pixels = sc.sensor.cols * sc.sensor.rows
    light = int(round(sc.run.light_paths_per_pixel * pixels * spp / 16))
    plane = np.zeros(groups.plane_shape)
    glints = np.zeros((sc.leds.count, *groups.shape))
    skin = _judged_pixels(groups.regions, opt)
    ests, parts, done, blurs = [], [], [0], []

    def advance_in(d: int, planned: int) -> None:
        if advance:
            left = len(groups.list) - len(ests) - 1
            advance(done[0] + d, done[0] + planned * (1 + left))

    for g, cg, sg in groups:
        if status:
            status(f"wavelength group {g.index + 1} of {len(groups.list)}: {g.wavelength_nm:g} nm")
        control = _run_control(cg, advance_in, opt)
        said = (lambda m, g=g: status(f"{g.wavelength_nm:g} nm: {m}")) if status else None
        est = trace_fast(cg, spp, light, sg, opt.rel_error, said, skin, control)
        groups.check_whole(g, est.interrupted)
        plane += direct_eye_plane(cg, sg)
        # the group's own wavelength
        blur = _Blur(cg, est.image, est.glint_images.sum(axis=0), est.glint_offsets)
        blurs.append(blur)
        glints[list(g.leds)] = blur.glints(est.glint_images)
        rays = est.samples_per_pixel * pixels + est.light_paths
        done[0] += rays
        ests.append(est)
        parts.append(
            GroupRender(g.wavelength_nm, g.leds, sg, cg.emitted_w, blur.image(est.image),
                        blur.variance(est.variance), rays, est.samples_per_pixel)
        )  # fmt: skip
    wall = time.perf_counter() - t0
    image = sum(p.eye_image for p in parts)
    variance = sum(p.eye_image_variance for p in parts)
    dof = min(e.variance_dof for e in ests)
    reached = err = None
    if opt.rel_error is not None:  # the delivered sum's own error, not the groups'
        m = (image > 0) & np.isfinite(image) & (True if skin is None else skin)
        e = median_pixel_rel_error(image[m], variance[m], dof) if m.any() else math.inf
        reached, err = e <= opt.rel_error, (e if math.isfinite(e) else None)
    return RenderResult(
        scene=sc,
        estimator="fast",
        rays=sum(p.rays for p in parts),
        seed=groups.seed,
        wall_time_s=wall,
        emitted_w=float(sum(p.emitted_w for p in parts)),
        eye_image=image,
        eye_image_variance=variance,
        eye_plane=plane,
        regions=with_glints(groups.regions, glints, groups.centres),
        interrupted=ests[-1].interrupted,
        samples_per_pixel=min(e.samples_per_pixel for e in ests),
        light_paths=sum(e.light_paths for e in ests),
        variance_dof=dof,
        kernel_load_s=kernel_s,
        target_reached=reached,
        rel_error_achieved=err,
        covered_pixels=ests[-1].covered_pixels,
        groups=parts,
        **_Blur.facts(blurs, [e.variance for e in ests]),
        **groups.extents,
    )


def _forward_shares(rays: int, compiled: list[CompiledScene]) -> list[int]:
    """Forward rays per wavelength group, in proportion to its LEDs' power (at least one)."""
    power = np.array([cg.emitted_w for cg in compiled])
    share = [max(1, int(rays * p / power.sum())) for p in power[:-1]]
    return [*share, max(1, rays - sum(share))]


def _groups_forward(groups: _Groups, opt: RenderOptions, progress) -> RenderResult:
    """Forward Monte Carlo over the wavelength groups (:func:`_render_groups`)."""
    sc = groups.cs.scene
    rays = sc.run.rays if opt.rays is None else int(opt.rays)
    shares = _forward_shares(rays, groups.compiled)
    kernel_s = warm_up_forward(groups.compiled[0]) or None
    t0 = time.perf_counter()
    image, variance = np.zeros(groups.shape), np.zeros(groups.shape)
    plane = np.zeros(groups.plane_shape)
    image_counts = np.zeros(groups.shape, dtype=np.int64)
    plane_counts = np.zeros(groups.plane_shape, dtype=np.int64)
    ledger: dict[str, float] = {}
    parts, interactions, traced, interrupted = [], 0, 0, False
    blurs, traced_vars = [], []
    px_area, pl_area = groups.areas
    for (g, cg, sg), n in zip(groups, shares, strict=True):

        def progress_in(d: int, _total: int, before: int = traced) -> None:
            if progress:
                progress(before + d, rays)

        fc = trace_forward(cg, n, sg, opt.batch_size, progress_in)
        groups.check_whole(g, fc.interrupted)
        interrupted = fc.interrupted
        w = cg.emitted_w / fc.rays
        traced_var = fc.image * (w / px_area) ** 2
        blur = _Blur(cg, fc.image, offsets=fc.glint_offsets)  # the group's own wavelength
        blurs.append(blur)
        traced_vars.append(traced_var)
        part = blur.image(fc.image * (w / px_area), fc.glint * (w / px_area))
        part_var = blur.variance(traced_var)
        image += part
        variance += part_var
        plane += fc.plane * (w / pl_area)
        for name, k in zip(cg.tallies, fc.tallies, strict=True):
            ledger[name] = ledger.get(name, 0.0) + float(k) * w
        image_counts += fc.image
        plane_counts += fc.plane
        interactions += fc.interactions
        traced += fc.rays
        parts.append(
            GroupRender(g.wavelength_nm, g.leds, sg, cg.emitted_w, part, part_var, fc.rays)
        )
    wall = time.perf_counter() - t0
    return RenderResult(
        scene=sc,
        estimator="forward",
        rays=traced,
        seed=groups.seed,
        wall_time_s=wall,
        emitted_w=float(sum(p.emitted_w for p in parts)),
        eye_image=image,
        eye_image_variance=variance,
        eye_plane=plane,
        regions=groups.regions,
        interrupted=interrupted,
        ray_power_w=None,  # the groups' rays carry about, not exactly, the same power
        image_counts=image_counts,
        plane_counts=plane_counts,
        ledger=ledger,
        interactions=interactions,
        kernel_load_s=kernel_s,
        groups=parts,
        **_Blur.facts(blurs, traced_vars),
        **groups.extents,
    )


#: Kinds of the traced rays of :class:`RenderExtras`: reached the sensor, born near the view's
#: section plane; reached the sensor, born off it (drawn projected); did not reach the sensor.
RAY_KINDS = ("sensor", "sensor, off the section", "other")


@dataclass
class RenderExtras:
    """What ``eyelume render`` draws and records beside its images, computed here (where rays
    may be traced) so that :mod:`eyelume.report` only writes it.

    ``sections``: the system in two orthogonal views, ``"yz"`` and ``"xz"``, world frame
    (:func:`eyelume.layout.system_sections`); ``ray_paths``: per view, a few dozen traced rays
    ((k, 3) world vertices in mm, kind of :data:`RAY_KINDS`)
    (:func:`eyelume.estimators.forward.trace_paths`): rays reaching the sensor born within
    1 mm of the view's section plane (the plane through the eye's nominal vertex the view
    cuts), topped up to 6 with rays reaching the sensor born off it (few rays reach the
    sensor of an off-axis camera, and perhaps none from the LEDs in one section: drawn
    projected onto it, so the camera's view shows in both sections), and rays that miss it
    born near the plane; ``truth``: the true gaze, pupil and glint positions on the picture
    (:func:`eyelume.analysis.truth.eye_truth`).
    """

    sections: dict[str, list[Section]]
    ray_paths: dict[str, list[tuple[np.ndarray, str]]]
    truth: dict


def render_extras(cs: CompiledScene, seed: int) -> RenderExtras:
    """The layout views, ray paths (drawn from the seed's stream, for each view those born
    near its section plane first) and truth of a compiled scene (:class:`RenderExtras`)."""
    from eyelume.compile import eye_plane_origin

    views = {view: system_sections(cs, view=view) for view in VIEWS}
    origin = eye_plane_origin(cs.scene)
    tol, want, least = 1.0, 24, 6
    # one search for rays reaching the sensor, born anywhere (rare for an off-axis camera)
    hits = [p for p, _ in trace_paths(cs, seed, detected=8 * want, other=0, section_tol=np.inf)]
    paths = {}
    for view, (cut, _) in VIEWS.items():
        # the world plane w_cut = origin[cut] in the camera frame: world = R^T p_c + o
        normal = cs.frame.rotation[:, cut]
        offset = float(origin[cut] - cs.frame.origin[cut])
        near = [abs(float(p[0] @ normal) - offset) <= tol for p in hits]
        chosen = [(p, "sensor") for p, n in zip(hits, near, strict=True) if n][:want]
        off = [p for p, n in zip(hits, near, strict=True) if not n]
        chosen += [(p, RAY_KINDS[1]) for p in off[: max(0, least - len(chosen))]]
        others = trace_paths(cs, seed, detected=0, other=want, plane=(normal, offset))
        chosen += [(p, "other") for p, hit in others if not hit]
        paths[view] = [(cs.frame.world_point(p), kind) for p, kind in chosen]
    return RenderExtras(views, paths, eye_truth(cs))
