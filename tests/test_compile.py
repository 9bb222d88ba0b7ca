"""The compiled scene: lens clear apertures from real-ray aiming, and geometry checks."""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit

import eyelume
from eyelume.compile import compile_scene
from eyelume.errors import EyelumeWarning, GeometryError
from eyelume.kernels import sequential as Q
from eyelume.kernels.sequential import trace_lens
from eyelume.scene.io import SceneError, apply_overrides, load_scene


@njit(cache=True)
def _lens_fates(lf, x, y, z, dx, dy, dz, status):
    """The sequential kernel's fate (LENS_PASSED, …) of each ray."""
    for i in range(x.shape[0]):
        status[i] = trace_lens(lf, x[i], y[i], z[i], dx[i], dy[i], dz[i], None, 0, False)[0]


def test_stop_alone_limits_every_bundle_from_the_eye_area(paper_compiled):
    """Rays from anywhere on the 40 × 30 mm eye plane, aimed over a disc that overfills the
    lens: with the compiled clear apertures exactly the rays the stop admits get through — no
    other surface vignettes the field (the semi-diameters enclose every rim ray found by real-ray
    aiming, plus 1 %)."""
    cs = paper_compiled
    open_lf = cs.lf.copy()
    open_lf[:, Q.L_SD] = np.inf
    open_lf[cs.stop_index, Q.L_SD] = cs.lf[cs.stop_index, Q.L_SD]
    rng = np.random.default_rng(8)
    n = 200_000
    x0, y0 = rng.uniform(-20, 20, n), rng.uniform(-15, 15, n)
    r = 40 * np.sqrt(rng.uniform(size=n))
    phi = rng.uniform(0, 2 * np.pi, n)
    d = np.stack([r * np.cos(phi) - x0, r * np.sin(phi) - y0, np.full(n, 70.0)], 1)
    d /= np.linalg.norm(d, axis=1, keepdims=True)

    def fates(lf):
        work = [x0.copy(), y0.copy(), np.zeros(n), *(d[:, k].copy() for k in range(3))]
        status = np.zeros(n, dtype=np.int64)
        _lens_fates(lf, *work, status)
        return status

    # a ray the stop rejects may die earlier with the real apertures (vignetted instead of
    # lost to TIR far outside them): only whether it passes must agree
    passed = fates(cs.lf) == Q.LENS_PASSED
    assert np.array_equal(fates(open_lf) == Q.LENS_PASSED, passed)
    assert 0.05 < passed.mean() < 0.95  # the test sees both fates


def test_semi_diameters_are_sized_by_the_rim_rays(paper_compiled):
    sd = paper_compiled.lf[:, Q.L_SD]
    # the 50 mm entrance pupil and a ±25 mm field: the front element is ~26 mm, the stop ~13
    assert sd[paper_compiled.stop_index] == sd.min()
    assert 24 < sd[0] < 28 and np.isfinite(sd).all()


@pytest.mark.parametrize(
    ("overrides", "words"),
    [
        ({"lens.surfaces.0.thickness_mm": "2.0"}, ["lens.surfaces.0", "lens.surfaces.1", "cross"]),
        ({"lens.surfaces.0.radius_mm": "-30.0", "lens.surfaces.0.conic": "0.0"}, ["lens"]),
    ],
)
def test_impossible_lens_geometry_is_refused(overrides, words):
    with pytest.raises(SceneError) as info:
        compile_scene(eyelume.load_scene("paper2005", overrides))
    assert all(w in str(info.value) for w in words), str(info.value)


@pytest.mark.parametrize(
    ("overrides", "words"),
    [
        (
            {"eye.surfaces.3.semi_diameter_mm": "6.0", "eye.surfaces.3.conic": "0.0"},
            ["eye.surfaces.3", "6.0"],
        ),
        (
            {"eye.surfaces.0.semi_diameter_mm": "9.5"},
            ["eye.surfaces.0", "9.5"],
        ),
    ],
)
def test_eye_aperture_beyond_its_conicoid_is_refused(overrides, words):
    with pytest.raises(GeometryError) as info:  # on loading (scene.eye.check_eye_geometry)
        compile_scene(eyelume.load_scene("paper2005", overrides))
    assert all(w in str(info.value) for w in words), str(info.value)


@pytest.mark.parametrize(
    ("overrides", "words"),
    [
        ({"camera.look_at_mm": None, "camera.direction": [0.0, 0.0, 1.0]}, "behind the camera"),
        ({"camera.look_at_mm": [30.0, 0.0, 0.0]}, "outside the"),
        ({"camera.look_at_mm": [20.785, -12.0, 20.0]}, "equals position_mm"),
        ({"head_offset_mm": [0.0, 0.0, 14.5]}, "inside the face: face.tissues 'brow'"),
        (
            {
                "head_offset_mm": [0.0, 0.0, 5.0],
                "leds.height_mm": 3.0,
                "leds.distance_mm": 4.0,
                "leds.pitch_deg": 0.0,
            },
            "inside the eye",
        ),
        ({"sensor.pixel_pitch_um": 80.0}, "more than the ideal lens covers"),
        ({"camera.position_mm": [0.0, 0.0, -5.0]}, "camera.position_mm = [0.0, 0.0, -5.0] (the"),
        (
            {"camera.position_mm": [0.0, 0.0, -30.0]},
            "camera.position_mm = [0.0, 0.0, -30.0] lies behind the eye plane z = 0 mm",
        ),
        (
            {"camera.position_mm": [21.0, -6.0, -4.0], "camera.ideal.focus_distance_mm": 22.0},
            "inside the face: face.tissues 'nose'",
        ),
    ],
)
def test_a_camera_anywhere_refuses_impossible_views(overrides, words):
    """A camera that sees no eye, a look-at point at the camera, an LED inside the face or the
    eye, a chip larger than the lens covers: one line naming the field and value."""
    scene = load_scene("vr-offaxis")
    with pytest.raises(SceneError) as e:
        compile_scene(apply_overrides(scene, overrides))
    msg = str(e.value)
    assert words in msg and "\n" not in msg


@pytest.mark.parametrize(
    ("overrides", "words"),
    [
        (
            {"lens.surfaces.10.semi_diameter_mm": 3.0},
            "lens.surfaces.10.semi_diameter_mm = 3 (the chief ray reaches",
        ),
        (
            {"lens.surfaces.0.semi_diameter_mm": 5.0},
            "lens.surfaces.0.semi_diameter_mm = 5 (the chief ray reaches",
        ),
    ],
)
def test_a_sensor_larger_than_the_prescription_covers_is_refused(overrides, words):
    """A user's clear aperture that lets no ray from part of the sensor's field through (those
    pixels would be black for want of a lens): one line naming the sensor and the aperture."""
    with pytest.raises(SceneError) as e:
        compile_scene(load_scene("paper2005", overrides))
    msg = str(e.value)
    assert msg.startswith("sensor: larger than the lens covers (46 × 34.3 mm")
    assert words in msg and "\n" not in msg


def test_a_sensor_field_far_past_the_lens_names_the_sensor():
    """A 460 × 343 mm picture on paper2005's Double Gauss (10× its 46 × 34.3 mm): most rim
    rays miss a surface or are totally reflected; the one line names the sensor's fields and
    values (a new user's finding: it named only the prescription)."""
    with pytest.raises(SceneError) as e:
        compile_scene(
            load_scene("paper2005", {"sensor.width_mm": 460.0, "sensor.height_mm": 343.0})
        )
    msg = str(e.value)
    assert "sensor.width_mm × sensor.height_mm = 460 × 343 mm" in msg and "\n" not in msg


def test_a_vignetting_aperture_warns():
    """An aperture that blocks the chief ray of part of the field while other rays pass: the
    scene renders (vignetting is a lens property), with a warning saying how much is vignetted."""
    with pytest.warns(EyelumeWarning, match=r"of 63 field points.*vignetted past 50 %"):
        compile_scene(load_scene("paper2005", {"lens.surfaces.10.semi_diameter_mm": 8.0}))


def test_automatic_apertures_cover_a_sensor_larger_than_the_eye_plane():
    """Automatic clear apertures are sized for the sensor's field when it exceeds the eye
    plane's: a 100 × 75 mm sensor (87 mm field in focus, the eye plane is 40 × 30 mm) gets a lens
    that passes all 72 rim rays (at 0.999 of the stop's radius: the stop's own edge is a tie)
    from each corner of its field (it used to vignette them: black
    corners), found by the same real-ray aiming with the compiled apertures in place."""
    scene = load_scene("paper2005", {"sensor.width_mm": 100.0, "sensor.height_mm": 75.0})
    cs = compile_scene(scene)
    m = abs(cs.first_order.magnification)
    stop_sd = cs.lf[cs.stop_index, Q.L_SD]
    ep = cs.first_order
    for x0, y0 in [(50 / m, 37.5 / m), (-50 / m, 37.5 / m), (-50 / m, -37.5 / m)]:
        _, found = Q.rim_ray_heights(
            cs.lf, cs.stop_index, 0.999 * stop_sd, np.array([x0]), np.array([y0]), 72,
            ep.entrance_pupil_radius / stop_sd, ep.entrance_pupil_z,
        )  # fmt: skip
        assert found == 72, (x0, y0, found)


@pytest.mark.parametrize(
    "overrides", [{"camera.direction": [0.0, 0.0, 1.0]}, {"camera.look_at_mm": [0.0, 0.0, 500.0]}]
)
def test_the_paper_lens_turned_away_from_the_eye_is_refused(overrides):
    """The paper's Double Gauss turned to look away (its entrance pupil lies 105 mm behind its
    first vertex, so the eye 70 mm behind the lens was still 'in front of' the pupil): one line,
    not a black picture (a fresh-user finding)."""
    with pytest.raises(SceneError, match="camera: sees no eye: the corneal vertex is behind"):
        compile_scene(load_scene("paper2005", overrides))


def test_refusals_name_the_scene_field_that_placed_the_led_or_the_view():
    """A fresh user's finding (session 19): "leds: LED 1 …" and "camera: sees no eye" named the
    object but not the field to change. LEDs placed one by one name ``leds.positions_mm[i]``,
    a ring LED names the ring's fields, a camera that sees no eye names the view's field."""
    both = {
        "leds.count": 2,
        "leds.positions_mm": [[10.0, 0.0, 15.0], [10.5, 0.0, 15.0]],
        "leds.aim_at_mm": [0.0, 0.0, 0.0],
    }
    with pytest.raises(SceneError) as err:
        compile_scene(load_scene("vr-offaxis", both))
    assert "leds.positions_mm[1] and leds.positions_mm[0]" in str(err.value), err.value
    with pytest.raises(SceneError) as err:
        compile_scene(load_scene("paper2005", {"leds.height_mm": 0.0, "leds.distance_mm": 1.0}))
    assert "LED 0 (the ring's" in str(err.value) and "leds.height_mm" in str(err.value)
    with pytest.raises(SceneError) as err:
        compile_scene(load_scene("vr-offaxis", {"camera.look_at_mm": [0.0, 100.0, 0.0]}))
    assert "sees no eye" in str(err.value) and "camera.look_at_mm = [0.0, 100.0, 0.0]" in str(
        err.value
    )
    with pytest.raises(SceneError) as err:
        compile_scene(load_scene("paper2005", {"camera.direction": [0.3, 0.0, -1.0]}))
    assert "sees no eye" in str(err.value) and "camera.direction = [0.3, 0.0, -1.0]" in str(
        err.value
    )
