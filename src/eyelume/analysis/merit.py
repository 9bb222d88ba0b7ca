"""Merit functions of the paper's optimisation scheme (§4, Fig. 7).

- The **generator** merit (§4.1.2) scores how well an eye-plane irradiance pattern matches a
  target pattern: :func:`generator_merit`.
- The **evaluator** merit (§4.2) scores a simulated eye image against an ideal one; it belongs in
  this module too, beside the generator's, and is not written yet.

The paper leaves the generator's merit to the LightTools optimizer, whose scale is not documented;
eyelume's is stated below and is not comparable in absolute value with LightTools' figures.
"""

from __future__ import annotations

import numpy as np

__all__ = ["generator_merit"]


def generator_merit(pattern: np.ndarray, target: np.ndarray) -> np.ndarray | float:
    """How far an eye-plane pattern's shape is from a target's: 0 is a perfect match.

    Both are scaled to unit mean over the bins, then

        merit = Σ_bins (p / p̄ − t / t̄)²,

    dimensionless, ≥ 0, independent of the LEDs' power and the target's scale (only the shape of
    the illumination is asked for). This is eyelume's definition, not LightTools' merit function,
    whose normalisation is undocumented.

    Parameters
    ----------
    pattern
        Irradiance per bin (any unit), (rows, cols), or (..., rows, cols) for many patterns at once.
    target
        The target (rows, cols), non-negative with a positive mean.

    Returns
    -------
    The merit, a float for one pattern or an array of the leading shape of ``pattern``. A pattern
    holding NaN (an impossible configuration) scores NaN; a pattern with no light (mean 0) scores
    +inf.

    >>> t = np.array([[1.0, 2.0], [3.0, 2.0]])
    >>> generator_merit(5 * t, t)
    0.0
    >>> generator_merit(np.ones((2, 2)), t)
    0.5
    """
    p = np.asarray(pattern, dtype=float)
    t = np.asarray(target, dtype=float)
    if t.ndim != 2:
        raise ValueError(f"target must be (rows, cols), got shape {t.shape}")
    if p.shape[-2:] != t.shape:
        raise ValueError(f"pattern bins {p.shape[-2:]} do not match the target's {t.shape}")
    t_mean = t.mean()
    if not (np.all(np.isfinite(t)) and t_mean > 0):
        raise ValueError("target must be finite with a positive mean")
    p_mean = p.mean(axis=(-2, -1), keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        merit = np.sum((p / p_mean - t / t_mean) ** 2, axis=(-2, -1))
    merit = np.where(p_mean[..., 0, 0] == 0, np.inf, merit)
    return float(merit) if merit.ndim == 0 else merit
