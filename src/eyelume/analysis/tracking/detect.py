"""Pupil and glint detection on one grey eye picture: the paper's Figure 2 pipeline, any image.

:func:`detect` takes a 2-D picture — uint8, uint16 (camera DN) or float (irradiance) — and
returns the pupil ellipse, the glints (matched to their LEDs when the LED azimuths are given) and,
instead of wrong numbers, the reasons a frame cannot be trusted.

Conventions
-----------
* **Pixels**: OpenCV's. Pixel (column c, row r) has its centre at (x, y) = (c, r); x grows to the
  right, y down the picture; row 0 is the top row.
* **Angles**: an ellipse's ``angle_deg`` is its major axis' direction in degrees from +x toward
  +y (clockwise as displayed), in [0, 180) — what ``cv2.ellipse`` takes. LED azimuths are
  counter-clockwise as displayed: 0° = picture +x, 90° = picture up (−y).
* **Grey levels**: the glints are found on the picture scaled by its own range, u8 = round(255
  (I − min) / (max − min)); the pupil on one scaled from its darkest pixel to its 99th
  percentile (:mod:`.pupil`). Edge levels, centroid weights and reported thresholds and peaks
  are in the input's own units.
* **Missing pixels**: non-finite pixels (NaN, inf) of a float picture and pixels outside the
  optional ``valid`` mask are missing: no dark region touching them is the pupil, no outline
  point next to them is used. So is a black border (:func:`_black_border`: a region at exactly
  the darkest value touching the picture's edge, ≥ 0.5 % of it; a warning says so). A picture
  with none left is a ValueError. Small enclosed holes of non-finite pixels (≤ ``HOLE_MAX_PX``,
  not touching the edge: dead pixels) are filled from their surround instead (:func:`_fill_holes`,
  a warning says so): one inside a pupil would otherwise cut it.

Pipeline (each step's choices are explained in :mod:`.pupil` and :mod:`.glints`)
----------------------------------------------------------------------------------
1. :func:`_prepare`: the array, its missing pixels, its range and pixel noise.
2. Glints (:func:`~.glints.find_glints`): pixels above the 99th percentile and halfway from
   their neighbourhood's mean to the maximum; bright blobs; a blob must stand above its local
   background by ``glint_min_snr`` × the pixel noise; intensity-weighted centroids, the
   background under a glint on an uneven surround (the limbus) interpolated from it. In a
   bright picture (the 99th percentile within ``glint_min_contrast`` of the top) the pixels
   near full scale, each blob standing ``glint_min_contrast`` of the range above its own
   surround.
3. Pupil (:func:`~.pupil.find_pupil`): threshold ladder → the darkest compact blob stable over
   neighbouring levels → closing → contrast against its own surround and the pixel noise →
   outline off glints and border → sub-pixel edge → robust ellipse fit → support. The old
   "valley after the darkest histogram mode" assumed the pupil had a mode of its own; on real
   pictures with a dark iris it had not (issue 13).
4. :func:`_pupil_result`: the pupil and the checks that make it untrustworthy.
5. Keep glints within ``glint_search_radius`` × the pupil's major axis of its centre, none
   whose spot is cut by a missing pixel (:func:`_glints_off_missing`); with LEDs given and
   fewer glints than LEDs, also the unsaturated ones standing out of the picture's white
   top-hat (:func:`~.glints.faint_glints_near`) and, still fewer, defocused ones with wider
   discs (:func:`~.glints.broad_glints_near`); match to LEDs, strongest first
   (:func:`_match_glints`, :func:`_strong_first`), and with an LED left without one look
   again out to twice as far (:func:`_wider_look`: a small pupil); a saturated glint whose
   skirt reaches the pupil's outline centred again over the edge's median profile as its
   background (:func:`_edge_backed_glints`); 6. warnings (:func:`_glint_warnings`).

Which failures make ``ok`` False
--------------------------------
``ok`` is False on: no pupil; a pupil whose fitted outline is less than ``min_boundary_support``
(45 %) backed by edge points or has an unbacked arc over ``max_boundary_gap`` (45 %) of it (cut
by an eyelid or the image border, or hidden); a pupil whose fitted outline holds a straight arc
(an eyelid's edge fitted as the pupil's) and, without it, fails the support checks ("pupil
cut by an eyelid", :func:`_straight_arc`); a pupil outline
that is not an ellipse (RMS residual of its edge points above max(``max_fit_residual_px``,
``max_fit_residual_frac`` × the semi-minor axis)); too few glints (LED azimuths given and
fewer than ``min_matched_glints`` (2; all of them with a single LED) matched to an LED, or, with
an LED missing, fewer than ``min_glints_when_missing`` (3), a glint left unmatched, or matched
glints that do not fit the LEDs' pattern); a matched glint broken up into specks (its centre
uncertain). Messages
starting ``"warning: "`` leave ``ok`` True: LEDs without a glint when enough others have one
(listed in ``Detection.missing_leds`` too: on a headset with 6–8 LEDs around an eye seen off its
axis some glints routinely fall off the cornea or under a lid; the gaze models use the matched
glints only), an eyelid's edge left out of the pupil's fit (:func:`_straight_arc`; the centre
is the refit's), a glint on the pupil's edge (its outline points there were dropped, so the
centre stands; a saturated one is centred over the edge's profile, an unsaturated one's
centroid may be biased), a glint matched to no LED, no glints
when no LEDs were given.

When ``ok`` is False ``pupil`` may still hold the rejected candidate, for diagnosis: use its
numbers only when ``ok`` is True.

Performance: measured by ``benchmarks/detect.py`` (one core) and, on real pictures,
``benchmarks/detect_real.py``.

>>> import numpy as np, cv2
>>> img = np.full((120, 160), 200, np.uint8)
>>> _ = cv2.circle(img, (80, 60), 40, 120, -1)                 # iris
>>> _ = cv2.ellipse(img, ((80.0, 60.0), (30.0, 26.0), 0.0), 20, -1)  # pupil
>>> d = detect(img)
>>> d.ok, [round(v, 1) for v in d.pupil.centre_px]
(True, [80.0, 60.0])
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field

import cv2
import numpy as np
from numba import njit

from eyelume.analysis.tracking.glints import (
    block_or_blur,
    broad_glints_near,
    default_max_angle,
    faint_glints_near,
    find_glints,
    fit_spot,
    glint_smoothing,
    glints_near,
    in_bright_run,
    jpeg_dc_step,
    match_leds,
    match_pattern,
    pattern_fit,
    pattern_fits,
    spot_sigma,
)
from eyelume.analysis.tracking.pupil import (
    Ellipse,
    _residual_limit,
    _stride,
    find_pupil,
    noise_sigma,
    percentiles,
    sampson_distance,
    support_of,
)

__all__ = [
    "DetectParams",
    "Detection",
    "Glint",
    "Pupil",
    "detect",
    "detection_to_dict",
    "enlargement_factor",
]

PIXEL_CONVENTION = (
    "OpenCV: pixel (column c, row r) centred at (x, y) = (c, r), row 0 at the top; ellipse "
    "angle from +x toward +y (clockwise as displayed); LED azimuth 0 deg = +x, 90 deg = up"
)


@dataclass(frozen=True)
class DetectParams:
    """Every tunable of :func:`detect`, with the default's reason.

    Pupil
    -----
    scale_percentile : the pupil's 8-bit picture runs from the darkest valid pixel to this
        percentile (99): glints and stuck pixels, ≪ 1 % of an eye picture, are clipped.
    ladder_rows, ladder_levels, ladder_top_percentile : the ladder runs on the picture reduced
        by round(min(rows, cols) / 80) (a pupil of ≥ 16 px stays ≥ 3 px across; the cost is
        one labelling per level), at levels spaced (P60 − P0.5) / 32 from its darkest pixel
        to its 60th percentile (the pupil is ≪ 40 % of an eye picture), and at least
        ``ladder_min_span`` (¼) of the 8-bit range above the darkest pixel: when most of the
        picture is an unlit surround at the black level (a wide-angle headset camera's view
        past the lit eye region, eyetrackvr), its 60th percentile is that black level and the
        ladder would never reach the iris.
    ladder_max_growth : largest MSER stability q = (A₊ − A₋) / A of the pupil's blob over the
        neighbouring levels (1: at 32 levels the pupil's blurred edge band is crossed in one or
        two steps; a merge with the iris multiplies the area).
    ladder_fine, ladder_fine_span : when the first ladder gives no whole pupil, or a pupil
        at the black level whose fit leaves an arc over 1 − ``ladder_fine_support`` of its
        outline unbacked (maybe merged with a dark iris: :func:`~.pupil.find_pupil`;
        paper2005's 8-bit PNG at (30°, 20°) was answered 1.27 px off, 43 % unbacked), its
        first ``ladder_fine_span`` (3) levels again ``ladder_fine`` (4) times finer (steps ≥
        1): a pupil near the black level whose step to the iris the ladder crosses in one or
        two levels (an off-axis view, where bright skin sets the levels' spacing) is then
        resolved. The finer fit replaces the first only when whole,
        by a stricter measure: ``ladder_fine_support`` (0.75) of its outline backed, no
        unbacked arc over 0.25 (a finer level can pick a lid-cut pupil's darkest core, whose
        outline passes the usual 0.45 with the centre over a pixel off: paper2005 at (−30°,
        −20°)). (1 = off.)
    max_candidates : stable blobs fitted in turn, darkest first, before giving up (3).
    small_pupil_axes : when the reduced ladder (f > 1) gives no whole pupil, the ladder again at
        full resolution for a pupil under this × f px across (4: the reduced ladder resolves
        ≥ ~3 f px; eyetrackvr's ~9 px pupil at f = 3 merged there with its iris), whole fits
        only (:func:`~.pupil._small_pupil`); 0 = off.
    core_quantile, core_max_fraction, core_min_sigma : a fitted pupil whose interior (inside
        0.9 × its ellipse, off glints and missing pixels) has a darker core — its
        ``core_quantile`` (5th percentile) within ``core_max_fraction`` (¼) of the way from
        the black level (the darkest valid pixel) to its median, and ``core_min_sigma`` (8) σ
        of the interior's pixel noise below that median — is an iris (or a dark fold) holding
        the real pupil: the finer ladder is tried, else it is refused ("pupil merged with
        iris: a darker core …"). A real pupil is uniform to its noise: its 5th percentile is
        1.6 σ under its median for Gaussian noise, 2–4 σ with glints' skirts and the edge band
        inside it (the tests' 15 px pupils with four glints); the iris fits holding the pupil
        on the off-axis presets' renders were 15–18 σ (vr-offaxis at (−10°, −20°): the iris,
        4.8 px off the pupil's centre, was answered).
    pupil_min_area_px, pupil_max_area_frac : area bounds of the dark blob (px; fraction of the
        picture, 10 %: an iris seen without a pupil is larger at the framing of an eye tracker);
        the fitted ellipse (π a b) must hold ``pupil_min_area_px`` too ("pupil too small").
    pupil_tiny_area_px : compact dark blobs from this up to the minimum area are reported as
        "pupil too small" when nothing larger is found.
    pupil_min_solidity : area / convex-hull area of the closed blob (0.8); an ellipse, even cut
        by an eyelid, is convex (1); lashes and shadows are not.
    pupil_min_solidity_glints : the same, when the blob passes only with the glints' pixels
        left out (:func:`~.pupil._glint_forgiven`: a glint beside a small pupil, filled with
        its dark, grows a bump on its blob) or with thin strokes cut off
        (:func:`~.pupil._without_strokes`: lashes across the pupil's edge) — 0.9: an
        ellipse outside its glints is convex
        (0.93–0.98 on vr-offaxis at 100 × 100 and on the tests' small pupils with glints on
        their edge), while a real close-up's dark-iris crescent that the glints' fill had
        joined to the pupil passed 0.8 at 0.87 and was answered 8 px off.
    pupil_min_axis_ratio : the fitted ellipse's minor / major axis (0.25): a circular pupil seen
        θ off its axis is foreshortened to about cos θ (the cornea's refraction makes it rounder
        still), and an eye camera sees it at most ~75° off (cos 75.5° = 0.25: the off-axis
        presets' most oblique pupil, vr-offaxis at (−30°, 10°), fits 0.33). A thinner dark blob
        — a black strip of skin beside a lid, a lash, a fold — is refused as a sliver and the
        next candidate fitted.
    surround_sector_ring, surround_sectors, surround_sector_min : the fitted ellipse's ring
        from 1.15 to 1.5 × its outline, cut into 8 sectors of equal angle: each sector's median
        must be above the pupil's level by 0.3 of the whole ring's step, else the blob is
        refused as dark on one side only (a black strip beside a lid: 0.16 on vr-offaxis at
        (20°, 0°) before the PSF; the presets' real pupils, lid-cut too, ≥ 0.65). A guess
        between those, checked on the real close-ups (benchmarks/detect_real.py).
    pupil_min_contrast_sigma, pupil_min_contrast : the surround's median must exceed the
        pupil's by 5 standard errors of that difference of medians (1.2533 σ √(1/N₁ + 1/N₂)
        over the N₁ and N₂ pixels, σ the pixel noise there: a 5 standard-error step is not
        noise) and by 3 % of the robust range (a guess at the smallest step a camera's
        shading and vignetting do not make).
    closing_kernel_px : the closing's elliptical element, px (odd); ``None`` = odd ≥ 3 near
        ``closing_kernel_frac`` (0.15) × the blob's equivalent diameter: 5 px for the 16 px
        pupil of an 87 × 65 picture, 17 px for a 110 px one. A glint is ≲ 0.25 of the pupil
        across in eye-tracker pictures and only its part over the edge notches the outline
        (points near glints are dropped anyway); a closing's cost grows with the element.
    border_margin_px : outline points this close to the picture's edge are not pupil edge.
    glint_margin_px : outline points within this of a bright (glint) pixel are dropped.
    glint_max_pupil_frac : a bright blob is a glint on a dark blob (joined to it, its outline
        points dropped) only when its area is ≤ this (¼) × the blob's: a corneal glint is
        far smaller than the pupil it sits on (an LED's virtual image in the cornea is a
        fraction of a millimetre, the pupil 2–8 mm); saturated skin beside a small pupil is
        not a glint on it (eyetrackvr: lit brow and lid, 38–125 px, within 15 px of a 60 px
        pupil, hid its whole outline).
    edge_fraction : the sub-pixel edge is where the image crosses this fraction of the way from
        the pupil's level to the iris's (¼; :mod:`.pupil` step 5 for why not ½).
    refine_reach_px, refine_reach_frac : the sub-pixel edge search runs ± max(3 px, 0.1 ×
        the blob's diameter) along the normal: farther than the blob's outline can be from the
        edge's ¼ level (the ladder's level can be near the iris's, ≈ 2σ_blur away; real pupils'
        soft edges are a few px wide).
    refine_smooth_px : optional Gaussian σ (px) of a glint-masked blur before the edge is read
        (0: on eyelume's 87 × 65 renders any blur moved the centre by ~0.3 px, as the pupil's
        surround is not symmetric).
    refine_tangential_px : the edge profile is the mean of 2 k + 1 parallel profiles 1 px
        apart along the tangent (k = 1): the noise averages along the edge without moving it.
    refine_passes, refine_again_below_px : a pupil narrower than 30 px gets a second edge pass
        from the first fit (its normals, its inliers as starts): at 87 × 65 the blob's outline
        can lie a pixel off the edge, a tenth of the pupil's radius, and four glints sit just
        inside it; the second pass brings eyelume's renders back to the earlier detector's
        precision (mean 0.23 px on the frames both answer). Wider real pupils keep one pass
        (a second one lost 2 % of the real close-ups).
    inlier_tol_px, inlier_tol_frac : edge points farther than max(1 px, 3σ, 0.03 × the pupil's
        diameter) from the ellipse are outliers, σ the measured edge noise (real pupils are a
        little out of round; 1 px is ~5σ at the tests' default noise).
    fit_iterations : robust refits; outlier_trim_points : inliers this close (in outline
        points) to an outlier are left out; min_edge_points : fewest edge points for a fit.
    min_boundary_support, max_boundary_gap : fewest fraction of the ellipse's outline backed
        by inliers (0.45) and longest unbacked arc (0.45 of it): a lid over the top quarter of
        the pupil leaves an arc of ~25 % and passes, with the centre within 0.3 px; over half
        of it does not; a ragged real edge leaves many short gaps.
    max_fit_residual_px, max_fit_residual_frac : largest RMS distance of the inliers to the
        ellipse: max(0.5 px, 3 % of the semi-minor axis) — a ragged outline (a noisy or
        non-elliptic blob) whose centre would be uncertain.
    lid_arc_deg, lid_arc_max_gap_deg, lid_arc_min_points : an arc of the inlier outline over
        ``lid_arc_deg`` (90°) of the ellipse, contiguous (no gap over 20°) and of ≥ 6 points,
        that a straight line fits better than the ellipse, and significantly better than the
        pupil's arc would given the edge noise, is an eyelid's edge taken for the pupil's
        (:func:`_straight_arc`: a quarter of a pupil's edge bows 0.29 × its semi-axis from its
        chord; a lid is straight at that scale): left out and the ellipse refitted
        (a warning), or "pupil cut by an eyelid" when the rest fails the support checks.

    Glints
    ------
    glint_percentile, glint_level, glint_window_px, glint_min_contrast : a glint pixel is
        brighter than the ``glint_percentile`` (99th) of the 8-bit picture and ≥ m + level
        (255 − m), m the mean of the ``glint_window_px`` box around it (``None`` = odd ≈
        min(rows, cols) / 16, ≥ 5); when max − P99 < min_contrast × 255 (15 %: skin near
        full scale), glint pixels are within it of the max and a glint's peak stands
        min_contrast of the range above its surround (bright skin does not).
    glint_close_px : closing of the bright mask (``None`` = odd ≈ min(rows, cols) / 160).
    glint_min_area_px, glint_max_area_frac : blob area bounds (px; fraction of the picture):
        ≥ 2 px, as the optics spread a glint over several pixels while a hot pixel or a noise
        spike is one; ≤ 0.5 % of the picture.
    glint_min_snr : a glint's peak stands ≥ this many σ of the pixel noise (Immerkær's
        estimate, or the noise of the blob's own surround when larger: a JPEG's, which second
        differences miss — :func:`~.glints._ring_noise`) above its local background (8: a
        Gaussian noise speck of 2–4 px is beyond 8 σ with probability ≪ 10⁻⁹ per pixel); a
        noise speck is never a glint.
    glint_smooth_px : Gaussian σ (px) of the picture the bright mask is taken from (``None`` =
        min(rows, cols) / 480, none below 0.5: 1 px at 640 × 480, where a Monte Carlo render's
        or a noisy camera's glint is then one blob, not a scatter of specks; a glint's size in
        px scales with the picture, and at 87 × 65 it is ~1.5 px across). The centroid weighs
        the unsmoothed picture.
    glint_min_flux_frac : a bright blob with less than this share (10 %) of the brightest one's
        light above background is a speck, not an LED's glint (the LEDs of one ring differ by
        far less at the cornea; specks are fragments, stray reflections or hot pixels).
    glint_max_fragment_frac : a matched glint with more than this share (5 %) of its own light
        in specks around it is broken up and its centre uncertain (an error).
    glint_max_flux_ratio : a matched glint with more than this × the light of the brightest
        other matched glint (3; correctly matched ones in eyelume's renders: ≤ 2.3 ×) is left
        out, its LED without a glint (a warning; :func:`_too_bright`): merged with another
        spot (the sun's glint) or a lit patch, its centroid is not the glint's.
    glint_search_radius : glints farther than this × the pupil's major axis from its centre are
        not the cornea's (2) — unless, with LEDs given and some left without a glint, a second
        look out to twice as far gives every LED a glint fitting their pattern
        (:func:`_wider_look`: a small pupil).
    glint_strong_frac : glints are matched to LEDs strongest first (:func:`_match_glints`): those
        rising ≥ this share (½) of the strongest one's rise above its own background first,
        the weaker only where they fit the pattern of those matched.
    glint_edge_margin_px : a glint whose centroid is within its equivalent radius + this of the
        fitted pupil outline is "on the pupil edge".
    match_max_angle_deg : largest glint–LED direction difference for a match (``None`` = half
        the smallest gap between LED azimuths: 45° for four LEDs 90° apart).
    min_matched_glints : fewest glints matched to LEDs for ``ok`` (2, or every LED when fewer
        are given): the geometric gaze model needs two glints to place the centre of corneal
        curvature (Guestrin & Eizenman 2006, :class:`~.gaze.GeometricGaze`), and a glint
        pattern of two or more fixes the PCCR reference (:func:`~.gaze.glint_offsets`). Fewer
        is a failure naming the missing LEDs; more missing LEDs than that are a warning.
        With LEDs missing, the matched glints must also fit the LEDs' glint pattern
        (:func:`_pattern_misfit`): direction alone lets two stray reflections pass for glints.
    min_glints_when_missing : with an LED missing, at least this many matched (3) and no glint
        left unmatched: two glints fit any pattern up to one degree of freedom, so a shifted
        copy of it — the LEDs' reflections in spectacles, or strays beside the pupil — passes
        for them (glasses-frame at 160 × 120, where the corneal glints are single pixels: two
        such strays answered frames 35–41° off); an unmatched glint may be a missing LED's.
    glint_off_fit_p : with ≥ 4 glints matched, one lying farther from where the others' fit
        puts its LED's glint than the others' scatter allows at this false-alarm rate (1 %)
        is a stray, not that LED's glint (:func:`_off_the_others`).
    glint_centroid_floor_px : the least uncertainty (px, per coordinate) granted a glint's
        centroid in that test (½ px: a spot one or two pixels across is placed to about its
        pixel when its own bias — clipping, a pupil edge or a missing pixel under it — does
        not show in the other glints' scatter).
    glint_skirt_p : with ≥ 3 glints matched, a spot with no blur skirt is taken for a block of
        stuck or hot pixels — its LED left without a glint, a warning — only when a block fits
        it better than a Gaussian of the other glints' width by more than chance allows at
        this false-alarm rate (0.1 %; :func:`_block_not_blur`).
    pattern_min_scale : with ``led_pattern_px`` given, the fitted pattern's scale must be within
        [this, 1 / this] of the prediction (0.5: a guess — the glints' spread changes with gaze
        and with the eye's distance by far less than 2×; strays beside the pupil do not keep it).
    """

    scale_percentile: float = 99.0
    ladder_rows: float = 80.0
    ladder_levels: int = 32
    ladder_top_percentile: float = 60.0
    ladder_min_span: float = 0.25
    ladder_max_growth: float = 1.0
    ladder_fine: int = 4
    ladder_fine_span: int = 3
    ladder_fine_support: float = 0.75
    core_quantile: float = 5.0
    core_max_fraction: float = 0.25
    core_min_sigma: float = 8.0
    max_candidates: int = 3
    small_pupil_axes: float = 4.0
    pupil_min_area_px: int = 30
    pupil_tiny_area_px: int = 6
    pupil_max_area_frac: float = 0.10
    pupil_min_solidity: float = 0.8
    pupil_min_solidity_glints: float = 0.9
    pupil_min_axis_ratio: float = 0.25
    surround_sector_ring: tuple[float, float] = (1.15, 1.5)
    surround_sectors: int = 8
    surround_sector_min: float = 0.3
    pupil_min_contrast_sigma: float = 5.0
    pupil_min_contrast: float = 0.03
    closing_kernel_px: int | None = None
    closing_kernel_frac: float = 0.15
    border_margin_px: float = 1.5
    glint_margin_px: float = 1.5
    glint_max_pupil_frac: float = 0.25
    edge_fraction: float = 0.25
    refine_reach_px: float = 3.0
    refine_reach_frac: float = 0.10
    refine_smooth_px: float = 0.0
    refine_tangential_px: int = 1
    refine_passes: int = 2
    refine_again_below_px: float = 30.0
    inlier_tol_px: float = 1.0
    inlier_tol_frac: float = 0.03
    fit_iterations: int = 6
    outlier_trim_points: int = 3
    min_edge_points: int = 8
    min_boundary_support: float = 0.45
    max_boundary_gap: float = 0.45
    max_fit_residual_px: float = 0.5
    max_fit_residual_frac: float = 0.03
    lid_arc_deg: float = 90.0
    lid_arc_max_gap_deg: float = 20.0
    lid_arc_min_points: int = 6
    glint_percentile: float = 99.0
    glint_level: float = 0.5
    glint_window_px: int | None = None
    glint_min_contrast: float = 0.15
    glint_close_px: int | None = None
    glint_min_area_px: int = 2
    glint_min_snr: float = 8.0
    glint_smooth_px: float | None = None
    glint_min_flux_frac: float = 0.1
    glint_max_fragment_frac: float = 0.05
    glint_max_area_frac: float = 0.005
    glint_search_radius: float = 2.0
    glint_strong_frac: float = 0.5
    glint_edge_margin_px: float = 1.0
    match_max_angle_deg: float | None = None
    min_matched_glints: int = 2
    min_glints_when_missing: int = 3
    pattern_min_scale: float = 0.5
    glint_max_flux_ratio: float = 3.0
    glint_off_fit_p: float = 0.01
    glint_skirt_p: float = 0.001
    glint_centroid_floor_px: float = 0.5


@dataclass
class Pupil:
    """The fitted pupil ellipse (pixel convention in the module doc).

    centre_px : (x, y) sub-pixel centre. axes_px : (major, minor) full lengths, px, of the
    pupil's edge: the fitted iso-line (``DetectParams.edge_fraction``, on the edge's dark side)
    grown by twice the edge's measured offset beyond it (:func:`~.pupil.edge_offset`: the
    step of a blurred step-and-iris model fitted to the median edge profile).
    angle_deg : the major axis from +x toward +y, [0, 180). area_px : pixels of the closed
    dark blob. threshold :
    the pupil threshold in the input's units (pixels ≤ it are dark). boundary_support : fraction
    of the fitted ellipse's outline backed by real edge points. fit_residual_px : RMS distance of
    those points to the ellipse.
    """

    centre_px: tuple[float, float]
    axes_px: tuple[float, float]
    angle_deg: float
    area_px: float
    threshold: float
    boundary_support: float
    fit_residual_px: float


@dataclass
class Glint:
    """A glint: ``centre_px`` (x, y) intensity-weighted centroid, ``area_px`` pixels above the
    glint threshold, ``peak`` its brightest pixel (input units), ``led`` its LED index or None,
    ``flux`` its light above the local background (input units × px), ``base`` that
    background (input units; None when not known)."""

    centre_px: tuple[float, float]
    area_px: float
    peak: float
    led: int | None = None
    flux: float = 0.0
    base: float | None = None


@dataclass
class Detection:
    """One frame's result: ``ok`` (trust it), ``failures`` (reasons; ``"warning: …"`` ones do
    not clear ``ok``), ``pupil``, ``glints`` (LED order first, then unmatched by peak),
    ``timings_ms`` per stage, ``glint_threshold`` the floor glint pixels are above (the 99th
    percentile, input units; None when nothing stood out), ``missing_leds`` the LEDs (indices
    into ``led_azimuths_deg``) left without a glint (empty when no LEDs were given)."""

    ok: bool
    failures: list[str]
    pupil: Pupil | None
    glints: list[Glint]
    timings_ms: dict[str, float] = field(default_factory=dict)
    glint_threshold: float | None = None
    missing_leds: list[int] = field(default_factory=list)


def _missing(
    img: np.ndarray, valid: np.ndarray | None, nonfinite: np.ndarray | None
) -> np.ndarray | None:
    """The missing pixels (bool): ``nonfinite`` (the float picture's non-finite pixels that
    :func:`_fill_holes` left, or None) and those outside ``valid``; None when there are none."""
    invalid = nonfinite if nonfinite is not None and nonfinite.any() else None
    if valid is not None:
        valid = np.asarray(valid, bool)
        if valid.shape != img.shape:
            raise ValueError(f"valid-area mask has shape {valid.shape}, the picture {img.shape}")
        invalid = ~valid if invalid is None else invalid | ~valid
    return invalid


#: The largest hole of non-finite pixels (px, 8-connected, not touching the picture's edge) that
#: :func:`_fill_holes` fills from its surround instead of leaving missing: a dead pixel or a
#: small cluster. ASSUMPTION (a choice, not a datum): 16 px, under a tenth of the smallest
#: pupil the detector answers (``min_pupil_px``); a larger hole may hide the pupil's edge.
HOLE_MAX_PX = 16


def _fill_holes(img: np.ndarray, nonfinite: np.ndarray) -> tuple[np.ndarray, int]:
    """Fill the small enclosed holes of ``nonfinite`` (bool, the picture's NaN/inf pixels) in
    ``img`` (float, modified) by OpenCV's inpainting (``cv2.inpaint``, Telea's fast marching,
    radius 3 px) from the valid pixels around them. A hole is an 8-connected component of at
    most :data:`HOLE_MAX_PX` pixels that does not touch the picture's edge: one dead pixel
    inside a pupil otherwise made the pupil "touch missing pixels" and refused it (a pupil cut
    by the frame). Returns (the pixels still missing, the number filled)."""
    n, lab, stats, _ = cv2.connectedComponentsWithStats(nonfinite.astype(np.uint8), connectivity=8)
    if n <= 1:
        return nonfinite, 0
    rows, cols = img.shape
    x, y = stats[:, cv2.CC_STAT_LEFT], stats[:, cv2.CC_STAT_TOP]
    w, h = stats[:, cv2.CC_STAT_WIDTH], stats[:, cv2.CC_STAT_HEIGHT]
    small = (stats[:, cv2.CC_STAT_AREA] <= HOLE_MAX_PX) & (x > 0) & (y > 0)
    small &= (x + w < cols) & (y + h < rows)
    small[0] = False
    if not small.any():
        return nonfinite, 0
    holes = small[lab]
    work = img.astype(np.float32)
    work[nonfinite] = 0.0
    filled = cv2.inpaint(work, holes.astype(np.uint8), 3, cv2.INPAINT_TELEA)
    img[holes] = filled[holes]
    return nonfinite & ~holes, int(holes.sum())


def _black_border(img: np.ndarray, lo: float, min_frac: float = 0.005) -> np.ndarray | None:
    """Pixels of a black border (bool), or None: the 4-connected regions of pixels at exactly
    the picture's darkest value ``lo`` that touch its edge and hold ≥ ``min_frac`` (0.5 %) of
    it — a crop that runs off the sensor, padding. A camera's dark pixels carry noise; a flat
    run at the minimum along the edge is no scene. Darker than any pupil, it would join a pupil
    it touches into one border-connected region; as missing pixels it cuts it instead."""
    edge = (img[0], img[-1], img[:, 0], img[:, -1])
    if not any((e == lo).any() for e in edge):
        return None
    # (OpenCV takes an array of 4 or fewer elements for a scalar: a 1 × 1 picture failed)
    flat = (
        cv2.compare(img, float(lo), cv2.CMP_EQ)
        if img.dtype != np.float64 and img.size > 4
        else None
    )
    if flat is None:
        flat = (img == lo).astype(np.uint8)
    if cv2.countNonZero(flat) < min_frac * img.size:
        return None  # too few pixels at the minimum for any region to be a border
    _, lab, stats, _ = cv2.connectedComponentsWithStats(flat, connectivity=4)
    on_edge = np.unique(np.concatenate([lab[0], lab[-1], lab[:, 0], lab[:, -1]]))
    on_edge = on_edge[(on_edge > 0) & (stats[on_edge, cv2.CC_STAT_AREA] >= min_frac * img.size)]
    if not len(on_edge):
        return None
    return np.isin(lab, on_edge)


def _mend_hot_pixels(img: np.ndarray, noise: float, q: float) -> tuple[int, float | None]:
    """Isolated hot pixels (stuck or defective: above the 99.9th percentile and 8 σ of the pixel
    noise above all 8 neighbours, which are flat within 8 σ) take the median of those
    neighbours, in place; returns how many, and the ``q``-th percentile of the pixels that 99.9th
    is taken over (every k-th each way, :func:`~.pupil._stride`: ``work_picture``'s, from the
    same count) when none was mended (else, or for a picture under 3 px a side, None). A glint,
    spread by the optics, lights some of its neighbours more than others; a hot pixel alone
    would set the picture's range and hide the glints."""
    rows, cols = img.shape
    if rows < 3 or cols < 3:
        return 0, None
    step = _stride(img.size)  # work_picture's: the same pixels for both percentiles
    thr, pct = percentiles(img[::step, ::step], (99.9, q))
    if img.dtype.kind in "iu":
        # The pixels above (I > t ⇔ I > ⌊t⌋ for integers), in row order: each row's maximum,
        # then the pixels of the rows holding any (a few hundred pixels of a frame), in one
        # compiled pass (:func:`_rows_above`; the comparison mask, its rows' sums and
        # cv2.findNonZero on those rows took ~3 ×).
        hit, found = _rows_above(img, math.floor(thr))
    else:
        # (cv2.compare is ~10× NumPy's comparison here.)
        above = cv2.compare(img, float(thr), cv2.CMP_GT)
        # The pixels above, in row order, looked for only in the rows holding any (a few
        # hundred pixels of a frame: cv2.findNonZero over the whole mask cost 5× the
        # comparison). The rows' sums (32-bit) find them: OpenCV's REDUCE_MAX along rows is
        # ~100× slower (0.8 ms at 640 × 400); cv2.findNonZero on those rows: (x, row) in row
        # order, as np.nonzero (6 × its speed).
        hit = np.flatnonzero(cv2.reduce(above, 1, cv2.REDUCE_SUM, dtype=cv2.CV_32S).ravel())
        found = cv2.findNonZero(above[hit]).reshape(-1, 2) if len(hit) else None
    if not len(hit):
        return 0, pct
    # The rest — their 8 neighbours' range and median (float64, the median the mean of the
    # middle two, cast back to the picture's type), all judged before any is mended — in one
    # compiled pass (:func:`_mend_alone`; the NumPy gather and reductions it replaces cost
    # ~0.1 ms).
    n = _mend_alone(img, found, hit, 8.0 * noise, 0.01 * img.size)
    return n, (None if n else pct)


@njit(cache=True, nogil=True)
def _rows_above(img, t):
    """The pixels of the integer picture ``img`` above ``t`` (an integer): the rows holding
    any (ascending int64) and the pixels as (column, index into those rows) (n, 2) int32, in
    row order — ``cv2.findNonZero`` of the comparison mask's rows that hold any."""
    rows, cols = img.shape
    hit = np.empty(rows, np.int64)
    count = np.empty(rows, np.int64)
    n_rows = n = 0
    for r in range(rows):
        row = img[r]
        top = row[0]
        for c in range(1, cols):  # (a select, not max(): the loop is vectorised)
            v = row[c]
            top = v if v > top else top
        if top > t:
            k = 0
            for c in range(cols):
                k += row[c] > t
            hit[n_rows] = r
            count[n_rows] = k
            n_rows += 1
            n += k
    found = np.empty((n, 2), np.int32)
    i = 0
    for j in range(n_rows):
        row = img[hit[j]]
        for c in range(cols):
            if row[c] > t:
                found[i, 0] = c
                found[i, 1] = j
                i += 1
    return hit[:n_rows], found


@njit(cache=True, nogil=True)
def _alone_median(img, r, c, k_sigma, nb):
    """The median of pixel (r, c)'s 8 neighbours (float64, into the buffer ``nb``) when it
    stands ``k_sigma`` over all of them and their range is within ``k_sigma``, else NaN."""
    k = 0
    for dr in range(-1, 2):
        for dc in range(-1, 2):
            if dr or dc:
                nb[k] = np.float64(img[r + dr, c + dc])
                k += 1
    top, bottom = nb.max(), nb.min()
    if np.float64(img[r, c]) - top > k_sigma and top - bottom <= k_sigma:
        srt = np.sort(nb)
        return 0.5 * (srt[3] + srt[4])
    return np.nan


@njit(cache=True, nogil=True)
def _mend_alone(img, found, hit, k_sigma, max_count):
    """:func:`_mend_hot_pixels` on the pixels above the 99.9th percentile (``found`` (n, 2):
    column and index into ``hit``, the rows holding any): the inner ones (none mended when
    there are more than ``max_count``) that stand ``k_sigma`` over all 8 neighbours, whose range
    is within ``k_sigma``, take the neighbours' median, in place; returns how many."""
    rows, cols = img.shape
    n = found.shape[0]
    inner = np.zeros(n, np.bool_)
    n_inner = 0
    for i in range(n):
        r, c = hit[found[i, 1]], found[i, 0]
        if r > 0 and c > 0 and r < rows - 1 and c < cols - 1:
            inner[i] = True
            n_inner += 1
    if n_inner == 0 or n_inner > max_count:
        return 0
    value = np.full(n, np.nan)
    nb = np.empty(8)
    for i in range(n):
        if inner[i]:
            value[i] = _alone_median(img, hit[found[i, 1]], found[i, 0], k_sigma, nb)
    m = 0
    for i in range(n):
        if value[i] == value[i]:
            img[hit[found[i, 1]], found[i, 0]] = value[i]
            m += 1
    return m


def _valid_noise(img: np.ndarray, invalid: np.ndarray | None) -> float:
    """The pixel noise σ (:func:`~.pupil.noise_sigma`) of the valid pixels: with missing pixels
    (``invalid``, bool), which are set to one value, over the pixels whose 3 × 3 neighbourhood
    is all valid (else the flat fill's zeros pull the median down: half a picture masked out
    gave σ 0.5 for 3, and sclera noise 5 DN passed for glints at the mask's edge)."""
    if invalid is None:
        return noise_sigma(img)
    inner = cv2.erode((~invalid).view(np.uint8), np.ones((3, 3), np.uint8))
    m = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], np.float32)
    r = cv2.filter2D(img.astype(np.float32), cv2.CV_32F, m, borderType=cv2.BORDER_REPLICATE)
    vals = np.abs(r[inner > 0])
    if vals.size == 0:
        return noise_sigma(img)
    vals = vals[:: max(1, vals.size // 20000)]
    return 1.4826 * float(np.median(vals)) / 6.0


#: :func:`_prepare`: the largest pixel magnitude a float picture may hold — √ of float32's
#: largest value (1.8e19): the noise and fit steps square differences of pixel values in float32
_FLOAT_LIMIT = float(np.sqrt(np.finfo(np.float32).max))


def _check_magnitude(img: np.ndarray) -> None:
    """Raise ValueError when a float picture's largest magnitude is over :data:`_FLOAT_LIMIT`."""
    if img.dtype.kind != "f":
        return
    big = float(np.abs(img).max())
    if big > _FLOAT_LIMIT:
        raise ValueError(
            f"the picture's values reach {big:.3g}: detection squares pixel differences in "
            f"float32, which overflows beyond {_FLOAT_LIMIT:.3g} (√ of float32's largest); "
            "rescale the picture"
        )


def _prepare(image: np.ndarray, valid: np.ndarray | None, q: float):
    """Step 1: the picture as a contiguous array (uint8/uint16/int16/float32 kept, other reals
    converted), its small enclosed non-finite holes filled (:func:`_fill_holes`), its invalid
    pixels (non-finite, or outside ``valid``; ``None`` when none) set to the darkest valid value,
    its range (min, max), its pixel noise, the counts (hot pixels, black border, filled) and,
    when known, the working picture's scale (:func:`~.pupil.work_picture`'s ``scale``: its
    (min, max, ``q``-th percentile), which needs no pixel left out nor mended; else None).
    (The glints' 8-bit picture is made by :func:`~.glints.find_glints`, from the smoothed
    picture when it smooths.)
    Raises ValueError for a picture that is not 2-D, empty, has no valid pixel, or holds
    values beyond :data:`_FLOAT_LIMIT`."""
    img = np.asarray(image)
    if img.ndim != 2:
        raise ValueError(f"detect needs a 2-D grey picture, got shape {img.shape}")
    if img.size == 0:
        raise ValueError(f"detect needs a non-empty picture, got shape {img.shape}")
    if img.dtype == bool or img.dtype not in (np.uint8, np.uint16, np.int16, np.float32):
        img = img.astype(np.float64 if img.dtype.kind == "f" else np.float32)
    img = np.array(img, order="C", copy=True)
    nonfinite, n_filled = None, 0
    if img.dtype.kind == "f":
        nonfinite = ~np.isfinite(img)
        if nonfinite.any() and not nonfinite.all():
            nonfinite, n_filled = _fill_holes(img, nonfinite)
    invalid = _missing(img, valid, nonfinite)
    if invalid is not None:
        if invalid.all():
            raise ValueError("the picture has no valid pixel (all NaN/inf or masked out)")
        img[invalid] = img[~invalid].min()
    _check_magnitude(img)
    # The range, for the black border's level and, unless hot pixels are mended, the answer.
    lo, hi, _, _ = cv2.minMaxLoc(img)
    black = _black_border(img, lo)
    n_black = 0
    if black is not None and not (invalid is not None and (invalid | black).all()):
        n_black = int(black.sum()) if invalid is None else int((black & ~invalid).sum())
        invalid = black if invalid is None else invalid | black
    noise = max(_valid_noise(img, invalid), 0.5 if img.dtype.kind in "iu" else 0.0)
    n_hot, pct = _mend_hot_pixels(img, noise, q)
    if n_hot:  # (a mended pixel takes its neighbours' median: the maximum may be lower)
        lo, hi, _, _ = cv2.minMaxLoc(img)
    scale = (lo, hi, pct) if invalid is None and pct is not None else None
    return img, invalid, float(lo), float(hi), (n_hot, noise, n_black, n_filled), scale


def _pupil_result(fit, params) -> tuple[Pupil | None, list[str], object]:
    """Step 4: the :class:`Pupil`, the errors that make it untrustworthy (cut, cut by an
    eyelid, not an ellipse; a ``"warning: "`` when an eyelid's edge was left out of the fit,
    :func:`_straight_arc`) and the fit it reports (refitted without a lid's edge), or (None,
    [refusal], fit)."""
    if not fit:
        return None, [fit.reason], fit
    errors = []
    lid = _straight_arc(fit, params)
    if lid:
        fit, note = lid
        errors.append(note)
    major, minor, ang = fit.ellipse.major_minor_angle
    pupil = Pupil(
        centre_px=(fit.ellipse.cx, fit.ellipse.cy),
        axes_px=(major, minor),
        angle_deg=ang,
        area_px=fit.area_px,
        threshold=fit.threshold,
        boundary_support=fit.support,
        fit_residual_px=fit.residual_px,
    )
    if fit.support < params.min_boundary_support or fit.gap > params.max_boundary_gap:
        dr = fit.dropped or {}
        errors.append(
            f"pupil cut or hidden: {100 * fit.support:.0f} % of its fitted outline is backed by "
            f"edge points (need {100 * params.min_boundary_support:.0f} %), the longest "
            f"unbacked arc is {100 * fit.gap:.0f} % of it (at most "
            f"{100 * params.max_boundary_gap:.0f} %); "
            f"outline points dropped: {dr.get('border', 0)} on the image border, "
            f"{dr.get('glint', 0)} on glints, {dr.get('outlier', 0)} off the ellipse "
            "(e.g. an eyelid's edge)"
        )
    limit = _residual_limit(fit.ellipse, params)
    if fit.residual_px > limit:
        errors.append(
            f"pupil outline is not an ellipse: RMS residual {fit.residual_px:.2f} px "
            f"(limit {limit:.2f} px)"
        )
    return pupil, errors, fit


def _edge_axes(pupil: Pupil | None, fit) -> Pupil | None:
    """The pupil with its edge's axes: the fitted ¼ iso-line's grown by twice the edge's
    offset beyond it (:func:`~.pupil.edge_offset`). The glints are looked for about the
    iso-line (their reach and caps scale with its axes, as they were set on it)."""
    if pupil is None or not fit.edge_offset_px:
        return pupil
    grow = 2.0 * fit.edge_offset_px
    return dataclasses.replace(pupil, axes_px=(pupil.axes_px[0] + grow, pupil.axes_px[1] + grow))


def _straight_arc(fit, params) -> tuple | None:
    """The fit without an eyelid's edge, or None when its outline holds none: a window of its
    inlier edge points,
    contiguous (no gap over ``lid_arc_max_gap_deg``) over ``lid_arc_deg`` (90°) of the ellipse's
    eccentric anomaly and holding ≥ ``lid_arc_min_points`` (run forward and backward in
    anomaly from each point), that a straight line fits better
    (smaller RMS perpendicular distance, total least squares) than the fitted ellipse does, and
    significantly straighter than the ellipse's own arc there (:func:`_flat_windows`: the
    squared line misfit 3 standard deviations below σ² + A², σ the edge points' noise, A²
    what the arc's curvature adds). Without that bound, on a
    noisy edge an ellipse loses to a line by chance (σ 0.46 px on a 7 px pupil: 58 of 200
    whole circles had such a window).

    A quarter of an ellipse bows 0.29 × its semi-axis away from its chord (0.9 px for the
    smallest pupil answered, 30 px in area; 2 px for paper2005's 14 px pupil), so on a pupil's
    own edge a line fits worse than the ellipse by that sagitta over the edge noise; an eyelid
    crossing the pupil, whose edge's radius in the picture is many times the pupil's, is
    straight at that scale. Such points passed the robust fit's inlier tolerance (a noisy
    edge: paper2005 at (30°, −20°), 4 samples per pixel, σ 0.46 px, tolerance 1.4 px, where the
    lower lid's edge was fitted as the pupil's and the centre moved 1.3 px off the truth; 0.4
    px without those points): the centre is biased. Those points are left out and the ellipse
    refitted to the rest: returns (that fit — its support and gap on the rest, as
    :func:`~.pupil.support_of` — and a warning), or, when the rest is too little (fewer than
    ``min_edge_points``, or its support fails ``min_boundary_support`` /
    ``max_boundary_gap``), (the fit unchanged, the error "pupil cut by an eyelid").
    The real close-ups' and headset frames' figures (benchmarks/detect_real.py) are the same
    with it. The windows: :func:`_flat_windows`."""
    if fit.inliers is None or len(fit.inliers[0]) < params.lid_arc_min_points:
        return ""
    e = fit.ellipse
    x, y = fit.inliers
    s_, q_ = e.local(x, y)
    phi = np.degrees(np.arctan2(q_ / e.b, s_ / e.a)) % 360.0
    order = np.argsort(phi)
    n = len(order)
    d = sampson_distance(e, x[order], y[order])
    # the points and the ellipse's points at the same anomalies (a cos t, b sin t), in the
    # ellipse's own frame (a line's misfit does not depend on the frame)
    s_, q_ = s_[order], q_[order]
    r = np.hypot(s_ / e.a, q_ / e.b)
    r[r == 0] = 1.0
    # the windows run from each point forward in anomaly and, the outline reversed, backward:
    # a lid's straight edge ends at a corner where the pupil's own edge goes on, and the window
    # of ``lid_arc_deg`` that starts at one end of it runs past the other into that curve
    # (paper2005 at (−20°, −20°), seed 1: the lower lid's 12 points, 78° of the ellipse that
    # bent to them; every forward window from them ran past the far corner, and only the
    # backward one from that corner holds the lid alone. Answered 1.37 px off the truth)
    uv = np.column_stack((s_, q_, s_ / r, q_ / r))
    args = (float(params.lid_arc_deg), float(params.lid_arc_max_gap_deg))
    on = _flat_windows(phi[order], uv, d, *args, int(params.lid_arc_min_points))
    on |= _flat_windows(
        360.0 - phi[order][::-1], uv[::-1], d[::-1], *args, int(params.lid_arc_min_points)
    )[::-1]
    if not on.any():
        return None
    xs, ys = x[order][~on], y[order][~on]
    n_lid = int(on.sum())
    refit = None
    if len(xs) >= max(params.min_edge_points, 5):
        box = cv2.fitEllipse(np.column_stack([xs, ys]).astype(np.float32))
        if min(box[1]) > 0 and all(map(math.isfinite, (*box[0], *box[1]))):
            refit = Ellipse.from_box(box)
    what = (
        f"{n_lid} of the pupil's {n} outline points lie on a straight arc (a line fits them "
        f"better than the ellipse over {params.lid_arc_deg:g}° of it: an eyelid's edge)"
    )
    if refit is not None:
        support, gap = support_of(refit, xs, ys)
        moved = math.hypot(refit.cx - e.cx, refit.cy - e.cy)
        if support >= params.min_boundary_support and gap <= params.max_boundary_gap:
            d = sampson_distance(refit, xs, ys)
            new = dataclasses.replace(
                fit,
                ellipse=refit,
                support=support,
                gap=gap,
                residual_px=float(np.sqrt(np.mean(d * d))),
                n_points=len(xs),
                inliers=(xs, ys),
            )
            return new, (f"warning: {what}, left out of the fit: the centre moved {moved:.2f} px")
        return fit, (
            f"pupil cut by an eyelid: {what}; without them {100 * support:.0f} % of the "
            f"outline is backed (need {100 * params.min_boundary_support:.0f} %), the longest "
            f"unbacked arc is {100 * gap:.0f} % (at most "
            f"{100 * params.max_boundary_gap:.0f} %), and the centre moves {moved:.2f} px"
        )
    return fit, f"pupil cut by an eyelid: {what}; too few points left to refit without them"


@njit(cache=True, nogil=True)
def _window_sums(uv, d):
    """:func:`_flat_windows`' prefix sums over the circle twice (a window [i, j], j < i + n, is
    c[j + 1] − c[i]; columns Σu, Σv, Σu², Σv², Σuv of the points, the same of the ellipse's
    points, Σd²) and σ, the points' noise from the second differences of d along the outline
    (var = 1.5 σ² for independent points; blind to a smooth misfit, as pupil._robust_fit's
    first estimate)."""
    n = d.size
    hf = np.empty(n)
    for k in range(n):
        hf[k] = abs(d[k] - 0.5 * (d[k - 1] + d[(k + 1) % n]))
    noise = 1.4826 * np.median(hf) / math.sqrt(1.5)
    c = np.zeros((2 * n + 1, 11))
    for t in range(2 * n):
        k = t % n
        for col in range(2):
            p, q = uv[k, 2 * col], uv[k, 2 * col + 1]
            c[t + 1, 5 * col] = c[t, 5 * col] + p
            c[t + 1, 5 * col + 1] = c[t, 5 * col + 1] + q
            c[t + 1, 5 * col + 2] = c[t, 5 * col + 2] + p * p
            c[t + 1, 5 * col + 3] = c[t, 5 * col + 3] + q * q
            c[t + 1, 5 * col + 4] = c[t, 5 * col + 4] + p * q
        c[t + 1, 10] = c[t, 10] + d[k] * d[k]
    return c, noise


@njit(cache=True, nogil=True)
def _line_var(c, i, j, col):
    """The mean squared distance of the points of window [i, j] (prefix sums ``c``: columns
    col … col + 4 = Σu, Σv, Σu², Σv², Σuv) to their total-least-squares line."""
    m = j - i + 1
    su = c[j + 1, col] - c[i, col]
    sv = c[j + 1, col + 1] - c[i, col + 1]
    cxx = (c[j + 1, col + 2] - c[i, col + 2]) / m - (su / m) ** 2
    cyy = (c[j + 1, col + 3] - c[i, col + 3]) / m - (sv / m) ** 2
    cxy = (c[j + 1, col + 4] - c[i, col + 4]) / m - (su / m) * (sv / m)
    return max(0.5 * (cxx + cyy) - math.sqrt((0.5 * (cxx - cyy)) ** 2 + cxy * cxy), 0.0)


@njit(cache=True, nogil=True)
def _flat_windows(phi, uv, d, span, max_gap, min_points):
    """:func:`_straight_arc`'s windows over the points sorted by anomaly ``phi`` (degrees, in
    [0, 360)); ``uv`` (n, 4): their (u, v) px in the ellipse's frame and the ellipse's points
    at the same anomalies, ``d`` their distances to the ellipse: for each start i the points within
    ``span``° after it (round the circle), if contiguous (no step over ``max_gap``°), ≥
    ``min_points`` and spanning ≥ 0.8 ``span``, whose mean squared distance L² to their
    total-least-squares line is below the ellipse's (Σd²/m) and 3 standard deviations below
    σ² + A², σ the points' noise (px, from the second differences of ``d`` along the outline)
    and A² the same line misfit of the ellipse's own arc
    there: the pupil's arc gives L² ≈ σ² + A², with a variance 2 σ⁴ / (m − 2) + 4 σ² A² / m
    (the noise's χ² of m − 2 degrees of freedom, and its projection on the arc's bow).
    Returns the mask of points in any such window. The windows run forward only:
    :func:`_straight_arc` runs it on the reversed outline too."""
    n = phi.size
    on = np.zeros(n, np.bool_)
    c, noise = _window_sums(uv, d)
    j = 0
    for i in range(n):
        if j < i:
            j = i
        # extend j (an index into the doubled circle) while within span and contiguous
        while j + 1 < i + n:
            k = (j + 1) % n
            pk = phi[k] + (360.0 if j + 1 >= n else 0.0)
            pj = phi[j % n] + (360.0 if j >= n else 0.0)
            if pk - phi[i] > span or pk - pj > max_gap:
                break
            j += 1
        m = j - i + 1
        pj = phi[j % n] + (360.0 if j >= n else 0.0)
        if m < min_points or pj - phi[i] < 0.8 * span:
            continue
        line = _line_var(c, i, j, 0)
        arc = _line_var(c, i, j, 5)
        var = noise * noise
        # L² of the pupil's arc: σ² + A² (mean), its spread from the noise alone (a χ² of m − 2
        # degrees of freedom) and from the noise's projection on the arc's bow (2 ε·a)
        sd = math.sqrt(2.0 * var * var / max(m - 2, 1) + 4.0 * var * arc / m)
        below = var + arc - 3.0 * sd
        if line < (c[j + 1, 10] - c[i, 10]) / m and line < below:
            for t in range(i, j + 1):
                on[t % n] = True
    return on


def _sharp_glints(img, value_range, noise, floor, params):
    """For :func:`~.pupil.find_pupil`'s small-pupil pass when step 2 smoothed the picture (else
    None): a function giving the mask of the glints of the unsmoothed picture
    (:func:`~.glints.glints_near` over all of it) — each one pixel on a small sensor, lost to
    the smoothing, and beside a pupil of a few px enough to notch its blob."""
    if glint_smoothing(img.shape, params) < 0.5 or floor is None:
        return None
    rows, cols = img.shape

    def sharp() -> np.ndarray:
        mask = np.zeros((rows, cols), np.uint8)
        glints_near(
            img,
            value_range,
            noise,
            (cols / 2, rows / 2),
            math.hypot(rows, cols),
            floor,
            params,
            mask,
        )
        return mask

    return sharp


def _blobs_near_pupil(  # noqa: PLR0913 - the picture, its scale, the pupil, the reach
    img, value_range, noise, found, pupil, floor, params, n_leds=None, reach=1.0, jpeg_step=0.0
) -> list[dict]:
    """Step 5 (start): the bright blobs near the pupil (:func:`_bright_blobs_near`) and, with
    LEDs given and fewer blobs than LEDs among them, the unsaturated glints that stand out of
    their own background but not toward the picture's top (:func:`~.glints.faint_glints_near`,
    with a disc a quarter of the pupil's major axis across, ≥ 5 px: a glint is narrower, the
    iris beside the pupil broader), within the bright ones' size cap and not where one is.
    ``jpeg_step`` > 0 (DN, a JPEG's picture: :func:`~.glints.jpeg_dc_step`): that search is
    made whatever the bright blobs' count (the coding's ringing along the sclera's edges makes
    as many bright specks as LEDs, and the glints were never looked for: matched 94–231 px
    off), with the noise raised to the blocks' quantisation σ, step / √12 (a block one step
    over its neighbours stays under the top-hat's threshold, 4 σ), too-big blobs re-cut
    (``recut``) and the glints centred by :func:`_add_jpeg_glints`."""
    near = _bright_blobs_near(img, value_range, noise, found, pupil, floor, params, n_leds, reach)
    if n_leds is None or (len(near) >= n_leds and not jpeg_step):
        return near
    r_max = reach * params.glint_search_radius * pupil.axes_px[0]
    width = max(5, int(round(pupil.axes_px[0] / 4.0)) | 1)
    cap = min(_glint_cap(pupil, params, reach), width * width)
    faint_noise = max(noise, jpeg_step / math.sqrt(12.0))
    faint = faint_glints_near(
        img, faint_noise, pupil.centre_px, r_max, width, cap, params, recut=jpeg_step > 0
    )
    if jpeg_step:
        _add_jpeg_glints(img, noise, faint, near, params)
    else:
        for b in faint:
            if all(math.dist(t["centre_px"], b["centre_px"]) > 1.5 for t in near):
                near.append(_fitted_centre(img, noise, b, params))
    if len(near) < n_leds and not any(b["peak"] >= value_range[1] for b in near):
        # A defocused picture's glints are broad unsaturated bumps, wider than that disc
        # (:func:`~.glints.broad_glints_near`): looked for with wider discs, up to the pupil's
        # major axis (a bump broader than the pupil is no glint of its cornea), within the
        # glints' size cap (at half height: the disc's own bound, width², is what the narrow
        # disc's search needs, not a defocused glint's) — not when a saturated glint was
        # found, which is sharp, and so are the picture's others.
        for b in broad_glints_near(
            img, noise, pupil.centre_px, r_max, width, pupil.axes_px[0],
            _glint_cap(pupil, params, reach), params,
            n_leds - len(near),
        ):  # fmt: skip
            r = math.sqrt(b["area_px"] / math.pi)
            if all(math.dist(t["centre_px"], b["centre_px"]) > r for t in near):
                near.append(b)
    return near


def _fitted_centre(img, noise: float, blob: dict, params) -> dict:
    """An unsaturated glint of :func:`~.glints.faint_glints_near` centred by the fit of
    :func:`~.glints.fit_spot` (a Gaussian over a plane, on the picture) rather than its
    top-hat centroid: the top-hat's skirt holds the noise of every pixel above half the glint
    test and the opening's own shape, and a glint 10 σ over the pupil 5 px from its edge was
    1.3 px off (session 19's gl30.png; 0.46 px fitted; 0.41 -> 0.12 px at 20 σ). The centroid
    stays when the fit fails, moves it more than the blob's equivalent radius, or leaves
    residuals of RMS over 1.5 × the noise: a right model leaves the noise, ≤ 1 σ (0.74-1.33 σ on
    the unsaturated glints of the session 19-20 pictures), but a glint on the pupil's edge
    sits on a step no plane follows (2.8-3.0 σ; fitted 2.4 px off, its centroid 0.5)."""
    noise = max(noise, blob.get("noise", 0.0))  # (the local σ it was found with)
    fitted = fit_spot(img, noise, blob, params, min_half=3)
    if fitted is None or fitted["fit_rms"] > 1.5 * noise:
        return blob
    r = math.sqrt(blob["area_px"] / math.pi)
    if math.dist(fitted["centre_px"], blob["centre_px"]) > r:
        return blob
    return {**blob, "centre_px": fitted["centre_px"]}


def _add_jpeg_glints(img, noise: float, faint: list[dict], near: list[dict], params) -> None:
    """A JPEG's unsaturated glints (``faint``, :func:`~.glints.faint_glints_near`) added to
    ``near`` (in place), centred first — two blobs of one glint (the re-cut's pieces) end on
    its one spot, and one within 1.5 px of a blob taken is that blob. The strong ones (rising
    ≥ ``glint_strong_frac`` of the most any blob rises, the only ones :func:`_match_glints`
    matches in a JPEG) by :func:`_fitted_centre` when its fit holds (a glint 5 px from the
    pupil's edge, whose core's window reaches the iris: 0.3 px fitted, 2.6 px by its core at
    q75), else by :func:`_core_centre`; the weak ones (the coding's specks, ~100 a frame: a fit
    each took seconds) by :func:`_core_centre`."""
    rises = [b["peak"] - b["base"] for b in [*near, *faint]]
    top = max(rises, default=0.0)
    for b in faint:
        c = b
        if b["peak"] - b["base"] >= params.glint_strong_frac * top:
            c = _fitted_centre(img, noise, b, params)
        if c is b:
            c = _core_centre(img, noise, b, params)
        if all(math.dist(t["centre_px"], c["centre_px"]) > 1.5 for t in near):
            near.append(c)


def _core_centre(img, noise: float, blob: dict, params) -> dict:
    """A JPEG's unsaturated glint (:func:`_blobs_near_pupil` with ``jpeg_step``) centred on its
    core instead of its top-hat blob: the coding's ringing about the glint and along the
    pupil's edge rises over the blob's threshold and joins it (areas 150–180 px against
    30–70 for the glint alone), pulling its centroid 1.7–3.6 px (q15–55). The core: the pixels
    at least half the spot's rise (peak − the blob's base) over the base, joined to its
    brightest pixel within the blob's equivalent radius + 2 px of its centroid; their area A
    gives the spot's σ = √(A / (2 ln 2 π)) (a Gaussian's half-height disc). The centre is the
    centroid of max(I − B, 0) within R = max(2, 2.5 σ) px of the brightest pixel, B the median
    of the ring R + 1 … R + 3 px out, taken again about that centroid (rounded). On single
    glints of σ 1.2–1.6 px, blurred by 0.8, 110–180 DN over a flat 28 DN, noise 2–3.5 DN,
    coded at q15–90 (300 each), this centroid at R = 4 px was ≤ 0.46 px from the truth
    (95th percentile 0.30 at q15, 0.14 at q70). Falls back on the blob when the core is
    empty, runs off the picture, or its centre lies farther than the blob's equivalent radius
    + 2 px from the blob's (something brighter beside it)."""
    rows, cols = img.shape
    x, y = blob["centre_px"]
    r_eq = math.sqrt(blob["area_px"] / math.pi) + 2.0
    h = int(math.ceil(r_eq))
    x0, y0 = max(0, int(round(x)) - h), max(0, int(round(y)) - h)
    x1, y1 = min(cols, int(round(x)) + h + 1), min(rows, int(round(y)) + h + 1)
    win = np.asarray(img[y0:y1, x0:x1], np.float64)
    if win.size == 0:
        return blob
    yy, xx = np.mgrid[y0:y1, x0:x1]
    inner = np.hypot(xx - x, yy - y) <= max(1.5, r_eq - 2.0)
    py, px = np.unravel_index(int(np.argmax(np.where(inner, win, -np.inf))), win.shape)
    base = float(blob["base"])
    half = (win >= base + 0.5 * (float(win[py, px]) - base)).astype(np.uint8)
    _, lab = cv2.connectedComponents(half, connectivity=8)
    area = int(np.count_nonzero(lab == lab[py, px]))
    sigma = math.sqrt(area / (2.0 * math.log(2.0) * math.pi))
    r_c = max(2.0, 2.5 * sigma)
    cx, cy = float(px + x0), float(py + y0)
    for _ in range(2):
        m = int(math.ceil(r_c)) + 3
        ix, iy = int(round(cx)), int(round(cy))
        if ix - m < 0 or iy - m < 0 or ix + m >= cols or iy + m >= rows:
            return blob
        w = np.asarray(img[iy - m : iy + m + 1, ix - m : ix + m + 1], np.float64)
        yy, xx = np.mgrid[-m : m + 1, -m : m + 1]
        d = np.hypot(xx, yy)
        b = float(np.median(w[(d > r_c + 1.0) & (d <= r_c + 3.0)]))
        wgt = np.where(d <= r_c, np.maximum(w - b, 0.0), 0.0)
        tot = float(wgt.sum())
        if not tot > 0:
            return blob
        cx = ix + float((wgt * xx).sum()) / tot
        cy = iy + float((wgt * yy).sum()) / tot
    if math.dist((cx, cy), (x, y)) > r_eq:
        return blob  # (not this blob's spot: something brighter beside it)
    return {**blob, "centre_px": (cx, cy)}


def _glint_cap(pupil, params, reach: float = 1.0) -> float:
    """The largest area (px) of a glint near ``pupil``: ``glint_max_pupil_frac`` of the pupil's,
    × ``reach`` on :func:`_wider_look`'s second look. A glint's picture is the LED's virtual
    image (a fraction of a millimetre) spread by the camera's blur and a saturated spot's
    bloom, neither of which shrinks with the pupil: a 2 mm pupil 8-10 px across holds glints
    of 17-18 px, 0.27-0.42 of its area. Not on the first look: lit lid margins beside a
    large pupil (glasses-frame at gaze (0°, 0°): 1234 px at full scale by a 7000 px pupil)
    would pass, and, holding the most light at the top of the scale, make the real glints
    specks (:func:`_split_specks`); saturated skin beside a small pupil (eyetrackvr: lit brow
    and lid, 38-125 px by a 60 px pupil)."""
    area = math.pi / 4.0 * pupil.axes_px[0] * pupil.axes_px[1]
    return reach * params.glint_max_pupil_frac * area


def _bright_blobs_near(  # noqa: PLR0913 - the picture, its scale, the pupil, the reach
    img, value_range, noise, found, pupil, floor, params, n_leds=None, reach=1.0, cap=None
) -> list[dict]:
    """Step 5 (start): the bright blobs that can be the cornea's glints on this pupil, from
    ``found`` = (blobs, bright mask) of step 2 — within ``glint_search_radius`` × its major
    axis of its centre, no larger than ``glint_max_pupil_frac`` × its area (saturated skin
    beside a small pupil is no glint) and with a peak ``glint_level`` of the way from the
    blob's own background to the picture's top — and, when step 2 worked on a smoothed
    picture, those the smoothing lost there (:func:`~.glints.glints_near`: glints under a
    pixel across, or a 3σ square that σ's smoothing dims by a quarter) — ≤ max(2, (3σ)²) px,
    their peak within 2 % of the picture's top — whose centre is off
    step 2's mask. ``reach`` scales the search radius (:func:`_wider_look`); ``cap`` (px)
    replaces the size cap (:func:`_glint_cap`) when given.

    The peak test is the pixel test of step 2 against the blob's background (the median
    around it, :func:`~.glints.glint_blobs`) instead of the box mean, which next to a dark
    iris mixes it with the lit lid and lets the lid's texture through (eyetrackvr: 1–5 px
    specks 15 DN over a lid at 185 DN, 10 px from the pupil, against the glints' 230 DN
    over the iris)."""
    blobs, bright = found
    cx, cy = pupil.centre_px
    top = value_range[1]
    r_max = reach * params.glint_search_radius * pupil.axes_px[0]
    cap = _glint_cap(pupil, params, reach) if cap is None else cap

    # A glint is an isolated spot: at its peak's level it stops within its skirt. A gap between
    # dark lashes on a saturated lid runs on along its strip of lid at that level
    # (in_bright_run) — taken as glints, such pieces (eyelume's vr-offaxis at 850 nm in
    # sunlight: 2-9 px at 1016 DN, 40-160 px from the true glints) were matched to LEDs and,
    # counted as glints of several pixels, kept the true ones from being looked for. The
    # peak's level: within glint_min_snr σ of it (what the noise cannot tell from it; a glint
    # rises that much over its background) and above its core (halfway from glint_level to
    # the peak) — not lower: a glint at the limbus (glasses-frame at (0°, 0°): 1016 DN, base
    # 291) joins the sclera beside it (~840 DN) at its core's level alone.
    core = 0.5 * (1.0 + params.glint_level)
    same = params.glint_min_snr * noise

    def corneal(b: dict) -> bool:
        x, y = b["centre_px"]
        return (
            math.hypot(x - cx, y - cy) <= r_max
            and b["area_px"] <= cap
            and b["peak"] - b["base"] >= params.glint_level * (top - b["base"])
            and not in_bright_run(img, b, core, same)
        )

    near = [b for b in blobs if corneal(b)]
    if floor is None:
        return near
    sigma = glint_smoothing(img.shape, params)
    smoothed = sigma >= 0.5
    if n_leds is not None and sum(b["area_px"] > 2 for b in near) >= n_leds:
        # As many glints of several pixels as LEDs: the smoothing lost none here, and the
        # search below (1.3 ms of a 640 × 400 frame's 7) would only add specks.
        return near
    rows, cols = bright.shape
    # A glint the smoothing lost holds its LED's light in a few pixels (≤ (3σ)², below: a larger
    # saturated blob keeps its smoothed peak, and one step 2 did not find was left out for a
    # reason — glasses-frame at (0°, −20°): pieces of a saturated lid highlight 150 px above
    # the pupil), the brightest thing per pixel, at the top of the scale (within 2 % of it, as
    # _split_specks takes the brightest glints). A pixel at the skin's level standing out of a
    # box mean that mixes the dark iris in is the lid's texture or noise (vr-offaxis at
    # (0°, −20°): 793 DN over lit skin at ~770, 14 px from LED 2's glint, which the lid hides,
    # was matched to it; glasses-frame at (−10°, 0°): two specks at 867 of 1017 DN, 104 px
    # from the pupil).
    # Unsmoothed (a picture under 240 px across), step 2 lost none to smoothing, but its
    # ``glint_min_area_px`` (2) left out a glint of one pixel: a diffraction-limited glint on
    # 12 µm pixels (paper2005-integrated: Airy radius 0.18 px, one saturated pixel whose
    # neighbours hold a third of it, below the glint threshold). Such a pixel is in step 2's
    # mask, so it is taken unless a blob already taken holds it — and only when a glint of
    # several pixels already reaches the top of the scale (else the top is not a glint's:
    # paper2005's irradiance picture at (30°, −10°), no glint found, took a 1-px highlight
    # 17 px from any glint's truth).
    taken = [b["centre_px"] for b in near]
    least = value_range[1] - 0.02 * (value_range[1] - value_range[0])
    if not smoothed and not any(b["peak"] >= least for b in near):
        return near
    # A saturated square of side 3σ keeps erf(3 / (2√2))² = 0.75 of its rise at its centre
    # after step 2's smoothing: enough lost to fall under step 2's threshold (glasses-frame at
    # (−10°, 0°) since d4b7805: LED 3's glint, 3 × 3 px at 1016 DN with a skirt ≤ 870, smoothed
    # under the threshold's 837 DN), so a smoothed picture's search takes up to (3σ)² px.
    # (Only blobs that small at the top can be taken: the others are not worked out.)
    max_area = max(2.0, (3.0 * sigma) ** 2) if smoothed else 2.0
    wanted = (max_area, least)
    for b in glints_near(img, value_range, noise, (cx, cy), r_max, floor, params, wanted=wanted):
        x, y = b["centre_px"]
        c, r = min(cols - 1, max(0, round(x))), min(rows - 1, max(0, round(y)))
        new = not bright[r, c] if smoothed else all(math.dist(t, (x, y)) > 1.5 for t in taken)
        if b["area_px"] <= max_area and b["peak"] >= least and corneal(b) and new:
            near.append(b)
    return near


def _match_or_look_wider(  # noqa: PLR0913 - the glints, the LEDs, the pupil, the second look
    glints, specks, led_azimuths_deg, pattern, params, wider, pupil=None, img=None, jpeg=False
):
    """Step 5b: :func:`_match_glints` on ``glints`` (``pupil``: the :class:`Pupil` or None); with
    an LED left without a glint and ``wider`` given (a callable: :func:`_wider_look` bound to
    the frame), its answer when it has one. Returns (glints, specks, messages, LEDs without a
    glint; ``jpeg``: see :func:`_match_glints`)."""
    lost, missing = _match_glints(glints, led_azimuths_deg, params, pattern, pupil, img, jpeg)
    if missing and wider is not None:
        again = wider()
        if again is not None:
            return again
    return glints, specks, lost, missing


def _glints_off_missing(  # noqa: PLR0913 - the blobs, the mask, the picture, its scale
    blobs: list[dict], invalid, img: np.ndarray, value_range, noise: float, params
) -> tuple[list[dict], list[str]]:
    """Step 5 (after the search): the blobs kept by the missing pixels (``invalid``, bool, the
    picture's shape, or None: all kept) and a warning for each one those pixels changed.

    A missing pixel is set to the darkest valid value, so the picture's edge at a valid-area
    mask or a black border is a step from black that the glint test takes for a bright spot (a
    sclera pixel at a mask's edge was matched to an LED). A blob whose square of half-side
    ⌈r⌉ + 3 px about its centre (r its equivalent radius: its skirt and the first of the
    background beyond) holds no missing pixel is kept as it is. One whose spot is cut — a
    missing pixel within r + max(2, ⌈r⌉) + 1 px of its centre: the blob and the skirt
    :func:`~.glints.glint_blobs` weighs, where its light is — is dropped with a warning
    naming the missing pixels: its centroid would be that of its visible part, and a bright
    edge beside a mask (a step from the black fill) looks the same. One whose spot is whole,
    with missing pixels only in the ring beyond, where its background is read (a column of
    missing pixels 6 px from a glint 3 px across: two of four glints were dropped until
    session 21), is judged again on the valid pixels alone: its background the median of the
    valid pixels of the square of half-side ⌈cut⌉ + 3 beyond the cut radius (≥ 8 of them),
    its peak standing ``glint_min_snr`` × ``noise`` and ``glint_level`` of the way from there
    to the picture's top (the corneal test of :func:`_bright_blobs_near`: a sclera pixel by a
    valid-area mask, whose median was pulled down by the black fill, fails it), and its
    centroid weighed again by max(I − B, 0) over the valid pixels within the cut radius; kept
    with a warning."""
    if invalid is None or not blobs:
        return blobs, []
    rows, cols = invalid.shape
    top = value_range[1]
    kept, notes = [], []
    for b in blobs:
        x, y = b["centre_px"]
        r = math.sqrt(b["area_px"] / math.pi)
        c, w = int(round(x)), int(round(y))
        h = int(math.ceil(r)) + 3
        if not invalid[max(0, w - h) : w + h + 1, max(0, c - h) : c + h + 1].any():
            kept.append(b)
            continue
        cut = r + max(2, math.ceil(r)) + 1.0
        h = int(math.ceil(cut)) + 3
        y0, x0 = max(0, w - h), max(0, c - h)
        win = img[y0 : w + h + 1, x0 : c + h + 1].astype(np.float64)
        bad = invalid[y0 : w + h + 1, x0 : c + h + 1]
        yy, xx = np.mgrid[y0 : y0 + win.shape[0], x0 : x0 + win.shape[1]]
        d = np.hypot(xx - x, yy - y)
        n_cut = int(np.count_nonzero(bad & (d <= cut)))
        where = f"the glint candidate at ({x:.1f}, {y:.1f}) px"
        if n_cut:
            notes.append(
                f"warning: {where} dropped: {n_cut} missing pixel(s) within {cut:.1f} px of it "
                "cut its spot (its centre cannot be read from its visible part alone)"
            )
            continue
        back = win[~bad & (d > cut)]
        if back.size < 8:
            continue
        base = float(np.median(back))
        peak = float(b["peak"])
        if peak - base < max(params.glint_min_snr * noise, params.glint_level * (top - base)):
            continue
        inner = ~bad & (d <= cut)
        wgt = np.where(inner, np.maximum(win - base, 0.0), 0.0)
        tot = float(wgt.sum())
        if tot <= 0:
            continue
        centre = (float((wgt * xx).sum() / tot), float((wgt * yy).sum() / tot))
        n_near = int(np.count_nonzero(bad))
        notes.append(
            f"warning: {where} kept beside {n_near} missing pixel(s) (none within {cut:.1f} px: "
            "its spot is whole); its background read from the valid pixels only"
        )
        kept.append({**b, "centre_px": centre, "base": base, "flux": tot})
    return kept, notes


def _wider_look(  # noqa: PLR0913 - the picture, its scale, the pupil, the LEDs
    img,
    value_range,
    noise,
    found,
    pupil,
    floor,
    led_azimuths_deg,
    pattern,
    params,
    invalid=None,
    jpeg_step=0.0,
):
    """Step 5 again, out to twice ``glint_search_radius`` × the pupil's major axis, for a frame
    whose LEDs were not all given a glint: the glints, specks and LEDs left without one when
    every LED then has a glint and they fit the LEDs' pattern (:func:`_pattern_misfit`, the
    azimuths' ring without ``pattern``), else None.

    The search radius scales with the pupil, but the cornea does not: the pupil is 2-8 mm
    across, the cornea's visible disc ~12 mm, so glints lie up to 3 diameters of a 2 mm pupil
    from its centre (a 9 px pupil with glints 25 px out: all four lost), out of the radius
    that keeps a large pupil's strays away (lit lashes' gaps 160 px from a 60 px pupil). Out
    there a blob is taken only as part of a whole pattern: strays seldom complete one.

    Nor does a glint's size shrink with the pupil: step 2's blobs over the size cap
    (:func:`_glint_cap`, ½ the pupil's area on this look) are tried too when that gives no
    answer — taken only when, with the others, they give every LED a glint fitting the
    pattern and the matched glints' areas are alike (the largest ≤ ``glint_max_flux_ratio`` ×
    the smallest: one ring's LEDs make like glints, :func:`_too_bright`): a 7 px pupil with
    four saturated glints of σ 2.6 px (86-89 px each, its cap 58) had none ("glint lost")."""
    # Step 2's blobs only (no floor: glints_near's search for glints the smoothing lost, 1.3 ms
    # of a 640 × 400 frame, is not run again for every frame with an LED left without one).
    n_leds = len(led_azimuths_deg)
    blobs = _blobs_near_pupil(
        img, value_range, noise, found, pupil, None, params, n_leds, reach=2.0,
        jpeg_step=jpeg_step,
    )  # fmt: skip
    got = _whole_pattern(img, value_range, noise, blobs, pupil, led_azimuths_deg, pattern,
                         params, invalid, jpeg_step > 0)  # fmt: skip
    if got is not None:
        return got
    big = _bright_blobs_near(
        img, value_range, noise, found, pupil, None, params, n_leds, reach=2.0, cap=math.inf
    )
    cap = _glint_cap(pupil, params, 2.0)
    if not any(b["area_px"] > cap for b in big):
        return None
    got = _whole_pattern(img, value_range, noise, big, pupil, led_azimuths_deg, pattern,
                         params, invalid, jpeg_step > 0)  # fmt: skip
    if got is None:
        return None
    areas = [g.area_px for g in got[0] if g.led is not None]
    if max(areas) > params.glint_max_flux_ratio * min(areas):
        return None
    return got


def _whole_pattern(  # noqa: PLR0913 - the picture, its scale, the blobs, the pupil, the LEDs
    img, value_range, noise, blobs, pupil, led_azimuths_deg, pattern, params, invalid, jpeg=False
):
    """:func:`_wider_look`'s test of ``blobs``: (glints, specks, messages, LEDs without a
    glint) when every LED gets a glint and they fit the LEDs' pattern, else None."""
    kept, _ = _glints_off_missing(blobs, invalid, img, value_range, noise, params)
    glints, specks = _split_specks(kept, params)
    lost, missing = _match_glints(glints, led_azimuths_deg, params, pattern, pupil, img, jpeg)
    if missing or lost:
        return None
    max_ang = params.match_max_angle_deg
    if max_ang is None:
        max_ang = default_max_angle(led_azimuths_deg)
    if _pattern_misfit(glints, led_azimuths_deg, pattern, max_ang, params):
        return None
    return glints, specks, lost, missing


def _split_specks(blobs: list[dict], params) -> tuple[list[Glint], list[Glint]]:
    """Step 5a: the glints, and the specks — blobs with less than ``glint_min_flux_frac`` of the
    brightest glint's light (above its background), which no LED's corneal reflection is.

    The brightest glint is the one with most light among the blobs whose peak reaches the
    brightest pixel of any blob (to 2 %): a corneal glint, the image of a point source, is the
    brightest thing per pixel, and when it saturates its light is clipped — a broad diffuse
    highlight (a lit lid margin: vr-offaxis at gaze (0, 0), 54 px at 742 DN against eight
    saturated glints) may hold more light without being a glint, and must not make the real
    ones specks; nor may a lit patch near the top of the scale (:func:`_brightest_glint_flux`).
    Nor may a broad highlight whose peak is as high but which rises less than
    ``glint_level`` of the most any of those rises over its own background: a corneal glint
    stands farthest out of its surround (a lit lid's highlight of 1 308 px at 252 of 255 DN
    over a 196 DN lid, beside six glints rising ~220 DN, on glasses-frame's eye_image.png at
    gaze (10°, −5°), seed 3: it made all six specks, "glint lost: 0 of 6", until session 21)."""
    every = [
        Glint(b["centre_px"], b["area_px"], b["peak"], flux=b["flux"], base=b["base"])
        for b in blobs
    ]
    top = _brightest_glint_flux(every, params)
    glints = [g for g in every if g.flux >= params.glint_min_flux_frac * top]
    specks = [g for g in every if g.flux < params.glint_min_flux_frac * top]
    return glints, specks


def _brightest_glint_flux(every: list[Glint], params) -> float:
    """The light (flux above background) of the brightest glint among ``every`` blob: the most
    among those whose peak reaches the brightest pixel of any (to 2 %), whose rise over their
    own background (peak − base) is at least ``glint_level`` of the most of those (a broad
    highlight on a bright lid, :func:`_split_specks`) and whose light per pixel above the glint
    threshold (flux / area) is at least half the most of those.

    A glint, the image of a point source, is compact: its light is held in a few pixels and
    their skirt; a lit patch of sclera or lid near the top of the scale spreads more light
    over hundreds of pixels at a fraction of that per pixel (glasses-frame's digital picture
    at gaze (10°, −5°): a 1360 px patch at 1002 of 1017 DN, 551 per pixel, against glints of
    2–5 px at 1016, 2900–6400 per pixel and 12–17 k in all — taken as the brightest glint it
    made all six glints specks and the frame was refused). A saturated glint bloomed over
    tens of pixels holds about (top − background) per pixel, as such a patch would: the patch
    is then left to the matching (:func:`_too_bright`)."""
    peak_top = max((g.peak for g in every), default=0.0)
    tops = [g for g in every if g.peak >= 0.98 * peak_top and g.area_px > 0]
    rise_top = max((g.peak - g.base for g in tops), default=0.0)
    tops = [g for g in tops if g.peak - g.base >= params.glint_level * rise_top]
    most = max((g.flux / g.area_px for g in tops), default=0.0)
    return max((g.flux for g in tops if g.flux / g.area_px >= 0.5 * most), default=0.0)


def _jpeg_fragments(glints: list[Glint], specks: list[Glint], params) -> list[Glint]:
    """The specks of a JPEG's picture that can be pieces of a glint (:func:`_broken_glints`):
    those rising ≥ ``glint_strong_frac`` of the most a glint rises over its background — the
    weaker ones are the coding's specks (:func:`_match_glints`), its ringing about the glint
    and along the pupil's edge, which do not move the glint's core (:func:`_core_centre`);
    counted, they refused 5 of 48 pictures of ``test_detect_glint_jpeg25.py`` as broken up."""
    rises = [g.peak - g.base for g in glints if g.led is not None and g.base is not None]
    if not rises:
        return specks
    top = max(rises)
    return [
        s for s in specks if s.base is None or s.peak - s.base >= params.glint_strong_frac * top
    ]


def _broken_glints(glints: list[Glint], specks: list[Glint], params) -> list[str]:
    """Step 5c: a matched glint with more than ``glint_max_fragment_frac`` of its light in specks
    within 2 r + 4 px of it (r its equivalent radius) is broken up — the sparse samples of a
    noisy picture (a Monte Carlo render with few samples, a short exposure) — and its centroid
    is uncertain by more than the detector's precision: an error, not a number to trust."""
    out = []
    for i, g in enumerate(glints):
        if g.led is None or g.flux <= 0:
            continue
        reach = 2.0 * math.sqrt(g.area_px / math.pi) + 4.0
        near = sum(
            s.flux
            for s in specks
            if math.hypot(s.centre_px[0] - g.centre_px[0], s.centre_px[1] - g.centre_px[1]) <= reach
        )
        if near > params.glint_max_fragment_frac * g.flux:
            out.append(
                f"glint {i} (LED {g.led}) is broken up: {100 * near / g.flux:.0f} % of its light "
                "is in specks around it (a noisy picture: more samples or a longer exposure); "
                "its centre is uncertain"
            )
    return out


def _pattern_misfit(glints: list[Glint], led_azimuths_deg, pattern, max_ang: float, params) -> str:
    """Why the matched glints do not fit the LEDs' glint pattern, or "" when they do.

    The pattern p_k (px, relative to its centre) is ``pattern`` when given (the glints'
    predicted layout, :func:`~.evaluate.led_picture_pattern`), else the unit vectors of the LED
    azimuths (a ring). The matched glints are fitted as g_k = t + s p_k (least squares in the
    shift t and the scale s): each must lie within s |p_k| sin(max_ang / 2) of t + s p_k —
    farther, and its direction from the pattern's centre could be a neighbour LED's (max_ang
    is the matching's own limit) — and s must be > 0 and, with a predicted pattern, within
    [``pattern_min_scale``, 1 / ``pattern_min_scale``]."""
    pairs = [(g.centre_px, g.led) for g in glints if g.led is not None]
    if pattern is None:
        az = np.radians(np.asarray(led_azimuths_deg, float))
        p_all = np.column_stack([np.cos(az), -np.sin(az)])
    else:
        p_all = np.asarray(pattern, float)
    g = np.array([c for c, _ in pairs], float)
    p = p_all[[k for _, k in pairs]]
    sol = pattern_fit(g, p)
    s = float(sol[2])
    if not (s > 0 and math.isfinite(s)):
        return "the matched glints lie in the reverse order of their LEDs'"
    if pattern is not None and not (params.pattern_min_scale <= s <= 1 / params.pattern_min_scale):
        return (
            f"the matched glints spread {s:.2f} × the predicted pattern (allowed "
            f"{params.pattern_min_scale:g}–{1 / params.pattern_min_scale:g})"
        )
    res = np.hypot(*(g - (sol[:2] + s * p)).T)
    tol = s * np.hypot(*p.T) * math.sin(math.radians(0.5 * max_ang))
    worst = int(np.argmax(res - tol))
    if res[worst] > tol[worst]:
        return (
            f"LED {pairs[worst][1]}'s glint lies {res[worst]:.1f} px from where the other "
            f"glints put it (tolerance {tol[worst]:.1f} px)"
        )
    return ""


def _uncertain_strays(glints: list[Glint], missing, pattern, max_ang: float) -> list[Glint]:
    """The unmatched glints that could be a missing LED's glint: all of them, unless the
    predicted layout ``pattern`` shows none can be (:func:`_strays_off_pattern`; those are
    then only warned of as matching no LED)."""
    strays = [g for g in glints if g.led is None]
    if strays and pattern is not None and _strays_off_pattern(glints, missing, pattern, max_ang):
        return []
    return strays


def _strays_off_pattern(glints: list[Glint], missing, pattern, max_ang: float) -> bool:
    """With the predicted layout ``pattern``: True when every unmatched glint lies farther than
    twice the matching tolerance s |p_k| sin(max_ang / 2) (:func:`_pattern_misfit`'s) from
    where the matched glints' fit t + s p_k puts each missing LED k's glint — none of them can
    be a missing LED's glint, even one displaced by a lid or the cornea's rim cutting it, so
    they do not make the matching uncertain (a lit lid margin or a skin highlight: vr-offaxis
    at (0°, −20°), a 185 px blob at 818 DN 33 px from where LED 2's glint, hidden by the lid,
    would be)."""
    p_all = np.asarray(pattern, float)
    pairs = [(g.centre_px, g.led) for g in glints if g.led is not None]
    sol = pattern_fit(np.array([c for c, _ in pairs], float), p_all[[k for _, k in pairs]])
    s = float(sol[2])
    if not (s > 0 and math.isfinite(s)):
        return False
    sin_half = math.sin(math.radians(0.5 * max_ang))
    for g in glints:
        if g.led is not None:
            continue
        for k in missing:
            where = sol[:2] + s * p_all[k]
            tol = 2.0 * s * math.hypot(*p_all[k]) * sin_half
            if math.hypot(g.centre_px[0] - where[0], g.centre_px[1] - where[1]) <= tol:
                return False
    return True


def _direction_off(centres: np.ndarray, leds, ref, led_azimuths_deg) -> np.ndarray:
    """Each glint's angle (degrees) from its LED's azimuth, seen from ``ref`` (∞ unmatched)."""
    rel = centres - np.asarray(ref, float)
    psi = np.degrees(np.arctan2(-rel[:, 1], rel[:, 0]))
    az = np.asarray(led_azimuths_deg, float)
    return np.array(
        [
            abs((p - az[k] + 180.0) % 360.0 - 180.0) if k is not None else math.inf
            for p, k in zip(psi, leds, strict=True)
        ]
    )


def _assign_leds(centres: np.ndarray, led_azimuths_deg, max_ang: float):
    """Each glint's LED or None, and notes on glints left out (module doc of :func:`detect`).

    Directions are taken from the glints' own centre: one glint alone has none (it is left
    unmatched unless there is one LED), and two have opposite ones, which tell their LEDs
    apart only when the LEDs are nearly opposite too — two neighbours of a ring lie exactly
    between two LEDs each, a tie (at max_ang) that is refused, not guessed: a pair's match
    must be within max_ang / 2 of its LEDs. With more glints and an LED left without one, a
    glint matched more than max_ang / 2 off its LED's direction lies between two LEDs' — two
    glints merged into one blob (at 87 × 65 two neighbours of the paper's ring are 4–5 px
    apart) or a stray, which also pulls the pattern's centre and so the others' directions —
    and the frame is refused (the notes returned)."""
    n, n_led = len(centres), len(led_azimuths_deg)
    if n < 2 and n_led > 1:
        return [None] * n, "", []
    if n:  # np.median(centres, axis=0) without its overhead: the middle one or two's mean
        s = np.sort(centres, axis=0)
        ref = tuple(s[n // 2] if n % 2 else (s[n // 2 - 1] + s[n // 2]) / 2)
    else:
        ref = (0.0, 0.0)
    leds, ref = match_leds(centres, led_azimuths_deg, ref, max_ang, with_reference=True)
    leds = list(leds)
    if n == 2 and n_led > 2:
        off = _direction_off(centres, leds, centres.mean(axis=0), led_azimuths_deg)
        if off.max() <= 0.5 * max_ang:
            return leds, "", []
        if math.isinf(off.max()):
            return [None, None], "; of the two glints found one matches no LED", []
        return (
            [None, None],
            (
                f"; the two glints found lie {off.max():.0f}° from their LEDs' directions (tie at "
                f"{max_ang:.0f}°): which LEDs they are is ambiguous"
            ),
            [],
        )
    between = []
    if n > 2 and len(set(leds) - {None}) < n_led:
        off = _direction_off(centres, leds, ref, led_azimuths_deg)
        for i in np.flatnonzero(np.isfinite(off) & (off > 0.5 * max_ang)):
            x, y = centres[i]
            between.append(
                f"the glint at ({x:.1f}, {y:.1f}) lies {off[i]:.0f}° off LED {leds[i]}'s "
                f"direction (at most {0.5 * max_ang:.0f}° with LEDs missing), between two "
                "LEDs' (two glints merged, or a stray?)"
            )
    return leds, "", between


def _all_matched(glints, led_azimuths_deg, pattern, max_ang: float, params) -> list[str]:
    """Every LED has a glint: with the predicted layout ``pattern`` they must fit it too (a
    stray matched to an LED whose own glint was not found — vr-offaxis at (30°, 0°): a skin
    highlight 63 px from LED 3's glint — is no glint); the error, or none."""
    misfit = (
        ""
        if pattern is None
        else _pattern_misfit(glints, led_azimuths_deg, pattern, max_ang, params)
    )
    if misfit:
        n = len(led_azimuths_deg)
        return [f"glint lost: all {n} LEDs have a glint but {misfit}: a stray taken for a glint?"]
    return []


def _leds_by_direction(centres: np.ndarray, led_azimuths_deg, max_ang: float, pattern):
    """Each glint's LED or None and the notes of :func:`_assign_leds` — or, with ``pattern``
    and ≥ 3 glints, :func:`~.glints.match_pattern`'s when it matches as many."""
    leds, ambiguous, between = _assign_leds(centres, led_azimuths_deg, max_ang)
    if pattern is not None and len(centres) >= 3:
        # The predicted layout (an off-axis camera's glints are a distorted ring, whose
        # directions from its centre are not the LEDs' azimuths): used when it matches at
        # least as many glints (glints.match_pattern; two glints fit any two of its points).
        by_pattern = match_pattern(centres, pattern)
        if sum(k is not None for k in by_pattern) >= sum(k is not None for k in leds):
            leds, ambiguous, between = by_pattern, "", []
    return leds, ambiguous, between


def _strong_first(glints: list[Glint], centres, led_azimuths_deg, max_ang: float, pattern, params):
    """The glints' LEDs matched strongest first, with :func:`_leds_by_direction`'s notes, or
    None when all the glints are strong (or fewer than two are).

    A corneal glint is the image of a point source: the brightest thing per pixel, saturated
    on most cameras, rising over its own background (pupil, iris) by far more than anything
    else near the pupil — the LEDs of one ring differ little at the cornea, and saturated
    glints over the pupil and the iris rise within 2 × of each other (255 − 20 against
    255 − 110). Specks rise a small share of that: a JPEG's compression specks 13–50 DN over
    a flat sclera against saturated glints' 225 (quality 8–20: matching by direction alone,
    which knows no scale, took specks 60 px out at an LED's azimuth over the glints 25 px
    from the pupil's centre), noise, a lid's texture. So the glints rising ≥
    ``glint_strong_frac`` of the strongest one's rise (peak − its background) are matched
    first; a weaker glint is then matched only to an LED left without one, and only where
    the strong ones' pattern puts that LED's glint (the fit t + s p_k of
    :func:`_pattern_misfit`, within its tolerance s |p_k| sin(max_ang / 2)) — a glint over
    the bright sclera, saturated too, rises less."""
    rise = np.array([g.peak - g.base if g.base is not None else math.inf for g in glints])
    if not np.isfinite(rise).all() or len(glints) < 3:
        return None
    strong = np.flatnonzero(rise >= params.glint_strong_frac * rise.max())
    if len(strong) < 2 or len(strong) == len(glints):
        return None
    s_leds, ambiguous, between = _leds_by_direction(
        centres[strong], led_azimuths_deg, max_ang, pattern
    )
    leds: list[int | None] = [None] * len(glints)
    for i, k in zip(strong, s_leds, strict=True):
        leds[int(i)] = k
    pairs = [(i, k) for i, k in enumerate(leds) if k is not None]
    missing = [k for k in range(len(led_azimuths_deg)) if k not in {k for _, k in pairs}]
    if len(pairs) < 2 or not missing:
        return leds, ambiguous, between
    if pattern is None:
        az = np.radians(np.asarray(led_azimuths_deg, float))
        p_all = np.column_stack([np.cos(az), -np.sin(az)])
    else:
        p_all = np.asarray(pattern, float)
    sol = pattern_fit(centres[[i for i, _ in pairs]], p_all[[k for _, k in pairs]])
    s = float(sol[2])
    if not (s > 0 and math.isfinite(s)):
        return leds, ambiguous, between
    sin_half = math.sin(math.radians(0.5 * max_ang))
    weak = [i for i in range(len(glints)) if leds[i] is None and i not in set(strong.tolist())]
    for k in missing:
        where = sol[:2] + s * p_all[k]
        tol = s * math.hypot(*p_all[k]) * sin_half
        d = {i: math.dist(centres[i], where) for i in weak if leds[i] is None}
        best = min(d, key=d.get, default=None)
        if best is not None and d[best] <= tol:
            leds[best] = k
    return leds, ambiguous, between


def _pattern_points(led_azimuths_deg, pattern) -> np.ndarray:
    """The LEDs' glint pattern p_k (k, 2): ``pattern`` when given, else the unit vectors of the
    LED azimuths, (cos φ, −sin φ) (a ring)."""
    if pattern is not None:
        return np.asarray(pattern, float)
    az = np.radians(np.asarray(led_azimuths_deg, float))
    return np.column_stack([np.cos(az), -np.sin(az)])


def _rival_patterns(  # noqa: PLR0913 - the glints, their LEDs, the layout, the pupil
    glints, centres, leds, led_azimuths_deg, pattern, max_ang: float, pupil, params
):
    """Step 5b, with glints left over after matching: the matching checked against the whole
    patterns the glints fit (:func:`~.glints.pattern_fits`, tolerance s |p_k| sin(max_ang / 2),
    :func:`_pattern_misfit`'s). Returns (leds, errors, warnings, undecided): ``undecided`` the
    indices of the glints at an LED's place that the fit could not tell apart (that LED left
    without a glint; no strays for :func:`_some_missing`: they were judged here).

    Matching each glint by its direction (or nearest place) alone can mix two patterns: a
    spectacle lens reflects the LEDs too — a shifted copy of the glints, as bright — and two
    glints of each, both in the LEDs' directions from the mixed set's centre, were matched (27–
    32 px off, answered ``ok``). Only strong glints (rising ≥ ``glint_strong_frac`` of the
    strongest one's rise, :func:`_strong_first`) and the matched ones take part. The
    candidates: the matching made, when it fits the pattern and has ≥ 3 glints, and the fits
    with at least as many glints (only those with the most when it does not fit), the best
    fitting (least residual) first. Candidates
    sharing < 2 glint–LED pairs are different patterns: one fitting far better than every other
    (:func:`_pick_family`) is taken; else the one whose centre t lies nearest
    the pupil's centre is taken when the other's is ≥ 2 × as far and farther by more than the
    pupil's semi-major axis (the LEDs' glints lie on the cornea around the pupil, their
    pattern's centre off the pupil's by the pupil–glint vector; a reflection's place is set by
    the lens, not the eye), else the frame is refused as ambiguous. Candidates sharing ≥ 2
    pairs differ at some LEDs only (two glints near one LED's place: the sun's glint beside an
    LED's): at each such LED the glint nearest where the shared glints' fit puts it is kept
    when the other is farther by more than 3 × that fit's residual (what the fit cannot tell
    apart is not told apart), else the LED is left without a glint (a warning). A fit that
    only adds a glint the matching left out is no rival, nor, when the matching made fits and
    no fit gives every LED a glint, a fit of another pattern (three glints of four fit more
    than one way): those glints are judged as strays by :func:`_match_glints`."""
    p_all = _pattern_points(led_azimuths_deg, pattern)
    sin_half = math.sin(math.radians(0.5 * max_ang))
    cands = _candidate_fits(glints, centres, leds, p_all, sin_half, params)
    if not cands:
        return leds, [], [], set()
    families: list[list[dict]] = []
    for f in cands:  # by residual: each family's first is its best fit
        for fam in families:
            if len(_pairs(f) & _pairs(fam[0])) >= 2:
                fam.append(f)
                break
        else:
            families.append([f])
    mine = [fam for fam in families if any(f.get("now") for f in fam)]
    if mine and max(f["count"] for f in cands) < len(p_all):
        # The matching made fits, and no fit gives every LED a glint: three glints of four fit
        # more than one way; the glints left over are strays for _match_glints to judge (one
        # where a missing LED's glint could be makes the matching uncertain).
        families = mine
    family, error = _pick_family(families, pupil)
    if error:
        return leds, [error], [], set()
    return _contested(centres, list(family[0]["leds"]), family, p_all)


def _pairs(fit: dict) -> set[tuple[int, int]]:
    """A fit's (glint index, LED) pairs."""
    return {(j, k) for j, k in enumerate(fit["leds"]) if k is not None}


def _candidate_fits(glints, centres, leds, p_all, sin_half: float, params) -> list[dict]:
    """:func:`_rival_patterns`'s candidates, least residual first (none: nothing to check)."""
    n = len(centres)
    n_now = sum(k is not None for k in leds)
    if n < 3 or n_now == n:
        return []
    rise = np.array([g.peak - g.base if g.base is not None else math.inf for g in glints])
    if np.isfinite(rise).all() and rise.max() > 0:
        strong = rise >= params.glint_strong_frac * rise.max()
        use = np.flatnonzero(strong | np.array([k is not None for k in leds]))
    else:
        use = np.arange(n)
    if len(use) < 3 or len(use) == n_now:
        return []
    fits = []
    for f in pattern_fits(np.asarray(centres, float)[use], p_all, sin_half):
        full: list[int | None] = [None] * n
        for j, k in zip(use, f["leds"], strict=True):
            full[int(j)] = k
        fits.append({**f, "leds": full})
    now = _as_fit(centres, leds, p_all, sin_half)
    if now is not None:
        cands = [now] + [
            f
            for f in fits
            if f["count"] >= n_now and f["leds"] != list(leds) and not _pairs(f) > _pairs(now)
        ]
    elif fits and fits[0]["count"] >= n_now:
        cands = [f for f in fits if f["count"] == fits[0]["count"]]
    else:
        return []
    return sorted(cands, key=lambda f: f["rms"])


#: :func:`_pick_family`: a pattern fit whose residual (rms, px) exceeds this many times
#: another's (and this many times the floor below) is a chance set of glints, not a copy of
#: the LEDs' pattern.
RIVAL_RMS_RATIO = 3.0
#: ... the floor (px): centroid noise and the cornea's distortion of the pattern leave a true
#: pattern's fit this far off. Measured over the detection tests (tests/analysis, 40 rival
#: checks): the LEDs' glints fit their pattern at 0.005–0.5 px rms in drawn pictures and up to
#: 1.86 px on vr-offaxis renders (8 LEDs seen off-axis, gaze 20°, −20°); chance sets of a stray
#: and two of the LEDs' glints at 8.0–10.9 px. 1.5 px puts the bar (4.5 px) 2.4 × above the
#: worst true fit and 1.8 × below the best chance one.
RIVAL_RMS_FLOOR_PX = 1.5


def _pick_family(families: list[list[dict]], pupil) -> tuple[list[dict], str]:
    """:func:`_rival_patterns`: the one pattern; or the one whose best fit's residual r is so
    much the least that every other's exceeds RIVAL_RMS_RATIO × max(r, RIVAL_RMS_FLOOR_PX) (a
    reflection of the LEDs in spectacles copies the pattern about as well as the cornea does;
    three glints that fit it only within the tolerance, 8 px off, are a stray and two of the
    LEDs' glints); or the one nearest the pupil's centre when the other's centre is ≥ 2 × as far
    and farther by more than the pupil's semi-major axis; else ([], the refusal)."""
    if len(families) == 1:
        return families[0], ""
    rms = [float(fam[0]["rms"]) for fam in families]
    best = int(np.argmin(rms))
    bar = RIVAL_RMS_RATIO * max(rms[best], RIVAL_RMS_FLOOR_PX)
    if all(r > bar for i, r in enumerate(rms) if i != best):
        return families[best], ""
    top = min(len(_pairs(fam[0])) for fam in families)
    if pupil is None:
        return [], _two_patterns(families, None, top)
    c = np.asarray(pupil.centre_px, float)
    d = [float(np.hypot(*(fam[0]["t"] - c))) for fam in families]
    order = np.argsort(d)
    d1, d2 = d[order[0]], d[order[1]]
    if not (d2 >= 2.0 * d1 and d2 - d1 > 0.5 * pupil.axes_px[0]):
        return [], _two_patterns([families[i] for i in order], sorted(d), top)
    return families[order[0]], ""


def _as_fit(centres, leds, p_all, sin_half: float) -> dict | None:
    """The matching ``leds`` as a :func:`~.glints.pattern_fits` entry (marked ``now``) when ≥ 3
    glints are matched and each lies within s |p_k| sin_half of t + s p_k of their fit, else
    None."""
    pairs = [(j, k) for j, k in enumerate(leds) if k is not None]
    if len(pairs) < 3:
        return None
    g = np.asarray(centres, float)[[j for j, _ in pairs]]
    p = p_all[[k for _, k in pairs]]
    sol = pattern_fit(g, p)
    s = float(sol[2])
    if not (s > 0 and math.isfinite(s)):
        return None
    res = np.hypot(*(g - (sol[:2] + s * p)).T)
    if (res > s * np.hypot(*p.T) * sin_half).any():
        return None
    rms = float(np.sqrt((res**2).mean()))
    return {"leds": list(leds), "count": len(pairs), "t": sol[:2], "s": s, "rms": rms, "now": True}


def _contested(centres, chosen, family, p_all):
    """:func:`_rival_patterns` within one pattern: at each LED k where another fit of
    ``family`` takes a different glint than ``chosen`` (the family's first), the glints are
    compared with where the fit of ``chosen``'s other glints puts k's: the nearest is kept when
    the others are farther by more than 3 × that fit's residual σ (per coordinate, 2m − 3
    degrees of freedom for m glints), else none (a warning). Returns (leds, [], warnings,
    undecided: the indices of the glints of the LEDs left so)."""
    first = list(chosen)
    contested = sorted(
        {
            k
            for f in family[1:]
            for j, k in enumerate(f["leds"])
            if k is not None and k in first and first.index(k) != j
        }
    )
    g = np.asarray(centres, float)
    warnings = []
    undecided: set[int] = set()
    for k in contested:
        cands = {first.index(k)} | {f["leds"].index(k) for f in family if k in f["leds"]}
        chosen = [None if kk == k else kk for kk in chosen]
        others = [(j, kk) for j, kk in enumerate(first) if kk is not None and kk != k]
        sigma = math.nan
        if len(others) >= 2:
            gs, ps = g[[j for j, _ in others]], p_all[[kk for _, kk in others]]
            sol = pattern_fit(gs, ps)
            res = gs - (sol[:2] + sol[2] * ps)
            sigma = float(np.sqrt((res**2).sum() / max(1, 2 * len(others) - 3)))
            where = sol[:2] + sol[2] * p_all[k]
            dists = sorted((float(np.hypot(*(g[j] - where))), j) for j in cands)
            if dists[1][0] - dists[0][0] > 3.0 * sigma:
                if chosen[dists[0][1]] is None:
                    chosen[dists[0][1]] = k
                continue
        spots = ", ".join(f"({g[j][0]:.1f}, {g[j][1]:.1f})" for j in sorted(cands))
        undecided |= cands
        warnings.append(
            f"warning: LED {k}'s glint left out: {len(cands)} glints fit the pattern at its "
            f"place ({spots}) and the other glints' fit (residual {sigma:.2f} px) does not "
            "tell which"
        )
    return chosen, [], warnings, undecided


def _two_patterns(families, dist, count: int) -> str:
    """The refusal for two sets of glints each fitting the LEDs' whole pattern."""
    where = []
    for i, fam in enumerate(families[:2]):
        t = fam[0]["t"]
        off = "" if dist is None else f", {dist[i]:.0f} px from the pupil's centre"
        where.append(f"centred at ({t[0]:.1f}, {t[1]:.1f}){off}")
    return (
        f"glint lost: two glint patterns fit the LEDs' with ≥ {count} glints each "
        f"({'; '.join(where)}): which is the LEDs' glints is ambiguous (a reflection of the "
        "LEDs in spectacles?)"
    )


def _too_bright(glints: list[Glint], params) -> list[tuple[int, float]]:
    """Matched glints holding more than ``glint_max_flux_ratio`` × the light (flux above their
    background) of the brightest other matched glint — (index, that ratio) each; none unless
    ≥ 3 are matched (two others to compare with).

    One ring's LEDs make glints of like light: the LEDs differ in distance and angle to the
    cornea, the glints in their background (pupil, iris) and how much of them saturates — in
    eyelume's renders (design benchmark frames, glasses-frame, vr-offaxis, paper2005) a
    correctly matched glint held at most 2.3 × the brightest other one's light. A blob at an
    LED's place holding several times more is the glint merged with another spot — the sun's
    corneal glint beside LED 1's (vr-offaxis in sunlight: 4.1–7.8 ×, its centroid 2–6 px off
    the glint, answered ``ok``) — or a lit patch of sclera or lid (hundreds of px) matched to
    an LED whose glint was not found; neither one's centroid is the glint's."""
    m = [(i, g) for i, g in enumerate(glints) if g.led is not None and g.flux > 0]
    if len(m) < 3:
        return []
    out = []
    for i, g in m:
        other = max(o.flux for j, o in m if j != i)
        if g.flux > params.glint_max_flux_ratio * other:
            out.append((i, g.flux / other))
    return out


#: :func:`_lit_patches`: how many times the other matched glints' median equivalent area a
#: blob no brighter than they are must have to be called a lit patch (:func:`_lit_patches`)
_PATCH_AREA_RATIO = 3.0


def _equivalent_area(g: Glint) -> float:
    """A glint's light over its rise, flux / (peak − base) (px²): 2πσ² for a Gaussian spot of
    σ, 2πσ² (1 + ln(P/C)) for one of peak P clipped at C."""
    return g.flux / max(g.peak - g.base, 1e-12)


def _lit_patches(glints: list[Glint]) -> list[tuple[int, float, float]]:
    """Matched glints that are a lit patch, not an LED's image — (index, its equivalent area,
    the other matched glints' median) each; none unless ≥ 3 are matched with a known
    background.

    The ring's glints are images of like point sources through the same optics: their
    equivalent areas (:func:`_equivalent_area`) differ only by the point spread's change over
    a few mm of the cornea and by clipping — up to 1 + ln 2.3 = 1.8 × between glints whose
    light differs by the 2.3 × of :func:`_too_bright`'s renders, and a glint no brighter
    (rise no higher) than the others' median is no more clipped than they are. A blob no
    brighter than that median whose equivalent area is over :data:`_PATCH_AREA_RATIO` × the
    others' median is a spread patch: in the 850/940 nm design run's frames (vr-offaxis, the
    sun on; 1 263 matched glints of 90 frames), pieces of bright sclera pinched between the
    dark iris and a shadow, matched to LEDs whose glints are off the cornea and answered
    ``ok`` (their "glints" 8–50 px from any), have 6–22 ×; the glints within 1.5 px of the
    truth at most 1.47 ×. (Medians, not extremes: two patches in one frame would each hide
    the other.) A brighter blob is left to :func:`_too_bright`, and so is a clipped one — its
    peak within 2 % of its rise of the matched glints' highest, the picture's top when they
    saturate: its rise is the clip level's, not its own, and its equivalent area its light
    over that level, which for spots clipped alike is the ratio of their light, not of their
    spread (eyetrackvr at (20°, 10°): four one-pixel glints at 254 of 255, LED 3's holding
    2.9 × the others' light, 3.2 × their equivalent area). In the design frames every
    clipped patch (peak 1017 DN) was beside an unclipped one of the same frame."""
    m = [(i, g) for i, g in enumerate(glints) if g.led is not None and g.base is not None]
    if len(m) < 3:
        return []
    eq = {i: _equivalent_area(g) for i, g in m}
    highest = max(g.peak for _, g in m)
    out = []
    for i, g in m:
        if g.peak >= highest - 0.02 * (highest - g.base):
            continue
        typical = float(np.median([eq[j] for j, _ in m if j != i]))
        rise = float(np.median([o.peak - o.base for j, o in m if j != i]))
        if eq[i] > _PATCH_AREA_RATIO * typical and g.peak - g.base <= rise:
            out.append((i, eq[i], typical))
    return out


def _spot_shape(img: np.ndarray, g: Glint) -> float | None:
    """The width of glint ``g``'s spot edge in ``img`` as a Gaussian's σ² (px²), from the area
    a₅₀ of its core — the pixels connected to its centre rising ≥ ½ of its rise P − B over
    its background B — and the area a₁₀ of the pixels rising ≥ 1/10 connected to it: for a
    Gaussian spot of σ, clipped or not, r₁₀² − r₅₀² = 2 σ² ln 5, so σ² = (a₁₀ − a₅₀) /
    (2π ln 5). None when the spot has no background or no core, or when that region reaches
    the window's edge (3 equivalent radii + 4 px out): another bright thing — a lid, the
    sclera, a highlight — joins it, and its edge is not the spot's alone."""
    if g.base is None or not g.peak > g.base:
        return None
    rows, cols = img.shape
    x, y = g.centre_px
    h = int(math.ceil(3.0 * math.sqrt(g.area_px / math.pi))) + 4
    c, r = min(cols - 1, max(0, round(x))), min(rows - 1, max(0, round(y)))
    y0, x0 = max(0, r - h), max(0, c - h)
    win = np.ascontiguousarray(img[y0 : r + h + 1, x0 : c + h + 1], dtype=np.float64)
    t50, t10 = g.base + 0.5 * (g.peak - g.base), g.base + 0.1 * (g.peak - g.base)
    # The core the centroid lies in (or, between two pixels, the nearest core pixel's): the
    # centroid's own pixel when it is a core pixel (then the nearest), else the nearest one.
    ny, nx = r - y0, c - x0
    if not win[ny, nx] >= t50:
        yy, xx = np.nonzero(win >= t50)
        if not len(yy):
            return None
        near = int(np.argmin((yy + y0 - y) ** 2 + (xx + x0 - x) ** 2))
        ny, nx = int(yy[near]), int(xx[near])
    a50, a10, edge = _connected_areas(win, t50, t10, ny, nx)
    if edge:
        return None  # joined to a lid, the sclera or another spot: not this spot's edge alone
    return (a10 - a50) / (2.0 * math.pi * math.log(5.0))


@njit(cache=True, nogil=True)
def _connected_areas(win, t50, t10, ny, nx):
    """(a₅₀, a₁₀, at the edge) for :func:`_spot_shape`: the pixel counts of the 8-connected
    regions of ``win`` (float64) ≥ ``t50`` and ≥ ``t10`` holding pixel (``ny``, ``nx``) (which
    is ≥ t50), and whether the second touches the window's edge (a flood fill each)."""
    rows, cols = win.shape
    out = np.zeros(3, np.int64)
    stack = np.empty(rows * cols, np.int64)
    for pass_, t in enumerate((t50, t10)):
        seen = np.zeros((rows, cols), np.bool_)
        seen[ny, nx] = True
        stack[0] = ny * cols + nx
        top, n, edge = 1, 0, False
        while top:
            top -= 1
            i, j = divmod(stack[top], cols)
            n += 1
            if i == 0 or j == 0 or i == rows - 1 or j == cols - 1:
                edge = True
            for di in (-1, 0, 1):
                for dj in (-1, 0, 1):
                    u, v = i + di, j + dj
                    if 0 <= u < rows and 0 <= v < cols and not seen[u, v] and win[u, v] >= t:
                        seen[u, v] = True
                        stack[top] = u * cols + v
                        top += 1
        out[pass_] = n
        if pass_ == 1:
            out[2] = edge
    return out[0], out[1], bool(out[2])


def _unlike_the_others(img: np.ndarray, glints: list[Glint], params) -> list[tuple[int, str]]:
    """Matched glints whose spot is not one point source's image like the other matched
    glints' — (index, why) each; none unless ≥ 3 are matched:

    - no skirt: a spot whose edge (σ² of :func:`_spot_shape`, the width of its fall from ½
      to 1/10 of its rise) is under ¼ of the narrowest other glint's (less than half as wide)
      when those are ≥ 1 px² — a point source's image has the optics' blur whatever its
      brightness or clipping, and a block of stuck or hot pixels has none (a 2 × 2 block at
      230 DN where LED 1's glint was absent, beside glints of σ 1.4 px, matched to LED 1);
    - a block, not a blurred spot (:func:`_block_not_blur`): a spot whose edge lies within a
      pixel (σ² of :func:`_spot_shape` under ¼ px²) when the others' edges cannot be read that
      way (their fall to 1/10 joins the pupil's edge or the iris beside them) or are under
      1 px²: judged by how much better it fits a block with no blur than a Gaussian of the
      other glints' own width, against the picture's noise (stuck blocks of 2–9 px at
      200–255 DN in pictures blurred by σ 0.8 px, 4.5 px inside the pupil's edge, were
      matched). With sharper optics the two models differ by less than the noise shows and
      the spot is kept."""
    m = [i for i, g in enumerate(glints) if g.led is not None]
    if len(m) < 3:
        return []
    shapes = {i: _spot_shape(img, glints[i]) for i in m}
    out = []
    widths: dict = {}  # (_block_not_blur's: the glints' widths and the picture's top, once)
    for i in m:
        own = shapes[i]
        edges = [shapes[j] for j in m if j != i and shapes[j] is not None]
        if own is None:
            continue
        if len(edges) >= 2 and min(edges) >= 1.0 and own < 0.25 * min(edges):
            out.append(
                (
                    i,
                    f"its edge is {math.sqrt(max(own, 0.0)):.2f} px wide as a Gaussian's σ, "
                    f"the other glints' {math.sqrt(min(edges)):.2f} px or more: no blur skirt "
                    "(stuck or hot pixels, not the optics' image of an LED)",
                )
            )
        elif own < _SHARP_EDGE_PX2:
            why = _block_not_blur(img, glints, i, [j for j in m if j != i], params, widths)
            if why:
                out.append((i, why))
    return out


#: :func:`_unlike_the_others`: a spot whose edge (:func:`_spot_shape`'s σ²) is under this
#: (px²) falls within one pixel — a uniform pixel's own spread is 1/12 px² — and is judged
#: against the other glints' profile (:func:`_block_not_blur`); a glint blurred by the
#: optics by ½ px or more is never (a first, cheap look that leaves most frames alone).
_SHARP_EDGE_PX2 = 0.25


def _block_not_blur(  # noqa: PLR0913 - the picture, the glints, which, the memo
    img: np.ndarray, glints: list[Glint], i: int, others: list[int], params, memo: dict
) -> str:
    """Why glint ``i``'s spot in ``img`` is a block of stuck or hot pixels rather than the
    optics' image of an LED like the glints ``others`` (indices), or "" (kept).

    Each glint's Gaussian σ is read from its skirt (:func:`~.glints.spot_sigma`); the others'
    narrowest, σₒ (≥ 2 of them read), is what a glint's skirt must show. A spot is fitted as a
    block (its core pixels free, the rest one background) and as a point source's Gaussian
    spot (:func:`~.glints.block_or_blur`), χ² from the pixel noise σ of the 33 × 33 px around
    the spot (Immerkær's, :func:`~.pupil.noise_sigma`): Δ = χ²_glint − χ²_block. A blurred
    spot leaves the block model its skirt (Δ ≪ 0); a block's hard edge leaves the glint model
    a skirt it does not have (Δ ≫ 0). The block model spends n_core − 1 more parameters; were
    the spot a glint of σₒ, the block could win by chance only as χ² with that many degrees
    of freedom: the spot is a block when its Δ at σₒ is beyond that χ²'s upper
    ``glint_skirt_p`` quantile — and no other glint read is, by the same test at its own σ.
    Where the glints themselves are that sharp, or unlike a Gaussian with noise the
    background's σ misstates (a render's glints: their shot noise, one-pixel spots), the test
    says nothing of the spot and it is kept. So too a spot over ``glint_max_flux_ratio`` ×
    the others' median area: one ring's LEDs make like glints (:func:`_too_bright`), and a
    spot that large is no point source's image like theirs, which the Gaussian model is
    (renders: a glint of 72-107 px beside others of 2-7 px, its edge sharp, was taken for a
    block). ``memo`` (a dict, empty at first) keeps the picture's
    top and noise and the glints' widths and Δ between calls for one frame."""
    from scipy.special import chdtri  # (only on this rare path)

    if glints[i].area_px > params.glint_max_flux_ratio * float(
        np.median([glints[j].area_px for j in others])
    ):
        return ""
    read = [j for j in others if _glint_width(img, glints, j, memo) is not None]
    noise = _glint_noise(img, glints, i, memo)
    if len(read) < 2 or not noise > 0:
        return ""
    sigma = min(_glint_width(img, glints, j, memo) for j in read)
    got = block_or_blur(img, _as_spot(glints[i]), sigma, memo["top"], noise)
    if got is None or got[0] <= float(chdtri(got[1], params.glint_skirt_p)):
        return ""
    for j in read:
        key = ("delta", j)
        if key not in memo:
            own = block_or_blur(
                img, _as_spot(glints[j]), _glint_width(img, glints, j, memo), memo["top"],
                _glint_noise(img, glints, j, memo),
            )  # fmt: skip
            memo[key] = (
                None if own is None else float(own[0] - chdtri(own[1], params.glint_skirt_p))
            )
        if memo[key] is None or not memo[key] <= 0:
            return ""
    return (
        f"its edge is sharper than a Gaussian spot of the other glints' σ {sigma:.2f} px "
        f"allows (a block of no blur fits it better by χ² {got[0]:.0f}, noise σ {noise:.2g}), "
        "while the others fit theirs: no blur skirt (stuck or hot "
        "pixels, not the optics' image of an LED)"
    )


def _as_spot(g: Glint) -> dict:
    """Glint ``g`` as the spot dict of :func:`~.glints.spot_sigma`."""
    return {"centre_px": g.centre_px, "area_px": g.area_px, "peak": g.peak, "base": g.base}


def _glint_noise(img: np.ndarray, glints: list[Glint], j: int, memo: dict) -> float:
    """The pixel noise σ (Immerkær's, :func:`~.pupil.noise_sigma`) of the 33 × 33 px of
    ``img`` about glint ``j``, kept in ``memo`` (:func:`_block_not_blur`; also the picture's
    top, ``memo["top"]``)."""
    if "top" not in memo:
        memo["top"] = float(np.max(img))
    key = ("noise", j)
    if key not in memo:
        x, y = glints[j].centre_px
        c, r = int(round(x)), int(round(y))
        near = img[max(0, r - 16) : r + 17, max(0, c - 16) : c + 17]
        memo[key] = noise_sigma(np.ascontiguousarray(near, dtype=np.float32))
    return memo[key]


def _glint_width(img: np.ndarray, glints: list[Glint], j: int, memo: dict) -> float | None:
    """Glint ``j``'s Gaussian σ px (:func:`~.glints.spot_sigma`), kept in ``memo``."""
    key = ("sigma", j)
    if key not in memo:
        noise = _glint_noise(img, glints, j, memo)
        memo[key] = spot_sigma(img, _as_spot(glints[j]), memo["top"], noise)
    return memo[key]


def _off_the_others(glints: list[Glint], led_azimuths_deg, pattern, params) -> tuple | None:
    """The matched glint lying farthest, beyond what the others' scatter allows, from where the
    other matched glints put its LED's glint — (index, distance px, allowed px, the others'
    residual σ px) — or None (fewer than 4 matched, or none beyond).

    Each matched glint j is left out in turn and the others fitted as g_k = t + s p_k
    (:func:`_pattern_misfit`'s model, least squares; p_k :func:`_pattern_points`). With m
    others their residual gives σ̂ per coordinate on ν = 2m − 3 degrees of freedom, and the
    prediction at p_j has variance σ̂² (1 + h) per coordinate (h the fit's leverage there,
    averaged over x and y). A glint of that LED lies at d from the prediction with
    d² / (2 σ² (1 + h)) an F(2, ν) variable, whose upper quantile at ``glint_off_fit_p`` is
    (ν / 2) (p^(−2/ν) − 1); the glint's own centroid bias, which the others' scatter need
    not show, adds ``glint_centroid_floor_px`` in quadrature. A glint beyond that is not
    the LED's (a stray 20–45° off a missing LED's direction on a 4-LED ring, matched by
    direction, or a lit patch 21 px from where a hidden LED's glint would be: both answered
    ``ok``). The others must number ≥ 3 (ν ≥ 3): two others fit t and s exactly and show no
    scatter."""
    m = [(i, g.led) for i, g in enumerate(glints) if g.led is not None]
    if len(m) < 4:
        return None
    p_all = _pattern_points(led_azimuths_deg, pattern)
    c = np.array([glints[i].centre_px for i, _ in m], float)
    p = p_all[[k for _, k in m]]
    nu = 2 * (len(m) - 1) - 3
    q = 0.5 * nu * (params.glint_off_fit_p ** (-2.0 / nu) - 1.0)  # F(2, ν) upper quantile
    floor2 = params.glint_centroid_floor_px**2
    worst = None
    # Normal equations of g = t + s p over all glints, each one's rows then taken out.
    rows_x = np.column_stack([np.ones(len(m)), np.zeros(len(m)), p[:, 0]])
    rows_y = np.column_stack([np.zeros(len(m)), np.ones(len(m)), p[:, 1]])
    ata = rows_x.T @ rows_x + rows_y.T @ rows_y
    atb = rows_x.T @ c[:, 0] + rows_y.T @ c[:, 1]
    # A bound first (the common case: every glint where the others put it). With all glints
    # fitted (residual e_j, hat block H_jj), glint j's distance from the others' prediction is
    # |(I − H_jj)⁻¹ e_j| ≤ |e_j| / (1 − tr H_jj) (H_jj is positive semi-definite: its largest
    # eigenvalue ≤ its trace), and the allowed distance ≥ √(2 q) × the floor (σ̂² ≥ 0, h ≥ 0):
    # when every glint's bound is under that, none is beyond and the loop is skipped.
    if abs(np.linalg.det(ata)) > 1e-12:
        inv_all = np.linalg.inv(ata)
        beta = inv_all @ atb
        e = c - (beta[:2] + beta[2] * p)
        tr = np.einsum("ij,jk,ik->i", rows_x, inv_all, rows_x) + np.einsum(
            "ij,jk,ik->i", rows_y, inv_all, rows_y
        )
        if np.all(tr < 1.0):
            bound = np.hypot(e[:, 0], e[:, 1]) / (1.0 - tr)
            if float(bound.max()) < math.sqrt(2.0 * q * floor2):
                return None
    for j in range(len(m)):
        ax, ay = rows_x[j], rows_y[j]
        mat = ata - np.outer(ax, ax) - np.outer(ay, ay)
        if abs(np.linalg.det(mat)) < 1e-12:
            continue
        inv = np.linalg.inv(mat)
        sol = inv @ (atb - ax * c[j, 0] - ay * c[j, 1])
        if not (sol[2] > 0 and np.isfinite(sol).all()):
            continue
        keep = np.arange(len(m)) != j
        res = c[keep] - (sol[:2] + sol[2] * p[keep])
        var = float((res**2).sum()) / nu
        h = 0.5 * float(ax @ inv @ ax + ay @ inv @ ay)
        d = float(np.hypot(*(c[j] - (sol[:2] + sol[2] * p[j]))))
        allowed = math.sqrt(2.0 * q * (var * (1.0 + h) + floor2))
        if d > allowed and (worst is None or d / allowed > worst[1] / worst[2]):
            worst = (m[j][0], d, allowed, math.sqrt(var))
    return worst


def _strong_only(glints: list[Glint], params) -> list[Glint] | None:
    """:func:`_match_glints`'s glints of a JPEG: those rising ≥ ``glint_strong_frac`` of the
    strongest one's rise over their own background, the others' LEDs cleared — or None when
    all are that strong."""
    rise = [g.peak - g.base if g.base is not None else math.inf for g in glints]
    if len(glints) < 2:
        return None
    top = max(rise)
    strong = [g for g, r in zip(glints, rise, strict=True) if r >= params.glint_strong_frac * top]
    if len(strong) == len(glints):
        return None
    for g in glints:
        g.led = None
    return strong


def _match_glints(  # noqa: PLR0913 - the glints, the LEDs, the pupil, the picture
    glints: list[Glint], led_azimuths_deg, params, pattern=None, pupil=None, img=None, jpeg=False
) -> tuple[list[str], list[int]]:
    """Step 5b: each glint's LED (in place, :func:`_assign_leds`, or with ``pattern`` and ≥ 3
    glints :func:`~.glints.match_pattern` when it matches as many); the messages and the LEDs
    left without a glint: an error when fewer than ``min_matched_glints`` (or, with fewer
    LEDs, all of them) are matched or when the matched do not fit the LEDs' pattern
    (:func:`_pattern_misfit`; with ``pattern`` given, also when every LED has one), else a
    warning. With glints left over, the matching is checked against the whole pattern those
    glints fit (:func:`_rival_patterns`: two patterns — a spectacle reflection — chosen by
    ``pupil``, the :class:`Pupil` or None, or refused; two glints at one LED's place told
    apart by the fit or that LED left out); a matched glint far brighter than the others is
    left out (:func:`_too_bright`, a warning), and so is one whose spot in ``img`` (the
    picture, or None: not judged) is not a point source's image like the others' — no blur
    skirt (:func:`_unlike_the_others`); one lying farther from where the
    other matched glints put its LED's glint than their scatter allows
    (:func:`_off_the_others`: a stray) is unmatched and the frame refused.

    ``jpeg`` (a JPEG's picture, :func:`~.glints.jpeg_dc_step`): only the glints rising ≥
    ``glint_strong_frac`` of the strongest one's rise over their own background are matched
    (the others stay unmatched): the coding's specks — blocks a quantum or two over their
    neighbours, ringing along the pupil's and the lids' edges — rise 10–25 DN where unsaturated
    glints dimmer than the sclera rise 110–180 over the pupil, and, matched by direction or
    where the strong glints' pattern puts an LED (within 10 px), they were answered ``ok``
    1.2–98 px from the glint (``test_detect_glint_jpeg25.py``'s pictures at
    q25–45)."""
    strong = _strong_only(glints, params) if jpeg else None
    if strong is not None:
        return _match_glints(strong, led_azimuths_deg, params, pattern, pupil, img)
    n_led = len(led_azimuths_deg)
    centres = np.array([g.centre_px for g in glints]).reshape(-1, 2)
    max_ang = params.match_max_angle_deg
    if max_ang is None:
        max_ang = default_max_angle(led_azimuths_deg)
    leds, ambiguous, between = _leds_by_direction(centres, led_azimuths_deg, max_ang, pattern)
    strong = _strong_first(glints, centres, led_azimuths_deg, max_ang, pattern, params)
    if strong is not None and sum(k is not None for k in strong[0]) >= sum(
        k is not None for k in leds
    ):
        leds, ambiguous, between = strong
    before = list(leds)
    leds, rival, notes, undecided = _rival_patterns(
        glints, centres, leds, led_azimuths_deg, pattern, max_ang, pupil, params
    )
    if leds != before:
        ambiguous, between = "", []
    for g, k in zip(glints, leds, strict=True):
        g.led = k
    if rival:
        for g in glints:
            g.led = None
        return rival, list(range(n_led))
    skip, stray = _leave_out(glints, led_azimuths_deg, pattern, params, img, notes)
    matched = {g.led for g in glints if g.led is not None}
    missing = [k for k in range(n_led) if k not in matched]
    if stray:
        return [*notes, stray], missing
    if not missing:
        return notes + _all_matched(glints, led_azimuths_deg, pattern, max_ang, params), []
    # The glints the pattern's fit could not tell apart at an LED's place were judged there (the
    # LED left out, a warning): no strays making the rest of the matching uncertain (the sun's
    # glint beside an LED's in design frames refused the 7 others' frame).
    lost, missing = _some_missing(glints, missing, led_azimuths_deg, pattern, max_ang, params,
                                  ambiguous, between, skip | undecided)  # fmt: skip
    return notes + lost, missing


def _leave_out(  # noqa: PLR0913 - the glints, the LEDs, the picture, the notes
    glints: list[Glint], led_azimuths_deg, pattern, params, img, notes: list[str]
) -> tuple[set[int], str]:
    """:func:`_match_glints`'s matched glints that are not their LED's, unmatched in place:
    far brighter than the others (:func:`_too_bright`) or unlike the others' spots
    (:func:`_unlike_the_others`; ``img`` the picture, None: not judged) — a warning each
    appended to ``notes``, their LEDs left without a glint — or a stray: a lit patch
    (:func:`_lit_patches`) or a glint off the others' fit (:func:`_off_the_others`). Returns
    the indices of the first kinds (blobs at an LED's place, no strays) and the error for a
    stray ("" none): a stray taken for a glint means strays are about, and what is left of
    the matching is not trusted (design frames: with the stray left out, a second one, also
    matched, passed the pattern checks)."""
    bright = _too_bright(glints, params)
    for i, ratio in bright:
        x, y = glints[i].centre_px
        notes.append(
            f"warning: LED {glints[i].led}'s glint left out: the blob at ({x:.1f}, {y:.1f}) holds "
            f"{ratio:.1f} × the light of the brightest other glint (> "
            f"{params.glint_max_flux_ratio:g} ×: merged with another spot — the sun's glint? — "
            "or a lit patch; its centre is not the glint's)"
        )
        glints[i].led = None
    skip = {i for i, _ in bright}
    patches = _lit_patches(glints)
    if patches:  # a stray matched: strays are about, the rest of the matching is not trusted
        i, area, typical = patches[0]
        x, y = glints[i].centre_px
        k = glints[i].led
        for j, _, _ in patches:
            glints[j].led = None
        return skip, (
            f"glint lost: the blob at ({x:.1f}, {y:.1f}) matched to LED {k} spreads its light "
            f"over {area:.1f} px² (flux over rise), over {_PATCH_AREA_RATIO:g} × the other "
            f"matched glints' median {typical:.1f} px², and is no brighter: a lit patch (sclera "
            "or skin between dark shadows) taken for a glint — the matching is uncertain"
        )
    for i, why in [] if img is None else _unlike_the_others(img, glints, params):
        x, y = glints[i].centre_px
        notes.append(
            f"warning: LED {glints[i].led}'s glint left out: the blob at ({x:.1f}, {y:.1f}): {why}"
        )
        glints[i].led = None
        skip.add(i)
    off = _off_the_others(glints, led_azimuths_deg, pattern, params)
    if off is None:
        return skip, ""
    i, d, allowed, sigma = off
    x, y = glints[i].centre_px
    k, glints[i].led = glints[i].led, None
    return skip, (
        f"glint lost: the glint at ({x:.1f}, {y:.1f}) matched to LED {k} lies {d:.1f} px from "
        f"where the other matched glints put that LED's glint (at most {allowed:.1f} px by "
        f"their fit's residual {sigma:.2f} px): a stray taken for a glint — the matching is "
        "uncertain"
    )


def _some_missing(  # noqa: PLR0913 - the matching and its notes
    glints, missing, led_azimuths_deg, pattern, max_ang, params, ambiguous, between, skip
) -> tuple[list[str], list[int]]:
    """:func:`_match_glints` with LEDs left without a glint: the error or warning; glints
    ``skip`` (indices: left out as too bright, :func:`_too_bright`) are no strays."""
    n_led = len(led_azimuths_deg)
    matched = {g.led for g in glints if g.led is not None}
    need = min(params.min_matched_glints, n_led)
    which = f"no glint for LED {', '.join(str(k) for k in missing)}"
    if len(matched) < need:
        lost = f"glint lost: {len(matched)} of {n_led} LEDs have a glint, {need} needed ({which})"
        return [lost + ambiguous], missing
    if len(matched) < params.min_glints_when_missing:
        return [
            f"glint lost: {len(matched)} of {n_led} LEDs have a glint ({which}); with LEDs "
            f"missing {params.min_glints_when_missing} are needed to tell which LEDs the glints "
            "are (two fit a shifted copy of the pattern: reflections in spectacles, strays)"
        ], missing
    kept = [g for i, g in enumerate(glints) if i not in skip]
    strays = _uncertain_strays(kept, missing, pattern, max_ang)
    if strays:
        x, y = strays[0].centre_px
        return [
            f"glint lost: {len(matched)} of {n_led} LEDs have a glint ({which}) and "
            f"{len(strays)} glint(s) found match none (the first at ({x:.1f}, {y:.1f})): which "
            "glints are the LEDs' is uncertain"
        ], missing
    misfit = "; ".join(between) or _pattern_misfit(
        glints, led_azimuths_deg, pattern, max_ang, params
    )
    if misfit:
        return [
            f"glint lost: {len(matched)} of {n_led} LEDs have a glint ({which}) and {misfit}: "
            "strays taken for glints?"
        ], missing
    return [
        f"warning: {len(missing)} of {n_led} LEDs without a glint ({which}); the "
        f"{len(matched)} matched are used"
    ], missing


#: :func:`_edge_backed_glints`' skirt beyond a glint's equivalent radius, px
_EDGE_GLINT_SKIRT_PX = 4.0
#: :func:`_edge_backed_glints`' largest one-sided excess about a glint over the edge profile,
#: × the edge's step
_EDGE_GLINT_DIPOLE = 0.2
#: the width of the ring outside its region where that excess is read, px
_EDGE_GLINT_RING_PX = 3.0
#: :func:`_edge_backed_centre`: the least equivalent radius (px) of an unclipped glint centred
#: over the edge's profile, and how often its region is centred again on its centroid
_EDGE_GLINT_MIN_R = 1.5
_EDGE_GLINT_RECENTRE = 5
#: :func:`_edge_backed_glints`' largest iris step about a glint, × the clip's height over the
#: pupil's level
_EDGE_GLINT_STEP_SHARE = 0.3


def _on_edge(g: Glint, d: float, params) -> bool:
    """Whether glint ``g``, whose centroid is ``d`` px (absolute) from the fitted pupil
    outline, is "on the pupil edge": within its equivalent radius + ``glint_edge_margin_px``."""
    return d < math.sqrt(g.area_px / math.pi) + params.glint_edge_margin_px


def _edge_backed_glints(
    img: np.ndarray, clip: float, glints: list[Glint], fit, params
) -> tuple[list[Glint], set[int]]:
    """The glints (clipped, or unclipped and not of a pixel or two) whose centroid's region
    reaches the pupil's fitted outline centred again over the edge's own profile as their
    background, the others as they are; and the indices of those centred again.

    A glint's centroid weighs its pixels by their light above one background level, the
    median of its surround (:func:`~.glints._blob`). On the pupil's edge the background under
    it is a blurred step — the dark pupil on one side, the iris on the other — and one level
    leaves the iris side's pixels weighted and clips the spot there wider: the centroid moves
    toward the iris, 0.23–1.24 px for glints of σ 1.5–4 px on the edge of a 112 × 96 px
    pupil (tests/analysis/test_detect_glint_edge.py). Here the background at each pixel is
    the pupil fit's median edge profile m (:func:`~.pupil.edge_profile`; glints left out of
    it) at the pixel's signed distance d to the fitted outline
    (:func:`~.pupil.sampson_distance`; m's end values beyond its reach), its step from the
    pupil's level m₀ = min m scaled to the iris about this glint:

        B(x, y) = m₀ + k (m(d(x, y)) − m₀),   w = max(I − B, 0),   centre = Σ w p / Σ w

    over the pixels within r + :data:`_EDGE_GLINT_SKIRT_PX` of the glint's centroid (r its
    equivalent radius) that are nearer to it than to any other glint's, k fitted by least
    squares to the picture on a :data:`_EDGE_GLINT_RING_PX` ring just outside them (an iris
    lit unevenly, ± 44 DN at 160 of 255, had moved glints 0.95–1.21 px with k = 1). For each
    glint whose region reaches within 1 px of the outline and where three checks pass:
    the iris's step k (max m − m₀) is positive and ≤ :data:`_EDGE_GLINT_STEP_SHARE` (0.3) of
    the clip's height over m₀ (a clipped top is weighed by clip − B, which a bright iris
    shrinks on its side: irides at 160–200 of 255, 0.61–0.77 of it, pulled glints 0.4–0.7 px
    toward the pupil; the tests' picture 0.14); and the picture's excess over B on the ring,
    projected on the direction from the glint and averaged (a dipole), is under
    :data:`_EDGE_GLINT_DIPOLE` (⅕) of the step — else a lid or a lash on one side, which the
    median over the outline does not hold, would move the glint (1.2 px on a test picture
    with a lid across a glint's side). (A skirt of 4 px, chosen with k = 1 and without the
    step's check: on round pupils' glints of σ 1.5–4 px on the edge ≤ 0.14 px from the
    truth, 0.21 with 3 px, 0.34 with 2; on paper2005's 640 × 480 renders, whose glints are
    20 px defocused discs, the saturated ones ≤ 0.37 px where they were ≤ 0.91 — ``_blob``'s
    skirt of r px took in 10 px of iris texture there and moved them to 0.75. As it stands:
    ≤ 0.12 px and ≤ 0.28 px.) A clipped glint (≥ 3 pixels within r of its centroid at the
    picture's largest valid value, ``clip``: :func:`_prepare`'s range's top; its missing
    pixels hold the darkest valid value): a saturated top, where the spot's shape is not read
    and the skirt carries its position. Since session 30 also an unclipped one of an
    equivalent radius r ≥ :data:`_EDGE_GLINT_MIN_R` (1.5 px), its region centred again on the
    centroid until it stays (:func:`_recentred`): its fit (a Gaussian over a plane) or
    centroid over one level had moved it toward the iris on a sharp edge, 0.6–2.1 px for
    glints of peak 300 DN and σ 1.5–2.5 px on the tests' oval pupil at a blur of 1 px, now
    ≤ 0.22 (tests/analysis/test_detect_glint_edge_unsaturated.py); on paper2005's 640 × 480
    renders (8 and 64 samples per pixel, the counts and the irradiance pictures) the six
    glints it moved went from 0.44–1.79 to 0.17–0.29 px off the truth. Not for a glint of a
    pixel or two, which a 4 px skirt would drown in the background's residuals
    (eyetrackvr's one-pixel glints beside a 9 px pupil moved 2.5 px). The glint's flux and
    base are left as found."""
    prof = getattr(fit, "edge_profile", None)
    if prof is None or not glints:
        return glints, set()
    e = fit.ellipse
    xy = np.array([g.centre_px for g in glints], np.float64)
    dist = np.abs(sampson_distance(e, xy[:, 0], xy[:, 1]))
    out = list(glints)
    centred: set[int] = set()
    for i, g in enumerate(glints):
        if not dist[i] < math.sqrt(g.area_px / math.pi) + _EDGE_GLINT_SKIRT_PX + 1.0:
            continue  # its region does not reach the outline
        others = [o.centre_px for j, o in enumerate(glints) if j != i]
        centre = _edge_backed_centre(img, clip, g, others, e, prof)
        if centre is not None:
            out[i] = dataclasses.replace(g, centre_px=centre)
            centred.add(i)
    return out, centred


def _edge_backed_centre(img, clip: float, g: Glint, others, e, prof) -> tuple | None:
    """:func:`_edge_backed_glints`' centroid of glint ``g`` (``others``: the other glints'
    centres; ``clip`` the picture's clipping level; ``e`` the fitted outline and ``prof`` its
    :class:`~.pupil.EdgeProfile`), or None where it does not apply there."""
    rows, cols = img.shape
    r = math.sqrt(g.area_px / math.pi)
    reach = r + _EDGE_GLINT_SKIRT_PX
    cx, cy = g.centre_px
    half = reach + _EDGE_GLINT_RING_PX  # the window holds the ring outside the region
    x0, y0 = max(0, int(math.floor(cx - half))), max(0, int(math.floor(cy - half)))
    x1, y1 = min(cols, int(math.ceil(cx + half)) + 1), min(rows, int(math.ceil(cy + half)) + 1)
    if x1 - x0 < 3 or y1 - y0 < 3:
        return None
    win = img[y0:y1, x0:x1].astype(np.float64)
    yy, xx = np.mgrid[y0:y1, x0:x1].astype(np.float64)
    d2 = (xx - cx) ** 2 + (yy - cy) ** 2
    mine = np.ones(d2.shape, bool)  # nearer to this glint than to any other
    for ox, oy in others:
        mine &= d2 < (xx - ox) ** 2 + (yy - oy) ** 2
    region = mine & (d2 <= reach * reach)
    clipped = np.count_nonzero(region & (d2 <= r * r) & (win >= clip)) >= 3
    if not clipped and r < _EDGE_GLINT_MIN_R:
        return None  # a glint of a pixel or two: nothing of it to weigh
    # The background: the profile's step from the pupil's level m₀ scaled to the iris about
    # this glint, B = m₀ + k (m(d) − m₀), k fitted (least squares) on a ring just outside the
    # region (the light on the iris falls off across the eye: ±30–44 DN on an iris at 160 of
    # 255 moved glints 0.8–1.2 px with k = 1).
    ring = mine & (d2 > reach * reach) & (d2 <= (reach + _EDGE_GLINT_RING_PX) ** 2)
    if not ring.any():
        return None
    m0 = float(prof.m.min())
    u = np.interp(sampson_distance(e, xx, yy), prof.s, prof.m) - m0
    uu = float((u[ring] ** 2).sum())
    if not uu > 0:
        return None
    k = float((u[ring] * (win[ring] - m0)).sum()) / uu
    step = k * float(prof.m.max() - m0)
    # The clipped top is weighed by clip − B, which a bright iris shrinks on its side: only
    # where the iris's step is a small part of the room to the clip (on the tests' pictures
    # 0.14; iris at 160–200 of 255, 0.61–0.77, pulled glints 0.4–0.7 px toward the pupil)
    if not 0.0 < step <= _EDGE_GLINT_STEP_SHARE * (clip - m0):
        return None
    bg = m0 + k * u
    # The profile must be this place's background, evenly about the glint: on the ring, the
    # picture's excess over it projected on the direction from the glint (its dipole: a lid's
    # skin or a lash on one side, which the median over the outline does not hold), under a
    # fifth of the step. (A lid across a glint's side: 0.66 of it, the glint moved 1.2 px
    # off; the glint's own skirt and the iris's shading: ≤ 0.08 on the test pictures and
    # paper2005's renders.)
    res = (win - bg)[ring]
    ux, uy = (xx - cx)[ring], (yy - cy)[ring]
    nn = np.hypot(ux, uy)
    dipole = math.hypot(float((res * ux / nn).mean()), float((res * uy / nn).mean()))
    if dipole > _EDGE_GLINT_DIPOLE * step:
        return None
    excess = np.maximum(win - bg, 0.0)
    w = np.where(region, excess, 0.0)
    tot = float(w.sum())
    if not tot > 0:
        return None
    px, py = float((w * xx).sum() / tot), float((w * yy).sum() / tot)
    return (px, py) if clipped else _recentred(excess, mine, xx, yy, px, py, reach)


def _recentred(excess, mine, xx, yy, px: float, py: float, reach: float) -> tuple | None:
    """An unclipped spot's centroid (px) of ``excess`` (its light over the background) over
    the pixels ``mine`` within ``reach`` of it: the region centred again on the centroid found,
    until it moves < 0.01 px or :data:`_EDGE_GLINT_RECENTRE` times (its first place was found
    over a plane); None if the region holds no light."""
    for _ in range(_EDGE_GLINT_RECENTRE):
        w = np.where(mine & ((xx - px) ** 2 + (yy - py) ** 2 <= reach * reach), excess, 0.0)
        tot = float(w.sum())
        if not tot > 0:
            return None
        qx, qy = float((w * xx).sum() / tot), float((w * yy).sum() / tot)
        moved = math.hypot(qx - px, qy - py)
        px, py = qx, qy
        if moved < 0.01:
            break
    return px, py


def _glint_warnings(glints, fit, led_azimuths_deg, params, centred=frozenset()) -> list[str]:
    """Step 6: warnings that leave ``ok`` alone (unmatched glints, none, glints on the edge;
    ``centred``: the indices of those centred over the edge's profile,
    :func:`_edge_backed_glints`)."""
    warnings = []
    if led_azimuths_deg is not None:
        warnings += [
            f"warning: glint {i} matches no LED" for i, g in enumerate(glints) if g.led is None
        ]
    elif not glints:
        warnings.append("warning: no glints found")
    if fit and glints:
        # All the glints' distances at once (sampson_distance's compiled pass for 1-D points).
        xy = np.array([g.centre_px for g in glints], np.float64)
        dist = np.abs(sampson_distance(fit.ellipse, xy[:, 0], xy[:, 1])).tolist()
        for i, (g, d) in enumerate(zip(glints, dist, strict=True)):
            if _on_edge(g, d, params):
                warnings.append(
                    f"warning: glint {i} on the pupil edge ({d:.1f} px from the fitted "
                    "outline): the outline under it was left out; "
                    + (
                        "centred over the edge's profile as its background"
                        if i in centred
                        else "its centroid may be biased"
                    )
                )
    return warnings


def detect(
    image: np.ndarray,
    *,
    led_azimuths_deg: Sequence[float] | None = None,
    valid: np.ndarray | None = None,
    led_pattern_px: np.ndarray | None = None,
    params: DetectParams = DetectParams(),  # noqa: B008 - frozen, never mutated
) -> Detection:
    """Find the pupil and glints in a grey eye picture (module doc: conventions, pipeline).

    Parameters
    ----------
    image : (rows, cols) uint8, uint16 or float — DN or irradiance; any other real dtype is
        converted. Non-finite pixels (NaN, inf) are missing pixels.
    led_azimuths_deg : the LEDs' azimuths (0° = picture +x, 90° = up); when given, each glint
        is matched to its LED; LEDs left without one are listed in ``missing_leds``, a failure
        when fewer than ``params.min_matched_glints`` (2) are matched, else a warning.
    valid : optional (rows, cols) bool, True where the picture shows the eye (e.g. inside a
        headset's lens); dark regions touching the rest are never the pupil.
    led_pattern_px : optional (k, 2) px, each LED's glint relative to the glints' centre as
        predicted (:func:`~.evaluate.led_picture_pattern`); with ≥ 3 glints they are matched
        to it (:func:`~.glints.match_pattern`) when that matches at least as many as the
        azimuths do; with LEDs missing the matched glints must fit it
        (:func:`_pattern_misfit`), else a ring of the azimuths.
    params : :class:`DetectParams`.

    Raises
    ------
    ValueError
        If the picture is not 2-D, is empty, or has no valid (finite, unmasked) pixel; if
        ``valid`` has another shape; if an LED azimuth is not finite; if ``led_pattern_px`` is
        not one finite (x, y) per LED.
    """
    if led_azimuths_deg is not None and not np.isfinite(np.asarray(led_azimuths_deg, float)).all():
        raise ValueError(f"LED azimuths must be finite degrees, got {list(led_azimuths_deg)}")
    if led_pattern_px is not None:
        led_pattern_px = np.asarray(led_pattern_px, float)
        n_led = 0 if led_azimuths_deg is None else len(led_azimuths_deg)
        if led_pattern_px.shape != (n_led, 2) or not np.isfinite(led_pattern_px).all():
            raise ValueError(
                f"LED glint pattern must be finite ({n_led}, 2) px, one row per LED azimuth; "
                f"got shape {led_pattern_px.shape}"
            )
    t_start = time.perf_counter()
    timings: dict[str, float] = {}
    prepared = _prepare(image, valid, params.scale_percentile)
    img, invalid, lo, hi, (n_hot, noise, n_black, n_filled), scale = prepared
    if hi <= lo:
        timings["total"] = 1e3 * (time.perf_counter() - t_start)
        mended = f" once its {n_hot} hot pixel(s) are mended" if n_hot else ""
        return Detection(
            False,
            [f"no pupil: the picture is uniform (every pixel {lo:.6g}{mended})"],
            None,
            [],
            timings,
        )
    t1 = time.perf_counter()
    timings["normalise"] = 1e3 * (t1 - t_start)
    blobs, bright, tg_value = find_glints(img, (lo, hi), noise, params)
    t2 = time.perf_counter()
    timings["glints"] = 1e3 * (t2 - t1)
    fit = find_pupil(
        img,
        invalid,
        bright,
        params,
        _sharp_glints(img, (lo, hi), noise, tg_value, params),
        scale=scale,
    )
    pupil, errors, fit = _pupil_result(fit, params)
    pupil_notes = [m for m in errors if m.startswith("warning: ")]
    errors = [m for m in errors if not m.startswith("warning: ")]
    t3 = time.perf_counter()
    timings["pupil"] = 1e3 * (t3 - t2)
    n_leds = None if led_azimuths_deg is None else len(led_azimuths_deg)
    near = blobs
    jpeg_step = jpeg_dc_step(image) if n_leds and pupil is not None else 0.0
    if pupil is not None:
        near = _blobs_near_pupil(
            img, (lo, hi), noise, (blobs, bright), pupil, tg_value, params, n_leds,
            jpeg_step=jpeg_step,
        )  # fmt: skip
    near, missing_notes = _glints_off_missing(near, invalid, img, (lo, hi), noise, params)
    glints, specks = _split_specks(near, params)
    missing_leds: list[int] = []
    lost_note: list[str] = []
    if n_leds:
        wider = None if pupil is None else functools.partial(
            _wider_look, img, (lo, hi), noise, (blobs, bright), pupil, tg_value,
            led_azimuths_deg, led_pattern_px, params, invalid, jpeg_step,
        )  # fmt: skip
        glints, specks, lost, missing_leds = _match_or_look_wider(
            glints, specks, led_azimuths_deg, led_pattern_px, params, wider, pupil, img,
            jpeg_step > 0,
        )  # fmt: skip
        errors += [m for m in lost if not m.startswith("warning: ")]
        lost_note = [m for m in lost if m.startswith("warning: ")]
    glints.sort(key=lambda g: (g.led is None, g.led if g.led is not None else 0, -g.peak))
    glints, centred = _edge_backed_glints(img, hi, glints, fit, params)
    errors += _broken_glints(
        glints, _jpeg_fragments(glints, specks, params) if jpeg_step else specks, params
    )
    warnings = (
        pupil_notes
        + lost_note
        + _glint_warnings(glints, fit, led_azimuths_deg, params, centred)
        + missing_notes
    )
    warnings += _frame_notes(n_hot, n_filled, n_black, jpeg_step)
    t4 = time.perf_counter()
    timings["match"] = 1e3 * (t4 - t3)
    timings["total"] = 1e3 * (t4 - t_start)
    return Detection(
        ok=not errors,
        failures=errors + warnings,
        pupil=_edge_axes(pupil, fit),
        glints=glints,
        timings_ms=timings,
        glint_threshold=tg_value,
        missing_leds=missing_leds,
    )


def _frame_notes(n_hot: int, n_filled: int, n_black: int, jpeg_step: float) -> list[str]:
    """The warnings about the picture itself: hot pixels mended, holes filled, a black border
    left out, a JPEG's coding (:func:`~.glints.jpeg_dc_step`, DN)."""
    notes: list[str] = []
    if jpeg_step:
        notes.append(
            f"warning: a JPEG's picture (8 × 8 blocks whose levels are {jpeg_step:g} DN apart): "
            "glints looked for on the pupil too, centred on their cores, and only those rising "
            "≥ half the strongest one's rise matched (the coding's blocks and ringing are specks)"
        )
    if n_hot:
        notes.append(f"warning: {n_hot} isolated hot pixel(s) replaced by their neighbours")
    if n_filled:
        notes.append(
            f"warning: {n_filled} missing pixel(s) in small enclosed holes (≤ {HOLE_MAX_PX} px) "
            "filled from their surround (cv2.inpaint)"
        )
    if n_black:
        notes.append(
            f"warning: a black border ({n_black} px at the picture's darkest value, touching its "
            "edge) is left out as missing pixels"
        )
    return notes


def enlargement_factor(image: np.ndarray, min_side: int = 8) -> int:
    """The factor k ≥ 2 by which a 2-D picture was enlarged by nearest neighbour (every k × k
    block one value, as ``eyelume render``'s PNGs of a small sensor are: 87 × 65 → 696 × 520),
    or 1. The largest such k leaving ≥ ``min_side`` pixels a side and a non-uniform picture;
    NaN equals NaN. A camera's picture, whose noise differs pixel to pixel, gives 1.

    >>> enlargement_factor(np.kron(np.arange(80.0).reshape(8, 10), np.ones((3, 3))))
    3
    """
    img = np.asarray(image)
    if img.ndim != 2:
        return 1
    rows, cols = img.shape
    g = math.gcd(rows, cols)
    eq_nan = img.dtype.kind == "f"
    for k in sorted((d for d in range(2, g + 1) if g % d == 0), reverse=True):
        if rows // k < min_side or cols // k < min_side:
            continue
        small = img[::k, ::k]
        row = np.repeat(small[0], k)
        if not np.array_equal(img[0], row, equal_nan=eq_nan):  # cheap first look
            continue
        finite = small[np.isfinite(small)] if eq_nan else small
        if finite.size == 0 or finite.min() == finite.max():
            continue  # uniform (or all NaN): nothing says it was enlarged
        big = np.repeat(np.repeat(small, k, axis=0), k, axis=1)
        if np.array_equal(img, big, equal_nan=eq_nan):
            return k
    return 1


def detection_to_dict(d: Detection) -> dict:
    """A JSON-ready dict of a :class:`Detection` (plain floats, lists, None), with the pixel
    convention spelled out under ``"convention"``."""

    def clean(v):
        if isinstance(v, dict):
            return {k: clean(x) for k, x in v.items()}
        if isinstance(v, list | tuple):
            return [clean(x) for x in v]
        if isinstance(v, np.generic):
            v = v.item()
        if isinstance(v, float) and not math.isfinite(v):
            return None
        return v

    out = {
        "ok": bool(d.ok),
        "failures": list(d.failures),
        "pupil": asdict(d.pupil) if d.pupil is not None else None,
        "glints": [asdict(g) for g in d.glints],
        "glint_threshold": d.glint_threshold,
        "missing_leds": list(d.missing_leds),
        "timings_ms": dict(d.timings_ms),
        "convention": PIXEL_CONVENTION,
    }
    return clean(out)
