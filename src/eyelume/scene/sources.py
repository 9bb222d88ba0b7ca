"""LED emitters: angular profiles and placement (paper Fig. 8)."""

from __future__ import annotations

import csv
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

from eyelume.scene.model import LedArray, LedProfile

__all__ = ["cos_power_exponent", "led_poses", "relative_intensity"]


def cos_power_exponent(half_intensity_angle_deg: float) -> float:
    """Exponent m of I(α) = I₀ cosᵐ α with I(α½) = I₀/2: m = ln ½ / ln cos α½.

    Examples
    --------
    >>> round(cos_power_exponent(22.5), 3)
    8.755
    """
    return math.log(0.5) / math.log(math.cos(math.radians(half_intensity_angle_deg)))


def _read_table(path: str) -> tuple[np.ndarray, np.ndarray]:
    where = f"leds.profile.table_csv = '{path}'"
    try:
        with Path(path).open(newline="", encoding="utf-8") as fh:
            rows = [r for r in csv.reader(fh) if r and not r[0].lstrip().startswith("#")]
    except OSError as exc:
        raise ValueError(f"{where}: cannot read ({exc.strerror})") from None
    angles, values = [], []
    for n, row in enumerate(rows, 1):
        try:
            a, v = float(row[0]), float(row[1])
        except (ValueError, IndexError):
            if n == 1:
                continue  # a header line
            raise ValueError(
                f"{where}: row {n} {row!r} is not 'angle_deg, relative_intensity'"
            ) from None
        if not (math.isfinite(a) and math.isfinite(v)) or v < 0:
            raise ValueError(f"{where}: row {n} has a bad value {row!r}")
        angles.append(a)
        values.append(v)
    a = np.asarray(angles)
    v = np.asarray(values)
    if len(a) < 2 or a[0] != 0 or np.any(np.diff(a) <= 0) or a[-1] > 90:
        raise ValueError(f"{where}: angles must start at 0, increase, and end at or below 90 deg")
    if v[0] <= 0:
        raise ValueError(f"{where}: the on-axis relative intensity must be > 0")
    return np.radians(a), v / v[0]


def relative_intensity(profile: LedProfile) -> Callable[[np.ndarray], np.ndarray]:
    """I(α)/I(0) as a vectorised function of α (radians from the LED axis, 0 … π/2)."""
    if profile.kind == "cos_power":
        m = cos_power_exponent(profile.half_intensity_angle_deg)
        return lambda alpha: np.cos(alpha) ** m
    alpha_t, value_t = _read_table(profile.table_csv)
    return lambda alpha: np.interp(alpha, alpha_t, value_t, right=0.0)


def led_poses(leds: LedArray) -> tuple[np.ndarray, np.ndarray]:
    """Body centres (N, 3) and unit axes (N, 3) of the LEDs in the world frame (mm).

    LED i at azimuth φ: centre (Y cos φ, Y sin φ, Z), axis pitched by θ from −z toward the axis:
    a = (−sin θ cos φ, −sin θ sin φ, −cos θ).
    """
    phi = np.radians(leds.azimuths())
    th = math.radians(leds.pitch_deg)
    centres = np.stack(
        [
            leds.height_mm * np.cos(phi),
            leds.height_mm * np.sin(phi),
            np.full_like(phi, leds.distance_mm),
        ],
        axis=1,
    )
    axes = np.stack(
        [
            -math.sin(th) * np.cos(phi),
            -math.sin(th) * np.sin(phi),
            np.full_like(phi, -math.cos(th)),
        ],
        axis=1,
    )
    return centres, axes
