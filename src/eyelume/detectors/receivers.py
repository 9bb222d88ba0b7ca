"""Binned planes for the analysis side: the picture on the sensor and the eye-plane receiver.

Both are one :class:`~eyelume.kernels.bins.PlaneGrid` each, compiled once with the scene
(``cs.picture``, ``cs.eye_plane``); the mm ↔ bin mapping is defined once, in
:mod:`eyelume.kernels.bins`, and :class:`BinnedPlane` evaluates those very expressions on NumPy
arrays. Layer decision (DESIGN.md §1: estimators → detectors): the tracers bin rays with the
kernel-level grid, since estimators may not import ``detectors``; this module wraps the same
grid for analysis, reports and tests, and adds nothing a kernel needs.

Pixel coordinates follow OpenCV's convention: bin (column c, row r) has its centre at (c, r).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from eyelume.kernels.bins import PlaneGrid, eye_plane_grid, from_grid, picture_grid, to_grid

__all__ = ["BinnedPlane"]


@dataclass(frozen=True)
class BinnedPlane:
    """A binned plane: the picture on the sensor (``cs.picture``) or the eye plane
    (``cs.eye_plane``); ``BinnedPlane(cs.picture)``."""

    grid: PlaneGrid

    @classmethod
    def picture(cls, sensor) -> BinnedPlane:
        """The picture's pixels on a scene's ``sensor`` (width_mm, height_mm, cols, rows)."""
        return cls(picture_grid(*sensor.field_mm, sensor.cols, sensor.rows))

    @classmethod
    def eye_plane(cls, plane) -> BinnedPlane:
        """The bins of a scene's ``eye_plane`` receiver (width_mm, height_mm, cols, rows)."""
        return cls(eye_plane_grid(plane.width_mm, plane.height_mm, plane.cols, plane.rows))

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols)."""
        return self.grid.rows, self.grid.cols

    @property
    def bin_area_mm2(self) -> float:
        g = self.grid
        return (g.width_mm / g.cols) * (g.height_mm / g.rows)

    @property
    def extent_mm(self) -> tuple[float, float, float, float]:
        """(left, right, bottom, top) of the rectangle in its plane's mm (matplotlib's extent)."""
        g = self.grid
        return (-g.width_mm / 2, g.width_mm / 2, -g.height_mm / 2, g.height_mm / 2)

    def to_pixel(self, x, y):
        """Plane point(s) (mm) → pixel coordinates (c, r), OpenCV convention (module doc)."""
        u, v = to_grid.py_func(self.grid, x, y)
        return u - 0.5, v - 0.5

    def from_pixel(self, c, r):
        """Pixel coordinates (c, r) (OpenCV convention) → plane point(s) (mm)."""
        return from_grid.py_func(self.grid, np.asarray(c) + 0.5, np.asarray(r) + 0.5)

    def centres(self) -> tuple[np.ndarray, np.ndarray]:
        """Bin-centre plane coordinates (mm): x (cols,) along the columns, y (rows,) along the
        rows."""
        g = self.grid
        x, _ = from_grid.py_func(g, np.arange(g.cols) + 0.5, 0.0)
        _, y = from_grid.py_func(g, 0.0, np.arange(g.rows) + 0.5)
        return x, y
