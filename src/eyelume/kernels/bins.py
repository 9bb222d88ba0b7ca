"""Binned planes: the picture on the sensor and the eye-plane receiver, defined once.

A :class:`PlaneGrid` is a width × height (mm) rectangle centred on its plane's origin, cut into
cols × rows bins. Continuous bin coordinates (u, v) — u along the columns, v along the rows, the
bin (col, row) covering [col, col + 1) × [row, row + 1) — relate to the plane's x, y (mm) by

    u = (s_x x + w/2) / w · cols,    v = (s_y y + h/2) / h · rows,

with the orientation signs s_x, s_y = ±1 of the grid:

* the **picture** (:func:`picture_grid`) is the sensor image turned by 180°, as a camera's
  readout shows it: row 0 at the top of the picture, world +y up, world +x to the right as seen
  from the camera; on the sensor (image z, the lens inverts) that is s_x = −1, s_y = +1;
* the **eye plane** (:func:`eye_plane_grid`, the paper's receiver at z = 0, Section 4.1.2):
  column 0 at −x, row 0 at +y: s_x = +1, s_y = −1.

A grid also has a **pose**: its plane's origin (``ox, oy, oz``) and unit axes (x̂ = ``ux, uy,
uz`` along the grid's x, ŷ = ``vx, vy, vz``, the normal n̂ = ``nx, ny, nz``) in the frame the
kernels trace in (the camera frame, :mod:`eyelume.scene.pose`). The eye plane's is the world's
plane through the eye's nominal corneal vertex normal to the headset's z axis (n̂ = world +z,
toward the headset), turned into the camera frame by :mod:`eyelume.compile`, so the receiver is
the same world plane for a camera anywhere; :func:`plane_coordinates` and :func:`plane_point`
map between it and the traced frame. The default is the identity (the paper's rig; the picture's
pose is not used).

These are Numba kernels (the tracers bin with them) and plain functions: ``f.py_func`` works on
NumPy arrays elementwise, which is how :mod:`eyelume.detectors.receivers` (the Python side used
by analysis) evaluates the very same expressions. Layer decision: the grid lives at the kernels
level because estimators (left of detectors in DESIGN.md §1) must bin rays and may not import
``detectors``; ``detectors/receivers.py`` wraps it for the analysis side.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from numba import njit

__all__ = [
    "PlaneGrid",
    "picture_grid",
    "eye_plane_grid",
    "to_grid",
    "from_grid",
    "bin_of",
    "plane_coordinates",
    "plane_point",
]


class PlaneGrid(NamedTuple):
    """A binned rectangle (see the module docstring): size (mm), bins, orientation signs, and
    its plane's pose in the traced frame (origin mm, unit axes x̂, ŷ, n̂; identity by default)."""

    width_mm: float
    height_mm: float
    cols: int
    rows: int
    x_sign: float
    y_sign: float
    ox: float = 0.0
    oy: float = 0.0
    oz: float = 0.0
    ux: float = 1.0
    uy: float = 0.0
    uz: float = 0.0
    vx: float = 0.0
    vy: float = 1.0
    vz: float = 0.0
    nx: float = 0.0
    ny: float = 0.0
    nz: float = 1.0


def picture_grid(width_mm: float, height_mm: float, cols: int, rows: int) -> PlaneGrid:
    """The picture's pixels on a sensor of ``width_mm`` × ``height_mm`` (row 0 at the top)."""
    return PlaneGrid(float(width_mm), float(height_mm), int(cols), int(rows), -1.0, 1.0)


def eye_plane_grid(
    width_mm: float, height_mm: float, cols: int, rows: int, origin=None, axes=None
) -> PlaneGrid:
    """The eye-plane receiver's bins (column 0 at −x, row 0 at +y), in the plane through
    ``origin`` (3,) mm with unit ``axes`` (3, 3), rows x̂, ŷ, n̂ (the traced frame; default:
    the plane z = 0 about the origin)."""
    pose = ()
    if origin is not None:
        a = [[float(c) for c in row] for row in axes]
        pose = (*(float(c) for c in origin), *a[0], *a[1], *a[2])
    return PlaneGrid(float(width_mm), float(height_mm), int(cols), int(rows), 1.0, -1.0, *pose)


@njit(cache=True, inline="always")
def plane_coordinates(g, x, y, z):
    """A point (x, y, z) mm of the traced frame → (x′, y′, h): its coordinates in the grid's
    plane and its height above the plane along n̂ (exact for the identity pose)."""
    px, py, pz = x - g.ox, y - g.oy, z - g.oz
    return (
        g.ux * px + g.uy * py + g.uz * pz,
        g.vx * px + g.vy * py + g.vz * pz,
        g.nx * px + g.ny * py + g.nz * pz,
    )


@njit(cache=True, inline="always")
def plane_point(g, x, y):
    """The point (mm, traced frame) of the grid's plane at plane coordinates (x, y)."""
    return (
        g.ox + x * g.ux + y * g.vx,
        g.oy + x * g.uy + y * g.vy,
        g.oz + x * g.uz + y * g.vz,
    )


@njit(cache=True, inline="always")
def to_grid(g, x, y):
    """Plane point (x, y) mm → continuous bin coordinates (u, v); bin (⌊u⌋, ⌊v⌋)."""
    return (
        (g.x_sign * x + 0.5 * g.width_mm) / g.width_mm * g.cols,
        (g.y_sign * y + 0.5 * g.height_mm) / g.height_mm * g.rows,
    )


@njit(cache=True, inline="always")
def from_grid(g, u, v):
    """Continuous bin coordinates (u, v) → plane point (x, y) mm (the inverse of to_grid)."""
    return (
        g.x_sign * (u * g.width_mm / g.cols - 0.5 * g.width_mm),
        g.y_sign * (v * g.height_mm / g.rows - 0.5 * g.height_mm),
    )


@njit(cache=True, inline="always")
def bin_of(g, x, y):
    """The bin (col, row) holding plane point (x, y) and whether it lies on the grid."""
    u, v = to_grid(g, x, y)
    col = int(math.floor(u))
    row = int(math.floor(v))
    return col, row, 0 <= col < g.cols and 0 <= row < g.rows
