"""LED emitters: angular profiles and placement (paper Fig. 8)."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

from eyelume.errors import InputFileError
from eyelume.scene.model import LedArray, LedProfile
from eyelume.scene.textfile import read_csv_table

__all__ = [
    "TABLE_END_FRACTION",
    "cos_power_exponent",
    "led_poses",
    "ring_basis",
    "ring_poses",
    "read_profile_table",
    "relative_intensity",
]


def cos_power_exponent(half_intensity_angle_deg: float) -> float:
    """Exponent m of I(α) = I₀ cosᵐ α with I(α½) = I₀/2: m = ln ½ / ln cos α½.

    Examples
    --------
    >>> round(cos_power_exponent(22.5), 3)
    8.755
    """
    return math.log(0.5) / math.log(math.cos(math.radians(half_intensity_angle_deg)))


_FIELD = "leds.profile.table_csv"

#: A table may end before 90° only where its intensity is at most this share of the on-axis
#: value: beyond its last row the LED is taken to emit nothing, which then misses at most
#: about this share of the power per steradian at those angles.
TABLE_END_FRACTION = 0.01
#: Largest relative intensity I(α)/I(0) a profile table may reach: off-axis peaks of real LEDs
#: (batwing and side-emitting packages) are a few times the on-axis value; far more is a typo
#: or a unit mix-up (and 1e308 overflowed the power integral).
MAX_PROFILE_PEAK = 100.0


def read_profile_table(path: str) -> tuple[np.ndarray, np.ndarray]:
    """An LED profile table: (angles in rad from 0, intensity relative to the on-axis value).

    The file (CSV as datasheets and spreadsheets export it: UTF-8 with or without a byte-order
    mark, UTF-16, or Windows-1252; see :func:`eyelume.scene.textfile.decode_text`) holds two
    columns, angle in degrees and relative intensity in any unit, one row per angle; lines
    starting with ``#`` are skipped, and a first row of words only (``angle_deg, intensity``:
    :func:`~eyelume.scene.textfile.is_header_row`) as its header; a row of another number of
    columns, or a first row mixing numbers and words, is refused. Angles start at 0, increase
    and end at or below 90°; intensities are finite and ≥ 0, the on-axis one > 0.

    The table must reach the intensity's end: where it stops before 90° with the intensity above
    :data:`TABLE_END_FRACTION` of the on-axis value it is refused, because the power beyond is
    unknown (a curve that ends at 30° at 28 % leaves a quarter of a typical LED's power
    unaccounted for). To say that nothing is emitted beyond, end the table with a zero row.

    Raises
    ------
    InputFileError
        One line naming the file (and the row) and the value.
    """
    where = Path(path)
    a, v = _numbers(where)
    if len(a) < 2 or a[0] != 0 or np.any(np.diff(a) <= 0) or a[-1] > 90:
        raise InputFileError(
            f"{len(a)} rows of angles {a[:6].tolist()}{' ...' if len(a) > 6 else ''}: "
            "angles must start at 0, increase, and end at or below 90 deg",
            file=where,
            field=_FIELD,
        )
    if v[0] <= 0:
        raise InputFileError(
            f"the on-axis (0 deg) intensity is {float(v[0])!r}, must be > 0",
            file=where,
            field=_FIELD,
        )
    with np.errstate(over="ignore"):
        rel = v / v[0]
    if not np.all(np.isfinite(rel)):
        raise InputFileError(
            f"the intensities relative to the on-axis value {float(v[0])!r} overflow (up to "
            f"{float(v.max())!r}): not a usable profile",
            file=where,
            field=_FIELD,
        )
    if rel.max() > MAX_PROFILE_PEAK:
        k = int(np.argmax(rel))
        raise InputFileError(
            f"the intensity at {a[k]:g} deg is {rel[k]:.3g} times the on-axis value (more than "
            f"{MAX_PROFILE_PEAK:g}): not a plausible LED profile",
            file=where,
            field=_FIELD,
        )
    if a[-1] < 90 and rel[-1] > TABLE_END_FRACTION:
        raise InputFileError(
            f"the table ends at {a[-1]:g} deg with the intensity still at {rel[-1]:.0%} of the "
            "on-axis value: the power beyond is unknown. Extend it to where the intensity "
            f"reaches 0, or add a row '{np.nextafter(a[-1], 90.0):.6g}, 0' to state that the "
            "LED emits nothing beyond",
            file=where,
            field=_FIELD,
        )
    return np.radians(a), rel


def _numbers(where: Path) -> tuple[np.ndarray, np.ndarray]:
    """(angles, intensities) of the table (:func:`~eyelume.scene.textfile.read_csv_table`)."""
    table = read_csv_table(where, _FIELD, ("angle_deg", "relative_intensity"))
    for n, (a, v) in enumerate(table, 1):
        if not (math.isfinite(a) and math.isfinite(v)) or v < 0:
            raise InputFileError(
                f"row {n} of numbers ({a:g}, {v:g}): angle and intensity must be finite, "
                "intensity >= 0",
                file=where,
                field=_FIELD,
            )
    return table[:, 0], table[:, 1]


def relative_intensity(profile: LedProfile) -> Callable[[np.ndarray], np.ndarray]:
    """I(α)/I(0) as a vectorised function of α (radians from the LED axis, 0 … π/2)."""
    if profile.kind == "cos_power":
        m = cos_power_exponent(profile.half_intensity_angle_deg)
        return lambda alpha: np.cos(alpha) ** m
    alpha_t, value_t = read_profile_table(profile.table_csv)
    return lambda alpha: np.interp(alpha, alpha_t, value_t, right=0.0)


def ring_basis(leds: LedArray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The ring's centre c and orthonormal basis ê₁, ê₂, n̂ (world), :class:`LedArray`."""
    c = np.asarray(leds.ring_centre_mm, dtype=float)
    n = np.asarray(leds.ring_axis, dtype=float)
    n = n / np.linalg.norm(n)
    if tuple(leds.ring_axis) == (0.0, 0.0, 1.0):
        return c, np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), n
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = helper - (helper @ n) * n
    e1 /= np.linalg.norm(e1)
    return c, e1, np.cross(n, e1), n


def ring_poses(leds: LedArray, heights, distances, pitches) -> tuple[np.ndarray, np.ndarray]:
    """Body centres and unit axes, (n, N, 3) each (world mm), of the ring ``leds`` at n
    configurations (Y, Z, θ) (arrays of n): the one definition of the ring (class
    :class:`LedArray`). Raises ValueError for LEDs placed one by one (no ring to vary)."""
    if leds.positions_mm is not None:
        raise ValueError("the LEDs are placed one by one (leds.positions_mm): no ring to vary")
    y = np.asarray(heights, dtype=float).reshape(-1, 1, 1)
    z = np.asarray(distances, dtype=float).reshape(-1, 1, 1)
    th = np.radians(np.asarray(pitches, dtype=float)).reshape(-1, 1, 1)
    phi = np.radians(np.asarray(leds.azimuths(), dtype=float)).reshape(1, -1, 1)
    c, e1, e2, n = ring_basis(leds)
    radial = np.cos(phi) * e1 + np.sin(phi) * e2  # (1, N, 3)
    centres = c + y * radial + z * n
    if leds.aim_at_mm is not None:
        d = np.asarray(leds.aim_at_mm, dtype=float) - centres
        axes = d / np.linalg.norm(d, axis=2, keepdims=True)
    else:
        axes = -np.sin(th) * radial - np.cos(th) * n
    return centres, axes


def led_poses(leds: LedArray) -> tuple[np.ndarray, np.ndarray]:
    """Body centres (N, 3) and unit axes (N, 3) of the LEDs in the world frame (mm): the ring
    (:func:`ring_poses`; the paper's: centre (Y cos φ, Y sin φ, Z), axis pitched by θ from −z
    toward the axis, a = (−sin θ cos φ, −sin θ sin φ, −cos θ)) or the LEDs one by one."""
    if leds.positions_mm is None:
        centres, axes = ring_poses(leds, [leds.height_mm], [leds.distance_mm], [leds.pitch_deg])
        return centres[0], axes[0]
    centres = np.asarray(leds.positions_mm, dtype=float).reshape(-1, 3)
    if leds.directions is not None:
        d = np.asarray(leds.directions, dtype=float).reshape(-1, 3)
    else:
        d = np.asarray(leds.aim_at_mm, dtype=float) - centres
    return centres, d / np.linalg.norm(d, axis=1, keepdims=True)
