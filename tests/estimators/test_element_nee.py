"""Next-event estimation through an optical element (issue 14: the fast estimator's specular
connection by Newton's method, :func:`eyelume.estimators.fast.led_through_elements`), against
closed forms written here:

* through a plane-parallel plate of thickness t and index n, normal to the line from a point
  source to a receiver on that line, the irradiance is I₀ T₁ T₂ / (D − t (1 − 1/n))² (the plate
  moves the source's paraxial image t (1 − 1/n) nearer; on the line the paraxial Jacobian is
  exact; Tⱼ = 1 − ((n − 1)/(n + 1))², Fresnel at normal incidence);
* off a plane mirror (R = 1), the fast estimator's eye plane (its direct irradiance,
  ``direct_eye_plane``) is the closed form of the LED's mirror image, bin by bin: the same
  scene and Gauss–Legendre quadrature as ``tests/test_elements.py``'s forward test;
* the chains compiled per LED: an element's surfaces in the order the LED meets them, the
  cornea's two steps appended for the iris, none for a converging lens or a curved mirror.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import eyelume
from eyelume.compile import compile_scene, connected_by_newton, element_index
from eyelume.estimators.cornea_nee import Receiver
from eyelume.estimators.fast import led_through_elements
from eyelume.estimators.fast_run import direct_eye_plane
from eyelume.kernels.sampling import orthonormal_basis
from eyelume.kernels.tables import REFLECT, TRANSMIT, TRANSMIT_A
from eyelume.scene.glass import load_catalog
from eyelume.scene.sources import relative_intensity

#: One LED on a line parallel to the camera's axis, 10 mm beside it, aimed down the line at a
#: receiver point in z = 0 (outside the eye and with no face: nothing but the plate between).
ON_LINE = {
    "face.enabled": "false",
    "leds.count": 1,
    "leds.positions_mm": [[10.0, 10.0, 30.0]],
    "leds.directions": [[0.0, 0.0, -1.0]],
}
PLATE = {
    "kind": "plate",
    "position_mm": [0.0, 0.0, 12.0],
    "thickness_mm": 3.0,
    "glass": "N-BK7",
    "semi_diameter_mm": 18.0,
}


@pytest.mark.filterwarnings("ignore::eyelume.compile.LedAimWarning")
def test_irradiance_through_a_plate_is_the_paraxial_closed_form_on_the_line():
    cs = compile_scene(eyelume.load_scene("paper2005", {"elements": [PLATE], **ON_LINE}))
    n = float(load_catalog()["N-BK7"].index(cs.scene.wavelength_nm))
    t_fresnel = 1.0 - ((n - 1.0) / (n + 1.0)) ** 2
    led = cs.led.points[0]
    d = led[2]  # the receiver at z = 0 on the LED's line (camera frame = world here)
    e1, e2 = orthonormal_basis(0.0, 0.0, 1.0)
    rc = Receiver(led[0], led[1], 0.0, 0.0, 0.0, 1.0, e1, e2)
    got = led_through_elements(cs.tables.surfaces, cs.camera, -1, cs.tables.leds, 0, rc)
    i0 = cs.scene.leds.radiant_intensity_w_sr
    want = i0 * t_fresnel**2 / (d - 3.0 * (1.0 - 1.0 / n)) ** 2
    # the paraxial closed form against the exact ray (analytic Jacobian): ~1e-5 relative
    assert got == pytest.approx(want, rel=1e-4)
    # the straight connection is blocked by the plate: without the chain there is nothing
    assert got > 0.5 * i0 / d**2


def _flux(src, axis, i0, f, plane) -> np.ndarray:
    """Flux per eye-plane bin (W) of a point LED by 16 × 16 Gauss–Legendre quadrature of
    I₀ f(α) cos β / r² (as tests/test_elements.py)."""
    w, h, nc, nr = plane.width_mm, plane.height_mm, plane.cols, plane.rows
    g, gw = np.polynomial.legendre.leggauss(16)
    flux = np.zeros((nr, nc))
    bw, bh = w / nc, h / nr
    for row in range(nr):
        y0 = h / 2 - (row + 1) * bh
        for col in range(nc):
            x0 = -w / 2 + col * bw
            xs, ys = np.meshgrid(x0 + (g + 1) * bw / 2, y0 + (g + 1) * bh / 2)
            dx, dy, dz = xs - src[0], ys - src[1], -src[2]
            r = np.sqrt(dx * dx + dy * dy + dz * dz)
            cos_a = (dx * axis[0] + dy * axis[1] + dz * axis[2]) / r
            alpha = np.arccos(np.clip(cos_a, -1, 1))
            inten = np.where(alpha <= math.pi / 2, i0 * f(np.minimum(alpha, math.pi / 2)), 0.0)
            flux[row, col] = np.einsum("i,j,ij->", gw, gw, inten * (src[2] / r) / r**2)
            flux[row, col] *= bw * bh / 4
    return flux


#: tests/test_elements.py's mirror scene: a dark eye, no face, one LED at z = 10 mm aimed away
#: from the eye at a plane mirror (R = 1) in z = 30 mm.
DARK = {
    "face.enabled": "false",
    "eye.cornea_reflection": "fixed",
    "eye.cornea_reflectance": 0.0,
    "eye.sclera_reflectance": 0.0,
    "eye.iris_reflectance": 0.0,
    "leds.count": 1,
    "leds.positions_mm": [[0.0, 20.0, 10.0]],
    "leds.directions": [[0.0, -0.3, 1.0]],
}
MIRROR = {"kind": "mirror", "position_mm": [0.0, 13.0, 30.0], "semi_diameter_mm": 11.5}


@pytest.mark.filterwarnings("ignore::eyelume.compile.LedAimWarning")
def test_fast_eye_plane_sees_the_mirror_image_of_an_led():
    cs = compile_scene(eyelume.load_scene("paper2005", {"elements": [MIRROR], **DARK}))
    sc = cs.scene
    src, axis = cs.led.points[0], cs.led.axes[0]
    f = relative_intensity(sc.leds.profile)
    i0 = sc.leds.radiant_intensity_w_sr
    image = _flux(
        [src[0], src[1], 60.0 - src[2]], [axis[0], axis[1], -axis[2]], i0, f, sc.eye_plane
    )
    want = image + _flux(src, axis, i0, f, sc.eye_plane)
    g = sc.eye_plane
    got = direct_eye_plane(cs, seed=5) * (g.width_mm / g.cols) * (g.height_mm / g.rows)
    # 16 × 16 jittered points per bin against 16 × 16 Gauss–Legendre nodes: where the
    # mirror's edge (its image's shadow line) crosses a bin the jitter's error is about the
    # bin's flux / 16 (one row of cells); elsewhere the two agree to the quadrature's accuracy
    assert got.sum() == pytest.approx(want.sum(), rel=5e-3)
    big = want > 0.05 * want.max()
    np.testing.assert_allclose(got[big], want[big], rtol=0.07)
    assert np.argmax(got) == np.argmax(want)


LENS = {
    "kind": "lens",
    "position_mm": [0.0, 0.0, 14.0],
    "thickness_mm": 2.0,
    "glass": "N-BK7",
    "semi_diameter_mm": 20.0,
}


@pytest.mark.parametrize(
    ("element", "connected"),
    [
        (PLATE, True),
        # (n − 1)(1/R₁ − 1/R₂) = 0.51 (1/127.5 − 1/72.9) = −3 D, and +3 D with the signs turned
        (LENS | {"front": {"radius_mm": 127.5}, "back": {"radius_mm": 72.9}}, True),
        (LENS | {"front": {"radius_mm": -127.5}, "back": {"radius_mm": -72.9}}, False),
        ({"kind": "mirror", "position_mm": [0.0, 13.0, 30.0], "semi_diameter_mm": 11.5}, True),
        (
            {
                "kind": "mirror",
                "position_mm": [0.0, 13.0, 30.0],
                "semi_diameter_mm": 11.5,
                "front": {"radius_mm": 60.0},
            },
            False,
        ),
    ],
)
def test_chains_are_compiled_for_the_elements_newton_connects(element, connected):
    """Per LED, one chain per element Newton's method connects (a mirror: R, and T unless its
    fixed T is 0): the surface the LED faces first, then the other; the cornea's two steps
    after them for the iris; none for a converging lens or a curved mirror."""
    scene = eyelume.load_scene("paper2005", {"elements": [element]})
    assert connected_by_newton(scene.elements[0], element_index(scene, 0, scene.elements[0])) is (
        connected
    )
    cs = compile_scene(scene)
    cam = cs.camera
    rows = [s for s, n in enumerate(cs.surface_names) if n.startswith("element 0")]
    optical = rows[:1] if element["kind"] == "mirror" else rows[:2]
    assert cam.element_rows.tolist() == optical
    if not connected:
        assert cam.chains.shape == (4, 0, 10)
        return
    cornea = cam.cornea
    for row in cam.chains.reshape(-1, 10):
        plain, full = row[0], row[1]
        surf, mode = row[2:6], row[6:10]
        assert full == plain + 2
        assert surf[plain : plain + 2].tolist() == [cornea, cornea + 1]
        assert mode[plain : plain + 2].tolist() == [TRANSMIT_A, TRANSMIT_A]
        if element["kind"] == "mirror":
            assert plain == 1 and surf[0] == optical[0] and mode[0] == REFLECT
        else:  # the paper's LEDs (z = 70 mm) face the back surface (z = 14 or 15 mm) first
            assert plain == 2 and surf[:2].tolist() == optical[::-1]
            assert mode[:2].tolist() == [TRANSMIT, TRANSMIT]
