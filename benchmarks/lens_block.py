"""The imaging lens traced in SIMD blocks: the benchmark's fast twin of
:func:`eyelume.kernels.sequential.trace_lens` (``lens_vs_optiland.py`` times it; nothing in
``src/`` uses it, so it lives here; ``tests/kernels/test_sequential.py`` checks it against the
per-ray kernel)."""

from __future__ import annotations

import math

from numba import njit

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
)

__all__ = ["trace_lens_block"]


@njit(cache=True, error_model="numpy", fastmath={"contract", "arcp", "nsz", "reassoc"})
def trace_lens_block(lf, x, y, z, dx, dy, dz, status):
    """Trace a block of rays through all lens surfaces, surface by surface, in place.

    The same physics as :func:`trace_lens`, arranged for SIMD: the loop over rays is innermost
    and branch-free (a ray that has failed keeps its status; its numbers are then meaningless),
    so blocks of a few hundred rays stay in cache. Of the roots q/a and c/q of
    a t² + 2 b t + c = 0 (q = −(b + sgn(b)·√(b² − a c)), stable, finite for a plane) it takes
    the nearest one ahead on the vertex sheet, as :func:`trace_lens` does. ``status[i]`` ends as
    LENS_PASSED, LENS_VIGNETTED or LENS_TIR.
    """
    n = x.shape[0]
    for i in range(n):
        status[i] = LENS_PASSED
    for j in range(lf.shape[0]):
        zv = lf[j, L_Z]
        c = lf[j, L_CURV]
        e = 1.0 + lf[j, L_CONIC]
        sd2 = lf[j, L_SD] * lf[j, L_SD]
        eta = lf[j, L_N0] / lf[j, L_N1]
        for i in range(n):
            px, py, pz = x[i], y[i], z[i] - zv
            ux, uy, uz = dx[i], dy[i], dz[i]
            a = c * (ux * ux + uy * uy + e * uz * uz)
            hb = c * (px * ux + py * uy + e * pz * uz) - uz
            cc = c * (px * px + py * py + e * pz * pz) - 2.0 * pz
            disc = hb * hb - a * cc
            q = -(hb + math.copysign(math.sqrt(max(disc, 0.0)), hb))
            t1 = q / a
            t2 = cc / q
            ok1 = (t1 > -1e-9) & (e * c * (pz + t1 * uz) <= 1.0)
            ok2 = (t2 > -1e-9) & (e * c * (pz + t2 * uz) <= 1.0)
            t = t1 if ok1 & ((not ok2) | (t1 < t2)) else t2
            hx, hy, hz = px + t * ux, py + t * uy, pz + t * uz
            met = (disc >= 0.0) & (ok1 | ok2) & (hx * hx + hy * hy <= sd2)
            nx, ny, nz = -c * hx, -c * hy, 1.0 - c * e * hz
            inv = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz)
            nx, ny, nz = nx * inv, ny * inv, nz * inv
            ci = ux * nx + uy * ny + uz * nz
            s2 = eta * eta * (1.0 - ci * ci)
            g = math.copysign(math.sqrt(max(0.0, 1.0 - s2)), ci) - eta * ci
            x[i], y[i], z[i] = hx, hy, hz + zv
            dx[i], dy[i], dz[i] = eta * ux + g * nx, eta * uy + g * ny, eta * uz + g * nz
            fate = LENS_PASSED if s2 <= 1.0 else LENS_TIR
            fate = fate if met else LENS_VIGNETTED
            status[i] = fate if status[i] == LENS_PASSED else status[i]
