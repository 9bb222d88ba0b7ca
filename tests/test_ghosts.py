"""Specular images caused by optical elements in ``truth.json`` (issue 14, "every bright spot
has an origin"), against independent references written here:

* a plane plate's first-surface ghost of an LED lies at the LED's mirror image in that surface's
  plane, projected by the camera model (the real chief ray through the point); its irradiance at
  the entrance pupil is I(u) R_F(θ) cos γ / D² (a plane mirror keeps the intensity: the light
  comes from the mirror image, at distance D from the pupil, γ the angle to the lens axis;
  R_F the unpolarised Fresnel reflectance at the angle of incidence θ);
* a spectacle lens's first-surface ghost lies at the LED's paraxial image in a convex mirror of
  the surface's radius R (1/s + 1/s' = 2/R, on the line from the centre of curvature through
  the LED), projected the same way; and its irradiance is that of the virtual image, whose
  intensity is I R (s'/s)² (a cone of half-angle u from the LED leaves the mirror in u' =
  u s/s');
* ``relative_to_glint`` against a partial plane mirror's ghost over the corneal glint's
  Coddington irradiance (the conic cornea's principal radii at the specular point);
* a two-reflection chain (LED → 4 % partial mirror → cornea → camera) lies at the corneal
  glint of the LED's mirror image;
* the forward render (which knows nothing of the truth) draws the ghosts there, as bright as
  their ``flux_w`` says, within its counting noise;
* a scene without elements has the same truth as before (pinned: ``tests/reference/
  truth_without_elements.json``, written by the code before ghosts were added).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy import optimize

import eyelume
from eyelume.analysis.ghosts import ghost_truth
from eyelume.analysis.truth import _view, eye_truth, sensor_to_pixel
from eyelume.compile import compile_scene
from eyelume.estimators.camera import aim_chief, into_scene
from eyelume.kernels.sampling import radiant_intensity
from eyelume.scene.glass import load_catalog

REFERENCE = Path(__file__).parent / "reference" / "truth_without_elements.json"
TILT = math.radians(14.0)
PLATE = {
    "kind": "plate",
    "name": "window",
    "position_mm": [0.0, 0.0, 45.0],
    "direction": [math.sin(TILT), 0.0, math.cos(TILT)],
    "thickness_mm": 3.0,
    "glass": "N-BK7",
    "semi_diameter_mm": 27.0,
}
# a -3 D spectacle lens 12 mm from the cornea, 8 deg pantoscopic tilt, its front (the convex
# side, toward the headset) 14 mm from the corneal vertex; base curve +4 D, back -7 D. CR-39
# is not in the shipped glass catalog: N-BK7 (n = 1.510 at 850 nm) stands in, the radii
# computed for it (R = (n - 1)/P); only the front radius matters for the first-surface ghost.
PANTO = math.radians(8.0)
N_SPEC = 0.51
SPECTACLE = {
    "kind": "lens",
    "name": "spectacle",
    "position_mm": [0.0, 0.0, 14.0],
    "direction": [0.0, math.sin(PANTO), -math.cos(PANTO)],
    "thickness_mm": 2.0,
    "glass": "N-BK7",
    "semi_diameter_mm": 25.0,
    "front": {"radius_mm": N_SPEC / 4.0 * 1000.0},
    "back": {"radius_mm": N_SPEC / 7.0 * 1000.0},
}


def _compiled(element):
    return compile_scene(eyelume.load_scene("paper2005", {"elements": [element]}))


def _project(cs, point):
    """The pixel whose real chief ray (no elements) passes through ``point`` (camera model),
    and where that ray crosses the entrance pupil's plane (camera frame, mm)."""
    cam = cs.camera

    def ray(s):
        c = aim_chief(cam, s[0], s[1])
        ok, x, y, z, dx, dy, dz, _ = into_scene(cam, s[0], s[1], c.qx, c.qy)
        return np.array([x, y, z]), np.array([dx, dy, dz])

    def miss(s):
        p, d = ray(s)
        t = (point[2] - p[2]) / d[2]
        return (p + t * d - point)[:2]

    m = -(cs.image_z - cam.entrance_pupil_z) / (cam.entrance_pupil_z - point[2])
    sol = optimize.root(miss, m * point[:2], tol=1e-12)
    assert np.abs(miss(sol.x)).max() < 1e-9, sol.message  # mm
    p, d = ray(sol.x)
    return np.array(sensor_to_pixel(cs, *sol.x)), p + (cam.entrance_pupil_z - p[2]) / d[2] * d


def _fresnel(cos_i, n):
    sin_t = math.sqrt(max(0.0, 1.0 - cos_i**2)) / n
    cos_t = math.sqrt(1.0 - sin_t**2)
    rs = ((cos_i - n * cos_t) / (cos_i + n * cos_t)) ** 2
    rp = ((n * cos_i - cos_t) / (n * cos_i + cos_t)) ** 2
    return (rs + rp) / 2


def _ghost(truth, led, chain):
    hits = [g for g in truth["ghosts"] if g["led"] == led and g["chain"] == chain]
    assert len(hits) == 1, truth["ghosts"]
    return hits[0]


def test_plane_plate_first_surface_ghost_at_the_mirror_image_with_its_flux():
    cs = _compiled(PLATE)
    truth = eye_truth(cs)
    axis = np.array(PLATE["direction"])
    surface = np.array(PLATE["position_mm"]) + PLATE["thickness_mm"] * axis  # toward the LEDs
    led = cs.led.points[0]
    image = led - 2.0 * ((led - surface) @ axis) * axis
    g = _ghost(truth, 0, ["window back"])
    expect, ep = _project(cs, image)
    assert np.hypot(*(np.array(g["centre_px"]) - expect)) < 1e-3  # px: both exact
    assert g["visible"]
    # irradiance where the chief ray crosses the entrance pupil's plane (ep, 0.2 mm off its
    # centre: the real chief ray goes through the stop's centre): the mirror image's, times R_F
    to_ep = ep - image
    dist = np.linalg.norm(to_ep)
    w = to_ep / dist
    hit = image + ((surface - image) @ axis) / (w @ axis) * w  # the reflection point
    u = (hit - led) / np.linalg.norm(hit - led)
    n = float(load_catalog()["N-BK7"].index(850.0))
    r_f = _fresnel(abs(u @ axis), n)
    e = float(radiant_intensity(cs.led, 0, *u)) * r_f * abs(w[2]) / dist**2
    assert g["reflectances"][0] == pytest.approx(r_f, rel=1e-6)
    # central differences of a plane mirror's linear map: exact to rounding
    assert g["pupil_irradiance_w_mm2"] == pytest.approx(e, rel=1e-5)
    r_ep = cs.first_order.entrance_pupil_radius
    assert g["flux_w"] == pytest.approx(g["pupil_irradiance_w_mm2"] * math.pi * r_ep**2)
    # the light comes from the mirror image: its apparent distance is the image's from ep
    assert g["apparent_distance_mm"] == pytest.approx(dist, rel=1e-5)
    # defocus: the cone from the image through the pupil (radius r_ep), cut by the plane in
    # focus (the object plane z = 0, D_f from the pupil), times |m|, in pixels
    fo = cs.first_order
    d_f = fo.entrance_pupil_z
    pitch = cs.scene.sensor.field_mm[0] / cs.scene.sensor.cols
    blur = 2 * r_ep * abs(dist - d_f) / dist * abs(fo.magnification) / pitch
    assert g["blur_px"] == pytest.approx(blur, rel=1e-5)


def test_spectacle_first_surface_ghost_against_the_convex_mirror():
    cs = _compiled(SPECTACLE)
    truth = eye_truth(cs)
    axis = np.array(SPECTACLE["direction"])  # toward the eye
    radius = SPECTACLE["front"]["radius_mm"]
    centre = np.array(SPECTACLE["position_mm"]) + radius * axis  # on the eye's side
    n_glass = float(load_catalog()["N-BK7"].index(850.0))
    for k in (0, 2, 3):
        led = cs.led.points[k]
        g = _ghost(truth, k, ["spectacle front"])
        dl = np.linalg.norm(led - centre)
        s = dl - radius  # object distance along the line centre → LED
        # convex: 1/s + 1/s' = 2/R with R = -|R| and a virtual image s' = -|s'|
        s_img = 1.0 / (1.0 / s + 2.0 / radius)  # |s'|
        image = centre + (radius - s_img) * (led - centre) / dl
        expect, ep = _project(cs, image)

        # the exact specular point P for the LED and the chief ray's pupil point ep (Fermat:
        # the shortest path LED -> sphere -> ep), once more with P's own chief ray
        def on_sphere(a, centre=centre, dl=dl, led=led):
            n0 = (led - centre) / dl
            e1 = np.cross(n0, [0.0, 1.0, 0.0])
            e1 /= np.linalg.norm(e1)
            e2 = np.cross(n0, e1)
            n = n0 + a[0] * e1 + a[1] * e2
            return centre + radius * n / np.linalg.norm(n)

        for _ in range(2):

            def path(a, led=led, ep=ep):
                p = on_sphere(a)
                return np.linalg.norm(p - led) + np.linalg.norm(ep - p)

            opts = {"xatol": 1e-12, "fatol": 1e-14}
            pt = on_sphere(
                optimize.minimize(path, [0.0, 0.0], method="Nelder-Mead", options=opts).x
            )
            exact, ep = _project(cs, pt)
        assert np.hypot(*(np.array(g["centre_px"]) - exact)) < 1e-3, (k, g, exact)
        # the paraxial image is exact for rays along the line centre -> LED; the chief ray meets
        # the mirror at beta off it, so the image point is off by the third-order |s'| beta^2
        # (mm), here ~0.1 mm: in pixels at the image's depth (1 mm sideways projected)
        beta = math.acos((pt - centre) @ (led - centre) / (radius * dl))
        side = np.cross(led - centre, [0.0, 0.0, 1.0])
        side = side / np.linalg.norm(side) if np.linalg.norm(side) > 0 else np.array([1.0, 0, 0])
        px_per_mm = np.hypot(*(_project(cs, image + side)[0] - expect))
        tol = abs(s_img) * beta**2 * px_per_mm
        assert np.hypot(*(np.array(g["centre_px"]) - expect)) < tol, (k, g, expect, tol)
        # its irradiance by the Coddington equations of a convex mirror (radius R) at P, angle
        # of incidence theta, object distance s: the reflected pencil diverges from virtual
        # foci |s_t|, |s_s| behind P, 1/|s_t| = 1/s + 2/(R cos theta), 1/|s_s| = 1/s +
        # 2 cos theta/R, so at distance L from P the normal irradiance is
        # I R_F |s_t||s_s| / (s^2 (L + |s_t|)(L + |s_s|)), times cos(gamma) on the pupil's plane
        rho = radius
        s_obj, dist = np.linalg.norm(pt - led), np.linalg.norm(ep - pt)
        u = (pt - led) / s_obj
        normal = (pt - centre) / rho
        cos_t = abs(u @ normal)
        s_t = 1.0 / (1.0 / s_obj + 2.0 / (rho * cos_t))
        s_s = 1.0 / (1.0 / s_obj + 2.0 * cos_t / rho)
        w = (ep - pt) / dist
        e = (
            float(radiant_intensity(cs.led, k, *u))
            * g["reflectances"][0]
            * s_t
            * s_s
            / (s_obj**2 * (dist + s_t) * (dist + s_s))
            * abs(w[2])
        )
        assert g["reflectances"][0] == pytest.approx(_fresnel(cos_t, n_glass), rel=1e-6)
        assert g["pupil_irradiance_w_mm2"] == pytest.approx(e, rel=1e-3), k


def test_back_surface_ghost_is_weaker_by_the_front_transmission_and_both_listed():
    cs = _compiled(SPECTACLE)
    truth = eye_truth(cs)
    chains = {tuple(g["chain"]) for g in truth["ghosts"] if g["led"] == 0}
    assert chains == {("spectacle front",), ("spectacle back",)}
    seen = [np.array(e["centre_px"]) for e in truth["glints"] if e["visible"]]
    assert len(seen) == 4
    for g in truth["ghosts"]:
        assert g["relative_to_glint"] > 1.0  # a plane-ish 4 % mirror beats the cornea's
        assert len(g["reflectances"]) == len(g["chain"])
        near = min(np.hypot(*(np.array(g["centre_px"]) - c)) for c in seen)
        assert g["nearest_glint_px"] == pytest.approx(near, rel=1e-12)
    assert truth["ghosts_visible"] == sum(g["visible"] for g in truth["ghosts"]) == 6


def test_no_ghosts_without_elements_and_the_truth_unchanged():
    ref = json.loads(REFERENCE.read_text())
    # the reference's vr-offaxis had 1.6 mm spherical LED bodies (before leds.body_shape)
    spheres = {
        "leds.body_shape": "sphere",
        "leds.body_diameter_mm": 1.6,
        "leds.body_length_mm": None,
    }
    for name in ("paper2005", "vr-offaxis"):
        cs = compile_scene(eyelume.load_scene(name, spheres if name == "vr-offaxis" else None))
        truth = json.loads(json.dumps(eye_truth(cs)))
        assert "ghosts" not in truth
        assert ghost_truth(_view(cs, cs.camera)) == []
        truth.pop("iris")  # the limbus, added after the reference was written (issue 17)
        truth.pop("glints_at_rim")  # glints cut by the cornea's rim, added since (issue 13)
        for g in truth["glints"]:
            g.pop("at_rim")
            g.pop("rim")
            # a lid or a lash over part of the stop, added since (session 31): none here
            assert g.pop("partly_blocked") is None
        _same(truth, ref[name])


def _same(a, b):
    if isinstance(a, dict):
        assert a.keys() == b.keys()
        for k in a:
            _same(a[k], b[k])
    elif isinstance(a, list):
        assert len(a) == len(b)
        for x, y in zip(a, b, strict=True):
            _same(x, y)
    elif isinstance(a, float):
        assert a == pytest.approx(b, rel=1e-9, abs=1e-9)
    else:
        assert a == b


def _mean_shift(img, start, radius):
    """The count-weighted centroid of ``img`` within ``radius`` px of itself (iterated from
    ``start``), the counts inside, and the centroid's standard error per axis (px)."""
    rr, cc = np.mgrid[: img.shape[0], : img.shape[1]]
    c = np.array(start, dtype=float)
    for _ in range(100):
        w = img * ((cc - c[0]) ** 2 + (rr - c[1]) ** 2 <= radius**2)
        n = w.sum()
        new = np.array([(w * cc).sum(), (w * rr).sum()]) / n
        if np.allclose(new, c, atol=1e-9):
            break
        c = new
    var = np.array([(w * (cc - c[0]) ** 2).sum(), (w * (rr - c[1]) ** 2).sum()]) / n
    return c, int(n), np.sqrt(var / n), (cc - c[0]) ** 2 + (rr - c[1]) ** 2 <= radius**2


@pytest.mark.slow
def test_spectacle_ghosts_where_and_as_bright_as_the_forward_render_shows_them():
    """The forward estimator (LED → spectacle → camera lens → sensor, no knowledge of the
    truth) draws each ghost as the blur disc of the virtual image (it lies ~15 mm behind the
    eye plane the camera focuses on: ~9 px across). Its count-weighted centroid matches the
    truth's pixel within 4 standard errors (the disc's own spread / √N), and the counts in it
    (less the picture's mean background per pixel) match flux_w / (P / rays) within 4 √N —
    each ray carries P / rays of the LEDs' total power P = Σ I₀ 2π ∫ f(α) sin α dα, and the
    camera lens transmits 100 % inside its apertures (kernels/sequential.py). LEDs 0 and 2
    (their two ghosts 11 px apart, apart from everything else); LED 3's two discs overlap."""
    from eyelume.estimators.forward import trace_forward

    cs = _compiled(SPECTACLE)
    truth = eye_truth(cs)
    rays = 4_000_000
    img = trace_forward(cs, rays, seed=7).image.astype(float)
    a = cs.led.alpha_grid
    power = sum(
        cs.led.i0[k] * 2 * math.pi * np.trapezoid(cs.led.intensity_grid[k] * np.sin(a), a)
        for k in range(len(cs.led.i0))
    )
    radius = 5.0  # px: the blur disc (~4.5 px) and a margin, short of the neighbour ghost
    spots = np.zeros(img.shape, dtype=bool)  # every ghost's and glint's disc
    for g in truth["ghosts"] + truth["glints"]:
        spots |= _mean_shift(img, g["centre_px"], radius)[3]
    background = img[~spots].mean()
    checked = 0
    for g in truth["ghosts"]:
        if g["led"] not in (0, 2):
            continue
        c, n, se, inside = _mean_shift(img, g["centre_px"], radius)
        assert np.all(np.abs(c - g["centre_px"]) < 4 * se), (g["chain"], g["centre_px"], c, se)
        expect = g["flux_w"] / (power / rays)
        got = n - background * inside.sum()
        assert abs(got - expect) < 4 * math.sqrt(expect), (g["led"], g["chain"], got, expect)
        # its size: a uniform disc of radius a has a per-axis variance a²/4 (+ 1/12 px² from
        # the pixels); blur_px/2 is paraxial (the back ghost is refracted twice by the tilted
        # front: astigmatic), so 15 % + 0.3 px (the variance's own noise is ~2 % at ~400 counts)
        rr, cc = np.mgrid[: img.shape[0], : img.shape[1]]
        w = (img - background) * inside
        var = np.array([(w * (cc - c[0]) ** 2).sum(), (w * (rr - c[1]) ** 2).sum()]) / w.sum()
        a = 2.0 * np.sqrt(var - 1.0 / 12.0)
        assert np.all(np.abs(a - g["blur_px"] / 2) < 0.15 * g["blur_px"] / 2 + 0.3), (a, g)
        checked += 1
    assert checked == 4


BEAMSPLITTER = {
    "kind": "mirror",
    "name": "beamsplitter",
    "position_mm": [0.0, 0.0, 65.0],
    "semi_diameter_mm": 30.0,
    "front": {"coating": {"model": "fixed", "reflectance": 0.04, "transmittance": 0.96}},
}
ONE_LED = {"leds.count": 1, "leds.positions_mm": [[22.0, 0.0, 45.0]]}


@pytest.mark.filterwarnings("ignore::eyelume.compile.LedAimWarning")
@pytest.mark.filterwarnings("ignore::eyelume.analysis.regions.RegionWarning")
def test_partial_mirror_then_cornea_is_the_glint_of_the_led_mirror_image():
    """An LED aimed away from the eye at a 4 % partial mirror (zero thickness: what it passes
    is not deviated) in z = 65 mm lights the cornea from its mirror image: the chain
    ["beamsplitter front", "cornea"] lies where the corneal glint of the mirrored emission point
    lies in the scene without the mirror (the glint truth's own solver, independent of the
    ghosts' code)."""
    from eyelume.analysis.truth import _glint_truth

    cs = compile_scene(
        eyelume.load_scene(
            "paper2005",
            {**ONE_LED, "leds.directions": [[0.0, 0.0, 1.0]], "elements": [BEAMSPLITTER]},
        )
    )
    truth = eye_truth(cs)
    g = _ghost(truth, 0, ["beamsplitter front", "cornea"])
    assert [tuple(e["chain"]) for e in truth["ghosts"]] == [("beamsplitter front", "cornea")]
    assert g["reflectances"][0] == 0.04
    assert g["visible"]
    led = cs.led.points[0].copy()
    image = led.copy()
    image[2] = 2 * BEAMSPLITTER["position_mm"][2] - led[2]
    ref = compile_scene(
        eyelume.load_scene("paper2005", {**ONE_LED, "leds.directions": [[0.0, 0.0, -1.0]]})
    )
    expect = _glint_truth(_view(ref, ref.camera), 0, image, 0)["centre_px"]
    assert np.hypot(*(np.array(g["centre_px"]) - expect)) < 1e-6  # px: both exact
    # the LED sends nothing toward the eye itself: no glint of its own to compare with
    assert g["relative_to_glint"] is None


def _coddington(intensity, refl, s_obj, dist, cos_t, r_t, r_s, cos_g):
    """Irradiance (W/mm²) on a plane at distance ``dist`` from a convex mirror's specular point
    (normal irradiance times ``cos_g``), principal radii ``r_t`` (in the plane of incidence)
    and ``r_s``: the reflected pencil diverges from virtual foci |s_t|, |s_s| behind the point,
    1/|s_t| = 1/s + 2/(r_t cos θ), 1/|s_s| = 1/s + 2 cos θ / r_s (Coddington)."""
    s_t = 1.0 / (1.0 / s_obj + 2.0 / (r_t * cos_t))
    s_s = 1.0 / (1.0 / s_obj + 2.0 * cos_t / r_s)
    return intensity * refl * s_t * s_s / (s_obj**2 * (dist + s_t) * (dist + s_s)) * cos_g


@pytest.mark.filterwarnings("ignore::eyelume.analysis.regions.RegionWarning")
def test_relative_to_glint_against_the_plane_mirror_and_coddington_on_the_cornea():
    """A zero-thickness 4 % partial mirror (nothing it passes is deviated) tilted in front of
    paper2005's eye: LED 0's ghost in it gives I(u) R cos γ / D² at the pupil (its mirror
    image), its corneal glint — seen twice through the mirror, T² — the Coddington irradiance
    of the conic cornea (R = 7.8 mm, k = −0.25) at the specular point, principal radii
    R_s = √(R² − k r²) (sagittal) and R_t = R_s³/R² (tangential; the plane of incidence is the
    meridian: LED 0 and the camera's axis lie in y = 0). ``relative_to_glint`` is their ratio."""
    mirror = {
        "kind": "mirror",
        "name": "window",
        "position_mm": [0.0, 0.0, 48.0],
        "direction": PLATE["direction"],
        "semi_diameter_mm": 27.0,
        "front": {"coating": {"model": "fixed", "reflectance": 0.04, "transmittance": 0.96}},
    }
    cs = _compiled(mirror)
    truth = eye_truth(cs)
    g = _ghost(truth, 0, ["window front"])
    led = cs.led.points[0]
    axis = np.array(mirror["direction"])
    surface = np.array(mirror["position_mm"])
    image = led - 2.0 * ((led - surface) @ axis) * axis
    px, ep = _project(cs, image)
    assert np.hypot(*(np.array(g["centre_px"]) - px)) < 1e-3
    w = (ep - image) / np.linalg.norm(ep - image)
    hit = image + ((surface - image) @ axis) / (w @ axis) * w
    u = (hit - led) / np.linalg.norm(hit - led)
    e_ghost = (
        float(radiant_intensity(cs.led, 0, *u)) * 0.04 * w[2] / np.linalg.norm(ep - image) ** 2
    )
    assert g["pupil_irradiance_w_mm2"] == pytest.approx(e_ghost, rel=1e-5)
    # the glint: Fermat's specular point on the cornea z = -sag(r) for the LED and its chief
    # ray's pupil point (found by projecting the point, twice)
    radius, k = 7.8, -0.25
    assert (cs.scene.eye.surfaces[0].radius_mm, cs.scene.eye.surfaces[0].conic) == (radius, k)

    def on_cornea(a):
        r2 = a[0] ** 2 + a[1] ** 2
        return np.array([a[0], a[1], -r2 / radius / (1 + math.sqrt(1 - (1 + k) * r2 / radius**2))])

    ep = np.array([0.0, 0.0, cs.camera.entrance_pupil_z])
    for _ in range(3):

        def path(a, ep=ep):
            p = on_cornea(a)
            return np.linalg.norm(p - led) + np.linalg.norm(ep - p)

        opts = {"xatol": 1e-12, "fatol": 1e-14}
        pt = on_cornea(optimize.minimize(path, [1.0, 0.0], method="Nelder-Mead", options=opts).x)
        glint_px, ep = _project(cs, pt)
    r = math.hypot(pt[0], pt[1])
    r_s = math.sqrt(radius**2 - k * r**2)
    r_t = r_s**3 / radius**2
    normal = np.array([pt[0], pt[1], math.sqrt(r_s**2 - r**2)]) / r_s  # toward the axis point
    s_obj, dist = np.linalg.norm(pt - led), np.linalg.norm(ep - pt)
    u = (pt - led) / s_obj
    cos_t = abs(u @ normal)
    w = (ep - pt) / dist
    t_mirror = 0.96
    e_glint = t_mirror**2 * _coddington(
        float(radiant_intensity(cs.led, 0, *u)), 0.024, s_obj, dist, cos_t, r_t, r_s, w[2]
    )
    assert np.hypot(*(np.array(truth["glints"][0]["centre_px"]) - glint_px)) < 1e-3
    assert g["relative_to_glint"] == pytest.approx(e_ghost / e_glint, rel=1e-3)


def test_ghosts_of_leds_of_two_wavelengths_each_at_its_own():
    """LEDs at 940 and 850 nm: each LED's ghosts come from its wavelength group's compile
    (the lens's index at that wavelength), marked with it; the 850 nm ones are those of the
    single-wavelength scene; ``ghosts=False`` skips them."""
    one = eye_truth(_compiled(SPECTACLE))
    cs = compile_scene(
        eyelume.load_scene(
            "paper2005", {"elements": [SPECTACLE], "leds.wavelength_nm": [850, 940, 940, 850]}
        )
    )
    two = eye_truth(cs)
    assert {g["led"] for g in two["ghosts"]} == {g["led"] for g in one["ghosts"]}
    for g in two["ghosts"]:
        assert g["wavelength_nm"] == (850.0 if g["led"] in (0, 3) else 940.0)
        same = _ghost(one, g["led"], g["chain"])
        if g["wavelength_nm"] == 850.0:
            assert g["centre_px"] == pytest.approx(same["centre_px"], abs=1e-6)
            assert g["flux_w"] == pytest.approx(same["flux_w"], rel=1e-6)
        else:  # a lower index at 940 nm: a weaker Fresnel reflection
            assert g["reflectances"][0] < same["reflectances"][0]
    assert "ghosts" not in eye_truth(cs, ghosts=False)


def test_reflection_region_is_a_disc_about_each_visible_ghost_and_in_the_stats():
    """The ``reflection`` region (analysis/regions.py): the pixels whose centres lie within
    blur_px/2 (+ the Airy radius: paper2005's prescription lens has no PSF) of each visible
    ghost's true centre, at least 1 px; removed from the pupil, iris, sclera and skin; its
    statistics give a flux."""
    from eyelume.analysis.regions import region_masks, region_stats

    cs = _compiled(SPECTACLE)
    truth = eye_truth(cs)
    masks = region_masks(cs)
    assert "reflection" in masks
    rr, cc = np.mgrid[: cs.picture.rows, : cs.picture.cols]
    expect = np.zeros_like(masks["reflection"])
    visible = [g for g in truth["ghosts"] if g["visible"]]
    assert len(visible) >= 4
    for g in visible:
        rho = max(1.0, g["blur_px"] / 2)
        x, y = g["centre_px"]
        expect |= (cc - x) ** 2 + (rr - y) ** 2 <= rho**2
        # the pixel the ghost's centre falls in is in the region
        assert masks["reflection"][int(round(y)), int(round(x))]
    assert np.array_equal(masks["reflection"], expect)
    for name in ("pupil", "iris", "sclera", "skin"):
        assert not np.any(masks[name] & masks["reflection"]), name
    plain = region_masks(cs, reflections=False)
    assert "reflection" not in plain
    assert np.array_equal(plain["skin"] & ~expect, masks["skin"])
    image = np.ones(masks["skin"].shape)
    stats = region_stats(image, 0.01 * image, masks, pixel_area_mm2=0.5)
    assert stats["reflection"]["pixels"] == int(expect.sum())
    assert stats["reflection"]["flux_w"] == pytest.approx(0.5 * expect.sum())


def test_no_reflection_region_without_elements():
    from eyelume.analysis.regions import region_masks

    cs = compile_scene(eyelume.load_scene("paper2005"))
    assert "reflection" not in region_masks(cs)


def test_false_glint_counts_over_gazes_from_the_truth():
    """The study's ``ghosts`` metric source: at each gaze the visible ghosts at least 5 % of
    their glint, their smallest distance to a visible glint and to the pupil's centre. The
    window's first-surface ghosts do not move with the gaze: each lies at its LED's mirror
    image in the surface's plane, projected (the closed form of the plate test)."""
    from eyelume.analysis.ghosts import FALSE_GLINT_MIN_RELATIVE, false_glint_counts

    scene = eyelume.load_scene("paper2005", {"elements": [PLATE]})
    gh = (0.0, 15.0)
    fg = false_glint_counts(scene, gaze_h=gh, gaze_v=(0.0,))
    cs = compile_scene(scene)
    axis = np.array(PLATE["direction"])
    surface = np.array(PLATE["position_mm"]) + PLATE["thickness_mm"] * axis
    front = []
    for led in cs.led.points:
        image = led - 2.0 * ((led - surface) @ axis) * axis
        front.append(_project(cs, image)[0])
    for j, h in enumerate(gh):
        turned = eyelume.load_scene(
            "paper2005", {"elements": [PLATE], "eye.gaze_horizontal_deg": h}
        )
        t = eye_truth(compile_scene(turned))
        false = [
            g
            for g in t["ghosts"]
            if g["visible"]
            and (
                g["relative_to_glint"] is None or g["relative_to_glint"] >= FALSE_GLINT_MIN_RELATIVE
            )
        ]
        assert fg["false_glints"][0][j] == len(false) > 0
        pts = [g["centre_px"] for g in false]
        firsts = [g for g in false if g["chain"] == ["window back"]]
        assert len(firsts) == 1  # LED 0's: the others image outside the picture
        for g in firsts:
            assert np.hypot(*(np.array(g["centre_px"]) - front[g["led"]])) < 1e-3
        seen = [g["centre_px"] for g in t["glints"] if g["visible"]]
        near = min(math.dist(p, q) for p in pts for q in seen)
        assert fg["nearest_glint_px"][0][j] == pytest.approx(near, rel=1e-12)
        pupil = min(math.dist(p, t["pupil"]["centre_px"]) for p in pts)
        assert fg["pupil_px"][0][j] == pytest.approx(pupil, rel=1e-12)
    plain = false_glint_counts(eyelume.load_scene("paper2005"), gaze_h=(0.0,), gaze_v=(0.0,))
    assert plain["false_glints"] == [[0]] and plain["pupil_px"] == [[None]]


def test_study_ghosts_metric_aggregates_the_grid(monkeypatch):
    """run_metrics' ``ghosts``: the mean and max count over the gazes and the smallest
    distances (None where no gaze has a false glint), on a constructed grid."""
    from eyelume.analysis import ghosts
    from eyelume.optimize.study import Study, run_metrics

    grid = {
        "false_glints": [[0, 2], [1, 0]],
        "nearest_glint_px": [[None, 7.5], [3.25, None]],
        "pupil_px": [[None, 40.0], [12.0, None]],
    }
    monkeypatch.setattr(ghosts, "false_glint_counts", lambda scene: grid)
    scene = eyelume.load_scene("paper2005")
    m = run_metrics(scene, {}, Study(name="g", metrics=["ghosts"]))
    assert m == {
        "false_glints_mean": 0.75,
        "false_glints_max": 2,
        "false_glint_to_glint_px_min": 3.25,
        "false_glint_to_pupil_px_min": 12.0,
    }
    grid = {k: [[None if k != "false_glints" else 0]] for k in grid}
    m = run_metrics(scene, {}, Study(name="g", metrics=["ghosts"]))
    assert m["false_glints_max"] == 0 and m["false_glint_to_glint_px_min"] is None


def test_every_ghost_of_paper2005_integrated_compares_with_its_leds_glint():
    """``relative_to_glint`` was null for LED 0's ghost on paper2005-integrated although its
    corneal glint is in the truth: the ghosts' own glint search (Newton from a 9 × 9 grid of
    the sensor) missed it, 0.11 mm from the sensor's centre between two grid points; it now
    starts from the truth's glint. Every ghost's LED has a glint there, so every ghost gets a
    number; and the four glints' irradiances at the entrance pupil are equal (the eye, the
    ring of LEDs, the eyepiece and the camera unfolded by the mirror all share the eye's
    axis: the fourfold symmetry), LED 0's included."""
    from eyelume.analysis.ghosts import _one_glint
    from eyelume.detectors.receivers import BinnedPlane

    cs = compile_scene(eyelume.load_scene("paper2005-integrated"))
    truth = eye_truth(cs)
    assert truth["ghosts"] and all(g["on_cornea"] for g in truth["glints"])
    for g in truth["ghosts"]:
        assert g["relative_to_glint"] is not None, g
        assert "relative_to_glint_note" not in g
    v = _view(cs, cs.camera)
    pixels = {g["led"]: g["centre_px"] for g in truth["glints"]}
    e = [
        _one_glint(v, row, led, np.array(BinnedPlane(cs.picture).from_pixel(*pixels[row])))
        for row, led in enumerate(cs.led.points)
    ]
    assert all(x is not None and x > 0 for x in e), e
    np.testing.assert_allclose(e, e[1], rtol=1e-6)


def test_a_ghost_without_its_leds_glint_says_why(monkeypatch):
    """Where an LED's corneal glint does not exist (the truth's glint entry has no pixel and
    the ghosts' search finds none: made so here), its ghosts' ``relative_to_glint`` is null
    and ``relative_to_glint_note`` gives the truth's reason."""
    from eyelume.analysis import ghosts as gh

    cs = compile_scene(eyelume.load_scene("paper2005-integrated"))
    v = _view(cs, cs.camera)
    none = [
        {"led": k, "centre_px": None, "reason": "no reflection toward this LED (test)"}
        for k in range(4)
    ]
    monkeypatch.setattr(gh, "_one_glint", lambda *a: None)
    ghosts = ghost_truth(v, none)
    assert ghosts
    for g in ghosts:
        assert g["relative_to_glint"] is None
        assert g["relative_to_glint_note"] == (
            "no corneal glint of this LED: no reflection toward this LED (test)"
        )
