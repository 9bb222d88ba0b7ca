"""The imaging lens passes the flux a Lambertian point on the eye plane sends into its real
numerical aperture: fraction sin²θ (the étendue of a cone), with θ the real marginal ray's angle.

This ties the Lambertian sampler, the stop sized for F/2.51, the clear apertures and the lens
trace together: a stop too small, a clear aperture that vignettes the axial bundle, or a biased
cosine sampler each move the fraction away from sin²θ by far more than the binomial noise.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from eyelume.kernels.rng import next_uniform, stream_start
from eyelume.kernels.sampling import cosine_hemisphere
from eyelume.kernels.sequential import LENS_PASSED, trace_lens


def real_marginal_angle(lf) -> float:
    """Largest angle from the axis at which a meridional ray from the axial point of the eye
    plane still passes the lens, by bisection to 1e-13 rad."""
    path = np.zeros((1, 3))
    lo, hi = 0.0, 0.6  # passes at 0; 0.6 rad is far beyond the ~0.2 rad aperture
    while hi - lo > 1e-13:
        mid = 0.5 * (lo + hi)
        status = trace_lens(lf, 0.0, 0.0, 0.0, 0.0, math.sin(mid), math.cos(mid), path, 0, False)[0]
        lo, hi = (mid, hi) if status == LENS_PASSED else (lo, mid)
    return lo


@njit(cache=True)
def _lens_fates(lf, x, y, z, dx, dy, dz, status):
    """The sequential kernel's fate (LENS_PASSED, …) of each ray."""
    for i in range(x.shape[0]):
        status[i] = trace_lens(lf, x[i], y[i], z[i], dx[i], dy[i], dz[i], None, 0, False)[0]


@njit(cache=True)
def _lambertian_rays(n, seed, dx, dy, dz):
    for i in range(n):
        s = stream_start(seed, i)
        s, u1 = next_uniform(s)
        s, u2 = next_uniform(s)
        dx[i], dy[i], dz[i] = cosine_hemisphere(u1, u2)


def test_axial_lambertian_flux_through_the_lens_is_sin2_of_the_real_aperture(paper_compiled):
    lf = paper_compiled.lf
    theta = real_marginal_angle(lf)
    expected = math.sin(theta) ** 2
    n = 2_000_000
    dx, dy, dz = np.empty(n), np.empty(n), np.empty(n)
    _lambertian_rays(n, 17, dx, dy, dz)
    status = np.zeros(n, dtype=np.int64)
    _lens_fates(lf, np.zeros(n), np.zeros(n), np.zeros(n), dx, dy, dz, status)
    got = float(np.mean(status == LENS_PASSED))
    sigma = math.sqrt(expected * (1 - expected) / n)
    assert abs(got - expected) < 4 * sigma, (got, expected, sigma)
    # and the first-order reading: by the Lagrange invariant the object-side NA of the eye-plane
    # conjugate is |m| / (2 N_w), N_w the paraxial working F-number; the real marginal ray
    # differs from it only by the pupil's spherical aberration at F/2.5 (a few per mille here)
    from eyelume.compile import lens_paraxial

    cs = paper_compiled
    par = lens_paraxial(cs.scene, cs.lens_indices)
    s = cs.scene.lens.object_distance_mm
    n_w = par.working_f_number(s, cs.stop_index, lf[cs.stop_index, 3])
    na_paraxial = abs(par.magnification(s)) / (2 * n_w)
    assert abs(math.sin(theta) / na_paraxial - 1) < 0.02
