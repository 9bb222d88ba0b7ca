"""Numba kernels: per-ray, allocation-free physics. Nothing else in eyelume traces a ray."""
