"""Compiled passes of the detector against the OpenCV / NumPy operations they replace (session
29): the same rows, columns and pixels, in the same order, on random pictures of each kind."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from eyelume.analysis.tracking.detect import _rows_above
from eyelume.analysis.tracking.glints import _rows_over, _value_range


def _random_pictures(dtype, count=300, seed=29):
    """Random pictures of ``dtype``, 3-60 px a side, values over a small, medium or full
    range, and an integer threshold in and just beyond that range."""
    rng = np.random.default_rng(seed)
    info = np.iinfo(dtype)
    for _ in range(count):
        rows, cols = (int(v) for v in rng.integers(3, 60, 2))
        top = int(min(rng.choice([3, 200, info.max]), info.max))
        low = max(info.min, -top) if info.min < 0 and rng.random() < 0.5 else 0
        img = rng.integers(low, top + 1, (rows, cols)).astype(dtype)
        yield img, int(rng.integers(low - 2, top + 2))


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.int16])
def test_rows_above_as_the_mask_its_row_sums_and_find_non_zero(dtype):
    """detect._mend_hot_pixels' pixels above t: the rows holding any (np.flatnonzero of the
    comparison mask's row sums) and cv2.findNonZero of those rows, bit for bit."""
    for img, t in _random_pictures(dtype):
        above = cv2.compare(img, float(t), cv2.CMP_GT)
        rows = np.flatnonzero(cv2.reduce(above, 1, cv2.REDUCE_SUM, dtype=cv2.CV_32S).ravel())
        hit, found = _rows_above(img, t)
        assert np.array_equal(hit, rows)
        if len(rows):
            expected = cv2.findNonZero(above[rows]).reshape(-1, 2)
            assert found.dtype == expected.dtype and np.array_equal(found, expected)
        else:
            assert found.shape == (0, 2)


def test_rows_over_as_the_mask_and_its_sums():
    """glints._bright_mask's rows above the floor and the first and last column of those
    pixels: the comparison mask's row and column sums' non-zero entries."""
    for img, t in _random_pictures(np.uint8):
        above = cv2.compare(img, float(t), cv2.CMP_GT)
        rows = np.flatnonzero(cv2.reduce(above, 1, cv2.REDUCE_SUM, dtype=cv2.CV_32S).ravel())
        cols = np.flatnonzero(cv2.reduce(above, 0, cv2.REDUCE_SUM, dtype=cv2.CV_32S).ravel())
        hit, first, last = _rows_over(img, t)
        assert np.array_equal(hit, rows)
        if len(rows):
            assert (first, last) == (cols[0], cols[-1])


def test_value_range_is_the_largest_less_the_least():
    rng = np.random.default_rng(29)
    for _ in range(50):
        win = rng.normal(0.0, 10.0, tuple(int(v) for v in rng.integers(1, 20, 2)))
        assert _value_range(win) == win.max() - win.min()
        win[rng.integers(win.shape[0]), rng.integers(win.shape[1])] = np.nan
        assert np.isnan(_value_range(win))
