"""Test 7: the rendered default scene shows what the paper's Figure 6b shows — a pupil darker
than the iris, skin brighter than the iris, and four glints inside the cornea where the LED
geometry puts them.

Regions are chosen from the geometry (object-plane coordinates mapped through the lens's
paraxial magnification) well inside each structure, so that blur and the glints stay out:
pupil r < 2.5 mm without the glints (the 7 mm pupil appears ~8 mm wide through the cornea),
iris annulus 4.9–5.6 mm (the 11 mm iris appears ~12 mm wide), skin a lateral patch of
periorbital skin.
Differences of region means are judged against their Poisson standard errors (4σ).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import ndimage

from eyelume.compile import lens_paraxial

SIGMAS = 4.0


def pixel_object_coords(cs):
    """Object-plane (eye plane) x, y in mm of each pixel centre, through the paraxial
    magnification; the picture is upright, so +x to the right and +y up."""
    sc = cs.scene
    m = abs(lens_paraxial(sc, cs.lens_indices).magnification(sc.lens.object_distance_mm))
    cols, rows = sc.sensor.cols, sc.sensor.rows
    xi = (np.arange(cols) + 0.5) * sc.sensor.width_mm / cols - sc.sensor.width_mm / 2
    yi = sc.sensor.height_mm / 2 - (np.arange(rows) + 0.5) * sc.sensor.height_mm / rows
    X, Y = np.meshgrid(xi / m, yi / m)
    return X, Y, m


def region_mean(counts, mask):
    n = counts[mask]
    return n.mean(), math.sqrt(n.sum()) / n.size  # Poisson standard error of the mean


def predicted_glints(cs):
    """Sensor positions (col, row; fractional pixel) of the four first Purkinje images.

    The anterior cornea near its vertex as a sphere of R = 7.8 mm: the virtual image of the
    point source S lies on the line from S to the centre of curvature C, at the mirror
    equation's distance; its chief ray through the lens's paraxial entrance pupil meets the eye
    plane z = 0 at X₀, which the lens images at m·X₀.
    """
    sc = cs.scene
    par = lens_paraxial(sc, cs.lens_indices)
    m = par.magnification(sc.lens.object_distance_mm)
    ep = np.array(
        [0.0, 0.0, sc.lens.object_distance_mm + par.entrance_pupil_position(cs.stop_index)]
    )
    radius = sc.eye.surfaces[0].radius_mm
    centre = np.array([0.0, 0.0, -radius])
    out = []
    for src in cs.led.points:
        u = (src - centre) / np.linalg.norm(src - centre)
        d_obj = np.linalg.norm(src - centre) - radius
        d_img = 1.0 / (-2.0 / radius - 1.0 / d_obj)  # negative: behind the surface
        q = centre + u * (radius + d_img)
        x0 = q + (ep - q) * (0.0 - q[2]) / (ep[2] - q[2])
        xi, yi = m * x0[0], m * x0[1]  # physical image coordinates (inverted)
        col = (sc.sensor.width_mm / 2 - xi) / sc.sensor.width_mm * sc.sensor.cols - 0.5
        row = (yi + sc.sensor.height_mm / 2) / sc.sensor.height_mm * sc.sensor.rows - 0.5
        out.append((col, row))
    return np.array(out)


@pytest.mark.slow
def test_dark_pupil_iris_and_skin(fig6b_render, paper_compiled):
    counts = fig6b_render.image_counts
    X, Y, _ = pixel_object_coords(paper_compiled)
    r = np.hypot(X, Y)
    pupil = r < 2.5
    iris = (r > 4.9) & (r < 5.6)
    skin = (X < -12.0) & (X > -19.0) & (np.abs(Y) < 3.0)
    assert counts.shape == (65, 87)
    p, sp = region_mean(counts, pupil & ~glint_mask(counts))
    i, si = region_mean(counts, iris)
    s, ss = region_mean(counts, skin)
    assert i - p > SIGMAS * math.hypot(sp, si), f"pupil {p:.2f}±{sp:.2f} vs iris {i:.2f}±{si:.2f}"
    assert s - i > SIGMAS * math.hypot(si, ss), f"iris {i:.2f}±{si:.2f} vs skin {s:.2f}±{ss:.2f}"


def glint_mask(counts):
    """Pixels of the four glints: the 3 × 3 window around each found spot."""
    mask = np.zeros(counts.shape, bool)
    for r, c in spot_peaks(counts):
        mask[r - 1 : r + 2, c - 1 : c + 2] = True
    return mask


def spot_peaks(counts, n=4):
    """(row, col) of the n strongest compact spots: local maxima of the white top-hat of the
    3 × 3-averaged image (brightness above the local background, a 9 × 9 grey opening)."""
    smooth = ndimage.uniform_filter(counts.astype(float), 3)
    tophat = smooth - ndimage.grey_opening(smooth, size=(9, 9))
    peaks = (tophat == ndimage.maximum_filter(tophat, 3)) & (tophat > 0)
    rows, cols = np.nonzero(peaks)
    order = np.argsort(tophat[peaks])[::-1][:n]
    return list(zip(rows[order], cols[order], strict=True))


def centroid(counts, r0, c0):
    """Count-weighted centroid (col, row) in the 3 × 3 window at (r0, c0) and its standard
    error per axis from Poisson counts: σ = √(Σ n (x − x̄)²) / Σ n."""
    w = counts[r0 - 1 : r0 + 2, c0 - 1 : c0 + 2].astype(float)
    rr, cc = np.mgrid[r0 - 1 : r0 + 2, c0 - 1 : c0 + 2]
    xm, ym = (w * cc).sum() / w.sum(), (w * rr).sum() / w.sum()
    sx = math.sqrt((w * (cc - xm) ** 2).sum()) / w.sum()
    sy = math.sqrt((w * (rr - ym) ** 2).sum()) / w.sum()
    return np.array([xm, ym]), np.array([sx, sy])


@pytest.mark.slow
def test_four_glints_where_the_led_geometry_puts_them(fig6b_render, paper_compiled):
    cs = paper_compiled
    counts = fig6b_render.image_counts
    predicted = predicted_glints(cs)
    _, _, m = pixel_object_coords(cs)
    limbus = cs.scene.eye.surfaces[0].semi_diameter_mm
    pitch = cs.scene.sensor.width_mm / cs.scene.sensor.cols
    matched = set()
    for r0, c0 in spot_peaks(counts):
        # inside the corneal region of the picture
        x = (c0 + 0.5) * pitch - cs.scene.sensor.width_mm / 2
        y = cs.scene.sensor.height_mm / 2 - (r0 + 0.5) * pitch
        assert math.hypot(x, y) / abs(m) < limbus
        found, sigma = centroid(counts, r0, c0)
        k = int(np.linalg.norm(predicted - found, axis=1).argmin())
        matched.add(k)
        # The glint is the image of a virtual point 3.7 mm behind the focused eye plane: a
        # blur disc ~3 px wide. Its windowed centroid scatters by σ (Poisson, ~0.1 px) and is
        # pulled toward the window's centre pixel by at most the true centre's offset from it.
        pull = np.abs(predicted[k] - np.array([c0, r0]))
        assert np.all(np.abs(found - predicted[k]) < 4 * sigma + pull), (found, predicted[k])
    assert matched == {0, 1, 2, 3}, "one glint per LED"
    # Orientation of the picture: the LED above the axis (+y) makes the topmost glint, the LED
    # at +x the rightmost one.
    leds = cs.led_centres
    assert leds[predicted[:, 1].argmin()][1] > 0
    assert leds[predicted[:, 0].argmax()][0] > 0


@pytest.mark.slow
def test_eye_plane_orientation(fig6b_render):
    """Row 0 is +y and columns run with +x: the nose (medial, +x) leans forward below the eye
    and crosses z = 0 only in the lower +x corner, shading it; the upper +x corner is lit."""
    plane = fig6b_render.eye_plane
    assert plane.shape == (15, 21)
    assert plane[-1, -1] < 0.2 * plane[0, -1]
    assert plane[-1, 0] > 0.5 * plane[0, 0]
