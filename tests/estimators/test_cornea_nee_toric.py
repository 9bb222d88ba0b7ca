"""Next-event estimation through an astigmatic, decentred cornea (estimators/cornea_nee.py)
against a brute-force count.

``led_through_cornea`` finds the LED's path to an iris point x through the anterior and
posterior cornea by Newton's method and gives the irradiance there as I(α) T₁ T₂ dω/dA, the
Jacobian by finite differences: nothing in it assumes a rotationally symmetric cornea, and this
checks it on the quadric. The reference knows nothing of Newton or Jacobians: rays drawn
uniformly in a cone from the LED (density 1/(2π(1 − cos θ_c)) per steradian), each carrying
I(α)/pdf × the two transmittances, followed by the kernels' nearest-hit search (first hit the
anterior cornea, then the posterior one, then the iris), tallied when they land within ρ of x
in the iris plane: E ≈ Σ w / (N π ρ²). Its standard error is the tally's own (the weights'
spread over N); the disk's averaging of a smoothly varying E is a bias of order (ρ/ℓ)² with ℓ
the mm scale over which E varies (ρ = 0.05 mm: ~1e-4), far below it. The cone is centred on
the mean hit direction of a coarse first pass, and wide enough that no tallied ray lies near
its edge (checked)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit

import eyelume
from eyelume.compile import compile_scene, eye_point
from eyelume.estimators.cornea_nee import Receiver, led_through_cornea
from eyelume.kernels import geometry as G
from eyelume.kernels.interact import interface_at, refract
from eyelume.kernels.rng import next_uniform, stream_start
from eyelume.kernels.sampling import about_axis, orthonormal_basis, radiant_intensity, uniform_cone

TORIC = {
    "eye.cornea.radius_steep_mm": 7.3,
    "eye.cornea.axis_deg": 60.0,
    "eye.cornea.decentration_mm": [0.4, 0.3],
}


@njit(cache=False)
def _count(sf, si, leds, k, rows, geom, n, seed):
    """Σ w and Σ w² of the rays landing within ρ of x, and the largest cos-distance from the
    cone's axis among them (1 − cos); ``rows`` (cornea, iris), ``geom`` (cone axis, cos of
    its half-angle, x, the iris normal, ρ)."""
    cornea, iris = rows
    axis, cos_max, x, normal, rho = geom
    s1 = 0.0
    s2 = 0.0
    edge = 0.0
    px, py, pz = leds.points[k, 0], leds.points[k, 1], leds.points[k, 2]
    inv_pdf = 2.0 * math.pi * (1.0 - cos_max)
    for i in range(n):
        state = stream_start(seed, i)
        state, u1 = next_uniform(state)
        state, u2 = next_uniform(state)
        lx, ly, lz = uniform_cone(u1, u2, cos_max)
        dx, dy, dz = about_axis(lx, ly, lz, axis[0], axis[1], axis[2])
        w = radiant_intensity(leds, k, dx, dy, dz) * inv_pdf
        if w <= 0.0:
            continue
        ox, oy, oz = px, py, pz
        ok = True
        for s in (cornea, cornea + 1):
            hit, t = G.nearest_hit(sf, si, ox, oy, oz, dx, dy, dz)
            if hit != s:
                ok = False
                break
            ox, oy, oz = ox + t * dx, oy + t * dy, oz + t * dz
            nx, ny, nz = G.surface_normal(sf, si, s, ox, oy, oz)
            cos_d = dx * nx + dy * ny + dz * nz
            f = interface_at(sf, si, s, cos_d)
            good, dx, dy, dz = refract(dx, dy, dz, nx, ny, nz, f.n1 / f.n2)
            if not good:
                ok = False
                break
            w *= 1.0 - f.reflectance - f.absorptance
        if not ok:
            continue
        hit, t = G.nearest_hit(sf, si, ox, oy, oz, dx, dy, dz)
        if hit != iris:
            continue
        ex = ox + t * dx - x[0]
        ey = oy + t * dy - x[1]
        ez = oz + t * dz - x[2]
        along = ex * normal[0] + ey * normal[1] + ez * normal[2]
        if ex * ex + ey * ey + ez * ez - along * along <= rho * rho:
            s1 += w
            s2 += w * w
            edge = max(edge, 1.0 - lz)
    return s1, s2, edge


def _brute_force(cs, k, target, cone, n):
    """(E, its standard error, the tallied rays' largest angle from the axis over the cone's):
    ``target`` (x, normal, ρ), ``cone`` (axis, half-angle rad), ``n`` rays."""
    x, normal, rho = target
    axis, half_angle = cone
    cos_max = math.cos(half_angle)
    rows = (cs.camera.cornea, cs.surface_names.index("iris"))
    geom = (axis, cos_max, x, normal, rho)
    s1, s2, edge = _count(cs.sf, cs.si, cs.tables.leds, k, rows, geom, n, 99)
    area = math.pi * rho * rho
    mean = s1 / n
    se = math.sqrt(max(s2 / n - mean * mean, 0.0) / n)
    return mean / area, se / area, edge / (1.0 - cos_max)


@pytest.mark.slow
def test_newton_connection_through_a_toric_cornea_matches_a_brute_force_count():
    cs = compile_scene(eyelume.load_scene("vr-offaxis", TORIC))
    scene = cs.scene
    depth = sum(s.thickness_mm for s in scene.eye.surfaces[: scene.eye.iris_surface])
    normal = cs.frame.vector(np.array([0.0, 0.0, 1.0]))  # the iris faces out of the eye
    normal = normal / np.linalg.norm(normal)
    e1, e2 = orthonormal_basis(*normal)
    iris = cs.surface_names.index("iris")
    checked = 0
    for k, az in ((0, 0.0), (5, 90.0), (3, 210.0)):
        a = math.radians(az)
        x = cs.frame.point(eye_point(scene, [4.5 * math.cos(a), 4.5 * math.sin(a), -depth]))
        rc = Receiver(*x, *normal, e1, e2)
        e_newton = led_through_cornea(
            cs.tables.surfaces, cs.camera.cornea, iris, cs.tables.leds, k, rc
        )
        assert e_newton > 0.0  # LED k reaches x through the cornea (not shadowed)
        led = cs.tables.leds.points[k]
        # coarse pass: where do the rays to x leave the LED? (a cone about the straight line)
        straight = (x - led) / np.linalg.norm(x - led)
        coarse = _count_axis(cs, k, x, normal, straight)
        e_ref, se, edge = _brute_force(
            cs, k, (x, normal, 0.05), (coarse, math.radians(1.0)), 2_000_000
        )
        assert edge < 0.7  # no tallied ray near the cone's rim: the cone holds every path
        assert se < 0.02 * e_ref  # the count resolves a 2 % error
        assert abs(e_newton - e_ref) < 4.0 * se, (k, e_newton, e_ref, se)
        print(f"LED {k}: Newton {e_newton:.5e}, count {e_ref:.5e} ± {se:.1e} W/mm²")
        checked += 1
    assert checked == 3


def _count_axis(cs, k, x, normal, straight):
    """The mean direction of the rays from LED k that land within 0.5 mm of x (a 6° cone about
    the straight line): the axis of the fine pass's cone."""
    from eyelume.kernels.sampling import about_axis as rotate

    cornea, iris = cs.camera.cornea, cs.surface_names.index("iris")
    led = cs.tables.leds.points[k]
    hits = []
    rng = np.random.default_rng(5)
    cos_max = math.cos(math.radians(6.0))
    for _ in range(20_000):
        u1, u2 = rng.random(2)
        d = np.array(rotate(*uniform_cone(u1, u2, cos_max), *straight))
        p = led.copy()
        ok = True
        for s in (cornea, cornea + 1):
            hit, t = G.nearest_hit(cs.sf, cs.si, *p, *d)
            if hit != s:
                ok = False
                break
            p = p + t * d
            nrm = np.array(G.surface_normal(cs.sf, cs.si, s, *p))
            f = interface_at(cs.sf, cs.si, s, float(d @ nrm))
            good, *dd = refract(*d, *nrm, f.n1 / f.n2)
            if not good:
                ok = False
                break
            d = np.array(dd)
        if not ok:
            continue
        hit, t = G.nearest_hit(cs.sf, cs.si, *p, *d)
        if hit == iris and np.linalg.norm(p + t * d - x) < 0.5:
            hits.append(rotate(*uniform_cone(u1, u2, cos_max), *straight))
    assert len(hits) > 20
    m = np.mean(hits, axis=0)
    return m / np.linalg.norm(m)
