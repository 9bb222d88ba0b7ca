"""Schematic-eye optics: indices at any wavelength and the eye's paraxial layout."""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from eyelume.errors import GeometryError
from eyelume.scene.eye_models import ocular_index, tear_film_reflectance
from eyelume.scene.model import Eye
from eyelume.scene.optics import curvature, sag

__all__ = [
    "LAMBDA_C",
    "LAMBDA_D",
    "LAMBDA_F",
    "LIMBUS_MISMATCH_MM",
    "anterior_cornea_points",
    "anterior_cornea_pose",
    "anterior_quadric",
    "check_eye_geometry",
    "eye_index",
    "eye_indices",
    "glint_reflectance",
    "iris_root_radius",
    "limbus_geometry",
    "meridian_sag",
    "with_contact_lens",
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
    """Indices [air, after surface 1, …] of the eye's media at ``wavelength_nm``; air is 1.

    By the eye's ``dispersion``: ``"cauchy_dFC"``, :func:`eye_index` from each medium's
    nd, nF, nC; ``"atchison_smith_2005"``, :func:`eyelume.scene.eye_models.ocular_index` from
    its medium and n_ref at ``eye.reference_wavelength_nm``.

    Raises
    ------
    ValueError
        ``"atchison_smith_2005"`` and a wavelength outside its 400–1060 nm (one line).
    """
    out = [1.0]
    for s in eye.surfaces[:-1]:
        if eye.dispersion == "atchison_smith_2005":
            n = ocular_index(s.medium, s.n_ref, eye.reference_wavelength_nm, wavelength_nm)
        else:
            n = eye_index(s.nd, s.nF, s.nC, wavelength_nm)
        out.append(n)
    return out


def glint_reflectance(eye: Eye, wavelength_nm: float) -> float:
    """The anterior cornea's reflectance as a fixed split at ``wavelength_nm``: the tear film's
    normal-incidence Fresnel reflectance for ``cornea_reflection = "tear_film"``
    (:func:`eyelume.scene.eye_models.tear_film_reflectance`), else ``cornea_reflectance``
    (for ``"fresnel"`` the kernel computes R(θ) itself and this value is unused)."""
    if eye.cornea_reflection == "tear_film":
        return tear_film_reflectance(wavelength_nm)
    return eye.cornea_reflectance


#: The farthest (mm) a decentred, tilted or astigmatic anterior cornea's edge may lie from the
#: sclera sphere it should meet at the limbus (ASSUMPTION: the corneoscleral limbus, where the
#: clear cornea turns into the sclera, is a band 1–2 mm wide, so a step of up to 1 mm stays
#: within it; the light that a step lets past the cornea's edge falls in that band).
LIMBUS_MISMATCH_MM = 1.0

#: Physical range of a meridian's asphericity Q for an astigmatic cornea (the population's,
#: ``presets/eyes/population.toml``).
_Q_RANGE = (-1.5, 1.0)


def anterior_quadric(eye: Eye) -> tuple[float, float, float]:
    """(c_flat, c_steep, k) of the anterior cornea's quadric (1/mm, 1/mm, —):

        c_flat x² + c_steep y² + (1 + k) c_flat z² − 2 z = 0

    in its own frame (x along the flat meridian, :class:`~eyelume.scene.model.AnteriorCornea`);
    c_steep = c_flat for a rotationally symmetric cornea (then the conicoid of
    ``eye.surfaces.0``)."""
    front = eye.surfaces[0]
    c = curvature(front.radius_mm)
    steep = eye.cornea.radius_steep_mm
    return c, (c if steep is None else 1.0 / steep), front.conic


def meridian_sag(c_flat: float, c_steep: float, k: float, h, psi):
    """Sag z (mm) of the quadric of :func:`anterior_quadric` at distance ``h`` (mm) from its
    apex along the meridian at angle ``psi`` (rad) from the flat one: that meridian is the
    conic of curvature c_ψ = c_flat cos²ψ + c_steep sin²ψ and conic constant
    (1 + k) c_flat / c_ψ − 1, so z = c_ψ h² / (1 + √(1 − (1 + k) c_flat c_ψ h²)); NaN where
    the surface has no point."""
    c_psi = c_flat * np.cos(psi) ** 2 + c_steep * np.sin(psi) ** 2
    disc = 1.0 - (1.0 + k) * c_flat * c_psi * np.asarray(h, dtype=float) ** 2
    with np.errstate(invalid="ignore"):
        return c_psi * np.asarray(h) ** 2 / (1.0 + np.sqrt(disc))


def _rot_x(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _rot_y(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rot_z(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


_EYE_FLIP = np.diag([-1.0, 1.0, -1.0])  # file frame (as written, primary gaze) ↔ eye frame


def anterior_cornea_pose(eye: Eye) -> tuple[np.ndarray, np.ndarray]:
    """(o, M): the anterior cornea's apex o (eye frame: x′ = −x, y′ = y, z′ mm behind the
    nominal vertex) and the rotation M (eye frame → the quadric's own frame, x along the
    flat meridian): a point p′ of the eye frame is M (p′ − o) in the quadric's frame.

    The decentration (x, y) of the file frame is o = (−x, y, 0); the tilt turns the corneal
    axis as gaze turns the eye (vertical about x toward +y, then horizontal about y toward
    +x), T = R_y(h) R_x(−v) in the file frame; the flat meridian at TABO ``axis_deg`` θ (file
    frame direction (cos θ, sin θ, 0)) lies at φ = 180° − θ from the eye frame's x′ axis:
    M = R_z(−φ) (F T F)ᵀ with F = diag(−1, 1, −1)."""
    cor = eye.cornea
    dx, dy = cor.decentration_mm
    v, h = (math.radians(a) for a in cor.tilt_deg)
    tilt = _EYE_FLIP @ (_rot_y(h) @ _rot_x(-v)) @ _EYE_FLIP
    phi = math.pi - math.radians(cor.axis_deg)
    return np.array([-dx, dy, 0.0]), _rot_z(-phi) @ tilt.T


def anterior_cornea_points(eye: Eye, h, psi) -> np.ndarray:
    """Eye-frame points (…, 3) of the anterior cornea at distance ``h`` from its apex along
    its meridian ``psi`` (rad from the flat meridian) (:func:`anterior_cornea_pose`,
    :func:`meridian_sag`)."""
    c1, c2, k = anterior_quadric(eye)
    h, psi = np.broadcast_arrays(np.asarray(h, float), np.asarray(psi, float))
    z = meridian_sag(c1, c2, k, h, psi)
    local = np.stack([h * np.cos(psi), h * np.sin(psi), z], axis=-1)
    o, m = anterior_cornea_pose(eye)
    return local @ m + o


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


#: Radii at which surfaces are compared for crossing, per unit of the common clear aperture.
_PROBES = np.linspace(0.0, 1.0, 65)


def _profile(eye: Eye, j: int, h: np.ndarray) -> np.ndarray:
    """Depth z′(h) (mm behind the anterior corneal vertex, eye frame) of surface ``j``."""
    s = eye.surfaces[j]
    z0 = sum(t.thickness_mm for t in eye.surfaces[:j])
    return z0 + sag(curvature(s.radius_mm), s.conic, h)


def check_eye_geometry(eye: Eye) -> None:
    """Refuse a schematic eye that cannot exist, before anything is traced.

    Checked, in this order (eye frame: z′ mm behind the anterior corneal vertex, h the distance
    from the axis):

    1. every surface's conicoid reaches its clear aperture (1 − (1+k) c² h² ≥ 0 at
       h = ``semi_diameter_mm``);
    2. the anterior cornea is convex toward the world (``radius_mm`` > 0): its edge, the
       limbus, lies behind its vertex, where the sclera meets it;
    3. every refracting surface has a thickness (``thickness_mm`` > 0 to the next surface);
    4. no two surfaces i < j cross inside their common clear aperture:
       z′_j(h) > z′_i(h) for 0 ≤ h ≤ min(semi-diameters), probed at 65 radii;
    5. the pupil fits the lens that carries it: ``pupil_diameter_mm`` ≤ 2 × that surface's
       ``semi_diameter_mm`` (light through the pupil must meet the lens);
    6. no surface cuts through the iris (the annulus from the pupil's to the iris's radius in
       the vertex plane z′_i of ``iris_surface``): the surfaces before it lie in front of that
       plane, the surface that carries it and those after lie behind it;
    7. the surfaces from the iris back (the lens and the retina; the cornea bulges beyond the
       sclera sphere, as a real one does) lie inside the eyeball, the sclera sphere of
       :func:`limbus_geometry`, over their clear apertures;
    8. an astigmatic, decentred or tilted anterior cornea (``eye.cornea``): each meridian's
       Q in −1.5 … 1 and reaching the clear aperture, its edge within
       :data:`LIMBUS_MISMATCH_MM` of the sclera, the cap in front of the iris plane and the
       posterior cornea (:func:`_check_cornea`).

    Raises
    ------
    GeometryError
        One line naming the field (``eye.surfaces.N.radius_mm``, ``.thickness_mm``,
        ``eye.pupil_diameter_mm``, ``eye.sclera_radius_mm`` …), its value and what it breaks.
    """
    _check_shapes(eye)
    _check_crossings(eye)
    _check_iris(eye)
    _check_eyeball(eye)
    _check_cornea(eye)


def _cornea_field(eye: Eye) -> tuple[str, object]:
    """The field (and value) to name for an astigmatic or placed cornea that cannot exist."""
    cor = eye.cornea
    if cor.placed:
        return "eye.cornea.decentration_mm / tilt_deg", (
            list(cor.decentration_mm),
            list(cor.tilt_deg),
        )
    return "eye.cornea.radius_steep_mm", cor.radius_steep_mm


def _check_cornea(eye: Eye) -> None:
    """Item 8 of :func:`check_eye_geometry`, for an astigmatic, decentred or tilted anterior
    cornea (:class:`~eyelume.scene.model.AnteriorCornea`; a rotationally symmetric one on the
    axis is items 1–7's): each meridian's asphericity within the physical range −1.5 … 1
    (population.toml) and its surface reaching the clear aperture; its edge within
    :data:`LIMBUS_MISMATCH_MM` of the sclera sphere (it must still meet the limbus); the whole
    cap in front of the iris plane and of the posterior cornea (probed on 17 rings × 72
    meridians)."""
    cor = eye.cornea
    if cor.radius_steep_mm is None and not cor.placed:
        return
    field, value = _cornea_field(eye)
    c1, c2, k = anterior_quadric(eye)
    h_max = eye.surfaces[0].semi_diameter_mm
    for name, c in (("flat", c1), ("steep", c2)):
        q = (1.0 + k) * c1 / c - 1.0
        if not _Q_RANGE[0] <= q <= _Q_RANGE[1]:
            raise GeometryError(
                f"the {name} meridian's asphericity Q = {q:.3f} lies outside the physical range "
                f"[{_Q_RANGE[0]:g}, {_Q_RANGE[1]:g}]",
                field="eye.cornea.radius_steep_mm",
                value=cor.radius_steep_mm,
            )
        psi_m = 0.0 if name == "flat" else math.pi / 2
        if math.isnan(float(meridian_sag(c1, c2, k, h_max, psi_m))):
            raise GeometryError(
                f"the anterior cornea's {name} meridian has no point at its clear aperture "
                f"(eye.surfaces.0.semi_diameter_mm = {h_max})",
                field=field,
                value=value,
            )
    psi = np.linspace(0.0, 2 * math.pi, 72, endpoint=False)
    _, _, z_c = limbus_geometry(eye)
    edge = anterior_cornea_points(eye, h_max, psi)
    miss = np.abs(np.linalg.norm(edge - [0.0, 0.0, z_c], axis=1) - eye.sclera_radius_mm)
    if float(miss.max()) > LIMBUS_MISMATCH_MM:
        raise GeometryError(
            f"the anterior cornea's edge lies up to {float(miss.max()):.3f} mm from the sclera "
            f"it should meet at the limbus (at most {LIMBUS_MISMATCH_MM} mm)",
            field=field,
            value=value,
        )
    cap = anterior_cornea_points(eye, (_PROBES[::4] * h_max)[:, None], psi[None, :])
    z_i = sum(t.thickness_mm for t in eye.surfaces[: eye.iris_surface])
    rho = np.hypot(cap[..., 0], cap[..., 1])
    inside = rho <= eye.surfaces[1].semi_diameter_mm
    behind = _profile(eye, 1, rho) - cap[..., 2]
    if float(cap[..., 2].max()) >= z_i or np.any(behind[inside] <= 0.0):
        raise GeometryError(
            "the anterior cornea reaches the posterior cornea or the iris plane "
            f"({z_i:.3g} mm behind the vertex)",
            field=field,
            value=value,
        )


def _check_shapes(eye: Eye) -> None:
    """Items 1–3 of :func:`check_eye_geometry`."""
    surf = eye.surfaces
    for j, s in enumerate(surf):
        if math.isnan(float(sag(curvature(s.radius_mm), s.conic, s.semi_diameter_mm))):
            raise GeometryError(
                f"exceeds the extent of the '{s.name}' conicoid (radius {s.radius_mm} mm, "
                f"conic {s.conic})",
                field=f"eye.surfaces.{j}.semi_diameter_mm",
                value=s.semi_diameter_mm,
            )
    if not surf[0].radius_mm > 0:
        raise GeometryError(
            "the anterior cornea must be convex toward the world (radius > 0): a concave front "
            "puts the limbus in front of the corneal vertex, which no eye has",
            field="eye.surfaces.0.radius_mm",
            value=surf[0].radius_mm,
        )
    for j, s in enumerate(surf[:-1]):
        if not s.thickness_mm > 0:
            raise GeometryError(
                f"'{s.name}' and '{surf[j + 1].name}' touch on the axis: every refracting "
                "surface needs a thickness > 0 to the next",
                field=f"eye.surfaces.{j}.thickness_mm",
                value=s.thickness_mm,
            )


def _check_crossings(eye: Eye) -> None:
    """Item 4 of :func:`check_eye_geometry`."""
    surf = eye.surfaces
    for i in range(len(surf)):
        for j in range(i + 1, len(surf)):
            h = _PROBES * min(surf[i].semi_diameter_mm, surf[j].semi_diameter_mm)
            gap = _profile(eye, j, h) - _profile(eye, i, h)
            if np.any(gap <= 0.0):
                at = float(h[np.argmax(gap <= 0.0)])
                raise GeometryError(
                    f"'{surf[i].name}' and '{surf[j].name}' cross {at:.3g} mm from the axis, "
                    "inside their clear apertures: no eye has surfaces that cross; check the "
                    f"radii and thicknesses of eye.surfaces.{i} to {j}",
                    field=f"eye.surfaces.{j - 1}.thickness_mm",
                    value=surf[j - 1].thickness_mm,
                )


def _check_iris(eye: Eye) -> None:
    """Items 5–6 of :func:`check_eye_geometry`, after :func:`iris_root_radius`'s own checks
    (the iris plane behind the limbus and inside the eyeball)."""
    try:
        iris_root_radius(eye)
    except ValueError as exc:
        raise GeometryError(str(exc)) from None
    surf, k = eye.surfaces, eye.iris_surface
    if eye.pupil_diameter_mm > 2 * surf[k].semi_diameter_mm:
        raise GeometryError(
            f"the pupil is wider than the '{surf[k].name}' it lies on (semi_diameter_mm "
            f"{surf[k].semi_diameter_mm}): light through its edge would meet no lens",
            field="eye.pupil_diameter_mm",
            value=eye.pupil_diameter_mm,
        )
    z_i = sum(t.thickness_mm for t in surf[:k])
    r_p, r_o = eye.pupil_diameter_mm / 2, eye.iris_outer_diameter_mm / 2
    for j, s in enumerate(surf):
        hi = min(r_o, s.semi_diameter_mm)
        if hi < r_p:
            continue
        z = _profile(eye, j, np.linspace(r_p, hi, 33))
        bad = np.any(z >= z_i) if j < k else np.any(z < z_i - 1e-12)
        if bad:
            raise GeometryError(
                f"the '{s.name}' surface cuts through the iris (the plane {z_i:.3g} mm behind the "
                f"corneal vertex, from the pupil's radius {r_p:g} mm to the iris's {r_o:g} mm)",
                field=f"eye.surfaces.{j}.radius_mm",
                value=s.radius_mm,
            )


def _check_eyeball(eye: Eye) -> None:
    """Item 7 of :func:`check_eye_geometry`."""
    surf, k = eye.surfaces, eye.iris_surface
    _, _, z_c = limbus_geometry(eye)
    big = eye.sclera_radius_mm * (1 + 1e-9)
    for j, s in enumerate(surf[k:], start=k):
        h = _PROBES * s.semi_diameter_mm
        dist = np.hypot(h, _profile(eye, j, h) - z_c)
        if np.any(dist > big):
            raise GeometryError(
                f"the '{s.name}' surface (eye.surfaces.{j}) reaches {float(dist.max()):.4g} mm "
                "from the eyeball's centre, outside the eyeball (the sclera sphere through the "
                "limbus)",
                field="eye.sclera_radius_mm",
                value=eye.sclera_radius_mm,
            )


def with_contact_lens(scene):
    """The scene with its eye's contact lens (``eye.contact_lens``,
    :class:`~eyelume.scene.model.ContactLens`) built in, and that field cleared (so applying it
    twice is applying it once); a scene without one is returned unchanged.
    :func:`eyelume.compile.compile_scene` calls it first, so everything compiled sees the lens.

    A thin shell of thickness t concentric with the anterior cornea (radius R, conic k): the
    eye's first surface becomes the lens's front, radius R + t, same conic (ASSUMPTION, a lens
    that follows the cornea's cap — for a conic, R + t with the same k is concentric only near
    the axis; a soft lens's skirt over the sclera is not modelled), t in front of the corneal
    vertex, so the eye frame's vertex moves t toward the world (``eye_pose.relief_mm`` − t;
    the rotation centre stays put: ``rotation_centre_mm`` + t; the face moves with the eye
    frame by t) and the first surface's thickness grows by t; its clear aperture ends where it
    meets the sclera sphere (so the eyeball, :func:`limbus_geometry`, stays where it was).
    An astigmatic cornea's lens is astigmatic alike (its steep radius + t, same axis and
    placement: a soft lens drapes over the cornea; ASSUMPTION for a rigid one).

    Its reflection: the front's Fresnel reflectance at normal incidence, R = ((n − 1)/(n + 1))²
    (n the lens's index; 4.0 % for 1.50 against the tear film's 2.1 %), as a fixed split
    (ASSUMPTION: its rise with the angle — 4.2 % at 30° for n = 1.50 — is ignored). Behind the
    front the shell refracts as the cornea (the medium after the first surface keeps the
    cornea's index): a thin concentric shell bends a ray as the single interface does to first
    order in t, and its back face against the tear film and cornea (index step 1.50 → ~1.376:
    R ≈ 0.2 %) forms no glint here.
    """
    eye = scene.eye
    lens = eye.contact_lens
    if lens is None:
        return scene
    t, n = lens.thickness_mm, lens.refractive_index
    cornea = eye.surfaces[0]
    c, k = curvature(cornea.radius_mm + t), cornea.conic
    _, _, z_c = limbus_geometry(eye)  # eyeball centre, behind the bare corneal vertex
    r_s = eye.sclera_radius_mm

    def off_sclera(h: float) -> float:  # the front's point at height h against the sclera
        return h * h + (z_c + t - float(sag(c, k, h))) ** 2 - r_s * r_s

    # the shell lies t outside the cornea, so it meets the sclera just beyond the limbus
    edge = brentq(off_sclera, cornea.semi_diameter_mm, cornea.semi_diameter_mm + 2.0)
    front = cornea.model_copy(
        update={
            "radius_mm": cornea.radius_mm + t,
            "thickness_mm": cornea.thickness_mm + t,
            "semi_diameter_mm": edge,
        }
    )
    steep = eye.cornea.radius_steep_mm
    cornea_shape = eye.cornea.model_copy(
        update={"radius_steep_mm": None if steep is None else steep + t}
    )
    fitted = eye.model_copy(
        update={
            "surfaces": [front, *eye.surfaces[1:]],
            "cornea": cornea_shape,
            "cornea_reflection": "fixed",
            "cornea_reflectance": ((n - 1.0) / (n + 1.0)) ** 2,
            "rotation_centre_mm": eye.rotation_centre_mm + t,
            "contact_lens": None,
        }
    )
    pose = scene.eye_pose.model_copy(update={"relief_mm": scene.eye_pose.relief_mm - t})
    return scene.model_copy(update={"eye": fitted, "eye_pose": pose})
