"""Optical elements (:class:`eyelume.scene.model.Element`) as geometry in their own frame, and
their coatings' reflectance tables.

An element's local frame: its axis is +z, its first surface's vertex the origin, surface j's
vertex at z = ``vertex_z_mm(element)[j]`` (0, then the centre thickness). A lens or plate is the
solid between its two surfaces within the clear aperture r ≤ sd, closed by the cylinder r = sd;
a mirror is its one surface (no thickness). :func:`outline_points` samples that boundary, so
:mod:`eyelume.compile` can refuse an element that cuts the eye, the face, an LED or another
element (a sampled test: a few hundred points per element, good to about sd/16).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from eyelume.errors import InputFileError
from eyelume.scene.model import Element
from eyelume.scene.textfile import is_header_row, read_csv_rows

__all__ = [
    "crosses_surfaces",
    "inside_solid",
    "near_element",
    "outline_points",
    "read_reflectance_table",
    "vertex_z_mm",
]

_AZIMUTHS = 24
_RADII = 16


def vertex_z_mm(element: Element) -> list[float]:
    """Local z (mm) of each surface's vertex: [0] for a mirror, [0, t] for a lens or plate."""
    return [0.0] if element.kind == "mirror" else [0.0, float(element.thickness_mm)]  # type: ignore[arg-type]


def _sag(element: Element, j: int, r: np.ndarray) -> np.ndarray:
    s = element.surfaces[j]
    return np.array([s.sag_mm(float(x)) for x in np.ravel(r)]).reshape(np.shape(r))


def outline_points(element: Element, azimuths: int = _AZIMUTHS, radii: int = _RADII) -> np.ndarray:
    """The element's boundary as meridian polylines, local frame (mm): (azimuths, m, 3). For
    each azimuth φ, the first surface from the axis out to the clear aperture, then (a lens or
    plate) down its edge and back in along the second surface to the axis."""
    sd = element.semi_diameter_mm
    r = np.linspace(0.0, sd, radii + 1)
    z0 = vertex_z_mm(element)
    rs = [r]
    zs = [z0[0] + _sag(element, 0, r)]
    if element.kind != "mirror":
        e0, e1 = zs[0][-1], z0[1] + _sag(element, 1, np.array([sd]))[0]
        rs += [np.full(4, sd), r[::-1]]
        zs += [np.linspace(e0, e1, 6)[1:-1], z0[1] + _sag(element, 1, r[::-1])]
    rr, zz = np.concatenate(rs), np.concatenate(zs)
    phi = np.linspace(0.0, 2.0 * math.pi, azimuths, endpoint=False)
    out = np.empty((azimuths, rr.size, 3))
    out[:, :, 0] = np.outer(np.cos(phi), rr)
    out[:, :, 1] = np.outer(np.sin(phi), rr)
    out[:, :, 2] = zz
    return out


def inside_solid(element: Element, local: np.ndarray, margin: float = 0.0) -> np.ndarray:
    """Which local points (…, 3) lie inside the element's solid by more than ``margin`` mm
    (r < sd − margin, sag₁(r) + margin < z < t + sag₂(r) − margin); a mirror has no inside."""
    local = np.asarray(local, dtype=float)
    if element.kind == "mirror":
        return np.zeros(local.shape[:-1], dtype=bool)
    r = np.hypot(local[..., 0], local[..., 1])
    sd = element.semi_diameter_mm
    rc = np.minimum(r, sd)
    z0 = vertex_z_mm(element)
    lo = z0[0] + _sag(element, 0, rc)
    hi = z0[1] + _sag(element, 1, rc)
    z = local[..., 2]
    return (r < sd - margin) & (z > lo + margin) & (z < hi - margin)


def near_element(element: Element, local: np.ndarray, clearance: float) -> np.ndarray:
    """Which local points (…, 3) lie within about ``clearance`` mm of the element: inside a
    lens's or plate's solid grown by ``clearance`` (a box in r and z, so a little generous at
    the rim), or within ``clearance`` of a mirror's surface along its axis, r ≤ sd + clearance.
    """
    local = np.asarray(local, dtype=float)
    if element.kind != "mirror":
        return inside_solid(element, local, margin=-clearance)
    r = np.hypot(local[..., 0], local[..., 1])
    h = local[..., 2] - _sag(element, 0, np.minimum(r, element.semi_diameter_mm))
    return (r <= element.semi_diameter_mm + clearance) & (np.abs(h) < clearance)


def crosses_surfaces(element: Element, polylines: np.ndarray) -> bool:
    """Whether a segment of ``polylines`` (k, m, 3) (local frame of ``element``) crosses one of
    its optical surfaces within its clear aperture (the signed height z − z_surface(r) changes
    sign between a segment's ends, both within the aperture)."""
    p = np.asarray(polylines, dtype=float)
    r = np.hypot(p[..., 0], p[..., 1])
    within = r <= element.semi_diameter_mm
    rc = np.minimum(r, element.semi_diameter_mm)
    for j, z0 in enumerate(vertex_z_mm(element)):
        h = p[..., 2] - (z0 + _sag(element, j, rc))
        flip = (np.sign(h[:, :-1]) != np.sign(h[:, 1:])) & within[:, :-1] & within[:, 1:]
        if np.any(flip):
            return True
    return False


def read_reflectance_table(
    path: str, field: str, wavelength_nm: float | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """A coating's R(θ) table at ``wavelength_nm``: (angles of incidence in rad, reflectance
    0 … 1).

    The CSV (UTF-8, UTF-16 or Windows-1252, as :func:`~eyelume.scene.textfile.read_text_file`
    reads it) has two columns, angle of incidence in degrees and reflectance R (a fraction),
    one row per angle — or three, angle (degrees), wavelength (nm) and R, the rows of each
    wavelength an R(θ) curve of their own (a coating measured at several wavelengths, for a
    scene whose LEDs have more than one). Lines starting with ``#`` are skipped, and a first
    row of words only (``angle_deg, R``: :func:`~eyelume.scene.textfile.is_header_row`) as its
    header; a first row mixing numbers and words (``O.5, 0.04``, a letter O for a zero), or a
    row of another number of columns, is refused naming the row. Each curve's angles increase
    from 0 to 90° (both given: R is interpolated linearly between rows, never extrapolated).
    With wavelengths, R(θ, λ) is interpolated linearly in λ between the two curves that bracket
    ``wavelength_nm`` (on the union of their angles); a wavelength outside the table's is
    refused, never extrapolated.

    Raises
    ------
    InputFileError
        One line naming the file, ``field`` and the bad row or value.
    """
    where = Path(path)
    curves: dict[float | None, tuple[list[float], list[float]]] = {}
    width = 0
    for n, row in enumerate(read_csv_rows(where, field), 1):
        got = _table_row(n, row, width, where, field)
        if got is None:
            continue  # a header line
        width, a, lam, v = got
        angles, values = curves.setdefault(lam, ([], []))
        angles.append(a)
        values.append(v)
    if not curves:
        raise InputFileError("no rows of 'angle_deg, reflectance'", file=where, field=field)
    for lam, (angles, _) in curves.items():
        a = np.asarray(angles)
        if a.size < 2 or np.any(np.diff(a) <= 0) or a[0] != 0.0 or a[-1] != 90.0:
            at = "" if lam is None else f" at {lam:g} nm"
            raise InputFileError(
                f"{a.size} rows of angles{at} {a[:6].tolist()}{' ...' if a.size > 6 else ''}: "
                "the angles must increase from 0 to 90 deg (every angle of incidence a ray can "
                "have)",
                file=where,
                field=field,
            )
    if width == 2:
        a, v = curves[None]
        return np.radians(a), np.asarray(v, dtype=float)
    return _at_wavelength(curves, wavelength_nm, where, field)


_FORMS = {
    0: "'angle_deg, reflectance' or 'angle_deg, wavelength_nm, reflectance'",
    2: "'angle_deg, reflectance'",
    3: "'angle_deg, wavelength_nm, reflectance'",
}


def _table_row(n: int, row: list[str], width: int, where: Path, field: str):
    """Row ``n`` of an R(θ) table as (width, angle °, wavelength nm or None, R); None for a
    first-row header; InputFileError naming the row otherwise. ``width``: the columns of the
    rows before (0: none yet)."""
    cells = [c for c in row if c.strip()]
    try:
        nums = [float(c) for c in cells]
    except ValueError:
        nums = None
    if nums is None or len(nums) not in (2, 3) or (width and len(nums) != width):
        if n == 1 and is_header_row(cells):
            return None  # a header: words only (a first row mixing words and numbers is not)
        raise InputFileError(f"row {n} {row!r} is not {_FORMS[width]}", file=where, field=field)
    a, v = nums[0], nums[-1]
    lam = nums[1] if len(nums) == 3 else None
    if not all(math.isfinite(x) for x in nums) or not 0.0 <= v <= 1.0:
        raise InputFileError(
            f"row {n} {row!r}: the angle{'' if lam is None else ' and wavelength'} must be "
            "finite and the reflectance within 0 … 1",
            file=where,
            field=field,
        )
    if lam is not None and lam <= 0.0:
        raise InputFileError(
            f"row {n} {row!r}: wavelength {lam:g} nm must be positive", file=where, field=field
        )
    if not 0.0 <= a <= 90.0:
        raise InputFileError(
            f"row {n} {row!r}: angle of incidence {a:g} deg out of range 0 … 90",
            file=where,
            field=field,
        )
    return len(nums), a, lam, v


def _at_wavelength(curves: dict, wavelength_nm: float | None, where: Path, field: str):
    """R(θ) at ``wavelength_nm`` from the curves {λ: (angles °, R)}: linear in λ between the
    two that bracket it, on the union of their angles (radians, R)."""
    lams = sorted(curves)
    if wavelength_nm is None or not lams[0] <= wavelength_nm <= lams[-1]:
        raise InputFileError(
            f"wavelength {wavelength_nm} nm outside the table's {lams[0]:g} … {lams[-1]:g} nm "
            "(a table is never extrapolated: add rows for it)",
            file=where,
            field=field,
        )
    hi = int(np.searchsorted(lams, wavelength_nm))
    if lams[hi] == wavelength_nm:
        a, v = curves[lams[hi]]
        return np.radians(a), np.asarray(v, dtype=float)
    l0, l1 = lams[hi - 1], lams[hi]
    (a0, v0), (a1, v1) = curves[l0], curves[l1]
    grid = np.union1d(a0, a1)
    w = (wavelength_nm - l0) / (l1 - l0)
    r = (1.0 - w) * np.interp(grid, a0, v0) + w * np.interp(grid, a1, v1)
    return np.radians(grid), r
