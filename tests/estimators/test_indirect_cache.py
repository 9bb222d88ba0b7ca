"""The fast estimator's irradiance cache (``run.indirect = "cache"``,
:func:`eyelume.estimators.fast.indirect_cache`) against its continuation paths
(``run.indirect = "paths"``), on vr-offaxis with the population's eyelashes at a quarter of
the tracking picture's resolution over the same field (the cache's points then 1 or 2 pixels
apart, the same world spacing as 4 or 8 pixels — the default — of the 400 × 400 picture).

Per region (skin, sclera, iris, pupil: the primary surface map's), the difference of the two
renders' means against its standard error from the statistics: each render's pixels are
independent (σ² = Σ var / n²), and the cache's points' own Monte Carlo errors (the variance
the cache keeps for each) reach the region's mean through the bilinear weights of the pixels
that read them, × the reflectance of the face they lie on: Σ_i c_i² var_i. |z| ≤ 4 (a
two-sided 6 × 10⁻⁵ chance per region were the cache unbiased).
"""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest
from pydantic import ValidationError

from eyelume.analysis.regions import surface_masks
from eyelume.compile import compile_scene
from eyelume.estimators.fast_run import primary_surface_map, trace_fast, with_indirect_cache
from eyelume.kernels import geometry as G
from eyelume.scene.io import apply_overrides, load_scene
from eyelume.scene.model import Run

Z_MAX = 4.0
COLS = 100


def _scene(indirect: str, spacing: int = 1):
    scene = load_scene("vr-offaxis")
    w, h = scene.sensor.field_mm
    rows = round(scene.sensor.rows * COLS / scene.sensor.cols)
    return apply_overrides(
        scene,
        {"sensor.width_mm": w, "sensor.height_mm": h, "sensor.cols": COLS, "sensor.rows": rows,
         "face.lashes.enabled": True, "run.indirect": indirect,
         "run.indirect_cache_spacing": spacing},
    )  # fmt: skip


def _cache_variance_of_means(cs, masks, labels, sides) -> dict[str, float]:
    """Var of each region's mean from the cache points' errors: each pixel (centre u, v)
    reads the four points of its cell with bilinear weights (those on its own surface,
    renormalised), scaled by its face's reflectance (the vertex's throughput)."""
    tab, k = cs.camera.indirect, cs.camera.indirect_spacing
    ny, nx = tab.shape[:2]
    rows, cols = labels.shape
    out = {}
    for name, mask in masks.items():
        n = int(mask.sum())
        c = np.zeros((ny, nx))
        for r, q in zip(*np.nonzero(mask), strict=True):
            s = labels[r, q]
            rho = cs.sf[s, G.RHO_B if sides[r, q] else G.RHO_A]
            a, b = (q + 0.5) / k, (r + 0.5) / k
            i0, j0 = min(int(a), nx - 2), min(int(b), ny - 2)
            fa, fb = a - i0, b - j0
            w = np.array([[(1 - fa) * (1 - fb), fa * (1 - fb)], [(1 - fa) * fb, fa * fb]])
            ok = tab[j0 : j0 + 2, i0 : i0 + 2, 7] == s
            if (w * ok).sum() > 0:
                c[j0 : j0 + 2, i0 : i0 + 2] += rho * w * ok / (w * ok).sum() / n
        out[name] = float((c**2 * tab[..., 8]).sum())
    return out


@pytest.mark.slow
@pytest.mark.parametrize("spacing", [1, 2])
def test_cache_agrees_with_paths_by_region(spacing):
    paths = compile_scene(_scene("paths"))
    cached = with_indirect_cache(compile_scene(_scene("cache", spacing)), 5)
    spp = 64
    light = COLS * COLS * spp
    ep = trace_fast(paths, spp, light, 3)
    ec = trace_fast(cached, spp, light, 4)
    labels, sides = primary_surface_map(paths)
    masks = surface_masks(paths, labels, sides)
    cache_var = _cache_variance_of_means(cached, masks, labels, sides)
    lines = []
    for name in ("skin", "sclera", "iris", "pupil"):
        m = masks[name]
        n = int(m.sum())
        if n < 20:
            continue
        d = ec.image[m].mean() - ep.image[m].mean()
        se = math.sqrt(
            (ec.variance[m].sum() + ep.variance[m].sum()) / n**2 + cache_var.get(name, 0.0)
        )
        lines.append((name, n, d / ep.image[m].mean(), d / se))
    assert any(name == "skin" for name, *_ in lines)
    bad = [x for x in lines if abs(x[3]) > Z_MAX]
    assert not bad, "; ".join(f"{a}: n {n}, Δ {r:+.4%}, z {z:+.1f}" for a, n, r, z in lines)


def test_cache_reads_most_skin_and_leaves_the_iris_to_paths():
    """The cache holds a point on most of the skin it covers, and none on the iris (lit
    through the cornea: its paths stay); its tolerance is a few point spacings' worth."""
    cs = with_indirect_cache(compile_scene(_scene("cache", 2)), 0)
    tab = cs.camera.indirect
    assert tab.shape == (-(-cs.picture.rows // 2) + 1, -(-cs.picture.cols // 2) + 1, 10)
    surf = tab[..., 7].astype(int)
    names = cs.surface_names
    on = {names[s] for s in np.unique(surf[surf >= 0])}
    assert not on & {"iris", "iris root"}, on
    assert (surf >= 0).mean() > 0.5
    assert np.all(tab[surf >= 0, 6] >= 0.0) and np.all(tab[surf >= 0, 8] >= 0.0)
    assert 0.0 < cs.camera.indirect_tol < 5.0


def test_same_seed_same_picture_whatever_threads():
    scene = _scene("cache", 2)
    images = []
    threads = numba.get_num_threads()
    try:
        for t in sorted({1, threads}):
            numba.set_num_threads(t)
            cs = compile_scene(scene)
            est = trace_fast(cs, 2, COLS * COLS, 7)
            images.append((with_indirect_cache(cs, 7).camera.indirect, est.image))
    finally:
        numba.set_num_threads(threads)
    for tab, image in images[1:]:
        np.testing.assert_array_equal(tab, images[0][0])
        np.testing.assert_array_equal(image, images[0][1])


def test_paths_by_default_and_bad_values_refused():
    assert Run().indirect == "paths"
    cs = compile_scene(load_scene("vr-offaxis"))
    assert cs.camera.indirect.shape[0] == 0 and cs.camera.indirect_spacing == 0.0
    assert with_indirect_cache(cs, 0) is cs
    for bad in ({"indirect": "irradiance"}, {"indirect_cache_spacing": 0},
                {"indirect_cache_grid": 0}):  # fmt: skip
        with pytest.raises(ValidationError):
            Run(**bad)
