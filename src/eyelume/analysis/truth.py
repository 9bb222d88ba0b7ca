"""Ground truth of a rendered eye: where the pupil and the glints truly image on the sensor.

Both come from the same real rays the renderer uses: the chief ray of a sensor point (through
the stop's centre, :func:`eyelume.estimators.camera.aim_chief`) leaves the lens into the scene;

* a pupil point P (on the pupil's edge, or its centre) images where the chief ray, refracted by
  the anterior and posterior cornea, passes through P — found by Newton's method on the sensor
  point, so the truth is the *apparent* pupil a camera sees through the cornea;
* LED k's glint images where the chief ray, reflected by the anterior cornea, passes through the
  LED's emission point (the centre of the blur disc of the first Purkinje image);
* an LED the camera sees directly images where the chief ray itself passes through its
  emission point.

With optical elements in the scene, every such ray is followed through the elements it meets
on its way (refracted by a window or lens, folded by a mirror: the branch the camera's view
takes, :func:`_through_elements` — the stronger of the reflected and transmitted ones, except
where the view of the eye takes the other, a beamsplitter's fold with R ≤ T), so the truth is
what the camera sees through and in them. Each spectacle ghost (an LED's image by a chain of
one or two specular reflections off element surfaces and the cornea) is listed under
``ghosts``
(:mod:`eyelume.analysis.ghosts`: its chain, pixel and flux); a scene without elements has no
``ghosts`` key.

Pixel coordinates follow OpenCV's convention on the upright picture: pixel (column c, row r) has
its centre at (x, y) = (c, r), row 0 at the top. A point is *visible* when nothing (an eyelid,
the lens mount) blocks its rays; a glint whose chief ray's reflection point falls outside the
cornea's cap has no ``centre_px`` (``on_cornea`` False) — unless the rays through part of the
camera's aperture still reflect off the cap: then a partial spot, cut by the cornea's rim, is in
the picture, and the glint is marked ``at_rim`` (as is one on the cap whose aperture's rays
partly fall past it), with where that spot's centroid lies (:func:`_rim_glint`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from eyelume.analysis.tracking.gaze import angles_from_axis, axis_from_angles
from eyelume.compile import (
    CompiledScene,
    compile_scene,
    eye_direction,
    eye_point,
    gaze_rotation,
    led_body_rows,
    single_wavelength,
    wavelength_groups,
)
from eyelume.detectors.receivers import BinnedPlane
from eyelume.errors import GeometryError
from eyelume.estimators.camera import aim_chief, aim_into_scene, into_scene
from eyelume.kernels import geometry as G
from eyelume.kernels.interact import interface_at, reflect, refract
from eyelume.kernels.sampling import orthonormal_basis, radiant_intensity
from eyelume.kernels.tables import CameraTables

__all__ = ["eye_truth", "glint_counts", "sclera_reflection", "sensor_to_pixel"]

_H = 1e-4  # mm on the sensor: forward-difference step
_EDGE_POINTS = 72


def sensor_to_pixel(cs: CompiledScene, xs: float, ys: float) -> tuple[float, float]:
    """Sensor-plane point (mm) → picture pixel coordinates (OpenCV convention, module doc)."""
    c, r = BinnedPlane(cs.picture).to_pixel(xs, ys)
    return float(c), float(r)


def _chief_ray(
    cs: CompiledScene, cam: CameraTables, xs: float, ys: float, target=None, share=False
):
    """The chief ray of sensor point (xs, ys) in the scene, past the optical elements it meets
    first (:func:`_through_elements`; before ``target`` when given), or None; with ``share``
    also the power share its element branches pass (:func:`_element_path`)."""
    chief = aim_chief(cam, xs, ys)
    if not chief.found:
        return None
    ok, x, y, z, dx, dy, dz, _ = into_scene(cam, xs, ys, chief.qx, chief.qy)
    if not ok:
        return None
    p, d, w = _element_path(cs, np.array([x, y, z]), np.array([dx, dy, dz]), target)
    return (p, d, w) if share else (p, d)


_ELEMENT_EVENTS = 16  # element surfaces a truth ray may cross or be folded by


def _through_elements(cs: CompiledScene, p: np.ndarray, d: np.ndarray, target=None):
    """The ray (p, d) past the optical elements (:attr:`eyelume.scene.model.Scene.elements`)
    it meets before any other surface (and, given ``target``, before passing it): at each
    element surface the branch of the camera's view (:func:`_view_branch`) — the path an
    image seen through or in the elements takes. A scene without elements: (p, d)
    unchanged."""
    return _element_path(cs, p, d, target)[:2]


def _element_path(cs: CompiledScene, p: np.ndarray, d: np.ndarray, target=None):
    """:func:`_through_elements`'s ray and the share of the power its branches carry (the
    product of their T or R: 0 behind an opaque element, 1 without elements)."""
    share = 1.0
    if not cs.scene.elements:
        return p, d, share
    for _ in range(_ELEMENT_EVENTS):
        s, t = G.nearest_hit(cs.sf, cs.si, *p, *d)
        if s < 0 or not cs.surface_names[s].startswith("element "):
            break
        if target is not None and t > (target - p) @ d:
            break
        p = p + t * d
        d, w = _view_branch(cs, s, p, d)
        share *= w
    return p, d, share


def view_reflects(cs: CompiledScene, s: int, reflectance: float, transmittance: float) -> bool:
    """Whether the camera's view takes the reflected branch at element surface ``s`` (of
    these R and T): as the compile found the view of the eye (``cs.view_branch``,
    :func:`eyelume.compile._view_through_elements`: a beamsplitter's fold even where R ≤ T),
    and off that branch the stronger part (R > T)."""
    v = -1 if cs.view_branch is None else int(cs.view_branch[s])
    return v == 1 or (v < 0 and reflectance > transmittance)


def _view_branch(cs: CompiledScene, s: int, p: np.ndarray, d: np.ndarray):
    """At point ``p`` of element surface ``s``: the direction of ray direction ``d`` along the
    camera's view (:func:`view_reflects`; reflected on total internal reflection) and that
    branch's share of the power (T or R)."""
    n = np.array(G.surface_normal(cs.sf, cs.si, s, *p))
    f = interface_at(cs.sf, cs.si, s, float(d @ n))
    ok, *dt = refract(*d, *n, f.n1 / f.n2)
    t = 1.0 - f.reflectance - f.absorptance
    if ok and not view_reflects(cs, s, f.reflectance, t):
        d, w = np.array(dt), t
    else:
        d, w = np.array(reflect(*d, *n)), (f.reflectance if ok else 1.0)
    return d / np.linalg.norm(d), float(w)


def _through_cornea(cs: CompiledScene, cornea: int, p: np.ndarray, d: np.ndarray):
    """The ray after refraction at both cornea surfaces, or None."""
    for s in (cornea, cornea + 1):
        t = G.intersect_surface(cs.sf, cs.si, s, *p, *d, math.inf)
        if t < 0:
            return None
        p = p + t * d
        n = np.array(G.surface_normal(cs.sf, cs.si, s, *p))
        ok, *dd = refract(*d, *n, cs.sf[s, G.N_A] / cs.sf[s, G.N_B])
        if not ok:
            return None
        d = np.array(dd)
    return p, d


def _off_cornea(cs: CompiledScene, cornea: int, p: np.ndarray, d: np.ndarray, sf=None):
    """The ray reflected by the anterior cornea, or None if it misses the cap; ``sf``: another
    surface table (:func:`_open_cap`'s, the cap extended past the limbus)."""
    sf = cs.sf if sf is None else sf
    t = G.intersect_surface(sf, cs.si, cornea, *p, *d, math.inf)
    if t < 0:
        return None
    p = p + t * d
    n = np.array(G.surface_normal(sf, cs.si, cornea, *p))
    return p, np.array(reflect(*d, *n))


def _open_cap(cs: CompiledScene, cornea: int) -> np.ndarray:
    """The surface table with the anterior cornea's surface extended past its cap (no radial or
    depth limits: the same conicoid or quadric beyond the limbus), for the reflection points of
    a glint cut by the cornea's rim (:func:`_rim_glint`)."""
    sf = cs.sf.copy()
    sf[cornea, G.RMAX2] = math.inf
    sf[cornea, G.ZLO] = -math.inf
    sf[cornea, G.ZHI] = math.inf
    return sf


def _stop_ray(
    cs: CompiledScene, cam: CameraTables, xs: float, ys: float, tx: float, ty: float, share=False
):
    """The ray from sensor point (xs, ys) through point (tx, ty) of the camera's stop (mm, the
    stop's frame; (0, 0): the chief ray) in the scene, past the optical elements, or None; with
    ``share`` also the power share its element branches pass (:func:`_element_path`)."""
    chief = aim_chief(cam, xs, ys)
    if not chief.found:
        return None
    _, r = aim_into_scene(
        cam, float(xs), float(ys), float(tx), float(ty), chief.qx, chief.qy, chief.jac
    )
    if not r.passed:
        return None
    p, d, w = _element_path(cs, np.array([r.x, r.y, r.z]), np.array([r.dx, r.dy, r.dz]))
    return (p, d, w) if share else (p, d)


def _miss(ray, target: np.ndarray, normal: np.ndarray, e1: np.ndarray, e2: np.ndarray):
    """Where ``ray`` meets the plane through ``target`` with ``normal``, in the basis (e1, e2)."""
    if ray is None:
        return None
    p, d = ray
    den = d @ normal
    if abs(den) < 1e-12:
        return None
    h = p + ((target - p) @ normal) / den * d - target
    return np.array([h @ e1, h @ e2])


def _solve(residual, guess: np.ndarray, tol: float = 1e-7):
    """Newton's method on a 2D residual of the sensor point; None if it fails."""
    x = np.array(guess, dtype=float)
    for _ in range(40):
        r = residual(x)
        if r is None:
            return None
        if r @ r < tol * tol:
            return x
        jac = np.empty((2, 2))
        for k in range(2):
            step = np.zeros(2)
            step[k] = _H
            rk = residual(x + step)
            if rk is None:
                return None
            jac[:, k] = (rk - r) / _H
        try:
            x = x - np.linalg.solve(jac, r)
        except np.linalg.LinAlgError:
            return None
    return None


def _basis(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors completing unit ``n`` to an orthonormal basis."""
    t, b = orthonormal_basis(*n)
    return np.array(t), np.array(b)


def _clear(cs: CompiledScene, start: np.ndarray, d: np.ndarray, expect: int) -> bool:
    s, _ = G.nearest_hit(cs.sf, cs.si, *start, *d)
    return s == expect


@dataclass
class _View:
    """What every truth query shares: the compiled scene, the camera, the cornea's surface
    index, and the eye's optical axis (camera frame) with a basis ``e1``, ``e2`` across it; the
    eye's pose, gaze and slip come from :func:`eyelume.compile.eye_point`."""

    cs: CompiledScene
    cam: CameraTables
    cornea: int
    axis: np.ndarray
    e1: np.ndarray
    e2: np.ndarray
    par_m: float  # paraxial guess scale
    open_sf: np.ndarray | None = None  # the surface table with the cap extended (_open_cap)

    def turned(self, p: np.ndarray) -> np.ndarray:
        """A primary-gaze eye point (world mm), turned with the gaze and moved with the head,
        in the camera frame (where the compiled scene is traced)."""
        return self.cs.frame.point(eye_point(self.cs.scene, p))

    def image_of(self, point: np.ndarray, guess: np.ndarray | None = None):
        """The sensor point (mm) whose chief ray, refracted by the cornea, passes through
        ``point`` (an eye point seen through the cornea), or None. ``guess``: a sensor point
        (mm) to start Newton's method from first (a neighbouring point's image)."""
        cs, cam, cornea = self.cs, self.cam, self.cornea

        def residual(s):
            ray = _chief_ray(cs, cam, s[0], s[1])
            ray = None if ray is None else _through_cornea(cs, cornea, *ray)
            return _miss(ray, point, self.axis, self.e1, self.e2)

        found = None if guess is None else _solve(residual, np.asarray(guess, float))
        if found is None:
            found = _solve(residual, np.array([-point[0], -point[1]]) * abs(self.par_m))
        if found is None and cs.scene.elements:  # a folded view: the straight guess misleads
            found = _solve(residual, np.zeros(2))
        if found is None and cs.scene.elements:
            # the eye turned far (paper2005-integrated at ±30°): the picture's centre looks
            # past the turned cornea's cap, so Newton from there meets rays that miss it;
            # start from the point's own image without the cornea (its chief ray through the
            # elements alone, which meets no cap), a fraction of a millimetre away
            straight = _direct_image(self, point, _line_of_sight(self))
            if straight is not None:
                found = _solve(residual, straight)
        return found


def _view(cs: CompiledScene, cam: CameraTables) -> _View:
    eye = cs.scene.eye
    # the optical axis, out of the eye (gaze, and a left eye's mirror)
    axis = cs.frame.vector(eye_direction(cs.scene, [0.0, 0.0, 1.0]))
    e1, e2 = _basis(axis)
    cornea = cs.surface_names.index(eye.surfaces[0].name)
    return _View(
        cs=cs,
        cam=cam,
        cornea=cornea,
        axis=axis,
        e1=e1,
        e2=e2,
        par_m=-(cs.image_z - cam.entrance_pupil_z) / (cam.entrance_pupil_z),
        open_sf=_open_cap(cs, cornea),
    )


def _from_neighbours(found: list, solve) -> None:
    """Fill the unsolved entries (None) of ``found`` — the sensor points (mm) of points round a
    closed outline, in order — by ``solve(k, guess)`` (a sensor point or None) from the
    neighbour's solution, going round the outline forward and then backward, in place."""
    n = len(found)
    for order in (range(n), range(n - 1, -1, -1)):
        for k in order:
            prev = found[(k - order.step) % n]
            if found[k] is None and prev is not None:
                found[k] = solve(k, prev)


#: :func:`_scan_start`'s grid over the picture (columns, rows)
_SCAN = (41, 31)


def _scan_start(v: _View, point: np.ndarray) -> np.ndarray | None:
    """The sensor point (mm) of a :data:`_SCAN` grid over the picture whose chief ray, refracted
    by the cornea, passes nearest ``point`` (measured across the eye's axis), or None when no
    ray of the grid passes the cornea: a start for :meth:`_View.image_of` where the paraxial
    guess's ray misses the cornea."""
    cs = v.cs
    half_w, half_h = cs.picture.width_mm / 2, cs.picture.height_mm / 2
    best, start = math.inf, None
    for xs in np.linspace(-half_w, half_w, _SCAN[0]):
        for ys in np.linspace(-half_h, half_h, _SCAN[1]):
            ray = _chief_ray(cs, v.cam, xs, ys)
            ray = None if ray is None else _through_cornea(cs, v.cornea, *ray)
            miss = _miss(ray, point, v.axis, v.e1, v.e2)
            if miss is not None and miss @ miss < best:
                best, start = float(miss @ miss), np.array([xs, ys])
    return start


def _pupil_truth(v: _View, pupil_c: np.ndarray) -> dict:
    """The apparent pupil: its centre's and 72 edge points' pixels, the share visible.

    Newton's method from the paraxial guess (:meth:`_View.image_of`) fails where that guess's
    chief ray misses the cornea — an eye turned far from an off-axis camera (vr-offaxis at
    (−30°, 20°): 45 of the 72 edge points and the centre, whose chief rays all pass the
    cornea); those start again from a neighbour's image, going round the outline both ways,
    and the centre from the mean of the edge's images. Where no start converged at all
    (glasses-frame at (−30°, 0°)), the centre starts from the ray of a coarse scan of the
    picture that passes nearest it (:func:`_scan_start`), and the edge from the centre's
    image (from that ray where the centre itself lies past the cornea's rim)."""
    cs, eye = v.cs, v.cs.scene.eye
    r = eye.pupil_diameter_mm / 2
    points = [
        pupil_c + r * (math.cos(a) * v.e1 + math.sin(a) * v.e2)
        for a in 2 * np.pi * np.arange(_EDGE_POINTS) / _EDGE_POINTS
    ]
    found = [v.image_of(point) for point in points]
    sc = v.image_of(pupil_c)
    if sc is None and not any(s is not None for s in found):
        # not one start converged (glasses-frame at (−30°, 0°): the whole pupil seen through
        # the cornea, its chief rays a few of a coarse scan's): from the scan's ray nearest
        # the centre, and the edge from the centre's image
        start = _scan_start(v, pupil_c)
        sc = None if start is None else v.image_of(pupil_c, start)
        if start is not None:  # (the centre itself may lie past the rim: from the scan's ray)
            found = [v.image_of(point, start if sc is None else sc) for point in points]
    _from_neighbours(found, lambda k, guess: v.image_of(points[k], guess))
    images = [s for s in found if s is not None]
    if sc is None and images:
        sc = v.image_of(pupil_c, np.mean(images, axis=0))
    edge, seen = [], 0
    for s in found:
        if s is None:
            continue
        edge.append(sensor_to_pixel(cs, *s))
        ray = _chief_ray(cs, v.cam, *s, share=True)
        if ray is not None and ray[2] > 0.0 and _clear(cs, ray[0], ray[1], v.cornea):
            seen += 1
    return {
        "centre_mm": cs.frame.world_point(pupil_c).tolist(),
        "diameter_mm": eye.pupil_diameter_mm,
        "centre_px": None if sc is None else list(sensor_to_pixel(cs, *sc)),
        "edge_px": [list(p) for p in edge],
        "visible_fraction": seen / _EDGE_POINTS,
    }


def _line_of_sight(v: _View) -> np.ndarray | None:
    """The direction (camera frame, unit) from the scene back toward the camera along the chief
    ray of the sensor's centre, past the optical elements (a folded view's last leg)."""
    ray = _chief_ray(v.cs, v.cam, 0.0, 0.0)
    return None if ray is None else -ray[1] / np.linalg.norm(ray[1])


def _direct_image(
    v: _View, point: np.ndarray, toward: np.ndarray | None = None, guess: np.ndarray | None = None
):
    """The sensor point (mm) whose chief ray (past the optical elements, which lie between the
    eye and the camera) passes through ``point`` (camera frame) itself, with no refraction by
    the eye: a point on the eye's outer surface, e.g. the limbus. The miss is measured across
    ``toward`` (the direction the ray arrives from, reversed: :func:`_line_of_sight`; default
    the straight line to the entrance pupil); ``guess``: a sensor point (mm) to start from
    first. None when it is not found."""
    cs, cam = v.cs, v.cam
    ep = np.array([0.0, 0.0, cam.entrance_pupil_z])
    if point[2] >= ep[2] and not cs.scene.elements:
        return None
    n = (ep - point) / np.linalg.norm(ep - point) if toward is None else toward
    g1, g2 = _basis(n)

    def residual(s):  # past every element: they all lie between the eye and the camera
        return _miss(_chief_ray(cs, cam, s[0], s[1]), point, n, g1, g2)

    # guesses: the pinhole image through the entrance pupil, then (a view through elements
    # may be folded: a straight guess can find a ray that misses a mirror and runs straight
    # to the point, imaged far outside the picture) the picture's centre
    guesses = [-(cs.image_z - ep[2]) / (ep[2] - point[2]) * point[:2]]
    if guess is not None:
        guesses.insert(0, guess)
    if cs.scene.elements:
        guesses.append(np.zeros(2))
    half = np.array([cs.picture.width_mm, cs.picture.height_mm])  # twice the half-size
    found = None
    for guess in guesses:
        found = _solve(residual, guess)
        if found is not None and np.all(np.abs(found) <= half):
            return found
    return found


def _seen_on_eye(v: _View, s: np.ndarray, point: np.ndarray, tol_mm: float = 0.05) -> bool:
    """Whether the chief ray of sensor point ``s`` (mm) first meets the eye within ``tol_mm``
    of ``point`` or beyond it on an eye surface (nothing of the face, a lash or an opaque
    element before it): the point is not under a lid."""
    ray = _chief_ray(v.cs, v.cam, *s, share=True)
    if ray is None or ray[2] <= 0.0:
        return False
    p, d, _ = ray
    hit, t = G.nearest_hit(v.cs.sf, v.cs.si, *p, *d)
    if hit < 0:
        return False
    eye_names = {x.name for x in v.cs.scene.eye.surfaces} | {"iris", "iris root", "sclera"}
    return v.cs.surface_names[hit] in eye_names and t >= (point - p) @ d - tol_mm


def _iris_truth(v: _View) -> dict:
    """The apparent iris's outline: the limbus (the corneoscleral junction, the anterior
    cornea's clear-aperture edge of radius r_l at depth z_l behind the corneal vertex,
    :func:`eyelume.scene.eye.limbus_geometry`), 72 points turned with the eye and imaged by the
    chief ray through each (:func:`_direct_image`: they lie on the eye's outer surface, so no
    refraction), and the share of them not under a lid or its lashes (:func:`_seen_on_eye`).
    The picture's iris region ends there: the iris's own outer edge
    (``iris_outer_diameter_mm``), seen through the cornea magnified about 1.13 times, lies
    behind the sclera at the limbus (5.5 mm × 1.13 > 6.0 mm for the presets' eyes), so what
    a camera sees of the iris, root included, is bounded by the limbus."""
    from eyelume.scene.eye import limbus_geometry

    cs = v.cs
    r_l, z_l, _ = limbus_geometry(cs.scene.eye)
    toward = _line_of_sight(v) if cs.scene.elements else None
    points = [
        v.turned(np.array([r_l * math.cos(a), r_l * math.sin(a), -z_l]))
        for a in 2 * np.pi * np.arange(_EDGE_POINTS) / _EDGE_POINTS
    ]
    found = [_direct_image(v, p, toward) for p in points]
    # Newton may not converge from the straight guesses through a folded view: start those
    # from a neighbour's solution, going round the circle both ways
    _from_neighbours(found, lambda k, guess: _direct_image(v, points[k], toward, guess))
    limbus, seen = [], 0
    for s, point in zip(found, points, strict=True):
        if s is not None:
            limbus.append(sensor_to_pixel(cs, *s))
            seen += _seen_on_eye(v, s, point)
    return {
        "centre_mm": cs.frame.world_point(v.turned(np.array([0.0, 0.0, -z_l]))).tolist(),
        "diameter_mm": 2 * r_l,
        "edge_px": [list(p) for p in limbus],
        "visible_fraction": seen / _EDGE_POINTS,
    }


def sclera_reflection(cs: CompiledScene, k: int) -> list[float] | None:
    """The pixel (c, r) where LED ``k``'s mirror image in the eyeball's sclera sphere lies: the
    sensor point whose chief ray, reflected by the sclera (the eyeball sphere behind the limbus,
    :func:`eyelume.scene.eye.limbus_geometry`), passes through the LED's emission point, the
    sclera being the first thing that ray meets. A real eye's moist sclera shows a weak glint
    there when the corneal glint has slid off the cornea; eyelume renders the sclera as
    Lambertian, so the picture has no spot there. None when there is no such point."""
    from eyelume.scene.eye import limbus_geometry

    v = _view(cs, cs.camera)
    sclera = cs.surface_names.index("sclera")
    led = cs.led.points[cs.led_indices.index(k)]
    eyeball = v.turned(np.array([0.0, 0.0, -limbus_geometry(cs.scene.eye)[2]]))
    n = (led - eyeball) / np.linalg.norm(led - eyeball)
    g1, g2 = _basis(n)

    def residual(s):
        ray = _chief_ray(cs, v.cam, s[0], s[1])
        ray = None if ray is None else _off_cornea(cs, sclera, *ray)
        ray = None if ray is None else _through_elements(cs, *ray, led)
        return _miss(ray, led, n, g1, g2)

    ep = np.array([0.0, 0.0, v.cam.entrance_pupil_z])
    bis = n + (ep - eyeball) / np.linalg.norm(ep - eyeball)
    q = eyeball + cs.scene.eye.sclera_radius_mm * bis / np.linalg.norm(bis)
    s = _solve(residual, -(cs.image_z - ep[2]) / (ep[2] - q[2]) * q[:2])
    if s is None:
        return None
    ray = _chief_ray(cs, v.cam, *s)
    if ray is None or G.nearest_hit(cs.sf, cs.si, *ray[0], *ray[1])[0] != sclera:
        return None
    return list(sensor_to_pixel(cs, *s))


def _glint_truth(v: _View, k: int, led: np.ndarray, row: int) -> dict:
    """LED ``k``'s glint (row ``row`` of the compiled LED table): the pixel whose chief ray the
    cornea reflects to the LED, and whether the way in and out is clear and the LED sends light
    that way (its profile I(α) > 0 toward the cornea); ``at_rim`` and ``rim``
    (:func:`_rim_glint`) when the cornea's rim cuts the rays through part of the camera's
    aperture, whether or not the chief ray's reflection lies on the cap."""
    cs, cam, cornea = v.cs, v.cam, v.cornea
    to_led = led - v.turned(np.array([0.0, 0.0, -cs.scene.eye.surfaces[0].radius_mm]))
    n = to_led / np.linalg.norm(to_led)
    g1, g2 = _basis(n)

    def residual(s):
        ray = _chief_ray(cs, cam, s[0], s[1])
        ray = None if ray is None else _off_cornea(cs, cornea, *ray)
        ray = None if ray is None else _through_elements(cs, *ray, led)
        return _miss(ray, led, n, g1, g2)

    # first guess: the corneal centre's image, shifted toward the LED (a far source, the
    # sun's stand-in 10 m away, as if at an LED's distance along its direction)
    c_img = v.image_of(v.turned(np.array([0.0, 0.0, -3.9])))
    near = led if np.linalg.norm(led) < 1e3 else led * (70.0 / np.linalg.norm(led))
    guess = (c_img if c_img is not None else np.zeros(2)) - 0.05 * abs(v.par_m) * near[:2]
    s = _solve(residual, guess)
    entry: dict = {
        "led": k,
        "centre_px": None,
        "on_cornea": False,
        "visible": False,
        "reason": "",
        "at_rim": False,
        "rim": None,
        "partly_blocked": None,
    }
    rim = _rim_glint(v, k, row, led, (n, g1, g2), guess if s is None else s)
    if rim is not None and 0.0 < rim["aperture_share"] < 1.0:
        entry["at_rim"] = True
        entry["rim"] = rim
    if s is None:
        entry["reason"] = "no reflection toward this LED on the cornea's cap (off the cornea)"
        if entry["at_rim"]:
            entry["reason"] = (
                f"cut by the cornea's rim: the chief ray's mirror point lies "
                f"{rim['beyond_rim_mm']:.3f} mm past the limbus, but rays through "
                f"{100 * rim['aperture_share']:.0f} % of the camera's aperture reflect off the "
                f"cap: a partial spot at {_fmt_px(rim['centre_px'])} px (see rim)"
            )
        return entry
    entry["on_cornea"] = True
    entry["centre_px"] = list(sensor_to_pixel(cs, *s))
    chief = _chief_ray(cs, cam, *s, share=True)
    entry["visible"], entry["reason"] = _glint_seen(v, k, row, led, *chief)
    if entry["reason"].startswith("the LED sends no light"):
        return entry
    clear = _aperture_clear(v, k, row, led, (n, g1, g2), s)
    if clear is not None and clear["aperture_share"] > 0.0:
        entry["partly_blocked"] = clear
        if not entry["visible"]:
            # a lash across the chief ray, some of the stop's rays past it: the spot is in the
            # picture, dimmed, its centroid on the clear part
            entry["visible"] = True
            entry["reason"] = (
                f"partly blocked (an eyelid or its lashes, the face or an opaque element): the "
                f"chief ray is hidden, but rays through {100 * clear['aperture_share']:.0f} % "
                f"of the camera's aperture are clear: a dimmed spot at "
                f"{_fmt_px(clear['centre_px'])} px (see partly_blocked)"
            )
    return entry


def _fmt_px(c) -> str:
    return "none" if c is None else f"({c[0]:.2f}, {c[1]:.2f})"


def _glint_seen(v: _View, k: int, row: int, led: np.ndarray, p, d, share_in: float):
    """(visible, reason) of LED ``k``'s glint along the camera ray (p, d) (past the elements,
    carrying ``share_in`` of the power): the way in and out clear and the LED sending light
    back along it (I(α) > 0)."""
    cs, cornea = v.cs, v.cornea
    hit = _off_cornea(cs, cornea, p, d)
    share_out = 1.0
    if hit is not None:
        *hit, share_out = _element_path(cs, *hit, led)
    blocked_in = share_in <= 0.0 or not _clear(cs, p, d, cornea)
    blocked_out = share_out <= 0.0
    blocked_out = (
        blocked_out
        or hit is None
        or G.nearest_hit(cs.sf, cs.si, *hit[0], *hit[1])[0]
        not in (*led_body_rows(cs.surface_names, k), -1)
    )
    dark = hit is not None and float(radiant_intensity(cs.led, row, *(-hit[1]))) <= 0.0
    visible = not (blocked_in or blocked_out or dark)
    reason = (
        ""
        if visible
        else "the LED sends no light this way (beyond its angular profile)"
        if dark and not (blocked_in or blocked_out)
        else "blocked (an eyelid or its lashes, the face or an opaque element)"
    )
    return visible, reason


def _rim_seen(v: _View, k: int, row: int, led: np.ndarray, s, t) -> bool:
    """:func:`_glint_seen` along the ray from sensor point ``s`` through stop point ``t``."""
    ray = _stop_ray(v.cs, v.cam, float(s[0]), float(s[1]), *t, share=True)
    return ray is not None and _glint_seen(v, k, row, led, *ray)[0]


def _stop_solves(v: _View, led: np.ndarray, frame, h: float, guess) -> list | None:
    """LED ``led``'s glint through the stop points t = (0, 0), (±h, 0), (0, ±h) (mm, the
    stop's frame): for each, the sensor point s(t) (mm) whose ray through t the cornea's
    anterior surface, extended past the limbus (:func:`_open_cap`), reflects to the LED, and
    that mirror point's (x, y) in the surface's local frame (mm) — Newton from ``guess`` (a
    sensor point), then from s(0). ``frame``: (n, e1, e2), the plane through the LED the
    reflected ray is aimed at (:func:`_miss`). None when a solve fails (the ray through the
    stop's edge vignetted, or no mirror point)."""
    cs, cam, cornea = v.cs, v.cam, v.cornea
    n, g1, g2 = frame
    sf = v.open_sf

    def mirror(t, start):
        def residual(s):
            ray = _stop_ray(cs, cam, s[0], s[1], *t)
            ray = None if ray is None else _off_cornea(cs, cornea, *ray, sf=sf)
            ray = None if ray is None else _through_elements(cs, *ray, led)
            return _miss(ray, led, n, g1, g2)

        s = _solve(residual, start)
        ray = None if s is None else _stop_ray(cs, cam, *s, *t)
        hit = None if ray is None else _off_cornea(cs, cornea, *ray, sf=sf)
        if hit is None:
            return None
        return s, np.array(G.to_local(sf, cornea, *hit[0]))[:2]

    stops = [(0.0, 0.0), (h, 0.0), (-h, 0.0), (0.0, h), (0.0, -h)]
    got = [mirror(stops[0], np.asarray(guess, float))]
    if got[0] is None:
        return None
    for t in stops[1:]:
        got.append(mirror(t, got[0][0]))
        if got[-1] is None:
            return None
    return got


def _stop_grid(side: int, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """The centres (tx, ty) of a ``side`` × ``side`` square grid over [−reach, reach]² that lie
    within the disc of radius ``reach`` (units of the samples' spacing h of
    :func:`_stop_solves`)."""
    u = ((np.arange(side) + 0.5) / side * 2.0 - 1.0) * reach
    tx, ty = np.meshgrid(u, u)
    keep = tx * tx + ty * ty <= reach * reach
    return tx[keep], ty[keep]


def _stop_model(f, tx: np.ndarray, ty: np.ndarray) -> np.ndarray:
    """f(t) = f₀ + c₁ t_x + c₂ t_x² + c₃ t_y + c₄ t_y² (N, 2) at the stop points (``tx``,
    ``ty``), through the five samples ``f`` (5, 2) at t = 0, +x, −x, +y, −y (one unit out)."""
    f = np.asarray(f, float)
    return (
        f[0]
        + np.outer(tx, (f[1] - f[2]) / 2)
        + np.outer(tx * tx, (f[1] + f[2] - 2 * f[0]) / 2)
        + np.outer(ty, (f[3] - f[4]) / 2)
        + np.outer(ty * ty, (f[3] + f[4] - 2 * f[0]) / 2)
    )


#: Stop samples a side of the square grid whose rays :func:`_aperture_clear` traces (12: 112
#: rays over the stop, ~0.03 ms each; the clear share resolved to ~1 %)
_CLEAR_GRID = 12


def _aperture_clear(v: _View, k: int, row: int, led: np.ndarray, frame, guess) -> dict | None:
    """How much of LED ``k``'s glint an eyelid's edge or its lashes hide, from the rays through
    the camera's whole stop rather than its chief ray alone (``guess``: the chief ray's sensor
    point, mm). None when it cannot be told (a solve fails) or no ray of the stop passes.

    A lash (~0.1 mm across) a few mm in front of the cornea crosses part of the narrow pencil
    of rays from the glint's virtual image to the camera's stop: the chief ray may be blocked
    while the rest of the stop sees the spot (the design run's vr-offaxis frames: a saturated
    spot 0.35 px from where the truth put LED 2's glint, called "blocked"), or be clear while
    part of the stop is not. Each stop point t has its own sensor point s(t) — the glint's
    virtual image lies off the plane in focus — modelled through five solves at t = 0, (±a/2,
    0), (0, ±a/2) (:func:`_stop_solves`, a the stop's radius; half-way out, where the rays
    pass a lens that vignettes at its stop's edge) as :func:`_stop_model`, and the ray from
    s(t) through t is traced at each point of a :data:`_CLEAR_GRID` grid over the stop
    (:func:`_glint_seen`: the way in and out clear). Rays the lens does not pass
    (:func:`_stop_ray` None) are not counted. Returns ``aperture_share`` (the share of the
    passing rays that are clear: the spot's power relative to a whole glint's, the cornea's
    reflectance and the lens's transmission taken as constant across the stop),
    ``centre_px`` (the clear part's centroid: where a detector's centroid lies; None when
    none is clear), ``full_centre_px`` (the whole spot's) and ``bias_px`` (their distance).
    A ray whose reflection falls past the cap (a glint at the cornea's rim) is not clear and
    not blocked: with no ray blocked by something, None (the rim's cut alone is
    :func:`_rim_glint`'s); with both, the share and centroid are of the spot both leave. The
    caller records it as ``partly_blocked`` only when some ray is clear (a glint hidden over
    the whole stop is just not visible)."""
    cs, cam = v.cs, v.cam
    h = 0.5 * cam.stop_radius
    if h <= 0.0:
        return None
    got = _stop_solves(v, led, frame, h, guess)
    if got is None:
        return None
    tx, ty = _stop_grid(_CLEAR_GRID, 2.0)
    s = _stop_model([g[0] for g in got], tx, ty)
    passed = np.zeros(len(tx), bool)
    clear = np.zeros(len(tx), bool)
    blocked = 0
    for i in range(len(tx)):
        ray = _stop_ray(cs, cam, float(s[i, 0]), float(s[i, 1]), h * tx[i], h * ty[i], share=True)
        if ray is None:
            continue
        passed[i] = True
        if _off_cornea(cs, v.cornea, *ray[:2]) is None:
            continue  # past the cap: the rim's cut (:func:`_rim_glint`), not an occluder's
        clear[i] = _glint_seen(v, k, row, led, *ray)[0]
        blocked += not clear[i]
    if not passed.any() or blocked == 0:
        return None
    full = sensor_to_pixel(cs, *s[passed].mean(axis=0))
    part = sensor_to_pixel(cs, *s[clear].mean(axis=0)) if clear.any() else None
    return {
        "aperture_share": float(clear[passed].mean()),
        "centre_px": None if part is None else list(part),
        "full_centre_px": list(full),
        "bias_px": None if part is None else math.dist(part, full),
    }


#: Stop samples a side of the square grid over which :func:`_rim_glint` integrates its model
#: (no tracing: the share is resolved to ~1 / (π/4 · 64²) of the aperture).
_RIM_GRID = 64


def _rim_glint(v: _View, k: int, row: int, led: np.ndarray, frame, guess) -> dict | None:
    """LED ``k``'s glint against the cornea's rim, from the rays through the camera's whole
    stop rather than its chief ray alone. None when it cannot be told (a solve fails).

    A point LED's glint is not one ray: the camera collects the LED's light reflected by the
    cornea through every point t of its stop (radius a, ``CameraTables.stop_radius``), and each
    t has its own mirror point P(t) on the cornea and its own sensor point s(t) (the glint's
    virtual image lies ~R/2 behind the corneal vertex, off the plane in focus: s(t) spans the
    glint's blur disc). The spot is whole when every P(t) lies on the cap (local radius ≤
    r_cap, the limbus); when the cap's edge crosses the set of P(t), only the rays through the
    part of the stop whose P(t) lies on the cap form it — the spot is cut and its centroid
    moves toward that part, and it exists even when the chief ray's P(0) lies just past the
    limbus. (The pixel's footprint adds no reach: the rays of a point source to the sensor are
    those through the stop; the pixel averages the picture without moving its centroid. The
    renderer's LEDs are points, ``LedArray``.)

    P(t) and s(t) are solved (Newton, as the chief ray's glint) on the anterior surface
    extended past the limbus (:func:`_open_cap`) at t = 0 and the stop's edge t = (±a, 0),
    (0, ±a), and modelled as f(t) = f₀ + c₁ t_x + c₂ t_x² + c₃ t_y + c₄ t_y² through those five
    (the blur disc spans a few pixels; this is exact at the five and second-order between) —
    or, where a ray through the stop's edge is vignetted and a solve there fails, at (±a/2,
    0), (0, ±a/2), the model taken on to the edge (:func:`_stop_solves`); the model is
    integrated over a uniform grid of the stop (a point source fills the stop
    evenly to first order: the cornea's reflectance and the lens's vignetting are taken as
    constant across it). Returns ``aperture_share`` (the share of the stop whose rays reflect
    off the cap: 1 a whole glint, 0 none), ``beyond_rim_mm`` (the chief ray's mirror point's
    local radius minus r_cap: > 0 past the limbus), ``reach_mm`` (the largest distance of a
    P(t) from P(0): how far past, or inside, the limbus the cut reaches), ``centre_px`` (the
    centroid of the part formed: where a detector's centroid lies; None when none is),
    ``full_centre_px`` (the whole spot's centroid on the extended surface), ``bias_px`` (their
    distance) and ``visible`` (:func:`_glint_seen` along the ray through the formed part's
    mean stop point)."""
    cs, cam, cornea = v.cs, v.cam, v.cornea
    r_cap = math.sqrt(cs.sf[cornea, G.RMAX2])
    if not math.isfinite(r_cap) or cam.stop_radius <= 0.0:
        return None
    a = cam.stop_radius
    got, unit = _stop_solves(v, led, frame, a, guess), a
    if got is None:
        # a ray through the stop's edge vignetted (the off-axis camera of vr-offaxis: the
        # solves at t = (−a, 0) failed for glints at the rim, which were then never flagged):
        # the samples half-way out, the model taken on to the edge
        got, unit = _stop_solves(v, led, frame, 0.5 * a, guess), 0.5 * a
    if got is None:
        return None
    tx, ty = _stop_grid(_RIM_GRID, a / unit)
    q = _stop_model([g[1] for g in got], tx, ty)
    s = _stop_model([g[0] for g in got], tx, ty)
    on = np.hypot(q[:, 0], q[:, 1]) <= r_cap
    share = float(on.mean())
    full = sensor_to_pixel(cs, *s.mean(axis=0))
    part = sensor_to_pixel(cs, *s[on].mean(axis=0)) if on.any() else None
    visible = on.any() and _rim_seen(
        v,
        k,
        row,
        led,
        s[on].mean(axis=0),
        (unit * float(tx[on].mean()), unit * float(ty[on].mean())),
    )
    return {
        "aperture_share": share,
        "beyond_rim_mm": float(np.hypot(*got[0][1]) - r_cap),
        "reach_mm": float(np.max(np.hypot(*(q - got[0][1]).T))),
        "centre_px": None if part is None else list(part),
        "full_centre_px": list(full),
        "bias_px": None if part is None else math.dist(part, full),
        "visible": bool(visible),
    }


def _led_in_view(v: _View, k: int, led: np.ndarray, row: int | None = None) -> dict | None:
    """LED ``k`` (row ``row`` of the LED table, default ``k``) seen directly (no cornea): the pixel
    whose chief ray passes through its emission point, if it falls inside the picture;
    ``visible`` when nothing lies between the lens and the LED and the LED sends light
    toward the lens (I(α) > 0, its radiant intensity that way given in W/sr). None when the
    LED is behind the entrance pupil or imaged outside the picture.
    """
    cs, cam = v.cs, v.cam
    ep = np.array([0.0, 0.0, cam.entrance_pupil_z])
    if led[2] >= ep[2]:
        return None
    n = (ep - led) / np.linalg.norm(ep - led)
    g1, g2 = _basis(n)

    def residual(s):
        return _miss(_chief_ray(cs, cam, s[0], s[1], led), led, n, g1, g2)

    # first guess: the pinhole image through the entrance pupil's centre
    m = -(cs.image_z - ep[2]) / (ep[2] - led[2])
    s = _solve(residual, m * led[:2])
    if s is None:
        return None
    c, r = sensor_to_pixel(cs, *s)
    if not (-0.5 <= c < cs.picture.cols - 0.5 and -0.5 <= r < cs.picture.rows - 0.5):
        return None
    p, d = _chief_ray(cs, cam, *s, led)
    hit, t = G.nearest_hit(cs.sf, cs.si, *p, *d)
    clear = hit < 0 or t >= (led - p) @ d - 1e-4  # nothing before the emission point
    intensity = float(radiant_intensity(cs.led, k if row is None else row, *(-d)))
    return {
        "led": k,
        "centre_px": [c, r],
        "visible": bool(clear and intensity > 0.0),
        "radiant_intensity_toward_lens_w_sr": intensity,
    }


def visual_axis(scene) -> tuple[np.ndarray, tuple[float, float]]:
    """The eye's visual axis: (unit vector in the world frame, its gaze angles (h, v) in
    degrees as the scene file writes gaze — a right eye's frame, before a left eye's mirror).

    The angle kappa (``eye.kappa_deg`` = (κh, κv)) is a fixed direction in the eye's frame,
    k = (cos κv sin κh, sin κv, cos κv cos κh) (:func:`~.tracking.gaze.axis_from_angles`), turned
    with the gaze: the visual axis is R k (:func:`eyelume.compile.gaze_rotation`), mirrored for a
    left eye. Kappa 0: the optical axis."""
    k = axis_from_angles(*scene.eye.kappa_deg)
    turned = gaze_rotation(scene.eye)[0] @ k
    return eye_direction(scene, k), angles_from_axis(turned)


def optical_gaze_for(scene, h_deg: float, v_deg: float, tol_deg: float = 1e-9):
    """The optical-axis gaze angles (``eye.gaze_horizontal_deg``, ``eye.gaze_vertical_deg``)
    with which the visual axis (:func:`visual_axis`) has the angles (``h_deg``, ``v_deg``): the
    eye fixating that target. Kappa 0: (h, v) themselves. Solved by the fixed-point iteration
    g ← g + (target − visual(g)) from g = target − κ (the rotation is near the identity's
    shift by κ; converges to ``tol_deg`` in a few steps for κ within ±15°).

    Raises
    ------
    GeometryError
        The optical gaze it needs lies outside the eye's ±30° or the iteration does not
        converge in 50 steps."""
    eye = scene.eye
    kh, kv = eye.kappa_deg
    if kh == 0.0 and kv == 0.0:
        return float(h_deg), float(v_deg)
    k = axis_from_angles(kh, kv)
    g = np.array([h_deg - kh, v_deg - kv], dtype=float)
    for _ in range(50):
        probe = eye.model_copy(update={"gaze_horizontal_deg": g[0], "gaze_vertical_deg": g[1]})
        got = np.array(angles_from_axis(gaze_rotation(probe)[0] @ k))
        miss = np.array([h_deg, v_deg]) - got
        if np.max(np.abs(miss)) < tol_deg:
            break
        g = g + miss
    else:
        raise GeometryError(
            f"fixating ({h_deg:g}°, {v_deg:g}°) with kappa {list(eye.kappa_deg)}: no optical "
            "gaze found",
            field="eye.kappa_deg",
        )
    if np.max(np.abs(g)) > 30.0:
        raise GeometryError(
            f"fixating ({h_deg:g}°, {v_deg:g}°) with kappa {list(eye.kappa_deg)} needs the "
            f"optical gaze ({g[0]:.2f}°, {g[1]:.2f}°), beyond the eye's ±30°",
            field="eye.kappa_deg",
        )
    return float(g[0]), float(g[1])


def eye_truth(cs: CompiledScene, cam: CameraTables | None = None, *, ghosts: bool = True) -> dict:
    """The true gaze, apparent pupil (centre and edge) and glints of a compiled scene.

    Returns a JSON-ready dict (``truth.json``): gaze angles; the pupil's 3D centre (world mm),
    its apparent centre in pixels, the pixel positions of 72 points of its edge, the share of
    them visible (not under a lid); ``iris``: its outline, the limbus (:func:`_iris_truth`:
    its centre (world mm), diameter, 72 edge points' pixels and the share not under a lid);
    per LED its glint's pixel position, whether its reflection lies on the cornea's cap
    (``on_cornea``) and is seen (``visible``), or why there is none, and whether the cornea's
    rim cuts it (``at_rim``: the rays through only part of the camera's aperture reflect off the
    cap — the chief ray's reflection just inside the limbus, or just past it, where
    ``on_cornea`` stays False and ``centre_px`` None although a partial spot is in the
    picture); for such a glint ``rim`` (else None, :func:`_rim_glint`) gives
    ``aperture_share`` (the share of the stop whose rays form it), ``beyond_rim_mm`` (the chief
    ray's reflection point's distance past the limbus, < 0 inside), ``reach_mm``,
    ``centre_px`` (the partial spot's centroid: where a detector finds it), ``full_centre_px``
    (the whole spot's, on the cornea's surface extended past the limbus), ``bias_px`` (their
    distance: how far the cut moves the centroid) and ``visible``;
    the counts ``glints_on_cornea``, ``glints_visible`` (as before: a rim glint off the cap is
    in neither) and ``glints_at_rim``; ``leds_in_view``: each LED the
    camera sees directly (a wide lens beside the ring), its pixel, whether it is seen and
    its radiant intensity toward the lens — a bright spot that is not a glint; with optical
    elements, ``ghosts``: each LED's specular images by the elements (chain, pixel, flux:
    :func:`eyelume.analysis.ghosts.ghost_truth`, and each one's ``nearest_glint_px``; their
    count ``ghosts_visible``; no such keys without elements or with
    ``ghosts=False``, which skips their search, ~1 s a scene); with ``ambient.sun``,
    ``sun_glint``: the sun's own corneal glint (:func:`_sun_glint`). LEDs of several
    wavelengths: each LED's entries at its own wavelength, marked with it
    (:func:`_truth_by_wavelength`); the pupil at the scene's.
    """
    if cs.led_ids is None and cam is None and not single_wavelength(cs.scene):
        return _truth_by_wavelength(cs, ghosts)
    v = _view(cs, cam or cs.camera)
    eye = cs.scene.eye
    depth = sum(s.thickness_mm for s in eye.surfaces[: eye.iris_surface])
    ids = cs.led_indices  # a wavelength group's compile: its LEDs' scene indices
    glints = [
        _glint_truth(v, k, led, row)
        for row, (k, led) in enumerate(zip(ids, cs.led.points, strict=True))
    ]
    in_view = [
        _led_in_view(v, k, led, row)
        for row, (k, led) in enumerate(zip(ids, cs.led.points, strict=True))
    ]
    in_view = [e for e in in_view if e is not None]
    out = {
        "gaze_deg": {
            "horizontal": eye.gaze_horizontal_deg,
            "vertical": eye.gaze_vertical_deg,
        },
        "eye": cs.scene.eye_pose.which,
        "optical_axis": cs.frame.world_vector(v.axis).tolist(),
        "kappa_deg": list(eye.kappa_deg),
        "visual_axis": visual_axis(cs.scene)[0].tolist(),
        "visual_axis_deg": dict(
            zip(("horizontal", "vertical"), visual_axis(cs.scene)[1], strict=True)
        ),
        "pixel_convention": "OpenCV: pixel (column c, row r) centred at (x, y) = (c, r); row 0 "
        "at the top of the upright picture",
        "pupil": _pupil_truth(v, v.turned(np.array([0.0, 0.0, -depth]))),
        "iris": _iris_truth(v),
        "glints": glints,
        "glints_on_cornea": sum(g["on_cornea"] for g in glints),
        "glints_visible": sum(g["visible"] for g in glints),
        "glints_at_rim": sum(g["at_rim"] for g in glints),
        "leds_in_view": in_view,
    }
    if cs.scene.ambient.sun is not None and cs.sun is None:
        out["sun_glint"] = _sun_glint(cs, v)
    if cs.scene.elements and ghosts:
        from eyelume.analysis.ghosts import ghost_truth

        out["ghosts"] = _near_glints(ghost_truth(v, glints), glints)
        out["ghosts_visible"] = sum(g["visible"] for g in out["ghosts"])
    return out


def _sun_glint(cs: CompiledScene, v: _View) -> dict:
    """The sun's own corneal glint (``ambient.sun``), found as an LED's is
    (:func:`_glint_truth`) for the sun's stand-in point source, :data:`eyelume.compile.
    SUN_DISTANCE_MM` away along the sun's direction (:class:`eyelume.compile.SunSource`, as
    :func:`eyelume.render.render` traces it): ``centre_px``, ``on_cornea``, ``visible``,
    ``reason`` (no ``led``). The renderer draws it — a bright, saturated spot — and no LED's
    glint is it: a detector that takes it for one is wrong (:func:`eyelume.analysis.tracking.
    evaluate.false_glints` counts such matches)."""
    from eyelume.compile import SunSource, compile_scene

    sc = cs.scene
    source = SunSource(sc.ambient.sun.direction(), 1.0, float(sc.wavelength_nm))
    cs_sun = compile_scene(sc, sun=source, nominal=cs)
    g = _glint_truth(_view(cs_sun, v.cam), 0, cs_sun.led.points[0], 0)
    g["reason"] = g["reason"].replace("this LED", "the sun").replace("the LED", "the sun")
    return {k: g[k] for k in ("centre_px", "on_cornea", "visible", "reason")}


def _near_glints(ghosts: list[dict], glints: list[dict]) -> list[dict]:
    """Each ghost with ``nearest_glint_px``: its distance (px) to the nearest visible corneal
    glint's centre (None without one) — how easily a detector takes it for a glint."""
    seen = [g["centre_px"] for g in glints if g["visible"] and g["centre_px"] is not None]
    for e in ghosts:
        d = [math.hypot(e["centre_px"][0] - c, e["centre_px"][1] - r) for c, r in seen]
        e["nearest_glint_px"] = min(d) if d else None
    return ghosts


def _truth_by_wavelength(cs: CompiledScene, with_ghosts: bool = True) -> dict:
    """:func:`eye_truth` of a scene whose LEDs have several wavelengths: the gaze and the pupil
    of the nominal compile ``cs`` (the scene's ``wavelength_nm``), each LED's glint and direct
    view from its wavelength group's compile (:func:`eyelume.compile.compile_scene`: the eye's
    and the lens's indices at that wavelength), the union over the groups in LED order, each
    entry with its ``wavelength_nm``."""
    first = compile_scene(cs.scene, wavelength_groups(cs.scene)[0], nominal=cs)
    out = eye_truth(first, ghosts=with_ghosts)
    base = _view(cs, cs.camera)
    eye = cs.scene.eye
    depth = sum(s.thickness_mm for s in eye.surfaces[: eye.iris_surface])
    out["pupil"] = _pupil_truth(base, base.turned(np.array([0.0, 0.0, -depth])))
    out["iris"] = _iris_truth(base)
    out["optical_axis"] = cs.frame.world_vector(base.axis).tolist()
    glints: dict[int, dict] = {}
    in_view: list[dict] = []
    ghosts: list[dict] = []
    for g in wavelength_groups(cs.scene):
        t = (
            out
            if g.index == 0
            else eye_truth(compile_scene(cs.scene, g, nominal=cs), ghosts=with_ghosts)
        )
        for e in t["glints"]:
            glints[e["led"]] = {**e, "wavelength_nm": g.wavelength_nm}
        in_view += [{**e, "wavelength_nm": g.wavelength_nm} for e in t["leds_in_view"]]
        ghosts += [{**e, "wavelength_nm": g.wavelength_nm} for e in t.get("ghosts", [])]
    out["glints"] = [glints[k] for k in sorted(glints)]
    out["glints_on_cornea"] = sum(e["on_cornea"] for e in out["glints"])
    out["glints_visible"] = sum(e["visible"] for e in out["glints"])
    out["glints_at_rim"] = sum(e["at_rim"] for e in out["glints"])
    out["leds_in_view"] = sorted(in_view, key=lambda e: e["led"])
    if cs.scene.elements and with_ghosts:
        out["ghosts"] = _near_glints(sorted(ghosts, key=lambda e: e["led"]), out["glints"])
        out["ghosts_visible"] = sum(g["visible"] for g in out["ghosts"])
    return out


#: The gaze grid of :func:`glint_counts` (degrees): ±20° horizontally, ±15° vertically.
COUNT_GAZE_H = (-20.0, -10.0, 0.0, 10.0, 20.0)
COUNT_GAZE_V = (-15.0, -7.5, 0.0, 7.5, 15.0)


def glint_counts(scene, gaze_h=COUNT_GAZE_H, gaze_v=COUNT_GAZE_V) -> dict:
    """How many LEDs' glints lie on the cornea, and how many of those are visible (not hidden
    by a lid or the face), over a gaze grid: ring glints slide off the cornea (onto the sclera)
    as the eye turns away from the camera.

    Returns ``{"gaze_h_deg": [...], "gaze_v_deg": [...], "on_cornea": (nv, nh) list,
    "visible": (nv, nh) list, "leds": N}`` (rows: vertical gaze, columns: horizontal)."""
    from eyelume.scene.io import apply_overrides

    on, seen = [], []
    for gv in gaze_v:
        row_on, row_seen = [], []
        for gh in gaze_h:
            turned = apply_overrides(
                scene, {"eye.gaze_horizontal_deg": gh, "eye.gaze_vertical_deg": gv}
            )
            t = eye_truth(compile_scene(turned), ghosts=False)
            row_on.append(t["glints_on_cornea"])
            row_seen.append(t["glints_visible"])
        on.append(row_on)
        seen.append(row_seen)
    return {
        "gaze_h_deg": list(gaze_h),
        "gaze_v_deg": list(gaze_v),
        "on_cornea": on,
        "visible": seen,
        "leds": scene.leds.count,
    }
