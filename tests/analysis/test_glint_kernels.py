"""glints' compiled kernels against their definitions written with OpenCV and NumPy on random
windows: _ring_noise_off (the dilation looked up at the ring's pixels, sectors by sign tests)
and in_bright_run (a flood fill for cv2.connectedComponents)."""

import math

import cv2
import numpy as np

from eyelume.analysis.tracking.glints import _SECTORS, _ring_noise_off, _sector, in_bright_run


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


def _bright_run_reference(img, blob, level, noise):
    """in_bright_run's definition: the pixels ≥ its level 8-connected to the seed (the
    brightest within r + ½ px of the centre) by cv2.connectedComponents, reaching an uncut
    edge of the square of half-side ⌈r⌉ + 3 px."""
    rows, cols = img.shape
    x, y = blob["centre_px"]
    r = math.sqrt(max(blob["area_px"], 1.0) / math.pi)
    h = int(math.ceil(r)) + 3
    c, w = int(round(x)), int(round(y))
    x0, y0, x1, y1 = c - h, w - h, c + h + 1, w + h + 1
    if x1 <= 0 or y1 <= 0 or x0 >= cols or y0 >= rows:
        return False
    wy0, wx0 = max(0, y0), max(0, x0)
    win = img[wy0 : min(rows, y1), wx0 : min(cols, x1)]
    thr = max(blob["base"] + level * (blob["peak"] - blob["base"]), blob["peak"] - noise)
    best, seed = -math.inf, None
    k = int(math.ceil(r + 0.5))
    for yy in range(max(wy0, w - k), min(rows, w + k + 1)):
        for xx in range(max(wx0, c - k), min(cols, c + k + 1)):
            v = float(img[yy, xx])
            if (xx - x) ** 2 + (yy - y) ** 2 <= (r + 0.5) ** 2 and v > best:
                best, seed = v, (yy - wy0, xx - wx0)
    if seed is None or best < thr:
        return False
    _, lab = cv2.connectedComponents((win >= thr).astype(np.uint8), connectivity=8)
    own = lab == lab[seed]
    return bool(
        (x0 >= 0 and own[:, 0].any())
        or (x1 <= cols and own[:, -1].any())
        or (y0 >= 0 and own[0, :].any())
        or (y1 <= rows and own[-1, :].any())
    )


def test_in_bright_run_matches_its_definition():
    rng = np.random.default_rng(11)
    runs = 0
    for t in range(1500):
        rows, cols = (int(v) for v in rng.integers(6, 40, 2))
        pic = rng.normal(100.0, 20.0, (rows, cols))
        for _ in range(int(rng.integers(0, 4))):  # bright strips (lit lid) and spots (glints)
            r0, c0 = int(rng.integers(0, rows)), int(rng.integers(0, cols))
            if rng.random() < 0.5:
                pic[r0 : r0 + int(rng.integers(1, 4)), :] += rng.uniform(50.0, 200.0)
            else:
                pic[r0 : r0 + 3, c0 : c0 + 3] += rng.uniform(50.0, 200.0)
        img = [
            np.clip(pic, 0, 255).astype(np.uint8),
            np.clip(4 * pic, 0, 1023).astype(np.uint16),
            pic.astype(np.float32),
            pic,
        ][t % 4]
        x = int(rng.integers(-2, cols + 2)) + float(rng.choice([0.0, 0.5, rng.random()]))
        y = int(rng.integers(-2, rows + 2)) + float(rng.choice([0.0, 0.5, rng.random()]))
        blob = {
            "centre_px": (x, y),
            "area_px": float(rng.uniform(0.5, 30.0)),
            "peak": float(img.max()) * float(rng.uniform(0.6, 1.0)),
            "base": float(np.median(img)),
        }
        level, noise = float(rng.uniform(0.3, 0.9)), float(rng.choice([0.0, 5.0, 30.0]))
        want = _bright_run_reference(img, blob, level, noise)
        assert in_bright_run(img, blob, level, noise) == want
        runs += want
    assert 50 < runs < 1450  # both answers are exercised


def test_distinct_points_counts_as_numpy_unique():
    from eyelume.analysis.tracking.glints import _distinct_points

    rng = np.random.default_rng(3)
    for _ in range(300):
        cols = int(rng.integers(5, 700))
        n = int(rng.integers(0, 60))
        xy = np.column_stack([rng.integers(0, cols, n), rng.integers(0, 50, n)]).astype(np.int32)
        xy = np.concatenate([xy, xy[: n // 3]])  # outlines revisit their points
        want = len(np.unique(xy[:, 1].astype(np.int64) * cols + xy[:, 0]))
        assert _distinct_points(xy, cols) == want
