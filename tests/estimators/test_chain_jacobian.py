"""The specular connection's Jacobian (estimators/cornea_nee.py, ``_through_jacobian``): the
derivative of the miss (u, v) in the receiver's tangent plane with respect to the emission
parameters (a₁, a₂), carried along the chain analytically, against central differences of the
same miss (step 1e-6 mm: truncation ~1e-12, rounding ~1e-10 relative; the two agreed to 1e-8
when written). Newton's method uses it and the irradiance divides by its determinant, so an
error here is an error of every iris pixel. Chains: the cornea's two refractions on
vr-offaxis and paper2005 (conicoids), on an astigmatic decentred cornea (a quadric), and the
element chains of paper2005-integrated (a plane mirror's reflection, the eyepiece's
refractions) at the eye plane's points."""

from __future__ import annotations

from itertools import product

import numpy as np
import pytest

import eyelume
from eyelume.compile import compile_scene
from eyelume.estimators import cornea_nee as CN
from eyelume.kernels import geometry as G
from eyelume.kernels.sampling import orthonormal_basis
from eyelume.kernels.tables import REFLECT, TRANSMIT_A

TORIC = {
    "eye.cornea.radius_steep_mm": 7.3,
    "eye.cornea.axis_deg": 60.0,
    "eye.cornea.decentration_mm": [0.4, 0.3],
}
H = 1e-6
#: tests/estimators/test_element_nee.py's element scenes: one LED at (10, 10, 30) aimed down
#: −z at the eye plane with no face, a plate or a −3 D lens between; one LED at (0, 20, 10)
#: aimed away from a dark eye at a plane mirror in z = 30 mm.
ON_LINE = {
    "face.enabled": "false",
    "leds.count": 1,
    "leds.positions_mm": [[10.0, 10.0, 30.0]],
    "leds.directions": [[0.0, 0.0, -1.0]],
}
PLATE = {"kind": "plate", "position_mm": [0.0, 0.0, 12.0], "thickness_mm": 3.0}
PLATE |= {"glass": "N-BK7", "semi_diameter_mm": 18.0}
DIVERGING = {"kind": "lens", "position_mm": [0.0, 0.0, 14.0], "thickness_mm": 2.0}
DIVERGING |= {"glass": "N-BK7", "semi_diameter_mm": 20.0}
DIVERGING |= {"front": {"radius_mm": 127.5}, "back": {"radius_mm": 72.9}}
DARK = {
    "face.enabled": "false",
    "leds.count": 1,
    "leds.positions_mm": [[0.0, 20.0, 10.0]],
    "leds.directions": [[0.0, -0.3, 1.0]],
}
MIRROR = {"kind": "mirror", "position_mm": [0.0, 13.0, 30.0], "semi_diameter_mm": 11.5}


def _check(surfaces, chain, led, plane, rc, starts) -> int:
    """Compare at each start point a; the number of points where the ray went through."""
    checked = 0
    for a1, a2 in starts:
        j = CN._through_jacobian(surfaces, chain, led, plane, a1, a2, rc)
        if not j.hit.ok:
            continue
        p = [CN._through_jacobian(surfaces, chain, led, plane, a1 + H, a2, rc).hit]
        p.append(CN._through_jacobian(surfaces, chain, led, plane, a1 - H, a2, rc).hit)
        p.append(CN._through_jacobian(surfaces, chain, led, plane, a1, a2 + H, rc).hit)
        p.append(CN._through_jacobian(surfaces, chain, led, plane, a1, a2 - H, rc).hit)
        if not all(h.ok for h in p):
            continue
        fd = np.array(
            [
                (p[0].u - p[1].u) / (2 * H),
                (p[0].v - p[1].v) / (2 * H),
                (p[2].u - p[3].u) / (2 * H),
                (p[2].v - p[3].v) / (2 * H),
            ]
        )
        an = np.array([j.j11, j.j21, j.j12, j.j22])
        assert np.abs(an - fd).max() <= 1e-6 * np.abs(an).max(), (a1, a2, an, fd)
        checked += 1
    return checked


@pytest.mark.parametrize(
    ("preset", "overrides"), [("vr-offaxis", {}), ("paper2005", {}), ("vr-offaxis", TORIC)]
)
def test_the_cornea_chain_jacobian_is_the_derivative_of_the_miss(preset, overrides, rng):
    cs = compile_scene(eyelume.load_scene(preset, overrides))
    surfaces, leds, cornea = cs.tables.surfaces, cs.tables.leds, cs.camera.cornea
    iris = cs.surface_names.index("iris")
    # iris points: the iris surface's vertex region, facing out of the eye
    o = cs.sf[iris, G.OX : G.OZ + 1]
    axis = cs.sf[iris, G.R20 : G.R22 + 1]
    w = axis if axis @ (cs.sf[cornea, G.OX : G.OZ + 1] - o) > 0.0 else -axis
    e1, e2 = orthonormal_basis(*w)
    chain = CN.Chain(2, (cornea, cornea + 1, 0, 0), (TRANSMIT_A, TRANSMIT_A, 0, 0))
    checked = 0
    for r, phi in rng.uniform([2.0, 0.0], [5.0, 2 * np.pi], size=(12, 2)):
        x = o + r * (np.cos(phi) * np.array(e1) + np.sin(phi) * np.array(e2))
        rc = CN.Receiver(*x, *w, e1, e2)
        plane = CN._eye_plane(surfaces, cornea, rc)
        for k in range(leds.points.shape[0]):
            led = tuple(float(c) for c in leds.points[k])
            starts = rng.uniform(-3.0, 3.0, size=(3, 2))
            checked += _check(surfaces, chain, led, plane, rc, starts)
    assert checked > 50


@pytest.mark.filterwarnings("ignore::eyelume.compile.LedAimWarning")
@pytest.mark.parametrize(
    ("overrides", "reflects"),
    [
        ({"elements": [PLATE], **ON_LINE}, False),
        ({"elements": [MIRROR], **DARK}, True),
        ({"elements": [DIVERGING], **ON_LINE}, False),
    ],
    ids=["plate", "plane mirror", "diverging lens"],
)
def test_the_element_chain_jacobian_is_the_derivative_of_the_miss(overrides, reflects, rng):
    """At points of the eye plane (z = 0, facing the LEDs) that an LED reaches through an
    element (``led_through_chain`` > 0, as the fast estimator's eye plane connects them):
    about the root and 0.5 mm off it."""
    cs = compile_scene(eyelume.load_scene("paper2005", overrides))
    surfaces, leds, chains = cs.tables.surfaces, cs.tables.leds, cs.camera.chains
    e1, e2 = orthonormal_basis(0.0, 0.0, 1.0)
    checked = 0
    for (x, y), c in product(rng.uniform(-10.0, 10.0, size=(30, 2)), range(chains.shape[1])):
        row = chains[0, c]
        if row[0] == 0:
            continue
        rc = CN.Receiver(x, y, 0.0, 0.0, 0.0, 1.0, e1, e2)
        chain = CN.chain_row(row, row[0])
        assert any(m == REFLECT for m in chain.mode[: chain.n]) == reflects
        plane = CN.straight_plane(leds, 0, chain, surfaces, rc)
        if CN.led_through_chain(surfaces, chain, plane, -1, leds, 0, rc) <= 0.0:
            continue
        led = tuple(float(v) for v in leds.points[0])
        starts = np.vstack([[0.0, 0.0], rng.uniform(-0.5, 0.5, size=(2, 2))])
        checked += _check(surfaces, chain, led, plane, rc, starts)
    assert checked > 20
