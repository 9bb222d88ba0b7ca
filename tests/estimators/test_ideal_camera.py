"""The ideal (thin, perfect) camera lens against closed forms (issue: any headset).

The camera-side estimator turns a uniform-radiance scene (L = 1 along every ray that leaves
the lens) into the image irradiance E = Σ A_stop g / |det J| over stop samples (the sum
:func:`eyelume.estimators.fast.camera_pass` forms, radiance 1). Integrated here by Gauss
quadrature over the stop, it must give:

* on the axis, the camera equation for a thin lens focused at s (object-space marginal ray
  angle θ, sin θ = a / √(s² + a²), magnification m = −v/s): E = π L sin²θ / m² — the
  image-space form π L sin²θ′ holds for an aplanatic lens; a thin lens focused at s keeps the
  object-space one exactly (derivation: the flux through the aperture from the axial object
  point's neighbourhood, written out in :func:`_thin_lens_irradiance`);
* off the axis, the same flux integral written from the thin lens's imaging (every ray through
  the aperture point h goes to the conjugate object point X = −x s / v), and its small-aperture
  limit, cos⁴ of the field angle;
* with radial distortion k1, k2, the chief ray of a sensor point x lands where OpenCV's model
  puts it: x = v D(s⃗) for a scene direction of slope s⃗ (checked by tracing the chief ray).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from eyelume.compile import compile_scene
from eyelume.estimators.camera import Mat2, aim_at_stop, into_scene
from eyelume.scene.io import load_scene
from eyelume.scene.model import Scene

EFL, FNUM, FOCUS = 1.646, 2.88, 31.0


def ideal_scene(efl=EFL, fnum=FNUM, focus=FOCUS, k1=0.0, k2=0.0, cols=400, rows=400) -> Scene:
    d = load_scene("paper2005").model_dump()
    d["camera"] = {
        "optics": "ideal",
        "ideal": {"efl_mm": efl, "f_number": fnum, "focus_distance_mm": focus, "k1": k1, "k2": k2},
        "position_mm": [0.0, 0.0, focus],
    }
    d["lens"] = None
    d["sensor"].update(width_mm=None, height_mm=None, cols=cols, rows=rows)
    return Scene.model_validate(d)


def _estimator_irradiance(cam, xs, ys, a, n_r=24, n_phi=48) -> float:
    """E / L at sensor point (xs, ys): Gauss–Legendre in r² (uniform area) × uniform in φ over
    the stop, each node weighted A g / det as the camera pass weights a sample."""
    nodes, weights = np.polynomial.legendre.leggauss(n_r)
    u = 0.5 * (nodes + 1.0)  # r² / a² on (0, 1)
    total = 0.0
    for ui, wi in zip(u, weights, strict=True):
        r = a * math.sqrt(ui)
        for k in range(n_phi):
            phi = 2.0 * math.pi * (k + 0.5) / n_phi
            tx, ty = r * math.cos(phi), r * math.sin(phi)
            aim = aim_at_stop(cam, xs, ys, tx, ty, tx, ty, Mat2(1.0, 0.0, 0.0, 1.0))
            assert aim.found
            ray = into_scene(cam, xs, ys, aim.qx, aim.qy)
            assert ray.passed
            total += 0.5 * wi / n_phi * ray.g / aim.det
    return math.pi * a * a * total


def _thin_lens_irradiance(x: float, y: float, a: float, s: float, v: float) -> float:
    """E / L at image point (x, y) of a thin lens (aperture radius a, object distance s, image
    distance v), from its imaging alone: the ray from aperture point h reaches the sensor point
    and, object side, heads for the conjugate point X = −(x, y) s / v. The étendue of the
    bundle through dA at h is cos θ dΩ dA, with the object side's cos⁴θ / s² per unit area of
    the conjugate patch; the conjugate patch has area (s/v)² per unit sensor area:
    E = (1/v²) ∫ cos⁴θ_obj(h) dA, cos θ_obj = s / √(s² + |X − h|²)."""
    xo, yo = -x * s / v, -y * s / v

    def f(r, phi):
        hx, hy = r * math.cos(phi), r * math.sin(phi)
        c2 = s * s / (s * s + (xo - hx) ** 2 + (yo - hy) ** 2)
        return c2 * c2 * r

    val, _ = integrate.dblquad(f, 0.0, 2.0 * math.pi, 0.0, a, epsabs=1e-14, epsrel=1e-11)
    return val / (v * v)


def test_camera_equation_on_axis():
    scene = ideal_scene()
    cs = compile_scene(scene)
    ideal = scene.camera.ideal
    a, s, v = ideal.pupil_radius_mm, FOCUS, ideal.image_distance_mm
    e = _estimator_irradiance(cs.camera, 0.0, 0.0, a)
    sin2 = a * a / (s * s + a * a)
    m = -v / s
    # quadrature of a smooth integrand: agreement to rounding, not to a tolerance of noise
    assert e == pytest.approx(math.pi * sin2 / (m * m), rel=1e-10)
    # and the textbook small-angle form π L / (4 N² (1 + |m|)²) … here 1/(4N²(1 − m)²) with
    # the working F-number N_w = N (1 − m): within (a/s)² + (a/v)²-order terms of it
    approx = math.pi / (4.0 * FNUM**2 * (1.0 - m) ** 2)
    assert e == pytest.approx(approx, rel=(a / v) ** 2)


@pytest.mark.parametrize(("x", "y"), [(0.3, 0.0), (0.42, -0.42), (0.0, 0.59)])
def test_off_axis_irradiance_is_the_thin_lens_integral(x, y):
    scene = ideal_scene()
    cs = compile_scene(scene)
    ideal = scene.camera.ideal
    a, v = ideal.pupil_radius_mm, ideal.image_distance_mm
    e = _estimator_irradiance(cs.camera, x, y, a, n_r=32, n_phi=96)
    ref = _thin_lens_irradiance(x, y, a, FOCUS, v)
    assert e == pytest.approx(ref, rel=1e-8)


def test_cos4_fall_off_in_the_small_aperture_limit():
    fnum = 64.0  # a pinhole-like aperture: a = 0.013 mm
    scene = ideal_scene(fnum=fnum)
    cs = compile_scene(scene)
    ideal = scene.camera.ideal
    a, v = ideal.pupil_radius_mm, ideal.image_distance_mm
    e0 = _estimator_irradiance(cs.camera, 0.0, 0.0, a, n_r=8, n_phi=16)
    for x in (0.2, 0.4, 0.6):
        theta = math.atan(x / v)
        e = _estimator_irradiance(cs.camera, x, 0.0, a, n_r=8, n_phi=16)
        # cos⁴ holds to O((a / s)²) of the aperture's spread of object-side angles
        assert e / e0 == pytest.approx(math.cos(theta) ** 4, rel=10 * (a / FOCUS) ** 2 + 1e-12)


@pytest.mark.parametrize(("k1", "k2"), [(0.0, 0.0), (-0.25, 0.05), (0.12, 0.0)])
def test_chief_ray_follows_opencv_distortion(k1, k2):
    scene = ideal_scene(k1=k1, k2=k2)
    cs = compile_scene(scene)
    v = scene.camera.ideal.image_distance_mm
    for xs, ys in [(0.1, 0.05), (-0.4, 0.3), (0.55, -0.55)]:
        ray = into_scene(cs.camera, xs, ys, 0.0, 0.0)  # through the lens's centre
        assert ray.passed
        # the scene-side direction, slope s⃗ = (dx, dy)/(−dz) toward the scene; OpenCV:
        # image point = v · D(s⃗) mapped onto the sensor turned by the lens (x_s = −v D(s⃗))
        sx, sy = ray.dx / -ray.dz, ray.dy / -ray.dz
        rho2 = sx * sx + sy * sy
        g = 1.0 + k1 * rho2 + k2 * rho2 * rho2
        assert -v * g * sx == pytest.approx(xs, abs=1e-12)
        assert -v * g * sy == pytest.approx(ys, abs=1e-12)
