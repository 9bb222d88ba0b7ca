"""glints._ring_noise_off (compiled: the dilation looked up at the ring's pixels, sectors by
sign tests) against its definition written with OpenCV and NumPy on random windows."""

import math

import cv2
import numpy as np

from eyelume.analysis.tracking.glints import _SECTORS, _ring_noise_off, _sector


def _reference(img, bright, cx, cy, r_in, r_out, m):
    """The definition: the window's bright pixels dilated by an elliptical disc 2⌈m⌉ + 1 px
    across (cv2.dilate), the ring's pixels off them in 8 sectors by atan2, each sector's
    1.4826 × MAD (≥ 4 pixels), the median of those."""
    rows, cols = img.shape
    x0, x1 = max(0, int(cx - r_out) - 1), min(cols, int(cx + r_out) + 3)
    y0, y1 = max(0, int(cy - r_out) - 1), min(rows, int(cy + r_out) + 3)
    k = 2 * int(math.ceil(m)) + 1
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))
    near = cv2.dilate(np.ascontiguousarray(bright[y0:y1, x0:x1]), disc)
    win = img[y0:y1, x0:x1].astype(np.float64)
    yy, xx = np.mgrid[0 : y1 - y0, 0 : x1 - x0]
    dy, dx = yy - (cy - y0), xx - (cx - x0)
    d2 = dy**2 + dx**2
    ring = (d2 > r_in * r_in) & (d2 <= r_out * r_out) & (near == 0)
    sect = np.minimum(
        ((np.arctan2(dy, dx) + math.pi) / (2.0 * math.pi) * _SECTORS).astype(int), _SECTORS - 1
    )
    sig = []
    for s in range(_SECTORS):
        v = win[ring & (sect == s)]
        if v.size >= 4:
            sig.append(1.4826 * np.median(np.abs(v - np.median(v))))
    return float(np.sort(sig)[(len(sig) - 1) // 2]) if sig else 0.0


def test_ring_noise_off_matches_its_definition():
    rng = np.random.default_rng(7)
    for t in range(400):
        rows, cols = (int(v) for v in rng.integers(10, 50, 2))
        img = rng.normal(100.0, 5.0, (rows, cols))
        if t % 2:
            img = np.round(img).astype(np.uint8)
        share = rng.choice([0.0, 0.02, 0.1, 0.3])
        bright = np.where(rng.random((rows, cols)) < share, 255, 0).astype(np.uint8)
        # glint centres are whole or half pixels (a blob's box centre); some near the edge
        cx = int(rng.integers(-3, cols + 3)) + 0.5 * int(rng.integers(0, 2))
        cy = int(rng.integers(-3, rows + 3)) + 0.5 * int(rng.integers(0, 2))
        m = int(rng.integers(2, 8))
        r_in = float(rng.uniform(0.5, 10.0)) + m
        got = _ring_noise_off(img, bright, cx, cy, r_in, r_in + 4.0, m)
        assert got == _reference(img, bright, cx, cy, r_in, r_in + 4.0, m)


def test_sector_is_atan2s_on_and_off_the_edges():
    for dy in np.arange(-6.0, 6.5, 0.5):
        for dx in np.arange(-6.0, 6.5, 0.5):
            want = min(int((math.atan2(dy, dx) + math.pi) / (2.0 * math.pi) * _SECTORS), 7)
            assert _sector(dy, dx) == want
