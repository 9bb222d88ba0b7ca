"""Scene → packed arrays for the kernels: the one place that knows both the scene and the kernels.

The compiled scene holds, at the scene's wavelength, the named tables of
:mod:`eyelume.kernels.tables`, each built once here by one function per scene part:

* ``surfaces`` (:class:`SurfaceTable` ``sf``, ``si``): the non-sequential surfaces (eye, iris,
  sclera, retina, face tissues, LED bodies, the imaging lens's entrance and the camera's body),
  columns in :mod:`eyelume.kernels.geometry` — :func:`_add_eye`, :func:`_add_face`,
  :func:`_add_led_bodies`, :func:`_add_lens_entrance`, :func:`_add_camera_body`;
* ``lens`` (:class:`LensTable`): the sequential lens table, columns in
  :mod:`eyelume.kernels.sequential` — :func:`_compile_lens`;
* ``led`` (:class:`LedTable`): the LED emission points, axes, and each LED's I₀ and
  angular-profile tables —
  :func:`_led_table`;
* ``picture``, ``eye_plane`` (:class:`~eyelume.kernels.bins.PlaneGrid`): the sensor's pixels and
  the eye-plane receiver's bins — :func:`_grids`;
* ``camera`` (:class:`CameraTables`): the lens traced backwards, its pupils and the aim table of
  the camera-side estimator — :func:`_camera_tables`;
* Ω_eff per LED (its power over I₀) and the names of the surfaces and of the ledger's entries.
"""

from __future__ import annotations

import heapq
import math
import warnings
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from eyelume.errors import EyelumeWarning, GeometryError, GlassError, InputFileError, SceneError
from eyelume.kernels import geometry as G
from eyelume.kernels import interact as I
from eyelume.kernels import sequential as Q
from eyelume.kernels.bins import PlaneGrid, eye_plane_grid, picture_grid
from eyelume.kernels.sampling import cos_power_tables, led_direction, profile_tables
from eyelume.kernels.tables import (
    A_AX,
    A_AZ,
    A_KIND,
    A_P,
    A_R,
    A_X,
    A_Z,
    AIM_IMAGE,
    CHAIN_COLS,
    CHAIN_STEPS,
    G_AX,
    G_AZ,
    G_COS,
    G_P,
    GLINT_AIM_COLS,
    INDIRECT_COLS,
    N_AIM,
    REFLECT,
    TRANSMIT,
    TRANSMIT_A,
    CameraTables,
    LedTable,
    LensTable,
    SceneTables,
    SurfaceTable,
)
from eyelume.scene.elements import (
    crosses_surfaces,
    inside_solid,
    near_element,
    outline_points,
    read_reflectance_table,
    vertex_z_mm,
)
from eyelume.scene.eye import (
    _rot_x,
    _rot_y,
    anterior_cornea_pose,
    anterior_quadric,
    check_eye_geometry,
    eye_indices,
    glint_reflectance,
    iris_root_radius,
    limbus_geometry,
    meridian_sag,
    with_contact_lens,
)
from eyelume.scene.focus import check_focus
from eyelume.scene.glass import Glass, load_catalog
from eyelume.scene.model import Coating, Element, LedProfile, Scene
from eyelume.scene.optics import ParaxialSystem, curvature, sag
from eyelume.scene.pose import MIRROR_X as _MIRROR_X
from eyelume.scene.pose import Frame, as_world, camera_frame, led_world_poses
from eyelume.scene.sources import (
    LedBody,
    bodies_overlap,
    body_points,
    body_sample_step,
    body_support,
    cos_power_exponent,
    inside_body,
    led_bodies,
    relative_intensity,
)

__all__ = [
    "CompiledScene",
    "FirstOrder",
    "WavelengthGroup",
    "compile_scene",
    "single_wavelength",
    "wavelength_groups",
    "SunSource",
    "SUN_DISTANCE_MM",
    "SUN_FIELD_RADIUS_MM",
    "scene_frame",
    "gaze_rotation",
    "eye_point",
    "eye_direction",
    "eye_plane_origin",
    "element_label",
    "element_pose",
    "as_world",
    "camera_pose",
    "led_world_poses",
    "lens_paraxial",
    "lens_indices",
]

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


def gaze_rotation(eye, share_vertical: float = 1.0, share_horizontal: float = 1.0):
    """(R, C): the eye's gaze as a rotation R (primary-gaze world → turned world) about the
    centre of rotation C (world mm): a primary-gaze point p moves to C + R (p − C).

    Vertical first, about x (positive gaze looks up: the optical axis +z tilts toward +y), then
    horizontal, about y (positive looks toward +x). ``share_*`` scale the angles (an eyelid's
    lid–eye coordination)."""
    v = math.radians(eye.gaze_vertical_deg) * share_vertical
    h = math.radians(eye.gaze_horizontal_deg) * share_horizontal
    return _rot_y(h) @ _rot_x(-v), np.array([0.0, 0.0, -eye.rotation_centre_mm])


def eye_point(
    scene: Scene, point, share_vertical: float = 1.0, share_horizontal: float = 1.0
) -> np.ndarray:
    """A point of the eye or its face (mm, written relative to the eye's nominal vertex in
    primary gaze, as the scene file writes it) in the world frame: turned with the gaze about
    the centre of rotation C, moved by the eye's pose V (:class:`EyePose`: relief, lateral
    offset) and the head offset h, then mirrored for a left eye (:func:`as_world`):
    M (V + h + C + R (p − C)) (:func:`gaze_rotation`; ``share_*`` as there)."""
    gaze, c0 = gaze_rotation(scene.eye, share_vertical, share_horizontal)
    head = np.asarray(scene.eye_pose.vertex_mm, dtype=float) + np.asarray(
        scene.head_offset_mm, dtype=float
    )
    return as_world(scene, head + c0 + gaze @ (np.asarray(point, dtype=float) - c0))


def eye_direction(scene: Scene, v) -> np.ndarray:
    """A direction of the eye in primary gaze (eye-relative, as written) in the world frame:
    turned with the gaze and mirrored for a left eye, M R v."""
    return as_world(scene, gaze_rotation(scene.eye)[0] @ np.asarray(v, dtype=float))


def eye_plane_origin(scene: Scene) -> np.ndarray:
    """The eye-plane receiver's centre in the world frame (mm): the eye's nominal corneal
    vertex (its pose, no gaze, no slip), M V."""
    return as_world(scene, scene.eye_pose.vertex_mm)


def camera_pose(scene: Scene) -> tuple[np.ndarray, np.ndarray, float]:
    """The camera's (position mm, viewing direction, roll °) in the world frame: the file's
    pose (:meth:`eyelume.scene.model.Camera.pose`), mirrored for a left eye (a mirror turns the
    roll the other way). Raises SceneError when the view has no direction."""
    try:
        pos, view = scene.camera.pose(scene.object_distance_mm)
    except ValueError as exc:
        raise SceneError(f"camera: {exc}") from None
    roll = scene.camera.roll_deg
    if scene.eye_pose.which == "left":
        roll = -roll
    return as_world(scene, pos), as_world(scene, view), roll


@dataclass(frozen=True)
class FirstOrder:
    """The camera's first-order optics in the camera frame (mm; z along the lens axis, the
    object plane at z = 0): ``efl``, ``f_number`` (EFL / entrance-pupil diameter), the
    ``object_distance`` (object plane → lens), entrance pupil (``entrance_pupil_z``, its radius
    ``entrance_pupil_radius``), exit pupil (``exit_pupil_z``, ``exit_pupil_magnification``), the
    sensor's ``image_z``, ``magnification`` (signed, object plane → image) and the image-side
    ``working_f_number`` N_w = 1 / (2 n′ |u′|) of the axial marginal ray from the object plane
    (an ideal lens: N (1 + |m|), exactly, its pupils being the lens). A prescription's come from
    its paraxial trace; an ideal lens's are exact (the pupils are the lens)."""

    efl: float
    f_number: float
    object_distance: float
    entrance_pupil_z: float
    entrance_pupil_radius: float
    exit_pupil_z: float
    exit_pupil_magnification: float
    image_z: float
    magnification: float
    working_f_number: float


@dataclass
class CompiledScene:
    """A scene compiled for the kernels (see module docstring): ``tables`` is what a forward
    trace reads, ``camera`` what the camera-side estimator adds."""

    scene: Scene
    tables: SceneTables
    camera: CameraTables
    surface_names: list[str]
    lens_indices: list[float]
    stop_index: int
    led_centres: np.ndarray  # (N, 3) LED body centres, camera frame mm
    omega_eff: np.ndarray  # (N,) sr: Φₖ = I₀ₖ · omega_eff[k]
    tallies: list[str]
    frame: Frame  # world → camera frame (eyelume.scene.pose); every table is in the camera frame
    first_order: FirstOrder  # the camera's first-order optics (camera frame)
    # a wavelength group's compile: the scene index of each LED table row (None: all, in order)
    led_ids: tuple[int, ...] | None = None
    # the sunlight's compile (compile_scene(..., sun=)): its one source is the sun, no LED emits
    sun: SunSource | None = None
    # (n_surfaces,) int64: the camera's view at each element surface on its branch through the
    # elements, 1 reflected, 0 refracted, −1 off it (the stronger part); _view_through_elements
    view_branch: np.ndarray | None = None

    @property
    def led_indices(self) -> list[int]:
        """The scene index of every row of the LED table (all LEDs, or a group's)."""
        n = self.tables.leds.points.shape[0]
        return list(range(n)) if self.led_ids is None else list(self.led_ids)

    @property
    def surfaces(self) -> SurfaceTable:
        return self.tables.surfaces

    @property
    def lens(self) -> LensTable:
        return self.tables.lens

    @property
    def led(self) -> LedTable:
        return self.tables.leds

    @property
    def picture(self) -> PlaneGrid:
        """The picture's pixels on the sensor (:func:`eyelume.kernels.bins.picture_grid`)."""
        return self.tables.picture

    @property
    def eye_plane(self) -> PlaneGrid:
        """The eye-plane receiver's bins (:func:`eyelume.kernels.bins.eye_plane_grid`)."""
        return self.tables.eye_plane

    @property
    def sf(self) -> np.ndarray:
        return self.tables.surfaces.sf

    @property
    def si(self) -> np.ndarray:
        return self.tables.surfaces.si

    @property
    def lf(self) -> np.ndarray:
        return self.tables.lens.lf

    @property
    def image_z(self) -> float:
        return self.tables.lens.image_z

    @property
    def led_powers_w(self) -> np.ndarray:
        """Radiant power of every LED (N,) (W): Φₖ = I₀ₖ ∫ Iₖ/I₀ₖ dΩ."""
        return self.tables.leds.i0 * self.omega_eff

    @property
    def emitted_w(self) -> float:
        """Radiant power of all LEDs (W)."""
        p = self.led_powers_w
        if self.tables.leds.equal_power:
            return float(p[0]) * p.shape[0]  # the same floats as before LEDs could differ
        return float(p.sum())


@dataclass
class SurfaceSpec:
    """One non-sequential surface before packing into a row of the surface table (columns in
    :mod:`eyelume.kernels.geometry`): shape, placement (``origin``, world → local ``rot``), its
    bounding sphere (centre, radius), conic data, clips, what it does to light, and the ledger
    entries of its two sides (default: its name)."""

    name: str
    shape: int
    origin: np.ndarray
    rot: np.ndarray
    bound: tuple[np.ndarray, float]
    curv: float = 0.0
    conic: float = 0.0
    radius: float = 0.0
    clip_r: tuple[float, float] = (0.0, math.inf)
    clip_z: tuple[float, float] = (-math.inf, math.inf)
    action: int = G.ACT_OPAQUE
    n_a: float = 1.0
    n_b: float = 1.0
    refl: float = 0.0
    absorb: float = 0.0
    fresnel: bool = False
    rho_a: float = 0.0
    rho_b: float = 0.0
    tally_a: str = ""
    tally_b: str = ""
    r_table: tuple[np.ndarray, np.ndarray] | None = None  # R(θ): angles (rad), R
    lashes: tuple[int, float, float] | None = None  # a fringe's count, pitch (rad), half-width

    def float_row(self) -> np.ndarray:
        f = np.zeros(G.N_FLOAT if self.r_table is None else I.N_FLOAT_WITH_TABLE)
        if self.lashes is not None:
            f = np.zeros(G.N_FLOAT_WITH_LASHES)
            f[G.LASH_COUNT], f[G.LASH_PITCH], f[G.LASH_HALF_WIDTH] = self.lashes
        if self.r_table is not None:
            angles, values = self.r_table
            f[I.R_TABLE_COUNT] = len(angles)
            f[I.R_TABLE_ANGLE : I.R_TABLE_ANGLE + len(angles)] = angles
            f[I.R_TABLE_VALUE : I.R_TABLE_VALUE + len(values)] = values
        f[G.OX : G.OZ + 1] = self.origin
        f[G.R00 : G.R22 + 1] = np.asarray(self.rot, dtype=float).ravel()
        f[G.CURV], f[G.CONIC], f[G.RADIUS] = self.curv, self.conic, self.radius
        f[G.RMIN2], f[G.RMAX2] = self.clip_r[0] ** 2, self.clip_r[1] ** 2
        f[G.ZLO], f[G.ZHI] = self.clip_z
        f[G.BX : G.BZ + 1] = self.bound[0]
        f[G.BR] = self.bound[1]
        f[G.N_A], f[G.N_B] = self.n_a, self.n_b
        f[G.REFL], f[G.ABSORB] = self.refl, self.absorb
        f[G.RHO_A], f[G.RHO_B] = self.rho_a, self.rho_b
        return f

    def int_row(self, tally_a: int, tally_b: int) -> np.ndarray:
        """The int row: shape, action, Fresnel flag and the ledger indices of its two sides."""
        i = np.zeros(G.N_INT, dtype=np.int64)
        code = I.R_TABLE if self.r_table is not None else int(self.fresnel)
        i[G.SHAPE], i[G.ACTION], i[G.FRESNEL] = self.shape, self.action, code
        i[G.TALLY_A], i[G.TALLY_B] = tally_a, tally_b
        return i


class _Table:
    """Collects non-sequential surfaces and ledger names."""

    def __init__(self, frame: Frame) -> None:
        self.frame = frame
        self.rows_f: list[np.ndarray] = []
        self.rows_i: list[np.ndarray] = []
        self.names: list[str] = []
        self.tallies: list[str] = list(FIXED_TALLIES)

    def tally(self, name: str) -> int:
        if name not in self.tallies:
            self.tallies.append(name)
        return self.tallies.index(name)

    def add(self, name: str, shape: int, origin, rot, bound, *, world=True, **options) -> None:
        """Append a surface: the arguments of :class:`SurfaceSpec`, placed in the world frame
        (``world``: moved into the camera frame here) or already in the camera frame."""
        if world and not self.frame.is_identity:
            f = self.frame
            origin = f.point(origin)
            rot = np.asarray(rot, dtype=float) @ f.rotation.T  # local = rot Rᵀ (p_c − o_c)
            bound = (f.point(bound[0]), bound[1])
        spec = SurfaceSpec(name, shape, origin, rot, bound, **options)
        tally_a = self.tally(spec.tally_a or name)
        tally_b = self.tally(spec.tally_b or name)
        self.rows_f.append(spec.float_row())
        self.rows_i.append(spec.int_row(tally_a, tally_b))
        self.names.append(name)

    def group(self, first: int, sphere: tuple[np.ndarray, float], *, world: bool = True) -> None:
        """Make the rows from ``first`` to the last one added a group (``G.GROUP_END``) that
        the searches skip at once when a ray misses ``sphere`` (centre, radius; camera frame
        when ``world`` is False, else world): it must hold every member's surface — the
        caller's body is what it knows (a member's bounding sphere may poke out of the body's:
        a disk's is a sphere of its radius). Bit for bit the same hits: a ray that misses the
        sphere misses every member. A group of one row is left alone."""
        end = len(self.rows_f)
        if end - first < 2:
            return
        centre, radius = sphere
        if world and not self.frame.is_identity:
            centre = self.frame.point(centre)
        head = self.rows_f[first]
        head[G.GBX : G.GBZ + 1], head[G.GBR] = centre, radius
        self.rows_i[first][G.GROUP_END] = end


def _stack_rows(rows: list[np.ndarray]) -> np.ndarray:
    """The float rows as one table: the geometry's N_FLOAT columns, or N_FLOAT_WITH_TABLE (the
    other rows padded with zeros) when a surface carries an R(θ) table
    (:mod:`eyelume.kernels.interact`)."""
    width = max(len(r) for r in rows)
    if all(len(r) == width for r in rows):
        return np.stack(rows)
    out = np.zeros((len(rows), width))
    for k, r in enumerate(rows):
        out[k, : len(r)] = r
    return out


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
        g = used[s.glass]
        indices.append(g.index(scene.wavelength_nm))
        if g.in_range(scene.wavelength_nm) is False and j == _first_use(lens.surfaces, s.glass):
            lo, hi = g.wavelength_range_nm  # type: ignore[misc]
            warnings.warn(
                f"lens.surfaces.{j}.glass = {s.glass!r}: {scene.wavelength_nm:g} nm lies outside "
                f"its catalog's stated range {lo:g}–{hi:g} nm: its index "
                f"{indices[-1]:.5f} is extrapolated by its dispersion formula",
                EyelumeWarning,
                stacklevel=2,
            )
    return indices, used


def _first_use(surfaces, glass: str) -> int:
    """The first surface made of ``glass`` (a glass used twice warns once)."""
    return next(j for j, s in enumerate(surfaces) if s.glass == glass)


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


def _field_in_focus(scene: Scene, par: ParaxialSystem) -> tuple[float, float]:
    """Width and height (mm) of the field the lens must pass on the plane in focus: the
    eye-plane receiver's and the sensor's (its size / |paraxial magnification|), whichever is
    larger in each direction."""
    m = abs(par.magnification(scene.object_distance_mm))
    sw, sh = scene.sensor.field_mm
    return max(scene.eye_plane.width_mm, sw / m), max(scene.eye_plane.height_mm, sh / m)


def _auto_semi_diameters(
    scene: Scene, indices: list[float], par: ParaxialSystem, stop: int, stop_sd: float
) -> tuple[list[float], float]:
    """Clear semi-diameters from a real-ray trace of the full field in focus.

    For a 9 × 7 grid of object points over the field (:func:`_field_in_focus`: the eye-plane
    receiver's or the sensor's, whichever is larger; corners included) the rays through 72
    points of the stop's rim are found by real-ray aiming; the largest height they reach at each
    surface + 1 % (a mechanical clear aperture) is its semi-diameter, so the stop alone limits
    every bundle from the eye area, as the paper's lens was designed. Also returns the fraction
    of rim rays that got through.
    """
    from eyelume.kernels.sequential import rim_ray_heights

    n = len(scene.lens.surfaces)
    lf, _ = _lens_table(scene, indices, [math.inf] * n)
    w, h = _field_in_focus(scene, par)
    xs = np.linspace(-w / 2, w / 2, 9)
    ys = np.linspace(-h / 2, h / 2, 7)
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


#: Rays of the axial fan :func:`real_best_focus` traces (over the first surface's aperture).
_FOCUS_FAN = 400


def real_best_focus(lf: np.ndarray) -> tuple[float, float] | None:
    """(s_b, ρ_rms): the real-ray best focus of the eye plane's axial point, in mm after the
    lens's last vertex, and the RMS spot radius (mm) there; None when no ray passes.

    A meridional fan from the axial point (world origin) aimed at ``_FOCUS_FAN`` heights a
    over the first surface's clear aperture is traced through the prescription ``lf`` (clear
    apertures and stop included) by the production per-ray tracer
    (:func:`eyelume.kernels.sequential.trace_lens`). After the last surface a ray is the line
    y(z) = y_r + (z − z_r) m, m = dy/dz, referred to the last vertex z_r; weighting each ray by
    a (the area of its ring of the rotationally symmetric pupil) the mean square spot radius
    Σ w y(z)² / Σ w is least at

        z_b = z_r − Σ w y_r m / Σ w m²,

    so s_b = z_b − z_r, with the RMS radius ρ_rms = √(Σ w y(z_b)² / Σ w).
    """
    from eyelume.kernels.sequential import LENS_PASSED, trace_lens

    z1, reach = lf[0, Q.L_Z], lf[0, Q.L_SD]
    path = np.zeros((1, 3))
    rays = []
    for a in np.linspace(0.0, reach, _FOCUS_FAN + 1)[1:]:
        n = math.hypot(a, z1)
        st, _, y, z, _, dy, dz, _, _ = trace_lens(lf, 0.0, 0.0, 0.0, 0.0, a / n, z1 / n, path,
                                                  0, False)  # fmt: skip
        if st == LENS_PASSED and dz > 0:
            rays.append((y, z, dy / dz, a))
    if not rays:
        return None
    y, z, m, w = np.array(rays).T
    z_r = lf[-1, Q.L_Z]
    y_r = y + (z_r - z) * m
    den = float(np.sum(w * m * m))
    s_b = -float(np.sum(w * y_r * m)) / den if den > 0 else 0.0
    rms = math.sqrt(float(np.sum(w * (y_r + s_b * m) ** 2) / np.sum(w)))
    return s_b, rms


def _led_field(scene: Scene, i: int) -> str:
    """The scene field that placed LED ``i``, for an error line: ``leds.positions_mm[i]`` (one
    by one) or the ring's fields (``leds.azimuths_deg[i]`` or its share of ``count``, with
    ``height_mm``, ``distance_mm`` and ``pitch_deg``)."""
    leds = scene.leds
    if leds.positions_mm is not None:
        return f"leds.positions_mm[{i}]"
    az = f"leds.azimuths_deg[{i}]" if leds.azimuths_deg is not None else f"LED {i} of leds.count"
    return f"the ring's {az}, leds.height_mm, leds.distance_mm, leds.pitch_deg"


def _check_leds(
    scene: Scene, centres: np.ndarray, lf: np.ndarray, frame: Frame, axes: np.ndarray
) -> None:
    """LED bodies (world ``centres``, unit ``axes``) in front of the eye, apart, and clear of
    the lens. A body's reach toward the eye plane is exact (:func:`body_support`); a cylinder
    against the lens and another cylinder is tested on its sampled surface."""
    bodies = led_bodies(scene.leds, centres, axes)
    plane_z = float(eye_plane_origin(scene)[2])
    down = np.array([0.0, 0.0, -1.0])
    for i, (c, body) in enumerate(zip(centres, bodies, strict=True)):
        rb = body.radius
        reach = body_support(body.shape, body.axis, rb, body.length, down)
        if c[2] - reach <= plane_z:
            where = "lies behind" if c[2] + reach <= plane_z else "crosses"
            raise SceneError(
                f"leds: LED {i} ({_led_field(scene, i)}) body (centre z = {c[2]:.2f} mm, "
                f"{body.words()}) {where} the "
                f"eye plane z = {plane_z + 0.0:g} (the eye's side): the LEDs must sit in front "
                "of the eye"
            )
        for j in range(i):
            if bodies_overlap(body, bodies[j]):
                sizes = (
                    f"radii {rb:g} and {bodies[j].radius:g} mm"
                    if body.shape == bodies[j].shape == "sphere"
                    else f"{body.words()} and {bodies[j].words()}"
                )
                raise SceneError(
                    f"leds: LED {i} and LED {j} bodies overlap ({_led_field(scene, i)} and "
                    f"{_led_field(scene, j)}; centres "
                    f"{np.round(c, 3).tolist()} and {np.round(centres[j], 3).tolist()} mm, "
                    f"{np.linalg.norm(c - centres[j]):.3g} mm apart, {sizes})"
                )
        # the body against the lens's first surface, within its clear aperture (camera frame)
        cc = frame.point(c)
        r_c = math.hypot(cc[0], cc[1])
        if body.shape == "sphere":
            if r_c - rb >= lf[0, Q.L_SD]:
                continue  # wholly outside the lens's clear aperture
            cuts = False
            for r in np.linspace(max(0.0, r_c - rb), min(r_c + rb, lf[0, Q.L_SD]), 32):
                half = math.sqrt(max(0.0, rb * rb - (r - r_c) ** 2))
                if half > 0 and cc[2] + half > _lens_surface_z(lf, 0, r):
                    cuts = True
                    break
        else:
            pts = frame.point(body.points())
            r = np.hypot(pts[:, 0], pts[:, 1])
            near = r < lf[0, Q.L_SD]
            cuts = bool(np.any(pts[near, 2] > _lens_surface_z(lf, 0, r[near])))
        if cuts:
            raise SceneError(
                f"leds: LED {i} ({_led_field(scene, i)}) body (world centre "
                f"{np.round(c, 1).tolist()} mm, {r_c:.1f} mm from the camera's axis) overlaps "
                f"the imaging lens's first surface (semi-diameter {lf[0, Q.L_SD]:.1f} mm)"
            )


def _check_leds_in_head(
    scene: Scene,
    centres: np.ndarray,
    rb: float | None = None,
    what: str = "leds: LED",
    axes: np.ndarray | None = None,
) -> None:
    """No LED body (world ``centres``, unit ``axes``; or, with ``what``, the camera's lens:
    radius ``rb``) inside the eyeball (with the cornea's bulge) or inside a face tissue's solid
    (a sphere or cylinder within its clip ranges, or behind a disk within its ring): a sphere
    by its centre's distance, a cylinder by its sampled surface
    (:func:`~eyelume.scene.sources.body_points`)."""
    if rb is None:
        assert axes is not None
        bodies = led_bodies(scene.leds, centres, axes)
    else:
        bodies = [LedBody("sphere", c, np.array([0.0, 0.0, 1.0]), rb, 2 * rb) for c in centres]
    for i, (c, body) in enumerate(zip(centres, bodies, strict=True)):
        rb = body.radius
        if body.shape == "sphere":
            where = _in_head(scene, c, rb)
        else:
            where = _in_head(scene, body.points(), 0.0)
        at = np.round(c, 2).tolist()
        if what == "camera":  # one lens: the field that placed it
            label, size = f"camera.position_mm = {at} (the lens)", ""
        else:
            field = f" ({_led_field(scene, i)})" if what == "leds: LED" else ""
            label, size = f"{what} {i}{field} (world centre {at} mm", f", {body.words()})"
        if where == "the eye":
            raise SceneError(f"{label}{size} is inside the eye")
        if where is not None:
            raise SceneError(f"{label}{')' if size else ''} is inside {where}")


def _in_head(scene: Scene, c: np.ndarray, rb: float) -> str | None:
    """What of the head a sphere of radius ``rb`` about the world point ``c`` (3,) — or about
    any of the points ``c`` (M, 3) — reaches into: ``"the eye"`` (the eyeball, with the
    cornea's bulge), ``"the face: face.tissues 'name'"`` (a tissue's solid: a sphere or
    cylinder within its clip ranges, or behind a disk within its ring), or None."""
    eye = scene.eye
    _, _, z_c = limbus_geometry(eye)
    eyeball = eye_point(scene, [0.0, 0.0, -z_c])
    vertex = eye_point(scene, np.zeros(3))
    axis = eye_direction(scene, [0.0, 0.0, 1.0])
    pts = np.asarray(c, dtype=float).reshape(-1, 3)
    d = pts - eyeball
    along = d @ axis
    # the eyeball sphere, and the cornea standing proud of it up to the vertex
    in_eye = (np.linalg.norm(d, axis=1) < eye.sclera_radius_mm + rb) | (
        ((pts - vertex) @ axis < rb)
        & (
            np.linalg.norm(d - along[:, None] * axis, axis=1)
            < eye.surfaces[0].semi_diameter_mm + rb
        )
        & (along > 0)
    )
    if in_eye.any():
        return "the eye"
    if not scene.face.enabled:
        return None
    for tis in scene.face.tissues:
        o = eye_point(scene, tis.center_mm, share_vertical=0.0, share_horizontal=0.0)
        local = (pts - o) @ _frame(as_world(scene, tis.axis)).T
        r = np.hypot(local[:, 0], local[:, 1])
        in_ring = (tis.clip_r_mm[0] <= r) & (r <= tis.clip_r_mm[1])
        in_clip = (tis.clip_z_mm[0] <= local[:, 2]) & (local[:, 2] <= tis.clip_z_mm[1]) & in_ring
        if tis.shape == "sphere":
            inside = in_clip & (np.linalg.norm(pts - o, axis=1) < tis.radius_mm + rb)
        elif tis.shape == "cylinder":
            inside = in_clip & (r < tis.radius_mm + rb)
        else:
            inside = in_ring & (local[:, 2] < rb)
        if inside.any():
            return f"the face: face.tissues '{tis.name}'"
    return None


class LedAimWarning(EyelumeWarning):
    """An LED whose cone, per its profile, misses the eye: it lights no part of the eye."""


def _check_leds_light_the_eye(
    scene: Scene, centres: np.ndarray, axes: np.ndarray, led: LedTable
) -> None:
    """Warn (:class:`LedAimWarning`) for each LED whose cone misses the eye entirely; refuse
    (GeometryError) when every LED's does: the render would be dark and say nothing — unless
    the scene has elements (a mirror may bring an LED's light to the eye).

    LED k's cone is the directions within αₖ,max of its axis, αₖ,max the largest angle at which
    its profile (the compiled grid ``intensity_grid[k]``, the one I(α)) is above 0: 90° for
    cosᵐ, where a table reaches 0 for a table. The eye is the sphere about the eyeball's centre
    c (gaze and head offset applied) through its farthest point, R = max(sclera radius, the
    corneal vertex's distance from c). The cone misses it when the angle γ between the axis
    and the direction to c, less the sphere's angular radius asin(R / |c − p|), is ≥ αₖ,max
    (p the emission point). World frame."""
    eye = scene.eye
    _, _, z_c = limbus_geometry(eye)
    eyeball = eye_point(scene, [0.0, 0.0, -z_c])
    radius = max(
        eye.sclera_radius_mm, float(np.linalg.norm(eye_point(scene, np.zeros(3)) - eyeball))
    )
    emit = centres + axes * np.asarray(scene.leds.emission_offsets_mm())[:, None]
    step = led.alpha_grid[1] - led.alpha_grid[0]
    misses = []
    for k in range(len(emit)):
        lit = np.flatnonzero(led.intensity_grid[k] > 0.0)
        a_max = min(float(led.alpha_grid[lit[-1]]) + step, math.pi / 2) if lit.size else 0.0
        v = eyeball - emit[k]
        dist = float(np.linalg.norm(v))
        gamma = math.acos(max(-1.0, min(1.0, float(v @ axes[k]) / dist)))
        off = gamma - math.asin(min(1.0, radius / dist))
        if off >= a_max:
            misses.append(
                f"LED {k} (world {np.round(centres[k], 2).tolist()} mm) aims "
                f"{math.degrees(gamma):.1f} deg away from the eye's centre and its profile "
                f"emits only to {math.degrees(a_max):.1f} deg"
            )
    if misses and len(misses) == len(emit) and not scene.elements:
        raise GeometryError(
            f"every LED's cone misses the eye, no light would reach it ({misses[0]}): aim the "
            "LEDs at the eye (leds.aim_at_mm, leds.directions or leds.pitch_deg)",
            field="leds",
        )
    for why in misses:
        warnings.warn(f"leds: {why}: its cone misses the eye", LedAimWarning, stacklevel=3)


def _check_view(
    scene: Scene, frame: Frame, first: FirstOrder, picture: PlaneGrid, straight: bool = True
) -> None:
    """The camera's lens is not inside the head, and (``straight``: its line of sight is not
    folded by a mirror, :func:`_view_through_elements`) it sees the eye: its corneal vertex
    (gaze and head offset applied) lies in front of the entrance pupil and is imaged inside the
    picture. Raises SceneError."""
    p = frame.point(eye_point(scene, np.zeros(3)))
    ep = first.entrance_pupil_z
    pos, view, _ = camera_pose(scene)
    _check_leds_in_head(scene, np.array([pos], dtype=float), rb=0.0, what="camera")
    plane_z = float(eye_plane_origin(scene)[2])
    if pos[2] <= plane_z:
        # Behind the eye, in the head: the eyeball and the face hide the cornea (a camera at
        # z = -30 mm on the eye's axis rendered a black picture without a word).
        raise SceneError(
            f"camera.position_mm = {np.round(np.asarray(pos, float), 2).tolist()} lies behind "
            f"the eye plane z = {plane_z + 0.0:g} mm (the eye's side, in the head): the camera "
            "sees no eye; it must sit in front of the eye"
        )
    if not straight:
        return
    unit = np.asarray(view, dtype=float) / np.linalg.norm(view)
    cam = scene.camera
    if cam.direction is not None:
        field = f"camera.direction = {list(cam.direction)}"
    elif cam.look_at_mm is not None:
        field = f"camera.look_at_mm = {list(cam.look_at_mm)}"
    else:
        field = "camera.look_at_mm and camera.direction unset: looking along -z"
    placed = (
        f"camera.position_mm = {list(cam.position_mm)}"
        if cam.position_mm is not None
        else "camera.position_mm unset"
    )
    where = (
        f"camera at {[round(float(x), 3) for x in pos]} mm looking along "
        f"{np.round(unit, 3).tolist()}; {placed}, {field}"
    )
    # behind the lens's first vertex (camera-frame z = L) or its entrance pupil (which for a
    # long lens can lie far behind the first vertex)
    if p[2] >= min(ep, scene.object_distance_mm) - 1e-9:
        raise SceneError(f"camera: sees no eye: the corneal vertex is behind the {where}")
    # where the vertex's line to the entrance pupil meets the plane in focus, in picture units
    xy = p[:2] * ep / (ep - p[2])
    half_w = picture.width_mm / 2 / abs(first.magnification)
    half_h = picture.height_mm / 2 / abs(first.magnification)
    if abs(xy[0]) > half_w or abs(xy[1]) > half_h:
        raise SceneError(
            f"camera: sees no eye: the corneal vertex is imaged at ({xy[0]:.1f}, {xy[1]:.1f}) "
            f"mm on the plane in focus, outside the ±{half_w:.1f} × ±{half_h:.1f} mm the "
            f"picture covers ({where})"
        )


_VIEW_EVENTS = 16  # element surfaces the line of sight may cross or be folded by along a branch
#: A branch of the camera's line of sight through the optical elements that carries less than
#: this share of it (the product of the R and T it takes) is no view of the eye
#: (:func:`_view_through_elements`): an image 10⁻³ as bright as the unobstructed one is lost
#: under the LEDs' direct light and the noise (ASSUMPTION: three decades, a 10-bit camera's
#: range).
VIEW_MIN_SHARE = 1e-3
_VIEW_NODES = 256  # element-surface events the branch tree may follow in all


class ViewWarning(EyelumeWarning):
    """The camera sees the eye through an element by its weak side of a coating's cut-off
    (a hot mirror whose cut-off is on the wrong side of the wavelength): a dim eye image."""


class _ViewStep(NamedTuple):
    row: int  # the element surface's row
    reflected: bool
    share: float  # the R or T (1 on total internal reflection) the branch takes there


class _ViewLeaf(NamedTuple):
    steps: tuple[_ViewStep, ...]
    weight: float  # the product of the steps' shares
    end: int  # the surface row the branch ends on (−1: nothing, it leaves the scene)
    reach: float  # the product of the shares of what leaves each surface (_view_branches)


def _is_optical(names: list[str], s: int) -> bool:
    """Whether row ``s`` is an element's optical surface (not its absorbing edge)."""
    return s >= 0 and names[s].startswith("element ") and not names[s].endswith(" edge")


def _view_branches(sf, si, names: list[str], p: np.ndarray, d: np.ndarray) -> list[_ViewLeaf]:
    """The ray (p, d) followed through the optical elements along both branches at each
    element surface — reflected (× R, × 1 on total internal reflection) and refracted (× T =
    1 − R − A) as :func:`eyelume.kernels.interact.interface_at` gives them — up to
    :data:`_VIEW_EVENTS` surfaces a branch and :data:`_VIEW_NODES` in all, those of the
    largest ``reach`` first: the product over the steps of each branch's share of what leaves
    the surface, R / (R + T) or T / (R + T) — what a surface absorbs does not count against
    where the line of sight goes (an opaque plate, R = T = 0, hides the eye, which the truth
    reports, but sends the view nowhere else: its stronger rule, refracted, reach 1); each
    branch ends on the first thing it meets that is not an element's optical surface. Returns
    the branches (zero-weight ones too, so that a refusal can say which branch would have
    seen the eye)."""
    heap = [(-1.0, 0, 1.0, p, d, ())]
    leaves: list[_ViewLeaf] = []
    tie = nodes = 0
    while heap:
        neg, _, weight, p, d, steps = heapq.heappop(heap)
        s, t = G.nearest_hit(sf, si, *p, *d)
        if not _is_optical(names, s) or len(steps) >= _VIEW_EVENTS:
            leaves.append(_ViewLeaf(steps, weight, -1 if _is_optical(names, s) else s, -neg))
            continue
        nodes += 1
        if nodes > _VIEW_NODES:
            continue  # lighter than every branch already followed
        x = p + t * d
        n = np.array(G.surface_normal(sf, si, s, *x))
        f = I.interface_at(sf, si, s, float(d @ n))
        ok, *dt = I.refract(*d, *n, f.n1 / f.n2)
        dr = np.array(I.reflect(*d, *n))
        r, tr = (f.reflectance, 1.0 - f.reflectance - f.absorptance) if ok else (1.0, 0.0)
        out = r + tr
        kids = [(True, r, r / out if out > 0.0 else 0.0, dr)]
        if ok:
            kids.append((False, tr, tr / out if out > 0.0 else 1.0, np.array(dt)))
        for reflected, share, part, dd in kids:
            tie += 1
            step = _ViewStep(s, reflected, float(share))
            unit = dd / np.linalg.norm(dd)
            heapq.heappush(heap, (neg * part, tie, weight * share, x, unit, (*steps, step)))
    return leaves


def _view_step(sf, si, view: np.ndarray, s: int, p: np.ndarray, d: np.ndarray):
    """At the point ``p`` of element surface ``s``, the ray ``d`` goes on as the camera's view
    does (``view``, :func:`_view_through_elements`): reflected where ``view[s]`` is 1,
    refracted where it is 0; off the view's branch (−1) along the stronger part, refracted when
    the transmittance 1 − R − A is at least R, else reflected; reflected on total internal
    reflection. Returns (p, unit direction, reflected)."""
    n = np.array(G.surface_normal(sf, si, s, *p))
    f = I.interface_at(sf, si, s, float(d @ n))
    ok, *dt = I.refract(*d, *n, f.n1 / f.n2)
    v = view[s]
    reflected = not ok or v == 1 or (v < 0 and 1.0 - f.reflectance - f.absorptance < f.reflectance)
    d = np.array(I.reflect(*d, *n)) if reflected else np.array(dt)
    return p, d / np.linalg.norm(d), reflected


def _step_words(scene: Scene, names: list[str], step: _ViewStep) -> str:
    """``element 1 (hot mirror) front reflects R = 0.1`` (or ``passes T = …``), with, for a
    fixed coating with a cut-off whose other side would serve this branch better, why: ``(its
    cut-off 900 nm is above the 850 nm light: R = 0.92 only at ≥ 900 nm)``."""
    name = names[step.row]
    k, side = int(name.split()[1]), name.rsplit(" ", 1)[1]
    el = scene.elements[k]
    what = "reflects R" if step.reflected else "passes T"
    words = f"{name} {what} = {step.share:.3g} at {scene.wavelength_nm:g} nm"
    coat = el.surfaces[_SIDES.index(side)].coating
    if coat is None or coat.model != "fixed" or coat.cutoff_nm is None:
        return words
    lam, cut = float(scene.wavelength_nm), float(coat.cutoff_nm)
    other = coat.fixed_at(cut - 1.0 if lam >= cut else cut)
    better = other[0] if step.reflected else other[1]
    if better <= step.share:
        return words
    where = "above" if cut > lam else "at or below"
    side_name = "≥" if lam < cut else "<"
    return (
        f"{words} (its cut-off {cut:g} nm, elements.{k}.{side}.coating.cutoff_nm, is {where} "
        f"the wavelength: it {what} = {better:g} only at {side_name} {cut:g} nm)"
    )


def _view_through_elements(
    scene: Scene, surfaces: SurfaceTable, names: list[str], lf: np.ndarray, *, strict: bool = True
) -> tuple[bool, np.ndarray]:
    """The camera's line of sight (its axis, from the lens's first vertex toward the scene,
    camera frame) followed through the optical elements along both branches at each element
    surface (:func:`_view_branches`). The view is the branch of largest reach that ends on the
    eye (else the face), if it carries at least :data:`VIEW_MIN_SHARE` of the line of sight
    (its reach: absorption aside): a 45°
    beamsplitter (R = T = 0.5, or R < T) folds the view onto the eye as a hot mirror does,
    its straight-through branch leaving the scene.

    Returns (folded, view): whether the view is reflected somewhere (then
    :func:`_check_view`'s straight-line test does not apply), and ``view`` (n_surfaces,)
    int64: per element surface on the view's branch 1 (the view reflects there) or 0
    (refracts; reflects only on total internal reflection), −1 elsewhere (the stronger
    branch: reflected where R > T). The truth, ghosts and regions follow the view by it
    (:attr:`CompiledScene.view_branch`).

    Raises SceneError in one line when no branch reaching the eye or the face carries that
    share: naming the heaviest branch's path and where it ends (nothing, an LED, the camera),
    and the branch that would reach the eye with the R or T that starves it (and, for a hot
    mirror's cut-off on the wrong side of the wavelength, the cut-off); and a view that takes a
    coating's weak side of its cut-off is warned about (:class:`ViewWarning`). Without
    ``strict`` (a wavelength group's or the sun's compile, whose geometry the scene's own
    compile checked: at another wavelength a hot mirror may pass what it folds at the scene's)
    nothing is refused or warned about: the heaviest branch that reaches the eye or the face
    is the view, whatever it carries, and with none the view is (True, all −1) (its picture
    is dark; the straight-line test is not repeated)."""
    sf, si = surfaces.sf, surfaces.si
    view = np.full(sf.shape[0], -1, dtype=np.int64)
    if not scene.elements:
        return False, view
    p = np.array([0.0, 0.0, float(lf[0, Q.L_Z]) - 1e-6])
    leaves = _view_branches(sf, si, names, p, np.array([0.0, 0.0, -1.0]))
    if len(leaves) == 1 and not leaves[0].steps:
        return False, view
    eye = {x.name for x in scene.eye.surfaces} | {"iris", "iris root", "sclera"}
    face = {x.name for x in scene.face.tissues} if scene.face.enabled else set()

    def rank(leaf: _ViewLeaf) -> tuple[bool, float]:
        return names[leaf.end] in eye, leaf.reach

    seeing = [x for x in leaves if x.steps and x.end >= 0 and names[x.end] in eye | face]
    good = [x for x in seeing if x.reach >= VIEW_MIN_SHARE or not strict]
    if not good and not strict:
        return True, view
    if not good:
        heavy = max((x for x in leaves if x.steps), key=lambda x: x.reach)
        seen = max(seeing, key=rank) if seeing else None
        raise SceneError(_no_view(scene, names, heavy, seen))
    best = max(good, key=rank)
    for st in best.steps:
        if view[st.row] < 0:
            view[st.row] = int(st.reflected)
    if strict:
        _warn_cutoff(scene, names, best)
    return any(st.reflected for st in best.steps), view


def _no_view(scene: Scene, names: list[str], heavy: _ViewLeaf, seen: _ViewLeaf | None) -> str:
    """The one line refusing a camera whose line of sight through the elements sees no eye:
    the heaviest branch's path and end, and the branch that would reach the eye or the face
    (``seen``) with the R or T under ½ that starve it (:func:`_step_words`)."""
    path = ", ".join(dict.fromkeys(names[st.row].rsplit(" ", 1)[0] for st in heavy.steps))
    where = "nothing (it leaves the scene)" if heavy.end < 0 else names[heavy.end]
    msg = f"camera: sees no eye: its line of sight, through {path}, ends on {where}"
    if seen is not None:
        weak = [st for st in seen.steps if st.share < 0.5] or list(seen.steps)
        msg += (
            f"; the branch that reaches the {names[seen.end]} carries only "
            f"{seen.reach:.2g} of it (less than {VIEW_MIN_SHARE:g}): "
            + "; ".join(_step_words(scene, names, st) for st in weak)
        )
    return msg


def _warn_cutoff(scene: Scene, names: list[str], best: _ViewLeaf) -> None:
    """Warn (:class:`ViewWarning`) when the view's branch takes a coating's weak side of its
    cut-off (:func:`_step_words` names it): the eye image is dim for a reason the user set."""
    for st in best.steps:
        words = _step_words(scene, names, st)
        if "cut-off" in words:
            warnings.warn(
                f"camera: sees the {names[best.end]} only through {words}: its image carries "
                f"{best.weight:.2g} of the light of the camera's line of sight",
                ViewWarning,
                stacklevel=4,
            )
            return


def _compile_lens(
    scene: Scene, semi_fixed: list[float] | None = None
) -> tuple[LensTable, list[float], int]:
    """The imaging lens (sequential): its table with clear semi-diameters from a real-ray trace
    of the eye-plane field, its indices and the stop's row. Raises SceneError for a lens with no
    positive power, crossing surfaces or one that blocks the field.

    ``semi_fixed``: the clear semi-diameters (stop included) of the lens as built, from its
    compile at the scene's wavelength — given when the lens is traced at another wavelength
    (a wavelength group, :func:`compile_scene`): the glass disperses, the apertures stay."""
    idx, _ = lens_indices(scene)
    stop = next(j for j, s in enumerate(scene.lens.surfaces) if s.stop)
    par = lens_paraxial(scene, idx)
    if not par.power > 0:
        raise SceneError(f"lens: the prescription has no positive power (EFL {par.efl:.3g} mm)")
    if semi_fixed is None:
        stop_sd = par.stop_semi_diameter_for_epd(stop, par.efl / scene.lens.f_number)
    else:
        stop_sd = semi_fixed[stop]
    check_focus(scene, par, stop, stop_sd, warn=False)  # a real image of the eye plane
    if semi_fixed is None:
        semi, rim_fraction = _auto_semi_diameters(scene, idx, par, stop, stop_sd)
    else:
        semi, rim_fraction = list(semi_fixed), 1.0
    lf, image_z = _lens_table(scene, idx, semi)
    _check_lens_geometry(lf)
    if rim_fraction < 0.9:
        sw, sh = scene.sensor.field_mm
        raise SceneError(
            f"lens: only {rim_fraction:.0%} of the rim rays of the eye-plane field pass the lens "
            "(total internal reflection or a surface missed): the picture (sensor.width_mm × "
            f"sensor.height_mm = {sw:g} × {sh:g} mm) is larger than the lens covers, or check "
            "the prescription"
        )
    _check_coverage(scene, par, stop, stop_sd, lf)
    best = real_best_focus(lf)
    check_focus(scene, par, stop, stop_sd, None if best is None else best[0])  # near the sensor
    return LensTable(lf, float(image_z)), idx, stop


#: Stop zones (fractions of the stop's radius) and azimuths of the rays
#: :func:`_check_coverage` aims from each field point: the chief ray and two rings.
_COVERAGE_ZONES = (0.0, 0.5, 0.999)  # the stop's own edge is a tie
_COVERAGE_AZIMUTHS = 8


def _check_coverage(
    scene: Scene, par: ParaxialSystem, stop: int, stop_sd: float, lf: np.ndarray
) -> None:
    """The lens covers the sensor: every point of a 9 × 7 grid over the sensor's field on the
    plane in focus (its size / |paraxial magnification|, corners included) sends some ray
    through the clear apertures to the sensor. Aperture limits are the user's
    (``semi_diameter_mm``; the automatic ones pass the whole field by construction,
    :func:`_auto_semi_diameters`). For each point, rays through the stop's centre and its half
    and full radius (8 azimuths each) are aimed by
    :func:`eyelume.kernels.sequential.rim_ray_heights` and traced with the apertures.

    Raises SceneError when a field point passes no ray (that part of the picture would be black
    for want of a lens, not of light), naming the sensor's size and the first clear aperture the
    point's chief ray overfills. A point whose chief ray is blocked but some rays pass is
    vignetted past 50 %: a warning."""
    from eyelume.kernels.sequential import rim_ray_heights

    if all(s.semi_diameter_mm is None for j, s in enumerate(scene.lens.surfaces) if j != stop):
        return
    m = abs(par.magnification(scene.object_distance_mm))
    sw, sh = scene.sensor.field_mm
    w, h = sw / m, sh / m
    pupil_mag = par.efl / scene.lens.f_number / 2 / stop_sd
    pupil_z = scene.lens.object_distance_mm + par.entrance_pupil_position(stop)
    open_lf = lf.copy()
    open_lf[:, Q.L_SD] = np.inf
    open_lf[stop, Q.L_SD] = stop_sd
    vignetted = []
    for x0 in np.linspace(-w / 2, w / 2, 9):
        for y0 in np.linspace(-h / 2, h / 2, 7):
            xs, ys = np.array([x0]), np.array([y0])
            passed = [
                rim_ray_heights(lf, stop, z * stop_sd, xs, ys, n, pupil_mag, pupil_z)[1]
                for z, n in zip(
                    _COVERAGE_ZONES, (1, _COVERAGE_AZIMUTHS, _COVERAGE_AZIMUTHS), strict=True
                )
            ]
            if passed[0]:
                continue
            heights, _ = rim_ray_heights(open_lf, stop, 0.0, xs, ys, 1, pupil_mag, pupil_z)
            over = [j for j in range(lf.shape[0]) if heights[j] > lf[j, Q.L_SD]]
            where = (
                f"lens.surfaces.{over[0]}.semi_diameter_mm = {lf[over[0], Q.L_SD]:g} (the chief "
                f"ray reaches {heights[over[0]]:.2f} mm there)"
                if over
                else "the lens"
            )
            if sum(passed) == 0:
                raise SceneError(
                    f"sensor: larger than the lens covers ({sw:.3g} × {sh:.3g} mm at "
                    f"magnification {m:.3g}): the point ({x0:.1f}, {y0:.1f}) mm of the plane in "
                    f"focus sends no ray through {where}"
                )
            vignetted.append((x0, y0, where))
    if vignetted:
        x0, y0, where = vignetted[0]
        warnings.warn(
            f"lens: {len(vignetted)} of 63 field points, e.g. ({x0:.1f}, {y0:.1f}) mm on the plane "
            f"in focus, are vignetted past 50 %: the chief ray is blocked by {where}",
            EyelumeWarning,
            stacklevel=2,
        )


#: Widest half field (°) an ideal (rectilinear) lens is allowed to cover: the slope tan θ of a
#: ray at 85° is 11, where a thin-lens model of a real module has long stopped meaning much.
MAX_IDEAL_HALF_FIELD_DEG = 85.0


def _compile_ideal(scene: Scene) -> tuple[LensTable, list[float], int]:
    """The ideal (thin, perfect) lens of ``[camera.ideal]`` as a one-row lens table: the lens
    plane at the focus distance, its aperture the stop, the sensor at the image distance v.
    Raises SceneError when the chip's corner lies beyond the field the lens covers."""
    ideal = scene.camera.ideal
    assert ideal is not None  # the model's validator
    lf = np.zeros((1, Q.N_LENS_COL))
    lf[0, Q.L_Z] = ideal.focus_distance_mm
    lf[0, Q.L_SD] = ideal.pupil_radius_mm
    lf[0, Q.L_N0] = lf[0, Q.L_N1] = 1.0
    lf[0, Q.L_POWER] = 1.0 / ideal.efl_mm
    lf[0, Q.L_K1], lf[0, Q.L_K2], lf[0, Q.L_WAY] = ideal.k1, ideal.k2, 1.0
    v = ideal.image_distance_mm
    w, h = scene.sensor.field_mm
    corner = math.hypot(w, h) / 2.0 / v  # the chief ray's distorted slope at the corner
    rho = float(Q.undistorted_radius(ideal.k1, ideal.k2, corner))
    if math.isnan(rho) or math.degrees(math.atan(rho)) > MAX_IDEAL_HALF_FIELD_DEG:
        seen = (
            "beyond the distortion's monotonic range"
            if math.isnan(rho)
            else (f"{math.degrees(math.atan(rho)):.1f}° off the axis")
        )
        raise SceneError(
            f"sensor: the chip's corner ({w / 2:.3g}, {h / 2:.3g}) mm lies {seen}: more than "
            f"the ideal lens covers (≤ {MAX_IDEAL_HALF_FIELD_DEG:g}°; camera.ideal.efl_mm = "
            f"{ideal.efl_mm}, k1 = {ideal.k1}, k2 = {ideal.k2})"
        )
    return LensTable(lf, float(ideal.focus_distance_mm + v)), [1.0, 1.0], 0


def _first_order(
    scene: Scene, lens: LensTable, idx: list[float], stop: int, fixed_stop: bool = False
) -> FirstOrder:
    """The camera's first-order optics (:class:`FirstOrder`). ``fixed_stop``: the stop's
    semi-diameter in ``lens`` is that of the lens as built (a wavelength group): the entrance
    pupil is then its paraxial image at the scene's wavelength, radius = stop semi-diameter /
    (stop height per unit entrance height), and the F-number EFL / its diameter."""
    s_obj = scene.object_distance_mm
    if scene.camera.optics == "ideal":
        ideal = scene.camera.ideal
        assert ideal is not None
        a = ideal.pupil_radius_mm
        m = -ideal.image_distance_mm / s_obj
        return FirstOrder(
            ideal.efl_mm, ideal.f_number, s_obj, s_obj, a, s_obj, 1.0, lens.image_z, m,
            ideal.f_number * (1.0 - m),
        )  # fmt: skip
    par = lens_paraxial(scene, idx)
    xp_z, xp_m = _exit_pupil(scene, idx, stop, lens.lf)
    f_number = scene.lens.f_number  # type: ignore[union-attr]
    ep_radius = par.efl / f_number / 2.0
    if fixed_stop:
        ep_radius = float(lens.lf[stop, Q.L_SD]) / abs(float(par.trace(1.0, 0.0)[0][stop]))
        f_number = par.efl / (2.0 * ep_radius)
    return FirstOrder(
        efl=par.efl,
        f_number=f_number,
        object_distance=s_obj,
        entrance_pupil_z=s_obj + par.entrance_pupil_position(stop),
        entrance_pupil_radius=ep_radius,
        exit_pupil_z=xp_z,
        exit_pupil_magnification=xp_m,
        image_z=lens.image_z,
        magnification=par.magnification(s_obj),
        working_f_number=par.working_f_number(s_obj, stop, float(lens.lf[stop, Q.L_SD])),
    )


def _check_eye_apertures(scene: Scene) -> None:
    """An eye that can exist (a Scene built without :func:`eyelume.scene.io.validate_scene`,
    e.g. by ``Scene.model_validate``, is checked here too)."""
    check_eye_geometry(scene.eye)


def _astigmatic(eye) -> bool:
    """Whether the anterior cornea's two meridians differ (else the rotationally symmetric
    conicoid, compiled as it always was, bit for bit)."""
    c1, c2, _ = anterior_quadric(eye)
    return c2 != c1


def _anterior_cornea(scene: Scene, eye_rot: np.ndarray):
    """The astigmatic, decentred or tilted anterior cornea's row data (``eye.cornea``,
    :func:`eyelume.scene.eye.anterior_cornea_pose`): (shape, world apex, world → local
    rotation, c_y, bounding sphere). The astigmatic quadric (``G.SHAPE_QUADRIC``, local x the
    flat meridian) when the two radii differ, else the conicoid, moved and tilted; its bounding
    sphere that of the deeper (steep) meridian's cap."""
    eye = scene.eye
    c1, c2, k = anterior_quadric(eye)
    _, to_local = anterior_cornea_pose(eye)
    rot = to_local @ eye_rot
    dx, dy = eye.cornea.decentration_mm
    origin = eye_point(scene, [dx, dy, 0.0])
    h = eye.surfaces[0].semi_diameter_mm
    depth = float(np.nanmax(meridian_sag(c1, c2, k, h, np.array([0.0, math.pi / 2]))))
    centre = np.asarray(origin) + rot[2] * (depth / 2.0)
    bound = (centre, math.hypot(h, depth / 2.0) * 1.000001 + 1e-9)
    shape = G.SHAPE_CONIC if c2 == c1 else G.SHAPE_QUADRIC
    return shape, origin, rot, (c2 if shape == G.SHAPE_QUADRIC else 0.0), bound


def _add_eye(t: _Table, scene: Scene) -> None:
    """The eye's refracting surfaces, iris, retina and sclera (eye frame: z' = −z), placed by
    the gaze rotation and the head offset."""
    eye = scene.eye
    _check_eye_apertures(scene)
    n_eye = eye_indices(eye, scene.wavelength_nm)
    r_l, z_l, z_c = limbus_geometry(eye)
    zprime = 0.0
    surf_z: list[float] = []
    for s in eye.surfaces:
        surf_z.append(zprime)
        zprime += s.thickness_mm
    gaze, _ = gaze_rotation(eye)
    eye_rot = EYE_AXIS_ROT @ gaze.T  # world → eye frame, gaze included
    if scene.eye_pose.which == "left":  # mirrored (improper): the eye's shapes are symmetric
        eye_rot = eye_rot * _MIRROR_X

    def on_eye(z_eye: float) -> np.ndarray:
        """World point of the eye axis at depth z_eye behind the vertex, gaze, pose and head
        offset included."""
        return eye_point(scene, np.array([0.0, 0.0, -z_eye]))

    refracting = eye.surfaces[:-1]
    for j, s in enumerate(refracting):
        c = curvature(s.radius_mm)
        origin = on_eye(surf_z[j])
        anterior = j == 0
        shape, rot, c_y = G.SHAPE_CONIC, eye_rot, 0.0
        bound = None
        if anterior and (_astigmatic(eye) or eye.cornea.placed):
            shape, origin, rot, c_y, bound = _anterior_cornea(scene, eye_rot)
        t.add(
            s.name,
            shape,
            origin,
            rot,
            bound or _conic_bound(origin, eye_rot, c, s.conic, s.semi_diameter_mm),
            curv=c,
            conic=s.conic,
            radius=c_y,
            clip_r=(0.0, s.semi_diameter_mm),
            action=G.ACT_REFRACT,
            n_a=n_eye[j],
            n_b=n_eye[j + 1],
            refl=glint_reflectance(eye, scene.wavelength_nm) if anterior else 0.0,
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


def _add_face(t: _Table, scene: Scene) -> None:
    """The face's tissues (Lambertian on their outside); a lid follows its share of the gaze."""
    if not scene.face.enabled:
        return
    eye = scene.eye
    for tis in scene.face.tissues:
        rho = scene.face.skin_reflectance if tis.reflectance is None else tis.reflectance
        # a lid takes its share of the eye's vertical rotation, about the same centre
        turn, _ = gaze_rotation(eye, share_vertical=tis.follows_gaze, share_horizontal=0.0)
        rot = _frame(as_world(scene, turn @ np.asarray(tis.axis, dtype=float)))
        o = eye_point(scene, tis.center_mm, share_vertical=tis.follows_gaze, share_horizontal=0.0)
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


#: The ledger's and the regions' name of an eyelash fringe (:func:`_add_lashes`).
LASHES_NAME = "eyelashes"


def lash_fringe(scene: Scene) -> dict | None:
    """The eyelash fringe of ``scene.face.lashes`` in the world frame, or None when it has none:
    ``apex`` (3,) mm and unit ``axis`` (3,) of its cone (the lid's axis, turned with the lid's
    share of the gaze), unit ``forward`` (3,) (local +x, the span's centre), ``slope`` m (the
    cone x² + y² = m² z², m = cot tilt), local ``z_range`` (mm, the lashes' roots and tips),
    ``count``, ``pitch`` (rad), ``half_width`` (mm), ``root_radius`` ρ_m (mm) and the margin's
    centre ``margin_centre`` (3,) mm. The lid's margin, at local z_m, is the circle of radius
    ρ_m = √(R² − z_m²); a lash from it at tilt θ meets the axis at z_m − ρ_m tan θ, the apex."""
    face = scene.face
    lashes = face.lashes
    if not (face.enabled and lashes.enabled):
        return None
    lid = next(tis for tis in face.tissues if tis.name == lashes.lid)  # the model's validator
    turn, _ = gaze_rotation(scene.eye, share_vertical=lid.follows_gaze, share_horizontal=0.0)
    axis = as_world(scene, turn @ np.asarray(lid.axis, dtype=float))
    axis = axis / np.linalg.norm(axis)
    fwd = as_world(scene, turn @ np.array([0.0, 0.0, 1.0]))
    fwd = fwd - axis * float(fwd @ axis)
    if np.linalg.norm(fwd) < 1e-6:
        raise SceneError(
            f"face.lashes.lid = {lashes.lid!r}: its axis points along the line of sight; "
            "the lashes need a lid axis across it"
        )
    fwd = fwd / np.linalg.norm(fwd)
    centre = eye_point(scene, lid.center_mm, share_vertical=lid.follows_gaze, share_horizontal=0.0)
    z_m = lid.clip_z_mm[0]
    rho = math.sqrt(lid.radius_mm**2 - z_m**2)
    tilt = math.radians(lashes.tilt_deg)
    z_apex = z_m - rho * math.tan(tilt)
    z0 = z_m - z_apex
    return {
        "apex": centre + axis * z_apex,
        "axis": axis,
        "forward": fwd,
        "slope": 1.0 / math.tan(tilt),
        "z_range": (z0, z0 + lashes.length_mm * math.sin(tilt)),
        "count": lashes.count,
        "pitch": math.radians(lashes.span_deg) / lashes.count,
        "half_width": lashes.width_mm / 2.0,
        "root_radius": rho,
        "margin_centre": centre + axis * z_m,
    }


def _add_lashes(t: _Table, scene: Scene) -> None:
    """The eyelash fringe (:func:`lash_fringe`): one opaque ``SHAPE_LASHES`` row, Lambertian
    with the lashes' reflectance on both faces, the ledger's "eyelashes"."""
    fr = lash_fringe(scene)
    if fr is None:
        return
    axis, fwd = fr["axis"], fr["forward"]
    rot = np.stack([fwd, np.cross(axis, fwd), axis])
    rho = scene.face.lashes.reflectance
    # every lash point lies within ρ_m + length of the margin's centre
    bound = (fr["margin_centre"], (fr["root_radius"] + scene.face.lashes.length_mm) * 1.000001)
    t.add(
        LASHES_NAME,
        G.SHAPE_LASHES,
        fr["apex"],
        rot,
        bound,
        curv=fr["slope"],
        clip_z=fr["z_range"],
        rho_a=rho,
        rho_b=rho,
        lashes=(fr["count"], fr["pitch"], fr["half_width"]),
    )


def _add_led_bodies(t: _Table, scene: Scene, centres: np.ndarray, axes: np.ndarray) -> None:
    """Each LED's body (the ledger's "LED bodies"), absorbing: a sphere of its own radius
    about its centre (one row, ``LED k body``), or a closed cylinder coaxial with its axis
    built from the camera body's shapes (:func:`_add_camera_body`): the front disk at
    centre + (L/2)·axis (``LED k body``, the face the light leaves from) and the side
    (``LED k body (side)``). The back disk is left out, and that is exact: a line meets a
    convex solid's surface where it enters and where it leaves, never twice in the plane of
    the back face, so every ray that would meet the back disk from outside meets the side or
    the front disk from inside next — with nothing between (no surface may lie inside an LED's
    body), so it ends in the same black body, one row fewer to test on every ray."""
    common = {"tally_a": "LED bodies", "tally_b": "LED bodies"}
    for i, b in enumerate(led_bodies(scene.leds, centres, axes)):
        rot, rb = _frame(b.axis), b.radius
        if b.shape == "sphere":
            t.add(f"LED {i} body", G.SHAPE_SPHERE, b.centre, rot, (b.centre, rb * 1.000001),
                  radius=rb, **common)  # fmt: skip
            continue
        half = b.length / 2
        front, back = b.centre + half * b.axis, b.centre - half * b.axis
        closed = (b.centre, math.hypot(rb, half) * 1.000001)  # holds the whole closed cylinder
        first = len(t.rows_f)
        t.add(f"LED {i} body", G.SHAPE_CONIC, front, rot, (front, rb * 1.000001),
              clip_r=(0.0, rb), **common)  # fmt: skip
        t.add(f"LED {i} body (side)", G.SHAPE_CYLINDER, back, rot, closed, radius=rb,
              clip_z=(0.0, b.length), **common)  # fmt: skip
        t.group(first, closed)


def led_body_rows(names: list[str], k: int) -> list[int]:
    """The rows of the surface table (``names``, :attr:`CompiledScene.surface_names`) that
    make LED ``k``'s body (:func:`_add_led_bodies`: one for a sphere, two for a cylinder)."""
    own = f"LED {k} body"
    return [s for s, name in enumerate(names) if name == own or name.startswith(own + " (")]


def _profile_grids(profile: LedProfile) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """One profile's (alpha_grid, cdf_grid, intensity_grid, Ω_eff in sr). Raises SceneError for
    a profile that cannot be used."""
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
    return alpha_grid, cdf_grid, intensity_grid, omega


def _led_table(
    scene: Scene, centres: np.ndarray, axes: np.ndarray, emitting: tuple[int, ...] | None = None
) -> tuple[LedTable, np.ndarray]:
    """The LEDs as point sources on the front of their bodies (a sphere's apex, a cylinder's
    front face's centre, :meth:`~eyelume.scene.model.LedArray.emission_offsets_mm`), each
    with its own I₀ and its profile's sampling and evaluation tables (every profile on the
    same α grid); and Ω_eff (N,) (sr) of every LED. ``emitting``: only these LEDs (their
    indices, in order; default all). Raises SceneError for a profile that cannot be used."""
    rb = np.asarray(scene.leds.emission_offsets_mm())[:, None]  # a sphere's radius
    emit = centres + axes * rb * (1.0 + 1e-9)
    profiles = scene.leds.profiles()
    i0 = np.array(scene.leds.intensities_w_sr(), dtype=float)
    if emitting is not None:
        keep = list(emitting)
        emit, axes, i0 = emit[keep], axes[keep], i0[keep]
        profiles = [profiles[k] for k in keep]
    grids: dict[LedProfile, tuple] = {}
    rows = []
    for profile in profiles:
        if profile not in grids:
            grids[profile] = _profile_grids(profile)
        rows.append(grids[profile])
    omega = np.array([r[3] for r in rows], dtype=float)
    power = i0 * omega
    table = LedTable(
        np.ascontiguousarray(emit),
        np.ascontiguousarray(axes, dtype=float),
        np.ascontiguousarray(i0),
        np.ascontiguousarray(rows[0][0]),
        np.ascontiguousarray(np.stack([r[1] for r in rows])),
        np.ascontiguousarray(np.stack([r[2] for r in rows])),
        np.ascontiguousarray(np.cumsum(power) / power.sum()),
        bool(np.all(power == power[0])),
    )
    return table, omega


def _add_lens_entrance(t: _Table, lf: np.ndarray) -> None:
    """The lens's first surface in the non-sequential table: it hands rays to the sequential
    trace (its back and mount count as vignetting)."""
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
        world=False,
    )


def _add_camera_body(t: _Table, scene: Scene, lf: np.ndarray, first: int) -> None:
    """The camera's body (:class:`eyelume.scene.model.CameraBody`), camera frame: an absorbing
    annulus in the plane of the lens's first vertex from its clear aperture to the body's
    radius, a cylinder to ``length_mm`` behind it and a back disk (the ledger's "camera
    body"), grouped (:meth:`_Table.group`) with the rows from ``first`` on (the lens's
    entrance) in the closed body's sphere, grown to hold those rows' bounding spheres. Raises
    SceneError for a body narrower than the lens's clear aperture."""
    body = scene.camera.body_used
    if body is None:
        return
    z0, sd, rb = float(lf[0, Q.L_Z]), float(lf[0, Q.L_SD]), body.diameter_mm / 2
    if rb <= sd:
        raise SceneError(
            f"camera.body.diameter_mm = {body.diameter_mm} must exceed the lens's clear "
            f"aperture ({2 * sd:.3g} mm across)"
        )
    back = z0 + body.length_mm
    rot = np.eye(3)
    common = {"tally_a": "camera body", "tally_b": "camera body", "world": False}
    front_o, back_o = np.array([0.0, 0.0, z0]), np.array([0.0, 0.0, back])
    t.add("camera body (front)", G.SHAPE_CONIC, front_o, rot, (front_o, rb * 1.000001),
          clip_r=(sd, rb), **common)  # fmt: skip
    mid = np.array([0.0, 0.0, (z0 + back) / 2])
    t.add("camera body (side)", G.SHAPE_CYLINDER, front_o, rot,
          (mid, math.hypot(rb, body.length_mm / 2) * 1.000001), radius=rb,
          clip_z=(0.0, body.length_mm), **common)  # fmt: skip
    t.add("camera body (back)", G.SHAPE_CONIC, back_o, rot, (back_o, rb * 1.000001),
          clip_r=(0.0, rb), **common)  # fmt: skip
    centre, radius = mid, math.hypot(rb, body.length_mm / 2) * 1.000001
    for row in t.rows_f[first : len(t.rows_f) - 3]:  # the lens's entrance
        centre, radius = _sphere_union(centre, radius, row[G.BX : G.BZ + 1], row[G.BR])
    t.group(first, (centre, radius), world=False)


def _sphere_union(c1, r1: float, c2, r2: float) -> tuple[np.ndarray, float]:
    """The smallest sphere holding spheres (c1, r1) and (c2, r2): the larger one if it holds
    the other, else the one whose diameter spans both along the line of their centres."""
    c1, c2 = np.asarray(c1, dtype=float), np.asarray(c2, dtype=float)
    d = float(np.linalg.norm(c2 - c1))
    if d + r2 <= r1:
        return c1, r1
    if d + r1 <= r2:
        return c2, r2
    radius = (d + r1 + r2) / 2
    return c1 + (c2 - c1) * ((radius - r1) / d), radius * (1 + 1e-12)


def element_label(k: int, element: Element) -> str:
    """The ledger entry of element ``k`` (what its coatings and edge absorb):
    ``element k (name)``, the name defaulting to its kind."""
    return f"element {k} ({element.name or element.kind})"


def element_pose(scene: Scene, element: Element) -> tuple[np.ndarray, np.ndarray]:
    """(origin, rotation) of an element in the world frame: its first vertex (mm) and the
    world → local rotation whose third row is its unit axis (a left eye's file mirrored)."""
    origin = as_world(scene, element.position_mm)
    axis = np.asarray(as_world(scene, element.axis()), dtype=float)
    return origin, _frame(axis)


def element_index(scene: Scene, k: int, element: Element) -> float:
    """The refractive index of element ``k``'s glass at the scene's wavelength, from the glass
    catalogs the lens prescription uses (``lens.glass_catalogs``, else the shipped one); 1 for
    a mirror. Raises SceneError naming ``elements.k.glass`` for a glass not in them."""
    if element.kind == "mirror":
        return 1.0
    files = scene.lens.glass_catalogs if scene.lens is not None else []
    try:
        catalog = load_catalog(*files) if files else load_catalog()
        glass = catalog[element.glass]
    except GlassError as exc:
        raise SceneError(f"field 'elements.{k}.glass' = {element.glass!r}: {exc}") from None
    return float(glass.index(scene.wavelength_nm))


_SIDES = ("front", "back")


def _coating_columns(k: int, j: int, coating: Coating, wavelength_nm: float) -> dict:
    """The surface-table options of a coating at ``wavelength_nm``: Fresnel flag; fixed R and
    A = 1 − R − T (either side of a hot mirror's cut-off); or
    an R(θ) table (T = 1 − R), read here. Raises InputFileError for a table that cannot be
    used or has more than :data:`eyelume.kernels.interact.R_TABLE_NODES` rows."""
    if coating.model == "fresnel":
        return {"fresnel": True}
    if coating.model == "fixed":
        r, t = coating.fixed_at(wavelength_nm)
        return {"refl": r, "absorb": max(0.0, 1.0 - r - t)}
    field = f"elements.{k}.{_SIDES[j]}.coating.table_csv"
    angles, values = read_reflectance_table(coating.table_csv, field, wavelength_nm)  # type: ignore[arg-type]
    if len(angles) > I.R_TABLE_NODES:
        raise InputFileError(
            f"{len(angles)} rows: at most {I.R_TABLE_NODES} angles per table",
            file=coating.table_csv,
            field=field,
        )
    return {"r_table": (angles, values)}


def _add_elements(t: _Table, scene: Scene) -> None:
    """Each element's optical surfaces (refracting interfaces with their coatings, glass
    inside a lens or plate) and a lens's or plate's absorbing edge, world frame; each
    element's absorption is its own ledger entry (:func:`element_label`)."""
    for k, el in enumerate(scene.elements):
        n = element_index(scene, k, el)
        origin, rot = element_pose(scene, el)
        sd = el.semi_diameter_mm
        tally = element_label(k, el)
        zs = vertex_z_mm(el)
        media = [(1.0, 1.0)] if el.kind == "mirror" else [(1.0, n), (n, 1.0)]
        for j, (surf, z0, (n_a, n_b)) in enumerate(zip(el.surfaces, zs, media, strict=True)):
            c = curvature(surf.radius_mm)
            o = origin + rot[2] * z0
            t.add(
                f"{tally} {_SIDES[j]}",
                G.SHAPE_CONIC,
                o,
                rot,
                _conic_bound(o, rot, c, surf.conic, sd),
                curv=c,
                conic=surf.conic,
                clip_r=(0.0, sd),
                action=G.ACT_REFRACT,
                n_a=n_a,
                n_b=n_b,
                tally_a=tally,
                tally_b=tally,
                **_coating_columns(k, j, surf.coating, scene.wavelength_nm),  # type: ignore[arg-type]
            )
        if el.kind == "mirror" or el.edge_thickness_mm <= 0.0:
            continue
        zlo = zs[0] + el.surfaces[0].sag_mm(sd)
        zhi = zs[1] + el.surfaces[1].sag_mm(sd)
        mid = origin + rot[2] * (zlo + zhi) / 2
        t.add(f"{tally} edge", G.SHAPE_CYLINDER, origin, rot,
              (mid, math.hypot(sd, (zhi - zlo) / 2) * 1.000001), radius=sd,
              clip_z=(zlo, zhi), tally_a=tally, tally_b=tally)  # fmt: skip


def _check_element_names(scene: Scene) -> None:
    """Each element's name (its kind when unnamed, :func:`element_label`) is its own:
    truth.json's ghost chains and the ledger name an element's surfaces by it. Raises
    SceneError naming the second ``elements.k.name``."""
    seen: dict[str, int] = {}
    for k, el in enumerate(scene.elements):
        name = el.name or el.kind
        if name in seen:
            was = (
                f"{el.name!r}, as elements.{seen[name]}'s"
                if el.name
                else f"'' (unnamed), as elements.{seen[name]}, both a {el.kind}"
            )
            raise SceneError(
                f"elements.{k}.name = {was}: truth.json's ghost chains name an element's "
                "surfaces by its name (its kind when unnamed), so each element needs its own"
            )
        seen[name] = k


def _check_elements(scene: Scene, led_centres: np.ndarray, led_axes: np.ndarray) -> None:
    """No element cuts the eye or the face (its sampled boundary, :func:`outline_points`),
    reaches behind the eye plane (into the head, where no tissue is modelled: the eye plane
    z through the eye's nominal corneal vertex, :func:`eye_plane_origin`, as the LEDs'
    bodies, :func:`_check_leds`), cuts an LED's body (world ``led_centres``, ``led_axes``; a
    cylinder by its sampled surface, within the sampling step) or another
    element; no two share a name (:func:`_check_element_names`). Raises SceneError naming
    the element."""
    _check_element_names(scene)
    shapes = []
    bodies = led_bodies(scene.leds, led_centres, led_axes)
    plane_z = float(eye_plane_origin(scene)[2])
    for k, el in enumerate(scene.elements):
        origin, rot = element_pose(scene, el)
        local = outline_points(el)
        world = local @ rot + origin
        for p in world.reshape(-1, 3):
            where = _in_head(scene, p, 0.0)
            if where is not None:
                raise SceneError(
                    f"elements.{k} ({el.name or el.kind} at {list(el.position_mm)} mm) reaches "
                    f"into {where} (at world {np.round(p, 2).tolist()} mm)"
                )
        back = world.reshape(-1, 3)[np.argmin(world[..., 2])]
        if back[2] <= plane_z:
            raise SceneError(
                f"elements.{k}.position_mm = {list(el.position_mm)}: the element "
                f"({el.name or el.kind}) reaches behind the eye plane z = {plane_z + 0.0:g} mm (to "
                f"world {np.round(back, 2).tolist()} mm), into the head: elements go in front "
                "of the eye, as the LEDs do"
            )
        for i, (c, b) in enumerate(zip(led_centres, bodies, strict=True)):
            if b.shape == "sphere":
                near = near_element(el, (rot @ (c - origin))[None], b.radius)[0]
            else:
                step = body_sample_step(b.radius, b.length)
                near = near_element(el, (b.points() - origin) @ rot.T, step).any()
            if near:
                raise SceneError(
                    f"elements.{k} ({el.name or el.kind}) overlaps LED {i}'s body (world centre "
                    f"{np.round(c, 2).tolist()} mm)"
                )
        for j, (other, o2, r2, w2) in enumerate(shapes):
            a_in_b = (world - o2) @ r2.T
            b_in_a = (w2 - origin) @ rot.T
            if (
                crosses_surfaces(other, a_in_b)
                or crosses_surfaces(el, b_in_a)
                or inside_solid(other, a_in_b).any()
                or inside_solid(el, b_in_a).any()
            ):
                raise SceneError(
                    f"elements.{k} ({el.name or el.kind}) intersects elements.{j} "
                    f"({other.name or other.kind})"
                )
        shapes.append((el, origin, rot, world))


def _check_elements_clear_of_camera(scene: Scene, lf: np.ndarray, frame: Frame) -> None:
    """No optical element cuts the camera: the solid cylinder of its body (or, without one,
    of the lens: its largest clear aperture, from the first vertex to the last surface), camera
    frame. Sampled: the element's outline points inside the cylinder, or the cylinder's axis
    and 12 lines of its wall crossing one of the element's surfaces or inside its solid. Raises
    SceneError naming the element."""
    body = scene.camera.body_used
    z0 = float(lf[0, Q.L_Z])
    if body is not None:
        rc, z1 = body.diameter_mm / 2, z0 + body.length_mm
    else:
        rc, z1 = float(np.max(lf[:, Q.L_SD])), max(float(lf[-1, Q.L_Z]), z0 + 1e-3)
    phi = np.linspace(0.0, 2.0 * math.pi, 12, endpoint=False)
    zs = np.linspace(z0, z1, 24)
    lines = [np.stack([np.zeros_like(zs), np.zeros_like(zs), zs], 1)]
    lines += [
        np.stack([np.full_like(zs, rc * math.cos(a)), np.full_like(zs, rc * math.sin(a)), zs], 1)
        for a in phi
    ]
    camera = frame.world_point(np.stack(lines))  # (13, 24, 3) world mm
    for k, el in enumerate(scene.elements):
        origin, rot = element_pose(scene, el)
        pts = frame.point(outline_points(el) @ rot + origin)
        inside = (np.hypot(pts[..., 0], pts[..., 1]) < rc) & (pts[..., 2] > z0) & (pts[..., 2] < z1)
        local = (camera - origin) @ rot.T
        if inside.any() or crosses_surfaces(el, local) or inside_solid(el, local).any():
            raise SceneError(
                f"elements.{k} ({el.name or el.kind} at {list(el.position_mm)} mm) cuts the "
                f"camera ({2 * rc:.3g} mm across, {z1 - z0:.3g} mm deep behind its lens's first "
                "vertex)"
            )


def _check_leds_outside_camera_body(
    scene: Scene, centres: np.ndarray, lf: np.ndarray, frame: Frame, axes: np.ndarray
) -> None:
    """No LED body (world ``centres``, unit ``axes``) reaches into the camera's body (a solid
    cylinder, :func:`_add_camera_body`): a sphere's centre must lie at least its radius from
    the solid; a cylinder must have no sampled point of its surface inside the solid and the
    solid none of its own inside the cylinder (:func:`~eyelume.scene.sources.body_points`).
    Raises SceneError naming the LED and the body."""
    body = scene.camera.body_used
    if body is None:
        return
    rc = body.diameter_mm / 2
    z0 = float(lf[0, Q.L_Z])
    # the camera body in the world: its centre and axis (camera frame +z, behind the lens)
    cam_c = frame.world_point(np.array([0.0, 0.0, z0 + body.length_mm / 2]))
    cam_a = frame.world_vector(np.array([0.0, 0.0, 1.0]))
    cam_points = None
    for i, (c, b) in enumerate(zip(centres, led_bodies(scene.leds, centres, axes), strict=True)):
        if b.shape == "sphere":
            p = frame.point(c)
            dz = max(0.0, z0 - p[2], p[2] - (z0 + body.length_mm))
            dr = max(0.0, math.hypot(p[0], p[1]) - rc)
            inside = math.hypot(dz, dr) < b.radius
        else:
            if cam_points is None:
                cam_points = body_points("cylinder", cam_c, cam_a, rc, body.length_mm)
            inside = bool(
                inside_body(b.points(), "cylinder", cam_c, cam_a, rc, body.length_mm).any()
                or b.inside(cam_points).any()
            )
        if inside:
            raise SceneError(
                f"leds: LED {i} ({_led_field(scene, i)}) body (world centre "
                f"{np.round(c, 2).tolist()} mm, {b.words()}) "
                f"is inside the camera body (camera.body: {body.diameter_mm} mm across, "
                f"{body.length_mm} mm deep behind the lens)"
            )


def _grids(scene: Scene, frame: Frame) -> tuple[PlaneGrid, PlaneGrid]:
    """The picture's pixels on the sensor and the eye-plane receiver's bins, the latter in
    the world plane through the eye's nominal vertex normal to the headset's z axis
    (:func:`eye_plane_origin`; x̂, ŷ, n̂ = world +x, +y, +z), turned into the camera frame."""
    sn, ep = scene.sensor, scene.eye_plane
    origin, axes = eye_plane_origin(scene), np.eye(3)
    if not frame.is_identity or any(origin):
        origin, axes = frame.point(origin), frame.vector(axes)
    return (
        picture_grid(*sn.field_mm, sn.cols, sn.rows),
        eye_plane_grid(ep.width_mm, ep.height_mm, ep.cols, ep.rows, origin, axes),
    )


#: Share of scatter directions aimed at the pupil (the rest cosine-sampled, which keeps the
#: estimator unbiased where refraction bends an aimed ray away from the lens).
AIM_PROBABILITY = 0.8
_PUPIL_MARGIN = 1.15  # real pupils of off-axis points are larger and shifted: aim a bit wider

#: The surfaces lit and seen through the cornea: the iris and its root (_add_eye).
_IRIS = ("iris", "iris root")


#: The angle (rad) of the rays :func:`_pupil_through_elements` traces from the pupil's centre.
_PUPIL_RAY_ANGLE = 1e-3


def _pupil_through_elements(
    surfaces: SurfaceTable,
    names: list[str],
    lf: np.ndarray,
    ep_z: float,
    ep_r: float,
    view: np.ndarray,
) -> np.ndarray | None:
    """The entrance pupil (centre (0, 0, ``ep_z``), radius ``ep_r``, camera frame) imaged
    through the optical elements the camera's line of sight meets, as an ``AIM_IMAGE`` aim row
    (probability 0; :mod:`eyelume.kernels.sampling`), or None when it meets none. Three real
    rays from the pupil's centre — along the axis and at :data:`_PUPIL_RAY_ANGLE` in x and in
    y — are followed from the lens's first vertex through the element surfaces along the
    camera's view (``view``, :func:`_view_through_elements`: a beamsplitter's fold even where
    R ≤ T) until the next thing they meet is not an element; the image's centre C is the
    mean of the points of the axial ray nearest each
    tilted one, its radius ``ep_r`` |u / u′| (u, u′ the tilted ray's angles to the axial ray
    before and after: the pupil's lateral magnification, in air on both sides), the row's
    axis the axial ray's direction after the elements. A pupil imaged at infinity (u′ = 0)
    gives None."""
    sf, si = surfaces.sf, surfaces.si
    z0 = float(lf[0, Q.L_Z]) - 1e-6
    u = _PUPIL_RAY_ANGLE
    starts = [np.array([0.0, 0.0, -1.0]), np.array([u, 0.0, -1.0]), np.array([0.0, u, -1.0])]
    out = []
    for d in starts:
        d = d / np.linalg.norm(d)
        p = np.array([0.0, 0.0, ep_z]) + d * (z0 - ep_z) / d[2]
        met = 0
        for _ in range(_VIEW_EVENTS):
            s, t = G.nearest_hit(sf, si, *p, *d)
            if not _is_optical(names, s):
                break
            met += 1
            p, d, _ = _view_step(sf, si, view, s, p + t * d, d)
        out.append((met, p, d))
    (met, p0, a), tilted = out[0], out[1:]
    if met == 0 or any(m != met for m, _, _ in tilted):
        return None
    centres, mags = [], []
    for _, p1, d1 in tilted:
        cross = np.cross(a, d1)
        sin_u = float(np.linalg.norm(cross))
        if sin_u < 1e-12:
            return None
        # the point of the axial line p0 + s a nearest the line p1 + q d1
        w = p1 - p0
        b = float(a @ d1)
        s = (float(w @ a) - b * float(w @ d1)) / (1.0 - b * b)
        centres.append(p0 + s * a)
        mags.append(math.sin(u) / sin_u)
    row = np.zeros(N_AIM)
    row[A_X : A_Z + 1] = np.mean(centres, axis=0)
    row[A_R], row[A_KIND] = ep_r * float(np.mean(mags)), AIM_IMAGE
    row[A_AX : A_AZ + 1] = a
    return row


#: Share of each LED's cornea-leg light paths aimed at its glint's specular point
#: (:func:`_glint_aims`; the rest drawn over the whole cornea as before, which keeps the
#: mixture unbiased wherever the aim is off).
GLINT_AIM_PROBABILITY = 0.125
#: The aimed cone's half-angle over the linearised preimage of the entrance pupil (the largest
#: angle from the specular direction at which a reflected ray still meets the pupil's rim).
_GLINT_CONE_MARGIN = 1.25
_GLINT_NEWTON_STEP = 1e-6  # rad: the finite-difference step of the Jacobian
_GLINT_TOLERANCE_MM = 1e-6  # the specular ray's miss of the pupil's centre when solved


def _pupil_plane_hit(sf, si, cornea: int, p: np.ndarray, d: np.ndarray, ep_z: float):
    """Where the ray from ``p`` along unit ``d``, reflected by the anterior cornea (the surface
    alone: whatever lies across the way, a lid or a lash, is not looked for), crosses the
    entrance pupil's plane z = ``ep_z`` toward the camera (x, y; None when it misses the cornea
    or leaves away from the camera)."""
    t = G.intersect_surface(sf, si, cornea, *p, *d, math.inf)
    if t < 0:
        return None
    x = p + t * d
    n = np.array(G.surface_normal(sf, si, cornea, *x))
    r = d - 2.0 * float(d @ n) * n
    if r[2] <= 1e-9:
        return None
    q = x + (ep_z - x[2]) / r[2] * r
    return q[:2]


def _glint_direction(sf, si, cornea, p, centre, radius, ep_z):
    """The direction from an LED at ``p`` to the anterior cornea's specular point for the
    entrance pupil's centre (0, 0, ``ep_z``), and the Jacobian (mm/rad) of the reflected ray's
    crossing of the pupil's plane in two directions across it, or None. Started at a sphere's
    specular point (``centre``, ``radius``: the cornea's vertex sphere; the fixed point X = C +
    r (û_P + û_E)/|û_P + û_E| of the bisector), solved on the real surface by Newton's method
    with finite differences."""
    e = np.array([0.0, 0.0, ep_z])
    x = centre + radius * _unit(_unit(p - centre) + _unit(e - centre))
    for _ in range(30):
        x = centre + radius * _unit(_unit(p - x) + _unit(e - x))
    d = _unit(x - p)
    h = _GLINT_NEWTON_STEP
    for _ in range(12):
        f = _pupil_plane_hit(sf, si, cornea, p, d, ep_z)
        if f is None:
            return None
        e1 = _unit(np.cross(d, [1.0, 0.0, 0.0] if abs(d[0]) < 0.9 else [0.0, 1.0, 0.0]))
        e2 = np.cross(d, e1)
        cols = []
        for v in (e1, e2):
            moved = _pupil_plane_hit(sf, si, cornea, p, _unit(d + h * v), ep_z)
            if moved is None:
                return None
            cols.append((moved - f) / h)
        jac = np.column_stack(cols)
        if float(np.hypot(*f)) < _GLINT_TOLERANCE_MM:
            return d, jac
        try:
            step = np.linalg.solve(jac, -f)
        except np.linalg.LinAlgError:
            return None
        d = _unit(d + step[0] * e1 + step[1] * e2)
    return None


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def _glint_aims(
    scene: Scene,
    frame: Frame,
    surfaces: SurfaceTable,
    cornea: int,
    led_points: np.ndarray,
    ep: tuple[float, float],
) -> np.ndarray:
    """Per LED the cone its light paths aim at its glint (:attr:`CameraTables.glint_aim`): about
    the direction to the anterior cornea's specular point for the entrance pupil's centre
    (``ep`` = (z, radius), camera frame; :func:`_glint_direction`), of half-angle
    :data:`_GLINT_CONE_MARGIN` × r_EP / σ_min(J) (J the Jacobian of the reflected ray's
    crossing of the pupil's plane, so that every reflected ray through the pupil comes from
    inside it), drawn with probability :data:`GLINT_AIM_PROBABILITY`, whatever lies across the
    specular ray's way in or out: a lash or a lid's edge across it may hide part of the glint's
    pencil only (a lash across the chief ray of vr-offaxis's LED 2 at (0°, −10°) for the design
    run's person 0 hides half), and the aim is importance sampling, unbiased either way (the
    draws a wholly hidden glint's aim wastes are its share p of that LED's light paths). It was
    skipped for a specular ray that met something: a half-hidden glint was then drawn by the
    whole-cornea draws alone and its power came out 0.2–1.4 × its expectation from seed to
    seed. No aim (probability 0) for an LED whose specular ray is not found, or in a scene
    with optical elements (their glints are drawn by the element legs)."""
    out = np.zeros((led_points.shape[0], GLINT_AIM_COLS))
    if scene.elements:
        return out
    sf, si = surfaces.sf, surfaces.si
    ep_z, ep_r = ep
    radius = scene.eye.surfaces[0].radius_mm
    centre = frame.point(eye_point(scene, [0.0, 0.0, -radius]))
    for k, p in enumerate(np.asarray(led_points, dtype=float)):
        found = _glint_direction(sf, si, cornea, p, centre, radius, ep_z)
        if found is None:
            continue
        d, jac = found
        sigma_min = float(np.linalg.svd(jac, compute_uv=False)[-1])
        if not sigma_min > 0.0:
            continue
        half = min(_GLINT_CONE_MARGIN * ep_r / sigma_min, 0.5 * math.pi)
        out[k, G_AX : G_AZ + 1] = d
        out[k, G_COS] = math.cos(half)
        out[k, G_P] = GLINT_AIM_PROBABILITY
    return out


def _mirrored_lens(lf: np.ndarray) -> np.ndarray:
    rev = lf[::-1].copy()
    rev[:, Q.L_Z] = -rev[:, Q.L_Z]
    rev[:, Q.L_CURV] = -rev[:, Q.L_CURV]
    rev[:, Q.L_WAY] = -rev[:, Q.L_WAY]
    rev[:, Q.L_N0], rev[:, Q.L_N1] = lf[::-1, Q.L_N1].copy(), lf[::-1, Q.L_N0].copy()
    return np.ascontiguousarray(rev)


def _exit_pupil(scene: Scene, idx: list[float], stop: int, lf: np.ndarray) -> tuple[float, float]:
    """World z and signed magnification of the paraxial exit pupil (the stop imaged by the
    surfaces after it)."""
    par = lens_paraxial(scene, idx)
    rear = ParaxialSystem(par.curvatures[stop + 1 :], par.gaps[stop + 1 :], par.indices[stop + 1 :])
    xp_z = float(lf[-1, Q.L_Z] + rear.image_distance(par.gaps[stop]))
    return xp_z, float(rear.magnification(par.gaps[stop]))


def _cornea_image(
    scene: Scene, frame: Frame, pupil_z: float, pupil_r: float
) -> tuple[np.ndarray, float]:
    """Camera-frame centre and radius of the entrance pupil's paraxial image through the cornea.

    The paper's rig (identity frame): on the z axis, the pupil at distance ``pupil_z`` from the
    corneal vertex. A camera anywhere: about the line from the anterior cornea's centre of
    curvature C through the pupil's centre E (a sphere images about any line through its
    centre), at depth z′ behind that line's vertex C + R û."""
    eye = eye_paraxial(scene)
    cornea = ParaxialSystem(eye.curvatures[:2], eye.gaps[:1], eye.indices[:3])
    if frame.is_identity and not any(eye_plane_origin(scene)):  # the paper's rig
        distance, centre = pupil_z, None
    else:
        radius = scene.eye.surfaces[0].radius_mm
        c = frame.point(eye_point(scene, [0.0, 0.0, -radius]))
        u = np.array([0.0, 0.0, pupil_z]) - c
        distance = float(np.linalg.norm(u)) - radius
        u = u / np.linalg.norm(u)
        centre = (c, u, radius)
    image = cornea.image_distance(distance)  # beyond the posterior cornea, eye frame
    mag = cornea.magnification(distance)
    z_eye = scene.eye.surfaces[0].thickness_mm + image
    if centre is None:
        return np.array([0.0, 0.0, -z_eye]), abs(mag) * pupil_r
    c, u, radius = centre
    return c + (radius - z_eye) * u, abs(mag) * pupil_r


def _cornea_image_of_row(scene: Scene, frame: Frame, row: np.ndarray) -> np.ndarray:
    """An ``AIM_IMAGE`` aim row (:func:`_pupil_through_elements`: the camera's pupil imaged
    through the elements, centre C, radius r, the camera's rays' direction a there) imaged
    once more, through the cornea into the eye: the aim of the light the iris scatters toward
    the camera seen through elements. Paraxial, about the line from the anterior cornea's
    centre of curvature c through C (a sphere images about any line through its centre), as
    :func:`_cornea_image`: C in front of the eye ((C − c) · a < 0) is an object
    |C − c| − R before the vertex c + R û (û = unit(C − c)); C beyond it (the camera's rays
    converge toward C behind the face) a virtual one, |C − c| + R behind the vertex
    c − R û. The row keeps its kind and axis a (inside the eye the rays still run along the
    camera's: :func:`eyelume.kernels.sampling.image_cone` tells toward from away by it); its
    centre is the image, its radius r times the cornea's magnification."""
    eye = eye_paraxial(scene)
    cornea = ParaxialSystem(eye.curvatures[:2], eye.gaps[:1], eye.indices[:3])
    radius = scene.eye.surfaces[0].radius_mm
    c = frame.point(eye_point(scene, [0.0, 0.0, -radius]))
    centre, a = row[A_X : A_Z + 1], row[A_AX : A_AZ + 1]
    w = centre - c
    dist = float(np.linalg.norm(w))
    sign = -1.0 if float(w @ a) > 0.0 else 1.0
    u = sign * w / dist
    distance = sign * dist - radius  # the object before the anterior vertex c + R u
    z_eye = scene.eye.surfaces[0].thickness_mm + cornea.image_distance(distance)
    out = row.copy()
    out[A_X : A_Z + 1] = c + (radius - z_eye) * u
    out[A_R] = row[A_R] * abs(cornea.magnification(distance))
    return out


def connected_by_newton(element: Element, n: float) -> bool:
    """Whether next-event estimation connects LEDs through ``element`` by Newton's method
    (:mod:`eyelume.estimators.cornea_nee`): a plate, a plane mirror or a lens of paraxial power
    ≤ 0 (thick lens, index ``n``: φ = φ₁ + φ₂ − (t/n) φ₁ φ₂), whose map of directions to points
    is one to one, so the root Newton finds is the only one. The light through a converging
    lens or off a curved mirror (caustics: several roots) is left to the light paths."""
    if element.kind == "plate":
        return True
    if element.kind == "mirror":
        return math.isinf(element.front.radius_mm)
    front, back = element.surfaces
    p1 = (n - 1.0) * curvature(front.radius_mm)
    p2 = (1.0 - n) * curvature(back.radius_mm)
    t = float(element.thickness_mm or 0.0)
    return p1 + p2 - t / n * p1 * p2 <= 0.0


#: Stratified (u₁, u₂) grid of :func:`element_light_shares`: 64² directions per LED, each
#: carrying 1/4096 of its flux (the LED's own sampler), so a share is resolved to 2.4·10⁻⁴,
#: 4 × finer than :data:`CONVERGING_SHARE_LIMIT`.
_SHARE_GRID = 64


def element_light_shares(cs: CompiledScene) -> np.ndarray:
    """(N_leds, N_elements): the share of each LED's emitted flux whose first hit is one of
    element j's optical surfaces — the light that reaches the eye, the face or the camera only
    through or off that element. A deterministic quadrature: the LED's own direction sampler
    (:func:`eyelume.kernels.sampling.led_direction`, density ∝ I(α)) on a stratified
    64 × 64 grid of midpoints, each direction's first hit by
    :func:`eyelume.kernels.geometry.nearest_hit`; share = hits / 64². Rows follow the
    compiled LED table (:attr:`CompiledScene.led_indices`)."""
    sc = cs.scene
    owner = {}
    for k, el in enumerate(sc.elements):
        label = element_label(k, el)
        for side in _SIDES[: len(el.surfaces)]:
            owner[cs.surface_names.index(f"{label} {side}")] = k
    leds = cs.led
    g = _SHARE_GRID
    u = (np.arange(g) + 0.5) / g
    out = np.zeros((leds.points.shape[0], len(sc.elements)))
    if not owner:
        return out
    for k in range(leds.points.shape[0]):
        p = leds.points[k]
        for u1 in u:
            for u2 in u:
                d = led_direction(leds, k, u1, u2)
                s, _ = G.nearest_hit(cs.sf, cs.si, p[0], p[1], p[2], *d)
                if s in owner:
                    out[k, owner[s]] += 1.0
    return out / (g * g)


#: The largest share of an LED's flux (:func:`element_light_shares`) a converging lens or a
#: curved mirror may take first for the fast estimator to render the scene: what reaches the
#: eye through or off such an element is left to its light paths (Newton's method may have
#: several roots there), which are unbiased but draw that light inefficiently. 10⁻³:
#: paper2005-integrated's eyepiece takes ~6·10⁻⁶ of each LED's flux (a 8192-point Fibonacci
#: sphere weighted by I(α); 0 on this grid: the LEDs beside it, on the eye side, reach its
#: front surface only at α ≈ 65–90°, where I(α)/I₀ < 10⁻³); a converging lens before
#: paper2005's ring (tests/test_elements.py) takes ~24 %.
CONVERGING_SHARE_LIMIT = 1e-3


def _chain_options(sf: np.ndarray, si: np.ndarray, rows: list[int], mirror: bool) -> list[list]:
    """The chains through one element's optical ``rows`` (in the order an LED meets them):
    a mirror's reflection (unless its fixed R is 0) and its transmission (unless its fixed
    T is 0); a plate's or lens's two surfaces, each transmitting."""
    if mirror:
        r = rows[0]
        out = []
        fixed = si[r, G.FRESNEL] == I.R_FIXED
        if not (fixed and sf[r, G.REFL] <= 0.0):
            out.append([(r, REFLECT)])
        if not (fixed and 1.0 - sf[r, G.REFL] - sf[r, G.ABSORB] <= 0.0):
            out.append([(r, TRANSMIT)])
        return out
    return [[(rows[0], TRANSMIT), (rows[1], TRANSMIT)]]


def _element_chains(
    scene: Scene, surfaces: SurfaceTable, names: list[str], points: np.ndarray, cornea: int
) -> tuple[np.ndarray, np.ndarray]:
    """(element_rows, chains) of :class:`CameraTables`: the rows of the elements' optical
    surfaces, and per LED (camera-frame ``points``) the chains of the elements
    :func:`connected_by_newton` connects — an element's surfaces in the order the LED meets
    them (the one it faces first: its local z below the first vertex's plane → front first),
    then, for the iris, the anterior and posterior cornea."""
    sf, si = surfaces.sf, surfaces.si
    element_rows: list[int] = []
    per_element = []
    for k, el in enumerate(scene.elements):
        label = element_label(k, el)
        rows = [names.index(f"{label} {side}") for side in _SIDES[: len(el.surfaces)]]
        element_rows += rows
        if connected_by_newton(el, float(sf[rows[0], G.N_B])):
            per_element.append((rows, el.kind == "mirror"))
    chains = []
    for p in points:
        mine = []
        for rows, mirror in per_element:
            r0 = rows[0]
            local_z = sf[r0, G.R20 : G.R22 + 1] @ (p - sf[r0, G.OX : G.OZ + 1])
            order = rows if local_z < 0.0 else rows[::-1]
            for steps in _chain_options(sf, si, order, mirror):
                row = np.zeros(CHAIN_COLS, dtype=np.int64)
                full = [*steps, (cornea, TRANSMIT_A), (cornea + 1, TRANSMIT_A)]
                row[0], row[1] = len(steps), len(full)
                for j, (r, mode) in enumerate(full):
                    row[2 + j], row[2 + CHAIN_STEPS + j] = r, mode
                mine.append(row)
        chains.append(mine)
    width = max((len(c) for c in chains), default=0)
    table = np.zeros((len(points), width, CHAIN_COLS), dtype=np.int64)
    for k, mine in enumerate(chains):
        for c, row in enumerate(mine):
            table[k, c] = row
    return np.asarray(element_rows, dtype=np.int64), table


def _iris_grid(run) -> int:
    """The continuation grid on the surfaces lit through the cornea (the iris):
    ``run.iris_continuation_grid`` if given, else ``run.continuation_grid`` but at least
    :data:`eyelume.kernels.tables.IRIS_GRID` (3)."""
    from eyelume.kernels.tables import IRIS_GRID

    if run.iris_continuation_grid is not None:
        return int(run.iris_continuation_grid)
    return max(int(run.continuation_grid), IRIS_GRID)


def _camera_tables(  # noqa: PLR0913 - the compiled parts it is made of
    scene: Scene,
    surfaces: SurfaceTable,
    names: list[str],
    lens: LensTable,
    first: FirstOrder,
    stop: int,
    frame: Frame,
    led_points: np.ndarray,
    view: np.ndarray,
) -> CameraTables:
    """The camera as the camera-side estimator sees it (:class:`CameraTables`; the physics in
    :mod:`eyelume.estimators.camera`)."""
    lf = lens.lf
    ep_z = first.entrance_pupil_z
    ep_r = first.entrance_pupil_radius * _PUPIL_MARGIN
    lf_rev = _mirrored_lens(lf)
    lf_open = lf_rev.copy()
    lf_open[:, Q.L_SD] = np.inf
    xp_z, xp_m = first.exit_pupil_z, first.exit_pupil_magnification
    aim = np.zeros((surfaces.sf.shape[0], 2, N_AIM))
    iris_c, iris_r = _cornea_image(scene, frame, ep_z, ep_r)
    through = np.array([name in _IRIS for name in names], dtype=np.int64)
    cornea = names.index(scene.eye.surfaces[0].name)
    # seen through elements (a fold mirror, an eyepiece), light reaches the lens from the face
    # along lines through the pupil's image, not the pupil itself
    image = (
        _pupil_through_elements(surfaces, names, lf, ep_z, ep_r, view) if scene.elements else None
    )
    # the iris is seen through the cornea and then the elements: its light aims at the pupil's
    # image through both, not at the camera's own pupil through the cornea (on
    # paper2005-integrated that lies past the eyepiece's rim, 60° off the camera's axis)
    iris_image = None if image is None else _cornea_image_of_row(scene, frame, image)
    for s, name in enumerate(names):
        if surfaces.si[s, G.ACTION] != G.ACT_OPAQUE:
            continue
        for side, rho_col in ((0, G.RHO_A), (1, G.RHO_B)):
            if surfaces.sf[s, rho_col] <= 0.0:
                continue
            if name in _IRIS and iris_image is not None:
                aim[s, side] = iris_image
                aim[s, side, A_P] = AIM_PROBABILITY
            elif name in _IRIS:
                aim[s, side, : A_P + 1] = (*iris_c, iris_r, AIM_PROBABILITY)
            elif name == "retina" or (name == "sclera" and side == 0):
                continue  # inside the eye behind the crystalline lens: cosine sampling
            elif image is not None:
                aim[s, side] = image
                aim[s, side, A_P] = AIM_PROBABILITY
            else:
                aim[s, side, : A_P + 1] = (0.0, 0.0, ep_z, ep_r, AIM_PROBABILITY)
    return CameraTables(
        lf_rev,
        np.ascontiguousarray(lf_open),
        int(lf.shape[0] - 1 - stop),
        float(lf[stop, Q.L_SD]),
        float(lens.image_z),
        float(lf[-1, Q.L_Z]),
        xp_z,
        xp_m,
        float(ep_z),
        aim,
        through,
        cornea,
        int(scene.run.continuation_grid),
        _iris_grid(scene.run),
        *_element_chains(scene, surfaces, names, led_points, cornea),
        _glint_aims(scene, frame, surfaces, cornea, led_points, (ep_z, ep_r)),
        G.dark_tail(surfaces.sf, surfaces.si),
        np.zeros((0, 0, INDIRECT_COLS)),  # the irradiance cache: built by a run that uses it
        0.0,
        0.0,
    )


#: The sun's stand-in point source lies this far from the eye's nominal corneal vertex (mm).
#: Over the 30 mm of an eye its rays diverge by ±0.09° (the sun's disc: ±0.27°) and the
#: irradiance varies by ±0.3 % (1/r²); a glint of it is a point image like the sun's.
SUN_DISTANCE_MM = 1.0e4
#: Its light reaches the plane through the eye (normal to the sun) out to this radius (mm)
#: about the vertex, uniformly (a flat-topped cone of half-angle atan(150/10⁴) = 0.86°): the
#: eye, lids, brow and cheek an eye camera sees; beyond it the face is not lit by the sun.
SUN_FIELD_RADIUS_MM = 150.0


@dataclass(frozen=True)
class SunSource:
    """The sun as the kernels trace it (:func:`compile_scene` with ``sun``): a point source at
    :data:`SUN_DISTANCE_MM` from the eye's nominal corneal vertex along ``direction`` (toward
    the sun, world frame as the file writes it; mirrored for a left eye), of radiant intensity
    I = E d² in a flat-topped cone reaching ``field_radius_mm`` (default
    :data:`SUN_FIELD_RADIUS_MM`) about the vertex, so that the irradiance normal to the sun at
    the eye is ``irradiance_w_mm2``; traced at ``wavelength_nm``
    (:class:`eyelume.detectors.sensor.SunlightBand`)."""

    direction: tuple[float, float, float]
    irradiance_w_mm2: float
    wavelength_nm: float
    field_radius_mm: float = SUN_FIELD_RADIUS_MM


def _sun_table(
    scene: Scene, sun: SunSource, frame: Frame
) -> tuple[LedTable, np.ndarray, np.ndarray]:
    """The sun's LedTable (one row), Ω_eff (1,) and its world position (1, 3)."""
    d = np.asarray(sun.direction, dtype=float)
    d = as_world(scene, d / np.linalg.norm(d))
    point = eye_point(scene, (0.0, 0.0, 0.0), 0.0, 0.0) + SUN_DISTANCE_MM * d
    world = point[None, :]
    points, axes = world, -d[None, :]
    if not frame.is_identity:
        points, axes = frame.point(points), frame.vector(axes)
    cone = math.atan(sun.field_radius_mm / SUN_DISTANCE_MM)

    def flat_top(alpha):
        return (np.asarray(alpha) <= cone).astype(float)

    alpha_grid, cdf_grid, omega = profile_tables(flat_top)
    i0 = sun.irradiance_w_mm2 * SUN_DISTANCE_MM**2
    table = LedTable(
        np.ascontiguousarray(points),
        np.ascontiguousarray(axes, dtype=float),
        np.array([i0]),
        np.ascontiguousarray(alpha_grid),
        np.ascontiguousarray(cdf_grid[None, :]),
        np.ascontiguousarray(flat_top(alpha_grid)[None, :]),
        np.array([1.0]),
        True,
    )
    return table, np.array([omega]), world


@dataclass(frozen=True)
class WavelengthGroup:
    """The LEDs of one wavelength: ``index`` (0, 1, … in order of increasing wavelength),
    ``wavelength_nm`` and ``leds``, their indices in the scene (increasing)."""

    index: int
    wavelength_nm: float
    leds: tuple[int, ...]


#: LED wavelengths closer than this (nm) are one wavelength group, traced at one wavelength:
#: 850 and 850.0000001 nm are the same LED to any datasheet (whose peak wavelengths are given
#: to 1 nm at best), and rendering them apart costs a whole render each. Over 0.01 nm the
#: indices of the eye and the lens glasses change by ~1e-7 (their dispersion dn/dλ is about
#: 1e-5 per nm near 850 nm), far below any effect on a picture.
WAVELENGTH_TOLERANCE_NM = 0.01


def wavelength_groups(scene: Scene) -> list[WavelengthGroup]:
    """The scene's LEDs grouped by wavelength (each LED's ``leds.wavelength_nm``, the scene's
    ``wavelength_nm`` where not given), in order of increasing wavelength. LEDs within
    :data:`WAVELENGTH_TOLERANCE_NM` of a group's shortest wavelength join that group; the group
    is traced at the scene's ``wavelength_nm`` when that is within the tolerance of the
    group's shortest, else at the mean of its LEDs' wavelengths (each LED's eye-safety weight
    stays at its own wavelength).

    >>> from eyelume.scene.io import load_scene
    >>> s = load_scene("paper2005", {"leds.wavelength_nm": [940, 850, 940, 850]})
    >>> [(g.wavelength_nm, g.leds) for g in wavelength_groups(s)]
    [(850.0, (1, 3)), (940.0, (0, 2))]
    >>> s = load_scene("paper2005", {"leds.wavelength_nm": [850, 850.0000001, 940, 940.004]})
    >>> [(g.wavelength_nm, g.leds) for g in wavelength_groups(s)]
    [(850.0, (0, 1)), (940.002, (2, 3))]
    """
    lams = scene.leds.wavelengths_nm(scene.wavelength_nm)
    order = sorted(range(len(lams)), key=lambda k: lams[k])
    members: list[list[int]] = []
    for k in order:
        if members and lams[k] - lams[members[-1][0]] <= WAVELENGTH_TOLERANCE_NM:
            members[-1].append(k)
        else:
            members.append([k])
    groups = []
    for g, leds in enumerate(members):
        first = lams[leds[0]]
        if abs(float(scene.wavelength_nm) - first) <= WAVELENGTH_TOLERANCE_NM:
            lam = float(scene.wavelength_nm)
        else:
            lam = float(sum(lams[k] for k in leds) / len(leds))
        groups.append(WavelengthGroup(g, lam, tuple(sorted(leds))))
    return groups


def single_wavelength(scene: Scene) -> bool:
    """True when every LED shines at the scene's ``wavelength_nm`` (within
    :data:`WAVELENGTH_TOLERANCE_NM`): the scene compiles and renders as one
    (:func:`compile_scene` without a group)."""
    groups = wavelength_groups(scene)
    return len(groups) == 1 and groups[0].wavelength_nm == float(scene.wavelength_nm)


def compile_scene(
    scene: Scene,
    group: WavelengthGroup | None = None,
    *,
    nominal: CompiledScene | None = None,
    sun: SunSource | None = None,
) -> CompiledScene:
    """Turn a validated scene into the tables the kernels read, one scene part at a time.
    Raises SceneError on geometry that cannot exist (crossing lens surfaces, LEDs inside the
    lens, the eye, the face or the camera body, a missing glass).

    Without ``group``: the scene at its ``wavelength_nm`` with every LED emitting — for a scene
    whose LEDs have several wavelengths, the nominal compile that geometry, truth, masks and the
    layout use; :func:`eyelume.render.render` renders such a scene group by group.

    With ``group`` (:func:`wavelength_groups`): the scene traced at the group's wavelength (the
    eye's and the lens's indices, the cornea's Fresnel reflection; ``scene`` of the result
    carries that ``wavelength_nm``) with only the group's LEDs emitting (the LED table's rows,
    ``led_ids`` their indices in the scene); every LED's body is still there (an absorber,
    whichever LEDs emit). A prescription lens keeps the clear apertures of the lens as built,
    sized at the scene's wavelength (from ``nominal``, that compile, made here if not given).

    With ``sun`` (:class:`SunSource`): the scene traced at the sun's wavelength like a group,
    its only source the sun (``led_ids`` = (), ``sun`` set); the LEDs' bodies stay.
    """
    scene = with_contact_lens(scene)  # a contact lens is built into the eye (scene/eye.py)
    if sun is not None:
        group = WavelengthGroup(-1, float(sun.wavelength_nm), ())
    if group is not None:
        if scene.camera.optics == "prescription" and nominal is None:
            nominal = compile_scene(scene)
        scene = scene.model_copy(update={"wavelength_nm": float(group.wavelength_nm)})
    frame = scene_frame(scene)
    t = _Table(frame)
    if scene.camera.optics == "ideal":
        lens, idx, stop = _compile_ideal(scene)
    elif group is not None:
        assert nominal is not None
        lens, idx, stop = _compile_lens(scene, nominal.lf[:, Q.L_SD].tolist())
    else:
        lens, idx, stop = _compile_lens(scene)
    fixed_stop = group is not None and scene.camera.optics == "prescription"
    first = _first_order(scene, lens, idx, stop, fixed_stop)
    _add_eye(t, scene)
    _add_face(t, scene)
    _add_lashes(t, scene)
    centres, axes = led_world_poses(scene)
    _check_leds(scene, centres, lens.lf, frame, axes)
    _check_leds_in_head(scene, centres, axes=axes)
    _check_leds_outside_camera_body(scene, centres, lens.lf, frame, axes)
    _add_led_bodies(t, scene, centres, axes)
    world = centres, axes
    if not frame.is_identity:
        centres, axes = frame.point(centres), frame.vector(axes)
    if sun is not None:
        led, omega, _ = _sun_table(scene, sun, frame)
    else:
        led, omega = _led_table(scene, centres, axes, None if group is None else group.leds)
    if group is None:  # a group's LEDs were looked at in the nominal compile
        _check_leds_light_the_eye(scene, *world, led)
    lens_row = len(t.rows_f)
    _add_lens_entrance(t, lens.lf)
    _add_camera_body(t, scene, lens.lf, lens_row)
    if scene.elements:
        _check_elements(scene, *world)
        _check_elements_clear_of_camera(scene, lens.lf, frame)
        _add_elements(t, scene)
    surfaces = SurfaceTable(
        np.ascontiguousarray(_stack_rows(t.rows_f)), np.ascontiguousarray(np.stack(t.rows_i))
    )
    picture, eye_plane = _grids(scene, frame)
    # refused or warned about at the scene's own wavelength only
    strict = group is None and sun is None
    folded, view = _view_through_elements(scene, surfaces, t.names, lens.lf, strict=strict)
    _check_view(scene, frame, first, picture, straight=not folded)
    tables = SceneTables(surfaces, lens, led, picture, eye_plane, int(scene.run.max_events))
    return CompiledScene(
        scene=scene,
        tables=tables,
        camera=_camera_tables(scene, surfaces, t.names, lens, first, stop, frame, led.points, view),
        surface_names=t.names,
        lens_indices=idx,
        stop_index=stop,
        led_centres=centres,
        omega_eff=omega,
        tallies=t.tallies,
        frame=frame,
        first_order=first,
        led_ids=None if group is None else group.leds,
        sun=sun,
        view_branch=view,
    )


def scene_frame(scene: Scene) -> Frame:
    """The world → camera-frame transform of ``scene`` (:mod:`eyelume.scene.pose`). Raises
    SceneError when the camera's view has no direction."""
    pos, view, roll = camera_pose(scene)
    return camera_frame(pos, view, roll, scene.object_distance_mm)
