"""A glint of a 3 × 3 saturated square with a dim skirt — glasses-frame's LED 3 at (−10°, 0°)
since the PSF spreads glint light from where it fell in its pixel (d4b7805) — falls under step
2's threshold once smoothed (σ = 1 px on 480 rows: a 3σ square keeps erf(3 / (2√2))² = 0.75 of
its rise at its centre), and the search for glints the smoothing lost took only blobs of ≤ 2 px:
the glint was lost and the frame refused. It must be found, at its centroid."""

from __future__ import annotations

import importlib

import numpy as np

from tests.analysis.test_detect import CENTRE, PICTURE, draw_eye

D = importlib.import_module("eyelume.analysis.tracking.detect")  # the module, not detect()
G = importlib.import_module("eyelume.analysis.tracking.glints")

# glasses-frame at (−10°, 0°), seed 0, 8 samples per pixel, rows 269–276 × cols 256–265 of
# the 480 × 640 counts (10-bit, 1017 DN at the top): LED 3's glint, 8 pixels at the top.
GLINT = np.array(
    [
        [98, 108, 108, 134, 139, 148, 153, 140, 129, 115],
        [102, 115, 136, 174, 209, 296, 265, 187, 148, 112],
        [111, 125, 158, 233, 492, 769, 680, 329, 186, 147],
        [120, 130, 163, 354, 1015, 1016, 1016, 584, 236, 160],
        [106, 131, 172, 421, 1016, 1016, 1016, 820, 231, 169],
        [111, 130, 159, 296, 868, 1016, 1017, 476, 214, 152],
        [108, 119, 141, 198, 328, 403, 397, 254, 164, 136],
        [100, 115, 128, 137, 168, 225, 206, 150, 135, 120],
    ],
    float,
)


def _picture():
    img = draw_eye(PICTURE._replace(dtype=np.float64))
    # lit skin near the top of the scale over 5 % of the picture, far from the eye (as the
    # render's highlights at 945–972 DN), which sets step 2's threshold near its level
    img[:24, :] += 950.0 - 500.0
    r0, c0 = round(CENTRE[1]) + 40, round(CENTRE[0]) - 40  # on the iris, inside the search
    base = np.median(img[r0 : r0 + 8, c0 : c0 + 10])
    img[r0 : r0 + 8, c0 : c0 + 10] = base + (GLINT - 100.0) * (1023.0 - base) / (1017.0 - 100.0)
    img = np.clip(img, 0.0, 1023.0)
    sub = np.maximum(GLINT - np.median(GLINT), 0.0)
    yy, xx = np.mgrid[: GLINT.shape[0], : GLINT.shape[1]]
    true = (c0 + (sub * xx).sum() / sub.sum(), r0 + (sub * yy).sum() / sub.sum())
    return img, true, (r0, c0)


def test_three_by_three_glint_lost_by_smoothing_is_found():
    img, (tx, ty), (r0, c0) = _picture()
    blobs, bright, _ = G.find_glints(img, (img.min(), img.max()), 8.0, D.DetectParams())
    assert not bright[r0 : r0 + 8, c0 : c0 + 10].any(), "step 2 must lose it (the case tested)"
    d = D.detect(img)
    near = [g for g in d.glints if abs(g.centre_px[0] - tx) < 2 and abs(g.centre_px[1] - ty) < 2]
    assert len(near) == 1, [g.centre_px for g in d.glints]
    assert near[0].area_px == 9
    # its centroid: the pasted patch's, over its own median background (not a tuned figure:
    # the patch's skirt reaches the window's edge, so the two backgrounds differ a little)
    assert np.hypot(near[0].centre_px[0] - tx, near[0].centre_px[1] - ty) < 0.25
