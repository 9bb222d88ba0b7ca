"""Scene → packed arrays for the kernels: the one place that knows both the scene and the kernels.

The compiled scene holds, at the scene's wavelength:

* ``sf``, ``si``: the non-sequential surface table (eye, iris, sclera, retina, face tissues, LED
  bodies and the imaging lens's entrance), columns in :mod:`eyelume.kernels.geometry`;
* ``lf``: the sequential lens table, columns in :mod:`eyelume.kernels.sequential`;
* the LED emission points, axes and the angular-profile sampling tables;
* the sensor and eye-plane binning, the power per LED, and the names of the ledger's entries.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from eyelume.errors import GeometryError, GlassError, SceneError
from eyelume.kernels import geometry as G
from eyelume.kernels import sequential as Q
from eyelume.kernels.sampling import cos_power_tables, profile_tables
from eyelume.scene.eye import eye_indices, iris_root_radius, limbus_geometry
from eyelume.scene.focus import check_focus
from eyelume.scene.glass import Glass, load_catalog
from eyelume.scene.model import Scene
from eyelume.scene.optics import ParaxialSystem, curvature, sag
from eyelume.scene.sources import cos_power_exponent, led_poses, relative_intensity

__all__ = ["CompiledScene", "compile_scene", "gaze_rotation", "lens_paraxial", "lens_indices"]

#: Fixed ledger entries; named surfaces follow.
TALLY_SENSOR, TALLY_ESCAPED, TALLY_VIGNETTED, TALLY_TIR, TALLY_OFF_SENSOR, TALLY_LIMIT = range(6)
FIXED_TALLIES = (
    "sensor",
    "escaped",
    "lens mount (vignetted)",
    "lens (total internal reflection)",
    "image plane outside the sensor",
    "stopped at max_events",
)

EYE_AXIS_ROT = np.array([[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]])
"""World → eye-frame rotation in primary gaze: z' = −z (into the eye), y' = y, x' = −x."""


def _rot_x(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _rot_y(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def gaze_rotation(eye, share_vertical: float = 1.0, share_horizontal: float = 1.0):
    """(R, C): the eye's gaze as a rotation R (primary-gaze world → turned world) about the
    centre of rotation C (world mm): a primary-gaze point p moves to C + R (p − C).

    Vertical first, about x (positive gaze looks up: the optical axis +z tilts toward +y), then
    horizontal, about y (positive looks toward +x). ``share_*`` scale the angles (an eyelid's
    lid–eye coordination)."""
    v = math.radians(eye.gaze_vertical_deg) * share_vertical
    h = math.radians(eye.gaze_horizontal_deg) * share_horizontal
    return _rot_y(h) @ _rot_x(-v), np.array([0.0, 0.0, -eye.rotation_centre_mm])


@dataclass
class CompiledScene:
    """Flat arrays of a scene for the kernels (see module docstring)."""

    scene: Scene
    sf: np.ndarray
    si: np.ndarray
    surface_names: list[str]
    lf: np.ndarray
    lens_indices: list[float]
    stop_index: int
    image_z: float
    leds: np.ndarray  # (N, 6): emission point xyz, unit axis xyz
    led_centres: np.ndarray
    alpha_grid: np.ndarray  # rad, uniform on [0, π/2]
    cdf_grid: np.ndarray
    intensity_grid: np.ndarray  # I(α)/I₀ on alpha_grid
    omega_eff: float  # sr: Φ_LED = I₀ · omega_eff
    sensor: np.ndarray  # width, height, cols, rows
    plane: np.ndarray  # width, height, cols, rows
    tallies: list[str]

    def kernel_arrays(self) -> tuple:
        """What the forward kernels read, as one tuple: (sf, si, lf, image_z, leds, alpha_grid,
        cdf_grid, sensor, plane, max_events)."""
        return (
            self.sf,
            self.si,
            self.lf,
            self.image_z,
            self.leds,
            self.alpha_grid,
            self.cdf_grid,
            self.sensor,
            self.plane,
            self.scene.run.max_events,
        )

    @property
    def led_power_w(self) -> float:
        """Radiant power of one LED (W): Φ = I₀ ∫ I/I₀ dΩ."""
        return self.scene.leds.radiant_intensity_w_sr * self.omega_eff

    @property
    def emitted_w(self) -> float:
        """Radiant power of all LEDs (W)."""
        return self.led_power_w * self.leds.shape[0]


class _Table:
    """Collects non-sequential surfaces and ledger names."""

    def __init__(self) -> None:
        self.rows_f: list[np.ndarray] = []
        self.rows_i: list[np.ndarray] = []
        self.names: list[str] = []
        self.tallies: list[str] = list(FIXED_TALLIES)

    def tally(self, name: str) -> int:
        if name not in self.tallies:
            self.tallies.append(name)
        return self.tallies.index(name)

    def add(
        self,
        name: str,
        shape: int,
        origin,
        rot: np.ndarray,
        bound: tuple[np.ndarray, float],
        *,
        curv: float = 0.0,
        conic: float = 0.0,
        radius: float = 0.0,
        clip_r: tuple[float, float] = (0.0, math.inf),
        clip_z: tuple[float, float] = (-math.inf, math.inf),
        action: int = G.ACT_OPAQUE,
        n_a: float = 1.0,
        n_b: float = 1.0,
        refl: float = 0.0,
        absorb: float = 0.0,
        fresnel: bool = False,
        rho_a: float = 0.0,
        rho_b: float = 0.0,
        tally_a: str = "",
        tally_b: str = "",
    ) -> None:
        f = np.zeros(G.N_FLOAT)
        f[G.OX : G.OZ + 1] = origin
        f[G.R00 : G.R22 + 1] = np.asarray(rot, dtype=float).ravel()
        f[G.CURV], f[G.CONIC], f[G.RADIUS] = curv, conic, radius
        f[G.RMIN2], f[G.RMAX2] = clip_r[0] ** 2, clip_r[1] ** 2
        f[G.ZLO], f[G.ZHI] = clip_z
        f[G.BX : G.BZ + 1] = bound[0]
        f[G.BR] = bound[1]
        f[G.N_A], f[G.N_B] = n_a, n_b
        f[G.REFL], f[G.ABSORB] = refl, absorb
        f[G.RHO_A], f[G.RHO_B] = rho_a, rho_b
        i = np.zeros(G.N_INT, dtype=np.int64)
        i[G.SHAPE], i[G.ACTION], i[G.FRESNEL] = shape, action, int(fresnel)
        i[G.TALLY_A] = self.tally(tally_a or name)
        i[G.TALLY_B] = self.tally(tally_b or name)
        self.rows_f.append(f)
        self.rows_i.append(i)
        self.names.append(name)


def _frame(axis) -> np.ndarray:
    """A rotation whose third row is the unit ``axis`` (world → local)."""
    z = np.asarray(axis, dtype=float)
    z = z / np.linalg.norm(z)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z])


def _conic_bound(origin, rot, curv, conic, rmax) -> tuple[np.ndarray, float]:
    """Bounding sphere of a conicoid cap of radius ``rmax`` about its vertex."""
    s = float(sag(curv, conic, rmax))
    if math.isnan(s):  # callers check apertures against the conicoid's extent first
        raise GeometryError(f"aperture {rmax} mm beyond the conicoid (c {curv}, k {conic})")
    centre = np.asarray(origin) + rot[2] * (s / 2.0)
    return centre, math.hypot(rmax, s / 2.0) * 1.000001 + 1e-9


def lens_indices(scene: Scene) -> tuple[list[float], dict[str, Glass]]:
    """Indices [object space, after surface 1, …] of the lens at the scene wavelength, and the
    catalog entry of each glass used. Raises SceneError for a glass missing from the catalogs."""
    lens = scene.lens
    try:
        catalog = load_catalog(*lens.glass_catalogs) if lens.glass_catalogs else load_catalog()
    except GlassError as exc:
        raise SceneError(f"lens.glass_catalogs: {exc}") from None
    indices = [1.0]
    used: dict[str, Glass] = {}
    for j, s in enumerate(lens.surfaces):
        if not s.glass or s.glass.lower() == "air":
            indices.append(1.0)
            continue
        try:
            used[s.glass] = catalog[s.glass]
        except GlassError as exc:
            raise SceneError(f"field 'lens.surfaces.{j}.glass' = {s.glass!r}: {exc}") from None
        indices.append(used[s.glass].index(scene.wavelength_nm))
    return indices, used


def lens_paraxial(scene: Scene, indices: list[float]) -> ParaxialSystem:
    """The imaging lens as a paraxial system (object space = air)."""
    surfaces = scene.lens.surfaces
    curv = tuple(curvature(s.radius_mm) for s in surfaces)
    gaps = tuple(s.thickness_mm for s in surfaces[:-1])
    return ParaxialSystem(curv, gaps, tuple(indices))


def eye_paraxial(scene: Scene, wavelength_nm: float | None = None) -> ParaxialSystem:
    """The eye's refracting surfaces as a paraxial system (air → vitreous), eye frame."""
    eye = scene.eye
    refracting = eye.surfaces[:-1]
    curv = tuple(curvature(s.radius_mm) for s in refracting)
    gaps = tuple(s.thickness_mm for s in refracting[:-1])
    idx = eye_indices(eye, wavelength_nm or scene.wavelength_nm)
    return ParaxialSystem(curv, gaps, tuple(idx))


def _lens_table(scene: Scene, indices: list[float], semi: list[float]) -> tuple[np.ndarray, float]:
    lens = scene.lens
    lf = np.zeros((len(lens.surfaces), Q.N_LENS_COL))
    z = lens.object_distance_mm
    for j, s in enumerate(lens.surfaces):
        lf[j, Q.L_Z] = z
        lf[j, Q.L_CURV] = curvature(s.radius_mm)
        lf[j, Q.L_CONIC] = s.conic
        lf[j, Q.L_SD] = semi[j]
        lf[j, Q.L_N0], lf[j, Q.L_N1] = indices[j], indices[j + 1]
        z += s.thickness_mm
    return lf, z


def _auto_semi_diameters(
    scene: Scene, indices: list[float], par: ParaxialSystem, stop: int, stop_sd: float
) -> tuple[list[float], float]:
    """Clear semi-diameters from a real-ray trace of the full eye-plane field.

    For a 9 × 7 grid of object points over the eye plane (corners included) the rays through 72
    points of the stop's rim are found by real-ray aiming; the largest height they reach at each
    surface + 1 % (a mechanical clear aperture) is its semi-diameter, so the stop alone limits
    every bundle from the eye area, as the paper's lens was designed. Also returns the fraction
    of rim rays that got through.
    """
    from eyelume.kernels.sequential import rim_ray_heights

    n = len(scene.lens.surfaces)
    lf, _ = _lens_table(scene, indices, [math.inf] * n)
    plane = scene.eye_plane
    xs = np.linspace(-plane.width_mm / 2, plane.width_mm / 2, 9)
    ys = np.linspace(-plane.height_mm / 2, plane.height_mm / 2, 7)
    # the aiming starts from the paraxial entrance pupil (its radius / the stop's)
    pupil_mag = par.efl / scene.lens.f_number / 2 / stop_sd
    pupil_z = scene.lens.object_distance_mm + par.entrance_pupil_position(stop)
    heights, found = rim_ray_heights(lf, stop, stop_sd, xs, ys, 72, pupil_mag, pupil_z)
    out = []
    for j, s in enumerate(scene.lens.surfaces):
        if j == stop:
            out.append(stop_sd)
        elif s.semi_diameter_mm is not None:
            out.append(s.semi_diameter_mm)
        else:
            out.append(1.01 * heights[j])
    return out, found / (xs.size * ys.size * 72)


def _lens_surface_z(lf: np.ndarray, j: int, r) -> np.ndarray:
    """World z (mm) of lens surface ``j`` at radial distance ``r``."""
    return lf[j, Q.L_Z] + sag(lf[j, Q.L_CURV], lf[j, Q.L_CONIC], r)


def _check_lens_geometry(lf: np.ndarray) -> None:
    """Reject surfaces whose sag is undefined inside their aperture or that cross a neighbour."""
    for j in range(lf.shape[0]):
        if np.isnan(_lens_surface_z(lf, j, lf[j, Q.L_SD])):
            raise SceneError(
                f"lens.surfaces.{j}: semi-diameter {lf[j, Q.L_SD]:.3f} mm exceeds the extent of "
                f"the conicoid (curvature {lf[j, Q.L_CURV]:.6g}/mm, conic {lf[j, Q.L_CONIC]})"
            )
    for j in range(lf.shape[0] - 1):
        r = np.linspace(0.0, min(lf[j, Q.L_SD], lf[j + 1, Q.L_SD]), 64)
        z0, z1 = _lens_surface_z(lf, j, r), _lens_surface_z(lf, j + 1, r)
        bad = np.nonzero(z1 < z0 - 1e-9)[0]
        if bad.size:
            k = bad[0]
            raise SceneError(
                f"lens.surfaces.{j} and lens.surfaces.{j + 1} cross at r = {r[k]:.2f} mm "
                f"(z {z0[k]:.3f} > {z1[k]:.3f}): impossible geometry"
            )


def _check_leds(scene: Scene, centres: np.ndarray, lf: np.ndarray) -> None:
    rb = scene.leds.body_diameter_mm / 2
    for i, c in enumerate(centres):
        if c[2] - rb <= 0:
            raise SceneError(
                f"leds: LED {i} body (centre z = {c[2]:.2f} mm, radius {rb}) crosses the "
                "eye plane z = 0"
            )
        for j in range(i):
            if np.linalg.norm(c - centres[j]) < 2 * rb:
                raise SceneError(
                    f"leds: LED {i} and LED {j} bodies overlap (centres {c}, {centres[j]})"
                )
        # the body against the lens's first surface, within its clear aperture
        r_c = math.hypot(c[0], c[1])
        for r in np.linspace(max(0.0, r_c - rb), min(r_c + rb, lf[0, Q.L_SD]), 32):
            half = math.sqrt(max(0.0, rb * rb - (r - r_c) ** 2))
            if half > 0 and c[2] + half > _lens_surface_z(lf, 0, r):
                raise SceneError(
                    f"leds: LED {i} body at (Y = {r_c:.1f}, Z = {c[2]:.1f}) mm overlaps the "
                    f"imaging lens's first surface (semi-diameter {lf[0, Q.L_SD]:.1f} mm)"
                )


def compile_scene(scene: Scene) -> CompiledScene:
    """Turn a validated scene into the arrays the kernels read. Raises SceneError on geometry
    that cannot exist (crossing lens surfaces, LEDs inside the lens, a missing glass)."""
    wl = scene.wavelength_nm
    t = _Table()
    eye = scene.eye

    # --- imaging lens (sequential) -------------------------------------------------------------
    idx, _ = lens_indices(scene)
    stop = next(j for j, s in enumerate(scene.lens.surfaces) if s.stop)
    par = lens_paraxial(scene, idx)
    if not par.power > 0:
        raise SceneError(f"lens: the prescription has no positive power (EFL {par.efl:.3g} mm)")
    stop_sd = par.stop_semi_diameter_for_epd(stop, par.efl / scene.lens.f_number)
    check_focus(scene, par, stop, stop_sd)  # a real image of the eye plane, near the sensor
    semi, rim_fraction = _auto_semi_diameters(scene, idx, par, stop, stop_sd)
    lf, image_z = _lens_table(scene, idx, semi)
    _check_lens_geometry(lf)
    if rim_fraction < 0.9:
        raise SceneError(
            f"lens: only {rim_fraction:.0%} of the rim rays of the eye-plane field pass the lens "
            "(total internal reflection or a surface missed): check the prescription"
        )

    # --- eye (eye frame: z' = −z) --------------------------------------------------------------
    for j, s in enumerate(eye.surfaces):
        if math.isnan(float(sag(curvature(s.radius_mm), s.conic, s.semi_diameter_mm))):
            raise SceneError(
                f"eye.surfaces.{j}.semi_diameter_mm = {s.semi_diameter_mm} exceeds the extent of "
                f"the '{s.name}' conicoid (radius {s.radius_mm} mm, conic {s.conic})"
            )
    n_eye = eye_indices(eye, wl)
    r_l, z_l, z_c = limbus_geometry(eye)
    zprime = 0.0
    surf_z: list[float] = []
    for s in eye.surfaces:
        surf_z.append(zprime)
        zprime += s.thickness_mm
    gaze, centre_rot = gaze_rotation(eye)
    eye_rot = EYE_AXIS_ROT @ gaze.T  # world → eye frame, gaze included
    head = np.asarray(scene.head_offset_mm, dtype=float)

    def on_eye(z_eye: float) -> np.ndarray:
        """World point of the eye axis at depth z_eye behind the vertex, gaze and head offset
        included."""
        return head + centre_rot + gaze @ (np.array([0.0, 0.0, -z_eye]) - centre_rot)

    refracting = eye.surfaces[:-1]
    for j, s in enumerate(refracting):
        c = curvature(s.radius_mm)
        origin = on_eye(surf_z[j])
        anterior = j == 0
        t.add(
            s.name,
            G.SHAPE_CONIC,
            origin,
            eye_rot,
            _conic_bound(origin, eye_rot, c, s.conic, s.semi_diameter_mm),
            curv=c,
            conic=s.conic,
            clip_r=(0.0, s.semi_diameter_mm),
            action=G.ACT_REFRACT,
            n_a=n_eye[j],
            n_b=n_eye[j + 1],
            refl=eye.cornea_reflectance if anterior else 0.0,
            absorb=eye.cornea_absorptance if anterior else 0.0,
            fresnel=anterior and eye.cornea_reflection == "fresnel",
        )
    # iris: an annulus in the vertex plane of the surface that carries the pupil
    iris_o = on_eye(surf_z[eye.iris_surface])
    t.add(
        "iris",
        G.SHAPE_CONIC,
        iris_o,
        eye_rot,
        (iris_o, eye.iris_outer_diameter_mm / 2 * 1.000001),
        clip_r=(eye.pupil_diameter_mm / 2, eye.iris_outer_diameter_mm / 2),
        rho_a=eye.iris_reflectance,
    )
    # iris root: the iris's periphery, its outer edge to the eyeball wall in the same plane,
    # with the iris's reflectance; it closes the eye, so light enters only through the pupil
    try:
        r_root = iris_root_radius(eye)
    except ValueError as exc:
        raise GeometryError(str(exc)) from None
    if r_root > eye.iris_outer_diameter_mm / 2:
        t.add(
            "iris root",
            G.SHAPE_CONIC,
            iris_o,
            eye_rot,
            (iris_o, r_root * 1.000001),
            clip_r=(eye.iris_outer_diameter_mm / 2, r_root),
            rho_a=eye.iris_reflectance,
        )
    # retina: the prescription's last surface (a cap), seen from the vitreous (side A)
    ret = eye.surfaces[-1]
    c_r = curvature(ret.radius_mm)
    ret_o = on_eye(surf_z[-1])
    t.add(
        "retina",
        G.SHAPE_CONIC,
        ret_o,
        eye_rot,
        _conic_bound(ret_o, eye_rot, c_r, ret.conic, ret.semi_diameter_mm),
        curv=c_r,
        conic=ret.conic,
        clip_r=(0.0, ret.semi_diameter_mm),
        rho_a=eye.retina_reflectance,
    )
    # sclera: the eyeball sphere behind the limbus; its inside is the fundus
    centre = on_eye(z_c)
    t.add(
        "sclera",
        G.SHAPE_SPHERE,
        centre,
        eye_rot,
        (centre, eye.sclera_radius_mm * 1.000001),
        radius=eye.sclera_radius_mm,
        clip_z=(z_l - z_c, math.inf),
        rho_b=eye.sclera_reflectance,
        rho_a=eye.retina_reflectance,
        tally_a="fundus (inside of the sclera)",
    )

    # --- face -----------------------------------------------------------------------------------
    if scene.face.enabled:
        for tis in scene.face.tissues:
            rho = scene.face.skin_reflectance if tis.reflectance is None else tis.reflectance
            # a lid takes its share of the eye's vertical rotation, about the same centre
            turn, _ = gaze_rotation(eye, share_vertical=tis.follows_gaze, share_horizontal=0.0)
            rot = _frame(turn @ np.asarray(tis.axis, dtype=float))
            o = head + centre_rot + turn @ (np.asarray(tis.center_mm, dtype=float) - centre_rot)
            zlo, zhi = tis.clip_z_mm
            if tis.shape == "sphere":
                shape, bound = G.SHAPE_SPHERE, (o, tis.radius_mm * 1.000001)
            elif tis.shape == "cylinder":
                half = max(abs(zlo), abs(zhi))
                shape, bound = G.SHAPE_CYLINDER, (o, math.hypot(tis.radius_mm, half) * 1.000001)
            else:
                shape, bound = G.SHAPE_CONIC, (o, tis.clip_r_mm[1] * 1.000001)
            t.add(
                tis.name,
                shape,
                o,
                rot,
                bound,
                radius=tis.radius_mm,
                clip_r=tis.clip_r_mm,
                clip_z=(zlo, zhi),
                rho_b=rho,
            )

    # --- LEDs -------------------------------------------------------------------------------------
    centres, axes = led_poses(scene.leds)
    _check_leds(scene, centres, lf)
    rb = scene.leds.body_diameter_mm / 2
    for i, c in enumerate(centres):
        t.add(
            f"LED {i} body",
            G.SHAPE_SPHERE,
            c,
            _frame(axes[i]),
            (c, rb * 1.000001),
            radius=rb,
            tally_a="LED bodies",
            tally_b="LED bodies",
        )
    emit = centres + axes * rb * (1.0 + 1e-9)
    profile = scene.leds.profile
    try:
        if profile.kind == "cos_power":
            m = cos_power_exponent(profile.half_intensity_angle_deg)
            alpha_grid, cdf_grid, omega = cos_power_tables(m)
            intensity_grid = np.cos(alpha_grid) ** m
        else:
            shape = relative_intensity(profile)
            alpha_grid, cdf_grid, omega = profile_tables(shape)
            intensity_grid = np.asarray(shape(alpha_grid), dtype=float)
    except ValueError as exc:
        raise SceneError(str(exc)) from None

    # --- the lens entrance: hands rays to the sequential trace ----------------------------
    o = np.array([0.0, 0.0, lf[0, Q.L_Z]])
    t.add(
        "imaging lens",
        G.SHAPE_CONIC,
        o,
        np.eye(3),
        _conic_bound(o, np.eye(3), lf[0, Q.L_CURV], lf[0, Q.L_CONIC], lf[0, Q.L_SD]),
        curv=lf[0, Q.L_CURV],
        conic=lf[0, Q.L_CONIC],
        clip_r=(0.0, lf[0, Q.L_SD]),
        action=G.ACT_LENS,
        tally_a="lens mount (vignetted)",
        tally_b="lens mount (vignetted)",
    )

    cs = CompiledScene(
        scene=scene,
        sf=np.ascontiguousarray(np.stack(t.rows_f)),
        si=np.ascontiguousarray(np.stack(t.rows_i)),
        surface_names=t.names,
        lf=lf,
        lens_indices=idx,
        stop_index=stop,
        image_z=image_z,
        leds=np.ascontiguousarray(np.hstack([emit, axes])),
        led_centres=centres,
        alpha_grid=alpha_grid,
        cdf_grid=cdf_grid,
        intensity_grid=np.ascontiguousarray(intensity_grid),
        omega_eff=omega,
        sensor=np.array(
            [scene.sensor.width_mm, scene.sensor.height_mm, scene.sensor.cols, scene.sensor.rows],
            float,
        ),
        plane=np.array(
            [
                scene.eye_plane.width_mm,
                scene.eye_plane.height_mm,
                scene.eye_plane.cols,
                scene.eye_plane.rows,
            ],
            float,
        ),
        tallies=t.tallies,
    )
    return cs
