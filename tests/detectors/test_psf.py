"""The camera's diffraction PSF (eyelume.detectors.psf) against closed forms and an independent
Monte Carlo, and its place in a render.

References: the Airy pattern's encircled energy EE(r) = 1 − J₀²(v) − J₁²(v), v = π r / (λ N)
(Born & Wolf, Principles of Optics, §8.5.2); the pixel kernel K(d) = ∫ PSF(u) Λ(u − d p) d²u
by SciPy's adaptive dblquad; a rendered glint against a Monte Carlo written here that draws the
Airy displacement by inverting the closed-form EE (not the module's quadrature).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy import integrate, ndimage
from typer.testing import CliRunner

import eyelume
from eyelume.cli import app
from eyelume.detectors.psf import (
    ENCIRCLED_ENERGY,
    airy_encircled_energy,
    airy_psf,
    convolve_irradiance,
    convolve_variance,
    diffraction_kernel,
    point_kernels,
    region_mean_variance,
)
from eyelume.errors import SceneError
from eyelume.scene.io import apply_overrides, load_scene
from tests.test_bit_identity import assert_variance_matches

LAM_NM = 850.0
LAM = LAM_NM * 1e-6
PITCH = 0.003


def _vr_working_f_number() -> float:
    """vr-offaxis's N_w from its preset's numbers, written here: N (1 + v / s), v the thin
    lens's image distance 1 / (1/f − 1/s)."""
    f, n, s = 1.646, 2.88, 33.25
    v = 1.0 / (1.0 / f - 1.0 / s)
    return n * (1.0 + v / s)


NW = _vr_working_f_number()


@pytest.mark.parametrize("v", [0.5, 1.0, 3.8317, 7.0156, 20.0, 60.0])
def test_psf_normalisation_against_the_encircled_energy_closed_form(v):
    """∫₀ʳ PSF 2π r dr by adaptive quadrature equals 1 − J₀² − J₁² (the two formulas are
    independent: one the pattern, the other Born & Wolf's integral of it)."""
    r = v * LAM * NW / math.pi
    got, err = integrate.quad(
        lambda x: airy_psf(x, LAM, NW) * 2 * math.pi * x, 0, r, limit=400, epsabs=1e-13
    )
    assert got == pytest.approx(float(airy_encircled_energy(r, LAM, NW)), abs=1e-9 + 10 * err)


@pytest.mark.parametrize("d", [(0, 0), (1, 0), (1, 1), (3, 2), (0, 6)])
def test_pixel_kernel_against_adaptive_quadrature(d):
    """K(d) = ∫ PSF(u) tri(ux/p − dx) tri(uy/p − dy) d²u by dblquad (before the module's
    renormalisation: × raw_sum). The module's midpoint rule is O(h²): its error is estimated
    (Richardson) from the same kernel at twice the cells, |K₂₄ − K₄₈| × 4/3; the tolerance is
    twice that estimate."""
    dx, dy = d
    coarse = diffraction_kernel(LAM_NM, NW, PITCH, PITCH, cells_per_lambda_n=24)
    fine = diffraction_kernel(LAM_NM, NW, PITCH, PITCH, cells_per_lambda_n=48)
    c = coarse.kernel.shape[0] // 2

    def f(y, x):
        tri = max(0.0, 1 - abs(x / PITCH - dx)) * max(0.0, 1 - abs(y / PITCH - dy))
        return float(airy_psf(math.hypot(x, y), LAM, NW)) * tri

    ref, _ = integrate.dblquad(
        f, (dx - 1) * PITCH, (dx + 1) * PITCH, (dy - 1) * PITCH, (dy + 1) * PITCH,
        epsabs=1e-13, epsrel=1e-10,
    )  # fmt: skip
    k24 = coarse.kernel[c + dy, c + dx] * coarse.raw_sum
    k48 = fine.kernel[c + dy, c + dx] * fine.raw_sum
    richardson = abs(k24 - k48) * 4 / 3
    assert abs(k24 - ref) <= 2 * richardson + 1e-12, (k24, ref, richardson)
    assert abs(k24 - ref) <= 1e-3 * ref  # the documented accuracy at the default


@pytest.mark.parametrize("pitch", [PITCH, 0.0015, 0.53])
def test_kernel_keeps_the_closed_form_encircled_energy(pitch):
    """Σ K before renormalisation is the PSF's power inside R (Σ_d Λ(u − d p) = 1), which the
    closed form gives as EE(R) = 0.99. The midpoint rule miscounts at most the cells the circle
    cuts: a ring 2h wide, at most 2π R · 2h · PSF_env(R − h) with the envelope |J₁(v)| ≤
    sqrt(2 / (π v))."""
    k = diffraction_kernel(LAM_NM, NW, pitch, pitch)
    radius = k.truncation_radius_mm
    assert float(airy_encircled_energy(radius, LAM, NW)) == pytest.approx(ENCIRCLED_ENERGY, 1e-12)
    ln = LAM * NW
    h = min(pitch, ln / 24)
    v = math.pi * (radius - h) / ln
    envelope = math.pi / (4 * ln * ln) * 4 * (2 / (math.pi * v)) / (v * v)
    tol = 2 * math.pi * radius * 2 * h * envelope
    assert abs(k.raw_sum - ENCIRCLED_ENERGY) <= tol, (k.raw_sum, tol)
    assert k.kernel.sum() == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(k.kernel, k.kernel[::-1, :], rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(k.kernel, k.kernel[:, ::-1], rtol=1e-12, atol=1e-18)
    assert k.airy_radius_mm == pytest.approx(1.21966989 * ln, rel=1e-8)
    assert float(airy_psf(k.airy_radius_mm, LAM, NW)) < 1e-12 * float(airy_psf(0.0, LAM, NW))


def test_convolution_conserves_power_and_a_uniform_field(rng):
    """A picture dark within twice the kernel's reach of its edges keeps its power to round-off; a
    uniform field stays uniform to its edges (normalised convolution there); a glint away from
    the edges becomes the kernel; values stay ≥ 0."""
    psf = diffraction_kernel(LAM_NM, NW, PITCH, PITCH)
    k = psf.kernel.shape[0] // 2
    img = np.zeros((50 + 4 * k, 70 + 4 * k))
    img[2 * k : -2 * k, 2 * k : -2 * k] = rng.exponential(1.0, size=(50, 70))
    img[2 * k + 10, 2 * k + 3] = 1e4  # a glint
    out = convolve_irradiance(img, psf)
    assert out.sum() == pytest.approx(img.sum(), rel=1e-12)
    assert out.min() >= 0
    point = np.zeros((4 * k + 1, 4 * k + 1))
    point[2 * k, 2 * k] = 1.0
    np.testing.assert_allclose(convolve_irradiance(point, psf)[k:-k, k:-k], psf.kernel, atol=1e-15)
    flat = convolve_irradiance(np.full((30, 40), 2.5), psf)
    np.testing.assert_allclose(flat, 2.5, rtol=1e-12)
    assert convolve_irradiance(img, None) is img
    with pytest.raises(ValueError, match="missing"):
        convolve_irradiance(np.where(img > 3, np.nan, img), psf)


def test_variance_of_the_convolved_picture_against_realisations(rng):
    """Independent pixels of known variance, convolved 4000 times: each pixel's sample
    variance against K² ⊗ Var, and a region mean's against region_mean_variance (each within
    5 σ of a sample variance of n Gaussian draws, σ = sqrt(2 / (n − 1)) relative)."""
    psf = diffraction_kernel(LAM_NM, NW, 2 * PITCH, 2 * PITCH)  # a smaller kernel, faster
    shape, n = (24, 30), 4000
    var = rng.uniform(0.5, 4.0, size=shape)
    var[5, 6] = 400.0  # a noisy glint pixel
    mask = np.zeros(shape, dtype=bool)
    mask[0:12, 4:20] = True  # touching the edge
    draws = rng.normal(size=(n, *shape)) * np.sqrt(var)
    conv = np.stack([convolve_irradiance(d + 50.0, psf) for d in draws])
    tol = 5 * math.sqrt(2 / (n - 1))
    predicted = convolve_variance(var, psf)
    for j in [(0, 0), (0, 15), (5, 6), (6, 6), (12, 20), (23, 29)]:  # corners and edges too
        assert conv[(slice(None), *j)].var(ddof=1) == pytest.approx(predicted[j], rel=tol)
    means = conv[:, mask].mean(axis=1)
    assert means.var(ddof=1) == pytest.approx(region_mean_variance(mask, var, psf), rel=tol)
    # what the naive sum of the convolved variances would say is far off: pixels correlate
    assert predicted[mask].sum() / mask.sum() ** 2 < 0.5 * means.var(ddof=1)


# the continuation grid the reference was rendered with (vr-offaxis's until de84d1d set 5 on the
# skin: a deliberate change of the fast samples, not of what this test compares)
SMALL = {
    "sensor.cols": 80,
    "sensor.rows": 80,
    "sensor.pixel_pitch_um": 15.0,
    "run.continuation_grid": 4,
    "run.iris_continuation_grid": 4,
}
REF = Path(__file__).parents[1] / "reference" / "vr_offaxis_small_seed3.npz"


def test_psf_none_reproduces_the_render_before_the_psf():
    """``camera.psf = "none"`` is the render as it was before the PSF existed: the arrays of
    ``tests/reference/vr_offaxis_small_seed3.npz`` (vr-offaxis at 80 × 80 pixels of 15 µm,
    fast 4 samples/pixel and forward 300 000 rays, seed 3), to 1e-9 relative as
    tests/test_bit_identity.py. Rendered by commit 88e872f, before the PSF existed; rendered
    again with ``camera.psf = "none"`` after deliberate changes of the picture: the tear
    film's glint (074eede, vr-offaxis's default), the cornea's Newton plane through its
    vertex (96dbce2: iris connections that failed from the camera frame's z = 0 now found),
    the first vertex's continuation skipping its free cone (its fast arrays only: 4233 of
    6400 pixels moved, the sum +0.02 %; the forward arrays unchanged, bit for bit) and the
    light paths aimed at each glint (fast arrays only: 64 of 6400 pixels moved, the sum
    +1 %: at this budget, 51 200 light paths, drawn over the whole cornea no glint got a
    single path; aimed, all eight are there) and the specular connections' analytic Jacobian
    (fast arrays only: 1734 of 6400 pixels moved, median 8e-9, at most 0.11 standard errors).
    The continuation grid is pinned to the reference's 4 (the preset's is 5 since de84d1d), and
    the LED bodies to the reference's 1.6 mm spheres (the preset's are 1.3 × 0.65 mm cylinders
    since leds.body_shape)."""
    ref = np.load(REF)
    spheres = {
        "leds.body_shape": "sphere",
        "leds.body_diameter_mm": 1.6,
        "leds.body_length_mm": None,
    }
    sc = apply_overrides(load_scene("vr-offaxis"), {**SMALL, **spheres, "camera.psf": "none"})
    f = eyelume.render(sc, eyelume.RenderOptions(estimator="fast", samples_per_pixel=4, seed=3))
    w = eyelume.render(sc, eyelume.RenderOptions(estimator="forward", rays=300_000, seed=3))
    assert f.psf is None and w.psf is None
    for name, arr in (("fast_image", f.eye_image), ("forward_image", w.eye_image)):
        np.testing.assert_allclose(arr, ref[name], rtol=1e-9, atol=0, err_msg=name)
    # the variances to 1e-9 of (var + image²): see assert_variance_matches
    for name, arr in (("fast", f.eye_image_variance), ("forward", w.eye_image_variance)):
        assert_variance_matches(arr, ref[f"{name}_variance"], ref[f"{name}_image"], name)


def _airy_kernel_by_monte_carlo(rng, n: int, radius: float, k: int) -> np.ndarray:
    """P(d): a point uniform over pixel 0, displaced by an Airy-distributed vector (|u| drawn
    by inverting the closed-form EE conditioned on |u| ≤ radius, direction uniform), lands in
    pixel d; (2k + 1)² histogram / n."""
    r_grid = np.linspace(0.0, radius, 200_001)
    cdf = airy_encircled_energy(r_grid, LAM, NW)
    cdf /= cdf[-1]
    r = np.interp(rng.uniform(size=n), cdf, r_grid)
    phi = rng.uniform(0, 2 * np.pi, size=n)
    x = rng.uniform(-0.5, 0.5, size=n) * PITCH + r * np.cos(phi)
    y = rng.uniform(-0.5, 0.5, size=n) * PITCH + r * np.sin(phi)
    ix, iy = np.rint(x / PITCH).astype(int) + k, np.rint(y / PITCH).astype(int) + k
    hist = np.zeros((2 * k + 1, 2 * k + 1))
    np.add.at(hist, (iy, ix), 1.0)
    return hist / n


@pytest.mark.slow
def test_a_rendered_glint_on_vr_offaxis_is_the_airy_pattern_over_pixels(rng):
    """vr-offaxis (its 3 µm pixels and optics; the chip cut to its central 120 × 120 pixels,
    which hold the pupil and the glints), rendered with and without the PSF at the same seed:
    away from the glints (no pixel of the geometric picture within the kernel's reach brighter
    than 5 × the median: light uniform over its pixel), the PSF render equals the geometric
    render convolved with a Monte Carlo Airy kernel drawn from the closed-form EE at N_w
    computed here from the preset's numbers, within 5 σ of that Monte Carlo plus the module's
    quadrature error (1e-3, test_pixel_kernel_against_adaptive_quadrature). About the brightest
    glint (spread from where its light fell in the pixel, tests/detectors/test_psf_points.py)
    the window keeps the geometric power within the same 5 σ + 1e-3, and the glint, mostly one
    pixel in the geometric picture (74 % of its power in its peak pixel at this seed), keeps
    under 60 % there with the PSF."""
    cut = {"sensor.cols": 120, "sensor.rows": 120}
    sc = apply_overrides(load_scene("vr-offaxis"), cut)
    opts = eyelume.RenderOptions(estimator="fast", samples_per_pixel=4, seed=2)
    blurred = eyelume.render(sc, opts)
    geo = eyelume.render(apply_overrides(sc, {"camera.psf": "none"}), opts).eye_image
    assert blurred.psf is not None
    assert blurred.psf.working_f_number == pytest.approx(NW, rel=1e-12)
    k = blurred.psf.kernel.shape[0] // 2
    n = 4_000_000
    p = _airy_kernel_by_monte_carlo(rng, n, blurred.psf.truncation_radius_mm, k)
    predicted = ndimage.convolve(geo, p, mode="constant")
    # the MC's error: Var = Σᵢ Eᵢ² P(1 − P) / n over the pixels sending light to j
    sigma = np.sqrt(ndimage.convolve(geo**2, p * (1 - p), mode="constant") / n)
    # plus the MC kernel's undrawn tail: a pixel whose share is ≲ 3 / n often gets no draw
    allowed = 5 * sigma + 1e-3 * predicted + 3 * geo.max() / n
    bright = geo > 5 * np.median(geo)
    near = ndimage.binary_dilation(bright, np.ones((2 * k + 3, 2 * k + 3), bool))
    inner = np.zeros(geo.shape, bool)
    inner[k + 1 : -k - 1, k + 1 : -k - 1] = True  # out of the edges' reach
    far = inner & ~near
    assert far.sum() > 500
    diff = np.abs(blurred.eye_image - predicted)
    assert np.all(diff[far] <= allowed[far]), np.max(diff[far] / allowed[far])
    # the brightest glint whose window is out of the edges' reach
    peak_in = np.where(inner, geo, -np.inf)
    peak = np.unravel_index(np.argmax(peak_in), geo.shape)
    assert geo[peak] > 20 * np.median(geo)  # a glint
    win = tuple(slice(c - 6, c + 7) for c in peak)
    got, want = blurred.eye_image[win].sum(), predicted[win].sum()
    # a point's light crossing the window's edge differs from a uniform pixel's by at most
    # max_s |Σ_window (P(·; s) − K)| (the point kernels' table)
    table = point_kernels(LAM_NM, NW, PITCH, PITCH)
    c = table.shape[2] // 2
    moved = np.abs(
        table[:, :, c - 6 : c + 7, c - 6 : c + 7].sum(axis=(2, 3))
        - blurred.psf.kernel[k - 6 : k + 7, k - 6 : k + 7].sum()
    ).max()
    slack = 5 * math.sqrt(np.sum(sigma[win] ** 2)) + (1e-3 + moved) * want
    assert abs(got - want) <= slack, (got, want, slack)
    # the geometric glint is (nearly) one pixel; the diffraction-limited one is not
    g = geo[win] - np.median(geo)
    b = blurred.eye_image[win] - np.median(blurred.eye_image)
    assert b.max() / b.sum() < 0.6 < g.max() / g.sum()


def test_unknown_psf_kind_is_one_line_naming_the_field():
    with pytest.raises(SceneError) as err:
        apply_overrides(load_scene("vr-offaxis"), {"camera.psf": "gaussian"})
    msg = str(err.value)
    assert "camera.psf" in msg and "gaussian" in msg and "\n" not in msg
    res = CliRunner().invoke(app, ["info", "--scene", "vr-offaxis", "--set", "camera.psf=gauss"])
    assert res.exit_code == 2 and res.output.count("\n") == 1 and "camera.psf" in res.output


def test_psf_defaults_by_optics():
    """Unset: diffraction for an ideal lens, none for a prescription (paper2005 unchanged)."""
    assert load_scene("vr-offaxis").camera.psf_used == "diffraction"
    assert load_scene("paper2005").camera.psf_used == "none"
    paper = load_scene("paper2005", {"camera.psf": "diffraction"})
    from eyelume.compile import compile_scene
    from eyelume.detectors.psf import camera_psf

    psf = camera_psf(compile_scene(paper))
    assert psf is not None and psf.kernel.shape == (3, 3)  # 530 µm bins: ~all in the centre
    assert psf.kernel[1, 1] > 0.98
