"""Target illumination patterns on the eye plane (paper §4.1.2): what the generator aims for.

The paper's user-defined pattern is "a 2D normal distribution with a falloff ratio of δ at the
diagonal corner of the eye plane", digitised on the eye plane's bins. Here

    t(x, y) = exp(−x² / (2 σx²) − y² / (2 σy²)),   t(0, 0) = 1,   t(±w/2, ±h/2) = 1 − δ,

sampled at the bin centres (w × h the eye plane, row 0 at +y, column 0 at −x). The paper does not
say how σx and σy relate; by default σx = σy (isotropic), or σx/σy = ``sigma_x_over_y``. A user
pattern can be loaded from a file instead (:func:`load_target`). Only the shape of a target
matters: the generator's merit (:mod:`eyelume.analysis.merit`) compares unit-mean patterns.
"""

from __future__ import annotations

import io
import math
from pathlib import Path

import numpy as np

from eyelume.detectors.receivers import BinnedPlane
from eyelume.errors import InputFileError
from eyelume.scene.model import EyePlane
from eyelume.scene.textfile import decode_text

__all__ = ["bin_centres", "gaussian_sigmas", "gaussian_target", "gaussian_value", "load_target"]


def _plane(plane) -> EyePlane:
    return getattr(plane, "eye_plane", plane)  # a Scene carries its EyePlane


def bin_centres(plane: EyePlane) -> tuple[np.ndarray, np.ndarray]:
    """Bin-centre coordinates (mm) of the eye plane: x (cols,) from −x, y (rows,) from +y."""
    return BinnedPlane.eye_plane(_plane(plane)).centres()


def _check_delta(delta: float) -> float:
    try:
        d = float(delta)
    except (TypeError, ValueError):
        raise ValueError(f"delta = {delta!r}: must be a number in [0, 1)") from None
    if not (math.isfinite(d) and 0 <= d < 1):
        raise ValueError(f"delta = {delta!r}: the corner falloff must be in [0, 1)")
    return d


def gaussian_sigmas(
    delta: float, plane: EyePlane, sigma_x_over_y: float | None = None
) -> tuple[float, float]:
    """(σx, σy) in mm of the target whose value at the corner (w/2, h/2) is 1 − δ (δ > 0).

    With a = σx/σy: (w/2)² / (2 a² σy²) + (h/2)² / (2 σy²) = −ln(1 − δ), so
    σy² = (w²/a² + h²) / (8 (−ln(1 − δ))), σx = a σy.

    >>> from eyelume.scene.model import EyePlane
    >>> sx, sy = gaussian_sigmas(0.5, EyePlane())   # 40 × 30 mm: √(w² + h²) = 50 mm
    >>> sx == sy, round(sx, 3), round(50 / math.sqrt(8 * math.log(2)), 3)
    (True, 21.233, 21.233)
    """
    d = _check_delta(delta)
    if d == 0:
        raise ValueError("delta = 0: the target is uniform (no finite sigma)")
    a = 1.0 if sigma_x_over_y is None else float(sigma_x_over_y)
    if not (math.isfinite(a) and a > 0):
        raise ValueError(f"sigma_x_over_y = {sigma_x_over_y!r}: must be a positive number")
    p = _plane(plane)
    sy = math.sqrt((p.width_mm**2 / a**2 + p.height_mm**2) / (8.0 * -math.log1p(-d)))
    return a * sy, sy


def gaussian_value(
    x: np.ndarray | float,
    y: np.ndarray | float,
    delta: float,
    plane: EyePlane,
    sigma_x_over_y: float | None = None,
) -> np.ndarray:
    """The target function t(x, y) (x, y in mm on the eye plane): 1 at the centre, 1 − δ at the
    corners (±w/2, ±h/2); exactly 1 everywhere when δ = 0.

    >>> from eyelume.scene.model import EyePlane
    >>> round(float(gaussian_value(20.0, 15.0, 0.3, EyePlane())), 12)
    0.7
    """
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if _check_delta(delta) == 0:
        if sigma_x_over_y is not None:
            gaussian_sigmas(0.5, plane, sigma_x_over_y)  # validate the aspect all the same
        return np.ones(np.broadcast(x, y).shape)
    sx, sy = gaussian_sigmas(delta, plane, sigma_x_over_y)
    return np.exp(-0.5 * ((x / sx) ** 2 + (y / sy) ** 2))


def gaussian_target(
    delta: float, plane: EyePlane, sigma_x_over_y: float | None = None
) -> np.ndarray:
    """The paper's target on the eye-plane bins: t at every bin centre, (rows, cols), row 0 at +y.

    Parameters
    ----------
    delta
        Falloff at the diagonal corner of the plane, 0 ≤ δ < 1: t(corner) = (1 − δ) t(centre).
        δ = 0 gives a uniform target (exactly 1 everywhere).
    plane
        The eye plane (or a Scene, whose ``eye_plane`` is used).
    sigma_x_over_y
        σx/σy; None for an isotropic distribution (σx = σy).

    >>> from eyelume.scene.model import EyePlane
    >>> t = gaussian_target(0.5, EyePlane())
    >>> t.shape, float(t[7, 10]), bool(t.min() > 0.5)
    ((15, 21), 1.0, True)
    """
    x, y = bin_centres(plane)
    return gaussian_value(x[None, :], y[:, None], delta, plane, sigma_x_over_y)


def load_target(path: str | Path, plane: EyePlane) -> np.ndarray:
    """A user-defined target pattern from a ``.csv`` (numbers separated by commas, ``#`` comments)
    (UTF-8 with or without a byte-order mark, UTF-16 or Windows-1252)
    or ``.npy`` file: a (rows, cols) array of the eye plane's bins, row 0 at +y, column 0 at −x.

    Raises InputFileError (a ValueError) naming the file and the problem: unreadable, wrong
    shape, a value that is not finite or is negative, or all zeros.
    """
    path = Path(path)
    p = _plane(plane)
    where = f"target file '{path}'"
    suffix = path.suffix.lower()
    if suffix not in (".csv", ".npy"):
        raise InputFileError(f"unknown format '{path.suffix}' (use .csv or .npy)", file=where)
    try:
        if suffix == ".npy":
            data = np.load(path, allow_pickle=False)
        else:  # any encoding a spreadsheet writes (a BOM, UTF-16, Windows-1252)
            text = decode_text(path.read_bytes(), path, InputFileError).lstrip("\ufeff")
            data = np.loadtxt(io.StringIO(text), delimiter=",", comments="#", ndmin=2, dtype=float)
    except OSError as exc:
        raise InputFileError(f"cannot read ({exc.strerror or exc})", file=where) from None
    except ValueError as exc:
        raise InputFileError(f"not a table of numbers ({exc})", file=where) from None
    data = np.asarray(data)
    if data.dtype.kind not in "iuf":
        raise InputFileError(f"holds {data.dtype} values, not numbers", file=where)
    data = data.astype(float)
    if data.shape != (p.rows, p.cols):
        raise InputFileError(
            f"shape {data.shape} but the eye plane has (rows, cols) = ({p.rows}, {p.cols})",
            file=where,
        )
    bad = ~np.isfinite(data)
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise InputFileError(
            f"value at row {r}, column {c} is {data[r, c]} (not finite)", file=where
        )
    if (data < 0).any():
        r, c = np.argwhere(data < 0)[0]
        raise InputFileError(f"value at row {r}, column {c} is {data[r, c]} (negative)", file=where)
    if not data.any():
        raise InputFileError("every value is zero (no pattern to match)", file=where)
    return data
