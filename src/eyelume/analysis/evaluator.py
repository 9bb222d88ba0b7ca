"""The illumination evaluator's scores (paper Sections 4.2.2 and 5).

:func:`evaluator_merit` rates a simulated eye image against the ideal mask of
:mod:`eyelume.analysis.masks`; :func:`skin_score` is the experiment's score, the skin region's
brightness mean and standard deviation.
"""

from __future__ import annotations

import numpy as np

__all__ = ["evaluator_merit", "skin_score"]


def evaluator_merit(image: np.ndarray, mask: np.ndarray, weights: np.ndarray) -> float:
    """Weighted mean squared mismatch of ``image`` to the ideal ``mask``, after exposure scaling.

    The image (any units, e.g. W/mm²) is first scaled by the least-squares exposure factor

        s = argmin_s Σ w (s I − M)² = Σ w I M / Σ w I²

    (s = 0 for an image dark wherever w > 0), then

        merit = Σ w (s I − M)² / Σ w,

    dimensionless, in units of the mask's levels squared (skin = 1); 0 is a perfect match. It is
    invariant to the image's overall scale (LED power, exposure), so it rates the illumination's
    *pattern*. It is not the LightTools merit value the paper quotes (341.8 … 459.1), whose
    scale depends on LightTools' own normalisation: compare values of this function only with
    each other.

    Parameters
    ----------
    image, mask, weights : (rows, cols) arrays
        The simulated image, the ideal levels and each pixel's weight (≥ 0; at least one > 0).

    Examples
    --------
    >>> import numpy as np
    >>> m = np.array([0.0, 0.5, 1.0, 1.0]); w = np.ones(4)
    >>> evaluator_merit(3e-6 * m, m, w) < 1e-24   # any exposure of the mask itself
    True
    >>> round(evaluator_merit(np.array([0.0, 0.5, 1.0, 0.8]), m, w), 5)
    0.00661
    """
    image = np.asarray(image, dtype=float)
    mask = np.asarray(mask, dtype=float)
    w = np.asarray(weights, dtype=float)
    if not (image.shape == mask.shape == w.shape):
        raise ValueError(
            f"shapes differ: image {image.shape}, mask {mask.shape}, weights {w.shape}"
        )
    if np.any(w < 0) or not np.all(np.isfinite(w)) or w.sum() <= 0:
        raise ValueError("weights must be finite, ≥ 0 and not all 0")
    if not np.all(np.isfinite(image[w > 0])):
        raise ValueError("image is not finite where weights > 0")
    ii = float(np.sum(w * image * image))
    s = float(np.sum(w * image * mask)) / ii if ii > 0 else 0.0
    return float(np.sum(w * (s * image - mask) ** 2) / w.sum())


def skin_score(image: np.ndarray, skin_mask: np.ndarray) -> tuple[float, float, float]:
    """The paper's Section 5 score: (mean, std, cv) of the image over the skin region.

    ``mean`` and ``std`` (population standard deviation, ddof = 0) are in the image's units;
    ``cv = std / mean`` is dimensionless (lower is more uniform; inf for a dark skin).

    Examples
    --------
    >>> import numpy as np
    >>> skin_score(np.array([[1.0, 3.0], [9.0, 9.0]]), np.array([[True, True], [False, False]]))
    (2.0, 1.0, 0.5)
    """
    vals = np.asarray(image, dtype=float)[np.asarray(skin_mask, dtype=bool)]
    if vals.size == 0:
        raise ValueError("skin_mask selects no pixel")
    mean = float(vals.mean())
    std = float(vals.std())
    return mean, std, std / mean if mean > 0 else float("inf")
