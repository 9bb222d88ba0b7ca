"""The ideal eye image of the paper's illumination evaluator (Section 4.2.1, Figure 9(a)).

The mask is the scene's own geometry seen through the camera: each pixel takes the ideal relative
level of the region its chief ray meets (:func:`eyelume.analysis.regions.region_masks`), so the
pupil, iris, sclera and skin sit exactly where the simulated image has them — same sensor grid,
row 0 at the top of the upright picture. Levels are relative to the skin (1); the evaluator
(:func:`eyelume.analysis.evaluator.evaluator_merit`) compares an image with the mask after
scaling the image by its least-squares exposure, so only the levels' ratios matter.

The paper's dark-pupil mask asks for a uniform dark pupil, a high-contrast pupil–iris boundary
and a uniform skin; its glints are removed from the model first (:func:`glints_off`), since a
real camera saturates on them anyway (Section 4.2.2).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from eyelume.analysis.regions import region_masks
from eyelume.compile import CompiledScene, compile_scene
from eyelume.scene.eye import eye_indices, glint_reflectance
from eyelume.scene.io import apply_overrides
from eyelume.scene.model import Scene

__all__ = [
    "IdealMask",
    "MaskLevels",
    "MaskWeights",
    "glints_off",
    "ideal_mask",
    "mask_from_regions",
]

_REGIONS = ("pupil", "iris", "sclera", "skin")


@dataclass(frozen=True)
class MaskLevels:
    """Ideal brightness of each region relative to the skin (dimensionless, skin = 1).

    Defaults, for a dark-pupil tracker (paper Fig. 9(a)):

    * ``pupil = 0``: dark and uniform — the feature to segment.
    * ``iris = 0.5``: half the skin level. The pupil–iris step is then half the image's range, so
      the histogram valley (a threshold at ~0.25) clears both sides by the same margin, and it is
      reachable: under uniform irradiance the iris images at ρ_iris/ρ_skin · T_cornea² =
      0.05/0.12 · 0.976² ≈ 0.40 of the skin, so 0.5 asks the illumination for ~25 % more
      irradiance on the iris than on the skin — the central brightening the paper expects
      (Section 4.2.1) — where asking iris = skin would need ~2.5×, far steeper than the
      paper's optimal patterns (falloff δ = 0.3–0.5).
    * ``sclera = 0.75``: ρ_sclera/ρ_skin = 0.09/0.12, what uniform light gives it (it is seen
      directly, not through the cornea). Bright like the skin, it never competes with the pupil.
    * ``skin = 1``: uniform; any gradient or hot spot can be mistaken for a feature.
    """

    pupil: float = 0.0
    iris: float = 0.5
    sclera: float = 0.75
    skin: float = 1.0


@dataclass(frozen=True)
class MaskWeights:
    """How much each pixel of a region counts in the evaluator's merit (per pixel).

    The paper's mask "considered only the pupil boundary and the skin area uniformity"
    (Section 4.2.2): the pupil and iris (the boundary's two sides) and the skin count, the sclera
    does not unless asked. Pixels of no region (the LED bodies, glints, nothing) always weigh 0.
    """

    pupil: float = 1.0
    iris: float = 1.0
    sclera: float = 0.0
    skin: float = 1.0


class IdealMask(NamedTuple):
    """The ideal image and its weights, both (rows, cols) float64 on the sensor grid, row 0 at
    the top of the upright picture. ``image`` holds :class:`MaskLevels` values (relative to the
    skin), ``weights`` the :class:`MaskWeights` of each pixel (0: does not count)."""

    image: np.ndarray
    weights: np.ndarray


def mask_from_regions(
    regions: dict[str, np.ndarray],
    levels: MaskLevels = MaskLevels(),  # noqa: B008 - frozen, immutable default
    weights: MaskWeights = MaskWeights(),  # noqa: B008
) -> IdealMask:
    """The ideal image and weights from region masks (e.g. ``RenderResult.regions``).

    Only the regions ``pupil`` (the iris's opening: the iris root closes the eye around the
    iris, see compile.py), ``iris`` (its root included), ``sclera`` and ``skin`` are used; glint
    and reflection regions, if present, were already removed from them and weigh 0.
    """
    shape = regions["skin"].shape
    image = np.zeros(shape)
    w = np.zeros(shape)
    for name in _REGIONS:
        m = regions[name]
        image[m] = getattr(levels, name)
        w[m] = getattr(weights, name)
    return IdealMask(image, w)


def ideal_mask(
    scene: Scene | CompiledScene,
    levels: MaskLevels = MaskLevels(),  # noqa: B008 - frozen, immutable default
    weights: MaskWeights = MaskWeights(),  # noqa: B008
) -> IdealMask:
    """The paper's ideal eye image (Fig. 9(a)) for ``scene``, on its sensor grid.

    The regions come from the chief ray of each pixel (refracted by the eye, an optical element's
    stronger branch: :func:`eyelume.analysis.regions.region_masks`), so they do not depend on
    the eye's reflectances: the mask of a scene and of :func:`glints_off` of it are the same.
    """
    cs = scene if isinstance(scene, CompiledScene) else compile_scene(scene)
    return mask_from_regions(region_masks(cs), levels, weights)


def glints_off(scene: Scene) -> Scene:
    """A copy of ``scene`` whose anterior cornea forms no glints (paper Section 4.2.2).

    The cornea's reflectance R goes to 0 and its absorptance rises by R (2.4 % by default), so
    no first Purkinje images form and the light the cornea transmits is unchanged. A Fresnel
    cornea becomes a fixed split with R its normal-incidence reflectance ((n − 1)/(n + 1))²
    at the scene wavelength: the transmission is then exact on axis and 0.12 % above Fresnel's
    at 30° incidence (0.5 % at 40°).
    """
    eye = scene.eye
    r = glint_reflectance(eye, scene.wavelength_nm)
    overrides: dict[str, object] = {"eye.cornea_reflectance": 0.0}
    if eye.cornea_reflection == "tear_film":  # its R at the scene wavelength, as a fixed split
        overrides["eye.cornea_reflection"] = "fixed"
    if eye.cornea_reflection == "fresnel":
        n = eye_indices(eye, scene.wavelength_nm)[1]
        r = ((n - 1.0) / (n + 1.0)) ** 2
        overrides["eye.cornea_reflection"] = "fixed"
    overrides["eye.cornea_absorptance"] = eye.cornea_absorptance + r
    return apply_overrides(scene, overrides)
