"""Sequential lens trace against closed forms: a plane slab, vignetting, TIR, a singlet's focus."""

from __future__ import annotations

import importlib
import math
import sys
from pathlib import Path

import numpy as np

from eyelume.kernels.sequential import (
    L_CONIC,
    L_CURV,
    L_N0,
    L_N1,
    L_SD,
    L_Z,
    LENS_PASSED,
    LENS_TIR,
    LENS_VIGNETTED,
    N_LENS_COL,
    trace_lens,
)


def _benchmark_module(name: str):
    """A module of ``benchmarks/`` (not a package), imported by name with that folder on the path
    as the benchmarks import it (Numba's cache re-imports a kernel's module by its name)."""
    folder = str(Path(__file__).resolve().parents[2] / "benchmarks")
    if folder not in sys.path:
        sys.path.insert(0, folder)
    return importlib.import_module(name)


def _lens(*surfaces):
    """Rows (z_vertex, curvature, conic, semi-diameter, n_before, n_after)."""
    lf = np.zeros((len(surfaces), N_LENS_COL))
    for j, (z, c, k, sd, n0, n1) in enumerate(surfaces):
        lf[j, L_Z], lf[j, L_CURV], lf[j, L_CONIC] = z, c, k
        lf[j, L_SD], lf[j, L_N0], lf[j, L_N1] = sd, n0, n1
    return lf


def _trace(lf, p, d, record=False):
    path = np.zeros((lf.shape[0], 3))
    status, x, y, z, dx, dy, dz, met, n_path = trace_lens(lf, *p, *d, path, 0, record)
    return status, np.array([x, y, z]), np.array([dx, dy, dz]), met, path[:n_path]


SLAB_T, SLAB_N = 10.0, 1.5
SLAB = _lens((0.0, 0.0, 0.0, 20.0, 1.0, SLAB_N), (SLAB_T, 0.0, 0.0, 20.0, SLAB_N, 1.0))


def test_slab_displaces_a_tilted_ray_parallel_to_itself():
    for theta_deg in (0.0, 5.0, 20.0, 45.0, 70.0):
        theta = math.radians(theta_deg)
        d = np.array([0.0, math.sin(theta), math.cos(theta)])
        p = np.array([0.3, -2.0, -5.0])
        status, q, e, met, path = _trace(SLAB, p, d, record=True)
        assert status == LENS_PASSED and met == 2 and len(path) == 2
        # exit direction = entry direction (two parallel interfaces, same medium either side);
        # a handful of roundings of unit vectors: 1e-14
        np.testing.assert_allclose(e, d, atol=1e-14)
        # lateral shift between the entry line and the exit line: t sin(θ − θ′)/cos θ′
        theta_t = math.asin(math.sin(theta) / SLAB_N)
        shift = SLAB_T * math.sin(theta - theta_t) / math.cos(theta_t)
        rel = q - p
        perp = np.linalg.norm(rel - (rel @ d) * d)
        # coordinates are O(10 mm): rounding ~ε·10 ≈ 2e-15 mm per operation
        assert abs(perp - shift) < 1e-12, theta_deg
        # the ray is recorded on both faces, in order
        assert abs(path[0, 2]) < 1e-12 and abs(path[1, 2] - SLAB_T) < 1e-12
        np.testing.assert_allclose(path[1], q, atol=0)


def test_ray_outside_a_semi_diameter_is_vignetted():
    lf = _lens((0.0, 0.0, 0.0, 20.0, 1.0, SLAB_N), (SLAB_T, 0.0, 0.0, 5.0, SLAB_N, 1.0))
    status, q, _, met, _ = _trace(lf, (0.0, 6.0, -5.0), (0.0, 0.0, 1.0))
    assert status == LENS_VIGNETTED and met == 2  # passes the first face, stopped at the second
    assert abs(q[2] - SLAB_T) < 1e-12  # where the mount stopped it
    status, *_ = _trace(lf, (0.0, 4.9, -5.0), (0.0, 0.0, 1.0))
    assert status == LENS_PASSED
    status, _, _, met, _ = _trace(lf, (0.0, 25.0, -5.0), (0.0, 0.0, 1.0))
    assert status == LENS_VIGNETTED and met == 1


def test_total_internal_reflection_is_reported():
    # a ray inside glass (n = 1.5) meeting a flat face at 60° > θc = 41.8° cannot leave
    lf = _lens((0.0, 0.0, 0.0, 50.0, 1.5, 1.0))
    d = (0.0, math.sin(math.radians(60.0)), math.cos(math.radians(60.0)))
    status, _, _, met, _ = _trace(lf, (0.0, 0.0, -1.0), d)
    assert status == LENS_TIR and met == 1
    d = (0.0, math.sin(math.radians(40.0)), math.cos(math.radians(40.0)))
    assert _trace(lf, (0.0, 0.0, -1.0), d)[0] == LENS_PASSED


# --- a biconvex singlet -------------------------------------------------------------------------

R1, R2, THICK, N_GLASS = 50.0, -50.0, 5.0, 1.5
Z1 = 10.0
SINGLET = _lens(
    (Z1, 1.0 / R1, 0.0, 12.0, 1.0, N_GLASS),
    (Z1 + THICK, 1.0 / R2, 0.0, 12.0, N_GLASS, 1.0),
)


def _paraxial_focus():
    """Back focal point (world z) by the thick-lens (lensmaker) formula."""
    n, d = N_GLASS, THICK
    power = (n - 1) * (1 / R1 - 1 / R2 + (n - 1) * d / (n * R1 * R2))
    f = 1.0 / power
    bfd = f * (1.0 - (n - 1) * d / (n * R1))
    return Z1 + THICK + bfd, f


def _axis_crossing(h):
    """z where the image-side ray of a ray parallel to the axis at height h crosses the axis."""
    status, q, e, met, _ = _trace(SINGLET, (0.0, h, 0.0), (0.0, 0.0, 1.0))
    assert status == LENS_PASSED and met == 2
    return q[2] - q[1] * e[2] / e[1]


def test_singlet_focuses_paraxial_rays_at_the_thick_lens_focus():
    z_f, f = _paraxial_focus()
    heights = np.array([0.05, 0.1, 0.2, 0.4])
    la = np.array([_axis_crossing(h) for h in heights]) - z_f  # longitudinal aberration
    # Spherical aberration: LA(h) = a h² + b h⁴ + …, with |b/a| ~ 1/f², so for h ≤ 0.4 mm the
    # quartic term is ≲ (h/f)² ≈ 6e-5 of the quadratic one. Hence:
    # (1) LA/h² is the same at every small height, to ~1e-4 relative (allow 1e-3);
    coeff = la / heights**2
    np.testing.assert_allclose(coeff, coeff[0], rtol=1e-3)
    # (2) eliminating the h² term between h₁ and h₂ (Richardson) leaves the focus at h → 0, off by
    # |b| h₁² h₂² ≲ |a| (h₁h₂/f)² ≈ 4e-12 mm, plus rounding of the crossing (~ε f/(h/f) ≈ 1e-11
    # mm at h = 0.05): the paraxial focus to 1e-9 mm.
    h1, h2 = heights[0], heights[1]
    z0 = (h2**2 * la[0] - h1**2 * la[1]) / (h2**2 - h1**2)
    assert abs(z0) < 1e-9
    # (3) a positive singlet is undercorrected (marginal focus nearer the lens), by about the
    # thin-lens third-order (Seidel) amount for an equiconvex n = 1.5 lens at infinite
    # conjugate, LA = −(h²/8f)·[(n/(n−1))² + (n+2)/(n(n−1)²)·(2(n²−1)/(n+2))² − n/(n+2)]
    # = −1.667 h²/f (e.g. Welford, Aberrations of Optical Systems). The lens is 5 mm thick
    # (d/f = 0.1), so only agreement within a factor 1.5 is asked.
    n = N_GLASS
    bracket = (n / (n - 1)) ** 2 + (n + 2) / (n * (n - 1) ** 2) * (2 * (n * n - 1) / (n + 2)) ** 2
    bracket -= n / (n + 2)
    a_thin = -bracket / (8.0 * f)
    assert coeff[0] < 0.0
    assert a_thin / 1.5 > coeff[0] > a_thin * 1.5


def test_block_kernel_reproduces_the_per_ray_kernel(paper_compiled):
    """The SIMD block kernel takes the same root, aperture and TIR decisions as trace_lens and
    lands on the same points: rays over the eye plane aimed past the rim of the first surface
    (so every fate occurs), compared ray by ray. Both evaluate the same formulas in float64 in a
    different order (and with contraction allowed), so positions agree to ~1e-12 mm after 11
    surfaces; 1e-9 mm / 1e-12 in direction cosines bounds that with room."""
    from eyelume.kernels.sequential import LENS_PASSED, LENS_VIGNETTED, trace_lens

    trace_lens_block = _benchmark_module("lens_block").trace_lens_block

    lf = paper_compiled.lf
    rng = np.random.default_rng(5)
    n = 4000
    x0 = rng.uniform(-20, 20, n)
    y0 = rng.uniform(-15, 15, n)
    r = 35 * np.sqrt(rng.uniform(size=n))
    phi = rng.uniform(0, 2 * np.pi, n)
    d = np.stack([r * np.cos(phi) - x0, r * np.sin(phi) - y0, np.full(n, 70.0)], 1)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    work = [x0.copy(), y0.copy(), np.zeros(n), d[:, 0].copy(), d[:, 1].copy(), d[:, 2].copy()]
    status = np.zeros(n, dtype=np.int64)
    trace_lens_block(lf, *work, status)
    path = np.zeros((1, 3))
    fates = set()
    for i in range(n):
        s, x, y, z, ux, uy, uz, _, _ = trace_lens(lf, x0[i], y0[i], 0.0, *d[i], path, 0, False)
        assert status[i] == s, i
        fates.add(s)
        if s == LENS_PASSED:
            np.testing.assert_allclose([work[0][i], work[1][i], work[2][i]], [x, y, z], atol=1e-9)
            np.testing.assert_allclose(
                [work[3][i], work[4][i], work[5][i]], [ux, uy, uz], atol=1e-12
            )
    assert {LENS_PASSED, LENS_VIGNETTED} <= fates
