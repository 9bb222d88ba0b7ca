"""A dataset picture's labels (issue 17) against computations written out here: the ellipse
convention on synthetic points, the segmentation's pupil against the pupil ellipse, the camera
model projecting the truth's limbus points (OpenCV's ``projectPoints``), the ideal lens's K from
its EFL, focus distance and pitch, the eye's axes in the paper's rig, the glint flags, the
OpenEDS view, and a label validated against the shipped JSON schema."""

from __future__ import annotations

import json
import math

import cv2
import jsonschema
import numpy as np
import pytest
from scipy import optimize

from eyelume.analysis import labels as L
from eyelume.analysis.regions import region_masks
from eyelume.analysis.truth import eye_truth
from eyelume.compile import compile_scene, eye_point
from eyelume.estimators.fast_run import trace_fast
from eyelume.scene.eye import limbus_geometry
from eyelume.scene.io import apply_overrides, load_scene

#: vr-offaxis at 100 × 100 pixels over the OV6211's 1.2 mm chip (12 µm bins): a small picture
#: of the same field, for speed.
SMALL = {"sensor.cols": 100, "sensor.rows": 100, "sensor.pixel_pitch_um": 12.0}
#: Eye turned so that the pupil is wholly visible and off-centre in both pictures.
GAZE = {"eye.gaze_horizontal_deg": 8.0, "eye.gaze_vertical_deg": -5.0}


def _picture(name: str, overrides: dict):
    scene = apply_overrides(load_scene(name), overrides)
    cs = compile_scene(scene)
    truth = eye_truth(cs)
    masks = region_masks(cs)
    label, seg = L.picture_labels(cs, None, None, None, masks, truth)
    return cs, truth, label, seg


@pytest.fixture(scope="module")
def vr():
    return _picture("vr-offaxis", {**SMALL, **GAZE})


@pytest.fixture(scope="module")
def paper():
    return _picture("paper2005", GAZE)


# ----------------------------------------------------------------------------- ellipses


@pytest.mark.parametrize("angle", [30.0, -50.0, 90.0, 0.0])
def test_ellipse_fit_recovers_a_synthetic_ellipse_in_the_stated_convention(angle):
    """Points x = c + a cos t (cos θ, sin θ) + b sin t (−sin θ, cos θ) (image y down) give back
    c, a ≥ b and θ in (−90°, 90°]; and a pixel along +θ from the centre lies inside."""
    c, a, b = np.array([40.3, 22.7]), 15.0, 6.0
    th = math.radians(angle)
    t = np.linspace(0, 2 * math.pi, 50, endpoint=False)
    u, v = np.array([math.cos(th), math.sin(th)]), np.array([-math.sin(th), math.cos(th)])
    pts = c + np.outer(a * np.cos(t), u) + np.outer(b * np.sin(t), v)
    e = L.fit_ellipse(pts)
    assert e["center_px"] == pytest.approx(c.tolist(), abs=1e-9)
    assert e["semi_axes_px"] == pytest.approx([a, b], abs=1e-9)
    assert e["angle_deg"] == pytest.approx(angle if angle != -90.0 else 90.0, abs=1e-7)
    # a point 12 px along the major axis (toward +x, +y = down for θ > 0) is inside, the same
    # point mirrored about the x axis (the other sign convention) is not
    p = c + 12.0 * u
    q = c + 12.0 * np.array([u[0], -u[1]])
    mask = L.ellipse_mask(e, (60, 80))
    r, col = int(round(p[1])), int(round(p[0]))
    assert mask[r, col]
    if abs(angle) not in (0.0, 90.0):
        assert not mask[int(round(q[1])), int(round(q[0]))]


def test_ellipse_fit_agrees_with_opencv_on_the_swapped_axes():
    """The same ellipse from cv2.fitEllipse (an independent implementation, its own
    convention: full axes (w, h), angle of w) rasterised by its own points."""
    rng = np.random.default_rng(3)
    c, a, b, th = np.array([30.0, 25.0]), 12.0, 7.0, math.radians(-35.0)
    t = rng.uniform(0, 2 * math.pi, 40)
    u, v = np.array([math.cos(th), math.sin(th)]), np.array([-math.sin(th), math.cos(th)])
    pts = c + np.outer(a * np.cos(t), u) + np.outer(b * np.sin(t), v)
    ours = L.fit_ellipse(pts)
    (cx, cy), (w, h), ang = cv2.fitEllipse(pts.astype(np.float32))
    theirs = {"center_px": [cx, cy], "semi_axes_px": [w / 2, h / 2], "angle_deg": ang}
    if h > w:
        theirs = {"center_px": [cx, cy], "semi_axes_px": [h / 2, w / 2], "angle_deg": ang + 90.0}
    inside = L.ellipse_mask(ours, (50, 60))
    assert (inside == L.ellipse_mask(theirs, (50, 60))).mean() > 0.995


# --------------------------------------------------------------------------- segmentation


@pytest.mark.parametrize("which", ["vr", "paper"])
def test_segmentation_pupil_matches_the_pupil_ellipse(which, request):
    """Both are pixel-centre samplings of the apparent pupil's outline: the segmentation by the
    chief ray through each pixel centre, the ellipse by its inside test. They can differ only
    at pixels whose centres lie between the fitted ellipse and the true outline. The outline
    deviates from the fit by fit_rms_px (refraction by the cornea; checked < 0.05 px) and at
    most a few times that; a band of width w along a curve of length P holds about P w pixel
    centres: the bound is P × 10 fit_rms_px + 1. A sign-flipped angle, or the centre off by
    half a pixel (the other pixel-centre convention), exceeds it many times (vr-offaxis: 37
    and 22 pixels against a bound of 4.8)."""
    cs, truth, label, seg = request.getfixturevalue(which)
    assert label["pupil"]["visible_share"] == 1.0
    e = label["pupil"]["ellipse"]
    assert e["fit_rms_px"] < 0.05
    pupil = L.openeds_map(seg, L.primary_classes(cs)) == 3
    ell = L.ellipse_mask(e, seg.shape)
    a, b = e["semi_axes_px"]
    perimeter = math.pi * (3 * (a + b) - math.sqrt((3 * a + b) * (a + 3 * b)))  # Ramanujan
    bound = perimeter * 10 * e["fit_rms_px"] + 1
    mismatch = int((pupil ^ ell).sum())
    assert mismatch <= bound, (mismatch, bound)
    assert (pupil & ell).sum() / (pupil | ell).sum() >= 1 - bound / ell.sum()
    # the pupil's label: its centre's image lies inside the ellipse, near its centre
    assert np.hypot(*np.subtract(label["pupil"]["center_px"], e["center_px"])) < 0.1 * b


@pytest.fixture(scope="module")
def folded():
    """paper2005-integrated: the camera sees the eye through an eyepiece, folded by a hot
    mirror."""
    return _picture("paper2005-integrated", GAZE)


@pytest.mark.parametrize("which", ["vr", "paper", "folded"])
def test_the_limbus_ellipse_bounds_the_segmentations_iris(which, request):
    """The picture's iris region ends at the limbus (the chief ray meets the cornea inside its
    clear aperture, so it reaches the iris or its root, or the sclera outside it); the limbus
    ellipse comes from 72 limbus points imaged one by one. Outside the ellipse no pixel is iris
    or pupil; inside it every pixel is iris, pupil or an eyelid (or skin) covering them — to
    the same band as the pupil's test (P × 10 fit_rms_px + 1 pixel). Through the folded view
    a Newton root on a ray that misses the mirror would put the outline elsewhere."""
    cs, truth, label, _ = request.getfixturevalue(which)
    assert len(truth["iris"]["edge_px"]) == 72
    e = label["iris"]["ellipse"]
    u = L.primary_classes(cs)
    ell = L.ellipse_mask(e, u.shape)
    eye = np.isin(u, [2, 3])
    a, b = e["semi_axes_px"]
    bound = math.pi * (a + b) * 10 * e["fit_rms_px"] + 1
    assert (eye & ~ell).sum() <= bound
    assert (ell & ~eye & ~np.isin(u, [4, 5])).sum() <= bound
    assert 0.2 < label["iris"]["visible_share"] < 1.0  # the lids cover its top and bottom


def test_segmentation_classes_and_the_openeds_view(vr):
    cs, truth, label, seg = vr
    assert seg.dtype == np.uint8 and seg.shape == (100, 100)
    present = set(np.unique(seg).tolist())
    assert {1, 2, 3, 4, 5} <= present  # sclera, iris, pupil, skin, the lids all in view
    # eyelid pixels are those whose surface is a lid: above and below the iris, not beside it
    cx, cy = label["iris"]["ellipse"]["center_px"]
    rows = np.nonzero((seg == 5).any(axis=1))[0]
    assert rows.min() < cy < rows.max()
    o = L.openeds_map(seg)
    assert set(np.unique(o).tolist()) <= {0, 1, 2, 3}
    assert np.array_equal(o[seg <= 3], seg[seg <= 3])


def test_openeds_map_puts_the_class_under_a_glint():
    seg = np.full((9, 9), 2, dtype=np.uint8)  # iris
    seg[:, 6:] = 4  # skin on the right
    seg[3:6, 3:6] = 3  # pupil
    seg[4, 4] = 6  # a glint on the pupil
    seg[0, 0] = 7  # a reflection on the iris
    under = seg.copy()
    under[4, 4], under[0, 0] = 3, 2
    o = L.openeds_map(seg)
    assert o[4, 4] == 3 and o[0, 0] == 2 and (o[:, 6:] == 0).all()
    assert np.array_equal(o, L.openeds_map(seg, under))


# ------------------------------------------------------------------------------- camera


def _limbus_world(cs) -> np.ndarray:
    """The 72 limbus points (world mm) as truth places them, written out here."""
    r_l, z_l, _ = limbus_geometry(cs.scene.eye)
    a = 2 * np.pi * np.arange(72) / 72
    return np.array([eye_point(cs.scene, [r_l * math.cos(t), r_l * math.sin(t), -z_l]) for t in a])


@pytest.mark.parametrize("which", ["vr", "paper"])
def test_the_camera_model_projects_the_limbus_onto_the_truths_pixels(which, request):
    """The limbus lies on the eye's outer surface: truth images each point by the chief ray
    through it (Newton on the real camera: the ideal lens, or the paper's Double Gauss). The
    label's K, dist, R, t with cv2.projectPoints must put it there: to 1e-3 px for the ideal
    lens (exact model), to 5 × the fit's RMS for the Double Gauss."""
    cs, truth, label, _ = request.getfixturevalue(which)
    cam = label["camera"]
    world = _limbus_world(cs)
    rvec = cv2.Rodrigues(np.array(cam["R"]))[0]
    px = cv2.projectPoints(
        world, rvec, np.array(cam["t_mm"]), np.array(cam["K"]), np.array(cam["dist"])
    )[0].reshape(-1, 2)
    assert len(truth["iris"]["edge_px"]) == 72
    err = np.hypot(*(px - np.array(truth["iris"]["edge_px"])).T)
    tol = 1e-3 if cs.scene.camera.optics == "ideal" else max(5 * cam["intrinsics_fit_rms_px"], 1e-3)
    assert err.max() < tol, (err.max(), cam["intrinsics_fit_rms_px"])
    # the same through the camera frame: x_cam = R x + t in front of the camera (z > 0)
    xc = world @ np.array(cam["R"]).T + np.array(cam["t_mm"])
    assert (xc[:, 2] > 0).all()
    px2 = cv2.projectPoints(
        xc, np.zeros(3), np.zeros(3), np.array(cam["K"]), np.array(cam["dist"])
    )[0].reshape(-1, 2)
    assert np.allclose(px2, px, atol=1e-9)


@pytest.mark.parametrize(
    "overrides",
    [{"eye_pose.which": "left"}, {"head_offset_mm": [1.0, -0.5, 0.7], "camera.roll_deg": 12.0}],
    ids=["left eye", "slip and roll"],
)
def test_the_camera_model_for_a_left_eye_and_a_rolled_camera(overrides):
    """A left eye (the whole headset mirrored, x → −x) and a camera rolled 12° with the headset
    slipped: R stays a proper rotation and the limbus projects onto the truth's pixels."""
    cs, truth, label, _ = _picture("vr-offaxis", {**SMALL, **GAZE, **overrides})
    cam = label["camera"]
    assert np.linalg.det(np.array(cam["R"])) == pytest.approx(1.0, abs=1e-12)
    rvec = cv2.Rodrigues(np.array(cam["R"]))[0]
    px = cv2.projectPoints(
        _limbus_world(cs), rvec, np.array(cam["t_mm"]), np.array(cam["K"]), np.array(cam["dist"])
    )[0].reshape(-1, 2)
    assert np.abs(px - np.array(truth["iris"]["edge_px"])).max() < 1e-3


def test_the_ideal_lens_intrinsics_from_efl_focus_distance_and_pitch():
    """fx = fy = v / p with v = 1 / (1/f − 1/s) the image distance and p the pixel pitch;
    (cx, cy) the picture's centre; dist = (k1, k2, 0, 0, 0) as the scene gives them."""
    scene = apply_overrides(
        load_scene("vr-offaxis"),
        {**SMALL, "camera.ideal.k1": -0.05, "camera.ideal.k2": 0.01},
    )
    cs = compile_scene(scene)
    cam = L.camera_intrinsics(cs)
    ideal = scene.camera.ideal
    v = 1.0 / (1.0 / ideal.efl_mm - 1.0 / ideal.focus_distance_mm)
    f_px = v / 0.012
    assert np.allclose(cam["K"], [[f_px, 0, 49.5], [0, f_px, 49.5], [0, 0, 1]], rtol=1e-12)
    assert cam["dist"] == [-0.05, 0.01, 0.0, 0.0, 0.0]
    # exact model: the chief rays of the distorting lens land where OpenCV puts them
    assert cam["intrinsics_fit_rms_px"] < 1e-6


def test_calibrate_camera_on_an_ideal_lens_recovers_its_exact_model():
    """The fitting path (cv2.calibrateCamera on the chief rays), run on an ideal lens with
    distortion, against the lens's own K and (k1, k2): the chief rays follow OpenCV's model
    exactly, so only the fit's convergence separates them (1e-6 relative)."""
    scene = apply_overrides(
        load_scene("vr-offaxis"),
        {**SMALL, "camera.ideal.k1": -0.05, "camera.ideal.k2": 0.01},
    )
    cs = compile_scene(scene)
    exact, fitted = L.camera_intrinsics(cs), L.camera_intrinsics(cs, fit=True)
    assert np.allclose(fitted["K"], exact["K"], rtol=1e-6)
    assert fitted["dist"] == pytest.approx([-0.05, 0.01, 0.0, 0.0, 0.0], abs=1e-4)
    assert np.allclose(fitted["R"], exact["R"], atol=1e-7)
    assert np.allclose(fitted["t_mm"], exact["t_mm"], atol=1e-5)
    assert fitted["intrinsics_fit_rms_px"] < 1e-4


def test_the_paper_rigs_eye_in_the_opencv_camera_frame(paper):
    """The paper's camera looks along −z at the eye: OpenCV's R is diag(1, −1, −1) (up to the
    fit's rounding) and the eye turned by GAZE (up/right in the world) has its optical axis
    (out of the eye, toward the camera: −z) with x ∝ sin h, y ∝ −sin v·… (down in OpenCV is
    −y of the world); the eyeball centre lies 13.5 − 7.8 = 5.7 mm behind the corneal centre
    along the axis."""
    cs, truth, label, _ = paper
    cam, frame = label["camera"], label["camera_frame"]
    assert np.allclose(cam["R"], np.diag([1.0, -1.0, -1.0]), atol=1e-6)
    h, v = math.radians(8.0), math.radians(-5.0)
    # world optical axis: R_y(h) R_x(−v) (0, 0, 1) = (sin h cos v, sin v, cos h cos v)
    world_axis = np.array([math.sin(h) * math.cos(v), math.sin(v), math.cos(h) * math.cos(v)])
    assert frame["optical_axis"] == pytest.approx(world_axis * [1, -1, -1], abs=1e-9)
    d = np.array(frame["eyeball_center_mm"]) - np.array(frame["cornea_center_mm"])
    assert np.linalg.norm(d) == pytest.approx(13.5 - 7.8, abs=1e-9)
    assert d / np.linalg.norm(d) == pytest.approx(-np.array(frame["optical_axis"]), abs=1e-9)


# ------------------------------------------------------------------------------- glints


def _centroids(images: np.ndarray) -> np.ndarray:
    """Each glint image's intensity centroid (x, y) in pixels (OpenCV convention)."""
    r, c = np.mgrid[0 : images.shape[1], 0 : images.shape[2]]
    w = images.sum(axis=(1, 2))
    return np.stack([(images * c).sum(axis=(1, 2)) / w, (images * r).sum(axis=(1, 2)) / w], 1)


def test_glint_positions_against_the_rendered_spots_centroids(paper):
    """The paper's camera blurs each glint over ~14 pixels (FocusWarning: the sensor sits
    1.9 mm behind best focus), so its intensity centroid in the fast estimator's per-LED glint
    image is a sub-pixel measurement. Two independent renders (seeds 1, 2; 200 000 light paths
    aimed at the cornea each) give the centroids' noise: σ of one render from the pooled
    differences, σ/√2 for their mean. The label's position must lie within 4 σ/√2 + 0.05 px
    of the mean (0.05 px: the aberrated spot's centroid need not sit on the chief ray; 0.03 px
    measured at 1.45 M paths), and within a quarter pixel in any case."""
    cs, truth, label, _ = paper
    runs = [_centroids(trace_fast(cs, 2, 80_000, seed).glint_images) for seed in (1, 2)]
    sigma = math.sqrt(np.mean((runs[0] - runs[1]) ** 2) / 2)
    mean = (runs[0] + runs[1]) / 2
    got = np.array([g["position_px"] for g in label["glints"]])
    assert all(g["visible"] for g in label["glints"]) and len(got) == 4
    err = np.abs(got - mean)
    assert err.max() <= 4 * sigma / math.sqrt(2) + 0.05, (err, sigma)
    assert err.max() < 0.25


def test_eye_openness_against_the_lid_margins_projected():
    """Paper rig, primary gaze: the lid margins are the circles y = +4.5 mm and y = −5.5 mm of
    the lid spheres (radius 13 mm about the eyeball centre 13.04 mm behind the vertex); their
    front points, projected by the label's camera, bound the eyeball's run in the limbus's
    column. Openness = that run (px) over the limbus's vertical chord, to ±1.5 px of the run
    (pixel centres) over the chord."""
    cs, truth, label, _ = _picture("paper2005", {})
    cam = label["camera"]
    z = lambda y: -13.04 + math.sqrt(13.0**2 - y**2)  # noqa: E731
    pts = np.array([[0.0, 4.5, z(4.5)], [0.0, -5.5, z(5.5)]])
    rvec = cv2.Rodrigues(np.array(cam["R"]))[0]
    px = cv2.projectPoints(
        pts, rvec, np.array(cam["t_mm"]), np.array(cam["K"]), np.array(cam["dist"])
    )[0].reshape(-1, 2)
    e = label["iris"]["ellipse"]
    a, b = e["semi_axes_px"]
    th = math.radians(e["angle_deg"])
    chord = 2 / math.sqrt(math.sin(th) ** 2 / a**2 + math.cos(th) ** 2 / b**2)  # along y
    expected = (px[1, 1] - px[0, 1]) / chord
    assert label["eye_openness"] == pytest.approx(expected, abs=1.5 / chord)
    assert 0.7 < label["eye_openness"] < 0.95  # the lids cover the limbus's top and bottom


#: A limbus ellipse for the synthetic columns below: centre (2, 20), a = 12 px along x, b = 8 px
#: along y, so its vertical chord through the centre is 16 px: the iris spans y ∈ [12, 28].
LIMBUS = {"center_px": [2.0, 20.0], "semi_axes_px": [12.0, 8.0], "angle_deg": 0.0}


def _column(eyeball_rows: range, rows: int = 40) -> np.ndarray:
    """A 5-column primary map: eyelid (5) everywhere, eyeball rows as iris (2), one as sclera."""
    m = np.full((rows, 5), L._CLASS["eyelid"], dtype=np.uint8)
    m[list(eyeball_rows), :] = L._CLASS["iris"]
    if len(eyeball_rows):
        m[eyeball_rows[0], :] = L._CLASS["sclera"]
    return m


@pytest.mark.parametrize(
    ("eyeball", "expected"),
    [
        (range(0, 40), 1.0),  # wide open, sclera above and below the iris: still 1
        (range(5, 35), 1.0),  # lids beyond the iris's top and bottom
        (range(15, 25), 10.0 / 16.0),  # y ∈ [14.5, 24.5] of the iris's [12, 28]
        (range(10, 26), 13.5 / 16.0),  # [9.5, 25.5] ∩ [12, 28] = [12, 25.5]
        (range(20, 21), 1.0 / 16.0),  # the centre's row alone
        (range(0, 20), 0.0),  # the lower lid over the centre: closed
        (range(0, 0), 0.0),  # closed
    ],
)
def test_eye_openness_is_the_visible_share_of_the_iris_height(eyeball, expected):
    """In [0, 1] by construction: 1 with the lids wide open (the fresh user's 1.18 and 1.61
    counted the sclera above and below the iris), 0 closed, and partial values computed by
    hand from the pixel edges and the limbus's chord."""
    got = L.eye_openness(_column(eyeball), LIMBUS)
    assert got == pytest.approx(expected, abs=1e-12)
    assert 0.0 <= got <= 1.0


def test_eye_openness_of_vr_offaxis_in_primary_gaze_is_at_most_one():
    """vr-offaxis in primary gaze, where the fresh user saw 1.18: the lids leave all or nearly
    all of the iris's height visible in this camera's view."""
    _, _, label, _ = _picture("vr-offaxis", SMALL)
    assert 0.5 < label["eye_openness"] <= 1.0


def test_a_glint_off_the_cornea_is_placed_on_the_sclera_by_fermats_principle():
    """vr-offaxis, the eye turned 25° away from the nose: LED 0's reflection leaves the cornea's
    cap. Its sclera mirror image is where |LED − P| + |P − O| is stationary for P on the
    eyeball sphere (12 mm about the eyeball centre; O the ideal lens's centre, the pinhole
    −Rᵀt), found here by SciPy and projected by the label's camera."""
    cs, truth, label, _ = _picture("vr-offaxis", {**SMALL, "eye.gaze_horizontal_deg": -25.0})
    g = label["glints"][0]
    assert not g["on_cornea"] and g["on_sclera"] and not g["visible"]
    cam = label["camera"]
    r, t = np.array(cam["R"]), np.array(cam["t_mm"])
    o = -r.T @ t
    led = np.array(label["leds"][0]["position_mm"])
    centre = eye_point(cs.scene, [0.0, 0.0, -limbus_geometry(cs.scene.eye)[2]])
    rad = cs.scene.eye.sclera_radius_mm

    def on_sphere(a):
        return centre + rad * np.array(
            [math.cos(a[1]) * math.sin(a[0]), math.sin(a[1]), math.cos(a[1]) * math.cos(a[0])]
        )

    def path(a):
        p = on_sphere(a)
        return np.linalg.norm(led - p) + np.linalg.norm(p - o)

    bis = (led - centre) / np.linalg.norm(led - centre) + (o - centre) / np.linalg.norm(o - centre)
    a0 = [math.atan2(bis[0], bis[2]), math.asin(bis[1] / np.linalg.norm(bis))]
    p = on_sphere(
        optimize.minimize(
            path, a0, method="Nelder-Mead", options={"xatol": 1e-12, "fatol": 1e-14}
        ).x
    )
    px = cv2.projectPoints(
        p[None], cv2.Rodrigues(r)[0], t, np.array(cam["K"]), np.array(cam["dist"])
    )[0].reshape(2)
    assert np.hypot(*(px - g["position_px"])) < 1e-3


def test_lashes_are_eyelid_and_glints_under_them_hidden():
    """vr-offaxis with lashes, the eye looking 25° down (the upper lid and its lashes follow):
    every pixel whose chief ray meets a lash (the primary surface map, read here) is class 5;
    a glint on the cornea whose pixel shows a lid or lash is hidden, never visible; a visible
    glint has iris or pupil under it (the cornea's cap lies within the limbus)."""
    from eyelume.compile import LASHES_NAME
    from eyelume.estimators.fast_run import primary_surface_map

    cs, truth, label, seg = _picture(
        "vr-offaxis", {**SMALL, "face.lashes.enabled": True, "eye.gaze_vertical_deg": -25.0}
    )
    under = L.primary_classes(cs)
    surf, _ = primary_surface_map(cs)
    lash = surf == cs.surface_names.index(LASHES_NAME)
    assert lash.sum() > 50 and (under[lash] == 5).all()
    hidden = [g for g in label["glints"] if g["hidden"]]
    assert hidden and all(not g["visible"] for g in hidden)
    under_lid = 0
    for g in label["glints"]:
        if g["position_px"] is None or not g["on_cornea"]:
            continue
        c, r = (int(round(x)) for x in g["position_px"])
        if under[r, c] == 5:
            assert g["hidden"]
            under_lid += 1
        if g["visible"]:
            assert under[r, c] in (2, 3)
    assert under_lid  # one glint lies behind the lid or its lashes as the camera sees it


def test_glint_flags_from_the_sensors_saturated_pixels(vr):
    cs, truth, _, _ = vr
    sat = np.zeros((100, 100), dtype=bool)
    g = next(e for e in truth["glints"] if e["visible"])
    c, r = (int(round(x)) for x in g["centre_px"])
    sat[r + 1, c] = True  # within the 3 × 3 neighbourhood
    glints = L._glints(cs, truth, sat)
    flagged = {e["led"] for e in glints if e["saturated"]}
    assert g["led"] in flagged
    sat[:] = False
    sat[r + 3, c] = True  # two pixels beyond it
    assert not any(e["saturated"] for e in L._glints(cs, truth, sat) if e["led"] == g["led"])


def test_leds_seen_directly_are_reflections():
    """eyetrackvr's wide lens sees its LED ring: each LED in view is a 'led in view'
    reflection and its pixel is class 7 in the segmentation (background in the OpenEDS view)."""
    cs, truth, label, seg = _picture("eyetrackvr", {})
    seen = [e for e in label["reflections"] if e["kind"] == "led in view" and e["visible"]]
    assert seen
    for e in seen:
        c, r = (int(round(x)) for x in e["position_px"])
        assert seg[r, c] == 7
        assert L.openeds_map(seg)[r, c] != 7


def test_picture_labels_refuses_arrays_of_another_size(vr):
    cs, truth, _, _ = vr
    masks = region_masks(cs)
    with pytest.raises(ValueError, match="saturated"):
        L.picture_labels(cs, None, np.zeros((10, 10), bool), None, masks, truth)
    with pytest.raises(ValueError, match="pupil"):
        L.picture_labels(cs, None, None, None, {**masks, "pupil": masks["pupil"][1:]}, truth)


# ------------------------------------------------------------------------------- schema


def test_a_label_line_validates_against_the_schema(vr, paper):
    schema = json.loads(L.SCHEMA_PATH.read_text(encoding="utf-8"))
    jsonschema.Draft202012Validator.check_schema(schema)
    validator = jsonschema.Draft202012Validator(schema)
    book = {
        "index": 0,
        "seed": 123,
        "image": "images/000000.png",
        "irradiance": "irradiance/000000.npy",
        "segmentation": "segmentation/000000.png",
        "image_bits": 8,
        "varied": {"eye.pupil_diameter_mm": 4.0},
        "person": None,
        "glasses": False,
        "render": {
            "estimator": "fast",
            "samples_per_pixel": 8,
            "median_skin_rel_error": 0.01,
            "skin_shot_noise": 0.02,
            "seconds": 1.0,
        },
    }
    for _, _, label, _ in (vr, paper):
        line = json.loads(json.dumps({**book, **label}))  # what labels.jsonl holds
        validator.validate(line)
    # the schema is strict: a misspelt key or a missing one is refused
    bad = json.loads(json.dumps({**book, **vr[2]}))
    bad["pupil"]["ellipse"]["angle"] = bad["pupil"]["ellipse"].pop("angle_deg")
    assert not validator.is_valid(bad)
    bad = json.loads(json.dumps({**book, **vr[2]}))
    del bad["camera"]
    assert not validator.is_valid(bad)
