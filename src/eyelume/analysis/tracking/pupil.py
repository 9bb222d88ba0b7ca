"""The dark pupil: a threshold ladder, the darkest stable compact blob, sub-pixel edge, ellipse.

The paper's Figure 2 — threshold the picture, close the holes, fit an ellipse — without its
assumption that the pupil has a histogram mode of its own (with a dark iris the two make one
mode; a black border or a headset's dark corners make a darker one). Each step is a function
that returns its result or a falsy :class:`Refusal` naming the cause (as scikit-image's
``EllipseModel`` returns a result or a falsy failure):

1. **Working picture** (:func:`work_picture`): 8 bits from the darkest valid pixel to the 99th
   percentile (saturated glints and stuck pixels, a small share of any eye picture, are
   clipped instead of stretching the scale); glint pixels take the darkest value around them,
   each within its own radius (a glint inside the pupil would punch a hole in it); invalid
   pixels (NaN, outside the valid-area mask) are bright, but for enclosed holes no larger
   than a pupil, which take their surround's level (:func:`_fill_holes_dark`: a NaN hole in
   the pupil would make it a ring). The pixel noise σ
   (:func:`noise_sigma`, Immerkær 1996).
2. **Threshold ladder** (:func:`ladder`): the picture reduced to ~80 rows and thresholded at
   levels (P60 − P0.5) / 32 apart from its darkest pixel to its 60th percentile; at each
   level the compact dark blobs off the picture's border and the invalid area are kept (box
   fill ≥ 0.5, aspect ≤ 3, centroid inside), nested blobs of successive levels form a chain
   (a level starts its new chains nearest the glints' middle first, else darkest first:
   where a blob joins several chains, the first started goes on; :func:`_ordered_level`),
   and each blob's stability is MSER's q = (A₊ − A₋) / A over the neighbouring levels (Matas
   et al. 2002). The ladder stops once the darkest chain has settled. When the fits of step
   4–7 give no whole pupil, or a pupil at the black level (stable from the second level) whose
   fit leaves an arc over ¼ of its outline unbacked, the ladder's first three levels are walked
   again four times finer, and a fit there backed by ≥ 75 % (no arc over ¼ unbacked) replaces
   it: a pupil near the black level, with bright skin setting the levels' spacing (an off-axis
   view), is otherwise crossed into the iris in one or two levels; and up a dark iris's ramp
   q keeps falling, so the walk of step 3 can stop with the iris in the blob. Still none: the
   ladder at full resolution for a pupil under 4 f px across, too small for the reduced
   picture (:func:`_small_pupil`).
3. **Choice** (:func:`choose`): chains darkest first; a chain's blob is its first level with
   q ≤ 1 walked on to the local minimum of q — the pupil's area holds while the threshold
   crosses its edge band, then jumps when it merges with the iris. When that blob is not
   compact at full resolution, the chain's blob before its largest jump in area is tried
   (:func:`_before_jump`: the pupil joined to a shadowed iris before it was stable).
   Refusals: "no pupil (merged with the iris?)" (compact dark blobs, none stable), "pupil too
   small: N px", "no dark pupil: bright-pupil image?" (no dark blob but a compact bright one
   of a pupil's size), and "no
   pupil off the picture's border" when a darker pupil-sized region touches the border or the
   missing pixels (a pupil cut by the frame; the blob inside is then not called the pupil;
   when that blob was refused for its own cause, only if darker than it by a pupil's
   contrast, ``pupil_min_contrast_sigma`` σ). A blob whose outline runs over
   ``max_boundary_gap`` along the border or missing pixels, or whose dark side is next to
   them, is "pupil cut or hidden" (a valid-area mask across the pupil). A whole fit holding
   a bright core larger than any glint (:func:`bright_core`) is "no dark pupil: bright-pupil
   image?"; one holding a darker core (:func:`darker_core`) is looked inside
   (:func:`_pupil_inside`: the core averaged out of the noise, fitted and taken when whole and
   ≥ 5 standard errors under its surround: a pupil a few σ under a dark iris), else "pupil
   merged with iris" naming why the core was not taken, or "pupil too small" when that core
   is under ``pupil_min_area_px``. When every candidate is refused, or the fit has none of the
   picture's glints within 6 of its radii (a mole on the skin darker than the pupil), the
   ladder is walked again past their chains (it stops once the darkest chain has settled, and
   a lash over the sclera may be that chain) and a whole fit with glints beside it is taken
   (:func:`_fit_chosen`); a whole fit with none within 3 of its radii (a black spot on the skin
   or in the iris, darker than the pupil, 3.7–6.4 of its radii from the glints) gives way to
   another chosen candidate whose whole fit has the glints about it.
4. **Full-resolution blob** (:func:`full_res_blob`): the picture (σ 1 px Gaussian) thresholded
   at the chosen level around the blob; glints touching it joined; a closing with an
   elliptical element of ≈ 0.15 × its diameter (odd, ≥ 3) fills what is left of a glint's
   notch; refused when not compact (solidity < 0.8) — unless, with the glints' pixels left
   out (:func:`_glint_forgiven`: the core dark without the glints' fill, and under a glint its
   convex hull), it is one piece of solidity ≥ 0.9: a glint just outside a small pupil's edge,
   filled with the pupil's dark, grows a bump on its blob; or, opened by the closing's element
   (:func:`_without_strokes`), the piece under its seed has solidity ≥ 0.9: lashes darker than
   the pupil across its edge.
5. **Contrast and edge** (:func:`blob_contrast`, :func:`edge_points`, :func:`_refine_smoothed`):
   the pupil's median against its own surround (a ring 0.05–0.1 × its diameter outside), at
   least 5 standard errors of that difference of medians, 1.2533 σ √(1/N₁ + 1/N₂), σ the
   pixel noise there (:func:`_local_noise`: shot noise grows with the signal, so the
   picture's own σ, set by bright skin, overstates it between a dark pupil and iris), and 3 %
   of the robust range, else "pupil merged with iris";
   the outline points less those on glints (grown by their own radius: a glint's skirt
   brightens the edge under it), the picture's border and invalid pixels; each point moves
   along the normal of a first ellipse fit to where the profile (the mean of three parallel
   profiles 1 px apart, which averages the noise along the edge without moving it across)
   crosses ``edge_fraction`` (¼) of the way from the pupil's level to the profile's own outer
   level (capped at the median outer level of all profiles: a lid's skin or the sclera beyond
   the iris does not lift it). Under a symmetric blur every such iso-line is an ellipse with
   the pupil's centre, whatever the threshold; a per-profile level keeps an unevenly lit iris
   from shifting it, and a low fraction reads the edge on the quiet dark side, where the
   iris's shading and texture and the glints' skirts weigh least. That iso-line is narrower
   than the sharp pupil by 2 × 0.674 σ for a Gaussian blur of σ (Φ⁻¹(¾) = 0.674): the axes
   answered are grown by twice the edge's offset beyond it (step 8).
   A pupil under 30 px across is refined a second time from the first fit.
6. **Robust fit** (:func:`_robust_fit`): ``cv2.fitEllipse`` on the edge points; when more than
   5 % lie off it, the best of fits to contiguous runs of the outline, so an eyelid's edge or a
   lash drops out. The inlier tolerance scales with the pupil: max(1 px, 3σ_edge, 0.03 ×
   its diameter). A fit smaller than ``pupil_min_area_px`` is refused ("pupil too small"), one
   thinner than ``pupil_min_axis_ratio`` (0.25 = cos 75.5°) as a sliver (a black strip of
   skin beside a lid), and the next candidate is fitted.
7. **Support** (:func:`support_of`): the fraction of the ellipse's outline backed by inlier
   edge points and its longest unbacked arc: a lid or the border hides one long arc, a ragged
   real edge leaves short gaps.
8. **Edge profile** (:func:`find_pupil`, :func:`edge_profile`): the median of the picture's
   profiles along the answered fit's normals. When it shows a dark iris ring inside the fit
   (:func:`_ring_inside`: a shelf between a darker inside and the fitted edge — a dilated
   pupil hugged by a 5–12 px dark iris, which the ladder's reduced picture does not resolve),
   the pupil inside is thresholded halfway between the two levels and fitted
   (:func:`_inside_ring`), else refused as merged with the iris. The fit's edge offset
   (:func:`edge_offset`): how far the step of a blurred step-and-iris model fitted to the
   profile (the pupil's level, a step, and an iris going on with its own slope and curvature,
   under a Gaussian blur) lies beyond the ¼ iso-line; ``detect`` reports the axes grown by
   twice it.

Missing pixels in strips ≤ 2 px thin (a dead row, a scratch) take the mean of the valid pixels
around them in the working picture (:func:`_fill_thin_missing`): they hide no pupil, but left
bright they would cut one in two.

Coordinates: OpenCV's — pixel (column c, row r) has its centre at (x, y) = (c, r); ellipse
angles in degrees from +x toward +y (down the picture, clockwise as displayed).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass
from functools import cached_property

import cv2
import numpy as np
from numba import njit

__all__ = ["Ellipse", "PupilFit", "Refusal", "find_pupil", "noise_sigma", "sampson_distance"]


@dataclass(frozen=True)
class Ellipse:
    """An ellipse: centre (x, y) px, semi-axis ``a`` along (cos θ, sin θ), ``b`` across, θ rad."""

    cx: float
    cy: float
    a: float
    b: float
    theta: float

    @classmethod
    def from_box(cls, box) -> Ellipse:
        """From OpenCV's ``RotatedRect`` ((cx, cy), (width, height), angle°)."""
        (cx, cy), (w, h), ang = box
        return cls(float(cx), float(cy), 0.5 * float(w), 0.5 * float(h), math.radians(ang))

    def local(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Coordinates (s, q) along and across the ``a`` axis, relative to the centre."""
        c, s = math.cos(self.theta), math.sin(self.theta)
        dx, dy = x - self.cx, y - self.cy
        return dx * c + dy * s, -dx * s + dy * c

    def outward_normal(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Unit gradient of s²/a² + q²/b² at (x, y), in picture coordinates."""
        s, q = self.local(x, y)
        gs, gq = s / self.a**2, q / self.b**2
        c, sn = math.cos(self.theta), math.sin(self.theta)
        nx, ny = gs * c - gq * sn, gs * sn + gq * c
        norm = np.hypot(nx, ny)
        norm[norm == 0] = 1.0
        return nx / norm, ny / norm

    @property
    def perimeter(self) -> float:
        """Ramanujan's approximation π[3(a+b) − √((3a+b)(a+3b))], px."""
        a, b = self.a, self.b
        return math.pi * (3 * (a + b) - math.sqrt((3 * a + b) * (a + 3 * b)))

    @property
    def major_minor_angle(self) -> tuple[float, float, float]:
        """(major, minor) full axis lengths px and the major axis' angle, degrees in [0, 180)."""
        if self.a >= self.b:
            return 2 * self.a, 2 * self.b, math.degrees(self.theta) % 180.0
        return 2 * self.b, 2 * self.a, (math.degrees(self.theta) + 90.0) % 180.0


def _grid_local(e: Ellipse, x0: int, x1: int, y0: int, y1: int, step: int = 1):
    """:meth:`Ellipse.local` of every ``step``-th pixel centre of the box [x0, x1) × [y0, y1):
    two (rows, cols) arrays, broadcast from the box's row and column coordinates (the same
    values as on ``np.mgrid``'s full grids, without building them)."""
    c, s = math.cos(e.theta), math.sin(e.theta)
    dx = np.arange(x0, x1, step, dtype=np.float64)[None, :] - e.cx
    dy = np.arange(y0, y1, step, dtype=np.float64)[:, None] - e.cy
    return dx * c + dy * s, -dx * s + dy * c


def _scaled_args(e: Ellipse) -> tuple[float, ...]:
    """(cx, cy, cos θ, sin θ, a, b) of ``e`` as floats, for the compiled grids below."""
    return (float(e.cx), float(e.cy), math.cos(e.theta), math.sin(e.theta), float(e.a), float(e.b))


@njit(cache=True, nogil=True)
def _inside_scaled(box, ell, lim):
    """Which pixel centres of the box (x0, x1, y0, y1) = [x0, x1) × [y0, y1) have (s / a)² +
    (q / b)² < ``lim``, (s, q) their coordinates along and across the ellipse ``ell`` = (cx,
    cy, cos θ, sin θ, a, b) (:meth:`Ellipse.local`): (rows, cols) bool, the same arithmetic as
    on :func:`_grid_local`'s arrays, in one compiled pass."""
    x0, x1, y0, y1 = box
    cx, cy, c, sn, a, b = ell
    out = np.empty((max(0, y1 - y0), max(0, x1 - x0)), np.bool_)
    for r in range(y1 - y0):
        dy = float(y0 + r) - cy
        for k in range(x1 - x0):
            dx = float(x0 + k) - cx
            u = (dx * c + dy * sn) / a
            v = (-dx * sn + dy * c) / b
            out[r, k] = u * u + v * v < lim
    return out


@njit(cache=True, nogil=True)
def _ring_scaled(box, step, ell, radii):
    """(s / a, q / b) of every ``step``-th pixel centre of the box (x0, x1, y0, y1) about the
    ellipse ``ell`` (as :func:`_inside_scaled`; :func:`_grid_local`'s arrays divided by the
    semi-axes) and which lie strictly between the scaled radii ``radii`` = (r0, r1) (hypot),
    in one compiled pass: the same numbers."""
    x0, x1, y0, y1 = box
    cx, cy, c, sn, a, b = ell
    r0, r1 = radii
    lo2, lo2b = r0 * r0 * (1.0 - 1e-9), r0 * r0 * (1.0 + 1e-9)
    hi2, hi2b = r1 * r1 * (1.0 + 1e-9), r1 * r1 * (1.0 - 1e-9)
    ny = max(0, (y1 - y0 + step - 1) // step)
    nx = max(0, (x1 - x0 + step - 1) // step)
    uo = np.empty((ny, nx))
    vo = np.empty((ny, nx))
    ring = np.empty((ny, nx), np.bool_)
    for r in range(ny):
        dy = float(y0 + r * step) - cy
        for k in range(nx):
            dx = float(x0 + k * step) - cx
            u = (dx * c + dy * sn) / a
            v = (-dx * sn + dy * c) / b
            uo[r, k] = u
            vo[r, k] = v
            # hypot (slow) only near the radii: u² + v² decides the rest (its rounding is
            # ~1e-16 relative, far inside the 1e-9 margins), the same answers.
            q = u * u + v * v
            if q < lo2 or q > hi2:
                ring[r, k] = False
            elif q > lo2b and q < hi2b:
                ring[r, k] = True
            else:
                rho = math.hypot(u, v)
                ring[r, k] = rho > r0 and rho < r1
    return uo, vo, ring


def sampson_distance(e: Ellipse, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Signed first-order distance (px) of points to the ellipse, > 0 outside.

    d = F / |∇F| with F = s²/a² + q²/b² − 1: the Sampson approximation of the geometric distance,
    exact to first order near the curve.
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    if x.ndim == 1 and x.shape == y.shape:  # an outline's points: one compiled pass
        c, sn = math.cos(e.theta), math.sin(e.theta)
        return _sampson_1d(x, y, (e.cx, e.cy), c, sn, e.a**2, e.b**2)
    s, q = e.local(x, y)
    f = s * s / e.a**2 + q * q / e.b**2 - 1.0
    g = 2.0 * np.hypot(s / e.a**2, q / e.b**2)
    return f / np.maximum(g, 1e-12)


@njit(cache=True, nogil=True)
def _sampson_1d(x, y, centre, c, sn, a2, b2):
    """:func:`sampson_distance` of the points (x, y) (1-D float64) to the ellipse about
    ``centre`` with cos θ, sin θ and the squared semi-axes: the same arithmetic, in one pass."""
    out = np.empty(x.size)
    for i in range(x.size):
        dx = x[i] - centre[0]
        dy = y[i] - centre[1]
        s = dx * c + dy * sn
        q = -dx * sn + dy * c
        f = s * s / a2 + q * q / b2 - 1.0
        g = 2.0 * math.hypot(s / a2, q / b2)
        out[i] = f / (g if (g >= 1e-12 or g != g) else 1e-12)
    return out


@dataclass
class PupilFit:
    """What :func:`find_pupil` found: the ellipse and the evidence behind it, or why not."""

    ellipse: Ellipse | None
    area_px: float = 0.0
    support: float = 0.0
    gap: float = 1.0
    residual_px: float = math.inf
    edge_noise_px: float = math.inf
    edge_level: float = math.nan
    contrast: float = 0.0
    n_points: int = 0
    dropped: dict | None = None
    reason: str = ""
    threshold: float = math.nan
    #: the edge points (x, y) px the ellipse was fitted to (its inliers), for the checks of
    #: :func:`~.detect._pupil_result`
    inliers: tuple[np.ndarray, np.ndarray] | None = None
    #: the ladder level of the first stable blob of the fitted blob's chain (:func:`choose`;
    #: 1 for a pupil at the black level), −1 when not from a ladder's chain
    stable_from: int = -1
    #: the first seed of that chain (:attr:`Candidate.first`)
    first: tuple[int, int] = (-1, -1)
    #: how far (px, + outward) the pupil's edge lies beyond ``ellipse``, the ¼ iso-line
    #: (:func:`edge_offset`): the pupil's axes are the ellipse's grown by twice it
    edge_offset_px: float = 0.0
    #: the median profile across ``ellipse``'s outline (:func:`edge_profile`) the offset was
    #: read from, or None: ``detect`` takes it as the background under glints on the edge
    edge_profile: EdgeProfile | None = None

    def __bool__(self) -> bool:
        return self.ellipse is not None


def _odd(n: float) -> int:
    k = max(3, int(round(n)))
    return k if k % 2 else k + 1


def _order_stats(a: np.ndarray, ks: tuple[int, ...]) -> list[float]:
    """The ``ks``-th smallest of the values ``a`` (1-D), as floats: for 8- and 16-bit pictures
    (and 32-bit integers) by counting (:func:`_counted_order_stats`: exact, and
    ``np.partition`` is slow on their many equal values), else by ``np.partition``."""
    if a.dtype == np.uint8 or a.dtype == np.uint16 or a.dtype == np.int32:
        return _counted_order_stats(np.ascontiguousarray(a), np.array(ks, np.int64)).tolist()
    p = np.partition(a, sorted(set(ks)))
    return [float(p[k]) for k in ks]


@njit(cache=True, nogil=True)
def _counted_order_stats(a, ks):
    """The ``ks``-th smallest (0-based) of the integer values ``a`` (1-D, not empty), as
    float64: the values counted over their range [min, max] (the first value whose running
    count exceeds k, as ``np.searchsorted(np.cumsum(counts), k, side="right")``), or sorted
    when that range is over 4 × their number. One compiled pass instead of NumPy's bincount
    (which copies the values to intp), cumsum and searchsorted: ~10 × faster on the few
    thousand values of a pupil's or its surround's median."""
    n = a.size
    out = np.empty(ks.size)
    lo = int(a[0])
    hi = lo
    for i in range(n):
        v = int(a[i])
        if v < lo:
            lo = v
        elif v > hi:
            hi = v
    if hi - lo + 1 > 4 * n:
        s = np.sort(a)
        for j in range(ks.size):
            out[j] = float(s[ks[j]])
        return out
    counts = np.zeros(hi - lo + 1, np.int64)
    for i in range(n):
        counts[int(a[i]) - lo] += 1
    order = np.argsort(ks)
    j = 0
    cum = 0
    for b in range(hi - lo + 1):
        cum += counts[b]
        while j < ks.size and ks[order[j]] < cum:
            out[order[j]] = float(lo + b)
            j += 1
        if j == ks.size:
            break
    return out


def median(a: np.ndarray) -> float:
    """The median of ``a``'s values (float), as ``np.median`` gives it, without its overhead
    (~0.1 ms a call; the detector takes a dozen medians a frame): :func:`_order_stats`."""
    a = np.asarray(a).ravel()
    n = a.size
    if n == 0:
        return math.nan
    k = n // 2
    if n % 2:
        return _order_stats(a, (k,))[0]
    lo, hi = _order_stats(a, (k - 1, k))
    return 0.5 * (lo + hi)


def percentile(a: np.ndarray, q: float) -> float:
    """The ``q``-th percentile of ``a``'s values (float), NumPy's default (linear) rule, without
    ``np.percentile``'s overhead (~0.25 ms a call): :func:`_order_stats`."""
    return percentiles(a, (q,))[0]


def percentiles(a: np.ndarray, qs: tuple[float, ...]) -> list[float]:
    """:func:`percentile` for each of ``qs``, from one :func:`_order_stats` (one count)."""
    a = np.asarray(a).ravel()
    n = a.size
    if n == 0:
        return [math.nan] * len(qs)
    ranks = []
    for q in qs:
        vi = q / 100.0 * (n - 1)
        lo = int(math.floor(vi))
        ranks += [lo, min(lo + 1, n - 1)]
    v = _order_stats(a, tuple(ranks))
    out = []
    for i, q in enumerate(qs):
        vi = q / 100.0 * (n - 1)
        g = vi - math.floor(vi)
        a_lo, a_hi = v[2 * i], v[2 * i + 1]
        out.append(a_lo + (a_hi - a_lo) * g if g < 0.5 else a_hi - (a_hi - a_lo) * (1.0 - g))
    return out


def float_percentiles(vals: np.ndarray, qs) -> float | list[float]:
    """``np.percentile(vals, qs)`` of a 1-D float array, NumPy's (linear) rule and arithmetic
    to the bit, without its ~30 µs of overhead a call: the order statistics by
    :func:`_order_stats`, then NumPy's interpolation — for a float ``qs`` in ``vals``' own
    precision (NumPy 2 takes a Python float q as weak: a float32 array's percentile is a
    float32), for a list or tuple in float64 from the float32 difference of the two values.
    Returns a float, or a list of floats. ValueError for an empty or non-float array."""
    if vals.dtype.kind != "f" or vals.ndim != 1 or vals.size == 0:
        raise ValueError(f"float_percentiles takes a non-empty 1-D float array, got {vals.dtype}")
    weak = isinstance(qs, int | float)
    n = vals.size
    idx = []
    for q in [qs] if weak else qs:
        vi = (n - 1) * np.true_divide(q, 100)
        lo = int(math.floor(vi))
        idx.append((vi, lo, lo + 1) if vi < n - 1 else (vi, -1, -1))
    ranks = sorted({n - 1 if k < 0 else k for _, lo, hi in idx for k in (lo, hi)})
    order = dict(zip(ranks, _order_stats(vals, tuple(ranks)), strict=True))
    kind = vals.dtype.type
    out = []
    for vi, lo, hi in idx:
        a, b = kind(order[n - 1 if lo < 0 else lo]), kind(order[n - 1 if hi < 0 else hi])
        g = float(vi - lo)  # (≥ 1 past the last value: b, as NumPy's index −1 gives it)
        diff = b - a  # (in the array's precision)
        if weak:
            out.append(float(a + diff * g if g < 0.5 else b - diff * (1.0 - g)))
        else:
            d = float(diff)
            out.append(float(a) + d * g if g < 0.5 else float(b) - d * (1.0 - g))
    return out[0] if weak else out


def median_and_percentile(a: np.ndarray, q: float) -> tuple[float, float]:
    """(:func:`median`, :func:`percentile` ``q``) of ``a``'s values, the same numbers from one
    :func:`_order_stats` (one count or partition)."""
    a = np.asarray(a).ravel()
    n = a.size
    if n == 0:
        return math.nan, math.nan
    k = n // 2
    vi = q / 100.0 * (n - 1)
    lo = int(math.floor(vi))
    ks = (k, lo, min(lo + 1, n - 1)) if n % 2 else (k - 1, k, lo, min(lo + 1, n - 1))
    v = _order_stats(a, ks)
    m = v[0] if n % 2 else 0.5 * (v[0] + v[1])
    a_lo, a_hi = v[-2:]
    g = vi - lo
    return m, a_lo + (a_hi - a_lo) * g if g < 0.5 else a_hi - (a_hi - a_lo) * (1.0 - g)


def _refine_edge(
    img: np.ndarray,
    e: Ellipse,
    x: np.ndarray,
    y: np.ndarray,
    pupil_level: float,
    reach: float,
    fraction: float,
    tangential: int = 0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Move each point along the ellipse's outward normal to the nearest rising crossing of its
    edge level within ± ``reach`` px (bilinear samples every 0.5 px, linear interpolation); the
    edge level is ``fraction`` of the way from ``pupil_level`` to the median of the profile's
    outer half, or to the median of those over all profiles when that is lower. Returns the new
    x, y and which points found a crossing. (``cv2.remap``'s bilinear weights are quantised to
    1/32 px, ≤ 0.016 px of position — far below the detector's precision; the border is
    replicated.)"""
    nx, ny = e.outward_normal(x, y)
    t = np.arange(-reach, reach + 1e-9, 0.5)
    n = len(x)
    if n == 0:
        return x.copy(), y.copy(), np.zeros(0, bool)
    # The profile and its parallels ± off px along the tangent, sampled in one remap; the
    # sample positions x + nx t − off ny (and y + ny t + off nx) taken in float64 and written
    # straight into the float32 maps remap reads (:func:`_profile_maps`).
    offs = np.array([0.0] + [float(s) for off in range(1, tangential + 1) for s in (-off, off)])
    mx, my = _profile_maps(x, y, nx, ny, t, offs)
    s32 = cv2.remap(img, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    # Each profile's own edge level, from the pupil's level toward its outer half (the iris
    # there), but never above the iris's typical level (the median over the profiles): an
    # iris shaded by a lid lowers the level where it is darker, while a profile whose outer
    # half reaches a brighter neighbour (a lid's skin, the sclera, a glint's skirt) does not
    # lift its level up the edge — that pushed the top of eyelume's renders' pupils outward,
    # 0.15 px on average (the former cap, median + 3 σ of the MAD, let it through). Then the
    # rising crossings of that level, interpolated, and each profile's nearest to 0
    # (:func:`_nearest_crossings`).
    outer_from = int(np.searchsorted(t, 0.5 * reach, side="left"))  # t ≥ reach / 2
    ok, tj = _nearest_crossings(s32, n, t, outer_from, float(pupil_level), float(fraction))
    return x + nx * tj, y + ny * tj, ok


@njit(cache=True, nogil=True)
def _profile_maps(x, y, nx, ny, t, offs):
    """remap's float32 maps (len(offs) · n, len(t)) of :func:`_refine_edge`'s samples: row
    o · n + i holds x_i + nx_i t − offs_o ny_i (and y_i + ny_i t + offs_o nx_i), taken in
    float64 as NumPy takes them on broadcast arrays, then rounded to float32."""
    n, m, k = x.size, t.size, offs.size
    mx = np.empty((k * n, m), np.float32)
    my = np.empty((k * n, m), np.float32)
    # Row by row (contiguous writes): the same float64 sums, each rounded once to float32.
    for o in range(k):
        off = offs[o]
        for i in range(n):
            r = o * n + i
            xi, yi, nxi, nyi = x[i], y[i], nx[i], ny[i]
            ox, oy = off * nyi, off * nxi
            for j in range(m):
                mx[r, j] = (xi + nxi * t[j]) - ox
                my[r, j] = (yi + nyi * t[j]) + oy
    return mx, my


@njit(cache=True, nogil=True)
def _nearest_crossings(s32, n, t, outer_from, pupil_level, fraction):
    """:func:`_refine_edge`'s crossings from remap's samples ``s32`` (k · n, len(t)) float32,
    k parallel profiles per point: the profile v = their mean (float64, summed in order); its
    edge level pupil_level + fraction (o − pupil_level), o the median of v over t[outer_from:]
    capped at the median of those over all profiles; the rising crossings of that level
    (v_j < level ≤ v_j+1) interpolated, t_j + 0.5 (v_j / (v_j − v_j+1)) after subtracting it,
    and per profile the one nearest to 0 (the first of equals). Returns (found, t of it or 0)
    — the same numbers as the array operations they replace."""
    m = t.size
    k = s32.shape[0] // n
    v = np.empty((n, m))
    for i in range(n):  # row by row: the same sums, in the same order (o = 0, 1, …)
        for j in range(m):
            v[i, j] = np.float64(s32[i, j])
        for o in range(1, k):
            for j in range(m):
                v[i, j] += np.float64(s32[o * n + i, j])
        for j in range(m):
            v[i, j] /= k
    outer = _row_medians_from(v, outer_from)
    p = np.sort(outer)
    hn = n // 2
    cap = p[hn] if n % 2 else 0.5 * (p[hn - 1] + p[hn])
    ok = np.zeros(n, np.bool_)
    tj = np.zeros(n)
    for i in range(n):
        o = min(outer[i], cap)
        level = pupil_level + fraction * (o - pupil_level)
        best = np.inf
        for j in range(m - 1):
            v0 = v[i, j] - level
            v1 = v[i, j + 1] - level
            if v0 < 0 and v1 >= 0:
                tc = t[j] + 0.5 * (v0 / (v0 - v1))
                if abs(tc) < best:
                    best = abs(tc)
                    tj[i] = tc
                    ok[i] = True
    return ok, tj


@njit(cache=True, nogil=True)
def _row_medians_from(v, start):
    """The median of each row of ``v`` (2-D float64, finite) over its columns ``start`` on:
    each row's values insertion-sorted in one buffer (a dozen or two), the same values as
    ``np.sort`` gives, without an array a row."""
    n, m = v.shape
    cnt = m - start
    h = cnt // 2
    out = np.empty(n)
    buf = np.empty(max(cnt, 1))
    for i in range(n):
        for j in range(cnt):
            x = v[i, start + j]
            q = j
            while q > 0 and buf[q - 1] > x:
                buf[q] = buf[q - 1]
                q -= 1
            buf[q] = x
        out[i] = buf[h] if cnt % 2 else 0.5 * (buf[h - 1] + buf[h])
    return out


def _fit(x: np.ndarray, y: np.ndarray, diam: float) -> Ellipse | None:
    """:func:`_fit_points` of the points (x, y)."""
    if len(x) < 5:
        return None
    return _fit_points(np.column_stack([x, y]).astype(np.float32), diam)


def _fit_points(pts: np.ndarray, diam: float) -> Ellipse | None:
    """``cv2.fitEllipse`` of ``pts`` ((n, 2) float32) as an :class:`Ellipse`, or None when there
    are fewer than 5, it is degenerate, or it is larger than 5 × ``diam``."""
    if len(pts) < 5:
        return None
    # Ellipse.from_box's numbers, checked before the Ellipse is built.
    (cx, cy), (w, h), ang = cv2.fitEllipse(pts)
    cx, cy, a, b = float(cx), float(cy), 0.5 * float(w), 0.5 * float(h)
    isfinite = math.isfinite
    if not (isfinite(cx) and isfinite(cy) and isfinite(a) and isfinite(b)) or not 0 < min(a, b):
        return None
    return Ellipse(cx, cy, a, b, math.radians(ang)) if max(a, b) < 5.0 * diam else None


def _sampson_many(fits: list[Ellipse], x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """:func:`sampson_distance` of the points to each ellipse of ``fits``: (len(fits), n), the
    same numbers, in one compiled pass (:func:`_sampson_rows`)."""
    par = np.array(
        [(h.cx, h.cy, math.cos(h.theta), math.sin(h.theta), h.a**2, h.b**2) for h in fits],
        np.float64,
    ).reshape(-1, 6)
    return _sampson_rows(par, np.asarray(x, np.float64), np.asarray(y, np.float64))


@njit(cache=True, nogil=True)
def _sampson_rows(par, x, y):
    """:func:`_sampson_1d` of the points (x, y) for each row (cx, cy, cos θ, sin θ, a², b²) of
    ``par``: (rows, n) float64, the same arithmetic as the array operations it replaces."""
    out = np.empty((par.shape[0], x.size))
    for r in range(par.shape[0]):
        cx, cy, c, sn, a2, b2 = par[r, 0], par[r, 1], par[r, 2], par[r, 3], par[r, 4], par[r, 5]
        for i in range(x.size):
            dx = x[i] - cx
            dy = y[i] - cy
            s = dx * c + dy * sn
            q = -dx * sn + dy * c
            f = s * s / a2 + q * q / b2 - 1.0
            g = 2.0 * math.hypot(s / a2, q / b2)
            out[r, i] = f / (g if (g >= 1e-12 or g != g) else 1e-12)
    return out


def _best_run(x, y, e: Ellipse, d: np.ndarray, diam: float, params):
    """The hypothesis with the most inliers among the fit to all points and fits to contiguous
    runs of 50 % and 30 % of the outline from 12 starts each (:func:`_robust_fit`); returns it,
    its distances and σ, the smallest spread of a run about its own fit.

    Runs are fitted only while they can still matter. The tolerance is max(``floor``, 3σ),
    ``floor`` = max(``inlier_tol_px``, ``inlier_tol_frac`` × the diameter); once 3σ is under
    the floor no later run can move it (σ only falls). Then:

    - a 50 % run whose fit holds ≥ ``_RUN_STOP_SHARE`` (85 %) of all the outline's points
      within the floor ends the search: an ellipse through that much of the outline is the
      pupil's, and the winner's refit on its inliers (:func:`_robust_fit`) decides;
    - after the 50 % runs, the 30 % runs (a smaller σ, and a hypothesis for a pupil whose
      visible edge is under half its outline) are left out when the best hypothesis so far
      holds ≥ ``_RUN_SKIP_SHARE`` (60 %) of the points: more than half the outline is on one
      ellipse, so some 50 % run lies on the pupil alone.

    A quality rule, not an identity: checked on the 613 (picture, LEDs) pairs of session 18
    (the 255 realdata pictures, 144 renders, 24 synthetic frames, 24 close-ups), whose 144
    robust fits ran 26 runs each before; no answer changed (in the 3 where a 30 % run had the
    most inliers the refits from the best 50 % run end on the same ellipse). A stop at 80 %
    changed one (an itmo close-up, 0.17 px farther from its annotation). On the slowest
    headset frame (openeds 000160, a lid-cut pupil) 4 runs are fitted instead of 26."""
    n = len(x)
    pts = np.column_stack([x, y]).astype(np.float32)
    # The outline twice over: a run of m ≤ n points from any start is one slice of it (the
    # same points, in the same order, as indexing the outline by (start + arange(m)) % n).
    pts2 = np.concatenate((pts, pts))
    floor = max(params.inlier_tol_px, params.inlier_tol_frac * diam)
    fits: list[Ellipse] = []
    dists: list[np.ndarray] = []
    sigma = 1.4826 * median(d)
    for frac in (0.5, 0.3):
        m = max(params.min_edge_points, int(frac * n))
        if frac == 0.3 and 3.0 * sigma <= floor:
            if max(_inlier_counts(d, dists, floor)) >= _RUN_SKIP_SHARE * n:
                break
        ar = np.arange(m)
        stop = False
        for s0 in range(0, n, max(1, n // 12)):
            run = (s0 + ar) % n
            h = _fit_points(pts2[s0 : s0 + m] if m <= n else pts[run], diam)
            if h is None:
                continue
            dist = np.abs(_sampson_many([h], x, y)[0])
            sigma = min(sigma, 1.4826 * median(dist[run]))  # the run's spread about its own fit
            fits.append(h)
            dists.append(dist)
            if frac == 0.5 and 3.0 * sigma <= floor:
                stop = int((dist <= floor).sum()) >= _RUN_STOP_SHARE * n
                if stop:
                    break
        if stop:
            break
    counts = _inlier_counts(d, dists, max(floor, 3.0 * sigma))
    best = int(np.argmax(counts))
    if best == 0:
        return e, d, sigma
    return fits[best - 1], dists[best - 1], sigma


def _inlier_counts(d: np.ndarray, dists: list[np.ndarray], tol: float) -> list[int]:
    """The points within ``tol`` of the whole outline's fit (distances ``d``) and of each run's
    fit (``dists``), in that order (:func:`_best_run`)."""
    return [int((d <= tol).sum())] + [int((r <= tol).sum()) for r in dists]


_RUN_STOP_SHARE = 0.85  # :func:`_best_run`: a 50 % run's inlier share that ends the search
_RUN_SKIP_SHARE = 0.6  # :func:`_best_run`: the best share of inliers that spares the 30 % runs


def _trim_near_outliers(x, y, e: Ellipse, inl: np.ndarray, diam: float, params):
    """Leave out inliers within ``outlier_trim_points`` (along the outline) of an outlier — the
    occluder's blur bends the edge next to it — and refit; unchanged if too few remain."""
    n = len(x)
    trim = params.outlier_trim_points
    if trim > 0 and 0 < (~inl).sum() < n:
        out = ~inl
        near = np.convolve(
            np.concatenate((out[-trim:], out, out[:trim])), np.ones(2 * trim + 1), "valid"
        )
        trimmed = inl & (near == 0)
        if trimmed.sum() >= params.min_edge_points:
            e_new = _fit(x[trimmed], y[trimmed], diam)
            if e_new is not None:
                return e_new, trimmed
    return e, inl


def _robust_fit(x: np.ndarray, y: np.ndarray, diam: float, params):
    """Ellipse fit that ignores a contiguous stretch of non-pupil outline (an eyelid's edge).

    The inlier tolerance is max(``inlier_tol_px``, 3σ), σ the edge noise. The fit to all points
    is kept when ≥ 95 % of them are inliers with σ from the second differences of their
    distances along the outline (blind to a smooth misfit): a whole pupil. Otherwise the
    hypotheses are the fits to contiguous runs of 50 % and 30 % of the outline from 12 starts
    each; σ is the smallest spread of a run about its own fit (a run on the pupil alone sees
    only noise) and the hypothesis with the most inliers over the whole outline wins. The
    winner is refitted on its inliers until they no longer change; inliers within
    ``outlier_trim_points`` (along the outline) of an outlier are then left out, as the
    occluder's blur bends the edge next to it.
    Returns (ellipse | None, inlier mask, σ).
    """
    n = len(x)
    e = _fit(x, y, diam)
    if e is None:
        return None, np.zeros(n, bool), math.inf
    ds = sampson_distance(e, x, y)
    d = np.abs(ds)
    # Point-to-point edge noise, blind to any smooth misfit: the second difference along the
    # outline (var = 1.5 σ² for independent points).
    hf = ds - 0.5 * (np.concatenate((ds[-1:], ds[:-1])) + np.concatenate((ds[1:], ds[:1])))
    sigma = 1.4826 * median(np.abs(hf)) / math.sqrt(1.5)
    tol = max(params.inlier_tol_px, 3.0 * sigma, params.inlier_tol_frac * diam)
    every = (d <= tol).mean() >= 0.95
    if every:
        sigma = max(sigma, 1.4826 * median(d))
    else:
        e, d, sigma = _best_run(x, y, e, d, diam, params)
        tol = max(params.inlier_tol_px, 3.0 * sigma, params.inlier_tol_frac * diam)
    inl = d <= tol
    # All points inliers of the fit to all of them: its refit on them would be the same fit
    # (cv2.fitEllipse is deterministic) with the same inliers — the loop's first pass would
    # stop there; skipped (most whole pupils).
    loops = 0 if every and inl.all() else params.fit_iterations
    for _ in range(loops):
        e_new = _fit(x[inl], y[inl], diam)
        if e_new is None:
            break
        e = e_new
        new = np.abs(sampson_distance(e, x, y)) <= tol
        if np.array_equal(new, inl) or new.sum() < params.min_edge_points:
            break
        inl = new
    e, inl = _trim_near_outliers(x, y, e, inl, diam, params)
    if inl.sum() >= params.min_edge_points:
        ext = _dark_extension(x[inl], y[inl], e, sigma, diam, params)
        if ext is not None:
            e, beyond = ext
            inl = inl.copy()
            inl[np.flatnonzero(inl)[beyond]] = False
    return e, inl, sigma


#: :func:`_dark_extension`'s windows: the spans of eccentric anomaly (degrees) left out in
#: turn, from a start every 30°
_EXTENSION_SPANS = (60.0, 90.0, 120.0)


def _dark_extension(x, y, e: Ellipse, sigma: float, diam: float, params):
    """A stretch of the outline that a dark region beside the pupil pushed outward (a lash's
    or the lid's shadow across its edge at the pupil's level, joined to its blob), or None:
    (the fit to the rest of the points, the points of the stretch as a bool mask of x).

    The fit to all the points ``e`` has an RMS residual ≥ 2 × the edge noise ``sigma`` (px;
    ≥ 0.25). Each span of :data:`_EXTENSION_SPANS` degrees of the fit's eccentric anomaly, from
    every 30°, is left out in turn (≥ 60 % of the points, ≥ ``min_edge_points``, left); the
    stretch is the span whose leaving-out gives the least RMS residual of the rest, where that
    residual is at most half the whole fit's and the span's points lie outside the rest's
    ellipse (≥ 80 % of them, their median distance > max(2 px, 3 × that residual)). The pupil's
    own edge is one ellipse to within its noise; a dark band at its level across its top
    edge (10–14 px tall) moved the whole fit 2–4.4 px, its outline a smooth curve the robust
    fit's inlier tolerance (3.4 px on a 112 px pupil) took whole. None on the 316 + 120
    pictures of session 29's fingerprints (the 255 real ones among them): the threshold
    values are guesses between them and the band's pictures
    (tests/analysis/test_detect_pupil_band.py)."""
    n = len(x)
    d = sampson_distance(e, x, y)
    rms = math.sqrt(float(np.mean(d * d)))
    if rms < 2.0 * max(sigma, 0.25):
        return None
    s_, q_ = e.local(x, y)
    anom = np.degrees(np.arctan2(q_ / e.b, s_ / e.a)) % 360.0
    best = None
    for span in _EXTENSION_SPANS:
        for start in range(0, 360, 30):
            win = ((anom - start) % 360.0) < span
            rest = ~win
            if win.sum() < 5 or rest.sum() < max(params.min_edge_points, 0.6 * n):
                continue
            h = _fit(x[rest], y[rest], diam)
            if h is None:
                continue
            dh = sampson_distance(h, x, y)
            rr = math.sqrt(float(np.mean(dh[rest] ** 2)))
            out = dh[win]
            if (
                rr <= 0.5 * rms
                and median(out) > max(3.0 * rr, 2.0)
                and (out > 0).mean() >= 0.8
                and (best is None or rr < best[0])
            ):
                best = (rr, h, win)
    return None if best is None else (best[1], best[2])


# --- Step 1: the pupil's working picture and the pixel noise --------------------------------


@dataclass(frozen=True)
class Refusal:
    """A step's falsy failure (as scikit-image's ``EllipseModel`` returns one): ``reason`` names
    the cause in words a user can act on."""

    reason: str

    def __bool__(self) -> bool:
        return False


#: :attr:`WorkPicture.glints_middle`'s least number of glint blobs
_RING_GLINTS = 3


@dataclass(frozen=True)
class WorkPicture:
    """The 8-bit picture the ladder runs on and what maps it back to the input's units.

    ``u8`` (rows, cols) = clip(255 (I − lo) / (hi − lo)), lo the darkest valid pixel and hi the
    ``scale_percentile`` (99th) of the valid pixels: saturated glints and stuck pixels, a small
    share of any eye picture, are clipped instead of stretching the scale. Invalid pixels (NaN,
    outside the valid-area mask) are set to 255 and listed in ``invalid`` (bool), except enclosed
    holes no larger than a pupil (``holes``, bool or None: :func:`_fill_holes_dark`), which
    take their surround's median level. ``noise`` is
    the pixel noise σ in ``u8`` units (:func:`noise_sigma`), ≥ 0.5 (8-bit quantisation, 1/√12 ≈
    0.29, with margin), computed on first use."""

    u8: np.ndarray
    invalid: np.ndarray | None
    lo: float
    hi: float
    glint_radius: float = 0.0
    holes: np.ndarray | None = None
    #: the glint mask (uint8 0/255, the picture's shape) or None, and its set pixels' bounding
    #: box (x, y, w, h; w 0 when none): for :attr:`glints_middle`
    bright: np.ndarray | None = None
    bright_box: tuple[int, int, int, int] = (0, 0, 0, 0)

    @cached_property
    def glints_middle(self) -> tuple[float, float] | None:
        """The glints' middle over the whole picture: the per-axis median (px, x right, y down)
        of the centroids of ``bright``'s blobs (8-connected), or None with fewer than
        :data:`_RING_GLINTS` (one or two glints lie on the cornea's edge, not about its
        centre). The LEDs' reflections ring the cornea, whose centre the pupil lies near
        (:func:`_ordered_level`)."""
        bx, by, bw, bh = self.bright_box
        if self.bright is None or bw == 0:
            return None
        n, _, _, cents = cv2.connectedComponentsWithStats(
            np.ascontiguousarray(self.bright[by : by + bh, bx : bx + bw]), connectivity=8
        )
        if n - 1 < _RING_GLINTS:
            return None
        return median(cents[1:, 0]) + bx, median(cents[1:, 1]) + by

    @cached_property
    def noise(self) -> float:
        """The pixel noise σ of ``u8`` (:func:`noise_sigma`, ≥ 0.5), computed when first asked
        (only a refusal's wording needs it)."""
        return max(0.5, noise_sigma(self.u8))

    def to_input(self, v8: float) -> float:
        """An 8-bit level in the input's units."""
        return self.lo + v8 / 255.0 * (self.hi - self.lo)


def noise_sigma(u8: np.ndarray) -> float:
    """Pixel noise σ (same units) from the Laplacian-like mask of Immerkær (1996,
    "Fast noise variance estimation", CVIU 64, 300–302), M = [[1, −2, 1], [−2, 4, −2], [1, −2,
    1]]: M * I is blind to planes and its coefficients' norm is 6, so σ = 1.4826 median|M * I| /
    6 (the median instead of Immerkær's mean: edges and glints, a small share of the pixels,
    do not count). Over every k-th pixel each way, ~5 × 10³ of them (:func:`_stride`): the
    median's standard error is then ~2 %, and σ only sets gates (a glint's and a hot pixel's
    8 σ, which unstable dark blobs :func:`choose` counts); with ~2 × 10⁴ the 255 real pictures
    of ``benchmarks/detect_real.py`` gave the same σ, renders and synthetic pictures within
    4 %."""
    rows, cols = u8.shape
    if rows < 3 or cols < 3:
        return 0.0
    k = _stride((rows - 2) * (cols - 2), 5e3)
    if u8.dtype.kind in "iu" and u8.itemsize <= 2:
        # Integer pictures: |M * I| in integers (exact) by one compiled pass, its median counted.
        return 1.4826 * median(_immerkaer_abs(u8, k)) / 6.0
    return 1.4826 * median(immerkaer_abs(u8, 1, k)) / 6.0  # others in float32


def immerkaer_abs(img: np.ndarray, lag: int = 1, step: int = 1) -> np.ndarray:
    """|M * I| of Immerkær's mask (:func:`noise_sigma`) with its taps ``lag`` px apart, at every
    ``step``-th pixel each way at least ``lag`` px inside ``img`` (rows, cols; any real dtype),
    in float32: a 2-D array ((rows − 2 lag) / step, (cols − 2 lag) / step), rounded up. Lag 1
    is :func:`noise_sigma`'s; wider lags see the low-frequency noise a JPEG keeps
    (:func:`~.glints._coarse_noise`). The caller checks ``img`` is over 2 lag px each way."""
    rows, cols = img.shape

    def at(dr: int, dc: int) -> np.ndarray:  # every step-th pixel's neighbour (dr, dc) lags off
        return img[
            lag + dr * lag : rows - lag + dr * lag : step,
            lag + dc * lag : cols - lag + dc * lag : step,
        ].astype(np.float32, copy=False)

    r = (
        4 * at(0, 0)
        - 2 * (at(-1, 0) + at(1, 0) + at(0, -1) + at(0, 1))
        + (at(-1, -1) + at(-1, 1) + at(1, -1) + at(1, 1))
    )
    return np.abs(r)


@njit(cache=True, nogil=True)
def _immerkaer_abs(img, k):
    """|M * I| (:func:`noise_sigma`) at every k-th inner pixel of the integer picture ``img``
    each way, in row order (int32 1-D; exact: ≤ 16 × 65535)."""
    rows, cols = img.shape
    ny = (rows - 3) // k + 1
    nx = (cols - 3) // k + 1
    out = np.empty(ny * nx, np.int32)
    n = 0
    for r in range(1, rows - 1, k):
        for c in range(1, cols - 1, k):
            v = 4 * np.int32(img[r, c]) - 2 * (
                np.int32(img[r - 1, c])
                + np.int32(img[r + 1, c])
                + np.int32(img[r, c - 1])
                + np.int32(img[r, c + 1])
            )
            v += (
                np.int32(img[r - 1, c - 1])
                + np.int32(img[r - 1, c + 1])
                + np.int32(img[r + 1, c - 1])
                + np.int32(img[r + 1, c + 1])
            )
            out[n] = abs(v)
            n += 1
    return out


def _stride(n: int, keep: float = 2e4) -> int:
    """Every k-th pixel in each direction keeps ~``keep`` (2 × 10⁴) of n: enough for a
    percentile or a median to ~1 % (their standard error ∝ 1/√n), and the same pixels every
    time."""
    return max(1, int(math.sqrt(n / keep)))


_DISCS: dict[int, np.ndarray] = {}


def _disc(k: int) -> np.ndarray:
    """OpenCV's k × k elliptical structuring element (``cv2.getStructuringElement(
    cv2.MORPH_ELLIPSE, (k, k))``, uint8), made once per size and kept read-only: a frame asks
    for the same few sizes a dozen times."""
    el = _DISCS.get(k)
    if el is None:
        el = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))
        el.flags.writeable = False
        _DISCS[k] = el
    return el


def _label_type(n_pixels: int) -> int:
    """OpenCV's label type for a picture of ``n_pixels``: 16-bit when every label fits (an
    8-connected picture has ≤ ¼ of its pixels + 1 components), else 32-bit. The same labels
    either way (as :func:`ladder` uses them), labelled ~2× faster in 16 bits (a 45 × 164 glint
    box: 24 against 58 µs)."""
    return cv2.CV_16U if n_pixels < 4 * 65535 else cv2.CV_32S


def _fill_glints(roi: np.ndarray, bright: np.ndarray, params) -> None:
    """Each glint of ``bright`` (grown by its own radius r, ≥ ``glint_margin_px``, + 2 px) takes
    the darkest value of ``roi`` within r + 2 px, in place: each glint with its own reach, so a
    large bright blob (a saturated patch of skin taken for a glint) does not make every small
    glint reach as far.

    Worked glint by glint in its own window — the glint's box grown by its reach g, and for the
    erosion that box padded by the element's half-width (outside the roi nothing counts, as for
    the whole roi) — which gives the same pixels as a dilation and an erosion of the whole roi
    per size class, at a fraction of the cost when the glints are spread over the picture."""
    # Labelled on the glints' bounding box only (the roi pads it by their reach: a third of
    # its pixels on a headset frame), the boxes put back in the roi's frame; 16-bit labels when
    # they fit (:func:`_label_type`). (The glints' order does not matter: each lowers the
    # picture to its own erosion's minimum, of the unchanged copy ``src``.)
    bx, by, bw, bh = cv2.boundingRect(bright)
    if not bw:
        return
    box = bright[by : by + bh, bx : bx + bw]
    n, lab_box, stats, _ = cv2.connectedComponentsWithStats(
        box, connectivity=8, ltype=_label_type(box.size)
    )
    if n < 2:
        return
    rows, cols = roi.shape
    lab = np.zeros(roi.shape, lab_box.dtype)
    lab[by : by + bh, bx : bx + bw] = lab_box
    stats[:, cv2.CC_STAT_LEFT] += bx
    stats[:, cv2.CC_STAT_TOP] += by
    radius = np.ceil(np.sqrt(stats[:, cv2.CC_STAT_AREA] / math.pi)).astype(int)
    src = roi.copy()
    for i in range(1, n):
        rc = int(radius[i])
        x, y, w, h = (int(v) for v in stats[i, :4])
        g = int(math.ceil(max(params.glint_margin_px, rc))) + 2
        gx0, gy0 = max(0, x - g), max(0, y - g)
        gx1, gy1 = min(cols, x + w + g), min(rows, y + h + g)
        own = cv2.compare(lab[gy0:gy1, gx0:gx1], i, cv2.CMP_EQ)
        grown = cv2.dilate(own, _disc(2 * g + 1))
        k = 2 * (rc + 2) + 1
        r = k // 2
        ex0, ey0 = max(0, gx0 - r), max(0, gy0 - r)
        ex1, ey1 = min(cols, gx1 + r), min(rows, gy1 + r)
        eroded = cv2.erode(src[ey0:ey1, ex0:ex1], _disc(k))
        eroded = eroded[gy0 - ey0 : gy1 - ey0, gx0 - ex0 : gx1 - ex0]
        sub = roi[gy0:gy1, gx0:gx1]
        np.copyto(sub, np.minimum(sub, eroded), where=grown > 0)


def work_picture(
    img: np.ndarray,
    invalid: np.ndarray | None,
    bright: np.ndarray | None,
    params,
    scale: tuple[float, float, float] | None = None,
) -> WorkPicture | Refusal:
    """Step 1 (module doc): the 8-bit working picture, or a refusal for a featureless one.

    Glint pixels (``bright``, uint8 0/255) take the darkest value around them
    (:func:`_fill_glints`): a glint inside the pupil would otherwise punch a hole in the dark
    blob and move its centroid off it. ``scale``: (min, max, ``scale_percentile``) of the valid
    pixels as worked out here — min and max of all, the percentile of every k-th each way
    (:func:`_stride`) — when the caller has them (``detect`` counts that percentile with the
    hot pixels' 99.9th, over the same pixels)."""
    if scale is not None:
        lo, top, hi = scale
    else:
        step = _stride(img.size)
        sub = img[::step, ::step]
        vals = sub[~invalid[::step, ::step]] if invalid is not None else sub.ravel()
        mask = None if invalid is None else (~invalid).astype(np.uint8)
        lo, top, _, _ = cv2.minMaxLoc(img, mask)
        hi = percentile(vals, params.scale_percentile) if vals.size else top
    if hi <= lo:
        hi = top
    if hi <= lo:
        return Refusal(f"no pupil: the picture is uniform (every pixel {lo:.6g})")
    native = img.dtype in (np.uint8, np.uint16, np.int16, np.float32)
    src = img if native else img.astype(np.float32)
    u8 = cv2.convertScaleAbs(src, alpha=255.0 / (hi - lo), beta=-255.0 * lo / (hi - lo))
    glint_r = 0.0
    # (an empty mask's bounding box is empty: no glints)
    bx, by, bw, bh = cv2.boundingRect(bright) if bright is not None else (0, 0, 0, 0)
    if bw:
        # Only around the glints (their bounding box, padded by what the dilation and the
        # erosion reach): the same pixels as on the whole picture, a fraction of the work.
        in_box = bright[by : by + bh, bx : bx + bw]
        glint_r = _largest_radius(in_box)
        big = math.ceil(max(glint_r, math.sqrt(cv2.countNonZero(in_box) / math.pi)))
        pad = int(big + 2 + math.ceil(max(params.glint_margin_px, big)) + 2) + 1
        x0, y0 = max(0, bx - pad), max(0, by - pad)
        x1, y1 = min(img.shape[1], bx + bw + pad), min(img.shape[0], by + bh + pad)
        _fill_glints(u8[y0:y1, x0:x1], bright[y0:y1, x0:x1], params)
    holes = None
    if invalid is not None:
        u8[invalid] = 255
        holes = _fill_holes_dark(u8, invalid, params)
    return WorkPicture(u8, invalid, float(lo), float(hi), glint_r, holes, bright, (bx, by, bw, bh))


def _fill_holes_dark(u8: np.ndarray, invalid: np.ndarray, params) -> np.ndarray | None:
    """Fill ``u8``'s enclosed holes of missing pixels (in place) with the median of the valid
    pixels around each (a 2 px ring), and return them (bool), or None when there is none.

    A hole is a piece of ``invalid`` off the picture's border and no larger than a pupil
    (``pupil_max_area_frac``): NaN pixels inside the pupil left bright would make its blob a
    ring, whose centroid is off it (not compact) and which touches the missing pixels (not off
    them); filled with the pupil's level the blob is whole, and its outline points next to the
    hole are still left out (:func:`edge_points`), so the ellipse is fitted to the outline seen.
    Missing pixels on the border (a valid-area mask, a black border, a cut-off side) are left
    bright: a dark region running into them may be cut there."""
    rows, cols = invalid.shape
    inv8 = invalid.view(np.uint8) if invalid.dtype == np.bool_ else invalid.astype(np.uint8)
    n, lab, stats, _ = cv2.connectedComponentsWithStats(inv8, connectivity=8)
    if n <= 1:
        return None
    max_area = params.pupil_max_area_frac * rows * cols
    holes = None
    for i in range(1, n):
        x, y, w, h, area = (int(v) for v in stats[i])
        if x == 0 or y == 0 or x + w == cols or y + h == rows or area > max_area:
            continue
        x0, y0, x1, y1 = max(0, x - 2), max(0, y - 2), min(cols, x + w + 2), min(rows, y + h + 2)
        hole = (lab[y0:y1, x0:x1] == i).astype(np.uint8)
        ring = (cv2.dilate(hole, np.ones((5, 5), np.uint8)) > 0) & ~invalid[y0:y1, x0:x1]
        if not ring.any():
            continue
        u8[y0:y1, x0:x1][hole > 0] = int(median(u8[y0:y1, x0:x1][ring]))
        if holes is None:
            holes = np.zeros_like(invalid, dtype=bool)
        holes[y0:y1, x0:x1] |= hole > 0
    return _fill_thin_missing(u8, invalid, inv8, holes)


def _fill_thin_missing(u8: np.ndarray, invalid: np.ndarray, inv8: np.ndarray, holes):
    """Fill the missing pixels of strips ≤ 2 px thin (those a 3 × 3 opening of ``invalid``
    removes: a dead row or column, a scratch), wherever they run, with the mean of the valid
    pixels in the 5 × 5 px around each (in place), and return ``holes`` with them added.

    Such a strip hides no pupil — both its sides are seen — but left bright it cuts one: a
    NaN row 10 px under the centre of a 60 px pupil split its blob, and the larger half's fit
    was refused as "cut or hidden" (40 % of its outline backed). Filled, the pupil's blob is
    whole; its outline points next to the strip are still left out (:func:`edge_points`), as
    missing pixels neither back nor contradict the fit."""
    thin = inv8 & ~cv2.morphologyEx(inv8, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    if holes is not None:
        thin[holes] = 0
    if not thin.any():
        return holes
    valid = (1 - inv8).astype(np.float32)
    num = cv2.boxFilter(u8.astype(np.float32) * valid, -1, (5, 5), normalize=False)
    den = cv2.boxFilter(valid, -1, (5, 5), normalize=False)
    # (only where valid pixels lie on two opposite sides within 2 px, across the strip: a
    # missing border one pixel wide round a few valid ones is no strip through the picture)
    ok = valid > 0
    pad = np.pad(ok, 2)
    rows, cols = ok.shape
    up = pad[1 : rows + 1, 2:-2] | pad[0:rows, 2:-2]
    down = pad[3 : rows + 3, 2:-2] | pad[4 : rows + 4, 2:-2]
    left = pad[2:-2, 1 : cols + 1] | pad[2:-2, 0:cols]
    right = pad[2:-2, 3 : cols + 3] | pad[2:-2, 4 : cols + 4]
    fill = thin.astype(bool) & (den > 0) & ((up & down) | (left & right))
    if not fill.any():
        return holes
    u8[fill] = np.rint(num[fill] / den[fill]).astype(np.uint8)
    if holes is None:
        holes = np.zeros_like(invalid, dtype=bool)
    holes |= fill
    return holes


# --- Step 2: the threshold ladder ------------------------------------------------------------


@dataclass
class Candidate:
    """A dark blob at one ladder level: ``level`` (8-bit), ``area`` px, ``bbox`` (x, y, w, h) and
    ``seed`` (x, y) a pixel inside it, all on the ladder's (reduced) grid; ``q`` its area's
    relative change over the neighbouring levels, (A₊ − A₋) / A (MSER's stability); ``index``
    its ladder level (0 the darkest); ``stable_from`` the ladder level of its chain's first
    stable blob (set by :func:`choose` on the blobs it picks)."""

    level: float
    area: int
    bbox: tuple[int, int, int, int]
    seed: tuple[int, int]
    q: float = math.nan
    index: int = 0
    stable_from: int = -1
    #: the seed of its chain's first blob (set by :func:`choose`): the chain's name for
    #: :func:`ladder`'s ``passed``
    first: tuple[int, int] = (-1, -1)
    #: its chain's blob before the chain's largest jump in area up to it (≥ :data:`_JUMP` ×),
    #: or None (set by :func:`choose`): tried when this blob is not compact
    #: (:func:`_fit_candidates`)
    before: Candidate | None = None


def _level_candidates(lab, stats, cent, min_area, max_area, touch):
    """Indices of compact, inner components of one level: within the area bounds, fill of their
    box ≥ 0.5 (a tilted 2:1 ellipse fills 0.63), box aspect ≤ 3, not touching the picture's border
    or the invalid area (``touch``: labels that do), with their centroid (rounded half to even,
    as ``np.rint``) on the blob (else not convex enough). The components' statistics are
    looked at in one compiled pass (:func:`_compact_inner`), the Candidates made of the few
    left."""
    touch = _NO_LABELS if touch is None else np.asarray(touch, np.int64)
    found = _compact_inner(lab, stats, cent, float(min_area), float(max_area), touch)
    return [Candidate(0.0, a, (x, y, w, h), (cx, cy)) for x, y, w, h, a, cx, cy in found.tolist()]


_NO_LABELS = np.empty(0, np.int64)


@njit(cache=True, nogil=True)
def _compact_inner(lab, stats, cent, min_area, max_area, touch):
    """:func:`_level_candidates`' tests on each component (label order): (m, 7) int64 rows (x,
    y, w, h, area, cx, cy) of those passing."""
    rows, cols = lab.shape
    n = stats.shape[0]
    touched = np.zeros(n, np.bool_)
    for k in touch:
        if 0 <= k < n:
            touched[k] = True
    out = np.empty((n, 7), np.int64)
    m = 0
    for k in range(1, n):
        x, y, w, h, area = stats[k, 0], stats[k, 1], stats[k, 2], stats[k, 3], stats[k, 4]
        if area < min_area or area > max_area or touched[k]:
            continue
        if x <= 0 or y <= 0 or x + w >= cols or y + h >= rows:
            continue
        if area < 0.5 * w * h or max(w, h) > 3 * min(w, h):
            continue
        cx, cy = int(np.rint(cent[k, 0])), int(np.rint(cent[k, 1]))
        if lab[cy, cx] == k:
            out[m, 0], out[m, 1], out[m, 2], out[m, 3] = x, y, w, h
            out[m, 4], out[m, 5], out[m, 6] = area, cx, cy
            m += 1
    return out[:m]


def ladder(
    wp: WorkPicture, params, reduced=None, fine: int = 1, passed: frozenset = frozenset()
) -> tuple[list[list[Candidate]], int, tuple]:
    """Step 2 (module doc): chains of nested compact dark blobs over a ladder of thresholds.

    The picture is reduced by f = max(1, round(min(rows, cols) / ``ladder_rows``)) (area
    average) and smoothed (Gaussian σ 1 px) — the ladder only needs the blob, the edge comes
    later at full resolution — and thresholded at up to ``ladder_levels`` levels evenly spaced
    from its darkest pixel to its ``ladder_top_percentile``. At each level the compact inner blobs
    (:func:`_level_candidates`) are kept; a blob holding an earlier chain's seed continues that
    chain (blobs only grow up the ladder). Returns the chains (darkest level first), f and, for
    the refusals, (the (level, area in full-resolution px) of blobs too small to be a pupil,
    a function giving :func:`_edge_dark`'s darkest pupil-sized region on the border or missing
    pixels: :func:`_first_edge_dark`, worked only when a refusal asks).

    ``reduced``: :func:`_reduced`'s triple when already made. ``fine`` > 1: the ladder's dark
    end again, ``fine`` times finer (steps ≥ 1 level), over the first ``ladder_fine_span``
    levels (:func:`find_pupil`). ``passed``: the first seeds of chains whose blobs were
    refused already (:attr:`Candidate.first`): the ladder does not stop for them."""
    small, inv, f = reduced if reduced is not None else _reduced(wp, params)
    lo, top, step = _levels(small if inv is None else small[~inv], params, fine)
    min_area = max(2, int(params.pupil_min_area_px / f**2))
    tiny_area = max(2, int(params.pupil_tiny_area_px / f**2))
    max_area = params.pupil_max_area_frac * small.size
    chains: list[list[Candidate]] = []
    tiny: list[tuple[float, int]] = []
    areas: list[tuple[np.ndarray, np.ndarray]] = []
    seen = []  # each level's labels for _edge_dark, looked at only when a refusal needs it
    n_levels = int((top - lo) / step + 1e-9)
    # 16-bit labels when they fit (a 8-connected picture has ≤ ¼ of its pixels + 1 blobs):
    # the same labels, labelled faster.
    ltype = cv2.CV_16U if small.size < 4 * 65535 else cv2.CV_32S
    for li in range(n_levels + 1):
        t = lo + (li + 1) * step
        _, dark = cv2.threshold(small, t, 255, cv2.THRESH_BINARY_INV)
        lab, stats, cent = _labelled(dark, ltype)
        areas.append((lab, stats[:, cv2.CC_STAT_AREA]))
        touch = np.unique(lab[inv]) if inv is not None else None
        seen.append((lab, stats, touch, t))
        found = _level_candidates(lab, stats, cent, tiny_area, max_area, touch)
        for c in _ordered_level(found, f, wp, lab, small):
            c.level, c.index = t, li
            if c.area < min_area:
                tiny.append((c.level, c.area * f * f))
            else:
                _extend_chains(chains, c, lab)
        for ch in chains:  # the previous level's blobs now have both neighbours
            for c in ch[-2:]:
                if c.index == li - 1:
                    c.q = _growth(areas, c)
        if _settled(chains, li, params, passed):
            break
    for ch in chains:
        if ch[-1].index == len(areas) - 1:
            ch[-1].q = _growth(areas, ch[-1])
    return chains, f, (tiny, functools.partial(_first_edge_dark, seen, (min_area, max_area), f))


def _ordered_level(found: list[Candidate], f: int, wp, lab, small) -> list[Candidate]:
    """One ladder level's blobs in the order it starts their chains: by their seeds' distance
    (full resolution: ``f`` × (seed + ½) on the reduced grid) from the glints' middle
    (:attr:`WorkPicture.glints_middle` of ``wp``) when there is one, else darkest first (each
    blob's darkest value on the ladder's picture ``small``, labels ``lab``:
    :func:`_blob_minima`); stable (ties keep label order, top to bottom).

    That order is the order :func:`choose` tries chains that start at one level, and when a
    blob up the ladder joins several chains, the first started goes on and the others' blobs
    are dropped (:func:`_extend_chains`). In label order a band of iris in the lid's shadow
    above the pupil, starting at the pupil's level (17–19 DN against 16, a design-run render
    at 850 nm whose unsaturated glints the whole-picture glint mask does not hold), came
    first: it took the pupil's chain over where they joined and was answered as the pupil,
    83 px off. A disc darker than the pupil in the iris, 100 px above it, took the pupil's
    chain over the same way (the tests' picture; below the pupil it was found, its label
    later). The glints ring the cornea, whose centre the pupil lies near (the prior of
    :func:`_nearer_the_glints`); darkness alone would hand every darker disc beside the pupil
    its chain (tests/analysis/test_detect_pupil_ladder_order.py)."""
    if len(found) < 2:
        return found
    middle = wp.glints_middle
    if middle is not None:
        mx, my = middle
        return sorted(
            found,
            key=lambda c: math.hypot(f * (c.seed[0] + 0.5) - mx, f * (c.seed[1] + 0.5) - my),
        )
    rows = np.array([(*c.bbox, c.seed[0], c.seed[1]) for c in found], np.int64)
    low = _blob_minima(lab, small, rows)
    return [found[i] for i in np.argsort(low, kind="stable")]


@njit(cache=True, nogil=True)
def _blob_minima(lab, pic, rows):
    """The darkest value of ``pic`` over each blob of ``rows`` ((m, 6) int64: x, y, w, h of its
    box and its seed x, y; the blob is the label at its seed), float64."""
    out = np.empty(rows.shape[0])
    for i in range(rows.shape[0]):
        x, y, w, h = rows[i, 0], rows[i, 1], rows[i, 2], rows[i, 3]
        k = lab[rows[i, 5], rows[i, 4]]
        low = np.inf
        for r in range(y, y + h):
            for c in range(x, x + w):
                if lab[r, c] == k and pic[r, c] < low:
                    low = pic[r, c]
        out[i] = low
    return out


def _labelled(dark: np.ndarray, ltype: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``cv2.connectedComponentsWithStats(dark, connectivity=8, ltype=ltype)``'s labels, stats
    and centroids, labelled only on the box of the set pixels when it is under half the
    picture (a ladder's dark levels: the pupil's core and a few specks) — its origin rounded
    down to even coordinates, so that OpenCV's 2 × 2-block scan meets the pixels in the same
    order and numbers the components alike — and put back in the picture's frame. The same
    labels and stats (the background's row 0 aside: the ladder never reads it) and centroids
    within float rounding of the whole picture's, whose nearest pixel (all the ladder takes of
    them) is the same: a centroid Σx / A with A ≤ the picture's pixels is a half-integer
    exactly or ≥ 1 / (2 A) from one (checked: labels, stats and rounded centroids equal on
    24 000 random masks, one and two threads)."""
    bx, by, bw, bh = cv2.boundingRect(dark)
    if bw == 0 or 2 * bw * bh > dark.size:
        _, lab, stats, cent = cv2.connectedComponentsWithStats(dark, connectivity=8, ltype=ltype)
        return lab, stats, cent
    x0, y0 = bx - bx % 2, by - by % 2
    _, sub, stats, cent = cv2.connectedComponentsWithStats(
        dark[y0 : by + bh, x0 : bx + bw], connectivity=8, ltype=ltype
    )
    lab = np.zeros(dark.shape, sub.dtype)
    lab[y0 : by + bh, x0 : bx + bw] = sub
    stats[1:, cv2.CC_STAT_LEFT] += x0
    stats[1:, cv2.CC_STAT_TOP] += y0
    cent[1:, 0] += x0
    cent[1:, 1] += y0
    return lab, stats, cent


def _levels(small: np.ndarray, params, fine: int) -> tuple[float, float, float]:
    """The ladder's (lo, top, step) from ``small``'s valid pixels (any shape; the caller leaves
    out the missing ones, which the working picture holds at 255 and which would otherwise
    push the percentiles up: with 40 % of a headset frame outside its lens, P60 was 255): from
    the darkest pixel (lo + step the first level) to the ``ladder_top_percentile`` in steps of
    (P60 − P0.5) / ``ladder_levels`` (≥ 1), the top at least ``ladder_min_span`` × 255 above
    P0.5 (an unlit surround filling most of the picture holds P60 at the black level); with
    ``fine`` > 1, only the first ``ladder_fine_span`` steps, ``fine`` times finer (≥ 1)."""
    p_lo, top = percentiles(small, (0.5, params.ladder_top_percentile))
    top = max(top, p_lo + params.ladder_min_span * 255.0)
    step = max(1.0, (top - p_lo) / params.ladder_levels)
    lo = p_lo - step * math.ceil((p_lo - float(small.min())) / step)  # down to the darkest
    if fine > 1:
        top = min(top, lo + params.ladder_fine_span * step)
        step = max(1.0, step / fine)
    return lo, top, step


def _edge_dark(lab, stats, touch, areas: tuple[int, float], f: int, level: float) -> tuple:
    """(level, area in full-resolution px, what it touches) of the largest dark region of a
    pupil's size
    (``areas`` = (min, max), ladder px) touching the picture's border or the missing pixels at
    this level, or () when none: the ladder leaves such regions out, so a pupil cut by the
    frame is not a refusal's "too small" blob. A region larger than any pupil (an unlit
    surround filling half a wide-angle headset camera's picture, eyetrackvr) is no cut pupil,
    and is not named as one."""
    rows, cols = lab.shape
    a = stats[1:, cv2.CC_STAT_AREA]
    idx = np.flatnonzero((a >= areas[0]) & (a <= areas[1])) + 1
    if not len(idx):
        return ()
    touching = set(touch.tolist()) if touch is not None else set()
    largest, where = -1, ""
    for k in idx.tolist():
        x, y, w, h, area = stats[k].tolist()
        on_border = x == 0 or y == 0 or x + w == cols or y + h == rows
        if (on_border or k in touching) and area > largest:
            largest, where = area, "the picture's border" if on_border else _MISSING
    return (level, largest * f * f, where) if largest >= 0 else ()


#: What :func:`_edge_dark` names when a dark region runs into missing pixels, not the border.
_MISSING = "the missing pixels (NaN, outside the valid-area mask, or a black border)"


def _first_edge_dark(seen, areas: tuple[int, float], f: int) -> tuple:
    """:func:`_edge_dark` of the first of the ladder's levels ``seen`` ((labels, stats,
    touching labels, level) each, darkest first) that has such a region, or ()."""
    for lab, stats, touch, level in seen:
        found = _edge_dark(lab, stats, touch, areas, f, level)
        if found:
            return found
    return ()


def _area_reduced(u8: np.ndarray, f: int) -> np.ndarray:
    """``cv2.resize(u8, (cols // f, rows // f), interpolation=cv2.INTER_AREA)``: for an odd f ≥ 3
    dividing both sides (a 640 × 400 headset frame, f = 5) each f × f block's mean rounded to
    the nearest integer by one compiled pass (:func:`_block_means`) — OpenCV's integer-scale
    area path rounds the same mean (sum × (1 / f²) in float32, then to nearest), and with f²
    odd no mean is a tie nor within float32's error of one: the same bytes, in ~⅓ of the time;
    other sizes by OpenCV."""
    rows, cols = u8.shape
    if f >= 3 and f % 2 and rows % f == 0 and cols % f == 0 and u8.dtype == np.uint8:
        return _block_means(u8, f)
    return cv2.resize(u8, (cols // f, rows // f), interpolation=cv2.INTER_AREA)


@njit(cache=True, nogil=True)
def _block_means(u8, f):
    """Each f × f block's mean of ``u8`` (rows and cols multiples of f), rounded to nearest
    (f odd: never a tie), uint8."""
    rows, cols = u8.shape
    ny, nx = rows // f, cols // f
    colsum = np.empty(cols, np.int32)
    out = np.empty((ny, nx), np.uint8)
    area = f * f
    for by in range(ny):
        r0 = by * f
        for c in range(cols):  # the block row's column sums (vectorised over the row)
            colsum[c] = u8[r0, c]
        for r in range(r0 + 1, r0 + f):
            for c in range(cols):
                colsum[c] += u8[r, c]
        for bx in range(nx):
            s = 0
            for c in range(bx * f, bx * f + f):
                s += colsum[c]
            out[by, bx] = (2 * s + area) // (2 * area)  # ⌊mean + ½⌋, no ties
    return out


def _reduced(wp: WorkPicture, params) -> tuple[np.ndarray, np.ndarray | None, int]:
    """The ladder's picture: ``wp.u8`` reduced by f (area average) and smoothed (σ 1 px), its
    missing pixels (grown by 1, or None) and f."""
    rows, cols = wp.u8.shape
    f = max(1, int(round(min(rows, cols) / params.ladder_rows)))
    size = (cols // f, rows // f)
    small = _area_reduced(wp.u8, f) if f > 1 else wp.u8
    small = cv2.GaussianBlur(small, (5, 5), 1.0)
    inv = None
    missing = wp.invalid if wp.holes is None else wp.invalid & ~wp.holes
    if missing is not None and missing.any():
        inv = cv2.resize(missing.astype(np.uint8), size, interpolation=cv2.INTER_AREA)
        inv = cv2.dilate(inv, np.ones((3, 3), np.uint8)) > 0
    return small, inv, f


def _extend_chains(chains: list[list[Candidate]], c: Candidate, lab: np.ndarray) -> None:
    """Add blob ``c`` to the chain whose first seed it holds (blobs only grow up the ladder);
    chains whose seeds it all holds become one (two dark cores joined); else a new chain."""
    k = lab[c.seed[1], c.seed[0]]
    owners = [ch for ch in chains if lab[ch[0].seed[1], ch[0].seed[0]] == k]
    if not owners:
        chains.append([c])
        return
    owners[0].append(c)
    for other in owners[1:]:
        chains.remove(other)


def _growth(areas, c: Candidate) -> float:
    """MSER's stability of a blob: (A₊ − A₋) / A over the neighbouring levels, ∞ at the top."""
    a_hi = _area_at(areas, c.index + 1, c.seed)
    return (a_hi - _area_at(areas, c.index - 1, c.seed)) / c.area if a_hi > 0 else math.inf


def _pick(ch: list[Candidate], params) -> int | None:
    """Index of a chain's stable blob (:func:`choose`), or None."""
    i = next((i for i, c in enumerate(ch) if c.q <= params.ladder_max_growth), None)
    if i is None:
        return None
    while i + 1 < len(ch) and ch[i + 1].q < ch[i].q:
        i += 1
    return i


def _settled(chains: list[list[Candidate]], li: int, params, passed=frozenset()) -> bool:
    """Whether the ladder can stop after level ``li``: the darkest chain that is not dead
    without a stable blob has its stable blob and the level after it measured (a brighter
    chain can only rank after it); chains whose first seed is in ``passed`` do not count."""
    for ch in chains:
        if ch[0].seed in passed:
            continue
        i = _pick(ch, params)
        dead = ch[-1].index < li
        if i is None:
            if dead:
                continue
            return False
        return i + 1 < len(ch) and not math.isnan(ch[i + 1].q) or dead
    return False


def _area_at(areas, i: int, seed: tuple[int, int]) -> int:
    if i < 0:
        return 0
    if i >= len(areas):
        return 0
    lab, a = areas[i]
    k = lab[seed[1], seed[0]]
    return int(a[k]) if k > 0 else 0


# --- Step 3: choosing the pupil ----------------------------------------------------------------


def choose(chains: list[list[Candidate]], f: int, tiny: tuple, wp: WorkPicture, params, img=None):
    """Step 3 (module doc): the darkest chain's first stable blob, or a refusal naming why none.

    A chain's blob is stable at the first level where q ≤ ``ladder_max_growth`` and q is a local
    minimum (the area holds while the threshold crosses the pupil's edge band). The chains are
    tried darkest first (the level at which they first appear); returns the candidates in that
    order (the caller fits them in turn) or a :class:`Refusal`."""
    picks = []
    unstable = []
    # A chain that never settles counts as a pupil merged with the iris only when it starts
    # well below the picture's typical level (5 σ of the noise under the median); dark noise
    # blobs of a featureless picture do not.
    for ch in sorted(chains, key=lambda ch: ch[0].level):
        i = _pick(ch, params)
        if i is not None:
            ch[i].stable_from = next(c.index for c in ch if c.q <= params.ladder_max_growth)
            ch[i].first = ch[0].seed
            ch[i].before = _before_jump(ch, i)
            picks.append(ch[i])
        else:
            unstable.append(ch[0].level)
    if picks:
        return picks
    if unstable:
        k = _stride(wp.u8.size)
        typical = wp.u8[::k, ::k]
        if wp.invalid is not None:  # missing pixels are 255 in u8: not the typical level
            typical = typical[~wp.invalid[::k, ::k]]
        deep = median(typical)
        deep -= params.pupil_min_contrast_sigma * wp.noise
        unstable = [level for level in unstable if level <= deep]
    tiny, edge_dark_of = tiny
    edge_dark = edge_dark_of() if tiny else ()
    if tiny and edge_dark and edge_dark[0] <= min(tiny)[0]:
        return Refusal(
            f"no pupil off the picture's border: the darkest region of a pupil's size "
            f"({edge_dark[1]} px) touches {edge_dark[2]} (a pupil cut there?); the only "
            f"compact dark blob inside is {min(tiny)[1]} px, too small for a pupil"
        )
    if tiny and (not unstable or min(tiny)[0] < min(unstable)):
        area = min(tiny)[1]
        return Refusal(
            f"pupil too small: {area} px, the darkest compact blob (a pupil needs ≥ "
            f"{params.pupil_min_area_px} px)"
        )
    hint = _bright_pupil_hint(wp, f, params, img)
    if hint:
        return Refusal(f"no dark pupil: bright-pupil image? ({hint})")
    if unstable:
        return Refusal(
            f"no pupil (merged with the iris?): {len(unstable)} compact dark blob(s) but none "
            "keeps its size over neighbouring threshold levels (no pupil–iris step in the grey "
            "levels)"
        )
    return Refusal("no pupil: no compact dark blob off the picture's border stands out")


#: :func:`_before_jump`'s least growth in area from one blob of a chain to the next
_JUMP = 2.0


def _before_jump(ch: list[Candidate], i: int) -> Candidate | None:
    """The blob of chain ``ch`` before its largest jump in area (≥ :data:`_JUMP` ×) among its
    blobs up to the picked one ``ch[i]``, or None: where the pupil joins a dark region beside
    it a level or two up (a dark iris in a shadow, a few levels lighter than the pupil), its
    chain's stable blob is the two together, not compact, and the pupil alone is the blob
    before the jump (MSER's q of it is the jump's, > 1: it is never stable; the design run at
    850 nm, person 4 (0°, −5°):
    pupil 16 DN, the shadowed iris 23–27 DN, 3 levels apart in the 8-bit working picture).
    Only blobs of at least :data:`_DARKER_SHARE` of the picked one's area count: a speck that
    started the chain (2 reduced px against 386: another render of that person at (10°, −5°),
    a dark spot beside a glint in the iris) is not a pupil the jump hid, and was answered
    ``ok``, 47 px off."""
    best, at = _JUMP, None
    least = _DARKER_SHARE * ch[i].area
    for j in range(i):
        grow = ch[j + 1].area / ch[j].area
        if grow >= best and ch[j].area >= least:
            best, at = grow, ch[j]
    return at


def _bright_pupil_hint(wp: WorkPicture, f: int, params, img=None) -> str:
    """A compact bright blob of a pupil's size off the border, if any: the picture may be a
    bright-pupil one (on-axis illumination). Looked for on the input ``img`` when given (the
    working picture fills glints' pixels with the dark around them, and a bright pupil over
    the glints' floor is taken for one), else on ``wp.u8``. A blob far bigger than any glint
    (4 × ``glint_max_area_frac`` of the picture) is one; a blob bigger than the largest glint
    (1 ×; or, when the picture's glints are known, ``wp.glint_radius``, 4 × the largest of
    them) only when the ring around it (out to 1.5 × its equivalent radius) is darker than
    the picture's median: a lit pupil in its iris, not a patch of bright skin. The bright
    pixels are those over the 97th percentile, then over levels ``pupil_min_contrast_sigma``
    σ of the noise lower, down to the median: a lit pupil dimmer than the sclera (170 DN in a
    100 DN iris, sclera 190) is under the 97th percentile but stands alone at a lower level,
    where the iris around it parts it from the sclera."""
    if img is not None:
        scale = 255.0 / (wp.hi - wp.lo)
        u8 = cv2.convertScaleAbs(np.asarray(img, np.float32), alpha=scale, beta=-wp.lo * scale)
    else:
        u8 = wp.u8
    if wp.invalid is not None:
        u8 = np.where(wp.invalid, 0, u8).astype(np.uint8)
    rows, cols = u8.shape
    thr = percentile(u8, 97)
    if thr >= 254:
        return ""
    glint_max = params.glint_max_area_frac * rows * cols
    # (the picture's own glints, when known: a lit pupil under the cap on a glint's area, a
    # 20 px radius one in 640 × 400, is still far larger than any glint there)
    known = 4.0 * math.pi * wp.glint_radius**2 if wp.glint_radius > 0 else glint_max
    min_area = max(params.pupil_min_area_px, min(glint_max, known))
    k = _stride(u8.size)
    typical = median(u8[::k, ::k])
    step = max(1.0, params.pupil_min_contrast_sigma * wp.noise)
    level = thr
    while True:
        _, bright = cv2.threshold(u8, level, 255, cv2.THRESH_BINARY)
        _, lab, stats, cent = cv2.connectedComponentsWithStats(bright, connectivity=8)
        for c in _level_candidates(lab, stats, cent, min_area, 0.1 * rows * cols, None):
            what = f"a compact bright blob of {c.area} px at ({c.seed[0]}, {c.seed[1]})"
            if c.area >= 4 * glint_max:
                return what
            r = max(2, int(round(0.5 * math.sqrt(c.area / math.pi))))
            x, y, w, h = c.bbox
            x0, y0 = max(0, x - r), max(0, y - r)
            x1, y1 = min(cols, x + w + r), min(rows, y + h + r)
            blob = (lab[y0:y1, x0:x1] == lab[c.seed[1], c.seed[0]]).astype(np.uint8)
            ring = cv2.dilate(blob, _disc(2 * r + 1)) > blob
            if ring.any() and median(u8[y0:y1, x0:x1][ring]) < typical:
                return f"{what} inside a darker ring"
        level -= step
        if level <= typical:
            return ""


# --- Steps 4–7: the blob at full resolution, closing, outline, edge, fit, support -------------


@dataclass(frozen=True)
class Blob:
    """The chosen blob at full resolution in a window (x0, y0) of the picture: ``mask`` (uint8
    0/255, the closed blob with the glints touching it), ``raw`` the thresholded blob alone,
    ``near_glint`` the glint mask grown by the glint margin, ``area`` (px) and ``diam`` (px) its
    equivalent diameter, ``level`` the threshold (8-bit)."""

    x0: int
    y0: int
    mask: np.ndarray
    raw: np.ndarray
    near_glint: np.ndarray
    contour: np.ndarray
    area: float
    diam: float
    level: float


def full_res_blob(wp: WorkPicture, cand: Candidate, f: int, bright: np.ndarray, params, img=None):
    """Step 4 (module doc): the candidate's blob at full resolution — the smoothed picture (σ 1
    px) thresholded at its level in a window around it, the component under its seed, glints
    touching it joined, closed — or a refusal (not compact). When it is not compact and glints
    are near, and ``img`` (the picture ``wp`` was made from) is given, it is judged again with
    the glints' pixels left out (:func:`_glint_forgiven`), then held to
    ``pupil_min_solidity_glints``."""
    rows, cols = wp.u8.shape
    bx, by, bw, bh = (v * f for v in cand.bbox)
    diam0 = math.sqrt(4.0 * cand.area * f * f / math.pi)
    k = params.closing_kernel_px or _odd(params.closing_kernel_frac * diam0)
    m = k + int(math.ceil(0.15 * diam0)) + 2 * f + 4
    x0, y0 = max(0, bx - m), max(0, by - m)
    x1, y1 = min(cols, bx + bw + m), min(rows, by + bh + m)
    roi = cv2.GaussianBlur(wp.u8[y0:y1, x0:x1], (5, 5), 1.0)
    _, dark = cv2.threshold(roi, cand.level, 255, cv2.THRESH_BINARY_INV)
    sx, sy = cand.seed[0] * f + f // 2 - x0, cand.seed[1] * f + f // 2 - y0
    sx, sy = min(sx, dark.shape[1] - 1), min(sy, dark.shape[0] - 1)
    if dark[sy, sx]:
        # The 8-connected component under the seed, by a flood fill (∝ its size; labelling
        # the whole window costs more).
        filled = np.zeros((dark.shape[0] + 2, dark.shape[1] + 2), np.uint8)
        flags = 8 | (255 << 8) | cv2.FLOODFILL_MASK_ONLY
        cv2.floodFill(dark, filled, (sx, sy), 0, 0, 0, flags)
        raw = filled[1:-1, 1:-1]
    else:
        _, lab, stats, _ = cv2.connectedComponentsWithStats(dark, connectivity=8)
        if len(stats) < 2:
            return Refusal("no pupil: the dark blob vanishes at full resolution")
        lab_seed = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
        raw = np.where(lab == lab_seed, 255, 0).astype(np.uint8)
    comp = raw.copy()
    near_glint, (gx0, gy0, gx1, gy1) = _grown_glints_box(
        _glints_beside(bright[y0:y1, x0:x1], cv2.countNonZero(raw), params), params
    )
    if gx1 > gx0:
        # Glints touching the blob (with their skirts) join it: no notch however small the
        # closing. Worked on the grown glints' box (nothing joins outside it); the blob's
        # 3 × 3 dilation there from the box padded by 1 px (the same pixels).
        box = (slice(gy0, gy1), slice(gx0, gx1))
        n_glab, glab = cv2.connectedComponents(
            near_glint[box], connectivity=8, ltype=_label_type((gy1 - gy0) * (gx1 - gx0))
        )
        py0, px0 = max(0, gy0 - 1), max(0, gx0 - 1)
        grown = cv2.dilate(comp[py0 : gy1 + 1, px0 : gx1 + 1], np.ones((3, 3), np.uint8))
        grown = grown[gy0 - py0 : gy0 - py0 + gy1 - gy0, gx0 - px0 : gx0 - px0 + gx1 - gx0]
        joined = np.zeros(n_glab, bool)
        joined[glab[(grown > 0) & (glab > 0)]] = True
        if joined.any():
            if n_glab <= 256:  # a look-up table over the labels: one pass, no index array
                lut = np.zeros(256, np.uint8)
                lut[:n_glab][joined] = 255
                cv2.bitwise_or(comp[box], cv2.LUT(glab.astype(np.uint8), lut), dst=comp[box])
            else:
                comp[box][joined[glab]] = 255
    closed, contour, solidity = _closed_solidity(comp, k)
    if solidity < params.pupil_min_solidity:
        got = _compact_again(
            (img, wp, (x0, y0, x1, y1)), (raw, comp, near_glint), k, (sx, sy), cand.level, params
        )
        if got is not None:
            closed, contour, solidity, raw = got
    area = float(cv2.countNonZero(closed))
    if solidity < params.pupil_min_solidity:
        return Refusal(
            f"no pupil: the darkest blob ({int(area)} px) is not compact "
            f"(solidity {solidity:.2f} < {params.pupil_min_solidity:.2f})"
        )
    diam = math.sqrt(4.0 * area / math.pi)
    return Blob(x0, y0, closed, raw, near_glint, contour, area, diam, cand.level)


def _compact_again(pics, masks, k: int, seed: tuple[int, int], level: float, params):
    """A blob not compact (step 4) judged again: with the glints' pixels left out
    (:func:`_glint_forgiven`), then with thin strokes cut off (:func:`_without_strokes`),
    each held to ``pupil_min_solidity_glints``. ``pics``: (the input or
    None, the working picture, the window (x0, y0, x1, y1)); ``masks``: the window's raw blob,
    the blob with its glints joined and the grown glints (0/255). Returns (closed, contour,
    solidity, raw) or None."""
    img, wp, window = pics
    raw, comp, near_glint = masks
    if img is not None and near_glint.any():
        # Glints beside the pupil change its blob where they are (a glint a few px outside
        # the edge is filled with the pupil's dark and grows a bump on it): judged again with
        # the glints' pixels left out (:func:`_glint_forgiven`), by a stricter measure.
        forgiven = _glint_forgiven(img, window, raw, near_glint, wp, level)
        if forgiven is not None:
            closed, contour, solidity = _closed_solidity(forgiven[0], k)
            if solidity >= params.pupil_min_solidity_glints:
                return closed, contour, solidity, forgiven[1]
    # Thin dark strokes joined to it (lashes, darker than the pupil, across its edge): cut off
    # by an opening with the closing's element, ≈ 0.15 × the pupil's diameter — a lash a few
    # px wide goes, the pupil (its outline's curvature radius ≥ its semi-minor axis, far over
    # k / 2) keeps its shape — and the piece under the seed judged again, by the stricter
    # measure too: on a real close-up (18 px pupil, k = 3) the opening split a ragged dark
    # blob and kept a piece of solidity 0.88, 8 px off the pupil.
    lash_free = _without_strokes(comp, k, seed)
    if lash_free is not None:
        closed, contour, solidity = _closed_solidity(lash_free, k)
        if solidity >= params.pupil_min_solidity_glints:
            return closed, contour, solidity, cv2.bitwise_and(raw, lash_free)
    return None


def _without_strokes(comp: np.ndarray, k: int, seed: tuple[int, int]) -> np.ndarray | None:
    """The blob ``comp`` (0/255) opened by the k × k elliptical element, the piece under
    ``seed`` (x, y) or else the largest (0/255), or None when nothing is left or the opening
    changed nothing: thin strokes (lashes) joined to a pupil cut off."""
    if k < 3:
        return None
    opened = cv2.morphologyEx(comp, cv2.MORPH_OPEN, _disc(k))
    if not cv2.countNonZero(opened) or cv2.countNonZero(opened) == cv2.countNonZero(comp):
        return None
    n, lab, stats, _ = cv2.connectedComponentsWithStats(opened, connectivity=8)
    i = int(lab[seed[1], seed[0]])
    if i == 0:
        i = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    return np.where(lab == i, 255, 0).astype(np.uint8)


def _glints_beside(bright: np.ndarray, pupil_area: int, params) -> np.ndarray:
    """The glint mask ``bright`` (0/255) of a dark blob's window without the bright blobs larger
    than ``glint_max_pupil_frac`` × the blob's area ``pupil_area`` (px): a corneal glint is far
    smaller than the pupil it sits on, while saturated skin beside a small pupil is not (the
    eyetrackvr preset: 38–125 px patches of lit brow and lid within 15 px of a 60 px pupil),
    and joined to the blob or grown by its radius it would take the pupil's outline with it.
    ``bright`` itself when nothing is dropped."""
    lim = params.glint_max_pupil_frac * pupil_area
    # Labelled on the glints' bounding box only (the same components: there is nothing
    # outside it), not on the whole window (a fifth of the cost on the synthetic 640 × 400).
    bx, by, bw, bh = cv2.boundingRect(bright)
    if not bw:
        return bright
    box = bright[by : by + bh, bx : bx + bw]
    n, lab, stats, _ = cv2.connectedComponentsWithStats(
        box, connectivity=8, ltype=_label_type(box.size)
    )
    big = stats[:, cv2.CC_STAT_AREA] > lim
    big[0] = False
    if not big.any():
        return bright
    out = bright.copy()
    out[by : by + bh, bx : bx + bw] = np.where(big[lab], 0, box)
    return out


def _closed_solidity(comp: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray, float]:
    """The blob ``comp`` (0/255) closed by the k × k element (:func:`_closing`), its largest
    outer contour, and that contour's solidity (its area / its convex hull's; 0 when flat)."""
    closed = _closing(comp, k)
    contours, _ = cv2.findContours(closed, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    contour = max(contours, key=cv2.contourArea)
    c_area = cv2.contourArea(contour)
    hull_area = cv2.contourArea(cv2.convexHull(contour))
    return closed, contour, c_area / hull_area if hull_area > 0 else 0.0


def _glint_forgiven(img, window, raw, near_glint, wp: WorkPicture, level: float):
    """The blob with the glints' pixels left out: (blob, raw) on the window, or None.

    The working picture fills each glint with the darkest value within its reach
    (:func:`_fill_glints`), so that a glint inside the pupil punches no hole in its blob; but a
    glint a few px outside the edge is then filled with the pupil's dark too and grows a bump
    on it (vr-offaxis at 100 × 100: 1–3 px glints 2–4 px outside a 16–20 px pupil, solidity
    0.71–0.77). Here the glints are left out instead, as eye trackers leave glint pixels out of
    the pupil (PuRe, ElSe, Pupil Labs' 2D detector): the core C is the pixels of ``raw`` that
    are dark in the picture without the fill (the same 8-bit scale, smoothing and ``level``)
    and off the grown glint mask G (``near_glint``, which the edge points and the pupil's level
    leave out too); the blob is C ∪ (G ∩ hull(C)) — under a glint, the core's convex hull: a
    bump is cut off, a notch a glint cut into the edge is filled (the convex deficiency under a
    glint is forgiven). Away from the glints nothing changes: lashes, shadows and folds are
    judged as before. ``raw`` (the pupil's level is its median) becomes C ∪ (raw ∩ G ∩ hull(C)).

    None when C is empty or not one piece: a glint on a pupil's edge does not cut it in two
    (a real close-up whose dark iris the glints' fill had joined to the pupil had a core of two
    pieces, and its forgiven blob was answered 5 px off)."""
    x0, y0, x1, y1 = window
    src = img[y0:y1, x0:x1]
    if src.dtype not in (np.uint8, np.uint16, np.int16, np.float32):
        src = src.astype(np.float32)  # as work_picture scales it
    alpha = 255.0 / (wp.hi - wp.lo)
    plain = cv2.convertScaleAbs(src, alpha=alpha, beta=-wp.lo * alpha)
    if wp.invalid is not None:
        plain[wp.invalid[y0:y1, x0:x1]] = 255
    if wp.holes is not None:  # enclosed holes at their surround's level, as in ``wp.u8``
        hole = wp.holes[y0:y1, x0:x1]
        plain[hole] = wp.u8[y0:y1, x0:x1][hole]
    smooth = cv2.GaussianBlur(plain, (5, 5), 1.0)
    _, dark = cv2.threshold(smooth, level, 255, cv2.THRESH_BINARY_INV)
    core = cv2.bitwise_and(cv2.bitwise_and(raw, dark), cv2.bitwise_not(near_glint))
    if cv2.connectedComponents(core, connectivity=8)[0] != 2:
        return None
    hull = np.zeros_like(raw)
    cv2.fillConvexPoly(hull, cv2.convexHull(cv2.findNonZero(core)), 255)
    under = cv2.bitwise_and(near_glint, hull)
    return cv2.bitwise_or(core, under), cv2.bitwise_or(core, cv2.bitwise_and(raw, under))


def _closing(mask: np.ndarray, k: int) -> np.ndarray:
    """Morphological closing of a 0/255 mask by the k × k elliptical element (OpenCV's default
    borders), worked only on the mask's bounding box padded by k // 2 + 1: the same pixels as
    on the whole mask — the dilation reaches k // 2 past the box, so the pad's outer ring stays
    0 and every erosion window reaching past it holds a 0 of that ring — at a fraction of the
    cost. The element's rows are centred runs (:func:`_ellipse_half_widths`): the closing is
    then worked row by row on runs of pixels for k ≥ 9 (:func:`_close_runs`, the same pixels
    as ``cv2.morphologyEx``, whose cost grows with the element's ~k² points: 3 × faster at
    k = 15)."""
    bx, by, bw, bh = cv2.boundingRect(mask)
    pad = k // 2 + 1
    x0, y0 = max(0, bx - pad), max(0, by - pad)
    x1, y1 = min(mask.shape[1], bx + bw + pad), min(mask.shape[0], by + bh + pad)
    out = np.zeros_like(mask)
    half = _ellipse_half_widths(k) if k >= 9 else None  # smaller: OpenCV's is as fast
    if half is not None:
        out[y0:y1, x0:x1] = _close_runs(mask[y0:y1, x0:x1], half)
        return out
    out[y0:y1, x0:x1] = cv2.morphologyEx(
        mask[y0:y1, x0:x1],
        cv2.MORPH_CLOSE,
        _disc(k),
    )
    return out


_HALF_WIDTHS: dict[int, np.ndarray | None] = {}


def _ellipse_half_widths(k: int) -> np.ndarray | None:
    """Each row's half-width (k,) int64 of OpenCV's k × k elliptical element, when every row is
    one run centred on the anchor (as for odd k), else None."""
    if k not in _HALF_WIDTHS:
        el = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))
        half = []
        for row in el:
            nz = np.flatnonzero(row)
            centred = len(nz) and nz[0] + nz[-1] == 2 * (k // 2)
            if not centred or len(nz) != nz[-1] - nz[0] + 1 or el.shape[0] % 2 == 0:
                half = None
                break
            half.append((len(nz) - 1) // 2)
        _HALF_WIDTHS[k] = None if half is None else np.array(half, np.int64)
    return _HALF_WIDTHS[k]


@njit(cache=True, nogil=True)
def _row_runs(src, invert):
    """The runs [start, end) of set pixels (≠ 0, or with ``invert`` = 0) of each row of ``src``
    ((h, w) uint8): starts and ends (h, w // 2 + 1) and their count a row."""
    h, w = src.shape
    cap = w // 2 + 1
    rs = np.empty((h, cap), np.int64)
    re = np.empty((h, cap), np.int64)
    nr = np.zeros(h, np.int64)
    for y in range(h):
        c = 0
        x = 0
        while x < w:
            if (src[y, x] != 0) != invert:
                s = x
                while x < w and (src[y, x] != 0) != invert:
                    x += 1
                rs[y, c] = s
                re[y, c] = x
                c += 1
            x += 1
        nr[y] = c
    return rs, re, nr


@njit(cache=True, nogil=True)
def _dilate_runs(src, half, invert):
    """Dilation of the set pixels of ``src`` ((h, w) uint8: those ≠ 0, or with ``invert`` those
    = 0) by the element whose row i (offset i − k // 2) is the run of half-width ``half[i]``
    about the anchor, nothing outside the picture counting: (h, w) uint8 0/1. Each row's runs
    found once; an output row adds its k source rows' runs, widened, in a difference array."""
    h, w = src.shape
    k = half.size
    r = k // 2
    rs, re, nr = _row_runs(src, invert)
    out = np.zeros((h, w), np.uint8)
    diff = np.zeros(w + 1, np.int64)
    for y in range(h):
        hit = False
        for i in range(k):
            yy = y + i - r
            if yy < 0 or yy >= h:
                continue
            g = half[i]
            for c in range(nr[yy]):
                diff[max(0, rs[yy, c] - g)] += 1
                diff[min(w, re[yy, c] + g)] -= 1
                hit = True
        if hit:
            acc = 0
            for x in range(w):
                acc += diff[x]
                diff[x] = 0
                if acc > 0:
                    out[y, x] = 1
            diff[w] = 0
    return out


@njit(cache=True, nogil=True)
def _close_runs(src, half):
    """:func:`_closing` of ``src`` (uint8, ≠ 0 set) by the element of row half-widths ``half``:
    the dilation (:func:`_dilate_runs`, outside counting as 0) then the erosion — the dilation
    of its zeros, outside counting as set (OpenCV's default borders) — as uint8 0/255."""
    d = _dilate_runs(src, half, False)
    z = _dilate_runs(d, half, True)
    h, w = src.shape
    out = np.empty((h, w), np.uint8)
    for y in range(h):
        for x in range(w):
            out[y, x] = 0 if z[y, x] else 255
    return out


def _grown_glints(bright: np.ndarray, params, extra: int = 0, radius: float | None = None):
    """The glint mask grown by max(``glint_margin_px``, r) px, r the equivalent radius of the
    largest glint in it (``radius`` when given): the mask holds a glint's core (above half its
    peak), and its skirt, which brightens the pupil's edge under it, reaches about as far
    again."""
    if not cv2.countNonZero(bright):
        return bright.copy()
    if radius is None:
        radius = _largest_radius(bright)
    g = int(math.ceil(max(params.glint_margin_px, radius))) + extra
    return cv2.dilate(bright, _disc(2 * g + 1))


def _grown_glints_box(bright: np.ndarray, params):
    """:func:`_grown_glints` of ``bright`` and the box (x0, y0, x1, y1) holding all of it
    (empty when there are no glints), worked on the glints' bounding box padded by the
    growth: the same pixels (a dilation reaches no farther), a fraction of the work."""
    if not cv2.countNonZero(bright):
        return np.zeros_like(bright), (0, 0, 0, 0)
    rows, cols = bright.shape
    bx, by, bw, bh = cv2.boundingRect(bright)
    # The outlines from the box padded by 1 px (as in the whole mask: none touches its edge).
    cx0, cy0 = max(0, bx - 1), max(0, by - 1)
    radius = _largest_radius(bright[cy0 : by + bh + 1, cx0 : bx + bw + 1])
    g = int(math.ceil(max(params.glint_margin_px, radius)))
    x0, y0 = max(0, bx - g), max(0, by - g)
    x1, y1 = min(cols, bx + bw + g), min(rows, by + bh + g)
    out = np.zeros_like(bright)
    out[y0:y1, x0:x1] = _grown_glints(bright[y0:y1, x0:x1], params, radius=radius)
    return out, (x0, y0, x1, y1)


def _largest_radius(bright: np.ndarray) -> float:
    """Equivalent radius (px) of the largest blob of a 0/255 mask (0 when empty)."""
    contours, _ = cv2.findContours(bright, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    if not contours:
        return 0.0
    return math.sqrt(
        max(cv2.contourArea(c) + 0.5 * cv2.arcLength(c, True) for c in contours) / math.pi
    )


_IMMERKAER = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], np.float32)


def _local_noise(u8: np.ndarray, inside: np.ndarray, ring: np.ndarray) -> float:
    """The pixel noise σ (``u8`` units) where the contrast is judged: Immerkær's estimate
    (:func:`noise_sigma`) over the pupil's pixels and over its surround's, the larger of the
    two. Shot noise grows with the signal, so a picture's noise — set by its brightest large
    area, the skin of an off-axis view or a Monte Carlo render's sparse samples there — can be
    several times that between a pupil and an iris near the black level."""
    # |M * u8| ≤ 16 × 255: exact in 16 bits, and its median is then counted (:func:`median`);
    # taken only at the pixels of each mask (:func:`_immerkaer_at`: the same values as
    # cv2.filter2D's over the whole window, BORDER_REFLECT).
    return max(1.4826 * median(_immerkaer_at(u8, m)) / 6.0 for m in (inside, ring))


@njit(cache=True, nogil=True)
def _immerkaer_at(u8, mask):
    """|M * u8| (Immerkær's mask, :func:`noise_sigma`) at the set pixels of ``mask`` (bool, the
    shape of ``u8``), in row order, the picture's edge reflected (OpenCV's BORDER_REFLECT: row
    −1 is row 0): uint16, exact."""
    h, w = u8.shape
    out = np.empty(h * w, np.uint16)
    n = 0
    for y in range(h):
        ym, yp = max(y - 1, 0), min(y + 1, h - 1)
        for x in range(w):
            if mask[y, x]:
                xm, xp = max(x - 1, 0), min(x + 1, w - 1)
                v = 4 * np.int32(u8[y, x]) - 2 * (
                    np.int32(u8[ym, x])
                    + np.int32(u8[yp, x])
                    + np.int32(u8[y, xm])
                    + np.int32(u8[y, xp])
                )
                v += (
                    np.int32(u8[ym, xm])
                    + np.int32(u8[ym, xp])
                    + np.int32(u8[yp, xm])
                    + np.int32(u8[yp, xp])
                )
                out[n] = abs(v)
                n += 1
    return out[:n]


def blob_contrast(img: np.ndarray, wp: WorkPicture, blob: Blob, params):
    """Step 5a (module doc): the pupil's level (median inside, off glints) and its surround's (a
    ring 0.05–0.1 × the diameter outside, ≥ 2 px each, off glints and invalid pixels), input
    units; a refusal when the step is under ``pupil_min_contrast_sigma`` × the pixel noise or
    ``pupil_min_contrast`` of the picture's (robust) range."""
    h, w = blob.mask.shape
    sub = img[blob.y0 : blob.y0 + h, blob.x0 : blob.x0 + w]
    usable = blob.near_glint == 0
    if wp.invalid is not None:
        usable &= ~wp.invalid[blob.y0 : blob.y0 + h, blob.x0 : blob.x0 + w]
    inside = (blob.raw > 0) & usable
    if not inside.any():
        return Refusal("no pupil: the dark blob is all glint")
    pupil_level = median(sub[inside])
    ring_in = max(2, int(round(0.05 * blob.diam)))
    ring_out = ring_in + max(2, int(round(0.05 * blob.diam)))
    # Distances from the blob, worked only on its box padded past the ring (the chamfer
    # distance's shortest paths stay in the box of their ends: the same values).
    bx, by, bw, bh = cv2.boundingRect(blob.mask)
    pad = ring_out + 2
    x0, y0 = max(0, bx - pad), max(0, by - pad)
    x1, y1 = min(w, bx + bw + pad), min(h, by + bh + pad)
    outside = cv2.distanceTransform(cv2.bitwise_not(blob.mask[y0:y1, x0:x1]), cv2.DIST_L2, 3)
    ring = np.zeros((h, w), bool)
    ring[y0:y1, x0:x1] = (outside > ring_in) & (outside <= ring_out)
    ring &= usable
    if not ring.any():
        return Refusal("no pupil: the dark blob has no surround to compare with")
    surround = median(sub[ring])
    span = wp.hi - wp.lo
    step = surround - pupil_level
    # The noise on the ring's box (the pixels it and the blob's inside reach, ≥ 2 px in: the
    # same values as on the whole window).
    box = (slice(y0, y1), slice(x0, x1))
    win = wp.u8[blob.y0 : blob.y0 + h, blob.x0 : blob.x0 + w][box]
    noise = _local_noise(win, inside[box], ring[box])
    noise = max(noise, 0.5) * span / 255.0
    # The step is a difference of medians over N₁ and N₂ pixels: judged by its own standard
    # error, 1.2533 σ √(1/N₁ + 1/N₂) (a median's efficiency against a mean, π/2), as
    # :func:`_core_step` judges the pupil found inside an iris — not by the pixel noise σ,
    # which refused a 60 px pupil 2–3 σ under its iris (pupil 20, iris 30 DN at σ 3: ~60
    # standard errors) whenever the ladder's first blob was that pupil rather than the iris
    # around it (saturated glints' filled discs joined the iris's ramp differently).
    n_in, n_ring = int(np.count_nonzero(inside)), int(np.count_nonzero(ring))
    err = 1.2533 * noise * math.sqrt(1.0 / n_in + 1.0 / n_ring)
    if step < params.pupil_min_contrast_sigma * err or step < params.pupil_min_contrast * span:
        return Refusal(
            f"pupil merged with iris: the darkest compact blob ({int(blob.area)} px) is only "
            f"{step / err:.1f} standard errors ({step / noise:.1f} σ of the pixel noise, "
            f"{100 * step / span:.0f} % of the range) darker than its surround (need "
            f"{params.pupil_min_contrast_sigma:.0f} and {100 * params.pupil_min_contrast:.0f} %)"
        )
    return pupil_level, surround


def edge_points(blob: Blob, shape: tuple[int, int], invalid, params):
    """Step 5b (module doc): the closed blob's outline points (x, y) in the picture, less those
    on glints, on the image border or next to invalid pixels; with the drop counts."""
    rows, cols = shape
    pts = blob.contour[:, 0, :].astype(np.float64)
    x, y = pts[:, 0] + blob.x0, pts[:, 1] + blob.y0
    b = params.border_margin_px
    on_border = (x < b) | (y < b) | (x > cols - 1 - b) | (y > rows - 1 - b)
    if invalid is not None:
        near_inv = cv2.dilate(invalid.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
        on_border |= near_inv[y.astype(int), x.astype(int)]
    on_glint = blob.near_glint[pts[:, 1].astype(int), pts[:, 0].astype(int)] > 0
    keep = ~on_border & ~on_glint
    dropped = {
        "border": int(on_border.sum()),
        "glint": int((on_glint & ~on_border).sum()),
        "no_edge": 0,
        "outlier": 0,
    }
    if keep.sum() < params.min_edge_points:
        return Refusal(
            f"no pupil: only {int(keep.sum())} of the dark blob's {len(pts)} outline points are "
            "off the image border and glints"
        ), dropped
    return (x[keep], y[keep]), dropped


def _refine_smoothed(img, bright, e: Ellipse, x, y, pupil_level: float, reach: float, params):
    """Step 5c: :func:`_refine_edge` on the picture smoothed by a Gaussian of
    ``refine_smooth_px`` (σ, px) in a window around the points. A symmetric blur moves no
    iso-line's centre (module doc, step 5) but averages the pixel noise along the normal, so a
    real, noisy edge has one crossing instead of several. The blur is a normalised convolution
    that leaves out the glints (``bright`` grown by ``glint_margin_px``), G * (w I) / G * w with
    w = 0 on them, lest it spread their light over the edge next to them."""
    rows, cols = img.shape
    m = int(math.ceil(reach + 3 * params.refine_smooth_px + 3))
    x0, y0 = max(0, int(x.min()) - m), max(0, int(y.min()) - m)
    x1, y1 = min(cols, int(x.max()) + m + 1), min(rows, int(y.max()) + m + 1)
    sub = img[y0:y1, x0:x1].astype(np.float32)
    if params.refine_smooth_px > 0:
        glints = bright[y0:y1, x0:x1]
        sig = params.refine_smooth_px
        if glints.any():
            g = int(math.ceil(params.glint_margin_px))
            w = (cv2.dilate(glints, _disc(2 * g + 1)) == 0).astype(np.float32)
            num = cv2.GaussianBlur(sub * w, (0, 0), sig)
            den = cv2.GaussianBlur(w, (0, 0), sig)
            sub = np.where(den > 1e-3, num / np.maximum(den, 1e-3), sub)
        else:
            sub = cv2.GaussianBlur(sub, (0, 0), sig)
    ex = Ellipse(e.cx - x0, e.cy - y0, e.a, e.b, e.theta)
    xr, yr, ok = _refine_edge(
        sub,
        ex,
        x - x0,
        y - y0,
        pupil_level,
        reach,
        params.edge_fraction,
        params.refine_tangential_px,
    )
    return xr + x0, yr + y0, ok


def _on_mask(mask: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Whether points (x, y) fall on a non-zero pixel of ``mask`` (False outside it or not
    finite): a refined edge point that moved onto a glint's skirt is no pupil edge."""
    ok = np.isfinite(x) & np.isfinite(y)
    c = np.rint(np.where(ok, x, -1)).astype(np.intp)
    r = np.rint(np.where(ok, y, -1)).astype(np.intp)
    inside = (c >= 0) & (r >= 0) & (c < mask.shape[1]) & (r < mask.shape[0])
    out = np.zeros(len(x), bool)
    out[inside] = mask[r[inside], c[inside]] > 0
    return out


def support_of(e: Ellipse, x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Step 7 (module doc): over equal eccentric-anomaly bins (≈ 2 px of arc, 12–180) of the
    ellipse, the fraction holding at least one of the points and the longest run of empty bins
    (circular), as a fraction of the outline. A lid or the picture's border hides one long arc;
    a ragged real edge leaves many short gaps."""
    s, q = e.local(x, y)
    anomaly = np.arctan2(q / e.b, s / e.a)
    n_bins = min(max(round(e.perimeter / 2.0), 12), 180)
    occ = np.zeros(n_bins, bool)
    occ[((anomaly + math.pi) / (2 * math.pi) * n_bins).astype(int) % n_bins] = True
    filled = np.flatnonzero(occ)  # circular gaps between occupied bins
    if not len(filled):
        return 0.0, 1.0
    # (scalars from here: the same numbers as the array operations on a few dozen bins)
    wrap = int(filled[0]) + n_bins - int(filled[-1])
    longest = max(wrap, int(np.diff(filled).max()) if len(filled) > 1 else 0) - 1
    return len(filled) / n_bins, longest / n_bins


def _no_edge(blob: Blob, dropped: dict, params) -> str:
    """The refusal of a blob with too few sharp edge points: cut, when more of its outline
    than a pupil may miss (``max_boundary_gap``) runs along the border or the missing pixels
    (a valid-area mask across the pupil leaves a sliver without a pupil's edge); hidden by
    glints, when as much of it lies on glints (grown by their radius): bloomed glints beside a
    small pupil, filled with its dark, join its blob and leave it little outline of its own
    (four 3000 DN glints of σ 2 px 6 px outside a 24 px pupil: 152 of 168 outline points)."""
    n_out = len(blob.contour)
    if dropped["border"] > params.max_boundary_gap * n_out:
        return (
            f"pupil cut or hidden: {dropped['border']} of the dark blob's {n_out} outline "
            f"points lie on the picture's border or next to {_MISSING}, and the rest have no "
            "sharp edge"
        )
    if dropped["glint"] > params.max_boundary_gap * n_out:
        return (
            f"pupil hidden by glints: {dropped['glint']} of the dark blob's {n_out} outline "
            "points lie on glints or their skirts (glint bloom over the pupil's edge?), and "
            "the rest have no sharp edge"
        )
    return "no pupil: the dark blob has no sharp edge"


def fit_blob(img: np.ndarray, wp: WorkPicture, blob: Blob, bright: np.ndarray, params) -> PupilFit:
    """Steps 5–7 for one blob: contrast, outline, sub-pixel edge, robust fit, support."""
    levels = blob_contrast(img, wp, blob, params)
    if not levels:
        return PupilFit(None, reason=levels.reason)
    pupil_level, surround = levels
    pts, dropped = edge_points(blob, img.shape, wp.invalid, params)
    if not pts:
        return PupilFit(None, reason=pts.reason, dropped=dropped)
    x, y = pts
    e = _fit(x, y, blob.diam)
    if e is None:
        return PupilFit(None, reason="no pupil: the dark blob's outline fits no ellipse")
    reach = max(params.refine_reach_px, params.refine_reach_frac * blob.diam)
    xr, yr, ok = _refine_smoothed(img, bright, e, x, y, pupil_level, reach, params)
    dropped["no_edge"] = int((~ok).sum())
    on_glint = _on_mask(blob.near_glint, xr - blob.x0, yr - blob.y0) & ok
    dropped["glint"] += int(on_glint.sum())
    ok &= ~on_glint
    xr, yr = xr[ok], yr[ok]
    if len(xr) < params.min_edge_points:
        return PupilFit(None, reason=_no_edge(blob, dropped, params), dropped=dropped)
    e, inl, sigma = _robust_fit(xr, yr, blob.diam, params)
    if e is None:
        return PupilFit(None, reason="no pupil: the dark blob's outline fits no ellipse")
    passes = params.refine_passes if blob.diam < params.refine_again_below_px else 1
    for _ in range(passes - 1):
        # Again from the fitted ellipse (its normals, the inliers as starts): each point now
        # starts at the edge, so the nearest crossing is the pupil's, not a skirt's or the
        # iris's texture next to where the blob's outline happened to be.
        x2, y2, ok2 = _refine_smoothed(img, bright, e, xr[inl], yr[inl], pupil_level, reach, params)
        ok2 &= ~_on_mask(blob.near_glint, x2 - blob.x0, y2 - blob.y0)
        if ok2.sum() < params.min_edge_points:
            break
        e2, inl2, sigma2 = _robust_fit(x2[ok2], y2[ok2], blob.diam, params)
        if e2 is None:
            break
        e, inl, sigma, xr, yr = e2, inl2, sigma2, x2[ok2], y2[ok2]
    implausible = _implausible(e, params) or _one_sided(img, wp, e, pupil_level, bright, params)
    if implausible:
        return PupilFit(None, reason=implausible, dropped=dropped)
    d = sampson_distance(e, xr[inl], yr[inl])
    dropped["outlier"] = int((~inl).sum())
    span = wp.hi - wp.lo
    support, gap = support_of(e, xr[inl], yr[inl])
    return PupilFit(
        e,
        area_px=blob.area,
        support=support,
        gap=gap,
        residual_px=float(np.sqrt(np.mean(d * d))),
        edge_noise_px=float(sigma),
        edge_level=0.5 * (pupil_level + surround),
        contrast=float((surround - pupil_level) / span),
        n_points=int(inl.sum()),
        dropped=dropped,
        threshold=wp.to_input(blob.level),
        inliers=(xr[inl], yr[inl]),
    )


def _implausible(e: Ellipse, params) -> str | None:
    """Why a fitted ellipse cannot be a pupil, or None: smaller than ``pupil_min_area_px``
    inside its outline ("pupil too small"), or thinner than ``pupil_min_axis_ratio`` (a
    sliver: a black strip of skin beside a lid, a lash, a fold)."""
    fitted_area = math.pi * e.a * e.b
    if fitted_area < params.pupil_min_area_px:
        return (
            f"pupil too small: {fitted_area:.0f} px inside its fitted outline (a pupil "
            f"needs ≥ {params.pupil_min_area_px} px)"
        )
    major, minor = 2 * max(e.a, e.b), 2 * min(e.a, e.b)
    if minor < params.pupil_min_axis_ratio * major:
        return (
            f"no pupil: the dark blob is a sliver, {major:.1f} × {minor:.1f} px (axis ratio "
            f"{minor / major:.2f}; a pupil seen up to "
            f"{math.degrees(math.acos(params.pupil_min_axis_ratio)):.0f}° off its axis has "
            f"≥ {params.pupil_min_axis_ratio:.2f})"
        )
    return None


def _group_medians(vals: np.ndarray, k: np.ndarray, n: int, min_count: int = 3) -> np.ndarray:
    """The median (as :func:`median`) of ``vals`` in each group ``k`` = 0 … n − 1, NaN for a
    group of fewer than ``min_count`` values: one sort by (group, value) for all the groups."""
    if vals.dtype.kind in "iu" and vals.dtype.itemsize <= 2 and len(vals):
        # Integers: counted per group when their range is small (an 8-bit picture's), else one
        # sort of (group, value) packed in an int64 (the same order as the lexsort below, ~3 ×
        # faster): the same middle values either way.
        lo, hi = int(vals.min()), int(vals.max())
        if (hi - lo + 1) * n <= 1 << 16:
            return _group_medians_counted(vals, np.asarray(k, np.int64), n, min_count, lo, hi)
        key = (k.astype(np.int64) << 32) + (vals.astype(np.int64) + 65536)
        sv = ((np.sort(key) & 0xFFFFFFFF) - 65536).astype(np.float64)
    else:
        sv = vals[np.lexsort((vals, k))].astype(np.float64)
    counts = np.bincount(k, minlength=n)
    starts = np.concatenate(([0], np.cumsum(counts)[:-1]))
    hi = starts + counts // 2
    lo = np.where(counts % 2, hi, hi - 1)
    ok = counts >= min_count
    out = np.full(n, np.nan)
    out[ok] = 0.5 * (sv[lo[ok]] + sv[hi[ok]])
    return out


@njit(cache=True, nogil=True)
def _group_medians_counted(vals, k, n, min_count, lo, hi):
    """:func:`_group_medians` of integer ``vals`` in [lo, hi] by counting them per group: each
    group's middle value (or the mean of the middle two, in float64), NaN for fewer than
    ``min_count``."""
    span = hi - lo + 1
    counts = np.zeros((n, span), np.int64)
    for i in range(vals.size):
        counts[k[i], np.int64(vals[i]) - lo] += 1
    out = np.full(n, np.nan)
    for g in range(n):
        c = 0
        for b in range(span):
            c += counts[g, b]
        if c < min_count:
            continue
        r_hi = c // 2
        r_lo = r_hi if c % 2 else r_hi - 1
        v_lo = v_hi = -1
        cum = 0
        for b in range(span):
            cum += counts[g, b]
            if v_lo < 0 and cum > r_lo:
                v_lo = b
            if cum > r_hi:
                v_hi = b
                break
        out[g] = 0.5 * (np.float64(v_lo + lo) + np.float64(v_hi + lo))
    return out


def _one_sided(img, wp: WorkPicture, e: Ellipse, pupil_level: float, bright, params) -> str | None:
    """Why a fitted ellipse is dark on one side only, or None: the ring between
    ``surround_sector_ring`` (1.15–1.5) × the ellipse outside it is cut into
    ``surround_sectors`` (8) equal angles about its centre, and each sector's median (off
    glints and invalid pixels) must exceed the pupil's level by ``surround_sector_min`` (0.3)
    of the whole ring's step. A pupil is surrounded by iris all round (a lid over it is skin,
    brighter still); a dark strip beside a lid or a fold has a dark side."""
    r0, r1 = params.surround_sector_ring
    rows, cols = img.shape
    reach = r1 * max(e.a, e.b) + 2
    # Every s-th pixel each way (≤ ~80 × 80 samples of the box): eight sector medians need a few
    # hundred pixels each, not the thousands of a large pupil's ring.
    s = max(1, int(reach / 40.0))
    x0, x1 = max(0, int(e.cx - reach)), min(cols, int(e.cx + reach) + 2)
    y0, y1 = max(0, int(e.cy - reach)), min(rows, int(e.cy + reach) + 2)
    u, v, ring = _ring_scaled((x0, x1, y0, y1), s, _scaled_args(e), (float(r0), float(r1)))
    ring &= bright[y0:y1:s, x0:x1:s] == 0
    if wp.invalid is not None:
        ring &= ~wp.invalid[y0:y1:s, x0:x1:s]
    if not ring.any():
        return None
    vals = img[y0:y1:s, x0:x1:s][ring]
    step = median(vals) - pupil_level
    if step <= 0:
        return None
    n = params.surround_sectors
    k = ((np.arctan2(v[ring], u[ring]) + math.pi) / (2 * math.pi) * n).astype(int) % n
    meds = _group_medians(vals, k, n)
    meds = meds[np.isfinite(meds)]
    if not len(meds):
        return None
    worst = float(np.min((meds - pupil_level) / step))
    # A dark side is as dark as the blob, near enough: a fold or a strip beside a lid runs on
    # into it. Signals count from the black level (the darkest valid pixel, ``wp.lo``): a
    # darkest sector with over twice the blob's signal is iris, however it compares with the
    # rest of the ring — on a sunlit face the iris in the lid's shadow holds 0.27 of the
    # ring's step over the pupil (vr-offaxis at 850 nm, 1 ms, the sun 40° up: pupil 16 DN,
    # the shadowed iris 30–32 and the lit one ~70 over a black of 14: 8× the pupil's signal).
    lit = float(np.min(meds)) - wp.lo > 2.0 * (pupil_level - wp.lo)
    if worst < params.surround_sector_min and not lit and wp.invalid is not None:
        # A sector's worth (1 / ``surround_sectors``) of the ring missing: the dark side may be
        # the rest of a pupil the missing pixels cut (a valid-area mask across it).
        _, _, whole = _ring_scaled((x0, x1, y0, y1), s, _scaled_args(e), (float(r0), float(r1)))
        lost = np.count_nonzero(whole & wp.invalid[y0:y1:s, x0:x1:s])
        if lost * n >= np.count_nonzero(whole):
            return (
                f"pupil cut or hidden: the dark blob at ({e.cx:.0f}, {e.cy:.0f}) px is dark on "
                f"one side only and {100 * lost / np.count_nonzero(whole):.0f} % of the ring "
                f"around it is {_MISSING}: a pupil cut there?"
            )
    if worst < params.surround_sector_min and not lit:
        return (
            f"no pupil: the dark blob at ({e.cx:.0f}, {e.cy:.0f}) px is dark on one side only "
            f"(its darkest surround sector is {worst:.2f} of the surround's step above it, "
            f"need {params.surround_sector_min:.2f}: a strip beside a lid or a fold?)"
        )
    return None


def _fit_candidates(img, wp, picks, f: int, bright, params, reasons: list[str]):
    """Steps 4–7 on the chosen candidates in turn (at most ``max_candidates``): the first
    fit (its ``stable_from`` its candidate's), or None with each candidate's refusal appended
    to ``reasons``."""
    for cand in picks[: params.max_candidates]:
        blob = full_res_blob(wp, cand, f, bright, params, img)
        if not blob and cand.before is not None:
            # (not compact: perhaps the pupil joined to a region beside it, :func:`_before_jump`)
            alone = full_res_blob(wp, cand.before, f, bright, params, img)
            blob = alone if alone else blob
        if not blob:
            reasons.append(blob.reason)
            continue
        fit = fit_blob(img, wp, blob, bright, params)
        if fit.ellipse is not None:
            fit.stable_from = cand.stable_from
            fit.first = cand.first
            return fit
        reasons.append(fit.reason)
    return None


def _box_about(e: Ellipse, shape: tuple[int, int]) -> tuple[int, int, int, int] | None:
    """(x0, x1, y0, y1): the picture's pixels within the ellipse's reach (its larger semi-axis
    + 1 px) about its centre, clipped to ``shape`` (rows, cols); None when under 3 px either
    way (nothing to look at)."""
    rows, cols = shape
    reach = max(e.a, e.b) + 1
    x0, x1 = max(0, int(e.cx - reach)), min(cols, int(e.cx + reach) + 2)
    y0, y1 = max(0, int(e.cy - reach)), min(rows, int(e.cy + reach) + 2)
    if x1 - x0 < 3 or y1 - y0 < 3:
        return None
    return x0, x1, y0, y1


def _interior(wp: WorkPicture, e: Ellipse, bright: np.ndarray, params, shape):
    """(box (x0, x1, y0, y1), mask over the box) of the pixels inside 0.9 × the ellipse ``e``,
    off the glints ``bright`` grown by their margin and off missing pixels: the interior
    :func:`darker_core` and :func:`_smoothed_bright_core` judge; None when the box is empty or
    fewer than ``pupil_min_area_px`` pixels are left."""
    box = _box_about(e, shape)
    if box is None:
        return None
    x0, x1, y0, y1 = box
    inside = _inside_scaled(box, _scaled_args(e), 0.81)
    glints = bright[y0:y1, x0:x1]
    if glints.any():
        inside &= _grown_glints_box(glints, params)[0] == 0
    if wp.invalid is not None:
        inside &= ~wp.invalid[y0:y1, x0:x1]
    if inside.sum() < params.pupil_min_area_px:
        return None
    return box, inside


class _Interior:
    """A fit's interior as :func:`darker_core` and :func:`_smoothed_bright_core` judge it, each
    part worked out once, when first asked for (both judge the same pixels): ``interior``
    (:func:`_interior`'s box and mask, or None), ``win`` (the input over that box, float32)
    and ``averaged`` (:func:`_box_averages` of ``win`` at :data:`_CORE_BOX` px, or None)."""

    def __init__(self, img: np.ndarray, wp: WorkPicture, e: Ellipse, bright: np.ndarray, params):
        self._img, self._wp, self._e, self._bright, self._params = img, wp, e, bright, params

    @cached_property
    def interior(self):
        return _interior(self._wp, self._e, self._bright, self._params, self._img.shape)

    @cached_property
    def win(self) -> np.ndarray:
        x0, x1, y0, y1 = self.interior[0]
        return self._img[y0:y1, x0:x1].astype(np.float32)

    @cached_property
    def averaged(self):
        return _box_averages(self.win, self.interior[1], self._params)


def darker_core(
    img: np.ndarray, wp: WorkPicture, e: Ellipse, bright: np.ndarray, params, parts=None
) -> str:
    """Why a fitted ellipse holds a darker core (an iris with the pupil inside it), or "".

    Over the pixels inside 0.9 × the ellipse (off glints grown by their margin and missing
    pixels), in the input's units: with b the black level (the darkest valid pixel, ``wp.lo``),
    m the interior's median and p its ``core_quantile`` (5th percentile), a core is there when
    p − b ≤ ``core_max_fraction`` (m − b) and m − p ≥ ``core_min_sigma`` × the interior's pixel
    noise σ (Immerkær's estimate over it, as :func:`noise_sigma`, or over its pixels darker than
    (m + p) / 2 when they are fewer σ — shot noise grows with the signal, and a core is judged
    against its own noise; the step between a core and the rest is a thin edge, which that
    median ignores; ≥ 1 step for an integer picture with under ½ step of noise, whose
    percentiles then move by the step, not the noise). A real pupil is uniform to its noise:
    its 5th percentile is a couple of σ under its median. When
    this finds no core, the interior averaged over 5 × 5 px is looked at again
    (:func:`_smoothed_core`: a pupil only a few σ of the pixel noise darker than its iris).
    ``parts``: the fit's :class:`_Interior`, when the caller has one (made here otherwise)."""
    parts = _Interior(img, wp, e, bright, params) if parts is None else parts
    interior = parts.interior
    if interior is None:
        return ""
    box, inside = interior
    x0, x1, y0, y1 = box
    vals = img[y0:y1, x0:x1][inside]
    black = wp.lo
    m, p = median_and_percentile(vals, params.core_quantile)
    # On the input (the working picture's glints are filled flat, which would hide noise).
    win = parts.win
    if p - black > params.core_max_fraction * (m - black):
        # no core at the black level, whatever the noise (its estimate is not worked out);
        # perhaps one a few σ above it, which only the averaged interior shows, or one too
        # small to move the 5th percentile
        return _smoothed_core(win, inside, e, params, parts) or _small_core(
            win, inside, e, (black, x0, y0, m, wp.hi - wp.lo), img.dtype.kind in "iu", params
        )
    lap = np.abs(cv2.filter2D(win, cv2.CV_32F, _IMMERKAER, borderType=cv2.BORDER_REFLECT)[inside])
    if img.dtype.kind in "iu" and img.itemsize <= 2:
        # Integers (|M * I| ≤ 16 × 65535: exact in float32 and in int32): counted, not sorted.
        lap = lap.astype(np.int32)
    noise = 1.4826 * median(lap) / 6.0
    dark = vals <= 0.5 * (m + p)
    if dark.sum() >= max(params.pupil_min_area_px, 0.02 * vals.size):
        # Shot noise grows with the signal: a dark core is judged against its own noise, not
        # the brighter iris's (a population render's pupil 16 DN at σ 0.5 in an iris 27 DN at
        # σ 1.7 with its texture: 11 DN is 6 σ of the iris, 22 σ of the pupil's own).
        noise = min(noise, 1.4826 * median(lap[dark]) / 6.0)
    # An integer picture's median and percentiles move in whole steps: where its noise is under
    # half a step they, not the noise, set how far apart a uniform pupil's median and 5th
    # percentile can be, and the noise counts as ≥ 1 step (an 8-bit close-up's pupil, median 2
    # DN over black, 5th percentile at it, is uniform; a uniform pupil at 0.3–0.5 DN of noise
    # with 14–20 DN of shading across it, or with glints' flare halos inside it, read as a
    # core 4–8 DN deep: session 32's new user). With ≥ ½ step of noise the percentiles resolve
    # it: a 2.3 mm pupil 16 DN in a dark iris 20–26 DN (its own noise 0.74 DN, the core 7 DN
    # under the median: 9 σ) was answered with the iris as the pupil at a 1-step floor (the
    # 850/940 nm design run at 1 ms; tests/analysis/test_detect_pupil_shot_noise.py).
    if img.dtype.kind in "iu" and noise < 0.5:
        noise = 1.0
    noise = max(noise, 0.5 * (wp.hi - wp.lo) / 255.0)
    if m - p >= params.core_min_sigma * noise:
        return (
            f"pupil merged with iris: the fitted blob at ({e.cx:.0f}, {e.cy:.0f}) px "
            f"({2 * max(e.a, e.b):.0f} × {2 * min(e.a, e.b):.0f} px) has a darker core: its "
            f"{params.core_quantile:g}th percentile is {p - black:.3g} above the black level "
            f"against its median's {m - black:.3g} ({(m - p) / noise:.0f} σ of the noise): the "
            "pupil inside an iris (or a dark fold) it was not told from"
        )
    return _smoothed_core(win, inside, e, params, parts) or _small_core(
        win, inside, e, (black, x0, y0, m, wp.hi - wp.lo), img.dtype.kind in "iu", params
    )


#: :func:`_smoothed_core`'s box (px a side): a core of the least pupil's area (30 px, ~6 px
#: across) keeps its level inside it, and white noise falls 5×.
_CORE_BOX = 5


def _box_averages(win: np.ndarray, inside: np.ndarray, params, k: int = _CORE_BOX):
    """(values, averaged window, mask) of ``win`` (float32) averaged over k (:data:`_CORE_BOX`) px
    boxes, at the boxes wholly ``inside`` (none reaches over the ellipse's 0.9 outline or a
    glint's margin): what :func:`_smoothed_core` and :func:`_smoothed_bright_core` judge. None
    when the window is under two boxes across or fewer than ``pupil_min_area_px`` are left."""
    if min(win.shape) < 2 * k:
        return None
    avg = cv2.blur(win, (k, k), borderType=cv2.BORDER_REFLECT)
    whole = cv2.erode(inside.astype(np.uint8), np.ones((k, k), np.uint8)) > 0
    vals = avg[whole]
    if vals.size < params.pupil_min_area_px:
        return None
    return vals, avg, whole


def _smoothed_core(win: np.ndarray, inside: np.ndarray, e: Ellipse, params, parts=None) -> str:
    """The darker core of :func:`darker_core` looked for again on the interior averaged over
    :data:`_CORE_BOX` × :data:`_CORE_BOX` boxes, or "": a pupil only a few σ of the pixel
    noise darker than its iris (pupil 18, iris 22–28 DN at σ 3: 24 of 24 such pictures were
    answered with the iris as the pupil) is a core of many pixels, which averaging brings out
    of the noise. With b, p and m the averaged interior's 1st percentile, ``core_quantile``
    (5th percentile) and median, a core is there when p − b ≤ ``core_max_fraction`` (m − b)
    and m − p ≥ ``core_min_sigma`` σ, σ the spread of the interior's brighter half
    (median(v − m | v ≥ m) / 0.6745, a normal's): measured on the averaged values themselves,
    so noise that is not white (a JPEG's blocks, a blur) and a smooth shading across a real
    pupil widen σ as they widen the lower tail, and a uniform pupil (its 5th percentile 1.6 σ
    under its median, its 1st 2.3 σ: p − b = 0.3 (m − b)) has no core by either test.

    When the first test finds a darker mode but not the depth, and the fit is wide, both are
    made again on boxes as wide as half the least pupil it can hold (its minor axis / (2 ×
    :data:`_GLINT_REACH`): an iris is at most 6 × its pupil across), odd, if wider than
    :data:`_CORE_BOX`: a pupil in that iris keeps its level in most of its boxes, and white
    noise falls k×. A pupil 10 DN under its iris at σ 6
    (134 px iris, 52 × 44 px pupil) is 7.6 σ under at 5 × 5 px and was answered as the iris;
    at 11 × 11 px it is 16 σ. Shading does not fall with the box, and widens σ with it.
    ``parts``: the :class:`_Interior` ``win`` and ``inside`` are from, whose
    :data:`_CORE_BOX` px averages are taken from it (worked out once a fit), or None."""
    k = _CORE_BOX
    found = _averaged_core(win, inside, params, k, parts)
    if found is None:
        return ""
    m, p, sigma = found
    wide = _odd(min(e.a, e.b) / _GLINT_REACH)
    if m - p < params.core_min_sigma * sigma and wide > _CORE_BOX:
        # (only when the 5 × 5 px averages already hold a separate darker mode, the first
        # test, but not deep enough: a uniform pupil's frames pay nothing more)
        k = wide
        found = _averaged_core(win, inside, params, k)
        if found is None:
            return ""
        m, p, sigma = found
    if m - p < params.core_min_sigma * sigma:
        return ""
    return (
        f"pupil merged with iris: the fitted blob at ({e.cx:.0f}, {e.cy:.0f}) px "
        f"({2 * max(e.a, e.b):.0f} × {2 * min(e.a, e.b):.0f} px) has a darker core: averaged "
        f"over {k} × {k} px its {params.core_quantile:g}th percentile is {m - p:.3g} under its "
        f"median ({(m - p) / sigma:.0f} σ of the averaged values' spread): the pupil inside an "
        "iris it was not told from, only a few σ of the pixel noise darker"
    )


def _averaged_core(win: np.ndarray, inside: np.ndarray, params, k: int, parts=None):
    """:func:`_smoothed_core`'s first test on the interior averaged over k × k px boxes:
    (median, ``core_quantile`` percentile, σ of the brighter half) when that percentile is
    within ``core_max_fraction`` of the way from the 1st percentile to the median (a darker
    mode apart from the rest), else None. The caller judges the depth. ``parts``: as
    :func:`_smoothed_core`'s."""
    if parts is not None and k == _CORE_BOX:
        averaged = parts.averaged
    else:
        averaged = _box_averages(win, inside, params, k)
    if averaged is None:
        return None
    vals = averaged[0]
    b = float_percentiles(vals, 1.0)  # (the least value is the noise's extreme, ~3.5 σ)
    m, p = median_and_percentile(vals, params.core_quantile)
    upper = vals[vals >= m] - m
    sigma = median(upper) / 0.6745 if upper.size else 0.0
    if not sigma > 0 or p - b > params.core_max_fraction * (m - b):
        return None
    return m, p, sigma


#: :func:`_small_core`'s box (px a side): noise falls 3×, and a dark spot keeps over half its
#: depth in the box only when ≥ 5 of its 9 pixels are dark — a dead pixel or two do not.
_SMALL_CORE_BOX = 3


#: :func:`_small_core`'s least depth, as a share of the picture's range (``wp.hi − wp.lo``): a
#: pupil too small to move the interior's 5th percentile is taken for one only where it
#: stands well out of the range (a 2 px pupil 90 DN under a 110 DN iris, 203 DN range: 0.44;
#: a JPEG's ringing in a flattened pupil, 0.06). A 2 px pupil in a dark iris (a few % of the
#: range) is not found by it.
_SMALL_CORE_DEPTH = 0.25


def _small_core(win, inside, e: Ellipse, at: tuple, integer: bool, params) -> str:
    """A darker core too small to move the interior's 5th percentile (:func:`darker_core`), or
    "": a 2 px pupil (~13–20 px of area) inside the iris fitted as the pupil (22 000 px: 0.1 %
    of its interior). On the interior averaged over :data:`_SMALL_CORE_BOX` px boxes (those
    wholly inside), with m its median and σ the spread of its brighter half (as
    :func:`_smoothed_core`; ≥ ⅓ of an integer picture's step), the darkest box is a core when
    it lies within ``core_max_fraction`` of the way from the black level (the darkest valid
    pixel; ``at`` = (black level, the window's first column, its first row, the raw interior's
    median, the picture's range ``wp.hi − wp.lo``)) to m, ≥ ``core_min_sigma`` σ under m and
    ≥ :data:`_SMALL_CORE_DEPTH` of the range under m.
    Over a uniform interior of 10⁵ boxes the darkest is ~4.5 σ under m (Gaussian extreme
    √(2 ln N)), and a real pupil at the black level has m − black of a few σ of its pixel
    noise: neither test passes. The core's area is
    the pixels of the input, around the darkest box, darker than halfway from m to it: under
    ``pupil_min_area_px`` the answer is "pupil too small", else "pupil merged with iris"."""
    k = _SMALL_CORE_BOX
    black, x0, y0, m_raw, span = at
    if min(win.shape) < 2 * k:
        return ""
    box = cv2.blur(win, (k, k), borderType=cv2.BORDER_REFLECT)
    whole = cv2.erode(inside.astype(np.uint8), np.ones((k, k), np.uint8)) > 0
    masked = np.where(whole, box, np.inf)
    r, c = np.unravel_index(int(np.argmin(masked)), masked.shape)
    low = float(masked[r, c])
    # (first against the raw interior's median ``m_raw``, which the boxes' median is within
    # noise of: a real pupil's darkest box is far from the black level, and stops here)
    if not np.isfinite(low) or low - black > params.core_max_fraction * (m_raw - black):
        return ""
    vals = box[whole]
    if vals.size < params.pupil_min_area_px:
        return ""
    m = median(vals)
    upper = vals[vals >= m] - m
    sigma = median(upper) / 0.6745 if upper.size else 0.0
    if integer:
        sigma = max(sigma, 1.0 / k)
    if not sigma > 0 or low - black > params.core_max_fraction * (m - black):
        return ""
    if m - low < max(params.core_min_sigma * sigma, _SMALL_CORE_DEPTH * span):
        # (nor a dip shallower than :data:`_SMALL_CORE_DEPTH` of the range: a JPEG flattens a
        # pupil's noise, σ falls to the integer floor, and its ringing beside a glint dips to
        # the black level, 13 DN under a 16 DN pupil in a 203 DN range at quality 8)
        return ""
    # the core: the pixels darker than halfway from m to the darkest box, connected to it
    dark = ((win < 0.5 * (m + low)) & inside).astype(np.uint8)
    _, lab = cv2.connectedComponents(dark, connectivity=8)
    area = int(np.count_nonzero(lab == lab[r, c])) if dark[r, c] else 0
    where = f"inside the fitted blob at ({e.cx:.0f}, {e.cy:.0f}) px "
    size = f"({2 * max(e.a, e.b):.0f} × {2 * min(e.a, e.b):.0f} px)"
    if area < params.pupil_min_area_px:
        return (
            f"pupil too small: {area} px, a darker core at ({x0 + c}, {y0 + r}) "
            f"{where}{size} — the iris around the pupil (a pupil needs "
            f"≥ {params.pupil_min_area_px} px)"
        )
    return (
        f"pupil merged with iris: the fitted blob at ({e.cx:.0f}, {e.cy:.0f}) px {size} has a "
        f"darker core of {area} px, {(m - low) / sigma:.0f} σ under its median: the pupil "
        "inside an iris it was not told from"
    )


#: :func:`_pupil_inside`'s Gaussian σ (px) for the edge read on a faint pupil: 2 px averages
#: ~50 pixels (white noise falls 7×) and moves no iso-line's centre (module doc, step 5).
_INSIDE_SMOOTH_PX = 2.0


def _pupil_inside(img: np.ndarray, wp: WorkPicture, e: Ellipse, bright: np.ndarray, params):
    """The pupil inside a whole fit that holds a darker core (:func:`darker_core`: a dark iris
    only a few σ of the pixel noise above its pupil, which the ladder could not tell apart), as
    a :class:`PupilFit`, or a :class:`Refusal` naming why the core is not taken for the pupil.

    Inside 0.9 × the iris's ellipse, off glints (grown by their margin) and missing pixels, the
    input is averaged over :data:`_CORE_BOX` × :data:`_CORE_BOX` px (the box of
    :func:`_smoothed_core`, which saw the core; only valid pixels count). With b and m the
    averaged interior's 1st percentile and median, the pixels under ½ (b + m) give the core's
    level c (their median), and the core is the connected piece under ½ (c + m) around the
    darkest box: the half-level iso-line, whose centre no symmetric blur moves. It must not
    reach the 0.9 outline (a shadow or fold along the iris's edge), be compact (solidity ≥
    ``pupil_min_solidity``) and hold ``pupil_min_area_px``. Its edge is then read on the input
    smoothed by a Gaussian of :data:`_INSIDE_SMOOTH_PX` (:func:`_refine_smoothed`) and fitted
    robustly (:func:`_robust_fit`). The step from the core to its surround (a ring as
    :func:`blob_contrast`'s), a difference of medians over N₁ and N₂ pixels, has the standard
    error 1.2533 σ √(1/N₁ + 1/N₂) (a median's efficiency against a mean, π/2), σ the pixel
    noise there (Immerkær's, as :func:`_local_noise`): the pupil is taken when the step is ≥
    ``pupil_min_contrast_sigma`` of that error and ≥ ``pupil_min_contrast`` of the range — a
    40 px disc 2 σ of the pixel noise under its iris stands ~50 standard errors out."""
    got = _core_piece(img, wp, e, bright, params)
    if not got:
        return got
    win, off, near_glint, comp, closed, contour, t, where = got
    x0, y0 = got.origin
    u8 = wp.u8[y0 : y0 + win.shape[0], x0 : x0 + win.shape[1]]
    levels = _core_step(win, u8, wp, (off, comp, closed), where, params)
    if not levels:
        return levels
    pupil_level, surround, step = levels
    pts = contour[:, 0, :].astype(np.float64)
    keep = near_glint[pts[:, 1].astype(int), pts[:, 0].astype(int)] == 0
    x, y = pts[keep, 0] + x0, pts[keep, 1] + y0
    diam0 = math.sqrt(4.0 * cv2.countNonZero(comp) / math.pi)
    e0 = _fit(x, y, diam0) if len(x) >= params.min_edge_points else None
    if e0 is None:
        return Refusal(f"{where} has too few outline points off the glints for an ellipse")
    reach = max(params.refine_reach_px, params.refine_reach_frac * diam0)
    # (the edge at ½ of the way to the iris: on a symmetric blur's profile the half-level
    # crossing is the sharp edge's, so the axes are not narrowed by the added blur)
    smooth = dataclasses.replace(params, refine_smooth_px=_INSIDE_SMOOTH_PX, edge_fraction=0.5)
    xr, yr, ok = _refine_smoothed(img, bright, e0, x, y, pupil_level, reach, smooth)
    ok &= ~_on_mask(near_glint, xr - x0, yr - y0)
    dropped = {"border": 0, "glint": int((~keep).sum()), "no_edge": int((~ok).sum()), "outlier": 0}
    xr, yr = xr[ok], yr[ok]
    fit_e, inl, edge_sigma = (
        _robust_fit(xr, yr, diam0, params)
        if len(xr) >= params.min_edge_points
        else (None, None, 0.0)
    )
    if fit_e is None:
        return Refusal(f"{where} has no sharp edge that fits an ellipse")
    implausible = _implausible(fit_e, params)
    if implausible:
        return Refusal(f"{where}: {implausible}")
    d = sampson_distance(fit_e, xr[inl], yr[inl])
    dropped["outlier"] = int((~inl).sum())
    support, gap = support_of(fit_e, xr[inl], yr[inl])
    return PupilFit(
        fit_e,
        area_px=float(cv2.countNonZero(closed)),
        support=support,
        gap=gap,
        residual_px=float(np.sqrt(np.mean(d * d))),
        edge_noise_px=float(edge_sigma),
        edge_level=0.5 * (pupil_level + surround),
        contrast=float(step / (wp.hi - wp.lo)),
        n_points=int(inl.sum()),
        dropped=dropped,
        threshold=float(t),
        inliers=(xr[inl], yr[inl]),
    )


class _Piece(tuple):
    """:func:`_core_piece`'s result: (window, off, near_glint, comp, closed, contour, level,
    words) with ``origin`` (x0, y0) of the window in the picture."""

    origin: tuple[int, int] = (0, 0)


def _core_piece(img: np.ndarray, wp: WorkPicture, e: Ellipse, bright: np.ndarray, params):
    """:func:`_pupil_inside`'s core: the connected piece of the averaged interior under ½ (c +
    m) around its darkest box, closed, with its outline — a :class:`_Piece` — or a refusal (too
    small, reaching the 0.9 outline, not compact)."""
    box = _box_about(e, img.shape)
    if box is None:
        return Refusal("the iris's fit is too small to look inside")
    x0, x1, y0, y1 = box
    inside = _inside_scaled(box, _scaled_args(e), 0.81)
    off = inside.copy()
    glints = bright[y0:y1, x0:x1]
    near_glint = np.zeros_like(glints)
    if glints.any():
        near_glint = _grown_glints_box(glints, params)[0]
        off &= near_glint == 0
    if wp.invalid is not None:
        off &= ~wp.invalid[y0:y1, x0:x1]
    win = img[y0:y1, x0:x1].astype(np.float32)
    k = _CORE_BOX
    w = off.astype(np.float32)
    num = cv2.blur(win * w, (k, k), borderType=cv2.BORDER_CONSTANT)
    den = cv2.blur(w, (k, k), borderType=cv2.BORDER_CONSTANT)
    usable = off & (den >= 0.5)  # (at least half of its box valid)
    if np.count_nonzero(usable) < 4 * params.pupil_min_area_px:
        return Refusal("too few valid pixels inside it to look for the pupil")
    avg = np.where(usable, num / np.maximum(den, 1e-6), np.inf).astype(np.float32)
    vals = avg[usable]
    b = float_percentiles(vals, 1.0)
    m = median(vals)
    t = 0.5 * (median(vals[vals < 0.5 * (b + m)]) + m)
    dark = ((avg < t) & usable).astype(np.uint8)
    r, c = np.unravel_index(int(np.argmin(avg)), avg.shape)
    _, lab = cv2.connectedComponents(dark, connectivity=8)
    comp = np.where(lab == lab[r, c], 255, 0).astype(np.uint8) if dark[r, c] else dark * 0
    area = cv2.countNonZero(comp)
    where = f"the darker core ({area} px at ({x0 + c}, {y0 + r}))"
    if area < params.pupil_min_area_px:
        return Refusal(
            f"{where} is too small for a pupil (a pupil needs ≥ {params.pupil_min_area_px} px)"
        )
    edge = cv2.dilate((~inside).astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
    if (edge & (comp > 0)).any():
        return Refusal(f"{where} runs to the iris's outline (a shadow or a fold, not a pupil)")
    diam0 = math.sqrt(4.0 * area / math.pi)
    # The glints' pixels (grown by their margin) and missing ones are unknown, not bright: under
    # the core's convex hull they are forgiven (as :func:`_glint_forgiven` does for the ladder's
    # blob). Else the discs of saturated glints on a pupil's edge, grown by their own radius,
    # notch the core (pupil 20, iris 26–30 DN, four glints of 3000 DN: solidity 0.78–0.80,
    # refused; the same pupil with unsaturated glints: 0.9).
    shape = comp
    unseen = inside & ~off
    if unseen.any():
        hull = np.zeros_like(comp)
        cv2.fillConvexPoly(hull, cv2.convexHull(cv2.findNonZero(comp)), 255)
        shape = np.where(unseen & (hull > 0), np.uint8(255), comp)
    closed, contour, solidity = _closed_solidity(shape, _odd(params.closing_kernel_frac * diam0))
    if solidity < params.pupil_min_solidity:
        return Refusal(
            f"{where} is not compact (solidity {solidity:.2f} < {params.pupil_min_solidity:.2f})"
        )
    piece = _Piece((win, off, near_glint, comp, closed, contour, t, where))
    piece.origin = (x0, y0)
    return piece


def _core_step(win: np.ndarray, u8: np.ndarray, wp: WorkPicture, masks, where: str, params):
    """:func:`_pupil_inside`'s contrast: (core's median, surround's, step) in the input's
    units, or a refusal when the step is under ``pupil_min_contrast_sigma`` standard errors of
    a difference of medians or ``pupil_min_contrast`` of the range. ``win`` and ``u8``: the
    window of the input and of the working picture; ``masks``: the window's usable pixels,
    the core and the core closed."""
    off, comp, closed = masks
    diam0 = math.sqrt(4.0 * cv2.countNonZero(comp) / math.pi)
    ring_in = max(2, int(round(0.05 * diam0)))
    ring_out = ring_in + max(2, int(round(0.05 * diam0)))
    dist = cv2.distanceTransform(cv2.bitwise_not(closed), cv2.DIST_L2, 3)
    ring = (dist > ring_in) & (dist <= ring_out) & off
    core = (comp > 0) & off
    n1, n2 = int(np.count_nonzero(core)), int(np.count_nonzero(ring))
    if n1 < params.pupil_min_area_px or n2 < params.pupil_min_area_px:
        return Refusal(f"{where} has too few pixels off the glints to measure its contrast")
    pupil_level, surround = median(win[core]), median(win[ring])
    span = wp.hi - wp.lo
    sigma = max(_local_noise(u8, core, ring), 0.5) * span / 255.0
    err = 1.2533 * sigma * math.sqrt(1.0 / n1 + 1.0 / n2)
    step = surround - pupil_level
    if step < params.pupil_min_contrast_sigma * err or step < params.pupil_min_contrast * span:
        return Refusal(
            f"{where} is only {step / err:.1f} standard errors ({100 * step / span:.1f} % of the "
            f"range) darker than its surround (need {params.pupil_min_contrast_sigma:.0f} and "
            f"{100 * params.pupil_min_contrast:.0f} %)"
        )
    return pupil_level, surround, step


def bright_core(img: np.ndarray, wp: WorkPicture, e: Ellipse, params) -> str:
    """Why a fitted dark blob is the iris around a bright pupil (a bright-pupil picture), or "".

    Over the pixels inside 0.9 × the ellipse (missing pixels left out), in the input's units,
    with d the interior's ``core_quantile`` (5th percentile, the blob's dark level) and h the
    picture's bright level (``wp.hi``, its 99th percentile): the pixels brighter than halfway
    from d to h, the connected piece with its centroid nearest the ellipse's centre. It is a
    lit pupil, not a glint, when its centroid is inside half the ellipse, it fills ≥ ½ of its
    box and it is larger than any glint the detector takes (``glint_max_area_frac`` of the
    picture, or ``glint_max_pupil_frac`` of the blob: :func:`_glints_beside`) and than
    ``pupil_min_area_px``. On-axis light makes the pupil glow inside its iris; the working
    picture fills it as a glint, and the iris with the glow filled fits as the pupil."""
    rows, cols = img.shape
    box = _box_about(e, img.shape)
    if box is None:
        return ""
    x0, x1, y0, y1 = box
    inside = _inside_scaled(box, _scaled_args(e), 0.81)
    if wp.invalid is not None:
        inside &= ~wp.invalid[y0:y1, x0:x1]
    if inside.sum() < params.pupil_min_area_px:
        return ""
    win = img[y0:y1, x0:x1]
    d = percentile(win[inside], params.core_quantile)
    if not wp.hi > d:
        return ""
    lit = inside & (win > 0.5 * (d + wp.hi))
    limit = max(
        params.pupil_min_area_px,
        min(
            params.glint_max_area_frac * rows * cols,
            params.glint_max_pupil_frac * math.pi * e.a * e.b,
        ),
    )
    piece = _central_piece(lit, box, e, limit)  # (none when a real pupil holds its glints)
    if piece is None:
        return ""
    area, cx, cy = piece
    return (
        f"a bright core of {area} px at ({cx:.0f}, {cy:.0f}) inside the dark blob at "
        f"({e.cx:.0f}, {e.cy:.0f}) px ({2 * max(e.a, e.b):.0f} × {2 * min(e.a, e.b):.0f} px), "
        "larger than any glint: a lit pupil in its iris"
    )


def _smoothed_bright_core(
    img: np.ndarray, wp: WorkPicture, e: Ellipse, bright: np.ndarray, params, parts=None
) -> str:
    """:func:`bright_core` for a lit pupil only a little brighter than its iris, or "".

    A bright pupil 5–40 DN over a 60–110 DN iris (σ 3) lies under :func:`bright_core`'s
    level, halfway from the blob's dark level to the picture's bright one (sclera, skin):
    the iris with the lit pupil inside was answered as the pupil. Here, as
    :func:`_smoothed_core` mirrored: the interior inside 0.9 × the ellipse, off the glints
    grown by their margin and missing pixels, averaged over :data:`_CORE_BOX` px boxes (those
    wholly inside), with m its median, q its (100 − ``core_quantile``)th percentile (95th)
    and t its 99th; σ the spread of its darker half (median(m − v | v ≤ m) / 0.6745: measured
    on the averaged values, so a JPEG's blocks or a blur widen it as they widen the tail). A
    bright core is there when q − m ≥ ``core_min_sigma`` σ and t − q ≤ ``core_max_fraction``
    (t − m) (a plateau: many pixels near the top, not a tail of ringing or one bright spot);
    it is a lit pupil when the piece brighter than (m + q) / 2 nearest the centre has its
    centroid inside half the ellipse, fills ≥ ½ of its box and is larger than any glint (as
    :func:`bright_core`). A dark pupil is uniform to its noise: its 95th percentile is
    ~1.6 σ over its median. ``parts``: as :func:`darker_core`'s."""
    parts = _Interior(img, wp, e, bright, params) if parts is None else parts
    if parts.interior is None:
        return ""
    box = parts.interior[0]
    k = _CORE_BOX
    averaged = parts.averaged
    if averaged is None:
        return ""
    vals, avg, whole = averaged
    m = median(vals)
    q, t = float_percentiles(vals, [100.0 - params.core_quantile, 99.0])
    lower = m - vals[vals <= m]
    sigma = median(lower) / 0.6745 if lower.size else 0.0
    if img.dtype.kind in "iu":
        # (an integer picture blurred smooth rounds its iris to one value: σ 0 of the
        # averages; ≥ 1 / k of a step, as :func:`_small_core`'s floor)
        sigma = max(sigma, 1.0 / k)
    if not sigma > 0 or q - m < params.core_min_sigma * sigma:
        return _small_bright_core(avg, whole, box, e, m, sigma, params)
    if t - q > params.core_max_fraction * (t - m):
        return _small_bright_core(avg, whole, box, e, m, sigma, params)
    rows, cols = img.shape
    limit = max(
        params.pupil_min_area_px,
        min(
            params.glint_max_area_frac * rows * cols,
            params.glint_max_pupil_frac * math.pi * e.a * e.b,
        ),
    )
    piece = _central_piece(whole & (avg > 0.5 * (m + q)), box, e, limit)
    if piece is None:
        return ""
    area, cx, cy = piece
    return (
        f"a core of {area} px at ({cx:.0f}, {cy:.0f}) brighter than the dark blob at "
        f"({e.cx:.0f}, {e.cy:.0f}) px ({2 * max(e.a, e.b):.0f} × {2 * min(e.a, e.b):.0f} px) "
        f"around it by {q - m:.3g} ({(q - m) / sigma:.0f} σ of the {k} × {k} px averages), "
        "larger than any glint: a lit pupil in its iris"
    )


#: :func:`_small_bright_core`'s least lit pupil, as a share of the interior it is looked for
#: in: a pupil ≥ 2 mm across in an iris ≤ 12.5 mm (Atchison & Smith, *Optics of the Human
#: Eye*, 2000: pupil 2–8 mm, visible iris 11–12.5 mm) is ≥ (2 / 12.5)² = 2.6 % of the iris's
#: disc and ≥ 3.2 % of the 0.9 × interior; 2 % leaves room for a fit a little larger than
#: the iris.
_SMALL_LIT_SHARE = 0.02


def _small_bright_core(avg, whole, box, e: Ellipse, m: float, sigma: float, params) -> str:
    """A lit pupil too small to move the averaged interior's 95th percentile
    (:func:`_smoothed_bright_core`), or "": a bright pupil 10–30 DN over its iris, 15 px in
    radius in an 85 px iris (4 % of the interior), was answered as the iris (46 of 108 made-up
    bright pupils, session 26).

    On the averaged window ``avg`` at the boxes ``whole`` (off glints, their margin and
    missing pixels: :func:`_box_averages`), with m their median and σ the spread of their
    darker half (the caller's) and T their 99th percentile (inside any plateau of ≥ 1 % of
    the boxes; a glint's skirt reaching past its margin is fewer boxes): a lit pupil when
    T − m ≥ ``core_min_sigma`` σ and the piece of boxes brighter than (m + T) / 2 that
    :func:`_central_piece` picks (centroid inside half the ellipse, filling ≥ ½ of its box)
    (i) holds ≥ :data:`_SMALL_LIT_SHARE` of the boxes and ≥ ``pupil_min_area_px``; (ii) is a
    plateau — its 95th percentile P and median M have P − M ≤ ``core_max_fraction`` (P − m)
    (a disc's top is flat to its noise: P − M ≈ 1.6 σ, ≤ 0.17 (P − m) at 8 σ; a Gaussian
    spot's values above its half height spread from ½ to 1 of its peak: 0.27). Over a
    uniform interior of 10⁴–10⁵ boxes the 99th percentile is 2.3 σ over m: under 8 σ."""
    vals = avg[whole]
    if not sigma > 0 or vals.size < params.pupil_min_area_px:
        return ""
    top = float_percentiles(vals, 99.0)
    if top - m < params.core_min_sigma * sigma:
        return ""
    limit = max(params.pupil_min_area_px, _SMALL_LIT_SHARE * vals.size)
    found = _central_piece(whole & (avg > 0.5 * (m + top)), box, e, limit, own=True)
    if found is None:
        return ""
    area, cx, cy, own = found
    big, mid = float_percentiles(avg[own], [95.0, 50.0])
    if big - mid > params.core_max_fraction * (big - m):
        return ""
    return (
        f"a core of {area} px at ({cx:.0f}, {cy:.0f}) brighter than the dark blob at "
        f"({e.cx:.0f}, {e.cy:.0f}) px ({2 * max(e.a, e.b):.0f} × {2 * min(e.a, e.b):.0f} px) "
        f"around it by {mid - m:.3g} ({(mid - m) / sigma:.0f} σ of the {_CORE_BOX} × "
        f"{_CORE_BOX} px averages), a flat top of {100 * area / vals.size:.0f} % of "
        "the interior: a lit pupil in its iris"
    )


def _central_piece(mask: np.ndarray, box, e: Ellipse, limit: float, own: bool = False):
    """(area px, centroid x, centroid y in picture px) of the first connected piece of
    ``mask`` (over ``box``) with its centroid inside half the ellipse ``e``, filling ≥ ½ of
    its bounding box and larger than ``limit`` px, or None; with ``own``, the piece's mask
    (over ``box``) too."""
    lit = mask.astype(np.uint8)
    if cv2.countNonZero(lit) <= limit:
        return None
    n, labels, stats, cent = cv2.connectedComponentsWithStats(lit, connectivity=8)
    central = _inside_scaled(box, _scaled_args(e), 0.25)
    for i in range(1, n):
        bw, bh, area = (int(v) for v in stats[i][2:])
        cx, cy = cent[i]
        if area > limit and area >= 0.5 * bw * bh and central[int(round(cy)), int(round(cx))]:
            if own:
                return area, box[0] + cx, box[2] + cy, labels == i
            return area, box[0] + cx, box[2] + cy
    return None


def _inner_core(img: np.ndarray, wp: WorkPicture, e: Ellipse, bright: np.ndarray, params) -> str:
    """Why a whole fit is not the pupil for what it holds, or "": a bright core larger than any
    glint (:func:`bright_core`: "no dark pupil: bright-pupil image?") or a darker core
    (:func:`darker_core`)."""
    lit = bright_core(img, wp, e, params)
    if lit:
        return f"no dark pupil: bright-pupil image? ({lit})"
    parts = _Interior(img, wp, e, bright, params)
    lit = _smoothed_bright_core(img, wp, e, bright, params, parts)
    if lit:
        return f"no dark pupil: bright-pupil image? ({lit})"
    return darker_core(img, wp, e, bright, params, parts)


def _darker_first(img, wp: WorkPicture, got, fit: PupilFit | None, bright, params):
    """``fit``, or the finer ladder's (:func:`_finer`) when a darker chain gave none
    (:func:`_darker_start`; ``got`` = (the reduced picture, the chains, f)).

    A chain of a pupil's size that began in the ladder's first levels, far darker than the
    fitted blob, and gave no fit: it never settled (it joined the iris one or two levels up)
    or its stable blob, higher up, was the iris (refused as not compact). A pupil at the
    black level in a dark iris, beside bright skin and sunlit lashes that set the levels'
    spacing (vr-offaxis at 940 nm in sunlight: a lash's shadow on the lid fitted whole
    instead, 130–160 px off). The finer ladder over that dark end (as for a first pass with
    nothing whole) is tried first: its whole fit is the darkest stable blob that the first
    ladder, finer, would have chosen — unless it lies off every glint of a picture that has
    some, as in :func:`_fit_chosen` (a mole on the skin darker than the pupil, passed over
    there, is the finer ladder's darkest), or has none about it where ``fit`` has (a dark
    spot beside the pupil the glints are about; :func:`_glints_about`)."""
    reduced, chains, f = got
    if fit is None or not _darker_start(chains, fit, wp, f, params):
        return fit
    again = _finer(img, wp, reduced, f, bright, params)
    if again is None or _off_the_glints(again.ellipse, bright):
        return fit
    if (
        _whole(fit, params)
        and fit.residual_px <= _residual_limit(fit.ellipse, params)
        and _glints_about(fit.ellipse, bright)
        and not _glints_about(again.ellipse, bright)
    ):
        # a dark spot beside a pupil that fits well and that the glints are about (a 10 DN
        # disc 60 px across on the skin or the iris of the tests' picture, 100–160 px from its
        # pupil): not taken
        return fit
    return again


def _residual_limit(e: Ellipse, params) -> float:
    """The limit on a fit's RMS residual (px) beyond which its outline is not an ellipse
    (``detect._pupil_result``'s refusal, :func:`_darker_first`'s well-fitting fit):
    ``max_fit_residual_px`` or ``max_fit_residual_frac`` of the smaller semi-axis, whichever
    is larger."""
    return max(params.max_fit_residual_px, params.max_fit_residual_frac * min(e.a, e.b))


def _glints_about(e: Ellipse, bright: np.ndarray, reach: float = 1.5) -> bool:
    """Whether a glint pixel of ``bright`` (uint8 0/255) lies within ``reach`` × the ellipse's
    larger semi-axis of its centre (a square window); 1.5: on the pupil or at its edge."""
    rows, cols = bright.shape
    r = reach * max(e.a, e.b)
    x0, x1 = max(0, int(e.cx - r)), min(cols, int(e.cx + r) + 1)
    y0, y1 = max(0, int(e.cy - r)), min(rows, int(e.cy + r) + 1)
    return x1 > x0 and y1 > y0 and cv2.countNonZero(bright[y0:y1, x0:x1]) > 0


#: :func:`_darker_start`: the least share of the fitted blob's area a darker chain's largest
#: blob must reach to be worth the finer ladder (a pupil instead of the fit, not a speck)
_DARKER_SHARE = 0.2


def _darker_start(chains: list[list[Candidate]], fit: PupilFit, wp, f: int, params) -> bool:
    """Whether another chain than ``fit``'s (:attr:`PupilFit.first`) starts within the ladder's
    first ``ladder_fine_span`` levels — the span :func:`_finer` walks again — darker than the
    fitted blob's threshold by ``pupil_min_contrast_sigma`` σ of the picture's noise (levels
    and σ in the working picture's 8-bit units), with a blob of at least :data:`_DARKER_SHARE`
    of the fitted ellipse's area π a b / f² (the ladder's grid, reduced by ``f``): a pupil that
    could be answered instead of the fit. The design run's pupils at the black level (persons
    0–4, 150 frames) reached 0.24–1.6 of the blob fitted instead (a lash's or the lid's
    shadow); the dark specks at the black level of the headset frames (openeds: lashes, 2–12
    reduced px) ≤ 0.13 of the pupil fitted, and each cost a finer ladder (~5 ms of the
    frame's ~12) that found nothing."""
    if params.ladder_fine <= 1 or not math.isfinite(fit.threshold) or wp.hi <= wp.lo:
        return False
    level = 255.0 * (fit.threshold - wp.lo) / (wp.hi - wp.lo)
    top = level - params.pupil_min_contrast_sigma * wp.noise
    least = _DARKER_SHARE * math.pi * fit.ellipse.a * fit.ellipse.b / (f * f)
    return any(
        ch[0].index < params.ladder_fine_span
        and ch[0].level < top
        and ch[0].seed != fit.first
        and max(c.area for c in ch) >= least
        for ch in chains
    )


def _finer(img: np.ndarray, wp: WorkPicture, reduced, f: int, bright: np.ndarray, params):
    """:func:`find_pupil`'s second pass, the ladder's dark end again ``ladder_fine`` × finer:
    its fit when whole by the stricter ``ladder_fine_support`` with no darker core, else None."""
    if params.ladder_fine <= 1:
        return None
    # Held to a stricter support than the first pass (``ladder_fine_support``): a finer
    # level can pick a lid-cut pupil's darkest core, whose outline passes the usual
    # support with the centre over a pixel off (paper2005 at (−30°, −20°)).
    strict = dataclasses.replace(
        params,
        min_boundary_support=params.ladder_fine_support,
        max_boundary_gap=1.0 - params.ladder_fine_support,
    )
    again, _, _ = ladder(wp, params, reduced, fine=params.ladder_fine)
    picks2 = choose(again, f, ([], tuple), wp, params)
    fit2 = _fit_candidates(img, wp, picks2, f, bright, params, []) if picks2 else None
    if (
        fit2 is not None
        and _whole(fit2, strict)
        and not _inner_core(img, wp, fit2.ellipse, bright, params)
    ):
        return fit2
    return None


def _small_pupil(img: np.ndarray, invalid, bright: np.ndarray, f: int, params) -> PupilFit | None:
    """A pupil too small for the ladder's reduced picture, or None: the ladder again at full
    resolution, when it was reduced (f > 1), keeping only a whole fit (``_whole``, no darker
    core) under ``small_pupil_axes`` × f px across. The reduced ladder resolves a pupil of ≥ ~3 f
    px (3 reduced px, smoothed by σ 1 px); a smaller one (eyetrackvr's 4 mm pupil seen by a
    130° lens at 240 × 240: ~9 px, f = 3) merges there with the iris around it, whose fit then
    has it as a darker core, or with a dark fold. Only bright blobs that could be glints on
    such a pupil (≤ ``glint_max_pupil_frac`` of its largest area) are filled in its working
    picture: a patch of saturated skin beside it, filled with the dark around it, would join
    it. Larger pupils are left to the reduced ladder (a full-resolution ladder on real
    close-ups, whose pupils are 30–80 px, answered wrong)."""
    if f <= 1 or params.small_pupil_axes <= 0:
        return None
    largest = math.pi / 4.0 * (params.small_pupil_axes * f) ** 2
    glints = _glints_beside(bright, largest, params)
    wp = work_picture(img, invalid, glints, params)
    if not wp:
        return None
    full = dataclasses.replace(params, ladder_rows=float(min(img.shape)))
    reduced = _reduced(wp, full)
    if reduced[1] is not None and reduced[1].all():
        return None
    chains, _, _ = ladder(wp, full, reduced)
    picks = choose(chains, 1, ([], tuple), wp, full)
    if not picks:
        return None
    picks = [c for c in picks if c.area <= largest]
    fit = _fit_candidates(img, wp, picks, 1, glints, full, []) if picks else None
    if (
        fit is None
        or not _whole(fit, params)
        or 2 * max(fit.ellipse.a, fit.ellipse.b) > params.small_pupil_axes * f
        or _inner_core(img, wp, fit.ellipse, glints, params)
    ):
        return None
    return fit


#: :func:`_small_beside`'s gate, in the fit's larger semi-axes: how far the glints' middle may
#: lie from a whole fit's centre before a small pupil nearer it is looked for (a guess: a
#: pupil's glints ring the cornea about it; the spots of session 30's new user lay 1.7–3.3)
_GLINTS_MIDDLE_REACH = 1.5


def _small_beside(img, invalid, bright, f: int, fit: PupilFit, params) -> PupilFit | None:
    """A small pupil (:func:`_small_pupil`) answered instead of a whole fit ``fit``, or None.

    The reduced ladder (f > 1) mixes a pupil a few reduced px across with the iris about it:
    a 20 px pupil at 30 DN in an iris at 170, reduced 6×, looks lighter than a 30 px spot at
    60 DN beside it, whose whole fit, with glints about it, was answered (session 30's new
    user: 35–58 px off, `ok`). Looked for only where the glints' middle (the per-axis median
    of their blobs' centroids) lies beyond :data:`_GLINTS_MIDDLE_REACH` × the fit's larger
    semi-axis from its centre and something darker than the fit's inside lies about it
    (:func:`_darker_about`); taken only when it is whole, nearer that middle
    (:func:`_nearer_the_glints`) and darker inside (:func:`_inside_median`, input units) than
    the fit."""
    if f <= 1 or not cv2.countNonZero(bright):
        return None
    e = fit.ellipse
    mx, my = _glints_middle(bright, e)
    if mx is None or math.hypot(e.cx - mx, e.cy - my) <= _GLINTS_MIDDLE_REACH * max(e.a, e.b):
        return None
    level = _inside_median(img, e, invalid)
    if not _darker_about(img, invalid, bright, (mx, my), e, level):
        return None  # (the full-resolution ladder costs ~1.7 ms: only where it may find one)
    small = _small_pupil(img, invalid, bright, f, params)
    if (
        small is None
        or not _whole(small, params)
        or not _nearer_the_glints(small.ellipse, e, bright)
        or not _inside_median(img, small.ellipse, invalid) < level
    ):
        return None
    return small


def _darker_about(img, invalid, bright, middle: tuple, e: Ellipse, level: float) -> bool:
    """Whether the picture's 5th percentile over the valid pixels within half the distance
    from ``middle`` (the glints' middle, px) to ``e``'s centre, off ``e`` grown by 2 px and off
    the glints, is under ``level`` (input units): something darker than the fit's inside lies
    about the glints' middle."""
    rows, cols = img.shape
    mx, my = middle
    r = 0.5 * math.hypot(e.cx - mx, e.cy - my)
    x0, x1 = max(0, int(mx - r)), min(cols, int(mx + r) + 1)
    y0, y1 = max(0, int(my - r)), min(rows, int(my + r) + 1)
    if x1 <= x0 or y1 <= y0:
        return False
    # (a row and a column of coordinates broadcast: the same numbers as over a grid of them)
    xx = np.arange(x0, x1, dtype=np.float64)[None, :]
    yy = np.arange(y0, y1, dtype=np.float64)[:, None]
    keep = ((xx - mx) ** 2 + (yy - my) ** 2 <= r * r) & (bright[y0:y1, x0:x1] == 0)
    s_, q_ = e.local(xx, yy)
    keep &= (s_ / (e.a + 2.0)) ** 2 + (q_ / (e.b + 2.0)) ** 2 > 1.0
    if invalid is not None:
        keep &= ~invalid[y0:y1, x0:x1]
    vals = img[y0:y1, x0:x1][keep]
    if vals.size == 0:
        return False
    # np.percentile(vals, 5)'s value, without its overhead (~0.1 ms)
    p5 = float_percentiles(vals, 5.0) if vals.dtype.kind == "f" else percentile(vals, 5.0)
    return float(p5) < level


def _glints_middle(bright: np.ndarray, *ellipses: Ellipse) -> tuple:
    """The glints' middle: the per-axis median (px) of the centroids of ``bright``'s blobs
    (uint8 0/255, 8-connected) within :data:`_GLINT_REACH` × each ellipse's larger semi-axis
    of its centre (square windows), or (None, None) without one. The blobs are labelled
    within the box about the glint pixels only (``cv2.boundingRect``): the same blobs as over
    the windows, at a fraction of the cost (a whole 640 × 400 window took ~1.2 ms)."""
    rows, cols = bright.shape
    boxes = []
    for el in ellipses:
        r = _GLINT_REACH * max(el.a, el.b)
        x0, x1 = max(0, int(el.cx - r)), min(cols, int(el.cx + r) + 1)
        y0, y1 = max(0, int(el.cy - r)), min(rows, int(el.cy + r) + 1)
        if x1 > x0 and y1 > y0:
            boxes.append((x0, x1, y0, y1))
    if not boxes:
        return None, None
    if len(boxes) == 1:  # (one window: read in place, no picture-sized mask)
        x0, x1, y0, y1 = boxes[0]
        mask, ox, oy = np.ascontiguousarray(bright[y0:y1, x0:x1]), x0, y0
    else:
        mask, ox, oy = np.zeros_like(bright), 0, 0
        for x0, x1, y0, y1 in boxes:
            mask[y0:y1, x0:x1] = bright[y0:y1, x0:x1]
    bx, by, bw, bh = cv2.boundingRect(mask)
    if bw == 0 or bh == 0:
        return None, None
    n, _, _, centroids = cv2.connectedComponentsWithStats(
        np.ascontiguousarray(mask[by : by + bh, bx : bx + bw]), connectivity=8
    )
    if n <= 1:
        return None, None
    mx, my = np.median(centroids[1:], axis=0)
    return float(mx) + bx + ox, float(my) + by + oy


def _inside_median(img: np.ndarray, e: Ellipse, invalid) -> float:
    """The median of the picture (input units) over the valid pixels inside ``e`` shrunk to
    0.7 of its axes (off its blurred edge); +inf where none is."""
    rows, cols = img.shape
    ax, bx_ = max(1, int(0.7 * e.a)), max(1, int(0.7 * e.b))
    r = max(ax, bx_) + 1
    cx, cy = int(round(e.cx)), int(round(e.cy))
    x0, x1 = max(0, cx - r), min(cols, cx + r + 1)
    y0, y1 = max(0, cy - r), min(rows, cy + r + 1)
    if x1 <= x0 or y1 <= y0:
        return math.inf
    mask = np.zeros((y1 - y0, x1 - x0), np.uint8)
    cv2.ellipse(mask, (cx - x0, cy - y0), (ax, bx_), math.degrees(e.theta), 0, 360, 255, -1)
    inside = mask > 0
    if invalid is not None:
        inside &= ~invalid[y0:y1, x0:x1]
    return median(img[y0:y1, x0:x1][inside]) if inside.any() else math.inf


def _whole(fit: PupilFit, params) -> bool:
    """Whether a fit's outline is backed enough to be trusted (``detect``'s support check)."""
    return fit.support >= params.min_boundary_support and fit.gap <= params.max_boundary_gap


def _core_answer(img, wp: WorkPicture, e: Ellipse, core: str, bright, params) -> PupilFit:
    """A whole fit ``e`` that holds a darker core (``core``, :func:`_inner_core`'s words): the
    core itself, looked for inside it with the noise averaged out (:func:`_pupil_inside`), when
    its fit is whole and holds no core itself; else a refusal naming the core and why it was
    not taken for the pupil."""
    inner = _pupil_inside(img, wp, e, bright, params)
    if inner and _whole(inner, params) and not _inner_core(img, wp, inner.ellipse, bright, params):
        return inner
    why = inner.reason if not inner else "its fit is not whole or holds a darker core itself"
    return PupilFit(None, reason=f"{core}; looked for inside it, {why}")


#: How far from a pupil its glints may lie, in its larger semi-axes: corneal reflections fall
#: on the cornea, whose visible disc (the iris, ~12 mm across) is ≤ 6 × the least pupil (2 mm).
_GLINT_REACH = 6.0
#: :func:`_fit_chosen`'s reach, in larger semi-axes: a whole fit with no glint within it (a
#: square window, as :func:`_glints_about`) gives way to another chosen candidate with glints
#: about it. A guess between the tests' pictures (glints 0.5 semi-axes from the pupil's
#: centre; the nearest 3.7–6.4 semi-axes from the dark spots' centres of
#: tests/analysis/test_detect_pupil_dark_spot.py) and :data:`_GLINT_REACH`'s 6 (a 2 mm
#: pupil's glints may lie 6 mm out: past 3 such a pupil is kept unless another dark blob with
#: glints about it was chosen too); no answer changed on session 29's 316 pictures (the 255
#: real ones among them).
_AWAY_REACH = 3.0


def _off_the_glints(e: Ellipse, bright: np.ndarray) -> bool:
    """Whether the picture has glints (``bright``, uint8 0/255) but none within
    :data:`_GLINT_REACH` × the ellipse's larger semi-axis of its centre (a square window): a
    dark spot off the eye (a mole on the skin), not the pupil the lights shine beside."""
    return not _glints_about(e, bright, _GLINT_REACH) and cv2.countNonZero(bright) > 0


def _fit_chosen(img, wp: WorkPicture, got, bright, params, reasons: list[str]):
    """The chosen candidates fitted in turn (:func:`_fit_candidates`; ``got`` = (the reduced
    picture, the picks, f)): the fit, or None (the candidates' refusals in ``reasons``).

    When every one was refused, the ladder again walked past their chains (``passed``) and its
    new candidates fitted: the ladder stops once the darkest chain has settled, and the darkest
    may be a lash over the sclera (a thin dark stroke, compact once reduced, not at full
    resolution) while the pupil's chain, a few levels brighter, has not: it was never a
    candidate. And when the fit lies off every glint of a picture that has some
    (:func:`_off_the_glints`: a mole on the skin darker than the pupil), the first of the
    other candidates and of those walked past whose fit is whole, holds no core and has
    glints beside it replaces it. A whole fit in reach of the glints but with none within
    :data:`_AWAY_REACH` of its semi-axes gives way, the same way, to the first other chosen
    candidate (not those walked past) whose fit has glints about it (:func:`_glints_about`)."""
    reduced, picks, f = got
    if not picks:
        return None
    fit = _fit_candidates(img, wp, picks, f, bright, params, reasons)
    # ``away``: a whole fit in reach of the glints (not :func:`_off_the_glints`) with none within
    # :data:`_AWAY_REACH` × its larger semi-axis — a dark spot a few of its own sizes from the
    # eye, darker than the pupil (a black disc 80 px across on the skin of the tests' picture,
    # 260 px from its pupil; one 36–40 px across in the iris, 90 px away) — gives way to the
    # first other chosen candidate whose blob has glints about it (:func:`_glints_about`,
    # within 1.5 × its half-size; its box, before any fit: a small pupil with its glints
    # further out costs no fit) and whose whole fit has them about it and holds no core.
    off = fit is not None and _off_the_glints(fit.ellipse, bright)
    away = (
        fit is not None
        and not off
        and _whole(fit, params)
        and not _glints_about(fit.ellipse, bright, _AWAY_REACH)
    )
    if fit is not None and not off and not away:
        return fit
    passed = frozenset(c.first for c in picks)
    if fit is None:
        more, f2 = _walked_past(wp, params, reduced, passed)
        return _fit_candidates(img, wp, more, f2, bright, params, []) if more else None

    def others():
        yield from ((c, f) for c in picks if c.first != fit.first)
        if away:  # (the other picks only: the second walk costs ~1 ms on a small pupil whose
            return  # glints lie further out, the commoner case, and found nothing there)
        more, f2 = _walked_past(wp, params, reduced, passed)
        yield from ((c, f2) for c in more)

    tried = 0
    for cand, fc in others():
        if tried >= params.max_candidates:
            break
        if away and not _box_glints_about(cand, fc, bright):
            continue
        tried += 1
        alt = _fit_candidates(img, wp, [cand], fc, bright, params, [])
        if (
            alt is not None
            and _whole(alt, params)
            and not _off_the_glints(alt.ellipse, bright)
            and (not away or _glints_about(alt.ellipse, bright))
            and (not away or _nearer_the_glints(alt.ellipse, fit.ellipse, bright))
            and not _inner_core(img, wp, alt.ellipse, bright, params)
        ):
            return alt
    return fit


def _nearer_the_glints(e: Ellipse, other: Ellipse, bright: np.ndarray) -> bool:
    """Whether ellipse ``e``'s centre lies nearer than ``other``'s to the glints' middle: the
    per-axis median of the centroids of ``bright``'s blobs (uint8 0/255, 8-connected) within
    :data:`_GLINT_REACH` × either's larger semi-axis (square windows). The LEDs' reflections
    ring the cornea, whose centre the pupil lies near (≲ 2 of its radii at 30° of gaze); a
    dark spot beside one glint of a ring that lies wider about the pupil (glints 3.5 pupil
    radii out, a spot 25 px across just past one: session 29's new user) has them all on one
    side (:func:`_glints_middle`). Pixels: the picture's, x right, y down. Known limit
    (README's Open list): a disc darker than the pupil at that middle, with the pupil 2 of its
    radii off it, is kept — the same picture as session 29's with the roles swapped."""
    mx, my = _glints_middle(bright, e, other)
    if mx is None:
        return False
    return math.hypot(e.cx - mx, e.cy - my) < math.hypot(other.cx - mx, other.cy - my)


def _walked_past(wp: WorkPicture, params, reduced, passed: frozenset) -> tuple[list, int]:
    """:func:`_fit_chosen`'s second walk: the ladder again past the chains ``passed`` (their
    first seeds) and the new candidates it chooses, with its reduction f."""
    chains, f2, _ = ladder(wp, params, reduced, passed=passed)
    more = choose(chains, f2, ([], tuple), wp, params)
    return [c for c in more or [] if c.first not in passed], f2


def _box_glints_about(c: Candidate, f: int, bright: np.ndarray) -> bool:
    """:func:`_glints_about` for a candidate's blob before its fit: a glint pixel within 1.5 ×
    half its box's larger side of the box's centre (the box, on the ladder's grid reduced by
    ``f``, taken to full resolution)."""
    x, y, w, h = c.bbox
    e = Ellipse(f * (x + 0.5 * w), f * (y + 0.5 * h), 0.5 * f * max(w, h), 0.5 * f * max(w, h), 0.0)
    return _glints_about(e, bright)


def find_pupil(
    img: np.ndarray, invalid, bright: np.ndarray, params, sharp=None, scale=None
) -> PupilFit:
    """Find and fit the pupil (module doc, steps 1–7). ``img`` (rows, cols) float32/float64 or
    integer, the input's own units, with invalid pixels (``invalid``, bool or None) holding any
    finite value; ``bright`` the glint mask (uint8, 0/255). The first of the chosen candidates
    (darkest first, at most ``max_candidates``) whose fit succeeds is returned; otherwise a
    :class:`PupilFit` with ``ellipse`` None and the first candidate's refusal. ``sharp``: an
    optional function giving more glints (uint8 0/255) for :func:`_small_pupil` — those of
    the unsmoothed picture, one pixel each on a small sensor, which would notch a small
    pupil's blob. ``scale``: :func:`work_picture`'s, when known.

    The fit's median edge profile (:func:`edge_profile`) then gives the edge's offset beyond
    it (:func:`edge_offset`, ``edge_offset_px``) — or, when it shows a dark iris ring inside
    the fit (:func:`_ring_inside`), the pupil inside that ring (:func:`_inside_ring`)."""
    wp = work_picture(img, invalid, bright, params, scale)
    if not wp:
        return PupilFit(None, reason=wp.reason)
    fit = _find_pupil(img, invalid, bright, params, sharp, wp)
    if not fit or fit.inliers is None:
        return fit
    prof = edge_profile(img, fit.ellipse, *fit.inliers, bright, invalid)
    if prof is None:
        return fit
    ring = _ring_inside(prof, wp, params)
    if ring:
        fit = _inside_ring(img, wp, fit, ring, bright, params)
        if not fit:
            return fit
        prof = edge_profile(img, fit.ellipse, *fit.inliers, bright, invalid)
        if prof is None:
            return fit
    fit.edge_offset_px = edge_offset(prof, fit.ellipse, params.edge_fraction)
    fit.edge_profile = prof
    return fit


def _ring_inside(prof: EdgeProfile, wp: WorkPicture, params) -> tuple[float, float] | None:
    """(the pupil's level, the ring's level), input units, when the fit's median edge profile
    ``prof`` shows a ring inside the fitted outline, between a darker inside and the fitted
    edge, else None: a dilated pupil hugged by a dark iris 5–12 px wide (pupil 18, iris
    35–55, sclera 190 DN), which the ladder's reduced, smoothed picture (σ 1 px there, f px
    here) does not resolve — its blob takes the ring, and the edge read ¼ of the way from the
    pupil to the sclera is the iris's outline.

    The fitted edge's line spread (:func:`_edge_span`'s peak) falls on its dark side to a
    valley, and further in rises again — a second edge (a single blurred edge's spread falls
    to the noise) — both peaks over 4 × the valley (resolved edges, a flat shelf between
    them); the ring is the profile's level at the valley,
    over the inner half of the profile's inside (the pupil) by ``pupil_min_contrast_sigma``
    standard errors of a difference of two medians over the profiles (1.2533 σ √(2 / N), σ
    the picture's pixel noise) and by
    ``pupil_min_contrast`` of the range, as a pupil's step to its surround must be
    (:func:`blob_contrast`)."""
    m, g = prof.m, prof.g
    span = _edge_span(g, prof.at)
    if span is None:
        return None
    lo = span[1]
    while lo > 0 and g[lo - 1] < g[lo]:  # down the edge's dark flank to its valley
        lo -= 1
    inner = prof.at // 2
    if lo <= inner:
        return None
    # Two edges resolved, a shelf between: the spread at the valley under ¼ of either edge's
    # peak (a ring 5–12 px wide at a blur of 0.8 px: ≤ 0.23 of the pupil's rise, ≤ 0.05 of the
    # fitted edge's; a blurred render's 20 px ramp, bumpy where the iris's texture is, dips
    # to ½ of its bumps and ⅓ of its peak).
    dip = 4.0 * max(float(g[lo]), 0.0)
    if not (g[inner:lo].max() > dip and g[span[1]] > dip):
        return None
    shelf, pupil = float(m[lo]), median(m[:inner])
    rng = wp.hi - wp.lo
    step = shelf - pupil
    if step < params.pupil_min_contrast * rng:  # (first: the noise is worked out on demand)
        return None
    err = 1.2533 * wp.noise * rng / 255.0 * math.sqrt(2.0 / prof.count)
    if step < params.pupil_min_contrast_sigma * err:
        return None
    return pupil, shelf


def _inside_ring(img, wp: WorkPicture, fit: PupilFit, ring, bright, params) -> PupilFit:
    """The pupil inside a fit whose edge profile shows a dark iris ring (:func:`_ring_inside`;
    ``ring`` = (pupil level, ring level), input units): the picture thresholded halfway between
    the two (:func:`full_res_blob`, seeded at the fit's centre) and fitted (:func:`fit_blob`),
    taken when whole (``_whole``); else a refusal naming the ring."""
    e = fit.ellipse
    pupil, shelf = ring
    level = 255.0 * (0.5 * (pupil + shelf) - wp.lo) / (wp.hi - wp.lo)
    r = max(e.a, e.b)
    rows, cols = wp.u8.shape
    cx, cy = min(max(int(round(e.cx)), 0), cols - 1), min(max(int(round(e.cy)), 0), rows - 1)
    x0, y0 = max(0, int(e.cx - r)), max(0, int(e.cy - r))
    box = (x0, y0, min(cols, int(e.cx + r) + 1) - x0, min(rows, int(e.cy + r) + 1) - y0)
    cand = Candidate(level, int(math.pi * e.a * e.b), box, (cx, cy))
    blob = full_res_blob(wp, cand, 1, bright, params, img)
    inner = fit_blob(img, wp, blob, bright, params) if blob else PupilFit(None, reason=blob.reason)
    if inner and _whole(inner, params):
        return inner
    why = inner.reason if not inner else "its fit is not whole"
    major, minor, _ = e.major_minor_angle
    return PupilFit(
        None,
        reason=f"pupil merged with iris: the fitted blob at ({e.cx:.0f}, {e.cy:.0f}) px "
        f"({major:.0f} × {minor:.0f} px) holds a darker disc (level {pupil:.4g}) inside a "
        f"ring at {shelf:.4g} along its outline: a dark iris ring round the pupil; the pupil "
        f"inside it: {why}",
    )


def _find_pupil(img: np.ndarray, invalid, bright: np.ndarray, params, sharp, wp) -> PupilFit:
    """:func:`find_pupil`'s fit (steps 2–7) on its working picture ``wp``."""
    reduced = _reduced(wp, params)
    if reduced[1] is not None and reduced[1].all():
        # Nothing valid is left on the ladder's picture (reduced f×, its missing pixels grown
        # by 1): a few valid pixels, or a strip of them thinner than ~3 f px.
        n = wp.u8.size - int(np.count_nonzero(wp.invalid))
        return PupilFit(
            None,
            reason=f"no pupil: too few valid pixels ({n} of {wp.u8.size}; the rest NaN, masked "
            f"out or a black border) — none is left once the picture is reduced {reduced[2]}× "
            "and the missing pixels are grown by one",
        )
    chains, f, tiny = ladder(wp, params, reduced)
    picks = choose(chains, f, tiny, wp, params, img)
    reasons: list[str] = []
    fit = _fit_chosen(img, wp, (reduced, picks, f), bright, params, reasons)
    fit = _darker_first(img, wp, (reduced, chains, f), fit, bright, params)
    # A whole fit with a darker core inside is an iris holding the pupil (a cut one is
    # refused as cut already, and a lid inside its ellipse would look like a core).
    whole = fit is not None and _whole(fit, params)
    core = _inner_core(img, wp, fit.ellipse, bright, params) if whole else ""
    # A whole fit with an unbacked arc over 1 − ``ladder_fine_support`` (¼) of its outline, of
    # a pupil at the black level (its chain stable from the ladder's second level, the first
    # whose q has a level below it: the finer ladder's span holds the whole pupil), may be a
    # pupil merged with a dark iris: up the iris's ramp the blob grows by a near-constant area
    # a level, so MSER's q = ΔA / A keeps falling and the walk to its local minimum
    # (:func:`_pick`) stops wherever the noise makes q tick up. On paper2005's 8-bit PNG at
    # gaze (30°, 20°) it stopped 9 levels up, half the blob iris and its median (the edge's
    # pupil level) 3 × the pupil's: the edge was read on the iris, no pupil edge was within
    # reach on the iris's wide side, and the ellipse, backed on 57 % of its outline (an arc
    # of 43 % unbacked), was answered 1.27 px off the truth (the irradiance picture's walk
    # stopped at a bump 4 levels lower: 0.23 px). The finer ladder below may then find it
    # whole. (On a noisy pupil the chain is stable only higher up; tried on the real
    # close-ups' long-arc fits too, the finer ladder changed no answer and cost up to 2 ms a
    # picture: not tried there.)
    long_arc = whole and fit.gap > 1.0 - params.ladder_fine_support and fit.stable_from <= 1
    if whole and not core and not long_arc:
        return _small_beside(img, invalid, bright, f, fit, params) or fit
    # Nothing whole (or a long arc as above): the ladder's dark end again, finer; its fit
    # replaces the first only when whole by the stricter measure. The first pass misses a
    # pupil near the black level whose step to the iris it crosses in one or two levels (an
    # off-axis view, where bright skin sets the levels' spacing): its chain's stable blob is
    # then the iris, or the pupil is unstable at the first level, joined at the next to the
    # iris or to a dark fold. Then, with nothing whole, for a pupil a few px across once
    # reduced, the ladder at full resolution (:func:`_small_pupil`; only for pupils under
    # ``small_pupil_axes`` × f px: for any pupil it gave wrong answers on real close-ups).
    again = _finer(img, wp, reduced, f, bright, params)
    if again is None and not (whole and not core):  # (a long arc's fit stands then)
        again = _small_pupil(img, invalid, bright, f, params) or (
            sharp and _small_pupil(img, invalid, cv2.bitwise_or(bright, sharp()), f, params)
        )
    if again is not None:
        return again
    if core:
        return _core_answer(img, wp, fit.ellipse, core, bright, params)
    if fit is not None:
        return fit
    if not picks:
        return PupilFit(None, reason=picks.reason)
    edge_dark = tiny[1]()
    # Darker by the contrast a pupil needs (``pupil_min_contrast_sigma`` σ of the noise): a
    # region a few σ darker is the noise's (a close-up's iris running off the frame, 2 σ
    # above its pupil, with bright skin filled as glints by the dark around them: called a
    # pupil cut by the frame instead of the pupil merged with its iris).
    if edge_dark and edge_dark[0] <= picks[0].level - params.pupil_min_contrast_sigma * wp.noise:
        return PupilFit(
            None,
            reason=f"no pupil off the picture's border: a darker region of a pupil's size "
            f"({edge_dark[1]} px) touches {edge_dark[2]} (a pupil cut there?); the darkest "
            f"blob inside was refused: {reasons[0]}",
        )
    return PupilFit(None, reason=reasons[0])


# --- The edge's profile: a dark iris ring inside the fit, and the edge's offset ---------------

#: :func:`edge_profile`'s sample step along the normals, px
_EDGE_STEP = 0.25
#: :func:`edge_profile`'s most profiles (evenly spaced over the backed outline)
_EDGE_PROFILES = 256
#: :func:`_spread`'s binomial kernel (9 taps, σ 0.35 px at :data:`_EDGE_STEP`)
_SPREAD_KERNEL = np.array([1.0, 8.0, 28.0, 56.0, 70.0, 56.0, 28.0, 8.0, 1.0]) / 256.0


@dataclass(frozen=True)
class EdgeProfile:
    """The median of the picture's profiles along a fitted ellipse's outward normals
    (:func:`edge_profile`): ``s`` (px, + outward, 0 on the ellipse) and ``m`` (input units),
    over ``count`` profiles; ``at`` the index of s = 0; ``g`` its line spread
    (:func:`_spread` of ``m``, per px), worked out once for :func:`_ring_inside` and
    :func:`edge_offset`."""

    s: np.ndarray
    m: np.ndarray
    count: int
    at: int
    g: np.ndarray


@njit(cache=True, nogil=True)
def _normal_maps(px, py, nx, ny, s):
    """:func:`edge_profile`'s sample points: (px + nx s, py + ny s) for each profile (row) and
    step s (column), worked out in float64 and rounded to float32 (NumPy's broadcast
    ``(px[:, None] + nx[:, None] * s[None, :]).astype(np.float32)``, the same floats), and
    their (least x, least y, largest x, largest y)."""
    n, k = px.size, s.size
    mx = np.empty((n, k), np.float32)
    my = np.empty((n, k), np.float32)
    lo_x, lo_y = np.float32(np.inf), np.float32(np.inf)
    hi_x, hi_y = np.float32(-np.inf), np.float32(-np.inf)
    for i in range(n):
        for j in range(k):
            vx = np.float32(px[i] + nx[i] * s[j])
            vy = np.float32(py[i] + ny[i] * s[j])
            mx[i, j] = vx
            my[i, j] = vy
            lo_x = min(lo_x, vx)
            hi_x = max(hi_x, vx)
            lo_y = min(lo_y, vy)
            hi_y = max(hi_y, vy)
    return mx, my, (lo_x, lo_y, hi_x, hi_y)


@njit(cache=True, nogil=True)
def _shift_maps(mx, my, x0, y0, w, h):
    """``mx`` −= x0 and ``my`` −= y0 in place (float32) and the samples off the w × h window
    (bool): :func:`edge_profile`'s points in its window."""
    n, k = mx.shape
    off = np.empty((n, k), np.bool_)
    fx0, fy0 = np.float32(x0), np.float32(y0)
    wx, hy = np.float32(w - 1), np.float32(h - 1)
    for i in range(n):
        for j in range(k):
            vx = mx[i, j] - fx0
            vy = my[i, j] - fy0
            mx[i, j] = vx
            my[i, j] = vy
            off[i, j] = vx < 0 or vy < 0 or vx > wx or vy > hy
    return off


def edge_profile(img: np.ndarray, e: Ellipse, x, y, bright, invalid) -> EdgeProfile | None:
    """The median profile across the edge of the ellipse ``e``, sampled every
    :data:`_EDGE_STEP` px along its normals at the eccentric anomalies of the edge points (x, y)
    (px arrays; at most :data:`_EDGE_PROFILES` of them, evenly spaced): inward 0.6 × its smaller
    semi-axis (≤ 24 px: not across the pupil), outward its larger one (≤ 24 px). A sample
    counts when it lies in the picture, off the glints (``bright``, uint8 0/255, grown by 2
    px: their skirts) and off the missing pixels (``invalid``, bool or None); the profile
    ends, each way, before a sample that fewer than 5 profiles keep (``count``: the fewest any
    sample keeps). None when fewer than 5 keep the sample on the ellipse. The median of a few
    dozen to a few hundred profiles is quiet and ignores a minority crossing a lash or the
    iris's texture."""
    rows, cols = img.shape
    s_, q_ = e.local(np.asarray(x, float), np.asarray(y, float))
    anom = np.arctan2(q_ / e.b, s_ / e.a)
    if len(anom) > _EDGE_PROFILES:
        anom = anom[np.linspace(0, len(anom) - 1, _EDGE_PROFILES).astype(np.intp)]
    c, sn = math.cos(e.theta), math.sin(e.theta)
    ea, eb = e.a * np.cos(anom), e.b * np.sin(anom)
    px, py = e.cx + ea * c - eb * sn, e.cy + ea * sn + eb * c
    nx, ny = e.outward_normal(px, py)
    reach_in = max(1.0, min(0.6 * min(e.a, e.b), 24.0))
    reach_out = max(2.0, min(max(e.a, e.b), 24.0))
    at = int(math.ceil(reach_in / _EDGE_STEP))
    s = (np.arange(at + int(math.ceil(reach_out / _EDGE_STEP)) + 1) - at) * _EDGE_STEP
    # The sample points (float32, as cv2.remap takes them) and their extent
    mx, my, lims = _normal_maps(px, py, nx, ny, s)
    x0 = max(0, int(math.floor(float(lims[0]))) - 1)
    y0 = max(0, int(math.floor(float(lims[1]))) - 1)
    x1 = min(cols, int(math.ceil(float(lims[2]))) + 2)
    y1 = min(rows, int(math.ceil(float(lims[3]))) + 2)
    if x1 - x0 < 2 or y1 - y0 < 2:
        return None
    # Samples off the picture, on the glints (grown by 2 px: their skirts) or on missing
    # pixels do not count; each sample's median is over the profiles that keep it there, and
    # the profile ends, each way, before a sample fewer than 5 profiles keep.
    off = _shift_maps(mx, my, x0, y0, x1 - x0, y1 - y0)
    bad = bright[y0:y1, x0:x1] > 0
    if invalid is not None:
        bad = bad | invalid[y0:y1, x0:x1]
    if bad.any():
        grown = cv2.dilate(bad.astype(np.uint8), _disc(5))
        off |= cv2.remap(grown, mx, my, cv2.INTER_NEAREST, borderMode=cv2.BORDER_REPLICATE) > 0
    sub = img[y0:y1, x0:x1].astype(np.float32)
    prof = cv2.remap(sub, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    kept = len(prof) - off.sum(axis=0)
    if kept[at] < 5:
        return None
    first, last = at, at
    while first > 0 and kept[first - 1] >= 5:
        first -= 1
    while last + 1 < len(s) and kept[last + 1] >= 5:
        last += 1
    prof = prof[:, first : last + 1]
    if off.any():
        # np.nanmedian's value (the mean of the two middle kept values, in float32) without its
        # masked-array path (~1.7 ms a frame): NaNs sort last, each column's middle by its count.
        # (NumPy's SIMD sort of the whole columns beats a compiled selection per column, 4×.)
        prof[off[:, first : last + 1]] = np.nan
        srt = np.sort(prof, axis=0)
        n = kept[first : last + 1]
        cols_ = np.arange(srt.shape[1])
        m = (srt[(n - 1) // 2, cols_] + srt[n // 2, cols_]) * np.float32(0.5)
    else:
        m = np.median(prof, axis=0)
    count = int(kept[first : last + 1].min())
    m = m.astype(np.float64)
    return EdgeProfile(s[first : last + 1], m, count, at - first, _spread(m))


def _spread(m: np.ndarray) -> np.ndarray:
    """The line spread of a median profile: its derivative (per px), smoothed by
    :data:`_SPREAD_KERNEL` so that the noise left in the median makes no local extremes on an
    edge's flanks."""
    g = np.gradient(m, _EDGE_STEP)
    # (np.pad(g, 4, mode="edge")'s values, without its general path: ~20 µs a call)
    padded = np.concatenate((np.full(4, g[0]), g, np.full(4, g[-1])))
    return np.convolve(padded, _SPREAD_KERNEL, "valid")


def _edge_span(g: np.ndarray, i: int) -> tuple[int, int, int] | None:
    """(dark end, peak, bright end) indices of the edge whose line spread ``g`` rises from
    index ``i`` (the fitted ¼ iso-line, on the edge's dark flank): up to its peak, then each way
    down to 5 % of the peak or to a local minimum under ½ of it (where a next edge begins: a
    dark iris ring's step to the sclera 5 px out, whose spread falls to 0.3 of the pupil's
    between them at a blur of 0.8 px). None without a rise."""
    n = len(g)
    while i + 1 < n and g[i + 1] > g[i]:
        i += 1
    while i > 0 and g[i - 1] > g[i]:
        i -= 1
    peak = g[i]
    if not peak > 0:
        return None
    hi = i
    while hi + 1 < n and g[hi] > 0.05 * peak and not (g[hi + 1] > g[hi] and g[hi] < 0.5 * peak):
        hi += 1
    lo = i
    while lo > 0 and g[lo] > 0.05 * peak and not (g[lo - 1] > g[lo] and g[lo] < 0.5 * peak):
        lo -= 1
    return lo, i, hi


def edge_offset(prof: EdgeProfile, e: Ellipse, fraction: float) -> float:
    """How far (px, + outward) the pupil's edge lies beyond the fitted ellipse ``e``, the
    iso-line at ``fraction`` (``edge_fraction``, ¼) of the way up the edge (module doc, step
    5), from its median profile ``prof`` (:func:`edge_profile`); 0.0 when the profile shows no
    edge or not the one the fit read.

    The edge is the step of a model fitted to the profile about its edge's line spread
    (:func:`_edge_span`; :func:`_step_fit`): a step at s = e from the pupil's level p to an
    iris that goes on as a quadratic in (s − e), blurred by a Gaussian of σ,

        m(s) = p + G_σ * [H(s − e) (q + k (s − e) + c (s − e)²)],

    least squares over p, q, k, c (linear) and e, σ; the fitted e plus σ² / 2(ρ + e), ρ =
    √(a b) (a blurred disc of radius R crosses its half level σ² / 2R inside R). A blur of σ
    moves the ¼ iso-line 0.674 σ inside the edge (Φ⁻¹(¾)): 2 px on a 60 px pupil at σ 1.5,
    in the axes a pupillometry user reads; the centre does not move (module doc, step 5). The
    iris's own slope and curvature are the model's: an iris that brightens gradually away
    from the pupil (26–45 DN at its edge rising to 110 over 4–40 px) does not move the edge
    out, as the half level of the whole rise did (3.4–13 px on the axes). Where the iris
    rises over a few σ of the blur (1 − exp(−d / τ), τ ≲ 5 σ), its rise and the step's
    blur are one shape and the edge cannot be told from the profile
    (tests/analysis/test_detect_pupil_gradual_iris.py). Where the fit is not this edge's, the
    former half level (:func:`_half_level_offset`) — also where the fitted step lies within
    :data:`_EDGE_FOOT` σ of the line spread's dark end: a defocused camera's pillbox blur makes
    a near-linear ramp that the model fits as well with a sharp step at its foot and the iris
    rising over it (axes 15–21 px short; tests/analysis/test_detect_pupil_pillbox.py). The
    half level reads the edge's span run on across shallow dips of a long ramp's noisy line
    spread (:func:`_ramp_foot`, :func:`_ramp_top`; the model's window keeps the span as
    found: joined, it let the model fit a small early rise of real close-ups' edges as the
    step)."""
    s, m = prof.s, prof.m
    g = prof.g
    span = _edge_span(g, prof.at)
    if span is None:
        return 0.0
    lo, pk, hi = span
    if not m[hi] > m[lo]:
        return 0.0
    pk = _spread_middle(g, lo, pk, hi)
    # The window: 2 px of the pupil's level before the span's dark end, and beyond the peak
    # (or the spread's centroid where its top is flat, :func:`_spread_middle`) twice the
    # span's dark flank (≈ 2.4 σ: the step's blur out to ≈ 5 σ) and 1 px more. The
    # step is looked for from ½ px before the dark end to 1 px past the peak; a fit at either
    # end of that, or at the largest blur tried, is not this edge's: the half level then.
    flank = s[pk] - s[lo]
    a = max(0, lo - int(round(2.0 / _EDGE_STEP)))
    b = min(len(s), pk + int(math.ceil((2.0 * flank + 1.0) / _EDGE_STEP)) + 1)
    if b > hi + 1 and g[hi:b].max() > g[pk]:
        # a stronger edge within the window beyond the span (a dark iris ring's step to the
        # sclera 5 px out), which the model's quadratic does not follow: the half level
        return _half_level_offset(prof, e, fraction, span)
    e_lo, e_hi, sig_hi = float(s[lo]) - 0.5, float(s[pk]) + 1.0, max(1.0, flank)
    edge, sig, _ = _step_fit(s[a:b], m[a:b], e_lo, e_hi, sig_hi)
    rho = math.sqrt(e.a * e.b)
    if not (e_lo < edge < e_hi and sig < 2.0 * sig_hi and rho + edge > 0):
        return _half_level_offset(prof, e, fraction, span)
    if edge - float(s[lo]) < _EDGE_FOOT * sig:
        # the step at the foot of the rise, its blur reaching ≥ 2 σ before it where the
        # profile is still flat: the rise was taken for the iris's slope, not the step's blur
        return _half_level_offset(prof, e, fraction, span)
    return edge + sig * sig / (2.0 * (rho + edge))


def _ramp_top(g: np.ndarray, m: np.ndarray, span) -> tuple[int, int, int]:
    """The span (:func:`_edge_span`: dark end, peak, bright end indices) that :func:`edge_offset`'s
    half level reads, its bright end moved on past shallow dips of the line spread ``g``
    where the profile ``m`` goes on rising: while the spread stops at a local minimum over
    :data:`_RAMP_DIP` of its peak, the next rise's peak is ≥ ½ of it and the profile has
    climbed more than :data:`_RAMP_SHARE` of the way from the dark end to that rise's top,
    the span runs on to that top. A defocused camera's 15–20 px edge (a pillbox blur: a
    near-flat spread, noisy in a median of few-sample profiles) dips so mid-ramp, and the
    half level read over part of the rise put the edge 6–11 px in (`paper2005` at 640 ×
    480). A dark iris ring before the sclera's step (:func:`_ring_inside`'s case) dips
    deeper or sooner: on the tests' pictures where a stronger edge follows, ≤ 0.11 of the
    peak, or 0.30–0.50 with ≤ 0.33 of the rise climbed; those ramps 0.37–0.57 with
    0.59–0.75."""
    lo, pk, hi = span
    n = len(g)
    while hi + 1 < n and g[hi] > _RAMP_DIP * g[pk] and g[hi + 1] > g[hi]:
        i = hi + 1
        while i + 1 < n and g[i + 1] >= g[i]:
            i += 1
        if g[i] < 0.5 * g[pk]:
            break
        nxt = _edge_span(g, i)
        if nxt is None or nxt[2] <= hi or not m[hi] - m[lo] > _RAMP_SHARE * (m[nxt[2]] - m[lo]):
            break
        hi = nxt[2]
    return lo, pk, hi


def _ramp_foot(g: np.ndarray, span) -> tuple[int, int, int]:
    """:func:`_ramp_top` on the dark side: the span's dark end moved back past shallow dips
    (over :data:`_RAMP_DIP` of the peak) of the line spread ``g`` to the foot of a rise whose
    peak is ≥ ½ of the span's — the start of a ramp whose noisy spread dipped near its middle
    (`paper2005` at 640 × 480, (−20°, −10°): the span began 5 px up the ramp, the ¼ line
    looked off it and the offset was refused, the axes 8–11 px short). A darker core inside
    the pupil, a shelf with the pupil's edge inside it, is :func:`_ring_inside`'s, read
    before."""
    lo, pk, hi = span
    while lo > 0 and g[lo] > _RAMP_DIP * g[pk] and g[lo - 1] > g[lo]:
        i = lo - 1
        while i > 0 and g[i - 1] >= g[i]:
            i -= 1
        if g[i] < 0.5 * g[pk]:
            break
        prev = _edge_span(g, i)
        if prev is None or prev[0] >= lo:
            break
        lo = prev[0]
    return lo, pk, hi


#: :func:`_ramp_top`, :func:`_ramp_foot`: the least dip of the line spread, as a share of its
#: peak, that is noise on one ramp rather than the gap between two edges (the tests' dark
#: iris rings before the sclera ≤ 0.11, or ≤ 0.50 with under a third of the rise climbed;
#: paper2005's 640 × 480 ramps 0.33–0.57; session 34's measurement, a guess between them)
_RAMP_DIP = 0.25
#: :func:`_ramp_top`: the least share of the rise to the next rise's top climbed at the dip
#: for the two to be one ramp (those rings ≤ 0.33, the ramps ≥ 0.59; as above)
_RAMP_SHARE = 0.5


#: :func:`edge_offset`: the least distance, in σ of the fitted blur, from the line spread's
#: dark end (5 % of its peak: 2.45 σ before a Gaussian-blurred step) to the fitted step for
#: the step to be the edge. The tests' pictures (sharp, blurred and gradual irises, renders at
#: 87 × 65) fit 0.86–4.3 σ after it; a defocused paper2005 render at 640 × 480 (its pupil's
#: edge a 15–20 px ramp, the blur a pillbox no Gaussian follows) 0.02–0.04 σ, the step at the
#: foot and the ramp taken for the iris (`ok`, its axes 16 px short at a 20° gaze in focus)
_EDGE_FOOT = 0.5


#: :func:`_spread_middle`: the least share of the spread's peak at its centroid for the top to
#: count as flat (a guess)
_FLAT_TOP = 0.8


def _spread_middle(g: np.ndarray, lo: int, pk: int, hi: int) -> int:
    """The index :func:`edge_offset` centres its window on: the line spread's peak ``pk``, or
    its centroid over the span [``lo``, ``hi``] where that lies further out. A blurred step's
    spread is a Gaussian about the edge; at a blur of σ 6–8 px its top is flat to within the
    median profile's noise and the first local peak the walk from the ¼ line meets can lie
    3–5 px inside the edge, which then lay outside the model's search (``e`` ≤ peak + 1 px):
    the axes came out up to 23 px small."""
    w = np.clip(g[lo : hi + 1], 0.0, None)
    total = float(w.sum())
    if not total > 0:
        return pk
    mid = min(lo + int(round(float(np.dot(w, np.arange(hi - lo + 1))) / total)), hi)
    return mid if mid > pk and g[mid] >= _FLAT_TOP * g[pk] else pk


def _half_level_offset(prof: EdgeProfile, e: Ellipse, fraction: float, span) -> float:
    """:func:`edge_offset` where its model's fit is not this edge's (at an end of its search
    window, or its blur as wide as the window: a defocused render's 15–20 px rise, bumpy
    where the iris's texture is, whose spread peaks early): the profile's mass-preserving step
    over the whole span (:func:`_edge_span`) — the step whose sharp disc holds as much light
    as the profile does over that ring (radius √(a b) + s), for a symmetric blur its half
    level; 0.0 when the fit's line does not sit about its own ``fraction`` up the span
    (within a factor 2): the walk climbed on to a brighter edge beyond. (Sessions 22–24's
    offset everywhere; on a gradual iris it reads the half level of the whole rise, far out.)
    The span is run on across a long ramp's noisy dips first (:func:`_ramp_foot`,
    :func:`_ramp_top`)."""
    s, m = prof.s, prof.m
    lo, _, hi = _ramp_top(prof.g, m, _ramp_foot(prof.g, span))
    m_lo, m_hi = m[lo], m[hi]
    up = (m[prof.at] - m_lo) / (m_hi - m_lo)
    if not 0.5 * fraction <= up <= 2.0 * fraction:
        return 0.0
    # (m_hi − m_lo)((ρ + s_hi)² − r²) / 2 = ∫ (m − m_lo) r dr over [ρ + s_lo, ρ + s_hi]
    # (trapezoids), ρ = √(a b)
    rho = math.sqrt(e.a * e.b)
    r = rho + s[lo : hi + 1]
    f = (m[lo : hi + 1] - m_lo) * r
    mass = float(np.sum(0.5 * (f[1:] + f[:-1]))) * _EDGE_STEP
    r2 = (rho + s[hi]) ** 2 - 2.0 * mass / (m_hi - m_lo)
    return math.sqrt(r2) - rho if r2 > 0 else 0.0


@njit(cache=True, nogil=True)
def _step_sse(s, m, e, sig, every, tab):
    """The least-squares residual (sum of squares) of :func:`edge_offset`'s model at step
    ``e`` and blur ``sig`` (px) over every ``every``-th sample, p, q, k, c solved from the
    4 × 4 normal equations. ``tab``: :func:`_step_table`'s Φ(x) and φ(x) for this ``sig``
    on the samples' grid (``s`` − ``e`` a multiple of :data:`_EDGE_STEP`), or empty: computed
    here."""
    # The normal equations' lower triangle and right side in scalars (registers: as arrays
    # they were stored and loaded at every sample), each sum taken in the samples' order.
    a00 = a10 = a11 = a20 = a21 = a22 = a30 = a31 = a32 = a33 = 0.0
    b0 = b1 = b2 = b3 = 0.0
    mm = 0.0
    r2 = 1.0 / math.sqrt(2.0)
    r2pi = 1.0 / math.sqrt(2.0 * math.pi)
    for i in range(0, s.size, every):
        x = (s[i] - e) / sig
        if tab.shape[0] > 0:
            k = int(round((s[i] - e) / _EDGE_STEP)) - int(tab[0, 2])
            big, small = tab[k, 0], tab[k, 1]
        else:
            big = 0.5 * math.erfc(-x * r2)
            small = math.exp(-0.5 * x * x) * r2pi
        c0 = 1.0
        c1 = big
        c2 = sig * (x * big + small)
        c3 = sig * sig * ((x * x + 1.0) * big + x * small)
        mi = m[i]
        b0 += c0 * mi
        b1 += c1 * mi
        b2 += c2 * mi
        b3 += c3 * mi
        a00 += c0 * c0
        a10 += c1 * c0
        a11 += c1 * c1
        a20 += c2 * c0
        a21 += c2 * c1
        a22 += c2 * c2
        a30 += c3 * c0
        a31 += c3 * c1
        a32 += c3 * c2
        a33 += c3 * c3
        mm += mi * mi
    ata = np.zeros((4, 4))
    ata[0, 0], ata[1, 0], ata[1, 1] = a00, a10, a11
    ata[2, 0], ata[2, 1], ata[2, 2] = a20, a21, a22
    ata[3, 0], ata[3, 1], ata[3, 2], ata[3, 3] = a30, a31, a32, a33
    atb = np.empty(4)
    atb[0], atb[1], atb[2], atb[3] = b0, b1, b2, b3
    return mm - _explained(ata, atb)


@njit(cache=True, nogil=True)
def _explained(ata, atb):
    """|L⁻¹ b|², L L' = A (Cholesky): the sum of squares a least-squares fit with normal
    matrix A = ``ata`` (4 × 4) and right side b = ``atb`` explains; the residual is |m|² less
    it (A's lower triangle is read). A ridge of 1e-9 of the diagonal keeps A positive
    definite where a column vanishes over the window; −inf (a residual of +inf) if it is
    not."""
    low = np.zeros((4, 4))
    for j in range(4):
        d = ata[j, j] * (1.0 + 1e-9) + 1e-12
        for k in range(j):
            d -= low[j, k] * low[j, k]
        if not d > 0:
            return -np.inf
        low[j, j] = math.sqrt(d)
        for i in range(j + 1, 4):
            v = ata[i, j]
            for k in range(j):
                v -= low[i, k] * low[j, k]
            low[i, j] = v / low[j, j]
    z = np.zeros(4)
    fit = 0.0
    for j in range(4):
        v = atb[j]
        for k in range(j):
            v -= low[j, k] * z[k]
        z[j] = v / low[j, j]
        fit += z[j] * z[j]
    return fit


@njit(cache=True, nogil=True)
def _on_step_grid(s, e_lo) -> bool:
    """Whether the samples ``s`` and ``e_lo`` are whole multiples of :data:`_EDGE_STEP`, a
    power of two dividing the coarse search's 0.25 px (then every s − e of :func:`_step_fit`'s
    coarse search is one, exact in binary)."""
    if math.log2(_EDGE_STEP) != round(math.log2(_EDGE_STEP)) or _EDGE_STEP > 0.25:
        return False
    for v in s:
        if v / _EDGE_STEP != round(v / _EDGE_STEP):
            return False
    return e_lo / _EDGE_STEP == round(e_lo / _EDGE_STEP)


@njit(cache=True, nogil=True)
def _step_table(d_lo, d_hi, sig):
    """Φ(x) and φ(x) (columns 0, 1) at x = k :data:`_EDGE_STEP` / ``sig`` for the whole k from
    d_lo to d_hi (px, multiples of the step); column 2 holds the first k."""
    k0 = int(round(d_lo / _EDGE_STEP))
    n = int(round(d_hi / _EDGE_STEP)) - k0 + 1
    tab = np.empty((n, 3))
    r2 = 1.0 / math.sqrt(2.0)
    r2pi = 1.0 / math.sqrt(2.0 * math.pi)
    for k in range(n):
        x = ((k0 + k) * _EDGE_STEP) / sig
        tab[k, 0] = 0.5 * math.erfc(-x * r2)
        tab[k, 1] = math.exp(-0.5 * x * x) * r2pi
        tab[k, 2] = k0
    return tab


@njit(cache=True, nogil=True)
def _step_fit(s, m, e_lo, e_hi, sig_hi):
    """(e, σ), px, of :func:`edge_offset`'s blurred step fitted to the profile ``m`` at ``s``:
    the least residual over e in [e_lo, e_hi] every 0.25 px and σ in [0.2, 2 ``sig_hi``] px
    every factor 1.25 (on every third sample), then about the best within ± 0.3 px every
    0.1 px and σ × 1.08^±3, ± 0.075 px every 0.025 px and σ × 1.02^±3, and ± 0.018 px every
    0.006 px and σ × 1.005^±3."""
    best, be, bs = np.inf, e_lo, 1.0
    ns = int(math.ceil(math.log(2.0 * sig_hi / 0.2) / math.log(1.25))) + 1
    ne = int(math.ceil((e_hi - e_lo) / 0.25)) + 1
    none = np.empty((0, 3))
    # On the profile's grid (as edge_profile's samples and edge_offset's e_lo are: multiples of
    # _EDGE_STEP, exact in binary) every s − e of the coarse search is k × _EDGE_STEP exactly,
    # so Φ and φ are tabulated once per σ over those k: the same numbers, ~6 × fewer erfc.
    grid = _on_step_grid(s, e_lo)
    for i in range(ns):  # (every third sample, 0.75 px apart: the coarse search)
        sig = 0.2 * 1.25**i
        tab = _step_table(s[0] - (e_lo + 0.25 * (ne - 1)), s[-1] - e_lo, sig) if grid else none
        for j in range(ne):
            e = e_lo + 0.25 * j
            r = _step_sse(s, m, e, sig, 3, tab)
            if r < best:
                best, be, bs = r, e, sig
    for de, fs, every in ((0.1, 1.08, 1), (0.025, 1.02, 1), (0.006, 1.005, 1)):
        best = np.inf
        e0, s0 = be, bs
        for i in range(-3, 4):
            sig = s0 * fs**i
            for j in range(-3, 4):
                e = e0 + de * j
                r = _step_sse(s, m, e, sig, every, none)
                if r < best:
                    best, be, bs = r, e, sig
    return be, bs, best
