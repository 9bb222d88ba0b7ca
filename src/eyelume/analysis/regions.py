"""Regions of the eye image — pupil, iris, sclera, skin, one per glint, the reflections — and
their statistics.

The regions come from the scene's own geometry seen through the camera: each pixel takes the
surface its chief ray meets first after refraction (never reflection) — through the cornea, the
iris (its root, out to the eyeball wall, included) or, through the pupil, the crystalline lens
and fundus. A glint's region is the set of pixels where the light that met only the cornea (no
Lambertian face) from that LED reaches at least 5 % of that glint's peak; glint pixels belong to
no other region. With optical elements, the ``reflection`` region holds the pixels of every
visible specular image an element causes (spectacle ghosts, :mod:`eyelume.analysis.ghosts`):
a disc about each one's true centre, as wide as its defocus blur and the diffraction PSF's
Airy disc (:func:`reflection_mask`); its pixels belong to no other region, and a glint's
region is then only the lit part of its LED's image about the true corneal glint
(:func:`with_glints`), never the LED's ghosts.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable

import numpy as np

from eyelume.compile import LASHES_NAME, CompiledScene
from eyelume.errors import EyelumeWarning
from eyelume.estimators.fast_run import primary_surface_map
from eyelume.estimators.statistics import median_pixel_rel_error

__all__ = [
    "GLINT_FRACTION",
    "REFLECTION_MIN_RADIUS_PX",
    "RegionWarning",
    "glint_centres",
    "reflection_mask",
    "region_masks",
    "region_stats",
    "surface_masks",
    "with_glints",
    "with_reflections",
]

GLINT_FRACTION = 0.05
_PUPIL_SURFACES = ("anterior lens", "posterior lens", "retina")
#: The smallest radius (px) of a reflection's disc: a point imaged in focus still lights the
#: pixel it falls in and, off its centre, a neighbour.
REFLECTION_MIN_RADIUS_PX = 1.0


def region_masks(
    cs: CompiledScene, glint_images: np.ndarray | None = None, *, reflections: bool = True
) -> dict[str, np.ndarray]:
    """Boolean (rows, cols) masks by region name: ``pupil``, ``iris``, ``sclera``, ``skin``,
    ``glint 0`` … (one per LED, when ``glint_images`` (n_leds, rows, cols) is given) and, for
    a scene with optical elements, ``reflection`` (:func:`reflection_mask` of the ghosts'
    truth; ``reflections=False`` skips their search, ~1 s)."""
    _warn_mirrors(cs)
    masks = surface_masks(cs, *primary_surface_map(cs))
    if cs.scene.elements and reflections:
        from eyelume.analysis.ghosts import ghost_truth
        from eyelume.analysis.truth import _view

        masks = with_reflections(masks, reflection_mask(cs, ghost_truth(_view(cs, cs.camera))))
    return masks if glint_images is None else with_glints(masks, glint_images)


def surface_masks(
    cs: CompiledScene, labels: np.ndarray, sides: np.ndarray
) -> dict[str, np.ndarray]:
    """Boolean (rows, cols) masks ``pupil``, ``iris``, ``sclera``, ``skin`` of the primary
    surface map (``labels``, ``sides``: :func:`eyelume.estimators.fast_run.primary_surface_map`),
    before any glint or reflection is taken out (what :func:`region_masks` starts from)."""
    names = cs.surface_names
    eye = cs.scene.eye
    tissues = {t.name for t in cs.scene.face.tissues} if cs.scene.face.enabled else set()
    pupil_names = {eye.surfaces[j].name for j in range(2, len(eye.surfaces))} | set(_PUPIL_SURFACES)

    def of(pred) -> np.ndarray:
        """Pixels whose (surface, side) satisfies pred(name, seen from side B)."""
        table = np.array(
            [[pred(n, False), pred(n, True)] for n in names] + [[False, False]], dtype=bool
        )
        return table[labels, sides]  # label −1 (nothing) indexes the last, all-False row

    return {
        "pupil": of(lambda n, b: n in pupil_names or (n == "sclera" and not b)),
        "iris": of(lambda n, b: n in ("iris", "iris root")),
        "sclera": of(lambda n, b: n == "sclera" and b),
        "skin": of(lambda n, b: n in tissues or n == LASHES_NAME),  # the lashes: the lid's
    }


class RegionWarning(EyelumeWarning):
    """The regions cannot be mapped faithfully for this scene (they are still returned)."""


def _mirror_rt(cs: CompiledScene, k: int, least: bool = False) -> tuple[float, float]:
    """(R, T) of mirror ``elements[k]`` where it reflects the most (``least``: the least) over
    the LEDs' wavelengths (a ``fixed`` coating, its cut-off) and, for an R(angle) table, its
    angles (T = 1 − R)."""
    from eyelume.scene.elements import read_reflectance_table
    from eyelume.scene.model import MIRROR_COATING

    coat = cs.scene.elements[k].front.coating or MIRROR_COATING
    lams = set(cs.scene.leds.wavelengths_nm(cs.scene.wavelength_nm)) | {cs.scene.wavelength_nm}
    if coat.model == "table":
        field = f"elements.{k}.front.coating.table_csv"
        rs = [read_reflectance_table(coat.table_csv, field, lam)[1] for lam in lams]  # type: ignore[arg-type]
        r = min(float(x.min()) for x in rs) if least else max(float(x.max()) for x in rs)
        return r, 1.0 - r
    pick = min if least else max
    return pick((coat.fixed_at(lam) for lam in lams), key=lambda rt: rt[0] - rt[1])


def _warn_mirrors(cs: CompiledScene) -> None:
    """Warn once per scene when a mirror element's stronger branch depends on the wavelength:
    the map follows every chief ray through an element by its stronger branch at the scene's
    wavelength (:func:`eyelume.estimators.fast_run.primary_surface_map`: reflected where
    R > T, a mirror's fold, as the compile follows the camera's line of sight), so it is
    wrong for LEDs of a wavelength at which the mirror turns the other way (R > T at one
    wavelength and R ≤ T at another, e.g. a hot mirror's cut-off between them). Only that is
    warned about, naming R and T."""
    for k, el in enumerate(cs.scene.elements):
        if el.kind != "mirror":
            continue
        r, t = _mirror_rt(cs, k)
        lo_r, lo_t = _mirror_rt(cs, k, least=True)
        if r > t and lo_r <= lo_t:
            warnings.warn(
                f"elements.{k} is a mirror that reflects more than it transmits at one LED "
                f"wavelength (R = {r:g}, T = {t:g}) and not at another (R = {lo_r:g}, "
                f"T = {lo_t:g}): the eye image's regions (pupil, iris, sclera, skin) follow "
                "the camera's view at the scene's wavelength only",
                RegionWarning,
                stacklevel=3,
            )
            return


def reflection_mask(cs: CompiledScene, ghosts: list[dict]) -> np.ndarray:
    """(rows, cols) bool: the pixels within radius ρ of each visible ghost's ``centre_px``
    (OpenCV convention; :func:`eyelume.analysis.ghosts.ghost_truth`), ρ = ``blur_px``/2 (its
    geometric defocus) + the Airy radius 1.22 λ N_w of the camera's diffraction PSF (0 without
    one), at least :data:`REFLECTION_MIN_RADIUS_PX`. Pixel (c, r) is inside when its centre
    is: (c − x)² + (r − y)² ≤ ρ²."""
    from eyelume.detectors.psf import camera_psf

    rows, cols = cs.picture.rows, cs.picture.cols
    psf = camera_psf(cs)
    airy = 0.0 if psf is None else psf.airy_radius_mm / psf.pitch_mm[0]
    r, c = np.mgrid[0:rows, 0:cols]
    out = np.zeros((rows, cols), dtype=bool)
    for g in ghosts:
        if not g["visible"]:
            continue
        rho = max(REFLECTION_MIN_RADIUS_PX, 0.5 * (g.get("blur_px") or 0.0) + airy)
        x, y = g["centre_px"]
        out |= (c - x) ** 2 + (r - y) ** 2 <= rho * rho
    return out


def with_reflections(masks: dict[str, np.ndarray], reflection: np.ndarray) -> dict[str, np.ndarray]:
    """``masks`` plus ``reflection`` (rows, cols) bool; its pixels are removed from the
    others."""
    out = {name: m & ~reflection for name, m in masks.items()}
    out["reflection"] = reflection
    return out


def glint_centres(cs: CompiledScene) -> list[tuple[float, float] | None] | None:
    """Each LED's true corneal glint pixel (x, y) (OpenCV convention; None where it has no
    visible glint), in scene LED order, for a scene with optical elements; None without
    elements (their glint images then hold the corneal glints alone). What
    :func:`with_glints` keeps each glint region to."""
    if not cs.scene.elements:
        return None
    from eyelume.analysis.truth import _glint_truth, _view

    v = _view(cs, cs.camera)
    ids = cs.led_indices
    out: list[tuple[float, float] | None] = [None] * (max(ids, default=-1) + 1)
    for row, (k, led) in enumerate(zip(ids, cs.led.points, strict=True)):
        g = _glint_truth(v, k, led, row)
        if g["visible"] and g["centre_px"] is not None:
            out[k] = (float(g["centre_px"][0]), float(g["centre_px"][1]))
    return out


def with_glints(
    masks: dict[str, np.ndarray],
    glint_images: np.ndarray,
    centres: list[tuple[float, float] | None] | None = None,
) -> dict[str, np.ndarray]:
    """``masks`` plus ``glint k`` for each LED's glint image (n_leds, rows, cols); glint pixels
    are removed from the other regions.

    A glint image holds every path of LED k that met no Lambertian face, so with optical
    elements it also holds LED k's ghosts (LED → spectacle → camera), often far brighter than
    its corneal glint. So the pixels of ``masks["reflection"]`` (the visible ghosts') are never
    a glint's, and with ``centres`` (:func:`glint_centres`: LED k's true corneal glint pixel,
    or None: no visible glint, no region) ``glint k`` is the 8-connected part of the image's
    lit pixels (> 0, outside the reflections) that holds — or, none holding it, comes nearest
    — that pixel, thresholded at :data:`GLINT_FRACTION` of its own peak. Without ``centres``:
    the image's pixels ≥ :data:`GLINT_FRACTION` of its peak."""
    out = dict(masks)
    shape = glint_images.shape[1:]
    reflection = masks.get("reflection")
    any_glint = np.zeros(shape, dtype=bool)
    for k, g in enumerate(glint_images):
        if reflection is not None:
            g = np.where(reflection, 0.0, g)
        if centres is not None:
            m = _corneal_part(g, centres[k] if k < len(centres) else None)
        else:
            peak = g.max()
            m = g >= GLINT_FRACTION * peak if peak > 0 else np.zeros(shape, dtype=bool)
        out[f"glint {k}"] = m
        any_glint |= m
    for name in masks:
        out[name] = masks[name] & ~any_glint
    return out


def _corneal_part(g: np.ndarray, centre: tuple[float, float] | None) -> np.ndarray:
    """(rows, cols) bool: the 8-connected component of ``g > 0`` holding (or nearest to)
    pixel ``centre`` (x, y), at ≥ :data:`GLINT_FRACTION` of that component's peak."""
    from scipy import ndimage

    none = np.zeros(g.shape, dtype=bool)
    lit = np.isfinite(g) & (g > 0)
    if centre is None or not lit.any():
        return none
    labels, _ = ndimage.label(lit, structure=np.ones((3, 3), dtype=bool))
    r, c = np.nonzero(lit)
    x, y = centre
    nearest = int(np.argmin((c - x) ** 2 + (r - y) ** 2))
    part = labels == labels[r[nearest], c[nearest]]
    peak = g[part].max()
    return part & (g >= GLINT_FRACTION * peak)


def region_stats(
    image: np.ndarray,
    variance: np.ndarray,
    masks: dict[str, np.ndarray],
    pixel_area_mm2: float,
    dof: int | None = None,
    mean_variance: Callable[[np.ndarray], float] | None = None,
) -> dict[str, dict]:
    """Per region: pixels, mean irradiance (W/mm²) and its relative standard error, the median
    pixel and the median over the region of each pixel's relative standard error; for glints
    and the reflections also the total flux (W) and its relative standard error.

    ``variance`` is the estimated variance of each pixel's value. Independent pixels: the
    variance of a region's mean is Σ variance / n². Pixels correlated by a point-spread
    function: ``mean_variance(mask)`` gives it (:func:`eyelume.detectors.psf.region_mean_variance`).
    """
    out = {}
    for name, m in masks.items():
        n = int(m.sum())
        if n == 0:
            out[name] = {"pixels": 0}
            continue
        vals, var = image[m], variance[m]
        mean = float(vals.mean())
        if mean_variance is None:
            se = math.sqrt(float(var.sum())) / n
        else:
            se = math.sqrt(mean_variance(m))
        entry = {
            "pixels": n,
            "mean_w_mm2": mean,
            "mean_rel_error": se / mean if mean > 0 else math.inf,
            "median_w_mm2": float(np.median(vals)),
            "median_pixel_rel_error": median_pixel_rel_error(vals, var, dof),
        }
        if name.startswith("glint") or name == "reflection":
            entry["flux_w"] = float(vals.sum()) * pixel_area_mm2
            entry["flux_rel_error"] = entry["mean_rel_error"]
        out[name] = entry
    return out
