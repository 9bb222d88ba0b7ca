"""How the per-ray kernels are compiled: :func:`per_ray`, Numba's ``njit`` without reference
counting.

Numba counts references to every array it hands around: an atomic add on the array's meminfo
when a function takes an array out of a struct or passes it on, and an atomic subtract when it
is done. The per-ray kernels only read the scene's tables and write into arrays their caller
owns, so the counting protects nothing there, and it costs: compiled with counting, the camera
path's ``_camera_branch`` held 23 increments and 61 decrements, ``nearest_hit`` and
``intersect_surface`` 2 and 2, 2 and 5, run for each of the ~8 nearest-hit searches and ~60
exact surface tests of a camera sample (paper2005); on two threads both cores update the same few
counters (the scene's tables are shared), so each atomic also waits for the other core's cache
line. Without it, a paper2005 render at 87 × 65 and 32 samples per pixel took ~18 % less CPU
time on one thread (1.6–1.8 s against 2.0–2.1 s, interleaved runs under load 8); same
results, bit for bit.

A function compiled by :func:`per_ray` must not allocate (Numba then refuses to compile it:
"NRT required but not enabled") nor return an array (its caller would release what it does not
own); calling it from a counted function is safe (the caller holds the references for the
call). ``_nrt`` is Numba's compile flag for this (``numba.core.options``).
"""

from __future__ import annotations

from numba import njit

__all__ = ["per_ray"]


def per_ray(fn):
    """``njit(cache=True)`` without reference counting (see the module docstring)."""
    return njit(cache=True, _nrt=False)(fn)
