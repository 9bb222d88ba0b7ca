"""Gaze from the pupil and glint positions in the camera picture.

Two estimators, and the forward model that makes their test data:

- :class:`PccrModel` — the pupil-centre/corneal-reflection (PCCR) polynomial: a per-user
  second-order polynomial from the pupil–glint vector (pixels) to the gaze angles (degrees),
  fitted by least squares on a calibration grid. No geometry; valid only near the head pose and
  over the range it was calibrated at.
- :class:`GeometricGaze` — the model of Guestrin & Eizenman, "General theory of remote gaze
  estimation using the pupil center and corneal reflections", IEEE TBME 53(6), 2006: the
  cornea as a spherical mirror of radius R, at least two LEDs at known positions, a calibrated
  camera. It finds the centre of corneal curvature **c** from the glints, the pupil centre **p**
  by refracting the pupil's camera ray at the corneal sphere, and the optical axis
  ω = (**p** − **c**)/|**p** − **c**|. No per-user polynomial; only the eye parameters R, K, n
  and (optionally) the angle kappa between the optical and visual axes.
- :func:`simulate_eye_features` — the exact pupil and glint picture positions of that same eye
  model rotated to a given gaze (the test truth).

Frames and units (ARCHITECTURE.md §2): world frame in mm, the headset's (the anterior corneal vertex
in primary gaze at the eye's pose, the origin by default), +z from the eye toward the camera, +y
up, +x toward the nose of a right eye (a left eye's scene is mirrored: there +x is temporal).
Picture positions are (col, row) in pixels, continuous, pixel centres at integers, row 0 at the
top of the upright picture. Gaze angles are in degrees:

    horizontal h = atan2(ω_x, ω_z),   vertical v = atan2(ω_y, hypot(ω_x, ω_z)),

so an eye looking straight at the camera (ω = +z) has (h, v) = (0, 0), h > 0 turns it toward +x
(the nose) and v > 0 up; conversely ω = (cos v sin h, sin v, cos v cos h) (Fick angles: the
horizontal turn about +y, then the vertical one about the turned x axis).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq, least_squares

__all__ = [
    "EyeFeatures",
    "GazeEstimate",
    "GeometricGaze",
    "ModelEye",
    "PccrModel",
    "PinholeCamera",
    "SPHERE_ZONE_DEG",
    "axis_from_angles",
    "angles_from_axis",
    "glint_offsets",
    "pupil_glint_vector",
    "simulate_eye_features",
]


# --- angles ---------------------------------------------------------------------------------------


def axis_from_angles(h_deg: float, v_deg: float) -> np.ndarray:
    """Unit gaze direction ω = (cos v sin h, sin v, cos v cos h) of angles (h, v) in degrees.

    >>> axis_from_angles(0.0, 0.0)
    array([0., 0., 1.])
    """
    h, v = math.radians(h_deg), math.radians(v_deg)
    return np.array([math.cos(v) * math.sin(h), math.sin(v), math.cos(v) * math.cos(h)])


def angles_from_axis(axis: np.ndarray) -> tuple[float, float]:
    """Gaze angles (h, v) in degrees of a direction: h = atan2(ω_x, ω_z), v = atan2(ω_y, ρ).

    ρ = hypot(ω_x, ω_z); the inverse of :func:`axis_from_angles`.

    >>> [round(a, 9) for a in angles_from_axis(axis_from_angles(12.0, -7.0))]
    [12.0, -7.0]
    """
    x, y, z = (float(a) for a in axis)
    return math.degrees(math.atan2(x, z)), math.degrees(math.atan2(y, math.hypot(x, z)))


def _unit(a: np.ndarray) -> np.ndarray:
    return a / np.linalg.norm(a, axis=-1, keepdims=True)


# --- camera ---------------------------------------------------------------------------------------


class PinholeCamera:
    """The eye camera as a pinhole: a node O and the eye plane z = 0 it is focused on.

    The lens images the eye plane onto the sensor at transverse magnification ``magnification``
    (−1.144 for the paper's Double Gauss); the picture is shown upright. Pixel (col, row) of the
    ``cols`` × ``rows`` picture, pitch p = ``sensor_width_mm`` / ``cols`` (46/87 mm by default),
    sees the point of the plane z = 0

        X = (col + 0.5 − cols/2) · p/|m|,   Y = (rows/2 − row − 0.5) · p/|m|

    (the sample at integer (col, row) is the centre of that pixel), along the ray from the node
    O = ``node_mm`` (the entrance pupil, (0, 0, 174.66) mm by default) through that point. Any
    point is pictured where its line to O crosses z = 0 (:meth:`project`).

    All of this is in the camera's frame (:mod:`eyelume.scene.pose`: z along the lens axis, the
    plane in focus at z = 0), which is the world frame for the paper's rig. ``frame`` (a
    :class:`eyelume.scene.pose.Frame`, world → camera frame; None: the identity) turns gaze
    directions and targets between the two (:meth:`to_world`, :meth:`from_world`).

    >>> cam = PinholeCamera()
    >>> cam.project(cam.pixel_to_plane(np.array([10.0, 20.0])))
    array([10., 20.])
    """

    def __init__(
        self,
        node_mm: Sequence[float] = (0.0, 0.0, 174.66),
        cols: int = 87,
        rows: int = 65,
        sensor_width_mm: float = 46.0,
        magnification: float = -1.144,
        frame=None,
    ) -> None:
        self.frame = frame
        self.node = np.asarray(node_mm, dtype=float)
        if self.node[2] <= 0:
            raise ValueError(f"node_mm must lie in front of the eye (z > 0), got {node_mm}")
        self.cols, self.rows = int(cols), int(rows)
        self.pitch_mm = sensor_width_mm / cols
        #: Size of one pixel on the eye plane, mm.
        self.scale_mm = self.pitch_mm / abs(magnification)

    def to_world(self, direction: np.ndarray) -> np.ndarray:
        """A camera-frame direction (3,) in the world frame."""
        return direction if self.frame is None else self.frame.world_vector(direction)

    def from_world(self, point_mm: np.ndarray) -> np.ndarray:
        """A world point (3,) mm in the camera frame."""
        return point_mm if self.frame is None else self.frame.point(point_mm)

    def pixel_to_plane(self, px: np.ndarray) -> np.ndarray:
        """Points (..., 3) on the plane z = 0 seen by picture positions ``px`` (..., 2)."""
        px = np.asarray(px, dtype=float)
        x = (px[..., 0] + 0.5 - self.cols / 2) * self.scale_mm
        y = (self.rows / 2 - px[..., 1] - 0.5) * self.scale_mm
        return np.stack([x, y, np.zeros_like(x)], axis=-1)

    def ray(self, px: np.ndarray) -> np.ndarray:
        """Unit directions (..., 3) from the node toward the eye of picture positions (..., 2)."""
        return _unit(self.pixel_to_plane(px) - self.node)

    def project(self, points_mm: np.ndarray) -> np.ndarray:
        """Picture positions (..., 2) of world points (..., 3) (which must lie at z < O_z)."""
        pts = np.asarray(points_mm, dtype=float)
        s = self.node[2] / (self.node[2] - pts[..., 2])
        xy = self.node[:2] + s[..., None] * (pts[..., :2] - self.node[:2])
        col = xy[..., 0] / self.scale_mm - 0.5 + self.cols / 2
        row = self.rows / 2 - 0.5 - xy[..., 1] / self.scale_mm
        return np.stack([col, row], axis=-1)

    def in_picture(self, px: np.ndarray) -> bool:
        """Whether a picture position lies inside the picture's pixels."""
        c, r = float(px[0]), float(px[1])
        return -0.5 <= c <= self.cols - 0.5 and -0.5 <= r <= self.rows - 0.5


# --- optics of the corneal sphere --------------------------------------------------------------


def _sphere_hit(o: np.ndarray, u: np.ndarray, c: np.ndarray, r: float) -> float | None:
    """Distance along the unit ray o + s u to its first crossing of the sphere |x − c| = r."""
    b = float(u @ (o - c))
    disc = b * b - (float((o - c) @ (o - c)) - r * r)
    if disc < 0:
        return None
    return -b - math.sqrt(disc)


def _refract(u: np.ndarray, normal: np.ndarray, eta: float) -> np.ndarray | None:
    """Snell's law, vector form: t = η u + (η cos i − cos t) N, cos i = −N·u, η = n₁/n₂.

    ``u`` the unit incident direction, ``normal`` the unit normal on the incident side; None on
    total internal reflection.
    """
    cos_i = -float(normal @ u)
    k = 1.0 - eta * eta * (1.0 - cos_i * cos_i)
    if k < 0:
        return None
    return eta * u + (eta * cos_i - math.sqrt(k)) * normal


# --- PCCR polynomial ------------------------------------------------------------------------------


def _glint_array(glints_xy: np.ndarray | Sequence) -> np.ndarray:
    if isinstance(glints_xy, np.ndarray):
        return glints_xy.astype(float)
    return np.array([[np.nan, np.nan] if q is None else q for q in glints_xy], dtype=float)


def glint_offsets(glints_xy: np.ndarray) -> np.ndarray:
    """Each LED's glint offset from the glint pattern's centre, px, from frames with some
    glints missing: the least-squares solution of g_fk = C_f + o_k over the found glints
    (frame f's pattern centre C_f, LED k's offset o_k), with Σ_k o_k = 0 — so a frame with
    every glint found has C_f = the mean of its glints, the classic PCCR reference.

    With o_k, the centre of a frame missing some glints is the mean over its found ones of
    g_k − o_k (:func:`pupil_glint_vector` with ``offsets``): unbiased, where the mean of the
    found glints alone moves toward them by up to the pattern's radius (on a headset with 6–8
    LEDs around an eye seen off its axis, some glints fall off the cornea at most gazes). The
    offsets change a little with gaze (the cornea turns under the LEDs); the calibration grid's
    frames give their mean.

    Parameters
    ----------
    glints_xy : (n, k, 2) glint centres of n frames and k LEDs, NaN where not found.

    Returns
    -------
    (k, 2) offsets, NaN for an LED found in no frame (its glint cannot be used) or in no frame
    that shares a found glint with the others.

    >>> g = np.array([[[0., 0.], [2., 0.], [1., 3.]], [[5., 5.], [np.nan, np.nan], [6., 8.]]])
    >>> (glint_offsets(g).round(6) + 0.0).tolist()  # + 0.0: a least-squares −0.0 prints as 0.0
    [[-1.0, -1.0], [1.0, -1.0], [0.0, 2.0]]
    """
    g = np.asarray(glints_xy, dtype=float).reshape(-1, np.shape(glints_xy)[-2], 2)
    n, k, _ = g.shape
    found = np.all(np.isfinite(g), axis=-1)
    frames, leds = np.nonzero(found)
    out = np.full((k, 2), np.nan)
    if len(frames) == 0:
        return out
    # Unknowns: C_f (n) then o_k (k); one row per found glint and the gauge row Σ o_k = 0 over
    # the LEDs seen (the model's one free direction, C_f + t, o_k − t, leaves the data's
    # residual unchanged, so the gauge row holds exactly).
    seen = np.unique(leds)
    a = np.zeros((len(frames) + 1, n + k))
    a[np.arange(len(frames)), frames] = 1.0
    a[np.arange(len(frames)), n + leds] = 1.0
    a[-1, n + seen] = 1.0
    b = np.zeros((len(frames) + 1, 2))
    b[:-1] = g[frames, leds]
    sol, *_ = np.linalg.lstsq(a, b, rcond=None)
    # An LED is determined when the frames it is seen in share glints with the others: the
    # design's rank is then n_used + k_seen − 1 (+ 1 for the gauge row).
    used = np.unique(frames)
    sub = a[:, np.r_[used, n + seen]]
    if np.linalg.matrix_rank(sub) == len(used) + len(seen):
        out[seen] = sol[n + seen]
    return out


def pupil_glint_vector(
    pupil_xy: np.ndarray,
    glints_xy: np.ndarray | Sequence,
    which: int | None = None,
    *,
    offsets: np.ndarray | None = None,
) -> np.ndarray:
    """The pupil–glint vector: pupil centre minus the mean of the matched glints, pixels.

    Parameters
    ----------
    pupil_xy : (2,) or (n, 2)
        Pupil centres in the picture, (col, row) px.
    glints_xy : (k, 2) or (n, k, 2)
        Glint centres, NaN (or ``None`` in a single frame's list) for a glint not found.
    which : int, optional
        Use glint ``which`` alone instead of the mean of the found ones.
    offsets : (k, 2), optional
        Each LED's glint offset from the pattern's centre (:func:`glint_offsets`): the
        reference is then the mean over the found glints of g_k − o_k, the pattern's centre
        whichever glints are missing (glints of LEDs with a NaN offset are not used).

    Returns
    -------
    (2,) or (n, 2) : pupil − glint reference; NaN where no glint (or glint ``which``) was found.

    >>> pupil_glint_vector(np.array([10.0, 5.0]), [[8.0, 4.0], None, [10.0, 4.0]])
    array([1., 1.])
    >>> o = np.array([[-1.0, 0.0], [0.0, -1.0], [1.0, 0.0], [0.0, 1.0]])
    >>> pupil_glint_vector(np.array([10.0, 5.0]), [[8.0, 4.0], [9.0, 3.0], None, None], offsets=o)
    array([1., 1.])
    """
    pupil = np.asarray(pupil_xy, dtype=float)
    g = _glint_array(glints_xy)
    if offsets is not None:
        g = g - np.asarray(offsets, dtype=float)
    if which is not None:
        ref = g[..., which, :]
    else:
        found = np.all(np.isfinite(g), axis=-1, keepdims=True)
        n = found.sum(axis=-2)
        with np.errstate(invalid="ignore", divide="ignore"):
            ref = np.where(found, g, 0.0).sum(axis=-2) / n
        ref = np.where(n > 0, ref, np.nan)
    return pupil - ref


def _quadratic_terms(v: np.ndarray) -> np.ndarray:
    x, y = v[:, 0], v[:, 1]
    return np.stack([np.ones_like(x), x, y, x * x, x * y, y * y], axis=1)


@dataclass(frozen=True)
class PccrModel:
    """Second-order PCCR polynomial: gaze angle = a₀ + a₁x + a₂y + a₃x² + a₄xy + a₅y².

    (x, y) is the pupil–glint vector in pixels (:func:`pupil_glint_vector`); each gaze output
    (h, v in degrees) has its own 6 coefficients, rows of ``coefficients`` (2, 6). Fitted by
    least squares over the calibration targets; the classic 9-point grid (3 × 3 targets)
    determines the 6 coefficients with 3 to spare. The polynomial reproduces its calibration
    targets exactly only when the true mapping is itself quadratic; the real one (refraction,
    the eye's rotation) is not, so it interpolates inside the calibrated range and extrapolates
    poorly outside it.

    >>> v = np.array([[x, y] for x in (-3.0, 0.0, 3.0) for y in (-2.0, 0.0, 2.0)])
    >>> m = PccrModel.fit(v, 5.0 * v)
    >>> m.predict(np.array([[1.0, 1.0]])).round(9)
    array([[5., 5.]])
    """

    coefficients: np.ndarray
    residual_rms_deg: float = 0.0

    @classmethod
    def fit(cls, pg_vectors: np.ndarray, gaze_deg: np.ndarray) -> PccrModel:
        """Least-squares fit on ``pg_vectors`` (n, 2) px → ``gaze_deg`` (n, 2), n ≥ 6."""
        v = np.asarray(pg_vectors, dtype=float).reshape(-1, 2)
        g = np.asarray(gaze_deg, dtype=float).reshape(-1, 2)
        if len(v) != len(g):
            raise ValueError(f"{len(v)} pupil-glint vectors but {len(g)} gaze targets")
        if not np.all(np.isfinite(v)) or not np.all(np.isfinite(g)):
            raise ValueError("calibration data must be finite (a missing glint or pupil?)")
        a = _quadratic_terms(v)
        if len(v) < 6 or np.linalg.matrix_rank(a) < 6:
            raise ValueError(
                "the 6-term quadratic needs >= 6 calibration points not all on one conic "
                f"(got {len(v)}); use a 3 x 3 target grid"
            )
        coef, *_ = np.linalg.lstsq(a, g, rcond=None)
        rms = float(np.sqrt(np.mean((a @ coef - g) ** 2)))
        return cls(coefficients=coef.T.copy(), residual_rms_deg=rms)

    def predict(self, pg_vectors: np.ndarray) -> np.ndarray:
        """Gaze angles (n, 2) in degrees, (h, v), of pupil–glint vectors (n, 2) px."""
        v = np.asarray(pg_vectors, dtype=float).reshape(-1, 2)
        return _quadratic_terms(v) @ self.coefficients.T


# --- geometric model (Guestrin & Eizenman 2006) -----------------------------------------------


@dataclass(frozen=True)
class GazeEstimate:
    """One frame's gaze. Angles in degrees (module docstring), positions in world mm.

    ``h_deg``, ``v_deg`` are the visual axis (the optical axis plus the kappa offsets; the
    optical axis when kappa is 0); ``optical_axis`` is ω, unit. On failure ``ok`` is False, the
    numbers are NaN and ``reason`` says why; ``reason`` may also carry a warning when ok.
    """

    h_deg: float
    v_deg: float
    cornea_centre_mm: np.ndarray
    pupil_centre_mm: np.ndarray
    ok: bool
    reason: str = ""
    optical_axis: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    glints_used: int = 0
    #: matched glints left out as lying outside the spherical cornea's validity zone
    #: (``GeometricGaze(zone_deg=…)``); 0 without a zone
    glints_outside_zone: int = 0


def _failed(
    reason: str, n_glints: int = 0, c: np.ndarray | None = None, outside: int = 0
) -> GazeEstimate:
    nan3 = np.full(3, np.nan)
    c = nan3 if c is None else c
    return GazeEstimate(math.nan, math.nan, c, nan3, False, reason, nan3, n_glints, outside)


#: The spherical cornea's validity zone (degrees) that ``evaluate-tracking`` gives the
#: geometric model (``GeometricGaze(zone_deg=…)``). A real anterior cornea is a prolate
#: conicoid, flatter away from its apex: the presets' Arizona cornea (R 7.8 mm, Q −0.25) has at
#: a point whose normal makes the angle θ with its axis the local radii
#: R_sagittal = R (1 + Q sin²θ)^(−1/2) and R_tangential = R (1 + Q sin²θ)^(−3/2), 3.3 % and
#: 10.2 % above R at θ = 30°, 6.9 % and 22 % at 45°. A sphere of radius R fitted to glints
#: reflected there puts the centre of curvature up to 1.4 mm off (vr-offaxis, whose camera
#: 50° off the eye's axis sees glints 5–48° from the apex): on the renderer's exact glints and
#: pupil the model read (−30°, 0°) as −39.6° after its kappa (README, "Tracking on the
#: presets"). 30° is where R_tangential reaches 1.10 R.
SPHERE_ZONE_DEG = 30.0


@dataclass(frozen=True)
class ModelEye:
    """The spherical-cornea eye that :func:`simulate_eye_features` turns to a gaze (mm).

    ``R``, ``K``, ``n``: the corneal sphere's radius, the distance from its centre to the pupil
    centre and the effective index, as :class:`GeometricGaze` takes them (their defaults are
    these: the Arizona eye's 7.8 mm anterior cornea, K = 7.8 − 3.6 = 4.2 mm, the keratometric
    index 1.3375). ``rotation_centre_mm``: depth of the centre of rotation behind the corneal
    vertex (13.5, the usual value). ``cap_radius_mm``: the corneal cap's semi-diameter (the
    Arizona cornea's 6 mm); a glint farther than this from the optical axis is missing.
    ``offset_mm``: the corneal vertex in primary gaze (the world origin by default).
    """

    R: float = 7.8
    K: float = 4.2
    n: float = 1.3375
    rotation_centre_mm: float = 13.5
    cap_radius_mm: float = 6.0
    offset_mm: tuple[float, float, float] = (0.0, 0.0, 0.0)


class GeometricGaze:
    """Gaze by the geometric model of Guestrin & Eizenman (2006), from ≥ 2 glints.

    The model's cornea is a sphere of one radius R centred on the optical axis: an astigmatic,
    decentred or tilted cornea in the scene (``eye.cornea``) is outside it, and its gaze error
    is part of what ``evaluate-tracking`` measures (the renders use the real quadric).

    Parameters
    ----------
    camera : PinholeCamera
        Gives each picture position its ray from the node O.
    leds_mm : (N, 3)
        World positions of the LEDs' emission points (the apex of each body), mm.
    R : float
        Radius of the corneal sphere, mm (7.8: the Arizona eye's anterior cornea).
    K : float
        Distance from the cornea's centre of curvature to the pupil centre, mm. The Arizona eye's
        pupil (the iris, in the anterior lens's vertex plane) lies 0.55 + 3.05 = 3.6 mm behind
        the corneal vertex, so K = 7.8 − 3.6 = 4.2.
    n : float
        Effective index of the cornea and aqueous humour for the pupil ray (1.3375, the
        keratometric index): the cornea is one refracting sphere.
    kappa_deg : (float, float)
        Offsets (h, v) added to the optical axis's angles to give the visual axis (from a
        one-point calibration, :meth:`calibrate_kappa`). An additive angle offset is a small-angle
        stand-in for kappa, which is really a fixed rotation in the eye's frame.
    zone_deg : float, optional
        The spherical cornea's validity zone, degrees (None: every matched glint is used, the
        model as published; ``evaluate-tracking`` uses :data:`SPHERE_ZONE_DEG`). A glint whose
        reflection point on the fitted sphere lies farther than ``zone_deg`` from the estimated
        optical axis (the angle at **c** between **q**ᵢ − **c** and ω) is left out and the
        fit repeated on the others (step (v) below); a frame with fewer than 2 glints inside
        is refused, saying so. A real cornea is aspheric (:data:`SPHERE_ZONE_DEG`): glints far
        from its apex bias **c**, and through it the gaze, by degrees.

    Notes
    -----
    (i) Centre of corneal curvature **c**. Glint i is pictured along the unit camera ray
    **u**ᵢ; its reflection point is **q**ᵢ = O + kᵢ **u**ᵢ. The unknowns (**c**, k₁ … k_m) solve
    by nonlinear least squares (``scipy.optimize.least_squares``, Levenberg–Marquardt) the
    residuals, for each found glint,

        |**q**ᵢ − **c**| − R = 0                       (q on the corneal sphere)
        R · (**ĥ**ᵢ − (**q**ᵢ − **c**)/|**q**ᵢ − **c**|) = 0   (law of reflection)

    with **ĥ**ᵢ the unit bisector of (Lᵢ − **q**ᵢ)/|·| and (O − **q**ᵢ)/|·|: the normal at **q**ᵢ
    must bisect the directions to the LED and to the camera, which holds exactly when the
    incident ray, the reflected ray and the normal are coplanar and make equal angles. Each
    glint adds one unknown and three independent equations, so m = 2 glints give 6 equations in
    5 unknowns (Guestrin & Eizenman: c is determined from two LEDs). The start is the
    reflection geometry at the camera rays' crossings with z = 0.

    (ii) Pupil centre **p**. The camera ray through the pupil's image centre meets the sphere at
    **r**; it is refracted there (Snell, vector form, air → n) and **p** is its first point at
    |**p** − **c**| = K. (The centre of the pupil's image is taken as the image of the pupil
    centre, as in the paper.)

    (iii) ω = (**p** − **c**)/|**p** − **c**| → (h, v) by :func:`angles_from_axis`.

    (iv) Visual axis: (h, v) + ``kappa_deg``.

    (v) With ``zone_deg``: each found glint's camera ray is met with the fitted sphere (**c**,
    R) at **q**ᵢ (a ray that misses it is outside); the glints within ``zone_deg`` of ω are
    kept and (i)–(iii) repeated on them, up to 5 times, until the kept set stops changing.

    The estimate needs no per-user calibration beyond R, K, n (and kappa), and it follows the
    eye when the head moves — the geometric model's advantage over :class:`PccrModel`.
    """

    def __init__(
        self,
        camera: PinholeCamera,
        leds_mm: np.ndarray,
        R: float = ModelEye.R,
        K: float = ModelEye.K,
        n: float = ModelEye.n,
        kappa_deg: tuple[float, float] = (0.0, 0.0),
        zone_deg: float | None = None,
    ) -> None:
        self.camera = camera
        self.leds = np.asarray(leds_mm, dtype=float).reshape(-1, 3)
        if not 0 < K < R:
            raise ValueError(f"need 0 < K < R, got K = {K}, R = {R}")
        if zone_deg is not None and not 0 < zone_deg <= 90:
            raise ValueError(f"zone_deg must lie in (0, 90], got {zone_deg}")
        self.R, self.K, self.n = float(R), float(K), float(n)
        self.kappa_deg = (float(kappa_deg[0]), float(kappa_deg[1]))
        self.zone_deg = None if zone_deg is None else float(zone_deg)

    # (i)
    def cornea_centre(self, glints_px: Sequence) -> tuple[np.ndarray | None, str]:
        """Centre of corneal curvature (3,) mm from glints matched to the LEDs (None: missing)."""
        if len(glints_px) != len(self.leds):
            raise ValueError(f"{len(glints_px)} glint entries for {len(self.leds)} LEDs")
        found = [i for i, g in enumerate(glints_px) if g is not None and np.all(np.isfinite(g))]
        if len(found) < 2:
            return None, f"needs >= 2 matched glints, got {len(found)}"
        o = self.camera.node
        u = self.camera.ray(np.array([glints_px[i] for i in found], dtype=float))
        leds = self.leds[found]
        r = self.R

        def residuals(x: np.ndarray) -> np.ndarray:
            c, k = x[:3], x[3:]
            q = o + k[:, None] * u
            d = q - c
            dn = np.linalg.norm(d, axis=1)
            h = _unit(_unit(leds - q) + _unit(o - q))
            return np.concatenate([dn - r, (r * (h - d / dn[:, None])).ravel()])

        k0 = -o[2] / u[:, 2]
        q0 = o + k0[:, None] * u
        h0 = _unit(_unit(leds - q0) + _unit(o - q0))
        c0 = np.mean(q0 - r * h0, axis=0)
        sol = least_squares(
            residuals, np.concatenate([c0, k0]), method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15
        )
        if sol.status <= 0 or not np.all(np.isfinite(sol.x)):
            return None, f"cornea centre fit failed: {sol.message}"
        return sol.x[:3], ""

    # (ii)
    def pupil_centre(self, pupil_px: np.ndarray, c: np.ndarray) -> tuple[np.ndarray | None, str]:
        """Pupil centre (3,) mm: the pupil ray refracted at the sphere, at distance K from c."""
        o = self.camera.node
        u = self.camera.ray(np.asarray(pupil_px, dtype=float))
        s = _sphere_hit(o, u, c, self.R)
        if s is None:
            return None, "the pupil's camera ray misses the corneal sphere"
        hit = o + s * u
        t = _refract(u, (hit - c) / self.R, 1.0 / self.n)
        if t is None:  # cannot happen going into the denser medium
            return None, "total internal reflection of the pupil ray"
        w = hit - c
        b = float(t @ w)
        disc = b * b - (self.R**2 - self.K**2)
        note = ""
        if disc < 0:  # noise: the ray passes outside the K-sphere; take its closest point
            disc, note = 0.0, "the refracted pupil ray misses |p - c| = K; closest point used"
        return hit + (-b - math.sqrt(disc)) * t, note

    def estimate(self, pupil_px: np.ndarray, glints_px: Sequence) -> GazeEstimate:
        """Gaze from one frame: the pupil's image centre (col, row) px and the glints.

        ``glints_px`` lists one entry per LED, in the order of ``leds_mm``: its glint (col, row)
        or None (or NaN) when missing. At least two are needed.
        """
        if len(glints_px) != len(self.leds):
            raise ValueError(f"{len(glints_px)} glint entries for {len(self.leds)} LEDs")
        found = [g is not None and bool(np.all(np.isfinite(g))) for g in glints_px]
        est = self._estimate(pupil_px, glints_px)
        if self.zone_deg is None or not est.ok:
            return est
        kept = found
        for _ in range(5):
            inside = self._inside_zone(glints_px, est.cornea_centre_mm, est.optical_axis)
            if inside == kept:
                break
            kept = inside
            n_in, n_out = sum(kept), sum(found) - sum(kept)
            if n_in < 2:
                return _failed(
                    f"{n_in} of {sum(found)} glints within the spherical cornea's validity "
                    f"zone ({self.zone_deg:g} deg of the optical axis); needs >= 2",
                    n_in,
                    est.cornea_centre_mm,
                    n_out,
                )
            est = self._estimate(
                pupil_px, [g if k else None for g, k in zip(glints_px, kept, strict=True)]
            )
            if not est.ok:
                return _failed(est.reason, n_in, est.cornea_centre_mm, n_out)
        return GazeEstimate(
            est.h_deg,
            est.v_deg,
            est.cornea_centre_mm,
            est.pupil_centre_mm,
            True,
            est.reason,
            est.optical_axis,
            sum(kept),
            sum(found) - sum(kept),
        )

    def _inside_zone(self, glints_px: Sequence, c: np.ndarray, omega: np.ndarray) -> list[bool]:
        """Per LED: its glint is found and its camera ray meets the sphere (c, R) within
        ``zone_deg`` of the optical axis ω (camera frame)."""
        o, cos_zone = self.camera.node, math.cos(math.radians(self.zone_deg))
        out = []
        for g in glints_px:
            if g is None or not np.all(np.isfinite(g)):
                out.append(False)
                continue
            u = self.camera.ray(np.asarray(g, dtype=float))
            s = _sphere_hit(o, u, c, self.R)
            out.append(s is not None and float((o + s * u - c) @ omega) >= self.R * cos_zone)
        return out

    def _estimate(self, pupil_px: np.ndarray, glints_px: Sequence) -> GazeEstimate:
        """Steps (i)–(iv) on the glints given (module :class:`GeometricGaze` notes)."""
        n_found = sum(g is not None and bool(np.all(np.isfinite(g))) for g in glints_px)
        c, why = self.cornea_centre(glints_px)
        if c is None:
            return _failed(why, n_found)
        if pupil_px is None or not np.all(np.isfinite(pupil_px)):
            return _failed("no pupil", n_found, c)
        p, why = self.pupil_centre(pupil_px, c)
        if p is None:
            return _failed(why, n_found, c)
        omega = _unit(p - c)
        h, v = angles_from_axis(self.camera.to_world(omega))
        return GazeEstimate(
            h + self.kappa_deg[0], v + self.kappa_deg[1], c, p, True, why, omega, n_found
        )

    def calibrate_kappa(
        self, pupil_px: np.ndarray, glints_px: Sequence, target_mm: np.ndarray
    ) -> GeometricGaze:
        """A copy with kappa set from one frame of the eye fixating ``target_mm`` (world mm).

        The visual axis runs from **c** to the target (Guestrin & Eizenman: it passes through the
        centre of corneal curvature); kappa = its angles − the optical axis's angles.
        """
        est = self.with_kappa((0.0, 0.0)).estimate(pupil_px, glints_px)
        if not est.ok:
            raise ValueError(f"kappa calibration frame failed: {est.reason}")
        target = self.camera.from_world(np.asarray(target_mm, dtype=float))
        th, tv = angles_from_axis(self.camera.to_world(_unit(target - est.cornea_centre_mm)))
        return self.with_kappa((th - est.h_deg, tv - est.v_deg))

    def with_kappa(self, kappa_deg: tuple[float, float]) -> GeometricGaze:
        """A copy with other kappa offsets (h, v), degrees."""
        return GeometricGaze(
            self.camera, self.leds, self.R, self.K, self.n, kappa_deg, self.zone_deg
        )


# --- forward model ----------------------------------------------------------------------------


@dataclass(frozen=True)
class EyeFeatures:
    """What the camera sees of the model eye: picture positions (col, row) px; world mm.

    ``glints_px[i]`` is LED i's glint, None when its reflection point lies off the corneal cap
    (or outside the picture); ``reflection_points_mm[i]`` is that point (NaN when missing).
    """

    pupil_px: np.ndarray
    glints_px: list[np.ndarray | None]
    cornea_centre_mm: np.ndarray
    pupil_centre_mm: np.ndarray
    optical_axis: np.ndarray
    reflection_points_mm: np.ndarray


def _plane_basis(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, float]:
    """Unit e₂ ⟂ a in the plane of unit vectors a, b (from a toward b) and the angle a→b."""
    cos_t = float(np.clip(a @ b, -1.0, 1.0))
    perp = b - cos_t * a
    norm = float(np.linalg.norm(perp))
    return (perp / norm if norm > 0 else perp), math.acos(cos_t)


def specular_point(c: np.ndarray, R: float, led: np.ndarray, o: np.ndarray) -> np.ndarray:
    """Point of the sphere (c, R) that reflects ``led`` into ``o`` (world mm).

    The normal N at the point lies in the plane of c, the LED and O, between the directions
    â = (L − c)/|L − c| and b̂ = (O − c)/|O − c|; with N = cos t â + sin t ê₂ the equal-angle
    condition N·(L − q)/|L − q| = N·(O − q)/|O − q| is a 1D root in t ∈ [0, ∠(â, b̂)]
    (positive at 0, negative at the far end), found by Brent's method.
    """
    a, b = _unit(led - c), _unit(o - c)
    e2, t_max = _plane_basis(a, b)
    if t_max < 1e-12:
        return c + R * a

    def f(t: float) -> float:
        nrm = math.cos(t) * a + math.sin(t) * e2
        q = c + R * nrm
        return float(nrm @ _unit(led - q) - nrm @ _unit(o - q))

    t = brentq(f, 0.0, t_max, xtol=1e-15, rtol=4 * np.finfo(float).eps)
    return c + R * (math.cos(t) * a + math.sin(t) * e2)


def refraction_point(
    c: np.ndarray,
    R: float,
    p: np.ndarray,
    o: np.ndarray,
    n: float,
) -> np.ndarray:
    """Point of the sphere (c, R) where the ray from ``o`` refracts (air → n) through ``p``.

    Snell's law keeps the ray in the plane of O, c and p; with the normal N = cos t ω̂ + sin t ê₂
    (ω̂ toward p, ê₂ toward O) the signed distance of p from the refracted ray changes sign on
    t ∈ [0, ∠(ω̂, O − c)]: a 1D root by Brent's method.
    """
    w, b = _unit(p - c), _unit(o - c)
    e2, t_max = _plane_basis(w, b)
    if t_max < 1e-12:
        return c + R * b
    plane_normal = np.cross(w, e2)

    def g(t: float) -> float:
        nrm = math.cos(t) * w + math.sin(t) * e2
        hit = c + R * nrm
        u = _unit(hit - o)
        tr = _refract(u, nrm, 1.0 / n)
        return float(np.cross(tr, p - hit) @ plane_normal)

    t = brentq(g, 0.0, t_max, xtol=1e-15, rtol=4 * np.finfo(float).eps)
    return c + R * (math.cos(t) * w + math.sin(t) * e2)


def simulate_eye_features(
    camera: PinholeCamera,
    leds_mm: np.ndarray,
    h_deg: float,
    v_deg: float,
    eye: ModelEye = ModelEye(),
) -> EyeFeatures:
    """Exact pupil and glint picture positions of the spherical-cornea eye at gaze (h, v).

    The eye (:class:`ModelEye`), in primary gaze with its corneal vertex at ``eye.offset_mm``,
    turns about its centre of rotation ``eye.rotation_centre_mm`` behind the vertex until its
    optical axis is ω = :func:`axis_from_angles` (h, v): the centre of corneal curvature is
    then c = C + (d − R) ω and the pupil centre p = c + K ω (C the rotation centre, d its depth).
    Each glint is the image of the specular point (:func:`specular_point`) of its LED toward the
    camera node; it is missing (None) when that point lies off the corneal cap — farther than
    ``eye.cap_radius_mm`` from the optical axis — or outside the picture. The pupil's image is
    that of p seen through the sphere (:func:`refraction_point`).

    >>> f = simulate_eye_features(PinholeCamera(), np.array([[0.0, 30.0, 70.0]]), 0.0, 0.0)
    >>> f.pupil_px.round(6)
    array([43., 32.])
    """
    R, K, n, cap_radius_mm = eye.R, eye.K, eye.n, eye.cap_radius_mm
    leds = np.asarray(leds_mm, dtype=float).reshape(-1, 3)
    omega = axis_from_angles(h_deg, v_deg)
    centre = np.asarray(eye.offset_mm, dtype=float) - np.array([0.0, 0.0, eye.rotation_centre_mm])
    c = centre + (eye.rotation_centre_mm - R) * omega
    p = c + K * omega
    o = camera.node
    glints: list[np.ndarray | None] = []
    points = np.full((len(leds), 3), np.nan)
    for i, led in enumerate(leds):
        q = specular_point(c, R, led, o)
        d = q - c
        along = float(d @ omega)
        off_axis = math.sqrt(max(float(d @ d) - along * along, 0.0))
        px = camera.project(q)
        if along <= 0 or off_axis > cap_radius_mm or not camera.in_picture(px):
            glints.append(None)
            continue
        glints.append(px)
        points[i] = q
    pupil_px = camera.project(refraction_point(c, R, p, o, n))
    return EyeFeatures(pupil_px, glints, c, p, omega, points)
