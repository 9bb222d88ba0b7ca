"""Schematic-eye optics: indices at any wavelength and the eye's paraxial layout."""

from __future__ import annotations

import math

from eyelume.scene.model import Eye
from eyelume.scene.optics import curvature, sag

__all__ = [
    "LAMBDA_C",
    "LAMBDA_D",
    "LAMBDA_F",
    "eye_index",
    "eye_indices",
    "iris_root_radius",
    "limbus_geometry",
]

LAMBDA_D = 587.5618  # nm, helium d line
LAMBDA_F = 486.1327  # nm, hydrogen F line
LAMBDA_C = 656.2725  # nm, hydrogen C line


def eye_index(nd: float, nF: float, nC: float, wavelength_nm: float) -> float:
    """Index of an ocular medium at any wavelength from its d, F and C values.

    The two-term Cauchy law n(λ) = A + B/λ², anchored at n_d with the slope B fixed by the F–C
    dispersion (the form behind the Arizona eye's dispersion, Schwiegerling 2004):

        n(λ) = n_d + (n_F − n_C) (λ⁻² − λ_d⁻²) / (λ_F⁻² − λ_C⁻²)

    Three values and two parameters: the law passes through n_d exactly and reproduces
    n_F − n_C exactly. Beyond the visible (850 nm) it is an extrapolation, as in the paper.

    Examples
    --------
    >>> round(eye_index(1.3771, 1.3807, 1.37405, 587.5618), 6)
    1.3771
    """
    if not (wavelength_nm > 0 and math.isfinite(wavelength_nm)):
        raise ValueError(f"wavelength_nm = {wavelength_nm!r} must be a positive number")
    inv2 = lambda lam: 1.0 / (lam * 1e-3) ** 2  # noqa: E731  (µm⁻²)
    slope = (nF - nC) / (inv2(LAMBDA_F) - inv2(LAMBDA_C))
    return nd + slope * (inv2(wavelength_nm) - inv2(LAMBDA_D))


def eye_indices(eye: Eye, wavelength_nm: float) -> list[float]:
    """Indices [air, after surface 1, …] of the eye's media at ``wavelength_nm``; air is 1."""
    out = [1.0]
    for s in eye.surfaces[:-1]:
        out.append(eye_index(s.nd, s.nF, s.nC, wavelength_nm))
    return out


def limbus_geometry(eye: Eye) -> tuple[float, float, float]:
    """The limbus and the eyeball: (limbus radius, limbus depth z', eyeball-centre depth z').

    The sclera is the sphere of ``sclera_radius_mm`` through the edge of the anterior cornea's
    clear aperture, centred on the axis (eye frame, mm behind the corneal vertex).
    """
    cornea = eye.surfaces[0]
    r_l = cornea.semi_diameter_mm
    z_l = float(sag(curvature(cornea.radius_mm), cornea.conic, r_l))
    if math.isnan(z_l):
        raise ValueError(
            f"eye.surfaces.0.semi_diameter_mm = {r_l} exceeds the extent of the corneal conicoid"
        )
    return r_l, z_l, z_l + math.sqrt(eye.sclera_radius_mm**2 - r_l**2)


def iris_root_radius(eye: Eye) -> float:
    """Outer radius (mm) of the iris root: where the iris's plane meets the eyeball wall.

    The iris lies in the vertex plane of surface ``iris_surface`` at depth z_i behind the
    corneal vertex (eye frame). Between its outer edge (``iris_outer_diameter_mm`` / 2) and the
    sclera sphere (radius R about the eyeball centre at depth z_c, :func:`limbus_geometry`) a real
    eye has the iris root, the iris's thin periphery inserting into the ciliary body; the scene
    closes that ring with an opaque annulus out to

        r_root = √(R² − (z_c − z_i)²),

    so that light enters the eye only through the pupil. Paper eye: z_i = 3.6 mm, R = 12 mm,
    z_c = 13.04 mm → r_root = 7.41 mm (the iris edge is at 5.5 mm).

    Raises
    ------
    ValueError
        One line naming the field, if the iris plane lies in front of the limbus (the root
        would have to meet the cornea, which the model does not describe) or outside the
        eyeball, or if the iris's outer edge reaches beyond the eyeball wall.
    """
    r_l, z_l, z_c = limbus_geometry(eye)
    z_i = sum(s.thickness_mm for s in eye.surfaces[: eye.iris_surface])
    if z_i < z_l:
        raise ValueError(
            f"eye.iris_surface = {eye.iris_surface}: the iris plane (depth {z_i:.3f} mm) lies in "
            f"front of the limbus (depth {z_l:.3f} mm), so the iris root cannot reach the sclera"
        )
    h2 = eye.sclera_radius_mm**2 - (z_c - z_i) ** 2
    if h2 <= 0.0:
        raise ValueError(
            f"eye.iris_surface = {eye.iris_surface}: the iris plane (depth {z_i:.3f} mm) lies "
            f"outside the eyeball (sclera_radius_mm = {eye.sclera_radius_mm})"
        )
    r_root = math.sqrt(h2)
    if eye.iris_outer_diameter_mm / 2 > r_root:
        raise ValueError(
            f"eye.iris_outer_diameter_mm = {eye.iris_outer_diameter_mm}: the iris reaches beyond "
            f"the eyeball wall, {2 * r_root:.3f} mm across in the iris plane"
        )
    return r_root
