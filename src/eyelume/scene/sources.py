"""LED emitters: angular profiles, placement (paper Fig. 8) and bodies.

An LED's body (:class:`eyelume.scene.model.LedArray`, ``body_shape``) is a sphere or a closed
cylinder coaxial with the LED's axis, about the LED's centre; here are the geometry the scene
checks use on it (world mm): :func:`body_support` (how far the body reaches along a
direction), :func:`cylinder_distance` (from points to a solid cylinder), :func:`inside_body`
and :func:`body_points` (its surface sampled, for tests against solids without a closed
form)."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

import numpy as np

from eyelume.errors import InputFileError
from eyelume.scene.model import LedArray, LedProfile
from eyelume.scene.textfile import read_csv_table

__all__ = [
    "TABLE_END_FRACTION",
    "LedBody",
    "bodies_overlap",
    "led_bodies",
    "body_points",
    "body_sample_step",
    "body_support",
    "cylinder_distance",
    "inside_body",
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


def body_support(shape: str, axis, radius: float, length: float, direction) -> float:
    """How far an LED body reaches from its centre along the unit ``direction`` (mm): the
    largest (p − c)·u over the body, r for a sphere of radius r; (L/2)|a·u| + r √(1 − (a·u)²)
    for a cylinder of radius r and length L along the unit axis a."""
    if shape == "sphere":
        return float(radius)
    cos = float(np.clip(np.dot(axis, direction), -1.0, 1.0))
    return length / 2 * abs(cos) + radius * math.sqrt(max(0.0, 1.0 - cos * cos))


def cylinder_distance(points, centre, axis, radius: float, length: float) -> np.ndarray:
    """Distance (mm) from each of ``points`` (M, 3) to the solid cylinder of ``radius`` and
    ``length`` about ``centre`` along the unit ``axis`` (0 inside): the hypotenuse of how far
    the point lies outside its radius and outside its two faces."""
    d = np.asarray(points, dtype=float).reshape(-1, 3) - np.asarray(centre, dtype=float)
    h = d @ np.asarray(axis, dtype=float)
    rho = np.linalg.norm(d - np.outer(h, axis), axis=1)
    return np.hypot(np.maximum(0.0, rho - radius), np.maximum(0.0, np.abs(h) - length / 2))


def inside_body(points, shape: str, centre, axis, radius: float, length: float) -> np.ndarray:
    """Whether each of ``points`` (M, 3) lies strictly inside the body (M,) bool."""
    d = np.asarray(points, dtype=float).reshape(-1, 3) - np.asarray(centre, dtype=float)
    if shape == "sphere":
        return np.linalg.norm(d, axis=1) < radius
    h = d @ np.asarray(axis, dtype=float)
    rho = np.linalg.norm(d - np.outer(h, axis), axis=1)
    return (rho < radius) & (np.abs(h) < length / 2)


#: Largest spacing (mm) of :func:`body_points` between neighbouring samples.
BODY_SAMPLE_MM = 0.1


def body_sample_step(radius: float, length: float) -> float:
    """The spacing s (mm) of :func:`body_points` for a body of ``radius`` and ``length``."""
    return min(BODY_SAMPLE_MM, max(2 * radius, length) / 32)


def body_points(shape: str, centre, axis, radius: float, length: float) -> np.ndarray:
    """Points on an LED body's surface (M, 3), world mm, no two neighbours farther apart than
    s = min(:data:`BODY_SAMPLE_MM`, size/32) (size the larger of its diameter and length):
    for a cylinder, rings on its side every ≤ s along the axis and concentric rings on its two
    faces; for a sphere, a Fibonacci lattice of ≈ 4πr²/s² points. Two closed convex solids
    overlap exactly when a point of one's surface lies inside the other (or one holds the
    other), so a test on these points misses only overlaps shallower than about s."""
    c = np.asarray(centre, dtype=float)
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    step = body_sample_step(radius, length)
    if shape == "sphere":
        n = max(16, math.ceil(4 * math.pi * radius * radius / (step * step)))
        i = np.arange(n) + 0.5
        z = 1.0 - 2.0 * i / n
        phi = math.pi * (3.0 - math.sqrt(5.0)) * i
        rho = np.sqrt(1.0 - z * z)
        return c + radius * np.stack([rho * np.cos(phi), rho * np.sin(phi), z], 1)
    helper = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = helper - (helper @ a) * a
    u /= np.linalg.norm(u)
    v = np.cross(a, u)

    def ring(r: float) -> np.ndarray:
        n = max(1, math.ceil(2 * math.pi * r / step)) if r > 0 else 1
        ang = 2 * math.pi * np.arange(n) / n
        return r * (np.outer(np.cos(ang), u) + np.outer(np.sin(ang), v))

    side = ring(radius)
    hs = np.linspace(-length / 2, length / 2, max(2, math.ceil(length / step) + 1))
    pts = [side + h * a for h in hs]
    disk = np.concatenate(
        [ring(r) for r in np.linspace(0.0, radius, max(2, math.ceil(radius / step) + 1))]
    )
    pts += [disk + length / 2 * a, disk - length / 2 * a]
    return c + np.concatenate(pts)


class LedBody(NamedTuple):
    """One LED's body (:class:`eyelume.scene.model.LedArray`), world mm: its shape
    (``"sphere"`` or ``"cylinder"``), centre, unit axis, radius (across the axis) and length
    (along it; a sphere's diameter)."""

    shape: str
    centre: np.ndarray
    axis: np.ndarray
    radius: float
    length: float

    @property
    def bound(self) -> float:
        """The radius of its bounding sphere about its centre (mm)."""
        return self.radius if self.shape == "sphere" else math.hypot(self.radius, self.length / 2)

    def words(self) -> str:
        """Its size for a message: ``radius 0.8`` (a sphere) or ``a cylinder 1.3 mm across,
        0.65 mm long``."""
        if self.shape == "sphere":
            return f"radius {self.radius}"
        return f"a cylinder {2 * self.radius:g} mm across, {self.length:g} mm long"

    def points(self) -> np.ndarray:
        """Its surface sampled (:func:`body_points`), (M, 3) world mm."""
        return body_points(self.shape, self.centre, self.axis, self.radius, self.length)

    def inside(self, points: np.ndarray) -> np.ndarray:
        """Which of ``points`` (M, 3) lie strictly inside it (M,) bool."""
        return inside_body(points, self.shape, self.centre, self.axis, self.radius, self.length)


def led_bodies(leds: LedArray, centres: np.ndarray, axes: np.ndarray) -> list[LedBody]:
    """Every LED's :class:`LedBody` at ``centres`` and unit ``axes`` (N, 3) (world mm)."""
    return [
        LedBody(shape, np.asarray(c, dtype=float), np.asarray(a, dtype=float), r, length)
        for shape, c, a, r, length in zip(
            leds.body_shapes(),
            centres,
            axes,
            leds.body_radii_mm(),
            leds.body_lengths_mm(),
            strict=True,
        )
    ]


def bodies_overlap(a: LedBody, b: LedBody) -> bool:
    """Whether two LED bodies overlap: two spheres, their centres nearer than the sum of their
    radii; a sphere and a cylinder, the sphere's centre nearer the solid cylinder than its
    radius (:func:`cylinder_distance`), exact; two cylinders, a sampled point of one's surface
    inside the other (:func:`body_points`)."""
    if a.shape == "sphere" and b.shape == "sphere":
        return bool(np.linalg.norm(a.centre - b.centre) < a.radius + b.radius)
    if np.linalg.norm(a.centre - b.centre) >= a.bound + b.bound:
        return False  # their bounding spheres are apart
    if b.shape == "sphere":
        a, b = b, a
    if a.shape == "sphere":
        gap = cylinder_distance(a.centre, b.centre, b.axis, b.radius, b.length)[0]
        return bool(gap < a.radius)
    return bool(b.inside(a.points()).any() or a.inside(b.points()).any())
