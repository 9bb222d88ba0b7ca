"""The picture grid and the eye-plane receiver: one mm ↔ bin mapping, its orientation, its
inverse, and the kernels binning with the very same expressions."""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from eyelume.detectors.receivers import BinnedPlane
from eyelume.kernels.bins import bin_of, eye_plane_grid, from_grid, picture_grid

PICTURE = picture_grid(46.0, 34.5, 87, 65)
EYE_PLANE = eye_plane_grid(40.0, 30.0, 21, 15)


@njit(cache=True)
def _bins(g, x, y):
    cols, rows, inside = np.empty(x.size, np.int64), np.empty(x.size, np.int64), np.empty(x.size)
    for i in range(x.size):
        c, r, ok = bin_of(g, x[i], y[i])
        cols[i], rows[i], inside[i] = c, r, ok
    return cols, rows, inside


def test_orientation():
    pic, eye = BinnedPlane(PICTURE), BinnedPlane(EYE_PLANE)
    # the picture is the sensor turned by 180°: column 0 at sensor +x, row 0 at sensor −y
    # (world +y, the top, images there through the inverting lens)
    assert pic.to_pixel(23.0, -17.25) == (-0.5, -0.5)
    assert pic.to_pixel(-23.0, 17.25) == (86.5, 64.5)
    # the eye plane: column 0 at −x, row 0 at +y
    assert eye.to_pixel(-20.0, 15.0) == (-0.5, -0.5)
    assert eye.to_pixel(20.0, -15.0) == (20.5, 14.5)
    assert pic.shape == (65, 87) and eye.shape == (15, 21)
    assert eye.bin_area_mm2 == pytest.approx((40 / 21) * (30 / 15))


@pytest.mark.parametrize("grid", [PICTURE, EYE_PLANE], ids=["picture", "eye plane"])
def test_round_trip_and_kernel_bins(grid):
    plane = BinnedPlane(grid)
    rng = np.random.default_rng(1)
    x = rng.uniform(-0.6, 0.6, 5000) * grid.width_mm
    y = rng.uniform(-0.6, 0.6, 5000) * grid.height_mm
    c, r = plane.to_pixel(x, y)
    xb, yb = plane.from_pixel(c, r)
    np.testing.assert_allclose(xb, x, atol=1e-12)
    np.testing.assert_allclose(yb, y, atol=1e-12)
    # the kernels' bin is the pixel whose centre is nearest: ⌊c + 0.5⌋, ⌊r + 0.5⌋
    cols, rows, inside = _bins(grid, x, y)
    np.testing.assert_array_equal(cols, np.floor(c + 0.5).astype(int))
    np.testing.assert_array_equal(rows, np.floor(r + 0.5).astype(int))
    on = (cols >= 0) & (cols < grid.cols) & (rows >= 0) & (rows < grid.rows)
    np.testing.assert_array_equal(inside.astype(bool), on)
    assert 0.3 < on.mean() < 0.9  # both cases occur


def test_centres_are_the_eye_plane_bin_centres():
    x, y = BinnedPlane(EYE_PLANE).centres()
    np.testing.assert_allclose(x, -20.0 + (np.arange(21) + 0.5) * 40.0 / 21, atol=1e-12)
    np.testing.assert_allclose(y, 15.0 - (np.arange(15) + 0.5) * 2.0, atol=1e-12)
    xs, ys = from_grid(EYE_PLANE, 0.5, 0.5)  # the kernel, compiled
    assert (xs, ys) == pytest.approx((x[0], y[0]), abs=1e-12)
