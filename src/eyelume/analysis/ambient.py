"""Signal to ambient: the LEDs' glints and pupil against the sunlight on the same pixels.

Both pictures are as the sensor counts them (W/mm² of light at the scene's wavelength giving
the same photo-electrons, :attr:`eyelume.render.RenderResult.led_image_at_scene_wavelength` and
:attr:`eyelume.render.AmbientRender.eye_image`), so every ratio here is a ratio of mean
photo-electrons. Analysis only: the pictures are given.

* Glint k (its region ``glint k``, :func:`eyelume.analysis.regions.with_glints`): the LEDs'
  peak pixel S_k over the region and the ambient A_k on that pixel; signal to ambient S_k / A_k.
  The sun's own brightest pixel A_max (its corneal glint, when the cornea sees the sun) is a
  glint the detector may take for an LED's: min S_k / A_max is reported beside.
  Its peak over the ambient's median on the iris, S_k / Ã_iris, is reported beside (the
  ambient on the glint's own pixel is 0 when the glint lies on a black pupil).
* Pupil: the LEDs' pupil–iris contrast C = Ĩ_iris − Ĩ_pupil (region medians: robust to the
  sun's glint, a few pixels) against the ambient's Ã_iris (the level the dark pupil must be
  told from) and the ambient's own contrast Ã_iris − Ã_pupil; with sunlight the Michelson
  contrast (I − P)/(I + P) of the sum falls from the LEDs' alone.
"""

from __future__ import annotations

import numpy as np

__all__ = ["signal_to_ambient"]


def _ratio(a: float, b: float) -> float | None:
    """a / b, None when b is 0 (no ambient there: the ratio is unbounded)."""
    return a / b if b > 0 else None


def _median(image: np.ndarray, mask: np.ndarray | None) -> float | None:
    if mask is None or not mask.any():
        return None
    return float(np.median(image[mask]))


def signal_to_ambient(
    led_image: np.ndarray, ambient_image: np.ndarray, regions: dict[str, np.ndarray]
) -> dict:
    """The glints' and the pupil's signal to ambient (module docstring).

    Parameters
    ----------
    led_image, ambient_image : (rows, cols) float64
        The LEDs' and the sunlight's pictures as the sensor counts them (W/mm² at the scene's
        wavelength); NaN pixels (an interrupted first round) are left out.
    regions : dict[str, (rows, cols) bool]
        ``pupil``, ``iris`` and, when the estimator labels them, ``glint k`` masks.

    Returns
    -------
    dict
        ``glints``: per LED {led, peak_w_mm2, ambient_w_mm2, signal_to_ambient,
        over_iris_ambient}; ``glint_signal_to_ambient_min``; ``ambient_peak_w_mm2`` and
        ``ambient_peak_pixel`` (row, col); ``glint_peak_over_ambient_peak`` (min glint peak /
        ambient peak); ``pupil``: LED and ambient medians of pupil and iris, the contrasts,
        ``signal_to_ambient`` = C / Ã_iris and
        the Michelson contrast without and with the ambient. A ratio whose denominator is 0 is
        None (JSON null).
    """
    ok = np.isfinite(led_image) & np.isfinite(ambient_image)
    led = np.where(ok, led_image, 0.0)
    amb = np.where(ok, ambient_image, 0.0)
    pupil, iris = regions.get("pupil"), regions.get("iris")
    pupil = None if pupil is None else pupil & ok
    iris = None if iris is None else iris & ok
    iris_amb = _median(amb, iris)
    glints = []
    for name in sorted(
        (k for k in regions if k.startswith("glint ")), key=lambda k: int(k.split()[1])
    ):
        mask = regions[name] & ok
        if not mask.any():
            continue
        flat = np.flatnonzero(mask)
        at = flat[int(np.argmax(led.ravel()[flat]))]
        peak, a = float(led.ravel()[at]), float(amb.ravel()[at])
        glints.append(
            {
                "led": int(name.split()[1]),
                "peak_w_mm2": peak,
                "ambient_w_mm2": a,
                "signal_to_ambient": _ratio(peak, a),
                "over_iris_ambient": _ratio(peak, iris_amb) if iris_amb is not None else None,
            }
        )
    peak_at = np.unravel_index(int(np.argmax(amb)), amb.shape)
    amb_peak = float(amb[peak_at])
    ratios = [g["signal_to_ambient"] for g in glints]
    out: dict = {
        "glints": glints,
        "glint_signal_to_ambient_min": (
            None if not glints or None in ratios else min(ratios)  # type: ignore[type-var]
        ),
        "ambient_peak_w_mm2": amb_peak,
        "ambient_peak_pixel": [int(peak_at[0]), int(peak_at[1])],
        "glint_peak_over_ambient_peak": (
            _ratio(min(g["peak_w_mm2"] for g in glints), amb_peak) if glints else None
        ),
    }
    p_led, i_led = _median(led, pupil), _median(led, iris)
    p_amb, i_amb = _median(amb, pupil), _median(amb, iris)
    if None in (p_led, i_led, p_amb, i_amb):
        out["pupil"] = None
        return out
    contrast = i_led - p_led  # type: ignore[operator]
    out["pupil"] = {
        "led_pupil_w_mm2": p_led,
        "led_iris_w_mm2": i_led,
        "ambient_pupil_w_mm2": p_amb,
        "ambient_iris_w_mm2": i_amb,
        "led_contrast_w_mm2": contrast,
        "ambient_contrast_w_mm2": i_amb - p_amb,  # type: ignore[operator]
        "signal_to_ambient": _ratio(contrast, i_amb),  # type: ignore[arg-type]
        "michelson_led": _ratio(contrast, i_led + p_led),  # type: ignore[operator]
        "michelson_with_ambient": _ratio(
            contrast + i_amb - p_amb,  # type: ignore[operator]
            i_led + p_led + i_amb + p_amb,  # type: ignore[operator]
        ),
    }
    return out
