"""Glints (first Purkinje images): bright-spot threshold, sub-pixel centroids, LED matching.

* **Threshold**: glints are the brightest and smallest things in an eye picture — far less
  than 1 % of it — so a glint pixel must be brighter than the 99th percentile of the 8-bit
  picture (:func:`glint_threshold`: the brightest *scene* level, skin or sclera) *and* stand out
  of its neighbourhood: u8 ≥ m + ``glint_level`` (255 − m), m the mean of the ``glint_window_px``
  box around it (default odd ≈ min(rows, cols) / 16, ≥ 5: a few glints across). Over bright
  skin that is halfway from the skin to the maximum; over the dark pupil, where glints sit,
  half the maximum, so a glint the eye turned dimmer keeps its shoulders. When the maximum is
  not ``glint_min_contrast`` of the range above the 99th percentile (light skin or sclera near
  full scale: the percentile sits close to the top, or on a saturated plateau), the floor is
  ``glint_min_contrast`` below the top and a glint is a blob whose peak stands that contrast
  above its own surround (:func:`saturated_floor`): skin, whose surround is as bright, is not
  one, and a glint-free picture has none. (Until session 14 this applied only when over 5 % of
  the picture lay within that contrast of the top; a well-exposed face with 1–5 % there —
  glasses-frame at its own chip — had its glints not looked for at all.)
* **Blobs**: the bright mask is closed with a small elliptical element (``glint_close_px``; by
  default odd ≈ min(rows, cols) / 160, i.e. none below 240 px, 3 px at 480 rows) so that a glint
  broken up by noise or a saturated speckle is one blob, then split into blobs (outer outlines,
  ``cv2.findContours``) kept within the area bounds: ≥ 2 px (the optics spread a glint over
  several pixels; a hot pixel or a noise spike is one), ≤ 0.5 % of the picture.
* **Centroid**: intensity-weighted over the blob and a skirt around it, weights max(I − B, 0)
  with B the local background (:func:`glint_blobs`). Weighting only what is above the threshold
  would weigh a saturated spot as a nearly hard-edged disc, whose centroid jumps with the pixel
  grid (0.1 px in the tests); with the skirt down to the background it is smooth. B is the
  surround's median when the surround is flat; when it is not (its 10–90 % spread over 8 σ of
  the noise: a glint at the limbus, half on iris and half on sclera) B(x, y) is interpolated
  under the spot from its surround (``cv2.inpaint``, Telea), else the bright side's skirt
  pulls the centroid toward it (:func:`_uneven_surround`). Where skirts of neighbouring blobs
  meet, a pixel goes to the nearer blob — but a fragment under ``glint_min_area_px`` is no
  blob: the unclosed mask of a small picture breaks a noisy glint into a blob and one-pixel
  fragments of the same spot, whose light is the glint's skirt, not another glint's (until
  session 16 they cut the skirt: paper2005's glints 1.03 and 1.09 px off, answered ``ok``).
* **Unsaturated glints** (:func:`faint_glints_near`, called by ``detect`` near the pupil when
  fewer glints than LEDs were found): a glint well below the top of the picture (80 DN over
  a pupil at 20 in a picture whose sclera is at 200) is under the 99th percentile and less
  than ``glint_level`` of the way to the top, yet stands tens of σ of the noise over its own
  background; it is looked for on the white top-hat I − open(I) (a disc wider than a glint,
  narrower than the iris), with a flat surround there and a peak ``glint_min_snr`` × the
  noise over it.
* **Matching** (:func:`match_leds`): LED k at azimuth φ_k (0° = picture +x, 90° = picture up, i.e.
  −row) makes a glint displaced from the glints' centroid toward φ_k; each glint's direction from
  that centroid is matched to the LED azimuths by the Hungarian algorithm
  (``scipy.optimize.linear_sum_assignment``) on the angular difference, and a pair further apart
  than ``match_max_angle_deg`` (default half the smallest gap between LED azimuths) stays
  unmatched. The first reference is the glints' median point (a stray bright pixel does not
  move it), then the centre of the LED pattern the matched glints fit — their centroid when
  all are there, unbiased when one is lost (:func:`match_leds`). Not the pupil centre: with
  the eye turned the glints' pattern moves off it by more than its own size.
  An off-axis camera sees the LEDs' glints as a foreshortened, distorted ring whose
  directions from its centre are not the azimuths: there the glints are matched to the
  predicted layout itself by a fitted shift, scale and rotation (:func:`match_pattern`).
  With glints left over, every distinct set of ≥ 3 glints fitting the whole pattern (shift and
  scale) is listed (:func:`pattern_fits`): ``detect`` checks the matching against them (a
  spectacle reflection of the LEDs is a second whole pattern; two glints at one LED's place
  are two fits differing there).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Sequence

import cv2
import numpy as np
from numba import njit
from scipy.optimize import linear_sum_assignment

from .pupil import immerkaer_abs

__all__ = [
    "find_glints",
    "glint_smoothing",
    "glints_near",
    "faint_glints_near",
    "broad_glints_near",
    "fit_spot",
    "spot_sigma",
    "block_or_blur",
    "in_bright_run",
    "glint_blobs",
    "jpeg_dc_step",
    "glint_threshold",
    "saturated_floor",
    "match_leds",
    "match_pattern",
    "default_max_angle",
    "pattern_fits",
]


def glint_threshold(hist: np.ndarray, percentile: float, min_contrast: float) -> int | None:
    """8-bit floor of glint pixels (they are brighter than it): the ``percentile`` of the
    picture's unsaturated pixels (those below its top level, when that level holds ≤ 5 % of
    them: big saturated glints in a close-up can be over 1 % of it), or ``None`` when the
    maximum is not ``min_contrast`` × 255 above it."""
    top = int(np.nonzero(hist)[0][-1]) if hist.any() else 0
    # Leave the top level out when it is a few pixels (saturated glints), not when it is a
    # large part of the picture (an over-exposed face, a flat bright background).
    few = hist[top] <= 0.05 * hist.sum()
    cum = np.cumsum(hist[:top] if few else hist)
    if top == 0 or cum[-1] == 0:
        return None
    base = int(np.searchsorted(cum, percentile / 100.0 * cum[-1]))
    if top - base < min_contrast * 255.0:
        return None
    return base


def saturated_floor(hist: np.ndarray, min_contrast: float) -> int | None:
    """8-bit floor of glint pixels in a picture whose 99th percentile is within
    ``min_contrast`` × 255 of its top (:func:`glint_threshold` gave ``None``: skin and sclera
    near or at full scale): glints — saturated too — are the pixels within ``min_contrast`` ×
    255 of the top; they are told from the skin by their surround (:func:`glint_blobs` with
    ``min_rise``), not by a global level. ``None`` when the picture is flat (the floor ≤ 0)."""
    if not hist.any():
        return None
    top = int(np.nonzero(hist)[0][-1])
    floor = top - int(math.ceil(min_contrast * 255.0))
    if floor <= 0 or not hist[floor + 1 :].any():
        return None
    return floor


def glint_smoothing(shape: tuple[int, int], params) -> float:
    """σ (px) of the Gaussian :func:`find_glints` smooths a picture of ``shape`` (rows, cols)
    by before its bright mask: ``glint_smooth_px``, or min(rows, cols) / 480 when ``None``;
    below 0.5 px it does not smooth."""
    sig = params.glint_smooth_px
    return min(shape) / 480.0 if sig is None else sig


def find_glints(img: np.ndarray, value_range, noise: float, params):
    """Step 2 of :func:`~eyelume.analysis.tracking.detect.detect`: the glint blobs (dicts), the
    bright mask (uint8 0/255) and the glint floor in the input's units (``None`` when nothing
    stands out). ``img`` is the input (missing pixels filled), ``value_range`` its (min, max),
    ``noise`` its pixel noise σ (input units). The bright mask is taken from the picture
    scaled by its own range to 8 bits, u8 = 255 (I − min) / (max − min), after smoothing by
    ``glint_smooth_px`` (when ≥ 0.5 px)."""
    sig = glint_smoothing(img.shape, params)
    lo, hi = value_range
    if sig >= 0.5:
        # Sparse bright samples (a Monte Carlo render's glint, shot noise) make one blob per
        # glint, not a scatter of specks; centroids still weigh the unsmoothed picture.
        smooth = _gaussian_f32(img, sig)
        lo, hi = (float(v) for v in cv2.minMaxLoc(smooth)[:2])
        # cv2.normalize(smooth, None, 0, 255, NORM_MINMAX, dtype=CV_8U) with the range just
        # found: its scale and shift, computed as it computes them (the same bytes, checked on
        # 58 pictures), without its second pass for the range.
        scale = 255.0 * (1.0 / (hi - lo)) if hi - lo > np.finfo(float).eps else 0.0
        u8 = cv2.convertScaleAbs(smooth, alpha=scale, beta=0.0 - lo * scale)
        # Freed now, not when this returns: the float picture (1 MB at 640 × 400) held through
        # the blobs' search raised the frame's peak of short-lived memory enough that the
        # allocator gave it back to the system after every frame and took it again, page by
        # page, the next (~500 page faults a call, ~0.6 ms of 3.7, in a process given only
        # 640 × 400 8-bit frames; none with it freed here).
        del smooth
    else:
        u8 = cv2.normalize(img, None, 0, 255, cv2.NORM_MINMAX, dtype=cv2.CV_8U)
    hist = _histogram(u8)
    tg8 = glint_threshold(hist, params.glint_percentile, params.glint_min_contrast)
    min_rise = 0.0
    if tg8 is None:
        # Over-exposed: glints are saturated blobs that stand out of a darker surround by
        # the contrast a glint needs, in the input's units.
        tg8 = saturated_floor(hist, params.glint_min_contrast)
        if tg8 is None:
            return [], np.zeros_like(u8), None
        min_rise = params.glint_min_contrast * (value_range[1] - value_range[0])
    floor = 1e-6 * (value_range[1] - value_range[0])
    blobs, bright = glint_blobs(u8, img, tg8, params, noise=max(noise, floor), min_rise=min_rise)
    return blobs, bright, lo + (tg8 + 0.5) / 255.0 * (hi - lo)


#: :func:`jpeg_dc_step`'s bar on the 8 × 8 grid's steps (standard errors over those elsewhere)
_GRID_Z = 5.0
#: :func:`jpeg_dc_step`'s least quantiser step it reports (DC units, i.e. 8 × DN of a block's
#: mean): below 6 the lattice test is weak — a random mean lies within its ±2 of a multiple of
#: 5 with probability 0.8 — and the step (≤ 0.6 DN) is under any camera's noise.
_MIN_DC_Q = 6


@njit(cache=True, nogil=True)
def _row_grid_steps(img):
    """:func:`_grid_steps` along every 8th row of ``img``, from the 4th (x steps)."""
    rows, cols = img.shape
    r8, c8 = rows // 8 * 8, cols // 8 * 8
    n_a = s_a = q_a = n_w = s_w = q_w = 0.0
    for i in range(3, r8, 8):
        for j in range(c8 - 1):
            d = abs(np.float64(img[i, j + 1]) - np.float64(img[i, j]))
            if j % 8 == 7:
                n_a += 1.0
                s_a += d
                q_a += d * d
            else:
                n_w += 1.0
                s_w += d
                q_w += d * d
    return n_a, s_a, q_a, n_w, s_w, q_w


def _grid_steps(img):
    """:func:`jpeg_dc_step`'s step statistics over every 8th row (x steps) and column (y steps),
    from the 4th: (count, Σ|d|, Σd²) of the steps across the 8 × 8 grid's lines, then of the
    others (float64; whole numbers for integer pictures, so exact in either order)."""
    x, y = _row_grid_steps(img), _row_grid_steps(img.T)
    return tuple(a + b for a, b in zip(x, y, strict=True))


def jpeg_dc_step(image: np.ndarray) -> float:
    """The step (DN) between the levels a JPEG's 8 × 8 blocks could take — its quantiser of the
    DC coefficient Q₀₀ over 8 — when ``image`` (2-D uint8) was decoded from a baseline JPEG
    with its block grid at pixel (0, 0), else 0.

    JPEG codes each 8 × 8 block by its DCT, F₀₀ = Σ (f − 128) / 8 quantised to a multiple of
    Q₀₀ (ITU-T T.81, A.3.3 and F.1.1.4; the IJG's table at quality q: 16 × (5000/q or 200 − 2q)
    / 100, e.g. 53 at q15, 14 at q55, 8 at q75). Two tests:

    * the block grid: the mean |step| between neighbouring pixels across the grid's lines (x
      or y ≡ 0 mod 8) exceeds the mean elsewhere by > ``_GRID_Z`` (5) standard errors (every
      8th row and column; a camera's or a render's picture has no grid: the two means differ
      by chance only, 5 σ at odds ~3 × 10⁻⁷);
    * the lattice: the blocks' sums / 8 − 1024 (F₀₀ as decoded) lie within ±2 (a block with
      any AC: 64 rounding errors of σ 0.29, their sum / 8 of σ 0.29) or ±4 (a flat block: its
      64 pixels rounded alike, ±0.5 × 8) of a multiple of Q — for ≥ 90 % of the blocks with no
      clipped pixel (0 or 255) and ≥ 90 % of those not flat; the largest Q from 255 down to
      ``_MIN_DC_Q`` (6) that fits is taken (a multiple of the true Q fits only by chance).

    Exact on the IJG's (OpenCV's) coding at q5–80 of ``test_detect_glint_jpeg25.py``'s
    pictures; 0 for a PNG of the same picture, for q ≳ 82 (Q ≤ 5) and for a nearest-neighbour
    enlargement by 2, 4 or 8 (steps only on the grid's lines, but every 2 × 2 square one
    value, which no JPEG's decoded blocks are: refused by that test). A JPEG cropped off its
    grid is not recognised (0)."""
    img = np.asarray(image)
    if img.dtype != np.uint8 or img.ndim != 2:
        return 0.0
    rows, cols = img.shape
    r8, c8 = rows // 8 * 8, cols // 8 * 8
    if r8 < 16 or c8 < 16:
        return 0.0
    n_a, s_a, q_a, n_w, s_w, q_w = _grid_steps(np.ascontiguousarray(img))
    m_a, m_w = s_a / n_a, s_w / n_w
    se = math.sqrt((q_a / n_a - m_a * m_a) / n_a + (q_w / n_w - m_w * m_w) / n_w)
    if not (se > 0 and m_a - m_w > _GRID_Z * se):
        return 0.0
    if np.array_equal(img[0 : rows - 1 : 2], img[1::2]) and np.array_equal(
        img[:, 0 : cols - 1 : 2], img[:, 1::2]
    ):
        return 0.0  # every 2 × 2 square one value: enlarged by 2, 4 or 8 (its grid is not a JPEG's)
    f = img[:r8, :c8].astype(np.int16)
    b = f.reshape(r8 // 8, 8, c8 // 8, 8)
    lo, hi = b.min(axis=(1, 3)), b.max(axis=(1, 3))
    keep = (lo > 0) & (hi < 255)
    if np.count_nonzero(keep) < 64:
        return 0.0
    dc = b.sum(axis=(1, 3), dtype=np.int64)[keep] / 8.0 - 1024.0
    textured = (hi > lo)[keep]
    tol = np.where(textured, 2.0, 4.0)
    # A sample of ≤ 256 blocks finds the candidates (all Q at once); each is confirmed on all.
    step = max(1, dc.size // 256)
    s_dc, s_tol = dc[::step], tol[::step]
    qs = np.arange(255, _MIN_DC_Q - 1, -1, dtype=np.float64)[:, None]
    near = (np.abs(s_dc - qs * np.round(s_dc / qs)) <= s_tol).mean(axis=1) >= 0.9
    for q in qs[near, 0]:
        hit = np.abs(dc - q * np.round(dc / q)) <= tol
        if hit.mean() >= 0.9 and (not textured.any() or hit[textured].mean() >= 0.9):
            return float(q) / 8.0
    return 0.0


def glints_near(  # noqa: PLR0913 - the picture, its scale, the place, what to return
    img: np.ndarray,
    value_range,
    noise: float,
    centre,
    radius: float,
    floor,
    params,
    mask=None,
    wanted: tuple[float, float] | None = None,
):
    """Glint blobs (dicts, as :func:`glint_blobs`) within ``radius`` px of ``centre`` (x, y) px —
    the pupil's, where corneal glints are — found on the *unsmoothed* picture: after
    :func:`find_glints` smoothed it (``glint_smooth_px`` ≥ 0.5), a glint under a pixel across
    (a wide-angle lens on a small sensor: eyetrackvr's 130° at 240 × 240, each glint one
    saturated pixel with its four neighbours lit by the optics' spread) is at ~0.6 of its peak
    there, below the picture's brightest skin (its 99th percentile, ``floor`` in the input's
    units) and is lost. Here a glint pixel is above that floor and ``glint_level`` of the way
    from its ``glint_window_px`` box mean to the top, as in :func:`find_glints`, on the picture
    scaled by ``value_range`` (min, max), and a blob may be one pixel: isolated hot pixels
    (flat neighbours) were mended before (``detect._mend_hot_pixels``) and a blob's peak must
    still stand ``glint_min_snr`` × ``noise`` above its background. ``mask`` (uint8, the
    picture's shape): the blobs kept are drawn into it (255). ``wanted`` = (max area px, least
    peak, input units): only the blobs no larger and with a peak no lower are returned — the
    others are dropped before their background and centroid are worked out (a caller that
    keeps only those; the same blobs as filtering the whole list)."""
    rows, cols = img.shape
    lo, hi = value_range
    if not hi > lo or floor is None:
        return []
    w = params.glint_window_px
    if w is None:  # the whole picture's box, not the window's
        w = max(5, int(round(min(rows, cols) / 16.0)))
        w = w if w % 2 else w + 1
    m = int(math.ceil(radius)) + w
    cx, cy = centre
    x0, y0 = max(0, int(cx) - m), max(0, int(cy) - m)
    x1, y1 = min(cols, int(cx) + m + 2), min(rows, int(cy) + m + 2)
    if x1 - x0 < 3 or y1 - y0 < 3:
        return []
    sub = np.ascontiguousarray(img[y0:y1, x0:x1])
    scale = 255.0 / (hi - lo)
    u8 = cv2.convertScaleAbs(sub, alpha=scale, beta=-lo * scale)
    floor8 = int(math.floor((floor - lo) * scale))
    one = _one_pixel_params(params, w)
    # (min_rise > 0 but below the noise's rise: the mask returned holds the blobs kept only)
    blobs, kept = glint_blobs(u8, sub, floor8, one, noise=noise, min_rise=1e-300, wanted=wanted)
    if mask is not None:
        cv2.bitwise_or(mask[y0:y1, x0:x1], kept, dst=mask[y0:y1, x0:x1])
    out = []
    for b in blobs:
        x, y = b["centre_px"][0] + x0, b["centre_px"][1] + y0
        if math.hypot(x - cx, y - cy) <= radius:
            out.append({**b, "centre_px": (x, y)})
    return out


def faint_glints_near(  # noqa: PLR0913 - the picture, its noise, the place, the sizes
    img: np.ndarray,
    noise: float,
    centre,
    radius: float,
    width_px: int,
    max_area: float,
    params,
    recut: bool = False,
) -> list[dict]:
    """Glint blobs (dicts, as :func:`glint_blobs`: centre_px, area_px, peak, flux, base) within
    ``radius`` px of ``centre`` (x, y) px that need not be near the top of the picture: an
    unsaturated glint (80 DN over a pupil at 20 DN in a picture whose sclera is at 200) is
    below the picture's 99th percentile — the floor of :func:`find_glints` and
    :func:`glints_near` — yet it stands 27 σ of the noise over its own background.

    Everything is judged on the white top-hat h = I − open(I) of the picture (the grey
    opening by a disc ``width_px`` across, odd ≥ 3, wider than a glint): a glint, narrower
    than the disc, stays in h whole, while anything broader — the iris beside the dark pupil
    (a disc rolls along a convex outline and leaves nothing of it), the sclera, the skin's
    shading — is removed, so h is the light of a spot above the background that follows the
    pupil's edge 5 px away. Pixels with h ≥ ½ ``glint_min_snr`` × ``noise`` (input units: half
    the peak a glint must reach, as ``glint_level`` takes a glint's shoulders) make blobs of
    ``glint_min_area_px`` to ``max_area`` px; a blob is a glint when on h (:func:`_skirt`) its
    peak stands ``glint_min_snr`` × ``noise`` over the median of its surround (8 σ: Gaussian
    noise exceeds it with probability ≪ 10⁻⁹ per pixel) and that surround is flat — its
    10–90 % spread ≤ ``_UNEVEN_SPREAD`` × ``noise`` (2.56 σ for noise alone): a thin bright
    line (a sliver of sclera between the iris and a lid, a gap between lashes) is narrower
    than the disc too, but runs on into its surround. The centroid weighs h above that
    median over the blob and its skirt; ``peak`` is the picture's, ``base`` the peak less the
    rise on h. ``noise`` is raised to the window's σ read at coarser lags
    (:func:`_coarse_noise`) and, blob by blob, to its surround's (:func:`_ring_noise`): a
    JPEG's noise, which second differences miss; each blob dict carries the σ it was judged
    by (``noise``).

    ``recut`` (a JPEG's picture, :func:`jpeg_dc_step`): a blob that is no glint at that
    threshold is cut again at 2, 4, … 32 × it (:func:`_recut`): the coding's ringing along the
    pupil's edge rises over the threshold and joins a glint 18 px inside it into one blob too
    wide for a glint (q25: 43 × 20 px), whose core, ≥ 100 DN over the pupil, is the glint."""
    rows, cols = img.shape
    if not noise > 0:
        return []
    cx, cy = centre
    m = int(math.ceil(radius)) + width_px
    x0, y0 = max(0, int(cx) - m), max(0, int(cy) - m)
    x1, y1 = min(cols, int(cx) + m + 2), min(rows, int(cy) + m + 2)
    if x1 - x0 < width_px or y1 - y0 < width_px:
        return []
    sub = np.ascontiguousarray(img[y0:y1, x0:x1], dtype=np.float32)
    noise = max(noise, _coarse_noise(sub))
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (width_px, width_px))
    hat = cv2.morphologyEx(sub, cv2.MORPH_TOPHAT, disc, borderType=cv2.BORDER_REPLICATE)
    above = cv2.compare(hat, 0.5 * params.glint_min_snr * noise, cv2.CMP_GE)
    contours, hier = cv2.findContours(above, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_NONE)
    if hier is None:
        return []
    hat = hat.astype(np.float64)
    out = []
    levels: dict[float, np.ndarray] = {}
    for c, h in zip(contours, hier[0], strict=True):
        if h[3] != -1:
            continue
        b = _faint_blob(c, (hat, above), sub, noise, width_px, max_area, params)
        found = [b] if b is not None else []
        if recut and b is None:
            found = _recut(c, (hat, levels), sub, noise, width_px, max_area, params)
        for b in found:
            x, y = b["centre_px"][0] + x0, b["centre_px"][1] + y0
            if math.hypot(x - cx, y - cy) <= radius:
                out.append({**b, "centre_px": (x, y)})
    return out


def _recut(c, hats, sub, noise, width_px, max_area, params) -> list[dict]:  # noqa: PLR0913
    """:func:`faint_glints_near`'s blob with outline ``c`` cut again at 2, 4, 8, 16 and 32 ×
    its threshold (½ ``glint_min_snr`` × ``noise`` on the top-hat): the pieces that are glints
    there (:func:`_faint_blob`, judged on that level's mask), each taken at the lowest level
    where it is one (a piece within 1.5 px of one taken is the same spot). ``hats`` = (the
    top-hat, a dict of the levels' masks over the window, filled as needed)."""
    hat, levels = hats
    rows, cols = hat.shape
    bx, by, bw, bh = cv2.boundingRect(c)
    own = np.zeros((bh, bw), np.uint8)
    cv2.drawContours(own, [c], 0, 255, thickness=-1, offset=(-bx, -by))
    out: list[dict] = []
    for f in (2.0, 4.0, 8.0, 16.0, 32.0):
        t = f * 0.5 * params.glint_min_snr * noise
        if t not in levels:
            levels[t] = cv2.compare(hat, t, cv2.CMP_GE)
        above = levels[t]
        piece = cv2.bitwise_and(above[by : by + bh, bx : bx + bw], own)
        if not cv2.countNonZero(piece):
            break
        parts, _ = cv2.findContours(
            piece, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE, offset=(bx, by)
        )
        for p in parts:
            b = _faint_blob(p, (hat, above), sub, noise, width_px, max_area, params)
            if b is not None and all(math.dist(o["centre_px"], b["centre_px"]) > 1.5 for o in out):
                out.append(b)
    return out


def _coarse_noise(sub: np.ndarray, lags=(2, 4)) -> float:
    """The pixel noise σ of the window ``sub`` (float32) seen at coarser lags: Immerkær's
    σ (:func:`~.pupil.noise_sigma`: 1.4826 median|M * I| / 6) with the mask's taps ``k`` px
    apart, for k in ``lags``, the largest (0 for a window too small). For white noise every
    lag gives the same σ (the mask's coefficients are the same, its taps independent); a
    JPEG's quantisation removes the high frequencies the one-pixel mask sees and keeps the
    blocks' low ones, which make the specks a glint must stand out of (noise of 3 DN coded at
    quality 75: σ 0.25 DN at lag 1, 1.0 at lag 2, 2.0 at lag 4 over the whole picture)."""
    out = 0.0
    rows, cols = sub.shape
    for k in lags:
        if rows <= 2 * k or cols <= 2 * k:
            continue
        out = max(out, 1.4826 * float(np.median(immerkaer_abs(sub, k))) / 6.0)
    return out


def broad_glints_near(  # noqa: PLR0913 - the picture, its noise, the place, the sizes
    img: np.ndarray,
    noise: float,
    centre,
    radius: float,
    width_px: int,
    max_width_px: float,
    max_area: float,
    params,
    wanted: int,
) -> list[dict]:
    """Defocused glints within ``radius`` px of ``centre`` (x, y) px: blobs (dicts as
    :func:`faint_glints_near`'s, plus ``sigma_px``) found by :func:`faint_glints_near` with
    discs wider than ``width_px`` — 2 w − 1, then again, up to ``max_width_px`` — until
    ``wanted`` spots are found (or none wider is tried), each centred by
    :func:`fit_spot`, for a picture whose glints the default disc missed.

    A defocused camera spreads a glint into a broad, unsaturated bump (a saturated
    glint blurred by a Gaussian of σ 3 px: 51 DN over the iris, ~11 px across at half its
    height) — still many σ of the noise over its background, but wider than the disc of
    :func:`faint_glints_near` (a quarter of the pupil's major axis), which leaves it no
    top-hat blob narrow enough to pass (the opening by a disc narrower than the bump keeps
    only its tip, and the blob of its threshold is wider than the disc). A wider disc keeps
    the bump; the tests of :func:`faint_glints_near` (peak ``glint_min_snr`` × ``noise`` over a
    flat surround on the top-hat) still apply. The top-hat's centroid of a bump as wide as
    the disc is biased toward the side whose background the opening reads lower (1.5 px off
    for σ 4 blur beside the pupil's edge), hence the fit. A blob whose fit fails, or whose
    half-height area (2 ln 2 π σ² px) exceeds ``max_area``, is left out. Blobs found at a
    narrower disc are kept; a wider disc's blob within its equivalent radius of one of them is
    the same spot."""
    out: list[dict] = []
    w = 2 * int(width_px) - 1
    while w <= max_width_px and len(out) < wanted:
        for b in faint_glints_near(img, noise, centre, radius, w, w * w, params):
            r = math.sqrt(b["area_px"] / math.pi)
            if any(math.dist(o["centre_px"], b["centre_px"]) <= r for o in out):
                continue
            fitted = fit_spot(img, noise, b, params)
            if (
                fitted is not None
                and 2.0 * math.log(2.0) * math.pi * fitted["sigma_px"] ** 2 <= max_area
                and math.dist(fitted["centre_px"], centre) <= radius
            ):
                out.append(fitted)
        w = 2 * w - 1
    return out


#: :func:`fit_spot`'s cap on the least-squares evaluations (≈ 2–5× what a spot's fit takes: 19–65
#: on three vr-offaxis frames' 27 fits, MINPACK's Levenberg–Marquardt).
_FIT_MAX_EVALUATIONS = 100


@njit(cache=True, nogil=True)
def _spot_residual(q, xs, ys, xc, yr, win, out):
    """:func:`fit_spot`'s residuals into ``out`` (n,) and returned: B0 + bx xc + by yr +
    A exp(−((x − px)² + (y − py)²) / 2 s²) − win at the window's n pixels (x, y) = (``xs``,
    ``ys``) px, (xc, yr) their offsets from the window's centre pixel, q = (px, py, A, s, B0,
    bx, by)."""
    px, py, a, s, b0, bx, by = q[0], q[1], q[2], q[3], q[4], q[5], q[6]
    two_s2 = 2.0 * s * s
    for i in range(xs.size):
        dx, dy = xs[i] - px, ys[i] - py
        g = math.exp(-(dx * dx + dy * dy) / two_s2)
        out[i] = b0 + bx * xc[i] + by * yr[i] + a * g - win[i]
    return out


@njit(cache=True, nogil=True)
def _spot_jacobian(q, xs, ys, jac):
    """:func:`_spot_residual`'s derivatives by px, py, A and s into the first four rows of
    ``jac`` (7, n) (its last three, the plane's, are constant: 1, xc, yr), returned:
    ∂/∂px = A g dx / s², ∂/∂py = A g dy / s², ∂/∂A = g, ∂/∂s = A g d² / s³."""
    px, py, a, s = q[0], q[1], q[2], q[3]
    s2 = s * s
    two_s2 = 2.0 * s2
    for i in range(xs.size):
        dx, dy = xs[i] - px, ys[i] - py
        d2 = dx * dx + dy * dy
        g = math.exp(-d2 / two_s2)
        ag = a * g / s2
        jac[0, i] = ag * dx
        jac[1, i] = ag * dy
        jac[2, i] = g
        jac[3, i] = ag * d2 / s
    return jac


def fit_spot(img: np.ndarray, noise: float, blob: dict, params, min_half: int = 2) -> dict | None:
    """The centre of an unsaturated spot (:func:`broad_glints_near`'s, and ``detect``'s for
    :func:`faint_glints_near`'s): ``img`` (rows, cols) the picture, input units; ``noise`` its
    pixel σ; ``blob`` a dict with centre_px (x, y) px, area_px, peak and base (input units).
    Raises nothing (a failed fit gives None). A least-squares fit of
    B0 + bx (x − c) + by (y − r) + A exp(−|p − p0|² / 2 s²) to the picture (input units) in the
    square of half-side ⌈1.5 s₀⌉ px (≥ ``min_half``: 2 for :func:`broad_glints_near`; 3 for
    ``detect``'s faint glints — 7 parameters on a 5 × 5 window leave a 10 σ glint's height
    and width confused, s 2.65 px and twice the rise, 0.9 px off) around the blob's top-hat
    centroid (c, r rounded),
    s₀ = ½ its equivalent radius. The window holds the bump's top, where it dominates; a plane
    takes the local slope of its background (the pupil's blurred edge beside it) — a wider
    window reaches the edge's curvature, which no plane follows (on σ 1.5-4 blurred
    pictures: ≤ 0.45 px off with this window, ≤ 0.6 px with 2.5 s₀, the top-hat's centroid
    ≤ 1.7 px). None when the fit does not rise ``glint_min_snr`` × ``noise``, its σ is not
    within [0.5, 2 s₀ + 2] px, its centre left the window or it did not converge within
    ``_FIT_MAX_EVALUATIONS`` evaluations. Returns the blob with centre_px,
    sigma_px (the fit's s), peak/base the fit's A + B0 and B0 at p0, and fit_rms the RMS of
    its residuals (input units).

    The fit is MINPACK's Levenberg–Marquardt (``lmder``, Moré 1978) through
    ``scipy.optimize.leastsq``, its parameters scaled by the Jacobian's columns (``diag``
    None) and tolerances 1e-8 (``least_squares``' defaults): the same iterations as
    ``least_squares(method="lm")`` (SciPy ≥ 1.16) without its wrappers' ~20 µs a call. On
    session 31's 150 design-run frames (vr-offaxis, 850/940 nm; 3 395 fits, ~23 a frame:
    faint blobs near the pupil, lashes' gaps among them) it took 2.6 CPU-s against 23.5 with
    ``least_squares``' default trust-region method (TRF: 40–100 evaluations a fit, and the
    cap reached by most of the blobs that are no spot), the frames' answers the same but one
    refusal's wording; 1.2 CPU-s since session 34, the residual and Jacobian compiled
    (:func:`_spot_residual`; their exp is libm's, not NumPy's SIMD one, which differs in the
    last bit on ~5 % of arguments: those frames, session 29's 322 + 120 fingerprint pictures
    and six vr-offaxis people's frames answered to the last digit as before)."""
    from scipy.optimize import leastsq  # (only on this path)

    rows, cols = img.shape
    x, y = blob["centre_px"]
    s0 = max(1.0, 0.5 * math.sqrt(blob["area_px"] / math.pi))
    k = max(min_half, int(math.ceil(1.5 * s0)))
    c, r = int(round(x)), int(round(y))
    x0, y0, x1, y1 = max(0, c - k), max(0, r - k), min(cols, c + k + 1), min(rows, r + k + 1)
    if x1 - x0 < 5 or y1 - y0 < 5:
        return None
    win = img[y0:y1, x0:x1].astype(np.float64)
    yy, xx = np.mgrid[y0:y1, x0:x1].astype(np.float64)
    xc, yr = xx - c, yy - r
    # the residual and its Jacobian by rows of parameters (MINPACK's col_deriv: no transposed
    # copy; its last three rows, the plane's, constant) by compiled loops over the window's
    # pixels (:func:`_spot_residual`, :func:`_spot_jacobian`): ~1 µs a call where the same
    # NumPy expressions took ~7 (a fit takes 20–100 of each; the analytic Jacobian saves the
    # 7 calls a numerical one costs). MINPACK copies what each returns.
    res = np.empty(win.size)
    jac = np.empty((7, win.size))
    jac[4], jac[5], jac[6] = 1.0, xc.ravel(), yr.ravel()
    xs, ys, xcs, yrs, ws = xx.ravel(), yy.ravel(), xc.ravel(), yr.ravel(), win.ravel()

    def resid(q):
        return _spot_residual(q, xs, ys, xcs, yrs, ws, res)

    def jacobian(q):
        return _spot_jacobian(q, xs, ys, jac)

    rise = float(blob["peak"] - blob["base"])
    q0 = np.array([x, y, rise, s0, float(blob["base"]), 0.0, 0.0])
    try:
        # one still wandering after _FIT_MAX_EVALUATIONS is not a spot there (seen: the centre
        # walking off the window over an edge or a lash; SciPy's default cap of 700
        # evaluations reached in 14 of 29 fits of a vr-offaxis frame, ~2.6 CPU-s)
        # (floating-point warnings off: a wandering fit's overflow, or its covariance's, which
        # leastsq works out unasked, is judged by the tests below, not printed)
        with np.errstate(all="ignore"):
            q, _, _, _, ier = leastsq(
                resid, q0, Dfun=jacobian, full_output=True, col_deriv=True, ftol=1e-8,
                xtol=1e-8, gtol=1e-8, maxfev=_FIT_MAX_EVALUATIONS,
            )  # fmt: skip
    except (ValueError, TypeError, np.linalg.LinAlgError):
        return None
    if ier not in (1, 2, 3, 4) or not np.all(np.isfinite(q)):
        # 5: the evaluation cap reached, not converged, its centre undetermined; 0, 6–8:
        # improper input, or tolerances no step can meet
        return None
    px, py, a, s, b0, bx, by = (float(v) for v in q)
    if not (
        a >= params.glint_min_snr * noise
        and 0.5 <= abs(s) <= 2.0 * s0 + 2.0
        and x0 <= px <= x1 - 1
        and y0 <= py <= y1 - 1
    ):
        return None
    base = b0 + bx * (px - c) + by * (py - r)
    rms = float(np.sqrt(np.mean(resid(q) ** 2)))
    return {
        **blob,
        "centre_px": (px, py),
        "sigma_px": abs(s),
        "peak": base + a,
        "base": base,
        "fit_rms": rms,
    }


def _disc(img: np.ndarray, centre, radius: float, core: float | None = None):
    """The pixels of ``img`` within ``radius`` px of ``centre`` (x, y) px: (values float64,
    their squared distances px², both 1-D), or None when fewer than 9 lie in the picture.
    With ``core`` (a level), a third array: whether each pixel is in the 8-connected region
    ≥ ``core`` holding the brightest pixel within 1.5 px of the centre (the spot's core, not
    a brighter neighbour's — the iris beside a glint on the pupil)."""
    rows, cols = img.shape
    x, y = centre
    k = int(math.ceil(radius))
    c, r = int(round(x)), int(round(y))
    x0, y0, x1, y1 = max(0, c - k), max(0, r - k), min(cols, c + k + 1), min(rows, r + k + 1)
    if x1 <= x0 or y1 <= y0:
        return None
    win = img[y0:y1, x0:x1].astype(np.float64)
    d2 = (np.arange(x0, x1)[None, :] - x) ** 2 + (np.arange(y0, y1)[:, None] - y) ** 2
    inside = d2 <= radius * radius
    if int(inside.sum()) < 9:
        return None
    if core is None:
        return win[inside], d2[inside]
    above = ((win >= core) & inside).astype(np.uint8)
    _, lab = cv2.connectedComponents(above, connectivity=8)
    seed = np.where(d2 <= 2.25, win, -np.inf)
    k = np.unravel_index(int(np.argmax(seed)), seed.shape)
    own = (lab == lab[k]) & (above > 0) if above[k] else np.zeros_like(inside)
    return win[inside], d2[inside], own[inside]


def spot_sigma(img: np.ndarray, spot: dict, top: float, noise: float) -> float | None:
    """The Gaussian σ (px) of a spot's profile in ``img`` (rows, cols; input units), read from
    its unclipped skirt: ``spot`` a dict with centre_px (x, y) px, area_px, peak and base
    (input units, as :func:`glint_blobs`' blobs or ``detect``'s glints); ``top`` the picture's
    saturation level (pixels at it are clipped, left out; ``inf``: none); ``noise`` the pixel
    σ. The core's radius r₅₀ (√(n / π), n the pixels rising ≥ ½ the spot's rise within its
    equivalent radius + 1 px) sets the disc read: r₅₀ + 2 px, where a Gaussian of σ ≤ 2 px has
    fallen from ½ to ~1/10 of its rise and whatever lies beside the spot (the pupil's edge a
    few px away, the iris) mostly does not reach. Its pixels rising v = I − base by 4 ×
    ``noise`` to 90 % of the rise and under ``top`` give ln v = ln A − d² / 2σ² (d from the
    centre), fitted by least squares weighted by v² (ln v's variance is σₙ² / v²), then again
    without the pixels more than 3 ``noise`` over the first fit (something else's light): a
    clipped spot's skirt holds its width, its plateau none. Sampled at pixel centres, so σ²
    includes the pixel's own 1/12 px². None when fewer than 3 pixels qualify or the profile
    does not fall (slope ≥ 0). Raises nothing."""
    if spot.get("base") is None or not spot["peak"] > spot["base"]:
        return None
    rise = spot["peak"] - spot["base"]
    got = _disc(img, spot["centre_px"], math.sqrt(spot["area_px"] / math.pi) + 1.0)
    if got is None:
        return None
    r50 = math.sqrt(float((got[0] >= spot["base"] + 0.5 * rise).sum()) / math.pi)
    got = _disc(img, spot["centre_px"], r50 + 2.0)
    if got is None:
        return None
    val, d2 = got
    v = val - spot["base"]
    use = (v >= max(4.0 * noise, 1e-12)) & (v <= 0.9 * rise) & (val < top)
    slope = None
    for _ in range(2):
        if int(use.sum()) < 3:
            return None
        vv, dd = v[use], d2[use]
        w = vv * vv
        lv = np.log(vv)
        sw, sx, sy = w.sum(), (w * dd).sum(), (w * lv).sum()
        sxx, sxy = (w * dd * dd).sum(), (w * dd * lv).sum()
        den = sw * sxx - sx * sx
        if not den > 0:
            return None
        slope = (sw * sxy - sx * sy) / den
        if not slope < 0:
            return None
        icpt = (sy - slope * sx) / sw
        use = use & (v - np.exp(icpt + slope * d2) <= 3.0 * noise)
    return math.sqrt(-0.5 / slope)


def block_or_blur(  # noqa: PLR0913 - the picture, the spot, the others' width, clip, noise
    img: np.ndarray, spot: dict, sigma: float, top: float, noise: float
) -> tuple[float, int] | None:
    """How much better a spot fits a block of pixels with no blur than a Gaussian spot of σ
    ``sigma`` px: (Δ = χ²_glint − χ²_block, the block's extra free parameters). ``spot`` a dict
    as :func:`spot_sigma`'s, ``img`` (rows, cols, input units), ``top`` the saturation level
    (``inf``: none), ``noise`` the pixel σ (> 0). Over the disc of radius √(area / π) + 2
    ``sigma`` + 1 px about the spot's centre — out to where a Gaussian of that σ has fallen to
    the noise — the block model takes each core pixel (≥ half the spot's rise over its base,
    8-connected to its top) at its own value and every other pixel at one background B (their
    mean); the glint model is min(B' + A exp(−d² / 2σ²), ``top``) about the spot's centre, A
    and B' fitted (least squares). χ² = Σ residual² / ``noise``². Pixels over the core's level
    not joined to it (the iris beside a glint on the pupil) are left out of both; the rest of
    anything else in the disc (the pupil's edge) costs both models alike. None when the disc
    is cut to under 9 pixels, the spot has no rise, or no pixel lies outside its core. Raises
    nothing."""
    from scipy.optimize import least_squares  # (only on this rare path)

    if spot.get("base") is None or not spot["peak"] > spot["base"] or not noise > 0:
        return None
    got = _disc(
        img,
        spot["centre_px"],
        math.sqrt(spot["area_px"] / math.pi) + 2.0 * sigma + 1.0,
        spot["base"] + 0.5 * (spot["peak"] - spot["base"]),
    )
    if got is None:
        return None
    val, d2, core = got
    # Pixels over the core's level not joined to it are another thing's light (the iris
    # beside a glint on the pupil): neither model's.
    keep = core | (val < spot["base"] + 0.5 * (spot["peak"] - spot["base"]))
    val, d2, core = val[keep], d2[keep], core[keep]
    n_core = int(core.sum())
    if n_core == 0 or n_core == val.size:
        return None
    rest = val[~core]
    chi_block = float(((rest - rest.mean()) ** 2).sum()) / noise**2
    g = np.exp(-0.5 * d2 / sigma**2)

    # Unclipped (no pixel at the top), the glint model is linear in A and B': solved directly.
    mat = np.column_stack([g, np.ones_like(g)])
    sol = np.linalg.lstsq(mat, val, rcond=None)[0]
    if float(val.max()) >= top or float(sol[0] * g.max() + sol[1]) > top:

        def resid(q):
            return np.minimum(q[1] + q[0] * g, top) - val

        a0 = float(max(spot["peak"] - spot["base"], noise))
        fit = least_squares(resid, [a0, float(spot["base"])], max_nfev=200)
        rss = float(2.0 * fit.cost)
    else:
        rss = float(((mat @ sol - val) ** 2).sum())
    chi_glint = rss / noise**2
    return chi_glint - chi_block, max(1, n_core - 1)


def _faint_blob(c, hats, sub, noise, width_px, max_area, params) -> dict | None:  # noqa: PLR0913
    """One blob of :func:`faint_glints_near` from its outline ``c`` on the top-hat ``hat``
    (float64) of the window ``sub`` (the picture's, float32), in the window's pixels, ``hats``
    = (hat, the mask of its pixels over the blobs' threshold, uint8); None when it is not a
    glint there (its doc)."""
    hat, above = hats
    bx, by, bw, bh = cv2.boundingRect(c)
    if bw * bh < params.glint_min_area_px or min(bw, bh) > width_px:
        return None
    rows, cols = hat.shape
    r = max(2, int(math.ceil(math.sqrt(cv2.contourArea(c) / math.pi + 1.0))))
    wx0, wy0 = max(0, bx - r - 2), max(0, by - r - 2)
    wx1, wy1 = min(cols, bx + bw + r + 2), min(rows, by + bh + r + 2)
    if _value_range(hat[wy0:wy1, wx0:wx1]) < params.glint_min_snr * noise:
        # The peak (on the blob, in the window) over the base (a median of the window's
        # values, or its least) is at most the window's range: under the bar, the blob is no
        # glint, told without its mask and skirt (a noisy picture's top-hat holds 10^4 specks:
        # 8 LEDs' glints merged into a ring were looked for over the whole picture, 0.3-0.8 s).
        return None
    own = np.zeros((wy1 - wy0, wx1 - wx0), np.uint8)
    cv2.drawContours(own, [c], 0, 255, thickness=-1, offset=(-wx0, -wy0))
    area = cv2.countNonZero(own)
    if area < params.glint_min_area_px or area > max_area:
        return None
    r = max(2, int(math.ceil(math.sqrt(area / math.pi))))
    d_own = cv2.distanceTransform(cv2.bitwise_not(own), cv2.DIST_L2, 3)
    base, peak, wgt, spread = _skirt(hat[wy0:wy1, wx0:wx1], own, d_own, d_own, False, float(r))
    cx, cy = bx + 0.5 * (bw - 1), by + 0.5 * (bh - 1)
    if peak - base < params.glint_min_snr * noise:
        return None  # (already under the bar: the local σ below can only raise it)
    req = math.sqrt(area / math.pi)
    noise = max(noise, _ring_noise(hat, above, cx, cy, req + r, req + r + _RING_PX))
    tot = float(wgt.sum())
    if peak - base < params.glint_min_snr * noise or spread > _UNEVEN_SPREAD * noise or tot <= 0:
        return None
    xs = np.arange(wx0, wx1, dtype=np.float64)
    ys = np.arange(wy0, wy1, dtype=np.float64)
    top = float(cv2.minMaxLoc(sub[wy0:wy1, wx0:wx1], own)[1])
    return {
        "centre_px": (
            float((wgt.sum(axis=0) * xs).sum() / tot),
            float((wgt.sum(axis=1) * ys).sum() / tot),
        ),
        "area_px": float(area),
        "peak": top,
        "flux": tot,
        "base": top - (peak - base),
        "noise": noise,
    }


@njit(cache=True, nogil=True)
def _value_range(win):
    """The largest less the least value of ``win`` (2-D float, not empty); NaN when it holds
    a NaN."""
    lo = hi = win[0, 0]
    for v in win.ravel():
        if v != v:
            return np.nan
        lo, hi = min(lo, v), max(hi, v)
    return hi - lo


def in_bright_run(img: np.ndarray, blob: dict, level: float, noise: float = 0.0) -> bool:
    """Whether ``blob`` (a dict of :func:`glint_blobs`: centre_px (x, y) px, area_px, peak,
    base, in ``img``'s units) is a piece of a longer bright run rather than an isolated spot:
    the pixels of ``img`` (rows, cols, the unsmoothed picture) at its peak's level — ≥ max(base
    + ``level`` × (peak − base), peak − ``noise``), input units — 8-connected to the blob's
    brightest pixel (within its equivalent radius r + ½ px of its centre), reach the edge of
    the square of half-side ceil(r) + 3 px around it: the skirt :func:`glint_blobs` weighs and
    reads the background beyond.

    A glint is the brightest thing per pixel, and its pixels at its peak's level are its core,
    inside its blob: a spot whose surround is darker all round stops there. A gap between dark
    lashes on a saturated, sunlit lid (eyelume's vr-offaxis at 850 nm with the sun 40° up:
    2-9 px at 1016 DN over a ~550 DN surround, the lashes cutting the lid into strips) passes
    the local glint tests — it is saturated and its box mean holds the dark lashes — but at
    that level it runs on along its strip of lid, 16-25 px, out of any glint's skirt. Callers
    give ``level`` above the blob's own threshold and ``noise`` a multiple of the pixel noise
    σ that the noise cannot tell from the peak (``detect``: ``glint_min_snr`` σ)."""
    x, y = blob["centre_px"]
    r = math.sqrt(max(blob["area_px"], 1.0) / math.pi)
    h = int(math.ceil(r)) + 3
    thr = max(blob["base"] + level * (blob["peak"] - blob["base"]), blob["peak"] - noise)
    # (NumPy compares a float array with a Python float in the array's precision: the
    # region's test, ``win >= thr``, was made so; the edge and seed tests in float64.)
    thr_a = float(img.dtype.type(thr)) if img.dtype.kind == "f" else thr
    return _bright_run(img, (x, y), (int(round(x)), int(round(y))), r, h, thr, thr_a)


@njit(cache=True, nogil=True)
def _bright_run(img, xy, cw, r, h, thr, thr_a):
    """:func:`in_bright_run`'s test, compiled: the square of half-side ``h`` about the pixel
    ``cw`` = (column, row) nearest ``xy`` = (x, y) (Python's round), cut by the picture's edge;
    False when no pixel on its uncut edges is ≥ ``thr``; the seed, the brightest pixel within
    ``r`` + ½ px of (x, y) (the first in row order), False when none or under ``thr``; then
    whether the 8-connected region of the square's pixels ≥ ``thr_a`` (``thr`` as the
    picture's dtype compares it) holding the seed reaches an uncut edge (a flood fill: the
    seed's label of ``cv2.connectedComponents``)."""
    rows, cols = img.shape
    x, y = xy
    c, w = cw
    x0, y0, x1, y1 = c - h, w - h, c + h + 1, w + h + 1
    if x1 <= 0 or y1 <= 0 or x0 >= cols or y0 >= rows:
        return False
    box = (max(0, x0), max(0, y0), min(cols, x1), min(rows, y1))
    uncut = (x0 >= 0, x1 <= cols, y0 >= 0, y1 <= rows)  # left, right, top, bottom
    if not _edge_at(img, box, uncut, thr):
        return False  # nothing at that level on the square's edge (most glints)
    best = -np.inf
    sy, sx = -1, -1
    k = int(math.ceil(r + 0.5))
    for yy in range(max(box[1], w - k), min(rows, w + k + 1)):
        for xx in range(max(box[0], c - k), min(cols, c + k + 1)):
            v = np.float64(img[yy, xx])
            if (xx - x) ** 2 + (yy - y) ** 2 <= (r + 0.5) ** 2 and v > best:
                best, sy, sx = v, yy, xx
    if sy < 0 or best < thr:
        return False
    # (the seed is in the region: ≥ thr, so ≥ thr rounded to the picture's float type)
    return _fill_reaches(img, box, uncut, (sy, sx), thr_a)


@njit(cache=True, nogil=True)
def _edge_at(img, box, uncut, thr):
    """Whether a pixel of ``img`` on an uncut edge of ``box`` = (x0, y0, x1, y1) is ≥ ``thr``
    (float64); ``uncut`` = (left, right, top, bottom)."""
    wx0, wy0, wx1, wy1 = box
    left, right, top, bottom = uncut
    for yy in range(wy0, wy1):
        if left and np.float64(img[yy, wx0]) >= thr:
            return True
        if right and np.float64(img[yy, wx1 - 1]) >= thr:
            return True
    for xx in range(wx0, wx1):
        if top and np.float64(img[wy0, xx]) >= thr:
            return True
        if bottom and np.float64(img[wy1 - 1, xx]) >= thr:
            return True
    return False


@njit(cache=True, nogil=True)
def _fill_reaches(img, box, uncut, seed, thr):
    """Whether the 8-connected region of ``box``'s pixels ≥ ``thr`` holding ``seed`` (row,
    column; in it) reaches an uncut edge of the box (as :func:`_edge_at`'s)."""
    wx0, wy0, wx1, wy1 = box
    left, right, top, bottom = uncut
    hh, ww = wy1 - wy0, wx1 - wx0
    seen = np.zeros((hh, ww), np.uint8)
    stack = np.empty(hh * ww, np.int64)
    seen[seed[0] - wy0, seed[1] - wx0] = 1
    stack[0] = (seed[0] - wy0) * ww + (seed[1] - wx0)
    n = 1
    while n:
        n -= 1
        i, j = stack[n] // ww, stack[n] % ww
        edge_x = (left and j == 0) or (right and j == ww - 1)
        if edge_x or (top and i == 0) or (bottom and i == hh - 1):
            return True
        for ii in range(max(0, i - 1), min(hh, i + 2)):
            for jj in range(max(0, j - 1), min(ww, j + 2)):
                if seen[ii, jj] == 0 and np.float64(img[wy0 + ii, wx0 + jj]) >= thr:
                    seen[ii, jj] = 1
                    stack[n] = ii * ww + jj
                    n += 1
    return False


@functools.lru_cache(maxsize=16)
def _one_pixel_params(params, w: int):
    """``params`` with ``glint_window_px`` = w and one-pixel blobs taken
    (:func:`glints_near`), made once per (params, w): ``dataclasses.replace`` builds all of
    its ~66 fields anew (~40 µs a frame); params are frozen and hashable."""
    return dataclasses.replace(params, glint_window_px=w, glint_close_px=1, glint_min_area_px=1)


def _histogram(u8: np.ndarray) -> np.ndarray:
    """``cv2.calcHist([u8], [0], None, [256], [0, 256]).ravel()`` (the counts of each 8-bit
    level, float32 — exact below 2²⁴ pixels, as calcHist's): counted by one compiled pass
    into four interleaved tables (:func:`_counts4`), ~1.3 × faster than calcHist."""
    if u8.size >= 1 << 24 or not u8.flags.c_contiguous:
        return cv2.calcHist([u8], [0], None, [256], [0, 256]).ravel()
    return _counts4(u8.ravel()).astype(np.float32)


@njit(cache=True, nogil=True)
def _counts4(v):
    """Counts of each value 0–255 of ``v`` (1-D uint8), int64: four tables filled in turn (a
    count does not wait on the one before it, which the same value often is), then summed."""
    h = np.zeros((4, 256), np.int64)
    n4 = v.size - v.size % 4
    for i in range(0, n4, 4):
        h[0, v[i]] += 1
        h[1, v[i + 1]] += 1
        h[2, v[i + 2]] += 1
        h[3, v[i + 3]] += 1
    for i in range(n4, v.size):
        h[0, v[i]] += 1
    return h[0] + h[1] + h[2] + h[3]


def _gaussian_f32(img: np.ndarray, sigma: float) -> np.ndarray:
    """``cv2.GaussianBlur(img.astype(np.float32), (0, 0), sigma)``. With kernels of 9 taps or
    more (shorter ones take another path inside OpenCV) through ``cv2.sepFilter2D`` with the
    kernel GaussianBlur makes for a float picture (``getGaussianKernel`` of size round(8 σ + 1)
    | 1, float32; its default border) on the float32 picture: the same floats (400 random
    pictures of 9–700 px a side, uint16, int16, float32 and float64) in ~0.85 ×
    GaussianBlur's time; a float32 picture needs no copy, others are converted first (16 bits
    read directly is 3 × slower: not taken). An 8-bit picture is read directly (0.7 × the
    time, no float copy): NOT always the same floats — 28 of 60 random 8-bit pictures differ
    from GaussianBlur's, by ≤ 2 × 10⁻⁷ relative (float rounding; the detector's figures since
    8562ede are this path's)."""
    ksize = int(np.rint(8.0 * sigma + 1.0)) | 1
    if ksize >= 9:
        k = cv2.getGaussianKernel(ksize, sigma, cv2.CV_32F)
        src = img if img.dtype in (np.uint8, np.float32) else img.astype(np.float32)
        return cv2.sepFilter2D(src, cv2.CV_32F, k, k, borderType=cv2.BORDER_REFLECT_101)
    return cv2.GaussianBlur(img.astype(np.float32), (0, 0), sigma)


def glint_blobs(
    u8: np.ndarray,
    img: np.ndarray,
    floor8: int,
    params,
    noise: float = 0.0,
    min_rise: float = 0.0,
    wanted: tuple[float, float] | None = None,
) -> tuple[list[dict], np.ndarray]:
    """Bright blobs as dicts (centre_px, area_px, peak) and the (closed) bright mask (0/255).

    The centroid is weighted by max(I − B, 0) over the blob and a skirt ``m`` = max(2, ⌈r⌉) px
    around it (r its equivalent radius), B the median of the window around it outside every
    blob's skirt; where skirts of neighbouring blobs meet, a pixel goes to the nearer blob
    (fragments of the mask under ``glint_min_area_px`` are no blob: they are a glint's own
    light, weighed when within its skirt). The
    spot's whole profile, down to its background, then weighs in: a saturated (flat-topped)
    spot's centroid is as smooth in its position as an unsaturated one's.

    A blob's ``rise`` is judged against the larger of ``noise`` and its surround's own σ
    (:func:`_ring_noise`, the other blobs and their skirts left out): a JPEG's sclera specks
    8–10 DN over a surround whose σ is 1.5 DN are no glints where the picture's σ (0.5 DN)
    would pass them. Each blob dict carries the σ it was judged by (``noise``).

    With ``min_rise`` > 0 (an over-exposed picture, :func:`saturated_floor`) a blob's peak must
    also stand ``min_rise`` (input units) above its local background — a saturated fragment of
    skin or sclera, whose surround is saturated too, is not a glint — and the bright mask
    returned holds only the glints found (not the saturated skin).

    ``wanted`` = (max area px, least peak, input units): blobs larger or with a lower peak are
    left out before their skirt is worked out (:func:`glints_near`'s callers keep no others).
    """
    rows, cols = u8.shape
    above, bright, (x0, y0, x1, y1) = _bright_mask(u8, floor8, params)
    if x1 <= x0:
        return [], bright
    # The outlines in the box holding the mask (0 on its edges): the same, with its offset.
    contours, hier = cv2.findContours(
        bright[y0:y1, x0:x1], cv2.RETR_CCOMP, cv2.CHAIN_APPROX_NONE, offset=(x0, y0)
    )
    if hier is None:
        return [], bright
    max_area = max(params.glint_min_area_px, params.glint_max_area_frac * rows * cols)
    tops = [c for c, h in zip(contours, hier[0], strict=True) if h[3] == -1]
    rise = max(params.glint_min_snr * noise, min_rise)
    blobs = []
    kept = []
    areas = [cv2.contourArea(c) + 0.5 * len(c) + 1.0 for c in tops]
    # Fragments too small to be a glint (one pixel) are not other blobs sharing out a skirt:
    # they are a noisy glint's own light, broken off by the threshold (module doc, Centroid).
    fragments = [c for c, a in zip(tops, areas, strict=True) if a < params.glint_min_area_px]
    others = bright
    if fragments:
        others = bright.copy()
        cv2.drawContours(others, fragments, -1, 0, thickness=-1)
    for c, approx_area in zip(tops, areas, strict=True):
        if params.glint_min_area_px <= approx_area <= 1.5 * max_area + 4:
            if wanted is not None and bright is above and len(c) > wanted[0]:
                # Unclosed, each point of the outline is a pixel of the blob: more distinct
                # points than the largest area wanted, it is left out before its mask is drawn
                # (most of glints_near's blobs are: lit skin, lashes' gaps).
                if _distinct_points(c.reshape(-1, 2), cols) > wanted[0]:
                    continue
            b = _blob(c, approx_area, above, others, img, (max_area, rise, noise, wanted), params)
            if b is not None:
                blobs.append(b)
                kept.append(c)
    if min_rise > 0:
        bright = np.zeros_like(bright)
        cv2.drawContours(bright, kept, -1, 255, thickness=-1)
    return blobs, bright


@njit(cache=True, nogil=True)
def _distinct_points(xy, cols):
    """How many distinct (x, y) rows the outline ``xy`` ((n, 2) int, OpenCV's points) holds in
    a picture ``cols`` wide: ``len(np.unique(y × cols + x))``, by a sort of those keys."""
    n = xy.shape[0]
    if n == 0:
        return 0
    keys = np.empty(n, np.int64)
    for i in range(n):
        keys[i] = np.int64(xy[i, 1]) * cols + np.int64(xy[i, 0])
    keys.sort()
    count = 1
    for i in range(1, n):
        count += keys[i] != keys[i - 1]
    return count


def _bright_mask(u8: np.ndarray, floor8: int, params):
    """Glint pixels of the picture smoothed by ``glint_smooth_px`` (above the floor and
    ``glint_level`` of the way from the local mean to 255) and the same mask closed by
    ``glint_close_px`` (uint8 0/255 both), and a box (x0, y0, x1, y1) holding every non-zero
    pixel of both with a 0 border (or the picture's edge) around them.

    Glint pixels are above ``floor8``, ~1 % of a picture (glints and the brightest skin): the
    box mean and the comparison are worked only at those pixels (in the rows holding any, on
    the box of them padded by the box mean's half-width), and the closing only on the box of
    the glint pixels found (padded by k // 2 + 1, as :func:`~.pupil._closing` argues) — the
    same bytes as on the whole picture. (Pixels above the floor are often spread over the
    whole frame — single bright noise pixels, skin — while the glint pixels that pass the
    local test are a few small blobs: closing and outlining the box of the former cost a
    full-frame pass each.)"""
    rows, cols = u8.shape
    w = params.glint_window_px
    if w is None:
        w = max(5, int(round(min(rows, cols) / 16.0)))
        w = w if w % 2 else w + 1
    k = params.glint_close_px
    if k is None:
        k = int(round(min(rows, cols) / 160.0))
        k = k if k % 2 else k + 1
    lut = _local_floor(params.glint_level, floor8)
    above = np.zeros_like(u8)
    # The rows holding any pixel above the floor and the first and last column of those
    # pixels: their box, as cv2.boundingRect finds it; the rows, where the pixels are (one
    # compiled pass, each row's maximum, instead of a comparison mask and its row and column
    # sums: ~1/5 of their time).
    hit, first_col, last_col = _rows_over(u8, floor8)
    if not len(hit):
        return above, (above if k <= 1 else np.zeros_like(u8)), (0, 0, 0, 0)
    bx, by = first_col, int(hit[0])
    bw, bh = last_col + 1 - bx, int(hit[-1]) + 1 - by
    r = w // 2
    wx0, wy0 = max(0, bx - r), max(0, by - r)
    wx1, wy1 = min(cols, bx + bw + r), min(rows, by + bh + r)
    inner = (slice(by, by + bh), slice(bx, bx + bw))
    if min(wx1 - wx0, wy1 - wy0) > w:
        # The box mean only where it is compared (pixels above the floor, ~1 % of them): from
        # the integral of the window with blur's border (reflected without its edge pixel,
        # BORDER_REFLECT_101), rounded to nearest as cv2.blur rounds it (w² odd: no ties; its
        # float32 product is within 2e-5 of the exact mean, a tie is 1 / (2 w²) away) — the
        # same bytes as blur + LUT + compare on the whole window, without the full box filter.
        pad = cv2.copyMakeBorder(u8[wy0:wy1, wx0:wx1], r, r, r, r, cv2.BORDER_REFLECT_101)
        sums = cv2.integral(pad, sdepth=cv2.CV_32S)
        found = _above_local(
            u8[inner], sums, (by - wy0, bx - wx0), w, lut.ravel(), floor8, hit - by, above[inner]
        )
        ax, ay, aw, ah = (int(v) for v in found)
    else:
        local = cv2.LUT(cv2.blur(u8[wy0:wy1, wx0:wx1], (w, w)), lut)
        above[inner] = cv2.compare(
            u8[inner], local[by - wy0 : by - wy0 + bh, bx - wx0 : bx - wx0 + bw], cv2.CMP_GE
        )
        ax, ay, aw, ah = cv2.boundingRect(above[inner])
    if aw == 0:
        return above, (above if k <= 1 else np.zeros_like(u8)), (0, 0, 0, 0)
    ax, ay = ax + bx, ay + by
    pad = max(1, k // 2 + 1)
    box = (max(0, ax - pad), max(0, ay - pad), min(cols, ax + aw + pad), min(rows, ay + ah + pad))
    if k <= 1:
        return above, above, box
    x0, y0, x1, y1 = box
    bright = np.zeros_like(u8)
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))
    bright[y0:y1, x0:x1] = cv2.morphologyEx(above[y0:y1, x0:x1], cv2.MORPH_CLOSE, disc)
    return above, bright, box


@functools.lru_cache(maxsize=64)
def _local_floor(level: float, floor8: int) -> np.ndarray:
    """:func:`_bright_mask`'s least glint value for each box mean m = 0 … 255 ((1, 256) uint8,
    read-only), made once per (level, floor): u8 ≥ local and u8 > floor8, i.e. u8 ≥
    max(local, floor8 + 1) — one comparison, with local = addWeighted(box mean, 1 − level, ·,
    0, 255 level) and the max taken by this look-up table over the box mean's 256 values, made
    by the same two OpenCV calls (the same bytes as on the whole picture, without two
    full-picture passes)."""
    levels = np.arange(256, dtype=np.uint8).reshape(1, 256)
    lut = cv2.max(cv2.addWeighted(levels, 1.0 - level, levels, 0.0, 255.0 * level), floor8 + 1.0)
    lut.flags.writeable = False
    return lut


@njit(cache=True, nogil=True)
def _rows_over(u8, floor8):
    """The rows of ``u8`` (2-D uint8) holding any value above ``floor8`` (ascending int64, as
    ``np.flatnonzero`` of the rows' counts) and the least and the greatest column of those
    values (``cols`` and −1 when there are none)."""
    rows, cols = u8.shape
    hit = np.empty(rows, np.int64)
    n = 0
    first, last = cols, -1
    for r in range(rows):
        row = u8[r]
        top = np.uint8(0)
        for c in range(cols):  # (a select, not max(): the loop is vectorised)
            v = row[c]
            top = v if v > top else top
        if top > floor8:
            hit[n] = r
            n += 1
            c = 0
            while row[c] <= floor8:
                c += 1
            first = min(first, c)
            c = cols - 1
            while row[c] <= floor8:
                c -= 1
            last = max(last, c)
    return hit[:n], first, last


@njit(cache=True, nogil=True)
def _above_local(u8, sums, offset, w, lut, floor8, hit, out):
    """:func:`_bright_mask`'s comparison on ``u8`` (the inner box, uint8) in place into ``out``
    (its shape, 0 or 255): u8 ≥ lut[m] for the pixels above ``floor8`` (lut ≥ floor8 + 1, so no
    other passes) in the rows ``hit`` (ascending; the only ones holding any), m the w × w box
    mean (w odd) about the pixel, rounded to nearest, from the integral ``sums`` (int32) of the
    window padded by w // 2 on each side; ``offset`` = (row, col) of the inner box in the
    window. Returns the box (x, y, w, h) of the pixels set (w = 0 when none), as
    cv2.boundingRect."""
    h, wd = u8.shape
    oy, ox = offset
    area = w * w
    xmin, ymin, xmax, ymax = wd, h, -1, -1
    for y in hit:
        for x in range(wd):
            v = u8[y, x]
            if v <= floor8:
                continue
            y0, x0 = y + oy, x + ox  # the box's top-left in the padded window
            s = np.int64(sums[y0 + w, x0 + w]) - sums[y0, x0 + w] - sums[y0 + w, x0] + sums[y0, x0]
            m = (2 * s + area) // (2 * area)
            if v >= lut[m]:
                out[y, x] = 255
                xmin, xmax = min(xmin, x), max(xmax, x)
                ymin, ymax = min(ymin, y), max(ymax, y)
    if xmax < 0:
        return np.zeros(4, np.int64)
    return np.array([xmin, ymin, xmax + 1 - xmin, ymax + 1 - ymin], np.int64)


def _blob(c, approx_area, above, bright, img, limits, params) -> dict | None:
    """One glint from its outline ``c``: area, peak and skirt-weighted centroid (module doc), or
    None when its area is out of bounds (``limits`` = (max_area, rise, noise, wanted), wanted as
    :func:`glint_blobs`'s) or its
    peak does not stand ``rise`` (input units:
    ``glint_min_snr`` × the noise, or more in an over-exposed picture) above its local
    background (a noise speck, or saturated skin)."""
    rows, cols = img.shape
    max_area, rise, noise, wanted = limits
    m = max(2, int(math.ceil(math.sqrt(approx_area / math.pi))))
    bx, by, bw, bh = cv2.boundingRect(c)
    x0, y0 = max(0, bx - m - 2), max(0, by - m - 2)
    x1, y1 = min(cols, bx + bw + m + 2), min(rows, by + bh + m + 2)
    own = np.zeros((y1 - y0, x1 - x0), np.uint8)
    cv2.drawContours(own, [c], 0, 255, thickness=-1, offset=(-x0, -y0))
    # (The masks are 0/255 bytes: OpenCV's bitwise operations and counts on them.)
    area = cv2.countNonZero(cv2.bitwise_and(above[y0:y1, x0:x1], own))
    if area < params.glint_min_area_px or area > max_area:
        return None
    raw = img[y0:y1, x0:x1]
    if wanted is not None and (
        area > wanted[0] or cv2.minMaxLoc(raw, own)[1] < wanted[1]  # (its peak, as _skirt's)
    ):
        return None
    not_own = cv2.bitwise_not(own)
    others = cv2.bitwise_and(bright[y0:y1, x0:x1], not_own)
    d_own = cv2.distanceTransform(not_own, cv2.DIST_L2, 3)
    has_others = cv2.countNonZero(others) > 0
    d_oth = cv2.distanceTransform(cv2.bitwise_not(others), cv2.DIST_L2, 3) if has_others else d_own
    base, peak, wgt, spread = _skirt(raw, own, d_own, d_oth, has_others, float(m))
    if peak - base < rise:
        return None  # (already under the bar: the local σ below can only raise it)
    req = math.sqrt(area / math.pi)
    cx, cy = bx + 0.5 * (bw - 1), by + 0.5 * (bh - 1)
    local = _ring_noise_off(img, bright, cx, cy, req + m, req + m + _RING_PX, m)
    if local > noise:
        # (rise = max(glint_min_snr × noise, min_rise): the noise's part, with the local σ)
        rise = max(rise, params.glint_min_snr * local)
        noise = local
    if peak - base < rise:
        return None  # a noise speck (or, over-exposed, saturated skin), not a glint
    tot = float(wgt.sum())
    if tot <= 0:
        return None
    wtot = tot  # (the flux stays the light above the median: specks, fragments)
    if (
        spread > _UNEVEN_SPREAD * noise
        and spread > _UNEVEN_SHARE * (peak - base)
        and np.count_nonzero(wgt >= 0.98 * wgt.max()) >= 3
    ):
        wgt = _uneven_surround(raw, wgt, d_own, d_oth, has_others, float(m))
        wtot = float(wgt.sum())
    xs = np.arange(x0, x1, dtype=np.float64)
    ys = np.arange(y0, y1, dtype=np.float64)
    cx = float((wgt.sum(axis=0) * xs).sum() / wtot)
    centre = (cx, float((wgt.sum(axis=1) * ys).sum() / wtot))
    return {
        "centre_px": centre,
        "area_px": float(area),
        "peak": peak,
        "flux": tot,
        "base": base,
        "noise": noise,
    }


_RING_PX = 4.0  # width of the ring _ring_noise reads, px: ≥ 4 pixels a sector for a 1 px blob
_UNEVEN_SPREAD = 8.0  # × the noise σ: a flat surround's 10–90 % spread is 2.56 σ
_UNEVEN_SHARE = 0.25  # × the glint's largest weight: a step that pulls its centroid


def _uneven_surround(raw, wgt, d_own, d_oth, has_others, m):
    """:func:`_skirt`'s weights again for a glint whose surround is not flat — :func:`_blob`
    calls it when the surround's 10–90 % spread (order statistics, from :func:`_skirt`) is over
    ``_UNEVEN_SPREAD`` × the pixel noise and over ``_UNEVEN_SHARE`` of the glint's peak above
    the median background: a glint at the limbus, half on the dark iris and half on the bright
    sclera, or on the edge of the skin. A single background level (the surround's median) then
    leaves the bright side's skirt pixels weighted and pulls the centroid toward it (2.5 px on
    glasses-frame's glint at the limbus); here the background under the spot is interpolated
    from its surround (``cv2.inpaint``, Telea's method, over the pixels within ``m`` of the
    blob) and the weights are max(I − B(x, y), 0) on the same region. Not for the texture of
    an iris under a real glint (4 % of the glints of the real pictures pass both tests): it
    moves a centroid by a small share of a pixel, not worth an interpolation per glint.
    Nor for an unsaturated glint (``_blob`` asks for a flat top: ≥ 3 pixels within 2 % of its
    peak): a Monte Carlo render's glint is a scatter of samples whose surround holds its own
    stray samples, which the interpolated background follows (on paper2005's 4-sample renders
    it moved glints by up to 1.8 px); the skirt matters most for a saturated glint, whose top
    carries no position.
    """
    region = (d_own <= m).astype(np.uint8)
    back = cv2.inpaint(raw.astype(np.float32), region, max(1.0, m), cv2.INPAINT_TELEA)
    weighed = d_own <= m
    if has_others:
        weighed &= d_own <= d_oth
    out = np.where(weighed, np.maximum(raw - back.astype(np.float64), 0.0), 0.0)
    return out if out.sum() > 0 else wgt


@njit(cache=True, nogil=True)
def _median_spread(vals, low):
    """:func:`_skirt`'s background median and 10–90 % spread of ``vals`` (``low`` and 0 when
    empty; spread 0 with fewer than 8)."""
    n = vals.size
    if n == 0:
        return low, 0.0
    s = np.sort(vals)
    k = n // 2
    base = np.float64(s[k]) if n % 2 else 0.5 * (np.float64(s[k - 1]) + np.float64(s[k]))
    spread = 0.0
    if n >= 8:
        spread = np.float64(s[(9 * (n - 1)) // 10]) - np.float64(s[(n - 1) // 10])
    return base, spread


@njit(cache=True, nogil=True)
def _skirt(raw, own, d_own, d_oth, has_others, m):
    """:func:`_blob`'s background, peak and weights in one compiled pass: the region is the
    pixels within ``m`` px of the blob (``d_own``, float32) and, with other blobs near
    (``has_others``), nearer to it than to them (``d_oth``); the background the pixels farther
    than ``m`` from all. Returns (base, peak, weights, spread): base the background's median (as
    :func:`~.pupil.median`: the middle value, or the mean of the middle two; the window's
    minimum when it has none), peak the largest value on the blob (``own`` ≠ 0), weights
    max(raw − base, 0) on the region, 0 elsewhere (float64) — the same numbers as the array
    operations they replace — and spread the background's 10–90 % spread (its sorted values'
    ⌊(n − 1) / 10⌋-th and ⌊9 (n − 1) / 10⌋-th; 0 with fewer than 8) for
    :func:`_uneven_surround`."""
    h, w = raw.shape
    vals = np.empty(h * w, raw.dtype)
    n = 0
    peak = -np.inf
    low = np.inf
    for i in range(h):
        for j in range(w):
            v = raw[i, j]
            low = min(low, np.float64(v))
            if own[i, j] and np.float64(v) > peak:
                peak = np.float64(v)
            if d_own[i, j] > m and (not has_others or d_oth[i, j] > m):
                vals[n] = v
                n += 1
    if peak == -np.inf:
        peak = 0.0
    base, spread = _median_spread(vals[:n], low)
    wgt = np.zeros((h, w))
    for i in range(h):
        for j in range(w):
            if d_own[i, j] <= m and (not has_others or d_own[i, j] <= d_oth[i, j]):
                v = np.float64(raw[i, j]) - base
                wgt[i, j] = v if v >= 0.0 else 0.0
    return base, peak, wgt, spread


_SECTORS = 8  # of a blob's surround, for _ring_noise


def _ring_noise_off(img, bright, cx, cy, r_in, r_out, m):  # noqa: PLR0913
    """:func:`_ring_noise` about a blob of :func:`glint_blobs` with the other bright blobs
    (``bright``, uint8, the picture's shape, the blob's own pixels too) and their skirts
    (``m`` px around them) left out: a neighbouring glint's skirt is no noise.

    The skirts are ``bright`` dilated by a disc 2 ⌈m⌉ + 1 px across (OpenCV's elliptical
    element) on the window holding the ring; the dilation is looked up at the ring's pixels
    only (:func:`_ring_noise_near`: the same pixels left out as ``cv2.dilate`` of the window,
    without dilating all of it)."""
    rows, cols = img.shape
    x0, x1 = max(0, int(cx - r_out) - 1), min(cols, int(cx + r_out) + 3)
    y0, y1 = max(0, int(cy - r_out) - 1), min(rows, int(cy + r_out) + 3)
    k = 2 * int(math.ceil(m)) + 1
    runs = _DISC_RUNS.get(k)
    if runs is None:
        runs = _DISC_RUNS[k] = _element_runs(cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k)))
    return _ring_noise_near(
        img, bright, (x0, y0, x1, y1), runs, (cx - x0, cy - y0, float(r_in), float(r_out))
    )


def _element_runs(disc: np.ndarray) -> np.ndarray:
    """(k, 2) int64: each row's first and last column of a structuring element (uint8 k × k)
    whose rows are each one run (OpenCV's ellipses are); an empty row (k, −1). ValueError for
    any other element."""
    k = disc.shape[0]
    runs = np.empty((k, 2), np.int64)
    for a in range(k):
        on = np.flatnonzero(disc[a])
        if on.size and on[-1] - on[0] + 1 != on.size:
            raise ValueError("a structuring element's row is not one run")
        runs[a] = (on[0], on[-1]) if on.size else (k, -1)
    return runs


_DISC_RUNS: dict[int, np.ndarray] = {}  # _ring_noise_off's elliptical elements' rows, by size


@njit(cache=True, nogil=True)
def _ring_noise_near(img, bright, box, runs, ring):
    """:func:`_ring_noise` on the window ``box`` = (x0, y0, x1, y1) of ``img``, its ``others``
    ``bright`` (uint8, ``img``'s shape) dilated within the window by a k × k element anchored at
    its centre (``runs``: its rows' first and last columns, :func:`_element_runs`) — as
    ``cv2.dilate`` of the window's crop, whose border adds nothing: dst(y, x) is set when
    src(y + a − k // 2, x + b − k // 2) is for any (a, b) of the element — worked out at the
    ring's pixels only, from each window row's running count of bright pixels; ``ring`` =
    (cx, cy, r_in, r_out) in the window's pixels."""
    x0, y0, x1, y1 = box
    cx, cy, r_in, r_out = ring
    h, w = y1 - y0, x1 - x0
    k = runs.shape[0]
    half = k // 2
    count = np.zeros((h, w + 1), np.int64)  # count[y, x]: bright pixels of row y left of x
    for y in range(h):
        for x in range(w):
            count[y, x + 1] = count[y, x] + (bright[y0 + y, x0 + x] != 0)
    rx0, rx1 = max(0, int(cx - r_out)), min(w, int(cx + r_out) + 2)
    ry0, ry1 = max(0, int(cy - r_out)), min(h, int(cy + r_out) + 2)
    cap = max((rx1 - rx0) * (ry1 - ry0), 1)
    vals = np.empty(cap, np.float64)
    sect = np.empty(cap, np.int64)
    n = 0
    for i in range(ry0, ry1):
        for j in range(rx0, rx1):
            d2 = (i - cy) ** 2 + (j - cx) ** 2
            if not (r_in * r_in < d2 <= r_out * r_out):
                continue
            hit = False
            for a in range(k):
                sy = i + a - half
                if 0 <= sy < h and runs[a, 0] <= runs[a, 1]:
                    lo = max(0, j + runs[a, 0] - half)
                    hi = min(w, j + runs[a, 1] - half + 1)
                    if lo < hi and count[sy, hi] > count[sy, lo]:
                        hit = True
                        break
            if not hit:
                sect[n] = _sector(i - cy, j - cx)
                vals[n] = np.float64(img[y0 + i, x0 + j])
                n += 1
    return _sector_sigma(vals, sect, n)


@njit(cache=True, nogil=True)
def _sector(dy, dx):
    """The sector (0 … 7) of direction (dx, dy): ⌊(atan2(dy, dx) + π) / 2π × 8⌋, at most 7.
    Clear of the sectors' edges (the axes and diagonals: the angle over 1e-9 rad from each,
    where the float arithmetic's errors are ~1e-15) by the signs of dx, dy and |dx| − |dy|;
    on and near them by the formula itself (what _ring_noise always used)."""
    ax, ay = abs(dx), abs(dy)
    if min(ax, ay, abs(ax - ay)) > 1e-9 * (ax + ay):
        if dy < 0:
            if dx < 0:
                return 0 if ax > ay else 1
            return 2 if ay > ax else 3
        if dx > 0:
            return 4 if ay < ax else 5
        return 6 if ay > ax else 7
    ang = math.atan2(dy, dx)
    return min(int((ang + math.pi) / (2.0 * math.pi) * _SECTORS), _SECTORS - 1)


@njit(cache=True, nogil=True)
def _sector_sigma(vals, sect, n):
    """:func:`_ring_noise`'s σ from the ring's first ``n`` pixels ``vals`` and their sectors
    ``sect`` (0 … ``_SECTORS`` − 1): in each sector with ≥ 4 pixels 1.4826 × the median
    absolute deviation from its median; the median of those (0 when none). The pixels are put
    in per-sector runs in one pass (a sector's median is its values', in any order)."""
    count = np.zeros(_SECTORS + 1, np.int64)
    for t in range(n):
        count[sect[t] + 1] += 1
    for k in range(_SECTORS):
        count[k + 1] += count[k]  # count[k]: where sector k's run starts
    fill = count[:_SECTORS].copy()
    runs = np.empty(max(n, 1), np.float64)
    for t in range(n):
        runs[fill[sect[t]]] = vals[t]
        fill[sect[t]] += 1
    sig = np.empty(_SECTORS, np.float64)
    dev = np.empty(max(n, 1), np.float64)
    ns = 0
    for k in range(_SECTORS):
        if count[k + 1] - count[k] >= 4:
            v = runs[count[k] : count[k + 1]]
            med = _sorted_median(v)
            d = dev[: v.size]
            for t in range(v.size):
                d[t] = abs(v[t] - med)
            sig[ns] = 1.4826 * _sorted_median(d)
            ns += 1
    if ns == 0:
        return 0.0
    return np.sort(sig[:ns])[(ns - 1) // 2]


@njit(cache=True, nogil=True)
def _sorted_median(v):
    """The median of ``v`` (float64, 1-D, not empty), sorted in place (insertion sort: a
    sector's few dozen pixels): the middle value, or the mean of the middle two as
    ``np.median`` takes it ((a + b) / 2) — the same float."""
    n = v.size
    for i in range(1, n):
        x = v[i]
        j = i - 1
        while j >= 0 and v[j] > x:
            v[j + 1] = v[j]
            j -= 1
        v[j + 1] = x
    h = n >> 1
    if n & 1:
        return v[h]
    return (v[h - 1] + v[h]) / 2


@njit(cache=True, nogil=True)
def _ring_noise(img, others, cx, cy, r_in, r_out):
    """The local pixel noise σ about a spot centred at (``cx``, ``cy``) (px, in ``img``'s
    pixels): the pixels at r_in < d ≤ r_out from it and off ``others`` (uint8, ``img``'s
    shape: 0 where no other bright blob is), in ``_SECTORS`` sectors of direction; in each
    with ≥ 4 pixels 1.4826 × the median absolute deviation from its median; σ the median of
    those (0 when none).

    The picture's σ (Immerkær's, from second differences: :func:`~.pupil.noise_sigma`) misses
    noise that is not white — a JPEG's coding removes the high frequencies it sees and keeps
    the blocks' low ones (sclera noise of 3 DN: σ 0.5 DN at quality 75, while the sclera keeps
    specks 8–10 DN over their surround, 1.5 DN of σ here). Sectors, not the whole ring: an
    edge through the surround (the pupil's beside a glint on it, the limbus) or a lash lifts
    the spread of the few sectors it crosses, and the noise is in every sector. (Callers leave
    out the other glints and their skirts: on a small picture — paper2005's 87 × 65, glints
    3-4 px apart — they fill most sectors.)"""
    rows, cols = img.shape
    x0, x1 = max(0, int(cx - r_out)), min(cols, int(cx + r_out) + 2)
    y0, y1 = max(0, int(cy - r_out)), min(rows, int(cy + r_out) + 2)
    cap = (x1 - x0) * (y1 - y0)
    vals = np.empty(max(cap, 1), np.float64)
    sect = np.empty(max(cap, 1), np.int64)
    n = 0
    for i in range(y0, y1):
        for j in range(x0, x1):
            d2 = (i - cy) ** 2 + (j - cx) ** 2
            if r_in * r_in < d2 <= r_out * r_out and others[i, j] == 0:
                sect[n] = _sector(i - cy, j - cx)
                vals[n] = np.float64(img[i, j])
                n += 1
    return _sector_sigma(vals, sect, n)


def default_max_angle(led_azimuths_deg: Sequence[float]) -> float:
    """Half the smallest circular gap between distinct LED azimuths, degrees (180 for one);
    remembered per azimuths (a tracker asks for the same LEDs every frame)."""
    key = tuple(float(a) for a in led_azimuths_deg)
    if key not in _MAX_ANGLE:
        if len(_MAX_ANGLE) > 64:
            _MAX_ANGLE.clear()
        _MAX_ANGLE[key] = _max_angle(key)
    return _MAX_ANGLE[key]


_MAX_ANGLE: dict[tuple[float, ...], float] = {}


def _max_angle(led_azimuths_deg: Sequence[float]) -> float:
    """:func:`default_max_angle`, computed."""
    az = np.unique(np.mod(np.asarray(led_azimuths_deg, float), 360.0))
    if len(az) < 2:
        return 180.0
    gaps = np.diff(np.concatenate([az, [az[0] + 360.0]]))
    return 0.5 * float(gaps.min())


def match_leds(
    centres: np.ndarray,
    led_azimuths_deg: Sequence[float],
    reference: tuple[float, float],
    max_angle_deg: float,
    iterations: int = 4,
    with_reference: bool = False,
):
    """LED index for each glint centre (n, 2) px, or ``None``; one glint per LED at most.

    Each glint's direction from a reference point — atan2(−(y − y_ref), x − x_ref), degrees,
    0° = picture +x, 90° = picture up — is matched to the LED azimuths minimising the total
    angular difference (Hungarian algorithm); pairs more than ``max_angle_deg`` apart are not
    matched. The reference starts at ``reference`` and becomes the centre c of the pattern the
    matched glints fit, g_k ≈ c + r (cos φ_k, −sin φ_k) (least squares in c and r): with every
    glint found that is their centroid; with one lost it is still the pattern's centre, where
    the centroid of the others would be pulled toward them. Repeated until the matching stands.
    With ``with_reference`` the final reference (x, y) is returned too.

    >>> match_leds(np.array([[10.0, 5.0], [5.0, 0.0], [0.0, 5.0], [5.0, 10.0]]),
    ...            [0, 90, 180, 270], (5.0, 5.0), 45.0)
    [0, 1, 2, 3]
    """
    centres = np.asarray(centres, float).reshape(-1, 2)
    az = np.asarray(led_azimuths_deg, float)
    out: list[int | None] = [None] * len(centres)
    ref = np.asarray(reference, float)
    if len(centres) == 0 or len(az) == 0:
        return (out, ref) if with_reference else out
    u = np.column_stack([np.cos(np.radians(az)), -np.sin(np.radians(az))])
    for _ in range(iterations):
        rel = centres - ref
        psi = np.degrees(np.arctan2(-rel[:, 1], rel[:, 0]))
        diff = np.abs((psi[:, None] - az[None, :] + 180.0) % 360.0 - 180.0)
        rows, cols = linear_sum_assignment(diff)
        new: list[int | None] = [None] * len(centres)
        for r, c in zip(rows, cols, strict=True):
            if diff[r, c] <= max_angle_deg:
                new[int(r)] = int(c)
        if new == out:
            break
        out = new
        pairs = [(j, k) for j, k in enumerate(out) if k is not None]
        if len(pairs) < 2:
            break
        a = np.zeros((2 * len(pairs), 3))
        b = np.zeros(2 * len(pairs))
        for i, (j, k) in enumerate(pairs):
            a[2 * i] = (1.0, 0.0, u[k, 0])
            a[2 * i + 1] = (0.0, 1.0, u[k, 1])
            b[2 * i : 2 * i + 2] = centres[j]
        sol = np.linalg.lstsq(a, b, rcond=None)[0]
        if not (sol[2] > 0 and np.isfinite(sol).all()):
            break
        ref = sol[:2]
    return (out, ref) if with_reference else out


def _pattern_start(gc, pc, spacing, gate_frac, min_scale, max_rotation_deg):
    """The similarity (t, z) that two glints and two LEDs define exactly (complex x + i y),
    over every such choice with |z| in [min_scale, 1 / min_scale] and |arg z| within
    max_rotation_deg, putting the most glints within the gate (ties: least summed distance);
    None when no choice is allowed."""
    n, k = len(gc), len(pc)
    j1, j2 = np.nonzero(~np.eye(n, dtype=bool))
    k1, k2 = np.nonzero(~np.eye(k, dtype=bool))
    z = (gc[j1][:, None] - gc[j2][:, None]) / (pc[k1][None, :] - pc[k2][None, :])
    t = (gc[j1][:, None] - z * pc[k1][None, :]).ravel()
    z = z.ravel()
    s = np.abs(z)
    ok = (s >= min_scale) & (s <= 1.0 / min_scale)
    ok &= np.abs(np.degrees(np.angle(z))) <= max_rotation_deg
    if not ok.any():
        return None
    z, t, s = z[ok], t[ok], s[ok]
    near = np.abs(gc[None, :, None] - (t[:, None, None] + z[:, None, None] * pc)).min(axis=2)
    inside = near <= (gate_frac * spacing * s)[:, None]
    best = np.lexsort((np.where(inside, near, 0.0).sum(axis=1), -inside.sum(axis=1)))[0]
    return t[best], z[best]


def match_pattern(
    centres: np.ndarray,
    pattern_px: np.ndarray,
    gate_frac: float = 0.35,
    min_scale: float = 0.5,
    max_rotation_deg: float = 30.0,
    iterations: int = 6,
) -> list[int | None]:
    """LED index for each glint centre (n, 2) px, or ``None``, by the glints' predicted layout.

    ``pattern_px`` (k, 2) px holds where each LED's glint is expected relative to the glints'
    centre (:func:`~.evaluate.led_picture_pattern`: for an off-axis camera a foreshortened,
    distorted ring, whose directions from its centre are not the LEDs' azimuths). The glints
    are matched to its points moved by a similarity transform, g_k ≈ t + z p_k (complex
    notation x + i y: t the shift, z = s e^{iθ} the scale s and rotation θ). Start: the
    transform two glints and two LEDs define exactly, over every such choice with s in
    [``min_scale``, 1 / ``min_scale``] and |θ| ≤ ``max_rotation_deg``, that puts the most
    glints within the gate. Then, until the matching stands: the Hungarian assignment
    (``scipy.optimize.linear_sum_assignment``) on the distances |g_j − (t + z p_k)| (capped at
    twice the gate, so far strays do not weigh), pairs beyond the gate left unmatched, and
    t, z refitted to the matched pairs (least squares). The gate is ``gate_frac`` × s × the
    smallest distance between two pattern points: within it a glint is nearer its own LED's
    point than any other's (``gate_frac`` < 0.5), so a stray or a lost glint does not shift
    the others' LEDs. Fewer than two glints or LEDs: none matched (no transform to tell).

    >>> match_pattern(np.array([[11.0, 5.0], [5.0, 0.0], [50.0, 50.0], [5.0, 10.0]]),
    ...               np.array([[5.0, 0.0], [0.0, -5.0], [-5.0, 0.0], [0.0, 5.0]]))
    [0, 1, None, 3]
    """
    g = np.asarray(centres, float).reshape(-1, 2)
    p_xy = np.asarray(pattern_px, float).reshape(-1, 2)
    n, k = len(g), len(p_xy)
    out: list[int | None] = [None] * n
    if n < 2 or k < 2:
        return out
    gc = g[:, 0] + 1j * g[:, 1]
    pc = p_xy[:, 0] + 1j * p_xy[:, 1]
    spacing = float(np.abs(pc[:, None] - pc[None, :])[~np.eye(k, dtype=bool)].min())
    if not spacing > 0:
        return out  # two LEDs' glints predicted at one place: they cannot be told apart
    tz = _pattern_start(gc, pc, spacing, gate_frac, min_scale, max_rotation_deg)
    if tz is None:
        return out
    for _ in range(iterations):
        dist = np.abs(gc[:, None] - (tz[0] + tz[1] * pc)[None, :])
        lim = gate_frac * spacing * abs(tz[1])
        rows, cols = linear_sum_assignment(np.minimum(dist, 2.0 * lim))
        new: list[int | None] = [None] * n
        for r, c in zip(rows, cols, strict=True):
            if dist[r, c] <= lim:
                new[int(r)] = int(c)
        if new == out:
            break
        out = new
        pairs = [(jj, kk) for jj, kk in enumerate(out) if kk is not None]
        if len(pairs) < 2:
            break
        a = np.column_stack([np.ones(len(pairs)), pc[[kk for _, kk in pairs]]])
        sol = np.linalg.lstsq(a, gc[[jj for jj, _ in pairs]], rcond=None)[0]
        if not (np.isfinite(sol).all() and abs(sol[1]) > 0):
            break
        tz = (sol[0], sol[1])
    return out


def pattern_fits(
    centres: np.ndarray, pattern_px: np.ndarray, tol_frac: float, min_count: int = 3
) -> list[dict]:
    """Every distinct way ≥ ``min_count`` glints fit the LEDs' pattern as a whole.

    ``centres`` (n, 2) px: the glints; ``pattern_px`` (k, 2): each LED's glint place relative to
    the pattern's centre (px, or the unit vectors of the LED azimuths, (cos φ, −sin φ)). A fit
    is g_k = t + s p_k (shift t, scale s > 0; no rotation: :func:`~.detect._pattern_misfit`'s
    model): each choice of two glints and two LEDs gives one (s from the glints' difference
    along the LEDs', t from their midpoint), then each LED takes the nearest glint within
    ``tol_frac`` × s |p_k| of t + s p_k (one glint per LED, the nearer LED keeping a shared
    one), t and s are refitted to those pairs (least squares) and the LEDs matched again.

    Returns one dict per distinct matching with ≥ ``min_count`` pairs, most pairs first, then
    least residual: ``leds`` (per glint its LED index or None), ``count``, ``t`` (2,) px, ``s``,
    ``rms`` the root-mean-square distance (px) of the matched glints from t + s p_k. Fewer than
    ``min_count`` glints or LEDs: [].

    >>> ring = np.array([[1.0, 0.0], [0.0, -1.0], [-1.0, 0.0], [0.0, 1.0]])
    >>> g = np.array([[30.0, 0], [0, -30], [-30, 0], [0, 30], [70, 40], [38, 6]])
    >>> best, *others = pattern_fits(g, ring, 0.38)
    >>> best["leds"], best["count"], round(best["s"], 1)
    ([0, 1, 2, 3, None, None], 4, 30.0)
    >>> others[0]["leds"], others[0]["count"]
    ([None, 1, 2, 3, None, 0], 4)
    """
    g = np.asarray(centres, float).reshape(-1, 2)
    p = np.asarray(pattern_px, float).reshape(-1, 2)
    n, k = len(g), len(p)
    if n < min_count or k < min_count:
        return []
    ii, jj = np.nonzero(~np.eye(n, dtype=bool))
    aa, bb = np.nonzero(np.triu(~np.eye(k, dtype=bool)))
    dg = (g[ii] - g[jj])[:, None, :]  # (pairs of glints, 1, 2)
    dp = (p[aa] - p[bb])[None, :, :]  # (1, pairs of LEDs, 2)
    s = (dg * dp).sum(axis=2) / (dp * dp).sum(axis=2)
    t = 0.5 * (g[ii] + g[jj])[:, None, :] - s[:, :, None] * 0.5 * (p[aa] + p[bb])[None, :, :]
    good = s > 0
    s, t = s[good], t[good]
    if not len(s):
        return []
    norm = np.hypot(*p.T)
    seen: dict[tuple, dict] = {}
    # Many hypotheses give one matching (each glint pair of a pattern, each LED pair): its
    # least-squares fit is made once (None: fewer than min_count pairs, or no fit). A matching's
    # fit is the same numbers whichever hypothesis gave it, so a second round's hypothesis is
    # each distinct fit once, in the order first found (a repeat adds nothing to ``seen``).
    fitted: dict[tuple, np.ndarray | None] = {}
    for _ in range(2):
        best, near = _nearest_glints(g, p, t, s)  # (H, k): each LED's nearest glint, its distance
        inside = near <= tol_frac * s[:, None] * norm[None, :]
        count = inside.sum(axis=1)
        keep = np.flatnonzero(count >= min_count)
        if not len(keep):
            return []
        t2, s2 = [], []
        taken = set()
        for h in keep:
            leds = _one_each(best[h], near[h], inside[h], n)
            key = tuple(-1 if kk is None else kk for kk in leds)
            if key in fitted:
                sol = fitted[key]
            else:
                sol = fitted[key] = _matching_fit(g, p, leds, min_count)
            if sol is None or key in taken:
                continue
            taken.add(key)
            t2.append(sol[:2])
            s2.append(sol[2])
            if key not in seen:
                pairs = [(j, kk) for j, kk in enumerate(leds) if kk is not None]
                res = g[[j for j, _ in pairs]] - (sol[:2] + sol[2] * p[[kk for _, kk in pairs]])
                seen[key] = {
                    "leds": leds,
                    "count": len(pairs),
                    "t": sol[:2],
                    "s": float(sol[2]),
                    "rms": float(np.sqrt((res**2).sum(axis=1).mean())),
                }
        if not t2:
            break
        t, s = np.array(t2), np.array(s2)
    return sorted(seen.values(), key=lambda f: (-f["count"], f["rms"]))


def _matching_fit(g: np.ndarray, p: np.ndarray, leds, min_count: int) -> np.ndarray | None:
    """:func:`pattern_fits`' refit of one matching ``leds`` (per glint its LED or None):
    :func:`pattern_fit`'s (t_x, t_y, s) on its pairs, or None when they are fewer than
    ``min_count`` or the fit is not a finite positive scale."""
    pairs = [(j, kk) for j, kk in enumerate(leds) if kk is not None]
    if len(pairs) < min_count:
        return None
    sol = pattern_fit(g[[j for j, _ in pairs]], p[[kk for _, kk in pairs]])
    if not (sol[2] > 0 and np.isfinite(sol).all()):
        return None
    return sol


@njit(cache=True, nogil=True)
def _nearest_glints(g, p, t, s):
    """:func:`pattern_fits`' nearest glint to each hypothesis' LED places: for hypothesis h
    (shift ``t[h]`` (2,), scale ``s[h]``) and LED kk (``p[kk]``), the index of the glint of
    ``g`` (n, 2) nearest t + s p_kk and its distance ((H, k) int64 and float64) — the first of
    equally near ones, as ``np.argmin`` over the distances ``np.hypot(g − q)`` takes it (the
    same libm hypot; a NaN distance is the nearest, as argmin's), without the (H, k, n)
    arrays (H runs to 10⁴–10⁵ with 8 LEDs and a few dozen glints)."""
    nh, k, n = s.shape[0], p.shape[0], g.shape[0]
    best = np.zeros((nh, k), np.int64)
    near = np.empty((nh, k))
    for h in range(nh):
        for kk in range(k):
            qx = t[h, 0] + s[h] * p[kk, 0]
            qy = t[h, 1] + s[h] * p[kk, 1]
            bj = 0
            bd = math.hypot(g[0, 0] - qx, g[0, 1] - qy)
            if bd == bd:
                for j in range(1, n):
                    d = math.hypot(g[j, 0] - qx, g[j, 1] - qy)
                    if d < bd:
                        bj, bd = j, d
                    elif d != d:
                        bj, bd = j, d
                        break
            best[h, kk] = bj
            near[h, kk] = bd
    return best, near


def _one_each(best, near, inside, n: int) -> list[int | None]:
    """Per glint its LED from each LED's nearest glint ``best`` (k,) at distance ``near`` (k,),
    those ``inside`` the tolerance only; a glint two LEDs take goes to the nearer."""
    leds: list[int | None] = [None] * n
    dist = [math.inf] * n
    for kk in np.argsort(near):
        if inside[kk] and leds[best[kk]] is None:
            leds[int(best[kk])] = int(kk)
            dist[best[kk]] = near[kk]
    return leds


def pattern_fit(g: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Least-squares (t_x, t_y, s) of glints ``g`` (n × 2, px) = t + s ``p`` (their pattern
    points, n × 2): the pattern's shift and scale."""
    a = np.zeros((2 * len(g), 3))
    a[0::2, 0] = 1.0
    a[1::2, 1] = 1.0
    a[0::2, 2] = p[:, 0]
    a[1::2, 2] = p[:, 1]
    return np.linalg.lstsq(a, g.reshape(-1), rcond=None)[0]
