"""Test 4: the anterior cornea as a convex mirror forms the first Purkinje image where the mirror
equation puts it.

Rays from an axial point source at distance s reflect off the traced corneal surface (the
compiled scene's conicoid, with the kernels' intersection, normal and reflection). Extended
backward, a reflected ray at height h crosses the axis at z(h) = z_i + a h² + O(h⁴) (spherical
aberration of the mirror); the h → 0 intercept is the paraxial virtual image, which the mirror
equation 1/s + 1/s' = 2/R (R = −7.8 mm for the convex cornea seen from outside) predicts.
"""

from __future__ import annotations

import numpy as np
import pytest

from eyelume.kernels.geometry import intersect_surface, surface_normal
from eyelume.kernels.interact import reflect


@pytest.mark.parametrize("s", [20.0, 70.0, 300.0])
def test_cornea_reflects_to_the_mirror_image(paper_compiled, s):
    cs = paper_compiled
    cornea = cs.surface_names.index("anterior cornea")
    heights = np.array([0.02, 0.04, 0.06, 0.08])
    crossings = []
    for h in heights:
        d = np.array([0.0, h, -s])  # aim at height h on the vertex plane
        d /= np.linalg.norm(d)
        t = intersect_surface(cs.sf, cs.si, cornea, 0.0, 0.0, s, *d, np.inf)
        assert t > 0
        p = np.array([0.0, 0.0, s]) + t * d
        n = surface_normal(cs.sf, cs.si, cornea, *p)
        r = np.array(reflect(*d, *n))
        crossings.append(p[2] - p[1] * r[2] / r[1])  # where the backward extension meets y = 0
    # fit z(h) = z_i + a h²; the intercept is the paraxial image
    a, z_i = np.polyfit(heights**2, np.array(crossings), 1)
    radius = 7.8  # vertex radius of the Arizona anterior cornea
    s_image = 1.0 / (-2.0 / radius - 1.0 / s)  # mirror equation, convex: f = −R/2
    # The fit's residual is O(h⁴) ~ a h⁴/R² ≪ 1e-8 mm at these heights; float64 rounding of
    # the crossings is ~1e-13 mm. 1e-7 mm leaves room for both.
    assert z_i == pytest.approx(s_image, abs=1e-7)
    assert z_i < 0 and z_i > -radius / 2  # virtual, between the vertex and the focal point
