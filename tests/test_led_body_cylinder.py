"""An LED's flat package: ``leds.body_shape = "cylinder"`` (a closed absorbing cylinder coaxial
with the LED's axis, ``body_diameter_mm`` across and ``body_length_mm`` long).

The shadow test: LED A (a 1.6 mm sphere at (0, 0, 50) mm, aimed along −z) lights the eye plane
z = 0; LED B's cylinder (4 mm across, 4 mm long, centre (−4, 3, 25) mm) stands between them
off A's axis, either facing A (its axis +z: A's light meets its front disk and side; B's own
light, cosᵐ with nothing beyond 90°, never reaches the plane) or turned away (its axis
(0.6, 0, −0.8): A's light meets its back and side, where the table has no back disk — the
cylinder's side and front stand for the closed body; B's I₀ then 10⁻⁹ of A's, its light on
the plane below I_B / (20 mm)²). A point P of the plane is in B's shadow when the segment
from P to A's emission point E meets the solid cylinder: written here in closed form (the
segment's parameter interval inside the slab |(X − C)·â| ≤ L/2 intersected with the one
inside the infinite cylinder, a quadratic), independent of the kernel's surfaces. Bins wholly
inside the shadow get no direct light from A in either estimator; bins wholly outside it see
the bare point source I₀ cosᵐα cos β / r², within the stratified-jitter bound of
``test_camera_body.py``.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from typer.testing import CliRunner

from eyelume.cli import app
from eyelume.compile import compile_scene, led_body_rows
from eyelume.errors import SceneError
from eyelume.estimators.closed_form import geometry_problem
from eyelume.estimators.fast_run import direct_eye_plane
from eyelume.kernels import sequential as Q
from eyelume.layout import system_sections
from eyelume.render import RenderOptions, render
from eyelume.scene.io import apply_overrides, load_scene
from eyelume.scene.model import LedArray

E_CENTRE = np.array([0.0, 0.0, 50.0])  # LED A's body centre, mm
RB_A = 0.8
EMIT = E_CENTRE + RB_A * np.array([0.0, 0.0, -1.0])  # its apex: where its light leaves
B_CENTRE = np.array([-4.0, 3.0, 25.0])
B_R, B_L = 2.0, 4.0
I0 = 0.001
HALF = 60.0
#: B's axis and I₀: facing A (its light never reaches the plane), or turned away, all but dark
B_POSES = {"facing": ((0.0, 0.0, 1.0), I0), "turned": ((0.6, 0.0, -0.8), 1e-9 * I0)}


def _scene(b_shape="cylinder", pose="facing", b_centre=B_CENTRE):
    axis, i_b = B_POSES[pose]
    length = [2 * RB_A, B_L] if b_shape == "cylinder" else None
    return apply_overrides(
        load_scene("vr-offaxis"),
        {
            "leds.body_length_mm": length,
            "face.enabled": False,
            "camera.position_mm": [15.0, 0.0, 30.0],
            "camera.look_at_mm": [0.0, 0.0, 0.0],
            "camera.body.enabled": False,
            "eye_plane.cols": 40,
            "eye_plane.rows": 30,
            "leds.count": 2,
            "leds.positions_mm": [E_CENTRE.tolist(), list(b_centre)],
            "leds.directions": [[0.0, 0.0, -1.0], list(axis)],
            "leds.body_shape": ["sphere", b_shape],
            "leds.body_diameter_mm": [2 * RB_A, 2 * B_R],
            "leds.radiant_intensity_w_sr": [I0, i_b],
            "leds.profile.half_intensity_angle_deg": HALF,
        },
    )


def _shadowed(x, y, axis):
    """Whether the segment from the plane point (x, y, 0) to E meets B's solid cylinder."""
    axis = np.asarray(axis, dtype=float)
    p = np.stack([x, y, np.zeros_like(x)], axis=-1) - B_CENTRE
    d = EMIT - B_CENTRE - p  # P + t d, t in [0, 1], B's centre at the origin
    pa, da = p @ axis, d @ axis
    # the slab |(P + t d)·â| <= L/2 (â·d ≠ 0 here: E lies well off B's faces' planes)
    t1, t2 = (-B_L / 2 - pa) / da, (B_L / 2 - pa) / da
    lo, hi = np.maximum(np.minimum(t1, t2), 0.0), np.minimum(np.maximum(t1, t2), 1.0)
    # the infinite cylinder: |q + t e|² <= R², q and e the parts across the axis
    q, e = p - pa[..., None] * axis, d - da[..., None] * axis
    a, b, c = (e * e).sum(-1), 2 * (q * e).sum(-1), (q * q).sum(-1) - B_R**2
    disc = b * b - 4 * a * c
    root = np.sqrt(np.maximum(disc, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):  # a = 0: a segment along the axis
        c1, c2 = (-b - root) / (2 * a), (-b + root) / (2 * a)
    along = (a == 0) & (c < 0) & (lo < hi)  # parallel to the axis, within its radius
    return along | ((a > 0) & (disc > 0) & (np.maximum(lo, c1) < np.minimum(hi, c2)))


def _bins(scene, axis):
    """Per bin: A's point-source mean (24 × 24 midpoint rule), the spread Δ_b, whether it is
    wholly in B's shadow (its 4 corners are: the shadow of a convex body is convex) and whether
    wholly out of it (no point of a 16 × 16 grid over the bin grown by a quarter bin is)."""
    m = math.log(0.5) / math.log(math.cos(math.radians(HALF)))
    ep = scene.eye_plane
    bw, bh = ep.width_mm / ep.cols, ep.height_mm / ep.rows

    def irradiance(x, y):
        v = np.stack([x, y, np.zeros_like(x)], axis=-1) - EMIT
        r = np.linalg.norm(v, axis=-1)
        cos = -v[..., 2] / r  # A's axis is −z, the plane's normal +z: α = β
        return I0 * cos**m * cos / r**2

    k = (np.arange(24) + 0.5) / 24
    g = np.linspace(-0.25, 1.25, 16)
    shape = (ep.rows, ep.cols)
    mean, spread = np.empty(shape), np.empty(shape)
    inside, outside = np.zeros(shape, bool), np.zeros(shape, bool)
    for row in range(ep.rows):
        y0 = ep.height_mm / 2 - (row + 1) * bh
        for col in range(ep.cols):
            x0 = -ep.width_mm / 2 + col * bw
            xx, yy = np.meshgrid(x0 + k * bw, y0 + k * bh)
            mean[row, col] = irradiance(xx, yy).mean()
            cx, cy = x0 + np.array([0, 1, 0, 1, 0.5]) * bw, y0 + np.array([0, 0, 1, 1, 0.5]) * bh
            e = irradiance(cx, cy)
            spread[row, col] = e.max() - e.min()
            inside[row, col] = _shadowed(cx[:4], cy[:4], axis).all()
            gx, gy = np.meshgrid(x0 + g * bw, y0 + g * bh)
            outside[row, col] = not _shadowed(gx, gy, axis).any()
    return mean, spread, inside, outside


def _compiled(scene):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # LED B's cone may miss the eye (it points away)
        return compile_scene(scene)


@pytest.fixture(scope="module", params=sorted(B_POSES))
def shadow(request):
    scene = _scene(pose=request.param)
    return request.param, scene, _compiled(scene), _bins(scene, B_POSES[request.param][0])


def test_the_cylinder_is_a_front_disk_and_a_side(shadow):
    _, _, cs, _ = shadow
    rows = led_body_rows(cs.surface_names, 1)
    assert [cs.surface_names[s] for s in rows] == ["LED 1 body", "LED 1 body (side)"]
    assert len(led_body_rows(cs.surface_names, 0)) == 1  # A: a sphere, one row


def test_the_cylinder_shadows_the_eye_plane_in_both_estimators(shadow):
    pose, scene, cs, (mean, spread, inside, outside) = shadow
    i_b = B_POSES[pose][1]
    # the lens's own tiny shadow (camera at (15, 0, 30)) falls outside the plane's field
    assert inside.sum() >= 30 and outside.sum() > 600
    n_sub = 16
    fast = direct_eye_plane(cs, seed=2, n_sub=n_sub)
    b_most = 0.0 if pose == "facing" else i_b / 20.0**2  # B's own light on the plane, bound
    assert np.all(fast[inside] <= b_most)
    tol = 5 * spread / (2 * n_sub**2) + 1e-12 * mean.max() + b_most
    assert np.all(np.abs(fast - mean)[outside] <= tol[outside])
    # bins neither wholly in nor out: partly lit, between 0 and the bare source
    edge = ~inside & ~outside
    assert np.all(fast[edge] <= mean[edge] + tol[edge])
    assert np.any((fast[edge] > 0) & (fast[edge] < 0.9 * mean[edge]))
    fwd = render(cs, RenderOptions(rays=400_000, seed=4))
    assert np.all(fwd.plane_counts[inside] == 0)
    assert fwd.ledger["LED bodies"] > 0
    area = (scene.eye_plane.width_mm / scene.eye_plane.cols) * (
        scene.eye_plane.height_mm / scene.eye_plane.rows
    )
    m = math.log(0.5) / math.log(math.cos(math.radians(HALF)))
    # A's share of the 400k rays (by power: the same profile) would put ≫ 1 ray in each
    share = 400_000 * I0 / (I0 + i_b)
    expected = share * mean * area / (I0 * 2 * math.pi / (m + 1))
    assert expected[inside].min() > 20


def test_a_sphere_of_the_same_diameter_casts_another_shadow(shadow):
    """The sphere B would be (4 mm across about the same centre) leaves lit some bins the
    cylinder darkens (its corners): the body's shape is what the tracer sees."""
    pose, _, _, (mean, _, inside, _) = shadow
    fast = direct_eye_plane(_compiled(_scene("sphere", pose)), seed=2, n_sub=16)
    assert np.any(fast[inside] > 0.5 * mean[inside])


def test_light_leaves_from_the_centre_of_the_front_face():
    p, d = np.array([3.0, -2.0, 18.0]), np.array([-0.3, 0.2, -1.0])
    leds = LedArray(
        count=1,
        positions_mm=[p.tolist()],
        directions=[d.tolist()],
        body_shape="cylinder",
        body_diameter_mm=1.3,
        body_length_mm=0.65,
        emitter_diameter_mm=0.3,
    )
    scene = apply_overrides(load_scene("vr-offaxis"), {"leds": leds.model_dump()})
    cs = compile_scene(scene)
    emit = cs.frame.world_point(cs.led.points[0])
    expected = p + 0.325 * d / np.linalg.norm(d)
    assert np.allclose(emit, expected, atol=1e-8)
    # the front disk passes through it, normal to the axis
    front = cs.surface_names.index("LED 0 body")
    o = cs.frame.world_point(cs.sf[front, :3])
    assert np.allclose(o, p + 0.325 * d / np.linalg.norm(d), atol=1e-9)


def test_the_sphere_stays_the_default():
    leds = load_scene("paper2005").leds
    assert leds.body_shapes() == ["sphere"] * leds.count
    assert leds.emission_offsets_mm() == leds.body_radii_mm()
    cs = compile_scene(load_scene("paper2005"))
    assert [n for n in cs.surface_names if n.startswith("LED")] == [
        f"LED {k} body" for k in range(leds.count)
    ]


# --- refusals: the body's shape, not a sphere about its centre ---------------------------------

#: One thin cylinder (vr-offaxis's camera body is 6 mm across, 5 mm deep behind its lens)
CAMERA = {"leds.count": 1, "leds.body_shape": "cylinder", "leds.body_diameter_mm": 1.0}


def _camera_axis():
    cs = compile_scene(load_scene("vr-offaxis"))
    origin = cs.frame.world_point(np.zeros(3))
    return origin, cs.frame.world_vector(np.array([0.0, 0.0, 1.0])), cs


def test_a_long_cylinder_reaching_into_the_camera_body_is_refused_one_line_exit_2():
    """Its centre lies 3.5 mm from the body's solid, more than its radius (a sphere of its
    diameter would pass), but its 10 mm length reaches 1.5 mm into it."""
    origin, axis, cs = _camera_axis()
    side = cs.frame.world_vector(np.array([1.0, 0.0, 0.0]))
    # the lens's first vertex: the camera body's front (the camera frame's z of surface 0)
    front = origin + float(cs.lf[0, Q.L_Z]) * axis
    centre = front + 2.0 * side - 3.5 * axis  # 2 mm off the axis, 3.5 mm in front of the body
    overrides = {
        **CAMERA,
        "leds.positions_mm": [np.round(centre, 4).tolist()],
        "leds.directions": [np.round(-axis, 6).tolist()],  # toward the eye
        "leds.body_length_mm": 10.0,
    }
    with pytest.raises(SceneError) as err:
        compile_scene(apply_overrides(load_scene("vr-offaxis"), overrides))
    msg = str(err.value)
    assert "inside the camera body" in msg and "cylinder 1 mm across, 10 mm long" in msg
    assert "\n" not in msg
    # 2 mm long, it ends 2.5 mm short of the body: accepted
    ok = apply_overrides(load_scene("vr-offaxis"), {**overrides, "leds.body_length_mm": 2.0})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        compile_scene(ok)
    args = ["info", "--scene", "vr-offaxis"]
    for k, v in overrides.items():
        args += ["--set", f"{k}={v}".replace(" ", "")]
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 2, res.output
    assert "inside the camera body" in res.output


def _two(p0, p1, d0=(0.0, 0.0, -1.0), d1=(0.0, 0.0, -1.0), **more):
    return apply_overrides(
        load_scene("vr-offaxis"),
        {
            "face.enabled": False,
            "leds.count": 2,
            "leds.positions_mm": [list(p0), list(p1)],
            "leds.directions": [list(d0), list(d1)],
            "leds.body_shape": "cylinder",
            "leds.body_diameter_mm": 2.0,
            "leds.body_length_mm": 0.6,
            **more,
        },
    )


def test_two_flat_cylinders_side_by_side_overlap_only_when_they_touch():
    """Two 2 mm × 0.6 mm cylinders tilted 60° about y toward each other, their centres on x:
    the bounding spheres (radius √(1 + 0.3²) = 1.044 mm) of ones 2.05 mm apart overlap. The
    nearest points of the two bodies are the rims' ends in the xz-plane: the body reaches
    r cos 60° + (L/2) sin 60° = 0.7598 mm along x from its centre, so at centres 2.05 mm apart
    (more than 2 × 0.7598) they are apart, at 1.45 mm they overlap."""
    t = math.radians(60.0)
    d0, d1 = (math.sin(t), 0.0, -math.cos(t)), (-math.sin(t), 0.0, -math.cos(t))
    reach = 1.0 * math.cos(t) + 0.3 * math.sin(t)
    for gap, refused in ((2 * reach + 0.02, False), (2 * reach - 0.02, True)):
        scene = _two((-gap / 2, -14.0, 12.0), (gap / 2, -14.0, 12.0), d0, d1)
        if refused:
            with pytest.raises(SceneError, match="LED 1 and LED 0 bodies overlap") as err:
                compile_scene(scene)
            assert "cylinder 2 mm across, 0.6 mm long" in str(err.value)
        else:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                compile_scene(scene)


def test_the_eye_plane_takes_the_cylinders_reach():
    """A flat cylinder 2 mm across, 0.6 mm long, axis tilted θ = 50° from −z, reaches
    (L/2) cos θ + r sin θ = 0.9588 mm below its centre: at centre z = 0.99 it is in front of
    the eye plane z = 0 (a sphere of its 2 mm diameter would cross it), at 0.93 it crosses."""
    t = math.radians(50.0)
    d = (math.sin(t), 0.0, -math.cos(t))
    reach = 0.3 * math.cos(t) + 1.0 * math.sin(t)
    assert 0.93 < reach < 0.99
    lone = {"leds.count": 1, "leds.body_shape": "cylinder", "leds.body_diameter_mm": 2.0}
    base = {**lone, "face.enabled": False, "leds.body_length_mm": 0.6}
    for z, refused in ((0.99, False), (0.93, True)):
        scene = apply_overrides(
            load_scene("vr-offaxis"),
            {**base, "leds.positions_mm": [[-16.0, 0.0, z]], "leds.directions": [list(d)]},
        )
        if refused:
            with pytest.raises(SceneError, match="crosses the eye plane"):
                compile_scene(scene)
        else:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                compile_scene(scene)


def test_the_ring_checks_take_the_cylinders_shape():
    """The paper's ring of 4 LEDs as flat cylinders (5 mm across, 1 mm long): pitched θ, each
    reaches (L/2) cos θ + r sin θ toward the eye plane (2.1651 mm at 60°, where a 5 mm sphere
    would reach 2.5 mm); side by side at Y, the nearest LEDs (90° apart) are √2 Y apart."""
    leds = LedArray(body_shape="cylinder", body_diameter_mm=5.0, body_length_mm=1.0)
    reach = 0.5 * math.cos(math.radians(60)) + 2.5 * math.sin(math.radians(60))
    assert geometry_problem(leds, 30, reach + 0.01, 60) is None
    assert "crosses the eye plane" in geometry_problem(leds, 30, reach - 0.01, 60)
    # at θ = 0 the LEDs face the eye, their rims 2.5 mm from their centres across the ring
    assert geometry_problem(leds, 5.0 / math.sqrt(2) + 0.01, 40, 0) is None
    assert "overlap" in geometry_problem(leds, 5.0 / math.sqrt(2) - 0.01, 40, 0)


@pytest.mark.parametrize(
    ("setting", "words"),
    [
        ("leds.body_shape=box", "body_shape"),
        ("leds.body_shape=cylinder", "body_length_mm is needed"),
        ("leds.body_length_mm=1.0", "body_length_mm = 1.0"),
    ],
)
def test_bad_body_input_is_one_line_exit_2(setting, words):
    res = CliRunner().invoke(app, ["info", "--scene", "paper2005", "--set", setting])
    assert res.exit_code == 2, res.output
    lines = [x for x in res.output.splitlines() if x.strip()]
    assert len(lines) == 1 and words in lines[0], res.output


def test_the_layout_draws_each_cylinder_as_one_closed_outline():
    """LED B's cylinder (4 mm across, 4 mm long, its axis +z) moved onto the yz-view's cut
    x = 0: its section is one closed 4 × 4 mm rectangle, z 23–27, y 1–5 mm."""
    cs = _compiled(_scene(b_centre=(0.0, 3.0, 25.0)))
    secs = [s for s in system_sections(cs, view="yz") if s.name.startswith("LED 1 body")]
    assert len(secs) == 1 and secs[0].category == "led"
    z, y = secs[0].z, secs[0].y
    assert (z[0], y[0]) == (z[-1], y[-1])
    area = 0.5 * abs(np.dot(z[:-1], y[1:]) - np.dot(z[1:], y[:-1]))
    assert area == pytest.approx(2 * B_R * B_L, rel=0.01)
    assert z.min() == pytest.approx(25.0 - B_L / 2) and y.max() == pytest.approx(3.0 + B_R)


def test_a_command_line_sphere_drops_the_scenes_cylinder_length_with_a_note():
    """vr-offaxis's LEDs are 1.3 × 0.65 mm cylinders: ``--set leds.body_shape=sphere`` gives
    1.3 mm spheres (light from the apex, 0.65 mm from the centre); the preset's length, a
    cylinder's, is dropped with one warning line naming it. Both set on the command line: the
    length is refused beside spheres, as in a file."""
    res = CliRunner().invoke(
        app, ["info", "--scene", "vr-offaxis", "--set", "leds.body_shape=sphere", "--json"]
    )
    assert res.exit_code == 0, res.output
    notes = [x for x in res.stderr.splitlines() if x.strip()]
    assert len(notes) == 1 and "body_length_mm = 0.65" in notes[0], res.stderr
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        leds = load_scene("vr-offaxis", {"leds.body_shape": "sphere"}).leds
    assert len(seen) == 1 and "dropped" in str(seen[0].message)
    assert leds.body_shapes() == ["sphere"] * 8 and leds.body_length_mm is None
    assert leds.emission_offsets_mm() == pytest.approx([1.3 / 2] * 8)
    both = ["--set", "leds.body_shape=sphere", "--set", "leds.body_length_mm=0.65"]
    res = CliRunner().invoke(app, ["info", "--scene", "vr-offaxis", *both])
    assert res.exit_code == 2, res.output
    lines = [x for x in res.output.splitlines() if x.strip()]
    assert len(lines) == 1 and "body_length_mm = 0.65" in lines[0], res.output


def test_the_layout_legend_names_each_body_shape_as_drawn(tmp_path):
    """A layout of cylinder LEDs labels their body a cylinder, drawn as a rectangle (its
    section), not a sphere's circle; spheres and cylinders together get one entry each."""
    from eyelume.report.plots import SectionCurve, observe_figures, save_layout

    z, y = np.array([0.0, 1, 1, 0, 0]), np.array([0.0, 0, 2, 2, 0])
    led = SectionCurve("LED 0 body", "led", z, y)
    seen = []

    def keep(fig, _name):
        legend = fig.axes[0].get_legend()
        seen.append(
            [
                (h.get_marker(), t.get_text())
                for h, t in zip(legend.legend_handles, legend.texts, strict=True)
            ]
        )

    with observe_figures(keep):
        for bodies in (["cylinder"] * 8, ["sphere"] * 4, ["cylinder", "sphere"]):
            save_layout([led], [], tmp_path / "l.png", title="t", led_bodies=bodies)
    assert seen[0] == [("s", "LED: cylinder body ▭, axis —, its id")]
    assert seen[1] == [("o", "LED: sphere body ○, axis —, its id")]
    assert seen[2] == [("o", "LED: sphere body ○"), ("s", "LED: cylinder body ▭, axis —, its id")]
