"""Issue 13: a glint broken by the noise into a blob and one-pixel fragments is weighed whole.

Below 240 px the bright mask is not closed (``glint_close_px``), so a small noisy glint — a Monte
Carlo render's scatter of samples, a spot on the pupil's edge — can come out of the threshold
as a blob of two pixels and a separate one-pixel fragment of the same spot. A fragment is no
glint (under ``glint_min_area_px``), and until session 16 it still counted as *another* blob
when the centroid's skirt was shared out between neighbours: the skirt pixels nearer to it were
left out, the spot's light beyond the blob with them, and the centroid moved toward the blob
(paper2005, 4 samples per pixel: 1.09 px at (30°, 0°), seed 1, on the irradiance; 1.03 px at
(−30°, 20°), seed 0, on the digital picture, answered ``ok``).
"""

from __future__ import annotations

import importlib
import math

import numpy as np

from eyelume.analysis.tracking import DetectParams

glints_mod = importlib.import_module("eyelume.analysis.tracking.glints")


def test_one_pixel_fragment_weighed_with_its_glint():
    # A flat background and a five-pixel spot whose middle row is below the local threshold:
    # the mask holds a two-pixel blob and, two rows below, a one-pixel fragment.
    img = np.full((65, 87), 100.0)
    spot = {(30, 40): 800.0, (30, 41): 800.0, (31, 40): 350.0, (31, 41): 350.0, (32, 40): 1000.0}
    for (r, c), v in spot.items():
        img[r, c] += v
    blobs, bright, _ = glints_mod.find_glints(img, (100.0, 1100.0), 1.0, DetectParams())
    assert bright[30, 40] and bright[32, 40] and not bright[31, 40], "not the case meant"
    assert len(blobs) == 1
    # On a flat background every pixel within the skirt weighs its light above it: the
    # centroid is the spot's own, Σ v·x / Σ v.
    w = sum(spot.values())
    tx = sum(v * c for (r, c), v in spot.items()) / w
    ty = sum(v * r for (r, c), v in spot.items()) / w
    cx, cy = blobs[0]["centre_px"]
    assert math.hypot(cx - tx, cy - ty) < 1e-9, ((cx, cy), (tx, ty))
    assert blobs[0]["flux"] == w
