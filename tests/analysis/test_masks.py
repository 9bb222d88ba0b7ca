"""The ideal eye-image mask against the pupil's analytic projection, glints_off renders, and the
evaluator's scores on synthetic images."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import ndimage
from scipy.optimize import brentq

import eyelume
from eyelume.analysis.evaluator import evaluator_merit, skin_score
from eyelume.analysis.masks import (
    MaskLevels,
    MaskWeights,
    glints_off,
    ideal_mask,
    mask_from_regions,
)
from eyelume.analysis.regions import region_masks
from eyelume.compile import compile_scene, eye_paraxial, lens_paraxial
from eyelume.estimators.fast_run import primary_surface_map
from eyelume.scene.eye import eye_indices
from eyelume.scene.optics import ParaxialSystem

FINE = {"sensor.cols": 348, "sensor.rows": 260}  # 0.13 mm pixels: the pupil spans ~3400


def _conic_hit(p, d, z0, c, k):
    """First crossing of the meridional ray p + t d (y, z) with the conicoid of vertex z0:
    c y² − 2 Z + (1 + k) c Z² = 0, Z = z − z0; returns the point and the unit normal."""
    zp = p[1] - z0
    a = c * d[0] ** 2 + (1 + k) * c * d[1] ** 2
    b = 2 * c * p[0] * d[0] - 2 * d[1] + 2 * (1 + k) * c * zp * d[1]
    cc = c * p[0] ** 2 - 2 * zp + (1 + k) * c * zp**2
    ts = [t.real for t in np.roots([a, b, cc]) if abs(t.imag) < 1e-12 and t.real > 0]
    t = min(ts, key=lambda t: abs(zp + t * d[1]))  # the sheet through the vertex
    q = p + t * d
    nrm = np.array([c * q[0], -1 + (1 + k) * c * (q[1] - z0)])
    return q, nrm / np.linalg.norm(nrm)


def _refract(d, nrm, n1, n2):
    """Snell's law in vector form (unit d, unit normal of either orientation)."""
    if d @ nrm > 0:
        nrm = -nrm
    eta, ci = n1 / n2, -(d @ nrm)
    return eta * d + (eta * ci - math.sqrt(1 - eta**2 * (1 - ci**2))) * nrm


def pupil_projection(scene, cs) -> dict[str, float]:
    """The pupil's image on the sensor: radius (mm) paraxially and with real cornea refraction.

    The eye's entrance pupil (the iris plane imaged by the two cornea surfaces into air) lies
    z_ep behind the eye plane z = 0 that the camera is focused on; the camera sees it through
    its own entrance pupil, D in front of the eye plane. The pupil's edge therefore images where
    the chief ray from the camera's entrance pupil to that edge crosses the eye plane, at
    r0 = r_ep · D / (D + z_ep), times the camera's chief-ray magnification to its sensor.
    """
    eye = scene.eye
    ep = eye_paraxial(scene)
    cornea = ParaxialSystem(ep.curvatures[:2], ep.gaps[:1], ep.indices[:3])
    t_iris = sum(s.thickness_mm for s in eye.surfaces[1 : eye.iris_surface])
    # the virtual object (L < 0: behind the vertex) that the cornea images onto the iris plane
    L = brentq(lambda L: cornea.image_distance(L) - t_iris, -1.0, -10.0)
    z_ep, r_ep = -L, eye.pupil_diameter_mm / 2 / abs(cornea.magnification(L))

    lens = lens_paraxial(scene, cs.lens_indices)
    d_cam = scene.lens.object_distance_mm + lens.entrance_pupil_position(cs.stop_index)
    r0_paraxial = r_ep * d_cam / (d_cam + z_ep)

    # real rays (eye frame, (y, z'), z' into the eye) from the camera's entrance pupil centre
    n = eye_indices(eye, scene.wavelength_nm)
    s0, s1 = eye.surfaces[0], eye.surfaces[1]
    z_iris = s0.thickness_mm + t_iris

    def iris_plane_height(r0):
        p, d = np.array([0.0, -d_cam]), np.array([r0, d_cam]) / math.hypot(r0, d_cam)
        q, nrm = _conic_hit(p, d, 0.0, 1 / s0.radius_mm, s0.conic)
        d = _refract(d, nrm, n[0], n[1])
        q, nrm = _conic_hit(q, d, s0.thickness_mm, 1 / s1.radius_mm, s1.conic)
        d = _refract(d, nrm, n[1], n[2])
        return q[0] + (z_iris - q[1]) / d[1] * d[0]

    r0_real = brentq(lambda r0: iris_plane_height(r0) - eye.pupil_diameter_mm / 2, 1.0, 6.0)

    # chief ray (through the stop centre) from eye-plane height r0 to the sensor plane
    a = lens.trace(1.0, 0.0)[0][cs.stop_index]
    b = lens.trace(0.0, 1.0)[0][cs.stop_index]
    L_obj = scene.lens.object_distance_mm

    def sensor_height(r0):
        u = -a * r0 / (a * L_obj + b)
        ys, us = lens.trace(r0 + L_obj * u, u)
        return abs(ys[-1] + scene.lens.surfaces[-1].thickness_mm * us[-1])

    return {
        "z_ep": z_ep,
        "r_ep": r_ep,
        "d_cam": d_cam,
        "paraxial": sensor_height(r0_paraxial),
        "real_cornea": sensor_height(r0_real),
    }


@pytest.fixture(scope="module")
def fine():
    scene = eyelume.load_scene("paper2005", FINE)
    cs = compile_scene(scene)
    return scene, cs, region_masks(cs)


def test_pupil_area_matches_projection(fine):
    scene, cs, regions = fine
    proj = pupil_projection(scene, cs)
    sn = scene.sensor
    px = (sn.width_mm / sn.cols) * (sn.height_mm / sn.rows)
    image, weights = ideal_mask(cs)
    n_mask = int(((image == 0) & (weights > 0)).sum())
    assert n_mask == int(regions["pupil"].sum())
    expected = math.pi * proj["real_cornea"] ** 2 / px
    # mask 3392 px against 3393 (real refraction at the cornea, paraxial camera)
    assert n_mask == pytest.approx(expected, rel=0.02)
    # The first-order projection (3577 px) is 5 % larger: the pupil's 3.5 mm edge is far from
    # paraxial for the steep cornea, whose pupil aberration shrinks the apparent radius 2.6 %.
    paraxial = math.pi * proj["paraxial"] ** 2 / px
    assert 1.03 < paraxial / n_mask < 1.08
    # the eye's entrance pupil lies 3.04 mm behind the eye plane: 3.4 % less area than if it
    # lay in the focused plane, so the depth must be (and is) accounted for
    assert proj["z_ep"] == pytest.approx(3.04, abs=0.02)
    assert (proj["d_cam"] / (proj["d_cam"] + proj["z_ep"])) ** 2 < 0.97


def test_pupil_is_one_disc_and_the_limbus_ring_is_iris(paper_compiled):
    """The iris root closes the ring between the iris (r 5.5 mm) and the sclera (r 7.4 mm in
    the iris plane): chief rays through the corneal edge meet it, so the pupil region is the
    iris's opening alone (one disc about the image centre) and the ring is iris (issue 12)."""
    regions = region_masks(paper_compiled)
    pupil = regions["pupil"]
    labels, n = ndimage.label(pupil)
    assert n == 1 and pupil.sum() > 150
    rows, cols = np.nonzero(pupil)
    centre = np.array(pupil.shape) / 2
    # apparent pupil radius: 3.5 mm × ~1.13 (cornea) × 1.144 (lens) / 0.529 mm per pixel ≈ 8.6
    assert np.hypot(rows - centre[0] + 0.5, cols - centre[1] + 0.5).max() < 10
    # the ring: the iris root's surface is what the chief rays beyond the iris edge meet
    names = paper_compiled.surface_names
    labels_map, _ = primary_surface_map(paper_compiled)
    root = labels_map == names.index("iris root")
    assert root.sum() > 0 and not (root & ~regions["iris"]).any()


def test_mask_levels_and_weights(paper_compiled, paper_scene):
    levels, weights = MaskLevels(), MaskWeights()
    image, w = ideal_mask(paper_compiled, levels, weights)
    regions = region_masks(paper_compiled)
    assert np.all(image[regions["skin"]] == levels.skin)
    assert np.all(image[regions["iris"]] == levels.iris)
    assert np.all(image[regions["sclera"]] == levels.sclera)
    assert np.all(w[regions["sclera"]] == 0) and np.all(w[regions["skin"]] == 1)
    nowhere = ~(regions["pupil"] | regions["iris"] | regions["sclera"] | regions["skin"])
    assert np.all(w[nowhere] == 0)
    # geometry only: the same mask without glints
    image_off, w_off = ideal_mask(glints_off(paper_scene))
    assert np.array_equal(image, image_off) and np.array_equal(w, w_off)
    # glint regions weigh 0
    glint = np.zeros_like(regions["skin"])
    glint[30:33, 40:43] = True
    with_glint = {k: v & ~glint for k, v in regions.items()} | {"glint 0": glint}
    assert np.all(mask_from_regions(with_glint).weights[glint] == 0)


def test_glints_off_scene(paper_scene):
    off = glints_off(paper_scene)
    assert off.eye.cornea_reflectance == 0
    assert off.eye.cornea_absorptance == pytest.approx(paper_scene.eye.cornea_reflectance)
    assert paper_scene.eye.cornea_reflectance == 0.024  # the original is untouched
    fres = glints_off(eyelume.load_scene("paper2005", {"eye.cornea_reflection": "fresnel"}))
    assert fres.eye.cornea_reflection == "fixed"
    assert fres.eye.cornea_absorptance == pytest.approx(0.0246, abs=2e-4)


@pytest.mark.slow
def test_glints_off_render_has_no_glints(paper_scene):
    on = eyelume.render(paper_scene, eyelume.RenderOptions(seed=11))
    off = eyelume.render(glints_off(paper_scene), eyelume.RenderOptions(seed=11))
    reg = on.regions
    cornea = reg["pupil"] | reg["iris"]
    for k in (k for k in reg if k.startswith("glint")):
        cornea |= reg[k]
    for res, has_glints in ((on, True), (off, False)):
        skin = float(np.median(res.eye_image[reg["skin"]]))
        peak = float(res.eye_image[cornea].max())
        if has_glints:
            assert peak > 1.5 * skin  # measured 2.7×
        else:
            assert peak < skin  # measured 0.56× (the iris)
    # the light the cornea transmits is unchanged: the iris is as bright in both
    means, variances = [], []
    for res in (on, off):
        v = res.eye_image[reg["iris"]]
        means.append(v.mean())
        variances.append(res.eye_image_variance[reg["iris"]].sum() / v.size**2)
    assert abs(means[0] - means[1]) < 4 * math.sqrt(sum(variances))


@pytest.fixture(scope="module")
def mask(paper_compiled):
    return ideal_mask(paper_compiled)


def test_evaluator_merit_zero_for_the_mask_at_any_exposure(mask):
    image, w = mask
    for scale in (1.0, 2.7e-6, 3e3):
        assert evaluator_merit(scale * image, image, w) < 1e-24


def test_evaluator_merit_grows_with_skin_noise_and_gradient(mask):
    image, w = mask
    skin = image == 1.0
    rng = np.random.default_rng(5)
    noisy = [image + skin * rng.normal(0, s, image.shape) for s in (0.05, 0.1, 0.2)]
    merits = [evaluator_merit(5e-6 * im, image, w) for im in noisy]
    assert 0 < merits[0] < merits[1] < merits[2]
    cols = np.linspace(-1, 1, image.shape[1])[None, :]
    ramps = [image * (1 + g * cols * skin) for g in (0.1, 0.3)]
    r0, r1 = (evaluator_merit(im, image, w) for im in ramps)
    assert 0 < r0 < r1
    assert evaluator_merit(3.0 * ramps[1], image, w) == pytest.approx(r1, rel=1e-12)
    # a dark image scores the mask's weighted mean square
    dark = evaluator_merit(np.zeros_like(image), image, w)
    assert dark == pytest.approx(np.sum(w * image**2) / w.sum())


def test_skin_score_synthetic():
    rng = np.random.default_rng(2)
    image = rng.uniform(0.5, 1.5, (40, 50))
    skin = np.zeros(image.shape, bool)
    skin[:, :20] = True
    image[:, :20] = 2.0 + 0.1 * np.tile([-1.0, 1.0], (40, 10))
    mean, std, cv = skin_score(image, skin)
    assert (mean, std, cv) == pytest.approx((2.0, 0.1, 0.05), rel=1e-12)
    with pytest.raises(ValueError):
        skin_score(image, np.zeros_like(skin))
