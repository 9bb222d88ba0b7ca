"""Specular images of the LEDs caused by optical elements (issue 14, "every bright spot has an
origin"): spectacle ghosts and their kin, found from the LED side the way corneal glints are
(:mod:`eyelume.analysis.truth`).

A *chain* is the ordered list of surfaces that reflect the LED's light on its way to the camera
(in the light's order): one element surface (``["spectacle front"]``: LED → that surface →
camera), or an element surface and the anterior cornea in either order (``["cornea",
"spectacle front"]``: LED → cornea → spectacle → camera). Between the reflections the light
crosses any element surface it meets by the camera's view's branch (refracted through a window
or a lens, so a back-surface ghost is refracted twice by the front; folded by a mirror or a
beamsplitter), as :func:`eyelume.analysis.truth._through_elements` does. A chain whose element
reflection is the view's branch there (a mirror, a hot mirror, a beamsplitter that folds the
view: :func:`eyelume.analysis.truth.view_reflects`) is the camera's ordinary view, not a
ghost, and is not listed (the glints and ``leds_in_view`` already give it).

Position: the sensor point whose real chief ray, reflected by the chain's surfaces in reverse
order, passes through the LED's emission point (Newton's method on the sensor point, started
from a coarse grid over the sensor). Only images inside the picture are listed.

Flux: the LED's radiant intensity I(u) toward the chain (W/sr, u the emission direction of the
image's chief ray) times the product W of the reflectances and transmittances along the path
(at the path's own angles of incidence), spread over the entrance pupil's plane by the chain:
the irradiance there is E = I(u) W / |det J|, J = ∂(x, y)/∂(u₁, u₂) the Jacobian (mm²/sr) of
where a ray from the LED meets the plane z = z_EP (camera frame, ⟂ the lens axis) with
respect to its emission direction (central differences). For a plane mirror |det J| =
D²/cos γ (D the distance from the LED's mirror image to the pupil, γ the angle to the axis),
for a curved one the caustic's focusing is in J. ``flux_w`` = E π r_EP² (W into the entrance
pupil of radius r_EP, before the lens's transmission and vignetting; valid while E varies
little over the pupil, the small-aperture camera of an eye tracker); ``relative_to_glint`` =
E / E_glint, the same LED's corneal glint computed the same way (None without one).

Size: the light reaches the pupil as if from a point at the *apparent distance* D =
sqrt(|det ∂x/∂d′| cos γ) (x the pupil-plane point, d′ the arriving ray's direction, both
differentiated over the emission direction: ∂x/∂d′ = J (∂d′/∂u)⁻¹; a point at distance D gives
|det| = D²/cos γ; the geometric mean of the two focal distances of an astigmatic chain; ∞
for a collimated one); a camera focused at D_f (its object plane)
blurs it to a disc ``blur_px`` = 2 r_EP |D − D_f| / D · |m| / pitch wide (geometric defocus,
paraxial; the LED taken as a point, as the renderer traces it; the diffraction PSF comes on
top). The eye image's ``reflection`` region is drawn from these
(:func:`eyelume.analysis.regions.with_reflections`).
"""

from __future__ import annotations

import math

import numpy as np

from eyelume.analysis.truth import (
    _ELEMENT_EVENTS,
    _basis,
    _solve,
    _View,
    _view_branch,
    sensor_to_pixel,
    view_reflects,
)
from eyelume.compile import led_body_rows
from eyelume.detectors.receivers import BinnedPlane
from eyelume.estimators.camera import aim_chief, into_scene
from eyelume.kernels import geometry as G
from eyelume.kernels.interact import interface_at, reflect
from eyelume.kernels.sampling import radiant_intensity

__all__ = ["FALSE_GLINT_MIN_RELATIVE", "false_glint_counts", "ghost_truth"]

#: A visible ghost at least this fraction of its LED's corneal glint's irradiance at the pupil
#: (``relative_to_glint``; or with no glint to compare) is counted as a false glint by
#: :func:`false_glint_counts`. ASSUMPTION: the 5 % of a glint's peak at which the regions call
#: a pixel part of a glint (:data:`eyelume.analysis.regions.GLINT_FRACTION`); a real detector's
#: glint threshold sits at a high percentile of the picture, and a glint saturates, so a spot a
#: twentieth of a glint is still far above the skin.
FALSE_GLINT_MIN_RELATIVE = 0.05

_GRID = 9  # coarse sensor grid (per side) the Newton searches start from
_STARTS = 4  # best grid points tried
_DU = 1e-5  # rad: emission-direction step of the flux Jacobian


def _chief_ray(cs, cam, xs: float, ys: float):
    """The chief ray of sensor point (xs, ys) as it leaves the camera (before any element),
    camera frame, or None."""
    chief = aim_chief(cam, xs, ys)
    if not chief.found:
        return None
    ok, x, y, z, dx, dy, dz, _ = into_scene(cam, xs, ys, chief.qx, chief.qy)
    return (np.array([x, y, z]), np.array([dx, dy, dz])) if ok else None


def _is_element(cs, s: int) -> bool:
    name = cs.surface_names[s] if s >= 0 else ""
    return name.startswith("element ") and not name.endswith(" edge")


def _label(cs, cornea: int, s: int) -> str:
    """``cornea``, or an element surface's ``name side`` (``spectacle front``)."""
    if s == cornea:
        return "cornea"
    name = cs.surface_names[s]
    return name[name.index("(") + 1 : name.rindex(")")] + name[name.rindex(")") + 1 :]


def _follow(cs, p, d, chain, target=None, strict=False, pupil_z=None):
    """The ray (p, d) reflected by the surfaces ``chain`` in order, crossing the element
    surfaces it meets before each (the view's branch), then through the elements up to
    ``target`` (a point: no element beyond its foot on the ray), or, with ``pupil_z``, until
    it crosses the plane z = ``pupil_z`` toward +z (camera frame: the entrance pupil's plane)
    before the next element — through a fold the pupil lies off the ray's line before the
    mirror, and a foot-of-target test stopped rays that meet the mirror's far half (LED 0's
    glint on paper2005-integrated came out 500× too faint). Returns (p, d, weight,
    reflectances) — weight the product of R and T along the path, ``reflectances`` the R at
    each chain surface — or None when a chain surface is missed (or, ``strict``, anything
    else is met first)."""
    w, refl = 1.0, []
    for s in chain:
        for _ in range(_ELEMENT_EVENTS):
            ts = G.intersect_surface(cs.sf, cs.si, s, *p, *d, math.inf)
            h, th = G.nearest_hit(cs.sf, cs.si, *p, *d)
            if h != s and h >= 0 and (ts < 0 or th < ts):
                if not _is_element(cs, h):
                    if strict:
                        return None
                    break
                p = p + th * d
                d, f = _view_branch(cs, h, p, d)
                w *= f
                continue
            break
        else:
            return None
        if ts < 0:
            return None
        p = p + ts * d
        n = np.array(G.surface_normal(cs.sf, cs.si, s, *p))
        r = float(interface_at(cs.sf, cs.si, s, float(d @ n)).reflectance)
        refl.append(r)
        w *= r
        d = np.array(reflect(*d, *n))
        d = d / np.linalg.norm(d)
    # after the chain: through the elements (their weights) up to the target
    for _ in range(_ELEMENT_EVENTS):
        h, th = G.nearest_hit(cs.sf, cs.si, *p, *d)
        if not _is_element(cs, h) or (target is not None and th > (target - p) @ d):
            break
        if pupil_z is not None and d[2] > 0.0 and (pupil_z - p[2]) / d[2] < th:
            break
        p = p + th * d
        d, f = _view_branch(cs, h, p, d)
        w *= f
    return p, d, w, refl


def _miss(ray, led, n, g1, g2):
    """Where the ray (after its chain) crosses the plane through the LED ⟂ n, relative to the
    LED, in (g1, g2); None when it does not reach that plane going forward (an LED behind the
    ray's last surface is no image of it)."""
    if ray is None:
        return None
    p, d = ray[0], ray[1]
    den = d @ n
    if abs(den) < 1e-12:
        return None
    t = ((led - p) @ n) / den
    if t < 0.0:
        return None
    h = p + t * d - led
    return np.array([h @ g1, h @ g2])


def _sensor_box(cs):
    """Half-width and half-height (mm) of the picture on the sensor."""
    return cs.picture.width_mm / 2.0, cs.picture.height_mm / 2.0


def _find(v: _View, chain_cam: list[int], led: np.ndarray, start: np.ndarray | None = None):
    """The sensor point (mm) of the image of ``led`` by ``chain_cam`` (camera-side order):
    Newton's method from ``start`` (sensor mm) when given, else (or when that fails) from the
    best points of a coarse grid over the sensor."""
    cs, cam = v.cs, v.cam
    n = led / np.linalg.norm(led)  # a plane through the LED, ⟂ its direction from the origin
    g1, g2 = _basis(n)

    def residual(s):
        ray = _chief_ray(cs, cam, s[0], s[1])
        if ray is None:
            return None
        return _miss(_follow(cs, *ray, chain_cam, led), led, n, g1, g2)

    if start is not None:
        found = _solve(residual, np.asarray(start, dtype=float))
        if found is not None:
            return found
    hw, hh = _sensor_box(cs)
    starts = []
    for x in np.linspace(-hw, hw, _GRID):
        for y in np.linspace(-hh, hh, _GRID):
            r = residual(np.array([x, y]))
            if r is not None:
                starts.append((float(r @ r), x, y))
    for _, x, y in sorted(starts)[:_STARTS]:
        found = _solve(residual, np.array([x, y]))
        if found is not None:
            return found
    return None


def _irradiance(v: _View, chain_led: list[int], row: int, led: np.ndarray, u: np.ndarray):
    """E (W/mm²) at the entrance pupil's plane of LED ``row``'s light sent along ``u`` and
    reflected by ``chain_led`` (light order), the path's weight and the apparent distance
    (mm) of the source seen from the pupil, sqrt(|det ∂x/∂d′| cos γ) (module doc); None if a
    ray is lost."""
    cs = v.cs
    zp = v.cam.entrance_pupil_z
    a, b = _basis(u)

    def at_pupil(du):
        d = u + du[0] * a + du[1] * b
        d = d / np.linalg.norm(d)
        got = _follow(cs, led, d, chain_led, pupil_z=zp)
        if got is None or abs(got[1][2]) < 1e-12:
            return None
        p, dd = got[0], got[1] / np.linalg.norm(got[1])
        t = (zp - p[2]) / dd[2]
        return (p + t * dd)[:2], dd, got[2]

    mid = at_pupil(np.zeros(2))
    if mid is None:
        return None
    _, d_mid, w = mid
    a2, b2 = _basis(d_mid)
    cols, turns = [], []
    for k in range(2):
        e = np.zeros(2)
        e[k] = _DU
        hi, lo = at_pupil(e), at_pupil(-e)
        if hi is None or lo is None:
            return None
        cols.append((hi[0] - lo[0]) / (2 * _DU))
        dd = (hi[1] - lo[1]) / (2 * _DU)
        turns.append([dd @ a2, dd @ b2])
    jac = np.column_stack(cols)
    det = abs(np.linalg.det(jac))
    if det == 0.0:
        return None
    intensity = float(radiant_intensity(cs.led, row, *u))
    # where the pupil-plane point moves per radian of the arriving ray's direction
    turn = abs(np.linalg.det(np.array(turns).T))
    dist = math.sqrt(det / turn * abs(d_mid[2])) if turn > 0.0 else math.inf
    return intensity * w / det, w, dist


def _emission(v: _View, s: np.ndarray, chain_cam: list[int], led: np.ndarray):
    """The emission direction (from the LED) of the image's chief ray, the path clear?"""
    cs = v.cs
    ray = _chief_ray(cs, v.cam, *s)
    got = _follow(cs, *ray, chain_cam, led, strict=True)
    clear = got is not None
    if got is None:
        got = _follow(cs, *ray, chain_cam, led)
    p, d = got[0], got[1]
    if clear:  # nothing between the last surface and the LED but its own body
        h, th = G.nearest_hit(cs.sf, cs.si, *p, *d)
        n_led = cs.scene.leds.count
        k_body = [i for k in range(n_led) for i in led_body_rows(cs.surface_names, k)]
        clear = h < 0 or h in k_body or th >= (led - p) @ d - 1e-4
    return -d, clear, got[3]


def _one(v: _View, k: int, row: int, led: np.ndarray, chain_cam: list[int]):
    """The entry of LED ``k``'s image by ``chain_cam`` (camera-side order), or None."""
    cs = v.cs
    s = _find(v, chain_cam, led)
    if s is None:
        return None
    c, r = sensor_to_pixel(cs, *s)
    if not (-0.5 <= c < cs.picture.cols - 0.5 and -0.5 <= r < cs.picture.rows - 0.5):
        return None
    u, clear, refl = _emission(v, s, chain_cam, led)
    for sf in chain_cam:  # the ordinary view (a mirror's or a beamsplitter's fold) is no ghost
        f = interface_at(cs.sf, cs.si, sf, -1.0)
        t = 1.0 - f.reflectance - f.absorptance
        if _is_element(cs, sf) and view_reflects(cs, sf, f.reflectance, t):
            return None
    chain_led = chain_cam[::-1]
    e = _irradiance(v, chain_led, row, led, u)
    intensity = float(radiant_intensity(cs.led, row, *u))
    return {
        "led": k,
        "chain": [_label(cs, v.cornea, x) for x in chain_led],
        "centre_px": [c, r],
        "visible": bool(clear and intensity > 0.0),
        "reflectances": refl[::-1],
        "pupil_irradiance_w_mm2": None if e is None else e[0],
        "flux_w": None if e is None else e[0] * math.pi * cs.first_order.entrance_pupil_radius**2,
        "apparent_distance_mm": None if e is None or math.isinf(e[2]) else e[2],
        "blur_px": None if e is None else _blur_px(cs, e[2]),
    }


def _blur_px(cs, distance_mm: float) -> float:
    """Geometric defocus blur diameter (px) of a point seen at ``distance_mm`` from the
    entrance pupil (radius r) by a camera focused at D_f (its object plane): the cone from the
    point through the pupil is 2 r |D − D_f| / D wide at the plane in focus, times |m| on the
    sensor (paraxial, thin-pupil)."""
    fo = cs.first_order
    d_f = fo.entrance_pupil_z  # the object plane is z = 0 of the camera frame
    width_mm = (
        2.0
        * fo.entrance_pupil_radius
        * (1.0 if math.isinf(distance_mm) else abs(distance_mm - d_f) / distance_mm)
    )
    return width_mm * abs(fo.magnification) / (cs.picture.width_mm / cs.picture.cols)


def ghost_truth(v: _View, glints: list[dict] | None = None) -> list[dict]:
    """Every specular image of an LED that an optical element causes, inside the picture: per
    LED and chain (module doc) its ``led``, ``chain`` (surface names in the light's order),
    ``centre_px`` (OpenCV convention), ``visible`` (nothing else on the path, the LED emitting
    that way), ``reflectances`` (R at each chain surface, same order), the irradiance it gives
    at the entrance pupil (``pupil_irradiance_w_mm2``), ``flux_w`` (W into the entrance
    pupil) and ``relative_to_glint`` (over the same LED's corneal glint, same method; None,
    with ``relative_to_glint_note`` saying why, when that glint does not exist or gives no
    irradiance). ``glints``: the truth's glints (:func:`eyelume.analysis.truth.eye_truth`), whose
    pixels start the search for each LED's glint here (the coarse grid alone missed LED 0's
    of paper2005-integrated, 0.11 mm from the sensor's centre between two grid points, and
    its ghosts had no ``relative_to_glint``). A scene without elements: []."""
    cs = v.cs
    if not cs.scene.elements:
        return []
    surfaces = [
        s
        for s, nm in enumerate(cs.surface_names)
        if nm.startswith("element ") and not nm.endswith(" edge")
    ]
    out = []
    known = {g["led"]: g for g in glints or []}
    for row, (k, led) in enumerate(zip(cs.led_indices, cs.led.points, strict=True)):
        truth = known.get(k)
        start = None
        if truth is not None and truth["centre_px"] is not None:
            start = np.array(BinnedPlane(cs.picture).from_pixel(*truth["centre_px"]), float)
        glint = _one_glint(v, row, led, start)
        note = None
        if not glint:
            note = (
                "no corneal glint of this LED: " + (truth["reason"] or "none found")
                if truth is not None and truth["centre_px"] is None
                else "its corneal glint gives no irradiance at the entrance pupil (a ray of it "
                "lost) or was not found"
            )
        for s in surfaces:
            for chain_cam in ([s], [s, v.cornea], [v.cornea, s]):
                e = _one(v, k, row, led, chain_cam)
                if e is None:
                    continue
                pe = e["pupil_irradiance_w_mm2"]
                e["relative_to_glint"] = None if (pe is None or not glint) else pe / glint
                if e["relative_to_glint"] is None:
                    e["relative_to_glint_note"] = note or "the ghost's irradiance was not found"
                out.append(e)
    return out


def _one_glint(v: _View, row: int, led: np.ndarray, start=None) -> float | None:
    """The corneal glint's irradiance at the entrance pupil (W/mm²), same method (its search
    started at ``start``, sensor mm, when given)."""
    s = _find(v, [v.cornea], led, start)
    if s is None:
        return None
    u, _, _ = _emission(v, s, [v.cornea], led)
    e = _irradiance(v, [v.cornea], row, led, u)
    return None if e is None else e[0]


def false_glint_counts(scene, gaze_h=None, gaze_v=None) -> dict:
    """False glints from the truth over a gaze grid (the study metric ``ghosts``): at each
    gaze, the visible ghosts (:func:`ghost_truth`) at least :data:`FALSE_GLINT_MIN_RELATIVE`
    of their LED's glint (or with no glint), their distance (px) to the nearest visible
    corneal glint (``nearest_glint_px``) and to the apparent pupil's centre.

    ``gaze_h`` / ``gaze_v`` (degrees): default :data:`eyelume.analysis.truth.COUNT_GAZE_H` /
    ``COUNT_GAZE_V`` (±20° × ±15°, 5 × 5). Returns ``{"gaze_h_deg", "gaze_v_deg",
    "false_glints": (nv, nh) counts, "nearest_glint_px": (nv, nh) the smallest distance at
    each gaze (None: no false glint or no visible glint), "pupil_px": (nv, nh) likewise to the
    pupil's centre}``. A scene without elements: all counts 0."""
    from eyelume.analysis.truth import COUNT_GAZE_H, COUNT_GAZE_V, eye_truth
    from eyelume.compile import compile_scene
    from eyelume.scene.io import apply_overrides

    gaze_h = COUNT_GAZE_H if gaze_h is None else gaze_h
    gaze_v = COUNT_GAZE_V if gaze_v is None else gaze_v
    counts, near, pupil = [], [], []
    for gv in gaze_v:
        row_n, row_g, row_p = [], [], []
        for gh in gaze_h:
            turned = apply_overrides(
                scene, {"eye.gaze_horizontal_deg": gh, "eye.gaze_vertical_deg": gv}
            )
            t = eye_truth(compile_scene(turned))
            false = [
                g
                for g in t.get("ghosts", [])
                if g["visible"]
                and (g["relative_to_glint"] is None
                     or g["relative_to_glint"] >= FALSE_GLINT_MIN_RELATIVE)
            ]  # fmt: skip
            row_n.append(len(false))
            d = [g["nearest_glint_px"] for g in false if g["nearest_glint_px"] is not None]
            row_g.append(min(d) if d else None)
            pc = t["pupil"]["centre_px"]
            d = [math.dist(g["centre_px"], pc) for g in false] if pc is not None else []
            row_p.append(min(d) if d else None)
        counts.append(row_n)
        near.append(row_g)
        pupil.append(row_p)
    return {
        "gaze_h_deg": list(gaze_h),
        "gaze_v_deg": list(gaze_v),
        "false_glints": counts,
        "nearest_glint_px": near,
        "pupil_px": pupil,
    }
