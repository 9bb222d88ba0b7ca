"""A camera path splits at each optical element's surface it meets before its first Lambertian
vertex (issue 14: the benchmark of ``paper2005-integrated`` at 1 % median skin error).

On ``paper2005-integrated`` the camera looks at the eye off a hot mirror (R 0.92, T 0.08) and
through the eyepiece's two AR-coated faces (R 0.005, T 0.995). Chosen between by chance, a skin
sample was 0 (the mirror's transmitted part, the eyepiece's reflected parts see nothing lit) or
its mean / 0.92: that was nearly all of the picture's noise. Split, the path goes on along the
stronger part with its coefficient as weight, and the weaker one is kept and followed after it:
checked here on a skin pixel's chief ray, against the coefficients written in the preset and
N-BK7's index at 850 nm — the first vertex's throughput is ρ R_mirror T_back T_front (the
(1/n)² of radiance entering the glass and the n² leaving it cancel), whatever the stream,
and the three weaker parts are kept with T_mirror, R_mirror R_back and
R_mirror T_back R_front / n². That the split is unbiased is the forward–fast χ² agreement on
the preset (tests/estimators/test_integrated_agreement.py) and on the element scenes
(tests/estimators/test_elements_agreement.py).
"""

from __future__ import annotations

import numpy as np
import pytest

import eyelume
from eyelume.compile import compile_scene
from eyelume.estimators import fast as F
from eyelume.estimators.camera import aim_chief, into_scene
from eyelume.estimators.fast_run import primary_surface_map
from eyelume.kernels.bins import from_grid
from eyelume.kernels.tables import Ray
from eyelume.scene.glass import load_catalog


def _scratch() -> F.Scratch:
    return F.Scratch(np.empty(4), np.empty((F.ELEMENT_BRANCHES, 7)), np.zeros(1, dtype=np.int64))


def test_a_camera_path_splits_at_each_element_surface_before_its_first_vertex():
    scene = eyelume.load_scene("paper2005-integrated")
    cs = compile_scene(scene)
    labels, _ = primary_surface_map(cs)
    lid = cs.surface_names.index("upper eyelid")
    rows, cols = np.nonzero(labels == lid)
    row, col = int(rows[len(rows) // 2]), int(cols[len(cols) // 2])
    xs, ys = from_grid(cs.tables.picture, col + 0.5, row + 0.5)
    chief = aim_chief(cs.camera, xs, ys)
    r = into_scene(cs.camera, xs, ys, chief.qx, chief.qy)
    assert chief.found and r.passed
    ray = Ray(r.x, r.y, r.z, r.dx, r.dy, r.dz)

    eyepiece, mirror = scene.elements
    r_m, t_m = mirror.front.coating.reflectance, mirror.front.coating.transmittance
    r_f, t_f = eyepiece.front.coating.reflectance, eyepiece.front.coating.transmittance
    r_b, t_b = eyepiece.back.coating.reflectance, eyepiece.back.coating.transmittance
    n = load_catalog()["N-BK7"].index(scene.wavelength_nm)
    rho = scene.face.skin_reflectance

    betas = set()
    for seed in (1, 2, 3, 12345):
        scratch = _scratch()
        out = F._camera_branch(np.uint64(seed), cs.tables, cs.camera, ray, 1.0, True, True, scratch)
        assert out.vertex.s == lid
        assert out.vertex.beta == pytest.approx(rho * r_m * t_b * t_f, rel=1e-12)
        betas.add(out.vertex.beta)
        assert scratch.count[0] == 3  # mirror, eyepiece back, eyepiece front, in that order
        weak = scratch.rays[:3, 6]
        assert weak == pytest.approx([t_m, r_m * r_b, r_m * t_b * r_f / n**2], rel=1e-12)
        # the mirror's transmitted part leaves from the mirror, on along the camera's ray
        assert scratch.rays[0, 3:6] == pytest.approx([r.dx, r.dy, r.dz], abs=1e-12)
    assert len(betas) == 1  # no choice by chance before the first vertex

    # a path followed without the split (a continuation, a kept part) pushes nothing and
    # chooses at each surface by chance: the vertex, when reached, has ρ or 0 × the chance's
    reached = []
    for seed in range(1, 400):
        scratch = _scratch()
        out = F._camera_branch(
            np.uint64(seed), cs.tables, cs.camera, ray, 1.0, False, True, scratch
        )
        assert scratch.count[0] == 0
        if out.vertex.s == lid:
            reached.append(out.vertex.beta)
    assert set(np.round(reached, 12)) == {round(rho, 12)}
    assert 0.8 < len(reached) / 399 < 0.99  # about R_mirror T_back T_front ≈ 0.91 of them
